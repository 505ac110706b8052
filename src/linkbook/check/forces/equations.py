"""The force reference's equations: 3 per moving body (ΣF = m·a_G, ΣM = I_G·α in d'Alembert's
form), all bodies at once, with the reactions as unknowns, solved row by row
(check/forces/__init__.py says how).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .loads import Loads, Rows, cross
from .topology import GROUND, Topology, host, number_of, pins

SINGULAR = 1e12       # a row's system with a larger condition number has no reliable solution


@dataclass
class _Reaction:
    """An unknown force of body i on body j at a point: a pin's, its x and y unknown (cols),
    or a guide's or a slot's, N along a unit normal (one col), with a guide's couple M."""
    i: int
    j: int
    point: str
    key: str                                    # F{i}{j}
    cols: tuple[int, ...]
    normal: tuple[np.ndarray, np.ndarray] | None = None
    couple: int | None = None


class System:
    """A·x = b per row: for each moving body its ΣFx, ΣFy and ΣM about its first joint O:
    Σ(unknown loads) = m·a_G − Σ(known loads), the moment with I·α + (G − O)×m·a_G."""

    def __init__(self, top: Topology, rows: Rows):
        self.rows = rows
        self.k = 3 * len(top.bodies)
        self.first = {b.number: 3 * i for i, b in enumerate(top.bodies)}
        self.origin = {b.number: rows.position(b.joints[0]) for b in top.bodies}
        self.A = np.zeros((rows.n, self.k, self.k))
        self.b = np.zeros((rows.n, self.k))
        # where a value of the description (a load, a mass) is an error: its equations' b
        self.errors = np.zeros((rows.n, self.k), dtype=bool)
        self.names: list[str] = []
        self.reactions: list[_Reaction] = []
        self.effort = ""                # the input's unknown: T12 or F_in

    def unknown(self, name: str) -> int:
        self.names.append(name)
        return len(self.names) - 1

    def force(self, body: int, col: int, ux, uy, point: str, sign: float = 1.0) -> None:
        """Unknown col times the direction (ux, uy) acts on body at point."""
        if body == GROUND:
            return
        r, (ox, oy) = self.first[body], self.origin[body]
        px, py = self.rows.position(point)
        self.A[:, r, col] += sign * ux
        self.A[:, r + 1, col] += sign * uy
        self.A[:, r + 2, col] += sign * cross(px - ox, py - oy, ux, uy)

    def couple(self, body: int, col: int, sign: float = 1.0) -> None:
        """Unknown col is a couple on body."""
        if body != GROUND:
            self.A[:, self.first[body] + 2, col] += sign

    def pin(self, i: int, j: int, point: str, key: str) -> None:
        """The force of body i on body j at the pin joining them, its x and y unknown, and
        its reaction on i."""
        cols = self.unknown(key + "x"), self.unknown(key + "y")
        for col, ux, uy in ((cols[0], 1.0, 0.0), (cols[1], 0.0, 1.0)):
            self.force(j, col, ux, uy, point)
            self.force(i, col, ux, uy, point, -1.0)
        self._add(_Reaction(i, j, point, key, cols))

    def across(self, i: int, j: int, point: str, tail: str, normal, couple: bool) -> None:
        """A guide's (couple = True) or a slot's force of body i on body j at its point, N
        along the unit normal (nx, ny); and its reaction on i."""
        col = self.unknown("N" + tail)
        self.force(j, col, *normal, point)
        self.force(i, col, *normal, point, -1.0)
        moment = None
        if couple:
            moment = self.unknown("M" + tail)
            self.couple(j, moment)
            self.couple(i, moment, -1.0)
        self._add(_Reaction(i, j, point, "F" + tail, (col,), normal, moment))

    def _add(self, reaction: _Reaction) -> None:
        if any(r.key == reaction.key for r in self.reactions):
            raise ValueError(f"two joints between the bodies {reaction.i} and {reaction.j} "
                             f"(at {reaction.point} and another): one key {reaction.key}")
        self.reactions.append(reaction)

    def known_force(self, body: int, fx, fy, px, py) -> None:
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] -= fx
        self.b[:, r + 1] -= fy
        self.b[:, r + 2] -= cross(px - ox, py - oy, fx, fy)

    def note_errors(self, body: int, value, equations: tuple[int, ...] = (0, 1, 2)) -> None:
        """The equations of a body that a value of the description enters, where it is an
        error (NaN): those rows' unknowns it reaches are NaN, the others stand."""
        for e in equations:
            self.errors[:, self.first[body] + e] |= np.isnan(value)

    def known_couple(self, body: int, torque) -> None:
        self.b[:, self.first[body] + 2] -= torque

    def inertia(self, body: int, mass, gx, gy, ax, ay) -> None:
        """m·a_G on the right: ΣF = m·a_G, ΣM_O = (G − O)×m·a_G (+ I·α, a known_couple)."""
        r, (ox, oy) = self.first[body], self.origin[body]
        self.b[:, r] += mass * ax
        self.b[:, r + 1] += mass * ay
        self.b[:, r + 2] += cross(gx - ox, gy - oy, mass * ax, mass * ay)


def equations(top: Topology, loads: Loads, rows: Rows) -> System:
    system = System(top, rows)
    for i, body, point in pins(top):
        system.pin(i, body.number, point, "F" + top.pair(i, body.number))
    for pair in top.pairs:           # a guide: across its line and a couple; a slot: across it
        j = pair.block.number
        sides = [(pair.guide, "line", True)] + [(pair.slotted, "slot", False)] * bool(pair.slot)
        for other, which, couple in sides:
            c, s = rows.direction(loads.lines[j, which])
            i = number_of(other)
            system.across(i, j, pair.point, top.pair(i, j), (-s, c), couple)
    _input_equations(top, system, rows)
    _load_equations(top, loads, rows, system)
    return system


