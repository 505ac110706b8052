"""Formula cells joined into groups: the cells of one sheet whose formulas have one shape (a
column of a sweep table is one group), each a Group of Members; and the grouping itself
(Grouper), of every sheet or only of what some cells need."""
from __future__ import annotations

from dataclasses import dataclass, field
from itertools import compress

import numpy as np

from .adapter import TokenInfo, tokenize
from .errors import UnsupportedFormulaError
from .references import (RefDesc, References, cell_name, constant_of, formula_of,
                         formula_shape, formula_text, lex_spans, skeleton_of)
from .vector import Batch
from ..base.xlsx import column_entries, coordinate_to_tuple

# Skeletons whose references the `formulas` tokenizer has been seen to read exactly as the
# lexer does, with the functions they call: a formula of a known skeleton is not re-tokenized.
READ_SKELETONS: dict[str, set[str]] = {}


@dataclass(slots=True)
class Member:
    """A formula cell of a group, made when asked for (Members holds them as arrays)."""
    row: int
    col: int
    formula: str


class Members:
    """The formula cells of a group, in order: their rows and columns as arrays and their
    formula texts (the sheet's own text objects), with no object per cell: a big book holds
    hundreds of thousands. A Member is made when one is asked for."""
    __slots__ = ("rows", "cols", "formulas")

    def __init__(self, rows, cols, formulas: list[str]):
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.formulas = formulas

    def __len__(self) -> int:
        return len(self.formulas)

    def __getitem__(self, i: int) -> Member:
        return Member(int(self.rows[i]), int(self.cols[i]), self.formulas[i])

    def __iter__(self):
        return map(Member, self.rows.tolist(), self.cols.tolist(), self.formulas)

    def take(self, index: list[int]) -> Members:
        """The members at `index`, in its order."""
        return Members(self.rows[index], self.cols[index], [self.formulas[i] for i in index])


@dataclass
class EachCell:
    """A member compiled on its own ('each' mode)."""
    func: object
    inputs: list  # per compiled input: ('ranges', Ranges template, rects) or ('name', RefDesc)
    rects: list


@dataclass
class Group:
    """Formula cells of one sheet with one shape, evaluated by one compiled function (or, in
    'each' mode, one per member); `gid` is its index in the evaluation's groups."""
    gid: int
    sheet: str
    shape: str
    members: Members
    info: TokenInfo            # of members[0]
    descs: list[RefDesc]       # per reference of the shape: the same for every member
    mode: str = "vector"
    func: object = None
    inputs: list[RefDesc] = field(default_factory=list)   # per compiled input, in order
    batch: Batch = field(default_factory=Batch)
    each: list[EachCell] = field(default_factory=list)

    @property
    def rows(self) -> np.ndarray:
        """The members' rows."""
        return self.members.rows

    @property
    def cols(self) -> np.ndarray:
        """The members' columns."""
        return self.members.cols

    def reads(self, i: int) -> list[tuple[str, int, int, int, int]]:
        """Rectangles (sheet, top, left, bottom, right) read by member i."""
        if self.mode == "each":
            return self.each[i].rects
        m = self.members[i]
        return [d.rect(m.row, m.col) for d in self.inputs]


def tokenize_member(member: Member, sheet: str, stats: dict) -> TokenInfo:
    """The tokenizer's reading of a member's formula (counted in `stats`); its errors name the
    cell."""
    stats["tokenized_cells"] += 1
    try:
        return tokenize(member.formula)
    except UnsupportedFormulaError as ex:
        raise UnsupportedFormulaError(f"{sheet}!{cell_name(member.row, member.col)}: {ex}") from ex


