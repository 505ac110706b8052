"""Forces as live formulas: the textbook's kinetostatics, group by group.

Every moving link with mass feels d'Alembert's inertia force −m·a_G at its centre of mass G and
the inertia torque −I_G·α, beside its weight m·g and the loads the description puts on it
([mechanism.dynamics], [[mechanism.bodies]], [[mechanism.loads]]: docs/language.md). The steps
that placed the points forward are solved backward, last first: each loop step's group (a dyad's
two links, a slider's rod and block) is in equilibrium under the known loads and the reactions
of the groups solved before it, and its own joint reactions follow in closed form, a 2×2 system
written out by Cramer's rule whose determinant is zero exactly where the group cannot carry a
load (a dyad stretched straight, a rod square to its line): there the forces are #N/A. The
crank comes last: the pivot's reaction and the driving torque T12 (a linear actuator's force
F_in comes out of the dyad it drives).

Lengths are in the book's unit and accelerations in that unit per s²: the formulas convert them
to metres with the one named cell `to_metres`; forces are in N and moments in N·m.

Bodies are numbered as the textbook numbers links: the ground 1, the crank 2, then the links in
the order of the description's `links` entries, then those only the steps make, then the
sliders' blocks. A pin's force is the force of the lower-numbered body on the higher one,
F{i}{j} (F{i}_{j} from ten bodies on); at a pin joining three bodies, the one that places the
pin's point carries it and the others are joined to it. Keys (the force reference's, which
verify compares with): T12 or F_in; F{i}{j}x, F{i}{j}y, F{i}{j} (its size); a block j's guide
force N1{j} (along the line turned +90°) as F1{j}x, F1{j}y, F1{j} and its couple M1{j};
shaking_x, shaking_y, shaking, shaking_moment (what the moving links do to the frame, about the
origin); a centre of mass G{j}: xG{j}, yG{j}, axG{j}, ayG{j}.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .excel import PRODUCT, ZERO, Expr, cross, guard, lin, mul, plus, radians, sq
from .expressions import expression
from .fields import as_table
from .model import ACCEL, ALIAS, LENGTH, DescriptionError, Quantity

FORCE = "force"              # the model's role of a force column (sheet Forces)
NEWTON, NEWTON_METRE = "N", "N·m"
TO_METRES = "to_metres"      # the named cell: metres per length unit
GROUND = 1
_METRES = f"{{{TO_METRES}}}"


@dataclass
class Body:
    """One moving link: the points it holds, and what is known to act on it so far."""
    joints: list[str]
    rank: int
    block: bool = False
    number: int = 0
    forces: list[tuple[str, str, str]] = field(default_factory=list)   # (Fx, Fy, at point)
    couples: list[str] = field(default_factory=list)                  # N·m

    def holds(self, *points: str) -> bool:
        return all(p in self.joints for p in points)


class ForceWriter:
    """Adds the Forces sheet's quantities to a compiled model (the compiler's state and the
    motion writer's rates): the bodies, their loads, then each step type's group (steps
    package, `forces`) from the last step back to the first."""

    def __init__(self, compiler, motion):
        self.c, self.w = compiler, motion
        self.model = compiler.model
        self.field = f"{compiler.field}"
        data = compiler.data
        self.entries = data.get("bodies") or []
        self.loads = data.get("loads") or []
        self.dynamics = as_table(f"{self.field}.dynamics", data.get("dynamics") or {})
        self.centres: dict[str, tuple[str, str]] = {}     # "G3": (x, y) texts
        self.actuator = self._actuator()
        self.effort = ""

    # ------------------------------------------------------------------ the whole analysis
    def run(self) -> None:
        from .steps import STEPS
        self.bodies = self._bodies()
        self.pairs = len(self.bodies) + GROUND >= 10
        self._masses()
        self._loads()
        for rec in reversed(self.c.records):
            solve = STEPS[rec["type"]].forces
            if solve is not None:
                solve(self, rec)
        self._shaking()

    # ------------------------------------------------------------------ helpers
    def add(self, key: str, symbol: str, unit: str, formula: str, label: str) -> str:
        self.model.add(Quantity(key, symbol, unit, formula, FORCE, label))
        return f"{{{key}}}"

    def expr(self, where: str, raw: object) -> str:
        known = self.c.symbols | self.c.swept | {q.key for q in self.model.quantities}
        return expression(where, raw, known).text

    def pos(self, point: str) -> tuple[str, str]:
        if point in self.centres:
            return self.centres[point]
        x, y = self.c.points[point]
        return x.text, y.text

    def arm(self, point: str, about: str) -> tuple[str, str]:
        """point − about, in metres."""
        (px, py), (ox, oy) = self.pos(point), self.pos(about)
        return (mul(_METRES, lin((1, px), (-1, ox))), mul(_METRES, lin((1, py), (-1, oy))))

    def pair(self, i: int, j: int) -> str:
        return f"{i}_{j}" if self.pairs else f"{i}{j}"

    def resultant(self, body: Body) -> tuple[str, str]:
        """The sum of the known forces on a body."""
        return (lin(*((1, fx) for fx, _, _ in body.forces)),
                lin(*((1, fy) for _, fy, _ in body.forces)))

    def moment(self, body: Body, about: str) -> str:
        """The moment about a point of the known loads on a body, N·m counter-clockwise."""
        terms = [(1, cross(self.arm(p, about), (fx, fy)))
                 for fx, fy, p in body.forces if p != about]
        return lin(*terms, *((1, c) for c in body.couples))

    def body(self, *points: str, block: bool = False) -> Body:
        found = [b for b in self.bodies if b.block == block and b.holds(*points)]
        return found[0]

    def holders(self, point: str) -> list[Body]:
        return [b for b in self.bodies if point in b.joints]

    def carrier(self, point: str, group: list[Body], where: str) -> Body:
        """The body that carries a moving pin: the lowest-numbered body holding it, which must
        be one of the group that places the point."""
        first = min(self.holders(point), key=lambda b: b.number)
        if first not in group:
            raise DescriptionError(where, f"force analysis: the pin {point} is carried by the "
                                          f"link {first.joints}, which a later step places; "
                                          "list the links that place it first in `links` "
                                          "(not supported yet)")
        return first

    def force_columns(self, key: str, fx: str, fy: str, what: str) -> tuple[str, str]:
        x = self.add(f"{key}x", f"{key}x", NEWTON, fx, f"{what}, x")
        y = self.add(f"{key}y", f"{key}y", NEWTON, fy, f"{what}, y")
        self.add(key, key, NEWTON, f"SQRT({sq(x)}+{sq(y)})", f"{what}, size")
        return x, y

    def neg(self, text: str) -> str:
        return lin((-1, text))

    # ------------------------------------------------------------------ reactions
    def outer(self, body: Body, point: str, fx: str, fy: str, where: str) -> None:
        """(fx, fy) acts on `body` at `point` from the links placed before this group (the
        ground at a ground point): a pin force column, and its reaction on the other link."""
        if point in self.c.ground:
            self.force_columns(f"F{self.pair(GROUND, body.number)}", fx, fy,
                               f"ground on link {body.number} at {point}")
            return
        holders = self.holders(point)
        k = min(holders, key=lambda b: b.number)
        if k is body:
            others = [b for b in holders if b is not body and b.number not in self.solved]
            if len(others) != 1:
                raise DescriptionError(where, f"force analysis: the pin {point} joins "
                                              f"{len(others) + 1} links placed at once (not "
                                              "supported yet)")
            e = others[0]
            x, y = self.force_columns(f"F{self.pair(body.number, e.number)}", self.neg(fx),
                                      self.neg(fy),
                                      f"link {body.number} on link {e.number} at {point}")
            e.forces.append((x, y, point))
            return
        if k.number in self.solved:
            raise DescriptionError(where, f"force analysis: the pin {point} is carried by the "
                                          f"link {k.joints}, which a later step places; list "
                                          "the links that place it first in `links` (not "
                                          "supported yet)")
        x, y = self.force_columns(f"F{self.pair(k.number, body.number)}", fx, fy,
                                  f"link {k.number} on link {body.number} at {point}")
        k.forces.append((self.neg(x), self.neg(y), point))

    def inner(self, first: Body, second: Body, point: str, fx: str, fy: str) -> tuple[str, str]:
        """The pin force of `first` on `second` at `point`, as columns named for the pair."""
        if first.number < second.number:
            return self.force_columns(f"F{self.pair(first.number, second.number)}", fx, fy,
                                      f"link {first.number} on link {second.number} at {point}")
        x, y = self.force_columns(f"F{self.pair(second.number, first.number)}", self.neg(fx),
                                  self.neg(fy),
                                  f"link {second.number} on link {first.number} at {point}")
        return self.neg(x), self.neg(y)

    # ------------------------------------------------------------------ the groups
    def two_links(self, n: str, p: str, q: str, where: str) -> None:
        """A dyad: links f (P–N) and s (Q–N) pinned at N. With X the pin force of the carrier
        f on s: s turns about Q, (N−Q)×X = −M_s(Q); f about P, (N−P)×X = M_f(P) — Cramer's
        rule over D = (N−P)×(N−Q), zero when P, Q and N are in line. Then the outer pins:
        f at P takes X − ΣF_f, s at Q takes −X − ΣF_s."""
        u, v = self.body(p, n), self.body(q, n)
        f = self.carrier(n, [u, v], where)
        s = v if f is u else u
        of, os_ = (p, q) if f is u else (q, p)
        a, b = self.arm(n, of), self.arm(n, os_)
        m1, m2 = self.moment(f, of), self.neg(self.moment(s, os_))
        det = self.alias(f"_Dforce_{n}", cross(a, b))
        xf = guard(det, lin((1, mul(m1, b[0])), (-1, mul(a[0], m2))))
        yf = guard(det, lin((1, mul(b[1], m1)), (-1, mul(a[1], m2))))
        x, y = self.inner(f, s, n, xf, yf)
        self.close(f, s, n, x, y, of, os_, where)

    def close(self, f: Body, s: Body, n: str, x: str, y: str, of: str, os_: str,
              where: str) -> None:
        """The pin force (x, y) of f on s at n is known: s and f are solved, their outer pins
        follow from ΣF = 0."""
        self.solved.update({f.number, s.number})
        (ffx, ffy), (sfx, sfy) = self.resultant(f), self.resultant(s)
        self.outer(f, of, lin((1, x), (-1, ffx)), lin((1, y), (-1, ffy)), where)
        self.outer(s, os_, lin((-1, x), (-1, sfx)), lin((-1, y), (-1, sfy)), where)

    def actuated(self, n: str, end: str, q: str, where: str) -> None:
        """A dyad whose side END–N is the linear actuator: its force F_in along e = (N − END)/s
        on the link s (Q–N), which turns about Q: F_in·(N−Q)×e = −M_s(Q)."""
        s = self.body(q, n)
        self.carrier(n, [s], where)
        length = f"{{{self.c.input_key}}}"
        (nx, ny), (ex, ey) = self.pos(n), self.pos(end)
        e = (guard(length, lin((1, nx), (-1, ex))), guard(length, lin((1, ny), (-1, ey))))
        det = self.alias(f"_Dforce_{n}", cross(self.arm(n, q), e))
        self.effort = "F_in"
        force = self.add("F_in", "F_in", NEWTON, guard(det, self.neg(self.moment(s, q))),
                         "actuator force, pushing its ends apart")
        fx, fy = mul(force, e[0]), mul(force, e[1])
        s.forces.append((fx, fy, n))
        if end not in self.c.ground:
            host = min(self.holders(end), key=lambda b: b.number)
            host.forces.append((self.neg(fx), self.neg(fy), end))
        self.actuator_force = (fx, fy, end)
        self.solved.add(s.number)
        sx, sy = self.resultant(s)
        self.outer(s, q, self.neg(sx), self.neg(sy), where)

    def slider(self, n: str, p: str, direction: tuple[str, str], where: str) -> None:
        """A slider: the rod u (P–N) pinned at N to the block b on a fixed line of direction
        e. With X the pin force of u on b: the block along its line, X·e = −ΣF_b·e; the rod
        about P, (N−P)×X = M_u(P) — over D = e·(N−P), zero when the rod is square to the
        line. The guide's normal force N1b = −(X + ΣF_b)·n (n = e turned +90°), its couple
        M1b = −M_b(N); the rod's pin at P takes X − ΣF_u."""
        u, blk = self.body(p, n), self.body(n, block=True)
        self.carrier(n, [u, blk], where)
        ex, ey = direction
        a = self.arm(n, p)
        kb = self.resultant(blk)
        c1 = self.neg(lin((1, mul(kb[0], ex)), (1, mul(kb[1], ey))))
        c2 = self.moment(u, p)
        det = self.alias(f"_Dforce_{n}", lin((1, mul(ex, a[0])), (1, mul(ey, a[1]))))
        x, y = self.inner(u, blk, n, guard(det, lin((1, mul(c1, a[0])), (-1, mul(ey, c2)))),
                          guard(det, lin((1, mul(ex, c2)), (1, mul(a[1], c1)))))
        tail = self.pair(GROUND, blk.number)
        normal = self.add(f"N{tail}", f"N{tail}", NEWTON,
                          lin((1, mul(lin((1, x), (1, kb[0])), ey)),
                              (-1, mul(lin((1, y), (1, kb[1])), ex))),
                          f"guide on block {blk.number}, across its line")
        gx = self.add(f"F{tail}x", f"F{tail}x", NEWTON, self.neg(mul(ey, normal)),
                      f"guide on block {blk.number}, x")
        gy = self.add(f"F{tail}y", f"F{tail}y", NEWTON, mul(ex, normal),
                      f"guide on block {blk.number}, y")
        self.add(f"F{tail}", f"F{tail}", NEWTON, f"ABS({normal})",
                 f"guide on block {blk.number}, size")
        self.guides.append((gx, gy, n))
        if blk.couples:
            self.guide_couples.append(self.add(f"M{tail}", f"M{tail}", NEWTON_METRE,
                                               self.neg(lin(*((1, c) for c in blk.couples))),
                                               f"guide's couple on block {blk.number}"))
        self.solved.update({u.number, blk.number})
        ux, uy = self.resultant(u)
        self.outer(u, p, lin((1, x), (-1, ux)), lin((1, y), (-1, uy)), where)

    def crank(self, pivot: str, point: str, where: str) -> None:
        """The crank turns about its pivot: the pivot takes −ΣF, the motor gives
        T12 = −M_crank(pivot)."""
        body = self.body(pivot, point)
        if body.number in self.solved:
            return            # a second crank on the same pivot: the same link
        key = f"T{self.pair(GROUND, body.number)}"
        self.effort = key
        self.add(key, key, NEWTON_METRE, self.neg(self.moment(body, pivot)),
                 "driving torque on the crank, counter-clockwise")
        self.solved.add(body.number)
        fx, fy = self.resultant(body)
        self.outer(body, pivot, self.neg(fx), self.neg(fy), where)

    def alias(self, key: str, text: str) -> str:
        self.model.add(Quantity(key, key, "-", text, ALIAS))
        return f"{{{key}}}"

    # ------------------------------------------------------------------ the frame
    def _shaking(self) -> None:
        """What the links do to the frame: minus the ground's forces on them (its pins, the
        guides, the actuator's base) and their moments about the origin, with the motor's."""
        ground = [(f"{{F{self.pair(GROUND, b.number)}x}}", f"{{F{self.pair(GROUND, b.number)}y}}", p)
                  for b in self.bodies if not b.block for p in b.joints if p in self.c.ground]
        ground += self.guides
        if self.actuator is not None and getattr(self, "actuator_force", None):
            fx, fy, end = self.actuator_force
            if end in self.c.ground:      # through the actuator, the frame pushes with F_in·e
                ground.append((fx, fy, end))
        sx = self.add("shaking_x", "Fs_x", NEWTON, self.neg(lin(*((1, f) for f, _, _ in ground))),
                      "shaking force on the frame, x")
        sy = self.add("shaking_y", "Fs_y", NEWTON, self.neg(lin(*((1, f) for _, f, _ in ground))),
                      "shaking force on the frame, y")
        self.add("shaking", "Fs", NEWTON, f"SQRT({sq(sx)}+{sq(sy)})", "shaking force, size")
        moments = [(-1, cross((mul(_METRES, self.pos(p)[0]), mul(_METRES, self.pos(p)[1])),
                              (fx, fy))) for fx, fy, p in ground]
        moments += [(-1, m) for m in self.guide_couples]
        if self.effort.startswith("T"):
            moments.append((-1, f"{{{self.effort}}}"))
        self.add("shaking_moment", "Ms", NEWTON_METRE, lin(*moments),
                 "shaking moment on the frame about the origin")

    # ------------------------------------------------------------------ bodies and loads
    def _actuator(self) -> tuple[str, str] | None:
        """(END, N) of the dyad side that is the linear actuator's length."""
        if not self.c.swept:
            return None
        for rec in self.c.records:
            if rec["type"] != "dyad":
                continue
            for end, side in (("p", "p_length"), ("q", "q_length")):
                if rec[side].text == f"{{{self.c.input_key}}}":
                    return rec[end], rec["point"]
        return None

    def _links(self) -> list[list[str]]:
        """The rigid sets the description implies, in the textbook's order: its `links`, then
        the steps' own (a crank and the cranks on its pivot, a dyad's sides, a slider's rod)."""
        drawn = [list(dict.fromkeys(map(str, link))) for link in self.c.data.get("links") or []]
        drawn = [j for j in drawn if len(j) >= 2 and set(j) != set(self.actuator or ())]
        implied, crank = [], None
        for rec in self.c.records:
            kind, n = rec["type"], rec.get("point")
            if kind == "crank" and crank is None:
                crank = [rec["pivot"], n]
                implied.append(crank)
            elif kind == "crank":
                crank.append(n)
            elif kind == "dyad":
                implied += [[rec[e], n] for e in ("p", "q")
                            if {rec[e], n} != set(self.actuator or ())]
            elif kind == "slider":
                implied.append([rec["p"], n])
        self.crank_joints = crank
        return drawn + implied

    def _bodies(self) -> list[Body]:
        groups = [Body(list(j), rank) for rank, j in enumerate(self._links())]
        groups = _merged(groups)
        fixed = set(self.c.ground)
        for rec in self.c.records:
            if rec["type"] == "point":
                a, b = rec["frame"]
                host = [g for g in groups if g.holds(a, b)]
                if a in fixed and b in fixed:
                    fixed.add(rec["point"])
                elif host:
                    host[0].joints.append(rec["point"])
                else:
                    raise DescriptionError(self.field, f"force analysis: the point "
                                                       f"{rec['point']} is carried by {a}→{b}, "
                                                       "which is no rigid link (not supported "
                                                       "yet)")
            elif rec["type"] in ("slide", "slot") or rec["type"] == "slider" and rec["along"]:
                what = "a slider on a moving line" if rec["type"] == "slider" else \
                    f"a {rec['type']} step"
                raise DescriptionError(self.field, f"force analysis of {what} is not supported "
                                                   "yet")
        groups = [g for g in _merged(groups) if not set(g.joints) <= fixed]
        self.fixed = fixed
        crank = next((g for g in groups if self.crank_joints and
                      set(self.crank_joints) <= set(g.joints)), None)
        bodies = ([crank] if crank else []) + [g for g in groups if g is not crank]
        bodies += [Body([rec["point"]], 0, block=True) for rec in self.c.records
                   if rec["type"] == "slider"]
        for number, b in enumerate(bodies, start=GROUND + 1):
            b.number = number
        self.solved: set[int] = set()
        self.guides: list[tuple[str, str, str]] = []
        self.guide_couples: list[str] = []
        return bodies

    def _entry_body(self, k: int, entry: dict) -> Body:
        where = f"{self.field}.bodies[{k}]"
        joints = [str(p) for p in entry.get("joints") or []]
        block = bool(entry.get("block", False))
        found = [b for b in self.bodies if b.block == block and
                 (set(joints) == set(b.joints) if block else
                  len(set(joints)) > 1 and set(joints) <= set(b.joints))]
        if len(found) != 1:
            raise DescriptionError(f"{where}.joints", f"{joints} is no moving link of the "
                                                      "steps and links (a slider's block: "
                                                      "[point] with block = true)")
        return found[0]

    def _masses(self) -> None:
        """Each body's weight and inertia force at its centre G, its inertia torque."""
        g = self._gravity()
        for k, entry in enumerate(self.entries):
            where = f"{self.field}.bodies[{k}]"
            entry = as_table(where, entry)
            body = self._entry_body(k, entry)
            mass = self.expr(f"{where}.mass", entry.get("mass", 0))
            inertia = self.expr(f"{where}.inertia", entry.get("inertia", 0))
            if body.block:
                centre, (ax, ay) = body.joints[0], self.w.acc(body.joints[0])
            else:
                centre, (ax, ay) = self._centre(where, body, entry)
            wx = lin((1, mul(mass, g[0])), (-1, mul(mass, _METRES, ax)))
            wy = lin((1, mul(mass, g[1])), (-1, mul(mass, _METRES, ay)))
            if (wx, wy) != (ZERO, ZERO):
                body.forces.append((wx, wy, centre))
            if inertia != ZERO and not body.block:
                alpha = self._alpha(body)
                body.couples.append(lin((-1, mul(inertia, alpha))))

    def _alpha(self, body: Body) -> str:
        return self._rates(body)[1]

    def _rates(self, body: Body) -> tuple[str, str]:
        """The body's ω and α: those of a link it holds (the Motion sheet's)."""
        for (a, b), rates in self.w.links.items():
            if body.holds(a, b):
                return rates
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
        theta = self.c.angle_of(a, b)
        (axp, ayp) = self.c.points[a]
        name = f"G{body.number}"
        if "local" in spec:
            u, v = (expression(f"{where}.centre.local[{i}]", spec["local"][i],
                               self.c.symbols).at_least(PRODUCT) for i in (0, 1))
            t = theta.text
            x = plus(axp, f"{u}*COS({t})-{v}*SIN({t})")
            y = plus(ayp, f"{u}*SIN({t})+{v}*COS({t})")
        else:
            d = expression(f"{where}.centre.distance", spec.get("distance", 0),
                           self.c.symbols).at_least(PRODUCT)
            turn = expression(f"{where}.centre.angle", spec.get("angle", 0), self.c.symbols)
            t = theta.text if turn.zero else plus(theta, radians(turn).text)
            x, y = plus(axp, f"{d}*COS({t})"), plus(ayp, f"{d}*SIN({t})")
        gx = self.add(f"x{name}", f"x{name}", LENGTH, x, f"centre of mass of link {body.number}, x")
        gy = self.add(f"y{name}", f"y{name}", LENGTH, y, f"centre of mass of link {body.number}, y")
        self.centres[name] = (gx, gy)
        omega, alpha = self._rates(body)
        rx, ry = lin((1, gx), (-1, axp.text)), lin((1, gy), (-1, ayp.text))
        (aax, aay) = self.w.acc(a)
        w2 = sq(omega)
        ax = self.add(f"ax{name}", f"ax{name}", ACCEL,
                      lin((1, aax), (-1, mul(alpha, ry)), (-1, mul(w2, rx))),
                      f"acceleration of G{body.number}, x")
        ay = self.add(f"ay{name}", f"ay{name}", ACCEL,
                      lin((1, aay), (1, mul(alpha, rx)), (-1, mul(w2, ry))),
                      f"acceleration of G{body.number}, y")
        return name, (ax, ay)

    def _gravity(self) -> tuple[str, str]:
        spec = self.dynamics.get("gravity")
        if spec is None:
            return ZERO, ZERO
        where = f"{self.field}.dynamics.gravity"
        spec = as_table(where, spec)
        g = self.expr(f"{where}.g", spec.get("g", 0))
        angle = expression(f"{where}.angle", spec.get("angle", -90), self.c.symbols)
        return _turned(g, angle)

    def _vector(self, where: str, raw: object) -> tuple[str, str]:
        if isinstance(raw, list) and len(raw) == 2:
            return self.expr(f"{where}[0]", raw[0]), self.expr(f"{where}[1]", raw[1])
        if isinstance(raw, dict) and "magnitude" in raw:
            size = self.expr(f"{where}.magnitude", raw["magnitude"])
            angle = expression(f"{where}.angle", raw.get("angle", 0),
                               self.c.symbols | {q.key for q in self.model.quantities})
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
            found = [b for b in self.bodies if wanted <= set(b.joints)]
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
                out.remove(other)
                merged = True
                break
    return out


def _turned(size: str, angle: Expr) -> tuple[str, str]:
    """size·(cos, sin) of an angle in degrees: exact at a literal quarter turn."""
    quarter = {0: ("1", "0"), 90: ("0", "1"), 180: ("-1", "0"), 270: ("0", "-1"),
               -90: ("0", "-1"), -180: ("-1", "0"), -270: ("0", "1")}
    try:
        c, s = quarter[int(float(angle.text))] if float(angle.text) % 90 == 0 else (None, None)
    except ValueError:
        c = s = None
    if c is None:
        r = radians(angle).text
        c, s = f"COS({r})", f"SIN({r})"
    return mul(size, c) if c != "-1" else lin((-1, size)), \
        mul(size, s) if s != "-1" else lin((-1, size))


__all__ = ["FORCE", "NEWTON", "NEWTON_METRE", "TO_METRES", "ForceWriter"]
