"""From a checked template to a saved workbook: lay out, evaluate, chart, write atomically."""
from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

from . import charts
from ..language import domain
from ..engine import evaluator as engine
from . import package
from . import workbook
from .controls import Control
from .stroke import grid_is_fine
from ..base.sheets import GRID, MECH, STROKE, SYNTHESIS
from ..base.files import write_atomic
from ..language.excel import is_direction
from ..language.model import COLUMN
from ..base.pause import gc_paused
from ..language.templates import FLAGS, Sweep, Template
from ..base.xlsx import column_letter, xml_text


def make(t: Template, values_needed: bool = True) -> tuple[workbook.Built, dict | None]:
    """The workbook and the value of every cell (the fast engine), or None for the values when
    not `values_needed` (a book saved without cached values: nothing else reads them).

    Output angles are shown in degrees in a 360° window chosen from the evaluated sweep, so that
    each curve is continuous: the angles, and only what they need, are evaluated first; the
    degree views are written with their windows; then, when the values are needed, the whole
    book is evaluated."""
    if table_cells(t) > SMALL_BOOK:
        domain.check_size(*book_size(t, values_needed))
    built = workbook.build(t)
    built.warnings += check_frames(t, built.model)
    angles = engine.evaluate(built.workbook,
                             only=degree_window_sources(built) | loop_witness_cells(built))
    workbook.set_degree_windows(built, degree_windows(built, angles))
    built.warnings += closure_warnings(built, t, angles)
    workbook.set_radian_windows(built, radian_windows(built, angles))
    values = engine.evaluate(built.workbook) if values_needed else None
    charts.add_charts(built, t, built.model)
    _print_setup(built)
    return built, values


def check_frames(t: Template, model) -> list[str]:
    """Refuse a step's frame whose two points are at one place on every row of the sweep (two
    ground points at one place, a slide's point on its pivot at offset 0): its direction is
    undefined, so every cell it places would be #N/A. A centre of mass's such frame is one
    warning line (its link's forces are #N/A; the kinematics stand). Where they meet on some
    rows only (a crank pin passing over a pivot) those rows are #N/A, as the reference says.
    Measured on the reference's positions with the template's values."""
    if not model.frames:
        return []
    import numpy as np
    from ..check import reference
    angles = np.array(t.sweep.angles())
    try:
        points = reference.solve(t.mechanism.description,
                                 reference.positions_only(t.values()), angles)["points"]
    except ValueError:          # what the reference cannot solve, verify says
        return []

    def xy(point: str) -> np.ndarray:
        return np.array([np.broadcast_to(np.asarray(c, dtype=float), angles.shape)
                         for c in points[point]])
    warnings = []
    for field, a, b, step in model.frames:
        dx, dy = xy(b) - xy(a)
        met, defined = (dx == 0) & (dy == 0), np.isfinite(dx) & np.isfinite(dy)
        if not (met.any() and met[defined].all()):
            continue
        what = f"{a} and {b} are at one place on every row of the sweep"
        if step:
            raise domain.InputError(field, f"{what}: a frame needs two points apart (its "
                                           "direction is undefined)")
        warnings.append(f"{field}: {what}: the link's centre of mass, and every force it "
                        "reaches, is #N/A")
    return warnings


def _print_setup(built: workbook.Built) -> None:
    """Page layout for printing and previews; the Mechanism sheet (inputs, current position and
    drawing side by side) prints one page wide, landscape, so no block is cut off, and the
    Forces sheet's summary on one page."""
    from .forces import summary_rows
    from .pages import apply_print_setup
    forces = built.meta.get("forces")
    kept = {forces["sheet"]: [summary_rows(forces)]} if forces else {}
    apply_print_setup(built.workbook, fit_to_width=(MECH, SYNTHESIS), keep_together=kept)


def _angle_columns(built: workbook.Built):
    """(quantity, its sweep column letter) of every output angle shown in degrees."""
    columns = built.record.sweep.columns
    return [(q, columns[q.key]) for q in built.model.of_role(COLUMN) if q.in_degrees]


