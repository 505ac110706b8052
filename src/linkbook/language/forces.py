"""Forces as live formulas: the textbook's kinetostatics, group by group.

Every moving link with mass feels d'Alembert's inertia force −m·a_G at its centre of mass G and
the inertia torque −I_G·α, beside its weight m·g and the loads the description puts on it
([mechanism.dynamics], [[mechanism.bodies]], [[mechanism.loads]]: docs/language.md). The steps
that placed the points forward are solved backward, last first: each loop step's group (a dyad's
two links, a slider's rod and block, a slide's or a slotted link's block and link, a slot's
block) is in equilibrium under the known loads and the reactions of the groups solved before it, and its own joint
reactions follow in closed form, written out by Cramer's rule over a determinant that is zero
exactly where the group cannot carry a load (a dyad stretched straight, a rod square to its
line): there the forces are #N/A. Each step type's group is solved in its module (steps
package, `forces`) through the helpers here. The crank comes last: the pivot's reaction and the
driving torque T12 (a linear actuator's force F_in comes out of the dyad it drives).

Lengths are in the book's unit and accelerations in that unit per s²: the formulas convert them
to metres with the one named cell `to_metres`; forces are in N and moments in N·m.

Bodies are numbered as the textbook numbers links: the ground 1, the crank 2, then the links in
the order of the description's `links` entries, then those only the steps make, then the
blocks (docs/language.md, "Sliding pairs"). A pin's force is the force of the lower-numbered
body on the higher one, F{i}{j} (F{i}_{j} from ten bodies on); at a pin joining three bodies,
the one that places the pin's point carries it and the others are joined to it. Keys (the force
reference's, which verify compares with): T12 or F_in; F{i}{j}x, F{i}{j}y, F{i}{j} (its size);
a block j's guide i (1: the ground) force N{i}{j} (along the line turned +90°) as F{i}{j}x,
F{i}{j}y, F{i}{j} and its couple M{i}{j}; a slot's link i on its block j, N{i}{j} across the
slot, as F{i}{j}x, F{i}{j}y, F{i}{j}; a triad's binary link P–N on its ternary, along P→N
and across it, Fa_N and Fn_N (steps/triad.py);
shaking_x, shaking_y, shaking, shaking_moment (what the moving links do to the frame, about the
origin); a centre of mass G{j}: xG{j}, yG{j}, axG{j}, ayG{j}.
"""
from __future__ import annotations

from .bodies import GROUND, METRES, METRES_REF, Body, BodiesAndLoads
from .excel import ZERO, cross, guard, lin, mul, sq
from .mechanisms import FORCE_ROLE, TO_METRES
from .model import NEWTON, NEWTON_METRE, DescriptionError, Quantity
from .steps import STEPS

FORCE = FORCE_ROLE           # the model's role of a force column (sheet Forces)


