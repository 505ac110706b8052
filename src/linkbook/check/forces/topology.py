"""The force reference's topology: the moving bodies of a description, numbered, their pins and
their sliding pairs (check/forces/__init__.py says how). Each step type says what it makes of
them in its own module (reference/steps, `topology`: its links, its carried point, its sliding
pair); here they are gathered, merged into rigid bodies and counted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from ..reference.step_type import Topology as StepTopology
from ..reference.step_type import slotted
from ..reference.steps import STEP_TYPES

GROUND = 1
# Each step of the description: its index, the step, and what it makes of the bodies
Steps = Sequence[tuple[int, Mapping, StepTopology]]


@dataclass
class Body:
    """A moving body of the force analysis: its joints, its mass's entry, its number."""
    joints: list[str]
    rank: int                       # the order in which the description names it
    block: bool = False
    spec: Mapping | None = None     # its `bodies` entry: mass, centre, inertia
    number: int = 0
    centre: str | None = None       # its centre of mass among the solved points
    spin: str | None = None         # an angle column that turns with it (a slide's link's line)
    guide: Body | None = None      # a block's guide (None: the ground, a fixed line)
    # directions turning with it beside its joints' (a slotted link's pivot to its pin):
    # their points name it, as a frame, not as pins
    frames: list[tuple[str, str]] = field(default_factory=list)

    def holds(self, a: str, b: str) -> bool:
        """Does it hold a and b: as joints, or as the two points of one of its frames?"""
        return {a, b} <= set(self.joints) or any({a, b} == set(f) for f in self.frames)

    def names(self, points: set[str]) -> bool:
        """Do these points, two or more, name it (its joints and its frames' points)?"""
        return len(points) > 1 and points <= {*self.joints, *(p for f in self.frames for p in f)}


@dataclass
class Pair:
    """A step's sliding pair: the block at `point` slides on its guide (None: the ground) along
    `line`; a slot's block also runs, by its pin, in the slot of the link `slotted` (None: the
    ground) along `slot`. A line is ("fixed", degrees), ("along", U, V, degrees: angle(U→V)
    plus these) or ("column", the key of an angle column, radians)."""
    point: str
    guide: Body | None
    line: tuple
    slotted: Body | None = None
    slot: tuple | None = None
    block: Body = field(default_factory=lambda: Body([], 0, block=True))


@dataclass
class Topology:
    """The bodies of a mechanism, its ground, its driver and its sliding pairs."""
    bodies: list[Body]
    fixed: set[str]                             # the ground's points
    crank: Body | None                         # the body the motor turns
    actuator: tuple[str, str] | None            # (P, R): the actuator pushes R away from P
    pairs: list[Pair]                          # the sliding pairs, in the order of their steps
    # (P, N, onto): a link P–N whose force at N on the link holding `onto` is also reported
    # along P→N and across it (a triad's binary links: reference/step_type.Topology.struts)
    struts: list[tuple[str, str, tuple[str, ...]]] = field(default_factory=list)

    def pair(self, i: int, j: int) -> str:
        """Two body numbers as a key's suffix: "23", or "2_13" from ten bodies on."""
        return f"{i}{j}" if len(self.bodies) + GROUND < 10 else f"{i}_{j}"


def number_of(body: Body | None) -> int:
    return GROUND if body is None else body.number


# --------------------------------------------------------------------------------------------
# Topology: the bodies, from the links and the steps
# --------------------------------------------------------------------------------------------

def _where(k: int, step: Mapping) -> str:
    return f"steps[{k}] ({step.get('type')} {step.get('point', step.get('key', ''))})"


def _merge(groups: list[Body]) -> list[Body]:
    """Groups sharing two points or more are one rigid body: merged into the one named first."""
    out = sorted(groups, key=lambda g: g.rank)
    while True:
        pair = next(((a, b) for i, a in enumerate(out) for b in out[i + 1:]
                     if len(set(a.joints) & set(b.joints)) >= 2), None)
        if pair is None:
            return out
        a, b = pair
        a.joints += [p for p in b.joints if p not in a.joints]
        a.frames += [f for f in b.frames if f not in a.frames]
        out.remove(b)


def _steps(description: Mapping) -> list[tuple[int, Mapping, StepTopology]]:
    """Each step with what its type makes of the bodies (a type of none: nothing)."""
    inp = description.get("input") or {}
    length_input = inp.get("key") if inp.get("kind", "angle") == "length" else None
    out = []
    for k, step in enumerate(description.get("steps") or []):
        kind = STEP_TYPES.get(step.get("type"))
        out.append((k, step, kind.topology(step, length_input) if kind else StepTopology()))
    return slotted(out)


