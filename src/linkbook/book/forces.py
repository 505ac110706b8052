"""The Forces sheet: the inertia loads, every joint's reaction and the driving effort, at the
current position (row 5) and at every row of the Sweep sheet, each reading that row's
positions (Sweep) and accelerations (Motion). Its formulas come from the force writer
(language/forces.py); lengths become metres through the one named cell `to_metres`.

Under the table, the summary of the sweep: the driving effort's mean (the trapezoid rule over
the sweep's inputs: for a crank's full turn, the work per turn over 2π) and RMS, its largest and
smallest value and where, each pin's peak load; for a crank also the energy fluctuation ΔE (the
swing of the work of T12 above its mean, column W) and the flywheel inertia ΔE/(Cs·ω²) for the
coefficient of speed fluctuation Cs, an input cell.
"""
from __future__ import annotations

from openpyxl.utils import column_index_from_string, get_column_letter

from ..base.sheets import FORCES_SHEET, MOTION_SHEET, SWEEP
from ..language.excel import in_domain_or_na
from ..language.forces import FORCE
from ..language.mechanisms import SPEED_FLUCTUATION, TO_METRES
from ..language.model import NEWTON, Model
from ..language.domain import LENGTH_UNITS
from ..language.templates import Template
from .motion import MOTION_OFFSET, model_name, row_table
from .style import (BOLD, DERIVED_FILL, FORMATS, INPUT_FILL, NOTE, define_name, header,
                    number_format, put_head, put_text, set_formula)

METRES_CELL = "A3"
CS_DEFAULT = 0.02     # a common design value for general machinery (Cs = (ωmax − ωmin)/ω)
FORCE_FORMAT, ENERGY_FORMAT = FORMATS[NEWTON], "0.0000"


def forces_table(wb, ws, t: Template, model: Model, names: dict, sweep: dict, position: dict,
                 motion: dict) -> dict:
    """The Forces sheet's table (motion.row_table), its rows beside the Motion sheet's, and the
    summary of the sweep beside it."""
    speed = model_name(names, "omega_in" if t.mechanism.input_is_angle else "v_in")
    effort = "T12 (the motor's torque on the crank)" if t.mechanism.input_is_angle else \
        "F_in (the actuator's force)"
    note = (f"Forces in N, moments in N·m, at the speed {speed} of sheet Mechanism: the "
            f"inertia and weight of each link, the force of link i on link j at their pin "
            f"(Fij), the guides' forces, the driving effort {effort} and the shaking force on "
            f"the frame. Row 5: the current position; from row {5 + MOTION_OFFSET}: each row "
            f"of sheet {SWEEP}. #N/A where the loop cannot close or where a group of links "
            f"cannot carry a load. Cell {METRES_CELL}: metres per {t.length_unit} (to_metres).")
    ws[METRES_CELL] = LENGTH_UNITS[t.length_unit]
    ws[METRES_CELL].number_format = f'0.####" m/{t.length_unit}"'
    ws[METRES_CELL].font = NOTE
    define_name(wb, TO_METRES, FORCES_SHEET, METRES_CELL)
    table = row_table(ws, t, model, {**names, TO_METRES: TO_METRES}, model.of_role(FORCE),
                      sweep, position, f"{t.title}: forces", note, (MOTION_SHEET, motion))
    ws.column_dimensions["A"].width = 14      # room for A3's "0.001 m/mm"
    out = {"sheet": FORCES_SHEET, **table}
    out.update(summary(wb, ws, t, model, names, out))
    return out


def effort_key(model: Model) -> str:
    keys = {q.key for q in model.of_role(FORCE)}
    return next(k for k in ("T12", "T1_2", "F_in") if k in keys)


def pin_keys(model: Model) -> list[str]:
    """The size of every pin's force and of every guide's, in the sheet's order."""
    return [q.key for q in model.of_role(FORCE)
            if q.unit == NEWTON and q.key[0] == "F" and q.key[1:].replace("_", "").isdigit()]


