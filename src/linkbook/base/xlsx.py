"""A fast read-only view of an .xlsx for verify: every cell's value and formula text, and the
workbook's defined names, read straight from the XML parts.

openpyxl's full load builds every style, dimension and chart object and takes most of a small
book's verify; verify needs only what this module reads. The view gives what openpyxl's
`load_workbook(path)` gives for the same file through the attributes verify and the engine use
(`wb.sheetnames`, `wb.worksheets`, `wb[title]`, `wb.defined_names`; `ws.title`, `ws[coord]`,
`ws.cell(row, col)`, `ws._cells`, `ws.max_row`, `ws.max_column`; `cell.value`,
`cell.data_type`, `cell.row`, `cell.column`, `cell.coordinate`, `cell.parent`), with openpyxl's
own rules: numbers with a '.', 'e' or 'E' are floats, others ints; a formula cell's value is
'=' and its text; shared strings lose 'x005F_'. A sheet holds its cells by column (Column:
lists of rows, values, kinds and stored values, no object per cell); a cell object is made when
asked for, and `ws._cells` makes every one (for tests and small sheets). A sheet part is
scanned by regular expressions where it is written as the writers write it, else read element
by element (both read it alike: tests/test_sheet_scan.py). A book with what the view does not
model (a shared, array or data-table formula, a number styled as a date, a chart sheet, a cell
without its address) raises Unsupported, after the whole book has been read: the caller loads
it with openpyxl.

What the spreadsheet application would read otherwise than this view (and openpyxl) raises
Refused: a number not in XML Schema's lexical form (Python's int() reads '3_5' and full-width
digits, the application does not), a defined name given twice (Excel compares names without
case), a sheet-scoped name that shadows a workbook name with another target (a formula on that
sheet reads the scoped one), and a formula longer or more deeply nested than Excel allows.
"""
from __future__ import annotations

import functools
import math
import re
import zipfile
from array import array
from bisect import bisect_left
from dataclasses import dataclass
from pathlib import PurePosixPath
from xml.etree.ElementTree import iterparse

__all__ = ["Unsupported", "Refused", "read", "coordinate_to_tuple", "coordinates_to_arrays",
           "column_index", "column_letter", "xml_text", "xml_attribute", "NOT_IN_XML"]

MAIN = "{http://schemas.openxmlformats.org/spreadsheetml/2006/main}"
REL = "{http://schemas.openxmlformats.org/officeDocument/2006/relationships}"
PKG_REL = "{http://schemas.openxmlformats.org/package/2006/relationships}"
# Built-in number formats that show a date or time (ECMA-376 18.8.30, with the East Asian ones).
DATE_FORMAT_IDS = frozenset([*range(14, 23), *range(27, 37), *range(45, 48), *range(50, 59)])
# A format code shows a date when a date/time letter is left after quoted text, escapes,
# fill/space characters and [..] sections are taken out (a little more eager than openpyxl's
# test: a false alarm only means openpyxl reads the book).
_NOT_DATE_PARTS = re.compile(r'"[^"]*"|\\.|_.|\*.|\[[^\]]*\]')
_DATE_LETTERS = re.compile(r"[dmyhsDMYHS]")
_COORDINATE = re.compile(r"^\$?([A-Za-z]{1,3})\$?(\d+)$")
# A number as a formula writes it: ASCII digits, at most one point, an optional exponent (a sign
# before it is an operator). The one spelling the mechanism language's expressions may use for a
# number (language.expressions) and verify's reference reads there (check.reference.expressions):
# no 1_000, 0x10, full-width or Arabic-Indic digits.
NUMBER_LITERAL = r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
# xsd:decimal / xsd:double without INF and NaN (LibreOffice reads those, and overflowing
# exponents, as infinities no formula can use), around XML white space (ASCII only: \s would
# take Unicode spaces too). LibreOffice reads the digits before a stray character ('3_5' as 3,
# '0x10' as 0): a book that needs that reading is refused.
_NUMBER = re.compile(rf"[ \t\r\n]*[+-]?{NUMBER_LITERAL}[ \t\r\n]*")
_INDEX = re.compile(r"[ \t\r\n]*[0-9]+[ \t\r\n]*")
# Excel's limits (Microsoft's "Excel specifications and limits"): 8,192 characters of formula
# contents, 64 levels of nested functions (counted here as brackets of any kind, so a formula
# of 64 nested brackets or fewer passes whatever its brackets are).
FORMULA_LENGTH_LIMIT = 8192
FORMULA_NESTING_LIMIT = 64
_QUOTED = re.compile(r'"(?:[^"]|"")*"|\'(?:[^\']|\'\')*\'')
_NOT_BRACKET = re.compile(r"[^()]+")


class Unsupported(Exception):
    """The book uses something this view does not model; read it with openpyxl."""


class Refused(Exception):
    """The application would read the book otherwise than this view and openpyxl do: it cannot
    be verified (one line naming the part and the cell or name)."""


BUILT_IN_PREFIX = "_XLNM."


def is_built_in(name: str) -> bool:
    """Excel's own names (ECMA-376 18.2.5: _xlnm.Print_Titles, _xlnm.Print_Area, …)."""
    return name.upper().startswith(BUILT_IN_PREFIX)


def _areas(text: str) -> frozenset[str]:
    """The ranges a built-in name lists, in any order, case and quoting of the sheet's name
    (outside quoted sheet names, a comma separates them)."""
    parts, quoted, current = [], False, []
    for ch in text:
        if ch == "'":
            quoted = not quoted
        if ch == "," and not quoted:
            parts.append("".join(current))
            current = []
        else:
            current.append(ch)
    parts.append("".join(current))
    return frozenset(p.strip().replace("'", "").upper() for p in parts)


