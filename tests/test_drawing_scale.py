"""Drawings to scale that follow every edit (issue 16), measured where a person sees them: every
bundled book's drawing and coupler curves rendered by LibreOffice to PDF, as built and after an
edit in the book that doubles a link length. On the rendered page a grid square must be as wide
as it is tall (the same points per length unit on x and y, within 2 %), and the frame must show
all of its 10 × 10 squares; the edited book's mapped coordinates (what the charts draw) must all
lie inside the frame."""
from __future__ import annotations

import re
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import openpyxl
import pytest
from conftest import template

from linkbook.book import charts
from linkbook.engine import evaluator as engine
from linkbook.book import frames
from linkbook.engine import office
from linkbook.language.mechanisms import LENGTH_KIND
from linkbook.base.record import BuildRecord
from linkbook.base.sheets import read_meta
from linkbook.check.verifier import inputs_of

pytestmark = pytest.mark.libreoffice
DPI = 150
SCOUT_DPI = 30       # finds the pages to measure


def _bundled() -> list[str]:
    return sorted(p.stem for p in (Path(__file__).parents[1] / "templates").glob("*.toml"))


def _first_length(t) -> str | None:
    """The first length the user types in (a designed one is a formula of the task)."""
    return next((p.symbol for p in t.parameters
                 if p.kind == LENGTH_KIND and not p.designed_by), None)


# Each bundled book as built, and with its first input length doubled: a motion or path
# generation book has none (the Synthesis sheet designs every length; its drawings after an
# edit of the task are verify's, in tests/test_synthesis_dyads_book.py)
BOOKS = [(name, edit) for name in _bundled() for edit in (False, True)
         if not edit or _first_length(template(name)) is not None]
IDS = [f"{name}-{'link-doubled' if edit else 'built'}" for name, edit in BOOKS]


def _meta(path: Path) -> dict:
    wb = openpyxl.load_workbook(path, read_only=True)
    try:
        return read_meta(wb)
    finally:
        wb.close()


def _grid_lines(counts: np.ndarray) -> list[float]:
    """Centres of the runs of pixel columns (rows) that are mostly gridline (and long: a
    frame's side is over an inch at this resolution)."""
    hot = np.flatnonzero(counts > max(0.5 * counts.max(), DPI))
    runs = np.split(hot, np.flatnonzero(np.diff(hot) > 1) + 1)
    return [float(r.mean()) for r in runs if r.size]


def _grid_coloured(png) -> np.ndarray:
    """The page's pixels (True) in the frame's gridline colour."""
    from PIL import Image
    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=int)
    grid = np.array([int(charts.GRID_COLOUR[i:i + 2], 16) for i in (0, 2, 4)])
    return (np.abs(rgb - grid) <= 30).all(axis=2)


def _pages_in_grid_colour(pdf: Path, scratch: Path) -> list[int]:
    """The numbers of the pages that draw anything in the gridline colour, from a coarse
    render without anti-aliasing (a thin line keeps its colour at any resolution). Most pages
    of a book are tables; only these are worth rendering at full resolution."""
    stem = scratch / pdf.stem
    subprocess.run(["pdftoppm", "-png", "-r", str(SCOUT_DPI), "-aa", "no", "-aaVector", "no",
                    str(pdf), str(stem)], check=True)
    return [int(png.stem.rsplit("-", 1)[1]) for png in sorted(scratch.glob(f"{pdf.stem}-*.png"))
            if _grid_coloured(png).any()]


def _render(pdf: Path, pages: list[int], stem: Path) -> list[Path]:
    """These pages of the PDF as PNG files at DPI."""
    out = []
    for page in pages:
        subprocess.run(["pdftoppm", "-png", "-r", str(DPI), "-f", str(page), "-l", str(page),
                        "-singlefile", str(pdf), f"{stem}-{page}"], check=True)
        out.append(Path(f"{stem}-{page}.png"))
    return out


def _measure(png) -> tuple[float, float] | None:
    """(x, y) gridline spacing in pixels of the one framed chart on a page (None: no frame),
    from the outermost lines: to a fraction of a pixel."""
    mask = _grid_coloured(png)
    xs, ys = _grid_lines(mask.sum(axis=0)), _grid_lines(mask.sum(axis=1))
    if len(xs) < 3 or len(ys) < 3:
        # a frame is a grid both ways; a long flat curve in a colour near the grid's (a pin
        # load on the Forces charts) makes lines one way only
        return None
    return _spacing(xs, png), _spacing(ys, png)


def _spacing(lines: list[float], png) -> float:
    """A square's side from the frame's two edges, which must be 2·HALF squares apart (a link
    lying on a gridline may hide that one line: the squares are counted, not the lines)."""
    span = lines[-1] - lines[0]
    squares = round(span / float(np.median(np.diff(lines))))
    assert squares == 2 * frames.HALF, (png.name, lines)
    return span / squares


SHOWN = ("Mechanism", "Charts")      # the sheets with drawings: only they are printed


