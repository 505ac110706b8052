"""Motion generation and path generation with prescribed timing by a four-bar, three positions
(issue 38): the independent reference for the Synthesis sheet's cells.

Conventions (docs/synthesis.md): a pose j is the position P_j = (x_j, y_j) of the coupler point
and the angle α_j of a line on the coupler, counter-clockwise from +x, radians. The crank turns
about A0 and carries the pin A; the rocker turns about B0 and carries the joint B; the coupler
is A–B–P. a = |A0A|, b = |AB|, c = |B0B|, d = |A0B0|. A dyad is a fixed pivot G and a moving
pivot M of the coupler; its rotation ρ_j is the angle its link turns through from pose 1 to
pose j (the textbook's β_j for the crank, γ_j for the rocker).

The writer follows the textbook's standard dyad form, W·(e^{iβ_j} − 1) + Z·(e^{iα_j} − 1) = δ_j
(W = A − A0, Z = P − A at pose 1, δ_j = P_j − P_1), solved for W and Z by Cramer's rule. This
reference shares neither the unknowns nor the method. It finds the pivots' positions themselves:
  - rotations given: the coupler's displacement from pose 1 to pose j carries M to where the
    dyad's rotation by ρ_j about G carries it, G + e^{iρ_j}(M − G) = P_j + e^{iΔα_j}(M − P_1)
    (Δα_j = α_j − α_1), two complex equations, linear in (G, M), solved by numpy's solve;
  - fixed pivot given: M's three positions are equidistant from G, |M_j − G|² = |M_1 − G|²,
    two real equations, linear in M, solved by numpy's lstsq.
Path generation with prescribed timing is motion generation whose coupler rotations α_j are
free choices and whose crank rotations β_j are the task.

A design that does not exist is NaN throughout (the sheet's #N/A): the standard form's matrix
(or the circle condition's) is near-singular, or a link comes out of zero length.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .fourbar import grashof_class
from .synthesis import SINGULAR_COND, assembly

# A crank, coupler, rocker or ground shorter than this, in units of the task's size (the
# largest distance between its pivots and points), is a degenerate root (a pin on its pivot:
# two equal poses give one): no four-bar.
DEGENERATE = 1e-9


def _three(values: Sequence[float], name: str) -> np.ndarray:
    out = np.asarray(values, dtype=float)
    if out.shape != (3,):
        raise ValueError(f"{name} needs three values, not {len(out)}")
    return out


def _poses(x: Sequence[float], y: Sequence[float], alpha: Sequence[float]
           ) -> tuple[np.ndarray, np.ndarray]:
    """The coupler point's positions as complex numbers and the coupler's rotations from pose 1."""
    alpha = _three(alpha, "alpha")
    return _three(x, "x") + 1j * _three(y, "y"), alpha - alpha[0]


def standard_form_condition(turn: np.ndarray, rotation: np.ndarray) -> float:
    """cond₂ of the textbook's standard dyad form's matrix [e^{iρ_j} − 1, e^{iΔα_j} − 1],
    j = 2, 3: the specification of a near-singular dyad (the sheet's determinant against its
    scale), whatever route solves it."""
    m = np.column_stack([np.exp(1j * rotation[1:]) - 1.0, np.exp(1j * turn[1:]) - 1.0])
    return float(np.linalg.cond(m))


def _minus_one(turn: np.ndarray) -> np.ndarray:
    """e^{iθ} − 1 without cancellation at small θ: 2i·sin(θ/2)·e^{iθ/2}."""
    return 2j * np.sin(0.5 * turn) * np.exp(0.5j * turn)


def dyad_from_rotations(points: np.ndarray, turn: np.ndarray, rotation: np.ndarray
                        ) -> tuple[complex, complex] | None:
    """(G, M): the fixed pivot and the moving pivot at pose 1 of the dyad that turns through
    `rotation` (ρ_1 = 0, ρ_2, ρ_3) while the coupler turns through `turn` (Δα_j) and its point
    passes through `points`. Pose j in the rotation about G and in the coupler's displacement,
    measured from P_1 (g = G − P_1, m = M − P_1, δ_j = P_j − P_1, so that poses far from the
    origin lose no digits): (1 − e^{iρ_j})·g + (e^{iρ_j} − e^{iΔα_j})·m = δ_j. None if
    singular."""
    spin, swing = _minus_one(rotation[1:]), _minus_one(turn[1:])
    m = np.column_stack([-spin, spin - swing])
    try:
        g, moving = np.linalg.solve(m, points[1:] - points[0])
    except np.linalg.LinAlgError:
        return None
    return complex(points[0] + g), complex(points[0] + moving)


def circle_condition(points: np.ndarray, turn: np.ndarray, fixed: complex
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The rows and right-hand side of |M_j − G|² = |M_1 − G|², j = 2, 3, in the unknown
    m = M − P_1 (real, 2-vector): with e_j = P_j − G and M_j = P_j + e^{iΔα_j}·m,
    2·(e^{−iΔα_j}·e_j − e_1)·m = |e_1|² − |e_j|². Both sides are written in the poses'
    differences δ_j = P_j − P_1, so that close poses lose no digits to cancellation:
    e^{−iΔα_j}·e_j − e_1 = e^{−iΔα_j}·δ_j + (e^{−iΔα_j} − 1)·e_1 and
    |e_1|² − |e_j|² = −δ_j·(e_1 + e_j)."""
    first, delta = points[0] - fixed, points[1:] - points[0]
    rows = 2.0 * (np.exp(-1j * turn[1:]) * delta + _minus_one(-turn[1:]) * first)
    rhs = -(delta.real * (2.0 * first + delta).real + delta.imag * (2.0 * first + delta).imag)
    return np.column_stack([rows.real, rows.imag]), rhs


