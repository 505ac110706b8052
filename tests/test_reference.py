"""Tests of the generic independent reference solver (src/linkbook/check/reference/), on the textbook's
eight mechanisms as the bundled templates describe them.

The solver is checked against what it must honour, never against numbers it produced itself:
the published values of the sources (tests/data/published.toml), the loop-closure equations of
docs/mechanisms.md rebuilt from the returned keys, the geometric branch invariants, exact
triangle-inequality tests for non-assembly, and the closed-form quick-return ratio.
"""

from __future__ import annotations

import math
import tomllib
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from linkbook.check import reference as generic
from linkbook.language import templates

REPO = Path(__file__).resolve().parents[1]
MECHANISMS = ("fourbar", "slider-crank", "pump", "inverted-slider-crank", "quick-return", "shaper",
              "garage-door", "tk-fourbar")


@lru_cache(maxsize=None)
def description(mech: str) -> dict:
    return templates.load(mech).mechanism.description


def solve(mech: str, params, angles) -> dict:
    return generic.solve(description(mech), params, angles)


LOOP_TOL = 1e-9
SWEEP = np.arange(0.0, 360.0 + 1e-9, 5.0)

# Default dimensions from docs/mechanisms.md (the seeds' examples where they give numbers).
DEFAULTS = {
    "fourbar": dict(a1=70.0, a2=35.0, a3=62.3, a4=56.0, b3=126.6, c3=84.1),
    "slider-crank": dict(a1=20.0, a2=50.0, a3=250.0, b3=120.0, gamma3=30.0),
    "pump": dict(a2=55.0, a3=240.0, a4=165.0, b1=185.0, c4=70.0, s1=20.0),
    "inverted-slider-crank": dict(a1=100.0, a2=40.0, a4=30.0),
    "quick-return": dict(a1=150.0, a2=60.0, a4=400.0, a5=120.0, b1=420.0),
    "shaper": dict(r1=60.0, r2=40.0, r6=60.0),
    "garage-door": dict(a1=100.0, a2=30.0, a3=110.0, a4=60.0, b2=80.0, a5=120.0, a6=150.0),
    "tk-fourbar": dict(a=0.5, b=1.0, c=1.5, m=1.2, n=-0.8, x3=1.8, y3=0.5),
}
PUMP_S1 = (20.0, 50.0, 100.0, 150.0, 200.0, 250.0)


def _published() -> dict:
    """tests/data/published.toml: the numbers the sources printed, kept inside the repository."""
    return tomllib.loads((REPO / "tests" / "data" / "published.toml").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def published() -> dict:
    return _published()


# ------------------------------------------------------------------------------------------
# Small geometry helpers for the checks
# ------------------------------------------------------------------------------------------

def angle_diff(a, b):
    """a − b reduced to [−π, π] (angles are compared modulo 2π)."""
    return np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b))))


def cross(ux, uy, vx, vy):
    return ux * vy - uy * vx


def off(x, y, x0, y0, length, angle):
    """Distance of (x, y) from the point (x0, y0) + length·e^{i·angle}."""
    return np.hypot(x - x0 - length * np.cos(angle), y - y0 - length * np.sin(angle))


def assert_zero(name, values, tol=LOOP_TOL):
    worst = float(np.max(np.abs(values)))
    assert worst <= tol, f"{name}: max |residual| = {worst:.3g} > {tol}"


def assert_same_angle(name, a, b, tol=LOOP_TOL):
    assert_zero(name, angle_diff(a, b), tol)


def assert_interior(name, angle):
    assert np.all((angle >= 0.0) & (angle <= math.pi)), f"{name} not in [0, π]"


# ------------------------------------------------------------------------------------------
# Loop closure rebuilt from the returned keys, and the branch invariants (one per mechanism)
# ------------------------------------------------------------------------------------------

