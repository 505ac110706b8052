"""`slot` — a slot carried by a link meets a fixed line (the pump's plunger, the shaper's ram).

The slot runs through E along angle(A→B) + slot_angle, the fixed line through T along
`direction`; P is on both: two linear residuals in the positions along them, so Newton lands on
the root in one step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import partial

import numpy as np

from ..expressions import scalar
from ..geometry import Point, cos_sin_deg, turned_direction
from ..newton import finite, linear_solve
from ..positions import Positions
from ..rates import Rates
from ..step_type import Guide, Pair, Sliding, StepType, Topology
from ..taylor import implicit, t_cos, t_sin


def _slot_crossing(E: Point, T: Point, ux, uy, dx: float, dy: float) -> Point:
    """Per row: (a, b) with E + a·u = T + b·d, the crossing of a slot (through E along u) and a
    fixed line (through T along d). The constraints are linear, so Newton from (0, 0) lands on
    the root in one step; a second step refines it. NaN where the lines are parallel."""
    ex, ey, tx, ty = E[0].tolist(), E[1].tolist(), T[0].tolist(), T[1].tolist()
    uxl, uyl = np.broadcast_to(ux, E[0].shape).tolist(), np.broadcast_to(uy, E[0].shape).tolist()
    a_out, b_out = [math.nan] * len(ex), [math.nan] * len(ex)
    for i in range(len(ex)):
        if not finite(ex[i], ey[i], tx[i], ty[i], uxl[i], uyl[i]):
            continue
        jac = ((uxl[i], -dx), (uyl[i], -dy))
        x = [0.0, 0.0]
        for _ in range(2):
            f = (ex[i] + x[0] * uxl[i] - tx[i] - x[1] * dx,
                 ey[i] + x[0] * uyl[i] - ty[i] - x[1] * dy)
            step = linear_solve(jac, f)
            if step is None:
                break
            x = [x[0] - step[0], x[1] - step[1]]
        else:
            if finite(*x):
                a_out[i], b_out[i] = x
    return np.array(a_out), np.array(b_out)


def place(solver: Positions, step: Mapping) -> None:
    """The crossing on every row; P exactly on the fixed line."""
    E = solver.known(step, "slot_through")
    a, b = solver.pair(step, "slot_frame")
    A, B = solver.points[a], solver.points[b]
    T = solver.known(step, "through")
    # the slot: through E along angle(A→B) + slot_angle; the line: through T along d
    c, s = cos_sin_deg(solver.num(step, "slot_angle", 0.0))
    fx, fy = B[0] - A[0], B[1] - A[1]
    f = np.hypot(fx, fy)
    fx, fy = fx / f, fy / f
    ux, uy = fx * c - fy * s, fx * s + fy * c
    dx, dy = cos_sin_deg(solver.num(step, "direction", 0.0))
    s_slot, pos = _slot_crossing(E, T, ux, uy, dx, dy)
    moving = solver.moves(step["slot_through"], a, b, step["through"])
    keys = solver.point_columns(step, {"s_slot": s_slot, "s": pos,
                                       "x": T[0] + pos * dx,     # exactly on the fixed line
                                       "y": T[1] + pos * dy}, moving)
    solver.new_point(step, keys, moving, loop=True)


def rates(motion: Rates, step: Mapping) -> None:
    """The positions' rates by implicit differentiation of the crossing."""
    n, e, t = step["point"], step["slot_through"], step["through"]
    a, b = motion.s.pair(step, "slot_frame")
    motion.put_rates(f"{a}_{b}", motion.angle(a, b), True)
    slot_angle = math.radians(motion.s.num(step, "slot_angle", 0.0))
    dc, ds = cos_sin_deg(motion.s.num(step, "direction", 0.0))    # exact at quarter turns
    z0 = [np.asarray(motion.s.out[motion.key(step, c, f"{c}_{n}")], dtype=float)
          for c in ("s_slot", "s")]

    def residuals(z, pts):
        u = motion.angle(a, b, pts=pts) + slot_angle
        (ex, ey), (tx, ty) = pts[e], pts[t]
        return [ex + z[0] * t_cos(u) - tx - z[1] * dc,
                ey + z[0] * t_sin(u) - ty - z[1] * ds]

    (s_slot, pos), dead, sine = implicit(residuals, z0, motion.points, motion.still())
    motion.dead |= dead & np.isfinite(z0[0]) & np.isfinite(z0[1])
    motion.note_sine(sine)
    tx, ty = motion.points[t]
    motion.place(n, tx + pos * dc, ty + pos * ds)
    u = motion.angle(a, b).a + slot_angle
    motion.out[f"det_{n}"] = np.cos(u) * ds - np.sin(u) * dc            # û × d
    motion.put_rates(motion.key(step, "s_slot", f"s_slot_{n}"), s_slot, False)
    motion.put_rates(motion.key(step, "s", f"s_{n}"), pos, False)


def _fixed_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    d = cos_sin_deg(scalar(step.get("direction", 0.0), params))
    return lambda solved: d


def _slot_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slot's direction: angle(A→B) of its frame plus slot_angle."""
    return turned_direction(*step["slot_frame"], scalar(step.get("slot_angle", 0.0), params))


def sliding(step: Mapping) -> Sliding:
    """The fixed line through T and the slot through E, each over P's travel, and the block at
    P along the fixed line."""
    n, fixed = step.get("point"), partial(_fixed_line, step)
    return Sliding((Guide(f"{n} guide", step["through"], n, fixed),
                    Guide(f"{n} slot", step["slot_through"], n, partial(_slot_line, step))),
                   n, fixed)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The block at the point on its fixed line, its pin pushed across the slot of the link
    of `slot_frame` (which also holds `slot_through`): it makes no link of its own."""
    point = str(step["point"])
    a, b = (str(p) for p in step["slot_frame"])
    return Topology(pair=Pair(point, ("fixed", step.get("direction", 0.0)),
                              beside=frozenset({str(step["slot_through"]), a, b}),
                              slotted=(a, b), slot=("along", a, b, step.get("slot_angle", 0.0))))


STEP = StepType(place=place, rates=rates, sliding=sliding, topology=topology)
