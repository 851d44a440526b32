"""Two fruit in one contact, told apart (issue 13, item 2).

When a second fruit (or a rebound) lands on the plate while another is still in contact, the force falls
from the first maximum and rises again (``indices.second_pulse``).  Both contacts are the simulator's
Hunt–Crossley pulse and forces on one plate add, so the contact is fitted as the sum of two pulses,

    F(t) = F_A · H((t − t0_A)/T_A; x_A) + F_B · H((t − t0_B)/T_B; x_B),

by the same Levenberg–Marquardt and tabulated shape H as one pulse (``signals.fit``), eight parameters,
started from the two maxima and the dip between them.  The separation is accepted only when the sum
leaves nothing but the noise (``MISFIT_LIMIT`` of the larger peak beyond it, as for one pulse), both
pulses lie inside the window in order, and each is well above the noise; then each pulse is reported as
its own contact, its indices measured on the samples less the other pulse's model, its fit the
corresponding block of the joint fit (its standard errors from the joint covariance, so the other pulse's
uncertainty is in them).  Otherwise the contact stays one report with status ``overlap``.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.signals.fit import MIN_PEAK_SNR, RESULT_KEYS, X_MAX, PulseModel, levenberg_marquardt, named_result
from fruitimpact.signals.indices import SECOND_PULSE_SMOOTHING, departure_from_one_peak

__all__ = ["MISFIT_LIMIT", "split_contact"]

#: A fit whose residual beyond the noise, √(rms² − σ²), exceeds this share of the peak is not one pulse (and
#: a joint fit of two, of the larger peak, not two).  One Hunt–Crossley contact leaves the noise plus a
#: structured part (plate ringing, hum left over) of at most 1.6 % of its peak over the line scenarios of
#: tests/linegen.py (2–3 kHz ringing, ζ 0.03–0.1, hum, drift) and 0.9 % in tests/test_signals_detect.py; two
#: fruit landing within a fraction of a time to peak leave 2–10 %.
MISFIT_LIMIT = 0.018
#: Ratio T/t_c of the starting guesses (a Hunt–Crossley pulse with e ≈ 0.6; the fit moves it).
_DURATION_OVER_RISE = 3.2


class _TwoPulses:
    """F(t; θ_A) + F(t; θ_B) and its Jacobian, for ``levenberg_marquardt``."""

    def __init__(self, t: np.ndarray):
        self.first, self.second = PulseModel(t), PulseModel(t)

    def __call__(self, theta, jacobian: bool = False):
        if not jacobian:
            return self.first.pulse(theta[:4]).copy() + self.second.pulse(theta[4:])
        fa, ja = self.first.pulse(theta[:4], True)
        fb, jb = self.second.pulse(theta[4:], True)
        return fa + fb, np.hstack([ja, jb])


def _landmarks(y: np.ndarray) -> tuple[int, int, int] | None:
    """(first maximum, dip, second maximum) indices of the force, in time order, from its smoothed
    departure from one peak (``indices.departure_from_one_peak``, as ``second_pulse`` measures it)."""
    s, top, rise, fall = departure_from_one_peak(y)
    centre = SECOND_PULSE_SMOOTHING // 2  # s[i] is centred on y[i + centre]
    if rise.size and (not fall.size or rise.max() >= fall.max()):
        second = top + int(np.argmax(rise))
        dip = top + int(np.argmin(s[top:second + 1]))
        return top + centre, dip + centre, second + centre
    if not fall.size or fall.max() <= 0:
        return None
    dip = int(np.argmax(fall))
    first = int(np.argmax(s[:dip + 1]))
    return first + centre, dip + centre, top + centre


def _onset(y: np.ndarray, end: int, level: float) -> int:
    """Last index before ``end`` where y was at or below ``level`` (0 if none)."""
    below = np.flatnonzero(y[:end] <= level)
    return int(below[-1]) if below.size else 0


def split_contact(time, force, noise: float, *, velocity=None, mass=None, diameter=None, poisson=None):
    """Fit two pulses to one contact (module docstring).

    ``time`` [s] and ``force`` [N] are the contact's window (baseline removed), ``noise`` the noise sd [N];
    ``velocity`` or ``mass`` and ``diameter``/``poisson`` as for ``fit.fit_impact`` (applied to both).
    Returns ((result_A, separated force A), (result_B, separated force B)) in time order, each result a dict
    with the keys of ``fit.RESULT_KEYS``, or None when the contact is not separated."""
    t = np.asarray(time, dtype=float)
    y = np.asarray(force, dtype=float)
    if t.size < 24 or not noise > 0:
        return None
    marks = _landmarks(y)
    if marks is None:
        return None
    first, dip, second = marks
    if not (first < dip < second):
        return None
    t_ref = float(t[0])
    ts = t - t_ref
    step = ts[1] - ts[0]
    level = 3.0 * noise
    start_a = _onset(y, first, level)
    rise_a = max(ts[first] - ts[start_a], 3 * step)
    start_b = dip - max(2, round(0.25 * (second - dip)))
    rise_b = max(ts[second] - ts[start_b], 3 * step)
    peak_a = max(float(y[first]), level)
    peak_b = max(float(y[second] - 0.5 * y[dip]), level)
    theta = np.array([ts[start_a], math.log(peak_a), math.log(_DURATION_OVER_RISE * rise_a), 1.0,
                      ts[start_b], math.log(peak_b), math.log(_DURATION_OVER_RISE * rise_b), 1.0])
    model = _TwoPulses(ts)
    weights = np.full(ts.shape, 1.0 / noise)
    try:  # a trial step far out (a duration of e^700) is a failed separation, not an error
        with np.errstate(all="ignore"):
            theta, jac, _, iterations, converged, _ = levenberg_marquardt(model, y, theta, weights, bounded=(3, 7))
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None
    try:  # a degenerate pulse (a peak or duration beyond double precision) is a failed separation
        with np.errstate(all="ignore"):
            residual = model(theta) - y
            rms = float(np.sqrt(np.mean(residual ** 2)))
            peaks = math.exp(theta[1]), math.exp(theta[5])
            misfit = math.sqrt(max(rms ** 2 - noise ** 2, 0.0)) / max(peaks)
            ends = theta[0] + math.exp(theta[2]), theta[4] + math.exp(theta[6])
            if not (converged and misfit <= MISFIT_LIMIT and ts[0] <= theta[0] < theta[4] and max(ends) <= ts[-1]
                    and min(peaks) > MIN_PEAK_SNR * noise and theta[3] < X_MAX and theta[7] < X_MAX):
                return None
            covariance = np.linalg.inv(jac.T @ jac)
            return _parts(theta, covariance, (velocity if mass is None else None, mass, diameter, poisson), t_ref,
                          ts, rms, noise, iterations, model, y)
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None


def _parts(theta, covariance, args, t_ref, ts, rms, noise, iterations, model, y):
    """The two results and separated forces of a joint fit (``split_contact``)."""
    out = []
    for k, (lo, hi) in enumerate(((0, 4), (4, 8))):
        part = theta[lo:hi]
        result = {name: math.nan for name in RESULT_KEYS}
        result.update(named_result(part, covariance[lo:hi, lo:hi], args, t_ref))
        inside = int(np.count_nonzero((ts > part[0]) & (ts < part[0] + math.exp(part[2]))))
        if not all(math.isfinite(result[name]) for name in ("peak_force", "contact_duration", "restitution")):
            raise ValueError("a part without a finite peak, duration or restitution")
        result.update(fit_residual=rms, fit_residual_relative=rms / result["peak_force"], noise=noise,
                      samples_in_contact=inside, converged=True, iterations=int(iterations),
                      message="converged; one of two pulses in one contact, fitted together")
        other = (model.second.pulse(theta[4:]) if k == 0 else model.first.pulse(theta[:4])).copy()
        out.append((result, y - other))
    return tuple(out)