def check_fourbar(p, r, br, **_):
    a1, a2, a3, a4, b3, c3 = (p[k] for k in ("a1", "a2", "a3", "a4", "b3", "c3"))
    th = r["theta12"]
    xA, yA, xB, yB, xC, yC = (r[k] for k in ("xA", "yA", "xB", "yB", "xC", "yC"))
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a2 * np.sin(th)))
    assert_zero("B from theta14", off(xB, yB, a1, 0.0, a4, r["theta14"]))
    assert_zero("|AB| = a3", np.hypot(xB - xA, yB - yA) - a3)
    assert_zero("|B0B| = a4", np.hypot(xB - a1, yB) - a4)
    assert_same_angle("theta13 = angle(A→B)", r["theta13"], np.arctan2(yB - yA, xB - xA))
    assert_zero("|AC| = b3", np.hypot(xC - xA, yC - yA) - b3)
    assert_zero("|BC| = c3", np.hypot(xC - xB, yC - yB) - c3)
    assert np.all(cross(xB - xA, yB - yA, xC - xA, yC - yA) > 0), "C left of A→B on both branches"
    assert_zero("C = A + b3 e^{i(θ13+γ)}", off(xC, yC, xA, yA, b3, r["theta13"] + r["gamma"]))
    # intermediate keys as the doc defines them
    assert_zero("xs", r["xs"] - (xA - a1))
    assert_zero("ys", r["ys"] - yA)
    assert_zero("s", r["s"] - np.hypot(xA - a1, yA))
    assert_same_angle("phi", r["phi"], np.arctan2(yA, xA - a1))
    assert_interior("mu", r["mu"])
    assert_interior("psi", r["psi"])
    assert_same_angle("theta14 = phi − branch·psi", r["theta14"], r["phi"] - br * r["psi"])
    assert_same_angle("theta13 = theta14 − branch·mu", r["theta13"], r["theta14"] - br * r["mu"])
    # branch invariant: cross(B − B0, A − B0) has the sign of branch
    assert np.all(br * cross(xB - a1, yB, xA - a1, yA) > 0), "fourbar branch invariant"


def check_slider_crank(p, r, br, **_):
    a1, a2, a3, b3 = (p[k] for k in ("a1", "a2", "a3", "b3"))
    g3 = math.radians(p["gamma3"])
    th = r["theta12"]
    xA, yA, xB, yB, xC, yC = (r[k] for k in ("xA", "yA", "xB", "yB", "xC", "yC"))
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a2 * np.sin(th)))
    assert_zero("B on the slider line", yB - a1)
    assert_zero("xB = s14", xB - r["s14"])
    assert_zero("|AB| = a3", np.hypot(xA - xB, yA - yB) - a3)
    assert_same_angle("theta13 = angle(B→A)", r["theta13"], np.arctan2(yA - yB, xA - xB))
    assert_zero("|BC| = b3", np.hypot(xC - xB, yC - yB) - b3)
    assert_same_angle("C = B + b3 e^{i(θ13−γ3)}", np.arctan2(yC - yB, xC - xB), r["theta13"] - g3)
    assert np.all(br * (xB - xA) > 0), "slider-crank branch invariant (branch 1: B right of A)"


def check_pump(p, r, br, **_):
    a2, a3, a4, b1, c4, s1 = (p[k] for k in ("a2", "a3", "a4", "b1", "c4", "s1"))
    th, t14 = r["theta12"], r["theta14"]
    xA, yA, xB, yB = (r[k] for k in ("xA", "yA", "xB", "yB"))
    x0, y0 = -b1, s1  # B0
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a2 * np.sin(th)))
    assert_zero("|AB| = a3", np.hypot(xB - xA, yB - yA) - a3)
    assert_zero("|B0B| = a4", np.hypot(xB - x0, yB - y0) - a4)
    assert_same_angle("arm B0B along theta14 + π/2", np.arctan2(yB - y0, xB - x0), t14 + math.pi / 2)
    assert_zero("E", np.hypot(r["xE"] - x0 - c4 * np.cos(t14), r["yE"] - y0 - c4 * np.sin(t14)))
    assert_zero("P on the x axis", r["yP"])
    assert_zero("P = (−s15, 0)", r["xP"] + r["s15"])
    # P lies in the slot: P = E + s4·e^{i(θ14 + π/2)}
    assert_zero("P in slot (x)", r["xP"] - r["xE"] + r["s4"] * np.sin(t14))
    assert_zero("P in slot (y)", r["yP"] - r["yE"] - r["s4"] * np.cos(t14))
    assert_zero("xa", r["xa"] - (b1 + a2 * np.cos(th)))
    assert_zero("ya", r["ya"] - (-s1 + a2 * np.sin(th)))
    assert_zero("s", r["s"] - np.hypot(r["xa"], r["ya"]))
    assert_same_angle("phi", r["phi"], np.arctan2(r["ya"], r["xa"]))
    assert_interior("psi", r["psi"])
    assert_same_angle("theta14 = phi − branch·psi − π/2", t14,
                      r["phi"] - br * r["psi"] - math.pi / 2)
    assert np.all(br * cross(xB - x0, yB - y0, xA - x0, yA - y0) > 0), "pump branch invariant"


