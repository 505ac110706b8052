"""The Forces sheet judged: every cell against the force reference (forces.py: the Newton–Euler
equations of all the links at once), at the sweep's inputs and at the current position.

The bound scales with the mechanism's loads as a length's scales with its size: F, the larger of
Σm·(S·(ω² + |α|) + g) (its masses' inertia and weight at its size S in metres) and the largest
force the reference finds anywhere in the sweep (the loads the description puts on it); a
force may differ by 1e-12·F, a moment by 1e-12·F·S. Where a group of links nears a position in
which it cannot carry a load, the forces grow like 1/D and their rounding like 1/D²: the same
allowance as a rate's near a dead centre (checks.compare's sine), and the growth allowance of
a value beyond its scale."""
from __future__ import annotations

import numpy as np

from ..base.sheets import FORCES_SHEET
from .checks import Check, unit_scale
from .forces import LENGTH_UNITS, forces
from .judge import motion_rates

GRAVITY_SCALE = 10.0     # m/s²: the weight's share of the scale (gravity or not)
NEWTON, NEWTON_METRE = "N", "N·m"


def force_scale(j, ref: dict, metres: float) -> float:
    """F (see the module's docstring), in N."""
    kinds = j.record.kinds()
    mass = sum(abs(v) for s, v in j.params.items() if kinds.get(s) == "mass")
    _, rate2 = motion_rates(j.mechanism, j.params, j.size)
    largest = [np.nanmax(np.abs(v)) for k, v in ref.items()
               if k.startswith(("F", "N")) and isinstance(v, np.ndarray) and np.isfinite(v).any()]
    return max(mass * (j.size * metres * rate2 + GRAVITY_SCALE), *largest, 1e-300)


def check_forces(j) -> None:
    """Every column of the Forces sheet, over the sweep's rows and at the current position."""
    table, mech = j.record.forces, j.mechanism
    metres = LENGTH_UNITS[j.record.length_unit]
    ref = forces(j.solver.description, j.params, j.angles, j.record.length_unit)
    one = forces(j.solver.description, j.params, [j.angle], j.record.length_unit)
    scale = force_scale(j, ref, metres)
    _, rate2 = motion_rates(mech, j.params, j.size)
    (r0, r1), now = table.rows, table.current_row
    sheet = table.sheet
    j.run(sheet, mech.input_column, sheet, [f"A{r}" for r in range(r0, r1 + 1)], j.angles,
          mech.input_unit)
    j.run(sheet, mech.input_column, sheet, [f"A{now}"], np.array([j.angle]), mech.input_unit)
    for key, letter in table.columns.items():
        unit = j.model.get(key).unit
        if unit in (NEWTON, NEWTON_METRE):
            size = scale * (j.size * metres if unit == NEWTON_METRE else 1.0)
            rate = 1.0
        else:                           # a centre of mass: a length, an acceleration
            size, rate = unit_scale(unit, j.size), (rate2 if unit != "length" else 1.0)
        for block, cells, expected, kin in (
                (FORCES_SHEET, [f"{letter}{r}" for r in range(r0, r1 + 1)], ref[key], j.ref),
                ("forces now", [f"{letter}{now}"], one[key], j.one)):
            c = Check(block, key, j.size, rate, size)
            j.compare(c, sheet, cells, np.asarray(expected, dtype=float), unit,
                      dead=kin.get("dead_centre"), sine=kin.get("sine"))
            j.checks.append(c)
