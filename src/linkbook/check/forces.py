"""Independent force reference: the driving effort, every pin load and the shaking force of a
described mechanism, from the Newton–Euler equations of all its moving links solved at once.

The description is a template's ``[mechanism]`` table (docs/language.md) with its dynamics:

    [mechanism.dynamics]
    gravity = { g = "g", angle = -90 }    # m/s², degrees from +x (default −90); none if absent
    [[mechanism.bodies]]                  # one per moving link that has mass
    joints = ["A", "B", "C"]              # the points the link holds
    block = false                         # true: a block (joints = [its point]), centred there
    mass = "m3"                           # kg
    centre = { frame = ["A", "B"], distance = "g3", angle = 0 }   # placed as a `point` step
    inertia = "I3"                        # kg·m² about the centre of mass
    [[mechanism.loads]]
    at = "C"; force = ["Fx", "Fy"]        # N; or force = { magnitude = "F", angle = "beta" }
    body = ["B0", "B"]; torque = "T4"     # N·m, counter-clockwise, on the body holding these

Every value is a number, a parameter or an expression, which may name the steps' columns and
the rates too (a damper's −c·ω: the kinematic reference's own rates).
Lengths are in the template's ``length_unit``, converted to metres once: forces in N, moments in
N·m. A force at a block's point acts on the block, at any other point on the lowest-numbered
link holding it, unless the load names its link (``body`` beside ``at``).

Why it is independent: it reads the topology from the description, assembles the equations from
the constraints, 3 per moving body (ΣF = m·a_G, ΣM = I_G·α, in d'Alembert's form) with the
reactions as unknowns, and solves them with numpy row by row. All it takes from linkbook is the
kinematic reference's public ``solve``: the motion of every point, and the evaluation of the
expressions (as an `expression` step's, after the rates). No closed form of the workbook's is used.

Topology. The rigid bodies are the sets of points that move together: each ``links`` entry and
each step's links (a crank's pivot and pin, a dyad's two sides, a slider's rod, a slide's link
from its pivot to its point; a carried point joins the body of its frame, or, by ``distances``
on a frame that is no body, makes two links); sets sharing two points are one body, and cranks
on one pivot are one body. A ``bodies`` entry gives the body holding its joints a mass. The side
of a dyad that is the linear actuator's length is no body: a massless member of unknown force.
Every step that slides makes a block, a body of one point (its centre), on a guide:
- a ``slider``: at its point, on its fixed line (the ground) or on the link of ``along``,
  pinned to its rod;
- a ``slide``: at its ``p``, on the slide's link (its pivot and point), pinned to the links
  holding p (the crank);
- a ``slot``: at its point, on its fixed line (the ground), and in the slot of the link of
  ``slot_frame``: a pin pushed across the slot only (one unknown, no couple).
A guide pushes its block across its line and holds it with a couple; the block turns with its
guide (not at all on a fixed line). A sliding point is no joint of its guide: a ``links`` entry
holding a point of the guide (``along`` and ``through``; the slide's pivot and point; the slot's
``slot_through`` and ``slot_frame``) leaves it out, and one left with fewer than two points only
draws. Numbering, as the textbook's: the ground 1, the crank 2, then the other bodies in the
order of the ``links`` entries, then those that only the steps name, then the blocks in the
order of their steps. Links that are no mechanism of one degree of freedom (unknowns, 2 per pin
and guide, 1 per slot and the effort, other than 3 per body) are refused; so is a slotted link
written with a ``vector`` step (the direction from its pivot to a pin sliding in it): it is no
link of the steps, a ``slide`` step is.

What ``forces`` returns (arrays over the rows; i < j body numbers, written together as "23", or
with "_" between them, "2_13", in a mechanism of ten bodies or more):
- ``T12``: the driving torque of the ground (the motor) on the crank 2, counter-clockwise
  positive; for a linear actuator ``F_in``: its force, positive pushing its two ends apart;
- ``F{i}{j}x``, ``F{i}{j}y``, ``F{i}{j}``: the force of body i on body j at the pin joining
  them, and its size. A pin held by more than two bodies is carried by the lowest-numbered of
  them (the ground at a ground point): each other body j gets F{that}{j};
- for a block j on its guide i (1: a fixed line): ``N{i}{j}``, the guide's force on it along
  the line's direction turned +90°; ``M{i}{j}``, the guide's couple on it; ``F{i}{j}x``,
  ``F{i}{j}y``, ``F{i}{j}``: that force as a vector, its size (|N|). The line's direction: a
  fixed line's ``direction``; angle(U→V) + ``direction`` along [U, V]; a slide's column
  ``theta_slide``. On the guide, the opposite force and couple;
- for a slot's block j in the link i: ``N{i}{j}``, the link's force on it across the slot (its
  direction, angle(slot_frame) + ``slot_angle``, turned +90°), ``F{i}{j}x``, ``F{i}{j}y``,
  ``F{i}{j}``; no couple;
- ``shaking_x``, ``shaking_y``, ``shaking``: the force the moving links exert on the ground
  (through the ground pins, the fixed guides with their couples and the actuator's ground
  end); ``shaking_moment``: its moment about the frame's origin, the motor's reaction −T12
  included;
- ``xG{n}``, ``yG{n}``, ``axG{n}``, ``ayG{n}``: a link's centre of mass and its acceleration,
  in the template's length unit (per s²);
- ``cond``: each row's condition number (equilibrated). A row is NaN where a position or a rate
  is NaN, or where the system is singular (cond above SINGULAR);
- ``bodies``: {number: the body's joints}; ``joints``: {reaction key F{i}{j}: its point} for
  every pin, guide and slot.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .reference import solve

__all__ = ["forces", "topology", "LENGTH_UNITS", "SINGULAR"]

LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}
SINGULAR = 1e12       # a row's system with a larger condition number has no reliable solution
GROUND = 1
# The data format's names of the input's speed and acceleration (docs/language.md).
_RATES = {"angle": ("omega_in", "alpha_in"), "length": ("v_in", "a_in")}
_OWN = "forces__"     # the points and keys this module adds to the description start so
_CENTRE_KEYS = ("frame", "local", "distances", "side", "distance", "angle")


@dataclass
class _Body:
    joints: list[str]
    rank: int                       # the order in which the description names it
    block: bool = False
    spec: Mapping | None = None     # its `bodies` entry: mass, centre, inertia
    number: int = 0
    centre: str | None = None       # its centre of mass among the solved points
    spin: str | None = None         # an angle column that turns with it (a slide's link's line)
    guide: _Body | None = None      # a block's guide (None: the ground, a fixed line)


@dataclass
class _Pair:
    """A step's sliding pair: the block at `point` slides on its guide (None: the ground) along
    `line`; a slot's block also runs, by its pin, in the slot of the link `slotted` (None: the
    ground) along `slot`. A line is ("fixed", degrees), ("along", U, V, degrees: angle(U→V)
    plus these) or ("column", the key of an angle column, radians)."""
    point: str
    guide: _Body | None
    line: tuple
    slotted: _Body | None = None
    slot: tuple | None = None
    block: _Body = field(default_factory=lambda: _Body([], 0, block=True))


@dataclass
class _Topology:
    bodies: list[_Body]
    fixed: set[str]                             # the ground's points
    crank: _Body | None                         # the body the motor turns
    actuator: tuple[str, str] | None            # (P, R): the actuator pushes R away from P
    pairs: list[_Pair]                          # the sliding pairs, in the order of their steps

    def pair(self, i: int, j: int) -> str:
        """Two body numbers as a key's suffix: "23", or "2_13" from ten bodies on."""
        return f"{i}{j}" if len(self.bodies) + GROUND < 10 else f"{i}_{j}"


