"""Workbook layout: the one place that knows openpyxl and how a linkbook workbook looks.

Sheets: Mechanism (inputs with defined names, derived constants, the current position and its
drawing), Sweep (one row per input angle, one formula column per step), Charts, and for a mechanism
with a grid (the pump) Grid and Stroke sweep. A hidden sheet `linkbook` records what was built and
where each quantity lives, so `verify` can read an edited workbook back.
"""
from __future__ import annotations

import re
import weakref
from dataclasses import dataclass, field, replace

from openpyxl import Workbook
from openpyxl.cell.cell import Cell
from openpyxl.styles import Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import column_index_from_string, get_column_letter, quote_sheetname
from openpyxl.workbook.defined_name import DefinedName
from openpyxl.worksheet.datavalidation import DataValidation

from ..base import __version__
from ..base.record import BuildRecord
from ..language.mechanisms import ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, MOTION_SYMBOLS
from ..language.model import (ACCEL, ANG_ACCEL, ANG_SPEED, AREA, COLUMN, CONSTANT, DEG, LENGTH, MOTION, RAD,
                    SPEED, Model, Resolver, header, parenthesize, render, unit_text)
from .controls import control_record
from ..language.domain import INPUT_ANGLE_LIMIT
from .package import Formula
from ..base.sheets import (CHARTS, DASH, DRAWING_COLUMNS, FORMAT_VERSION, GAPS_SHOWN, GRID, MECH,  # noqa: F401
                     META, MOTION_SHEET, STROKE, SWEEP, read_meta, summary_prefix, write_meta)
from ..language.steps import outside_domain
from ..language.templates import Template

ROW = "\x00"   # stands for the row number in a rendered sweep formula
SWEEP_ROW = "\x02"   # the Sweep sheet's row of a Motion row (MOTION_OFFSET rows up)
MOTION_OFFSET = 2     # Motion row 5: the current position; row 7 on: Sweep row 5 on
COL = "\x01"   # stands for the column letter in a rendered grid formula

TITLE = Font(bold=True, size=14)
BOLD = Font(bold=True)
NOTE = Font(italic=True, color="595959")
HEAD_FILL = PatternFill("solid", fgColor="DDEBF7")
INPUT_FILL = PatternFill("solid", fgColor="FFF2CC")
DERIVED_FILL = PatternFill("solid", fgColor="EDEDED")
THIN = Side(style="thin", color="A6A6A6")
BOX = Border(left=THIN, right=THIN, top=THIN, bottom=THIN)
FORMATS = {LENGTH: "0.0000", RAD: "0.000000", DEG: "0.000", "-": "0.0000", SPEED: "0.000",
           ACCEL: "0.00", ANG_SPEED: "0.00000", ANG_ACCEL: "0.0000"}


# Decimals a unit adds to a length's format, so that a book in m shows what one in mm does.
UNIT_DECIMALS = {"mm": 0, "cm": 1, "in": 1, "ft": 2, "m": 3}


def number_format(unit: str, length_unit: str = "mm") -> str:
    fmt = FORMATS.get(unit, "0.0000")
    if unit.startswith(LENGTH):
        more = UNIT_DECIMALS.get(length_unit, 0) * (2 if unit == AREA else 1)
        fmt += "0" * more
    return fmt


@dataclass
class Built:
    """The workbook and the record of where everything is (stored in the hidden sheet): as
    the writer assembled it (`meta`) and typed (`record`)."""
    workbook: Workbook
    model: Model
    meta: dict = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)   # for the builder's user, not the book
    record: BuildRecord | None = None


def build(t: Template) -> Built:
    """Lay the workbook out; each output angle's degree view starts at its default window
    (set_degree_windows moves it)."""
    model = t.mechanism.build()
    wb = Workbook()
    wb.security = None      # openpyxl's default writes an empty <workbookProtection/>: it
                            # protects nothing, and Gnumeric does not know the element
    ws_mech = wb.active
    ws_mech.title = MECH
    ws_sweep = wb.create_sheet(SWEEP)
    ws_motion = wb.create_sheet(MOTION_SHEET) if model.of_role(MOTION) else None
    wb.create_sheet(CHARTS)     # filled by charts.add_charts once values are known
    meta = {"format": FORMAT_VERSION, "linkbook": __version__, "template": t.name,
            "mechanism": t.mechanism.name, "title": t.title, "length_unit": t.length_unit,
            "input": t.mechanism.input_key}
    if t.mechanism.description is not None:
        meta["description"] = t.mechanism.description

    names, meta["inputs"], meta["constants"], next_row = _inputs_block(wb, ws_mech, t, model)
    meta["position"] = _position_block(wb, ws_mech, t, model, names)
    meta["sweep"] = _sweep_table(ws_sweep, t, model, names)
    if ws_motion is not None:
        meta["motion"] = _motion_table(ws_motion, t, model, names, meta["sweep"],
                                       meta["position"])
        _position_motion(ws_mech, t, model, meta["position"], meta["motion"])
    meta["numbers_only"] = sweep_numbers_only(ws_sweep, t, model, meta["sweep"])
    meta["summary"] = _summary_block(ws_mech, t, model, names, meta["sweep"], next_row + 1)
    _top_align_tall_rows(ws_mech)
    meta["controls"] = {MECH: _controls(ws_mech, t, meta["inputs"])}
    if t.mechanism.grid:
        meta["grid"] = _grid_sheet(wb.create_sheet(GRID), t, model, names)
        meta["grid"]["stroke_step"] = t.stroke_step     # the template's: what verify expects
        # A grid that already samples a whole turn finely enough is its own stroke sweep.
        meta["stroke"] = (meta["grid"] if grid_is_fine(t) else
                          _stroke_sheet(wb.create_sheet(STROKE), t, model, names, meta["grid"]))
        meta["grid"]["stroke_row"] = _stroke_row(wb[GRID], t, meta["grid"], meta["stroke"])
    from .frames import frames_sheet      # it lays its cells out with this module's helpers
    meta["frames"] = frames_sheet(wb, t, model, meta)
    record = BuildRecord.from_json(meta)      # a key the record does not know fails here
    write_meta(wb.create_sheet(META), record)
    return Built(wb, model, meta, record=record)


# ---------------------------------------------------------------- cells and names
def _define(wb: Workbook, name: str, sheet: str, cell: str) -> None:
    col = "".join(ch for ch in cell if ch.isalpha())
    row = "".join(ch for ch in cell if ch.isdigit())
    wb.defined_names[name] = DefinedName(name, attr_text=f"{quote_sheetname(sheet)}!${col}${row}")


