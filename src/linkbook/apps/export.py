"""`linkbook export`: the tables of a built book as CSV, one file per table sheet; and the same
tables as arrays (`linkbook.tables`).

The values are the engine's, computed from the book's formulas, so a book saved without stored
values exports numbers too. Where each table's header and rows are comes from the build
record (sheets.py); both the CSV and the arrays come from one reading of them (table_cells)."""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

from .info import Book

# A text field starting with one of these is read as a formula by spreadsheets that open the
# CSV (CSV has no cell types): OWASP's advice is to prefix it with an apostrophe
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


@dataclass
class Table:
    """One table sheet as export writes it: its header rows, then its data rows."""
    sheet: str
    rows: list[int]     # the header rows as in the book, then the data rows
    width: int | None = None    # its last column, where a block beside it is no part of it
    heads: int = 1      # how many of `rows` are header rows (the Grid's: its quantity, then s1)


def tables(book: Book) -> list[Table]:
    """The book's table sheets in its tab order: Sweep, Motion, Forces, Grid, Stroke sweep
    (those it has)."""
    from ..base.xlsx import column_index
    record, found, widths = book.record, {}, {}
    r0, r1 = record.sweep.rows
    found[record.sweep.sheet] = [r0 - 1, *range(r0, r1 + 1)]
    if record.motion:
        m = record.motion
        # the header above the current position's row; the table from the sweep's first row
        found[m.sheet] = [m.current_row - 1, *range(m.rows[0], m.rows[1] + 1)]
    if record.forces:
        f = record.forces
        found[f.sheet] = [f.current_row - 1, *range(f.rows[0], f.rows[1] + 1)]
        widths[f.sheet] = max(column_index(c) for c in [*f.columns.values(), f.work or "A"])
    if record.grid:
        g = record.grid
        stroke = [g.stroke_row] if g.stroke_row is not None else []
        found[g.sheet] = [g.param_row - 1, g.param_row, *range(g.rows[0], g.rows[1] + 1), *stroke]
    if record.stroke:
        s = record.stroke
        found[s.sheet] = [s.param_row, *range(s.rows[0], s.rows[1] + 1)]
    heads = {record.grid.sheet: 2} if record.grid else {}
    return [Table(name, found[name], widths.get(name), heads.get(name, 1))
            for name in book.wb.sheetnames if name in found]


def field(value) -> str:
    """One CSV field: a number in full precision (repr), an error as its code (#N/A), a text
    guarded against being read as a formula, an empty cell empty."""
    from ..engine.evaluator import error_code
    if value is None:
        return ""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else "#NUM!"
    code = error_code(value)
    if code is not None:
        return code
    text = str(value)
    return "'" + text if text.startswith(FORMULA_STARTS) else text


def _last_column(book: Book, table: Table) -> int:
    """The table's width: its last column holding anything in any of its rows."""
    from ..base.xlsx import coordinate_to_tuple
    rows, last = set(table.rows), 0
    for (sheet, cell), value in book.values.items():
        if sheet == table.sheet and value is not None and value != "":
            row, col = coordinate_to_tuple(cell)
            if row in rows:
                last = max(last, col)
    return last


def table_cells(book: Book, table: Table) -> list[list]:
    """The table's values, row by row (its header rows first), each row as wide as the table:
    the one reading of a table that the CSV and the arrays share."""
    from ..base.xlsx import column_letter
    width = table.width or _last_column(book, table)
    letters = [column_letter(c) for c in range(1, width + 1)]
    return [[book.values.get((table.sheet, f"{letter}{row}")) for letter in letters]
            for row in table.rows]


def table_text(book: Book, table: Table) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    for row in table_cells(book, table):
        writer.writerow([field(value) for value in row])
    return out.getvalue()


def _float(value) -> float:
    """A cell's value as a float: NaN for #N/A, any other error, a text or an empty cell."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return math.nan


def table_arrays(book: Book, table: Table) -> dict:
    """{header: numpy array} of one table: each column under the text its last header row
    shows (as the CSV writes it), the data rows as floats."""
    import numpy as np
    cells = table_cells(book, table)
    heads, data = cells[table.heads - 1], cells[table.heads:]
    return {field(head): np.array([_float(row[i]) for row in data])
            for i, head in enumerate(heads)}


def arrays(book: Book) -> dict[str, dict]:
    """{sheet: {header: numpy array}} of every table, in the book's tab order."""
    return {table.sheet: table_arrays(book, table) for table in tables(book)}


def file_name(book_stem: str, sheet: str) -> str:
    return f"{book_stem}-{sheet.replace(' ', '-')}.csv"


def table_texts(book: Book) -> list[tuple[str, str]]:
    """(sheet, CSV text) of every table: all computed before any file is written."""
    return [(table.sheet, table_text(book, table)) for table in tables(book)]


def export(texts: list[tuple[str, str]], book_stem: str, outdir: Path) -> list[Path]:
    """Write each table's text to OUTDIR/BOOK-SHEET.csv (UTF-8 with a byte-order mark, so that
    Excel reads θ and μ right); each file written whole or not at all."""
    from ..base.files import write_atomic
    written = []
    for sheet, text in texts:
        path = outdir / file_name(book_stem, sheet)
        write_atomic(path, lambda tmp, text=text: Path(tmp).write_text(text,
                                                                        encoding="utf-8-sig"))
        written.append(path)
    return written
