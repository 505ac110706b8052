"""Bad input of every kind: exit 2, one line naming the field and the value, no file written,
and an existing workbook never left half-written."""
from __future__ import annotations

import os
import re
from pathlib import Path

import openpyxl
import pytest

from conftest import ROOT
from linkbook.book import builder as build_module
from linkbook.apps.cli import main

# the bundled four-bar with its load a plain torque, which the cases below rewrite
FOURBAR_TOML = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8").replace(
    'torque = "-T4*SIGN(omega_theta14)"', 'torque = "T4"')


def _balanced_sum(term: str, levels: int) -> str:
    """2**levels copies of `term` summed as a balanced tree: a long text, nested only `levels`
    deep (an expression may nest 64 levels)."""
    text = term
    for _ in range(levels):
        text = f"({text} + {text})"
    return text

# (what is tried, command-line arguments, TOML text or None, text the one-line message must hold)
COMMAND_LINE = [
    ("negative length", ["--set", "a2=-5"], "a2"),
    ("zero length", ["--set", "a2=0"], "a2"),
    ("word for a number", ["--set", "a2=abc"], "'abc'"),
    ("empty value", ["--set", "a2="], "a2"),
    ("NaN", ["--set", "a2=nan"], "finite"),
    ("infinity", ["--set", "a2=inf"], "finite"),
    ("negative infinity", ["--set", "a3=-inf"], "finite"),
    ("unknown key", ["--set", "a9=3"], "a9"),
    ("unknown key near a known one", ["--set", "a22=3"], "did you mean a2"),
    ("a key in capitals", ["--set", "A2=40"], "--set A2: unknown parameter; did you mean a2?"),
    ("no = in --set", ["--set", "a2"], "KEY=VALUE"),
    ("empty key", ["--set", "=4"], "KEY=VALUE"),
    ("branch not ±1", ["--set", "branch=2"], "branch"),
    ("branch word misspelt", ["--set", "branch=opne"], "branch"),
    ("zero step", ["--step", "0"], "step"),
    ("negative step", ["--step", "-5"], "step"),
    ("word for a step", ["--step", "five"], "step"),
    ("step beyond Excel's rows", ["--step", "0.0001"], "1,048,576"),
    ("not an .xlsx output", ["-o", "out.csv"], "-o"),
    ("output folder missing", ["-o", "no/such/dir/out.xlsx"], "does not exist"),
    ("unknown template", [], "template"),
]

