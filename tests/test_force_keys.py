"""The force analysis' keys of the mechanism language (docs/language.md, "Mass, gravity and
loads"): the schema and the load-time checks accept what the force reference reads and refuse
what it cannot mean, a book carries them in its record unchanged, and every bundled template that
gives its links masses is one the force reference analyses. (The refusals as the command line
reports them, one line each, are in test_bad_input.py.)"""
from __future__ import annotations

import copy
import json
import tomllib

import jsonschema
import numpy as np
import pytest

from conftest import ROOT, built, checks_of, formula_cells
from linkbook.base.errors import InputError
from linkbook.base.record import BuildRecord
from linkbook.base.sheets import FORCES_SHEET, META
from linkbook.book import builder
from linkbook.check.forces import forces, topology
from linkbook.language import templates
from linkbook.language.bundled import from_record
from linkbook.language.model import DescriptionError

SCHEMA = json.loads((ROOT / "src" / "linkbook" / "language" / "mechanism.schema.json")
                    .read_text(encoding="utf-8"))
FORCE_KEYS = ("dynamics", "bodies", "loads")
WITH_BODIES = sorted(p.stem for p in templates.bundled()
                     if "bodies" in (tomllib.loads(p.read_text(encoding="utf-8"))
                                     .get("mechanism") or {}))


def _data(name: str) -> dict:
    return tomllib.loads((ROOT / "templates" / f"{name}.toml").read_text(encoding="utf-8"))


def _without_force_keys(data: dict) -> dict:
    data = copy.deepcopy(data)
    for k in FORCE_KEYS:
        data["mechanism"].pop(k, None)
    return data


def _fourbar_with(**keys) -> dict:
    """The four-bar without its own masses and loads, with these keys in its [mechanism]."""
    data = _without_force_keys(_data("fourbar"))
    data["mechanism"].update(keys)
    return data


def _refusal(data: dict) -> str:
    with pytest.raises(InputError) as caught:
        templates.from_data("mine", data, origin="mine.toml")
    return str(caught.value)


EVERY_FORM = dict(
    dynamics={"gravity": {"g": 9.81, "angle": "-90 + 0*a1"}},
    bodies=[{"joints": ["A0", "A"], "mass": 0.1, "centre": {"frame": ["A0", "A"],
                                                             "distance": "a2/2"},
             "inertia": 1e-5},
            {"joints": ["A", "B", "C"], "mass": "0.2", "inertia": "1e-4",
             "centre": {"frame": ["A", "B"], "distances": ["b3/2", "c3/2"], "side": "branch"}},
            {"joints": ["B0", "B"], "mass": 0.05, "centre": {"frame": ["B", "B0"],
                                                              "local": ["a4/2", 0]}},
            ],
    loads=[{"at": "C", "force": [10, "-5*COS(theta13)"]},
           {"at": "B", "body": ["A", "B"], "force": {"magnitude": 3, "angle": "DEGREES(mu)"}},
           {"at": "B", "force": {"magnitude": "a4/10"}},
           {"body": ["B0", "B"], "torque": -2}])


def test_every_form_of_the_keys_is_accepted_by_the_schema_the_language_and_the_reference():
    data = _fourbar_with(**copy.deepcopy(EVERY_FORM))
    assert not list(jsonschema.Draft7Validator(SCHEMA).iter_errors(data))
    t = templates.from_data("mine", data, origin="mine.toml")
    got = forces(t.mechanism.description, t.values(), np.arange(0.0, 360.0, 30.0),
                 t.length_unit)
    assert np.isfinite(got["T12"]).all()


