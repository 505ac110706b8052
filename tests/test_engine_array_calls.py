"""Nodes that run on whole arrays instead of formulas' per-element calls (engine/vector.py): IF on
a boolean array (ISNUMBER's), IFERROR, ISNUMBER, and the numeric forms over whole ranges in one
cell (a power balance's SUMPRODUCT of two columns). Each must give what formulas' own function
gives for the same arguments, value for value and type for type, over numbers, NaN, infinities,
errors, empty cells, text, booleans and ints; and must have run on the arrays (not handed
everything back)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import openpyxl
import pytest
import schedula as sh
from formulas.functions import get_functions
from formulas.functions.operators import OPERATORS
from formulas.tokens.operand import Error
from openpyxl.utils import get_column_letter

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from conftest import examples  # noqa: E402
from linkbook.engine import adapter  # noqa: E402
from linkbook.engine import evaluator as engine  # noqa: E402
from linkbook.engine import vector as vectorized  # noqa: E402
from test_engine import RANGE_VALUES, _same_result, assert_as_per_cell  # noqa: E402

NA = Error.errors["#N/A"]
# Branches and operands: what a cell or a node can hand a function, scalars of a call's own too.
SCALARS = [2.5, 7, -0.0, "—", "", True, False, sh.EMPTY, NA, Error.errors["#DIV/0!"],
           np.float64(1.25), np.int64(-3)]


def formulas_function(name: str):
    """formulas' own function for a node name, as the engine's pipe takes it."""
    if name.upper() in OPERATORS:
        return OPERATORS[name.upper()]
    return adapter._plain_function(get_functions()[name])


def _objects(rng, shape, pool) -> np.ndarray:
    a = np.empty(shape, object)
    a.reshape(-1)[:] = [pool[i] for i in rng.integers(len(pool), size=a.size)]
    return a


# ---------------------------------------------------------------- IF on a boolean array

TRUTHS = [True, False, 0.0, -0.0, 2.5, -1e-300, float("nan"), float("inf")]


def _condition(rng, n: int):
    """A condition over n rows as a vector call meets it (of n rows, or of one, shared):
    ISNUMBER's boolean array, a plain boolean array, a comparison's or a number's objects
    (booleans and floats), or values of any kind."""
    rows = n if rng.random() < 0.8 else 1
    draw = rng.random()
    if draw < 0.4:
        return get_functions()["ISNUMBER"](_objects(rng, (rows, 1), RANGE_VALUES))
    if draw < 0.6:
        return rng.random((rows, 1)) < 0.5
    return _objects(rng, (rows, 1), TRUTHS if draw < 0.8 else RANGE_VALUES)


def _branch(rng, n: int):
    """A branch: a column of n values of any kind, one value in a (1, 1) array, or a scalar."""
    draw = rng.random()
    if draw < 0.6:
        return _objects(rng, (n, 1), RANGE_VALUES)
    if draw < 0.8:
        return _objects(rng, (1, 1), RANGE_VALUES)
    return SCALARS[rng.integers(len(SCALARS))]


def test_if_on_a_boolean_condition_gives_what_formulas_gives():
    """IF(ISNUMBER(x), a, b) in a vector call: with the condition a boolean array (or booleans
    and numbers, and formulas' call for the rows of anything else), IF picks each row's branch
    on the arrays, exactly formulas' element: the branch's own object, a blank picked as 0,
    FALSE for a missing third argument."""
    def draw(rng, n):
        condition = _condition(rng, n)
        args = [condition, _branch(rng, n)] + ([_branch(rng, n)] if rng.random() < 0.7 else [])
        if condition.size == 1 and not any(vectorized._size(a) == n for a in args[1:]):
            args[1] = _objects(rng, (n, 1), RANGE_VALUES)     # the call is over n rows
        return args
    _on_arrays_as_formulas("IF", 20261128, draw)


def _on_arrays_as_formulas(name: str, seed: int, draw) -> None:
    """`name`'s node, wrapped for vector calls, gives formulas' own result on each set of
    arguments `draw(rng, n)` draws for n rows, and runs on the arrays every time."""
    func = formulas_function(name)
    batch = vectorized.Batch()
    node = vectorized.wrap(func, name, batch)
    rng = np.random.default_rng(seed)
    for _ in range(examples(300, at_least=40)):
        n = int(rng.integers(2, 30))
        args = draw(rng, n)
        batch.n = n
        before = batch.numeric
        got = node(*args)
        batch.n = 1
        assert _same_result(got, func(*args)), (args, got)
        assert batch.numeric == before + 1, args             # it ran on the arrays


def test_iferror_on_arrays_gives_what_formulas_gives():
    """IFERROR(x, alternative) in a vector call picks on the arrays, exactly formulas' element:
    the value itself (a blank as 0) or, for any error, the alternative's object (a blank as
    0); values and alternatives of every kind, columns, single cells and scalars."""
    def draw(rng, n):
        args = [_objects(rng, (n, 1), RANGE_VALUES), _branch(rng, n)]
        if rng.random() < 0.3:
            args.reverse()                  # an error or a blank shared by every row
            if not isinstance(args[0], np.ndarray):
                args[0] = _objects(rng, (1, 1), RANGE_VALUES)
        return args
    _on_arrays_as_formulas("IFERROR", 20261129, draw)


def test_isnumber_of_arrays_gives_what_formulas_gives():
    """ISNUMBER of a column (a vector call's, or a range's in one cell) judged by the values'
    types gives formulas' own FalseArray, element for element: numbers of each type (NaN too)
    are numbers; booleans, errors and blanks are not; text (which formulas reads as a number
    where float() can: "2.5") is left to formulas' call."""
    func = formulas_function("ISNUMBER")
    reached = []

    def spy(*args):
        reached.append(args)
        return func(*args)
    node = vectorized.wrap(spy, "ISNUMBER", None)
    plain = [v for v in RANGE_VALUES if not isinstance(v, str) or isinstance(v, Error)]
    rng = np.random.default_rng(20261130)
    by_type = 0
    for trial in range(examples(200, at_least=40)):
        pool = plain if trial % 2 else RANGE_VALUES + [sh.Token("2")]     # a blank's type
        a = _objects(rng, (int(rng.integers(1, 40)), int(rng.integers(1, 3))), pool)
        arg = a if rng.random() < 0.5 else adapter.ranges_of(
            f"B2:{get_column_letter(1 + a.shape[1])}{1 + a.shape[0]}", a)
        reached.clear()
        got = node(arg)
        assert _same_result(got, func(arg)), (a, got)
        by_type += not reached
    assert by_type >= examples(200, at_least=40) // 3


