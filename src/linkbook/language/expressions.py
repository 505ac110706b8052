"""The description's expressions: a number, or Excel-like text of parameter symbols, turned into
Excel text with explicit precedence (expression), and read back as the number it stands for
(value_of). Every problem raises DescriptionError naming the field.
"""
from __future__ import annotations

import ast
import math
import operator
import re

from ..base.xlsx import NUMBER_LITERAL, bracket_depth
from .excel import ATOM, COMPARISON, NEGATION, OUTSIDE_DOMAIN, POWER, PRODUCT, SUM, Expr, \
    in_domain_or_na, number
from .model import DescriptionError

# name -> number of arguments (None: one or more)
FUNCTIONS = {"SQRT": 1, "ABS": 1, "SIN": 1, "COS": 1, "TAN": 1, "ASIN": 1, "ACOS": 1, "ATAN": 1,
             "ATAN2": 2, "RADIANS": 1, "DEGREES": 1, "PI": 0, "MIN": None, "MAX": None,
             "IF": 3, "IFERROR": 2, "NA": 0, "AND": None, "OR": None, "NOT": 1, "SIGN": 1,
             "LN": 1, "LOG10": 1, "EXP": 1}
# the functions whose value is TRUE or FALSE, as a comparison's
LOGICAL = ("AND", "OR", "NOT")
_COMPARE = {ast.Gt: ">", ast.GtE: ">=", ast.Lt: "<", ast.LtE: "<=", ast.Eq: "=", ast.NotEq: "<>"}
# What an expression may be (docs/language.md): the readers of an expression — Python's parser,
# the writer here, the reference's reader — recurse once per level, so a text of thousands of
# signs or terms would exhaust the stack. The bundled templates' longest is 191 characters and
# 10 levels deep.
LENGTH_LIMIT = 1000
DEPTH_LIMIT = 64        # levels: brackets inside brackets, or operations inside operations


def _finite(field: str, value: int | float) -> Expr:
    """A number the description writes, refused when no double holds it (an integer of hundreds
    of digits, 1e999)."""
    try:
        if math.isfinite(float(value)):
            return number(value)
    except OverflowError:
        pass
    shown = f"an integer of {len(str(abs(value)))} digits" if isinstance(value, int) else value
    raise DescriptionError(field, f"must be a finite number (got {shown})")


