"""Exact engine for the power-law family F = K δ^n (1 + c δ̇).

Plain floats and arrays in, plain arrays out; no I/O, no units.

Method (derived in docs/physics.md, checked in tests/test_engine_powerlaw.py)
-------------------------------------------------------------------------------
Write the impact velocity v0, x = c·v0 and the Hertz scales
δ_H = ((n+1) m v0² / (2K))^(1/(n+1)) and t_H = δ_H / v0.  One integration of
m v dv/dδ = -F gives the phase curve (Hunt & Crossley 1975)

    (δ/δ_H)^(n+1) = 2 ΔΦ,   ΔΦ = r(x) - ζ² ρ(xζ),

in the variable ζ = ln(1 + x w)/x, w = δ̇/v0, with r(s) = (s - ln(1+s))/s²
and ρ(z) = (e^z - 1 - z)/z².  ζ runs from ζ1 = ln(1+x)/x at first touch,
through 0 at maximum deflection, to ζ0 < 0 at separation, where ΔΦ(ζ0) = 0.
In ζ the time element is free of the 1/(1 + x w) pole that makes the
velocity form stiff for heavy damping:

    dt = -(2 t_H/(n+1)) (2ΔΦ)^(-n/(n+1)) dζ,

so every characteristic time is an integral with one integrable endpoint
singularity (b - ζ)^(-n/(n+1)), done exactly by a Gauss–Jacobi rule.  The
peak force is where dF/dt = 0, which reduces to x (n+1) ΔΦ = n w; the peak
Hertz pressure 3F/(2π R δ) peaks where x (n+1) ΔΦ = (n-1) w.  Both are
single monotone roots, found by Newton's method from the side on which it
converges monotonically.  All of this is uniform in x, down to x = 0
(undamped Hertz impact, where ρ = r = 1/2).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.quadrature import gauss_jacobi

#: Gauss–Jacobi nodes per integral; the integrands' remaining factors are
#: analytic; 16 nodes already reach 1e-13 relative for e ≥ 0.05, 20 leave a margin (tests).
QUADRATURE_NODES = 20

from fruitimpact.engine.codes import (ABSORBED_ENERGY, CHARACTERISTIC_COLUMNS, COLUMN, CONTACT_DURATION, CONTACT_RADIUS,  # noqa: F401
                    EXIT_VELOCITY, FIRMNESS_C, FIRMNESS_C_STAR, MAX_DEFLECTION, MAX_PRESSURE, N_CHARACTERISTICS,
                    PEAK_FORCE, RESTITUTION, TIME_TO_MAX_DEFLECTION, TIME_TO_PEAK)

_JIT = dict(cache=CACHE, fastmath=False, error_model="numpy")


@nb.njit(cache=CACHE, error_model="numpy")
def fill_characteristics(out, peak_force, time_to_peak, duration, max_deflection, time_to_max,
                         exit_speed, velocity, mass, max_force_ratio, radius):
    """Write one impact's characteristics into ``out`` (CHARACTERISTIC_COLUMNS order)
    from what every solver measures: the peak force [N] and its time [s], the
    contact duration [s], δ_max [m] and its time [s], the rebound speed [m/s],
    and the largest F/δ [N/m] over the contact (for the Hertz pressure)."""
    out[PEAK_FORCE] = peak_force
    out[TIME_TO_PEAK] = time_to_peak
    out[CONTACT_DURATION] = duration
    out[MAX_DEFLECTION] = max_deflection
    out[TIME_TO_MAX_DEFLECTION] = time_to_max
    out[EXIT_VELOCITY] = exit_speed
    out[RESTITUTION] = exit_speed / velocity
    out[ABSORBED_ENERGY] = 0.5 * mass * (velocity - exit_speed) * (velocity + exit_speed)
    out[FIRMNESS_C] = peak_force / time_to_peak if time_to_peak > 0.0 else math.nan
    out[FIRMNESS_C_STAR] = peak_force / (time_to_peak * time_to_peak) if time_to_peak > 0.0 else math.nan
    out[MAX_PRESSURE] = 3.0 * max_force_ratio / (2.0 * math.pi * radius)  # p0 = 3F/(2π a²), a² = R δ
    out[CONTACT_RADIUS] = math.sqrt(radius * max_deflection)


@nb.njit(**_JIT)
def r_func(s):
    """r(s) = (s - ln(1+s))/s², r(0) = 1/2; s > -1."""
    if abs(s) < 0.05:
        # alternating series Σ (-s)^k/(k+2); 14 terms reach 1e-18 at |s| = 0.05
        total = 0.0
        term = 1.0
        for k in range(14):
            total += term / (k + 2)
            term *= -s
        return total
    return (s - math.log1p(s)) / (s * s)


@nb.njit(**_JIT)
def _r_many(x, out):
    for i in range(x.shape[0]):
        out[i] = r_func(x[i])


def r_array(x) -> np.ndarray:
    """``r_func`` of each element of ``x`` (a serial loop: for the few rows of a self-check)."""
    x = np.ascontiguousarray(np.atleast_1d(np.asarray(x, dtype=float)).ravel())
    out = np.empty_like(x)
    _r_many(x, out)
    return out


@nb.njit(**_JIT)
def rho_func(z):
    """ρ(z) = (e^z - 1 - z)/z², ρ(0) = 1/2."""
    if abs(z) < 0.05:
        total = 0.0
        term = 0.5  # z^k/(k+2)!
        for k in range(10):
            total += term
            term *= z / (k + 3)
        return total
    return (math.expm1(z) - z) / (z * z)


@nb.njit(**_JIT)
def e1_func(z):
    """E1(z) = (e^z - 1)/z, E1(0) = 1."""
    if abs(z) < 1e-8:
        return 1.0 + 0.5 * z
    return math.expm1(z) / z


@nb.njit(**_JIT)
def delta_phi(x, zeta, r_x):
    """ΔΦ(ζ) = r(x) - ζ² ρ(xζ); (δ/δ_H)^(n+1) = 2ΔΦ."""
    return r_x - zeta * zeta * rho_func(x * zeta)


@nb.njit(**_JIT)
def separation_zeta(x, r_x):
    """ζ0 in (-1, 0) with ΔΦ(ζ0) = 0.  ΔΦ is concave and increasing on ζ < 0,
    so Newton from the left end ζ = -1 (where ΔΦ ≤ 0) converges monotonically."""
    zeta = -1.0
    for _ in range(100):
        w = zeta * e1_func(x * zeta)
        step = delta_phi(x, zeta, r_x) / w  # Newton: ζ - g/g' with g' = -w
        zeta_new = zeta + step
        if zeta_new > 0.0:
            zeta_new = 0.5 * zeta
        # quadratic convergence: once a step is below 1e-8 the next error is below 1e-16
        if abs(zeta_new - zeta) <= 1e-8 * abs(zeta_new):
            w = zeta_new * e1_func(x * zeta_new)
            return zeta_new + delta_phi(x, zeta_new, r_x) / w
        zeta = zeta_new
    return zeta


@nb.njit(**_JIT)
def stationary_zeta(x, n, r_x, zeta1, order):
    """Root in [0, ζ1] of h(ζ) = x (n+1) ΔΦ(ζ) - order·w(ζ).

    order = n locates the peak force (dF/dt = 0), order = n - 1 the peak of
    F/δ (the Hertz pressure).  h is concave and decreasing, so Newton from
    the right end ζ1 (h < 0) converges monotonically."""
    if x == 0.0:
        return 0.0
    zeta = zeta1
    for _ in range(100):
        exz = math.exp(x * zeta)
        w = zeta * e1_func(x * zeta)
        h = x * (n + 1.0) * delta_phi(x, zeta, r_x) - order * w
        dh = -x * (n + 1.0) * w - order * exz
        zeta_new = zeta - h / dh
        if zeta_new < 0.0:
            zeta_new = 0.5 * zeta
        if abs(zeta_new - zeta) <= 1e-8 * zeta1:  # one more (quadratic) step reaches rounding
            exz = math.exp(x * zeta_new)
            w = zeta_new * e1_func(x * zeta_new)
            h = x * (n + 1.0) * delta_phi(x, zeta_new, r_x) - order * w
            return zeta_new - h / (-x * (n + 1.0) * w - order * exz)
        zeta = zeta_new
    return zeta


@nb.njit(**_JIT)
def tau_to_upper(x, p, r_x, a, b, nodes, weights):
    """∫_a^b (2ΔΦ)^(-p) dζ where ΔΦ(b) = 0 (b = ζ1): weight (b - ζ)^(-p).

    nodes, weights: Gauss–Jacobi rule for (1-u)^(-p) on [-1, 1]."""
    half = 0.5 * (b - a)
    if half <= 0.0:
        return 0.0
    total = 0.0
    for i in range(nodes.shape[0]):
        u = nodes[i]
        zeta = a + half * (1.0 + u)
        dist = half * (1.0 - u)  # b - ζ without cancellation
        total += weights[i] * (dist / (2.0 * delta_phi(x, zeta, r_x))) ** p
    return total * half ** (1.0 - p)


@nb.njit(**_JIT)
def tau_from_lower(x, p, r_x, a, b, nodes, weights):
    """∫_a^b (2ΔΦ)^(-p) dζ where ΔΦ(a) = 0 (a = ζ0): weight (ζ - a)^(-p).

    nodes, weights: Gauss–Jacobi rule for (1+u)^(-p) on [-1, 1]."""
    half = 0.5 * (b - a)
    if half <= 0.0:
        return 0.0
    total = 0.0
    for i in range(nodes.shape[0]):
        u = nodes[i]
        zeta = a + half * (1.0 + u)
        dist = half * (1.0 + u)
        total += weights[i] * (dist / (2.0 * delta_phi(x, zeta, r_x))) ** p
    return total * half ** (1.0 - p)


@nb.njit(**_JIT)
def _characteristics_row(mass, stiffness, n, damping_factor, velocity, radius,
                         up_nodes, up_weights, lo_nodes, lo_weights, out):
    p = n / (n + 1.0)
    x = damping_factor * velocity
    delta_h = ((n + 1.0) * mass * velocity * velocity / (2.0 * stiffness)) ** (1.0 / (n + 1.0))
    time_scale = 2.0 * (delta_h / velocity) / (n + 1.0)
    r_x = r_func(x)
    zeta1 = math.log1p(x) / x if x > 0.0 else 1.0
    zeta0 = separation_zeta(x, r_x)
    restitution = -zeta0 * e1_func(x * zeta0)

    max_deflection = delta_h * (2.0 * r_x) ** (1.0 / (n + 1.0))
    zeta_f = stationary_zeta(x, n, r_x, zeta1, n)
    delta_f = delta_h * (2.0 * delta_phi(x, zeta_f, r_x)) ** (1.0 / (n + 1.0))
    peak_force = stiffness * delta_f ** n * math.exp(x * zeta_f)
    time_to_peak = time_scale * tau_to_upper(x, p, r_x, zeta_f, zeta1, up_nodes, up_weights)
    time_to_max = time_scale * tau_to_upper(x, p, r_x, 0.0, zeta1, up_nodes, up_weights)
    duration = time_to_max + time_scale * tau_from_lower(x, p, r_x, zeta0, 0.0, lo_nodes, lo_weights)

    if n > 1.0:
        zeta_p = stationary_zeta(x, n, r_x, zeta1, n - 1.0)
        delta_p = delta_h * (2.0 * delta_phi(x, zeta_p, r_x)) ** (1.0 / (n + 1.0))
        max_ratio = stiffness * delta_p ** (n - 1.0) * math.exp(x * zeta_p)  # largest F/δ
    else:
        max_ratio = math.nan
    fill_characteristics(out, peak_force, time_to_peak, duration, max_deflection, time_to_max,
                         restitution * velocity, velocity, mass, max_ratio, radius)


@nb.njit(parallel=True, **_JIT)
def _characteristics_kernel(mass, stiffness, n, damping_factor, velocity, radius,
                            up_nodes, up_weights, lo_nodes, lo_weights, out):
    for i in nb.prange(mass.shape[0]):
        _characteristics_row(mass[i], stiffness[i], n, damping_factor[i], velocity[i], radius[i],
                             up_nodes, up_weights, lo_nodes, lo_weights, out[i])


@nb.njit(**_JIT)
def _characteristics_kernel_serial(mass, stiffness, n, damping_factor, velocity, radius,
                                   up_nodes, up_weights, lo_nodes, lo_weights, out):
    for i in range(mass.shape[0]):
        _characteristics_row(mass[i], stiffness[i], n, damping_factor[i], velocity[i], radius[i],
                             up_nodes, up_weights, lo_nodes, lo_weights, out[i])


def _rules(exponent: float, n_nodes: int = QUADRATURE_NODES):
    p = exponent / (exponent + 1.0)
    up = gauss_jacobi(n_nodes, -p, 0.0)
    lo = gauss_jacobi(n_nodes, 0.0, -p)
    return up[0], up[1], lo[0], lo[1]


def powerlaw_characteristics(mass, stiffness, damping_factor, velocity, radius,
                             exponent: float = 1.5, parallel: bool | None = None,
                             tabulated: bool | None = None) -> np.ndarray:
    """Characteristics of impacts with F = K δ^n (1 + c δ̇), one row per impact.

    Parameters
    ----------
    mass : array_like
        Mass (or reduced mass) m [kg].
    stiffness : array_like
        Contact stiffness K [N/m^n] (k_c of the paper's eq 9 for n = 1.5).
    damping_factor : array_like
        c = λ/K [s/m] (λ of eqs 5 and 21 divided by k_c); 0 is undamped Hertz.
    velocity : array_like
        Impact velocity v0 > 0 [m/s].
    radius : array_like
        Effective radius R [m], for the contact radius and the Hertz pressure.
    exponent : float
        n, 1.5 for Hertz contact.
    parallel : bool or None
        Use all cores; by default when there are more than 2000 rows.
    tabulated : bool or None
        Use the Chebyshev table of the dimensionless characteristics (agrees with
        the exact kernel to the error ``powerlaw_table`` reports, ~1e-13);
        by default for more than 20000 rows, where it pays for its build.

    Returns
    -------
    ndarray, shape (rows, len(CHARACTERISTIC_COLUMNS))
        Columns in the order of ``CHARACTERISTIC_COLUMNS`` (SI units).
        Inputs are not validated here: validate at the boundary.
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                   (mass, stiffness, damping_factor, velocity, radius)))
    arrays = [np.ascontiguousarray(a.ravel()) for a in arrays]
    rows = arrays[0].shape[0]
    out = np.empty((rows, N_CHARACTERISTICS))
    if tabulated if tabulated is not None else rows > 20000:
        coefficients, _ = powerlaw_table(float(exponent))
        width = math.log1p(TABLE_X_MAX) / TABLE_PANELS
        _tabulated_kernel(arrays[0], arrays[1], float(exponent), arrays[2], arrays[3], arrays[4], coefficients,
                          width, TABLE_X_MAX, *_rules(float(exponent)), out)
        return out
    kernel = _characteristics_kernel if (parallel if parallel is not None else rows > PARALLEL_MIN_ROWS) \
        else _characteristics_kernel_serial
    kernel(arrays[0], arrays[1], float(exponent), arrays[2], arrays[3], arrays[4],
           *_rules(float(exponent)), out)
    return out


