"""Independent force reference: the driving effort, every pin load and the shaking force of a
described mechanism, from the Newton–Euler equations of all its moving links solved at once.

The description is a template's ``[mechanism]`` table (docs/language.md) with its dynamics:

    [mechanism.dynamics]
    gravity = { g = "g", angle = -90 }      # m/s², direction in degrees from +x (default −90);
                                            # no gravity table: no gravity
    [[mechanism.bodies]]                    # one per moving link that has mass
    joints = ["A", "B", "C"]                # the points the link holds
    block = false                           # true: a slider's block, its centre at its point
    mass = "m3"                             # kg
    centre = { frame = ["A", "B"], distance = "g3", angle = 0 }   # placed as a `point` step
    inertia = "I3"                          # kg·m² about the centre of mass
    [[mechanism.loads]]
    at = "C"; force = ["Fx", "Fy"]          # N; or force = { magnitude = "F", angle = "beta" }
    body = ["B0", "B"]; torque = "T4"       # N·m, counter-clockwise, on the body holding these

Every value is a number, a parameter or an expression; it may also name the columns of the steps.
Lengths are in the template's ``length_unit``, converted to metres once: forces come out in N,
moments in N·m.

Why it is independent: it reads the topology from the description and assembles the equations
from the constraints, 3 per moving body (ΣF = m·a_G, ΣM = I_G·α, d'Alembert's form), with the
reactions as unknowns, and solves them with numpy row by row; the only thing it takes from
linkbook is the kinematic reference's public ``solve`` (the motion of every point, and its own
parser for the expressions). No closed form of the workbook's is used.

Topology. The rigid bodies are the sets of points that move together: each ``links`` entry,
each step's links (a crank's pivot and pin, a dyad's two sides, a slider's rod; a carried point
joins the body of its frame, or, by ``distances`` on a frame that is no body, makes two links);
sets sharing two points are one body, and cranks on one pivot are one body. A ``bodies`` entry
gives one of them its mass: the body holding its joints. A slider's point carries a block, a body of its own sliding on a fixed line. The side of a
dyad that is the linear actuator's length is no body: a massless member of unknown force.
``slide`` and ``slot`` steps and sliders on a moving line are refused (ValueError).

Numbering, as the textbook's: the ground is 1, the crank 2, then the other bodies in the order of
the ``links`` entries, then those only the steps or ``bodies`` name, then the blocks.

What ``forces`` returns (arrays over the rows; i < j body numbers, written together as "23", or
with "_" between them, "2_13", in a mechanism of ten bodies or more):

- ``T12``: the driving torque of the ground (the motor) on the crank 2, counter-clockwise
  positive; for a linear actuator ``F_in``: its force, positive pushing its two ends apart;
- ``F{i}{j}x``, ``F{i}{j}y``: the force of body i on body j at the pin that joins them, and its
  magnitude ``F{i}{j}``. A pin held by more than two bodies is carried by the lowest-numbered
  of them (the ground at a ground point): each other body j gets F{that}{j};
- for a block j: ``N1{j}``, the guide's force on it along the line turned +90°; ``M1{j}``, the
  guide's couple on it; ``F1{j}x``, ``F1{j}y``, ``F1{j}``: that force as a vector, its size;
- ``shaking_x``, ``shaking_y``, ``shaking``: the force the moving links exert on the ground
  (through the ground pins, the guides and the actuator's ground end); ``shaking_moment``: its
  moment about the frame's origin, the motor's reaction −T12 included;
- ``cond``: the condition number of each row's equilibrated system. A row is NaN where a position
  or a rate is NaN, or where the system is singular (cond above SINGULAR);
- ``bodies``: {number: the body's joints}; ``joints``: {reaction key F{i}{j}: its point}.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .reference import solve

__all__ = ["forces", "LENGTH_UNITS", "SINGULAR"]

LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}
SINGULAR = 1e12       # a row's system with a larger condition number has no reliable solution
GROUND = 1
# Points and keys this module adds to the description it hands to solve() start with this.
_OWN = "forces__"
_UNSUPPORTED = ("slide", "slot")
_CENTRE_KEYS = ("frame", "local", "distances", "side", "distance", "angle")


@dataclass
class _Body:
    joints: list[str]
    rank: int                       # the order in which the description names it
    block: bool = False
    spec: Mapping | None = None     # its `bodies` entry: mass, centre, inertia
    number: int = 0
    centre: str | None = None       # the name of its centre of mass among the solved points


@dataclass
class _Topology:
    bodies: list[_Body]
    fixed: set[str]                             # the ground's points
    crank: _Body | None                         # the body the motor turns
    actuator: tuple[str, str] | None            # (P, R): the actuator pushes R away from P
    lines: dict[str, object] = field(default_factory=dict)   # block point: direction (degrees)


# --------------------------------------------------------------------------------------------
# Topology: the bodies, from the links, the steps and the bodies entries
# --------------------------------------------------------------------------------------------

def _where(k: int, step: Mapping) -> str:
    return f"steps[{k}] ({step.get('type')} {step.get('point', step.get('key', ''))})"


def _merge(groups: list[_Body]) -> list[_Body]:
    """Groups sharing two points or more are one rigid body: merged into the one named first."""
    out = sorted(groups, key=lambda g: g.rank)
    merged = True
    while merged:
        merged = False
        for a in range(len(out)):
            for b in range(a + 1, len(out)):
                if len(set(out[a].joints) & set(out[b].joints)) >= 2:
                    out[a].joints += [p for p in out[b].joints if p not in out[a].joints]
                    del out[b]
                    merged = True
                    break
            if merged:
                break
    return out


def _refuse_unsupported(steps: Sequence[Mapping]) -> None:
    for k, step in enumerate(steps):
        kind = step.get("type")
        if kind in _UNSUPPORTED:
            raise ValueError(f"{_where(k, step)}: force analysis of a {kind} step is not "
                             "supported yet")
        if kind == "slider" and "along" in step:
            raise ValueError(f"{_where(k, step)}: force analysis of a slider on a moving line "
                             "is not supported yet")


def _actuator(description: Mapping) -> tuple[str, str] | None:
    """(P, R) of the dyad side whose length is the linear actuator's input, if any."""
    inp = description.get("input") or {}
    if inp.get("kind", "angle") != "length":
        return None
    for step in description.get("steps") or []:
        if step.get("type") == "dyad":
            for end, side in (("p", "p_length"), ("q", "q_length")):
                if step.get(side) == inp.get("key"):
                    return str(step[end]), str(step["point"])
    raise ValueError("mechanism.input: no dyad side is the actuator's length "
                     f"{inp.get('key')!r}")


