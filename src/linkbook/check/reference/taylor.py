"""Velocity and acceleration by Taylor arithmetic: the constraints differentiated, not solved.

Every quantity is carried as its second-order Taylor expansion in time about each row,
x(t) = a + b·t + c·t²/2 (b the velocity, c the acceleration), element-wise over the rows. A
point placed directly (a crank pin, a carried point) is computed in this arithmetic. A step
whose unknowns z satisfy constraints F(z, known) = 0 is differentiated implicitly (`implicit`):
its Jacobian J = ∂F/∂z comes from seeding each unknown with a unit velocity (the knowns held
still), then ż = −J⁻¹·(the velocity F has with z held still) and z̈ = −J⁻¹·(the acceleration
F has with z moving at ż): J·ż = −(∂F/∂θ)·ω and the once more differentiated system. No
closed form of the workbook's is used; a singular J (a dead centre) gives NaN.
"""

from __future__ import annotations

import numpy as np


class Taylor:
    """a + b·t + c·t²/2, element-wise (numpy arrays or floats).

    c None: first order only (a value and its derivative, what a Jacobian needs), which is what
    an operation gives where either operand carries no c. b may hold several derivatives along a
    leading axis (a Jacobian's columns at once): each is, bit for bit, the one the same
    operations give seeded alone, as every operation on b is element-wise."""
    __slots__ = ("a", "b", "c")

    def __init__(self, a, b=0.0, c=0.0):
        self.a, self.b, self.c = a, b, c

    def __add__(self, o):
        o = lift(o)
        c = None if self.c is None or o.c is None else self.c + o.c
        return Taylor(self.a + o.a, self.b + o.b, c)

    __radd__ = __add__

    def __neg__(self):
        return Taylor(-self.a, -self.b, None if self.c is None else -self.c)

    def __sub__(self, o):
        return self + (-lift(o))

    def __rsub__(self, o):
        return lift(o) - self

    def __mul__(self, o):
        o = lift(o)
        c = None if self.c is None or o.c is None else \
            self.a * o.c + 2.0 * self.b * o.b + self.c * o.a
        return Taylor(self.a * o.a, self.a * o.b + self.b * o.a, c)

    __rmul__ = __mul__

    def __truediv__(self, o):
        o = lift(o)
        q0 = self.a / o.a
        q1 = (self.b - q0 * o.b) / o.a
        c = None if self.c is None or o.c is None else \
            (self.c - 2.0 * q1 * o.b - q0 * o.c) / o.a
        return Taylor(q0, q1, c)


def lift(x) -> Taylor:
    """A number or an array as a Taylor expansion that does not move."""
    return x if isinstance(x, Taylor) else Taylor(x)


def t_sin(x: Taylor) -> Taylor:
    s, c = np.sin(x.a), np.cos(x.a)
    return Taylor(s, c * x.b, None if x.c is None else c * x.c - s * x.b * x.b)


def t_cos(x: Taylor) -> Taylor:
    s, c = np.sin(x.a), np.cos(x.a)
    return Taylor(c, -s * x.b, None if x.c is None else -s * x.c - c * x.b * x.b)


def t_sqrt(x: Taylor) -> Taylor:
    r = np.sqrt(x.a)
    d1 = x.b / (2.0 * r)
    return Taylor(r, d1, None if x.c is None else (x.c - 2.0 * d1 * d1) / (2.0 * r))


def t_atan2(y: Taylor, x: Taylor) -> Taylor:
    r2 = x.a * x.a + y.a * y.a
    d1 = (x.a * y.b - y.a * x.b) / r2
    d2 = None if x.c is None or y.c is None else \
        (x.a * y.c - y.a * x.c) / r2 - 2.0 * d1 * (x.a * x.b + y.a * y.b) / r2
    return Taylor(np.arctan2(y.a, x.a), d1, d2)


def still(x: Taylor) -> Taylor:
    """x held still: its value, no velocity or acceleration."""
    return Taylor(x.a)


# Two constraint gradients closer to parallel than this (the sine of their angle) make a dead
# centre as far as double precision can tell: the solved position itself is only good to about
# √ε there (a double root), so the rates are not determined by the data.
DEAD_CENTRE = 1e-7


