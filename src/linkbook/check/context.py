"""What the judging of one book shares: the reference solver of the mechanism its record
describes, the slope of a reference value (the allowance near a limit position), and the
context every block's check reads (the record, the values, how errors show, the bound, the
reference's results) and adds its checks to, in the report's order."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
import numpy as np

from . import reference as generic
from ..base.record import BuildRecord
from .checks import (ANGLE_UNITS, EDGE_SLOPE, NEARER_STEPS, SENSITIVITY_STEP, Check, Rules,
                     compare, expected_of, unit_scale)
from .reading import UnusableFile


class Reference:
    """The independent solver of one book's mechanism: the generic reference (reference.py),
    given the description the book records, with the book's own input values."""

    def __init__(self, record: BuildRecord):
        self.mechanism = _mechanism_of(record)
        self.description = self.mechanism.description

    def solve(self, params: dict, angles, turns: dict | None = None) -> dict:
        return generic.solve(self.description, params, angles, turns)

    def fourbar_loops(self, params: dict):
        return generic.fourbar_loops(self.description, params)

    def limit_angles(self, params: dict, length: float, loop: int = 0) -> list[float]:
        return generic.limit_angles(self.description, params, length, loop)


# The record last compiled and its mechanism: verify makes a Reference of one record for the
# book's own inputs, again for the other input sets and for each set's judging, and compiling
# the description is the same work each time (a Mechanism is frozen: shared safely).
_COMPILED: list = [None, None]


def _mechanism_of(record: BuildRecord):
    """The mechanism `record` describes, compiled once for that record object."""
    if _COMPILED[0] is record:
        return _COMPILED[1]
    from ..language.model import DescriptionError
    from ..language.bundled import from_record
    try:
        mechanism = from_record(record)
    except (DescriptionError, KeyError, TypeError, AttributeError) as exc:
        raise UnusableFile(f"the mechanism recorded in the book is unusable: {exc}") from None
    _COMPILED[:] = record, mechanism
    return mechanism


def slope_of(solver: Reference, params: dict, angles: np.ndarray, key: str, unit: str,
             param: str | None = None, column_values=(),
             scale: float = math.degrees(1.0), motion: bool = False):
    """|∂x/∂θ| per row (per column value, for a grid) by a central difference of the reference,
    computed for one row when asked. `scale`: input units per unit of θ (degrees per radian of a
    crank; the mechanism's size for an actuator's length). `motion`: x is a velocity or an
    acceleration (else the reference is asked for positions only, which is quicker)."""
    period = ANGLE_UNITS.get(unit)
    h = SENSITIVITY_STEP
    if not motion:
        from ..language.mechanisms import MOTION_SYMBOLS
        params = {k: v for k, v in params.items()
                  if k not in MOTION_SYMBOLS[solver.mechanism.input_kind]}

    def around(p: dict, i: int, step: float) -> np.ndarray:
        return expected_of(solver.solve(p, float(angles[i]) + scale * np.array(
            [-step, 0.0, step])), key)

    def differences(p: dict, i: int) -> tuple[np.ndarray, float]:
        """x at θ − step, θ, θ + step, and the step: h, or on a row within h of a limit
        position (one side closes, the other not) the first of NEARER_STEPS at which both
        sides close. The slope there runs like 1/√δ (δ the row's distance from the limit):
        a difference over h to the one side that closes takes it √(h/δ) times too small."""
        x = around(p, i, h)
        if np.isfinite(x[0]) == np.isfinite(x[2]):
            return x, h
        for step in NEARER_STEPS:
            closer = around(p, i, step)
            if np.isfinite(closer).all():
                return closer, step
        return x, h

    def at(i: int, j: int = 0) -> float:
        p = {**params, param: column_values[j]} if param else params
        x, step = differences(p, i)
        pairs = [(a, b, span) for a, b, span in ((0, 2, 2 * step), (0, 1, step), (1, 2, step))
                 if np.isfinite(x[a]) and np.isfinite(x[b])]
        if not pairs:
            # Both neighbours fail to close: a limit position, a double root, where any solver
            # (the reference's Newton included) gets only about √ε: allow 1e-6 there.
            return EDGE_SLOPE
        a, b, span = pairs[0]
        d = x[b] - x[a]
        if period:
            d = (d + period / 2) % period - period / 2
        return abs(d) / span
    return at


