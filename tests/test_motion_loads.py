"""Loads that depend on the motion (issue 39): a viscous damper, Coulomb friction opposing the
motion and a force on the working stroke only, on bundled mechanisms. Each book agrees with the
independent references (verify) and balances power on every row, the loads' power taken with
the book's own rates (test_forces_book.assert_power_balance); the bundled four-bar's friction
takes, per turn, the work its crank's mean driving torque gives."""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

import linkbook
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.engine import evaluator as engine
from linkbook.language import templates
from test_forces_book import assert_power_balance, assert_verified

DAMPING = {"label": "damping of the rocker's bearing", "unit": "N·m·s", "value": 0.004,
           "kind": "damping"}
FRICTION = {"label": "friction force on the piston, opposing its motion", "unit": "N",
            "value": 4.0, "kind": "force"}
PRESS = {"label": "press force on the working stroke", "unit": "N", "value": 25.0,
         "kind": "force"}

# template, parameters to add, its loads
CASES = {
    "fourbar-friction": ("fourbar", {}, None),     # as bundled: −T4·SIGN(ω14)
    "fourbar-damper": ("fourbar", {"c4": DAMPING},
                       [{"body": ["B0", "B"], "torque": "-c4*omega_theta14"}]),
    "slider-crank-friction-and-press": (
        "slider-crank", {"F0": FRICTION, "Fp": PRESS},
        [{"at": "B", "force": ["-F0*SIGN(v_s14)", 0]},
         {"at": "B", "force": ["IF(AND(v_s14 < 0, NOT(theta12 < 1)), Fp, 0)", 0]}]),
    "inverted-slider-crank-damper": ("inverted-slider-crank", {"c4": DAMPING},
                                     [{"body": ["B0", "B"], "torque": "-c4*omega_theta14"}]),
}


def case(name: str) -> templates.Template:
    base, parameters, loads = CASES[name]
    data = tomllib.loads((templates.TEMPLATE_DIR / f"{base}.toml").read_text(encoding="utf-8"))
    data["parameters"].update(parameters)
    if loads is not None:
        data["mechanism"]["loads"] = loads
    return templates.from_data(name, data)


@pytest.mark.parametrize("name", CASES)
def test_a_load_of_the_motion_verifies_and_balances_power(name):
    t = case(name)
    built, values = builder.make(t)
    assert_verified(built, values)
    assert assert_power_balance(t, built, values) > 0


def test_the_fourbars_mean_driving_torque_is_the_work_its_friction_takes():
    """Over a turn at constant ω12 the links' kinetic and potential energy come back, so the
    crank's mean driving torque (the book's own summary) times 2π is the work the rocker's
    friction takes: ∫ T4·|ω14| dt = ∫ T4·|ω14|/ω12 dθ12, by numpy's trapezoid rule on the
    book's rows from the reference's ω14 — and, to the trapezoid rule's accuracy at the
    reversals, T4 times twice the rocker's swing (the reference's, sampled every 0.005°)."""
    t = templates.load("fourbar")
    built, values = builder.make(t)
    forces = built.meta["forces"]
    mean = values[(forces["sheet"], forces["summary"]["effort_mean"]["cell"])]
    params = t.values()
    assert params["alpha_in"] == 0 and params["T4"] > 0
    angles = np.array(t.sweep.angles())
    assert angles[0] == 0 and angles[-1] == 360
    w14 = solve(t.mechanism.description, params, angles)["omega_theta14"]
    work = np.trapezoid(params["T4"] * np.abs(w14) / params["omega_in"], np.radians(angles))
    assert mean == pytest.approx(work / (2 * math.pi), rel=1e-9)
    fine = np.linspace(0.0, 360.0, 72001)
    theta14 = np.unwrap(solve(t.mechanism.description, params, fine)["theta14"])
    swing = theta14.max() - theta14.min()
    assert mean == pytest.approx(2 * params["T4"] * swing / (2 * math.pi), rel=1e-3)


@pytest.mark.libreoffice
def test_libreoffice_recalculates_a_damped_book_as_the_references(tmp_path):
    from test_degenerate_frames import _require
    from linkbook.engine import office
    _require(office.soffice_path(), "LibreOffice")
    path = tmp_path / "damper.xlsx"
    builder.build_file(case("inverted-slider-crank-damper"), path)
    report = linkbook.verify(path, engine="libreoffice")
    assert report.status == 0, report.differing


def test_a_load_that_is_an_error_on_one_row_is_na_there_and_only_what_it_reaches():
    """A torque on the crank that divides by zero at θ12 = 180° exactly (RADIANS(180) is PI()):
    the book shows #N/A there (not #DIV/0!) in the driving torque, the reference has no value
    there either, and the pins, which a couple on the crank does not reach, stay numbers in
    both."""
    data = tomllib.loads((templates.TEMPLATE_DIR / "fourbar.toml").read_text(encoding="utf-8"))
    data["mechanism"]["loads"].append(
        {"body": ["A0", "A"], "torque": "IF(theta12 > 3, 0.01/(theta12 - PI()), 0)"})
    built, values = builder.make(templates.from_data("pole", data))
    assert_verified(built, values)
    forces = built.meta["forces"]
    row = forces["rows"][0] + 36                                  # θ12 = 180°
    assert values[(forces["sheet"], f"A{row}")] == 180

    def at(key: str, r: int = row):
        value = values[(forces["sheet"], f"{forces['columns'][key]}{r}")]
        return engine.error_code(value) if engine.is_error(value) else value
    assert at("T12") == "#N/A"
    assert all(isinstance(at(key), float) for key in ("F12x", "F23x", "F34x", "F14x"))
    assert isinstance(at("T12", row + 1), float)