def check_inverted_slider_crank(p, r, br, **_):
    a1, a2, a4 = (p[k] for k in ("a1", "a2", "a4"))
    th, t14 = r["theta12"], r["theta14"]
    xA, yA, xB, yB = (r[k] for k in ("xA", "yA", "xB", "yB"))
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a2 * np.sin(th)))
    assert_zero("B = B0 + a4 e^{iθ14}", np.hypot(xB - a1 - a4 * np.cos(t14), yB - a4 * np.sin(t14)))
    assert np.all(r["s"] >= 0), "s ≥ 0"
    assert_zero("|BA| = s", np.hypot(xA - xB, yA - yB) - r["s"])
    assert_zero("slide line ⊥ B0B", ((xA - xB) * (xB - a1) + (yA - yB) * yB) / (a4 * (a1 + a2)))
    assert_same_angle("theta13 = theta14 + branch·π/2", r["theta13"], t14 + br * math.pi / 2)
    assert_zero("A = B + s e^{iθ13}", np.hypot(xA - xB - r["s"] * np.cos(r["theta13"]),
                                               yA - yB - r["s"] * np.sin(r["theta13"])))
    assert_zero("p", r["p"] - np.hypot(xA - a1, yA))
    assert_zero("xp, yp", np.hypot(r["xp"] - (xA - a1), r["yp"] - yA))
    assert_same_angle("phi", r["phi"], np.arctan2(yA, xA - a1))
    assert_interior("psi", r["psi"])
    assert_same_angle("theta14 = phi − branch·psi", t14, r["phi"] - br * r["psi"])
    assert np.all(br * cross(xB - a1, yB, xA - a1, yA) > 0), "inverted slider-crank branch invariant"


def check_quick_return(p, r, br, **_):
    a1, a2, a4, a5, b1 = (p[k] for k in ("a1", "a2", "a4", "a5", "b1"))
    th, t14 = r["theta12"], r["theta14"]
    xA, yA, xC, yC, xD, yD = (r[k] for k in ("xA", "yA", "xC", "yC", "xD", "yD"))
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a1 - a2 * np.sin(th)))
    assert np.all(r["s43"] > 0), "s43 > 0"
    assert_zero("block on rocker: A = s43 e^{iθ14}", off(xA, yA, 0.0, 0.0, r["s43"], t14))
    assert_zero("C = a4 e^{iθ14}", np.hypot(xC - a4 * np.cos(t14), yC - a4 * np.sin(t14)))
    assert_zero("D on the ram line", yD - b1)
    assert_zero("xD = s16", xD - r["s16"])
    assert_zero("|CD| = a5", np.hypot(xC - xD, yC - yD) - a5)
    assert_same_angle("theta15 = angle(D→C)", r["theta15"], np.arctan2(yC - yD, xC - xD))
    assert np.all(br * (xD - xC) > 0), "quick-return branch invariant (branch 1: D right of C)"


def check_shaper(p, r, **_):
    r1, r2, r6 = p["r1"], p["r2"], p["r6"]
    th, t3 = r["theta2"], r["theta3"]
    xA, yA, xB, yB = (r[k] for k in ("xA", "yA", "xB", "yB"))
    assert_zero("A on crank", np.hypot(xA - r2 * np.cos(th), yA - r1 - r2 * np.sin(th)))
    assert_zero("A = r3 e^{iθ3} (I, II)", off(xA, yA, 0.0, 0.0, r["r3"], t3))
    assert_zero("B = r4 e^{iθ3}", np.hypot(xB - r["r4"] * np.cos(t3), yB - r["r4"] * np.sin(t3)))
    assert_zero("B on the ram line (III)", yB - (r1 + r6))
    assert_zero("r5 = x of B (IV)", r["r5"] - xB)
    assert np.all((r["r3"] > 0) & (r["r4"] > 0)), "r3, r4 are lengths"


