"""The book's sheet names and its build record: what the writer lays out and verify reads.

No openpyxl here: verify reads a book through the fast view (linkbook.base.xlsx) and does not pay
for importing the writer's library."""
from __future__ import annotations

import json

from .record import FORMAT_VERSION, BuildRecord  # noqa: F401  (the version: the record's)

MECH, SWEEP, MOTION_SHEET, CHARTS, GRID, STROKE, META = (
    "Mechanism", "Sweep", "Motion", "Charts", "Grid", "Stroke sweep", "linkbook")
FORCES_SHEET = "Forces"
SYNTHESIS = "Synthesis"
# The Synthesis sheet's checks in words (book/synthesis.py writes them, verify expects them)
SYNTHESIS_WORDS = {
    "singular": "near-singular (cond₂ > 10⁶): nothing is designed",
    "solvable": "solvable",
    "positive": "both positive",
    "crank negative": "crank a < 0: its pin lies beyond A0 (the crank turned 180°); not analysed",
    "rocker negative": "rocker c < 0: its pin lies beyond B0 (the rocker turned 180°); "
                       "not analysed",
    "both negative": "a < 0 and c < 0: both pins lie beyond their pivots; not analysed",
    "defect": "branch defect: the points need both assemblies, no one linkage passes "
              "through all",
    "no defect": "no branch defect",
    # motion and path generation: a link that comes out of (almost) zero length
    "too short": "a link shorter than 10⁻⁹ of the task's size: nothing is designed",
    "long enough": "every link longer than 10⁻⁹ of the task's size",
}
DRAWING_COLUMNS = ("N", "O")   # x and y of the joints table and of the links the drawing plots
JOINT_COLUMN = "M"             # the joints table's joint names: the drawing's labels read them
DASH = "—"     # "no value here" in text cells (SMALL, MIN, MAX and COUNT skip text)
GAPS_SHOWN = 3       # the assembly gaps the summary lists
CELL_TEXT = 30_000    # Excel holds at most 32,767 characters in a cell


def summary_prefix(base: str, i: int) -> str:
    """Keys of the summary's i-th transmission angle or four-bar loop: the first keeps the
    names older books have (mu_min, fb_ground, grashof, limit_folded_1), then mu2_min, fb2_…"""
    return base + (str(i) if i > 1 else "")


def write_meta(ws, record: BuildRecord | dict) -> None:
    """The record as JSON in A2, continued in A3, A4, … when a large description needs it. A
    dict is read as a record first, so that a key the record does not know fails here."""
    if not isinstance(record, BuildRecord):
        record = BuildRecord.from_json(record)
    write_meta_json(ws, record.to_json())


def write_meta_json(ws, meta) -> None:
    """`meta` as the record's JSON, unchecked (a test writes a damaged record with it)."""
    ws.sheet_state = "hidden"
    ws["A1"] = "linkbook build record: which template, branch and layout this workbook has."
    ws["A1"].data_type = "s"
    text = json.dumps(meta, ensure_ascii=False, sort_keys=True)
    for i in range(0, len(text), CELL_TEXT):
        cell = ws.cell(2 + i // CELL_TEXT, 1, text[i:i + CELL_TEXT])
        cell.data_type = "s"


def read_meta(wb) -> dict | None:
    """The record's JSON as written (None without the sheet or when the text is not JSON);
    read_record gives it typed."""
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


def read_record(wb) -> BuildRecord | None:
    """The book's build record, typed and upgraded to today's shape; None without the record
    sheet. DamagedRecord when its text is no record of this format; KeyError, TypeError or
    ValueError when its entries are not what the writer records."""
    if META not in wb.sheetnames:
        return None
    try:
        data = read_meta(wb)
    except RecursionError:
        data = None
    return BuildRecord.from_json(data)