def _step_groups(steps: Sequence[Mapping], actuator, first_rank: int
                 ) -> tuple[list[_Body], dict[str, object], str | None, list[str]]:
    """The links the crank, dyad and slider steps imply (the cranks on one pivot are one body:
    they turn together), the blocks' lines, the crank's pivot and its pins."""
    groups, lines, pivot, pins = [], {}, None, []
    for k, step in enumerate(steps):
        kind, point = step.get("type"), step.get("point")
        if kind == "crank":
            if pivot is not None and step["pivot"] != pivot:
                raise ValueError(f"{_where(k, step)}: a second crank on another pivot")
            pivot = str(step["pivot"])
            pins.append(str(point))
            sides = [] if len(pins) > 1 else [(pivot, point)]
        elif kind == "dyad":
            sides = [(step[end], point) for end in ("p", "q")
                     if {step[end], point} != set(actuator or ())]
        elif kind == "slider":
            sides = [(step["p"], point)]
            lines[str(point)] = step.get("direction", 0.0)
        else:
            continue
        for a, b in sides:
            groups.append(_Body([str(a), str(b)], first_rank + len(groups)))
    crank = next((g for g in groups if g.joints[0] == pivot), None)
    if crank is not None:
        crank.joints = [pivot, *pins]
    return groups, lines, pivot, pins


def _drawn_groups(description: Mapping, actuator) -> list[_Body]:
    groups = []
    for rank, link in enumerate(description.get("links") or []):
        joints = list(dict.fromkeys(str(p) for p in link))
        if len(joints) >= 2 and set(joints) != set(actuator or ()):
            groups.append(_Body(joints, rank))
    return groups