def check_garage_door(p, r, br, bd, **_):
    a1, a2, a3, a4, b2, a5, a6 = (p[k] for k in ("a1", "a2", "a3", "a4", "b2", "a5", "a6"))
    th = r["theta12"]
    xA, yA, xB, yB, xC, yC, xD, yD = (r[k] for k in ("xA", "yA", "xB", "yB", "xC", "yC", "xD", "yD"))
    assert_zero("A on crank", np.hypot(xA - a2 * np.cos(th), yA - a2 * np.sin(th)))
    assert_zero("D on crank line", np.hypot(xD - b2 * np.cos(th), yD - b2 * np.sin(th)))
    assert_zero("|AB| = a3", np.hypot(xB - xA, yB - yA) - a3)
    assert_zero("|B0B| = a4", np.hypot(xB, yB - a1) - a4)
    assert_zero("|BC| = a5", np.hypot(xC - xB, yC - yB) - a5)
    assert_zero("|CD| = a6", np.hypot(xC - xD, yC - yD) - a6)
    assert_same_angle("theta14 = angle(B0→B)", r["theta14"], np.arctan2(yB - a1, xB))
    assert_same_angle("theta13 = angle(A→B)", r["theta13"], np.arctan2(yB - yA, xB - xA))
    assert_same_angle("theta15 = angle(B→C)", r["theta15"], np.arctan2(yC - yB, xC - xB))
    assert_same_angle("theta16 = angle(D→C)", r["theta16"], np.arctan2(yC - yD, xC - xD))
    assert_zero("xs, ys", np.hypot(r["xs"] - xA, r["ys"] - (yA - a1)))
    assert_zero("s", r["s"] - np.hypot(r["xs"], r["ys"]))
    assert_same_angle("phi", r["phi"], np.arctan2(r["ys"], r["xs"]))
    for k in ("mu", "psi", "xi", "gamma"):
        assert_interior(k, r[k])
    assert_same_angle("theta14 = phi − branch·psi", r["theta14"], r["phi"] - br * r["psi"])
    assert_same_angle("theta13 = theta14 − branch·mu", r["theta13"], r["theta14"] - br * r["mu"])
    assert_zero("xs2, ys2", np.hypot(r["xs2"] - (xD - xB), r["ys2"] - (yD - yB)))
    assert_zero("s2", r["s2"] - np.hypot(xD - xB, yD - yB))
    assert_same_angle("eta", r["eta"], np.arctan2(yD - yB, xD - xB))
    assert_same_angle("theta15 = eta − branch_door·xi", r["theta15"], r["eta"] - bd * r["xi"])
    # the seed's closing step θ16 = η + π − γ is branch_door = −1; its mirror for +1
    assert_same_angle("theta16 = eta + bd·(γ − π)", r["theta16"],
                      r["eta"] + bd * (r["gamma"] - math.pi))
    assert np.all(br * cross(xB, yB - a1, xA, yA - a1) > 0), "garage four-bar branch invariant"
    assert np.all(bd * cross(xC - xB, yC - yB, xD - xB, yD - yB) > 0), "door-dyad branch invariant"


def check_tk_fourbar(p, r, br, **_):
    a, b, c, m, n, x3, y3 = (p[k] for k in ("a", "b", "c", "m", "n", "x3", "y3"))
    phi = r["phi"]
    x1, y1, x2, y2, x4, y4 = (r[k] for k in ("x1", "y1", "x2", "y2", "x4", "y4"))
    assert_zero("P1", np.hypot(x1 - a * np.cos(phi), y1 - a * np.sin(phi)))
    assert_zero("P2 = P3 + c e^{iψ}", off(x2, y2, x3, y3, c, r["psi"]))
    assert_zero("|P1P2| = b", np.hypot(x2 - x1, y2 - y1) - b)
    assert_same_angle("theta = angle(P1→P2)", r["theta"], np.arctan2(y2 - y1, x2 - x1))
    # the seed's ptord(sqrt(m²+n²), atan2d(y2−y1, x2−x1) + atan2d(n, m))
    ang = np.arctan2(y2 - y1, x2 - x1) + math.atan2(n, m)
    rho = math.hypot(m, n)
    assert_zero("P4", np.hypot(x4 - x1 - rho * np.cos(ang), y4 - y1 - rho * np.sin(ang)))
    assert_zero("d", r["d"] - rho)
    assert_zero("e", r["e"] - math.hypot(m - b, n))
    assert_zero("xs, ys", np.hypot(r["xs"] - (x1 - x3), r["ys"] - (y1 - y3)))
    assert_zero("s", r["s"] - np.hypot(x1 - x3, y1 - y3))
    assert_same_angle("delta", r["delta"], np.arctan2(y1 - y3, x1 - x3))
    assert_interior("beta", r["beta"])
    assert_interior("mu", r["mu"])
    assert_same_angle("psi = delta − branch·beta", r["psi"], r["delta"] - br * r["beta"])
    assert_same_angle("theta = psi − branch·mu", r["theta"], r["psi"] - br * r["mu"])
    assert np.all(br * cross(x2 - x3, y2 - y3, x1 - x3, y1 - y3) > 0), "tk-fourbar branch invariant"