class Cell:
    __slots__ = ("parent", "row", "column", "value", "data_type")

    def __init__(self, parent, row, column, value, data_type):
        self.parent, self.row, self.column = parent, row, column
        self.value, self.data_type = value, data_type

    @property
    def coordinate(self) -> str:
        return f"{column_letter(self.column)}{self.row}"


class Column:
    """The cells of one column of a sheet, in row order, held as parallel lists (no object per
    cell: a big book holds hundreds of thousands): each cell's row, value and kind (openpyxl's
    data_type), and what a formula cell stores with it (its `<v>`: the number, or (kind, text)
    for any other kind; None where it stores nothing or is no formula)."""
    __slots__ = ("rows", "values", "kinds", "stored", "ordered")

    def __init__(self):
        self.rows = array("i")
        self.values: list = []
        self.kinds: list[str] = []
        self.stored: list = []
        self.ordered = True

    def append(self, row: int, value, kind: str, stored=None) -> None:
        if self.rows and row <= self.rows[-1]:
            self.ordered = False
        self.rows.append(row)
        self.values.append(value)
        self.kinds.append(kind)
        self.stored.append(stored)

    def finish(self) -> None:
        """Rows in order, one cell each: a cell written again (the same address twice) is the
        last one written, as a dict keyed by address holds it."""
        if self.ordered:
            return
        last = {row: i for i, row in enumerate(self.rows)}
        keep = [last[row] for row in sorted(last)]
        self.rows = array("i", [self.rows[i] for i in keep])
        self.values = [self.values[i] for i in keep]
        self.kinds = [self.kinds[i] for i in keep]
        self.stored = [self.stored[i] for i in keep]
        self.ordered = True

    def index(self, row: int) -> int | None:
        i = bisect_left(self.rows, row)
        return i if i < len(self.rows) and self.rows[i] == row else None


class HeldCell:
    """A cell of a Column, made when asked for: its value and kind are read from (and written
    to) the column."""
    __slots__ = ("parent", "row", "column", "_held", "_i")

    def __init__(self, parent, row: int, column: int, held: Column, i: int):
        self.parent, self.row, self.column, self._held, self._i = parent, row, column, held, i

    @property
    def value(self):
        return self._held.values[self._i]

    @value.setter
    def value(self, value) -> None:
        self._held.values[self._i] = value

    @property
    def data_type(self) -> str:
        return self._held.kinds[self._i]

    @data_type.setter
    def data_type(self, kind: str) -> None:
        self._held.kinds[self._i] = kind

    @property
    def coordinate(self) -> str:
        return f"{column_letter(self.column)}{self.row}"


class Worksheet:
    def __init__(self, title: str):
        self.title = title
        self.held_columns: dict[int, Column] = {}

    def __getitem__(self, coordinate: str) -> Cell | HeldCell:
        return self.cell(*coordinate_to_tuple(coordinate))

    def cell(self, row: int, column: int) -> Cell | HeldCell:
        held = self.held_columns.get(column)
        i = None if held is None else held.index(row)
        return Cell(self, row, column, None, "n") if i is None else \
            HeldCell(self, row, column, held, i)

    def stored_items(self):
        """((row, column), (kind, text)) of every formula cell that stores a value."""
        for col, held in self.held_columns.items():
            for row, stored in zip(held.rows, held.stored):
                if stored is not None:
                    yield (row, col), (stored if type(stored) is tuple else ("n", stored))

    @property
    def _cells(self) -> dict[tuple[int, int], HeldCell]:
        """openpyxl's {(row, column): cell}, made on demand (a cell object each: for tests and
        small sheets, not for a big book's every cell)."""
        return {(row, col): HeldCell(self, row, col, held, i)
                for col, held in self.held_columns.items() for i, row in enumerate(held.rows)}

    @property
    def max_row(self) -> int:
        return max((held.rows[-1] for held in self.held_columns.values()), default=1)

    @property
    def max_column(self) -> int:
        return max(self.held_columns, default=1)


# one text object for each kind a cell can have, not one a cell
KINDS = {kind: kind for kind in ("n", "s", "b", "e", "d", "str", "inlineStr")}


def column_entries(ws):
    """(column, rows, values, data_types) of each column of a worksheet that holds cells, the
    rows in order: the view's columns as it holds them, or an openpyxl worksheet's cells."""
    if isinstance(ws, Worksheet):
        return ((col, held.rows, held.values, held.kinds)
                for col, held in ws.held_columns.items())
    by_column: dict[int, list] = {}
    for (row, col), c in sorted(ws._cells.items(), key=lambda item: item[0][::-1]):
        by_column.setdefault(col, []).append((row, c.value, c.data_type))
    return ((col, *map(list, zip(*cells))) for col, cells in by_column.items())


@dataclass(frozen=True)
class DefinedName:
    """A defined name of the book, as its workbook part writes it."""
    name: str
    attr_text: str
    hidden: bool = False
    localSheetId: str | None = None     # the index of the sheet, as written


class Workbook:
    def __init__(self, worksheets: list[Worksheet], defined_names: dict[str, DefinedName],
                 notes: list[str] | None = None):
        self.worksheets = worksheets
        self.defined_names = defined_names
        # what the book holds that does not change its numbers but a reader should hear of
        self.notes = notes or []
        self._by_title = {ws.title: ws for ws in worksheets}

    @property
    def sheetnames(self) -> list[str]:
        return [ws.title for ws in self.worksheets]

    def __getitem__(self, title: str) -> Worksheet:
        try:
            return self._by_title[title]
        except KeyError:
            raise KeyError(f"Worksheet {title} does not exist.") from None

    def __contains__(self, title: str) -> bool:
        return title in self._by_title


