"""The reference's triad (a class-III group: a ternary link held by three binary links, its six
distances solved together by Newton, continued from row to row from the sketch) against a third
party: scipy.optimize.root (MINPACK's hybrid method) on the same linkage written its own way,
in the binary links' three angles, continued the same way. Random triads driven by a crank,
each built from a random assembly at θ = 0 (so that position is known exactly), sketched 1 %
of its shortest link off it.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from scipy.optimize import root

from conftest import examples
from linkbook.check.reference import solve
from linkbook.check.reference.group import Bar, Turn, solve_group

STEP = 3.0            # degrees between rows
POINT = st.tuples(st.floats(-60, 60), st.floats(-60, 60))


def _description(crank, pivots, joints, sketch):
    """A crank A0–A (A0 at the origin) and a triad D, E, F on the pivots A, B0, C0, its lengths
    those of the assembly `joints` at θ = 0."""
    a = (crank, 0.0)
    ends = [a, *pivots]
    lengths = [math.dist(p, j) for p, j in zip(ends, joints)]
    sides = [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
    return {"input": {"key": "t", "symbol": "t"},
            "ground": {"A0": [0.0, 0.0], "B0": list(pivots[0]), "C0": list(pivots[1])},
            "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": crank},
                      {"type": "triad", "points": ["D", "E", "F"], "pivots": ["A", "B0", "C0"],
                       "lengths": lengths, "sides": sides,
                       "sketch": [list(p) for p in sketch]}]}, lengths, sides


def _scipy_sweep(crank, pivots, lengths, sides, sketch, angles):
    """The joints per row by scipy.optimize.root on the binary links' angles φ1..φ3 (each joint
    on its link's circle; residuals: the ternary's sides), each row from the row above's root
    (the first from the sketch's angles); NaN from the first row it does not solve on."""
    def joints(phi, a):
        return [(p[0] + r * math.cos(f), p[1] + r * math.sin(f))
                for p, r, f in zip([a, *pivots], lengths, phi)]

    def sense(js):
        (x0, y0), (x1, y1), (x2, y2) = js
        return (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)

    a0 = (crank, 0.0)
    phi = [math.atan2(s[1] - p[1], s[0] - p[0]) for p, s in zip([a0, *pivots], sketch)]
    want = math.copysign(1.0, sense(sketch))
    out = np.full((len(angles), 6), math.nan)
    for i, t in enumerate(np.radians(angles)):
        a = (crank * math.cos(t), crank * math.sin(t))

        def residuals(f):
            js = joints(f, a)
            return [math.dist(js[k], js[(k + 1) % 3]) - sides[k] for k in range(3)]
        # judged by its residual: at xtol 1e-15 MINPACK reports that it cannot improve
        sol = root(residuals, phi, method="hybr", options={"xtol": 1e-15})
        js = joints(sol.x, a)
        if max(map(abs, residuals(sol.x))) > 1e-12 * sum(sides) or want * sense(js) <= 0:
            break
        out[i] = [c for j in js for c in j]
        phi = list(sol.x)
    return out


def _reference(description, angles):
    out = solve(description, {}, angles)
    return np.column_stack([out[k] for k in ("xD", "yD", "xE", "yE", "xF", "yF")])


def conditioning(ends, joints) -> float:
    """|det| over the product of the rows' lengths of the six distances' Jacobian at an
    assembly (0 at a dead centre, 1 at best), in the joints' coordinates."""
    rows = []
    for k, (p, j) in enumerate(zip(ends, joints)):
        line = np.zeros(6)
        line[2 * k:2 * k + 2] = np.subtract(j, p)
        rows.append(line)
    for k in range(3):
        m = (k + 1) % 3
        line = np.zeros(6)
        line[2 * k:2 * k + 2] = np.subtract(joints[k], joints[m])
        line[2 * m:2 * m + 2] = -line[2 * k:2 * k + 2]
        rows.append(line)
    jac = np.array(rows)
    return abs(np.linalg.det(jac)) / np.prod(np.linalg.norm(jac, axis=1))


@settings(max_examples=examples(100))
@given(crank=st.floats(5, 25), b0=POINT, c0=POINT, d=POINT, e=POINT, f=POINT,
       off=st.lists(st.floats(-1, 1), min_size=6, max_size=6))
def test_the_reference_agrees_with_scipy_on_random_triads(crank, b0, c0, d, e, f, off):
    joints = [d, e, f]
    ends = [(crank, 0.0), b0, c0]
    # a linkage one draws: no link shorter than a tenth of the box, pivots apart, and the
    # assembly at θ = 0 away from a dead centre
    assume(min(math.dist(p, j) for p, j in zip(ends, joints)) >= 6)
    assume(min(math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)) >= 6)
    assume(min(math.dist(ends[k], ends[(k + 1) % 3]) for k in range(3)) >= 6)
    assume(conditioning(ends, joints) > 0.05)
    shortest = min([math.dist(p, j) for p, j in zip(ends, joints)]
                   + [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)])
    sketch = [(j[0] + 0.01 * shortest * off[2 * k], j[1] + 0.01 * shortest * off[2 * k + 1])
              for k, j in enumerate(joints)]
    description, lengths, sides = _description(crank, (b0, c0), joints, sketch)
    angles = np.arange(0.0, 360.0 + STEP / 2, STEP)
    ours = _reference(description, angles)
    size = crank + sum(abs(c) for c in (*b0, *c0)) + sum(lengths) + sum(sides)
    # the first row: the assembly the lengths were made from, found from the sketch
    assert np.allclose(ours[0], [c for j in joints for c in j], rtol=0, atol=1e-9 * size)
    theirs = _scipy_sweep(crank, (b0, c0), lengths, sides, sketch, angles)
    # the rows from θ = 0 on where both solve and the group is away from a dead centre: near
    # one, positions are good only to √ε and two continuations may part on different
    # branches, so the comparison stops at the first row that comes within 1e-2 of one
    well = [np.isfinite(r).all() and np.isfinite(q).all() and conditioning(
        [(crank * math.cos(t), crank * math.sin(t)), b0, c0],
        [tuple(r[0:2]), tuple(r[2:4]), tuple(r[4:6])]) > 1e-2
        for t, r, q in zip(np.radians(angles), ours, theirs)]
    rows = np.cumprod(well).astype(bool)
    assert rows[0]
    np.testing.assert_allclose(ours[rows], theirs[rows], rtol=0, atol=1e-9 * size)


