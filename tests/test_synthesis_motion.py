"""The motion and path generation reference (issue 38): against linkbook's position reference
(the designed linkage, placed at each pose's crank angle, must put its coupler point and angle
on the pose), against the linkage that made the poses, against the textbook's standard dyad
form written out here, and against pylinkage.

Expected values never come from the module under test: they are the position reference's
placement, the generating linkage's own dimensions, the textbook's equations solved here by
numpy, or a third party's design.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, event, given, settings, strategies as st

from conftest import examples

from linkbook.check.reference import solve
from linkbook.check.reference.synthesis import SINGULAR_COND
from linkbook.check.reference.synthesis_motion import (DEGENERATE, motion_generation,
                                                       path_generation)

EXAMPLES = examples(100)
ROUND_TRIP = 1e-9       # of the linkage's size (positions) or rad (the coupler's angle)
# ... except at a dead centre (a double root of the position), where the lengths' round-off ε
# moves the joint by √ε.
DEAD_CENTRE = 1e-7

# A four-bar with a coupler point in the mechanism language: the crank A about A0, the joint B
# of the dyad over P = A and Q = B0 (docs/language.md: branch +1 is B clockwise from A seen from
# B0), and the coupler point P = A + u·ê + v·ê⊥ in the frame A→B.
FOURBAR = {"input": {"key": "theta2"}, "ground": {"A0": ["ax", "ay"], "B0": ["bx", "by"]},
           "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": "a", "phase": 0},
                     {"type": "dyad", "point": "B", "p": "A", "q": "B0", "p_length": "b",
                      "q_length": "c", "branch": "branch"},
                     {"type": "point", "point": "P", "frame": ["A", "B"],
                      "local": ["u", "v"]}]}


def params_of(design: dict, branch: int) -> dict:
    (ax, ay), (bx, by), (u, v) = design["A0"], design["B0"], design["coupler_point"]
    return {"ax": ax, "ay": ay, "bx": bx, "by": by, "a": design["a"], "b": design["b"],
            "c": design["c"], "u": u, "v": v, "branch": branch}


def placed(params: dict, theta2) -> dict:
    """The position reference's four-bar at crank angles θ2 (rad): P's position and the angle
    of A→B, NaN where it cannot close."""
    out = solve(FOURBAR, params, np.degrees(np.atleast_1d(theta2)))
    return {"P": out["xP"] + 1j * out["yP"], "theta3": out["theta_p_B"],
            "theta4": out["theta_q_B"]}


def angle_gap(x, y) -> np.ndarray:
    """x − y as an angle in [−π, π)."""
    return np.remainder(np.asarray(x) - np.asarray(y) + math.pi, 2.0 * math.pi) - math.pi


def size_of(design: dict) -> float:
    return max(design[k] for k in "abcd")


def misses(design: dict, x, y, alpha, branch: int) -> np.ndarray:
    """Per pose, how far the designed linkage placed on `branch` at the pose's crank angle is
    from the pose: the larger of |ΔP|/size and |Δα| (NaN-free: a pose it cannot reach is inf)."""
    where = placed(params_of(design, branch), design["theta2"])
    gap_p = np.abs(where["P"] - (np.asarray(x) + 1j * np.asarray(y))) / size_of(design)
    gap_a = np.abs(angle_gap(where["theta3"] + design["coupler_offset"], alpha))
    return np.nan_to_num(np.maximum(gap_p, gap_a), nan=np.inf)


def assert_passes_through(design: dict, x, y, alpha) -> None:
    """The linkage on its named branch meets every pose to ROUND_TRIP; the other branch misses
    one; with a branch defect, neither branch meets all three."""
    gaps = {side: misses(design, x, y, alpha, side) for side in (1, -1)}
    if design["branch_defect"]:
        event("branch defect")
        assert all(not (gap < DEAD_CENTRE).all() for gap in gaps.values())
        return
    side = int(design["branch"][design["branch"] != 0][0])
    event(f"branch {side:+d}")
    bound = np.where(design["branch"] == 0, DEAD_CENTRE, ROUND_TRIP)
    assert (gaps[side] < bound).all(), gaps[side]
    assert gaps[-side].max() > 1e-6


# --- a linkage that made the poses --------------------------------------------------------

coordinate = st.floats(-5.0, 5.0)
length = st.floats(0.3, 5.0)
angle = st.floats(-3.1, 3.1)


@st.composite
def linkages(draw):
    """A four-bar with a coupler point, its branch and three crank angles (rad) at which the
    position reference closes it; the poses its coupler point and the line A→B (plus a drawn
    offset) pass through."""
    ax, ay, ground, heading = (draw(coordinate), draw(coordinate), draw(length), draw(angle))
    params = {"ax": ax, "ay": ay, "bx": ax + ground * math.cos(heading),
              "by": ay + ground * math.sin(heading), "a": draw(length), "b": draw(length),
              "c": draw(length), "u": draw(coordinate), "v": draw(coordinate),
              "branch": draw(st.sampled_from([1, -1]))}
    theta2 = np.radians(draw(st.tuples(*(st.floats(-180.0, 180.0),) * 3)))
    where = placed(params, theta2)
    assume(np.isfinite(where["P"]).all())
    offset = draw(st.floats(-3.0, 3.0))
    return params, theta2, where, offset


def assert_same_linkage(design: dict, params: dict, theta2: np.ndarray) -> None:
    """The design is the generating linkage: its pivots, lengths and coupler point, to the
    system's condition × round-off of its size."""
    size = max(params[k] for k in ("a", "b", "c"))
    tol = max(ROUND_TRIP, design["condition"] * 1e-13) * max(size, 1.0) * 10
    assert design["A0"] == pytest.approx((params["ax"], params["ay"]), abs=tol)
    assert design["B0"] == pytest.approx((params["bx"], params["by"]), abs=tol)
    assert [design[k] for k in "abc"] == pytest.approx([params[k] for k in "abc"], abs=tol)
    assert design["coupler_point"] == pytest.approx((params["u"], params["v"]), abs=tol)
    assert np.abs(angle_gap(design["theta2"], theta2)).max() < tol / params["a"]


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(linkages())
def test_each_form_recovers_the_linkage_that_made_the_poses(linkage):
    """Poses made by a known four-bar (placed by the position reference): the free choices
    read off that placement (its crank's and rocker's rotations), or its fixed pivots, give
    that four-bar back; so does path generation with the crank's rotations as timing."""
    params, theta2, where, offset = linkage
    x, y, alpha = where["P"].real, where["P"].imag, where["theta3"] + offset
    beta, gamma = theta2[1:] - theta2[0], where["theta4"][1:] - where["theta4"][0]
    forms = {"rotations": motion_generation(x, y, alpha, crank_rotation=beta,
                                            rocker_rotation=gamma),
             "pivots": motion_generation(x, y, alpha,
                                         crank_pivot=(params["ax"], params["ay"]),
                                         rocker_pivot=(params["bx"], params["by"])),
             "timing": path_generation(x, y, beta, alpha[1:] - alpha[0], gamma)}
    for name, design in forms.items():
        if design["singular"]:
            event(f"{name}: singular")
            continue
        assert not design["degenerate"]
        assert_same_linkage(design, params, theta2)
        sides = design["branch"][design["branch"] != 0]
        assert (sides == params["branch"]).all()
        # path generation states the coupler's rotations only: its α_1 is 0
        assert_passes_through(design, x, y, alpha - (alpha[0] if name == "timing" else 0.0))