TOML_CASES = [
    ("TOML that does not parse", "mechanism = \n", "not valid TOML"),
    ("mechanism missing", FOURBAR_TOML.replace("[mechanism]", "[mechanisms]"),
     "mine.toml: unknown key 'mechanisms' (did you mean 'mechanism'?)"),
    ("unknown mechanism", 'mechanism = "fivebar"\n' + FOURBAR_TOML[:FOURBAR_TOML.index(
        "[mechanism]")], "fivebar"),
    ("title missing", FOURBAR_TOML.replace('title = ', 'xtitle = '), "title"),
    ("control character in the title", FOURBAR_TOML.replace(
        'title = "Four-bar', 'title = "Four\\u0007bar'),
     "title: contains the control character U+0007"),
    ("U+FFFF in a label", FOURBAR_TOML.replace(
        'label = "rocker |B0B|"', 'label = "rocker \\uFFFF"'),
     "label: contains the character U+FFFF"),
    ("sweep missing", FOURBAR_TOML.replace("[sweep]", "[sweeps]"), "sweep"),
    ("sweep step is text", FOURBAR_TOML.replace("step = 5", 'step = "5"'), "step"),
    ("sweep runs backwards", FOURBAR_TOML.replace("stop = 360", "stop = -10"),
     "mine.toml: sweep: stop must be greater than start"),
    ("sweep step zero", FOURBAR_TOML.replace("step = 5", "step = 0"),
     "mine.toml: sweep.step: must be a positive angle"),
    ("sweep step beyond Excel's rows", FOURBAR_TOML.replace("step = 5", "step = 0.0001"),
     "mine.toml: sweep.step: 0.0001 degrees gives 3,600,002 rows"),
    ("parameter missing", FOURBAR_TOML.replace('c3 = {', 'zz = {'), "zz"),
    ("parameter value missing",
     FOURBAR_TOML.replace(', value = 84.1 }', ' }'), "parameters.c3.value"),
    ("negative length in TOML", FOURBAR_TOML.replace("value = 35.0", "value = -35.0"), "a2"),
    ("NaN in TOML", FOURBAR_TOML.replace("value = 35.0", "value = nan"), "finite"),
    ("a 401-digit integer in an expression",
     FOURBAR_TOML.replace('p_length = "a3"', 'p_length = "a3 + 1' + "0" * 400 + '"'),
     "p_length: must be a finite number (got an integer of 401 digits)"),
    ("label missing", FOURBAR_TOML.replace('a4 = { label = "rocker |B0B|", ', 'a4 = { '),
     "label"),
    ("cell-like Excel name", FOURBAR_TOML.replace('name = "Branch"', 'name = "B3"'),
     "looks like a cell"),
    ("R1C1-like Excel name", FOURBAR_TOML.replace('name = "Branch"', 'name = "R2C3"'),
     "looks like a cell"),
    ("Excel name with a space", FOURBAR_TOML.replace('name = "Branch"', 'name = "my branch"'),
     "name"),
    ("two parameters, one name", FOURBAR_TOML.replace('name = "Branch"', 'name = "a_1"'),
     "already"),
    # what the schema (src/linkbook/language/mechanism.schema.json) refuses, before the semantic checks
    ("a misspelt required key of a step", FOURBAR_TOML.replace('p_length = "a3"',
                                                               'p_lenght = "a3"'),
     "mine.toml: mechanism.steps[1] (dyad B): unknown key 'p_lenght' (did you mean "
     "'p_length'?)"),
    ("a misspelt kind of a parameter", FOURBAR_TOML.replace('kind = "branch"', 'knid = "branch"'),
     "mine.toml: parameters.branch: unknown key 'knid' (did you mean 'kind'?)"),
    ("an unknown key of a parameter", FOURBAR_TOML.replace('a2 = { label', 'a2 = { note = "", '
                                                                          'label'),
     "mine.toml: parameters.a2: unknown key 'note'; known: kind, label, name, unit, value"),
    ("an unknown top-level key", "comment = 'mine'\n" + FOURBAR_TOML,
     "mine.toml: unknown key 'comment'; known: "),
    ("a word for true or false", FOURBAR_TOML.replace("equal_axes = true", 'equal_axes = "yes"'),
     "mine.toml: mechanism.charts[1].equal_axes: must be true or false (got 'yes')"),
    ("a required key missing", FOURBAR_TOML.replace('type = "dyad"', 'tpye = "dyad"'),
     "mechanism.steps[1] (step B).type: is missing ('tpye' is not a key: did you mean "
     "'type'?)"),
    ("a step of an unknown type", FOURBAR_TOML.replace('type = "dyad"', 'type = "tetrad"'),
     "(tetrad B).type: must be one of crank, dyad, slider"),
    ("a symbol that is no identifier", FOURBAR_TOML.replace("a2 = {", "2a = {"),
     "mine.toml: parameters.2a: is not a symbol: letters, digits and _, starting with a letter"),
    ("a link of one point", FOURBAR_TOML.replace('links = [["A0", "A"]', 'links = [["A0"]'),
     "mine.toml: mechanism.links[0]: must have at least 2 entries (got ['A0'])"),
    ("a chart's curve that is no column key", FOURBAR_TOML.replace('y = ["yC"]', 'y = [["yC"]]'),
     "mine.toml: mechanism.charts[1].y[0]: must be text (got ['yC'])"),
    ("a sweep key misspelt", FOURBAR_TOML.replace('step = 5', 'stpe = 5'),
     "mine.toml: sweep: unknown key 'stpe' (did you mean 'step'?)"),
    ("an actuator's length swept through zero", (ROOT / "templates" / "boom-cylinder.toml")
     .read_text(encoding="utf-8").replace("start = 600", "start = -10"),
     "mine.toml: sweep.start: a linear actuator's length must be positive (got -10 mm)"),
    # the force analysis' keys (docs/language.md, "Mass, gravity and loads")
    ("a misspelt key of a body", FOURBAR_TOML.replace('inertia = "I4"', 'inertai = "I4"'),
     "mine.toml: mechanism.bodies[2]: unknown key 'inertai' (did you mean 'inertia'?)"),
    ("a body's joint that is no point", FOURBAR_TOML.replace('joints = ["B0", "B"]',
                                                             'joints = ["B0", "D"]'),
     "mine.toml: mechanism.bodies[2].joints[1]: 'D' is no point of the mechanism"),
    ("a centre's frame outside its link", FOURBAR_TOML.replace(
        'centre = { frame = ["B0", "B"]', 'centre = { frame = ["B0", "C"]'),
     "mine.toml: mechanism.bodies[2].centre.frame: must be two different joints of the link"),
    ("a torque beside a point", FOURBAR_TOML.replace('torque = "T4"', 'torque = "T4"\nat = "C"'),
     "mine.toml: mechanism.loads[0]: must be a table of at and force (body optional), or of "
     "body and torque"),
    ("a load of an unknown symbol", FOURBAR_TOML.replace('torque = "T4"', 'torque = "T5"'),
     "mine.toml: mechanism.loads[0].torque: unknown symbol 'T5'"),
    ("a mass in grams", FOURBAR_TOML.replace('unit = "kg", value = 0.02198',
                                             'unit = "g", value = 21.98'),
     "mine.toml: parameters.m4.unit: must be kg for a mass parameter in a book of mm (got 'g')"),
    ("an inertia in a unit of volume", FOURBAR_TOML.replace('unit = "kg·m²"', 'unit = "kg*m^3"'),
     "mine.toml: parameters.I2.unit: must be kg·m² for an inertia parameter in a book of mm "
     "(got 'kg*m^3')"),
    ("a negative mass", FOURBAR_TOML.replace('value = 0.02198', 'value = -0.02198'),
     "mine.toml: parameters.m4.value: must be zero or more (got -0.02198)"),
    ("a torque written near the least double", FOURBAR_TOML.replace('torque = "T4"',
                                                                    'torque = 2.2e-308'),
     "mine.toml: mechanism.loads[0].torque: must be 0 or from 1e-30 to 1e+30 either way "
     "(got 2.2e-308)"),
    ("gravity misspelt", FOURBAR_TOML.replace('gravity = { g = "g" }', 'gravity = { G = "g" }'),
     "mine.toml: mechanism.dynamics.gravity: unknown key 'G'; known: angle, g"),
    # the defined names the book gives cells of its own (one cell per name, whatever the case)
    ("a parameter named as the current position", FOURBAR_TOML.replace(
        'name = "Branch"', 'name = "theta12_now"'),
     "mine.toml: parameters.branch.name: 'theta12_now' is the book's own name 'theta12_now' "
     "(the current position)"),
    ("a parameter named as metres per unit, in capitals", FOURBAR_TOML.replace(
        'name = "Branch"', 'name = "TO_Metres"'),
     "mine.toml: parameters.branch.name: 'TO_Metres' is the book's own name 'to_metres'"),
    ("a parameter named as Cs", FOURBAR_TOML.replace('name = "Branch"',
                                                     'name = "speed_fluctuation"'),
     "mine.toml: parameters.branch.name: 'speed_fluctuation' is the book's own name"),
    ("a parameter's symbol a derived constant's name", FOURBAR_TOML.replace(
        "a1 = {", 'k_rpm_in = { label = "x", unit = "mm", value = 1.0 }\na1 = {'),
     "mine.toml: parameters.k_rpm_in: 'k_rpm_in' is the book's own name 'k_rpm_in'"),
    ("a parameter's symbol the placeholder of metres per unit", FOURBAR_TOML.replace(
        "a1 = {", 'to_metres = { label = "x", unit = "mm", value = 1.0, name = "tm" }\na1 = {'),
     "mine.toml: parameters.to_metres: 'to_metres' is the book's own name 'to_metres'"),
    # numbers and symbols spelt as verify's reference reads them (base.xlsx.NUMBER_LITERAL)
    ("a load's number with an underscore", FOURBAR_TOML.replace('torque = "T4"',
                                                                'torque = "-1_000"'),
     "mine.toml: mechanism.loads[0].torque: '1_000' is not a number as a formula writes one"),
    ("a hexadecimal number in a length", FOURBAR_TOML.replace('p_length = "a3"',
                                                              'p_length = "a3 + 0x10"'),
     "p_length: '0x10' is not a number as a formula writes one"),
    ("a full-width symbol", FOURBAR_TOML.replace('p_length = "a3"', 'p_length = "ａ3"'),
     "p_length: 'ａ3' is not a symbol: ASCII letters, digits and _ only"),
    # formulas within Excel's limits (base.xlsx.formula_problem, as verify checks a book)
    ("120 loads on one point", FOURBAR_TOML + '\n[[mechanism.loads]]\nat = "C"\nforce = [1, 2]\n'
     * 120, "mine.toml: mechanism.loads: the formula of F34x would be one of 11,953 characters; "
     "Excel's limit is 8,192"),
    ("a load nested 70 functions deep", FOURBAR_TOML.replace(
        'torque = "T4"', 'torque = "' + "ABS(" * 70 + "T4" + ")" * 70 + '"'),
     "mine.toml: mechanism.loads[0].torque: nests 70 brackets inside each other (a sign, a term "
     "of a sum or a bracket is one level); at most 64"),
    ("a load whose formula nests beyond Excel's limit", FOURBAR_TOML.replace(
        'torque = "T4"', 'torque = "' + "ABS(" * 62 + "T4" + ")" * 62 + '"'),
     "mine.toml: mechanism.loads: the formula of F34x would be one nested 67 brackets deep; "
     "Excel's limit is 64 levels"),
    ("a step's length too long for a cell", FOURBAR_TOML.replace(
        'p_length = "a3"', 'p_length = "' + _balanced_sum("a3", 7) + '"').replace(
        'value = 62.3 }', 'value = 62.3, name = "coupler_' + "x" * 60 + '" }'),
     "mine.toml: mechanism.steps[2] (point C): the formula of gamma would be one of 26,585 "
     "characters"),      # (the point's angle reads that length: the first cell written over)
    # loads that are numbers on some row, TRUE or FALSE on none, angles within ±360°
    ("a load of NA()", FOURBAR_TOML.replace('torque = "T4"', 'torque = "NA()"'),
     "mine.toml: mechanism.loads[0].torque: 'NA()' is an error (#N/A, #DIV/0!, #NUM!) on every "
     "row with these parameters"),
    ("a load of 1/0", FOURBAR_TOML.replace('torque = "T4"', 'torque = "T4 + 1/0"'),
     "mine.toml: mechanism.loads[0].torque: 'T4 + 1/0' is an error"),
    ("a load of a column over 0", FOURBAR_TOML.replace(
        'torque = "T4"', 'torque = "IF(a2 > 1, xB/0, NA())"'),
     "mine.toml: mechanism.loads[0].torque: 'IF(a2 > 1, xB/0, NA())' is an error"),
    ("a mass of NA()", FOURBAR_TOML.replace('mass = "m2"', 'mass = "m2*NA()"'),
     "mine.toml: mechanism.bodies[0].mass: 'm2*NA()' is an error"),
    ("a load that is a comparison", FOURBAR_TOML.replace('torque = "T4"', 'torque = "T4==T4"'),
     "mine.toml: mechanism.loads[0].torque: 'T4==T4' is a comparison, TRUE or FALSE"),
    ("a load's angle of 1e300", FOURBAR_TOML.replace(
        'torque = "T4"', 'at = "B"\nforce = { magnitude = "T4", angle = 1e300 }'),
     "mine.toml: mechanism.loads[0].force.angle: must be an angle from -360 to 360 degrees "
     "(got 1e+300)"),
    ("parameter not a table", FOURBAR_TOML.replace(
        'a1 = { label = "ground link |A0B0|", unit = "mm", value = 70.0 }', "a1 = 70"), "a1"),
    # deep nesting and long expressions: refused before anything recurses once per level
    ("a table header nested 2,000 deep", FOURBAR_TOML + "\n[" + ".".join(["a"] * 2000) + "]\n",
     "mine.toml: " + ".".join(["a"] * 33) + ": tables and lists nest more than 32 deep"),
    ("a step's column nested 2,000 deep", FOURBAR_TOML.replace(
        'columns.x.label = "crank pin A"', "columns.x." + ".".join(["a"] * 2000) + ' = "A"'),
     "mine.toml: mechanism.steps[0].columns.x." + ".".join(["a"] * 28) + ": tables and lists "
     "nest more than 32 deep"),
    ("5,000 leading minus signs in a length", FOURBAR_TOML.replace(
        'p_length = "a3"', 'p_length = "' + "-" * 5000 + 'a3"'),
     "mine.toml: mechanism.steps[1] (dyad B).p_length: is 5,002 characters long; an "
     "expression may have at most 1,000"),
    ("5,000 leading minus signs in a load", FOURBAR_TOML.replace(
        'torque = "T4"', 'torque = "' + "-" * 5000 + 'T4"'),
     "mine.toml: mechanism.loads[0].torque: is 5,002 characters long"),
    ("20,000 terms", FOURBAR_TOML.replace('p_length = "a3"', 'p_length = "' + "+".join(
        ["a3"] * 20_000) + '"'), "(dyad B).p_length: is 59,999 characters long"),
    ("998 minus signs, within the length", FOURBAR_TOML.replace(
        'p_length = "a3"', 'p_length = "' + "-" * 998 + 'a3"'),
     "(dyad B).p_length: nests 999 operations inside each other (a sign, a term of a sum or a "
     "bracket is one level); at most 64"),
    ("a sum of 65 terms", FOURBAR_TOML.replace('p_length = "a3"', 'p_length = "' + "+".join(
        ["a3"] * 65) + '"'), "(dyad B).p_length: nests 65 operations inside each other"),
    ("65 brackets deep", FOURBAR_TOML.replace(
        'p_length = "a3"', 'p_length = "' + "(" * 65 + "a3" + ")" * 65 + '"'),
     "(dyad B).p_length: nests 65 brackets inside each other"),
]


