"""The triad book's rates are the derivatives of its own positions (issue 41: "rates agree with
finite differences of the positions"): the bundled template (templates/triad-sixbar.toml)
built on five rows h apart at three stretches of the turn; every velocity and angular velocity
on its Motion sheet against central differences of the Sweep sheet's positions, every
acceleration against the second differences (and the first, for the crank's α).

The bound knows its step: a central difference's error is c·h² + O(h⁴), so the difference
between the steps h and 2h is 3·c·h², three times the error at h, allowed in full; rounding in
positions good to a few ulps adds (ulps · size)/h for a first difference, /h² for a second.
"""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from conftest import ROOT
from linkbook.book import builder
from linkbook.language import templates

TEMPLATE = ROOT / "templates" / "triad-sixbar.toml"
STEP = 0.05                     # degrees between the rows
OMEGA, ALPHA = 1.3, 0.7         # the crank's ω (rad/s) and α (rad/s²)
ULPS = 64 * np.finfo(float).eps


def _book(centre: float):
    """The example on five rows, STEP apart around `centre` (the first row from the sketch, so
    more iterations than the example's four)."""
    data = tomllib.loads(TEMPLATE.read_text(encoding="utf-8"))
    data["mechanism"].pop("charts")
    data["mechanism"]["steps"][1]["iterations"] = 12
    data["parameters"]["omega_in"] = {"label": "crank speed", "unit": "rad/s", "value": OMEGA}
    data["parameters"]["alpha_in"] = {"label": "crank acceleration", "unit": "rad/s²",
                                      "value": ALPHA}
    data["sweep"] = {"start": centre - 2 * STEP, "stop": centre + 2 * STEP, "step": STEP,
                     "position": centre}
    return builder.make(templates.from_data("triad", data))


def _rows(b, values, sheet: str, key: str) -> np.ndarray:
    meta = b.meta["sweep"] if sheet == "Sweep" else b.meta["motion"]
    first, last = meta["rows"]
    return np.array([values[(sheet, f"{meta['columns'][key]}{r}")]
                     for r in range(first, last + 1)], dtype=float)


def _differences(f: np.ndarray, h: float) -> dict[str, float]:
    """First and second central differences at the middle row at steps h and 2h, and each
    one's bound at h: the steps' disagreement plus rounding."""
    scale = ULPS * max(1.0, float(np.max(np.abs(f))))
    d1, d1_wide = (f[3] - f[1]) / (2 * h), (f[4] - f[0]) / (4 * h)
    d2, d2_wide = (f[3] - 2 * f[2] + f[1]) / h ** 2, (f[4] - 2 * f[2] + f[0]) / (4 * h ** 2)
    return {"d1": d1, "bound1": abs(d1_wide - d1) + scale / h,
            "d2": d2, "bound2": abs(d2_wide - d2) + 4 * scale / h ** 2}


def _pairs(motion_columns) -> list[tuple[str, str, str]]:
    """(position on Sweep, its velocity, its acceleration on Motion): the points' x and y, the
    links' angles (radians)."""
    out = []
    for key in motion_columns:
        if key.startswith(("vx_", "vy_")):
            axis, point = key[1], key[3:]
            out.append((f"{axis}{point}", key, f"a{axis}_{point}"))
        elif key.startswith("omega_"):
            out.append((key[len("omega_"):], key, "alpha_" + key[len("omega_"):]))
    return out


@pytest.mark.parametrize("centre", [30.0, 150.0, 270.0])
def test_the_books_rates_are_the_differences_of_its_positions(centre):
    b, values = _book(centre)
    angles = _rows(b, values, "Sweep", "theta12")          # radians
    h = math.radians(STEP)
    assert np.allclose(np.diff(angles), h, rtol=1e-9, atol=0)
    pairs = _pairs(b.meta["motion"]["columns"])
    assert {"theta_D", "theta_DE", "xE", "yF"} <= {p for p, _, _ in pairs}
    for position, velocity, acceleration in pairs:
        f = _rows(b, values, "Sweep", position)
        assert np.isfinite(f).all(), (centre, position)
        if position.startswith("theta"):
            f = np.unwrap(f)
        d = _differences(f, h)
        v = _rows(b, values, "Motion", velocity)[2]
        a = _rows(b, values, "Motion", acceleration)[2]
        assert abs(v - OMEGA * d["d1"]) <= OMEGA * d["bound1"], (centre, velocity, v, d)
        want = OMEGA ** 2 * d["d2"] + ALPHA * d["d1"]
        allowed = OMEGA ** 2 * d["bound2"] + ALPHA * d["bound1"]
        assert abs(a - want) <= allowed, (centre, acceleration, a, want, allowed)
