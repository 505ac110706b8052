"""Re-check a linkbook workbook against the independent reference.

The workbook says what it is (the hidden `linkbook` sheet: mechanism and layout); its inputs are
read from its own cells, so a book edited in Excel is verified with its new numbers. Every formula
cell is evaluated by an engine and compared with reference.solve() at the angles and adjustments
the sheets hold: |Δ| ≤ tolerance where the loop closes, #N/A exactly where it cannot.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import reference as generic
from ..base import sheets as layout
from ..base.pause import gc_paused
from ..base.sheets import summary_prefix
from ..language.model import RAD
from ..language.domain import (InputError, check_input, check_lengths_together, check_value,
                     check_written_lengths)

ABS_TOL = 1e-9
ANGLE_UNITS = {"rad": 2 * math.pi, "deg": 360.0}
# The bound is ABS_TOL per PER units of a quantity's natural magnitude: the mechanism's size S
# for a length (S² for an area), 1 for an angle or a ratio, each times the input's rate for a
# velocity or an acceleration. So a mechanism in metres and the same one in micrometres are
# judged alike: |Δ| ≤ 1e-12·S for a length, 1e-9 for an angle.
PER = 1e3
TOLERANCE_RULE = {
    "length": "1e-12·S (S the mechanism's size; S² for an area; times the input's rate for a "
              "velocity or an acceleration)",
    "angle": "1e-9 (times the input's rate for an angular velocity or acceleration)",
    "singular": "a length or a rate beyond its magnitude m may differ by 1e-12·|x|²/m; near a "
                "limit position a further 1e-12·|∂x/∂θ|, at an isolated one 1e-6; a rate near a "
                "dead centre its base bound / sine² (sine: between a loop's constraint "
                "gradients)",
    "libreoffice": "1e-9·max(|x|, the unit's bound): it keeps 15 digits",
    "gnumeric": "as libreoffice: 1e-9·max(|x|, the unit's bound)",
}


class UnusableFile(Exception):
    """The file cannot be verified at all (exit 2)."""


@dataclass
class Mismatch:
    sheet: str
    cell: str
    expected: object
    got: object


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
    mismatches: list[Mismatch] = field(default_factory=list)
    judged: set[tuple[str, str]] = field(default_factory=set, repr=False)  # (sheet, cell)

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

    def as_dict(self) -> dict:
        return {"block": self.block, "column": self.name, "cells": self.cells,
                "max_abs_diff": self.max_abs, "na_expected": self.na_expected,
                "na_agree": self.na_agree, "dead_centre": self.dead_centre, "ok": self.ok,
                "mismatches": [m.__dict__ for m in self.mismatches[:20]]}


@dataclass
class Report:
    path: str
    mechanism: str
    engine: str
    checks: list[Check]
    formula_cells: int = 0                    # in the whole book
    unjudged: list[tuple[str, str]] = field(default_factory=list)   # formula cells not compared
    inputs: dict[str, float] = field(default_factory=dict)          # as read from the book
    size: float = 0.0                         # S, the mechanism's size
    causes: set[tuple[str, str]] = field(default_factory=set)   # differing cells reading none
    sheets: list[str] = field(default_factory=list)  # the book's sheets in its tab order
    error: str | None = None        # why the book cannot be verified at all (status 2)
    # cells the build record holds formulas in that hold a constant instead
    replaced: list[tuple[str, str]] = field(default_factory=list)
    # cells the build record holds formulas in that are empty or on a sheet deleted (each
    # differs: it has no value)
    absent: list[tuple[str, str]] = field(default_factory=list)

    @property
    def disagrees(self) -> bool:
        return any(not c.ok for c in self.checks)

    @property
    def ok(self) -> bool:
        return not self.disagrees and not self.unjudged and self.error is None

    @property
    def status(self) -> int:
        """The exit status: 0 every formula cell agrees, 1 a cell disagrees, 2 some formula
        cells cannot be judged (and none disagrees), or the book cannot be verified at all."""
        if self.error is not None:
            return 2
        return 1 if self.disagrees else 2 if self.unjudged else 0

    @property
    def cells(self) -> int:
        """Formula cells compared with the reference (each counted once; a constant where the
        record has a formula is judged, and differs, but is not a formula cell)."""
        return len(set().union(*(c.judged for c in self.checks)) - set(self.replaced)
                   - set(self.absent))

    @property
    def stored_differ(self) -> int:
        """Formula cells whose stored value (what a reader that does not calculate shows)
        differs from the reference."""
        return sum(len(c.mismatches) for c in self.checks if c.block == STORED)

    @property
    def differing(self) -> int:
        """Cells that differ from the reference (each counted once)."""
        return len({(m.sheet, m.cell) for c in self.checks for m in c.mismatches})

    @property
    def max_abs(self) -> float:
        return max((c.max_abs for c in self.checks), default=0.0)


# ---------------------------------------------------------------- reading the book
def inputs_of(wb, meta: dict) -> dict[str, float]:
    """The parameter values as they stand in the workbook's input cells."""
    ws = wb[layout.MECH]
    values = {}
    for symbol, info in meta["inputs"].items():
        raw = ws[info["cell"]].value
        try:
            values[symbol] = check_value(f"input {symbol} (cell {info['cell']})", info["kind"], raw)
        except InputError as exc:
            raise UnusableFile(str(exc)) from None
    try:
        check_lengths_together(values, {s: i["kind"] for s, i in meta["inputs"].items()},
                               "input ", written_in(meta))
    except InputError as exc:
        raise UnusableFile(str(exc)) from None
    return values


def written_in(meta: dict) -> dict[str, float]:
    """The lengths the recorded description writes as numbers (domain.written_lengths)."""
    try:
        return check_written_lengths(meta.get("description") or {}, "the book's record: ")
    except InputError as exc:
        raise UnusableFile(str(exc)) from None


def _angles(ws, column: str, rows: list[int], is_angle: bool) -> np.ndarray:
    return np.array([_input(ws, f"{column}{r}", "input value", is_angle)
                     for r in range(rows[0], rows[1] + 1)])


def _input(ws, cell: str, what: str, is_angle: bool) -> float:
    """An input angle (or actuator length): a number within the supported domain."""
    try:
        return check_input(f"{ws.title}!{cell}: {what}", _number(ws, cell, what), is_angle)
    except InputError as exc:
        raise UnusableFile(str(exc)) from None


def _number(ws, cell: str, what: str) -> float:
    v = ws[cell].value
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        raise UnusableFile(f"{ws.title}!{cell}: {what} must be a number (got {v!r})")
    return float(v)


def mechanism_size(meta: dict, params: dict[str, float]) -> float:
    """S: the sum of the input lengths and offsets and of the lengths the description writes as
    numbers (every frame fits in a circle that big)."""
    kinds = {s: info["kind"] for s, info in meta["inputs"].items()}
    size = sum(abs(v) for s, v in params.items() if kinds[s] in ("length", "offset"))
    return max(size + sum(abs(v) for v in written_in(meta).values()), 1e-300)


# ---------------------------------------------------------------- comparing
def _expected(ref: dict, key: str) -> np.ndarray:
    """Reference values for a column key; `_deg` keys are the degree view of a radian key."""
    if key.endswith("_deg") and key[:-4] in ref:
        return np.degrees(np.asarray(ref[key[:-4]], dtype=float))
    return np.asarray(ref[key], dtype=float)


