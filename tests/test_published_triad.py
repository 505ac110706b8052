"""Published poses of a class-III group: T. Sauer's planar Stewart platform (tests/data/
published.toml, sauer_stewart_platform). With its struts' lengths given, the platform is a triad:
a triangle (the ternary link) whose three vertices are held by three struts (the binary links)
to three base points. The reference's triad and the book's triad step each find the poses the
sources print, every assembly chosen by a sketch near it (the printed pose rounded to 0.1).

The source's base point (0, 0) is the end A of a crank of length 1 from A0 = (−1, 0) at θ12 = 0
(the triad step's first pivot is a moving point); its other two base points are ground points.
The source's vertex 1 is D, vertex 2 is E, vertex 3 is F, and its θ (the angle of side 1→2) is
the triad's theta_DE.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import checks_of, published
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.language import templates

CASE = published()["sauer_stewart_platform"]
ACTIVITIES = ("activity_4", "activity_5")
ITERATIONS = 8          # from a sketch 0.05 off in θ, x and y; converged rows need fewer


def _sauer_xy(theta: float, i: dict) -> tuple[float, float]:
    """The source's vertex 1 for a given θ: with vertices 2 and 3 placed from (x, y) and θ, the
    differences of the struts' squared lengths are linear in x and y (Sauer's x = N1/D,
    y = N2/D), solved here as he writes them. Its poses are the θ where this point is also p1
    from the origin."""
    gamma = math.radians(i["gamma"])
    a2, b2 = i["L3"] * math.cos(theta) - i["x1"], i["L3"] * math.sin(theta)
    a3 = i["L2"] * math.cos(theta + gamma) - i["x2"]
    b3 = i["L2"] * math.sin(theta + gamma) - i["y2"]
    u = i["p2"] ** 2 - i["p1"] ** 2 - a2 ** 2 - b2 ** 2
    v = i["p3"] ** 2 - i["p1"] ** 2 - a3 ** 2 - b3 ** 2
    d = 2.0 * (a2 * b3 - b2 * a3)
    return (b3 * u - b2 * v) / d, (-a3 * u + a2 * v) / d


def _sketch(i: dict, pose) -> list[tuple[float, float]]:
    """The vertices of a printed pose [θ, x, y] rounded to 0.1: near it, not on it."""
    theta, x, y = (round(c, 1) for c in pose)
    gamma = math.radians(i["gamma"])
    return [(x, y), (x + i["L3"] * math.cos(theta), y + i["L3"] * math.sin(theta)),
            (x + i["L2"] * math.cos(theta + gamma), y + i["L2"] * math.sin(theta + gamma))]


def _param(value: float, label: str, kind: str | None = None) -> dict:
    return {"label": label, "unit": "mm", "value": float(value)} | ({"kind": kind} if kind else {})


def _data(i: dict, sketch) -> dict:
    """The platform as a template: the triad D, E, F on the pivots A, B0, C0, one row at
    θ12 = 0 (and one at 1°), the current position there too."""
    (dx, dy), (ex, ey), (fx, fy) = sketch
    lengths = {k: _param(i[k], k) for k in ("L1", "L2", "L3", "p1", "p2", "p3")}
    offsets = {k: _param(v, k, "offset") for k, v in (
        ("x1", i["x1"]), ("x2", i["x2"]), ("y2", i["y2"]), ("sxD", dx), ("syD", dy),
        ("sxE", ex), ("syE", ey), ("sxF", fx), ("syF", fy))}
    return {"title": "Sauer's planar Stewart platform", "source": "tests/data/published.toml",
            "length_unit": "mm", "sweep": {"start": 0, "stop": 1, "step": 1, "position": 0},
            "parameters": lengths | offsets,
            "mechanism": {
                "input": {"key": "theta12", "symbol": "θ12"},
                "ground": {"A0": [-1, 0], "B0": ["x1", 0], "C0": ["x2", "y2"]},
                "links": [["A0", "A"], ["A", "D"], ["D", "E", "F", "D"], ["B0", "E"],
                          ["C0", "F"]],
                "steps": [{"type": "crank", "point": "A", "pivot": "A0", "length": 1},
                          {"type": "triad", "points": ["D", "E", "F"],
                           "pivots": ["A", "B0", "C0"], "lengths": ["p1", "p2", "p3"],
                           "sides": ["L3", "L1", "L2"],
                           "sketch": [["sxD", "syD"], ["sxE", "syE"], ["sxF", "syF"]],
                           "iterations": ITERATIONS}]}}


def _size(i: dict) -> float:
    return sum(abs(i[k]) for k in ("x1", "x2", "y2", "L1", "L2", "L3", "p1", "p2", "p3"))


def _reference(data: dict) -> tuple[float, float, float]:
    """θ, x and y of the pose the reference's triad reaches from the sketch at θ12 = 0."""
    params = {k: v["value"] for k, v in data["parameters"].items()}
    out = solve(data["mechanism"], params, np.array([0.0]))
    return out["theta_DE"][0], out["xD"][0], out["yD"][0]


