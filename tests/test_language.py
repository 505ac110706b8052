"""The mechanism language (docs/language.md): bad descriptions are refused with one line naming the
step and the field; expressions mean what the doc says; every template fits the JSON Schema; a
user's new step needs no Python."""
from __future__ import annotations

import copy
import json
import subprocess
import sys
import tomllib

import pytest

from conftest import checks_of, examples, formula_cells, ROOT
from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.language import templates
from linkbook.language.templates import InputError

SCHEMA = ROOT / "src" / "linkbook" / "language" / "mechanism.schema.json"


def fourbar_data() -> dict:
    return tomllib.loads((templates.TEMPLATE_DIR / "fourbar.toml").read_text(encoding="utf-8"))


def step(data: dict, point: str) -> dict:
    return next(s for s in data["mechanism"]["steps"] if s.get("point") == point)


def _set(path: str, value):
    def change(d):
        *head, last = path.split(".")
        for k in head:
            d = d[k]
        d[last] = value
    return change


def _step(point: str, key: str, value):
    def change(d):
        s = step(d, point)
        if value is _DELETE:
            del s[key]
        else:
            s[key] = value
    return change


_DELETE = object()


def _add_step(new: dict, at: int | None = None):
    def change(d):
        steps = d["mechanism"]["steps"]
        steps.insert(len(steps) if at is None else at, new)
    return change


def _move_first_last(d):
    steps = d["mechanism"]["steps"]
    steps.append(steps.pop(0))