@nb.njit(**_JIT)
def _invert_time(x, p, r_x, target, zeta_end, zeta_other, time_scale, nodes, weights, upper):
    """ζ at which the time measured from the singular end ``zeta_end`` equals
    ``target``.  Solved for s = |ζ - ζ_end|^(1-p), in which that time is
    smooth and monotone, by Newton's method kept inside a shrinking bracket."""
    q = 1.0 - p
    s_lo = 0.0
    s_hi = abs(zeta_other - zeta_end) ** q
    s = 0.5 * s_hi
    for _ in range(80):
        dist = s ** (1.0 / q)
        if upper:
            zeta = zeta_end - dist
            t = time_scale * tau_to_upper(x, p, r_x, zeta, zeta_end, nodes, weights)
        else:
            zeta = zeta_end + dist
            t = time_scale * tau_from_lower(x, p, r_x, zeta_end, zeta, nodes, weights)
        f = t - target
        if f > 0.0:
            s_hi = s
        else:
            s_lo = s
        dphi = delta_phi(x, zeta, r_x)
        # dt/ds = time_scale (2ΔΦ)^(-p) s^(p/q)/q; written with dist/ΔΦ to stay finite at s → 0
        if dphi > 0.0:
            slope = time_scale * (dist / (2.0 * dphi)) ** p / q
        else:
            slope = 0.0
        s_new = s - f / slope if slope > 0.0 else 0.5 * (s_lo + s_hi)
        if not (s_lo < s_new < s_hi):
            s_new = 0.5 * (s_lo + s_hi)
        if abs(s_new - s) <= 1e-15 * s_hi:
            s = s_new
            break
        s = s_new
    dist = s ** (1.0 / q)
    return zeta_end - dist if upper else zeta_end + dist


