"""How each group runs: its mode (vector: one call for all members; cell: one compiled function
called per member; each: every member compiled on its own with its host cell) and its compiled
function, tied to the references of its shape.  Compiled functions are kept for reuse across
groups and evaluations in this process (COMPILED)."""
from __future__ import annotations

import numpy as np
from formulas.ranges import Ranges

from .adapter import TokenInfo, compile_formula
from .errors import UnsupportedFormulaError
from .groups import EachCell, Group, Member, tokenize_member
from .references import (MAX_COL, MAX_ROW, RefDesc, References, cell_name, lex_spans,
                         sheet_prefix, skeleton_of)
from .vector import VECTOR_SAFE, Batch

# Functions that read the host cell (the compiled graph has the CELL input).
HOST_AWARE = frozenset({"ROW", "COLUMN", "SINGLE", "_XLFN.SINGLE", "@"})

# Compiled functions by (sheet, skeleton, pattern of equal references, mode): see
# Planner.compiled.
COMPILED: dict[tuple, tuple[object, list[int], Batch]] = {}
COMPILED_MAX = 2048


class Planner:
    """Plans and compiles the groups of one evaluation."""

    def __init__(self, refs: References, stats: dict, vectorize: bool = True):
        self.refs = refs
        self.stats = stats
        self.vectorize = vectorize

    def plan(self, g: Group) -> None:
        """Choose g's mode (vector, cell, each) and compile it."""
        functions = g.info.functions
        if functions & HOST_AWARE:
            return self.plan_each(g)
        rep = self.representative(g)
        if rep is None:
            return self.plan_each(g)
        vector = (self.vectorize and functions <= VECTOR_SAFE
                  and not any(d.is_range for d in g.descs))
        g.mode = "vector" if vector else "cell"
        compiled = self.compiled(g, *rep)
        if compiled is None:
            return self.plan_each(g)   # unions, intersections: not tied to one reference
        g.func, positions = compiled
        g.inputs = [g.descs[i] for i in positions]
        self.stats[f"{g.mode}_groups"] += 1

    def compiled(self, g: Group, rep: Member, spans, keys):
        """(compiled function, index of the reference behind each of its inputs), or None when
        an input is not one reference.  Reused across groups and evaluations in this process:
        the function depends only on the text around the references, the pattern of equal
        references, the sheet and the mode (compiling is most of the cost of a small book)."""
        pattern = tuple(keys.index(k) for k in keys)
        skeleton = rep.formula if g.shape.startswith("\0") else skeleton_of(rep.formula, spans)
        key = (g.sheet, skeleton, pattern, g.mode)
        cached = COMPILED.get(key)
        if cached is not None:
            func, positions, g.batch = cached
            g.batch.row_by_row = g.batch.numeric = 0
            self.stats["reused"] += 1
            return func, positions
        info = g.info
        first = (rep.row, rep.col) == (g.rows[0], g.cols[0])
        if not first or info.builder is None or info.keys is None:
            info = tokenize_member(rep, g.sheet, self.stats)
        g.info = TokenInfo(info.spans, info.keys, info.functions, None)  # compile() consumes it
        func = compile_formula(info.builder, g.batch if g.mode == "vector" else None)
        self.stats["compiled"] += 1
        positions = []
        for name, template in func.inputs.items():
            i = info.keys.index(name) if name in info.keys else -1
            if i < 0 or not same_cells(g.descs[i], template, rep, g.sheet, self.refs):
                return None
            positions.append(i)
        if tuple(info.keys.index(k) for k in info.keys) != pattern:
            return func, positions   # the tokenizer pairs references otherwise: not reusable
        if len(COMPILED) >= COMPILED_MAX:
            COMPILED.pop(next(iter(COMPILED)))
        COMPILED[key] = (func, positions, g.batch)
        return func, positions

    def representative(self, g: Group):
        """(member, spans, reference keys) of a member whose formula gives every compiled input
        one descriptor.  In row 5, `=B5+$B$5` has one input 'B5' for two descriptors; row 6 has
        two inputs, and its compiled function serves rows 5.. as well (two inputs that happen to
        hold one cell are still right).  None if no member fits."""
        n = len(g.members)
        for i in dict.fromkeys((0, min(1, n - 1), n // 2, n - 1)):
            m = g.members[i]
            if g.shape.startswith("\0"):    # the lexer misread this shape: the tokenizer's keys
                info = g.info if i == 0 else tokenize_member(m, g.sheet, self.stats)
                spans, keys = info.spans, info.keys
            else:
                spans = g.info.spans if i == 0 else lex_spans(m.formula, self.refs)
                keys = [m.formula[a:b].replace("$", "").upper() for a, b in spans]
            by_key, clash = {}, []
            for key, desc in zip(keys, g.descs):
                if by_key.setdefault(key, desc) != desc:
                    clash.append((by_key[key], desc))
            if not clash or all(self.always_same(g, a, b) for a, b in clash):
                return m, spans, keys
        return None

    @staticmethod
    def always_same(g: Group, a: RefDesc, b: RefDesc) -> bool:
        """Do two descriptors name the same cells for every member (e.g. B8 and $B8 in C)?"""
        if a.sheet != b.sheet or a.is_range != b.is_range:
            return False
        shape = g.rows.shape
        return all(np.array_equal(np.broadcast_to(x, shape), np.broadcast_to(y, shape))
                   for x, y in zip(a.at(g.rows, g.cols), b.at(g.rows, g.cols)))

    def plan_each(self, g: Group) -> None:
        """Compile every member of g on its own, with its host cell ('each' mode)."""
        g.mode, g.each = "each", []
        for m in g.members:
            # a fresh parse: compile() may have run on g.info
            info = tokenize_member(m, g.sheet, self.stats)
            host = Ranges().push(f"{sheet_prefix(g.sheet)}{cell_name(m.row, m.col)}")
            func = compile_formula(info.builder, host=host)
            self.stats["compiled"] += 1
            inputs, rects = [], []
            for key, template in func.inputs.items():
                if isinstance(template, Ranges):
                    cells = [self.range_rect(r, g.sheet) for r in template.ranges]
                    inputs.append(("ranges", template, cells))
                    rects += cells
                elif template is None and self.refs.is_name(key):
                    desc = self.refs.name(key)
                    inputs.append(("name", desc))
                    rects.append(desc.rect(m.row, m.col))
                else:
                    raise UnsupportedFormulaError(
                        f"{g.sheet}!{cell_name(m.row, m.col)}: unknown reference {key!r}")
            g.each.append(EachCell(func, inputs, rects))
        self.stats["each_groups"] += 1

    def range_rect(self, r: dict, host_sheet: str):
        r1, r2, c1, c2 = int(r["r1"]), int(r["r2"]), r["n1"], r["n2"]
        if not (1 <= r1 <= r2 < MAX_ROW and 1 <= c1 <= c2 < MAX_COL):
            raise UnsupportedFormulaError(f"the whole-row/column or invalid range {r['name']!r} "
                                          "cannot be evaluated here")
        sid = r.get("sheet_id") or ""
        if sid.startswith("'"):
            sid = sid[1:-1].replace("''", "'")
        if "[" in sid:
            raise UnsupportedFormulaError(f"external reference {r['name']!r}")
        return (self.refs.sheet(sid) if sid else host_sheet), r1, c1, r2, c2

    def vector_form(self, g: Group):
        """(vector-compiled function, its batch, the reference behind each of its inputs) of a
        group planned cell by cell; (None, None, None) where it has none."""
        rep = self.representative(g)
        if rep is None:
            return None, None, None
        mode, batch, info = g.mode, g.batch, g.info
        g.mode, g.batch = "vector", Batch()
        try:
            compiled = self.compiled(g, *rep)
            if compiled is None:
                return None, None, None
            func, positions = compiled
            return func, g.batch, [g.descs[i] for i in positions]  # the batch may be a cached one
        finally:
            g.mode, g.batch, g.info = mode, batch, info


def same_cells(desc: RefDesc, template, rep: Member, host_sheet: str, refs: References) -> bool:
    """Does the compiled input's own range equal the descriptor at the representative cell?"""
    if template is None:   # a defined name: formulas leaves it unresolved
        return True
    if not isinstance(template, Ranges) or len(template.ranges) != 1:
        return False
    r = template.ranges[0]
    sid = r.get("sheet_id") or ""
    sid = sid[1:-1].replace("''", "'") if sid.startswith("'") else sid
    sheet = refs.titles.get(sid.upper()) if sid else host_sheet
    return (sheet, int(r["r1"]), r["n1"], int(r["r2"]), r["n2"]) == desc.rect(rep.row, rep.col)
