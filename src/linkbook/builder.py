"""From a checked template to a saved workbook: lay out, evaluate, chart, write atomically."""
from __future__ import annotations

import math
from pathlib import Path

from . import charts, engine, package, workbook
from .controls import Control
from .files import write_atomic
from .model import COLUMN
from .templates import Template


def make(t: Template, values_needed: bool = True) -> tuple[workbook.Built, dict | None]:
    """The workbook and the value of every cell (the fast engine), or None for the values when
    not `values_needed` (a book saved without cached values: nothing else reads them).

    Output angles are shown in degrees in a 360° window chosen from the evaluated sweep, so that
    each curve is continuous; the degree views are rewritten after the evaluation and, when the
    values are needed, only they are evaluated again (every other cell keeps its value: no
    formula reads a degree view)."""
    built = workbook.build(t)
    values = engine.evaluate(built.workbook)
    changed = workbook.set_degree_windows(built, degree_windows(built, values))
    if not values_needed:
        values = None
    elif changed:
        known = {cell: v for cell, v in values.items() if cell not in changed}
        values = engine.evaluate(built.workbook, known=known)
    charts.add_charts(built, t, built.model)
    _print_setup(built.workbook)
    return built, values


def _print_setup(wb) -> None:
    """Page layout for printing and previews; the Mechanism sheet (inputs, current position and
    drawing side by side) prints one page wide, landscape, so no block is cut off."""
    from .office import apply_print_setup
    apply_print_setup(wb, fit_to_width=(workbook.MECH,))


def degree_windows(built: workbook.Built, values: dict) -> dict[str, float]:
    """For each output angle: the start of a 360° window that puts the cut in the widest empty
    arc of its sampled values (a multiple of 10°, in [-180°, 180°)). A full turn keeps [0°, 360°)."""
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    out = {}
    for q in built.model.of_role(COLUMN):
        if not q.in_degrees:
            continue
        if q.wrap_360:
            out[q.key] = 0.0
            continue
        letter = sweep["columns"][q.key]
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


def build_file(t: Template, path: Path, with_values: bool = False) -> workbook.Built:
    built, values = make(t, values_needed=with_values)

    def write(tmp: Path) -> None:
        built.workbook.save(tmp)
        controls = {sheet: [Control.of(c) for c in items]
                    for sheet, items in built.meta.get("controls", {}).items()}
        package.finish(tmp, tmp, values=values if with_values else None, controls=controls)

    write_atomic(path, write)
    return built
