"""Solvers behind one interface: ``accurate`` (exact) and ``rk4`` (the paper's).

A solver turns rows of resolved contact laws (stiffness, damping factor),
masses, impact velocities and effective radii into the characteristics
(``engine.powerlaw.CHARACTERISTIC_COLUMNS``), and one impact into curves.
Each solver states the accuracy it promises (``tolerance``) and whether its
results are checked against the accurate solver (``checked``), which
``status.judge`` enforces.  Failures come back as NaN rows, never as an
exception in the middle of a sweep.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fruitimpact.engine.codes import N_CHARACTERISTICS

# The compiled engine is imported inside the functions that run it: the registry
# (and the command line's --help) must not start numba.

#: Safety limit on RK4 steps for one impact.
RK4_MAX_STEPS = 2_000_000
#: Fewest RK4 steps per contact accepted (the step may be at most T_Hertz / this).
RK4_MIN_STEPS_PER_CONTACT = 20
#: The refusal of a step finer than ``RK4_MAX_STEPS`` steps over the undamped Hertz duration, a lower bound of T:
#: such a contact cannot end within the steps allowed (it ran every row to the limit, and failed each).
RK4_FINE_STEP_REFUSAL = (f"step must be at least 1/{RK4_MAX_STEPS:,} of the contact duration for rk4 (at most "
                         f"{RK4_MAX_STEPS:,} steps per contact)")
#: The refusal of a step coarser than ``max_rk4_step`` (a row's message; a run refused whole starts with it).
RK4_STEP_REFUSAL = (f"step must be at most 1/{RK4_MIN_STEPS_PER_CONTACT} of the contact duration for rk4 (at least "
                    f"{RK4_MIN_STEPS_PER_CONTACT} steps per contact)")
#: Relative tolerance of the compiled adaptive integrator (laws without a first integral).
ADAPTIVE_RTOL = 1e-10


def max_rk4_step(mass, stiffness, velocity):
    """Coarsest accepted RK4 step [s]: 1/20 of the undamped Hertz contact duration,
    a lower bound of T for the laws here (damping lengthens the contact)."""
    from fruitimpact.physics.hertz import hertz_contact_duration

    with np.errstate(invalid="ignore", divide="ignore", over="ignore", under="ignore"):
        return hertz_contact_duration(mass, stiffness, velocity) / RK4_MIN_STEPS_PER_CONTACT


def power_law_closed_forms(stiffness, damping_factor, mass, velocity, exponent: float = 1.5):
    """(δ_max [m], e) from the first integral of F = K δ^n (1 + c δ̇), arrays:
    δ_max = [(n+1) m (x - ln(1+x)) / (K c²)]^(1/(n+1)), x = c v0, and e the root
    of (1 + x) = (1 - e x) exp((1 + e) x) (Hunt & Crossley 1975; docs/physics.md).
    A self-check beside the solvers' numbers, independent of their quadrature."""
    from fruitimpact.engine.powerlaw import exact_restitution, r_array

    stiffness, damping_factor, mass, velocity = (np.asarray(a, dtype=float) for a in
                                                 (stiffness, damping_factor, mass, velocity))
    x = damping_factor * velocity
    # (x - ln(1+x))/c² = v0² r(x), written through r to stay exact as c → 0
    r = r_array(x).reshape(x.shape)
    n = exponent
    max_deflection = ((n + 1.0) * mass * velocity ** 2 * r / stiffness) ** (1.0 / (n + 1.0))
    return max_deflection, exact_restitution(x)


def _accurate_batch(law, stiffness, damping_factor, mass, velocity, radius, step, tabulated=None):
    from fruitimpact.physics.calibrate import law_params
    from fruitimpact.engine.powerlaw import powerlaw_characteristics

    if law.force_family.first_integral:
        return powerlaw_characteristics(mass, stiffness, damping_factor, velocity, radius, tabulated=tabulated)
    from fruitimpact.engine.adaptive import adaptive_characteristics

    rows = len(mass)
    return adaptive_characteristics(np.full(rows, law.family), law_params(law.family, stiffness, damping_factor),
                                    np.full(rows, law.clamp), mass, velocity, radius, ADAPTIVE_RTOL)


