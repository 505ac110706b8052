"""`distance` — a length to watch: the distance between two known points, measured."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..positions import Positions
from ..rates import Rates
from ..step_type import StepType
from ..taylor import t_sqrt


def place(solver: Positions, step: Mapping) -> None:
    """The distance, measured."""
    key = step.get("key")
    if not isinstance(key, str) or not key:
        raise ValueError(f"{solver.where}: missing key")
    a, b = solver.pair(step, "between")
    (x1, y1), (x2, y2) = solver.points[a], solver.points[b]
    solver.column(step, "d", key, np.hypot(x2 - x1, y2 - y1), solver.moves(a, b))


def rates(motion: Rates, step: Mapping) -> None:
    """Its rate."""
    a, b = motion.s.pair(step, "between")
    (ax, ay), (bx, by) = motion.points[a], motion.points[b]
    dx, dy = bx - ax, by - ay
    motion.put_rates(motion.key(step, "d", step["key"]), t_sqrt(dx * dx + dy * dy), False)


# a measurement, not a part of the mechanism: nothing of it counts towards its size
STEP = StepType(place=place, rates=rates, length_fields=())
