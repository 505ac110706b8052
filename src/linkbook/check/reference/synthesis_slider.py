"""Function generation by a slider-crank, three positions (issue 38): the independent reference
for the Synthesis sheet's cells.

Conventions (docs/synthesis.md): the crank turns about A0 at the origin and carries the pin A;
the slider's pin B runs on the line y = e, parallel to +x; s is B's x coordinate (the `slider`
step's `s` with `through` = (0, e) and `direction` = 0). a = crank |A0A| (signed: a negative
crank is the pin turned by 180°), b = coupler |AB|, e = the line's offset (signed). The task:
the slider at s_j when the crank is at θ2_j (radians), j = 1..3.

The writer follows the textbook's linear form, |B_j − A_j|² = b² written as
2a·s_j·cos θ2_j + 2ae·sin θ2_j + (b² − a² − e²) = s_j², three linear equations in
(2a, 2ae, b² − a² − e²) solved by Cramer's rule. This reference shares neither: it solves the
loop closure a·e^{iθ2_j} + b·e^{iθ3_j} = s_j + i·e for (a, b, e, θ3_1..θ3_3) by Newton from a
deterministic grid of first guesses, and requires the converged roots to agree.

NaN (the sheet's #N/A) where no slider-crank exists: the linear form's matrix is near-singular
(cond₂ of its rows [s_j/L·cos θ2_j, sin θ2_j, 1], s in units of L = max |s_j|, above
SINGULAR_COND), or it gives a = 0 (|s_j| all equal: no crank, e undetermined; Newton then finds
no root). b² = |B_j − A_j|² is never negative.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .newton import TANGENT
from .synthesis import SINGULAR_COND, agreed_root, best_fitting

_GUESS_SIZES = tuple(10.0 ** (k / 2.0) for k in range(-2, 7))     # 0.1 .. 10³, √10 apart
_DEGENERATE = 1e-9    # a crank or coupler shorter than this × L: no slider-crank
# The loop also closes at infinity: a line infinitely far off, the coupler perpendicular to it
# (b − |e| finite). Newton's tolerance accepts points far out on that asymptote; a root with b
# beyond this × L is one of them, not a slider-crank (the grid's guesses stop at 10³).
_AT_INFINITY = 1e6


def linear_form(theta2: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The textbook's rows [s_j/L·cos θ2_j, sin θ2_j, 1], right-hand side (s_j/L)² and L: the
    specification of a near-singular task (its condition number), not a route to the answer."""
    scale = float(np.max(np.abs(s)))
    u = s / scale
    return np.column_stack([u * np.cos(theta2), np.sin(theta2), np.ones(3)]), u * u, scale


def _loop_closure(theta2: np.ndarray, s: np.ndarray):
    """The loop closure per point in units of L, unknowns (a, b, e, θ3_1..θ3_3): its real and
    imaginary parts, and their Jacobian."""
    c2, s2 = np.cos(theta2), np.sin(theta2)

    def fun(v):
        a, b, e = v[0], v[1], v[2]
        f, jac = [], []
        for j in range(3):
            c3, s3 = math.cos(v[3 + j]), math.sin(v[3 + j])
            f += [a * c2[j] + b * c3 - s[j], a * s2[j] + b * s3 - e]
            row_re, row_im = [c2[j], c3, 0.0, 0.0, 0.0, 0.0], [s2[j], s3, -1.0, 0.0, 0.0, 0.0]
            row_re[3 + j], row_im[3 + j] = -b * s3, b * c3
            jac += [row_re, row_im]
        return f, jac
    return fun


def _first_guesses(theta2: np.ndarray, s: np.ndarray) -> list[list[float]]:
    """(a, b, e, θ3_j) for a grid of (a, e) in units of L: the coupler vectors A→B each implies
    give θ3_j and b (their mean length); the best-fitting guesses (least spread) first."""
    sizes = np.array([0.0] + [v * sign for v in _GUESS_SIZES for sign in (1.0, -1.0)])
    a, e = (g.ravel()[:, None] for g in np.meshgrid(sizes[1:], sizes, indexing="ij"))
    coupler = s + 1j * e - a * np.exp(1j * theta2)                  # one row per guess
    return best_fitting(a, e, coupler)


