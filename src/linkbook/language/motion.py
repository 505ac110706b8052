"""Velocity and acceleration as live formulas: each step's loop differentiated once and twice.

The input turns at ω with angular acceleration α (a linear actuator: extends at v with
acceleration a), two named inputs. Every step places its point from points already known, and
its motion follows from theirs, step after step as the positions do:

* a point carried by a link moves with it as a rigid body: v = v_A + ω × r, a = a_A + α × r − ω² r
  (r = A→point, ω and α the link's);
* a loop step's unknown rates solve its differentiated loop equation, a 2×2 linear system
  written out by Cramer's rule. Its determinant is a cross or dot product of the step's own
  vectors and is exactly zero at a dead centre: there the rates are #N/A (IF(det=0,NA(),…)),
  never #DIV/0!, and a position that is #N/A makes its rates #N/A too.

Keys (the data format's, which the reference computes under the same names): a point N's
velocity vx_N, vy_N and acceleration ax_N, ay_N (the traced point also |v| vmag_N and |a| amag_N);
an angle column k's ω and α omega_k, alpha_k; a length column k's rates v_k, acc_k; a frame A→B
measured from its points omega_A_B, alpha_A_B; the loop that places N its determinant det_N.
Expression steps get none (a formula of the user's has no derivative written for it).
"""
from __future__ import annotations

from .excel import ZERO, cross, dot, guard, lin, mul, sq
from .model import (ACCEL, ALIAS, ANG_ACCEL, ANG_SPEED, AREA, CONSTANT, MOTION, RPM, SPEED,
                    DescriptionError, Quantity)
from .steps import STEPS


def rate_symbol(symbol: str, order: int, angle: bool) -> str:
    """θ13 → ω13, α13; another symbol gets one or two dots over its first letter (ṡ14, s̈14);
    one that starts with no letter (|BA|, (AB)) d/dt: a dot combined onto a bar or a bracket
    would sit on no letter (||̇BA||)."""
    if angle and symbol.startswith("θ"):
        return ("ω", "α")[order - 1] + symbol[1:]
    if not symbol[:1].isalpha():
        return (f"d{symbol}/dt", f"d²{symbol}/dt²")[order - 1]
    return symbol[0] + ("\u0307", "\u0308")[order - 1] + symbol[1:]


def readable_rates(model) -> set[str]:
    """The Motion sheet's keys a load may read (docs/language.md): every rate, not a loop's
    determinant (its sign and scale are the writer's choice, not a quantity of the motion)."""
    return {q.key for q in model.of_role(MOTION) if not q.key.startswith("det_")}


