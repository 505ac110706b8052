"""The point step: a point carried by a link's frame, by local coordinates, by two distances
(a frame that may stretch) or by a distance and an angle.
"""
from __future__ import annotations

from ..columns import Column
from ..excel import (PRODUCT, SUM, angle_of_triangle_or_na, key, local_point, plus,
                     radians)
from ..model import LENGTH, RAD, DescriptionError, Quantity
from .step_type import StepType, Topology, fixed, schema_keys


def place(c, field: str, s: dict) -> None:
    """A point fixed in the frame A→B: by local coordinates [u, v], by its distances to A
    and B, or by a distance from A at an angle from A→B."""
    n = s["point"]
    a, b = c.frame(f"{field}.frame", s["frame"], n)
    forms = [k for k in ("local", "distances", "distance") if k in s]
    if len(forms) != 1:
        raise DescriptionError(field, "needs exactly one of local, distances or distance "
                                      f"(got {', '.join(forms) or 'none'})")
    form = forms[0]
    allowed = {"local": set(), "distances": {"side"}, "distance": {"angle"}}[form]
    for k in ("side", "angle"):
        if k in s and k not in allowed:
            raise DescriptionError(f"{field}.{k}", f"does not go with {form}")
    defaults = [Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
                Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)]
    if form == "distances":
        defaults.insert(0, Column("gamma", f"gamma_{n}", f"γ_{n}", f"angle ∠{b}{a}{n}", RAD))
    if form == "distance":
        defaults.insert(0, Column("theta", f"theta_{n}", f"θ({a}{n})", f"angle of {a}→{n}",
                                  RAD, True, shown=False))
    cols = c.columns(field, s, defaults)
    ax, ay = c.points[a]
    base = c.angle_of(a, b, f"{field}.frame")
    if form == "local":
        pair = s["local"]
        if not isinstance(pair, list) or len(pair) != 2:
            raise DescriptionError(f"{field}.local", f"must be [u, v] (got {pair!r})")
        u, v = (c.expr(f"{field}.local[{i}]", pair[i]) for i in (0, 1))
        x, y = local_point((ax, ay), u, v, base.text)
    else:
        if form == "distances":
            pair = s["distances"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise DescriptionError(f"{field}.distances", f"must be [|{a}{n}|, |{b}{n}|] "
                                                             f"(got {pair!r})")
            da = c.expr(f"{field}.distances[0]", pair[0])
            db = c.expr(f"{field}.distances[1]", pair[1])
            side = c.branch(f"{field}.side", s.get("side", 1))
            ab = c.length_of(a, b)
            k_ab = c.operand(f"frame_length_{n}", ab)
            k_a, k_b = (c.length_operand(f"{field}.distances[{i}]", f"{h}_{n}", e, pair[i])
                        for i, (h, e) in enumerate((("distance_a", da), ("distance_b", db))))
            g = cols["gamma"]
            gamma = angle_of_triangle_or_na(k_ab, k_a, k_b, once=k_ab)
            c.model.add(Quantity(g.key, g.symbol, RAD, gamma, c.role(gamma, g),
                                 g.label))
            turn = f"+{{{g.key}}}" if side == "_plus_one" else \
                f"-{{{g.key}}}" if side == "_minus_one" else f"+{{{side}}}*{{{g.key}}}"
            angle = f"{base.at_least(SUM)}{turn}"
            d = da.at_least(PRODUCT)
        else:
            da = c.expr(f"{field}.distance", s["distance"])
            c.lengths.append((f"{field}.distance", s["distance"]))
            offset = c.expr(f"{field}.angle", s.get("angle", 0))
            angle = base.text if offset.zero else plus(base, radians(offset).text)
            t = cols["theta"]
            c.model.add(Quantity(t.key, t.symbol, RAD, angle, c.role(angle, t),
                                 t.label, in_degrees=t.deg, wrap_360=t.wrap))
            angle = f"{{{t.key}}}"
            c.rigid[(a, n)] = (da, key(t.key))
            d = da.at_least(PRODUCT)
        x = plus(ax, f"{d}*COS({angle})")
        y = plus(ay, f"{d}*SIN({angle})")
    c.add_point(field, n, cols["x"], cols["y"], x, y)
    c.records.append({"type": "point", "field": field, "point": n, "frame": (a, b),
                      "form": form, "theta": cols.get("theta")})


def rates(w, rec: dict) -> None:
    """Carried by its frame as a rigid body; by two circles where the frame stretches."""
    n, (a, b) = rec["point"], rec["frame"]
    if rec["form"] == "distances" and not w.fixed_length(a, b):
        w.two_circles(n, a, b)      # a frame that stretches: two circles about its points
        return
    omega, alpha = w.link_rates(a, b)
    w.rigid(n, a, omega, alpha)
    if rec["theta"] is not None:
        w.links[(a, n)] = w.rates(rec["theta"], omega, alpha)


def topology(rec: dict, length_input: str | None) -> Topology:
    """The point is carried by the link of its frame."""
    a, b = rec["frame"]
    return Topology(carried=(rec["point"], a, b))


STEP = StepType(schema_keys("point"), place, rates,
                fixed({"local": 1, "distances": 1, "distance": 1, "angle": 0}),
                topology=topology)