def _run(tmp_path: Path, args: list[str], capsys) -> tuple[int, str]:
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        code = main(args)
    finally:
        os.chdir(cwd)
    return code, capsys.readouterr().err


def _assert_refused(tmp_path, code, err, must_hold, before):
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("linkbook: error: "), err
    assert must_hold in lines[0], lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "a file was left behind"


@pytest.mark.parametrize("what,args,must_hold", COMMAND_LINE, ids=[c[0] for c in COMMAND_LINE])
def test_bad_command_line(tmp_path, capsys, what, args, must_hold):
    name = "fivebar" if what == "unknown template" else "fourbar"
    code, err = _run(tmp_path, ["build", name, *args], capsys)
    _assert_refused(tmp_path, code, err, must_hold, [])


@pytest.mark.parametrize("what,text,must_hold", TOML_CASES, ids=[c[0] for c in TOML_CASES])
def test_bad_template_file(tmp_path, capsys, what, text, must_hold):
    (tmp_path / "mine.toml").write_text(text, encoding="utf-8")
    code, err = _run(tmp_path, ["build", "mine.toml", "-o", "mine.xlsx"], capsys)
    _assert_refused(tmp_path, code, err, must_hold, ["mine.toml"])


def test_the_older_form_names_a_bundled_mechanism(tmp_path, capsys):
    """A template written before the mechanism language (`mechanism = "fourbar"`, parameters
    without kinds) still builds: the name stands for the bundled description."""
    old = 'mechanism = "fourbar"\n' + FOURBAR_TOML[:FOURBAR_TOML.index("[mechanism]")]
    old = old.replace(', kind = "branch"', "")
    (tmp_path / "old.toml").write_text(old, encoding="utf-8")
    code, err = _run(tmp_path, ["build", "old.toml", "-o", "old.xlsx", "--set", "a2=30"], capsys)
    assert code == 0, err
    assert (tmp_path / "old.xlsx").is_file()


