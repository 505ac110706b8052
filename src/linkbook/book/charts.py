"""XY scatter charts: the mechanism drawing, the sweep charts and the pump family.

Geometry is drawn to scale and live: such a chart has fixed axes, the same on x and y, in a square
plot area, and draws coordinates that formulas map into that frame from the live extents
(frames.py). Excel and LibreOffice would otherwise pick each axis range on its own and distort
the mechanism, and axis limits fixed at build time would lose it after an edit.
"""
from __future__ import annotations


from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.chart.axis import ChartLines
from openpyxl.chart.data_source import NumFmt, StrRef
from openpyxl.chart.legend import LegendEntry
from openpyxl.chart.series import SeriesLabel
from openpyxl.drawing.line import LineProperties
from openpyxl.chart.layout import Layout, ManualLayout
from openpyxl.chart.shapes import GraphicalProperties
from openpyxl.utils import column_index_from_string, get_column_letter, quote_sheetname

from . import frames
from ..base.palette import (LINK_COLOURS, PART_COLOURS, PATH_COLOUR, drawing_colours,
                            link_label)
from ..language.model import ANG_ACCEL, ANG_SPEED, LENGTH, NEWTON, NEWTON_METRE, Model
from .style import header, unit_text
from ..language.templates import Template
from ..base.sheets import (CHARTS, FORCES_SHEET, GRID, JOINT_COLUMN, MECH, MOTION_SHEET,
                           SWEEP)
from .workbook import Built

LINE_EMU = 22000          # 1.7 pt
DRAWING_CM = 15.0
# The drawing's colours, set in the file (not left to the theme) so that `linkbook animate`
# draws each link as the workbook does: link 1, 2, ... then the traced point's path.
SWEEP_CHART_CM = 18         # the width of the Charts sheet's charts
SIDE, WIDTH_RATIO = 0.75, 1.45    # a framed chart: square plot area, legend on the right
GRID_COLOUR = "9DC3E6"     # the frame's gridlines, one per grid square: light blue paper


def _series(ws, x_col: str, y_col: str, rows: tuple[int, int], title: str,
            *, markers: bool = False, width: int = LINE_EMU, colour: str | None = None) -> Series:
    x = Reference(ws, min_col=column_index_from_string(x_col), min_row=rows[0], max_row=rows[1])
    y = Reference(ws, min_col=column_index_from_string(y_col), min_row=rows[0], max_row=rows[1])
    s = Series(y, x, title=title)
    s.smooth = False
    s.marker.symbol = "circle" if markers else "none"
    if markers:
        s.marker.size = 7
    s.graphicalProperties.line.width = width
    if colour:
        s.graphicalProperties.line.solidFill = colour
        if markers:
            s.marker.graphicalProperties = GraphicalProperties(solidFill=colour)
            s.marker.graphicalProperties.line.solidFill = colour
    return s


def _chart(title: str, x_title: str, y_title: str) -> ScatterChart:
    c = ScatterChart()
    c.title = title
    c.style = 2
    c.scatterStyle = "lineMarker"
    c.x_axis.title = x_title
    c.y_axis.title = y_title
    c.x_axis.delete = False      # openpyxl hides axes unless told otherwise
    c.y_axis.delete = False
    c.x_axis.majorGridlines = ChartLines()
    c.y_axis.majorGridlines = ChartLines()
    c.x_axis.majorTickMark = c.y_axis.majorTickMark = "out"
    for axis in (c.x_axis, c.y_axis):
        axis.numFmt = NumFmt(formatCode="General", sourceLinked=False)  # not the cells' 0.0000
        axis.tickLblPos = "low"      # labels at the edge of the plot, not where the axes cross
    c.legend.position = "b"
    return c


