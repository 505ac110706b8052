"""The writer's style kit: fonts, fills, number formats, how a cell, a header or a label is put
on a sheet, how wide text is, and the numbers-only columns the extents read.

Every sheet module lays its cells out with these, so that the sheets look alike and a change of
style is made in one place.
"""
from __future__ import annotations

import weakref

from openpyxl import Workbook
from openpyxl.cell.cell import Cell
from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import column_index_from_string, get_column_letter, quote_sheetname
from openpyxl.workbook.defined_name import DefinedName

from ..base.sheets import DASH
from ..language.model import (ACCEL, ANG_ACCEL, ANG_SPEED, AREA, DEG, LENGTH, NEWTON,
                              NEWTON_METRE, RAD, SPEED)
from .package import Formula


def unit_text(unit: str, length_unit: str) -> str:
    """The unit as a reader sees it: the template's length unit put in (mm, mm/s, mm/s²)."""
    if unit.startswith(LENGTH):
        return length_unit + unit[len(LENGTH):]
    return unit


def header(symbol: str, unit: str, length_unit: str) -> str:
    """`θ13 [deg]`: every header is the symbol and its unit in brackets."""
    return f"{symbol} [{unit_text(unit, length_unit)}]"


ROW = "\x00"   # stands for the row number in a table formula rendered once for all rows
ABOVE = "\x03"  # ... and for the number of the row above it (a continuation)

TITLE = Font(bold=True, size=14)
BOLD = Font(bold=True)
NOTE = Font(italic=True, color="595959")
HEAD_FILL = PatternFill("solid", fgColor="DDEBF7")
INPUT_FILL = PatternFill("solid", fgColor="FFF2CC")
DERIVED_FILL = PatternFill("solid", fgColor="EDEDED")
THIN = Side(style="thin", color="A6A6A6")
BOX = Border(left=THIN, right=THIN, top=THIN, bottom=THIN)
FORMATS = {LENGTH: "0.0000", RAD: "0.000000", DEG: "0.000", "-": "0.0000", SPEED: "0.000",
           ACCEL: "0.00", ANG_SPEED: "0.00000", ANG_ACCEL: "0.0000", NEWTON: "0.000",
           NEWTON_METRE: "0.000"}


# Decimals a unit adds to a length's format, so that a book in m shows what one in mm does.
UNIT_DECIMALS = {"mm": 0, "cm": 1, "in": 1, "ft": 2, "m": 3}


def number_format(unit: str, length_unit: str = "mm") -> str:
    fmt = FORMATS.get(unit, "0.0000")
    if unit.startswith(LENGTH):
        more = UNIT_DECIMALS.get(length_unit, 0) * (2 if unit == AREA else 1)
        fmt += "0" * more
    return fmt


# ---------------------------------------------------------------- cells and names
def define_name(wb: Workbook, name: str, sheet: str, cell: str) -> None:
    col = "".join(ch for ch in cell if ch.isalpha())
    row = "".join(ch for ch in cell if ch.isdigit())
    wb.defined_names[name] = DefinedName(name, attr_text=f"{quote_sheetname(sheet)}!${col}${row}")


def put_text(ws, cell: str, value: str, font: Font | None = None) -> None:
    """Text from a template or the command line stays text, even if it starts with '='."""
    c = ws[cell]
    c.value = value
    c.data_type = "s"
    if font:
        c.font = font


def table_style(ws, number_format: str | None = None, **parts):
    """The style of a cell with `number_format` and the style `parts` (font, fill, border,
    alignment), for `put`."""
    probe = Cell(ws)
    if number_format is not None:
        probe.number_format = number_format
    for name, part in parts.items():
        setattr(probe, name, part)
    return probe._style


def put(ws, row: int, col: int, value, style=None) -> None:
    """ws.cell(row, col, value) with a `table_style`, made straight into the sheet's cell map.
    The table rows are most of a book's cells, and openpyxl's cell() would check each formula
    for characters Excel refuses and add its format to the book's list once per cell: the style
    is made once (table_style), and the characters are checked where the cells are written
    (package.cells_held_back)."""
    cell = Cell(ws, row=row, column=col, style_array=style)
    if isinstance(value, Formula):
        cell._value, cell.data_type = value, "f"
    else:
        cell.value = value
        if isinstance(value, str):
            cell.data_type = "s"    # text stays text, whatever it starts with ('=', '#N/A')
    ws._cells[row, col] = cell


def set_formula(cell, text: str):
    """`cell` (already styled, or styled after) holds the formula `text`: a package.Formula, the
    only kind of text the writer writes as a formula. Returns the cell."""
    cell._value, cell.data_type = Formula(text), "f"
    return cell