CHECKS = {
    "fourbar": check_fourbar,
    "slider-crank": check_slider_crank,
    "pump": check_pump,
    "inverted-slider-crank": check_inverted_slider_crank,
    "quick-return": check_quick_return,
    "shaper": check_shaper,
    "garage-door": check_garage_door,
    "tk-fourbar": check_tk_fourbar,
}


def _cases():
    """(mechanism, params, branch, branch_door) on the default dimensions, every branch."""
    for mech in MECHANISMS:
        base = DEFAULTS[mech]
        if mech == "shaper":
            yield pytest.param(mech, dict(base), 1, 1, id=mech)
        elif mech == "garage-door":
            for br in (1, -1):
                for bd in (1, -1):
                    yield pytest.param(mech, dict(base, branch=br, branch_door=bd), br, bd,
                                       id=f"{mech}-b{br}-d{bd}")
        elif mech == "pump":
            for s1 in PUMP_S1:
                for br in (1, -1):
                    yield pytest.param(mech, dict(base, s1=s1, branch=br), br, 1,
                                       id=f"{mech}-s{s1:g}-b{br}")
        else:
            for br in (1, -1):
                yield pytest.param(mech, dict(base, branch=br), br, 1, id=f"{mech}-b{br}")


def test_all_mechanisms_covered():
    assert set(MECHANISMS) == set(CHECKS) == set(DEFAULTS)
    assert len(MECHANISMS) == 8


# The keys of each mechanism's table in docs/mechanisms.md.
KEYS = {
    "fourbar": "theta12 xs ys s phi mu psi theta14 theta13 xA yA xB yB xC yC gamma",
    "slider-crank": "theta12 theta13 s14 xA yA xB yB xC yC",
    "pump": "theta12 xa ya s phi psi theta14 s4 s15 xA yA xB yB xE yE xP yP",
    "inverted-slider-crank": "theta12 xp yp p phi psi s theta14 theta13 xA yA xB yB",
    "quick-return": "theta12 theta14 s43 theta15 s16 xA yA xC yC xD yD time_ratio",
    "shaper": "theta2 r3 theta3 r4 r5 xA yA xB yB",
    "garage-door": ("theta12 xs ys s phi mu psi theta14 theta13 xs2 ys2 s2 eta xi gamma "
                    "theta15 theta16 xA yA xB yB xD yD xC yC"),
    "tk-fourbar": "phi x1 y1 xs ys s delta beta mu psi theta x2 y2 x4 y4 d e",
}


@pytest.mark.parametrize("mech, params, br, bd", list(_cases()))
def test_loop_closure_and_branch(mech, params, br, bd):
    r = solve(mech, params, SWEEP)
    # The doc says every default mechanism closes at every crank angle.
    assert r["assembled"].dtype == bool and r["assembled"].all()
    for key in KEYS[mech].split():
        val = r[key]
        if key in ("gamma", "time_ratio") and mech in ("fourbar", "quick-return"):
            assert isinstance(val, float)
        else:
            assert isinstance(val, np.ndarray) and val.shape == SWEEP.shape, key
    CHECKS[mech](params, r, br=br, bd=bd)


def test_quantity_keys():
    """The keys of the tables in docs/mechanisms.md, and 'assembled', are all there."""
    for mech in MECHANISMS:
        params = dict(DEFAULTS[mech], branch=1.0, branch_door=1.0)
        r = solve(mech, params, [0.0, 10.0])
        assert set(KEYS[mech].split()) | {"assembled"} <= set(r), mech


def test_input_angle_echoed_in_radians():
    deg = np.array([0.0, 30.0, 181.5, 359.9])
    r = solve("shaper", DEFAULTS["shaper"], deg)
    np.testing.assert_array_equal(r["theta2"], np.radians(deg))
    r = solve("tk-fourbar", dict(DEFAULTS["tk-fourbar"], branch=1), deg)
    np.testing.assert_array_equal(r["phi"], np.radians(deg))