def _text(ws, cell: str, value: str, font: Font | None = None) -> None:
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
    for characters Excel refuses and add its format to the book's list once per cell (0.35 s of
    the 0.1° four-bar's build): the style is made once here, and the characters are checked
    where the cells are written (package.cells_held_back)."""
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


def label_lines(text: str, width: float) -> list[str]:
    """`text` broken between words as a cell `width` wide shows it (no word split)."""
    lines: list[str] = []
    for word in text.split():
        if lines and text_width(f"{lines[-1]} {word}") <= width:
            lines[-1] += f" {word}"
        else:
            lines.append(word)
    return lines or [""]


def _fit_labels(ws, row: int, letters, heads: int | None = None) -> None:
    """Widen each column of a row of wrapped labels so that its longest word (and the bold
    header under it, in row `heads`) fits whole, and make the row tall enough for every line."""
    lines = 1
    for letter in letters:
        dim = ws.column_dimensions[letter]
        width = dim.width or 12
        needs = [text_width(w) for w in str(ws[f"{letter}{row}"].value or "").split()]
        if heads is not None and isinstance(ws[f"{letter}{heads}"].value, str):
            needs.append(text_width(ws[f"{letter}{heads}"].value, bold=True))   # one line
        width = max([width] + needs)
        dim.width = round(width, 1)
        lines = max(lines, len(label_lines(str(ws[f"{letter}{row}"].value or ""), width)))
    ws.row_dimensions[row].height = LINE_HEIGHT * lines


def _head(ws, row: int, col: int, value: str) -> None:
    """A column header: bold, centred and wrapped, in a shaded box; text even if it starts
    with '='."""
    put(ws, row, col, value, _head_style(ws))
    ws._cells[row, col].data_type = "s"


_HEAD_STYLES: "weakref.WeakKeyDictionary[Workbook, object]" = weakref.WeakKeyDictionary()


def _head_style(ws):
    """The headers' style, made once per book (each header cell gets a copy): openpyxl finds
    each of a cell's four style parts in the book's lists by hashing it, done for every header
    a seventh of the garage door's layout time."""
    style = _HEAD_STYLES.get(ws.parent)
    if style is None:
        style = _HEAD_STYLES[ws.parent] = table_style(
            ws, font=BOLD, fill=HEAD_FILL, border=BOX,
            alignment=Alignment(horizontal="center", vertical="center", wrap_text=True))
    return style


def _block_head(ws, first_col: str, title: str, columns, row: int = 5) -> None:
    """A block's bold title in `row` and its column headers (with widths) in the row below."""
    ws[f"{first_col}{row}"] = title
    ws[f"{first_col}{row}"].font = BOLD
    start = column_index_from_string(first_col)
    for i, (head, width) in enumerate(columns):
        # a header on one line: at least its bold width in the font LibreOffice draws
        width = max(width, round(text_width(head, bold=True), 1))
        ws.column_dimensions[get_column_letter(start + i)].width = width
        _head(ws, row + 1, start + i, head)


def _validation(kind: str, field_name: str) -> DataValidation:
    if kind == BRANCH_KIND:
        dv = DataValidation(type="list", formula1='"1,-1"', allow_blank=False)
        dv.prompt = "1 = open branch, -1 = crossed branch"
    elif kind == LENGTH_KIND:
        dv = DataValidation(type="decimal", operator="greaterThan", formula1="0")
        dv.prompt = "A length: a positive number"
    elif kind == ANGLE_KIND:
        dv = DataValidation(type="decimal", operator="between", formula1="-360", formula2="360")
        dv.prompt = "An angle in degrees, from -360 to 360"
    else:
        dv = DataValidation(type="decimal", operator="between", formula1="-1E+300",
                            formula2="1E+300")
        dv.prompt = "A number (may be zero or negative)"
    dv.promptTitle = field_name[:32]
    dv.error = dv.prompt
    dv.errorTitle = "linkbook"
    dv.showInputMessage = dv.showErrorMessage = True
    return dv


# ---------------------------------------------------------------- Mechanism sheet
def _inputs_block(wb, ws, t: Template, model: Model):
    _text(ws, "A1", t.title, TITLE)
    _text(ws, "A2", t.source, NOTE)
    _text(ws, "A3", "Yellow cells are inputs: change them and every formula, table and chart "
                    "follows.", NOTE)
    symbols = [p.symbol for p in t.parameters] + [q.symbol for q in model.of_role(CONSTANT)]
    _block_head(ws, "A", "Inputs", (("Quantity", 43),
                                      ("Symbol", max([9] + [text_width(s) for s in symbols])),
                                      ("Value", 12), ("Unit", 8), ("Excel name", 14)))
    names: dict[str, str] = {}
    inputs: dict[str, dict] = {}
    row = 7
    for p in t.parameters:
        _text(ws, f"A{row}", p.label)
        _wrap_in(ws, f"A{row}")
        _text(ws, f"B{row}", p.symbol)
        value = ws[f"C{row}"]
        value.value = int(p.value) if p.kind == BRANCH_KIND else p.value
        value.fill = INPUT_FILL
        value.border = BOX
        value.number_format = "0" if p.kind == BRANCH_KIND else "General"
        _text(ws, f"D{row}", p.unit)
        _text(ws, f"E{row}", p.name, NOTE)
        dv = _validation(p.kind, p.label)
        ws.add_data_validation(dv)
        dv.add(f"C{row}")
        _define(wb, p.name, MECH, f"C{row}")
        names[p.symbol] = p.name
        inputs[p.symbol] = {"cell": f"C{row}", "name": p.name, "kind": p.kind}
        row += 1
    constants: dict[str, dict] = {}
    derived = model.of_role(CONSTANT)
    if derived:
        row += 1
        ws[f"A{row}"] = "Derived from the inputs"
        ws[f"A{row}"].font = BOLD
        row += 1
        resolve = Resolver(model, names, {})
        for q in derived:
            name = f"k_{q.key}"
            _text(ws, f"A{row}", q.label)
            _wrap_in(ws, f"A{row}")
            _text(ws, f"B{row}", q.symbol)
            c = ws[f"C{row}"]
            set_formula(c, resolve.formula(q.key))
            c.fill = DERIVED_FILL
            c.number_format = number_format(q.unit, t.length_unit)
            _text(ws, f"D{row}", unit_text(q.unit, t.length_unit))
            _text(ws, f"E{row}", name, NOTE)
            _define(wb, name, MECH, f"C{row}")
            names[q.key] = name
            constants[q.key] = {"cell": f"C{row}", "name": name, "unit": q.unit}
            row += 1
    return names, inputs, constants, row


