"""The sheet scan of the fast view (base/xlsx.py: regular expressions over a sheet part's text)
against the element-by-element reading of the same part (ElementTree, which test_xlsx.py holds
to openpyxl's) and against openpyxl itself: every cell, every stored value and every refusal
the same, whether the part is written as the scan reads it or in a form it leaves to the
elements."""
from __future__ import annotations

import zipfile
from pathlib import Path
from xml.sax.saxutils import escape

import openpyxl
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import examples
from linkbook.base import xlsx

STRINGS = ["zero", "one & two", "<three>"]
QUOTES = {'"': "&quot;"}
CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.'
    'relationships+xml"/><Default Extension="xml" ContentType="application/xml"/>'
    '<Override PartName="/xl/workbook.xml" ContentType="application/vnd.openxmlformats-'
    'officedocument.spreadsheetml.sheet.main+xml"/>'
    '<Override PartName="/xl/worksheets/sheet1.xml" ContentType="application/vnd.'
    'openxmlformats-officedocument.spreadsheetml.worksheet+xml"/>'
    '<Override PartName="/xl/sharedStrings.xml" ContentType="application/vnd.openxmlformats-'
    'officedocument.spreadsheetml.sharedStrings+xml"/></Types>')
PACKAGE_RELS = (
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Id="rId1" Type="http://schemas.openxmlformats.org/officeDocument/2006/'
    'relationships/officeDocument" Target="xl/workbook.xml"/></Relationships>')
WORKBOOK = (
    '<workbook xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main" '
    'xmlns:r="http://schemas.openxmlformats.org/officeDocument/2006/relationships">'
    '<sheets><sheet name="S" sheetId="1" r:id="rId1"/></sheets></workbook>')
WORKBOOK_RELS = (
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Id="rId1" Type="http://schemas.openxmlformats.org/officeDocument/2006/'
    'relationships/worksheet" Target="worksheets/sheet1.xml"/>'
    '<Relationship Id="rId2" Type="http://schemas.openxmlformats.org/officeDocument/2006/'
    'relationships/sharedStrings" Target="sharedStrings.xml"/></Relationships>')
SHARED = ('<sst xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
          + "".join(f"<si><t>{escape(s)}</t></si>" for s in STRINGS) + "</sst>")
HEAD = ('<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\n'
        '<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
        '<dimension ref="A1"/><sheetData>')
TAIL = '</sheetData><pageMargins left="0.7" right="0.7" top="0.75" bottom="0.75" ' \
       'header="0.3" footer="0.3"/></worksheet>'


def book(path: Path, rows: str, head: str = HEAD, tail: str = TAIL) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("[Content_Types].xml", CONTENT_TYPES)
        zf.writestr("_rels/.rels", PACKAGE_RELS)
        zf.writestr("xl/workbook.xml", WORKBOOK)
        zf.writestr("xl/_rels/workbook.xml.rels", WORKBOOK_RELS)
        zf.writestr("xl/sharedStrings.xml", SHARED)
        zf.writestr("xl/worksheets/sheet1.xml", head + rows + tail)
    return path


def outcome(path: Path, scan: bool) -> tuple:
    """What reading the book gives: its cells (value, kind, stored) and notes, or the refusal;
    with `scan` False, the sheet read element by element."""
    with pytest.MonkeyPatch.context() as m:
        if not scan:
            m.setattr(xlsx, "_scan_cells", _not_scanned)
        try:
            wb = xlsx.read(path)
        except (xlsx.Refused, xlsx.Unsupported) as exc:
            return type(exc).__name__, str(exc)
        except Exception as exc:        # damaged: openpyxl says what (safety.py)
            return "damaged", type(exc).__name__
    ws = wb["S"]
    held = [ws.cell(*k) for k in sorted(ws._cells)]       # each found by its address
    return ([((c.row, c.column), c.value, type(c.value), c.data_type) for c in held],
            sorted(ws.stored_items()), wb.notes)


def _not_scanned(*_):
    raise xlsx._NotScanned("off")


