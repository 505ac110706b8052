"""One check of a book's formula cells against the reference: the bound a cell may differ by
(per unit and per the mechanism's size), the comparison of cells with expected values, and the
record of what differs."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

ABS_TOL = 1e-9
ANGLE_UNITS = {"rad": 2 * math.pi, "deg": 360.0}
# The bound is ABS_TOL per PER units of a quantity's natural magnitude: the mechanism's size S
# for a length (S² for an area), 1 for an angle or a ratio, each times the input's rate for a
# velocity or an acceleration. So a mechanism in metres and the same one in micrometres are
# judged alike: |Δ| ≤ 1e-12·S for a length, 1e-9 for an angle.
PER = 1e3
# A bound judges a value only while it is smaller than this fraction of it (of max(|x|, the
# strict bound)): see Check.determines.
DETERMINED = 1e-2
TOLERANCE_RULE = {
    "length": "1e-12·S (S the mechanism's size; S² for an area; times the input's rate for a "
              "velocity or an acceleration)",
    "angle": "1e-9 (times the input's rate for an angular velocity or acceleration)",
    "singular": "a length or a rate beyond its magnitude m may differ by 1e-12·|x|²/m; near a "
                "limit position a further 1e-12·|∂x/∂θ|, at an isolated one 1e-6; a rate near a "
                "dead centre its base bound / sine² (sine: between a loop's constraint "
                "gradients)",
    "not judged": "a cell the strict bound does not admit, whose allowance near a singular "
                  "position reaches 1% of max(|x|, its strict bound): the reference's own "
                  "conditioning leaves its value open to that much, so no allowance passes an "
                  "error of 1% or more; such cells are named as not judged (exit status 2)",
    "libreoffice": "1e-9·max(|x|, the unit's bound): it keeps 15 digits",
    "gnumeric": "as libreoffice: 1e-9·max(|x|, the unit's bound)",
}



@dataclass
class Mismatch:
    """A cell whose value differs from the reference's: what was expected, what it holds."""
    sheet: str
    cell: str
    expected: object
    got: object


class JudgedCells:
    """The (sheet, cell) keys a check judged, held as a list of cells a sheet (a big book's
    checks judge hundreds of thousands: a set would hold a tuple each). Iterated and compared
    as the set of its keys."""
    __slots__ = ("by_sheet",)

    def __init__(self, keys=()):
        self.by_sheet: dict[str, list[str]] = {}
        self.update(keys)

    def add(self, key: tuple[str, str]) -> None:
        self.by_sheet.setdefault(key[0], []).append(key[1])

    def update(self, keys) -> None:
        for key in keys:
            self.add(key)

    def extend(self, sheet: str, cells: list[str]) -> None:
        self.by_sheet.setdefault(sheet, []).extend(cells)

    def __iter__(self):
        for sheet, cells in self.by_sheet.items():
            for cell in dict.fromkeys(cells):
                yield sheet, cell

    def __len__(self) -> int:
        return sum(len(set(cells)) for cells in self.by_sheet.values())

    def __eq__(self, other) -> bool:
        return set(self) == set(other)

    __hash__ = None


def judged_count(checks, excluded) -> int:
    """How many cells `checks` judged between them, each counted once, but for the (sheet,
    cell) keys `excluded`: counted a sheet at a time, with no key made for each cell."""
    by_sheet: dict[str, set[str]] = {}
    for check in checks:
        for sheet, cells in check.judged.by_sheet.items():
            by_sheet.setdefault(sheet, set()).update(cells)
    for sheet, cell in set(excluded):
        by_sheet.get(sheet, set()).discard(cell)
    return sum(map(len, by_sheet.values()))


