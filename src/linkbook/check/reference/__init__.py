"""Generic independent reference: any mechanism described in the mechanism language.

The description is the ``[mechanism]`` table of a template (docs/language.md): ground points, an
input angle and an ordered list of steps, each placing one new point from points already known.
This module reads the same description as the workbook writer but shares no formula with it (and
imports nothing from linkbook): every step is turned into the geometric constraints it implies and
its unknown is found by Newton–Raphson, row after row:

* ``crank`` — the pin is a function of the input angle alone: evaluated directly;
* ``dyad`` — R = (x, y) with |R − P| = p and |R − Q| = q (two circle residuals), the branch
  fixed by the sign of cross(R − Q, P − Q);
* ``slider`` — R = T + s·d on its line with |R − P| = l (one residual in s), the branch by the
  sign of (R − P)·d; R is then put exactly on the line;
* ``slide`` — the link angle θ with (P − Q)·e^{iθ} = offset (the slide line, perpendicular to the
  link at the offset, passes through P), the branch by the sign of cross(e^{iθ}, P − Q);
* ``slot`` — P on the slot and on the fixed line (two linear residuals in the positions along
  them: Newton lands on the root in one step);
* ``point`` — by ``distances``: the two circles again (solved once, in the frame's own
  coordinates, when the frame is a rigid link of known length: then γ is a constant); by
  ``local`` or ``distance``/``angle``: placed directly;
* ``vector``, ``distance`` — measured; ``expression`` — the user's formula, evaluated by this
  module's own parser (Excel's functions, errors as NaN).

Newton continues from the previous row's root. On the first row, after a row that could not
close, or when the continued root is on the wrong branch, it restarts from a spread of first
guesses and keeps the first root on the requested branch; a row where none is found is NaN. An
independent existence check (the triangle inequality of a dyad, ...) is used only to decide to
try a denser spread of first guesses, never to produce a value. Next to a limit position (a
double root) Newton converges only linearly and, in plain doubles, stalls on a plateau of width
√ε where the residual rounds to zero: such a root is polished with residuals carried in
double-double (or written in a form that keeps its digits), so that a dead centre reached
exactly by the data is found to round-off, not to √ε.

Every column is then measured on the solved points: distances (hypot), np.arctan2 of
joint-to-joint vectors, interior angles from dot and cross products. An angle is returned in the
window of the doc's definition (theta_q = ϕ − b·ψ in [ϕ − π, ϕ] or [ϕ, ϕ + π], ...), so that the
smallest and largest value of an angle column mean the same as in the workbook.

Pure-Python scalar arithmetic is used inside Newton (1×1 and 2×2 systems are much faster that way
than with small numpy calls); the columns are then measured with vectorised numpy.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np

__all__ = ["solve", "pivots", "fourbar_loops", "limit_angles", "evaluate",
           "refined_extreme", "time_ratio", "slider_drawing", "slider_parts"]

_TAU = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
_WRAP_AT = 4.0 * math.pi

# Newton stops once every step is below _STEP_TOL × the unknown's scale (1 rad for angles, the
# mechanism's size for lengths); quadratic convergence then leaves an error of order _STEP_TOL²
# (round-off). The residual (a length) must also be below _RES_TOL × size: a constraint with no
# real solution keeps a residual at least as large as its gap, so it can never pass.
_STEP_TOL = 1e-10
_RES_TOL = 1e-9
_MAX_ITER = 40
_STARTS = 8          # first guesses for a restart
_DENSE_STARTS = 48   # ... when the existence check says the step should close but Newton failed
# Next to a double root (a limit position: |sin| of the angle between the two constraints'
# gradients below _NEAR_DOUBLE) Newton converges only linearly and stops early: the root is
# polished with a careful residual, up to _POLISH_ITER more steps, down to steps of _POLISH_TOL.
_NEAR_DOUBLE = 1e-4
_POLISH_TOL = 1e-15
_POLISH_ITER = 100
# There the two branches meet: a root less than _TANGENT (relative) off the dead-centre line is
# taken as on either branch.
_TANGENT = 1e-12

Fun = Callable[[Sequence[float]], tuple[tuple[float, ...], tuple[tuple[float, ...], ...]]]
Point = tuple[np.ndarray, np.ndarray]


# --------------------------------------------------------------------------------------------
# Expressions: a small recursive-descent parser and an evaluator over floats and numpy arrays
# (never eval). Any error Excel would show (#NUM!, #DIV/0!, #N/A) is NaN.
# --------------------------------------------------------------------------------------------

_TOKEN = re.compile(
    r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<op>\*\*|>=|<=|<>|==|!=|[-+*/^(),<>=]))"
)
_COMPARE_OPS = {">", ">=", "<", "<=", "=", "==", "<>", "!="}


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
        self.text = text
        self.tokens: list[tuple[str, str]] = []
        pos, end = 0, len(text.rstrip())
        while pos < end:
            m = _TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                raise ValueError(f"expression {text!r}: unexpected character at {pos + 1}")
            self.tokens.append((m.lastgroup, m.group(m.lastgroup)))
            pos = m.end()
        self.k = 0

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
        if self.is_op("-"):
            self.take()
            return ("neg", self.unary())
        if self.is_op("+"):
            self.take()
            return self.unary()
        return self.power()

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
    ATAN ATAN2(x, y) RADIANS DEGREES PI() MIN MAX IF IFERROR NA()) over env: {name: number or
    array}. A float when every name it uses is a number, else an array. A domain error (SQRT of
    a negative, a division by zero, ...) gives NaN, as Excel shows an error; a malformed
    expression or an unknown name raises ValueError."""
    if isinstance(expr, bool):
        raise ValueError(f"expected a number or an expression, got {expr!r}")
    if isinstance(expr, (int, float)):
        return float(expr)
    if not isinstance(expr, str) or not expr.strip():
        raise ValueError(f"expected a number or an expression, got {expr!r}")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        value = _run(_Parser(expr).parse(), env, expr)
    return float(value) if value.ndim == 0 else value


def _scalar(expr: object, params: Mapping[str, float]) -> float:
    """An expression of the parameters alone: a float."""
    value = evaluate(expr, params)
    if not isinstance(value, float):
        raise ValueError(f"expression {expr!r} must depend on the parameters alone")
    return value


def _branch(value: object, params: Mapping[str, float], what: str) -> int:
    b = _scalar(value, params)
    if b not in (1.0, -1.0):
        raise ValueError(f"{what} must be 1 or -1, got {value!r} = {b!r}")
    return int(b)


# --------------------------------------------------------------------------------------------
# Newton–Raphson and the continuation sweep (after reference.py)
# --------------------------------------------------------------------------------------------

def _linear_solve(jac: Sequence[Sequence[float]], rhs: Sequence[float]) -> list[float] | None:
    """Solve jac · x = rhs for 1×1 and 2×2 systems; None if singular."""
    if len(rhs) == 1:
        d = jac[0][0]
        return None if d == 0.0 else [rhs[0] / d]
    (a, b), (c, d) = jac
    det = a * d - b * c
    if det == 0.0:
        return None
    return [(d * rhs[0] - b * rhs[1]) / det, (a * rhs[1] - c * rhs[0]) / det]


def _newton(fun: Fun, x0: Sequence[float], scales: Sequence[float], tol_f: float,
            angle_slots: Sequence[int] = ()) -> list[float] | None:
    """Newton–Raphson from x0. Returns the root, or None when it does not converge."""
    x = list(x0)
    n = len(x)
    for _ in range(_MAX_ITER):
        f, jac = fun(x)
        dx = _linear_solve(jac, f)
        if dx is None:
            # An exactly singular Jacobian at an exact root (a double root met exactly): done.
            return x if max(abs(v) for v in f) == 0.0 else None
        worst = 0.0
        for k in range(n):
            x[k] -= dx[k]
            r = abs(dx[k]) / scales[k]
            if r > worst or r != r:  # r != r: NaN, which then sticks
                worst = r
        if not worst < math.inf:  # NaN or overflow: diverged
            return None
        for k in angle_slots:
            # a wild early step can throw an angle many turns away: bring it back
            if abs(x[k]) > _WRAP_AT:
                x[k] = math.remainder(x[k], _TAU)
        if worst <= _STEP_TOL:
            # f was taken before this (tiny) step, so it bounds the final residual from above.
            return x if max(abs(v) for v in f) <= tol_f else None
    return None


def _polish(fun: Fun, x: Sequence[float], scales: Sequence[float], tol_f: float) -> list[float]:
    """More Newton steps on a root found next to a double root (a limit position), where Newton
    converges only linearly and stops early: until the step reaches round-off (_POLISH_TOL) or
    stops shrinking (the noise floor of the residual). `fun` evaluates the residual carefully, so
    that floor is far below the usual one."""
    x = list(x)
    n = len(x)
    last = math.inf
    for _ in range(_POLISH_ITER):
        f, jac = fun(x)
        if not max(abs(v) for v in f) <= tol_f:
            break
        dx = _linear_solve(jac, f)
        if dx is None:
            break
        worst = max(abs(dx[k]) / scales[k] for k in range(n))
        if not worst < last:
            break
        x = [x[k] - dx[k] for k in range(n)]
        last = worst
        if worst <= _POLISH_TOL:
            break
    return x


