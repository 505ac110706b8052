"""The reference's own reader of the mechanism language's expressions.

A parameter, a length, a branch or an `expression` step's formula may be text in Excel syntax.
The reference reads it with this small recursive-descent parser and evaluates the tree over
floats and numpy arrays (never eval), so that it shares no code with the workbook writer's
grammar. Any error Excel would show (#NUM!, #DIV/0!, #N/A) is NaN.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable, Mapping

import numpy as np

from ...base.xlsx import NUMBER_LITERAL

_TOKEN = re.compile(
    rf"\s*(?:(?P<num>{NUMBER_LITERAL})"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<op>\*\*|>=|<=|<>|==|!=|[-+*/^(),<>=]))"
)
_COMPARE_OPS = {">", ">=", "<", "<=", "=", "==", "<>", "!="}
# The reader recurses once per level (up to six calls for a bracket) and the evaluator once per
# operation: a text of thousands of signs or terms is refused before it exhausts the stack. The
# mechanism language allows 1,000 characters and 64 levels; these limits are no tighter.
_LONGEST = 1000
_DEEPEST_BRACKETS = 64
_DEEPEST = 128


def _clean(v):
    """Excel has no inf or NaN: an overflow, a division by zero or a domain error is an error
    value, NaN here."""
    v = np.asarray(v, dtype=float)
    return np.where(np.isfinite(v), v, math.nan) if v.ndim else (
        v if math.isfinite(float(v)) else np.asarray(math.nan))


def _np1(f: Callable) -> Callable:
    return lambda x: _clean(f(x))


def _atan2(x, y):                  # Excel's ATAN2(x, y): x first; ATAN2(0, 0) is #DIV/0!
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return _clean(np.where((x == 0.0) & (y == 0.0), math.nan, np.arctan2(y, x)))


def _if(c, a, b):
    c = np.asarray(c, dtype=float)
    return _clean(np.where(np.isnan(c), math.nan, np.where(c != 0.0, a, b)))


def _iferror(a, b):
    a = np.asarray(a, dtype=float)
    return _clean(np.where(np.isnan(a), b, a))


def _logical(fn):
    """AND, OR: TRUE (1) or FALSE (0) of numbers (non-zero is TRUE); an error propagates."""
    def f(*args):
        values = [np.asarray(a, dtype=float) for a in args]
        error = functools.reduce(np.logical_or, [np.isnan(v) for v in values])
        value = functools.reduce(fn, [v != 0.0 for v in values])
        return np.where(error, math.nan, np.asarray(value, dtype=float))
    return f


def _not(x):
    x = np.asarray(x, dtype=float)
    return np.where(np.isnan(x), math.nan, (x == 0.0).astype(float))


def _extreme(fn):
    def f(*args):
        out = np.asarray(args[0], dtype=float)
        for a in args[1:]:
            out = fn(out, np.asarray(a, dtype=float))   # NaN (an error) propagates
        return _clean(out)
    return f


# name → (number of arguments, None: one or more; function); Excel's spelling, case-insensitive.
_FUNCTIONS: dict[str, tuple[int | None, Callable]] = {
    "SQRT": (1, _np1(np.sqrt)),
    "ABS": (1, _np1(np.abs)),
    "SIN": (1, _np1(np.sin)),
    "COS": (1, _np1(np.cos)),
    "TAN": (1, _np1(np.tan)),
    "ASIN": (1, _np1(np.arcsin)),
    "ACOS": (1, _np1(np.arccos)),
    "ATAN": (1, _np1(np.arctan)),
    "ATAN2": (2, _atan2),
    "RADIANS": (1, _np1(np.radians)),
    "DEGREES": (1, _np1(np.degrees)),
    "PI": (0, lambda: np.asarray(math.pi)),
    "MIN": (None, _extreme(np.minimum)),
    "MAX": (None, _extreme(np.maximum)),
    "IF": (3, _if),
    "IFERROR": (2, _iferror),
    "NA": (0, lambda: np.asarray(math.nan)),
    "AND": (None, _logical(np.logical_and)),
    "OR": (None, _logical(np.logical_or)),
    "NOT": (1, _not),
    "SIGN": (1, _np1(np.sign)),
    "LN": (1, _np1(np.log)),          # a synthesis task's function of x (docs/synthesis.md)
    "LOG10": (1, _np1(np.log10)),
    "EXP": (1, _np1(np.exp)),
}


def _binary(op: str, a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if op == "+":
        return _clean(a + b)
    if op == "-":
        return _clean(a - b)
    if op == "*":
        return _clean(a * b)
    if op == "/":
        return _clean(a / b)
    if op == "^":                  # Excel: 0^0 is #NUM!, (−8)^(1/3) is #NUM!
        return _clean(np.where((a == 0.0) & (b == 0.0), math.nan, np.power(a, b)))
    nan = np.isnan(a) | np.isnan(b)
    res = {">": a > b, ">=": a >= b, "<": a < b, "<=": a <= b, "=": a == b, "==": a == b,
           "<>": a != b, "!=": a != b}[op]
    return np.where(nan, math.nan, res.astype(float))


class _Parser:
    """Precedence as in algebra (and in Python, whose `**`, `==` and `!=` are accepted too):
    compare := sum (op sum)?;  sum := product (('+'|'-') product)*;
    product := unary (('*'|'/') unary)*;  unary := ('+'|'-') unary | power;
    power := atom ('^' unary)?  (so −a^2 = −(a^2) and a^b^c = a^(b^c));
    atom := number | name | NAME '(' args ')' | '(' compare ')'.
    The tree: ('num', v) | ('name', n) | ('neg', t) | ('bin', op, l, r) | ('call', NAME, args)."""

    def __init__(self, text: str):
        if len(text) > _LONGEST:
            raise ValueError(f"an expression of {len(text):,} characters (at most {_LONGEST:,})")
        self.text = text
        self.tokens: list[tuple[str, str]] = []
        pos, end, brackets = 0, len(text.rstrip()), 0
        while pos < end:
            m = _TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                raise ValueError(f"expression {text!r}: unexpected character at {pos + 1}")
            self.tokens.append((m.lastgroup, m.group(m.lastgroup)))
            brackets += {"(": 1, ")": -1}.get(m.group(m.lastgroup), 0)
            if brackets > _DEEPEST_BRACKETS:
                raise self.error(f"brackets nested more than {_DEEPEST_BRACKETS} deep")
            pos = m.end()
        self.k = 0
        self.level = 0          # how many unary() calls are open: every recursion passes one

    def error(self, what: str) -> ValueError:
        return ValueError(f"expression {self.text!r}: {what}")

    def peek(self) -> tuple[str, str] | None:
        return self.tokens[self.k] if self.k < len(self.tokens) else None

    def is_op(self, *ops: str) -> bool:
        tok = self.peek()
        return tok is not None and tok[0] == "op" and tok[1] in ops

    def take(self, op: str | None = None) -> tuple[str, str]:
        tok = self.peek()
        if tok is None:
            raise self.error("unexpected end")
        if op is not None and tok != ("op", op):
            raise self.error(f"expected {op!r}, got {tok[1]!r}")
        self.k += 1
        return tok

    def parse(self) -> tuple:
        tree = self.compare()
        if self.peek() is not None:
            raise self.error(f"unexpected {self.peek()[1]!r}")
        if _depth(tree) > _DEEPEST:         # a sum of many terms: deep, read without recursion
            raise self.error(f"more than {_DEEPEST} operations nested")
        return tree

    def compare(self) -> tuple:
        tree = self.sum()
        if self.is_op(*_COMPARE_OPS):
            op = self.take()[1]
            tree = ("bin", op, tree, self.sum())
            if self.is_op(*_COMPARE_OPS):
                raise self.error("chained comparisons are not allowed")
        return tree

    def sum(self) -> tuple:
        tree = self.product()
        while self.is_op("+", "-"):
            op = self.take()[1]
            tree = ("bin", op, tree, self.product())
        return tree

    def product(self) -> tuple:
        tree = self.unary()
        while self.is_op("*", "/"):
            op = self.take()[1]
            tree = ("bin", op, tree, self.unary())
        return tree

    def unary(self) -> tuple:
        self.level += 1
        if self.level > _DEEPEST:
            raise self.error(f"more than {_DEEPEST} signs, brackets and powers nested")
        try:
            if self.is_op("-"):
                self.take()
                return ("neg", self.unary())
            if self.is_op("+"):
                self.take()
                return self.unary()
            return self.power()
        finally:
            self.level -= 1

    def power(self) -> tuple:
        tree = self.atom()
        if self.is_op("^", "**"):
            self.take()
            return ("bin", "^", tree, self.unary())
        return tree

    def atom(self) -> tuple:
        kind, text = self.take()
        if kind == "num":
            return ("num", float(text))
        if kind == "op":
            if text != "(":
                raise self.error(f"unexpected {text!r}")
            tree = self.compare()
            self.take(")")
            return tree
        if not self.is_op("("):
            return ("name", text)
        self.take()                       # a function call
        fn = _FUNCTIONS.get(text.upper())
        if fn is None:
            raise self.error(f"unknown function {text!r}")
        args: list[tuple] = []
        if not self.is_op(")"):
            args.append(self.compare())
            while self.is_op(","):
                self.take()
                args.append(self.compare())
        self.take(")")
        count = fn[0]
        if (len(args) != count) if count is not None else not args:
            raise self.error(f"{text.upper()} takes {count if count is not None else 'one or more'}"
                             f" argument(s), got {len(args)}")
        return ("call", text.upper(), tuple(args))


def _depth(tree: tuple) -> int:
    """How many operations deep a tree goes (a number or a name is 1), without recursion."""
    deepest, todo = 0, [(tree, 1)]
    while todo:
        node, depth = todo.pop()
        deepest = max(deepest, depth)
        kind = node[0]
        children = (node[1:] if kind == "neg" else node[2:] if kind == "bin"
                    else node[2] if kind == "call" else ())
        todo.extend((child, depth + 1) for child in children)
    return deepest


def _lookup(env: Mapping[str, object], name: str, text: str):
    if name in env:
        value = env[name]
    else:                                  # Excel names are case-insensitive
        matches = [k for k in env if isinstance(k, str) and k.lower() == name.lower()]
        if len(matches) != 1:
            raise ValueError(f"expression {text!r}: unknown name {name!r}")
        value = env[matches[0]]
    if isinstance(value, bool):
        raise ValueError(f"expression {text!r}: {name!r} is not a number: {value!r}")
    return np.asarray(value, dtype=float)


def _run(tree: tuple, env: Mapping[str, object], text: str):
    kind = tree[0]
    if kind == "num":
        return np.asarray(tree[1])
    if kind == "name":
        return _lookup(env, tree[1], text)
    if kind == "neg":
        return -_run(tree[1], env, text)
    if kind == "bin":
        return _binary(tree[1], _run(tree[2], env, text), _run(tree[3], env, text))
    return _FUNCTIONS[tree[1]][1](*(_run(a, env, text) for a in tree[2]))


def evaluate(expr: object, env: Mapping[str, object]):
    """Value of an expression of the mechanism language: a number, or text in Excel syntax
    (symbols, numbers, + - * / ^, comparisons, parentheses and SQRT ABS SIN COS TAN ASIN ACOS
    ATAN ATAN2(x, y) RADIANS DEGREES PI() MIN MAX IF IFERROR NA() AND OR NOT SIGN LN LOG10
    EXP) over env: {name: number or array}. A float when every name it uses is a number, else an
    array. A domain error (SQRT of a negative, a division by zero, ...) gives NaN, as Excel shows
    an error; a malformed expression or an unknown name raises ValueError."""
    if isinstance(expr, bool):
        raise ValueError(f"expected a number or an expression, got {expr!r}")
    if isinstance(expr, (int, float)):
        return float(expr)
    if not isinstance(expr, str) or not expr.strip():
        raise ValueError(f"expected a number or an expression, got {expr!r}")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        value = _run(_parsed(expr), env, expr)
    return float(value) if value.ndim == 0 else value


@functools.lru_cache(maxsize=1024)
def _parsed(expr: str) -> tuple:
    """The tree of an expression, read once: the reference evaluates each of a mechanism's
    expressions at every solve (a malformed one raises each time: nothing is kept of it)."""
    return _Parser(expr).parse()


def scalar(expr: object, params: Mapping[str, float]) -> float:
    """An expression of the parameters alone: a float."""
    value = evaluate(expr, params)
    if not isinstance(value, float):
        raise ValueError(f"expression {expr!r} must depend on the parameters alone")
    return value


def branch_sign(value: object, params: Mapping[str, float], what: str) -> int:
    """A branch or a side: an expression of the parameters whose value is 1 or -1."""
    b = scalar(value, params)
    if b not in (1.0, -1.0):
        raise ValueError(f"{what} must be 1 or -1, got {value!r} = {b!r}")
    return int(b)

