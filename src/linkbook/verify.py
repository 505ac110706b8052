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

from . import generic, workbook as layout
from .workbook import summary_prefix
from .templates import InputError, check_value

ABS_TOL = 1e-9
ANGLE_UNITS = {"rad": 2 * math.pi, "deg": 360.0}


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
    cells: int = 0
    max_abs: float = 0.0
    na_expected: int = 0
    na_agree: int = 0
    dead_centre: int = 0        # rates at a dead centre: not determined by the data
    mismatches: list[Mismatch] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.mismatches

    def limit(self, expected: float, tol: float = ABS_TOL, relative: bool = False) -> float:
        """|Δ| allowed. `relative` (LibreOffice keeps 15 digits): tol·max(1, |x|). Otherwise tol
        for every value up to the mechanism's own size S. Larger values only arise near a
        singular position (the pump's plunger as its slot turns parallel to the plunger line,
        s15 ~ 1/cos θ14), where the error of any double-precision evaluation grows like |x|²/S:
        there the bound is tol·(|x|/S)²."""
        if relative:
            return tol * max(1.0, abs(expected))
        rate = max(self.rate, 1e-300)
        return tol * rate * max(1.0, (abs(expected) / (self.size * rate)) ** 2)

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

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def cells(self) -> int:
        return sum(c.cells for c in self.checks)

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
    return values


def _angles(ws, column: str, rows: list[int]) -> np.ndarray:
    return np.array([_number(ws, f"{column}{r}", "input angle")
                     for r in range(rows[0], rows[1] + 1)])


def _number(ws, cell: str, what: str) -> float:
    v = ws[cell].value
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        raise UnusableFile(f"{ws.title}!{cell}: {what} must be a number (got {v!r})")
    return float(v)


def mechanism_size(meta: dict, params: dict[str, float]) -> float:
    """S: the sum of the input lengths and offsets (every frame fits in a circle that big)."""
    kinds = {s: info["kind"] for s, info in meta["inputs"].items()}
    size = sum(abs(v) for s, v in params.items() if kinds[s] in ("length", "offset"))
    return max(size, 1e-300)


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
            slope=None, dead=None) -> None:
    """`slope(i)`: |∂x/∂θ| of cell i from the reference, asked only for a cell that misses the
    strict bound. Near a limit position (an ACOS argument close to ±1, the pump's cos θ14 close
    to 0) every evaluation loses digits in proportion to it, so such a cell may differ by
    ROUNDING·|∂x/∂θ| more: the forward-error bound, not a looser test of healthy cells."""
    period = ANGLE_UNITS.get(unit)
    for i, (cell, value, exp) in enumerate(zip(cells, got,
                                               np.broadcast_to(expected, (len(cells),)))):
        check.cells += 1
        exp = float(exp)
        if math.isnan(exp) and dead is not None and dead[i]:
            # a dead centre (to within the reference's own accuracy there): a rate is not
            # determined by the data; #N/A or any number is the workbook's honest answer
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
        limit = check.limit(exp, tol, relative)
        if diff > limit and slope is not None:
            limit += ROUNDING * slope(i)
        if diff > limit:
            check.mismatches.append(Mismatch(sheet, cell, exp, float(value)))


def _show(value, error_code):
    code = error_code(value)
    return code if code else value


def column_unit(model, key: str) -> str:
    if key.endswith("_deg"):
        return "deg"
    return model.get(key).unit