def _book(data: dict) -> dict[str, tuple[float, float, float]]:
    """θ, x and y in the book: the current position (from the sketch) and the sweep's first row
    (from the sketch too); and whether verify found every formula cell right."""
    b, values = builder.make(templates.from_data("sauer-platform", data))
    now, sweep = b.meta["position"]["cells"], b.meta["sweep"]["columns"]
    first = b.meta["sweep"]["rows"][0]
    keys = ("theta_DE", "xD", "yD")
    bad = [(c.name, c.mismatches[:1]) for c in checks_of(b, values) if not c.ok]
    return {"now": tuple(values[("Mechanism", now[k])] for k in keys),
            "row": tuple(values[("Sweep", f"{sweep[k]}{first}")] for k in keys),
            "verify": bad}


@pytest.fixture(scope="module")
def printed():
    """Every printed pose with the reference's pose and the book's, each from its own sketch."""
    out = []
    for name in ACTIVITIES:
        i = CASE[name]["inputs"]
        for pose in CASE[name]["poses"]:
            data = _data(i, _sketch(i, pose))
            out.append((name, pose, _reference(data), _book(data)))
    return out


def test_the_test_case_has_its_two_poses_at_plus_and_minus_a_quarter_turn():
    """Figure 1.15's platform: θ = −π/4 and θ = π/4, exactly, from sketches near each."""
    case = CASE["test_case"]
    i = case["inputs"]
    for theta in case["thetas"]:
        x, y = _sauer_xy(theta, i)
        data = _data(i, _sketch(i, (theta, x, y)))
        got, (x_ref, y_ref) = _reference(data), (x, y)
        assert got[0] == pytest.approx(theta, abs=case["tolerance"])
        assert got[1:] == pytest.approx((x_ref, y_ref), abs=1e-12 * _size(i))
        book = _book(data)
        assert not book["verify"], book["verify"]
        for where in ("now", "row"):
            assert book[where][0] == pytest.approx(theta, abs=case["tolerance"])


@pytest.mark.parametrize("name", ACTIVITIES)
def test_the_reference_reproduces_every_printed_pose(printed, name):
    """θ to its printed digits. x and y: the source's own formula (vertex 1 for a given θ)
    agrees with the reference at the reference's θ to round-off; the printed x, y are that
    formula at the printed θ (see published.toml), so each is allowed what the formula moves
    between the two θ, plus half its last digit."""
    case = CASE[name]
    i, tol = case["inputs"], case["tolerance"]
    rows = [(pose, ref) for n, pose, ref, _ in printed if n == name]
    assert len(rows) == len(case["poses"]) == {"activity_4": 4, "activity_5": 6}[name]
    for (theta_p, x_p, y_p), (theta, x, y) in rows:
        assert abs(theta - theta_p) <= tol, (theta_p, theta)
        assert _sauer_xy(theta, i) == pytest.approx((x, y), abs=1e-12 * _size(i))
        moved = np.subtract(_sauer_xy(theta_p, i), _sauer_xy(theta, i))
        assert abs(x - x_p) <= tol + abs(moved[0]), (theta_p, x, x_p)
        assert abs(y - y_p) <= tol + abs(moved[1]), (theta_p, y, y_p)


@pytest.mark.parametrize("name", ACTIVITIES)
def test_a_book_at_each_printed_pose_agrees_with_the_reference(printed, name):
    """Each pose as a book: its current position and its sweep's first row (the book's Newton
    from the sketch, in its cells) are the reference's pose, and verify finds every formula cell
    of the book right."""
    size = _size(CASE[name]["inputs"])
    for n, pose, ref, book in printed:
        if n != name:
            continue
        assert not book["verify"], (pose, book["verify"])
        for where in ("now", "row"):
            assert book[where] == pytest.approx(ref, abs=1e-9 * size), (pose, where)
            assert abs(book[where][0] - pose[0]) <= CASE[name]["tolerance"], (pose, where)


def test_six_poses_where_the_source_says_six():
    """Activity 5's own data, p2 = 7: "there will be six poses". From sketches near the six
    printed for p2 = 6.99, the reference reaches six poses at p2 = 7, each nearest (in θ) to
    the printed pose it was sketched from: six different assemblies, none reached twice."""
    i = dict(CASE["activity_5"]["inputs"], p2=7.0)
    printed = [pose[0] for pose in CASE["activity_5"]["poses"]]
    poses = [_reference(_data(i, _sketch(i, pose))) for pose in CASE["activity_5"]["poses"]]
    for theta, x, y in poses:       # a pose by the source's equations: vertex 1 p1 from (0, 0)
        assert _sauer_xy(theta, i) == pytest.approx((x, y), abs=1e-12 * _size(i))
        assert math.hypot(x, y) == pytest.approx(i["p1"], abs=1e-12 * _size(i))
    found = [theta for theta, _, _ in poses]
    assert min(np.diff(sorted(found))) > 1e-3, found
    for k, theta in enumerate(found):
        assert int(np.argmin(np.abs(np.subtract(printed, theta)))) == k, (k, theta, printed)
