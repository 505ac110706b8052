"""`vector` — rectangular to polar: the vector between two known points, measured."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..geometry import direction
from ..positions import Positions
from ..rates import Rates
from ..step_type import Pair, StepType, Topology
from ..taylor import t_atan2, t_sqrt


def place(solver: Positions, step: Mapping) -> None:
    """The vector's components, length and angle, measured."""
    key = step.get("key")
    if not isinstance(key, str) or not key:
        raise ValueError(f"{solver.where}: missing key")
    F, T = solver.known(step, "from"), solver.known(step, "to")
    moving = solver.moves(step["from"], step["to"])
    xs, ys = T[0] - F[0], T[1] - F[1]
    phi = direction(xs, ys)
    for col, value in (("xs", xs), ("ys", ys), ("s", np.hypot(xs, ys)), ("phi", phi)):
        k = solver.column(step, col, f"{col}_{key}", value, moving)
    solver.add_link(step["from"], step["to"], phi, k)


def rates(motion: Rates, step: Mapping) -> None:
    """The rates of its length and angle."""
    key = step["key"]
    (ax, ay), (bx, by) = motion.points[step["from"]], motion.points[step["to"]]
    dx, dy = bx - ax, by - ay
    motion.put_rates(motion.key(step, "s", f"s_{key}"), t_sqrt(dx * dx + dy * dy), False)
    motion.put_rates(motion.key(step, "phi", f"phi_{key}"), t_atan2(dy, dx), True)


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The direction measured from U to V; where it is a slotted link (step_type.slotted), the
    link turning about U, and the block at V sliding in it along U→V (its guide)."""
    u, v = str(step.get("from")), str(step.get("to"))
    return Topology(links=((u,),), frame=(u, v), turns=(u, v),
                    pair=Pair(v, ("along", u, v, 0.0), guide=(u, v), beside=frozenset({u})))


STEP = StepType(place=place, rates=rates, topology=topology)
