"""The textbook's step types: each solves one triangle of a loop and adds named quantities.

A mechanism is an ordered list of these steps, described as data (docs/language.md) and compiled
by language.py. Formulas are Excel text with
{key} placeholders; model.render resolves them. Guards: an ACOS/ASIN whose argument leaves [-1, 1]
means the loop cannot close, so it becomes #N/A (never #NUM!, never a clamped wrong number), and
#N/A then propagates to every cell that depends on it. The argument's domain is tested before
the function is called, not caught after: spreadsheet applications do not agree on what ACOS(2)
is (an error in Excel, LibreOffice and Gnumeric, a NaN that reads as 0 in IronCalc).
"""
from __future__ import annotations

from dataclasses import dataclass

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


def _q(sym: Sym, unit: str, formula: str) -> Quantity:
    return Quantity(sym.key, sym.symbol, unit, formula, COLUMN if sym.shown else ALIAS,
                    label=sym.label, in_degrees=sym.deg and sym.shown, wrap_360=sym.wrap)


# Where a function is undefined, as Excel text with {x} for its argument (a comparison binds
# last in Excel: a sum needs no brackets before <0).
OUTSIDE_DOMAIN = {"ACOS": "ABS({x})>1", "ASIN": "ABS({x})>1", "SQRT": "{x}<0"}


def outside_domain(function: str, arg: str) -> str:
    """The test, as Excel text, that `arg` is outside `function`'s domain."""
    return OUTSIDE_DOMAIN[function].format(x=arg)


def in_domain_or_na(function: str, arg: str) -> str:
    """function(arg), or #N/A where arg is outside its domain (tested, not caught)."""
    return f"IF({outside_domain(function, arg)},NA(),{function}({arg}))"


def angle_of_triangle_or_na(adjacent1: str, adjacent2: str, opposite: str, once: str) -> str:
    """The cosine rule: the angle between sides {adjacent1} and {adjacent2} (keys), or #N/A
    where the three sides make no triangle. That test is the domain of the ACOS's argument,
    |b - c| <= a <= b + c, written with side {once} appearing once: in a grid's
    self-contained formula a side is a whole formula, and ABS(argument)>1 would write the
    argument, and each side in it, twice more in every nested step."""
    a, b = (k for k in (adjacent1, adjacent2, opposite) if k != once)
    fails = f"ABS({{{once}}}-MAX({{{a}}},{{{b}}}))>MIN({{{a}}},{{{b}}})"
    cosine = (f"({{{adjacent1}}}^2+{{{adjacent2}}}^2-{{{opposite}}}^2)"
              f"/(2*{{{adjacent1}}}*{{{adjacent2}}})")
    # IFERROR: a zero side divides by zero, and rounding at an exact limit position can put
    # the cosine a hair beyond 1; both are #N/A too
    return f"IFERROR(IF({fails},NA(),ACOS({cosine})),NA())"


def acos_or_na(arg: str) -> str:
    # IFERROR: a zero length divides by zero; that too is #N/A
    return f"IFERROR({in_domain_or_na('ACOS', arg)},NA())"


def asin_or_na(arg: str) -> str:
    return f"IFERROR({in_domain_or_na('ASIN', arg)},NA())"


def input_angle(model: Model, key: str, symbol: str) -> None:
    """The input angle in radians, from its degree value `{key}_deg` (a constant or an input cell)."""
    model.add(Quantity(key, symbol, RAD, f"RADIANS({{{key}_deg}})", label="input angle"))


def polar(model: Model, dx: str, dy: str, x: Sym, y: Sym, length: Sym, angle: Sym) -> None:
    """A vector from its components: the calculator's rectangular-to-polar conversion."""
    model.add(
        _q(x, LENGTH, dx),
        _q(y, LENGTH, dy),
        _q(length, LENGTH, f"SQRT({{{x.key}}}^2+{{{y.key}}}^2)"),
        _q(angle, RAD, f"ATAN2({{{x.key}}},{{{y.key}}})"),  # Excel's ATAN2 takes x first
    )


