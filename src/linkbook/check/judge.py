"""The judge: every formula cell the build record names, compared with the independent
reference at the input values and adjustments the book's own cells hold (|Δ| within the bound
where the loop closes, #N/A exactly where it cannot).

check_book judges the blocks in the report's order: the sweep, the current position, its joints
and drawing (drawing.py), the degree windows, the numbers-only copies, the derived constants,
the Motion sheet, the assembly and summary (summary.py) and the grid (grid.py)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import reference as generic
from ..base import sheets as layout
from ..base.record import BuildRecord
from ..base.xlsx import column_cells
from .checks import ABS_TOL, Check, Mismatch, Rules, column_unit, expected_of
from .context import Judging, Reference, motion_rates
from .reading import input_at, input_column, inputs_of, mechanism_size

ASSEMBLY_COLUMNS = ("closes", "gap_from", "gap_to")
DASH = layout.DASH
RATIO_TOL = 1e-6     # relative: a reversal's angle is located to 1e-6° (generic.time_ratio)
WINDOW_STARTS = (-180.0, 180.0)   # where a degree view's 360° window may start


def check_book(wb, record: BuildRecord, values: dict, is_error, error_code, *,
               tol: float = ABS_TOL, relative: bool = False) -> list[Check]:
    """Every check of the book's formula cells against the reference, in the report's order
    (`values` computed by an engine that shows an error as `is_error` and `error_code` say)."""
    return judge_book(wb, record, values, Rules(is_error, error_code, tol, relative))


def judge_book(wb, record: BuildRecord, values: dict, rules: Rules,
               own_inputs: bool = True) -> list[Check]:
    """check_book, with the rules given whole. `own_inputs` False: the input cells hold one of
    verify's other input sets (input_sets.py), where the tables are judged (the sweep, the
    current position and its joints, the constants, Motion, Forces, the grid) and what reads
    only them or the sampling is left to the book's own inputs: the drawing's frames, the degree
    windows, the numbers-only copies, the geometry summary, the stroke sweep."""
    from . import drawing, grid, summary
    solver = Reference(record)
    params = inputs_of(wb, record)
    if record.synthesis is not None:
        from .synthesis import as_designed
        params = as_designed(wb, record, values, params)
    j = Judging(wb, record, values, rules, solver, solver.mechanism.build(), params,
                mechanism_size(record, params), own_inputs=own_inputs)
    _check_sweep(j)
    _check_position(j)
    drawing.check_drawing(j)
    if own_inputs:
        _check_degree_windows(j)
        j.checks += _check_numbers_only(j)
    _check_constants(j)
    if record.motion is not None:
        _check_motion(j)
    if record.forces is not None:
        from .force_cells import check_forces
        check_forces(j)
    if "closes" in record.sweep.columns and own_inputs:
        j.checks += summary.check_assembly(j)
    if record.grid is not None:
        j.checks += grid.check_grid(j)
    if record.synthesis is not None:
        from .synthesis import check_synthesis
        from .synthesis_drawing import check_positions_drawing
        angles = check_synthesis(j)
        if record.synthesis.drawing is not None:
            check_positions_drawing(j, record.synthesis.drawing, record.synthesis.sheet, angles)
    return j.checks


def _check_sweep(j: Judging) -> None:
    """The sweep table, column by column; sets the reference over the sweep's input values."""
    mech, sweep = j.mechanism, j.record.sweep
    j.angles = input_column(j.wb[sweep.sheet], "A", sweep.rows, mech.input_is_angle)
    # the slope of a cell is taken per radian of a crank, per `size` of an actuator's stroke
    j.scale = math.degrees(1.0) if mech.input_is_angle else j.size
    j.turns = j.shown_angles(sweep.sheet, {key: sweep.cells(key) for key in sweep.columns})
    j.ref = j.solver.solve(j.params, j.angles, j.turns)
    note_other_assembly(j, j.ref, lambda i: sweep.rows[0] + i)
    for key in sweep.columns:
        if key == mech.input_column or key in ASSEMBLY_COLUMNS:
            continue
        unit = column_unit(j.model, key)
        j.slopes[key] = j.slope(j.angles, key, unit)
        j.run(layout.SWEEP, key, sweep.sheet, sweep.cells(key), expected_of(j.ref, key), unit,
              j.slopes[key])


