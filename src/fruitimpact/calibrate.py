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


_GROUP_TABLES: dict[str, tuple[np.ndarray, np.ndarray]] = {}


def _group_table(law):
    """(g, e): the restitution of ``law`` on a grid of its dimensionless damping group
    g, from a reference impact (m = K = v0 = 1), since e depends on g alone.  Built
    once per law (about 1400 integrations); never separating counts as e = 0."""
    table = _GROUP_TABLES.get(law.name)
    if table is None:
        group = np.concatenate([[0.0], np.geomspace(1e-5, 1e3, 1400)])
        one = np.ones_like(group)
        e = achieved_restitution(law, law.from_group(group, one, one, one), one, one, one)
        table = _GROUP_TABLES[law.name] = (group, np.nan_to_num(e, nan=0.0))
    return table


def _invert_numerically(law, target, mass, stiffness, velocity):
    """Damping factor giving restitution ``target``: the law's table of e(g) brackets
    the dimensionless group g between two neighbouring grid points, then an
    Illinois iteration on each row's own impact (only rows not yet converged)
    finds g to EXACT_TOLERANCE in e."""
    group_grid, e_grid = _group_table(law)
    index = np.clip(np.searchsorted(-e_grid, -target, side="left"), 1, len(e_grid) - 1)
    lo, hi = group_grid[index - 1], group_grid[index]
    f_lo, f_hi = e_grid[index - 1] - target, e_grid[index] - target
    group = hi.copy()
    side = np.zeros_like(hi)
    active = np.arange(len(target))
    for _ in range(60):
        a = active
        trial = hi[a] - f_hi[a] * (hi[a] - lo[a]) / (f_hi[a] - f_lo[a])
        trial = np.where(np.isfinite(trial) & (trial > lo[a]) & (trial < hi[a]), trial, 0.5 * (lo[a] + hi[a]))
        factor = law.from_group(trial, mass[a], stiffness[a], velocity[a])
        f = np.nan_to_num(achieved_restitution(law, factor, mass[a], stiffness[a], velocity[a]) - target[a],
                          nan=-target[a])
        group[a] = trial
        positive = f > 0  # e above target: the root lies between trial and hi
        lo[a] = np.where(positive, trial, lo[a])
        hi[a] = np.where(positive, hi[a], trial)
        # Illinois: halve the retained end's value when the same side is kept twice
        f_lo[a] = np.where(positive, f, np.where(side[a] < 0, f_lo[a] / 2.0, f_lo[a]))
        f_hi[a] = np.where(positive, np.where(side[a] > 0, f_hi[a] / 2.0, f_hi[a]), f)
        side[a] = np.where(positive, 1.0, -1.0)
        active = a[np.abs(f) > EXACT_TOLERANCE * target[a]]
        if active.size == 0:
            break
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
