"""A vector call over more rows than CALL_ROWS is made in parts (engine/evaluator.py, to bound
what a long formula over a big grid holds at once): the parts must join to what the rows' own
calls give. Judged against the independent reference, with parts small enough that every
sweep and grid of the bundled books is called in several, and a part of one row among them."""
from __future__ import annotations

import pytest

from linkbook.check.verifier import verify
from linkbook.engine import evaluator


@pytest.mark.parametrize("name", ["slider-crank", "pump"])
def test_vector_calls_in_parts_agree_with_the_reference(bundled_books, monkeypatch, name):
    rows_called = []
    whole = evaluator._rows_called

    def counted(func, batch, args, n, takes_inputs):
        rows_called.append(n)
        return whole(func, batch, args, n, takes_inputs)

    monkeypatch.setattr(evaluator, "CALL_ROWS", 8)
    monkeypatch.setattr(evaluator, "_rows_called", counted)
    report = verify(bundled_books[name])
    assert report.status == 0, report.differing_cells()
    assert report.cells > 1000
    assert 8 in rows_called and max(rows_called) == 8      # the calls were made in parts
    # the slider-crank's sweep has 73 rows: nine parts of 8 and one of a single row
    assert name != "slider-crank" or 1 in rows_called