def hadamard_ratio(jac: list[list[np.ndarray]]) -> np.ndarray:
    """|det J| over the product of its rows' lengths, per row: 1 where the constraint
    gradients are orthogonal, 0 where they are dependent (for two, the sine between them)."""
    m = np.stack([np.stack(np.broadcast_arrays(*line), axis=-1) for line in jac], axis=-2)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(np.linalg.det(m)) / np.prod(np.linalg.norm(m, axis=-1), axis=-1)


def _t_solve_large(jac: list[list[np.ndarray]], rhs: list[np.ndarray]
                   ) -> tuple[list, np.ndarray]:
    """jac·x = rhs per row for three unknowns or more (LAPACK); NaN and marked where jac is
    singular to within DEAD_CENTRE (its Hadamard ratio)."""
    m = np.stack([np.stack(np.broadcast_arrays(*line), axis=-1) for line in jac], axis=-2)
    b = np.stack(np.broadcast_arrays(*rhs), axis=-1)
    dead = ~(hadamard_ratio(jac) > DEAD_CENTRE)
    safe = np.where(dead[..., None, None], np.eye(len(rhs)), m)
    x = np.linalg.solve(safe, np.where(dead[..., None], 0.0, b)[..., None])[..., 0]
    return [np.where(dead, np.nan, x[..., k]) for k in range(len(rhs))], dead


def t_solve(jac: list[list[np.ndarray]], rhs: list[np.ndarray]) -> tuple[list, np.ndarray]:
    """jac·x = rhs per row; NaN where jac is singular. Also the rows where a 2×2 (or larger)
    jac is singular to within DEAD_CENTRE (the rates there are NaN and marked)."""
    if len(rhs) > 2:
        return _t_solve_large(jac, rhs)
    with np.errstate(divide="ignore", invalid="ignore"):
        if len(rhs) == 1:
            d = jac[0][0]
            dead = d == 0.0
            return [np.where(dead, np.nan, rhs[0] / np.where(dead, 1.0, d))], dead
        (a, b), (c, d) = jac
        det = a * d - b * c
        dead = np.abs(det) <= DEAD_CENTRE * np.hypot(a, b) * np.hypot(c, d)
        safe = np.where(dead, 1.0, det)
        x = (rhs[0] * d - b * rhs[1]) / safe
        y = (a * rhs[1] - c * rhs[0]) / safe
        return [np.where(dead, np.nan, x), np.where(dead, np.nan, y)], dead


def implicit(residuals, z0: list[np.ndarray], knowns: dict, still: dict
             ) -> tuple[list[Taylor], np.ndarray, np.ndarray]:
    """The unknowns z(t) with residuals(z, knowns) = 0, z(0) = z0 (see the section's comment),
    the rows at a dead centre, and per row how far from one (a 2×2 system's sine between its
    gradients, a larger one's Hadamard ratio; 1 for one unknown, whose step measures its
    own)."""
    k = len(z0)
    shape = np.shape(z0[0])
    # every unknown seeded at once, to first order: b's first axis is the Jacobian's column
    seeds = np.eye(k).reshape((k, k) + (1,) * len(shape))
    jac = [[None] * k for _ in range(k)]
    for i, r in enumerate(residuals([Taylor(z0[j], seeds[j], None) for j in range(k)], still)):
        columns = np.broadcast_to(np.asarray(r.b, dtype=float), (k,) + shape)
        for j in range(k):
            jac[i][j] = columns[j]
    first = residuals([Taylor(z) for z in z0], knowns)
    z1, dead = t_solve(jac, [-np.asarray(r.b, dtype=float) for r in first])
    second = residuals([Taylor(z, d) for z, d in zip(z0, z1)], knowns)
    z2, _ = t_solve(jac, [-np.asarray(r.c, dtype=float) for r in second])
    sine = np.ones_like(z0[0], dtype=float)
    if k == 2:      # the sine of the angle between the two constraint gradients
        (a, b), (c, d) = jac
        with np.errstate(divide="ignore", invalid="ignore"):
            sine = np.abs(a * d - b * c) / (np.hypot(a, b) * np.hypot(c, d))
    elif k > 2:     # a group's: how far its gradients are from dependent
        sine = hadamard_ratio(jac)
    return [Taylor(z, d, dd) for z, d, dd in zip(z0, z1, z2)], dead, sine