@dataclass
class Judging:
    """One book being judged: its record and cell values, the rules they are judged by (how
    the engine shows an error, the bound), the reference and the book's inputs and size. The sweep's check sets the reference's results the later checks
    compare with (`angles`, `ref`; the current position's `angle` and `one`). `checks` holds
    the checks made so far, in the report's order."""
    wb: object
    record: BuildRecord
    values: dict
    rules: Rules
    solver: Reference
    model: object
    params: dict
    size: float
    checks: list[Check] = field(default_factory=list)
    scale: float = 1.0             # input units per radian of a crank; S of an actuator
    angles: np.ndarray | None = None
    ref: dict | None = None
    slopes: dict = field(default_factory=dict)
    angle: float = 0.0
    one: dict | None = None
    # the book's own angle columns over the sweep and at the current position (radians): the
    # turn an expression of an angle reads them in (reference.solve's `turns`)
    turns: dict = field(default_factory=dict)
    turns_now: dict = field(default_factory=dict)
    own_inputs: bool = True        # False: one of verify's other input sets (input_sets.py)

    @property
    def mechanism(self):
        return self.solver.mechanism

    def shown_angles(self, sheet: str, cells: dict[str, list[str]]) -> dict[str, np.ndarray]:
        """{key: the book's values} of the angle columns (radians) among `cells` ({key: its
        cells}), NaN where a cell holds no number."""
        def number(v):
            return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) \
                else math.nan
        def is_angle(key: str) -> bool:
            try:
                return self.model.get(key).unit == "rad"
            except KeyError:            # the sweep's bookkeeping (where each row closes)
                return False
        return {key: np.array([number(v) for v in self.got(sheet, where)])
                for key, where in cells.items() if is_angle(key)}

    def got(self, sheet: str, cells: list[str]) -> list:
        return looked_up(self.values, sheet, cells)

    def compare(self, check: Check, sheet: str, cells: list[str], expected, unit: str,
                slope=None, dead=None, sine=None, rules: Rules | None = None) -> None:
        """checks.compare of `cells` (their values in the book) with `expected`, by this
        book's rules unless `rules` says otherwise."""
        compare(check, sheet, cells, self.got(sheet, cells), expected, unit,
                rules or self.rules, slope, dead, sine)

    def run(self, block: str, name: str, sheet: str, cells: list[str], expected, unit: str,
            slope=None, rate: float = 1.0, dead=None, sine=None) -> None:
        """A new check of `cells` against `expected`, added to `checks`."""
        c = Check(block, name, self.size, rate, unit_scale(unit, self.size))
        self.compare(c, sheet, cells, expected, unit, slope, dead, sine)
        self.checks.append(c)

    def slope(self, inputs, key: str, unit: str, **options):
        return slope_of(self.solver, self.params, inputs, key, unit, scale=self.scale, **options)


def looked_up(values, sheet: str, cells: list[str]) -> list:
    """The values of `cells` of `sheet` (None where none): the engine's values (a view of its
    grid) look a column up together, any other mapping cell by cell."""
    many = getattr(values, "many", None)
    return many(sheet, cells) if many else [values.get((sheet, x)) for x in cells]


MIN_RATE = 1e-9


def motion_rates(mech, params: dict, size: float) -> tuple[float, float]:
    """The scale of velocities and accelerations: a crank's |ω| and ω² + |α| (per second, per
    second²); an actuator's |v|/S and (v/S)² + |a|/S. A velocity's bound is the position's
    bound times the first, an acceleration's times the second. Neither goes below 1e-9 (a
    rate of one part in 10⁹ of the size per second is zero for any purpose; `formulas` reads
    an input of 1e-184 as 0, to 15 decimals)."""
    from ..language.mechanisms import MOTION_SYMBOLS
    speed, accel = (float(params.get(k, 0.0)) for k in MOTION_SYMBOLS[mech.input_kind])
    if not mech.input_is_angle:
        speed, accel = speed / size, accel / size
    return max(abs(speed), MIN_RATE), max(speed * speed + abs(accel), MIN_RATE)
