"""The fast read-only view (linkbook.base.xlsx) against openpyxl's own load of the same files, and
its refusals: a book it does not model is read by openpyxl instead."""
from __future__ import annotations

import datetime
import re
import shutil
import zipfile
from pathlib import Path

import openpyxl
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from openpyxl.workbook.defined_name import DefinedName

from conftest import built, examples
from linkbook.base import safety
from linkbook.base import xlsx
from test_engine import build_book, edge_book


def cells(wb) -> dict:
    return {(ws.title, c.coordinate): (c.value, type(c.value), c.data_type)
            for ws in wb.worksheets for c in ws._cells.values() if c.value is not None}


def names(wb) -> dict:
    return {k: (v.attr_text, bool(v.hidden)) for k, v in wb.defined_names.items()}


def assert_same_as_openpyxl(path: Path) -> None:
    view, full = xlsx.read(path), openpyxl.load_workbook(path)
    assert view.sheetnames == full.sheetnames
    assert cells(view) == cells(full)
    assert names(view) == names(full)
    for ws in full.worksheets:
        mine = view[ws.title]
        for c in list(ws._cells.values())[:50]:
            assert mine[c.coordinate].value == c.value
            assert mine.cell(c.row, c.column).value == c.value
        assert mine.max_row <= ws.max_row and mine.max_column <= ws.max_column


def rich_book() -> openpyxl.Workbook:
    """Strings of every kind (shared, rich text, escapes, empty), a hidden name, big and small
    numbers, numbers written as ints and floats, booleans, error constants."""
    from openpyxl.cell.rich_text import CellRichText, TextBlock
    from openpyxl.cell.text import InlineFont
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "It's a sheet"
    values = ["plain", "x005F_x000D_ escaped", "line\nbreak", " spaced ", 1, 1.0, -0.0, 1e300,
              5e-324, 2 ** 62, True, False, "#DIV/0!", "=1/0", "=\"a\"&\"b\""]
    for i, v in enumerate(values, start=1):
        ws.cell(i, 2, v)
    ws["C1"] = CellRichText("bold ", TextBlock(InlineFont(b=True), "and plain"))
    ws["C2"].number_format = "0.000"
    ws["C3"] = 7
    ws["C3"].number_format = '0.0" mm/s"'          # letters of a date, but quoted
    wb.defined_names["hidden_one"] = DefinedName("hidden_one", attr_text="'It''s a sheet'!$B$5",
                                                 hidden=True)
    return wb


def with_shared_strings(path: Path) -> None:
    """Rewrite openpyxl's inline strings as a shared-string table, as Excel and LibreOffice
    save them."""
    table: list[str] = []

    def shared(m: re.Match) -> str:
        table.append(f"<si>{m[2]}</si>")
        return f'<c {m[1]} t="s"><v>{len(table) - 1}</v></c>'
    tmp = path.with_suffix(".tmp")
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w") as dst:
        for info in src.infolist():
            data = src.read(info).decode()
            if info.filename.startswith("xl/worksheets/sheet"):
                data = re.sub(r'<c ([^>]*?) t="inlineStr"><is>(.*?)</is></c>', shared, data,
                              flags=re.S)
            elif info.filename == "xl/_rels/workbook.xml.rels":
                data = data.replace("</Relationships>", (
                    '<Relationship Id="rIdSST" Target="sharedStrings.xml" Type="http://schemas.'
                    'openxmlformats.org/officeDocument/2006/relationships/sharedStrings"/>'
                    "</Relationships>"))
            elif info.filename == "[Content_Types].xml":
                data = data.replace("</Types>", (
                    '<Override PartName="/xl/sharedStrings.xml" ContentType="application/vnd.'
                    'openxmlformats-officedocument.spreadsheetml.sharedStrings+xml"/></Types>'))
            dst.writestr(info, data)
        dst.writestr("xl/sharedStrings.xml", (
            '<sst xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
            + "".join(table) + "</sst>"))
    shutil.move(tmp, path)
    assert table


