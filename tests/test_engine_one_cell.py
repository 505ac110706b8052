"""Formulas that stand alone: a group of one cell (a current position's cell, a summary's) runs
as a vector call of one row, and a formula that is one reference, name or constant as a compiled
pipe of no steps (engine/plan.py, engine/adapter.py). Both must give, value and type, what a
per-cell call gives and what formulas.ExcelModel gives."""
from __future__ import annotations

import sys
from pathlib import Path

import openpyxl
from openpyxl.workbook.defined_name import DefinedName

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from linkbook.engine import adapter  # noqa: E402
from linkbook.engine import evaluator as engine  # noqa: E402
from test_engine import (ONE_ARG, OPERATORS, PANEL, SECOND, TWO_ARG,  # noqa: E402
                         as_excel_model_gives, assert_as_per_cell, put_pair)

# Functions a vector call must not take (ranges-aware, array makers): their lone cells stay
# cell by cell, as in a group of many.
NOT_VECTOR = ["=ROWS($A$2:$A$4)+$A${r}", "=INDEX($A$2:$B$4,2,2)&$B${r}",
              "=SUM($A$2:$A${r})", "=ROWS($A${r})+COLUMNS($B${r})", "=INDEX($A${r},1,1)"]


def lone_cells_book() -> openpyxl.Workbook:
    """One row per panel value, each formula with absolute references only: no two cells share
    a shape, so every group is one cell."""
    wb = openpyxl.Workbook()
    ws = wb.active
    for i, a in enumerate(PANEL):
        r, b = 2 + i, SECOND[i % len(SECOND)]
        put_pair(ws, r, a, b)
        formulas = ([f"={f}($A${r})" for f in ONE_ARG] + [f"={f}($A${r},$B${r})" for f in TWO_ARG]
                    + [f"=$A${r}{op}$B${r}" for op in OPERATORS]
                    + [f"=IF($A${r}>0,$B${r},NA())", f"=$A${r}", f"=$B${r}"]
                    + [f.format(r=r) for f in NOT_VECTOR])
        for j, formula in enumerate(formulas):
            ws.cell(row=r, column=3 + j, value=formula)
    return wb


def test_a_group_of_one_cell_is_one_vector_call_as_per_cell_calls_give():
    wb = lone_cells_book()
    vector = engine.Engine(wb)
    got = vector.run()
    assert all(len(g.members) == 1 for g in vector.groups)
    lone_formulas = len(ONE_ARG) + len(TWO_ARG) + len(OPERATORS) + 3
    assert vector.stats["vector_groups"] >= len(PANEL) * lone_formulas
    assert vector.stats["cell_groups"] == len(PANEL) * len(NOT_VECTOR)
    want = engine.Engine(wb, vectorize=False).run()
    assert set(got) == set(want)
    assert_as_per_cell(got, want)


def lone_references_book() -> openpyxl.Workbook:
    """Formulas that are one reference (to a number, text, a boolean, an error, an empty cell,
    another sheet, a range), one name or one constant."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Data"
    for ref, v in {"A1": 2.5, "A2": "abc", "A3": True, "A4": "=NA()", "A5": 7,
                   "A6": "=1/0"}.items():
        ws[ref] = v
    wb.defined_names["size"] = DefinedName("size", attr_text="'Data'!$A$1")
    wb.defined_names["nothing"] = DefinedName("nothing", attr_text="'Data'!$Z$9")
    other = wb.create_sheet("Other sheet")
    formulas = ["=Data!A1", "=Data!$A$2", "=Data!A3", "=Data!A4", "=Data!A5", "=Data!A6",
                "=Data!Z20", "=size", "=nothing", "=0", "=1.5E+3", '="text"', "=TRUE",
                "=Data!A1:A1", "=B1", "=-Data!A1"]
    for r, formula in enumerate(formulas, start=1):
        other[f"B{r}"] = formula
    for r in range(1, 4):                       # and a group of them down a column
        other[f"C{r}"] = f"=Data!A{r}"
    return wb


def test_a_lone_reference_name_or_constant_gives_what_excel_model_gives(tmp_path):
    path = tmp_path / "lone.xlsx"
    ours = as_excel_model_gives(lone_references_book(), path)
    assert_as_per_cell(ours, engine.Engine(openpyxl.load_workbook(path), vectorize=False,
                                           excel_model_constants=True).run())
    assert ours[("Other sheet", "B1")] == 2.5 and ours[("Other sheet", "B3")] is True
    assert ours[("Other sheet", "B7")] == 0.0 and ours[("Other sheet", "B12")] == "text"


def test_a_lone_reference_compiles_to_a_pipe_without_formulas_graph():
    """No dispatcher built for `=A1`, `=size` or `=0`: its pipe has no steps."""
    for formula in ("=Data!A1", "=size", "=0", '="x"'):
        pipe = adapter.compile_formula(adapter.tokenize(formula).builder)
        assert isinstance(pipe, adapter.Pipe) and not pipe.steps
        assert pipe.compiled is None
