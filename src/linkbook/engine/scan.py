"""Row recurrences evaluated as scans: one pass down the rows, each cell by a plain Python
function on floats where it can give the cell path's value.

A *row recurrence* is a strongly connected set of one-column groups of one sheet whose cells
read cells of the set only in their own row or in rows above (`=IF(ISNUMBER(AT5),AT5,...)` in
E6 with AT6 computed from E6 through a block of columns: a Newton iteration that starts from the
row above's solution, or a running value). Within a row the groups read each other in an order
without cycles, so the cells can be evaluated row after row, the groups of a row in that order:
a valid order of every cell, found once, where the general cycle path (order.cell_order) finds
one cell by cell.

Each cell is evaluated by its group's *fast form* where the group has one: the formula written
as a Python function of floats (grammar's graph, node for node) that calls, for every node, the
same operation `formulas` calls for it on the same values (Python's float arithmetic, the numpy
ufunc on a Python float, the comparison of (type, value) pairs), so its value is bit for bit
and type for type the one the cell path gives. Whenever the cell path would meet anything else —
an input that is not a number, an error (NA(), a division by zero, a result that is not
finite), a complex power — the fast form gives up (Off) and that one cell goes to the cell
path, which decides. IF evaluates only the branch it picks: formulas evaluates both, but the
branch it does not pick cannot change its result. A group whose formula calls anything else
has no fast form: its cells go to the cell path, in the scan's order. A fast form is written
once for all groups of one skeleton and pattern of references (fast_form): the iteration blocks
of a Newton recurrence are one formula a block, shifted, and share it.
"""
from __future__ import annotations

import graphlib
import math
from typing import NamedTuple

import numpy as np

from . import grammar
from .adapter import plain_functions
from .groups import Group
from .references import References, lex_spans, skeleton_of


class Off(Exception):
    """The fast form cannot give this cell's value: the cell path decides."""


# Functions formulas computes as wrap_ufunc(numpy ufunc): the ufunc on float(argument).
_UFUNCS = {"ABS": np.abs, "ACOS": np.arccos, "ASIN": np.arcsin, "ATAN": np.arctan,
           "COS": np.cos, "DEGREES": np.degrees, "EXP": np.exp, "LN": np.log,
           "RADIANS": np.radians, "SIN": np.sin, "SQRT": np.sqrt, "TAN": np.tan}
_ARITHMETIC = {"+": "+", "-": "-", "*": "*"}
# formulas compares (type id, value) pairs: 0 for numbers. The pair's comparison gives the
# type of result formulas gives (a numpy bool where a numpy number decides it).
_COMPARISONS = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
_FLOAT_RESULTS = frozenset({*_ARITHMETIC, "/", "^", "U-", "%", "PI"})     # Python floats
_NUMBER, _BOOL, _TEXT = "n", "b", "s"
_NUMBERS = frozenset({float, int, np.float64})
_NAMESPACE = {"Off": Off, "NUMBERS": _NUMBERS, "atan2": np.arctan2, "mod": np.mod,
              "np_true": np.True_, "np_false": np.False_,
              **{f"u_{name}": fn for name, fn in _UFUNCS.items()}}
_FORMS: dict[tuple, "_Form"] = {}       # by _form_key
_FORMS_MAX = 4096


# ------------------------------------------------------------------------------ the order

def row_order(gids: list[int], groups: list[Group], owner) -> list[int] | None:
    """The groups of a strongly connected component in the order a row evaluates them, where
    the component is a row recurrence (module doc); None where it is not."""
    parts = [groups[gid] for gid in gids]
    sheet = parts[0].sheet
    if any(g.mode == "each" or g.sheet != sheet or len(set(g.cols.tolist())) != 1
           for g in parts):
        return None
    inside = set(gids)
    same_row: dict[int, set[int]] = {gid: set() for gid in gids}
    for g in parts:
        for d in g.inputs:
            read = _owners_read(g, d, owner) & inside
            if not read:
                continue
            if d.sheet != sheet or d.is_range or d.ar1 or d.r1 > 0:
                return None
            if d.r1 == 0:
                if g.gid in read:
                    return None
                same_row[g.gid] |= read
    try:
        return list(graphlib.TopologicalSorter(same_row).static_order())
    except graphlib.CycleError:
        return None


def _owners_read(g: Group, d, owner) -> set[int]:
    """The groups owning a cell that descriptor d of group g reads, over all its members."""
    r1, c1, r2, c2 = d.at(g.rows, g.cols)
    grid = owner[d.sheet]
    if not d.is_range:
        return set(grid[r1, c1].ravel().tolist())
    found = set()
    for a, b, c, e in zip(*(np.broadcast_to(x, g.rows.shape).tolist() for x in (r1, c1, r2, c2))):
        found.update(grid[min(a, c):max(a, c) + 1, min(b, e):max(b, e) + 1].ravel().tolist())
    return found


