"""Independent force reference: the driving effort, every pin load and the shaking force of a
described mechanism, from the Newton–Euler equations of all its moving links solved at once.

The description is a template's ``[mechanism]`` table (docs/language.md) with its dynamics:

    [mechanism.dynamics]
    gravity = { g = "g", angle = -90 }    # m/s², degrees from +x (default −90); none if absent
    [[mechanism.bodies]]                  # one per moving link that has mass
    joints = ["A", "B", "C"]              # the points the link holds
    block = false                         # true: a block (joints = [its point]), centred there
    mass = "m3"                           # kg
    centre = { frame = ["A", "B"], distance = "g3", angle = 0 }   # placed as a `point` step
    inertia = "I3"                        # kg·m² about the centre of mass
    [[mechanism.loads]]
    at = "C"; force = ["Fx", "Fy"]        # N; or force = { magnitude = "F", angle = "beta" }
    body = ["B0", "B"]; torque = "T4"     # N·m, counter-clockwise, on the body holding these

Every value is a number, a parameter or an expression, which may name the steps' columns and
the rates too (a damper's −c·ω: the kinematic reference's own rates).
Lengths are in the template's ``length_unit``, converted to metres once: forces in N, moments in
N·m. A force at a block's point acts on the block, at any other point on the lowest-numbered
link holding it, unless the load names its link (``body`` beside ``at``).

Why it is independent: it reads the topology from the description, assembles the equations from
the constraints, 3 per moving body (ΣF = m·a_G, ΣM = I_G·α, in d'Alembert's form) with the
reactions as unknowns, and solves them with numpy row by row. All it takes from linkbook is the
kinematic reference's public ``positions`` and ``motion`` (``solve`` in two halves): the motion of
every point, and the evaluation of the expressions (as an `expression` step's, after the rates).
No closed form of the workbook's is used. ``forces_and_at_rest`` takes one solution of the
positions on to the forces at the given speed and at rest, where the positions read no rate.

Three modules do the work: topology.py (the bodies, their pins and sliding pairs), loads.py
(what acts on them, per row) and equations.py (the system and its solution); this one reports.

Topology. Each step type says what it makes of the bodies in its own module
(reference/steps/<type>.py, ``topology``). The rigid bodies are the sets of points that move
together: each ``links`` entry and each step's links (a crank's pivot and pin, a dyad's two
sides, a slider's rod, a slide's link from its pivot to its point; a carried point joins the
body of its frame, or, by ``distances`` on a frame that is no body, makes two links); sets
sharing two points are one body, and cranks on one pivot are one body. A ``bodies`` entry gives
the body holding its joints a mass. The side of a dyad that is the linear actuator's length is
no body: a massless member of unknown force.
Every step that slides makes a block, a body of one point (its centre), on a guide:
- a ``slider``: at its point, on its fixed line (the ground) or on the link of ``along``,
  pinned to its rod;
- a ``slide``: at its ``p``, on the slide's link (its pivot and point), pinned to the links
  holding p (the crank);
- a ``slot``: at its point, on its fixed line (the ground), and in the slot of the link of
  ``slot_frame``: a pin pushed across the slot only (one unknown, no couple);
- a ``vector`` from a pivot U to a pin V, where another step places a point on the frame U→V
  or slides on it and no other step's link holds both (a slotted link: the crank shaper's
  rocker): at V, on the slotted link turning about U along U→V, pinned to the links holding V.
A link's frame turns with it beside its joints (a slotted link's U→V; a slide's line, its
point→p, which at offset 0 is the one a point is placed on): a carried point, a centre, a
``bodies`` entry and a torque may name the link by it; its second point is no joint (no pin).
A guide pushes its block across its line and holds it with a couple; the block turns with its
guide (not at all on a fixed line). A sliding point is no joint of its guide: a ``links`` entry
holding a point of the guide (``along`` and ``through``; the slide's pivot and point; the slot's
``slot_through`` and ``slot_frame``; a slotted link's pivot) leaves it out, and one left with
fewer than two points only draws. Numbering, as the textbook's: the ground 1, the crank 2, then the other bodies in the
order of the ``links`` entries, then those that only the steps name, then the blocks in the
order of their steps. Links that are no mechanism of one degree of freedom (unknowns, 2 per pin
and guide, 1 per slot and the effort, other than 3 per body) are refused.

What ``forces`` returns (arrays over the rows; i < j body numbers, written together as "23", or
with "_" between them, "2_13", in a mechanism of ten bodies or more):
- ``T12``: the driving torque of the ground (the motor) on the crank 2, counter-clockwise
  positive; for a linear actuator ``F_in``: its force, positive pushing its two ends apart;
- ``F{i}{j}x``, ``F{i}{j}y``, ``F{i}{j}``: the force of body i on body j at the pin joining
  them, and its size. A pin held by more than two bodies is carried by the lowest-numbered of
  them (the ground at a ground point): each other body j gets F{that}{j};
- for a block j on its guide i (1: a fixed line): ``N{i}{j}``, the guide's force on it along
  the line's direction turned +90°; ``M{i}{j}``, the guide's couple on it; ``F{i}{j}x``,
  ``F{i}{j}y``, ``F{i}{j}``: that force as a vector, its size (|N|). The line's direction: a
  fixed line's ``direction``; angle(U→V) + ``direction`` along [U, V]; a slide's column
  ``theta_slide``. On the guide, the opposite force and couple;
- for a slot's block j in the link i: ``N{i}{j}``, the link's force on it across the slot (its
  direction, angle(slot_frame) + ``slot_angle``, turned +90°), ``F{i}{j}x``, ``F{i}{j}y``,
  ``F{i}{j}``; no couple;
- for a triad's binary link P–N (a strut, its step's topology): ``Fa_N``, ``Fn_N``, its pin
  force on the ternary resolved along P→N and across it (P→N turned +90°);
- ``shaking_x``, ``shaking_y``, ``shaking``: the force the moving links exert on the ground
  (through the ground pins, the fixed guides with their couples and the actuator's ground
  end); ``shaking_moment``: its moment about the frame's origin, the motor's reaction −T12
  included;
- ``xG{n}``, ``yG{n}``, ``axG{n}``, ``ayG{n}``: a link's centre of mass and its acceleration,
  in the template's length unit (per s²);
- ``cond``: each row's condition number (equilibrated). A row is NaN where a position or a rate
  is NaN, or where the system is singular (cond above SINGULAR);
- ``bodies``: {number: the body's joints}; ``joints``: {reaction key F{i}{j}: its point} for
  every pin, guide and slot.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..reference import motion, positions, reads_rates
from ..reference.positions import Positions
from .equations import SINGULAR, Conditions, System, actuator_line, equations, solve_rows
from .loads import Rows, cross, read_loads
from .topology import GROUND, Topology, body_of, topology

__all__ = ["forces", "forces_and_at_rest", "topology", "LENGTH_UNITS", "SINGULAR"]

LENGTH_UNITS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}
# The data format's names of the input's speed and acceleration (docs/language.md).
_RATES = {"angle": ("omega_in", "alpha_in"), "length": ("v_in", "a_in")}


def _shake(shaking, fx, fy, at):
    """The ground pushes the links with (fx, fy) at `at`: they push it back."""
    sx, sy, sm = shaking
    return sx - fx, sy - fy, sm - cross(at[0], at[1], fx, fy)


def _report(top: Topology, system: System, x: np.ndarray) -> dict:
    rows, out, joints = system.rows, {}, {}
    shaking = (np.zeros(rows.n), np.zeros(rows.n), np.zeros(rows.n))
    for r in system.reactions:
        if r.normal is None:                            # a pin
            fx, fy = x[:, r.cols[0]], x[:, r.cols[1]]
            out[r.key] = np.hypot(fx, fy)
        else:                                           # a guide or a slot: N across its line
            normal = out["N" + r.key[1:]] = x[:, r.cols[0]]
            fx, fy = r.normal[0] * normal, r.normal[1] * normal
            out[r.key] = np.abs(normal)
        out[r.key + "x"], out[r.key + "y"], joints[r.key] = fx, fy, r.point
        couple = np.zeros(rows.n) if r.couple is None else x[:, r.couple]
        if r.couple is not None:
            out["M" + r.key[1:]] = couple
        if r.i == GROUND:
            sx, sy, sm = _shake(shaking, fx, fy, rows.position(r.point))
            shaking = sx, sy, sm - couple
    effort = out[system.effort] = x[:, system.names.index(system.effort)]
    sx, sy, sm = shaking
    if top.crank is not None:
        sm = sm - effort                                # the motor's stator turns the other way
    elif top.actuator[0] in top.fixed:
        ux, uy = actuator_line(top, rows)
        sx, sy, sm = _shake((sx, sy, sm), effort * ux, effort * uy,
                            rows.position(top.actuator[0]))
    out.update(shaking_x=sx, shaking_y=sy, shaking=np.hypot(sx, sy), shaking_moment=sm)
    for body in top.bodies:          # each centre of mass: where it is, how it accelerates
        if body.centre is not None and not body.block:
            x, y = (np.broadcast_to(np.asarray(c, dtype=float), (rows.n,))
                    for c in rows.solved["points"][body.centre])
            ax, ay = (a / rows.m for a in rows.rate("a", body.centre))
            n = body.number
            out[f"xG{n}"], out[f"yG{n}"], out[f"axG{n}"], out[f"ayG{n}"] = x, y, ax, ay
    out.update(_struts(top, system, out))
    out["bodies"] = {b.number: tuple(b.joints) for b in top.bodies}
    out["joints"] = joints
    return out


def _struts(top: Topology, system: System, out: dict) -> dict:
    """Each strut's (a triad's binary link P–N) force on the link it holds at N, along P→N
    (Fa_N) and across it, turned +90° (Fn_N): the pin force F{i}{j} between the two, turned
    into the strut's on the other link and resolved. A strut pinned to that link through a
    third body (the pin carried by neither) has none."""
    found = {}
    for pivot, joint, onto in top.struts:
        link, other = body_of(top, (pivot, joint), "strut"), body_of(top, onto, "strut")
        pin = next((r for r in system.reactions if r.point == joint and r.normal is None
                    and {r.i, r.j} == {link.number, other.number}), None)
        if pin is None:
            continue
        sign = 1.0 if pin.i == link.number else -1.0
        fx, fy = sign * out[pin.key + "x"], sign * out[pin.key + "y"]
        (px, py), (nx, ny) = system.rows.position(pivot), system.rows.position(joint)
        length = np.hypot(nx - px, ny - py)
        ux, uy = (nx - px) / length, (ny - py) / length
        found[f"Fa_{joint}"], found[f"Fn_{joint}"] = fx * ux + fy * uy, fy * ux - fx * uy
    return found


def forces(description: Mapping, params: Mapping[str, float], angles_deg,
           length_unit: str = "m", turns: Mapping[str, np.ndarray] | None = None) -> dict:
    """Dynamic force analysis of a described mechanism at each input (degrees for a crank, the
    length for an actuator; 1-D array-like), as the module's docstring says.

    description: the [mechanism] table as parsed by tomllib, with its dynamics; params:
    {parameter symbol: value}, the input's speed and acceleration among them (omega_in and
    alpha_in, or v_in and a_in); length_unit: the template's (mm, cm, m, in, ft); turns: as
    the kinematic reference's (an expression reads each angle in the turn a book shows).

    Raises ValueError for a description it cannot analyse (a body entry naming no link, links
    that do not make a mechanism of one degree of freedom, ...)."""
    analysis = _Analysis(description, params, length_unit)
    return analysis.at(analysis.positions(params, angles_deg, turns), params)


def forces_and_at_rest(description: Mapping, params: Mapping[str, float], angles_deg,
                       length_unit: str = "m", turns: Mapping[str, np.ndarray] | None = None
                       ) -> tuple[dict, dict]:
    """forces() as given, and again with the input at rest (its speed and acceleration 0):
    the masses' and the loads' own scale (check/force_cells.py). Where no value the positions
    take reads the input's speed or acceleration (reference.reads_rates), the positions are
    solved once for both: only the rates, the loads and the equations are taken again (and
    only the condition numbers of rows whose matrix differs)."""
    analysis = _Analysis(description, params, length_unit)
    still = {**params, **dict.fromkeys(analysis.rates, 0.0)}
    solved = analysis.positions(params, angles_deg, turns)
    resting = (analysis.positions(still, angles_deg, turns)
               if reads_rates(analysis.described) else solved)
    return analysis.at(solved, params), analysis.at(resting, still)


class _Analysis:
    """One description's bodies and loads, read once, and its kinematic reference's
    positions taken on to the forces at some speed of the input."""

    def __init__(self, description: Mapping, params: Mapping[str, float], length_unit: str):
        if length_unit not in LENGTH_UNITS:
            raise ValueError(f"length_unit must be one of {sorted(LENGTH_UNITS)}")
        self.rates = _RATES[(description.get("input") or {}).get("kind", "angle")]
        if not all(name in params for name in self.rates):
            raise ValueError(f"force analysis needs the input's speed and acceleration: the "
                             f"parameters {self.rates[0]} and {self.rates[1]}")
        self.top = topology(description)
        self.loads = read_loads(description, self.top)
        self.described = self.loads.described()
        self.metres = LENGTH_UNITS[length_unit]
        self.conditions = Conditions()      # the moving system's, for the same one at rest

    def positions(self, params: Mapping[str, float], angles_deg, turns) -> Positions:
        return positions(self.described, params, angles_deg, turns)

    def at(self, solved: Positions, params: Mapping[str, float]) -> dict:
        """The forces on the solved positions, the input moving as `params` say."""
        rows = Rows(motion(solved, self.described, params, self.loads.values), solved.n,
                    self.metres)
        with np.errstate(invalid="ignore", divide="ignore"):
            system = equations(self.top, self.loads, rows)
            x, cond = solve_rows(system.A, system.b, system.errors, self.conditions)
            for r in system.reactions:  # a guide's couple is NaN where its force is (the book's)
                if r.couple is not None:
                    x[np.isnan(x[:, r.cols[0]]), r.couple] = np.nan
            return {**_report(self.top, system, x), "cond": cond}