# ------------------------------------------------------------------ the cells a writer writes
NUMBER = st.one_of(st.integers(-10**6, 10**6).map(str),
                   st.floats(allow_nan=False, allow_infinity=False).map(repr),
                   st.sampled_from(["1e999", "1_0", " 2 ", "", "0x10", "-0.0", "5E-3"]))
# characters, and texts that read as an entity once a '&' before them is read as one: a
# decoder that reads '&amp;' first reads '&amp;lt;' as '<', not as the text '&lt;'
FORMULA = st.lists(st.one_of(st.sampled_from(list('AB12+-*/()&<>"\' $:!.,')),
                             st.sampled_from(["&lt;", "&amp;", "&gt;", "&quot;", "&#60;", "lt;"])),
                   max_size=30).map("".join)
CELL = st.one_of(
    st.tuples(st.just("n"), NUMBER),
    st.tuples(st.just("s"), st.sampled_from(["0", "1", "2", "3", "x"])),
    st.tuples(st.just("b"), st.sampled_from(["0", "1", "2"])),
    st.tuples(st.just("e"), st.sampled_from(["#N/A", "#DIV/0!"])),
    st.tuples(st.just("str"), st.text(st.sampled_from("ab <&>\"'"), max_size=6)),
    st.tuples(st.just("inlineStr"), st.text(st.sampled_from("ab <&>\"'"), max_size=6)),
    st.tuples(st.just("f"), st.tuples(FORMULA, st.sampled_from(["", "n", "str", "e", "b"]),
                                      st.one_of(st.none(), NUMBER, st.just("#N/A")))),
    st.tuples(st.just("empty"), st.just("")))


def cell_xml(col: int, row: int, cell, style: int | None) -> str:
    letters = xlsx.column_letter(col)
    kind, what = cell
    s = "" if style is None else f' s="{style}"'
    if kind == "empty":
        return f'<c r="{letters}{row}"{s}/>'
    if kind == "f":
        text, t, stored = what
        t_attr = f' t="{t}"' if t else ""
        v = "" if stored is None else ("<v/>" if stored == "" else f"<v>{escape(stored)}</v>")
        f = "<f/>" if text == "" else f"<f>{escape(text, QUOTES)}</f>"  # as LibreOffice writes
        return f'<c r="{letters}{row}"{s}{t_attr}>{f}{v}</c>'
    if kind == "inlineStr":
        return f'<c r="{letters}{row}"{s} t="inlineStr"><is><t>{escape(what)}</t></is></c>'
    t_attr = "" if kind == "n" else f' t="{kind}"'
    return f'<c r="{letters}{row}"{s}{t_attr}><v>{escape(what)}</v></c>'


SHEET = st.lists(st.tuples(st.integers(1, 6), st.integers(1, 30), CELL,
                           st.one_of(st.none(), st.integers(0, 3))),
                 min_size=1, max_size=25, unique_by=lambda c: (c[0], c[1]))


def rows_xml(cells) -> str:
    """Cells in rows, each row's cells in column order, as the writers write them."""
    out, by_row = [], {}
    for col, row, cell, style in cells:
        by_row.setdefault(row, []).append(cell_xml(col, row, cell, style))
    for row in sorted(by_row):
        out.append(f'<row r="{row}">{"".join(sorted(by_row[row], key=_column_of))}</row>')
    return "".join(out)


def _column_of(cell_text: str) -> int:
    return xlsx.coordinate_to_tuple(cell_text.split('"')[1])[::-1][0]


def pretty(rows: str) -> str:
    """The rows with white space between every two tags, as Gnumeric writes them."""
    return rows.replace("><", ">\n    <")


@settings(max_examples=examples(60))
@given(cells=SHEET, spaced=st.booleans())
def test_the_scan_reads_what_the_elements_read(tmp_path_factory, cells, spaced):
    rows = rows_xml(cells)
    path = book(tmp_path_factory.mktemp("scan") / "book.xlsx", pretty(rows) if spaced else rows)
    assert outcome(path, True) == outcome(path, False)