def _frame_axes(chart: ScatterChart, size_cm: float) -> None:
    """A live frame's fixed axes (frames.py): -HALF … HALF grid squares on both, a gridline
    per square, no tick labels (they would count squares, not lengths: the scale bar's legend
    gives the square's size), in a square plot area of a square chart."""
    for axis in (chart.x_axis, chart.y_axis):
        axis.scaling.min, axis.scaling.max = -frames.HALF, frames.HALF
        axis.majorUnit = 1
        axis.numFmt = NumFmt(formatCode=";;;", sourceLinked=False)   # no tick labels
        axis.majorTickMark = "none"
        axis.crosses = "min"          # the axis lines on the frame's edges, not through 0
        axis.spPr = GraphicalProperties(ln=LineProperties(solidFill=GRID_COLOUR, w=6350))
        axis.majorGridlines = ChartLines()
        axis.majorGridlines.spPr = GraphicalProperties(ln=LineProperties(solidFill=GRID_COLOUR,
                                                                          w=6350))
    _square_plot_area(chart, size_cm)


def _square_plot_area(chart: ScatterChart, size_cm: float, left: float = 0.06) -> None:
    """The inner plot area (the axes' box, without their labels) a square, SIDE of the chart's
    height, with the title above it and the legend to its right (a column of links fits there
    at any count); `left`: the room left of it, a share of the chart's width. openpyxl writes
    chart.layout as the plot area's layout; Excel and LibreOffice both honour it."""
    chart.height, chart.width = size_cm, size_cm * WIDTH_RATIO
    chart.layout = Layout(ManualLayout(layoutTarget="inner", xMode="edge", yMode="edge",
                                       x=left, y=0.15, w=SIDE / WIDTH_RATIO, h=SIDE))
    chart.legend.position = "r"


JOINT_LABEL_SIZE = 900       # 9 pt, bold: a joint's name above its point


def _joint_names(ws_frame, links: dict, drawing: list[dict]) -> list[Series]:
    """Each joint named once on the drawing, as pylinkage does: a series of one point, the
    first point of a link that reaches the joint, drawn invisible, named by the joints
    table's cell with the joint's name and labelled with that name (its series name). The
    label belongs to its point, so it moves with the joint when an input changes. (A label
    of a link's own point with its text from a cell Excel shows, LibreOffice does not: it
    shows the point's value there.)"""
    from openpyxl.chart.label import DataLabelList
    from openpyxl.chart.text import RichText
    from openpyxl.drawing.text import CharacterProperties, Paragraph, ParagraphProperties
    out, named = [], set()
    for link in drawing:
        if link.get("kind") in PART_COLOURS:        # a guide's or a block's corners: no joint
            continue
        for k, name in enumerate(link["joints"]):
            if name in named:
                continue
            named.add(name)
            row = link["rows"][0] + k
            s = _mapped(ws_frame, links, (row, row), name)
            s.tx = SeriesLabel(strRef=StrRef(f"{quote_sheetname(MECH)}!${JOINT_COLUMN}${row}"))
            s.graphicalProperties.line.noFill = True
            bold = CharacterProperties(sz=JOINT_LABEL_SIZE, b=True)
            s.dLbls = DataLabelList(showSerName=True, showVal=False, showCatName=False,
                                    dLblPos="t", txPr=RichText(
                p=[Paragraph(pPr=ParagraphProperties(defRPr=bold), r=[], endParaRPr=bold)]))
            out.append(s)
    return out


def _scale_bar(ws, frame: dict) -> Series:
    """One grid square drawn as a thick black bar; its legend entry (a live cell) names the
    square's size."""
    bar = frame["bar"]
    s = _series(ws, *bar["columns"], tuple(bar["rows"]), "scale", width=50800, colour="000000")
    label = frame["cells"]["label"]
    column = label.rstrip("0123456789")
    s.tx = SeriesLabel(strRef=StrRef(f"{quote_sheetname(ws.title)}!${column}${label[len(column):]}"))
    return s


def _mapped(ws, series: dict, rows: tuple[int, int], title: str, **style) -> Series:
    """A series drawn from a frame's mapped columns (`rows`: the source rows it reads)."""
    first = series["mapped_rows"][0] + rows[0] - series["rows"][0]
    return _series(ws, *series["columns"], (first, first + rows[1] - rows[0]), title, **style)


