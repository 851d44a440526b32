"""Exact engine for elastic–plastic contact, on a half-space or a thin layer, with viscous damping.

Plain floats and arrays in, plain arrays out; no I/O, no units.

The contact law
---------------
The rate-independent force F_T(δ) of the fruit is Thornton's elastic–perfectly
plastic law (C. Thornton, J. Appl. Mech. 64 (1997) 383–386; with equation
numbers in C. Thornton, Z. Ning, Powder Technol. 99 (1998) 154–162, "TN98"):

* elastic loading, Hertz: F = K δ_f^1.5, K = (4/3) E* √R, up to the yield
  force F_y = π³ p_y³ R² / (6 E*²) at δ_y = R (π p_y / (2E*))² (TN98 eqs 9, 14, 16);
* plastic loading: F = F_y + π p_y R (δ_f − δ_y) (TN98 eq 19);
* unloading (and reloading below the largest force F* reached), Hertz about a
  flattened contact: F = (4/3) E* √R_p (δ_f − δ_p)^1.5 with
  R_p = (4E*/(3F*)) ((2F* + F_y)/(2π p_y))^1.5 (TN98 eqs 20, 28, 29).

A cushion of thickness h on a rigid substrate is an elastic-foundation
(Winkler) layer in series with the fruit: under a sphere of radius R it
carries F = K_L δ_L² with K_L = π k R, k = (1−ν)E/((1+ν)(1−2ν)h) (the
Simbody ``ElasticFoundationForce`` layer; F = π k R δ² by integrating
k (δ − r²/2R) over the contact, derived in docs/damage.md).  When δ_L
reaches h the pad has bottomed out: the force beyond F_b = K_L h² is carried
by the substrate (the layer stays at δ_L = h).  The total deflection at a
force F is δ = δ_f(F) + δ_L(F); the layer is elastic (it unloads along its
loading curve).

Viscous damping multiplies the rate-independent force, F = F_T(δ)(1 + c δ̇),
the rule of the power-law family (Hunt & Crossley 1975), with the yield and
unloading history driven by F_T alone: plastic work is the loop area ∮F_T dδ,
viscous work ∫ c F_T δ̇² dt, and the two add up to the absorbed energy.

Method
------
Along a monotone branch F_T is a parameter of the motion, and the equation of
motion m dv/dt = −F_T (1 + c v) has the first integral

    m v² r(c v) = E_in − W(F_T),    r(s) = (s − ln(1+s))/s²,

with E_in = m V² r(c V) the energy the contact can take and W the work of F_T
along the branch, known in closed form for every piece (Hertz, plastic line,
layer, bottomed layer).  So the largest force F* solves W(F*) = E_in, the
rebound speed solves m w² r(−c w) = U(F*) (U the elastic energy returned
along the unloading branch), the peak force is where m v = c F_T² dδ/dF_T
(the stationarity of F_T (1 + c v) along loading), and every time is
∫ (dδ/dF_T) / v dF_T, a Gauss–Legendre quadrature on pieces split at the
kinks (F_y, F_b) with substitutions that make the endpoint singularities
(F^(−1/3), F^(−1/2) at first touch, (F* − F)^(−1/2) at the turn) smooth.
Without damping, a half-space and finite p_y, this is Thornton's closed form
exactly (tests/test_plastic.py checks TN98 eq 44 to 1e-10 and the whole
impact against SciPy's ``solve_ivp`` at rtol 1e-12).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.codes import N_CHARACTERISTICS
from fruitimpact.engine.halfspace import halfspace_impact
from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.plasticforms import (N_PLASTIC, PLASTIC_COLUMNS, winkler_stiffness,  # noqa: F401  (re-exported)
                                             yield_force, yield_pressure_of_force)
from fruitimpact.engine.powerlaw import r_func
from fruitimpact.engine.quadrature import gauss_jacobi

_JIT = dict(cache=CACHE, fastmath=False, error_model="numpy")

#: Gauss–Legendre nodes per piece of a time integral (the integrands are smooth after substitution).
NODES = 24
#: A half-space impact is walked in the speed (``halfspace``) while c w < this (w the exit speed): beyond it
#: (restitution ≲ 1/(c V), a damping far outside fruit) ln(1 − c u) is singular next to the exit and the
#: force parametrisation is kept.  Below it the two agree to 1e-8 (tests/test_plastic.py).
HALFSPACE_DAMPING_LIMIT = 0.9
#: Rows from which the parallel kernel is used.
PARALLEL_MIN_ROWS = 2000

# ---------------------------------------------------------------------------------------------
# the branches, parametrised by the rate-independent force F (p: the row's parameters)
# p = (K, R, E*, F_y, δ_y, kp = π p_y R, K_L, F_b, h, K_p, δ_p, crushed)
# ---------------------------------------------------------------------------------------------
K_, R_, ES_, FY_, DY_, KP_, KL_, FB_, H_, KU_, DP_, CR_ = range(12)


@nb.njit(**_JIT)
def _layer(F, p):
    """(δ_L, dδ_L/dF, ∫_0^F δ_L dF) of the layer (zeros without one)."""
    KL = p[KL_]
    if not KL < math.inf:
        return 0.0, 0.0, 0.0
    FB = p[FB_]
    if F <= FB:
        d = math.sqrt(F / KL)
        return d, (0.5 / math.sqrt(KL * F) if F > 0.0 else math.inf), 2.0 / 3.0 * F * d
    return p[H_], 0.0, 2.0 / 3.0 * FB * p[H_] + p[H_] * (F - FB)


@nb.njit(**_JIT)
def _layer_unload(F, p):
    """``_layer`` on the unloading branch: the layer unloads along its loading curve, except a board that
    crushed (``CR_``: it reached F_b and its flutes collapsed), which stays flat at δ_L = h and returns nothing."""
    if p[CR_] > 0.0:
        return p[H_], 0.0, p[H_] * F
    return _layer(F, p)


@nb.njit(**_JIT)
def _fruit_load(F, p):
    """(δ_f, dδ_f/dF, ∫_0^F δ_f dF) of the fruit on the loading branch (Hertz, then plastic)."""
    K = p[K_]
    FY = p[FY_]
    if F <= FY:
        d = (F / K) ** (2.0 / 3.0)
        return d, (2.0 / 3.0 * d / F if F > 0.0 else math.inf), 0.6 * F * d
    DY = p[DY_]
    kp = p[KP_]
    return DY + (F - FY) / kp, 1.0 / kp, 0.6 * FY * DY + DY * (F - FY) + 0.5 * (F - FY) ** 2 / kp


@nb.njit(**_JIT)
def _fruit_unload(F, p):
    """(δ_f, dδ_f/dF, ∫_0^F (δ_f − δ_p) dF) of the fruit on the unloading branch."""
    d = (F / p[KU_]) ** (2.0 / 3.0)
    return p[DP_] + d, (2.0 / 3.0 * d / F if F > 0.0 else math.inf), 0.6 * F * d


@nb.njit(**_JIT)
def load_work(F, p):
    """W(F) = ∫ F dδ along loading = F δ(F) − ∫_0^F δ dF [J]."""
    df, _, i_f = _fruit_load(F, p)
    dl, _, i_l = _layer(F, p)
    return F * (df + dl) - i_f - i_l


@nb.njit(**_JIT)
def unload_energy(F, p):
    """U(F): the elastic energy the unloading branch returns between F and 0 [J]."""
    df, _, i_f = _fruit_unload(F, p)
    dl, _, i_l = _layer_unload(F, p)
    return F * (df - p[DP_] + dl) - i_f - i_l


@nb.njit(**_JIT)
def _load_slope(F, p):
    return _fruit_load(F, p)[1] + _layer(F, p)[1]


@nb.njit(**_JIT)
def _unload_slope(F, p):
    return _fruit_unload(F, p)[1] + _layer_unload(F, p)[1]


@nb.njit(**_JIT)
def _invert_first_integral(q, sign):
    """y ≥ 0 with y² r(sign · y) = q: the loading (sign +1, y − ln(1 + y) = q) or unloading
    (sign −1, y ∈ (0, 1), −y − ln(1 − y) = q) first integral in y = c |v|.

    A start from the inverse series y = s + sign s²/3 + s³/36 − sign s⁴/270 (s = √(2q), q < 1; for
    q < 1e-8 the series is exact to rounding and is returned), or from a fixed point for q ≥ 1
    (y = q + ln(1 + y) loading, y = 1 − exp(−q − y) unloading), then Halley steps (cubic convergence:
    two or three), kept inside the domain."""
    if q < 1.0:
        root = math.sqrt(2.0 * q)
        y = root * (1.0 + root * (sign / 3.0 + root * (1.0 / 36.0 - sign * root / 270.0)))
        if q < 1e-8:  # the series' next term is ~s⁵/4320: below rounding here, and Halley would cancel
            return y
    elif sign > 0.0:
        y = q + math.log1p(q + math.log1p(q))
        y = q + math.log1p(y)
    else:
        y = -math.expm1(-1.0 - q)
        y = -math.expm1(-q - y)
    if sign < 0.0 and not 0.0 < y < 1.0:
        y = 0.5
    for _ in range(60):
        f = y * y * r_func(sign * y) - q
        one = 1.0 + sign * y
        d1 = y / one
        d2 = 1.0 / (one * one)
        step = 2.0 * f * d1 / (2.0 * d1 * d1 - f * d2)
        y_new = y - step
        if not y_new > 0.0:
            y_new = 0.5 * y
        elif sign < 0.0 and not y_new < 1.0:  # unloading: stay below 1 (bisect towards it)
            y_new = 0.5 * (y + 1.0)
        y = y_new
        if abs(step) <= 4e-16 * y:
            break
    return y


@nb.njit(**_JIT)
def speed_of_energy(mass, c, energy):
    """v ≥ 0 with m v² r(c v) = energy (loading: v toward the surface) [m/s]."""
    if energy <= 0.0:
        return 0.0
    if c == 0.0:
        return math.sqrt(2.0 * energy / mass)
    return _invert_first_integral(c * c * energy / mass, 1.0) / c


@nb.njit(**_JIT)
def rebound_speed_of_energy(mass, c, energy):
    """w ≥ 0 with m w² r(−c w) = energy (unloading: v = −w away from the surface) [m/s]."""
    if energy <= 0.0:
        return 0.0
    if c == 0.0:
        return math.sqrt(2.0 * energy / mass)
    return _invert_first_integral(c * c * energy / mass, -1.0) / c


@nb.njit(**_JIT)
def _solve_max_force(energy, p, guess):
    """F* with W(F*) = energy: Newton in ln F (W is a power of F on each piece), bracketed."""
    lo = 0.0
    hi = guess
    while load_work(hi, p) < energy:
        lo = hi
        hi *= 4.0
    F = hi
    for _ in range(200):
        W = load_work(F, p)
        if W < energy:
            lo = F
        else:
            hi = F
        slope = F * _load_slope(F, p)  # dW/dF = F dδ/dF
        new = F - (W - energy) / slope if slope > 0.0 else 0.5 * (lo + hi)
        if not (lo < new < hi):
            new = 0.5 * (lo + hi) if lo > 0.0 else 0.5 * hi
        if abs(new - F) <= 1e-15 * F:
            F = new
            break
        F = new
    return F


@nb.njit(**_JIT)
def _log_slope_of_pressure(F, p, yield_pressure):
    """ε = d ln p_T / d ln F of the centre pressure along loading (1/3 for Hertz, 0 once yielded)."""
    h = 1e-6
    low, high = F * (1.0 - h), F * (1.0 + h)
    if p[CR_] > 0.0 and low <= p[FB_] < high:
        # a crushed board's pressure jumps at F_b (it stops spreading the load): the difference is taken on F's
        # own side of the jump, or the slope at the end of the piece below it is that of the jump
        if F <= p[FB_]:
            high = F
        else:
            low = F
    lo = _pressure_at(low, p, yield_pressure)[0]
    hi = _pressure_at(high, p, yield_pressure)[0]
    return (math.log(hi) - math.log(lo)) / (math.log(high) - math.log(low))


@nb.njit(**_JIT)
def _stationarity(F, mass, c, energy, p, pressure, yield_pressure):
    """m v ε − c F² dδ/dF along loading: > 0 while F_T (1 + c v) (ε = 1, ``pressure`` False) or the
    pressure p_T (1 + c v) (ε = d ln p_T/d ln F) rises; d ln(1 + c v)/dF = −c F (dδ/dF)/(m v)."""
    v = speed_of_energy(mass, c, energy - load_work(F, p))
    slope = 1.0 if not pressure else _log_slope_of_pressure(F, p, yield_pressure)
    return mass * v * slope - c * F * F * _load_slope(F, p)


@nb.njit(**_JIT)
def _root_on(a, b, mass, c, energy, p, pressure, yield_pressure):
    """The root of the (decreasing) stationarity on [a, b], or -1 when it does not change sign."""
    if a > 0.0 and p[CR_] > 0.0:  # inside the piece: at a = F_b a crushed board's pressure slope is the jump's
        a *= 1.0 + 4e-6
    fa = _stationarity(a, mass, c, energy, p, pressure, yield_pressure) if a > 0.0 else mass * 1.0
    fb = _stationarity(b, mass, c, energy, p, pressure, yield_pressure)
    if not (fa > 0.0 and fb < 0.0):
        return -1.0
    for _ in range(200):  # Illinois regula falsi with bisection safeguard
        m = b - fb * (b - a) / (fb - fa)
        if not (a < m < b):
            m = 0.5 * (a + b)
        fm = _stationarity(m, mass, c, energy, p, pressure, yield_pressure)
        if fm > 0.0:
            a, fa = m, fm
            fb *= 0.5
        else:
            b, fb = m, fm
            fa *= 0.5
        if b - a <= (1e-8 if pressure else 1e-12) * b:  # a peak's value is quadratic in its location error
            break
    return 0.5 * (a + b)


@nb.njit(**_JIT)
def _largest(mass, c, energy, p, F_star, pressure, yield_pressure):
    """(largest value, F_T where it is reached) of F_T (1 + c v) (or of the pressure p_T (1 + c v))
    along loading: at the stationary points of the pieces between the kinks, or at their ends."""
    ends = np.empty(4)
    n = 1
    ends[0] = 0.0
    for kink in (p[FY_], p[FB_]):
        if 0.0 < kink < F_star:
            ends[n] = kink
            n += 1
    ends[n] = F_star
    n += 1
    if n == 4 and ends[1] > ends[2]:
        ends[1], ends[2] = ends[2], ends[1]
    best = -1.0
    where = F_star
    for k in range(n - 1):
        # the piece's end, its stationary point, and the right limit at its start (where the value jumps: the
        # pressure of a board that crushed at F_b; elsewhere that limit is the previous piece's end)
        start = ends[k] * (1.0 + 1e-12) if ends[k] > 0.0 else -1.0
        for F_try in (ends[k + 1], _root_on(ends[k], ends[k + 1], mass, c, energy, p, pressure, yield_pressure),
                      start):
            if F_try <= 0.0:
                continue
            v = speed_of_energy(mass, c, energy - load_work(F_try, p))
            value = (F_try if not pressure else _pressure_at(F_try, p, yield_pressure)[0]) * (1.0 + c * v)
            if value > best:
                best = value
                where = F_try
    return best, where


@nb.njit(**_JIT)
def _piece(a, b, first_touch, F_star, unloading, mass, c, energy, p, nodes, weights):
    """∫_a^b (dδ/dF) / |v(F)| dF on one smooth piece [s].

    ``first_touch``: F = w^6 (w from a^(1/6) to b^(1/6)), smooth against the F^(−1/3) (Hertz) and
    F^(−1/2) (layer) slopes of F = 0, on [0, b] or just above it.  Otherwise F = F* − s²: 1/v grows like (F* − F)^(−1/2) towards the turn F*, and the
    substitution makes the integrand smooth on every piece, however close to the turn it ends."""
    if not first_touch:
        s_high = math.sqrt(F_star - a)
        s_low = math.sqrt(max(F_star - b, 0.0))
        if 0.0 < 2.0 * s_low < s_high:
            # a piece ending at a kink just below the turn (F* − F_b ≪ F* − a): there 1/v changes on the
            # scale s ~ √(F* − F_b) (the energy left at the kink is first order in F* − F_b, below it the
            # slope of the kinked piece takes over), so the s-range is cut geometrically, each cut resolving it
            total = 0.0
            low = s_low
            while low < s_high:
                high = min(2.0 * low, s_high)
                total += _quadrature(low, high, first_touch, F_star, unloading, mass, c, energy, p, nodes, weights)
                low = high
            return total
        return _quadrature(s_low, s_high, first_touch, F_star, unloading, mass, c, energy, p, nodes, weights)
    return _quadrature(a ** (1.0 / 6.0), b ** (1.0 / 6.0), first_touch, F_star, unloading, mass, c, energy, p, nodes,
                       weights)


@nb.njit(**_JIT)
def _quadrature(low, high, first_touch, F_star, unloading, mass, c, energy, p, nodes, weights):
    """Gauss–Legendre of (dδ/dF)/|v| over one range of the substituted variable: w from ``low`` to ``high``
    with F = w^6 (``first_touch``), else s with F = F* − s² (``_piece``)."""
    total = 0.0
    if first_touch:
        u_low = low
        width = high - low
    else:
        s_low = low
        width = high - low
    for j in range(nodes.shape[0]):
        u = 0.5 * (nodes[j] + 1.0)  # on (0, 1)
        if first_touch:  # F = w^6, w from a^(1/6) to b^(1/6): smooth against F^(−1/3), F^(−1/2) at F = 0
            w = u_low + width * u
            F = w ** 6
            jac = 6.0 * width * w ** 5
            gap = F_star - F
        else:
            s_node = s_low + width * u
            gap = s_node * s_node  # F* − F, exact even where F rounds to F*
            F = F_star - gap
            jac = 2.0 * s_node * width
        # the energy left at F, W(F*) − W(F): where the difference of the closed forms cancels to rounding
        # (right at the turn, just above a kink), its first-order value F δ'(F) (F* − F) instead
        if unloading:
            slope = _unload_slope(F, p)
            left = energy - unload_energy(F, p)
        else:
            slope = _load_slope(F, p)
            left = energy - load_work(F, p)
        if left < 1e-13 * energy:
            left = F * slope * gap
        v = rebound_speed_of_energy(mass, c, left) if unloading else speed_of_energy(mass, c, left)
        total += 0.5 * weights[j] * jac * slope / v
    return total


@nb.njit(**_JIT)
def _segment(a, b, F_star, unloading, mass, c, energy, p, nodes, weights):
    """∫_a^b (dδ/dF) / |v(F)| dF on one piece between kinks [s]; a piece from first touch, or from a
    kink well below its end, is split at its middle, the lower half taking the F = w^6 substitution."""
    if b <= a:
        return 0.0
    if a < 0.5 * b:  # first touch (a = 0), or a kink well below b: the slopes' F = 0 singularity is near
        mid = 0.5 * (a + b)
        return _piece(a, mid, True, F_star, unloading, mass, c, energy, p, nodes, weights) + \
            _piece(mid, b, False, F_star, unloading, mass, c, energy, p, nodes, weights)
    return _piece(a, b, False, F_star, unloading, mass, c, energy, p, nodes, weights)


@nb.njit(**_JIT)
def _branch_time(F_end, F_star, unloading, mass, c, energy, p, nodes, weights):
    """Time along a branch from F = 0 to ``F_end`` (≤ F*), split at the kinks F_y and F_b."""
    cuts = np.empty(4)
    n = 0
    cuts[n] = 0.0
    n += 1
    for kink in (p[FY_] if not unloading else math.inf, p[FB_]):
        if 0.0 < kink < F_end:
            cuts[n] = kink
            n += 1
    cuts[n] = F_end
    n += 1
    if n == 4 and cuts[1] > cuts[2]:
        cuts[1], cuts[2] = cuts[2], cuts[1]
    total = 0.0
    for k in range(n - 1):
        total += _segment(cuts[k], cuts[k + 1], F_star, unloading, mass, c, energy, p, nodes, weights)
    return total


@nb.njit(**_JIT)
def _pressure_at(F, p, yield_pressure):
    """Centre contact pressure of the rate-independent field at force F on loading [Pa], and the
    contact radius [m].

    Half-space: Hertz, p0 = 3F/(2π a²), a² = R δ_f (capped at p_y once yielded: Thornton's
    truncated profile).  Layer in series: a² = R (δ_f + 2 δ_L) (Hertz's a² = R δ and the rigid
    sphere on a Winkler layer's a² = 2 R δ_L) and a shape factor interpolated between Hertz's
    3/2 and the layer's paraboloid 2 by the share of each in a²: an approximation (docs/damage.md).
    Beyond the bottoming-out force F_b, the excess F − F_b presses on the substrate through the crushed pad:
    its Hertz pressure (6 (F − F_b) E*² / (π³ R²))^(1/3) if that is larger.  A board that crushed (``CR_``)
    spreads nothing beyond F_b: the whole force is the fruit's Hertz contact on the floor (a² = R δ_f)."""
    deflection_fruit = _fruit_load(F, p)[0]
    deflection_layer = _layer(F, p)[0]
    if F > p[FB_] and p[CR_] > 0.0:
        deflection_layer = 0.0
    a2 = p[R_] * (deflection_fruit + 2.0 * deflection_layer)
    if a2 <= 0.0:
        return 0.0, 0.0
    shape = (1.5 * deflection_fruit + 4.0 * deflection_layer) / (deflection_fruit + 2.0 * deflection_layer)
    pressure = shape * F / (math.pi * a2)
    if F > p[FB_] and not p[CR_] > 0.0:  # a bottomed-out pad: the force beyond F_b meets the substrate alone
        R = p[R_]
        pressure = max(pressure, (6.0 * (F - p[FB_]) * p[ES_] ** 2 / (math.pi ** 3 * R * R)) ** (1.0 / 3.0))
    return min(pressure, yield_pressure), math.sqrt(a2)


@nb.njit(**_JIT)
def _setup(mass, velocity, stiffness, radius, contact_modulus, yield_pressure, layer_stiffness, thickness, c,
           crushes):
    """(parameters p, energy the contact takes E_in [J], largest rate-independent force F* [N]),
    with the unloading branch fixed by F* (Thornton's R_p and δ_p; a board that ``crushes`` at F_b crushed when
    F* > F_b)."""
    p = np.empty(12)
    p[CR_] = 0.0
    p[K_] = stiffness
    p[R_] = radius
    p[ES_] = contact_modulus
    if yield_pressure < math.inf:
        dy = radius * (math.pi * yield_pressure / (2.0 * contact_modulus)) ** 2
        p[DY_] = dy
        p[FY_] = stiffness * dy ** 1.5
        p[KP_] = math.pi * yield_pressure * radius
    else:
        p[DY_] = math.inf
        p[FY_] = math.inf
        p[KP_] = math.inf
    p[KL_] = layer_stiffness
    p[H_] = thickness
    p[FB_] = layer_stiffness * thickness * thickness if layer_stiffness < math.inf else math.inf
    energy = mass * velocity * velocity * r_func(c * velocity)
    # undamped elastic Hertz force for the same energy: the bracket's start
    guess = stiffness ** 0.4 * (2.5 * energy) ** 0.6
    F_star = _solve_max_force(energy, p, guess)
    if crushes and F_star > p[FB_]:
        p[CR_] = 1.0
    df_star = _fruit_load(F_star, p)[0]
    if F_star > p[FY_]:
        FY = p[FY_]
        radius_p = 4.0 * contact_modulus / (3.0 * F_star) * ((2.0 * F_star + FY) / (2.0 * math.pi * yield_pressure)) ** 1.5
        p[KU_] = 4.0 / 3.0 * contact_modulus * math.sqrt(radius_p)
        p[DP_] = df_star - (F_star / p[KU_]) ** (2.0 / 3.0)
    else:
        p[KU_] = stiffness
        p[DP_] = 0.0
    return p, energy, F_star


@nb.njit(**_JIT)
def _layered_impact(mass, c, energy, returned, p, F_star, yield_pressure, nodes, weights):
    """(peak force, peak pressure, time to peak, time to the largest deflection, unloading time) walking each
    branch in the force F_T: the fruit in series with a layer (any surface, the general path)."""
    # peak force F_T (1 + c v) and peak pressure: at F* without damping; else at a stationary point
    if c > 0.0:
        peak, F_peak_T = _largest(mass, c, energy, p, F_star, False, yield_pressure)
        pressure, _ = _largest(mass, c, energy, p, F_star, True, yield_pressure)
    else:
        peak, F_peak_T = F_star, F_star
        pressure = _pressure_at(F_star, p, yield_pressure)[0]
    time_to_max = _branch_time(F_star, F_star, False, mass, c, energy, p, nodes, weights)
    time_to_peak = time_to_max
    if F_peak_T < F_star:  # the rest of loading, from the peak to the turn, is the smoother integral
        time_to_peak -= _segment(F_peak_T, F_star, F_star, False, mass, c, energy, p, nodes, weights) \
            if not (F_peak_T < p[FY_] < F_star or F_peak_T < p[FB_] < F_star) else \
            time_to_max - _branch_time(F_peak_T, F_star, False, mass, c, energy, p, nodes, weights)
    unload_time = _branch_time(F_star, F_star, True, mass, c, returned, p, nodes, weights)
    return peak, pressure, time_to_peak, time_to_max, unload_time


@nb.njit(**_JIT)
def plastic_row(mass, velocity, stiffness, radius, contact_modulus, yield_pressure, layer_stiffness,
                thickness, c, crushes, nodes, weights, out, extra):
    """One impact: the characteristics into ``out`` (``codes.CHARACTERISTIC_COLUMNS``) and
    ``PLASTIC_COLUMNS`` into ``extra``.  ``yield_pressure`` = inf: elastic fruit;
    ``layer_stiffness`` = inf: a half-space surface (no layer); ``crushes``: the layer is a board that crushes
    at its bottoming force (``crushing_characteristics``)."""
    p, energy, F_star = _setup(mass, velocity, stiffness, radius, contact_modulus, yield_pressure,
                               layer_stiffness, thickness, c, crushes)
    df_star = _fruit_load(F_star, p)[0]
    dl_star = _layer(F_star, p)[0]  # the board's depth: the same on loading and (crushed) after
    loaded = load_work(F_star, p)
    returned = unload_energy(F_star, p)
    exit_speed = rebound_speed_of_energy(mass, c, returned)

    if not layer_stiffness < math.inf and c * exit_speed < HALFSPACE_DAMPING_LIMIT:
        # a half-space: every work inverts in closed form, walk in the speed
        peak, pressure, time_to_peak, time_to_max, unload_time = halfspace_impact(
            mass, velocity, c, stiffness, p[FY_], p[DY_], p[KP_], p[KU_], radius, yield_pressure, F_star,
            exit_speed, nodes, weights)
    else:
        peak, pressure, time_to_peak, time_to_max, unload_time = _layered_impact(
            mass, c, energy, returned, p, F_star, yield_pressure, nodes, weights)
    a_star = _pressure_at(F_star, p, yield_pressure)[1]
    out[0] = peak
    out[1] = time_to_peak
    out[2] = time_to_max + unload_time
    out[3] = df_star + dl_star
    out[4] = time_to_max
    out[5] = exit_speed
    out[6] = exit_speed / velocity
    out[7] = 0.5 * mass * (velocity - exit_speed) * (velocity + exit_speed)
    out[8] = peak / time_to_peak if time_to_peak > 0.0 else math.nan
    out[9] = peak / (time_to_peak * time_to_peak) if time_to_peak > 0.0 else math.nan
    out[10] = pressure
    out[11] = a_star
    if p[FY_] < math.inf:
        W_y = load_work(p[FY_], p)
        extra[0] = speed_of_energy(mass, c, W_y) if c > 0.0 else math.sqrt(2.0 * W_y / mass)
        # m V² r(cV) = W_y: the speed_of_energy inversion solves exactly that
    else:
        extra[0] = math.inf
    extra[1] = p[DP_]
    plastic = loaded - returned
    extra[2] = plastic if plastic > 0.0 else 0.0
    extra[3] = out[7] - extra[2]
    extra[4] = p[FY_]
    extra[5] = 1.0 if F_star > p[FB_] else 0.0
    # the fruit's share of the work of deformation at the turn (the rest is the layer's)
    df, _, i_f = _fruit_load(F_star, p)
    extra[6] = (F_star * df - i_f) / loaded if loaded > 0.0 else 1.0
    if p[CR_] > 0.0:  # a crushed board keeps its F_b h/3 (its collapse): the rest of what was absorbed is the fruit's
        absorbed = out[7]
        extra[6] = max(absorbed - p[FB_] * p[H_] / 3.0, 0.0) / absorbed if absorbed > 0.0 else 0.0
    # Thornton's R_p of the flattened contact ((4/3) E* √R_p = K_p; R when it did not yield)
    extra[7] = (0.75 * p[KU_] / contact_modulus) ** 2


@nb.njit(**_JIT)
def _curve_points(mass, velocity, stiffness, radius, contact_modulus, yield_pressure, layer_stiffness, thickness,
                  c, crushes, nodes, weights, n):
    """Time [s], deflection [m], rate [m/s] and force [N] at 2n points along loading then unloading,
    parametrised by the rate-independent force (dense near the turn and the ends)."""
    p, energy, F_star = _setup(mass, velocity, stiffness, radius, contact_modulus, yield_pressure, layer_stiffness,
                               thickness, c, crushes)
    returned = unload_energy(F_star, p)
    t = np.empty(2 * n)
    d = np.empty(2 * n)
    v = np.empty(2 * n)
    f = np.empty(2 * n)
    t_max = _branch_time(F_star, F_star, False, mass, c, energy, p, nodes, weights)
    t_unload = _branch_time(F_star, F_star, True, mass, c, returned, p, nodes, weights)
    for k in range(n):
        s = k / (n - 1.0)
        F = F_star * (1.0 - (1.0 - s) ** 2) if k < n - 1 else F_star
        F = F * s  # dense at both ends: F ∝ s² near 0, F* − F ∝ (1 − s)² near the turn
        t[k] = _branch_time(F, F_star, False, mass, c, energy, p, nodes, weights) if k < n - 1 else t_max
        d[k] = _fruit_load(F, p)[0] + _layer(F, p)[0]
        v[k] = speed_of_energy(mass, c, energy - load_work(F, p))
        f[k] = F * (1.0 + c * v[k])
    for k in range(n):
        s = 1.0 - k / (n - 1.0)  # from the turn down to separation
        F = F_star * (1.0 - (1.0 - s) ** 2) * s if k > 0 else F_star
        j = n + k
        t[j] = t_max + t_unload - (_branch_time(F, F_star, True, mass, c, returned, p, nodes, weights)
                                   if k > 0 else t_unload)
        d[j] = _fruit_unload(F, p)[0] + _layer_unload(F, p)[0]
        v[j] = -rebound_speed_of_energy(mass, c, returned - unload_energy(F, p))
        f[j] = F * (1.0 + c * v[j])
    return t, d, v, f


def plastic_curves(points: int, mass, velocity, stiffness, radius, contact_modulus, yield_pressure=math.inf,
                   layer_stiffness=math.inf, thickness=math.inf, damping_factor=0.0, crushes=False):
    """δ(t), δ̇(t), F(t) of one elastic–plastic impact on ``points`` equally spaced times over [0, T]:
    (time [s], deflection [m], rate [m/s], force [N]) arrays, interpolated linearly between 2 × 400 exact points
    along the loading and unloading branches.  ``crushes``: the layer is a board that crushes at its bottoming
    force (``crushing_characteristics``)."""
    nodes, weights = gauss_jacobi(NODES, 0.0, 0.0)
    t, d, v, f = _curve_points(float(mass), float(velocity), float(stiffness), float(radius),
                               float(contact_modulus), float(yield_pressure), float(layer_stiffness),
                               float(thickness), float(damping_factor), bool(crushes), np.ascontiguousarray(nodes),
                               np.ascontiguousarray(weights), 400)
    order = np.argsort(t, kind="stable")
    t, d, v, f = t[order], d[order], v[order], f[order]
    keep = np.concatenate(([True], np.diff(t) > 0.0))
    t, d, v, f = t[keep], d[keep], v[keep], f[keep]
    grid = np.linspace(0.0, t[-1], int(points))
    return grid, np.interp(grid, t, d), np.interp(grid, t, v), np.interp(grid, t, f)


@nb.njit(parallel=True, **_JIT)
def _kernel(mass, velocity, stiffness, radius, modulus, yield_pressure, layer, thickness, c, crushes, nodes, weights,
            out, extra):
    for i in nb.prange(mass.shape[0]):
        plastic_row(mass[i], velocity[i], stiffness[i], radius[i], modulus[i], yield_pressure[i], layer[i],
                    thickness[i], c[i], crushes, nodes, weights, out[i], extra[i])


@nb.njit(**_JIT)
def _kernel_serial(mass, velocity, stiffness, radius, modulus, yield_pressure, layer, thickness, c, crushes, nodes,
                   weights, out, extra):
    for i in range(mass.shape[0]):
        plastic_row(mass[i], velocity[i], stiffness[i], radius[i], modulus[i], yield_pressure[i], layer[i],
                    thickness[i], c[i], crushes, nodes, weights, out[i], extra[i])


def plastic_characteristics(mass, velocity, stiffness, radius, contact_modulus, yield_pressure=math.inf,
                            layer_stiffness=math.inf, thickness=math.inf, damping_factor=0.0,
                            parallel: bool | None = None, crushes: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Characteristics of elastic–plastic impacts, one row per impact.

    Parameters
    ----------
    mass : array_like
        (Reduced) mass m [kg].
    velocity : array_like
        Impact (approach) velocity V > 0 [m/s].
    stiffness : array_like
        Hertz stiffness of the fruit's contact K = (4/3) E* √R [N/m^1.5].
    radius : array_like
        Effective radius R [m].
    contact_modulus : array_like
        E* [Pa] of the fruit's contact (with the layer's substrate taken as rigid).
    yield_pressure : array_like
        Thornton's limiting contact pressure p_y [Pa]; inf: elastic.
    layer_stiffness : array_like
        K_L = π k R [N/m²] of a Winkler layer (``winkler_stiffness``); inf: no layer.
    thickness : array_like
        Layer thickness h [m] (bottoming out at δ_L = h); inf: never bottoms out.
    damping_factor : array_like
        c [s/m] of F = F_T (1 + c δ̇); 0: no viscous damping.
    crushes : bool
        The layer is a board that crushes where it would bottom out (``crushing_characteristics``).

    Returns
    -------
    characteristics : ndarray (rows, 12)
        ``codes.CHARACTERISTIC_COLUMNS`` [SI].
    plastic : ndarray (rows, 6)
        ``PLASTIC_COLUMNS``: yield velocity [m/s] (inf: elastic), permanent deflection δ_p [m],
        plastic work W_p [J], viscous work W_v [J], yield force F_y [N], 1 where the layer
        bottomed out, the fruit's share of the work of deformation at the largest force, and the
        radius R_p [m] of the flattened contact that unloads (R where it did not yield).  Inputs are not validated here: validate at the boundary.
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                   (mass, velocity, stiffness, radius, contact_modulus, yield_pressure,
                                    layer_stiffness, thickness, damping_factor)))
    arrays = [np.ascontiguousarray(a.ravel()) for a in arrays]
    rows = arrays[0].shape[0]
    out = np.empty((rows, N_CHARACTERISTICS))
    extra = np.empty((rows, N_PLASTIC))
    nodes, weights = gauss_jacobi(NODES, 0.0, 0.0)
    kernel = _kernel if (parallel if parallel is not None else rows > PARALLEL_MIN_ROWS) else _kernel_serial
    kernel(*arrays, bool(crushes), np.ascontiguousarray(nodes), np.ascontiguousarray(weights), out, extra)
    return out, extra


