"""Form controls (spin buttons, scroll bars) linked to input cells: the textbook's spin button.

openpyxl has no API for form controls, so this module writes the parts Excel itself writes for
them, into a package openpyxl has already saved (package.finish calls it):

- the legacy VML drawing (`xl/drawings/vmlDrawingN.vml`): one `v:shape` per control whose
  `x:ClientData` holds the type, the anchor, the linked cell and the range. Excel 2007 reads only
  this part, and so does LibreOffice (oox imports each one as a live form control bound to the
  cell);
- one control properties part per control (`xl/ctrlProps/ctrlPropN.xml`, `formControlPr`), which
  Excel 2010 and later read;
- in the worksheet, `<legacyDrawing>` and the `<controls>` list (inside `mc:AlternateContent`
  requiring x14, as Excel writes it, so Excel 2007 skips it);
- the relationships from the sheet to those parts, and their content types.

Where the controls go and what they link to is the layout's call (workbook.py puts a list of
dicts in the build record: `kind` Spin or Scroll, `cell`, `min`, `max`, `inc`, `page`, `value`,
`anchor` = [col, dx, row, dy, col, dx, row, dy]: zero-based cells and pixel offsets, as VML's
x:Anchor). A form control holds an integer from 0 to 30,000.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..base.xlsx import xml_attribute

VML_TYPE = "application/vnd.openxmlformats-officedocument.vmlDrawing"
CTRL_TYPE = "application/vnd.ms-excel.controlproperties+xml"
REL = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"
VML_REL = f"{REL}/vmlDrawing"
CTRL_REL = f"{REL}/ctrlProp"
X14 = "http://schemas.microsoft.com/office/spreadsheetml/2009/9/main"
MC = "http://schemas.openxmlformats.org/markup-compatibility/2006"
XDR = "http://schemas.openxmlformats.org/drawingml/2006/spreadsheetDrawing"
KINDS = {"Spin": ("Spinner", 201), "Scroll": ("Scroll Bar", 201)}
LIMIT = 30_000          # the largest value a form control holds
EMU_PER_PX = 9525
SHAPES_PER_BLOCK = 1024  # VML shape ids come in blocks of 1,024 per drawing (o:idmap)


@dataclass(frozen=True)
class Control:
    """A spin button or scroll bar (a form control) and the cell it sets."""
    kind: str                 # "Spin" or "Scroll"
    cell: str                 # the linked cell on the same sheet, "I7"
    min: int
    max: int
    inc: int
    page: int
    value: int
    anchor: tuple[int, ...]   # col, dx, row, dy (top left), col, dx, row, dy (bottom right)

    @classmethod
    def of(cls, record: dict) -> "Control":
        return cls(record["kind"], record["cell"], int(record["min"]), int(record["max"]),
                   int(record["inc"]), int(record["page"]), int(record["value"]),
                   tuple(int(v) for v in record["anchor"]))

    @property
    def link(self) -> str:
        """The cell as Excel writes it in fmlaLink: absolute."""
        letters = self.cell.rstrip("0123456789")
        return f"${letters}${self.cell[len(letters):]}"

    @property
    def horizontal(self) -> bool:
        return self.kind == "Scroll"


def control_record(kind: str, cell: str, lo: float, hi: float, inc: float, page: float,
                   value: float, anchor: tuple[int, ...]) -> dict | None:
    """The build record of one control, or None when its range cannot be held (a form control
    counts in whole numbers from 0 to 30,000)."""
    lo, hi = max(0, int(round(lo))), min(LIMIT, int(round(hi)))
    if hi <= lo:
        return None
    inc = max(1, int(round(inc)))
    page = max(1, int(round(page)))
    value = min(hi, max(lo, int(round(value))))
    return {"kind": kind, "cell": cell, "min": lo, "max": hi, "inc": inc, "page": page,
            "value": value, "anchor": list(anchor)}


# ---------------------------------------------------------------- the parts
@dataclass(frozen=True)
class SheetControls:
    """Everything one worksheet's controls add to the package."""
    sheet_part: str                   # "xl/worksheets/sheet1.xml"
    controls: tuple[Control, ...]
    drawing_number: int               # N of vmlDrawingN.vml, and the VML shape id block
    first_prop: int                   # N of the first ctrlPropN.xml
    first_rel: int                    # N of the first new relationship id rIdN of the sheet

    @property
    def vml_part(self) -> str:
        return f"xl/drawings/vmlDrawing{self.drawing_number}.vml"

    def prop_part(self, i: int) -> str:
        return f"xl/ctrlProps/ctrlProp{self.first_prop + i}.xml"

    def shape_id(self, i: int) -> int:
        return self.drawing_number * SHAPES_PER_BLOCK + 1 + i

    def names(self) -> list[str]:
        """Excel's default names: "Spinner 1", "Scroll Bar 2", numbered across the sheet."""
        return [f"{KINDS[c.kind][0]} {i + 1}" for i, c in enumerate(self.controls)]

    def parts(self) -> dict[str, bytes]:
        out = {self.vml_part: self.vml().encode()}
        for i, c in enumerate(self.controls):
            out[self.prop_part(i)] = control_properties(c).encode()
        return out

    def relationships(self) -> list[tuple[str, str, str]]:
        """(Id, Type, Target) of the sheet's new relationships: the VML drawing, then each
        control's properties."""
        first_id = self.first_rel
        rels = [(f"rId{first_id}", VML_REL, "/" + self.vml_part)]
        for i in range(len(self.controls)):
            rels.append((f"rId{first_id + 1 + i}", CTRL_REL, "/" + self.prop_part(i)))
        return rels

    def sheet_xml(self) -> str:
        """`<legacyDrawing>` and the `<controls>` list, for the worksheet part."""
        first_id = self.first_rel
        items = []
        for i, (c, name) in enumerate(zip(self.controls, self.names())):
            col0, dx0, row0, dy0, col1, dx1, row1, dy1 = c.anchor
            items.append(
                f'<mc:AlternateContent><mc:Choice Requires="x14">'
                f'<control shapeId="{self.shape_id(i)}" r:id="rId{first_id + 1 + i}" '
                f'name={xml_attribute(name)}><controlPr defaultSize="0" autoPict="0">'
                f'<anchor moveWithCells="1">{_xdr_marker("from", col0, dx0, row0, dy0)}'
                f'{_xdr_marker("to", col1, dx1, row1, dy1)}</anchor></controlPr></control>'
                f'</mc:Choice></mc:AlternateContent>')
        return (f'<legacyDrawing xmlns:r="{REL}" r:id="rId{first_id}"/>'
                f'<mc:AlternateContent xmlns:mc="{MC}" xmlns:x14="{X14}" xmlns:xdr="{XDR}" '
                f'xmlns:r="{REL}"><mc:Choice Requires="x14"><controls>{"".join(items)}'
                f'</controls></mc:Choice></mc:AlternateContent>')

    def vml(self) -> str:
        shapes = "".join(_vml_shape(c, self.shape_id(i), i + 1)
                         for i, c in enumerate(self.controls))
        return ('<xml xmlns:v="urn:schemas-microsoft-com:vml" '
                'xmlns:o="urn:schemas-microsoft-com:office:office" '
                'xmlns:x="urn:schemas-microsoft-com:office:excel">'
                f'<o:shapelayout v:ext="edit"><o:idmap v:ext="edit" data="{self.drawing_number}"/>'
                '</o:shapelayout>'
                '<v:shapetype id="_x0000_t201" coordsize="21600,21600" o:spt="201" '
                'path="m,l,21600r21600,l21600,xe"><v:stroke joinstyle="miter"/>'
                '<v:path shadowok="f" o:extrusionok="f" strokeok="f" fillok="f" '
                'o:connecttype="rect"/><o:lock v:ext="edit" shapetype="t"/></v:shapetype>'
                f'{shapes}</xml>')


