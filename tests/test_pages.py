"""Pages a person reads (issue 16): on the Sweep and Motion sheets every label breaks only
between words and shows all its lines, and every column header fits on one line — measured
with the font LibreOffice draws here (DejaVu Sans: its glyphs are wider than Calibri's, the
font Excel sizes columns by), not with the writer's own estimate."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import built

from linkbook.language import templates

FONTS = Path("/usr/share/fonts/truetype/dejavu")
PX_PER_PT = 96 / 72


def _font(name: str):
    pil = pytest.importorskip("PIL.ImageFont")
    path = FONTS / name
    if not path.is_file():
        pytest.skip(f"{path} is not installed")
    return pil.truetype(str(path), round(11 * PX_PER_PT))


def _column_px(ws, letter: str) -> float:
    """Excel's rule: width w (digits of Calibri 11) is w·7 + 5 pixels; minus 2 px of padding
    each side as LibreOffice draws a cell."""
    width = ws.column_dimensions[letter].width or 8.43
    return width * 7 + 5 - 4


def _lines(text: str, room: float, font) -> int:
    lines: list[str] = []
    for word in text.split():
        if lines and font.getlength(f"{lines[-1]} {word}") <= room:
            lines[-1] += f" {word}"
        else:
            lines.append(word)
    return max(1, len(lines))


@pytest.mark.parametrize("name", [p.stem for p in templates.bundled()])
def test_labels_and_headers_of_the_tables_fit_their_cells(name):
    b, _ = built(name)
    italic, bold = _font("DejaVuSans-Oblique.ttf"), _font("DejaVuSans-Bold.ttf")
    for sheet in ("Sweep", "Motion"):
        if sheet not in b.workbook.sheetnames:
            continue
        ws = b.workbook[sheet]
        height_pt = ws.row_dimensions[3].height or 15
        for cell in ws[4]:
            if not isinstance(cell.value, str):
                continue
            room = _column_px(ws, cell.column_letter)
            assert bold.getlength(cell.value) <= room, (sheet, cell.coordinate, cell.value)
            label = ws.cell(3, cell.column).value or ""
            for word in label.split():
                assert italic.getlength(word) <= room, (sheet, cell.coordinate, word)
            lines = _lines(label, room, italic)
            assert lines * 15 <= height_pt + 1e-9, (sheet, cell.coordinate, label, lines)


FONT_FILES = {(False, False): "DejaVuSans.ttf", (True, False): "DejaVuSans-Bold.ttf",
              (False, True): "DejaVuSans-Oblique.ttf", (True, True): "DejaVuSans-BoldOblique.ttf"}


def _cell_font(cell):
    pil = pytest.importorskip("PIL.ImageFont")
    f = cell.font
    path = FONTS / FONT_FILES[(bool(f.b), bool(f.i))]
    if not path.is_file():
        pytest.skip(f"{path} is not installed")
    return pil.truetype(str(path), round(float(f.sz or 11) * PX_PER_PT)), float(f.sz or 11)


def _room(ws, cell, merged: dict) -> float:
    """Pixels a text may take: its merged range, else its column and, unless it wraps, the
    empty cells to its right (text overflows into them)."""
    from openpyxl.utils import get_column_letter
    if cell.coordinate in merged:
        first, last = merged[cell.coordinate]
        return sum(_column_px(ws, get_column_letter(c)) + 4 for c in range(first, last + 1)) - 4
    room = _column_px(ws, cell.column_letter)
    if cell.alignment.wrap_text:
        return room
    step = -1 if cell.alignment.horizontal == "right" else 1     # right-aligned: it overflows left
    col = cell.column + step
    taken = {c for rng in ws.merged_cells.ranges if rng.min_row <= cell.row <= rng.max_row
             for c in range(rng.min_col, rng.max_col + 1)}
    last = ws.max_column
    while getattr(ws._cells.get((cell.row, col)), "value", None) is None and col not in taken \
            and 1 <= col <= last:
        room += _column_px(ws, get_column_letter(col)) + 4
        col += step
    return room


@pytest.mark.parametrize("name", [p.stem for p in templates.bundled()])
def test_every_text_on_the_mechanism_grid_and_drawing_sheets_fits(name):
    """Every text cell (labels, headers, notes, a formula's text result) shows whole: on one
    line within its column and the empty cells after it, or wrapped within its column or its
    merged cells into as many lines as its row is tall (LibreOffice does not grow a row of no
    set height to fit), no word wider than its room. Measured in DejaVu Sans."""
    b, values = built(name)
    for sheet in ("Mechanism", "Grid", "Stroke sweep", "Drawing data", "Charts"):
        if sheet not in b.workbook.sheetnames:
            continue
        ws = b.workbook[sheet]
        merged = {}
        for rng in ws.merged_cells.ranges:
            merged[f"{rng.start_cell.coordinate}"] = (rng.min_col, rng.max_col)
        for row in ws.iter_rows():
            for cell in row:
                text = values.get((sheet, cell.coordinate)) if cell.data_type == "f" \
                    else cell.value
                if not isinstance(text, str) or not text.strip():
                    continue
                font, size = _cell_font(cell)
                room = _room(ws, cell, merged)
                where = (sheet, cell.coordinate, text)
                if not (cell.alignment.wrap_text or cell.coordinate in merged):
                    assert font.getlength(text) <= room, where
                    continue
                assert all(font.getlength(w) <= room for w in text.split()), where
                height = ws.row_dimensions[cell.row].height or 15
                assert _lines(text, room, font) * 15 * size / 11 <= height + 1e-6, where


@pytest.mark.parametrize("name", [p.stem for p in templates.bundled()])
def test_no_chart_covers_a_used_cell(name):
    """Each chart's box (its anchor and size, in the column widths and row heights the sheet
    sets) holds no cell with a value: no chart is printed over data or labels."""
    from linkbook.book.pages import _chart_box
    b, _ = built(name)
    for ws in b.workbook.worksheets:
        for chart in ws._charts:
            c0, c1, r0, r1 = _chart_box(ws, chart)
            covered = [c.coordinate for (r, col), c in ws._cells.items()
                       if r0 <= r <= r1 and c0 <= col <= c1 and c.value not in (None, "")]
            assert not covered, (ws.title, chart.anchor, covered[:5])
