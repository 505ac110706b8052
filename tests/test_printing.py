"""Pages a teacher prints (issue 40): every bundled Mechanism sheet — inputs, current position,
joints table, drawing and geometry summary — on one landscape page, and the inputs' labels on
one line (a label wrapped into a second line that Calibri or Carlito draws on one left a
half-empty row after each inertia and torque input)."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import built

from linkbook.language import templates
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
def test_the_mechanism_sheet_prints_on_one_page(needs, tmp_path, name):
    """LibreOffice's own print of the sheet: one page (these four printed on two before)."""
    from linkbook.apps.preview import preview
    from linkbook.book import builder
    needs("libreoffice", "pdftoppm")
    path = tmp_path / f"{name}.xlsx"
    builder.build_file(templates.with_overrides(templates.load(name), [], None, None), path)
    pages = preview(path, tmp_path / "pages", dpi=20, sheets=["Mechanism"])
    assert [p.name for p in pages] == [f"{name}-Mechanism-1.png"]


@pytest.mark.slow
@pytest.mark.libreoffice
def test_a_five_degree_fourbar_prints_on_at_most_thirty_pages(needs, tmp_path):
    """The bundled four-bar (5°, forces): every visible sheet, as LibreOffice prints it."""
    from linkbook.apps.preview import preview
    from linkbook.book import builder
    needs("libreoffice", "pdftoppm")
    path = tmp_path / "fourbar.xlsx"
    builder.build_file(templates.with_overrides(templates.load("fourbar"), [], None, None), path)
    pages = preview(path, tmp_path / "pages", dpi=20)
    assert len(pages) <= 30, [p.name for p in pages]
