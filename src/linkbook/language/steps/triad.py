"""The triad step (a class-III group, docs/coupled-loops.md): a ternary link with joints N0, N1,
N2, each held by a binary link to a known pivot P0, P1, P2, which no step can place one point
at a time. The book solves it the textbook's way (§3.9), by Newton–Raphson in two unknowns,
the angle φ of the binary link P0→N0 and the angle θ of the ternary's side N0→N1:

    N0 = P0 + L0·e^{iφ},  N1 = N0 + S0·e^{iθ},  N2 = N0 + S2·e^{i(θ + γ)}
    r1 = (|N1 − P1|² − L1²)/(2·L1) = 0,  r2 = (|N2 − P2|² − L2²)/(2·L2) = 0

(γ the ternary's signed angle at N0, its sense that of the sketch). Each iteration is a block of
columns: the iterate, its residuals, its Jacobian and the correction by Cramer's rule. Row r
starts from row r − 1's solution; the first row, and a row after one that did not converge,
from the sketch. A row whose last correction is above TOLERANCE (it did not converge in the
iterations written) or whose Jacobian is singular is #N/A, never a wrong number. The rates
solve the same Jacobian at the solution once for the velocities, once for the accelerations.
"""
from __future__ import annotations

from ..columns import Column, Sym, quantity
from ..excel import ZERO, Expr, cross, dot, guard, lin, mul, one_group, sq
from ..mechanisms import TO_METRES
from ..model import (ALIAS, AREA, COLUMN, LENGTH, NEWTON, RAD, DescriptionError,
                     Quantity)
from .step_type import StepType, Topology, fixed, schema_keys

ITERATIONS = 6        # Newton iterations per row unless the step says (docs/coupled-loops.md)
TOLERANCE = "1E-9"    # rad: the last correction of a converged row


def _triple(field: str, s: dict, key: str) -> list:
    value = s[key]
    if not isinstance(value, list) or len(value) != 3:
        raise DescriptionError(f"{field}.{key}", f"must hold three entries (got {value!r})")
    return value


def _names(c, field: str, s: dict) -> tuple[list[str], list[str]]:
    """The three new joints and the three known pivots."""
    points = _triple(field, s, "points")
    for i, n in enumerate(points):
        c.check_new_point(f"{field}.points[{i}]", n)
    if len(set(points)) != 3:
        raise DescriptionError(f"{field}.points", f"must be three different points (got "
                                                   f"{points!r})")
    pivots = [c.known_point(f"{field}.pivots[{i}]", p) for i, p in
              enumerate(_triple(field, s, "pivots"))]
    for i, p in enumerate(pivots):
        if p in points:
            raise DescriptionError(f"{field}.pivots[{i}]", f"{p!r} is a point this step defines")
    return points, pivots


def _lengths(c, field: str, s: dict, key: str, hint: str, n: str) -> list[str]:
    """Keys standing for three positive lengths (checked at build; #N/A in the book where an
    edited input makes one non-positive)."""
    out = []
    for i, raw in enumerate(_triple(field, s, key)):
        where = f"{field}.{key}[{i}]"
        out.append(c.length_operand(where, f"{hint}{i}_{n}", c.expr(where, raw), raw))
    return out


def _sketch(c, field: str, s: dict) -> list[tuple[str, str]]:
    pairs = []
    for i, pair in enumerate(_triple(field, s, "sketch")):
        where = f"{field}.sketch[{i}]"
        if not isinstance(pair, list) or len(pair) != 2:
            raise DescriptionError(where, f"must be [x, y] (got {pair!r})")
        pairs.append(tuple(c.expr(f"{where}[{k}]", pair[k]).text for k in (0, 1)))
    return pairs


def _iterations(field: str, s: dict) -> int:
    n = s.get("iterations", ITERATIONS)
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 20:
        raise DescriptionError(f"{field}.iterations", f"must be a whole number from 1 to 20 "
                                                      f"(got {n!r})")
    return n


def _k(key: str) -> str:
    return f"{{{key}}}"