def _sweep(
    n_rows: int,
    system: Callable[[int], Fun | None],
    starts: Callable[[int, int], Iterable[Sequence[float]]],
    on_branch: Callable[[int, Sequence[float]], bool],
    scales: Sequence[float],
    angle_slots: Sequence[int],
    tol_f: float,
    closes: Callable[[int], bool] | None = None,
    careful: Callable[[int], Fun] | None = None,
    near_double: Callable[[int, Sequence[float]], bool] | None = None,
) -> list[tuple[float, ...] | None]:
    """Solve one step row after row by Newton with continuation; None where it cannot close.

    system(i): row i's residual function (None: skip the row, a known point is undefined there);
    starts(i, k): first guesses (k of them); on_branch(i, x): the branch invariant; closes(i),
    optional: the independent existence check, used only to decide on a denser restart;
    careful(i), optional: the same residual evaluated with less round-off, used by that denser
    restart and to polish a root where near_double(i, x) says it is close to a double root.
    """
    out: list[tuple[float, ...] | None] = [None] * n_rows
    prev: tuple[float, ...] | None = None

    def attempt(fun: Fun, i: int, x0: Sequence[float]) -> list[float] | None:
        x = _newton(fun, x0, scales, tol_f, angle_slots)
        if x is None:
            return None
        if near_double is not None and near_double(i, x):
            x = _polish(careful(i) if careful else fun, x, scales, tol_f)
        return x if on_branch(i, x) else None

    def restart(fun: Fun, i: int, guesses) -> list[float] | None:
        for x0 in guesses:     # multi-start: the first root on the requested branch
            x = attempt(fun, i, x0)
            if x is not None:
                return x
        return None

    for i in range(n_rows):
        fun = system(i)
        if fun is None:
            prev = None
            continue
        x = attempt(fun, i, prev) if prev is not None else None
        if x is None:
            x = restart(fun, i, starts(i, _STARTS))
        if x is None and closes is not None and closes(i):
            x = restart(careful(i) if careful else fun, i, starts(i, _DENSE_STARTS))
        if x is not None:
            for k in angle_slots:
                x[k] = math.remainder(x[k], _TAU)
            prev = tuple(x)
        else:
            prev = None
        out[i] = prev
    return out


def _directions(k: int) -> list[float]:
    """k first-guess angles around the circle, offset so none is a special angle."""
    return [0.1 + _TAU * j / k for j in range(k)]


def _column(sols: list, k: int) -> np.ndarray:
    return np.array([math.nan if x is None else x[k] for x in sols], dtype=float)


def _finite(*values: float) -> bool:
    return all(v == v and abs(v) != math.inf for v in values)


# Error-free transformations (Dekker, Knuth): a residual such as |R − P|² − p² near a double root
# is a difference of nearly equal squares; in plain doubles it is exactly 0 on a whole plateau
# of width √ε around the root. Carried in double-double it is not.
_SPLITTER = 134217729.0  # 2^27 + 1


def _two_sum(a: float, b: float) -> tuple[float, float]:
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_square(a: float) -> tuple[float, float]:
    p = a * a
    t = _SPLITTER * a
    hi = t - (t - a)
    lo = a - hi
    return p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo


def _square_gap(x: float, y: float, px: float, py: float, r: float) -> float:
    """(x − px)² + (y − py)² − r², with the differences and squares carried exactly."""
    dx, ex = _two_sum(x, -px)
    dy, ey = _two_sum(y, -py)
    a, ea = _two_square(dx)
    b, eb = _two_square(dy)
    c, ec = _two_square(r)
    s, es = _two_sum(a, b)
    s, es2 = _two_sum(s, -c)
    return s + (((es + es2) + (ea + eb - ec)) + 2.0 * (dx * ex + dy * ey))


# --------------------------------------------------------------------------------------------
# Constraint systems
# --------------------------------------------------------------------------------------------

def _circles(px: float, py: float, p: float, qx: float, qy: float, q: float) -> Fun:
    """R = (x, y) with |R − P| = p and |R − Q| = q: residuals (|R − P|² − p²)/(2p) and
    (|R − Q|² − q²)/(2q) (lengths, ≈ |R − P| − p near the root)."""
    ip, iq = 1.0 / p, 1.0 / q
    hp, hq = 0.5 * p, 0.5 * q

    def fun(x):
        ux, uy = x[0] - px, x[1] - py
        vx, vy = x[0] - qx, x[1] - qy
        return (((ux * ux + uy * uy) * 0.5 * ip - hp, (vx * vx + vy * vy) * 0.5 * iq - hq),
                ((ux * ip, uy * ip), (vx * iq, vy * iq)))

    return fun


def _circles_careful(px: float, py: float, p: float, qx: float, qy: float, q: float) -> Fun:
    """_circles with the residuals carried in double-double (see _square_gap)."""
    ip, iq = 1.0 / p, 1.0 / q

    def fun(x):
        return ((_square_gap(x[0], x[1], px, py, p) * 0.5 * ip,
                 _square_gap(x[0], x[1], qx, qy, q) * 0.5 * iq),
                (((x[0] - px) * ip, (x[1] - py) * ip), ((x[0] - qx) * iq, (x[1] - qy) * iq)))

    return fun


def _two_circles(P: Point, Q: Point, p, q, branch: int, size: float,
                 tol_f: float) -> Point:
    """Per row: R with |R − P| = p, |R − Q| = q and branch·cross(R − Q, P − Q) > 0; NaN where no
    such point is found. p and q are lengths, or per-row arrays where a side is a linear
    actuator. (At a limit position the two branches meet: a root whose side is below _TANGENT of
    the lengths is on both.)"""
    n = len(P[0])
    pxl, pyl, qxl, qyl = P[0].tolist(), P[1].tolist(), Q[0].tolist(), Q[1].tolist()
    pl = np.broadcast_to(np.asarray(p, dtype=float), (n,)).tolist()
    ql = np.broadcast_to(np.asarray(q, dtype=float), (n,)).tolist()
    slack = _RES_TOL * size

    def system(i):
        if not (_finite(pxl[i], pyl[i], qxl[i], qyl[i], pl[i], ql[i])
                and pl[i] > 0.0 and ql[i] > 0.0):
            return None
        return _circles(pxl[i], pyl[i], pl[i], qxl[i], qyl[i], ql[i])

    def careful(i):
        return _circles_careful(pxl[i], pyl[i], pl[i], qxl[i], qyl[i], ql[i])

    def side(i, x):
        qx, qy = qxl[i], qyl[i]
        return ((x[0] - qx) * (pyl[i] - qy) - (x[1] - qy) * (pxl[i] - qx),
                math.hypot(x[0] - qx, x[1] - qy) * math.hypot(pxl[i] - qx, pyl[i] - qy))

    def on_branch(i, x):
        cross, scale = side(i, x)
        return branch * cross > -_TANGENT * scale

    def near_double(i, x):   # R, P, Q nearly in line: the Jacobian is nearly singular
        ux, uy, vx, vy = x[0] - pxl[i], x[1] - pyl[i], x[0] - qxl[i], x[1] - qyl[i]
        return abs(ux * vy - uy * vx) <= _NEAR_DOUBLE * math.hypot(ux, uy) * math.hypot(vx, vy)

    def starts(i, k):
        qx, qy, px, py, p_i, q_i = qxl[i], qyl[i], pxl[i], pyl[i], pl[i], ql[i]
        ring = [(qx + q_i * math.cos(a), qy + q_i * math.sin(a)) for a in _directions(k)]
        if k > _STARTS:  # dense: also around P, and half-way rings
            ring += [(px + p_i * math.cos(a), py + p_i * math.sin(a)) for a in _directions(k)]
            ring += [(qx + 0.5 * q_i * math.cos(a), qy + 0.5 * q_i * math.sin(a))
                     for a in _directions(k)]
        # the guesses on the requested side first
        first = [g for g in ring if branch * side(i, g)[0] > 0.0]
        return first + [g for g in ring if not branch * side(i, g)[0] > 0.0]

    def closes(i):
        d = math.hypot(pxl[i] - qxl[i], pyl[i] - qyl[i])
        return abs(pl[i] - ql[i]) - slack <= d <= pl[i] + ql[i] + slack

    sols = _sweep(n, system, starts, on_branch, (size, size), (), tol_f, closes, careful,
                  near_double)
    return _column(sols, 0), _column(sols, 1)


def _slider_system(h: float, w: float, length: float) -> Fun:
    """R = T + s·d, P = T + h·d + w·d⊥: residual (|R − P|² − l²)/(2l) in the unknown s, written
    ((s − h)² + (w − l)(w + l))/(2l) so that it keeps its digits next to a double root."""
    il = 1.0 / length
    c = (w - length) * (w + length)

    def fun(x):
        u = x[0] - h
        return ((u * u + c) * 0.5 * il,), ((u * il,),)

    return fun


def _slide_system(vx: float, vy: float, offset: float) -> Fun:
    """Link angle θ with (P − Q)·e^{iθ} = offset, V = P − Q (the slide line, at the offset from
    the pivot and perpendicular to the link, passes through P). The residual V·e^{iθ} − offset
    is written in the polar form of the dot product about the direction ψ0 where it is largest
    in the offset's sign, σ(|V| − |offset|) − 2σ|V|·sin²((θ − ψ0)/2), so that it keeps its
    digits next to a double root (|V| = |offset|)."""
    r = math.hypot(vx, vy)
    sig = 1.0 if offset >= 0.0 else -1.0
    psi0 = math.atan2(vy, vx) if sig > 0.0 else math.atan2(-vy, -vx)
    gap = sig * (r - abs(offset))

    def fun(x):
        d = x[0] - psi0
        h = math.sin(0.5 * d)
        return (gap - 2.0 * sig * r * h * h,), ((-sig * r * math.sin(d),),)

    return fun


