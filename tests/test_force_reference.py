"""The independent force reference (linkbook.check.forces): cases derived by hand (a four-bar, a
slider-crank, and one mechanism per sliding pair: a slide, a slot, a slider on a moving line),
the slider-crank a book printed, and the balances of power and momentum on random masses and
loads of the bundled mechanisms and a slider on a moving line. Every expected value comes from
outside the code under test: statics and virtual work with the kinematic reference's rates, a
closed-form slider-crank, the book's numbers, and the energy and momentum the kinematic
reference's motion implies."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import examples, published
from si_motion import SIMotion, inline_piston
from linkbook.check.forces import forces
from linkbook.check.reference import solve
from linkbook.language import templates

EXAMPLES = examples(25, at_least=5)     # the fast tier's five, as before the profiles
SLOTTED_EXAMPLES = examples(100, at_least=5)     # issue 39: a hundred per slotted family
DATA = Path(__file__).resolve().parent / "data" / "forces"
MM = 1e-3


def _with(description: dict, **dynamics) -> dict:
    """A template's description with these bodies, loads and gravity in place of its own."""
    bare = {k: v for k, v in description.items() if k not in ("dynamics", "bodies", "loads")}
    return {**bare, **dynamics}


def test_static_fourbar_by_virtual_work():
    """No masses, only a torque T on the rocker B0-B (body 4). The pins are frictionless and the
    links rigid, so the efforts' powers sum to zero (virtual work): T12·ω12 + T·ω14 = 0, hence
    T12 = −T·ω14/ω12, with ω14 from the kinematic reference (not from the force solver).
    Statics of the links: the coupler A-B-C carries no load but its two pins, so it is a
    two-force member: F23 ∥ (B − A), and its pins' forces balance, F34 = F23. The crank has two
    pins and a couple: F12 + F32 = 0, F12 = F23; the rocker likewise: F14 = −F34."""
    t = templates.load("fourbar")
    torque, w12 = 7.5, 3.0
    params = {**t.values(), "omega_in": w12, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 5.0)
    description = _with(t.mechanism.description,
                        loads=[{"body": ["B0", "B"], "torque": torque}])
    got = forces(description, params, angles, t.length_unit)
    motion = solve(t.mechanism.description, params, angles)
    assert got["bodies"] == {2: ("A0", "A"), 3: ("A", "B", "C"), 4: ("B", "B0")}
    np.testing.assert_allclose(got["T12"], -torque * motion["omega_theta14"] / w12, rtol=1e-10)
    points = motion["points"]
    ax, ay = (np.asarray(c) for c in points["A"])
    bx, by = (np.asarray(c) for c in points["B"])
    size = got["F23"]
    assert np.all(np.abs(got["F23x"] * (by - ay) - got["F23y"] * (bx - ax))
                  <= 1e-10 * size * np.hypot(bx - ax, by - ay))
    for key, sign in (("F12", 1.0), ("F34", 1.0), ("F14", -1.0)):
        for c in "xy":
            np.testing.assert_allclose(got[key + c], sign * got["F23" + c], rtol=0,
                                       atol=1e-10 * size.max())


