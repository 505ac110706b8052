"""The Mechanism sheet's inputs and current position: the named input cells (each with its
check), the constants derived from them, the current position that one input value drives (with
the traced point's velocity and acceleration), and the form controls that turn the input.

The sheet's other blocks, the joints table the drawing reads and the geometry summary, are
joints.py's and summary.py's.
"""
from __future__ import annotations

import math

from openpyxl.styles import Alignment
from openpyxl.utils import quote_sheetname
from openpyxl.worksheet.datavalidation import DataValidation

from ..base.sheets import MECH, MOTION_SHEET
from ..language.domain import INPUT_ANGLE_LIMIT
from ..language.mechanisms import ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, constant_name, position_name
from ..language.model import CONSTANT, DEG, LENGTH, Model
from .resolve import Resolver
from ..language.templates import Template
from .controls import control_record
from .joints import joints_table
from .style import (BOLD, BOX, DERIVED_FILL, INPUT_FILL, NOTE, TITLE, block_head, define_name,
                    number_format, put_text, set_formula, text_width, unit_text, wrap_in)
from .sweep import degree_formula, sweep_columns


def inputs_block(wb, ws, t: Template, model: Model):
    """The title, then the Inputs block: each template parameter in a named yellow cell with its
    check, then the constants derived from them. Returns the Excel name of each symbol, the
    records of the inputs and the constants, and the first row under the block."""
    put_text(ws, "A1", t.title, TITLE)
    put_text(ws, "A2", t.source, NOTE)
    put_text(ws, "A3", "Yellow cells are inputs: change them and every formula, table and "
                       "chart follows.", NOTE)
    symbols = [p.symbol for p in t.parameters] + [q.symbol for q in model.of_role(CONSTANT)]
    labels = [p.label for p in t.parameters] + [q.label for q in model.of_role(CONSTANT)]
    block_head(ws, "A", "Inputs", (("Quantity", _label_width(labels)),
                                   ("Symbol", max([9] + [text_width(s) for s in symbols])),
                                   ("Value", 12), ("Unit", 8), ("Excel name", 14)))
    names: dict[str, str] = {}
    inputs: dict[str, dict] = {}
    row = 7
    for p in t.parameters:
        put_text(ws, f"A{row}", p.label)
        wrap_in(ws, f"A{row}")
        put_text(ws, f"B{row}", p.symbol)
        names[p.symbol] = p.name
        if p.designed_by:
            inputs[p.symbol] = _designed_link(ws, row, p, t.length_unit)
            row += 1
            continue
        value = ws[f"C{row}"]
        value.value = int(p.value) if p.kind == BRANCH_KIND else p.value
        value.fill = INPUT_FILL
        value.border = BOX
        value.number_format = "0" if p.kind == BRANCH_KIND else "General"
        put_text(ws, f"D{row}", p.unit)
        put_text(ws, f"E{row}", p.name, NOTE)
        dv = _validation(p.kind, p.label)
        ws.add_data_validation(dv)
        dv.add(f"C{row}")
        define_name(wb, p.name, MECH, f"C{row}")
        inputs[p.symbol] = {"cell": f"C{row}", "name": p.name, "kind": p.kind}
        row += 1
    constants: dict[str, dict] = {}
    derived = model.of_role(CONSTANT)
    if derived:
        row += 1
        ws[f"A{row}"] = "Derived from the inputs"
        ws[f"A{row}"].font = BOLD
        row += 1
        resolve = Resolver(model, names, {})
        for q in derived:
            name = constant_name(q.key)
            put_text(ws, f"A{row}", q.label)
            wrap_in(ws, f"A{row}")
            put_text(ws, f"B{row}", q.symbol)
            c = ws[f"C{row}"]
            set_formula(c, resolve.formula(q.key))
            c.fill = DERIVED_FILL
            c.number_format = number_format(q.unit, t.length_unit)
            put_text(ws, f"D{row}", unit_text(q.unit, t.length_unit))
            put_text(ws, f"E{row}", name, NOTE)
            define_name(wb, name, MECH, f"C{row}")
            names[q.key] = name
            constants[q.key] = {"cell": f"C{row}", "name": name, "unit": q.unit}
            row += 1
    return names, inputs, constants, row


