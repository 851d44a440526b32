"""Independent reference integrations with SciPy (test-only).

A tight DOP853 integration (rtol 1e-12) with terminal events, and dense-output
root finding for the peak force (dF/dt = 0) and the maximum deflection
(δ̇ = 0).  Shares no code with the package's engine.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def reference_powerlaw(mass, stiffness, damping_factor, velocity, exponent=1.5):
    """Characteristics of m δ̈ = -K δ^n (1 + c δ̇) by solve_ivp, plus the work of
    the damping force W_d = ∫ c K δ^n δ̇² dt integrated alongside."""
    k, c, n, m = stiffness, damping_factor, exponent, mass

    def rhs(t, y):
        d, v, _ = y
        d = max(d, 0.0)
        elastic = k * d ** n
        return [v, -(elastic * (1.0 + c * v)) / m, elastic * c * v * v]

    def separation(t, y):
        return y[0] if t > 0 else 1.0

    separation.terminal = True
    separation.direction = -1
    t_end = 50.0 * ((1.25 * m * velocity ** 2 / k) ** 0.4) / velocity
    sol = solve_ivp(rhs, [0.0, t_end], [0.0, velocity, 0.0], method="DOP853", rtol=1e-12,
                    atol=[1e-16, 1e-14, 1e-16], events=separation, dense_output=True)
    duration = float(sol.t_events[0][0])
    exit_rate = float(sol.y_events[0][0][1])
    work = float(sol.y_events[0][0][2])

    def force_rate(t):  # dF/dt = K n δ^(n-1) δ̇ (1 + c δ̇) + K δ^n c δ̈
        d, v, _ = sol.sol(t)
        d = max(d, 1e-300)
        acc = -k * d ** n * (1.0 + c * v) / m
        return k * n * d ** (n - 1.0) * v * (1.0 + c * v) + k * d ** n * c * acc

    t_max = brentq(lambda t: sol.sol(t)[1], 1e-3 * duration, duration * 0.999, xtol=1e-15, rtol=1e-14)
    t_peak = brentq(force_rate, 1e-4 * duration, t_max * (1 + 1e-9) + 1e-15, xtol=1e-15, rtol=1e-14) \
        if c > 0 else t_max
    d_peak, v_peak, _ = sol.sol(t_peak)
    return dict(
        peak_force=k * d_peak ** n * (1.0 + c * v_peak),
        time_to_peak=t_peak,
        contact_duration=duration,
        max_deflection=float(sol.sol(t_max)[0]),
        time_to_max_deflection=t_max,
        restitution=-exit_rate / velocity,
        damping_work=work,
        solution=sol,
    )


def state_at(sol, times):
    """(δ, δ̇) of a reference solution at ``times``."""
    y = sol.sol(np.asarray(times))
    return y[0], y[1]
