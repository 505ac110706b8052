"""The values a book stores with its formulas (`--values`) are judged too: they are what a reader
that does not calculate shows (LibreOffice with default settings, openpyxl's data_only, pandas),
so a stored value its formula does not give differs, with the formula check's bounds; and a
constant where the build wrote a formula differs whatever its value."""
from __future__ import annotations

import json
import re
import zipfile
from pathlib import Path

import pytest

import linkbook
from linkbook.book import package
from linkbook.base import xlsx
from linkbook.apps.cli import main


@pytest.fixture(scope="module")
def book(tmp_path_factory) -> Path:
    """The four-bar built with its values stored, at a 30° step (13 rows: every formula shape;
    the tests edit or paste cells, the row count is not their point)."""
    return linkbook.build("fourbar", tmp_path_factory.mktemp("stored") / "fourbar.xlsx",
                          step=30, values=True)


@pytest.fixture(scope="module")
def fresh(book):
    """The untouched book's report (read only)."""
    return linkbook.verify(book)


def rewritten(src: Path, dst: Path, sheets, edit) -> Path:
    """A copy of `src` with `edit(xml bytes)` applied to the parts of `sheets`."""
    with zipfile.ZipFile(src) as zin:
        parts = {package.sheet_parts(zin)[sheet] for sheet in sheets}
        with zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
            for info in zin.infolist():
                data = zin.read(info)
                zout.writestr(info, edit(data) if info.filename in parts else data)
    return dst


def stored_in(path: Path, sheet: str, cell: str) -> bytes:
    with zipfile.ZipFile(path) as z:
        xml = z.read(package.sheet_parts(z)[sheet])
    return re.search(rb'<c r="' + cell.encode() + rb'"[^>]*><f>[^<]*</f><v>([^<]*)</v>',
                     xml)[1]


def with_stored(src: Path, dst: Path, sheet: str, cell: str, value: bytes,
                kind: bytes = b"") -> Path:
    """`cell`'s stored value replaced by `value` (its formula kept), typed `kind` ('e', ...)."""
    def edit(xml: bytes) -> bytes:
        pattern = rb'<c r="' + cell.encode() + rb'"([^>]*?)( t="\w+")?><f>([^<]*)</f><v>[^<]*</v>'
        t = b' t="' + kind + b'"' if kind else b""
        new, n = re.subn(pattern, lambda m: b'<c r="' + cell.encode() + b'"' + m[1] + t + b"><f>"
                         + m[3] + b"</f><v>" + value + b"</v>", xml, count=1)
        assert n == 1
        return new
    return rewritten(src, dst, [sheet], edit)


def pasted(src: Path, dst: Path, sheets, only: str | None = None) -> Path:
    """Formulas pasted as their values: each formula cell (or only `only`) keeps its stored
    value as a constant."""
    def edit(xml: bytes) -> bytes:
        cell = rb"[A-Z]+\d+" if only is None else only.encode()
        xml = re.sub(rb'(<c r="' + cell + rb'"[^>]*>)<f>[^<]*</f>', rb"\1", xml)
        return re.sub(rb'<c r="(' + cell + rb')"([^>]*?) t="str"><v>([^<]*)</v></c>',
                      rb'<c r="\1"\2 t="inlineStr"><is><t>\3</t></is></c>', xml)
    return rewritten(src, dst, sheets, edit)


def verdict(path: Path, capsys) -> tuple[int, str, dict]:
    code = main(["verify", str(path)])
    text = capsys.readouterr().out
    main(["verify", str(path), "--json"])
    [data] = json.loads(capsys.readouterr().out)
    return code, text, data


def test_a_fresh_book_stores_what_its_formulas_give(fresh):
    report = fresh
    stored = [c for c in report.checks if c.block == "stored"]
    assert report.status == 0
    assert len(stored) == 1 and stored[0].cells == report.formula_cells == report.cells


def test_a_book_without_stored_values_is_judged_as_before(tmp_path):
    report = linkbook.verify(linkbook.build("fourbar", tmp_path / "plain.xlsx", step=30))
    assert report.status == 0 and not [c for c in report.checks if c.block == "stored"]


def test_one_stored_value_changed_is_named_with_both_values(book, tmp_path, capsys):
    cell = "C9"
    formula_gives = float(stored_in(book, "Sweep", cell))
    path = with_stored(book, tmp_path / "edited.xlsx", "Sweep", cell, b"99.9")
    code, text, data = verdict(path, capsys)
    assert code == 1
    assert f"Sweep!{cell}: expected {formula_gives!r}, got 99.9" in text
    assert "1 cells differ (1 store a value their formula does not give)" in text
    assert data["status"] == 1 and data["mismatches"] == 1 and data["stored_values_differ"] == 1
    stored = next(c for c in data["checks"] if c["block"] == "stored")
    assert stored["mismatches"] == [{"sheet": "Sweep", "cell": cell, "expected": formula_gives,
                                     "got": 99.9}]