def _number(body: _Body | None) -> int:
    return GROUND if body is None else body.number


# --------------------------------------------------------------------------------------------
# Topology: the bodies, from the links and the steps
# --------------------------------------------------------------------------------------------

def _where(k: int, step: Mapping) -> str:
    return f"steps[{k}] ({step.get('type')} {step.get('point', step.get('key', ''))})"


def _merge(groups: list[_Body]) -> list[_Body]:
    """Groups sharing two points or more are one rigid body: merged into the one named first."""
    out = sorted(groups, key=lambda g: g.rank)
    while True:
        pair = next(((a, b) for i, a in enumerate(out) for b in out[i + 1:]
                     if len(set(a.joints) & set(b.joints)) >= 2), None)
        if pair is None:
            return out
        a, b = pair
        a.joints += [p for p in b.joints if p not in a.joints]
        out.remove(b)


def _sliding_points(steps: Sequence[Mapping]) -> list[tuple[str, set[str]]]:
    """Each point that slides on a moving guide or in a slot, with the points of that guide (or
    slotted link): a `links` entry holding one of them does not hold the sliding point."""
    out = []
    for step in steps:
        kind, point = step.get("type"), str(step.get("point"))
        if kind == "slider" and "along" in step:
            out.append((point, {*map(str, step["along"]), str(step["through"])}))
        elif kind == "slide":
            out.append((str(step["p"]), {str(step["pivot"]), point}))
        elif kind == "slot":
            out.append((point, {str(step["slot_through"]), *map(str, step["slot_frame"])}))
    return out


def _drawn_links(description: Mapping) -> list[list[str]]:
    """The `links` entries as sets of joints, each without the points that slide on it."""
    sliding = _sliding_points(description.get("steps") or [])
    out = []
    for link in description.get("links") or []:
        joints = list(dict.fromkeys(map(str, link)))
        out.append([p for p in joints
                    if not any(p == q and set(joints) & guide for q, guide in sliding)])
    return out


def _turned_by_vector(steps: Sequence[Mapping], groups: Sequence[Sequence[str]]) -> str:
    """The hint for a link that only a `vector` step turns (a slotted link written as the
    direction from its pivot to a pin), where its two points are one of these groups' or
    a frame that is no link: empty where there is none."""
    for k, step in enumerate(steps):
        ends = {str(step.get("from")), str(step.get("to"))}
        if step.get("type") == "vector" and any(ends <= set(map(str, g)) for g in groups):
            return (f"; {_where(k, step)} turns the link {step.get('from')}→{step.get('to')} "
                    "as a direction to a pin that slides on it (a slotted link), which no step "
                    "makes a link: write the slotted link as a slide step to give it forces")
    return ""