def loop_closure_solution(theta2: np.ndarray, s: np.ndarray) -> list[float] | None:
    """(a, b, e, θ3_1..θ3_3) in units of L = 1 (s given in those units), by Newton from the
    first-guess grid; None if no guess converges to a slider-crank."""
    return agreed_root(_loop_closure(theta2, s), _first_guesses(theta2, s), 3,
                       lambda v: min(abs(v[0]), abs(v[1])) > _DEGENERATE
                       and abs(v[1]) < _AT_INFINITY)


def slider_branches(a: float, e: float, theta2: np.ndarray, s: np.ndarray) -> np.ndarray:
    """linkbook's `slider` branch at each point: +1 when B is ahead of the foot of A on the line
    (s_j > a·cos θ2_j), −1 behind; 0 where the coupler stands perpendicular to the line (a dead
    centre: the gap below TANGENT of the coupler's length)."""
    ahead = s - a * np.cos(theta2)
    coupler = np.hypot(ahead, e - a * np.sin(theta2))
    return np.where(np.abs(ahead) <= TANGENT * coupler, 0.0, np.sign(ahead))


def _undesigned(condition: float) -> dict:
    nan3 = np.full(3, math.nan)
    return {"a": math.nan, "b": math.nan, "e": math.nan, "theta3": nan3, "branch": nan3,
            "branch_defect": False, "wrong_branch": False, "full_turn": None,
            "singular": condition > SINGULAR_COND, "condition": condition,
            "ill_determined": False}


def slider_crank_function_generation(theta2: Sequence[float], s: Sequence[float],
                                     branch: int | None = None) -> dict:
    """The slider-crank whose slider is at s_j when its crank is at θ2_j (radians), j = 1..3.

    Returns a dict: a (signed), b, e (signed); `theta3`: the coupler's angle A→B per point;
    `branch` (+1, −1, 0 at a dead centre, per point), `branch_defect`, `wrong_branch` (a
    requested `branch` differs from some point's); `full_turn`: the crank can turn a full
    revolution (b ≥ |a| + |e|); `singular` and `condition` (cond₂ of the linear form);
    `ill_determined`: the loop closure's roots disagree beyond round-off. Every value is NaN
    where no slider-crank exists or its digits are not determined."""
    theta2, s = np.asarray(theta2, dtype=float), np.asarray(s, dtype=float)
    if theta2.shape != (3,) or s.shape != (3,):
        raise ValueError("slider-crank function generation needs three pairs (θ2_j, s_j)")
    if branch not in (None, 1, -1):
        raise ValueError(f"branch must be 1, -1 or None, not {branch!r}")
    m, _, scale = linear_form(theta2, s) if np.any(s) else (None, None, 0.0)
    condition = float(np.linalg.cond(m)) if m is not None else math.inf
    if not condition <= SINGULAR_COND:
        return _undesigned(condition)
    try:
        root = loop_closure_solution(theta2, s / scale)
    except ArithmeticError:
        # roots from different first guesses differ beyond round-off: the task is so near a
        # degenerate one (the coupler across the slider's line at every point, b → ∞) that its
        # design has not the digits a check needs; stated as not designed, and why
        return {**_undesigned(condition), "ill_determined": True}
    if root is None:
        return _undesigned(condition)
    a, b, e = (v * scale for v in root[:3])
    sides = slider_branches(a, e, theta2, s)
    used = set(sides[sides != 0].tolist())
    return {"a": a, "b": b, "e": e, "theta3": np.array(root[3:]), "branch": sides,
            "branch_defect": len(used) > 1,
            "wrong_branch": branch is not None and bool(used - {branch}),
            "full_turn": b >= abs(a) + abs(e), "singular": False, "condition": condition,
            "ill_determined": False}