def _position_block(wb, ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The textbook's spin-button row: one input value drives every step and the drawing."""
    mech = t.mechanism
    _block_head(ws, "G", "Current position",
                (("Quantity", 37), ("Symbol", 8), ("Value", 13), ("Unit", 7)))
    input_name = f"{mech.input_key}_now"
    _text(ws, "G7", f"input {mech.input_word}: change it, all follows")
    _wrap_in(ws, "G7")
    _text(ws, "H7", mech.input_symbol)
    ws["I7"] = t.position
    ws["I7"].fill = INPUT_FILL
    ws["I7"].border = BOX
    ws["I7"].number_format = number_format(mech.input_unit, t.length_unit)
    _text(ws, "J7", unit_text(mech.input_unit, t.length_unit))
    if mech.input_is_angle:
        dv = DataValidation(type="decimal", operator="between",
                            formula1=f"{-INPUT_ANGLE_LIMIT:g}", formula2=f"{INPUT_ANGLE_LIMIT:g}")
        dv.prompt = "The input angle in degrees"
    else:
        dv = DataValidation(type="decimal", operator="greaterThan", formula1="0")
        dv.prompt = f"The actuator's length in {t.length_unit}"
    dv.showInputMessage = True
    ws.add_data_validation(dv)
    dv.add("I7")
    _define(wb, input_name, MECH, "I7")
    cells = {mech.input_column: input_name}
    rows = _sweep_columns(model, mech.input_column)[1:]
    for row, (key, _) in enumerate(rows, start=8):
        cells[key] = f"I{row}"
    resolve = Resolver(model, names, cells)
    for key, q in rows:
        cell = cells[key]
        r = int(cell[1:])
        _text(ws, f"G{r}", q.label)
        ws[f"G{r}"].alignment = Alignment(wrap_text=True, vertical="top")
        _text(ws, f"H{r}", q.symbol)
        set_formula(ws[cell], _degree_formula(q, cells[q.key]) if key != q.key
                    else resolve.formula(key))
        unit = DEG if key != q.key else q.unit
        ws[cell].number_format = number_format(unit, t.length_unit)
        _text(ws, f"J{r}", unit_text(unit, t.length_unit))
    joints = _joints_table(ws, t, model, resolve)
    return {"sheet": MECH, "input_cell": "I7", "input_name": input_name,
            "cells": {k: v for k, v in cells.items() if k != mech.input_column},
            "joints": joints["cells"], "drawing": joints["drawing"],
            "traced": _traced_joint(model),
            "chart_anchor": f"L{joints['chart_row']}"}


def _traced_joint(model: Model) -> str | None:
    """The joint whose path the drawing shows (its coordinates are the path's columns)."""
    if not model.path:
        return None
    x, y = model.path
    return next((j.name for j in model.joints if (j.x, j.y) == (f"{{{x}}}", f"{{{y}}}")), None)


def _controls(ws, t: Template, inputs: dict) -> list[dict]:
    """The textbook's spin button, and a scroll bar, linked to the current-position input (I7):
    a click turns the crank by 1 (degree, or length unit), a page by the sweep's step; a spin
    button beside the grid parameter's input (the pump's s1). controls.py writes them."""
    mech = t.mechanism
    lo, hi = (0, 360) if mech.input_is_angle else (t.sweep.start, t.sweep.stop)
    page = t.sweep.step
    ws["G4"] = f"drag or click to move the input {mech.input_word}:"
    ws["G4"].alignment = Alignment(horizontal="right", vertical="center")
    # anchors: zero-based column, pixel offset, row, pixel offset (top left, then bottom right)
    out = [control_record("Scroll", "I7", lo, hi, 1, page, t.position, (7, 0, 3, 2, 10, 0, 3, 18)),
           control_record("Spin", "I7", lo, hi, 1, page, t.position, (10, 4, 6, 1, 10, 24, 8, 0))]
    if mech.grid:
        param = mech.grid[0]
        row = int(inputs[param]["cell"][1:]) - 1
        values = t.grid_values
        out.append(control_record("Spin", inputs[param]["cell"], min(values), max(values), 1,
                                  1, t.values()[param], (5, 4, row, 1, 5, 24, row + 1, 0)))
    return [c for c in out if c is not None]


def _joints_table(ws, t: Template, model: Model, resolve: Resolver) -> dict:
    """Joint coordinates, then each link as a run of rows the drawing chart reads."""
    _block_head(ws, "L", "Joints and links (drawing data)",
                (("Link", 8), ("Joint", 8), ("x", 11), ("y", 11)))
    cells: dict[str, list[str]] = {}
    row = 7
    x_col, y_col = DRAWING_COLUMNS
    for j in model.joints:
        _text(ws, f"M{row}", j.name)
        for col, expr in ((x_col, j.x), (y_col, j.y)):
            set_formula(ws[f"{col}{row}"], "=" + render(expr, resolve))
            ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
        cells[j.name] = [f"{x_col}{row}", f"{y_col}{row}"]
        row += 1
    drawing = []
    row += 1
    # the textbook's numbering: the ground is link 1 (drawn through the fixed pivots when there
    # are two or more), the crank link 2, and so on
    links = [(1, model.ground, True)] if len(model.ground) > 1 else []
    links += [(i, link, False) for i, link in enumerate(model.links, start=2)]
    for i, link, ground in links:
        first = row
        for name in link:
            _text(ws, f"L{row}", f"link {i}")
            _text(ws, f"M{row}", name)
            set_formula(ws[f"{x_col}{row}"], f"={cells[name][0]}")
            set_formula(ws[f"{y_col}{row}"], f"={cells[name][1]}")
            for col in DRAWING_COLUMNS:
                ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
            row += 1
        body = link[:-1] if len(link) > 2 and link[0] == link[-1] else link
        drawing.append({"joints": list(link), "rows": [first, row - 1], "ground": ground,
                        "label": f"link {i}: " + ("ground" if ground else "".join(body))})
    for part in _slider_parts(t, model, resolve):
        first = row
        for name, (x, y) in part["points"]:
            _text(ws, f"L{row}", part["kind"])
            _text(ws, f"M{row}", name)
            set_formula(ws[f"{x_col}{row}"], x)
            set_formula(ws[f"{y_col}{row}"], y)
            for col in DRAWING_COLUMNS:
                ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
            row += 1
        drawing.append({"joints": [name for name, _ in part["points"]], "rows": [first, row - 1],
                        "ground": False, "kind": part["kind"], "label": part["label"]})
    for col in ("L", "M"):      # a slider's rows name longer points (`B guide 1`): shown whole
        names = [ws[f"{col}{r}"].value for r in range(7, row)]
        widest = max((text_width(n) for n in names if isinstance(n, str)), default=0.0)
        ws.column_dimensions[col].width = max(ws.column_dimensions[col].width, round(widest, 1))
    return {"cells": cells, "drawing": drawing, "chart_row": row + 1}


# A block is BLOCK_SQUARES grid squares of the drawing (along its line, across it), so that it
# reads the same at any size; a guide runs over the block's travel in the sweep, whose ends lie
# inside the drawing's frame.
BLOCK_SQUARES = (0.8, 0.4)
BLOCK_CORNERS = ((-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1))    # closed, counter-clockwise


def _slider_parts(t: Template, model: Model, resolve: Resolver) -> list[dict]:
    """The guides and blocks of the drawing: {kind, label, points: [(name, (x, y))]}, each
    coordinate a formula at the current position sized in the drawing's grid squares."""
    from .frames import SQUARE_CELL      # frames.py lays its cells out with this module's helpers
    copies, first, last = _numbers_place(t, model)
    half_long, half_across = (f"{b / 2:g}*{SQUARE_CELL}" for b in BLOCK_SQUARES)
    parts = []
    for g in model.guides:
        travel = column_range(SWEEP, copies[g.travel], first, last)   # numbers only
        ends = []
        for k, fn in enumerate(("MIN", "MAX"), start=1):
            reach = f"{fn}({travel})"
            # a block that never closes over the sweep has no travel: no guide (#N/A)
            ends.append((f"{g.point} {g.kind} {k}",
                         tuple(f"=IF(COUNT({travel}),"
                               + _sum([(1, render(o, resolve), "1"),
                                       (1, reach, render(c, resolve))]) + ",NA())"
                               for o, c in ((g.x, g.cos), (g.y, g.sin)))))
        parts.append({"kind": g.kind, "label": f"{g.kind} of {g.point}", "points": ends})
    for b in model.blocks:
        x, y, cos, sin = (render(e, resolve) for e in (b.x, b.y, b.cos, b.sin))
        corners = []
        for k, (u, v) in enumerate(BLOCK_CORNERS[:-1], start=1):
            # the corner u·(half length)·d + v·(half width)·n, n = d turned +90°
            corners.append((f"{b.point} block {k}", (
                "=" + _sum([(1, x, "1"), (u, half_long, cos), (-v, half_across, sin)]),
                "=" + _sum([(1, y, "1"), (u, half_long, sin), (v, half_across, cos)]))))
        parts.append({"kind": "block", "label": f"block at {b.point}",
                      "points": corners + corners[:1]})
    return parts


def _sum(terms: list[tuple[int, str, str]]) -> str:
    """Σ sign·term·factor as formula text; a factor 0 drops its term, 1 and −1 are written into
    its sign (a horizontal line's formulas carry no ×0 or ×1)."""
    out = ""
    for sign, term, factor in terms:
        f = factor.strip()
        if f in ("0", "-0", "(0)") or term in ("0", "(0)"):
            continue
        if f in ("-1", "(-1)"):
            sign, f = -sign, "1"
        if f not in ("1", "(1)") or sign < 0:
            term = f"({term})" if _has_sum(term) else term
        text = term if f in ("1", "(1)") else f"{term}*{parenthesize(f)}"
        out += ("-" if sign < 0 else ("+" if out else "")) + text
    return out or "0"


def _has_sum(text: str) -> bool:
    """A + or − outside brackets (after the first character): the text needs brackets to be
    multiplied or subtracted."""
    depth = 0
    for i, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and i > 0 and ch in "+-" and text[i - 1] not in "*/^(" \
                and not _EXPONENT.search(text[:i]):
            return True
    return text.startswith("-")


# a number's exponent just before a sign (1.5E-3): the sign is the number's, not a sum's
_EXPONENT = re.compile(r"(?<![\w$.])\d+(\.\d*)?E$")


# ---------------------------------------------------------------- Sweep sheet
def _sweep_columns(model: Model, input_column: str) -> list[tuple[str, object]]:
    """(key, quantity) in table order: the input (an angle in degrees), the steps, then outputs
    in degrees."""
    columns: list[tuple[str, object]] = [(input_column, None)]
    columns += [(q.key, q) for q in model.of_role(COLUMN)]
    columns += [(f"{q.key}_deg", q) for q in model.of_role(COLUMN) if q.in_degrees]
    return columns


def default_window(q) -> float:
    """Where the 360° window of a degree view starts unless the build chose one from data."""
    return 0.0 if q.wrap_360 else -180.0


def set_degree_windows(built: Built, windows: dict[str, float]) -> None:
    """Rewrite the degree views (current position and sweep) of the output angles whose window
    start `windows` gives."""
    position, sweep = built.meta["position"], built.meta["sweep"]
    r0, r1 = sweep["rows"]
    ws_mech, ws_sweep = built.workbook[MECH], built.workbook[SWEEP]
    for q in built.model.of_role(COLUMN):
        key = f"{q.key}_deg"
        if not q.in_degrees or windows.get(q.key, default_window(q)) == default_window(q):
            continue
        cell = position["cells"][key]
        set_formula(ws_mech[cell], _degree_formula(q, position["cells"][q.key], windows[q.key]))
        letter, source = sweep["columns"][key], sweep["columns"][q.key]
        col = column_index_from_string(letter)
        for r in range(r0, r1 + 1):
            set_formula(ws_sweep.cell(r, col), _degree_formula(q, f"{source}{r}", windows[q.key]))


def set_radian_windows(built: Built, windows: dict[str, float]) -> None:
    """Rewrite the radian cells (current position and sweep) of the ATAN2 angles whose window
    start (degrees) `windows` gives, where it is not ATAN2's own (-180°, 180°]."""
    position, sweep = built.meta["position"], built.meta["sweep"]
    r0, r1 = sweep["rows"]
    ws_mech, ws_sweep = built.workbook[MECH], built.workbook[SWEEP]
    for key, lo in windows.items():
        if lo == -180.0:
            continue
        cell = position["cells"][key]
        set_formula(ws_mech[cell], _radian_window(ws_mech[cell].value, lo))
        col = column_index_from_string(sweep["columns"][key])
        for r in range(r0, r1 + 1):
            set_formula(ws_sweep.cell(r, col), _radian_window(ws_sweep.cell(r, col).value, lo))


def _radian_window(formula: str, lo: float) -> str:
    """An angle formula's value shown in [lo°, lo° + 360°), in radians."""
    shift = f"-RADIANS({lo:g})" if lo > 0 else f"+RADIANS({-lo:g})" if lo < 0 else ""
    back = f"+RADIANS({lo:g})" if lo > 0 else f"-RADIANS({-lo:g})" if lo < 0 else ""
    return f"=MOD({formula[1:]}{shift},2*PI()){back}"


def _degree_formula(q, ref: str, lo: float | None = None) -> str:
    """The degree view of a radian cell, shown in [lo, lo + 360) (by default q's window)."""
    lo = default_window(q) if lo is None else lo
    shift = f"-{lo:g}" if lo > 0 else f"+{-lo:g}" if lo < 0 else ""
    back = f"+{lo:g}" if lo > 0 else f"-{-lo:g}" if lo < 0 else ""
    return f"=MOD(DEGREES({ref}){shift},360){back}"


def _sweep_place(t: Template, model: Model) -> tuple[dict[str, str], int, int]:
    """The Sweep sheet's column letters by key, its first and last row of numbers."""
    columns = _sweep_columns(model, t.mechanism.input_column)
    letters = {key: get_column_letter(i) for i, (key, _) in enumerate(columns, start=1)}
    return letters, SWEEP_FIRST_ROW, SWEEP_FIRST_ROW + len(t.sweep.angles()) - 1


SWEEP_FIRST_ROW = 5


def _sweep_table(ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    mech = t.mechanism
    angles = t.sweep.angles()
    columns = _sweep_columns(model, mech.input_column)
    letters = _sweep_place(t, model)[0]
    _text(ws, "A1", f"{t.title}: one row per {mech.input_symbol}", TITLE)
    _text(ws, "A2", f"Formulas read the named inputs on sheet Mechanism; #N/A marks "
                    f"{mech.input_word}s where the loop cannot close.", NOTE)
    head_row, first = 4, SWEEP_FIRST_ROW
    formulas: dict[str, str] = {}
    resolve = Resolver(model, names, {k: f"{letters[k]}{ROW}" for k, _ in columns})
    for i, (key, q) in enumerate(columns, start=1):
        ws.column_dimensions[letters[key]].width = 12
        if q is None:
            _text(ws, f"{letters[key]}3", f"input {mech.input_word}", NOTE)
            ws[f"{letters[key]}3"].alignment = Alignment(wrap_text=True, vertical="top")
            _head(ws, head_row, i, header(mech.input_symbol, mech.input_unit, t.length_unit))
            continue
        degree_column = key.endswith("_deg") and key != q.key
        unit = DEG if degree_column else q.unit
        _text(ws, f"{letters[key]}3", q.label, NOTE)
        ws[f"{letters[key]}3"].alignment = Alignment(wrap_text=True, vertical="top")
        _head(ws, head_row, i, header(q.symbol, unit, t.length_unit))
        if degree_column:
            formulas[key] = _degree_formula(q, f"{letters[q.key]}{ROW}")
        else:
            formulas[key] = resolve.formula(key)
    formats = {key: number_format(DEG if key.endswith("_deg") else q.unit, t.length_unit)
               for key, q in columns if q is not None}
    columns_at = {key: column_index_from_string(letters[key]) for key in formulas}
    angle_style = table_style(ws, "0.0##")
    styles = {key: table_style(ws, formats[key]) for key in formulas}
    for r, angle in enumerate(angles, start=first):
        put(ws, r, 1, angle, angle_style)
        row_text = str(r)
        for key, text in formulas.items():
            put(ws, r, columns_at[key], Formula(text.replace(ROW, row_text)), styles[key])
    last = first + len(angles) - 1
    if model.closes:
        letters.update(_assembly_columns(ws, letters, model.closes, first, last, head_row,
                                         unit_text(mech.input_unit, t.length_unit),
                                         mech.input_word))
    _fit_labels(ws, 3, list(letters.values()), heads=head_row)
    ws.freeze_panes = ws.cell(first, 2)
    return {"sheet": SWEEP, "rows": [first, last], "columns": letters}


# ---------------------------------------------------------------- Motion sheet
def _motion_table(ws, t: Template, model: Model, names: dict, sweep: dict,
                  position: dict) -> dict:
    """Velocities and accelerations: row 5 at the current position (sheet Mechanism), then one
    row per Sweep row, reading that row's positions."""
    mech = t.mechanism
    qs = model.of_role(MOTION)
    letters = {q.key: get_column_letter(i) for i, q in enumerate(qs, start=2)}
    speed, accel = (model_name(names, s) for s in MOTION_SYMBOLS[mech.input_kind])
    _text(ws, "A1", f"{t.title}: velocities and accelerations", TITLE)
    _text(ws, "A2", f"The input moves at {speed} with acceleration {accel} (sheet Mechanism). "
                    f"Row 5: the current position; from row {5 + MOTION_OFFSET}: each row of "
                    f"sheet {SWEEP}. #N/A where the loop cannot close or at a dead centre.", NOTE)
    head_row, current, first = 4, 5, 5 + MOTION_OFFSET
    _head(ws, head_row, 1, header(mech.input_symbol, mech.input_unit, t.length_unit))
    ws.column_dimensions["A"].width = 12
    for i, q in enumerate(qs, start=2):
        letter = letters[q.key]
        ws.column_dimensions[letter].width = 12
        _text(ws, f"{letter}3", q.label, NOTE)
        ws[f"{letter}3"].alignment = Alignment(wrap_text=True, vertical="top")
        _head(ws, head_row, i, header(q.symbol, q.unit, t.length_unit))
    _fit_labels(ws, 3, ["A"] + [letters[q.key] for q in qs], heads=head_row)
    own = {k: f"{v}{ROW}" for k, v in letters.items()}
    src = quote_sheetname(SWEEP)
    in_sweep = {k: f"{src}!{v}{SWEEP_ROW}" for k, v in sweep["columns"].items()}
    at_sweep = Resolver(model, names, {**in_sweep, **own})
    pos = quote_sheetname(MECH)
    in_position = {k: f"{pos}!{v}" for k, v in position["cells"].items()}
    in_position[mech.input_column] = position["input_name"]
    at_current = Resolver(model, names, {**in_position, **own})
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
    return {"sheet": MOTION_SHEET, "rows": [r0 + MOTION_OFFSET, r1 + MOTION_OFFSET],
            "current_row": current, "columns": letters}


def model_name(names: dict, symbol: str) -> str:
    return names.get(symbol, symbol)


def _position_motion(ws, t: Template, model: Model, position: dict, motion: dict) -> None:
    """Under the current position: the traced point's velocity and acceleration, from row 5
    of the Motion sheet."""
    if not model.path:
        return
    keys = [k for k in motion["columns"] if k.startswith(("vmag_", "amag_"))]
    name = keys[0].split("_", 1)[1]
    keys = [f"vx_{name}", f"vy_{name}", *keys]
    row = 8 + len(_sweep_columns(model, t.mechanism.input_column)) - 1
    src = quote_sheetname(MOTION_SHEET)
    by_key = {q.key: q for q in model.quantities}
    cells = {}
    for key in keys:
        q = by_key[key]
        _text(ws, f"G{row}", q.label)
        _text(ws, f"H{row}", q.symbol)
        c = ws[f"I{row}"]
        set_formula(c, f"={src}!{motion['columns'][key]}{motion['current_row']}")
        c.number_format = number_format(q.unit, t.length_unit)
        _text(ws, f"J{row}", unit_text(q.unit, t.length_unit))
        cells[key] = f"I{row}"
        row += 1
    position["motion_cells"] = cells


ASSEMBLY_COLUMNS = 3     # closes, gap from, gap to: right of the sweep's own columns


def _assembly_columns(ws, letters: dict, witnesses: tuple[str, ...], first: int, last: int,
                      head_row: int, unit: str, word: str) -> dict:
    """Bookkeeping for the summary: does the row close (1/0), and where do gaps start and end."""
    col = len(letters) + 1
    closes, start, end = (get_column_letter(col + i) for i in range(ASSEMBLY_COLUMNS))
    for i, (text, label) in enumerate((("closes [1/0]", "1 where every loop closes"),
                                       (f"gap from [{unit}]", f"first {word} of a gap"),
                                       (f"gap to [{unit}]", f"last {word} of a gap"))):
        _head(ws, head_row, col + i, text)
        _text(ws, f"{get_column_letter(col + i)}3", label, NOTE)
        ws.column_dimensions[get_column_letter(col + i)].width = 11
    for r in range(first, last + 1):
        every = "*".join(f"ISNUMBER({letters[w]}{r})" for w in witnesses)
        put(ws, r, col, Formula(f"=IF({every},1,0)"))
        # (x=0)*(y=1) rather than AND(): the same truth in every application, and element-wise
        # for the vector engine (AND aggregates, so it would run row by row).
        before = f"{closes}{r}=0" if r == first else f"({closes}{r}=0)*({closes}{r - 1}=1)"
        after = f"{closes}{r}=0" if r == last else f"({closes}{r}=0)*({closes}{r + 1}=1)"
        put(ws, r, col + 1, Formula(f'=IF({before},A{r},"{DASH}")'))
        put(ws, r, col + 2, Formula(f'=IF({after},A{r},"{DASH}")'))
    return {"closes": closes, "gap_from": start, "gap_to": end}


def numbers_only(ws, col: int, head_row: int, sources: list[str | None], head: str,
                 number_format: str) -> str:
    """A column, from row head_row + 1 on, that holds each source cell's number, or a dash
    where the source holds #N/A (the loop cannot close) or nothing (None). MIN, MAX and COUNT
    skip text in a range in every spreadsheet application, so the smallest and largest values
    of a column with #N/A in it are read from such a column. (AGGREGATE would skip the errors
    itself, but it is Excel 2010's: Gnumeric and IronCalc show #NAME?.) Returns its letter."""
    letter = get_column_letter(col)
    _head(ws, head_row, col, head)
    style = table_style(ws, number_format)
    for r, src in enumerate(sources, start=head_row + 1):
        value = f'=IF(ISNUMBER({src}),{src},"{DASH}")' if src else f'="{DASH}"'
        put(ws, r, col, Formula(value), style)
    return letter


def column_range(sheet: str, letter: str, first: int, last: int) -> str:
    return f"{quote_sheetname(sheet)}!${letter}${first}:${letter}${last}"


def _numbers_keys(model: Model) -> list[str]:
    """The sweep columns whose smallest and largest values a formula reads, in the order their
    numbers-only copies stand beside the sweep table: each slider's travel (its guide's ends),
    then the summary's output and transmission angles."""
    keys = [g.travel for g in model.guides]
    if model.closes:
        if model.output:
            q = model.get(model.output)
            keys.append(f"{q.key}_deg" if q.unit == RAD else q.key)
        keys += model.transmissions
    return list(dict.fromkeys(keys))


def _numbers_place(t: Template, model: Model) -> tuple[dict[str, str], int, int]:
    """The column letter of each numbers-only copy (_numbers_keys) right of the sweep table,
    and the sweep's first and last row: known before the sweep is laid out, so the drawing's
    guides can read them."""
    letters, first, last = _sweep_place(t, model)
    start = len(letters) + 1 + (ASSEMBLY_COLUMNS if model.closes else 0)
    return ({key: get_column_letter(start + i) for i, key in enumerate(_numbers_keys(model))},
            first, last)


def sweep_numbers_only(ws_sweep, t: Template, model: Model, sweep: dict) -> list[dict]:
    """Every numbers-only copy beside the sweep table (_numbers_place), each with a note over
    it; their records for the build record's numbers_only."""
    cols, (r0, r1) = sweep["columns"], sweep["rows"]
    records = []
    for key, letter in _numbers_place(t, model)[0].items():
        q = replace(model.get(key[:-4]), unit=DEG) if key.endswith("_deg") else model.get(key)
        ws_sweep.column_dimensions[letter].width = 12
        _text(ws_sweep, f"{letter}3", f"{q.symbol}'s numbers, {DASH} at #N/A: MIN and MAX "
                                      "read these", NOTE)
        ws_sweep[f"{letter}3"].alignment = Alignment(wrap_text=True, vertical="top")
        numbers_only(ws_sweep, column_index_from_string(letter), r0 - 1,
                     [f"{cols[key]}{r}" for r in range(r0, r1 + 1)],
                     f"{q.symbol} numbers [{unit_text(q.unit, t.length_unit)}]",
                     number_format(q.unit, t.length_unit))
        records.append({"sheet": SWEEP, "column": letter, "rows": [r0, r1], "sweep": key})
    if records:
        _fit_labels(ws_sweep, 3, [get_column_letter(c) for c in range(1, ws_sweep.max_column + 1)],
                    heads=r0 - 1)
    return records


def _summary_block(ws, t: Template, model: Model, names: dict, sweep: dict, row: int) -> dict:
    """Geometry honesty, as live formulas: where the mechanism assembles, its swing, the range
    of every transmission angle, and for every four-bar loop on the ground its Grashof class and
    the input's limit angles. Ranges are read from the numbers-only copies beside the sweep
    table (sweep_numbers_only)."""
    if not model.closes:
        return {}
    cols, (r0, r1) = sweep["columns"], sweep["rows"]
    src = quote_sheetname(SWEEP)

    def rng(key: str) -> str:
        return f"{src}!${cols[key]}${r0}:${cols[key]}${r1}"

    ws[f"A{row}"] = f"Geometry summary (over the {t.mechanism.input_symbol} sweep on sheet {SWEEP})"
    ws[f"A{row}"].font = BOLD
    row += 1
    cells: dict[str, dict] = {}

    def add(key: str, label: str, formula: str, unit: str = "", kind: str = "number") -> str:
        nonlocal row
        _text(ws, f"A{row}", label)
        _wrap_across(ws, row, "A", "B", label)
        c = set_formula(ws[f"C{row}"], formula)
        c.fill = DERIVED_FILL
        c.number_format = number_format(unit, t.length_unit) if unit else "General"
        # a text value (a Grashof class) reads on into the empty cells to its right
        c.alignment = Alignment(horizontal="left" if kind == "text" else "right")
        if unit:
            _text(ws, f"D{row}", unit_text(unit, t.length_unit))
        cells[key] = {"cell": f"C{row}", "kind": kind, "unit": unit}
        row += 1
        return f"$C${row - 1}"

    w = rng("closes")
    word = t.mechanism.input_word
    add("assembles_all", f"assembles at every {word} of the sweep",
        f'=IF(SUM({w})=ROWS({w}),"yes","no")', kind="text")
    add("not_closing", f"{word}s where the loop cannot close", f"=ROWS({w})-SUM({w})")
    first_failing = f'"{DASH}"'
    for key, (_, name) in reversed(list(zip(model.closes, model.loop_steps))):
        first_failing = f'IF(COUNT({rng(key)})<ROWS({rng(key)}),"{name}",{first_failing})'
    add("failing_step", "first loop step that cannot close", "=" + first_failing, kind="text")
    for k in range(1, GAPS_SHOWN + 1):
        add(f"gap{k}_from", f"gap {k}: cannot close from",
            f'=IFERROR(SMALL({rng("gap_from")},{k}),"{DASH}")', t.mechanism.input_unit,
            "number_or_dash")
        add(f"gap{k}_to", f"gap {k}: … to", f'=IFERROR(SMALL({rng("gap_to")},{k}),"{DASH}")',
            t.mechanism.input_unit, "number_or_dash")

    copies = _numbers_place(t, model)[0]

    def numbers_of(key: str) -> str:
        """The range of the numbers-only copy of sweep column `key` (sweep_numbers_only)."""
        return column_range(SWEEP, copies[key], r0, r1)

    def extremes(prefix: str, what: str, key: str, unit: str, convert: str = "") -> list[str]:
        column = numbers_of(key)
        cells = []
        for suffix, fn, word in (("min", "MIN", "smallest"), ("max", "MAX", "largest")):
            value = f"{fn}({column})"
            value = f"{convert}({value})" if convert else value
            cells.append(add(f"{prefix}_{suffix}", f"{word} {what}",
                             f'=IF(COUNT({column})=0,"{DASH}",{value})', unit, "number_or_dash"))
        return cells

    if model.output:
        q = model.get(model.output)
        if q.unit == RAD:
            # an angle (a rocker's): its degree view, whose window keeps the swing in one piece
            low, high = extremes("output", f"{q.symbol} ({q.label})", f"{q.key}_deg", DEG)
            add("output_swing", f"swing of {q.symbol} (largest − smallest)",
                f'=IF(ISNUMBER({low}),{high}-{low},"{DASH}")', DEG, "number_or_dash")
        else:
            extremes("output", f"{q.symbol} ({q.label})", model.output, q.unit)
    for i, key in enumerate(model.transmissions, start=1):
        # read in radians: a degree view's window moves with the data, μ lies in [0, π]
        extremes(summary_prefix("mu", i), f"transmission angle {model.get(key).symbol}",
                 key, DEG, convert="DEGREES")
    for i, loop in enumerate(model.fourbars, start=1):
        _fourbar_summary(add, loop, summary_prefix("", i), Resolver(model, names, {}))
    return cells


def _top_align_tall_rows(ws) -> None:
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


def _wrap_in(ws, cell: str) -> None:
    """A label longer than its column: wrapped there, its row tall enough for every line."""
    letter = cell.rstrip("0123456789")
    lines = label_lines(str(ws[cell].value), ws.column_dimensions[letter].width or 8.43)
    if len(lines) < 2:
        return
    ws[cell].alignment = Alignment(wrap_text=True, vertical="top")
    row = ws[cell].row
    ws.row_dimensions[row].height = max(ws.row_dimensions[row].height or LINE_HEIGHT,
                                        LINE_HEIGHT * len(lines))


def _wrap_across(ws, row: int, first: str, last: str, text: str) -> None:
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


def _fourbar_summary(add, fb, n: str, resolve) -> None:
    what = f"four-bar loop {fb.name}"
    g = add(f"fb{n}_ground", f"{what}: ground link", "=" + render(fb.ground, resolve), LENGTH)
    c = add(f"fb{n}_crank", f"{what}: input crank", "=" + render(fb.crank, resolve), LENGTH)
    k = add(f"fb{n}_coupler", f"{what}: coupler", "=" + render(fb.coupler, resolve), LENGTH)
    r = add(f"fb{n}_rocker", f"{what}: output link", "=" + render(fb.rocker, resolve), LENGTH)
    links = f"{g},{c},{k},{r}"
    shortest, longest = f"MIN({links})", f"MAX({links})"
    others = f"({g}+{c}+{k}+{r}-{shortest}-{longest})"
    add(f"grashof{n}", f"{what}: Grashof class",
        f'=IF({shortest}+{longest}>{others}*(1+1E-12),"non-Grashof: triple rocker",'
        f'IF({shortest}+{longest}>={others}*(1-1E-12),"change point",'
        f'IF({shortest}={g},"Grashof: double crank",IF({shortest}={c},"Grashof: crank-rocker",'
        f'IF({shortest}={k},"Grashof: double rocker","Grashof: rocker-crank")))))', kind="text")
    ground_angle = render(fb.ground_angle, resolve)
    for name, length in (("stretched", f"({k}+{r})"), ("folded", f"ABS({k}-{r})")):
        cosine = f"({g}^2+{c}^2-{length}^2)/(2*{g}*{c})"
        lo = f"MOD(DEGREES({ground_angle}-ACOS({cosine})),360)"
        hi = f"MOD(DEGREES({ground_angle}+ACOS({cosine})),360)"
        # the cosine's domain tested, not ACOS's error caught (IronCalc's ACOS(2) is a NaN
        # that IFERROR lets through);
        # IFERROR: a length edited to 0 divides by zero, and there is no limit angle either
        none = outside_domain("ACOS", cosine)
        add(f"limit{n}_{name}_1", f"{what}: input limit angle, coupler and output link {name}",
            f'=IFERROR(IF({none},"none",MIN({lo},{hi})),"none")', DEG, "number_or_none")
        add(f"limit{n}_{name}_2", "… and the other one",
            f'=IFERROR(IF({none},"none",MAX({lo},{hi})),"none")', DEG, "number_or_none")


# ---------------------------------------------------------------- grid (pump)
def _grid_sheet(ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The textbook's copyable grid: one self-contained formula per cell, mixed references."""
    param, out = t.mechanism.grid
    q_out = model.get(out)
    _text(ws, "A1", f"{t.title}: {q_out.symbol} for every {t.mechanism.input_symbol} and "
                    f"{param}", TITLE)
    _text(ws, "A2", f"Each cell is one formula reading its row's {t.mechanism.input_symbol} "
                    f"($A) and its column's {param} (row 5), like the textbook's "
                    "=AdjustablePump(…; B$5; $A6). No macros.", NOTE)
    head_row, first = 5, 6
    angles = t.sweep.angles()
    _head(ws, head_row - 1, 1, "")
    _corner_head(ws, head_row, f"{t.mechanism.input_symbol} [deg] / {param} [{t.length_unit}]")
    cols = []
    for j, value in enumerate(t.grid_values, start=2):
        letter = get_column_letter(j)
        ws.column_dimensions[letter].width = 12
        _head(ws, head_row - 1, j, header(q_out.symbol, LENGTH, t.length_unit))
        c = ws.cell(head_row, j, value)
        c.fill = INPUT_FILL
        c.font = BOLD
        c.border = BOX
        cols.append(letter)
    for i, angle in enumerate(angles, start=first):
        ws.cell(i, 1, angle).number_format = "0.0##"
    _fill_grid(ws, t, model, names, head_row, range(first, first + len(angles)), cols)
    return {"sheet": GRID, "param": param, "key": out, "param_row": head_row,
            "rows": [first, first + len(angles) - 1], "columns": cols}


def _corner_head(ws, row: int, text: str) -> None:
    """A grid's corner header in A: its lines (bold: a tenth wider) each get room in the row,
    so that none crosses the row's border."""
    ws.column_dimensions["A"].width = GRID_CORNER_WIDTH
    _head(ws, row, 1, text)
    ws.row_dimensions[row].height = LINE_HEIGHT * len(label_lines(text, GRID_CORNER_WIDTH / 1.1))


GRID_CORNER_WIDTH = 16     # also the bold `stroke [mm]` under the grid


def _fill_grid(ws, t: Template, model: Model, names: dict, param_row: int, rows: range,
               cols: list[str]) -> None:
    """One self-contained formula per cell: the row's angle in $A, the column's value in
    `param_row`; the same text with the row and column put in."""
    param, out = t.mechanism.grid
    text = _grid_formula(model, names, t.mechanism.input_column, param, out, param_row)
    style = table_style(ws, number_format(LENGTH, t.length_unit))
    at = {letter: column_index_from_string(letter) for letter in cols}
    for i in rows:
        for letter in cols:
            put(ws, i, at[letter], Formula(text.replace(COL, letter).replace(ROW, str(i))),
                style)
    ws.freeze_panes = ws.cell(rows.start, 2)


EXCEL_FORMULA_CHARS, EXCEL_NESTING = 8192, 64


def _grid_formula(model, names, input_column, param, out, param_row) -> str:
    """The self-contained grid formula, refused (before any file is written) where Excel could
    not open it: over 8,192 characters or 64 levels of nested functions."""
    from ..language.templates import InputError
    cells = {input_column: f"$A{ROW}", param: f"{COL}${param_row}"}
    text = Resolver(model, names, cells).formula(out)
    depth = deepest = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        deepest = max(deepest, depth)
    # The cell's own text is a little longer (row and column put in): keep a margin.
    if len(text) > EXCEL_FORMULA_CHARS - 200 or deepest > EXCEL_NESTING:
        raise InputError("grid.output", f"the self-contained formula of {out} in each grid cell "
                                        f"would have {len(text):,} characters and {deepest} "
                                        f"nested parentheses; Excel allows "
                                        f"{EXCEL_FORMULA_CHARS:,} and {EXCEL_NESTING}: grid an "
                                        "earlier column, or leave out the [grid]")
    return text


def _stroke_sheet(ws, t: Template, model: Model, names: dict[str, str], grid: dict) -> dict:
    """A fine sweep of the same grid formula, so that max − min finds the real stroke."""
    param, out = t.mechanism.grid
    step = t.stroke_step
    count = int(round(360 / step)) + 1
    _text(ws, "A1", f"Fine sweep of {out} every {step:g}° for the stroke", TITLE)
    _text(ws, "A2", f"The stroke (max − min over a turn) is under the grid on sheet {GRID}.",
          NOTE)
    head_row, first = 4, 5
    _corner_head(ws, head_row, f"{t.mechanism.input_symbol} [deg] / {param} [{t.length_unit}]")
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
    _fill_grid(ws, t, model, names, head_row, range(first, first + count), cols)
    return {"sheet": STROKE, "param_row": head_row, "rows": [first, first + count - 1],
            "columns": cols}


def grid_is_fine(t: Template) -> bool:
    s = t.sweep
    return s.step <= t.stroke_step and s.start <= 0 and s.stop >= 360


def _stroke_row(ws, t: Template, grid: dict, stroke: dict) -> int:
    """Under the grid: max − min of the fine sweep (or of the grid itself), per column."""
    row = grid["rows"][1] + 2
    _text(ws, f"A{row}", f"stroke [{t.length_unit}]", BOLD)
    first, last = stroke["rows"]
    src = "" if stroke is grid else f"{quote_sheetname(stroke['sheet'])}!"
    for mine, theirs in zip(grid["columns"], stroke["columns"]):
        rng = f"{src}{theirs}{first}:{theirs}{last}"
        c = set_formula(ws[f"{mine}{row}"], f"=MAX({rng})-MIN({rng})")
        c.number_format = number_format(LENGTH, t.length_unit)
        c.font = BOLD
        c.fill = DERIVED_FILL
    source = "the grid above" if stroke is grid else f"the {t.stroke_step:g}° sweep on sheet {STROKE}"
    # under the values, not in column A: a continuation page repeats column A, and would cut
    # the note at its edge
    _text(ws, f"B{row + 1}", f"max − min of {source}", NOTE)
    return row