def _carry_points(steps: Sequence[Mapping], groups: list[_Body], fixed: set[str]
                  ) -> list[_Body]:
    """Each carried point joins the body of its frame, in step order (a point on the ground's
    frame is fixed)."""
    for k, step in enumerate(steps):
        if step.get("type") != "point":
            continue
        a, b = (str(p) for p in step["frame"])
        point = str(step["point"])
        if a in fixed and b in fixed:
            fixed.add(point)
            continue
        host = next((g for g in groups if a in g.joints and b in g.joints), None)
        if host is not None:
            if point not in host.joints:
                host.joints.append(point)
        elif "distances" in step:          # the frame stretches: two links, as a dyad's
            rank = max(g.rank for g in groups) + 1
            groups += [_Body([a, point], rank), _Body([b, point], rank + 1)]
        else:
            raise ValueError(f"{_where(k, step)}: its frame {a}→{b} is no rigid link")
        groups = _merge(groups)
    return groups


def _number(groups: list[_Body], blocks: list[_Body], pivot: str | None,
            crank_pins: list[str]) -> _Body | None:
    """Number the bodies: the crank 2, the others in the order the description names them,
    the blocks last; the crank is returned."""
    crank = None
    if pivot is not None:
        crank = next(g for g in groups if {pivot, *crank_pins} <= set(g.joints))
    ordered = ([crank] if crank else []) + [g for g in groups if g is not crank] + blocks
    for number, body in enumerate(ordered, start=GROUND + 1):
        body.number = number
    return crank


def _attach_entries(entries: Sequence[Mapping], groups: list[_Body],
                    blocks: dict[str, _Body]) -> None:
    """Each `bodies` entry's mass, centre and inertia go to the body it names."""
    for k, entry in enumerate(entries):
        joints = [str(p) for p in entry.get("joints") or []]
        if entry.get("block", False):
            if len(joints) != 1 or joints[0] not in blocks:
                raise ValueError(f"mechanism.bodies[{k}]: a block is [point] of a slider step")
            if "centre" in entry:
                raise ValueError(f"mechanism.bodies[{k}]: a block's centre is its point")
            body = blocks[joints[0]]
        else:
            body = next((g for g in groups if len(joints) > 1 and set(joints) <= set(g.joints)),
                        None)
            if body is None:
                raise ValueError(f"mechanism.bodies[{k}]: {joints} is no moving link of the "
                                 "steps and links (a slider's block: block = true)")
        if body.spec is not None:
            raise ValueError(f"mechanism.bodies[{k}]: a second entry for the body {body.joints}")
        body.spec = entry


def topology(description: Mapping) -> _Topology:
    """The moving bodies of a description, numbered (see the module's docstring)."""
    steps = list(description.get("steps") or [])
    entries = list(description.get("bodies") or [])
    _refuse_unsupported(steps)
    actuator = _actuator(description)
    fixed = {str(p) for p in (description.get("ground") or {})}
    drawn = _drawn_groups(description, actuator)
    implied, lines, pivot, crank_pins = _step_groups(steps, actuator, len(drawn))
    groups = _carry_points(steps, _merge(drawn + implied), fixed)
    groups = [g for g in groups if not set(g.joints) <= fixed]
    for g in groups:
        if len(set(g.joints) & fixed) >= 2:
            raise ValueError(f"the link {g.joints} is held by two ground points: it cannot move")
    blocks = {p: _Body([p], len(drawn) + len(implied), block=True) for p in lines}
    crank = _number(groups, list(blocks.values()), pivot, crank_pins)
    _attach_entries(entries, groups, blocks)
    return _Topology(groups + list(blocks.values()), fixed, crank, actuator, lines)


def _pins(top: _Topology) -> list[tuple[int, _Body, str]]:
    """(i, body j, point) for every pin: i the body carrying the pin (the ground at a ground
    point, else the lowest-numbered body holding it), j each other body holding it."""
    holders: dict[str, list[_Body]] = {}
    for body in top.bodies:
        for p in body.joints:
            holders.setdefault(p, []).append(body)
    pins = []
    for point, bodies in holders.items():
        bodies = sorted(bodies, key=lambda b: b.number)
        if point in top.fixed:
            pins += [(GROUND, b, point) for b in bodies]
        else:
            pins += [(bodies[0].number, b, point) for b in bodies[1:]]
    return pins


