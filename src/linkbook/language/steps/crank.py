"""The crank step: a point turning with the input angle about a known pivot, at a given
length and phase; it moves with the crank as a rigid body.
"""
from __future__ import annotations

from ..columns import Column
from ..excel import PRODUCT, SUM, Expr, key, plus, radians
from ..mechanisms import ANGLE_KIND
from ..model import LENGTH, DescriptionError
from .step_type import StepType, Topology, fixed, schema_keys


def place(c, field: str, s: dict) -> None:
    """P = pivot + length·(cos, sin)(input angle + phase)."""
    name = s["point"]
    if c.input_kind != ANGLE_KIND:
        raise DescriptionError(f"{field}.type", "a crank turns with an angle input; this "
                                                "mechanism's input is a length (a linear "
                                                "actuator): use it as a dyad's p_length or "
                                                "q_length")
    pivot = c.known_point(f"{field}.pivot", s["pivot"], name)
    length = c.expr(f"{field}.length", s["length"])
    c.lengths.append((f"{field}.length", s["length"]))
    phase = c.expr(f"{field}.phase", s.get("phase", 0))
    angle = key(c.input_key) if phase.zero else \
        Expr(f"{{{c.input_key}}}+{radians(phase).text}", SUM)
    cols = c.columns(field, s, [
        Column("x", f"x{name}", f"x{name}", f"x of {name}", LENGTH),
        Column("y", f"y{name}", f"y{name}", f"y of {name}", LENGTH)])
    px, py = c.points[pivot]
    r = length.at_least(PRODUCT)
    c.add_point(field, name, cols["x"], cols["y"],
                plus(px, f"{r}*COS({angle.text})"), plus(py, f"{r}*SIN({angle.text})"))
    c.rigid[(pivot, name)] = (length, angle)
    c.crank_of[name] = pivot
    c.cranks.append({"point": name, "pivot": pivot, "length": length, "phase": phase})
    c.records.append({"type": "crank", "field": field, "point": name, "pivot": pivot})


def rates(w, rec: dict) -> None:
    """The crank turns about its pivot at the input's ω and α."""
    n, pivot = rec["point"], rec["pivot"]
    w.links[(pivot, n)] = (w.speed, w.accel)
    w.rigid(n, pivot, w.speed, w.accel)


def forces(w, rec: dict) -> None:
    """The crank is solved last: its pivot's reaction and the driving torque."""
    w.crank(rec["pivot"], rec["point"], rec.get("field", "crank"))


def topology(rec: dict, length_input: str | None) -> Topology:
    """The crank is a link from its pivot to its point, turned by the input."""
    return Topology(links=((rec["pivot"], rec["point"]),), crank=True)


STEP = StepType(schema_keys("crank"), place, rates, fixed({"length": 1, "phase": 0}), forces,
                topology)