class Grouper:
    """Reads the cells of a workbook's sheets: their constants (self.constants, by sheet) and
    their formulas, joined into groups (self.groups)."""

    def __init__(self, refs: References, stats: dict, excel_model_constants: bool = False):
        self.refs = refs
        self.stats = stats
        self.excel_model_constants = excel_model_constants
        self.constants: dict[str, dict[tuple[int, int], object]] = {}
        self.groups: list[Group] = []

    def read_cells(self, worksheets) -> dict[str, list[tuple[int, list[int], list[str]]]]:
        """The formulas of `worksheets` by sheet, a column at a time in column order: (column,
        its rows in order, their texts); their constants go to self.constants."""
        formulas_by_sheet = {}
        for ws in worksheets:
            consts, columns = {}, []
            # only cells that exist (ExcelModel too)
            for col, held_rows, values, kinds in sorted(column_entries(ws),
                                                        key=lambda entry: entry[0]):
                formula = [kind == "f" for kind in kinds]
                rows = list(compress(held_rows, formula))
                if rows:
                    columns.append((col, rows, [
                        formula_of(value) if type(value) is str else
                        formula_text(ws.cell(row, col))
                        for row, value in zip(rows, compress(values, formula))]))
                    self.stats["formula_cells"] += len(rows)
                if len(rows) == len(kinds):
                    continue                # a column of formulas only
                for row, value, kind in zip(held_rows, values, kinds):
                    if value is not None and kind != "f":
                        value = constant_of(value, kind, self.excel_model_constants)
                        if value is not None:
                            consts[(row, col)] = value
            self.constants[ws.title] = consts
            formulas_by_sheet[ws.title] = columns
        return formulas_by_sheet

    def group(self, formulas_by_sheet) -> None:
        """Join the formulas of each sheet into groups of one shape (self.groups)."""
        candidates: dict[tuple[str, str], Members] = {}
        for sheet, columns in formulas_by_sheet.items():
            candidates.update(((sheet, shape), members) for shape, members in
                              self._shapes(sheet, columns).items())
        exact: dict[tuple[str, str], tuple[list, TokenInfo, list[RefDesc]]] = {}
        for (sheet, shape), members in candidates.items():
            rep = members[0]
            lexed = None if shape.startswith("\0") else lex_spans(rep.formula, self.refs)
            skeleton = None if lexed is None else skeleton_of(rep.formula, lexed)
            read = READ_SKELETONS.get(skeleton)
            info = (TokenInfo(lexed, None, read, None) if read is not None
                    else tokenize_member(rep, sheet, self.stats))
            if lexed is not None and info.spans == lexed:
                exact_shape, descs = self._exact_shape(rep, sheet, info)
                if exact_shape == shape:
                    READ_SKELETONS[skeleton] = info.functions
                    exact[(sheet, shape)] = ([members], info, descs)
                    continue
            if info.builder is None:
                info = tokenize_member(rep, sheet, self.stats)
            for i, m in enumerate(members):  # the lexer misread this shape: re-read each
                m_info = info if i == 0 else tokenize_member(m, sheet, self.stats)
                exact_shape, descs = self._exact_shape(m, sheet, m_info)
                entry = exact.setdefault((sheet, "\0" + exact_shape), ([], m_info, descs))
                entry[0].append(members.take([i]))
        for (sheet, shape), (parts, info, descs) in exact.items():
            members = parts[0] if len(parts) == 1 else Members(
                np.concatenate([p.rows for p in parts]), np.concatenate([p.cols for p in parts]),
                [text for p in parts for text in p.formulas])
            self.groups.append(Group(len(self.groups), sheet, shape, members, info, descs))
        self.stats["shapes"] = len(self.groups)

    def _shapes(self, sheet: str, columns) -> dict[str, Members]:
        """The formulas of one sheet (read_cells' columns) by shape, each shape's members in
        row order and the shapes in the order a walk of the sheet row by row meets them.

        A cell that is a copy of the nearest formula above it, or else of the nearest to its
        left, has its shape (checking a copy is much cheaper than lexing); the entries keep the
        cell the template was made from, so every copy is a shift of that one. The columns are
        walked in turn, left to right: the nearest cells above and to the left are the same as
        in a walk row by row, and a run of copies down a column is checked in one call."""
        left = {}      # per row: the last (row, col, shape, template) to its left
        found: dict[str, tuple[list, list, list]] = {}

        def put(shape, col, rows, texts):
            held = found.get(shape)
            if held is None:
                held = found[shape] = ([], [], [])
            held[0].extend(rows)
            held[1].extend([col] * len(rows))
            held[2].extend(texts)

        for col, rows, texts in columns:
            above, i = None, 0
            while i < len(rows):
                row, formula = rows[i], texts[i]
                entry = self.copied_shape(formula, row, col, above, left.get(row))
                if entry is None:
                    try:
                        shape, template = self.refs.fast_shape(formula, sheet, row, col)
                        entry = (row, col, shape, template)
                    except UnsupportedFormulaError:
                        put("\0" + formula, col, [row], [formula])  # the tokenizer decides
                        i += 1
                        continue
                above = entry
                origin, origin_col, shape, template = entry
                end = i + 1 if origin_col != col else \
                    template.copied_down(origin, rows, texts, i + 1)
                left.update(zip(rows[i:end], [entry] * (end - i)))
                put(shape, col, rows[i:end], texts[i:end])
                i = end
        shapes = {}
        for shape, (rows, cols, texts) in found.items():
            order = np.lexsort((cols, rows)).tolist()          # row by row
            shapes[shape] = Members(np.array(rows)[order], np.array(cols)[order],
                                    [texts[k] for k in order])
        return dict(sorted(shapes.items(), key=lambda item: (int(item[1].rows[0]),
                                                             int(item[1].cols[0]))))

    def group_needed(self, wb, cells) -> None:
        """Group only what the formula cells among `cells` need, directly or not, following
        the references of each shape (before any compile: that is the cost saved).  A sheet is
        read and grouped when a needed group first reads it: a sheet that nothing needed reads
        (the Motion sheet, for the sweep's angles) is never read at all."""
        sheets = {ws.title: ws for ws in wb.worksheets}
        grouped: set[str] = set()
        needed: set[int] = set()
        todo_sheets = {sheet for sheet, _ in cells} & set(sheets)
        while todo_sheets:
            self.group(self.read_cells([sheets[s] for s in sorted(todo_sheets)]))
            grouped |= todo_sheets
            needed, read_sheets = self.needed_groups(cells)
            todo_sheets = (read_sheets & set(sheets)) - grouped
        self.groups = [g for g in self.groups if g.gid in needed]
        for gid, g in enumerate(self.groups):
            g.gid = gid

    def needed_groups(self, cells) -> tuple[set[int], set[str]]:
        """The groups that the formula cells among `cells` need, and every sheet they read."""
        owner = {}
        for g in self.groups:
            rows, cols = owner.get(g.sheet, (0, 0))
            owner[g.sheet] = (max(rows, int(g.rows.max())), max(cols, int(g.cols.max())))
        owner = {sheet: np.full((r + 1, c + 1), -1, dtype=np.int64)
                 for sheet, (r, c) in owner.items()}
        for g in self.groups:
            owner[g.sheet][g.rows, g.cols] = g.gid
        todo = set()
        for sheet, a1 in cells:
            row, col = coordinate_to_tuple(a1)
            grid = owner.get(sheet)
            if grid is not None and row < grid.shape[0] and col < grid.shape[1]:
                todo.add(int(grid[row, col]))
        todo.discard(-1)
        needed, sheets = set(), set()
        while todo:
            gid = todo.pop()
            needed.add(gid)
            sheets.update(d.sheet for d in self.groups[gid].descs)
            todo |= self.owners_read(self.groups[gid], owner) - needed - {-1}
        return needed, sheets

    @staticmethod
    def owners_read(g: Group, owner: dict[str, np.ndarray]) -> set[int]:
        """The groups (in `owner`, one grid per sheet) owning a cell that group g's references
        name, for any member."""
        rows, cols = g.rows, g.cols
        found = set()
        for d in dict.fromkeys(g.descs):     # a reference written twice is read once
            grid = owner.get(d.sheet)
            if grid is None:
                continue
            r1, c1, r2, c2 = np.broadcast_arrays(*d.at(rows, cols), rows)[:4]
            if not d.is_range:      # one cell per member: one look-up for all of them
                inside = (r1 < grid.shape[0]) & (c1 < grid.shape[1])
                found.update(grid[r1[inside], c1[inside]].ravel().tolist())
                continue
            for a, b, c, e in {(int(a), int(b), int(c), int(e))
                               for a, b, c, e in zip(r1, c1, r2, c2)}:
                found.update(grid[a:c + 1, b:e + 1].ravel().tolist())
        return found

    @staticmethod
    def copied_shape(formula, row, col, above, left):
        """The entry (row, col, shape, template) of the cell above, or else of the cell to the
        left, if this formula is its copy; None if it is neither's."""
        for prev in (above, left):
            if prev is None:
                continue
            prow, pcol, shape, template = prev
            if template.shifted(row - prow, col - pcol) == formula:
                return prev
        return None

    def _exact_shape(self, m: Member, sheet: str, info: TokenInfo):
        try:
            return formula_shape(m.formula, info.spans, self.refs, sheet, m.row, m.col)
        except UnsupportedFormulaError as ex:
            raise UnsupportedFormulaError(f"{sheet}!{cell_name(m.row, m.col)}: {ex}") from ex
