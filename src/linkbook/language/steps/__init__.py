"""The step types of the language on the writer's side, one module each, found through STEPS.

STEPS maps a step's `type` to its StepType (step_type.py): its keys, its position formulas and
its rate formulas. Adding a step type to the writer is one new module here and one entry in
STEPS (plus its schema in mechanism.schema.json and its page in docs/language.md). The order of
STEPS is the order error messages list the types in.
"""
from __future__ import annotations

from collections.abc import Iterator, Mapping

from . import crank, distance, dyad, expression, point, slide, slider, slot, triad, vector
from .step_type import COMMON_KEYS, StepType

STEPS: dict[str, StepType] = {
    "crank": crank.STEP, "dyad": dyad.STEP, "slider": slider.STEP, "slide": slide.STEP,
    "point": point.STEP, "slot": slot.STEP, "vector": vector.STEP, "distance": distance.STEP,
    "expression": expression.STEP, "triad": triad.STEP,
}


class _Keys(Mapping):
    """Each step type's (required, optional) keys, read from STEPS as it is now."""

    def __getitem__(self, kind: str) -> tuple[set[str], set[str]]:
        return STEPS[kind].keys

    def __iter__(self) -> Iterator[str]:
        return iter(STEPS)

    def __len__(self) -> int:
        return len(STEPS)


STEP_KEYS: Mapping[str, tuple[set[str], set[str]]] = _Keys()

__all__ = ["COMMON_KEYS", "STEPS", "STEP_KEYS", "StepType"]
