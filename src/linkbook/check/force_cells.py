"""The Forces sheet judged: every cell against the force reference (forces.py: the Newton–Euler
equations of all the links at once), at the sweep's inputs and at the current position.

The bound scales with the mechanism's loads as a length's scales with its size: F, the larger of
Σm·(S·(ω² + |α|) + 10 m/s²) (its masses' inertia and weight at its size S in metres) and the
largest force the reference finds anywhere in the sweep (the loads the description puts on it,
and what a sum of forces that cancel carries); a force may differ by 1e-12·F, a moment by
1e-12·F·S. On a row whose largest force X runs beyond F₀ (F with the input at rest: the
masses' and the loads' own scale), an inertia force where an acceleration runs far beyond its
own scale (the pump's plunger where its slot nears parallel to its line), every force there
carries that acceleration's growth allowance: 1e-12·X²/F₀, as a value beyond its scale.
Where a group of links nears a position in which it cannot carry a load, the forces grow like
1/D and their rounding like 1/D²: the same allowance as a rate's near a dead centre
(checks.compare's sine), and the growth allowance of a value beyond its scale. At a row where
the reference finds the equations singular (a group in the position where it cannot carry a
load: a rod square to its guide, a dyad stretched straight), the forces are not determined by
the data: the book's #N/A or any number there is its honest answer (as a rate's at a dead
centre), but not #DIV/0! or another error; the summary's sums and extremes over such a sweep
are then the reference's arithmetic on the rows the book shows (each judged on its own)."""
from __future__ import annotations

import numpy as np

from ..base.sheets import FORCES_SHEET
from ..base.xlsx import column_cells
from .checks import Check, unit_scale
from .reading import UnusableFile
from .forces import LENGTH_UNITS, SINGULAR, forces, forces_and_at_rest
from .context import motion_rates

GRAVITY_SCALE = 10.0     # m/s²: the weight's share of the scale (gravity or not)
# The least scale, in N: a book's force below about 1e-154 N has a square that underflows (its
# size SQRT(x²+y²) reads 0), which the reference, scaling its equations, does not; the domain
# keeps the loads' parameters and numbers from 1e-30 up, but an expression may still make a load
# that small (T3*1e-300). Forces far below this are judged as the zero they nearly are.
FORCE_FLOOR = 1e-140
# A guide's couple a book must show: one beyond a thousand times a moment's bound somewhere in
# the sweep (a block with no couple to carry has M = 0, the reference's to rounding).
COUPLE_SHOWN = 1e-9


def _largest(result: dict) -> np.ndarray:
    """Per row, the largest |force| (a pin's or a guide's) of a forces() result (0 for none)."""
    parts = [np.abs(np.nan_to_num(np.asarray(v, dtype=float), nan=0.0))
             for k, v in result.items() if k.startswith(("F", "N")) and isinstance(v, np.ndarray)]
    return np.max(parts, axis=0) if parts else np.zeros(1)


def force_scale(j, ref: dict, static: dict, metres: float, rate2: float
                ) -> tuple[float, float]:
    """F and F₀ (see the module's docstring), in N, from the reference over the sweep as given
    (`ref`) and with the input at rest (`static`); `rate2`: the input's ω² + |α|
    (motion_rates)."""
    kinds = j.record.kinds()
    mass = sum(abs(v) for s, v in j.params.items() if kinds.get(s) == "mass")
    own = max(mass * (j.size * metres * rate2 + GRAVITY_SCALE), float(_largest(static).max()),
              FORCE_FLOOR)
    return max(own, float(_largest(ref).max())), own


def _sine(kin: dict, result: dict, scale: float, own: float) -> np.ndarray:
    """The rows' sine for checks.compare (which allows the base bound / sine²): the
    kinematics' (near a dead centre) or the growth X²/(F₀·F) of a row's largest force X beyond
    F₀, whichever allows more."""
    row = _largest(result)
    sine = 1.0 / np.sqrt(np.maximum(row * row / (own * scale), 1.0))
    if kin.get("sine") is not None:
        sine = np.minimum(sine, np.asarray(kin["sine"], dtype=float))
    return sine


