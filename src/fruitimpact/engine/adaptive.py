"""Adaptive Runge–Kutta integration of one impact, with exact event location.

For the force laws of ``engine.forces`` that have no first integral (and for
the power law too, as a cross-check of ``engine.powerlaw``):

    m δ̈ = -F(δ, δ̇),   δ(0) = 0,   δ̇(0) = v0 > 0,

in contact until separation.  Plain floats and arrays in, plain arrays out;
no I/O, no unit conversion (SI throughout).

Method
------
Dormand & Prince's explicit Runge–Kutta pair of order 8 with the 5th/3rd
order error estimators and the 7th-order dense output (DOP853: Hairer,
Nørsett & Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.
1993, §II.10; coefficients as in Hairer's ``dop853.f`` and SciPy's
``solve_ivp``).  The integration runs in units of the impact (``_scales``):
lengths in δ_ref (the elastic part's undamped maximum deflection), times in
t_ref = δ_ref/v0, masses in m.  So every impact with the same dimensionless
damping is the same computation, nothing inside it under- or overflows, and
the local error is measured against rtol·δ_ref for δ and rtol·v0 for δ̇:
``rtol`` is a relative accuracy of the characteristics.  Step-size control as
in DOP853 (safety 0.9, factors 0.2–10, no growth right after a rejection).
An impact whose scales (δ_ref, t_ref, m v0/t_ref, m v0²) are not normal
doubles, or whose characteristics are not once scaled back, is NaN.

The laws with δ^0.5 or δ^0.25 factors (and δ^n) make the motion
non-smooth in t at δ = 0: near first touch and separation δ(t) is a series
in t^(1/4) or t^(1/2), and an explicit RK method crawls there.  So the
impact is integrated in three phases (``_integrate``):

A. from first touch until δ = 0.1·δ_ref (or δ̇ = v0/2), in σ = δ^(1/q)
   with state (t, δ̇): dt/dσ = qσ^(q-1)/δ̇, dδ̇/dσ = -qσ^(q-1) F/(m δ̇),
   q = 4 for δ^0.25, 2 for δ^0.5 and δ^1.5, 1 for Kelvin–Voigt, where the
   laws are polynomials in σ and the motion is smooth (δ̇ stays ≥ v0/2);
B. in t with state (δ, δ̇) through the maximum deflection;
C. in σ again from δ ≈ 0.3·δ_max in restitution down to σ = 0 exactly:
   separation is the end of the interval, not an event on a singular curve.

Clamped laws are integrated unclamped: until separation they coincide
(the force is positive in compression and contact ends where it first
vanishes), and the smooth continuation puts the release event on a smooth
interpolant instead of across a kink.

Events are located on the dense output of the step in which they occur, by
a bracketing (Illinois) root finder, never read off a grid:

* separation: σ = 0 (the end of phase C), or, clamped, the unclamped force
  F = 0 while δ̇ < 0 if that comes first (located as the sign change of F
  divided by its lowest power of δ, ``_release``); the exit velocity is δ̇
  there, from a step of the integrator to that point (8th order, where the
  interpolant is 7th: e is read to the integration's accuracy);
* maximum deflection: δ̇(t) = 0;
* peak force: dF/dt = ∂F/∂δ·δ̇ + ∂F/∂δ̇·δ̈ = 0 (analytic, with δ̈ = -F/m),
  crossing from + to -; the force at first touch (b·v0 for Kelvin–Voigt,
  the peak where dF/dt(0) = v0 k (1 - 4ζ²) ≤ 0) is a candidate too;
* peak Hertz pressure 3F/(2πRδ): d(F/δ)/dt = 0, crossing from + to -, and
  the limits of F/δ at the ends of the contact.  Where a dissipative term
  vanishes more slowly than δ at first touch (Kelvin–Voigt b > 0,
  Kuwabara–Kono B > 0, Tsuji η > 0, power law n < 1) F/δ is unbounded and
  the maximum pressure is +inf.

Both event functions are dF/dt and d(F/δ)/dt times the lowest power of δ
that keeps them finite at δ = 0 (``_rates``): there they are the rates'
leading terms, not 0, so an extremum inside the very first step (Kelvin–Voigt
with ζ just below 1/2 peaks at t ≈ 1e-6 of the contact) is bracketed from the
step's start and found to its own size.

Conventions follow ``engine.rk4``/``engine.powerlaw``: firmness_c is
F_max/t_peak and firmness_c_star F_max/t_peak² (NaN when the peak force is
at first touch), exit velocity positive.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.codes import (ABSORBED_ENERGY, CHARACTERISTIC_COLUMNS, KELVIN_VOIGT, KUWABARA_KONO, MAX_PRESSURE,
                    N_CHARACTERISTICS, POWER_LAW, TIME_TO_PEAK)
from fruitimpact.engine.forces import contact_force, pressure_ratio
from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.powerlaw import PARALLEL_MIN_ROWS, fill_characteristics

_JIT = dict(cache=CACHE, error_model="numpy")

#: Default relative accuracy of the characteristics.
DEFAULT_RTOL = 1e-10
#: Accepted steps allowed per impact before giving up (return -1).
MAX_STEPS = 100_000

_SAFETY = 0.9
_MIN_FACTOR = 0.2
_MAX_FACTOR = 10.0

# ---------------------------------------------------------------------------
# DOP853 coefficients (Hairer's dop853.f; identical to SciPy's
# scipy/integrate/_ivp/dop853_coefficients.py).  Stages 0–11 make the step,
# stage 12 is f at the new point (FSAL), stages 13–15 serve the dense output.
# ---------------------------------------------------------------------------
_C = np.array([0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274,
               0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077,
               0.6512820512820513, 0.6, 0.8571428571428571, 1.0, 1.0, 0.1, 0.2,
               0.7777777777777778])

_A = np.zeros((16, 16))
_A[1, 0] = 5.26001519587677318785587544488e-2
_A[2, :2] = [1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2]
_A[3, [0, 2]] = [2.95875854768068491816892993775e-2, 8.87627564304205475450678981324e-2]
_A[4, [0, 2, 3]] = [2.41365134159266685502369798665e-1, -8.84549479328286085344864962717e-1,
                    9.24834003261792003115737966543e-1]
_A[5, [0, 3, 4]] = [3.7037037037037037037037037037e-2, 1.70828608729473871279604482173e-1,
                    1.25467687566822425016691814123e-1]
_A[6, [0, 3, 4, 5]] = [3.7109375e-2, 1.70252211019544039314978060272e-1,
                       6.02165389804559606850219397283e-2, -1.7578125e-2]
_A[7, [0, 3, 4, 5, 6]] = [3.70920001185047927108779319836e-2, 1.70383925712239993810214054705e-1,
                          1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
                          8.27378916381402288758473766002e-3]
_A[8, [0, 3, 4, 5, 6, 7]] = [6.24110958716075717114429577812e-1, -3.36089262944694129406857109825,
                             -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
                             2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1]
_A[9, [0, 3, 4, 5, 6, 7, 8]] = [4.77662536438264365890433908527e-1, -2.48811461997166764192642586468,
                                -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
                                1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
                                -2.03312017085086261358222928593e-2]
_A[10, [0, 3, 4, 5, 6, 7, 8, 9]] = [-9.3714243008598732571704021658e-1, 5.18637242884406370830023853209,
                                    1.09143734899672957818500254654, -8.14978701074692612513997267357,
                                    -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
                                    2.49360555267965238987089396762, -3.0467644718982195003823669022]
_A[11, [0, 3, 4, 5, 6, 7, 8, 9, 10]] = [2.27331014751653820792359768449, -1.05344954667372501984066689879e1,
                                        -2.00087205822486249909675718444, -1.79589318631187989172765950534e1,
                                        2.79488845294199600508499808837e1, -2.85899827713502369474065508674,
                                        -8.87285693353062954433549289258, 1.23605671757943030647266201528e1,
                                        6.43392746015763530355970484046e-1]
_A[12, [0, 5, 6, 7, 8, 9, 10, 11]] = [5.42937341165687622380535766363e-2, 4.45031289275240888144113950566,
                                      1.89151789931450038304281599044, -5.8012039600105847814672114227,
                                      3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
                                      2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2]
_A[13, [0, 6, 7, 8, 9, 10, 11, 12]] = [5.61675022830479523392909219681e-2, 2.53500210216624811088794765333e-1,
                                       -2.46239037470802489917441475441e-1, -1.24191423263816360469010140626e-1,
                                       1.5329179827876569731206322685e-1, 8.20105229563468988491666602057e-3,
                                       7.56789766054569976138603589584e-3, -8.298e-3]
_A[14, [0, 5, 6, 7, 10, 11, 12, 13]] = [3.18346481635021405060768473261e-2, 2.83009096723667755288322961402e-2,
                                        5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2,
                                        -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4,
                                        -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1]
_A[15, [0, 5, 6, 7, 8, 12, 13, 14]] = [-4.28896301583791923408573538692e-1, -4.69762141536116384314449447206,
                                       7.68342119606259904184240953878, 4.06898981839711007970213554331,
                                       3.56727187455281109270669543021e-1, -1.39902416515901462129418009734e-3,
                                       2.9475147891527723389556272149, -9.15095847217987001081870187138]

_B = _A[12, :12].copy()
_E5 = np.array([0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502,
                1.6643771824549864, -0.35032884874997366, 0.3341791187130175, 0.08192320648511571,
                -0.022355307863886294, 0.0])
_E3 = np.array([-0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
                -5.801203960010585, -0.4226823213237919, -0.1521609496625161, 0.20136540080403034,
                0.02265179219836082, 0.0])
_D = np.array([
    [-8.428938276109013, 0.0, 0.0, 0.0, 0.0, 0.5667149535193777, -3.0689499459498917, 2.38466765651207,
     2.117034582445028, -0.871391583777973, 2.2404374302607883, 0.6315787787694688, -0.08899033645133331,
     18.148505520854727, -9.194632392478356, -4.436036387594894],
    [10.427508642579134, 0.0, 0.0, 0.0, 0.0, 242.28349177525817, 165.20045171727028, -374.5467547226902,
     -22.113666853125306, 7.733432668472264, -30.674084731089398, -9.332130526430229, 15.697238121770845,
     -31.139403219565178, -9.35292435884448, 35.81684148639408],
    [19.985053242002433, 0.0, 0.0, 0.0, 0.0, -387.0373087493518, -189.17813819516758, 527.8081592054236,
     -11.57390253995963, 6.8812326946963, -1.0006050966910838, 0.7777137798053443, -2.778205752353508,
     -60.19669523126412, 84.32040550667716, 11.99229113618279],
    [-25.69393346270375, 0.0, 0.0, 0.0, 0.0, -154.18974869023643, -231.5293791760455, 357.6391179106141,
     93.40532418362432, -37.45832313645163, 104.0996495089623, 29.8402934266605, -43.53345659001114,
     96.32455395918828, -39.17726167561544, -149.72683625798564],
])


#: Smallest positive normal double: below it a number has lost precision.
_TINY = 2.2250738585072014e-308


@nb.njit(**_JIT)
def _normal(x):
    """x is a positive, finite, normal double."""
    return x >= _TINY and x < math.inf


@nb.njit(**_JIT)
def _scales(family, params, mass, velocity, scaled):
    """(ok, δ_ref [m], t_ref [s], F_ref [N]) of one impact, and in ``scaled``
    the law's parameters in these units, where m = v0 = δ_ref = 1.

    δ_ref is the maximum deflection of the law's elastic part without damping
    (½ m v0² = ∫ F_el dδ), written without v0² so that it does not underflow
    before the scales do; t_ref = δ_ref/v0 and F_ref = m v0/t_ref.  The
    elastic coefficient becomes (n+1)/2, 1 or 5/4, and the damping its
    dimensionless group: c v0, b t_ref/m = 2ζ, B/t_ref, η δ_ref^(1/4) t_ref/m.
    ``ok`` is False where a scale, the energy scale m v0² or a scaled
    parameter is not a finite normal number (the impact's scales under- or
    overflow), or without an elastic part (the fruit never comes back)."""
    if family == POWER_LAW:
        n = params[1]
        delta_ref = (0.5 * (n + 1.0) * mass / params[0]) ** (1.0 / (n + 1.0)) * velocity ** (2.0 / (n + 1.0))
    elif family == KELVIN_VOIGT:
        delta_ref = velocity * math.sqrt(mass / params[0])
    else:  # Kuwabara–Kono and Tsuji: elastic part K δ^1.5
        delta_ref = (1.25 * mass / params[0]) ** 0.4 * velocity ** 0.8
    time_ref = delta_ref / velocity
    force_ref = mass * velocity / time_ref
    scaled[2] = 0.0
    if family == POWER_LAW:
        scaled[0] = 0.5 * (params[1] + 1.0)
        scaled[1] = params[1]
        scaled[2] = params[2] * velocity
    elif family == KELVIN_VOIGT:
        scaled[0] = 1.0
        scaled[1] = params[1] * time_ref / mass
    elif family == KUWABARA_KONO:
        scaled[0] = 1.25
        scaled[1] = params[1] / time_ref
    else:  # TSUJI
        scaled[0] = 1.25
        scaled[1] = params[1] * time_ref / mass * math.sqrt(math.sqrt(delta_ref))
    ok = (_normal(mass) and _normal(velocity) and _normal(delta_ref) and _normal(time_ref)
          and _normal(force_ref) and _normal(mass * velocity * velocity))
    for j in range(3):
        ok = ok and abs(scaled[j]) < math.inf
    return ok, delta_ref, time_ref, force_ref


@nb.njit(**_JIT)
def _rates(family, params, clamp, d, v):
    """(F, g, r) at the state (δ, δ̇): F the force that drives the motion
    (clamped if ``clamp``), g = δ^a·dF/dt and r = δ^b·d(F/δ)/dt with the
    smallest powers that keep them finite at δ = 0 (a, b = 1 - n, 2 - n for
    the power law; 0, 2 Kelvin–Voigt; 1/2, 3/2 Kuwabara–Kono; 3/4, 7/4
    Tsuji).  They have the signs of the rates, and at first touch they are
    the rates' leading terms instead of 0, so an extremum inside the first
    step is bracketed from its start.  dF/dt = F_δ δ̇ + F_δ̇ δ̈, δ̈ = -F (m = 1,
    as everywhere inside the integration: see ``_scales``)."""
    force = contact_force(family, params, d, v, clamp)
    if d < 0.0:
        d = 0.0
    if clamp and force <= 0.0:
        return force, 0.0, 0.0
    a = -force
    if family == POWER_LAW:
        # F = K δ^n (1 + c δ̇):  dF/dt = K δ^(n-1) [n δ̇ (1 + c δ̇) + c δ δ̈]
        rise = v * (1.0 + params[2] * v)
        dash = params[2] * d * a
        g = params[0] * (params[1] * rise + dash)
        r = params[0] * ((params[1] - 1.0) * rise + dash)
    elif family == KELVIN_VOIGT:
        # F = k δ + b δ̇:  dF/dt = k δ̇ + b δ̈,  δ² d(F/δ)/dt = b (δ δ̈ - δ̇²)
        g = params[0] * v + params[1] * a
        r = params[1] * (d * a - v * v)
    elif family == KUWABARA_KONO:
        # F = K (δ^1.5 + B δ^0.5 δ̇):  δ^0.5 dF/dt = K (1.5 δ δ̇ + B (0.5 δ̇² + δ δ̈))
        g = params[0] * (1.5 * d * v + params[1] * (0.5 * v * v + d * a))
        r = params[0] * (0.5 * d * v + params[1] * (d * a - 0.5 * v * v))
    else:  # TSUJI
        # F = K δ^1.5 + η δ^0.25 δ̇:  δ^0.75 dF/dt = 1.5 K δ^1.25 δ̇ + η (0.25 δ̇² + δ δ̈)
        elastic = params[0] * d * math.sqrt(math.sqrt(d)) * v
        g = 1.5 * elastic + params[1] * (0.25 * v * v + d * a)
        r = 0.5 * elastic + params[1] * (d * a - 0.75 * v * v)
    return force, g, r


@nb.njit(**_JIT)
def _release(family, params, d, v):
    """The unclamped force divided by its lowest power of δ (δ^n, 1, δ^0.5,
    δ^0.25): same sign as F for δ > 0, but not forced to 0 at δ = 0, so that
    a clamped law's release (F = 0 at δ > 0) is a simple sign change."""
    if d < 0.0:
        d = 0.0
    if family == POWER_LAW:
        return params[0] * (1.0 + params[2] * v)
    if family == KELVIN_VOIGT:
        return params[0] * d + params[1] * v
    if family == KUWABARA_KONO:
        return params[0] * (d + params[1] * v)
    return params[0] * d * math.sqrt(math.sqrt(d)) + params[1] * v