@dataclass
class Check:
    """One column (or grid, or block) of formula cells compared with the reference."""
    block: str
    name: str
    size: float = math.inf      # the mechanism's size S (sum of its input lengths)
    rate: float = 1.0           # per second, per second²: a velocity's or acceleration's scale
    scale: float | None = None  # the unit's natural magnitude: S (length), S² (area); None for
                                # a quantity with no length in it (an angle, a ratio, a count)
    cells: int = 0
    max_abs: float = 0.0
    na_expected: int = 0
    na_agree: int = 0
    dead_centre: int = 0        # rates at a dead centre: not determined by the data
    # cells too near a singular position to judge: the allowance they need reaches DETERMINED
    # of their value (see `determines`)
    not_judged: list[tuple[str, str]] = field(default_factory=list)
    mismatches: list[Mismatch] = field(default_factory=list)
    # one line per stretch of rows where the book's method reaches another assembly than the
    # reference's continuation (judge.note_other_assembly): named, not passed
    assembly: list[str] = field(default_factory=list)
    judged: JudgedCells = field(default_factory=JudgedCells, repr=False)  # (sheet, cell)

    @property
    def ok(self) -> bool:
        return not self.mismatches

    def limit(self, expected: float, tol: float = ABS_TOL, relative: bool = False,
              grows: bool = True) -> float:
        """|Δ| allowed: tol per PER units of the quantity's magnitude (see PER): for a length
        m = S·rate and the bound tol·m/PER, for an angle or an angular rate m = rate and the
        bound tol·m. Where a value only gets near a singular position (the pump's plunger as its
        slot turns parallel to the plunger line, s15 ~ 1/cos θ14; an angular velocity near a
        dead centre, ω ~ 1/det) the error of any double-precision evaluation grows like |x|²/m,
        and so does the bound once that is larger: tol·|x|²/(PER·m), which is the length's
        base bound times (|x|/m)². An angle itself (`grows` False: it is periodic, it never
        gets large) keeps tol. `relative` (LibreOffice keeps 15 digits): tol·max(|x|, base)."""
        linear = self.scale is not None
        magnitude = max((self.scale if linear else 1.0) * self.rate, 1e-300)
        base = tol * magnitude / PER if linear else tol * magnitude
        if relative:
            return max(tol * abs(expected), base)
        if not grows:
            return base
        return max(base, tol * expected * expected / (PER * magnitude))

    @staticmethod
    def determines(allowed: float, expected: float, strict: float) -> bool:
        """Does a bound of `allowed` still judge a value of `expected` (whose strict bound is
        `strict`)? Each allowance near a singular position is a forward-error bound, u·κ·|x|
        (κ the condition number) with the bound's margin over u: it grows without limit as
        the position nears the singularity. Once it reaches DETERMINED of the value, the data
        (as the reference's conditioning sees them) no longer fix the value to better than
        that, and a bound that wide would pass a wrong formula (twice the value, once it
        reaches |x|): the cell is not judged. Below it, whatever passes is within 1%."""
        return allowed < DETERMINED * max(abs(expected), strict)

    def judge(self, sheet: str, cell: str, expected: float, got: float, diff: float,
              strict: float, allowed: Callable[[], float]) -> None:
        """One number against the reference, `diff` apart: agrees within `strict` (the bound
        away from any singular position); else differs beyond `allowed()` (the allowance near
        one, asked only here), or is not judged where that allowance no longer `determines`
        the value."""
        if diff <= strict:
            return
        bound = allowed()
        if diff > bound:
            self.mismatches.append(Mismatch(sheet, cell, expected, got))
        elif not self.determines(bound, expected, strict):
            self.not_judged.append((sheet, cell))

    def beyond_rounding(self, values) -> bool:
        """Is some value so far out that its rounding bound (see `limit`) no longer
        `determines` it? A point a round-off determinant puts at "infinity" (a lever parallel
        to the ram line it should meet): its size, even its sign, is the rounding's, so an
        extreme taken over it is not determined."""
        v = np.abs(np.asarray(values, dtype=float))
        v = v[np.isfinite(v)]
        if not v.size:
            return False
        far = float(v.max())
        return not self.determines(self.limit(far), far, self.limit(far, grows=False))

    def as_dict(self) -> dict:
        return {"block": self.block, "column": self.name, "cells": self.cells,
                "max_abs_diff": self.max_abs, "na_expected": self.na_expected,
                "na_agree": self.na_agree, "dead_centre": self.dead_centre,
                "not_judged": len(self.not_judged), "ok": self.ok,
                "other_assembly": self.assembly,
                "mismatches": [m.__dict__ for m in self.mismatches[:20]]}


STORED = "stored"      # the block of the check of stored values (stored.py)


def differing(checks: list[Check]) -> set[tuple[str, str]]:
    """The cells that differ in any of `checks`, each once."""
    return {(m.sheet, m.cell) for c in checks for m in c.mismatches}


