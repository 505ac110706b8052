"""Motion generation and path generation with prescribed timing by a four-bar, three positions
(docs/synthesis.md): the `[synthesis]` table of kind "motion" or "path", checked here, each
problem one line naming the field; `design` is the writer's own solution in Python of the
textbook's standard dyad form (the values a template's checks and `linkbook info` read before
the book exists). The book's formulas are book/synthesis_dyads.py's; the independent reference
is check/reference/synthesis_motion.py.

Both kinds are one task: three positions P_j of the coupler point, the coupler's rotations α_j
from pose 1, the crank's β_j and the rocker's γ_j. Motion generation gives the poses' angles
and leaves β and γ free; path generation gives the crank's β (the timing) and leaves α and γ
free, with α_1 = 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .domain import InputError
from .mechanisms import ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, OFFSET_KIND

KINDS = ("motion", "path")
# the designed parameters: role -> kind; `ground` and `offset` are optional (the mechanism
# needs neither: they are shown, and the offset is the coupler's angle against A→B)
ROLES = {"crank": LENGTH_KIND, "coupler": LENGTH_KIND, "rocker": LENGTH_KIND,
         "ground": LENGTH_KIND, "u": OFFSET_KIND, "v": OFFSET_KIND, "offset": ANGLE_KIND,
         "xA0": OFFSET_KIND, "yA0": OFFSET_KIND, "xB0": OFFSET_KIND, "yB0": OFFSET_KIND,
         "branch": BRANCH_KIND}
OPTIONAL_ROLES = ("ground", "offset")
LENGTH_ROLES = ("crank", "coupler", "rocker", "ground")
# cond₂ of a dyad's standard form above which nothing is designed (the reference's)
SINGULAR_COND = 1e6
# a link shorter than this share of the task's size is a degenerate root: no four-bar
DEGENERATE = 1e-9
# a pose nearer a dead centre than this (|cross| against its sides' product) is on neither
# branch: the position reference's TANGENT
DEAD_CENTRE = 1e-12


@dataclass(frozen=True)
class DyadTask:
    """Three positions of the coupler point and the rotations of the coupler, the crank and
    the rocker from position 1 (degrees); which of them are the task depends on `kind`."""
    kind: str                                  # motion or path
    x: tuple[float, float, float]              # the coupler point P_j
    y: tuple[float, float, float]
    alpha: tuple[float, float, float]          # motion: the poses' angles; path: (0, α2, α3)
    beta: tuple[float, float] | None           # the crank's rotations β2, β3 (None: its pivot)
    gamma: tuple[float, float] | None          # the rocker's rotations γ2, γ3 (None: its pivot)
    designs: tuple[tuple[str, str], ...]       # (role, parameter symbol)
    keys: tuple[tuple[str, str], ...] = ()     # the model's keys: theta3, theta4, x, y of P
    # the fixed pivots given instead of a dyad's rotations (Norton §5.9): (dyad, (x, y))
    pivots: tuple[tuple[str, tuple[float, float]], ...] = ()

    def pivot(self, dyad: str) -> tuple[float, float] | None:
        """The dyad's given fixed pivot ("crank" or "rocker"), or None: its rotations given."""
        return dict(self.pivots).get(dyad)

    def designed(self) -> dict[str, str]:
        """{parameter symbol: role} of the parameters the task designs."""
        return {symbol: role for role, symbol in self.designs}

    def symbol(self, role: str) -> str:
        return dict(self.designs)[role]

    def key(self, what: str) -> str:
        return dict(self.keys)[what]

    def in_unit(self, factor: float) -> DyadTask:
        """The task with its positions in another length unit (times `factor`)."""
        return replace(self, x=tuple(v * factor for v in self.x),
                       y=tuple(v * factor for v in self.y),
                       pivots=tuple((dyad, (gx * factor, gy * factor))
                                    for dyad, (gx, gy) in self.pivots))