def _slider_positions(P: Point, T: Point, dx: float, dy: float, length: float, branch: int,
                      size: float, tol_f: float) -> np.ndarray:
    """Per row: the position s of R = T + s·d with |R − P| = length and
    branch·((R − P)·d) > 0; NaN where no such point is found."""
    n = len(P[0])
    if not (_finite(length) and length > 0.0):
        return np.full(n, math.nan)
    vx, vy = P[0] - T[0], P[1] - T[1]
    hl = (vx * dx + vy * dy).tolist()   # P's foot on the line, along d
    wl = (dx * vy - dy * vx).tolist()   # P's distance from the line, to the left of d
    slack = _RES_TOL * size

    def system(i):
        return _slider_system(hl[i], wl[i], length) if _finite(hl[i], wl[i]) else None

    def starts(i, k):
        h = hl[i]
        if k <= _STARTS:
            return [(h + branch * length * c,) for c in (1.0, 0.5, 2.0, 0.1)]
        return [(h + branch * length * c,) for c in np.linspace(0.02, 4.0, k).tolist()]

    sols = _sweep(n, system, starts,
                  lambda i, x: branch * (x[0] - hl[i]) > -_TANGENT * length,
                  (size,), (), tol_f, lambda i: abs(wl[i]) <= length + slack, system,
                  lambda i, x: abs(x[0] - hl[i]) <= _NEAR_DOUBLE * length)
    return _column(sols, 0)


def _slide_angles(P: Point, Q: Point, offset: float, branch: int, size: float,
                  tol_f: float) -> np.ndarray:
    """Per row: the link angle θ with (P − Q)·e^{iθ} = offset and
    branch·cross(e^{iθ}, P − Q) > 0; NaN where no such angle is found."""
    n = len(P[0])
    if not math.isfinite(offset):
        return np.full(n, math.nan)
    vxl, vyl = (P[0] - Q[0]).tolist(), (P[1] - Q[1]).tolist()
    slack = _RES_TOL * size

    def system(i):
        return _slide_system(vxl[i], vyl[i], offset) if _finite(vxl[i], vyl[i]) else None

    def on_branch(i, x):
        cross = math.cos(x[0]) * vyl[i] - math.sin(x[0]) * vxl[i]
        return branch * cross > -_TANGENT * math.hypot(vxl[i], vyl[i])

    def near_double(i, x):   # the link nearly along P − Q
        cross = math.cos(x[0]) * vyl[i] - math.sin(x[0]) * vxl[i]
        return abs(cross) <= _NEAR_DOUBLE * math.hypot(vxl[i], vyl[i])

    def starts(i, k):
        return [(a,) for a in _directions(k)]

    return _column(_sweep(n, system, starts, on_branch, (1.0,), (0,), tol_f,
                          lambda i: math.hypot(vxl[i], vyl[i]) >= abs(offset) - slack,
                          system, near_double), 0)


def _slot_crossing(E: Point, T: Point, ux, uy, dx: float, dy: float) -> Point:
    """Per row: (a, b) with E + a·u = T + b·d, the crossing of a slot (through E along u) and a
    fixed line (through T along d). The constraints are linear, so Newton from (0, 0) lands on
    the root in one step; a second step refines it. NaN where the lines are parallel."""
    ex, ey, tx, ty = E[0].tolist(), E[1].tolist(), T[0].tolist(), T[1].tolist()
    uxl, uyl = np.broadcast_to(ux, E[0].shape).tolist(), np.broadcast_to(uy, E[0].shape).tolist()
    a_out, b_out = [math.nan] * len(ex), [math.nan] * len(ex)
    for i in range(len(ex)):
        if not _finite(ex[i], ey[i], tx[i], ty[i], uxl[i], uyl[i]):
            continue
        jac = ((uxl[i], -dx), (uyl[i], -dy))
        x = [0.0, 0.0]
        for _ in range(2):
            f = (ex[i] + x[0] * uxl[i] - tx[i] - x[1] * dx,
                 ey[i] + x[0] * uyl[i] - ty[i] - x[1] * dy)
            step = _linear_solve(jac, f)
            if step is None:
                break
            x = [x[0] - step[0], x[1] - step[1]]
        else:
            if _finite(*x):
                a_out[i], b_out[i] = x
    return np.array(a_out), np.array(b_out)


def _triangle_apex(base: float, left: float, right: float) -> tuple[float, float]:
    """C = (x, y), y ≥ 0, with |AC| = left and |BC| = right, A = (0, 0), B = (base, 0): found by
    Newton (the residuals carried carefully, so that a flat triangle is found too); (NaN, NaN)
    if there is no such triangle."""
    if not (_finite(base, left, right) and base > 0.0 and left > 0.0 and right > 0.0):
        return math.nan, math.nan
    size = base + left + right
    fun = _circles_careful(0.0, 0.0, left, base, 0.0, right)
    guesses = [(0.5 * base, size), (0.0, left), (base, right)]
    guesses += [(left * math.cos(a), left * math.sin(a)) for a in _directions(_DENSE_STARTS)]
    for x0 in guesses:
        x = _newton(fun, x0, (size, size), _RES_TOL * size)
        if x is not None:
            if abs(x[1]) <= _NEAR_DOUBLE * size:
                x = _polish(fun, x, (size, size), _RES_TOL * size)
            return x[0], abs(x[1])
    return math.nan, math.nan


# --------------------------------------------------------------------------------------------
# Geometry on solved points (vectorised)
# --------------------------------------------------------------------------------------------

def _interior(ux, uy, vx, vy):
    """Interior angle between vectors u and v, in [0, π]."""
    return np.arctan2(np.abs(ux * vy - uy * vx), ux * vx + uy * vy)