def _angle_axis(chart: ScatterChart, t: Template) -> None:
    chart.x_axis.scaling.min = t.sweep.start
    chart.x_axis.scaling.max = t.sweep.stop
    chart.x_axis.majorUnit = 30 if t.sweep.stop - t.sweep.start >= 180 else None


def add_charts(built: Built, t: Template, model: Model) -> None:
    wb, meta = built.workbook, built.meta
    _drawing(wb, t, model, meta)
    row = _sweep_charts(wb, t, model, meta)
    if "motion" in meta:
        row = _motion_charts(wb, t, model, meta, row)
    if "forces" in meta:
        _force_charts(wb, t, model, meta, row)
    if "grid" in meta:
        _family_chart(wb, t, model, meta)
    if "synthesis" in meta:
        if meta["synthesis"]["task"]["kind"] == "function":
            _structural_error_chart(wb, meta["synthesis"])
        if meta["synthesis"].get("drawing"):
            positions_chart(wb[meta["synthesis"]["sheet"]], meta["synthesis"]["drawing"],
                            f"x [{t.length_unit}]")


def _column_of(cells) -> tuple[str, tuple[int, int]]:
    """The column letter and first and last rows of a column's cells, top to bottom."""
    letter = cells[0].rstrip("0123456789")
    return letter, (int(cells[0][len(letter):]), int(cells[-1][len(letter):]))


def _structural_error_chart(wb, syn: dict) -> None:
    """The Synthesis sheet's structural error against x over the range, the precision points
    marked (where it is zero), beside the table it plots."""
    ws = wb[syn["sheet"]]
    chart = _chart("Structural error: generated − desired output", "x", "error [deg]")
    (x, rows), (error, _) = _column_of(syn["error"]["x"]), _column_of(syn["error"]["error"])
    chart.series.append(_series(ws, x, error, rows, "structural error"))
    (x, rows), (error, _) = _column_of(syn["points"]["x"]) if "x" in syn["points"] else \
        _column_of(list(syn["inputs"][f"x_{j}"] for j in range(1, syn["task"]["points"] + 1))), \
        _column_of(syn["points"]["error"])
    points = _series(ws, x, error, rows, "precision points", markers=True, colour="C00000")
    points.graphicalProperties.line.solidFill = None     # markers only: no line between them
    points.graphicalProperties.line.noFill = True
    chart.series.append(points)
    chart.width, chart.height = SWEEP_CHART_CM, 10
    letter, (first, _) = _column_of(syn["error"]["error"])
    ws.add_chart(chart, f"{get_column_letter(column_index_from_string(letter) + 2)}{first + 2}")


def positions_chart(ws, drawing: dict, title: str) -> None:
    """A linkage at several positions (book/synthesis_drawing.py's record), to scale in its
    live frame: one series per position through its joints, each in its own colour, named by
    its legend cell (θ2 = …), and the scale bar; beside the frame's cells."""
    chart = _chart(drawing.get("title", "The designed linkage at each precision position"),
                   title, title.replace("x", "y", 1))
    for i, p in enumerate(drawing["positions"]):
        (x, first), (_, last) = (_split(p["mapped"][0][0]), _split(p["mapped"][-1][0]))
        y = _split(p["mapped"][0][1])[0]
        s = _series(ws, x, y, (first, last), p["title"], markers=True,
                    colour=LINK_COLOURS[i % len(LINK_COLOURS)])
        column, row = _split(p["title"])
        s.tx = SeriesLabel(strRef=StrRef(f"{quote_sheetname(ws.title)}!${column}${row}"))
        chart.series.append(s)
    chart.series.append(_scale_bar(ws, {"bar": drawing["bar"], "cells": drawing["frame"]}))
    _frame_axes(chart, DRAWING_CM * 0.8)
    label = drawing["bar"]["columns"][1]
    anchor = get_column_letter(column_index_from_string(label) + 2)
    ws.add_chart(chart, f"{anchor}{drawing['bar']['rows'][0] - len(drawing['frame']) - 2}")