def read(path, guards: dict | None = None) -> Workbook:
    """The view of the workbook at `path` (already checked by safety.check_zip, but for the
    parts in `guards`: each is fed to its guard as it is read, before anything parses it).
    Refused is raised before Unsupported: every part is read, so a book openpyxl will load has
    been checked whole."""
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
        strings = _shared_strings(zf, "xl/sharedStrings.xml") if "xl/sharedStrings.xml" in \
            names else []
        date_styles = _date_styles(zf) if "xl/styles.xml" in names else frozenset()
        unmodelled: list[str] = []
        notes: list[str] = []
        sheets, defined = _workbook(zf, unmodelled, notes)
        worksheets = []
        for title, part in sheets:
            ws = Worksheet(title)
            _read_part(zf, part, ws, strings, date_styles, unmodelled,
                       (guards or {}).get(part))
            worksheets.append(ws)
    if unmodelled:
        raise Unsupported(unmodelled[0])
    return Workbook(worksheets, defined, notes)


def _workbook(zf: zipfile.ZipFile, unmodelled: list[str], notes: list[str]):
    """[(sheet title, part name)] in tab order (worksheets only: any other kind of sheet is
    noted in `unmodelled`), and the workbook-scoped defined names."""
    targets = {}
    with zf.open("xl/_rels/workbook.xml.rels") as f:
        for _, el in iterparse(f):
            if el.tag == f"{PKG_REL}Relationship":
                targets[el.get("Id")] = (el.get("Target"), el.get("Type", ""))
    titles, sheets, entries = [], [], []
    with zf.open("xl/workbook.xml") as f:
        for _, el in iterparse(f):
            if el.tag == f"{MAIN}sheet":
                titles.append(el.get("name"))
                target, kind = targets[el.get(f"{REL}id")]
                if not kind.endswith("/worksheet"):
                    unmodelled.append(f"sheet {el.get('name')!r} is not a worksheet")
                    continue
                part = (target.lstrip("/") if target.startswith("/")
                        else str(PurePosixPath("xl") / target))
                sheets.append((el.get("name"), part))
            elif el.tag == f"{MAIN}definedName":
                entries.append(DefinedName(el.get("name") or "", el.text or "",
                                           el.get("hidden") in ("1", "true"),
                                           el.get("localSheetId")))
    return sheets, _workbook_names(entries, titles, notes)


def _workbook_names(entries: list[DefinedName], titles: list[str],
                    notes: list[str]) -> dict[str, DefinedName]:
    """The workbook-scoped names, once every name is known to be unambiguous: Excel compares
    names without case, so A_2 after a_2 in one scope is a second definition (Excel reads the
    first, openpyxl the last); and a formula on a sheet with its own a_2 reads that one, which
    verify, reading workbook-scoped names only, would not. Excel's built-in names (print titles
    and areas, filters) are the application's, and no formula of a book reads them: LibreOffice
    writes each sheet's print titles twice, in both orders, so a repeat meaning the same ranges
    passes, and one meaning others is a note in `notes`, not a reason to refuse the numbers."""
    def scope(entry: DefinedName) -> str:
        local = entry.localSheetId
        if local is None:
            return "the workbook"
        title = titles[int(local)] if local.isascii() and local.isdigit() and int(local) < len(titles) else None
        return f"sheet {title!r}" if title is not None else f"sheet number {local}"

    seen: dict[tuple, DefinedName] = {}
    for entry in entries:
        key = (entry.localSheetId, entry.name.upper())
        first = seen.setdefault(key, entry)
        if first is not entry and is_built_in(entry.name):
            if _areas(first.attr_text) != _areas(entry.attr_text):
                notes.append(f"xl/workbook.xml: the built-in name {entry.name!r} is defined "
                             f"twice in {scope(entry)} with other ranges ({first.attr_text!r} "
                             f"and {entry.attr_text!r}); no formula reads it")
        elif first is not entry:
            raise Refused(f"xl/workbook.xml: the name {entry.name!r} is defined twice in "
                          f"{scope(entry)} ({first.attr_text!r} and {entry.attr_text!r}; "
                          "names are compared without case)")
    for entry in entries:
        shadowed = seen.get((None, entry.name.upper()))
        if entry.localSheetId is not None and shadowed is not None and not is_built_in(entry.name) \
                and entry.attr_text.upper() != shadowed.attr_text.upper():
            raise Refused(f"xl/workbook.xml: the name {entry.name!r} of {scope(entry)} "
                          f"({entry.attr_text!r}) shadows the workbook's {shadowed.name!r} "
                          f"({shadowed.attr_text!r}) for that sheet's formulas; verify reads "
                          "workbook names only")
    return {e.name: DefinedName(e.name, e.attr_text, e.hidden) for e in entries
            if e.localSheetId is None}


def _text(el) -> str:
    """The text of a string item: its <t>, or its runs' <t>s (phonetic runs left out)."""
    t = el.find(f"{MAIN}t")
    if t is not None:
        return t.text or ""
    return "".join(r.findtext(f"{MAIN}t") or "" for r in el.iterfind(f"{MAIN}r"))


