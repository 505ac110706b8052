"""The force reference's values: what acts on the bodies (masses, centres, gravity, loads) as
keys of the description the kinematic reference solves, and those values per row in SI units
(check/forces/__init__.py says how).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .topology import Body, Topology, body_of, host

_OWN = "forces__"     # the points and keys this module adds to the description start so
_CENTRE_KEYS = ("frame", "local", "distances", "side", "distance", "angle")


def cross(px, py, fx, fy):
    return px * fy - py * fx


@dataclass
class Loads:
    """What acts on the bodies, as keys of the solved description: each value a formula the
    reference's parser evaluates after the rates, per row where it names a column or a rate
    (`values`: solve's `late`); a centre of mass a `point` step appended to the description,
    and so moving with the rest. A vector is ("xy", x, y) or ("polar", magnitude, angle in
    degrees)."""
    description: Mapping
    steps: list[dict] = field(default_factory=list)
    values: dict[str, object] = field(default_factory=dict)
    gravity: tuple[str, str, str] | None = None
    forces: list[tuple[Body, str, tuple[str, str, str]]] = field(default_factory=list)
    torques: list[tuple[Body, str]] = field(default_factory=list)
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
        """A pair's line (see Pair) with its degrees as a key."""
        return (*spec[:-1], self.value(spec[-1], what)) if spec[0] != "column" else spec

    def centre(self, body: Body, spec: Mapping, what: str) -> str:
        frame = spec.get("frame")
        if not isinstance(frame, (list, tuple)) or not body.names(set(map(str, frame))):
            raise ValueError(f"{what}.frame must be two joints of the body {body.joints}")
        name = f"{_OWN}G{body.number}"
        self.steps.append({"type": "point", "point": name,
                           **{k: spec[k] for k in _CENTRE_KEYS if k in spec}})
        return name

    def described(self) -> dict:
        return {**self.description,
                "steps": list(self.description.get("steps") or []) + self.steps}


def _read_bodies(loads: Loads, top: Topology) -> None:
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


def read_loads(description: Mapping, top: Topology) -> Loads:
    loads = Loads(description)
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
            body = body_of(top, load["body"], what) if "body" in load else host(top, at)
            if at not in body.joints:
                raise ValueError(f"{what}: the link {body.joints} does not hold {at!r}")
            loads.forces.append((body, at, loads.vector(load["force"], f"{what}.force")))
        elif "body" in load and "torque" in load:
            loads.torques.append((body_of(top, load["body"], what),
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


class Rows:
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
        """The unit vector along a pair's line (see Pair, its degrees evaluated) per row."""
        if line[0] == "fixed":
            return _cos_sin(self.array(line[1]))
        if line[0] == "column":
            angle = self.array(line[1])
        else:
            (ux, uy), (vx, vy) = self.position(line[1]), self.position(line[2])
            angle = np.arctan2(vy - uy, vx - ux) + np.radians(self.array(line[3]))
        return np.cos(angle), np.sin(angle)

    def angular_acceleration(self, body: Body | None) -> np.ndarray:
        """α of a body, from the motion of its first two joints: for r = P1 − P0,
        Δa = α k×r − ω² r, so α = r×Δa / |r|². A slotted link of one joint, from its frame:
        the pin P1 slides along r = |r| e^{iθ}, so r×Δa = α |r|² + 2 (r·Δv) ω, ω = r×Δv / |r|².
        A block turns with its guide (a block on a fixed line, the ground, does not turn); a
        slide's link as its line's column, whose rates stay defined where its two joints meet
        (a slide of offset zero)."""
        if body is None:
            return np.zeros(self.n)
        if body.block:
            return self.angular_acceleration(body.guide)
        if body.spin is not None:
            return self.array("alpha_" + body.spin)
        p0, p1 = body.joints[:2] if len(body.joints) > 1 else body.frames[0]
        (x0, y0), (x1, y1) = self.position(p0), self.position(p1)
        (a0, b0), (a1, b1) = self.rate("a", p0), self.rate("a", p1)
        rx, ry = x1 - x0, y1 - y0
        r2 = rx * rx + ry * ry
        if len(body.joints) > 1:
            return cross(rx, ry, a1 - a0, b1 - b0) / r2
        (u0, w0), (u1, w1) = self.rate("v", p0), self.rate("v", p1)
        omega = cross(rx, ry, u1 - u0, w1 - w0) / r2
        return (cross(rx, ry, a1 - a0, b1 - b0)
                - 2.0 * omega * (rx * (u1 - u0) + ry * (w1 - w0))) / r2