def _rk4_batch(law, stiffness, damping_factor, mass, velocity, radius, step, tabulated=None):
    from fruitimpact.physics.calibrate import law_params
    from fruitimpact.engine.powerlaw import PARALLEL_MIN_ROWS
    from fruitimpact.engine.rk4 import rk4_batch, rk4_batch_serial

    rows = len(mass)
    out = np.empty((rows, N_CHARACTERISTICS))
    kernel = rk4_batch if rows > PARALLEL_MIN_ROWS // 20 else rk4_batch_serial
    kernel(np.full(rows, law.family, dtype=np.int64), law_params(law.family, stiffness, damping_factor),
           np.full(rows, law.clamp), np.ascontiguousarray(mass, dtype=float),
           np.ascontiguousarray(velocity, dtype=float), np.ascontiguousarray(radius, dtype=float),
           np.ascontiguousarray(np.broadcast_to(step, (rows,)), dtype=float), RK4_MAX_STEPS, out)
    return out


def _accurate_curves(law, stiffness, damping_factor, mass, velocity, step, times):
    """δ, δ̇, F of rows of impacts at ``times`` (rows, points): the exact phase curve, or
    the adaptive integrator's dense output."""
    from fruitimpact.physics.calibrate import law_params

    if law.force_family.first_integral:
        from fruitimpact.engine.powerlaw import powerlaw_curves_batch

        return powerlaw_curves_batch(mass, stiffness, damping_factor, velocity, times)
    from fruitimpact.engine.adaptive import adaptive_curves

    params = law_params(law.family, stiffness, damping_factor)
    out = [np.empty(times.shape) for _ in range(3)]
    for i in range(times.shape[0]):
        d, v, f, _ = adaptive_curves(law.family, params[i], law.clamp, mass[i], velocity[i], times[i])
        out[0][i], out[1][i], out[2][i] = d, v, f
    return tuple(out)


def _accurate_samples(law, stiffness, damping_factor, mass, velocity, step, points, duration):
    """(t, δ, δ̇, F) of one impact at ``points`` evenly spaced times over [0, T]."""
    times = np.linspace(0.0, duration, int(points))
    curves = _accurate_curves(law, *(np.atleast_1d(float(a)) for a in (stiffness, damping_factor, mass, velocity)),
                              step, times[None, :])
    return (times, *(c[0] for c in curves))


def _rk4_samples(law, stiffness, damping_factor, mass, velocity, step, points=None, duration=None):
    """The RK4 grid of one impact: (t, δ, δ̇, F), the last sample at the interpolated
    separation.  ``ValueError`` if the contact does not end within ``RK4_MAX_STEPS``."""
    from fruitimpact.physics.calibrate import law_params
    from fruitimpact.engine.rk4 import rk4_impact

    estimate = 40.0 * ((1.25 * mass * velocity ** 2 / stiffness) ** 0.4 / velocity) / step
    size = int(min(RK4_MAX_STEPS, max(estimate, 1000))) + 2
    arrays = [np.empty(size) for _ in range(4)]
    out = np.empty(N_CHARACTERISTICS)
    params = law_params(law.family, stiffness, damping_factor)
    count = rk4_impact(law.family, params, law.clamp, mass, velocity, 1.0, step, size - 2, True, *arrays, out)
    if count < 0:
        raise ValueError(f"rk4: the contact did not end within {size - 2} steps of {step:g} s")
    return tuple(a[:count].copy() for a in arrays)