SENSITIVITY_STEP = 1e-7      # rad, for the central difference of the reference
ROUNDING = 1e-12             # rad: what rounding can do to an input angle's effect on a result
EDGE_SLOPE = 1e6             # at an isolated limit position: ROUNDING·EDGE_SLOPE = 1e-6


def compare(check: Check, sheet: str, cells: list[str], got: list, expected, unit: str,
            is_error, error_code, tol: float = ABS_TOL, relative: bool = False,
            slope=None, dead=None, sine=None) -> None:
    """`slope(i)`: |∂x/∂θ| of cell i from the reference, asked only for a cell that misses the
    strict bound. Near a limit position (an ACOS argument close to ±1, the pump's cos θ14 close
    to 0) every evaluation loses digits in proportion to it, so such a cell may differ by
    ROUNDING·|∂x/∂θ| more: the forward-error bound, not a looser test of healthy cells.
    `sine` (rates): per row, the reference's smallest sine between a loop's two constraint
    gradients; near a dead centre the rounding of any evaluation of a rate grows like 1/sine²,
    and so may a cell that misses the strict bound: base bound / sine²."""
    period = ANGLE_UNITS.get(unit)
    for i, (cell, value, exp) in enumerate(zip(cells, got,
                                               np.broadcast_to(expected, (len(cells),)))):
        check.cells += 1
        check.judged.add((sheet, cell))
        exp = float(exp)
        if math.isnan(exp) and dead is not None and dead[i]:
            # a dead centre (to within the reference's own accuracy there): a rate is not
            # determined by the data; #N/A or any number is the workbook's honest answer, but
            # not #DIV/0! or another error
            if is_error(value) and error_code(value) != "#N/A":
                check.mismatches.append(Mismatch(sheet, cell, "#N/A or a number",
                                                 _show(value, error_code)))
            else:
                check.dead_centre += 1
            continue
        if math.isnan(exp):
            check.na_expected += 1
            if is_error(value) and error_code(value) == "#N/A":
                check.na_agree += 1
            else:
                check.mismatches.append(Mismatch(sheet, cell, "#N/A", _show(value, error_code)))
            continue
        if is_error(value) or not isinstance(value, (int, float)) or isinstance(value, bool):
            check.mismatches.append(Mismatch(sheet, cell, exp, _show(value, error_code)))
            continue
        diff = float(value) - exp
        if period:
            diff = (diff + period / 2) % period - period / 2
        diff = abs(diff)
        check.max_abs = max(check.max_abs, diff)
        limit = check.limit(exp, tol, relative, grows=not period)
        if diff > limit and slope is not None:
            limit += ROUNDING * slope(i)
        if diff > limit and sine is not None and sine[i] < 1.0:
            limit = max(limit, check.limit(0.0, tol, relative) / max(float(sine[i]), 1e-150) ** 2)
        if diff > limit:
            check.mismatches.append(Mismatch(sheet, cell, exp, float(value)))


def _show(value, error_code):
    code = error_code(value)
    return code if code else value


def _show_stored(value, error_code):
    """A stored or computed value as the stored check names it: a text quoted, so that the
    text "1.5" does not read as the number 1.5."""
    from ..base.xlsx import CellError
    if isinstance(value, CellError):
        return str(value)
    shown = _show(value, error_code)
    return repr(shown) if isinstance(shown, str) and not error_code(value) else shown


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


# ---------------------------------------------------------------- the reference of a book
class Reference:
    """The independent solver of one book's mechanism: the generic reference (generic.py), given
    the description the book records, with the book's own input values."""

    def __init__(self, meta: dict):
        from ..language.model import DescriptionError
        from ..language.templates import from_record
        try:
            self.mechanism = from_record(meta)
        except (DescriptionError, KeyError, TypeError, AttributeError) as exc:
            raise UnusableFile(f"the mechanism recorded in the book is unusable: {exc}") \
                from None
        self.description = self.mechanism.description

    def solve(self, params: dict, angles) -> dict:
        return generic.solve(self.description, params, angles)

    def fourbar_loops(self, params: dict):
        return generic.fourbar_loops(self.description, params)

    def limit_angles(self, params: dict, length: float, loop: int = 0) -> list[float]:
        return generic.limit_angles(self.description, params, length, loop)


# ---------------------------------------------------------------- blocks
def check_book(wb, meta: dict, values: dict, is_error, error_code, *, tol: float = ABS_TOL,
               relative: bool = False) -> list[Check]:
    solver = Reference(meta)
    mech = solver.mechanism
    model = mech.build()
    params = inputs_of(wb, meta)
    size = mechanism_size(meta, params)
    checks: list[Check] = []

    def run(block, name, sheet, cells, expected, unit, slope=None, rate=1.0, dead=None,
            sine=None):
        c = Check(block, name, size, rate, unit_scale(unit, size))
        compare(c, sheet, cells, [values.get((sheet, x)) for x in cells], expected, unit,
                is_error, error_code, tol, relative, slope, dead, sine)
        checks.append(c)

    # The sweep table, column by column.
    sweep = meta["sweep"]
    ws = wb[sweep["sheet"]]
    rows = sweep["rows"]
    angles = _angles(ws, "A", rows, mech.input_is_angle)
    # the slope of a cell is taken per radian of a crank, per `size` of an actuator's stroke
    scale = math.degrees(1.0) if mech.input_is_angle else size
    ref = solver.solve(params, angles)
    slopes = {}
    for key, letter in sweep["columns"].items():
        if key == mech.input_column or key in ASSEMBLY_COLUMNS:
            continue
        cells = [f"{letter}{r}" for r in range(rows[0], rows[1] + 1)]
        unit = column_unit(model, key)
        slopes[key] = _slope(solver, params, angles, key, unit, scale=scale)
        run(layout.SWEEP, key, sweep["sheet"], cells, _expected(ref, key), unit, slopes[key])

    # The current position, the joints and the drawing rows.
    pos = meta["position"]
    angle = _input(wb[pos["sheet"]], pos["input_cell"], f"the current input {mech.input_word}",
                   mech.input_is_angle)
    one = solver.solve(params, np.array([angle]))
    for key, cell in pos["cells"].items():
        unit = column_unit(model, key)
        run("position", key, pos["sheet"], [cell], _expected(one, key), unit,
            _slope(solver, params, np.array([angle]), key, unit, scale=scale))
    joint_values = {name: (float(x[0]), float(y[0])) for name, (x, y) in one["points"].items()}
    for joint in model.joints:
        x_cell, y_cell = pos["joints"][joint.name]
        run("joints", joint.name, pos["sheet"], [x_cell, y_cell],
            np.array(joint_values[joint.name]), "length")
    joints = {j.name: joint_values[j.name] for j in model.joints}   # the joints table's
    # the sliders' guides and blocks: the reference's, sized in the drawing's grid square
    drawn, over_sweep = dict(joint_values), ref
    if "frames" in meta:
        square = _drawing_square(meta, values, ref, joints)
        sliders = generic.slider_drawing(solver.description, params, ref, one, square)
        drawn.update({name: (float(x[0]), float(y[0])) for name, (x, y) in sliders.items()})
        over_sweep = {**ref, "points": {**ref["points"], **generic.slider_drawing(
            solver.description, params, ref, ref, square)}}
    drawing_cells, drawing_expected = [], []
    for link in pos["drawing"]:
        for i, name in enumerate(link["joints"]):
            r = link["rows"][0] + i
            drawing_cells += [f"N{r}", f"O{r}"]
            drawing_expected += list(drawn.get(name, (math.nan, math.nan)))
    run("joints", "drawing rows", pos["sheet"], drawing_cells, np.array(drawing_expected),
        "length")
    checks.append(_check_links(pos, solver.description, over_sweep, size))
    if "frames" in meta:
        checks += _check_frames(meta, values, ref, joints, drawn, slopes, size, is_error,
                                error_code, tol, relative)
    checks += _check_degree_windows(model, mech.input_column, sweep, pos, ref, values, size)
    checks += _check_numbers_only(meta, values, size)

    # Derived constants: a time ratio from the reversals of its output (the reference's own
    # motion, not the template's formula); any other from the reference.
    ratios = time_ratios(solver.description)
    for key, info in meta.get("constants", {}).items():   # solve() returns them as floats
        if key in ratios:
            c = Check(f"reversals of {ratios[key]}", key, size)
            compare(c, layout.MECH, [info["cell"]], [values.get((layout.MECH, info["cell"]))],
                    np.array([generic.time_ratio(solver.description, params, ratios[key])]),
                    info["unit"], is_error, error_code, RATIO_TOL, True)
            checks.append(c)
            continue
        run("constants", key, layout.MECH, [info["cell"]], np.array([float(ref[key])]),
            info["unit"])

    if "motion" in meta:
        _check_motion(meta, model, solver, params, angles, ref, one, angle, scale, size, run)
    if "closes" in sweep["columns"]:
        checks += _check_assembly(wb, meta, model, solver, params, angles, ref, values, size)
    if "grid" in meta:
        checks += _check_grid(wb, meta, solver, params, values, is_error, error_code, tol,
                              relative, size)
    return checks


