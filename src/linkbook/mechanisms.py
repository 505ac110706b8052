"""Every mechanism as an ordered list of steps. Frames and keys: docs/mechanisms.md.

Adding a mechanism is writing one function here that calls the step types of steps.py, and a
template in templates/. Nothing below touches openpyxl.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .model import LENGTH, RAD, RATIO, Chart, FourBarLoop, Joint, Model
from .steps import (Sym, acos_or_na, asin_or_na, column, constant, four_bar_loop, input_angle,
                    offset_slide, point, polar, slider, triangle)

# Kinds of parameter, each with its own check (see params.py).
LENGTH_KIND, OFFSET_KIND, ANGLE_KIND, BRANCH_KIND = "length", "offset", "angle", "branch"


@dataclass(frozen=True)
class Mechanism:
    name: str
    parameters: dict[str, str]      # symbol -> kind, in the order the inputs block shows them
    input_key: str                  # "theta12"
    input_symbol: str               # "θ12"
    build: Callable[[], Model]
    grid: tuple[str, str] | None = None   # (parameter across the grid, quantity in its cells)


def on_loop(value: str, witness: str) -> str:
    """A coordinate fixed by construction (a slider pin's y on its line) that exists only where
    the loop closes: #N/A wherever `witness` is."""
    return f"IF(ISNUMBER({{{witness}}}),{value},NA())"


def _joints(**where: tuple[str, str] | None) -> list[Joint]:
    """Joints in drawing order: fixed ones with their coordinates, moving ones (None) from the
    point columns xName, yName that the steps added."""
    return [Joint(name, *(xy or (f"{{x{name}}}", f"{{y{name}}}"))) for name, xy in where.items()]


def _angle_chart(title: str, x: str, keys: tuple[str, ...], x_title: str) -> Chart:
    return Chart(title, x, tuple(f"{k}_deg" for k in keys), x_title, "angle [deg]")


def fourbar() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    four_bar_loop(m, "{a2}*COS({theta12})-{a1}", "{a2}*SIN({theta12})",
                  coupler="a3", rocker="a4")
    constant(m, Sym("gamma", "γ", "coupler angle ∠BAC"), RAD,
             acos_or_na("({a3}^2+{b3}^2-{c3}^2)/(2*{a3}*{b3})"))
    point(m, "A", "{a2}*COS({theta12})", "{a2}*SIN({theta12})", label="crank pin A")
    point(m, "B", "{a1}+{a4}*COS({theta14})", "{a4}*SIN({theta14})", label="rocker pin B")
    point(m, "C", "{xA}+{b3}*COS({theta13}+{gamma})", "{yA}+{b3}*SIN({theta13}+{gamma})",
          label="coupler point C")
    m.joints = _joints(A0=("0", "0"), A=None, B=None, B0=("{a1}", "0"), C=None)
    m.links = [("A0", "A"), ("A", "B", "C", "A"), ("B", "B0")]
    m.closes, m.transmission = "theta13", "mu"
    m.fourbar = FourBarLoop("{a1}", "{a2}", "{a3}", "{a4}")
    m.path = ("xC", "yC")
    m.charts = [_angle_chart("Output angles and transmission angle", "theta12_deg",
                             ("theta13", "theta14", "mu"), "θ12 [deg]"),
                Chart("Coupler curve of C", "xC", ("yC",), "xC", "yC", equal_axes=True)]
    return m


def slider_crank() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    slider(m, pin_x="{a2}*COS({theta12})", pin_y="{a2}*SIN({theta12})", line_y="a1",
           length="a3", branch="branch",
           angle=Sym("theta13", "θ13", "coupler, angle of B→A", deg=True),
           position=Sym("s14", "s14", "slider position, x of B"))
    point(m, "A", "{a2}*COS({theta12})", "{a2}*SIN({theta12})", label="crank pin A")
    point(m, "B", "{s14}", on_loop("{a1}", "s14"), label="slider pin B")
    point(m, "C", "{s14}+{b3}*COS({theta13}-RADIANS({gamma3}))",
          "{a1}+{b3}*SIN({theta13}-RADIANS({gamma3}))", label="coupler point C")
    m.joints = _joints(A0=("0", "0"), A=None, B=None, C=None)
    m.links = [("A0", "A"), ("A", "B", "C", "A")]
    m.closes, m.output = "theta13", "s14"
    m.path = ("xC", "yC")
    m.charts = [_angle_chart("Coupler angle θ13", "theta12_deg", ("theta13",), "θ12 [deg]"),
                Chart("Slider position s14", "theta12_deg", ("s14",), "θ12 [deg]", "s14"),
                Chart("Coupler curve of C", "xC", ("yC",), "xC", "yC", equal_axes=True)]
    return m


def pump() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    polar(m, "{b1}+{a2}*COS({theta12})", "-{s1}+{a2}*SIN({theta12})",
          Sym("xa", "xa", "B0→A, x"), Sym("ya", "ya", "B0→A, y"),
          Sym("s", "s", "|B0A|"), Sym("phi", "ϕ", "angle of B0→A"))
    triangle(m, side="s", angle="phi", p="a3", q="a4", branch="branch",
             psi=Sym("psi", "ψ", "∠AB0B"),
             q_angle=Sym("theta14", "θ14", "rocker, angle of B0→B − 90°", deg=True),
             q_offset="-PI()/2")
    column(m, Sym("s4", "s4", "plunger pin along the slot"), LENGTH,
           "-({s1}+{c4}*SIN({theta14}))/COS({theta14})")
    # The textbook's s15 = b1 − c4·cos θ14 + s4·sin θ14 with s4 substituted: the same number,
    # and the self-contained grid formula then carries θ14 twice instead of four times.
    column(m, Sym("s15", "s15", "plunger position"), LENGTH,
           "{b1}-({c4}+{s1}*SIN({theta14}))/COS({theta14})")
    point(m, "A", "{a2}*COS({theta12})", "{a2}*SIN({theta12})", label="crank pin A")
    point(m, "B", "-{b1}-{a4}*SIN({theta14})", "{s1}+{a4}*COS({theta14})", label="rocker pin B")
    point(m, "E", "-{b1}+{c4}*COS({theta14})", "{s1}+{c4}*SIN({theta14})", label="slot foot E")
    point(m, "P", "-{s15}", on_loop("0", "s15"), label="plunger pin P")
    m.joints = _joints(A0=("0", "0"), A=None, B=None, B0=("-{b1}", "{s1}"), E=None, P=None)
    m.closes, m.output = "s15", "s15"
    m.fourbar = FourBarLoop("SQRT({b1}^2+{s1}^2)", "{a2}", "{a3}", "{a4}", "ATAN2(-{b1},{s1})")
    m.links = [("A0", "A"), ("A", "B"), ("B", "B0", "E"), ("E", "P")]
    m.charts = [Chart("Plunger position s15", "theta12_deg", ("s15",), "θ12 [deg]", "s15"),
                _angle_chart("Rocker angle θ14", "theta12_deg", ("theta14",), "θ12 [deg]")]
    return m


def inverted_slider_crank() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    polar(m, "{a2}*COS({theta12})-{a1}", "{a2}*SIN({theta12})",
          Sym("xp", "xp", "B0→A, x"), Sym("yp", "yp", "B0→A, y"),
          Sym("p", "p", "|B0A|"), Sym("phi", "ϕ", "angle of B0→A"))
    offset_slide(m, p="p", angle="phi", offset="a4", branch="branch",
                 psi=Sym("psi", "ψ", "∠AB0B"),
                 travel=Sym("s", "s", "slider position |BA|"),
                 link_angle=Sym("theta14", "θ14", "link 4, angle of B0→B", deg=True),
                 slide_angle=Sym("theta13", "θ13", "slide direction, angle of B→A", deg=True))
    point(m, "A", "{a2}*COS({theta12})", "{a2}*SIN({theta12})", label="crank pin A")
    point(m, "B", "{a1}+{a4}*COS({theta14})", "{a4}*SIN({theta14})", label="foot B of the slide")
    m.joints = _joints(A0=("0", "0"), A=None, B=None, B0=("{a1}", "0"))
    m.closes, m.output = "theta14", "s"
    m.links = [("A0", "A"), ("B0", "B", "A")]
    m.charts = [_angle_chart("Link angles", "theta12_deg", ("theta14", "theta13"), "θ12 [deg]"),
                Chart("Slider position s", "theta12_deg", ("s",), "θ12 [deg]", "s")]
    return m


def quick_return() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    polar(m, "{a2}*COS({theta12})", "{a1}+{a2}*SIN({theta12})",
          Sym("xA", "xA", "crank pin A = B0→A, x"), Sym("yA", "yA", "crank pin A = B0→A, y"),
          Sym("s43", "s43", "block on the rocker, |B0A|"),
          Sym("theta14", "θ14", "rocker, angle of B0→A", deg=True))
    slider(m, pin_x="{a4}*COS({theta14})", pin_y="{a4}*SIN({theta14})", line_y="b1",
           length="a5", branch="branch",
           angle=Sym("theta15", "θ15", "link 5, angle of D→C", deg=True),
           position=Sym("s16", "s16", "ram position, x of D"))
    # The rocker swings over 90° ± α, α = asin(a2/a1), and the ram turns back at the swing's ends:
    # ratio (π + 2α)/(π − 2α). It exists when the ram link closes over the whole turn (it reaches
    # the ram line at both ends of the swing) and the ram reverses only there, i.e. no dead
    # centre of the ram dyad (B0, C, D in line: sin θ14 = b1/(a4 ± a5)) lies inside the swing.
    alpha = asin_or_na("{a2}/{a1}")
    closes = f"MAX(ABS({{b1}}-{{a4}}*COS({alpha})),ABS({{b1}}-{{a4}}))>{{a5}}"

    def dead_centre_in_swing(length: str) -> str:
        return (f"IFERROR(({{b1}}/({length})>=COS({alpha}))*({{b1}}/({length})<=1),0)")

    constant(m, Sym("time_ratio", "Q", "quick-return ratio, forward/return time"), RATIO,
             f"IF(({closes})+{dead_centre_in_swing('{a4}+{a5}')}"
             f"+{dead_centre_in_swing('{a4}-{a5}')},NA(),(PI()+2*{alpha})/(PI()-2*{alpha}))")
    point(m, "C", "{a4}*COS({theta14})", "{a4}*SIN({theta14})", label="rocker end C")
    point(m, "D", "{s16}", on_loop("{b1}", "s16"), label="ram pin D")
    m.joints = _joints(A0=("0", "{a1}"), A=None, B0=("0", "0"), C=None, D=None)
    m.closes, m.output = "s16", "s16"
    m.links = [("A0", "A"), ("B0", "C"), ("C", "D")]
    m.path = None
    m.charts = [_angle_chart("Rocker and link angles", "theta12_deg", ("theta14", "theta15"),
                             "θ12 [deg]"),
                Chart("Ram position s16", "theta12_deg", ("s16",), "θ12 [deg]", "s16")]
    return m


def shaper() -> Model:
    m = Model()
    input_angle(m, "theta2", "θ2")
    polar(m, "{r2}*COS({theta2})", "{r1}+{r2}*SIN({theta2})",
          Sym("xA", "xA", "block A"), Sym("yA", "yA", "block A"),
          Sym("r3", "r3", "|O1A|"), Sym("theta3", "θ3", "lever, angle of O1→A", deg=True))
    column(m, Sym("r4", "r4", "|O1B|, lever to the ram pin"), LENGTH,
           "({r1}+{r6})/SIN({theta3})")
    column(m, Sym("r5", "r5", "ram position, x of B"), LENGTH, "{r4}*COS({theta3})")
    point(m, "B", "{r5}", "{r1}+{r6}", label="ram pin B")
    m.joints = _joints(O1=("0", "0"), O2=("0", "{r1}"), A=None, B=None)
    m.closes, m.output = "r5", "r5"
    m.links = [("O2", "A"), ("O1", "A", "B")]
    m.charts = [_angle_chart("Lever angle θ3", "theta2_deg", ("theta3",), "θ2 [deg]"),
                Chart("Lengths r3, r4, r5", "theta2_deg", ("r3", "r4", "r5"), "θ2 [deg]",
                      "length")]
    return m


def garage_door() -> Model:
    m = Model()
    input_angle(m, "theta12", "θ12")
    four_bar_loop(m, "{a2}*COS({theta12})", "{a2}*SIN({theta12})-{a1}",
                  coupler="a3", rocker="a4")
    point(m, "B", "{a4}*COS({theta14})", "{a1}+{a4}*SIN({theta14})")
    point(m, "D", "{b2}*COS({theta12})", "{b2}*SIN({theta12})")
    polar(m, "{xD}-{xB}", "{yD}-{yB}",
          Sym("xs2", "xs′", "B→D, x"), Sym("ys2", "ys′", "B→D, y"),
          Sym("s2", "s′", "|BD|"), Sym("eta", "η", "angle of B→D"))
    triangle(m, side="s2", angle="eta", p="a6", q="a5", branch="branch_door",
             psi=Sym("xi", "ξ", "∠DBC"),
             p_interior=Sym("gamma", "γ", "∠BDC"),
             q_angle=Sym("theta15", "θ15", "link 5, angle of B→C", deg=True),
             p_angle=Sym("theta16", "θ16", "door, angle of D→C", deg=True))
    point(m, "C", "{xB}+{a5}*COS({theta15})", "{yB}+{a5}*SIN({theta15})")
    point(m, "A", "{a2}*COS({theta12})", "{a2}*SIN({theta12})", label="crank pin A")
    m.joints = _joints(A0=("0", "0"), A=None, D=None, B=None, B0=("0", "{a1}"), C=None)
    m.closes, m.transmission = "theta16", "mu"
    m.fourbar = FourBarLoop("{a1}", "{a2}", "{a3}", "{a4}", "PI()/2")
    m.links = [("A0", "A", "D"), ("A", "B"), ("B0", "B"), ("B", "C"), ("D", "C")]
    m.path = ("xC", "yC")
    m.charts = [_angle_chart("Link angles", "theta12_deg",
                             ("theta13", "theta14", "theta15", "theta16"), "θ12 [deg]"),
                Chart("Path of the door edge C", "xC", ("yC",), "xC", "yC", equal_axes=True)]
    return m


def tk_fourbar() -> Model:
    m = Model()
    input_angle(m, "phi", "φ")
    point(m, "1", "{a}*COS({phi})", "{a}*SIN({phi})")
    polar(m, "{x1}-{x3}", "{y1}-{y3}",
          Sym("xs", "xs", "P3→P1, x"), Sym("ys", "ys", "P3→P1, y"),
          Sym("s", "s", "|P3P1|"), Sym("delta", "δ", "angle of P3→P1"))
    triangle(m, side="s", angle="delta", p="b", q="c", branch="branch",
             psi=Sym("beta", "β", "∠P1P3P2"),
             mu=Sym("mu", "μ", "transmission angle ∠P3P2P1", deg=True),
             q_angle=Sym("psi", "ψ", "output crank, angle of P3→P2", deg=True, wrap=True),
             p_angle=Sym("theta", "θ", "coupler, angle of P1→P2", deg=True))
    point(m, "2", "{x3}+{c}*COS({psi})", "{y3}+{c}*SIN({psi})")
    point(m, "4", "{x1}+{m}*COS({theta})-{n}*SIN({theta})",
          "{y1}+{m}*SIN({theta})+{n}*COS({theta})")
    column(m, Sym("d", "d", "|P1P4|, must stay constant"), LENGTH,
           "SQRT(({x4}-{x1})^2+({y4}-{y1})^2)")
    column(m, Sym("e", "e", "|P2P4|, must stay constant"), LENGTH,
           "SQRT(({x4}-{x2})^2+({y4}-{y2})^2)")
    m.joints = [Joint("P0", "0", "0"), Joint("P1", "{x1}", "{y1}"), Joint("P2", "{x2}", "{y2}"),
                Joint("P3", "{x3}", "{y3}"), Joint("P4", "{x4}", "{y4}")]
    m.closes, m.transmission = "theta", "mu"
    m.fourbar = FourBarLoop("SQRT({x3}^2+{y3}^2)", "{a}", "{b}", "{c}", "ATAN2({x3},{y3})")
    m.links = [("P0", "P1"), ("P1", "P2", "P4", "P1"), ("P3", "P2")]
    m.path = ("x4", "y4")
    m.charts = [_angle_chart("Output crank ψ and coupler θ", "phi_deg", ("psi", "theta"),
                             "φ [deg]"),
                Chart("Coupler-point curve of P4", "x4", ("y4",), "x4", "y4", equal_axes=True)]
    return m


L, O, A_, B_ = LENGTH_KIND, OFFSET_KIND, ANGLE_KIND, BRANCH_KIND

MECHANISMS: dict[str, Mechanism] = {m.name: m for m in (
    Mechanism("fourbar", {"a1": L, "a2": L, "a3": L, "a4": L, "b3": L, "c3": L, "branch": B_},
              "theta12", "θ12", fourbar),
    Mechanism("slider-crank", {"a1": O, "a2": L, "a3": L, "b3": L, "gamma3": A_, "branch": B_},
              "theta12", "θ12", slider_crank),
    Mechanism("pump", {"a2": L, "a3": L, "a4": L, "b1": L, "c4": L, "s1": O, "branch": B_},
              "theta12", "θ12", pump, grid=("s1", "s15")),
    Mechanism("inverted-slider-crank", {"a1": L, "a2": L, "a4": O, "branch": B_},
              "theta12", "θ12", inverted_slider_crank),
    Mechanism("quick-return", {"a1": L, "a2": L, "a4": L, "a5": L, "b1": O, "branch": B_},
              "theta12", "θ12", quick_return),
    Mechanism("shaper", {"r1": L, "r2": L, "r6": O}, "theta2", "θ2", shaper),
    Mechanism("garage-door", {"a1": L, "a2": L, "a3": L, "a4": L, "b2": L, "a5": L, "a6": L,
                              "branch": B_, "branch_door": B_},
              "theta12", "θ12", garage_door),
    Mechanism("tk-fourbar", {"a": L, "b": L, "c": L, "m": O, "n": O, "x3": O, "y3": O,
                             "branch": B_},
              "phi", "φ", tk_fourbar),
)}