@nb.njit(**_JIT)
def _ratio_limit(family, params, clamp, rate):
    """lim F/δ [N/m] as δ → 0+ at rate δ̇ (±inf where unbounded)."""
    if family == POWER_LAW:
        n = params[1]
        factor = params[0] * (1.0 + params[2] * rate)
        if n > 1.0:
            limit = 0.0
        elif n == 1.0:
            limit = factor
        else:
            limit = math.inf * factor if factor != 0.0 else 0.0
    elif family == KELVIN_VOIGT:
        dash = params[1] * rate
        limit = params[0] if dash == 0.0 else math.inf * dash
    else:  # Kuwabara–Kono (K B δ^0.5 δ̇), Tsuji (η δ^0.25 δ̇)
        dash = params[0] * params[1] * rate if family == KUWABARA_KONO else params[1] * rate
        limit = 0.0 if dash == 0.0 else math.inf * dash
    if clamp and limit < 0.0:
        return 0.0
    return limit


@nb.njit(**_JIT)
def _substitution_power(family, params):
    """Integer q of the substitution δ = σ^q that makes the law a smooth
    (polynomial) function of σ near δ = 0: δ^0.5 → q = 2, δ^0.25 → q = 4."""
    if family == KELVIN_VOIGT:
        return 1
    if family == KUWABARA_KONO:
        return 2
    if family == POWER_LAW:
        n = params[1]
        if n == math.floor(n):
            return 1
        if 2.0 * n == math.floor(2.0 * n):
            return 2
    return 4


