"""Vector calls: a compiled formula called once for every row of a group, each node of its graph
wrapped to run on (n, 1) arrays, giving, row for row, what a per-cell call gives.

Element-wise nodes (ELEMENTWISE) run on the whole arrays; arithmetic, comparisons and the common
math functions first as float-array operations on the rows of finite numbers (NUMERIC_FORMS),
with formulas' own bits; IF on arrays where its condition is a boolean (a boolean array too,
ISNUMBER's) or a number, and IFERROR; MIN, MAX and COUNT on arrays (AGGREGATES), per row here
and over whole ranges outside vector calls; any other node, and an element-wise node whose
output collapsed, runs row by row on (1, 1) slices, which is exactly what a per-cell call does.
A group of one cell is a call of one row: its numeric forms on its numbers, formulas' own
functions on the rest. Outside vector calls the numeric forms also run over whole ranges of one
shape (a power balance's SUMPRODUCT of two columns' products), element by element as formulas
would.
"""
from __future__ import annotations

import itertools

import numpy as np
import schedula as sh
from formulas.functions import Array, is_number, parse_ranges
from formulas.functions.info import FalseArray
from formulas.tokens.operand import XlError

# Functions whose compiled node maps (n, 1) arrays element by element exactly as it maps (1, 1)
# arrays (checked against per-cell calls over numbers, bools, strings, EMPTY and errors in
# tests/test_engine.py).  Every other node runs row by row in vector mode.
ELEMENTWISE = frozenset("""
    ABS ACOS ACOSH ASIN ASINH ATAN ATAN2 ATANH CHOOSE COS COSH COT CSC DEGREES EVEN EXP IF
    IFERROR IFNA INT ISBLANK ISERR ISERROR ISNA ISNUMBER ISTEXT LN LOG LOG10 MOD NA NOT ODD PI
    POWER RADIANS ROUND ROUNDDOWN ROUNDUP SEC SIGN SIN SINH SQRT TAN TANH TRUNC
    + - * / ^ & = <> < > <= >= u- u+ % bypass
""".split())
# Functions that give one value for scalar arguments but do not map arrays element-wise (MAX
# aggregates them): in vector mode their nodes run row by row.  Anything outside ELEMENTWISE and
# ROW_BY_ROW (ranges-aware ROWS/INDEX, array makers such as {1,2,3} or SEQUENCE, ...) puts its
# group in cell mode, so that no array that merely has n elements is taken for n rows.
ROW_BY_ROW = frozenset("""
    AND AVERAGE CEILING CONCAT CONCATENATE COUNT COUNTA EXACT FACT FALSE FIND FLOOR LEFT LEN
    LOWER MAX MEDIAN MID MIN N OR PRODUCT RIGHT SEARCH SQRTPI SUBSTITUTE SUM SUMSQ TEXT TRIM TRUE
    UPPER VALUE XOR
""".split())
VECTOR_SAFE = ELEMENTWISE | ROW_BY_ROW


class Batch:
    """Rows of the current vector call (1 outside vector calls); shared by a group's nodes.
    `row_by_row` counts node calls that had to run row by row, `numeric` those that ran on float
    arrays (NUMERIC_FORMS)."""
    n = 1
    row_by_row = 0
    numeric = 0


# formulas runs an element-wise function through np.vectorize, one Python call per element with
# an error scan of its arguments: on a 361 × 51 grid of long formulas that is most of the time.
# Where every argument is a finite number, the functions below give, element for element,
# the same bits and type as formulas' own per-element call (its lambda on Python floats, or the
# numpy ufunc on a scalar); tests/test_engine.py checks that on random and edge values.  An element
# whose argument is not a finite number, or whose result is not finite (formulas turns it into
# #NUM!, #DIV/0!, #VALUE!), is left to formulas' own call.
def _typed(fn, kind):
    """An array function whose elements formulas gives as `kind` (its lambdas on Python floats
    give float, a numpy ufunc on a scalar gives np.float64)."""
    return lambda *xs: (fn(*xs), kind)


