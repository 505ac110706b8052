"""Give every formula cell of a saved .xlsx a cached value, touching nothing else.

openpyxl writes formulas without values (`<f>…</f><v/>`), so a viewer that does not calculate
(a file preview, a phone, pandas, openpyxl's data_only) shows empty cells. This module rewrites
only the `<c>` elements that hold a formula in the worksheet parts: the `<f>` stays byte for byte,
a `<v>` is added with the value, and the cell's `t` says its type (none for a number, `e` for an
error, `str` for text, `b` for a boolean). Every other part of the zip (defined names, styles,
number formats, charts, data validation) is copied unchanged. xl/workbook.xml also gets
`<calcPr fullCalcOnLoad="1"/>`, so Excel and LibreOffice recalculate anyway when they open it.

The copy itself is package.finish's one streaming pass (package.add_cached_values) (with `tidy=False` here: nothing but the
formula cells and calcPr changes). Cells without an `r` attribute (allowed by the standard,
written by neither openpyxl nor LibreOffice) are left as they are.
"""
from __future__ import annotations

import math
import numbers
import re

from ..base.xlsx import error_code
from ..base.xlsx import xml_text


# One cell: optional namespace prefix, attributes, then either "/>" or a body up to its end tag.
CELL = re.compile(rb"<((?:[A-Za-z_][\w.-]*:)?c)((?:\s[^>]*?)?)(/>|>(.*?)</\1>)", re.S)
ATTR = re.compile(rb"""\s([\w:.-]+)\s*=\s*("[^"]*"|'[^']*')""")
TYPE_ATTR = re.compile(rb"""\st\s*=\s*("[^"]*"|'[^']*')""")
# calcPr comes after definedNames and before these (CT_Workbook's sequence).
AFTER_CALCPR = ("oleSize", "customWorkbookViews", "pivotCaches", "smartTagPr", "smartTagTypes",
                "webPublishing", "fileRecoveryPr", "webPublishObjects", "extLst")


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
    return "str", xml_text(str(value)).encode()


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