# Links from each fixed pivot to a moving joint: (pivot, moving joint's keys, length parameter).
PIVOT_LINKS = {
    "fourbar": [("A0", ("xA", "yA"), "a2"), ("B0", ("xB", "yB"), "a4")],
    "slider-crank": [("A0", ("xA", "yA"), "a2")],
    "pump": [("A0", ("xA", "yA"), "a2"), ("B0", ("xB", "yB"), "a4"), ("B0", ("xE", "yE"), "c4")],
    "inverted-slider-crank": [("A0", ("xA", "yA"), "a2"), ("B0", ("xB", "yB"), "a4")],
    "quick-return": [("A0", ("xA", "yA"), "a2"), ("B0", ("xC", "yC"), "a4")],
    "shaper": [("O2", ("xA", "yA"), "r2")],
    "garage-door": [("A0", ("xA", "yA"), "a2"), ("A0", ("xD", "yD"), "b2"), ("B0", ("xB", "yB"), "a4")],
    "tk-fourbar": [("P0", ("x1", "y1"), "a"), ("P3", ("x2", "y2"), "c")],
}


@pytest.mark.parametrize("mech", MECHANISMS)
def test_pivots_are_the_frame(mech):
    params = dict(DEFAULTS[mech], branch=1.0, branch_door=1.0)
    piv = generic.pivots(description(mech), params)
    r = solve(mech, params, SWEEP)
    for name, (kx, ky), length in PIVOT_LINKS[mech]:
        x0, y0 = piv[name]
        assert_zero(f"|{name}–{kx[1:]}| = {length}",
                    np.hypot(r[kx] - x0, r[ky] - y0) - params[length])


# ------------------------------------------------------------------------------------------
# Published numbers
# ------------------------------------------------------------------------------------------

def test_slider_crank_example_1(published):
    case = published["slider_crank_example_1"]
    inp = dict(case["inputs"])
    angle = inp.pop("theta12")
    r = solve("slider-crank", dict(inp, branch=1), [angle])
    got = {"theta13": math.degrees(r["theta13"][0]) % 360.0, "s14": r["s14"][0],
           "xC": r["xC"][0], "yC": r["yC"][0]}
    for key, want in case["published"].items():
        assert abs(got[key] - want) <= case["tolerance"], (key, got[key], want)


def test_pump_table_example_4(published):
    case = published["pump_table_example_4"]
    rows = np.array(case["rows"], dtype=float)
    for col, s1 in enumerate(case["s1"], start=1):
        r = solve("pump", dict(case["inputs"], s1=s1, branch=1), rows[:, 0])
        assert r["assembled"].all()
        err = np.abs(r["s15"] - rows[:, col])
        assert err.max() <= case["tolerance"], (s1, err.max())


def test_pump_stroke_mathcad_output_3(published):
    case = published["pump_stroke_mathcad_output_3"]
    angles = np.arange(0.0, 360.0, 0.1)
    for item in case["published"]:
        r = solve("pump", dict(case["inputs"], s1=item["s1"], branch=1), angles)
        assert r["assembled"].all()
        stroke = r["s15"].max() - r["s15"].min()
        assert abs(stroke - item["stroke"]) <= case["tolerance"], (item, stroke)


@pytest.mark.parametrize("branch, guess", [(1, "guess_90"), (-1, "guess_270")])
def test_tk_fourbar_both_assembly_modes(published, branch, guess):
    case = published["tk_solver_fourbar"]
    inp = dict(case["inputs"])
    phi = inp.pop("phi")
    r = solve("tk-fourbar", dict(inp, branch=branch), [phi])
    rel = case["rel_tolerance"]
    for key, want in case[guess]["published"].items():
        got = float(r[key][0])
        if key == "psi":
            got = math.degrees(got) % 360.0
        assert abs(got - want) <= rel * abs(want), (key, got, want)


def test_shaper_seed_004(published):
    case = published["shaper_quick_return_seed_004"]
    inp = dict(case["inputs"])
    theta2 = inp.pop("theta2")
    r = solve("shaper", inp, [theta2])
    got = {"r3": r["r3"][0], "r4": r["r4"][0], "r5": r["r5"][0],
           "theta3": math.degrees(r["theta3"][0]) % 360.0}
    for key, want in case["published"].items():
        assert abs(got[key] - want) <= case["tolerance"], (key, got[key], want)


def test_fourbar_textbook_branch():
    """docs: branch 1 (open) at θ12 = 90° has B ≈ (59.0, 54.9)."""
    r = solve("fourbar", dict(DEFAULTS["fourbar"], branch=1), [90.0])
    assert abs(r["xB"][0] - 59.0) < 0.05 and abs(r["yB"][0] - 54.9) < 0.05


