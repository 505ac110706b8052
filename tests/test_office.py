"""LibreOffice as the real spreadsheet: recalculation against the independent reference, cached
values written into the file, page setup and PNG previews.

Tests that need soffice are skipped when it is missing (conftest's `needs`), except under CI
(CI set), where a missing LibreOffice is a failure: .ci/run installs it, so its absence there is a broken build.
"""
from __future__ import annotations

import contextlib
import os
import re
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
import zlib
from pathlib import Path

import openpyxl
import pytest
from openpyxl import Workbook

from conftest import HANG_GUARD_S, gone, said_pids, wait_until

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:        # conftest does this too; kept for --noconftest
    sys.path.insert(0, str(ROOT / "src"))

from linkbook.book import builder
from linkbook.book import cached
from linkbook.book import charts
from linkbook.apps import cli
from linkbook.engine import office
from linkbook.apps import preview
from linkbook.book import pages
from linkbook.book import package
from linkbook.language import templates
from linkbook.check import verifier
from linkbook.book import workbook  # noqa: E402
from linkbook.base.sheets import MECH, SWEEP  # noqa: E402

REL_TOL = 1e-9          # LibreOffice stores 15 significant digits
NON_GRASHOF = ("a1=100", "a2=60", "a3=50", "a4=40")      # cannot turn fully: #N/A rows


# ---------------------------------------------------------------- helpers
def _template(name: str, sets=()):
    return templates.with_overrides(templates.load(name), list(sets), None, None)


def _formula_cells(wb) -> dict[tuple[str, str], str]:
    return {(ws.title, c.coordinate): c.value for ws in wb.worksheets for row in ws.iter_rows()
            for c in row if isinstance(c.value, str) and c.value.startswith("=")}


def _built_and_values(name: str, sets, tmp: Path):
    """A finished workbook, saved, and every cell as LibreOffice recalculates it."""
    b, _ = builder.make(_template(name, sets))
    path = tmp / f"{name}.xlsx"
    b.workbook.save(path)
    return b, path, office.recalculated_values(path)


def _book_with_charts(name: str, tmp: Path, sets=()) -> Path:
    """The full layout: the charts (framed live: they read no values), then the print setup
    every built book gets (the Mechanism sheet one page wide)."""
    t = _template(name, sets)
    b = workbook.build(t)
    charts.add_charts(b, t, b.model)
    builder._print_setup(b)
    path = tmp / f"{name}-charts.xlsx"
    b.workbook.save(path)
    return path


def _same(got, expected) -> bool:
    """Equal errors, equal text, or numbers within REL_TOL (relative above 1, absolute below)."""
    if office.is_error(expected) or not isinstance(expected, float):
        return got == expected
    return isinstance(got, float) and abs(got - expected) <= REL_TOL * max(1.0, abs(expected))


