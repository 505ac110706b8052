"""The workbook's layout: which sheets a linkbook workbook has, in which order they are laid out,
and the build record that says where each quantity lives.

Sheets: Mechanism (inputs with defined names, derived constants, the current position with its
joints table and drawing, the geometry summary: mechanism.py, joints.py, summary.py), Sweep (one
row per input value, one formula column per step: sweep.py), Motion (velocities and
accelerations: motion.py), Charts (filled by charts.py once values are known), for a mechanism
with a grid (the pump) Grid and Stroke (grid.py, stroke.py), and Drawing data (the live frames of
the equal-scale charts: frames.py). A hidden sheet `linkbook` holds the build record, so that
`verify` can read an edited workbook back. Each sheet's cells are laid out with the style kit
(style.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from openpyxl import Workbook
from openpyxl.utils import column_index_from_string

from ..base import __version__
from ..base.record import BuildRecord
from ..base.sheets import (CHARTS, FORCES_SHEET, FORMAT_VERSION, GRID, MECH, META, MOTION_SHEET,
                           STROKE, SWEEP, SYNTHESIS, write_meta)
from ..language.forces import FORCE
from ..language.model import COLUMN, MOTION, Model
from ..language.templates import Template
from .forces import forces_table
from .frames import frames_sheet
from .grid import grid_sheet
from .mechanism import form_controls, inputs_block, position_block, position_motion
from .motion import motion_table
from .stroke import grid_is_fine, stroke_row, stroke_sheet
from .style import set_formula, top_align_tall_rows
from .summary import summary_block
from .synthesis import synthesis_sheet
from .synthesis_dyads import dyads_sheet
from .sweep import default_window, degree_formula, radian_window, sweep_numbers_only, sweep_table


@dataclass
class Built:
    """The workbook and the record of where everything is (stored in the hidden sheet): as
    the writer assembled it (`meta`) and typed (`record`)."""
    workbook: Workbook
    model: Model
    meta: dict = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)   # for the builder's user, not the book
    record: BuildRecord | None = None


def build(t: Template) -> Built:
    """Lay the workbook out; each output angle's degree view starts at its default window
    (set_degree_windows moves it)."""
    model = t.mechanism.build()
    wb = Workbook()
    wb.security = None      # openpyxl's default writes an empty <workbookProtection/>: it
                            # protects nothing, and Gnumeric does not know the element
    ws_mech = wb.active
    ws_mech.title = MECH
    ws_sweep = wb.create_sheet(SWEEP)
    ws_motion = wb.create_sheet(MOTION_SHEET) if model.of_role(MOTION) else None
    ws_forces = wb.create_sheet(FORCES_SHEET) if model.of_role(FORCE) else None
    ws_synthesis = wb.create_sheet(SYNTHESIS, 1) if t.synthesis is not None else None
    wb.create_sheet(CHARTS)     # filled by charts.add_charts once values are known
    meta = {"format": FORMAT_VERSION, "linkbook": __version__, "template": t.name,
            "mechanism": t.mechanism.name, "title": t.title, "length_unit": t.length_unit,
            "input": t.mechanism.input_key}
    if t.mechanism.description is not None:
        meta["description"] = t.mechanism.description

    names, meta["inputs"], meta["constants"], next_row = inputs_block(wb, ws_mech, t, model)
    if ws_synthesis is not None:
        # function generation, or motion and path generation (the standard dyad form)
        sheet = synthesis_sheet if t.synthesis.kind == "function" else dyads_sheet
        meta["synthesis"] = sheet(wb, ws_synthesis, t, model, names)
    meta["position"] = position_block(wb, ws_mech, t, model, names)
    meta["sweep"] = sweep_table(ws_sweep, t, model, names)
    if ws_motion is not None:
        meta["motion"] = motion_table(ws_motion, t, model, names, meta["sweep"],
                                      meta["position"])
        position_motion(ws_mech, t, model, meta["position"], meta["motion"])
    if ws_forces is not None:
        meta["forces"] = forces_table(wb, ws_forces, t, model, names, meta["sweep"],
                                      meta["position"], meta["motion"])
    meta["numbers_only"] = sweep_numbers_only(ws_sweep, t, model, meta["sweep"])
    meta["summary"] = summary_block(ws_mech, t, model, names, meta["sweep"], next_row + 1)
    top_align_tall_rows(ws_mech)
    meta["controls"] = {MECH: form_controls(ws_mech, t, meta["inputs"])}
    if t.mechanism.grid:
        meta["grid"] = grid_sheet(wb.create_sheet(GRID), t, model, names)
        meta["grid"]["stroke_step"] = t.stroke_step     # the template's: what verify expects
        # A grid that already samples a whole turn finely enough is its own stroke sweep.
        meta["stroke"] = (meta["grid"] if grid_is_fine(t) else
                          stroke_sheet(wb.create_sheet(STROKE), t, model, names, meta["grid"]))
        meta["grid"]["stroke_row"] = stroke_row(wb[GRID], t, meta["grid"], meta["stroke"])
    meta["frames"] = frames_sheet(wb, t, model, meta)
    record = BuildRecord.from_json(meta)      # a key the record does not know fails here
    write_meta(wb.create_sheet(META), record)
    return Built(wb, model, meta, record=record)


def set_degree_windows(built: Built, windows: dict[str, float]) -> None:
    """Rewrite the degree views (current position and sweep) of the output angles whose window
    start `windows` gives."""
    position, sweep = built.meta["position"], built.meta["sweep"]
    r0, r1 = sweep["rows"]
    ws_mech, ws_sweep = built.workbook[MECH], built.workbook[SWEEP]
    for q in built.model.of_role(COLUMN):
        key = f"{q.key}_deg"
        if not q.in_degrees or windows.get(q.key, default_window(q)) == default_window(q):
            continue
        cell = position["cells"][key]
        set_formula(ws_mech[cell], degree_formula(q, position["cells"][q.key], windows[q.key]))
        letter, source = sweep["columns"][key], sweep["columns"][q.key]
        col = column_index_from_string(letter)
        for r in range(r0, r1 + 1):
            set_formula(ws_sweep.cell(r, col), degree_formula(q, f"{source}{r}", windows[q.key]))


def set_radian_windows(built: Built, windows: dict[str, float]) -> None:
    """Rewrite the radian cells (current position and sweep) of the ATAN2 angles whose window
    start (degrees) `windows` gives, where it is not ATAN2's own (-180°, 180°]."""
    position, sweep = built.meta["position"], built.meta["sweep"]
    r0, r1 = sweep["rows"]
    ws_mech, ws_sweep = built.workbook[MECH], built.workbook[SWEEP]
    for key, lo in windows.items():
        if lo == -180.0:
            continue
        cell = position["cells"][key]
        set_formula(ws_mech[cell], radian_window(ws_mech[cell].value, lo))
        col = column_index_from_string(sweep["columns"][key])
        for r in range(r0, r1 + 1):
            set_formula(ws_sweep.cell(r, col), radian_window(ws_sweep.cell(r, col).value, lo))

