"""Give every formula cell of a saved .xlsx a cached value, touching nothing else.

openpyxl writes formulas without values (`<f>…</f><v/>`), so a viewer that does not calculate
(a file preview, a phone, pandas, openpyxl's data_only) shows empty cells. This module rewrites
only the `<c>` elements that hold a formula in the worksheet parts: the `<f>` stays byte for byte,
a `<v>` is added with the value, and the cell's `t` says its type (none for a number, `e` for an
error, `str` for text, `b` for a boolean). Every other part of the zip (defined names, styles,
number formats, charts, data validation) is copied unchanged. xl/workbook.xml also gets
`<calcPr fullCalcOnLoad="1"/>`, so Excel and LibreOffice recalculate anyway when they open it.

Worksheet parts are streamed in chunks cut at row ends: a sheet of 20 columns × 3,601 rows of
1,200-character formulas is about 90 MB of XML and never has to be in memory twice.
Cells without an `r` attribute (allowed by the standard, written by neither openpyxl nor
LibreOffice) are left as they are.
"""
from __future__ import annotations

import math
import numbers
import posixpath
import re
import zipfile
from pathlib import Path
from xml.sax.saxutils import escape

from defusedxml import ElementTree

from .files import write_atomic
from .office import error_code

MAIN_NS = "http://schemas.openxmlformats.org/spreadsheetml/2006/main"
REL_NS = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"
PKG_REL_NS = "http://schemas.openxmlformats.org/package/2006/relationships"
CHUNK = 4 * 1024 * 1024

# One cell: optional namespace prefix, attributes, then either "/>" or a body up to its end tag.
CELL = re.compile(rb"<((?:[A-Za-z_][\w.-]*:)?c)((?:\s[^>]*?)?)(/>|>(.*?)</\1>)", re.S)
ATTR = re.compile(rb"""\s([\w:.-]+)\s*=\s*("[^"]*"|'[^']*')""")
TYPE_ATTR = re.compile(rb"""\st\s*=\s*("[^"]*"|'[^']*')""")
# calcPr comes after definedNames and before these (CT_Workbook's sequence).
AFTER_CALCPR = ("oleSize", "customWorkbookViews", "pivotCaches", "smartTagPr", "smartTagTypes",
                "webPublishing", "fileRecoveryPr", "webPublishObjects", "extLst")


def add_cached_values(path_in, path_out, values: dict) -> int:
    """Copy path_in to path_out with a cached value in every formula cell found in `values`
    ((sheet title, 'B7') -> float | str | bool | error). Errors may be office.CellError, the
    plain code string ('#N/A') or any object whose str() is a known code (formulas' XlError).
    Returns how many formula cells got a value; formula cells missing from `values` keep what
    they had. path_out may be path_in: the file is replaced only when the copy is complete."""
    path_in, path_out = Path(path_in), Path(path_out)
    with zipfile.ZipFile(path_in) as zin:
        parts = sheet_parts(zin)
        by_part = _values_by_part(values, parts)
        written = 0

        def copy(tmp: Path) -> None:
            nonlocal written
            with zipfile.ZipFile(tmp, "w") as zout:
                for info in zin.infolist():
                    if info.filename in by_part:
                        written += _copy_sheet(zin, zout, info, by_part[info.filename])
                    elif info.filename == "xl/workbook.xml":
                        zout.writestr(_same_entry(info), full_calc_on_load(zin.read(info)))
                    else:
                        zout.writestr(_same_entry(info), zin.read(info))

        write_atomic(path_out, copy)
    return written


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


def _values_by_part(values: dict, parts: dict[str, str]) -> dict[str, dict[bytes, object]]:
    by_part: dict[str, dict[bytes, object]] = {}
    for (sheet, cell), value in values.items():
        part = parts.get(sheet)
        if part is not None:
            by_part.setdefault(part, {})[cell.replace("$", "").upper().encode()] = value
    return by_part


# ---------------------------------------------------------------- worksheet parts
def _same_entry(info: zipfile.ZipInfo) -> zipfile.ZipInfo:
    """A fresh entry with the original's name, date and compression."""
    out = zipfile.ZipInfo(info.filename, date_time=info.date_time)
    out.compress_type = info.compress_type
    out.external_attr = info.external_attr
    return out


