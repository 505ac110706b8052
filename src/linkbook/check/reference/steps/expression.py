"""`expression` — a named derived quantity: the user's formula, evaluated by the reference's own
parser (expressions.py: Excel's functions, errors as NaN). It has no rates: the workbook writes
none either.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..expressions import evaluate
from ..geometry import near
from ..positions import Positions
from ..step_type import StepType


def place(solver: Positions, step: Mapping) -> None:
    """The formula evaluated: one named value (a float) where every name it uses is fixed,
    else a column."""
    key = step.get("key")
    if not isinstance(key, str) or not key:
        raise ValueError(f"{solver.where}: missing key")
    if "formula" not in step:
        raise ValueError(f"{solver.where}: missing formula")
    value = evaluate(step["formula"], env_of(solver))
    if isinstance(value, float):
        solver.put(key, value, True)
    else:
        solver.put(key, np.broadcast_to(value, (solver.n,)).astype(float), False)


def env_of(solver: Positions) -> dict:
    """What an expression reads: the parameters, the input and every column so far. The
    workbook makes it one named cell when every name it uses is fixed (a parameter, a constant,
    a hidden value independent of the input angle); such names are passed as floats, so that
    the value comes back as a float. An angle is read in the turn an evaluation shows."""
    return {k: (float(np.asarray(v).flat[0]) if solver.fixed.get(k) and np.ndim(v) and solver.n
                else _turned(v, solver.turns.get(k))) for k, v in solver.env.items()}


def evaluate_late(solver: Positions, rates: Mapping, formulas: Mapping[str, object],
                  motion: Mapping[str, float] | None = None) -> dict:
    """Formulas that may read the rates as well (a load: a damper's −c·ω), evaluated after
    them: {key: a float, or an array over the rows}; `motion`: the input's speed and
    acceleration the rates were taken at, where they are not the positions' own parameters."""
    env = {**env_of(solver), **(motion or {}), **rates}
    return {key: evaluate(formula, env) for key, formula in formulas.items()}


def _turned(angle, shown):
    """An angle column taken in the turn of the values an evaluation shows for it (`shown`,
    radians, one per row), where it shows a number; else as it is."""
    if shown is None or np.ndim(angle) == 0:
        return angle
    shown = np.asarray(shown, dtype=float)
    if shown.shape != np.shape(angle):
        return angle
    return np.where(np.isfinite(shown), near(angle, np.nan_to_num(shown)), angle)


STEP = StepType(place=place)
