"""The Sweep sheet: one row per input value, one formula column per step (each rendered once
and written row by row), the degree views of the output angles, the bookkeeping of where the
loops close, and the numbers-only copies whose MIN and MAX the summary and the drawing read.

Where each column stands is known before the sheet is laid out (sweep_place, numbers_place), so
that the Mechanism sheet, written first, can refer to it.
"""
from __future__ import annotations

from dataclasses import replace

from openpyxl.utils import column_index_from_string, get_column_letter

from ..base.sheets import DASH, SWEEP
from ..language.model import COLUMN, DEG, RAD, Model
from .resolve import ABOVE_SUFFIX, Resolver
from ..language.templates import Template
from .package import Formula
from .style import (ABOVE, NOTE, ROW, TITLE, fit_labels, header, number_format, numbers_only, put,
                    put_head, put_text, table_style, unit_text)


def sweep_columns(model: Model, input_column: str) -> list[tuple[str, object]]:
    """(key, quantity) in table order: the input (an angle in degrees), the steps, then outputs
    in degrees."""
    columns: list[tuple[str, object]] = [(input_column, None)]
    columns += [(q.key, q) for q in model.of_role(COLUMN)]
    columns += [(f"{q.key}_deg", q) for q in model.of_role(COLUMN) if q.in_degrees]
    return columns


def default_window(q) -> float:
    """Where the 360° window of a degree view starts unless the build chose one from data."""
    return 0.0 if q.wrap_360 else -180.0


def radian_window(formula: str, lo: float) -> str:
    """An angle formula's value shown in [lo°, lo° + 360°), in radians."""
    shift = f"-RADIANS({lo:g})" if lo > 0 else f"+RADIANS({-lo:g})" if lo < 0 else ""
    back = f"+RADIANS({lo:g})" if lo > 0 else f"-RADIANS({-lo:g})" if lo < 0 else ""
    return f"=MOD({formula[1:]}{shift},2*PI()){back}"


def degree_formula(q, ref: str, lo: float | None = None) -> str:
    """The degree view of a radian cell, shown in [lo, lo + 360) (by default q's window)."""
    lo = default_window(q) if lo is None else lo
    shift = f"-{lo:g}" if lo > 0 else f"+{-lo:g}" if lo < 0 else ""
    back = f"+{lo:g}" if lo > 0 else f"-{-lo:g}" if lo < 0 else ""
    return f"=MOD(DEGREES({ref}){shift},360){back}"


def sweep_place(t: Template, model: Model) -> tuple[dict[str, str], int, int]:
    """The Sweep sheet's column letters by key, its first and last row of numbers."""
    columns = sweep_columns(model, t.mechanism.input_column)
    letters = {key: get_column_letter(i) for i, (key, _) in enumerate(columns, start=1)}
    return letters, SWEEP_FIRST_ROW, SWEEP_FIRST_ROW + len(t.sweep.angles()) - 1


SWEEP_FIRST_ROW = 5


