"""The vector step: the textbook's rectangular-to-polar columns of the vector between two known
points, and their rates.
"""
from __future__ import annotations

from ..columns import polar, polar_columns
from ..excel import key, minus
from ..fields import IDENT
from ..model import DescriptionError
from .slide import turning_guide
from .step_type import Block, StepType, Topology, schema_keys


def place(c, field: str, s: dict) -> None:
    """The polar columns of A→B; its angle is the link A→B's where no step gave one."""
    k = s["key"]
    if not isinstance(k, str) or not IDENT.match(k):
        raise DescriptionError(f"{field}.key", f"must be an identifier (got {k!r})")
    a = c.known_point(f"{field}.from", s["from"])
    b = c.known_point(f"{field}.to", s["to"])
    if a == b:
        raise DescriptionError(f"{field}.to", "must differ from from")
    cols = c.columns(field, s, polar_columns(k, a, b, degrees=True))
    (ax, ay), (bx, by) = c.points[a], c.points[b]
    polar(c.model, minus(bx, ax).text, minus(by, ay).text,
          cols["xs"], cols["ys"], cols["s"], cols["phi"])
    if (a, b) not in c.rigid and (b, a) not in c.rigid:
        c.rigid[(a, b)] = (None, key(cols["phi"].key))
    c.records.append({"type": "vector", "field": field, "from": a, "to": b, "xs": cols["xs"],
                      "ys": cols["ys"], "length": cols["s"], "angle": cols["phi"]})


def rates(w, rec: dict) -> None:
    """|AB| and the angle of A→B: their rates from the points' motion."""
    w.length_and_angle(rec["from"], rec["to"], rec["length"], rec["angle"])


def forces(w, rec: dict) -> None:
    """A slotted link (see topology) turning about A, the block at B sliding in it along A→B:
    solved as a slide's link and block, through the force writer `w`."""
    a, b = rec["from"], rec["to"]
    link = next((body for body in w.bodies if (a, b) in body.frames), None)
    if link is not None:
        turning_guide(w, link, w.body(b, block=True), a, rec["angle"].key, rec["field"])


def topology(rec: dict, length_input: str | None) -> Topology:
    """A direction measured from A to B; where it is a slotted link (step_type.slotted: a step
    is carried by it or slides on it), the link turning about A along A→B, and the block at B
    sliding in it, turning with it."""
    a, b, phi = rec["from"], rec["to"], rec["angle"].key
    block = Block(b, (f"COS({{{phi}}})", f"SIN({{{phi}}})"), guide=(a, b), spin=(a, b),
                  beside=frozenset({a}))
    return Topology(links=((a,),), block=block, frame=(a, b), turns=(a, b))


STEP = StepType(schema_keys("vector"), place, rates, forces=forces, topology=topology)
