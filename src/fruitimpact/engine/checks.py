"""Physical checks of computed characteristics, one pass over the rows (compiled).

``classify`` sorts each row of a characteristics array (``engine.codes``
column order) into one of the outcomes below and removes a round-off excess
of the restitution over 1 in place (within ``tolerance``: e = 1, exit
velocity = impact velocity, absorbed energy 0), so that round-off never
creates energy in reported figures.  ``fruitimpact.impact.status`` turns the
outcomes into statuses and messages.  Row-major, one pass: a million rows
cost a few milliseconds.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.codes import ABSORBED_ENERGY, CONTACT_DURATION, EXIT_VELOCITY, MAX_DEFLECTION, PEAK_FORCE, RESTITUTION
from fruitimpact.engine.jitcache import CACHE

#: Outcomes of ``classify``.
PHYSICAL = 0
NOT_FINITE = 1
COLLAPSED = 2
ENERGY_CREATED = 3
NO_REBOUND = 4

_JIT = dict(cache=CACHE, error_model="numpy")


@nb.njit(**_JIT)
def classify_row(values, velocity, tolerance):
    if not (math.isfinite(values[PEAK_FORCE]) and math.isfinite(values[CONTACT_DURATION])
            and math.isfinite(values[MAX_DEFLECTION]) and math.isfinite(values[RESTITUTION])):
        return NOT_FINITE
    if not (values[CONTACT_DURATION] > 0.0 and values[MAX_DEFLECTION] > 0.0):
        return COLLAPSED
    e = values[RESTITUTION]
    if e > 1.0 + tolerance:
        return ENERGY_CREATED
    if not (e > 0.0):
        return NO_REBOUND
    if e > 1.0:  # round-off of an elastic impact: exactly elastic
        values[RESTITUTION] = 1.0
        values[EXIT_VELOCITY] = velocity
        values[ABSORBED_ENERGY] = 0.0
    return PHYSICAL


@nb.njit(parallel=True, **_JIT)
def _classify_parallel(values, velocity, tolerance, out):
    for i in nb.prange(values.shape[0]):
        out[i] = classify_row(values[i], velocity[i], tolerance)


@nb.njit(**_JIT)
def _classify_serial(values, velocity, tolerance, out):
    for i in range(values.shape[0]):
        out[i] = classify_row(values[i], velocity[i], tolerance)


def classify(values: np.ndarray, velocity: np.ndarray, tolerance: float) -> np.ndarray:
    """Outcome code (``PHYSICAL`` …) of each row of ``values`` (rows, 12), C-contiguous and
    modified in place; ``velocity`` [m/s] per row; ``tolerance`` the solver's accuracy on e."""
    out = np.empty(values.shape[0], dtype=np.int8)
    velocity = np.ascontiguousarray(velocity, dtype=float)
    (_classify_parallel if values.shape[0] > 20000 else _classify_serial)(values, velocity, float(tolerance), out)
    return out


__all__ = ["COLLAPSED", "ENERGY_CREATED", "NOT_FINITE", "NO_REBOUND", "PHYSICAL", "classify", "classify_row"]
