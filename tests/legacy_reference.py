"""Independent reference solver: the truth the workbooks are checked against.

Method
------
Every mechanism of ``docs/mechanisms.md`` is analysed from its vector loop-closure equations,
written as residuals ``F(x; input) = 0`` (the real and imaginary parts of each loop) in the
mechanism's position variables ``x`` (θ13/θ14, θ13/s14, r3/r4/r5/θ3, ...). At each input angle, in
the order given, the equations are solved by Newton–Raphson with an analytic Jacobian, the
numerical method of the sources (TK Solver's NewtonN loop, the shaper seed):

* **continuation** — the root at the previous angle is the first guess at the next one;
* **branch** — after convergence the doc's geometric invariant is checked (a dyad on branch 1 has
  ``cross(R − Q, P − Q) > 0``, slider-crank branch 1 has the slider right of the crank pin, lengths
  such as |BA| are positive). On the first row, after rows that could not close, or when the
  continued root lies on the wrong branch, Newton restarts from a spread of first guesses and keeps
  the first root on the requested branch;
* **non-assembly** — a row where Newton converges from no first guess has no real position: its
  keys are NaN and ``assembled`` is False (a quantity fixed by the input angle alone, such as the
  crank pin, keeps its value). An independent distance check (is a dyad's ground
  distance inside [|p − q|, p + q]? ...) is only used to confirm: when it says the loop should
  close, a denser set of first guesses is tried before giving up.

Mechanisms solved in steps (pump, quick-return, garage door) run one Newton sweep per loop, the
later loop taking the earlier one's solved joints as known.

Derived quantities (s, ϕ, ψ, μ, η, ξ, ...) are measured on the solved joints: distances, np.arctan2
of joint-to-joint vectors and interior angles from dot and cross products — never the workbook's
cosine-theorem steps. Nothing here is imported from, or shared with, the rest of linkbook.

Pure-Python scalar arithmetic is used inside Newton (2×2 and 4×4 systems are faster that way than
with small numpy calls); the keys are then assembled with vectorised numpy.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np

__all__ = ["MECHANISMS", "PARAMETERS", "pivots", "solve"]

MECHANISMS: tuple[str, ...] = (
    "fourbar",
    "slider-crank",
    "pump",
    "inverted-slider-crank",
    "quick-return",
    "shaper",
    "garage-door",
    "tk-fourbar",
)

# Parameter symbols per mechanism, as listed in docs/mechanisms.md.
PARAMETERS: dict[str, tuple[str, ...]] = {
    "fourbar": ("a1", "a2", "a3", "a4", "b3", "c3", "branch"),
    "slider-crank": ("a1", "a2", "a3", "b3", "gamma3", "branch"),
    "pump": ("a2", "a3", "a4", "b1", "c4", "s1", "branch"),
    "inverted-slider-crank": ("a1", "a2", "a4", "branch"),
    "quick-return": ("a1", "a2", "a4", "a5", "b1", "branch"),
    "shaper": ("r1", "r2", "r6"),
    "garage-door": ("a1", "a2", "a3", "a4", "b2", "a5", "a6", "branch", "branch_door"),
    "tk-fourbar": ("a", "b", "c", "m", "n", "x3", "y3", "branch"),
}

_BRANCH_KEYS = ("branch", "branch_door")
_TAU = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
_WRAP_AT = 4.0 * math.pi

# Newton stops once every step is below _STEP_TOL × the unknown's scale (1 rad for angles, the
# mechanism's size for lengths); quadratic convergence then leaves an error of order _STEP_TOL²
# (round-off). The residual must also be below _RES_TOL × size: a loop with no real solution keeps
# a residual at least as large as its gap, so it can never pass.
_STEP_TOL = 1e-10
_RES_TOL = 1e-9
_MAX_ITER = 40
_STARTS = 8          # first-guess directions for a restart
_DENSE_STARTS = 48   # ... when the distance check says the loop should close but Newton failed

Fun = Callable[[Sequence[float]], tuple[tuple[float, ...], tuple[tuple[float, ...], ...]]]


# --------------------------------------------------------------------------------------------
# Newton–Raphson and the continuation sweep
# --------------------------------------------------------------------------------------------

def _linear_solve(jac: Sequence[Sequence[float]], rhs: Sequence[float]) -> list[float] | None:
    """Solve jac · x = rhs; None if singular. Cramer for 2×2, pivoted elimination otherwise."""
    if len(rhs) == 2:
        (a, b), (c, d) = jac
        det = a * d - b * c
        if det == 0.0:
            return None
        return [(d * rhs[0] - b * rhs[1]) / det, (a * rhs[1] - c * rhs[0]) / det]
    n = len(rhs)
    m = [list(row) + [rhs[k]] for k, row in enumerate(jac)]
    for col in range(n):
        piv = max(range(col, n), key=lambda r: abs(m[r][col]))
        if m[piv][col] == 0.0:
            return None
        m[col], m[piv] = m[piv], m[col]
        for r in range(col + 1, n):
            f = m[r][col] / m[col][col]
            if f:
                for c2 in range(col, n + 1):
                    m[r][c2] -= f * m[col][c2]
    x = [0.0] * n
    for r in range(n - 1, -1, -1):
        acc = m[r][n] - sum(m[r][c2] * x[c2] for c2 in range(r + 1, n))
        x[r] = acc / m[r][r]
    return x


def _newton(fun: Fun, x0: Sequence[float], scales: Sequence[float], tol_f: float,
            angle_slots: Sequence[int] = ()) -> list[float] | None:
    """Newton–Raphson from x0. Returns the root, or None when it does not converge."""
    x = list(x0)
    n = len(x)
    for _ in range(_MAX_ITER):
        f, jac = fun(x)
        dx = _linear_solve(jac, f)
        if dx is None:
            return None
        worst = 0.0
        for k in range(n):
            x[k] -= dx[k]
            r = abs(dx[k]) / scales[k]
            if r > worst or r != r:  # r != r: NaN, which then sticks
                worst = r
        if not worst < math.inf:  # NaN or overflow: diverged
            return None
        for k in angle_slots:
            # A wild early step can throw an angle many turns away, where a double keeps only
            # ~1e-12 rad of absolute precision: bring it back before the final steps.
            if abs(x[k]) > _WRAP_AT:
                x[k] = math.remainder(x[k], _TAU)
        if worst <= _STEP_TOL:
            # f was taken before this (tiny) step, so it bounds the final residual from above.
            return x if max(abs(v) for v in f) <= tol_f else None
    return None


def _wrap(x: list[float], angle_slots: Sequence[int]) -> tuple[float, ...]:
    """Angles into [−π, π] so that continuation does not drift by whole turns."""
    for k in angle_slots:
        x[k] = math.remainder(x[k], _TAU)
    return tuple(x)


def _sweep(
    n_rows: int,
    system: Callable[[int], Fun | None],
    starts: Callable[[int, int], Iterable[Sequence[float]]],
    on_branch: Callable[[int, Sequence[float]], bool],
    scales: Sequence[float],
    angle_slots: Sequence[int],
    tol_f: float,
    closes: Callable[[int], bool] | None = None,
) -> list[tuple[float, ...] | None]:
    """Solve one loop row after row by Newton with continuation; None where it cannot close.

    system(i) gives row i's residual function (None: skip the row, an earlier loop failed there);
    starts(i, k) yields first guesses (k directions); on_branch(i, x) is the branch invariant;
    closes(i), optional, is the independent distance check used to trigger a denser restart.
    """
    out: list[tuple[float, ...] | None] = [None] * n_rows
    prev: tuple[float, ...] | None = None
    for i in range(n_rows):
        fun = system(i)
        if fun is None:
            prev = None
            continue
        x = None
        if prev is not None:
            x = _newton(fun, prev, scales, tol_f, angle_slots)
            if x is not None and not on_branch(i, x):
                x = None
        if x is None:
            x = _restart(fun, starts(i, _STARTS), i, on_branch, scales, angle_slots, tol_f)
        if x is None and closes is not None and closes(i):
            x = _restart(fun, starts(i, _DENSE_STARTS), i, on_branch, scales, angle_slots, tol_f)
        prev = None if x is None else _wrap(x, angle_slots)
        out[i] = prev
    return out


def _dyad_sweep(n_rows: int, q_at: Callable[[int], tuple[float, float] | None],
                p_at: Callable[[int], tuple[float, float]], q: float, p: float, branch: int,
                tol_f: float) -> list[tuple[float, ...] | None]:
    """One dyad over all rows: R with |QR| = q, |PR| = p; x = (angle(Q→R), angle(P→R)).
    q_at(i) is None where an earlier loop left Q undefined."""
    def system(i):
        qi = q_at(i)
        return None if qi is None else _dyad_loop(*qi, *p_at(i), q, p)

    return _sweep(
        n_rows, system, _dyad_starts(branch),
        lambda i, x: _dyad_side(*q_at(i), *p_at(i), x[0], branch),
        (1.0, 1.0), (0, 1), tol_f,
        lambda i: _dyad_closes(math.dist(q_at(i), p_at(i)), p, q),
    )


def _restart(fun, guesses, i, on_branch, scales, angle_slots, tol_f) -> list[float] | None:
    """Multi-start: the first converged root on the requested branch."""
    for x0 in guesses:
        x = _newton(fun, x0, scales, tol_f, angle_slots)
        if x is not None and on_branch(i, x):
            return x
    return None


def _directions(k: int) -> list[float]:
    """k first-guess angles around the circle, offset so none is a special angle."""
    return [0.1 + _TAU * j / k for j in range(k)]


# --------------------------------------------------------------------------------------------
# Loop types: residual F and Jacobian dF/dx of each kind of vector loop
# --------------------------------------------------------------------------------------------

def _dyad_loop(qx: float, qy: float, px: float, py: float, q: float, p: float) -> Fun:
    """Loop Q + q·e^{iα} = P + p·e^{iβ} (R reached from both known points), x = (α, β).

    α = angle(Q→R), β = angle(P→R)."""
    dx, dy = qx - px, qy - py

    def fun(x):
        ca, sa = math.cos(x[0]), math.sin(x[0])
        cb, sb = math.cos(x[1]), math.sin(x[1])
        return ((dx + q * ca - p * cb, dy + q * sa - p * sb),
                ((-q * sa, p * sb), (q * ca, -p * cb)))

    return fun


def _dyad_starts(branch: int) -> Callable[[int, int], list[tuple[float, float]]]:
    """First guesses for a dyad. cross(R − Q, P − Q) = q·p·sin(α − β), so β = α − branch·π/2
    starts on the requested side; the dense restart adds the mirrored guesses too."""
    def starts(_i: int, k: int) -> list[tuple[float, float]]:
        dirs = _directions(k)
        same = [(a, a - branch * _HALF_PI) for a in dirs]
        return same if k <= _STARTS else same + [(a, a + branch * _HALF_PI) for a in dirs]
    return starts


def _dyad_side(qx: float, qy: float, px: float, py: float, alpha: float, branch: int) -> bool:
    """Branch invariant of a dyad: branch · cross(R − Q, P − Q) > 0, R − Q ∥ e^{iα}."""
    return branch * (math.cos(alpha) * (py - qy) - math.sin(alpha) * (px - qx)) > 0.0


def _dyad_closes(d: float, p: float, q: float) -> bool:
    """Independent check: a triangle with sides d, p, q exists."""
    return abs(p - q) <= d <= p + q


def _slider_loop(kx: float, ky: float, h: float, length: float) -> Fun:
    """Loop K = S + l·e^{iθ}: a link of length l from the known pin K to a slider pin S = (s, h)
    on the line y = h; x = (θ, s), θ = angle(S→K)."""
    def fun(x):
        c, s = math.cos(x[0]), math.sin(x[0])
        return ((kx - x[1] - length * c, ky - h - length * s),
                ((length * s, -1.0), (-length * c, 0.0)))
    return fun


def _slider_starts(kx: Callable[[int], float]) -> Callable[[int, int], list[tuple[float, float]]]:
    def starts(i: int, k: int) -> list[tuple[float, float]]:
        return [(a, kx(i)) for a in _directions(k)]
    return starts


def _slider_side(theta: float, branch: int) -> bool:
    """Branch 1: the slider pin is right of the crank pin, i.e. cos(angle(S→K)) < 0."""
    return -branch * math.cos(theta) > 0.0


def _polar_loop(vx: float, vy: float) -> Fun:
    """Loop V = r·e^{iθ} (a block sliding on a line through the origin), x = (r, θ)."""
    def fun(x):
        c, s = math.cos(x[1]), math.sin(x[1])
        return ((vx - x[0] * c, vy - x[0] * s),
                ((-c, x[0] * s), (-s, -x[0] * c)))
    return fun


def _polar_starts(r0: float) -> Callable[[int, int], list[tuple[float, float]]]:
    def starts(_i: int, k: int) -> list[tuple[float, float]]:
        return [(r0, a) for a in _directions(k)]
    return starts


# --------------------------------------------------------------------------------------------
# Geometry on solved joints (vectorised)
# --------------------------------------------------------------------------------------------

def _interior(ux, uy, vx, vy):
    """Interior angle between vectors u and v, in [0, π]."""
    return np.arctan2(np.abs(ux * vy - uy * vx), ux * vx + uy * vy)


def _column(sols: list, k: int) -> np.ndarray:
    return np.array([math.nan if x is None else x[k] for x in sols], dtype=float)


def _solved(sols: list) -> np.ndarray:
    return np.array([x is not None for x in sols], dtype=bool)


def _finish(out: dict, assembled: np.ndarray, input_key: str, constants: Iterable[str] = (),
            on_loop: Iterable[str] = ()) -> dict:
    """Add the 'assembled' mask (every loop closes).

    Each quantity is NaN exactly where a loop it depends on cannot close: that comes from the
    solved unknowns being NaN there and propagating through the arithmetic, so a quantity fixed
    by the input alone (the crank pin, |B0A|) keeps its value. Keys that are constant by
    construction but belong to a joint that only exists when the loop closes (a slider pin's y
    on its line) are listed in `on_loop` and masked explicitly.
    """
    skip = {input_key, *constants}
    for key, val in out.items():
        if key not in skip:
            out[key] = np.asarray(val, dtype=float)
    for key in on_loop:
        out[key] = np.where(assembled, out[key], np.nan)
    out["assembled"] = assembled
    return out


def _triangle_apex(base: float, left: float, right: float) -> tuple[float, float]:
    """Point C with |AC| = left, |BC| = right, A = (0, 0), B = (base, 0), y ≥ 0, by Newton;
    (nan, nan) if no such triangle."""
    def fun(x):
        return ((x[0] ** 2 + x[1] ** 2 - left ** 2, (x[0] - base) ** 2 + x[1] ** 2 - right ** 2),
                ((2 * x[0], 2 * x[1]), (2 * (x[0] - base), 2 * x[1])))
    size = max(base, left, right, 1e-300)
    x = _newton(fun, (0.5 * base, size), (size, size), _RES_TOL * size * size)
    if x is None:
        return math.nan, math.nan
    return x[0], abs(x[1])


# --------------------------------------------------------------------------------------------
# Mechanisms
# --------------------------------------------------------------------------------------------

def _fourbar(p: dict, th: np.ndarray) -> dict:
    a1, a2, a3, a4, b3, c3 = (p[k] for k in ("a1", "a2", "a3", "a4", "b3", "c3"))
    br = int(p["branch"])
    size = a1 + a2 + a3 + a4
    ax, ay = (a2 * np.cos(th)).tolist(), (a2 * np.sin(th)).tolist()
    # Loop a2·e^{iθ12} + a3·e^{iθ13} = a1 + a4·e^{iθ14}: dyad Q = B0, P = A, x = (θ14, θ13).
    sols = _dyad_sweep(len(th), lambda i: (a1, 0.0), lambda i: (ax[i], ay[i]), a4, a3, br,
                       _RES_TOL * size)
    ok = _solved(sols)
    t14, t13 = _column(sols, 0), _column(sols, 1)
    xA, yA = a2 * np.cos(th), a2 * np.sin(th)
    xB, yB = a1 + a4 * np.cos(t14), a4 * np.sin(t14)
    xs, ys = xA - a1, yA
    # Coupler point: C solved in the frame of A→B (left of it, on both branches: the coupler is
    # rigid); γ = ∠BAC is the angle of that local vector. No such triangle: γ and C are NaN, the
    # loop itself (assembled) is unaffected.
    cx, cy = _triangle_apex(a3, b3, c3)
    gamma = math.atan2(cy, cx)
    xC, yC = xA + b3 * np.cos(t13 + gamma), yA + b3 * np.sin(t13 + gamma)
    out = {
        "theta12": th, "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": np.arctan2(ys, xs),
        "mu": _interior(xA - xB, yA - yB, a1 - xB, -yB),
        "psi": _interior(xs, ys, xB - a1, yB),
        "theta14": t14, "theta13": t13,
        "xA": xA, "yA": yA, "xB": xB, "yB": yB, "xC": xC, "yC": yC,
        "gamma": gamma,
    }
    return _finish(out, ok, "theta12", ("gamma",))


def _slider_crank(p: dict, th: np.ndarray) -> dict:
    a1, a2, a3, b3 = (p[k] for k in ("a1", "a2", "a3", "b3"))
    g3 = math.radians(p["gamma3"])
    br = int(p["branch"])
    size = abs(a1) + a2 + a3
    ax, ay = (a2 * np.cos(th)).tolist(), (a2 * np.sin(th)).tolist()
    # Loop a2·e^{iθ12} = s14 + i·a1 + a3·e^{iθ13}, x = (θ13, s14).
    sols = _sweep(
        len(th),
        lambda i: _slider_loop(ax[i], ay[i], a1, a3),
        _slider_starts(lambda i: ax[i]),
        lambda i, x: _slider_side(x[0], br),
        (1.0, size), (0,), _RES_TOL * size,
        lambda i: abs(ay[i] - a1) <= a3,
    )
    ok = _solved(sols)
    t13, s14 = _column(sols, 0), _column(sols, 1)
    xB, yB = s14, np.full_like(th, a1)
    out = {
        "theta12": th, "theta13": t13, "s14": s14,
        "xA": a2 * np.cos(th), "yA": a2 * np.sin(th), "xB": xB, "yB": yB,
        "xC": xB + b3 * np.cos(t13 - g3), "yC": yB + b3 * np.sin(t13 - g3),
    }
    return _finish(out, ok, "theta12", on_loop=("yB",))


def _pump(p: dict, th: np.ndarray) -> dict:
    a2, a3, a4, b1, c4, s1 = (p[k] for k in ("a2", "a3", "a4", "b1", "c4", "s1"))
    br = int(p["branch"])
    size = a2 + a3 + a4 + abs(b1) + abs(c4) + abs(s1)
    qx, qy = -b1, s1  # B0
    ax, ay = (a2 * np.cos(th)).tolist(), (a2 * np.sin(th)).tolist()
    # Loop 1, four-bar A0ABB0: A + a3·e^{iθ13} = B0 + a4·e^{i(θ14 + π/2)}, x = (θ14 + π/2, θ13).
    arm = _dyad_sweep(len(th), lambda i: (qx, qy), lambda i: (ax[i], ay[i]), a4, a3, br,
                      _RES_TOL * size)
    t14 = [None if x is None else x[0] - _HALF_PI for x in arm]
    # Loop 2, double slide: c4·e^{iθ14} + i·s4·e^{iθ14} = −i·s1 − s15 + b1, x = (s4, s15).
    slide = _sweep(
        len(th),
        lambda i: None if t14[i] is None else _pump_slot_loop(t14[i], c4, b1, s1),
        lambda i, k: [(0.0, b1)],
        lambda i, x: True,
        (size, size), (), _RES_TOL * size,
    )
    ok = _solved(slide)
    alpha, s4, s15 = _column(arm, 0), _column(slide, 0), _column(slide, 1)
    theta14 = alpha - _HALF_PI
    xA, yA = a2 * np.cos(th), a2 * np.sin(th)
    xB, yB = qx + a4 * np.cos(alpha), qy + a4 * np.sin(alpha)
    xa, ya = xA - qx, yA - qy
    out = {
        "theta12": th, "xa": xa, "ya": ya, "s": np.hypot(xa, ya), "phi": np.arctan2(ya, xa),
        "psi": _interior(xa, ya, xB - qx, yB - qy),
        "theta14": theta14, "s4": s4, "s15": s15,
        "xA": xA, "yA": yA, "xB": xB, "yB": yB,
        "xE": qx + c4 * np.cos(theta14), "yE": qy + c4 * np.sin(theta14),
        "xP": -s15, "yP": np.zeros_like(th),
    }
    return _finish(out, ok, "theta12", on_loop=("yP",))


def _pump_slot_loop(t14: float, c4: float, b1: float, s1: float) -> Fun:
    """Residual of c4·e^{iθ14} + i·s4·e^{iθ14} − (b1 − s15 − i·s1), x = (s4, s15) (linear)."""
    c, s = math.cos(t14), math.sin(t14)

    def fun(x):
        return ((c4 * c - x[0] * s - b1 + x[1], c4 * s + x[0] * c + s1),
                ((-s, 1.0), (c, 0.0)))

    return fun


def _inverted_loop(vx: float, vy: float, a4: float, br: int) -> Fun:
    """Residual of (a4 + i·branch·s)·e^{iθ14} − V with V = B0→A, x = (θ14, s)."""
    def fun(x):
        c, sn = math.cos(x[0]), math.sin(x[0])
        bs = br * x[1]
        return ((vx - a4 * c + bs * sn, vy - a4 * sn - bs * c),
                ((a4 * sn + bs * c, br * sn), (-a4 * c + bs * sn, -br * c)))
    return fun


def _inverted_slider_crank(p: dict, th: np.ndarray) -> dict:
    a1, a2, a4 = (p[k] for k in ("a1", "a2", "a4"))
    br = int(p["branch"])
    size = a1 + a2 + a4
    vx, vy = (a2 * np.cos(th) - a1).tolist(), (a2 * np.sin(th)).tolist()
    # Loop a2·e^{iθ12} = a1 + a4·e^{iθ14} + s·e^{i(θ14 + branch·π/2)}, x = (θ14, s), s > 0.
    sols = _sweep(
        len(th),
        lambda i: _inverted_loop(vx[i], vy[i], a4, br),
        lambda i, k: [(a, size) for a in _directions(k)],
        lambda i, x: x[1] > 0.0,
        (1.0, size), (0,), _RES_TOL * size,
        lambda i: math.hypot(vx[i], vy[i]) >= a4,
    )
    ok = _solved(sols)
    t14, s = _column(sols, 0), _column(sols, 1)
    xA, yA = a2 * np.cos(th), a2 * np.sin(th)
    xB, yB = a1 + a4 * np.cos(t14), a4 * np.sin(t14)
    xp, yp = xA - a1, yA
    out = {
        "theta12": th, "xp": xp, "yp": yp, "p": np.hypot(xp, yp), "phi": np.arctan2(yp, xp),
        # ψ against the direction of link 4, which is defined even for an in-line slide (a4 = 0)
        "psi": _interior(xp, yp, np.cos(t14), np.sin(t14)), "s": s, "theta14": t14,
        "theta13": np.arctan2(yA - yB, xA - xB),
        "xA": xA, "yA": yA, "xB": xB, "yB": yB,
    }
    return _finish(out, ok, "theta12")


def _quick_return_loops(p: dict, th: np.ndarray):
    """Both loops over the crank angles th: [(s43, θ14)], [(θ15, s16)] (None where open)."""
    a1, a2, a4, a5, b1 = (p[k] for k in ("a1", "a2", "a4", "a5", "b1"))
    br = int(p["branch"])
    size = a1 + a2 + a4 + a5 + abs(b1)
    ax, ay = (a2 * np.cos(th)).tolist(), (a1 + a2 * np.sin(th)).tolist()
    # Loop 1, in-line inverted slider-crank: s43·e^{iθ14} = i·a1 + a2·e^{iθ12}, s43 > 0.
    rocker = _sweep(
        len(th), lambda i: _polar_loop(ax[i], ay[i]), _polar_starts(a1),
        lambda i, x: x[0] > 0.0, (size, 1.0), (1,), _RES_TOL * size,
        lambda i: math.hypot(ax[i], ay[i]) > 0.0,
    )
    cx = [None if x is None else a4 * math.cos(x[1]) for x in rocker]
    cy = [None if x is None else a4 * math.sin(x[1]) for x in rocker]
    # Loop 2, slider-crank driven by θ14: a4·e^{iθ14} = s16 + i·b1 + a5·e^{iθ15}, x = (θ15, s16).
    ram = _sweep(
        len(th),
        lambda i: None if cx[i] is None else _slider_loop(cx[i], cy[i], b1, a5),
        _slider_starts(lambda i: cx[i]),
        lambda i, x: _slider_side(x[0], br),
        (1.0, size), (0,), _RES_TOL * size,
        lambda i: abs(cy[i] - b1) <= a5,
    )
    return rocker, ram


def _quick_return(p: dict, th: np.ndarray) -> dict:
    a1, a2, a4, b1 = (p[k] for k in ("a1", "a2", "a4", "b1"))
    rocker, ram = _quick_return_loops(p, th)
    ok = _solved(ram)
    s43, t14 = _column(rocker, 0), _column(rocker, 1)
    t15, s16 = _column(ram, 0), _column(ram, 1)
    out = {
        "theta12": th, "theta14": t14, "s43": s43, "theta15": t15, "s16": s16,
        "xA": a2 * np.cos(th), "yA": a1 + a2 * np.sin(th),
        "xC": a4 * np.cos(t14), "yC": a4 * np.sin(t14),
        "xD": s16, "yD": np.full_like(th, b1),
        "time_ratio": _quick_return_time_ratio(p),
    }
    return _finish(out, ok, "theta12", ("time_ratio",), on_loop=("yD",))


def _quick_return_rate(p: dict, t12: float, rocker, ram) -> float:
    """ds16/dθ12 by implicit differentiation of both loops (dx/dt = −J⁻¹·∂F/∂t)."""
    a1, a2, a4, b1 = (p[k] for k in ("a1", "a2", "a4", "b1"))
    _, j1 = _polar_loop(a2 * math.cos(t12), a1 + a2 * math.sin(t12))(rocker)
    d1 = _linear_solve(j1, (a2 * math.sin(t12), -a2 * math.cos(t12)))  # −∂F1/∂θ12
    t14 = rocker[1]
    _, j2 = _slider_loop(a4 * math.cos(t14), a4 * math.sin(t14), b1, p["a5"])(ram)
    d2 = _linear_solve(j2, (a4 * math.sin(t14), -a4 * math.cos(t14)))  # −∂F2/∂θ14
    if d1 is None or d2 is None:
        return math.nan
    return d2[1] * d1[1]


def _quick_return_time_ratio(p: dict, samples: int = 720) -> float:
    """Forward/return time from the extremes of s16 over a full crank turn; NaN unless the ram
    reverses exactly twice per turn.

    The crank angles where ds16/dθ12 changes sign are bracketed on a grid and bisected (each
    evaluation a Newton solve continued from the bracket), the global max and min of s16 among
    them mark the stroke ends, and the ratio is the longer crank interval between them over the
    shorter one (the slow stroke is the working stroke)."""
    grid = np.linspace(0.0, _TAU, samples, endpoint=False)
    rocker, ram = _quick_return_loops(p, grid)
    if any(x is None for x in ram):
        return math.nan
    rates = [_quick_return_rate(p, t, r1, r2) for t, r1, r2 in zip(grid.tolist(), rocker, ram)]
    crit: list[tuple[float, float]] = []  # (crank angle, s16)
    for k in range(samples):
        k2 = (k + 1) % samples
        g0, g1 = rates[k], rates[k2]
        if g0 == 0.0:
            crit.append((float(grid[k]), ram[k][1]))
        elif g0 * g1 < 0.0:
            t0, t1 = float(grid[k]), float(grid[k]) + _TAU / samples
            crit.append(_bisect_rate(p, t0, t1, g0, rocker[k], ram[k]))
    # One forward and one return stroke per turn means exactly two reversals of the ram; with
    # more (the ram link passing a dead centre inside the rocker's swing) there is no such pair.
    if len(crit) != 2 or any(math.isnan(c[1]) for c in crit):
        return math.nan
    t_max = max(crit, key=lambda c: c[1])[0]
    t_min = min(crit, key=lambda c: c[1])[0]
    one_way = (t_min - t_max) % _TAU
    slow, quick = max(one_way, _TAU - one_way), min(one_way, _TAU - one_way)
    return slow / quick


def _bisect_rate(p, t0, t1, g0, rocker, ram) -> tuple[float, float]:
    """Root of ds16/dθ12 in [t0, t1] by bisection; returns (θ12, s16 there)."""
    br = int(p["branch"])
    a1, a2, a4, a5, b1 = (p[k] for k in ("a1", "a2", "a4", "a5", "b1"))
    size = a1 + a2 + a4 + a5 + abs(b1)
    tol_f = _RES_TOL * size
    x1, x2 = rocker, ram
    for _ in range(60):
        tm = 0.5 * (t0 + t1)
        y1 = _newton(_polar_loop(a2 * math.cos(tm), a1 + a2 * math.sin(tm)), x1,
                     (size, 1.0), tol_f, (1,))
        if y1 is None or y1[0] <= 0.0:
            return tm, math.nan
        y2 = _newton(_slider_loop(a4 * math.cos(y1[1]), a4 * math.sin(y1[1]), b1, a5), x2,
                     (1.0, size), tol_f, (0,))
        if y2 is None or not _slider_side(y2[0], br):
            return tm, math.nan
        x1, x2 = y1, y2
        gm = _quick_return_rate(p, tm, y1, y2)
        if gm == 0.0 or t1 - t0 < 1e-15:
            break
        if (gm < 0.0) == (g0 < 0.0):
            t0, g0 = tm, gm
        else:
            t1 = tm
    return 0.5 * (t0 + t1), x2[1]


def _shaper_loop(t2: float, r1: float, r2: float, r6: float) -> Fun:
    """The seed's equations I–IV as residuals, x = (r3, r4, r5, θ3)."""
    k1, k2 = r1 + r2 * math.sin(t2), r2 * math.cos(t2)

    def fun(x):
        r3, r4, r5, t3 = x
        c, s = math.cos(t3), math.sin(t3)
        return ((k1 - r3 * s, k2 - r3 * c, r1 + r6 - r4 * s, r5 - r4 * c),
                ((-s, 0.0, 0.0, -r3 * c),
                 (-c, 0.0, 0.0, r3 * s),
                 (0.0, -s, 0.0, -r4 * c),
                 (0.0, -c, 1.0, r4 * s)))

    return fun