def test_inline_slider_crank_piston_inertia_by_hand():
    """In-line slider-crank, crank r = 50 mm, rod l = 200 mm, turning at a constant ω; only the
    piston has mass (m), no gravity. Its position x_B = r·cos θ + D, D = √(l² − r² sin² θ):
        x′  = −r sin θ − r² sin θ cos θ / D
        x″  = −r cos θ − r² cos 2θ / D − r⁴ sin² θ cos² θ / D³
    and v_B = ω·x′, a_B = ω²·x″ (α = 0). The crank and rod are massless and the pins and the
    guide frictionless (the guide's force is normal to the motion), so the motor's power feeds
    only the piston's kinetic energy: T12·ω = d(½ m v_B²)/dt = m·a_B·v_B. That is, the piston's
    inertia force −m·a_B times its velocity ratio v_B/ω, balanced: T12 = −(−m·a_B)·v_B/ω.
    The piston's x equation has the rod's push alone (the guide's force is along y):
    F34x = m·a_B; the rod is a two-force member, F23 ∥ (B − A), and the crank passes its load
    on, F12 = F23."""
    r, l, w, m = 50.0, 200.0, 30.0, 2.0
    description = {"input": {"key": "theta"}, "ground": {"A0": [0, 0]},
                   "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": "r"},
                             {"type": "slider", "point": "B", "p": "A", "length": "l",
                              "through": "A0", "branch": 1}],
                   "bodies": [{"joints": ["B"], "block": True, "mass": "m"}]}
    params = {"r": r, "l": l, "m": m, "omega_in": w, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 7.5)
    got = forces(description, params, angles, "mm")
    th = np.radians(angles)
    rm, lm = r * MM, l * MM
    v, a, d = inline_piston(rm, lm, w, th)
    scale = m * np.max(np.abs(a)) * np.max(np.abs(v)) / w
    np.testing.assert_allclose(got["T12"], m * a * v / w, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(got["F34x"], m * a, rtol=0, atol=1e-10 * m * np.max(np.abs(a)))
    ay = rm * np.sin(th)            # B − A = (x_B − r cos θ, 0 − r sin θ) = (D, −r sin θ)
    assert np.all(np.abs(got["F23x"] * -ay - got["F23y"] * d) <= 1e-10 * got["F23"] * lm)
    np.testing.assert_allclose(got["F12x"], got["F23x"], rtol=1e-12)


def _marghitu(case: dict) -> dict:
    """The book's slider-crank as a description: A the origin, the crank A→B, the slider C on
    the x axis through A, ahead of B's foot (branch 1)."""
    i = case["inputs"]
    return {"input": {"key": "phi"}, "ground": {"A": [0, 0]},
            "steps": [{"type": "crank", "point": "B", "pivot": "A", "length": i["AB"]},
                      {"type": "slider", "point": "C", "p": "B", "length": i["BC"],
                       "through": "A", "branch": 1}],
            "dynamics": {"gravity": {"g": i["g"]}},          # the default direction: −y
            "bodies": [{"joints": ["A", "B"], "mass": i["m1"], "inertia": i["I1"],
                        "centre": {"frame": ["A", "B"], "distance": i["AB"] / 2}},
                       {"joints": ["B", "C"], "mass": i["m2"], "inertia": i["I2"],
                        "centre": {"frame": ["B", "C"], "distance": i["BC"] / 2}},
                       {"joints": ["C"], "block": True, "mass": i["m3"], "inertia": i["I3"]}],
            "loads": [{"at": "C", "force": [i["F_ext"], 0.0]}]}


def test_marghitu_slider_crank_published():
    """Marghitu (2009), p. 144: F12, the crank's force on the rod at B. The book numbers the
    links from 0 (the ground); here the ground is 1, so its F12 is our F23."""
    case = published()["marghitu_slider_crank_forces"]
    i = case["inputs"]
    got = forces(_marghitu(case), {"omega_in": i["omega"], "alpha_in": i["alpha"]},
                 [i["phi"]], "m")
    assert got["joints"]["F23"] == "B"
    for book, ours in (("F12x", "F23x"), ("F12y", "F23y")):
        assert got[ours][0] == pytest.approx(case["published"][book], rel=case["rel_tolerance"])


def test_marghitu_slider_crank_derived():
    """The other unknowns of the same example, not printed on the page we have: closed forms
    solved from the book's data link by link (each link's ΣF and ΣM; derived, not published),
    in the book's numbering F01 → our F12, F23 → F34, F03 → F14, M → T12. The shaking force is
    what the links push the ground with, −(F01 + F03); its moment about A, −M − r_C × F03."""
    case = published()["marghitu_slider_crank_forces"]
    i = case["inputs"]
    got = forces(_marghitu(case), {"omega_in": i["omega"], "alpha_in": i["alpha"]},
                 [i["phi"]], "m")
    r2 = math.sqrt(2.0)
    derived = {"T12": 3 + 105 * r2, "F12x": -100 - 2 * r2, "F12y": 115 + r2,
               "F34x": -100 - r2, "F34y": 95 + 1.5 * r2, "F14x": 0.0, "F14y": -85 - 1.5 * r2,
               "N14": -85 - 1.5 * r2, "M14": 0.0, "shaking_x": 100 + 2 * r2,
               "shaking_y": -30 + r2 / 2, "shaking_moment": -20 * r2}
    for key, want in derived.items():
        assert got[key][0] == pytest.approx(want, rel=1e-12, abs=1e-12), key


# --------------------------------------------------------------------------------------------
# Sliding pairs: a slide, a slot and a slider on a moving line, statics by hand
# --------------------------------------------------------------------------------------------

# A four-bar A0-A-B-B0 whose rocker B0-B carries a guide (its line through B0 at δ to B0→B,
# out beyond B) on which a block K slides, pushed by a rod from the coupler's point C: a slider
# on a moving line. The drawing's rocker holds K (it is drawn on its guide); the force analysis
# leaves it out.
ROCKER_SLIDER = {
    "input": {"key": "theta12"}, "ground": {"A0": [0, 0], "B0": ["a1", 0]},
    "links": [["A0", "A"], ["A", "B", "C"], ["B0", "B", "K"], ["C", "K"]],
    "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": "a2"},
              {"type": "dyad", "point": "B", "p": "A", "q": "B0", "p_length": "a3",
               "q_length": "a4", "branch": 1},
              {"type": "point", "point": "C", "frame": ["A", "B"], "local": ["u3", "v3"]},
              {"type": "slider", "point": "K", "p": "C", "length": "a5", "through": "B0",
               "along": ["B0", "B"], "direction": "delta", "branch": 1}]}
