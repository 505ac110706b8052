"""The slide step (RPR, the inverted slider-crank): a link turning about a pivot whose slide
line, at an offset from the pivot, passes through a known point.
"""
from __future__ import annotations

from ..columns import Column, Sym, polar, polar_columns, quantity
from ..excel import PRODUCT, acos_or_na, dot, guard, key, lin, minus, mul, plus, sq
from ..model import LENGTH, RAD, DescriptionError, Model
from .step_type import Block, StepType, Topology, fixed, schema_keys


def offset_slide(model: Model, *, p: str, angle: str, offset: str, branch: str,
                 psi: Sym, travel: Sym, link_angle: Sym, slide_angle: Sym) -> None:
    """The inverted slider-crank step: the slide line sits at distance {offset} from the pivot.

    The triangle pivot–foot–pin is right-angled at the foot: ψ = acos(offset/p), travel = p·sin ψ.
    """
    model.add(
        quantity(psi, RAD, acos_or_na(f"{{{offset}}}/{{{p}}}")),
        quantity(travel, LENGTH, f"{{{p}}}*SIN({{{psi.key}}})"),
        quantity(link_angle, RAD, f"{{{angle}}}-{{{branch}}}*{{{psi.key}}}"),
        quantity(slide_angle, RAD, f"{{{link_angle.key}}}+{{{branch}}}*PI()/2"),
    )