def _shaper(p: dict, th: np.ndarray) -> dict:
    r1, r2, r6 = p["r1"], p["r2"], p["r6"]
    size = abs(r1) + abs(r2) + abs(r6)
    t2 = th.tolist()
    sols = _sweep(
        len(th),
        lambda i: _shaper_loop(t2[i], r1, r2, r6),
        lambda i, k: [(size, size, 0.0, a) for a in _directions(k)],
        lambda i, x: x[0] > 0.0,  # r3 = |O1A|
        (size, size, size, 1.0), (3,), _RES_TOL * size,
    )
    ok = _solved(sols)
    r3, r4, r5, t3 = (_column(sols, k) for k in range(4))
    out = {
        "theta2": th, "r3": r3, "theta3": t3, "r4": r4, "r5": r5,
        "xA": r2 * np.cos(th), "yA": r1 + r2 * np.sin(th),
        # The ram pin slides on the ram line (equations III–IV): its y is the line's, its x is r5.
        # (r4·sin θ3 would lose digits when the lever lies almost along the line and r4 is huge.)
        "xB": r5, "yB": np.full_like(th, r1 + r6),
    }
    return _finish(out, ok, "theta2", on_loop=("yB",))


def _garage_door(p: dict, th: np.ndarray) -> dict:
    a1, a2, a3, a4, b2, a5, a6 = (p[k] for k in ("a1", "a2", "a3", "a4", "b2", "a5", "a6"))
    br, bd = int(p["branch"]), int(p["branch_door"])
    size = a1 + a2 + a3 + a4 + b2 + a5 + a6
    tol_f = _RES_TOL * size
    c12, s12 = np.cos(th).tolist(), np.sin(th).tolist()
    ax, ay = [a2 * c for c in c12], [a2 * s for s in s12]
    dx, dy = [b2 * c for c in c12], [b2 * s for s in s12]
    # Loop 1, four-bar: dyad Q = B0 = (0, a1), P = A; x = (θ14, θ13).
    fourbar = _dyad_sweep(len(th), lambda i: (0.0, a1), lambda i: (ax[i], ay[i]), a4, a3, br,
                          tol_f)
    bx = [None if x is None else a4 * math.cos(x[0]) for x in fourbar]
    by = [None if x is None else a1 + a4 * math.sin(x[0]) for x in fourbar]
    # Loop 2, door dyad: Q = B, P = D: B + a5·e^{iθ15} = D + a6·e^{iθ16}; x = (θ15, θ16).
    door = _dyad_sweep(len(th), lambda i: None if bx[i] is None else (bx[i], by[i]),
                       lambda i: (dx[i], dy[i]), a5, a6, bd, tol_f)
    ok = _solved(door)
    t14, t13 = _column(fourbar, 0), _column(fourbar, 1)
    t15, t16 = _column(door, 0), _column(door, 1)
    xA, yA = a2 * np.cos(th), a2 * np.sin(th)
    xD, yD = b2 * np.cos(th), b2 * np.sin(th)
    xB, yB = a4 * np.cos(t14), a1 + a4 * np.sin(t14)
    xC, yC = xB + a5 * np.cos(t15), yB + a5 * np.sin(t15)
    xs, ys = xA, yA - a1
    xs2, ys2 = xD - xB, yD - yB
    out = {
        "theta12": th, "xs": xs, "ys": ys, "s": np.hypot(xs, ys), "phi": np.arctan2(ys, xs),
        "mu": _interior(xA - xB, yA - yB, -xB, a1 - yB),
        "psi": _interior(xs, ys, xB, yB - a1),
        "theta14": t14, "theta13": t13,
        "xs2": xs2, "ys2": ys2, "s2": np.hypot(xs2, ys2), "eta": np.arctan2(ys2, xs2),
        "xi": _interior(xs2, ys2, xC - xB, yC - yB),
        "gamma": _interior(xB - xD, yB - yD, xC - xD, yC - yD),
        "theta15": t15, "theta16": t16,
        "xA": xA, "yA": yA, "xB": xB, "yB": yB, "xD": xD, "yD": yD, "xC": xC, "yC": yC,
    }
    return _finish(out, ok, "theta12")