RATIO_TOL = 1e-6     # relative: a reversal's angle is located to 1e-6° (generic.time_ratio)


def time_ratios(description: dict) -> dict[str, str]:
    """{expression key: output key} for the expressions declared a time ratio (time_ratio_of)."""
    return {s["key"]: s["time_ratio_of"] for s in description.get("steps", [])
            if isinstance(s, dict) and s.get("type") == "expression" and "time_ratio_of" in s}


def joined_pairs(description: dict, ref: dict, size: float) -> set[frozenset]:
    """Pairs of points the reference knows are joined, found without the description's list of
    links: a step's new point and each point the step names (a crank's pivot, a dyad's two
    ends, a slider's line, an actuator's ends; a vector's two ends), any two points of one
    slider's guide or of one block (generic.slider_parts), and any two points whose distance
    never changes over the sweep (a rigid link, the ground)."""
    pairs = {frozenset((a, b)) for part in generic.slider_parts(description)
             for a in part for b in part if a != b}
    for step in description.get("steps", []):
        if not isinstance(step, dict):
            continue
        named = _point_names({k: v for k, v in step.items()
                              if k not in ("point", "columns", "type", "key")})
        if isinstance(step.get("point"), str):
            pairs.update(frozenset((step["point"], name)) for name in named)
        else:       # a vector (from, to): the two points it measures between
            pairs.update(frozenset((a, b)) for a in named for b in named if a != b)
    points = ref.get("points", {})
    names = sorted(points)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (xa, ya), (xb, yb) = points[a], points[b]
            d = np.hypot(np.asarray(xa, float) - xb, np.asarray(ya, float) - yb)
            d = d[np.isfinite(d)]
            if d.size and np.ptp(d) <= 1e-9 * size:
                pairs.add(frozenset((a, b)))
    return pairs


def _point_names(value) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [n for v in value.values() for n in _point_names(v)]
    if isinstance(value, list):
        return [n for v in value for n in _point_names(v)]
    return []


def _check_links(pos: dict, description: dict, ref: dict, size: float) -> Check:
    """Each segment the drawing draws joins two points the reference knows are joined (a check
    of the drawing's structure: its cells are compared in "drawing rows")."""
    c = Check("joints", "drawn links", size)
    joined = joined_pairs(description, ref, size)
    x_col = layout.DRAWING_COLUMNS[0]
    for link in pos["drawing"]:
        names = link["joints"]
        for i, (a, b) in enumerate(zip(names, names[1:])):
            if a != b and frozenset((a, b)) not in joined:
                c.mismatches.append(Mismatch(pos["sheet"], f"{x_col}{link['rows'][0] + i + 1}",
                                             "a link between joined points",
                                             f"{a}–{b}, which nothing joins"))
    return c


# ---------------------------------------------------------------- drawing frames
# The rule of a live frame (docs/mechanisms.md, "Drawings"), restated here from the documented
# convention: the frame is centred on the extents of what a chart draws, and a grid square is
# the smallest 1, 2 or 5 × 10ⁿ that fits MARGIN times the larger extent in 2·HALF squares.
FRAME_HALF, FRAME_MARGIN = 5, 1.12
FRAME_SQUARES = (1.0, 2.0, 5.0, 10.0)


def frame_squares(need: float) -> list[tuple[float, float]]:
    """(power of ten, grid square) for `need` per square; two when `need` is within rounding of
    a step (1, 2, 5 × 10ⁿ), where either evaluation may fall on either side."""
    out = []
    for r in (need * (1 - 1e-9), need, need * (1 + 1e-9)):
        decade = 10.0 ** math.floor(math.log10(r))
        square = decade * next(m for m in FRAME_SQUARES if r <= m * decade * (1 + 1e-15))
        if (decade, square) not in out:
            out.append((decade, square))
    return out


def _frame_extents(frame: dict, ref: dict, joint_values: dict) -> tuple[dict, dict, float]:
    """The least and greatest x and y of what a frame holds (the reference's), and the size
    needed per grid square."""
    ext = frame["extent"]
    lo, hi = {}, {}
    for i, axis in enumerate("xy"):
        parts = [_expected(ref, key) for key in ext[axis]]
        if ext["position"]:
            parts.append(np.array([xy[i] for xy in joint_values.values()]))
        v = np.concatenate(parts) if parts else np.array([])
        v = v[np.isfinite(v)]
        lo[axis], hi[axis] = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
    need = max(hi["x"] - lo["x"], hi["y"] - lo["y"], 1e-12) * FRAME_MARGIN / (2 * FRAME_HALF)
    return lo, hi, need


def _drawing_square(meta: dict, values: dict, ref: dict, joint_values: dict) -> float:
    """The drawing's grid square by the rule, from the reference's extents (where the need is
    within rounding of a step, the one the book chose)."""
    frame = meta["frames"]["frames"][0]
    options = [square for _, square in frame_squares(_frame_extents(frame, ref,
                                                                    joint_values)[2])]
    got = values.get((meta["frames"]["sheet"], frame["cells"]["square"]))
    return next((o for o in options if isinstance(got, (int, float))
                 and abs(got - o) <= 1e-12 * o), options[0])


