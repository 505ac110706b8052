"""The slider-crank function generation reference (issue 38): against linkbook's position
reference (the design, placed at each crank angle, puts its slider at the target), against the
slider-crank that made the targets, and against the textbook's linear form solved here.

Expected values never come from the module under test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, event, example, given, settings, strategies as st

from conftest import examples

from linkbook.check.reference import solve
from linkbook.check.reference.synthesis import SINGULAR_COND
from linkbook.check.reference.synthesis_slider import slider_crank_function_generation

EXAMPLES = examples(100)
ROUND_TRIP = 1e-9       # of the largest |s_j|
DEAD_CENTRE = 1e-7      # ... at a dead centre (a double root), √ε

# The slider-crank in the mechanism language: the crank A about A0 = (0, 0) (a negative a is
# the crank turned by 180°), the slider's pin B on the line through L0 = (0, e) along +x.
SLIDER_CRANK = {"input": {"key": "theta2"}, "ground": {"A0": [0, 0], "L0": [0, "e"]},
                "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": "a",
                           "phase": "phase"},
                          {"type": "slider", "point": "B", "p": "A", "length": "b",
                           "through": "L0", "direction": 0, "branch": "branch"}]}


def params_of(a: float, b: float, e: float, branch: int) -> dict:
    return {"a": abs(a), "phase": 180.0 if a < 0 else 0.0, "b": b, "e": e, "branch": branch}


def placed_s(params: dict, theta2) -> np.ndarray:
    """The slider's position s at crank angles θ2 (rad) by the position reference."""
    return solve(SLIDER_CRANK, params, np.degrees(np.atleast_1d(theta2)))["s_B"]


def textbook(theta2, s) -> tuple[float, float, float]:
    """(a, e, b²) of the linear form 2a·s·cos θ + 2ae·sin θ + (b² − a² − e²) = s², by numpy."""
    theta2, s = np.asarray(theta2), np.asarray(s)
    k = np.linalg.solve(np.column_stack([2 * s * np.cos(theta2), 2 * np.sin(theta2),
                                         np.ones(3)]), s * s)
    a, e = k[0], k[1] / k[0]
    return a, e, k[2] + a * a + e * e


def assert_meets_targets(design: dict, theta2, s) -> None:
    scale = float(np.max(np.abs(s)))
    gaps = {side: np.nan_to_num(np.abs(placed_s(params_of(design["a"], design["b"],
                                                           design["e"], side), theta2) - s)
                                / scale, nan=np.inf) for side in (1, -1)}
    if design["branch_defect"]:
        event("branch defect")
        assert all(not (gap < DEAD_CENTRE).all() for gap in gaps.values())
        return
    side = int(design["branch"][design["branch"] != 0][0])
    event(f"branch {side:+d}")
    bound = np.where(design["branch"] == 0, DEAD_CENTRE, ROUND_TRIP)
    assert (gaps[side] < bound).all(), gaps[side]
    assert gaps[-side].max() > 1e-6


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(a=st.floats(0.2, 5.0), b=st.floats(0.2, 10.0), e=st.floats(-3.0, 3.0),
       turned=st.booleans(), branch=st.sampled_from([1, -1]),
       theta2=st.lists(st.floats(-3.1, 3.1), min_size=3, max_size=3, unique=True))
def test_the_slider_crank_that_made_the_targets_comes_back(a, b, e, turned, branch, theta2):
    a = -a if turned else a
    s = placed_s(params_of(a, b, e, branch), theta2)
    assume(np.isfinite(s).all() and np.max(np.abs(s)) > 1e-3)
    design = slider_crank_function_generation(theta2, s)
    if design["ill_determined"]:
        event("ill-determined")
        assert math.isnan(design["a"]) and not design["singular"]
        return
    if design["singular"]:
        event("singular")
        return
    tol = max(ROUND_TRIP, design["condition"] * 1e-13) * max(abs(a), b, abs(e), 1.0) * 10
    assert [design["a"], design["b"], design["e"]] == pytest.approx([a, b, e], abs=tol)
    assert set(design["branch"][design["branch"] != 0].tolist()) <= {branch}
    assert_meets_targets(design, theta2, s)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(theta2=st.lists(st.floats(-3.1, 3.1), min_size=3, max_size=3, unique=True),
       s=st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3, unique=True))
@example(theta2=[1.0, 0.0, 1e-05], s=[1.0, 0.00390625, 0.0])   # roots that disagree
def test_random_tasks_meet_their_targets_or_have_no_slider_crank(theta2, s):
    """A design meets its targets on its branch (the position reference), and its a, e, b are
    the textbook's linear form solved by numpy; no design where that form is near-singular or
    gives a = 0."""
    theta2, s = np.array(theta2), np.array(s)
    design = slider_crank_function_generation(theta2, s)
    if design["ill_determined"]:
        event("ill-determined")
        assert math.isnan(design["a"]) and not design["singular"]
        return
    if design["singular"]:
        event("singular")
        assert design["condition"] > SINGULAR_COND and math.isnan(design["a"])
        return
    a, e, b2 = textbook(theta2, s)
    scale = np.max(np.abs(s))
    if math.isnan(design["a"]):         # b² = |B_j − A_j|² ≥ 0 always: only a crank of no length
        event("no crank")
        assert abs(a) <= 1e-9 * scale
        return
    # e = 2ae/2a: a short crank (2a small against the coefficients' size) costs e its digits
    k = np.array([2 * a * scale, 2 * a * e, b2 - a * a - e * e]) / scale ** 2
    tol = design["condition"] * 1e-12 * (scale + (abs(a) + abs(e)) * np.abs(k).max()
                                         / abs(k[0]))
    assert [design["a"], design["e"]] == pytest.approx([a, e], abs=tol)
    assert design["b"] ** 2 == pytest.approx(b2, abs=tol * max(scale, math.sqrt(b2)) * 10)
    event("full turn" if design["full_turn"] else "partial turn")
    assert_meets_targets(design, theta2, s)
    # the crank turns fully where the position reference closes the loop all the way round
    # (every degree, 90° and 270° among them, where |a·sin θ − e| is largest)
    margin = design["b"] - abs(design["a"]) - abs(design["e"])
    if abs(margin) > 1e-9 * scale:
        round_trip = placed_s(params_of(design["a"], design["b"], design["e"], 1),
                              np.radians(np.arange(0.0, 360.0, 1.0)))
        assert bool(np.isfinite(round_trip).all()) == design["full_turn"]


def test_no_slider_crank_where_none_exists():
    """A point given twice: two equal rows (singular). |s_j| all equal: the linear form gives
    2a = 0 (checked here): no crank, so nothing is designed."""
    same = slider_crank_function_generation([0.3, 0.3, 1.0], [1.0, 1.0, 3.0])
    assert same["singular"] and same["condition"] > SINGULAR_COND and math.isnan(same["a"])
    theta2, s = [0.0, 1.0, 2.0], [1.0, 1.0, -1.0]
    assert abs(textbook(theta2, s)[0]) < 1e-15
    none = slider_crank_function_generation(theta2, s)
    assert not none["singular"] and all(math.isnan(none[k]) for k in ("a", "b", "e"))
    with pytest.raises(ValueError, match="three pairs"):
        slider_crank_function_generation([0.1, 0.2], [1.0, 2.0])