def dyad_from_fixed_pivot(points: np.ndarray, turn: np.ndarray, fixed: complex
                          ) -> tuple[complex, float]:
    """(M, condition): the moving pivot at pose 1 whose three positions lie on a circle about
    the given fixed pivot, by lstsq of the circle condition; M is NaN where that is
    near-singular. Close poses make its entries small differences of larger terms, so its
    condition counts what they lose: (the largest term of a row + of the right-hand side / |m|)
    over the smallest singular value, the solution's relative error per unit round-off."""
    m, rhs = circle_condition(points, turn, fixed)
    first, delta = abs(points[0] - fixed), np.abs(points[1:] - points[0])
    row_terms = 2.0 * (delta + np.abs(_minus_one(turn[1:])) * first)
    rhs_terms = delta * (2.0 * first + delta)
    smallest = float(np.linalg.svd(m, compute_uv=False)[-1])
    if not smallest > 0.0:
        return complex(math.nan, math.nan), math.inf
    u = np.linalg.lstsq(m, rhs, rcond=None)[0]
    reach = max(math.hypot(*u), 1e-300)
    condition = float((row_terms.max() + rhs_terms.max() / reach) / smallest)
    if not condition <= SINGULAR_COND:
        return complex(math.nan, math.nan), condition
    return complex(points[0] + complex(u[0], u[1])), condition


def _turned(start: complex, now: np.ndarray) -> np.ndarray:
    """The angle a link turns through from its first position, in (−π, π]."""
    return np.angle(now / start)


_NAN2 = (math.nan, math.nan)


def _undesigned(condition: float, reason: str) -> dict:
    """The result when no four-bar exists: every value NaN."""
    nan3 = np.full(3, math.nan)
    return {"A0": _NAN2, "B0": _NAN2, "A": _NAN2, "B": _NAN2, "W": _NAN2, "Z": _NAN2,
            "U": _NAN2, "S": _NAN2, "a": math.nan, "b": math.nan, "c": math.nan,
            "d": math.nan, "coupler_point": _NAN2, "coupler_offset": math.nan,
            "theta2": nan3, "theta3": nan3, "theta4": nan3, "crank_rotation": nan3,
            "rocker_rotation": nan3, "branch": nan3, "branch_defect": False,
            "wrong_branch": False, "grashof": None, "singular": reason == "singular",
            "degenerate": reason == "degenerate", "condition": condition}


def _xy(z: complex) -> tuple[float, float]:
    return float(z.real), float(z.imag)


def four_bar(points: np.ndarray, alpha: np.ndarray, crank: tuple[complex, complex],
             rocker: tuple[complex, complex], condition: float,
             branch: int | None = None) -> dict:
    """The four-bar of the two dyads (fixed pivot, moving pivot at pose 1) whose coupler point
    passes through `points` with the coupler at angles `alpha`, measured pose by pose."""
    (a0, a1), (b0, b1) = crank, rocker
    turn = alpha - alpha[0]
    carried = np.exp(1j * turn)
    pins, joints = points + carried * (a1 - points[0]), points + carried * (b1 - points[0])
    a, b, c, d = abs(a1 - a0), abs(b1 - a1), abs(b1 - b0), abs(b0 - a0)
    size = max(a, b, c, d, float(np.max(np.abs(points - points[0]))))
    if not all(math.isfinite(v) for v in (a, b, c, d)):
        return _undesigned(condition, "singular")
    if min(a, b, c, d) <= DEGENERATE * size:
        return _undesigned(condition, "degenerate")
    coupler = joints - pins
    along = (points[0] - a1) / (coupler[0] / b)        # P − A in the frame A→B
    sides = assembly(pins, joints, b0)
    used = set(sides[sides != 0].tolist())
    return {"A0": _xy(a0), "B0": _xy(b0), "A": _xy(a1), "B": _xy(b1),
            "W": _xy(a1 - a0), "Z": _xy(points[0] - a1), "U": _xy(b1 - b0),
            "S": _xy(points[0] - b1), "a": a, "b": b, "c": c, "d": d,
            "coupler_point": _xy(along),
            "coupler_offset": float(math.remainder(alpha[0] - np.angle(coupler[0]), math.tau)),
            "theta2": np.angle(pins - a0), "theta3": np.angle(coupler),
            "theta4": np.angle(joints - b0),
            "crank_rotation": _turned(a1 - a0, pins - a0),
            "rocker_rotation": _turned(b1 - b0, joints - b0),
            "branch": sides, "branch_defect": len(used) > 1,
            "wrong_branch": branch is not None and bool(used - {branch}),
            "grashof": grashof_class(d, a, b, c), "singular": False, "degenerate": False,
            "condition": condition}