LOAD = 'body = ["B0", "B"]\ntorque = "T4"'


@pytest.mark.parametrize("load, line", [
    ('at = "C"\nforce = { magnitude = "T4", angel = 30 }',
     "mine.toml: mechanism.loads[0].force: unknown key 'angel' (did you mean 'angle'?)"),
    (LOAD + '\nat = "C"\nforce = ["T4", 0]',
     "mine.toml: mechanism.loads[0]: must be a table of at and force (body optional), or of "
     "body and torque (got a table of body, torque, at and force)"),
], ids=["a polar force's angle misspelt", "a load of a force and a torque"])
def test_a_load_that_fits_no_form_is_named_in_one_plain_line(tmp_path, capsys, load, line):
    """The line names the key or the keys, never a Python dict ({'magnitude': ...})."""
    assert FOURBAR_TOML.count(LOAD) == 1
    (tmp_path / "mine.toml").write_text(FOURBAR_TOML.replace(LOAD, load), encoding="utf-8")
    code, err = _run(tmp_path, ["build", "mine.toml", "-o", "mine.xlsx"], capsys)
    _assert_refused(tmp_path, code, err, line, ["mine.toml"])
    assert err.strip() == f"linkbook: error: {line}"


# the issue's `../own/x.tml`, run in a folder of tmp_path (its parent is tmp_path), written in
# parts: a quoted parent-folder literal is how test_standalone finds a path leaving the repo
UP = str(Path("..") / "own" / "x.tml")