def _power(x, y):
    # Python's float ** (as in formulas' lambda), not np.power: libm pow and numpy's SIMD pow
    # differ in the last bit.  A complex or overflowing result becomes NaN: formulas decides it.
    out = np.empty(len(x))
    for i, (a, b) in enumerate(zip(x.tolist(), y.tolist())):
        try:
            v = a ** b
        except (OverflowError, ZeroDivisionError):
            v = np.nan
        out[i] = v if type(v) is float else np.nan
    return out, float


def _divide(x, y):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(y == 0, np.nan, x / np.where(y == 0, 1.0, y)), float


def _atan2(x, y):
    return np.where((x == 0) & (y == 0), np.nan, np.arctan2(y, x)), np.float64


def _mod(x, y):
    # formulas' MOD: #DIV/0! for a zero divisor (NaN here: formulas decides), else np.mod
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(y == 0, np.nan, np.mod(x, np.where(y == 0, 1.0, y))), np.float64


NUMERIC_FORMS = {
    "+": _typed(np.add, float), "-": _typed(np.subtract, float),
    "*": _typed(np.multiply, float), "u-": _typed(np.negative, float),
    "/": _divide, "^": _power, "ATAN2": _atan2, "MOD": _mod,
    **{name: _typed(fn, np.float64) for name, fn in {
        "SIN": np.sin, "COS": np.cos, "TAN": np.tan, "ACOS": np.arccos, "ASIN": np.arcsin,
        "ATAN": np.arctan, "SQRT": np.sqrt, "RADIANS": np.radians, "DEGREES": np.degrees,
        "ABS": np.abs, "EXP": np.exp, "SIGN": np.sign}.items()},
}
_NUMBER_TYPES = frozenset({float, int, np.float64, np.int64})

# formulas compares two numbers as Python does (its logic operators give a Python bool). A
# float array compares an int exactly up to 2**53: a cell's number is read as a float, and the
# ints formulas makes (counts, lengths, sums of booleans) are far smaller.
COMPARISONS = {"=": np.equal, "<>": np.not_equal, "<": np.less, ">": np.greater,
               "<=": np.less_equal, ">=": np.greater_equal}
# formulas orders (type, value) tuples: where the values differ their own comparison decides,
# which gives numpy's boolean when either is a numpy number (a SIN's result, which formulas
# gives as np.float64); where they are equal the tuples' lengths do, a Python bool. = and <>
# give a Python bool always.
_ORDERED = "ordered"
NUMERIC_FORMS.update({name: _typed(op, bool if name in ("=", "<>") else _ORDERED)
                      for name, op in COMPARISONS.items()})
_NUMPY_NUMBERS = frozenset({np.float64, np.int64})
# The other forms' functions read each operand with float() (formulas' wrap_ufunc), a boolean
# as 1.0 or 0.0 (a product of comparisons counts the rows where both hold); a comparison
# orders a boolean after every number.
_COMPARISON_FORMS = frozenset(NUMERIC_FORMS[name] for name in COMPARISONS)
_READ_AS_FLOATS = _NUMBER_TYPES | {bool, np.bool_}


def _operand_types(form) -> frozenset:
    """The operands' types a numeric form takes as formulas' function reads them."""
    return _NUMBER_TYPES if form in _COMPARISON_FORMS else _READ_AS_FLOATS


def _objects(result: np.ndarray, kind, operands, xs) -> list:
    """A numeric form's result as the objects formulas' per-element call gives: of `kind`
    (float and bool: Python's; an ordering: _ORDERED's rule over the operands' objects, arrays
    of the result's length, and their values `xs`)."""
    if kind is _ORDERED:
        values = result.tolist()
        numpy_operand = np.zeros(len(values), bool)
        for a in operands:
            if not _NUMPY_NUMBERS.isdisjoint(map(type, a.tolist())):
                numpy_operand |= np.fromiter((type(v) in _NUMPY_NUMBERS for v in a), bool,
                                             len(values))
        for i in np.flatnonzero(numpy_operand & (xs[0] != xs[1])).tolist():
            values[i] = np.bool_(values[i])
        return values
    return result.tolist() if kind in (float, bool) else list(result)


