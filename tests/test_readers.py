"""Every reader reads a built book whole, whichever XML writer openpyxl used to build it.

A reader that streams a big book (openpyxl in read-only mode, pandas, calamine) trusts each sheet's
`<dimension>`: a wrong one (A1:A1) hides the table. Without lxml, openpyxl writes its elements as
`<dimension ref=".." />`, with lxml as `<dimension ref=".."/>`; the last pass over the package
(linkbook.book.package) writes the cells and must put the true used range in either form. The books
are built by the command in a subprocess, once with lxml and once with openpyxl's own writer
(openpyxl reads OPENPYXL_LXML at import), with cached values so that pandas has numbers to read.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import openpyxl
import pytest
from conftest import HANG_GUARD_S
from defusedxml import ElementTree

# every bundled book read by three third-party readers, built two ways: the full suite (CI)
# runs it, the fast tier leaves it out
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
BACKENDS = {"lxml": "True", "openpyxl's own XML writer": "False"}
# docProps/core.xml holds the time of the build
TIMESTAMPS = {"{http://purl.org/dc/terms/}created", "{http://purl.org/dc/terms/}modified"}


def _env(use_lxml: str) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT / "src"), "OPENPYXL_LXML": use_lxml}


def _backend_in_use(use_lxml: str) -> bool:
    out = subprocess.run([sys.executable, "-c", "import openpyxl.xml; print(openpyxl.xml.LXML)"],
                         env=_env(use_lxml), capture_output=True, text=True, check=True)
    return out.stdout.strip() == "True"


@pytest.fixture(scope="module")
def books(needs, tmp_path_factory) -> dict[str, dict[str, Path]]:
    """backend -> template name -> every bundled book, built by `linkbook build --all
    --values` in a process of its own (with lxml and without: without it they are the same)."""
    needs("lxml")
    assert _backend_in_use("True"), "openpyxl does not use lxml though it is installed"
    assert not _backend_in_use("False"), "OPENPYXL_LXML=False did not turn lxml off"
    made = {}
    for backend, use_lxml in BACKENDS.items():
        folder = tmp_path_factory.mktemp("lxml" if use_lxml == "True" else "no-lxml")
        run = subprocess.run([sys.executable, "-m", "linkbook", "build", "--all", "--values",
                              "--outdir", str(folder)], env=_env(use_lxml), capture_output=True,
                             text=True, timeout=2 * HANG_GUARD_S)
        assert run.returncode == 0, run.stderr
        made[backend] = {p.stem: p for p in sorted(folder.glob("*.xlsx"))}
    names = [by_name.keys() for by_name in made.values()]
    assert names[0] == names[1] == {t.stem for t in (ROOT / "templates").glob("*.toml")}
    return made


def _all_books(books):
    return [(backend, path) for backend, by_name in books.items() for path in by_name.values()]


# ---------------------------------------------------------------- the same book either way
def _tree(element) -> tuple:
    """An element as data: its name, attributes, text and children (namespace declarations,
    where they are written, and `<a/>` against `<a></a>` are spelling, not content)."""
    text = "" if element.tag in TIMESTAMPS else (element.text or "")
    return (element.tag, sorted(element.attrib.items()), text, element.tail or "",
            [_tree(child) for child in element])


def test_the_build_does_not_depend_on_the_xml_writer(books):
    differ = []
    for name, with_lxml in books["lxml"].items():
        other = books["openpyxl's own XML writer"][name]
        with zipfile.ZipFile(with_lxml) as a, zipfile.ZipFile(other) as b:
            assert a.namelist() == b.namelist(), name
            for part in a.namelist():
                x, y = a.read(part), b.read(part)
                if x != y and _tree(ElementTree.fromstring(x)) != _tree(ElementTree.fromstring(y)):
                    differ.append(f"{name}: {part}")
    assert not differ, differ


# ---------------------------------------------------------------- openpyxl, streamed or whole
def _cells(path: Path, **mode) -> dict[tuple[str, str], object]:
    wb = openpyxl.load_workbook(path, **mode)
    try:
        return {(ws.title, c.coordinate): c.value for ws in wb.worksheets
                for row in ws.iter_rows() for c in row
                if getattr(c, "value", None) is not None}
    finally:
        wb.close()


@pytest.mark.parametrize("data_only", [False, True], ids=["formulas", "cached values"])
def test_openpyxl_read_only_reads_every_cell(books, data_only):
    """read-only mode (iter_rows bounded by the dimension) sees every cell a full load sees."""
    for backend, path in _all_books(books):
        whole = _cells(path, data_only=data_only)
        streamed = _cells(path, data_only=data_only, read_only=True)
        assert len(whole) > 100, (backend, path.name)
        missing = sorted(whole.keys() - streamed.keys())
        assert not missing, f"{backend}, {path.name}: {len(missing)} cells missing: {missing[:5]}"
        assert streamed == whole, (backend, path.name)


def _read_only_dimensions(path: Path) -> dict[str, tuple[int, int]]:
    wb = openpyxl.load_workbook(path, read_only=True)
    try:
        return {ws.title: (ws.max_row, ws.max_column) for ws in wb.worksheets}
    finally:
        wb.close()


def test_every_sheet_declares_its_used_range(books):
    for backend, path in _all_books(books):
        used: dict[str, tuple[int, int]] = {}
        for (sheet, cell) in _cells(path):
            row, col = openpyxl.utils.cell.coordinate_to_tuple(cell)
            r, c = used.get(sheet, (1, 1))
            used[sheet] = (max(r, row), max(c, col))
        declared = _read_only_dimensions(path)
        for sheet, (rows, cols) in used.items():
            got_rows, got_cols = declared[sheet]
            assert got_rows >= rows and got_cols >= cols, (backend, path.name, sheet,
                                                           declared[sheet], used[sheet])


# ---------------------------------------------------------------- pandas
def _same_value(got, expected) -> bool:
    """pandas' cell against openpyxl's cached value: an error cell is NaN in pandas."""
    if isinstance(expected, str) and expected.startswith("#"):
        return got is None or (isinstance(got, float) and math.isnan(got)) or got == expected
    if isinstance(expected, bool):
        return bool(got) == expected
    if isinstance(expected, (int, float)):
        return isinstance(got, (int, float)) and float(got) == float(expected)
    return got == expected


@pytest.mark.parametrize("engine", ["openpyxl", "calamine"])
def test_pandas_reads_every_table_whole(needs, books, engine):
    needs("pandas", *(["calamine"] if engine == "calamine" else []))
    import pandas as pd
    for backend, path in _all_books(books):
        expected = _cells(path, data_only=True)
        frames = pd.read_excel(path, sheet_name=None, header=None, engine=engine)
        wrong = []
        for (sheet, cell), value in expected.items():
            row, col = openpyxl.utils.cell.coordinate_to_tuple(cell)
            frame = frames[sheet]
            got = frame.iat[row - 1, col - 1] if (row <= frame.shape[0]
                                                  and col <= frame.shape[1]) else "(not read)"
            if not _same_value(got, value):
                wrong.append(f"{sheet}!{cell}: {got!r}, not {value!r}")
        assert not wrong, f"{engine}, {backend}, {path.name}: {len(wrong)} cells: {wrong[:4]}"


# ---------------------------------------------------------------- where namespaces are declared
A = "http://schemas.openxmlformats.org/drawingml/2006/main"
C = "http://schemas.openxmlformats.org/drawingml/2006/chart"


def test_drawing_namespaces_move_to_the_root():
    """The form openpyxl writes through lxml (each prefix declared where it is used) becomes
    the form of its own writer, which Gnumeric reads: every prefix declared on the root."""
    from linkbook.book.package import namespaces_on_root
    local = (f'<?xml version="1.0"?>\n<wsDr xmlns="urn:d"><g><a:graphic xmlns:a="{A}">'
             f'<c:chart xmlns:c="{C}" id="1"/></a:graphic></g><a:x xmlns:a="{A}">t</a:x>'
             f'</wsDr>').encode()
    moved = namespaces_on_root(local)
    assert moved == (f'<?xml version="1.0"?>\n<wsDr xmlns="urn:d" xmlns:a="{A}" xmlns:c="{C}">'
                     f'<g><a:graphic><c:chart id="1"/></a:graphic></g><a:x>t</a:x>'
                     f'</wsDr>').encode()
    assert _tree(ElementTree.fromstring(moved)) == _tree(ElementTree.fromstring(local))


@pytest.mark.parametrize("xml", [
    f'<r><a:x xmlns:a="{A}"/><a:y xmlns:a="{C}"/></r>',     # one prefix, two namespaces
    '<r/>',
])
def test_namespaces_left_alone_where_they_cannot_move(xml):
    from linkbook.book.package import namespaces_on_root
    assert namespaces_on_root(xml.encode()) == xml.encode()


def test_text_that_looks_like_a_declaration_stays():
    from linkbook.book.package import namespaces_on_root
    text = 'a title with xmlns:b="urn:not-markup" in it'
    assert namespaces_on_root(f'<r><a:x xmlns:a="{A}">{text}</a:x></r>'.encode()) == \
        f'<r xmlns:a="{A}"><a:x>{text}</a:x></r>'.encode()


def test_a_self_closing_root_takes_the_declarations():
    from linkbook.book.package import namespaces_on_root
    assert namespaces_on_root(f'<r xmlns:a="{A}" b="1"/>'.encode()) == \
        f'<r b="1" xmlns:a="{A}"/>'.encode()