@pytest.mark.parametrize("target, line", [
    (UP, f"template: no such file {UP!r} (a template is a .toml file, not .tml)"),
    ("own/mine.toml", "template: no such file 'own/mine.toml'"),
    ("own/fourbar", "template: no such file 'own/fourbar'"),
])
def test_a_missing_template_file_is_named_as_a_file(tmp_path, capsys, target, line):
    """A path (a folder or a suffix in it) is a file the user means, never an unknown bundled
    template; a suffix other than .toml is named."""
    (tmp_path / "here").mkdir()
    code, err = _run(tmp_path / "here", ["build", target], capsys)
    _assert_refused(tmp_path / "here", code, err, line, [])
    assert err.strip() == f"linkbook: error: {line}"


def _mechanism_units(book: Path) -> list:
    ws = openpyxl.load_workbook(book)["Mechanism"]
    return [ws.cell(r, 4).value for r in range(1, ws.max_row + 1)]


@pytest.mark.parametrize("spelling", [("kg*m^2", "N*m", "m/s^2"), ("kg m^2", "N m", "m/s**2"),
                                      ("kg.m^2", "N.m", "m / s^2")])
def test_units_typed_without_dot_and_square_are_the_books(tmp_path, capsys, spelling):
    """`kg*m^2`, `N*m`, `m/s^2` (a keyboard's spellings) are kg·m², N·m and m/s²: the book is
    the bundled template's, its units written as the book always shows them."""
    inertia, torque, acceleration = spelling
    text = FOURBAR_TOML.replace('unit = "kg·m²"', f'unit = "{inertia}"').replace(
        'unit = "N·m"', f'unit = "{torque}"').replace('unit = "m/s²"', f'unit = "{acceleration}"')
    assert "kg·m²" not in text and "N·m" not in text.split("[mechanism]")[0]
    (tmp_path / "mine.toml").write_text(text, encoding="utf-8")
    (tmp_path / "bundled.toml").write_text(FOURBAR_TOML, encoding="utf-8")
    for name in ("mine", "bundled"):
        code, err = _run(tmp_path, ["build", f"{name}.toml", "-o", f"{name}.xlsx"], capsys)
        assert code == 0, err
    units = _mechanism_units(tmp_path / "mine.xlsx")
    assert units == _mechanism_units(tmp_path / "bundled.xlsx")
    assert {"kg·m²", "N·m", "m/s²"} <= set(units)