def _actuator(description: Mapping) -> tuple[str, str] | None:
    """(P, R) of the dyad side whose length is the linear actuator's input, if any."""
    inp = description.get("input") or {}
    if inp.get("kind", "angle") != "length":
        return None
    for step in description.get("steps") or []:
        for end, side in (("p", "p_length"), ("q", "q_length")):
            if step.get("type") == "dyad" and step.get(side) == inp.get("key"):
                return str(step[end]), str(step["point"])
    raise ValueError(f"mechanism.input: no dyad side is the actuator's length {inp.get('key')!r}")


def _step_groups(steps: Sequence[Mapping], actuator, first_rank: int
                 ) -> tuple[list[_Body], _Body | None]:
    """The links the crank, dyad, slider and slide steps imply (the cranks on one pivot are one
    body: they turn together; a slide's link runs from its pivot to its point), and the
    crank."""
    groups, crank = [], None
    for k, step in enumerate(steps):
        kind, point = step.get("type"), str(step.get("point"))
        sides = []
        if kind == "crank" and crank is None:
            crank = _Body([str(step["pivot"]), point], first_rank + len(groups))
            groups.append(crank)
        elif kind == "crank":
            if str(step["pivot"]) != crank.joints[0]:
                raise ValueError(f"{_where(k, step)}: a second crank on another pivot")
            crank.joints.append(point)
        elif kind == "dyad":
            sides = [step[end] for end in ("p", "q") if {step[end], point} != set(actuator or ())]
        elif kind == "slider":
            sides = [step["p"]]
        elif kind == "slide":
            sides = [step["pivot"]]
        groups += [_Body([str(a), point], first_rank + len(groups) + n)
                   for n, a in enumerate(sides)]
    return groups, crank


def _carry_points(steps: Sequence[Mapping], groups: list[_Body], fixed: set[str]
                  ) -> list[_Body]:
    """Each carried point joins the body of its frame, in step order (a point on the ground's
    frame is fixed)."""
    for k, step in enumerate(steps):
        if step.get("type") != "point":
            continue
        (a, b), point = (str(p) for p in step["frame"]), str(step["point"])
        host = next((g for g in groups if a in g.joints and b in g.joints), None)
        if a in fixed and b in fixed:
            fixed.add(point)
        elif host is not None:
            host.joints += [point] if point not in host.joints else []
        elif "distances" in step:          # the frame stretches: two links, as a dyad's
            rank = max(g.rank for g in groups) + 1
            groups = _merge(groups + [_Body([a, point], rank), _Body([b, point], rank + 1)])
        else:
            raise ValueError(f"{_where(k, step)}: its frame {a}→{b} is no rigid link"
                             + _turned_by_vector(steps, [(a, b)]))
    return _merge(groups)


def _link(bodies: Sequence[_Body], fixed: set[str], a: str, b: str, what: str) -> _Body | None:
    """The moving body holding the points a and b (None: both are the ground's)."""
    if a in fixed and b in fixed:
        return None
    found = next((g for g in bodies if a in g.joints and b in g.joints), None)
    if found is None:
        raise ValueError(f"{what}: its line's link {a}→{b} is no rigid link of the steps")
    return found


def _slide_key(step: Mapping) -> str:
    """A slide's line: its `theta_slide` column, under the key the step's `columns` gives."""
    spec = (step.get("columns") or {}).get("theta_slide")
    key = str(spec.get("key") or "") if isinstance(spec, Mapping) else ""
    return key or f"theta_slide_{step['point']}"


def _pairs(steps: Sequence[Mapping], bodies: Sequence[_Body], fixed: set[str]) -> list[_Pair]:
    """The sliding pairs of the slider, slide and slot steps, each with its block."""
    pairs = []
    for k, step in enumerate(steps):
        kind, point, what = step.get("type"), str(step.get("point")), _where(k, step)
        if kind == "slider" and "along" in step:
            u, v = (str(p) for p in step["along"])
            pair = _Pair(point, _link(bodies, fixed, u, v, what),
                         ("along", u, v, step.get("direction", 0.0)))
        elif kind == "slider":
            pair = _Pair(point, None, ("fixed", step.get("direction", 0.0)))
        elif kind == "slide":
            guide = _link(bodies, fixed, str(step["pivot"]), point, what)
            guide.spin = _slide_key(step)
            pair = _Pair(str(step["p"]), guide, ("column", guide.spin))
        elif kind == "slot":
            a, b = (str(p) for p in step["slot_frame"])
            pair = _Pair(point, None, ("fixed", step.get("direction", 0.0)),
                         _link(bodies, fixed, a, b, what),
                         ("along", a, b, step.get("slot_angle", 0.0)))
        else:
            continue
        for other in (pair.guide, pair.slotted):
            if other is not None and pair.point in other.joints:
                raise ValueError(f"{what}: the link {other.joints} holds {pair.point!r}, the "
                                 "point that slides on it")
        pair.block = _Body([pair.point], 0, block=True, guide=pair.guide)
        pairs.append(pair)
    return pairs