@nb.njit(**_JIT)
def _rhs(mode, q, family, params, x, y1, y2):
    """Right-hand side (m = 1).  mode 0: x = t, y = (δ, δ̇), y' = (δ̇, -F).
    mode 1: x = σ = δ^(1/q), y = (t, δ̇), dy/dσ = (1, -F)·q σ^(q-1)/δ̇.
    F is the unclamped law: until separation a clamped law equals it (it is
    positive in compression, and contact ends where it first vanishes in
    restitution), and its smooth continuation past that event lets the
    event be located on a smooth interpolant instead of across a kink."""
    if mode == 0:
        return y2, -contact_force(family, params, y1, y2, False)
    s = x if x > 0.0 else 0.0
    if q == 1:
        p = 1.0
    elif q == 2:
        p = s
    else:
        p = s * s * s
    w = q * p / y2
    return w, -contact_force(family, params, p * s, y2, False) * w


@nb.njit(**_JIT)
def _step(mode, q, family, params, x, y1, y2, h, k1, k2):
    """One DOP853 step of size h from (x, y) with k1[0], k2[0] = f(x, y) set.
    Fills stages 1–12 (12: f at the new point) and returns the new y.
    Written out over the nonzero coefficients: twice as fast as loops."""
    a0 = k1[0]
    b0 = k2[0]
    d1 = y1 + h * (_A[1, 0] * a0)
    d2 = y2 + h * (_A[1, 0] * b0)
    a1, b1 = _rhs(mode, q, family, params, x + _C[1] * h, d1, d2)
    d1 = y1 + h * (_A[2, 0] * a0 + _A[2, 1] * a1)
    d2 = y2 + h * (_A[2, 0] * b0 + _A[2, 1] * b1)
    a2, b2 = _rhs(mode, q, family, params, x + _C[2] * h, d1, d2)
    d1 = y1 + h * (_A[3, 0] * a0 + _A[3, 2] * a2)
    d2 = y2 + h * (_A[3, 0] * b0 + _A[3, 2] * b2)
    a3, b3 = _rhs(mode, q, family, params, x + _C[3] * h, d1, d2)
    d1 = y1 + h * (_A[4, 0] * a0 + _A[4, 2] * a2 + _A[4, 3] * a3)
    d2 = y2 + h * (_A[4, 0] * b0 + _A[4, 2] * b2 + _A[4, 3] * b3)
    a4, b4 = _rhs(mode, q, family, params, x + _C[4] * h, d1, d2)
    d1 = y1 + h * (_A[5, 0] * a0 + _A[5, 3] * a3 + _A[5, 4] * a4)
    d2 = y2 + h * (_A[5, 0] * b0 + _A[5, 3] * b3 + _A[5, 4] * b4)
    a5, b5 = _rhs(mode, q, family, params, x + _C[5] * h, d1, d2)
    d1 = y1 + h * (_A[6, 0] * a0 + _A[6, 3] * a3 + _A[6, 4] * a4 + _A[6, 5] * a5)
    d2 = y2 + h * (_A[6, 0] * b0 + _A[6, 3] * b3 + _A[6, 4] * b4 + _A[6, 5] * b5)
    a6, b6 = _rhs(mode, q, family, params, x + _C[6] * h, d1, d2)
    d1 = y1 + h * (_A[7, 0] * a0 + _A[7, 3] * a3 + _A[7, 4] * a4 + _A[7, 5] * a5 + _A[7, 6] * a6)
    d2 = y2 + h * (_A[7, 0] * b0 + _A[7, 3] * b3 + _A[7, 4] * b4 + _A[7, 5] * b5 + _A[7, 6] * b6)
    a7, b7 = _rhs(mode, q, family, params, x + _C[7] * h, d1, d2)
    d1 = y1 + h * (_A[8, 0] * a0 + _A[8, 3] * a3 + _A[8, 4] * a4 + _A[8, 5] * a5 + _A[8, 6] * a6
            + _A[8, 7] * a7)
    d2 = y2 + h * (_A[8, 0] * b0 + _A[8, 3] * b3 + _A[8, 4] * b4 + _A[8, 5] * b5 + _A[8, 6] * b6
            + _A[8, 7] * b7)
    a8, b8 = _rhs(mode, q, family, params, x + _C[8] * h, d1, d2)
    d1 = y1 + h * (_A[9, 0] * a0 + _A[9, 3] * a3 + _A[9, 4] * a4 + _A[9, 5] * a5 + _A[9, 6] * a6
            + _A[9, 7] * a7 + _A[9, 8] * a8)
    d2 = y2 + h * (_A[9, 0] * b0 + _A[9, 3] * b3 + _A[9, 4] * b4 + _A[9, 5] * b5 + _A[9, 6] * b6
            + _A[9, 7] * b7 + _A[9, 8] * b8)
    a9, b9 = _rhs(mode, q, family, params, x + _C[9] * h, d1, d2)
    d1 = y1 + h * (_A[10, 0] * a0 + _A[10, 3] * a3 + _A[10, 4] * a4 + _A[10, 5] * a5 + _A[10, 6] * a6
            + _A[10, 7] * a7 + _A[10, 8] * a8 + _A[10, 9] * a9)
    d2 = y2 + h * (_A[10, 0] * b0 + _A[10, 3] * b3 + _A[10, 4] * b4 + _A[10, 5] * b5 + _A[10, 6] * b6
            + _A[10, 7] * b7 + _A[10, 8] * b8 + _A[10, 9] * b9)
    a10, b10 = _rhs(mode, q, family, params, x + _C[10] * h, d1, d2)
    d1 = y1 + h * (_A[11, 0] * a0 + _A[11, 3] * a3 + _A[11, 4] * a4 + _A[11, 5] * a5 + _A[11, 6] * a6
            + _A[11, 7] * a7 + _A[11, 8] * a8 + _A[11, 9] * a9 + _A[11, 10] * a10)
    d2 = y2 + h * (_A[11, 0] * b0 + _A[11, 3] * b3 + _A[11, 4] * b4 + _A[11, 5] * b5 + _A[11, 6] * b6
            + _A[11, 7] * b7 + _A[11, 8] * b8 + _A[11, 9] * b9 + _A[11, 10] * b10)
    a11, b11 = _rhs(mode, q, family, params, x + _C[11] * h, d1, d2)
    y1_new = y1 + h * (_B[0] * a0 + _B[5] * a5 + _B[6] * a6 + _B[7] * a7 + _B[8] * a8 + _B[9] * a9
            + _B[10] * a10 + _B[11] * a11)
    y2_new = y2 + h * (_B[0] * b0 + _B[5] * b5 + _B[6] * b6 + _B[7] * b7 + _B[8] * b8 + _B[9] * b9
            + _B[10] * b10 + _B[11] * b11)
    a12, b12 = _rhs(mode, q, family, params, x + h, y1_new, y2_new)
    k1[1] = a1
    k2[1] = b1
    k1[2] = a2
    k2[2] = b2
    k1[3] = a3
    k2[3] = b3
    k1[4] = a4
    k2[4] = b4
    k1[5] = a5
    k2[5] = b5
    k1[6] = a6
    k2[6] = b6
    k1[7] = a7
    k2[7] = b7
    k1[8] = a8
    k2[8] = b8
    k1[9] = a9
    k2[9] = b9
    k1[10] = a10
    k2[10] = b10
    k1[11] = a11
    k2[11] = b11
    k1[12] = a12
    k2[12] = b12
    return y1_new, y2_new


