"""The last pass over a package openpyxl saved: what openpyxl cannot write, or writes in a form
that Excel's own validator (the Open XML SDK, `openxml-audit` here) does not accept.

One streaming copy of the zip does all of it:
- text cells become shared strings (openpyxl writes every text cell as an inline string, which
  Excel moves into a new shared-strings part the first time it saves);
- the children of each `<font>` in styles.xml are put in the schema's order (openpyxl writes the
  default font's `color` after `family`);
- drawings and charts declare their namespaces on the root element (see namespaces_on_root);
- form controls (controls.py) are added to the sheets that have them;
- with `values`, every formula cell gets its cached value (cached.py);
- with `cells` (from `cells_held_back`), every sheet's `<sheetData>` is written here: openpyxl
  saves the book with its worksheets emptied of cells, and this module writes the cells as
  openpyxl would have, byte for byte but with shared strings, as text built directly rather
  than through openpyxl's XML writer (the slow part of saving a big book).

Every other part, and every other byte of the parts it touches, is copied unchanged. Worksheet
parts are streamed in chunks cut at row ends, so a sheet of 90 MB is never in memory twice (the
cells written here are held once, in chunks, next to the cells they are written from).
"""
from __future__ import annotations

import posixpath
import re
import zipfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from defusedxml import ElementTree
from openpyxl.compat import safe_string

from . import cached
from .controls import CTRL_TYPE, VML_TYPE, Control, SheetControls
from ..base.files import write_atomic
from ..base.xlsx import NOT_IN_XML, column_letter, xml_attribute

MAIN_NS = "http://schemas.openxmlformats.org/spreadsheetml/2006/main"
REL_NS = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"
PKG_REL_NS = "http://schemas.openxmlformats.org/package/2006/relationships"
SST_PART = "xl/sharedStrings.xml"
SST_TYPE = "application/vnd.openxmlformats-officedocument.spreadsheetml.sharedStrings+xml"
SST_REL = f"{REL_NS}/sharedStrings"
CHUNK = 4 * 1024 * 1024


class Formula(str):
    """A formula linkbook made ('=' first). The writer here writes a cell as a formula only when
    its value is a Formula: any other text (a title, a label, a note from a template or the
    command line) is a string cell, whatever it starts with ('=', '+', '-', '@'), so no text a
    user wrote can become a live formula."""
    __slots__ = ()

# An inline-string cell as openpyxl writes it (no namespace prefix, `t` after `r` and `s`).
INLINE = re.compile(rb'<c( [^>]*?) t="inlineStr"([^>]*)><is>(.*?)</is></c>', re.S)
# The DrawingML parts: a sheet's drawing (its charts' anchors) and each chart.
# CT_Font's children in the schema's order.
FONT_ORDER = ("b", "i", "strike", "condense", "extend", "outline", "shadow", "u", "vertAlign",
              "sz", "color", "name", "family", "charset", "scheme")
# Worksheet children that come after <legacyDrawing> (CT_Worksheet's sequence; <controls> comes
# after legacyDrawingHF, drawingHF, picture and oleObjects, but a sheet with those has no place
# for both without splitting them, and linkbook's sheets have none).
AFTER_CONTROLS = ("legacyDrawingHF", "drawingHF", "picture", "oleObjects", "controls",
                  "webPublishItems", "tableParts", "extLst")


def add_cached_values(path_in, path_out, values: dict) -> int:
    """Copy path_in to path_out with a cached value in every formula cell found in `values`
    ((sheet title, 'B7') -> float | str | bool | error). Errors may be xlsx.CellError (a
    recalculation's), the plain code string ('#N/A') or any object whose str() is a known code
    (formulas' XlError).
    Returns how many formula cells got a value; formula cells missing from `values` keep what
    they had. path_out may be path_in: the file is replaced only when the copy is complete."""
    return finish(path_in, path_out, values=values, tidy=False)