def _cut_columns(built: workbook.Built):
    """(quantity, its sweep column letter) of every angle that is one ATAN2: its cut at ±180°
    can fall on a sample (the crank at 180° puts a pin on the ground line), where the sign of
    a rounding error in a sine, which applications do not share, would pick +π or −π."""
    columns = built.record.sweep.columns
    return [(q, columns[q.key]) for q in built.model.of_role(COLUMN)
            if is_direction(q.formula)]


def degree_window_sources(built: workbook.Built) -> set[tuple[str, str]]:
    """The sweep cells whose values choose the degree windows (and the radian windows of the
    ATAN2 columns)."""
    sweep = built.record.sweep
    r0, r1 = sweep.rows
    columns = [(q, letter) for q, letter in _angle_columns(built) if not q.wrap_360]
    return {(sweep.sheet, f"{letter}{r}") for q, letter in columns + _cut_columns(built)
            for r in range(r0, r1 + 1)}


def loop_witness_cells(built: workbook.Built) -> set[tuple[str, str]]:
    """The sweep cells of each loop step's witness column: a number exactly where it closes."""
    sweep = built.record.sweep
    r0, r1 = sweep.rows
    return {(sweep.sheet, f"{sweep.columns[key]}{r}") for key in built.model.closes
            for r in range(r0, r1 + 1)}


