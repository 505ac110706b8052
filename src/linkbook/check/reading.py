"""Reading a book to judge it: the workbook and its build record (typed, base.record), its
input values as its cells hold them, the mechanism's size, and which cells hold formulas and
what values they store. A file that cannot be judged at all raises UnusableFile with one line."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..base import sheets as layout
from ..base.record import BuildRecord, DamagedRecord
from ..language.domain import (InputError, check_input, check_lengths_together, check_value,
                               check_written_lengths)

from .cells import UnusableFile, number_at  # noqa: F401  (read from here by the others)

# what reading a record that does not match its book raises (a key missing, a value mistyped)
RECORD_ERRORS = (KeyError, IndexError, TypeError, ValueError, AttributeError)


def read_book(path: Path):
    """(workbook, build record) of the book at `path`, read as the application reads it (the
    fast XML view, or openpyxl where it must); UnusableFile with one line when it cannot be."""
    from ..base.safety import UnsafeFile, read_workbook_safely
    try:
        wb = read_workbook_safely(path)
    except UnsafeFile as exc:
        raise UnusableFile(str(exc)) from None
    return wb, book_record(path, wb)


def record_mismatch(path: Path, exc: Exception) -> str:
    return (f"{path}: the build record (sheet {layout.META}) does not match the workbook "
            f"({type(exc).__name__}: {exc})")


def book_record(path: Path, wb) -> BuildRecord:
    """The book's build record; UnusableFile saying what is wrong when it is missing, damaged
    or not the shape linkbook writes, or when a sheet it names was renamed in case only."""
    try:
        record = layout.read_record(wb)
    except DamagedRecord as exc:
        raise UnusableFile(f"{path}: the build record (sheet {layout.META}) is damaged: it is "
                           f"{exc}") from None
    except RECORD_ERRORS as exc:
        raise UnusableFile(record_mismatch(path, exc)) from None
    if record is None:
        raise UnusableFile(f"{path}: not a linkbook workbook (no build record sheet)")
    for sheet in sorted(({layout.MECH} | record.sheets()) - set(wb.sheetnames)):
        # a sheet deleted is judged by the cells that read it; one renamed in case only, and
        # the sheet of the inputs, are named here
        for alike in (s for s in wb.sheetnames if s.casefold() == sheet.casefold()):
            raise UnusableFile(f"{path}: the sheet {sheet!r} is missing (the book has "
                               f"{alike!r}: the record names sheets exactly, so rename it back)")
        if sheet == layout.MECH:
            raise UnusableFile(f"{path}: the sheet {sheet!r} (the inputs) is missing")
    return record


def inputs_of(wb, record: BuildRecord) -> dict[str, float]:
    """The parameter values as they stand in the workbook's input cells."""
    ws = wb[layout.MECH]
    values = {}
    for symbol, info in record.inputs.items():
        if info.designed:
            continue            # a link to the Synthesis sheet: its value is the design's
        raw = ws[info.cell].value
        field = f"input {symbol} (cell {info.cell})"
        if ws[info.cell].data_type == "f":
            raise UnusableFile(f"{field}: holds a formula ({raw}); an input must be a number "
                               "typed in its cell")
        if isinstance(raw, str):
            # Text is never a number here, whatever its digits ('1_0', full-width or
            # Arabic-Indic ones): the applications show #VALUE! where Python would read 10.
            raise UnusableFile(f"{field}: must be a number, not text (got {raw!r}); type the "
                               "number without quotes or a leading apostrophe")
        try:
            values[symbol] = check_value(field, info.kind, raw)
        except InputError as exc:
            raise UnusableFile(str(exc)) from None
    if record.synthesis is not None:
        from .synthesis import designed_values
        values = designed_values(wb, record, values)
    try:
        check_lengths_together({k: v for k, v in values.items() if not np.isnan(v)},
                               record.kinds(), "input ", written_in(record))
    except InputError as exc:
        raise UnusableFile(str(exc)) from None
    return values


def written_in(record: BuildRecord) -> dict[str, float]:
    """The lengths the recorded description writes as numbers (domain.written_lengths)."""
    try:
        return check_written_lengths(record.description or {}, "the book's record: ")
    except InputError as exc:
        raise UnusableFile(str(exc)) from None


def mechanism_size(record: BuildRecord, params: dict[str, float]) -> float:
    """S: the sum of the input lengths and offsets and of the lengths the description writes as
    numbers (every frame fits in a circle that big)."""
    kinds = record.kinds()
    size = sum(abs(v) for s, v in params.items()
               if kinds[s] in ("length", "offset") and not np.isnan(v))   # NaN: not designed
    return max(size + sum(abs(v) for v in written_in(record).values()), 1e-300)


def input_column(ws, column: str, rows, is_angle: bool) -> np.ndarray:
    """The input values down `column` over `rows` (first, last)."""
    return np.array([input_at(ws, f"{column}{r}", "input value", is_angle)
                     for r in range(rows[0], rows[1] + 1)])


