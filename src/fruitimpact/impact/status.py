"""The status of a result: never report the impossible as ok.

Every computed impact is judged here before anyone sees it:

* ``failed``: the solver did not produce an impact: non-finite
  characteristics, a contact duration or deflection of 0 (the impact's
  scales underflow double precision), a restitution outside (0, 1] beyond
  the solver's tolerance (energy created, or a rebound into the surface);
* ``inaccurate``: a physical result whose numerical error, measured against
  the accurate solver, exceeds what the method promises (RK4 at a coarse
  step: 0.01 on e, absolute since e may be near 0; 1 % on T, δ_max, F_max);
  the message says by how much and which step would do;
* ``invalid``: refused input (set by validation, before any computing);
* ``ok``: everything else.  Round-off may not create energy: a restitution
  that exceeds 1 by less than the solver's tolerance (an undamped impact
  integrated to 1 + 3e-11) is reported as exactly 1 and the absorbed energy
  as 0.
"""

from __future__ import annotations

import numpy as np

from fruitimpact.engine.codes import (CONTACT_DURATION, MAX_DEFLECTION, PEAK_FORCE,
                              RESTITUTION)
from fruitimpact.impact.validation import MessageBook

OK, INACCURATE, FAILED, INVALID = 0, 1, 2, 3
#: Status names by code (a categorical's categories).
STATUS_NAMES = ("ok", "inaccurate", "failed", "invalid")

#: Characteristics every completed impact has.
ESSENTIAL = (PEAK_FORCE, CONTACT_DURATION, MAX_DEFLECTION, RESTITUTION)
#: Characteristics compared with the accurate solver, and whether the error is relative.
CHECKED = (("restitution", RESTITUTION, False), ("contact_duration", CONTACT_DURATION, True),
           ("max_deflection", MAX_DEFLECTION, True), ("peak_force", PEAK_FORCE, True))
#: The message of an impact whose scales leave double precision.
UNDERFLOW_MESSAGE = ("the contact duration or deflection is 0 or not finite: the impact's scales under- or "
                     "overflow double precision (the velocity or mass is too small or too large)")
#: Observed order of RK4 from first touch (δ^1.5 has an unbounded second derivative at δ = 0;
#: measured 2.5 in tests/test_solvers.py): the error shrinks as step^2.5.
RK4_ORDER = 2.5


def _suggest_step(step, error, tolerance):
    """A step that should bring ``error`` below ``tolerance`` at the observed order, with a margin."""
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.clip((0.5 * tolerance / error) ** (1.0 / RK4_ORDER), 1e-3, 0.5)
    return float(f"{step * factor:.1g}")


def judge(values: np.ndarray, rows: np.ndarray, status: np.ndarray, messages: MessageBook, *, solver,
          velocity: np.ndarray, step: np.ndarray, reference: np.ndarray | None = None,
          time_scale=None) -> None:
    """Judge the characteristics ``values`` (one row per entry of ``rows``, modified in place:
    a round-off excess of e over 1 is removed), setting ``status`` and ``messages`` of ``rows``.

    ``velocity`` and ``step`` are per row of the whole table; ``reference`` holds the accurate
    solver's characteristics of the same rows when the solver is ``checked``; ``time_scale``
    (rows → the undamped Hertz contact duration [s]) tells, for the rows without a result,
    an impact whose scales leave double precision from a solver that did not finish."""
    from fruitimpact.engine.checks import COLLAPSED, ENERGY_CREATED, NO_REBOUND, NOT_FINITE, classify

    outcome = classify(values, np.asarray(velocity[rows], dtype=float), solver.tolerance)
    if not outcome.any():  # every row physical: the common case, settled in one pass
        status[rows] = OK
        if solver.checked and reference is not None and rows.size:
            _check_against_reference(values, rows, reference, status, messages, solver, step)
        return
    finite = outcome != NOT_FINITE
    collapsed = outcome == COLLAPSED
    energy_created = outcome == ENERGY_CREATED
    no_rebound = outcome == NO_REBOUND
    failed = ~finite | collapsed | energy_created | no_rebound
    status[rows] = OK
    status[rows[failed]] = FAILED
    if solver.checked and reference is not None:
        # the reference tells a method error (a step too coarse) from an impossible impact
        for i in np.flatnonzero(failed):
            messages.set_row(rows[i], _checked_failure(solver, values[i], reference[i], step[rows[i]]))
    if time_scale is not None and (~finite).any():
        scale = np.asarray(time_scale(rows[~finite]), dtype=float)
        lost = ~(np.isfinite(scale) & (scale >= np.finfo(float).tiny))
        messages.set(_mask(rows[~finite][lost], status.size), UNDERFLOW_MESSAGE)
    messages.set(_mask(rows[~finite], status.size), "the solver did not reach separation (non-finite characteristics)")
    messages.set(_mask(rows[collapsed], status.size), UNDERFLOW_MESSAGE)
    for i in np.flatnonzero(energy_created | no_rebound):
        what = "the solver created energy" if values[i, RESTITUTION] > 1.0 else "the fruit does not rebound"
        messages.set_row(rows[i], f"restitution {values[i, RESTITUTION]:.4g} is outside (0, 1]: {what}")
    if solver.checked and reference is not None:
        kept = ~failed
        _check_against_reference(values[kept], rows[kept], reference[kept], status, messages, solver, step)


