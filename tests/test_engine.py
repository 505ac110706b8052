"""The vector engine (linkbook.engine.evaluator) against formulas.ExcelModel, cell by cell.

Workbooks are built here with openpyxl: named parameters, a sweep table with loops that cannot
close (#N/A), a mixed-reference grid, summaries over ranges on a sheet whose name has spaces,
running sums (a column that reads itself), and literal errors."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import openpyxl
import pytest
import schedula as sh
from formulas.tokens.operand import Error
from openpyxl.utils import get_column_letter
from openpyxl.workbook.defined_name import DefinedName

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from linkbook.engine import adapter, references  # noqa: E402
from linkbook.engine import vector as vectorized  # noqa: E402
from linkbook.engine import evaluator as engine  # noqa: E402

TOL = 1e-12
SWEEP = "Stroke sweep"
FIRST, LAST = 5, 40           # 36 angles, 0..350 degrees
PARAMS = {"a_1": 2.0, "a_2": 1.0, "a_3": 1.2, "a_4": 1.0, "branch": 1}

SWEEP_COLUMNS = {              # letter -> formula template for row {r} ({p} = row above)
    "B": "=RADIANS(A{r})",
    "C": "=a_2*COS(B{r})-a_1",
    "D": "=a_2*SIN(B{r})",
    "E": "=SQRT(C{r}^2+D{r}^2)",
    "F": "=ATAN2(C{r},D{r})",
    "G": "=IFERROR(ACOS((a_3^2+a_4^2-E{r}^2)/(2*a_3*a_4)),NA())",   # #N/A where E > 2.2
    "H": "=DEGREES(G{r})",
    "I": "=F{r}-branch*G{r}",                                       # #N/A propagates
    "J": "=MAX(ABS(C{r}),ABS(D{r}))",            # not element-wise: row by row in vector mode
    "K": '=IF(ISNUMBER(G{r}),"yes","no")',
    "L": "=AND(E{r}>1.5,E{r}<2.5)",
    "M": "=10^A{r}",                             # overflows to #VALUE! past 10^308
    "N": "=LOG10(A{r}+1)+1E-12*$A$5-$A{r}/1E+3",
    "O": "=MOD(A{r},90)+ROUND(B{r},3)",
    "P": "='Stroke sweep'!C{r}+Grid!$B$7",       # qualified refs, own sheet and another
    "Q": "=Q{p}+B{r}",                           # running sum: a group that reads itself
    "R": "=S{p}+1",                              # R and S read each other across rows
    "S": "=R{r}*0.5",
    "T": "=B{r}+$B$5+B{r}",                      # B5 and $B$5 are one compiled input in row 5
    "U": "=B{r}*$B{r}",                          # one input, two descriptors, same cells
    "V": "=SUM((B{r},C{r}))",                    # union: compiled cell by cell
}


def build_book() -> openpyxl.Workbook:
    wb = openpyxl.Workbook()
    mech = wb.active
    mech.title = "Mechanism"
    for i, (name, value) in enumerate(PARAMS.items()):
        mech.cell(row=3 + i, column=2, value=name)
        mech.cell(row=3 + i, column=3, value=value)
        wb.defined_names[name] = DefinedName(name, attr_text=f"'Mechanism'!$C${3 + i}")
    wb.defined_names["angles"] = DefinedName(
        "angles", attr_text=f"'{SWEEP}'!$A${FIRST}:$A${LAST}")
    mech["E3"] = "text constant"
    mech["E4"] = True

    ws = wb.create_sheet(SWEEP)
    for r in range(FIRST, LAST + 1):
        ws[f"A{r}"] = 10.0 * (r - FIRST)
        for letter, template in SWEEP_COLUMNS.items():
            ws[f"{letter}{r}"] = template.format(r=r, p=r - 1)
    ws[f"Q{FIRST}"] = f"=B{FIRST}"
    ws[f"R{FIRST}"] = "=1"

    grid = wb.create_sheet("Grid")
    for j in range(6):
        grid.cell(row=7, column=2 + j, value=0.5 * (j + 1))
    for i in range(19):
        grid.cell(row=8 + i, column=1, value=i - 9)
        for j in range(6):
            grid.cell(row=8 + i, column=2 + j, value=f"=$A{8 + i}*{'BCDEFG'[j]}$7+a_1")

    rng = f"'{SWEEP}'!B{FIRST}:B{LAST}"
    summary = wb.create_sheet("Summary sheet")
    cells = {
        "A1": f"=MAX({rng})-MIN('{SWEEP}'!$B${FIRST}:$B${LAST})",
        "A2": f"=COUNT('{SWEEP}'!G{FIRST}:G{LAST})",
        "A3": f"=ROWS('{SWEEP}'!G{FIRST}:G{LAST})-COUNT('{SWEEP}'!G{FIRST}:G{LAST})",
        "A4": f'=IFERROR(SMALL(\'{SWEEP}\'!G{FIRST}:G{LAST},2),"-")',
        "A5": "=SUM(Grid!B8:G26)",
        "A6": "=MAX(angles)",
        "A7": "=a_1+a_2*branch",
        "A8": "=ATAN2(0,0)",
        "A9": "=SQRT(-1)",
        "A10": "=1/0",
        "A11": "=NA()",
        "A12": "=Z99+1",                      # empty cell counts as 0
        "A13": "=ROW()+COLUMN(C3)",           # host-cell function: compiled per cell
        "A14": f"=SUM('{SWEEP}'!Q{FIRST}:Q{LAST})",
        "A15": "=Mechanism!E3",
        "A16": "=NOT(Mechanism!E4)",
    }
    for ref, formula in cells.items():
        summary[ref] = formula
    return wb


def compare(ours: dict, theirs: dict) -> float:
    """Assert same keys, same error codes, same str/bool, numbers within TOL; max |diff|."""
    assert set(ours) == set(theirs)
    worst = 0.0
    for key, want in theirs.items():
        got = ours[key]
        if engine.is_error(want) or engine.is_error(got):
            assert engine.error_code(got) == engine.error_code(want), (key, got, want)
        elif isinstance(want, float):
            assert isinstance(got, float), (key, got, want)
            assert abs(got - want) <= TOL, (key, got, want)
            worst = max(worst, abs(got - want))
        else:
            assert type(got) is type(want) and got == want, (key, got, want)
    return worst


@pytest.fixture(scope="module")
def book_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("engine") / "mechanism.xlsx"
    build_book().save(path)
    return path


@pytest.fixture(scope="module")
def model_values(book_path):
    return engine.evaluate_formulas_model(book_path)


@pytest.mark.slow        # formulas' ExcelModel
def test_every_cell_matches_excel_model(book_path, model_values):
    ours = engine.evaluate_file(book_path)
    compare(ours, model_values)
    # The book really exercises what it claims to.
    codes = {engine.error_code(v) for v in ours.values()}
    assert {"#N/A", "#DIV/0!", "#NUM!", "#VALUE!"} <= codes
    assert engine.error_code(ours[(SWEEP, "I23")]) == "#N/A"       # 180°: propagated via F - G
    assert ours[(SWEEP, "K5")] == "yes" and ours[(SWEEP, "K25")] == "no"
    assert ours[("Summary sheet", "A12")] == 1.0
    assert all(isinstance(ours[(SWEEP, f"L{r}")], bool) for r in range(FIRST, LAST + 1))


def edge_book(sheet: str = "Data sheet") -> openpyxl.Workbook:
    """Constants of every kind, names to an empty and to a formula cell, error constants."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = sheet
    for i, v in enumerate([5.0, "abc", True, "#N/A", 123456789.123456789, 2 ** 60, 0.1 + 0.2,
                           1e-17, -0.0, ""], start=1):
        ws[f"A{i}"] = v
    q = "'" + sheet.replace("'", "''") + "'"
    other = wb.create_sheet("Other 2")
    formulas = {"B1": f'={q}!A1&"x"', "B2": f"={q}!A2*2", "B3": f"={q}!A3+1", "B4": f"={q}!A4",
                "B5": f"=ISNA({q}!A4)", "B6": "=Z99", "B7": "=nm_empty+1", "B8": "=nm_formula*2",
                "B9": f"={q}!A5*1", "B10": f"={q}!A6+1", "B11": f"={q}!A7*3",
                "B12": f"={q}!A8*1E+17", "B13": '=IF(1>2,"a",Z98)', "B14": '=""', "B15": "=TRUE",
                "B16": f"=SUM({q}!A1:A9)", "C1": "=B1&B2", "C2": f"={q}!A10+1",
                "C3": f'={q}!A10&"x"'}
    for ref, formula in formulas.items():
        other[ref] = formula
    for r in range(1, 6):
        other[f"D{r}"] = f'=IFERROR(1/(E{r}-2),"inf")'
        other[f"E{r}"] = r
    wb.defined_names["nm_empty"] = DefinedName("nm_empty", attr_text="'Other 2'!$Z$50")
    wb.defined_names["nm_formula"] = DefinedName("nm_formula", attr_text="'Other 2'!$B$11")
    return wb