@nb.njit(**_JIT)
def _error_norm(k1, k2, h, rtol):
    """DOP853's combined 5th/3rd-order error estimate (≤ 1: accept), every
    component measured against rtol (the state is in units of the impact)."""
    e51 = 0.0
    e52 = 0.0
    e31 = 0.0
    e32 = 0.0
    for j in range(12):
        e51 += _E5[j] * k1[j]
        e52 += _E5[j] * k2[j]
        e31 += _E3[j] * k1[j]
        e32 += _E3[j] * k2[j]
    e51 /= rtol
    e52 /= rtol
    e31 /= rtol
    e32 /= rtol
    err5 = e51 * e51 + e52 * e52
    err3 = e31 * e31 + e32 * e32
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * 2.0)


@nb.njit(**_JIT)
def _dense_setup(mode, q, family, params, x, y1, y2, h, y1_new, y2_new, k1, k2, c1, c2):
    """Coefficients of DOP853's 7th-order interpolant on the last step
    (three more stages)."""
    for s in range(13, 16):
        s1 = 0.0
        s2 = 0.0
        for j in range(s):
            a = _A[s, j]
            s1 += a * k1[j]
            s2 += a * k2[j]
        k1[s], k2[s] = _rhs(mode, q, family, params, x + _C[s] * h, y1 + h * s1, y2 + h * s2)
    d1 = y1_new - y1
    d2 = y2_new - y2
    c1[0] = d1
    c2[0] = d2
    c1[1] = h * k1[0] - d1
    c2[1] = h * k2[0] - d2
    c1[2] = 2.0 * d1 - h * (k1[12] + k1[0])
    c2[2] = 2.0 * d2 - h * (k2[12] + k2[0])
    for i in range(4):
        s1 = 0.0
        s2 = 0.0
        for j in range(16):
            s1 += _D[i, j] * k1[j]
            s2 += _D[i, j] * k2[j]
        c1[3 + i] = h * s1
        c2[3 + i] = h * s2