def _attach_entries(entries: Sequence[Mapping], bodies: list[_Body]) -> None:
    """Each `bodies` entry's mass, centre and inertia go to the body holding its joints."""
    for k, entry in enumerate(entries):
        joints = {str(p) for p in entry.get("joints") or []}
        block = bool(entry.get("block", False))
        found = [b for b in bodies if b.block == block and (
                 joints == set(b.joints) if block else len(joints) > 1 and joints <= set(b.joints))]
        if len(found) != 1:
            raise ValueError(f"mechanism.bodies[{k}]: {sorted(joints)} is no moving link of the "
                             "steps and links (a block: [the point of a slider or a slot, or a "
                             "slide's p], block = true)")
        if block and "centre" in entry:
            raise ValueError(f"mechanism.bodies[{k}]: a block's centre is its point")
        if found[0].spec is not None:
            raise ValueError(f"mechanism.bodies[{k}]: a second entry for {found[0].joints}")
        found[0].spec = entry


def topology(description: Mapping) -> _Topology:
    """The moving bodies of a description, numbered (see the module's docstring); refused
    where they are no mechanism of one degree of freedom."""
    steps = list(description.get("steps") or [])
    actuator = _actuator(description)
    fixed = {str(p) for p in (description.get("ground") or {})}
    drawn = [_Body(joints, rank) for rank, joints in enumerate(_drawn_links(description))
             if len(joints) >= 2 and set(joints) != set(actuator or ())]
    implied, crank = _step_groups(steps, actuator, len(drawn))
    groups = _carry_points(steps, _merge(drawn + implied), fixed)
    groups = [g for g in groups if not set(g.joints) <= fixed]
    for g in groups:
        if len(set(g.joints) & fixed) >= 2:
            raise ValueError(f"the link {g.joints} is held by two ground points: it cannot move"
                             + _turned_by_vector(steps, [g.joints]))
    if crank is not None:          # the group the crank was merged into
        crank = next(g for g in groups if set(crank.joints) <= set(g.joints))
    bodies = ([crank] if crank else []) + [g for g in groups if g is not crank]
    pairs = _pairs(steps, bodies, fixed)
    bodies += [p.block for p in pairs]
    for number, body in enumerate(bodies, start=GROUND + 1):
        body.number = number
    _attach_entries(description.get("bodies") or [], bodies)
    top = _Topology(bodies, fixed, crank, actuator, pairs)
    _count(top, steps)
    return top


def _count(top: _Topology, steps: Sequence[Mapping]) -> None:
    """Two unknowns per pin and per guide, one per slot and the effort: as many as the
    equations, three per moving body, or the links are no mechanism of one degree of
    freedom."""
    pins, guides = len(_pins(top)), len(top.pairs)
    slots = sum(p.slot is not None for p in top.pairs)
    unknowns, equations = 2 * pins + 2 * guides + slots + 1, 3 * len(top.bodies)
    if unknowns != equations:
        raise ValueError(
            f"{unknowns} unknowns (2 × {pins} pins, 2 × {guides} guides, {slots} slots, the "
            f"effort) for {equations} equations (3 × {len(top.bodies)} moving bodies: "
            f"{[b.joints for b in top.bodies]}): the links are no mechanism of one degree of "
            "freedom" + _turned_by_vector(steps, [b.joints for b in top.bodies]))


def _pins(top: _Topology) -> list[tuple[int, _Body, str]]:
    """(i, body j, point) for every pin: i the body carrying the pin (the ground at a ground
    point, else the lowest-numbered body holding it), j each other body holding it."""
    holders: dict[str, list[_Body]] = {}
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


def _host(top: _Topology, point: str) -> _Body:
    """Where a force at a point acts: the block there (a piston's, a ram's), else the
    lowest-numbered moving body holding the point."""
    holding = [b for b in top.bodies if point in b.joints]
    if not holding or point in top.fixed:
        raise ValueError(f"no moving link holds the point {point!r}")
    return next((b for b in holding if b.block), holding[0])


def _body_of(top: _Topology, joints: Sequence[str], what: str) -> _Body:
    """The body holding all these joints (the one holding exactly them where several do)."""
    wanted = {str(p) for p in joints}
    found = [b for b in top.bodies if wanted <= set(b.joints)]
    found = [b for b in found if set(b.joints) == wanted] if len(found) > 1 else found
    if len(found) != 1:
        raise ValueError(f"{what}: no single moving link holds {sorted(wanted)}")
    return found[0]


# --------------------------------------------------------------------------------------------
# The values: expressions and centres, evaluated and moved by the kinematic reference
# --------------------------------------------------------------------------------------------

