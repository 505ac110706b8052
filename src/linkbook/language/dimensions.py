"""Dimensions of a description's expressions, for a change of length unit (--unit): a length
written as a number cannot be converted, so a description that writes one is refused.
"""
from __future__ import annotations

import ast
from fractions import Fraction

from .expressions import value_of
from .mechanisms import LENGTH_KIND, MOTION_SYMBOLS, OFFSET_KIND, Mechanism
from .bodies import METRES
from .model import ACCEL, AREA, LENGTH, SPEED, Model
from .steps import STEPS

# The power of length each expression stands for: a parameter of kind length or offset, a
# length column, a linear actuator's length is 1, an angle or a ratio 0; a bare number takes
# the dimension its place gives it (a scale factor in a product, a length in a sum with one).
_ANGLE_FUNCTIONS = {"SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "RADIANS", "DEGREES"}


class _Dimensions:
    """Finds where an expression writes a length as a number (which a change of length unit
    cannot convert) or mixes a length with a number."""

    def __init__(self, dims: dict[str, int]):
        self.dims = dims
        self.problem: str | None = None

    def check(self, raw: object, want: int) -> str | None:
        if not isinstance(raw, str):
            raw = repr(raw)
        self.need(ast.parse(raw.replace("^", "**"), mode="eval").body, Fraction(want))
        return self.problem

    def _note(self, text: str) -> None:
        self.problem = self.problem or text

    def need(self, node: ast.AST, want: Fraction) -> None:
        got = self.dim(node)
        if got is None:
            if want != 0 and value_of(_source(node), {}) != 0:
                self._note(f"the number {_source(node)} is {_dimension_word(want)} here, which a "
                           "change of unit cannot convert; make it a parameter (a number in a "
                           "product, a ratio or an angle is fine)")
        elif got != want:
            self._note(f"{_source(node)} is {_dimension_word(got)}, where "
                       f"{_dimension_word(want)} belongs, so a change of unit would change "
                       "its meaning")

    def same(self, nodes: list) -> Fraction | None:
        """The one dimension of terms that are added, compared or chosen between."""
        dims = [self.dim(n) for n in nodes]
        known = {d for d in dims if d is not None}
        if len(known) > 1:
            self._note(f"{' and '.join(_source(n) for n in nodes)} mix a length with a number, "
                       "so a change of unit would change their meaning")
            return max(known)
        d = known.pop() if known else None
        if d:
            for n, nd in zip(nodes, dims):
                if nd is None:
                    self.need(n, d)
        return d

    def dim(self, node: ast.AST) -> Fraction | None:
        """The node's dimension, None for a bare number (or numbers alone)."""
        if isinstance(node, ast.Constant):
            return None
        if isinstance(node, ast.Name):
            return Fraction(self.dims.get(node.id, 0))
        if isinstance(node, ast.UnaryOp):
            return self.dim(node.operand)
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, (ast.Add, ast.Sub)):
                return self.same([node.left, node.right])
            if isinstance(node.op, ast.Pow):
                self.need(node.right, Fraction(0))
                base, power = self.dim(node.left), value_of(_source(node.right), {})
                if base is None or base == 0:
                    return base
                if power is None or power != power:
                    self._note(f"{_source(node)} raises a length to a power that is not a number")
                    return base
                return base * Fraction(power).limit_denominator(12)
            a, b = self.dim(node.left), self.dim(node.right)
            if a is None and b is None:
                return None
            a, b = a or Fraction(0), b or Fraction(0)
            return a + b if isinstance(node.op, ast.Mult) else a - b
        if isinstance(node, ast.Compare):
            self.same([node.left, *node.comparators])
            return Fraction(0)
        name = node.func.id.upper()
        args = node.args
        if name in _ANGLE_FUNCTIONS:
            for a in args:
                self.need(a, Fraction(0))
            return Fraction(0)
        if name == "ATAN2":
            self.same(args)
            return Fraction(0)
        if name == "SQRT":
            d = self.dim(args[0])
            return None if d is None else d / 2
        if name == "IF":
            self.dim(args[0])
            return self.same(args[1:])
        if name in ("AND", "OR", "NOT", "SIGN"):      # TRUE, FALSE, -1, 0, 1: numbers
            for a in args:
                self.dim(a)
            return Fraction(0)
        if name in ("ABS", "MIN", "MAX", "IFERROR"):
            return self.same(args)
        return None                                   # PI(), NA(): numbers