def _cos_sin_deg(deg: float) -> tuple[float, float]:
    """cos and sin of an angle in degrees, exact at multiples of 90° (a horizontal line stays
    exactly horizontal)."""
    if deg == deg and abs(deg) != math.inf and deg % 90.0 == 0.0:
        k = int(deg // 90.0) % 4
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[k]
    r = math.radians(deg)
    return math.cos(r), math.sin(r)


# --------------------------------------------------------------------------------------------
# The description
# --------------------------------------------------------------------------------------------

_LOOP_STEPS = ("dyad", "slider", "slide", "slot")   # steps that may fail to close
_STEP_TYPES = _LOOP_STEPS + ("crank", "point", "vector", "distance", "expression")
# fields holding a length or an offset: their sum is the mechanism's size
_LENGTH_FIELDS = ("length", "p_length", "q_length", "offset", "distance")


def _steps(description: Mapping) -> list[Mapping]:
    steps = description.get("steps", [])
    if not isinstance(steps, list):
        raise ValueError("mechanism.steps must be a list of tables")
    for k, step in enumerate(steps):
        if not isinstance(step, Mapping) or step.get("type") not in _STEP_TYPES:
            kind = step.get("type") if isinstance(step, Mapping) else step
            raise ValueError(f"steps[{k}]: unknown or missing type {kind!r}")
    return steps


def pivots(description: Mapping, params: Mapping[str, float]) -> dict[str, tuple[float, float]]:
    """The ground points of the description, evaluated: {name: (x, y)}."""
    ground = description.get("ground", {})
    if not isinstance(ground, Mapping):
        raise ValueError("mechanism.ground must be a table of [x, y] pairs")
    out = {}
    for name, xy in ground.items():
        if not isinstance(xy, (list, tuple)) or len(xy) != 2:
            raise ValueError(f"ground point {name!r} must be [x, y]")
        out[str(name)] = (_scalar(xy[0], params), _scalar(xy[1], params))
    return out


def _size(steps: list[Mapping], params: Mapping[str, float],
          ground: Mapping[str, tuple[float, float]]) -> float:
    """The mechanism's size: the sum of |every length and offset| of the description (ground
    coordinates, link lengths, offsets, carried points' distances and local coordinates)."""
    total = 0.0
    for x, y in ground.values():
        total += abs(x) + abs(y)
    for step in steps:
        for field in _LENGTH_FIELDS:
            if field in step and step["type"] != "distance":
                value = evaluate(step[field], params)   # a swept length: its largest value
                total += float(np.nanmax(np.abs(value), initial=0.0)) \
                    if isinstance(value, np.ndarray) else abs(_scalar(step[field], params))
        for field in ("local", "distances"):
            if isinstance(step.get(field), (list, tuple)):
                total += sum(abs(_scalar(v, params)) for v in step[field])
    return total if total > 0.0 and math.isfinite(total) else 1.0


def _near(angle, center):
    """The angle (radians, any turn) brought into [center − π, center + π)."""
    return center + (np.remainder(angle - center + math.pi, _TAU) - math.pi)


class _Solver:
    """One pass over the steps, in order: each step's points and columns, for every row.

    Besides the values it keeps what the workbook's layout depends on: which points move with
    the input angle, the angle of each known link (for a point placed at an angle to it), and
    which keys are fixed (hidden, or a constant, and independent of the input angle), so that a
    carried point's gamma or theta and an expression come back as a float exactly where the
    workbook makes them one named constant cell."""

    def __init__(self, description: Mapping, params: Mapping[str, float], angles: np.ndarray):
        inp = description.get("input")
        if not isinstance(inp, Mapping) or not isinstance(inp.get("key"), str):
            raise ValueError("mechanism.input must be a table with a key")
        self.input_key = inp["key"]
        self.params = params
        self.steps = _steps(description)
        # the input: a crank's angle (degrees given, radians used) or a linear actuator's
        # length, which a dyad's side may be
        self.angle_input = inp.get("kind", "angle") == "angle"
        values = np.asarray(angles, dtype=float)
        self.th = np.radians(values) if self.angle_input else None
        self.swept = {} if self.angle_input else {self.input_key: values}
        self.n = n = len(angles)
        ground = pivots(description, params)
        self.size = _size(self.steps, {**params, **self.swept}, ground)
        self.tol_f = _RES_TOL * self.size
        self.points: dict[str, Point] = {name: (np.full(n, x), np.full(n, y))
                                         for name, (x, y) in ground.items()}
        self.moving: set[str] = set()             # points that move with the input angle
        self.coords: dict[str, tuple[str, str]] = {}   # a step point's x and y keys
        # pairs of points a fixed, known distance apart (a rigid link of known length)
        self.rigid: dict[frozenset, float] = {}
        # the angle of a known link A→B, as the workbook writes it: (values, key or None)
        self.link: dict[tuple[str, str], tuple[np.ndarray, str | None]] = {}
        for a, (x1, y1) in ground.items():
            for b, (x2, y2) in ground.items():
                if a != b:
                    self.rigid[frozenset((a, b))] = math.hypot(x2 - x1, y2 - y1)
                    self.link[(a, b)] = (np.full(n, math.atan2(y2 - y1, x2 - x1)), None)
        self.out: dict[str, object] = {self.input_key: self.th if self.angle_input else values}
        self.fixed: dict[str, bool] = {}
        # what an expression step may name: parameters, the input angle, every earlier key
        self.env: dict[str, object] = {k: v for k, v in params.items()}
        if self.angle_input:
            self.env[self.input_key] = self.th
            self.env[f"{self.input_key}_deg"] = values
        else:
            self.env[self.input_key] = values
        self.reserved = {self.input_key, "assembled", "points"}
        self.assembled = np.ones(n, dtype=bool)

    # -- helpers
    def run(self) -> dict:
        for k, step in enumerate(self.steps):
            self.where = f"steps[{k}] ({step['type']} {step.get('point', step.get('key', ''))})"
            getattr(self, f"step_{step['type']}")(step)
        self.out["assembled"] = self.assembled
        self.out["points"] = self.points
        return self.out

    def known(self, step: Mapping, field: str) -> Point:
        name = step.get(field)
        if not isinstance(name, str) or name not in self.points:
            raise ValueError(f"{self.where}.{field}: {name!r} is not a known point")
        return self.points[name]

    def pair(self, step: Mapping, field: str) -> tuple[str, str]:
        names = step.get(field)
        if not isinstance(names, (list, tuple)) or len(names) != 2:
            raise ValueError(f"{self.where}.{field} must be [A, B]")
        for nm in names:
            if not isinstance(nm, str) or nm not in self.points:
                raise ValueError(f"{self.where}.{field}: {nm!r} is not a known point")
        return names[0], names[1]

    def num(self, step: Mapping, field: str, default: float | None = None) -> float:
        if field not in step:
            if default is None:
                raise ValueError(f"{self.where}: missing {field}")
            return float(default)
        return _scalar(step[field], self.params)

    def side(self, step: Mapping, field: str):
        """A dyad's side: a length, or per-row lengths where it is the swept actuator."""
        if not self.swept:
            return self.num(step, field)
        value = evaluate(step[field], {**self.params, **self.swept})
        if isinstance(value, np.ndarray):
            return value.astype(float)
        if not isinstance(value, float):
            raise ValueError(f"{self.where}.{field}: not a number")
        return value

    def branch(self, step: Mapping, field: str = "branch") -> int:
        return _branch(step.get(field, 1), self.params, f"{self.where}.{field}")

    def moves(self, *names: str) -> bool:
        return any(nm in self.moving for nm in names)

    def coords_fixed(self, name: str) -> bool:
        """The workbook writes the point's coordinates as fixed values (a ground point's
        expressions, or hidden columns independent of the input angle)."""
        if name not in self.coords:
            return name not in self.moving
        return all(self.fixed.get(k, False) for k in self.coords[name])

    def put(self, key: str, value, fixed: bool) -> None:
        if key in self.out or key in self.reserved:
            raise ValueError(f"{self.where}: column key {key!r} is written twice")
        self.out[key] = value
        self.env[key] = value
        self.fixed[key] = fixed

    def column(self, step: Mapping, col: str, default: str, value, moving: bool,
               shown_by_default: bool = True) -> str:
        """A column under its key: the default, or the `key` its `columns` entry gives
        (`false` or `shown = false` hides it from the sheets, not from here)."""
        spec = (step.get("columns") or {}).get(col)
        key, shown = default, shown_by_default
        if spec is False:
            shown = False
        elif spec is True:
            shown = True
        elif isinstance(spec, Mapping):
            key = str(spec.get("key") or default)
            shown = bool(spec.get("shown", True))
        if isinstance(value, float):        # a constant: one named cell
            fixed = True
        else:
            value = np.asarray(value, dtype=float)
            fixed = not moving and not shown
        self.put(key, value, fixed)
        return key

    def point_columns(self, step: Mapping, values: Mapping[str, object], moving: bool,
                      hidden: tuple[str, ...] = ()) -> dict[str, str]:
        """Columns of a step that places point N: f"{col}_{N}", x → xN, y → yN (`hidden`:
        columns shown only when the step's `columns` asks for them)."""
        name = step["point"]
        return {col: self.column(step, col, f"{col}{name}" if col in ("x", "y") else
                                 f"{col}_{name}", value, moving, col not in hidden)
                for col, value in values.items()}

    def new_point(self, step: Mapping, keys: Mapping[str, str], moving: bool, loop: bool) -> None:
        name = step.get("point")
        if not isinstance(name, str) or not name:
            raise ValueError(f"{self.where}: missing point")
        if name in self.points:
            raise ValueError(f"{self.where}: point {name!r} is defined twice")
        x, y = self.out[keys["x"]], self.out[keys["y"]]
        self.points[name] = (x, y)
        self.coords[name] = (keys["x"], keys["y"])
        if moving:
            self.moving.add(name)
        if loop:    # a loop step closes exactly where its point exists
            self.assembled &= np.isfinite(x) & np.isfinite(y)

    def add_link(self, a: str, b: str, angle: np.ndarray, key: str | None,
                 length=None) -> None:
        """A link A→B and its angle; with a length (not a swept one), a rigid pair."""
        self.link.setdefault((a, b), (angle, key))
        if length is not None and not isinstance(length, np.ndarray):
            self.rigid[frozenset((a, b))] = abs(length)

    def angle_of(self, a: str, b: str) -> tuple[np.ndarray, bool]:
        """angle(A→B) as the workbook takes it (a known link's angle column, or the angle of
        the points), and whether that is a fixed value."""
        if (a, b) in self.link:
            angle, key = self.link[(a, b)]
        elif (b, a) in self.link:
            angle, key = self.link[(b, a)]
            angle = angle + math.pi
        else:
            (ax, ay), (bx, by) = self.points[a], self.points[b]
            return np.arctan2(by - ay, bx - ax), self.coords_fixed(a) and self.coords_fixed(b)
        fixed = self.fixed.get(key, False) if key is not None else \
            self.coords_fixed(a) and self.coords_fixed(b)
        return angle, fixed

    # -- step types
    def step_crank(self, step: Mapping) -> None:
        if not self.angle_input:
            raise ValueError(f"{self.where}: a crank needs an angle input")
        P = self.known(step, "pivot")
        length = self.num(step, "length")
        t = self.th + math.radians(self.num(step, "phase", 0.0))
        keys = self.point_columns(step, {"x": P[0] + length * np.cos(t),
                                         "y": P[1] + length * np.sin(t)}, True)
        self.new_point(step, keys, True, loop=False)
        self.add_link(step["pivot"], step["point"], t, None, length)

    def step_dyad(self, step: Mapping) -> None:
        P, Q = self.known(step, "p"), self.known(step, "q")
        pl, ql = self.side(step, "p_length"), self.side(step, "q_length")
        b = self.branch(step)
        x, y = _two_circles(P, Q, pl, ql, b, self.size, self.tol_f)
        xs, ys = P[0] - Q[0], P[1] - Q[1]
        phi = np.arctan2(ys, xs)
        # angles measured on the solved points, each in the window of the doc's definition:
        # theta_q = ϕ − b·ψ; theta_p = theta_q − b·μ, or ϕ + π + b·∠QPR where the workbook
        # shows the angle at P in place of μ
        theta_q = _near(np.arctan2(y - Q[1], x - Q[0]), phi - b * _HALF_PI)
        given = step.get("columns") or {}

        def shown(col: str) -> bool:
            spec = given.get(col, {} if col != "p_interior" else None)
            return isinstance(spec, Mapping) and spec.get("shown", True) or spec is True

        centre = phi + math.pi + b * _HALF_PI if not shown("mu") and shown("p_interior") \
            else theta_q - b * _HALF_PI
        theta_p = _near(np.arctan2(y - P[1], x - P[0]), centre)
        moving = self.moves(step["p"], step["q"])
        keys = self.point_columns(step, {
            "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": phi,
            "psi": _interior(xs, ys, x - Q[0], y - Q[1]),
            "mu": _interior(Q[0] - x, Q[1] - y, P[0] - x, P[1] - y),
            "p_interior": _interior(Q[0] - P[0], Q[1] - P[1], x - P[0], y - P[1]),
            "theta_q": theta_q, "theta_p": theta_p, "x": x, "y": y}, moving, ("p_interior",))
        self.new_point(step, keys, moving, loop=True)
        self.add_link(step["q"], step["point"], theta_q, keys["theta_q"], ql)
        self.add_link(step["p"], step["point"], theta_p, keys["theta_p"], pl)

    def step_slider(self, step: Mapping) -> None:
        P, T = self.known(step, "p"), self.known(step, "through")
        length = self.num(step, "length")
        direction = self.num(step, "direction", 0.0)
        b = self.branch(step)
        columns = {}
        if "along" in step:     # a line carried by the link U→V, at `direction` from it
            u, v = self.pair(step, "along")
            line = self.angle_of(u, v)[0] + math.radians(direction)
            dx, dy = np.cos(line), np.sin(line)
            columns["line"] = line
            moving = self.moves(step["p"], step["through"], u, v)
        else:
            line = math.radians(direction)
            dx, dy = _cos_sin_deg(direction)
            moving = self.moves(step["p"], step["through"])
        s = _slider_positions(P, T, dx, dy, length, b, self.size, self.tol_f)
        # R exactly on its line, R = T + s·d: a horizontal line keeps y = T_y to the last digit
        x, y = T[0] + s * dx, T[1] + s * dy
        # angle(R→P), in the window of the doc's branches: R ahead of P's foot (b = 1) or behind
        theta = _near(np.arctan2(P[1] - y, P[0] - x), line + (1 + b) * _HALF_PI)
        keys = self.point_columns(step, {**columns, "theta": theta, "s": s, "x": x, "y": y},
                                  moving)
        self.new_point(step, keys, moving, loop=True)
        self.add_link(step["point"], step["p"], theta, keys["theta"], length)

    def step_slide(self, step: Mapping) -> None:
        P, Q = self.known(step, "p"), self.known(step, "pivot")
        offset = self.num(step, "offset")
        b = self.branch(step)
        xs, ys = P[0] - Q[0], P[1] - Q[1]
        phi = np.arctan2(ys, xs)
        theta = _near(_slide_angles(P, Q, offset, b, self.size, self.tol_f), phi - b * _HALF_PI)
        ux, uy = np.cos(theta), np.sin(theta)
        x, y = Q[0] + offset * ux, Q[1] + offset * uy
        tx, ty = P[0] - x, P[1] - y
        travel = np.hypot(tx, ty)
        # The slide line is fixed to the link at right angles, on P's side (the branch): its
        # direction is θ + b·π/2, which is angle(B→P) wherever the travel is not zero, and stays
        # defined at a limit position where B and P meet (atan2 of a rounding-sized vector).
        slide = np.where(np.isnan(travel), np.nan, theta + b * _HALF_PI)
        moving = self.moves(step["p"], step["pivot"])
        keys = self.point_columns(step, {
            "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": phi,
            "psi": _interior(ux, uy, xs, ys), "travel": travel, "theta": theta,
            "theta_slide": slide, "x": x, "y": y}, moving)
        self.new_point(step, keys, moving, loop=True)
        self.add_link(step["point"], step["p"], slide, keys["theta_slide"])

    def step_point(self, step: Mapping) -> None:
        a, b = self.pair(step, "frame")
        A, B = self.points[a], self.points[b]
        name = step.get("point")
        moving = self.moves(a, b)
        if "local" in step:
            pair = step["local"]
            if not isinstance(pair, (list, tuple)) or len(pair) != 2:
                raise ValueError(f"{self.where}.local must be [u, v]")
            u, v = (_scalar(e, self.params) for e in pair)
            ex, ey = B[0] - A[0], B[1] - A[1]
            ab = np.hypot(ex, ey)
            ex, ey = ex / ab, ey / ab
            keys = self.point_columns(step, {"x": A[0] + u * ex - v * ey,
                                             "y": A[1] + u * ey + v * ex}, moving)
        elif "distances" in step:
            pair = step["distances"]
            if not isinstance(pair, (list, tuple)) or len(pair) != 2:
                raise ValueError(f"{self.where}.distances must be [|AC|, |BC|]")
            da, db = (_scalar(e, self.params) for e in pair)
            side = self.branch(step, "side")
            base = self.rigid.get(frozenset((a, b)))
            if base is None and self.coords_fixed(a) and self.coords_fixed(b):
                base = float(math.hypot(B[0][0] - A[0][0], B[1][0] - A[1][0])) if self.n else None
            if base is not None:
                # A rigid frame of known length: the triangle is solved once, in the frame's own
                # coordinates (C = A + cx·ê + side·cy·ê⊥), and γ is a constant.
                cx, cy = _triangle_apex(base, da, db)
                gamma = math.atan2(cy, cx)
                ex, ey = B[0] - A[0], B[1] - A[1]
                ab = np.hypot(ex, ey)
                ex, ey = ex / ab, ey / ab
                x = A[0] + cx * ex - side * cy * ey
                y = A[1] + cx * ey + side * cy * ex
            else:
                # side·cross(B − A, C − A) > 0 is the dyad over Q = A, P = B on branch −side
                x, y = _two_circles(B, A, db, da, -side, self.size, self.tol_f)
                gamma = _interior(B[0] - A[0], B[1] - A[1], x - A[0], y - A[1])
            keys = self.point_columns(step, {"gamma": gamma, "x": x, "y": y}, moving)
        elif "distance" in step:
            d = self.num(step, "distance")
            base, fixed = self.angle_of(a, b)
            theta = base + math.radians(self.num(step, "angle", 0.0))
            x, y = A[0] + d * np.cos(theta), A[1] + d * np.sin(theta)
            if fixed and self.n and np.all(theta == theta[0]):
                theta = float(theta[0])            # one named cell in the workbook
            keys = self.point_columns(step, {"theta": theta, "x": x, "y": y}, moving,
                                      ("theta",))
            self.add_link(a, name, np.broadcast_to(theta, (self.n,)), keys["theta"], d)
        else:
            raise ValueError(f"{self.where}: needs local, distances or distance")
        self.new_point(step, keys, moving, loop=False)

    def step_slot(self, step: Mapping) -> None:
        E = self.known(step, "slot_through")
        a, b = self.pair(step, "slot_frame")
        A, B = self.points[a], self.points[b]
        T = self.known(step, "through")
        # the slot: through E along angle(A→B) + slot_angle; the line: through T along d
        c, s = _cos_sin_deg(self.num(step, "slot_angle", 0.0))
        fx, fy = B[0] - A[0], B[1] - A[1]
        f = np.hypot(fx, fy)
        fx, fy = fx / f, fy / f
        ux, uy = fx * c - fy * s, fx * s + fy * c
        dx, dy = _cos_sin_deg(self.num(step, "direction", 0.0))
        s_slot, pos = _slot_crossing(E, T, ux, uy, dx, dy)
        moving = self.moves(step["slot_through"], a, b, step["through"])
        keys = self.point_columns(step, {"s_slot": s_slot, "s": pos,
                                         "x": T[0] + pos * dx,     # exactly on the fixed line
                                         "y": T[1] + pos * dy}, moving)
        self.new_point(step, keys, moving, loop=True)

    def step_vector(self, step: Mapping) -> None:
        key = step.get("key")
        if not isinstance(key, str) or not key:
            raise ValueError(f"{self.where}: missing key")
        F, T = self.known(step, "from"), self.known(step, "to")
        moving = self.moves(step["from"], step["to"])
        xs, ys = T[0] - F[0], T[1] - F[1]
        phi = np.arctan2(ys, xs)
        for col, value in (("xs", xs), ("ys", ys), ("s", np.hypot(xs, ys)), ("phi", phi)):
            k = self.column(step, col, f"{col}_{key}", value, moving)
        self.add_link(step["from"], step["to"], phi, k)

    def step_distance(self, step: Mapping) -> None:
        key = step.get("key")
        if not isinstance(key, str) or not key:
            raise ValueError(f"{self.where}: missing key")
        a, b = self.pair(step, "between")
        (x1, y1), (x2, y2) = self.points[a], self.points[b]
        self.column(step, "d", key, np.hypot(x2 - x1, y2 - y1), self.moves(a, b))

    def step_expression(self, step: Mapping) -> None:
        key = step.get("key")
        if not isinstance(key, str) or not key:
            raise ValueError(f"{self.where}: missing key")
        if "formula" not in step:
            raise ValueError(f"{self.where}: missing formula")
        # The workbook makes it one named cell when every name it uses is fixed (a parameter, a
        # constant, a hidden value independent of the input angle); such names are passed as
        # floats, so that the value comes back as a float.
        env = {k: (float(np.asarray(v).flat[0]) if self.fixed.get(k) and np.ndim(v) and self.n
                   else v) for k, v in self.env.items()}
        value = evaluate(step["formula"], env)
        if isinstance(value, float):
            self.put(key, value, True)
        else:
            self.put(key, np.broadcast_to(value, (self.n,)).astype(float), False)


# --------------------------------------------------------------------------------------------
# Velocity and acceleration: the constraints differentiated by Taylor arithmetic
# --------------------------------------------------------------------------------------------
#
# Every quantity is carried as its second-order Taylor expansion in time about each row,
# x(t) = a + b·t + c·t²/2 (b the velocity, c the acceleration), element-wise over the rows. A
# point placed directly (a crank pin, a carried point) is computed in this arithmetic. A step
# whose unknowns z satisfy constraints F(z, known) = 0 is differentiated implicitly: its
# Jacobian J = ∂F/∂z comes from seeding each unknown with a unit velocity (the knowns held
# still), then ż = −J⁻¹·(the velocity F has with z held still) and z̈ = −J⁻¹·(the acceleration
# F has with z moving at ż): J·ż = −(∂F/∂θ)·ω and the once more differentiated system. No
# closed form of the workbook's is used; a singular J (a dead centre) gives NaN.

# The data format's names of the input's speed and acceleration parameters.
_MOTION_PARAMS = {"angle": ("omega_in", "alpha_in"), "length": ("v_in", "a_in")}


class _T:
    """a + b·t + c·t²/2, element-wise (numpy arrays or floats)."""
    __slots__ = ("a", "b", "c")

    def __init__(self, a, b=0.0, c=0.0):
        self.a, self.b, self.c = a, b, c

    def __add__(self, o):
        o = _lift(o)
        return _T(self.a + o.a, self.b + o.b, self.c + o.c)

    __radd__ = __add__

    def __neg__(self):
        return _T(-self.a, -self.b, -self.c)

    def __sub__(self, o):
        return self + (-_lift(o))

    def __rsub__(self, o):
        return _lift(o) - self

    def __mul__(self, o):
        o = _lift(o)
        return _T(self.a * o.a, self.a * o.b + self.b * o.a,
                  self.a * o.c + 2.0 * self.b * o.b + self.c * o.a)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = _lift(o)
        q0 = self.a / o.a
        q1 = (self.b - q0 * o.b) / o.a
        return _T(q0, q1, (self.c - 2.0 * q1 * o.b - q0 * o.c) / o.a)


def _lift(x) -> _T:
    return x if isinstance(x, _T) else _T(x)


def _t_sin(x: _T) -> _T:
    s, c = np.sin(x.a), np.cos(x.a)
    return _T(s, c * x.b, c * x.c - s * x.b * x.b)


def _t_cos(x: _T) -> _T:
    s, c = np.sin(x.a), np.cos(x.a)
    return _T(c, -s * x.b, -s * x.c - c * x.b * x.b)


def _t_sqrt(x: _T) -> _T:
    r = np.sqrt(x.a)
    d1 = x.b / (2.0 * r)
    return _T(r, d1, (x.c - 2.0 * d1 * d1) / (2.0 * r))


def _t_atan2(y: _T, x: _T) -> _T:
    r2 = x.a * x.a + y.a * y.a
    d1 = (x.a * y.b - y.a * x.b) / r2
    d2 = (x.a * y.c - y.a * x.c) / r2 - 2.0 * d1 * (x.a * x.b + y.a * y.b) / r2
    return _T(np.arctan2(y.a, x.a), d1, d2)


def _still(x: _T) -> _T:
    return _T(x.a)


# Two constraint gradients closer to parallel than this (the sine of their angle) make a dead
# centre as far as double precision can tell: the solved position itself is only good to about
# √ε there (a double root), so the rates are not determined by the data.
_DEAD_CENTRE = 1e-7


def _t_solve(jac: list[list[np.ndarray]], rhs: list[np.ndarray]) -> tuple[list, np.ndarray]:
    """jac·x = rhs per row (1×1 or 2×2); NaN where jac is singular. Also the rows where a 2×2
    jac is singular to within _DEAD_CENTRE (the rates there are NaN and marked)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        if len(rhs) == 1:
            d = jac[0][0]
            dead = d == 0.0
            return [np.where(dead, np.nan, rhs[0] / np.where(dead, 1.0, d))], dead
        (a, b), (c, d) = jac
        det = a * d - b * c
        dead = np.abs(det) <= _DEAD_CENTRE * np.hypot(a, b) * np.hypot(c, d)
        safe = np.where(dead, 1.0, det)
        x = (rhs[0] * d - b * rhs[1]) / safe
        y = (a * rhs[1] - c * rhs[0]) / safe
        return [np.where(dead, np.nan, x), np.where(dead, np.nan, y)], dead


def _implicit(residuals, z0: list[np.ndarray], knowns: dict, still: dict
              ) -> tuple[list[_T], np.ndarray, np.ndarray]:
    """The unknowns z(t) with residuals(z, knowns) = 0, z(0) = z0 (see the section's comment),
    the rows at a dead centre, and per row how far from one (a 2×2 system's sine between its
    gradients; 1 for one unknown, whose step measures its own)."""
    k = len(z0)
    jac = [[None] * k for _ in range(k)]
    for j in range(k):
        seeded = [_T(z0[i], 1.0 if i == j else 0.0) for i in range(k)]
        for i, r in enumerate(residuals(seeded, still)):
            jac[i][j] = np.broadcast_to(np.asarray(r.b, dtype=float), z0[0].shape)
    first = residuals([_T(z) for z in z0], knowns)
    z1, dead = _t_solve(jac, [-np.asarray(r.b, dtype=float) for r in first])
    second = residuals([_T(z, d) for z, d in zip(z0, z1)], knowns)
    z2, _ = _t_solve(jac, [-np.asarray(r.c, dtype=float) for r in second])
    sine = np.ones_like(z0[0], dtype=float)
    if k == 2:      # the sine of the angle between the two constraint gradients
        (a, b), (c, d) = jac
        with np.errstate(divide="ignore", invalid="ignore"):
            sine = np.abs(a * d - b * c) / (np.hypot(a, b) * np.hypot(c, d))
    return [_T(z, d, dd) for z, d, dd in zip(z0, z1, z2)], dead, sine


class _Motion:
    """Velocities and accelerations of a solved mechanism (a _Solver after run())."""

    def __init__(self, solver: "_Solver", description: Mapping, speed: float, accel: float):
        self.s = solver
        self.description = description
        n = solver.n
        self.zero = np.zeros(n)
        self.points: dict[str, tuple[_T, _T]] = {
            name: (_T(x), _T(y)) for name, (x, y) in solver.points.items()}
        values = solver.out[solver.input_key]
        self.input = _T(np.asarray(values, dtype=float), speed, accel)
        self.out: dict[str, np.ndarray] = {}
        self.dead = np.zeros(n, dtype=bool)     # rows at a dead centre of some loop
        # per row, the smallest sine between a loop's two constraint gradients (1 far from any
        # dead centre): rounding in any evaluation of the rates grows like 1/sine²
        self.sine = np.ones(n)

    def note_sine(self, sine) -> None:
        sine = np.broadcast_to(np.asarray(sine, dtype=float), self.sine.shape)
        self.sine = np.fmin(self.sine, np.where(np.isfinite(sine), sine, 1.0))

    def run(self) -> dict:
        for k, step in enumerate(self.s.steps):
            self.where = f"steps[{k}]"
            getattr(self, f"step_{step['type']}")(step)
        trace = self.description.get("trace")
        if isinstance(trace, str) and trace in self.points:
            x, y = self.points[trace]
            self.out[f"vmag_{trace}"] = np.hypot(x.b, y.b)
            self.out[f"amag_{trace}"] = np.hypot(x.c, y.c)
        out = {k: np.broadcast_to(np.asarray(v, dtype=float), (self.s.n,)).copy()
               for k, v in self.out.items()}
        out["dead_centre"] = self.dead
        out["sine"] = self.sine
        return out

    # -- helpers
    def key(self, step: Mapping, col: str, default: str) -> str:
        spec = (step.get("columns") or {}).get(col)
        return str(spec.get("key") or default) if isinstance(spec, Mapping) else default

    def put_rates(self, key: str, value: _T, angle: bool) -> None:
        first, second = ("omega_", "alpha_") if angle else ("v_", "acc_")
        self.out[first + key] = value.b
        self.out[second + key] = value.c

    def place(self, name: str, x: _T, y: _T) -> None:
        self.points[name] = (x, y)
        self.out[f"vx_{name}"], self.out[f"vy_{name}"] = x.b, y.b
        self.out[f"ax_{name}"], self.out[f"ay_{name}"] = x.c, y.c

    def length(self, step: Mapping, field: str) -> _T | float:
        """A length of the description: the swept input where it is the input key itself."""
        if step[field] == self.s.input_key and not self.s.angle_input:
            return self.input
        return self.s.num(step, field)

    def still(self) -> dict:
        return {name: (_still(x), _still(y)) for name, (x, y) in self.points.items()}

    def angle(self, a: str, b: str, pts=None) -> _T:
        (ax, ay), (bx, by) = (pts or self.points)[a], (pts or self.points)[b]
        return _t_atan2(by - ay, bx - ax)

    def determinant(self, n: str, q: str, p: str) -> None:
        """(R − Q) × (R − P) of the solved points: zero where P, Q, R line up."""
        (rx, ry), (qx, qy), (px, py) = self.points[n], self.points[q], self.points[p]
        self.out[f"det_{n}"] = ((rx.a - qx.a) * (ry.a - py.a) - (ry.a - qy.a) * (rx.a - px.a))

    # -- step types
    def step_crank(self, step: Mapping) -> None:
        ox, oy = self.points[step["pivot"]]
        r = self.s.num(step, "length")
        t = self.input + math.radians(self.s.num(step, "phase", 0.0))
        self.place(step["point"], ox + r * _t_cos(t), oy + r * _t_sin(t))

    def circles(self, name: str, a: str, ra, b: str, rb) -> tuple[_T, _T]:
        """R with |R − A| = ra and |R − B| = rb (the solved R as the start)."""
        x0, y0 = self.s.points[name]

        def residuals(z, pts):
            (ax, ay), (bx, by) = pts[a], pts[b]
            ra_, rb_ = (r if not isinstance(r, _T) or pts is self.points else _still(r)
                        for r in (ra, rb))
            return [(z[0] - ax) * (z[0] - ax) + (z[1] - ay) * (z[1] - ay) - ra_ * ra_,
                    (z[0] - bx) * (z[0] - bx) + (z[1] - by) * (z[1] - by) - rb_ * rb_]

        (x, y), dead, sine = _implicit(residuals, [x0, y0], self.points, self.still())
        self.dead |= dead & np.isfinite(x0) & np.isfinite(y0)
        self.note_sine(sine)
        return x, y

    def step_dyad(self, step: Mapping) -> None:
        n, p, q = step["point"], step["p"], step["q"]
        x, y = self.circles(n, p, self.length(step, "p_length"), q,
                            self.length(step, "q_length"))
        self.place(n, x, y)
        self.determinant(n, q, p)
        self.put_rates(self.key(step, "theta_q", f"theta_q_{n}"), self.angle(q, n), True)
        self.put_rates(self.key(step, "theta_p", f"theta_p_{n}"), self.angle(p, n), True)

    def step_slider(self, step: Mapping) -> None:
        n, p, t = step["point"], step["p"], step["through"]
        length = self.s.num(step, "length")
        direction = math.radians(self.s.num(step, "direction", 0.0))
        along = self.s.pair(step, "along") if "along" in step else None
        if along:
            self.put_rates("_".join(along), self.angle(*along), True)

        fixed = _cos_sin_deg(self.s.num(step, "direction", 0.0))   # exact at quarter turns

        def line(pts):
            """The line's direction (cos, sin): turning with the link `along`, else fixed."""
            if along:
                lam = self.angle(*along, pts=pts) + direction
                return _t_cos(lam), _t_sin(lam)
            return _T(fixed[0]), _T(fixed[1])

        s0 = np.asarray(self.s.out[self.key(step, "s", f"s_{n}")], dtype=float)

        def residuals(z, pts):
            (dx, dy), (tx, ty), (px, py) = line(pts), pts[t], pts[p]
            rx, ry = tx + z[0] * dx - px, ty + z[0] * dy - py
            return [rx * rx + ry * ry - length * length]

        (pos,), _, _ = _implicit(residuals, [s0], self.points, self.still())
        (dx, dy), (tx, ty) = line(self.points), self.points[t]
        self.place(n, tx + pos * dx, ty + pos * dy)
        (px, py), (rx, ry) = self.points[p], self.points[n]
        self.out[f"det_{n}"] = dx.a * (px.a - rx.a) + dy.a * (py.a - ry.a)   # d·(P − R)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.note_sine(np.abs(self.out[f"det_{n}"]) / np.hypot(px.a - rx.a, py.a - ry.a))
        self.put_rates(self.key(step, "s", f"s_{n}"), pos, False)
        self.put_rates(self.key(step, "theta", f"theta_{n}"), self.angle(n, p), True)
        if along:
            self.put_rates(self.key(step, "line", f"line_{n}"),
                           self.angle(*along) + direction, True)

    def step_slide(self, step: Mapping) -> None:
        n, p, q = step["point"], step["p"], step["pivot"]
        offset = self.s.num(step, "offset")
        th0 = np.asarray(self.s.out[self.key(step, "theta", f"theta_{n}")], dtype=float)

        def residuals(z, pts):
            (px, py), (qx, qy) = pts[p], pts[q]
            return [(px - qx) * _t_cos(z[0]) + (py - qy) * _t_sin(z[0]) - offset]

        (theta,), _, _ = _implicit(residuals, [th0], self.points, self.still())
        qx, qy = self.points[q]
        self.place(n, qx + offset * _t_cos(theta), qy + offset * _t_sin(theta))
        (px, py) = self.points[p]
        self.out[f"det_{n}"] = (-(px.a - qx.a) * np.sin(theta.a)          # (P − Q)·(i e)
                                + (py.a - qy.a) * np.cos(theta.a))
        self.put_rates(self.key(step, "theta", f"theta_{n}"), theta, True)
        self.put_rates(self.key(step, "theta_slide", f"theta_slide_{n}"), theta, True)
        (px, py), (nx, ny) = self.points[p], self.points[n]
        self.put_rates(self.key(step, "travel", f"travel_{n}"),
                       _t_sqrt((px - nx) * (px - nx) + (py - ny) * (py - ny)), False)

    def step_point(self, step: Mapping) -> None:
        n = step["point"]
        a, b = self.s.pair(step, "frame")
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        self.put_rates(f"{a}_{b}", self.angle(a, b), True)     # the frame's own ω and α
        if "local" in step:
            u, v = (_scalar(e, self.s.params) for e in step["local"])
            ab = _t_sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay))
            ex, ey = (bx - ax) / ab, (by - ay) / ab
            self.place(n, ax + u * ex - v * ey, ay + u * ey + v * ex)
        elif "distances" in step:
            da, db = (_scalar(e, self.s.params) for e in step["distances"])
            self.place(n, *self.circles(n, a, da, b, db))
            if frozenset((a, b)) not in self.s.rigid:     # the frame stretches: a loop of its own
                self.determinant(n, b, a)
        else:
            d = self.s.num(step, "distance")
            theta = self.angle(a, b) + math.radians(self.s.num(step, "angle", 0.0))
            self.place(n, ax + d * _t_cos(theta), ay + d * _t_sin(theta))
            self.put_rates(self.key(step, "theta", f"theta_{n}"), theta, True)

    def step_slot(self, step: Mapping) -> None:
        n, e, t = step["point"], step["slot_through"], step["through"]
        a, b = self.s.pair(step, "slot_frame")
        self.put_rates(f"{a}_{b}", self.angle(a, b), True)
        slot_angle = math.radians(self.s.num(step, "slot_angle", 0.0))
        dc, ds = _cos_sin_deg(self.s.num(step, "direction", 0.0))    # exact at quarter turns
        z0 = [np.asarray(self.s.out[self.key(step, c, f"{c}_{n}")], dtype=float)
              for c in ("s_slot", "s")]

        def residuals(z, pts):
            u = self.angle(a, b, pts=pts) + slot_angle
            (ex, ey), (tx, ty) = pts[e], pts[t]
            return [ex + z[0] * _t_cos(u) - tx - z[1] * dc,
                    ey + z[0] * _t_sin(u) - ty - z[1] * ds]

        (s_slot, pos), dead, sine = _implicit(residuals, z0, self.points, self.still())
        self.dead |= dead & np.isfinite(z0[0]) & np.isfinite(z0[1])
        self.note_sine(sine)
        tx, ty = self.points[t]
        self.place(n, tx + pos * dc, ty + pos * ds)
        u = self.angle(a, b).a + slot_angle
        self.out[f"det_{n}"] = np.cos(u) * ds - np.sin(u) * dc            # û × d
        self.put_rates(self.key(step, "s_slot", f"s_slot_{n}"), s_slot, False)
        self.put_rates(self.key(step, "s", f"s_{n}"), pos, False)

    def step_vector(self, step: Mapping) -> None:
        key = step["key"]
        (ax, ay), (bx, by) = self.points[step["from"]], self.points[step["to"]]
        dx, dy = bx - ax, by - ay
        self.put_rates(self.key(step, "s", f"s_{key}"), _t_sqrt(dx * dx + dy * dy), False)
        self.put_rates(self.key(step, "phi", f"phi_{key}"), _t_atan2(dy, dx), True)

    def step_distance(self, step: Mapping) -> None:
        a, b = self.s.pair(step, "between")
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        dx, dy = bx - ax, by - ay
        self.put_rates(self.key(step, "d", step["key"]), _t_sqrt(dx * dx + dy * dy), False)

    def step_expression(self, step: Mapping) -> None:
        """A formula of the user's: no rates (the workbook writes none either)."""


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------

