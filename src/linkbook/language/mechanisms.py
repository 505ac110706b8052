"""What the workbook writer needs to know of a mechanism, whatever describes it.

Every mechanism is described as data in the mechanism language (docs/language.md, compiler.py);
the bundled ones are templates/*.toml. Nothing here touches openpyxl.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

from .model import CONSTANT, Model

# Kinds of parameter, each with its own check (domain.check_value) and input validation.
LENGTH_KIND, OFFSET_KIND, ANGLE_KIND, BRANCH_KIND = "length", "offset", "angle", "branch"
RATE_KIND = "rate"     # the input's speed or acceleration: any number
# Kinds of the loads' parameters (docs/language.md, "Mass, gravity and loads"), each in the one
# SI unit the force analysis reads it in, whatever the book's length unit.
LOAD_UNITS = {"mass": "kg", "inertia": "kg·m²", "force": "N", "torque": "N·m",
              "acceleration": "m/s²", "damping": "N·m·s"}    # a rotary damper's torque per rad/s
NOT_NEGATIVE_KINDS = ("mass", "inertia")
# How a unit is typed on a keyboard without · and ²: kg*m^2, kg m^2, N.m, m/s**2, m / s^2
PRODUCT_SIGNS = re.compile(r"\s*[*.·⋅]\s*|(?<=[A-Za-z])\s+(?=[A-Za-z])")
POWERS = re.compile(r"(?:\^|\*\*)([23])")


def typed_unit(text: str) -> str:
    """A unit as typed, in the spelling the book shows: `kg*m^2` and `kg m^2` are kg·m², `N*m`
    N·m, `m/s^2` m/s²; any other text as it is (then refused as the wrong unit, if it is)."""
    if not isinstance(text, str):
        return text
    squared = POWERS.sub(lambda m: "²³"[int(m.group(1)) - 2], text.strip())
    return PRODUCT_SIGNS.sub("·", re.sub(r"\s*/\s*", "/", squared))

# The input's speed and acceleration, parameters every mechanism has (the data format's names,
# which the reference reads too): a crank's ω and α, a linear actuator's velocity and
# acceleration.
MOTION_SYMBOLS = {ANGLE_KIND: ("omega_in", "alpha_in"), LENGTH_KIND: ("v_in", "a_in")}

# The defined names a book gives cells of its own, beside its parameters' names: the one place
# they are spelt (book_names). A parameter may take none of them.
TO_METRES = "to_metres"                    # metres per length unit (the Forces sheet's A3)
SPEED_FLUCTUATION = "speed_fluctuation"    # the coefficient of speed fluctuation Cs
FORCE_ROLE = "force"                       # the model's role of a Forces sheet column


def position_name(input_key: str) -> str:
    """The defined name of the current position's input cell: theta12_now."""
    return f"{input_key}_now"


def constant_name(key: str) -> str:
    """The defined name of a quantity derived from the inputs alone: k_gamma."""
    return f"k_{key}"


@dataclass(frozen=True)
class Mechanism:
    """A compiled mechanism: its parameters, its input and the model its steps build."""
    name: str
    parameters: dict[str, str]      # symbol -> kind, in the order the inputs block shows them
    input_key: str                  # "theta12"
    input_symbol: str               # "θ12"
    build: Callable[[], Model]
    grid: tuple[str, str] | None = None   # (parameter across the grid, quantity in its cells)
    description: dict | None = None       # the [mechanism] table it was compiled from
    input_kind: str = ANGLE_KIND          # a crank's angle, or a linear actuator's length
    # (field, expression) of every length a step takes: each must come out positive
    lengths: tuple[tuple[str, object], ...] = ()
    # (field, expression) of every mass, inertia, load and gravity: none an error on every row
    loads: tuple[tuple[str, object], ...] = ()

    def book_names(self) -> dict[str, str]:
        """{defined name: what it names} of the cells the book names itself (beside the
        parameters): what a parameter's name may not be, as Excel compares names without case,
        nor its symbol, which the formulas' placeholders share."""
        model = self.build()
        names = {position_name(self.input_key): "the current position"}
        names.update({constant_name(q.key): f"the derived {q.key}"
                      for q in model.of_role(CONSTANT)})
        if model.of_role(FORCE_ROLE):
            names[TO_METRES] = "metres per length unit"
            if self.input_is_angle:
                names[SPEED_FLUCTUATION] = "the coefficient of speed fluctuation"
        return names

    @property
    def input_is_angle(self) -> bool:
        return self.input_kind == ANGLE_KIND

    @property
    def input_column(self) -> str:
        """The key of the swept value as the sweep's first column holds it: an angle in degrees
        (`theta12_deg`; the model's `theta12` is its radians), a length as it is (`s`)."""
        return f"{self.input_key}_deg" if self.input_is_angle else self.input_key

    @property
    def input_unit(self) -> str:
        """The swept value's unit as model.header writes it: "deg" or "length"."""
        return "deg" if self.input_is_angle else "length"

    @property
    def input_word(self) -> str:
        return "angle" if self.input_is_angle else "length"


def on_loop(value: str, witness: str) -> str:
    """A coordinate fixed by construction (a slider pin's y on its line) that exists only where
    the loop closes: #N/A wherever `witness` is."""
    return f"IF(ISNUMBER({{{witness}}}),{value},NA())"
