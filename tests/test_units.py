"""One length unit per book (issue 16): from a known list, every parameter agreeing with it,
--unit converting a template, and every header, label and axis title following it."""
from __future__ import annotations

import re
import tomllib
import zipfile

import openpyxl
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from conftest import checks_of, examples, ROOT

from linkbook.book import builder
from linkbook.apps import cli
from linkbook.engine import evaluator as engine
from linkbook.language import templates
from linkbook.base.sheets import read_meta

BUNDLED = [p.stem for p in templates.bundled()]


def _xml_text(path) -> str:
    with zipfile.ZipFile(path) as z:
        return " ".join(z.read(n).decode("utf-8") for n in z.namelist() if n.endswith(".xml"))


@pytest.fixture(scope="module")
def metre_book(tmp_path_factory):
    path = tmp_path_factory.mktemp("units") / "m.xlsx"
    assert cli.main(["build", "fourbar", "--unit", "m", "-o", str(path)]) == 0
    return path


def test_the_metre_four_bar_says_m_everywhere(metre_book, capsys):
    text = _xml_text(metre_book)
    assert not re.search(r"\bmm\b", text)
    assert "[m]" in text and "x [m]" in text and "y [m]" in text
    wb = openpyxl.load_workbook(metre_book)
    cell = wb.defined_names["a_2"].attr_text.split("!")[1].replace("$", "")
    assert wb["Mechanism"][cell].value == pytest.approx(0.035)   # 35 mm
    assert cli.main(["verify", str(metre_book)]) == 0
    capsys.readouterr()


def test_a_metre_drawing_names_its_grid_square_in_metres(metre_book):
    """The drawing's frame has no tick numbers (they would count squares); the scale bar's
    legend, a live cell, says how big a square is, in a round number of metres."""
    text = _xml_text(metre_book)
    for value in re.findall(r'<c:(?:min|max) val="([^"]+)"', text):
        assert "E" not in value.upper() and len(value) <= 8, value
    wb = openpyxl.load_workbook(metre_book)
    meta = read_meta(wb)
    values = engine.evaluate(wb)
    for frame in meta["frames"]["frames"]:
        label = values[("Drawing data", frame["cells"]["label"])]
        assert re.fullmatch(r"grid square 0\.0*[125] m", label), label


def _fourbar_text(**changes) -> str:
    text = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new, 1)
    return text


@pytest.mark.parametrize("change, words", [
    ({'a2 = { label = "crank |A0A|", unit = "mm"': 'a2 = { label = "crank |A0A|", unit = "m"'},
     ["parameters.a2.unit", "must be mm", "'m'"]),
    ({'length_unit = "mm"': 'length_unit = "inch"'}, ["length_unit", "mm, cm, m, in, ft"]),
])
def test_a_unit_that_does_not_agree_is_refused(tmp_path, capsys, change, words):
    path = tmp_path / "mine.toml"
    path.write_text(_fourbar_text(**change), encoding="utf-8")
    assert cli.main(["build", str(path), "-o", str(tmp_path / "x.xlsx")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(w in err for w in words), err
    assert not (tmp_path / "x.xlsx").exists()


def test_a_length_written_as_a_number_cannot_be_converted(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    path.write_text(_fourbar_text(**{'B0 = ["a1", 0]': 'B0 = [80, 0]'}), encoding="utf-8")
    assert cli.main(["build", str(path), "--unit", "cm", "-o", str(tmp_path / "x.xlsx")]) == 2
    assert "mechanism.ground.B0" in capsys.readouterr().err


@pytest.mark.slow        # every template in every unit
@settings(max_examples=examples(20), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(BUNDLED), unit=st.sampled_from(list(templates.LENGTH_UNITS)))
def test_every_template_in_every_unit_verifies(name, unit):
    """The same mechanism in any unit: lengths converted, every cell against the reference."""
    t = templates.with_unit(templates.load(name), unit)
    t = templates.with_overrides(t, step=30 if t.mechanism.input_is_angle else None)
    b, values = builder.make(t)
    bad = [(c.block, c.name, m) for c in checks_of(b, values) for m in c.mismatches[:2]]
    assert not bad, (name, unit, bad[:3])
    assert b.meta["length_unit"] == unit


def test_a_length_expression_with_a_number_cannot_be_converted():
    data = tomllib.loads(_fourbar_text())
    data["mechanism"]["steps"].append({"type": "expression", "key": "reach", "unit": "length",
                                       "formula": "a2+10"})
    t = templates.from_data("mine", data)
    with pytest.raises(templates.InputError) as caught:
        templates.with_unit(t, "m")
    assert "steps[" in str(caught.value) and ".formula" in str(caught.value)


def _with_expression(formula: str, unit: str) -> templates.Template:
    data = tomllib.loads(_fourbar_text())
    data["mechanism"].pop("columns")
    data["mechanism"]["steps"].append({"type": "expression", "key": "q", "unit": unit,
                                       "formula": formula})
    return templates.from_data("mine", data, origin="mine.toml")


# Numbers that are no length (a ratio, a scale factor, an angle in degrees): --unit converts
@pytest.mark.parametrize("formula, unit", [
    ("yC/a2 - 4", "-"), ("2*a2", "length"), ("SQRT(a2^2 + a3^2)", "length"),
    ("DEGREES(ATAN2(xC, yC)) + 90", "-"), ("IF(xC > 0, xC, 0)", "length"),
    ("a2*PI()/180", "length"), ("(a2 + a3)/2", "length")])
def test_a_number_that_is_no_length_converts(formula, unit):
    t = templates.with_unit(_with_expression(formula, unit), "m")
    assert t.length_unit == "m"


# Numbers that are lengths (or mixed with one): --unit cannot convert them and says where
@pytest.mark.parametrize("formula, unit, words", [
    ("a2 + 10", "length", "the number 10 is a length here"),
    ("MAX(a2, 5)", "length", "the number 5 is a length here"),
    ("SQRT(a2^2 + 9)", "length", "the number 9 is an area here"),
    ("IF(xC > 3, xC, 0)", "length", "the number 3 is a length here"),
    ("yC/a2 - 4", "length", "yC / a2 - 4 is a number (no length in it), where a length belongs"),
    ("SIN(a2)", "-", "a2 is a length, where a number (no length in it) belongs")])
def test_a_number_that_is_a_length_is_named(formula, unit, words):
    with pytest.raises(templates.InputError) as caught:
        templates.with_unit(_with_expression(formula, unit), "m")
    message = str(caught.value)
    assert message.startswith("--unit: mechanism.steps[3] (expression q).formula: "), message
    assert words in message, message