def _rk4_curves(law, stiffness, damping_factor, mass, velocity, step, times):
    """δ, δ̇, F of rows of impacts at ``times`` (rows, points): cubic Hermite interpolation
    of each row's RK4 grid (δ with δ̇ as its slope, δ̇ with -F/m), and the law's force at
    the interpolated state; after separation the separation state with F = 0."""
    from fruitimpact.physics.calibrate import law_params
    from fruitimpact.engine.forces import contact_force

    step = np.broadcast_to(step, np.shape(mass))
    out = [np.empty(times.shape) for _ in range(3)]
    params = law_params(law.family, stiffness, damping_factor)
    for i in range(times.shape[0]):
        t, d, v, _ = _rk4_samples(law, stiffness[i], damping_factor[i], mass[i], velocity[i], step[i])
        accel = np.array([-contact_force(law.family, params[i], di, vi, law.clamp) / mass[i] for di, vi in zip(d, v)])
        clipped = np.clip(times[i], t[0], t[-1])
        index = np.clip(np.searchsorted(t, clipped, side="right") - 1, 0, len(t) - 2)
        h = t[index + 1] - t[index]
        s = np.where(h > 0, (clipped - t[index]) / np.where(h > 0, h, 1.0), 0.0)
        h00, h10 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s
        h01, h11 = -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
        deflection = np.maximum(h00 * d[index] + h10 * h * v[index] + h01 * d[index + 1] + h11 * h * v[index + 1], 0)
        rate = h00 * v[index] + h10 * h * accel[index] + h01 * v[index + 1] + h11 * h * accel[index + 1]
        force = np.array([contact_force(law.family, params[i], di, vi, law.clamp) for di, vi in zip(deflection, rate)])
        force[times[i] >= t[-1]] = 0.0
        out[0][i], out[1][i], out[2][i] = deflection, rate, force
    return tuple(out)


@dataclass(frozen=True)
class Solver:
    """A way to integrate impacts.

    batch(law, stiffness, damping_factor, mass, velocity, radius, step, tabulated) -> (rows, 12)
        characteristics of rows of one damping law (arrays; serial kernels for a few rows);
    curves(law, stiffness, damping_factor, mass, velocity, step, times) -> (δ, δ̇, F)
        rows of impacts (arrays) at ``times`` [s], shape (rows, points);
    samples(law, stiffness, damping_factor, mass, velocity, step, points, duration) -> (t, δ, δ̇, F)
        one impact on the solver's own grid (``points`` over [0, T], or the RK4 steps).
    tolerance : float
        The accuracy it promises: relative on F_max, T, δ_max and absolute on e.
    checked : bool
        Its results are compared with the accurate solver's (``status.judge``).
    """

    name: str
    description: str
    batch: Callable
    curves: Callable
    samples: Callable
    tolerance: float
    checked: bool = False


SOLVERS: dict[str, Solver] = {
    "accurate": Solver(
        name="accurate",
        description=("exact: characteristics from the first integral and Gauss-Jacobi quadrature of the "
                     "contact time, or compiled DOP853 with exact event location for the laws without a first "
                     "integral; curves by exact inversion of t(δ̇) or dense output (agrees with closed forms to "
                     "~1e-12)"),
        batch=_accurate_batch,
        curves=_accurate_curves,
        samples=_accurate_samples,
        tolerance=1e-8,
    ),
    "rk4": Solver(
        name="rk4",
        description=("the paper's method: classical Runge-Kutta at a fixed step; peaks are grid samples, the "
                     "end of contact is interpolated inside the last step; checked against the accurate solver "
                     "(1 % on e, T, δ_max and F_max; t_c is a grid sample, good to one step)"),
        batch=_rk4_batch,
        curves=_rk4_curves,
        samples=_rk4_samples,
        tolerance=1e-2,
        checked=True,
    ),
}


def get_solver(name: str) -> Solver:
    """The solver registered as ``name``; ValueError naming the choices otherwise."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise ValueError(f"method must be one of {', '.join(SOLVERS)}; got {name!r}") from None


__all__ = ["ADAPTIVE_RTOL", "RK4_MAX_STEPS", "RK4_MIN_STEPS_PER_CONTACT", "SOLVERS", "Solver", "power_law_closed_forms",
           "get_solver", "max_rk4_step", "RK4_MIN_STEPS_PER_CONTACT", "RK4_STEP_REFUSAL",
           "RK4_FINE_STEP_REFUSAL"]