def undetermined(checks: list[Check]) -> set[tuple[str, str]]:
    """The cells too near a singular position to judge in any of `checks`
    (Check.determines), each once; a cell that differs in one of them is counted there."""
    return set().union(*(c.not_judged for c in checks)) - differing(checks)


def expected_of(ref: dict, key: str) -> np.ndarray:
    """Reference values for a column key; `_deg` keys are the degree view of a radian key."""
    if key.endswith("_deg") and key[:-4] in ref:
        return np.degrees(np.asarray(ref[key[:-4]], dtype=float))
    return np.asarray(ref[key], dtype=float)


SENSITIVITY_STEP = 1e-7      # rad, for the central difference of the reference
# rad: shorter steps, for a row within SENSITIVITY_STEP of a limit position (context.slope_of)
NEARER_STEPS = tuple(SENSITIVITY_STEP * 10.0 ** -k for k in range(1, 7))
ROUNDING = 1e-12             # rad: what rounding can do to an input angle's effect on a result
EDGE_SLOPE = 1e6             # at an isolated limit position: ROUNDING·EDGE_SLOPE = 1e-6


@dataclass(frozen=True)
class Rules:
    """How the values were computed and how they are judged: how the engine shows an error
    (`is_error`; `error_code` gives its code, or None), and the bound: `tol` per PER units of a
    quantity's magnitude, `relative` for an application that keeps 15 digits."""
    is_error: Callable
    error_code: Callable
    tol: float = ABS_TOL
    relative: bool = False


def compare(check: Check, sheet: str, cells: list[str], got: list, expected, unit: str,
            rules: Rules, slope=None, dead=None, sine=None) -> None:
    """`slope(i)`: |∂x/∂θ| of cell i from the reference, asked only for a cell that misses the
    strict bound. Near a limit position (an ACOS argument close to ±1, the pump's cos θ14 close
    to 0) every evaluation loses digits in proportion to it, so such a cell may differ by
    ROUNDING·|∂x/∂θ| more: the forward-error bound, not a looser test of healthy cells.
    `sine` (rates): per row, the reference's smallest sine between a loop's two constraint
    gradients; near a dead centre the rounding of any evaluation of a rate grows like 1/sine²,
    and so may a cell that misses the strict bound: base bound / sine²."""
    is_error, error_code, tol, relative = rules.is_error, rules.error_code, rules.tol, \
        rules.relative
    period = ANGLE_UNITS.get(unit)
    expected = np.asarray(expected, dtype=float)
    if expected.shape != (len(cells),):     # a column already (most): no view made of it
        expected = np.broadcast_to(expected, (len(cells),))
    rest = _agreeing(check, sheet, cells, got, expected, period, rules)
    for i in rest:
        cell, value, exp = cells[i], got[i], expected[i]
        check.cells += 1
        check.judged.add((sheet, cell))
        exp = float(exp)
        if math.isnan(exp) and dead is not None and dead[i]:
            # a dead centre (to within the reference's own accuracy there): a rate is not
            # determined by the data; #N/A or any number is the workbook's honest answer, but
            # not #DIV/0! or another error
            if is_error(value) and error_code(value) != "#N/A":
                check.mismatches.append(Mismatch(sheet, cell, "#N/A or a number",
                                                 show(value, error_code)))
            else:
                check.dead_centre += 1
            continue
        if math.isnan(exp):
            check.na_expected += 1
            if is_error(value) and error_code(value) == "#N/A":
                check.na_agree += 1
            else:
                check.mismatches.append(Mismatch(sheet, cell, "#N/A", show(value, error_code)))
            continue
        if math.isinf(exp):
            # the exact value is beyond the largest float (a quotient of a tiny ω², say): the
            # application's answer is its overflow error, #NUM! (Excel, LibreOffice, formulas)
            # or the infinity itself (Gnumeric); any finite number is wrong
            if error_code(value) != "#NUM!" and not (isinstance(value, float) and value == exp):
                check.mismatches.append(Mismatch(sheet, cell, "#NUM! (beyond the float range)",
                                                 show(value, error_code)))
            continue
        if is_error(value) or not isinstance(value, (int, float)) or isinstance(value, bool):
            check.mismatches.append(Mismatch(sheet, cell, exp, show(value, error_code)))
            continue
        diff = float(value) - exp
        if period:
            diff = (diff + period / 2) % period - period / 2
        diff = abs(diff)
        check.max_abs = max(check.max_abs, diff)

        def allowed(i=i, exp=exp, diff=diff) -> float:
            limit = check.limit(exp, tol, relative, grows=not period)
            if diff > limit and slope is not None:
                limit += ROUNDING * slope(i)
            if diff > limit and sine is not None and sine[i] < 1.0:
                limit = max(limit, check.limit(0.0, tol, relative)
                            / max(float(sine[i]), 1e-150) ** 2)
            return limit
        check.judge(sheet, cell, exp, float(value), diff,
                    check.limit(exp, tol, relative, grows=False), allowed)


