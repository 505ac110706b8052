"""Motion analysis: velocities and accelerations of a solved mechanism.

Rates walks the steps again, after Positions, in Taylor arithmetic (taylor.py): the input moves
at its given speed and acceleration, each step's own work is its step type's `rates`
(step_type.StepType), looked up by the step's `type`; a loop's unknowns are differentiated
implicitly through its constraints (taylor.implicit), so no closed form of the workbook's is
used.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .positions import Positions
from .taylor import Taylor, implicit, still, t_atan2

# The data format's names of the input's speed and acceleration parameters.
MOTION_PARAMS = {"angle": ("omega_in", "alpha_in"), "length": ("v_in", "a_in")}


class Rates:
    """Velocities and accelerations of a solved mechanism (a Positions after run())."""

    def __init__(self, solver: Positions, description: Mapping, speed: float, accel: float):
        self.s = solver
        self.description = description
        n = solver.n
        self.points: dict[str, tuple[Taylor, Taylor]] = {
            name: (Taylor(x), Taylor(y)) for name, (x, y) in solver.points.items()}
        values = solver.out[solver.input_key]
        self.input = Taylor(np.asarray(values, dtype=float), speed, accel)
        self.out: dict[str, np.ndarray] = {}
        self.dead = np.zeros(n, dtype=bool)     # rows at a dead centre of some loop
        # per row, the smallest sine between a loop's two constraint gradients (1 far from any
        # dead centre): rounding in any evaluation of the rates grows like 1/sine²
        self.sine = np.ones(n)

    def note_sine(self, sine) -> None:
        """Keep, per row, the smallest sine a loop reports (NaN rows do not count)."""
        sine = np.broadcast_to(np.asarray(sine, dtype=float), self.sine.shape)
        self.sine = np.fmin(self.sine, np.where(np.isfinite(sine), sine, 1.0))

    def run(self) -> dict:
        """Every step's rates in order, the trace point's speed and acceleration, and per row
        'dead_centre' and 'sine' (see note_sine)."""
        for k, step in enumerate(self.s.steps):
            self.where = f"steps[{k}]"
            rates = self.s.step_types[step["type"]].rates
            if rates is not None:
                rates(self, step)
        trace = self.description.get("trace")
        if isinstance(trace, str) and trace in self.points:
            x, y = self.points[trace]
            self.out[f"vmag_{trace}"] = np.hypot(x.b, y.b)
            self.out[f"amag_{trace}"] = np.hypot(x.c, y.c)
        out = {k: _column(v, self.s.n) for k, v in self.out.items()}
        out["dead_centre"] = self.dead
        out["sine"] = self.sine
        return out

    # -- what a step type's `rates` reads and writes
    def key(self, step: Mapping, col: str, default: str) -> str:
        """A column's key: the default, or the `key` the step's `columns` entry gives it."""
        spec = (step.get("columns") or {}).get(col)
        return str(spec.get("key") or default) if isinstance(spec, Mapping) else default

    def put_rates(self, key: str, value: Taylor, angle: bool) -> None:
        """The rates of column `key`: omega_/alpha_ for an angle, v_/acc_ for a length."""
        first, second = ("omega_", "alpha_") if angle else ("v_", "acc_")
        self.out[first + key] = value.b
        self.out[second + key] = value.c

    def place(self, name: str, x: Taylor, y: Taylor) -> None:
        """Point `name` in motion, and its velocity and acceleration columns."""
        self.points[name] = (x, y)
        self.out[f"vx_{name}"], self.out[f"vy_{name}"] = x.b, y.b
        self.out[f"ax_{name}"], self.out[f"ay_{name}"] = x.c, y.c

    def length(self, step: Mapping, field: str) -> Taylor | float:
        """A length of the description: the swept input where it is the input key itself."""
        if step[field] == self.s.input_key and not self.s.angle_input:
            return self.input
        return self.s.num(step, field)

    def still(self) -> dict:
        """The known points held still (the knowns of a Jacobian)."""
        return {name: (still(x), still(y)) for name, (x, y) in self.points.items()}

    def angle(self, a: str, b: str, pts=None) -> Taylor:
        """angle(A→B) in motion (of `pts`, by default the points as they move)."""
        (ax, ay), (bx, by) = (pts or self.points)[a], (pts or self.points)[b]
        return t_atan2(by - ay, bx - ax)

    def determinant(self, n: str, q: str, p: str) -> None:
        """(R − Q) × (R − P) of the solved points: zero where P, Q, R line up."""
        (rx, ry), (qx, qy), (px, py) = self.points[n], self.points[q], self.points[p]
        self.out[f"det_{n}"] = ((rx.a - qx.a) * (ry.a - py.a) - (ry.a - qy.a) * (rx.a - px.a))

    def circles(self, name: str, a: str, ra, b: str, rb) -> tuple[Taylor, Taylor]:
        """R with |R − A| = ra and |R − B| = rb (the solved R as the start)."""
        x0, y0 = self.s.points[name]

        def residuals(z, pts):
            (ax, ay), (bx, by) = pts[a], pts[b]
            ra_, rb_ = (r if not isinstance(r, Taylor) or pts is self.points else still(r)
                        for r in (ra, rb))
            return [(z[0] - ax) * (z[0] - ax) + (z[1] - ay) * (z[1] - ay) - ra_ * ra_,
                    (z[0] - bx) * (z[0] - bx) + (z[1] - by) * (z[1] - by) - rb_ * rb_]

        (x, y), dead, sine = implicit(residuals, [x0, y0], self.points, self.still())
        self.dead |= dead & np.isfinite(x0) & np.isfinite(y0)
        self.note_sine(sine)
        return x, y


def _column(value, n: int) -> np.ndarray:
    """A copy of `value` as a column of n floats (a constant repeated down it)."""
    value = np.asarray(value, dtype=float)
    return value.copy() if value.shape == (n,) else np.broadcast_to(value, (n,)).copy()