# ---------------------------------------------------------------- the reference of a book
class Reference:
    """The independent solver of one book's mechanism: the generic reference (generic.py), given
    the description the book records, with the book's own input values."""

    def __init__(self, meta: dict):
        from .language import DescriptionError, from_record
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

    def run(block, name, sheet, cells, expected, unit, slope=None, rate=1.0, dead=None):
        c = Check(block, name, size, rate)
        compare(c, sheet, cells, [values.get((sheet, x)) for x in cells], expected, unit,
                is_error, error_code, tol, relative, slope, dead)
        checks.append(c)

    # The sweep table, column by column.
    sweep = meta["sweep"]
    ws = wb[sweep["sheet"]]
    rows = sweep["rows"]
    angles = _angles(ws, "A", rows)
    # the slope of a cell is taken per radian of a crank, per `size` of an actuator's stroke
    scale = math.degrees(1.0) if mech.input_is_angle else size
    ref = solver.solve(params, angles)
    for key, letter in sweep["columns"].items():
        if key == mech.input_column or key in ASSEMBLY_COLUMNS:
            continue
        cells = [f"{letter}{r}" for r in range(rows[0], rows[1] + 1)]
        unit = column_unit(model, key)
        run(layout.SWEEP, key, sweep["sheet"], cells, _expected(ref, key), unit,
            _slope(solver, params, angles, key, unit, scale=scale))

    # The current position, the joints and the drawing rows.
    pos = meta["position"]
    angle = _number(wb[pos["sheet"]], pos["input_cell"], f"the current input {mech.input_word}")
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
    drawing_cells, drawing_expected = [], []
    for link in pos["drawing"]:
        for i, name in enumerate(link["joints"]):
            r = link["rows"][0] + i
            drawing_cells += [f"N{r}", f"O{r}"]
            drawing_expected += list(joint_values[name])
    run("joints", "drawing rows", pos["sheet"], drawing_cells, np.array(drawing_expected),
        "length")

    # Derived constants.
    for key, info in meta.get("constants", {}).items():   # solve() returns them as floats
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


def motion_rates(mech, params: dict, size: float) -> tuple[float, float]:
    """The scale of velocities and accelerations: a crank's |ω| and ω² + |α| (per second, per
    second²); an actuator's |v|/S and (v/S)² + |a|/S. A velocity's bound is the position's
    bound times the first, an acceleration's times the second. Neither goes below 1e-9 (a
    rate of one part in 10⁹ of the size per second is zero for any purpose; `formulas` reads
    an input of 1e-184 as 0, to 15 decimals)."""
    from .mechanisms import MOTION_SYMBOLS
    speed, accel = (float(params.get(k, 0.0)) for k in MOTION_SYMBOLS[mech.input_kind])
    if not mech.input_is_angle:
        speed, accel = speed / size, accel / size
    return max(abs(speed), MIN_RATE), max(speed * speed + abs(accel), MIN_RATE)


MIN_RATE = 1e-9


def _check_motion(meta, model, solver, params, angles, ref, one, angle, scale, size, run) -> None:
    """The Motion sheet (the sweep's rows and the current position's row) and the traced
    point's velocity under the current position, each compared through `run`."""
    from .model import ACCEL, ANG_ACCEL, AREA, LENGTH, RATIO
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
        # a determinant is a position measured (an area's scale is S)
        rate = {ACCEL: rate2, ANG_ACCEL: rate2, AREA: size, LENGTH: 1.0, RATIO: 1.0}.get(unit,
                                                                                     rate1)
        run(sheet, key, sheet, [f"{letter}{r}" for r in range(r0, r1 + 1)], _expected(ref, key),
            unit, slope(angles, key, unit), rate, ref.get("dead_centre"))
        run("motion now", key, sheet, [f"{letter}{now}"], _expected(one, key), unit,
            slope(np.array([angle]), key, unit), rate, one.get("dead_centre"))
    for key, cell in meta["position"].get("motion_cells", {}).items():
        unit = model.get(key).unit
        rate = rate2 if unit in (ACCEL, ANG_ACCEL) else rate1
        run("position", key, layout.MECH, [cell], _expected(one, key), unit,
            slope(np.array([angle]), key, unit), rate, one.get("dead_centre"))


ASSEMBLY_COLUMNS = ("closes", "gap_from", "gap_to")
DASH = layout.DASH


