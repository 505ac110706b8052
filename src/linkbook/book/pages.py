"""Page setup: each sheet's orientation, scale, print titles and manual breaks, chosen from the
column widths, row heights and chart sizes openpyxl knows, so that a printed sheet or preview
never cuts a table or a chart."""
from __future__ import annotations

# ---------------------------------------------------------------- page setup
# Printing is how a workbook becomes pictures, and how an engineer takes it to a meeting. The
# sheets are wide (Mechanism: three tables and a drawing side by side) and the charts must not be
# cut by a page break, so each sheet gets its own orientation, scale and manual breaks, chosen
# from the column widths, row heights and chart sizes openpyxl knows.
PAPER_CM = (21.0, 29.7)                  # A4, the paper of the textbook's metric world
MARGIN_IN = {"left": 0.5, "right": 0.5, "top": 0.6, "bottom": 0.6, "header": 0.3,
             "footer": 0.3}
# Down to 65 %: 7 pt on paper, as a printed table of numbers often is; a 5° four-bar (Sweep,
# Motion, Forces, Charts, Drawing data) then prints on 28 landscape pages, not 44.
SCALES = (100, 95, 90, 85, 80, 75, 70, 65)
FIT = 0.95                               # slack for LibreOffice's own font metrics
ROW_CM = 15 / 72 * 2.54                  # the default row height, 15 pt
DEFAULT_COL_CHARS = 8.54                 # what LibreOffice gives a column of no set width
CHAR_CM = 0.0972 * 2.54


def apply_print_setup(wb, fit_to_width: tuple[str, ...] = (),
                      keep_together: dict[str, list[tuple[int, int]]] | None = None) -> None:
    """Landscape or portrait, a scale, page breaks and a footer for every visible sheet, so
    that printed (and previewed) pages are readable and no chart is split across pages.
    Sheets named in `fit_to_width` print landscape, one page wide (blocks side by side stay
    together), with the row breaks chosen for them. `keep_together` names, by sheet, the
    (first, last) rows of blocks that no row break may cut, as none cuts a chart. A title or
    note wider than the first page wraps within it. Call after the charts have been added; it
    changes no cell's value."""
    from openpyxl.worksheet.page import PageMargins
    for ws in wb.worksheets:
        if ws.sheet_state != "visible":
            continue
        ws.page_margins = PageMargins(**MARGIN_IN)
        ws.page_setup.paperSize = ws.PAPERSIZE_A4
        ws.sheet_properties.pageSetUpPr.fitToPage = False    # a fixed scale keeps breaks
        _repeat_frozen_titles(ws)
        kept = (keep_together or {}).get(ws.title, [])
        sheet = _SheetShape.of(ws, kept)
        orientation, scale, col_breaks, row_breaks = sheet.best_layout()
        fit = ws.title in fit_to_width
        room = sheet.first_page_cm(orientation, None if fit else scale, col_breaks)
        if _wrap_title_rows(ws, sheet, room):     # taller rows: the row breaks move
            sheet = _SheetShape.of(ws, kept)
            orientation, scale, col_breaks, row_breaks = sheet.best_layout()
        if fit:
            orientation, scale, col_breaks, row_breaks = "landscape", None, [], []
            ws.sheet_properties.pageSetUpPr.fitToPage = True
            ws.page_setup.fitToWidth, ws.page_setup.fitToHeight = 1, 1
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
    from .style import LINE_HEIGHT, label_lines
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
    print a slice of them on every continuation page, each down to the last row it holds
    something in (a block under a table, the Forces sheet's summary, makes no empty pages
    in the columns right of it)."""
    if not col_breaks or not ws.print_title_cols:
        return
    # the last range a few empty columns wider: a chart at the right edge keeps its right
    # side where LibreOffice's default column is narrower than this count of it
    last_col = max(sheet.col_cm) + SPARE_COLUMNS
    starts = [1] + [c + 1 for c in col_breaks]
    ends = [c for c in col_breaks] + [last_col]
    ws.print_area = [f"{_letter(a)}{1 if i == 0 else TITLE_ROWS + 1}:{_letter(b)}"
                     f"{_last_row(ws, sheet, a, b)}" for i, (a, b) in enumerate(zip(starts, ends))]


def _last_row(ws, sheet: "_SheetShape", first_col: int, last_col: int) -> int:
    """The last row holding a value or a chart in the columns first_col..last_col."""
    rows = [row for (row, col), c in ws._cells.items()
            if first_col <= col <= last_col and c.value is not None]
    rows += [r1 for c0, c1, _, r1 in sheet.charts if c0 <= last_col and c1 >= first_col]
    return max(rows, default=TITLE_ROWS + 1)


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

    def __init__(self, col_cm, row_cm, used_cols, charts, title_rows_cm, title_cols_cm,
                 kept=()):
        self.col_cm = col_cm              # index 1.. -> width in cm
        self.row_cm = row_cm              # index 1.. -> height in cm
        self.used_cols = used_cols        # column indices holding a value or a chart
        self.charts = charts              # (first col, last col, first row, last row)
        self.title_rows_cm = title_rows_cm    # repeated at the top of every further page
        self.title_cols_cm = title_cols_cm    # repeated at the left of every further page
        self.kept = list(kept)            # (first row, last row) of blocks kept on one page

    @classmethod
    def of(cls, ws, kept=()) -> "_SheetShape":
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
        return cls(col_cm, row_cm, used_cols, charts, title_rows, title_cols, kept)

    def best_layout(self):
        """The orientation and scale that cost least: cost = pages / scale, e.g. 6 pages at 70 %
        beat 10 at 95 %, and 2 pages at 90 % beat 3 at 100 %."""
        best = None
        for orientation in ("portrait", "landscape"):
            width, height = _printable_cm(orientation)
            for scale in SCALES:
                f = scale / 100
                col_breaks, col_pages = self._column_pages(width * FIT / f)
                row_breaks, row_pages = self._row_pages(height * FIT / f)
                cost = col_pages * row_pages / f
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
        """A break where each page is full, and one before a chart (or a block kept together)
        that would otherwise be cut at the foot of a page."""
        starts = {}
        for r0, r1 in self._kept_rows():
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

    def _kept_rows(self):
        """The row spans no break may cut: the charts' and the kept blocks', overlaps merged."""
        spans = sorted([(r0, r1) for _, _, r0, r1 in self.charts] + list(self.kept))
        merged = []
        for r0, r1 in spans:
            if merged and r0 <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], r1)
            else:
                merged.append([r0, r1])
        return [(r0, r1) for r0, r1 in merged]


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