def summary(wb, ws, t: Template, model: Model, names: dict, table: dict) -> dict:
    """The summary block under the table (see the module's docstring); for a crank the work
    column W right of the last force column."""
    crank = t.mechanism.input_is_angle
    letters, (r0, r1) = table["columns"], table["rows"]
    last = max(column_index_from_string(v) for v in letters.values())
    effort = effort_key(model)
    q = model.get(effort)
    col = letters[effort]
    rng = f"${col}${r0}:${col}${r1}"
    lo, hi = f"${col}${r0}:${col}${r1 - 1}", f"${col}${r0 + 1}:${col}${r1}"
    span = f"($A${r0 + 1}:$A${r1}-$A${r0}:$A${r1 - 1})"
    length = f"($A${r1}-$A${r0})"
    work = None
    label_col, value_col, unit_col = _summary_columns(ws)
    cells: dict = {}
    row = r1 + 2
    put_text(ws, f"{label_col}{row}", "Summary over the sweep", BOLD)

    def add(key, label, formula, unit, fill=DERIVED_FILL, fmt=FORCE_FORMAT, kind="number"):
        nonlocal row
        row += 1
        put_text(ws, f"{label_col}{row}", label)
        c = ws[f"{value_col}{row}"]
        if formula.startswith("="):
            set_formula(c, formula)
        else:
            c.value = float(formula)
        c.fill, c.number_format = fill, fmt
        put_text(ws, f"{unit_col}{row}", unit)
        cells[key] = {"cell": f"{value_col}{row}", "kind": kind, "unit": unit}
        return f"${value_col}${row}"

    mean = add("effort_mean", f"{q.symbol}: mean (trapezoid rule over the sweep)",
               f"=SUMPRODUCT(({lo}+{hi})/2*{span})/{length}", q.unit)
    # products, not ^2: LibreOffice squares an array's #N/A into #NUM!
    square = f"SUMPRODUCT(({lo}*{lo}+{hi}*{hi})/2*{span})/{length}"
    add("effort_rms", f"{q.symbol}: RMS", "=" + in_domain_or_na("SQRT", square), q.unit)
    for word, fn in (("largest", "MAX"), ("smallest", "MIN")):
        peak = add(f"effort_{word}", f"{q.symbol}: {word}", f"={fn}({rng})", q.unit)
        # the input of the first row holding it: the sweep's steps are equal but the last
        # (INDEX would do, but the vector engine reads MATCH and arithmetic natively)
        k = f"MATCH({peak},{rng},0)"
        add(f"effort_{word}_at", f"… at {t.mechanism.input_symbol}",
            f"=IF({k}={r1 - r0 + 1},$A${r1},$A${r0}+({k}-1)*($A${r0 + 1}-$A${r0}))",
            "deg" if crank else t.length_unit, fmt=number_format(
                t.mechanism.input_unit, t.length_unit))
    for key in pin_keys(model):
        c = letters[key]
        add(f"peak_{key}", f"peak load |{model.get(key).symbol}|", f"=MAX(${c}${r0}:${c}${r1})",
            NEWTON)
    if crank:
        work = get_column_letter(last + 1)
        _work_column(ws, t, work, col, mean, table)
        wr = f"${work}${r0}:${work}${r1}"
        energy = add("energy_fluctuation", "energy fluctuation ΔE = max W − min W",
                     f"=MAX({wr})-MIN({wr})", "J", fmt=ENERGY_FORMAT)
        cs = add("speed_fluctuation", "coefficient of speed fluctuation Cs (input)",
                 str(CS_DEFAULT), "-", fill=INPUT_FILL, fmt="0.000", kind="input")
        define_name(wb, SPEED_FLUCTUATION, FORCES_SHEET, cs.replace("$", ""))
        omega = model_name(names, "omega_in")
        add("flywheel", "flywheel inertia ΔE / (Cs·ω²)",
            f"=IF({cs}*{omega}^2=0,NA(),{energy}/({cs}*{omega}^2))", "kg·m²",
            fmt=ENERGY_FORMAT)
    _mean_line_cells(ws, t, cells, row + 2, (label_col, value_col), mean, r0, r1)
    _polar_square_cells(ws, cells, row + 6, (label_col, value_col),
                        [f"${letters[k]}${r0}:${letters[k]}${r1}" for k in SHAKING])
    return {"summary": cells, **({"work": work} if work else {})}


def summary_rows(forces: dict) -> tuple[int, int]:
    """The rows of the summary block, its title to its last cell (the chart points'): printed
    on one page (pages.apply_print_setup's keep_together)."""
    from openpyxl.utils.cell import coordinate_from_string
    rows = [coordinate_from_string(c["cell"])[1] for c in forces["summary"].values()]
    return min(rows) - 1, max(rows)


