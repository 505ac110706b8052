"""XY scatter charts: the mechanism drawing, the sweep charts and the pump family.

Geometry is drawn with equal scales: both axes get the same span, fixed from the evaluated
workbook (every joint over the whole sweep plus a margin), and a square plot area. Excel and
LibreOffice would otherwise pick each axis range on its own and distort the mechanism.
"""
from __future__ import annotations

import math

from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.chart.axis import ChartLines
from openpyxl.chart.data_source import NumFmt
from openpyxl.chart.layout import Layout, ManualLayout
from openpyxl.chart.shapes import GraphicalProperties
from openpyxl.utils import column_index_from_string, get_column_letter

from .model import ANG_ACCEL, ANG_SPEED, LENGTH, Model, header, unit_text
from .templates import Template
from .workbook import CHARTS, DRAWING_COLUMNS, GRID, MECH, MOTION_SHEET, SWEEP, Built

LINE_EMU = 22000          # 1.7 pt
DRAWING_CM = 15.0
# The drawing's colours, set in the file (not left to the theme) so that `linkbook animate`
# draws each link as the workbook does: link 1, 2, ... then the traced point's path.
LINK_COLOURS = ("4F81BD", "C0504D", "9BBB59", "F79646", "4BACC6", "1F497D", "948A54")
PATH_COLOUR = "8064A2"
GROUND_COLOUR = "7F7F7F"


def drawing_colours(drawing: list[dict]) -> list[str]:
    """A colour per drawn link: grey for the ground, the palette in turn for moving links."""
    colours, k = [], 0
    for link in drawing:
        if link.get("ground"):
            colours.append(GROUND_COLOUR)
        else:
            colours.append(LINK_COLOURS[k % len(LINK_COLOURS)])
            k += 1
    return colours


def link_label(link: dict, i: int) -> str:
    """The legend's name of a drawn link (books built before labels: numbered from 1)."""
    if "label" in link:
        return link["label"]
    joints = link["joints"]
    body = joints[:-1] if len(joints) > 2 and joints[0] == joints[-1] else joints
    return f"link {i}: {''.join(body)}"


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


def nice_step(span: float) -> float:
    """A 1-2-5 grid step giving about 6 divisions."""
    raw = span / 6
    power = 10 ** math.floor(math.log10(raw))
    return next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw)


def decimals(step: float) -> int:
    """The decimals a tick label of a 1-2-5 step needs (0.25 → 2, 50 → 0)."""
    return next((d for d in range(16) if abs(round(step, d) - step) <= 1e-9 * step), 15)


def _equal_axes(chart: ScatterChart, xs: list[float], ys: list[float], size_cm: float) -> None:
    """Same span on both axes, centred on the data, and a square plot area."""
    xs = [v for v in xs if isinstance(v, float) and math.isfinite(v)]
    ys = [v for v in ys if isinstance(v, float) and math.isfinite(v)]
    if not xs or not ys:
        return
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-9) * 1.12
    step = nice_step(span)
    cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    half = math.ceil(span / 2 / step) * step
    places = decimals(step)
    for axis, centre in ((chart.x_axis, cx), (chart.y_axis, cy)):
        # whole multiples of the step, rounded to its decimals: no tick reads 2.8E-17
        low = round(math.floor((centre - half) / step) * step, places)
        axis.scaling.min = low
        axis.scaling.max = round(low + 2 * half + step, places)
        axis.majorUnit = step
        axis.numFmt = NumFmt(formatCode="0." + "0" * places if places else "0",
                             sourceLinked=False)
    chart.width = chart.height = size_cm
    chart.plot_area.layout = Layout(ManualLayout(layoutTarget="inner", xMode="edge",
                                                 yMode="edge", x=0.16, y=0.11, w=0.72, h=0.72))


def _angle_axis(chart: ScatterChart, t: Template) -> None:
    chart.x_axis.scaling.min = t.sweep.start
    chart.x_axis.scaling.max = t.sweep.stop
    chart.x_axis.majorUnit = 30 if t.sweep.stop - t.sweep.start >= 180 else None