def actuator_line(top: Topology, rows: Rows) -> tuple[np.ndarray, np.ndarray]:
    """The unit vector from the actuator's end P to its end R."""
    (px, py), (rx, ry) = (rows.position(p) for p in top.actuator)
    length = np.hypot(rx - px, ry - py)
    return (rx - px) / length, (ry - py) / length


def _input_equations(top: Topology, system: System, rows: Rows) -> None:
    if top.crank is not None:
        system.effort = "T" + top.pair(GROUND, top.crank.number)
        system.couple(top.crank.number, system.unknown(system.effort))
    elif top.actuator is not None:
        (p, r), col = top.actuator, system.unknown("F_in")
        system.effort = "F_in"
        ux, uy = actuator_line(top, rows)
        system.force(host(top, r).number, col, ux, uy, r)
        if p not in top.fixed:
            system.force(host(top, p).number, col, ux, uy, p, -1.0)
    else:
        raise ValueError("mechanism.input: neither a crank step nor a linear actuator")


def _load_equations(top: Topology, loads: Loads, rows: Rows, system: System) -> None:
    g = rows.vector(loads.gravity) if loads.gravity else (0.0, 0.0)
    for body in top.bodies:
        mass, inertia = (rows.array(k) for k in loads.masses[body.number])
        system.note_errors(body.number, mass)
        system.note_errors(body.number, inertia, (2,))
        system.known_couple(body.number, -inertia * rows.angular_acceleration(body))
        if body.centre is not None:
            (gx, gy), (ax, ay) = rows.position(body.centre), rows.rate("a", body.centre)
            system.inertia(body.number, mass, gx, gy, ax, ay)
            system.known_force(body.number, mass * g[0], mass * g[1], gx, gy)
    for body, point, spec in loads.forces:
        fx, fy = rows.vector(spec)
        system.known_force(body.number, fx, fy, *rows.position(point))
        system.note_errors(body.number, fx + fy)
    for body, key in loads.torques:
        system.known_couple(body.number, rows.array(key))
        system.note_errors(body.number, rows.array(key), (2,))


class Conditions:
    """Each row's condition number of the scaled matrices solve_rows met last, kept for the
    next system solved: the forces at rest (forces_and_at_rest) have the moving ones' matrix
    on every row (the positions' alone), and its condition number, an SVD per row, is most of
    solve_rows' work. A row's number is reused only where its matrix is the same to the bit."""

    def __init__(self):
        self.A: np.ndarray | None = None
        self.cond = np.zeros(0)

    def __call__(self, A: np.ndarray) -> np.ndarray:
        if self.A is None or self.A.shape != A.shape:
            cond = np.linalg.cond(A) if len(A) else np.zeros(0)
        else:
            same = (A.view(np.uint64) == self.A.view(np.uint64)).all(axis=(1, 2))
            cond = self.cond.copy()
            if not same.all():
                cond[~same] = np.linalg.cond(A[~same])
        self.A, self.cond = A, cond
        return cond


def solve_rows(A: np.ndarray, b: np.ndarray, errors: np.ndarray,
               conditions: Conditions | None = None) -> tuple[np.ndarray, np.ndarray]:
    """x with A·x = b on every row, and each row's condition number. Rows and columns are
    scaled by their largest entries first (forces and moments, metres and ones); a row with a
    NaN or a condition number above SINGULAR is NaN, but for a NaN in b where a value of the
    description is an error (`errors`): that makes NaN only the unknowns it reaches
    (_reaches). `conditions`: the condition numbers of an earlier system, where it had
    the same matrix."""
    n, k = b.shape
    finite = np.isfinite(A).all(axis=(1, 2)) & (np.isfinite(b) | errors).all(axis=1)
    missing = ~np.isfinite(b) & finite[:, None]
    A = np.where(finite[:, None, None], A, np.eye(k))
    big = np.maximum(np.abs(A).max(axis=2), np.finfo(float).tiny)
    A, b = A / big[..., None], np.where(finite[:, None] & ~missing, b, 0.0) / big
    col = np.maximum(np.abs(A).max(axis=1, keepdims=True), np.finfo(float).tiny)
    A = A / col
    cond = (conditions or Conditions())(A)
    ok = finite & (cond < SINGULAR)
    structure = (A[ok] != 0).any(axis=0)
    A = np.where(ok[:, None, None], A, np.eye(k))
    y = np.linalg.solve(A, np.where(ok[:, None], b, 0.0)[..., None])[..., 0]
    x = y / col[:, 0, :]
    x[~ok] = np.nan
    x[(missing & ok[:, None]).astype(float) @ _reaches(structure).T > 0] = np.nan
    return x, np.where(finite, cond, np.nan)


def _reaches(structure: np.ndarray) -> np.ndarray:
    """Which unknowns each equation's known side reaches: x_i depends on b_j where (A⁻¹)_ij
    is not zero for a matrix of the system's structure (its entries that are not zero on some
    row) with generic values. A term that is zero on one row only (a moment arm where a crank
    lies on the line) still counts: the book's formula reads that load there too."""
    # values in [1, 2) with no relation between them (multiples of the golden ratio, whole
    # turns dropped; numpy.random stays unimported, as verify's start-up wants it)
    spread = (np.arange(1, structure.size + 1) * 0.6180339887498949 % 1.0 + 1.0)
    generic = np.where(structure, np.sqrt(spread).reshape(structure.shape), 0.0)
    try:
        inverse = np.abs(np.linalg.inv(generic))
    except np.linalg.LinAlgError:      # no row solves: nothing to spare
        return np.ones(structure.shape, dtype=bool)
    return inverse > 1e-9 * inverse.max()