def _shared_strings(zf: zipfile.ZipFile, part: str) -> list[str]:
    out = []
    with zf.open(part) as f:
        for _, el in iterparse(f):
            if el.tag == f"{MAIN}si":
                out.append(_text(el).replace("x005F_", ""))
                el.clear()
    return out


def _date_styles(zf: zipfile.ZipFile) -> frozenset[int]:
    """Indexes of the cell formats (the `s` of a cell) that show a number as a date or time."""
    codes, xfs, in_cell_xfs = {}, [], False
    with zf.open("xl/styles.xml") as f:
        for event, el in iterparse(f, events=("start", "end")):
            if el.tag == f"{MAIN}cellXfs":
                in_cell_xfs = event == "start"
            elif event == "end" and el.tag == f"{MAIN}numFmt":
                codes[int(el.get("numFmtId"))] = el.get("formatCode", "")
            elif event == "end" and el.tag == f"{MAIN}xf" and in_cell_xfs:
                xfs.append(int(el.get("numFmtId", 0)))
    return frozenset(i for i, fmt in enumerate(xfs)
                     if (fmt in DATE_FORMAT_IDS and fmt not in codes)
                     or (fmt in codes and _DATE_LETTERS.search(_NOT_DATE_PARTS.sub("", codes[fmt]))))


def _read_part(zf: zipfile.ZipFile, part: str, ws: Worksheet, strings: list[str],
               date_styles: frozenset[int], unmodelled: list[str], guard=None) -> None:
    """The cells of one sheet part into `ws`: scanned (_scan_cells) where the part is written
    as the scan reads it, else read element by element (_read_cells) from the start again.
    `guard` (safety.PartGuard) is fed each chunk the scan reads before expat sees it, and the
    whole part before ElementTree reads it (the scan may stop before the root element: a
    carriage return in the declaration)."""
    noted = len(unmodelled)
    try:
        with zf.open(part) as f:
            _scan_cells(f if guard is None else _Guarded(f, guard), ws, strings, date_styles,
                        part, unmodelled)
        return
    except Refused:     # the part is well-formed up to the cell refused: the elements say so too
        raise
    except Exception:   # not as the scan reads it (or damaged): the elements say what it holds
        if guard is not None and guard.refused:     # a DTD: nothing parses the part
            raise
        ws.held_columns.clear()
        del unmodelled[noted:]
    if guard is not None and not guard.whole:
        with zf.open(part) as f:        # all of it scanned before ElementTree reads any of it
            whole = _Guarded(f, type(guard)(guard.part, guard.path))
            while whole.read(SCAN_CHUNK):
                pass
            guard.bracket, guard.whole = whole.guard.bracket, True
    with zf.open(part) as f:
        _read_cells(f, ws, strings, date_styles, part, unmodelled)


class _Guarded:
    """A part's file whose every chunk read goes to `guard` first (safety.PartGuard)."""

    def __init__(self, f, guard):
        self.f, self.guard = f, guard

    def read(self, size: int = -1) -> bytes:
        chunk = self.f.read(size)
        self.guard(chunk)
        return chunk


# The scan: a sheet part as the writers of .xlsx write it (openpyxl, LibreOffice, Gnumeric,
# Excel), read by regular expressions over its text instead of an element object per cell; expat
# checks the text is well-formed XML as it goes (a damaged part is then read by _read_cells,
# which says what is wrong as before). What the scan does not read exactly as ElementTree would
# (an inline string of runs, a comment, CDATA, a namespace prefix, an encoding other than UTF-8,
# a carriage return, attributes in another order or form) stops it: the part is then read
# element by element.
SCAN_CHUNK = 1 << 16      # text held at a time: the cells of a few hundred rows
# a cell as the writers write it: r, s and t in that order, a formula (its attributes, its text),
# a stored value and an inline string of one text, white space between them (as Gnumeric writes
# them; a cell's own text is no part of its value); "<f", "<v" and "<is>" are kept to tell an
# empty element from none
_CELL = re.compile(r'<c r="([A-Z]{1,3})([0-9]+)"(?: s="([0-9]+)")?(?: t="([A-Za-z]+)")?'
                   r'(?:/>|>[ \t\n]*(?:(<f)([^<>]*?)(?:/>|>([^<]*)</f>)[ \t\n]*)?'
                   r'(?:(<v)(?:/>|>([^<]*)</v>)[ \t\n]*)?'
                   r'(?:(<is>)[ \t\n]*<t(?: xml:space="preserve")?(?:/>|>([^<]*)</t>)[ \t\n]*'
                   r'</is>[ \t\n]*)?</c>)')
_ATTRIBUTE = re.compile(r"""([A-Za-z_][\w.\-]*)\s*=\s*(?:"([^"]*)"|'([^']*)')""")
_ENTITY = re.compile(r"&(#x[0-9A-Fa-f]+|#[0-9]+|amp|lt|gt|quot|apos);")
_NAMED_ENTITIES = {"amp": "&", "lt": "<", "gt": ">", "quot": '"', "apos": "'"}
_MAIN_DEFAULT = f'xmlns="{MAIN[1:-1]}"'
_DECLARATION = re.compile(r"""<\?xml[^?]*?encoding\s*=\s*["']([^"']*)["']""")
_OTHER_CELLS = re.compile(r"<c[\s/>]|<row[\s/>]")
# a prefix's declaration: one bound to the main namespace makes <x:c> a cell the elements read
# (the form controls' markup openpyxl writes after <sheetData> binds others, with <xdr:row>s)
_PREFIX_DECLARATION = re.compile(r"""xmlns:[A-Za-z_][\w.\-]*\s*=\s*(?:"([^"]*)"|'([^']*)')""")


