"""The numbers the sources printed, read from the workbooks' evaluated cells."""
from __future__ import annotations

import math

import pytest

from conftest import built, published, value_at


def test_slider_crank_example_1():
    data = published()["slider_crank_example_1"]
    b, values = built("slider-crank")
    tol = data["tolerance"]
    got = {"theta13": value_at(b, values, "theta13_deg", 60), "s14": value_at(b, values, "s14", 60),
           "xC": value_at(b, values, "xC", 60), "yC": value_at(b, values, "yC", 60)}
    for key, expected in data["published"].items():
        assert abs(got[key] - expected) <= tol, (key, got[key], expected)


def test_pump_table_example_4_all_114_cells():
    data = published()["pump_table_example_4"]
    b, values = built("pump")
    grid = b.meta["grid"]
    ws = b.workbook["Grid"]
    assert [ws[f"{c}{grid['param_row']}"].value for c in grid["columns"]] == data["s1"]
    compared = 0
    worst = 0.0
    for row in data["rows"]:
        r = next(r for r in range(grid["rows"][0], grid["rows"][1] + 1)
                 if ws[f"A{r}"].value == row[0])
        for letter, expected in zip(grid["columns"], row[1:]):
            got = values[("Grid", f"{letter}{r}")]
            worst = max(worst, abs(got - expected))
            compared += 1
    assert compared == 114
    assert worst <= data["tolerance"], worst


def test_pump_stroke_mathcad_output_3():
    data = published()["pump_stroke_mathcad_output_3"]
    b, values = built("pump")
    grid = b.meta["grid"]
    ws = b.workbook["Grid"]
    for item in data["published"]:
        letter = next(c for c in grid["columns"]
                      if ws[f"{c}{grid['param_row']}"].value == item["s1"])
        got = values[("Grid", f"{letter}{grid['stroke_row']}")]
        assert abs(got - item["stroke"]) <= data["tolerance"], (item, got)


@pytest.mark.parametrize("branch,guess", [("open", "guess_90"), ("crossed", "guess_270")])
def test_tk_solver_both_assembly_modes(branch, guess):
    data = published()["tk_solver_fourbar"]
    b, values = built("tk-fourbar", (), None, branch)
    expected = data[guess]["published"]
    keys = {"x1": "x1", "y1": "y1", "x2": "x2", "y2": "y2", "psi": "psi_deg", "x4": "x4",
            "y4": "y4", "d": "d", "e": "e"}
    for name, key in keys.items():
        got = value_at(b, values, key, 45)
        assert math.isclose(got, expected[name], rel_tol=data["rel_tolerance"]), (name, got)


def test_shaper_at_30_degrees():
    data = published()["shaper_quick_return_seed_004"]
    b, values = built("shaper")
    got = {"r3": value_at(b, values, "r3", 30), "r4": value_at(b, values, "r4", 30),
           "r5": value_at(b, values, "r5", 30), "theta3": value_at(b, values, "theta3_deg", 30)}
    for key, expected in data["published"].items():
        assert abs(got[key] - expected) <= data["tolerance"], (key, got[key], expected)