def _split(cell: str) -> tuple[str, int]:
    letters = cell.rstrip("0123456789")
    return letters, int(cell[len(letters):])


def _drawing(wb, t, model: Model, meta: dict) -> None:
    ws = wb[MECH]
    pos = meta["position"]
    frame = meta["frames"]["frames"][0]
    ws_frame = wb[frames.SHEET]
    chart = _chart(f"{t.title} at the current {t.mechanism.input_symbol}",
                   f"x [{t.length_unit}]", f"y [{t.length_unit}]")
    links, *path = frame["series"]
    colours = drawing_colours(pos["drawing"])
    for i, link in enumerate(pos["drawing"], start=1):
        part = link.get("kind") in PART_COLOURS      # a guide or a block: a line, no joints
        series = _mapped(ws_frame, links, tuple(link["rows"]), link_label(link, i),
                         markers=not part, width=38000, colour=colours[i - 1])
        if link.get("ground"):       # fixed pivots: triangles on a thinner grey line
            series.marker.symbol, series.marker.size = "triangle", 10
            series.graphicalProperties.line.width = 19050
        elif part:
            series.graphicalProperties.line.width = 25400 if link["kind"] == "block" else 12700
        chart.series.append(series)
    for p in path:
        chart.series.append(_mapped(ws_frame, p, tuple(p["rows"]), p["title"], width=12700,
                                    colour=PATH_COLOUR))
    chart.series.append(_scale_bar(ws_frame, frame))
    names = _joint_names(ws_frame, links, pos["drawing"])     # last: the legend leaves them out
    chart.series += names
    chart.legend.legendEntry = [LegendEntry(idx=i, delete=True) for i in
                                range(len(chart.series) - len(names), len(chart.series))]
    _frame_axes(chart, DRAWING_CM)
    ws.add_chart(chart, pos["chart_anchor"])   # under the joints table it draws


def _sweep_charts(wb, t, model: Model, meta: dict) -> int:
    ws_data, ws = wb[SWEEP], wb[CHARTS]
    sweep = meta["sweep"]
    rows = tuple(sweep["rows"])
    letters = sweep["columns"]
    ws["A1"] = f"{t.title}: charts (data on sheet {SWEEP})"
    anchor_row = 3
    for i, spec in enumerate(model.charts):
        chart = _chart(spec.title, _axis_title(spec.x_title, model, spec.x, t),
                       _axis_title(spec.y_title, model, spec.ys[0], t))
        if not spec.equal_axes:
            for key in spec.ys:
                chart.series.append(_series(ws_data, letters[spec.x], letters[key], rows,
                                            _series_title(model, key)))
        if spec.equal_axes:
            _framed(wb, chart, meta, i)
        else:
            chart.width, chart.height = SWEEP_CHART_CM, 10
            if spec.x.endswith("_deg"):
                _angle_axis(chart, t)
        ws.add_chart(chart, f"A{anchor_row}")
        anchor_row += 26 if spec.equal_axes else 21
    return anchor_row


def _framed(wb, chart: ScatterChart, meta: dict, index: int) -> None:
    """An equal-scale chart of sweep columns: its series from its live frame."""
    frame = next(f for f in meta["frames"]["frames"] if f.get("chart") == index)
    ws = wb[frames.SHEET]
    for s in frame["series"]:
        chart.series.append(_mapped(ws, s, tuple(s["rows"]), s["title"]))
    chart.series.append(_scale_bar(ws, frame))
    _frame_axes(chart, SWEEP_CHART_CM / WIDTH_RATIO)   # as wide as the other sweep charts


