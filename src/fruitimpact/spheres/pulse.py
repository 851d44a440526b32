"""The sphere's impact in units of the impact: a Hunt–Crossley pulse depends on the restitution alone.

For F = K δ^1.5 (1 + c δ̇) (Hunt & Crossley 1975; the founding paper, "Theoretical aspects about
simulating the reaction to impact of apples on rigid plane surfaces", eq 5 with eq 6's damping) and a
body of mass m hitting at V, the scales δ* = (m V²/K)^(2/5), t* = δ*/V and F* = K δ*^1.5 make the
equation of motion x'' = −x^1.5 (1 + x_c x') with the single group x_c = c V, and x_c is fixed by the
restitution e (``engine.powerlaw.exact_x``).  Hence, with f(e) = F_max/F* and g(e) = T/t*:

    F_max = f(e) K^(2/5) m^(3/5) V^(6/5)          T = g(e) m^(2/5) K^(-2/5) V^(-1/5)

and a reading of an accelerometer inside the body (a_max = F_max/m, ΔV = (1 + e) V, T) gives the
dimensionless group

    Π = ΔV / (a_max T) = (1 + e) / (f(e) g(e)),

which depends on e alone: Π(1) = 2/((5/4)^(3/5) · 2.9432 (5/4)^(2/5)) = 0.5436 for the elastic Hertz pulse
(a half-sine gives 2/π = 0.637), and Π falls monotonically to 0 as e → 0 (checked when the table is
built).  The duration therefore decides e, and then V and K follow from ΔV and a_max.

f and g are tabulated once from the exact power-law engine (``engine.powerlaw``) on a grid uniform in
ln e and read by linear interpolation of ln f, ln g and Π in ln e (f and g grow as powers of 1/e as e → 0:
in ln e they are nearly straight); the table's own error (interpolation against the engine at the
midpoints) is measured when it is built, ``PulseTable.error``: 3e-7 relative, far below any reading's.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Lowest restitution tabulated: below it a "bounce" leaves the surface at under 0.5 % of its speed, and the
#: readings of such a dead impact fix nothing (the inversion reports it as not reproduced).
E_MIN = 0.005
#: Nodes of the table, uniform in ln e (interpolation error 3e-7; uniform in e it was 2e-4 near E_MIN).
NODES = 4001


@dataclass(frozen=True)
class PulseTable:
    """f(e) = F_max/F*, g(e) = T/t* and Π(e) = (1 + e)/(f g) on a grid uniform in ln e over [E_MIN, 1]
    (``log_e``, ``log_f``, ``log_g``, ``pi``).

    ``error``: the largest relative difference between the interpolated f, g and the engine at the
    midpoints of the grid (measured at build)."""

    log_e: np.ndarray
    log_f: np.ndarray
    log_g: np.ndarray
    pi: np.ndarray
    error: float

    def restitution(self, pi) -> np.ndarray:
        """e with Π(e) = ``pi`` (array); NaN outside [Π(E_MIN), Π(1)]."""
        pi = np.asarray(pi, dtype=float)
        e = np.exp(np.interp(pi, self.pi, self.log_e))
        return np.where((pi >= self.pi[0]) & (pi <= self.pi[-1]), e, np.nan)

    def force(self, e) -> np.ndarray:
        """f(e) = F_max/F* [-]."""
        return np.exp(np.interp(np.log(e), self.log_e, self.log_f))

    def duration(self, e) -> np.ndarray:
        """g(e) = T/t* [-]."""
        return np.exp(np.interp(np.log(e), self.log_e, self.log_g))

    def group(self, e) -> np.ndarray:
        """Π(e) = ΔV/(a_max T) [-]."""
        return np.interp(np.log(e), self.log_e, self.pi)


def _engine(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(f, g) of the unit impact m = K = V = 1 at restitutions ``e``, from the exact engine."""
    from fruitimpact.engine.codes import CONTACT_DURATION, PEAK_FORCE
    from fruitimpact.engine.powerlaw import exact_x, powerlaw_characteristics

    ones = np.ones_like(e)
    out = powerlaw_characteristics(ones, ones, exact_x(e), ones, ones, tabulated=False)
    return out[:, PEAK_FORCE], out[:, CONTACT_DURATION]


@functools.cache
def pulse_table() -> PulseTable:
    """The table, built once (about 10 ms)."""
    log_e = np.linspace(math.log(E_MIN), 0.0, NODES)
    e = np.exp(log_e)
    f, g = _engine(e)
    pi = (1.0 + e) / (f * g)
    if not np.all(np.diff(pi) > 0.0):  # the inversion rests on it
        raise RuntimeError("Π(e) of the Hunt–Crossley pulse is not monotone on the table's grid")
    table = PulseTable(log_e, np.log(f), np.log(g), pi, 0.0)
    middle = np.exp(0.5 * (log_e[1:] + log_e[:-1]))
    f_mid, g_mid = _engine(middle)
    error = float(max(np.max(np.abs(table.force(middle) / f_mid - 1.0)),
                      np.max(np.abs(table.duration(middle) / g_mid - 1.0))))
    return PulseTable(log_e, table.log_f, table.log_g, pi, error)


def peak_force(e, mass, stiffness, velocity):
    """F_max [N] of the Hunt–Crossley impact of a body of ``mass`` [kg] at ``velocity`` [m/s] on a contact of
    Hertz ``stiffness`` K [N/m^1.5] with restitution ``e``."""
    return pulse_table().force(e) * np.power(stiffness, 0.4) * np.power(mass, 0.6) * np.power(velocity, 1.2)


def contact_duration(e, mass, stiffness, velocity):
    """T [s] of the same impact."""
    return pulse_table().duration(e) * np.power(mass, 0.4) * np.power(stiffness, -0.4) * np.power(velocity, -0.2)


def stiffness_from_peak(e, mass, velocity, force):
    """K [N/m^1.5] whose impact at ``velocity`` with restitution ``e`` peaks at ``force`` [N]:
    K = (F_max / (f(e) m^(3/5) V^(6/5)))^(5/2)."""
    return np.power(force / (pulse_table().force(e) * np.power(mass, 0.6) * np.power(velocity, 1.2)), 2.5)


__all__ = ["E_MIN", "PulseTable", "contact_duration", "peak_force", "pulse_table",
           "stiffness_from_peak"]