def _sheet_part(parts: dict[str, bytes], title: str) -> str:
    """The package part of the sheet of this title (workbook.xml's r:id, then its target)."""
    workbook = parts["xl/workbook.xml"].decode()
    rid = re.search(rf'<sheet\b[^>]*\bname="{title}"[^>]*\br:id="([^"]+)"', workbook)[1]
    rels = parts["xl/_rels/workbook.xml.rels"].decode()
    target = re.search(rf'<Relationship\b[^>]*\bTarget="([^"]+)"[^>]*\bId="{rid}"', rels)[1]
    return target.lstrip("/") if target.startswith("/") else f"xl/{target}"


def _only_shown(workbook: str) -> str:
    """workbook.xml with every sheet but SHOWN hidden."""
    def state(sheet: re.Match) -> str:
        tag = re.sub(r'\sstate="[^"]*"', "", sheet[0])
        hidden = re.search(r'\bname="([^"]+)"', tag)[1] not in SHOWN
        return tag.replace("<sheet ", '<sheet state="hidden" ', 1) if hidden else tag
    return re.sub(r"<sheet\b[^>]*/>", state, workbook)


def _doubled(sheet: str, cell: str) -> str:
    """The sheet's XML with the number in `cell` doubled, as a user would type it over."""
    new, count = re.subn(rf'(<c r="{cell}"[^>]*><v>)([^<]+)(</v>)',
                         lambda m: f"{m[1]}{2 * float(m[2])!r}{m[3]}", sheet)
    assert count == 1, f"no number in Mechanism!{cell}"
    return new


def _printable_copy(book: Path, out: Path, doubled: str | None) -> None:
    """A copy of the book as `linkbook build` wrote it, with only the SHOWN sheets visible and,
    given a Mechanism cell, the number there doubled: edited in the package's XML, as openpyxl
    would drop the charts if it saved the book."""
    with zipfile.ZipFile(book) as src:
        infos = src.infolist()
        parts = {info.filename: src.read(info) for info in infos}
    parts["xl/workbook.xml"] = _only_shown(parts["xl/workbook.xml"].decode()).encode()
    if doubled:
        mechanism = _sheet_part(parts, "Mechanism")
        parts[mechanism] = _doubled(parts[mechanism].decode(), doubled).encode()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in infos:
            dst.writestr(info, parts[info.filename])


@pytest.fixture(scope="module")
def rendered(needs, bundled_books, tmp_path_factory):
    """Each bundled book (conftest's), as built and with its first length doubled, printed to
    PDF (only the SHOWN sheets), and its pages that draw in the grid's colour rendered to PNG."""
    needs("libreoffice", "pdftoppm")
    tmp = tmp_path_factory.mktemp("scale")
    books = {}
    for name, edit in BOOKS:
        meta = _meta(bundled_books[name])
        cell = meta["inputs"][_first_length(template(name))]["cell"] if edit else None
        path = tmp / f"{name}-{'doubled' if edit else 'built'}.xlsx"
        _printable_copy(bundled_books[name], path, cell)
        books[(name, edit)] = (path, meta)
    # every book printed in one run of LibreOffice (one start-up, not one a book)
    pdfs = office.to_pdf_all([path for path, _ in books.values()], tmp / "pdf")
    (tmp / "scout").mkdir()
    (tmp / "png").mkdir()
    out = {}
    for ((name, edit), (path, meta)), pdf in zip(books.items(), pdfs):
        pages = _pages_in_grid_colour(pdf, tmp / "scout")
        out[(name, edit)] = (path, meta, _render(pdf, pages, tmp / "png" / path.stem))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name, edit", BOOKS, ids=IDS)
def test_every_drawing_is_to_scale_on_the_page(rendered, name, edit):
    path, meta, pages = rendered[(name, edit)]
    spacings = [m for page in pages if (m := _measure(page))]
    framed = 1 + sum(1 for f in meta["frames"]["frames"] if "chart" in f)
    assert len(spacings) == framed, f"{len(spacings)} framed charts printed, {framed} built"
    for x, y in spacings:
        assert x > 10 and abs(x / y - 1) <= 0.02, (name, x, y)


@pytest.mark.parametrize("name, edit", BOOKS, ids=IDS)
def test_the_mapped_drawing_stays_inside_its_frame(rendered, name, edit):
    """Every mapped coordinate of the printed book (evaluated by the engine that verify checks
    against LibreOffice) inside the frame, with the margin the frame keeps for the scale bar."""
    path, meta, _ = rendered[(name, edit)]
    wb = openpyxl.load_workbook(path)
    values = engine.evaluate(wb)
    sheet = meta["frames"]["sheet"]
    inside = frames.HALF / frames.MARGIN * (1 + 1e-9)
    drawn = 0
    for frame in meta["frames"]["frames"]:
        for s in frame["series"]:
            first, last = s["mapped_rows"]
            for letter in s["columns"]:
                column = [values[(sheet, f"{letter}{r}")] for r in range(first, last + 1)]
                numbers = [v for v in column if isinstance(v, float)]
                drawn += len(numbers)
                assert all(abs(v) <= inside for v in numbers), (name, frame["cells"], letter)
    assert drawn > 0
    if edit:
        t = template(name)
        doubled = _first_length(t)
        assert inputs_of(wb, BuildRecord.from_json(meta))[doubled] == 2 * t.values()[doubled]