@pytest.mark.parametrize("shared", [False, True], ids=["inline strings", "shared strings"])
@pytest.mark.parametrize("make", [build_book, edge_book, rich_book])
def test_the_view_reads_what_openpyxl_reads(tmp_path, make, shared):
    path = tmp_path / "book.xlsx"
    make().save(path)
    if shared:
        with_shared_strings(path)
    assert_same_as_openpyxl(path)


@pytest.mark.parametrize("name", ["pump", "jansen"])
def test_the_view_reads_a_bundled_book_as_openpyxl_does(tmp_path, name):
    path = tmp_path / f"{name}.xlsx"
    built(name)[0].workbook.save(path)
    assert_same_as_openpyxl(path)


def _rewrite(path: Path, part: str, old: str, new: str) -> None:
    tmp = path.with_suffix(".tmp")
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == part:
                assert old.encode() in data
                data = data.replace(old.encode(), new.encode(), 1)
            dst.writestr(info, data)
    shutil.move(tmp, path)


def _date_book(path: Path) -> None:
    wb = openpyxl.Workbook()
    wb.active["A1"] = datetime.datetime(2026, 11, 23)
    wb.save(path)


def _shared_formula_book(path: Path) -> None:
    wb = openpyxl.Workbook()
    ws = wb.active
    ws["A1"], ws["A2"], ws["B1"], ws["B2"] = 1, 2, "=A1*2", "=A2*2"
    wb.save(path)
    _rewrite(path, "xl/worksheets/sheet1.xml", "<f>A1*2</f>", '<f t="shared" ref="B1:B2" si="0">A1*2</f>')
    _rewrite(path, "xl/worksheets/sheet1.xml", "<f>A2*2</f>", '<f t="shared" si="0"/>')


@pytest.mark.parametrize("make", [_date_book, _shared_formula_book])
def test_what_the_view_does_not_model_is_read_by_openpyxl(tmp_path, make):
    path = tmp_path / "book.xlsx"
    make(path)
    with pytest.raises(xlsx.Unsupported):
        xlsx.read(path)
    wb = safety.read_workbook_safely(path)
    assert isinstance(wb, openpyxl.Workbook)
    assert cells(wb) == cells(openpyxl.load_workbook(path))


# ---------------------------------------------------------------- what the application reads
# Each case is a bundled four-bar damaged as a hand edit or a hostile file would be: verify
# must read it as Excel and LibreOffice do, or refuse it with one line naming the part and the
# name or cell (exit 2), never say "all agree" about a book the application reads otherwise.
INPUT_A2 = ('<c r="C8" s="6" t="n"><v>35</v></c>', "xl/worksheets/sheet1.xml")   # a_2 = 35 mm
# every formula cell of the book compared, and all agree
ALL_AGREE = re.compile(r"all agree: (\d+) of \1 formula cells compared")
FIRST_NAME = "<definedName name=\"a_1\">'Mechanism'!$C$7</definedName>"


@pytest.fixture(scope="module")
def fourbar_bytes(coarse_fourbar) -> bytes:
    """The four-bar at a 30° step: every part and formula shape the reading tests edit, in
    fewer rows."""
    return coarse_fourbar.read_bytes()


def _damaged(tmp_path: Path, raw: bytes, part: str, old: str, new: str) -> Path:
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(raw)
    _rewrite(path, part, old, new)
    return path


def _verify(path: Path, capsys, *options) -> tuple[int, str]:
    from linkbook.apps.cli import main
    code = main(["verify", str(path), *options])
    out = capsys.readouterr()
    lines = (out.out + out.err).strip().splitlines()
    assert "Traceback" not in out.out + out.err
    return code, lines[-1]


def _scoped(name: str, target: str, sheet: int = 1) -> str:
    return f'<definedName name="{name}" localSheetId="{sheet}">{target}</definedName>'