ROCKER_SLIDER_VALUES = {"a1": 100.0, "a2": 30.0, "a3": 90.0, "a4": 80.0, "u3": 45.0,
                        "v3": 40.0, "a5": 70.0, "delta": 8.0}


def _unit(points, a: str, b: str):
    """The unit vector a→b of two solved points, per row."""
    (ax, ay), (bx, by) = ((np.asarray(c, dtype=float) for c in points[p]) for p in (a, b))
    size = np.hypot(bx - ax, by - ay)
    return (bx - ax) / size, (by - ay) / size


def test_the_sliding_pairs_bodies_and_keys():
    """The numbering of docs/language.md (ground 1, crank 2, the links in `links` order, the
    steps' links, the blocks last) with each sliding point left out of its guide's drawing, and
    the keys of the pins, guides and slots with the point of each."""
    cases = {
        # the drawing's link 4 ["B0", "B", "A"] is the link B0-B: A slides on it
        "inverted-slider-crank": ({2: ("A0", "A"), 3: ("B0", "B"), 4: ("A",)},
                                  {"F12": "A0", "F24": "A", "F13": "B0", "F34": "A"}),
        # ["E", "P"], the slot drawn from its foot E, is no link
        "pump": ({2: ("A0", "A"), 3: ("A", "B"), 4: ("B", "B0", "E"), 5: ("P",)},
                 {"F12": "A0", "F23": "A", "F34": "B", "F14": "B0", "F15": "P", "F45": "P"}),
    }
    for name, (bodies, joints) in cases.items():
        t = templates.load(name)
        got = forces(t.mechanism.description, t.values(), [30.0], t.length_unit)
        assert got["bodies"] == bodies and got["joints"] == joints, name
    got = forces(ROCKER_SLIDER, {**ROCKER_SLIDER_VALUES, "omega_in": 1.0, "alpha_in": 0.0},
                 [30.0], "mm")
    assert got["bodies"] == {2: ("A0", "A"), 3: ("A", "B", "C"), 4: ("B0", "B"),
                             5: ("C", "K"), 6: ("K",)}
    assert got["joints"] == {"F12": "A0", "F23": "A", "F34": "B", "F35": "C", "F14": "B0",
                             "F56": "K", "F46": "K"}
    assert {"N46", "M46", "F46"} <= set(got) and "N34" not in got     # B is a pin


def test_inverted_slider_crank_static_by_hand():
    """The bundled inverted slider-crank, no masses, only a torque T on the slide's link B0-B
    (body 3; the block at A is body 4). Virtual work: T12·ω12 + T·ω14 = 0, ω14 the rate of its
    column theta14 (the link's angle B0→B) from the kinematic reference: T12 = −T·ω14/ω12.
    Statics: the massless block has the crank's pin force F24 and the guide's force N34·n and
    couple M34, all at A: about A, M34 = 0, and F34 = N34·n = −F24, n the slide's direction
    (the column theta13) turned +90°, n = (−sin θ13, cos θ13). The link 3 turns about B0 under
    T and the block's push −N34·n at A: T − (A − B0) × N34·n = 0, N34 = T / ((A − B0) × n)."""
    t = templates.load("inverted-slider-crank")
    torque, w12 = 4.0, 5.0
    params = {**t.values(), "omega_in": w12, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 5.0)
    got = forces(_with(t.mechanism.description, loads=[{"body": ["B0", "B"], "torque": torque}]),
                 params, angles, t.length_unit)
    motion = solve(t.mechanism.description, params, angles)
    want = -torque * motion["omega_theta14"] / w12
    np.testing.assert_allclose(got["T12"], want, rtol=0, atol=1e-10 * np.max(np.abs(want)))
    nx, ny = -np.sin(motion["theta13"]), np.cos(motion["theta13"])
    (ax, ay), (bx, by) = ((np.asarray(c) * MM for c in motion["points"][p]) for p in ("A", "B0"))
    normal = torque / ((ax - bx) * ny - (ay - by) * nx)
    size = np.max(np.abs(normal))
    np.testing.assert_allclose(got["N34"], normal, rtol=1e-10)
    np.testing.assert_allclose(got["M34"], 0.0, atol=1e-10 * size * 0.1)   # N·m: 0.1 m
    for c, n in (("x", nx), ("y", ny)):
        np.testing.assert_allclose(got["F34" + c], normal * n, rtol=0, atol=1e-10 * size)
        np.testing.assert_allclose(got["F24" + c], -normal * n, rtol=0, atol=1e-10 * size)
    np.testing.assert_allclose(got["F34"], np.abs(normal), rtol=1e-10)


