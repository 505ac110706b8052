"""Forces of the triad's links (issue 41, docs/coupled-loops.md "Forces"): the book resolves each
binary link's force on the ternary along the link (f, by Cramer's rule over the ternary's three
equations) and across it (g, by the binary link's moment balance). Every expected value comes
from outside the force writer: the independent Newton–Euler reference (all links' equations at
once, its pin forces resolved along the links for Fa_*, Fn_*), judged by verify's own
machinery, and the power balance with the velocities of the independent kinematic reference
(test_forces_book.py). The template is tests/data/forces/triad-sixbar.toml: the example's
geometry with a mass on every link, a force, a torque and gravity, each a parameter."""
from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, given, settings
from hypothesis import strategies as st

from conftest import ROOT, examples
from test_forces_book import assert_power_balance, assert_verified, with_values
from test_slotted_forces import DRAWS, RATES, judge_draw, rows_of
from test_properties import in_load_domain
from test_triad_book import triad_assembly
from test_triad_reference import conditioning
from linkbook.base.errors import InputError
from linkbook.book import builder
from linkbook.check.forces import forces
from linkbook.check.reference import solve
from linkbook.engine import evaluator as engine
from linkbook.language import templates

EXAMPLE = ROOT / "templates" / "triad-sixbar.toml"
FORCES = ROOT / "tests" / "data" / "forces" / "triad-sixbar.toml"
SHEET = "Forces"
STEP = 30.0                     # the random draws' sweep
ITERATIONS = 8                  # enough from the row above at STEP on the triads drawn
POINT = st.tuples(st.floats(-60, 60), st.floats(-60, 60))
CENTRE = st.floats(-60.0, 60.0)     # a link's centre in its frame, mm