def _motion_charts(wb, t, model: Model, meta: dict, anchor_row: int) -> int:
    """From the Motion sheet: the angular velocities, the angular accelerations, and the main
    output's (else the traced point's) velocity and acceleration, against the input."""
    motion = meta["motion"]
    ws_data, ws = wb[MOTION_SHEET], wb[CHARTS]
    rows, letters = tuple(motion["rows"]), motion["columns"]
    by_key = {q.key: q for q in model.quantities}
    mech = t.mechanism
    x_title = header(mech.input_symbol, mech.input_unit, t.length_unit)
    omegas = [k for k in letters if k.startswith("omega_")]
    alphas = [k for k in letters if k.startswith("alpha_")]
    out = model.output
    pair = ([f"v_{out}", f"acc_{out}"] if out and f"v_{out}" in letters else
            [k for k in letters if k.startswith(("vmag_", "amag_"))])
    specs = [("Angular velocities", omegas, ANG_SPEED), ("Angular accelerations", alphas,
                                                           ANG_ACCEL)]
    specs += [(f"{by_key[k].symbol}: {by_key[k].label}", [k], by_key[k].unit) for k in pair]
    reference = _reference_sweep(t)
    for title, keys, unit in specs:
        if not keys:
            continue
        y_title = (header(by_key[keys[0]].symbol, unit, t.length_unit) if len(keys) == 1
                   else f"[{unit_text(unit, t.length_unit)}]")
        chart = _chart(title, x_title, y_title)
        alike = coinciding(keys, reference)
        for k in keys:
            name = by_key[k].symbol
            if alike.get(k):
                # one line hides the other (which one is on top differs between
                # applications): each legend entry says where the missing colour went
                name += f" (= {', '.join(by_key[o].symbol for o in alike[k])}: one curve)"
            chart.series.append(_series(ws_data, "A", letters[k], rows, name))
        chart.width, chart.height = 18, 10
        if mech.input_is_angle:
            _angle_axis(chart, t)
        ws.add_chart(chart, f"A{anchor_row}")
        anchor_row += 21
    return anchor_row


def _force_charts(wb, t, model: Model, meta: dict, anchor_row: int) -> None:
    """From the Forces sheet: the driving effort with its mean, every pin's load, the shaking
    force as a polar diagram (its y against its x) and the shaking moment."""
    from .forces import effort_key, pin_keys
    table = meta["forces"]
    ws_data, ws = wb[FORCES_SHEET], wb[CHARTS]
    rows, letters = tuple(table["rows"]), table["columns"]
    mech = t.mechanism
    x_title = header(mech.input_symbol, mech.input_unit, t.length_unit)
    effort = model.get(effort_key(model))
    specs = [(f"Driving effort {effort.symbol} (mean: the horizontal line)",
              [effort.key], effort.unit, True),
             ("Pin loads", pin_keys(model), NEWTON, False),
             ("Shaking moment on the frame", ["shaking_moment"], NEWTON_METRE, False)]
    for title, keys, unit, with_mean in specs:
        chart = _chart(title, x_title, f"[{unit}]" if len(keys) > 1 else
                       header(model.get(keys[0]).symbol, unit, t.length_unit))
        for k in keys:
            chart.series.append(_series(ws_data, "A", letters[k], rows, model.get(k).symbol))
        if with_mean:
            chart.series.append(_mean_line(ws_data, table["summary"]))
        chart.width, chart.height = SWEEP_CHART_CM, 10
        if mech.input_is_angle:
            _angle_axis(chart, t)
        ws.add_chart(chart, f"A{anchor_row}")
        anchor_row += 21
    ws.add_chart(_polar_diagram(ws_data, table), f"A{anchor_row}")


POLAR_CM = 12      # the polar diagram's height (its square plot area: SIDE of it)


