"""LibreOffice and Gnumeric, headless: real spreadsheet applications as checkers, and
LibreOffice as a printer.

A recalculation is one mechanism for both applications: the application loads the book, computes
every formula and saves an .xlsx into a scratch folder, whose values are then read back. LibreOffice
(`soffice`) runs with a private, freshly made profile (two jobs sharing one profile lose output)
whose settings force a full recalculation on load: it would otherwise keep whatever values a file
caches, or none. Gnumeric (`ssconvert --recalc`) recalculates every cell when told to. Both exit 0
even when they fail, so each call checks that the file it asked for exists. Temporary folders are
always removed.

Errors: a formula's cached error comes back from openpyxl (data_only) as the plain string of its
code with data_type 'e' ('#N/A', '#NUM!', '#DIV/0!', '#VALUE!', '#NAME?', ...).
`recalculated_values` wraps those in `CellError`, a str subclass, so an error is never taken for a
text result. LibreOffice differs from Excel on a few: SQRT(-1) is #VALUE! (Excel #NUM!),
ATAN2(0, 0) is 0 (Excel #DIV/0!). Gnumeric writes its error values with Excel's codes, and gives
Excel's answer on both; Debian's Gnumeric 1.12.55 computes in long double and writes 21 digits
(1/3 is 0.333333333333333333342), read back here as the nearest double.
"""
from __future__ import annotations

import html
import os
import re
import shutil
import signal
import subprocess
import tempfile
import zipfile
from contextlib import contextmanager
from pathlib import Path

TIMEOUT_S = 300
PREVIEW_DPI = 110          # a table's small print stays readable
XLSX_FILTER = "xlsx:Calc MS Excel 2007 XML"
PDF_FILTER = "pdf:calc_pdf_Export"
ERROR_CODES = frozenset({"#NULL!", "#DIV/0!", "#VALUE!", "#REF!", "#NAME?", "#NUM!", "#N/A",
                         "#GETTING_DATA", "#SPILL!", "#CALC!"})
INSTALL_HINT = ("LibreOffice is needed for this (the `soffice` command was not found). "
                "Install it, e.g. on Debian/Ubuntu: apt-get install -y --no-install-recommends "
                "libreoffice-calc-nogui; for PNG previews also poppler-utils (pdftoppm).")
GNUMERIC_HINT = ("Gnumeric is needed for this (the `ssconvert` command was not found). "
                 "Install it, e.g. on Debian/Ubuntu: apt-get install -y --no-install-recommends "
                 "gnumeric.")
# the applications a book can be recalculated in (verify's engines of the same names)
APPLICATIONS = ("libreoffice", "gnumeric")

# Recalculation modes 0 = always, 1 = never, 2 = ask: "always" for files from Excel (OOXML) and
# from LibreOffice (ODF). Written into the private profile before soffice first starts.
REGISTRY = """<?xml version="1.0" encoding="UTF-8"?>
<oor:items xmlns:oor="http://openoffice.org/2001/registry" \
xmlns:xs="http://www.w3.org/2001/XMLSchema" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">
<item oor:path="/org.openoffice.Office.Calc/Formula/Load">\
<prop oor:name="OOXMLRecalcMode" oor:op="fuse"><value>0</value></prop></item>
<item oor:path="/org.openoffice.Office.Calc/Formula/Load">\
<prop oor:name="ODFRecalcMode" oor:op="fuse"><value>0</value></prop></item>
</oor:items>
"""


class OfficeUnavailable(Exception):
    """soffice (or pdftoppm, for previews) is not installed."""


class OfficeFailed(Exception):
    """soffice ran but did not produce the file it was asked for (or timed out)."""


class CellError(str):
    """A formula error read back from a recalculated file: str(e) is its code, e.g. '#N/A'."""

    def __repr__(self) -> str:
        return f"CellError({str(self)!r})"