def _designed_link(ws, row: int, p, length_unit: str) -> dict:
    """A designed parameter's row: a link to its named cell on the Synthesis sheet, shaded as
    derived, never an input; its record names that cell and the link."""
    c = ws[f"C{row}"]
    set_formula(c, f"={p.name}")
    c.fill = DERIVED_FILL
    c.number_format = "0" if p.kind == BRANCH_KIND else number_format(
        DEG if p.kind == ANGLE_KIND else LENGTH, length_unit)
    put_text(ws, f"D{row}", p.unit)
    put_text(ws, f"E{row}", f"designed: {p.name}", NOTE)
    return {"cell": f"C{row}", "name": p.name, "kind": p.kind, "designed": True}


# The inputs' label column: wide enough for a usual label on one line (a label wrapped into a
# second line that Calibri or Carlito draws on one leaves a half-empty row), within a width that
# keeps the sheet's blocks on one landscape page; a longer label wraps.
LABEL_WIDTH = (43, 58)


def _label_width(labels: list[str]) -> float:
    lo, hi = LABEL_WIDTH
    return math.ceil(min(max([lo] + [text_width(label) for label in labels]), hi) * 10) / 10


def position_block(wb, ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The textbook's spin-button row: one input value drives every step and the drawing."""
    mech = t.mechanism
    block_head(ws, "G", "Current position",
               (("Quantity", 37), ("Symbol", 8), ("Value", 13), ("Unit", 7)))
    input_name = position_name(mech.input_key)
    put_text(ws, "G7", f"input {mech.input_word}: change it, all follows")
    wrap_in(ws, "G7")
    put_text(ws, "H7", mech.input_symbol)
    ws["I7"] = t.position
    ws["I7"].fill = INPUT_FILL
    ws["I7"].border = BOX
    ws["I7"].number_format = number_format(mech.input_unit, t.length_unit)
    put_text(ws, "J7", unit_text(mech.input_unit, t.length_unit))
    if mech.input_is_angle:
        dv = DataValidation(type="decimal", operator="between",
                            formula1=f"{-INPUT_ANGLE_LIMIT:g}", formula2=f"{INPUT_ANGLE_LIMIT:g}")
        dv.prompt = "The input angle in degrees"
    else:
        dv = DataValidation(type="decimal", operator="greaterThan", formula1="0")
        dv.prompt = f"The actuator's length in {t.length_unit}"
    dv.showInputMessage = True
    ws.add_data_validation(dv)
    dv.add("I7")
    define_name(wb, input_name, MECH, "I7")
    cells = {mech.input_column: input_name}
    rows = sweep_columns(model, mech.input_column)[1:]
    for row, (key, _) in enumerate(rows, start=8):
        cells[key] = f"I{row}"
    resolve = Resolver(model, names, cells)
    for key, q in rows:
        cell = cells[key]
        r = int(cell[1:])
        put_text(ws, f"G{r}", q.label)
        ws[f"G{r}"].alignment = Alignment(wrap_text=True, vertical="top")
        put_text(ws, f"H{r}", q.symbol)
        set_formula(ws[cell], degree_formula(q, cells[q.key]) if key != q.key
                    else resolve.formula(key))
        unit = DEG if key != q.key else q.unit
        ws[cell].number_format = number_format(unit, t.length_unit)
        put_text(ws, f"J{r}", unit_text(unit, t.length_unit))
    joints = joints_table(ws, t, model, resolve)
    return {"sheet": MECH, "input_cell": "I7", "input_name": input_name,
            "cells": {k: v for k, v in cells.items() if k != mech.input_column},
            "joints": joints["cells"], "drawing": joints["drawing"],
            "traced": _traced_joint(model),
            "chart_anchor": f"L{joints['chart_row']}"}


def _traced_joint(model: Model) -> str | None:
    """The joint whose path the drawing shows (its coordinates are the path's columns)."""
    if not model.path:
        return None
    x, y = model.path
    return next((j.name for j in model.joints if (j.x, j.y) == (f"{{{x}}}", f"{{{y}}}")), None)


def form_controls(ws, t: Template, inputs: dict) -> list[dict]:
    """The textbook's spin button, and a scroll bar, linked to the current-position input (I7):
    a click turns the crank by 1 (degree, or length unit), a page by the sweep's step; a spin
    button beside the grid parameter's input (the pump's s1). controls.py writes them."""
    mech = t.mechanism
    lo, hi = (0, 360) if mech.input_is_angle else (t.sweep.start, t.sweep.stop)
    page = t.sweep.step
    ws["G4"] = f"drag or click to move the input {mech.input_word}:"
    ws["G4"].alignment = Alignment(horizontal="right", vertical="center")
    # anchors: zero-based column, pixel offset, row, pixel offset (top left, then bottom right)
    out = [control_record("Scroll", "I7", lo, hi, 1, page, t.position, (7, 0, 3, 2, 10, 0, 3, 18)),
           control_record("Spin", "I7", lo, hi, 1, page, t.position, (10, 4, 6, 1, 10, 24, 8, 0))]
    if mech.grid:
        param = mech.grid[0]
        row = int(inputs[param]["cell"][1:]) - 1
        values = t.grid_values
        out.append(control_record("Spin", inputs[param]["cell"], min(values), max(values), 1,
                                  1, t.values()[param], (5, 4, row, 1, 5, 24, row + 1, 0)))
    return [c for c in out if c is not None]


def position_motion(ws, t: Template, model: Model, position: dict, motion: dict) -> None:
    """Under the current position: the traced point's velocity and acceleration, from row 5
    of the Motion sheet."""
    if not model.path:
        return
    keys = [k for k in motion["columns"] if k.startswith(("vmag_", "amag_"))]
    name = keys[0].split("_", 1)[1]
    keys = [f"vx_{name}", f"vy_{name}", *keys]
    row = 8 + len(sweep_columns(model, t.mechanism.input_column)) - 1
    src = quote_sheetname(MOTION_SHEET)
    by_key = {q.key: q for q in model.quantities}
    cells = {}
    for key in keys:
        q = by_key[key]
        put_text(ws, f"G{row}", q.label)
        put_text(ws, f"H{row}", q.symbol)
        c = ws[f"I{row}"]
        set_formula(c, f"={src}!{motion['columns'][key]}{motion['current_row']}")
        c.number_format = number_format(q.unit, t.length_unit)
        put_text(ws, f"J{row}", unit_text(q.unit, t.length_unit))
        cells[key] = f"I{row}"
        row += 1
    position["motion_cells"] = cells


def _validation(kind: str, field_name: str) -> DataValidation:
    """The check of an input cell of `kind`: the values it accepts, and a prompt that says so."""
    if kind == BRANCH_KIND:
        dv = DataValidation(type="list", formula1='"1,-1"', allow_blank=False)
        dv.prompt = "1 = open branch, -1 = crossed branch"
    elif kind == LENGTH_KIND:
        dv = DataValidation(type="decimal", operator="greaterThan", formula1="0")
        dv.prompt = "A length: a positive number"
    elif kind == ANGLE_KIND:
        dv = DataValidation(type="decimal", operator="between", formula1="-360", formula2="360")
        dv.prompt = "An angle in degrees, from -360 to 360"
    else:
        dv = DataValidation(type="decimal", operator="between", formula1="-1E+300",
                            formula2="1E+300")
        dv.prompt = "A number (may be zero or negative)"
    dv.promptTitle = field_name[:32]
    dv.error = dv.prompt
    dv.errorTitle = "linkbook"
    dv.showInputMessage = dv.showErrorMessage = True
    return dv