def task_of(table: dict, kinds: dict[str, str], where: str) -> DyadTask:
    """The [synthesis] table of kind motion or path (the schema has checked its keys and
    types), checked against the parameters' kinds."""
    kind = table["kind"]
    if kind == "motion":
        poses = table["poses"]
        x, y, alpha = (tuple(float(p[k]) for p in poses) for k in range(3))
        _angles(f"{where}.poses", alpha, "the poses' angles")
    else:
        points = table["points"]
        x, y = (tuple(float(p[k]) for p in points) for k in range(2))
        alpha = (0.0, *_pair(table, "alpha", where))
    pivots = tuple((dyad, tuple(float(v) for v in xy))
                   for dyad, xy in table.get("pivots", {}).items())
    rotations = {}
    for dyad, key in (("crank", "beta"), ("rocker", "gamma")):
        if (key in table) == (dyad in dict(pivots)):
            raise InputError(f"{where}.{key}", f"give the {dyad}'s rotations ({key}) or its "
                                               f"fixed pivot (pivots.{dyad}), one of the two")
        rotations[key] = _pair(table, key, where) if key in table else None
    return DyadTask(kind, x, y, alpha, rotations["beta"], rotations["gamma"],
                    _designs(table, kinds, where), pivots=pivots)


def _pair(table: dict, key: str, where: str) -> tuple[float, float]:
    values = tuple(float(v) for v in table[key])
    _angles(f"{where}.{key}", values, "rotations from position 1")
    return values


def _angles(field: str, values, what: str) -> None:
    if any(abs(v) > 360 for v in values):
        raise InputError(field, f"{what} are degrees within ±360 (got {list(values)})")


def _designs(table: dict, kinds: dict[str, str], where: str) -> tuple[tuple[str, str], ...]:
    given = table["designs"]
    out = []
    for role, want in ROLES.items():
        if role not in given:
            if role in OPTIONAL_ROLES:
                continue
            raise InputError(f"{where}.designs.{role}", "is missing")
        symbol = given[role]
        if kinds.get(symbol) != want:
            article = "an" if want[0] in "ao" else "a"
            raise InputError(f"{where}.designs.{role}", f"{symbol!r} must be {article} {want} "
                                                        "parameter of the mechanism")
        out.append((role, symbol))
    if len({s for _, s in out}) != len(out):
        raise InputError(f"{where}.designs", "the designed parameters must be different "
                                             "parameters")
    return tuple(out)


def fitted_to(task: DyadTask, description: dict, origin: str) -> DyadTask:
    """The task with the model's keys it reads: the mechanism must be the four-bar the task
    designs (a crank of length `crank` about a ground pivot at [xA0, yA0] with no phase, a
    dyad on its pin and a ground pivot at [xB0, yB0] with the coupler, the rocker and the
    branch, and a `point` step on the frame [crank pin, dyad point] at `local` [u, v]), else
    one line naming what does not fit."""
    where = f"{origin}: synthesis"
    s = task.symbol
    steps, ground = description.get("steps", []), description.get("ground", {})
    crank = next((st for st in steps if st.get("type") == "crank"), None)
    if crank is None or crank.get("length") != s("crank") or crank.get("phase", 0) != 0 or \
            ground.get(crank.get("pivot")) != [s("xA0"), s("yA0")]:
        raise InputError(f"{where}.designs.crank", f"the mechanism's crank must have length "
                                                   f"{s('crank')!r}, no phase, and turn about "
                                                   f"a ground pivot at [{s('xA0')!r}, "
                                                   f"{s('yA0')!r}]")
    dyad = next((st for st in steps if st.get("type") == "dyad" and
                 st.get("p") == crank["point"] and st.get("p_length") == s("coupler") and
                 st.get("q_length") == s("rocker") and st.get("branch") == s("branch") and
                 ground.get(st.get("q")) == [s("xB0"), s("yB0")]), None)
    if dyad is None:
        raise InputError(f"{where}.designs", "the mechanism needs a dyad on the crank's pin and "
                                             f"a ground pivot at [{s('xB0')!r}, {s('yB0')!r}] "
                                             f"with p_length {s('coupler')!r}, q_length "
                                             f"{s('rocker')!r} and branch {s('branch')!r}")
    frame = [crank["point"], dyad["point"]]
    point = next((st for st in steps if st.get("type") == "point" and
                  st.get("frame") == frame and st.get("local") == [s("u"), s("v")]), None)
    if point is None:
        raise InputError(f"{where}.designs", f"the mechanism needs a point step on the frame "
                                             f"{frame} at local [{s('u')!r}, {s('v')!r}]: the "
                                             "coupler point")
    keys = (("theta3", _key(dyad, "theta_p", f"theta_p_{dyad['point']}")),
            ("theta4", _key(dyad, "theta_q", f"theta_q_{dyad['point']}")),
            ("x", _key(point, "x", f"x{point['point']}")),
            ("y", _key(point, "y", f"y{point['point']}")))
    return replace(task, keys=keys)