def as_excel_model_gives(wb, path) -> dict:
    """The book saved at `path`, evaluated by the engine (constants rounded as ExcelModel
    rounds them) and checked cell by cell against formulas' ExcelModel; the engine's values."""
    wb.save(path)
    ours = engine.evaluate_file(path, excel_model_constants=True)
    compare(ours, engine.evaluate_formulas_model(path))
    return ours


def test_constants_names_and_empty_cells_match_excel_model(tmp_path):
    path = tmp_path / "edge.xlsx"
    ours = as_excel_model_gives(edge_book(), path)
    compare(engine.evaluate(edge_book(), excel_model_constants=True), ours)
    assert ours[("Other 2", "B1")] == "5x"          # 5.0 is saved as 5
    assert ours[("Data sheet", "A8")] == 0.0          # 1e-17 rounded to 15 decimals, as ExcelModel
    assert ours[("Other 2", "B7")] == 1.0             # a name of an empty cell is 0
    # without ExcelModel's rounding, a constant is the double the file holds (as in Excel)
    assert engine.evaluate_file(path)[("Data sheet", "A8")] == 1e-17


def test_sheet_name_with_apostrophe():
    """ExcelModel answers #REF! for 'It''s'!A1 (formulas 1.3.4); the engine reads the cell."""
    values = engine.evaluate(edge_book("It's"))
    assert values[("Other 2", "B1")] == "5x"
    assert values[("Other 2", "B11")] == pytest.approx(0.9)


def test_in_memory_book_equals_saved_book(book_path):
    """evaluate(wb) before saving gives exactly what the saved file evaluates to."""
    assert compare(engine.evaluate(build_book()), engine.evaluate_file(book_path)) == 0.0


