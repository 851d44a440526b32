"""The paper's fixed-step classical Runge–Kutta integration (4th order).

Reproduces the paper's method (section 3: RK4, Δt = 1e-4 s, Turbo Pascal) for
any force family of ``engine.forces``, and shows its discretisation error.
The state is (δ, δ̇) with m δ̈ = -F(δ, δ̇), δ(0) = 0, δ̇(0) = v0.

Read-off convention (the paper's, see docs/paper.md): the peak force, its time
and the maximum deflection are the largest grid samples, first touch included; the end of contact
is located inside the last step by cubic Hermite interpolation of δ(t) (or
linear interpolation of F(t) when a clamped force vanishes first), and the
exit velocity is the Hermite interpolant's slope there.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.forces import contact_force, pressure_ratio
from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS, N_CHARACTERISTICS, fill_characteristics

_JIT = dict(cache=CACHE, error_model="numpy")


@nb.njit(**_JIT)
def _acceleration(family, params, clamp, mass, deflection, rate):
    return -contact_force(family, params, deflection, rate, clamp) / mass


@nb.njit(**_JIT)
def rk4_step(family, params, clamp, mass, d, v, step):
    """One classical Runge–Kutta step of (δ, δ̇)' = (δ̇, -F/m)."""
    k1d = v
    k1v = _acceleration(family, params, clamp, mass, d, v)
    k2d = v + 0.5 * step * k1v
    k2v = _acceleration(family, params, clamp, mass, d + 0.5 * step * k1d, v + 0.5 * step * k1v)
    k3d = v + 0.5 * step * k2v
    k3v = _acceleration(family, params, clamp, mass, d + 0.5 * step * k2d, v + 0.5 * step * k2v)
    k4d = v + step * k3v
    k4v = _acceleration(family, params, clamp, mass, d + step * k3d, v + step * k3v)
    return (d + step / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d),
            v + step / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))


@nb.njit(**_JIT)
def rk4_advance(family, params, clamp, mass, d, v, step, n_steps):
    """State after ``n_steps`` RK4 steps from (δ, δ̇) (for convergence studies)."""
    for _ in range(n_steps):
        d, v = rk4_step(family, params, clamp, mass, d, v, step)
    return d, v


@nb.njit(**_JIT)
def _hermite_root(h, d0, v0, d1, v1):
    """θ in [0, 1] where the cubic Hermite interpolant of δ on one step vanishes
    (d0 > 0 ≥ d1), by bisection refined with Newton."""
    lo, hi = 0.0, 1.0
    theta = d0 / (d0 - d1) if d0 != d1 else 0.5
    for _ in range(60):
        t2 = theta * theta
        t3 = t2 * theta
        val = (2 * t3 - 3 * t2 + 1) * d0 + (t3 - 2 * t2 + theta) * h * v0 + (-2 * t3 + 3 * t2) * d1 + (t3 - t2) * h * v1
        der = ((6 * t2 - 6 * theta) * d0 + (3 * t2 - 4 * theta + 1) * h * v0 + (-6 * t2 + 6 * theta) * d1
               + (3 * t2 - 2 * theta) * h * v1)
        if val > 0.0:
            lo = theta
        else:
            hi = theta
        new = theta - val / der if der != 0.0 else 0.5 * (lo + hi)
        if not (lo < new < hi):
            new = 0.5 * (lo + hi)
        if abs(new - theta) < 1e-15:
            theta = new
            break
        theta = new
    t2 = theta * theta
    slope = ((6 * t2 - 6 * theta) * d0 + (3 * t2 - 4 * theta + 1) * h * v0 + (-6 * t2 + 6 * theta) * d1
             + (3 * t2 - 2 * theta) * h * v1) / h
    return theta, slope