def place(c, field: str, s: dict) -> None:
    """The polar columns of pivot→P, then the right triangle pivot–foot–P: the link's
    angle and the travel along the slide."""
    n = s["point"]
    p = c.known_point(f"{field}.p", s["p"], n)
    pivot = c.known_point(f"{field}.pivot", s["pivot"], n)
    if p == pivot:
        raise DescriptionError(f"{field}.pivot", "must differ from p")
    offset = c.expr(f"{field}.offset", s["offset"])
    branch = c.branch(f"{field}.branch", s["branch"])
    cols = c.columns(field, s, [
        *polar_columns(n, pivot, p),
        Column("psi", f"psi_{n}", f"ψ_{n}", f"∠{p}{pivot}{n}", RAD),
        Column("travel", f"travel_{n}", f"|{n}{p}|", f"slide travel |{n}{p}|", LENGTH),
        Column("theta", f"theta_{n}", f"θ({pivot}{n})", f"link, angle of {pivot}→{n}", RAD,
               True),
        Column("theta_slide", f"theta_slide_{n}", f"θ({n}{p})", f"slide, angle of {n}→{p}",
               RAD, True),
        Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
        Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
    (px, py), (qx, qy) = c.points[p], c.points[pivot]
    polar(c.model, minus(px, qx).text, minus(py, qy).text,
          cols["xs"], cols["ys"], cols["s"], cols["phi"])
    offset_key = c.operand(f"offset_{n}", offset)
    offset_slide(c.model, p=cols["s"].key, angle=cols["phi"].key, offset=offset_key,
                 branch=branch, psi=cols["psi"], travel=cols["travel"],
                 link_angle=cols["theta"], slide_angle=cols["theta_slide"])
    r, t = offset.at_least(PRODUCT), cols["theta"].key
    c.add_point(field, n, cols["x"], cols["y"],
                plus(qx, f"{r}*COS({{{t}}})"), plus(qy, f"{r}*SIN({{{t}}})"))
    c.rigid[(n, p)] = (None, key(cols["theta_slide"].key))
    c.witness(field, cols, ("theta", "travel", "x", "y", "psi"))
    slide = (f"COS({{{cols['theta_slide'].key}}})", f"SIN({{{cols['theta_slide'].key}}})")
    c.slides_on(n, "guide", n, slide, cols["travel"])
    c.block(p, slide)
    c.records.append({"type": "slide", "field": field, "point": n, "p": p, "pivot": pivot,
                      "theta": cols["theta"], "theta_slide": cols["theta_slide"],
                      "travel": cols["travel"], "direction": slide})


def rates(w, rec: dict) -> None:
    """The slide line, square to the link at the offset, passes through P:
    (P − Q)·e = offset, e = (cos θ, sin θ); differentiated, θ̇ (P − Q)·(i e) = −(v_P − v_Q)·e,
    over the determinant (P − Q)·(i e) (zero where the travel is zero)."""
    n, p, q = rec["point"], rec["p"], rec["pivot"]
    th = f"{{{rec['theta'].key}}}"
    e, ie = (f"COS({th})", f"SIN({th})"), (f"-SIN({th})", f"COS({th})")
    qp = w.rel(q, p)
    (vpx, vpy), (vqx, vqy) = w.vel(p), w.vel(q)
    (apx, apy), (aqx, aqy) = w.acc(p), w.acc(q)
    dv = (lin((1, vpx), (-1, vqx)), lin((1, vpy), (-1, vqy)))
    da = (lin((1, apx), (-1, aqx)), lin((1, apy), (-1, aqy)))
    den = w.determinant(n, LENGTH, dot(qp, ie))
    td = w.rate(rec["theta"], 1, guard(den, lin((-1, dot(dv, e)))))
    tdd = w.rate(rec["theta"], 2, guard(den, lin((-1, dot(da, e)),
                                                 (-1, mul("2", td, dot(dv, ie))),
                                                 (1, mul(sq(td), dot(qp, e))))))
    w.links[(q, n)] = (td, tdd)
    w.links[(n, p)] = w.rates(rec["theta_slide"], td, tdd)
    w.rigid(n, q, td, tdd)
    # the travel |nP| = |(P − Q)·(i e)|: its rates, with the sign of (P − Q)·(i e)
    sign = f"SIGN({den})"
    w.rates(rec["travel"],
            mul(sign, lin((1, dot(dv, ie)), (-1, mul(td, dot(qp, e))))),
            mul(sign, lin((1, dot(da, ie)), (-1, mul("2", td, dot(dv, e))),
                          (-1, mul(tdd, dot(qp, e))), (-1, mul(sq(td), dot(qp, ie))))),
            angle=False)


def forces(w, rec: dict) -> None:
    """The block at P on the slide's link (pivot Q, point N), through the force writer `w`."""
    turning_guide(w, w.body(rec["pivot"], rec["point"]), w.body(rec["p"], block=True),
                  rec["pivot"], rec["point"], rec["field"])


def turning_guide(w, link, blk, pivot: str, name: str, where: str) -> None:
    """The block b at P slides on the link L turning about Q (`pivot`), along the line e, through
    the force writer `w`: the guide pushes it with N·n (n = e turned +90°) and the couple
    M = −M_b(P). L turns about Q under −N·n at P and −M: N·((P−Q)·e) = M_L(Q) + M_b(P), zero
    when P is at the foot of Q on the line. The block's pin at P takes −N·n − ΣF_b; L's pivot
    N·n − ΣF_L. `name` names the determinant's alias (a slide's point, a vector's key)."""
    p = blk.joints[0]
    ex, ey = blk.line
    a = w.arm(p, pivot)
    det = w.w.alias(f"_Dforce_{name}", lin((1, mul(ex, a[0])), (1, mul(ey, a[1]))))
    normal = w.guide_normal(link, blk, guard(det, lin((1, w.moment(link, pivot)),
                                                      (1, w.moment(blk, p)))))
    nx, ny = w.neg(mul(ey, normal)), mul(ex, normal)
    kb, kl = w.resultant(blk), w.resultant(link)
    w.guide_columns(link, blk, normal, nx, ny)
    w.solved.update({link.number, blk.number})
    w.outer(link, pivot, lin((1, nx), (-1, kl[0])), lin((1, ny), (-1, kl[1])), where)
    w.outer(blk, p, lin((-1, nx), (-1, kb[0])), lin((-1, ny), (-1, kb[1])), where)


def topology(rec: dict, length_input: str | None) -> Topology:
    """The link from the pivot to the point, and the block at p sliding on it along the
    slide's line, turning with that line (N→P): the link's direction beside its points'
    (at offset 0, where N is the pivot, the one that places a point on the link)."""
    n, p, pivot = rec["point"], rec["p"], rec["pivot"]
    return Topology(links=((pivot, n),), frame=(n, p),
                    block=Block(p, rec["direction"], guide=(pivot, n), spin=(n, p),
                                beside=frozenset({pivot, n})))


STEP = StepType(schema_keys("slide"), place, rates, fixed({"offset": 1}), forces, topology)