@pytest.mark.parametrize("added", [
    _scoped("a_2", "'Mechanism'!$C$9"),                 # the Name Manager edit
    _scoped("A_2", "'Mechanism'!$C$9", sheet=2),        # names are compared without case
], ids=["a_2 on Sweep", "A_2 on Motion"])
def test_a_scoped_name_shadowing_an_input_is_refused(tmp_path, fourbar_bytes, capsys, added):
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", FIRST_NAME, FIRST_NAME + added)
    code, last = _verify(path, capsys)
    assert code == 2
    assert "xl/workbook.xml" in last and "shadows the workbook's 'a_2'" in last, last


@pytest.mark.parametrize("added", [
    _scoped("a_2", "'Mechanism'!$C$8"),                 # the same target: read the same
    _scoped("not_read", "'Mechanism'!$C$9"),           # no workbook name of that name
], ids=["same target", "another name"])
def test_a_scoped_name_that_changes_no_reading_is_accepted(tmp_path, fourbar_bytes, capsys,
                                                           added):
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", FIRST_NAME, FIRST_NAME + added)
    code, last = _verify(path, capsys)
    assert code == 0 and ALL_AGREE.match(last), last


@pytest.mark.parametrize("first", ["a_2", "A_2"])
def test_a_name_defined_twice_is_refused(tmp_path, fourbar_bytes, capsys, first):
    """Excel and LibreOffice read the first definition, openpyxl kept the last."""
    added = f"<definedName name=\"{first}\">'Mechanism'!$C$9</definedName>"
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", FIRST_NAME, added + FIRST_NAME)
    code, last = _verify(path, capsys)
    assert code == 2
    assert "xl/workbook.xml" in last and "is defined twice in the workbook" in last, last


SWEEP_TITLES = ("<definedName name=\"_xlnm.Print_Titles\" localSheetId=\"1\">"
                "'Sweep'!$3:$4,'Sweep'!$A:$A</definedName>")


@pytest.mark.parametrize("again", [
    "Sweep!$A:$A,Sweep!$3:$4",              # LibreOffice 7.4's save: the other order, unquoted
    "'Sweep'!$3:$4,'Sweep'!$A:$A",          # the same text
    "'SWEEP'!$a:$a,'Sweep'!$3:$4",          # case
], ids=["reordered", "repeated", "case"])
def test_a_built_in_name_repeated_with_the_same_ranges_is_accepted(tmp_path, fourbar_bytes,
                                                                   capsys, again):
    added = SWEEP_TITLES.replace("'Sweep'!$3:$4,'Sweep'!$A:$A", again)
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", SWEEP_TITLES,
                    SWEEP_TITLES + added)
    from linkbook.apps.cli import main
    code = main(["verify", str(path)])
    out = capsys.readouterr()
    assert code == 0 and ALL_AGREE.match(out.out.strip().splitlines()[-1]), out
    assert "warning" not in out.err and "Traceback" not in out.err


def test_a_built_in_name_repeated_with_other_ranges_is_a_warning(tmp_path, fourbar_bytes,
                                                                 capsys):
    """Print titles are the application's, not the numbers': verify judges the book and warns."""
    added = SWEEP_TITLES.replace("'Sweep'!$3:$4,'Sweep'!$A:$A", "Sweep!$3:$5")
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", SWEEP_TITLES,
                    SWEEP_TITLES + added)
    from linkbook.apps.cli import main
    for command in (["verify"], ["info"], ["export", "-o", str(tmp_path / "csv")]):
        code = main([command[0], str(path), *command[1:]])
        out = capsys.readouterr()
        assert code == 0, (command, out)
        warning = [line for line in out.err.splitlines() if line.startswith("linkbook: warning")]
        assert len(warning) == 1 and "'_xlnm.Print_Titles' is defined twice in sheet 'Sweep' " \
            "with other ranges" in warning[0], (command, out.err)
        if command == ["verify"]:
            assert ALL_AGREE.match(out.out.strip().splitlines()[-1]), out.out
    import json
    main(["verify", str(path), "--json"])
    data = json.loads(capsys.readouterr().out)[0]
    assert data["status"] == 0 and len(data["notes"]) == 1