def _host(top: _Topology, point: str) -> _Body:
    """The lowest-numbered moving body holding a point (where a load or the actuator acts)."""
    holding = [b for b in top.bodies if point in b.joints]
    if not holding or point in top.fixed:
        raise ValueError(f"no moving link holds the point {point!r}")
    return min(holding, key=lambda b: b.number)


def _loaded(top: _Topology, point: str) -> _Body:
    """Where a force at a point acts: the block there (a piston's, a ram's), else the
    lowest-numbered moving body holding the point."""
    block = next((b for b in top.bodies if b.block and b.joints == [point]), None)
    return block or _host(top, point)


def _body_of(top: _Topology, joints: Sequence[str], what: str) -> _Body:
    """The body holding all these joints (the one holding exactly them where several do)."""
    wanted = {str(p) for p in joints}
    found = [b for b in top.bodies if wanted <= set(b.joints)]
    if len(found) > 1:
        found = [b for b in found if set(b.joints) == wanted]
    if len(found) != 1:
        raise ValueError(f"{what}: no single moving link holds {sorted(wanted)}")
    return found[0]


# --------------------------------------------------------------------------------------------
# The values: expressions and centres solved by the kinematic reference, per row
# --------------------------------------------------------------------------------------------

class _Extension:
    """The description with this module's own steps appended: one `expression` step per value
    (evaluated by the reference's parser, per row where it names a column) and one `point`
    step per centre of mass (its position, velocity and acceleration come with the others)."""

    def __init__(self, description: Mapping):
        self.description = description
        self.steps: list[dict] = []

    def value(self, formula: object, what: str) -> str:
        if isinstance(formula, bool) or not isinstance(formula, (int, float, str)):
            raise ValueError(f"{what}: expected a number or an expression, got {formula!r}")
        key = f"{_OWN}{len(self.steps)}"
        self.steps.append({"type": "expression", "key": key, "formula": formula})
        return key

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


def _direction(ext: _Extension, spec, what: str) -> tuple[str, str]:
    """A force's components as keys: [x, y], or {magnitude, angle (degrees)} (see _vector)."""
    if isinstance(spec, (list, tuple)) and len(spec) == 2:
        return ext.value(spec[0], f"{what}[0]"), ext.value(spec[1], f"{what}[1]")
    if isinstance(spec, Mapping) and "magnitude" in spec:
        return (ext.value(spec["magnitude"], f"{what}.magnitude"),
                ext.value(spec.get("angle", 0.0), f"{what}.angle") + "@")
    raise ValueError(f"{what} must be [x, y] or {{ magnitude, angle }}")


@dataclass
class _Loads:
    gravity: tuple[str, str] | None = None
    forces: list[tuple[_Body, str, tuple[str, str]]] = field(default_factory=list)
    torques: list[tuple[_Body, str]] = field(default_factory=list)
    masses: dict[int, tuple[str, str]] = field(default_factory=dict)   # number: (mass, inertia)


def _read_dynamics(description: Mapping, top: _Topology, ext: _Extension) -> _Loads:
    loads = _Loads()
    gravity = (description.get("dynamics") or {}).get("gravity")
    if gravity is not None:
        loads.gravity = _direction(ext, {"magnitude": gravity.get("g", 0.0),
                                         "angle": gravity.get("angle", -90.0)},
                                   "mechanism.dynamics.gravity")
    for body in top.bodies:
        spec = body.spec or {}
        what = f"mechanism.bodies (the link {body.joints})"
        loads.masses[body.number] = (ext.value(spec.get("mass", 0.0), f"{what}.mass"),
                                     ext.value(spec.get("inertia", 0.0), f"{what}.inertia"))
        if body.block:
            body.centre = body.joints[0]
        elif "centre" in spec:
            body.centre = ext.centre(body, spec["centre"], f"{what}.centre")
        elif "mass" in spec:
            raise ValueError(f"{what}: a mass needs its centre")
    for k, load in enumerate(description.get("loads") or []):
        what = f"mechanism.loads[{k}]"
        if "at" in load and "force" in load:
            body = _body_of(top, load["body"], what) if "body" in load else \
                _loaded(top, str(load["at"]))
            if str(load["at"]) not in body.joints:
                raise ValueError(f"{what}: the link {body.joints} does not hold {load['at']!r}")
            loads.forces.append((body, str(load["at"]), _direction(ext, load["force"], what)))
        elif "body" in load and "torque" in load:
            loads.torques.append((_body_of(top, load["body"], what),
                                  ext.value(load["torque"], f"{what}.torque")))
        else:
            raise ValueError(f"{what}: needs at and force, or body and torque")
    for point, direction in top.lines.items():
        top.lines[point] = ext.value(direction, f"the slider {point}'s direction")
    return loads