class _Writer:
    """The position formulas of one triad, quantity by quantity into the compiler's model."""

    def __init__(self, c, field: str, s: dict):
        self.c, self.field, self.step = c, field, s
        self.points, self.pivots = _names(c, field, s)
        n = self.n = self.points[0]
        self.links = _lengths(c, field, s, "lengths", "link", n)
        self.sides = _lengths(c, field, s, "sides", "side", n)
        self.sketch = _sketch(c, field, s)
        self.iterations = _iterations(field, s)

    def add(self, key: str, symbol: str, unit: str, formula: str, label: str,
            role: str = COLUMN) -> str:
        self.c.model.add(Quantity(key, symbol, unit, formula, role, label))
        return _k(key)

    def pivot(self, i: int) -> tuple[str, str]:
        x, y = self.c.points[self.pivots[i]]
        return x.text, y.text

    def turn(self) -> str:
        """γ: the ternary's angle at N0 from N0→N1 to N0→N2, signed by the sketch's sense (a
        named constant where the sides are parameters)."""
        (x0, y0), (x1, y1), (x2, y2) = ((f"({x})", f"({y})") for x, y in self.sketch)
        sense = f"IF(({x1}-{x0})*({y2}-{y0})-({y1}-{y0})*({x2}-{x0})>0,1,-1)"
        s0, s1, s2 = self.sides
        cosine = f"({_k(s0)}^2+{_k(s2)}^2-{_k(s1)}^2)/(2*{_k(s0)}*{_k(s2)})"
        text = f"{sense}*IFERROR(IF(ABS({cosine})>1,NA(),ACOS({cosine})),NA())"
        p = self.points
        key, symbol = f"gamma_{self.n}", f"γ_{self.n}"
        role = self.c.role(text, Sym(key, symbol))
        return self.add(key, symbol, RAD, text, f"ternary's angle ∠{p[1]}{p[0]}{p[2]}, signed",
                        role)

    def joints(self, phi: str, theta: str, gamma: str, tag: str) -> list[tuple[str, str]]:
        """N0, N1, N2 at the angles φ, θ (texts): aliases written into the formulas."""
        (px, py) = self.pivot(0)
        l0, s0, s2 = (_k(k) for k in (self.links[0], self.sides[0], self.sides[2]))
        out = []
        for name, base, r, a in ((f"_{tag}0", (px, py), l0, phi), (f"_{tag}1", None, s0, theta),
                                 (f"_{tag}2", None, s2, f"{theta}+{gamma}")):
            bx, by = base if base is not None else out[0]
            x = self.add(f"{name}x_{self.n}", name, LENGTH, f"{bx}+{r}*COS({a})", "", ALIAS)
            y = self.add(f"{name}y_{self.n}", name, LENGTH, f"{by}+{r}*SIN({a})", "", ALIAS)
            out.append((x, y))
        return out

    def jacobian(self, phi: str, theta: str, gamma: str, joints, k: int | str):
        """The residuals and the Jacobian of the iterate (φ, θ), as columns (texts back)."""
        n, p = self.n, self.points
        l0, l1, l2, s0, s2 = (_k(x) for x in (*self.links, self.sides[0], self.sides[2]))
        d, e, f = joints
        pe, pf = self.pivot(1), self.pivot(2)
        ue = (lin((1, e[0]), (-1, pe[0])), lin((1, e[1]), (-1, pe[1])))
        uf = (lin((1, f[0]), (-1, pf[0])), lin((1, f[1]), (-1, pf[1])))
        arm = (mul(l0, f"COS({phi})"), mul(l0, f"SIN({phi})"))
        side = (mul(s0, f"COS({theta})"), mul(s0, f"SIN({theta})"))
        other = (mul(s2, f"COS({theta}+{gamma})"), mul(s2, f"SIN({theta}+{gamma})"))
        res = [self.add(f"r{i}_{k}_{n}", f"r{i}({k})", LENGTH,
                        f"({sq(u[0])}+{sq(u[1])}-{sq(ln)})/(2*{ln})",
                        f"iteration {k}: (|{p[i]}{pv}|² − L²)/2L")
               for i, u, ln, pv in ((1, ue, l1, self.pivots[1]), (2, uf, l2, self.pivots[2]))]
        jac = [self.add(f"J{i}{j}_{k}_{n}", f"J{i}{j}({k})", LENGTH,
                        f"{_p(cross(v, u))}/{ln}", f"iteration {k}: ∂r{i}/∂{w}")
               for i, u, ln in ((1, ue, l1), (2, uf, l2))
               for j, v, w in ((1, arm, "φ"), (2, side if i == 1 else other, "θ"))]
        return res, jac

    def place(self) -> None:
        c, n, p = self.c, self.n, self.points
        gamma = self.turn()
        cols = c.columns(self.field, self.step, self.defaults())
        # each row starts from the solution in the row above (excel.PLACEHOLDER's @above)
        final_phi, final_theta = cols[f"theta_{n}"].key, cols[f"theta_{p[0]}{p[1]}"].key
        (px, py), ((sx0, sy0), (sx1, sy1), _) = self.pivot(0), self.sketch
        phi = self.add(f"phi_0_{n}", f"φ(0)", RAD,
                       f"IF(ISNUMBER({{{final_phi}@above}}),{{{final_phi}@above}},"
                       f"ATAN2(({sx0})-({px}),({sy0})-({py})))",
                       f"iteration 0: angle of {self.pivots[0]}→{n}")
        theta = self.add(f"th_0_{n}", f"θ(0)", RAD,
                         f"IF(ISNUMBER({{{final_theta}@above}}),{{{final_theta}@above}},"
                         f"ATAN2(({sx1})-({sx0}),({sy1})-({sy0})))",
                         f"iteration 0: angle of {p[0]}→{p[1]}")
        for k in range(self.iterations):
            joints = self.joints(phi, theta, gamma, f"i{k}")
            (r1, r2), (j11, j12, j21, j22) = self.jacobian(phi, theta, gamma, joints, k)
            det = f"({j11}*{j22}-{j12}*{j21})"
            dphi = self.add(f"dphi_{k}_{n}", f"Δφ({k})", RAD,
                            guard(det, f"{j22}*{r1}-{j12}*{r2}"), f"iteration {k}: correction")
            dth = self.add(f"dth_{k}_{n}", f"Δθ({k})", RAD,
                           guard(det, f"{j11}*{r2}-{j21}*{r1}"), f"iteration {k}: correction")
            if k + 1 < self.iterations:
                phi = self.add(f"phi_{k + 1}_{n}", f"φ({k + 1})", RAD, f"{phi}-{dphi}",
                               f"iteration {k + 1}: φ")
                theta = self.add(f"th_{k + 1}_{n}", f"θ({k + 1})", RAD, f"{theta}-{dth}",
                                 f"iteration {k + 1}: θ")
        conv = self.add(f"conv_{n}", f"|Δ|_{n}", RAD,
                        f"IF(ABS({dphi})>ABS({dth}),ABS({dphi}),ABS({dth}))",
                        f"last correction (done if ≤ {TOLERANCE})")
        done = f"{conv}<={TOLERANCE}"
        self.add_sym(cols[f"theta_{n}"], f"IF({done},{phi}-{dphi},NA())")
        self.add_sym(cols[f"theta_{p[0]}{p[1]}"], f"IF({done},{theta}-{dth},NA())")
        self.place_points(cols, gamma)

    def defaults(self) -> list[Column]:
        p, q = self.points, self.pivots
        out = [Column(f"theta_{p[0]}", f"theta_{p[0]}", f"θ({q[0]}{p[0]})",
                      f"angle of {q[0]}→{p[0]}", RAD, True),
               Column(f"theta_{p[0]}{p[1]}", f"theta_{p[0]}{p[1]}", f"θ({p[0]}{p[1]})",
                      f"ternary: angle of {p[0]}→{p[1]}", RAD, True)]
        out += [Column(f"theta_{p[i]}", f"theta_{p[i]}", f"θ({q[i]}{p[i]})",
                       f"angle of {q[i]}→{p[i]}", RAD, True) for i in (1, 2)]
        for name in p:
            out += [Column(f"x{name}", f"x{name}", f"x{name}", f"x of {name}", LENGTH),
                    Column(f"y{name}", f"y{name}", f"y{name}", f"y of {name}", LENGTH)]
        return out

    def add_sym(self, sym: Sym, formula: str) -> str:
        self.c.model.add(quantity(sym, RAD if sym.key.startswith("theta") else LENGTH, formula))
        return _k(sym.key)

    def place_points(self, cols, gamma: str) -> None:
        c, p, q = self.c, self.points, self.pivots
        phi, theta = _k(cols[f"theta_{p[0]}"].key), _k(cols[f"theta_{p[0]}{p[1]}"].key)
        (px, py) = self.pivot(0)
        l0, s0, s2 = (_k(k) for k in (self.links[0], self.sides[0], self.sides[2]))
        c.add_point(self.field, p[0], cols[f"x{p[0]}"], cols[f"y{p[0]}"],
                    f"{px}+{l0}*COS({phi})", f"{py}+{l0}*SIN({phi})")
        x0, y0 = (e.text for e in c.points[p[0]])
        c.add_point(self.field, p[1], cols[f"x{p[1]}"], cols[f"y{p[1]}"],
                    f"{x0}+{s0}*COS({theta})", f"{y0}+{s0}*SIN({theta})")
        c.add_point(self.field, p[2], cols[f"x{p[2]}"], cols[f"y{p[2]}"],
                    f"{x0}+{s2}*COS({theta}+{gamma})", f"{y0}+{s2}*SIN({theta}+{gamma})")
        for i in (1, 2):
            (bx, by), (nx, ny) = self.pivot(i), (e.text for e in c.points[p[i]])
            self.add_sym(cols[f"theta_{p[i]}"], f"ATAN2({nx}-{_p(bx)},{ny}-{_p(by)})")
        for i in range(3):
            length = Expr(_k(self.links[i]))
            c.rigid[(q[i], p[i])] = (length, Expr(_k(cols[f"theta_{p[i]}"].key)))
        c.rigid[(p[0], p[1])] = (Expr(_k(self.sides[0])), Expr(theta))
        c.witness(self.field, cols, (f"x{p[0]}", f"y{p[0]}", f"theta_{p[0]}"))
        c.records.append({"type": "triad", "field": self.field, "points": p, "pivots": q,
                          "links": self.links, "sides": self.sides, "gamma": gamma,
                          "cols": cols})