def triangle(model: Model, *, side: str, angle: str, p: str, q: str, branch: str,
             psi: Sym, q_angle: Sym, q_offset: str = "", mu: Sym | None = None,
             p_interior: Sym | None = None, p_angle: Sym | None = None) -> None:
    """Raven's step: R joined to P by a link {p} and to Q by a link {q}; |QP| = {side} and
    angle(Q→P) = {angle} are known.

    ψ = ∠PQR, μ = ∠QRP and the angle at P by the cosine theorem; angle(Q→R) = ϕ − branch·ψ
    (+ q_offset, for a mechanism that measures its link from another direction); angle(P→R) is
    angle(Q→R) − branch·μ, or angle(Q→P) + π + branch·∠QPR when the angle at P is the one shown.
    """
    def cosine_rule(adjacent1: str, adjacent2: str, opposite: str) -> str:
        return angle_of_triangle_or_na(adjacent1, adjacent2, opposite, once=side)

    model.add(_q(psi, RAD, cosine_rule(q, side, p)))
    if mu is not None:
        model.add(_q(mu, RAD, cosine_rule(p, q, side)))
    if p_interior is not None:
        model.add(_q(p_interior, RAD, cosine_rule(p, side, q)))
    model.add(_q(q_angle, RAD, f"{{{angle}}}-{{{branch}}}*{{{psi.key}}}{q_offset}"))
    if p_angle is None:
        return
    if mu is not None and not q_offset:
        model.add(_q(p_angle, RAD, f"{{{q_angle.key}}}-{{{branch}}}*{{{mu.key}}}"))
    elif p_interior is not None:
        model.add(_q(p_angle, RAD, f"{{{angle}}}+PI()+{{{branch}}}*{{{p_interior.key}}}"))
    else:
        raise ValueError("angle(P→R) needs μ (with an unshifted angle(Q→R)) or the angle at P")


def slider(model: Model, *, pin_x: str, pin_y: str, line_y: str, length: str, branch: str,
           angle: Sym, position: Sym, direction: str = "") -> None:
    """The slider-crank step: slider S on a line, |S pin| = {length}. pin_x, pin_y: the pin in
    the line's frame (x along the line); line_y: the line's y in that frame (Excel text, "0" for a
    line through the frame's origin); direction: the line's angle (radians, Excel text; "" for a
    horizontal line, whose frame is the mechanism's own).

    angle = angle(S→pin): π − asin(…) on branch 1 (S ahead of the pin), asin(…) on branch −1,
    written as π/2 + branch·(π/2 − asin(…)) so that the argument appears once; the position is
    S's x in the line's frame.
    """
    rise = pin_y if line_y == "0" else f"({pin_y}-{line_y})"
    turn = f"{direction}+" if direction else ""
    relative = f"({{{angle.key}}}-{direction})" if direction else f"{{{angle.key}}}"
    model.add(
        _q(angle, RAD, f"{turn}PI()/2+{{{branch}}}*(PI()/2-"
                       + asin_or_na(f"{rise}/{{{length}}}") + ")"),
        _q(position, LENGTH, f"{pin_x}-{{{length}}}*COS({relative})"),
    )


def offset_slide(model: Model, *, p: str, angle: str, offset: str, branch: str,
                 psi: Sym, travel: Sym, link_angle: Sym, slide_angle: Sym) -> None:
    """The inverted slider-crank step: the slide line sits at distance {offset} from the pivot.

    The triangle pivot–foot–pin is right-angled at the foot: ψ = acos(offset/p), travel = p·sin ψ.
    """
    model.add(
        _q(psi, RAD, acos_or_na(f"{{{offset}}}/{{{p}}}")),
        _q(travel, LENGTH, f"{{{p}}}*SIN({{{psi.key}}})"),
        _q(link_angle, RAD, f"{{{angle}}}-{{{branch}}}*{{{psi.key}}}"),
        _q(slide_angle, RAD, f"{{{link_angle.key}}}+{{{branch}}}*PI()/2"),
    )