def _binds_main(text: str, start: int = 0) -> bool:
    """Whether `text` from `start` binds a prefix to the main namespace (or to a value spelled
    with a reference, which the scan does not read)."""
    return any(uri == MAIN[1:-1] or "&" in uri for double, single in
               _PREFIX_DECLARATION.findall(text, start) for uri in (double or single,))


class _NotScanned(Exception):
    """The part holds what the scan does not read exactly as ElementTree does."""


def _unescaped(text: str) -> str:
    """Character data (holding a '&') with XML's five entities and character references
    replaced."""
    if "&#" not in text:
        # '&amp;' last: only it makes a '&', so no entity is read twice ('&amp;lt;' is '&lt;')
        return text.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", '"') \
            .replace("&apos;", "'").replace("&amp;", "&")

    def one(m):
        name = m[1]
        if name[0] == "#":
            return chr(int(name[2:], 16) if name[1] in "xX" else int(name[1:]))
        return _NAMED_ENTITIES[name]
    return _ENTITY.sub(one, text)


def _attributes(text: str) -> dict[str, str]:
    found = {}
    for name, double, single in _ATTRIBUTE.findall(text):
        found[name] = double if double or not single else single
    return found


def _scan_cells(f, ws: Worksheet, strings: list[str], date_styles: frozenset[int], part: str,
                unmodelled: list[str]) -> None:
    """The cells of one sheet part into `ws`, scanned (see SCAN_CHUNK); _NotScanned, or expat's
    error for a part that is not well-formed XML, where the scan does not apply."""
    import codecs
    from xml.parsers import expat
    checker, decoder = expat.ParserCreate(), codecs.getincrementaldecoder("utf-8")()
    head, body, where = "", "", "head"
    for chunk in iter(lambda: f.read(SCAN_CHUNK), b""):
        checker.Parse(chunk, False)
        text = decoder.decode(chunk)
        if "\r" in text:
            raise _NotScanned("a carriage return")
        if where == "head":
            head += text
            start = head.find("<sheetData>")
            if start < 0:
                continue
            _check_head(head[:start])
            body, where = head[start + len("<sheetData>"):], "body"
        else:
            body += text
        end = body.rfind("</row>")
        if end >= 0:
            _scan_rows(body[:end + len("</row>")], ws, strings, date_styles, part, unmodelled)
            body = body[end + len("</row>"):]
    checker.Parse(b"", True)
    if where == "head":
        raise _NotScanned("no <sheetData> element")
    end = body.find("</sheetData>")
    if end < 0:
        raise _NotScanned("no end of <sheetData>")
    _scan_rows(body[:end], ws, strings, date_styles, part, unmodelled)
    if _OTHER_CELLS.search(body, end) or _binds_main(body, end):
        raise _NotScanned("cells after <sheetData>")
    for held in ws.held_columns.values():
        held.finish()


def _check_head(head: str) -> None:
    """The part up to <sheetData>: UTF-8, the main namespace the default one and declared once,
    no cells and nothing that makes the text read otherwise (a DOCTYPE)."""
    declared = _DECLARATION.match(head)
    if head.startswith("\ufeff") \
            or (declared and declared[1].lower().replace("-", "") != "utf8"):
        raise _NotScanned("an encoding other than UTF-8")
    if head.count("xmlns=") != 1 or _MAIN_DEFAULT not in head or "<!" in head \
            or _binds_main(head) \
            or _OTHER_CELLS.search(head) or not re.search(r"<worksheet[\s>]", head):
        raise _NotScanned("namespaces the scan does not read")


def _scan_rows(text: str, ws: Worksheet, strings: list[str], date_styles: frozenset[int],
               part: str, unmodelled: list[str]) -> None:
    """The cells in `text` (whole rows of <sheetData>) into `ws`: every element that starts
    with '<c' a cell as _CELL reads it, and nothing else to read (a comment, CDATA, a namespace
    declaration)."""
    cells = _CELL.findall(text)
    if len(cells) != text.count("<c") or "<!" in text or "<?" in text or "xmlns" in text:
        raise _NotScanned("a cell as the scan does not read it")
    columns = ws.held_columns
    for (letters, digits, style, kind, f_open, f_attrs, f_text, v_open, v_text, is_open,
         is_text) in cells:
        if f_open and not (kind or f_attrs or v_text) and len(f_text) <= FORMULA_NESTING_LIMIT:
            # most cells: a formula storing no value, too short to reach Excel's limits
            col = column_index(letters)
            held = columns.get(col)
            if held is None:
                held = columns[col] = Column()
            held.append(int(digits), "=" + (f_text if "&" not in f_text else _unescaped(f_text)),
                        "f")
            continue
        if "&" in f_attrs:
            raise _NotScanned("an entity in a formula's attributes")
        formula = None if not f_open else (
            f_text if "&" not in f_text else _unescaped(f_text),
            _attributes(f_attrs).get("t") if f_attrs else None)
        _put(ws, int(digits), column_index(letters), letters + digits, kind or "n", style or 0,
             formula, None if not v_open else v_text if "&" not in v_text else
             _unescaped(v_text), None if not is_open else is_text if "&" not in is_text else
             _unescaped(is_text), strings, date_styles, part, unmodelled)


