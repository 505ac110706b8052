"""What verify holds a cell by, without an object a cell: the addresses the checks name read
as arrays (xlsx.coordinates_to_arrays, against openpyxl's reading of each address), the formula
cells of a book as a grid a sheet (reading.FormulaCells), parted by what the checks judged as
the sets of (sheet, cell) keys they stand for would be."""
from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st
from openpyxl.utils.cell import (column_index_from_string, coordinate_from_string,
                                 coordinate_to_tuple, get_column_letter)

from conftest import examples
from linkbook.base import xlsx
from linkbook.check.checks import Check, JudgedCells
from linkbook.check.reading import FormulaCells

PLAIN = st.builds(lambda c, r: f"{get_column_letter(c)}{r}",
                  st.integers(1, 16384), st.integers(1, 1048576))
SPELLED = st.one_of(PLAIN, PLAIN.map(str.lower), PLAIN.map(lambda a: "$" + a))


@settings(max_examples=examples(200))
@given(cells=st.one_of(st.lists(PLAIN, min_size=1, max_size=30),
                       st.lists(SPELLED, min_size=1, max_size=10)))
def test_addresses_read_as_openpyxl_reads_each(cells):
    rows, cols = xlsx.coordinates_to_arrays(cells)
    expected = [(row, column_index_from_string(col))
                for col, row in map(coordinate_from_string, cells)]
    assert list(zip(rows.tolist(), cols.tolist())) == expected


SHEETS = ("Sweep", "Forces")
KEY = st.tuples(st.sampled_from(SHEETS + ("Gone",)),
                st.builds(lambda c, r: f"{get_column_letter(c)}{r}", st.integers(1, 5),
                          st.integers(1, 12)))


def _book(formulas: set, constants: set) -> xlsx.Workbook:
    sheets = {title: xlsx.Worksheet(title) for title in SHEETS}
    for (sheet, cell) in sorted(constants | formulas, key=lambda k: coordinate_to_tuple(k[1])):
        if sheet in sheets:
            row, col = coordinate_to_tuple(cell)
            held = sheets[sheet].held_columns.setdefault(col, xlsx.Column())
            held.append(row, f"=A{row}" if (sheet, cell) in formulas else 1.5,
                        "f" if (sheet, cell) in formulas else "n")
    return xlsx.Workbook(list(sheets.values()), {})


@settings(max_examples=examples(100))
@given(formulas=st.sets(KEY, max_size=25), constants=st.sets(KEY, max_size=8),
       judged=st.lists(st.sets(KEY, max_size=25), max_size=3))
def test_formula_cells_part_as_the_sets_of_their_keys(formulas, constants, judged):
    formulas = {k for k in formulas if k[0] != "Gone"}
    constants -= formulas
    cells = FormulaCells(_book(formulas, constants))
    assert set(cells) == formulas and len(cells) == len(formulas)
    checks = []
    for keys in judged:
        check = Check("c", "c")
        check.judged.update(sorted(keys) * 2)       # a cell judged twice counts once
        checks.append(check)
    every = set().union(*judged)
    elsewhere, judged_formulas = cells.judged(checks)
    assert elsewhere == every - formulas
    assert set(judged_formulas) == every & formulas
    assert list(cells.without(judged_formulas)) == sorted(
        formulas - every, key=lambda k: (k[0],) + coordinate_to_tuple(k[1])[::-1])
    assert all((k in cells) == (k in formulas) for k in every | constants)


def test_judged_cells_compare_as_the_set_of_their_keys():
    judged = JudgedCells([("S", "A1"), ("S", "A1")])
    judged.extend("T", ["B2", "B3"])
    assert judged == {("S", "A1"), ("T", "B2"), ("T", "B3")} and len(judged) == 3
    assert judged != {("S", "A1")}


def test_a_columns_addresses_are_one_text_each_until_verify_is_done(bundled_books):
    """Each check and each input set names a column's cells with the same texts (the memory of
    a big book's verify), let go of when the book is done."""
    from linkbook.check.verifier import verify
    first, again = xlsx.column_cells("B", 5, 7), xlsx.column_cells("B", 5, 7)
    assert first == ["B5", "B6", "B7"] and all(a is b for a, b in zip(first, again))
    assert verify(bundled_books["fourbar"]).ok
    assert xlsx._column_cells.cache_info().currsize == 0
