"""The Mechanism sheet's joints table: every joint's coordinates at the current position, then
each link, guide and slider block as a run of rows that the drawing chart draws (through its
frame on the sheet `Drawing data`, frames.py).
"""
from __future__ import annotations

import re

from ..base.sheets import DRAWING_COLUMNS, JOINT_COLUMN, SWEEP
from ..language.excel import parenthesize, render
from ..language.model import LENGTH, Model
from .resolve import Resolver
from ..language.templates import Template
from .frames import SQUARE_CELL
from .style import (block_head, column_range, column_width, number_format, put_text,
                    set_formula)
from .sweep import numbers_place


def joints_table(ws, t: Template, model: Model, resolve: Resolver) -> dict:
    """Joint coordinates, then each link as a run of rows the drawing chart reads."""
    block_head(ws, "L", "Joints and links (drawing data)",
               (("Link", 8), ("Joint", 8), ("x", 11), ("y", 11)))
    cells: dict[str, list[str]] = {}
    row = 7
    x_col, y_col = DRAWING_COLUMNS
    for j in model.joints:
        put_text(ws, f"{JOINT_COLUMN}{row}", j.name)
        for col, expr in ((x_col, j.x), (y_col, j.y)):
            set_formula(ws[f"{col}{row}"], "=" + render(expr, resolve))
            ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
        cells[j.name] = [f"{x_col}{row}", f"{y_col}{row}"]
        row += 1
    drawing = []
    row += 1
    # the textbook's numbering: the ground is link 1 (drawn through the fixed pivots when there
    # are two or more), the crank link 2, and so on
    links = [(1, model.ground, True)] if len(model.ground) > 1 else []
    links += [(i, link, False) for i, link in enumerate(model.links, start=2)]
    for i, link, ground in links:
        first = row
        for name in link:
            put_text(ws, f"L{row}", f"link {i}")
            put_text(ws, f"{JOINT_COLUMN}{row}", name)
            set_formula(ws[f"{x_col}{row}"], f"={cells[name][0]}")
            set_formula(ws[f"{y_col}{row}"], f"={cells[name][1]}")
            for col in DRAWING_COLUMNS:
                ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
            row += 1
        body = link[:-1] if len(link) > 2 and link[0] == link[-1] else link
        drawing.append({"joints": list(link), "rows": [first, row - 1], "ground": ground,
                        "label": f"link {i}: " + ("ground" if ground else "".join(body))})
    for part in _slider_parts(t, model, resolve):
        first = row
        for name, (x, y) in part["points"]:
            put_text(ws, f"L{row}", part["kind"])
            put_text(ws, f"{JOINT_COLUMN}{row}", name)
            set_formula(ws[f"{x_col}{row}"], x)
            set_formula(ws[f"{y_col}{row}"], y)
            for col in DRAWING_COLUMNS:
                ws[f"{col}{row}"].number_format = number_format(LENGTH, t.length_unit)
            row += 1
        drawing.append({"joints": [name for name, _ in part["points"]], "rows": [first, row - 1],
                        "ground": False, "kind": part["kind"], "label": part["label"]})
    # a slider's rows name longer points (`B guide 1`): shown whole
    for col in ("L", JOINT_COLUMN):
        names = [ws[f"{col}{r}"].value for r in range(7, row)]
        widest = max((column_width(n) for n in names if isinstance(n, str)), default=0.0)
        ws.column_dimensions[col].width = max(ws.column_dimensions[col].width, widest)
    return {"cells": cells, "drawing": drawing, "chart_row": row + 1}


# A block is BLOCK_SQUARES grid squares of the drawing (along its line, across it), so that it
# reads the same at any size; a guide runs over the block's travel in the sweep, whose ends lie
# inside the drawing's frame.
BLOCK_SQUARES = (0.8, 0.4)
BLOCK_CORNERS = ((-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1))    # closed, counter-clockwise


def _slider_parts(t: Template, model: Model, resolve: Resolver) -> list[dict]:
    """The guides and blocks of the drawing: {kind, label, points: [(name, (x, y))]}, each
    coordinate a formula at the current position sized in the drawing's grid squares."""
    copies, first, last = numbers_place(t, model)
    half_long, half_across = (f"{b / 2:g}*{SQUARE_CELL}" for b in BLOCK_SQUARES)
    parts = []
    for g in model.guides:
        travel = column_range(SWEEP, copies[g.travel], first, last)   # numbers only
        ends = []
        for k, fn in enumerate(("MIN", "MAX"), start=1):
            reach = f"{fn}({travel})"
            # a block that never closes over the sweep has no travel: no guide (#N/A)
            ends.append((f"{g.point} {g.kind} {k}",
                         tuple(f"=IF(COUNT({travel}),"
                               + _sum([(1, render(o, resolve), "1"),
                                       (1, reach, render(c, resolve))]) + ",NA())"
                               for o, c in ((g.x, g.cos), (g.y, g.sin)))))
        parts.append({"kind": g.kind, "label": f"{g.kind} of {g.point}", "points": ends})
    for b in model.blocks:
        x, y, cos, sin = (render(e, resolve) for e in (b.x, b.y, b.cos, b.sin))
        corners = []
        for k, (u, v) in enumerate(BLOCK_CORNERS[:-1], start=1):
            # the corner u·(half length)·d + v·(half width)·n, n = d turned +90°
            corners.append((f"{b.point} block {k}", (
                "=" + _sum([(1, x, "1"), (u, half_long, cos), (-v, half_across, sin)]),
                "=" + _sum([(1, y, "1"), (u, half_long, sin), (v, half_across, cos)]))))
        parts.append({"kind": "block", "label": f"block at {b.point}",
                      "points": corners + corners[:1]})
    return parts


def _sum(terms: list[tuple[int, str, str]]) -> str:
    """Σ sign·term·factor as formula text; a factor 0 drops its term, 1 and −1 are written into
    its sign (a horizontal line's formulas carry no ×0 or ×1)."""
    out = ""
    for sign, term, factor in terms:
        f = factor.strip()
        if f in ("0", "-0", "(0)") or term in ("0", "(0)"):
            continue
        if f in ("-1", "(-1)"):
            sign, f = -sign, "1"
        if f not in ("1", "(1)") or sign < 0:
            term = f"({term})" if _has_sum(term) else term
        text = term if f in ("1", "(1)") else f"{term}*{parenthesize(f)}"
        out += ("-" if sign < 0 else ("+" if out else "")) + text
    return out or "0"


def _has_sum(text: str) -> bool:
    """A + or − outside brackets (after the first character): the text needs brackets to be
    multiplied or subtracted."""
    depth = 0
    for i, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and i > 0 and ch in "+-" and text[i - 1] not in "*/^(" \
                and not _EXPONENT.search(text[:i]):
            return True
    return text.startswith("-")


# a number's exponent just before a sign (1.5E-3): the sign is the number's, not a sum's
_EXPONENT = re.compile(r"(?<![\w$.])\d+(\.\d*)?E$")