def finish(path_in, path_out, *, values: dict | None = None,
           controls: dict[str, list[Control]] | None = None, tidy: bool = True,
           cells: "HeldCells | None" = None) -> int:
    """Copy path_in to path_out, finished (see the module's docstring). `values`: (sheet title,
    'B7') -> value of formula cells, as add_cached_values takes them; `controls`: sheet
    title -> its form controls; `tidy`: shared strings and fonts in order; `cells`: the cells
    `cells_held_back` kept from openpyxl's save (`tidy` is then implied). Returns how many
    formula cells got a cached value. path_out may be path_in: the file is replaced only when
    the copy is complete."""
    path_in, path_out = Path(path_in), Path(path_out)
    with zipfile.ZipFile(path_in) as zin:
        names = set(zin.namelist())
        parts = sheet_parts(zin)
        by_part = _values_by_part(values or {}, parts)
        if cells is not None:
            if SST_PART in names:
                raise ValueError(f"{path_in} has shared strings of its own")
            strings = cells.strings
            held = {parts[title]: sheet for title, sheet in cells.sheets.items()}
        else:
            strings = _SharedStrings() if tidy and SST_PART not in names else None
            held = {}
        with_controls = _place_controls(zin, controls or {}, parts)
        rels_added = {sc.sheet_part: sc for sc in with_controls}
        written = 0

        def copy(tmp: Path) -> None:
            nonlocal written
            with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
                for info in zin.infolist():
                    name = info.filename
                    if name in parts.values():
                        sc = rels_added.get(name)
                        tail = _controls_tail(sc) if sc else None
                        written += _copy_sheet(zin, zout, info, by_part.get(name), strings, tail,
                                               held.get(name))
                        continue
                    data = zin.read(info)
                    if name == "[Content_Types].xml":
                        data = _content_types(data, with_controls, strings is not None)
                    elif name == "xl/_rels/workbook.xml.rels" and strings is not None:
                        data = _add_relationships(data, [(_free_id(data), SST_REL,
                                                          "sharedStrings.xml")])
                    elif name == "xl/styles.xml" and tidy:
                        data = fonts_in_order(data)
                    elif tidy and _DRAWING_PART.fullmatch(name):
                        data = namespaces_on_root(data)
                    elif name == "xl/workbook.xml" and values is not None:
                        data = cached.full_calc_on_load(data)
                    elif (owner := _rels_owner(name)) in rels_added:
                        data = _add_relationships(data, rels_added[owner].relationships())
                    zout.writestr(_same_entry(info), data)
                for sc in with_controls:
                    rels = _rels_part(sc.sheet_part)
                    if rels not in names:
                        zout.writestr(rels, _add_relationships(EMPTY_RELS, sc.relationships()))
                    for part, data in sc.parts().items():
                        zout.writestr(part, data)
                if strings is not None:
                    zout.writestr(SST_PART, strings.xml())

        write_atomic(path_out, copy)
    return written


EMPTY_RELS = f'<Relationships xmlns="{PKG_REL_NS}"></Relationships>'.encode()


# ---------------------------------------------------------------- where each sheet lives
def sheet_parts(zin: zipfile.ZipFile) -> dict[str, str]:
    """Sheet title -> zip part name, from xl/workbook.xml and its relationships."""
    book = ElementTree.fromstring(zin.read("xl/workbook.xml"))
    rels = ElementTree.fromstring(zin.read("xl/_rels/workbook.xml.rels"))
    targets = {r.get("Id"): r.get("Target") for r in rels.iter(f"{{{PKG_REL_NS}}}Relationship")}
    parts = {}
    for sheet in book.iter(f"{{{MAIN_NS}}}sheet"):
        target = targets.get(sheet.get(f"{{{REL_NS}}}id"))
        if target:
            parts[sheet.get("name")] = _part_name(target)
    return parts


def _part_name(target: str) -> str:
    """A relationship target is relative to xl/ unless it starts with '/'."""
    if target.startswith("/"):
        return target.lstrip("/")
    return posixpath.normpath(posixpath.join("xl", target))


def _rels_part(part: str) -> str:
    folder, name = posixpath.split(part)
    return posixpath.join(folder, "_rels", name + ".rels")


def _rels_owner(rels: str) -> str | None:
    folder, name = posixpath.split(rels)
    if posixpath.basename(folder) != "_rels" or not name.endswith(".rels"):
        return None
    return posixpath.join(posixpath.dirname(folder), name[:-len(".rels")])