@nb.njit(**_JIT)
def _dense(theta, y0, coef):
    """Interpolant at θ = (x - x_old)/h in [0, 1]."""
    y = 0.0
    for i in range(6, -1, -1):
        y += coef[i]
        if i % 2 == 0:
            y *= theta
        else:
            y *= 1.0 - theta
    return y0 + y


@nb.njit(**_JIT)
def _state(mode, q, theta, x, h, y1, y2, c1, c2):
    """(t, δ, δ̇) at θ on the interpolant of the last step."""
    a = _dense(theta, y1, c1)
    v = _dense(theta, y2, c2)
    if mode == 0:
        return x + theta * h, a, v
    s = x + theta * h
    if s < 0.0:
        s = 0.0
    return a, s ** q, v


@nb.njit(**_JIT)
def _event(kind, theta, target, mode, q, family, params, clamp, x, h, y1, y2, c1, c2):
    """Event function at θ: 1 δ̇, 2 dF/dt and 3 d(F/δ)/dt (scaled as in
    ``_rates``), 4 the sign of the unclamped F (``_release``), 5 t - target."""
    t, d, v = _state(mode, q, theta, x, h, y1, y2, c1, c2)
    if kind == 1:
        return v
    if kind == 4:
        return _release(family, params, d, v)
    if kind == 5:
        return t - target
    force, g, hp = _rates(family, params, clamp, d, v)
    return g if kind == 2 else hp


@nb.njit(**_JIT)
def _locate(kind, theta_end, f_end, mode, q, family, params, clamp, x, h, y1, y2, c1, c2):
    """(t, δ, δ̇) where event ``kind`` (2: dF/dt, 3: d(F/δ)/dt) vanishes inside the
    last step, from its value at the step start and ``f_end`` at ``theta_end``."""
    f_start = _event(kind, 0.0, 0.0, mode, q, family, params, clamp, x, h, y1, y2, c1, c2)
    theta = _root(kind, 0.0, f_start, theta_end, f_end, 0.0, mode, q, family, params, clamp,
                  x, h, y1, y2, c1, c2)
    return _state(mode, q, theta, x, h, y1, y2, c1, c2)


@nb.njit(**_JIT)
def _root(kind, lo, f_lo, hi, f_hi, target, mode, q, family, params, clamp, x, h, y1, y2, c1, c2):
    """θ in [lo, hi] where event ``kind`` changes sign (f_lo, f_hi of
    opposite signs or zero), by the Illinois variant of regula falsi,
    to 1e-13 of θ (the step is a fraction of the contact)."""
    if f_lo == 0.0:
        return lo
    if f_hi == 0.0:
        return hi
    side = 0
    theta = lo
    for _ in range(100):
        theta = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        f = _event(kind, theta, target, mode, q, family, params, clamp, x, h, y1, y2, c1, c2)
        if f == 0.0:
            return theta
        if (f > 0.0) == (f_hi > 0.0):
            hi = theta
            f_hi = f
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            lo = theta
            f_lo = f
            if side == -1:
                f_hi *= 0.5
            side = -1
        if hi - lo <= 1e-13 * hi:  # relative: an event near θ = 0 is found to its own size
            break
    return theta


#: Phase switches: first-touch phase in σ until δ = _SWITCH_A·δ_ref (or δ̇
#: has fallen to half of v0); last phase in σ from δ ≈ _SWITCH_C·δ_max.
_SWITCH_A = 0.1
_SWITCH_C = 0.3