def test_the_keys_add_the_forces_sheet_and_change_no_other_cell():
    """Mass, gravity and loads add the Forces sheet (and its charts); every other sheet lays
    out the same cells with the same formulas, and the book with every form of the keys
    verifies: each formula cell judged, none differing from the references."""
    books = [builder.make(templates.from_data("fourbar", data))
             for data in (_without_force_keys(_data("fourbar")),
                          _fourbar_with(**copy.deepcopy(EVERY_FORM)))]
    cells = [{(ws.title, c.coordinate): c.value for ws in b.workbook.worksheets
              if ws.title not in (META, FORCES_SHEET)
              for row in ws.iter_rows() for c in row if c.value is not None} for b, _ in books]
    assert cells[0] == cells[1]
    assert FORCES_SHEET not in books[0][0].workbook.sheetnames
    assert FORCES_SHEET in books[1][0].workbook.sheetnames
    records = [json.loads(json.dumps(b.meta)) for b, _ in books]
    assert records[1]["description"] == {**records[0]["description"], **EVERY_FORM}
    assert "forces" not in records[0] and "forces" in records[1]
    built_book, values = books[1]
    checks = checks_of(built_book, values)
    assert not [m for c in checks for m in c.mismatches]
    assert sum(c.cells for c in checks) == len(formula_cells(built_book.workbook))


@pytest.mark.parametrize("name", WITH_BODIES)
def test_the_record_gives_the_keys_back(name):
    """verify reads the mechanism from the book's record: the description it compiles there
    is the template's, force keys and all."""
    b, _ = built(name)
    record = BuildRecord.from_json(json.loads(json.dumps(b.meta)))
    description = from_record(record).description
    mechanism = _data(name)["mechanism"]
    for k in FORCE_KEYS:
        assert description.get(k) == mechanism.get(k), k


def test_at_least_five_bundled_templates_give_their_links_masses():
    assert {"fourbar", "slider-crank", "toggle-press", "boom-cylinder"} <= set(WITH_BODIES)
    assert len(WITH_BODIES) >= 5


@pytest.mark.parametrize("name", WITH_BODIES)
def test_the_force_reference_analyses_every_bundled_template_with_masses(name):
    """Its topology finds a link for every `bodies` entry, and its effort is finite on the rows
    where the mechanism assembles and the link's position is no dead centre."""
    t = templates.load(name)
    description = t.mechanism.description
    top = topology(description)
    named = [sorted(map(str, e["joints"])) for e in description["bodies"]]
    attached = [b for b in top.bodies if b.spec is not None]
    assert len(attached) == len(named)
    got = forces(description, t.values(), np.asarray(t.sweep.angles()), t.length_unit)
    effort = got["T12"] if "T12" in got else got["F_in"]
    assert np.isfinite(effort).mean() >= 0.9, effort
    assert np.nanmax(np.abs(effort)) > 0


@pytest.mark.parametrize("name", WITH_BODIES)
def test_a_template_states_its_loads_in_parameters_of_their_units(name):
    """Every mass, inertia and load is an input cell a user edits: a parameter of its kind."""
    data = _data(name)
    kinds = {s: e.get("kind", "length") for s, e in data["parameters"].items()}
    for body in data["mechanism"]["bodies"]:
        for k, kind in (("mass", "mass"), ("inertia", "inertia")):
            if k in body:
                assert kinds.get(body[k]) == kind, (body, k)


# ---------------------------------------------------------------------------------------------
# Refusals: each one line naming the file and the field
# ---------------------------------------------------------------------------------------------

BAR = {"joints": ["B0", "B"], "mass": 1.0, "centre": {"frame": ["B0", "B"], "distance": 10}}

