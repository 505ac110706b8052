"""Pages a teacher prints (issue 40): every bundled Mechanism sheet — inputs, current position,
joints table, drawing and geometry summary — on one landscape page, and the inputs' labels on
one line (a label wrapped into a second line that Calibri or Carlito draws on one left a
half-empty row after each inertia and torque input)."""
from __future__ import annotations

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


# ------------------------------------------------------------- no label clipped
# Text measured by the font files themselves (Pillow), not by the writer's width table: DejaVu
# Sans, the widest of the fonts a book is drawn with, 11 pt at 96 dpi hinted to 15 px, in
# digits of 7 px plus one for the cell's padding (how a column's width counts characters).
DEJAVU = Path("/usr/share/fonts/truetype/dejavu")
SLACK = 0.05          # a width is written to a tenth of a character


def _font_width():
    from PIL import ImageFont
    fonts = {bold: ImageFont.truetype(str(DEJAVU / name), 15)
             for bold, name in ((False, "DejaVuSans.ttf"), (True, "DejaVuSans-Bold.ttf"))}
    return lambda text, bold, size: fonts[bold].getlength(text) * size / 11 / 7 + 1.0


def _column(ws, c: int) -> float:
    from openpyxl.utils import get_column_letter
    d = ws.column_dimensions.get(get_column_letter(c))
    return d.width if d is not None and d.customWidth else 8.43


def _free(ws, r: int, c: int) -> bool:
    cell = ws._cells.get((r, c))
    return cell is None or cell.value is None


def _room(ws, r: int, first: int, last: int, horizontal) -> float:
    """The width a one-line text has: its cell (or merged cells), and where it is aligned
    left (or right) the empty cells it runs on over to the right (or left); centred, both."""
    room = sum(_column(ws, k) for k in range(first, last + 1))
    sides = {"right": (-1,), "center": (-1, 1), "centerContinuous": (-1, 1)}.get(horizontal, (1,))
    for step in sides:
        k = last + 1 if step > 0 else first - 1
        while 1 <= k <= 16384 and _free(ws, r, k) and room < 500:
            room += _column(ws, k)
            k += step
    return room


def clipped_labels(ws, width) -> list[tuple]:
    """Every text cell of the sheet that does not show whole: a wrapped one with a word wider
    than its column or more lines than its row is high; a one-line one wider than its room."""
    merged = {(m.min_row, m.min_col): m.max_col for m in ws.merged_cells.ranges}
    found = []
    for (r, c), cell in sorted(ws._cells.items()):
        text = cell.value
        if not isinstance(text, str) or cell.data_type == "f":
            continue
        bold = bool(cell.font and cell.font.b)
        size = float(cell.font.sz or 11) if cell.font else 11.0
        last = merged.get((r, c), c)
        if cell.alignment is not None and cell.alignment.wrap_text:
            room = sum(_column(ws, k) for k in range(c, last + 1)) + SLACK
            lines: list[str] = []
            for word in text.split():
                if width(word, bold, size) > room:
                    found.append((cell.coordinate, text, "a word wider than the column"))
                if lines and width(f"{lines[-1]} {word}", bold, size) <= room:
                    lines[-1] += f" {word}"
                else:
                    lines.append(word)
            d = ws.row_dimensions.get(r)
            height = d.ht if d is not None and d.ht else 15.0
            if len(lines) * 15.0 * size / 11 > height + 0.01:
                found.append((cell.coordinate, text, f"{len(lines)} lines in {height} pt"))
        elif width(text, bold, size) > _room(ws, r, c, last,
                                             cell.alignment.horizontal) + SLACK:
            found.append((cell.coordinate, text, "wider than its room"))
    return found


@pytest.mark.parametrize("name", BUNDLED)
def test_no_label_of_a_bundled_book_is_clipped(name):
    """Every visible sheet: headers, notes, the Sweep sheet's bookkeeping labels (`1 where
    every loop closes`, `last angle of a gap`: clipped before), the summaries' labels."""
    if not (DEJAVU / "DejaVuSans-Bold.ttf").exists():
        if os.environ.get("CI"):
            pytest.fail("CI needs fonts-dejavu-core")
        pytest.skip("needs DejaVu Sans to measure text")
    width = _font_width()
    b, _ = built(name)
    found = {ws.title: clipped_labels(ws, width) for ws in b.workbook.worksheets
             if ws.sheet_state == "visible"}
    assert not any(found.values()), {k: v for k, v in found.items() if v}


# ------------------------------------------------------------- the polar diagram
C = "{http://schemas.openxmlformats.org/drawingml/2006/chart}"
A = "{http://schemas.openxmlformats.org/drawingml/2006/main}"
XDR = "{http://schemas.openxmlformats.org/drawingml/2006/spreadsheetDrawing}"


def _saved_charts(book):
    """(chart XML root, its anchor's width / height) of every chart of a saved book."""
    import posixpath
    import re
    import zipfile
    from xml.etree import ElementTree as ET
    rel_id = "{http://schemas.openxmlformats.org/officeDocument/2006/relationships}id"
    out = []
    with zipfile.ZipFile(book) as z:
        drawings = [n for n in z.namelist() if re.fullmatch(r"xl/drawings/drawing\d+\.xml", n)]
        for drawing in drawings:
            rels = ET.fromstring(z.read(drawing.replace("drawings/", "drawings/_rels/") + ".rels"))
            target = {r.get("Id"): posixpath.normpath(posixpath.join(
                "xl/drawings", r.get("Target"))).lstrip("/") for r in rels}    # absolute or not
            for anchor in ET.fromstring(z.read(drawing)):
                chart, ext = anchor.find(f".//{C}chart"), anchor.find(f"{XDR}ext")
                if chart is not None:
                    root = ET.fromstring(z.read(target[chart.get(rel_id)]))
                    out.append((root, int(ext.get("cx")) / int(ext.get("cy"))))
    return out


