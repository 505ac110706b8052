"""The triad's Newton iterations as the book writes them (docs/coupled-loops.md), judged one
iteration at a time: each iteration's residuals, Jacobian and correction are what the
reference's own geometry gives at the book's own iterate (the angle φ of the first binary
link, the angle θ of the ternary's first side), so that a wrong cell is found where it is,
not only where its error reaches the solution.

At an iterate (φ, θ) the joints are placed by the reference's own construction (the ternary's
third joint from its sides by constraints.triangle_apex), the residuals are
(|E − B|² − b²)/2b and (|F − C|² − c²)/2c, the Jacobian their derivatives by Taylor
arithmetic (taylor.py), and the correction LAPACK's solve of J·Δ = r. The first iterate is the
row above's solution (the reference's own), or where the row above did not close (and on the
first row) the sketch's angles. Where the book's iterates are not given (the reference asked
on its own, for a slope), the iterates are the reference's own, from that start.

The book's triad closes on a row where its iterations converge (the last correction at most
TOLERANCE): the reference's solution stands there and is NaN on the other rows (`converged`),
so that a row the written iterations do not reach is #N/A, and the next row starts from the
sketch, in both.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..constraints import triangle_apex
from ..taylor import Taylor, t_cos, t_sin

# ∂/∂φ and ∂/∂θ seeded together (Taylor's b along a leading axis, against the rows)
_SEEDS = (np.array([[1.0], [0.0]]), np.array([[0.0], [1.0]]))
DEFAULT_ITERATIONS = 6      # the language's default (docs/coupled-loops.md)
TOLERANCE = 1e-9            # rad: a row converged where its last correction is at most this


def ternary_frame(sides: list[float], sense: float) -> tuple[float, float]:
    """The third joint in the frame of the first side (its first joint at the origin, the
    second on +x at |side 0|): (u, v), v signed by the link's turning sense."""
    cx, cy = triangle_apex(sides[0], sides[2], sides[1])
    return cx, sense * cy


def _joints(phi, theta, pivot, length, side, frame):
    """D, E, F (Taylor pairs) at the angles φ, θ (Taylor)."""
    u, v = frame
    dx = Taylor(pivot[0]) + length * t_cos(phi)     # Taylor first: not numpy's element loop
    dy = Taylor(pivot[1]) + length * t_sin(phi)
    c, s = t_cos(theta), t_sin(theta)
    ex, ey = dx + side * c, dy + side * s
    fx, fy = dx + u * c - v * s, dy + u * s + v * c
    return (dx, dy), (ex, ey), (fx, fy)


def residuals(phi, theta, pivots, lengths, sides, frame):
    """(r1, r2) at the iterate: (|E − B|² − b²)/2b and (|F − C|² − c²)/2c."""
    _, e, f = _joints(phi, theta, pivots[0], lengths[0], sides[0], frame)
    out = []
    for joint, pivot, length in ((e, pivots[1], lengths[1]), (f, pivots[2], lengths[2])):
        dx, dy = joint[0] - Taylor(pivot[0]), joint[1] - Taylor(pivot[1])
        out.append((dx * dx + dy * dy - length * length) / (2.0 * length))
    return out


def iteration(phi: np.ndarray, theta: np.ndarray, pivots, lengths, sides, frame) -> dict:
    """Residuals, Jacobian and correction at the iterate, per row. The Jacobian's two columns
    are one pass of first-order Taylor arithmetic, seeded in φ and in θ along b's first axis."""
    both = residuals(Taylor(phi, _SEEDS[0], None), Taylor(theta, _SEEDS[1], None),
                     pivots, lengths, sides, frame)
    r = [np.asarray(x.a, dtype=float) for x in both]
    jac = np.stack([np.broadcast_to(x.b, (2,) + r[0].shape).T for x in both], axis=-2)
    det = np.linalg.det(jac)
    ok = np.isfinite(det) & (det != 0.0)
    safe = np.where(ok[:, None, None], jac, np.eye(2))
    step = np.linalg.solve(safe, np.stack(r, axis=-1)[..., None])[..., 0]
    step = np.where(ok[:, None], step, math.nan)
    return {"r1": r[0], "r2": r[1], "J11": jac[:, 0, 0], "J12": jac[:, 0, 1],
            "J21": jac[:, 1, 0], "J22": jac[:, 1, 1], "dphi": step[:, 0], "dth": step[:, 1]}


