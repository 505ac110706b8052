"""Pages a teacher prints (issue 40): every bundled Mechanism sheet — inputs, current position,
joints table, drawing and geometry summary — on one landscape page, and the inputs' labels on
one line (a label wrapped into a second line that Calibri or Carlito draws on one left a
half-empty row after each inertia and torque input)."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from conftest import built

from linkbook.language import templates
from linkbook.language.forces import FORCE
from linkbook.book.style import text_width

BUNDLED = [p.stem for p in templates.bundled()]


@pytest.mark.parametrize("name", BUNDLED)
def test_the_mechanism_sheet_is_set_to_one_landscape_page(name):
    ws = built(name)[0].workbook["Mechanism"]
    setup = ws.page_setup
    assert ws.sheet_properties.pageSetUpPr.fitToPage
    assert (setup.orientation, setup.fitToWidth, setup.fitToHeight) == ("landscape", 1, 1)
    assert not ws.row_breaks.brk and not ws.col_breaks.brk


@pytest.mark.parametrize("name", BUNDLED)
def test_the_input_labels_are_on_one_line(name):
    """Each input's label fits its column on one line in DejaVu Sans (the widest of the fonts a
    book is drawn with): no row is made taller for it."""
    b, _ = built(name)
    ws = b.workbook["Mechanism"]
    width = ws.column_dimensions["A"].width
    for info in b.record.inputs.values():
        row = int(info.cell[1:])
        label = ws[f"A{row}"].value
        assert text_width(label) <= width, (label, width)


@pytest.mark.slow
@pytest.mark.libreoffice
@pytest.mark.parametrize("name", ["pump", "toggle-press", "jansen", "watt-sixbar"])
def test_the_mechanism_sheet_prints_on_one_page(tmp_path, name):
    """LibreOffice's own print of the sheet: one page (these four printed on two before)."""
    from linkbook.apps.preview import preview
    from linkbook.book import builder
    from linkbook.engine import office
    if not office.soffice_path() or not shutil.which("pdftoppm"):
        if os.environ.get("CI"):
            pytest.fail("CI needs soffice and pdftoppm: .ci/run installs them")
        pytest.skip("needs soffice and pdftoppm")
    path = tmp_path / f"{name}.xlsx"
    builder.build_file(templates.with_overrides(templates.load(name), [], None, None), path)
    pages = preview(path, tmp_path / "pages", dpi=20, sheets=["Mechanism"])
    assert [p.name for p in pages] == [f"{name}-Mechanism-1.png"]


@pytest.mark.slow
@pytest.mark.libreoffice
def test_a_five_degree_fourbar_prints_on_at_most_thirty_pages(tmp_path):
    """The bundled four-bar (5°, forces): every visible sheet, as LibreOffice prints it."""
    from linkbook.apps.preview import preview
    from linkbook.book import builder
    from linkbook.engine import office
    if not office.soffice_path() or not shutil.which("pdftoppm"):
        if os.environ.get("CI"):
            pytest.fail("CI needs soffice and pdftoppm: .ci/run installs them")
        pytest.skip("needs soffice and pdftoppm")
    path = tmp_path / "fourbar.xlsx"
    builder.build_file(templates.with_overrides(templates.load("fourbar"), [], None, None), path)
    pages = preview(path, tmp_path / "pages", dpi=20)
    assert len(pages) <= 30, [p.name for p in pages]


FORCE_BOOKS = [n for n in BUNDLED if templates.load(n).mechanism.build().of_role(FORCE)]


@pytest.mark.parametrize("name", FORCE_BOOKS)
def test_the_forces_summary_prints_with_no_input_column_beside_it(name):
    """Pages repeat the input column (A) on every page of the Forces sheet: the summary stands
    where column A is empty (under the table), so no θ12 prints beside a summary line
    (`60.000 T12: RMS 0.089 N·m` before), and inside the first print range."""
    from openpyxl.utils.cell import coordinate_from_string, range_boundaries
    b, _ = built(name)
    ws = b.workbook["Forces"]
    assert ws.print_title_cols == "$A:$A"
    rows = {coordinate_from_string(c["cell"])[1] for c in b.meta["forces"]["summary"].values()}
    for r in range(min(rows) - 1, max(rows) + 1):
        assert ws.cell(r, 1).value is None, (r, ws.cell(r, 1).value)
    first_range = str(ws.print_area).split(",")[0].split("!")[-1]
    c0, r0, c1, r1 = range_boundaries(first_range.replace("$", ""))
    for key, cell in b.meta["forces"]["summary"].items():
        letter, row = coordinate_from_string(cell["cell"])
        col = range_boundaries(f"{letter}1")[0]
        assert c0 <= col <= c1 and r0 <= row <= r1, (key, cell["cell"], first_range)


@pytest.mark.parametrize("name", FORCE_BOOKS)
def test_no_page_break_cuts_the_forces_summary(name):
    """The summary, its title to the mean line's cells, on one page."""
    from linkbook.book.forces import summary_rows
    b, _ = built(name)
    first, last = summary_rows(b.meta["forces"])
    breaks = [brk.id for brk in b.workbook["Forces"].row_breaks.brk]   # the last row above it
    assert not [r for r in breaks if first <= r < last], (first, last, breaks)