# ------------------------------------------------------------------------------ the scan

def scans_of(order: list[list[int]], self_reading: set[int], groups: list[Group],
             owner, refs: References) -> dict[int, "Scan"]:
    """The scan of each row recurrence among the components of `order` (the cycles of groups
    and the groups that read themselves), by the component's first group."""
    scans = {}
    for component in order:
        if len(component) > 1 or component[0] in self_reading:
            rows = row_order(component, groups, owner)
            if rows is not None:
                scans[component[0]] = Scan(component, rows, groups, refs)
    return scans


class Scan:
    """A row recurrence: its cells in evaluation order, each with its group's fast form."""

    def __init__(self, gids: list[int], order: list[int], groups: list[Group],
                 refs: References):
        rank = {gid: k for k, gid in enumerate(order)}
        self.sheets: list[str] = []
        fast = {gid: fast_form(groups[gid], self.sheets, refs) for gid in gids}
        cells = [(m.row, rank[gid], groups[gid], i, m.col, fast[gid])
                 for gid in gids for i, m in enumerate(groups[gid].members)]
        cells.sort(key=lambda c: c[:2])
        self.sheet = groups[gids[0]].sheet
        self.cells = [c[2:] + (c[0],) for c in cells]   # (group, member, col, fast, row)

    def run(self, grid: dict[str, np.ndarray], cell_path, stats: dict) -> None:
        """Every cell in order: its fast form's value, or the cell path's (cell_path(g, i))
        where the group has none or it gives up."""
        sheets = tuple(grid[s] for s in self.sheets)
        target = grid[self.sheet]
        slow = 0
        for g, i, col, fast, row in self.cells:
            if fast is not None:
                try:
                    target[row, col] = fast(row, sheets)
                    continue
                except (Off, ArithmeticError):
                    pass
            slow += 1
            cell_path(g, i)
        stats["scans"] += 1
        stats["scan_cells"] += len(self.cells)
        stats["scan_cell_path"] += slow


# ------------------------------------------------------------------------------ fast forms

def fast_form(g: Group, sheets: list[str], refs: References):
    """g's formula as a function (row, sheet grids) -> value on floats, or None where it calls
    what the fast form does not write; `sheets` collects the sheets it reads (their order is
    the grids' order).

    The function is made by a *form*, written once for all formulas of one skeleton (the text
    around their references, as Planner.compiled shares compiled functions) and one pattern of
    references: the sheet, row and column each reference reads are the form's arguments. The
    iteration blocks of a Newton recurrence, and the same iteration written down a column of
    another sheet, are one form."""
    key = _form_key(g, refs)
    form = _FORMS.get(key) if key is not None else None
    if form is None:
        form = _written_form(g)
        if key is not None and form.shared:
            if len(_FORMS) >= _FORMS_MAX:
                _FORMS.pop(next(iter(_FORMS)))
            _FORMS[key] = form
    if form.make is None:
        return None
    col = g.members[0].col
    arguments = []
    for j in form.slots:
        d = g.descs[j]
        if d.sheet not in sheets:
            sheets.append(d.sheet)
        arguments += [sheets.index(d.sheet), d.r1, d.c1 if d.ac1 else col + d.c1]
    return form.make(*arguments)


def _form_key(g: Group, refs: References):
    """What a form is written from: the skeleton, and for each reference the first one equal
    to it, whether its row is absolute and whether it is a range; None where the lexer's
    reading is not the group's own (the tokenizer decided its shape)."""
    rep = g.members[0]
    if g.shape.startswith("\0"):
        return None
    spans = lex_spans(rep.formula, refs)
    if len(spans) != len(g.descs):
        return None
    first = {}
    return (skeleton_of(rep.formula, spans),
            tuple((first.setdefault(d, j), d.ar1, d.is_range)
                  for j, d in enumerate(g.descs)))


class _Form(NamedTuple):
    """make(sheet index, row, column, ...) -> the cell function, three arguments for each
    reference in `slots` (indices into a group's descriptors: the first of each key), or None
    where there is no fast form; `shared`: the form of every group of its key (_form_key).
    References one key reads are equal descriptors in every group of the key, so the form
    reads them right in each."""
    make: object
    slots: tuple[int, ...]
    shared: bool