# ---------------------------------------------------------------- numeric forms over ranges

TWO_OPERANDS = {"+", "-", "*", "/", "^", "ATAN2", "MOD", *vectorized.COMPARISONS}
FINITE = [0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 3, -2, 7, 1e308, -1e308, 1e-300, 700.0, 710.0,
          0.9999999999999999, np.float64(1.25), np.int64(-3), 2 ** 40]
# Everything else a range can hold: NaN, infinities, errors, blanks, text (some of which
# reads as a number), booleans, an int beyond any float.
OTHER = [float("nan"), float("inf"), -float("inf"), sh.EMPTY, "abc", "2.5", "", True, False,
         NA, Error.errors["#VALUE!"], 10 ** 400]


def _finite(rng, size: int) -> list:
    """Random finite numbers over many scales, now and then an edge of FINITE or a boolean (a
    comparison's, which arithmetic reads as 1 or 0)."""
    x = rng.uniform(-3, 3, size) * rng.choice([1.0, 1e-6, 1e3, 1e150, 1e-300], size)
    edges = FINITE + [True, False, np.True_]
    return [edges[rng.integers(len(edges))] if rng.random() < 0.2 else v for v in x.tolist()]


def _operand(rng, shape, other: float):
    """An operand over a range of `shape`: a range's values (a share `other` of them not
    finite numbers), now and then one cell's (1, 1) array or a number of the call's own; as
    the Ranges a cell formula's node receives, or as an array a node before it gave."""
    draw = rng.random()
    if draw < 0.15:
        return FINITE[rng.integers(len(FINITE))]
    size = 1 if draw < 0.3 else int(np.prod(shape))
    values = _finite(rng, size)
    for i in np.flatnonzero(rng.random(size) < other).tolist():
        values[i] = OTHER[rng.integers(len(OTHER))]
    a = np.empty(size, object)
    a[:] = values
    a = a.reshape(shape if size > 1 else (1, 1))
    if rng.random() < 0.1:
        return a.reshape(-1)            # a node's result of one dimension
    if rng.random() < 0.5:
        return a
    return adapter.ranges_of(f"B2:{get_column_letter(1 + a.shape[1])}{1 + a.shape[0]}", a)