@dataclass
class _Loads:
    """What acts on the bodies, as keys of the solved description: each value a formula the
    reference's parser evaluates after the rates, per row where it names a column or a rate
    (`values`: solve's `late`); a centre of mass a `point` step appended to the description,
    and so moving with the rest. A vector is ("xy", x, y) or ("polar", magnitude, angle in
    degrees)."""
    description: Mapping
    steps: list[dict] = field(default_factory=list)
    values: dict[str, object] = field(default_factory=dict)
    gravity: tuple[str, str, str] | None = None
    forces: list[tuple[_Body, str, tuple[str, str, str]]] = field(default_factory=list)
    torques: list[tuple[_Body, str]] = field(default_factory=list)
    masses: dict[int, tuple[str, str]] = field(default_factory=dict)   # number: (mass, inertia)
    lines: dict[tuple[int, str], tuple] = field(default_factory=dict)  # (block, "line"/"slot")

    def value(self, formula: object, what: str) -> str:
        if isinstance(formula, bool) or not isinstance(formula, (int, float, str)):
            raise ValueError(f"{what}: expected a number or an expression, got {formula!r}")
        key = f"{_OWN}{len(self.values)}"
        self.values[key] = formula
        return key

    def vector(self, spec, what: str) -> tuple[str, str, str]:
        if isinstance(spec, (list, tuple)) and len(spec) == 2:
            return "xy", self.value(spec[0], f"{what}[0]"), self.value(spec[1], f"{what}[1]")
        if isinstance(spec, Mapping) and "magnitude" in spec:
            return ("polar", self.value(spec["magnitude"], f"{what}.magnitude"),
                    self.value(spec.get("angle", 0.0), f"{what}.angle"))
        raise ValueError(f"{what} must be [x, y] or {{ magnitude, angle }}")

    def line(self, spec: tuple, what: str) -> tuple:
        """A pair's line (see _Pair) with its degrees as a key."""
        return (*spec[:-1], self.value(spec[-1], what)) if spec[0] != "column" else spec

    def centre(self, body: _Body, spec: Mapping, what: str) -> str:
        frame = spec.get("frame")
        if not isinstance(frame, (list, tuple)) or not set(map(str, frame)) <= set(body.joints):
            raise ValueError(f"{what}.frame must be two joints of the body {body.joints}")
        name = f"{_OWN}G{body.number}"
        self.steps.append({"type": "point", "point": name,
                           **{k: spec[k] for k in _CENTRE_KEYS if k in spec}})
        return name

    def described(self) -> dict:
        return {**self.description,
                "steps": list(self.description.get("steps") or []) + self.steps}


def _read_bodies(loads: _Loads, top: _Topology) -> None:
    for body in top.bodies:
        spec, what = body.spec or {}, f"mechanism.bodies (the link {body.joints})"
        loads.masses[body.number] = (loads.value(spec.get("mass", 0.0), f"{what}.mass"),
                                     loads.value(spec.get("inertia", 0.0), f"{what}.inertia"))
        if body.block:
            body.centre = body.joints[0]
        elif "centre" in spec:
            body.centre = loads.centre(body, spec["centre"], f"{what}.centre")
        elif "mass" in spec:
            raise ValueError(f"{what}: a mass needs its centre")


def _read_loads(description: Mapping, top: _Topology) -> _Loads:
    loads = _Loads(description)
    gravity = (description.get("dynamics") or {}).get("gravity")
    if gravity is not None:
        loads.gravity = loads.vector({"magnitude": gravity.get("g", 0.0),
                                      "angle": gravity.get("angle", -90.0)},
                                     "mechanism.dynamics.gravity")
    _read_bodies(loads, top)
    for k, load in enumerate(description.get("loads") or []):
        what = f"mechanism.loads[{k}]"
        if "at" in load and "force" in load:
            at = str(load["at"])
            body = _body_of(top, load["body"], what) if "body" in load else _host(top, at)
            if at not in body.joints:
                raise ValueError(f"{what}: the link {body.joints} does not hold {at!r}")
            loads.forces.append((body, at, loads.vector(load["force"], f"{what}.force")))
        elif "body" in load and "torque" in load:
            loads.torques.append((_body_of(top, load["body"], what),
                                  loads.value(load["torque"], f"{what}.torque")))
        else:
            raise ValueError(f"{what}: needs at and force, or body and torque")
    for pair in top.pairs:
        what = f"the sliding pair at {pair.point}"
        loads.lines[pair.block.number, "line"] = loads.line(pair.line, f"{what}: its line")
        if pair.slot is not None:
            loads.lines[pair.block.number, "slot"] = loads.line(pair.slot, f"{what}: its slot")
    return loads


def _cos_sin(deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of degrees, exact at the quarter turns (gravity at −90° has no x part)."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    quarter = np.remainder(deg, 90.0) == 0.0
    return np.where(quarter, np.round(c), c), np.where(quarter, np.round(s), s)


class _Rows:
    """The solved description's values per row, in SI units."""

    def __init__(self, solved: Mapping, n: int, metres: float):
        self.solved, self.n, self.m = solved, n, metres

    def array(self, key: str) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.solved[key], dtype=float), (self.n,))

    def vector(self, spec: tuple[str, str, str]) -> tuple[np.ndarray, np.ndarray]:
        kind, a, b = spec
        if kind == "polar":
            c, s = _cos_sin(self.array(b))
            return self.array(a) * c, self.array(a) * s
        return self.array(a), self.array(b)

    def position(self, point: str) -> tuple[np.ndarray, np.ndarray]:
        return tuple(np.broadcast_to(np.asarray(c, dtype=float) * self.m, (self.n,))
                     for c in self.solved["points"][point])

    def rate(self, kind: str, point: str) -> tuple[np.ndarray, np.ndarray]:
        """A point's velocity (kind "v") or acceleration ("a"), m/s or m/s²; a ground point
        is still."""
        if f"{kind}x_{point}" not in self.solved:
            return np.zeros(self.n), np.zeros(self.n)
        return (self.array(f"{kind}x_{point}") * self.m, self.array(f"{kind}y_{point}") * self.m)

    def direction(self, line: tuple) -> tuple[np.ndarray, np.ndarray]:
        """The unit vector along a pair's line (see _Pair, its degrees evaluated) per row."""
        if line[0] == "fixed":
            return _cos_sin(self.array(line[1]))
        if line[0] == "column":
            angle = self.array(line[1])
        else:
            (ux, uy), (vx, vy) = self.position(line[1]), self.position(line[2])
            angle = np.arctan2(vy - uy, vx - ux) + np.radians(self.array(line[3]))
        return np.cos(angle), np.sin(angle)

    def angular_acceleration(self, body: _Body | None) -> np.ndarray:
        """α of a body, from the motion of its first two joints: for r = P1 − P0,
        Δa = α k×r − ω² r, so α = r×Δa / |r|². A block turns with its guide (a block on a
        fixed line, the ground, does not turn); a slide's link as its line's column, whose
        rates stay defined where its two joints meet (a slide of offset zero)."""
        if body is None:
            return np.zeros(self.n)
        if body.block:
            return self.angular_acceleration(body.guide)
        if body.spin is not None:
            return self.array("alpha_" + body.spin)
        (x0, y0), (x1, y1) = self.position(body.joints[0]), self.position(body.joints[1])
        (a0, b0), (a1, b1) = self.rate("a", body.joints[0]), self.rate("a", body.joints[1])
        rx, ry = x1 - x0, y1 - y0
        return _cross(rx, ry, a1 - a0, b1 - b0) / (rx * rx + ry * ry)