@pytest.mark.parametrize("wanted, needs, not_needed", [
    # a name, a range of a column that reads itself down the rows, a union of two columns
    ([("Summary sheet", "A6"), ("Summary sheet", "A14")], [(SWEEP, f"Q{LAST}")],
     [("Grid", "B8"), (SWEEP, "C5")]),
    ([(SWEEP, "V9")], [(SWEEP, "B9"), (SWEEP, "C9")], [(SWEEP, "D9"), ("Summary sheet", "A1")]),
    ([("Summary sheet", "A5")], [("Grid", "G26")], [(SWEEP, "B5")]),
])
def test_only_evaluates_what_the_wanted_cells_need(book_path, model_values, wanted, needs,
                                                    not_needed):
    """evaluate(only=...) gives ExcelModel's values for the wanted cells and what they read, and
    leaves out formulas they do not need."""
    values = engine.evaluate(openpyxl.load_workbook(book_path), only=set(wanted))
    for cell in wanted + needs:
        compare({cell: values[cell]}, {cell: model_values[cell]})
    for cell in not_needed:
        assert cell not in values


def test_per_cell_mode_matches_excel_model(book_path, model_values):
    """The fallback path alone (no vector calls) is also ExcelModel's result."""
    eng = engine.Engine(openpyxl.load_workbook(book_path), vectorize=False)
    compare(eng.run(), model_values)
    assert eng.stats["vector_groups"] == 0


def test_modes_chosen(book_path):
    eng = engine.Engine(openpyxl.load_workbook(book_path))
    eng.run()
    by_shape = {(g.sheet, references.cell_name(g.members[0].row, g.members[0].col)): g
                for g in eng.groups}
    assert by_shape[(SWEEP, "B5")].mode == "vector"
    assert by_shape[(SWEEP, "B5")].batch.row_by_row == 0
    assert by_shape[(SWEEP, "J5")].mode == "vector"             # MAX picks its winner per row
    assert by_shape[(SWEEP, "J5")].batch.row_by_row == 0
    assert by_shape[(SWEEP, "J5")].batch.numeric > 0
    assert by_shape[(SWEEP, "M5")].batch.row_by_row > 0         # the overflow collapsed ^
    assert by_shape[(SWEEP, "T5")].mode == "vector"   # compiled from row 6: B5, $B$5 collide in 5
    assert by_shape[(SWEEP, "U5")].mode == "vector"   # B5 and $B5 are the same cell in every row
    assert by_shape[(SWEEP, "V5")].mode == "each"     # a union is not one reference
    assert by_shape[("Grid", "B8")].mode == "vector"
    assert len(by_shape[("Grid", "B8")].members) == 19 * 6
    assert by_shape[("Summary sheet", "A13")].mode == "each"     # ROW()
    assert len(by_shape[(SWEEP, "N5")].members) == LAST - FIRST + 1
    assert eng.stats["shapes"] <= 2 * len(SWEEP_COLUMNS) + 20
    assert eng.stats["running_sums"] == 1                        # Q: its terms as one array
    # R and S read each other across rows: a row recurrence, evaluated as one scan down the
    # rows (every cell by its fast form), not split into cells
    assert eng.stats["split_groups"] == 0
    assert (eng.stats["scans"], eng.stats["scan_cells"], eng.stats["scan_cell_path"]) == (
        1, 2 * (LAST - FIRST + 1) - 1, 0)
    assert len(by_shape[(SWEEP, "S5")].members) == LAST - FIRST + 1


def test_shapes_of_a_361_row_table():
    wb = openpyxl.Workbook()
    ws = wb.active
    for name, value in PARAMS.items():
        wb.defined_names[name] = DefinedName(name, attr_text="'Sheet'!$Z$1")
    ws["Z1"] = 1.5
    columns = [t for k, t in SWEEP_COLUMNS.items() if k in "BCDEFGHIJK"]
    for k in range(361):
        r = 2 + k
        ws[f"A{r}"] = float(k)
        for j, template in enumerate(columns):
            ws.cell(row=r, column=2 + j, value=template.format(r=r, p=r - 1))
    eng = engine.Engine(wb)
    values = eng.run()
    assert eng.stats["formula_cells"] == 3610
    assert eng.stats["shapes"] == 10
    assert eng.stats["compiled"] + eng.stats["reused"] == 10   # one compile per shape
    assert eng.stats["vector_groups"] == 10
    assert values[("Sheet", "B362")] == pytest.approx(math.radians(360.0))


def test_3601_rows_evaluate():
    """Scale check (no timing assertion): a 3601-row sweep runs and gives sane values."""
    wb = build_book()
    ws = wb[SWEEP]
    last = FIRST + 3600
    for r in range(LAST + 1, last + 1):
        ws[f"A{r}"] = 0.1 * (r - FIRST)
        for letter in "BCDEFGHI":
            ws[f"{letter}{r}"] = SWEEP_COLUMNS[letter].format(r=r, p=r - 1)
    values = engine.evaluate(wb)
    angles = np.radians(0.1 * np.arange(3601))
    got = np.array([values[(SWEEP, f"B{r}")] for r in range(FIRST + 36, last + 1)])
    assert np.allclose(got, angles[36:], rtol=0, atol=1e-12)
    g = [values[(SWEEP, f"G{r}")] for r in range(FIRST, last + 1)]
    assert any(engine.is_error(v) for v in g) and any(isinstance(v, float) for v in g)


# ---------------------------------------------------------------- references and shapes

