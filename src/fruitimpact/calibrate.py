"""From a restitution coefficient to the damping of a contact law (vectorised).

``damping_factor(law, calibration, e, m, K, v0)`` returns the law's damping
factor (``ContactLaw.damping_factor``) for arrays of impacts.  The ``exact``
calibration inverts the restitution the law really produces: in closed form
for the power-law family (``engine.powerlaw.exact_x``), by the published
formula where that is exact (unclamped Kelvin–Voigt and Tsuji), and otherwise
by a bracketed root find on the law's dimensionless damping group, on which
alone e depends, with the compiled integrator supplying e.
"""

from __future__ import annotations

import numpy as np

from .engine import forces
from .engine.powerlaw import CHARACTERISTIC_COLUMNS, exact_x

RESTITUTION = CHARACTERISTIC_COLUMNS.index("restitution")

#: Relative tolerance of the numerical exact calibration on e.
EXACT_TOLERANCE = 1e-11


def law_params(family, stiffness, damping_factor, exponent=1.5):
    """Parameter matrix for the compiled force of ``family`` (rows of impacts)."""
    stiffness = np.asarray(stiffness, dtype=float)
    damping_factor = np.asarray(damping_factor, dtype=float)
    stiffness, damping_factor = np.broadcast_arrays(stiffness, damping_factor)
    params = np.zeros(stiffness.shape + (3,))
    params[..., 0] = stiffness
    if family == forces.POWER_LAW:
        params[..., 1] = exponent
        params[..., 2] = damping_factor
    elif family == forces.KUWABARA_KONO:
        params[..., 1] = damping_factor  # B [s]
    else:  # KELVIN_VOIGT (b = c k), TSUJI (η = c K)
        params[..., 1] = damping_factor * stiffness
    return params


def achieved_restitution(law, damping_factor, mass, stiffness, velocity):
    """Restitution the law really produces with this damping (compiled integrator
    for non-power-law families)."""
    from .engine.adaptive import adaptive_characteristics

    mass, stiffness, velocity, damping_factor = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, dtype=float)) for a in (mass, stiffness, velocity, damping_factor)))
    law_k = law.linear_stiffness(mass, stiffness, velocity)
    params = law_params(law.family, law_k, damping_factor)
    out = adaptive_characteristics(np.full(mass.shape, law.family), params, np.full(mass.shape, law.clamp),
                                   mass, velocity, np.ones_like(mass))
    return out[:, RESTITUTION]


def _invert_numerically(law, target, mass, stiffness, velocity):
    """Damping factor giving restitution ``target``: Illinois iteration on the
    dimensionless group g (e decreases with g), bracket grown from the
    published value."""
    group0 = law.group(law.published_damping_factor(target, mass, stiffness, velocity), mass, stiffness, velocity)
    group0 = np.where(group0 > 0, group0, 1e-3)

    def residual(group):
        factor = law.from_group(group, mass, stiffness, velocity)
        return achieved_restitution(law, factor, mass, stiffness, velocity) - target

    lo = np.zeros_like(group0)
    f_lo = 1.0 - target  # e = 1 without damping
    hi = group0.copy()
    f_hi = residual(hi)
    for _ in range(60):  # grow hi until e(hi) < target (never separating counts as e = 0)
        grow = ~(f_hi < 0)
        if not grow.any():
            break
        lo = np.where(grow, hi, lo)
        f_lo = np.where(grow, f_hi, f_lo)
        hi = np.where(grow, hi * 2.0, hi)
        f_hi = np.where(grow, np.nan_to_num(residual(hi), nan=-target), f_hi)
    side = np.zeros_like(hi)
    group = hi
    for _ in range(100):
        group = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        f = np.nan_to_num(residual(group), nan=-target)
        done = np.abs(f) <= EXACT_TOLERANCE * target
        if done.all():
            break
        positive = f > 0  # e above target: root lies between group and hi
        lo, f_lo = np.where(positive, group, lo), np.where(positive, f, f_lo)
        hi, f_hi = np.where(positive, hi, group), np.where(positive, f_hi, f)
        # Illinois: halve the retained end's value when the same side is kept twice
        f_hi = np.where(positive & (side > 0), f_hi / 2.0, f_hi)
        f_lo = np.where(~positive & (side < 0), f_lo / 2.0, f_lo)
        side = np.where(positive, 1.0, -1.0)
    return law.from_group(group, mass, stiffness, velocity)


def damping_factor(law, calibration: str, restitution, mass, stiffness, velocity):
    """Damping factor of ``law`` for restitution e (arrays broadcast).

    Parameters
    ----------
    law : models.DampingLaw
    calibration : str
        ``paper`` (the law's published formula) or ``exact``.
    restitution : array_like
        Target e in (0, 1].
    mass, stiffness, velocity : array_like
        m [kg], Hertz contact stiffness k_c [N/m^1.5], v0 [m/s].
    """
    e, m, k, v = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (restitution, mass, stiffness, velocity)))
    if law.undamped:
        return np.zeros_like(e)
    if calibration == "paper" or law.exact_by_construction:
        return np.asarray(law.published_damping_factor(e, m, k, v), dtype=float) * np.ones_like(e)
    if law.family == forces.POWER_LAW:
        return exact_x(e) / v
    result = np.zeros_like(e)
    damped = e < 1.0
    if damped.any():
        result[damped] = _invert_numerically(law, e[damped], m[damped], k[damped], v[damped])
    return result
