"""The distance step: the distance between two known points, and its rates.
"""
from __future__ import annotations

from ..columns import Column
from ..excel import ATOM, minus
from ..model import ALIAS, COLUMN, LENGTH, DescriptionError, Quantity
from .step_type import StepType, schema_keys


def place(c, field: str, s: dict) -> None:
    """|AB| from the points' coordinates."""
    k = s["key"]
    pair = s["between"]
    if not isinstance(pair, list) or len(pair) != 2:
        raise DescriptionError(f"{field}.between", f"must be [A, B] (got {pair!r})")
    a = c.known_point(f"{field}.between[0]", pair[0])
    b = c.known_point(f"{field}.between[1]", pair[1])
    cols = c.columns(field, {k_: v for k_, v in s.items() if k_ == "columns"}, [
        Column("d", k, s.get("symbol", k), s.get("label", f"|{a}{b}|"), LENGTH)])
    (ax, ay), (bx, by) = c.points[a], c.points[b]
    dx, dy = minus(bx, ax), minus(by, ay)
    d = cols["d"]
    c.model.add(Quantity(d.key, d.symbol, LENGTH,
                         f"SQRT({dx.at_least(ATOM)}^2+{dy.at_least(ATOM)}^2)",
                         COLUMN if d.shown else ALIAS, d.label))
    c.records.append({"type": "distance", "between": (a, b), "length": d})


def rates(w, rec: dict) -> None:
    """|AB|'s rates from the points' motion."""
    w.length_and_angle(*rec["between"], rec["length"], None)


STEP = StepType(schema_keys("distance"), place, rates)