def test_shape_relative_and_absolute_parts():
    assert engine.shape_of("=A8*COS(B8)-$D$2+E$7", "C8") == (
        "='Sheet'!R[0]C[-2]*COS('Sheet'!R[0]C[-1])-'Sheet'!R2C4+'Sheet'!R7C[2]")
    # the same formula copied one row down has the same shape
    assert engine.shape_of("=A9*COS(B9)-$D$2+E$7", "C9") == engine.shape_of(
        "=A8*COS(B8)-$D$2+E$7", "C8")
    assert engine.shape_of("=$A9*B$7", "C9") != engine.shape_of("=A9*B7", "C9")


def test_shape_of_ranges_sheets_and_names():
    wb = build_book()
    shape = engine.shape_of(f"=MAX('{SWEEP}'!$B$5:$B$40)+Grid!B8:C9+a_1", "D10", SWEEP, wb)
    assert shape == (f"=MAX('{SWEEP}'!R5C2:R40C2)+'Grid'!R[-2]C[-2]:R[-1]C[-1]"
                     f"+'Mechanism'!R3C3")
    assert engine.shape_of("=a_1*2", "B2", SWEEP, wb) == engine.shape_of(
        "=Mechanism!$C$3*2", "B2", SWEEP, wb)


@pytest.mark.parametrize("formula", [
    "=A8*COS(B8)-$D$2+E$7",
    "=1E-12*A1+2.5E+3-.5e-2",
    "=LOG10(A1)+ATAN2(B2,C3)+LOG10(2)",
    '="A1 and B2"&C3&"""quoted"" D4"',
    "=SUM('Stroke sweep'!$B$5:$B$365)+Sweep!D8+'It''s'!A1",
    "=a_2*COS(B8)-a_1+branch",
    "=IF(TRUE,#N/A,FALSE)+IFERROR(#DIV/0!,1)",
    "=SUM(A1:B2 B1:B3)",
    "=A1:INDEX(A1:A4,2)",
    "=SUM(A:A)",
])
def test_lexer_finds_what_the_tokenizer_finds(formula):
    refs = references.References(["Sheet", "Stroke sweep", "Sweep", "It's"],
                             {n: "'Sheet'!$Z$1" for n in ("a_1", "a_2", "branch")})
    lexed = references.lex_spans(formula, refs)
    tokens = adapter.tokenize(formula).spans
    if formula in ("=A1:INDEX(A1:A4,2)", "=SUM(A:A)"):
        assert lexed != tokens   # the lexer misses these; the tokenizer path takes over
    else:
        assert lexed == tokens


@pytest.mark.parametrize("formula", ['=INDIRECT("A1")', "=OFFSET(A1,1,1)", "=SUM(A:A)",
                                     "=nosuchname+1", "=Nowhere!A1"])
def test_unsupported_formulas_raise(formula):
    wb = openpyxl.Workbook()
    wb.active["B2"] = formula
    with pytest.raises(engine.UnsupportedFormulaError):
        engine.evaluate(wb)


def test_circular_reference_raises():
    wb = openpyxl.Workbook()
    wb.active["A1"] = "=B1+1"
    wb.active["B1"] = "=A1+1"
    with pytest.raises(engine.CircularReferenceError):
        engine.evaluate(wb)


# ---------------------------------------------------------------- element-wise functions

PANEL = [0.5, -0.5, 0.0, 2.0, -3.7, 1e-300, 1e300, 7, True, False, "abc", "2.5", None,
         "#N/A", "#DIV/0!"]
SECOND = [0.5, -1, 0, 2, 3.7, True, "abc", None, "#VALUE!"]
ONE_ELEMENTWISE = sorted(f for f in vectorized.ELEMENTWISE if f.isalpha() and f not in {
    "ATAN2", "POWER", "MOD", "ROUND", "ROUNDDOWN", "ROUNDUP", "IFERROR", "IFNA", "CHOOSE",
    "IF", "NA", "PI", "bypass", "LOG", "TRUNC"}) + ["LOG", "TRUNC"]
ONE_ARG = list(ONE_ELEMENTWISE)
TWO_ARG = ["ATAN2", "POWER", "MOD", "ROUND", "ROUNDDOWN", "ROUNDUP", "IFERROR", "IFNA", "LOG",
           "TRUNC", "IF"]
# Not element-wise over arrays, run row by row inside vector calls.
ONE_ARG += ["FACT", "SQRTPI", "N", "VALUE", "LEN", "UPPER", "TRIM"]
TWO_ARG += ["MAX", "MIN", "SUM", "AND", "OR", "XOR", "COUNT", "AVERAGE", "PRODUCT", "LEFT",
            "EXACT", "CONCATENATE", "CEILING", "FIND"]
assert set(ONE_ARG + TWO_ARG) <= vectorized.VECTOR_SAFE
OPERATORS = ["+", "-", "*", "/", "^", "&", "=", "<>", "<", ">", "<=", ">="]


def put_pair(ws, r: int, a, b) -> None:
    """Panel values a and b in A and B of row r (an error as the formula that makes it, None
    as an empty cell)."""
    for col, v in ((1, a), (2, b)):
        if isinstance(v, str) and v.startswith("#"):
            ws.cell(row=r, column=col, value=f"={v}")
        elif v is not None:
            ws.cell(row=r, column=col, value=v)