# ---------------------------------------------------------------- errors
def error_code(value) -> str | None:
    """'#N/A', '#NUM!', ... for an error value of any engine (CellError, the plain string that
    openpyxl reads, or an object such as formulas' XlError whose str() is the code); else None."""
    if value is None or isinstance(value, (bool, int, float)):
        return None
    text = str(value)
    return text if text in ERROR_CODES else None


def is_error(value) -> bool:
    return error_code(value) is not None


# ---------------------------------------------------------------- running soffice
def soffice_path() -> str | None:
    return shutil.which("soffice") or shutil.which("libreoffice")


def _require_soffice() -> str:
    exe = soffice_path()
    if exe is None:
        raise OfficeUnavailable(INSTALL_HINT)
    return exe


def ssconvert_path() -> str | None:
    return shutil.which("ssconvert")


def _require_ssconvert() -> str:
    exe = ssconvert_path()
    if exe is None:
        raise OfficeUnavailable(GNUMERIC_HINT)
    return exe


@contextmanager
def _profile():
    """A fresh LibreOffice user profile that recalculates every file on load."""
    with tempfile.TemporaryDirectory(prefix="linkbook-lo-") as tmp:
        user = Path(tmp, "user")
        user.mkdir()
        (user / "registrymodifications.xcu").write_text(REGISTRY, encoding="utf-8")
        yield Path(tmp).as_uri()


def _convert(path: Path, outdir: Path, target: str, suffix: str) -> Path:
    """soffice --convert-to TARGET into a scratch folder, then move the result into outdir."""
    exe = _require_soffice()
    with _profile() as profile:
        return _made_by("LibreOffice", path, outdir, suffix, lambda source, scratch: [
            exe, f"-env:UserInstallation={profile}", "--headless", "--norestore",
            "--nolockcheck", "--calc", "--convert-to", target, "--outdir", str(scratch),
            str(source)])


def _gnumeric_recalculate(path: Path, outdir: Path) -> Path:
    """ssconvert --recalc: every formula computed by Gnumeric, saved as .xlsx (Excel 2007+)."""
    exe = _require_ssconvert()
    return _made_by("Gnumeric", path, outdir, ".xlsx", lambda source, scratch: [
        exe, "--recalc", "--export-type=Gnumeric_Excel:xlsx2", str(source),
        str(scratch / (source.stem + ".xlsx"))])


def _made_by(application: str, path: Path, outdir: Path, suffix: str, command) -> Path:
    """Run `command(source, scratch folder)`, which writes STEM+suffix into the scratch folder,
    and move that file into outdir."""
    path = Path(path).resolve()
    if not path.is_file():
        raise FileNotFoundError(path)
    outdir = Path(outdir)
    out = outdir / (path.stem + suffix)
    if out.resolve() == path:               # the application's copy is not the file we wrote
        raise ValueError(f"{out} would replace its own source: choose another outdir")
    outdir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="linkbook-out-") as scratch:
        code, detail = _run(command(path, Path(scratch)), f"converting {path.name}")
        made = Path(scratch, out.name)
        if not made.is_file() or made.stat().st_size == 0:
            raise OfficeFailed(f"{application} could not convert {path.name} to {suffix} "
                               f"(exit {code}){': ' + _last_line(detail) if detail else ''}")
        shutil.move(str(made), out)
    return out


def _last_line(detail: str) -> str:
    """An application's last words: Gnumeric prints a warning per element it does not know
    before the one that says why it failed."""
    return detail.strip().splitlines()[-1].strip() if detail.strip() else ""


def _run(cmd: list[str], what: str) -> tuple[int, str]:
    """Run a command in a process group of its own, so that a time-out ends soffice.bin too
    (soffice is a launcher script that starts it as a child)."""
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise OfficeFailed(f"{Path(cmd[0]).name} did not finish {what} within {TIMEOUT_S} s") \
            from None
    except BaseException:
        # Ctrl-C or SIGTERM reached only us (the command has a session of its own): end it too
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    return proc.returncode, (stderr or stdout).strip()


