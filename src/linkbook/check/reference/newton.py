"""Newton–Raphson for the reference's small systems, and the continuation sweep over the rows.

Every loop step of a mechanism is a 1×1 or 2×2 system of constraint residuals in its unknowns.
Newton continues from the previous row's root. On the first row, after a row that could not
close, or when the continued root is on the wrong branch, it restarts from a spread of first
guesses and keeps the first root on the requested branch; a row where none is found is None
(NaN in the columns). An independent existence check (the triangle inequality of a dyad, ...)
is used only to decide to try a denser spread of first guesses, never to produce a value. Next
to a limit position (a double root) Newton converges only linearly and, in plain doubles,
stalls on a plateau of width √ε where the residual rounds to zero: such a root is polished with
a residual that keeps its digits there (see constraints.square_gap), so that a dead centre
reached exactly by the data is found to round-off, not to √ε.

Pure-Python scalar arithmetic is used inside Newton: 1×1 and 2×2 systems are much cheaper that
way than with small numpy calls.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from .geometry import TAU

_WRAP_AT = 4.0 * math.pi

# Newton stops once every step is below _STEP_TOL × the unknown's scale (1 rad for angles, the
# mechanism's size for lengths); quadratic convergence then leaves an error of order _STEP_TOL²
# (round-off). The residual (a length) must also be below RES_TOL × size: a constraint with no
# real solution keeps a residual at least as large as its gap, so it can never pass.
_STEP_TOL = 1e-10
RES_TOL = 1e-9
_MAX_ITER = 40
STARTS = 8          # first guesses for a restart
DENSE_STARTS = 48   # ... when the existence check says the step should close but Newton failed
# Next to a double root (a limit position: |sin| of the angle between the two constraints'
# gradients below NEAR_DOUBLE) Newton converges only linearly and stops early: the root is
# polished with a careful residual, up to _POLISH_ITER more steps, down to steps of _POLISH_TOL.
NEAR_DOUBLE = 1e-4
_POLISH_TOL = 1e-15
_POLISH_ITER = 100
# There the two branches meet: a root less than TANGENT (relative) off the dead-centre line is
# taken as on either branch.
TANGENT = 1e-12

Fun = Callable[[Sequence[float]], tuple[tuple[float, ...], tuple[tuple[float, ...], ...]]]


def linear_solve(jac: Sequence[Sequence[float]], rhs: Sequence[float]) -> list[float] | None:
    """Solve jac · x = rhs; None if singular. 1×1 and 2×2 systems in scalar arithmetic (the
    steps' systems, solved row after row); larger ones (synthesis's loop closure) by LAPACK."""
    if len(rhs) > 2:
        try:
            x = np.linalg.solve(np.asarray(jac, dtype=float), np.asarray(rhs, dtype=float))
        except np.linalg.LinAlgError:
            return None
        return x.tolist() if np.isfinite(x).all() else None
    if len(rhs) == 1:
        d = jac[0][0]
        return None if d == 0.0 else [rhs[0] / d]
    (a, b), (c, d) = jac
    det = a * d - b * c
    if det == 0.0:
        return None
    return [(d * rhs[0] - b * rhs[1]) / det, (a * rhs[1] - c * rhs[0]) / det]


def newton(fun: Fun, x0: Sequence[float], scales: Sequence[float], tol_f: float,
           angle_slots: Sequence[int] = ()) -> list[float] | None:
    """Newton–Raphson from x0. Returns the root, or None when it does not converge."""
    x = list(x0)
    n = len(x)
    for _ in range(_MAX_ITER):
        f, jac = fun(x)
        dx = linear_solve(jac, f)
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
                x[k] = math.remainder(x[k], TAU)
        if worst <= _STEP_TOL:
            # f was taken before this (tiny) step, so it bounds the final residual from above.
            return x if max(abs(v) for v in f) <= tol_f else None
    return None


def polish(fun: Fun, x: Sequence[float], scales: Sequence[float], tol_f: float) -> list[float]:
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
        dx = linear_solve(jac, f)
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


def sweep(
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
        x = newton(fun, x0, scales, tol_f, angle_slots)
        if x is None:
            return None
        if near_double is not None and near_double(i, x):
            x = polish(careful(i) if careful else fun, x, scales, tol_f)
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
            x = restart(fun, i, starts(i, STARTS))
        if x is None and closes is not None and closes(i):
            x = restart(careful(i) if careful else fun, i, starts(i, DENSE_STARTS))
        if x is not None:
            for k in angle_slots:
                x[k] = math.remainder(x[k], TAU)
            prev = tuple(x)
        else:
            prev = None
        out[i] = prev
    return out


def directions(k: int) -> list[float]:
    """k first-guess angles around the circle, offset so none is a special angle."""
    return [0.1 + TAU * j / k for j in range(k)]


def solved_column(sols: list, k: int) -> np.ndarray:
    """Unknown number k of a sweep's roots, row by row: NaN where the row did not close."""
    return np.array([math.nan if x is None else x[k] for x in sols], dtype=float)


def finite(*values: float) -> bool:
    """Every value is a number (neither NaN nor ±inf)."""
    return all(v == v and abs(v) != math.inf for v in values)