def _p(text: str) -> str:
    """The text in brackets unless it is one bracket group already."""
    return text if one_group(text) and text.startswith("(") else f"({text})"


def place(c, field: str, s: dict) -> None:
    """The triad's iterations, its solution's angles and its three joints."""
    _Writer(c, field, s).place()


def _angle_rates(w, sym, centre: str, point: str) -> tuple[str, str]:
    """ω and α of the line centre→point from the points' motion (r = point − centre):
    ω = (r × v)/|r|², α = (r × a − 2 (r·v) ω)/|r|²."""
    r = w.rel(centre, point)
    (vcx, vcy), (vpx, vpy) = w.vel(centre), w.vel(point)
    (acx, acy), (apx, apy) = w.acc(centre), w.acc(point)
    v = (lin((1, vpx), (-1, vcx)), lin((1, vpy), (-1, vcy)))
    a = (lin((1, apx), (-1, acx)), lin((1, apy), (-1, acy)))
    r2 = dot(r, r)
    omega = w.rate(sym, 1, guard(r2, cross(r, v)))
    return omega, w.rate(sym, 2, guard(r2, lin((1, cross(r, a)), (-1, mul("2", dot(r, v),
                                                                          omega)))))


def rates(w, rec: dict) -> None:
    """The Jacobian at the solution, J·(φ̇, θ̇) = g and J·(φ̈, θ̈) = h, each by Cramer's rule
    over the loop's determinant (a Motion column); the joints' motion from the two angles'."""
    p, q, cols = rec["points"], rec["pivots"], rec["cols"]
    l1, l2 = (_k(k) for k in rec["links"][1:])
    arm, side, other = w.rel(q[0], p[0]), w.rel(p[0], p[1]), w.rel(p[0], p[2])
    ue, uf = w.rel(q[1], p[1]), w.rel(q[2], p[2])
    j11, j12 = (f"{_p(cross(arm, ue))}/{l1}", f"{_p(cross(side, ue))}/{l1}")
    j21, j22 = (f"{_p(cross(arm, uf))}/{l2}", f"{_p(cross(other, uf))}/{l2}")
    det = w.determinant(p[0], AREA, f"{j11}*{j22}-{j12}*{j21}")
    (va, aa), (vb, ab), (vc, ac) = ((w.vel(x), w.acc(x)) for x in q)
    g1 = f"-{_p(dot(ue, (lin((1, va[0]), (-1, vb[0])), lin((1, va[1]), (-1, vb[1])))))}/{l1}"
    g2 = f"-{_p(dot(uf, (lin((1, va[0]), (-1, vc[0])), lin((1, va[1]), (-1, vc[1])))))}/{l2}"
    phi_sym, theta_sym = cols[f"theta_{p[0]}"], cols[f"theta_{p[0]}{p[1]}"]
    wphi = w.rate(phi_sym, 1, guard(det, f"{j22}*{_p(g1)}-{j12}*{_p(g2)}"))
    wth = w.rate(theta_sym, 1, guard(det, f"{j11}*{_p(g2)}-{j21}*{_p(g1)}"))
    # the joints' velocities: N0 turns about P0 at φ̇, N1 and N2 about N0 at θ̇
    vd = (lin((1, va[0]), (-1, mul(wphi, arm[1]))), lin((1, va[1]), (1, mul(wphi, arm[0]))))
    ve = (lin((1, vd[0]), (-1, mul(wth, side[1]))), lin((1, vd[1]), (1, mul(wth, side[0]))))
    vf = (lin((1, vd[0]), (-1, mul(wth, other[1]))), lin((1, vd[1]), (1, mul(wth, other[0]))))
    # twice differentiated: (E − B)·(a_E − a_B) + |v_E − v_B|² = 0, a_E's unknown part moved left
    known_e = tuple(lin((1, aa[i]), (-1, ab[i]), (-1, mul(sq(wphi), arm[i])),
                        (-1, mul(sq(wth), side[i]))) for i in (0, 1))
    known_f = tuple(lin((1, aa[i]), (-1, ac[i]), (-1, mul(sq(wphi), arm[i])),
                        (-1, mul(sq(wth), other[i]))) for i in (0, 1))
    rel_e = (lin((1, ve[0]), (-1, vb[0])), lin((1, ve[1]), (-1, vb[1])))
    rel_f = (lin((1, vf[0]), (-1, vc[0])), lin((1, vf[1]), (-1, vc[1])))
    h1 = f"-({dot(rel_e, rel_e)}+{_p(dot(ue, known_e))})/{l1}"
    h2 = f"-({dot(rel_f, rel_f)}+{_p(dot(uf, known_f))})/{l2}"
    aphi = w.rate(phi_sym, 2, guard(det, f"{j22}*{_p(h1)}-{j12}*{_p(h2)}"))
    ath = w.rate(theta_sym, 2, guard(det, f"{j11}*{_p(h2)}-{j21}*{_p(h1)}"))
    w.point(p[0], *vd, lin((1, aa[0]), (-1, mul(aphi, arm[1])), (-1, mul(sq(wphi), arm[0]))),
            lin((1, aa[1]), (1, mul(aphi, arm[0])), (-1, mul(sq(wphi), arm[1]))))
    (ad0, ad1) = w.acc(p[0])
    for name, r, v in ((p[1], side, ve), (p[2], other, vf)):
        w.point(name, *v, lin((1, ad0), (-1, mul(ath, r[1])), (-1, mul(sq(wth), r[0]))),
                lin((1, ad1), (1, mul(ath, r[0])), (-1, mul(sq(wth), r[1]))))
    w.links[(q[0], p[0])] = (wphi, aphi)
    w.links[(p[0], p[1])] = (wth, ath)
    w.links[(p[0], p[2])] = (wth, ath)
    w.links[(p[1], p[2])] = (wth, ath)
    for i in (1, 2):
        w.links[(q[i], p[i])] = _angle_rates(w, cols[f"theta_{p[i]}"], q[i], p[i])


