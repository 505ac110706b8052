"""The one domain of numbers and sizes a book supports. build checks what a user gives against it
(templates, language) and verify checks an edited book against the same definitions, so what
build accepts, its own verify accepts and agrees with.

Numbers (in the book's length unit). A length is from 1e-6 to 1e9, an offset or a coordinate
written as a number up to 1e9 either way, an input rate up to 1e9, an input angle (the sweep, the
current position) up to 3600° either way (the input cell's validation). The mechanism's extent —
its largest length, offset or written coordinate — is at most LENGTH_SPAN times its smallest
length. Why LENGTH_SPAN is 1e3: verify's bound for a length is 1e-12·S (S the mechanism's size),
about 4500 times the rounding of one double of size S (2.2e-16·S). Where a loop subtracts lengths
of size S to get one of the smallest length ℓ (the shaper's slot direction r1 + r2·sin θ2 near
θ2 = 180°), the rounding of any evaluation is ε·S on a result of size ℓ: a relative error of
ε·S/ℓ, which every quantity computed from it carries (the ram's position, 2e9 mm at r2 = 1e9,
was 2.65 mm apart between the workbook and the reference). That stays within the bound while
S/ℓ ≤ 4500; 1e3 keeps a margin of 4.5. (1e9, the bound before, let r2 = 1e9 beside r1 = 60
build and then fail its own verify.)

Loads. A mass, an inertia, a force, a torque or gravity is 0 or from 1e-30 to 1e30 of its unit
either way (LOAD_RANGE): the inertia of a part far below a millimetre fits, and no product of a
few of them with the lengths and rates under- or overflows a double. The force formulas multiply them by lengths in metres (down to 1e-9 m)
and by the rates, so a value near the least double (1e-308) underflows to 0 in the book where the
reference, which scales its equations first, still finds a force: a torque of 2.2e-308 N·m made a
pin force of 4e-307 N that the book showed as 0.

Sizes. verify refuses to inflate more than safety.MAX_UNCOMPRESSED (512 MiB) of XML, and a book
needs memory in proportion to its formula cells and their text: MEMORY_BUDGET. build estimates
both before it lays out a cell (builder.book_size) and refuses a book over either.
"""
from __future__ import annotations

import ast
import math

from ..base.errors import InputError
from .mechanisms import (ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, LOAD_UNITS, NOT_NEGATIVE_KINDS,
                         OFFSET_KIND, RATE_KIND)
from ..base.safety import MAX_UNCOMPRESSED

LENGTH_RANGE = (1e-6, 1e9)       # a length; an offset may also be 0 (or up to 1e9 either way)
RATE_LIMIT = 1e9                 # |ω|, |α|, |v|, |a| of the input
LENGTH_SPAN = 1e3                # the mechanism's extent over its smallest length (see above)
INPUT_ANGLE_LIMIT = 3600.0       # degrees either way: the sweep and the current position
LOAD_RANGE = (1e-30, 1e30)       # a mass, inertia, force, torque or gravity, if not 0 (above)
BRANCH_WORDS = {"open": 1.0, "crossed": -1.0}
# The length units a book may have, in metres: one per mechanism (the template's length_unit).
LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}

# Memory, measured with the 0.05° four-bar (324,178 formula cells, 27 MB of XML) and the pump
# with 100 adjustments (39,283 cells, 70 MB): verify needs about 1 kB per formula cell and 1.2
# bytes per byte of XML, build about 0.35 kB and 3.8 bytes; the larger of each is the estimate.
MEMORY_BUDGET = 4 * 1024 ** 3
MEMORY_PER_CELL = 1000
MEMORY_PER_XML_BYTE = 4
MAX_XML = MAX_UNCOMPRESSED


def parse_number(field: str, text: object) -> float:
    if isinstance(text, bool):
        raise InputError(field, f"must be a number (got {text!r})")
    try:
        value = float(text)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(field, f"must be a number (got {text!r})") from None
    except OverflowError:       # an integer with hundreds of digits
        raise InputError(field, f"must be a finite number (got an integer of "
                                f"{len(str(abs(text)))} digits)") from None
    if not math.isfinite(value):
        raise InputError(field, f"must be a finite number (got {text!r})")
    return value


def check_value(field: str, kind: str, raw: object) -> float:
    """The parameter's value, checked for its kind."""
    if kind == BRANCH_KIND:
        if isinstance(raw, str) and raw.strip().lower() in BRANCH_WORDS:
            return BRANCH_WORDS[raw.strip().lower()]
        value = parse_number(field, raw)
        if value not in (1.0, -1.0):
            raise InputError(field, f"must be open (1) or crossed (-1) (got {raw!r})")
        return value
    value = parse_number(field, raw)
    if kind == LENGTH_KIND and value <= 0:
        raise InputError(field, f"must be a positive length (got {raw!r})")
    lo, hi = LENGTH_RANGE
    if kind == LENGTH_KIND and not lo <= value <= hi:
        raise InputError(field, f"must be a length from {lo:g} to {hi:g} (got {raw!r})")
    if kind == OFFSET_KIND and abs(value) > hi:
        raise InputError(field, f"must be from {-hi:g} to {hi:g} (got {raw!r})")
    if kind == RATE_KIND and abs(value) > RATE_LIMIT:
        raise InputError(field, f"must be from {-RATE_LIMIT:g} to {RATE_LIMIT:g} (got {raw!r})")
    if kind in NOT_NEGATIVE_KINDS and value < 0:
        raise InputError(field, f"must be zero or more (got {raw!r})")
    small, big = LOAD_RANGE
    if kind in LOAD_UNITS and value != 0 and not small <= abs(value) <= big:
        raise InputError(field, f"must be 0 or from {small:g} to {big:g} either way "
                                f"(got {raw!r})")
    if kind == ANGLE_KIND and not -360 <= value <= 360:
        raise InputError(field, f"must be an angle from -360 to 360 degrees (got {raw!r})")
    return value