def panel_book() -> openpyxl.Workbook:
    """Every element-wise function over every pair of panel values, one column each."""
    wb = openpyxl.Workbook()
    ws = wb.active
    pairs = [(a, b) for a in PANEL for b in SECOND]
    for i, (a, b) in enumerate(pairs):
        r = 2 + i
        put_pair(ws, r, a, b)
        formulas = ([f"={f}(A{r})" for f in ONE_ARG] + [f"={f}(A{r},B{r})" for f in TWO_ARG]
                    + [f"=A{r}{op}B{r}" for op in OPERATORS]
                    + [f"=-A{r}", f"=A{r}%", f"=+A{r}", f"=PI()*A{r}+NA()*0",
                       f"=CHOOSE(2,A{r},B{r})", f"=IF(A{r}>0,B{r},NA())",
                       f"=MAX(ABS(A{r}),B{r})+IF(AND(A{r}>0,B{r}<1),1,2)",
                       f'=MID(A{r},1,2)&TEXT(B{r},"0.00")'])
        for j, formula in enumerate(formulas):
            ws.cell(row=r, column=3 + j, value=formula)
    return wb


def assert_as_per_cell(got: dict, want: dict) -> None:
    """Every cell of `want` (a per-cell evaluation) has the same value and type in `got`: the
    same error, NaN for NaN."""
    for key, w in want.items():
        g = got[key]
        if engine.is_error(w) or engine.is_error(g):
            assert engine.error_code(g) == engine.error_code(w), key
        elif isinstance(w, float) and math.isnan(w):
            assert isinstance(g, float) and math.isnan(g), key
        else:
            assert type(g) is type(w) and g == w, (key, g, w)


def test_elementwise_functions_vectorize_exactly():
    """Vector calls give, cell by cell, the same value and type as per-cell calls."""
    wb = panel_book()
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    assert vector.stats["vector_groups"] >= len(ONE_ARG) + len(TWO_ARG) + len(OPERATORS)
    assert vector.stats["row_by_row_nodes"] >= len(ONE_ARG) - len(ONE_ELEMENTWISE)
    assert set(got) == set(want)
    assert_as_per_cell(got, want)


def test_compiled_shapes_are_reused_with_identical_results():
    """A second book of the same layout (other inputs) reuses every compiled shape and still
    gives exactly what a fresh ExcelModel-equivalent evaluation gives."""
    from linkbook.language import templates
    from linkbook.book import workbook
    first = workbook.build(templates.load("slider-crank")).workbook
    engine.Engine(first).run()
    t = templates.with_overrides(templates.load("slider-crank"), ["a1=-7", "a3=90"])
    second = workbook.build(t).workbook
    eng = engine.Engine(second)
    reused = eng.run()
    assert eng.stats["reused"] == eng.stats["shapes"] and eng.stats["compiled"] == 0
    fresh = engine.Engine(second, vectorize=False).run()
    assert all(_same_value(reused[k], fresh[k]) for k in fresh)


def test_formulas_of_one_skeleton_share_a_compiled_function_by_position(tmp_path):
    """Formulas that differ only in the cells they read share one compiled function, its inputs
    tied by position: swapped references, equal references and a mixed pattern must each give
    ExcelModel's values."""
    wb = openpyxl.Workbook()
    ws = wb.active
    for r in range(1, 7):
        ws[f"A{r}"], ws[f"B{r}"], ws[f"C{r}"] = r, 10 * r + 1, 100 * r + 3
        ws[f"D{r}"] = f"=A{r}-B{r}/C{r}"
    cells = {"E1": "=B1-A1/C1", "E2": "=C2-A2/B2", "E3": "=A3-A3/B3", "E4": "=$A$4-A4/C4",
             "E5": "=B5-B5/B5", "E6": "=C6-B6/A6", "F1": "=A1-B1/A1", "F2": "=B3-C4/A5"}
    for cell, text in cells.items():
        ws[cell] = text
    path = tmp_path / "skeleton.xlsx"
    wb.save(path)
    eng = engine.Engine(openpyxl.load_workbook(path))
    compare(eng.run(), engine.evaluate_formulas_model(path))
    assert eng.stats["reused"] >= 4


def _same_value(a, b) -> bool:
    if engine.is_error(a) or engine.is_error(b):
        return engine.error_code(a) == engine.error_code(b)
    return a == b


def numeric_book(rows: int = 600) -> openpyxl.Workbook:
    """Random finite numbers over many scales (and the edges of each function's domain) for
    every function that has a numeric form, one column each."""
    rng = np.random.default_rng(20261122)
    scales = [1.0, 1e-6, 1e3, 1e150, 1e-300]
    edges = [0.0, 1.0, -1.0, 2.0, 0.5, -0.0, 1e308, 700.0, 710.0, 3, -2, 0.9999999999999999]
    a = np.concatenate([rng.uniform(-1, 1, rows) * rng.choice(scales, rows), edges])
    b = np.concatenate([rng.uniform(-3, 3, rows) * rng.choice(scales, rows), edges[::-1]])
    b[::7] = np.round(b[::7])                       # integer exponents for ^
    # A power that never overflows nor divides by zero: positive and negative bases of moderate
    # size, whole and fractional exponents (a negative base with a fractional one is #NUM!).
    base = rng.uniform(-1, 1, a.size) * rng.choice([1e-3, 1.0, 50.0], a.size)
    exponent = np.where(np.arange(a.size) % 2, np.round(b % 7 - 3), b % 7 - 3)
    wb = openpyxl.Workbook()
    ws = wb.active
    forms = sorted(vectorized.NUMERIC_FORMS)
    for i, (x, y) in enumerate(zip(a.tolist(), b.tolist())):
        r = 1 + i
        ws.cell(row=r, column=1, value=x)
        ws.cell(row=r, column=2, value=int(y) if i % 11 == 0 else y)
        ws.cell(row=r, column=3 + len(forms), value=float(base[i]))
        ws.cell(row=r, column=4 + len(forms), value=float(exponent[i]))
        powers = f"{get_column_letter(3 + len(forms))}{r}^{get_column_letter(4 + len(forms))}{r}"
        ws.cell(row=r, column=5 + len(forms), value=f"={powers}")
        for j, name in enumerate(forms):
            if name == "u-":
                text = f"=-A{r}"
            elif name in "+-*/^" or name in vectorized.COMPARISONS:
                text = f"=A{r}{name}B{r}"
            else:
                text = f"={name}(A{r},B{r})" if name in ("ATAN2", "MOD") else f"={name}(A{r})"
            ws.cell(row=r, column=3 + j, value=text)
    return wb