def forces(w, rec: dict) -> None:
    """The group's pin forces (docs/coupled-loops.md, "Forces"). Binary link k, from its pivot
    P_k to its joint N_k, puts on the ternary at N_k the force f_k·u_k + g_k·n_k (u_k the unit
    vector P_k→N_k, n_k it turned +90°): its moment balance about P_k gives g_k; the ternary's
    ΣF = 0 and ΣM = 0 about N0 are then linear in f_0, f_1, f_2, solved by Cramer's rule over
    a determinant that is zero where the binary links' lines meet in one point (#N/A there);
    each binary link's force balance gives its pivot's force."""
    p, q, where = rec["points"], rec["pivots"], rec["field"]
    ternary = w.body(*p)
    links = [w.body(q[k], p[k]) for k in range(3)]
    for k in range(3):
        w.carrier(p[k], [links[k], ternary], where)
    units = [_unit(w, q[k], p[k], _k(rec["links"][k])) for k in range(3)]
    normal = [_normal_part(w, links[k], ternary, q[k], p[k], _k(rec["links"][k]))
              for k in range(3)]
    columns, known = _ternary_equations(w, ternary, p, units, normal)
    det = w.w.alias(f"_Dtriad_{p[0]}", _det3(*columns))
    w.solved.update({ternary.number, *(b.number for b in links)})
    for k in range(3):
        solved = [known if i == k else c for i, c in enumerate(columns)]
        f = _component(w, links[k], ternary, q[k], p[k], "a", guard(det, _det3(*solved)),
                       "along")
        u, g = units[k], normal[k]
        x, y = w.inner(links[k], ternary, p[k], lin((1, mul(f, u[0])), (-1, mul(g, u[1]))),
                       lin((1, mul(f, u[1])), (1, mul(g, u[0]))))
        fx, fy = w.resultant(links[k])
        w.outer(links[k], q[k], lin((1, x), (-1, fx)), lin((1, y), (-1, fy)), where)