@nb.njit(**_JIT)
def _curves_kernel(mass, stiffness, n, damping_factor, velocity, times,
                   up_nodes, up_weights, lo_nodes, lo_weights, deflection, rate, force):
    p = n / (n + 1.0)
    x = damping_factor * velocity
    delta_h = ((n + 1.0) * mass * velocity * velocity / (2.0 * stiffness)) ** (1.0 / (n + 1.0))
    time_scale = 2.0 * (delta_h / velocity) / (n + 1.0)
    r_x = r_func(x)
    zeta1 = math.log1p(x) / x if x > 0.0 else 1.0
    zeta0 = separation_zeta(x, r_x)
    time_to_max = time_scale * tau_to_upper(x, p, r_x, 0.0, zeta1, up_nodes, up_weights)
    duration = time_to_max + time_scale * tau_from_lower(x, p, r_x, zeta0, 0.0, lo_nodes, lo_weights)
    for i in range(times.shape[0]):
        t = times[i]
        if t <= 0.0:
            zeta = zeta1
        elif t >= duration:
            zeta = zeta0
        elif t <= time_to_max:
            zeta = _invert_time(x, p, r_x, t, zeta1, 0.0, time_scale, up_nodes, up_weights, True)
        else:
            zeta = _invert_time(x, p, r_x, duration - t, zeta0, 0.0, time_scale,
                                lo_nodes, lo_weights, False)
        dphi = delta_phi(x, zeta, r_x)
        # exactly zero at the ends: ΔΦ there is a rounding residue, amplified by the power 1/(n+1)
        d = delta_h * (2.0 * dphi) ** (1.0 / (n + 1.0)) if (dphi > 0.0 and 0.0 < t < duration) else 0.0
        deflection[i] = d
        rate[i] = velocity * zeta * e1_func(x * zeta)
        force[i] = stiffness * d ** n * math.exp(x * zeta)
    return duration


