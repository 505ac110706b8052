"""What a verify does once that it used to do more than once (issue 42, start-up)."""
from __future__ import annotations

import pytest

from linkbook.book import builder
from linkbook.check import verifier
from linkbook.language import bundled, templates

BOOKS = ("fourbar", "slider-crank")


@pytest.fixture(scope="module")
def books(tmp_path_factory) -> dict:
    folder = tmp_path_factory.mktemp("startup")
    paths = {name: folder / f"{name}.xlsx" for name in BOOKS}
    for name, path in paths.items():
        builder.build_file(templates.load(name), path)
    return paths


def test_verify_compiles_the_recorded_mechanism_once_per_book(books, monkeypatch):
    """The book's own judging, the other input sets' draw and their judging share one compiled
    mechanism; a second book gets its own."""
    compiled = []
    real = bundled.from_record

    def counted(record):
        compiled.append(record.mechanism)
        return real(record)
    monkeypatch.setattr(bundled, "from_record", counted)
    for name, path in books.items():
        report = verifier.verify(path)
        assert report.ok and report.mechanism == name
        assert [s.skipped for s in report.input_sets] == [None]      # judged at a second set
    assert compiled == list(BOOKS)


def test_the_value_grid_reaches_the_furthest_empty_cell_a_copied_formula_reads(tmp_path):
    """A column's formulas read empty cells beyond the sheet's last one, each row further down
    and to the right (the grid is sized from the group's last member): their values are those
    of ExcelModel, an empty cell read as 0."""
    import openpyxl
    from linkbook.engine import evaluator as engine
    wb = openpyxl.Workbook()
    ws = wb.active
    for r in range(1, 6):
        ws[f"A{r}"] = r * 1.5
        ws[f"B{r}"] = f"=A{r}+D{r + 20}*2+ISBLANK(E{r + 30})"
        ws[f"C{r}"] = f"=B{r}-$F$3+G{r + 25}"
    path = tmp_path / "beyond.xlsx"
    wb.save(path)
    ours = engine.evaluate_file(path)
    model = engine.evaluate_formulas_model(path)
    assert {k: ours[k] for k in model} == model
    assert [ours[("Sheet", f"B{r}")] for r in range(1, 6)] == [r * 1.5 + 1 for r in range(1, 6)]


def test_verify_reads_each_columns_places_once_and_lets_them_go(books, monkeypatch):
    """The engine's values are read a column at a time at the book's own inputs and again at
    the other input set: each short list of addresses has its places (rows and columns) read
    from its texts once, a column's list from column_cells not at all (it knows them), and
    what was kept is forgotten when the verify ends."""
    from linkbook.base.xlsx import ColumnCells
    from linkbook.engine import rerun
    read = []
    real = rerun.coordinates_to_arrays

    def counted(cells):
        read.append((type(cells) is ColumnCells, tuple(cells)))
        return real(cells)
    monkeypatch.setattr(rerun, "coordinates_to_arrays", counted)
    report = verifier.verify(books["fourbar"])
    assert report.ok and [s.skipped for s in report.input_sets] == [None]
    texts = [cells for known, cells in read if not known and len(cells) <= rerun.KEPT_CELLS]
    assert texts and len(texts) == len(set(texts))
    assert any(known for known, _ in read)
    assert rerun._kept_places.cache_info().currsize == 0


@pytest.mark.parametrize("letter, first, last", [("A", 1, 1), ("B", 5, 77), ("AB", 9, 3609),
                                                 ("XFD", 1048570, 1048576)])
def test_a_columns_addresses_know_their_places(letter, first, last):
    """column_cells' list gives the places coordinate_to_tuple reads from each address, and
    once changed is read from its texts again."""
    from linkbook.base import xlsx
    cells = xlsx.column_cells(letter, first, last)
    rows, cols = xlsx.coordinates_to_arrays(cells)
    assert list(zip(rows.tolist(), cols.tolist())) == [xlsx.coordinate_to_tuple(c)
                                                       for c in cells]
    cells[-1] = "C2"
    rows, cols = xlsx.coordinates_to_arrays(cells)
    assert (rows[-1], cols[-1]) == (2, 3)
    if len(cells) > 2:
        cells[-1], cells[1] = xlsx.column_cells(letter, first, last)[-1], "D4"  # the middle
        rows, cols = xlsx.coordinates_to_arrays(cells)
        assert (rows[1], cols[1]) == (4, 4)


