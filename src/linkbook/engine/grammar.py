"""A fast reader of the formula grammar linkbook writes, for the engine.

`formulas`' parser is slow enough to be most of a small book's verify once the libraries are
loaded.  This one reads the subset of Excel's grammar that linkbook's books use — numbers,
strings, TRUE/FALSE, cell and range references (A1 style, optionally on a sheet, quoted or not),
defined names, the arithmetic, text and comparison operators, postfix %, and calls of functions
that `formulas` implements — in one regex pass and one operator-precedence pass, and gives the
same graph `formulas`' parser would: the same operators and functions from `formulas`' own tables,
the same constants, the same inputs under the same names, the same order of operations
(`formulas`' precedence and left associativity, unary minus above ^ as in Excel), repeated
subexpressions computed once, as `formulas` shares them (by their expression text).  The text
of a node is never built: it is known by its length and a hash made from its parts' (see
_Reader._node), so memory grows linearly with a formula's length, not with its square.
tests/test_grammar.py checks that node by node against `formulas` on every formula of the bundled
books and on random formulas in and around the grammar.

A run of signs is one operator, by the parity of its minus signs, as `formulas` reads it
(``A1--B1`` is ``A1+B1``, ``=--A1`` is ``=+A1``).

Anything else gives None, and the caller uses `formulas`' parser, which decides: whitespace
outside strings, newlines, empty arguments, arrays, error literals, unions and intersections, R1C1,
names with dots, a function `formulas` does not know, and the corners where `formulas` reads
otherwise than Excel would (a name or sheet that begins TRUE_ or FALSE!, a name spelled as a
function the formula calls, numbers with leading zeros or of hundreds of digits).
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass

from ..base.xlsx import column_index

# One token at a time, at the current position (re.match).  A reference or name must not run on
# into more of a name, a call, a sheet, a range or a spill mark; a number must not run on into a
# letter, a digit, a dot or a colon (the lookaheads `formulas` uses).
_TOKEN = re.compile(r"""
    (?P<string>"(?:[^"]|"")*")
  | (?P<ref>(?:(?P<sheet>'(?:''|[^'?*/\[\]:\\])+'|[A-Za-z_][A-Za-z0-9_.]*)!)?
        (?P<c1>\$?[A-Za-z]{1,3})(?P<r1>\$?[1-9][0-9]*)
        (?::(?P<c2>\$?[A-Za-z]{1,3})(?P<r2>\$?[1-9][0-9]*))?
    )(?![\w.(!:$\#\[])
  | (?P<number>(?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)(?:[eE][+-][0-9]+)?)(?![A-Za-z0-9.:])
  | (?P<call>[A-Za-z_][A-Za-z0-9_.]*)\(
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)(?![\w.(!:$\#\[])
  | (?P<signs>[-+]{2,})
  | (?P<op><=|>=|<>|[-+*/^&=<>%])
  | (?P<open>\()
  | (?P<close>\))
  | (?P<comma>,)
""", re.X)
# Names `formulas` reads otherwise: R1C1 references (R, C, RC, R2C3, ...); and a name or sheet
# that begins with TRUE or FALSE followed by what cannot continue a number (TRUE_X, TRUE!A1),
# which formulas' number token takes for the boolean.
_R1C1 = re.compile(r"[Rr][0-9]*(?:[Cc][0-9]*)?|[Cc][0-9]*")
_BOOLEAN_START = re.compile(r"(?:TRUE|FALSE)(?![A-Za-z0-9.])", re.IGNORECASE)
_LONGEST_NUMBER = 300       # Python will not read an integer of over 4,300 digits
_MAX_ROW, _MAX_COL = 1048576, 16384
# Expression texts are compared by length and a polynomial hash modulo a Mersenne prime; texts
# that hash alike are compared in full, so a collision costs time, never a wrong graph.
_MODULUS = (1 << 127) - 1
_BASE = 0x9E3779B97F4A7C15F39CC0605CEDC835

# formulas' precedences (tokens/operator.py): all binary operators are left-associative.
_PRECEDENCE = {"u-": 7, "u+": 7, "%": 6, "^": 5, "*": 4, "/": 4, "+": 3, "-": 3, "&": 2,
               "=": 1, "<": 1, ">": 1, "<=": 1, ">=": 1, "<>": 1}
OPERATORS = frozenset(_PRECEDENCE)
_UNARY = frozenset({"u-", "u+", "%"})


@dataclass(frozen=True)
class Parsed:
    """A formula as a graph.  `nodes[i]` is ("input", key) for a reference or name (key: the
    name `formulas` gives its Range token), ("const", value), or ("call", name, arguments) where
    name is the operator ('u-', '+', ...) or the function as written, and arguments are indices
    of earlier nodes; the last node is the result.  `spans` and `keys` are the references in
    the order of the text (one per occurrence); `functions` the operator and upper-case function
    names called."""
    formula: str
    spans: list[tuple[int, int]]
    keys: list[str]
    functions: frozenset[str]
    nodes: tuple[tuple, ...]


class _Unread(Exception):
    """Outside the grammar: `formulas` decides."""


def parse(formula: str, known_functions) -> Parsed | None:
    """The graph of `formula`, or None if it is outside this grammar (or calls a function not
    in `known_functions`, upper-case names)."""
    try:
        return _Reader(formula, known_functions).read()
    except _Unread:
        return None


class _Reader:
    def __init__(self, formula: str, known_functions):
        self.formula, self.known = formula, known_functions
        self.nodes: list[tuple] = []
        # A node's expression text as parts: literal strings and indices of earlier nodes
        # (whose texts they stand for); its length and hash; the nodes of each (length, hash).
        self.parts: list[tuple] = []
        self.lengths: list[int] = []
        self.hashes: list[int] = []
        self.index: dict[tuple[int, int], list[int]] = {}
        self.values: list[int] = []         # node indices of the operands read so far
        self.stack: list[list] = []         # operators, and ["(", None] / ["call", name, n]
        self.spans: list[tuple[int, int]] = []
        self.keys: list[str] = []
        self.functions: set[str] = set()

    def read(self) -> Parsed:
        text = self.formula
        if not text.startswith("=") or len(text) < 2 or "\n" in text \
                or "_XLETA." in text.upper():
            raise _Unread       # formulas drops newlines, and reads _xleta. as a lambda
        pos, expect_operand, last = 1, True, None
        while pos < len(text):
            m = _TOKEN.match(text, pos)
            if m is None:
                raise _Unread
            kind, token = m.lastgroup, m.group(m.lastgroup)
            if kind in ("string", "ref", "number", "name"):
                if not expect_operand:
                    raise _Unread
                self.values.append(self._operand(kind, token, m))
                expect_operand = False
            elif kind in ("op", "signs"):
                if kind == "signs":     # formulas folds a run of signs into one: --x is +x
                    token = "-" if token.count("-") % 2 else "+"
                expect_operand = self._operator(token, expect_operand, last)
            elif kind == "open":
                if not expect_operand:
                    raise _Unread
                self.stack.append(["(", None])
            elif kind == "call":
                if not expect_operand or token.upper() in ("TRUE", "FALSE") \
                        or token.upper() not in self.known:
                    raise _Unread
                self.functions.add(token.upper())
                self.stack.append(["call", token, 0])
            elif kind == "comma":
                if expect_operand:
                    raise _Unread        # an empty argument
                top = self._reduce_to_bracket()
                if top[0] != "call":
                    raise _Unread        # a union (A1,B1)
                top[2] += 1
                expect_operand = True
            else:   # close
                top = self._close(expect_operand, last)
                expect_operand = False
            last = (kind, token)
            pos = m.end()
        if expect_operand:
            raise _Unread
        while self.stack:
            entry = self.stack.pop()
            if entry[0] in ("(", "call"):
                raise _Unread
            self._apply(entry[0])
        if self.values != [len(self.nodes) - 1]:
            raise _Unread           # (the result is always the last node made)
        if set(self.keys) & self.functions:
            raise _Unread           # a name or cell named as a called function: formulas fails
        return Parsed(text, self.spans, self.keys, frozenset(self.functions), tuple(self.nodes))

    # ---- operands
    def _operand(self, kind: str, token: str, m) -> int:
        """The node of an operand; its expression text is the token as written, or the key."""
        if kind == "string":
            return self._node((token,), ("const", token[1:-1].replace('""', '"')))
        if kind == "number":
            if len(token) > 1 and token[0] == "0" and token[1].isdigit() \
                    or len(token) > _LONGEST_NUMBER:
                raise _Unread       # 007: formulas evaluates the text as Python does
            value = float(token) if any(c in token for c in ".eE") else int(token)
            return self._node((token,), ("const", value))
        if kind == "name":
            if token.upper() in ("TRUE", "FALSE"):
                return self._node((token,), ("const", token.upper() == "TRUE"))
            if _R1C1.fullmatch(token) or _BOOLEAN_START.match(token):
                raise _Unread
            key = token.upper()
        else:
            sheet = m["sheet"]
            if sheet is not None and not sheet.startswith("'") and _BOOLEAN_START.match(sheet):
                raise _Unread
            key = self._ref_key(m)
        self.spans.append(m.span(kind))
        self.keys.append(key)
        return self._node((key,), ("input", key))

    @staticmethod
    def _ref_key(m) -> str:
        """The name formulas gives the Range token: upper case, no $, a range of one cell as that
        cell, the sheet unquoted unless it has a space."""
        corners = []
        for c, r in (("c1", "r1"), ("c2", "r2")):
            if m[c] is None:
                continue
            col, row = m[c].lstrip("$").upper(), int(m[r].lstrip("$"))
            n = column_index(col)
            if n >= _MAX_COL or row >= _MAX_ROW:
                raise _Unread       # formulas reads the last column or row as a whole one
            corners.append((col, row, n))
        if len(corners) == 2:
            (_, r1, n1), (_, r2, n2) = corners
            if r1 > r2 or n1 > n2:
                raise _Unread
        cells = dict.fromkeys(f"{col}{row}" for col, row, _ in corners)
        ref = ":".join(cells)
        sheet = m["sheet"]
        if sheet is None:
            return ref
        if sheet.startswith("'"):
            sheet = sheet[1:-1]
        sheet = sheet.replace("''", "'").upper()
        if " " in sheet:
            sheet = f"'{sheet}'"
        return f"{sheet}!{ref}"

    # ---- operators
    def _operator(self, op: str, expect_operand: bool, last) -> bool:
        """Handle one operator token; whether an operand is expected next."""
        if expect_operand:
            if op not in ("+", "-"):
                raise _Unread
            self._push("u" + op)
            return True
        if op == "%":
            if last == ("op", "%"):
                raise _Unread          # formulas reads %% as one (unknown) operator
            self._push("%")
            return False
        self._push(op)
        return True

    def _push(self, op: str) -> None:
        """formulas' Operator.ast: pop what binds at least as tightly, then push."""
        pred = _PRECEDENCE[op]
        while self.stack and self.stack[-1][0] in _PRECEDENCE \
                and pred <= _PRECEDENCE[self.stack[-1][0]]:
            self._apply(self.stack.pop()[0])
        self.stack.append([op])

    def _reduce_to_bracket(self) -> list:
        while self.stack and self.stack[-1][0] in _PRECEDENCE:
            self._apply(self.stack.pop()[0])
        if not self.stack:
            raise _Unread
        return self.stack[-1]

    def _close(self, expect_operand: bool, last) -> None:
        if expect_operand:
            # only F(): a call with nothing between its brackets
            if last is None or last[0] != "call":
                raise _Unread
            top = self.stack.pop()
            self._apply_call(top[1], 0)
            return
        top = self._reduce_to_bracket()
        self.stack.pop()
        if top[0] == "call":
            self._apply_call(top[1], top[2] + 1)

    def _apply(self, op: str) -> None:
        args = self._arguments(1 if op in _UNARY else 2)
        self.functions.add(op)
        parts = ((op[1], args[0]) if op in ("u-", "u+") else (args[0], "%") if op == "%"
                 else ("(", args[0], f" {op} ", args[1], ")"))
        self.values.append(self._node(parts, ("call", op, args)))

    def _apply_call(self, name: str, n: int) -> None:
        args = self._arguments(n)
        parts = [f"{name.upper()}("]
        for i, a in enumerate(args):
            parts += (", ", a) if i else (a,)
        parts.append(")")
        self.values.append(self._node(tuple(parts), ("call", name, args)))

    def _arguments(self, n: int) -> tuple[int, ...]:
        """The last n operands read, taken off the operand stack."""
        if len(self.values) < n:
            raise _Unread
        args = tuple(self.values[len(self.values) - n:])
        del self.values[len(self.values) - n:]
        return args

    def _node(self, parts: tuple, node: tuple) -> int:
        """The index of the node of this expression text (`parts`: literal strings and earlier
        nodes standing for their texts), as formulas writes it (its node id): a repeated
        subexpression is computed once, and what formulas takes for one (-(A1%) and (-A1)%,
        both -A1%) is one node here too."""
        length, digest = 0, 0
        for part in parts:
            if isinstance(part, str):
                n, h = len(part), _hash(part)
            else:
                n, h = self.lengths[part], self.hashes[part]
            digest = (digest * _power(n) + h) % _MODULUS
            length += n
        alike = self.index.setdefault((length, digest), [])
        for i in alike:
            if self.parts[i] == parts or self._text(self.parts[i]) == self._text(parts):
                return i
        alike.append(len(self.nodes))
        self.nodes.append(node)
        self.parts.append(parts)
        self.lengths.append(length)
        self.hashes.append(digest)
        return len(self.nodes) - 1

    def _text(self, parts: tuple) -> str:
        """The expression text the parts stand for (only to tell apart texts that hash alike)."""
        out, todo = [], list(reversed(parts))
        while todo:
            part = todo.pop()
            if isinstance(part, str):
                out.append(part)
            else:
                todo.extend(reversed(self.parts[part]))
        return "".join(out)


@functools.lru_cache(maxsize=4096)     # short texts' lengths recur
def _power(n: int) -> int:
    """_BASE ** n modulo _MODULUS: what a hash is multiplied by when n characters follow."""
    return pow(_BASE, n, _MODULUS)


@functools.lru_cache(maxsize=4096)     # tokens and operator texts recur
def _hash(text: str) -> int:
    """The polynomial hash of a text: its characters' code points as digits in base _BASE."""
    digest = 0
    for ch in text:
        digest = (digest * _BASE + ord(ch)) % _MODULUS
    return digest
