"""Function generation by a four-bar (issue 38): the independent reference for the Synthesis
sheet's cells.

Conventions (docs/synthesis.md): A0 at the origin, B0 at (d, 0); a = crank |A0A|, b = coupler
|AB|, c = rocker |B0B|; θ2 the angle of A0→A, θ4 of B0→B, both from +x, counter-clockwise, in
radians. Freudenstein's equation in Norton's form, the objective of the least-squares case:

    K1·cos θ4 − K2·cos θ2 + K3 = cos(θ2 − θ4),  K1 = d/a, K2 = d/c, K3 = (a² − b² + c² + d²)/(2ac)

The writer solves the three-point case by Cramer's rule and turns the coefficients into
lengths; this reference shares neither: with three points it solves the loop closure itself,
a·e^{iθ2_j} + b·e^{iθ3_j} − d − c·e^{iθ4_j} = 0 for (a, b, c, θ3_1..θ3_3), by Newton from a
deterministic grid of first guesses, and requires the converged roots to agree. Beyond three
points the least-squares objective on Freudenstein's residual is the specification: it is solved
by numpy's lstsq (an orthogonal factorisation, not the normal equations), and the tests check at
three points that it gives the loop closure's solution.

a and c come out signed, as the equations give them (a negative one is reported, not hidden);
a quantity that does not exist is NaN (the sheet's #N/A): everything solved where the system
is near-singular, a or c where its coefficient is 0, b where b² < 0. That last only by round-off
(b ≈ 0): |d + c·e^{iθ4_j} − a·e^{iθ2_j}|² = b² + 2ac·(residual_j), and the residual sums to zero
(exactly at three points; by least squares, whose residual is orthogonal to the constant
column, beyond), so b² is the mean of those squared lengths.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from .fourbar import grashof_class
from .newton import RES_TOL, TANGENT, newton

SPACINGS = ("chebyshev", "equal")
# Near-singular: cond₂ of the system's matrix [cos θ4, −cos θ2, 1] above this. Two correct
# solutions of a system differ by up to about cond·ε (ε = 2.2e-16) relative; verify holds the
# book's cells to 1e-9, so beyond 1e6 (cond·ε ≈ 2e-10, a safety factor of five left) the
# coefficients no longer have the digits a check needs and the design is not stated at all.
SINGULAR_COND = 1e6
# First guesses for (a, c) in units of d (each sign), the coupler's angles and b then made to
# fit them; the guesses nearest to closing the loop are tried first.
_GUESS_SIZES = tuple(10.0 ** (k / 2.0) for k in range(-2, 9))     # 0.1 .. 10⁴, √10 apart
_AGREE = 3            # converged roots compared before one is accepted
_AGREE_TOL = 1e-7     # relative: the roots of one system differ by round-off only
# a = c = 0, b = d, θ3 = 0 closes every loop: no linkage. A root with a crank or rocker below
# this (in units of d) is that one, or next to it, and is set aside.
_DEGENERATE = 1e-6


def precision_points(f: Callable[[np.ndarray], np.ndarray], x0: float, x1: float, n: int,
                     spacing: str = "chebyshev", given: Sequence[float] | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(x, y = f(x)) at the n precision points of [x0, x1].

    chebyshev: x_j = (x0 + x1)/2 − (x1 − x0)/2·cos((2j − 1)π/(2n)), j = 1..n (ascending);
    equal: x_j = x0 + (j − 1)(x1 − x0)/(n − 1); `given`: those x values (spacing ignored).
    f is a callable over numpy arrays."""
    if given is not None:
        x = np.asarray(given, dtype=float)
    elif spacing == "chebyshev":
        j = np.arange(1, n + 1)
        x = 0.5 * (x0 + x1) - 0.5 * (x1 - x0) * np.cos((2 * j - 1) * math.pi / (2 * n))
    elif spacing == "equal":
        if n < 2:
            raise ValueError("equal spacing needs at least 2 points")
        x = x0 + np.arange(n) * (x1 - x0) / (n - 1)
    else:
        raise ValueError(f"spacing must be one of {', '.join(SPACINGS)}, not {spacing!r}")
    return x, np.asarray(f(x), dtype=float)