@pytest.mark.parametrize("spaced", [False, True])
def test_the_scan_reads_a_writers_part_itself(tmp_path, monkeypatch, spaced):
    """The writers' form is scanned, not handed to the elements (else the test above would
    compare the elements with themselves)."""
    cells = [(1, 1, ("n", "1.5"), None), (2, 1, ("f", ("A1*2", "", "3")), 1),
             (1, 2, ("s", "1"), None), (2, 2, ("f", ('"a"&"<b>"', "str", "a<b>")), None),
             (3, 2, ("inlineStr", "a & b"), None)]
    rows = rows_xml(cells)
    path = book(tmp_path / "book.xlsx", pretty(rows) if spaced else rows)
    monkeypatch.setattr(xlsx, "_read_cells", _not_scanned)
    wb = xlsx.read(path)
    assert [(c.coordinate, c.value) for c in wb["S"]._cells.values()] == [
        ("A1", 1.5), ("A2", "one & two"), ("B1", "=A1*2"), ("B2", '="a"&"<b>"'),
        ("C2", "a & b")]
    assert sorted(wb["S"].stored_items()) == [((1, 2), ("n", 3)), ((2, 2), ("str", "a<b>"))]


PLAIN = [(1, 1, ("n", "1.5"), None), (2, 1, ("f", ("A1*2&\"x\"", "", "3")), None),
         (3, 1, ("s", "2"), None), (1, 2, ("f", ("SUM(A1:B1)", "", None)), None),
         (2, 2, ("b", "1"), None), (3, 2, ("e", "#N/A"), None)]
OTHER_FORMS = {
    "attributes in another order": lambda x: x.replace('<c r="C1" t="s">', '<c t="s" r="C1">'),
    "two spaces before an attribute": lambda x: x.replace('<c r="B1">', '<c  r="B1">'),
    "single quotes": lambda x: x.replace('r="A1"', "r='A1'"),
    "white space between elements": lambda x: x.replace("<row", "\n  <row"),
    "a comment": lambda x: x.replace("</row>", "<!-- note --></row>", 1),
    "a cell commented out": lambda x: x.replace("</row>", '<!--<c r="D1"><v>4</v></c>--></row>'),
    "CDATA": lambda x: x.replace("<f>SUM(A1:B1)</f>", "<f><![CDATA[SUM(A1:B1)]]></f>"),
    "a carriage return": lambda x: x.replace("SUM(A1:B1)", "SUM(A1:B1)\r\n"),
    "an inline string of runs": lambda x: x.replace(
        '<c r="C1" t="s"><v>2</v></c>',
        '<c r="C1" t="inlineStr"><is><r><t>&lt;th</t></r><r><t>ree&gt;</t></r></is></c>'),
    "a character reference": lambda x: x.replace("SUM(A1:B1)", "SUM(A1&#58;B1)"),
    "a formula's attributes": lambda x: x.replace("<f>SUM", '<f aca="false">SUM'),
    "rows out of order": lambda x: x.replace(
        '<row r="1">', '<row r="9"><c r="A9"><v>9</v></c><c r="C1"><v>7</v></c></row><row r="1">'),
}


@pytest.mark.parametrize("form", sorted(OTHER_FORMS))
def test_a_part_in_another_form_reads_as_openpyxl_reads_it(tmp_path, form):
    path = book(tmp_path / "book.xlsx", OTHER_FORMS[form](rows_xml(PLAIN)))
    scanned, elements = outcome(path, True), outcome(path, False)
    assert scanned == elements
    full = openpyxl.load_workbook(path)["S"]
    assert [(k, value) for k, value, _, _ in scanned[0]] == sorted(
        (k, c.value) for k, c in full._cells.items() if c.value is not None)


@pytest.mark.parametrize("head", [
    HEAD.replace("spreadsheetml/2006/main", "spreadsheetml/2006/other"),
    HEAD.replace('encoding="UTF-8"', 'encoding="ISO-8859-1"'),
    HEAD.replace("<worksheet xmlns=", "<x:worksheet xmlns:x=").replace("<dimension", "<x:dimension")
        .replace("<sheetData>", "<x:sheetData>")])