def test_at_least_25_kinds_of_bad_input_are_tried():
    assert len(COMMAND_LINE) + len(TOML_CASES) >= 25


def test_text_from_a_template_stays_text(tmp_path, capsys):
    text = FOURBAR_TOML.replace('label = "crank |A0A|"', 'label = "=1+1 crank"').replace(
        'title = "Four-bar mechanism with coupler point C"', 'title = "=HYPERLINK(\\"x\\")"')
    (tmp_path / "mine.toml").write_text(text, encoding="utf-8")
    code, err = _run(tmp_path, ["build", "mine.toml", "-o", "mine.xlsx"], capsys)
    assert code == 0, err
    ws = openpyxl.load_workbook(tmp_path / "mine.xlsx")["Mechanism"]
    cells = {c.value: c.data_type for row in ws.iter_rows() for c in row
             if isinstance(c.value, str) and ("=1+1" in c.value or "HYPERLINK" in c.value)}
    assert cells == {"=1+1 crank": "s", '=HYPERLINK("x")': "s"}


def test_a_failed_build_leaves_the_earlier_file_intact(tmp_path, monkeypatch):
    """Simulate a build killed while writing: the save writes half a file, then dies."""
    target = tmp_path / "fourbar.xlsx"
    assert main(["build", "fourbar", "-o", str(target)]) == 0
    before = target.read_bytes()

    def half_then_die(self, filename):
        Path(filename).write_bytes(b"PK\x03\x04 half a zip")
        raise KeyboardInterrupt("killed mid-write")

    monkeypatch.setattr(openpyxl.Workbook, "save", half_then_die)
    assert main(["build", "fourbar", "--set", "a2=40", "-o", str(target)]) == 130
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["fourbar.xlsx"]   # no temporary left
    openpyxl.load_workbook(target)


