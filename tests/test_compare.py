"""checks.compare judges most cells as arrays (the cells within the strict bound) and the rest one
by one: the bounds below are worked by hand from the rule the docs state (1e-12·S for a length,
1e-9 for an angle, modulo a turn; 1e-9·|x| for an application that keeps 15 digits), so a fast
path that takes a cell the rule does not admit, or drops one it does, fails here."""
from __future__ import annotations

import math

import numpy as np
from formulas.tokens.operand import Error

from linkbook.check.checks import Check, Rules, compare, unit_scale
from linkbook.engine.evaluator import error_code, is_error

NA = Error.errors["#N/A"]
S = 1000.0           # the mechanism's size: a length may differ by 1e-12·S = 1e-9
RULES = Rules(is_error, error_code)


def judged(cells: list, got: list, expected: list, unit: str, rules: Rules = RULES) -> Check:
    check = Check("sweep", "x", S, 1.0, unit_scale(unit, S))
    compare(check, "Sweep", cells, got, np.array(expected, dtype=float), unit, rules)
    return check


def test_a_length_within_its_bound_agrees_and_beyond_it_differs():
    cells = ["B5", "B6", "B7", "B8", "B9", "B10"]
    got = [2.0, 3.0 + 0.9e-9, 4.0 + 1.1e-9, NA, True, 7]
    c = judged(cells, got, [2.0, 3.0, 4.0, 5.0, 1.0, 7.0], "length")
    assert [m.cell for m in c.mismatches] == ["B7", "B8", "B9"]     # beyond, an error, a bool
    assert c.cells == 6 and c.judged == {("Sweep", x) for x in cells}
    assert math.isclose(c.max_abs, 1.1e-9, rel_tol=1e-6)           # the one that differs


def test_the_largest_difference_of_cells_that_agree_is_reported():
    c = judged(["C5", "C6", "C7"], [1.0, 1.0 + 4e-10, 1.0 - 7e-10], [1.0, 1.0, 1.0], "length")
    assert c.ok and c.cells == 3
    assert math.isclose(c.max_abs, 7e-10, rel_tol=1e-5)


def test_an_angle_agrees_across_a_whole_turn_and_not_beyond_its_bound():
    c = judged(["D5", "D6", "D7"], [0.0, 180.0 + 2e-9, 2 * math.pi - 1e-10],
               [360.0 - 1e-10, 180.0, 0.0], "deg")
    assert [m.cell for m in c.mismatches] == ["D6", "D7"]    # 2e-9 over; radians in degrees
    c = judged(["E5"], [2 * math.pi - 5e-10], [0.0], "rad")
    assert c.ok and c.max_abs < 1e-9


def test_an_na_where_the_reference_has_none_agrees_and_a_number_there_differs():
    c = judged(["F5", "F6"], [NA, 0.5], [math.nan, math.nan], "length")
    assert c.na_expected == 2 and c.na_agree == 1
    assert [m.cell for m in c.mismatches] == ["F6"]


def test_an_application_is_judged_to_15_digits_of_the_value():
    relative = Rules(is_error, error_code, relative=True)
    c = judged(["G5", "G6", "G7"], [1e6 + 5e-4, 1e6 + 2e-3, 1.0 + 5e-10],
               [1e6, 1e6, 1.0], "length", relative)
    assert [m.cell for m in c.mismatches] == ["G6"]    # 1e-9·1e6 = 1e-3; 1e-9 at 1.0


NUM = Error.errors["#NUM!"]


def test_a_value_beyond_the_float_range_is_the_overflow_error_or_the_infinity_itself():
    """Where the exact value overflows (a flywheel's ΔE/(Cs·ω²) at ω = 3.6e-154 rad/s, which a
    random draw reached), the engines answer #NUM! and Gnumeric the infinity: both agree; the
    largest float, another error or the other infinity differ."""
    big = np.finfo(float).max
    c = judged(["H5", "H6", "H7", "H8", "H9"], [NUM, math.inf, big, NA, -math.inf],
               [math.inf] * 5, "length")
    assert [m.cell for m in c.mismatches] == ["H7", "H8", "H9"]
    assert c.cells == 5 and c.judged == {("Sweep", f"H{r}") for r in range(5, 10)}
