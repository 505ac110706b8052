"""The slot step: a slot carried by a link meets a fixed line; the block at their crossing.
"""
from __future__ import annotations

from ..columns import Column
from ..excel import (POWER, PRODUCT, combine, cross, guard, key, key_text, lin, minus, mul, negate,
                     sq, times, turned)
from ..mechanisms import on_loop
from ..model import ALIAS, COLUMN, LENGTH, RATIO, DescriptionError, Quantity
from .step_type import Block, StepType, Topology, fixed, schema_keys


def place(c, field: str, s: dict) -> None:
    """E + s_slot·û = T + s·d̂ (the slot through E, the line through T), by Cramer's rule."""
    n = s["point"]
    e = c.known_point(f"{field}.slot_through", s["slot_through"], n)
    a, b = c.frame(f"{field}.slot_frame", s["slot_frame"], n)
    through = c.known_point(f"{field}.through", s["through"], n)
    if through not in c.ground:
        raise DescriptionError(f"{field}.through", f"{through!r} must be a fixed point")
    cols = c.columns(field, s, [
        Column("s_slot", f"s_slot_{n}", f"s_slot_{n}", f"{n} along the slot from {e}",
               LENGTH),
        Column("s", f"s_{n}", f"s_{n}", f"{n} along its line from {through}", LENGTH),
        Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
        Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
    uc, us = turned(c.angle_of(a, b, f"{field}.slot_frame"), c.expr(f"{field}.slot_angle",
                                             s.get("slot_angle", 0)))
    dc, ds = turned(None, c.expr(f"{field}.direction", s.get("direction", 0)))
    (ex, ey), (tx, ty) = c.points[e], c.points[through]
    wx, wy = minus(tx, ex), minus(ty, ey)
    # E + s_slot·û = T + s·d̂, solved by Cramer's rule; parallel lines (D = 0) are #N/A.
    det = combine([times(key_text(uc), ds), negate(times(key_text(us), dc))])
    for sym, terms in ((cols["s_slot"], [times(wx, ds), negate(times(wy, dc))]),
                       (cols["s"], [times(wx, us), negate(times(wy, uc))])):
        num = combine(terms)
        c.model.add(Quantity(sym.key, sym.symbol, LENGTH,
                             f"IFERROR({num.at_least(PRODUCT)}/{det.at_least(POWER)},NA())",
                             COLUMN if sym.shown else ALIAS, sym.label))
    pos = cols["s"].key
    x = on_loop(tx.text, pos) if dc == "0" else \
        combine([times(tx, "1"), times(key(pos), dc)]).text
    y = on_loop(ty.text, pos) if ds == "0" else \
        combine([times(ty, "1"), times(key(pos), ds)]).text
    c.add_point(field, n, cols["x"], cols["y"], x, y)
    c.witness(field, cols, ("s", "s_slot", "x", "y"))
    c.slides_on(n, "guide", through, (dc, ds), cols["s"])
    c.slides_on(n, "slot", e, (uc, us), cols["s_slot"])
    c.block(n, (dc, ds))
    c.records.append({"type": "slot", "field": field, "point": n, "slot_through": e,
                      "frame": (a, b), "through": through, "slot_dir": (uc, us),
                      "direction": (dc, ds),
                      "s_slot": cols["s_slot"], "s": cols["s"]})


def rates(w, rec: dict) -> None:
    """E + s_slot û = T + s d̂ (the slot, direction û, turns with its link at ω):
    ṡ d̂ − ṡ_slot û = v_E + s_slot ω (i û), over the determinant û × d̂ (zero when the slot
    is parallel to the line)."""
    n, e = rec["point"], rec["slot_through"]
    omega, alpha = w.link_rates(*rec["frame"])
    uc, us = rec["slot_dir"]
    dc, ds = rec["direction"]
    ss = f"{{{rec['s_slot'].key}}}"
    (vex, vey), (aex, aey) = w.vel(e), w.acc(e)
    det = w.determinant(n, RATIO, cross((uc, us), (dc, ds)))
    dx = lin((1, vex), (-1, mul(ss, omega, us)))
    dy = lin((1, vey), (1, mul(ss, omega, uc)))
    sd = w.rate(rec["s"], 1, guard(det, cross((uc, us), (dx, dy))), angle=False)
    ssd = w.rate(rec["s_slot"], 1, guard(det, cross((dc, ds), (dx, dy))), angle=False)
    coriolis = mul("2", ssd, omega)
    ex = lin((1, aex), (-1, mul(coriolis, us)), (-1, mul(ss, alpha, us)),
             (-1, mul(ss, sq(omega), uc)))
    ey = lin((1, aey), (1, mul(coriolis, uc)), (1, mul(ss, alpha, uc)),
             (-1, mul(ss, sq(omega), us)))
    sdd = w.rate(rec["s"], 2, guard(det, cross((uc, us), (ex, ey))), angle=False)
    w.rate(rec["s_slot"], 2, guard(det, cross((dc, ds), (ex, ey))), angle=False)
    w.point(n, mul(sd, dc), mul(sd, ds), mul(sdd, dc), mul(sdd, ds), witness=sd)


def forces(w, rec: dict) -> None:
    """The block b at N on its fixed line e, its pin N in the slot (direction u) of the link S,
    through the force writer `w`. S pushes the pin across the slot, λ·m (m = u turned +90°):
    along the line, λ·(m·e) = −ΣF_b·e, zero when the slot is parallel to the line; the guide
    takes the rest across the line (guided). S feels −λ·m at N."""
    n = rec["point"]
    blk, link = w.body(n, block=True), w.body(*rec["frame"])
    ex, ey = blk.line
    ux, uy = rec["slot_dir"]
    kb = w.resultant(blk)
    det = w.w.alias(f"_Dforce_{n}", lin((1, mul(ux, ey)), (-1, mul(uy, ex))))
    lam = w.guide_normal(link, blk, guard(det, w.neg(lin((1, mul(kb[0], ex)),
                                                         (1, mul(kb[1], ey))))),
                         "across the slot")
    mx, my = w.neg(mul(uy, lam)), mul(ux, lam)
    w.guide_columns(link, blk, lam, mx, my, couple=False)
    w.guided(blk, lin((1, mx), (1, kb[0])), lin((1, my), (1, kb[1])))
    w.solved.add(blk.number)


def topology(rec: dict, length_input: str | None) -> Topology:
    """The block at the point on its fixed line, its pin pushed across the slot of the link
    of `frame` (which also holds `slot_through`): it makes no link of its own."""
    return Topology(block=Block(rec["point"], rec["direction"], slotted=rec["frame"],
                                beside=frozenset({rec["slot_through"], *rec["frame"]})))


STEP = StepType(schema_keys("slot"), place, rates, fixed({"direction": 0, "slot_angle": 0}),
                forces, topology)
