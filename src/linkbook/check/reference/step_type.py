"""What the reference needs of one step type of the mechanism language (docs/language.md).

Each step type has a module of its own under steps/, which builds one StepType; steps/__init__.py
lists them in STEP_TYPES, keyed by the step's `type`. Positions, Rates and the drawing of
sliders look a step's type up there and know nothing else of it, so adding a step type to the
reference is one new module and one line in that dict.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

# Fields holding a length or an offset: the sum of their sizes is the mechanism's size (the
# scale of Newton's tolerances), unless a step type names other fields.
LENGTH_FIELDS = ("length", "p_length", "q_length", "offset", "distance")

# A line's direction as the drawing takes it: given the parameters, a function of a solve()
# result that gives the line's unit direction (dx, dy), per row or fixed.
LineOf = Callable[[Mapping[str, float]], Callable[[Mapping], tuple]]


class Guide(NamedTuple):
    """A drawn line a block slides on: through point `origin`, in the direction `line`, over the
    travel of the block on point `mover` (its parts: "<label> 1", "<label> 2")."""
    label: str
    origin: str
    mover: str
    line: LineOf


class Pair(NamedTuple):
    """A step's sliding pair as the force reference reads it: a block at `point` slides on the
    link holding the two points `guide` (None: the ground) along `line`, turning with its
    `spin` column where the guide's own joints cannot give it (a slide's link); a slot's block
    also runs, by its pin, in the slot of the link holding `slotted` along `slot`. A line is
    ("fixed", degrees), ("along", U, V, degrees: angle(U→V) plus these) or ("column", the key
    of an angle column). `beside`: the points of the links it slides on (a `links` entry
    holding one of them does not hold `point`)."""
    point: str
    line: tuple
    guide: tuple[str, str] | None = None
    beside: frozenset[str] = frozenset()
    spin: str | None = None
    slotted: tuple[str, str] | None = None
    slot: tuple | None = None


class Topology(NamedTuple):
    """What a step makes of the force analysis' bodies: the rigid `links` it implies (sets of
    points that move together); `crank`: its link turns with the input (the cranks on one
    pivot are one body); `carried`: (point, A, B, stretches) for a point carried by the frame
    A→B, joining the link holding both (stretches: by distances, so a frame that is no link
    makes two); `pair`: its sliding pair; `actuator`: (P, R), the side whose length is the
    input (a massless member of unknown force, no link); `frame`: (U, V), a direction that
    turns with its link beside its points' (a slide's: its point to p; a slotted link's: its
    pivot to the pin in its slot); `turns`: (U, V), the direction a vector step measures, its
    links and pair a slotted link's (pivot U) and the block at V's only where another step
    is carried by U→V or slides on it and no other step's link holds both (`slotted`);
    `struts`: (P, N, onto) for a link P–N whose pin force at N on the link holding the points
    `onto` the report also gives along P→N and across it (a triad's binary links on its
    ternary: Fa_N, Fn_N)."""
    links: tuple[tuple[str, ...], ...] = ()
    crank: bool = False
    carried: tuple[str, str, str, bool] | None = None
    pair: Pair | None = None
    actuator: tuple[str, str] | None = None
    frame: tuple[str, str] | None = None
    turns: tuple[str, str] | None = None
    struts: tuple[tuple[str, str, tuple[str, ...]], ...] = ()


def slotted(steps: list) -> list:
    """(k, step, Topology) of each step, a vector step's kept as a slotted link where it is
    one (see Topology.turns), else reduced to the direction it measures."""
    uses: set[frozenset] = set()
    for _, _, made in steps:
        if made.turns is not None:
            continue
        if made.carried is not None:
            uses.add(frozenset(made.carried[1:3]))
        if made.pair is not None:
            uses |= {frozenset(made.pair.guide or ()), frozenset(made.pair.slotted or ())}
    held = [set(link) for _, _, made in steps if made.turns is None for link in made.links]
    return [(k, step, made) if made.turns is None or (
                frozenset(made.turns) in uses and not any(set(made.turns) <= h for h in held))
            else (k, step, Topology(turns=made.turns)) for k, step, made in steps]


# A step type's topology, given its step and the key of a length input (None for an angle)
TopologyOf = Callable[[Mapping, "str | None"], Topology]


def no_topology(step: Mapping, length_input: str | None) -> Topology:
    """A step that makes no link (a column of the user's, a measured distance)."""
    return Topology()


class Sliding(NamedTuple):
    """What a sliding step draws: its guides, and a block centred on point `block`, its long side
    along `line` (its corners: "<block> block 1" … "<block> block 4")."""
    guides: tuple[Guide, ...]
    block: str
    line: LineOf


@dataclass(frozen=True)
class StepType:
    """One step type, as the reference reads it.

    place(positions, step): solve the step on every row and record what it makes, through the
        methods of positions.Positions (known points and numbers in; point_columns, new_point,
        column, add_link out); it raises ValueError for a malformed step.
    rates(rates, step), optional: the step's velocities and accelerations, through the methods of
        rates.Rates (place, put_rates, circles, ...; taylor.implicit for a loop); without it the
        step has none (a later step may then not use a point it places in its rates).
    length_fields: the fields whose values count towards the mechanism's size.
    sliding(step), optional: the guides and the block the step draws (a sliding joint).
    topology(step, length_input): what the step makes of the force analysis' bodies (its
        links, its carried point, its sliding pair: Topology), read by check/forces.
    """
    place: Callable[[Any, Mapping], None]
    rates: Callable[[Any, Mapping], None] | None = None
    length_fields: tuple[str, ...] = LENGTH_FIELDS
    sliding: Callable[[Mapping], Sliding] | None = None
    topology: TopologyOf = no_topology
