"""From a checked template to a saved workbook: lay out, evaluate, chart, write atomically."""
from __future__ import annotations

import math
from pathlib import Path

from . import charts, engine, package, workbook
from .controls import Control
from .files import write_atomic
from .model import COLUMN, _one_group
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
    angles = engine.evaluate(built.workbook, only=degree_window_sources(built))
    workbook.set_degree_windows(built, degree_windows(built, angles))
    workbook.set_radian_windows(built, radian_windows(built, angles))
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


def _cut_columns(built: workbook.Built):
    """(quantity, its sweep column letter) of every angle that is one ATAN2: its cut at ±180°
    can fall on a sample (the crank at 180° puts a pin on the ground line), where the sign of
    a rounding error in a sine, which applications do not share, would pick +π or −π."""
    columns = built.meta["sweep"]["columns"]
    return [(q, columns[q.key]) for q in built.model.of_role(COLUMN)
            if q.formula.startswith("ATAN2(") and _one_group(q.formula)]


def degree_window_sources(built: workbook.Built) -> set[tuple[str, str]]:
    """The sweep cells whose values choose the degree windows (and the radian windows of the
    ATAN2 columns)."""
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    columns = [(q, letter) for q, letter in _angle_columns(built) if not q.wrap_360]
    return {(sweep["sheet"], f"{letter}{r}") for q, letter in columns + _cut_columns(built)
            for r in range(r0, r1 + 1)}


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
        out[q.key] = _cut(_sampled_degrees(built, values, letter))
    return out


def radian_windows(built: workbook.Built, values: dict) -> dict[str, float]:
    """For each ATAN2 column: the start of a 360° window (degrees) for its radian values that
    puts the cut in the widest empty arc of its samples, also for an angle that turns all the
    way round, so that no sample sits on the cut."""
    return {q.key: _cut(_sampled_degrees(built, values, letter), full_turn=None)
            for q, letter in _cut_columns(built)}


def _sampled_degrees(built: workbook.Built, values: dict, letter: str) -> list[float]:
    sweep = built.meta["sweep"]
    r0, r1 = sweep["rows"]
    return sorted(math.degrees(v) % 360.0 for r in range(r0, r1 + 1)
                  if isinstance(v := values.get((sweep["sheet"], f"{letter}{r}")), float)
                  and math.isfinite(v))


def _cut(degs: list[float], full_turn: float | None = 0.0) -> float:
    """A window start in the widest gap of `degs` (a multiple of 10° where one fits); for an
    angle that turns all the way round (no gap of 20°), `full_turn` (None: in the gap too)."""
    if not degs:
        return -180.0
    gaps = [(b - a, a, b) for a, b in zip(degs, degs[1:] + [degs[0] + 360.0])]
    width, a, b = max(gaps)
    if width < 20.0 and full_turn is not None:   # any window has a jump
        return full_turn
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
