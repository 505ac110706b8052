"""Workbooks that compute in Excel 2010 and later and LibreOffice 6 and later (issue 16): every
function of every bundled book, and every function a template's expression may use, is one that
Excel 2010 has; a function Excel added in 2010 carries the `_xlfn.` prefix Excel needs to read it.
"""
from __future__ import annotations

import re

import pytest
from conftest import built

from linkbook import templates
from linkbook.language import FUNCTIONS as EXPRESSION_FUNCTIONS

# Excel 2007's functions that a linkage workbook could reasonably use (not the whole catalogue:
# a function outside this list fails the test until someone checks its version and adds it).
EXCEL_2007 = {
    "ABS", "ACOS", "AND", "ASIN", "ATAN", "ATAN2", "AVERAGE", "CHOOSE", "COS", "COUNT",
    "COUNTA", "COUNTIF", "DEGREES", "EXP", "FIXED", "IF", "IFERROR", "INDEX", "INT", "ISERROR",
    "ISNA", "ISNUMBER", "LARGE", "LN", "LOG", "LOG10", "MATCH", "MAX", "MIN", "MOD", "NA", "NOT",
    "OR", "PI", "POWER", "RADIANS", "ROUND", "ROWS", "SIGN", "SIN", "SMALL", "SQRT", "SUM",
    "SUMPRODUCT", "TAN",
}
EXCEL_2010 = {"AGGREGATE"}          # new in Excel 2010: written as _xlfn.AGGREGATE

_CALL = re.compile(r"((?:_xlfn\.)?[A-Za-z][A-Za-z0-9.]*)\(")
_STRING = re.compile(r'"(?:[^"]|"")*"')


def functions_of(wb) -> set[str]:
    return {name for ws in wb.worksheets for row in ws.iter_rows() for c in row
            if c.data_type == "f" for name in _CALL.findall(_STRING.sub('""', c.value))}


@pytest.mark.parametrize("name", [p.stem for p in templates.bundled()])
def test_every_function_of_a_bundled_book_is_in_excel_2010(name):
    b, _ = built(name)
    used = functions_of(b.workbook)
    plain = {f for f in used if not f.startswith("_xlfn.")}
    prefixed = {f[len("_xlfn."):] for f in used if f.startswith("_xlfn.")}
    assert plain <= EXCEL_2007, plain - EXCEL_2007
    assert prefixed <= EXCEL_2010, prefixed - EXCEL_2010
    assert not plain & EXCEL_2010, "a 2010 function without _xlfn.: Excel shows #NAME?"


def test_the_summary_needs_no_function_newer_than_excel_2010():
    """MINIFS/MAXIFS (Excel 2019) were what the summary used: the four-bar's summary is where a
    newer function would show up first."""
    b, _ = built("fourbar")
    assert not {f for f in functions_of(b.workbook) if "IFS" in f.upper()}


def test_an_expression_may_only_use_excel_2007_functions():
    assert set(EXPRESSION_FUNCTIONS) <= EXCEL_2007
