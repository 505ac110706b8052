"""The Forces sheet: the inertia loads, every joint's reaction and the driving effort, at the
current position (row 5) and at every row of the Sweep sheet, each reading that row's
positions (Sweep) and accelerations (Motion). Its formulas come from the force writer
(language/forces.py); lengths become metres through the one named cell `to_metres`.
"""
from __future__ import annotations

from ..base.sheets import FORCES_SHEET, MOTION_SHEET, SWEEP
from ..language.forces import FORCE, TO_METRES
from ..language.model import Model
from ..language.templates import LENGTH_UNITS, Template
from .motion import MOTION_OFFSET, model_name, row_table
from .style import NOTE, define_name

METRES_CELL = "A3"


def forces_table(wb, ws, t: Template, model: Model, names: dict, sweep: dict, position: dict,
                 motion: dict) -> dict:
    """The Forces sheet's table (motion.row_table), its rows beside the Motion sheet's."""
    speed = model_name(names, "omega_in" if t.mechanism.input_is_angle else "v_in")
    effort = "T12 (the motor's torque on the crank)" if t.mechanism.input_is_angle else \
        "F_in (the actuator's force)"
    note = (f"Forces in N, moments in N·m, at the speed {speed} of sheet Mechanism: the "
            f"inertia and weight of each link, the force of link i on link j at their pin "
            f"(Fij), the guides' forces, the driving effort {effort} and the shaking force on "
            f"the frame. Row 5: the current position; from row {5 + MOTION_OFFSET}: each row "
            f"of sheet {SWEEP}. #N/A where the loop cannot close or where a group of links "
            f"cannot carry a load. Cell {METRES_CELL}: metres per {t.length_unit} (to_metres).")
    ws[METRES_CELL] = LENGTH_UNITS[t.length_unit]
    ws[METRES_CELL].number_format = "0.####"
    ws[METRES_CELL].font = NOTE
    define_name(wb, TO_METRES, FORCES_SHEET, METRES_CELL)
    table = row_table(ws, t, model, {**names, TO_METRES: TO_METRES}, model.of_role(FORCE),
                      sweep, position, f"{t.title}: forces", note, (MOTION_SHEET, motion))
    return {"sheet": FORCES_SHEET, **table}
