"""Forces of the slotted-link machines (issue 39): the bundled crank shaper (`quick-return`), the
student project's `shaper` and `whitworth`, each a slotted link written as a vector step from its
pivot to the pin that slides in it, and the crank shaper written with a slide of offset 0
(tests/data/forces/slide-shaper.toml). Every expected value comes from outside the force writer:
the independent Newton–Euler reference, judged by verify's own machinery, and the power balance
with the velocities of the independent kinematic reference (test_forces_book.py)."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import examples
from test_forces_book import (SHEET, assert_power_balance, assert_verified, coarse, load,
                              with_values)
from linkbook.base.errors import InputError
from linkbook.book import builder
from linkbook.check.input_sets import input_cell, write_inputs
from linkbook.check.judge import judge_book
from linkbook.check.checks import Rules
from linkbook.engine import evaluator as engine
from linkbook.engine.rerun import rerun
from linkbook.language import templates
from linkbook.language.mechanisms import OFFSET_KIND
from test_properties import in_load_domain

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ["quick-return", "shaper", "whitworth"]
FAMILIES = [*BUNDLED, "slide-shaper"]
EXAMPLES = examples(100, at_least=5)
# what a draw gives each kind of the dynamics' parameters (a kind not here keeps its value)
DRAWS = {"mass": st.floats(0.0, 10.0), "inertia": st.floats(0.0, 0.1),
         "force": st.floats(-1e3, 1e3), "torque": st.floats(-100.0, 100.0),
         "acceleration": st.one_of(st.just(0.0), st.floats(0.0, 20.0)),
         "angle": st.floats(-180.0, 180.0)}
# the input's rates in the loads' domain: at a subnormal ω (2.2e-313, which a draw reached) the
# power balance's products keep no digits to compare
RATES = {"omega_in": st.floats(-30.0, 30.0).filter(in_load_domain),
         "alpha_in": st.floats(-100.0, 100.0).filter(in_load_domain)}
# the slotted link's centre in its frame (mm), and the slide's offset: 0 as written, or not
PLACES = {"u3": st.floats(-300.0, 300.0), "v3": st.floats(-60.0, 60.0),
          "e": st.sampled_from([0.0, 0.0, 12.0, -12.0])}


def rows_of(built) -> int:
    first, last = built.meta["forces"]["rows"]
    return last - first + 2            # the sweep's rows and the current position


@pytest.mark.parametrize("name", BUNDLED)
def test_the_bundled_machines_verify_and_balance_power_on_every_row(name):
    """The templates as bundled (masses on every moving link, gravity, the cutting force on
    the working stroke): every formula cell as the reference says, and the power balance on
    every row of the Forces sheet to 1e-9 of its terms (no row without a driving torque)."""
    t = templates.load(name)
    built, values = builder.make(t)
    assert_verified(built, values)
    assert assert_power_balance(t, built, values) == rows_of(built)


def test_a_flywheel_beyond_the_float_range_is_the_overflow_error():
    """At ω = 3.6e-154 rad/s (a random draw reached it) Cs·ω² is a subnormal number and ΔE over
    it is beyond the largest float: the book's flywheel cell shows #NUM!, the reference's
    quotient is inf, and verify takes the one for the other; every other cell still agrees."""
    t = with_values(templates.load("quick-return"), omega_in=3.6e-154)
    built, values = builder.make(coarse(t, {}))
    cell = built.meta["forces"]["summary"]["flywheel"]["cell"]
    assert engine.error_code(values[(SHEET, cell)]) == "#NUM!"
    assert_verified(built, values)


@pytest.fixture(scope="module")
def books():
    """Each family's book on a coarse sweep, built once, with the engine that evaluated it (to
    evaluate it again at drawn inputs, as verify does at its other input sets)."""
    out = {}
    for name in FAMILIES:
        t = coarse(load(name), {})
        built, _ = builder.make(t)
        evaluation = engine.Engine(built.workbook)
        out[name] = (t, built, evaluation, evaluation.run())
    return out


def draws(t: templates.Template):
    """The dynamics' parameters of a template drawn, its geometry as written (but PLACES)."""
    kinds = {p.symbol: DRAWS[p.kind].filter(in_load_domain) for p in t.parameters
             if p.kind in DRAWS and (p.kind != "angle" or p.symbol == "g_angle")}
    offsets = {p.symbol for p in t.parameters if p.kind == OFFSET_KIND}
    return st.fixed_dictionaries({**kinds, **RATES,
                                  **{k: v for k, v in PLACES.items() if k in offsets}})