def test_write_atomic_never_exposes_a_partial_file(tmp_path):
    target = tmp_path / "book.xlsx"
    target.write_bytes(b"old")

    def write(tmp):
        tmp.write_bytes(b"partial")
        assert target.read_bytes() == b"old"   # the target is untouched while writing
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        build_module.write_atomic(target, write)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["book.xlsx"]


# ---------------------------------------------------------------- deep and long, quickly
def test_deep_and_long_input_is_refused_before_the_work_that_recurses(tmp_path, capsys,
                                                                       monkeypatch):
    """Refused before the steps whose cost grows with the depth: the schema's check (which
    recursed in jsonschema) and Python's parser (which recursed once per sign)."""
    import ast

    from linkbook.language import expressions, schema

    def never(*args, **kwargs):
        raise AssertionError("reached the work the limit guards")

    monkeypatch.setattr(schema, "problem", never)
    (tmp_path / "mine.toml").write_text(FOURBAR_TOML.replace(
        'columns.x.label = "crank pin A"', "columns.x." + ".".join(["a"] * 2000) + ' = "A"'),
        encoding="utf-8")
    code, err = _run(tmp_path, ["check", "mine.toml"], capsys)
    assert code == 2 and "nest more than 32 deep" in err, err
    monkeypatch.undo()

    class ParserOfShortTexts:       # the language's `ast`, whose parse refuses a long text
        def __getattr__(self, name):
            return getattr(ast, name)

        @staticmethod
        def parse(text, *args, **kwargs):
            if len(text) > expressions.LENGTH_LIMIT:
                never()
            return ast.parse(text, *args, **kwargs)

    monkeypatch.setattr(expressions, "ast", ParserOfShortTexts())
    (tmp_path / "mine.toml").write_text(FOURBAR_TOML.replace(
        'p_length = "a3"', 'p_length = "' + "-" * 5000 + 'a3"'), encoding="utf-8")
    code, err = _run(tmp_path, ["check", "mine.toml"], capsys)
    assert code == 2 and "is 5,002 characters long" in err, err


