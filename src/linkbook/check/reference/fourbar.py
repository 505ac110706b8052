"""The four-bar loops of a description: Grashof's class and the input's limit angles.

A four-bar loop is a dyad with one end a ground point and the other the pin of a crank turning
about a ground point; its lengths are read from the description, not from any solution.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from .expressions import scalar
from .positions import pivots, steps_of
from .steps import STEP_TYPES


def _fourbar_parts(description: Mapping, params: Mapping[str, float]) -> list[tuple]:
    """Per four-bar loop on the ground, in step order: (crank pivot (x, y), output pivot (x, y),
    crank length, phase in degrees, coupler, output link).  A loop is a dyad with one end a
    ground point and the other the pin of a crank turning about a ground point."""
    ground = pivots(description, params)
    cranks, loops = {}, []
    for step in steps_of(description, STEP_TYPES):
        kind = step["type"]
        if kind == "crank" and step.get("pivot") in ground and step.get("point"):
            cranks.setdefault(step["point"], step)
        elif kind == "dyad":
            for pin, fixed, coupler, rocker in (("p", "q", "p_length", "q_length"),
                                                ("q", "p", "q_length", "p_length")):
                if step.get(fixed) in ground and step.get(pin) in cranks:
                    crank = cranks[step[pin]]
                    loops.append((ground[crank["pivot"]], ground[step[fixed]],
                                  scalar(crank["length"], params),
                                  scalar(crank.get("phase", 0), params),
                                  scalar(step[coupler], params), scalar(step[rocker], params)))
                    break
    return loops


def fourbar_loops(description: Mapping, params: Mapping[str, float]
                  ) -> list[tuple[float, float, float, float]]:
    """(ground, crank, coupler, output link) lengths of every four-bar loop on the ground."""
    return [(math.hypot(qx - ax, qy - ay), crank, coupler, rocker)
            for (ax, ay), (qx, qy), crank, _, coupler, rocker
            in _fourbar_parts(description, params)]


def grashof_class(ground: float, crank: float, coupler: float, rocker: float) -> str:
    """Grashof's rule, s + l against p + q, and which link is the shortest."""
    links = {"ground": ground, "crank": crank, "coupler": coupler, "rocker": rocker}
    s, l = min(links.values()), max(links.values())
    pq = sum(links.values()) - s - l
    if s + l > pq * (1 + 1e-12):
        return "non-Grashof: triple rocker"
    if s + l >= pq * (1 - 1e-12):
        return "change point"
    shortest = min(links, key=links.get)
    return {"ground": "Grashof: double crank", "crank": "Grashof: crank-rocker",
            "coupler": "Grashof: double rocker", "rocker": "Grashof: rocker-crank"}[shortest]


def limit_angles(description: Mapping, params: Mapping[str, float], length: float,
                 loop: int = 0) -> list[float]:
    """Input angles (degrees, [0, 360), ascending) where four-bar loop number `loop`'s output
    pivot Q is exactly `length` from the crank pin A(θ) (the crank's phase included): found by
    sampling |Q − A(θ)| − length and bisecting each sign change. [] if there is no such loop."""
    parts = _fourbar_parts(description, params)
    if loop >= len(parts):
        return []
    (ax, ay), (qx, qy), r, phase, _, _ = parts[loop]

    def f(deg: float) -> float:
        t = math.radians(deg + phase)
        return math.hypot(qx - ax - r * math.cos(t), qy - ay - r * math.sin(t)) - length

    roots = []
    grid = [i * 0.25 for i in range(1441)]
    values = [f(x) for x in grid]
    for x0, x1, f0, f1 in zip(grid, grid[1:], values, values[1:]):
        if f0 == 0.0:
            roots.append(x0)
        elif f0 * f1 < 0:
            for _ in range(200):
                xm = 0.5 * (x0 + x1)
                fm = f(xm)
                if xm in (x0, x1):
                    break
                x0, f0, x1 = (xm, fm, x1) if f0 * fm > 0 else (x0, f0, xm)
            roots.append(0.5 * (x0 + x1))
    return sorted({round(x % 360.0, 12) for x in roots})
