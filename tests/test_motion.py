"""Velocity and acceleration: a case derived by hand, the reference against finite differences
of its own positions, and the workbook's Motion sheet against the reference (the property tests
cover random dimensions and speeds; test_office covers LibreOffice)."""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest

from conftest import built, checks_of
from linkbook.check import reference as generic
from linkbook.language import templates


def test_offset_slider_crank_by_hand():
    """Example 1 (a1 = 20 offset, a2 = 50 crank, a3 = 250 coupler) at θ12 = 60°, ω12 = 10 rad/s,
    α12 = 0. The loop A = B + a3·e^{iθ13}, B = (s14, a1):
        (1)  a2 cos θ12 = s14 + a3 cos θ13
        (2)  a2 sin θ12 = a1 + a3 sin θ13
    (2) gives sin θ13 = (a2 sin θ12 − a1)/a3, θ13 = 180° − asin(…) (B ahead of A).
    Differentiated: (2) a2 ω12 cos θ12 = a3 ω13 cos θ13 → ω13 = a2 ω12 cos θ12 / (a3 cos θ13);
                    (1) −a2 ω12 sin θ12 = ṡ14 − a3 ω13 sin θ13 → ṡ14 = −a2 ω12 sin θ12 + a3 ω13 sin θ13.
    Once more (α12 = 0):
        (2) −a2 ω12² sin θ12 = a3 α13 cos θ13 − a3 ω13² sin θ13
        (1) −a2 ω12² cos θ12 = s̈14 − a3 α13 sin θ13 − a3 ω13² cos θ13."""
    a1, a2, a3, w12 = 20.0, 50.0, 250.0, 10.0
    t12 = math.radians(60.0)
    t13 = math.pi - math.asin((a2 * math.sin(t12) - a1) / a3)
    w13 = a2 * w12 * math.cos(t12) / (a3 * math.cos(t13))
    s_dot = -a2 * w12 * math.sin(t12) + a3 * w13 * math.sin(t13)
    a13 = (a3 * w13 ** 2 * math.sin(t13) - a2 * w12 ** 2 * math.sin(t12)) / (a3 * math.cos(t13))
    s_ddot = -a2 * w12 ** 2 * math.cos(t12) + a3 * a13 * math.sin(t13) + a3 * w13 ** 2 * math.cos(t13)
    assert math.degrees(t13) == pytest.approx(174.652, abs=5e-4)      # the published 174.7
    b, values = built("slider-crank", ("omega_in=10", "alpha_in=0"), 5)
    motion = b.meta["motion"]
    row = next(r for r in range(*motion["rows"]) if b.workbook["Motion"][f"A{r}"].value == "='Sweep'!A17")
    got = {k: values[("Motion", f"{motion['columns'][k]}{row}")]
           for k in ("omega_theta13", "v_s14", "alpha_theta13", "acc_s14")}
    assert got["omega_theta13"] == pytest.approx(w13, rel=1e-12)      # −1.00437 rad/s
    assert got["v_s14"] == pytest.approx(s_dot, rel=1e-12)            # −456.416 mm/s
    assert got["alpha_theta13"] == pytest.approx(a13, rel=1e-11)      # 17.3018 rad/s²
    assert got["acc_s14"] == pytest.approx(s_ddot, rel=1e-11)         # −2347.94 mm/s²


def _richardson(f, x: float, h: float, order: int) -> np.ndarray:
    """The first or second derivative of f at x by central differences, Richardson-extrapolated
    (error O(h⁴))."""
    def central(step):
        if order == 1:
            return (f(x + step) - f(x - step)) / (2 * step)
        return (f(x + step) - 2 * f(x) + f(x - step)) / step ** 2
    return (4 * central(h / 2) - central(h)) / 3


