"""Motion and path generation end to end (issue 38): a template's [synthesis] task of kind
"motion" or "path", the Synthesis sheet that designs the four-bar by the textbook's standard
dyad form in live formulas, the analysis sheets that read the designed cells, and verify
judging all of it.

Expected values come from the independent reference (check/reference/synthesis_motion.py,
which solves for the pivots themselves and is checked against pylinkage and the position
reference in test_synthesis_motion.py), from the four-bar that made the poses (placed by the
position reference), and from LibreOffice; never from the writer.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from conftest import examples
from test_synthesis_motion import linkages, placed

from linkbook.base.errors import InputError
from linkbook.base.sheets import SYNTHESIS, SYNTHESIS_WORDS
from linkbook.book import builder
from linkbook.check.reference.fourbar import grashof_class
from linkbook.check.reference.synthesis_motion import motion_generation, path_generation
from linkbook.check.verifier import verify
from linkbook.engine import evaluator as engine
from linkbook.language.templates import from_data, load

ROOT = Path(__file__).resolve().parents[1]
TEMPLATES = {kind: ROOT / "templates" / f"{name}.toml"
             for kind, name in (("motion", "motion-3pose"), ("path", "path-timing"))}
EXAMPLES = examples(100)
EPS = 2.2e-16


def _data(kind: str, **task) -> dict:
    data = tomllib.loads(TEMPLATES[kind].read_text(encoding="utf-8"))
    data["synthesis"] = {**data["synthesis"], **task}
    return data


def _is_na(value) -> bool:
    return not isinstance(value, (int, float)) and "N/A" in str(value)


class Book:
    """A bundled synthesis book built once (`pivots`: with both fixed pivots given instead of
    the rotations); each task is typed into its input cells and its Synthesis sheet evaluated
    again by the vector engine, as a user's edit would be."""

    def __init__(self, kind: str, pivots: bool = False):
        self.built, _ = builder.make(load(str(TEMPLATES[kind])) if not pivots else
                                     from_data("pivots", _with_pivots(_data(kind))))
        self.syn = self.built.record.synthesis
        self.wanted = {(SYNTHESIS, c) for c in self.syn.cells.values()} | {
            (SYNTHESIS, c) for cells in self.syn.points.values() for c in cells}

    def evaluate(self, inputs: dict[str, float]):
        ws = self.built.workbook[SYNTHESIS]
        for key, value in inputs.items():
            ws[self.syn.inputs[key]].value = float(value)
        values = engine.evaluate(self.built.workbook, only=self.wanted)
        cell = lambda key: values[(SYNTHESIS, self.syn.cells[key])]      # noqa: E731
        column = lambda key: [values[(SYNTHESIS, c)] for c in self.syn.points[key]]  # noqa
        return cell, column


def _with_pivots(data: dict) -> dict:
    """A motion task with both fixed pivots given (Norton §5.9) instead of the rotations."""
    task = {k: v for k, v in data["synthesis"].items() if k not in ("beta", "gamma")}
    return {**data, "synthesis": {**task, "pivots": {"crank": [0.0, 0.0],
                                                     "rocker": [150.0, -30.0]}}}


@pytest.fixture(scope="module")
def books() -> dict[str, Book]:
    return {**{kind: Book(kind) for kind in TEMPLATES}, "pivots": Book("motion", pivots=True)}


def _degrees(angle) -> np.ndarray:
    """Radians as degrees in (−180, 180]: a task's angles as a user types them."""
    return 180.0 - np.remainder(180.0 - np.degrees(angle), 360.0)


MODES = ("recover", "recover", "defect", "free", "singular")