# ------------------------------------------------------------------------------------------
# Non-assembly: the mask equals an exact triangle-inequality check
# ------------------------------------------------------------------------------------------

NON_GRASHOF = dict(a1=100.0, a2=60.0, a3=50.0, a4=40.0, b3=30.0, c3=35.0)
SHORT_SLIDER = dict(a1=20.0, a2=50.0, a3=25.0, b3=120.0, gamma3=30.0)


def fourbar_closes(p, deg):
    th = np.radians(deg)
    s = np.hypot(p["a2"] * np.cos(th) - p["a1"], p["a2"] * np.sin(th))
    return (abs(p["a3"] - p["a4"]) <= s) & (s <= p["a3"] + p["a4"])


def slider_closes(p, deg):
    return np.abs(p["a2"] * np.sin(np.radians(deg)) - p["a1"]) <= p["a3"]


def assert_nan_where_open(r, input_key, constants=(), defined=()):
    """Keys that depend on the loop are NaN exactly on open rows; keys fixed by the input angle
    alone (`defined`: the crank pin, |B0A|, a first loop that still closes) stay finite."""
    ok = r["assembled"]
    table = {k for keys in KEYS.values() for k in keys.split()}
    for key, val in r.items():
        if key in ("assembled", input_key, *constants) or key not in table:
            continue
        if key in defined:
            assert np.all(np.isfinite(val)), f"{key} should be defined on every row"
            continue
        assert np.all(np.isnan(val[~ok])), f"{key} not NaN on open rows"
        assert np.all(np.isfinite(val[ok])), f"{key} not finite on closed rows"


def solve_partly_open(mechanism: str, p: dict, closes) -> tuple[dict, dict]:
    """Solve a 1° sweep that closes only on some rows; the assembled mask must be the
    independent distance check `closes`. Returns the solution and its closed rows alone."""
    deg = np.arange(0.0, 360.0 + 1e-9, 1.0)
    r = solve(mechanism, p, deg)
    want = closes(p, deg)
    assert 0 < want.sum() < len(deg)
    np.testing.assert_array_equal(r["assembled"], want)
    ok = r["assembled"]
    return r, {k: (v[ok] if isinstance(v, np.ndarray) else v) for k, v in r.items()}


@pytest.mark.parametrize("br", [1, -1])
def test_non_grashof_fourbar_mask(br):
    p = dict(NON_GRASHOF, branch=br)
    r, closed = solve_partly_open("fourbar", p, fourbar_closes)
    assert_nan_where_open(r, "theta12", ("gamma",), ("xs", "ys", "s", "phi", "xA", "yA"))
    check_fourbar(p, closed, br)


@pytest.mark.parametrize("br", [1, -1])
def test_short_coupler_slider_crank_mask(br):
    p = dict(SHORT_SLIDER, branch=br)
    r, closed = solve_partly_open("slider-crank", p, slider_closes)
    assert_nan_where_open(r, "theta12", defined=("xA", "yA"))
    check_slider_crank(p, closed, br)


def test_inverted_slider_crank_mask():
    """With a4 > a1 − a2 the crank cannot turn fully: open where |B0A| < a4."""
    def closes(p, deg):
        th = np.radians(deg)
        return np.hypot(p["a2"] * np.cos(th) - p["a1"], p["a2"] * np.sin(th)) >= p["a4"]

    p = dict(a1=100.0, a2=40.0, a4=80.0, branch=1)
    r, _ = solve_partly_open("inverted-slider-crank", p, closes)
    assert_nan_where_open(r, "theta12", defined=("xp", "yp", "p", "phi", "xA", "yA"))


def test_quick_return_ram_mask():
    """A ram line too high for the ram link at some rocker angles: open where
    |a4 sinθ14 − b1| > a5."""
    def closes(p, deg):
        th = np.radians(deg)
        t14 = np.arctan2(p["a1"] + p["a2"] * np.sin(th), p["a2"] * np.cos(th))
        return np.abs(p["a4"] * np.sin(t14) - p["b1"]) <= p["a5"]

    p = dict(a1=150.0, a2=60.0, a4=400.0, a5=150.0, b1=520.0, branch=1)
    r, _ = solve_partly_open("quick-return", p, closes)
    assert_nan_where_open(r, "theta12", ("time_ratio",),
                          ("xA", "yA", "s43", "theta14", "xC", "yC"))
    assert math.isnan(r["time_ratio"])