# (what is wrong, the change, words the one-line message must hold)
BAD = [
    ("a point used before it is defined", _move_first_last, ["steps[0] (dyad B).p",
                                                              "defined by a later step"]),
    ("an unknown point", _step("B", "q", "B9"), ["(dyad B).q", "'B9' is not defined"]),
    ("an unknown symbol", _step("B", "p_length", "a3*k9"), ["(dyad B).p_length",
                                                             "unknown symbol 'k9'"]),
    ("a missing key", _step("B", "q_length", _DELETE), ["(dyad B).q_length", "is missing"]),
    ("an unknown key", _step("B", "lenght", 3), ["(dyad B): unknown key 'lenght'"]),
    ("a duplicate point", _add_step({"type": "crank", "point": "A", "pivot": "A0",
                                     "length": "a2"}), ["point 'A' is defined twice"]),
    ("a duplicate column key", _step("C", "columns", {"x": {"key": "xA"}}),
     ["(point C).columns", "'xA' defined twice"]),
    ("a cyclic definition", _step("B", "p", "B"), ["(dyad B).p", "cyclic"]),
    ("a branch other than ±1", _step("B", "branch", 2), ["(dyad B).branch", "must be 1, -1"]),
    ("a branch that is a length", _step("B", "branch", "a1"), ["(dyad B).branch",
                                                                "not a branch"]),
    ("a name Excel would reject", _set("parameters.a1.name", "AB12"),
     ["parameters.a1.name", "cell reference"]),
    ("a link through an undefined point", _set("mechanism.links", [["A0", "Q"]]),
     ["links[0][1]", "'Q' is not defined"]),
    ("an unknown step type", _step("B", "type", "tetrad"), ["type", "must be one of"]),
    ("an expression that does not parse", _step("B", "p_length", "a3*(a4"),
     ["(dyad B).p_length", "is not an expression"]),
    ("an unknown function", _step("B", "p_length", "COSH(a3)"), ["unknown function COSH"]),
    ("a dyad over one point twice", _step("B", "q", "A"), ["(dyad B).q", "must differ"]),
    ("a point frame of one point", _step("C", "frame", ["A", "A"]),
     ["(point C).frame", "two different points"]),
    ("two forms of a carried point", _step("C", "local", [1, 2]),
     ["(point C)", "exactly one of local, distances or distance"]),
    ("an unknown column name", _step("B", "columns", {"theta": {"key": "t"}}),
     ["(dyad B).columns.theta", "writes no such column"]),
    ("a column key taken by a parameter", _step("C", "columns", {"x": {"key": "a1"}}),
     ["(point C).columns.x.key", "is taken"]),
    ("a chart of an unknown column", _set("mechanism.charts", [{"title": "t", "x": "xQ",
                                                                "y": ["yC"]}]),
     ["charts[0]", "'xQ' is not a column"]),
    ("a fixed point that is not a pair", _set("mechanism.ground.B0", ["a1"]),
     ["ground.B0", "must be [x, y]"]),
    ("a trace of a fixed point", _set("mechanism.trace", "A0"), ["trace", "moving point"]),
    ("an output that is no column", _set("mechanism.output", "theta9"),
     ["mechanism.output", "'theta9' is not a shown column of a length or an angle"]),
    ("an angle output without its degree view", _set("mechanism.output", "psi"),
     ["mechanism.output", "the angle 'psi' needs its degree view (degrees = true)"]),
    ("an unknown parameter kind", _set("parameters.a1.kind", "distance"),
     ["parameters.a1.kind", "must be one of"]),
    ("an input without a symbol", _set("mechanism.input", {"key": "theta12"}),
     ["input.symbol", "is missing"]),
    ("a column order that forgets a column", _set("mechanism.columns", ["xs"]),
     ["mechanism.columns", "must list every shown column once"]),
    ("a slider through a moving point", _add_step({"type": "slider", "point": "S", "p": "C",
                                                   "length": "a3", "through": "A",
                                                   "branch": 1}),
     ["(slider S).through", "must be a fixed point"]),
    ("an input of an unknown kind", _set("mechanism.input", {"key": "theta12", "symbol": "θ",
                                                             "kind": "force"}),
     ["input.kind", "must be angle", "length", "(got 'force')"]),
    ("a crank turned by a length input", _set("mechanism.input", {"key": "s", "symbol": "s",
                                                                  "kind": "length"}),
     ["(crank A).type", "a crank turns with an angle input"]),
    ("a swept length where a constant is needed",
     lambda d: (_set("mechanism.input", {"key": "s", "symbol": "s", "kind": "length"})(d),
                d["mechanism"]["steps"].pop(0), _step("B", "p", "A0")(d),
                _step("B", "q_length", "s")(d), _step("C", "frame", ["A0", "B"])(d),
                _step("C", "local", ["s", 0])(d), _step("C", "distances", _DELETE)(d),
                _step("C", "side", _DELETE)(d), _step("C", "columns", _DELETE)(d)),
     ["(point C).local[0]", "unknown symbol 's'"]),
    ("a key taken by the input's speed", _add_step({"type": "expression", "key": "omega_in",
                                                    "formula": "1"}),
     ["(expression omega_in).key", "'omega_in' is taken"]),
    ("an actuator's side that is not its length itself",
     lambda d: (_set("mechanism.input", {"key": "s", "symbol": "s", "kind": "length"})(d),
                d["mechanism"]["steps"].pop(0), _step("B", "p", "A0")(d),
                _step("B", "q_length", "s+1")(d), _step("C", "frame", ["A0", "B"])(d),
                _set("mechanism.links", [["A0", "B", "C"]])(d), d["mechanism"].pop("charts"),
                d["mechanism"].pop("columns")),
     ["(dyad B).q_length", "must be its length itself"]),
    ("a moving line given by one point", _add_step({"type": "slider", "point": "S", "p": "C",
                                                    "length": "a3", "through": "A",
                                                    "along": ["A", "A"], "branch": 1}),
     ["(slider S).along", "two different points"]),
    ("a time ratio of an unknown column", _add_step({"type": "expression", "key": "Q",
                                                     "formula": "1", "time_ratio_of": "s99"}),
     ["(expression Q).time_ratio_of", "must be the key of an earlier column"]),
    ("a time ratio that changes with the input", _add_step({"type": "expression", "key": "Q",
                                                            "formula": "xB/a1",
                                                            "time_ratio_of": "xB"}),
     ["(expression Q).time_ratio_of", "one number per book"]),
]


@pytest.mark.parametrize("what,change,words", BAD, ids=[b[0] for b in BAD])
def test_bad_description_names_the_step_and_field(what, change, words):
    data = fourbar_data()
    change(data)
    with pytest.raises(InputError) as caught:
        templates.from_data("bad", data, origin="bad.toml")
    message = str(caught.value)
    assert "\n" not in message
    for w in words:
        assert w in message, (what, message)


