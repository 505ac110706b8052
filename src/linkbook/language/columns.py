"""The columns a step writes: what each is called (Column, Sym), and the formulas several step
types share (the input angle, the rectangular-to-polar conversion).
"""
from __future__ import annotations

from dataclasses import dataclass

from .excel import direction, key
from .model import ALIAS, COLUMN, LENGTH, RAD, Model, Quantity


@dataclass(frozen=True)
class Sym:
    """The key, printed symbol and a short description of one quantity a step adds."""
    key: str
    symbol: str
    label: str = ""
    deg: bool = False      # an output angle: also shown in degrees
    wrap: bool = False     # show that degree value in [0°, 360°)
    shown: bool = True     # a column of its own, or only written into the formulas that use it


def quantity(sym: Sym, unit: str, formula: str) -> Quantity:
    """The quantity of a step's column: a column of its own where shown, else an alias written
    into the formulas that use it."""
    return Quantity(sym.key, sym.symbol, unit, formula, COLUMN if sym.shown else ALIAS,
                    label=sym.label, in_degrees=sym.deg and sym.shown, wrap_360=sym.wrap)


@dataclass(frozen=True)
class Column:
    """One column a step type writes: its name in `columns`, defaults, unit."""
    name: str
    key: str
    symbol: str
    label: str
    unit: str
    degrees: bool = False
    shown: bool = True


def polar_columns(n: str, a: str, b: str, degrees: bool = False) -> list[Column]:
    """The textbook's rectangular-to-polar columns of the vector a→b, keyed by `n`."""
    return [Column("xs", f"xs_{n}", f"xs_{n}", f"{a}→{b}, x", LENGTH),
            Column("ys", f"ys_{n}", f"ys_{n}", f"{a}→{b}, y", LENGTH),
            Column("s", f"s_{n}", f"s_{n}", f"|{a}{b}|", LENGTH),
            Column("phi", f"phi_{n}", f"ϕ_{n}", f"angle of {a}→{b}", RAD, degrees)]


def input_angle(model: Model, key: str, symbol: str) -> None:
    """The input angle in radians, from its degree value `{key}_deg` (a constant or an input cell)."""
    model.add(Quantity(key, symbol, RAD, f"RADIANS({{{key}_deg}})", label="input angle"))


def polar(model: Model, dx: str, dy: str, x: Sym, y: Sym, length: Sym, angle: Sym,
          closes: bool = False) -> None:
    """A vector from its components: the calculator's rectangular-to-polar conversion. Its
    angle is #N/A where the vector is zero (excel.direction), except for a loop that `closes`
    on it only where it is not zero (a dyad's P→Q: its triangle needs |PQ| > 0): there the
    plain ATAN2 keeps a formula a grid inlines short."""
    atan = f"ATAN2({{{x.key}}},{{{y.key}}})" if closes else \
        direction(key(x.key), key(y.key)).text
    model.add(
        quantity(x, LENGTH, dx),
        quantity(y, LENGTH, dy),
        quantity(length, LENGTH, f"SQRT({{{x.key}}}^2+{{{y.key}}}^2)"),
        quantity(angle, RAD, atan),
    )