EXTREME_STEP = 1.0    # degrees: the reference's sampling of a turn to find an extreme's basin
REVERSAL_STEP = 0.1   # degrees: ... to count an output's reversals


def refined_extreme(description: Mapping, params: Mapping[str, float], key: str,
                    angles: np.ndarray, values: np.ndarray, pick: Callable,
                    rounds: int = 6) -> tuple[float, float]:
    """(input angle, value) of column `key`'s extreme (`pick`: np.argmax or np.argmin) over
    sampled `angles`, refined by resampling 21 points around the best one, tenfold finer each
    round (six rounds from a 1° sampling: 1e-6°; the value is then exact to round-off)."""
    params = positions_only(params)
    i = int(pick(values))
    angle = float(angles[i])
    width = float(np.max(np.diff(angles))) if len(angles) > 1 else EXTREME_STEP
    for _ in range(rounds):
        near = np.linspace(angle - width, angle + width, 21)
        v = np.asarray(solve(description, params, near)[key], dtype=float)
        if not np.isfinite(v).all():
            break
        i = int(pick(v))
        angle, width = float(near[i]), width / 10.0
    value = float(np.asarray(solve(description, params, np.array([angle]))[key])[0])
    return angle, value


def positions_only(params: Mapping[str, float]) -> dict:
    """The parameters without the input's speed and acceleration: solve() then skips motion."""
    rates = {name for pair in _MOTION_PARAMS.values() for name in pair}
    return {k: v for k, v in params.items() if k not in rates}