def _polar_diagram(ws_data, table: dict) -> ScatterChart:
    """The shaking force's tip over the sweep, at equal scales: with it, drawn invisible and
    left out of the legend, the two corners of its square about the origin (the summary's
    polar_square cells), so both axes scale to the same span, in a square plot area. (Gnumeric
    lists the corners in the legend: it reads no deleted legend entry.)"""
    from openpyxl.utils.cell import coordinate_from_string
    from .forces import POLAR_SQUARE, SHAKING
    polar = _chart("Shaking force on the frame: polar diagram", "Fs_x [N]", "Fs_y [N]")
    polar.series.append(_series(ws_data, *(table["columns"][k] for k in SHAKING),
                                tuple(table["rows"]), "Fs (tip of the vector over the sweep)"))
    for i in (0, 1):      # a series per corner: one point, no line to draw in any application
        (x_col, row), (y_col, _) = (coordinate_from_string(
            table["summary"][f"{POLAR_SQUARE}{a}{i}"]["cell"]) for a in "xy")
        corner = _series(ws_data, x_col, y_col, (row, row), f"corner {i + 1} of the square")
        corner.graphicalProperties.line.noFill = True
        polar.series.append(corner)
    polar.legend.legendEntry = [LegendEntry(idx=i, delete=True) for i in (1, 2)]
    # room on the left for the y axis's title and its numbers, which a frame has not
    _square_plot_area(polar, POLAR_CM, left=0.12)
    return polar


def _mean_line(ws, cells: dict) -> Series:
    """The effort's mean as a horizontal line over the sweep: the summary's two points (the
    inputs in one column, the mean beside them)."""
    (x0, x1), (y0, _) = ([cells[f"mean_line_{a}{i}"]["cell"] for i in (0, 1)] for a in "xy")
    x_col, y_col = x0.rstrip("0123456789"), y0.rstrip("0123456789")
    s = _series(ws, x_col, y_col, (int(x0[len(x_col):]), int(x1[len(x_col):])), "mean")
    s.graphicalProperties.line.prstDash = "dash"
    return s


EQUAL_REL = 1e-9      # two series within this share of their peak at every row are one curve


def _reference_sweep(t: Template) -> dict:
    """Every column over the sweep as the independent reference computes it: it, not the
    formulas being charted, says which curves coincide."""
    import numpy as np
    from ..check import reference as generic
    return generic.solve(t.mechanism.description, t.values(), np.array(t.sweep.angles()))


def same_curve(a, b) -> bool:
    """Equal at every row of the sweep (relative to their peak), undefined at the same rows."""
    import numpy as np
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    shown = np.isfinite(a)
    if not shown.any() or not np.array_equal(shown, np.isfinite(b)):
        return False
    peak = max(np.abs(a[shown]).max(), np.abs(b[shown]).max())
    return bool(np.abs(a[shown] - b[shown]).max() <= EQUAL_REL * max(peak, 1e-300))


def coinciding(keys: list[str], reference: dict) -> dict[str, list[str]]:
    """{key: the other keys whose series equals its own over the whole sweep}."""
    known = [k for k in keys if k in reference]
    return {k: [o for o in known if o != k and same_curve(reference[k], reference[o])]
            for k in known}


def _series_title(model: Model, key: str) -> str:
    base = key[:-4] if key.endswith("_deg") else key
    return model.get(base).symbol if base in {q.key for q in model.quantities} else key


def _axis_title(text: str, model: Model, key: str, t: Template) -> str:
    if "[" in text:
        return text
    if key == t.mechanism.input_column:
        return header(text, t.mechanism.input_unit, t.length_unit)
    base = key[:-4] if key.endswith("_deg") else key
    try:
        q = model.get(base)
    except KeyError:
        return text
    return header(text, "deg" if key.endswith("_deg") else q.unit, t.length_unit)


def _family_chart(wb, t, model: Model, meta: dict) -> None:
    grid = meta["grid"]
    ws = wb[GRID]
    param, out = grid["param"], grid["key"]
    q = model.get(out)
    chart = _chart(f"{q.symbol} over a crank turn, one curve per {param}",
                   f"{t.mechanism.input_symbol} [deg]", header(q.symbol, LENGTH, t.length_unit))
    rows = tuple(grid["rows"])
    for letter, value in zip(grid["columns"], t.grid_values):
        chart.series.append(_series(ws, "A", letter, rows, f"{param} = {value:g} {t.length_unit}"))
    chart.width, chart.height = 20, 12
    _angle_axis(chart, t)
    ws.add_chart(chart, f"{get_column_letter(len(grid['columns']) + 3)}4")