def _mask(index: np.ndarray, size: int) -> np.ndarray:
    mask = np.zeros(size, dtype=bool)
    mask[index] = True
    return mask


def _checked_failure(solver, values, reference_row, step) -> str:
    """Why a checked solver's (RK4's) row failed, against the accurate solver's row."""
    e, duration = values[RESTITUTION], values[CONTACT_DURATION]
    if not np.all(np.isfinite(values[list(ESSENTIAL)])):
        what = "the contact did not end"
    elif not (duration > 0):
        what = f"contact duration {duration:.3g} s"
    else:
        what = f"restitution {e:.4g} outside (0, 1]"
    exact = reference_row[RESTITUTION]
    against = f" (the accurate solver gives e = {exact:.4g})" if np.isfinite(exact) else ""
    return (f"{solver.name} at step {step:g} s fails: {what}{against}; use a step of at most "
            f"{_suggest_step(step, 1.0, solver.tolerance):g} s")


def _check_against_reference(values, rows, reference, status, messages, solver, step):
    """Mark rows whose error against the accurate solver exceeds the solver's tolerance."""
    errors = np.zeros((rows.size, len(CHECKED)))
    with np.errstate(divide="ignore", invalid="ignore"):
        for j, (_, column, relative) in enumerate(CHECKED):
            diff = np.abs(values[:, column] - reference[:, column])
            errors[:, j] = diff / np.abs(reference[:, column]) if relative else diff
    usable = np.all(np.isfinite(reference[:, list(ESSENTIAL)]), axis=1)
    errors[~usable] = 0.0  # no reference: judged on physics alone (above)
    worst = np.argmax(errors, axis=1)
    bad = errors[np.arange(rows.size), worst] > solver.tolerance
    for i in np.flatnonzero(bad):
        row = rows[i]
        name, column, relative = CHECKED[worst[i]]
        error = errors[i, worst[i]]
        size = f"{100 * error:.2g} %" if relative else f"{error:.2g}"
        limit = f"{100 * solver.tolerance:g} %" if relative else f"{solver.tolerance:g}"
        status[row] = INACCURATE
        messages.set_row(row, f"{solver.name} at step {step[row]:g} s is inaccurate: {name} {values[i, column]:.5g} "
                              f"against {reference[i, column]:.5g} from the accurate solver (off by {size}, "
                              f"tolerance {limit}); use a step of at most "
                              f"{_suggest_step(step[row], error, solver.tolerance):g} s")


__all__ = ["CHECKED", "ESSENTIAL", "FAILED", "INACCURATE", "INVALID", "OK", "RK4_ORDER", "STATUS_NAMES",
           "UNDERFLOW_MESSAGE", "judge"]
