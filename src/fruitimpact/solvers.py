"""Solvers behind one interface: ``accurate`` (exact) and ``rk4`` (the paper's).

Each solver turns a resolved force law, a mass, an impact velocity and an
effective radius into the characteristics (``engine.powerlaw.CHARACTERISTIC_COLUMNS``)
and into curves.  Failures come back as ``success = False`` with a message,
never as an exception in the middle of a sweep.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .engine import forces
from .engine.powerlaw import (N_CHARACTERISTICS, powerlaw_characteristics, powerlaw_curves, powerlaw_single,
                              r_func, restitution_of_x)
from .engine.rk4 import rk4_impact

#: Safety limit on RK4 steps for one impact.
RK4_MAX_STEPS = 2_000_000
#: Fewest RK4 steps per contact accepted (the step may be at most T_Hertz / this).
RK4_MIN_STEPS_PER_CONTACT = 20


def max_rk4_step(mass, stiffness, velocity):
    """Coarsest accepted RK4 step [s]: 1/20 of the undamped Hertz contact duration,
    a lower bound of T for the laws here (damping lengthens the contact)."""
    from .contact import hertz_contact_duration

    with np.errstate(invalid="ignore", divide="ignore"):
        return hertz_contact_duration(mass, stiffness, velocity) / RK4_MIN_STEPS_PER_CONTACT


def closed_forms(law, mass: float, velocity: float) -> tuple[float, float]:
    """(δ_max [m], e) from the first integral of F = K δ^n (1 + c δ̇):
    δ_max = [(n+1) m (x - ln(1+x)) / (K c²)]^(1/(n+1)), x = c v0, and e the root
    of (1 + x) = (1 - e x) exp((1 + e) x) (Hunt & Crossley 1975; docs/physics.md).
    NaN for other force families."""
    if law.family != forces.POWER_LAW:
        return math.nan, math.nan
    n = law.exponent
    x = law.damping_factor * velocity
    # (x - ln(1+x))/c² = v0² r(x), written through r to stay exact as c → 0
    max_deflection = ((n + 1.0) * mass * velocity ** 2 * r_func(x) / law.stiffness) ** (1.0 / (n + 1.0))
    return max_deflection, restitution_of_x(x)


#: Relative tolerance of the compiled adaptive integrator (laws without a first integral).
ADAPTIVE_RTOL = 1e-10


def _accurate_characteristics(law, mass, velocity, radius, step):
    if law.family == forces.POWER_LAW:
        values = powerlaw_single(mass, law.stiffness, law.exponent, law.damping_factor, velocity, radius)
    else:
        from .engine.adaptive import adaptive_impact

        values = np.empty(N_CHARACTERISTICS)
        if adaptive_impact(law.family, law.params(), law.clamp, mass, velocity, radius, ADAPTIVE_RTOL, values) < 0:
            return tuple(float(v) for v in values), False, "adaptive integrator did not reach separation"
    return _judge(values)


#: Characteristics that every completed impact has (peak force, duration, δ_max, e).
_ESSENTIAL = [0, 2, 3, 6]


def _judge(values):
    """(values, success, message): success needs the essential characteristics
    finite; a peak at first touch (a dashpot's force jump) leaves C and C*
    undefined, which is reported, not failed."""
    values = [float(v) for v in values]
    if not all(np.isfinite(values[i]) for i in _ESSENTIAL):
        return tuple(values), False, "solver produced non-finite characteristics"
    notes = []
    if values[1] == 0.0:
        notes.append("peak force at first touch (force jump of the dashpot): C and C* undefined")
    if np.isinf(values[10]):
        values[10] = math.nan
        notes.append("max_pressure undefined: the damping force does not vanish with δ at first touch, "
                     "so the Hertz pressure 3F/(2πRδ) is unbounded there")
    return tuple(values), True, "; ".join(notes) or "ok"


def _accurate_curves(law, mass, velocity, step, points):
    values, _, _ = _accurate_characteristics(law, mass, velocity, 1.0, step)
    times = np.linspace(0.0, values[2], int(points))
    if law.family == forces.POWER_LAW:
        deflection, rate, force, _ = powerlaw_curves(mass, law.stiffness, law.damping_factor, velocity,
                                                     times, law.exponent)
    else:
        from .engine.adaptive import adaptive_curves

        deflection, rate, force, _ = adaptive_curves(law.family, law.params(), law.clamp, mass, velocity, times)
    return times, deflection, rate, force


def _rk4_run(law, mass, velocity, radius, step, store):
    # the contact lasts a few Hertz times; the step limit only guards runaway input
    max_steps = RK4_MAX_STEPS
    size = max_steps + 2 if store else 1
    if store:
        estimate = 40.0 * ((1.25 * mass * velocity ** 2 / law.stiffness) ** 0.4 / velocity) / step
        size = int(min(max_steps, max(estimate, 1000))) + 2
        max_steps = size - 2
    arrays = [np.empty(size) for _ in range(4)]
    out = np.empty(N_CHARACTERISTICS)
    count = rk4_impact(law.family, law.params(), law.clamp, mass, velocity, radius, step,
                       max_steps, store, *arrays, out)
    return count, arrays, out


def _rk4_characteristics(law, mass, velocity, radius, step):
    count, _, out = _rk4_run(law, mass, velocity, radius, step, False)
    if count < 0:
        return tuple(out), False, f"rk4: contact did not end within {RK4_MAX_STEPS} steps of {step:g} s"
    return _judge(out)


def _rk4_curves(law, mass, velocity, step, points):
    count, (t, d, v, f), _ = _rk4_run(law, mass, velocity, 1.0, step, True)
    if count < 0:
        raise RuntimeError(f"rk4: contact did not end within the step limit at step {step:g} s")
    return t[:count].copy(), d[:count].copy(), v[:count].copy(), f[:count].copy()


def judge_batch(out: np.ndarray) -> np.ndarray:
    """Rows of a characteristics array that completed (as ``_judge``); an unbounded
    Hertz pressure at first touch is set to NaN in place."""
    out[np.isinf(out[:, 10]), 10] = np.nan
    return np.all(np.isfinite(out[:, _ESSENTIAL]), axis=1)


def _accurate_batch(family, clamp, stiffness, damping_factor, mass, velocity, radius, step, tabulated=None):
    if family == forces.POWER_LAW:
        return powerlaw_characteristics(mass, stiffness, damping_factor, velocity, radius, tabulated=tabulated)
    from .calibrate import law_params
    from .engine.adaptive import adaptive_characteristics

    rows = len(mass)
    return adaptive_characteristics(np.full(rows, family), law_params(family, stiffness, damping_factor),
                                    np.full(rows, clamp), mass, velocity, radius, ADAPTIVE_RTOL)


def _rk4_batch(family, clamp, stiffness, damping_factor, mass, velocity, radius, step, tabulated=None):
    from .calibrate import law_params
    from .engine.rk4 import rk4_batch

    rows = len(mass)
    out = np.empty((rows, N_CHARACTERISTICS))
    rk4_batch(np.full(rows, family, dtype=np.int64), law_params(family, stiffness, damping_factor),
              np.full(rows, clamp), mass, velocity, radius, np.broadcast_to(step, (rows,)).astype(float),
              RK4_MAX_STEPS, out)
    return out


@dataclass(frozen=True)
class Solver:
    """A way to integrate impacts, one or many.

    characteristics(law, mass, velocity, radius, step) -> (values, success, message)
    curves(law, mass, velocity, step, points) -> (t, δ, δ̇, F)
    batch(family, clamp, stiffness, damping_factor, mass, velocity, radius, step, tabulated) -> (rows, 12)
    """

    name: str
    description: str
    characteristics: Callable
    curves: Callable
    batch: Callable
    closed_forms: Callable = closed_forms


SOLVERS: dict[str, Solver] = {
    "accurate": Solver(
        name="accurate",
        description=("exact: characteristics from the first integral and Gauss-Jacobi quadrature of the "
                     "contact time; curves by exact inversion of t(δ̇) (agrees with closed forms to ~1e-12)"),
        characteristics=_accurate_characteristics,
        curves=_accurate_curves,
        batch=_accurate_batch,
    ),
    "rk4": Solver(
        name="rk4",
        description=("the paper's method: classical Runge-Kutta at a fixed step; peaks are grid samples, the "
                     "end of contact is interpolated inside the last step"),
        characteristics=_rk4_characteristics,
        curves=_rk4_curves,
        batch=_rk4_batch,
    ),
}


def get_solver(name: str) -> Solver:
    """The solver registered as ``name``; ValueError naming the choices otherwise."""
    try:
        return SOLVERS[name]
    except KeyError:
        raise ValueError(f"method must be one of {', '.join(SOLVERS)}; got {name!r}") from None