@pytest.mark.parametrize("how,value,kind,differs", [
    ("rounded to 15 digits, as LibreOffice keeps it", "round15", b"", False),
    ("off by 1e-6 mm (the bound is 1e-12·S, S = 434 mm)", "plus1e-6", b"", True),
    ("an error where a number belongs", b"#N/A", b"e", True),
    ("text where a number belongs", b"60.62", b"str", True),
])
def test_stored_values_are_judged_with_the_formula_bounds(book, tmp_path, how, value, kind,
                                                          differs):
    cell = "C10"           # xs, a length (-100.31...: 15 digits do not hold it exactly)
    x = float(stored_in(book, "Sweep", cell))
    if value == "round15":
        value = f"{x:.15g}".encode()
        assert float(value) != x
    elif value == "plus1e-6":
        value = repr(x + 1e-6).encode()
    path = with_stored(book, tmp_path / "edited.xlsx", "Sweep", cell, value, kind)
    report = linkbook.verify(path)
    assert report.status == (1 if differs else 0), how
    assert report.stored_differ == (1 if differs else 0)


def test_every_formula_pasted_as_its_value_differs(book, fresh, tmp_path, capsys):
    before = fresh
    with zipfile.ZipFile(book) as z:
        sheets = [s for s in package.sheet_parts(z) if s != "linkbook"]
    path = pasted(book, tmp_path / "pasted.xlsx", sheets)
    code, text, data = verdict(path, capsys)
    assert code == 1
    assert data["formula_cells"] == data["cells"] == 0       # never "3418 of 0"
    assert len(data["replaced_by_constants"]) == data["mismatches"] == before.formula_cells
    assert (f"{before.formula_cells} cells differ ({before.formula_cells} hold a constant where "
            f"the build wrote a formula)") in text
    assert "0 of 0 formula cells compared" in text


def test_one_formula_pasted_as_its_exact_value_differs(book, fresh, tmp_path, capsys):
    path = pasted(book, tmp_path / "one.xlsx", ["Sweep"], only="C9")
    code, text, data = verdict(path, capsys)
    assert code == 1 and data["replaced_by_constants"] == ["Sweep!C9"]
    total = fresh.formula_cells
    assert data["formula_cells"] == data["cells"] == total - 1
    assert "Sweep!C9: expected a formula, got the constant" in text


def test_books_openpyxl_reads_have_their_stored_values_judged(book, tmp_path, monkeypatch):
    """A book the fast reader does not model (Excel writes shared formulas) is read by openpyxl;
    its stored values are judged the same way."""
    path = with_stored(book, tmp_path / "edited.xlsx", "Sweep", "C9", b"99.9")

    def unsupported(path):
        raise xlsx.Unsupported("as if Excel had saved it")
    monkeypatch.setattr(xlsx, "read", unsupported)
    report = linkbook.verify(path)
    assert report.status == 1 and report.stored_differ == 1
    assert linkbook.verify(book).status == 0      # read by openpyxl too


def test_cells_of_a_deleted_sheet_are_not_counted_as_compared(book, fresh, tmp_path):
    """A sheet deleted takes its formula cells with it: they differ (no value), and are
    neither constants nor formula cells compared."""
    import openpyxl
    wb = openpyxl.load_workbook(book)
    gone = sum(1 for row in wb["Drawing data"].iter_rows() for c in row if c.data_type == "f")
    del wb["Drawing data"]
    wb.save(tmp_path / "deleted.xlsx")
    report = linkbook.verify(tmp_path / "deleted.xlsx")
    assert report.status == 1 and not report.replaced
    assert len(report.absent) == gone > 0
    assert report.cells == report.formula_cells == fresh.formula_cells - gone


@pytest.mark.parametrize("value,kind,shown", [(b"1", b"b", "True"), (b"1", b"str", "'1'")],
                         ids=["TRUE for 1", "the text 1 for 1"])
def test_a_value_of_another_kind_stored_differs(book, fresh, tmp_path, capsys, value, kind,
                                                shown):
    """TRUE or the text "1" stored where the formula gives the number 1: a reader that does not
    calculate shows TRUE or left-aligned text, however close the numbers."""
    closes = _first_closes(book)
    assert float(stored_in(book, "Sweep", closes)) == 1.0 and fresh.status == 0
    path = with_stored(book, tmp_path / "kind.xlsx", "Sweep", closes, value, kind)
    code, text, data = verdict(path, capsys)
    assert code == 1 and data["stored_values_differ"] == 1
    assert f"Sweep!{closes}: expected 1" in text and f"got {shown}" in text


def test_a_boolean_stored_as_another_word_is_refused(book, tmp_path, capsys):
    path = with_stored(book, tmp_path / "two.xlsx", "Sweep", _first_closes(book), b"2", b"b")
    assert main(["verify", str(path)]) == 2
    assert "is not a boolean" in capsys.readouterr().err


def _first_closes(book: Path) -> str:
    """The first cell of the sweep's "closes [1/0]" column (1 where every loop closes)."""
    from linkbook.base import sheets
    sweep = sheets.read_meta(xlsx.read(book))["sweep"]
    return f"{sweep['columns']['closes']}{sweep['rows'][0]}"