def _fourbar_limit_angles(p):
    """Crank angles (deg, in (0, 180)) where |B0A| = a3 + a4 or |a3 − a4|, by the cosine rule."""
    out = []
    for s in (p["a3"] + p["a4"], abs(p["a3"] - p["a4"])):
        c = (p["a1"] ** 2 + p["a2"] ** 2 - s ** 2) / (2 * p["a1"] * p["a2"])
        if -1 < c < 1:
            out.append(math.degrees(math.acos(c)))
    return out


@pytest.mark.parametrize("br", [1, -1])
@pytest.mark.parametrize("eps", [1e-6, -1e-6])
def test_fourbar_near_limit_positions(br, eps):
    """Rows 1e-6 rad on either side of a limit position are classified correctly, whether reached
    by continuation from a closed row or solved alone."""
    p = dict(NON_GRASHOF, branch=br)
    limits = _fourbar_limit_angles(p)
    assert limits
    for lim in limits:
        for sign in (1, -1):  # the limit at +lim and its mirror at −lim
            target = sign * (lim + math.degrees(eps))
            want = bool(fourbar_closes(p, np.array([target]))[0])
            inside = sign * (lim - 5.0) if fourbar_closes(p, np.array([sign * (lim - 5.0)]))[0] \
                else sign * (lim + 5.0)
            sweep = np.append(np.linspace(inside, target, 6)[:-1], target)
            assert solve("fourbar", p, sweep)["assembled"][-1] == want, (lim, sign, eps)
            assert solve("fourbar", p, [target])["assembled"][0] == want, (lim, sign, eps)


@pytest.mark.parametrize("br", [1, -1])
@pytest.mark.parametrize("eps", [1e-6, -1e-6])
def test_slider_crank_near_limit_positions(br, eps):
    p = dict(SHORT_SLIDER, branch=br)
    for v in ((p["a1"] + p["a3"]) / p["a2"], (p["a1"] - p["a3"]) / p["a2"]):  # a2 sinθ − a1 = ±a3
        lim = math.degrees(math.asin(v))
        for base in (lim, 180.0 - lim):
            target = base + math.degrees(eps)
            want = bool(slider_closes(p, np.array([target]))[0])
            assert solve("slider-crank", p, [target])["assembled"][0] == want, (base, eps)
            for start in (base - 5.0, base + 5.0):
                if slider_closes(p, np.array([start]))[0]:
                    sweep = np.append(np.linspace(start, target, 6)[:-1], target)
                    assert solve("slider-crank", p, sweep)["assembled"][-1] == want, (base, eps)


# ------------------------------------------------------------------------------------------
# Quick-return time ratio
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("params", [
    DEFAULTS["quick-return"],
    dict(a1=200.0, a2=100.0, a4=500.0, a5=150.0, b1=560.0),
    dict(a1=300.0, a2=90.0, a4=600.0, a5=250.0, b1=550.0),
])
@pytest.mark.parametrize("br", [1, -1])
def test_quick_return_time_ratio(params, br):
    r = solve("quick-return", dict(params, branch=br), [0.0, 90.0])
    alpha = math.asin(params["a2"] / params["a1"])
    want = (math.pi + 2 * alpha) / (math.pi - 2 * alpha)
    assert isinstance(r["time_ratio"], float)
    assert abs(r["time_ratio"] - want) <= 1e-6, (r["time_ratio"], want)


def test_quick_return_default_ratio_and_rocker_range():
    """docs: θ14 ∈ [66.4°, 113.6°], ratio 1.710."""
    r = solve("quick-return", dict(DEFAULTS["quick-return"], branch=1), np.arange(0.0, 360.0, 0.05))
    t14 = np.degrees(r["theta14"])
    assert abs(t14.min() - 66.4) < 0.05 and abs(t14.max() - 113.6) < 0.05
    assert round(r["time_ratio"], 3) == 1.710


# ------------------------------------------------------------------------------------------
# API errors
# ------------------------------------------------------------------------------------------

def test_missing_parameter():
    p = dict(DEFAULTS["fourbar"])  # no branch
    with pytest.raises(ValueError):
        solve("fourbar", p, [0.0])
    p = dict(DEFAULTS["garage-door"], branch=1)  # no branch_door
    with pytest.raises(ValueError):
        solve("garage-door", p, [0.0])
