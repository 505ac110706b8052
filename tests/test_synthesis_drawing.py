"""The designed linkage drawn at each precision position, on the Synthesis sheet (issue 38): its
joints at θ2_j by the position steps, an equal-scale chart with a series per position, and
verify judging it.

Expected values come from the independent references: the synthesis reference designs the
linkage, the kinematic reference places it at each θ2_j on the branch the design names."""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from linkbook.base.sheets import SYNTHESIS
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.check.reference import synthesis as ref
from linkbook.check.verifier import verify
from linkbook.language.templates import from_data

ROOT = Path(__file__).resolve().parents[1]
TEMPLATE = ROOT / "templates" / "function-log10.toml"
TITLE = "The designed linkage at each precision position"


def _data(**task) -> dict:
    data = tomllib.loads(TEMPLATE.read_text(encoding="utf-8"))
    data["synthesis"] = {**data["synthesis"], **task}
    return data


@pytest.fixture(scope="module")
def book():
    """The bundled task's book (three Chebyshev points) and the reference's design of it."""
    t = from_data("function-log10", _data())
    built, values = builder.make(t)
    task = _data()["synthesis"]
    x, _ = ref.precision_points(np.log10, *task["x"], task["points"], task["spacing"])
    theta2, theta4 = ref.precision_angles(np.log10, x, *task["x"], *np.radians(
        [*task["theta2"], *task["theta4"]]))
    design = ref.function_generation(theta2, theta4, 100.0)
    return built, values, t, design, np.degrees(theta2)


def test_the_joints_are_the_reference_design_placed_at_each_precision_angle(book):
    """Each position's A0, A, B, B0: the kinematic reference placing the synthesis
    reference's design (its lengths and its branch) at θ2_j, to 1e-9 of the linkage's size;
    the legend names θ2_j."""
    built, values, t, design, angles = book
    [branch] = set(design["branch"])
    params = {**t.values(), "a2": design["a"], "a3": design["b"], "a4": design["c"],
              "branch": branch}
    placed = solve(t.mechanism.description, params, angles)["points"]
    drawing = built.record.synthesis.drawing
    assert len(drawing["positions"]) == 3
    for i, p in enumerate(drawing["positions"]):
        assert p["joints"] == ["A0", "A", "B", "B0"]
        assert values[(SYNTHESIS, p["title"])] == f"θ2 = {angles[i]:.1f}°"
        for name, (x, y) in zip(p["joints"], p["cells"]):
            for cell, want in ((x, placed[name][0][i]), (y, placed[name][1][i])):
                assert abs(values[(SYNTHESIS, cell)] - want) <= 1e-9 * 100, (name, cell)
    # the coupler is a link of the drawn line, and of the designed length
    for p in drawing["positions"]:
        a, b = (np.array([values[(SYNTHESIS, c)] for c in p["cells"][k]]) for k in (1, 2))
        assert float(np.hypot(*(b - a))) == pytest.approx(design["b"], rel=1e-9)


def test_the_chart_has_a_series_per_position_at_equal_scales(book):
    """One series per position named by its legend cell, in distinct colours, and the scale
    bar; both axes fixed at the same span (the frame maps the joints into it)."""
    built, *_ = book
    ws = built.workbook[SYNTHESIS]
    [chart] = [c for c in ws._charts if TITLE in str(c.title.tx.rich.p[0].r[0].t)]
    drawing = built.record.synthesis.drawing
    positions = drawing["positions"]
    assert len(chart.series) == len(positions) + 1
    colours = set()
    for s, p in zip(chart.series, positions):
        assert s.tx.strRef.f.replace("$", "").replace("'", "") == f"{SYNTHESIS}!{p['title']}"
        colours.add(str(s.graphicalProperties.line.solidFill.srgbClr))
        assert s.xVal.numRef.f.replace("$", "").endswith(
            f"{p['mapped'][0][0]}:{p['mapped'][-1][0]}")
    assert len(colours) == len(positions)
    spans = {(a.scaling.min, a.scaling.max) for a in (chart.x_axis, chart.y_axis)}
    assert len(spans) == 1 and spans.pop()[0] == -5


def test_verify_judges_the_drawing_and_catches_a_joint_at_the_wrong_angle(tmp_path, book):
    """verify compares every drawing cell (joints, legends, frame, mapped cells); a joint
    formula that reads the next position's angle differs there."""
    import openpyxl
    built, *_ = book
    path = tmp_path / "log10.xlsx"
    builder.build_file(from_data("function-log10", _data()), path)
    report = verify(path)
    drawing = built.record.synthesis.drawing
    drawn = {(SYNTHESIS, c) for p in drawing["positions"] for xy in p["cells"] + p["mapped"]
             for c in xy} | {(SYNTHESIS, c) for c in drawing["frame"].values()}
    judged = set().union(*(c.judged for c in report.checks))
    assert report.status == 0 and drawn <= judged
    wb = openpyxl.load_workbook(path)
    first, second = drawing["positions"][:2]
    cell = first["cells"][1][0]                  # A's x at the first position
    wb[SYNTHESIS][cell] = wb[SYNTHESIS][second["cells"][1][0]].value
    wb.save(path)
    report = verify(path)
    assert report.status == 1
    assert (SYNTHESIS, cell) in {(m.sheet, m.cell) for c in report.checks for m in c.mismatches}


def test_a_task_with_no_design_draws_only_the_ground_pivots(tmp_path):
    """A branch defect: A and B are #N/A at every position (the fixed pivots are not), the
    frame with them; verify agrees."""
    data = _data(theta2=[0, 300], theta4=[30, 200])
    path = tmp_path / "defect.xlsx"
    built = builder.build_file(from_data("defect", data), path)
    report = verify(path)
    assert report.status == 0 and math.isnan(report.inputs["a2"])
    import openpyxl
    from linkbook.engine import evaluator
    values = evaluator.Engine(openpyxl.load_workbook(path)).run()
    for p in built.record.synthesis.drawing["positions"]:
        shown = {name: [values[(SYNTHESIS, c)] for c in xy] for name, xy in
                 zip(p["joints"], p["cells"])}
        assert shown["A0"] == [0, 0] and shown["B0"] == [100, 0]
        assert all(evaluator.is_error(v) for v in shown["A"] + shown["B"])
