"""Contact force families as compiled functions of (δ, δ̇).

Each family is an integer code with a fixed parameter vector, so that one
compiled integrator serves them all.  The friendly registry of named models
(``fruitimpact.models``) maps each published model onto one of these.
All forces are in N, δ in m (positive in compression), δ̇ in m/s (positive
while approaching).
"""

from __future__ import annotations

import math

import numba as nb

from .codes import KELVIN_VOIGT, KUWABARA_KONO, POWER_LAW, TSUJI  # noqa: F401  (the family codes)

_JIT = dict(cache=True, error_model="numpy")


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