def expression(field: str, raw: object, symbols: set[str]) -> Expr:
    """A number, or Excel-like text of parameter symbols, + - * / ^, parentheses and a few
    functions, turned into Excel text with explicit precedence (−a^2 is −(a^2), as in algebra;
    Excel alone would square −a)."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        raise DescriptionError(field, f"must be a number or an expression (got {raw!r})")
    if not isinstance(raw, str):
        return _finite(field, raw)
    tree = parsed(field, raw)
    _check_spelling(field, raw.replace("^", "**"), tree)
    return _emit(field, tree, symbols)


def parsed(field: str, text: str) -> ast.expr:
    """The syntax tree of an expression's text, once it is known to be within LENGTH_LIMIT
    and DEPTH_LIMIT (its brackets, and its operations, each nested at most so deep)."""
    if len(text) > LENGTH_LIMIT:
        raise DescriptionError(field, f"is {len(text):,} characters long; an expression may "
                                      f"have at most {LENGTH_LIMIT:,}")
    brackets = bracket_depth(text)
    if brackets > DEPTH_LIMIT:
        raise _too_deep(field, f"{brackets} brackets")
    try:
        tree = ast.parse(text.replace("^", "**"), mode="eval").body
    except SyntaxError:
        raise DescriptionError(field, f"is not an expression: {text!r}") from None
    except (RecursionError, MemoryError):     # Python's own parser, on thousands of levels
        raise _too_deep(field, "thousands of operations") from None
    depth = _depth(tree)
    if depth > DEPTH_LIMIT:
        raise _too_deep(field, f"{depth} operations")
    return tree


def _too_deep(field: str, what: str) -> DescriptionError:
    return DescriptionError(field, f"nests {what} inside each other (a sign, a term of a sum "
                                   f"or a bracket is one level); at most {DEPTH_LIMIT}")


def _depth(tree: ast.expr) -> int:
    """How many operations deep the tree goes (a name or a number is 1), without recursion."""
    deepest, todo = 0, [(tree, 1)]
    while todo:
        node, depth = todo.pop()
        deepest = max(deepest, depth)
        todo.extend((child, depth + 1) for child in ast.iter_child_nodes(node)
                    if isinstance(child, ast.expr))
    return deepest


_NUMBER_LITERAL = re.compile(NUMBER_LITERAL)


def _check_spelling(field: str, source: str, tree: ast.AST) -> None:
    """Numbers and symbols spelt as verify's reference reads them: Python also reads 1_000,
    0x10 and (by NFKC) a full-width symbol, which the reference refuses or reads otherwise."""
    for node in ast.walk(tree):
        if not isinstance(node, (ast.Constant, ast.Name)):
            continue
        text = ast.get_source_segment(source, node)
        if isinstance(node, ast.Name) and text != node.id:
            raise DescriptionError(field, f"{text!r} is not a symbol: ASCII letters, digits and "
                                          "_ only")
        if isinstance(node, ast.Constant) and type(node.value) in (int, float, complex) \
                and not _NUMBER_LITERAL.fullmatch(text or ""):
            raise DescriptionError(field, f"{text!r} is not a number as a formula writes one "
                                          "(digits, one point, an exponent: 1000, 0.5, 2.5e3)")


_BINARY = {ast.Add: ("+", SUM), ast.Sub: ("-", SUM), ast.Mult: ("*", PRODUCT),
           ast.Div: ("/", PRODUCT), ast.Pow: ("^", POWER)}


def _emit(field: str, node: ast.AST, symbols: set[str]) -> Expr:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
            and not isinstance(node.value, bool):
        return _finite(field, node.value)
    if isinstance(node, ast.Name):
        if node.id not in symbols:
            raise DescriptionError(field, f"unknown symbol {node.id!r}; parameters are "
                                          f"{', '.join(sorted(symbols))}")
        return Expr(f"{{{node.id}}}")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _emit(field, node.operand, symbols)
        if isinstance(node.op, ast.UAdd):
            return inner
        return Expr(f"-{inner.at_least(ATOM)}", NEGATION)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        sign, rank = _BINARY[type(node.op)]
        left, right = _emit(field, node.left, symbols), _emit(field, node.right, symbols)
        if rank == POWER:    # both sides atoms: Excel's ^ is left-associative, algebra's is not
            return Expr(f"{left.at_least(ATOM)}^{right.at_least(ATOM)}", POWER)
        need = ATOM if right.rank == NEGATION else rank + (sign in "-/")
        return Expr(f"{left.at_least(rank)}{sign}{right.at_least(need)}", rank)
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _COMPARE:
        left = _emit(field, node.left, symbols)
        right = _emit(field, node.comparators[0], symbols)
        return Expr(f"{left.at_least(SUM)}{_COMPARE[type(node.ops[0])]}{right.at_least(SUM)}",
                    COMPARISON)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        name = node.func.id.upper()
        if name not in FUNCTIONS:
            raise DescriptionError(field, f"unknown function {node.func.id}(); known: "
                                          f"{', '.join(FUNCTIONS)}")
        count = FUNCTIONS[name]
        if (len(node.args) != count) if count is not None else not node.args:
            raise DescriptionError(field, f"{name}() takes "
                                          f"{count if count is not None else 'one or more'} "
                                          "argument(s)")
        args = [_emit(field, a, symbols) for a in node.args]
        if name in OUTSIDE_DOMAIN:    # ACOS(2): an error in most applications, NaN in IronCalc
            return Expr(in_domain_or_na(name, args[0].at_least(SUM)))
        return Expr(f"{name}({','.join(a.text for a in args)})")
    raise DescriptionError(field, "may hold only numbers, symbols, + - * / ^, comparisons, "
                                  "parentheses and " + ", ".join(FUNCTIONS))


class _NotANumber(Exception):
    """An expression's value is an error (#N/A, a domain error, a division by zero)."""


def value_of(raw: object, values: dict[str, float]) -> float | None:
    """The number an expression of parameters stands for with these values: NaN where its
    value is an error, None where it names something else (the swept input, a column). The
    grammar is expression()'s; the arithmetic Excel's."""
    if not isinstance(raw, str):
        return float(raw)
    try:
        return _value(parsed("expression", raw), values)
    except _NotANumber:
        return math.nan
    except KeyError:
        return None


