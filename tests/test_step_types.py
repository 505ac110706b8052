"""A step type is one module on each side: adding one touches the writer's registry
(linkbook.language.steps.STEPS), the reference's (linkbook.check.reference.STEP_TYPES) and the
schema, and nothing else. This test adds a toy step type at run time — `midpoint`: the point
halfway between two known points, carried by the link holding them (its force topology) —
builds a book with it and verifies it.
"""
from __future__ import annotations

import copy
from pathlib import Path

import pytest

import linkbook
from linkbook.check.reference import STEP_TYPES, StepType as ReferenceStep
from linkbook.check.reference.step_type import Topology as ReferenceTopology
from linkbook.language import schema as schema_module
from linkbook.language.columns import Column
from linkbook.language.model import LENGTH
from linkbook.language.steps import STEPS, StepType as WriterStep
from linkbook.language.steps.step_type import Topology as WriterTopology

FOURBAR = Path(__file__).resolve().parents[1] / "templates" / "fourbar.toml"
TOY = """
[[mechanism.steps]]
type = "midpoint"
point = "M"
between = ["A", "B"]
"""


# ---- the writer's side: position formulas, then rate formulas
def _write_place(c, field: str, s: dict) -> None:
    n = s["point"]
    a = c.known_point(f"{field}.between[0]", s["between"][0], n)
    b = c.known_point(f"{field}.between[1]", s["between"][1], n)
    cols = c.columns(field, s, [Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
                                Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
    (ax, ay), (bx, by) = c.points[a], c.points[b]
    c.add_point(field, n, cols["x"], cols["y"], f"({ax.text}+{bx.text})/2",
                f"({ay.text}+{by.text})/2")
    c.records.append({"type": "midpoint", "point": n, "between": [a, b]})


def _write_rates(w, rec: dict) -> None:
    a, b = rec["between"]
    halves = [f"({p}+{q})/2" for p, q in zip(w.vel(a) + w.acc(a), w.vel(b) + w.acc(b))]
    w.point(rec["point"], *halves)


def _write_topology(rec: dict, length_input) -> WriterTopology:
    return WriterTopology(carried=(rec["point"], *rec["between"]))


# ---- the reference's side: its own solution of the same step
def _reference(weight: float, carrier: tuple[str, str] | None = None):
    """The toy's reference: M at `weight` of the way from the first point to the second,
    carried by the link holding `carrier` (by default those two points)."""
    def place(solver, step):
        a, b = solver.pair(step, "between")
        (ax, ay), (bx, by) = solver.points[a], solver.points[b]
        moving = solver.moves(a, b)
        keys = solver.point_columns(step, {"x": ax + weight * (bx - ax),
                                           "y": ay + weight * (by - ay)}, moving)
        solver.new_point(step, keys, moving, loop=False)

    def rates(motion, step):
        (ax, ay), (bx, by) = (motion.points[n] for n in step["between"])
        motion.place(step["point"], ax + weight * (bx - ax), ay + weight * (by - ay))

    def topology(step, length_input):
        a, b = carrier or step["between"]
        return ReferenceTopology(carried=(step["point"], a, b, False))
    return ReferenceStep(place=place, rates=rates, topology=topology)


def _schema_rule() -> dict:
    return {"if": {"properties": {"type": {"const": "midpoint"}}, "required": ["type"]},
            "then": {"type": "object", "additionalProperties": False,
                     "required": ["type", "point", "between"],
                     "properties": {"type": {"const": "midpoint"}, "point": {"type": "string"},
                                    "between": {"type": "array", "items": {"type": "string"},
                                                "minItems": 2, "maxItems": 2},
                                    "columns": {"type": "object"}}}}


@pytest.fixture
def toy_step():
    """Register the toy on both sides and in the schema; put everything back afterwards."""
    schema = schema_module.schema()
    saved = copy.deepcopy(schema)
    steps = schema["properties"]["mechanism"]["properties"]["steps"]["items"]
    steps["properties"]["type"]["enum"].append("midpoint")
    steps["allOf"].append(_schema_rule())
    schema_module._validator.cache_clear()
    STEPS["midpoint"] = WriterStep(({"point", "between"}, set()), _write_place, _write_rates,
                                   topology=_write_topology)

    def reference(weight: float, carrier: tuple[str, str] | None = None) -> None:
        STEP_TYPES["midpoint"] = _reference(weight, carrier)
    reference(0.5)
    yield reference
    STEPS.pop("midpoint", None)
    STEP_TYPES.pop("midpoint", None)
    schema.clear()
    schema.update(saved)
    schema_module._validator.cache_clear()


def _toy_template(tmp_path: Path, extra: str = "") -> Path:
    text = FOURBAR.read_text(encoding="utf-8")
    text = text.replace('"xC", "yC"]', '"xC", "yC", "xM", "yM"]', 1)
    path = tmp_path / "fourbar-midpoint.toml"
    path.write_text(text + TOY + extra, encoding="utf-8")
    return path


# a force at the toy's point: on the link its step type's topology says carries it
LOAD_AT_M = """
[[mechanism.loads]]
at = "M"
force = [0, -50]
"""


def test_a_toy_step_type_builds_and_verifies(toy_step, tmp_path):
    book = linkbook.build(_toy_template(tmp_path), tmp_path / "toy.xlsx")
    report = linkbook.verify(book)
    assert report.status == 0, report.error or report
    judged = {check.name for check in report.checks}
    assert {"xM", "yM", "vx_M", "ay_M"} <= judged, sorted(judged)


def test_the_toy_is_judged_against_the_reference(toy_step, tmp_path):
    """A reference that places the toy's point 1e-6 of the way off disagrees with the book on
    exactly the toy's cells: the book's toy columns are checked, not passed."""
    book = linkbook.build(_toy_template(tmp_path), tmp_path / "toy.xlsx")
    toy_step(0.5 + 1e-6)
    report = linkbook.verify(book)
    assert report.status == 1
    differing = {check.name for check in report.checks if not check.ok}
    assert differing and differing <= {"xM", "yM", "vx_M", "vy_M", "ax_M", "ay_M"}, differing


def test_without_the_toy_the_template_is_refused(tmp_path):
    with pytest.raises(linkbook.InputError, match="midpoint"):
        linkbook.build(_toy_template(tmp_path), tmp_path / "toy.xlsx")


def test_the_toys_force_topology_is_read_from_its_modules(toy_step, tmp_path):
    """A load at the toy's point: both sides put it on the coupler A–B, as each side's toy
    module says, and the book's forces verify."""
    book = linkbook.build(_toy_template(tmp_path, LOAD_AT_M), tmp_path / "toy.xlsx")
    report = linkbook.verify(book)
    assert report.status == 0, report.error or report
    judged = {check.name for check in report.checks}
    assert {"T12", "F23x", "F34y"} <= judged, sorted(judged)


def test_a_toy_carried_by_another_link_in_the_reference_fails_the_forces(toy_step, tmp_path):
    """A reference whose toy module carries the point on the crank A0–A (the book's on the
    coupler) disagrees on the forces, and only there: the reference reads the toy's own
    topology, not a rule of its own."""
    book = linkbook.build(_toy_template(tmp_path, LOAD_AT_M), tmp_path / "toy.xlsx")
    toy_step(0.5, ("A0", "A"))
    report = linkbook.verify(book)
    assert report.status == 1
    differing = {check.name for check in report.checks if not check.ok}
    assert "F12x" in differing or "F12y" in differing, differing
    assert not differing & {"xM", "yM", "vx_M", "ay_M"}, differing
