"""Function generation end to end (issue 38): a template's [synthesis] task, the Synthesis sheet
that designs the linkage in live formulas, the analysis sheets that read the designed cells, and
verify judging all of it.

Expected values come from the independent reference (check/reference/synthesis.py, itself
checked against pylinkage and the loop closure in test_synthesis_reference.py) and from the
kinematic reference, never from the writer."""
from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from conftest import checks_of, examples, formula_cells

from linkbook.base.errors import InputError
from linkbook.base.sheets import SYNTHESIS, SYNTHESIS_WORDS
from linkbook.book import builder
from linkbook.check.reference import synthesis as ref
from linkbook.check.reference.expressions import evaluate
from linkbook.check.verifier import verify
from linkbook.language.templates import from_data, with_overrides

ROOT = Path(__file__).resolve().parents[1]
TEMPLATE = ROOT / "templates" / "function-log10.toml"
EXAMPLES = examples(8)


def _data(**task) -> dict:
    data = tomllib.loads(TEMPLATE.read_text(encoding="utf-8"))
    data["synthesis"] = {**data["synthesis"], **task}
    return data


def _reference(task: dict, d: float = 100.0) -> dict:
    """The reference's design of a [synthesis] table's task."""
    def f(x):
        return np.asarray(evaluate(task["f"], {"x": np.asarray(x, dtype=float)}), dtype=float)
    x0, x1 = task["x"]
    spacing = task.get("spacing", "chebyshev")
    if isinstance(spacing, list):
        x, _ = ref.precision_points(f, x0, x1, len(spacing), given=spacing)
    else:
        x, _ = ref.precision_points(f, x0, x1, task.get("points", 3), spacing)
    theta2, theta4 = ref.precision_angles(f, x, x0, x1, *np.radians([*task["theta2"],
                                                                     *task["theta4"]]))
    return ref.function_generation(theta2, theta4, d, input_range=(
        math.radians(task["theta2"][0]), math.radians(task["theta2"][1])))


def _cells(t):
    built, values = builder.make(t)
    syn = built.record.synthesis
    return syn, lambda key: values.get((SYNTHESIS, syn.cells[key])), \
        lambda key: [values.get((SYNTHESIS, c)) for c in syn.points[key]]


def _is_na(value) -> bool:
    return not isinstance(value, (int, float)) and "N/A" in str(value)