def _png_rgb(path: Path) -> tuple[int, int, int, bytes]:
    """(width, height, channels, pixel bytes) of an 8-bit PNG: chunks, zlib, un-filtering."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    assert depth == 8, "only 8-bit PNGs are read here"
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    raw = zlib.decompress(idat)
    stride = width * channels
    out, prev = bytearray(), bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        _unfilter(kind, line, prev, channels)
        out += line
        prev = line
    return width, height, channels, bytes(out)


def _unfilter(kind: int, line: bytearray, prev: bytearray, bpp: int) -> None:
    if kind == 0:
        return
    for i in range(len(line)):
        left = line[i - bpp] if i >= bpp else 0
        up = prev[i]
        if kind == 1:
            line[i] = (line[i] + left) & 0xFF
        elif kind == 2:
            line[i] = (line[i] + up) & 0xFF
        elif kind == 3:
            line[i] = (line[i] + ((left + up) >> 1)) & 0xFF
        else:
            corner = prev[i - bpp] if i >= bpp else 0
            p = left + up - corner
            pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
            pred = left if pa <= pb and pa <= pc else up if pb <= pc else corner
            line[i] = (line[i] + pred) & 0xFF


def _ink(path: Path) -> float:
    """The share of pixels that are not (near) white."""
    width, height, channels, pixels = _png_rgb(path)
    grey = pixels[::channels]            # the first channel is enough to tell ink from paper
    return sum(1 for v in grey if v < 200) / (width * height)


# ---------------------------------------------------------------- without LibreOffice
@pytest.mark.parametrize("value,code", [
    (office.CellError("#N/A"), "#N/A"), ("#NUM!", "#NUM!"), ("#DIV/0!", "#DIV/0!"),
    ("#VALUE!", "#VALUE!"), ("#N/A ", None), ("abc", None), ("#", None), (1.5, None),
    (0, None), (None, None), (True, None)])
def test_error_codes(value, code):
    assert office.error_code(value) == code
    assert office.is_error(value) is (code is not None)


def test_formulas_errors_are_errors():
    from formulas.tokens.operand import XlError
    assert office.error_code(XlError("#N/A")) == "#N/A"
    assert cached.encode_value(XlError("#N/A")) == ("e", b"#N/A")


def test_missing_soffice_says_how_to_install(monkeypatch, tmp_path):
    monkeypatch.setattr(office.shutil, "which", lambda name: None)
    assert office.soffice_path() is None
    (tmp_path / "a.xlsx").write_bytes(b"PK")
    with pytest.raises(office.OfficeUnavailable, match="apt-get install .*libreoffice-calc"):
        office.recalculate(tmp_path / "a.xlsx", tmp_path)


def test_silent_soffice_failure_is_an_error(monkeypatch, tmp_path):
    """soffice exits 0 even when it writes nothing: the missing output must raise."""
    fake = tmp_path / "soffice"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o755)
    monkeypatch.setattr(office, "soffice_path", lambda: str(fake))
    scratch = _private_tempdir(monkeypatch, tmp_path)
    book = tmp_path / "b.xlsx"
    Workbook().save(book)
    with pytest.raises(office.OfficeFailed, match="could not convert b.xlsx"):
        office.recalculate(book, tmp_path / "out")
    assert not any(scratch.iterdir()), "a temporary folder was left behind"


def test_books_of_one_name_are_not_recalculated_in_one_run(monkeypatch, tmp_path):
    """One run of soffice writes each book as NAME.xlsx into one folder: two books of one name
    would come back as one, so they are refused before soffice starts."""
    monkeypatch.setattr(office, "soffice_path", lambda: str(tmp_path / "never-run"))
    books = [tmp_path / "a" / "x.xlsx", tmp_path / "b" / "x.xlsx"]
    for book in books:
        book.parent.mkdir()
        Workbook().save(book)
    with pytest.raises(ValueError, match="same name"):
        office.recalculate_all(books, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_hanging_soffice_is_ended_with_its_children(monkeypatch, tmp_path):
    """soffice is a launcher: a time-out must end soffice.bin too, not only the script."""
    child_pid = tmp_path / "child.pid"
    fake = tmp_path / "soffice"
    fake.write_text(f"#!/bin/sh\nsleep {2 * HANG_GUARD_S} &\necho $! > {child_pid}\nwait\n")
    fake.chmod(0o755)
    monkeypatch.setattr(office, "soffice_path", lambda: str(fake))
    monkeypatch.setattr(office, "TIMEOUT_S", 1)

    class ChildFirst(subprocess.Popen):
        """The time-out starts once the launcher has started its child (however slowly a
        loaded machine starts it), so that there is a child to end."""
        def communicate(self, *args, timeout=None, **kwargs):
            if timeout is not None:
                wait_until(lambda: said_pids(child_pid, 1), "the launcher's child")
            return super().communicate(*args, timeout=timeout, **kwargs)
    monkeypatch.setattr(office.subprocess, "Popen", ChildFirst)
    book = tmp_path / "b.xlsx"
    Workbook().save(book)
    start = time.monotonic()
    try:
        with pytest.raises(office.OfficeFailed, match="did not finish converting b.xlsx"):
            office.recalculate(book, tmp_path / "out")
        # not the child's own end: it outlives the hang guard, which a 1 s time-out undercuts
        assert time.monotonic() - start < HANG_GUARD_S
        wait_until(lambda: gone(said_pids(child_pid, 1)[0]), "the end of the launcher's child")
    finally:
        for pid in said_pids(child_pid, 1) or []:   # a failure leaves nothing running
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def _private_tempdir(monkeypatch, tmp_path: Path) -> Path:
    """Point tempfile at a folder of this test's own, to see what is left in it."""
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    return scratch


