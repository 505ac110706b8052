"""Constraint systems the reference shares between step types: a point at given distances from
two known points (a dyad's loop, a point carried by a stretching frame) and a triangle from its
three sides (a point carried by a rigid frame).

Each system is a residual function of the unknowns with its Jacobian, for newton.newton and
newton.sweep. Residuals are lengths, so that one tolerance in the mechanism's size judges them.
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import Point
from .newton import (DENSE_STARTS, NEAR_DOUBLE, RES_TOL, STARTS, TANGENT, Fun, directions,
                     finite, newton, polish, solved_column, sweep)

# Error-free transformations (Dekker, Knuth): a residual such as |R − P|² − p² near a double root
# is a difference of nearly equal squares; in plain doubles it is exactly 0 on a whole plateau
# of width √ε around the root. Carried in double-double it is not.
_SPLITTER = 134217729.0  # 2^27 + 1


def _two_sum(a: float, b: float) -> tuple[float, float]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_square(a: float) -> tuple[float, float]:
    p = a * a
    t = _SPLITTER * a
    hi = t - (t - a)
    lo = a - hi
    return p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo


def square_gap(x: float, y: float, px: float, py: float, r: float) -> float:
    """(x − px)² + (y − py)² − r², with the differences and squares carried exactly."""
    dx, ex = _two_sum(x, -px)
    dy, ey = _two_sum(y, -py)
    a, ea = _two_square(dx)
    b, eb = _two_square(dy)
    c, ec = _two_square(r)
    s, es = _two_sum(a, b)
    s, es2 = _two_sum(s, -c)
    return s + (((es + es2) + (ea + eb - ec)) + 2.0 * (dx * ex + dy * ey))



def circles(px: float, py: float, p: float, qx: float, qy: float, q: float) -> Fun:
    """R = (x, y) with |R − P| = p and |R − Q| = q: residuals (|R − P|² − p²)/(2p) and
    (|R − Q|² − q²)/(2q) (lengths, ≈ |R − P| − p near the root)."""
    ip, iq = 1.0 / p, 1.0 / q
    hp, hq = 0.5 * p, 0.5 * q

    def fun(x):
        ux, uy = x[0] - px, x[1] - py
        vx, vy = x[0] - qx, x[1] - qy
        return (((ux * ux + uy * uy) * 0.5 * ip - hp, (vx * vx + vy * vy) * 0.5 * iq - hq),
                ((ux * ip, uy * ip), (vx * iq, vy * iq)))

    return fun


def circles_careful(px: float, py: float, p: float, qx: float, qy: float, q: float) -> Fun:
    """circles with the residuals carried in double-double (see square_gap)."""
    ip, iq = 1.0 / p, 1.0 / q

    def fun(x):
        return ((square_gap(x[0], x[1], px, py, p) * 0.5 * ip,
                 square_gap(x[0], x[1], qx, qy, q) * 0.5 * iq),
                (((x[0] - px) * ip, (x[1] - py) * ip), ((x[0] - qx) * iq, (x[1] - qy) * iq)))

    return fun


def two_circles(P: Point, Q: Point, p, q, branch: int, size: float,
                tol_f: float) -> Point:
    """Per row: R with |R − P| = p, |R − Q| = q and branch·cross(R − Q, P − Q) > 0; NaN where no
    such point is found. p and q are lengths, or per-row arrays where a side is a linear
    actuator. (At a limit position the two branches meet: a root whose side is below TANGENT of
    the lengths is on both.)"""
    n = len(P[0])
    pxl, pyl, qxl, qyl = P[0].tolist(), P[1].tolist(), Q[0].tolist(), Q[1].tolist()
    pl = np.broadcast_to(np.asarray(p, dtype=float), (n,)).tolist()
    ql = np.broadcast_to(np.asarray(q, dtype=float), (n,)).tolist()
    slack = RES_TOL * size

    def system(i):
        if not (finite(pxl[i], pyl[i], qxl[i], qyl[i], pl[i], ql[i])
                and pl[i] > 0.0 and ql[i] > 0.0):
            return None
        return circles(pxl[i], pyl[i], pl[i], qxl[i], qyl[i], ql[i])

    def careful(i):
        return circles_careful(pxl[i], pyl[i], pl[i], qxl[i], qyl[i], ql[i])

    def side(i, x):
        qx, qy = qxl[i], qyl[i]
        return ((x[0] - qx) * (pyl[i] - qy) - (x[1] - qy) * (pxl[i] - qx),
                math.hypot(x[0] - qx, x[1] - qy) * math.hypot(pxl[i] - qx, pyl[i] - qy))

    def on_branch(i, x):
        cross, scale = side(i, x)
        return branch * cross > -TANGENT * scale

    def near_double(i, x):   # R, P, Q nearly in line: the Jacobian is nearly singular
        ux, uy, vx, vy = x[0] - pxl[i], x[1] - pyl[i], x[0] - qxl[i], x[1] - qyl[i]
        return abs(ux * vy - uy * vx) <= NEAR_DOUBLE * math.hypot(ux, uy) * math.hypot(vx, vy)

    def starts(i, k):
        qx, qy, px, py, p_i, q_i = qxl[i], qyl[i], pxl[i], pyl[i], pl[i], ql[i]
        ring = [(qx + q_i * math.cos(a), qy + q_i * math.sin(a)) for a in directions(k)]
        if k > STARTS:  # dense: also around P, and half-way rings
            ring += [(px + p_i * math.cos(a), py + p_i * math.sin(a)) for a in directions(k)]
            ring += [(qx + 0.5 * q_i * math.cos(a), qy + 0.5 * q_i * math.sin(a))
                     for a in directions(k)]
        # the guesses on the requested side first
        first = [g for g in ring if branch * side(i, g)[0] > 0.0]
        return first + [g for g in ring if not branch * side(i, g)[0] > 0.0]

    def closes(i):
        d = math.hypot(pxl[i] - qxl[i], pyl[i] - qyl[i])
        return abs(pl[i] - ql[i]) - slack <= d <= pl[i] + ql[i] + slack

    sols = sweep(n, system, starts, on_branch, (size, size), (), tol_f, closes, careful,
                 near_double)
    return solved_column(sols, 0), solved_column(sols, 1)


def triangle_apex(base: float, left: float, right: float) -> tuple[float, float]:
    """C = (x, y), y ≥ 0, with |AC| = left and |BC| = right, A = (0, 0), B = (base, 0): found by
    Newton (the residuals carried carefully, so that a flat triangle is found too); (NaN, NaN)
    if there is no such triangle."""
    if not (finite(base, left, right) and base > 0.0 and left > 0.0 and right > 0.0):
        return math.nan, math.nan
    size = base + left + right
    fun = circles_careful(0.0, 0.0, left, base, 0.0, right)
    guesses = [(0.5 * base, size), (0.0, left), (base, right)]
    guesses += [(left * math.cos(a), left * math.sin(a)) for a in directions(DENSE_STARTS)]
    for x0 in guesses:
        x = newton(fun, x0, (size, size), RES_TOL * size)
        if x is not None:
            if abs(x[1]) <= NEAR_DOUBLE * size:
                x = polish(fun, x, (size, size), RES_TOL * size)
            return x[0], abs(x[1])
    return math.nan, math.nan