def _columns_of(args, n: int, types: frozenset):
    """The arguments of a node over n rows as object arrays of n (a scalar of `types`, or an
    array of one value, repeated); None when an argument is not such an array or scalar."""
    flat = []
    for a in args:
        if isinstance(a, np.ndarray) and a.size in (1, n):
            a = a.reshape(-1)
        elif type(a) in types:
            a = np.array([a], object)
        else:
            return None
        flat.append(np.broadcast_to(a, (n,)) if a.size == 1 else a)
    return flat


def _rows_of(args, n: int, types: frozenset):
    """The arguments of a node over n rows as (object arrays of n, the rows where every
    argument is of `types`, float arrays of n with those rows filled); None when an argument is
    not a plain array or scalar, or holds an int beyond any float."""
    flat = _columns_of(args, n, types)
    if flat is None:
        return None
    plain = np.ones(n, bool)
    for a in flat:
        if not set(map(type, a.tolist())) <= types:    # else every row is plain (most columns)
            plain &= np.fromiter((type(v) in types for v in a), bool, n)
    xs = []
    for a in flat:
        x = np.zeros(n)
        try:
            x[plain] = a[plain].astype(float)
        except OverflowError:       # an int beyond any float: formulas' call decides
            return None
        xs.append(x)
    return flat, plain, xs


def _numeric_call(form, func, args, n: int, whole: bool = False):
    """`func` (formulas' node) over n rows: `form` on the rows where it applies, `func` on the
    rest.  None when an argument is not a plain array or scalar (the caller uses `func`), and
    for a `whole` call (not row by row) when `func` raised on the rest: formulas' call on the
    whole arrays then gives one #VALUE! (an overflowing ^), which the caller's call gives."""
    rows = _rows_of(args, n, _operand_types(form))
    if rows is None:
        return None
    flat, plain, xs = rows
    with np.errstate(all="ignore"):
        result, kind = form(*xs)
    for x in (result, *xs):     # a NaN operand: formulas' comparison of it reads its identity
        plain &= np.isfinite(x)
    out = np.empty(n, object)
    out[:] = _objects(result, kind, flat, xs)
    if not plain.all():
        rest = ~plain
        sub = func(*[a[rest].reshape(-1, 1) if a.size == n and not _is_broadcast(a) else
                     np.asarray(a[:1], object).reshape(1, 1) for a in flat])
        k = int(rest.sum())
        if not isinstance(sub, np.ndarray) or sub.size != k or whole and not _elementwise(sub):
            return None                                         # an exception collapsed it
        out[rest] = sub.reshape(-1)
    return out.reshape(n, 1).view(Array)


def _elementwise(out: np.ndarray) -> bool:
    """Whether formulas' element-wise function gave its result element by element (an Array)
    rather than the one error of an exception it caught (a plain array, even of one row)."""
    return isinstance(out, Array)


def _one_number_call(form, args):
    """`form` on the one row of a group of one cell, where every argument is a number and the
    result is finite: the (1, 1) array _numeric_call gives that row, without its machinery for
    many rows; None otherwise (formulas' own call decides)."""
    operands, xs = [], []
    for a in args:
        v = a.reshape(-1)[0] if isinstance(a, np.ndarray) and a.size == 1 else a
        if type(v) not in _NUMBER_TYPES or type(v) is int and abs(v) > _EXACT_INTEGER:
            return None         # (an int beyond any float: formulas' call decides)
        operands.append(np.array([v], object))
        xs.append(np.array([v], dtype=float))
    with np.errstate(all="ignore"):
        result, kind = form(*xs)
    if not all(np.isfinite(x[0]) for x in (result, *xs)):
        return None
    out = np.empty((1, 1), object)
    out[0, 0] = _objects(result, kind, operands, xs)[0]
    return out.view(Array)


