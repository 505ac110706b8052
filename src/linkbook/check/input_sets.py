"""Other sets of inputs a book's formulas are judged at, besides the book's own.

A formula with a wrong term that vanishes at the book's inputs (−I·α while α is 0, an offset's
term at offset 0, the weight with g = 0) gives the reference's numbers there. So verify also
evaluates the book's formulas at a few other points of the inputs' domain and judges them
against the reference at the same inputs: every length, offset, angle, rate and load moved a
little from the book's value (within ±SPREAD, an angle within ±ANGLE_SPREAD degrees), and every
zero that may be otherwise (a rate, an offset, an angle, a mass, an inertia, a load, gravity)
made a value of its kind's natural scale. A synthesis book's task moves too (its x values as
lengths do, the ranges' starts as angles, their spans by ±SPREAD), and the reference designs the
linkage of the task moved. The points come from a seed, so a verdict can be repeated. A set is
kept only where the reference assembles the mechanism at the same sweep rows as at the book's
own inputs, and within the domain (domain.py, the task's rules); else its geometric moves (the
lengths, offsets, angles and the task) are halved, up to SHRINKS times, and then left out: the
book's own geometry with its rates and loads moved. A synthesis book's set is then not judged:
its task moved has no design like the book's, which the set would not show.
"""
from __future__ import annotations

import math
import random
import statistics
from dataclasses import dataclass, field

import numpy as np

from ..base import sheets as layout
from ..base.record import BuildRecord
from ..language.domain import LENGTH_UNITS, InputError, check_lengths_together, check_value
from ..language.mechanisms import (ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, MOTION_SYMBOLS,
                                   OFFSET_KIND, RATE_KIND)
from .checks import Check, differing, judged_count, undetermined
from .reading import mechanism_size, written_in

DEFAULT_SEED = 1
OTHER_SETS = 1          # input sets judged besides the book's own
SPREAD = 0.05           # a value moves by up to ±5 % of itself
ANGLE_SPREAD = 5.0      # degrees: an angle parameter moves by up to this either way
SHRINKS = 3             # halvings of the geometric moves before a set is given up
DIGITS = 4              # significant digits of a drawn value (typed back, it is the same set)
GEOMETRIC = (LENGTH_KIND, OFFSET_KIND, ANGLE_KIND)
# a zero of these kinds is made a value of the natural scale (a branch stays as it is)
GRAVITY = 9.81          # m/s²
OMEGA = 10.0            # rad/s: a crank's speed, when the book's is 0
OFFSET_SHARE = 0.05     # a zero offset becomes this share of the smallest length
ANGLE = 10.0            # degrees: a zero angle parameter becomes this
TASK = "syn_"           # a synthesis task's input in a set: its key so prefixed (its Excel name)
TASK_ANGLES = ("alpha", "beta", "gamma")    # a motion or path task's angles, by their keys


@dataclass
class InputSet:
    """One other set of input values, its checks (no stored values: those belong to the
    book's own inputs) or why it was not judged."""
    number: int                         # the book's own inputs are set 1
    inputs: dict[str, float]            # every input symbol's value in this set (and TASK + key:
                                        # a synthesis task's inputs)
    changed: list[str]                  # the symbols whose value is not the book's
    checks: list[Check] = field(default_factory=list)
    skipped: str | None = None          # why the set was not judged

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    def differing(self) -> set[tuple[str, str]]:
        return differing(self.checks)

    def not_judged(self) -> set[tuple[str, str]]:
        """Cells too near a singular position at this set to judge (Check.determines)."""
        return undetermined(self.checks)

    @property
    def cells(self) -> int:
        """Formula cells compared with the reference at this set (those not judged left out)."""
        return judged_count(self.checks, self.not_judged())

    @property
    def max_abs(self) -> float:
        return max((c.max_abs for c in self.checks), default=0.0)