def _check_frames(meta, values, ref, joint_values, drawn, slopes, size, is_error, error_code,
                  tol, relative) -> list[Check]:
    """Each equal-scale chart's frame (extents, centre, grid square, the scale bar's legend)
    from the reference's points (`joint_values`: the joints table's), and each mapped cell:
    the reference's coordinate in squares of that frame (`drawn`: every drawn point's)."""
    sheet, pos = meta["frames"]["sheet"], meta["position"]
    unit = meta.get("length_unit", "mm")
    checks = []
    for frame in meta["frames"]["frames"]:
        name = "drawing" if "chart" not in frame else f"chart {frame['chart'] + 1}"
        cells = frame["cells"]
        lo, hi, need = _frame_extents(frame, ref, joint_values)
        centre = {"x": (lo["x"] + hi["x"]) / 2, "y": (lo["y"] + hi["y"]) / 2}
        expected = {"xmin": lo["x"], "xmax": hi["x"], "ymin": lo["y"], "ymax": hi["y"],
                    "cx": centre["x"], "cy": centre["y"], "need": need}
        c = Check("frame", f"{name}: extents", size, 1.0, size)
        keys = list(expected)
        compare(c, sheet, [cells[k] for k in keys],
                [values.get((sheet, cells[k])) for k in keys],
                np.array([expected[k] for k in keys]), "length", is_error, error_code, tol,
                relative)
        checks.append(c)
        square_check, g = _check_square(sheet, cells, values, need, size, unit, name)
        checks.append(square_check)
        for s in frame["series"]:
            checks += _check_mapped(sheet, s, pos, values, ref, drawn, slopes, centre,
                                    g, f"{name}: {s['title']}", size, is_error, error_code,
                                    tol, relative)
    return checks


def _check_square(sheet, cells, values, need, size, unit, name) -> tuple[Check, float]:
    """The power of ten and the grid square: the rule's choice for the reference's `need`
    (either one at a step); the legend's text names the square the book chose."""
    c = Check("frame", f"{name}: grid square", size, 1.0, size)
    options = frame_squares(need)
    got = tuple(values.get((sheet, cells[k])) for k in ("decade", "square"))
    chosen = next((o for o in options if all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v - e) <= 1e-12 * e
        for v, e in zip(got, o))), None)
    for k, v, e in zip(("decade", "square"), got, options[0]):
        c.cells += 1
        c.judged.add((sheet, cells[k]))
        if chosen is None:
            c.mismatches.append(Mismatch(sheet, cells[k], " or ".join(
                f"{o[k == 'square']:g}" for o in options), v))
    square = (chosen or options[0])[1]
    places = max(0, -math.floor(round(math.log10(square), 6)))
    compare_exact(c, sheet, [cells["label"]], [values.get((sheet, cells["label"]))],
                  [f"grid square {square:.{places}f} {unit}"])
    return c, square


def _check_mapped(sheet, series, pos, values, ref, joint_values, slopes, centre, square,
                  name, size, is_error, error_code, tol, relative) -> list[Check]:
    """A mapped column pair: (coordinate − centre) / square, the coordinate the reference's
    (a joint at the current position, or a sweep column at the sweep's angles), judged with the
    bound of a length scaled to squares."""
    first, last = series["mapped_rows"]
    out = []
    for i, axis in enumerate("xy"):
        letter = series["columns"][i]
        cells = [f"{letter}{r}" for r in range(first, last + 1)]
        slope = None
        if series["kind"] == "links":
            world = np.full(len(cells), np.nan)
            for link in pos["drawing"]:
                for k, joint in enumerate(link["joints"]):
                    world[link["rows"][0] + k - series["rows"][0]] = \
                        joint_values.get(joint, (math.nan, math.nan))[i]
        else:
            key = series[axis]
            world = _expected(ref, key)
            if key in slopes:
                slope = (lambda f: lambda j: f(j) / square)(slopes[key])
        c = Check("frame", f"{name} {axis}", size, 1.0, size / square)
        compare(c, sheet, cells, [values.get((sheet, x)) for x in cells],
                (world - centre[axis]) / square, "-", is_error, error_code, tol, relative, slope)
        out.append(c)
    return out


def _check_numbers_only(meta, values, size) -> list[Check]:
    """Each numbers-only column (what MIN and MAX read for an extent) holds its source cell's
    own number, or a dash where the source is not a number (#N/A: the loop cannot close) or
    there is no source (no joint in that row). The sources, a sweep column and the joints
    table, are judged against the reference themselves, with their own allowances."""
    sweep, joints = meta["sweep"], meta["position"]["joints"]
    checks = []
    for column in meta.get("numbers_only", []):
        first, last = column["rows"]
        if "sweep" in column:
            letter, (r0, r1) = sweep["columns"][column["sweep"]], sweep["rows"]
            sources = [(sweep["sheet"], f"{letter}{r}") for r in range(r0, r1 + 1)]
            name = column["sweep"]
        else:
            sources = [(meta["position"]["sheet"], joints[j][column["axis"]]) if j else None
                       for j in column["joints"]]
            name = f"joints {'xy'[column['axis']]}"
        c = Check(column["sheet"], f"{name} numbers only", size)
        for r, source in zip(range(first, last + 1), sources):
            cell = f"{column['column']}{r}"
            want = values.get(source) if source else None
            if not isinstance(want, (int, float)) or isinstance(want, bool):
                want = DASH
            got = values.get((column["sheet"], cell))
            c.cells += 1
            c.judged.add((column["sheet"], cell))
            if got != want or isinstance(got, bool):
                c.mismatches.append(Mismatch(column["sheet"], cell, want, got))
        checks.append(c)
    return checks


WINDOW_STARTS = (-180.0, 180.0)   # where a degree view's 360° window may start


def _check_degree_windows(model, input_column: str, sweep: dict, pos: dict, ref: dict,
                          values: dict, size: float) -> list[Check]:
    """How a degree view shows its angle (docs/mechanisms.md): in one 360° window [lo, lo+360)
    for the sweep column and the current position, lo in [-180°, 180°) ([0°, 360°) for an angle
    that wraps). The build puts lo in the widest gap of the data it had; a user's edit moves the
    data, not the window, so only the window itself is judged here, from the values shown.
    The values are compared with the reference modulo 360° in the sweep and position checks."""
    checks = []
    rows = range(sweep["rows"][0], sweep["rows"][1] + 1)
    eps = 1e-9 * 360.0
    for key, letter in sweep["columns"].items():
        if not key.endswith("_deg") or key[:-4] not in ref or key == input_column:
            continue
        c = Check(layout.SWEEP, f"{key} window", size)
        checks.append(c)
        cells = [(sweep["sheet"], f"{letter}{r}") for r in rows]
        if key in pos["cells"]:
            cells.append((pos["sheet"], pos["cells"][key]))
        shown = [(cell, float(v)) for cell in cells
                 if isinstance(v := values.get(cell), (int, float)) and not isinstance(v, bool)
                 and math.isfinite(v)]
        if not shown:
            continue
        (low_cell, low), (high_cell, high) = (min(shown, key=lambda s: s[1]),
                                              max(shown, key=lambda s: s[1]))
        if model.get(key[:-4]).wrap_360:
            first, last = 0.0, 0.0
        else:
            first, last = WINDOW_STARTS
        # some lo in [first, last] with low >= lo and high < lo + 360
        if low < first - eps:
            bad, want = (low_cell, low), f"at least {first:g}°"
        elif high >= last + 360.0 + eps:
            bad, want = (high_cell, high), f"below {last + 360.0:g}°"
        elif high - low >= 360.0 + eps:
            bad, want = (high_cell, high), f"within 360° of {low:.10g}° ({low_cell[1]})"
        else:
            continue
        c.mismatches.append(Mismatch(bad[0][0], bad[0][1],
                                     f"one 360° window starting in [{first:g}°, {last:g}°]: "
                                     f"{want}", bad[1]))
    return checks


