"""`triad` — a class-III group: a ternary link with joints at three points, each held by a binary
link to a known point, placed all at once (group.solve_group).

The six unknowns (each joint's x and y) meet six distances: the three binary links' lengths and
the ternary link's three sides, solved by Newton together, continued from row to row from the
template's sketch; the ternary link keeps the turning sense its joints have in the sketch.
Columns measured on the solved points: each binary link's angle, the ternary link's angle (its
first side), the joints' x and y; and the determinant of the book's 2×2 system in the first
binary link's angle and the ternary's, as a quantity of the points (docs/coupled-loops.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..expressions import scalar
from .triad_iterations import (DEFAULT_ITERATIONS, book_method, converged, other_assembly,
                               ternary_frame)
from ..group import Bar, Turn, residuals, solve_group
from ..newton import newton
from ..positions import Positions
from ..rates import Rates
from ..step_type import StepType, Topology
from ..taylor import implicit

def _triple(solver: Positions, step: Mapping, field: str) -> list:
    value = step.get(field)
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise ValueError(f"{solver.where}.{field} must hold three entries")
    return list(value)


def read(solver: Positions, step: Mapping):
    """The step's points, pivots (as known points), lengths, sides and sketch (x, y, ...)."""
    names = [str(n) for n in _triple(solver, step, "points")]
    pivots = _triple(solver, step, "pivots")
    for p in pivots:
        if not isinstance(p, str) or p not in solver.points:
            raise ValueError(f"{solver.where}.pivots: {p!r} is not a known point")
    lengths = [scalar(e, solver.params) for e in _triple(solver, step, "lengths")]
    sides = [scalar(e, solver.params) for e in _triple(solver, step, "sides")]
    sketch = []
    for pair in _triple(solver, step, "sketch"):
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise ValueError(f"{solver.where}.sketch must be three [x, y] pairs")
        sketch += [scalar(e, solver.params) for e in pair]
    return names, pivots, lengths, sides, sketch


def sense(sketch: list[float]) -> float:
    """The turning sense of the ternary link's joints in the sketch: 1 counter-clockwise."""
    (x0, y0, x1, y1, x2, y2) = sketch
    return 1.0 if (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0) > 0.0 else -1.0


def bars(solver: Positions, pivots, lengths, sides) -> list[Bar]:
    """The six distances: pivot k to joint k, then the ternary's sides 0–1, 1–2, 2–0."""
    return [Bar(solver.points[p], k, length) for k, (p, length) in enumerate(zip(pivots, lengths))] \
        + [Bar(k, (k + 1) % 3, side) for k, side in enumerate(sides)]


def cross(ux, uy, vx, vy):
    return ux * vy - uy * vx


def determinant(joints, pivots_xy, b: float, c: float):
    """J11·J22 − J12·J21 of the book's system in (angle of the first binary link, angle of the
    ternary's first side) with residuals (|E − B|² − b²)/2b and (|F − C|² − c²)/2c: J11 =
    (D − A)×(E − B)/b, J12 = (E − D)×(E − B)/b, J21 = (D − A)×(F − C)/c, J22 =
    (F − D)×(F − C)/c; zero exactly where the group is at a dead centre."""
    (dx, dy), (ex, ey), (fx, fy) = joints
    (ax, ay), (bx, by), (cx, cy) = pivots_xy
    j11 = cross(dx - ax, dy - ay, ex - bx, ey - by)
    j12 = cross(ex - dx, ey - dy, ex - bx, ey - by)
    j21 = cross(dx - ax, dy - ay, fx - cx, fy - cy)
    j22 = cross(fx - dx, fy - dy, fx - cx, fy - cy)
    return (j11 * j22 - j12 * j21) / (b * c)


def place(solver: Positions, step: Mapping) -> None:
    """The three joints on every row, by Newton on the six distances together."""
    names, pivots, lengths, sides, sketch = read(solver, step)
    if min(lengths + sides) <= 0.0:
        raise ValueError(f"{solver.where}: lengths and sides must be positive")
    distances = bars(solver, pivots, lengths, sides)
    joints = solve_group(solver.n, 3, distances, sketch,
                         [Turn(0, 1, 2, sense(sketch))], solver.size, solver.tol_f)
    moving = solver.moves(*pivots)
    turning = sense(sketch)
    frame = ternary_frame(sides, turning)
    solver.put(f"gamma_{names[0]}", turning * abs(math.atan2(frame[1], frame[0])), True)
    count = step.get("iterations", DEFAULT_ITERATIONS)
    at = [solver.points[p] for p in pivots]
    joints = _as_the_book_reaches(solver, names[0], count, joints, distances, at, frame,
                                  sketch)
    iterations, joints = converged(names[0], count, joints, at, lengths, sides, frame, sketch,
                                   solver.turns)
    for key, value in iterations.items():
        solver.put(key, value, False)
    angles = {}
    for name, pivot, (x, y) in zip(names, pivots, joints):
        px, py = solver.points[pivot]
        angles[name] = solver.column(step, f"theta_{name}", f"theta_{name}",
                                     np.arctan2(y - py, x - px), moving)
    (x0, y0), (x1, y1) = joints[0], joints[1]
    first = f"{names[0]}{names[1]}"
    ternary = solver.column(step, f"theta_{first}", f"theta_{first}",
                            np.arctan2(y1 - y0, x1 - x0), moving)
    keys = {}
    for name, (x, y) in zip(names, joints):
        keys[name] = {"x": solver.column(step, f"x{name}", f"x{name}", x, moving),
                      "y": solver.column(step, f"y{name}", f"y{name}", y, moving)}
    for name in names:
        solver.new_point({"point": name}, keys[name], moving, loop=True)
    for name, pivot, length in zip(names, pivots, lengths):
        solver.add_link(pivot, name, solver.out[angles[name]], angles[name], length)
    for k, side in enumerate(sides):
        a, b = names[k], names[(k + 1) % 3]
        (ax, ay), (bx, by) = joints[k], joints[(k + 1) % 3]
        solver.add_link(a, b, np.arctan2(by - ay, bx - ax), ternary if k == 0 else None, side)