def recalculate(path, outdir, application: str = "libreoffice") -> Path:
    """Load in the application (one of APPLICATIONS) with a full recalculation and save as
    .xlsx into outdir."""
    if application == "gnumeric":
        return _gnumeric_recalculate(Path(path), Path(outdir))
    if application != "libreoffice":
        raise ValueError(f"no application {application!r}: one of {', '.join(APPLICATIONS)}")
    return _convert(Path(path), Path(outdir), XLSX_FILTER, ".xlsx")


def to_pdf(path, outdir) -> Path:
    """Print every visible sheet (and its charts) to PDF, as the workbook's page setup says."""
    return _convert(Path(path), Path(outdir), PDF_FILTER, ".pdf")


# ---------------------------------------------------------------- reading values back
def read_values(path) -> dict[tuple[str, str], object]:
    """(sheet title, 'B7') -> the cached value of every non-empty cell of an .xlsx file."""
    import warnings
    import openpyxl
    with warnings.catch_warnings():
        # about the application's copy, not the book: Gnumeric writes no default cell style
        # and a print area of several ranges as ERROR("..."), which openpyxl reports
        warnings.simplefilter("ignore", UserWarning)
        wb = openpyxl.load_workbook(path, data_only=True, read_only=True)
    try:
        values = {}
        for ws in wb.worksheets:
            for row in ws.iter_rows():
                for c in row:
                    value = _value(c)
                    if value is not None:
                        values[(ws.title, c.coordinate)] = value
        return values
    finally:
        wb.close()


def _value(cell):
    if not hasattr(cell, "coordinate"):             # read-only padding for a missing cell
        return None
    if cell.data_type == "e":
        return CellError(str(cell.value))
    if cell.value is None:
        # A formula whose result is "" is cached as t="str" with an empty <v>.
        return "" if cell.data_type == "str" else None
    if isinstance(cell.value, int) and not isinstance(cell.value, bool):
        return float(cell.value)
    return cell.value


def recalculated_values(path, application: str = "libreoffice") -> dict[tuple[str, str], object]:
    """Every cell's value after the application (LibreOffice or Gnumeric) has recalculated a
    copy: numbers as float, errors as CellError, text as str ('' for a formula whose result is
    empty text), booleans as bool."""
    with tempfile.TemporaryDirectory(prefix="linkbook-recalc-") as tmp:
        return read_values(recalculate(path, tmp, application))


# ---------------------------------------------------------------- page setup
# Printing is how a workbook becomes pictures, and how an engineer takes it to a meeting. The
# sheets are wide (Mechanism: three tables and a drawing side by side) and the charts must not be
# cut by a page break, so each sheet gets its own orientation, scale and manual breaks, chosen
# from the column widths, row heights and chart sizes openpyxl knows.
PAPER_CM = (21.0, 29.7)                  # A4, the paper of the textbook's metric world
MARGIN_IN = {"left": 0.5, "right": 0.5, "top": 0.6, "bottom": 0.6, "header": 0.3,
             "footer": 0.3}
SCALES = (100, 95, 90, 85, 80, 75)     # below 75 % a preview at 80 dpi is hard to read
FIT = 0.95                               # slack for LibreOffice's own font metrics
ROW_CM = 15 / 72 * 2.54                  # the default row height, 15 pt
DEFAULT_COL_CHARS = 8.54                 # what LibreOffice gives a column of no set width
CHAR_CM = 0.0972 * 2.54


