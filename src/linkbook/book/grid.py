"""The Grid sheet (a mechanism with a [grid], the pump): the textbook's copyable grid, one
self-contained formula per cell reading its row's input and its column's parameter.
"""
from __future__ import annotations

from openpyxl.utils import column_index_from_string, get_column_letter

from ..base.errors import InputError
from ..base.sheets import GRID
from ..language.model import LENGTH, Model
from .resolve import Resolver
from ..language.templates import Template
from .package import Formula
from .style import (BOLD, BOX, INPUT_FILL, LINE_HEIGHT, NOTE, ROW, TITLE, column_width, header,
                    label_lines, number_format, put, put_head, put_text, table_style)

COL = "\x01"   # stands for the column letter in a grid formula rendered once for all cells


def grid_sheet(ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The textbook's copyable grid: one self-contained formula per cell, mixed references."""
    param, out = t.mechanism.grid
    q_out = model.get(out)
    put_text(ws, "A1", f"{t.title}: {q_out.symbol} for every {t.mechanism.input_symbol} and "
                       f"{param}", TITLE)
    put_text(ws, "A2", f"Each cell is one formula reading its row's {t.mechanism.input_symbol} "
                       f"($A) and its column's {param} (row 5), like the textbook's "
                       "=AdjustablePump(…; B$5; $A6). No macros.", NOTE)
    head_row, first = 5, 6
    angles = t.sweep.angles()
    put_head(ws, head_row - 1, 1, "")
    corner_head(ws, head_row, f"{t.mechanism.input_symbol} [deg] / {param} [{t.length_unit}]")
    cols = []
    for j, value in enumerate(t.grid_values, start=2):
        letter = get_column_letter(j)
        head = header(q_out.symbol, LENGTH, t.length_unit)
        ws.column_dimensions[letter].width = max(12, column_width(head, bold=True))
        put_head(ws, head_row - 1, j, head)
        c = ws.cell(head_row, j, value)
        c.fill = INPUT_FILL
        c.font = BOLD
        c.border = BOX
        cols.append(letter)
    for i, angle in enumerate(angles, start=first):
        ws.cell(i, 1, angle).number_format = "0.0##"
    fill_grid(ws, t, model, names, head_row, range(first, first + len(angles)), cols)
    return {"sheet": GRID, "param": param, "key": out, "param_row": head_row,
            "rows": [first, first + len(angles) - 1], "columns": cols}


def corner_head(ws, row: int, text: str) -> None:
    """A grid's corner header in A: its lines (bold: a tenth wider) each get room in the row,
    so that none crosses the row's border."""
    ws.column_dimensions["A"].width = GRID_CORNER_WIDTH
    put_head(ws, row, 1, text)
    ws.row_dimensions[row].height = LINE_HEIGHT * len(label_lines(text, GRID_CORNER_WIDTH / 1.1))


GRID_CORNER_WIDTH = 16     # also the bold `stroke [mm]` under the grid


def fill_grid(ws, t: Template, model: Model, names: dict, param_row: int, rows: range,
              cols: list[str]) -> None:
    """One self-contained formula per cell: the row's angle in $A, the column's value in
    `param_row`; the same text with the row and column put in."""
    param, out = t.mechanism.grid
    text = _grid_formula(model, names, t.mechanism.input_column, param, out, param_row,
                         max(str(rows[-1]), cols[-1], key=len))
    style = table_style(ws, number_format(LENGTH, t.length_unit))
    at = {letter: column_index_from_string(letter) for letter in cols}
    for i in rows:
        for letter in cols:
            put(ws, i, at[letter], Formula(text.replace(COL, letter).replace(ROW, str(i))),
                style)
    ws.freeze_panes = ws.cell(rows.start, 2)


def _grid_formula(model, names, input_column, param, out, param_row, place: str) -> str:
    """The self-contained grid formula, refused (before any file is written) where Excel could
    not open it (Resolver.formula: Excel's limits)."""
    cells = {input_column: f"$A{ROW}", param: f"{COL}${param_row}"}
    try:
        return Resolver(model, names, cells, field="grid.output", place=place).formula(out)
    except InputError as exc:
        raise InputError(exc.field, f"{exc.message}, in each grid cell (all of it inlined "
                                    "there): grid an earlier column, or leave out the [grid]") \
            from None