# --- random tasks ---------------------------------------------------------------------------

# Distinct values, so that most tasks have a design: the singular ones still come (collinear
# points, a free choice equal to the coupler's rotation), and the tests below name some.
distinct = st.lists(angle, min_size=3, max_size=3, unique=True)
poses = st.tuples(st.lists(coordinate, min_size=3, max_size=3, unique=True),
                  st.lists(coordinate, min_size=3, max_size=3, unique=True), distinct)
free_choices = st.tuples(distinct, distinct).map(lambda pair: pair[0][1:] + pair[1][1:])


def report(design: dict) -> bool:
    """Event the kind of result; True if there is a linkage to place."""
    if design["singular"] or design["degenerate"]:
        event("singular" if design["singular"] else "degenerate")
        assert all(math.isnan(design[k]) for k in "abcd") and design["grashof"] is None
        if design["singular"]:
            assert design["condition"] > SINGULAR_COND
        return False
    event(design["grashof"].split(":")[0])
    return True


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(task=poses, free=free_choices)
def test_motion_generation_by_free_choices_passes_through_its_poses(task, free):
    x, y, alpha = (np.array(v) for v in task)
    design = motion_generation(x, y, alpha, crank_rotation=free[:2], rocker_rotation=free[2:])
    if report(design):
        assert_passes_through(design, x, y, alpha)
        assert design["crank_rotation"][1:] == pytest.approx(
            angle_gap(np.array(free[:2]), 0.0), abs=1e-9)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(task=poses, pivots=st.tuples(coordinate, coordinate, coordinate, coordinate))