def compare_exact(check: Check, sheet: str, cells: list[str], got: list, expected: list,
                  slack: list | None = None) -> None:
    """Text (and bookkeeping) cells: the same text, or the same number within the bound
    (plus `slack`, for an extreme taken at a limit position)."""
    for cell, value, exp, extra in zip(cells, got, expected, slack or [0.0] * len(cells)):
        check.cells += 1
        if isinstance(exp, str) or isinstance(value, str):
            if value != exp:
                check.mismatches.append(Mismatch(sheet, cell, exp, value))
            continue
        if not isinstance(value, (int, float)) or abs(float(value) - exp) > check.limit(exp) + extra:
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
        compare_exact(c, sweep["sheet"], cells, [values.get((sweep["sheet"], x)) for x in cells],
                      expected)
        checks.append(c)
    expected = _summary_expected(model, solver, params, ref, closes, starts, ends)
    slack = _edge_slack(model, ref, closes)
    summary = meta.get("summary", {})
    c = Check("summary", "geometry", size)
    for key, info in summary.items():
        compare_exact(c, layout.MECH, [info["cell"]], [values.get((layout.MECH, info["cell"]))],
                      [expected[key]], [slack.get(key, 0.0)])
    checks.append(c)
    return checks


def _edge_slack(model, ref, closes: np.ndarray) -> dict[str, float]:
    """A sampled extreme taken on a row next to a row that cannot close sits at a limit
    position (a double root): it gets the same √ε-level allowance as that cell itself."""
    edge = closes & ~(np.roll(closes, 1) & np.roll(closes, -1))
    out = {}
    extremes = [("output", model.output, 1.0)] + [
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


def _summary_expected(model, solver, params, ref, closes, starts, ends) -> dict:
    from .workbook import GAPS_SHOWN
    out: dict[str, object] = {
        "assembles_all": "yes" if closes.all() else "no",
        "not_closing": float((~closes).sum()),
    }
    gap_starts = sorted(x for x in starts if x != DASH)
    gap_ends = sorted(x for x in ends if x != DASH)
    for k in range(1, GAPS_SHOWN + 1):
        out[f"gap{k}_from"] = gap_starts[k - 1] if k <= len(gap_starts) else DASH
        out[f"gap{k}_to"] = gap_ends[k - 1] if k <= len(gap_ends) else DASH
    if model.output:
        o = np.asarray(ref[model.output], dtype=float)
        out["output_min"], out["output_max"] = _extreme(o, np.min), _extreme(o, np.max)
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
        from .mechanisms import MOTION_SYMBOLS
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
        angles = _angles(ws, "A", block["rows"])
        if block is grid:
            adjust = [_number(ws, f"{c}{grid['param_row']}", f"{param}") for c in grid["columns"]]
        expected = _grid_reference(solver, params, param, angles, adjust)
        expected_by_block[block["sheet"]] = expected
        c = Check(block["sheet"], f"{grid['key']} grid", size)
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
            h = Check(block["sheet"], f"{param} header", size)
            compare(h, block["sheet"], heads, [values.get((block["sheet"], x)) for x in heads],
                    np.array(adjust), "length", is_error, error_code, tol, relative)
            checks.append(h)
    fine = expected_by_block[stroke["sheet"]]
    strokes = np.ptp(fine, axis=0)          # NaN where some angle cannot close
    cells = [f"{c}{grid['stroke_row']}" for c in grid["columns"]]
    s = Check(grid["sheet"], "stroke", size)
    compare(s, grid["sheet"], cells, [values.get((grid["sheet"], x)) for x in cells], strokes,
            "length", is_error, error_code, tol, relative)
    checks.append(s)
    return checks


# ---------------------------------------------------------------- the command
def verify(path: Path, engine: str = "vector") -> Report:
    from .safety import load_workbook_safely
    wb = load_workbook_safely(path)
    meta = layout.read_meta(wb)
    if meta is None or meta.get("format") != layout.FORMAT_VERSION:
        raise UnusableFile(f"{path}: not a linkbook workbook (no build record sheet)")
    from . import engine as engines
    is_error, error_code, relative = engines.is_error, engines.error_code, False
    if engine == "vector":
        values = engines.evaluate(wb)
    elif engine == "formulas":
        values = engines.evaluate_formulas_model(path)
    elif engine == "libreoffice":
        from . import office
        values = office.recalculated_values(path)
        is_error, error_code, relative = office.is_error, office.error_code, True
    else:
        raise UnusableFile(f"unknown engine {engine!r}")
    checks = check_book(wb, meta, values, is_error, error_code, relative=relative)
    return Report(str(path), meta["mechanism"], engine, checks)