def apply_print_setup(wb, fit_to_width: tuple[str, ...] = ()) -> None:
    """Landscape or portrait, a scale, page breaks and a footer for every visible sheet, so
    that printed (and previewed) pages are readable and no chart is split across pages.
    Sheets named in `fit_to_width` print landscape, one page wide (blocks side by side stay
    together), with the row breaks chosen for them. A title or note wider than the first page
    wraps within it. Call after the charts have been added; it changes no cell's value."""
    from openpyxl.worksheet.page import PageMargins
    for ws in wb.worksheets:
        if ws.sheet_state != "visible":
            continue
        ws.page_margins = PageMargins(**MARGIN_IN)
        ws.page_setup.paperSize = ws.PAPERSIZE_A4
        ws.sheet_properties.pageSetUpPr.fitToPage = False    # a fixed scale keeps breaks
        _repeat_frozen_titles(ws)
        sheet = _SheetShape.of(ws)
        orientation, scale, col_breaks, row_breaks = sheet.best_layout()
        fit = ws.title in fit_to_width
        room = sheet.first_page_cm(orientation, None if fit else scale, col_breaks)
        if _wrap_title_rows(ws, sheet, room):     # taller rows: the row breaks move
            sheet = _SheetShape.of(ws)
            orientation, scale, col_breaks, row_breaks = sheet.best_layout()
        if fit:
            orientation, scale, col_breaks = "landscape", None, []
            ws.sheet_properties.pageSetUpPr.fitToPage = True
            ws.page_setup.fitToWidth, ws.page_setup.fitToHeight = 1, 0
        ws.page_setup.orientation = orientation
        ws.page_setup.scale = scale
        _set_breaks(ws, col_breaks, row_breaks)
        _column_page_areas(ws, sheet, col_breaks)
        ws.oddFooter.center.text = "&A, page &P of &N"
        ws.oddFooter.center.size = 8
        _leave_out_empty_headers(ws)


def _leave_out_empty_headers(ws) -> None:
    """No element for a header or footer that prints nothing (openpyxl writes all six, empty
    or not): an absent one means the same to Excel and LibreOffice, and Gnumeric, which reads
    only the odd ones, warns on each other element it finds."""
    items = ws.HeaderFooter
    for name in ("oddHeader", "oddFooter", "evenHeader", "evenFooter", "firstHeader",
                 "firstFooter"):
        if not getattr(items, name):
            setattr(items, name, None)


SPARE_COLUMNS = 3
TITLE_ROWS = 2      # a sheet's title (A1) and note (A2): printed once, as text that overflows
HEADER_CHARS = 200  # Excel allows 255 characters in a page header, codes included


def _repeat_frozen_titles(ws) -> None:
    """The rows and columns frozen on screen are the headings: repeat them on every page,
    except the title and note rows, whose text overflows across the first page's columns and
    would be cut at the edge of the repeated column A; every page's header names the sheet's
    title instead, whole."""
    if isinstance(ws["A1"].value, str):
        title = ws["A1"].value
        title = title if len(title) <= HEADER_CHARS else title[:HEADER_CHARS - 1] + "…"
        ws.oddHeader.center.text = title.replace("&", "&&")
        ws.oddHeader.center.size = 8
        ws.HeaderFooter.differentFirst = True      # page 1 shows A1 itself
        ws.firstFooter.center.text = "&A, page &P of &N"
        ws.firstFooter.center.size = 8
    if not ws.freeze_panes:
        return
    from openpyxl.utils.cell import coordinate_from_string, column_index_from_string
    letter, row = coordinate_from_string(ws.freeze_panes)
    if row > TITLE_ROWS + 1:
        ws.print_title_rows = f"{TITLE_ROWS + 1}:{row - 1}"
    elif row > 1:
        ws.print_title_rows = f"1:{row - 1}"
    if column_index_from_string(letter) > 1:
        ws.print_title_cols = f"A:{_letter(column_index_from_string(letter) - 1)}"