def _drawn_links(description: Mapping, steps: Steps) -> list[list[str]]:
    """The `links` entries as sets of joints, each without the points that slide on it (a
    sliding pair's point, where the entry holds a point of the links it slides on)."""
    sliding = [(s.pair.point, s.pair.beside) for _, _, s in steps if s.pair is not None]
    out = []
    for link in description.get("links") or []:
        joints = list(dict.fromkeys(map(str, link)))
        out.append([p for p in joints
                    if not any(p == q and set(joints) & guide for q, guide in sliding)])
    return out


def _actuator(description: Mapping, steps: Steps) -> tuple[str, str] | None:
    """(P, R) of the dyad side whose length is the linear actuator's input, if any."""
    inp = description.get("input") or {}
    if inp.get("kind", "angle") != "length":
        return None
    found = next((made.actuator for _, _, made in steps if made.actuator is not None), None)
    if found is None:
        raise ValueError(f"mechanism.input: no dyad side is the actuator's length "
                         f"{inp.get('key')!r}")
    return found


def _step_groups(steps: Steps, actuator, first_rank: int) -> tuple[list[Body], Body | None]:
    """The links the steps imply (the cranks on one pivot are one body: they turn together),
    but the actuator's side, and the crank."""
    groups, crank = [], None
    for k, step, made in steps:
        if made.crank:
            (pivot, point), = made.links
            if crank is None:
                crank = Body([pivot, point], first_rank + len(groups))
                groups.append(crank)
            elif pivot != crank.joints[0]:
                raise ValueError(f"{_where(k, step)}: a second crank on another pivot")
            else:
                crank.joints.append(point)
            continue
        links = [link for link in made.links if set(link) != set(actuator or ())]
        groups += [Body(list(link), first_rank + len(groups) + n,
                        frames=[made.frame] if made.frame else [])
                   for n, link in enumerate(links)]
    return groups, crank


def _carry_points(steps: Steps, groups: list[Body], fixed: set[str]) -> list[Body]:
    """Each carried point joins the body of its frame, in step order (a point on the ground's
    frame is fixed)."""
    for k, step, made in steps:
        if made.carried is None:
            continue
        point, a, b, stretches = made.carried
        host = next((g for g in groups if g.holds(a, b)), None)
        if a in fixed and b in fixed:
            fixed.add(point)
        elif host is not None:
            host.joints += [point] if point not in host.joints else []
        elif stretches:          # the frame stretches: two links, as a dyad's
            rank = max(g.rank for g in groups) + 1
            groups = _merge(groups + [Body([a, point], rank), Body([b, point], rank + 1)])
        else:
            raise ValueError(f"{_where(k, step)}: its frame {a}→{b} is no rigid link")
    return _merge(groups)


def _link(bodies: Sequence[Body], fixed: set[str], a: str, b: str, what: str) -> Body | None:
    """The moving body holding the points a and b (None: both are the ground's)."""
    if a in fixed and b in fixed:
        return None
    found = next((g for g in bodies if g.holds(a, b)), None)
    if found is None:
        raise ValueError(f"{what}: its line's link {a}→{b} is no rigid link of the steps")
    return found


def _pairs(steps: Steps, bodies: Sequence[Body], fixed: set[str]) -> list[Pair]:
    """The sliding pairs of the steps, each with its block."""
    pairs = []
    for k, step, made in steps:
        spec, what = made.pair, _where(k, step)
        if spec is None:
            continue
        guide = _link(bodies, fixed, *spec.guide, what) if spec.guide else None
        if spec.spin is not None:
            guide.spin = spec.spin
        slotted = _link(bodies, fixed, *spec.slotted, what) if spec.slotted else None
        pair = Pair(spec.point, guide, spec.line, slotted, spec.slot)
        for other in (pair.guide, pair.slotted):
            if other is not None and pair.point in other.joints:
                raise ValueError(f"{what}: the link {other.joints} holds {pair.point!r}, the "
                                 "point that slides on it")
        pair.block = Body([pair.point], 0, block=True, guide=pair.guide)
        pairs.append(pair)
    return pairs


