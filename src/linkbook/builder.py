"""From a checked template to a saved workbook: lay out, evaluate, chart, write atomically."""
from __future__ import annotations

import math
from pathlib import Path

from . import charts, engine, package, workbook
from .controls import Control
from .files import write_atomic
from .model import COLUMN
from .pause import gc_paused
from .templates import Template


def make(t: Template, values_needed: bool = True) -> tuple[workbook.Built, dict | None]:
    """The workbook and the value of every cell (the fast engine), or None for the values when
    not `values_needed` (a book saved without cached values: nothing else reads them).

    Output angles are shown in degrees in a 360° window chosen from the evaluated sweep, so that
    each curve is continuous: the angles, and only what they need, are evaluated first; the
    degree views are written with their windows; then, when the values are needed, the whole
    book is evaluated."""
    built = workbook.build(t)
    angles = engine.evaluate(built.workbook,
                             only=degree_window_sources(built) | loop_witness_cells(built))
    workbook.set_degree_windows(built, degree_windows(built, angles))
    built.warnings += closure_warnings(built, t, angles)
    values = engine.evaluate(built.workbook) if values_needed else None
    charts.add_charts(built, t, built.model)
    _print_setup(built.workbook)
    return built, values


def _print_setup(wb) -> None:
    """Page layout for printing and previews; the Mechanism sheet (inputs, current position and
    drawing side by side) prints one page wide, landscape, so no block is cut off."""
    from .office import apply_print_setup
    apply_print_setup(wb, fit_to_width=(workbook.MECH,))


def _angle_columns(built: workbook.Built):
    """(quantity, its sweep column letter) of every output angle shown in degrees."""
    columns = built.meta["sweep"]["columns"]
    return [(q, columns[q.key]) for q in built.model.of_role(COLUMN) if q.in_degrees]


def degree_window_sources(built: workbook.Built) -> set[tuple[str, str]]:
    """The sweep cells whose values choose the degree windows."""
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    return {(sweep["sheet"], f"{letter}{r}") for q, letter in _angle_columns(built)
            if not q.wrap_360 for r in range(r0, r1 + 1)}


def loop_witness_cells(built: workbook.Built) -> set[tuple[str, str]]:
    """The sweep cells of each loop step's witness column: a number exactly where it closes."""
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    return {(sweep["sheet"], f"{sweep['columns'][key]}{r}") for key in built.model.closes
            for r in range(r0, r1 + 1)}


def closure_warnings(built: workbook.Built, t: Template, values: dict) -> list[str]:
    """One line for the first loop step that cannot close somewhere in the sweep (the steps
    after it fail there with it): which step, and over which input values."""
    sweep, model = built.meta["sweep"], built.model
    r0, r1 = sweep["rows"]
    inputs = t.sweep.angles()
    for key, (step, _) in zip(model.closes, model.loop_steps):
        letter = sweep["columns"][key]
        failing = [inputs[r - r0] for r in range(r0, r1 + 1)
                   if not isinstance(values.get((sweep["sheet"], f"{letter}{r}")), float)]
        if failing:
            return [f"{step}: the loop cannot close {_where(t, inputs, failing)}; every cell "
                    "that depends on it is #N/A there"]
    return []


def _where(t: Template, inputs: list[float], failing: list[float]) -> str:
    """'at any θ12 of the sweep (0° to 360°)', 'for θ12 from 40° to 120°, at 300° (18 of 73
    rows)'."""
    mech = t.mechanism
    unit = "°" if mech.input_is_angle else f" {t.length_unit}"
    if len(failing) == len(inputs):
        return f"at any {mech.input_symbol} of the sweep ({inputs[0]:g}{unit} to " \
               f"{inputs[-1]:g}{unit})"
    runs, index = [], {x: i for i, x in enumerate(inputs)}
    for x in failing:
        if runs and index[x] == index[runs[-1][1]] + 1:
            runs[-1][1] = x
        else:
            runs.append([x, x])
    spans = [f"at {a:g}{unit}" if a == b else f"from {a:g}{unit} to {b:g}{unit}"
             for a, b in runs]
    shown = ", ".join(spans[:3]) + (f" and {len(spans) - 3} more" if len(spans) > 3 else "")
    return f"for {mech.input_symbol} {shown} ({len(failing)} of {len(inputs)} rows)"


def degree_windows(built: workbook.Built, values: dict) -> dict[str, float]:
    """For each output angle: the start of a 360° window that puts the cut in the widest empty
    arc of its sampled values (a multiple of 10°, in [-180°, 180°)). A full turn keeps [0°, 360°)."""
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    out = {}
    for q, letter in _angle_columns(built):
        if q.wrap_360:
            out[q.key] = 0.0
            continue
        degs = sorted(math.degrees(v) % 360.0 for r in range(r0, r1 + 1)
                      if isinstance(v := values.get((sweep["sheet"], f"{letter}{r}")), float)
                      and math.isfinite(v))
        out[q.key] = _cut(degs)
    return out


def _cut(degs: list[float]) -> float:
    if not degs:
        return -180.0
    gaps = [(b - a, a, b) for a, b in zip(degs, degs[1:] + [degs[0] + 360.0])]
    width, a, b = max(gaps)
    if width < 20.0:       # the angle turns all the way round: any window has a jump
        return 0.0
    lo = math.floor((a + b) / 2 / 10.0) * 10.0
    if not a < lo < b:
        lo = (a + b) / 2
    return (lo + 180.0) % 360.0 - 180.0


@gc_paused
def build_file(t: Template, path: Path, with_values: bool = False) -> workbook.Built:
    built, values = make(t, values_needed=with_values)

    def write(tmp: Path) -> None:
        with package.cells_held_back(built.workbook) as cells:
            built.workbook.save(tmp)
        controls = {sheet: [Control.of(c) for c in items]
                    for sheet, items in built.meta.get("controls", {}).items()}
        package.finish(tmp, tmp, values=values if with_values else None, controls=controls,
                       cells=cells)

    write_atomic(path, write)
    return built