def _wrap_title_rows(ws, sheet: "_SheetShape", room_cm: float) -> bool:
    """The title and note (rows 1 to TITLE_ROWS, column A) whose text is wider than the first
    printed page: merged across the page's columns and wrapped there, the row as tall as its
    lines (text that overflows a page edge is cut in print)."""
    from openpyxl.styles import Alignment
    from ..book.workbook import LINE_HEIGHT, label_lines
    last, x = 1, 0.0
    for i in sorted(sheet.col_cm):
        if x + sheet.col_cm[i] > room_cm:
            break
        x, last = x + sheet.col_cm[i], i
    changed = False
    for r in range(1, TITLE_ROWS + 1):
        cell = ws.cell(r, 1)
        if not isinstance(cell.value, str) or any(
                ws.cell(r, c).value is not None for c in range(2, last + 1)):
            continue
        size = float(cell.font.sz or 11) if cell.font else 11.0
        grow = size / 11 * (1.1 if cell.font is not None and cell.font.b else 1.0)
        lines = label_lines(cell.value, x / CHAR_CM / grow)
        if len(lines) < 2:
            continue
        ws.merge_cells(start_row=r, start_column=1, end_row=r, end_column=last)
        cell.alignment = Alignment(wrap_text=True, vertical="top")
        ws.row_dimensions[r].height = LINE_HEIGHT * size / 11 * len(lines)
        changed = True
    return changed


def _column_page_areas(ws, sheet: "_SheetShape", col_breaks) -> None:
    """A sheet printed in several columns of pages: one print range per column of pages, the
    later ones from the row under the title and note, so that the repeated column A does not
    print a slice of them on every continuation page."""
    if not col_breaks or not ws.print_title_cols:
        return
    # the last range a few empty columns wider: a chart at the right edge keeps its right
    # side where LibreOffice's default column is narrower than this count of it
    last_col, last_row = max(sheet.col_cm) + SPARE_COLUMNS, max(sheet.row_cm)
    starts = [1] + [c + 1 for c in col_breaks]
    ends = [c for c in col_breaks] + [last_col]
    ws.print_area = [f"{_letter(a)}{1 if i == 0 else TITLE_ROWS + 1}:{_letter(b)}{last_row}"
                     for i, (a, b) in enumerate(zip(starts, ends))]


def _set_breaks(ws, col_breaks, row_breaks) -> None:
    from openpyxl.worksheet.pagebreak import Break, ColBreak, RowBreak
    ws.row_breaks = RowBreak()
    ws.col_breaks = ColBreak()
    for r in row_breaks:        # OOXML: 0-based index of the first row (column) after it
        ws.row_breaks.append(Break(id=r))
    for c in col_breaks:
        ws.col_breaks.append(Break(id=c))


def _letter(index: int) -> str:
    from openpyxl.utils import get_column_letter
    return get_column_letter(index)