def test_numeric_forms_give_formulas_own_bits_and_types():
    """On finite numbers the numeric forms replace formulas' per-element calls: every value
    (and error) must be the one the per-cell evaluation gives, bit for bit and of the same type."""
    wb = numeric_book()
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    # Every form ran on its column, and ^ on the column of moderate powers; 2^710 in the other ^
    # column overflows, which makes formulas' own call raise for the whole column, so that node
    # ran row by row, as a per-cell call does.
    assert vector.stats["numeric_nodes"] == len(vectorized.NUMERIC_FORMS)
    assert vector.stats["row_by_row_nodes"] == 1
    assert set(got) == set(want)
    errors = 0
    for key, w in want.items():
        g = got[key]
        if engine.is_error(w) or engine.is_error(g):
            errors += 1
            assert engine.error_code(g) == engine.error_code(w), (key, g, w)
        else:
            assert type(g) is type(w) and (g == w or (g != g and w != w)), (key, g, w)
    assert errors > 0        # the domain edges were reached: formulas made those errors


def test_comparisons_give_formulas_own_booleans():
    """A comparison's numeric form, row by row as a per-cell evaluation gives it, and of the
    type the formula's next node reads (TRUE joined to text): equal floats, 0 and -0, an int
    beside a float, text, booleans, blanks and errors."""
    pairs = [(1.5, 1.5), (0.0, -0.0), (2.0, 3.0), (3.0, 2.0), (1e-300, 0.0), (7, 7.0),
             ("a", "A"), ("b", 1.0), (True, 1.0), (None, 0.0), (None, ""), ("=NA()", 1.0),
             ("=1/0", 2.0), (-1e308, 1e308)] * 3
    wb = openpyxl.Workbook()
    ws = wb.active
    names = sorted(vectorized.COMPARISONS)
    for r, (a, b) in enumerate(pairs, start=1):
        ws.cell(row=r, column=1, value=a)
        ws.cell(row=r, column=2, value=b)
        for j, name in enumerate(names):
            ws.cell(row=r, column=3 + j, value=f"=A{r}{name}B{r}")
        ws.cell(row=r, column=3 + len(names), value=f'=(A{r}<B{r})&""')
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    assert vector.stats["numeric_nodes"] == len(names) + 1
    assert set(got) == set(want)
    for key, w in want.items():
        g = got[key]
        assert type(g) is type(w) and _same_value(g, w), (key, g, w)


def test_if_picks_as_formulas_does():
    """IF on arrays, row by row as a per-cell evaluation gives it: conditions that are
    booleans (a comparison's, ISNUMBER's), numbers (0, -0, 2.5), text, blanks and errors;
    branches that are numbers, text, blanks, booleans and errors; with and without the third
    argument; and what it gives read by the next node (a blank picked is 0: "0" as text)."""
    conditions = ["=A{r}>0", "=ISNUMBER(A{r})", "=A{r}", '="x"', "=1/0", "=Z{r}"]
    values = [1.5, 0.0, -0.0, 2.5, -3.0, "t", True, None, "=NA()"]
    wb = openpyxl.Workbook()
    ws = wb.active
    r = 0
    for a in values:
        for x in values:
            r += 1
            ws[f"A{r}"], ws[f"B{r}"], ws[f"C{r}"] = a, x, -7.0
            for j, condition in enumerate(conditions):
                test = condition.format(r=r)[1:]
                ws.cell(row=r, column=5 + 2 * j, value=f"=IF({test},B{r},C{r})")
                ws.cell(row=r, column=6 + 2 * j, value=f"=IF({test},B{r})")
            ws.cell(row=r, column=5 + 2 * len(conditions), value=f'=IF(A{r}>0,B{r},C{r})&""')
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    assert vector.stats["numeric_nodes"] >= 2 * len(conditions)
    assert set(got) == set(want)
    for key, w in want.items():
        g = got[key]
        assert type(g) is type(w) and _same_value(g, w), (key, g, w)