def motion_rates(mech, params: dict, size: float) -> tuple[float, float]:
    """The scale of velocities and accelerations: a crank's |ω| and ω² + |α| (per second, per
    second²); an actuator's |v|/S and (v/S)² + |a|/S. A velocity's bound is the position's
    bound times the first, an acceleration's times the second. Neither goes below 1e-9 (a
    rate of one part in 10⁹ of the size per second is zero for any purpose; `formulas` reads
    an input of 1e-184 as 0, to 15 decimals)."""
    from ..language.mechanisms import MOTION_SYMBOLS
    speed, accel = (float(params.get(k, 0.0)) for k in MOTION_SYMBOLS[mech.input_kind])
    if not mech.input_is_angle:
        speed, accel = speed / size, accel / size
    return max(abs(speed), MIN_RATE), max(speed * speed + abs(accel), MIN_RATE)


MIN_RATE = 1e-9


def _check_motion(meta, model, solver, params, angles, ref, one, angle, scale, size, run) -> None:
    """The Motion sheet (the sweep's rows and the current position's row) and the traced
    point's velocity under the current position, each compared through `run`."""
    from ..language.model import ACCEL, ANG_ACCEL, AREA, LENGTH, RATIO
    mech = solver.mechanism
    motion, sheet = meta["motion"], meta["motion"]["sheet"]
    rate1, rate2 = motion_rates(mech, params, size)
    (r0, r1), now = motion["rows"], motion["current_row"]

    def slope(inputs, key, unit):
        return _slope(solver, params, inputs, key, unit, scale=scale, motion=True)

    run(sheet, mech.input_column, sheet, [f"A{r}" for r in range(r0, r1 + 1)], angles,
        mech.input_unit)
    run(sheet, mech.input_column, sheet, [f"A{now}"], np.array([angle]), mech.input_unit)
    for key, letter in motion["columns"].items():
        unit = model.get(key).unit
        # a determinant is a position measured (an area's scale is S², see unit_scale)
        rate = {ACCEL: rate2, ANG_ACCEL: rate2, AREA: 1.0, LENGTH: 1.0, RATIO: 1.0}.get(unit,
                                                                                    rate1)
        run(sheet, key, sheet, [f"{letter}{r}" for r in range(r0, r1 + 1)], _expected(ref, key),
            unit, slope(angles, key, unit), rate, ref.get("dead_centre"), ref.get("sine"))
        run("motion now", key, sheet, [f"{letter}{now}"], _expected(one, key), unit,
            slope(np.array([angle]), key, unit), rate, one.get("dead_centre"), one.get("sine"))
    for key, cell in meta["position"].get("motion_cells", {}).items():
        unit = model.get(key).unit
        rate = rate2 if unit in (ACCEL, ANG_ACCEL) else rate1
        run("position", key, layout.MECH, [cell], _expected(one, key), unit,
            slope(np.array([angle]), key, unit), rate, one.get("dead_centre"), one.get("sine"))


ASSEMBLY_COLUMNS = ("closes", "gap_from", "gap_to")
DASH = layout.DASH


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
        if units:
            bound = Check(check.block, check.name, check.size, check.rate,
                          unit_scale(units[i], check.size)).limit(
                              exp, grows=units[i] not in ANGLE_UNITS)
        else:
            bound = check.limit(exp)
        if not isinstance(value, (int, float)) or abs(float(value) - exp) > bound + extra:
            check.mismatches.append(Mismatch(sheet, cell, exp, value))
        else:
            check.max_abs = max(check.max_abs, abs(float(value) - exp))


def _gaps(angles: np.ndarray, closes: np.ndarray) -> tuple[list, list]:
    """Per row: the angle where a run of rows that cannot close starts / ends, else a dash."""
    n = len(angles)
    starts = [float(angles[i]) if not closes[i] and (i == 0 or closes[i - 1]) else DASH
              for i in range(n)]
    ends = [float(angles[i]) if not closes[i] and (i == n - 1 or closes[i + 1]) else DASH
            for i in range(n)]
    return starts, ends


def _check_assembly(wb, meta, model, solver, params, angles, ref, values, size) -> list[Check]:
    sweep = meta["sweep"]
    cols, (r0, r1) = sweep["columns"], sweep["rows"]
    closes = np.asarray(ref["assembled"], dtype=bool)
    starts, ends = _gaps(angles, closes)
    checks = []
    for key, expected in (("closes", [1.0 if c else 0.0 for c in closes]),
                          ("gap_from", starts), ("gap_to", ends)):
        c = Check(layout.SWEEP, key, size)
        cells = [f"{cols[key]}{r}" for r in range(r0, r1 + 1)]
        unit = "" if key == "closes" else solver.mechanism.input_unit
        compare_exact(c, sweep["sheet"], cells, [values.get((sweep["sheet"], x)) for x in cells],
                      expected, units=[unit] * len(cells))
        checks.append(c)
    expected = _summary_expected(model, solver, params, ref, closes, starts, ends,
                                 _shown_output_degrees(model, sweep, values))
    slack = _edge_slack(model, ref, closes)
    summary = meta.get("summary", {})
    c = Check("summary", "geometry", size)
    for key, info in summary.items():
        compare_exact(c, layout.MECH, [info["cell"]], [values.get((layout.MECH, info["cell"]))],
                      [expected[key]], [slack.get(key, 0.0)], [info.get("unit", "")])
    checks.append(c)
    return checks


def _edge_slack(model, ref, closes: np.ndarray) -> dict[str, float]:
    """A sampled extreme taken on a row next to a row that cannot close sits at a limit
    position (a double root): it gets the same √ε-level allowance as that cell itself."""
    edge = closes & ~(np.roll(closes, 1) & np.roll(closes, -1))
    out = {}
    output_scale = 180.0 / math.pi if model.output and model.get(model.output).unit == RAD \
        else 1.0
    extremes = [("output", model.output, output_scale)] + [
        (summary_prefix("mu", i), key, 180.0 / math.pi)
        for i, key in enumerate(model.transmissions, start=1)]
    for prefix, key, scale in extremes:
        if not key:
            continue
        x = np.asarray(ref[key], dtype=float) * scale
        finite = np.isfinite(x)
        if not finite.any():
            continue
        for name, pick in (("min", np.nanargmin), ("max", np.nanargmax)):
            i = int(pick(np.where(finite, x, np.nan)))
            out[f"{prefix}_{name}"] = ROUNDING * EDGE_SLOPE if edge[i] else 0.0
    return out


def _extreme(values: np.ndarray, fn) -> object:
    values = values[np.isfinite(values)]
    return DASH if values.size == 0 else float(fn(values))


def _shown_output_degrees(model, sweep: dict, values: dict) -> list | None:
    """An angle output's degree view as the book shows it, row by row (None for a length)."""
    if not model.output or model.get(model.output).unit != RAD:
        return None
    letter = sweep["columns"].get(f"{model.output}_deg")
    rows = range(sweep["rows"][0], sweep["rows"][1] + 1)
    return [values.get((sweep["sheet"], f"{letter}{r}")) for r in rows]