REFUSED = [
    ("a body's joint that is no point", dict(bodies=[{"joints": ["B0", "Q"]}]),
     "mine.toml: mechanism.bodies[0].joints[1]: 'Q' is no point of the mechanism"),
    ("a body of one joint, no block", dict(bodies=[{"joints": ["B"]}]),
     "mine.toml: mechanism.bodies[0].joints: a link is named by two of its points or more"),
    ("a block at no slider's point", dict(bodies=[{"joints": ["B"], "block": True}]),
     "mine.toml: mechanism.bodies[0].joints: a block is named by its one point, a slider"),
    ("a centre's frame outside its link",
     dict(bodies=[{**BAR, "centre": {"frame": ["B0", "A"], "distance": 10}}]),
     "mine.toml: mechanism.bodies[0].centre.frame: must be two different joints of the link"),
    ("a centre placed two ways",
     dict(bodies=[{**BAR, "centre": {"frame": ["B0", "B"], "distance": 1, "local": [1, 0]}}]),
     "mine.toml: mechanism.bodies[0].centre: needs exactly one of local, distances or "
     "distance (got local, distance)"),
    ("an angle beside distances",
     dict(bodies=[{**BAR, "centre": {"frame": ["B0", "B"], "distances": [1, 2], "angle": 3}}]),
     "mine.toml: mechanism.bodies[0].centre.angle: does not go with distances"),
    ("a mass without its centre", dict(bodies=[{"joints": ["B0", "B"], "mass": 1.0}]),
     "mine.toml: mechanism.bodies[0].centre: is missing: a link's mass needs its centre"),
    ("a mass of an unknown symbol", dict(bodies=[{**BAR, "mass": "m9"}]),
     "mine.toml: mechanism.bodies[0].mass: unknown symbol 'm9'"),
    ("a mass that is true", dict(bodies=[{**BAR, "mass": True}]),
     "mine.toml: mechanism.bodies[0].mass: must be a number or text (got True)"),
    ("a misspelt key of a body", dict(bodies=[{**BAR, "intertia": 1.0}]),
     "mine.toml: mechanism.bodies[0]: unknown key 'intertia' (did you mean 'inertia'?)"),
    ("a force at no point", dict(loads=[{"at": "Q", "force": [1, 0]}]),
     "mine.toml: mechanism.loads[0].at: 'Q' is no point of the mechanism"),
    ("a force's link not holding its point", dict(loads=[{"at": "C", "body": ["B0", "B"],
                                                          "force": [1, 0]}]),
     "mine.toml: mechanism.loads[0].body: must hold the point 'C' the force acts at"),
    ("a force of three components", dict(loads=[{"at": "C", "force": [1, 0, 0]}]),
     "mine.toml: mechanism.loads[0].force: must be [Fx, Fy] in N, or { magnitude (N), angle"),
    ("a torque at a point", dict(loads=[{"at": "C", "force": [1, 0], "torque": 2}]),
     "mine.toml: mechanism.loads[0]: must be a table of at and force (body optional), or of "
     "body and torque"),
    ("a torque on no link named", dict(loads=[{"torque": 2}]),
     "mine.toml: mechanism.loads[0]: must be a table of at and force"),
    ("a force naming a loop's determinant (no rate)",
     dict(loads=[{"at": "C", "force": ["det_B", 0]}]),
     "mine.toml: mechanism.loads[0].force[0]: unknown symbol 'det_B'"),
    ("gravity without its size", dict(dynamics={"gravity": {"angle": -90}}),
     "mine.toml: mechanism.dynamics.gravity.g: is missing"),
    ("gravity misspelt", dict(dynamics={"gravitation": {"g": 9.81}}),
     "mine.toml: mechanism.dynamics: unknown key 'gravitation' (did you mean 'gravity'?)"),
]


@pytest.mark.parametrize("what,keys,message", REFUSED, ids=[c[0] for c in REFUSED])
def test_a_force_key_that_cannot_mean_anything_is_refused(what, keys, message):
    assert message in _refusal(_fourbar_with(**copy.deepcopy(keys)))


@pytest.mark.parametrize("what,keys,message", REFUSED, ids=[c[0] for c in REFUSED])
def test_a_book_record_with_such_a_key_is_refused_too(what, keys, message):
    """verify compiles the record's description without the template's schema check: the
    same problem, named in the workbook."""
    b, _ = built("fourbar")
    meta = json.loads(json.dumps(b.meta))
    meta["description"] = {k: v for k, v in meta["description"].items() if k not in FORCE_KEYS}
    meta["description"].update(copy.deepcopy(keys))
    with pytest.raises(DescriptionError) as caught:
        from_record(BuildRecord.from_json(meta))
    assert message.replace("mine.toml: ", "workbook: ") in str(caught.value)