def test_pump_slot_static_by_hand():
    """The bundled pump, no masses, only a force F along the plunger's line d (direction 180°:
    d = (−1, 0)) on the block at P. Virtual work: T12·ω12 + F·(v_P·d) = 0, v_P from the
    kinematic reference: T12 = −F·(v_P·d)/ω12. Statics of the massless block: the load F·d,
    the guide's N15·n (n = d turned +90° = (0, −1)) and couple M15, the slot's N45·m (m the
    slot's direction u = angle(B0→E) + 90° turned +90°), all at P: M15 = 0; along x,
    −F + N45·m_x = 0, so N45 = F/m_x; along y, −N15 + N45·m_y = 0, so N15 = N45·m_y. The pin
    in the slot pushes across the slot only: no M45."""
    t = templates.load("pump")
    push, w12 = 300.0, 8.0
    params = {**t.values(), "omega_in": w12, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 5.0)
    got = forces(_with(t.mechanism.description, loads=[{"at": "P", "force": [-push, 0.0]}]),
                 params, angles, t.length_unit)
    motion = solve(t.mechanism.description, params, angles)
    want = -push * (-motion["vx_P"] * MM) / w12
    np.testing.assert_allclose(got["T12"], want, rtol=0, atol=1e-10 * np.max(np.abs(want)))
    fx, fy = _unit(motion["points"], "B0", "E")          # u = the frame's direction + 90°
    ux, uy = -fy, fx
    mx, my = -uy, ux
    slot = push / mx
    size = np.max(np.abs(slot))
    np.testing.assert_allclose(got["N45"], slot, rtol=1e-10)
    np.testing.assert_allclose(got["N15"], slot * my, rtol=0, atol=1e-10 * size)
    np.testing.assert_allclose(got["M15"], 0.0, atol=1e-10 * size * 0.1)   # N·m: 0.1 m
    assert "M45" not in got
    for key, n, sign in (("F45", (mx, my), slot), ("F15", (0.0, -1.0), slot * my)):
        np.testing.assert_allclose(got[key + "x"], sign * n[0], rtol=0, atol=1e-10 * size)
        np.testing.assert_allclose(got[key + "y"], sign * n[1], rtol=0, atol=1e-10 * size)


def test_slider_on_a_moving_line_static_by_hand():
    """ROCKER_SLIDER, no masses, only a force F along the guide's line d, at δ to B0→B, on
    the block K (body 6, on the rocker 4, pushed by the rod C-K, body 5). Virtual work:
    T12·ω12 + F·(v_K·d) = 0: T12 = −F·(v_K·d)/ω12, v_K from the kinematic reference. Statics:
    the rod is a two-force member, F56 = f·w with w = (K − C)/|K − C|; the massless block has
    F56, F·d, the guide's N46·n (n = d turned +90°) and couple M46, all at K: M46 = 0; along d,
    f·(w·d) + F = 0; along n, f·(w·n) + N46 = 0: N46 = F·(w·n)/(w·d)."""
    push, w12 = 120.0, 6.0
    params = {**ROCKER_SLIDER_VALUES, "omega_in": w12, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 5.0)
    load = {"at": "K", "force": ["F*COS(line_K)", "F*SIN(line_K)"]}
    got = forces({**ROCKER_SLIDER, "loads": [load]}, {**params, "F": push}, angles, "mm")
    motion = solve(ROCKER_SLIDER, params, angles)
    bx, by = _unit(motion["points"], "B0", "B")
    cd, sd = math.cos(math.radians(params["delta"])), math.sin(math.radians(params["delta"]))
    dx, dy = bx * cd - by * sd, bx * sd + by * cd
    nx, ny = -dy, dx
    wx, wy = _unit(motion["points"], "C", "K")
    vd = (motion["vx_K"] * dx + motion["vy_K"] * dy) * MM
    want = -push * vd / w12
    np.testing.assert_allclose(got["T12"], want, rtol=0, atol=1e-10 * np.max(np.abs(want)))
    f = -push / (wx * dx + wy * dy)
    normal = push * (wx * nx + wy * ny) / (wx * dx + wy * dy)
    size = np.max(np.abs(f))
    np.testing.assert_allclose(got["N46"], normal, rtol=0, atol=1e-10 * size)
    np.testing.assert_allclose(got["M46"], 0.0, atol=1e-10 * size * 0.1)   # N·m: 0.1 m
    for c, n, w in (("x", nx, wx), ("y", ny, wy)):
        np.testing.assert_allclose(got["F46" + c], normal * n, rtol=0, atol=1e-10 * size)
        np.testing.assert_allclose(got["F56" + c], f * w, rtol=0, atol=1e-10 * size)