# At the limit (64 levels, 64 brackets), the language writes the expression and the reference
# reads it; the values are the algebra's.
AT_THE_LIMIT = [("-" * 63 + "a", -2.0), ("+".join(["a"] * 64), 128.0),
                ("(" * 64 + "a" + ")" * 64, 2.0), ("a" + "^1" * 63, 2.0)]


@pytest.mark.parametrize("text,value", AT_THE_LIMIT, ids=["signs", "terms", "brackets", "powers"])
def test_an_expression_at_the_limit_is_written_and_read(text, value):
    from linkbook.check.reference.expressions import evaluate
    from linkbook.language.expressions import expression, value_of
    expression("f", text, {"a"})
    assert value_of(text, {"a": 2.0}) == value
    assert evaluate(text, {"a": 2.0}) == value


@pytest.mark.parametrize("text,message", [
    ("-" * 5000 + "a", "an expression of 5,001 characters (at most 1,000)"),
    ("+".join(["a"] * 20_000), "an expression of 39,999 characters"),
    ("-" * 999 + "a", "more than 128 signs, brackets and powers nested"),
    ("+".join(["a"] * 400), "more than 128 operations nested"),
    ("a" + "^a" * 400, "more than 128 signs, brackets and powers nested"),
    ("(" * 65 + "a" + ")" * 65, "brackets nested more than 64 deep"),
], ids=["5,000 signs", "20,000 terms", "999 signs", "400 terms", "400 powers", "65 brackets"])
def test_the_reference_refuses_what_would_exhaust_its_stack(text, message):
    """The reference reads a book's recorded expressions with a reader of its own: a hostile
    record is refused there too, in one line, not with RecursionError."""
    from linkbook.check.reference.expressions import evaluate
    with pytest.raises(ValueError, match=re.escape(message)):
        evaluate(text, {"a": 2.0})


def _edited_book(tmp_path: Path, part: str, old: str, new: str) -> Path:
    """The bundled four-bar with one text of one part replaced."""
    from test_xlsx import _rewrite
    built = tmp_path / "built.xlsx"
    assert main(["build", "fourbar", "-o", str(built)]) == 0
    path = tmp_path / "fourbar.xlsx"
    built.rename(path)
    _rewrite(path, part, old, new)
    return path


def test_a_recorded_expression_of_5000_signs_is_refused_by_verify(tmp_path, capsys):
    path = _edited_book(tmp_path, "xl/sharedStrings.xml", '"p_length": "a3"',
                        '"p_length": "' + "-" * 5000 + 'a3"')
    capsys.readouterr()
    assert main(["verify", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].endswith(
        "mechanism.steps[1] (dyad B).p_length: is 5,002 characters long; an expression may "
        "have at most 1,000"), lines


@pytest.mark.parametrize("signs,code", [(5000, 0), (5001, 1)])
def test_a_formula_of_5000_signs_is_one_operator_to_the_engine(tmp_path, capsys, signs, code):
    """A run of signs is one operator for the engine's grammar (no recursion per sign): an even
    run leaves the cell's value as it was, an odd one negates it, and verify says so."""
    cell = '<c r="N8" s="8"><f>I17</f>'
    path = _edited_book(tmp_path, "xl/worksheets/sheet1.xml", cell,
                        cell.replace("I17", "-" * signs + "I17"))
    capsys.readouterr()
    assert main(["verify", str(path)]) == code
    out = capsys.readouterr().out
    assert ("likely cause Mechanism!N8" in out) == (code == 1), out