def other_sets(solver, record: BuildRecord, params: dict[str, float], angles: np.ndarray,
               seed: int, count: int = OTHER_SETS, task: dict[str, float] | None = None
               ) -> list[InputSet]:
    """`count` input sets drawn from `seed` (each its own stream: set k is the same whatever
    `count` is), each kept where the reference assembles the mechanism at the same rows of
    `angles` (the sweep's inputs) as at `params`, the book's inputs (`task`: a synthesis
    book's task inputs, check.synthesis.task_inputs)."""
    own = _assembled(solver, params, angles)
    own_values = {**params, **{TASK + key: v for key, v in (task or {}).items()}}
    # the geometric moves halved SHRINKS times, then none: the book's own geometry (its zero
    # offsets and angles kept) with its rates and loads moved, which assembles alike; not for
    # a synthesis book, whose geometry is its task
    shrinks = [0.5 ** i for i in range(SHRINKS + 1)] + ([0.0] if record.synthesis is None
                                                        else [])
    sets = []
    for k in range(count):
        number = k + 2
        for shrink in shrinks:
            values = draw(record, solver.mechanism.input_kind, params, seed, number, shrink,
                          task)
            if values is not None and np.array_equal(
                    _assembled(solver, {s: values[s] for s in params}, angles), own):
                sets.append(InputSet(number, values,
                                     [s for s in values if values[s] != own_values[s]
                                      and not _designed(record, s)]))
                break
        else:
            sets.append(InputSet(number, dict(params), [], skipped=_why_none(
                record, solver.mechanism.input_kind, params, seed, number, task)))
    return sets


def _why_none(record: BuildRecord, input_kind: str, params: dict[str, float], seed: int,
              number: int, task: dict[str, float] | None) -> str:
    """Why no set `number` was kept, in words: the domain, or (a synthesis book) what the
    reference says of the task moved least."""
    values = draw(record, input_kind, params, seed, number, 0.5 ** SHRINKS, task)
    if record.synthesis is None or values is None:
        return "no inputs drawn near the book's are within the domain (domain.py)"
    from .synthesis import why_no_design     # a synthesis book's (as below): here, on use
    moved = {key: values[TASK + key] for key in task}
    why = why_no_design(record, moved, values)
    return ("no task drawn near the book's has a design like the book's (" +
            (f"the nearest: {why}" if why else "the nearest assembles on other sweep rows")
            + ")")


def _designed(record: BuildRecord, symbol: str) -> bool:
    info = record.inputs.get(symbol)
    return info is not None and info.designed


def _assembled(solver, params: dict[str, float], angles: np.ndarray) -> np.ndarray:
    """Which rows of `angles` every loop closes on, by the reference (positions only)."""
    rates = set(MOTION_SYMBOLS[solver.mechanism.input_kind])
    return np.asarray(solver.solve({s: v for s, v in params.items() if s not in rates},
                                   angles)["assembled"], dtype=bool)


def draw(record: BuildRecord, input_kind: str, params: dict[str, float], seed: int,
         number: int, shrink: float = 1.0, task: dict[str, float] | None = None
         ) -> dict[str, float] | None:
    """Input set `number` of `seed`: every value moved, every zero that may be otherwise made
    one of its natural scale; a synthesis book's `task` (its inputs by key) moved and the
    linkage redesigned; the geometric moves times `shrink`. None where the values leave the
    domain (the caller shrinks them)."""
    rng = random.Random(f"linkbook input set {seed} {number}")
    kinds = record.kinds()
    scales = _natural_scales(record, input_kind, params)
    out = {}
    for symbol in sorted(params):           # one draw per symbol, in a fixed order
        u = rng.uniform(-1.0, 1.0)
        out[symbol] = _moved(kinds[symbol], params[symbol], scales.get(symbol), u,
                             shrink if kinds[symbol] in GEOMETRIC else 1.0)
    moved = {}
    if record.synthesis is not None:
        if task is None:
            raise ValueError("a synthesis book's input set moves its task: give its inputs")
        from .synthesis import with_design
        moved = _moved_task(task, rng, shrink)
        if not _task_in_domain(record, moved):
            return None
        out = with_design(record, out, moved)   # never drawn: the reference's
    speed, accel = MOTION_SYMBOLS[input_kind]
    if params.get(accel) == 0 and speed in out:     # an acceleration of the speed's scale
        per = 1.0 if input_kind == ANGLE_KIND else mechanism_size(record, out)
        out[accel] = _round(out[speed] ** 2 / per * (1.0 + SPREAD * rng.uniform(-1.0, 1.0)))
    try:
        for symbol, value in out.items():
            if not record.inputs[symbol].designed:     # the design's: NaN where there is none
                check_value(symbol, kinds[symbol], value)
        check_lengths_together({s: v for s, v in out.items() if not math.isnan(v)}, kinds, "",
                               written_in(record))
    except InputError:
        return None
    return {**out, **{TASK + key: value for key, value in moved.items()}}