def test_a_part_in_another_encoding_or_namespace_reads_as_the_elements_do(tmp_path, head):
    rows = rows_xml(PLAIN)
    tail = TAIL
    if "x:" in head:
        rows = rows.replace("<", "<x:").replace("<x:/", "</x:")
        tail = tail.replace("</", "</x:").replace("<pageMargins", "<x:pageMargins")
    path = book(tmp_path / "book.xlsx", rows, head, tail)
    scanned = outcome(path, True)
    assert scanned == outcome(path, False)
    assert len(scanned[0]) == (0 if "other" in head else len(PLAIN))


@pytest.mark.parametrize("damage", ['<c r="A1"><v>1</c>', '<c r="A1" r="B1"><v>1</v></c>',
                                    "<c r=\"A1\"><v>&bogus;</v></c>", '<c r="A1"><v>\x01</v></c>'])
def test_a_damaged_part_is_read_as_the_elements_read_it(tmp_path, damage):
    path = book(tmp_path / "book.xlsx", f'<row r="1">{damage}</row>')
    assert outcome(path, True) == outcome(path, False) \
        == ("damaged", "ParseError")


CONTROLS = ('<mc:AlternateContent xmlns:mc="http://schemas.openxmlformats.org/markup-compatibility'
            '/2006"><mc:Choice Requires="x14"><control shapeId="1025" r:id="rId3" '
            'name="Spinner 1" xmlns:r="http://schemas.openxmlformats.org/officeDocument/2006/'
            'relationships"><anchor><from xmlns:xdr="http://schemas.openxmlformats.org/'
            'drawingml/2006/spreadsheetDrawing"><xdr:col>7</xdr:col><xdr:row>3</xdr:row></from>'
            '</anchor></control></mc:Choice></mc:AlternateContent>')
PREFIXED_CELL = ('<x:row xmlns:x="http://schemas.openxmlformats.org/spreadsheetml/2006/main" '
                 'r="7"><x:c r="D7"><x:v>4</x:v></x:c></x:row>')


@pytest.mark.parametrize("after, scanned", [(CONTROLS, True), (PREFIXED_CELL, False)])
def test_what_follows_the_sheet_data_is_read_as_the_elements_read_it(tmp_path, after, scanned):
    """A form control's markup after <sheetData> (its own namespaces, no cell: every bundled
    book with a spin button) is scanned; a cell there under a prefix bound to the main namespace
    (which the elements read) sends the part to the elements."""
    path = book(tmp_path / "book.xlsx", rows_xml(PLAIN),
                tail=TAIL.replace("<pageMargins", after + "<pageMargins"))
    calls = []
    with pytest.MonkeyPatch.context() as m:
        m.setattr(xlsx, "_read_cells", lambda *a, _r=xlsx._read_cells: calls.append(1) or _r(*a))
        got = outcome(path, True)
    assert got == outcome(path, False)
    assert len(got[0]) == len(PLAIN) + (0 if scanned else 1)
    assert calls == ([] if scanned else [1])


def test_a_prefix_bound_to_the_main_namespace_on_the_sheet_sends_it_to_the_elements(tmp_path):
    """<worksheet> binding x to the main namespace as well: a cell written <x:c> is a cell, read
    by the elements, so the part is read by them."""
    head = HEAD.replace("<worksheet xmlns=\"http://schemas.openxmlformats.org/spreadsheetml/2006/"
                        "main\"", "<worksheet xmlns=\"http://schemas.openxmlformats.org/"
                        "spreadsheetml/2006/main\" xmlns:x=\"http://schemas.openxmlformats.org/"
                        "spreadsheetml/2006/main\"")
    assert head != HEAD
    rows = rows_xml(PLAIN).replace("</row>", '<x:c r="H1"><x:v>8</x:v></x:c></row>', 1)
    path = book(tmp_path / "book.xlsx", rows, head)
    got = outcome(path, True)
    assert got == outcome(path, False) and len(got[0]) == len(PLAIN) + 1