def _sign_changes(values: np.ndarray) -> int:
    """How often a sampled run of values turns back (flat steps skipped)."""
    steps = np.diff(values)
    steps = steps[steps != 0.0]
    return int(np.count_nonzero(np.sign(steps[1:]) != np.sign(steps[:-1])))


def _reversals(description, params, key: str, angles: np.ndarray, values: np.ndarray) -> int:
    """How often the output turns back over the sampled turn, looking 100 times closer
    wherever it nearly stops (a local minimum of its step): a pair of reversals narrower than
    the sampling (a dead centre just inside the swing) hides there."""
    steps = np.abs(np.diff(np.append(values, values[0])))
    slow = np.nonzero((steps <= np.roll(steps, 1)) & (steps <= np.roll(steps, -1)))[0]
    if len(slow) > 50:          # an output that barely moves: no quick-return ratio
        return -1
    count, step = 0, float(angles[1] - angles[0])
    for i in slow:
        near = np.linspace(angles[i] - step, angles[i] + 2 * step, 301)
        count += _sign_changes(np.asarray(solve(description, params, near)[key], dtype=float))
    return count


def time_ratio(description: Mapping, params: Mapping[str, float], key: str) -> float:
    """A quick-return ratio measured on the motion, not from any formula: column `key` (an
    output that moves forward and back once per turn of the input) over a turn sampled every
    REVERSAL_STEP; the input angles of its two reversals (its refined maximum and minimum) split
    the turn into the longer and the shorter stroke: longer / shorter. NaN where some sampled
    angle cannot close, or where the output reverses other than twice per turn."""
    params = positions_only(params)
    angles = np.arange(0.0, 360.0, REVERSAL_STEP)
    values = np.asarray(solve(description, params, angles)[key], dtype=float)
    if not np.isfinite(values).all():
        return math.nan
    if _reversals(description, params, key, angles, values) != 2:
        return math.nan
    top, _ = refined_extreme(description, params, key, angles, values, np.argmax, rounds=5)
    low, _ = refined_extreme(description, params, key, angles, values, np.argmin, rounds=5)
    one = (low - top) % 360.0
    return max(one, 360.0 - one) / min(one, 360.0 - one)


