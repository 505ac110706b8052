"""The book's sheet names and its build record: what the writer lays out and verify reads.

No openpyxl here: verify reads a book through the fast view (linkbook.xlsx) and does not pay
for importing the writer's library."""
from __future__ import annotations

import json

MECH, SWEEP, MOTION_SHEET, CHARTS, GRID, STROKE, META = (
    "Mechanism", "Sweep", "Motion", "Charts", "Grid", "Stroke sweep", "linkbook")
FORMAT_VERSION = 1
DRAWING_COLUMNS = ("N", "O")   # x and y of the joints table and of the links the drawing plots
DASH = "—"     # "no value here" in text cells (SMALL, MIN, MAX and COUNT skip text)
GAPS_SHOWN = 3       # the assembly gaps the summary lists
CELL_TEXT = 30_000    # Excel holds at most 32,767 characters in a cell


def summary_prefix(base: str, i: int) -> str:
    """Keys of the summary's i-th transmission angle or four-bar loop: the first keeps the
    names older books have (mu_min, fb_ground, grashof, limit_folded_1), then mu2_min, fb2_…"""
    return base + (str(i) if i > 1 else "")


def write_meta(ws, meta: dict) -> None:
    """The record as JSON in A2, continued in A3, A4, … when a large description needs it."""
    ws.sheet_state = "hidden"
    ws["A1"] = "linkbook build record: which template, branch and layout this workbook has."
    ws["A1"].data_type = "s"
    text = json.dumps(meta, ensure_ascii=False, sort_keys=True)
    for i in range(0, len(text), CELL_TEXT):
        cell = ws.cell(2 + i // CELL_TEXT, 1, text[i:i + CELL_TEXT])
        cell.data_type = "s"


def read_meta(wb) -> dict | None:
    if META not in wb.sheetnames:
        return None
    ws, parts, row = wb[META], [], 2
    while isinstance(part := ws.cell(row, 1).value, str):
        parts.append(part)
        row += 1
    try:
        return json.loads("".join(parts)) if parts else None
    except json.JSONDecodeError:
        return None
