"""Fast evaluation of a workbook of live formulas, with the `formulas` package's own functions.

Method
------
1. *Shapes.* Every formula cell's text is rewritten with each reference in a relative form
   (R1C1: an offset for relative parts, a number for ``$`` parts, the sheet always explicit; a
   workbook-scoped defined name becomes the absolute reference to its target).  In C8,
   ``=A8*COS(B8)-$D$2+E$7`` has the shape ``='S'!R[0]C[-2]*COS('S'!R[0]C[-1])-'S'!R2C4+'S'!R7C[2]``.
   Cells of one sheet with one shape form a *group*: a column of a sweep table is one group.
   References are found by a regex lexer (fast), and for every group the parser re-reads the
   first member: if its references are not exactly the lexer's spans, every member of that group
   is re-read by the parser (slow but exact).  The parser is the engine's grammar (grammar.py),
   which reads the grammar linkbook writes into the graph `formulas`' parser would make, node for
   node, in a fraction of its time; for any formula outside that grammar it is `formulas`' own
   parser.
2. *One compile per group.* The parsed graph of a representative member, compiled.
   The compiled function's inputs (``'E5'``, ``'SWEEP!B5:B40'``, ``'A_3'``) are tied to the
   reference descriptors of the shape (and checked against the ranges `formulas` resolved), so
   any member's inputs are the descriptors shifted to that member.  The representative is the
   first member unless two descriptors share one input there (``=B5+$B$5`` in row 5): then a
   member where they do not (row 6) is compiled instead.  "Compiled" means a Pipe: the parsed
   graph's function nodes (formulas' own functions) called in dependency order, without
   schedula's dispatcher; only a graph with operators on references or impure functions goes
   through ``compile()``.  A formula that is one reference, name or constant is a pipe of no
   steps.  With ``only`` (cells wanted), the groups those cells do not need,
   by the references of the shapes, are dropped before anything is compiled, and a sheet is
   grouped only when a needed group reads it.
3. *Order.* A group depends on the groups owning the cells it reads.  Groups are evaluated in
   topological order of their strongly connected components; a group that reads itself (a running
   column) or a cycle of groups is evaluated cell by cell in cell-level topological order, but
   for a running sum (running.py: each cell the cell above plus a term), whose terms are one
   vector call and whose sum runs down the rows, and a row recurrence (scan.py: one-column
   groups that read each other only in their row or rows above, as a Newton iteration that
   starts from the row above's solution), evaluated in one pass down the rows, each cell by
   its formula written as a Python function on floats, or by the cell path where that cannot
   give the cell path's value.
4. *Modes.*
   - ``vector``: single-cell inputs only, functions from ELEMENTWISE and ROW_BY_ROW only.  The
     function is called once with an (n, 1) object array per input.  A group of one cell too:
     its nodes are formulas' functions called on (1, 1) arrays, a per-cell call without a
     Ranges built for each input.  Each node of the compiled
     graph is wrapped: element-wise functions (arithmetic, COS, ATAN2, IF, IFERROR, ...) run on
     the whole array; other nodes (MAX of two cells, AND, ...), and an element-wise node whose
     output collapsed (``formulas`` turns an exception such as an overflow into one #VALUE! for
     the whole call), run row by row on (1, 1) slices, which is exactly what a per-cell call does.
     Arithmetic and the common math functions (NUMERIC_FORMS) first run as float-array
     operations on the rows whose arguments are finite numbers, giving the bits formulas' own
     per-element call gives; the other rows (errors, text, EMPTY, non-finite results) go through
     formulas' function.  MIN, MAX and COUNT (AGGREGATES) pick their result per row on arrays.
   - ``cell``: ranges or other functions (ROWS, INDEX, SMALL, ``:``, ...).  The group's one
     compiled function is called per member with `formulas` Ranges inputs, as ExcelModel does;
     MIN, MAX and COUNT read their ranges as arrays.
   - ``each``: functions that read the host cell (ROW(), COLUMN(), ``@``), or inputs that are not
     one reference (unions, intersections): every member is compiled on its own with its host
     cell, like ExcelModel.
5. *Values* follow ExcelModel: an empty cell is ``sh.EMPTY`` (functions treat it as 0 / ""), a
   result that is EMPTY becomes 0, numeric constants are the double the saved file holds (openpyxl
   writes ``%.16g``; rounded to 15 decimals as ExcelModel rounds them with
   ``excel_model_constants``), errors are `formulas` XlError objects (#N/A, #NUM!, ...).

Limits (they raise UnsupportedFormulaError rather than guess): INDIRECT, OFFSET, ISFORMULA,
FORMULATEXT, CELL, spill/anchor references, whole-column/row ranges (A:A, 1:1), R1C1 text,
external books, unknown sheets or names, sheet-scoped names, names that are not a cell or range
reference, multi-cell array formulas, data-table formulas.  Circular references raise
CircularReferenceError.  Dates are passed through as openpyxl returns them.  A self-reading group
that reads itself through ranges (``=SUM($C$5:C7)`` in column C) costs O(n^2) to order.

Modules of the engine: references (what a formula reads: descriptors, shapes, the lexer),
adapter (the one place that touches `formulas`' internals: its tokenizer, compiled pipes,
ExcelModel), vector (vector calls), groups (cells into groups of one shape), plan (each group's
mode and compiled function), order (the order of evaluation), running (running sums), grammar
(the fast parser), scan (row recurrences), rerun (after run(), the book again with other
values in some constant cells: only what moves with them and is asked for), and this one: the public entry points and the Engine that runs the steps above.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import numpy as np
import schedula as sh
from formulas.ranges import Ranges
from formulas.tokens.operand import XlError

from .adapter import (call, cell_result, empty_as_zero, evaluate_formulas_model, public_value,
                      ranges_of, tokenize)
from .errors import CircularReferenceError, EngineError, UnsupportedFormulaError
from .groups import Group, Grouper, Member
from .order import cell_order, closure, downstream, group_deps, untangled_components
from .plan import Planner
from .rerun import Values
from .running import running_sum_input
from .scan import row_order, scans_of
from .references import (RefDesc, References, cell_name, cells_read, formula_shape,
                         sheet_prefix)
from .vector import VECTOR_SAFE, Batch
from ..base.xlsx import coordinate_to_tuple

__all__ = [
    "evaluate", "vary", "evaluate_file", "evaluate_formulas_model", "is_error", "error_code",
    "shape_of", "cells_read", "Engine",
    "EngineError", "UnsupportedFormulaError", "CircularReferenceError",
]


# --------------------------------------------------------------------------- public API


def evaluate(wb, only=None,
             excel_model_constants: bool = False) -> dict[tuple[str, str], object]:
    """Value of every non-empty cell of every worksheet, keyed by (sheet title, 'B7').

    Formula cells get a float, a `formulas` XlError (#N/A, #NUM!, #DIV/0!, ...), or a str/bool
    where the formula yields one; constants keep their type (ints stay ints).  `only`: cells
    ((sheet title, 'B7')) whose values are wanted: then only the formulas they need, directly
    or not, are evaluated, and the result holds those formula cells and every constant of the
    sheets they read (other sheets are not read at all). Number
    constants are read as the double the file holds, as Excel and LibreOffice read them;
    `excel_model_constants` rounds them to 15 decimals first, as formulas.ExcelModel does (which
    loses digits of small numbers: 1.2345678901234e-5 becomes 1.2345678901e-5), for bit-for-bit
    comparisons with it."""
    return Engine(wb, only=only, excel_model_constants=excel_model_constants).run()


def vary(wb, cell: tuple[str, str], inputs, read) -> Iterator[dict]:
    """For each value of `inputs` put into the input cell `cell` ((sheet title, 'I7')): the
    values (as evaluate() gives them) of the cells in `read`. The book is evaluated once; then
    only the formulas downstream of the input cell are evaluated again for each value."""
    return Engine(wb).vary(cell[0], cell[1], inputs, read)


def evaluate_file(path, excel_model_constants: bool = False) -> dict[tuple[str, str], object]:
    """evaluate() of the workbook at `path`, loaded with its formulas (not data_only)."""
    import openpyxl
    return evaluate(openpyxl.load_workbook(path, data_only=False),
                    excel_model_constants=excel_model_constants)


def shape_of(formula: str, cell: str, sheet: str = "Sheet", wb=None) -> str:
    """The shape of `formula` written in `cell` ('C8') of `sheet`: every reference in R1C1 form
    with its sheet, names of `wb` replaced by their targets.  Found by the `formulas` tokenizer."""
    refs = References.of(wb) if wb is not None else References([sheet])
    row, col = coordinate_to_tuple(cell)
    return formula_shape(formula, tokenize(formula).spans, refs, refs.sheet(sheet), row, col)[0]


def is_error(value) -> bool:
    return isinstance(value, XlError)


def error_code(value) -> str | None:
    """'#N/A', '#NUM!', ... for an error value, else None."""
    return str(value) if isinstance(value, XlError) else None


class Engine:
    """One evaluation of one workbook; `stats` tells how it was grouped and run."""

    def __init__(self, wb, vectorize: bool = True, only=None,
                 excel_model_constants: bool = False, scan: bool = True):
        self.wb = wb
        self.scan = scan            # row recurrences as scans (scan.py); False: cell by cell
        self.excel_model_constants = excel_model_constants
        self.only = only
        self.vectorize = vectorize
        self.refs = References.of(wb)
        self.constants: dict[str, dict[tuple[int, int], object]] = {}
        self.groups: list[Group] = []
        self.grid: dict[str, np.ndarray] = {}
        self.owner: dict[str, np.ndarray] = {}
        self.member: dict[str, np.ndarray] = {}
        self.stats = dict(formula_cells=0, shapes=0, compiled=0, reused=0, vector_groups=0,
                          cell_groups=0, each_groups=0, cyclic_cells=0, tokenized_cells=0,
                          vector_fallbacks=0, row_by_row_nodes=0, split_groups=0,
                          running_sums=0, scans=0, scan_cells=0, scan_cell_path=0)
        self.planner = Planner(self.refs, self.stats, vectorize)

    # ---- pipeline
    def run(self) -> dict[tuple[str, str], object]:
        self._evaluate_all()
        return self._values()

    def run_view(self) -> Values:
        """run(), its values read where the engine holds them (rerun.Values, a mapping like
        run()'s dict) instead of copied into a dict of every cell."""
        self._evaluate_all()
        return Values(self)

    def _evaluate_all(self) -> None:
        self._prepare()
        # Overflow warnings would only repeat what the #NUM!/#VALUE! results say; 'ignore' and
        # numpy's default 'warn' give the same values.
        with np.errstate(all="ignore"):
            for component in self.order:
                self._evaluate_component(component)
        batches = {id(g.batch): g.batch for g in self.groups}.values()   # groups share them
        self.stats["row_by_row_nodes"] = sum(b.row_by_row for b in batches)
        self.stats["numeric_nodes"] = sum(b.numeric for b in batches)

    def _prepare(self) -> None:
        """Group, plan, allocate and order: everything but the evaluation."""
        if self.groups or self.constants:
            raise EngineError("an Engine runs once; make a new one")
        grouper = Grouper(self.refs, self.stats, self.excel_model_constants)
        if self.only is None:
            grouper.group(grouper.read_cells(self.wb.worksheets))
        else:
            grouper.group_needed(self.wb, self.only)
        self.groups, self.constants = grouper.groups, grouper.constants
        for g in self.groups:
            self.planner.plan(g)
        self._allocate()
        self.order, self.self_reading = untangled_components(
            self.groups, self.owner, self.member, self.stats,
            keep=lambda c: self.scan and row_order(c, self.groups, self.owner) is not None)
        self.scans = (scans_of(self.order, self.self_reading, self.groups, self.owner,
                               self.refs) if self.scan else {})

    # ---- storage
    def _allocate(self):
        """Value grid (object, EMPTY where nothing), and which group/member owns each cell."""
        size = {ws.title: [ws.max_row, ws.max_column] for ws in self.wb.worksheets
                if ws.title in self.constants}          # the sheets read (all, without `only`)
        for g in self.groups:
            last_row, last_col = int(g.rows.max()), int(g.cols.max())
            self._grow(size, g.sheet, last_row, last_col)
            if g.mode == "each":
                for cell in g.each:
                    for sheet, _, _, r2, c2 in cell.rects:
                        self._grow(size, sheet, r2, c2)
                continue
            for d in g.inputs:
                # a reference's row (column) is the host's plus an offset, or fixed: at the
                # last member's row and column it reaches its furthest
                r1, c1, r2, c2 = d.at(last_row, last_col)
                self._grow(size, d.sheet, max(r1, r2), max(c1, c2))
        for sheet, (rows, cols) in size.items():
            grid = np.empty((rows + 1, cols + 1), object)
            grid.fill(sh.EMPTY)
            for (r, c), v in self.constants.get(sheet, {}).items():
                grid[r, c] = v
            self.grid[sheet] = grid
            self.owner[sheet] = np.full((rows + 1, cols + 1), -1, dtype=np.int64)
            self.member[sheet] = np.full((rows + 1, cols + 1), -1, dtype=np.int64)
        for g in self.groups:
            self.owner[g.sheet][g.rows, g.cols] = g.gid
            self.member[g.sheet][g.rows, g.cols] = np.arange(len(g.members))

    @staticmethod
    def _grow(size, sheet, rows, cols):
        size[sheet][0] = max(size[sheet][0], rows)
        size[sheet][1] = max(size[sheet][1], cols)

    def vary(self, sheet: str, cell: str, inputs, read) -> Iterator[dict]:
        """For each value of `inputs` put into the constant cell (sheet, cell), the values of
        the cells `read` ((sheet, 'B7') each; None for a cell outside every sheet).

        Only what the read cells need is evaluated: once what does not move with the input,
        then what does, once for all the input values together: the input values are one more
        batch dimension of the compiled vector functions (a group that cannot take it is
        evaluated value by value, cell by cell). Groups count whole, so a little more than
        needed may be evaluated, never less."""
        self._prepare()
        read = list(read)
        place = self._input_place(sheet, cell)
        targets = []
        for s, a1 in read:
            r, c = coordinate_to_tuple(a1)
            if s in self.grid and r < self.grid[s].shape[0] and c < self.grid[s].shape[1]:
                targets.append((s, a1, r, c))
        deps = {g.gid: group_deps(g, self.owner) for g in self.groups}
        needed = closure({int(self.owner[s][r, c]) for s, _, r, c in targets} - {-1}, deps)
        with np.errstate(all="ignore"):
            for component in self.order:          # what the read cells need, once
                if needed.intersection(component):
                    self._evaluate_component(component)
        inputs = list(inputs)
        varying = {place: np.array(inputs, dtype=object)}
        reached = downstream(self.groups, self.grid, [place], deps) & needed
        with np.errstate(all="ignore"):
            for component in self.order:          # then what moves with the input, per value
                if not reached.intersection(component):
                    continue
                if len(component) == 1 and component[0] not in self.self_reading \
                        and self._vary_vector(self.groups[component[0]], varying, len(inputs)):
                    continue
                self._vary_cells(component, varying, len(inputs))
        for f in range(len(inputs)):
            out = dict.fromkeys(read)
            for s, a1, r, c in targets:
                value = varying[(s, r, c)][f] if (s, r, c) in varying else self.grid[s][r, c]
                out[(s, a1)] = public_value(value, self.owner[s][r, c] >= 0)
            yield out

    def _input_place(self, sheet: str, cell: str) -> tuple[str, int, int]:
        """(sheet, row, col) of a constant cell that may take other values."""
        row, col = coordinate_to_tuple(cell)
        grid = self.grid.get(sheet)
        if grid is None or row >= grid.shape[0] or col >= grid.shape[1]:
            raise EngineError(f"no cell {sheet}!{cell}")
        if self.owner[sheet][row, col] >= 0:
            raise EngineError(f"{sheet}!{cell} holds a formula, not an input value")
        return sheet, row, col

    def _vary_vector(self, g: Group, varying: dict, n: int) -> bool:
        """One call of g's vector function for all members × all input values; False (nothing
        stored) where g has no vector form or the result is not one value per row."""
        if g.mode not in ("vector", "cell") or not g.info.functions <= VECTOR_SAFE \
                or any(d.is_range for d in g.inputs):
            return False
        func, batch, inputs = ((g.func, g.batch, g.inputs) if g.mode == "vector"
                               else self.planner.vector_form(g))
        if func is None:
            return False
        m = len(g.members)
        args = []
        for d in inputs:
            r1, c1, _, _ = d.at(g.rows, g.cols)
            rows, cols = np.broadcast_arrays(r1, c1, g.rows)[:2]
            column = np.empty((m, n), dtype=object)
            for i, (r, c) in enumerate(zip(rows.tolist(), cols.tolist())):
                column[i, :] = varying.get((d.sheet, r, c), self.grid[d.sheet][r, c])
            args.append(column.reshape(m * n, 1))
        values = _per_row(func, batch, args, m * n, bool(inputs))
        if values is None:
            return False
        for i, member in enumerate(g.members):
            varying[(g.sheet, member.row, member.col)] = values[i * n:(i + 1) * n]
        return True

    def _vary_cells(self, component: list[int], varying: dict, n: int) -> None:
        """The fallback: the component evaluated cell by cell, once per input value."""
        cells = [(self.groups[gid].sheet, m.row, m.col)
                 for gid in component for m in self.groups[gid].members]
        results = {key: np.empty(n, dtype=object) for key in cells}
        for f in range(n):
            for (s, r, c), values in varying.items():
                self.grid[s][r, c] = values[f]
            self._evaluate_component(component)
            for key in cells:
                results[key][f] = self.grid[key[0]][key[1], key[2]]
        varying.update(results)

    # ---- evaluation
    def _evaluate_component(self, component: list[int]):
        if len(component) == 1 and component[0] not in self.self_reading:
            g = self.groups[component[0]]
            if g.mode == "vector" and self._evaluate_vector(g):
                return
            for i in range(len(g.members)):
                self._evaluate_cell(g, i)
            return
        if len(component) == 1 and self._evaluate_running_sum(self.groups[component[0]]):
            return
        scan = self.scans.get(component[0])
        if scan is not None:
            scan.run(self.grid, self._evaluate_cell, self.stats)
            return
        for gid, i in cell_order(self.groups, set(component), self.owner, self.member,
                                 self.stats):
            self._evaluate_cell(self.groups[gid], i)

    def _vector_args(self, g: Group, replaced: int | None = None, by=None) -> list:
        """Each input's cells for every member, an (n, 1) object array; input `replaced` holds
        `by` in every row instead."""
        n = len(g.members)
        args = []
        for k, d in enumerate(g.inputs):
            if k == replaced:
                column = np.empty((n, 1), dtype=object)
                column.fill(by)
                args.append(column)
                continue
            r1, c1, _, _ = d.at(g.rows, g.cols)
            rows, cols = np.broadcast_arrays(r1, c1, g.rows)[:2]  # absolute refs: one cell, n times
            args.append(self.grid[d.sheet][rows, cols].reshape(n, 1))
        return args

    def _evaluate_vector(self, g: Group) -> bool:
        """One call for the whole group; False (nothing stored) if the result is not per row."""
        n = len(g.members)
        values = _per_row(g.func, g.batch, self._vector_args(g), n, bool(g.inputs))
        if values is None:
            self.stats["vector_fallbacks"] += 1
            return False
        self.grid[g.sheet][g.rows, g.cols] = values
        return True

    def _evaluate_running_sum(self, g: Group) -> bool:
        """A running sum (running.py): its terms in one vector call, then each cell the cell
        above plus its term, in row order; a cell whose sum is not a plain finite number (an
        error above or in its term, a blank) by the cell path. False: not a running sum."""
        k = running_sum_input(g)
        if k is None:
            return False
        terms = _per_row(g.func, g.batch, self._vector_args(g, k, -0.0), len(g.members), True)
        if terms is None:
            return False
        grid = self.grid[g.sheet]
        for i in np.argsort(g.rows, kind="stable").tolist():
            m = g.members[i]
            above, term = grid[m.row - 1, m.col], terms[i]
            total = above + term if _plain(above) and _plain(term) else None
            if total is not None and np.isfinite(total):
                grid[m.row, m.col] = total
            else:
                self._evaluate_cell(g, i)
        self.stats["running_sums"] += 1
        return True

    def _evaluate_cell(self, g: Group, i: int):
        m = g.members[i]
        if g.mode == "each":
            cell = g.each[i]
            func = cell.func
            args = [self._name_arg(x[1], m) if x[0] == "name" else self._ranges_arg(x[1], x[2])
                    for x in cell.inputs]
        else:
            func = g.func
            args = [self._desc_arg(d, m) for d in g.inputs]
        try:
            value = cell_result(call(func, args))
        except Exception as ex:
            raise EngineError(f"{g.sheet}!{cell_name(m.row, m.col)} {m.formula!r}: {ex!r}") from ex
        self.grid[g.sheet][m.row, m.col] = value

    def _desc_arg(self, d: RefDesc, m: Member) -> Ranges:
        sheet, r1, c1, r2, c2 = d.rect(m.row, m.col)
        ref = f"{sheet_prefix(sheet)}{cell_name(r1, c1)}:{cell_name(r2, c2)}"
        return ranges_of(ref, self.grid[sheet][r1:r2 + 1, c1:c2 + 1].copy())

    _name_arg = _desc_arg

    def _ranges_arg(self, template: Ranges, rects) -> Ranges:
        values = {}
        for r, (sheet, r1, c1, r2, c2) in zip(template.ranges, rects):
            values[r["name"]] = (r, self.grid[sheet][r1:r2 + 1, c1:c2 + 1].copy())
        return Ranges(template.ranges, values)

    # ---- output
    def _values(self) -> dict[tuple[str, str], object]:
        out = {}
        for sheet, consts in self.constants.items():
            for (r, c), v in consts.items():
                out[(sheet, cell_name(r, c))] = public_value(v, False)
        for g in self.groups:
            grid = self.grid[g.sheet]
            for m in g.members:
                out[(g.sheet, cell_name(m.row, m.col))] = public_value(grid[m.row, m.col], True)
        return out


def _plain(value) -> bool:
    """A number as a cell holds one (not a bool, an error, a blank or text)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


# rows of one vector call: every node of the formula holds an object a row until the call
# ends, and a long formula over a big grid would hold tens of MB at once
CALL_ROWS = 4096


def _per_row(func, batch: Batch, args: list, n: int, takes_inputs: bool) -> np.ndarray | None:
    """One call of a vector-compiled function over n rows: its n results (an object array), or
    None where a call fails or does not give one value per row (a formula without inputs
    gives one value, which every row shares). Rows are called CALL_ROWS at a time: a vector
    call gives each row what that row's own call gives, so the parts join to the whole."""
    if n <= CALL_ROWS or not args:
        return _rows_called(func, batch, args, n, takes_inputs)
    values = np.empty(n, object)
    for start in range(0, n, CALL_ROWS):
        stop = min(start + CALL_ROWS, n)
        part = _rows_called(func, batch, [a[start:stop] for a in args], stop - start,
                            takes_inputs)
        if part is None:
            return None
        values[start:stop] = part
    return values


def _rows_called(func, batch: Batch, args: list, n: int, takes_inputs: bool
                 ) -> np.ndarray | None:
    """_per_row's one call over n rows."""
    batch.n = n
    try:
        out = empty_as_zero(np.asarray(call(func, args), dtype=object))
    except Exception:   # e.g. _NotScalar: the per-cell path reports real errors
        return None
    finally:
        batch.n = 1
    flat = out.reshape(-1)
    if not (out.size == n or (out.size == 1 and not takes_inputs)) \
            or any(map(isinstance, flat, itertools.repeat(np.ndarray))):
        return None
    values = np.empty(n, object)
    values[:] = list(flat) if out.size == n else [flat[0]] * n
    return values