def _source(node: ast.AST) -> str:
    return ast.unparse(node).replace("**", "^")


def _dimension_word(d: Fraction) -> str:
    return {0: "a number (no length in it)", 1: "a length", 2: "an area"}.get(
        d, f"a length to the power {d}")


LENGTH_DIMENSIONS = {LENGTH: 1, SPEED: 1, ACCEL: 1, AREA: 2}


def unconvertible(mechanism: Mechanism, model: Model) -> tuple[str, str] | None:
    """(field, why) of the first place a description writes a length as a number (or mixes
    a length with a number), so that a change of length unit could not convert it; None when
    every length is a parameter's."""
    description = mechanism.description or {}
    dims = {symbol: int(kind in (LENGTH_KIND, OFFSET_KIND))
            for symbol, kind in mechanism.parameters.items()}
    dims.update({s: 1 for s in MOTION_SYMBOLS[LENGTH_KIND]})
    # a velocity and an acceleration carry one length (per second: a load reads the rates)
    dims.update({q.key: LENGTH_DIMENSIONS.get(q.unit, 0) for q in model.quantities})
    dims[mechanism.input_key] = int(not mechanism.input_is_angle)
    for name, xy in (description.get("ground") or {}).items():
        for i, raw in enumerate(xy):
            found = _Dimensions(dims).check(raw, 1)
            if found:
                return f"mechanism.ground.{name}[{i}]", found
    for i, step in enumerate(description.get("steps") or []):
        label = step.get("point") or step.get("key")
        field = f"mechanism.steps[{i}] ({step.get('type')} {label})"
        wants = STEPS[step["type"]].dimensions(step)
        for k, raw in step.items():
            want = wants.get(k)
            if want is None:
                continue
            for j, item in enumerate(raw if isinstance(raw, list) else [raw]):
                for sub in item if isinstance(item, list) else [item]:   # a sketch's [x, y]
                    found = _Dimensions(dims).check(sub, want)
                    if found:
                        return f"{field}.{k}" + (f"[{j}]" if isinstance(raw, list) else ""), \
                            found
    return _unconvertible_force_key(description, {**dims, METRES: -1})


# The dimension of each value of the force analysis' keys: a centre's place is a length, every
# other value a number (a mass, a force, an angle: SI units, which a change of length unit leaves)
_CENTRE_DIMENSIONS = {"local": 1, "distances": 1, "distance": 1, "angle": 0}


def _force_key_values(description: dict):
    """(field, value, its dimension) of every value of dynamics, bodies and loads."""
    gravity = (description.get("dynamics") or {}).get("gravity") or {}
    for k, raw in gravity.items():
        yield f"mechanism.dynamics.gravity.{k}", raw, 0
    for i, body in enumerate(description.get("bodies") or []):
        field = f"mechanism.bodies[{i}]"
        for k in ("mass", "inertia"):
            if k in body:
                yield f"{field}.{k}", body[k], 0
        for k, raw in (body.get("centre") or {}).items():
            if k in _CENTRE_DIMENSIONS:
                yield from _items(f"{field}.centre.{k}", raw, _CENTRE_DIMENSIONS[k])
    for i, load in enumerate(description.get("loads") or []):
        field = f"mechanism.loads[{i}]"
        force = load.get("force")
        if isinstance(force, dict):
            for k, raw in force.items():
                yield f"{field}.force.{k}", raw, 0
        elif force is not None:
            yield from _items(f"{field}.force", force, 0)
        if "torque" in load:
            yield f"{field}.torque", load["torque"], 0


def _items(field: str, raw: object, want: int):
    if isinstance(raw, list):
        for j, item in enumerate(raw):
            yield f"{field}[{j}]", item, want
    else:
        yield field, raw, want


def _unconvertible_force_key(description: dict, dims: dict[str, int]) -> tuple[str, str] | None:
    for field, raw, want in _force_key_values(description):
        found = _Dimensions(dims).check(raw, want)
        if found:
            return field, found
    return None