def _data() -> dict:
    return tomllib.loads(FORCES.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def example():
    t = templates.load(str(FORCES))
    built, values = builder.make(t)
    return t, built, values


def test_the_forces_template_is_the_example_with_masses():
    """Its geometry, sketch and steps are the bundled example's (templates/triad-sixbar.toml), word
    for word: what is verified here is the example book with masses on it."""
    example, ours = tomllib.loads(EXAMPLE.read_text(encoding="utf-8")), _data()
    assert ours["mechanism"]["steps"] == example["mechanism"]["steps"]
    for key in ("ground", "links", "input"):
        assert ours["mechanism"][key] == example["mechanism"][key]
    assert {k: v for k, v in ours["parameters"].items() if k in example["parameters"]} == \
        example["parameters"]


def test_the_example_with_masses_and_gravity_verifies_and_balances_power(example):
    """Every formula cell of the book, the Forces sheet's among them (a mass on each of the
    five links, a force at F, a torque on B0-E, gravity), within verify's bounds of the
    reference; the driving torque balances the power on every row of the sweep (the current
    position's 60° comes first to the kinematic reference, which then does not continue back
    to the sweep's 0°: that row has no reference velocities to balance with)."""
    t, built, values = example
    assert_verified(built, values)
    assert assert_power_balance(t, built, values) >= rows_of(built) - 1
    columns = built.meta["forces"]["columns"]
    assert {"T12", "F34x", "F45y", "F46x", "F15", "F16", "Fa_D", "Fn_E", "Fa_F"} <= set(columns)


def test_a_binary_link_without_mass_or_load_pushes_along_itself(example):
    """A binary link with no mass and no load is a two-force member: the reference's force of
    B0-E on the ternary has no part across the link (Fn_E = 0 to rounding) and its part along
    it is the whole pin force (|Fa_E| = F45); the book's columns agree, as verify judges."""
    t, _, _ = example
    t = with_values(t, m5=0.0, I5=0.0, T5=0.0)
    angles = np.arange(0.0, 360.0, 30.0)
    ref = forces(t.mechanism.description, t.values(), angles, t.length_unit)
    assert np.isfinite(ref["Fa_E"]).all()
    np.testing.assert_allclose(ref["Fn_E"], 0.0, atol=1e-12 * np.max(ref["F45"]))
    np.testing.assert_allclose(np.abs(ref["Fa_E"]), ref["F45"], rtol=1e-12)
    assert np.max(np.abs(ref["Fn_D"])) > 1e-3 * np.max(ref["F34"])      # link 3 has its mass
    assert_verified(*builder.make(dataclasses.replace(
        t, sweep=dataclasses.replace(t.sweep, step=STEP))))


@st.composite
def triads(draw) -> dict:
    """A triad six-bar that closes on every row of the sweep at STEP, 2 % or more away from a
    dead centre on each (as test_triad_book draws them: nearer one, the book's Newton and the
    reference's may reach different assemblies), sketched within 1 % of its size of its
    assembly at θ = 0."""
    crank = draw(st.floats(2.0, 8.0))
    b0, c0, *joints = (draw(POINT) for _ in range(5))
    ends = [(crank, 0.0), b0, c0]
    shortest = min([math.dist(p, j) for p, j in zip(ends, joints)]
                   + [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
                   + [math.dist(ends[k], ends[(k + 1) % 3]) for k in range(3)])
    assume(shortest >= 6.0)
    off = draw(st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
    sketch = [(j[0] + 0.01 * shortest * off[2 * k], j[1] + 0.01 * shortest * off[2 * k + 1])
              for k, j in enumerate(joints)]
    values = triad_assembly(crank, b0, c0, joints, sketch)
    data = _data()
    params = {**{k: v["value"] for k, v in data["parameters"].items()}, **values}
    angles = np.arange(0.0, 360.0 + STEP / 2, STEP)
    ref = solve(data["mechanism"], params, angles)
    assume(np.isfinite(ref["xD"]).all())
    assume(all(conditioning([(crank * math.cos(a), crank * math.sin(a)), b0, c0],
                            [(ref[f"x{n}"][i], ref[f"y{n}"][i]) for n in "DEF"]) > 0.02
               for i, a in enumerate(np.radians(angles))))
    return values


@pytest.fixture(scope="module")
def coarse():
    """The template on a sweep every STEP degrees with ITERATIONS Newton iterations, built
    once, with the engine that evaluated it (to evaluate it again at drawn inputs, as verify
    does at its other input sets)."""
    data = _data()
    data["sweep"]["step"] = STEP
    data["mechanism"]["steps"][1]["iterations"] = ITERATIONS
    t = templates.from_data("triad-forces", data)
    built, _ = builder.make(t)
    evaluation = engine.Engine(built.workbook)
    return t, built, evaluation, evaluation.run()


def loads(t: templates.Template):
    """The dynamics' parameters drawn: masses, inertias, the force and the torque, gravity
    and its direction, the input's rates, and each link's centre anywhere near it."""
    kinds = {p.symbol: DRAWS[p.kind].filter(in_load_domain) for p in t.parameters
             if p.kind in DRAWS and (p.kind != "angle" or p.symbol == "g_angle")}
    centres = {f"{c}{n}": CENTRE for c in "uv" for n in range(2, 7)}
    return st.fixed_dictionaries({**kinds, **RATES, **centres})


def test_random_masses_and_loads_on_random_triads_agree_with_the_reference(coarse):
    """For random triads and random masses, inertias, centres, loads, gravity and input rates:
    the book's formulas evaluated at those inputs agree with the force reference in every
    cell, as verify judges a book at its other input sets, and its driving torque balances
    the power on every row."""
    t, built, evaluation, _ = coarse
    balanced = []

    @settings(max_examples=examples(12, at_least=3), deadline=None, derandomize=True,
              phases=[Phase.explicit, Phase.reuse, Phase.generate],
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                     HealthCheck.function_scoped_fixture])
    @given(triads(), loads(t))
    def check(geometry, dynamics):
        balanced.append(judge_draw(t, built, evaluation, {**geometry, **dynamics}))

    check()
    assert min(balanced) >= rows_of(built) - 1, balanced


@pytest.mark.libreoffice
def test_libreoffice_recalculates_the_forces_like_the_reference(needs, tmp_path):
    """LibreOffice's full recalculation of the example with masses (the Forces sheet's
    Cramer's rule over the Newton iterations' solution) agrees with the reference in every
    formula cell."""
    needs("libreoffice")
    import linkbook
    path = linkbook.build(FORCES, tmp_path / "triad-forces.xlsx")
    report = linkbook.verify(path, engine="libreoffice")
    assert report.status == 0, [(c.name, c.mismatches[:2]) for c in report.checks if not c.ok]
    assert any(c.block == SHEET for c in report.checks)


def _hung(data: dict, joint: str, first: bool = False) -> dict:
    """The template with a dyad G hung from the triad's joint, its link to G0 on the ground,
    a mass on the link joint–G and a force at G; its link listed first in `links` or last."""
    mech = data["mechanism"]
    mech["ground"]["G0"] = [-40, 40]
    hung = [[joint, "G"]]
    mech["links"] = (hung if first else []) + mech["links"] + ([] if first else hung) + \
        [["G0", "G"]]
    mech["steps"].append({"type": "dyad", "point": "G", "p": joint, "q": "G0",
                          "p_length": 50, "q_length": 40, "branch": 1})
    mech["bodies"].append({"joints": [joint, "G"], "mass": 0.5, "inertia": 0.0002,
                           "centre": {"frame": [joint, "G"], "local": [25, 5]}})
    mech["loads"].append({"at": "G", "force": [10, 20]})
    data["sweep"]["step"] = STEP
    return data


@pytest.mark.parametrize("joint", ["D", "E"])
def test_a_group_hung_from_a_joint_of_the_triad(joint):
    """A later group's reaction at a joint of the triad enters its equations: at D it acts
    on the binary link A-D (the pin's carrier: its moment about A, so g), at E on the ternary
    (its three equations). The book verifies and balances power on every row."""
    t = templates.from_data("triad-hung", _hung(_data(), joint))
    built, values = builder.make(t)
    assert_verified(built, values)
    assert assert_power_balance(t, built, values) >= rows_of(built) - 1


def test_a_joint_of_the_triad_carried_by_a_later_link_is_refused_in_one_line():
    """The same dyad with its link E-G listed first: that link would carry the pin at E, which
    joins three links the book's groups cannot share out (the force analysis' existing limit,
    docs/language.md): refused in one line naming the file and the step."""
    with pytest.raises(InputError) as caught:
        templates.from_data("triad-hung", _hung(_data(), "E", first=True),
                            origin="triad-hung.toml")
    message = str(caught.value)
    assert "\n" not in message, message
    assert message.startswith("triad-hung.toml: mechanism.steps[2] (dyad G): force analysis: "
                              "the pin E "), message
