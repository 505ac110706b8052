"""The slider step (RRP): a block on a line at a given distance from a known point — a fixed
line, or one carried by a moving link.
"""
from __future__ import annotations

from ..columns import Column, Sym, quantity
from ..excel import (PRODUCT, SUM, ZERO, Expr, asin_or_na, cross, dot, guard, key, lin, minus, mul,
                     plus, radians, sq)
from ..mechanisms import on_loop
from ..model import ALIAS, COLUMN, LENGTH, RAD, DescriptionError, Model, Quantity
from .step_type import Block, StepType, Topology, fixed, schema_keys


def slider(model: Model, *, pin_x: str, pin_y: str, line_y: str, length: str, branch: str,
           angle: Sym, position: Sym, direction: str = "") -> None:
    """The slider-crank step: slider S on a line, |S pin| = {length}. pin_x, pin_y: the pin in
    the line's frame (x along the line); line_y: the line's y in that frame (Excel text, "0" for a
    line through the frame's origin); direction: the line's angle (radians, Excel text; "" for a
    horizontal line, whose frame is the mechanism's own).

    angle = angle(S→pin): π − asin(…) on branch 1 (S ahead of the pin), asin(…) on branch −1,
    written as π/2 + branch·(π/2 − asin(…)) so that the argument appears once; the position is
    S's x in the line's frame.
    """
    rise = pin_y if line_y == "0" else f"({pin_y}-{line_y})"
    turn = f"{direction}+" if direction else ""
    relative = f"({{{angle.key}}}-{direction})" if direction else f"{{{angle.key}}}"
    model.add(
        quantity(angle, RAD, f"{turn}PI()/2+{{{branch}}}*(PI()/2-"
                             + asin_or_na(f"{rise}/{{{length}}}") + ")"),
        quantity(position, LENGTH, f"{pin_x}-{{{length}}}*COS({relative})"),
    )