def test_motion_generation_by_fixed_pivots_passes_through_its_poses(task, pivots):
    x, y, alpha = (np.array(v) for v in task)
    design = motion_generation(x, y, alpha, crank_pivot=pivots[:2], rocker_pivot=pivots[2:])
    if report(design):
        assert design["A0"] == pivots[:2] and design["B0"] == pivots[2:]
        assert_passes_through(design, x, y, alpha)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(points=poses, timing=distinct, free=free_choices)
def test_path_generation_meets_its_points_at_its_crank_angles(points, timing, free):
    """The coupler point reaches P_j when the crank has turned through β_j (the placement is
    at the design's θ2_1 + β_j), with the coupler turned through the free α_j."""
    x, y, timing = np.array(points[0]), np.array(points[1]), np.array(timing[1:])
    design = path_generation(x, y, timing, free[:2], free[2:])
    if report(design):
        alpha = np.concatenate([[0.0], free[:2]])
        assert_passes_through(design, x, y, alpha)
        assert angle_gap(design["theta2"][1:] - design["theta2"][0],
                         timing) == pytest.approx([0, 0], abs=1e-9)


# --- the textbook's standard form, solved here ----------------------------------------------

def standard_form(x, y, alpha, rotation) -> tuple[complex, complex]:
    """W, Z of W·(e^{iβ_j} − 1) + Z·(e^{iα_j} − 1) = δ_j, j = 2, 3 (Norton §5.7), by numpy."""
    p = np.asarray(x) + 1j * np.asarray(y)
    turn = np.asarray(alpha)[1:] - alpha[0]
    m = np.column_stack([np.exp(1j * np.asarray(rotation)) - 1.0, np.exp(1j * turn) - 1.0])
    return tuple(np.linalg.solve(m, p[1:] - p[0]))


def cross(p: complex, q: complex) -> float:
    return p.real * q.imag - p.imag * q.real