def test_bad_description_on_the_command_line_writes_nothing(tmp_path):
    data = (templates.TEMPLATE_DIR / "fourbar.toml").read_text(encoding="utf-8")
    bad = tmp_path / "bad.toml"
    bad.write_text(data.replace('q = "B0"', 'q = "B7"'), encoding="utf-8")
    out = tmp_path / "bad.xlsx"
    run = subprocess.run([sys.executable, "-m", "linkbook", "build", str(bad), "-o", str(out)],
                         capture_output=True, text=True, cwd=tmp_path,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "steps[1] (dyad B).q" in lines[0] and "B7" in lines[0], run.stderr
    assert "Traceback" not in run.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == [bad]


def _expression_book(formula: str, **extra):
    data = fourbar_data()
    data["mechanism"]["steps"].append({"type": "expression", "key": "probe", "formula": formula,
                                       **extra})
    data["mechanism"].pop("columns")
    return builder.make(templates.from_data("probe", data))


@pytest.mark.parametrize("formula,expected", [
    ("-a2^2", -35.0 ** 2),          # algebra's precedence, not Excel's (-a)^2
    ("a1-(a2-a3)", 70.0 - (35.0 - 62.3)),
    ("2^3^2", 2.0 ** 9),            # right-associative, as in algebra
    ("a1/(a2*a4)", 70.0 / (35.0 * 56.0)),
    ("IF(a1 > a2, 1, 2) + MAX(a2, a3, a4)", 1 + 62.3),
    ("ASIN(2)", None),              # a domain error shows #N/A
])
def test_expression_means_what_the_doc_says(formula, expected):
    b, values = _expression_book(formula)
    cell = b.meta["constants"]["probe"]["cell"]
    got = values[("Mechanism", cell)]
    if expected is None:
        assert engine.error_code(got) == "#N/A", got
    else:
        assert got == pytest.approx(expected, rel=1e-15), got


def test_every_template_fits_the_json_schema():
    import jsonschema
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    jsonschema.Draft7Validator.check_schema(schema)
    texts = {path.name: path.read_text(encoding="utf-8") for path in templates.bundled()}
    for name, text in {**texts, "EVERY_OPTION": EVERY_OPTION}.items():
        errors = list(jsonschema.Draft7Validator(schema).iter_errors(tomllib.loads(text)))
        assert not errors, (name, [e.message for e in errors[:3]])
    broken = fourbar_data()
    step(broken, "B")["branch"] = 3
    assert list(jsonschema.Draft7Validator(schema).iter_errors(broken))


def test_the_docs_copy_of_the_schema_is_the_packaged_one():
    """Editors read docs/mechanism.schema.json; build checks with the one inside the package."""
    docs = (ROOT / "docs" / "mechanism.schema.json").read_bytes()
    assert docs == SCHEMA.read_bytes(), ("docs/mechanism.schema.json has drifted: copy "
                                         "src/linkbook/language/mechanism.schema.json over it")


def test_the_compiler_knows_the_keys_the_schema_allows():
    """One source of truth: the semantic checks take each step's keys from the schema, so a key
    the schema allows is one the compiler reads, and no other."""
    from linkbook.language import steps as language
    steps = json.loads(SCHEMA.read_text(encoding="utf-8"))["properties"]["mechanism"][
        "properties"]["steps"]["items"]
    for rule in steps["allOf"]:
        kind = rule["if"]["properties"]["type"]["const"]
        required, optional = language.STEP_KEYS[kind]
        assert required | optional | language.COMMON_KEYS == set(rule["then"]["properties"])
        assert required | {"type"} == set(rule["then"]["required"])


def test_a_new_step_in_a_copied_template_needs_no_python():
    """A user's change: a second dyad hung on the coupler point C, and a point on its link."""
    data = copy.deepcopy(fourbar_data())
    data["parameters"]["a5"] = {"label": "link |CD|", "unit": "mm", "value": 90.0}
    data["parameters"]["a6"] = {"label": "output |D0D|", "unit": "mm", "value": 80.0}
    data["mechanism"]["ground"]["D0"] = [150, 60]
    data["mechanism"]["steps"] += [
        {"type": "dyad", "point": "D", "p": "C", "q": "D0", "p_length": "a5",
         "q_length": "a6", "branch": 1},
        {"type": "point", "point": "E", "frame": ["D0", "D"], "local": [40, 10]}]
    data["mechanism"]["links"] += [["C", "D"], ["D0", "D", "E"]]
    data["mechanism"].pop("columns")
    b, values = builder.make(templates.from_data("mine", data))
    checks = checks_of(b, values)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
    assert not bad, bad[:5]
    assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))
    assert "xE" in b.meta["sweep"]["columns"] and "theta_q_D" in b.meta["sweep"]["columns"]
    assert any(c.name == "xE" and c.cells > 0 for c in checks)