def check_forces(j) -> None:
    """Every column of the Forces sheet, over the sweep's rows and at the current position,
    then its summary and work column."""
    from ..language.model import NEWTON, NEWTON_METRE
    table, mech = j.record.forces, j.mechanism
    metres = LENGTH_UNITS[j.record.length_unit]
    # a load's expression may convert a length with the book's `to_metres`
    params = {**j.params, "to_metres": metres}
    ref, static = forces_and_at_rest(j.solver.description, params, j.angles,
                                     j.record.length_unit, j.turns)
    one = forces(j.solver.description, params, [j.angle], j.record.length_unit, j.turns_now)
    _, rate2 = motion_rates(mech, j.params, j.size)
    scale, own = force_scale(j, ref, static, metres, rate2)
    _require_every_column(table, ref, COUPLE_SHOWN * scale * j.size * metres)
    (r0, r1), now = table.rows, table.current_row
    sheet = table.sheet
    j.run(sheet, mech.input_column, sheet, column_cells("A", r0, r1), j.angles,
          mech.input_unit)
    j.run(sheet, mech.input_column, sheet, [f"A{now}"], np.array([j.angle]), mech.input_unit)
    dead = _singular(ref, j.ref.get("dead_centre"))
    dead_now = _singular(one, j.one.get("dead_centre"))
    sines, sines_now = _sine(j.ref, ref, scale, own), _sine(j.one, one, scale, own)
    for key, letter in table.columns.items():
        unit = j.model.get(key).unit
        force = unit in (NEWTON, NEWTON_METRE)
        if force:
            size = scale * (j.size * metres if unit == NEWTON_METRE else 1.0)
            rate = 1.0
        else:                           # a centre of mass: a length, an acceleration
            size, rate = unit_scale(unit, j.size), (rate2 if unit != "length" else 1.0)
        for block, cells, expected, sine, singular in (
                (FORCES_SHEET, column_cells(letter, r0, r1), ref[key],
                 sines if force else j.ref.get("sine"), dead),
                ("forces now", [f"{letter}{now}"], one[key],
                 sines_now if force else j.one.get("sine"), dead_now)):
            c = Check(block, key, j.size, rate, size)
            j.compare(c, sheet, cells, np.asarray(expected, dtype=float), unit,
                      dead=singular, sine=sine)
            j.checks.append(c)
    _check_summary(j, ref, scale, metres, dead, sines)


def _require_every_column(table, ref: dict, couple: float) -> None:
    """The sheet must have a column for every force the reference finds (a guide's couple
    only where it has one: beyond `couple` on some row): a force the book leaves out is not a
    force it got right."""
    def shown(key: str, v: np.ndarray) -> bool:
        if not key.startswith("M"):
            return True
        finite = v[np.isfinite(v)]
        return bool(finite.size) and float(np.max(np.abs(finite))) > couple
    wanted = {k for k, v in ref.items()
              if isinstance(v, np.ndarray) and k != "cond" and shown(k, v)}
    missing = sorted(wanted - set(table.columns))
    if missing:
        raise UnusableFile(f"sheet {table.sheet} has no column of {', '.join(missing[:6])}, "
                           "which the mechanism's force analysis has")


def _singular(ref: dict, dead_centre) -> np.ndarray:
    """Rows where the forces are not determined: the reference's equations are singular (its
    condition number beyond SINGULAR), or the kinematics is at a dead centre."""
    cond = np.asarray(ref["cond"], dtype=float)
    singular = np.isfinite(cond) & (cond >= SINGULAR)
    if dead_centre is not None:
        singular |= np.asarray(dead_centre, dtype=bool)
    return singular


def _trapezoid(y: np.ndarray, x: np.ndarray) -> float:
    return float(np.sum((y[1:] + y[:-1]) / 2 * np.diff(x)))