LINE_HEIGHT = 15.0      # points per line of 11-pt text
# The widths of DejaVu Sans, the font LibreOffice draws with where Calibri is missing (and the
# wider of the two): advances in units of 2048 per em, regular and bold (oblique as regular), of
# the printable ASCII characters and then of _SYMBOLS. A character not listed counts as an em.
_SYMBOLS = "θωαμϕψφβγδεΔλπρστ∠→←²³·×ⁿ—…−°–’“”√±≤≥∞"
_REGULAR = (
    651, 821, 942, 1716, 1303, 1946, 1597, 563, 799, 799, 1024, 1716, 651, 739, 651, 690,
    1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 690, 690, 1716, 1716, 1716,
    1087, 2048, 1401, 1405, 1430, 1577, 1294, 1178, 1587, 1540, 604, 604, 1343, 1141, 1767,
    1532, 1612, 1235, 1612, 1423, 1300, 1251, 1499, 1401, 2025, 1403, 1251, 1403, 799, 690,
    799, 1716, 1024, 1024, 1255, 1300, 1126, 1300, 1260, 721, 1300, 1298, 569, 569, 1186,
    569, 1995, 1298, 1253, 1300, 1300, 842, 1067, 803, 1298, 1212, 1675, 1212, 1212, 1075,
    1303, 690, 1303, 1716, 1253, 1715, 1350, 1303, 1351, 1351, 1351, 1307, 1212, 1253, 1107,
    1401, 1212, 1233, 1300, 1298, 1233, 1836, 1716, 1716, 821, 821, 651, 1716, 816, 2048,
    2048, 1716, 1024, 1024, 651, 1061, 1061, 1305, 1716, 1716, 1716, 1706,
)
_BOLD = (
    713, 934, 1067, 1716, 1425, 2052, 1786, 627, 936, 936, 1071, 1716, 778, 850, 778, 748,
    1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 819, 819, 1716, 1716, 1716,
    1188, 2048, 1585, 1561, 1503, 1700, 1399, 1399, 1681, 1714, 762, 762, 1587, 1305, 2038,
    1714, 1741, 1501, 1741, 1577, 1475, 1397, 1663, 1585, 2259, 1579, 1483, 1485, 936, 748,
    936, 1716, 1024, 1024, 1382, 1466, 1214, 1466, 1389, 891, 1466, 1458, 702, 702, 1362,
    702, 2134, 1458, 1407, 1466, 1466, 1010, 1219, 979, 1458, 1335, 1892, 1321, 1335, 1192,
    1458, 748, 1458, 1716, 1407, 1780, 1407, 1507, 1631, 1626, 1602, 1466, 1395, 1407, 1140,
    1585, 1296, 1620, 1466, 1595, 1307, 1836, 1716, 1716, 897, 897, 778, 1716, 933, 2048,
    2048, 1716, 1024, 1024, 778, 1346, 1346, 1366, 1716, 1716, 1716, 1706,
)
_CHARS = "".join(map(chr, range(32, 127))) + _SYMBOLS
_ADVANCE = {False: dict(zip(_CHARS, _REGULAR)), True: dict(zip(_CHARS, _BOLD))}
PX_PER_UNIT = 15 / 2048       # 11-pt text on a 96-dpi screen: 14.7 px, hinted to 15
DIGIT_PX = 7                           # a column's width counts Calibri digits of 7 px


def text_width(text: str, bold: bool = False) -> float:
    """The column width `text` needs on one line in DejaVu Sans 11 pt: its advances in pixels,
    in digits of 7 px, plus one digit for the cell's padding (combining marks take none)."""
    import unicodedata
    table = _ADVANCE[bold]
    units = sum(0 if unicodedata.combining(ch) else table.get(ch, 2048) for ch in text)
    return units * PX_PER_UNIT / DIGIT_PX + 1.0


def column_width(text: str, bold: bool = False) -> float:
    """The width of a column that shows `text` on one line: text_width rounded up to the
    tenth a width is written with (rounded to the nearest, a header could lose its last
    letter to a second line)."""
    import math
    return math.ceil(text_width(text, bold) * 10 - 1e-9) / 10


def label_lines(text: str, width: float, bold: bool = False) -> list[str]:
    """`text` broken between words as a cell `width` wide shows it (no word split)."""
    lines: list[str] = []
    for word in text.split():
        if lines and text_width(f"{lines[-1]} {word}", bold) <= width:
            lines[-1] += f" {word}"
        else:
            lines.append(word)
    return lines or [""]


def fit_labels(ws, row: int, letters, heads: int | None = None) -> None:
    """Widen each column of a row of labels so that its longest word (and the bold header
    under it, in row `heads`) fits whole, wrap each label in its column, and make the row tall
    enough for every line."""
    lines = 1
    for letter in letters:
        dim, label = ws.column_dimensions[letter], ws[f"{letter}{row}"]
        width = dim.width or 12
        needs = [column_width(w) for w in str(label.value or "").split()]
        if heads is not None and isinstance(ws[f"{letter}{heads}"].value, str):
            needs.append(column_width(ws[f"{letter}{heads}"].value, bold=True))   # one line
        dim.width = width = max([width] + needs)
        if label.value is not None:
            label.alignment = Alignment(wrap_text=True, vertical="top")
            lines = max(lines, len(label_lines(str(label.value), width)))
    ws.row_dimensions[row].height = LINE_HEIGHT * lines