def _jansen_with_grid(output: str, extra_steps=()) -> dict:
    data = tomllib.loads((templates.TEMPLATE_DIR / "jansen.toml").read_text(encoding="utf-8"))
    data["grid"] = {"parameter": "m", "output": output, "values": [12.0, 15.0, 19.0],
                    "stroke_step": 10.0}
    data["mechanism"]["steps"] += list(extra_steps)
    return data


def test_a_grid_of_any_described_mechanism_is_verified():
    """The textbook's adjustment-by-angle grid for Jansen's leg: the foot's height for three
    crank lengths, one self-contained formula per cell, every cell against the reference."""
    b, values = builder.make(templates.from_data("jansen-grid", _jansen_with_grid("yF")))
    checks = checks_of(b, values)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
    assert not bad, bad[:5]
    assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))
    grid = b.meta["grid"]
    assert [c.name for c in checks if c.block == "Grid"] == ["yF grid", "stroke", "stroke sampling"]
    assert all("Mechanism!" not in str(b.workbook["Grid"][f"{c}{grid['rows'][0]}"].value)
               for c in grid["columns"])        # self-contained: names and its own row only


def test_a_grid_formula_excel_could_not_open_is_refused():
    deeper = [{"type": "dyad", "point": "G", "p": "F", "q": "Z", "p_length": "h",
               "q_length": "k", "branch": 1},
              {"type": "dyad", "point": "H", "p": "G", "q": "E", "p_length": "h",
               "q_length": "k", "branch": 1}]
    with pytest.raises(InputError) as caught:
        builder.make(templates.from_data("deep", _jansen_with_grid("yH", deeper)))
    assert "grid.output" in str(caught.value) and "Excel's limit is 8,192" in str(caught.value)