def _in_shown_window(degrees: np.ndarray, shown: list) -> np.ndarray:
    """The reference's angles, each moved by whole turns next to the book's value in its row:
    the 360° window is the book's presentation (judged by the window check), the values are
    the reference's."""
    out = np.array(degrees, dtype=float)
    for i, v in enumerate(shown):
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) \
                and math.isfinite(out[i]):
            out[i] += 360.0 * round((float(v) - out[i]) / 360.0)
    return out


def _summary_expected(model, solver, params, ref, closes, starts, ends,
                      shown_output=None) -> dict:
    out: dict[str, object] = {
        "assembles_all": "yes" if closes.all() else "no",
        "not_closing": float((~closes).sum()),
        # the first loop step, in order, where the reference finds no assembly on some row
        "failing_step": next((name for key, (_, name) in zip(model.closes, model.loop_steps)
                              if not np.isfinite(np.asarray(ref[key], dtype=float)).all()),
                             DASH),
    }
    gap_starts = sorted(x for x in starts if x != DASH)
    gap_ends = sorted(x for x in ends if x != DASH)
    for k in range(1, layout.GAPS_SHOWN + 1):
        out[f"gap{k}_from"] = gap_starts[k - 1] if k <= len(gap_starts) else DASH
        out[f"gap{k}_to"] = gap_ends[k - 1] if k <= len(gap_ends) else DASH
    if model.output:
        o = np.asarray(ref[model.output], dtype=float)
        if shown_output is not None:            # an angle: in degrees, in the book's window
            o = _in_shown_window(np.degrees(o), shown_output)
        out["output_min"], out["output_max"] = _extreme(o, np.min), _extreme(o, np.max)
        if shown_output is not None:
            out["output_swing"] = (DASH if out["output_min"] == DASH
                                   else out["output_max"] - out["output_min"])
    for i, key in enumerate(model.transmissions, start=1):
        m = np.degrees(np.asarray(ref[key], dtype=float))
        n = summary_prefix("mu", i)
        out[f"{n}_min"], out[f"{n}_max"] = _extreme(m, np.min), _extreme(m, np.max)
    for i, (g, c, k, r) in enumerate(solver.fourbar_loops(params)):
        n = summary_prefix("", i + 1)
        out.update({f"fb{n}_ground": g, f"fb{n}_crank": c, f"fb{n}_coupler": k,
                    f"fb{n}_rocker": r, f"grashof{n}": generic.grashof_class(g, c, k, r)})
        for name, length in (("stretched", k + r), ("folded", abs(k - r))):
            roots = solver.limit_angles(params, length, i)
            lo, hi = (roots[0], roots[-1]) if roots else ("none", "none")
            out[f"limit{n}_{name}_1"], out[f"limit{n}_{name}_2"] = lo, hi
    return out


def _slope(solver: Reference, params: dict, angles: np.ndarray, key: str, unit: str,
           param: str | None = None, column_values=(), scale: float = math.degrees(1.0),
           motion: bool = False):
    """|∂x/∂θ| per row (per column value, for a grid) by a central difference of the reference,
    computed for one row when asked. `scale`: input units per unit of θ (degrees per radian of a
    crank; the mechanism's size for an actuator's length). `motion`: x is a velocity or an
    acceleration (else the reference is asked for positions only, which is quicker)."""
    period = ANGLE_UNITS.get(unit)
    h = SENSITIVITY_STEP
    if not motion:
        from ..language.mechanisms import MOTION_SYMBOLS
        params = {k: v for k, v in params.items()
                  if k not in MOTION_SYMBOLS[solver.mechanism.input_kind]}

    def at(i: int, j: int = 0) -> float:
        p = {**params, param: column_values[j]} if param else params
        deg = float(angles[i]) + scale * np.array([-h, 0.0, h])
        x = _expected(solver.solve(p, deg), key)
        pairs = [(a, b, span) for a, b, span in ((0, 2, 2 * h), (0, 1, h), (1, 2, h))
                 if np.isfinite(x[a]) and np.isfinite(x[b])]
        if not pairs:
            # Both neighbours fail to close: a limit position, a double root, where any solver
            # (the reference's Newton included) gets only about √ε: allow 1e-6 there.
            return EDGE_SLOPE
        a, b, span = pairs[0]
        d = x[b] - x[a]
        if period:
            d = (d + period / 2) % period - period / 2
        return abs(d) / span
    return at


def _grid_reference(solver, params, param, angles, column_values):
    out = np.empty((len(angles), len(column_values)))
    for j, v in enumerate(column_values):
        out[:, j] = solver.solve({**params, param: v}, angles)[solver.mechanism.grid[1]]
    return out


def _check_grid(wb, meta, solver, params, values, is_error, error_code, tol, relative, size):
    checks = []
    grid, stroke = meta["grid"], meta["stroke"]
    param = grid["param"]
    expected_by_block = {}
    own_sweep = stroke["sheet"] != grid["sheet"]     # else the grid is its own stroke sweep
    for block in (grid, stroke) if own_sweep else (grid,):
        ws = wb[block["sheet"]]
        angles = _angles(ws, "A", block["rows"], solver.mechanism.input_is_angle)
        if block is grid:
            adjust = [_number(ws, f"{c}{grid['param_row']}", f"{param}") for c in grid["columns"]]
            kind = meta["inputs"][param]["kind"]
            try:
                adjust = [check_value(f"{param} (cell {block['sheet']}!{c}{grid['param_row']})",
                                      kind, v) for c, v in zip(grid["columns"], adjust)]
                check_lengths_together({**params, **{f"{param}@{c}": v for c, v in
                                                     zip(grid["columns"], adjust)}},
                                       {**{s: i["kind"] for s, i in meta["inputs"].items()},
                                        **{f"{param}@{c}": kind for c in grid["columns"]}},
                                       "input ", written_in(meta))
            except InputError as exc:
                raise UnusableFile(str(exc)) from None
        expected = _grid_reference(solver, params, param, angles, adjust)
        expected_by_block[block["sheet"]] = expected
        c = Check(block["sheet"], f"{grid['key']} grid", size, scale=size)
        slope = _slope(solver, params, angles, solver.mechanism.grid[1], "length", param,
                       adjust)
        for j, letter in enumerate(block["columns"]):
            cells = [f"{letter}{r}" for r in range(block["rows"][0], block["rows"][1] + 1)]
            compare(c, block["sheet"], cells, [values.get((block["sheet"], x)) for x in cells],
                    expected[:, j], "length", is_error, error_code, tol, relative,
                    lambda i, j=j, slope=slope: slope(i, j))
        checks.append(c)
        if own_sweep and block is stroke:
            heads = [f"{x}{stroke['param_row']}" for x in stroke["columns"]]
            h = Check(block["sheet"], f"{param} header", size, scale=size)
            compare(h, block["sheet"], heads, [values.get((block["sheet"], x)) for x in heads],
                    np.array(adjust), "length", is_error, error_code, tol, relative)
            checks.append(h)
    fine = expected_by_block[stroke["sheet"]]
    strokes = np.ptp(fine, axis=0)          # NaN where some angle cannot close
    cells = [f"{c}{grid['stroke_row']}" for c in grid["columns"]]
    s = Check(grid["sheet"], "stroke", size, scale=size)
    compare(s, grid["sheet"], cells, [values.get((grid["sheet"], x)) for x in cells], strokes,
            "length", is_error, error_code, tol, relative)
    checks.append(s)
    checks.append(_check_stroke_sampling(solver, params, grid, adjust, values, size))
    return checks