def powerlaw_curves(mass: float, stiffness: float, damping_factor: float, velocity: float,
                    times, exponent: float = 1.5):
    """Deflection δ [m], rate δ̇ [m/s] and force F [N] at ``times`` [s] for one
    impact with F = K δ^n (1 + c δ̇), from the exact phase curve (no time
    stepping).  Times outside [0, T] are clamped to the ends of the contact.

    Returns (deflection, rate, force, contact_duration).
    """
    times = np.ascontiguousarray(np.asarray(times, dtype=float).ravel())
    deflection = np.empty_like(times)
    rate = np.empty_like(times)
    force = np.empty_like(times)
    duration = _curves_kernel(float(mass), float(stiffness), float(exponent), float(damping_factor),
                              float(velocity), times, *_rules(float(exponent)), deflection, rate, force)
    return deflection, rate, force, duration


@nb.njit(**_JIT)
def r_prime(s):
    """r'(s) = (1/(1+s) - 2 r(s))/s."""
    if abs(s) < 0.05:
        total = 0.0
        term = -1.0  # (-1)^k s^(k-1), k = 1..
        for k in range(1, 16):
            total += k * term / (k + 2)
            term *= -s
        return total
    return (1.0 / (1.0 + s) - 2.0 * r_func(s)) / s


