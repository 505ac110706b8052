"""`dyad` — RRR, Raven's triangle: R at given distances from two known points P and Q.

R = (x, y) with |R − P| = p and |R − Q| = q (two circle residuals, constraints.two_circles), the
branch fixed by the sign of cross(R − Q, P − Q). A side may be the swept length of a linear
actuator. Its angles are measured on the solved points, each in the window of the doc's
definition, so that the smallest and largest value of an angle column mean the same as in the
workbook.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..constraints import two_circles
from ..geometry import HALF_PI, interior, near
from ..positions import Positions
from ..rates import Rates
from ..step_type import StepType, Topology


def place(solver: Positions, step: Mapping) -> None:
    """R on every row by Newton, its angles measured on the solved points; its sides links."""
    P, Q = solver.known(step, "p"), solver.known(step, "q")
    pl, ql = solver.side(step, "p_length"), solver.side(step, "q_length")
    b = solver.branch(step)
    x, y = two_circles(P, Q, pl, ql, b, solver.size, solver.tol_f)
    xs, ys = P[0] - Q[0], P[1] - Q[1]
    phi = np.arctan2(ys, xs)
    # angles measured on the solved points, each in the window of the doc's definition:
    # theta_q = ϕ − b·ψ; theta_p = theta_q − b·μ, or ϕ + π + b·∠QPR where the workbook
    # shows the angle at P in place of μ
    theta_q = near(np.arctan2(y - Q[1], x - Q[0]), phi - b * HALF_PI)
    given = step.get("columns") or {}

    def shown(col: str) -> bool:
        spec = given.get(col, {} if col != "p_interior" else None)
        return isinstance(spec, Mapping) and spec.get("shown", True) or spec is True

    centre = phi + math.pi + b * HALF_PI if not shown("mu") and shown("p_interior") \
        else theta_q - b * HALF_PI
    theta_p = near(np.arctan2(y - P[1], x - P[0]), centre)
    moving = solver.moves(step["p"], step["q"])
    keys = solver.point_columns(step, {
        "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": phi,
        "psi": interior(xs, ys, x - Q[0], y - Q[1]),
        "mu": interior(Q[0] - x, Q[1] - y, P[0] - x, P[1] - y),
        "p_interior": interior(Q[0] - P[0], Q[1] - P[1], x - P[0], y - P[1]),
        "theta_q": theta_q, "theta_p": theta_p, "x": x, "y": y}, moving, ("p_interior",))
    solver.new_point(step, keys, moving, loop=True)
    solver.add_link(step["q"], step["point"], theta_q, keys["theta_q"], ql)
    solver.add_link(step["p"], step["point"], theta_p, keys["theta_p"], pl)


def rates(motion: Rates, step: Mapping) -> None:
    """R's rates by implicit differentiation of the two circles; its angles' rates measured."""
    n, p, q = step["point"], step["p"], step["q"]
    x, y = motion.circles(n, p, motion.length(step, "p_length"), q,
                          motion.length(step, "q_length"))
    motion.place(n, x, y)
    motion.determinant(n, q, p)
    motion.put_rates(motion.key(step, "theta_q", f"theta_q_{n}"), motion.angle(q, n), True)
    motion.put_rates(motion.key(step, "theta_p", f"theta_p_{n}"), motion.angle(p, n), True)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """Two links pinned at the point, from p and from q; the side whose length is a linear
    actuator's input (p's first) is that actuator."""
    point = str(step["point"])
    actuator = next(((str(step[end]), point) for end, side in (("p", "p_length"),
                                                                ("q", "q_length"))
                     if length_input is not None and step.get(side) == length_input), None)
    return Topology(links=tuple((str(step[end]), point) for end in ("p", "q")),
                    actuator=actuator)


STEP = StepType(place=place, rates=rates, topology=topology)
