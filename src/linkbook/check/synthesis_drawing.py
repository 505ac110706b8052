"""Judging the drawing of a designed linkage at its positions (book/synthesis_drawing.py): each
joint's coordinates against the kinematic reference placing the designed linkage at that
position's input angle on its branch, each legend, and the live frame by the rule every
equal-scale drawing follows (drawing.py)."""
from __future__ import annotations

import math

import numpy as np

from .checks import Check, compare, compare_exact
from .context import Judging, slope_of
from .drawing import _book_extents, _check_square, _need


class _Joints:
    """The reference's solver with each joint's coordinate as a column (`x B`, `y B`), so that
    context.slope_of takes a joint's slope as it takes a column's."""

    def __init__(self, solver):
        self.solver, self.mechanism = solver, solver.mechanism

    def solve(self, params: dict, angles, turns=None) -> dict:
        points = self.solver.solve(params, angles)["points"]
        return {f"{'xy'[axis]} {name}": np.asarray(xy[axis], dtype=float)
                for name, xy in points.items() for axis in (0, 1)}


def check_positions_drawing(j: Judging, drawing: dict, sheet: str, angles: np.ndarray) -> None:
    """`drawing`: the record's; `angles`: each position's input angle in degrees (the
    reference's, which places the designed linkage there: NaN where there is none)."""
    positions = drawing["positions"]
    joints = _Joints(j.solver)
    world = joints.solve(j.params, angles)      # NaN but at the fixed pivots, if not usable
    legends = Check("synthesis", "drawing legends", j.size)
    titles = [p["title"] for p in positions]
    shown = j.got(sheet, titles)
    placed = np.isfinite(angles)        # a position no design reaches: its legend is #N/A
    compare_exact(legends, sheet, [c for c, ok in zip(titles, placed) if ok],
                  [text for text, ok in zip(shown, placed) if ok],
                  [_legend(a, text) for a, text, ok in zip(angles, shown, placed) if ok])
    compare(legends, sheet, [c for c, ok in zip(titles, placed) if not ok],
            [text for text, ok in zip(shown, placed) if not ok], np.nan, "-", j.rules)
    j.checks.append(legends)
    coordinates = {0: [], 1: []}            # per axis: (position, name, cell, mapped cell)
    for i, p in enumerate(positions):
        for name, cells, mapped in zip(p["joints"], p["cells"], p["mapped"]):
            for axis in (0, 1):
                coordinates[axis].append((i, name, cells[axis], mapped[axis]))
    expected = {axis: np.array([world[f"{'xy'[axis]} {name}"][i]
                                for i, name, _, _ in coordinates[axis]]) for axis in (0, 1)}

    def slope(axis: int, per: float = 1.0):
        def at(k: int) -> float:
            i, name, _, _ = coordinates[axis][k]
            return slope_of(joints, j.params, angles[i:i + 1], f"{'xy'[axis]} {name}",
                            "length", scale=j.scale)(0) / per
        return at
    for axis in (0, 1):
        j.run("synthesis", f"drawing {'xy'[axis]}", sheet,
              [c for _, _, c, _ in coordinates[axis]], expected[axis], "length", slope(axis))
    _check_frame(j, drawing["frame"], sheet, coordinates, expected, slope)


def _legend(angle: float, shown) -> str:
    """θ2 to one decimal, as the legend shows it: in any 360° window (a pose's θ2_j = ∠W + β_j
    may pass 180°: the same crank position), and either rounding where θ2 is within 1e-9 of a
    half-step (θ2 = 75.05, which the book's θ2 may hold as 75.04999…)."""
    texts = [f"θ2 = {a + turn:.1f}°" for turn in (0, 360, -360)
             for a in (angle, angle * (1 - 1e-9), angle * (1 + 1e-9))]
    return shown if shown in texts else texts[0]


def _check_frame(j: Judging, cells: dict, sheet: str, coordinates: dict, expected: dict,
                 slope) -> None:
    """The frame's extents, centre and square by the rule, and every mapped cell: the
    reference's coordinate in squares of that frame."""
    mapped = {axis: [m for _, _, _, m in coordinates[axis]] for axis in (0, 1)}
    if not np.isfinite(np.concatenate([expected[0], expected[1]])).all():
        j.run("synthesis", "drawing frame", sheet, [cells[k] for k in cells],
              np.full(len(cells), math.nan), "-")
        for axis in (0, 1):
            j.run("synthesis", f"drawing {'xy'[axis]} [squares]", sheet, mapped[axis],
                  np.full(len(mapped[axis]), math.nan), "-")
        return
    lo = {"x": float(expected[0].min()), "y": float(expected[1].min())}
    hi = {"x": float(expected[0].max()), "y": float(expected[1].max())}
    ext = _book_extents(j, sheet, cells, lo, hi)
    centre = {"x": (ext["xmin"] + ext["xmax"]) / 2, "y": (ext["ymin"] + ext["ymax"]) / 2}
    need = _need(ext)
    keys = ("xmin", "xmax", "ymin", "ymax", "cx", "cy", "need")
    values = (lo["x"], hi["x"], lo["y"], hi["y"], centre["x"], centre["y"], need)
    # an extent is a joint's coordinate: its allowance near a limit position (the centre and
    # the need are judged from the book's own extents)
    at = [int(np.argmin(expected[0])), int(np.argmax(expected[0])),
          int(np.argmin(expected[1])), int(np.argmax(expected[1]))]
    j.run("synthesis", "drawing frame", sheet, [cells[k] for k in keys], np.array(values),
          "length", lambda k: slope(k // 2)(at[k]) if k < 4 else 0.0)
    square_check, square = _check_square(j, sheet, cells, need, "synthesis drawing")
    j.checks.append(square_check)
    for axis, centre_of in ((0, centre["x"]), (1, centre["y"])):
        c = Check("synthesis", f"drawing {'xy'[axis]} [squares]", j.size, 1.0, j.size / square)
        j.compare(c, sheet, mapped[axis], (expected[axis] - centre_of) / square, "-",
                  slope(axis, square))
        j.checks.append(c)