def _attach_entries(entries: Sequence[Mapping], bodies: list[Body]) -> None:
    """Each `bodies` entry's mass, centre and inertia go to the body holding its joints."""
    for k, entry in enumerate(entries):
        joints = {str(p) for p in entry.get("joints") or []}
        block = bool(entry.get("block", False))
        found = [b for b in bodies if b.block == block and (
                 joints == set(b.joints) if block else b.names(joints))]
        if len(found) != 1:
            raise ValueError(f"mechanism.bodies[{k}]: {sorted(joints)} is no moving link of the "
                             "steps and links (a block: [the point of a slider or a slot, or a "
                             "slide's p], block = true)")
        if block and "centre" in entry:
            raise ValueError(f"mechanism.bodies[{k}]: a block's centre is its point")
        if found[0].spec is not None:
            raise ValueError(f"mechanism.bodies[{k}]: a second entry for {found[0].joints}")
        found[0].spec = entry


def topology(description: Mapping) -> Topology:
    """The moving bodies of a description, numbered (see check/forces/__init__.py); refused
    where they are no mechanism of one degree of freedom."""
    steps = _steps(description)
    actuator = _actuator(description, steps)
    fixed = {str(p) for p in (description.get("ground") or {})}
    drawn = [Body(joints, rank) for rank, joints in enumerate(_drawn_links(description, steps))
             if len(joints) >= 2 and set(joints) != set(actuator or ())]
    implied, crank = _step_groups(steps, actuator, len(drawn))
    groups = _carry_points(steps, _merge(drawn + implied), fixed)
    groups = [g for g in groups if g.frames or not set(g.joints) <= fixed]
    for g in groups:
        if len(set(g.joints) & fixed) >= 2:
            raise ValueError(f"the link {g.joints} is held by two ground points: it cannot move")
    if crank is not None:          # the group the crank was merged into
        crank = next(g for g in groups if set(crank.joints) <= set(g.joints))
    bodies = ([crank] if crank else []) + [g for g in groups if g is not crank]
    pairs = _pairs(steps, bodies, fixed)
    bodies += [p.block for p in pairs]
    for number, body in enumerate(bodies, start=GROUND + 1):
        body.number = number
    _attach_entries(description.get("bodies") or [], bodies)
    top = Topology(bodies, fixed, crank, actuator, pairs,
                   [strut for _, _, made in steps for strut in made.struts])
    _count(top)
    return top


def _count(top: Topology) -> None:
    """Two unknowns per pin and per guide, one per slot and the effort: as many as the
    equations, three per moving body, or the links are no mechanism of one degree of
    freedom."""
    joints, guides = len(pins(top)), len(top.pairs)
    slots = sum(p.slot is not None for p in top.pairs)
    unknowns, equations = 2 * joints + 2 * guides + slots + 1, 3 * len(top.bodies)
    if unknowns != equations:
        raise ValueError(
            f"{unknowns} unknowns (2 × {joints} pins, 2 × {guides} guides, {slots} slots, the "
            f"effort) for {equations} equations (3 × {len(top.bodies)} moving bodies: "
            f"{[b.joints for b in top.bodies]}): the links are no mechanism of one degree of "
            f"freedom")


def pins(top: Topology) -> list[tuple[int, Body, str]]:
    """(i, body j, point) for every pin: i the body carrying the pin (the ground at a ground
    point, else the lowest-numbered body holding it), j each other body holding it."""
    holders: dict[str, list[Body]] = {}
    for body in top.bodies:
        for p in body.joints:
            holders.setdefault(p, []).append(body)
    pins = []
    for point, bodies in holders.items():
        if point in top.fixed:
            pins += [(GROUND, b, point) for b in bodies]
        else:
            pins += [(bodies[0].number, b, point) for b in bodies[1:]]
    return pins


def host(top: Topology, point: str) -> Body:
    """Where a force at a point acts: the block there (a piston's, a ram's), else the
    lowest-numbered moving body holding the point."""
    holding = [b for b in top.bodies if point in b.joints]
    if not holding or point in top.fixed:
        raise ValueError(f"no moving link holds the point {point!r}")
    return next((b for b in holding if b.block), holding[0])


def body_of(top: Topology, joints: Sequence[str], what: str) -> Body:
    """The body holding all these joints (the one holding exactly them where several do)."""
    wanted = {str(p) for p in joints}
    found = [b for b in top.bodies if wanted <= set(b.joints) or not b.block and b.names(wanted)]
    found = [b for b in found if set(b.joints) == wanted] if len(found) > 1 else found
    if len(found) != 1:
        raise ValueError(f"{what}: no single moving link holds {sorted(wanted)}")
    return found[0]