def _values_by_part(values: dict, parts: dict[str, str]) -> dict[str, dict[bytes, object]]:
    by_part: dict[str, dict[bytes, object]] = {}
    for (sheet, cell), value in values.items():
        part = parts.get(sheet)
        if part is not None:
            by_part.setdefault(part, {})[cell.replace("$", "").upper().encode()] = value
    return by_part


def _same_entry(info: zipfile.ZipInfo) -> zipfile.ZipInfo:
    """A fresh entry with the original's name, date and compression."""
    out = zipfile.ZipInfo(info.filename, date_time=info.date_time)
    out.compress_type = info.compress_type
    out.external_attr = info.external_attr
    return out


# ---------------------------------------------------------------- worksheet parts
def _copy_sheet(zin, zout, info, cells: dict[bytes, object] | None,
                strings: "_SharedStrings | None", tail, held: "_SheetCells | None" = None) -> int:
    """Stream one worksheet part through the cell rewriters, cut at row ends; `tail` edits
    what follows the last row (where `<legacyDrawing>` and `<controls>` go); `held`: the
    sheet's cells, written in place of the `<sheetData>` openpyxl wrote without them."""
    count = [0]

    def rewrite(match: re.Match) -> bytes:
        new = cached.cell_with_value(match, cells)
        if new is not None:
            count[0] += 1
            return new
        if strings is not None:
            return strings.cell(match.group(0))
        return match.group(0)

    def convert(text: bytes) -> bytes:
        if cells:
            return cached.CELL.sub(rewrite, text)
        if strings is not None:
            return INLINE.sub(strings.inline, text)
        return text

    if held is not None:
        with zout.open(_same_entry(info), "w", force_zip64=True) as dst:
            head, rest = held.around(zin.read(info))
            dst.write(head)
            for chunk in held.rows:
                dst.write(cached.CELL.sub(rewrite, chunk) if cells else chunk)
            dst.write(tail(rest) if tail else rest)
        return count[0]
    with zin.open(info) as src, zout.open(_same_entry(info), "w", force_zip64=True) as dst:
        pending = b""
        while chunk := src.read(CHUNK):
            pending += chunk
            cut = pending.rfind(b"</row>")
            if cut < 0:
                continue
            cut += len(b"</row>")
            dst.write(convert(pending[:cut]))
            pending = pending[cut:]
        last = convert(pending)
        dst.write(tail(last) if tail else last)
    return count[0]


class _SharedStrings:
    """The shared-strings table, filled as the sheets stream by: an inline string's `<is>` and a
    shared string's `<si>` have the same content model, so the content moves over byte for byte."""

    def __init__(self) -> None:
        self.index: dict[bytes, int] = {}
        self.count = 0

    def add(self, body: bytes) -> int:
        """The index of a string's `<si>` content (as an inline string's `<is>` holds it)."""
        self.count += 1
        return self.index.setdefault(body, len(self.index))

    def inline(self, m: re.Match) -> bytes:
        i = self.add(m.group(3))
        return b"<c" + m.group(1) + b' t="s"' + m.group(2) + b"><v>" + str(i).encode() + b"</v></c>"

    def cell(self, element: bytes) -> bytes:
        m = INLINE.fullmatch(element)
        return self.inline(m) if m else element

    def xml(self) -> bytes:
        items = b"".join(b"<si>" + body + b"</si>" for body in self.index)
        return (b'<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\n'
                + f'<sst xmlns="{MAIN_NS}" count="{self.count}" '
                  f'uniqueCount="{len(self.index)}">'.encode() + items + b"</sst>")


# ---------------------------------------------------------------- cells written here
# What openpyxl 3.1 writes for a cell (openpyxl.cell._writer.lxml_write_cell), with lxml's
# escapes (&, <, > and CR in text; non-ASCII as decimal character references), except that text
# goes to the shared strings as `finish` would move it there.
def _escaped(text: str) -> str:
    """Text for an element's content, as openpyxl escapes it (& < > and CR). Chained replaces
    run at C speed, where str.translate with a table calls back per character: every formula
    with a domain test holds a comparison to escape."""
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace("\r", "&#13;"))