def test_a_triad_that_cannot_close_is_nan_from_there_and_restarts_from_the_sketch():
    """Lengths that close only near θ = 0: the rows away from it are NaN, and a row where the
    crank has come back near the sketch closes again, on the sketch's assembly."""
    joints = [(35.0, 25.0), (60.0, 30.0), (45.0, 45.0)]
    description, _, _ = _description(20.0, ((80.0, 0.0), (10.0, 70.0)), joints, joints)
    ours = _reference(description, np.array([0.0, 1.0, 180.0, 359.0, 0.0]))
    assert np.isfinite(ours[[0, 1, 3, 4]]).all() and np.isnan(ours[2]).all()
    np.testing.assert_allclose(ours[4], [c for j in joints for c in j], atol=1e-9)


def test_a_root_of_the_other_turning_sense_is_no_assembly():
    """The six distances are met by the ternary link's mirror image too: the group keeps the
    turning sense of its link. Asked for the clockwise sense, the counter-clockwise root the
    sketch leads to is refused (NaN); asked for the counter-clockwise one, it is the root."""
    joints = [(35.0, 25.0), (60.0, 30.0), (45.0, 45.0)]
    ends = [(20.0, 0.0), (80.0, 0.0), (10.0, 70.0)]
    pivots = [(np.array([x]), np.array([y])) for x, y in ends]
    bars = [Bar(p, k, math.dist(e, j)) for k, (p, e, j) in enumerate(zip(pivots, ends, joints))]
    bars += [Bar(k, (k + 1) % 3, math.dist(joints[k], joints[(k + 1) % 3])) for k in range(3)]
    sketch = [c for j in joints for c in j]
    for sign, found in ((-1.0, False), (1.0, True)):
        xy = solve_group(1, 3, bars, sketch, [Turn(0, 1, 2, sign)], 300.0, 1e-9 * 300.0)
        assert np.isfinite(xy[2][0][0]) == found


