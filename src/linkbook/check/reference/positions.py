"""Position analysis: one pass over a description's steps, in order, on every row.

The description is the ``[mechanism]`` table of a template (docs/language.md): ground points, an
input (a crank's angle or a linear actuator's length) and an ordered list of steps, each placing
one new point from points already known, or measuring. Positions keeps what the steps have
made; each step's own work is its step type's `place` (step_type.StepType), looked up by the
step's `type`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from .expressions import branch_sign, evaluate, scalar
from .geometry import Point, direction
from .newton import RES_TOL
from .step_type import StepType


def steps_of(description: Mapping, step_types: Mapping[str, StepType]) -> list[Mapping]:
    """The description's steps, each a table whose `type` is one of step_types."""
    steps = description.get("steps", [])
    if not isinstance(steps, list):
        raise ValueError("mechanism.steps must be a list of tables")
    for k, step in enumerate(steps):
        if not isinstance(step, Mapping) or step.get("type") not in step_types:
            kind = step.get("type") if isinstance(step, Mapping) else step
            raise ValueError(f"steps[{k}]: unknown or missing type {kind!r}")
    return steps


def pivots(description: Mapping, params: Mapping[str, float]) -> dict[str, tuple[float, float]]:
    """The ground points of the description, evaluated: {name: (x, y)}."""
    ground = description.get("ground", {})
    if not isinstance(ground, Mapping):
        raise ValueError("mechanism.ground must be a table of [x, y] pairs")
    out = {}
    for name, xy in ground.items():
        if not isinstance(xy, (list, tuple)) or len(xy) != 2:
            raise ValueError(f"ground point {name!r} must be [x, y]")
        out[str(name)] = (scalar(xy[0], params), scalar(xy[1], params))
    return out


def size_of(steps: list[Mapping], step_types: Mapping[str, StepType],
            params: Mapping[str, float], ground: Mapping[str, tuple[float, float]]) -> float:
    """The mechanism's size: the sum of |every length and offset| of the description (ground
    coordinates, link lengths, offsets, carried points' distances and local coordinates)."""
    total = 0.0
    for x, y in ground.values():
        total += abs(x) + abs(y)
    for step in steps:
        for field in step_types[step["type"]].length_fields:
            if isinstance(step.get(field), (list, tuple)):     # a group's lengths
                total += sum(abs(scalar(v, params)) for v in step[field])
            elif field in step:
                value = evaluate(step[field], params)   # a swept length: its largest value
                total += float(np.nanmax(np.abs(value), initial=0.0)) \
                    if isinstance(value, np.ndarray) else abs(scalar(step[field], params))
        for field in ("local", "distances"):
            if isinstance(step.get(field), (list, tuple)):
                total += sum(abs(scalar(v, params)) for v in step[field])
    return total if total > 0.0 and math.isfinite(total) else 1.0


