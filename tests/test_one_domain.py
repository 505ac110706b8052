"""One domain for build and verify: what build accepts, its own verify reads the same way.

The mechanism language's expressions are read twice: by the writer (language.expressions,
through Python's parser) and by verify's independent reference (check.reference.expressions, a
parser of its own). A number or a symbol the writer accepts must be one the reference reads as
the same value; what the reference would not read, the writer refuses.
"""
from __future__ import annotations

import math

import pytest
from hypothesis import given, settings, strategies as st

from linkbook.check.reference.expressions import evaluate
from linkbook.language.expressions import expression
from linkbook.language.model import DescriptionError

SYMBOLS = {"a2": 3.0, "b3": 0.5}


def _built(text: str) -> float | None:
    """The number the writer puts in the book for `text`, or None if it refuses the text."""
    try:
        excel = expression("f", text, set(SYMBOLS)).text
    except DescriptionError:
        return None
    for symbol, value in SYMBOLS.items():
        excel = excel.replace(f"{{{symbol}}}", repr(value))
    return eval(excel.replace("^", "**"))   # + - * / ^ and numbers only (no functions drawn)


def _read(text: str) -> float | None:
    try:
        return float(evaluate(text, SYMBOLS))
    except ValueError:
        return None


@pytest.mark.parametrize("text", ["-1_000", "0x10", "0o7", "0b1", "1j", "１０", "١٠", "ａ2",
                                  "1e5", "1.", ".5", "2.5E+3", "a2*1e-3", "00"])
def test_a_number_the_writer_accepts_is_one_the_reference_reads_alike(text):
    built = _built(text)
    if built is not None:
        assert _read(text) == pytest.approx(built, rel=1e-15), text


def test_the_spellings_python_alone_reads_are_refused():
    """The reference reads none of these (so verify refused the book build wrote)."""
    for text in ["-1_000", "0x10", "0o7", "0b1", "１０", "١٠", "ａ2"]:
        assert _read(text) is None, text
        assert _built(text) is None, text


@given(st.text(alphabet="0123456789._eE+-*/ xob()a2١０ａj", min_size=1, max_size=12))
@settings(max_examples=300, deadline=None)
def test_random_spellings_the_writer_accepts_the_reference_reads_alike(text):
    try:
        built = _built(text)
    except (ZeroDivisionError, OverflowError):
        return          # an error value in both (the reference's NaN): not the spelling's
    if built is not None and math.isfinite(built):
        read = _read(text)
        assert read is not None and read == pytest.approx(built, rel=1e-12, abs=1e-300), text
