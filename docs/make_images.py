"""Remake the pictures in docs/images from the bundled books, as LibreOffice prints them.

    python docs/make_images.py            # needs LibreOffice and pdftoppm (linkbook preview)

Each picture is cut from a printed page: a book's drawing (found by its blue grid), the whole
Mechanism page of the four-bar, the four-bar's first Charts page with a drawing, the page of
the pump's family chart, the slider-crank's page with its driving torque, function-log10's
drawing of its designed linkage at the precision positions.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageOps

from linkbook.book import builder
from linkbook.book import charts
from linkbook.apps import preview
from linkbook.language import templates

IMAGES = Path(__file__).resolve().parent / "images"
DRAWINGS = ("boom-cylinder", "garage-door", "hoeken", "jansen", "toggle-press", "triad-sixbar",
            "watt-sixbar", "whitworth")
DPI = 110


def pages(name: str, tmp: Path, sheets=("Mechanism",), dpi: int = DPI) -> list[Path]:
    """The printed pages of the named sheets of a freshly built bundled book."""
    built, _ = builder.make(templates.load(name))
    path = tmp / f"{name}.xlsx"
    built.workbook.save(path)
    return preview.preview(path, tmp / name, dpi=dpi, sheets=list(sheets))


def synthesis_positions(tmp: Path) -> None:
    """The synthesis books' designed linkage at its precision positions (poses), cut from
    each Synthesis page (the whole sheet on one page: printed finer, so that the cut reads),
    and motion-3pose's whole Synthesis page."""
    for name in ("function-log10", "motion-3pose"):
        page = Image.open(pages(name, tmp, ("Synthesis",), dpi=3 * DPI)[0])
        page.crop(drawing_box(page)).save(IMAGES / f"{name}-positions.png")
    printed = page.convert("L").point(lambda v: 255 if v > 250 else 0)   # motion-3pose's page
    whole = page.crop(ImageOps.invert(printed).getbbox())
    whole.thumbnail((1800, 1800))
    whole.save(IMAGES / "motion-3pose-synthesis.png")


def drawing_box(page: Image.Image) -> tuple[int, int, int, int] | None:
    """The box of the framed chart on a page, from its grid (the plot area's place in the
    chart is fixed: charts.SIDE, charts.WIDTH_RATIO and the layout's left and top)."""
    rgb = np.asarray(page.convert("RGB"), dtype=int)
    grid = np.array([int(charts.GRID_COLOUR[i:i + 2], 16) for i in (0, 2, 4)])
    mask = (np.abs(rgb - grid) <= 30).all(axis=2)
    cols = np.flatnonzero(mask.sum(axis=0) > DPI)
    rows = np.flatnonzero(mask.sum(axis=1) > DPI)
    if cols.size < 2 or rows.size < 2:
        return None
    side = rows[-1] - rows[0]
    height = side / charts.SIDE
    width = height * charts.WIDTH_RATIO
    left = cols[0] - 0.06 * width
    top = rows[0] - 0.15 * height
    return (max(0, int(left) - 4), max(0, int(top) - 4), int(left + width) + 4,
            int(top + height) + 4)


def colourful(page: Image.Image) -> int:
    """Pixels of clear colour (the curves of a chart), not grey or white."""
    rgb = np.asarray(page, dtype=int)
    return int(((rgb.max(axis=2) - rgb.min(axis=2)) > 60).sum())


def page_with(pngs: list[Path], text: str) -> Path:
    """The first of a preview's pages whose printed text holds `text` (pdftotext on the PDF
    the preview wrote beside them: BOOK.pdf, its pages in the order of the pictures)."""
    import subprocess
    pdf = next(pngs[0].parent.glob("*.pdf"))
    for number, png in enumerate(pngs, start=1):
        printed = subprocess.run(["pdftotext", "-f", str(number), "-l", str(number), str(pdf),
                                  "-"], capture_output=True, text=True, check=True).stdout
        if text in printed:
            return png
    raise SystemExit(f"no page of {pdf.name} shows {text!r}")


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        first = pages("fourbar", tmp, ("Mechanism", "Charts"))
        Image.open(first[0]).save(IMAGES / "fourbar-mechanism.png")
        chart_pages = [p for p in first[1:] if drawing_box(Image.open(p))]
        Image.open(chart_pages[0]).save(IMAGES / "fourbar-charts.png")
        grid = [Image.open(p).convert("RGB") for p in pages("pump", tmp, ("Grid",))]
        max(grid, key=colourful).save(IMAGES / "pump-family.png")      # the family chart
        # the Charts sheet's page with the driving torque, found by its chart's title
        forces = pages("slider-crank", tmp, ("Charts",))
        Image.open(page_with(forces, "Driving effort")).save(IMAGES / "slider-crank-forces.png")
        for name in DRAWINGS:
            page = Image.open(pages(name, tmp)[0])
            page.crop(drawing_box(page)).save(IMAGES / f"{name}-mechanism.png")
            print(f"wrote {IMAGES / name}-mechanism.png")
        synthesis_positions(tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