def _check_stroke_sampling(solver, params: dict, grid: dict, adjust: list, values: dict,
                           size: float) -> Check:
    """The stroke under the grid is max − min over a sweep sampled every `stroke_step`
    degrees (the template's, as recorded): it may fall short of the true stroke (the
    reference's extremes, refined to 1e-6°) by what a sample h/2 from each extreme loses, and
    never exceed it. A sweep sampled more coarsely than the template asks misses by more."""
    key = solver.mechanism.grid[1]
    c = Check(grid["sheet"], "stroke sampling", size, scale=size)
    if "stroke_step" not in grid:       # a book built before the record kept it
        return c
    h = float(grid["stroke_step"])
    angles = np.arange(0.0, 360.0, generic.EXTREME_STEP)
    for letter, v in zip(grid["columns"], adjust):
        cell = f"{letter}{grid['stroke_row']}"
        got = values.get((grid["sheet"], cell))
        p = generic.positions_only({**params, grid["param"]: v})
        fine = np.asarray(solver.solve(p, angles)[key], dtype=float)
        if not np.isfinite(fine).all() or not isinstance(got, (int, float)) \
                or isinstance(got, bool):
            continue        # the stroke check at the book's own angles judges this cell
        top_at, top = generic.refined_extreme(solver.description, p, key, angles, fine, np.argmax)
        low_at, low = generic.refined_extreme(solver.description, p, key, angles, fine, np.argmin)
        near = solver.solve(p, np.array([top_at - h / 2, top_at + h / 2,
                                         low_at - h / 2, low_at + h / 2]))[key]
        near = np.asarray(near, dtype=float)
        allowance = (top - min(near[0], near[1])) + (max(near[2], near[3]) - low)
        true = top - low
        limit = c.limit(true)
        if not true - allowance - limit <= got <= true + limit:
            c.mismatches.append(Mismatch(
                grid["sheet"], cell, f"{true:.10g} (the true stroke; a {h:g}° sampling may "
                                     f"fall short by {allowance:.3g})", float(got)))
    return c


# ---------------------------------------------------------------- the command
def read_book(path: Path):
    """(workbook, build record) of the book at `path`, read as the application reads it (the
    fast XML view, or openpyxl where it must); UnusableFile with one line when it cannot be."""
    from ..base.safety import UnsafeFile, read_workbook_safely
    try:
        wb = read_workbook_safely(path)
    except UnsafeFile as exc:
        raise UnusableFile(str(exc)) from None
    return wb, _build_record(path, wb)


@gc_paused
def verify(path: Path, engine: str = "vector") -> Report:
    """Every formula cell of the book at `path` compared with the independent reference.
    Raises UnusableFile with one line when the file cannot be verified."""
    wb, meta = read_book(path)
    try:
        params = inputs_of(wb, meta)    # first: an input no number holds is named, not computed
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise UnusableFile(_record_mismatch(path, exc)) from None
    from ..engine import evaluator as engines
    is_error, error_code, relative = engines.is_error, engines.error_code, False
    try:
        if engine == "vector":
            values = engines.evaluate(wb)
        elif engine == "formulas":
            # ExcelModel rounds number constants to 15 decimals (engine.evaluate's
            # excel_model_constants): judged with the relative bound, as LibreOffice is
            values = engines.evaluate_formulas_model(path)
            relative = True
        else:
            # a real application (LibreOffice, Gnumeric) recalculates a copy: judged alike
            from ..engine import office
            if engine not in office.APPLICATIONS:
                raise UnusableFile(f"unknown engine {engine!r}")
            values = office.recalculated_values(path, engine)
            is_error, error_code, relative = office.is_error, office.error_code, True
    except engines.EngineError as exc:
        raise UnusableFile(f"{path}: {exc}") from None
    formulas = formula_cells(wb)
    try:
        checks = check_book(wb, meta, values, is_error, error_code, relative=relative)
        judged = set().union(*(c.judged for c in checks))
        replaced, absent = _not_formulas(wb, judged - formulas)
        if replaced:
            checks.append(_check_replaced(wb, replaced))
        stored = stored_values(wb, path, formulas & judged)
        if stored:
            checks.append(_check_stored(wb, meta, values, stored, is_error, error_code,
                                        relative))
        return Report(str(path), meta["mechanism"], engine, checks, len(formulas),
                      sorted(formulas - judged, key=cell_order), params,
                      mechanism_size(meta, params), likely_causes(wb, checks),
                      sheets=list(wb.sheetnames), replaced=replaced, absent=absent)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise UnusableFile(_record_mismatch(path, exc)) from None


def _record_mismatch(path: Path, exc: Exception) -> str:
    return (f"{path}: the build record (sheet {layout.META}) does not match the workbook "
            f"({type(exc).__name__}: {exc})")


def _build_record(path: Path, wb) -> dict:
    """The book's build record; UnusableFile saying what is wrong when it is missing or damaged,
    or when a sheet it names was renamed in case only."""
    if layout.META not in wb.sheetnames:
        raise UnusableFile(f"{path}: not a linkbook workbook (no build record sheet)")
    try:
        meta = layout.read_meta(wb)
    except RecursionError:
        meta = None
    if not isinstance(meta, dict) or meta.get("format") != layout.FORMAT_VERSION:
        raise UnusableFile(f"{path}: the build record (sheet {layout.META}) is damaged: it is "
                           f"not the JSON object of format {layout.FORMAT_VERSION} linkbook "
                           "writes")
    for sheet in sorted(_sheets_named(meta) - set(wb.sheetnames)):
        # a sheet deleted is judged by the cells that read it; one renamed in case only, and
        # the sheet of the inputs, are named here
        for alike in (s for s in wb.sheetnames if s.casefold() == sheet.casefold()):
            raise UnusableFile(f"{path}: the sheet {sheet!r} is missing (the book has "
                               f"{alike!r}: the record names sheets exactly, so rename it back)")
        if sheet == layout.MECH:
            raise UnusableFile(f"{path}: the sheet {sheet!r} (the inputs) is missing")
    return meta


def _sheets_named(meta: dict) -> set[str]:
    """The Mechanism sheet and every sheet the record names (any "sheet" entry, at any depth)."""
    named, todo = {layout.MECH}, [meta]
    while todo:
        item = todo.pop()
        if isinstance(item, dict):
            if isinstance(item.get("sheet"), str):
                named.add(item["sheet"])
            todo.extend(item.values())
        elif isinstance(item, list):
            todo.extend(item)
    return named


# ---------------------------------------------------------------- what the book shows unrecalculated
STORED = "stored"


def _not_formulas(wb, cells: set[tuple[str, str]]) -> tuple[list, list]:
    """Cells the record holds formulas in that hold none: (those holding a constant, those
    empty or on a sheet deleted), in cell order."""
    replaced, absent = [], []
    for key in sorted(cells, key=cell_order):
        held = key[0] in wb.sheetnames and wb[key[0]][key[1]].value is not None
        (replaced if held else absent).append(key)
    return replaced, absent