def test_verifying_a_book_imports_no_scipy(tmp_path):
    """`formulas`' statistics module imports scipy at its top, and its math module numpy.random;
    linkbook imports those modules with scipy and numpy.random standing in (issue 14: about a
    second, and 15 ms, of every verify's start-up), so a book that uses no function needing them
    never imports them (numpy.random: unless numpy itself does, as 1.26 does at its import),
    one that does still gets them, and numpy.random is numpy's own module afterwards."""
    import subprocess
    import sys
    from linkbook.book import builder
    from linkbook.language import templates
    book = tmp_path / "fourbar.xlsx"
    builder.build_file(templates.load("fourbar"), book)
    code = ("import sys, numpy, linkbook; eager = 'numpy.random' in sys.modules; "
            "r = linkbook.verify(sys.argv[1]); "
            "print(r.status, 'scipy' in sys.modules, eager or 'numpy.random' not in sys.modules); "
            "from formulas.functions import get_functions; "
            "print(round(get_functions()['KURT'](1, 2, 3, 4, 7), 6), 'scipy' in sys.modules); "
            "rand = get_functions()['RAND']['function']; x = float(rand(False)); "
            "print(0 <= x < 1, 'numpy.random' in sys.modules); "
            "import numpy.random as real; numpy.random.seed(7); a = numpy.random.rand(); "
            "real.seed(7); b = float(rand(False)); print(numpy.random is real, a == b)")
    out = subprocess.run([sys.executable, "-c", code, str(book)], capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == ["0", "False", "True", "1.128515", "True", "True", "True", "True", "True"], out


def test_min_and_max_pick_the_first_winner_as_per_cell_calls_do():
    """MIN, MAX and COUNT of one value per row run on arrays in vector calls: the winner is the
    first smallest (largest) argument itself, as formulas' per-cell call gives it (value and
    type), ints among the numbers; rows with a text that reads as a number, a NaN, an integer
    beyond 2^53 or (for MIN and MAX) an error take the per-cell path."""
    pairs = [(0.5, 0.5), (1.5, -2.5), (-2.5, 1.5), (1e-300, -1e-300), (0.0, -0.0), (-0.0, 0.0),
             (3.0, 3), (3, 3.0), (56, 62.3), (2.0, True), ("4", 1.0), ("abc", 2), (1.0, "#N/A"),
             (float("nan"), 1.0), (1.0, float("nan")), (2 ** 60, 2 ** 60 + 1), (None, None),
             (None, 7)]
    wb = openpyxl.Workbook()
    ws = wb.active
    for r, (a, b) in enumerate(pairs, start=1):
        for col, v in ((1, a), (2, b)):
            ws.cell(row=r, column=col, value=f"={v}" if v == "#N/A" else v)
        for col, f in enumerate(("MIN", "MAX", "COUNT"), start=3):
            ws.cell(row=r, column=col, value=f"={f}(A{r},B{r})")
            ws.cell(row=r, column=col + 3, value=f"={f}(B{r},A{r},B{r})")
            ws.cell(row=r, column=col + 6, value=f"={f}(A{r},2.5)+{f}(A{r},-1)")
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    assert vector.stats["vector_groups"] >= 9
    assert vector.stats["numeric_nodes"] >= 12          # each MIN, MAX and COUNT ran on arrays
    assert_as_per_cell(got, want)


# Values a range can hold, as the value grid holds them: numbers of each type, booleans, text
# (some of which reads as a number), empty cells and every error.
RANGE_VALUES = [1.5, -2.0, 3, 0.0, -0.0, 1e300, -1e-300, 7.25, np.float64(-4.5), np.int64(9),
                True, False, "abc", "", "—", "2.5", sh.EMPTY, float("nan"), 2 ** 60,
                *(Error.errors[code] for code in ("#N/A", "#DIV/0!", "#VALUE!", "#NUM!",
                                                  "#REF!", "#NAME?", "#NULL!"))]
PLAIN = [v for v in RANGE_VALUES[:17] if not (isinstance(v, str) and v == "2.5")]


def _range_arguments(rng, pool) -> list:
    """One to three arguments: object arrays of random shapes drawn from `pool`, and now and
    then a number, a boolean or a text of the call's own."""
    args = []
    for _ in range(rng.integers(1, 4)):
        if rng.random() < 0.2:
            args.append([2.0, 5, True, "abc", "3"][rng.integers(5)])
            continue
        shape = (int(rng.integers(1, 40)), int(rng.integers(1, 3)))
        a = np.empty(shape, object)
        a.reshape(-1)[:] = [pool[i] for i in rng.integers(len(pool), size=a.size)]
        args.append(a)
    return args


def _same_result(a, b) -> bool:
    """The same value of the same type, the same error, NaN for NaN; arrays element-wise."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
                and type(a) is type(b)
                and all(_same_result(x, y) for x, y in zip(a.reshape(-1), b.reshape(-1))))
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return type(a) is type(b)
    return type(a) is type(b) and a == b and str(a) == str(b)


@pytest.mark.parametrize("name", sorted(vectorized.AGGREGATES))
def test_aggregates_over_ranges_give_what_formulas_gives(name):
    """MIN, MAX and COUNT over ranges computed on arrays give what formulas' own function gives
    for the same arguments, value and type: over numbers, text, booleans, empty cells and each
    error; an error in the range propagates (MIN, MAX) or is not counted (COUNT) as there."""
    from formulas.functions import get_functions
    func = get_functions()[name]
    node = vectorized._ranges_node(func, name)
    rng = np.random.default_rng(20261125)
    on_arrays = 0
    for pool in (PLAIN, RANGE_VALUES, [sh.EMPTY, "—", True], [sh.EMPTY]):
        for _ in range(150):
            args = _range_arguments(rng, pool)
            want = func(*args)
            got = node(*args)
            assert _same_result(got, want), (name, args, got, want)
            on_arrays += pool is PLAIN and all(isinstance(a, np.ndarray) for a in args)
    # Ranges of plain values (no error, no numeric text) are computed on arrays, not by formulas.
    table = np.array([PLAIN * 3], object)
    assert not vectorized._aggregate_rows(name, table)[1].any()
    assert on_arrays > 50


def test_aggregates_over_ranges_in_a_book_match_excel_model(tmp_path):
    """A summary's MIN, MAX and COUNT over long columns mixing numbers, text, booleans, empty
    cells and errors give what formulas.ExcelModel gives (and what the per-cell path gives)."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Data"
    rng = np.random.default_rng(7)
    columns = {"A": [1.5, -2.0, 3, "—", True, None, 1e-300, -0.0],
               "B": [4.25, "abc", False, None, "#N/A", 2, -7.5],
               "C": ["—", None, True],
               "D": [0.5, "#DIV/0!", "x", 12, -3.25]}
    for letter, pool in columns.items():
        for r in range(1, 401):
            v = pool[rng.integers(len(pool))]
            if isinstance(v, str) and v.startswith("#"):
                ws[f"{letter}{r}"] = f"={v}"
            elif v is not None:
                ws[f"{letter}{r}"] = v
    for i, f in enumerate(("MIN", "MAX", "COUNT")):
        for j, args in enumerate(("A1:A400", "B1:B400", "C1:C400", "D1:D400",
                                  "A1:A400,C1:C400,2.5", "A1:B400")):
            ws.cell(row=1 + j, column=6 + i, value=f"={f}({args})")
    path = tmp_path / "aggregates.xlsx"
    wb.save(path)
    got = engine.evaluate_file(path)
    compare(got, engine.evaluate_formulas_model(path))
    assert_as_per_cell(got, engine.Engine(openpyxl.load_workbook(path), vectorize=False).run())
    assert engine.error_code(got[("Data", "F2")]) == "#N/A" and got[("Data", "H2")] > 0


def test_running_sums_are_summed_as_the_cells_add():
    """A column that is the cell above plus a term (the Forces sheet's work column) is summed
    in one pass over its terms; every cell must be what the per-cell path gives, bit for bit
    (the sign of a zero too): with terms over many scales, an #N/A and a #DIV/0! in the chain,
    text above the first cell, a chain of negative zeros, and shapes that are no running sum,
    left to the cell path: `above + a - b`, a comparison, a term that reads the cell above
    again, two columns of one shape each reading the other."""
    rng = np.random.default_rng(7)
    wb = openpyxl.Workbook()
    ws = wb.active
    ws["C1"], ws["D1"], ws["E1"], ws["F1"], ws["G1"] = 0, 0.5, "W", -1e-300, 0
    ws["H1"], ws["I1"], ws["J1"], ws["K1"], ws["M1"] = 1.5, -2.0, 1.0, 3.0, -0.0
    for r in range(2, 400):
        ws[f"A{r}"] = float(rng.normal() * 10.0 ** rng.integers(-12, 12))
        ws[f"B{r}"] = "=NA()" if r == 150 else float(rng.normal())
        ws[f"C{r}"] = f"=C{r - 1}+((A{r}+B{r})/2-0.25)*RADIANS(3)"
        ws[f"D{r}"] = f"=D{r - 1}+A{r}-B{r}"
        ws[f"E{r}"] = f"=E{r - 1}+A{r}*2"
        ws[f"F{r}"] = f"=F{r - 1}+1/(B{r}-B{r})" if r == 300 else f"=F{r - 1}+A{r}/3"
        ws[f"G{r}"] = f"=G{r - 1}+A{r}>0"
        ws[f"H{r}"] = f"=H{r - 1}+H{r - 1}*0.5"
        ws[f"I{r}"] = f"=I{r - 1}+(I{r - 1}+A{r})"
        ws[f"J{r}"] = f"=J{r - 1}+K{r}"           # J and K: one shape, J's term is K's cell
        ws[f"K{r}"] = f"=K{r - 1}+L{r}"
        ws[f"L{r}"] = 0.25 * r
        ws[f"M{r}"] = f"=M{r - 1}+(-0)*A{r}"       # -0.0 + -0.0 stays -0.0
    vector = engine.Engine(wb)
    got = vector.run()
    want = engine.Engine(wb, vectorize=False).run()
    assert vector.stats["running_sums"] >= 3          # C, E and M at least
    assert set(got) == set(want)
    assert_as_per_cell(got, want)
    for key, w in want.items():                       # == does not see the sign of a zero
        if isinstance(w, float) and w == 0:
            assert math.copysign(1.0, got[key]) == math.copysign(1.0, w), key
    assert engine.error_code(got[("Sheet", "C399")]) == "#N/A"
    assert engine.error_code(got[("Sheet", "E2")]) == "#VALUE!"


@pytest.mark.parametrize("formula, dr, copied", [
    ("=A8*COS(B8)-$D$2+E$7", 3, "=A11*COS(B11)-$D$2+E$7"),
    ('=IF(B8>0,"{x}",{1,2})+SUM(F7:F8)', 2, '=IF(B10>0,"{x}",{1,2})+SUM(F9:F10)'),
    ("=Sweep!Z99+'Mechanism'!C6*a_2", -5, "=Sweep!Z94+'Mechanism'!C1*a_2"),
    ("=Sweep!Z99+'Mechanism'!C6", -6, None),              # C0 is no cell
    ("=A8+1", 1048576 - 8, "=A1048576+1"),
    ("=A8+1", 1048576 - 7, None),                          # beyond the last row
    ("=$A$1+B$2+1", -500, "=$A$1+B$2+1"),                  # nothing relative: any copy
])
def test_a_copy_down_a_column_is_its_formula_shifted(formula, dr, copied):
    """The grouping takes a cell for a copy of the one above when its text is the template's
    shift (engine.references.Template.shifted); the texts here are written by hand."""
    from linkbook.engine.references import References
    refs = References(["Sweep", "Mechanism"], {"A_2": "'Mechanism'!$C$6"})
    _, template = refs.fast_shape(formula, "Sweep", 8, 3)
    assert template.shifted(dr, 0) == copied