@nb.njit(**_JIT)
def _integrate(family, params, clamp, mass, velocity, radius, rtol, out,
               times, curve_d, curve_v, curve_f, work):
    """Integrate one impact; fill ``out`` (characteristics) and, at the
    ascending ``times`` [s], the curves.  Returns the number of accepted
    steps, or -1 (too many steps) / -2 (step size underflow) / -3 (scales
    or results not representable, see ``_scales``), with NaNs.

    The integration runs in units of the impact (``_scales``: m = v0 =
    δ_ref = 1), so that it is the same for every impact with the same
    dimensionless damping and nothing inside it under- or overflows; results
    are scaled back at the end, and NaN if one of them is then subnormal or
    infinite (other than an unbounded pressure) or a time, deflection or
    force underflows to 0.

    Three phases: (A) from first touch in σ = δ^(1/q), state (t, δ̇);
    (B) in time, state (δ, δ̇), through the maximum deflection; (C) in σ
    again, down to σ = 0 (separation) unless a clamped force vanishes first.
    In σ the laws are polynomials and the motion is smooth up to δ = 0."""
    k1 = work[0:16]  # stages
    k2 = work[16:32]
    c1 = work[32:39]  # interpolant coefficients
    c2 = work[39:46]
    scaled = work[46:49]  # the law's parameters in units of the impact
    ok, delta_ref, time_ref, force_ref = _scales(family, params, mass, velocity, scaled)
    if not ok:
        return _fail(out, curve_d, curve_v, curve_f, 0, -3)
    q = _substitution_power(family, scaled)

    # F at first touch, and the signs of dF/dt and d(F/δ)/dt just after it: the
    # rates' leading terms, 0 only without a dashpot, where F and F/δ rise from
    # 0 (Hertz) or stay constant (F/δ = k, or K(1 + c v0) for n = 1)
    force0, g_old, h_old = _rates(family, scaled, clamp, 0.0, 1.0)
    peak_force = force0
    time_to_peak = 0.0
    max_deflection = 0.0
    time_to_max = 0.0
    max_ratio = _ratio_limit(family, scaled, clamp, 1.0)
    touch_force = contact_force(family, params, 0.0, velocity, clamp)  # F(0) [N] exactly (b v0)
    if g_old == 0.0 and force0 == 0.0:
        g_old = 1.0
    if h_old == 0.0 and max_ratio == 0.0:
        h_old = 1.0

    n_times = times.shape[0]
    ti = 0
    while ti < n_times and times[ti] <= 0.0:
        curve_d[ti] = 0.0
        curve_v[ti] = velocity
        curve_f[ti] = touch_force
        ti += 1

    # phase A: x = σ, y = (t, δ̇)
    phase = 0
    mode = 1
    x = 0.0
    y1 = 0.0
    y2 = 1.0
    sigma_end = _SWITCH_A ** (1.0 / q)
    k1[0], k2[0] = _rhs(mode, q, family, scaled, x, y1, y2)
    h = sigma_end
    rejected = False
    steps = 0
    while steps < MAX_STEPS:
        clipped = False
        if phase == 0 and x + h >= sigma_end:
            h = sigma_end - x
            clipped = True
        elif phase == 2 and x + h <= 0.0:
            h = -x
            clipped = True
        elif phase == 1 and y2 < 0.0 and max_deflection > 0.0:
            # restitution: do not step past δ = 0.6·δ_switch (the motion is
            # not smooth at δ = 0); δ + v h - ½|a| h² = target
            gap = y1 - 0.6 * _SWITCH_C * max_deflection
            if gap > 0.0:
                reach = 2.0 * gap / (-y2 + math.sqrt(y2 * y2 + 2.0 * abs(k2[0]) * gap))
                if h > reach:
                    h = reach
        y1_new, y2_new = _step(mode, q, family, scaled, x, y1, y2, h, k1, k2)
        err = _error_norm(k1, k2, h, rtol)
        if not (err <= 1.0):  # also catches NaN
            factor = _MIN_FACTOR if err != err else max(_MIN_FACTOR, _SAFETY * err ** -0.125)
            h *= factor
            rejected = True
            if abs(h) <= 1e-14 * (abs(x) + abs(h) / factor):
                break
            continue

        # state at the end of the step
        if mode == 0:
            t_new = x + h
            d_new = y1_new
        else:
            t_new = y1_new
            s_new = x + h if not clipped or phase == 0 else 0.0
            d_new = s_new ** q
        v_new = y2_new
        f_raw = _release(family, scaled, d_new, v_new)
        ended = clamp and f_raw <= 0.0 and v_new < 0.0
        if not ended and phase == 1 and v_new < 0.0 and d_new < _SWITCH_C * max_deflection:
            # entering the last phase: land in (0.3, 1)·δ_switch, not past separation
            if d_new < 0.3 * _SWITCH_C * max_deflection:
                h *= max(0.05, (y1 - 0.6 * _SWITCH_C * max_deflection) / (y1 - d_new))
                rejected = True
                continue
        steps += 1

        # ---- events in the accepted step ----
        dense_ready = False
        theta_end = 1.0
        t_end = t_new
        d_end = d_new
        v_end = v_new
        if ended:  # clamped force vanishes: separation with δ > 0
            _dense_setup(mode, q, family, scaled, x, y1, y2, h, y1_new, y2_new, k1, k2, c1, c2)
            dense_ready = True
            d_start = y1 if mode == 0 else x ** q
            f_start = _release(family, scaled, d_start, y2)
            theta_end = _root(4, 0.0, f_start, 1.0, f_raw, 0.0, mode, q, family, scaled, clamp,
                              x, h, y1, y2, c1, c2)
            # the state there from a step of θh (8th order; the interpolant is 7th):
            # the exit velocity is the restitution, and F = 0 makes it insensitive to θ
            y1_end, v_end = _step(mode, q, family, scaled, x, y1, y2, theta_end * h, k1, k2)
            if mode == 0:
                t_end, d_end = x + theta_end * h, max(y1_end, 0.0)
            else:
                t_end, d_end = y1_end, (x + theta_end * h) ** q
        elif phase == 2 and clipped:  # σ = 0: separation at δ = 0
            ended = True
            d_end = 0.0

        if mode == 0 and y2 > 0.0 and v_end <= 0.0:  # maximum deflection
            if not dense_ready:
                _dense_setup(mode, q, family, scaled, x, y1, y2, h, y1_new, y2_new,
                             k1, k2, c1, c2)
                dense_ready = True
            theta = _root(1, 0.0, y2, theta_end, v_end, 0.0, mode, q, family, scaled, clamp,
                          x, h, y1, y2, c1, c2)
            time_to_max, max_deflection, _v = _state(mode, q, theta, x, h, y1, y2, c1, c2)

        force_end, g_end, h_end = _rates(family, scaled, clamp, d_end, v_end)
        force_peak = g_old > 0.0 and g_end < 0.0  # local maximum of F in this step
        ratio_peak = h_old > 0.0 and h_end < 0.0  # local maximum of F/δ in this step
        if (force_peak or ratio_peak) and not dense_ready:
            _dense_setup(mode, q, family, scaled, x, y1, y2, h, y1_new, y2_new, k1, k2, c1, c2)
            dense_ready = True
        if force_peak:
            tt, dd, vv = _locate(2, theta_end, g_end, mode, q, family, scaled, clamp, x, h,
                                 y1, y2, c1, c2)
            force = contact_force(family, scaled, dd, vv, clamp)
            if force > peak_force:
                peak_force = force
                time_to_peak = tt
        if ratio_peak:
            tt, dd, vv = _locate(3, theta_end, h_end, mode, q, family, scaled, clamp, x, h,
                                 y1, y2, c1, c2)
            if dd > 0.0:
                ratio = contact_force(family, scaled, dd, vv, clamp) / dd
                if ratio > max_ratio:
                    max_ratio = ratio
        if g_end != 0.0:
            g_old = g_end
        if h_end != 0.0:
            h_old = h_end

        while ti < n_times and times[ti] < t_end * time_ref:
            if not dense_ready:
                _dense_setup(mode, q, family, scaled, x, y1, y2, h, y1_new, y2_new,
                             k1, k2, c1, c2)
                dense_ready = True
            tau = times[ti] / time_ref
            if mode == 0:
                theta = (tau - x) / h
            else:
                theta = _root(5, 0.0, y1 - tau, theta_end, t_end - tau, tau, mode, q,
                              family, scaled, clamp, x, h, y1, y2, c1, c2)
            tt, dd, vv = _state(mode, q, theta, x, h, y1, y2, c1, c2)
            curve_d[ti] = max(dd, 0.0) * delta_ref
            curve_v[ti] = vv * velocity
            curve_f[ti] = contact_force(family, scaled, dd, vv, clamp) * force_ref
            ti += 1

        if ended:
            while ti < n_times:
                curve_d[ti] = d_end * delta_ref
                curve_v[ti] = v_end * velocity
                curve_f[ti] = 0.0
                ti += 1
            if d_end > 0.0:
                ratio = force_end / d_end
            else:
                ratio = _ratio_limit(family, scaled, clamp, v_end)
            if ratio > max_ratio:
                max_ratio = ratio
            if time_to_peak > 0.0:
                peak_force *= force_ref
            else:
                peak_force = touch_force
            max_ratio = pressure_ratio(family, scaled, max_ratio, max_deflection)
            fill_characteristics(out, peak_force, time_to_peak * time_ref, t_end * time_ref,
                                 max_deflection * delta_ref, time_to_max * time_ref, -v_end * velocity,
                                 velocity, mass, max_ratio * (force_ref / delta_ref), radius)
            if not _representable(out, max_ratio):
                return _fail(out, curve_d, curve_v, curve_f, 0, -3)
            return steps

        # ---- advance, switching phase where due ----
        factor = _MAX_FACTOR if err == 0.0 else min(_MAX_FACTOR, _SAFETY * err ** -0.125)
        if rejected:
            factor = min(1.0, factor)
            rejected = False
        if phase == 0 and (clipped or v_new <= 0.5):
            # to time: dt = (dt/dσ) dσ
            h = factor * h * q * (x + h) ** (q - 1) / v_new
            phase = 1
            mode = 0
            x = t_new
            y1 = d_new
            y2 = v_new
            k1[0], k2[0] = _rhs(mode, q, family, scaled, x, y1, y2)
        elif phase == 1 and v_new < 0.0 and d_new < _SWITCH_C * max_deflection:
            phase = 2
            mode = 1
            x = d_new ** (1.0 / q)
            h = -factor * h * abs(v_new) / (q * x ** (q - 1))
            y1 = t_new
            y2 = v_new
            k1[0], k2[0] = _rhs(mode, q, family, scaled, x, y1, y2)
        else:
            x += h
            y1 = y1_new
            y2 = y2_new
            k1[0] = k1[12]
            k2[0] = k2[12]
            h *= factor

    return _fail(out, curve_d, curve_v, curve_f, ti, -1 if steps >= MAX_STEPS else -2)