class _SheetShape:
    """Sizes in cm of a sheet's columns and rows, what is used, and where the charts sit."""

    def __init__(self, col_cm, row_cm, used_cols, charts, title_rows_cm, title_cols_cm):
        self.col_cm = col_cm              # index 1.. -> width in cm
        self.row_cm = row_cm              # index 1.. -> height in cm
        self.used_cols = used_cols        # column indices holding a value or a chart
        self.charts = charts              # (first col, last col, first row, last row)
        self.title_rows_cm = title_rows_cm    # repeated at the top of every further page
        self.title_cols_cm = title_cols_cm    # repeated at the left of every further page

    @classmethod
    def of(cls, ws) -> "_SheetShape":
        from openpyxl.utils import column_index_from_string
        used_cols, max_row = set(), 0
        for (row, col), c in ws._cells.items():   # iter_rows() would fill the gaps with cells
            if c.value is not None:
                used_cols.add(col)
                max_row = max(max_row, row)
        charts = [_chart_box(ws, ch) for ch in ws._charts]
        for c0, c1, r0, r1 in charts:
            used_cols.update(range(c0, c1 + 1))
            max_row = max(max_row, r1)
        last_col = max(used_cols, default=1)
        col_cm = {i: _column_cm(ws, i) for i in range(1, last_col + 1)}
        row_cm = {r: _row_cm(ws, r) for r in range(1, max_row + 1)}
        title_rows = title_cols = 0.0
        if ws.print_title_rows:
            first, last = (int(x) for x in ws.print_title_rows.replace("$", "").split(":"))
            title_rows = sum(row_cm.get(r, ROW_CM) for r in range(first, last + 1))
        if ws.print_title_cols:
            first, last = (column_index_from_string(x)
                           for x in ws.print_title_cols.replace("$", "").split(":"))
            title_cols = sum(col_cm.get(c, 0.0) for c in range(first, last + 1))
        return cls(col_cm, row_cm, used_cols, charts, title_rows, title_cols)

    def best_layout(self):
        """The orientation and scale that cost least, counting a page less than legibility:
        cost = pages / scale², e.g. 2 pages at 90 % beat 3 pages at 100 %."""
        best = None
        for orientation in ("portrait", "landscape"):
            width, height = _printable_cm(orientation)
            for scale in SCALES:
                f = scale / 100
                col_breaks, col_pages = self._column_pages(width * FIT / f)
                row_breaks, row_pages = self._row_pages(height * FIT / f)
                cost = col_pages * row_pages / f ** 2
                if best is None or cost < best[0] - 1e-9:
                    best = (cost, orientation, scale, col_breaks, row_breaks)
        return best[1:]

    def first_page_cm(self, orientation: str, scale: int | None, col_breaks) -> float:
        """The width the first page prints, in the sheet's cm (scale None: the sheet is
        fitted to one page wide)."""
        used = max(self.used_cols, default=1)
        last = col_breaks[0] if col_breaks else used
        width = sum(self.col_cm.get(i, 0.0) for i in range(1, last + 1))
        if scale is None:
            return width
        return min(width, _printable_cm(orientation)[0] * FIT / (scale / 100))

    def _column_pages(self, width: float):
        """Greedy: whole blocks of used columns (split at empty spacer columns) per page; a
        block wider than a page is broken between the columns that fill each page."""
        breaks, x, pages, previous = [], 0.0, 1, 0
        room = width - self.title_cols_cm
        for first, last in self._blocks():
            block = sum(self.col_cm[i] for i in range(first, last + 1))
            # A page starts at its first block (LibreOffice prints no empty leading columns
            # after a break); the spacer columns between blocks on one page count.
            spacers = sum(self.col_cm[i] for i in range(previous + 1, first)) if x else 0.0
            previous = last
            limit = width if pages == 1 else room
            if x and x + spacers + block > limit:
                breaks.append(first - 1)
                pages, x, spacers, limit = pages + 1, 0.0, 0.0, room
            if x + spacers + block <= limit:
                x += spacers + block
                continue
            x += spacers                  # a block wider than a page: break between columns
            for c in range(first, last + 1):
                if x and x + self.col_cm[c] > limit:
                    breaks.append(c - 1)
                    pages, x, limit = pages + 1, 0.0, room
                x += self.col_cm[c]
        return breaks, pages
    def _blocks(self):
        cols = sorted(self.used_cols)
        blocks = []
        for c in cols:
            if blocks and c == blocks[-1][1] + 1:
                blocks[-1][1] = c
            else:
                blocks.append([c, c])
        return blocks

    def _row_pages(self, height: float):
        """A break where each page is full, and one before a chart that would otherwise be cut
        at the foot of a page."""
        starts = {}
        for _, _, r0, r1 in self._merged_chart_rows():
            starts[r0] = r1
        breaks, y, pages = [], 0.0, 1
        room = height - self.title_rows_cm
        for r in sorted(self.row_cm):
            h = self.row_cm[r]
            if r in starts:
                span = sum(self.row_cm[i] for i in range(r, starts[r] + 1))
                if y + span > (height if pages == 1 else room) and y > 0 and span <= room:
                    # the break a row above the chart: a chart whose top edge lies on the
                    # break prints that edge at the foot of the page before too
                    gap = self.row_cm.get(r - 1, 0.0) if r > 2 else 0.0
                    breaks.append(r - 2 if gap else r - 1)
                    pages, y = pages + 1, gap
            if y + h > (height if pages == 1 else room):
                # written too: LibreOffice's own page is a little longer than this one (FIT),
                # and would end below a chart that this count put on the next page
                breaks.append(r - 1)
                pages, y = pages + 1, 0.0
            y += h
        return breaks, pages

    def _merged_chart_rows(self):
        spans = sorted((r0, r1) for _, _, r0, r1 in self.charts)
        merged = []
        for r0, r1 in spans:
            if merged and r0 <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], r1)
            else:
                merged.append([r0, r1])
        return [(0, 0, r0, r1) for r0, r1 in merged]


