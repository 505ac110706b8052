"""Geometry on solved points, vectorised over the rows: the angle between two vectors, an
angle brought into the window of its definition, the direction of a line given in degrees.
"""

from __future__ import annotations

import math

import numpy as np

Point = tuple[np.ndarray, np.ndarray]    # a point's x and y, one value per row

HALF_PI = 0.5 * math.pi
TAU = 2.0 * math.pi


def interior(ux, uy, vx, vy):
    """Interior angle between vectors u and v, in [0, π]."""
    return np.arctan2(np.abs(ux * vy - uy * vx), ux * vx + uy * vy)


def direction(dx, dy):
    """The angle of the vector (dx, dy), NaN where it is zero: two points at one place give
    no direction (np.arctan2 would say 0)."""
    dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
    return np.where((dx == 0.0) & (dy == 0.0), math.nan, np.arctan2(dy, dx))


def cos_sin_deg(deg: float) -> tuple[float, float]:
    """cos and sin of an angle in degrees, exact at multiples of 90° (a horizontal line stays
    exactly horizontal)."""
    if deg == deg and abs(deg) != math.inf and deg % 90.0 == 0.0:
        k = int(deg // 90.0) % 4
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[k]
    r = math.radians(deg)
    return math.cos(r), math.sin(r)



def near(angle, center):
    """The angle (radians, any turn) brought into [center − π, center + π)."""
    return center + (np.remainder(angle - center + math.pi, TAU) - math.pi)



def unit(x, y) -> tuple:
    """The vector (x, y) scaled to length 1."""
    r = np.hypot(x, y)
    return x / r, y / r


def turned_direction(a: str, b: str, degrees: float):
    """The direction of the frame a→b turned by `degrees`, as a function of a solve() result
    (a line carried by a moving link: a slider along its link, a slot in its frame)."""
    c, s = cos_sin_deg(degrees)

    def line(solved):
        points = solved["points"]
        ex, ey = unit(points[b][0] - points[a][0], points[b][1] - points[a][1])
        return ex * c - ey * s, ex * s + ey * c
    return line
