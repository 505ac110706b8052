"""A running sum: a column each of whose cells is the cell above plus a term, `=W7+term` in W8
(the Forces sheet's work column, the trapezoid rule's sum so far). Each cell reads the one above,
so the group is a chain that the cell path evaluates one cell at a time; here the terms are one
call of the group's vector function (the cell above read as -0.0, the exact identity of IEEE
addition: -0.0 + term is the term, its sign of zero too) and the chain is summed in row order,
each sum the one IEEE addition the cell's `+` is.
"""
from __future__ import annotations

from .groups import Group
from .references import cell_name

# Outside brackets and strings, a term with one of these would not be one addend of `above +`:
# `W7+a-b` is (W7+a)-b, whose rounding differs from W7+(a-b); `W7+a>b` compares.
_LOOSER = set("+-<>=&")


def running_sum_input(g: Group) -> int | None:
    """The index of g's input that is the cell above each member, where g is one column whose
    formula is `=<cell above>+<term>` with a term that binds tighter than the `+` and reads
    nothing of that column (not the cell above again: `=W7+W7*2` is no running sum); None for
    any other group."""
    if g.mode != "vector" or not g.members or len(set(g.cols.tolist())) != 1:
        return None
    above = [k for k, d in enumerate(g.inputs)
             if d.sheet == g.sheet and not d.is_range and not (d.ar1 or d.ac1)
             and (d.r1, d.c1) == (-1, 0)]
    if len(above) != 1 or sum(d == g.inputs[above[0]] for d in g.descs) != 1:
        return None
    m = g.members[0]
    head = f"={cell_name(m.row - 1, m.col)}+"
    if not m.formula.startswith(head) or not _one_addend(m.formula[len(head):]):
        return None
    for k, d in enumerate(g.inputs):
        if k != above[0] and d.sheet == g.sheet:
            c1, c2 = d.at(m.row, m.col)[1::2]
            if min(c1, c2) <= m.col <= max(c1, c2):
                return None
    return above[0]


def _one_addend(term: str) -> bool:
    """No operator looser than `+` (or `+` itself) outside the term's brackets and strings."""
    depth, quoted = 0, False
    for ch in term:
        if ch == '"':
            quoted = not quoted
        elif quoted:
            continue
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif depth == 0 and ch in _LOOSER:
            return False
    return bool(term) and depth == 0 and not quoted