def _printable_cm(orientation: str) -> tuple[float, float]:
    w, h = PAPER_CM if orientation == "portrait" else PAPER_CM[::-1]
    return (w - (MARGIN_IN["left"] + MARGIN_IN["right"]) * 2.54,
            h - (MARGIN_IN["top"] + MARGIN_IN["bottom"]) * 2.54)


def _column_cm(ws, index: int) -> float:
    """A width in characters, in cm as LibreOffice lays it out when Calibri and its metric twin
    Carlito are missing (DejaVu Sans: 0.0972 in a character, measured). With Calibri (Excel)
    a character is 7 px = 0.185 cm, so pages come out a little less full, never cut."""
    dim = ws.column_dimensions.get(_letter(index))
    chars = dim.width if dim is not None and dim.customWidth else DEFAULT_COL_CHARS
    return chars * CHAR_CM


def _row_cm(ws, row: int) -> float:
    dim = ws.row_dimensions.get(row)
    return dim.ht / 72 * 2.54 if dim is not None and dim.ht else ROW_CM


def _chart_box(ws, chart) -> tuple[int, int, int, int]:
    """(first col, last col, first row, last row) that a chart covers, 1-based."""
    from openpyxl.utils.cell import column_index_from_string, coordinate_from_string
    anchor = chart.anchor
    if isinstance(anchor, str):
        letter, row = coordinate_from_string(anchor)
        col = column_index_from_string(letter)
    else:                                    # an anchor object, after a save
        col, row = anchor._from.col + 1, anchor._from.row + 1
    last_col, x = col, _column_cm(ws, col)
    while x < chart.width:
        last_col += 1
        x += _column_cm(ws, last_col)
    last_row, y = row, _row_cm(ws, row)
    while y < chart.height:
        last_row += 1
        y += _row_cm(ws, last_row)
    return col, last_col, row, last_row


# ---------------------------------------------------------------- pictures
def preview(path, outdir, dpi: int = PREVIEW_DPI, sheets: list[str] | None = None
            ) -> list[Path]:
    """The printed pages (sheets and charts) as PNG, and the whole print as PDF: soffice ->
    PDF -> pdftoppm, one sheet at a time so that each picture is named by its sheet.

    `sheets`: the visible sheets to print (default: all, in the book's order). Writes
    STEM.pdf (those sheets, in order) and STEM-SHEET-1.png, STEM-SHEET-2.png, ... per sheet
    (SHEET with anything but letters, digits, - and _ as _; pdftoppm pads the number with zeros
    when a sheet prints ten or more pages). Returns the pictures in print order."""
    pdftoppm = shutil.which("pdftoppm")
    if pdftoppm is None:
        raise OfficeUnavailable("pdftoppm (Debian package poppler-utils) is needed for PNG "
                                "previews: apt-get install -y poppler-utils")
    path, outdir = Path(path), Path(outdir)
    chosen = list(sheets) if sheets else visible_sheets(path)
    outdir.mkdir(parents=True, exist_ok=True)
    stem = path.stem
    with tempfile.TemporaryDirectory(prefix="linkbook-pdf-") as tmp:
        whole = to_pdf(_only_sheets(path, chosen, Path(tmp, "all")), tmp)
        shutil.move(str(whole), outdir / f"{stem}.pdf")
        out = []
        for sheet in chosen:
            name = f"{stem}-{_file_word(sheet)}"
            pdf = to_pdf(_only_sheets(path, [sheet], Path(tmp, name)), tmp)
            pictures = Path(tmp, "png", name)
            pictures.mkdir(parents=True)
            code, detail = _run([pdftoppm, "-png", "-r", str(dpi), str(pdf),
                                 str(pictures / name)], f"rendering {sheet}")
            if code != 0:
                raise OfficeFailed(f"pdftoppm failed on {sheet} (exit {code}): {detail}")
            # Rendered apart, then moved: pages of an earlier, longer preview are never returned.
            made = sorted(pictures.glob("*.png"), key=_page_number)
            if not made:
                raise OfficeFailed(f"no pages were rendered from sheet {sheet!r}")
            # pdftoppm pads the page number to the page count's digits (-01 of 12 pages)
            out += [Path(shutil.move(str(p), outdir / f"{name}-{_page_number(p)}.png"))
                    for p in made]
        return out


