"""The stroke of a grid's output: the Stroke sheet, a fine sweep of the grid's formula over a whole
turn, and the row under the grid that takes max − min of it (or of the grid itself, when the
grid already samples a turn finely enough).
"""
from __future__ import annotations

from openpyxl.utils import get_column_letter, quote_sheetname

from ..base.sheets import GRID, STROKE
from ..language.model import LENGTH, Model
from ..language.templates import Template
from .grid import corner_head, fill_grid
from .style import BOLD, DERIVED_FILL, HEAD_FILL, NOTE, TITLE, number_format, put_text, set_formula


def stroke_sheet(ws, t: Template, model: Model, names: dict[str, str], grid: dict) -> dict:
    """A fine sweep of the same grid formula, so that max − min finds the real stroke."""
    param, out = t.mechanism.grid
    step = t.stroke_step
    count = int(round(360 / step)) + 1
    put_text(ws, "A1", f"Fine sweep of {out} every {step:g}° for the stroke", TITLE)
    put_text(ws, "A2", f"The stroke (max − min over a turn) is under the grid on sheet {GRID}.",
             NOTE)
    head_row, first = 4, 5
    corner_head(ws, head_row, f"{t.mechanism.input_symbol} [deg] / {param} [{t.length_unit}]")
    cols = []
    grid_ws_ref = quote_sheetname(GRID)
    for j, letter in enumerate(grid["columns"], start=2):
        mine = get_column_letter(j)
        c = set_formula(ws.cell(head_row, j), f"={grid_ws_ref}!{letter}${grid['param_row']}")
        c.font = BOLD
        c.fill = HEAD_FILL
        cols.append(mine)
    for i in range(count):
        ws.cell(first + i, 1, round(i * step, 10))
    fill_grid(ws, t, model, names, head_row, range(first, first + count), cols)
    return {"sheet": STROKE, "param_row": head_row, "rows": [first, first + count - 1],
            "columns": cols}


def grid_is_fine(t: Template) -> bool:
    s = t.sweep
    return s.step <= t.stroke_step and s.start <= 0 and s.stop >= 360


def stroke_row(ws, t: Template, grid: dict, stroke: dict) -> int:
    """Under the grid: max − min of the fine sweep (or of the grid itself), per column."""
    row = grid["rows"][1] + 2
    put_text(ws, f"A{row}", f"stroke [{t.length_unit}]", BOLD)
    first, last = stroke["rows"]
    src = "" if stroke is grid else f"{quote_sheetname(stroke['sheet'])}!"
    for mine, theirs in zip(grid["columns"], stroke["columns"]):
        rng = f"{src}{theirs}{first}:{theirs}{last}"
        c = set_formula(ws[f"{mine}{row}"], f"=MAX({rng})-MIN({rng})")
        c.number_format = number_format(LENGTH, t.length_unit)
        c.font = BOLD
        c.fill = DERIVED_FILL
    source = ("the grid above" if stroke is grid
              else f"the {t.stroke_step:g}° sweep on sheet {STROKE}")
    # under the values, not in column A: a continuation page repeats column A, and would cut
    # the note at its edge
    put_text(ws, f"B{row + 1}", f"max − min of {source}", NOTE)
    return row