def judge_draw(t: templates.Template, built, evaluation, drawn: dict) -> int:
    """The book's formulas evaluated again at the `drawn` inputs (as verify does at its other
    input sets): every cell agrees with the force reference, the Forces sheet among them, and
    the driving torque balances the power; the rows it balances on. The inputs restored after."""
    wb, record = built.workbook, built.record
    rules = Rules(engine.is_error, engine.error_code)
    held = write_inputs(wb, record, drawn)
    try:
        with rerun(evaluation, {input_cell(record, k): v for k, v in drawn.items()}) as got:
            checks = judge_book(wb, record, got, rules, own_inputs=False)
            bad = [(c.block, c.name, m) for c in checks for m in c.mismatches]
            assert not bad, bad[:4]
            assert any(c.block == SHEET for c in checks)
            return assert_power_balance(with_values(t, **drawn), built, got)
    finally:
        write_inputs(wb, record, held)


@pytest.mark.parametrize("name", FAMILIES)
def test_random_masses_and_loads_agree_with_the_reference(books, name):
    """For random masses, inertias, loads, gravity, input rates and the slotted link's centre
    (and the slide's offset, zero among them): the book's formulas evaluated at those inputs
    agree with the force reference everywhere, as verify judges a book at its other input
    sets, and its driving torque balances the power on every row it has one."""
    t, built, evaluation, _ = books[name]
    balanced = []

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(draws(t))
    def check(drawn):
        balanced.append(judge_draw(t, built, evaluation, drawn))

    check()
    assert min(balanced) > 0, balanced          # every draw has rows with a driving torque


def test_the_slide_shaper_is_the_vector_written_crank_shaper():
    """The crank shaper written with a slide of offset 0 and the one written with a vector step
    are one machine: given the same masses and loads (the rocker's centre at one place of its
    frame, B→A or B0→A), their books' driving torques agree on every row."""
    vector = coarse(load("quick-return"), {"u3": 200.0, "v3": 5.0})
    slide = coarse(load("slide-shaper"), {})
    assert vector.values()["I_blk"] == slide.values()["I5"]
    shared = {p.symbol for p in vector.parameters} & {p.symbol for p in slide.parameters}
    assert all(vector.values()[k] == slide.values()[k] for k in shared - {"branch"})
    efforts = []
    for t in (vector, slide):
        built, values = builder.make(t)
        table = built.meta["forces"]
        first, last = table["rows"]
        col = table["columns"]["T12"]
        efforts.append(np.array([values[(SHEET, f"{col}{r}")] for r in range(first, last + 1)],
                                dtype=float))
    np.testing.assert_allclose(efforts[0], efforts[1], rtol=1e-9)


def test_the_docs_worked_example_is_the_bundled_crank_shaper():
    """docs/language.md's complete example with forces is templates/quick-return.toml, word for
    word: what the tests above build and verify is what a reader copies."""
    text = (ROOT / "docs" / "language.md").read_text(encoding="utf-8")
    section = text[text.index("### A complete example with forces: the crank shaper"):]
    example = section[section.index("```toml\n") + len("```toml\n"):]
    assert example[:example.index("```")] == \
        (ROOT / "templates" / "quick-return.toml").read_text(encoding="utf-8")


def test_a_vector_step_no_step_is_carried_by_only_measures():
    """The shaper without its ram (no slot in the lever): the vector O1→A carries nothing, so it
    is a direction measured, no link, and a mass on the lever it would be is refused in one
    line naming the entry (and so is one on a block at A: there is none)."""
    data = tomllib.loads((ROOT / "templates" / "shaper.toml").read_text(encoding="utf-8"))
    mech = data["mechanism"]
    mech["steps"] = [s for s in mech["steps"] if s["type"] != "slot"]
    mech["bodies"] = [b for b in mech["bodies"] if len(b["joints"]) > 1]
    mech["loads"], mech["charts"], mech["output"] = [], [], "r3"
    mech["links"] = [["O2", "A"]]
    with pytest.raises(InputError) as caught:
        templates.from_data("lever", data, origin="lever.toml")
    assert str(caught.value).startswith("lever.toml: mechanism.bodies[1].joints: ")
    assert "\n" not in str(caught.value)
    mech["bodies"] = [{"joints": ["A"], "block": True, "mass": "m4"}]
    with pytest.raises(InputError, match=r"^lever.toml: mechanism.bodies\[0\].joints: a block"):
        templates.from_data("lever", data, origin="lever.toml")