_SHEET_TAG = re.compile(r"<sheet\b[^>]*/>")


def visible_sheets(path) -> list[str]:
    """The names of the book's visible sheets, in order (read from the file's workbook part,
    without loading the workbook)."""
    with zipfile.ZipFile(path) as z:
        xml = z.read("xl/workbook.xml").decode("utf-8")
    return [name for name, state in _sheet_tags(xml) if state == "visible"]


def _sheet_tags(xml: str) -> list[tuple[str, str]]:
    out = []
    for tag in _SHEET_TAG.findall(xml):
        name = html.unescape(re.search(r'\bname="([^"]*)"', tag).group(1))
        state = re.search(r'\bstate="([^"]*)"', tag)
        out.append((name, state.group(1) if state else "visible"))
    return out


def _only_sheets(path: Path, sheets: list[str], folder: Path) -> Path:
    """A copy of the book, byte for byte but for its workbook part, in which only `sheets` are
    visible (the first of them active): LibreOffice prints visible sheets only."""
    folder.mkdir(parents=True, exist_ok=True)
    copy = folder / path.name
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(copy, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "xl/workbook.xml":
                data = _show_only(data.decode("utf-8"), sheets).encode("utf-8")
            dst.writestr(item, data)
    return copy


def _show_only(xml: str, sheets: list[str]) -> str:
    names = [name for name, _ in _sheet_tags(xml)]
    active = names.index(sheets[0])

    def state(match: re.Match) -> str:
        tag = re.sub(r'\s*\bstate="[^"]*"', "", match.group(0))
        name = html.unescape(re.search(r'\bname="([^"]*)"', tag).group(1))
        return tag if name in sheets else tag.replace("<sheet ", '<sheet state="hidden" ', 1)
    xml = _SHEET_TAG.sub(state, xml)
    # LibreOffice prints a hidden sheet that has a print area: the hidden sheets' go
    hidden = {str(k) for k, name in enumerate(names) if name not in sheets}
    xml = re.sub(r'<definedName name="_xlnm\.Print_(?:Area|Titles)" localSheetId="(\d+)"'
                 r'[^>]*>[^<]*</definedName>',
                 lambda m: "" if m.group(1) in hidden else m.group(0), xml)
    xml = re.sub(r'\bactiveTab="\d+"', f'activeTab="{active}"', xml)
    return re.sub(r'\bfirstSheet="\d+"', f'firstSheet="{active}"', xml)


def _file_word(sheet: str) -> str:
    """A sheet's name as part of a file name: `Drawing data` → `Drawing_data`."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", sheet).strip("_") or "sheet"


def _page_number(p: Path) -> int:
    tail = p.stem.rsplit("-", 1)[-1]
    return int(tail) if tail.isdigit() else 0