@st.composite
def tasks(draw):
    """Three poses made by a random four-bar (the position reference places it) and the free
    choices: read off that placement (the design must be that four-bar), the third pose on
    the other branch (a branch defect), drawn at random (any design: non-Grashof, a link too
    short, ...), or a crank that turns with the coupler (a singular dyad)."""
    params, theta2, where, offset = draw(linkages())
    mode = draw(st.sampled_from(MODES))
    if mode == "defect":
        other = placed({**params, "branch": -params["branch"]}, theta2[2:])
        assume(np.isfinite(other["P"]).all() and abs(other["P"][0] - where["P"][2]) > 1e-3)
        for key in ("P", "theta3", "theta4"):
            where[key] = np.concatenate([where[key][:2], other[key]])
    alpha = where["theta3"] + offset
    rotations = {"beta": theta2[1:] - theta2[0],
                 "gamma": where["theta4"][1:] - where["theta4"][0]}
    if mode == "free":
        drawn = draw(st.lists(st.floats(-3.0, 3.0), min_size=4, max_size=4))
        rotations["beta"], rotations["gamma"] = np.array(drawn[:2]), np.array(drawn[2:])
    if mode == "singular":
        rotations["beta"] = alpha[1:] - alpha[0]
    event(mode)
    return {"x": where["P"].real, "y": where["P"].imag, "alpha": alpha, "params": params,
            "mode": mode, **rotations}


def _inputs(kind: str, task: dict, pivots: bool = False) -> dict[str, float]:
    """The task as the book's input cells hold it (degrees within ±180); `pivots`: the fixed
    pivots of the four-bar that made the poses (moved by task["moved"]) for the rotations."""
    out = {}
    for j in (1, 2, 3):
        out[f"x{j}"], out[f"y{j}"] = task["x"][j - 1], task["y"][j - 1]
    for key in ("beta", "gamma") if not pivots else ():
        for j in (2, 3):
            out[f"{key}{j}"] = float(_degrees(task[key][j - 2]))
    if pivots:
        params, (dx, dy) = task["params"], task["moved"]
        out.update(crank_x=params["ax"] + dx, crank_y=params["ay"] + dy,
                   rocker_x=params["bx"] - dy, rocker_y=params["by"] + dx)
    alpha = task["alpha"] - (task["alpha"][0] if kind == "path" else 0.0)
    for j in (1, 2, 3) if kind == "motion" else (2, 3):     # a path's α_1 is 0
        out[f"alpha{j}"] = float(_degrees(alpha[j - 1]))
    return out


def _reference(kind: str, inputs: dict[str, float]) -> dict:
    x = [inputs[f"x{j}"] for j in (1, 2, 3)]
    y = [inputs[f"y{j}"] for j in (1, 2, 3)]
    beta, gamma = (np.radians([inputs.get(f"{k}2", 0.0), inputs.get(f"{k}3", 0.0)])
                   for k in ("beta", "gamma"))
    if kind == "path":
        return path_generation(x, y, beta, np.radians([inputs["alpha2"], inputs["alpha3"]]),
                               gamma)
    alpha = np.radians([inputs[f"alpha{j}"] for j in (1, 2, 3)])
    if "crank_x" in inputs:
        return motion_generation(x, y, alpha, crank_pivot=(inputs["crank_x"],
                                                           inputs["crank_y"]),
                                 rocker_pivot=(inputs["rocker_x"], inputs["rocker_y"]))
    return motion_generation(x, y, alpha, crank_rotation=beta, rocker_rotation=gamma)


def _bounds(expected: dict, inputs: dict[str, float]) -> tuple[float, float, float]:
    """verify's bounds (docs/verification.md): a length within max(1e-9, 1000·ε·κ)·L, L the
    task's size, κ the dyads' condition; a quantity measured off the shortest link (the
    coupler point, an angle) that times L over it."""
    bound = max(1e-9, 1000 * EPS * expected["condition"])
    points = [abs(complex(inputs[f"x{j}"], inputs[f"y{j}"])) for j in (1, 2, 3)]
    sizes = points + [expected[k] for k in "abcd"] + [abs(complex(*expected[k]))
                                                      for k in ("A0", "B0", "A", "B")]
    size = max(s for s in sizes if math.isfinite(s))
    shortest = min(expected[k] for k in "abc")
    return bound, size, max(1.0, size / shortest)