@nb.njit(**_JIT)
def restitution_of_x(x):
    """Exact restitution e of the law F = K δ^n (1 + c δ̇) for x = c·v0 ≥ 0
    (independent of n, K and m).  Root of e² r(-x e) = r(x)."""
    r_x = r_func(x)
    zeta0 = separation_zeta(x, r_x)
    return -zeta0 * e1_func(x * zeta0)


#: Below this e the root is polished in u (near the pole x = 1/e), above it in x.
_SMALL_E = 0.25


@nb.njit(**_JIT)
def _newton_x(e, x):
    """Root of f(x) = e² r(-x e) - r(x) in (0, 1/e) by safeguarded Newton from ``x``.

    f rises from (e² - 1)/2 at x = 0 to +∞ at x = 1/e (the trivial root x = 0 of the
    exact relation is divided out by r), so it is well conditioned for e near 1."""
    lo = 0.0
    hi = 1.0 / e
    if not (lo < x < hi):
        x = min(1.5 * (1.0 - e) / e, 0.5 * hi)  # Hunt–Crossley first-order guess, kept inside
    for _ in range(200):
        f = e * e * r_func(-x * e) - r_func(x)
        if f == 0.0:
            return x
        if f > 0.0:
            hi = x
        else:
            lo = x
        df = -e * e * e * r_prime(-x * e) - r_prime(x)
        x_new = x - f / df if df > 0.0 else 0.5 * (lo + hi)
        if not (lo <= x_new <= hi):
            x_new = 0.5 * (lo + hi)
        if abs(x_new - x) <= 1e-8 * x_new:
            # quadratic convergence: this step left an error ~1e-16; one more reaches rounding
            # (asking for 2e-16 instead makes Newton dither by an ulp and fall back to bisection)
            f = e * e * r_func(-x_new * e) - r_func(x_new)
            df = -e * e * e * r_prime(-x_new * e) - r_prime(x_new)
            final = x_new - f / df if df > 0.0 else x_new
            return final if lo <= final <= hi else x_new
        if hi - lo <= 2e-16 * hi:
            return x_new
        x = x_new
    return x


@nb.njit(**_JIT)
def _newton_u(e, u):
    """Root of the exact relation for small e, in u = -ln(1 - e x): x = -expm1(-u)/e stays
    below the pole 1/e for every u, and H(u) = ln(1 + x) + u - (1 + e) x is smooth there
    (its trivial root u = 0 is far when e is small).  Newton from ``u``; returns x."""
    for _ in range(100):
        decay = math.exp(-u)
        x = -math.expm1(-u) / e
        h = math.log1p(x) + u - (1.0 + e) * x
        dh = 1.0 + (1.0 / (1.0 + x) - (1.0 + e)) * decay / e
        step = h / dh
        u_new = u - step
        if u_new <= 0.0:
            u_new = 0.5 * u
        if abs(u_new - u) <= 1e-8 * u_new:  # quadratic: one more step reaches rounding
            x = -math.expm1(-u_new) / e
            h = math.log1p(x) + u_new - (1.0 + e) * x
            dh = 1.0 + (1.0 / (1.0 + x) - (1.0 + e)) * math.exp(-u_new) / e
            return -math.expm1(-(u_new - h / dh)) / e
        u = u_new
    return -math.expm1(-u) / e