def _read_cells(f, ws: Worksheet, strings: list[str], date_styles: frozenset[int], part: str,
                unmodelled: list[str]) -> None:
    """The cells of one sheet part into `ws`, element by element; what the view does not model
    is noted in `unmodelled` and reading goes on, so that all of the book is checked."""
    c_tag, v_tag, f_tag, is_tag = f"{MAIN}c", f"{MAIN}v", f"{MAIN}f", f"{MAIN}is"
    row_tag = f"{MAIN}row"
    for _, el in iterparse(f):
        tag = el.tag
        if tag == row_tag:
            el.clear()
            continue
        if tag != c_tag:
            continue
        address = el.get("r")
        m = _COORDINATE.match(address) if address else None
        if m is None:
            raise Unsupported("a cell without its address")
        formula, kind = el.find(f_tag), el.get("t", "n")
        inline = el.find(is_tag) if kind == "inlineStr" and formula is None else None
        _put(ws, int(m[2]), column_index(m[1]), address, kind, el.get("s", 0),
             None if formula is None else (formula.text or "", formula.get("t")),
             el.findtext(v_tag), _text(inline) if inline is not None else None,
             strings, date_styles, part, unmodelled)
    for held in ws.held_columns.values():
        held.finish()


def _put(ws: Worksheet, row: int, col: int, address: str, kind: str, style,
         formula: tuple | None, stored: str | None, inline: str | None, strings: list[str],
         date_styles: frozenset[int], part: str, unmodelled: list[str]) -> None:
    """One cell into `ws`, from what its element holds: its address (row, column and as
    written), its attributes t and s, its formula (text and t) or None, the text of its <v>
    (None without one) and of its inline string."""
    held = ws.held_columns.get(col)
    if held is None:
        held = ws.held_columns[col] = Column()
    if formula is not None:
        text, shared = formula
        if len(text) > FORMULA_NESTING_LIMIT and (len(text) > FORMULA_LENGTH_LIMIT
                                                  or text.count("(") > FORMULA_NESTING_LIMIT):
            _check_formula(text, part, ws.title, address)
        if shared in ("shared", "array", "dataTable"):
            unmodelled.append(f"{ws.title}!{address}: a {shared} formula")
        if stored or kind == "str":     # an empty <v> stores nothing, but as empty text
            stored = (_number(stored, part, ws.title, address) if kind == "n" else
                      (kind, _shared(strings, stored, part, ws.title, address)
                       if kind == "s" else stored or ""))
        else:
            stored = None
        held.append(row, "=" + text, "f", stored)
        return
    if kind == "inlineStr":
        value, kind = (inline, "s") if inline is not None else (None, "n")
    else:
        value = stored or None
        if value is not None:
            if kind == "n":
                if int(style) in date_styles:
                    unmodelled.append(f"{ws.title}!{address}: a number shown as a date")
                value = _number(value, part, ws.title, address)
            elif kind == "s":
                value = _shared(strings, value, part, ws.title, address)
            elif kind == "b":
                value = bool(_index(value, part, ws.title, address))
            elif kind == "str":
                kind = "s"
            elif kind == "d":
                unmodelled.append(f"{ws.title}!{address}: an ISO 8601 date")
    held.append(row, value, KINDS.get(kind, kind))


def _number(text: str, part: str, title: str, address: str) -> int | float:
    """A stored number as openpyxl reads it (a '.', 'e' or 'E' makes a float), once it is
    known to be one the application reads as the same finite number."""
    if _NUMBER.fullmatch(text) and math.isfinite(as_float := float(text)):
        if "." in text or "e" in text or "E" in text:
            return as_float
        try:
            return int(text)
        except ValueError:      # digits past int()'s limit (leading zeros): nothing reads that
            pass
    raise Refused(f"{part}: cell {title}!{address} holds {_shown(text)}, not a finite number "
                  "in XML Schema's form (the spreadsheet application would read it otherwise)")


def _shown(text: str, most: int = 40) -> str:
    """A cell's text for a one-line message: whole when short, else its start and its length."""
    if len(text) <= most:
        return repr(text)
    return f"{text[:most]!r}… ({len(text):,} characters)"


def _index(text: str, part: str, title: str, address: str) -> int:
    """A shared string's index or a boolean's 0/1: digits only."""
    if _INDEX.fullmatch(text) and len(text) <= 18:
        return int(text)
    raise Refused(f"{part}: cell {title}!{address} holds {_shown(text)} where a whole number "
                  "belongs")


def _shared(strings: list[str], text: str, part: str, title: str, address: str) -> str:
    """The shared string a cell's index names; refused when the table has no such entry."""
    index = _index(text, part, title, address)
    if index < len(strings):
        return strings[index]
    raise Refused(f"{part}: cell {title}!{address} names shared string {index}, and the table "
                  f"has {len(strings)}")


def _check_formula(text: str, part: str, title: str, address: str) -> None:
    """Refuse a formula Excel would not hold, before anything parses it: parsing costs grow
    with its length, and deep nesting crashes LibreOffice. (Called where the formula is long
    or has many brackets: a cheap test in the loop over cells keeps the call off most.)"""
    problem = formula_problem(text)
    if problem:
        raise Refused(f"{part}: cell {title}!{address} has a formula {problem}")


def formula_problem(text: str) -> str | None:
    """How a formula's text is beyond Excel's limits ("of 9,000 characters; Excel's limit is
    8,192"), or None: what verify refuses in a book, and build before it writes one."""
    if len(text) > FORMULA_LENGTH_LIMIT:
        return f"of {len(text):,} characters; Excel's limit is {FORMULA_LENGTH_LIMIT:,}"
    if text.count("(") <= FORMULA_NESTING_LIMIT:
        return None
    deepest = _nesting(text)
    if deepest > FORMULA_NESTING_LIMIT:
        return f"nested {deepest} brackets deep; Excel's limit is {FORMULA_NESTING_LIMIT} levels"
    return None


