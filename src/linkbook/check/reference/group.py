"""A group of points found together: a class-III Assur group (the triad) whose unknown points
are held by distances to known points and to one another, and can be placed only all at once.

Every unknown point's x and y is an unknown; every distance is one residual
(|P − Q|² − L²)/(2L) (a length, ≈ |P − Q| − L near the root), and Newton solves all of them
together (newton.newton, LAPACK for the system). The assembly is the one the template's sketch
chooses: the first row starts from the sketch, every next row from the row above's root
(continuation), and a row after one where the group did not close starts from the sketch
again. A rigid link through three of the points (the triad's ternary link) keeps the turning
sense of its three joints: a root that mirrors it is no assembly of that link (NaN).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple, Union

import numpy as np

from .geometry import Point
from .newton import Fun, finite, newton

# An end of a distance: the index of an unknown point, or a known point (its x, y per row).
End = Union[int, Point]


class Bar(NamedTuple):
    """|p − q| = length: a binary link (a known point to an unknown one) or a side of a
    rigid link between two unknown points."""
    p: End
    q: End
    length: float


class Turn(NamedTuple):
    """The turning sense of three unknown points of one rigid link: sign·cross(j − i, k − i) > 0."""
    i: int
    j: int
    k: int
    sign: float


def residuals(bars: Sequence[Bar], row: int, count: int) -> Fun:
    """Row `row`'s residuals and their Jacobian in the 2·count unknowns (x0, y0, x1, y1, ...)."""
    ends = [_end(bar.p, row) + _end(bar.q, row) + (bar.length, bar.length * bar.length,
                                                    2.0 * bar.length) for bar in bars]
    width = 2 * count

    def fun(z):
        f, jac = [], []
        for p, px, py, q, qx, qy, length, square, twice in ends:
            if p >= 0:
                px, py = z[p], z[p + 1]
            if q >= 0:
                qx, qy = z[q], z[q + 1]
            dx, dy = px - qx, py - qy
            f.append((dx * dx + dy * dy - square) / twice)
            line = [0.0] * width
            if p >= 0:      # the derivatives in p's x and y, (±dx, ±dy)/length, added to 0
                line[p] += dx / length
                line[p + 1] += dy / length
            if q >= 0:
                line[q] += -dx / length
                line[q + 1] += -dy / length
            jac.append(tuple(line))
        return tuple(f), tuple(jac)
    return fun


def _end(end: End, row: int) -> tuple[int, float, float]:
    """(the index of its x among the unknowns, or -1; its x and y where it is known)."""
    if isinstance(end, int):
        return 2 * end, math.nan, math.nan
    return -1, float(end[0][row]), float(end[1][row])


def turning(turn: Turn, z: Sequence[float]) -> float:
    """cross(j − i, k − i) of the unknowns z."""
    xi, yi = z[2 * turn.i], z[2 * turn.i + 1]
    return ((z[2 * turn.j] - xi) * (z[2 * turn.k + 1] - yi)
            - (z[2 * turn.j + 1] - yi) * (z[2 * turn.k] - xi))


def solve_group(n_rows: int, count: int, bars: Sequence[Bar], sketch: Sequence[float],
                turns: Sequence[Turn], size: float, tol_f: float) -> list[Point]:
    """The `count` unknown points on every row (NaN where the group does not close), by Newton
    on every distance at once, continued from row to row and started from the `sketch`
    (x0, y0, x1, y1, ...) on the first row and after a row that did not close."""
    out = np.full((n_rows, 2 * count), math.nan)
    scales = [size] * (2 * count)
    prev: list[float] | None = None
    for row in range(n_rows):
        known = [b.length for b in bars] + [float(c[row]) for b in bars for end in (b.p, b.q)
                                            if not isinstance(end, int) for c in end]
        if not finite(*known) or min(b.length for b in bars) <= 0.0:
            prev = None
            continue
        z = newton(residuals(bars, row, count), prev if prev is not None else sketch,
                   scales, tol_f)
        if z is not None and all(t.sign * turning(t, z) > 0.0 for t in turns):
            out[row] = z
            prev = z
        else:
            prev = None
    return [(out[:, 2 * k], out[:, 2 * k + 1]) for k in range(count)]