def sheet_condition(x, y, alpha, rotation) -> float:
    """cond₂ of [e^{iβ_j} − 1, e^{iα_j} − 1] by the 2×2 formula docs/synthesis.md gives the
    sheet: √(t₁/t₂), t₁ the larger root of t² − F·t + |D|², t₂ = |D|²/t₁."""
    turn = np.asarray(alpha)[1:] - alpha[0]
    m = np.column_stack([np.exp(1j * np.asarray(rotation)) - 1.0, np.exp(1j * turn) - 1.0])
    f, det = float(np.sum(np.abs(m) ** 2)), abs(m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0])
    if det == 0.0:
        return math.inf
    t1 = 0.5 * (f + math.sqrt(max(f * f - 4.0 * det * det, 0.0)))
    return t1 / det         # √(t₁/t₂) with t₂ = |D|²/t₁


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True)
@given(task=poses, free=free_choices)
def test_the_sheets_standard_form_gives_the_same_design(task, free):
    """docs/synthesis.md's "For the sheet": W, Z, U, S of the standard form (solved here by
    numpy), then the pivots, lengths, coupler point, offset and crank and rocker angles by its
    formulas, and its condition number: the reference's design, to condition × round-off."""
    x, y, alpha = (np.array(v) for v in task)
    design = motion_generation(x, y, alpha, crank_rotation=free[:2], rocker_rotation=free[2:])
    condition = max(sheet_condition(x, y, alpha, free[:2]), sheet_condition(x, y, alpha, free[2:]))
    if condition > SINGULAR_COND:       # near an exact singularity both are round-off
        assert design["condition"] > SINGULAR_COND
    else:
        assert condition == pytest.approx(design["condition"], rel=1e-6)
    assume(not design["singular"] and not design["degenerate"])
    tol = design["condition"] * 1e-13 * size_of(design)
    (w, z), (u, s) = (standard_form(x, y, alpha, free[:2]), standard_form(x, y, alpha, free[2:]))
    p1 = complex(x[0], y[0])
    expected = {"W": w, "Z": z, "U": u, "S": s, "A": p1 - z, "B": p1 - s,
                "A0": p1 - z - w, "B0": p1 - s - u}
    for key, value in expected.items():
        assert complex(*design[key]) == pytest.approx(value, abs=tol), key
    # what is measured between the two dyads (Z − S, W + Z − U − S) loses the digits a short
    # link cancels: size / shortest
    tol *= size_of(design) / min(design[k] for k in "abcd")
    b = abs(z - s)
    assert [design[k] for k in "abcd"] == pytest.approx(
        [abs(w), b, abs(u), abs(w + z - u - s)], abs=tol)
    assert design["coupler_point"] == pytest.approx(
        ((z * np.conj(z - s)).real / b, cross(z - s, z) / b), abs=tol)
    assert angle_gap(design["coupler_offset"], alpha[0] - np.angle(z - s)) \
        == pytest.approx(0.0, abs=tol / b)
    assert angle_gap(design["theta2"], np.angle(w) + np.array([0.0, *free[:2]])) \
        == pytest.approx([0.0] * 3, abs=tol / abs(w))
    assert angle_gap(design["theta4"], np.angle(u) + np.array([0.0, *free[2:]])) \
        == pytest.approx([0.0] * 3, abs=tol / abs(u))


# --- no linkage ------------------------------------------------------------------------------

def test_a_translation_along_a_line_designs_nothing():
    """Three collinear points, the coupler not turning: the standard form's column e^{iα_j} − 1
    vanishes, and with the fixed pivots given the circle condition's rows are parallel."""
    x, y, alpha = [0.0, 1.0, 3.0], [0.0, 0.5, 1.5], [0.2, 0.2, 0.2]
    for design in (motion_generation(x, y, alpha, crank_rotation=[0.3, 0.7],
                                     rocker_rotation=[-0.2, -0.5]),
                   motion_generation(x, y, alpha, crank_pivot=(1.0, -2.0),
                                     rocker_pivot=(3.0, -1.0))):
        assert design["singular"] and design["condition"] > SINGULAR_COND
        assert all(math.isnan(design[k]) for k in "abcd")
        assert all(math.isnan(v) for v in design["A0"] + design["coupler_point"])
        assert np.isnan(design["theta2"]).all() and np.isnan(design["branch"]).all()


def test_a_dyad_turning_with_the_coupler_designs_nothing():
    """β_j = α_j: the standard form's two columns are equal."""
    design = motion_generation([0, 1, 2], [0, 1, 0], [0.0, 0.4, 0.9],
                               crank_rotation=[0.4, 0.9], rocker_rotation=[-0.2, -0.5])
    assert design["singular"] and math.isnan(design["a"])


def test_a_repeated_pose_gives_a_crank_of_no_length():
    """Poses 1 and 2 equal: the crank's pin must stay on its pivot (W = 0): degenerate."""
    x, y, alpha = [1.0, 1.0, 2.0], [0.5, 0.5, 1.0], [0.1, 0.1, 0.6]
    w, _ = standard_form(x, y, alpha, [0.5, 1.0])
    assert abs(w) < 1e-15
    design = motion_generation(x, y, alpha, crank_rotation=[0.5, 1.0],
                               rocker_rotation=[-0.3, 0.4])
    assert design["degenerate"] and not design["singular"]
    assert all(math.isnan(design[k]) for k in "abcd")
    assert DEGENERATE < 1e-6