def _tk_fourbar(p: dict, th: np.ndarray) -> dict:
    a, b, c, m, n, x3, y3 = (p[k] for k in ("a", "b", "c", "m", "n", "x3", "y3"))
    br = int(p["branch"])
    size = a + b + c + math.hypot(x3, y3)
    x1l, y1l = (a * np.cos(th)).tolist(), (a * np.sin(th)).tolist()
    # Loop a·e^{iφ} + b·e^{iθ} = (x3 + i·y3) + c·e^{iψ}: dyad Q = P3, P = P1, x = (ψ, θ).
    sols = _dyad_sweep(len(th), lambda i: (x3, y3), lambda i: (x1l[i], y1l[i]), c, b, br,
                       _RES_TOL * size)
    ok = _solved(sols)
    psi, theta = _column(sols, 0), _column(sols, 1)
    x1, y1 = a * np.cos(th), a * np.sin(th)
    x2, y2 = x3 + c * np.cos(psi), y3 + c * np.sin(psi)
    ux, uy = np.cos(theta), np.sin(theta)           # unit vector P1→P2
    x4, y4 = x1 + m * ux - n * uy, y1 + m * uy + n * ux  # P1 + m·u + n·(u turned +90°)
    xs, ys = x1 - x3, y1 - y3
    out = {
        "phi": th, "x1": x1, "y1": y1, "xs": xs, "ys": ys,
        "s": np.hypot(xs, ys), "delta": np.arctan2(ys, xs),
        "beta": _interior(xs, ys, x2 - x3, y2 - y3),
        "mu": _interior(x3 - x2, y3 - y2, x1 - x2, y1 - y2),
        "psi": psi, "theta": theta, "x2": x2, "y2": y2, "x4": x4, "y4": y4,
        "d": np.hypot(x4 - x1, y4 - y1), "e": np.hypot(x4 - x2, y4 - y2),
    }
    return _finish(out, ok, "phi")