@pytest.mark.parametrize("value,expected", [
    (0.1, ("", b"0.1")), (3, ("", b"3.0")), (-1e-300, ("", b"-1e-300")),
    (float("nan"), ("e", b"#NUM!")), (True, ("b", b"1")), ("#N/A", ("e", b"#N/A")),
    (office.CellError("#DIV/0!"), ("e", b"#DIV/0!")), ("a<b & c", ("str", b"a&lt;b &amp; c"))])
def test_encode_value(value, expected):
    assert cached.encode_value(value) == expected


def test_full_calc_on_load():
    ns = b'<workbook xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
    add = cached.full_calc_on_load(ns + b"<sheets/><definedNames/><extLst/></workbook>")
    assert add == ns + b'<sheets/><definedNames/><calcPr fullCalcOnLoad="1"/><extLst/></workbook>'
    keep = cached.full_calc_on_load(ns + b'<calcPr calcId="191029" fullCalcOnLoad="0"/></workbook>')
    assert b'<calcPr calcId="191029" fullCalcOnLoad="1" />' in keep


def _zip_with_sheet(path: Path, sheet_xml: bytes) -> None:
    """A minimal package: enough for cached.py, which reads only these three parts."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("xl/workbook.xml",
                   '<workbook xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main" '
                   'xmlns:r="http://schemas.openxmlformats.org/officeDocument/2006/relationships">'
                   '<sheets><sheet name="S &amp; T" sheetId="1" r:id="rId7"/></sheets></workbook>')
        z.writestr("xl/_rels/workbook.xml.rels",
                   '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/'
                   'relationships"><Relationship Id="rId7" Target="worksheets/other.xml" '
                   'Type="x"/></Relationships>')
        z.writestr("xl/worksheets/other.xml", sheet_xml)


def test_cells_rewritten_exactly(tmp_path):
    """Prefixes, shared formulas, stale values and types, and cells that must stay as they are."""
    sheet = (b'<x:worksheet xmlns:x="http://schemas.openxmlformats.org/spreadsheetml/2006/main">'
             b'<x:cols><x:col min="1" max="1"/></x:cols><x:sheetData><x:row r="1">'
             b'<x:c r="A1" s="2"><x:f t="shared" ref="A1:A2" si="0">B1*2</x:f><x:v/></x:c>'
             b'<x:c r="A2" t="str" s=\'3\'><x:f t="shared" si="0"/><x:v>old</x:v></x:c>'
             b'<x:c r="A3"><x:f>NA()</x:f></x:c>'
             b'<x:c r="A4" t="s"><x:v>0</x:v></x:c><x:c r="A5"/>'
             b'<x:c r="A6"><x:f>1/0</x:f><x:v>9</x:v></x:c>'
             b'</x:row></x:sheetData></x:worksheet>')
    src, out = tmp_path / "in.xlsx", tmp_path / "out.xlsx"
    _zip_with_sheet(src, sheet)
    values = {("S & T", "A1"): 4.25, ("S & T", "A2"): 7, ("S & T", "A3"): "#N/A",
              ("S & T", "A4"): 99.0, ("S & T", "A5"): 1.0}
    assert package.add_cached_values(src, out, values) == 3
    xml = zipfile.ZipFile(out).read("xl/worksheets/other.xml")
    assert (b'<x:c r="A1" s="2"><x:f t="shared" ref="A1:A2" si="0">B1*2</x:f>'
            b'<x:v>4.25</x:v></x:c>') in xml
    assert b'<x:c r="A2" s=\'3\'><x:f t="shared" si="0"/><x:v>7.0</x:v></x:c>' in xml
    assert b'<x:c r="A3" t="e"><x:f>NA()</x:f><x:v>#N/A</x:v></x:c>' in xml
    assert b'<x:c r="A4" t="s"><x:v>0</x:v></x:c><x:c r="A5"/>' in xml      # no formula
    assert b'<x:c r="A6"><x:f>1/0</x:f><x:v>9</x:v></x:c>' in xml            # no value given
    assert xml.startswith(b'<x:worksheet') and b"<x:cols><x:col min" in xml


def test_large_sheet_is_streamed_quickly(tmp_path):
    """20 columns × 3,601 rows, the size of a fine stroke sweep, in a few seconds."""
    rows, cols = 3601, 20
    head = b'<worksheet xmlns="http://schemas.openxmlformats.org/spreadsheetml/2006/main"><sheetData>'
    body = b"".join(
        b'<row r="%d">' % r + b"".join(
            b'<c r="%s%d" s="1"><f>SQRT(ABS(COS(RADIANS($A%d))*%d))+0*LONGTEXT_PADDING_PADDING'
            b'_PADDING_PADDING</f><v/></c>' % (openpyxl.utils.get_column_letter(c).encode(), r, r, c)
            for c in range(1, cols + 1)) + b"</row>"
        for r in range(1, rows + 1))
    src, out = tmp_path / "big.xlsx", tmp_path / "big-out.xlsx"
    _zip_with_sheet(src, head + body + b"</sheetData></worksheet>")
    values = {("S & T", f"{openpyxl.utils.get_column_letter(c)}{r}"): r * 0.5 + c
              for r in range(1, rows + 1) for c in range(1, cols + 1)}
    start = time.process_time()          # CPU time: another process's load does not count
    assert package.add_cached_values(src, out, values) == rows * cols
    assert time.process_time() - start < 20
    xml = zipfile.ZipFile(out).read("xl/worksheets/other.xml")
    assert xml.count(b"<v>") == rows * cols and b'<c r="T3601" s="1"><f>' in xml
    assert b"<v>1820.5</v></c></row></sheetData>" in xml


def test_print_setup_keeps_charts_whole():
    """Mechanism: the drawing starts a page of its own; every visible sheet has a scale."""
    t = _template("fourbar")
    b = workbook.build(t)
    charts.add_charts(b, t, b.model)
    pages.apply_print_setup(b.workbook)
    mech = b.workbook[MECH]
    chart_col = openpyxl.utils.column_index_from_string(
        re.match(r"[A-Z]+", mech._charts[0].anchor).group())
    assert chart_col - 1 in [br.id for br in mech.col_breaks.brk]
    for ws in b.workbook.worksheets:
        if ws.sheet_state == "visible":
            assert ws.page_setup.orientation in ("portrait", "landscape")
            assert min(pages.SCALES) <= ws.page_setup.scale <= 100
        else:
            assert ws.page_setup.scale is None
    assert b.workbook[SWEEP].print_title_rows


# ---------------------------------------------------------------- with LibreOffice
@pytest.fixture(scope="module")
def lo_books(needs, tmp_path_factory):
    """(Built, path, LibreOffice values) for the four-bar on its defaults and non-Grashof, and
    for the boom driven by a linear actuator (an input that is a length)."""
    needs("libreoffice", "pdftoppm")
    return {case: _built_and_values(name, sets, tmp_path_factory.mktemp(case))
            for case, name, sets in (("default", "fourbar", ()),
                                     ("non-grashof", "fourbar", NON_GRASHOF),
                                     ("boom", "boom-cylinder", ()))}


@pytest.mark.libreoffice
def test_errors_as_libreoffice_caches_them(needs, tmp_path):
    needs("libreoffice", "pdftoppm")
    wb = Workbook()
    ws = wb.active
    for i, f in enumerate(["=NA()", "=1/0", "=ACOS(2)", '="a"+1', '="abc"', "=1/3",
                           "=NOSUCH()", "=ATAN2(0,0)"], start=1):
        ws[f"A{i}"] = f
    wb.save(tmp_path / "e.xlsx")
    v = {cell: value for (_, cell), value in office.recalculated_values(tmp_path / "e.xlsx").items()}
    assert [office.error_code(v[f"A{i}"]) for i in range(1, 5)] == [
        "#N/A", "#DIV/0!", "#NUM!", "#VALUE!"]
    assert isinstance(v["A1"], office.CellError) and v["A1"] == "#N/A"
    assert v["A5"] == "abc" and not office.is_error(v["A5"])
    assert v["A6"] == pytest.approx(1 / 3, rel=1e-14)
    assert v["A7"] == "#NAME?"
    assert v["A8"] == 0.0          # LibreOffice: 0; Excel and `formulas`: #DIV/0!


@pytest.mark.libreoffice
def test_stale_cached_values_are_recalculated(needs, tmp_path):
    """A wrong cached value and no fullCalcOnLoad: LibreOffice's default profile keeps the 42
    (measured); the private profile (OOXMLRecalcMode = 0) must recalculate."""
    needs("libreoffice", "pdftoppm")
    assert office.recalculated_values(stale_book(tmp_path))[("Sheet", "B1")] == 6.0


def stale_book(tmp_path) -> Path:
    """B1 = A1*3 with A1 = 2, its cached value a wrong 42, and no fullCalcOnLoad: an
    application that shows the cache shows 42."""
    wb = Workbook()
    wb.active["A1"] = 2
    wb.active["B1"] = "=A1*3"
    wb.save(tmp_path / "fresh.xlsx")
    package.add_cached_values(tmp_path / "fresh.xlsx", tmp_path / "cached.xlsx",
                             {("Sheet", "B1"): 42.0})
    with zipfile.ZipFile(tmp_path / "cached.xlsx") as zin, \
            zipfile.ZipFile(tmp_path / "stale.xlsx", "w", zipfile.ZIP_DEFLATED) as zout:
        for name in zin.namelist():
            data = zin.read(name)
            if name == "xl/workbook.xml":
                data = data.replace(b' fullCalcOnLoad="1"', b"")
            zout.writestr(name, data)
    assert openpyxl.load_workbook(tmp_path / "stale.xlsx", data_only=True).active["B1"].value == 42
    return tmp_path / "stale.xlsx"


@pytest.mark.libreoffice
@pytest.mark.parametrize("case", ["default", "non-grashof", "boom"])
def test_libreoffice_matches_reference(lo_books, case):
    """Every formula cell as LibreOffice computes it, against the generic reference: the sweep table
    directly here, and every block that verify knows (position, joints, constants) through it."""
    b, _, values = lo_books[case]
    formulas = _formula_cells(b.workbook)
    assert all(k in values for k in formulas), "a formula cell has no value"

    worst, na_rows = _sweep_against_reference(b, values)
    assert worst <= REL_TOL
    assert (na_rows > 0) == (case == "non-grashof")

    checks = verifier.check_book(b.workbook, b.record, values, office.is_error, office.error_code,
                               tol=REL_TOL, relative=True)
    bad = [f"{c.block}/{c.name}: {m.sheet}!{m.cell} expected {m.expected!r}, LibreOffice "
           f"{m.got!r}" for c in checks for m in c.mismatches]
    assert not bad, "\n".join(bad[:8])
    assert sum(c.cells for c in checks) > 1000


def _sweep_against_reference(b, values) -> tuple[float, int]:
    """The largest relative difference over the sweep columns the reference also computes
    (angles compared modulo a turn), and how many rows the reference says cannot close."""
    import numpy as np
    sweep = b.meta["sweep"]
    first, last = sweep["rows"]
    ws = b.workbook[sweep["sheet"]]
    angles = np.array([ws[f"A{r}"].value for r in range(first, last + 1)], dtype=float)
    ref = verifier.Reference(b.record).solve(verifier.inputs_of(b.workbook, b.record), angles)
    worst, compared = 0.0, 0
    for key, letter in sweep["columns"].items():
        degrees = key.endswith("_deg")
        base = key[:-4] if degrees else key
        if base not in ref or base == b.meta["input"]:
            continue
        expected = np.broadcast_to(np.asarray(ref[base], dtype=float), angles.shape)
        expected = np.degrees(expected) if degrees else expected
        unit = "deg" if degrees else b.model.get(base).unit
        period = {"deg": 360.0, "rad": 2 * np.pi}.get(unit)
        for r, exp in zip(range(first, last + 1), expected):
            got = values[(sweep["sheet"], f"{letter}{r}")]
            compared += 1
            if np.isnan(exp):
                assert office.error_code(got) == "#N/A", (key, r, got)
                continue
            assert isinstance(got, float), (key, r, got)
            diff = got - exp
            if period:
                diff = (diff + period / 2) % period - period / 2
            worst = max(worst, abs(diff) / max(1.0, abs(exp)))
    assert compared >= 10 * len(angles), "too few sweep cells compared"
    return worst, int((~np.asarray(ref["assembled"], dtype=bool)).sum())


@pytest.mark.libreoffice
def test_cached_values_round_trip(lo_books, tmp_path):
    b, path, values = lo_books["non-grashof"]
    out = tmp_path / "cached.xlsx"
    formulas = _formula_cells(b.workbook)
    assert package.add_cached_values(path, out, values) == len(formulas)

    shown = openpyxl.load_workbook(out, data_only=True)
    kinds = set()
    for (sheet, cell) in formulas:
        v = shown[sheet][cell].value
        expected = values[(sheet, cell)]
        if office.is_error(expected):
            kinds.add("error")
            assert v == office.error_code(expected)
        elif isinstance(expected, float):
            kinds.add("number")
            assert isinstance(v, float) and v == expected
        else:                           # text results: "yes", "—"; "" reads back as None
            kinds.add("text")
            assert v == (expected or None)
    assert {"error", "number"} <= kinds
    again = openpyxl.load_workbook(out)
    assert _formula_cells(again) == formulas
    assert set(again.defined_names) == set(b.workbook.defined_names)

    before, after = zipfile.ZipFile(path), zipfile.ZipFile(out)
    assert before.namelist() == after.namelist()
    sheets = set(package.sheet_parts(before).values())
    for name in before.namelist():
        if name not in sheets and name != "xl/workbook.xml":
            assert before.read(name) == after.read(name), f"{name} changed"
    wb_xml = after.read("xl/workbook.xml").decode()
    assert re.search(r'<calcPr[^>]*fullCalcOnLoad="1"', wb_xml)
    assert (re.search(r"<definedNames>.*</definedNames>", wb_xml).group()
            == re.search(r"<definedNames>.*</definedNames>",
                         before.read("xl/workbook.xml").decode()).group())

    # LibreOffice still opens it and, recalculating, gets the same numbers.
    again_values = office.recalculated_values(out)
    for key in formulas:
        assert _same(again_values[key], values[key]), key


@pytest.mark.libreoffice
def test_cached_book_with_charts_prints(needs, tmp_path):
    needs("libreoffice", "pdftoppm")
    path = _book_with_charts("fourbar", tmp_path)
    values = office.recalculated_values(path)
    out = tmp_path / "fourbar-cached.xlsx"
    package.add_cached_values(path, out, values)
    pdf = office.to_pdf(out, tmp_path / "pdf")
    text = subprocess.run(["pdftotext", str(pdf), "-"], capture_output=True, text=True,
                          check=True).stdout
    for title in ("Coupler curve of C", "Output angles and transmission angle", "x [mm]"):
        assert title in text, f"chart text {title!r} not printed"


@pytest.mark.libreoffice
@pytest.mark.slow
@pytest.mark.parametrize("name", ["fourbar", "pump"])
def test_preview_pages_are_pictures(needs, name, tmp_path, monkeypatch):
    needs("libreoffice", "pdftoppm")
    book = _book_with_charts(name, tmp_path)
    scratch = _private_tempdir(monkeypatch, tmp_path)
    pages = preview.preview(book, tmp_path / "png", dpi=30)
    assert not any(scratch.iterdir()), "a temporary folder was left behind"
    assert len(pages) >= 4 and all(p.suffix == ".png" for p in pages)
    for page in pages:
        ink = _ink(page)
        assert 0.002 < ink < 0.6, f"{page.name}: {ink:.1%} ink, blank or black"


# ---------------------------------------------------------------- preview by sheet
def test_a_sheet_alone_is_the_only_visible_one_and_prints_no_other(tmp_path):
    """The copy preview prints one sheet from: read back by openpyxl, only that sheet is
    visible and active, and no hidden sheet keeps a print area (LibreOffice prints those)."""
    book = _book_with_charts("fourbar", tmp_path)
    assert preview.visible_sheets(book) == [ws.title for ws in openpyxl.load_workbook(
        book).worksheets if ws.sheet_state == "visible"]
    assert {"Mechanism", "Drawing data"} < set(preview.visible_sheets(book))
    copy = preview._only_sheets(book, ["Drawing data"], tmp_path / "one")
    wb = openpyxl.load_workbook(copy)
    assert [ws.title for ws in wb.worksheets if ws.sheet_state == "visible"] == ["Drawing data"]
    assert wb.active.title == "Drawing data"
    for ws in wb.worksheets:
        if ws.title != "Drawing data":
            assert not ws.print_area and not ws.print_title_rows, ws.title
    assert wb["Drawing data"].print_title_rows.replace("$", "") == "3:4"
    assert preview._file_word("Drawing data") == "Drawing_data"


@pytest.mark.libreoffice
@pytest.mark.slow
def test_preview_prints_the_chosen_sheets_named_by_sheet_with_the_pdf(needs, tmp_path, capsys):
    needs("libreoffice", "pdftoppm")
    book = _book_with_charts("fourbar", tmp_path)
    out = tmp_path / "pictures"
    assert cli.main(["preview", str(book), "--sheet", "Drawing data", "--sheet", "Mechanism",
                     "--dpi", "40", "-o", str(out)]) == 0
    pdf = out / f"{book.stem}.pdf"
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pdf.is_file() and pngs[0] == f"{book.stem}-Drawing_data-1.png"
    assert f"{book.stem}-Mechanism-1.png" in pngs
    assert all(re.fullmatch(rf"{book.stem}-(Mechanism|Drawing_data)-\d+\.png", p) for p in pngs)
    # poppler reads the kept PDF: the two sheets in the book's order, no other, one PNG a page
    text = subprocess.run(["pdftotext", str(pdf), "-"], capture_output=True, text=True,
                          check=True).stdout
    footers = re.findall(r"^(.+), page \d+ of \d+$", text, flags=re.M)
    assert footers and set(footers) == {"Mechanism", "Drawing data"}
    assert footers.index("Drawing data") > footers.index("Mechanism")
    assert len(footers) == len(pngs)
    width, height, _, _ = _png_rgb(out / f"{book.stem}-Mechanism-1.png")
    assert abs(max(width, height) - 29.7 / 2.54 * 40) <= 2        # A4 at 40 dpi


def test_preview_refuses_a_sheet_the_book_lacks_in_one_line(tmp_path, capsys):
    book = _book_with_charts("fourbar", tmp_path)
    assert cli.main(["preview", str(book), "--sheet", "Grid"]) == 2
    err = capsys.readouterr().err
    assert "--sheet: fourbar-charts.xlsx has no visible sheet 'Grid'" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "fourbar-charts_preview").exists()