# Every option of every step type at least once, with values no bundled template has: a crank
# phase, a slider line at a slant, a slot at a non-quarter angle, a branch and a side given by
# parameters, a carried point by distance and angle, an expression over columns.
EVERY_OPTION = """
title = "Every option"
length_unit = "mm"
[sweep]
start = 0
stop = 360
step = 15
[parameters]
a1 = { label = "ground", unit = "mm", value = 70.0 }
a2 = { label = "crank", unit = "mm", value = 25.0 }
a3 = { label = "coupler", unit = "mm", value = 80.0 }
a4 = { label = "rocker", unit = "mm", value = 60.0 }
ph = { label = "phase of the second crank", unit = "deg", value = 35.0, kind = "angle" }
d5 = { label = "slider rod", unit = "mm", value = 90.0 }
dir = { label = "slider line direction", unit = "deg", value = 25.0, kind = "angle" }
e6 = { label = "offset of the slide", unit = "mm", value = 10.0, kind = "offset" }
side = { label = "side of C", unit = "-", value = -1, kind = "branch" }
br = { label = "branch", unit = "-", value = 1, kind = "branch" }
[mechanism]
input = { key = "t", symbol = "t" }
ground = { O = [0, 0], Q = ["a1", "a1/7"], L = [-20, -40], R = [-60, 30] }
links = [["O", "A", "A2"], ["A", "B", "C"], ["Q", "B"], ["C", "S"], ["R", "F", "A2"], ["B", "P"],
         ["A2", "G", "L"], ["A2", "K"]]
trace = "C"
output = "s_S"
steps = [
  { type = "crank", point = "A", pivot = "O", length = "a2" },
  { type = "crank", point = "A2", pivot = "O", length = "0.8*a2", phase = "ph" },
  { type = "dyad", point = "B", p = "A", q = "Q", p_length = "a3", q_length = "a4", branch = "br" },
  { type = "point", point = "C", frame = ["A", "B"], distances = ["a3/2", "a3*0.7"], side = "side" },
  { type = "point", point = "C2", frame = ["B", "Q"], distance = "a4/3", angle = "-ph/2", columns = { theta = { key = "theta_C2" } } },
  { type = "point", point = "C3", frame = ["A", "B"], local = ["a3/3", "-a2/4"] },
  { type = "slider", point = "S", p = "C", length = "d5", through = "L", direction = "dir", branch = -1 },
  { type = "slide", point = "F", p = "A2", pivot = "R", offset = "e6", branch = "br" },
  { type = "dyad", point = "G", p = "L", q = "A2", p_length = "a4", q_length = "a3", branch = -1 },
  { type = "slider", point = "K", p = "A2", length = "d5*0.6", through = "B", along = ["Q", "B"], direction = "dir/3", branch = "br" },
  { type = "slot", point = "P", slot_through = "B", slot_frame = ["Q", "B"], slot_angle = 70, through = "L", direction = "dir" },
  { type = "vector", from = "C", to = "S", key = "rod" },
  { type = "distance", between = ["C3", "S"], key = "d_CS" },
  { type = "expression", key = "ratio", formula = "d_CS/s_rod + IF(s_S > 0, 1, -1)" },
  { type = "expression", key = "k", formula = "SQRT(a1^2 + a2^2)/MAX(a3, a4)", unit = "-" },
  { type = "triad", points = ["X1", "X2", "X3"], pivots = ["A", "Q", "R"], lengths = [104.043, 92.195, 155.322], sides = [72.111, 25.0, 68.007], sketch = [[110, 60], [50, 100], [70, 115]], iterations = 5, columns = { theta_X1X2 = { key = "tern", symbol = "θt" } } },
]
"""


def _every_option(drop: tuple[str, ...] = (), **values) -> templates.Template:
    """EVERY_OPTION with these parameter values, without the steps of the types in `drop`."""
    data = tomllib.loads(EVERY_OPTION)
    steps = data["mechanism"]["steps"]
    steps[:] = [s for s in steps if s["type"] not in drop]
    for k, v in values.items():
        data["parameters"][k]["value"] = v
    return templates.from_data("every-option", data)


def test_every_option_of_every_step_type_is_verified():
    t = _every_option()
    assert {s["type"] for s in t.mechanism.description["steps"]} == set(
        __import__("linkbook.language.steps", fromlist=["STEP_KEYS"]).STEP_KEYS)
    b, values = builder.make(t)
    checks = checks_of(b, values)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
    assert not bad, bad[:5]
    assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))
    assert "k" in b.meta["constants"] and "ratio" in b.meta["sweep"]["columns"]
    # two transmission angles and two four-bar loops on the ground, the second with its crank
    # pin at the dyad's q end: each with its own summary rows, each checked above
    summary = b.meta["summary"]
    assert {"mu_min", "mu2_max", "fb_ground", "grashof2", "limit2_folded_2"} <= set(summary)
    assert values[("Mechanism", summary["fb2_coupler"]["cell"])] == pytest.approx(80.0)


@pytest.mark.slow        # many random books, each built and verified
def test_every_option_on_random_dimensions():
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    @settings(max_examples=examples(30), deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow])
    @given(st.fixed_dictionaries({
        "a2": st.floats(5, 60), "a3": st.floats(20, 120), "a4": st.floats(20, 120),
        "ph": st.floats(-180, 180), "d5": st.floats(10, 150), "dir": st.floats(-180, 180),
        "e6": st.floats(-40, 40), "side": st.sampled_from([1, -1]),
        "br": st.sampled_from([1, -1])}))
    def check(values):
        # the triad's random dimensions are test_triad_book's (its rows near a limit position
        # make the judge take many slopes: it would double this test's time)
        b, computed = builder.make(_every_option(drop=("triad",), **values))
        checks = checks_of(b, computed)
        bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
        assert not bad, (values, bad[:5])
        assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))

    check()


