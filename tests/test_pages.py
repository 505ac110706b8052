"""Pages a person reads (issue 16): on the Sweep and Motion sheets every label breaks only
between words and shows all its lines, and every column header fits on one line — measured
with the font LibreOffice draws here (DejaVu Sans: its glyphs are wider than Calibri's, the
font Excel sizes columns by), not with the writer's own estimate."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import built

from linkbook import templates

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
