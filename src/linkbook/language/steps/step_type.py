"""What the writer needs of one step type of the language: its keys, its position formulas and
its rate formulas, together in one StepType (one module per step type in this package).

The compiler reads a step's keys and places it (`place`), which records what it placed; the
motion writer then differentiates each record (`rates`), step after step as the positions go.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..schema import keys_of, step_schemas

# Keys every step may have beside its own: its type, and the table that renames or hides columns
COMMON_KEYS = {"type", "columns"}


def schema_keys(kind: str) -> tuple[set[str], set[str]]:
    """(required, optional) keys of a step type as the schema allows them, beside COMMON_KEYS:
    the schema is the one source of truth of what a step may contain."""
    required, optional = keys_of(step_schemas()[kind])
    return required - COMMON_KEYS, optional - COMMON_KEYS


def fixed(dimensions: dict[str, int]) -> Callable[[dict], dict[str, int]]:
    """Dimensions of a step's keys that do not depend on its other keys."""
    return lambda step: dimensions


def _none(step: dict) -> dict[str, int]:
    return {}


@dataclass(frozen=True)
class StepType:
    """One step type on the writer's side.

    keys: (required, optional) keys of the step beside COMMON_KEYS; a key outside them, or a
        missing required one, is refused before `place` runs.
    place(c, field, step): writes the step's position formulas into the compiler `c`
        (compiler.Compiler: its model, points, rigid links, helpers such as known_point,
        expr, columns, add_point) and appends to c.records one dict with "type" (the step's
        kind) and whatever its `rates` needs; `field` names the step in error messages.
    rates(w, record): writes the velocity and acceleration formulas of a record `place` made,
        through the motion writer `w` (motion.MotionWriter: vel, acc, rel, rate, point,
        link_rates, determinant); None for a step that records nothing.
    forces(w, record): solves the step's group for its joint reactions, through the force
        writer `w` (forces.ForceWriter: its helpers, and two_links, crank, actuated), the
        steps being solved from the last back to the first; None for a step that places no
        link (a point carried by one, a column of the user's).
    dimensions(step): the power of length of each key that takes an expression (a length 1,
        an angle in degrees 0), for a change of length unit; keys left out are not checked.
    """
    keys: tuple[set[str], set[str]]
    place: Callable[..., None]
    rates: Callable[..., None] | None = None
    dimensions: Callable[[dict], dict[str, int]] = field(default=_none)
    forces: Callable[..., None] | None = None