def test_the_bundled_book_verifies_and_is_a_grashof_crank_rocker(tmp_path):
    t = from_data("function-log10", _data())
    path = tmp_path / "log10.xlsx"
    builder.build_file(t, path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    expected = _reference(_data()["synthesis"])
    assert expected["grashof"] == "Grashof: crank-rocker" and not expected["branch_defect"]
    syn, cell, _ = _cells(t)
    assert cell("grashof") == "Grashof: crank-rocker"
    assert cell("defect") == SYNTHESIS_WORDS["no defect"]
    for role, key in (("crank", "a"), ("coupler", "b"), ("rocker", "c")):
        assert abs(cell(f"designed_{role}") - expected[key]) <= 1e-9 * 100


TASKS = st.fixed_dictionaries({
    "f": st.sampled_from(["LOG10(x)", "x^2", "EXP(x)", "SQRT(x)", "1/x"]),
    "theta2": st.tuples(st.integers(-180, 180), st.integers(40, 160)
                        | st.integers(-160, -40)).map(list),
    "theta4": st.tuples(st.integers(-180, 180), st.integers(20, 120)
                        | st.integers(-120, -20)).map(list),
    "points": st.sampled_from([3, 3, 4, 6]),
    "spacing": st.sampled_from(["chebyshev", "equal"]),
})


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(TASKS)
def test_random_tasks_give_the_references_design_or_na(task):
    """Every kind of outcome: a design, a branch defect, a negative length, a near-singular
    system: the sheet's coefficients and lengths the reference's (within its bound for the
    task's conditioning), its words the reference's, and #N/A exactly where nothing exists."""
    task = {**task, "x": [1, 3]}
    expected = _reference(task)
    syn, cell, column = _cells(from_data("random", _data(**task)))
    kappa = expected["condition"]
    # two correct solutions of a system of condition κ: about κ·ε apart, κ²·ε by the normal
    # equations (n > 3); a margin of 1000 over those (docs/verification.md)
    bound = max(1e-9, 1000 * 2.2e-16 * kappa ** (1 if task["points"] == 3 else 2))
    a, b, c = expected["a"], expected["b"], expected["c"]
    growth = 1.0 if not math.isfinite(b) or b == 0 else max(1.0, (
        a * a + c * c + 100.0 ** 2 + 2 * abs(a * c * expected["K3"])) / (b * b))
    for key, scale in (("K1", 1.0), ("K2", 1.0), ("K3", 1.0), ("a", 100.0), ("c", 100.0),
                       ("b", 100.0)):
        want, got = expected[key], cell(key)
        if math.isnan(want):
            assert _is_na(got), (key, got)
        else:
            allowed = bound * max(abs(want), scale) * (growth if key == "b" else 1.0)
            assert abs(got - want) <= allowed, (key, got, want)
    if expected["singular"]:
        assert cell("system") == SYNTHESIS_WORDS["singular"]
        assert all(_is_na(cell(f"designed_{r}")) for r in ("crank", "coupler", "rocker"))
        return
    branches = column("branch")
    assert [float(v) for v in branches] == list(expected["branch"])
    assert cell("defect") == SYNTHESIS_WORDS["defect" if expected["branch_defect"]
                                             else "no defect"]
    usable = expected["a"] > 0 and expected["c"] > 0 and not expected["branch_defect"]
    for role, key in (("crank", "a"), ("coupler", "b"), ("rocker", "c")):
        got = cell(f"designed_{role}")
        assert (abs(got - expected[key]) <= bound * growth * max(expected[key], 100)) \
            if usable else _is_na(got)


BOOK_EXAMPLES = examples(100)
# The outcomes the random tasks through the book must reach at the default profile (the fast
# profile's handful need not): a design on each branch, a non-Grashof design, a branch defect.
OUTCOMES_REACHED = ("open", "crossed", "non-Grashof", "branch defect")
NEAR_DEFECT = {"f": "LOG10(x)", "x": [1, 10], "theta2": [30, 90], "theta4": [240, -79.668],
               "points": 3, "spacing": "chebyshev"}


def _outcome(expected: dict) -> str:
    """What the reference's design of a task is, in the words OUTCOMES_REACHED uses."""
    if expected["singular"]:
        return "near-singular"
    if expected["branch_defect"]:
        return "branch defect"
    if not (expected["a"] > 0 and expected["c"] > 0):
        return "negative crank or rocker"
    if not expected["grashof"].startswith("Grashof"):
        return "non-Grashof"
    return "open" if expected["branch"][0] == 1 else "crossed"


def test_random_tasks_through_the_book_verify():
    """Random tasks (f, both ranges, 3 to 6 points, either spacing) through the whole book:
    every formula cell the vector engine computes is judged by verify's checks against the
    references (the synthesis reference's design, the kinematic reference placing it), none
    differs, and every cell is judged. #N/A exactly where there is no design is part of that.
    NEAR_DEFECT: the rocker's span 0.01 % short of a branch defect, where the first precision
    point is 0.0008° from a dead centre and the position steps' θ4 there loses digits like
    1/sin μ (the allowance near a limit position: its structural error is not judged, not
    passed)."""
    reached: dict[str, int] = {}

    @settings(max_examples=BOOK_EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow])
    @given(TASKS, st.sampled_from([[1, 3], [0.5, 4], [2, 2.5]]))
    @example(NEAR_DEFECT, NEAR_DEFECT["x"])
    def check(task, x):
        task = {**task, "x": x}
        expected = _reference(task)
        # Left out, as test_properties leaves out a crank pin through a pivot: a dead centre
        # exactly at a precision point (θ2_j = θ4_j = ±180°: A, B and B0 on the ground line)
        # puts a limit position exactly on a sweep row, where whether the loop closes is
        # round-off's, and the Sweep's judgement does not yet take #N/A there.
        assume(expected["singular"] or 0 not in list(expected["branch"]))
        try:
            t = from_data("random", _data(**task))
        except InputError as refused:       # lengths over 1000 times the ground: refused
            assume("too small beside" not in str(refused))
            raise
        t = dataclasses.replace(t, sweep=dataclasses.replace(t.sweep, step=15))
        built, values = builder.make(t)
        checks = checks_of(built, values)
        bad = [(c.name, m) for c in checks for m in c.mismatches[:2]]
        assert not bad, (task, bad[:5])
        assert sum(c.cells for c in checks) == len(formula_cells(built.workbook))
        if task == NEAR_DEFECT:         # given up there only: the error 0.0008° from μ = 0
            assert {cell for c in checks for cell in c.not_judged} == \
                {(SYNTHESIS, built.record.synthesis.points["error"][0])}
        outcome = _outcome(expected)
        reached[outcome] = reached.get(outcome, 0) + 1

    check()
    if BOOK_EXAMPLES >= 100:
        assert set(OUTCOMES_REACHED) <= set(reached), reached


