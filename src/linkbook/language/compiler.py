"""The mechanism language (docs/language.md): a mechanism described as data, compiled into the
model the workbook writer lays out, one step type of steps.py per step.

Every problem with a description raises InputError naming the step and the field, before any file
is touched. Nothing here touches openpyxl, and nothing here is used by the reference solver.
"""
from __future__ import annotations

import ast
import keyword
import math
import operator
import re
from dataclasses import dataclass
from fractions import Fraction

from .mechanisms import (ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, MOTION_SYMBOLS, OFFSET_KIND,
                         RATE_KIND, Mechanism, on_loop)
from .model import (ALIAS, COLUMN, CONSTANT, LENGTH, RAD, Block, Chart, FourBarLoop, Guide,
                    DescriptionError, Joint, Model, Quantity, _one_group, references)
from ..base.xlsx import excel_name_problem
from .schema import keys_of, schema, step_schemas
from .steps import (OUTSIDE_DOMAIN, Sym, angle_of_triangle_or_na, in_domain_or_na,
                    input_angle, offset_slide, polar, slider, triangle)

KINDS = (LENGTH_KIND, OFFSET_KIND, ANGLE_KIND, BRANCH_KIND)
_IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_POINT = re.compile(r"^[A-Za-z0-9_]+$")
RESERVED_KEYS = {"closes", "gap_from", "gap_to"}     # the sweep's bookkeeping columns


# ---------------------------------------------------------------- expressions
# Precedence of Excel text: a sum, a product, a negation, a power, an atom (name, number, call).
COMPARISON, SUM, PRODUCT, NEGATION, POWER, ATOM = range(6)
# name -> number of arguments (None: one or more)
FUNCTIONS = {"SQRT": 1, "ABS": 1, "SIN": 1, "COS": 1, "TAN": 1, "ASIN": 1, "ACOS": 1, "ATAN": 1,
             "ATAN2": 2, "RADIANS": 1, "DEGREES": 1, "PI": 0, "MIN": None, "MAX": None,
             "IF": 3, "IFERROR": 2, "NA": 0}
_COMPARE = {ast.Gt: ">", ast.GtE: ">=", ast.Lt: "<", ast.LtE: "<=", ast.Eq: "=", ast.NotEq: "<>"}


@dataclass(frozen=True)
class Expr:
    """Excel text with {symbol} placeholders, and how tightly it binds."""
    text: str
    rank: int = ATOM

    def at_least(self, rank: int) -> str:
        return self.text if self.rank >= rank else f"({self.text})"

    @property
    def zero(self) -> bool:
        return self.text == "0"


def number(value: float) -> Expr:
    text = repr(float(value)).upper()
    text = text[:-2] if text.endswith(".0") else text
    return Expr(text) if value >= 0 else Expr(text, NEGATION)


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
    try:
        tree = ast.parse(raw.replace("^", "**"), mode="eval")
    except SyntaxError:
        raise DescriptionError(field, f"is not an expression: {raw!r}") from None
    return _emit(field, tree.body, symbols)


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
        return _value(ast.parse(raw.replace("^", "**"), mode="eval").body, values)
    except _NotANumber:
        return math.nan
    except KeyError:
        return None


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
          "NA": _not_available}


# ---------------------------------------------------------------- dimensions (for --unit)
# The power of length each expression stands for: a parameter of kind length or offset, a
# length column, a linear actuator's length is 1, an angle or a ratio 0; a bare number takes
# the dimension its place gives it (a scale factor in a product, a length in a sum with one).
_ANGLE_FUNCTIONS = {"SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "RADIANS", "DEGREES"}


class _Dimensions:
    """Finds where an expression writes a length as a number (which a change of length unit
    cannot convert) or mixes a length with a number."""

    def __init__(self, dims: dict[str, int]):
        self.dims = dims
        self.problem: str | None = None

    def check(self, raw: object, want: int) -> str | None:
        if not isinstance(raw, str):
            raw = repr(raw)
        self.need(ast.parse(raw.replace("^", "**"), mode="eval").body, Fraction(want))
        return self.problem

    def _note(self, text: str) -> None:
        self.problem = self.problem or text

    def need(self, node: ast.AST, want: Fraction) -> None:
        got = self.dim(node)
        if got is None:
            if want != 0 and value_of(_source(node), {}) != 0:
                self._note(f"the number {_source(node)} is {_dimension_word(want)} here, which a "
                           "change of unit cannot convert; make it a parameter (a number in a "
                           "product, a ratio or an angle is fine)")
        elif got != want:
            self._note(f"{_source(node)} is {_dimension_word(got)}, where "
                       f"{_dimension_word(want)} belongs, so a change of unit would change "
                       "its meaning")

    def same(self, nodes: list) -> Fraction | None:
        """The one dimension of terms that are added, compared or chosen between."""
        dims = [self.dim(n) for n in nodes]
        known = {d for d in dims if d is not None}
        if len(known) > 1:
            self._note(f"{' and '.join(_source(n) for n in nodes)} mix a length with a number, "
                       "so a change of unit would change their meaning")
            return max(known)
        d = known.pop() if known else None
        if d:
            for n, nd in zip(nodes, dims):
                if nd is None:
                    self.need(n, d)
        return d

    def dim(self, node: ast.AST) -> Fraction | None:
        """The node's dimension, None for a bare number (or numbers alone)."""
        if isinstance(node, ast.Constant):
            return None
        if isinstance(node, ast.Name):
            return Fraction(self.dims.get(node.id, 0))
        if isinstance(node, ast.UnaryOp):
            return self.dim(node.operand)
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, (ast.Add, ast.Sub)):
                return self.same([node.left, node.right])
            if isinstance(node.op, ast.Pow):
                self.need(node.right, Fraction(0))
                base, power = self.dim(node.left), value_of(_source(node.right), {})
                if base is None or base == 0:
                    return base
                if power is None or power != power:
                    self._note(f"{_source(node)} raises a length to a power that is not a number")
                    return base
                return base * Fraction(power).limit_denominator(12)
            a, b = self.dim(node.left), self.dim(node.right)
            if a is None and b is None:
                return None
            a, b = a or Fraction(0), b or Fraction(0)
            return a + b if isinstance(node.op, ast.Mult) else a - b
        if isinstance(node, ast.Compare):
            self.same([node.left, *node.comparators])
            return Fraction(0)
        name = node.func.id.upper()
        args = node.args
        if name in _ANGLE_FUNCTIONS:
            for a in args:
                self.need(a, Fraction(0))
            return Fraction(0)
        if name == "ATAN2":
            self.same(args)
            return Fraction(0)
        if name == "SQRT":
            d = self.dim(args[0])
            return None if d is None else d / 2
        if name == "IF":
            self.dim(args[0])
            return self.same(args[1:])
        if name in ("ABS", "MIN", "MAX", "IFERROR"):
            return self.same(args)
        return None                                   # PI(), NA(): numbers


def _source(node: ast.AST) -> str:
    return ast.unparse(node).replace("**", "^")


def _dimension_word(d: Fraction) -> str:
    return {0: "a number (no length in it)", 1: "a length", 2: "an area"}.get(
        d, f"a length to the power {d}")


