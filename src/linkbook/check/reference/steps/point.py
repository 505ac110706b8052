"""`point` — a point carried by a known link (its frame A→B).

By `distances` [|AC|, |BC|]: the two circles again (constraints.two_circles), or, when the frame
is a rigid link of known length, the triangle solved once in the frame's own coordinates
(constraints.triangle_apex: then its angle γ is a constant); by `local` [u, v] or by
`distance`/`angle`: placed directly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..constraints import triangle_apex, two_circles
from ..expressions import scalar
from ..geometry import interior
from ..positions import Positions
from ..rates import Rates
from ..step_type import StepType, Topology
from ..taylor import t_cos, t_sin, t_sqrt


def place(solver: Positions, step: Mapping) -> None:
    """C on every row: by local coordinates, by distances, or by distance and angle."""
    a, b = solver.pair(step, "frame")
    A, B = solver.points[a], solver.points[b]
    name = step.get("point")
    moving = solver.moves(a, b)
    if "local" in step:
        pair = step["local"]
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise ValueError(f"{solver.where}.local must be [u, v]")
        u, v = (scalar(e, solver.params) for e in pair)
        ex, ey = B[0] - A[0], B[1] - A[1]
        ab = np.hypot(ex, ey)
        ex, ey = ex / ab, ey / ab
        keys = solver.point_columns(step, {"x": A[0] + u * ex - v * ey,
                                           "y": A[1] + u * ey + v * ex}, moving)
    elif "distances" in step:
        pair = step["distances"]
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise ValueError(f"{solver.where}.distances must be [|AC|, |BC|]")
        da, db = (scalar(e, solver.params) for e in pair)
        side = solver.branch(step, "side")
        base = solver.rigid.get(frozenset((a, b)))
        if base is None and solver.coords_fixed(a) and solver.coords_fixed(b):
            base = float(math.hypot(B[0][0] - A[0][0], B[1][0] - A[1][0])) if solver.n else None
        if base is not None:
            # A rigid frame of known length: the triangle is solved once, in the frame's own
            # coordinates (C = A + cx·ê + side·cy·ê⊥), and γ is a constant.
            cx, cy = triangle_apex(base, da, db)
            gamma = math.atan2(cy, cx)
            ex, ey = B[0] - A[0], B[1] - A[1]
            ab = np.hypot(ex, ey)
            ex, ey = ex / ab, ey / ab
            x = A[0] + cx * ex - side * cy * ey
            y = A[1] + cx * ey + side * cy * ex
        else:
            # side·cross(B − A, C − A) > 0 is the dyad over Q = A, P = B on branch −side
            x, y = two_circles(B, A, db, da, -side, solver.size, solver.tol_f)
            gamma = interior(B[0] - A[0], B[1] - A[1], x - A[0], y - A[1])
        keys = solver.point_columns(step, {"gamma": gamma, "x": x, "y": y}, moving)
    elif "distance" in step:
        d = solver.num(step, "distance")
        base, fixed = solver.angle_of(a, b)
        theta = base + math.radians(solver.num(step, "angle", 0.0))
        x, y = A[0] + d * np.cos(theta), A[1] + d * np.sin(theta)
        if fixed and solver.n and np.all(theta == theta[0]):
            theta = float(theta[0])            # one named cell in the workbook
        keys = solver.point_columns(step, {"theta": theta, "x": x, "y": y}, moving,
                                    ("theta",))
        solver.add_link(a, name, np.broadcast_to(theta, (solver.n,)), keys["theta"], d)
    else:
        raise ValueError(f"{solver.where}: needs local, distances or distance")
    solver.new_point(step, keys, moving, loop=False)


def rates(motion: Rates, step: Mapping) -> None:
    """C in motion: placed directly, or by the two circles differentiated implicitly."""
    n = step["point"]
    a, b = motion.s.pair(step, "frame")
    (ax, ay), (bx, by) = motion.points[a], motion.points[b]
    motion.put_rates(f"{a}_{b}", motion.angle(a, b), True)     # the frame's own ω and α
    if "local" in step:
        u, v = (scalar(e, motion.s.params) for e in step["local"])
        ab = t_sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
        ex, ey = (bx - ax) / ab, (by - ay) / ab
        motion.place(n, ax + u * ex - v * ey, ay + u * ey + v * ex)
    elif "distances" in step:
        da, db = (scalar(e, motion.s.params) for e in step["distances"])
        motion.place(n, *motion.circles(n, a, da, b, db))
        if frozenset((a, b)) not in motion.s.rigid:     # the frame stretches: a loop of its own
            motion.determinant(n, b, a)
    else:
        d = motion.s.num(step, "distance")
        theta = motion.angle(a, b) + math.radians(motion.s.num(step, "angle", 0.0))
        motion.place(n, ax + d * t_cos(theta), ay + d * t_sin(theta))
        motion.put_rates(motion.key(step, "theta", f"theta_{n}"), theta, True)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The point is carried by the link of its frame (by distances, a frame that is no link
    stretches: two links, as a dyad's)."""
    a, b = (str(p) for p in step["frame"])
    return Topology(carried=(str(step["point"]), a, b, "distances" in step))


STEP = StepType(place=place, rates=rates, topology=topology)