_SOLVERS = {
    "fourbar": _fourbar,
    "slider-crank": _slider_crank,
    "pump": _pump,
    "inverted-slider-crank": _inverted_slider_crank,
    "quick-return": _quick_return,
    "shaper": _shaper,
    "garage-door": _garage_door,
    "tk-fourbar": _tk_fourbar,
}


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------

def _read_params(mechanism: str, params: Mapping[str, float]) -> dict[str, float]:
    if mechanism not in _SOLVERS:
        raise ValueError(f"unknown mechanism {mechanism!r}; expected one of {', '.join(MECHANISMS)}")
    names = PARAMETERS[mechanism]
    missing = [k for k in names if k not in params]
    if missing:
        raise ValueError(f"{mechanism}: missing parameter(s) {', '.join(missing)}")
    out = {}
    for k in names:
        v = float(params[k])
        if k in _BRANCH_KEYS and v not in (1.0, -1.0):
            raise ValueError(f"{mechanism}: {k} must be 1 or -1, got {params[k]!r}")
        if not math.isfinite(v):
            raise ValueError(f"{mechanism}: parameter {k} is not finite: {params[k]!r}")
        out[k] = v
    return out


def solve(mechanism: str, params: Mapping[str, float], angles_deg) -> dict[str, np.ndarray]:
    """Position analysis at each input angle (degrees, 1-D array-like).

    params: every parameter symbol listed in docs/mechanisms.md for that mechanism (see
    PARAMETERS), including the branch parameters (branch, branch_door) as +1.0 / -1.0; gamma3
    (slider-crank) is in degrees. Returns one float array per quantity key of that mechanism's
    table (angles in radians, lengths in the parameters' unit, the input angle key echoed in
    radians), NaN on rows where the loop cannot close, plus 'assembled': a bool array. Constant
    keys (fourbar 'gamma', quick-return 'time_ratio') are floats, not arrays.

    Raises ValueError for an unknown mechanism, a missing parameter or a branch not ±1.
    """
    p = _read_params(mechanism, params)
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    if angles.ndim != 1:
        raise ValueError("angles_deg must be one-dimensional")
    return _SOLVERS[mechanism](p, np.radians(angles))