class ForceWriter:
    """Adds the Forces sheet's quantities to a compiled model (the compiler's state and the
    motion writer's rates): the bodies and their loads (`known`, bodies.py), then each step
    type's group (steps package, `forces`) from the last step back to the first."""

    def __init__(self, compiler, motion):
        self.c, self.w = compiler, motion
        self.model = compiler.model
        self.field = compiler.field
        self.rank: dict[str, tuple] = {}                   # a column: its place in the sheet
        self.known = BodiesAndLoads(compiler, motion, self.add)
        self.centres = self.known.centres                  # "G3": (x, y) texts
        self.actuator = self.known.actuator                # (END, N) of a linear actuator
        self.actuator_force: tuple[str, str, str] | None = None   # F_in·e at N, and END
        self.effort = ""
        self.solved: set[int] = set()                      # the bodies solved so far
        self.guides: list[tuple[str, str, str]] = []       # each guide's force, and its point
        self.guide_couples: list[str] = []

    # ------------------------------------------------------------------ the whole analysis
    def run(self) -> None:
        known = self.known
        known.find()
        self.bodies, self.fixed, self.crank_joints = known.bodies, known.fixed, known.crank_joints
        # what grows a force's formula without bound is the loads on one link
        self.model.where = f"{self.field}.{'loads' if known.loads else 'bodies'}"
        self.pairs = len(self.bodies) + GROUND >= 10
        known.load()
        for rec in reversed(self.c.records):
            solve = STEPS[rec["type"]].forces
            if solve is not None:
                solve(self, rec)
        unsolved = [b.joints for b in self.bodies if b.number not in self.solved]
        if unsolved:
            raise DescriptionError(self.field, f"force analysis: no step's group carries the "
                                               f"link {unsolved[0]} (a link of `links` that "
                                               "is no rigid link of the steps?)")
        self._shaking()
        self._reading_order()

    def _reading_order(self) -> None:
        """The force columns as a reader looks for them (they are made last group first): the
        centres of mass, the driving effort, the pins by their links' numbers, the guides, the
        shaking force."""
        forces = [q for q in self.model.quantities if q.role == FORCE]
        others = [q for q in self.model.quantities if q.role != FORCE]
        order = {q.key: (self.rank.get(q.key, (5,)), i) for i, q in enumerate(forces)}
        self.model.quantities[:] = others + sorted(forces, key=lambda q: order[q.key])

    # ------------------------------------------------------------------ helpers
    def add(self, key: str, symbol: str, unit: str, formula: str, label: str,
            rank: tuple = (4,)) -> str:
        """A force column; `rank` places it in the sheet (see _reading_order)."""
        self.model.add(Quantity(key, symbol, unit, formula, FORCE, label))
        self.rank[key] = rank
        return f"{{{key}}}"

    def pos(self, point: str) -> tuple[str, str]:
        if point in self.centres:
            return self.centres[point]
        x, y = self.c.points[point]
        return x.text, y.text

    def arm(self, point: str, about: str) -> tuple[str, str]:
        """point − about, in metres."""
        (px, py), (ox, oy) = self.pos(point), self.pos(about)
        return (mul(METRES_REF, lin((1, px), (-1, ox))), mul(METRES_REF, lin((1, py), (-1, oy))))

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
        return self.known.holders(point)

    def first_holder(self, point: str) -> Body:
        """The lowest-numbered body holding a point: the one that carries a pin there."""
        return min(self.holders(point), key=lambda b: b.number)

    def carrier(self, point: str, group: list[Body], where: str) -> Body:
        """The body that carries a moving pin, which must be one of the group that places the
        point."""
        first = self.first_holder(point)
        if first not in group:
            raise _carried_later(where, point, first)
        return first

    def force_columns(self, key: str, fx: str, fy: str, what: str,
                      pair: tuple[int, int]) -> tuple[str, str]:
        """A pin's force of link i on link j (`pair`): x, y and size."""
        x = self.add(f"{key}x", f"{key}x", NEWTON, fx, f"{what}, x", (2, pair))
        y = self.add(f"{key}y", f"{key}y", NEWTON, fy, f"{what}, y", (2, pair))
        self.add(key, key, NEWTON, f"SQRT({sq(x)}+{sq(y)})", f"{what}, size", (2, pair))
        return x, y

    def neg(self, text: str) -> str:
        return lin((-1, text))

    # ------------------------------------------------------------------ reactions
    def outer(self, body: Body, point: str, fx: str, fy: str, where: str) -> None:
        """(fx, fy) acts on `body` at `point` from the links placed before this group (the
        ground at a ground point): a pin force column, and its reaction on the other link."""
        if point in self.fixed:
            self.force_columns(f"F{self.pair(GROUND, body.number)}", fx, fy,
                               f"ground on {_named(body)} at {point}", (GROUND, body.number))
            return
        other = self.first_holder(point)
        if other is body:
            others = [b for b in self.holders(point)
                      if b is not body and b.number not in self.solved]
            if len(others) != 1:
                raise DescriptionError(where, f"force analysis: the pin {point} joins "
                                              f"{len(others) + 1} links placed at once (not "
                                              "supported yet)")
            other = others[0]
        elif other.number in self.solved:
            raise _carried_later(where, point, other)
        x, y = self.inner(other, body, point, fx, fy)
        other.forces.append((_reaction(x), _reaction(y), point))

    def inner(self, first: Body, second: Body, point: str, fx: str, fy: str) -> tuple[str, str]:
        """The pin force of `first` on `second` at `point`, as columns named for the pair."""
        if first.number < second.number:
            return self.force_columns(f"F{self.pair(first.number, second.number)}", fx, fy,
                                      f"{_named(first)} on {_named(second)} at {point}",
                                      (first.number, second.number))
        x, y = self.force_columns(f"F{self.pair(second.number, first.number)}", self.neg(fx),
                                  self.neg(fy),
                                  f"{_named(second)} on {_named(first)} at {point}",
                                  (second.number, first.number))
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
        det = self.w.alias(f"_Dforce_{n}", cross(a, b))
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
        det = self.w.alias(f"_Dforce_{n}", cross(self.arm(n, q), e))
        self.effort = "F_in"
        force = self.add("F_in", "F_in", NEWTON, guard(det, self.neg(self.moment(s, q))),
                         "actuator force, pushing its ends apart", (1,))
        fx, fy = mul(force, e[0]), mul(force, e[1])
        s.forces.append((fx, fy, n))
        if end not in self.fixed:
            self.first_holder(end).forces.append((self.neg(fx), self.neg(fy), end))
        self.actuator_force = (fx, fy, end)
        self.solved.add(s.number)
        sx, sy = self.resultant(s)
        self.outer(s, q, self.neg(sx), self.neg(sy), where)

    def guided(self, blk: Body, fx: str, fy: str) -> None:
        """The block's guide takes what (fx, fy) leaves across its line: N = −(fx, fy)·n, and
        the couple M = −M_b(point); as columns, and on the guide with the opposite sign."""
        ex, ey = blk.line
        guide = self.guide_of(blk)
        normal = self.guide_normal(guide, blk, lin((1, mul(fx, ey)), (-1, mul(fy, ex))))
        self.guide_columns(guide, blk, normal, self.neg(mul(ey, normal)), mul(ex, normal))

    def guide_of(self, blk: Body) -> Body | None:
        """The link a block slides on (None: the ground)."""
        return self.body(*blk.guide) if blk.guide else None

    def guide_normal(self, guide: Body | None, blk: Body, text: str,
                     across: str = "across its line") -> str:
        """The signed force of a guide (or a slot's link) on a block, across the line."""
        tail = self.pair(guide.number if guide else GROUND, blk.number)
        what = f"link {guide.number}" if guide else "guide"
        return self.add(f"N{tail}", f"N{tail}", NEWTON, text,
                        f"{what} on block {blk.number}, {across}", (3, blk.number))

    def guide_columns(self, guide: Body | None, blk: Body, normal: str, fx: str, fy: str,
                      couple: bool = True) -> None:
        """A guide's (or a slot's) force on a block as a vector and its size, its couple where
        the block carries one; the opposite acts on a moving guide, a fixed one is the frame's."""
        number = guide.number if guide else GROUND
        tail = self.pair(number, blk.number)
        what = f"link {number}" if guide else "guide"
        point = blk.joints[0]
        gx = self.add(f"F{tail}x", f"F{tail}x", NEWTON, _or_na(fx, normal),
                      f"{what} on block {blk.number}, x", (3, blk.number))
        gy = self.add(f"F{tail}y", f"F{tail}y", NEWTON, _or_na(fy, normal),
                      f"{what} on block {blk.number}, y", (3, blk.number))
        self.add(f"F{tail}", f"F{tail}", NEWTON, f"ABS({normal})",
                 f"{what} on block {blk.number}, size", (3, blk.number))
        m = None
        if couple and blk.couples:     # the block's own couples: #N/A where its place is
            m = self.add(f"M{tail}", f"M{tail}", NEWTON_METRE,
                         _na_with(self.neg(lin(*((1, c) for c in blk.couples))), normal),
                         f"{what}'s couple on block {blk.number}", (3, blk.number))
        if guide is None:
            self.guides.append((gx, gy, point))
            if m is not None:
                self.guide_couples.append(m)
            return
        guide.forces.append((_reaction(gx), _reaction(gy), point))
        if m is not None:
            guide.couples.append(_reaction(m))

    def crank(self, pivot: str, point: str, where: str) -> None:
        """The crank turns about its pivot: the pivot takes −ΣF, the motor gives
        T12 = −M_crank(pivot)."""
        if point != self.crank_joints[1]:
            return      # a later crank on the same pivot: the same link, solved at the first
        body = self.body(pivot, point)
        key = f"T{self.pair(GROUND, body.number)}"
        self.effort = key
        self.add(key, key, NEWTON_METRE, self.neg(self.moment(body, pivot)),
                 "driving torque on the crank, counter-clockwise", (1,))
        self.solved.add(body.number)
        fx, fy = self.resultant(body)
        self.outer(body, pivot, self.neg(fx), self.neg(fy), where)

    # ------------------------------------------------------------------ the frame
    def _shaking(self) -> None:
        """What the links do to the frame: minus the ground's forces on them (its pins, the
        guides, the actuator's base) and their moments about the origin, with the motor's."""
        keys = {b.number: f"F{self.pair(GROUND, b.number)}" for b in self.bodies}
        ground = [(f"{{{keys[b.number]}x}}", f"{{{keys[b.number]}y}}", p)
                  for b in self.bodies for p in b.joints if p in self.fixed]
        ground += self.guides
        if self.actuator_force is not None:
            fx, fy, end = self.actuator_force
            if end in self.fixed:      # through the actuator, the frame pushes with F_in·e
                ground.append((fx, fy, end))
        sx = self.add("shaking_x", "Fs_x", NEWTON, self.neg(lin(*((1, f) for f, _, _ in ground))),
                      "shaking force on the frame, x")
        sy = self.add("shaking_y", "Fs_y", NEWTON, self.neg(lin(*((1, f) for _, f, _ in ground))),
                      "shaking force on the frame, y")
        self.add("shaking", "Fs", NEWTON, f"SQRT({sq(sx)}+{sq(sy)})", "shaking force, size")
        moments = [(-1, cross((mul(METRES_REF, self.pos(p)[0]), mul(METRES_REF, self.pos(p)[1])),
                              (fx, fy))) for fx, fy, p in ground]
        moments += [(-1, m) for m in self.guide_couples]
        if self.effort.startswith("T"):
            moments.append((-1, f"{{{self.effort}}}"))
        self.add("shaking_moment", "Ms", NEWTON_METRE, lin(*moments),
                 "shaking moment on the frame about the origin")


def _named(body: Body) -> str:
    """A body as the sheet's labels name it: "link 3", or "block 4" for a sliding block."""
    return f"{'block' if body.block else 'link'} {body.number}"


def _carried_later(where: str, point: str, body: Body) -> DescriptionError:
    return DescriptionError(where, f"force analysis: the pin {point} is carried by the link "
                                   f"{body.joints}, which a later step places; list the links "
                                   "that place it first in `links` (not supported yet)")


def _reaction(text: str) -> str:
    """The force on the other link at a pin, from the columns `inner` gives (a column or its
    negation): its negation, written without a double sign."""
    return text[1:] if text.startswith("-{") and text.count("{") == 1 else f"-{text}"


def _or_na(text: str, witness: str) -> str:
    """A component zero by construction (a horizontal guide's x) is #N/A where `witness` is."""
    return _na_with(text, witness) if text == ZERO else text


def _na_with(text: str, witness: str) -> str:
    """text, but #N/A where `witness` is (a value that reads nothing of the row's position)."""
    return f"IF(ISNUMBER({witness}),{text},NA())"


__all__ = ["FORCE", "TO_METRES", "ForceWriter"]