_ASCII_BUT_BRACKETS = {i: None for i in range(128) if chr(i) not in "()"}


def _nesting(text: str) -> int:
    """How deep a formula's brackets nest (outside its strings and quoted sheet names): exact up
    to one level past the limit, and past the limit beyond it. Each pass takes away the
    innermost pairs, so the passes count the levels, each a scan at C speed. A bracket never
    closed counts as one more level."""
    if '"' in text or "'" in text:
        text = _QUOTED.sub("", text)
    brackets = text.translate(_ASCII_BUT_BRACKETS)      # a table lookup per character, in C
    if len(brackets) != brackets.count("(") + brackets.count(")"):
        brackets = _NOT_BRACKET.sub("", brackets)        # characters beyond ASCII were kept
    return _bracket_depth(brackets)


def bracket_depth(text: str) -> int:
    """How deep the brackets of a formula or expression nest (see _nesting)."""
    return _nesting(text) if "(" in text else 0


@functools.lru_cache(maxsize=512)       # a grid's formulas share their brackets' pattern
def _bracket_depth(brackets: str) -> int:
    passes = 0
    while "()" in brackets and passes <= FORMULA_NESTING_LIMIT:
        brackets = brackets.replace("()", "")
        passes += 1
    return passes + brackets.count("(")


# ---------------------------------------------------------------- external references
EXTERNAL_LINKS = "xl/externalLinks/"      # the parts of the workbooks a book links to
# A formula reads another workbook through [n], the index of its external link, before a sheet
# or a name ('[1]Sheet1!A1', '[1]!total'); text in double quotes is no reference.
_EXTERNAL = re.compile(r"\[\d+\]")
_STRING = re.compile(r'"(?:[^"]|"")*"')


def external_reference(zf: zipfile.ZipFile, bracketed: list[str]) -> str | None:
    """Where the book reads another file: the first formula of a sheet part in `bracketed`
    (the parts that hold a '[') with an external reference, else the first external-link
    part, with the file it names; None when the book names none. Nothing is opened but the
    book's own parts."""
    links = sorted(n for n in zf.namelist() if n.startswith(EXTERNAL_LINKS)
                   and not n.endswith(".rels"))
    sheets = [p for p in bracketed if p.startswith("xl/worksheets/")]
    if sheets:
        titles = _sheet_titles(zf)
        for part in sheets:
            found = _external_formula(zf, part, titles.get(part, part))
            if found:
                return found
    if links:
        return f"part {links[0]} is an external reference{_link_target(zf, links[0])}"
    return None


def _external_formula(zf: zipfile.ZipFile, part: str, title: str) -> str | None:
    address = "?"
    with zf.open(part) as f:
        for event, el in iterparse(f, events=("start", "end")):
            if event == "start":
                if el.tag == f"{MAIN}c":
                    address = el.get("r") or "?"
            elif el.tag == f"{MAIN}f" and el.text \
                    and _EXTERNAL.search(_STRING.sub("", el.text)):
                return f"cell {title}!{address} has an external reference ({_shown(el.text)})"
            elif el.tag == f"{MAIN}row":
                el.clear()
    return None


def _sheet_titles(zf: zipfile.ZipFile) -> dict[str, str]:
    """{sheet part: title}, or {} where the workbook's parts do not say."""
    try:
        sheets, _ = _workbook(zf, [], [])
    except Exception:       # a damaged workbook part: the refusal names the sheet part
        return {}
    return {part: title for title, part in sheets}


def _link_target(zf: zipfile.ZipFile, link: str) -> str:
    """' to <the file it names>', as its relationship says, or ''."""
    folder, name = link.rsplit("/", 1)
    rels = f"{folder}/_rels/{name}.rels"
    if rels not in zf.namelist():
        return ""
    with zf.open(rels) as f:
        for _, el in iterparse(f):
            if el.tag == f"{PKG_REL}Relationship" and el.get("Target"):
                return f" to {_shown(el.get('Target'), 80)}"
    return ""


def coordinate_to_tuple(coordinate: str) -> tuple[int, int]:
    """'B7' -> (7, 2), as openpyxl.utils.cell.coordinate_to_tuple."""
    m = _COORDINATE.match(coordinate)
    if not m:
        raise ValueError(f"{coordinate!r} is not a cell address")
    return int(m[2]), column_index(m[1])


def coordinates_to_arrays(coordinates: list[str]):
    """The rows and the columns of `coordinates` as two int64 arrays, as coordinate_to_tuple
    gives each: plain addresses ('B7', 'AB12': a column of a table, the cells a check names)
    read all at once from their characters' codes; any other spelling ('$B$7', 'b7') cell by
    cell. ValueError for an empty list or one that is no cell address, TypeError for one that
    is no text, as coordinate_to_tuple would raise."""
    import numpy as np
    if type(coordinates) is ColumnCells:
        found = coordinates.places()
        if found is not None:
            return found
    text = np.array(coordinates)
    if text.dtype.kind == "U" and 2 <= text.dtype.itemsize // 4 <= 12:
        codes = text.view(np.uint32).reshape(len(text), -1)
        letter, digit = (codes >= 65) & (codes <= 90), (codes >= 48) & (codes <= 57)
        letters, digits = letter.sum(axis=1), digit.sum(axis=1)
        at = np.arange(codes.shape[1])
        # letters first, then digits, then nothing (the padding of shorter addresses; a text
        # that ends in NULs, which the array drops, is longer than what it holds)
        in_digits = (at >= letters[:, None]) & (at < (letters + digits)[:, None])
        if ((letters >= 1) & (letters <= 3) & (digits >= 1)).all() \
                and (letter == (at < letters[:, None])).all() and (digit == in_digits).all() \
                and (letters + digits == np.fromiter(map(len, coordinates), np.int64,
                                                     len(coordinates))).all():
            rows, cols = np.zeros(len(text), np.int64), np.zeros(len(text), np.int64)
            for j in range(codes.shape[1]):
                rows = np.where(digit[:, j], rows * 10 + codes[:, j] - 48, rows)
                cols = np.where(letter[:, j], cols * 26 + codes[:, j] - 64, cols)
            return rows, cols
    rows, cols = zip(*map(coordinate_to_tuple, coordinates))
    return np.array(rows, np.int64), np.array(cols, np.int64)