@nb.njit(**_JIT)
def _x_from_guess(e, u):
    """x for restitution e from a guess ``u`` of u = -ln(1 - e x) (in u near the pole
    x = 1/e, where small e puts the root; in x otherwise)."""
    if e < _SMALL_E:
        return _newton_u(e, u)
    return _newton_x(e, -math.expm1(-u) / e)


@nb.njit(**_JIT)
def x_of_restitution(e):
    """x = c·v0 ≥ 0 for which the law F = K δ^n (1 + c δ̇) gives restitution e
    in (0, 1]: the root of (1 + x) = (1 - e x) exp((1 + e) x) in (0, 1/e), by
    safeguarded Newton (``_newton_u`` for small e, ``_newton_x`` otherwise) from
    a first-order guess.  ``exact_x`` does the same from a tabulated guess."""
    if e >= 1.0:
        return 0.0
    if not (e > 0.0):
        return math.nan
    if e < _SMALL_E:
        x = 1.0 / e  # the root tends to the pole as e → 0
        return _x_from_guess(e, (1.0 + e) * x - math.log1p(x))
    x = 1.5 * (1.0 - e) / e  # Hunt–Crossley first order, kept below the pole
    return _x_from_guess(e, -math.log1p(-min(e * x, 0.5)))


#: Starting guesses of ``exact_x`` on a uniform grid of e: g(e) = e u/(1 - e) with
#: u = -ln(1 - e x), smooth and between 1 and 1.5 on (0, 1) (x ≈ 1.5 (1 - e) as e → 1,
#: x ≈ 1/e as e → 0), interpolated linearly (error ~1e-7, so Newton needs 2–3 steps).
_GUESS_NODES = 2049
_GUESS: list = []


def _guess_table() -> np.ndarray:
    if not _GUESS:
        e = np.linspace(0.0, 1.0, _GUESS_NODES)
        g = np.empty_like(e)
        g[0], g[-1] = 1.0, 1.5
        for i in range(1, _GUESS_NODES - 1):
            x = x_of_restitution(e[i])
            u = (1.0 + e[i]) * x - math.log1p(x)  # = -ln(1 - e x) at the root, without cancellation
            g[i] = u * e[i] / (1.0 - e[i])
        _GUESS.append(g)
    return _GUESS[0]


@nb.njit(**_JIT)
def _x_from_table(e, table):
    if e >= 1.0:
        return 0.0
    if not (e > 0.0):
        return math.nan
    position = e * (table.shape[0] - 1)
    i = min(int(position), table.shape[0] - 2)
    g = table[i] + (position - i) * (table[i + 1] - table[i])
    return _x_from_guess(e, g * (1.0 - e) / e)


@nb.njit(parallel=True, **_JIT)
def _vector_x_of_restitution(e, table, out):
    for i in nb.prange(e.shape[0]):
        out[i] = _x_from_table(e[i], table)


@nb.njit(**_JIT)
def _vector_x_of_restitution_serial(e, table, out):
    for i in range(e.shape[0]):
        out[i] = _x_from_table(e[i], table)


@nb.njit(parallel=True, **_JIT)
def _vector_restitution_of_x(x, out):
    for i in nb.prange(x.shape[0]):
        out[i] = restitution_of_x(x[i])


@nb.njit(**_JIT)
def _vector_restitution_of_x_serial(x, out):
    for i in range(x.shape[0]):
        out[i] = restitution_of_x(x[i])


#: Below this many rows the serial kernels win: starting threads costs more
#: than the work, and far more when the other cores are busy.
PARALLEL_MIN_ROWS = 2000


def _uniform(values: np.ndarray) -> bool:
    """Every value the same finite number (a table's restitution is often one value: the fruit's or the default),
    so that a root per row would find one root n times; two passes cost ~1 % of the roots."""
    return values.shape[0] > PARALLEL_MIN_ROWS and values[0] == values.min() == values.max()


def exact_x(restitution):
    """Vectorised ``x_of_restitution``: x = c·v0 from e ∈ (0, 1]."""
    e = np.ascontiguousarray(np.atleast_1d(np.asarray(restitution, dtype=float)).ravel())
    out = np.empty_like(e)
    if _uniform(e):
        _vector_x_of_restitution_serial(e[:1], _guess_table(), out[:1])
        out.fill(out[0])
    else:
        kernel = _vector_x_of_restitution if e.shape[0] > PARALLEL_MIN_ROWS else _vector_x_of_restitution_serial
        kernel(e, _guess_table(), out)
    return out.reshape(np.shape(restitution))