SHAKING = ("shaking_x", "shaking_y")     # the shaking force's components: its polar diagram
POLAR_SQUARE = "polar_square_"           # the summary cells of that diagram's square


def _polar_square_cells(ws, cells: dict, row: int, columns: tuple[str, str],
                        ranges: list[str]) -> None:
    """Two points for the polar diagram, drawn invisible: the corners (−R, −R) and (R, R) of
    the square about the origin that holds the shaking force, R its largest component in size.
    Both axes then span the same data, so the applications' own axis scaling (live, after any
    edit) gives both the same range: in a square plot area, equal scales."""
    x, y = columns
    put_text(ws, f"{x}{row}", "the polar diagram's square: (−R, −R), then (R, R), R the "
                              "largest |Fs_x| or |Fs_y|", NOTE)
    reach = f"${x}${row + 2}"
    parts = ",".join(f"MAX({r}),-MIN({r})" for r in ranges)
    formulas = {"x0": f"=-{reach}", "y0": f"=-{reach}", "x1": f"=MAX({parts})",
                "y1": f"={reach}"}
    for key, formula in formulas.items():
        cell = f"{x if key[0] == 'x' else y}{row + 1 + int(key[1])}"
        set_formula(ws[cell], formula).number_format = FORCE_FORMAT
        cells[f"{POLAR_SQUARE}{key}"] = {"cell": cell, "kind": "number", "unit": ""}


SUMMARY_LABEL_WIDTH = 44     # the longest label, "coefficient of speed fluctuation Cs (input)"


def _summary_columns(ws) -> tuple[str, str, str]:
    """The summary's label, value and unit columns, under the table from column B: a label
    reads on over the empty cells to its right, the value stands in the first column past
    SUMMARY_LABEL_WIDTH. Under the table, not beside it: a printed page of the summary then
    has no repeated input column beside it (pages.py repeats column A on every page), only
    the empty cells of column A under the table's last row."""
    first = col = column_index_from_string("B")
    while sum(ws.column_dimensions[get_column_letter(c)].width or 8.43
              for c in range(first, col)) < SUMMARY_LABEL_WIDTH:
        col += 1
    return tuple(get_column_letter(c) for c in (first, col, col + 1))


def _mean_line_cells(ws, t: Template, cells: dict, row: int, columns: tuple[str, str], mean: str,
               r0: int, r1: int) -> None:
    """Two points for the chart's mean line: the first and the last input, the mean at both."""
    x, y = columns
    put_text(ws, f"{x}{row}", f"the mean as a line on the chart: {t.mechanism.input_symbol}, "
                              "then the mean", NOTE)
    fmt = number_format(t.mechanism.input_unit, t.length_unit)
    for i, r in enumerate((r0, r1)):
        set_formula(ws[f"{x}{row + 1 + i}"], f"=A{r}").number_format = fmt
        set_formula(ws[f"{y}{row + 1 + i}"], f"={mean}").number_format = FORCE_FORMAT
        cells[f"mean_line_x{i}"] = {"cell": f"{x}{row + 1 + i}", "kind": "number", "unit": ""}
        cells[f"mean_line_y{i}"] = {"cell": f"{y}{row + 1 + i}", "kind": "number", "unit": ""}


def _work_column(ws, t: Template, work: str, col: str, mean: str, table: dict) -> None:
    """W: the work of T12 above its mean from the sweep's first row, by the trapezoid rule
    (J: N·m per radian)."""
    (r0, r1), head = table["rows"], 4
    put_text(ws, f"{work}3", "work of the driving torque above its mean, from the first row",
             NOTE)
    put_head(ws, head, column_index_from_string(work), header("W", "J", t.length_unit))
    ws.column_dimensions[work].width = 12
    ws[f"{work}{r0}"] = 0
    ws[f"{work}{r0}"].number_format = ENERGY_FORMAT
    for r in range(r0 + 1, r1 + 1):
        c = ws[f"{work}{r}"]
        set_formula(c, f"={work}{r - 1}+(({col}{r - 1}+{col}{r})/2-{mean})"
                       f"*RADIANS(A{r}-A{r - 1})")
        c.number_format = ENERGY_FORMAT