# --------------------------------------------------------------------------------------------
# The drawing's sliders: guides and blocks (docs/mechanisms.md, "Drawings")
# --------------------------------------------------------------------------------------------

BLOCK = (0.8, 0.4)     # a block's length along its line and its width, in grid squares


def slider_drawing(description: Mapping, params: Mapping[str, float], sweep: Mapping,
                   now: Mapping, square: float) -> dict[str, Point]:
    """The drawn points of every sliding block and the line it slides on, measured on solved
    points: {name: (x, y)} at the positions of `now` (a solve() result), a line's extent taken
    from the block's travel over `sweep` (another). A guide runs along its line over the
    block's smallest to largest position; a block is a
    rectangle centred on the point it is pivoted at, its long side along its line, corners
    counter-clockwise from behind-right ("B block 1" … "B block 4"). Slider R on a line through
    T: "R guide 1", "R guide 2"; slide B (the block at P): the line through B across the link,
    on P's side; slot P: its fixed line ("P guide") and the slot ("P slot"), the block along
    the fixed line."""
    half_long, half_across = BLOCK[0] / 2 * square, BLOCK[1] / 2 * square
    at, over = now["points"], sweep["points"]
    out: dict[str, Point] = {}

    def guide(name: str, origin: str, mover: str, line: Callable) -> None:
        """The line through `origin` over the travel of the block on `mover`."""
        (tx, ty), (dx, dy), (mx, my) = over[origin], line(sweep), over[mover]
        travel = np.asarray((mx - tx) * dx + (my - ty) * dy, dtype=float)
        travel = travel[np.isfinite(travel)]
        lo, hi = (travel.min(), travel.max()) if travel.size else (math.nan, math.nan)
        (ox, oy), (ux, uy) = at[origin], line(now)
        for k, reach in ((1, lo), (2, hi)):
            out[f"{name} {k}"] = (ox + reach * ux, oy + reach * uy)

    def block(centre: str, line: Callable) -> None:
        (cx, cy), (dx, dy) = at[centre], line(now)
        for k, (u, v) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1)), start=1):
            out[f"{centre} block {k}"] = (cx + u * half_long * dx - v * half_across * dy,
                                          cy + u * half_long * dy + v * half_across * dx)

    for step in _steps(description):
        kind, n = step["type"], step.get("point")
        if kind == "slider":
            line = _slider_line(step, params)
            guide(f"{n} guide", step["through"], n, line)
            block(n, line)
        elif kind == "slide":
            line = _slide_line(step, params)
            guide(f"{n} guide", n, step["p"], line)
            block(step["p"], line)
        elif kind == "slot":
            fixed = _fixed_line(step, params)
            guide(f"{n} guide", step["through"], n, fixed)
            guide(f"{n} slot", step["slot_through"], n, _slot_line(step, params))
            block(n, fixed)
    return out