def test_a_long_description_fits_the_build_record(tmp_path):
    """The record (with the description) is split across cells: Excel holds 32,767 characters in
    one. Forty extra steps make it longer than that; the saved book still verifies."""
    from linkbook.check.verifier import verify
    data = fourbar_data()
    data["mechanism"].pop("columns")
    data["sweep"]["step"] = 30              # the record's length is the point, not the rows
    for i in range(40):
        data["mechanism"]["steps"].append(
            {"type": "point", "point": f"K{i}", "frame": ["A", "B"], "local": [i, -i],
             "columns": {"x": {"label": "a long label " * 20}, "y": {"label": "y " * 100}}})
    t = templates.from_data("long", data)
    path = tmp_path / "long.xlsx"
    builder.build_file(t, path)
    import openpyxl
    record = openpyxl.load_workbook(path)["linkbook"]
    assert isinstance(record["A3"].value, str)       # the record did need a second cell
    assert all(len(c.value) <= 32_767 for c in record["A"] if isinstance(c.value, str))
    assert verify(path).ok


def _boom_data() -> dict:
    return tomllib.loads((templates.TEMPLATE_DIR / "boom-cylinder.toml").read_text(encoding="utf-8"))


def test_a_linear_actuator_sweeps_a_length():
    """The boom's input is the cylinder's length: the sweep's first column and the current
    position are lengths, the dyad's side follows them, and everything is verified."""
    t = templates.with_overrides(templates.load("boom-cylinder"), step="25")
    b, values = builder.make(t)
    checks = checks_of(b, values)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
    assert not bad, bad[:5]
    assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))
    sweep = b.workbook["Sweep"]
    assert sweep["A4"].value == "s [mm]" and sweep["A5"].value == 600
    assert b.workbook["Mechanism"]["J7"].value == "mm"
    assert list(b.meta["sweep"]["columns"])[0] == "s"
    # the dyad's side |CB| is the swept length itself: on every row |CB| = s
    cols, (r0, r1) = b.meta["sweep"]["columns"], b.meta["sweep"]["rows"]
    for r in range(r0, r1 + 1):
        s = sweep[f"A{r}"].value
        xb, yb = values[("Sweep", f"{cols['xB']}{r}")], values[("Sweep", f"{cols['yB']}{r}")]
        assert ((xb - 250.0) ** 2 + (yb + 500.0) ** 2) ** 0.5 == pytest.approx(s, rel=1e-12)


def test_a_grid_needs_a_crank():
    data = _boom_data()
    data["grid"] = {"parameter": "b", "output": "yT", "values": [700, 800]}
    with pytest.raises(InputError) as caught:
        templates.from_data("boom", data, origin="boom.toml")
    assert "grid" in str(caught.value) and "input is a length" in str(caught.value)


def test_a_bad_step_of_a_length_sweep_says_its_unit():
    with pytest.raises(InputError) as caught:
        templates.with_overrides(templates.load("boom-cylinder"), step="-5")
    assert "positive length in mm" in str(caught.value)


GARAGE_TOML = (templates.TEMPLATE_DIR / "garage-door.toml").read_text(encoding="utf-8")


def test_a_length_that_comes_out_negative_is_refused_at_build(tmp_path, capsys):
    """|CD| = a6 − 200 is −50 mm with the template's a6 = 150: the loop cannot be assembled
    (the reference says so), so build refuses with one line naming the step's field."""
    from linkbook.apps.cli import main
    (tmp_path / "mine.toml").write_text(
        GARAGE_TOML.replace('p_length = "a6"', 'p_length = "a6 - 200"'), encoding="utf-8")
    code = main(["build", str(tmp_path / "mine.toml"), "-o", str(tmp_path / "mine.xlsx")])
    err = capsys.readouterr().err
    assert code == 2 and err == ("linkbook: error: mine.toml: mechanism.steps[3] (dyad C)."
                                 "p_length: 'a6 - 200' = -50 mm with these parameters; a length "
                                 "must be positive\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml"]
    for raw, shown in (("a1 - a1", "0 mm"), ("SQRT(a1 - 200)", "not a number")):
        data = tomllib.loads(GARAGE_TOML)
        step(data, "D")["length"] = raw
        with pytest.raises(InputError, match=f"(crank D).length: '{raw}' = {shown}".replace(
                "(", r"\(").replace(")", r"\)")):
            templates.from_data("bad", data, origin="bad.toml")