def test_editing_a_task_input_in_the_book_redesigns_and_verifies(tmp_path):
    """As a user would: the book opened with openpyxl, the crank's span typed over, saved;
    verify reads the new task, designs it with the reference and agrees with every sheet."""
    import openpyxl
    path = tmp_path / "edited.xlsx"
    t = from_data("function-log10", _data())
    built = builder.build_file(t, path)
    cell = built.record.synthesis.inputs["theta2_span"]
    wb = openpyxl.load_workbook(path)
    wb[SYNTHESIS][cell] = 100
    wb.save(path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    before = _reference(_data()["synthesis"])["a"]
    after = _reference(_data(theta2=[30, 100])["synthesis"])["a"]
    assert report.inputs["a2"] == pytest.approx(after, rel=1e-9) and abs(after - before) > 1


@pytest.mark.libreoffice
def test_libreoffice_recalculates_the_book_to_the_references_numbers(tmp_path):
    path = tmp_path / "log10.xlsx"
    builder.build_file(from_data("function-log10", _data()), path)
    report = verify(path, engine="libreoffice")
    assert report.status == 0, report.error or [(c.block, c.name, c.mismatches[:2])
                                                for c in report.checks if not c.ok]


@pytest.mark.gnumeric
def test_gnumeric_recalculates_the_book_to_the_references_numbers(tmp_path):
    path = tmp_path / "log10.xlsx"
    builder.build_file(from_data("function-log10", _data()), path)
    report = verify(path, engine="gnumeric")
    assert report.status == 0, report.error or [(c.block, c.name, c.mismatches[:2])
                                                for c in report.checks if not c.ok]


BAD = [
    ("x", {"x": [10, 1]}, "synthesis.x"),
    ("span", {"theta2": [0, 0]}, "synthesis.theta2"),
    ("f", {"f": "LOG10(y)"}, "synthesis.f"),
    ("flat f", {"f": "1 + 0*x"}, "synthesis.f"),
    ("points", {"spacing": [1, 2, 3, 4]}, "synthesis.points"),
    ("unknown", {"designs": {"crank": "a9", "coupler": "a3", "rocker": "a4",
                             "branch": "branch"}}, "synthesis.designs.crank"),
    ("ground designed", {"ground": "a2"}, "synthesis.designs"),
    ("a key", {"spaceing": "equal"}, "synthesis"),
]


@pytest.mark.parametrize("what, change, field", BAD, ids=[b[0] for b in BAD])
def test_a_bad_task_is_one_line_naming_the_field(what, change, field):
    with pytest.raises(InputError) as caught:
        from_data("bad", _data(**change), origin="bad.toml")
    said = str(caught.value)
    assert "\n" not in said and f"bad.toml: {field}" in said, said


def test_a_designed_parameter_has_no_value_and_cannot_be_set():
    data = _data()
    data["parameters"]["a2"]["value"] = 30.0
    with pytest.raises(InputError, match="parameters.a2.value.*designed by"):
        from_data("bad", data, origin="bad.toml")
    t = from_data("function-log10", _data())
    with pytest.raises(InputError, match="--set a2: a2 is designed by"):
        with_overrides(t, ["a2=30"])


OUTCOMES = [
    ("crossed", {"theta2": [60, 120], "theta4": [270, -45]}),
    ("branch defect", {"theta2": [0, 300], "theta4": [30, 200]}),
    ("negative rocker", {"f": "x^2", "x": [1, 3], "theta2": [6, -40], "theta4": [7, 20],
                         "points": 6}),
    ("least squares, ill-conditioned", {"f": "x^2", "x": [1, 3], "theta2": [-152, -40],
                                        "theta4": [-152, -20], "points": 6}),
    ("given x", {"spacing": [1.5, 3, 6, 9.5], "points": 4}),
    ("near-singular", {"theta2": [0, 90], "theta4": [0, 1e-6]}),
]


@pytest.mark.parametrize("what, task", OUTCOMES, ids=[o[0] for o in OUTCOMES])
def test_every_outcome_verifies(tmp_path, what, task):
    """verify on books whose tasks end each way: every cell the reference's, or #N/A where
    there is no design (the analysis sheets too)."""
    data = _data(**task)
    path = tmp_path / "task.xlsx"
    builder.build_file(from_data("task", data), path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    expected = _reference(data["synthesis"])
    usable = not expected["singular"] and expected["a"] > 0 and expected["c"] > 0 \
        and not expected["branch_defect"]
    assert math.isnan(report.inputs["a2"]) != usable


def test_the_published_example_as_a_book(tmp_path):
    """OSU ME 3751 Lecture 12 (tests/data/published.toml) stated through the language
    (tests/data/osu-lecture12.toml: x the crank angle, f the quadratic through the printed
    pairs): the book's precision angles are the printed ones, its K1-K3 and lengths the exact
    solution of those angles by the reference to 1e-9 and the printed numbers within their
    printed accuracy (the ~1 % docs/synthesis.md explains), and verify agrees."""
    from conftest import published
    from linkbook.language.templates import load
    osu = published()["synthesis"]["osu_me3751_lecture12"]
    theta, phi, r1 = (osu["inputs"][k] for k in ("theta", "phi", "r1"))
    t = load(str(ROOT / "tests" / "data" / "osu-lecture12.toml"))
    assert t.values()["a1"] == r1 and t.length_unit == "in"
    syn, cell, column = _cells(t)
    assert column("theta2_deg") == pytest.approx(theta, abs=1e-12)
    assert column("theta4_deg") == pytest.approx(phi, abs=1e-12)
    exact = ref.function_generation(np.radians(theta), np.radians(phi), r1)
    for key in ("K1", "K2", "K3", "a", "b", "c"):
        assert cell(key) == pytest.approx(exact[key], rel=1e-9), key
    printed = osu["published"]
    for key, name in (("K3", "z1"), ("K1", "z2"), ("K2", "z3"), ("a", "R2"), ("b", "R3"),
                      ("c", "R4")):
        assert cell(key) == pytest.approx(printed[name], rel=osu["rel_tolerance"]), key
    assert cell("grashof") == "Grashof: crank-rocker" and cell("designed_branch") == 1
    path = tmp_path / "osu.xlsx"
    builder.build_file(t, path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
