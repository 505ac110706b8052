"""The drawing's sliders: guides and blocks (docs/mechanisms.md, "Drawings"), measured on solved
points. Which steps slide, and on which lines, each step type says (its `sliding`)."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from .geometry import Point
from .positions import steps_of
from .step_type import Sliding
from .steps import STEP_TYPES

BLOCK = (0.8, 0.4)     # a block's length along its line and its width, in grid squares


def slider_drawing(description: Mapping, params: Mapping[str, float], sweep: Mapping,
                   now: Mapping, square: float) -> dict[str, Point]:
    """The drawn points of every sliding block and the line it slides on, measured on solved
    points: {name: (x, y)} at the positions of `now` (a solve() result), a line's extent taken
    from the block's travel over `sweep` (another). A guide runs along its line over the
    block's smallest to largest position; a block is a
    rectangle centred on the point it is pivoted at, its long side along its line, corners
    counter-clockwise from behind-right ("B block 1" … "B block 4"). Slider R on a line through
    T: "R guide 1", "R guide 2"; slide B (the block at P): the line through B across the link,
    on P's side; slot P: its fixed line ("P guide") and the slot ("P slot"), the block along
    the fixed line."""
    half_long, half_across = BLOCK[0] / 2 * square, BLOCK[1] / 2 * square
    at, over = now["points"], sweep["points"]
    out: dict[str, Point] = {}

    def guide(name: str, origin: str, mover: str, line: Callable) -> None:
        """The line through `origin` over the travel of the block on `mover`."""
        (tx, ty), (dx, dy), (mx, my) = over[origin], line(sweep), over[mover]
        travel = np.asarray((mx - tx) * dx + (my - ty) * dy, dtype=float)
        travel = travel[np.isfinite(travel)]
        lo, hi = (travel.min(), travel.max()) if travel.size else (math.nan, math.nan)
        (ox, oy), (ux, uy) = at[origin], line(now)
        for k, reach in ((1, lo), (2, hi)):
            out[f"{name} {k}"] = (ox + reach * ux, oy + reach * uy)

    def block(centre: str, line: Callable) -> None:
        (cx, cy), (dx, dy) = at[centre], line(now)
        for k, (u, v) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1)), start=1):
            out[f"{centre} block {k}"] = (cx + u * half_long * dx - v * half_across * dy,
                                          cy + u * half_long * dy + v * half_across * dx)

    for sliding in _slidings(description):
        for label, origin, mover, line in sliding.guides:
            guide(label, origin, mover, line(params))
        block(sliding.block, sliding.line(params))
    return out


def guide_movers(description: Mapping) -> dict[str, str]:
    """{guide label: the point whose travel over the sweep sets the guide's extent}."""
    return {label: mover for sliding in _slidings(description)
            for label, _origin, mover, _line in sliding.guides}


def slider_parts(description: Mapping) -> list[tuple[str, ...]]:
    """The points of each guide and each block slider_drawing places, part by part: the points
    of one part are joined (a guide is one line, a block one rigid body), whether or not the
    block ever closes."""
    parts: list[tuple[str, ...]] = []
    for sliding in _slidings(description):
        parts += [(f"{guide.label} 1", f"{guide.label} 2") for guide in sliding.guides]
        parts.append(tuple(f"{sliding.block} block {k}" for k in range(1, 5)))
    return parts


def _slidings(description: Mapping) -> list[Sliding]:
    """What each sliding step of the description draws, in step order."""
    steps = steps_of(description, STEP_TYPES)
    return [STEP_TYPES[step["type"]].sliding(step) for step in steps
            if STEP_TYPES[step["type"]].sliding is not None]
