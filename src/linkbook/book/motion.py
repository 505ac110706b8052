"""The Motion sheet: velocities and accelerations, at the current position (row 5) and at every
row of the Sweep sheet, each reading that row's positions.
"""
from __future__ import annotations

from openpyxl.utils import column_index_from_string, get_column_letter, quote_sheetname

from ..base.sheets import MECH, MOTION_SHEET, SWEEP
from ..language.mechanisms import MOTION_SYMBOLS
from ..language.model import MOTION, Model
from .resolve import Resolver
from ..language.templates import Template
from .package import Formula
from .style import (DERIVED_FILL, NOTE, ROW, TITLE, fit_labels, header, number_format, put,
                    put_head, put_text, set_formula, table_style)


SWEEP_ROW = "\x02"   # the Sweep sheet's row of a Motion row (MOTION_OFFSET rows up)
MOTION_OFFSET = 2     # Motion row 5: the current position; row 7 on: Sweep row 5 on


def motion_table(ws, t: Template, model: Model, names: dict, sweep: dict,
                 position: dict) -> dict:
    """Velocities and accelerations: row 5 at the current position (sheet Mechanism), then one
    row per Sweep row, reading that row's positions."""
    speed, accel = (model_name(names, s) for s in MOTION_SYMBOLS[t.mechanism.input_kind])
    note = (f"The input moves at {speed} with acceleration {accel} (sheet Mechanism). Row 5: "
            f"the current position; from row {5 + MOTION_OFFSET}: each row of sheet {SWEEP}. "
            "#N/A where the loop cannot close or at a dead centre.")
    table = row_table(ws, t, model, names, model.of_role(MOTION), sweep, position,
                      f"{t.title}: velocities and accelerations", note)
    return {"sheet": MOTION_SHEET, **table}


def row_table(ws, t: Template, model: Model, names: dict, qs: list, sweep: dict,
              position: dict, title: str, note: str, beside: tuple[str, dict] | None = None
              ) -> dict:
    """A table of quantities `qs` beside the sweep: row 5 at the current position (sheet
    Mechanism), then one row per Sweep row (MOTION_OFFSET rows down), each reading that row's
    positions — and, with `beside` = (sheet, its record), the same row of that sheet (the
    Forces sheet reads the Motion sheet's)."""
    mech = t.mechanism
    letters = {q.key: get_column_letter(i) for i, q in enumerate(qs, start=2)}
    put_text(ws, "A1", title, TITLE)
    put_text(ws, "A2", note, NOTE)
    head_row, current, first = 4, 5, 5 + MOTION_OFFSET
    put_head(ws, head_row, 1, header(mech.input_symbol, mech.input_unit, t.length_unit))
    ws.column_dimensions["A"].width = 12
    for i, q in enumerate(qs, start=2):
        letter = letters[q.key]
        ws.column_dimensions[letter].width = 12
        put_text(ws, f"{letter}3", q.label, NOTE)
        put_head(ws, head_row, i, header(q.symbol, q.unit, t.length_unit))
    fit_labels(ws, 3, ["A"] + [letters[q.key] for q in qs], heads=head_row)
    own = {k: f"{v}{ROW}" for k, v in letters.items()}
    src = quote_sheetname(SWEEP)
    in_sweep = {k: f"{src}!{v}{SWEEP_ROW}" for k, v in sweep["columns"].items()}
    pos = quote_sheetname(MECH)
    in_position = {k: f"{pos}!{v}" for k, v in position["cells"].items()}
    in_position[mech.input_column] = position["input_name"]
    if beside is not None:
        other, table = quote_sheetname(beside[0]), beside[1]
        in_sweep.update({k: f"{other}!{v}{ROW}" for k, v in table["columns"].items()})
        in_position.update({k: f"{other}!{v}{table['current_row']}"
                            for k, v in table["columns"].items()})
    at_sweep = Resolver(model, names, {**in_sweep, **own},
                        place=str(sweep["rows"][1] + MOTION_OFFSET))
    at_current = Resolver(model, names, {**in_position, **own}, place=str(current))
    formats = {q.key: number_format(q.unit, t.length_unit) for q in qs}
    set_formula(ws.cell(current, 1), f"={position['input_name']}").number_format = \
        number_format(mech.input_unit, t.length_unit)
    for q in qs:
        c = ws[f"{letters[q.key]}{current}"]
        set_formula(c, at_current.formula(q.key).replace(ROW, str(current)))
        c.number_format = formats[q.key]
        c.fill = DERIVED_FILL
    texts = {q.key: at_sweep.formula(q.key) for q in qs}
    columns_at = {key: column_index_from_string(letters[key]) for key in texts}
    r0, r1 = sweep["rows"]
    input_style = table_style(ws, number_format(mech.input_unit, t.length_unit))
    styles = {key: table_style(ws, formats[key]) for key in texts}
    for r in range(r0, r1 + 1):
        row, row_text, sweep_text = r + MOTION_OFFSET, str(r + MOTION_OFFSET), str(r)
        put(ws, row, 1, Formula(f"={src}!A{r}"), input_style)
        for key, text in texts.items():
            put(ws, row, columns_at[key],
                Formula(text.replace(ROW, row_text).replace(SWEEP_ROW, sweep_text)), styles[key])
    ws.freeze_panes = ws.cell(first, 2)
    return {"rows": [r0 + MOTION_OFFSET, r1 + MOTION_OFFSET], "current_row": current,
            "columns": letters}


def model_name(names: dict, symbol: str) -> str:
    """The Excel name of an input's `symbol` (the symbol itself if it has none)."""
    return names.get(symbol, symbol)