def start(solved, pivots, sketch: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Each row's first iterate: the row above's solution where it closed, else the sketch's
    angles (from the row's own pivot of the first binary link)."""
    (dx, dy), (ex, ey) = solved[0], solved[1]
    ax, ay = pivots[0]
    above_phi = np.roll(np.arctan2(dy - ay, dx - ax), 1)
    above_theta = np.roll(np.arctan2(ey - dy, ex - dx), 1)
    closed = np.isfinite(above_phi) & np.isfinite(above_theta)
    closed[0] = False
    phi0 = np.arctan2(sketch[1] - ay, sketch[0] - ax)
    theta0 = np.full_like(phi0, math.atan2(sketch[3] - sketch[1], sketch[2] - sketch[0]))
    return np.where(closed, above_phi, phi0), np.where(closed, above_theta, theta0)


def iteration_columns(n: str, count: int, solved, pivots, lengths, sides, frame, sketch,
                      shown: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Every iteration column of the triad whose first joint is `n`, keyed as the book keys
    them; `shown`: the book's own iterates where known (reference.solve's `turns`)."""
    out: dict[str, np.ndarray] = {}
    phi, theta = start(solved, pivots, sketch)
    step = {}
    for k in range(count):
        out[f"phi_{k}_{n}"], out[f"th_{k}_{n}"] = phi, theta
        at_phi = shown.get(f"phi_{k}_{n}", phi)
        at_theta = shown.get(f"th_{k}_{n}", theta)
        step = iteration(np.asarray(at_phi, dtype=float), np.asarray(at_theta, dtype=float),
                         pivots, lengths, sides, frame)
        for name, value in step.items():
            out[f"{name}_{k}_{n}"] = value
        phi, theta = at_phi - step["dphi"], at_theta - step["dth"]
    out[f"conv_{n}"] = np.maximum(np.abs(step["dphi"]), np.abs(step["dth"]))
    return out


def _closed(solved) -> np.ndarray:
    """Per row: whether the three joints `solved` are placed (the group closed there)."""
    return np.isfinite(solved[0][0]) & np.isfinite(solved[1][0]) & np.isfinite(solved[2][0])


def converged(n: str, count: int, solved, pivots, lengths, sides, frame, sketch,
              shown: Mapping[str, np.ndarray]) -> tuple[dict[str, np.ndarray], list]:
    """The iteration columns, and the solved joints kept only on the rows where the written
    iterations converge. A row dropped makes the next row start from the sketch, which may
    change whether that one converges: repeated until no row changes."""
    closed = _closed(solved)
    while True:
        kept = [(np.where(closed, x, math.nan), np.where(closed, y, math.nan))
                for x, y in solved]
        columns = iteration_columns(n, count, kept, pivots, lengths, sides, frame, sketch,
                                    shown)
        still = closed & (columns[f"conv_{n}"] <= TOLERANCE)
        if (still == closed).all():
            return columns, kept
        closed = still


SAME = 1e-6         # rad: two solutions of the group this close in (φ, θ) are one assembly


def book_method(count: int, n_rows: int, pivots, lengths, sides, frame, sketch, solved
                ) -> tuple[np.ndarray, np.ndarray]:
    """The book's own method in the reference's arithmetic, independent of the book's cells:
    row by row, `count` corrections from the row above's converged solution (the sketch's
    angles on the first row and after a row that did not converge); per row the solution's
    (φ, θ), NaN where the last correction is above TOLERANCE. From the sketch it may reach
    another assembly than the six-coordinate continuation `solved` (`other_assembly`)."""
    first = [(np.broadcast_to(np.asarray(x, dtype=float), (n_rows,)),
              np.broadcast_to(np.asarray(y, dtype=float), (n_rows,))) for x, y in pivots]
    alike = _where_the_continuation_leads(count, first, lengths, sides, frame, sketch, solved)
    if alike is not None:
        return alike
    phi0, theta0 = start([(np.full(n_rows, math.nan),) * 2] * 2, first, sketch)
    phis, thetas = np.full(n_rows, math.nan), np.full(n_rows, math.nan)
    above = None
    for row in range(n_rows):
        at = [(x[row:row + 1], y[row:row + 1]) for x, y in first]
        phi, theta = (np.array([phi0[row]]), np.array([theta0[row]])) if above is None \
            else above
        step = {"dphi": np.array([math.nan]), "dth": np.array([math.nan])}
        for _ in range(count):
            step = iteration(phi, theta, at, lengths, sides, frame)
            phi, theta = phi - step["dphi"], theta - step["dth"]
        done = max(abs(step["dphi"][0]), abs(step["dth"][0])) <= TOLERANCE
        above = (phi, theta) if done else None
        if done:
            phis[row], thetas[row] = phi[0], theta[0]
    return phis, thetas


def _where_the_continuation_leads(count: int, pivots, lengths, sides, frame, sketch, solved):
    """book_method's answer in one pass over all rows, when the book's method keeps to the
    continuation `solved`: every row's corrections started, as the book starts them, from the
    row above's solution where it closed and from the sketch where it did not, with the
    continuation's solution standing for the book's own above. If each row then converges
    exactly where the continuation closed, to its assembly, that is what the book's method
    does row by row (the two starts differ by the convergence's last digits); else None, and
    the rows are followed one by one."""
    phi, theta = start(solved, pivots, sketch)
    step = {"dphi": phi * math.nan, "dth": theta * math.nan}
    for _ in range(count):
        step = iteration(phi, theta, pivots, lengths, sides, frame)
        phi, theta = phi - step["dphi"], theta - step["dth"]
    with np.errstate(invalid="ignore"):
        done = np.maximum(np.abs(step["dphi"]), np.abs(step["dth"])) <= TOLERANCE
    closed = _closed(solved)
    if (done != closed).any() or other_assembly(np.where(done, phi, math.nan), theta, solved,
                                                 pivots).any():
        return None
    return np.where(done, phi, math.nan), np.where(done, theta, math.nan)


RESTARTED, CONTINUED = 2, 1     # other_assembly's codes of a row in another assembly


def _turn_apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a − b| of two angles, whole turns left out (at most π)."""
    return np.abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def other_assembly(phi: np.ndarray, theta: np.ndarray, solved, pivots) -> np.ndarray:
    """Per row: 0 where the book's method (book_method's φ, θ) reaches the continuation's
    solution `solved` (the joints) or none; where it reaches one the continuation has not,
    RESTARTED if that row started from the sketch, else CONTINUED (from the row above)."""
    (dx, dy), (ex, ey) = solved[0], solved[1]
    ax, ay = pivots[0]
    with np.errstate(invalid="ignore"):
        apart = np.maximum(_turn_apart(np.arctan2(dy - ay, dx - ax), phi),
                           _turn_apart(np.arctan2(ey - dy, ex - dx), theta))
        other = np.isfinite(phi) & ~(apart <= SAME)
    restarted = ~np.isfinite(np.roll(phi, 1))
    restarted[0] = True
    return np.where(other, np.where(restarted, RESTARTED, CONTINUED), 0)