# LibreOffice 7.4 reads '3_5' as 3, '３５' and '0x10' as 0, '35.0.0' as 35, and '1e999', 'INF'
# and 'NaN' as infinities no formula can use (recalculated and saved as CSV); Python's int()
# and float() read 35, 35, an error, an error, inf, inf and nan.
@pytest.mark.parametrize("stored", ["3_5", "３５", "0x10", "35.0.0", "1e999", "INF", "NaN",
                                    "3 5", "35mm", "1e", "+-35", "0" * 5000 + "35"])
def test_a_number_the_application_reads_otherwise_is_refused(tmp_path, fourbar_bytes, capsys,
                                                             stored):
    cell, part = INPUT_A2
    path = _damaged(tmp_path, fourbar_bytes, part, cell, cell.replace(">35<", f">{stored}<"))
    code, last = _verify(path, capsys)
    assert code == 2
    assert f"{part}: cell Mechanism!C8 holds {stored[:40]!r}" in last, last


def test_a_shared_string_the_table_lacks_is_refused(tmp_path, fourbar_bytes, capsys):
    cell, part = INPUT_A2
    path = _damaged(tmp_path, fourbar_bytes, part, cell,
                    cell.replace(' t="n"><v>35<', ' t="s"><v>99999<'))
    code, last = _verify(path, capsys)
    assert code == 2
    assert f"{part}: cell Mechanism!C8 names shared string 99999, and the table has" in last


# Every form of XML Schema's decimal and double: LibreOffice reads each as 35.
ACCEPTED_35 = [" 35", "35\t", "+35", "35.", "35.000", "3.5e1", "3.5E+1", "350e-1", "035"]


@pytest.mark.parametrize("stored", ACCEPTED_35)
def test_a_number_in_xml_schema_form_is_read(tmp_path, fourbar_bytes, capsys, stored):
    cell, part = INPUT_A2
    path = _damaged(tmp_path, fourbar_bytes, part, cell, cell.replace(">35<", f">{stored}<"))
    assert xlsx.read(path)["Mechanism"]["C8"].value == 35
    code, last = _verify(path, capsys)
    assert code == 0 and ALL_AGREE.match(last), last


# Edits verify accepts, each in the place it is made: (part, old text, new text).
ACCEPTED_EDITS = {
    "a_2 stored ' 35'": (INPUT_A2[1], INPUT_A2[0], INPUT_A2[0].replace(">35<", "> 35<")),
    "a_2 stored '3.5E+1'": (INPUT_A2[1], INPUT_A2[0], INPUT_A2[0].replace(">35<", ">3.5E+1<")),
    "a scoped a_2 to the same cell": ("xl/workbook.xml", FIRST_NAME,
                                      FIRST_NAME + _scoped("a_2", "'Mechanism'!$C$8")),
}


@pytest.mark.libreoffice
@pytest.mark.parametrize("edit", sorted(ACCEPTED_EDITS))
def test_libreoffice_reads_an_accepted_edit_as_verify_does(needs, tmp_path, fourbar_bytes, capsys,
                                                           edit):
    """The judge: LibreOffice recalculates with what it reads, and verify compares that with
    the reference computed from what verify read."""
    needs("libreoffice")
    path = _damaged(tmp_path, fourbar_bytes, *ACCEPTED_EDITS[edit])
    code, last = _verify(path, capsys, "--engine", "libreoffice")
    assert code == 0 and ALL_AGREE.match(last), last


