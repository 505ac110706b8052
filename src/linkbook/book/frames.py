"""Live frames for the equal-scale charts: the mechanism's drawing and the coupler curves.

A chart cannot take its axis limits from cells, and automatic axes do not give equal scales. So
each such chart has fixed axes, -HALF to HALF on both, in a square plot area (charts.py), and draws
coordinates that formulas on the sheet `Drawing data` map into that frame: centred on the live
extents of what the chart draws and divided by a grid square of 1, 2 or 5 × 10ⁿ length units, the
smallest that holds everything with a margin. Edit a length and the drawing stays in view, at
equal scales; the legend's scale bar, one grid square long, says how big a square is.
"""
from __future__ import annotations

from openpyxl.styles import Alignment
from openpyxl.utils import get_column_letter, quote_sheetname

from ..base.sheets import DASH, DRAWING_COLUMNS, MECH, SWEEP
from ..language.model import LENGTH, Model
from ..language.templates import Template
from .package import Formula
from .style import (BOLD, DERIVED_FILL, LINE_HEIGHT, NOTE, TITLE, column_range, label_lines,
                    number_format, numbers_only, put, put_head, put_text, set_formula, table_style,
                    text_width, unit_text, wrap_across)

SHEET = "Drawing data"
HALF = 5                 # the frame: -HALF … HALF grid squares on both axes
MARGIN = 1.12            # the drawing fills at most 1/MARGIN of the frame's width
SQUARES = (1, 2, 5)      # a grid square is one of these × 10ⁿ length units
BAR = ((3.5, -4.75), (4.5, -4.75))   # the scale bar: one square, bottom right, in the margin
FIRST_ROW = 5            # the first row of every block (the Sweep sheet's first row too)
# The frame's cells, top to bottom: (key, label, is a length).
FRAME_CELLS = (("xmin", "x min", True), ("xmax", "x max", True), ("ymin", "y min", True),
               ("ymax", "y max", True), ("cx", "centre x", True), ("cy", "centre y", True),
               ("need", "size needed per grid square", True),
               ("decade", "its power of ten", True), ("square", "grid square", True),
               ("label", "legend of the scale bar", False))
# The drawing's grid square (its frame is the sheet's first block: labels in A, values in B);
# the Mechanism sheet sizes the sliders' blocks in it.
SQUARE_CELL = (f"{quote_sheetname(SHEET)}!$B$"
               f"{FIRST_ROW + [key for key, _, _ in FRAME_CELLS].index('square')}")
MAPPED_FORMAT = "0.0000"
MAPPED_WIDTH = 14        # a header's longest word, "[squares]", in bold


def square_label(text: str, unit: str) -> str:
    """The scale bar's legend formula, from the grid square's cell: `grid square 50 mm`."""
    decimals = f"MAX(0,-INT(ROUND(LOG10({text}),6)))"
    return f'="grid square "&FIXED({text},{decimals},TRUE)&" {unit}"'


def frames_sheet(wb, t: Template, model: Model, meta: dict) -> dict:
    """The sheet of live frames: one block of columns per equal-scale chart (the drawing first)."""
    ws = wb.create_sheet(SHEET)
    put_text(ws, "A1", "Drawing frames", TITLE)
    put_text(ws, "A2", f"Each drawing is a fixed square of {2 * HALF} × {2 * HALF} grid "
                       "squares. These formulas centre it on the live extents and pick the grid "
                       f"square (1, 2 or 5 × 10ⁿ {t.length_unit}), so it stays in view and to "
                       "scale after any edit.", NOTE)
    pos, sweep = meta["position"], meta["sweep"]
    frames, col = [], 1
    extent = _drawing_extent(model, sweep)
    frames.append(_block(ws, t, col, "The mechanism (sheet Mechanism)", extent,
                         [_sources(extent, a, pos, sweep) for a in "xy"],
                         _drawing_series(model, pos, sweep), meta["numbers_only"]))
    for i, spec in enumerate(model.charts):
        if not spec.equal_axes:
            continue
        col = frames[-1]["next_column"] + 1
        extent = {"x": [spec.x], "y": list(spec.ys), "position": False}
        series = [{"kind": "sweep", "x": spec.x, "y": k, "title": _path_title(model, spec.x, k),
                   "source": [sweep["columns"][spec.x], sweep["columns"][k]],
                   "rows": list(sweep["rows"])} for k in spec.ys]
        frame = _block(ws, t, col, f"{spec.title} (sheet Charts)", extent,
                       [_sources(extent, a, pos, sweep) for a in "xy"], series,
                       meta["numbers_only"])
        frame["chart"] = i
        frames.append(frame)
    for f in frames:
        del f["next_column"]
    ws.freeze_panes = f"A{FIRST_ROW}"
    return {"sheet": SHEET, "frames": frames}


