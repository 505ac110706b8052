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
class Block:
    """A step's sliding pair as the force writer reads it: a block at `point` slides along
    `line` ((cos, sin) texts) on the link holding the points `guide`, turning with the line
    through the two points `spin` (the motion writer's link_rates); on the ground where there
    is no guide or its points are the ground's. `beside`: the points of the links it slides on
    (a `links` entry holding one of them does not hold `point`). `slotted`: the two points of
    the link in whose slot its pin also runs (a slot's), if any."""
    point: str
    line: tuple[str, str]
    guide: tuple[str, ...] = ()
    spin: tuple[str, str] | None = None
    beside: frozenset[str] = frozenset()
    slotted: tuple[str, ...] = ()


@dataclass(frozen=True)
class Topology:
    """What a step makes of the force writer's bodies: the rigid `links` it implies (sets of
    points that move together); `crank`: its link turns with the input (the cranks on one
    pivot are one link); `carried`: (point, A, B) for a point carried by the frame A→B, which
    joins the link holding both; `block`: its sliding pair; `actuator`: (END, N), its side
    whose length is the input (no link: a member of unknown force); `frame`: (A, B), a
    direction that turns with its link beside its points' (a slide's, its point to p; a
    slotted link's, its pivot to the pin sliding in it); `turns`: (A, B), the direction a
    vector step measures, whose link and block are the slotted link's and its pin's only where
    another step is carried by or slides on A→B and no step's link holds both (`slotted`)."""
    links: tuple[tuple[str, ...], ...] = ()
    crank: bool = False
    carried: tuple[str, str, str] | None = None
    block: Block | None = None
    actuator: tuple[str, str] | None = None
    frame: tuple[str, str] | None = None
    turns: tuple[str, str] | None = None


def slotted(made: list[tuple[dict, Topology]]) -> list[tuple[dict, Topology]]:
    """Each step's topology, a vector step's as a slotted link (its pivot A, the block at B
    sliding in it along A→B) where another step places a point on A→B or slides or runs on
    it and no other step's link holds both; elsewhere a direction measured, no link."""
    used: set[frozenset[str]] = set()
    linked = [set(link) for _, m in made if m.turns is None for link in m.links]
    for _, m in made:
        if m.turns is None and m.carried is not None:
            used.add(frozenset(m.carried[1:]))
        if m.turns is None and m.block is not None:
            used |= {frozenset(m.block.guide), frozenset(m.block.slotted)}
    return [(rec, m if m.turns is None or (frozenset(m.turns) in used and
                                           not any(set(m.turns) <= k for k in linked))
             else Topology(turns=m.turns)) for rec, m in made]


def no_topology(record: dict, length_input: str | None) -> Topology:
    """A step that makes no link (a column of the user's, a measured distance)."""
    return Topology()


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
    topology(record, length_input): what a record `place` made makes of the force writer's
        bodies (Topology: its links, its carried point, its block), `length_input` the input's
        cell as formula text where it is a length (a linear actuator), else None.
    dimensions(step): the power of length of each key that takes an expression (a length 1,
        an angle in degrees 0), for a change of length unit; keys left out are not checked.
    """
    keys: tuple[set[str], set[str]]
    place: Callable[..., None]
    rates: Callable[..., None] | None = None
    dimensions: Callable[[dict], dict[str, int]] = field(default=_none)
    forces: Callable[..., None] | None = None
    topology: Callable[[dict, str | None], Topology] = no_topology
