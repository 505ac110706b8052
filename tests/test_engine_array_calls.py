"""Nodes that run on whole arrays instead of formulas' per-element calls (engine/vector.py): IF on
a boolean array (ISNUMBER's). Each must give what formulas' own function gives for the
same arguments, value for value and type for type, over numbers, NaN, infinities, errors, empty
cells, text, booleans and ints; and must have run on the arrays (not handed everything back)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import schedula as sh
from formulas.functions import get_functions
from formulas.functions.operators import OPERATORS
from formulas.tokens.operand import Error

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from conftest import examples  # noqa: E402
from linkbook.engine import adapter  # noqa: E402
from linkbook.engine import vector as vectorized  # noqa: E402
from test_engine import RANGE_VALUES, _same_result  # noqa: E402

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

def _boolean_condition(rng, n: int):
    """A condition over n rows as a vector call meets it: ISNUMBER's boolean array of (n, 1)
    (or of one row, shared), or a plain boolean array."""
    rows = n if rng.random() < 0.8 else 1
    if rng.random() < 0.5:
        return get_functions()["ISNUMBER"](_objects(rng, (rows, 1), RANGE_VALUES))
    return rng.random((rows, 1)) < 0.5


def _branch(rng, n: int):
    """A branch: a column of n values of any kind, one value in a (1, 1) array, or a scalar."""
    draw = rng.random()
    if draw < 0.6:
        return _objects(rng, (n, 1), RANGE_VALUES)
    if draw < 0.8:
        return _objects(rng, (1, 1), RANGE_VALUES)
    return SCALARS[rng.integers(len(SCALARS))]


def test_if_on_a_boolean_condition_gives_what_formulas_gives():
    """IF(ISNUMBER(x), a, b) in a vector call: with the condition a boolean array, IF picks
    each row's branch on the arrays, exactly formulas' element: the branch's own object, a
    blank picked as 0, FALSE for a missing third argument."""
    func = formulas_function("IF")
    batch = vectorized.Batch()
    node = vectorized.wrap(func, "IF", batch)
    rng = np.random.default_rng(20261128)
    for _ in range(examples(300, at_least=40)):
        n = int(rng.integers(2, 30))
        condition = _boolean_condition(rng, n)
        args = [condition, _branch(rng, n)] + ([_branch(rng, n)] if rng.random() < 0.7 else [])
        if condition.size == 1 and not any(vectorized._size(a) == n for a in args[1:]):
            args[1] = _objects(rng, (n, 1), RANGE_VALUES)     # the call is over n rows
        batch.n = n
        before = batch.numeric
        got = node(*args)
        batch.n = 1
        assert _same_result(got, func(*args)), (args, got)
        assert batch.numeric == before + 1, args             # IF ran on the arrays
