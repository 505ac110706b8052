"""The step types of the mechanism language as the reference reads them, one module each.

STEP_TYPES maps a step's `type` to its step_type.StepType; Positions, Rates and the drawing of
sliders find a step's work only here. A plain dict: a new step type is one more module and one
more entry (a test may add one at run time).
"""

from __future__ import annotations

from ..step_type import StepType
from . import crank, distance, dyad, expression, point, slide, slider, slot, triad, vector

STEP_TYPES: dict[str, StepType] = {
    "crank": crank.STEP,
    "dyad": dyad.STEP,
    "slider": slider.STEP,
    "slide": slide.STEP,
    "slot": slot.STEP,
    "point": point.STEP,
    "vector": vector.STEP,
    "distance": distance.STEP,
    "expression": expression.STEP,
    "triad": triad.STEP,
}