def _check_position(j: Judging) -> None:
    """The current position's cells; sets the reference at the current input value."""
    mech, pos = j.mechanism, j.record.position
    j.angle = input_at(j.wb[pos.sheet], pos.input_cell, f"the current input {mech.input_word}",
                       mech.input_is_angle)
    j.turns_now = j.shown_angles(pos.sheet, {key: [cell] for key, cell in pos.cells.items()})
    j.one = j.solver.solve(j.params, np.array([j.angle]), j.turns_now)
    note_other_assembly(j, j.one, None)
    for key, cell in pos.cells.items():
        unit = column_unit(j.model, key)
        j.run("position", key, pos.sheet, [cell], expected_of(j.one, key), unit,
              j.slope(np.array([j.angle]), key, unit))


def note_other_assembly(j: Judging, ref: dict, row_of) -> None:
    """A check naming each stretch of rows (`row_of`: the sheet's row of a reference row; None:
    the current position) where the book's method, Newton in two angles from the sketch or
    the row above, reaches another assembly than the reference's continuation in six
    coordinates (reference/steps/triad.py). The reference judges the book's cells there in the
    book's assembly, but which assembly is meant the data do not say: named, not passed."""
    from .reference.steps.triad_iterations import RESTARTED
    for first_joint, codes in ref.get("other_assembly", {}).items():
        rows = np.flatnonzero(codes)
        if not rows.size:
            continue
        c = Check("assembly", f"triad {first_joint}", j.size)
        differs = f"the book's assembly of the triad {first_joint} differs from the reference's"
        if row_of is None:
            c.assembly.append(f"the current position ({j.record.position.sheet}): {differs} "
                              "after a restart from the sketch")
        else:
            for run in np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1):
                a, b = row_of(int(run[0])), row_of(int(run[-1]))
                how = (f"after a restart at row {a}" if codes[run[0]] == RESTARTED
                       else f"from row {a} (its Newton from the row above)")
                c.assembly.append(f"{j.record.sweep.sheet} rows {a}–{b}: {differs} {how}")
        j.checks.append(c)


def _check_constants(j: Judging) -> None:
    """Derived constants: a time ratio from the reversals of its output (the reference's own
    motion, not the template's formula); any other from the reference."""
    ratios = time_ratios(j.solver.description)
    for key, info in j.record.constants.items():   # solve() returns them as floats
        if key in ratios:
            c = Check(f"reversals of {ratios[key]}", key, j.size)
            j.compare(c, layout.MECH, [info.cell], np.array([generic.time_ratio(
                j.solver.description, j.params, ratios[key])]), info.unit,
                rules=replace(j.rules, tol=RATIO_TOL, relative=True))
            j.checks.append(c)
            continue
        j.run("constants", key, layout.MECH, [info.cell], np.array([float(j.ref[key])]),
              info.unit)


def time_ratios(description: dict) -> dict[str, str]:
    """{expression key: output key} for the expressions declared a time ratio (time_ratio_of)."""
    return {s["key"]: s["time_ratio_of"] for s in description.get("steps", [])
            if isinstance(s, dict) and s.get("type") == "expression" and "time_ratio_of" in s}


def _check_numbers_only(j: Judging) -> list[Check]:
    """Each numbers-only column (what MIN and MAX read for an extent) holds its source cell's
    own number, or a dash where the source is not a number (#N/A: the loop cannot close) or
    there is no source (no joint in that row). The sources, a sweep column and the joints
    table, are judged against the reference themselves, with their own allowances."""
    sweep, pos = j.record.sweep, j.record.position
    checks = []
    for column in j.record.numbers_only:
        first, last = column.rows
        if column.sweep is not None:
            letter, (r0, r1) = sweep.columns[column.sweep], sweep.rows
            source_sheet, sources = sweep.sheet, column_cells(letter, r0, r1)
            name = column.sweep
        else:
            source_sheet = pos.sheet
            sources = [pos.joints[joint][column.axis] if joint else None
                       for joint in column.joints]
            name = f"joints {'xy'[column.axis]}"
        c = Check(column.sheet, f"{name} numbers only", j.size)
        cells = column_cells(column.column, first, last)[:len(sources)]
        # each column and its sources looked up together, not cell by cell
        wants = iter(j.got(source_sheet, [s for s in sources if s]))
        for cell, got, source in zip(cells, j.got(column.sheet, cells), sources):
            want = next(wants) if source else None
            if not isinstance(want, (int, float)) or isinstance(want, bool):
                want = DASH
            c.cells += 1
            c.judged.add((column.sheet, cell))
            if got != want or isinstance(got, bool):
                c.mismatches.append(Mismatch(column.sheet, cell, want, got))
        checks.append(c)
    return checks