def test_a_block_turns_with_its_slide_of_offset_zero():
    """The inverted slider-crank with its slide line through the pivot (offset 0: the link's
    point B is its pivot B0, so the link's spin is its column's, theta14). Only the block at A
    has mass m and inertia I; a torque T on the link. The block turns with the link, so the
    motor's power feeds its kinetic energy less T's power:
        T12·ω12 + T·ω14 = m·a_A·v_A + I·α14·ω14."""
    t = templates.load("inverted-slider-crank")
    m, inertia, torque, w12, a12 = 1.5, 0.02, -3.0, 12.0, 40.0
    params = {**t.values(), "a4": 0.0, "omega_in": w12, "alpha_in": a12}
    angles = np.arange(0.0, 360.0, 5.0)
    got = forces(_with(t.mechanism.description,
                       bodies=[{"joints": ["A"], "block": True, "mass": m, "inertia": inertia}],
                       loads=[{"body": ["B0", "B"], "torque": torque}]),
                 params, angles, t.length_unit)
    kin = _Kinematics(solve(t.mechanism.description, params, angles), MM, {})
    _, (vx, vy), (ax, ay) = kin.point("A")
    w14, a14 = kin.s["omega_theta14"], kin.s["alpha_theta14"]
    kinetic = m * (ax * vx + ay * vy) + inertia * a14 * w14
    residual = got["T12"] * w12 + torque * w14 - kinetic
    assert np.all(np.isfinite(residual))
    assert np.all(np.abs(residual) <= 1e-9 * (np.abs(got["T12"] * w12) + np.abs(kinetic)))


# --------------------------------------------------------------------------------------------
# The balances of power and momentum on random masses and loads
# --------------------------------------------------------------------------------------------

# The moving links of the mechanisms, as this test reads their drawings (a one-point entry is
# a block: it turns with the link GUIDES names, a block on a fixed line does not turn).
LINKS = {
    "fourbar": [["A0", "A"], ["A", "B", "C"], ["B0", "B"]],
    "slider-crank": [["A0", "A"], ["A", "B", "C"], ["B"]],
    "watt-sixbar": [["A0", "A"], ["A", "B"], ["B0", "B", "C"], ["C", "D"], ["D0", "D"]],
    "jansen": [["O", "A"], ["A", "B"], ["A", "C"], ["Z", "B", "D"], ["Z", "C"], ["D", "E"],
               ["C", "E", "F"]],
    "boom-cylinder": [["O", "B", "T"]],
    "inverted-slider-crank": [["A0", "A"], ["B0", "B"], ["A"]],
    "pump": [["A0", "A"], ["A", "B"], ["B", "B0", "E"], ["P"]],
    "rocker-slider": [["A0", "A"], ["A", "B", "C"], ["B0", "B"], ["C", "K"], ["K"]],
    # the slotted links, each named by its frame first (its pivot or slide point, and the pin
    # sliding in it): their centres are placed in that frame, which turns with the link
    "quick-return": [["A0", "A"], ["B0", "A", "C"], ["C", "D"], ["A"], ["D"]],
    "whitworth": [["A0", "A"], ["B0", "A", "C"], ["C", "D"], ["A"], ["D"]],
    "shaper": [["O2", "A"], ["O1", "A"], ["A"], ["B"]],
    "slide-shaper": [["A0", "A"], ["B", "A", "C"], ["C", "D"], ["A"], ["D"]],
}
GUIDES = {"inverted-slider-crank": {"A": ["B0", "B"]}, "rocker-slider": {"K": ["B0", "B"]},
          "quick-return": {"A": ["B0", "C"]}, "whitworth": {"A": ["B0", "C"]},
          "shaper": {"A": ["O1", "A"]}, "slide-shaper": {"A": ["B", "C"]}}
SLOTTED_FAMILIES = {"quick-return", "whitworth", "shaper", "slide-shaper"}