def _column(values: dict, sheet: str, letter: str, rows: tuple[int, int]) -> list:
    return [values.get((sheet, f"{letter}{r}")) for r in range(rows[0], rows[1] + 1)]


def add_charts(built: Built, t: Template, model: Model, values: dict) -> None:
    wb, meta = built.workbook, built.meta
    _drawing(wb, t, model, meta, values)
    row = _sweep_charts(wb, t, model, meta, values)
    if "motion" in meta:
        _motion_charts(wb, t, model, meta, row)
    if "grid" in meta:
        _family_chart(wb, t, model, meta)


def _drawing(wb, t, model: Model, meta: dict, values: dict) -> None:
    ws = wb[MECH]
    pos, sweep = meta["position"], meta["sweep"]
    rows = tuple(sweep["rows"])
    chart = _chart(f"{t.title} at the current {t.mechanism.input_symbol}",
                   f"x [{t.length_unit}]", f"y [{t.length_unit}]")
    colours = drawing_colours(pos["drawing"])
    for i, link in enumerate(pos["drawing"], start=1):
        series = _series(ws, *DRAWING_COLUMNS, tuple(link["rows"]), link_label(link, i),
                         markers=True, width=38000, colour=colours[i - 1])
        if link.get("ground"):       # fixed pivots: triangles on a thinner grey line
            series.marker.symbol, series.marker.size = "triangle", 10
            series.graphicalProperties.line.width = 19050
        chart.series.append(series)
    if model.path:
        x_key, y_key = model.path
        chart.series.append(_series(wb[SWEEP], sweep["columns"][x_key], sweep["columns"][y_key],
                                    rows, f"path of {y_key[1:]}", width=12700,
                                    colour=PATH_COLOUR))
    xs, ys = [], []
    for joint in model.joints:
        for key, out in ((joint.x, xs), (joint.y, ys)):
            column = key.strip("{}")
            if key == f"{{{column}}}" and column in sweep["columns"]:
                out += _column(values, SWEEP, sweep["columns"][column], rows)
            else:
                cell = pos["joints"][joint.name][0 if out is xs else 1]
                out.append(values.get((MECH, cell)))
    _equal_axes(chart, xs, ys, DRAWING_CM)
    ws.add_chart(chart, pos["chart_anchor"])   # under the joints table it draws


def _sweep_charts(wb, t, model: Model, meta: dict, values: dict) -> None:
    ws_data, ws = wb[SWEEP], wb[CHARTS]
    sweep = meta["sweep"]
    rows = tuple(sweep["rows"])
    letters = sweep["columns"]
    ws["A1"] = f"{t.title}: charts (data on sheet {SWEEP})"
    anchor_row = 3
    for spec in model.charts:
        chart = _chart(spec.title, _axis_title(spec.x_title, model, spec.x, t),
                       _axis_title(spec.y_title, model, spec.ys[0], t))
        for key in spec.ys:
            chart.series.append(_series(ws_data, letters[spec.x], letters[key], rows,
                                        _series_title(model, key)))
        if spec.equal_axes:
            _equal_axes(chart, _column(values, SWEEP, letters[spec.x], rows),
                        _column(values, SWEEP, letters[spec.ys[0]], rows), 14)
        else:
            chart.width, chart.height = 18, 10
            if spec.x.endswith("_deg"):
                _angle_axis(chart, t)
        ws.add_chart(chart, f"A{anchor_row}")
        anchor_row += 30 if spec.equal_axes else 21
    return anchor_row


def _motion_charts(wb, t, model: Model, meta: dict, anchor_row: int) -> None:
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
    for title, keys, unit in specs:
        if not keys:
            continue
        y_title = (header(by_key[keys[0]].symbol, unit, t.length_unit) if len(keys) == 1
                   else f"[{unit_text(unit, t.length_unit)}]")
        chart = _chart(title, x_title, y_title)
        for k in keys:
            chart.series.append(_series(ws_data, "A", letters[k], rows, by_key[k].symbol))
        chart.width, chart.height = 18, 10
        if mech.input_is_angle:
            _angle_axis(chart, t)
        ws.add_chart(chart, f"A{anchor_row}")
        anchor_row += 21


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