@nb.njit(**_JIT)
def _representable(out, max_ratio):
    """The scaled-back characteristics kept their precision: none subnormal
    or infinite (but an unbounded pressure, F/δ → ∞ at first touch), and
    none 0 but the time to a peak at first touch or the energy absorbed
    in an elastic impact."""
    for j in range(out.shape[0]):
        value = abs(out[j])
        if value == math.inf:
            if j != MAX_PRESSURE or max_ratio != math.inf:
                return False
        elif value == 0.0:
            if j != TIME_TO_PEAK and j != ABSORBED_ENERGY:
                return False
        elif value < _TINY:
            return False
    return True


@nb.njit(**_JIT)
def _fail(out, curve_d, curve_v, curve_f, first, code):
    """NaN characteristics, and NaN curve samples from index ``first``; returns ``code``."""
    for j in range(out.shape[0]):
        out[j] = math.nan
    for j in range(first, curve_d.shape[0]):
        curve_d[j] = math.nan
        curve_v[j] = math.nan
        curve_f[j] = math.nan
    return code


#: Up to this many rows ``adaptive_characteristics`` stays on one thread: the
#: work of PARALLEL_MIN_ROWS power-law rows (an adaptive impact costs about ten).
SERIAL_MAX_ROWS = PARALLEL_MIN_ROWS // 10

_WORK = 49  # workspace: 2 × 16 stages, 2 × 7 interpolant coefficients, 3 scaled parameters
_CHUNK = 64  # impacts per parallel work item