def fit_heads(ws, row: int, letters) -> None:
    """Widen each column of a row of bold headers so its longest word fits whole, and make the
    row tall enough for the header that wraps to the most lines."""
    lines = 1
    for letter in letters:
        dim, head = ws.column_dimensions[letter], ws[f"{letter}{row}"]
        text = str(head.value or "")
        dim.width = width = max([dim.width or 12] + [column_width(w, bold=True)
                                                     for w in text.split()])
        lines = max(lines, len(label_lines(text, width, bold=True)))
    ws.row_dimensions[row].height = max(ws.row_dimensions[row].height or 0, LINE_HEIGHT * lines)


def put_head(ws, row: int, col: int, value: str) -> None:
    """A column header: bold, centred and wrapped, in a shaded box; text even if it starts
    with '='."""
    put(ws, row, col, value, _head_style(ws))
    ws._cells[row, col].data_type = "s"


_HEAD_STYLES: "weakref.WeakKeyDictionary[Workbook, object]" = weakref.WeakKeyDictionary()


def _head_style(ws):
    """The headers' style, made once per book (each header cell gets a copy): otherwise openpyxl
    would find each of a header's four style parts in the book's lists by hashing it, for every
    header again."""
    style = _HEAD_STYLES.get(ws.parent)
    if style is None:
        style = _HEAD_STYLES[ws.parent] = table_style(
            ws, font=BOLD, fill=HEAD_FILL, border=BOX,
            alignment=Alignment(horizontal="center", vertical="center", wrap_text=True))
    return style


def block_head(ws, first_col: str, title: str, columns, row: int = 5) -> None:
    """A block's bold title in `row` and its column headers (with widths) in the row below."""
    ws[f"{first_col}{row}"] = title
    ws[f"{first_col}{row}"].font = BOLD
    start = column_index_from_string(first_col)
    for i, (head, width) in enumerate(columns):
        # a header on one line: at least its bold width in the font LibreOffice draws
        width = max(width, column_width(head, bold=True))
        ws.column_dimensions[get_column_letter(start + i)].width = width
        put_head(ws, row + 1, start + i, head)


def top_align_tall_rows(ws) -> None:
    """A row made taller for a wrapped label holds the other blocks' cells too: every cell of
    it starts at the top, level with the label's first line."""
    from copy import copy
    for r, dim in ws.row_dimensions.items():
        if not dim.height or dim.height <= LINE_HEIGHT:
            continue
        for cell in ws[r]:
            if cell.value is not None:
                align = copy(cell.alignment)
                align.vertical = "top"
                cell.alignment = align


def wrap_in(ws, cell: str) -> None:
    """A label longer than its column: wrapped there, its row tall enough for every line."""
    letter = cell.rstrip("0123456789")
    lines = label_lines(str(ws[cell].value), ws.column_dimensions[letter].width or 8.43)
    if len(lines) < 2:
        return
    ws[cell].alignment = Alignment(wrap_text=True, vertical="top")
    row = ws[cell].row
    ws.row_dimensions[row].height = max(ws.row_dimensions[row].height or LINE_HEIGHT,
                                        LINE_HEIGHT * len(lines))


def wrap_across(ws, row: int, first: str, last: str, text: str) -> None:
    """A label longer than the columns first..last (the cells beside it empty): merged across
    them and wrapped, its row as tall as its lines."""
    width = sum(ws.column_dimensions[get_column_letter(c)].width or 8.43
                for c in range(column_index_from_string(first), column_index_from_string(last) + 1))
    lines = label_lines(text, width)
    if len(lines) < 2:
        return
    ws.merge_cells(f"{first}{row}:{last}{row}")
    ws[f"{first}{row}"].alignment = Alignment(wrap_text=True, vertical="top")
    ws.row_dimensions[row].height = max(ws.row_dimensions[row].height or LINE_HEIGHT,
                                        LINE_HEIGHT * len(lines))


def numbers_only(ws, col: int, head_row: int, sources: list[str | None], head: str,
                 number_format: str) -> str:
    """A column, from row head_row + 1 on, that holds each source cell's number, or a dash
    where the source holds #N/A (the loop cannot close) or nothing (None). MIN, MAX and COUNT
    skip text in a range in every spreadsheet application, so the smallest and largest values
    of a column with #N/A in it are read from such a column. (AGGREGATE would skip the errors
    itself, but it is Excel 2010's: Gnumeric and IronCalc show #NAME?.) Returns its letter."""
    letter = get_column_letter(col)
    put_head(ws, head_row, col, head)
    style = table_style(ws, number_format)
    for r, src in enumerate(sources, start=head_row + 1):
        value = f'=IF(ISNUMBER({src}),{src},"{DASH}")' if src else f'="{DASH}"'
        put(ws, r, col, Formula(value), style)
    return letter


def column_range(sheet: str, letter: str, first: int, last: int) -> str:
    return f"{quote_sheetname(sheet)}!${letter}${first}:${letter}${last}"