def test_verify_of_a_four_bar_imports_neither_synthesis_nor_the_applications(books):
    """A process that verifies a bundled four-bar imports no module that only a synthesis book
    or a recalculation by LibreOffice or Gnumeric uses (nor subprocess, which only they need)."""
    import os
    import subprocess
    import sys
    from conftest import HANG_GUARD_S, ROOT
    code = ("import sys\n"
            "from linkbook.apps.cli import main\n"
            f"assert main(['verify', '--quiet', {str(books['fourbar'])!r}]) == 0\n"
            "print(sorted(m for m in sys.modules if 'synthesis' in m or m in "
            "('linkbook.engine.office', 'subprocess')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT / "src")),
                          timeout=HANG_GUARD_S)
    assert done.returncode == 0 and done.stdout.strip() == "[]", (done.stdout, done.stderr)


class _Cycle:
    """An object that refers to itself: only the cyclic collector frees it."""

    def __init__(self):
        self.me = self


def test_a_process_paused_until_exit_collects_between_books_only(monkeypatch):
    """The command line's process keeps the collector off to its exit (pause_until_exit): a
    paused call (a book's build or verify) collects the cycles the calls before it left when
    it begins, the first call and a call inside another collect nothing, and the collector
    stays off after each."""
    import gc
    import weakref
    from linkbook.base import pause
    monkeypatch.setattr(pause, "_until_exit", False)
    monkeypatch.setattr(pause, "_begun", 0)
    monkeypatch.setattr(pause, "_running", 0)
    left, collected = [], []

    def collections(phase, info):
        if phase == "stop":
            collected.append(info["generation"])

    @pause.gc_paused
    def book(inner=False):
        seen = (gc.isenabled(), [ref() is None for ref in left], len(collected))
        cycle = _Cycle()
        left.append(weakref.ref(cycle))
        return (seen, book()) if inner else seen

    gc.callbacks.append(collections)
    try:
        pause.pause_until_exit()
        first = book()
        assert first == (False, [], 0) and not gc.isenabled()
        outer, inner = book(inner=True)
        assert outer == (False, [True], 1) and inner == (False, [True, False], 1)
        assert book() == (False, [True, True, True], 2) and not gc.isenabled()
    finally:
        gc.callbacks.remove(collections)
        gc.enable()


def test_every_dataclass_has_a_docstring_of_its_own():
    """A dataclass without a docstring gets one made from inspect.signature when its module is
    imported, which costs more than making the rest of the class (a verify imports dozens)."""
    import dataclasses
    import importlib
    import inspect
    import pkgutil
    import linkbook
    made = []
    for info in pkgutil.walk_packages(linkbook.__path__, "linkbook."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        made += [f"{info.name}.{name}" for name, cls in vars(module).items()
                 if inspect.isclass(cls) and cls.__module__ == info.name
                 and dataclasses.is_dataclass(cls)
                 and (cls.__doc__ or "").startswith(f"{cls.__name__}(")]
    assert not made, ", ".join(made)


def test_the_reference_reads_an_expression_once_and_evaluates_it_each_time(monkeypatch):
    """The reference evaluates a mechanism's expressions at every solve: each text is read
    into its tree once, each evaluation takes its own values, and a malformed text is refused
    every time it is asked for."""
    from linkbook.check.reference import expressions
    parsed = []
    real = expressions._Parser.parse

    def counted(self):
        parsed.append(self.text)
        return real(self)
    expressions._parsed.cache_clear()
    monkeypatch.setattr(expressions._Parser, "parse", counted)
    assert expressions.evaluate("a*2+1", {"a": 3.0}) == 7.0
    assert expressions.evaluate("a*2+1", {"a": 4.0}) == 9.0
    assert expressions.evaluate("SQRT(b)-1", {"b": 16.0}) == 3.0
    assert expressions.evaluate("a*2+1", {"a": -0.5}) == 0.0
    assert len(parsed) == 2
    for _ in range(2):
        with pytest.raises(ValueError):
            expressions.evaluate("a*", {"a": 1.0})
    assert len(parsed) == 4


def test_a_rerun_finds_what_reads_which_group_and_what_moves_in_one_look(books):
    """deps_and_downstream gives what group_deps and downstream give, looking at each group's
    reads once: for every input of the book alone and for all of them together."""
    from linkbook.check.input_sets import input_cell
    from linkbook.check.reading import read_book
    from linkbook.engine import evaluator, order
    for path in books.values():
        wb, record = read_book(path)
        engine = evaluator.Engine(wb)
        engine.run_view()
        places = [engine._input_place(*input_cell(record, key)) for key in record.inputs
                  if not record.inputs[key].designed]
        deps = {g.gid: order.group_deps(g, engine.owner) for g in engine.groups}
        for chosen in [[p] for p in places] + [places]:
            moved = order.downstream(engine.groups, engine.grid, chosen, deps)
            assert order.deps_and_downstream(engine.groups, engine.owner, chosen) == (deps, moved)
        assert any(order.downstream(engine.groups, engine.grid, [p], deps) for p in places)