def test_the_branch_asked_for_is_checked():
    """A known crossed four-bar's poses: asking for the open one is a wrong branch."""
    params = {"ax": 0.0, "ay": 0.0, "bx": 4.0, "by": 0.0, "a": 1.0, "b": 3.5, "c": 2.5,
              "u": 1.0, "v": 1.0, "branch": -1}
    theta2 = np.radians([40.0, 80.0, 120.0])
    where = placed(params, theta2)
    x, y, alpha = where["P"].real, where["P"].imag, where["theta3"]
    pivots = {"crank_pivot": (0.0, 0.0), "rocker_pivot": (4.0, 0.0)}
    assert motion_generation(x, y, alpha, branch=-1, **pivots)["branch"].tolist() == [-1] * 3
    assert not motion_generation(x, y, alpha, branch=-1, **pivots)["wrong_branch"]
    assert motion_generation(x, y, alpha, branch=1, **pivots)["wrong_branch"]
    with pytest.raises(ValueError, match="branch"):
        motion_generation(x, y, alpha, branch=2, **pivots)
    with pytest.raises(ValueError, match="crank"):
        motion_generation(x, y, alpha, rocker_pivot=(4.0, 0.0))


# --- pylinkage, a third party ----------------------------------------------------------------

def carried(point, x, y, alpha) -> np.ndarray:
    """A point of the coupler, given at pose 1, at each pose (a rigid displacement)."""
    p = np.asarray(x) + 1j * np.asarray(y)
    return p + np.exp(1j * (np.asarray(alpha) - alpha[0])) * (complex(*point) - p[0])


def test_pylinkage_burmester_dyads_are_the_same_four_bars():
    """pylinkage 1.3's motion_generation_3_poses samples the Burmester centre-point curve and
    pairs dyads (fixed pivot, moving pivot at pose 1). Given its fixed pivots, the circle
    condition finds its moving pivots; given its dyads' rotations (its moving pivots carried
    through the poses), the pose transform finds its fixed pivots. Its path_generation_with_
    timing is not compared: it takes the crank angles as the coupler's rotations."""
    synthesis = pytest.importorskip("pylinkage.synthesis")
    rng = np.random.default_rng(38)
    compared = 0
    for _ in range(12):
        x, y, alpha = rng.uniform(-3.0, 3.0, 3), rng.uniform(-3.0, 3.0, 3), \
            rng.uniform(-1.5, 1.5, 3)
        result = synthesis.motion_generation_3_poses(
            [synthesis.Pose(*pose) for pose in zip(x, y, alpha)])
        for theirs in result.raw_solutions[:5]:
            fixed = (theirs.ground_pivot_a, theirs.ground_pivot_d)
            moving = (theirs.crank_pivot_b, theirs.coupler_pivot_c)
            spins = [np.angle((carried(m, x, y, alpha) - complex(*g))
                              / (complex(*m) - complex(*g)))[1:] for g, m in zip(fixed, moving)]
            by_pivots = motion_generation(x, y, alpha, crank_pivot=fixed[0],
                                          rocker_pivot=fixed[1])
            by_rotations = motion_generation(x, y, alpha, crank_rotation=spins[0],
                                             rocker_rotation=spins[1])
            lengths = [theirs.crank_length, theirs.coupler_length, theirs.rocker_length,
                       theirs.ground_length]
            for design in (by_pivots, by_rotations):
                tol = max(ROUND_TRIP, design["condition"] * 1e-13) * max(lengths)
                assert design["A0"] == pytest.approx(fixed[0], abs=tol)
                assert design["B0"] == pytest.approx(fixed[1], abs=tol)
                assert design["A"] == pytest.approx(moving[0], abs=tol)
                assert design["B"] == pytest.approx(moving[1], abs=tol)
                assert [design[k] for k in "abcd"] == pytest.approx(lengths, abs=tol)
            compared += 1
    assert compared >= 30