# MIN, MAX and COUNT computed on arrays: in vector calls one result per row over that row's
# arguments (the cosine rule's domain test ABS(s-MAX(p,q))>MIN(p,q)), elsewhere one result over
# every value of the ranges they read (a summary's MIN of a 3,601-row sweep column).  formulas
# gives MIN (MAX) the first smallest (largest) number itself, as Python's min (max) does, and 0
# when there is none, and COUNT the number of numbers; what they skip in a range (empty cells,
# booleans, text that is not a number, and for COUNT errors) is skipped here too.  A row holding
# anything else (an error for MIN or MAX, text that reads as a number, a NaN or an infinity, an
# integer beyond 2^53, another type) is left to formulas' own call, as is a call with an
# argument of its own that is not a number (MAX(TRUE, ...)).
AGGREGATES = frozenset({"MIN", "MAX", "COUNT"})
_NUMBER, _INTEGER, _SKIPPED, _TEXT, _ERROR, _TOKEN, _OTHER = range(7)
_KIND_OF_TYPE = {float: _NUMBER, np.float64: _NUMBER, int: _INTEGER, np.int64: _INTEGER,
                 bool: _SKIPPED, np.bool_: _SKIPPED, str: _TEXT, XlError: _ERROR,
                 type(sh.EMPTY): _TOKEN}
_EXACT_INTEGER = 2.0 ** 53      # every integer up to it is a float exactly: comparisons agree


def _numbers_in(table: np.ndarray, skip_errors: bool):
    """Of an object array of values as ranges hold them: (where the numbers are, the numbers
    as floats with 0 elsewhere, where a value needs formulas' own judgement)."""
    flat = table.reshape(-1)
    kinds = np.fromiter(map(_KIND_OF_TYPE.get, map(type, flat), itertools.repeat(_OTHER)),
                        np.int8, flat.size)
    numbers = (kinds == _NUMBER) | (kinds == _INTEGER)
    x = np.zeros(flat.size)
    bad = kinds == _OTHER
    try:
        x[numbers] = flat[numbers].astype(float)
    except OverflowError:           # an integer beyond any float
        return numbers, x, np.ones(table.shape, bool)
    bad |= numbers & ~np.isfinite(x)
    bad |= (kinds == _INTEGER) & (np.abs(x) > _EXACT_INTEGER)
    if not skip_errors:
        bad |= kinds == _ERROR
    text = np.flatnonzero(kinds == _TEXT)
    numeric = {v for v in set(flat[text].tolist()) if is_number(v)}
    if numeric:
        bad[text] |= np.fromiter((v in numeric for v in flat[text]), bool, text.size)
    for i in np.flatnonzero(kinds == _TOKEN):
        bad[i] |= flat[i] is not sh.EMPTY
    return numbers.reshape(table.shape), x.reshape(table.shape), bad.reshape(table.shape)


def _aggregate_rows(name: str, table: np.ndarray):
    """MIN, MAX or COUNT of each row of an object table, as formulas computes it on rows that
    hold no value _numbers_in leaves to formulas; and the rows that hold one."""
    numbers, x, bad = _numbers_in(table, skip_errors=name == "COUNT")
    if name == "COUNT":
        return [int(k) for k in numbers.sum(axis=1)], bad.any(axis=1)
    if name == "MIN":
        winner = np.argmin(np.where(numbers, x, np.inf), axis=1)
    else:
        winner = np.argmax(np.where(numbers, x, -np.inf), axis=1)
    found = numbers.any(axis=1)
    return ([table[i, j] if f else 0 for i, (j, f) in enumerate(zip(winner.tolist(),
                                                                      found.tolist()))],
            bad.any(axis=1))