def _check_summary(j, ref: dict, scale: float, metres: float, dead: np.ndarray,
                   sines: np.ndarray) -> None:
    """The summary's cells and the work column: the trapezoid rule, the extremes and the
    work, taken of the reference's effort and pin loads over the sweep. Where a row's forces are
    not determined (see `_singular`: the book may show any number there, judged row by row
    already) they are taken of the book's own row cells instead: the sums must still be the
    sums of what the sheet shows."""
    table, sheet = j.record.forces, j.record.forces.sheet
    effort = "F_in" if "F_in" in ref else next(k for k in ref if k.startswith("T1"))
    moment = scale * j.size * metres
    size = moment if effort != "F_in" else scale
    x = np.asarray(j.angles, dtype=float)
    undetermined = bool(dead.any())
    rows = _book_rows(j) if undetermined else None

    def column(key: str) -> np.ndarray:
        return rows(key) if undetermined else np.asarray(ref[key], dtype=float)
    y = column(effort)
    # a sum or an extreme over the sweep carries the rounding of its worst-conditioned row
    worst = np.array([float(np.nanmin(sines)) if np.isfinite(sines).any() else 1.0])
    length = x[-1] - x[0]
    mean = _trapezoid(y, x) / length
    expected = {"effort_mean": (mean, size), "effort_rms": (
        np.sqrt(_trapezoid(y * y, x) / length), size)}
    for word, fn in (("largest", np.max), ("smallest", np.min)):
        expected[f"effort_{word}"] = (fn(y), size)
    for key in table.summary:
        if key.startswith("peak_"):
            expected[key] = (np.max(column(key[5:])), scale)
    if table.work is not None:
        work = np.concatenate([[0.0], np.cumsum(((y[1:] + y[:-1]) / 2 - mean)
                                                * np.radians(np.diff(x)))])
        r0, r1 = table.rows
        c = Check(sheet, "W", j.size, 1.0, moment * 2 * np.pi)
        j.compare(c, sheet, [f"{table.work}{r}" for r in range(r0 + 1, r1 + 1)], work[1:], "J",
                  sine=np.full(len(work) - 1, worst[0]))
        j.checks.append(c)
        energy = float(np.max(work) - np.min(work))
        expected["energy_fluctuation"] = (energy, moment * 2 * np.pi)
        cs = j.values.get((sheet, table.summary["speed_fluctuation"].cell))
        omega = float(j.params.get("omega_in", 0.0))
        if isinstance(cs, (int, float)) and cs * omega * omega != 0:
            expected["flywheel"] = (energy / (cs * omega * omega),
                                    moment * 2 * np.pi / abs(cs * omega * omega))
        else:
            expected["flywheel"] = (np.nan, 1.0)
    for i in (0, 1):
        expected[f"mean_line_x{i}"] = (x[-i], 1.0)
        expected[f"mean_line_y{i}"] = (mean, size)
    if "polar_square_x1" in table.summary:     # absent from a book written before it
        # the polar diagram's square: its largest component in size (NaN where one is)
        reach = float(np.max(np.abs(np.concatenate([column("shaking_x"),
                                                    column("shaking_y")]))))
        for corner, sign in (("0", -1.0), ("1", 1.0)):
            for axis in "xy":
                expected[f"polar_square_{axis}{corner}"] = (sign * reach, scale)
    for key, (value, bound) in expected.items():
        c = Check("forces summary", key, j.size, 1.0, bound)
        j.compare(c, sheet, [table.summary[key].cell], np.array([value]), "", sine=worst)
        j.checks.append(c)
    for word in ("largest", "smallest"):
        _check_where(j, table.summary[f"effort_{word}_at"].cell, x, y,
                     float(expected[f"effort_{word}"][0]), size / min(worst[0], 1.0) ** 2, word)


def _book_rows(j):
    """A force column's values as the book's rows show them (NaN for an error), by key."""
    table = j.record.forces
    r0, r1 = table.rows

    def values(key: str) -> np.ndarray:
        letter = table.columns[key]
        got = j.got(table.sheet, column_cells(letter, r0, r1))
        return np.array([float(v) if isinstance(v, (int, float)) and not isinstance(v, bool)
                         and not j.rules.is_error(v) else np.nan for v in got])
    return values


def _check_where(j, cell: str, x: np.ndarray, y: np.ndarray, peak: float, size: float,
                 word: str) -> None:
    """Where the effort is largest (smallest): an input of the sweep at which the reference's
    effort is its peak within the bound (two rows may tie)."""
    sheet = j.record.forces.sheet
    c = Check("forces summary", f"effort_{word}_at", j.size, 1.0, size)
    got = j.values.get((sheet, cell))
    c.cells += 1
    c.judged.add((sheet, cell))
    if np.isnan(peak):
        c.na_expected += 1
        ok = j.rules.is_error(got) and j.rules.error_code(got) == "#N/A"
        c.na_agree += ok
    else:
        rows = np.flatnonzero(np.abs(y - peak) <= c.limit(peak))
        # an input as the book writes it, to the 1e-9 of any cell, relative where it is large
        ok = isinstance(got, (int, float)) and any(
            abs(float(got) - x[r]) <= 1e-9 * max(1.0, abs(x[r])) for r in rows)
    if not ok:
        from .checks import Mismatch
        c.mismatches.append(Mismatch(sheet, cell, f"an input where {word}", got))
    j.checks.append(c)
