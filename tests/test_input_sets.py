"""verify at more than one set of inputs: a formula whose wrong term vanishes at the book's own
inputs (−I·α at α = 0, an offset's term at offset 0, the weight at g = 0) agrees there and must
differ at verify's other input set; the set is drawn from a seed (the same seed, the same set);
the engine's rerun gives, bit for bit, what a full evaluation of the book holding those inputs
gives."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import openpyxl
import pytest

from conftest import examples, passes_or_names_another_assembly, template
from linkbook.apps import cli
from linkbook.base.sheets import read_meta, read_record
from linkbook.book import builder
from linkbook.language import templates
from linkbook.check import input_sets, verifier
from linkbook.engine import evaluator as engine
from linkbook.engine.rerun import rerun


def _build(folder: Path, name: str, sets=(), step=30.0) -> Path:
    path = folder / f"{name}-{'-'.join(sets) or 'own'}.xlsx"
    builder.build_file(template(name, sets, step), path)
    return path


EDITED: dict[Path, set] = {}      # an edited book's edited cells


def _edited(path: Path, sheet: str, column_of, old: str, new: str) -> Path:
    """The book with `old` replaced by `new` in every formula of one column of `sheet` (the
    column letter from the build record: column_of(meta) -> (letter, (first, last)))."""
    wb = openpyxl.load_workbook(path)
    letter, (first, last) = column_of(read_meta(wb))
    for r in range(first, last + 1):
        cell = wb[sheet][f"{letter}{r}"]
        assert old in cell.value, cell.value
        cell.value = cell.value.replace(old, new)
    out = path.with_name(f"edited-{path.name}")
    wb.save(out)
    EDITED[out] = {(sheet, f"{letter}{r}") for r in range(first, last + 1)}
    return out


@pytest.fixture(scope="module")
def books(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("books")
    fourbar = _build(folder, "fourbar")                     # alpha_in = 0 as bundled
    weightless = _build(folder, "fourbar", ("g=0",))
    centred = _build(folder, "slider-crank", ("a1=0",))     # the slider line through A0
    return {
        "fourbar": fourbar,
        # the crank pin's acceleration without its α term: right while alpha_in is 0
        "no alpha": _edited(fourbar, "Motion", lambda m: (m["motion"]["columns"]["ax_A"],
                                                          m["motion"]["rows"]),
                            "alpha_in", "0"),
        # the crank's pin force without the crank's weight: right while g is 0
        "no weight": _edited(weightless, "Forces", lambda m: (
            m["forces"]["columns"]["F12y"], m["forces"]["rows"]), "m_2*(-g)", "0"),
        # the coupler's angle without the slider line's offset: right while a1 is 0
        "no offset": _edited(centred, "Sweep", lambda m: (m["sweep"]["columns"]["theta13"],
                                                          m["sweep"]["rows"]), "-a_1", ""),
        "near change point": _build(folder, "fourbar", ("a4=42.69",)),
    }


@pytest.mark.parametrize("name, zero", [("no alpha", "alpha_in"), ("no weight", "g"),
                                        ("no offset", "a1")])
def test_a_term_that_vanishes_at_the_books_inputs_differs_at_another_set(books, name, zero,
                                                                        capsys):
    report = verifier.verify(books[name])
    assert all(c.ok for c in report.checks), "the wrong term vanishes at the book's inputs"
    assert report.inputs[zero] == 0
    [other] = report.input_sets
    assert other.skipped is None and other.inputs[zero] != 0 and not other.ok
    # the edited cells themselves (where their wrong term is not 0), named as likely causes
    edited = EDITED[books[name]] & other.differing()
    assert edited and edited <= report.causes
    assert report.status == 1 and report.differing == len(other.differing())
    # the largest difference is the other set's, where the wrong term shows
    assert report.max_abs == other.max_abs > max(c.max_abs for c in report.checks)
    code = cli.main(["verify", str(books[name])])
    lines = capsys.readouterr().out.splitlines()
    assert code == 1 and lines[-1].startswith("DISAGREES: ")
    said = [line for line in lines if line.startswith("differs at input set 2 (seed 1; ")]
    assert len(said) == 1 and f"{zero}=" in said[0], lines


def test_the_untouched_books_agree_at_the_other_set(books, capsys):
    for name in ("fourbar", "near change point"):
        report = verifier.verify(books[name])
        [other] = report.input_sets
        assert report.status == 0 and other.skipped is None and other.ok and other.checks
    code = cli.main(["verify", str(books["fourbar"])])
    lines = capsys.readouterr().out.splitlines()
    assert code == 0 and lines[1].startswith("also judged at input set 2 (seed 1; alpha_in=")
    assert lines[1].endswith("cells compared") and lines[2].startswith("all agree: ")


def test_a_set_assembles_where_the_book_does(books):
    """Near the four-bar's change point (s + l exceeds p + q by 1e-4 of it) moving the lengths
    5 % changes where the loop closes: the set drawn keeps the rows the book's inputs close on,
    by the reference."""
    wb = openpyxl.load_workbook(books["near change point"])
    record = read_record(wb)
    own = verifier.inputs_of(wb, record)
    [other] = verifier.verify(books["near change point"]).input_sets
    first, last = record.sweep.rows
    angles = np.array([wb["Sweep"][f"A{r}"].value for r in range(first, last + 1)], float)
    solver = verifier.Reference(record)
    closes = [solver.solve(p, angles)["assembled"] for p in (own, other.inputs)]
    assert np.array_equal(closes[0], closes[1]) and not closes[0].all()


def test_the_set_is_the_seeds(books):
    wb = openpyxl.load_workbook(books["fourbar"])
    record = read_record(wb)
    own = verifier.inputs_of(wb, record)
    first = input_sets.draw(record, "angle", own, 1, 2)
    assert first == input_sets.draw(record, "angle", own, 1, 2)
    assert first != input_sets.draw(record, "angle", own, 2, 2)
    kinds = record.kinds()
    for symbol, value in own.items():
        if kinds[symbol] == "branch":
            assert first[symbol] == value
        elif value == 0:
            assert first[symbol] != 0, symbol          # alpha_in: the bundled book's zero
        else:
            assert 0 < first[symbol] / value and abs(first[symbol] / value - 1) <= 0.05 + 1e-3


def test_json_names_the_seed_and_each_input_set(books, capsys):
    code = cli.main(["verify", str(books["fourbar"]), "--json", "--seed", "7"])
    [report] = json.loads(capsys.readouterr().out)
    own, other = report["input_sets"]
    assert code == 0 and report["seed"] == 7
    assert own["set"] == 1 and own["inputs"] == report["inputs"] and own["changed"] == []
    assert other["set"] == 2 and other["judged"] and other["not_judged_because"] is None
    assert "alpha_in" in other["changed"] and other["mismatches"] == 0 and other["cells"] > 0
    assert set(own) == set(other)
    code = cli.main(["verify", str(books["no alpha"]), "--json", "--seed", "7"])
    [bad] = json.loads(capsys.readouterr().out)
    assert code == 1 and bad["input_sets"][1]["inputs"] == other["inputs"]
    assert bad["input_sets"][0]["mismatches"] == 0 and bad["input_sets"][1]["differing"]
    assert bad["mismatches"] == bad["input_sets"][1]["mismatches"]
    assert bad["max_abs_diff"] == bad["input_sets"][1]["max_abs_diff"] > 1e-6
    assert any(not c["ok"] for c in bad["input_sets"][1]["checks"])


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and (a == b or str(a) == str(b))


@pytest.mark.parametrize("name", ["fourbar", "no offset"])
def test_rerun_equals_a_full_evaluation_with_those_inputs(books, name):
    """Every cell, for two sets of new inputs one after the other, as evaluate() gives it for
    the book holding them; the engine holds the book's own values again after each."""
    wb = openpyxl.load_workbook(books[name])
    record = read_record(wb)
    own = verifier.inputs_of(wb, record)
    ev = engine.Engine(wb)
    before = ev.run()
    for seed in (1, 2):
        new = input_sets.draw(record, "angle", own, seed, 2)
        cells = {("Mechanism", record.inputs[k].cell): v for k, v in new.items() if v != own[k]}
        with rerun(ev, cells) as values:
            got = dict(values)
        for (sheet, cell), value in cells.items():
            wb[sheet][cell] = value
        full = engine.evaluate(wb)
        for (sheet, cell) in cells:
            wb[sheet][cell] = own[next(k for k, i in record.inputs.items() if i.cell == cell)]
        assert set(got) == set(full)
        bad = [k for k in full if not _same(full[k], got[k])]
        assert not bad, bad[:5]
        with rerun(ev, {}) as values:
            assert all(_same(before[k], values[k]) for k in before)