@pytest.mark.libreoffice
def test_libreoffice_reads_the_scoped_name_verify_refuses(needs, tmp_path, fourbar_bytes, capsys):
    """Why the shadowing name is refused: the application's formulas on Sweep read a_3."""
    needs("libreoffice")
    added = _scoped("a_2", "'Mechanism'!$C$9")
    path = _damaged(tmp_path, fourbar_bytes, "xl/workbook.xml", FIRST_NAME, FIRST_NAME + added)
    from linkbook.engine import office
    clean = tmp_path / "clean.xlsx"
    clean.write_bytes(fourbar_bytes)
    before, after = office.recalculated_values(clean), office.recalculated_values(path)
    sweep = [k for k in before if k[0] == "Sweep" and isinstance(before[k], float)]
    assert sum(before[k] != after[k] for k in sweep) > 100


COMMENT = "<!-- " + "x" * 5000 + " -->"
DTD = '<!DOCTYPE worksheet [<!ENTITY a2 "35">]>'


@pytest.mark.parametrize("part,where", [
    ("xl/worksheets/sheet1.xml", "after a 5 KB comment"),
    ("xl/charts/chart1.xml", "after a 5 KB comment"),
    ("docProps/app.xml", "after a 5 KB comment"),
    ("xl/worksheets/sheet2.xml", "at the end"),
])
def test_a_dtd_anywhere_in_any_part_is_refused(tmp_path, fourbar_bytes, capsys, part, where):
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(fourbar_bytes)
    with zipfile.ZipFile(path) as zf:
        body = zf.read(part).decode()
    root = re.search(r"<[A-Za-z]", body.split("?>", 1)[-1]).group()
    if where == "at the end":
        _rewrite(path, part, body[-30:], body[-30:] + COMMENT + DTD)
    else:
        _rewrite(path, part, root, COMMENT + DTD + root)
    code, last = _verify(path, capsys)
    assert code == 2
    assert f"part {part} declares a DTD or XML entities; refusing" in last, last


def test_a_dtd_in_a_worksheet_part_no_sheet_names_is_refused(tmp_path, fourbar_bytes, capsys):
    """verify scans the worksheet parts as it reads them; a worksheet part the workbook does
    not list is read by no one, and is still scanned whole."""
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(fourbar_bytes)
    with zipfile.ZipFile(path, "a") as zf:
        zf.writestr("xl/worksheets/sheet99.xml", '<?xml version="1.0"?>' + DTD + "<worksheet/>")
    code, last = _verify(path, capsys)
    assert code == 2
    assert "part xl/worksheets/sheet99.xml declares a DTD or XML entities; refusing" in last, last


def test_no_worksheet_part_is_parsed_before_it_is_scanned_whole(tmp_path, fourbar_bytes,
                                                                monkeypatch):
    """A worksheet part the view reads element by element (here: a carriage return stops the
    scan at its first chunk, before a long comment) has been scanned for a DTD to its end
    before ElementTree parses any of it."""
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(fourbar_bytes)
    part = "xl/worksheets/sheet2.xml"
    long = "<!-- " + "x" * (2 * xlsx.SCAN_CHUNK) + " -->"
    _rewrite(path, part, "<worksheet ", "\r\n" + long + "<worksheet ")
    guards, parsed = {}, []

    class Recorded(safety.PartGuard):
        def __init__(self, name, where):
            super().__init__(name, where)
            guards.setdefault(name, []).append(self)
    real = xlsx._read_cells

    def read_cells(f, ws, strings, date_styles, name, unmodelled):
        parsed.append((name, any(g.whole for g in guards.get(name, []))))
        return real(f, ws, strings, date_styles, name, unmodelled)
    monkeypatch.setattr(safety, "PartGuard", Recorded)
    monkeypatch.setattr(xlsx, "_read_cells", read_cells)
    safety.read_workbook_safely(path)
    assert (part, True) in parsed and all(whole for _, whole in parsed), parsed


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_a_dtd_in_a_utf16_part_is_refused(tmp_path, fourbar_bytes, encoding):
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(fourbar_bytes)
    tmp = tmp_path / "out.xlsx"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "docProps/app.xml":
                data = ("\ufeff" + COMMENT + DTD + data.decode()).encode(encoding)
            dst.writestr(info, data)
    with pytest.raises(safety.UnsafeFile, match="part docProps/app.xml declares a DTD"):
        safety.check_zip(tmp)


