"""A template's synthesis task (docs/synthesis.md): what the linkage must do, from which the
Synthesis sheet designs some of its parameters.

Function generation by a four-bar (`kind = "function"`): the rocker's angle θ4 follows
y = f(x) while the crank's angle θ2 follows x over [x0, x1]. Motion and path generation
(`kind = "motion"`, `"path"`) are synthesis_dyads.py's; the functions here dispatch on the
kind. The task is checked here, each problem one line naming the field; `design` is the
writer's own solution in Python (the values a template's checks and `linkbook info` read
before the book exists). The book's formulas are book/synthesis.py's; the independent
reference is check/reference/synthesis.py.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .domain import InputError
from .expressions import expression, value_of
from .mechanisms import BRANCH_KIND, LENGTH_KIND
from .model import DescriptionError
from . import synthesis_dyads as dyads
from .synthesis_dyads import DyadTask

KINDS = ("function", *dyads.KINDS)
SPACINGS = ("chebyshev", "equal")
ROLES = ("crank", "coupler", "rocker", "branch")     # what a function generator designs
DEFAULT_POINTS = 3
# cond₂ of the rows [cos θ4, −cos θ2, 1] above which nothing is designed: the reference's
# SINGULAR_COND (check/reference/synthesis.py says why); the sheet states the same test
SINGULAR_COND = 1e6
# A precision point nearer a dead centre than this (|cross| against its sides' product) is
# on neither branch: the position reference's TANGENT
DEAD_CENTRE = 1e-12


@dataclass(frozen=True)
class FunctionTask:
    """Function generation: y = f(x) over [x0, x1] by the rocker's angle against the crank's."""
    f: str                            # as written: an expression of x
    f_excel: str                      # Excel text with {x} for x
    x: tuple[float, float]            # x0, x1
    theta2: tuple[float, float]       # the crank's start and signed span, degrees
    theta4: tuple[float, float]       # the rocker's start and signed span, degrees
    points: int
    spacing: str                      # chebyshev, equal, or given (the x values in `given`)
    given: tuple[float, ...]
    ground: str                       # the ground length's parameter: an input
    designs: tuple[tuple[str, str], ...]   # (role, parameter symbol) for each of ROLES
    output: str = ""                  # the model's key of the rocker's angle θ4 (fitted_to)
    kind: str = "function"

    def designed(self) -> dict[str, str]:
        """{parameter symbol: role} of the parameters the task designs."""
        return {symbol: role for role, symbol in self.designs}

    def symbol(self, role: str) -> str:
        return dict(self.designs)[role]

    def in_unit(self, factor: float) -> FunctionTask:
        """The task in another length unit: nothing in it is a length (the ground is a
        parameter)."""
        return self

    def f_of(self, x: float) -> float:
        """f(x) by the writer's reading of the expression; NaN where it is an error."""
        value = value_of(self.f, {"x": float(x)})
        return math.nan if value is None else value


def task_of(data: dict, kinds: dict[str, str], origin: str) -> FunctionTask | DyadTask | None:
    """The template's [synthesis] table, checked against the parameters' kinds (`kinds`), or
    None when it has none. The schema has checked the keys and their types."""
    table = data.get("synthesis")
    if table is None:
        return None
    where = f"{origin}: synthesis"
    if table["kind"] in dyads.KINDS:
        return dyads.task_of(table, kinds, where)
    try:
        f_excel = expression(f"{where}.f", table["f"], {"x"}).text
    except DescriptionError as exc:
        raise InputError(exc.field, exc.message) from None
    x0, x1 = (float(v) for v in table["x"])
    if not x0 < x1:
        raise InputError(f"{where}.x", f"must be [x0, x1] with x0 < x1 (got {table['x']})")
    for key in ("theta2", "theta4"):
        start, span = (float(v) for v in table[key])
        if span == 0 or abs(span) > 360 or abs(start) > 360:
            raise InputError(f"{where}.{key}", "must be [start, span] in degrees, the span "
                                               f"not 0, both within ±360 (got {table[key]})")
    spacing, given = table.get("spacing", "chebyshev"), ()
    points = table.get("points", DEFAULT_POINTS)
    if isinstance(spacing, list):
        given = tuple(float(v) for v in spacing)
        if "points" in table and points != len(given):
            raise InputError(f"{where}.points", f"is {points}, but spacing lists {len(given)} "
                                                "x values")
        points, spacing = len(given), "given"
        if sorted(set(given)) != list(given):
            raise InputError(f"{where}.spacing", "the x values must be distinct and ascending")
    task = FunctionTask(str(table["f"]), f_excel, (x0, x1), tuple(table["theta2"]),
                        tuple(table["theta4"]), int(points), spacing, given,
                        _ground(table, kinds, where),
                        tuple((role, _designed(table, role, kinds, where)) for role in ROLES))
    if len({s for _, s in task.designs} | {task.ground}) != len(ROLES) + 1:
        raise InputError(f"{where}.designs", "the ground and the designed parameters must be "
                                             "four different parameters")
    ends = [task.f_of(x0), task.f_of(x1)]
    if not all(math.isfinite(v) for v in ends) or ends[0] == ends[1]:
        raise InputError(f"{where}.f", f"f(x0) and f(x1) must be two different numbers (got "
                                       f"{ends[0]:g} and {ends[1]:g}): they map onto θ4's range")
    return task


