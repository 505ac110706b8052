"""`slider` — RRP, the slider-crank's loop: R on a line, at a given distance from a known point P.

R = T + s·d on its line (through T, along d: fixed at `direction` degrees, or carried by the link
`along` at that angle to it) with |R − P| = l: one residual in s, the branch by the sign of
(R − P)·d. R is then put exactly on the line, so that a horizontal line keeps y = T_y to the
last digit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import partial

import numpy as np

from ..expressions import scalar
from ..geometry import HALF_PI, Point, cos_sin_deg, near, turned_direction
from ..newton import NEAR_DOUBLE, RES_TOL, STARTS, TANGENT, Fun, finite, solved_column, sweep
from ..positions import Positions
from ..rates import Rates
from ..step_type import Guide, Pair, Sliding, StepType, Topology
from ..taylor import Taylor, implicit, t_cos, t_sin


def _slider_system(h: float, w: float, length: float) -> Fun:
    """R = T + s·d, P = T + h·d + w·d⊥: residual (|R − P|² − l²)/(2l) in the unknown s, written
    ((s − h)² + (w − l)(w + l))/(2l) so that it keeps its digits next to a double root."""
    il = 1.0 / length
    c = (w - length) * (w + length)

    def fun(x):
        u = x[0] - h
        return ((u * u + c) * 0.5 * il,), ((u * il,),)

    return fun


def _slider_positions(P: Point, T: Point, dx: float, dy: float, length: float, branch: int,
                      size: float, tol_f: float) -> np.ndarray:
    """Per row: the position s of R = T + s·d with |R − P| = length and
    branch·((R − P)·d) > 0; NaN where no such point is found."""
    n = len(P[0])
    if not (finite(length) and length > 0.0):
        return np.full(n, math.nan)
    vx, vy = P[0] - T[0], P[1] - T[1]
    hl = (vx * dx + vy * dy).tolist()   # P's foot on the line, along d
    wl = (dx * vy - dy * vx).tolist()   # P's distance from the line, to the left of d
    slack = RES_TOL * size

    def system(i):
        return _slider_system(hl[i], wl[i], length) if finite(hl[i], wl[i]) else None

    def starts(i, k):
        h = hl[i]
        if k <= STARTS:
            return [(h + branch * length * c,) for c in (1.0, 0.5, 2.0, 0.1)]
        return [(h + branch * length * c,) for c in np.linspace(0.02, 4.0, k).tolist()]

    sols = sweep(n, system, starts,
                 lambda i, x: branch * (x[0] - hl[i]) > -TANGENT * length,
                 (size,), (), tol_f, lambda i: abs(wl[i]) <= length + slack, system,
                 lambda i, x: abs(x[0] - hl[i]) <= NEAR_DOUBLE * length)
    return solved_column(sols, 0)


def place(solver: Positions, step: Mapping) -> None:
    """s on every row by Newton, R put exactly on its line, the angle R→P measured."""
    P, T = solver.known(step, "p"), solver.known(step, "through")
    length = solver.num(step, "length")
    direction = solver.num(step, "direction", 0.0)
    b = solver.branch(step)
    columns = {}
    if "along" in step:     # a line carried by the link U→V, at `direction` from it
        u, v = solver.pair(step, "along")
        line = solver.angle_of(u, v)[0] + math.radians(direction)
        dx, dy = np.cos(line), np.sin(line)
        columns["line"] = line
        moving = solver.moves(step["p"], step["through"], u, v)
    else:
        line = math.radians(direction)
        dx, dy = cos_sin_deg(direction)
        moving = solver.moves(step["p"], step["through"])
    s = _slider_positions(P, T, dx, dy, length, b, solver.size, solver.tol_f)
    # R exactly on its line, R = T + s·d: a horizontal line keeps y = T_y to the last digit
    x, y = T[0] + s * dx, T[1] + s * dy
    # angle(R→P), in the window of the doc's branches: R ahead of P's foot (b = 1) or behind
    theta = near(np.arctan2(P[1] - y, P[0] - x), line + (1 + b) * HALF_PI)
    keys = solver.point_columns(step, {**columns, "theta": theta, "s": s, "x": x, "y": y},
                                moving)
    solver.new_point(step, keys, moving, loop=True)
    solver.add_link(step["point"], step["p"], theta, keys["theta"], length)


def rates(motion: Rates, step: Mapping) -> None:
    """s's rates by implicit differentiation of |R − P| = l, the line turning with `along`."""
    n, p, t = step["point"], step["p"], step["through"]
    length = motion.s.num(step, "length")
    direction = math.radians(motion.s.num(step, "direction", 0.0))
    along = motion.s.pair(step, "along") if "along" in step else None
    if along:
        motion.put_rates("_".join(along), motion.angle(*along), True)

    fixed = cos_sin_deg(motion.s.num(step, "direction", 0.0))   # exact at quarter turns

    def line(pts):
        """The line's direction (cos, sin): turning with the link `along`, else fixed."""
        if along:
            lam = motion.angle(*along, pts=pts) + direction
            return t_cos(lam), t_sin(lam)
        return Taylor(fixed[0]), Taylor(fixed[1])

    s0 = np.asarray(motion.s.out[motion.key(step, "s", f"s_{n}")], dtype=float)

    def residuals(z, pts):
        (dx, dy), (tx, ty), (px, py) = line(pts), pts[t], pts[p]
        rx, ry = tx + z[0] * dx - px, ty + z[0] * dy - py
        return [rx * rx + ry * ry - length * length]

    (pos,), _, _ = implicit(residuals, [s0], motion.points, motion.still())
    (dx, dy), (tx, ty) = line(motion.points), motion.points[t]
    motion.place(n, tx + pos * dx, ty + pos * dy)
    (px, py), (rx, ry) = motion.points[p], motion.points[n]
    motion.out[f"det_{n}"] = dx.a * (px.a - rx.a) + dy.a * (py.a - ry.a)   # d·(P − R)
    with np.errstate(divide="ignore", invalid="ignore"):
        motion.note_sine(np.abs(motion.out[f"det_{n}"]) / np.hypot(px.a - rx.a, py.a - ry.a))
    motion.put_rates(motion.key(step, "s", f"s_{n}"), pos, False)
    motion.put_rates(motion.key(step, "theta", f"theta_{n}"), motion.angle(n, p), True)
    if along:
        motion.put_rates(motion.key(step, "line", f"line_{n}"),
                         motion.angle(*along) + direction, True)


def _slider_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slider's line direction: fixed at `direction` degrees, or along its link U→V."""
    direction = scalar(step.get("direction", 0.0), params)
    if "along" not in step:
        d = cos_sin_deg(direction)
        return lambda solved: d
    return turned_direction(*step["along"], direction)


def sliding(step: Mapping) -> Sliding:
    """The guide through T over R's travel, and the block at R."""
    n, line = step.get("point"), partial(_slider_line, step)
    return Sliding((Guide(f"{n} guide", step["through"], n, line),), n, line)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The rod from p to the point, and the block at the point on its line: fixed, or on
    the link of `along` (which also holds `through`)."""
    point = str(step["point"])
    if "along" in step:
        u, v = (str(p) for p in step["along"])
        pair = Pair(point, ("along", u, v, step.get("direction", 0.0)), guide=(u, v),
                    beside=frozenset({u, v, str(step["through"])}))
    else:
        pair = Pair(point, ("fixed", step.get("direction", 0.0)))
    return Topology(links=((str(step["p"]), point),), pair=pair)


STEP = StepType(place=place, rates=rates, sliding=sliding, topology=topology)