ROWS_PER_CHUNK = 2000


@dataclass
class _SheetCells:
    """One worksheet's cells written as XML, held back from openpyxl's save."""
    dimension: str                       # openpyxl's calculate_dimension() of the real cells
    rows: list[bytes]                    # the `<row>` elements, in chunks

    def around(self, part: bytes) -> tuple[bytes, bytes]:
        """The part openpyxl wrote without cells, cut where the rows go: up to `<sheetData>`
        (with the true dimension) and from `</sheetData>`."""
        m = re.search(rb"<sheetData(?:/>|>.*?</sheetData>)", part, re.S)
        if m is None:
            raise ValueError("a worksheet part without <sheetData>")
        # openpyxl wrote the dimension of the emptied sheet (A1:A1): `<dimension ref=".."/>`
        # through lxml, `<dimension ref=".." />` through its own XML writer
        head, found = _DIMENSION.subn(f'<dimension ref="{self.dimension}"/>'.encode(),
                                      part[:m.start()], count=1)
        if not found:
            raise ValueError("a worksheet part without <dimension>")
        return head + b"<sheetData>", b"</sheetData>" + part[m.end():]


_DIMENSION = re.compile(rb'<dimension ref="[^"]*"\s*/>')


@dataclass
class HeldCells:
    """Every worksheet's cells held back from openpyxl's save, and their shared strings."""
    sheets: dict[str, _SheetCells] = field(default_factory=dict)
    strings: _SharedStrings = field(default_factory=_SharedStrings)


@contextmanager
def cells_held_back(wb) -> Iterator[HeldCells]:
    """Write every worksheet's cells to XML (shared strings in one table), then let openpyxl's
    save run inside the block with the worksheets emptied of cells; `finish(cells=...)` puts
    them back. Styles are numbered here in openpyxl's order (sheet by sheet, cell by cell), so
    the styles part it writes after the sheets is the one it would have written (but for styled
    column dimensions, which openpyxl numbers before a sheet's cells: linkbook has none)."""
    held = HeldCells()
    for ws in wb.worksheets:
        if ws.tables:       # openpyxl reads a table's column names from its cells while saving
            raise ValueError(f"{ws.title}: sheets with tables are not written here")
        held.sheets[ws.title] = _sheet_cells(ws, held.strings)
    kept = [(ws, ws._cells) for ws in wb.worksheets]
    try:
        for ws, _ in kept:
            ws._cells = {}
        yield held
    finally:
        for ws, cells in kept:
            ws._cells = cells


def _sheet_cells(ws, strings: "_SharedStrings") -> _SheetCells:
    """openpyxl's WorksheetWriter.write_rows, for the cells linkbook writes."""
    by_row: dict[int, list] = {}
    for (row, col), cell in sorted(ws._cells.items()):
        by_row.setdefault(row, []).append(cell)
    dims = ws.row_dimensions
    for row in dims.keys() - by_row.keys():
        by_row[row] = []
    style_ids = _StyleIds(ws.parent._cell_styles)
    chunks, pending = [], []
    for row in sorted(by_row):
        attrs = "".join(f" {k}={xml_attribute(v)}" for k, v in dims[row]) if row in dims else ""
        items = [f'<row r="{row}"{attrs}>']
        for cell in by_row[row]:
            if cell.comment is not None or cell.hyperlink is not None:
                raise ValueError(f"{_where(cell)}: comments and hyperlinks are not written here")
            style = style_ids.attribute(cell._style)
            value = cell._value
            if value is None and not style:
                continue
            ref = f'<c r="{column_letter(cell.column)}{row}"{style}'
            if type(value) is Formula:                            # most cells: formulas
                text = value[1:]
                if _NEEDS_ESCAPE.search(text):
                    _refuse_what_xml_cannot_hold(cell, text)
                    text = _escaped(text)
                items.append(f"{ref}><f>{text}</f><v></v></c>")
            else:
                items.append(_cell_xml(cell, ref, strings))
        items.append("</row>")
        pending.append("".join(items))
        if len(pending) == ROWS_PER_CHUNK:
            chunks.append("".join(pending).encode("ascii", "xmlcharrefreplace"))
            pending = []
    if pending:
        chunks.append("".join(pending).encode("ascii", "xmlcharrefreplace"))
    return _SheetCells(ws.calculate_dimension(), chunks)