def pivots(mechanism: str, params: Mapping[str, float]) -> dict[str, tuple[float, float]]:
    """The fixed joints of the mechanism's frame (docs/mechanisms.md), by the doc's names."""
    p = _read_params(mechanism, params)
    frames = {
        "fourbar": lambda: {"A0": (0.0, 0.0), "B0": (p["a1"], 0.0)},
        "slider-crank": lambda: {"A0": (0.0, 0.0)},
        "pump": lambda: {"A0": (0.0, 0.0), "B0": (-p["b1"], p["s1"])},
        "inverted-slider-crank": lambda: {"A0": (0.0, 0.0), "B0": (p["a1"], 0.0)},
        "quick-return": lambda: {"A0": (0.0, p["a1"]), "B0": (0.0, 0.0)},
        "shaper": lambda: {"O1": (0.0, 0.0), "O2": (0.0, p["r1"])},
        "garage-door": lambda: {"A0": (0.0, 0.0), "B0": (0.0, p["a1"])},
        "tk-fourbar": lambda: {"P0": (0.0, 0.0), "P3": (p["x3"], p["y3"])},
    }
    return frames[mechanism]()


# --------------------------------------------------------------------------------------------
# Properties of a mechanism's four-bar loop (Grashof class, input limit angles)
# --------------------------------------------------------------------------------------------