@pytest.mark.parametrize("name", FORCE_BOOKS)
def test_the_polar_diagram_is_at_equal_scales(tmp_path, name):
    """Both axes scale to the same data (the square's corners (−R, −R), (R, R), drawn
    invisible, no legend entry) and neither has limits of its own, so each application gives
    both the same span; the plot area's box is square on the chart's anchor."""
    b, values = built(name)
    book = tmp_path / f"{name}.xlsx"
    b.workbook.save(book)
    polar = [(root, ratio) for root, ratio in _saved_charts(book)
             if "polar diagram" in "".join(root.itertext())]
    assert len(polar) == 1
    root, ratio = polar[0]
    series = root.findall(f".//{C}ser")
    assert len(series) == 3
    deleted = [e.find(f"{C}idx").get("val") for e in root.iter(f"{C}legendEntry")
               if e.find(f"{C}delete").get("val") in ("1", "true")]
    assert deleted == ["1", "2"]
    points = []
    for corner in series[1:]:          # one point each: no line, no marker
        assert corner.find(f"{C}spPr/{A}ln/{A}noFill") is not None
        assert corner.find(f"{C}marker/{C}symbol").get("val") == "none"
        point = []
        for axis in ("xVal", "yVal"):
            ref = corner.find(f"{C}{axis}/{C}numRef/{C}f").text     # 'Forces'!$B$101
            sheet, cells = ref.rsplit("!", 1)
            assert ":" not in cells
            point.append(values[(sheet.strip("'"), cells.replace("$", ""))])
        points.append(point)
    (x0, y0), (x1, y1) = points
    reach = max(abs(v) for k in ("shaking_x", "shaking_y")
                for v in _column_values(b, values, k))
    assert (x0, y0, x1, y1) == (-reach, -reach, reach, reach)
    for axis in root.iter(f"{C}valAx"):
        scaling = axis.find(f"{C}scaling")
        assert scaling.find(f"{C}min") is None and scaling.find(f"{C}max") is None
    layout = root.find(f"{C}chart/{C}plotArea/{C}layout/{C}manualLayout")
    assert layout.find(f"{C}layoutTarget").get("val") == "inner"
    w, h = (float(layout.find(f"{C}{k}").get("val")) for k in ("w", "h"))
    assert w * ratio == pytest.approx(h, rel=1e-3)


def _column_values(b, values, key):
    table = b.meta["forces"]
    r0, r1 = table["rows"]
    return [values[("Forces", f"{table['columns'][key]}{r}")] for r in range(r0, r1 + 1)]


# ------------------------------------------------------------- joint names on the drawing
@pytest.mark.parametrize("name", BUNDLED)
def test_every_joint_is_named_once_on_the_drawing(tmp_path, name):
    """The Mechanism sheet's drawing (chart XML of the saved book): per joint, as pylinkage
    labels them, one invisible one-point series out of the legend, named by the joints
    table's cell holding the joint's name and labelled with that name, drawn at a point the
    drawing maps from the same joints-table row (so it moves with its joint)."""
    import re
    b, _ = built(name)
    book = tmp_path / f"{name}.xlsx"
    b.workbook.save(book)
    drawing = [root for root, _ in _saved_charts(book)
               if "at the current" in "".join(root.itertext())]
    assert len(drawing) == 1
    root, mech, frames = drawing[0], b.workbook["Mechanism"], b.workbook["Drawing data"]
    deleted = {e.find(f"{C}idx").get("val") for e in root.iter(f"{C}legendEntry")
               if e.find(f"{C}delete").get("val") in ("1", "true")}
    named = []
    for ser in root.iter(f"{C}ser"):
        name_ref = ser.find(f"{C}tx/{C}strRef/{C}f")
        if name_ref is None or ser.find(f"{C}dLbls") is None:
            continue
        labels = ser.find(f"{C}dLbls")
        assert labels.find(f"{C}showSerName").get("val") == "1"
        assert labels.find(f"{C}showVal").get("val") == "0"
        assert ser.find(f"{C}spPr/{A}ln/{A}noFill") is not None
        assert ser.find(f"{C}marker/{C}symbol").get("val") == "none"
        assert ser.find(f"{C}idx").get("val") in deleted
        sheet, cell = name_ref.text.rsplit("!", 1)
        assert sheet.strip("'") == "Mechanism"
        row = int(re.fullmatch(r"\$M\$(\d+)", cell).group(1))
        for axis, column in (("xVal", "N"), ("yVal", "O")):    # the point drawn from that row
            point = ser.find(f"{C}{axis}/{C}numRef/{C}f").text.rsplit("!", 1)[1]
            formula = frames[point.replace("$", "")].value
            assert f"'Mechanism'!{column}{row}-" in formula, (point, formula, row)
        named.append(mech[f"M{row}"].value)
    assert sorted(named) == sorted(j.name for j in b.model.joints)