# What the formula of the fast path needs escaped (_escaped's characters), or refused (NOT_IN_XML's).
_NEEDS_ESCAPE = re.compile(f"[&<>\r]|{NOT_IN_XML.pattern}")


def _refuse_what_xml_cannot_hold(cell, text: str) -> None:
    """openpyxl refuses these when a cell is set or saved; escaped as character references
    they would make the part unreadable."""
    bad = NOT_IN_XML.search(text)
    if bad:
        raise ValueError(f"{_where(cell)}: the character U+{ord(bad.group()):04X} cannot be "
                         f"written to a workbook")


def _where(cell) -> str:
    return f"{cell.parent.title}!{cell.coordinate}"


class _StyleIds:
    """A cell's ` s="N"` attribute ('' unstyled): openpyxl's style_id (the index of its style
    array in the workbook's list, added when new), looked up once per distinct array."""

    def __init__(self, cell_styles) -> None:
        self.cell_styles = cell_styles
        self.known: dict[bytes, str] = {}

    def attribute(self, style) -> str:
        if style is None:
            return ""
        key = style.tobytes()
        found = self.known.get(key)
        if found is None:
            found = self.known[key] = (f' s="{self.cell_styles.add(style)}"' if any(style)
                                       else "")
        return found


def _cell_xml(cell, ref: str, strings: "_SharedStrings") -> str:
    """A cell other than a formula, after its `<c r=".." s=".."` (not yet closed)."""
    kind, value = cell.data_type, cell._value
    if kind == "f" and isinstance(value, str):
        kind = "s"          # text that openpyxl took for a formula: not one linkbook made
    elif kind == "f":
        raise ValueError(f"{_where(cell)}: array and data-table formulas are not written here")
    if kind == "s":
        if not isinstance(value, str):
            raise ValueError(f"{_where(cell)}: rich text is not written here")
        if value == "":
            return f'{ref} t="inlineStr"></c>'
        _refuse_what_xml_cannot_hold(cell, value)
        space = ' xml:space="preserve"' if value != value.strip() else ""
        body = f"<t{space}>{_escaped(value)}</t>".encode("ascii", "xmlcharrefreplace")
        return f'{ref} t="s"><v>{strings.add(body)}</v></c>'
    if kind not in ("n", "b", "e"):
        raise ValueError(f"{_where(cell)}: cells of type {kind!r} are not written here")
    if value is None:
        return f'{ref} t="{kind}"></c>'
    text = safe_string(value)                 # numbers as %.16g, as openpyxl writes them
    _refuse_what_xml_cannot_hold(cell, text)
    return f'{ref} t="{kind}"><v>{_escaped(text)}</v></c>'


# ---------------------------------------------------------------- form controls
def _place_controls(zin: zipfile.ZipFile, controls: dict[str, list[Control]],
                    parts: dict[str, str]) -> list[SheetControls]:
    """Number the new VML drawings, control property parts and each sheet's new relationships
    after any the package has."""
    names = set(zin.namelist())
    drawing = _highest(names, r"xl/drawings/vmlDrawing(\d+)\.vml")
    prop = _highest(names, r"xl/ctrlProps/ctrlProp(\d+)\.xml")
    out = []
    for sheet, items in controls.items():
        if sheet not in parts or not items:
            continue
        drawing += 1
        rels = _rels_part(parts[sheet])
        first_rel = _max_id(zin.read(rels)) + 1 if rels in names else 1
        out.append(SheetControls(parts[sheet], tuple(items), drawing, prop + 1, first_rel))
        prop += len(items)
    return out


def _highest(names: set[str], pattern: str) -> int:
    numbers = [int(m.group(1)) for n in names if (m := re.fullmatch(pattern, n))]
    return max(numbers, default=0)