@pytest.mark.parametrize("kind,unit,value,message", [
    ("mass", "kg", -1.0, "parameters.m9.value: must be zero or more (got -1.0)"),
    ("inertia", "kg·m²", -1e-3, "parameters.m9.value: must be zero or more"),
    ("torque", "N·m", 2.2250738585072014e-308,
     "parameters.m9.value: must be 0 or from 1e-30 to 1e+30 either way (got 2.22"),
    ("force", "N", -3e30, "parameters.m9.value: must be 0 or from 1e-30 to 1e+30 either way"),
    ("mass", "g", 1.0, "parameters.m9.unit: must be kg for a mass parameter"),
    ("inertia", "kg*m^3", 1.0, "must be kg·m² for an inertia parameter"),
    ("force", "kN", 1.0, "must be N for a force parameter"),
    ("torque", "Nm", 1.0, "must be N·m for a torque parameter"),
    ("acceleration", "ft/s^2", 1.0, "must be m/s² for an acceleration parameter"),
    ("weight", "N", 1.0, "parameters.m9.kind: must be one of length, offset, angle, branch, "
                         "mass, inertia, force, torque, acceleration"),
])
def test_a_load_parameter_has_its_kind_unit_and_sign(kind, unit, value, message):
    data = _data("fourbar")
    data["parameters"]["m9"] = {"label": "probe", "unit": unit, "value": value, "kind": kind}
    assert message in _refusal(data)


def test_load_parameters_keep_their_units_in_a_book_of_inches():
    """A mass, a force or gravity is in SI units whatever the book's length unit: --unit in
    converts the lengths and leaves them as they are."""
    t = templates.load("slider-crank")
    inches = templates.with_unit(t, "in")
    for symbol in ("m2", "I2", "g", "Fgas"):
        assert inches.parameter(symbol).value == t.parameter(symbol).value
        assert inches.parameter(symbol).unit == t.parameter(symbol).unit
    assert inches.parameter("a2").value == pytest.approx(t.parameter("a2").value / 25.4)


@pytest.mark.parametrize("keys,message", [
    (dict(bodies=[{**BAR, "centre": {"frame": ["B0", "B"], "distance": 28}}]),
     "--unit: mechanism.bodies[0].centre.distance: the number 28 is a length here"),
    (dict(bodies=[{**BAR, "centre": {"frame": ["B0", "B"], "local": ["a4/2", 5]}}]),
     "--unit: mechanism.bodies[0].centre.local[1]: the number 5 is a length here"),
    (dict(loads=[{"at": "C", "force": ["xC", 0]}]),
     "--unit: mechanism.loads[0].force[0]: xC is a length, where a number (no length in it) "
     "belongs"),
])
def test_a_length_written_as_a_number_in_a_centre_is_refused_by_a_change_of_unit(keys, message):
    """A centre's place is in the book's length unit: --unit converts it where it is made of
    parameters, and refuses a number it cannot convert, as it does in a step. A force that is a
    length would change its meaning with the unit."""
    t = templates.from_data("mine", _fourbar_with(**copy.deepcopy(keys)), origin="mine.toml")
    with pytest.raises(InputError) as caught:
        templates.with_unit(t, "in")
    assert message in str(caught.value)


@pytest.mark.parametrize("name", WITH_BODIES)
def test_every_template_with_masses_converts_to_inches(name):
    t = templates.load(name)
    assert templates.with_unit(t, "in").length_unit == "in"


def test_the_docs_example_is_a_slider_crank_the_language_and_the_reference_accept():
    """docs/language.md's example of the keys, on the bundled slider-crank (its points A, B, C,
    its parameters, and a force F at angle beta and a torque T3 added)."""
    text = (ROOT / "docs" / "language.md").read_text(encoding="utf-8")
    section = text[text.index("## Mass, gravity and loads"):]
    example = section[section.index("```toml") + len("```toml"):]
    example = tomllib.loads("[mechanism]\n" + example[:example.index("```")])["mechanism"]
    data = _without_force_keys(_data("slider-crank"))
    data["mechanism"].update(example)
    data["parameters"]["F"] = {"label": "F", "unit": "N", "value": 50.0, "kind": "force"}
    data["parameters"]["beta"] = {"label": "β", "unit": "deg", "value": 30.0, "kind": "angle"}
    data["parameters"]["T3"] = {"label": "T3", "unit": "N·m", "value": -1.0, "kind": "torque"}
    t = templates.from_data("mine", data, origin="mine.toml")
    got = forces(t.mechanism.description, t.values(), np.asarray(t.sweep.angles()),
                 t.length_unit)
    assert np.isfinite(got["T12"]).all()