def _check_book(kind: str, book: Book, task: dict, pivots: bool = False) -> None:
    inputs = _inputs(kind, task, pivots)
    cell, column = book.evaluate(inputs)
    expected = _reference(kind, inputs)
    words = SYNTHESIS_WORDS
    singular = expected["singular"]
    assert (cell("c_system") == words["singular"] or cell("r_system") == words["singular"]) \
        == singular
    if singular:
        assert all(_is_na(cell(f"designed_{role}")) for role in ("crank", "xA0", "branch"))
        return
    if expected["degenerate"]:
        event("degenerate")
        assert cell("short") == words["too short"] and _is_na(cell("designed_crank"))
        return
    bound, size, lever = _bounds(expected, inputs)
    for vector in ("W", "Z", "U", "S"):
        for axis, part in (("x", 0), ("y", 1)):
            assert abs(cell(f"{vector}_{axis}") - expected[vector][part]) <= bound * size
    for key in "abcd":
        assert abs(cell(key) - expected[key]) <= bound * size, key
    for key, part in (("u", 0), ("v", 1)):
        assert abs(cell(key) - expected["coupler_point"][part]) <= bound * size * lever
    assert [float(v) for v in column("at_branch")] == list(expected["branch"])
    assert cell("defect") == words["defect" if expected["branch_defect"] else "no defect"]
    assert cell("grashof") == grashof_class(*(expected[k] for k in "dabc"))
    event(expected["grashof"].split(":")[0])
    gap = np.remainder(np.array(column("at_theta2"), dtype=float)
                       - np.degrees(expected["theta2"]) + 180, 360) - 180
    assert np.abs(gap).max() <= math.degrees(bound * lever)
    sides = {s for s in expected["branch"] if s != 0}
    if len(sides) != 1:
        assert all(_is_na(cell(f"designed_{role}")) for role in ("crank", "u", "branch"))
        return
    # the designed linkage, placed by the position steps at θ2_j, passes through its poses
    for role, key in (("crank", "a"), ("coupler", "b"), ("rocker", "c")):
        assert abs(cell(f"designed_{role}") - expected[key]) <= bound * size
    assert cell("designed_branch") == sides.pop()
    assert cell("largest_miss") <= 1e-9 * size * lever
    assert cell("largest_angle_miss") <= math.degrees(1e-9 * lever)
    if task["mode"] == "recover" and task.get("moved", (0, 0)) == (0, 0):
        # the four-bar that made the poses, on its branch
        params = task["params"]
        assert cell("designed_branch") == params["branch"]
        for role, key in (("crank", "a"), ("coupler", "b"), ("rocker", "c")):
            assert abs(cell(f"designed_{role}") - params[key]) <= 10 * bound * size * lever
        for role, key in (("xA0", "ax"), ("yA0", "ay"), ("xB0", "bx"), ("yB0", "by")):
            assert abs(cell(f"designed_{role}") - params[key]) <= 10 * bound * size * lever


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(tasks())
def test_random_motion_tasks_give_the_references_design_or_na(books, task):
    """The motion book with a random task typed in: W, Z, U, S, the lengths, the coupler
    point, the angles and branch at each pose, the words the reference's within verify's
    bounds; #N/A exactly where nothing is designed; where a linkage is designed, the position
    steps put it on its poses, and it is the four-bar that made them."""
    _check_book("motion", books["motion"], task)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(tasks())
def test_random_path_tasks_give_the_references_design_or_na(books, task):
    """The path book with a random task: its points and the crank's rotations (the timing)
    from the four-bar that made them, the coupler's and rocker's rotations the free choices;
    as for motion generation, with α_1 = 0."""
    _check_book("path", books["path"], task)