def _moved_task(task: dict[str, float], rng: random.Random, shrink: float
                ) -> dict[str, float]:
    """A synthesis task's inputs moved, one draw each in a fixed order: the ranges' starts and
    the poses' angles and rotations (alpha…, beta…, gamma…) as angle parameters are, every
    other (x0, x1, the given x values, the spans, the poses' coordinates) by up to ±SPREAD of
    itself, as a length is (a zero x stays 0: f's domain may end there)."""
    return {key: _moved(ANGLE_KIND if key.endswith("_start") or key.startswith(TASK_ANGLES)
                        else LENGTH_KIND, task[key], None, rng.uniform(-1.0, 1.0), shrink)
            for key in sorted(task)}


def _task_in_domain(record: BuildRecord, moved: dict[str, float]) -> bool:
    """Whether the task with these inputs is one the language accepts (function generation:
    x0 < x1, the spans within ±360°, the given x ascending, f(x0) ≠ f(x1) both numbers;
    motion and path generation: the angles within ±360°)."""
    from ..language.synthesis import task_of
    from .synthesis import task_table
    try:
        task_of({"synthesis": task_table(record, moved)}, record.kinds(), "")
    except InputError:
        return False
    return True


def _moved(kind: str, value: float, natural: float | None, u: float, shrink: float) -> float:
    """`value` moved by the draw u in [-1, 1] (`natural`: what a zero becomes, None to keep
    it)."""
    if kind == BRANCH_KIND or shrink == 0:
        return value
    if kind == ANGLE_KIND:
        return _round(value + ANGLE_SPREAD * shrink * u if value else
                      math.copysign(ANGLE * shrink, u))
    if value == 0:
        if natural is None:
            return value
        sign = math.copysign(1.0, u) if kind == OFFSET_KIND else 1.0
        return _round(sign * natural * (shrink if kind == OFFSET_KIND else 1.0)
                      * (1.0 + SPREAD * abs(u)))
    return _round(value * (1.0 + SPREAD * shrink * u))


def _round(value: float) -> float:
    return float(f"{value:.{DIGITS}g}")


def _natural_scales(record: BuildRecord, input_kind: str, params: dict[str, float]
                    ) -> dict[str, float]:
    """What each input that is 0 becomes: the typical value of the book's others of its kind
    (their median), or one of the kind's own scale (the weight of the book's typical mass, its
    inertia as a rod the mechanism's size long, a crank's 10 rad/s, gravity)."""
    kinds = record.kinds()
    size = mechanism_size(record, params)
    metres = size * LENGTH_UNITS[record.length_unit]

    def typical(kind: str, otherwise: float) -> float:
        values = [abs(v) for s, v in params.items() if kinds[s] == kind and v != 0]
        return statistics.median(values) if values else otherwise
    mass = typical("mass", 1.0)
    force = typical("force", mass * GRAVITY)
    by_kind = {"mass": mass, "inertia": typical("inertia", mass * metres ** 2 / 12),
               "force": force, "torque": typical("torque", force * metres),
               "acceleration": GRAVITY, "damping": typical("damping", force * metres / OMEGA),
               OFFSET_KIND: OFFSET_SHARE * min((abs(v) for s, v in params.items()
                                                if kinds[s] == LENGTH_KIND), default=size)}
    out = {s: by_kind[k] for s, k in kinds.items() if k in by_kind}
    speed = MOTION_SYMBOLS[input_kind][0]
    if kinds.get(speed) == RATE_KIND:
        out[speed] = OMEGA if input_kind == ANGLE_KIND else size / OMEGA
    return out


def write_inputs(wb, record: BuildRecord, values: dict[str, float]) -> dict[str, object]:
    """Put `values` into the book's input cells (in memory); returns what the cells held."""
    held = {}
    for symbol, value in values.items():
        sheet, cell = input_cell(record, symbol)
        held[symbol] = wb[sheet][cell].value
        wb[sheet][cell].value = value
    return held


def input_cell(record: BuildRecord, symbol: str) -> tuple[str, str]:
    """(sheet, cell) of an input set's value: a parameter's on the Mechanism sheet, a synthesis
    task's (TASK + its key) on the Synthesis sheet."""
    if symbol in record.inputs:
        return layout.MECH, record.inputs[symbol].cell
    return record.synthesis.sheet, record.synthesis.inputs[symbol.removeprefix(TASK)]
