"""The dyad step (RRR, Raven's triangle): a point at given distances from two known points,
placed by the cosine rule on the branch asked for; its rates solve the two circles
differentiated. A side may be the linear actuator's length.
"""
from __future__ import annotations

from ..columns import Column, Sym, polar, polar_columns, quantity
from ..excel import PRODUCT, angle_of_triangle_or_na, key, minus, plus
from ..expressions import expression
from ..model import LENGTH, RAD, DescriptionError, Model
from .step_type import StepType, Topology, fixed, schema_keys


def triangle(model: Model, *, side: str, angle: str, p: str, q: str, branch: str,
             psi: Sym, q_angle: Sym, q_offset: str = "", mu: Sym | None = None,
             p_interior: Sym | None = None, p_angle: Sym | None = None) -> None:
    """Raven's step: R joined to P by a link {p} and to Q by a link {q}; |QP| = {side} and
    angle(Q→P) = {angle} are known.

    ψ = ∠PQR, μ = ∠QRP and the angle at P by the cosine theorem; angle(Q→R) = ϕ − branch·ψ
    (+ q_offset, for a mechanism that measures its link from another direction); angle(P→R) is
    angle(Q→R) − branch·μ, or angle(Q→P) + π + branch·∠QPR when the angle at P is the one shown.
    """
    def cosine_rule(adjacent1: str, adjacent2: str, opposite: str) -> str:
        return angle_of_triangle_or_na(adjacent1, adjacent2, opposite, once=side)

    model.add(quantity(psi, RAD, cosine_rule(q, side, p)))
    if mu is not None:
        model.add(quantity(mu, RAD, cosine_rule(p, q, side)))
    if p_interior is not None:
        model.add(quantity(p_interior, RAD, cosine_rule(p, side, q)))
    model.add(quantity(q_angle, RAD, f"{{{angle}}}-{{{branch}}}*{{{psi.key}}}{q_offset}"))
    if p_angle is None:
        return
    if mu is not None and not q_offset:
        model.add(quantity(p_angle, RAD, f"{{{q_angle.key}}}-{{{branch}}}*{{{mu.key}}}"))
    elif p_interior is not None:
        model.add(quantity(p_angle, RAD, f"{{{angle}}}+PI()+{{{branch}}}*{{{p_interior.key}}}"))
    else:
        raise ValueError("angle(P→R) needs μ (with an unshifted angle(Q→R)) or the angle at P")


def place(c, field: str, s: dict) -> None:
    """R from |PR| = p_length, |QR| = q_length: the polar columns of Q→P, then the
    triangle's angles (the cosine rule) on the branch asked for."""
    name = s["point"]
    p = c.known_point(f"{field}.p", s["p"], name)
    q = c.known_point(f"{field}.q", s["q"], name)
    if p == q:
        raise DescriptionError(f"{field}.q", "must differ from p")
    # a linear actuator is a dyad side whose length is the swept input
    p_len = expression(f"{field}.p_length", s["p_length"], c.symbols | c.swept)
    q_len = expression(f"{field}.q_length", s["q_length"], c.symbols | c.swept)
    branch = c.branch(f"{field}.branch", s["branch"])
    n = name
    cols = c.columns(field, s, [
        *polar_columns(n, q, p),
        Column("psi", f"psi_{n}", f"ψ_{n}", f"∠{p}{q}{n}", RAD),
        Column("mu", f"mu_{n}", f"μ_{n}", f"transmission angle ∠{q}{n}{p}", RAD, True),
        Column("p_interior", f"p_interior_{n}", f"∠{q}{p}{n}", f"∠{q}{p}{n}", RAD,
               shown=False),
        Column("theta_q", f"theta_q_{n}", f"θ({q}{n})", f"angle of {q}→{n}", RAD, True),
        Column("theta_p", f"theta_p_{n}", f"θ({p}{n})", f"angle of {p}→{n}", RAD, True),
        Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
        Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
    (px, py), (qx, qy) = c.points[p], c.points[q]
    polar(c.model, minus(px, qx).text, minus(py, qy).text,
          cols["xs"], cols["ys"], cols["s"], cols["phi"], closes=True)
    p_key = c.length_operand(f"{field}.p_length", f"p_length_{n}", p_len, s["p_length"])
    q_key = c.length_operand(f"{field}.q_length", f"q_length_{n}", q_len, s["q_length"])
    # angle(P→R) from μ, or from the angle at P when μ is hidden and that angle is shown.
    use_p = not cols["mu"].shown and cols["p_interior"].shown
    triangle(c.model, side=cols["s"].key, angle=cols["phi"].key, p=p_key, q=q_key,
             branch=branch, psi=cols["psi"], q_angle=cols["theta_q"],
             mu=None if use_p else cols["mu"],
             p_interior=cols["p_interior"] if use_p else None, p_angle=cols["theta_p"])
    if not use_p and cols["p_interior"].shown:
        raise DescriptionError(f"{field}.columns.p_interior",
                               "is shown only in place of mu (set mu = false)")
    r = q_len.at_least(PRODUCT)
    theta_q = cols["theta_q"].key
    c.add_point(field, n, cols["x"], cols["y"],
                plus(qx, f"{r}*COS({{{theta_q}}})"), plus(qy, f"{r}*SIN({{{theta_q}}})"))
    c.rigid[(q, n)] = (q_len, key(theta_q))
    c.rigid[(p, n)] = (p_len, key(cols["theta_p"].key))
    c.witness(field, cols, ("theta_p", "theta_q", "x", "y", "mu", "psi"))
    c.records.append({"type": "dyad", "field": field, "point": n, "p": p, "q": q,
                      "p_length": p_len, "q_length": q_len, "theta_q": cols["theta_q"],
                      "theta_p": cols["theta_p"]})
    c.dyads.append({"point": n, "p": p, "q": q, "p_length": p_len, "q_length": q_len,
                    "mu": cols["mu"]})


def rates(w, rec: dict) -> None:
    """The two circles about P and Q differentiated; a side that is the actuator's length
    changes at the input's rate."""
    n, p, q = rec["point"], rec["p"], rec["q"]
    p_rates = w.side_rates(f"{rec['field']}.p_length", rec["p_length"])
    q_rates = w.side_rates(f"{rec['field']}.q_length", rec["q_length"])
    wq, wp, aq, ap = w.two_circles(n, p, q, p_rates, q_rates,
                                   rec["p_length"].text, rec["q_length"].text,
                                   rec["theta_q"], rec["theta_p"])
    w.links[(q, n)] = (wq, aq)
    w.links[(p, n)] = (wp, ap)


def forces(w, rec: dict) -> None:
    """The two links pinned at the point, or the link the actuator side pushes."""
    n, p, q = rec["point"], rec["p"], rec["q"]
    if w.actuator == (p, n):
        w.actuated(n, p, q, rec["field"])
    elif w.actuator == (q, n):
        w.actuated(n, q, p, rec["field"])
    else:
        w.two_links(n, p, q, rec["field"])


def topology(rec: dict, length_input: str | None) -> Topology:
    """Two links pinned at the point, from p and from q; the side whose length is the linear
    actuator's input (p's first) is that actuator."""
    n = rec["point"]
    actuator = next(((rec[end], n) for end, side in (("p", "p_length"), ("q", "q_length"))
                     if length_input is not None and rec[side].text == length_input), None)
    return Topology(links=((rec["p"], n), (rec["q"], n)), actuator=actuator)


STEP = StepType(schema_keys("dyad"), place, rates, fixed({"p_length": 1, "q_length": 1}),
                forces, topology)