@pytest.mark.parametrize("name", sorted(p.stem for p in templates.bundled()))
def test_reference_motion_is_the_derivative_of_its_positions(name):
    """On every bundled template, at five inputs: the reference's velocities (ω = 1, α = 0) are
    the first derivatives of its own positions in the input, its accelerations the second; with
    ω = 0, α = 1 the accelerations are the first derivatives."""
    t = templates.load(name)
    mech = t.mechanism
    speed, accel = ("omega_in", "alpha_in") if mech.input_is_angle else ("v_in", "a_in")
    params = {p.symbol: p.value for p in t.parameters}
    unit = math.degrees(1.0) if mech.input_is_angle else 1.0    # input units per unit of rate
    h = 1e-3 if mech.input_is_angle else 1e-3 * max(abs(v) for v in params.values())
    span = t.sweep.stop - t.sweep.start
    inputs = [t.sweep.start + span * f for f in (0.13, 0.31, 0.52, 0.71, 0.89)]
    compared = 0
    for x in inputs:
        @lru_cache(maxsize=None)
        def positions(u):
            """The reference at input u (in units of rate): each key's differences ask it at
            the same inputs, solved once."""
            return generic.solve(mech.description, params, np.array([u * unit]))
        base = positions(x / unit)
        if not base["assembled"][0]:
            continue
        moving = generic.solve(mech.description, {**params, speed: 1.0, accel: 0.0},
                               np.array([x]))
        pushing = generic.solve(mech.description, {**params, speed: 0.0, accel: 1.0},
                                np.array([x]))
        for key in [k for k in moving if k.startswith(("vx_", "vy_", "omega_", "v_"))]:
            if key.startswith(("vx_", "vy_")):
                point, axis = key[3:], 0 if key.startswith("vx_") else 1
                value = lambda u, point=point, axis=axis: positions(u)["points"][point][axis]
                acc_key = ("ax_" if axis == 0 else "ay_") + point
            else:
                pre = "omega_" if key.startswith("omega_") else "v_"
                source = key[len(pre):]
                if source not in base:
                    continue
                value = lambda u, source=source: np.unwrap(np.asarray(positions(u)[source], float))
                acc_key = ("alpha_" if pre == "omega_" else "acc_") + source
            first = _richardson(value, x / unit, h / unit, 1)[0]
            second = _richardson(value, x / unit, 20 * h / unit, 2)[0]
            scale = max(1.0, abs(first), abs(second))
            assert moving[key][0] == pytest.approx(first, abs=1e-6 * scale), (name, x, key)
            assert moving[acc_key][0] == pytest.approx(second, abs=2e-5 * scale), (name, x, acc_key)
            assert pushing[acc_key][0] == pytest.approx(first, abs=1e-6 * scale), (name, x, acc_key)
            compared += 1
    assert compared >= 10


def test_motion_cells_are_all_checked_and_a_wrong_sign_is_caught():
    """verify compares every Motion cell; a deliberate bug (ω13 with the wrong sign) fails."""
    b, values = built("fourbar")
    checks = checks_of(b, values)
    motion = [c for c in checks if c.block in ("Motion", "motion now")]
    assert sum(c.cells for c in motion) >= len(b.meta["motion"]["columns"]) * 37
    assert all(c.ok for c in motion)
    letter = b.meta["motion"]["columns"]["omega_theta13"]
    r0, r1 = b.meta["motion"]["rows"]
    broken = dict(values)
    for r in range(r0, r1 + 1):
        v = broken[("Motion", f"{letter}{r}")]
        broken[("Motion", f"{letter}{r}")] = -v if isinstance(v, float) else v
    bad = [c for c in checks_of(b, broken) if not c.ok]
    assert [c.name for c in bad] == ["omega_theta13"]


def test_a_dead_centre_is_na_not_div0():
    """Ground 10, crank 20, coupler 4, rocker 6: at θ12 = 0 the crank pin A = (20, 0) is 10 from
    B0 = (10, 0), coupler and rocker lie stretched along the x axis (ψ = acos(1) = 0, θ14 = 0,
    B = (16, 0), all exact) and the dyad's determinant u_q × u_p is exactly zero. The positions
    there are numbers, every rate that divides by the determinant is #N/A, and nothing in the
    book is #DIV/0!. (Trigonometry rarely lands on an exact zero: elsewhere a determinant near
    zero gives large, finite rates, bounded by verify's forward-error allowance.)"""
    b, values = built("fourbar", ("a1=10", "a2=20", "a3=4", "a4=6", "b3=3", "c3=2"), 10)
    motion = b.meta["motion"]
    row = motion["rows"][0]                      # θ12 = 0
    assert b.workbook["Motion"][f"A{row}"].value == "='Sweep'!A5"
    assert isinstance(values[("Sweep", f"{b.meta['sweep']['columns']['xB']}5")], float)
    for key in ("omega_theta13", "omega_theta14", "alpha_theta13", "vx_B", "ax_B"):
        v = values[("Motion", f"{motion['columns'][key]}{row}")]
        assert verify_code(v) == "#N/A", (key, v)
    assert not any(verify_code(v) == "#DIV/0!" for v in values.values())
    # The reference's own position there is good to round-off only, its Jacobian singular to
    # within 1e-7: it marks the row a dead centre, where #N/A (or a number) is the honest answer.
    checks = checks_of(b, values)
    assert all(c.ok for c in checks), [(c.name, c.mismatches[:1]) for c in checks if not c.ok]
    assert sum(c.dead_centre for c in checks   # θ12 = 0° and 360°
               if c.name == "omega_theta13" and c.block == "Motion") == 2


def verify_code(value):
    from linkbook.engine import evaluator as engine
    return engine.error_code(value) if engine.is_error(value) else None