def always_an_error(raw: object, values: dict[str, float]) -> bool:
    """Whether an expression is an error value (#N/A, #DIV/0!, #NUM!) with these parameter
    values whatever the columns it names hold: on every row of the book (NA(), 1/0, a2*NA(),
    xA/0)."""
    if not isinstance(raw, str):
        return False
    return _always(parsed("expression", raw), values)


def _always(node: ast.AST, values: dict[str, float]) -> bool:
    try:
        _value(node, values)
        return False
    except _NotANumber:
        return True
    except KeyError:        # it names a column: an error only where a part is one regardless
        pass
    if isinstance(node, ast.Call):
        name, args = node.func.id.upper(), node.args
        if name == "IFERROR":
            return _always(args[0], values) and _always(args[1], values)
        if name == "IF":
            return _always(args[0], values) or all(_always(a, values) for a in args[1:])
        return any(_always(a, values) for a in args)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and _zero(node.right, values):
        return True
    parts = [node.operand] if isinstance(node, ast.UnaryOp) else \
        [node.left, node.right] if isinstance(node, ast.BinOp) else \
        [node.left, *node.comparators] if isinstance(node, ast.Compare) else []
    return any(_always(p, values) for p in parts)


def _zero(node: ast.AST, values: dict[str, float]) -> bool:
    try:
        return _value(node, values) == 0
    except (_NotANumber, KeyError):
        return False


def is_comparison(raw: object) -> bool:
    """Whether an expression's value is TRUE or FALSE (a comparison, AND, OR or NOT outside any
    other function), which the book's sums would read otherwise than the reference."""
    if not isinstance(raw, str):
        return False
    tree = parsed("expression", raw)
    return isinstance(tree, ast.Compare) or isinstance(tree, ast.Call) and \
        isinstance(tree.func, ast.Name) and tree.func.id.upper() in LOGICAL


def _value(node: ast.AST, values: dict[str, float]) -> float:
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return values[node.id]
    if isinstance(node, ast.UnaryOp):
        inner = _value(node.operand, values)
        return -inner if isinstance(node.op, ast.USub) else inner
    if isinstance(node, ast.BinOp):
        a, b = _value(node.left, values), _value(node.right, values)
        return _checked(lambda: _ARITHMETIC[type(node.op)](a, b))
    if isinstance(node, ast.Compare):
        a, b = _value(node.left, values), _value(node.comparators[0], values)
        return float(_ORDER[type(node.ops[0])](a, b))
    name = node.func.id.upper()
    if name == "IF":
        test = _value(node.args[0], values)
        return _value(node.args[1 if test else 2], values)
    if name == "IFERROR":
        try:
            return _value(node.args[0], values)
        except _NotANumber:
            return _value(node.args[1], values)
    args = [_value(a, values) for a in node.args]
    return _checked(lambda: _EXCEL[name](*args))


def _checked(compute) -> float:
    try:
        result = float(compute())
    except (ValueError, ZeroDivisionError, OverflowError, TypeError):   # TypeError: complex
        raise _NotANumber from None
    if not math.isfinite(result):
        raise _NotANumber
    return result


def _not_available() -> float:
    raise _NotANumber


_ARITHMETIC = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
               ast.Div: operator.truediv, ast.Pow: operator.pow}
_ORDER = {ast.Gt: operator.gt, ast.GtE: operator.ge, ast.Lt: operator.lt, ast.LtE: operator.le,
          ast.Eq: operator.eq, ast.NotEq: operator.ne}
_EXCEL = {"SQRT": math.sqrt, "ABS": abs, "SIN": math.sin, "COS": math.cos, "TAN": math.tan,
          "ASIN": math.asin, "ACOS": math.acos, "ATAN": math.atan,
          "ATAN2": lambda x, y: math.atan2(y, x), "RADIANS": math.radians,
          "DEGREES": math.degrees, "PI": lambda: math.pi, "MIN": min, "MAX": max,
          "NA": _not_available, "SIGN": lambda x: float((x > 0) - (x < 0)),
          "AND": lambda *a: all(a), "OR": lambda *a: any(a), "NOT": lambda x: not x,
          "LN": math.log, "LOG10": math.log10, "EXP": math.exp}