# --------------------------------------------------------------------------------------------
# The equations: 3 per moving body, all bodies at once, per row
# --------------------------------------------------------------------------------------------

def _cross(px, py, fx, fy):
    return px * fy - py * fx


@dataclass
class _Reaction:
    """An unknown force of body i on body j at a point: a pin's, its x and y unknown (cols),
    or a guide's or a slot's, N along a unit normal (one col), with a guide's couple M."""
    i: int
    j: int
    point: str
    key: str                                    # F{i}{j}
    cols: tuple[int, ...]
    normal: tuple[np.ndarray, np.ndarray] | None = None
    couple: int | None = None


class _System:
    """A·x = b per row: for each moving body its ΣFx, ΣFy and ΣM about its first joint O:
    Σ(unknown loads) = m·a_G − Σ(known loads), the moment with I·α + (G − O)×m·a_G."""

    def __init__(self, top: _Topology, rows: _Rows):
        self.rows = rows
        self.k = 3 * len(top.bodies)
        self.first = {b.number: 3 * i for i, b in enumerate(top.bodies)}
        self.origin = {b.number: rows.position(b.joints[0]) for b in top.bodies}
        self.A = np.zeros((rows.n, self.k, self.k))
        self.b = np.zeros((rows.n, self.k))
        # where a value of the description (a load, a mass) is an error: its equations' b
        self.errors = np.zeros((rows.n, self.k), dtype=bool)
        self.names: list[str] = []
        self.reactions: list[_Reaction] = []
        self.effort = ""                # the input's unknown: T12 or F_in

    def unknown(self, name: str) -> int:
        self.names.append(name)
        return len(self.names) - 1

    def force(self, body: int, col: int, ux, uy, point: str, sign: float = 1.0) -> None:
        """Unknown col times the direction (ux, uy) acts on body at point."""
        if body == GROUND:
            return
        r, (ox, oy) = self.first[body], self.origin[body]
        px, py = self.rows.position(point)
        self.A[:, r, col] += sign * ux
        self.A[:, r + 1, col] += sign * uy
        self.A[:, r + 2, col] += sign * _cross(px - ox, py - oy, ux, uy)

    def couple(self, body: int, col: int, sign: float = 1.0) -> None:
        """Unknown col is a couple on body."""
        if body != GROUND:
            self.A[:, self.first[body] + 2, col] += sign

    def pin(self, i: int, j: int, point: str, key: str) -> None:
        """The force of body i on body j at the pin joining them, its x and y unknown, and
        its reaction on i."""
        cols = self.unknown(key + "x"), self.unknown(key + "y")
        for col, ux, uy in ((cols[0], 1.0, 0.0), (cols[1], 0.0, 1.0)):
            self.force(j, col, ux, uy, point)
            self.force(i, col, ux, uy, point, -1.0)
        self._add(_Reaction(i, j, point, key, cols))

    def across(self, i: int, j: int, point: str, tail: str, normal, couple: bool) -> None:
        """A guide's (couple = True) or a slot's force of body i on body j at its point, N
        along the unit normal (nx, ny); and its reaction on i."""
        col = self.unknown("N" + tail)
        self.force(j, col, *normal, point)
        self.force(i, col, *normal, point, -1.0)
        moment = None
        if couple:
            moment = self.unknown("M" + tail)
            self.couple(j, moment)
            self.couple(i, moment, -1.0)
        self._add(_Reaction(i, j, point, "F" + tail, (col,), normal, moment))

    def _add(self, reaction: _Reaction) -> None:
        if any(r.key == reaction.key for r in self.reactions):
            raise ValueError(f"two joints between the bodies {reaction.i} and {reaction.j} "
                             f"(at {reaction.point} and another): one key {reaction.key}")
        self.reactions.append(reaction)

    def known_force(self, body: int, fx, fy, px, py) -> None:
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] -= fx
        self.b[:, r + 1] -= fy
        self.b[:, r + 2] -= _cross(px - ox, py - oy, fx, fy)

    def note_errors(self, body: int, value, equations: tuple[int, ...] = (0, 1, 2)) -> None:
        """The equations of a body that a value of the description enters, where it is an
        error (NaN): those rows' unknowns it reaches are NaN, the others stand."""
        for e in equations:
            self.errors[:, self.first[body] + e] |= np.isnan(value)

    def known_couple(self, body: int, torque) -> None:
        self.b[:, self.first[body] + 2] -= torque

    def inertia(self, body: int, mass, gx, gy, ax, ay) -> None:
        """m·a_G on the right: ΣF = m·a_G, ΣM_O = (G − O)×m·a_G (+ I·α, a known_couple)."""
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] += mass * ax
        self.b[:, r + 1] += mass * ay
        self.b[:, r + 2] += _cross(gx - ox, gy - oy, mass * ax, mass * ay)