def _path_title(model: Model, x: str, y: str) -> str:
    """`path of C` for a joint's two coordinate columns, else `yC (xC)`."""
    joint = next((j.name for j in model.joints if (j.x, j.y) == (f"{{{x}}}", f"{{{y}}}")), None)
    return f"path of {joint}" if joint else f"{y} ({x})"


def _drawing_extent(model: Model, sweep: dict) -> dict:
    """What the drawing's frame must hold: every joint at the current position (the joints
    table), and over the sweep every joint whose coordinates are sweep columns."""
    out: dict = {"x": [], "y": [], "position": True}
    for joint in model.joints:
        for axis, expr in (("x", joint.x), ("y", joint.y)):
            key = expr.strip("{}")
            if expr == f"{{{key}}}" and key in sweep["columns"]:
                out[axis].append(key)
    return out


def _sources(extent: dict, axis: str, pos: dict, sweep: dict) -> list[dict]:
    """What a frame must hold on one axis, one entry per column of cells: its header, the
    source cells (None where the joints table has no joint) and what they are, for verify."""
    i = "xy".index(axis)
    out = []
    if extent["position"]:
        col = DRAWING_COLUMNS[i]
        at_row = {int(cells[i][1:]): name for name, cells in pos["joints"].items()}
        rows = range(min(at_row), max(at_row) + 1)
        out.append({"head": f"joints {axis}", "cells": [
            f"{quote_sheetname(MECH)}!{col}{r}" if r in at_row else None for r in rows],
            "of": {"joints": [at_row.get(r) for r in rows], "axis": i}})
    r0, r1 = sweep["rows"]
    for key in extent[axis]:
        letter = sweep["columns"][key]
        out.append({"head": key, "cells": [f"{quote_sheetname(SWEEP)}!{letter}{r}"
                                               for r in range(r0, r1 + 1)],
                    "of": {"sweep": key}})
    return out


def _drawing_series(model: Model, pos: dict, sweep: dict) -> list[dict]:
    """The links (the joints table's link rows, mapped row for row), then the traced path."""
    first, last = pos["drawing"][0]["rows"][0], pos["drawing"][-1]["rows"][1]
    series = [{"kind": "links", "title": "links", "source": list(DRAWING_COLUMNS),
               "sheet": MECH, "rows": [first, last]}]
    if model.path:
        x, y = model.path
        series.append({"kind": "sweep", "x": x, "y": y, "title": _path_title(model, x, y),
                       "source": [sweep["columns"][x], sweep["columns"][y]],
                       "rows": list(sweep["rows"])})
    return series