@functools.lru_cache(maxsize=None)     # a book has few distinct column letters
def column_index(letters: str) -> int:
    """'AB' -> 28 (any case)."""
    n = 0
    for ch in letters.upper():
        n = n * 26 + ord(ch) - 64
    return n


_LETTERS: dict[int, str] = {}


def column_letter(col: int) -> str:
    found = _LETTERS.get(col)
    if found is None:
        n, out = col, ""
        while n:
            n, r = divmod(n - 1, 26)
            out = chr(65 + r) + out
        found = _LETTERS[col] = out
    return found


class ColumnCells(list):
    """column_cells' list of addresses, knowing the column and the first row it names: the
    places of its cells are not read back from their texts (coordinates_to_arrays)."""
    __slots__ = ("letter", "first")

    def places(self):
        """(rows, columns) as coordinates_to_arrays gives them; None where the list no longer
        holds what column_cells made (changed since: its texts are compared, most by
        identity)."""
        import numpy as np
        n = len(self)
        if not n or tuple(self) != _column_cells(self.letter, self.first, self.first + n - 1):
            return None
        return np.arange(self.first, self.first + n, dtype=np.int64), \
            np.full(n, column_index(self.letter), np.int64)


def column_cells(letter: str, first: int, last: int) -> list[str]:
    """The addresses down column `letter` from row `first` to `last` ('B5', 'B6', …); every
    list of one column's rows shares its texts (verify names each cell in several checks, and
    again at each input set: one text a cell, not one a naming)."""
    cells = ColumnCells(_column_cells(letter, first, last))
    cells.letter, cells.first = letter, first
    return cells


@functools.lru_cache(maxsize=1024)
def _column_cells(letter: str, first: int, last: int) -> tuple[str, ...]:
    return tuple(f"{letter}{r}" for r in range(first, last + 1))


def forget_column_cells() -> None:
    """Let go of the addresses column_cells holds (verify, done with a book)."""
    _column_cells.cache_clear()


# Characters no XML 1.0 document can hold, escaped or not: the C0 controls but tab, LF and CR
# (openpyxl's ILLEGAL_CHARACTERS_RE), surrogates (Python text from undecodable bytes), U+FFFE and
# U+FFFF. openpyxl refuses them when a cell is set or saved; a cell written here must too.
NOT_IN_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")

# XML escapes of our own: xml.sax.saxutils imports urllib.request (and with it http, ssl and
# email), a fifth of the start-up of a build.
_TEXT_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;"})
_ATTRIBUTE_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;",
                                    "\n": "&#10;", "\r": "&#13;", "\t": "&#9;"})


def xml_text(value: str) -> str:
    """`value` escaped for an element's text."""
    return value.translate(_TEXT_ESCAPES)


def xml_attribute(value: str) -> str:
    """`value` as a double-quoted attribute value, quotes included."""
    return f'"{value.translate(_ATTRIBUTE_ESCAPES)}"'


# ---------------------------------------------------------------- error values
ERROR_CODES = frozenset({"#NULL!", "#DIV/0!", "#VALUE!", "#REF!", "#NAME?", "#NUM!", "#N/A",
                         "#GETTING_DATA", "#SPILL!", "#CALC!"})


class CellError(str):
    """A formula error read back from a recalculated file: str(e) is its code, e.g. '#N/A'."""

    def __repr__(self) -> str:
        return f"CellError({str(self)!r})"


def error_code(value) -> str | None:
    """'#N/A', '#NUM!', ... for an error value of any engine (CellError, the plain string that
    openpyxl reads, or an object such as formulas' XlError whose str() is the code); else None."""
    if value is None or isinstance(value, (bool, int, float)):
        return None
    text = str(value)
    return text if text in ERROR_CODES else None


def is_error(value) -> bool:
    return error_code(value) is not None


# ---------------------------------------------------------------- defined names
_CELL_A1 = re.compile(r"^\$?[A-Za-z]{1,3}\$?\d+$")
_CELL_R1C1 = re.compile(r"^[Rr](\d*|\[-?\d+\])[Cc](\d*|\[-?\d+\])$|^[RrCc]\d*$")
_NAME_CHARS = re.compile(r"^[A-Za-z_\\][A-Za-z0-9_.]*$")


def excel_name_problem(name: str) -> str | None:
    """Why `name` cannot be an Excel defined name, or None when it can."""
    if not name or len(name) > 255:
        return "must have 1 to 255 characters"
    if not _NAME_CHARS.match(name):
        return "must start with a letter or _ and hold only letters, digits, _ and ."
    if _CELL_A1.match(name) or _CELL_R1C1.match(name):
        return "looks like a cell reference"
    if name.upper() in {"TRUE", "FALSE"}:
        return "is a reserved word"
    return None