def _outcome(func, args):
    """What a call gives, or the type of what it raised (formulas refuses arrays of two shapes
    that do not broadcast)."""
    try:
        return func(*args)
    except Exception as ex:
        return type(ex)


@pytest.mark.parametrize("name", sorted(vectorized.NUMERIC_FORMS))
def test_numeric_forms_over_whole_ranges_give_what_formulas_gives(name):
    """Outside vector calls a node with a numeric form, given ranges of one shape (and numbers
    or single cells), runs the form on their finite numbers and formulas' call on the rest:
    the result must be formulas' own, element for element and in its shape; ranges of
    numbers alone must not reach formulas' call (beyond an element whose result is not
    finite)."""
    func = formulas_function(name)
    reached = []

    def spy(*args):
        reached.append(sum(np.size(a) for a in adapter.parse_ranges(*args)[0]))
        return func(*args)
    node = vectorized.wrap(spy, name, None)
    rng = np.random.default_rng(sum(map(ord, name)))
    on_arrays = 0
    for trial in range(examples(120, at_least=20)):
        other = 0.0 if trial % 2 else rng.choice([0.05, 0.5, 1.0])
        shape = (int(rng.integers(2, 40)), int(rng.integers(1, 3)))
        args = [_operand(rng, shape, other) for _ in range(2 if name in TWO_OPERANDS else 1)]
        if not any(vectorized._size(a) > 1 for a in adapter.parse_ranges(*args)[0]):
            args[0] = _operand(rng, shape, other) if rng.random() < 0.5 else \
                adapter.ranges_of("B2:B3", np.array([[1.5], [-0.0]], object))
        reached.clear()
        want = _outcome(func, args)
        got = _outcome(node, args)
        assert _same_result(got, want), (name, args, got, want)
        on_arrays += other == 0.0 and sum(reached) < np.size(got)
    assert on_arrays >= examples(120, at_least=20) // 10     # (^ overflows on many)


def _sums_book() -> openpyxl.Workbook:
    """Columns of numbers (a blank, text, a boolean and an #N/A among them in some) and cells
    that combine whole columns element by element inside SUMPRODUCT, SUM and MAX, as the
    Forces sheet's power balance and energy do."""
    rng = np.random.default_rng(11)
    wb = openpyxl.Workbook()
    ws = wb.active
    rows = 300
    for r in range(1, rows + 1):
        ws[f"A{r}"] = float(rng.normal() * 10.0 ** rng.integers(-6, 6))
        ws[f"B{r}"] = float(rng.uniform(0.5, 2.0)) if r % 37 else int(r)
        ws[f"C{r}"] = {50: None, 90: "x", 120: True}.get(r, float(rng.normal()))
        ws[f"D{r}"] = "=NA()" if r == 200 else float(rng.normal())
        ws[f"E{r}"] = 0.0 if r == 70 else float(rng.uniform(1, 3))
    col = {c: f"${c}$1:${c}${rows}" for c in "ABCDE"}
    below = {c: f"${c}$2:${c}${rows}" for c in "ABCDE"}
    above = {c: f"${c}$1:${c}${rows - 1}" for c in "ABCDE"}
    cells = [
        f"=SUMPRODUCT(({above['A']}+{below['A']})/2*({below['B']}-{above['B']}))",
        f"=SUMPRODUCT({col['A']}*{col['B']})/SUM({col['B']})",
        f"=SUMPRODUCT({col['A']}*{col['C']})",        # a blank, text and TRUE among the values
        f"=SUM({col['A']}-{col['D']})",               # an #N/A: the sum is #N/A
        f"=SUM({col['A']}/{col['E']})",               # a zero divisor: #DIV/0!
        f"=MAX(ABS({col['A']}-$A$1))+SUMPRODUCT(SQRT({col['E']}),-{col['B']})",
        f"=SUMPRODUCT(({col['A']}>0)*1)+SUMPRODUCT(COS({col['A']})^2+SIN({col['A']})^2)",
        f"=SUMPRODUCT(ATAN2({col['B']},{col['A']}),DEGREES({col['E']}))",
    ]
    for i, text in enumerate(cells, start=1):
        ws[f"H{i}"] = text
    return wb