def test_a_dtd_split_between_two_chunks_is_found(tmp_path, fourbar_bytes):
    """The scan reads a part a chunk at a time: a marker across the boundary is still seen."""
    for cut in range(1, len("<!DOCTYPE")):
        path = tmp_path / f"cut{cut}.xlsx"
        path.write_bytes(fourbar_bytes)
        padding = "x" * (safety._CHUNK - cut - len("<!--  -->"))
        _rewrite(path, "docProps/app.xml", "<", f"<!-- {padding} --><!DOCTYPE Properties><")
        with zipfile.ZipFile(path) as zf:
            assert zf.read("docProps/app.xml").index(b"<!DOCTYPE") == safety._CHUNK - cut
        with pytest.raises(safety.UnsafeFile, match="declares a DTD"):
            safety.check_zip(path)


def _formula_book(path: Path, formula: str) -> Path:
    wb = openpyxl.Workbook()
    wb.active["A1"], wb.active["B1"] = 1, "=" + formula
    wb.save(path)
    return path


def _sum_of_length(n: int) -> str:
    return "A1" + "+1" * ((n - 2) // 2) + ("1" if n % 2 else "")


@pytest.mark.parametrize("length,refused", [(8192, False), (8193, True)])
def test_a_formula_longer_than_excel_holds_is_refused(tmp_path, length, refused):
    formula = _sum_of_length(length)
    assert len(formula) == length
    path = _formula_book(tmp_path / "book.xlsx", formula)
    if not refused:
        assert xlsx.read(path)["Sheet"]["B1"].value == "=" + formula
        return
    with pytest.raises(xlsx.Refused, match=r"^xl/worksheets/sheet1.xml: cell Sheet!B1 has a "
                                            r"formula of 8,193 characters; Excel's limit is "
                                            r"8,192$"):
        xlsx.read(path)


@pytest.mark.parametrize("formula,refused", [
    ("(" * 64 + "A1" + ")" * 64, False),
    ("(" * 65 + "A1" + ")" * 65, True),
    ("SIN(" * 65 + "A1" + ")" * 65, True),
    ("(" * 64 + "A1" + ")" * 64 + "&\"" + "(" * 70 + "\"", False),     # brackets in text
    ("'((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((('!A1+"
     + "(" * 60 + "1" + ")" * 60, False),                                # and in a sheet name
    ("(" * 60 + ")" * 60 + "+" + "(" * 60 + "A1" + ")" * 60, False),    # wide, not deep
])
def test_a_formula_nested_deeper_than_excel_allows_is_refused(tmp_path, formula, refused):
    path = _formula_book(tmp_path / "book.xlsx", formula)
    if not refused:
        xlsx.read(path)
        return
    with pytest.raises(xlsx.Refused, match=r"cell Sheet!B1 has a formula nested 65 brackets "
                                            r"deep; Excel's limit is 64 levels$"):
        xlsx.read(path)


def test_verify_refuses_a_long_formula_before_parsing_it(tmp_path, fourbar_bytes, capsys):
    """The issue's `(I17-a_1)+0+0…` (100 k characters took 7 GiB to parse): refused at once."""
    cell = '<c r="I9" s="8"><f>I17-a_1</f>'
    long = cell.replace("I17-a_1", "(I17-a_1)" + "+0" * 50_000)
    path = _damaged(tmp_path, fourbar_bytes, "xl/worksheets/sheet1.xml", cell, long)
    code, last = _verify(path, capsys)
    assert code == 2
    assert last.endswith("xl/worksheets/sheet1.xml: cell Mechanism!I9 has a formula of 100,009 "
                         "characters; Excel's limit is 8,192"), last


def test_a_book_openpyxl_reads_is_checked_whole_first(tmp_path):
    """A shared formula sends the book to openpyxl, whose int() reads '3_5' as 35: the view
    reads every part first, and refuses."""
    path = tmp_path / "book.xlsx"
    _shared_formula_book(path)
    _rewrite(path, "xl/worksheets/sheet1.xml", "<v>2</v>", "<v>3_5</v>")
    with pytest.raises(xlsx.Refused, match="cell Sheet!A2 holds '3_5'"):
        xlsx.read(path)
    with pytest.raises(safety.UnsafeFile, match="cell Sheet!A2 holds '3_5'"):
        safety.read_workbook_safely(path)


def _matched_height_and_open(text: str) -> tuple[int, int]:
    """(how deep matched bracket pairs nest, how many '(' never close), by a stack."""
    stack, partner = [], {}
    for i, ch in enumerate(text):
        if ch == "(":
            stack.append(i)
        elif ch == ")" and stack:
            partner[stack.pop()] = i
    height, open_matched = 0, []
    for i, ch in enumerate(text):
        if open_matched and open_matched[-1] == i:
            open_matched.pop()
        if ch == "(" and i in partner:
            open_matched.append(partner[i])
            height = max(height, len(open_matched))
    return height, len(stack)


@settings(max_examples=examples(300), deadline=None, derandomize=True)
@given(st.text(alphabet="()xé+", max_size=80))
def test_nesting_is_the_height_of_matched_pairs_plus_brackets_never_closed(text):
    """Outside strings, a formula's nesting is how deep its matched brackets go, and a bracket
    never closed counts as one level more (characters beyond ASCII included)."""
    height, never_closed = _matched_height_and_open(text)
    assert xlsx._nesting(text) == height + never_closed


def test_nesting_beyond_the_limit_is_beyond_it():
    """Past one level over the limit the count need not be exact, only over the limit."""
    limit = xlsx.FORMULA_NESTING_LIMIT
    assert xlsx._nesting("(" * (limit + 1) + ")" * (limit + 1)) == limit + 1
    assert xlsx._nesting("(" * 200 + ")" * 200) > limit
    assert xlsx._nesting("SUM(" * limit + ")" * limit) == limit


def test_brackets_inside_strings_and_quoted_sheet_names_do_not_nest():
    assert xlsx._nesting('IF(A1="((((",(\'(a)\'!B1))') == 2


# addresses as a table's column spells them, and spellings that take the cell-by-cell path
_ADDRESS = st.one_of(
    st.builds(lambda col, row: f"{openpyxl.utils.get_column_letter(col)}{row}",
              st.integers(1, 16_384), st.integers(1, 1_048_576)),
    st.sampled_from(["$B$7", "b7", "AB007", "A1 B2", "", "B7\n", "ABCD1", "B", "7", "B٣"]))


@settings(max_examples=examples(100), deadline=None)
@given(st.lists(_ADDRESS, max_size=30))
@example(["B7", "A1 B2"]).via("a space inside an address: two addresses' worth of runs")
@example(["B7", "$B$8", "XFD1048576"]).via("a spelling the one-pass reading leaves alone")
@example(["B7", "C8\x00"]).via("a NUL the array of texts drops")
def test_a_list_of_addresses_reads_as_each_address_alone(cells):
    """coordinates_to_arrays (the engine's column lookups, the judged cells: read at once)
    against coordinate_to_tuple of each address alone: the same rows and columns, or the same
    kind of error; a plain address's reading is openpyxl's too."""
    from openpyxl.utils.cell import coordinate_to_tuple as openpyxls
    try:
        want = [xlsx.coordinate_to_tuple(c) for c in cells]
    except ValueError:
        want = None
    if want is None or not cells:
        with pytest.raises(ValueError):
            xlsx.coordinates_to_arrays(cells)
        return
    rows, columns = xlsx.coordinates_to_arrays(cells)
    assert list(zip(rows.tolist(), columns.tolist())) == want
    plain = [(c, w) for c, w in zip(cells, want) if re.fullmatch(r"[A-Z]+[0-9]+", c)]
    assert [openpyxls(c) for c, _ in plain] == [w for _, w in plain]