def _all_same(got: list, want: list) -> None:
    assert len(got) == len(want)
    bad = [(i, a, b) for i, (a, b) in enumerate(zip(got, want)) if not _same(a, b)]
    assert not bad, bad[:5]


def _columns(wb):
    """(sheet, cells) of every column of every sheet, from the row above the first to beyond the
    last (constants, formulas, empty cells and cells outside the sheet)."""
    for ws in wb.worksheets:
        for col in range(1, ws.max_column + 2):
            letter = openpyxl.utils.get_column_letter(col)
            yield ws.title, [f"{letter}{r}" for r in range(0, ws.max_row + 3)]


def test_a_column_looked_up_together_is_what_a_full_evaluation_gives(books):
    """verify reads the engine's values a column at a time (rerun.Values.many), at the book's
    own inputs and at other ones: each cell as evaluate() of the book holding them gives it
    (None where it gives none)."""
    wb = openpyxl.load_workbook(books["fourbar"])
    record = read_record(wb)
    own = verifier.inputs_of(wb, record)
    ev = engine.Engine(wb)
    view, full = ev.run_view(), engine.evaluate(wb)
    for sheet, cells in _columns(wb):
        _all_same(view.many(sheet, cells), [full.get((sheet, c)) for c in cells])
    assert view.many("Sweep", ["B5", "no cell"]) == [full[("Sweep", "B5")], None]
    assert view.many("no sheet", ["B5"]) == [None] and view.many("Sweep", []) == []
    new = input_sets.draw(record, "angle", own, 1, 2)
    cells = {("Mechanism", record.inputs[k].cell): v for k, v in new.items() if v != own[k]}
    for (sheet, cell), value in cells.items():
        wb[sheet][cell] = value
    moved = engine.evaluate(wb)
    with rerun(ev, cells) as values:
        for sheet, column in _columns(wb):
            _all_same(values.many(sheet, column), [moved.get((sheet, c)) for c in column])


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(p.stem for p in templates.bundled()))
def test_random_books_agree_at_their_other_set(family, tmp_path):
    """A book of random dimensions, rates and loads (test_properties' draws), untouched,
    agrees at verify's other input set as at its own (or that set is said not judged)."""
    from hypothesis import HealthCheck, assume, given, settings
    from test_properties import dimensions, through_a_pivot, with_values
    base = templates.load(family)

    @settings(max_examples=examples(20, at_least=3), deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(dimensions(base))
    def check(values):
        t = with_values(base, values)
        assume(not through_a_pivot(t))
        path = tmp_path / f"{family}.xlsx"
        builder.build_file(t, path)
        report = verifier.verify(path)
        [other] = report.input_sets
        bad = [(c.block, c.name, m) for c in other.checks for m in c.mismatches[:2]]
        assert passes_or_names_another_assembly(report) and not bad, \
            (values, other.inputs, bad[:5])
    check()


def test_a_synthesis_books_other_set_moves_its_task(tmp_path):
    """A Chebyshev centre written (x0² + x1)/2 is right while x0 = 1, as in the bundled
    function-log10 book: verify's other input set moves the task's x0 (and its other inputs,
    as a user typing in the yellow cells would), redesigns with the reference and differs
    there, in the x column and what follows it."""
    path = _build(tmp_path, "function-log10")
    wb = openpyxl.load_workbook(path)
    record = read_record(wb)
    cells = record.synthesis.points["x"]
    for cell in cells:
        text = wb["Synthesis"][cell].value
        assert "(syn_x0+syn_x1)/2" in text, text
        wb["Synthesis"][cell] = text.replace("(syn_x0+syn_x1)/2", "(syn_x0^2+syn_x1)/2")
    edited = tmp_path / "edited-centre.xlsx"
    wb.save(edited)
    report = verifier.verify(edited)
    assert all(c.ok for c in report.checks), "x0² = x0 at the book's own x0 = 1"
    [other] = report.input_sets
    assert other.skipped is None and other.inputs["syn_x0"] != 1 and not other.ok
    assert {("Synthesis", c) for c in cells} <= other.differing()
    assert report.status == 1
    # the untouched book agrees there: the designed linkage is the reference's of the task
    # moved (its crank, checked here against the reference's own design of that task)
    [same] = verifier.verify(path).input_sets
    assert same.ok and same.checks
    moved = {key: same.inputs[f"syn_{key}"] for key in ("x0", "x1", "theta2_start",
                                                        "theta2_span", "theta4_start",
                                                        "theta4_span")}
    assert {f"syn_{key}" for key in moved} <= set(same.changed)
    from linkbook.check.reference import synthesis as ref
    x, _ = ref.precision_points(np.log10, moved["x0"], moved["x1"], 3, "chebyshev")
    theta2, theta4 = ref.precision_angles(np.log10, x, moved["x0"], moved["x1"], *np.radians(
        [moved[k] for k in ("theta2_start", "theta2_span", "theta4_start", "theta4_span")]))
    design = ref.function_generation(theta2, theta4, same.inputs["a1"])
    assert same.inputs["a2"] == pytest.approx(design["a"], rel=1e-9)
    assert same.inputs["branch"] == design["branch"][0]


def test_a_synthesis_set_whose_moved_task_has_no_design_is_not_judged(tmp_path, capsys):
    """The rocker's span 0.01 % short of a branch defect (the reference's: at −79.75° the
    precision points need two assemblies): the task moved by seed 1, however little, has
    none; verify says that set is not judged and why, and the verdict is the book's own."""
    import tomllib
    from linkbook.check.reference import synthesis as ref
    from linkbook.language.templates import from_data
    source = next(p for p in templates.bundled() if p.stem == "function-log10")
    data = tomllib.loads(source.read_text(encoding="utf-8"))
    data["synthesis"]["theta4"] = [240, -79.66]
    path = tmp_path / "edge.xlsx"
    builder.build_file(from_data("edge", data), path)

    def defect(span: float) -> bool:
        x, _ = ref.precision_points(np.log10, 1, 10, 3, "chebyshev")
        t2, t4 = ref.precision_angles(np.log10, x, 1, 10, *np.radians([30, 90, 240, span]))
        return ref.function_generation(t2, t4, 100.0)["branch_defect"]
    assert not defect(-79.66) and defect(-79.75)
    report = verifier.verify(path)
    [other] = report.input_sets
    assert report.status == 0 and not math.isnan(report.inputs["a2"])
    assert other.skipped == ("no task drawn near the book's has a design like the book's "
                             "(the nearest: a branch defect)") and not other.checks
    assert cli.main(["verify", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1] == f"input set 2 (seed 1) not judged: {other.skipped}"
    assert lines[-1].startswith("all agree (at the book's own inputs; input set 2 not judged)")