def test_whole_range_arithmetic_in_a_book_matches_excel_model(tmp_path):
    """Cells that combine whole columns element by element give exactly what formulas.ExcelModel
    gives (its own per-element calls), and what the per-cell path gives; the errors among the
    values propagate as there."""
    path = tmp_path / "sums.xlsx"
    _sums_book().save(path)
    got = engine.evaluate_file(path, excel_model_constants=True)    # its reading of numbers
    model = engine.evaluate_formulas_model(path)
    assert set(got) == set(model)
    assert_as_per_cell(got, model)                 # exactly: bits, types and errors
    per_cell = engine.Engine(openpyxl.load_workbook(path), vectorize=False).run()
    assert_as_per_cell(engine.evaluate_file(path), per_cell)
    assert engine.error_code(got[("Sheet", "H4")]) == "#N/A"
    assert engine.error_code(got[("Sheet", "H5")]) == "#DIV/0!"


def test_ordering_a_numpy_number_gives_formulas_numpy_boolean(tmp_path):
    """formulas gives SIN's result as np.float64, and ordering it against a number gives numpy's
    boolean, which its text join writes "True" (a Python bool: "TRUE"): the numeric forms give
    the same, in a column's vector call, a lone cell's and over a whole range."""
    wb = openpyxl.Workbook()
    ws = wb.active
    for r in range(1, 9):
        ws[f"A{r}"] = r * 0.25
        ws[f"B{r}"] = f"=SIN(A{r})"
        ws[f"C{r}"] = f'=(B{r}<0.5)&(B{r}>=B{r})&(B{r}=0.5)'
    ws["E1"] = '=(SIN($A$2)<0.5)&""'
    ws["E2"] = '=CONCAT((B1:B8<=0.5)&"")'
    path = tmp_path / "orderings.xlsx"
    wb.save(path)
    got = engine.evaluate_file(path)
    assert_as_per_cell(got, engine.evaluate_formulas_model(path))
    assert got[("Sheet", "C1")] == "TrueTRUEFALSE" and got[("Sheet", "E1")] == "True"


def test_a_blank_a_column_gives_is_zero_to_the_next_column():
    """A vector call's blank (a formula that reads an empty cell) is stored as 0, as a per-cell
    call's is (adapter.empty_as_zero), so the next column joins "0" to text, not nothing."""
    wb = openpyxl.Workbook()
    ws = wb.active
    for r in range(1, 7):
        if r % 2:
            ws[f"A{r}"] = 2.5
        ws[f"B{r}"] = f"=A{r}"
        ws[f"C{r}"] = f'=B{r}&"x"'
    vector = engine.Engine(wb)
    got = vector.run()
    assert vector.stats["vector_groups"] >= 2
    assert_as_per_cell(got, engine.Engine(wb, vectorize=False).run())
    assert [got[("Sheet", f"C{r}")] for r in (1, 2)] == ["2.5x", "0x"]
