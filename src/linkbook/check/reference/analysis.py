"""Analysis of a described mechanism over its input: solve() on a sweep of input values, and
what is measured on such solutions (an extreme refined, a quick-return ratio).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping

import numpy as np

from .positions import Positions
from .rates import MOTION_PARAMS, Rates
from .steps import STEP_TYPES
from .steps.expression import evaluate_late


def solve(description: Mapping, params: Mapping[str, float], angles_deg,
          turns: Mapping[str, np.ndarray] | None = None,
          late: Mapping[str, object] | None = None) -> dict:
    """Position analysis of a described mechanism at each input angle (degrees, 1-D array-like).

    description: the [mechanism] table of a template as parsed by tomllib (input, ground, steps,
    links, ...); params: {parameter symbol: value} (angle-kind parameters in degrees, branch
    parameters ±1).

    Returns {column key: np.ndarray} for every column of every step, hidden ones included
    (radians, lengths; NaN where the step cannot close or a point it uses is undefined), the
    input key (radians), constants as floats (a carried point's gamma on a rigid frame of known
    length, an expression of the parameters alone), 'assembled': a bool array (every loop step —
    dyad, slider, slide, slot — closes on that row) and 'points': {point name: (x ndarray,
    y ndarray)} for every ground and step point.

    turns: {angle column key: the values (radians) an evaluation shows for it, one per row}: an
    expression step reads each of those angles as the one of its turns nearest that value. An
    angle is determined only up to whole turns, and the window a workbook shows it in is its
    own choice; a formula of the angle itself (a load `T*theta14`) then means what it means
    with the angle as shown.

    late: {key: formula} evaluated after the rates, as an `expression` step's formula but
    reading the rates too (a load: a damper's −c·ω); each value comes back under its key.

    Raises ValueError for a malformed description (unknown step type, unknown point, unknown
    parameter, a branch not ±1, a key written twice, ...).
    """
    return motion(positions(description, params, angles_deg, turns), description, params, late)


def positions(description: Mapping, params: Mapping[str, float], angles_deg,
              turns: Mapping[str, np.ndarray] | None = None) -> Positions:
    """solve()'s first half: the steps placed on every row (a Positions after run()), which
    motion() takes on."""
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    if angles.ndim != 1:
        raise ValueError("angles_deg must be one-dimensional")
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        solver = Positions(description, params, angles, STEP_TYPES, turns)
        solver.run()
        return solver


def motion(solver: Positions, description: Mapping, params: Mapping[str, float],
           late: Mapping[str, object] | None = None) -> dict:
    """solve()'s second half: the columns of `description` solved by positions(), with the
    rates at the input's speed and acceleration in `params` and the `late` formulas (see
    solve), as a new dict.

    `params` may differ from the ones the positions were solved with in the input's speed and
    acceleration alone, and only where no step's value reads them (reads_rates): the same
    positions then move at another speed (at rest: forces' scale); the late formulas read the
    speed and acceleration of `params`."""
    out = dict(solver.out)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        speed, accel = MOTION_PARAMS["angle" if solver.angle_input else "length"]
        rates, moving = {}, {}
        if speed in params and accel in params:
            moving = {speed: params[speed], accel: params[accel]}
            rates = Rates(solver, description, float(params[speed]),
                          float(params[accel])).run()
            out.update(rates)
            if solver.angle_input:
                out["rpm_in"] = float(params[speed]) * 30.0 / math.pi   # rad/s in rev/min
        if late:
            out.update(evaluate_late(solver, rates, late, moving))
        return out


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def reads_rates(description: Mapping) -> bool:
    """Whether some value the positions take (a ground point's, a step's) may name the
    input's speed or acceleration: any text of the ground and the steps holding one of their
    names as a word, in any case (as an expression looks a name up). Where none does, the
    positions do not depend on the speed: one solution serves every speed (motion)."""
    rates = {name.lower() for pair in MOTION_PARAMS.values() for name in pair}

    def texts(value) -> list[str]:
        if isinstance(value, str):
            return [value]
        if isinstance(value, Mapping):
            value = list(value.values())
        if isinstance(value, (list, tuple)):
            return [t for v in value for t in texts(v)]
        return []
    return any(word.lower() in rates
               for text in texts([description.get("ground"), description.get("steps")])
               for word in _NAME.findall(text))


EXTREME_STEP = 1.0    # degrees: the reference's sampling of a turn to find an extreme's basin
REVERSAL_STEP = 0.1   # degrees: ... to count an output's reversals


def refined_extreme(description: Mapping, params: Mapping[str, float], key: str,
                    angles: np.ndarray, values: np.ndarray, pick: Callable,
                    rounds: int = 6) -> tuple[float, float]:
    """(input angle, value) of column `key`'s extreme (`pick`: np.argmax or np.argmin) over
    sampled `angles`, refined by resampling 21 points around the best one, tenfold finer each
    round (six rounds from a 1° sampling: 1e-6°; the value is then exact to round-off)."""
    params = positions_only(params)
    i = int(pick(values))
    angle = float(angles[i])
    width = float(np.max(np.diff(angles))) if len(angles) > 1 else EXTREME_STEP
    for _ in range(rounds):
        near = np.linspace(angle - width, angle + width, 21)
        v = np.asarray(solve(description, params, near)[key], dtype=float)
        if not np.isfinite(v).all():
            break
        i = int(pick(v))
        angle, width = float(near[i]), width / 10.0
    value = float(np.asarray(solve(description, params, np.array([angle]))[key])[0])
    return angle, value


def positions_only(params: Mapping[str, float]) -> dict:
    """The parameters without the input's speed and acceleration: solve() then skips motion."""
    rates = {name for pair in MOTION_PARAMS.values() for name in pair}
    return {k: v for k, v in params.items() if k not in rates}


def _sign_changes(values: np.ndarray) -> int:
    """How often a sampled run of values turns back (flat steps skipped)."""
    steps = np.diff(values)
    steps = steps[steps != 0.0]
    return int(np.count_nonzero(np.sign(steps[1:]) != np.sign(steps[:-1])))


def _reversals(description, params, key: str, angles: np.ndarray, values: np.ndarray) -> int:
    """How often the output turns back over the sampled turn, looking 100 times closer
    wherever it nearly stops (a local minimum of its step): a pair of reversals narrower than
    the sampling (a dead centre just inside the swing) hides there."""
    steps = np.abs(np.diff(np.append(values, values[0])))
    slow = np.nonzero((steps <= np.roll(steps, 1)) & (steps <= np.roll(steps, -1)))[0]
    if len(slow) > 50:          # an output that barely moves: no quick-return ratio
        return -1
    count, step = 0, float(angles[1] - angles[0])
    for i in slow:
        near = np.linspace(angles[i] - step, angles[i] + 2 * step, 301)
        count += _sign_changes(np.asarray(solve(description, params, near)[key], dtype=float))
    return count


def time_ratio(description: Mapping, params: Mapping[str, float], key: str) -> float:
    """A quick-return ratio measured on the motion, not from any formula: column `key` (an
    output that moves forward and back once per turn of the input) over a turn sampled every
    REVERSAL_STEP; the input angles of its two reversals (its refined maximum and minimum) split
    the turn into the longer and the shorter stroke: longer / shorter. NaN where some sampled
    angle cannot close, or where the output reverses other than twice per turn."""
    params = positions_only(params)
    angles = np.arange(0.0, 360.0, REVERSAL_STEP)
    values = np.asarray(solve(description, params, angles)[key], dtype=float)
    if not np.isfinite(values).all():
        return math.nan
    if _reversals(description, params, key, angles, values) != 2:
        return math.nan
    top, _ = refined_extreme(description, params, key, angles, values, np.argmax, rounds=5)
    low, _ = refined_extreme(description, params, key, angles, values, np.argmin, rounds=5)
    one = (low - top) % 360.0
    return max(one, 360.0 - one) / min(one, 360.0 - one)
