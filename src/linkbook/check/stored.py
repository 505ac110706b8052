"""What a book shows unrecalculated: a constant where the record has a formula (pasted as its
value) differs whatever its value, and each value stored with a formula (what a reader that does
not calculate shows) is judged as its formula's value is, with the same bounds."""
from __future__ import annotations

from collections import ChainMap
from dataclasses import replace

from ..base.record import BuildRecord

from .checks import STORED, Check, Mismatch, Rules, show
from .context import looked_up
from .judge import judge_book
from .reading import cell_order


def show_stored(value, error_code):
    """A stored or computed value as the stored check names it: a text quoted, so that the
    text "1.5" does not read as the number 1.5."""
    from ..base.xlsx import CellError
    if isinstance(value, CellError):
        return str(value)
    shown = show(value, error_code)
    return repr(shown) if isinstance(shown, str) and not error_code(value) else shown


def not_formulas(wb, cells: set[tuple[str, str]]) -> tuple[list, list]:
    """Cells the record holds formulas in that hold none: (those holding a constant, those
    empty or on a sheet deleted), in cell order."""
    replaced, absent = [], []
    for key in sorted(cells, key=cell_order):
        held = key[0] in wb.sheetnames and wb[key[0]][key[1]].value is not None
        (replaced if held else absent).append(key)
    return replaced, absent


def check_replaced(wb, replaced: list[tuple[str, str]]) -> Check:
    """A constant where the build record has a formula differs whatever its value: the book no
    longer follows its inputs there (a formula pasted as its value)."""
    c = Check("constants", "in place of formulas", cells=len(replaced))
    for sheet, cell in replaced:
        c.mismatches.append(Mismatch(sheet, cell, "a formula",
                                     f"the constant {wb[sheet][cell].value!r}"))
    return c


def _kind(value, error_code) -> str:
    """What a reader shows a cell as: an error, a boolean, a number or a text."""
    from ..base.xlsx import CellError
    if isinstance(value, CellError) or error_code(value) is not None:
        return "error"
    if isinstance(value, bool):
        return "boolean"
    return "number" if isinstance(value, (int, float)) else "text"


def _same(a, b, error_code) -> bool:
    from ..base.xlsx import CellError
    code_a = str(a) if isinstance(a, CellError) else None
    if code_a is not None or error_code(b) is not None:
        return code_a == error_code(b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return isinstance(a, bool) == isinstance(b, bool) and float(a) == float(b)
    return a == b


def _computed(values, stored: dict) -> dict:
    """{cell: the value its formula gives} of the cells that store one, looked up a sheet at a
    time."""
    by_sheet: dict[str, list[str]] = {}
    for sheet, cell in stored:
        by_sheet.setdefault(sheet, []).append(cell)
    return {(sheet, cell): v for sheet, cells in by_sheet.items()
            for cell, v in zip(cells, looked_up(values, sheet, cells))}


def check_stored(wb, record: BuildRecord, values, stored: dict, rules: Rules) -> Check:
    """Each stored value judged as its formula's value is, with the same bounds: a value stored
    that its formula does not give (an edit of the file, a stale save) differs, named with what
    the formula gives and what is stored. Only the stored values that differ from the formula's
    own are judged again."""
    from ..base.xlsx import CellError
    is_error, error_code = rules.is_error, rules.error_code
    c = Check(STORED, "value ≠ the formula's", cells=len(stored))
    computed = _computed(values, stored)
    differ = {k: v for k, v in stored.items() if not _same(v, computed.get(k), error_code)}
    # a value of another kind (TRUE for 1, the text "1.5" for 1.5) differs outright: a reader
    # that does not calculate shows it as it is, whatever the bounds say of its number
    for key in [k for k, v in differ.items()
                if _kind(v, error_code) != _kind(computed.get(k), error_code)]:
        c.mismatches.append(Mismatch(key[0], key[1], show_stored(computed.get(key), error_code),
                                     show_stored(differ.pop(key), error_code)))
    if not differ:
        return c

    def any_error(v) -> bool:
        return isinstance(v, CellError) or is_error(v)

    def any_code(v) -> str | None:
        return str(v) if isinstance(v, CellError) else error_code(v)

    again = judge_book(wb, record, ChainMap(differ, values),
                       replace(rules, is_error=any_error, error_code=any_code))
    named = set()
    for check in again:
        for m in check.mismatches:
            key = (m.sheet, m.cell)
            if key in differ and key not in named:
                named.add(key)
                formula, got = computed.get(key), differ[key]
                c.mismatches.append(Mismatch(m.sheet, m.cell, show_stored(formula, error_code),
                                             show_stored(got, any_code)))
                if isinstance(formula, float) and isinstance(got, float):
                    c.max_abs = max(c.max_abs, abs(got - formula))
    return c