def _aggregate_call(name: str, func, args, n: int):
    """MIN, MAX or COUNT over n rows (one value per argument and row): on arrays where
    _aggregate_rows applies, `func` row by row on the rest.  None when an argument is not a
    plain array or number (the caller runs `func` row by row)."""
    columns = _columns_of(args, n, _NUMBER_TYPES)
    if columns is None or any(a.dtype != object for a in columns if isinstance(a, np.ndarray)):
        return None     # an array of numpy numbers: its values are not the objects it holds
    table = np.stack(columns, axis=1)
    values, bad = _aggregate_rows(name, table)
    out = np.empty(n, object)
    out[:] = values
    cols = [np.reshape(a, (n, 1)) if _size(a) == n else None for a in args]
    for i in np.flatnonzero(bad).tolist():
        out[i] = _single(func(*[a if c is None else c[i:i + 1] for a, c in zip(args, cols)]))
    return out.reshape(n, 1).view(Array)


# IF's condition on the rows IF takes as arrays: a boolean (a comparison's, ISNUMBER's) or a
# number; formulas' IF picks `x if condition else y` for those, a text gives #VALUE! and an
# error itself (formulas' call takes those rows).
_CONDITION_TYPES = frozenset({bool, np.bool_, float, int, np.float64, np.int64})


def _if_call(func, args, n: int):
    """IF over n rows: on the rows whose condition is of _CONDITION_TYPES, the object of the
    branch it picks (a blank read as 0, as formulas' IF reads its arguments; FALSE for a
    missing third argument), `func` on the rest. None when an argument is not an object array
    of one value or of n, or a scalar (the caller runs `func`)."""
    cols = _choice_columns(args, n, (2, 3), first=bool)
    if cols is None:
        return None
    branches = cols[1:] if len(cols) == 3 else [cols[1], np.full(n, False, object)]
    plain, truth = _truth_of(cols[0], n)
    out = _picked(truth, *branches)
    if not plain.all():
        rest = ~plain
        sub = func(*[a[rest].reshape(-1, 1) if a.size == n and not _is_broadcast(a) else
                     np.asarray(a[:1], object).reshape(1, 1) for a in cols])
        if not isinstance(sub, np.ndarray) or sub.size != int(rest.sum()):
            return None
        out[rest] = sub.reshape(-1)
    return out.reshape(n, 1).view(Array)


def _iferror_call(args, n: int):
    """IFERROR over n rows: each row's value, or its alternative where the value is an error,
    as formulas' IFERROR picks them (the objects themselves, a blank read as 0). None when an
    argument is not an object array of one value or of n, or a scalar (the caller runs
    formulas' call)."""
    cols = _choice_columns(args, n, (2,))
    if cols is None:
        return None
    value, alternative = cols
    errors = np.fromiter((isinstance(v, XlError) for v in value.tolist()), bool, n)
    return _picked(errors, alternative, value).reshape(n, 1).view(Array)


def _choice_columns(args, n: int, counts: tuple, first=None):
    """The arguments of IF or IFERROR over n rows as object arrays of n (an array of one value
    or a scalar repeated); the first may also be an array of dtype `first`. None when their
    number is not among `counts` or an argument is not such an array or scalar."""
    if len(args) not in counts:
        return None
    cols = []
    for k, a in enumerate(args):
        if isinstance(a, np.ndarray):
            if a.size not in (1, n) or not (a.dtype == object or k == 0 and first is not None
                                            and a.dtype == first):
                return None
            a = a.reshape(-1)
        else:
            a = np.array([a], object)
        cols.append(np.broadcast_to(a, (n,)) if a.size == 1 else a)
    return cols


def _picked(which: np.ndarray, if_true: np.ndarray, if_false: np.ndarray) -> np.ndarray:
    """Row by row the object of `if_true` or `if_false`, a blank as 0 (formulas' IF and IFERROR
    read their arguments with blanks replaced)."""
    out = np.empty(len(which), object)
    out[:] = [0 if v is sh.EMPTY else v for v in np.where(which, if_true, if_false).tolist()]
    return out