def input_at(ws, cell: str, what: str, is_angle: bool) -> float:
    """An input angle (or actuator length): a number within the supported domain."""
    try:
        return check_input(f"{ws.title}!{cell}: {what}", number_at(ws, cell, what), is_angle)
    except InputError as exc:
        raise UnusableFile(str(exc)) from None


def formula_cells(wb) -> set[tuple[str, str]]:
    """(sheet, cell) of every formula cell of the book."""
    return set(FormulaCells(wb))


class FormulaCells:
    """Formula cells of a book as one boolean grid a sheet (indexed by row and column, from 1):
    a big book holds hundreds of thousands, which a set of (sheet, cell) keys would hold as two
    objects each. Iterated in cell order."""

    def __init__(self, wb=None, grids: dict[str, np.ndarray] | None = None):
        from ..base.xlsx import column_entries
        self.grids = {} if grids is None else grids
        for ws in (wb.worksheets if wb is not None else ()):
            rows, cols = [], []
            for col, held_rows, _, kinds in column_entries(ws):
                found = [row for row, kind in zip(held_rows, kinds) if kind == "f"]
                rows += found
                cols += [col] * len(found)
            if rows:
                grid = self.grids[ws.title] = np.zeros((max(rows) + 1, max(cols) + 1), bool)
                grid[rows, cols] = True

    def __len__(self) -> int:
        return sum(int(grid.sum()) for grid in self.grids.values())

    def __iter__(self):
        from ..base.xlsx import column_letter
        for sheet in sorted(self.grids):
            cols, rows = np.nonzero(self.grids[sheet].T)    # column by column, down each
            for col, row in zip(cols.tolist(), rows.tolist()):
                yield sheet, f"{column_letter(col)}{row}"

    def holds(self, sheet: str, row: int, col: int) -> bool:
        grid = self.grids.get(sheet)
        return grid is not None and row < grid.shape[0] and col < grid.shape[1] \
            and bool(grid[row, col])

    def __contains__(self, key: tuple[str, str]) -> bool:
        from ..base.xlsx import coordinate_to_tuple
        return self.holds(key[0], *coordinate_to_tuple(key[1]))

    def judged(self, checks) -> tuple[set[tuple[str, str]], FormulaCells]:
        """What `checks` judged, parted: the cells that hold no formula here, and the formula
        cells."""
        from ..base.xlsx import coordinates_to_arrays
        by_sheet: dict[str, list[str]] = {}
        for check in checks:
            for sheet, cells in check.judged.by_sheet.items():
                by_sheet.setdefault(sheet, []).extend(cells)
        elsewhere, grids = set(), {}
        for sheet, cells in ((s, c) for s, c in by_sheet.items() if c):
            rows, cols = coordinates_to_arrays(cells)
            grid = self.grids.get(sheet, np.zeros((0, 0), bool))
            inside = (rows < grid.shape[0]) & (cols < grid.shape[1])
            formula = np.zeros(len(cells), bool)
            formula[inside] = grid[rows[inside], cols[inside]]
            elsewhere.update((sheet, cells[i]) for i in np.flatnonzero(~formula).tolist())
            if formula.any():
                grids[sheet] = np.zeros_like(grid)
                grids[sheet][rows[formula], cols[formula]] = True
        return elsewhere, FormulaCells(grids=grids)

    def without(self, other: FormulaCells) -> FormulaCells:
        """These cells but those of `other`."""
        return FormulaCells(grids={sheet: grid & ~other.grids[sheet] if sheet in other.grids
                                   else grid for sheet, grid in self.grids.items()})


def cell_order(key: tuple[str, str]) -> tuple:
    from ..base.xlsx import coordinate_to_tuple
    row, col = coordinate_to_tuple(key[1])
    return key[0], col, row


def stored_values(wb, path, cells: FormulaCells) -> dict[tuple[str, str], object]:
    """(sheet, cell) -> the value each of `cells` (formula cells) stores with its formula (the
    `<v>`): what LibreOffice with default settings, openpyxl's data_only and pandas show. Numbers
    as float, errors as office.CellError, text as str; a cell that stores none is left out."""
    from ..base.xlsx import CellError, column_letter
    if not all(hasattr(ws, "stored_items") for ws in wb.worksheets):   # openpyxl read it
        from ..engine.office import read_values
        return {k: v for k, v in read_values(path).items() if k in cells}
    out = {}
    for ws in wb.worksheets:
        for (row, col), (kind, text) in ws.stored_items():
            if not cells.holds(ws.title, row, col):
                continue
            key = (ws.title, f"{column_letter(col)}{row}")
            if kind == "e":
                out[key] = CellError(text)
            elif kind == "b":
                if text.strip() not in ("0", "1", "true", "false"):
                    raise UnusableFile(f"{path}: {key[0]}!{key[1]}: the stored value {text!r} "
                                       "is not a boolean")
                out[key] = text.strip() in ("1", "true")
            elif kind == "n":
                try:
                    out[key] = float(text)
                except ValueError:
                    raise UnusableFile(f"{path}: {key[0]}!{key[1]}: the stored value {text!r} "
                                       "is not a number") from None
            else:
                out[key] = text
    return out

