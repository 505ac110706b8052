"""The judge of an adjustable mechanism's grid (one column per value of the adjustment): the
quantity in each cell, the Stroke sweep's columns and headers, the stroke under each column,
and how finely the stroke is sampled."""
from __future__ import annotations

import numpy as np

from . import reference as generic
from ..base.xlsx import column_cells
from ..language.domain import InputError, check_lengths_together, check_value
from .checks import Check, Mismatch
from .context import Judging, slope_of
from .reading import UnusableFile, input_column, number_at, written_in


def grid_reference(solver, params, param, angles, column_values):
    out = np.empty((len(angles), len(column_values)))
    for j, v in enumerate(column_values):
        out[:, j] = solver.solve({**params, param: v}, angles)[solver.mechanism.grid[1]]
    return out


def _adjustments(j: Judging, ws) -> list[float]:
    """The adjustment's values the grid's header row holds, each a valid value of its input."""
    grid, record = j.record.grid, j.record
    param = grid.param
    adjust = [number_at(ws, f"{c}{grid.param_row}", f"{param}") for c in grid.columns]
    kind = record.inputs[param].kind
    try:
        adjust = [check_value(f"{param} (cell {grid.sheet}!{c}{grid.param_row})", kind, v)
                  for c, v in zip(grid.columns, adjust)]
        check_lengths_together({**j.params, **{f"{param}@{c}": v for c, v in
                                               zip(grid.columns, adjust)}},
                               {**record.kinds(), **{f"{param}@{c}": kind for c in grid.columns}},
                               "input ", written_in(record))
    except InputError as exc:
        raise UnusableFile(str(exc)) from None
    return adjust


def check_grid(j: Judging) -> list[Check]:
    checks = []
    grid, stroke = j.record.grid, j.record.stroke
    solver, param = j.solver, grid.param
    expected_by_block = {}
    # at another input set (input_sets.py) the grid alone: the Stroke sweep holds the grid's
    # own formula at finer angles, and the stroke under the grid is that sampling's
    own_sweep = stroke.sheet != grid.sheet and j.own_inputs    # else the grid is its own
    for block in (grid, stroke) if own_sweep else (grid,):
        ws = j.wb[block.sheet]
        angles = input_column(ws, "A", block.rows, solver.mechanism.input_is_angle)
        if block is grid:
            adjust = _adjustments(j, ws)
        expected = grid_reference(solver, j.params, param, angles, adjust)
        expected_by_block[block.sheet] = expected
        c = Check(block.sheet, f"{grid.key} grid", j.size, scale=j.size)
        slope = slope_of(solver, j.params, angles, solver.mechanism.grid[1], "length", param,
                         adjust)
        for k, letter in enumerate(block.columns):
            cells = column_cells(letter, block.rows[0], block.rows[1])
            j.compare(c, block.sheet, cells, expected[:, k], "length",
                      lambda i, k=k, slope=slope: slope(i, k))
        checks.append(c)
        if own_sweep and block is stroke:
            heads = [f"{x}{stroke.param_row}" for x in stroke.columns]
            h = Check(block.sheet, f"{param} header", j.size, scale=j.size)
            j.compare(h, block.sheet, heads, np.array(adjust), "length")
            checks.append(h)
    if not j.own_inputs:
        return checks
    fine = expected_by_block[stroke.sheet]
    strokes = np.ptp(fine, axis=0)          # NaN where some angle cannot close
    cells = [f"{c}{grid.stroke_row}" for c in grid.columns]
    s = Check(grid.sheet, "stroke", j.size, scale=j.size)
    j.compare(s, grid.sheet, cells, strokes, "length")
    checks.append(s)
    checks.append(_check_stroke_sampling(j, adjust))
    return checks


def _check_stroke_sampling(j: Judging, adjust: list) -> Check:
    """The stroke under the grid is max − min over a sweep sampled every `stroke_step`
    degrees (the template's, as recorded): it may fall short of the true stroke (the
    reference's extremes, refined to 1e-6°) by what a sample h/2 from each extreme loses, and
    never exceed it. A sweep sampled more coarsely than the template asks misses by more."""
    solver, params, grid, values = j.solver, j.params, j.record.grid, j.values
    key = solver.mechanism.grid[1]
    c = Check(grid.sheet, "stroke sampling", j.size, scale=j.size)
    if grid.stroke_step is None:       # a book built before the record kept it
        return c
    h = float(grid.stroke_step)
    angles = np.arange(0.0, 360.0, generic.EXTREME_STEP)
    for letter, v in zip(grid.columns, adjust):
        cell = f"{letter}{grid.stroke_row}"
        got = values.get((grid.sheet, cell))
        p = generic.positions_only({**params, grid.param: v})
        fine = np.asarray(solver.solve(p, angles)[key], dtype=float)
        if not np.isfinite(fine).all() or not isinstance(got, (int, float)) \
                or isinstance(got, bool):
            continue        # the stroke check at the book's own angles judges this cell
        top_at, top = generic.refined_extreme(solver.description, p, key, angles, fine, np.argmax)
        low_at, low = generic.refined_extreme(solver.description, p, key, angles, fine, np.argmin)
        near = solver.solve(p, np.array([top_at - h / 2, top_at + h / 2,
                                         low_at - h / 2, low_at + h / 2]))[key]
        near = np.asarray(near, dtype=float)
        allowance = (top - min(near[0], near[1])) + (max(near[2], near[3]) - low)
        true = top - low
        limit = c.limit(true)
        if not true - allowance - limit <= got <= true + limit:
            c.mismatches.append(Mismatch(
                grid.sheet, cell, f"{true:.10g} (the true stroke; a {h:g}° sampling may "
                                     f"fall short by {allowance:.3g})", float(got)))
    return c