def _ternary_equations(w, ternary, points, units, normal):
    """The ternary's ΣF = 0 and ΣM = 0 about N0 as A·f = b in f_0, f_1, f_2: A's columns (u_k,
    r_k × u_k), r_k = N_k − N0 in metres (0 for k = 0), and b = −(its known loads) − Σ g_k·n_k
    (n_k's moment r_k × n_k = r_k·u_k)."""
    arms = [w.arm(n, points[0]) for n in points[1:]]
    columns = [(units[0][0], units[0][1], ZERO)] + \
        [(u[0], u[1], cross(r, u)) for u, r in zip(units[1:], arms)]
    (tx, ty), moment = w.resultant(ternary), w.moment(ternary, points[0])
    known = (lin((-1, tx), *((1, mul(g, u[1])) for g, u in zip(normal, units))),
             lin((-1, ty), *((-1, mul(g, u[0])) for g, u in zip(normal, units))),
             lin((-1, moment), *((-1, mul(g, dot(r, u)))
                                 for g, u, r in zip(normal[1:], units[1:], arms))))
    return columns, known


def _unit(w, pivot: str, joint: str, length: str) -> tuple[str, str]:
    """The unit vector pivot→joint of a binary link of this length."""
    (nx, ny), (px, py) = w.pos(joint), w.pos(pivot)
    return (f"{_p(lin((1, nx), (-1, px)))}/{length}", f"{_p(lin((1, ny), (-1, py)))}/{length}")