class MotionWriter:
    """Adds the Motion sheet's quantities to a compiled model (compiler.Compiler's state): each
    step type's rates (steps package) through the helpers here."""

    def __init__(self, compiler):
        self.c = compiler
        self.model = compiler.model
        self.speed, self.accel = (f"{{{s}}}" for s in compiler.motion_symbols)
        self.motion: dict[str, tuple[str, str, str, str]] = {
            g: (ZERO, ZERO, ZERO, ZERO) for g in compiler.ground}
        self.links: dict[tuple[str, str], tuple[str, str]] = {}   # link a→b: (ω, α) texts

    def run(self) -> None:
        c = self.c
        if c.input_kind == "angle":
            symbol = "n" + c.input_symbol[1:] if c.input_symbol.startswith("θ") else "n"
            self.add(Quantity("rpm_in", symbol, RPM, f"{self.speed}*30/PI()", CONSTANT,
                              "input speed in revolutions per minute"))
        for rec in c.records:
            rates = STEPS[rec["type"]].rates
            if rates is not None:
                rates(self, rec)
        if self.model.path:
            name = self.c.traced
            vx, vy, ax, ay = self.motion[name]
            self.add(Quantity(f"vmag_{name}", f"v{name}", SPEED, f"SQRT({sq(vx)}+{sq(vy)})",
                              MOTION, f"speed of {name}"),
                     Quantity(f"amag_{name}", f"a{name}", ACCEL, f"SQRT({sq(ax)}+{sq(ay)})",
                              MOTION, f"acceleration of {name}, magnitude"))

    # -- helpers
    def add(self, *quantities: Quantity) -> None:
        try:
            self.model.add(*quantities)
        except ValueError as exc:
            raise DescriptionError(f"{self.c.field}", f"{exc} (velocity and acceleration keys "
                                                      "start with vx_, vy_, ax_, ay_, omega_, "
                                                      "alpha_, v_, acc_)") from None

    def pos(self, n: str) -> tuple[str, str]:
        x, y = self.c.points[n]
        return x.text, y.text

    def rel(self, a: str, b: str) -> tuple[str, str]:
        """b − a, the components of the vector a→b (position formulas)."""
        (ax, ay), (bx, by) = self.pos(a), self.pos(b)
        return lin((1, bx), (-1, ax)), lin((1, by), (-1, ay))

    def vel(self, n: str) -> tuple[str, str]:
        return self.motion[n][:2]

    def acc(self, n: str) -> tuple[str, str]:
        return self.motion[n][2:]

    def point(self, n: str, vx: str, vy: str, ax: str, ay: str, witness: str = "") -> None:
        """n's velocity and acceleration; a component that is zero by construction (a slider
        on a horizontal line) is #N/A where `witness` is: where the loop cannot close."""
        if witness:
            vx, vy, ax, ay = (f"IF(ISNUMBER({witness}),0,NA())" if t == ZERO else t
                              for t in (vx, vy, ax, ay))
        keys = (f"vx_{n}", f"vy_{n}", f"ax_{n}", f"ay_{n}")
        units = (SPEED, SPEED, ACCEL, ACCEL)
        labels = (f"velocity of {n}, x", f"velocity of {n}, y", f"acceleration of {n}, x",
                  f"acceleration of {n}, y")
        symbols = (f"vx{n}", f"vy{n}", f"ax{n}", f"ay{n}")
        self.add(*(Quantity(k, s, u, f, MOTION, lab)
                   for k, s, u, f, lab in zip(keys, symbols, units, (vx, vy, ax, ay), labels)))
        self.motion[n] = tuple(f"{{{k}}}" for k in keys)

    def rates(self, sym, omega: str, alpha: str, angle: bool = True) -> tuple[str, str]:
        """ω and α (or a length's v and a) of the column `sym`, as quantities; their texts."""
        return self.rate(sym, 1, omega, angle), self.rate(sym, 2, alpha, angle)

    def rate(self, sym, order: int, text: str, angle: bool = True) -> str:
        """The first or second time derivative of the column `sym` as a quantity (shown where
        the column is; None: no column, the text itself)."""
        if sym is None:
            return text
        pre = (("omega_", "alpha_") if angle else ("v_", "acc_"))[order - 1]
        unit = ((ANG_SPEED, ANG_ACCEL) if angle else (SPEED, ACCEL))[order - 1]
        word = (("angular velocity", "angular acceleration") if angle else
                ("velocity", "acceleration"))[order - 1]
        key = f"{pre}{sym.key}"
        # a column even where the position is hidden: later formulas read it, not inline it
        self.add(Quantity(key, rate_symbol(sym.symbol, order, angle), unit, text, MOTION,
                          f"{sym.label}: {word}"))
        return f"{{{key}}}"

    def rigid(self, n: str, a: str, omega: str, alpha: str) -> None:
        """n carried by a body turning at ω, α about a known point a."""
        rx, ry = self.rel(a, n)
        (vax, vay), (aax, aay) = self.vel(a), self.acc(a)
        w2 = sq(omega)
        self.point(n, lin((1, vax), (-1, mul(omega, ry))), lin((1, vay), (1, mul(omega, rx))),
                   lin((1, aax), (-1, mul(alpha, ry)), (-1, mul(w2, rx))),
                   lin((1, aay), (1, mul(alpha, rx)), (-1, mul(w2, ry))))

    def link_rates(self, a: str, b: str) -> tuple[str, str]:
        """ω and α of the line a→b: a known link's, else from the points' motion,
        ω = (r × v)/|r|², α = (r × a − 2 (r·v) ω)/|r|² (r = a→b)."""
        if (a, b) in self.links:
            return self.links[(a, b)]
        if (b, a) in self.links:
            return self.links[(b, a)]
        if a in self.c.ground and b in self.c.ground:
            return ZERO, ZERO
        r = self.rel(a, b)
        (vax, vay), (vbx, vby) = self.vel(a), self.vel(b)
        (aax, aay), (abx, aby) = self.acc(a), self.acc(b)
        v = (lin((1, vbx), (-1, vax)), lin((1, vby), (-1, vay)))
        acc = (lin((1, abx), (-1, aax)), lin((1, aby), (-1, aay)))
        r2 = dot(r, r)
        w_key, a_key = f"omega_{a}_{b}", f"alpha_{a}_{b}"
        omega = f"{{{w_key}}}"
        alpha = guard(r2, lin((1, cross(r, acc)), (-1, mul("2", dot(r, v), omega))))
        self.add(Quantity(w_key, f"ω({a}{b})", ANG_SPEED, guard(r2, cross(r, v)), MOTION,
                          f"angular velocity of {a}→{b}"),
                 Quantity(a_key, f"α({a}{b})", ANG_ACCEL, alpha, MOTION,
                          f"angular acceleration of {a}→{b}"))
        self.links[(a, b)] = (f"{{{w_key}}}", f"{{{a_key}}}")
        return self.links[(a, b)]

    def fixed_length(self, a: str, b: str) -> bool:
        """Is |ab| a constant (a link of a length that is not the actuator's, or two fixed
        points)? Then a point at given distances from a and b is carried by that link."""
        if a in self.c.ground and b in self.c.ground:
            return True
        for pair in ((a, b), (b, a)):
            length = self.c.rigid.get(pair, (None, None))[0]
            if length is not None:
                return not any(f"{{{k}}}" in length.text for k in self.c.swept)
        return False

    def side_rates(self, field: str, side) -> tuple[str, str]:
        """A dyad side's rate: zero for a link, the input's speed for the actuator itself."""
        if not any(k in side.text for k in (f"{{{s}}}" for s in self.c.swept)):
            return ZERO, ZERO
        if side.text == f"{{{self.c.input_key}}}":
            return self.speed, self.accel
        raise DescriptionError(field, "a side driven by the actuator must be its length itself "
                                      f"({self.c.input_key}), so that its rate is the input's")

    def two_circles(self, n: str, p: str, q: str, p_rates=(ZERO, ZERO), q_rates=(ZERO, ZERO),
                    p_len: str = "", q_len: str = "", q_sym=None, p_sym=None
                    ) -> tuple[str, str, str, str]:
        """R = n with |PR| = p and |QR| = q: R = Q + q e_q = P + p e_p differentiated,
        ω_q (i u_q) − ω_p (i u_p) = v_P − v_Q + ṗ e_p − q̇ e_q, solved by Cramer's rule over the
        determinant c = u_q × u_p (zero when P, Q, R are in line: a dead centre).
        Returns (ω_q, ω_p, α_q, α_p) as texts; defines n's motion."""
        uq, up = self.rel(q, n), self.rel(p, n)
        c = cross(uq, up)
        c = self.determinant(n, AREA, c)
        (vpx, vpy), (vqx, vqy) = self.vel(p), self.vel(q)
        (apx, apy), (aqx, aqy) = self.acc(p), self.acc(q)
        (pd, pdd), (qd, qdd) = p_rates, q_rates
        ep = tuple(guard(p_len, u) if pd != ZERO else ZERO for u in up)
        eq = tuple(guard(q_len, u) if qd != ZERO else ZERO for u in uq)
        dx = lin((1, vpx), (-1, vqx), (1, mul(pd, ep[0])), (-1, mul(qd, eq[0])))
        dy = lin((1, vpy), (-1, vqy), (1, mul(pd, ep[1])), (-1, mul(qd, eq[1])))
        wq = self.rate(q_sym, 1, guard(c, dot((dx, dy), up))) if q_sym else \
            self.alias(f"_wq_{n}", guard(c, dot((dx, dy), up)))
        wp = self.rate(p_sym, 1, guard(c, dot((dx, dy), uq))) if p_sym else \
            self.alias(f"_wp_{n}", guard(c, dot((dx, dy), uq)))
        vqx_, vqy_ = self.vel(q)
        vx = lin((1, vqx_), (1, mul(qd, eq[0])), (-1, mul(wq, uq[1])))
        vy = lin((1, vqy_), (1, mul(qd, eq[1])), (1, mul(wq, uq[0])))
        # second derivative: ..., the centripetal −ω² u and Coriolis 2 ṗ ω (i e_p) terms moved right
        ex = lin((1, apx), (-1, aqx), (-1, mul(sq(wp), up[0])), (1, mul(sq(wq), uq[0])),
                 (1, mul(pdd, ep[0])), (-1, mul("2", pd, wp, ep[1])),
                 (-1, mul(qdd, eq[0])), (1, mul("2", qd, wq, eq[1])))
        ey = lin((1, apy), (-1, aqy), (-1, mul(sq(wp), up[1])), (1, mul(sq(wq), uq[1])),
                 (1, mul(pdd, ep[1])), (1, mul("2", pd, wp, ep[0])),
                 (-1, mul(qdd, eq[1])), (-1, mul("2", qd, wq, eq[0])))
        aq = self.rate(q_sym, 2, guard(c, dot((ex, ey), up))) if q_sym else \
            self.alias(f"_aq_{n}", guard(c, dot((ex, ey), up)))
        ap = self.rate(p_sym, 2, guard(c, dot((ex, ey), uq))) if p_sym else \
            self.alias(f"_ap_{n}", guard(c, dot((ex, ey), uq)))
        ax = lin((1, aqx), (1, mul(qdd, eq[0])), (-1, mul("2", qd, wq, eq[1])),
                 (-1, mul(aq, uq[1])), (-1, mul(sq(wq), uq[0])))
        ay = lin((1, aqy), (1, mul(qdd, eq[1])), (1, mul("2", qd, wq, eq[0])),
                 (1, mul(aq, uq[0])), (-1, mul(sq(wq), uq[1])))
        self.point(n, vx, vy, ax, ay)
        return wq, wp, aq, ap

    def determinant(self, n: str, unit: str, text: str) -> str:
        """The determinant of the step's differentiated loop, a column of its own (Δ_n): zero
        exactly at a dead centre, where the rates that divide by it are #N/A."""
        self.add(Quantity(f"det_{n}", f"Δ_{n}", unit, text, MOTION,
                          f"determinant of the loop that places {n}"))
        return f"{{det_{n}}}"

    def alias(self, key: str, text: str) -> str:
        self.add(Quantity(key, key, "-", text, ALIAS))
        return f"{{{key}}}"

    def length_and_angle(self, a: str, b: str, length, angle) -> None:
        """|r| and the angle of r = a→b: ṙ = (r·v)/|r|, φ̇ = (r × v)/|r|²,
        r̈ = (|v|² + r·a − ṙ²)/|r|, φ̈ = (r × a − 2 (r·v) φ̇)/|r|²."""
        r = self.rel(a, b)
        (vax, vay), (vbx, vby) = self.vel(a), self.vel(b)
        (aax, aay), (abx, aby) = self.acc(a), self.acc(b)
        v = (lin((1, vbx), (-1, vax)), lin((1, vby), (-1, vay)))
        acc = (lin((1, abx), (-1, aax)), lin((1, aby), (-1, aay)))
        size = f"{{{length.key}}}"
        rd = self.rate(length, 1, guard(size, dot(r, v)), angle=False)
        self.rate(length, 2, guard(size, lin((1, dot(v, v)), (1, dot(r, acc)), (-1, sq(rd)))),
                  angle=False)
        if angle is not None:
            r2 = sq(size)
            w = self.rate(angle, 1, guard(r2, cross(r, v)))
            self.rate(angle, 2, guard(r2, lin((1, cross(r, acc)), (-1, mul("2", dot(r, v), w)))))