def test_a_length_made_negative_in_the_book_is_na_where_the_reference_says_so(tmp_path):
    """The same length, positive in the template (a6 = 350: |CD| = 150) and then made −50 by
    editing a6 in the book: the cells of the dyad C are #N/A, and verify agrees with the
    reference, which cannot assemble that loop either."""
    import openpyxl
    import linkbook
    text = GARAGE_TOML.replace('p_length = "a6"', 'p_length = "a6 - 200"').replace(
        "value = 150.0", "value = 350.0")
    (tmp_path / "mine.toml").write_text(text, encoding="utf-8")
    book = linkbook.build(str(tmp_path / "mine.toml"), tmp_path / "mine.xlsx")
    assert linkbook.verify(book).status == 0
    wb = openpyxl.load_workbook(book)
    sheet, cell = wb.defined_names["a_6"].attr_text.replace("$", "").split("!")
    wb[sheet.strip("'")][cell].value = 150.0
    wb.save(book)
    report = linkbook.verify(book)
    assert report.status == 0, report.differing
    closing = next(c for c in report.checks if c.name == "xC")
    assert closing.na_expected == closing.cells > 0


def _runs(angles, closes) -> list[tuple[float, float]]:
    runs = []
    for i, (angle, ok) in enumerate(zip(angles, closes)):
        if ok:
            continue
        if runs and not closes[i - 1]:
            runs[-1] = (runs[-1][0], angle)
        else:
            runs.append((angle, angle))
    return runs


@pytest.mark.parametrize("door", [10.0, 1.0])
def test_a_loop_that_cannot_close_is_named_with_where_at_build(tmp_path, capsys, door):
    """|CD| = 10 mm: the garage door's dyad C closes over part of the turn only (|CD| = 1 mm:
    nowhere). Build still writes the book (exit 0) and says, in one line on stderr, which step
    fails and over which angles — the angles where the independent reference cannot assemble
    the mechanism."""
    import numpy as np
    from linkbook.check import reference as generic
    from linkbook.apps.cli import main
    path = tmp_path / "door.toml"
    path.write_text(GARAGE_TOML.replace("value = 150.0", f"value = {door}"), encoding="utf-8")
    t = templates.load(str(path))
    angles = t.sweep.angles()
    closes = generic.solve(t.mechanism.description, t.values(), np.array(angles))["assembled"]
    assert not closes.all()
    runs = _runs(angles, closes)
    if closes.any():
        spans = ", ".join(f"from {a:g}° to {b:g}°" for a, b in runs)
        where = f"for θ12 {spans} ({int((~closes).sum())} of {len(angles)} rows)"
    else:
        where = f"at any θ12 of the sweep ({angles[0]:g}° to {angles[-1]:g}°)"
    for command in (["build", str(path), "-o", str(tmp_path / "door.xlsx")],
                    ["check", str(path)]):
        assert main(command) == 0
        err = capsys.readouterr().err
        assert err == (f"linkbook: warning: door.toml: mechanism.steps[3] (dyad C): the loop "
                       f"cannot close {where}; every cell that depends on it is #N/A there\n")
    assert (tmp_path / "door.xlsx").is_file()