def _normal_part(w, link, ternary, pivot: str, joint: str, length: str) -> str:
    """g: the binary link turns about its pivot, so its force on the ternary has the moment
    of its known loads there, L·g = M(pivot) (#N/A where the joint is)."""
    text = f"{_p(w.moment(link, pivot))}/({{{TO_METRES}}}*{length})"
    return _component(w, link, ternary, pivot, joint, "n",
                      f"IF(ISNUMBER({w.pos(joint)[0]}),{text},NA())", "across")


def _component(w, link, ternary, pivot: str, joint: str, kind: str, text: str,
               way: str) -> str:
    """The column of a binary link's force on the ternary along its link or across it."""
    pair = tuple(sorted((link.number, ternary.number)))
    return w.add(f"F{kind}_{joint}", f"F{kind}({joint})", NEWTON, text,
                 f"link {link.number} on link {ternary.number} at {joint}, {way} "
                 f"{pivot}→{joint}{' turned +90°' if kind == 'n' else ''}",
                 (2, pair, 1 if kind == "a" else 2))


def _det3(a: tuple[str, str, str], b: tuple[str, str, str], c: tuple[str, str, str]) -> str:
    """The determinant of the 3×3 matrix of these columns."""
    return lin((1, mul(a[0], lin((1, mul(b[1], c[2])), (-1, mul(b[2], c[1]))))),
               (-1, mul(a[1], lin((1, mul(b[0], c[2])), (-1, mul(b[2], c[0]))))),
               (1, mul(a[2], lin((1, mul(b[0], c[1])), (-1, mul(b[1], c[0]))))))


def topology(rec: dict, length_input: str | None) -> Topology:
    """Three binary links, pivot to joint, and the ternary link through the three joints."""
    p, q = rec["points"], rec["pivots"]
    return Topology(links=tuple(zip(q, p)) + (tuple(p),))


STEP = StepType(schema_keys("triad"), place, rates,
                fixed({"lengths": 1, "sides": 1, "sketch": 1}), forces, topology)
