"""Contact force families as compiled functions of (δ, δ̇).

Each family is an integer code with a fixed parameter vector, so that one
compiled integrator serves them all.  The friendly registry of named models
(``fruitimpact.physics``) maps each published model onto one of these.
All forces are in N, δ in m (positive in compression), δ̇ in m/s (positive
while approaching).
"""

from __future__ import annotations

import math

import numba as nb

from fruitimpact.engine.codes import KELVIN_VOIGT, KUWABARA_KONO, POWER_LAW, TSUJI  # noqa: F401  (the family codes)
from fruitimpact.engine.jitcache import CACHE

_JIT = dict(cache=CACHE, error_model="numpy")


@nb.njit(**_JIT)
def contact_force(family, params, deflection, rate, clamp):
    """Contact force [N] of ``family`` at deflection δ and rate δ̇, in contact.

    The caller decides when contact ends; here δ < 0 (an integrator stage just
    past separation) counts as δ = 0, so that a law with a dashpot term, like
    Kelvin–Voigt, has its force b·δ̇ at first touch.  With ``clamp`` the force
    is never tensile (max(F, 0)): a fruit cannot pull on the surface."""
    if deflection < 0.0:
        deflection = 0.0
    if family == POWER_LAW:
        force = params[0] * deflection ** params[1] * (1.0 + params[2] * rate)
    elif family == KELVIN_VOIGT:
        force = params[0] * deflection + params[1] * rate
    elif family == KUWABARA_KONO:
        root = math.sqrt(deflection)
        force = params[0] * root * (deflection + params[1] * rate)
    else:  # TSUJI
        force = params[0] * deflection * math.sqrt(deflection) + params[1] * math.sqrt(math.sqrt(deflection)) * rate
    if clamp and force < 0.0:
        return 0.0
    return force


@nb.njit(**_JIT)
def pressure_ratio(family, params, max_ratio, max_deflection):
    """The (F/δ)_max [N/m] that sets the peak Hertz contact pressure p_0 = 3 (F/δ)_max / (2π R) (a² = R δ;
    Johnson 1985, eq 4.23), from the largest F/δ of the whole force seen over the contact (``max_ratio``)
    and the largest deflection.  Power law: the whole force (Hunt–Crossley damping scales the Hertz force
    by (1 + c δ̇), keeping its distribution).  Kuwabara–Kono and Tsuji: their Hertz elastic part K δ_max^0.5
    alone (the dashpot, ∝ δ^0.5 δ̇ or δ^0.25 δ̇, has no Hertz distribution and makes F/a² unbounded at
    first touch).  Kelvin–Voigt: NaN (a linear spring has no Hertz contact pressure)."""
    if family == POWER_LAW:
        return max_ratio
    if family == KELVIN_VOIGT:
        return math.nan
    return params[0] * math.sqrt(max(max_deflection, 0.0))
