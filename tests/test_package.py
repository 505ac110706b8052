"""The cells `package.cells_held_back` writes in place of openpyxl's writer: the same package,
part for part and byte for byte, as openpyxl's own save followed by the same `finish` — openpyxl
is the oracle here, on sheets with every kind of cell linkbook writes and on random ones."""
from __future__ import annotations

import math
import zipfile
from decimal import Decimal
from pathlib import Path

import numpy as np
import openpyxl
import pytest
from conftest import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from openpyxl.comments import Comment
from openpyxl.styles import Alignment, Font, PatternFill

from linkbook.book import package
from linkbook.book import style, workbook


def _parts(path: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as z:
        return {n: z.read(n) for n in z.namelist() if n != "docProps/core.xml"}  # a timestamp


def _both_ways(tmp_path: Path, make) -> tuple[dict, dict]:
    """The package of `make()`'s book saved by openpyxl and finished, and saved with its cells
    held back and finished with them. Each gets a book of its own (writing styles numbers them)."""
    plain, held = tmp_path / "plain.xlsx", tmp_path / "held.xlsx"
    make().save(plain)
    package.finish(plain, plain)
    wb = make()
    with package.cells_held_back(wb) as cells:
        wb.save(held)
    package.finish(held, held, cells=cells)
    return _parts(plain), _parts(held)


def _every_kind() -> openpyxl.Workbook:
    wb = openpyxl.Workbook()
    ws = wb.active
    ws["A1"] = "θ13 [deg]"
    ws["A1"].font = Font(bold=True)
    ws["B1"] = "  leading and trailing  "
    ws["C1"] = "a & b < c > d\r\nline"
    ws["D1"] = ""
    ws["E1"] = "plain"
    ws["F1"] = "plain"
    ws["A2"] = 0.1 + 0.2
    ws["B2"] = -1e-300
    ws["C2"] = 12345678901234567
    ws["D2"] = True
    ws["E2"] = False
    ws["F2"] = math.nan
    ws["G2"] = math.inf
    ws["H2"] = "#N/A"
    ws["H2"].data_type = "e"
    ws["I2"] = np.float32(0.1)                         # numbers of other types: openpyxl's
    ws["J2"] = np.int64(2**60)                         # %.16g, as for floats
    ws["K2"] = np.bool_(True)
    ws["L2"] = Decimal("0.1000000000000000055511151231257827")
    ws["M2"] = -0.0
    style.set_formula(ws["A3"], '=IF(B3<>"–",A2&"<x>",NA())')
    ws["A3"].number_format = "0.000"
    style.set_formula(ws["B3"], "=SUM(A2:C2)")
    ws["B3"].fill = PatternFill("solid", fgColor="FFFF00")
    ws["C4"].alignment = Alignment(wrap_text=True)     # styled, no value
    ws["D4"]                                           # neither: not written
    ws.row_dimensions[2].height = 30
    ws.row_dimensions[7].height = 45                   # a row with no cells
    ws.merge_cells("A9:C9")
    ws["A9"] = "merged"
    second = wb.create_sheet("Sweep θ")
    style.set_formula(second["B5"], "=Sheet!A2*2")
    wb.create_sheet("Empty")
    return wb


def test_every_kind_of_cell_as_openpyxl_writes_it(tmp_path):
    plain, held = _both_ways(tmp_path, _every_kind)
    assert plain.keys() == held.keys()
    for name in plain:
        assert held[name] == plain[name], name


def test_a_bundled_book_as_openpyxl_writes_it(tmp_path):
    """The whole fourbar book: every sheet, chart anchor, control and style."""
    from conftest import template

    def make():
        built = workbook.build(template("fourbar"))
        return built.workbook

    plain, held = _both_ways(tmp_path, make)
    assert plain == held


_TEXT = st.text(st.characters(blacklist_categories=("Cs", "Cc")) | st.sampled_from("\r\n\t &<>"),
                max_size=12)
_VALUE = st.one_of(st.none(), st.booleans(), st.integers(-10**17, 10**17),
                   st.floats(allow_nan=True, allow_infinity=True), _TEXT,
                   _TEXT.map(lambda t: package.Formula("=" + repr(t).replace("'", '"'))))


@settings(max_examples=examples(150), derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cells=st.dictionaries(st.tuples(st.integers(1, 40), st.integers(1, 30)),
                             st.tuples(_VALUE, st.sampled_from(["", "0.00", "0.0##"])),
                             max_size=40),
       heights=st.dictionaries(st.integers(1, 50), st.sampled_from([15, 30.5, 45]), max_size=4))
def test_random_sheets_as_openpyxl_writes_them(tmp_path, cells, heights):
    def make():
        wb = openpyxl.Workbook()
        ws = wb.active
        for (row, col), (value, fmt) in cells.items():
            c = ws.cell(row, col)
            if isinstance(value, package.Formula):
                style.set_formula(c, value)
            else:
                c.value = value
                if isinstance(value, str):
                    c.data_type = "s"       # text is text (openpyxl's guess aside)
            if fmt:
                c.number_format = fmt
        for row, height in heights.items():
            ws.row_dimensions[row].height = height
        return wb

    plain, held = _both_ways(tmp_path, make)
    assert plain == held


def test_table_cells_are_openpyxl_cells(tmp_path):
    """style.put makes the cell openpyxl's cell() would: same type, value and style."""
    wb = openpyxl.Workbook()
    ws = wb.active
    three_decimals = style.table_style(ws, "0.000")
    style.put(ws, 3, 2, package.Formula("=A1*2"), three_decimals)
    style.put(ws, 4, 2, 1.5, three_decimals)
    style.put(ws, 5, 2, package.Formula("=A1"))
    for row, value, fmt in ((3, "=A1*2", "0.000"), (4, 1.5, "0.000"), (5, "=A1", "General")):
        made = ws.cell(row, 2)
        expected = openpyxl.Workbook().active.cell(row, 2, value)
        assert (made.value, made.data_type, made.number_format) == \
            (expected.value, expected.data_type, fmt)


def test_text_is_never_a_formula(tmp_path):
    """Text that openpyxl's setter takes for a formula (it starts with '='), or that put() is
    given, is written as a string cell: only a package.Formula is a formula."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws["A1"] = '=HYPERLINK("http://example.com","click")'
    style.put(ws, 2, 1, "=1+1")
    style.put(ws, 3, 1, "#N/A")
    style.put(ws, 4, 1, package.Formula("=1+1"))
    assert [ws.cell(r, 1).data_type for r in (2, 3, 4)] == ["s", "s", "f"]
    path = tmp_path / "text.xlsx"
    with package.cells_held_back(wb) as cells:
        wb.save(path)
    package.finish(path, path, cells=cells)
    with zipfile.ZipFile(path) as z:
        sheet = z.read("xl/worksheets/sheet1.xml").decode()
    assert sheet.count("<f>") == 1 and "<f>1+1</f>" in sheet
    back = openpyxl.load_workbook(path).active
    assert [(back.cell(r, 1).value, back.cell(r, 1).data_type) for r in (1, 2, 3)] == [
        ('=HYPERLINK("http://example.com","click")', "s"), ("=1+1", "s"), ("#N/A", "s")]


def _commented(cell, value):
    cell.value = value
    cell.comment = Comment("a comment", "me")


def _linked(cell, value):
    cell.hyperlink = "https://example.org"
    cell.value = value


@pytest.mark.parametrize("attach,value", [(_commented, "noted"), (_commented, "=A1"),
                                          (_linked, None)],
                         ids=["comment on text", "comment on a formula", "link, empty cell"])
def test_comments_and_hyperlinks_are_refused(attach, value):
    wb = openpyxl.Workbook()
    attach(wb.active["C3"], value)
    with pytest.raises(ValueError, match="Sheet!C3: comments and hyperlinks"):
        with package.cells_held_back(wb):
            pass


def test_sheets_with_tables_are_refused():
    from openpyxl.worksheet.table import Table
    wb = openpyxl.Workbook()
    wb.active["A1"], wb.active["B1"], wb.active["A2"] = "x", "y", 1
    wb.active.add_table(Table(displayName="T", ref="A1:B2"))
    with pytest.raises(ValueError, match="Sheet: sheets with tables"):
        with package.cells_held_back(wb):
            pass


@pytest.mark.parametrize("value,code", [('=A1&"\x07"', "0007"), ('=A1&"\uffff"', "FFFF"),
                                        ("text \ufffe", "FFFE"), ("bytes \udcff", "DCFF")])
def test_characters_no_workbook_can_hold_are_refused(value, code):
    """openpyxl refuses them (when the cell is set, or at save); put() does not look, so the
    writer must, or the part would not parse."""
    wb = openpyxl.Workbook()
    if value.startswith("="):
        style.put(wb.active, 2, 3, package.Formula(value))
    else:                       # text set past openpyxl's own check, as put() sets formulas
        cell = wb.active.cell(2, 3)
        cell._value, cell.data_type = value, "s"
    with pytest.raises(ValueError, match=f"Sheet!C2: the character U\\+{code} cannot"):
        with package.cells_held_back(wb):
            pass
