"""The symbolic model of a mechanism's analysis, and how its formulas become a cell's Excel text
where they land (Resolver).

A model is an ordered list of quantities. Each quantity's formula is Excel text in which `{key}`
stands for another quantity or a parameter. Where a formula lands decides what `{key}` becomes:

- a parameter or a constant -> its workbook-scoped defined name (`a_2`);
- a column quantity -> the cell that holds it in the same block (a same-row cell in the sweep table,
  a fixed cell in the current-position block), or, for a self-contained grid cell, its own formula
  inlined in parentheses;
- an alias (a short expression that never gets a cell of its own, like `A = a2·e^{iθ12}`)
  -> always inlined.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace


# Roles a quantity can play.
COLUMN = "column"      # one cell per row of the sweep, shown with its header
ALIAS = "alias"        # inlined wherever it is used
CONSTANT = "constant"  # one cell in the inputs block, with a defined name (depends on parameters only)
MOTION = "motion"      # one cell per row of the Motion sheet (velocities and accelerations)

# Units a quantity can have. LENGTH is replaced by the template's length unit when shown.
LENGTH, RAD, DEG, RATIO = "length", "rad", "deg", "-"
SPEED, ACCEL = "length/s", "length/s²"          # a point's or a slider's velocity, acceleration
AREA = "length²"                                # a dyad's determinant u_q × u_p
ANG_SPEED, ANG_ACCEL, RPM = "rad/s", "rad/s²", "rpm"
NEWTON, NEWTON_METRE = "N", "N·m"                # a force, a moment (sheet Forces)


@dataclass(frozen=True)
class Quantity:
    """One quantity of the model: a column of the tables, or an alias written into them."""
    key: str            # ASCII id shared with the reference solver: "theta13"
    symbol: str         # what a reader sees: "θ13"
    unit: str           # LENGTH, RAD, DEG or RATIO
    formula: str        # Excel expression with {key} placeholders (no leading '=')
    role: str = COLUMN
    label: str = ""     # a few words for a reader: "rocker angle, B0→B"
    in_degrees: bool = False   # an output angle: also shown in degrees at the table's right
    wrap_360: bool = False     # show that degree value in [0, 360)
    made_by: str = ""   # the template's field that made it (Model.add: where), for messages


@dataclass(frozen=True)
class Joint:
    """A point of the mechanism drawing; x and y are expressions like formulas."""
    name: str
    x: str
    y: str


@dataclass(frozen=True)
class Guide:
    """The line a block slides on, drawn over the block's travel. x, y: a point of the line
    (expressions); cos, sin: its direction; travel: the sweep column of the block's signed
    position along the line from that point."""
    point: str          # the step's new point: the drawn points are named after it
    kind: str           # "guide" (the line the block slides on) or "slot" (a slot's line)
    x: str
    y: str
    cos: str
    sin: str
    travel: str


@dataclass(frozen=True)
class Block:
    """A sliding block: a rectangle centred on the point (x, y), its long side along
    (cos, sin)."""
    point: str          # the point the block is pivoted on: the drawn corners are named after it
    x: str
    y: str
    cos: str
    sin: str


@dataclass(frozen=True)
class Chart:
    """An XY chart of sweep columns (keys of quantities; `_deg` suffix = the degree column)."""
    title: str
    x: str
    ys: tuple[str, ...]
    x_title: str
    y_title: str
    equal_axes: bool = False


@dataclass(frozen=True)
class FourBarLoop:
    """The four-bar loop inside a mechanism, for its Grashof class and dead centres: link
    lengths as expressions, and the direction of the ground link (input pivot → output pivot)."""
    ground: str
    crank: str
    coupler: str
    rocker: str
    ground_angle: str = "0"
    name: str = ""            # its points, e.g. "A0 A B B0"


@dataclass
class Model:
    """What the workbook writer needs: quantities in evaluation order, drawing and charts."""
    quantities: list[Quantity] = field(default_factory=list)
    joints: list[Joint] = field(default_factory=list)
    links: list[tuple[str, ...]] = field(default_factory=list)   # polylines through joint names
    ground: tuple[str, ...] = ()   # fixed pivots the links use: the ground link (link 1)
    charts: list[Chart] = field(default_factory=list)
    path: tuple[str, str] | None = None    # (x key, y key) of a traced point drawn on the mechanism
    closes: tuple[str, ...] = ()   # quantities that are all numbers exactly where every loop closes
    # the loop step each of `closes` belongs to: (as errors name it, its short name "dyad C")
    loop_steps: tuple[tuple[str, str], ...] = ()
    output: str = ""          # the main output, whose swing the summary reports
    transmissions: tuple[str, ...] = ()   # transmission angles whose range the summary reports
    fourbars: tuple[FourBarLoop, ...] = ()  # four-bar loops on the ground (Grashof, limit angles)
    guides: list[Guide] = field(default_factory=list)    # drawn under the links
    blocks: list[Block] = field(default_factory=list)
    where: str = ""           # the template's field being compiled: what Model.add stamps
    # the frames whose angle is the direction of two points: (field, A, B, a step's frame?)
    frames: list[tuple[str, str, str, bool]] = field(default_factory=list)

    def add(self, *quantities: Quantity) -> None:
        known = {q.key for q in self.quantities}
        for q in quantities:
            if q.key in known:
                raise ValueError(f"quantity {q.key!r} defined twice")
            known.add(q.key)
            self.quantities.append(q if q.made_by else replace(q, made_by=self.where))

    def get(self, key: str) -> Quantity:
        for q in self.quantities:
            if q.key == key:
                return q
        raise KeyError(key)

    def of_role(self, role: str) -> list[Quantity]:
        return [q for q in self.quantities if q.role == role]


class DescriptionError(Exception):
    """A problem with a description: `field` names the step and key, `message` says what."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field, self.message = field, message