def _controls_tail(sc: SheetControls):
    """Put `<legacyDrawing>` and `<controls>` after `<drawing>`, before anything CT_Worksheet's
    sequence puts after them (AFTER_CONTROLS), or else at the end."""
    def tail(text: bytes) -> bytes:
        if b"<legacyDrawing " in text or b"<controls>" in text:
            raise ValueError(f"{sc.sheet_part} already has a legacy drawing or controls")
        at = min((i for name in AFTER_CONTROLS
                  if (i := text.find(b"<" + name.encode())) >= 0),
                 default=text.rfind(b"</worksheet>"))
        return text[:at] + sc.sheet_xml().encode() + text[at:]
    return tail


# ---------------------------------------------------------------- small parts
def _max_id(rels: bytes) -> int:
    return max((int(n) for n in re.findall(rb'Id="rId(\d+)"', rels)), default=0)


def _free_id(rels: bytes) -> str:
    return f"rId{_max_id(rels) + 1}"


def _add_relationships(rels: bytes, new: list[tuple[str, str, str]]) -> bytes:
    items = "".join(f"<Relationship Id={xml_attribute(i)} Type={xml_attribute(t)} "
                    f"Target={xml_attribute(target)}/>" for i, t, target in new)
    end = rels.rfind(b"</Relationships>")
    return rels[:end] + items.encode() + rels[end:]


def _content_types(xml: bytes, with_controls: list[SheetControls], sst: bool) -> bytes:
    add = []
    if with_controls and b'Extension="vml"' not in xml:
        add.append(f'<Default Extension="vml" ContentType="{VML_TYPE}"/>')
    for sc in with_controls:
        for i in range(len(sc.controls)):
            add.append(f'<Override PartName="/{sc.prop_part(i)}" ContentType="{CTRL_TYPE}"/>')
    if sst:
        add.append(f'<Override PartName="/{SST_PART}" ContentType="{SST_TYPE}"/>')
    end = xml.rfind(b"</Types>")
    return xml[:end] + "".join(add).encode() + xml[end:]


# Drawings and charts: openpyxl through lxml declares the DrawingML prefixes (a:, c:, r:) on
# the elements that use them, through its own writer on the root element. Gnumeric 1.12 reads a
# drawing's chart only in the second form (in the first it drops every chart, measured).
_DRAWING_PART = re.compile(r"xl/(drawings|charts)/[^/]+\.xml")
_START_TAG = re.compile(rb"<[A-Za-z][^>]*>")
_PREFIX_DECLARATION = re.compile(rb'\s+xmlns:([A-Za-z_][\w.-]*)="([^"]*)"')


def namespaces_on_root(xml: bytes) -> bytes:
    """The part with every prefixed namespace declared once, on its root element (unchanged
    if a prefix stands for two namespaces in it)."""
    found: dict[bytes, bytes] = {}
    for tag in _START_TAG.finditer(xml):
        for name, uri in _PREFIX_DECLARATION.findall(tag.group()):
            if found.setdefault(name, uri) != uri:
                return xml
    root = _START_TAG.search(xml)
    if root is None or not found:
        return xml
    declarations = b"".join(b' xmlns:%s="%s"' % item for item in found.items())
    bare = _START_TAG.sub(lambda m: _PREFIX_DECLARATION.sub(b"", m.group()), xml[root.start():])
    end = bare.index(b">")
    end -= bare[end - 1:end] == b"/"
    return xml[:root.start()] + bare[:end] + declarations + bare[end:]


def fonts_in_order(styles: bytes) -> bytes:
    """styles.xml with each `<font>`'s children in CT_Font's order (openpyxl writes the default
    font as name, family, color, sz, scheme)."""
    rank = {name.encode(): i for i, name in enumerate(FONT_ORDER)}

    def order(m: re.Match) -> bytes:
        children = re.findall(rb"<(\w+)\b[^>]*/>", m.group(2))
        elements = re.findall(rb"<\w+\b[^>]*/>", m.group(2))
        if len(elements) != len(children) or b"".join(elements) != m.group(2):
            return m.group(0)           # not a run of empty elements: leave it alone
        ordered = sorted(zip(children, elements), key=lambda ce: rank.get(ce[0], len(rank)))
        return m.group(1) + b"".join(e for _, e in ordered) + m.group(3)

    return re.sub(rb"(<font>)(.*?)(</font>)", order, styles, flags=re.S)