def place(c, field: str, s: dict) -> None:
    """RRP: R at `length` from P, on a line through `through` at `direction` — a fixed line,
    or, with `along = [U, V]`, a line carried by the link U→V (direction then measured from
    U→V)."""
    n = s["point"]
    p = c.known_point(f"{field}.p", s["p"], n)
    through = c.known_point(f"{field}.through", s["through"], n)
    along = c.frame(f"{field}.along", s["along"], n) if "along" in s else None
    if along is None and through not in c.ground:
        raise DescriptionError(f"{field}.through", f"{through!r} must be a fixed point (or "
                                                   "give the moving line's link as along)")
    length = c.expr(f"{field}.length", s["length"])
    direction = c.expr(f"{field}.direction", s.get("direction", 0))
    branch = c.branch(f"{field}.branch", s["branch"])
    moving_line = [Column("line", f"line_{n}", f"θ(line)_{n}",
                          f"slider line, angle along {'→'.join(along)}", RAD, True)] \
        if along else []
    cols = c.columns(field, s, [
        *moving_line,
        Column("theta", f"theta_{n}", f"θ({n}{p})", f"link, angle of {n}→{p}", RAD, True),
        Column("s", f"s_{n}", f"s_{n}", f"slider position along its line from {through}",
               LENGTH),
        Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
        Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
    (px, py), (tx, ty) = c.points[p], c.points[through]
    dx, dy = minus(px, tx), minus(py, ty)
    length_key = c.length_operand(f"{field}.length", f"length_{n}", length, s["length"])
    pos = cols["s"].key
    if along:
        angle = c.angle_of(*along, f"{field}.along")
        if not direction.zero:
            angle = Expr(plus(angle, radians(direction).text), SUM)
        line = cols["line"]
        c.model.add(Quantity(line.key, line.symbol, RAD, angle.text,
                             COLUMN if line.shown else ALIAS, line.label,
                             in_degrees=line.deg and line.shown, wrap_360=line.wrap))
        d = f"{{{line.key}}}"
    elif direction.zero:
        slider(c.model, pin_x=dx.text, pin_y=dy.at_least(PRODUCT), line_y="0",
               length=length_key,
               branch=branch, angle=cols["theta"], position=cols["s"])
        x, y = plus(tx, f"{{{pos}}}"), on_loop(ty.text, pos)
    else:
        d = radians(direction).text
    if along or not direction.zero:
        u = f"{dx.at_least(PRODUCT)}*COS({d})+{dy.at_least(PRODUCT)}*SIN({d})"
        v = f"{dy.at_least(PRODUCT)}*COS({d})-{dx.at_least(PRODUCT)}*SIN({d})"
        slider(c.model, pin_x=f"({u})", pin_y=f"({v})", line_y="0", length=length_key,
               branch=branch, angle=cols["theta"], position=cols["s"], direction=d)
        x = plus(tx, f"{{{pos}}}*COS({d})")
        y = plus(ty, f"{{{pos}}}*SIN({d})")
    c.add_point(field, n, cols["x"], cols["y"], x, y)
    c.rigid[(n, p)] = (length, key(cols["theta"].key))
    c.witness(field, cols, ("theta", "s", "x", "y"))
    line_dir = ((f"COS({d})", f"SIN({d})") if along or not direction.zero else ("1", "0"))
    c.slides_on(n, "guide", through, line_dir, cols["s"])
    c.block(n, line_dir)
    c.records.append({"type": "slider", "field": field, "point": n, "p": p, "through": through,
                      "along": along, "line": cols.get("line"), "direction": line_dir,
                      "theta": cols["theta"], "s": cols["s"]})


def rates(w, rec: dict) -> None:
    """R = T + s d on its line (angle λ), P = R + u: ṡ d + θ̇ (i u) = v_P − v_T − s λ̇ (i d),
    over the determinant d·u (zero where the rod is square to the line)."""
    n, p, t = rec["point"], rec["p"], rec["through"]
    dc, ds = rec["direction"]
    if rec["along"]:
        lw, la = w.link_rates(*rec["along"])
        lw, la = w.rates(rec["line"], lw, la)
    else:
        lw = la = ZERO
    s = f"{{{rec['s'].key}}}"
    ux, uy = w.rel(n, p)
    (vpx, vpy), (vtx, vty) = w.vel(p), w.vel(t)
    (apx, apy), (atx, aty) = w.acc(p), w.acc(t)
    det = w.determinant(n, LENGTH, dot((dc, ds), (ux, uy)))
    dx = lin((1, vpx), (-1, vtx), (1, mul(s, lw, ds)))
    dy = lin((1, vpy), (-1, vty), (-1, mul(s, lw, dc)))
    sd = w.rate(rec["s"], 1, guard(det, dot((dx, dy), (ux, uy))), angle=False)
    td = w.rate(rec["theta"], 1, guard(det, cross((dc, ds), (dx, dy))))
    coriolis = mul("2", sd, lw)
    ex = lin((1, apx), (-1, atx), (1, mul(coriolis, ds)), (1, mul(s, la, ds)),
             (1, mul(s, sq(lw), dc)), (1, mul(sq(td), ux)))
    ey = lin((1, apy), (-1, aty), (-1, mul(coriolis, dc)), (-1, mul(s, la, dc)),
             (1, mul(s, sq(lw), ds)), (1, mul(sq(td), uy)))
    sdd = w.rate(rec["s"], 2, guard(det, dot((ex, ey), (ux, uy))), angle=False)
    tdd = w.rate(rec["theta"], 2, guard(det, cross((dc, ds), (ex, ey))))
    w.point(n, lin((1, vtx), (1, mul(sd, dc)), (-1, mul(s, lw, ds))),
            lin((1, vty), (1, mul(sd, ds)), (1, mul(s, lw, dc))),
            lin((1, atx), (1, mul(sdd, dc)), (-1, mul(coriolis, ds)), (-1, mul(s, la, ds)),
                (-1, mul(s, sq(lw), dc))),
            lin((1, aty), (1, mul(sdd, ds)), (1, mul(coriolis, dc)), (1, mul(s, la, dc)),
                (-1, mul(s, sq(lw), ds))), witness=sd)
    w.links[(n, p)] = (td, tdd)


def forces(w, rec: dict) -> None:
    """The rod u (P–N) pinned at N to the block b on its line, of direction e, through the
    force writer `w`. With X the pin force of u on b: the block along its line,
    X·e = −ΣF_b·e; the rod about P, (N−P)×X = M_u(P) — over D = e·(N−P), zero when the rod is
    square to the line. The guide's force across the line and its couple follow from the
    block's balance (guided); the rod's pin at P takes X − ΣF_u."""
    n, p, where = rec["point"], rec["p"], rec["field"]
    u, blk = w.body(p, n), w.body(n, block=True)
    w.carrier(n, [u, blk], where)
    ex, ey = blk.line
    a = w.arm(n, p)
    kb = w.resultant(blk)
    c1 = w.neg(lin((1, mul(kb[0], ex)), (1, mul(kb[1], ey))))
    c2 = w.moment(u, p)
    det = w.w.alias(f"_Dforce_{n}", lin((1, mul(ex, a[0])), (1, mul(ey, a[1]))))
    x, y = w.inner(u, blk, n, guard(det, lin((1, mul(c1, a[0])), (-1, mul(ey, c2)))),
                   guard(det, lin((1, mul(ex, c2)), (1, mul(a[1], c1)))))
    w.guided(blk, lin((1, x), (1, kb[0])), lin((1, y), (1, kb[1])))
    w.solved.update({u.number, blk.number})
    ux, uy = w.resultant(u)
    w.outer(u, p, lin((1, x), (-1, ux)), lin((1, y), (-1, uy)), where)


def topology(rec: dict, length_input: str | None) -> Topology:
    """The rod from p to the point, and the block at the point on its line: fixed, or on the
    link of `along` (which also holds `through`), turning with it."""
    n, along = rec["point"], tuple(rec["along"] or ())
    block = Block(n, rec["direction"], guide=along, spin=along or None,
                  beside=frozenset({*along, rec["through"]}) if along else frozenset())
    return Topology(links=((rec["p"], n),), block=block)


STEP = StepType(schema_keys("slider"), place, rates, fixed({"length": 1, "direction": 0}),
                forces, topology)