def _truth_of(condition: np.ndarray, n: int):
    """(the rows whose condition IF takes as a boolean, what it reads there) for a condition
    over n rows: every row of a boolean array (ISNUMBER's, which formulas' IF reads element by
    element as Python booleans) or of Python booleans and floats (a float's truth is bool()'s,
    a NaN's too), else the rows of _CONDITION_TYPES."""
    if condition.dtype == bool:
        return np.ones(n, bool), condition
    conditions = condition.tolist()
    if set(map(type, conditions)) <= {bool, float}:     # a comparison's, mostly
        return np.ones(n, bool), np.array(conditions, bool)
    plain = np.fromiter((type(c) in _CONDITION_TYPES for c in conditions), bool, n)
    truth = np.fromiter((p and bool(c) for c, p in zip(conditions, plain.tolist())), bool, n)
    return plain, truth


def _range_values(args):
    """The arguments' values as formulas' functions read them (a range's as its array); None
    where formulas' own call must decide (a range it cannot read)."""
    try:
        return parse_ranges(*args)[0]
    except Exception:
        return None


def _array_shape(values):
    """The one shape of the arrays among `values` that hold more than one element, where every
    other value is a scalar or an array of one element that broadcasts to it (of no more
    dimensions); None otherwise (no such array, two shapes)."""
    shape = None
    for a in values:
        if isinstance(a, np.ndarray) and a.size > 1:
            if shape is not None and a.shape != shape:
                return None
            shape = a.shape
    if shape is None or any(isinstance(a, np.ndarray) and a.size == 1 and a.ndim > len(shape)
                            for a in values):
        return None
    return shape


def _whole_array_call(form, func, args):
    """An element-wise node with a numeric form over whole ranges in one cell (a power
    balance's SUMPRODUCT of two columns' product): `form` on the elements that are finite
    numbers, `func` on the rest (_numeric_call over the arrays' elements in order), the result
    in the arrays' shape as formulas' call gives it; None where formulas' call decides (a
    range it cannot read, arrays of different shapes, no array of more than one element)."""
    values = _range_values(args)
    shape = None if values is None else _array_shape(values)
    if shape is None:
        return None
    out = _numeric_call(form, func, values, int(np.prod(shape)), whole=True)
    return None if out is None else out.reshape(shape)


def _cell_numeric_node(func, form):
    """Wrap a node that has a numeric form for calls outside vector calls: over whole ranges
    by _whole_array_call, else (one value, or what it does not take) by `func`."""
    def node(*args, **kw):
        out = None if kw else _whole_array_call(form, func, args)
        return func(*args, **kw) if out is None else out
    node.formulas_function = func       # what the node stands for (tests compare graphs by it)
    return node


# ISNUMBER of a value of these types, as formulas' is_number judges it (a number, not a boolean,
# an error or a blank); a value of any other type (text, which it reads as a number where
# float() does) is left to formulas' call.
_IS_NUMBER = {float: True, int: True, np.float64: True, np.int64: True, bool: False,
              np.bool_: False, XlError: False, type(sh.EMPTY): False}


def _isnumber_node(func):
    """Wrap ISNUMBER to judge an array of more than one value on the array where each value's
    type decides (_IS_NUMBER; of blanks' type, only the blank itself): formulas' result, a
    FalseArray of booleans in the value's shape; else `func` (formulas' call)."""
    def node(*args, **kw):
        values = None if kw or len(args) != 1 else _range_values(args)
        a = None if values is None else values[0]
        if not isinstance(a, np.ndarray) or a.dtype != object or a.size < 2:
            return func(*args, **kw)
        flat = a.reshape(-1).tolist()
        kinds = set(map(type, flat))
        if not kinds <= _IS_NUMBER.keys() or type(sh.EMPTY) in kinds and any(
                type(v) is type(sh.EMPTY) and v is not sh.EMPTY for v in flat):
            return func(*args, **kw)
        judged = np.fromiter(map(_IS_NUMBER.__getitem__, map(type, flat)), bool, len(flat))
        return judged.reshape(a.shape).view(FalseArray)
    node.formulas_function = func       # what the node stands for (tests compare graphs by it)
    return node