def exact_restitution(x):
    """Vectorised ``restitution_of_x``: e from x = c·v0 ≥ 0."""
    xs = np.ascontiguousarray(np.atleast_1d(np.asarray(x, dtype=float)).ravel())
    out = np.empty_like(xs)
    if _uniform(xs):
        _vector_restitution_of_x_serial(xs[:1], out[:1])
        out.fill(out[0])
    else:
        (_vector_restitution_of_x if xs.shape[0] > PARALLEL_MIN_ROWS else _vector_restitution_of_x_serial)(xs, out)
    return out.reshape(np.shape(x))


_SINGLE_RULES: dict[float, tuple] = {}


def powerlaw_single(mass: float, stiffness: float, exponent: float, damping_factor: float,
                    velocity: float, radius: float) -> np.ndarray:
    """Characteristics of one impact (``CHARACTERISTIC_COLUMNS`` order), with
    the least Python overhead: the single-impact API's path into the engine."""
    rules = _SINGLE_RULES.get(exponent)
    if rules is None:
        rules = _SINGLE_RULES[exponent] = _rules(exponent)
    out = np.empty(N_CHARACTERISTICS)
    _characteristics_row(mass, stiffness, exponent, damping_factor, velocity, radius, *rules, out)
    return out


# ---------------------------------------------------------------------------
# Batch acceleration: every characteristic of the power-law family is a known
# scale (δ_H, t_H, K δ_H^n, K δ_H^(n-1)/R) times a smooth function of the single
# number x = c·v0 (and n).  For batches those functions are interpolated from
# the exact kernel above by piecewise Chebyshev series in u = ln(1 + x); the
# table is built on first use (a few ms), its error checked against the exact
# kernel at points between the nodes, and rows with x beyond the table use the
# exact kernel directly.

#: Table range and resolution: x ≤ TABLE_X_MAX (e ≥ 0.0099), panels × degree.
TABLE_X_MAX = 100.0
TABLE_PANELS = 48
TABLE_DEGREE = 16
_TABLE_FUNCS = 7  # e, δ_max, t_c, T, t_m, F_max, pressure (dimensionless)
_TABLES: dict[float, tuple[np.ndarray, float]] = {}


def _dimensionless(x, n, rules):
    """Exact dimensionless characteristics at each x, shape (len(x), 7): m = v0 = R = 1
    and K = (n+1)/2 make δ_H = t_H = 1, so lengths and times come out in units of δ_H
    and t_H, forces in K δ_H^n and the pressure in K δ_H^(n-1)/R."""
    x = np.ascontiguousarray(x, dtype=float)
    ones = np.ones_like(x)
    stiffness = (n + 1.0) / 2.0
    out = np.empty((len(x), N_CHARACTERISTICS))
    _characteristics_kernel_serial(ones, ones * stiffness, n, x, ones, ones, *rules, out)
    return np.column_stack([out[:, RESTITUTION], out[:, MAX_DEFLECTION], out[:, TIME_TO_PEAK], out[:, CONTACT_DURATION],
                            out[:, TIME_TO_MAX_DEFLECTION], out[:, PEAK_FORCE] / stiffness,
                            out[:, MAX_PRESSURE] / stiffness])


def powerlaw_table(exponent: float = 1.5) -> tuple[np.ndarray, float]:
    """(Chebyshev coefficients [func, panel, k], max relative interpolation error
    measured between the nodes) for ``exponent``; built once per exponent."""
    table = _TABLES.get(exponent)
    if table is not None:
        return table
    rules = _rules(exponent)
    width = math.log1p(TABLE_X_MAX) / TABLE_PANELS
    theta = np.pi * (np.arange(TABLE_DEGREE) + 0.5) / TABLE_DEGREE
    nodes = np.cos(theta)  # Chebyshev points of the first kind on [-1, 1]
    coefficients = np.empty((_TABLE_FUNCS, TABLE_PANELS, TABLE_DEGREE))
    for panel in range(TABLE_PANELS):
        u = width * (panel + 0.5 * (1.0 + nodes))
        values = _dimensionless(np.expm1(u), exponent, rules)  # (degree, funcs)
        for k in range(TABLE_DEGREE):
            coefficients[:, panel, k] = 2.0 / TABLE_DEGREE * (values * np.cos(k * theta)[:, None]).sum(axis=0)
        coefficients[:, panel, 0] *= 0.5
    # check between the nodes (panel edges and midpoints of node gaps)
    probe = np.concatenate([np.linspace(0.0, math.log1p(TABLE_X_MAX), 4 * TABLE_PANELS * TABLE_DEGREE + 1)[1:-1]])
    exact = _dimensionless(np.expm1(probe), exponent, rules)
    interpolated = np.empty_like(exact)
    _table_eval_many(np.expm1(probe), coefficients, width, interpolated)
    error = float(np.max(np.abs(interpolated / exact - 1.0)))
    _TABLES[exponent] = (coefficients, error)
    return coefficients, error