def sweep_table(ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The Sweep sheet's table: the input values down column A, each step's formula (rendered once,
    then written row by row) in a column of its own, the degree views, and where the mechanism
    has loops, the columns that say where they close."""
    mech = t.mechanism
    angles = t.sweep.angles()
    columns = sweep_columns(model, mech.input_column)
    letters = sweep_place(t, model)[0]
    put_text(ws, "A1", f"{t.title}: one row per {mech.input_symbol}", TITLE)
    put_text(ws, "A2", f"Formulas read the named inputs on sheet Mechanism; #N/A marks "
                       f"{mech.input_word}s where the loop cannot close.", NOTE)
    head_row, first = 4, SWEEP_FIRST_ROW
    formulas: dict[str, str] = {}
    cells = {k: f"{letters[k]}{ROW}" for k, _ in columns}
    cells.update({f"{k}{ABOVE_SUFFIX}": f"{letters[k]}{ABOVE}" for k, _ in columns})
    resolve = Resolver(model, names, cells, place=str(first + len(angles)))
    for i, (key, q) in enumerate(columns, start=1):
        ws.column_dimensions[letters[key]].width = 12
        if q is None:
            put_text(ws, f"{letters[key]}3", f"input {mech.input_word}", NOTE)
            put_head(ws, head_row, i, header(mech.input_symbol, mech.input_unit, t.length_unit))
            continue
        degree_column = key.endswith("_deg") and key != q.key
        unit = DEG if degree_column else q.unit
        put_text(ws, f"{letters[key]}3", q.label, NOTE)
        put_head(ws, head_row, i, header(q.symbol, unit, t.length_unit))
        if degree_column:
            formulas[key] = degree_formula(q, f"{letters[q.key]}{ROW}")
        else:
            formulas[key] = resolve.formula(key)
    formats = {key: number_format(DEG if key.endswith("_deg") else q.unit, t.length_unit)
               for key, q in columns if q is not None}
    columns_at = {key: column_index_from_string(letters[key]) for key in formulas}
    angle_style = table_style(ws, "0.0##")
    styles = {key: table_style(ws, formats[key]) for key in formulas}
    for r, angle in enumerate(angles, start=first):
        put(ws, r, 1, angle, angle_style)
        row_text, above = str(r), str(r - 1)    # the first row's above is the header
        for key, text in formulas.items():
            put(ws, r, columns_at[key], Formula(text.replace(ROW, row_text).replace(ABOVE, above)),
                styles[key])
    last = first + len(angles) - 1
    if model.closes:
        letters.update(_assembly_columns(ws, letters, model.closes, first, last, head_row,
                                         unit_text(mech.input_unit, t.length_unit),
                                         mech.input_word))
    fit_labels(ws, 3, list(letters.values()), heads=head_row)
    ws.freeze_panes = ws.cell(first, 2)
    return {"sheet": SWEEP, "rows": [first, last], "columns": letters}


ASSEMBLY_COLUMNS = 3     # closes, gap from, gap to: right of the sweep's own columns


def _assembly_columns(ws, letters: dict, witnesses: tuple[str, ...], first: int, last: int,
                      head_row: int, unit: str, word: str) -> dict:
    """Bookkeeping for the summary: does the row close (1/0), and where do gaps start and end."""
    col = len(letters) + 1
    closes, start, end = (get_column_letter(col + i) for i in range(ASSEMBLY_COLUMNS))
    for i, (text, label) in enumerate((("closes [1/0]", "1 where every loop closes"),
                                       (f"gap from [{unit}]", f"first {word} of a gap"),
                                       (f"gap to [{unit}]", f"last {word} of a gap"))):
        put_head(ws, head_row, col + i, text)
        put_text(ws, f"{get_column_letter(col + i)}3", label, NOTE)
        ws.column_dimensions[get_column_letter(col + i)].width = 11
    for r in range(first, last + 1):
        every = "*".join(f"ISNUMBER({letters[w]}{r})" for w in witnesses)
        put(ws, r, col, Formula(f"=IF({every},1,0)"))
        # (x=0)*(y=1) rather than AND(): the same truth in every application, and element-wise
        # for the vector engine (AND aggregates, so it would run row by row).
        before = f"{closes}{r}=0" if r == first else f"({closes}{r}=0)*({closes}{r - 1}=1)"
        after = f"{closes}{r}=0" if r == last else f"({closes}{r}=0)*({closes}{r + 1}=1)"
        put(ws, r, col + 1, Formula(f'=IF({before},A{r},"{DASH}")'))
        put(ws, r, col + 2, Formula(f'=IF({after},A{r},"{DASH}")'))
    return {"closes": closes, "gap_from": start, "gap_to": end}


def _numbers_keys(model: Model) -> list[str]:
    """The sweep columns whose smallest and largest values a formula reads, in the order their
    numbers-only copies stand beside the sweep table: each slider's travel (its guide's ends),
    then the summary's output and transmission angles."""
    keys = [g.travel for g in model.guides]
    if model.closes:
        if model.output:
            q = model.get(model.output)
            keys.append(f"{q.key}_deg" if q.unit == RAD else q.key)
        keys += model.transmissions
    return list(dict.fromkeys(keys))


def numbers_place(t: Template, model: Model) -> tuple[dict[str, str], int, int]:
    """The column letter of each numbers-only copy (_numbers_keys) right of the sweep table,
    and the sweep's first and last row: known before the sweep is laid out, so the drawing's
    guides can read them."""
    letters, first, last = sweep_place(t, model)
    start = len(letters) + 1 + (ASSEMBLY_COLUMNS if model.closes else 0)
    return ({key: get_column_letter(start + i) for i, key in enumerate(_numbers_keys(model))},
            first, last)


def sweep_numbers_only(ws_sweep, t: Template, model: Model, sweep: dict) -> list[dict]:
    """Every numbers-only copy beside the sweep table (numbers_place), each with a note over
    it; their records for the build record's numbers_only."""
    cols, (r0, r1) = sweep["columns"], sweep["rows"]
    records = []
    for key, letter in numbers_place(t, model)[0].items():
        q = replace(model.get(key[:-4]), unit=DEG) if key.endswith("_deg") else model.get(key)
        ws_sweep.column_dimensions[letter].width = 12
        put_text(ws_sweep, f"{letter}3", f"{q.symbol}'s numbers, {DASH} at #N/A: MIN and "
                                         "MAX read these", NOTE)
        numbers_only(ws_sweep, column_index_from_string(letter), r0 - 1,
                     [f"{cols[key]}{r}" for r in range(r0, r1 + 1)],
                     f"{q.symbol} numbers [{unit_text(q.unit, t.length_unit)}]",
                     number_format(q.unit, t.length_unit))
        records.append({"sheet": SWEEP, "column": letter, "rows": [r0, r1], "sweep": key})
    if records:
        fit_labels(ws_sweep, 3, [get_column_letter(c) for c in range(1, ws_sweep.max_column + 1)],
                   heads=r0 - 1)
    return records