def _mechanism(name: str):
    """A mechanism of LINKS: its description, parameter values, swept inputs, length unit."""
    if name == "rocker-slider":
        return ROCKER_SLIDER, dict(ROCKER_SLIDER_VALUES), np.arange(0.0, 360.0, 5.0), "mm"
    t = templates.load(str(DATA / f"{name}.toml") if name == "slide-shaper" else name)
    description = t.mechanism.description
    angle_input = description["input"].get("kind", "angle") == "angle"
    angles = np.asarray(t.sweep.angles()[:-1] if angle_input else t.sweep.angles(), dtype=float)
    return description, t.values(), angles, t.length_unit


def _draw_dynamics(data, name: str, moving: list[str]) -> dict:
    """Random masses (some links massless), centres (`local` in the link's frame), inertias,
    point forces (as components or magnitude and angle), torques (on a link or a block) and
    gravity."""
    bodies, loads = [], []
    for joints in LINKS[name]:
        if not data.draw(st.booleans()):
            continue
        entry = {"joints": joints, "mass": data.draw(st.floats(0.05, 20.0)),
                 "inertia": data.draw(st.floats(0.0, 0.5))}
        if len(joints) == 1:
            entry["block"] = True
        else:
            entry["centre"] = {"frame": joints[:2],
                               "local": [data.draw(st.floats(-120.0, 120.0)),
                                         data.draw(st.floats(-60.0, 60.0))]}
        bodies.append(entry)
    for _ in range(data.draw(st.integers(0, 2))):
        at = data.draw(st.sampled_from(moving))
        if data.draw(st.booleans()):
            force = [data.draw(st.floats(-500.0, 500.0)), data.draw(st.floats(-500.0, 500.0))]
        else:
            force = {"magnitude": data.draw(st.floats(0.0, 500.0)),
                     "angle": data.draw(st.floats(-180.0, 180.0))}
        loads.append({"at": at, "force": force})
    if data.draw(st.booleans()):               # on a link or a block (its one point)
        loads.append({"body": data.draw(st.sampled_from(LINKS[name]))[:2],
                      "torque": data.draw(st.floats(-50.0, 50.0))})
    out = {"bodies": bodies, "loads": loads}
    if data.draw(st.booleans()):
        gravity = {"g": data.draw(st.floats(0.0, 20.0))}
        if data.draw(st.booleans()):           # else the default direction, −y
            gravity["angle"] = data.draw(st.floats(-180.0, 180.0))
        out["dynamics"] = {"gravity": gravity}
    return out


class _Kinematics(SIMotion):
    """The kinematic reference's motion in SI units, as the drawn links see it; `guides`:
    {a block's point: its guide's joints}."""

    def __init__(self, solved: dict, metres: float, guides: dict):
        super().__init__(solved, metres)
        self.guides = guides

    def link_spin(self, joints: list[str]):
        """ω and α of a rigid link, from its first and last joints; a block's are its guide's
        (a block on a fixed line does not turn)."""
        if len(joints) == 1:
            if joints[0] in self.guides:
                return self.link_spin(self.guides[joints[0]])
            return np.zeros(self.n), np.zeros(self.n)
        return self.spin(joints[0], joints[-1])

    def centre(self, entry: dict):
        """The centre of mass's position, velocity and acceleration: G = A + u·ê + v·ê⊥ on the
        frame A→B of the link's first two joints, moving with the link."""
        joints = entry["joints"]
        if entry.get("block"):
            return self.point(joints[0])
        u, v = (c * self.unit for c in entry["centre"]["local"])
        return self.carried(joints[0], joints[1], u, v)[:3]


def _vector(force) -> tuple[float, float]:
    if isinstance(force, dict):
        angle = math.radians(force["angle"])
        return force["magnitude"] * math.cos(angle), force["magnitude"] * math.sin(angle)
    return force[0], force[1]