def check_lengths_together(values: dict[str, float], kinds: dict[str, str],
                           where: str = "", written: dict[str, float] | None = None) -> None:
    """The mechanism's extent (its largest length, offset or coordinate `written` as a number)
    at most LENGTH_SPAN times its smallest length: beyond it, rounding at the size of the one
    outgrows the bound at the size of the other (see the module's docstring). An offset or a
    coordinate far below the lengths acts as the zero it nearly is."""
    lengths = {k: abs(v) for k, v in values.items() if kinds.get(k) == LENGTH_KIND}
    if not lengths:
        return
    extent = {**lengths, **{k: abs(v) for k, v in values.items() if kinds.get(k) == OFFSET_KIND},
              **{k: abs(v) for k, v in (written or {}).items()}}
    small = min(lengths, key=lengths.get)
    large = max(extent, key=extent.get)
    if extent[large] > LENGTH_SPAN * lengths[small]:
        what = values.get(large, (written or {}).get(large))
        raise InputError(f"{where}{small}", f"{values[small]:g} is too small beside {large} = "
                                            f"{what:g} (at most {LENGTH_SPAN:g} times apart)")


def check_input(field: str, value: float, is_angle: bool) -> float:
    """An input value a book holds (a sweep angle, the current position; an actuator's length):
    within what the input cell's validation allows."""
    limit, unit = (INPUT_ANGLE_LIMIT, "°") if is_angle else (LENGTH_RANGE[1], "")
    if not abs(value) <= limit:
        raise InputError(field, f"{value:.12g} is outside the supported range "
                                f"(±{limit:g}{unit})")
    return value


# Keys of the mechanism language whose numbers are lengths (ground points too).
LENGTH_KEYS = ("length", "p_length", "q_length", "local", "distances", "distance", "offset")


def _number_terms(text: str) -> list[float]:
    """The numbers a length expression adds as lengths of their own: the terms of its outermost
    sum (`a6 - 200` → 200, `120` → 120). A number inside a product, a quotient or a function's
    arguments is a factor, a ratio or an angle (`a2*PI()/180`), not a length."""
    try:
        node = ast.parse(text.replace("^", "**"), mode="eval").body
    except (SyntaxError, ValueError, RecursionError):
        return []       # not an expression: the language names it
    terms, todo = [], [node]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            todo += [node.left, node.right]
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
            todo.append(node.operand)
        elif isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                and not isinstance(node.value, bool):
            try:
                terms.append(abs(float(node.value)))
            except OverflowError:           # an integer no double holds: refused as too large
                terms.append(math.inf)
    return terms[::-1]


def written_lengths(description: dict) -> dict[str, float]:
    """{field: value} of every non-zero length the description writes as a number, not a
    parameter (a ground point's coordinate, a step's length; numbers inside an expression
    there): part of the mechanism's size and extent."""
    found: dict[str, float] = {}

    def numbers(field: str, value) -> None:
        if isinstance(value, bool):
            return
        if isinstance(value, (int, float)):
            if value != 0:
                found[field] = float(value)
        elif isinstance(value, str):
            for i, term in enumerate(_number_terms(value)):
                if term != 0:
                    found[f"{field} ({term:g})" if i or field in found else field] = term
        elif isinstance(value, list):
            for i, v in enumerate(value):
                numbers(f"{field}[{i}]", v)
    ground = description.get("ground") if isinstance(description, dict) else None
    for name, xy in (ground if isinstance(ground, dict) else {}).items():
        numbers(f"mechanism.ground.{name}", xy)
    steps = description.get("steps") if isinstance(description, dict) else None
    for i, step in enumerate(steps if isinstance(steps, list) else []):
        if isinstance(step, dict):
            for k in LENGTH_KEYS:
                numbers(f"mechanism.steps[{i}].{k}", step.get(k))
            if step.get("type") == "expression" and step.get("unit") == "length":
                numbers(f"mechanism.steps[{i}].formula", step.get("formula"))
    return found


def check_written_lengths(description: dict, where: str = "") -> dict[str, float]:
    """The description's numbers that are lengths (written_lengths), each within an offset's
    range."""
    found = written_lengths(description)
    hi = LENGTH_RANGE[1]
    for field, value in found.items():
        if not math.isfinite(value) or abs(value) > hi:
            raise InputError(f"{where}{field}", f"a length written as a number must be from "
                                                f"{-hi:g} to {hi:g} (got {value:g})")
    return found


def check_size(formula_cells: int, xml_bytes: int) -> None:
    """Refuse a book verify could not read (more than MAX_XML of XML) or that would need more
    than MEMORY_BUDGET to build or verify."""
    if xml_bytes > MAX_XML:
        raise InputError("book size", f"the book would hold about {xml_bytes / 2**20:,.0f} MiB of XML; "
                                 f"verify reads at most {MAX_XML / 2**20:,.0f} MiB: "
                                 "a coarser step or fewer adjustments")
    memory = MEMORY_PER_CELL * formula_cells + MEMORY_PER_XML_BYTE * xml_bytes
    if memory > MEMORY_BUDGET:
        raise InputError("book size", f"the book's {formula_cells:,} formula cells would need about "
                                 f"{memory / 2**30:.1f} GiB of memory to build or verify; the "
                                 f"budget is {MEMORY_BUDGET / 2**30:.0f} GiB: a coarser step or "
                                 "fewer adjustments")