def _written_form(g: Group) -> _Form:
    """The form of g's formula: the grammar's graph written as Python."""
    none = _Form(None, (), True)
    parsed = grammar.parse(g.members[0].formula, plain_functions())
    if parsed is None or len(parsed.keys) != len(g.descs) or parsed.nodes[-1][0] != "call":
        return none
    slots: dict[str, int] = {}
    for j, (key, d) in enumerate(zip(parsed.keys, g.descs)):
        if d.is_range:
            return none
        if g.descs[slots.setdefault(key, j)] != d:
            # one key, two references (=B5+$B5 in B5): this member's reading, not its key's
            return none._replace(shared=False)
    try:
        source = _Writer(parsed.nodes, slots, g.descs).source()
    except _Unwritten:
        return none
    namespace = dict(_NAMESPACE)
    exec(compile(source, "<scan>", "exec"), namespace)
    return _Form(namespace["form"], tuple(slots.values()), True)


class _Unwritten(Exception):
    """The formula calls what the fast form does not write."""


class _Writer:
    """The source of a fast form. Each node is computed where it is first needed (inside the
    branch of an IF that needs it), as v<i>; its float, where arithmetic reads it, as f<i>."""

    def __init__(self, nodes, slots: dict[str, int], descs: list):
        self.nodes, self.slots, self.descs = nodes, slots, descs
        self.kinds: dict[int, frozenset[str]] = {}
        arguments = ", ".join(f"s{j}, r{j}, c{j}" for j in slots.values())
        self.lines = [f"def form({arguments}):", "    def cell(r, S):"]

    def source(self) -> str:
        top = _Scope(set(), 2)
        last = len(self.nodes) - 1
        self.line(top, f"return {self.value(last, top)}")
        self.lines.append("    return cell")
        return "\n".join(self.lines) + "\n"

    def line(self, scope: "_Scope", text: str) -> None:
        self.lines.append("    " * scope.indent + text)

    # ---- values
    def value(self, i: int, scope: "_Scope") -> str:
        """The name of node i's value, computed in `scope` if not yet."""
        name = f"v{i}"
        if i not in scope.done:
            getattr(self, "_" + self.nodes[i][0])(i, scope)
            scope.done.add(i)
        return name

    def number(self, i: int, scope: "_Scope") -> str:
        """Node i's value as the float formulas' arithmetic makes of it (float(x))."""
        if self.kind(i) - {_NUMBER, _BOOL}:
            raise _Unwritten
        v = self.value(i, scope)
        if self.float_kind(i):
            return v
        if ("f", i) not in scope.done:
            self.line(scope, f"f{i} = float({v})")
            scope.done.add(("f", i))
        return f"f{i}"

    def kind(self, i: int) -> frozenset[str]:
        if i not in self.kinds:
            self.kinds[i] = self._kind(self.nodes[i])
        return self.kinds[i]

    def float_kind(self, i: int) -> bool:
        """Is node i's value always a Python float (what arithmetic gives)?"""
        node = self.nodes[i]
        return node[0] == "call" and node[1].upper() in _FLOAT_RESULTS

    def _kind(self, node) -> frozenset[str]:
        if node[0] == "input":
            return frozenset({_NUMBER})
        if node[0] == "const":
            value = node[1]
            if isinstance(value, bool):
                return frozenset({_BOOL})
            return frozenset({_NUMBER if isinstance(value, (int, float)) else _TEXT})
        name, args = node[1].upper(), node[2]
        if name in _COMPARISONS or name == "ISNUMBER":
            return frozenset({_BOOL})
        if name == "IF":
            return self.kind(args[1]) | (self.kind(args[2]) if len(args) == 3
                                         else frozenset({_BOOL}))
        if name == "U+":
            return self.kind(args[0])
        return frozenset({_NUMBER})

    # ---- nodes
    def _input(self, i: int, scope: "_Scope") -> None:
        j = self.slots[self.nodes[i][1]]
        row = f"r{j}" if self.descs[j].ar1 else f"r + r{j}"
        v = f"v{i}"
        self.line(scope, f"{v} = S[s{j}][{row}, c{j}]")
        # a number, finite: anything else (text, a blank, an error, a boolean) the cell path
        self.line(scope, f"if type({v}) not in NUMBERS or {v} - {v}: raise Off")

    def _const(self, i: int, scope: "_Scope") -> None:
        value = self.nodes[i][1]
        if isinstance(value, float) and not math.isfinite(value):
            raise _Unwritten
        self.line(scope, f"v{i} = {value!r}")

    def _call(self, i: int, scope: "_Scope") -> None:
        _, name, args = self.nodes[i]
        name = name.upper()
        write, arity = _CALLS.get(name, (None, ()))
        if write is None or len(args) not in arity:
            raise _Unwritten
        write(self, name, i, args, scope)

    def _arithmetic(self, name: str, i: int, args, scope: "_Scope") -> None:
        a, b = (self.number(k, scope) for k in args)
        self.finite(scope, f"v{i} = {a} {_ARITHMETIC[name]} {b}", f"v{i}")

    def _divide(self, name: str, i: int, args, scope: "_Scope") -> None:
        a, b = (self.number(k, scope) for k in args)
        self.line(scope, f"if not {b}: raise Off")            # formulas: #DIV/0!
        self.finite(scope, f"v{i} = {a} / {b}", f"v{i}")

    def _power(self, name: str, i: int, args, scope: "_Scope") -> None:
        a, b = (self.number(k, scope) for k in args)
        self.line(scope, f"v{i} = {a} ** {b}")
        # a complex power is no float; 0 ** -1 and an overflow raise (ArithmeticError)
        self.line(scope, f"if type(v{i}) is not float or v{i} - v{i}: raise Off")

    def _unary(self, name: str, i: int, args, scope: "_Scope") -> None:
        if name == "U+":        # formulas passes the value itself on
            self.line(scope, f"v{i} = {self.value(args[0], scope)}")
        elif name == "U-":
            self.line(scope, f"v{i} = -{self.number(args[0], scope)}")
        else:                   # %
            self.line(scope, f"v{i} = {self.number(args[0], scope)} / 100.0")

    def _compare(self, name: str, i: int, args, scope: "_Scope") -> None:
        if any(self.kind(k) != {_NUMBER} for k in args):
            raise _Unwritten
        a, b = (self.value(k, scope) for k in args)
        self.line(scope, f"v{i} = (0, {a}) {_COMPARISONS[name]} (0, {b})")

    def _isnumber(self, name: str, i: int, args, scope: "_Scope") -> None:
        kind = self.kind(args[0])
        if len(kind) != 1:
            raise _Unwritten
        self.value(args[0], scope)          # its errors are the cell path's
        # formulas gives an array of booleans: a numpy bool where it is the cell's value,
        # a Python bool where a node reads it (as an object array)
        truth = kind == {_NUMBER}
        last = i == len(self.nodes) - 1
        self.line(scope, f"v{i} = {('np_true' if truth else 'np_false') if last else truth}")

    def _na(self, name: str, i: int, args, scope: "_Scope") -> None:
        self.line(scope, "raise Off")
        self.line(scope, f"v{i} = None")

    def _pi(self, name: str, i: int, args, scope: "_Scope") -> None:
        self.line(scope, f"v{i} = {math.pi!r}")

    def _ufunc(self, name: str, i: int, args, scope: "_Scope") -> None:
        self.finite(scope, f"v{i} = u_{name}({self.number(args[0], scope)})", f"v{i}")

    def _atan2(self, name: str, i: int, args, scope: "_Scope") -> None:
        x, y = (self.number(k, scope) for k in args)
        self.line(scope, f"if {x} == 0 and {y} == 0: raise Off")
        self.finite(scope, f"v{i} = atan2({y}, {x})", f"v{i}")

    def _mod(self, name: str, i: int, args, scope: "_Scope") -> None:
        x, y = (self.number(k, scope) for k in args)
        self.line(scope, f"if {y} == 0: raise Off")
        self.finite(scope, f"v{i} = mod({x}, {y})", f"v{i}")

    def _if(self, name: str, i: int, args, scope: "_Scope") -> None:
        if self.kind(args[0]) - {_NUMBER, _BOOL}:
            raise _Unwritten
        condition = self.value(args[0], scope)
        self.line(scope, f"if {condition}:")
        picked = _Scope(set(scope.done), scope.indent + 1)
        self.line(picked, f"v{i} = {self.value(args[1], picked)}")
        self.line(scope, "else:")
        other = _Scope(set(scope.done), scope.indent + 1)
        self.line(other, f"v{i} = {self.value(args[2], other) if len(args) == 3 else False}")

    def finite(self, scope: "_Scope", assignment: str, v: str) -> None:
        """An assignment, then Off where its value is not finite (formulas makes it #NUM!)."""
        self.line(scope, assignment)
        self.line(scope, f"if {v} - {v}: raise Off")


# The calls a fast form writes: (the writer, the numbers of arguments it takes).
_CALLS = {**{name: (_Writer._arithmetic, (2,)) for name in _ARITHMETIC},
          **{name: (_Writer._compare, (2,)) for name in _COMPARISONS},
          **{name: (_Writer._unary, (1,)) for name in ("U+", "U-", "%")},
          **{name: (_Writer._ufunc, (1,)) for name in _UFUNCS},
          "/": (_Writer._divide, (2,)), "^": (_Writer._power, (2,)),
          "IF": (_Writer._if, (2, 3)), "ISNUMBER": (_Writer._isnumber, (1,)),
          "NA": (_Writer._na, (0,)), "PI": (_Writer._pi, (0,)),
          "ATAN2": (_Writer._atan2, (2,)), "MOD": (_Writer._mod, (2,))}


class _Scope:
    """The nodes computed so far on the way to this point of the source, and its indent."""

    def __init__(self, done: set, indent: int):
        self.done, self.indent = done, indent