@settings(max_examples=examples(30), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(tasks(), st.sampled_from([(0.0, 0.0), (0.0, 0.0), (0.3, -0.2), (-1.0, 2.0)]))
def test_random_motion_tasks_by_fixed_pivots(books, task, moved):
    """A motion book whose dyads take their fixed pivots (Norton §5.9): the pivots of the
    four-bar that made the poses give it back; moved pivots give the reference's design (the
    circle condition, solved by lstsq there and by Cramer's rule on the sheet)."""
    _check_book("motion", books["pivots"], {**task, "moved": moved}, pivots=True)


@pytest.mark.parametrize("kind", TEMPLATES)
def test_the_bundled_book_verifies_and_is_a_grashof_crank_rocker(tmp_path, kind):
    path = tmp_path / f"{kind}.xlsx"
    builder.build_file(load(str(TEMPLATES[kind])), path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    book = Book(kind)
    cell, _ = book.evaluate({})
    inputs = {key: book.built.workbook[SYNTHESIS][c].value
              for key, c in book.syn.inputs.items()}
    expected = _reference(kind, inputs)
    assert expected["grashof"] == "Grashof: crank-rocker" and not expected["branch_defect"]
    assert cell("grashof") == "Grashof: crank-rocker"
    assert cell("defect") == SYNTHESIS_WORDS["no defect"]
    assert cell("largest_miss") < 1e-9 * expected["d"]


def test_editing_a_pose_in_the_book_redesigns_and_verifies(tmp_path):
    """As a user would: the motion book opened with openpyxl, pose 2's angle typed over,
    saved; verify designs the new task with the reference and agrees with every sheet."""
    import openpyxl
    path = tmp_path / "edited.xlsx"
    built = builder.build_file(load(str(TEMPLATES["motion"])), path)
    cell = built.record.synthesis.inputs["alpha2"]
    wb = openpyxl.load_workbook(path)
    wb[SYNTHESIS][cell] = 40.0
    wb.save(path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    task = _data("motion")["synthesis"]
    poses = [list(p) for p in task["poses"]]
    poses[1][2] = 40.0
    x, y, alpha = (np.array([p[k] for p in poses]) for k in range(3))
    after = motion_generation(x, y, np.radians(alpha), crank_rotation=np.radians(task["beta"]),
                              rocker_rotation=np.radians(task["gamma"]))
    assert report.inputs["a2"] == pytest.approx(after["a"], rel=1e-9)
    assert abs(after["a"] - load(str(TEMPLATES["motion"])).values()["a2"]) > 0.1


OUTCOMES = [
    ("motion", "singular: the crank turns with the coupler", {"beta": [-16.3, -4.3]},
     "singular"),
    ("motion", "two equal poses: a link of zero length",
     {"poses": [[73.0, 90.7, 61.9], [73.0, 90.7, 61.9], [-14.6, 54.6, 57.6]]}, "degenerate"),
    ("motion", "branch defect", {"beta": [20, 40], "gamma": [-30, 100]}, "branch_defect"),
    ("path", "non-Grashof, one branch", {"alpha": [10, 20], "gamma": [60, -30]}, None),
]


@pytest.mark.parametrize("kind, what, task, outcome", OUTCOMES, ids=[o[1] for o in OUTCOMES])
def test_every_outcome_verifies(tmp_path, kind, what, task, outcome):
    """verify on books whose tasks end each way: every cell the reference's, or #N/A where
    there is no design (the analysis sheets and the drawing too)."""
    data = _data(kind, **task)
    path = tmp_path / "task.xlsx"
    built = builder.build_file(from_data("task", data), path)
    report = verify(path)
    assert report.status == 0, [(c.block, c.name, c.mismatches[:2]) for c in report.checks
                                if not c.ok]
    inputs = {key: built.workbook[SYNTHESIS][c].value
              for key, c in built.record.synthesis.inputs.items()}
    expected = _reference(kind, inputs)
    if outcome is None:
        assert not expected["grashof"].startswith("Grashof") and not expected["branch_defect"]
    else:
        assert expected[outcome]
    assert math.isnan(report.inputs["a2"]) == (outcome is not None)


@pytest.mark.libreoffice
@pytest.mark.parametrize("kind", TEMPLATES)
def test_libreoffice_recalculates_the_book_to_the_references_numbers(tmp_path, needs, kind):
    needs("libreoffice")
    path = tmp_path / f"{kind}.xlsx"
    builder.build_file(load(str(TEMPLATES[kind])), path)
    report = verify(path, engine="libreoffice")
    assert report.status == 0, report.error or [(c.block, c.name, c.mismatches[:2])
                                                for c in report.checks if not c.ok]


@pytest.mark.gnumeric
def test_gnumeric_recalculates_the_path_book_to_the_references_numbers(tmp_path, needs):
    needs("gnumeric")
    path = tmp_path / "path.xlsx"
    builder.build_file(load(str(TEMPLATES["path"])), path)
    report = verify(path, engine="gnumeric")
    assert report.status == 0, report.error or [(c.block, c.name, c.mismatches[:2])
                                                for c in report.checks if not c.ok]


BAD = [
    ("motion", "poses", {"poses": [[0, 0, 0], [1, 1, 400], [2, 0, 10]]}, "synthesis.poses"),
    ("motion", "beta", {"beta": [10, 500]}, "synthesis.beta"),
    ("motion", "a pose of two numbers", {"poses": [[0, 0], [1, 1, 4], [2, 0, 10]]},
     "synthesis.poses"),
    ("motion", "a length for a pivot", {"designs": {**_data("motion")["synthesis"]["designs"],
                                                    "xA0": "a1"}}, "synthesis.designs.xA0"),
    ("motion", "a designed parameter missing",
     {"designs": {k: v for k, v in _data("motion")["synthesis"]["designs"].items()
                  if k != "u"}}, "synthesis.designs"),
    ("path", "alpha missing", {"alpha": None}, "synthesis"),
    ("path", "gamma", {"gamma": [0, -361]}, "synthesis.gamma"),
    ("motion", "both the rotations and the pivot", {"pivots": {"crank": [0, 0]}},
     "synthesis.beta"),
    ("motion", "neither", {"gamma": None}, "synthesis.gamma"),
    ("path", "the crank's pivot drops the timing", {"pivots": {"crank": [0, 0]}},
     "synthesis.pivots"),
]


@pytest.mark.parametrize("kind, what, change, field", BAD, ids=[b[1] for b in BAD])
def test_a_bad_task_is_one_line_naming_the_field(kind, what, change, field):
    data = _data(kind, **change)
    data["synthesis"] = {k: v for k, v in data["synthesis"].items() if v is not None}
    with pytest.raises(InputError) as caught:
        from_data("bad", data, origin="bad.toml")
    said = str(caught.value)
    assert "\n" not in said and f"bad.toml: {field}" in said, said


def test_a_mechanism_that_does_not_read_the_design_is_refused():
    """The coupler point must be the `point` step at local [u, v] on the crank pin and the
    dyad's joint: another frame is one line naming the task's designs."""
    data = _data("motion")
    data["mechanism"]["steps"][2]["frame"] = ["B", "A"]
    with pytest.raises(InputError, match=r"bad.toml: synthesis.designs: .*point step"):
        from_data("bad", data, origin="bad.toml")


def test_info_prints_the_design_its_branch_class_and_largest_miss():
    """`linkbook info` of the bundled path book: the designed lengths the reference's, the
    branch, Grashof's class and the largest miss of the points (round-off: it passes
    through them)."""
    from linkbook.apps.info import built_book, lines, summary
    data = summary(built_book(str(TEMPLATES["path"])))
    syn = data["synthesis"]
    task = _data("path")["synthesis"]
    (x, y), rotations = zip(*task["points"]), np.radians([task["beta"], task["alpha"],
                                                          task["gamma"]])
    expected = path_generation(x, y, *rotations)
    for role, key in (("crank a2", "a"), ("coupler a3", "b"), ("rocker a4", "c"),
                      ("ground a1", "d")):
        assert syn["designed"][role] == pytest.approx(expected[key], rel=1e-9)
    assert syn["grashof"] == expected["grashof"] == "Grashof: crank-rocker"
    assert syn["branch"] == SYNTHESIS_WORDS["no defect"] and syn["designed"]["branch branch"] == 1
    assert syn["largest_miss"] < 1e-9 * expected["d"]
    text = "\n".join(lines(data))
    assert "Synthesis: path generation, three points with timing" in text
    assert "largest miss of the poses by the position steps" in text


def test_a_book_in_metres_designs_the_same_linkage_in_metres():
    """--unit m converts the poses with the lengths: the designed crank is the reference's
    design of the task in mm, over 1000."""
    from linkbook.language.templates import with_unit
    t = with_unit(load(str(TEMPLATES["motion"])), "m")
    task = _data("motion")["synthesis"]
    x, y, alpha = (np.array([p[k] for p in task["poses"]]) for k in range(3))
    expected = motion_generation(x, y, np.radians(alpha), crank_rotation=np.radians(
        task["beta"]), rocker_rotation=np.radians(task["gamma"]))
    assert t.values()["a2"] == pytest.approx(expected["a"] / 1000, rel=1e-9)
    assert t.values()["xB0"] == pytest.approx(expected["B0"][0] / 1000, rel=1e-9)
