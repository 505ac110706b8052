"""Frames whose two points meet (issue 39): where the direction is undefined the book says #N/A
in every application (never ATAN2(0, 0)'s #DIV/0!, never LibreOffice's 0) and verify's
reference names the same cells undefined; a frame whose points meet on every row is refused."""
from __future__ import annotations

import os
import tomllib

import pytest

import linkbook
from linkbook.base.errors import InputError
from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.engine import office
from linkbook.language import templates

# A crank A0-A of 35 and a ground point P0 at (35, 0): at θ12 = 0 the crank pin A is exactly
# on P0, so D, carried by the frame A→P0, has no place there, and the vector P0→A no angle
# (and only there: the sweep stops at 330° so that no row lands a rounding error from P0).
PASSING = """
title = "a point framed on a crank pin and a pivot it passes over"
length_unit = "mm"
[sweep]
start = 0
stop = 330
step = 30
position = 60
[parameters]
a1 = { label = "ground", unit = "mm", value = 70.0 }
a2 = { label = "crank", unit = "mm", value = 35.0 }
[mechanism]
input = { key = "theta12", symbol = "θ12" }
ground = { A0 = [0, 0], B0 = ["a1", 0], P0 = ["a2", 0] }
links = [["A0", "A"]]
[[mechanism.steps]]
type = "crank"
point = "A"
pivot = "A0"
length = "a2"
[[mechanism.steps]]
type = "point"
point = "D"
frame = ["A", "P0"]
local = [10, 5]
[[mechanism.steps]]
type = "vector"
from = "P0"
to = "A"
key = "r"
"""
# the same frame on two ground points at one place: D is nowhere on any row
ONE_PLACE = PASSING.replace('P0 = ["a2", 0]', 'P0 = ["a1", 0]').replace(
    'frame = ["A", "P0"]', 'frame = ["B0", "P0"]')


def _book(tmp_path, text: str):
    """The built book's path, and where D's cells and the vector's angle are on the row
    θ12 = 0."""
    toml = tmp_path / "frame.toml"
    toml.write_text(text, encoding="utf-8")
    path = tmp_path / "frame.xlsx"
    built = builder.build_file(templates.load(str(toml)), path)
    sweep, motion = built.meta["sweep"], built.meta["motion"]
    cells = [("Sweep", f"{sweep['columns'][k]}{sweep['rows'][0]}")
             for k in ("xD", "yD", "phi_r")]
    cells += [("Motion", f"{letter}{motion['rows'][0]}")
              for k, letter in motion["columns"].items() if k.endswith(("_D", "_phi_r"))]
    return path, cells


def _code(value):
    return engine.error_code(value) if engine.is_error(value) else value


def test_a_frame_whose_points_meet_on_every_row_is_refused_naming_it(tmp_path):
    with pytest.raises(InputError) as caught:
        _book(tmp_path, ONE_PLACE)
    message = str(caught.value)
    assert "\n" not in message
    assert "mechanism.steps[1] (point D).frame: B0 and P0 are at one place on every row" \
        in message
    assert not (tmp_path / "frame.xlsx").exists()


def test_a_point_framed_on_a_slides_pivot_and_foot_at_offset_zero_is_refused():
    """The lever framed on its pivot B0 and the slide's foot B: at offset 0 the foot is the
    pivot on every row."""
    data = tomllib.loads(
        (templates.TEMPLATE_DIR / "inverted-slider-crank.toml").read_text(encoding="utf-8"))
    data["parameters"]["a4"]["value"] = 0
    del data["mechanism"]["columns"]
    data["mechanism"]["steps"].append({"type": "point", "point": "E", "frame": ["B0", "B"],
                                       "local": [50, 0]})
    with pytest.raises(InputError, match=r"mechanism\.steps\[\d\] \(point E\)\.frame: B0 and "
                                         r"B are at one place on every row"):
        builder.make(templates.from_data("lever", data))


def test_a_centre_framed_on_a_slides_pivot_and_foot_at_offset_zero_is_a_warning():
    """The inverted slider-crank's link 4 has its centre in the frame B0→B: in-line (offset
    0) the book keeps its kinematics, and says in one line that link 4's forces are #N/A."""
    built, _ = builder.make(templates.with_overrides(templates.load("inverted-slider-crank"),
                                                     ["a4=0"], None, None))
    assert built.warnings == ["inverted-slider-crank.toml: mechanism.bodies[2].centre.frame: "
                              "B0 and B are at one place on every row of the sweep: the "
                              "link's centre of mass, and every force it reaches, is #N/A"]


def test_a_crank_pin_passing_over_a_pivot_is_na_there_and_verifies(tmp_path):
    path, cells = _book(tmp_path, PASSING)
    report = linkbook.verify(path)
    assert report.status == 0, report.differing
    values = engine.evaluate_file(path)
    assert len(cells) == 9 and {_code(values[c]) for c in cells} == {"#N/A"}
    assert isinstance(values[("Sweep", cells[0][1].replace("5", "6"))], float)
    assert not any(_code(v) == "#DIV/0!" for v in values.values())


def _require(found, what: str) -> None:
    if found:
        return
    if os.environ.get("CI"):
        pytest.fail(f"CI needs {what}")
    pytest.skip(f"needs {what}")


@pytest.mark.parametrize("application", [
    pytest.param("libreoffice", marks=pytest.mark.libreoffice),
    pytest.param("gnumeric", marks=pytest.mark.gnumeric)])
def test_the_applications_say_na_where_the_frame_is_undefined(application, tmp_path):
    _require(office.soffice_path() if application == "libreoffice" else office.ssconvert_path(),
             application)
    path, cells = _book(tmp_path, PASSING)
    values = office.recalculated_values(path, application)
    assert {_code(values[c]) for c in cells} == {"#N/A"}
    assert not any(_code(v) == "#DIV/0!" for v in values.values())
    assert linkbook.verify(path, engine=application).status == 0