def _check_branch(branch: int | None) -> None:
    if branch not in (None, 1, -1):
        raise ValueError(f"branch must be 1, -1 or None, not {branch!r}")


def motion_generation(x: Sequence[float], y: Sequence[float], alpha: Sequence[float],
                      crank_rotation: Sequence[float] | None = None,
                      rocker_rotation: Sequence[float] | None = None,
                      crank_pivot: tuple[float, float] | None = None,
                      rocker_pivot: tuple[float, float] | None = None,
                      branch: int | None = None) -> dict:
    """The four-bar whose coupler point passes through (x_j, y_j) with the coupler at angle α_j
    (radians), j = 1..3. Either the free choices of the textbook, the crank's rotations
    (β2, β3) and the rocker's (γ2, γ3), or the fixed pivots A0 and B0, each per dyad.

    branch: the assembly the task asks for (+1 open, −1 crossed), or None.

    Returns a dict: A0, B0, and A, B at pose 1, as (x, y); W = A − A0, Z = P − A, U = B − B0,
    S = P − B at pose 1 (the textbook's dyad vectors); a, b, c, d; `coupler_point`: P in the
    coupler's frame, (u along A→B, v to its left); `coupler_offset`: α_1 − angle(A→B);
    `theta2`, `theta3`, `theta4`: angle(A0→A), angle(A→B), angle(B0→B) per pose;
    `crank_rotation`, `rocker_rotation`: the links' rotations from pose 1 (0 first);
    `branch` (+1 open, −1 crossed, 0 dead centre, per pose), `branch_defect`, `wrong_branch`,
    `grashof`; `singular`, `degenerate` (then everything is NaN) and `condition`, the larger
    of the two dyads' condition numbers (the standard form's, or the circle condition's)."""
    _check_branch(branch)
    points, turn = _poses(x, y, alpha)
    crank, crank_condition = _dyad(points, turn, crank_rotation, crank_pivot, "crank")
    rocker, rocker_condition = _dyad(points, turn, rocker_rotation, rocker_pivot, "rocker")
    return four_bar(points, _three(alpha, "alpha"), crank, rocker,
                    max(crank_condition, rocker_condition), branch)


def _dyad(points: np.ndarray, turn: np.ndarray, rotation: Sequence[float] | None,
          pivot: tuple[float, float] | None, name: str) -> tuple[tuple[complex, complex], float]:
    """((G, M), condition) of one dyad from its rotations or its fixed pivot; G and M NaN
    where its system is near-singular."""
    if (rotation is None) == (pivot is None):
        raise ValueError(f"the {name} needs either its rotations or its fixed pivot")
    if pivot is not None:
        fixed = complex(*pivot)
        moving, condition = dyad_from_fixed_pivot(points, turn, fixed)
        return (fixed, moving), condition
    rotation = np.concatenate([[0.0], _two(rotation, f"{name}_rotation")])
    condition = standard_form_condition(turn, rotation)
    solved = dyad_from_rotations(points, turn, rotation) if condition <= SINGULAR_COND else None
    return solved or (complex(math.nan, math.nan),) * 2, condition


def _two(values: Sequence[float], name: str) -> np.ndarray:
    out = np.asarray(values, dtype=float)
    if out.shape != (2,):
        raise ValueError(f"{name} needs two values (positions 2 and 3), not {len(out)}")
    return out


def path_generation(x: Sequence[float], y: Sequence[float], crank_rotation: Sequence[float],
                    coupler_rotation: Sequence[float], rocker_rotation: Sequence[float],
                    branch: int | None = None) -> dict:
    """The four-bar whose coupler point passes through (x_j, y_j), j = 1..3, when the crank has
    turned through β2, β3 from the first point (prescribed timing, radians). The free choices:
    the coupler's rotations (α2, α3) and the rocker's (γ2, γ3). The result as
    motion_generation's, with the coupler's angle α_1 = 0 (so `coupler_offset` is −θ3_1)."""
    alpha = np.concatenate([[0.0], _two(coupler_rotation, "coupler_rotation")])
    return motion_generation(x, y, alpha, crank_rotation=crank_rotation,
                             rocker_rotation=rocker_rotation, branch=branch)