def _block(ws, t: Template, col: int, title: str, extent: dict, sources: list[list[dict]],
           series: list[dict], numbers: list) -> dict:
    """A frame's cells (label, value), its mapped columns and the numbers-only copies of what
    it must hold (their extents), from column `col` on; those copies are listed in `numbers`."""
    label, value = get_column_letter(col), get_column_letter(col + 1)
    ws.column_dimensions[label].width = max(text_width(text) for _, text, _ in FRAME_CELLS)
    ws.column_dimensions[value].width = 22     # the scale bar's legend: grid square 0.005 mm
    put_text(ws, f"{label}3", title, BOLD)
    put_head(ws, 4, col, "Frame")
    put_head(ws, 4, col + 1, f"Value [{t.length_unit}]")
    cells = {k: f"{value}{FIRST_ROW + i}" for i, (k, _, _) in enumerate(FRAME_CELLS)}
    ref = {k: f"${value}${FIRST_ROW + i}" for i, (k, _, _) in enumerate(FRAME_CELLS)}
    c = col + 2
    for s in series:
        x_letter, y_letter = get_column_letter(c), get_column_letter(c + 1)
        sheet = s.get("sheet", SWEEP)
        for j, axis in enumerate(("x", "y")):
            letter = (x_letter, y_letter)[j]
            ws.column_dimensions[letter].width = MAPPED_WIDTH
            put_head(ws, 4, c + j, f"{s[axis]} [squares]" if s["kind"] == "sweep"
                     else f"links {axis} [squares]")
            centre = ref["cx"] if axis == "x" else ref["cy"]
            source = f"{quote_sheetname(sheet)}!{s['source'][j]}"
            style = table_style(ws, MAPPED_FORMAT)
            for k, r in enumerate(range(s["rows"][0], s["rows"][1] + 1)):
                put(ws, FIRST_ROW + k, c + j,
                    Formula(f"=({source}{r}-{centre})/{ref['square']}"), style)
        s["columns"] = [x_letter, y_letter]
        s["mapped_rows"] = [FIRST_ROW, FIRST_ROW + s["rows"][1] - s["rows"][0]]
        c += 2
    # An empty column before the copies: LibreOffice computes adjacent formula columns of the
    # same rows as one block, and took the mapped columns (which read the grid square, which
    # reads the copies' MIN and MAX) and the copies beside them for a circular reference.
    c += 1
    note, first_copy = (f"What the frame must hold, as numbers ({DASH} where a coordinate is "
                        "#N/A): the extents' MIN and MAX read these"), c
    put_text(ws, f"{get_column_letter(c)}3", note, NOTE)
    ranges = []
    for axis in sources:
        ranges.append([])
        for source in axis:
            numbers_only(ws, c, 4, source["cells"],
                         f"{source['head']} numbers [{unit_text(LENGTH, t.length_unit)}]",
                         number_format(LENGTH, t.length_unit))
            ws.column_dimensions[get_column_letter(c)].width = MAPPED_WIDTH
            last = FIRST_ROW + len(source["cells"]) - 1
            numbers.append({"sheet": SHEET, "column": get_column_letter(c),
                            "rows": [FIRST_ROW, last], **source["of"]})
            ranges[-1].append(column_range(SHEET, get_column_letter(c), FIRST_ROW, last))
            c += 1
    wrap_across(ws, 3, get_column_letter(first_copy), get_column_letter(c - 1), note)
    formulas = frame_formulas(ref, ranges, t.length_unit)
    for i, (key, text, is_length) in enumerate(FRAME_CELLS):
        r = FIRST_ROW + i
        put_text(ws, f"{label}{r}", text)
        set_formula(ws[f"{value}{r}"], formulas[key])
        ws[f"{value}{r}"].fill = DERIVED_FILL
        if is_length:
            ws[f"{value}{r}"].number_format = number_format(LENGTH, t.length_unit)
        else:
            ws[f"{value}{r}"].alignment = Alignment(horizontal="right")
    # the scale bar's two points under the frame's cells, in its two columns
    bar_head = FIRST_ROW + len(FRAME_CELLS) + 1
    lines = 1
    for j, axis in enumerate(("x", "y")):
        head = f"scale bar {axis} [squares]"
        put_head(ws, bar_head, col + j, head)
        width = ws.column_dimensions[get_column_letter(col + j)].width
        lines = max(lines, len(label_lines(head, width / 1.1)))     # bold: a tenth wider
        for k, point in enumerate(BAR, start=1):
            ws.cell(bar_head + k, col + j, point[j]).number_format = MAPPED_FORMAT
    ws.row_dimensions[bar_head].height = LINE_HEIGHT * lines
    ws.row_dimensions[4].height = 45
    for k in range(col, c):
        ws.cell(4, k).alignment = Alignment(horizontal="center", vertical="center",
                                            wrap_text=True)
    return {"cells": cells, "extent": extent, "series": series,
            "bar": {"columns": [label, value], "rows": [bar_head + 1, bar_head + 2]},
            "next_column": c}


def frame_formulas(ref: dict, ranges: list[list[str]], unit: str) -> dict[str, str]:
    """The formula of each of a frame's cells (FRAME_CELLS' keys; `ref`: their references):
    the extents over `ranges` (x's, then y's), the centre, the size a square must hold, its
    power of ten, the square and the scale bar's legend."""
    return {
        "xmin": _extreme("MIN", ranges[0]), "xmax": _extreme("MAX", ranges[0]),
        "ymin": _extreme("MIN", ranges[1]), "ymax": _extreme("MAX", ranges[1]),
        "cx": f"=({ref['xmin']}+{ref['xmax']})/2", "cy": f"=({ref['ymin']}+{ref['ymax']})/2",
        "need": f"=MAX({ref['xmax']}-{ref['xmin']},{ref['ymax']}-{ref['ymin']},1E-12)"
                f"*{MARGIN}/{2 * HALF}",
        "decade": f"=10^INT(LOG10({ref['need']}))",
        "square": "={d}*IF({n}<={d},1,IF({n}<=2*{d},2,IF({n}<=5*{d},5,10)))".format(
            d=ref["decade"], n=ref["need"]),
        "label": square_label(ref["square"], unit),
    }


def _extreme(fn: str, ranges: list[str]) -> str:
    """The least or greatest number in the numbers-only ranges (0 where they hold none)."""
    return f"={fn}(" + ",".join(ranges) + ")"