def _balances(got: dict, dyn: dict, kin: _Kinematics, power_in, links: list[list[str]]):
    """The power and the momentum balances' residuals, each with the sum of its terms' scales:
        T12·ω12 (or F_in·v_in) + Σ F·v_P + Σ T·ω + Σ m g·v_G = Σ (m a_G·v_G + I α ω)
        −S + Σ F + Σ m g = Σ m a_G
        −M_S + Σ r_P × F + Σ T + Σ r_G × m g = Σ (r_G × m a_G + I α)    (about the origin)
    S and M_S: the shaking force and moment (what the links do to the ground)."""
    gravity = dyn.get("dynamics", {}).get("gravity")
    g = _vector({"magnitude": gravity["g"], "angle": gravity.get("angle", -90.0)}) \
        if gravity else (0.0, 0.0)
    # each term with its scale: a dot or cross product's is the product of its factors'
    # magnitudes (|F|·|v|, |r|·|F|), of which its rounding is ε even where it vanishes
    size = np.abs
    power = [(power_in, size(power_in))]
    force_x, force_y = [(-got["shaking_x"], size(got["shaking_x"]))], \
        [(-got["shaking_y"], size(got["shaking_y"]))]
    moment = [(-got["shaking_moment"], size(got["shaking_moment"]))]
    for load in dyn["loads"]:
        if "torque" in load:
            link = next(j for j in links if load["body"] == j[:2])
            torque_power = load["torque"] * kin.link_spin(link)[0]
            power.append((torque_power, size(torque_power)))
            moment.append((np.full(kin.n, load["torque"]), np.full(kin.n, abs(load["torque"]))))
            continue
        fx, fy = _vector(load["force"])
        (x, y), (vx, vy), _ = kin.point(load["at"])
        f = math.hypot(fx, fy)
        power.append((fx * vx + fy * vy, f * np.hypot(vx, vy)))
        force_x.append((np.full(kin.n, fx), np.full(kin.n, abs(fx))))
        force_y.append((np.full(kin.n, fy), np.full(kin.n, abs(fy))))
        moment.append((x * fy - y * fx, f * np.hypot(x, y)))
    g_size = math.hypot(*g)
    for entry in dyn["bodies"]:
        m, inertia = entry["mass"], entry["inertia"]
        (x, y), (vx, vy), (ax, ay) = kin.centre(entry)
        w, al = kin.link_spin(entry["joints"])
        v, a, r = np.hypot(vx, vy), np.hypot(ax, ay), np.hypot(x, y)
        # α is rounding of the order of ε·ω² where it vanishes (the crank's at a constant ω)
        spin = abs(inertia) * (size(al) + w * w)
        power += [(m * (g[0] * vx + g[1] * vy), abs(m) * g_size * v),
                  (-(m * (ax * vx + ay * vy)), abs(m) * a * v),
                  (-inertia * al * w, spin * size(w))]
        force_x += [(np.full(kin.n, m * g[0]), np.full(kin.n, abs(m * g[0]))),
                    (-m * ax, size(m * ax))]
        force_y += [(np.full(kin.n, m * g[1]), np.full(kin.n, abs(m * g[1]))),
                    (-m * ay, size(m * ay))]
        moment += [(m * (x * g[1] - y * g[0]), abs(m) * r * g_size),
                   (-m * (x * ay - y * ax), abs(m) * r * a), (-inertia * al, spin)]
    return [(sum(t for t, _ in terms), sum(scale for _, scale in terms))
            for terms in (power, force_x, force_y, moment)]