@nb.njit(**_JIT)
def adaptive_impact(family, params, clamp, mass, velocity, radius, rtol, out):
    """Characteristics of one impact m δ̈ = -F(δ, δ̇) by adaptive DOP853.

    Parameters: ``family`` and ``params`` as in ``engine.forces``; ``clamp``
    keeps F ≥ 0 and ends contact where the unclamped force vanishes during
    restitution; mass m [kg]; impact velocity v0 > 0 [m/s]; radius R [m]
    (contact radius sqrt(R δ_max), Hertz pressure 3F/(2πRδ)); rtol [-], the
    relative accuracy asked of the characteristics (1e-10 is a good value).

    Fills ``out`` (length ≥ 12) in the order of ``CHARACTERISTIC_COLUMNS``.
    Returns the number of accepted steps (> 0), or a negative number (and
    NaNs in ``out``) if the integration failed or the impact's scales are not
    representable in double precision (``_integrate``)."""
    none = out[:0]  # no curve samples (an empty, writable view)
    return _integrate(family, params, clamp, mass, velocity, radius, rtol, out, none, none, none, none,
                      np.empty(_WORK))


@nb.njit(parallel=True, **_JIT)
def adaptive_batch(family, params, clamp, mass, velocity, radius, rtol, out):
    """Characteristics of many impacts: row i uses family[i], params[i, :],
    clamp[i], mass[i], velocity[i], radius[i] and fills out[i, :]."""
    rows = mass.shape[0]
    n_chunks = (rows + _CHUNK - 1) // _CHUNK
    for chunk in nb.prange(n_chunks):
        work = np.empty(_WORK)  # one workspace per chunk: no allocation per impact
        for i in range(chunk * _CHUNK, min(rows, (chunk + 1) * _CHUNK)):
            none = out[i, :0]
            _integrate(family[i], params[i], clamp[i], mass[i], velocity[i], radius[i], rtol, out[i],
                       none, none, none, none, work)


@nb.njit(**_JIT)
def adaptive_batch_serial(family, params, clamp, mass, velocity, radius, rtol, out):
    """``adaptive_batch`` on one thread, for few rows: starting the threads
    costs more than the work (milliseconds when the other cores are busy)."""
    work = np.empty(_WORK)
    for i in range(mass.shape[0]):
        none = out[i, :0]
        _integrate(family[i], params[i], clamp[i], mass[i], velocity[i], radius[i], rtol, out[i],
                   none, none, none, none, work)


@nb.njit(**_JIT)
def _curves_kernel(family, params, clamp, mass, velocity, rtol, times, deflection, rate, force, out):
    return _integrate(family, params, clamp, mass, velocity, 1.0, rtol, out, times, deflection, rate, force,
                      np.empty(_WORK))


def adaptive_characteristics(family, params, clamp, mass, velocity, radius,
                             rtol: float = DEFAULT_RTOL) -> np.ndarray:
    """Characteristics of impacts under any force law of ``engine.forces``.

    Parameters
    ----------
    family : int or array_like of int
        Force family code (``engine.forces.POWER_LAW`` …).
    params : array_like, shape (P,) or (..., P)
        Force parameters, one row per impact or one row for all.
    clamp : bool or array_like of bool
        Keep F ≥ 0 (contact ends when the unclamped force vanishes).
    mass, velocity, radius : array_like
        m [kg], v0 > 0 [m/s], effective radius R [m].
    rtol : float
        Relative accuracy of the characteristics.

    Returns
    -------
    ndarray, shape (rows, len(CHARACTERISTIC_COLUMNS))
        Inputs broadcast together (params along its leading axes) and
        flattened to rows.  Rows whose integration failed are NaN.
        Inputs are not validated here: validate at the boundary.  Up to
        ``SERIAL_MAX_ROWS`` rows run on one thread (``adaptive_batch_serial``).
    """
    params = np.asarray(params, dtype=float)
    if params.ndim == 0:
        params = params.reshape(1)
    scalars = [np.asarray(family, dtype=np.int64), np.asarray(clamp, dtype=np.bool_),
               np.asarray(mass, dtype=float), np.asarray(velocity, dtype=float),
               np.asarray(radius, dtype=float)]
    shape = np.broadcast_shapes(params.shape[:-1], *(a.shape for a in scalars))
    scalars = [np.ascontiguousarray(np.broadcast_to(a, shape).ravel()) for a in scalars]
    n_params = max(params.shape[-1], 3)
    rows = scalars[0].shape[0]
    table = np.zeros((rows, n_params))
    table[:, :params.shape[-1]] = np.broadcast_to(params, shape + params.shape[-1:]).reshape(rows, -1)
    out = np.empty((rows, N_CHARACTERISTICS))
    kernel = adaptive_batch if rows > SERIAL_MAX_ROWS else adaptive_batch_serial
    kernel(scalars[0], table, scalars[1], scalars[2], scalars[3], scalars[4], float(rtol), out)
    return out


def adaptive_curves(family: int, params, clamp: bool, mass: float, velocity: float, times,
                    rtol: float = DEFAULT_RTOL):
    """Deflection δ [m], rate δ̇ [m/s] and force F [N] at ``times`` [s] for one
    impact, from the dense output of the adaptive integration.  Times ≤ 0 give
    the state at first touch; times at or after the end of contact give the
    separation state (δ_end, δ̇_exit) with F = 0.

    Returns (deflection, rate, force, contact_duration)."""
    times = np.asarray(times, dtype=float)
    flat = times.ravel()
    order = np.argsort(flat, kind="stable")
    sorted_times = np.ascontiguousarray(flat[order])
    d = np.empty_like(sorted_times)
    v = np.empty_like(sorted_times)
    f = np.empty_like(sorted_times)
    table = np.zeros(max(np.size(params), 3))
    table[:np.size(params)] = np.asarray(params, dtype=float).ravel()
    out = np.empty(N_CHARACTERISTICS)
    _curves_kernel(int(family), table, bool(clamp), float(mass), float(velocity), float(rtol),
                   sorted_times, d, v, f, out)
    deflection = np.empty_like(d)
    rate = np.empty_like(v)
    force = np.empty_like(f)
    deflection[order] = d
    rate[order] = v
    force[order] = f
    return (deflection.reshape(times.shape), rate.reshape(times.shape), force.reshape(times.shape),
            float(out[2]))


__all__ = ["adaptive_impact", "adaptive_batch", "adaptive_batch_serial", "adaptive_characteristics", "adaptive_curves",
           "CHARACTERISTIC_COLUMNS", "N_CHARACTERISTICS", "DEFAULT_RTOL"]