def precision_angles(f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, x0: float,
                     x1: float, theta2_start: float, theta2_span: float,
                     theta4_start: float, theta4_span: float) -> tuple[np.ndarray, np.ndarray]:
    """(θ2_j, θ4_j) in radians: x and y = f(x) mapped linearly onto the input and output
    ranges (start and signed span), x0 → θ2_start, f(x0) → θ4_start."""
    x = np.asarray(x, dtype=float)
    y0, y1 = (float(v) for v in np.asarray(f(np.array([x0, x1], dtype=float)), dtype=float))
    theta2 = theta2_start + (x - x0) / (x1 - x0) * theta2_span
    theta4 = theta4_start + (np.asarray(f(x), dtype=float) - y0) / (y1 - y0) * theta4_span
    return theta2, theta4


def freudenstein_matrix(theta2: np.ndarray, theta4: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows [cos θ4, −cos θ2, 1] and the right-hand side cos(θ2 − θ4): M·(K1, K2, K3) = r."""
    m = np.column_stack([np.cos(theta4), -np.cos(theta2), np.ones_like(theta2)])
    return m, np.cos(theta2 - theta4)


def _loop_closure(theta2: np.ndarray, theta4: np.ndarray):
    """The loop closure at the precision points, d = 1, unknowns (a, b, c, θ3_1..θ3_n): per
    point its real and imaginary parts, and their Jacobian."""
    c2, s2, c4, s4 = np.cos(theta2), np.sin(theta2), np.cos(theta4), np.sin(theta4)
    n = len(theta2)

    def fun(u):
        a, b, c = u[0], u[1], u[2]
        f, jac = [], []
        for j in range(n):
            c3, s3 = math.cos(u[3 + j]), math.sin(u[3 + j])
            f += [a * c2[j] + b * c3 - 1.0 - c * c4[j], a * s2[j] + b * s3 - c * s4[j]]
            row_re, row_im = [c2[j], c3, -c4[j]] + [0.0] * n, [s2[j], s3, -s4[j]] + [0.0] * n
            row_re[3 + j], row_im[3 + j] = -b * s3, b * c3
            jac += [row_re, row_im]
        return f, jac
    return fun


def _first_guesses(theta2: np.ndarray, theta4: np.ndarray) -> list[list[float]]:
    """(a, b, c, θ3_j) for a grid of (a, c), d = 1: the coupler vector A→B each guess implies at
    each point gives θ3_j and b (its mean length); ordered by how far the implied coupler lengths
    spread (the best-fitting guesses first)."""
    sizes = np.array([s * sign for s in _GUESS_SIZES for sign in (1.0, -1.0)])
    a, c = (g.ravel()[:, None] for g in np.meshgrid(sizes, sizes, indexing="ij"))
    coupler = 1.0 + c * np.exp(1j * theta4) - a * np.exp(1j * theta2)   # one row per guess
    return best_fitting(a, c, coupler)


def best_fitting(a: np.ndarray, other: np.ndarray, coupler: np.ndarray) -> list[list[float]]:
    """Guesses (a, b, other, θ3_j) from the coupler vectors A→B each implies (one row per
    guess): b their mean length, θ3_j their angles; the least spread of lengths first."""
    lengths = np.abs(coupler)
    b = lengths.mean(axis=1)
    spread = np.ptp(lengths, axis=1) / np.maximum(b, 1e-300)
    guesses = np.column_stack([a[:, 0], b, other[:, 0], np.angle(coupler)])
    return guesses[np.argsort(spread, kind="stable")].tolist()


def normalised(u: list[float]) -> list[float]:
    """The same root (a, b, c or e, θ3_j…) with b ≥ 0 (b and θ3 + π describe the same coupler),
    angles in (−π, π]."""
    a, b, c, *theta3 = u
    if b < 0.0:
        b, theta3 = -b, [t + math.pi for t in theta3]
    return [a, b, c] + [math.remainder(t, 2.0 * math.pi) for t in theta3]


def loop_closure_solution(theta2: np.ndarray, theta4: np.ndarray) -> list[float] | None:
    """(a, b, c, θ3_1..θ3_n) with d = 1 solving the loop closure at n = 3 precision points, by
    Newton from the first-guess grid; None if no guess converges to a linkage.
    The first _AGREE roots found must agree (the three-point system has one solution)."""
    n = len(theta2)
    return agreed_root(_loop_closure(theta2, theta4), _first_guesses(theta2, theta4), n,
                       lambda u: min(abs(u[0]), abs(u[1]), abs(u[2])) > _DEGENERATE)


def agreed_root(fun, guesses, n: int, accept) -> list[float] | None:
    """Newton on `fun` (three lengths, then n angles) from each first guess in turn; the roots
    `accept` takes, normalised; the first of them once _AGREE agree (one solution, found from
    several guesses), None if none is found. Roots that disagree beyond round-off raise
    ArithmeticError."""
    roots = []
    for guess in guesses:
        size = max(1.0, *(abs(v) for v in guess[:3]))     # Newton's steps judged against it
        u = newton(fun, guess, [size] * 3 + [1.0] * n, RES_TOL * size,
                   angle_slots=tuple(range(3, 3 + n)))
        if u is not None and accept(u):
            roots.append(normalised(u))
            if len(roots) == _AGREE:
                break
    if not roots:
        return None
    first = np.array(roots[0][:3])
    for other in roots[1:]:
        if np.max(np.abs(np.array(other[:3]) - first)) > _AGREE_TOL * max(1.0, *abs(first)):
            raise ArithmeticError(f"the loop closure's roots disagree: {roots[0]} and {other}")
    return roots[0]


def _lengths_from_coefficients(k: np.ndarray, d: float) -> tuple[float, float, float]:
    """(a, b, c) from K1 = d/a, K2 = d/c and K3's definition; NaN where none exists."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a, c = d / k[0], d / k[1]
        b2 = a * a + c * c + d * d - 2.0 * a * c * k[2]
    a, c = (float(v) if math.isfinite(v) else math.nan for v in (a, c))
    return a, math.sqrt(b2) if b2 >= 0.0 else math.nan, c


def _coefficients(a: float, b: float, c: float, d: float) -> np.ndarray:
    """K1, K2, K3 by their definitions."""
    return np.array([d / a, d / c, (a * a - b * b + c * c + d * d) / (2.0 * a * c)])


def assembly(pin, joint, pivot) -> np.ndarray:
    """linkbook's dyad branch of a four-bar from its points (complex numbers or arrays): the
    crank pin A, the coupler-rocker joint B and the rocker's pivot B0. The sign of
    cross(B − B0, A − B0): +1 open, −1 crossed; 0 at a dead centre, where both meet (the cross
    product below TANGENT of its sides' product, as the position reference takes it)."""
    rocker, reach = np.asarray(joint) - pivot, np.asarray(pin) - pivot
    cross = (np.conj(rocker) * reach).imag
    flat = np.abs(cross) <= TANGENT * np.abs(rocker) * np.abs(reach)
    return np.where(flat, 0.0, np.sign(cross))


def _branches(a: float, c: float, d: float, theta2: np.ndarray, theta4: np.ndarray
              ) -> np.ndarray:
    """The assembly at each point of the linkage with A0 at the origin and B0 at (d, 0)."""
    return assembly(a * np.exp(1j * theta2), d + c * np.exp(1j * theta4), d)


def _transmission_cosine(a: float, b: float, c: float, d: float, theta2) -> np.ndarray:
    """cos μ, μ = ∠ABB0 the transmission angle, at crank angles θ2 (the same on both
    branches): beyond ±1 where the loop cannot close."""
    s2 = a * a + d * d - 2.0 * a * d * np.cos(np.asarray(theta2, dtype=float))
    return (b * b + c * c - s2) / (2.0 * b * abs(c))


def transmission_cosines(a: float, b: float, c: float, d: float, start: float, span: float
                         ) -> np.ndarray:
    """cos μ where the transmission angle can take its extremes while the crank turns from
    `start` through the signed `span` (radians). |A − B0| is monotone in θ2 between multiples
    of π, and μ monotone in |A − B0|: the extremes are at the ends or at such a multiple inside
    the range."""
    lo, hi = sorted((start, start + span))
    inner = np.arange(math.ceil(lo / math.pi), math.floor(hi / math.pi) + 1) * math.pi
    return _transmission_cosine(a, b, c, d, np.concatenate([[lo, hi], inner]))


def transmission_range(a: float, b: float, c: float, d: float, start: float, span: float
                       ) -> tuple[float, float]:
    """(smallest, largest) transmission angle (interior, [0, π]) while the crank turns from
    `start` through the signed `span` (radians), or (NaN, NaN) where the loop cannot close
    somewhere on the way."""
    cosine = transmission_cosines(a, b, c, d, start, span)
    if not (np.abs(cosine) <= 1.0).all():
        return math.nan, math.nan
    mu = np.arccos(cosine)
    return float(mu.min()), float(mu.max())


def _undesigned(d: float, n: int, condition: float) -> dict:
    """The result for a near-singular system: nothing designed."""
    nan3 = np.full(3, math.nan)
    return {"a": math.nan, "b": math.nan, "c": math.nan, "d": d, "K1": math.nan,
            "K2": math.nan, "K3": math.nan, "coefficients": nan3,
            "residual": np.full(n, math.nan), "theta3": np.full(n, math.nan),
            "branch": np.full(n, math.nan), "branch_defect": False, "wrong_branch": False,
            "grashof": None, "transmission": (math.nan, math.nan),
            "transmission_turn": (math.nan, math.nan), "singular": True,
            "condition": condition, "solved_by": None}


def function_generation(theta2: Sequence[float], theta4: Sequence[float], d: float,
                        branch: int | None = None,
                        input_range: tuple[float, float] | None = None) -> dict:
    """The four-bar whose output angle is θ4_j when its input angle is θ2_j (radians, n ≥ 3
    points; exact for 3, least squares of Freudenstein's residual beyond), ground length d.

    branch: the assembly the task asks for (+1 open, −1 crossed, as linkbook's dyad means it),
    or None; input_range: (start, signed span) of the crank in radians, by default the span of
    the precision points.

    Returns a dict: a, b, c, d (a and c signed; NaN where they do not exist); K1, K2, K3 and
    `coefficients` (the three as an array); `residual`: Freudenstein's residual per point;
    `theta3`: the coupler's angle (A→B) per point; `branch`: the linkage's assembly at each
    point (+1 open, −1 crossed, 0 at a dead centre, NaN where there is no linkage);
    `branch_defect`: the points need different assemblies; `wrong_branch`: a requested `branch`
    differs from some point's; `grashof`: Grashof's class (text, None without a linkage);
    `transmission`: (min, max) transmission angle over the input range, `transmission_turn`:
    over a full turn of the crank ((NaN, NaN) where the loop cannot close on the way);
    `singular`: the system is near-singular (cond₂ > SINGULAR_COND: then every solved value is
    NaN); `condition`: that condition number; `solved_by`: "loop closure" (Newton, n = 3) or
    "least squares" (lstsq: n > 3, or Newton found no root at n = 3, which the tests forbid)."""
    theta2, theta4 = np.asarray(theta2, dtype=float), np.asarray(theta4, dtype=float)
    n = len(theta2)
    if n < 3 or len(theta4) != n:
        raise ValueError("function generation needs n ≥ 3 pairs of angles (θ2_j, θ4_j)")
    if branch not in (None, 1, -1):
        raise ValueError(f"branch must be 1, -1 or None, not {branch!r}")
    m, rhs = freudenstein_matrix(theta2, theta4)
    condition = float(np.linalg.cond(m))
    if not condition <= SINGULAR_COND:
        return _undesigned(d, n, condition)
    root = loop_closure_solution(theta2, theta4) if n == 3 else None
    if root is not None:
        a, b, c = (v * d for v in root[:3])
        k = _coefficients(a, b, c, d)
        theta3 = np.array(root[3:])
        solved_by = "loop closure"
    else:
        k = np.linalg.lstsq(m, rhs, rcond=None)[0]
        a, b, c = _lengths_from_coefficients(k, d)
        coupler = d + c * np.exp(1j * theta4) - a * np.exp(1j * theta2)
        theta3 = np.angle(coupler) if math.isfinite(b) else np.full(n, math.nan)
        solved_by = "least squares"
    exists = all(math.isfinite(v) for v in (a, b, c))
    sides = _branches(a, c, d, theta2, theta4) if exists else np.full(n, math.nan)
    used = set(sides[sides != 0].tolist()) if exists else set()
    start, span = input_range if input_range is not None else (
        float(theta2.min()), float(np.ptp(theta2)))
    return {
        "a": a, "b": b, "c": c, "d": d, "K1": float(k[0]), "K2": float(k[1]),
        "K3": float(k[2]), "coefficients": k, "residual": m @ k - rhs, "theta3": theta3,
        "branch": sides, "branch_defect": len(used) > 1,
        "wrong_branch": branch is not None and bool(used - {branch}),
        "grashof": grashof_class(d, abs(a), b, abs(c)) if exists else None,
        "transmission": transmission_range(a, b, c, d, start, span) if exists
        else (math.nan, math.nan),
        "transmission_turn": transmission_range(a, b, c, d, 0.0, 2.0 * math.pi) if exists
        else (math.nan, math.nan),
        "singular": False, "condition": condition, "solved_by": solved_by}