def crushing_characteristics(mass, velocity, stiffness, radius, contact_modulus, yield_pressure, layer_stiffness,
                             crush_depth, damping_factor) -> tuple[np.ndarray, np.ndarray]:
    """Impacts on a board that crushes (corrugated cardboard, issue 14 item 3), one row per impact.

    The board is the Winkler layer of ``plastic_characteristics`` up to its crush depth δ_c [m] (where the
    centre pressure k δ_L reaches its flat-crush strength σ_c: δ_c = σ_c/k).  An impact that does not reach
    the crush force F_c = K_L δ_c² is that layer impact.  One that does crushes the flutes: the board stays
    flat at δ_c and carries the whole force to the floor, so the fruit goes on as on a rigid half-space, from
    its own deflection and speed at F_c (the same first integral, walked on: the board's work K_L δ_c³/3 and
    the viscous work before the crush are spent), and unloads alone: the crushed board gives nothing back.
    Its pressure beyond F_c is the fruit's Hertz contact on the floor (the board no longer spreads it).
    Reported for those rows: ``bottomed_out`` 1, the plastic work (the loop ∮F_T dδ) holding the board's
    K_L δ_c³/3 (its flutes collapse for good), and as the fruit's share the rest of the absorbed energy (its
    own plastic work and the viscous work of its law, as before the change to this walk-on model).  Without damping this is the rigid impact at
    V' = √(V² − 2 K_L δ_c³/(3m)), as energy says.  Arguments as for ``plastic_characteristics``."""
    return plastic_characteristics(mass, velocity, stiffness, radius, contact_modulus, yield_pressure,
                                   layer_stiffness, crush_depth, damping_factor, crushes=True)


__all__ = ["N_PLASTIC", "PLASTIC_COLUMNS", "crushing_characteristics", "plastic_characteristics", "plastic_curves",
           "winkler_stiffness", "yield_force", "yield_pressure_of_force"]
