"""Generic independent reference: any mechanism described in the mechanism language.

The description is the ``[mechanism]`` table of a template (docs/language.md): ground points, an
input angle (or a linear actuator's length) and an ordered list of steps, each placing one new
point from points already known. The reference reads the same description as the workbook
writer but shares no formula with it, and imports nothing of linkbook (only the standard library
and numpy): every step is turned into the geometric constraints it implies and its unknown is
found by Newton–Raphson, row after row, continuing from the previous row's root. Every column is
then measured on the solved points (distances, np.arctan2 of joint-to-joint vectors, interior
angles), each angle in the window of the doc's definition, so that the smallest and largest
value of an angle column mean the same as in the workbook.

The package, by concern:
  expressions   its own parser and evaluator of the language's expressions
  newton        Newton–Raphson and the continuation sweep over the rows
  constraints   the constraint systems step types share (two circles, a triangle)
  geometry      measurements on solved points
  positions     one pass over the steps (Positions) and the mechanism's ground and size
  taylor        Taylor arithmetic: rates by implicit differentiation of the constraints
  rates         velocities and accelerations of a solved mechanism (Rates)
  step_type     what the reference needs of one step type (StepType)
  steps/        one module per step type, and STEP_TYPES, the registry keyed by a step's type
  analysis      solve() (positions(), then motion()) and what is measured over a sweep
                (extremes, a quick-return ratio)
  drawing       the drawn guides and blocks of the sliders
  fourbar       four-bar loops: Grashof's class, the input's limit angles
  synthesis     function generation (issue 38): the four-bar through given (θ2, θ4) pairs
  synthesis_motion  motion and path generation (issue 38): the four-bar through three poses
  synthesis_slider  slider-crank function generation (issue 38): three (θ2, s) pairs
"""

from __future__ import annotations

from .analysis import (EXTREME_STEP, REVERSAL_STEP, motion, positions, positions_only,
                       reads_rates, refined_extreme, solve, time_ratio)
from .drawing import BLOCK, guide_movers, slider_drawing, slider_parts
from .expressions import evaluate
from .fourbar import fourbar_loops, grashof_class, limit_angles
from .positions import pivots
from .step_type import Guide, Sliding, StepType
from .steps import STEP_TYPES

__all__ = ["solve", "positions", "motion", "reads_rates", "pivots", "fourbar_loops",
           "grashof_class", "limit_angles", "evaluate", "refined_extreme", "positions_only",
           "time_ratio", "slider_drawing", "slider_parts", "guide_movers", "EXTREME_STEP",
           "REVERSAL_STEP", "BLOCK", "STEP_TYPES", "StepType", "Sliding", "Guide"]