@pytest.mark.parametrize("name", sorted(LINKS))
def test_power_and_momentum_balance(name):
    """On every row, for random masses, centres, inertias, loads, gravity and input rates: the
    input's power equals the rate of the kinetic energy less the loads' and gravity's power, and
    the shaking force and moment close the mechanism's momentum balance (to 1e-9 of the terms)."""
    description, values, angles, length_unit = _mechanism(name)
    angle_input = description["input"].get("kind", "angle") == "angle"
    moving = sorted({p for j in LINKS[name] for p in j} - set(description["ground"]))

    @settings(max_examples=SLOTTED_EXAMPLES if name in SLOTTED_FAMILIES else EXAMPLES,
              deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
    @given(st.data())
    def check(data):
        dyn = _draw_dynamics(data, name, moving)
        speed, accel = ("omega_in", "alpha_in") if angle_input else ("v_in", "a_in")
        rates = {speed: data.draw(st.floats(-30.0, 30.0) if angle_input
                                  else st.floats(-500.0, 500.0)),
                 accel: data.draw(st.floats(-100.0, 100.0) if angle_input
                                  else st.floats(-1000.0, 1000.0))}
        params = {**values, **rates}
        got = forces(_with(description, **dyn), params, angles, length_unit)
        kin = _Kinematics(solve(description, params, angles), MM, GUIDES.get(name, {}))
        assert np.isfinite(got["shaking_moment"]).all()
        power_in = got["T12"] * rates[speed] if angle_input else got["F_in"] * rates[speed] * MM
        balances = _balances(got, dyn, kin, power_in, LINKS[name])
        # the solve leaves rounding of its pin forces' size in the effort and in the shaking
        # force and moment (sums of the ground pins' forces), even where every true term
        # vanishes (a link turning about its centre of mass: its pins carry only the couple)
        pins = np.max([np.abs(got[k]) for k in got if k[0] == "F" and k[1:].isdigit()], axis=0)
        reach = max(np.nanmax(np.hypot(*kin.point(p)[0])) for p in moving)
        speed_scale = reach * abs(rates[speed]) if angle_input else abs(rates[speed]) * MM
        balances = [(residual, size + pins * scale) for (residual, size), scale
                    in zip(balances, (speed_scale, 1.0, 1.0, reach))]
        for residual, size in balances:
            assert np.all(np.abs(residual) <= 1e-9 * size + 1e-12), np.max(np.abs(residual))

    check()


# --------------------------------------------------------------------------------------------
# What it refuses, and the rows it cannot solve
# --------------------------------------------------------------------------------------------

# The slotted links written with a vector step from the pivot to the pin sliding in it: the
# bodies as docs/language.md numbers them (the slotted link holds its pivot and what is carried
# on it; the block at the pin, pinned to the crank, slides in it), and every joint's point.
SLOTTED = {
    "quick-return": ({2: ("A0", "A"), 3: ("B0", "C"), 4: ("C", "D"), 5: ("A",), 6: ("D",)},
                     {"F12": "A0", "F13": "B0", "F25": "A", "F35": "A", "F34": "C", "F46": "D",
                      "F16": "D"}, ("B0", "A")),
    "whitworth": ({2: ("A0", "A"), 3: ("C", "B0"), 4: ("C", "D"), 5: ("A",), 6: ("D",)},
                  {"F12": "A0", "F13": "B0", "F25": "A", "F35": "A", "F34": "C", "F46": "D",
                   "F16": "D"}, ("B0", "A")),
    "shaper": ({2: ("O2", "A"), 3: ("O1",), 4: ("A",), 5: ("B",)},
               {"F12": "O2", "F13": "O1", "F24": "A", "F34": "A", "F35": "B", "F15": "B"},
               ("O1", "A")),
}


@pytest.mark.parametrize("name", sorted(SLOTTED))
def test_a_slotted_link_turned_by_a_vector_step_static_by_hand(name):
    """No masses, only a torque T on the slotted link (body 3, named by its pivot and the pin
    in its slot). Virtual work: T12·ω12 + T·ω3 = 0, ω3 the kinematic reference's rate of the
    vector's angle. The block in the slot is massless, held by two forces only, the crank's
    pin and the link's push across the slot: they balance, F2b = −F3b, and the pin's force is
    square to the slot (F2b·e = 0, e along pivot→pin); no couple where the block has none."""
    t = templates.load(name)
    bodies, joints, (pivot, pin) = SLOTTED[name]
    torque, w12 = 4.0, 3.0
    params = {**t.values(), "omega_in": w12, "alpha_in": 0.0}
    angles = np.arange(0.0, 360.0, 5.0)
    got = forces(_with(t.mechanism.description, loads=[{"body": [pivot, pin], "torque": torque}]),
                 params, angles, t.length_unit)
    assert got["bodies"] == bodies and got["joints"] == joints
    motion = solve(t.mechanism.description, params, angles)
    vector = next(s for s in t.mechanism.description["steps"] if s["type"] == "vector")
    omega = motion["omega_" + vector["columns"]["phi"]["key"]]
    np.testing.assert_allclose(got["T12"], -torque * omega / w12, rtol=1e-10)
    blk = next(n for n, j in bodies.items() if j == (pin,))        # the block at the pin
    pin_key, guide_key = f"F2{blk}", f"F3{blk}"
    size = np.max(got[pin_key])
    e = _unit(motion["points"], pivot, pin)
    for c in "xy":
        np.testing.assert_allclose(got[pin_key + c], -got[guide_key + c], rtol=0,
                                   atol=1e-10 * size)
    assert np.all(np.abs(got[pin_key + "x"] * e[0] + got[pin_key + "y"] * e[1]) <= 1e-10 * size)


def test_a_body_entry_naming_no_link_is_refused():
    t = templates.load("fourbar")
    description = _with(t.mechanism.description, bodies=[{"joints": ["A0", "B"], "mass": 1.0,
                                                          "centre": {"frame": ["A0", "B"],
                                                                     "distance": 1.0}}])
    with pytest.raises(ValueError, match=r"bodies\[0\]"):
        forces(description, t.values(), [0.0], t.length_unit)


def test_rows_that_do_not_close_are_nan():
    """A four-bar whose crank is too long to turn all round: where the loop cannot close the
    positions are NaN, and so is every force; elsewhere they are numbers."""
    t = templates.load("fourbar")
    params = {**t.values(), "a2": 60.0}
    angles = np.arange(0.0, 360.0, 10.0)
    closed = solve(t.mechanism.description, params, angles)["assembled"]
    assert closed.any() and not closed.all()
    got = forces(_with(t.mechanism.description, loads=[{"at": "C", "force": [10.0, 0.0]}]),
                 params, angles, t.length_unit)
    for key in ("T12", "F23x", "F14", "shaking_moment"):
        assert np.array_equal(np.isfinite(got[key]), closed), key