_NUMBER_TYPES = frozenset({float, int})


def _agreeing(check: Check, sheet: str, cells: list[str], got: list, expected: np.ndarray,
              period: float | None, rules: Rules) -> list[int]:
    """The cells that agree within the strict bound, counted into `check` as compare's loop
    counts them, taken as arrays (most cells of a book); the indexes of the others, for that
    loop to judge one by one."""
    # exactly a float or an int (no error value, bool or numpy scalar: the loop takes those);
    # a column of numbers only (most of a book) is taken whole
    if set(map(type, got)) <= _NUMBER_TYPES:
        number, value = np.ones(len(got), dtype=bool), np.array(got, dtype=float)
    else:
        number = np.fromiter((type(v) in _NUMBER_TYPES for v in got), bool, len(got))
        value = np.array([v if n else math.nan for v, n in zip(got, number.tolist())],
                         dtype=float)
    diff = value - expected
    if period:
        diff = (diff + period / 2) % period - period / 2
    diff = np.abs(diff)
    strict = (np.maximum(rules.tol * np.abs(expected), check.limit(0.0, rules.tol, grows=False))
              if rules.relative else check.limit(0.0, rules.tol, grows=False))
    with np.errstate(invalid="ignore"):
        agree = number & ~np.isnan(expected) & (diff <= strict)
    if agree.any():
        check.cells += int(agree.sum())
        check.max_abs = max(check.max_abs, float(diff[agree].max()))
        check.judged.extend(sheet, [cells[i] for i in np.flatnonzero(agree).tolist()])
    return np.flatnonzero(~agree).tolist()


def show(value, error_code):
    code = error_code(value)
    return code if code else value



def unit_scale(unit: str, size: float) -> float | None:
    """The natural magnitude of a unit: S for a length (also per second, per second²), S² for
    an area; None for an angle, a ratio or a count (a quantity with no length in it)."""
    from ..language.model import ACCEL, AREA, LENGTH, SPEED
    if unit in (LENGTH, SPEED, ACCEL):
        return size
    return size * size if unit == AREA else None


def column_unit(model, key: str) -> str:
    if key.endswith("_deg"):
        return "deg"
    return model.get(key).unit


def compare_exact(check: Check, sheet: str, cells: list[str], got: list, expected: list,
                  slack: list | None = None, units: list | None = None) -> None:
    """Text (and bookkeeping) cells: the same text, or the same number within the bound
    (plus `slack`, for an extreme taken at a limit position; `units`: each cell's unit, which
    sets its bound, else the check's own)."""
    for i, (cell, value, exp) in enumerate(zip(cells, got, expected)):
        extra = slack[i] if slack else 0.0
        check.cells += 1
        check.judged.add((sheet, cell))
        if isinstance(exp, str) or isinstance(value, str):
            if value != exp:
                check.mismatches.append(Mismatch(sheet, cell, exp, value))
            continue
        if not isinstance(value, (int, float)):
            check.mismatches.append(Mismatch(sheet, cell, exp, value))
            continue
        bounds = Check(check.block, check.name, check.size, check.rate,
                       unit_scale(units[i], check.size)) if units else check
        grows = units[i] not in ANGLE_UNITS if units else True
        diff = abs(float(value) - exp)
        before = len(check.mismatches)
        check.judge(sheet, cell, exp, value, diff, bounds.limit(exp, grows=False),
                    lambda: bounds.limit(exp, grows=grows) + extra)
        if len(check.mismatches) == before:
            check.max_abs = max(check.max_abs, diff)