def slider_parts(description: Mapping) -> list[tuple[str, ...]]:
    """The points of each guide and each block slider_drawing places, part by part: the points
    of one part are joined (a guide is one line, a block one rigid body), whether or not the
    block ever closes."""
    parts: list[tuple[str, ...]] = []
    for step in _steps(description):
        kind, n = step["type"], step.get("point")
        lines = {"slider": ("guide",), "slide": ("guide",), "slot": ("guide", "slot")}.get(kind)
        if lines:
            parts += [(f"{n} {line} 1", f"{n} {line} 2") for line in lines]
            centre = step["p"] if kind == "slide" else n
            parts.append(tuple(f"{centre} block {k}" for k in range(1, 5)))
    return parts


def _unit(x, y) -> tuple:
    r = np.hypot(x, y)
    return x / r, y / r


def _slider_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slider's line direction: fixed at `direction` degrees, or along its link U→V."""
    direction = _scalar(step.get("direction", 0.0), params)
    if "along" not in step:
        d = _cos_sin_deg(direction)
        return lambda solved: d
    u, v = step["along"]
    c, s = _cos_sin_deg(direction)

    def line(solved):
        points = solved["points"]
        ex, ey = _unit(points[v][0] - points[u][0], points[v][1] - points[u][1])
        return ex * c - ey * s, ex * s + ey * c
    return line


def _slide_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slide's line: the direction this module solved for it (θ + b·π/2, θ the link's angle),
    which stays defined where B and P meet or the offset is zero."""
    spec = (step.get("columns") or {}).get("theta_slide")
    key = str(spec.get("key") or "") if isinstance(spec, Mapping) else ""
    key = key or f"theta_slide_{step['point']}"
    return lambda solved: (np.cos(solved[key]), np.sin(solved[key]))


def _fixed_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    d = _cos_sin_deg(_scalar(step.get("direction", 0.0), params))
    return lambda solved: d


def _slot_line(step: Mapping, params: Mapping[str, float]) -> Callable:
    """A slot's direction: angle(A→B) of its frame plus slot_angle."""
    a, b = step["slot_frame"]
    c, s = _cos_sin_deg(_scalar(step.get("slot_angle", 0.0), params))

    def line(solved):
        points = solved["points"]
        fx, fy = _unit(points[b][0] - points[a][0], points[b][1] - points[a][1])
        return fx * c - fy * s, fx * s + fy * c
    return line


def solve(description: Mapping, params: Mapping[str, float], angles_deg) -> dict:
    """Position analysis of a described mechanism at each input angle (degrees, 1-D array-like).

    description: the [mechanism] table of a template as parsed by tomllib (input, ground, steps,
    links, ...); params: {parameter symbol: value} (angle-kind parameters in degrees, branch
    parameters ±1).

    Returns {column key: np.ndarray} for every column of every step, hidden ones included
    (radians, lengths; NaN where the step cannot close or a point it uses is undefined), the
    input key (radians), constants as floats (a carried point's gamma on a rigid frame of known
    length, an expression of the parameters alone), 'assembled': a bool array (every loop step —
    dyad, slider, slide, slot — closes on that row) and 'points': {point name: (x ndarray,
    y ndarray)} for every ground and step point.

    Raises ValueError for a malformed description (unknown step type, unknown point, unknown
    parameter, a branch not ±1, a key written twice, ...).
    """
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    if angles.ndim != 1:
        raise ValueError("angles_deg must be one-dimensional")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        solver = _Solver(description, params, angles)
        out = solver.run()
        speed, accel = _MOTION_PARAMS["angle" if solver.angle_input else "length"]
        if speed in params and accel in params:
            out.update(_Motion(solver, description, float(params[speed]),
                               float(params[accel])).run())
            if solver.angle_input:
                out["rpm_in"] = float(params[speed]) * 30.0 / math.pi   # rad/s in rev/min
        return out


# --------------------------------------------------------------------------------------------
# The four-bar loop of a description (Grashof class, input limit angles)
# --------------------------------------------------------------------------------------------

def _fourbar_parts(description: Mapping, params: Mapping[str, float]) -> list[tuple]:
    """Per four-bar loop on the ground, in step order: (crank pivot (x, y), output pivot (x, y),
    crank length, phase in degrees, coupler, output link).  A loop is a dyad with one end a
    ground point and the other the pin of a crank turning about a ground point."""
    ground = pivots(description, params)
    cranks, loops = {}, []
    for step in _steps(description):
        kind = step["type"]
        if kind == "crank" and step.get("pivot") in ground and step.get("point"):
            cranks.setdefault(step["point"], step)
        elif kind == "dyad":
            for pin, fixed, coupler, rocker in (("p", "q", "p_length", "q_length"),
                                                ("q", "p", "q_length", "p_length")):
                if step.get(fixed) in ground and step.get(pin) in cranks:
                    crank = cranks[step[pin]]
                    loops.append((ground[crank["pivot"]], ground[step[fixed]],
                                  _scalar(crank["length"], params),
                                  _scalar(crank.get("phase", 0), params),
                                  _scalar(step[coupler], params), _scalar(step[rocker], params)))
                    break
    return loops


def fourbar_loops(description: Mapping, params: Mapping[str, float]
                  ) -> list[tuple[float, float, float, float]]:
    """(ground, crank, coupler, output link) lengths of every four-bar loop on the ground."""
    return [(math.hypot(qx - ax, qy - ay), crank, coupler, rocker)
            for (ax, ay), (qx, qy), crank, _, coupler, rocker
            in _fourbar_parts(description, params)]


def grashof_class(ground: float, crank: float, coupler: float, rocker: float) -> str:
    """Grashof's rule, s + l against p + q, and which link is the shortest."""
    links = {"ground": ground, "crank": crank, "coupler": coupler, "rocker": rocker}
    s, l = min(links.values()), max(links.values())
    pq = sum(links.values()) - s - l
    if s + l > pq * (1 + 1e-12):
        return "non-Grashof: triple rocker"
    if s + l >= pq * (1 - 1e-12):
        return "change point"
    shortest = min(links, key=links.get)
    return {"ground": "Grashof: double crank", "crank": "Grashof: crank-rocker",
            "coupler": "Grashof: double rocker", "rocker": "Grashof: rocker-crank"}[shortest]


def limit_angles(description: Mapping, params: Mapping[str, float], length: float,
                 loop: int = 0) -> list[float]:
    """Input angles (degrees, [0, 360), ascending) where four-bar loop number `loop`'s output
    pivot Q is exactly `length` from the crank pin A(θ) (the crank's phase included): found by
    sampling |Q − A(θ)| − length and bisecting each sign change. [] if there is no such loop."""
    parts = _fourbar_parts(description, params)
    if loop >= len(parts):
        return []
    (ax, ay), (qx, qy), r, phase, _, _ = parts[loop]

    def f(deg: float) -> float:
        t = math.radians(deg + phase)
        return math.hypot(qx - ax - r * math.cos(t), qy - ay - r * math.sin(t)) - length

    roots = []
    grid = [i * 0.25 for i in range(1441)]
    values = [f(x) for x in grid]
    for x0, x1, f0, f1 in zip(grid, grid[1:], values, values[1:]):
        if f0 == 0.0:
            roots.append(x0)
        elif f0 * f1 < 0:
            for _ in range(200):
                xm = 0.5 * (x0 + x1)
                fm = f(xm)
                if xm in (x0, x1):
                    break
                x0, f0, x1 = (xm, fm, x1) if f0 * fm > 0 else (x0, f0, xm)
            roots.append(0.5 * (x0 + x1))
    return sorted({round(x % 360.0, 12) for x in roots})