class Positions:
    """One pass over the steps, in order: each step's points and columns, for every row.

    Besides the values it keeps what the workbook's layout depends on: which points move with
    the input angle, the angle of each known link (for a point placed at an angle to it), and
    which keys are fixed (hidden, or a constant, and independent of the input angle), so that a
    carried point's gamma or theta and an expression come back as a float exactly where the
    workbook makes them one named constant cell."""

    def __init__(self, description: Mapping, params: Mapping[str, float], angles: np.ndarray,
                 step_types: Mapping[str, StepType],
                 turns: Mapping[str, np.ndarray] | None = None):
        inp = description.get("input")
        if not isinstance(inp, Mapping) or not isinstance(inp.get("key"), str):
            raise ValueError("mechanism.input must be a table with a key")
        self.input_key = inp["key"]
        self.params = params
        self.turns = turns or {}      # see analysis.solve: the turn an expression reads
        self.step_types = step_types
        self.steps = steps_of(description, step_types)
        # the input: a crank's angle (degrees given, radians used) or a linear actuator's
        # length, which a dyad's side may be
        self.angle_input = inp.get("kind", "angle") == "angle"
        values = np.asarray(angles, dtype=float)
        self.th = np.radians(values) if self.angle_input else None
        self.swept = {} if self.angle_input else {self.input_key: values}
        self.n = n = len(angles)
        ground = pivots(description, params)
        self.size = size_of(self.steps, step_types, {**params, **self.swept}, ground)
        self.tol_f = RES_TOL * self.size
        self.points: dict[str, Point] = {name: (np.full(n, x), np.full(n, y))
                                         for name, (x, y) in ground.items()}
        self.moving: set[str] = set()             # points that move with the input angle
        self.coords: dict[str, tuple[str, str]] = {}   # a step point's x and y keys
        # pairs of points a fixed, known distance apart (a rigid link of known length)
        self.rigid: dict[frozenset, float] = {}
        # the angle of a known link A→B, as the workbook writes it: (values, key or None)
        self.link: dict[tuple[str, str], tuple[np.ndarray, str | None]] = {}
        for a, (x1, y1) in ground.items():
            for b, (x2, y2) in ground.items():
                if a != b:
                    self.rigid[frozenset((a, b))] = math.hypot(x2 - x1, y2 - y1)
                    self.link[(a, b)] = (np.full(n, math.atan2(y2 - y1, x2 - x1)), None)
        self.out: dict[str, object] = {self.input_key: self.th if self.angle_input else values}
        self.fixed: dict[str, bool] = {}
        # what an expression step may name: parameters, the input angle, every earlier key
        self.env: dict[str, object] = {k: v for k, v in params.items()}
        if self.angle_input:
            self.env[self.input_key] = self.th
            self.env[f"{self.input_key}_deg"] = values
        else:
            self.env[self.input_key] = values
        self.reserved = {self.input_key, "assembled", "points", "other_assembly"}
        self.assembled = np.ones(n, dtype=bool)

    def run(self) -> dict:
        """Every step placed in order: the columns, 'assembled' and 'points' (see solve)."""
        for k, step in enumerate(self.steps):
            self.where = f"steps[{k}] ({step['type']} {step.get('point', step.get('key', ''))})"
            self.step_types[step['type']].place(self, step)
        self.out["assembled"] = self.assembled
        self.out["points"] = self.points
        return self.out

    # -- what a step type's `place` reads and writes
    def known(self, step: Mapping, field: str) -> Point:
        """The point the step's `field` names, which an earlier step (or the ground) placed."""
        name = step.get(field)
        if not isinstance(name, str) or name not in self.points:
            raise ValueError(f"{self.where}.{field}: {name!r} is not a known point")
        return self.points[name]

    def pair(self, step: Mapping, field: str) -> tuple[str, str]:
        """The names of the two known points [A, B] the step's `field` holds."""
        names = step.get(field)
        if not isinstance(names, (list, tuple)) or len(names) != 2:
            raise ValueError(f"{self.where}.{field} must be [A, B]")
        for nm in names:
            if not isinstance(nm, str) or nm not in self.points:
                raise ValueError(f"{self.where}.{field}: {nm!r} is not a known point")
        return names[0], names[1]

    def num(self, step: Mapping, field: str, default: float | None = None) -> float:
        """The step's `field`, an expression of the parameters alone (or the default)."""
        if field not in step:
            if default is None:
                raise ValueError(f"{self.where}: missing {field}")
            return float(default)
        return scalar(step[field], self.params)

    def side(self, step: Mapping, field: str):
        """A dyad's side: a length, or per-row lengths where it is the swept actuator."""
        if not self.swept:
            return self.num(step, field)
        value = evaluate(step[field], {**self.params, **self.swept})
        if isinstance(value, np.ndarray):
            return value.astype(float)
        if not isinstance(value, float):
            raise ValueError(f"{self.where}.{field}: not a number")
        return value

    def branch(self, step: Mapping, field: str = "branch") -> int:
        """The step's branch (or side): 1 or -1, 1 where it is not given."""
        return branch_sign(step.get(field, 1), self.params, f"{self.where}.{field}")

    def moves(self, *names: str) -> bool:
        """Some of the named points move with the input."""
        return any(nm in self.moving for nm in names)

    def coords_fixed(self, name: str) -> bool:
        """The workbook writes the point's coordinates as fixed values (a ground point's
        expressions, or hidden columns independent of the input angle)."""
        if name not in self.coords:
            return name not in self.moving
        return all(self.fixed.get(k, False) for k in self.coords[name])

    def put(self, key: str, value, fixed: bool) -> None:
        """Column `key` (once only), which later expressions may name; `fixed`: the workbook
        writes it as one value independent of the input."""
        if key in self.out or key in self.reserved:
            raise ValueError(f"{self.where}: column key {key!r} is written twice")
        self.out[key] = value
        self.env[key] = value
        self.fixed[key] = fixed

    def column(self, step: Mapping, col: str, default: str, value, moving: bool,
               shown_by_default: bool = True) -> str:
        """A column under its key: the default, or the `key` its `columns` entry gives
        (`false` or `shown = false` hides it from the sheets, not from here)."""
        spec = (step.get("columns") or {}).get(col)
        key, shown = default, shown_by_default
        if spec is False:
            shown = False
        elif spec is True:
            shown = True
        elif isinstance(spec, Mapping):
            key = str(spec.get("key") or default)
            shown = bool(spec.get("shown", True))
        if isinstance(value, float):        # a constant: one named cell
            fixed = True
        else:
            value = np.asarray(value, dtype=float)
            fixed = not moving and not shown
        self.put(key, value, fixed)
        return key

    def point_columns(self, step: Mapping, values: Mapping[str, object], moving: bool,
                      hidden: tuple[str, ...] = ()) -> dict[str, str]:
        """Columns of a step that places point N: f"{col}_{N}", x → xN, y → yN (`hidden`:
        columns shown only when the step's `columns` asks for them)."""
        name = step["point"]
        return {col: self.column(step, col, f"{col}{name}" if col in ("x", "y") else
                                 f"{col}_{name}", value, moving, col not in hidden)
                for col, value in values.items()}

    def new_point(self, step: Mapping, keys: Mapping[str, str], moving: bool, loop: bool) -> None:
        """The step's point, from its x and y columns (`keys`); a loop step's point exists
        exactly where the mechanism is assembled."""
        name = step.get("point")
        if not isinstance(name, str) or not name:
            raise ValueError(f"{self.where}: missing point")
        if name in self.points:
            raise ValueError(f"{self.where}: point {name!r} is defined twice")
        x, y = self.out[keys["x"]], self.out[keys["y"]]
        self.points[name] = (x, y)
        self.coords[name] = (keys["x"], keys["y"])
        if moving:
            self.moving.add(name)
        if loop:    # a loop step closes exactly where its point exists
            self.assembled &= np.isfinite(x) & np.isfinite(y)

    def add_link(self, a: str, b: str, angle: np.ndarray, key: str | None,
                 length=None) -> None:
        """A link A→B and its angle; with a length (not a swept one), a rigid pair."""
        self.link.setdefault((a, b), (angle, key))
        if length is not None and not isinstance(length, np.ndarray):
            self.rigid[frozenset((a, b))] = abs(length)

    def angle_of(self, a: str, b: str) -> tuple[np.ndarray, bool]:
        """angle(A→B) as the workbook takes it (a known link's angle column, or the angle of
        the points), and whether that is a fixed value."""
        if (a, b) in self.link:
            angle, key = self.link[(a, b)]
        elif (b, a) in self.link:
            angle, key = self.link[(b, a)]
            angle = angle + math.pi
        else:
            (ax, ay), (bx, by) = self.points[a], self.points[b]
            return direction(bx - ax, by - ay), self.coords_fixed(a) and self.coords_fixed(b)
        fixed = self.fixed.get(key, False) if key is not None else \
            self.coords_fixed(a) and self.coords_fixed(b)
        return angle, fixed