def _key(step: dict, column: str, default: str) -> str:
    spec = step.get("columns", {}).get(column)
    return (spec.get("key") if isinstance(spec, dict) else None) or default


# ---------------------------------------------------------------- the writer's own design
def _standard_form(turn: np.ndarray, rotation: np.ndarray, delta: np.ndarray
                   ) -> tuple[complex, complex] | None:
    """(W, Z) of W·(e^{iρ_j} − 1) + Z·(e^{iα_j} − 1) = δ_j, j = 2, 3; None if near-singular."""
    m = np.column_stack([np.exp(1j * rotation) - 1.0, np.exp(1j * turn) - 1.0])
    if not np.linalg.cond(m) <= SINGULAR_COND:
        return None
    w, z = np.linalg.solve(m, delta)
    return complex(w), complex(z)


def _about_pivot(turn: np.ndarray, delta: np.ndarray, first: complex
                 ) -> tuple[complex, complex] | None:
    """(W, Z) of the dyad about a given fixed pivot G (`first` = P_1 − G): m = M − P_1 from
    |M_j − G| = |M_1 − G|, 2·Re(conj(e^{−iα_j}·δ_j + (e^{−iα_j} − 1)·e_1)·m) =
    −δ_j·(2e_1 + δ_j), j = 2, 3; None if near-singular."""
    q = np.exp(-1j * turn)
    rows = 2.0 * (q * delta + (q - 1.0) * first)
    m = np.column_stack([rows.real, rows.imag])
    if not np.linalg.cond(m) <= SINGULAR_COND:
        return None
    rhs = -(delta.real * (2 * first.real + delta.real) + delta.imag * (2 * first.imag
                                                                       + delta.imag))
    mx, my = np.linalg.solve(m, rhs)
    return first + complex(mx, my), -complex(mx, my)


def _dyad(task: DyadTask, dyad: str, turn, delta, p1: complex):
    pivot = task.pivot(dyad)
    if pivot is not None:
        return _about_pivot(turn, delta, p1 - complex(*pivot))
    rotation = task.beta if dyad == "crank" else task.gamma
    return _standard_form(turn, np.radians(rotation), delta)


def design(task: DyadTask) -> dict[str, float]:
    """{role: value} of the designed parameters, NaN where the design does not exist or cannot
    be used (a near-singular dyad, a link too short, a branch defect)."""
    nothing = {role: math.nan for role in ROLES} | {"branch": 1.0}
    p = np.array(task.x) + 1j * np.array(task.y)
    alpha = np.radians(task.alpha)
    turn, delta = alpha[1:] - alpha[0], p[1:] - p[0]
    crank, rocker = (_dyad(task, dyad, turn, delta, p[0]) for dyad in ("crank", "rocker"))
    if crank is None or rocker is None:
        return nothing
    (w, z), (u, s) = crank, rocker
    a0, b0 = p[0] - z - w, p[0] - s - u
    a, b, c, d = abs(w), abs(z - s), abs(u), abs(b0 - a0)
    if min(a, b, c, d) <= DEGENERATE * max(a, b, c, d, float(np.max(np.abs(delta)))):
        return nothing
    carried = np.exp(1j * (alpha - alpha[0]))       # the coupler's rotations from pose 1
    theta2 = np.angle(w + (p - p[0]) + (carried - 1.0) * -z)
    theta4 = np.angle(u + (p - p[0]) + (carried - 1.0) * -s)
    reach, rocker_arm = a0 - b0 + a * np.exp(1j * theta2), c * np.exp(1j * theta4)
    cross = (np.conj(rocker_arm) * reach).imag
    sides = set(np.sign(cross[np.abs(cross) > DEAD_CENTRE * c * np.abs(reach)]).tolist())
    if len(sides) != 1:
        return nothing
    e = (z - s) / b
    return {"crank": a, "coupler": b, "rocker": c, "ground": d,
            "u": float((np.conj(e) * z).real), "v": float((np.conj(e) * z).imag),
            "offset": math.degrees(math.remainder(alpha[0] - np.angle(z - s),
                                                  math.tau)),
            "xA0": float(a0.real), "yA0": float(a0.imag), "xB0": float(b0.real),
            "yB0": float(b0.imag), "branch": float(sides.pop())}