def unconvertible(mechanism: "Mechanism", model: Model) -> tuple[str, str] | None:
    """(field, why) of the first place a description writes a length as a number (or mixes
    a length with a number), so that a change of length unit could not convert it; None when
    every length is a parameter's."""
    description = mechanism.description or {}
    dims = {symbol: int(kind in (LENGTH_KIND, OFFSET_KIND))
            for symbol, kind in mechanism.parameters.items()}
    dims.update({s: 1 for s in MOTION_SYMBOLS[LENGTH_KIND]})
    dims.update({q.key: int(q.unit == LENGTH) for q in model.quantities})
    dims[mechanism.input_key] = int(not mechanism.input_is_angle)
    for name, xy in (description.get("ground") or {}).items():
        for i, raw in enumerate(xy):
            found = _Dimensions(dims).check(raw, 1)
            if found:
                return f"mechanism.ground.{name}[{i}]", found
    for i, step in enumerate(description.get("steps") or []):
        label = step.get("point") or step.get("key")
        field = f"mechanism.steps[{i}] ({step.get('type')} {label})"
        for k, raw in step.items():
            want = _STEP_DIMENSIONS.get(k)
            if k == "formula":
                want = int(step.get("unit") == "length")
            if want is None:
                continue
            for j, item in enumerate(raw if isinstance(raw, list) else [raw]):
                found = _Dimensions(dims).check(item, want)
                if found:
                    return f"{field}.{k}" + (f"[{j}]" if isinstance(raw, list) else ""), found
    return None


# The dimension of each step key that takes an expression: lengths 1, angles (degrees) 0
_STEP_DIMENSIONS = {"length": 1, "p_length": 1, "q_length": 1, "local": 1, "distances": 1,
                    "distance": 1, "offset": 1, "phase": 0, "angle": 0, "direction": 0,
                    "slot_angle": 0}


def radians(angle: Expr) -> Expr:
    """Degrees → radians in Excel text; −RADIANS(x) rather than RADIANS(−x)."""
    if angle.zero:
        return angle
    if angle.rank == NEGATION:
        return Expr(f"-RADIANS({angle.text[1:]})", NEGATION)
    return Expr(f"RADIANS({angle.text})")


def plus(a: Expr, term: str) -> str:
    """a + term (term a product or an atom, possibly with a leading minus)."""
    if a.zero:
        return term
    return f"{a.at_least(SUM)}{term}" if term.startswith("-") else f"{a.at_least(SUM)}+{term}"


def minus(a: Expr, b: Expr) -> Expr:
    if b.zero:
        return a
    if a.zero:
        return Expr(f"-{b.at_least(ATOM)}", NEGATION)
    return Expr(f"{a.at_least(SUM)}-{b.at_least(ATOM if b.rank == NEGATION else PRODUCT)}", SUM)


def key(name: str) -> Expr:
    return Expr(f"{{{name}}}")


def key_text(text: str) -> Expr:
    """A cosine or sine text from turned(): an atom, or the negation of one."""
    return Expr(text, NEGATION) if text.startswith("-") else Expr(text)


QUARTERS = {0: 0, 90: 1, 180: 2, 270: 3, -90: 3, -180: 2, -270: 1, 360: 0, -360: 0}


def turned(base: Expr | None, degrees: Expr) -> tuple[str, str]:
    """cos and sin of (base + degrees) as Excel text (base None: 0); a quarter turn is written
    exactly (cos(b + 90°) = −sin b), so a horizontal or vertical line carries no rounding."""
    c, s = ("1", "0") if base is None else (f"COS({base.text})", f"SIN({base.text})")
    try:
        quarter = QUARTERS.get(float(degrees.text.replace("(", "").replace(")", "")))
    except ValueError:
        quarter = None
    if quarter is None:
        angle = radians(degrees) if base is None else Expr(plus(base, radians(degrees).text), SUM)
        return f"COS({angle.text})", f"SIN({angle.text})"
    for _ in range(quarter):
        c, s = _neg(s), c
    return c, s


def _neg(text: str) -> str:
    return "0" if text == "0" else text[1:] if text.startswith("-") else f"-{text}"


def times(x: Expr, c: str) -> tuple[int, str] | None:
    """x·c as (sign, text of a product), or None when it is zero."""
    if c == "0" or x.zero:
        return None
    sign = -1 if c.startswith("-") else 1
    c = c.lstrip("-")
    if x.rank == NEGATION:
        sign, x = -sign, Expr(x.text[1:])
    if c == "1":
        return sign, x.at_least(PRODUCT)
    return sign, f"{x.at_least(PRODUCT)}*{c}"


def negate(term: tuple[int, str] | None) -> tuple[int, str] | None:
    return None if term is None else (-term[0], term[1])


def combine(terms: list) -> Expr:
    """A signed sum of product terms, zeros left out."""
    terms = [t for t in terms if t is not None]
    if not terms:
        return Expr("0")
    text = "".join(("-" if sign < 0 else "+" if i else "") + body
                   for i, (sign, body) in enumerate(terms))
    if len(terms) == 1:
        atom = _one_group(text) or re.fullmatch(r"\{\w+\}", text)
        return Expr(text, NEGATION if terms[0][0] < 0 else ATOM if atom else PRODUCT)
    return Expr(text, SUM)


# ---------------------------------------------------------------- the description
@dataclass(frozen=True)
class Column:
    """One column a step type writes: its name in `columns`, defaults, unit."""
    name: str
    key: str
    symbol: str
    label: str
    unit: str
    degrees: bool = False
    shown: bool = True


def polar_columns(n: str, a: str, b: str, degrees: bool = False) -> list[Column]:
    """The textbook's rectangular-to-polar columns of the vector a→b, keyed by `n`."""
    return [Column("xs", f"xs_{n}", f"xs_{n}", f"{a}→{b}, x", LENGTH),
            Column("ys", f"ys_{n}", f"ys_{n}", f"{a}→{b}, y", LENGTH),
            Column("s", f"s_{n}", f"s_{n}", f"|{a}{b}|", LENGTH),
            Column("phi", f"phi_{n}", f"ϕ_{n}", f"angle of {a}→{b}", RAD, degrees)]


# The keys each part of a description may have: the schema's (one source of truth)
COMMON_KEYS = {"type", "columns"}
STEP_KEYS = {kind: tuple(keys - COMMON_KEYS for keys in keys_of(part))
             for kind, part in step_schemas().items()}
UNITS = {"length": LENGTH, "rad": RAD, "-": "-"}
_MECHANISM = schema()["properties"]["mechanism"]
MECHANISM_KEYS = keys_of(_MECHANISM)
CHART_KEYS = keys_of(_MECHANISM["properties"]["charts"]["items"])


def _table(field: str, value: object) -> dict:
    if not isinstance(value, dict):
        raise DescriptionError(field, f"must be a table (got {value!r})")
    return value


def _text(field: str, value: object) -> str:
    if not isinstance(value, str) or not value.strip():
        raise DescriptionError(field, f"must be non-empty text (got {value!r})")
    return value


def _keys(field: str, table: dict, required: set, optional: set) -> None:
    for k in sorted(required):
        if k not in table:
            raise DescriptionError(f"{field}.{k}", "is missing")
    for k in table:
        if k not in required | optional:
            known = ", ".join(sorted(required | optional))
            raise DescriptionError(f"{field}.{k}", f"is not a key here; known: {known}")