def _quarter_exact(deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of degrees, exact at the quarter turns (gravity at −90° has no x part)."""
    rad = np.radians(deg)
    c, s = np.cos(rad), np.sin(rad)
    quarter = np.remainder(deg, 90.0) == 0.0
    return np.where(quarter, np.round(c), c), np.where(quarter, np.round(s), s)


class _Rows:
    """The solved description's values per row, in SI units."""

    def __init__(self, solved: Mapping, n: int, metres: float, fixed: set[str]):
        self.solved, self.n, self.m, self.fixed = solved, n, metres, fixed

    def array(self, key: str) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.solved[key], dtype=float), (self.n,))

    def vector(self, keys: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
        if keys[1].endswith("@"):               # magnitude and angle in degrees
            size = self.array(keys[0])
            c, s = _quarter_exact(self.array(keys[1][:-1]))
            return size * c, size * s
        return self.array(keys[0]), self.array(keys[1])

    def position(self, point: str) -> tuple[np.ndarray, np.ndarray]:
        x, y = self.solved["points"][point]
        return (np.broadcast_to(np.asarray(x, dtype=float) * self.m, (self.n,)),
                np.broadcast_to(np.asarray(y, dtype=float) * self.m, (self.n,)))

    def rate(self, kind: str, point: str) -> tuple[np.ndarray, np.ndarray]:
        """A point's velocity (kind "v") or acceleration ("a"), m/s or m/s²."""
        if f"{kind}x_{point}" not in self.solved:
            if point in self.fixed:
                return np.zeros(self.n), np.zeros(self.n)
            raise ValueError("force analysis needs the input's speed and acceleration among "
                             "the parameters (omega_in and alpha_in, or v_in and a_in)")
        return (self.array(f"{kind}x_{point}") * self.m, self.array(f"{kind}y_{point}") * self.m)

    def turning(self, body: _Body) -> tuple[np.ndarray, np.ndarray]:
        """ω and α of a body, from the motion of its first two joints: for r = P1 − P0,
        Δv = ω k×r and Δa = α k×r − ω² r, so ω = r×Δv / |r|², α = r×Δa / |r|². A block on a
        fixed line does not turn."""
        if body.block:
            return np.zeros(self.n), np.zeros(self.n)
        (x0, y0), (x1, y1) = self.position(body.joints[0]), self.position(body.joints[1])
        (u0, v0), (u1, v1) = self.rate("v", body.joints[0]), self.rate("v", body.joints[1])
        (a0, b0), (a1, b1) = self.rate("a", body.joints[0]), self.rate("a", body.joints[1])
        rx, ry = x1 - x0, y1 - y0
        r2 = rx * rx + ry * ry
        return ((rx * (v1 - v0) - ry * (u1 - u0)) / r2, (rx * (b1 - b0) - ry * (a1 - a0)) / r2)


# --------------------------------------------------------------------------------------------
# The equations: 3 per moving body, all bodies at once, per row
# --------------------------------------------------------------------------------------------

def _cross(px, py, fx, fy):
    return px * fy - py * fx


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
        self.names: list[str] = []
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

    def couple(self, body: int, col: int) -> None:
        self.A[:, self.first[body] + 2, col] += 1.0

    def known_force(self, body: int, fx, fy, px, py) -> None:
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] -= fx
        self.b[:, r + 1] -= fy
        self.b[:, r + 2] -= _cross(px - ox, py - oy, fx, fy)

    def known_couple(self, body: int, torque) -> None:
        self.b[:, self.first[body] + 2] -= torque

    def inertia(self, body: int, mass, gx, gy, ax, ay, inertia, alpha) -> None:
        """m·a_G and I·α on the right: ΣF = m·a_G, ΣM_O = I·α + (G − O)×m·a_G."""
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] += mass * ax
        self.b[:, r + 1] += mass * ay
        self.b[:, r + 2] += inertia * alpha + _cross(gx - ox, gy - oy, mass * ax, mass * ay)


