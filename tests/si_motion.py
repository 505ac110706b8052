"""Positions, velocities and accelerations in SI units, from the independent kinematic
reference (linkbook.check.reference.solve): what the power-balance tests of the forces multiply
the efforts by (test_force_reference.py, test_forces_book.py); and the one closed form those
tests derive by hand, the in-line slider-crank's piston."""
from __future__ import annotations

import numpy as np


class SIMotion:
    """The motion of a solved mechanism's points, in metres (per s, per s²)."""

    def __init__(self, solved: dict, metres: float):
        self.s, self.unit, self.n = solved, metres, len(solved["assembled"])

    def point(self, name: str):
        """(position, velocity, acceleration) of a point; a ground point is still."""
        x, y = (np.broadcast_to(np.asarray(c, dtype=float), (self.n,)) * self.unit
                for c in self.s["points"][name])
        if f"vx_{name}" not in self.s:
            zero = np.zeros(self.n)
            return (x, y), (zero, zero), (zero, zero)
        return ((x, y), tuple(self.s[f"{k}_{name}"] * self.unit for k in ("vx", "vy")),
                tuple(self.s[f"{k}_{name}"] * self.unit for k in ("ax", "ay")))

    def spin(self, a: str, b: str):
        """ω and α of the direction a→b (a rigid link's, or a slotted link's from its pivot a
        to the pin b sliding in it): with r = b − a = |r| e^{iθ}, r × Δv = θ̇ r² and
        r × Δa = θ̈ r² + 2 (r·Δv) θ̇ (the last term zero where |r| is constant)."""
        (p, v, acc), (q, w, bcc) = self.point(a), self.point(b)
        rx, ry = q[0] - p[0], q[1] - p[1]
        dvx, dvy = w[0] - v[0], w[1] - v[1]
        r2 = rx * rx + ry * ry
        omega = (rx * dvy - ry * dvx) / r2
        return (omega, (rx * (bcc[1] - acc[1]) - ry * (bcc[0] - acc[0])
                        - 2.0 * (rx * dvx + ry * dvy) * omega) / r2)

    def carried(self, a: str, b: str, u, v):
        """The point at (u, v) metres in the frame a→b (u along it), moving with that link:
        its position, velocity and acceleration (v = v_A + ω k × r, a = a_A + α k × r − ω² r)
        and the link's ω and α."""
        (pa, va, aa), (pb, _, _) = self.point(a), self.point(b)
        theta = np.arctan2(pb[1] - pa[1], pb[0] - pa[0])
        rx = u * np.cos(theta) - v * np.sin(theta)
        ry = u * np.sin(theta) + v * np.cos(theta)
        w, al = self.spin(a, b)
        return ((pa[0] + rx, pa[1] + ry), (va[0] - w * ry, va[1] + w * rx),
                (aa[0] - al * ry - w * w * rx, aa[1] + al * rx - w * w * ry), w, al)


def inline_piston(r: float, l: float, w: float, th):
    """The piston's velocity and acceleration of an in-line slider-crank (crank r, rod l in
    metres, constant ω = w, crank angles th in radians): x = r cos θ + D, D = √(l² − r² sin²θ),
    differentiated once and twice."""
    d = np.sqrt(l ** 2 - r ** 2 * np.sin(th) ** 2)
    v = w * (-r * np.sin(th) - r ** 2 * np.sin(th) * np.cos(th) / d)
    a = w ** 2 * (-r * np.cos(th) - r ** 2 * np.cos(2 * th) / d
                  - r ** 4 * np.sin(th) ** 2 * np.cos(th) ** 2 / d ** 3)
    return v, a, d