@nb.njit(**_JIT)
def rk4_impact(family, params, clamp, mass, velocity, radius, step, max_steps, store,
               t_arr, d_arr, v_arr, f_arr, out):
    """Integrate one impact with classical RK4 at a fixed ``step`` [s].

    Fills ``out`` (CHARACTERISTIC_COLUMNS order) and, if ``store``, the grid
    samples in t_arr, d_arr, v_arr, f_arr (length ≥ max_steps + 1).
    Returns the number of grid points written (≥ 2), or -1 if contact did not
    end within ``max_steps`` steps."""
    d = 0.0
    v = velocity
    t = 0.0
    # the first grid sample is first touch: F(0, V), zero for the Hertz laws but b V for Kelvin–Voigt's dashpot,
    # whose peak may be there (t_c = 0)
    force = contact_force(family, params, 0.0, velocity, False)
    if clamp and not force > 0.0:
        force = 0.0
    peak_force = force
    time_to_peak = 0.0
    max_deflection = 0.0
    time_to_max = 0.0
    max_ratio = 0.0  # max of F/δ, for the Hertz pressure
    if store:
        t_arr[0] = 0.0
        d_arr[0] = 0.0
        v_arr[0] = velocity
        f_arr[0] = force
    for k in range(1, max_steps + 1):
        d_new, v_new = rk4_step(family, params, clamp, mass, d, v, step)
        t_new = k * step
        f_raw = contact_force(family, params, d_new, v_new, False)
        ended = d_new <= 0.0 or (clamp and f_raw <= 0.0 and v_new < 0.0)
        if ended:
            if d_new <= 0.0:
                theta, exit_rate = _hermite_root(step, d, v, d_new, v_new)
            else:  # clamped force vanished while δ > 0: linear interpolation of F
                theta = force / (force - f_raw) if force != f_raw else 1.0
                exit_rate = v + theta * (v_new - v)
            duration = t + theta * step
            if store:
                t_arr[k] = duration
                d_arr[k] = max(d + theta * (d_new - d), 0.0) if d_new > 0.0 else 0.0
                v_arr[k] = exit_rate
                f_arr[k] = 0.0
            fill_characteristics(out, peak_force, time_to_peak, duration, max_deflection, time_to_max,
                                 -exit_rate, velocity, mass, pressure_ratio(family, params, max_ratio,
                                                                            max_deflection), radius)
            return k + 1
        d = d_new
        v = v_new
        t = t_new
        force = f_raw if (not clamp or f_raw > 0.0) else 0.0
        if store:
            t_arr[k] = t
            d_arr[k] = d
            v_arr[k] = v
            f_arr[k] = force
        if force > peak_force:
            peak_force = force
            time_to_peak = t
        if d > max_deflection:
            max_deflection = d
            time_to_max = t
        if force / d > max_ratio:
            max_ratio = force / d
    for j in range(out.shape[0]):
        out[j] = math.nan
    return -1


@nb.njit(parallel=True, **_JIT)
def rk4_batch(family, params, clamp, mass, velocity, radius, step, max_steps, out):
    """Characteristics of many impacts by RK4; row i uses params[i], etc."""
    dummy = np.empty(1)
    for i in nb.prange(mass.shape[0]):
        rk4_impact(family[i], params[i], clamp[i], mass[i], velocity[i], radius[i], step[i],
                   max_steps, False, dummy, dummy, dummy, dummy, out[i])


@nb.njit(**_JIT)
def rk4_batch_serial(family, params, clamp, mass, velocity, radius, step, max_steps, out):
    """``rk4_batch`` on one thread: for a few rows, where starting threads costs more than the work."""
    dummy = np.empty(1)
    for i in range(mass.shape[0]):
        rk4_impact(family[i], params[i], clamp[i], mass[i], velocity[i], radius[i], step[i],
                   max_steps, False, dummy, dummy, dummy, dummy, out[i])


__all__ = ["rk4_impact", "rk4_batch", "rk4_batch_serial", "CHARACTERISTIC_COLUMNS", "N_CHARACTERISTICS"]