def _equations(top: _Topology, loads: _Loads, rows: _Rows) -> _System:
    system = _System(top, rows)
    for i, body, point in _pins(top):
        system.pin(i, body.number, point, "F" + top.pair(i, body.number))
    for pair in top.pairs:           # a guide: across its line and a couple; a slot: across it
        j = pair.block.number
        sides = [(pair.guide, "line", True)] + [(pair.slotted, "slot", False)] * bool(pair.slot)
        for other, which, couple in sides:
            c, s = rows.direction(loads.lines[j, which])
            i = _number(other)
            system.across(i, j, pair.point, top.pair(i, j), (-s, c), couple)
    _input_equations(top, system, rows)
    _load_equations(top, loads, rows, system)
    return system


def _actuator_line(top: _Topology, rows: _Rows) -> tuple[np.ndarray, np.ndarray]:
    """The unit vector from the actuator's end P to its end R."""
    (px, py), (rx, ry) = (rows.position(p) for p in top.actuator)
    length = np.hypot(rx - px, ry - py)
    return (rx - px) / length, (ry - py) / length


def _input_equations(top: _Topology, system: _System, rows: _Rows) -> None:
    if top.crank is not None:
        system.effort = "T" + top.pair(GROUND, top.crank.number)
        system.couple(top.crank.number, system.unknown(system.effort))
    elif top.actuator is not None:
        (p, r), col = top.actuator, system.unknown("F_in")
        system.effort = "F_in"
        ux, uy = _actuator_line(top, rows)
        system.force(_host(top, r).number, col, ux, uy, r)
        if p not in top.fixed:
            system.force(_host(top, p).number, col, ux, uy, p, -1.0)
    else:
        raise ValueError("mechanism.input: neither a crank step nor a linear actuator")


def _load_equations(top: _Topology, loads: _Loads, rows: _Rows, system: _System) -> None:
    g = rows.vector(loads.gravity) if loads.gravity else (0.0, 0.0)
    for body in top.bodies:
        mass, inertia = (rows.array(k) for k in loads.masses[body.number])
        system.note_errors(body.number, mass)
        system.note_errors(body.number, inertia, (2,))
        system.known_couple(body.number, -inertia * rows.angular_acceleration(body))
        if body.centre is not None:
            (gx, gy), (ax, ay) = rows.position(body.centre), rows.rate("a", body.centre)
            system.inertia(body.number, mass, gx, gy, ax, ay)
            system.known_force(body.number, mass * g[0], mass * g[1], gx, gy)
    for body, point, spec in loads.forces:
        fx, fy = rows.vector(spec)
        system.known_force(body.number, fx, fy, *rows.position(point))
        system.note_errors(body.number, fx + fy)
    for body, key in loads.torques:
        system.known_couple(body.number, rows.array(key))
        system.note_errors(body.number, rows.array(key), (2,))