def _ground(table: dict, kinds: dict[str, str], where: str) -> str:
    symbol = table["ground"]
    if kinds.get(symbol) != LENGTH_KIND:
        raise InputError(f"{where}.ground", f"{symbol!r} must be a length parameter")
    return symbol


def _designed(table: dict, role: str, kinds: dict[str, str], where: str) -> str:
    symbol = table["designs"][role]
    want = BRANCH_KIND if role == "branch" else LENGTH_KIND
    if kinds.get(symbol) != want:
        raise InputError(f"{where}.designs.{role}", f"{symbol!r} must be a {want} parameter "
                                                    "of the mechanism")
    return symbol


def fitted_to(task: FunctionTask | DyadTask, description: dict, origin: str
              ) -> FunctionTask | DyadTask:
    """The task with the key of its output angle: the mechanism must be the four-bar the task
    designs, as docs/synthesis.md places it (A0 at the origin, B0 at (ground, 0), the crank
    the input turning about A0, a dyad on the crank's pin and B0 with the coupler, the rocker
    and the branch), else one line naming what does not fit."""
    if isinstance(task, DyadTask):
        return dyads.fitted_to(task, description, origin)
    where = f"{origin}: synthesis"
    steps = description.get("steps", [])
    ground = description.get("ground", {})
    crank = next((s for s in steps if s.get("type") == "crank"), None)
    if crank is None or crank.get("length") != task.symbol("crank") or \
            ground.get(crank.get("pivot")) not in ([0, 0], [0.0, 0.0]):
        raise InputError(f"{where}.designs.crank", f"the mechanism's crank must turn about a "
                                                   f"pivot at [0, 0] with length "
                                                   f"{task.symbol('crank')!r}")
    for step in steps:
        if step.get("type") == "dyad" and step.get("p") == crank["point"] and \
                step.get("p_length") == task.symbol("coupler") and \
                step.get("q_length") == task.symbol("rocker") and \
                step.get("branch") == task.symbol("branch") and \
                ground.get(step.get("q")) in ([task.ground, 0], [task.ground, 0.0]):
            column = step.get("columns", {}).get("theta_q")
            key = column.get("key") if isinstance(column, dict) else None
            return replace(task, output=key or f"theta_q_{step['point']}")
    raise InputError(f"{where}.designs", "the mechanism needs a dyad on the crank's pin and "
                                         f"a ground pivot at [{task.ground!r}, 0] with "
                                         f"p_length {task.symbol('coupler')!r}, q_length "
                                         f"{task.symbol('rocker')!r} and branch "
                                         f"{task.symbol('branch')!r}")


# ---------------------------------------------------------------- the writer's own design
def precision_x(task: FunctionTask) -> np.ndarray:
    """x_j, j = 1..n: Chebyshev's, equally spaced, or the given ones."""
    (x0, x1), n = task.x, task.points
    j = np.arange(1, n + 1)
    if task.spacing == "given":
        return np.array(task.given)
    if task.spacing == "equal":
        return x0 + (j - 1) * (x1 - x0) / (n - 1)
    return (x0 + x1) / 2 - (x1 - x0) / 2 * np.cos((2 * j - 1) * math.pi / (2 * n))


def design(task: FunctionTask | DyadTask, values: dict[str, float]) -> dict[str, float]:
    """{role: value} of the designed parameters, NaN where the design does not exist or cannot
    be used (a negative crank or rocker, a branch defect, a near-singular system); `values`:
    the parameters' (a function generator's ground length is one)."""
    if isinstance(task, DyadTask):
        return dyads.design(task)
    d = values[task.ground]
    # no linkage: its lengths NaN leave every analysis cell #N/A whichever branch it is
    # given, and the references want a branch of ±1
    nothing = {"crank": math.nan, "coupler": math.nan, "rocker": math.nan, "branch": 1.0}
    x = precision_x(task)
    y = np.array([task.f_of(v) for v in x])
    y0, y1 = task.f_of(task.x[0]), task.f_of(task.x[1])
    t2 = np.radians(task.theta2[0] + (x - task.x[0]) / (task.x[1] - task.x[0]) * task.theta2[1])
    t4 = np.radians(task.theta4[0] + (y - y0) / (y1 - y0) * task.theta4[1])
    m = np.column_stack([np.cos(t4), -np.cos(t2), np.ones_like(t2)])
    if not np.isfinite(m).all() or not np.linalg.cond(m) <= SINGULAR_COND:
        return nothing
    k = np.linalg.lstsq(m, np.cos(t2 - t4), rcond=None)[0]
    a, c = d / k[0], d / k[1]
    b2 = a * a + c * c + d * d - 2 * a * c * k[2]
    if not (a > 0 and c > 0 and b2 > 0):
        return nothing
    cross = c * np.cos(t4) * a * np.sin(t2) - c * np.sin(t4) * (a * np.cos(t2) - d)
    sides = set(np.sign(cross[np.abs(cross) > DEAD_CENTRE * c * np.hypot(
        a * np.cos(t2) - d, a * np.sin(t2))]).tolist())
    if len(sides) != 1:
        return nothing
    return {"crank": float(a), "coupler": math.sqrt(b2), "rocker": float(c),
            "branch": float(sides.pop())}