def _as_the_book_reaches(solver: Positions, n: str, count: int, joints, distances, at, frame,
                         sketch) -> list:
    """The joints, on the rows where the book's method (triad_iterations.book_method: Newton in
    two angles from the row above or the sketch) reaches another assembly than the
    continuation, in the book's assembly, made the reference's own by Newton on the six
    distances from there; those rows are noted under `other_assembly` (verify names them: the
    book and the reference chose different assemblies, neither is judged the right one)."""
    lengths, sides = [b.length for b in distances[:3]], [b.length for b in distances[3:]]
    phi, theta = book_method(count, solver.n, at, lengths, sides, frame, sketch, joints)
    other = other_assembly(phi, theta, joints, at)
    solver.out.setdefault("other_assembly", {})[n] = other
    if not other.any():
        return joints
    z = np.array([c for x, y in joints for c in (x, y)], dtype=float).T     # rows × 6
    for row in np.flatnonzero(other):
        d = (at[0][0][row] + lengths[0] * math.cos(phi[row]),
             at[0][1][row] + lengths[0] * math.sin(phi[row]))
        c, s = math.cos(theta[row]), math.sin(theta[row])
        guess = [d[0], d[1], d[0] + sides[0] * c, d[1] + sides[0] * s,
                 d[0] + frame[0] * c - frame[1] * s, d[1] + frame[0] * s + frame[1] * c]
        root = newton(residuals(distances, row, 3), guess, [solver.size] * 6, solver.tol_f)
        z[row] = root if root is not None else math.nan
    return [(z[:, 2 * k], z[:, 2 * k + 1]) for k in range(3)]


def rates(motion: Rates, step: Mapping) -> None:
    """The joints' rates by implicit differentiation of the six distances; the angles'
    rates measured on the moving points."""
    names, pivots = list(step["points"]), list(step["pivots"])
    lengths = [scalar(e, motion.s.params) for e in step["lengths"]]
    sides = [scalar(e, motion.s.params) for e in step["sides"]]
    z0 = [c for name in names for c in motion.s.points[name]]

    def residuals(z, pts):
        out = []
        for k, (pivot, length) in enumerate(zip(pivots, lengths)):
            px, py = pts[pivot]
            dx, dy = z[2 * k] - px, z[2 * k + 1] - py
            out.append(dx * dx + dy * dy - length * length)
        for k, side in enumerate(sides):
            m = (k + 1) % 3
            dx, dy = z[2 * k] - z[2 * m], z[2 * k + 1] - z[2 * m + 1]
            out.append(dx * dx + dy * dy - side * side)
        return out

    z, dead, sine = implicit(residuals, z0, motion.points, motion.still())
    motion.dead |= dead & np.isfinite(z0[0])
    motion.note_sine(sine)
    for k, name in enumerate(names):
        motion.place(name, z[2 * k], z[2 * k + 1])
    for name, pivot in zip(names, pivots):
        motion.put_rates(motion.key(step, f"theta_{name}", f"theta_{name}"),
                         motion.angle(pivot, name), True)
    first = f"{names[0]}{names[1]}"
    motion.put_rates(motion.key(step, f"theta_{first}", f"theta_{first}"),
                     motion.angle(names[0], names[1]), True)
    joints = [(motion.points[n][0].a, motion.points[n][1].a) for n in names]
    at = [(motion.points[p][0].a, motion.points[p][1].a) for p in pivots]
    motion.out[f"det_{names[0]}"] = determinant(joints, at, lengths[1], lengths[2])


def topology(step: Mapping, length_input: str | None) -> Topology:
    """Three binary links, pivot to joint, and the ternary link through the three joints; each
    binary link's force on the ternary is also resolved along the link and across it (the
    book's unknowns, docs/coupled-loops.md)."""
    names, pivots = [str(n) for n in step["points"]], [str(p) for p in step["pivots"]]
    return Topology(links=tuple(zip(pivots, names)) + (tuple(names),),
                    struts=tuple((p, n, tuple(names)) for p, n in zip(pivots, names)))


STEP = StepType(place=place, rates=rates, length_fields=("lengths", "sides"),
                topology=topology)