def _equations(top: _Topology, loads: _Loads, rows: _Rows, pins, names) -> _System:
    unknowns = 2 * len(pins) + 2 * sum(b.block for b in top.bodies) + 1
    if unknowns != 3 * len(top.bodies):
        raise ValueError(f"the description makes {unknowns} unknowns for "
                         f"{3 * len(top.bodies)} equations of {len(top.bodies)} moving links: "
                         "its links and steps do not make a mechanism of one degree of freedom")
    system = _System(top, rows)
    for i, body, point in pins:                       # the force of i on j, and its reaction
        x, y = system.unknown(names(i, body.number) + "x"), system.unknown("")
        for col, ux, uy in ((x, 1.0, 0.0), (y, 0.0, 1.0)):
            system.force(body.number, col, ux, uy, point)
            system.force(i, col, ux, uy, point, -1.0)
    for body in top.bodies:
        if body.block:                                # the guide: a normal force and a couple
            c, s = _quarter_exact(rows.array(top.lines[body.joints[0]]))
            normal = system.unknown("N" + names(GROUND, body.number))
            system.force(body.number, normal, -s, c, body.joints[0])
            system.couple(body.number, system.unknown("M" + names(GROUND, body.number)))
    _input_equations(top, system, rows)
    _load_equations(top, loads, rows, system)
    return system


def _input_equations(top: _Topology, system: _System, rows: _Rows) -> None:
    if top.crank is not None:
        system.effort = "T" + _pair(GROUND, top.crank.number, len(top.bodies))
        system.couple(top.crank.number, system.unknown(system.effort))
    elif top.actuator is not None:
        system.effort = "F_in"
        (p, r), col = top.actuator, system.unknown(system.effort)
        (px, py), (rx, ry) = rows.position(p), rows.position(r)
        length = np.hypot(rx - px, ry - py)
        ux, uy = (rx - px) / length, (ry - py) / length
        system.force(_host(top, r).number, col, ux, uy, r)
        if p not in top.fixed:
            system.force(_host(top, p).number, col, ux, uy, p, -1.0)
    else:
        raise ValueError("mechanism.input: neither a crank step nor a linear actuator")


def _load_equations(top: _Topology, loads: _Loads, rows: _Rows, system: _System) -> None:
    g = rows.vector(loads.gravity) if loads.gravity else (0.0, 0.0)
    for body in top.bodies:
        mass, inertia = (rows.array(k) for k in loads.masses[body.number])
        if body.centre is None:                      # no mass: only I·α, about any point
            system.known_couple(body.number, -inertia * rows.turning(body)[1])
            continue
        (gx, gy), (ax, ay) = rows.position(body.centre), rows.rate("a", body.centre)
        system.inertia(body.number, mass, gx, gy, ax, ay, inertia, rows.turning(body)[1])
        system.known_force(body.number, mass * g[0], mass * g[1], gx, gy)
    for body, point, keys in loads.forces:
        fx, fy = rows.vector(keys)
        system.known_force(body.number, fx, fy, *rows.position(point))
    for body, key in loads.torques:
        system.known_couple(body.number, rows.array(key))