def _xdr_marker(tag: str, col: int, dx: int, row: int, dy: int) -> str:
    return (f"<{tag}><xdr:col>{col}</xdr:col><xdr:colOff>{dx * EMU_PER_PX}</xdr:colOff>"
            f"<xdr:row>{row}</xdr:row><xdr:rowOff>{dy * EMU_PER_PX}</xdr:rowOff></{tag}>")


def _vml_shape(c: Control, shape_id: int, z: int) -> str:
    horiz = "<x:Horiz/>" if c.horizontal else ""
    anchor = ", ".join(str(v) for v in c.anchor)
    return (f'<v:shape id="_x0000_s{shape_id}" type="#_x0000_t201" '
            f'style="position:absolute;z-index:{z}" filled="f" fillcolor="window [65]" '
            'stroked="f" strokecolor="windowText [64]" o:insetmode="auto">'
            '<v:path shadowok="t" strokeok="t" fillok="t"/><o:lock v:ext="edit" rotation="t"/>'
            f'<x:ClientData ObjectType="{c.kind}"><x:MoveWithCells/>'
            f'<x:Anchor>{anchor}</x:Anchor><x:AutoFill>False</x:AutoFill>'
            f'<x:FmlaLink>{c.link}</x:FmlaLink><x:Val>{c.value}</x:Val><x:Min>{c.min}</x:Min>'
            f'<x:Max>{c.max}</x:Max><x:Inc>{c.inc}</x:Inc><x:Page>{c.page}</x:Page>{horiz}'
            '<x:Dx>16</x:Dx></x:ClientData></v:shape>')


def control_properties(c: Control) -> str:
    horiz = ' horiz="1"' if c.horizontal else ""
    return (f'<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\n'
            f'<formControlPr xmlns="{X14}" objectType="{c.kind}" dx="16" '
            f'fmlaLink="{c.link}"{horiz} inc="{c.inc}" max="{c.max}" min="{c.min}" '
            f'page="{c.page}" val="{c.value}"/>')