def _ranges_node(func, name: str):
    """Wrap a MIN, MAX or COUNT node for calls outside vector calls: one result over every value
    of its arguments (the ranges' values in order, row by row), computed on arrays where
    _aggregate_rows applies to all of them, else by `func`."""
    def node(*args, **kw):
        if kw:
            return func(*args, **kw)
        values = _range_values(args)
        if values is None:
            return func(*args)
        if not any(isinstance(a, np.ndarray) and a.size > 1 for a in values):
            return func(*args)
        parts = []
        for a in values:
            if isinstance(a, np.ndarray) and a.dtype == object:
                parts.append(a.reshape(-1))
            elif type(a) in _NUMBER_TYPES:
                parts.append(np.array([a], object))
            else:
                return func(*args)
        result, bad = _aggregate_rows(name, np.concatenate(parts).reshape(1, -1))
        return func(*args) if bad[0] else result[0]
    node.formulas_function = func       # what the node stands for (tests compare graphs by it)
    return node


def _is_broadcast(a: np.ndarray) -> bool:
    return a.strides == (0,)


def _size(x) -> int:
    return x.size if isinstance(x, np.ndarray) else 1


def _single(x):
    """The one value of a per-row result."""
    if isinstance(x, np.ndarray):
        if x.size != 1:
            raise _NotScalar
        return x.reshape(-1)[0]
    return x


class _NotScalar(Exception):
    """A row-by-row node returned more than one value: the group cannot be vectorized."""


def _vector_node(func, batch: Batch, elementwise: bool, numeric=None, aggregate=None,
                 choice: str | None = None):
    """Wrap a node of the compiled graph for (n, 1) calls.  A node with a numeric form runs it
    on the rows of finite numbers, MIN, MAX and COUNT (`aggregate`, their name) on the rows of
    plain numbers (AGGREGATES), IF (`choice`, its name) on the rows of a boolean or numeric
    condition (_if_call) and IFERROR on every row (_iferror_call).  Element-wise nodes run
    once; if their output is not (n, 1) (an exception collapsed it), or the node is not
    element-wise, it runs row by row on (1, 1) slices, exactly as in a per-cell call."""
    def node(*args, **kw):
        n = batch.n
        if n == 1 and numeric is not None and not kw:
            out = _one_number_call(numeric, args)
            if out is not None:
                batch.numeric += 1
                return out
        if n == 1 or not any(_size(a) == n for a in args):
            return func(*args, **kw)
        if numeric is not None and not kw:
            out = _numeric_call(numeric, func, args, n)
            if out is not None:
                batch.numeric += 1
                return out
        if aggregate is not None and not kw:
            out = _aggregate_call(aggregate, func, args, n)
            if out is not None:
                batch.numeric += 1
                return out
        if choice is not None and not kw:
            out = _if_call(func, args, n) if choice == "IF" else _iferror_call(args, n)
            if out is not None:
                batch.numeric += 1
                return out
        if elementwise:
            out = func(*args, **kw)
            if isinstance(out, np.ndarray) and out.shape == (n, 1):
                return out
        batch.row_by_row += 1
        out = np.empty((n, 1), object)
        cols = [np.reshape(a, (n, 1)) if _size(a) == n else None for a in args]
        for i in range(n):
            row = [a if c is None else c[i:i + 1] for a, c in zip(args, cols)]
            out[i, 0] = _single(func(*row, **kw))
        return out.view(Array)
    return node


def wrap(func, name: str, batch: Batch | None):
    """A node's function as the graph runs it: for vector calls, wrapped by its name; outside
    them, MIN, MAX and COUNT wrapped to read their ranges on arrays, and the nodes with a
    numeric form to run it over whole ranges; ISNUMBER judges arrays by type in both."""
    if name == "ISNUMBER":
        func = _isnumber_node(func)
    if batch is None:
        if name in AGGREGATES:
            return _ranges_node(func, name)
        return _cell_numeric_node(func, NUMERIC_FORMS[name]) if name in NUMERIC_FORMS else func
    return _vector_node(func, batch, name in ELEMENTWISE, NUMERIC_FORMS.get(name),
                        name if name in AGGREGATES else None,
                        name if name in ("IF", "IFERROR") else None)