def _solve_rows(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x with A·x = b on every row, and each row's condition number. Rows and columns are
    scaled by their largest entries first (forces and moments, metres and ones); a row with a
    NaN or a condition number above SINGULAR is NaN."""
    n, k = b.shape
    finite = np.isfinite(A).all(axis=(1, 2)) & np.isfinite(b).all(axis=1)
    A = np.where(finite[:, None, None], A, np.eye(k))
    b = np.where(finite[:, None], b, 0.0)
    big = np.abs(A).max(axis=2, keepdims=True)
    A, b = A / np.where(big > 0, big, 1.0), b / np.where(big[..., 0] > 0, big[..., 0], 1.0)
    col = np.abs(A).max(axis=1, keepdims=True)
    col = np.where(col > 0, col, 1.0)
    A = A / col
    cond = np.linalg.cond(A) if n else np.zeros(0)
    ok = finite & (cond < SINGULAR)
    y = np.linalg.solve(np.where(ok[:, None, None], A, np.eye(k)),
                        np.where(ok[:, None], b, 0.0)[..., None])[..., 0]
    x = y / col[:, 0, :]
    x[~ok] = np.nan
    return x, np.where(finite, cond, np.nan)


def _pair(i: int, j: int, count: int) -> str:
    return f"{i}{j}" if count + GROUND < 10 else f"{i}_{j}"


# --------------------------------------------------------------------------------------------
# The answer
# --------------------------------------------------------------------------------------------

def _report(top: _Topology, system: _System, x: np.ndarray, cond: np.ndarray, pins,
            names) -> dict:
    rows, out = system.rows, {}
    columns = {name: x[:, c] for c, name in enumerate(system.names)}
    sx, sy, sm = np.zeros(rows.n), np.zeros(rows.n), np.zeros(rows.n)
    joints: dict[str, str] = {}
    for c, (i, body, point) in enumerate(pins):
        key = "F" + names(i, body.number)
        fx, fy = x[:, 2 * c], x[:, 2 * c + 1]
        out[key + "x"], out[key + "y"], out[key] = fx, fy, np.hypot(fx, fy)
        joints[key] = point
        if i == GROUND:
            sx, sy, sm = _shake(sx, sy, sm, fx, fy, rows.position(point))
    for body in (b for b in top.bodies if b.block):
        tail = names(GROUND, body.number)
        normal, couple = columns["N" + tail], columns["M" + tail]
        c, s = _quarter_exact(rows.array(top.lines[body.joints[0]]))
        fx, fy = -s * normal, c * normal
        out["N" + tail], out["M" + tail] = normal, couple
        out["F" + tail + "x"], out["F" + tail + "y"], out["F" + tail] = fx, fy, np.abs(normal)
        joints["F" + tail] = body.joints[0]
        sx, sy, sm = _shake(sx, sy, sm - couple, fx, fy, rows.position(body.joints[0]))
    effort = system.effort
    out[effort] = columns[effort]
    if top.crank is not None:
        sm = sm - columns[effort]                       # the motor's stator turns the other way
    elif top.actuator[0] in top.fixed:
        (p, r), force = top.actuator, columns[effort]
        (px, py), (rx, ry) = rows.position(p), rows.position(r)
        length = np.hypot(rx - px, ry - py)
        sx, sy, sm = _shake(sx, sy, sm, force * (rx - px) / length, force * (ry - py) / length,
                            (px, py))
    out.update(shaking_x=sx, shaking_y=sy, shaking=np.hypot(sx, sy), shaking_moment=sm,
               cond=cond)
    out["bodies"] = {b.number: tuple(b.joints) for b in top.bodies}
    out["joints"] = joints
    return out


def _shake(sx, sy, sm, fx, fy, at):
    """The ground pushes the links with (fx, fy) at `at`: they push it back."""
    return sx - fx, sy - fy, sm - _cross(at[0], at[1], fx, fy)


def forces(description: Mapping, params: Mapping[str, float], angles_deg,
           length_unit: str = "m") -> dict:
    """Dynamic force analysis of a described mechanism at each input (degrees for a crank, the
    length for an actuator; 1-D array-like), as the module's docstring says.

    description: the [mechanism] table as parsed by tomllib, with its dynamics; params:
    {parameter symbol: value}, the input's speed and acceleration among them (omega_in and
    alpha_in, or v_in and a_in); length_unit: the template's (mm, cm, m, in, ft).

    Raises ValueError for a description it cannot analyse (a slide or slot step, a body entry
    naming no link, links that do not make a mechanism of one degree of freedom, ...)."""
    if length_unit not in LENGTH_UNITS:
        raise ValueError(f"length_unit must be one of {sorted(LENGTH_UNITS)}")
    top = topology(description)
    ext = _Extension(description)
    loads = _read_dynamics(description, top, ext)
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    solved = solve(ext.described(), params, angles)
    rows = _Rows(solved, len(angles), LENGTH_UNITS[length_unit], top.fixed)
    pins = _pins(top)

    def names(i: int, j: int) -> str:
        return _pair(i, j, len(top.bodies))

    with np.errstate(invalid="ignore", divide="ignore"):
        system = _equations(top, loads, rows, pins, names)
        x, cond = _solve_rows(system.A, system.b)
        return _report(top, system, x, cond, pins, names)
