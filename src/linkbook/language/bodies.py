"""The links of a mechanism as the force writer sees them, and what acts on each: the rigid
bodies the description implies (numbered as the textbook numbers links), their masses placed at
their centres, gravity and the loads the description names (docs/language.md, "Mass, gravity
and loads"). The writer (forces.py) solves the groups; this part says what is known of them.
Each step type says what it makes of the bodies in its own module (steps package, `topology`:
its links, its carried point, its block); here they are gathered and merged.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from .excel import (PRODUCT, SUM, ZERO, Expr, angle_of_triangle_or_na, lin, local_point,
                    mul, plus, radians, sq, turned)
from .expressions import expression
from .fields import as_table
from .mechanisms import TO_METRES
from .model import ACCEL, LENGTH, DescriptionError
from .steps import STEPS
from .steps.step_type import Block, slotted

GROUND = 1
# what can make a value another error than #N/A: a division (but by a whole number), a power
# (but a whole one), ATAN2(0, 0)
_CAN_FAIL = re.compile(r"[/^](?![1-9]\d*(?![\d.E]))|ATAN2\(")
METRES = TO_METRES           # the named cell of metres per length unit
METRES_REF = f"{{{METRES}}}"    # the placeholder of that cell in a formula


@dataclass
class Body:
    """One moving link: the points it holds, and what is known to act on it so far. A block
    (a step's sliding pair, docs/language.md "Sliding pairs") holds one point and slides on
    its guide: the link holding `guide`'s points (none: the ground), along `line` (cos, sin),
    turning with it at `spin` (ω, α; None on a fixed line). `frames`: directions (A, B) that
    turn with a link beside its joints' (a slotted link's, its pivot to the pin in its slot):
    it holds A and B as a frame, to carry points and a centre, not as pins."""
    joints: list[str]
    rank: int
    frames: list[tuple[str, str]] = field(default_factory=list)
    block: bool = False
    number: int = 0
    forces: list[tuple[str, str, str]] = field(default_factory=list)   # (Fx, Fy, at point)
    couples: list[str] = field(default_factory=list)                  # N·m
    guide: tuple[str, ...] = ()
    line: tuple[str, str] = ("1", "0")
    spin: tuple[str, str] | None = None

    def holds(self, *points: str) -> bool:
        """Are these its joints, or the two points of one of its frames?"""
        return (all(p in self.joints for p in points) or
                any(set(points) == set(f) for f in self.frames))

    def names(self, points: set[str]) -> bool:
        """Do these points, two or more, name it (its joints and its frames' points)?"""
        return len(points) > 1 and points <= {*self.joints, *(p for f in self.frames for p in f)}


class BodiesAndLoads:
    """The force writer's first half, a value it holds: the bodies the steps and the links
    make, and their known loads. It reads the compiler `c` and the motion writer `w`, and
    writes its columns (the centres of mass) through `add`, the force writer's, which keeps
    their place in the sheet."""

    def __init__(self, compiler, motion, add):
        self.c, self.w, self.add = compiler, motion, add
        self.model, self.field = compiler.model, compiler.field
        data = compiler.data
        self.entries = data.get("bodies") or []
        self.loads = data.get("loads") or []
        self.dynamics = as_table(f"{self.field}.dynamics", data.get("dynamics") or {})
        self.centres: dict[str, tuple[str, str]] = {}     # "G3": (x, y) texts
        length_input = f"{{{compiler.input_key}}}" if compiler.swept else None
        self.made = slotted([(rec, STEPS[rec["type"]].topology(rec, length_input))
                             for rec in compiler.records])
        # (END, N) of the dyad side that is the linear actuator's length
        self.actuator = next((m.actuator for _, m in self.made if m.actuator is not None), None)
        self.bodies: list[Body] = []
        self.fixed: set[str] = set()
        self.crank_joints: list[str] | None = None

    def holders(self, point: str) -> list[Body]:
        return [b for b in self.bodies if point in b.joints]

    def find(self) -> None:
        """The moving bodies, numbered, and the ground's points (`fixed`)."""
        self.bodies = self._bodies()

    def load(self) -> None:
        """Each body's weight and inertia, then the loads the description names."""
        self._masses()
        self._loads()

    def expr(self, where: str, raw: object) -> str:
        """A mass, an inertia or a load as formula text, #N/A where its value is an error (a
        division by zero on some row): verify's reference has no other error."""
        text = self.expression(where, raw).text
        return f"IFERROR({text},NA())" if _CAN_FAIL.search(text) else text

    def expression(self, where: str, raw: object, constant: bool = False):
        """A value of the force keys: what an `expression` step may name, and to_metres; a
        `constant` one (a centre's place, gravity) the parameters and to_metres alone."""
        known = self.c.symbols | {METRES}
        if not constant:
            known |= self.c.swept | {q.key for q in self.model.quantities}
        return expression(where, raw, known)

    def _drawn(self) -> list[list[str]]:
        """The `links` entries as rigid sets: a sliding point drawn on its guide (an entry
        holding a point of the links it slides on) is no joint of it."""
        sliding = [(m.block.point, m.block.beside) for _, m in self.made if m.block is not None]
        drawn = []
        for link in self.c.data.get("links") or []:
            joints = list(dict.fromkeys(map(str, link)))
            joints = [j for j in joints
                      if not any(j == point and guide & set(joints) for point, guide in sliding)]
            if len(joints) >= 2 and set(joints) != set(self.actuator or ()):
                drawn.append(joints)
        return drawn

    def _links(self) -> list[Body]:
        """The rigid sets the description implies, in the textbook's order: its `links`, then
        the steps' own (the cranks on one pivot are one link), but the actuator's side."""
        drawn = [Body(joints, 0) for joints in self._drawn()]
        implied, crank = [], None
        for rec, made in self.made:
            if made.crank:
                (pivot, point), = made.links
                if crank is None:
                    crank = [pivot, point]
                    implied.append(Body(crank, 0))
                elif pivot != crank[0]:
                    raise DescriptionError(rec["field"], "force analysis: a second crank on "
                                                         "another pivot (not supported)")
                else:
                    crank.append(point)
                continue
            implied += [Body(list(link), 0, frames=[made.frame] if made.frame else [])
                        for link in made.links if set(link) != set(self.actuator or ())]
        self.crank_joints = list(crank) if crank else None
        return drawn + implied

    def _bodies(self) -> list[Body]:
        groups = self._links()
        for rank, g in enumerate(groups):
            g.rank = rank
        groups = _merged(groups)
        fixed = set(self.c.ground)
        for rec, made in self.made:
            if made.carried is None:
                continue
            point, a, b = made.carried
            host = [g for g in groups if g.holds(a, b)]
            if a in fixed and b in fixed:
                fixed.add(point)
            elif host:
                host[0].joints.append(point)
            else:
                raise DescriptionError(rec["field"], f"force analysis: the point {point} is "
                                                     f"carried by {a}→{b}, which is no rigid "
                                                     "link")
        groups = [g for g in _merged(groups) if g.frames or not set(g.joints) <= fixed]
        self.fixed = fixed
        crank = next((g for g in groups if self.crank_joints and
                      set(self.crank_joints) <= set(g.joints)), None)
        bodies = ([crank] if crank else []) + [g for g in groups if g is not crank]
        bodies += [self._block(m.block) for _, m in self.made if m.block is not None]
        for number, b in enumerate(bodies, start=GROUND + 1):
            b.number = number
        return bodies

    def _block(self, block: Block) -> Body:
        """The block a sliding step makes: its point, its guide, its line and its spin (on
        the ground where its guide's points are the ground's)."""
        if block.guide and not set(block.guide) <= self.fixed:
            return Body([block.point], 0, block=True, guide=block.guide, line=block.line,
                        spin=self.w.link_rates(*block.spin))
        return Body([block.point], 0, block=True, line=block.line)

    def _entry_body(self, k: int, entry: dict) -> Body:
        where = f"{self.field}.bodies[{k}]"
        joints = [str(p) for p in entry.get("joints") or []]
        block = bool(entry.get("block", False))
        found = [b for b in self.bodies if b.block == block and
                 (set(joints) == set(b.joints) if block else b.names(set(joints)))]
        if len(found) != 1:
            raise DescriptionError(f"{where}.joints", f"{joints} is no moving link of the "
                                                      "steps and links (a block, a slider's, "
                                                      "a slide's or a slot's: [point] with "
                                                      "block = true)")
        return found[0]

    def _masses(self) -> None:
        """Each body's weight and inertia force at its centre G, its inertia torque."""
        g = self._gravity()
        described: set[int] = set()
        for k, entry in enumerate(self.entries):
            where = f"{self.field}.bodies[{k}]"
            entry = as_table(where, entry)
            body = self._entry_body(k, entry)
            if body.number in described:
                raise DescriptionError(f"{where}.joints", f"a second entry for the link "
                                                          f"{body.joints}")
            described.add(body.number)
            mass = self.expr(f"{where}.mass", entry.get("mass", 0))
            inertia = self.expr(f"{where}.inertia", entry.get("inertia", 0))
            if body.block:
                centre, (ax, ay) = body.joints[0], self.w.acc(body.joints[0])
            elif "centre" in entry:
                centre, (ax, ay) = self._centre(where, body, entry)
            else:               # no mass to place (the language's check): an inertia alone
                centre, ax, ay, mass = body.joints[0], ZERO, ZERO, ZERO
            wx = lin((1, mul(mass, g[0])), (-1, mul(mass, METRES_REF, ax)))
            wy = lin((1, mul(mass, g[1])), (-1, mul(mass, METRES_REF, ay)))
            if (wx, wy) != (ZERO, ZERO):
                body.forces.append((wx, wy, centre))
            if inertia != ZERO and (not body.block or body.spin is not None):
                alpha = self._rates(body)[1]
                body.couples.append(lin((-1, mul(inertia, alpha))))

    def _rates(self, body: Body) -> tuple[str, str]:
        """The body's ω and α: those of a link it holds (the Motion sheet's); a block's, its
        guide's."""
        if body.block:
            return body.spin
        for (a, b), rates in self.w.links.items():
            if body.holds(a, b):
                return rates
        if body.frames:
            return self.w.link_rates(*body.frames[0])
        return self.w.link_rates(body.joints[0], body.joints[1])

    def _centre(self, where: str, body: Body, entry: dict) -> tuple[str, tuple[str, str]]:
        """G placed in the frame A→B of its link as a point step places a point: by a distance
        and an angle from A→B, or by local coordinates; its acceleration by the rigid body's
        a_G = a_A + α×r − ω²r."""
        spec = as_table(f"{where}.centre", entry.get("centre"))
        frame = spec.get("frame")
        if not isinstance(frame, list) or len(frame) != 2 or not body.holds(*map(str, frame)):
            raise DescriptionError(f"{where}.centre.frame", f"must be two joints of the link "
                                                            f"{body.joints}")
        a, b = map(str, frame)
        name = f"G{body.number}"
        theta = self._frame_angle(f"{where}.centre.frame", name, a, b)
        (axp, ayp) = self.c.points[a]
        if "local" in spec:
            u, v = (self.expression(f"{where}.centre.local[{i}]", spec["local"][i], True)
                    for i in (0, 1))
            x, y = local_point((axp, ayp), u, v, theta.text)
        elif "distances" in spec:
            x, y = self._by_distances(where, spec, name, a, b, theta)
        else:
            d = self.expression(f"{where}.centre.distance", spec.get("distance", 0), True) \
                .at_least(PRODUCT)
            turn = self.expression(f"{where}.centre.angle", spec.get("angle", 0), True)
            t = theta.text if turn.zero else plus(theta, radians(turn).text)
            x, y = plus(axp, f"{d}*COS({t})"), plus(ayp, f"{d}*SIN({t})")
        gx = self.add(f"x{name}", f"x{name}", LENGTH, x,
                      f"centre of mass of link {body.number}, x", (0, body.number))
        gy = self.add(f"y{name}", f"y{name}", LENGTH, y,
                      f"centre of mass of link {body.number}, y", (0, body.number))
        self.centres[name] = (gx, gy)
        omega, alpha = self._rates(body)
        rx, ry = lin((1, gx), (-1, axp.text)), lin((1, gy), (-1, ayp.text))
        (aax, aay) = self.w.acc(a)
        w2 = sq(omega)
        ax = self.add(f"ax{name}", f"ax{name}", ACCEL,
                      lin((1, aax), (-1, mul(alpha, ry)), (-1, mul(w2, rx))),
                      f"acceleration of G{body.number}, x", (0, body.number))
        ay = self.add(f"ay{name}", f"ay{name}", ACCEL,
                      lin((1, aay), (1, mul(alpha, rx)), (-1, mul(w2, ry))),
                      f"acceleration of G{body.number}, y", (0, body.number))
        return name, (ax, ay)

    def _frame_angle(self, where: str, name: str, a: str, b: str) -> Expr:
        """angle(A→B) of a centre's frame (the compiler's angle_of: #N/A where they meet, so a
        book whose link has its two joints at one place, a slide's link at offset 0, keeps its
        kinematics), one alias: the centre's formulas use it more than once."""
        theta = self.c.angle_of(a, b, where, step=False)
        if any(pair in self.c.rigid for pair in ((a, b), (b, a))):
            return theta
        return Expr(self.w.alias(f"_{name}_frame", theta.text))

    def _by_distances(self, where: str, spec: dict, name: str, a: str, b: str, theta: Expr
                      ) -> tuple[str, str]:
        """G at given distances from A and B, on the side `side` of A→B: the angle at A by the
        cosine rule (#N/A where the three make no triangle)."""
        sides = spec["distances"]
        keys = [self.w.alias(f"_{name}_{k}", e.text) for k, e in (
            ("frame", self.c.length_of(a, b)),
            *((k, self.expression(f"{where}.centre.distances[{i}]", sides[i], True))
              for i, k in enumerate(("from_a", "from_b"))))]
        ab, da, db = (k[1:-1] for k in keys)
        gamma = self.w.alias(f"_{name}_gamma", angle_of_triangle_or_na(ab, da, db, once=ab))
        side = self.c.branch(f"{where}.centre.side", spec.get("side", 1))
        t = f"{theta.at_least(SUM)}+{{{side}}}*{gamma}"
        (ax, ay), d = self.c.points[a], f"{{{da}}}"
        return plus(ax, f"{d}*COS({t})"), plus(ay, f"{d}*SIN({t})")

    def _gravity(self) -> tuple[str, str]:
        spec = self.dynamics.get("gravity")
        if spec is None:
            return ZERO, ZERO
        where = f"{self.field}.dynamics.gravity"
        spec = as_table(where, spec)
        g = self.expression(f"{where}.g", spec.get("g", 0), True).text
        angle = self.expression(f"{where}.angle", spec.get("angle", -90), True)
        return _turned(g, angle)

    def _vector(self, where: str, raw: object) -> tuple[str, str]:
        if isinstance(raw, list) and len(raw) == 2:
            return self.expr(f"{where}[0]", raw[0]), self.expr(f"{where}[1]", raw[1])
        if isinstance(raw, dict) and "magnitude" in raw:
            size = self.expr(f"{where}.magnitude", raw["magnitude"])
            angle = self.expression(f"{where}.angle", raw.get("angle", 0))
            return _turned(size, angle)
        raise DescriptionError(where, "must be [Fx, Fy] or { magnitude, angle }")

    def _loads(self) -> None:
        for k, load in enumerate(self.loads):
            where = f"{self.field}.loads[{k}]"
            load = as_table(where, load)
            if "at" in load and "force" in load:
                at = str(load["at"])
                if at not in self.c.points or at in self.fixed:
                    raise DescriptionError(f"{where}.at", f"{at!r} is no moving point")
                body = self._load_body(where, load, at)
                fx, fy = self._vector(f"{where}.force", load["force"])
                body.forces.append((fx, fy, at))
            elif "body" in load and "torque" in load:
                body = self._load_body(where, load, None)
                body.couples.append(self.expr(f"{where}.torque", load["torque"]))
            else:
                raise DescriptionError(where, "needs at and force, or body and torque")

    def _load_body(self, where: str, load: dict, at: str | None) -> Body:
        """The body a load names (`body`: its joints), else the block at `at`, else the
        lowest-numbered link holding it."""
        if "body" in load:
            wanted = {str(p) for p in load["body"]}
            found = [b for b in self.bodies if not b.block and b.names(wanted) or
                     wanted <= set(b.joints)]
            found = [b for b in found if set(b.joints) == wanted] if len(found) > 1 else found
            if len(found) != 1 or (at is not None and at not in found[0].joints):
                raise DescriptionError(f"{where}.body", f"no single moving link holds "
                                                        f"{sorted(wanted | {at} - {None})}")
            return found[0]
        holding = sorted(self.holders(at), key=lambda b: (not b.block, b.number))
        return holding[0]


def _merged(groups: list[Body]) -> list[Body]:
    """Sets sharing two points or more are one rigid link, kept under the one named first."""
    out = sorted(groups, key=lambda g: g.rank)
    merged = True
    while merged:
        merged = False
        for i, a in enumerate(out):
            other = next((b for b in out[i + 1:] if len(set(a.joints) & set(b.joints)) >= 2),
                         None)
            if other is not None:
                a.joints += [p for p in other.joints if p not in a.joints]
                a.frames += [f for f in other.frames if f not in a.frames]
                out.remove(other)
                merged = True
                break
    return out


def _turned(size: str, angle: Expr) -> tuple[str, str]:
    """size·(cos, sin) of an angle in degrees: exact at a literal quarter turn."""
    return tuple(lin((-1, size)) if part == "-1" else mul(size, part)
                 for part in turned(None, angle))