def closure_warnings(built: workbook.Built, t: Template, values: dict) -> list[str]:
    """One line for the first loop step that cannot close somewhere in the sweep (the steps
    after it fail there with it): which step, and over which input values."""
    sweep, model = built.record.sweep, built.model
    r0, r1 = sweep.rows
    inputs = t.sweep.angles()
    for key, (step, _) in zip(model.closes, model.loop_steps):
        letter = sweep.columns[key]
        failing = [inputs[r - r0] for r in range(r0, r1 + 1)
                   if not isinstance(values.get((sweep.sheet, f"{letter}{r}")), float)]
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
    sweep = built.record.sweep
    r0, r1 = sweep.rows
    return sorted(math.degrees(v) % 360.0 for r in range(r0, r1 + 1)
                  if isinstance(v := values.get((sweep.sheet, f"{letter}{r}")), float)
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
def build_template(template: str | Path, output: str | Path | None = None, *, sets=(),
                   step=None, branch: str | None = None, unit: str | None = None,
                   values: bool = False, names: dict[str, str] = FLAGS
                   ) -> tuple[Path, workbook.Built]:
    """One workbook from a bundled template's name or a .toml file, with `unit`, `sets`, `step`
    and `branch` applied, written to `output` (None: <name>.xlsx here): the build of both
    `linkbook build` and linkbook.build. `names`: what the messages call the arguments
    (templates.FLAGS for the command, templates.ARGUMENTS for the API)."""
    from ..base.files import check_output
    from ..language import templates
    t = templates.load(str(template))
    if unit is not None:
        t = templates.with_unit(t, unit, names["unit"])
    t = templates.with_overrides(t, list(sets), step, branch, names)
    path = check_output(Path(output) if output is not None else Path(f"{t.name}.xlsx"),
                        names["output"], (".xlsx",))
    return path, build_file(t, path, values)


def build_file(t: Template, path: Path, with_values: bool = False) -> workbook.Built:
    built, values = make(t, values_needed=with_values)

    def write(tmp: Path) -> None:
        with package.cells_held_back(built.workbook) as cells:
            built.workbook.save(tmp)
        controls = {sheet: [Control.of(c.to_json()) for c in items]
                    for sheet, items in built.record.controls.items()}
        package.finish(tmp, tmp, values=values if with_values else None, controls=controls,
                       cells=cells)
        _refuse_beyond_verify(tmp)

    write_atomic(path, write)
    return built


def _refuse_beyond_verify(path: Path) -> None:
    """The written book, checked as verify will check it (safety.check_zip: its XML, exactly,
    where book_size estimated it): one verify would refuse is refused before it takes the place
    of anything."""
    from ..base.safety import UnsafeFile, check_zip
    try:
        check_zip(path)
    except UnsafeFile as exc:
        raise domain.InputError("book size", f"verify would refuse the book: "
                                        f"{str(exc).split(': ', 1)[-1]}") from None


# ---------------------------------------------------------------- how big a book will be
# A book of at most this many sweep rows and grid cells stays inside the budget whatever its
# mechanism (300 formula cells a row would be 1.5 million cells; a grid cell holds at most about
# 8 kB, base.xlsx.FORMULA_LENGTH_LIMIT), so its size is not estimated: every bundled template.
SMALL_BOOK = 5_000
SMALL_ROWS = 3            # sweep rows of the small books a size is measured on
OTHER_PARTS = 2 * 2**20   # charts, drawings, styles, controls: bytes, generously
VALUE_BYTES = 24          # a stored value: <v> and up to 17 digits, sign and exponent
_REFERENCE = re.compile(r"(?<![A-Za-z_\d.])\$?[A-Z]{1,3}\$?\d+(?![\d(])")


def table_cells(t: Template) -> int:
    """Sweep rows plus grid cells: what a book's size grows with."""
    rows = (t.sweep.stop - t.sweep.start) / t.sweep.step + 2
    if not t.mechanism.grid:
        return int(rows)
    fine = 0 if grid_is_fine(t) else 360 / t.stroke_step + 1
    return int(rows + (rows + fine) * len(t.grid_values))


def book_size(t: Template, with_values: bool = False) -> tuple[int, int]:
    """(formula cells, bytes of XML) of the book `t` makes, estimated before it is laid out:
    from two small books of the same mechanism (SMALL_ROWS and one more sweep row, one grid
    column, a three-row stroke sweep), what a sweep row adds, a grid cell holds and the rest
    takes, scaled to `t`'s rows and columns (a cell reference grows with its row's digits)."""
    rows = int(table_cells(replace(t, grid_values=())))
    if rows <= SMALL_ROWS + 1 and len(t.grid_values) <= 1:
        first = second = _layout_size(t)
        rows_small = rows
    else:
        first = _layout_size(_small(t, SMALL_ROWS))
        second = _layout_size(_small(t, SMALL_ROWS + 1))
        rows_small = SMALL_ROWS
    grow = len(str(rows + 10)) - 1                    # digits a row number gains
    per_row = [b - a for a, b in zip(first["rows"], second["rows"])]   # cells, bytes, refs
    cells = first["rows"][0] + (rows - rows_small) * per_row[0]
    xml = first["rows"][1] + (rows - rows_small) * (per_row[1] + per_row[2] * grow)
    if t.mechanism.grid:
        columns = len(t.grid_values)
        fine = 0 if grid_is_fine(t) else int(round(360 / t.stroke_step)) + 1
        size, refs = first["grid cell"]
        grid_cells = (rows + 1 + fine + 1) * columns
        grow = len(str(max(rows, fine) + 10)) - 1 + len(column_letter(columns + 1)) - 1
        cells += grid_cells
        xml += grid_cells * (size + refs * grow)
    if with_values:
        xml += cells * VALUE_BYTES
    return cells, xml + OTHER_PARTS


def _small(t: Template, rows: int) -> Template:
    """`t` with `rows` sweep rows, one grid column and a three-row stroke sweep."""
    s = t.sweep
    return replace(t, sweep=Sweep(s.start, s.start + (rows - 1) * s.step, s.step),
                   grid_values=t.grid_values[:1], stroke_step=180.0)


def _layout_size(t: Template) -> dict:
    """Formula cells and bytes of cell XML (about what package writes) of `t`'s layout: "rows"
    (cells, bytes, references) of every sheet but the grid's; "grid cell" the largest of the
    grid's formula cells (bytes, references), all but a few of which hold the same formula."""
    built = workbook.build(t)
    out = {"rows": [0, 0, 0], "grid cell": [0, 0]}
    for ws in built.workbook.worksheets:
        grid = ws.title in (GRID, STROKE)
        rows = out["rows"]
        for cell in ws._cells.values():
            value = cell._value
            size = 32 + len(cell.coordinate)
            if cell.data_type == "f" and isinstance(value, str):
                size += len(xml_text(value).encode("ascii", "xmlcharrefreplace"))
                refs = len(_REFERENCE.findall(value))
                if grid:
                    out["grid cell"] = max(out["grid cell"], [size, refs])
                    continue
                rows[0] += 1
                rows[2] += refs
            if not grid:
                rows[1] += size
    return out