def _check_replaced(wb, replaced: list[tuple[str, str]]) -> Check:
    """A constant where the build record has a formula differs whatever its value: the book no
    longer follows its inputs there (a formula pasted as its value)."""
    c = Check("constants", "in place of formulas", cells=len(replaced))
    for sheet, cell in replaced:
        c.mismatches.append(Mismatch(sheet, cell, "a formula",
                                     f"the constant {wb[sheet][cell].value!r}"))
    return c


def stored_values(wb, path, cells: set[tuple[str, str]]) -> dict[tuple[str, str], object]:
    """(sheet, cell) -> the value each of `cells` (formula cells) stores with its formula (the
    `<v>`): what LibreOffice with default settings, openpyxl's data_only and pandas show. Numbers
    as float, errors as office.CellError, text as str; a cell that stores none is left out."""
    from ..base.xlsx import CellError
    from ..engine.office import read_values
    from ..base.xlsx import column_letter
    if not all(hasattr(ws, "stored") for ws in wb.worksheets):   # openpyxl read the book
        return {k: v for k, v in read_values(path).items() if k in cells}
    out = {}
    for ws in wb.worksheets:
        for (row, col), (kind, text) in ws.stored.items():
            key = (ws.title, f"{column_letter(col)}{row}")
            if key not in cells:
                continue
            if kind == "e":
                out[key] = CellError(text)
            elif kind == "b":
                if text.strip() not in ("0", "1", "true", "false"):
                    raise UnusableFile(f"{path}: {key[0]}!{key[1]}: the stored value {text!r} "
                                       "is not a boolean")
                out[key] = text.strip() in ("1", "true")
            elif kind == "n":
                try:
                    out[key] = float(text)
                except ValueError:
                    raise UnusableFile(f"{path}: {key[0]}!{key[1]}: the stored value {text!r} "
                                       "is not a number") from None
            else:
                out[key] = text
    return out


def _kind(value, error_code) -> str:
    """What a reader shows a cell as: an error, a boolean, a number or a text."""
    from ..base.xlsx import CellError
    if isinstance(value, CellError) or error_code(value) is not None:
        return "error"
    if isinstance(value, bool):
        return "boolean"
    return "number" if isinstance(value, (int, float)) else "text"


def _same(a, b, error_code) -> bool:
    from ..base.xlsx import CellError
    code_a = str(a) if isinstance(a, CellError) else None
    if code_a is not None or error_code(b) is not None:
        return code_a == error_code(b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return isinstance(a, bool) == isinstance(b, bool) and float(a) == float(b)
    return a == b


def _check_stored(wb, meta, values, stored, is_error, error_code, relative) -> Check:
    """Each stored value judged as its formula's value is, with the same bounds: a value stored
    that its formula does not give (an edit of the file, a stale save) differs, named with what
    the formula gives and what is stored. Only the stored values that differ from the formula's
    own are judged again."""
    from ..base.xlsx import CellError
    c = Check(STORED, "value ≠ the formula's", cells=len(stored))
    differ = {k: v for k, v in stored.items() if not _same(v, values.get(k), error_code)}
    # a value of another kind (TRUE for 1, the text "1.5" for 1.5) differs outright: a reader
    # that does not calculate shows it as it is, whatever the bounds say of its number
    for key in [k for k, v in differ.items()
                if _kind(v, error_code) != _kind(values.get(k), error_code)]:
        c.mismatches.append(Mismatch(key[0], key[1], _show_stored(values.get(key), error_code),
                                     _show_stored(differ.pop(key), error_code)))
    if not differ:
        return c

    def any_error(v) -> bool:
        return isinstance(v, CellError) or is_error(v)

    def any_code(v) -> str | None:
        return str(v) if isinstance(v, CellError) else error_code(v)

    again = check_book(wb, meta, {**values, **differ}, any_error, any_code, relative=relative)
    named = set()
    for check in again:
        for m in check.mismatches:
            key = (m.sheet, m.cell)
            if key in differ and key not in named:
                named.add(key)
                computed, got = values.get(key), differ[key]
                c.mismatches.append(Mismatch(m.sheet, m.cell, _show_stored(computed, error_code),
                                             _show_stored(got, any_code)))
                if isinstance(computed, float) and isinstance(got, float):
                    c.max_abs = max(c.max_abs, abs(got - computed))
    return c


def likely_causes(wb, checks: list[Check]) -> set[tuple[str, str]]:
    """The differing cells that read no other differing cell: where each chain of
    disagreement starts (a broken formula; the cells downstream differ because they read it)."""
    from ..engine import evaluator as engines
    from ..base.xlsx import coordinate_to_tuple
    differ = {(m.sheet, m.cell) for c in checks for m in c.mismatches}
    where: dict[str, set[tuple[int, int]]] = {}
    for sheet, cell in differ:
        where.setdefault(sheet, set()).add(coordinate_to_tuple(cell))

    def reads_a_differing_cell(key, rects) -> bool:
        me = (key[0], coordinate_to_tuple(key[1]))
        for sheet, top, left, bottom, right in rects:
            cells = where.get(sheet, set())
            if (bottom - top + 1) * (right - left + 1) <= len(cells):   # walk the smaller side
                hits = ((r, c) for r in range(top, bottom + 1) for c in range(left, right + 1)
                        if (r, c) in cells)
            else:
                hits = ((r, c) for r, c in cells if top <= r <= bottom and left <= c <= right)
            if any((sheet, rc) != me for rc in hits):
                return True
        return False
    # a cell on a sheet the edit deleted reads nothing: it is a cause itself
    reads = engines.cells_read(wb, {k for k in differ if k[0] in wb.sheetnames})
    return {key for key in differ if not reads_a_differing_cell(key, reads.get(key, []))}


def formula_cells(wb) -> set[tuple[str, str]]:
    return {(ws.title, c.coordinate) for ws in wb.worksheets for c in ws._cells.values()
            if c.data_type == "f"}


def cell_order(key: tuple[str, str]) -> tuple:
    from ..base.xlsx import coordinate_to_tuple
    row, col = coordinate_to_tuple(key[1])
    return key[0], col, row


def cell_ranges(cells: list[tuple[str, str]], most: int = 6) -> str:
    """'Sweep!F5:F77, Mechanism!I9' for sorted (sheet, cell) pairs: runs down a column joined;
    after `most` runs, how many more."""
    runs = cell_runs(cells)
    text = runs[:most]
    if len(runs) > most:
        text.append(f"and {len(runs) - most} more ranges")
    return ", ".join(text)


def cell_runs(cells: list[tuple[str, str]]) -> list[str]:
    """['Sweep!F5:F77', 'Mechanism!I9'] for sorted (sheet, cell) pairs: each run of rows down
    one column as one range."""
    from ..base.xlsx import column_letter, coordinate_to_tuple
    runs: list[list] = []
    for sheet, cell in cells:
        row, index = coordinate_to_tuple(cell)
        col = column_letter(index)
        last = runs[-1] if runs else None
        if last and last[0] == sheet and last[1] == col and last[3] == row - 1:
            last[3] = row
        else:
            runs.append([sheet, col, row, row])
    return [f"{s}!{c}{a}" if a == b else f"{s}!{c}{a}:{c}{b}" for s, c, a, b in runs]