def _copy_sheet(zin, zout, info, cells: dict[bytes, object]) -> int:
    """Stream one worksheet part through the cell rewriter, cut at row ends."""
    count = [0]

    def rewrite(match: re.Match) -> bytes:
        new = cell_with_value(match, cells)
        if new is None:
            return match.group(0)
        count[0] += 1
        return new

    with zin.open(info) as src, zout.open(_same_entry(info), "w", force_zip64=True) as dst:
        pending = b""
        while chunk := src.read(CHUNK):
            pending += chunk
            cut = pending.rfind(b"</row>")
            if cut < 0:
                continue
            cut += len(b"</row>")
            dst.write(CELL.sub(rewrite, pending[:cut]))
            pending = pending[cut:]
        dst.write(CELL.sub(rewrite, pending))
    return count[0]


def cell_with_value(match: re.Match, cells: dict[bytes, object]) -> bytes | None:
    """The rewritten `<c>` element, or None to keep it (no formula, no value, no address)."""
    tag, attrs, body = match.group(1), match.group(2) or b"", match.group(4)
    prefix = tag[:-1]                                   # b"" or b"x:"
    if body is None or b"<" + prefix + b"f" not in body:
        return None
    ref = next((v[1:-1] for k, v in ATTR.findall(attrs) if k == b"r"), None)
    if ref is None or ref.upper() not in cells:
        return None
    formula = _formula(body, prefix)
    if formula is None:
        return None
    kind, text = encode_value(cells[ref.upper()])
    rest = _after_value(body, prefix)
    kept = TYPE_ATTR.sub(b"", attrs)            # the other attributes, byte for byte
    type_attr = f' t="{kind}"'.encode() if kind else b""
    return (b"<" + tag + kept + type_attr + b">" + formula + b"<" + prefix + b"v>" + text
            + b"</" + prefix + b"v>" + rest + b"</" + tag + b">")


def _formula(body: bytes, prefix: bytes) -> bytes | None:
    """The `<f>` element exactly as it was (self-closing for a shared formula's followers)."""
    m = re.search(rb"<" + re.escape(prefix) + rb"f\b[^>]*?(/>|>.*?</" + re.escape(prefix)
                  + rb"f>)", body, re.S)
    return m.group(0) if m else None


def _after_value(body: bytes, prefix: bytes) -> bytes:
    """An `<extLst>` after the value, if any, must stay (the schema puts it last)."""
    m = re.search(rb"<" + re.escape(prefix) + rb"extLst\b.*", body, re.S)
    return m.group(0) if m else b""


def encode_value(value) -> tuple[str, bytes]:
    """(t attribute, `<v>` text) of a value: numbers as repr(float), errors by code."""
    code = error_code(value)
    if code is not None:
        return "e", code.encode()
    if isinstance(value, bool):
        return "b", b"1" if value else b"0"
    if isinstance(value, numbers.Real):
        number = float(value)
        if not math.isfinite(number):          # no cell can hold NaN or infinity
            return "e", b"#NUM!"
        return "", repr(number).encode()
    if value is None:
        return "str", b""
    return "str", escape(str(value)).encode()


# ---------------------------------------------------------------- workbook part
def full_calc_on_load(xml: bytes) -> bytes:
    """xl/workbook.xml with `fullCalcOnLoad="1"` on calcPr (added if the file has none)."""
    m = re.search(rb"<((?:[A-Za-z_][\w.-]*:)?)calcPr\b([^>]*?)(/?)>", xml)
    if m:
        attrs = re.sub(rb"""\sfullCalcOnLoad\s*=\s*("[^"]*"|'[^']*')""", b"", m.group(2))
        new = (b"<" + m.group(1) + b"calcPr" + attrs.rstrip() + b' fullCalcOnLoad="1"'
               + (b" />" if m.group(3) else b">"))
        return xml[:m.start()] + new + xml[m.end():]
    prefix = re.match(rb".*?<((?:[A-Za-z_][\w.-]*:)?)workbook\b", xml, re.S)
    p = prefix.group(1) if prefix else b""
    element = b"<" + p + b'calcPr fullCalcOnLoad="1"/>'
    for name in AFTER_CALCPR:
        at = re.search(rb"<" + re.escape(p) + name.encode() + rb"\b", xml)
        if at:
            return xml[:at.start()] + element + xml[at.start():]
    end = xml.rfind(b"</" + p + b"workbook>")
    return xml[:end] + element + xml[end:]
