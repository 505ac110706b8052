"""`crank` — the input link: its pin turns about a known pivot with the input angle.

The pin is a function of the input angle alone: evaluated directly, no constraint to solve.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..positions import Positions
from ..rates import Rates
from ..step_type import StepType, Topology
from ..taylor import t_cos, t_sin


def place(solver: Positions, step: Mapping) -> None:
    """The pin on every row, from the input angle and the phase; the crank a rigid link."""
    if not solver.angle_input:
        raise ValueError(f"{solver.where}: a crank needs an angle input")
    P = solver.known(step, "pivot")
    length = solver.num(step, "length")
    t = solver.th + math.radians(solver.num(step, "phase", 0.0))
    keys = solver.point_columns(step, {"x": P[0] + length * np.cos(t),
                                       "y": P[1] + length * np.sin(t)}, True)
    solver.new_point(step, keys, True, loop=False)
    solver.add_link(step["pivot"], step["point"], t, None, length)


def rates(motion: Rates, step: Mapping) -> None:
    """The pin in motion: the input's speed and acceleration carried through cos and sin."""
    ox, oy = motion.points[step["pivot"]]
    r = motion.s.num(step, "length")
    t = motion.input + math.radians(motion.s.num(step, "phase", 0.0))
    motion.place(step["point"], ox + r * t_cos(t), oy + r * t_sin(t))


def topology(step: Mapping, length_input: str | None) -> Topology:
    """The crank is a link from its pivot to its point, turned by the input."""
    return Topology(links=((str(step["pivot"]), str(step["point"])),), crank=True)


STEP = StepType(place=place, rates=rates, topology=topology)
