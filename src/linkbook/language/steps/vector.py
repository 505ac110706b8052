"""The vector step: the textbook's rectangular-to-polar columns of the vector between two known
points, and their rates.
"""
from __future__ import annotations

from ..columns import polar, polar_columns
from ..excel import key, minus
from ..fields import IDENT
from ..model import DescriptionError
from .step_type import StepType, Topology, schema_keys


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
    c.records.append({"type": "vector", "from": a, "to": b, "xs": cols["xs"],
                      "ys": cols["ys"], "length": cols["s"], "angle": cols["phi"]})


def rates(w, rec: dict) -> None:
    """|AB| and the angle of A→B: their rates from the points' motion."""
    w.length_and_angle(rec["from"], rec["to"], rec["length"], rec["angle"])


def topology(rec: dict, length_input: str | None) -> Topology:
    """No link: a direction measured from one point to another (a slotted link written this
    way is no link of the steps, which a refusal says)."""
    return Topology(turns=(rec["from"], rec["to"]))


STEP = StepType(schema_keys("vector"), place, rates, topology=topology)