# (input pivot, output pivot, crank, coupler, output link) of each four-bar loop in the doc.
_FOURBAR_LOOPS = {
    "fourbar": ("A0", "B0", "a2", "a3", "a4"),
    "pump": ("A0", "B0", "a2", "a3", "a4"),
    "garage-door": ("A0", "B0", "a2", "a3", "a4"),
    "tk-fourbar": ("P0", "P3", "a", "b", "c"),
}


def fourbar_loop(mechanism: str, params: Mapping[str, float]):
    """(ground, crank, coupler, output link) lengths of the mechanism's four-bar loop, or None."""
    if mechanism not in _FOURBAR_LOOPS:
        return None
    a, b, crank, coupler, rocker = _FOURBAR_LOOPS[mechanism]
    piv = pivots(mechanism, params)
    ground = math.dist(piv[a], piv[b])
    return ground, float(params[crank]), float(params[coupler]), float(params[rocker])


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


def limit_angles(mechanism: str, params: Mapping[str, float], length: float) -> list[float]:
    """Input angles (degrees, [0, 360), ascending) where the output pivot is exactly `length`
    from the crank pin: found by sampling |Q − A(θ)| − length and bisecting each sign change."""
    a, b, crank, _, _ = _FOURBAR_LOOPS[mechanism]
    piv = pivots(mechanism, params)
    (ax, ay), (qx, qy) = piv[a], piv[b]
    r = float(params[crank])

    def f(deg: float) -> float:
        t = math.radians(deg)
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