def test_the_rates_agree_with_finite_differences_of_the_positions():
    """Velocities and accelerations of the joints (implicit differentiation of the six
    distances) against central differences of the reference's own positions."""
    joints = [(35.0, 25.0), (60.0, 30.0), (45.0, 45.0)]
    description, _, _ = _description(20.0, ((80.0, 0.0), (10.0, 70.0)), joints, joints)
    description["steps"][1]["iterations"] = 20     # the row at 80° follows the one at 0°
    h, t, speed = 1e-3, 80.0, 10.0       # degrees, degrees, rad/s
    rows = solve(description, {"omega_in": speed, "alpha_in": 0.0},
                 np.array([0.0, t - h, t, t + h]))
    dt = math.radians(h) / speed
    for n in ("D", "E", "F"):
        for c in ("x", "y"):
            x = rows[f"{c}{n}"][1:]
            assert np.isfinite(x).all()
            v = (x[2] - x[0]) / (2 * dt)
            a = (x[2] - 2 * x[1] + x[0]) / (dt * dt)
            assert rows[f"v{c}_{n}"][2] == pytest.approx(v, rel=1e-6, abs=1e-6)
            assert rows[f"a{c}_{n}"][2] == pytest.approx(a, rel=1e-4, abs=1e-3)


def test_the_book_methods_jacobian_is_the_closed_forms():
    """One iteration of the book's method (triad_iterations.iteration: its two Jacobian
    columns, ∂/∂φ and ∂/∂θ, seeded in one pass of Taylor arithmetic) against the closed forms
    written out by hand here: with D = A + a(cos φ, sin φ), E = D + s(cos θ, sin θ) and F = D +
    u(cos θ, sin θ) + v(−sin θ, cos θ), J11 = (D − A)×(E − B)/b, J12 = (E − D)×(E − B)/b,
    J21 = (D − A)×(F − C)/c, J22 = (F − D)×(F − C)/c; the residuals (|E − B|² − b²)/2b and
    (|F − C|² − c²)/2c; the correction J⁻¹r."""
    from linkbook.check.reference.steps.triad_iterations import iteration
    rng = np.random.default_rng(7)
    n = 40
    phi, theta = rng.uniform(-math.pi, math.pi, (2, n))
    pivots = [tuple(rng.uniform(-50, 50, (2, n))) for _ in range(3)]
    lengths, sides = list(rng.uniform(10, 60, 3)), list(rng.uniform(10, 60, 3))
    frame = (float(rng.uniform(-20, 40)), float(rng.uniform(5, 40)))
    got = iteration(phi, theta, pivots, lengths, sides, frame)

    (ax, ay), (bx, by), (cx, cy) = pivots
    a, b, c, s = lengths[0], lengths[1], lengths[2], sides[0]
    (u, v), cos, sin = frame, np.cos(theta), np.sin(theta)
    dx, dy = ax + a * np.cos(phi), ay + a * np.sin(phi)
    ex, ey = dx + s * cos, dy + s * sin
    fx, fy = dx + u * cos - v * sin, dy + u * sin + v * cos

    def cross(px, py, qx, qy):
        return px * qy - py * qx
    want = {"r1": ((ex - bx) ** 2 + (ey - by) ** 2 - b * b) / (2 * b),
            "r2": ((fx - cx) ** 2 + (fy - cy) ** 2 - c * c) / (2 * c),
            "J11": cross(dx - ax, dy - ay, ex - bx, ey - by) / b,
            "J12": cross(ex - dx, ey - dy, ex - bx, ey - by) / b,
            "J21": cross(dx - ax, dy - ay, fx - cx, fy - cy) / c,
            "J22": cross(fx - dx, fy - dy, fx - cx, fy - cy) / c}
    scale = 100.0
    for key, value in want.items():
        assert np.allclose(got[key], value, rtol=1e-12, atol=1e-12 * scale), key
    det = want["J11"] * want["J22"] - want["J12"] * want["J21"]
    dphi = (want["J22"] * want["r1"] - want["J12"] * want["r2"]) / det
    dth = (want["J11"] * want["r2"] - want["J21"] * want["r1"]) / det
    assert np.allclose(got["dphi"], dphi, rtol=1e-9) and np.allclose(got["dth"], dth, rtol=1e-9)