@nb.njit(**_JIT)
def _table_eval(x, coefficients, width, out):
    """Clenshaw evaluation of the dimensionless functions at x (x ≤ TABLE_X_MAX)."""
    u = math.log1p(x)
    panel = min(int(u / width), coefficients.shape[1] - 1)
    t = 2.0 * (u / width - panel) - 1.0
    for f in range(coefficients.shape[0]):
        b1 = 0.0
        b2 = 0.0
        for k in range(coefficients.shape[2] - 1, 0, -1):
            b0 = 2.0 * t * b1 - b2 + coefficients[f, panel, k]
            b2 = b1
            b1 = b0
        out[f] = t * b1 - b2 + coefficients[f, panel, 0]


@nb.njit(**_JIT)
def _table_eval_many(x, coefficients, width, out):
    for i in range(x.shape[0]):
        _table_eval(x[i], coefficients, width, out[i])


@nb.njit(**_JIT)
def _tabulated_row(mass, stiffness, n, damping_factor, velocity, radius, coefficients, width, x_max,
                   up_nodes, up_weights, lo_nodes, lo_weights, out):
    x = damping_factor * velocity
    if not (x <= x_max):  # beyond the table (or NaN): the exact kernel
        _characteristics_row(mass, stiffness, n, damping_factor, velocity, radius,
                             up_nodes, up_weights, lo_nodes, lo_weights, out)
        return
    _table_eval(x, coefficients, width, out)  # out[:7] holds the dimensionless values for now
    e, d_max, t_peak, t_end, t_max, f_peak, pressure = out[0], out[1], out[2], out[3], out[4], out[5], out[6]
    delta_h = ((n + 1.0) * mass * velocity * velocity / (2.0 * stiffness)) ** (1.0 / (n + 1.0))
    t_h = delta_h / velocity
    force_scale = stiffness * delta_h ** n
    # the table's pressure is 3F/(2π R δ) in units of K δ_H^(n-1)/R; back to max F/δ
    max_ratio = force_scale / delta_h * pressure * 2.0 * math.pi / 3.0
    fill_characteristics(out, force_scale * f_peak, t_h * t_peak, t_h * t_end, delta_h * d_max, t_h * t_max,
                         e * velocity, velocity, mass, max_ratio, radius)


@nb.njit(parallel=True, **_JIT)
def _tabulated_kernel(mass, stiffness, n, damping_factor, velocity, radius, coefficients, width, x_max,
                      up_nodes, up_weights, lo_nodes, lo_weights, out):
    for i in nb.prange(mass.shape[0]):
        _tabulated_row(mass[i], stiffness[i], n, damping_factor[i], velocity[i], radius[i], coefficients, width,
                       x_max, up_nodes, up_weights, lo_nodes, lo_weights, out[i])


@nb.njit(parallel=True, **_JIT)
def _curves_batch_kernel(mass, stiffness, n, damping_factor, velocity, times,
                         up_nodes, up_weights, lo_nodes, lo_weights, deflection, rate, force):
    for i in nb.prange(mass.shape[0]):
        _curves_kernel(mass[i], stiffness[i], n, damping_factor[i], velocity[i], times[i],
                       up_nodes, up_weights, lo_nodes, lo_weights, deflection[i], rate[i], force[i])


def powerlaw_curves_batch(mass, stiffness, damping_factor, velocity, times, exponent: float = 1.5):
    """δ [m], δ̇ [m/s], F [N] of many impacts at ``times`` [s]: shape (points,) for a
    common grid or (rows, points) for one grid per row.  Returns three (rows, points)
    arrays from the exact phase curve (as ``powerlaw_curves``, row by row)."""
    mass, stiffness, damping_factor, velocity = (np.ascontiguousarray(np.atleast_1d(np.asarray(a, dtype=float)))
                                                 for a in np.broadcast_arrays(mass, stiffness, damping_factor, velocity))
    times = np.asarray(times, dtype=float)
    times = np.ascontiguousarray(np.broadcast_to(times, (mass.shape[0], times.shape[-1])))
    deflection = np.empty_like(times)
    rate = np.empty_like(times)
    force = np.empty_like(times)
    _curves_batch_kernel(mass, stiffness, float(exponent), damping_factor, velocity, times, *_rules(float(exponent)),
                         deflection, rate, force)
    return deflection, rate, force