class Compiler:
    """Walks a description once, in order, building the model and checking every reference."""

    def __init__(self, data: dict, kinds: dict[str, str], origin: str):
        self.origin = origin
        self.kinds = dict(kinds)
        self.symbols = set(kinds)
        self.model = Model()
        self.points: dict[str, tuple[Expr, Expr]] = {}
        self.ground: set[str] = set()
        self.crank_of: dict[str, str] = {}              # crank point -> its pivot
        self.rigid: dict[tuple[str, str], tuple[Expr | None, Expr]] = {}  # (A, B) -> |AB|, angle(A→B)
        self.cranks: list[dict] = []
        self.dyads: list[dict] = []
        self.input_kind = ANGLE_KIND
        self.swept: set[str] = set()     # the input key, where it is a length expressions use
        self.records: list[dict] = []    # per step what it placed, for motion.py
        self.lengths: list[tuple[str, object]] = []   # (field, expression) of every length
        self.traced = ""
        self.field = f"{origin}: mechanism"
        self.data = _table(self.field, data)

    # -- helpers
    @property
    def input_column(self) -> str:
        return f"{self.input_key}_deg" if self.input_kind == ANGLE_KIND else self.input_key

    def expr(self, field: str, raw: object) -> Expr:
        return expression(field, raw, self.symbols)

    def frame(self, field: str, raw: object, defining: str) -> tuple[str, str]:
        """[A, B]: two different known points (a link's frame)."""
        if not isinstance(raw, list) or len(raw) != 2:
            raise DescriptionError(field, f"must be [A, B], two known points (got {raw!r})")
        a = self.known_point(f"{field}[0]", raw[0], defining)
        b = self.known_point(f"{field}[1]", raw[1], defining)
        if a == b:
            raise DescriptionError(field, "needs two different points")
        return a, b

    def known_point(self, field: str, name: object, defining: str = "") -> str:
        if not isinstance(name, str):
            raise DescriptionError(field, f"must be a point name (got {name!r})")
        if name == defining:
            raise DescriptionError(field, f"{name!r} is the point this step defines (a cyclic "
                                          "definition)")
        if name not in self.points:
            steps = self.data.get("steps")
            later = isinstance(steps, list) and any(
                isinstance(s, dict) and s.get("point") == name for s in steps)
            why = "is defined by a later step" if later else "is not defined"
            raise DescriptionError(field, f"point {name!r} {why}; known so far: "
                                          f"{', '.join(self.points) or 'none'}")
        return name

    def branch(self, field: str, raw: object) -> str:
        """A branch: a parameter of kind branch, or the number 1 or −1 (an alias of it)."""
        if isinstance(raw, str) and raw in self.kinds:
            if self.kinds[raw] != BRANCH_KIND:
                raise DescriptionError(field, f"{raw!r} is a parameter of kind "
                                              f"{self.kinds[raw]}, not a branch")
            return raw
        if isinstance(raw, bool) or raw not in (1, -1):
            raise DescriptionError(field, f"must be 1, -1 or a branch parameter (got {raw!r})")
        name = "_plus_one" if raw == 1 else "_minus_one"   # no user symbol starts with _
        if not any(q.key == name for q in self.model.quantities):
            self.model.add(Quantity(name, str(int(raw)), "-", str(int(raw)), ALIAS))
        return name

    def operand(self, hint: str, e: Expr) -> str:
        """A key standing for an expression: the parameter itself, or an alias of the text (its
        key starts with _, which no user symbol or column key does)."""
        inner = e.text[1:-1]
        if e.text.startswith("{") and e.text.endswith("}") and inner in self.symbols:
            return inner
        self.model.add(Quantity(f"_{hint}", hint, LENGTH, e.text, ALIAS))
        return f"_{hint}"

    def length_operand(self, field: str, hint: str, e: Expr, raw: object) -> str:
        """A key standing for a length the loop is closed with. The template's value must be
        positive (checked at build: `self.lengths`); in the book, where the inputs make it zero
        or negative the loop cannot be assembled and the cells that use it are #N/A, as the
        reference says (a length parameter itself needs no guard: its cell refuses a
        non-positive value, and so does the swept input's)."""
        self.lengths.append((field, raw))
        inner = e.text[1:-1]
        bare = e.text.startswith("{") and e.text.endswith("}")
        if "{" not in e.text or bare and (self.kinds.get(inner) == LENGTH_KIND
                                          or inner in self.swept):
            return self.operand(hint, e)
        guarded = f"IF({e.at_least(SUM)}>0,{e.text},NA())"
        self.model.add(Quantity(f"_{hint}", hint, LENGTH, guarded, ALIAS))
        return f"_{hint}"

    def columns(self, field: str, step: dict, defaults: list[Column]) -> dict[str, Sym]:
        """The step's columns after its `columns` table renamed or hid them."""
        given = step.get("columns", {})
        given = _table(f"{field}.columns", given)
        names = {c.name for c in defaults}
        for name in given:
            if name not in names:
                raise DescriptionError(f"{field}.columns.{name}",
                                       f"this step writes no such column; it writes "
                                       f"{', '.join(c.name for c in defaults)}")
        out = {}
        for c in defaults:
            spec = given.get(c.name, {})
            where = f"{field}.columns.{c.name}"
            if spec is False:
                out[c.name] = Sym(c.key, c.symbol, c.label, shown=False)
                continue
            if spec is True:
                spec = {}
            spec = _table(where, spec)
            _keys(where, spec, set(), {"key", "symbol", "label", "degrees", "wrap", "shown"})
            k = self.new_key(f"{where}.key", spec.get("key", c.key))
            degrees, wrap = spec.get("degrees", c.degrees), spec.get("wrap", False)
            shown = spec.get("shown", True)
            for flag, v in (("degrees", degrees), ("wrap", wrap), ("shown", shown)):
                if not isinstance(v, bool):
                    raise DescriptionError(f"{where}.{flag}", "must be true or false")
            out[c.name] = Sym(k, _text(f"{where}.symbol", spec.get("symbol", c.symbol)),
                              _text(f"{where}.label", spec.get("label", c.label)),
                              deg=degrees and c.unit == RAD, wrap=wrap,
                              shown=shown and (c.shown or c.name in given))
        return out

    def new_key(self, field: str, k: object) -> str:
        """A column key: an identifier that no parameter, degree view or bookkeeping column has."""
        if not isinstance(k, str) or not _IDENT.match(k) or keyword.iskeyword(k):
            raise DescriptionError(field, f"must be letters, digits and _, starting with a "
                                          f"letter (got {k!r})")
        if k in self.symbols or k.endswith("_deg") or k in RESERVED_KEYS:
            raise DescriptionError(field, f"{k!r} is taken (a parameter, a degree view or a "
                                          "bookkeeping column)")
        return k

    def add_point(self, field: str, name: str, sx: Sym, sy: Sym, x: str, y: str) -> None:
        self.model.add(Quantity(sx.key, sx.symbol, LENGTH, x, COLUMN if sx.shown else ALIAS,
                                sx.label),
                       Quantity(sy.key, sy.symbol, LENGTH, y, COLUMN if sy.shown else ALIAS,
                                sy.label))
        self.points[name] = (key(sx.key), key(sy.key))

    def slides_on(self, n: str, kind: str, origin: str, direction: tuple[str, str],
                  travel: Sym) -> None:
        """The line a block of step `n` slides on, drawn over the block's travel: the sweep's
        column of its position along the line from `origin` (a hidden column: no guide)."""
        if travel.shown:
            ox, oy = self.points[origin]
            self.model.guides.append(Guide(n, kind, ox.text, oy.text, *direction, travel.key))

    def block(self, centre: str, direction: tuple[str, str]) -> None:
        """A block pivoted on the point `centre`, its long side along the line it slides on."""
        cx, cy = self.points[centre]
        self.model.blocks.append(Block(centre, cx.text, cy.text, *direction))

    def angle_of(self, a: str, b: str) -> Expr:
        """angle(A→B) as Excel text: a known link's angle column, or ATAN2 of the points."""
        if (a, b) in self.rigid:
            return self.rigid[(a, b)][1]
        if (b, a) in self.rigid:
            return Expr(f"{self.rigid[(b, a)][1].at_least(SUM)}+PI()", SUM)
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        return Expr(f"ATAN2({minus(bx, ax).text},{minus(by, ay).text})")

    def length_of(self, a: str, b: str) -> Expr:
        """|AB|: a known link's length, or the distance of the points."""
        for pair in ((a, b), (b, a)):
            if pair in self.rigid and self.rigid[pair][0] is not None:
                return self.rigid[pair][0]
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        dx, dy = minus(bx, ax), minus(by, ay)
        return Expr(f"SQRT({dx.at_least(ATOM)}^2+{dy.at_least(ATOM)}^2)")

    # -- the whole description
    def run(self) -> Model:
        d = self.data
        _keys(self.field, d, *MECHANISM_KEYS)
        self.read_input(d["input"])
        self.read_ground(d["ground"])
        steps = d["steps"]
        if not isinstance(steps, list) or not steps:
            raise DescriptionError(f"{self.field}.steps", "must be a non-empty list of steps")
        for i, step in enumerate(steps):
            self.read_step(i, step)
        self.read_presentation(d)
        from .motion import MotionWriter
        MotionWriter(self).run()
        return self.model

    def read_input(self, raw: object) -> None:
        field = f"{self.field}.input"
        table = _table(field, raw)
        _keys(field, table, {"key", "symbol"}, {"kind"})
        k = table["key"]
        if not isinstance(k, str) or not _IDENT.match(k) or k in self.symbols \
                or k.endswith("_deg"):
            raise DescriptionError(f"{field}.key", f"must be a new identifier not ending in _deg "
                                                   f"(got {k!r})")
        self.input_kind = table.get("kind", ANGLE_KIND)
        if self.input_kind not in (ANGLE_KIND, LENGTH_KIND):
            raise DescriptionError(f"{field}.kind", f"must be {ANGLE_KIND} (a crank's angle) or "
                                                    f"{LENGTH_KIND} (a linear actuator's length) "
                                                    f"(got {self.input_kind!r})")
        problem = excel_name_problem(f"{k}_now")
        if problem:
            raise DescriptionError(f"{field}.key", f"{k}_now (its Excel name) {problem}")
        self.input_key, self.input_symbol = k, _text(f"{field}.symbol", table["symbol"])
        if self.input_kind == ANGLE_KIND:
            input_angle(self.model, k, self.input_symbol)
        else:   # the swept length is the sweep's first column itself; a dyad's side may be it
            self.swept = {k}
        self.motion_symbols = MOTION_SYMBOLS[self.input_kind]
        for symbol in self.motion_symbols:    # the input's speed and acceleration
            self.kinds[symbol] = RATE_KIND
            self.symbols.add(symbol)

    def read_ground(self, raw: object) -> None:
        field = f"{self.field}.ground"
        table = _table(field, raw)
        if not table:
            raise DescriptionError(field, "needs at least one fixed point")
        for name, xy in table.items():
            where = f"{field}.{name}"
            self.check_new_point(where, name)
            if not isinstance(xy, list) or len(xy) != 2:
                raise DescriptionError(where, f"must be [x, y] (got {xy!r})")
            self.points[name] = (self.expr(f"{where}[0]", xy[0]), self.expr(f"{where}[1]", xy[1]))
            self.ground.add(name)

    def check_new_point(self, field: str, name: object) -> None:
        if not isinstance(name, str) or not _POINT.match(name):
            raise DescriptionError(field, f"a point name must be letters, digits and _ "
                                          f"(got {name!r})")
        if name in self.points:
            raise DescriptionError(field, f"point {name!r} is defined twice")

    def read_step(self, i: int, raw: object) -> None:
        field = f"{self.field}.steps[{i}]"
        step = _table(field, raw)
        kind = step.get("type")
        if kind not in STEP_KEYS:
            raise DescriptionError(f"{field}.type", f"must be one of {', '.join(STEP_KEYS)} "
                                                    f"(got {kind!r})")
        label = step.get("point") or step.get("key")
        field = f"{self.field}.steps[{i}] ({kind} {label})" if isinstance(label, str) else field
        self.step_name = f"{kind} {label}"
        required, optional = STEP_KEYS[kind]
        _keys(field, step, required, optional | COMMON_KEYS)
        if "point" in step:
            self.check_new_point(f"{field}.point", step["point"])
        try:
            getattr(self, f"step_{kind}")(field, step)
        except ValueError as exc:      # Model.add: a key defined twice
            raise DescriptionError(f"{field}.columns", str(exc)) from None

    # -- step types
    def step_crank(self, field: str, s: dict) -> None:
        name = s["point"]
        if self.input_kind != ANGLE_KIND:
            raise DescriptionError(f"{field}.type", "a crank turns with an angle input; this "
                                                    "mechanism's input is a length (a linear "
                                                    "actuator): use it as a dyad's p_length or "
                                                    "q_length")
        pivot = self.known_point(f"{field}.pivot", s["pivot"], name)
        length = self.expr(f"{field}.length", s["length"])
        self.lengths.append((f"{field}.length", s["length"]))
        phase = self.expr(f"{field}.phase", s.get("phase", 0))
        angle = key(self.input_key) if phase.zero else \
            Expr(f"{{{self.input_key}}}+{radians(phase).text}", SUM)
        cols = self.columns(field, s, [
            Column("x", f"x{name}", f"x{name}", f"x of {name}", LENGTH),
            Column("y", f"y{name}", f"y{name}", f"y of {name}", LENGTH)])
        px, py = self.points[pivot]
        r = length.at_least(PRODUCT)
        self.add_point(field, name, cols["x"], cols["y"],
                       plus(px, f"{r}*COS({angle.text})"), plus(py, f"{r}*SIN({angle.text})"))
        self.rigid[(pivot, name)] = (length, angle)
        self.crank_of[name] = pivot
        self.cranks.append({"point": name, "pivot": pivot, "length": length, "phase": phase})
        self.records.append({"type": "crank", "point": name, "pivot": pivot})

    def step_dyad(self, field: str, s: dict) -> None:
        name = s["point"]
        p = self.known_point(f"{field}.p", s["p"], name)
        q = self.known_point(f"{field}.q", s["q"], name)
        if p == q:
            raise DescriptionError(f"{field}.q", "must differ from p")
        # a linear actuator is a dyad side whose length is the swept input
        p_len = expression(f"{field}.p_length", s["p_length"], self.symbols | self.swept)
        q_len = expression(f"{field}.q_length", s["q_length"], self.symbols | self.swept)
        branch = self.branch(f"{field}.branch", s["branch"])
        n = name
        cols = self.columns(field, s, [
            *polar_columns(n, q, p),
            Column("psi", f"psi_{n}", f"ψ_{n}", f"∠{p}{q}{n}", RAD),
            Column("mu", f"mu_{n}", f"μ_{n}", f"transmission angle ∠{q}{n}{p}", RAD, True),
            Column("p_interior", f"p_interior_{n}", f"∠{q}{p}{n}", f"∠{q}{p}{n}", RAD,
                   shown=False),
            Column("theta_q", f"theta_q_{n}", f"θ({q}{n})", f"angle of {q}→{n}", RAD, True),
            Column("theta_p", f"theta_p_{n}", f"θ({p}{n})", f"angle of {p}→{n}", RAD, True),
            Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
            Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
        (px, py), (qx, qy) = self.points[p], self.points[q]
        polar(self.model, minus(px, qx).text, minus(py, qy).text,
              cols["xs"], cols["ys"], cols["s"], cols["phi"])
        p_key = self.length_operand(f"{field}.p_length", f"p_length_{n}", p_len, s["p_length"])
        q_key = self.length_operand(f"{field}.q_length", f"q_length_{n}", q_len, s["q_length"])
        # angle(P→R) from μ, or from the angle at P when μ is hidden and that angle is shown.
        use_p = not cols["mu"].shown and cols["p_interior"].shown
        triangle(self.model, side=cols["s"].key, angle=cols["phi"].key, p=p_key, q=q_key,
                 branch=branch, psi=cols["psi"], q_angle=cols["theta_q"],
                 mu=None if use_p else cols["mu"],
                 p_interior=cols["p_interior"] if use_p else None, p_angle=cols["theta_p"])
        if not use_p and cols["p_interior"].shown:
            raise DescriptionError(f"{field}.columns.p_interior",
                                   "is shown only in place of mu (set mu = false)")
        r = q_len.at_least(PRODUCT)
        theta_q = cols["theta_q"].key
        self.add_point(field, n, cols["x"], cols["y"],
                       plus(qx, f"{r}*COS({{{theta_q}}})"), plus(qy, f"{r}*SIN({{{theta_q}}})"))
        self.rigid[(q, n)] = (q_len, key(theta_q))
        self.rigid[(p, n)] = (p_len, key(cols["theta_p"].key))
        self.witness(field, cols, ("theta_p", "theta_q", "x", "y", "mu", "psi"))
        self.records.append({"type": "dyad", "field": field, "point": n, "p": p, "q": q,
                             "p_length": p_len, "q_length": q_len, "theta_q": cols["theta_q"],
                             "theta_p": cols["theta_p"]})
        self.dyads.append({"point": n, "p": p, "q": q, "p_length": p_len, "q_length": q_len,
                           "mu": cols["mu"]})

    def step_slider(self, field: str, s: dict) -> None:
        """RRP: R at `length` from P, on a line through `through` at `direction` — a fixed line,
        or, with `along = [U, V]`, a line carried by the link U→V (direction then measured from
        U→V)."""
        n = s["point"]
        p = self.known_point(f"{field}.p", s["p"], n)
        through = self.known_point(f"{field}.through", s["through"], n)
        along = self.frame(f"{field}.along", s["along"], n) if "along" in s else None
        if along is None and through not in self.ground:
            raise DescriptionError(f"{field}.through", f"{through!r} must be a fixed point (or "
                                                       "give the moving line's link as along)")
        length = self.expr(f"{field}.length", s["length"])
        direction = self.expr(f"{field}.direction", s.get("direction", 0))
        branch = self.branch(f"{field}.branch", s["branch"])
        moving_line = [Column("line", f"line_{n}", f"θ(line)_{n}",
                              f"slider line, angle along {'→'.join(along)}", RAD, True)] \
            if along else []
        cols = self.columns(field, s, [
            *moving_line,
            Column("theta", f"theta_{n}", f"θ({n}{p})", f"link, angle of {n}→{p}", RAD, True),
            Column("s", f"s_{n}", f"s_{n}", f"slider position along its line from {through}",
                   LENGTH),
            Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
            Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
        (px, py), (tx, ty) = self.points[p], self.points[through]
        dx, dy = minus(px, tx), minus(py, ty)
        length_key = self.length_operand(f"{field}.length", f"length_{n}", length, s["length"])
        pos = cols["s"].key
        if along:
            angle = self.angle_of(*along)
            if not direction.zero:
                angle = Expr(plus(angle, radians(direction).text), SUM)
            line = cols["line"]
            self.model.add(Quantity(line.key, line.symbol, RAD, angle.text,
                                    COLUMN if line.shown else ALIAS, line.label,
                                    in_degrees=line.deg and line.shown, wrap_360=line.wrap))
            d = f"{{{line.key}}}"
        elif direction.zero:
            slider(self.model, pin_x=dx.text, pin_y=dy.at_least(PRODUCT), line_y="0",
                   length=length_key,
                   branch=branch, angle=cols["theta"], position=cols["s"])
            x, y = plus(tx, f"{{{pos}}}"), on_loop(ty.text, pos)
        else:
            d = radians(direction).text
        if along or not direction.zero:
            u = f"{dx.at_least(PRODUCT)}*COS({d})+{dy.at_least(PRODUCT)}*SIN({d})"
            v = f"{dy.at_least(PRODUCT)}*COS({d})-{dx.at_least(PRODUCT)}*SIN({d})"
            slider(self.model, pin_x=f"({u})", pin_y=f"({v})", line_y="0", length=length_key,
                   branch=branch, angle=cols["theta"], position=cols["s"], direction=d)
            x = plus(tx, f"{{{pos}}}*COS({d})")
            y = plus(ty, f"{{{pos}}}*SIN({d})")
        self.add_point(field, n, cols["x"], cols["y"], x, y)
        self.rigid[(n, p)] = (length, key(cols["theta"].key))
        self.witness(field, cols, ("theta", "s", "x", "y"))
        line_dir = ((f"COS({d})", f"SIN({d})") if along or not direction.zero else ("1", "0"))
        self.slides_on(n, "guide", through, line_dir, cols["s"])
        self.block(n, line_dir)
        self.records.append({"type": "slider", "point": n, "p": p, "through": through,
                             "along": along, "line": cols.get("line"), "direction": line_dir,
                             "theta": cols["theta"], "s": cols["s"]})

    def step_slide(self, field: str, s: dict) -> None:
        n = s["point"]
        p = self.known_point(f"{field}.p", s["p"], n)
        pivot = self.known_point(f"{field}.pivot", s["pivot"], n)
        if p == pivot:
            raise DescriptionError(f"{field}.pivot", "must differ from p")
        offset = self.expr(f"{field}.offset", s["offset"])
        branch = self.branch(f"{field}.branch", s["branch"])
        cols = self.columns(field, s, [
            *polar_columns(n, pivot, p),
            Column("psi", f"psi_{n}", f"ψ_{n}", f"∠{p}{pivot}{n}", RAD),
            Column("travel", f"travel_{n}", f"|{n}{p}|", f"slide travel |{n}{p}|", LENGTH),
            Column("theta", f"theta_{n}", f"θ({pivot}{n})", f"link, angle of {pivot}→{n}", RAD,
                   True),
            Column("theta_slide", f"theta_slide_{n}", f"θ({n}{p})", f"slide, angle of {n}→{p}",
                   RAD, True),
            Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
            Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
        (px, py), (qx, qy) = self.points[p], self.points[pivot]
        polar(self.model, minus(px, qx).text, minus(py, qy).text,
              cols["xs"], cols["ys"], cols["s"], cols["phi"])
        offset_key = self.operand(f"offset_{n}", offset)
        offset_slide(self.model, p=cols["s"].key, angle=cols["phi"].key, offset=offset_key,
                     branch=branch, psi=cols["psi"], travel=cols["travel"],
                     link_angle=cols["theta"], slide_angle=cols["theta_slide"])
        r, t = offset.at_least(PRODUCT), cols["theta"].key
        self.add_point(field, n, cols["x"], cols["y"],
                       plus(qx, f"{r}*COS({{{t}}})"), plus(qy, f"{r}*SIN({{{t}}})"))
        self.rigid[(n, p)] = (None, key(cols["theta_slide"].key))
        self.witness(field, cols, ("theta", "travel", "x", "y", "psi"))
        slide = (f"COS({{{cols['theta_slide'].key}}})", f"SIN({{{cols['theta_slide'].key}}})")
        self.slides_on(n, "guide", n, slide, cols["travel"])
        self.block(p, slide)
        self.records.append({"type": "slide", "point": n, "p": p, "pivot": pivot,
                             "theta": cols["theta"], "theta_slide": cols["theta_slide"],
                             "travel": cols["travel"]})

    def step_point(self, field: str, s: dict) -> None:
        n = s["point"]
        a, b = self.frame(f"{field}.frame", s["frame"], n)
        forms = [k for k in ("local", "distances", "distance") if k in s]
        if len(forms) != 1:
            raise DescriptionError(field, "needs exactly one of local, distances or distance "
                                          f"(got {', '.join(forms) or 'none'})")
        form = forms[0]
        allowed = {"local": set(), "distances": {"side"}, "distance": {"angle"}}[form]
        for k in ("side", "angle"):
            if k in s and k not in allowed:
                raise DescriptionError(f"{field}.{k}", f"does not go with {form}")
        defaults = [Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
                    Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)]
        if form == "distances":
            defaults.insert(0, Column("gamma", f"gamma_{n}", f"γ_{n}", f"angle ∠{b}{a}{n}", RAD))
        if form == "distance":
            defaults.insert(0, Column("theta", f"theta_{n}", f"θ({a}{n})", f"angle of {a}→{n}",
                                      RAD, True, shown=False))
        cols = self.columns(field, s, defaults)
        ax, ay = self.points[a]
        base = self.angle_of(a, b)
        if form == "local":
            pair = s["local"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise DescriptionError(f"{field}.local", f"must be [u, v] (got {pair!r})")
            u = self.expr(f"{field}.local[0]", pair[0]).at_least(PRODUCT)
            v = self.expr(f"{field}.local[1]", pair[1]).at_least(PRODUCT)
            t = base.text
            x = plus(ax, f"{u}*COS({t})-{v}*SIN({t})")
            y = plus(ay, f"{u}*SIN({t})+{v}*COS({t})")
        else:
            if form == "distances":
                pair = s["distances"]
                if not isinstance(pair, list) or len(pair) != 2:
                    raise DescriptionError(f"{field}.distances", f"must be [|{a}{n}|, |{b}{n}|] "
                                                                 f"(got {pair!r})")
                da = self.expr(f"{field}.distances[0]", pair[0])
                db = self.expr(f"{field}.distances[1]", pair[1])
                side = self.branch(f"{field}.side", s.get("side", 1))
                ab = self.length_of(a, b)
                k_ab = self.operand(f"frame_length_{n}", ab)
                k_a, k_b = (self.length_operand(f"{field}.distances[{i}]", f"{h}_{n}", e, pair[i])
                            for i, (h, e) in enumerate((("distance_a", da), ("distance_b", db))))
                g = cols["gamma"]
                gamma = angle_of_triangle_or_na(k_ab, k_a, k_b, once=k_ab)
                self.model.add(Quantity(g.key, g.symbol, RAD, gamma, self.role(gamma, g),
                                        g.label))
                turn = f"+{{{g.key}}}" if side == "_plus_one" else \
                    f"-{{{g.key}}}" if side == "_minus_one" else f"+{{{side}}}*{{{g.key}}}"
                angle = f"{base.at_least(SUM)}{turn}"
                d = da.at_least(PRODUCT)
            else:
                da = self.expr(f"{field}.distance", s["distance"])
                self.lengths.append((f"{field}.distance", s["distance"]))
                offset = self.expr(f"{field}.angle", s.get("angle", 0))
                angle = base.text if offset.zero else plus(base, radians(offset).text)
                t = cols["theta"]
                self.model.add(Quantity(t.key, t.symbol, RAD, angle, self.role(angle, t),
                                        t.label, in_degrees=t.deg, wrap_360=t.wrap))
                angle = f"{{{t.key}}}"
                self.rigid[(a, n)] = (da, key(t.key))
                d = da.at_least(PRODUCT)
            x = plus(ax, f"{d}*COS({angle})")
            y = plus(ay, f"{d}*SIN({angle})")
        self.add_point(field, n, cols["x"], cols["y"], x, y)
        self.records.append({"type": "point", "point": n, "frame": (a, b), "form": form,
                             "theta": cols.get("theta")})

    def step_slot(self, field: str, s: dict) -> None:
        n = s["point"]
        e = self.known_point(f"{field}.slot_through", s["slot_through"], n)
        a, b = self.frame(f"{field}.slot_frame", s["slot_frame"], n)
        through = self.known_point(f"{field}.through", s["through"], n)
        if through not in self.ground:
            raise DescriptionError(f"{field}.through", f"{through!r} must be a fixed point")
        cols = self.columns(field, s, [
            Column("s_slot", f"s_slot_{n}", f"s_slot_{n}", f"{n} along the slot from {e}",
                   LENGTH),
            Column("s", f"s_{n}", f"s_{n}", f"{n} along its line from {through}", LENGTH),
            Column("x", f"x{n}", f"x{n}", f"x of {n}", LENGTH),
            Column("y", f"y{n}", f"y{n}", f"y of {n}", LENGTH)])
        uc, us = turned(self.angle_of(a, b), self.expr(f"{field}.slot_angle",
                                                       s.get("slot_angle", 0)))
        dc, ds = turned(None, self.expr(f"{field}.direction", s.get("direction", 0)))
        (ex, ey), (tx, ty) = self.points[e], self.points[through]
        wx, wy = minus(tx, ex), minus(ty, ey)
        # E + s_slot·û = T + s·d̂, solved by Cramer's rule; parallel lines (D = 0) are #N/A.
        det = combine([times(key_text(uc), ds), negate(times(key_text(us), dc))])
        for sym, terms in ((cols["s_slot"], [times(wx, ds), negate(times(wy, dc))]),
                           (cols["s"], [times(wx, us), negate(times(wy, uc))])):
            num = combine(terms)
            self.model.add(Quantity(sym.key, sym.symbol, LENGTH,
                                    f"IFERROR({num.at_least(PRODUCT)}/{det.at_least(POWER)},NA())",
                                    COLUMN if sym.shown else ALIAS, sym.label))
        pos = cols["s"].key
        x = on_loop(tx.text, pos) if dc == "0" else \
            combine([times(tx, "1"), times(key(pos), dc)]).text
        y = on_loop(ty.text, pos) if ds == "0" else \
            combine([times(ty, "1"), times(key(pos), ds)]).text
        self.add_point(field, n, cols["x"], cols["y"], x, y)
        self.witness(field, cols, ("s", "s_slot", "x", "y"))
        self.slides_on(n, "guide", through, (dc, ds), cols["s"])
        self.slides_on(n, "slot", e, (uc, us), cols["s_slot"])
        self.block(n, (dc, ds))
        self.records.append({"type": "slot", "point": n, "slot_through": e, "frame": (a, b),
                             "through": through, "slot_dir": (uc, us), "direction": (dc, ds),
                             "s_slot": cols["s_slot"], "s": cols["s"]})

    def step_expression(self, field: str, s: dict) -> None:
        k = self.new_key(f"{field}.key", s["key"])
        unit = s.get("unit", "-")
        if unit not in UNITS:
            raise DescriptionError(f"{field}.unit", f"must be one of {', '.join(UNITS)} "
                                                    f"(got {unit!r})")
        shown = s.get("shown", True)
        if not isinstance(shown, bool):
            raise DescriptionError(f"{field}.shown", "must be true or false")
        known = self.symbols | self.swept | {q.key for q in self.model.quantities}
        body = expression(f"{field}.formula", s["formula"], known)
        if "time_ratio_of" in s:
            of = s["time_ratio_of"]
            if not isinstance(of, str) or of not in {q.key for q in self.model.quantities}:
                raise DescriptionError(f"{field}.time_ratio_of",
                                       f"must be the key of an earlier column (got {of!r})")
        formula = f"IFERROR({body.text},NA())"
        sym = Sym(k, _text(f"{field}.symbol", s.get("symbol", k)),
                  _text(f"{field}.label", s.get("label", k)), shown=shown)
        role = self.role(formula, sym)
        if "time_ratio_of" in s and role != CONSTANT:
            raise DescriptionError(f"{field}.time_ratio_of", "a time ratio is one number per "
                                                             "book: the formula must be shown and "
                                                             "depend on the parameters alone")
        self.model.add(Quantity(k, sym.symbol, UNITS[unit], formula, role, sym.label))

    def role(self, formula: str, sym: Sym) -> str:
        """CONSTANT when a quantity depends on the parameters alone (one named cell)."""
        if not sym.shown:
            return ALIAS
        by_key = {q.key: q for q in self.model.quantities}

        def fixed(k: str) -> bool:
            if k in self.symbols:
                return True
            q = by_key.get(k)
            return q is not None and q.role in (ALIAS, CONSTANT) and \
                all(fixed(r) for r in references(q.formula))
        return CONSTANT if all(fixed(k) for k in references(formula)) else COLUMN

    def step_vector(self, field: str, s: dict) -> None:
        k = s["key"]
        if not isinstance(k, str) or not _IDENT.match(k):
            raise DescriptionError(f"{field}.key", f"must be an identifier (got {k!r})")
        a = self.known_point(f"{field}.from", s["from"])
        b = self.known_point(f"{field}.to", s["to"])
        if a == b:
            raise DescriptionError(f"{field}.to", "must differ from from")
        cols = self.columns(field, s, polar_columns(k, a, b, degrees=True))
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        polar(self.model, minus(bx, ax).text, minus(by, ay).text,
              cols["xs"], cols["ys"], cols["s"], cols["phi"])
        if (a, b) not in self.rigid and (b, a) not in self.rigid:
            self.rigid[(a, b)] = (None, key(cols["phi"].key))
        self.records.append({"type": "vector", "from": a, "to": b, "xs": cols["xs"],
                             "ys": cols["ys"], "length": cols["s"], "angle": cols["phi"]})

    def step_distance(self, field: str, s: dict) -> None:
        k = s["key"]
        pair = s["between"]
        if not isinstance(pair, list) or len(pair) != 2:
            raise DescriptionError(f"{field}.between", f"must be [A, B] (got {pair!r})")
        a = self.known_point(f"{field}.between[0]", pair[0])
        b = self.known_point(f"{field}.between[1]", pair[1])
        cols = self.columns(field, {k_: v for k_, v in s.items() if k_ == "columns"}, [
            Column("d", k, s.get("symbol", k), s.get("label", f"|{a}{b}|"), LENGTH)])
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        dx, dy = minus(bx, ax), minus(by, ay)
        d = cols["d"]
        self.model.add(Quantity(d.key, d.symbol, LENGTH,
                                f"SQRT({dx.at_least(ATOM)}^2+{dy.at_least(ATOM)}^2)",
                                COLUMN if d.shown else ALIAS, d.label))
        self.records.append({"type": "distance", "between": (a, b), "length": d})

    def witness(self, field: str, cols: dict[str, Sym], order: tuple[str, ...]) -> None:
        """A shown column of a loop step: a number exactly where this loop closes."""
        for name in order:
            if cols[name].shown:
                self.model.closes += (cols[name].key,)
                self.model.loop_steps += ((field, self.step_name),)
                return
        raise DescriptionError(f"{field}.columns", f"a loop step must show one of "
                                                   f"{', '.join(order)}")

    # -- drawing, outputs, charts
    def read_presentation(self, d: dict) -> None:
        m = self.model
        shown = {q.key: q for q in m.of_role(COLUMN)}
        links = d["links"]
        if not isinstance(links, list) or not links:
            raise DescriptionError(f"{self.field}.links", "must be a list of point lists")
        for i, link in enumerate(links):
            where = f"{self.field}.links[{i}]"
            if not isinstance(link, list) or len(link) < 2:
                raise DescriptionError(where, f"must list two or more points (got {link!r})")
            for j, name in enumerate(link):
                if not isinstance(name, str) or name not in self.points:
                    raise DescriptionError(f"{where}[{j}]", f"point {name!r} is not defined")
            m.links.append(tuple(link))
        used = list(dict.fromkeys(n for link in m.links for n in link))
        m.joints = [Joint(n, *(p.text for p in self.points[n])) for n in used]
        m.ground = tuple(n for n in used if n in self.ground)
        if "trace" in d:
            t = d["trace"]
            if not isinstance(t, str) or t not in self.points or t in self.ground:
                raise DescriptionError(f"{self.field}.trace", f"must be a moving point "
                                                              f"(got {t!r})")
            x, y = (e.text[1:-1] for e in self.points[t])
            if x not in shown or y not in shown:
                raise DescriptionError(f"{self.field}.trace", f"{t}'s coordinates must be "
                                                              "shown columns")
            m.path = (x, y)
            self.traced = t
        if "output" in d:
            out = d["output"]
            q = shown.get(out) if isinstance(out, str) else None
            if q is None or q.unit not in (LENGTH, RAD):
                raise DescriptionError(f"{self.field}.output", f"{out!r} is not a shown column "
                                                               "of a length or an angle")
            if q.unit == RAD and not q.in_degrees:
                # its smallest and largest value are read in its degree view, whose window
                # keeps the swing in one piece
                raise DescriptionError(f"{self.field}.output", f"the angle {out!r} needs its "
                                                               "degree view (degrees = true)")
            m.output = out
        m.transmissions = self.transmissions(d.get("transmission"), shown)
        m.fourbars = self.fourbar_loops()
        if "columns" in d:
            self.reorder(d["columns"])
        m.charts = self.charts(d.get("charts"), shown)

    def transmissions(self, given: object, shown: dict) -> tuple[str, ...]:
        """The transmission angles the summary reports: those named (a key or a list of keys of
        shown angle columns in [0, π]), by default μ of every dyad that shows it."""
        if given is None:
            return tuple(dy["mu"].key for dy in self.dyads if dy["mu"].shown)
        keys = [given] if isinstance(given, str) else given
        field = f"{self.field}.transmission"
        if not isinstance(keys, list):
            raise DescriptionError(field, "must be a column key or a list of them")
        for k in keys:
            if not isinstance(k, str) or k not in shown or shown[k].unit != RAD:
                # its smallest and largest value are read in radians: an angle in [0, π]
                raise DescriptionError(field, f"{k!r} is not a shown column of an angle")
        return tuple(keys)

    def fourbar_loops(self) -> tuple[FourBarLoop, ...]:
        """Every dyad with one end a ground point and the other the pin of a crank about a
        ground point: a four-bar loop on the ground, whose Grashof class and limit angles the
        summary reports.  The output link is the dyad's side at the ground point."""
        loops = []
        for dy in self.dyads:
            for pin, fixed, coupler, rocker in ((dy["p"], dy["q"], "p_length", "q_length"),
                                                (dy["q"], dy["p"], "q_length", "p_length")):
                pivot = self.crank_of.get(pin)
                if fixed in self.ground and pivot in self.ground:
                    loops.append(self.fourbar(pivot, pin, dy, fixed, coupler, rocker))
                    break
        return tuple(loops)

    def fourbar(self, pivot: str, pin: str, dy: dict, fixed: str, coupler: str,
                rocker: str) -> FourBarLoop:
        crank = next(c for c in self.cranks if c["point"] == pin)
        (ox, oy), (qx, qy) = self.points[pivot], self.points[fixed]
        dx, dy_ = minus(qx, ox), minus(qy, oy)
        ground = (f"ABS({dx.text})" if dy_.zero else f"ABS({dy_.text})" if dx.zero
                  else f"SQRT({dx.at_least(ATOM)}^2+{dy_.at_least(ATOM)}^2)")
        angle = f"ATAN2({dx.text},{dy_.text})"
        if not crank["phase"].zero:
            angle = f"{angle}-{radians(crank['phase']).at_least(PRODUCT)}"
        return FourBarLoop(ground, crank["length"].text, dy[coupler].text, dy[rocker].text,
                           angle, f"{pivot} {pin} {dy['point']} {fixed}")

    def reorder(self, order: object) -> None:
        field = f"{self.field}.columns"
        shown = [q.key for q in self.model.of_role(COLUMN) if q.key != self.input_key]
        if not isinstance(order, list) or sorted(order, key=str) != sorted(shown):
            missing = [k for k in shown if not isinstance(order, list) or k not in order]
            extra = [k for k in order if k not in shown] if isinstance(order, list) else []
            raise DescriptionError(field, "must list every shown column once"
                                   + (f"; missing {', '.join(missing)}" if missing else "")
                                   + (f"; unknown {', '.join(map(str, extra))}" if extra else ""))
        rank = {k: i for i, k in enumerate([self.input_key, *order])}
        qs = self.model.quantities
        columns = sorted((q for q in qs if q.role == COLUMN), key=lambda q: rank[q.key])
        it = iter(columns)
        self.model.quantities = [next(it) if q.role == COLUMN else q for q in qs]

    def charts(self, raw: object, shown: dict) -> list[Chart]:
        field = f"{self.field}.charts"
        symbol_of = {**{k: q.symbol for k, q in shown.items()},
                     **{f"{k}_deg": q.symbol for k, q in shown.items() if q.in_degrees},
                     self.input_column: self.input_symbol}
        if raw is None:
            return self.default_charts(shown)
        if not isinstance(raw, list):
            raise DescriptionError(field, "must be a list of charts")
        out = []
        for i, c in enumerate(raw):
            where = f"{field}[{i}]"
            c = _table(where, c)
            _keys(where, c, *CHART_KEYS)
            ys = c["y"] if isinstance(c["y"], list) else [c["y"]]
            if not ys:
                raise DescriptionError(f"{where}.y", "must name at least one column to plot")
            for k in [c["x"], *ys]:
                if not isinstance(k, str) or k not in symbol_of:
                    raise DescriptionError(where, f"{k!r} is not a column; columns are "
                                                  f"{', '.join(symbol_of)}")
            x_title = c.get("x_title", symbol_of[c["x"]])
            y_title = c.get("y_title", ", ".join(symbol_of[k] for k in ys))
            out.append(Chart(_text(f"{where}.title", c["title"]), c["x"], tuple(ys),
                             _text(f"{where}.x_title", x_title),
                             _text(f"{where}.y_title", y_title),
                             bool(c.get("equal_axes", False))))
        return out

    def default_charts(self, shown: dict) -> list[Chart]:
        """Without charts in the description: every degree column against the input angle, and
        the traced point's path."""
        degs = tuple(f"{k}_deg" for k, q in shown.items() if q.in_degrees)
        charts = []
        if degs:
            charts.append(Chart("Link angles", self.input_column, degs, self.input_symbol,
                                "angle [deg]"))
        if self.model.path:
            px, py = self.model.path
            charts.append(Chart(f"Path of {px[1:]}", px, (py,), px, py, equal_axes=True))
        return charts


def parameter_kinds(origin: str, table: dict, defaults: dict[str, str] | None = None
                    ) -> dict[str, str]:
    """Each parameter's kind: `kind` of its entry, else its default (an older template's symbol
    takes the bundled template's kind), else a length."""
    defaults = defaults or {}
    kinds = {}
    for symbol, entry in table.items():
        field = f"{origin}: parameters.{symbol}"
        if not _IDENT.match(symbol) or keyword.iskeyword(symbol):
            raise DescriptionError(field, "a symbol must be letters, digits and _, starting with "
                                          "a letter")
        kind = defaults.get(symbol, LENGTH_KIND)
        kind = entry.get("kind", kind) if isinstance(entry, dict) else kind
        if kind not in KINDS:
            raise DescriptionError(f"{field}.kind", f"must be one of {', '.join(KINDS)} "
                                                    f"(got {kind!r})")
        kinds[symbol] = kind
    return kinds


def compile_mechanism(name: str, data: dict, kinds: dict[str, str], origin: str,
                      grid: tuple[str, str] | None = None) -> Mechanism:
    """The Mechanism a described template builds, checked through (DescriptionError)."""
    c = Compiler(data, kinds, origin)
    model = c.run()
    if grid is not None:
        if c.input_kind != ANGLE_KIND:
            raise DescriptionError(f"{origin}: grid", "a grid sweeps a crank turn; this "
                                                      "mechanism's input is a length")
        param, out = grid
        if param not in kinds:
            raise DescriptionError(f"{origin}: grid.parameter", f"{param!r} is not a parameter")
        if out not in {q.key for q in model.of_role(COLUMN)}:
            raise DescriptionError(f"{origin}: grid.output", f"{out!r} is not a shown column")
    return Mechanism(name, dict(c.kinds), c.input_key, c.input_symbol, lambda: model, grid,
                     description=data, input_kind=c.input_kind, lengths=tuple(c.lengths))
