"""`slide` — RPR, the inverted slider-crank's loop: a block at P slides on a line fixed to a link
turning about a known pivot Q.

The unknown is the link angle θ with (P − Q)·e^{iθ} = offset (the slide line, perpendicular to
the link at the offset, passes through P), the branch by the sign of cross(e^{iθ}, P − Q).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import partial

import numpy as np

from ..geometry import HALF_PI, Point, direction, interior, near
from ..newton import NEAR_DOUBLE, RES_TOL, TANGENT, Fun, directions, finite, solved_column, sweep
from ..positions import Positions
from ..rates import Rates
from ..step_type import Guide, Pair, Sliding, StepType, Topology
from ..taylor import implicit, t_cos, t_sin, t_sqrt


def _slide_system(vx: float, vy: float, offset: float) -> Fun:
    """Link angle θ with (P − Q)·e^{iθ} = offset, V = P − Q (the slide line, at the offset from
    the pivot and perpendicular to the link, passes through P). The residual V·e^{iθ} − offset
    is written in the polar form of the dot product about the direction ψ0 where it is largest
    in the offset's sign, σ(|V| − |offset|) − 2σ|V|·sin²((θ − ψ0)/2), so that it keeps its
    digits next to a double root (|V| = |offset|)."""
    r = math.hypot(vx, vy)
    sig = 1.0 if offset >= 0.0 else -1.0
    psi0 = math.atan2(vy, vx) if sig > 0.0 else math.atan2(-vy, -vx)
    gap = sig * (r - abs(offset))

    def fun(x):
        d = x[0] - psi0
        h = math.sin(0.5 * d)
        return (gap - 2.0 * sig * r * h * h,), ((-sig * r * math.sin(d),),)

    return fun


def _slide_angles(P: Point, Q: Point, offset: float, branch: int, size: float,
                  tol_f: float) -> np.ndarray:
    """Per row: the link angle θ with (P − Q)·e^{iθ} = offset and
    branch·cross(e^{iθ}, P − Q) > 0; NaN where no such angle is found."""
    n = len(P[0])
    if not math.isfinite(offset):
        return np.full(n, math.nan)
    vxl, vyl = (P[0] - Q[0]).tolist(), (P[1] - Q[1]).tolist()
    slack = RES_TOL * size

    def system(i):
        return _slide_system(vxl[i], vyl[i], offset) if finite(vxl[i], vyl[i]) else None

    def on_branch(i, x):
        cross = math.cos(x[0]) * vyl[i] - math.sin(x[0]) * vxl[i]
        return branch * cross > -TANGENT * math.hypot(vxl[i], vyl[i])

    def near_double(i, x):   # the link nearly along P − Q
        cross = math.cos(x[0]) * vyl[i] - math.sin(x[0]) * vxl[i]
        return abs(cross) <= NEAR_DOUBLE * math.hypot(vxl[i], vyl[i])

    def starts(i, k):
        return [(a,) for a in directions(k)]

    return solved_column(sweep(n, system, starts, on_branch, (1.0,), (0,), tol_f,
                               lambda i: math.hypot(vxl[i], vyl[i]) >= abs(offset) - slack,
                               system, near_double), 0)


def place(solver: Positions, step: Mapping) -> None:
    """θ on every row by Newton; the block's pivot B, the travel and the slide line measured."""
    P, Q = solver.known(step, "p"), solver.known(step, "pivot")
    offset = solver.num(step, "offset")
    b = solver.branch(step)
    xs, ys = P[0] - Q[0], P[1] - Q[1]
    phi = direction(xs, ys)
    theta = near(_slide_angles(P, Q, offset, b, solver.size, solver.tol_f), phi - b * HALF_PI)
    ux, uy = np.cos(theta), np.sin(theta)
    x, y = Q[0] + offset * ux, Q[1] + offset * uy
    tx, ty = P[0] - x, P[1] - y
    travel = np.hypot(tx, ty)
    # The slide line is fixed to the link at right angles, on P's side (the branch): its
    # direction is θ + b·π/2, which is angle(B→P) wherever the travel is not zero, and stays
    # defined at a limit position where B and P meet (atan2 of a rounding-sized vector).
    slide = np.where(np.isnan(travel), np.nan, theta + b * HALF_PI)
    moving = solver.moves(step["p"], step["pivot"])
    keys = solver.point_columns(step, {
        "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": phi,
        "psi": interior(ux, uy, xs, ys), "travel": travel, "theta": theta,
        "theta_slide": slide, "x": x, "y": y}, moving)
    solver.new_point(step, keys, moving, loop=True)
    solver.add_link(step["point"], step["p"], slide, keys["theta_slide"])


def rates(motion: Rates, step: Mapping) -> None:
    """θ's rates by implicit differentiation of (P − Q)·e^{iθ} = offset."""
    n, p, q = step["point"], step["p"], step["pivot"]
    offset = motion.s.num(step, "offset")
    th0 = np.asarray(motion.s.out[motion.key(step, "theta", f"theta_{n}")], dtype=float)

    def residuals(z, pts):
        (px, py), (qx, qy) = pts[p], pts[q]
        return [(px - qx) * t_cos(z[0]) + (py - qy) * t_sin(z[0]) - offset]

    (theta,), _, _ = implicit(residuals, [th0], motion.points, motion.still())
    qx, qy = motion.points[q]
    motion.place(n, qx + offset * t_cos(theta), qy + offset * t_sin(theta))
    (px, py) = motion.points[p]
    motion.out[f"det_{n}"] = (-(px.a - qx.a) * np.sin(theta.a)          # (P − Q)·(i e)
                              + (py.a - qy.a) * np.cos(theta.a))
    motion.put_rates(motion.key(step, "theta", f"theta_{n}"), theta, True)
    motion.put_rates(motion.key(step, "theta_slide", f"theta_slide_{n}"), theta, True)
    (px, py), (nx, ny) = motion.points[p], motion.points[n]
    motion.put_rates(motion.key(step, "travel", f"travel_{n}"),
                     t_sqrt((px - nx) * (px - nx) + (py - ny) * (py - ny)), False)


def _slide_key(step: Mapping) -> str:
    """A slide's line: its `theta_slide` column, under the key the step's `columns` gives."""
    spec = (step.get("columns") or {}).get("theta_slide")
    key = str(spec.get("key") or "") if isinstance(spec, Mapping) else ""
    return key or f"theta_slide_{step['point']}"


def _slide_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slide's line: the direction `place` solved for it (θ + b·π/2, θ the link's angle),
    which stays defined where B and P meet or the offset is zero."""
    key = _slide_key(step)
    return lambda solved: (np.cos(solved[key]), np.sin(solved[key]))


def sliding(step: Mapping) -> Sliding:
    """The guide through B (the point on the link) over P's travel, and the block at P."""
    n, line = step.get("point"), partial(_slide_line, step)
    return Sliding((Guide(f"{n} guide", n, step["p"], line),), step["p"], line)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The link from the pivot to the point, and the block at p sliding on it along the
    slide's line, which turns with the link (its column stays defined where the link's two
    points meet, a slide of offset zero); the line's direction, point→p, is the link's frame
    (at offset zero the one that places a point on it)."""
    pivot, point, key = str(step["pivot"]), str(step["point"]), _slide_key(step)
    return Topology(links=((pivot, point),), frame=(point, str(step["p"])),
                    pair=Pair(str(step["p"]), ("column", key), guide=(pivot, point),
                              beside=frozenset({pivot, point}), spin=key))


STEP = StepType(place=place, rates=rates, sliding=sliding, topology=topology)