def _solve_rows(A: np.ndarray, b: np.ndarray, errors: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """x with A·x = b on every row, and each row's condition number. Rows and columns are
    scaled by their largest entries first (forces and moments, metres and ones); a row with a
    NaN or a condition number above SINGULAR is NaN, but for a NaN in b where a value of the
    description is an error (`errors`): that makes NaN only the unknowns it reaches
    (_reaches)."""
    n, k = b.shape
    finite = np.isfinite(A).all(axis=(1, 2)) & (np.isfinite(b) | errors).all(axis=1)
    missing = ~np.isfinite(b) & finite[:, None]
    A = np.where(finite[:, None, None], A, np.eye(k))
    big = np.maximum(np.abs(A).max(axis=2), np.finfo(float).tiny)
    A, b = A / big[..., None], np.where(finite[:, None] & ~missing, b, 0.0) / big
    col = np.maximum(np.abs(A).max(axis=1, keepdims=True), np.finfo(float).tiny)
    A = A / col
    cond = np.linalg.cond(A) if n else np.zeros(0)
    ok = finite & (cond < SINGULAR)
    structure = (A[ok] != 0).any(axis=0)
    A = np.where(ok[:, None, None], A, np.eye(k))
    y = np.linalg.solve(A, np.where(ok[:, None], b, 0.0)[..., None])[..., 0]
    x = y / col[:, 0, :]
    x[~ok] = np.nan
    x[(missing & ok[:, None]).astype(float) @ _reaches(structure).T > 0] = np.nan
    return x, np.where(finite, cond, np.nan)


def _reaches(structure: np.ndarray) -> np.ndarray:
    """Which unknowns each equation's known side reaches: x_i depends on b_j where (A⁻¹)_ij
    is not zero for a matrix of the system's structure (its entries that are not zero on some
    row) with generic values. A term that is zero on one row only (a moment arm where a crank
    lies on the line) still counts: the book's formula reads that load there too."""
    # values in [1, 2) with no relation between them (multiples of the golden ratio, whole
    # turns dropped; numpy.random stays unimported, as verify's start-up wants it)
    spread = (np.arange(1, structure.size + 1) * 0.6180339887498949 % 1.0 + 1.0)
    generic = np.where(structure, np.sqrt(spread).reshape(structure.shape), 0.0)
    try:
        inverse = np.abs(np.linalg.inv(generic))
    except np.linalg.LinAlgError:      # no row solves: nothing to spare
        return np.ones(structure.shape, dtype=bool)
    return inverse > 1e-9 * inverse.max()


# --------------------------------------------------------------------------------------------
# The answer
# --------------------------------------------------------------------------------------------

def _shake(shaking, fx, fy, at):
    """The ground pushes the links with (fx, fy) at `at`: they push it back."""
    sx, sy, sm = shaking
    return sx - fx, sy - fy, sm - _cross(at[0], at[1], fx, fy)


def _report(top: _Topology, system: _System, x: np.ndarray) -> dict:
    rows, out, joints = system.rows, {}, {}
    shaking = (np.zeros(rows.n), np.zeros(rows.n), np.zeros(rows.n))
    for r in system.reactions:
        if r.normal is None:                            # a pin
            fx, fy = x[:, r.cols[0]], x[:, r.cols[1]]
            out[r.key] = np.hypot(fx, fy)
        else:                                           # a guide or a slot: N across its line
            normal = out["N" + r.key[1:]] = x[:, r.cols[0]]
            fx, fy = r.normal[0] * normal, r.normal[1] * normal
            out[r.key] = np.abs(normal)
        out[r.key + "x"], out[r.key + "y"], joints[r.key] = fx, fy, r.point
        couple = np.zeros(rows.n) if r.couple is None else x[:, r.couple]
        if r.couple is not None:
            out["M" + r.key[1:]] = couple
        if r.i == GROUND:
            sx, sy, sm = _shake(shaking, fx, fy, rows.position(r.point))
            shaking = sx, sy, sm - couple
    effort = out[system.effort] = x[:, system.names.index(system.effort)]
    sx, sy, sm = shaking
    if top.crank is not None:
        sm = sm - effort                                # the motor's stator turns the other way
    elif top.actuator[0] in top.fixed:
        ux, uy = _actuator_line(top, rows)
        sx, sy, sm = _shake((sx, sy, sm), effort * ux, effort * uy,
                            rows.position(top.actuator[0]))
    out.update(shaking_x=sx, shaking_y=sy, shaking=np.hypot(sx, sy), shaking_moment=sm)
    for body in top.bodies:          # each centre of mass: where it is, how it accelerates
        if body.centre is not None and not body.block:
            x, y = (np.broadcast_to(np.asarray(c, dtype=float), (rows.n,))
                    for c in rows.solved["points"][body.centre])
            ax, ay = (a / rows.m for a in rows.rate("a", body.centre))
            n = body.number
            out[f"xG{n}"], out[f"yG{n}"], out[f"axG{n}"], out[f"ayG{n}"] = x, y, ax, ay
    out["bodies"] = {b.number: tuple(b.joints) for b in top.bodies}
    out["joints"] = joints
    return out


def forces(description: Mapping, params: Mapping[str, float], angles_deg,
           length_unit: str = "m", turns: Mapping[str, np.ndarray] | None = None) -> dict:
    """Dynamic force analysis of a described mechanism at each input (degrees for a crank, the
    length for an actuator; 1-D array-like), as the module's docstring says.

    description: the [mechanism] table as parsed by tomllib, with its dynamics; params:
    {parameter symbol: value}, the input's speed and acceleration among them (omega_in and
    alpha_in, or v_in and a_in); length_unit: the template's (mm, cm, m, in, ft); turns: as
    the kinematic reference's (an expression reads each angle in the turn a book shows).

    Raises ValueError for a description it cannot analyse (a body entry naming no link, links
    that do not make a mechanism of one degree of freedom, a slotted link written with a
    `vector` step, ...)."""
    if length_unit not in LENGTH_UNITS:
        raise ValueError(f"length_unit must be one of {sorted(LENGTH_UNITS)}")
    rates = _RATES[(description.get("input") or {}).get("kind", "angle")]
    if not all(name in params for name in rates):
        raise ValueError(f"force analysis needs the input's speed and acceleration: the "
                         f"parameters {rates[0]} and {rates[1]}")
    top = topology(description)
    loads = _read_loads(description, top)
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    rows = _Rows(solve(loads.described(), params, angles, turns, late=loads.values),
                 len(angles), LENGTH_UNITS[length_unit])
    with np.errstate(invalid="ignore", divide="ignore"):
        system = _equations(top, loads, rows)
        x, cond = _solve_rows(system.A, system.b, system.errors)
        for r in system.reactions:      # a guide's couple is NaN where its force is (the book's)
            if r.couple is not None:
                x[np.isnan(x[:, r.cols[0]]), r.couple] = np.nan
        return {**_report(top, system, x), "cond": cond}
