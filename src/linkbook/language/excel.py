"""Excel formula text, written and read: the pieces every formula writer of the language shares.

Formulas are Excel text with `{key}` placeholders for other quantities and parameters; a
quantity's formula is rendered into a cell's text where it lands (model.Resolver). Three kinds of
helper write such text, each keeping the text as short as the meaning allows:

- position formulas build `Expr`s, text that knows how tightly it binds, so that brackets appear
  only where Excel's precedence needs them (−RADIANS(x), not RADIANS(−x); a quarter turn exact);
- rate formulas (velocity, acceleration) join plain text with `mul`, `lin`, `dot`, `cross`,
  dropping terms that are zero by construction, and divide only through `guard` (#N/A at a
  dead centre, never #DIV/0!);
- domain guards: an ACOS/ASIN whose argument leaves [-1, 1] means the loop cannot close, so it
  becomes #N/A (never #NUM!, never a clamped wrong number), and #N/A then propagates to every
  cell that depends on it. The argument's domain is tested before the function is called, not
  caught after: spreadsheet applications do not agree on what ACOS(2) is (an error in Excel,
  LibreOffice and Gnumeric, a NaN that reads as 0 in IronCalc).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

# ---------------------------------------------------------------- placeholders
# {key@above}: the key's cell in the row above (a sweep's continuation; NA() elsewhere)
PLACEHOLDER = re.compile(r"\{(\w+(?:@above)?)\}")


def references(formula: str) -> list[str]:
    """The keys a formula mentions, in order of first use."""
    return list(dict.fromkeys(PLACEHOLDER.findall(formula)))


def render(formula: str, resolve: Callable[[str], str]) -> str:
    """Replace every {key} by the text `resolve(key)` gives for it."""
    return PLACEHOLDER.sub(lambda m: resolve(m.group(1)), formula)


_SIMPLE = re.compile(r"^(\$?[A-Za-z_][\w.]*\$?\d*|[\d.]+(E[+-]?\d+)?|'[^']+'!\$?[A-Z]+\$?\d+)$")


def parenthesize(text: str) -> str:
    """Wrap an inlined expression unless it is a single name, reference or number."""
    if _SIMPLE.match(text) or one_group(text):
        return text
    return f"({text})"


_CALL = re.compile(r"^[A-Z][A-Z0-9.]*(?=\()")


def one_group(text: str) -> bool:
    """True for '(a+b)' or 'COS(a+b)': one bracket group or call spanning the whole text."""
    call = _CALL.match(text)
    start = call.end() if call else 0
    if not text[start:].startswith("("):
        return False
    depth = 0
    for i in range(start, len(text)):
        depth += text[i] == "("
        depth -= text[i] == ")"
        if depth == 0:
            return i == len(text) - 1
    return False


# ---------------------------------------------------------------- position text
# Precedence of Excel text: a sum, a product, a negation, a power, an atom (name, number, call).
COMPARISON, SUM, PRODUCT, NEGATION, POWER, ATOM = range(6)


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


def local_point(origin: tuple[Expr, Expr], u: Expr, v: Expr, angle: str) -> tuple[str, str]:
    """x, y of origin + u·ê + v·ê⊥, ê the unit vector at `angle` (radians, Excel text) and ê⊥
    it turned +90°: a point by local coordinates [u, v]. A coordinate that is zero by
    construction drops its terms (local = [u, 0] gives A + u·COS, no -0*SIN)."""
    uu, vv = u.at_least(PRODUCT), v.at_least(PRODUCT)
    x = ("" if u.zero else f"{uu}*COS({angle})") + ("" if v.zero else f"-{vv}*SIN({angle})")
    y = ("" if u.zero else f"{uu}*SIN({angle})") + ("" if v.zero else f"+{vv}*COS({angle})")
    return tuple(plus(a, term.removeprefix("+")) if term else a.text
                 for a, term in zip(origin, (x, y)))


def minus(a: Expr, b: Expr) -> Expr:
    if b.zero:
        return a
    if a.zero:
        return Expr(f"-{b.at_least(ATOM)}", NEGATION)
    return Expr(f"{a.at_least(SUM)}-{b.at_least(ATOM if b.rank == NEGATION else PRODUCT)}", SUM)


def direction(dx: Expr, dy: Expr) -> Expr:
    """The angle of the vector (dx, dy), ATAN2 (Excel's takes x first), #N/A where both are
    zero: two points at one place give no direction, and ATAN2(0, 0) is #DIV/0! in Excel and
    Gnumeric but 0 in LibreOffice. Every frame's and vector's angle is written here."""
    atan = f"ATAN2({dx.text},{dy.text})"
    if any(_nonzero_number(d) for d in (dx, dy)):
        return Expr(atan)
    tests = [f"{d.text}=0" for d in (dx, dy) if not d.zero]
    if not tests:
        return Expr("NA()")
    test = tests[0] if len(tests) == 1 else f"AND({tests[0]},{tests[1]})"
    return Expr(f"IF({test},NA(),{atan})")


_GUARDED_ATAN2 = re.compile(r"^IF\((?:AND\()?.*,NA\(\),(ATAN2\(.*\))\)$")


def is_direction(formula: str) -> bool:
    """Whether a formula is one angle of a vector as direction() writes it."""
    guarded = _GUARDED_ATAN2.match(formula)
    atan = guarded.group(1) if guarded else formula
    return atan.startswith("ATAN2(") and one_group(atan)


def _nonzero_number(e: Expr) -> bool:
    try:
        return float(e.text.replace("(", "").replace(")", "")) != 0
    except ValueError:
        return False


def key(name: str) -> Expr:
    return Expr(f"{{{name}}}")


def key_text(text: str) -> Expr:
    """A cosine or sine text from turned(): an atom, or the negation of one."""
    return Expr(text, NEGATION) if text.startswith("-") else Expr(text)


def quarters(degrees: Expr) -> int | None:
    """How many quarter turns a number of degrees is (0 to 3), or None: not a number, or not a
    whole number of quarter turns."""
    try:
        value = float(degrees.text.replace("(", "").replace(")", ""))
    except ValueError:
        return None
    return int(value // 90) % 4 if value % 90 == 0 else None


def turned(base: Expr | None, degrees: Expr) -> tuple[str, str]:
    """cos and sin of (base + degrees) as Excel text (base None: 0); a quarter turn is written
    exactly (cos(b + 90°) = −sin b), so a horizontal or vertical line carries no rounding."""
    c, s = ("1", "0") if base is None else (f"COS({base.text})", f"SIN({base.text})")
    quarter = quarters(degrees)
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
        atom = one_group(text) or re.fullmatch(r"\{\w+\}", text)
        return Expr(text, NEGATION if terms[0][0] < 0 else ATOM if atom else PRODUCT)
    return Expr(text, SUM)


# ---------------------------------------------------------------- rate text
ZERO = "0"


def _p(text: str) -> str:
    """Parenthesized unless an atom: a key, a number, or one call or bracket group."""
    if text.startswith("{") and text.endswith("}") and text.count("{") == 1:
        return text
    if text.replace(".", "", 1).isdigit() or one_group(text):
        return text
    return f"({text})"


def mul(*factors: str) -> str:
    if any(f == ZERO for f in factors):
        return ZERO
    kept = [f for f in factors if f != "1"]
    return "*".join(_p(f) for f in kept) if kept else "1"


def lin(*terms: tuple[int, str]) -> str:
    """A sum of signed terms (sign ±1, text), zeros dropped."""
    out = ""
    for sign, text in terms:
        if text == ZERO:
            continue
        if sign > 0:
            out += text if not out else "+" + (_p(text) if text.startswith("-") else text)
        else:
            out += "-" + _p(text)
    return out or ZERO


def guard(den: str, num: str) -> str:
    """num/den, #N/A where den is exactly zero (a dead centre) or #N/A (the loop cannot close)
    — never #DIV/0!; a numerator that is zero by construction still keeps that #N/A."""
    if num == ZERO:
        return f"IF({den}=0,NA(),0)"
    return f"IF({den}=0,NA(),{_p(num)}/{_p(den)})"


def sq(text: str) -> str:
    return ZERO if text == ZERO else f"{_p(text)}^2"


def dot(a: tuple[str, str], b: tuple[str, str]) -> str:
    return lin((1, mul(a[0], b[0])), (1, mul(a[1], b[1])))


def cross(a: tuple[str, str], b: tuple[str, str]) -> str:
    return lin((1, mul(a[0], b[1])), (-1, mul(a[1], b[0])))


# ---------------------------------------------------------------- domain guards
# Where a function is undefined, as Excel text with {x} for its argument (a comparison binds
# last in Excel: a sum needs no brackets before <0).
OUTSIDE_DOMAIN = {"ACOS": "ABS({x})>1", "ASIN": "ABS({x})>1", "SQRT": "{x}<0"}


def outside_domain(function: str, arg: str) -> str:
    """The test, as Excel text, that `arg` is outside `function`'s domain."""
    return OUTSIDE_DOMAIN[function].format(x=arg)


def in_domain_or_na(function: str, arg: str) -> str:
    """function(arg), or #N/A where arg is outside its domain (tested, not caught)."""
    return f"IF({outside_domain(function, arg)},NA(),{function}({arg}))"


def angle_of_triangle_or_na(adjacent1: str, adjacent2: str, opposite: str, once: str) -> str:
    """The cosine rule: the angle between sides {adjacent1} and {adjacent2} (keys), or #N/A
    where the three sides make no triangle. That test is the domain of the ACOS's argument,
    |b - c| <= a <= b + c, written with side {once} appearing once: in a grid's
    self-contained formula a side is a whole formula, and ABS(argument)>1 would write the
    argument, and each side in it, twice more in every nested step."""
    a, b = (k for k in (adjacent1, adjacent2, opposite) if k != once)
    fails = f"ABS({{{once}}}-MAX({{{a}}},{{{b}}}))>MIN({{{a}}},{{{b}}})"
    cosine = (f"({{{adjacent1}}}^2+{{{adjacent2}}}^2-{{{opposite}}}^2)"
              f"/(2*{{{adjacent1}}}*{{{adjacent2}}})")
    # IFERROR: a zero side divides by zero, and rounding at an exact limit position can put
    # the cosine a hair beyond 1; both are #N/A too
    return f"IFERROR(IF({fails},NA(),ACOS({cosine})),NA())"


def acos_or_na(arg: str) -> str:
    # IFERROR: a zero length divides by zero; that too is #N/A
    return f"IFERROR({in_domain_or_na('ACOS', arg)},NA())"


def asin_or_na(arg: str) -> str:
    return f"IFERROR({in_domain_or_na('ASIN', arg)},NA())"