@pytest.mark.parametrize("door, expected", [(10.0, None), (150.0, "—")])
def test_the_summary_names_the_first_loop_step_that_cannot_close(door, expected):
    """The geometry summary's live cell names the first loop step (in order) that cannot close
    somewhere in the sweep: the first step whose point the reference cannot place on some row;
    a dash where every loop closes."""
    import numpy as np
    from linkbook.check import reference as generic
    t = templates.from_data("door", tomllib.loads(GARAGE_TOML.replace(
        "value = 150.0", f"value = {door}")))
    ref = generic.solve(t.mechanism.description, t.values(), np.array(t.sweep.angles()))
    if expected is None:
        loops = [s for s in t.mechanism.description["steps"]
                 if s["type"] in ("dyad", "slider", "slide", "slot")]
        expected = next(f"{s['type']} {s['point']}" for s in loops
                        if not np.isfinite(ref["points"][s["point"]][0]).all())
    b, values = builder.make(t)
    cell = b.meta["summary"]["failing_step"]["cell"]
    assert values[("Mechanism", cell)] == expected
    assert not [m for c in checks_of(b, values) for m in c.mismatches]


def test_a_mechanism_that_closes_everywhere_builds_without_a_warning(tmp_path, capsys):
    from linkbook.apps.cli import main
    assert main(["build", "garage-door", "-o", str(tmp_path / "door.xlsx")]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("b0", ['["a1", 0]', '[0, "a1"]'])
def test_an_angle_output_gives_its_range_and_swing_in_degrees(b0):
    """A rocker's swing is a four-bar's design number: output = "theta14" gives the summary
    its smallest and largest value and the swing, in degrees, in the degree view's window
    (with the ground turned 90°, the rocker swings across 180°: still one piece). Expected
    values: the reference's rocker angle, unwrapped."""
    import numpy as np
    from linkbook.check import reference as generic
    data = fourbar_data()
    data["mechanism"]["output"] = "theta14"
    data["mechanism"]["ground"]["B0"] = json.loads(b0)
    t = templates.from_data("rocker", data)
    ref = generic.solve(t.mechanism.description, t.values(), np.array(t.sweep.angles()))
    (bx, by), (ox, oy) = ref["points"]["B"], ref["points"]["B0"]
    rocker = np.degrees(np.unwrap(np.arctan2(by - oy, bx - ox)))    # angle of B0→B
    b, values = builder.make(t)
    got = {k: values[("Mechanism", b.meta["summary"][f"output_{k}"]["cell"])]
           for k in ("min", "max", "swing")}
    assert got["swing"] == pytest.approx(np.ptp(rocker), abs=1e-9)
    assert (got["min"] - rocker.min()) % 360 == pytest.approx(0, abs=1e-9)
    assert got["max"] - got["min"] == pytest.approx(np.ptp(rocker), abs=1e-9)
    assert not [m for c in checks_of(b, values) for m in c.mismatches]


def _zero_terms(wb) -> list[str]:
    """Formula cells holding a term multiplied by a literal zero (-0*SIN(…), +0*COS(…))."""
    import re
    zero_term = re.compile(r"(?<![\w.$])0\*")
    return [f"{ws}!{cell}" for ws, cell in formula_cells(wb)
            if zero_term.search(wb[ws][cell].value)]


@pytest.mark.parametrize("local", [('"u"', "0"), ("0", '"u"')])
def test_a_zero_local_coordinate_writes_no_zero_term(local):
    """hoeken's coupler point P (local = [u, 0]) and its coupler's centre (local = [u/2, 0]),
    and the same with the coordinates swapped: x of P is A's x plus u·COS(angle), nothing
    times zero, and the book still agrees with the reference."""
    text = (ROOT / "templates" / "hoeken.toml").read_text(encoding="utf-8")
    assert 'local = ["u", 0]' in text and 'local = ["u/2", 0]' in text
    u, v = local
    text = text.replace('local = ["u", 0]', f"local = [{u}, {v}]").replace(
        'local = ["u/2", 0]', f"local = [{u.replace('u', 'u/2')}, {v.replace('u', 'u/2')}]")
    t = templates.from_data("hoeken", tomllib.loads(text), origin="hoeken.toml")
    b, values = builder.make(t)
    assert _zero_terms(b.workbook) == []
    xp = b.workbook["Sweep"][f"{b.meta['sweep']['columns']['xP']}5"].value
    xa = b.meta["sweep"]["columns"]["xA"]
    angle = "COS" if u != "0" else "SIN"
    assert xp.startswith(f"={xa}5") and xp.count("u*") == 1 and f"*{angle}(" in xp, xp
    assert all(c.ok for c in checks_of(b, values))