def _check_degree_windows(j: Judging) -> None:
    """How a degree view shows its angle (docs/mechanisms.md): in one 360° window [lo, lo+360)
    for the sweep column and the current position, lo in [-180°, 180°) ([0°, 360°) for an angle
    that wraps). The build puts lo in the widest gap of the data it had; a user's edit moves the
    data, not the window, so only the window itself is judged here, from the values shown.
    The values are compared with the reference modulo 360° in the sweep and position checks."""
    sweep, pos = j.record.sweep, j.record.position
    rows = range(sweep.rows[0], sweep.rows[1] + 1)
    eps = 1e-9 * 360.0
    for key, letter in sweep.columns.items():
        if not key.endswith("_deg") or key[:-4] not in j.ref or key == j.mechanism.input_column:
            continue
        c = Check(layout.SWEEP, f"{key} window", j.size)
        j.checks.append(c)
        cells = [(sweep.sheet, f"{letter}{r}") for r in rows]
        if key in pos.cells:
            cells.append((pos.sheet, pos.cells[key]))
        shown = [(cell, float(v)) for cell in cells
                 if isinstance(v := j.values.get(cell), (int, float)) and not isinstance(v, bool)
                 and math.isfinite(v)]
        if not shown:
            continue
        (low_cell, low), (high_cell, high) = (min(shown, key=lambda s: s[1]),
                                              max(shown, key=lambda s: s[1]))
        if j.model.get(key[:-4]).wrap_360:
            first, last = 0.0, 0.0
        else:
            first, last = WINDOW_STARTS
        # some lo in [first, last] with low >= lo and high < lo + 360
        if low < first - eps:
            bad, want = (low_cell, low), f"at least {first:g}°"
        elif high >= last + 360.0 + eps:
            bad, want = (high_cell, high), f"below {last + 360.0:g}°"
        elif high - low >= 360.0 + eps:
            bad, want = (high_cell, high), f"within 360° of {low:.10g}° ({low_cell[1]})"
        else:
            continue
        c.mismatches.append(Mismatch(bad[0][0], bad[0][1],
                                     f"one 360° window starting in [{first:g}°, {last:g}°]: "
                                     f"{want}", bad[1]))


def _check_motion(j: Judging) -> None:
    """The Motion sheet (the sweep's rows and the current position's row) and the traced
    point's velocity under the current position."""
    from ..language.model import ACCEL, ANG_ACCEL, AREA, LENGTH, RATIO
    mech, motion = j.mechanism, j.record.motion
    sheet = motion.sheet
    rate1, rate2 = motion_rates(mech, j.params, j.size)
    (r0, r1), now = motion.rows, motion.current_row
    now_angle = np.array([j.angle])

    def slope(inputs, key, unit):
        return j.slope(inputs, key, unit, motion=True)

    j.run(sheet, mech.input_column, sheet, column_cells("A", r0, r1), j.angles,
          mech.input_unit)
    j.run(sheet, mech.input_column, sheet, [f"A{now}"], now_angle, mech.input_unit)
    for key, letter in motion.columns.items():
        unit = j.model.get(key).unit
        # a determinant is a position measured (an area's scale is S², see unit_scale)
        rate = {ACCEL: rate2, ANG_ACCEL: rate2, AREA: 1.0, LENGTH: 1.0, RATIO: 1.0}.get(unit,
                                                                                    rate1)
        j.run(sheet, key, sheet, column_cells(letter, r0, r1),
              expected_of(j.ref, key), unit, slope(j.angles, key, unit), rate,
              j.ref.get("dead_centre"), j.ref.get("sine"))
        j.run("motion now", key, sheet, [f"{letter}{now}"], expected_of(j.one, key), unit,
              slope(now_angle, key, unit), rate, j.one.get("dead_centre"), j.one.get("sine"))
    for key, cell in (j.record.position.motion_cells or {}).items():
        unit = j.model.get(key).unit
        rate = rate2 if unit in (ACCEL, ANG_ACCEL) else rate1
        j.run("position", key, layout.MECH, [cell], expected_of(j.one, key), unit,
              slope(now_angle, key, unit), rate, j.one.get("dead_centre"), j.one.get("sine"))
