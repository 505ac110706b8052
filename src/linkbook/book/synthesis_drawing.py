"""The designed linkage drawn at each of its positions, on the Synthesis sheet (issue 38): a live
frame (frames.py's rule: centred on the extents of every drawn joint, a grid square of 1, 2 or
5 × 10ⁿ length units) that maps the joints' coordinates into the fixed axes of an equal-scale
chart, one series per position (charts.py draws it from the record this returns).

positions_drawing takes the positions as cells already written (each position's legend cell
and its joints' coordinate cells, in drawing order), so that any synthesis table can be drawn:
function generation writes the joints at each precision point's θ2_j (joints_at).
"""
from __future__ import annotations

from openpyxl.utils import get_column_letter

from ..language.excel import render
from ..language.model import LENGTH, Model
from ..language.templates import Template
from .frames import BAR, FRAME_CELLS, MAPPED_FORMAT, frame_formulas
from .resolve import Resolver
from .style import (BOLD, DERIVED_FILL, number_format, put_head, put_text, set_formula,
                    text_width, unit_text)


def linkage_path(model: Model) -> list[str]:
    """The moving links as one line through their joints (A0, A, B, B0 for a four-bar; a
    coupler triangle's sides too): each link's sides in turn, continuing from the line's end,
    and where none continues, back along the shortest run of sides already drawn to a joint
    where one does (a line retraced is drawn over itself)."""
    sides = [(link[k], link[k + 1]) for link in model.links for k in range(len(link) - 1)]
    if not sides:
        return []
    path, left = [sides[0][0]], list(sides)
    while left:
        here = path[-1]
        nxt = next((s for s in left if here in s), None)
        if nxt is None:
            path += _route(sides, here, {p for s in left for p in s})[1:]
            continue
        left.remove(nxt)
        path.append(nxt[1] if nxt[0] == here else nxt[0])
    return path


def _route(sides: list[tuple[str, str]], start: str, goals: set[str]) -> list[str]:
    """The shortest run of sides from `start` to any of `goals` (breadth first)."""
    came = {start: None}
    queue = [start]
    for here in queue:
        if here in goals:
            route = [here]
            while came[route[-1]] is not None:
                route.append(came[route[-1]])
            return route[::-1]
        for p, q in sides:
            for a, b in ((p, q), (q, p)):
                if a == here and b not in came:
                    came[b] = here
                    queue.append(b)
    raise ValueError(f"the links do not join {start} to {sorted(goals)}")


def joints_at(ws, t: Template, model: Model, names: dict[str, str], head: int, col: int,
              angles: list[str]) -> list[dict]:
    """A table from row `head`, column `col`: per input angle (cells in degrees, `angles`) its
    legend text and the joints of linkage_path at that angle by the position steps (the
    designed linkage, as every sheet computes it); the positions for positions_drawing."""
    path = linkage_path(model)
    joints = {j.name: j for j in model.joints}
    letters = [get_column_letter(col + k) for k in range(5)]
    unit = unit_text(LENGTH, t.length_unit)
    for k, text in enumerate(("j", "legend", "joint", f"x [{unit}]", f"y [{unit}]")):
        put_head(ws, head, col + k, text)
    positions = []
    row = head + 1
    for i, angle in enumerate(angles, start=1):
        resolve = Resolver(model, names, {t.mechanism.input_column: angle})
        ws[f"{letters[0]}{row}"] = i
        label = f"{letters[1]}{row}"
        set_formula(ws[label], f'="θ2 = "&FIXED({angle},1,TRUE)&"°"')
        cells = []
        for name in path:
            put_text(ws, f"{letters[2]}{row}", name)
            xy = []
            for letter, expr in zip(letters[3:], (joints[name].x, joints[name].y)):
                set_formula(ws[f"{letter}{row}"], "=" + render(expr, resolve))
                ws[f"{letter}{row}"].number_format = number_format(LENGTH, t.length_unit)
                xy.append(f"{letter}{row}")
            cells.append(xy)
            row += 1
        positions.append({"title": label, "theta2": angle, "joints": path, "cells": cells})
    return positions


def positions_drawing(ws, t: Template, positions: list[dict], head: int, col: int) -> dict:
    """Each position's joints mapped into one live frame, from row `head`, column `col`: two
    columns of mapped coordinates (a run of rows per position), then the frame's cells and
    the scale bar's two points. Every position's coordinates must be numbers or #N/A alike
    (a designed linkage closes at all its positions, or there is none): the extents are MIN
    and MAX over them. The record: the frame's cells, the bar, and per position its mapped
    cells."""
    mx, my = get_column_letter(col), get_column_letter(col + 1)
    label, value = get_column_letter(col + 3), get_column_letter(col + 4)
    put_head(ws, head, col, "x [squares]")
    put_head(ws, head, col + 1, "y [squares]")
    ref = {k: f"${value}${head + 1 + i}" for i, (k, _, _) in enumerate(FRAME_CELLS)}
    cells = {k: f"{value}{head + 1 + i}" for i, (k, _, _) in enumerate(FRAME_CELLS)}
    row = head + 1
    for p in positions:
        p["mapped"] = []
        for x, y in p["cells"]:
            for letter, source, centre in ((mx, x, ref["cx"]), (my, y, ref["cy"])):
                set_formula(ws[f"{letter}{row}"], f"=({source}-{centre})/{ref['square']}")
                ws[f"{letter}{row}"].number_format = MAPPED_FORMAT
            p["mapped"].append([f"{mx}{row}", f"{my}{row}"])
            row += 1
    ranges = [[_span(p["cells"], axis) for p in positions] for axis in (0, 1)]
    ws.column_dimensions[label].width = max(text_width(text) for _, text, _ in FRAME_CELLS)
    ws.column_dimensions[value].width = 22     # the scale bar's legend: grid square 0.005 mm
    put_head(ws, head, col + 3, "Frame")
    put_head(ws, head, col + 4, f"Value [{unit_text(LENGTH, t.length_unit)}]")
    formulas = frame_formulas(ref, ranges, t.length_unit)
    for key, text, is_length in FRAME_CELLS:
        put_text(ws, f"{label}{cells[key][len(value):]}", text)
        set_formula(ws[cells[key]], formulas[key])
        ws[cells[key]].fill = DERIVED_FILL
        if is_length:
            ws[cells[key]].number_format = number_format(LENGTH, t.length_unit)
    bar = head + 2 + len(FRAME_CELLS)
    put_text(ws, f"{label}{bar - 1}", "scale bar [squares]", BOLD)
    for k, point in enumerate(BAR):
        for letter, v in zip((label, value), point):
            ws[f"{letter}{bar + k}"] = v
    return {"frame": cells, "bar": {"columns": [label, value], "rows": [bar, bar + 1]},
            "positions": positions}


def _span(cells: list[list[str]], axis: int) -> str:
    """The run of cells of one axis of a position (top to bottom), as a range."""
    first, last = cells[0][axis], cells[-1][axis]
    return first if first == last else f"{first}:{last}"
