"""Two fruit in one contact, told apart (issue 13, item 2).

When a second fruit (or a rebound) lands on the plate while another is still in contact, the force falls
from the first maximum and rises again (``indices.second_pulse``).  Both contacts are the simulator's
Hunt–Crossley pulse and forces on one plate add, so the contact is fitted as the sum of two pulses,

    F(t) = F_A · H((t − t0_A)/T_A; x_A) + F_B · H((t − t0_B)/T_B; x_B),

by the same Levenberg–Marquardt and tabulated shape H as one pulse (``signals.fit``), eight parameters.
Two pulses a few milliseconds apart show no dip: the second lands on the first one's rise or peak and only
its shoulder shows.  So the fit is started from several places (``_starts``): the two maxima and the dip
between them when there is one, then the best few of a grid of pulse pairs (the second onset anywhere in the
contact, each pulse 55–85 % of the contact's span, x = 1), each pair's two peaks from linear least squares;
every start's fit is kept when it is accepted (below), and of those whose χ² are alike the one whose
restitutions agree with the lane's wins: the first pulse's tail lies under the second, so its restitution
trades against the second's amplitude (two fits of one overlap, e 0.34 with 94.6 N and e 0.71 with 99.9 N,
leave the same residual), while a fruit has the lane's restitution and a rebound a higher one.  When an
earlier fruit's rebound is due in the contact, the physics says more: the rebound is that fruit at its exit
speed, so its peak, duration and x are known within the spread of the speed ratio and the spot it lands on
(``rebounds.expected_rebound``).  They enter each fit as Gaussian priors on the pulse nearer them (extra rows
of the least squares; one fit per start and per contact whose rebound is due), and the separation with the
least χ² of data and prior together wins.
The separation is accepted only when the sum
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
#: The grid of starts: second onsets over the contact, durations as shares of the contact's span (one pulse
#: alone spans 100 %; two that overlap each span less), and how many of the best pairs are fitted.
GRID_ONSETS = 12
GRID_DURATIONS = (0.55, 0.7, 0.85)
GRID_STARTS = 4
#: How far a pulse may end after the window [share of its duration]: the window is cut before the next
#: contact's rise, and a Hunt–Crossley pulse's last 15 % carry ~2 % of its impulse (its force ~(T − t)^1.5).
END_ALLOWANCE = 0.15
#: A separation that leaves at most this share of the peak beyond the noise is taken at once; above it every
#: start is fitted and the least misfit wins (two fruit 1–4 ms apart have wrong local minima at 0.5–1.5 %,
#: the right one at 0–0.5 %, over the overlaps of tests/linegen.py's chain10).
GOOD_MISFIT = 0.004
#: Separations whose χ² lie within this of the least are alike (3 sd of one parameter): the data cannot choose
#: between them, the lane's restitution does (``_implausibility``).
ALIKE_CHI2 = 9.0
#: A part's restitution may lie this far below the lane's fruit before it counts as implausible (the lot's
#: spread of e: c varies ±25 % between fruit, e by ±0.1 at e ≈ 0.6).
RESTITUTION_SPREAD = 0.12


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


def split_contact(time, force, noise: float, *, velocity=None, mass=None, diameter=None, poisson=None,
                  restitution=None, expected=()):
    """Fit two pulses to one contact (module docstring).

    ``time`` [s] and ``force`` [N] are the contact's window (baseline removed), ``noise`` the noise sd [N];
    ``velocity`` or ``mass`` and ``diameter``/``poisson`` as for ``fit.fit_impact`` (applied to both).
    ``restitution``: the lane's typical fruit restitution, when known, to choose between separations that fit
    alike; ``expected``: the pulses one of the two may be (``rebounds.expected_rebound`` of each earlier contact
    whose rebound is due), each as Gaussian priors on its peak, duration and x (module docstring).
    Returns ((result_A, separated force A), (result_B, separated force B)) in time order, each result a dict
    with the keys of ``fit.RESULT_KEYS``, or None when the contact is not separated."""
    t = np.asarray(time, dtype=float)
    y = np.asarray(force, dtype=float)
    if t.size < 24 or not noise > 0:
        return None
    marks = _landmarks(y)
    t_ref = float(t[0])
    ts = t - t_ref
    model = _TwoPulses(ts)
    weights = np.full(ts.shape, 1.0 / noise)
    args = (velocity if mass is None else None, mass, diameter, poisson)
    found = []
    for theta in _starts(ts, y, noise, marks):
        for prior in [_Prior.on_nearer(e, theta) for e in expected] or [None]:
            fit = _separated(model, ts, y, noise, weights, theta, args, t_ref, prior)
            if fit is not None:
                found.append(fit)
        if not expected and found and found[-1][1] <= GOOD_MISFIT and _implausibility(found[-1][2], restitution) == 0:
            break
    if not found:
        return None
    if expected:  # the posterior: the data's χ² and the prior's
        return min(found, key=lambda fit: fit[0])[2]
    least = min(chi2 for chi2, _, _ in found)
    alike = [fit for fit in found if fit[0] <= least + ALIKE_CHI2]
    return min(alike, key=lambda fit: (_implausibility(fit[2], restitution), fit[0]))[2]


class _Prior:
    """Gaussian priors on one pulse's (ln F_max, ln T, x) as extra rows of the least squares: the model
    returns (F(θ), θ[idx]) and the data (y, μ) with weights (1/σ_noise, 1/sd)."""

    KEYS = ("log_peak", "log_duration", "x")

    def __init__(self, expected: dict, pulse: int):
        self.index = np.array([4 * pulse + 1, 4 * pulse + 2, 4 * pulse + 3])
        self.mean = np.array([expected[k] for k in self.KEYS], dtype=float)
        self.weight = 1.0 / np.array([expected[f"{k}_sd"] for k in self.KEYS], dtype=float)

    @classmethod
    def on_nearer(cls, expected: dict, theta) -> _Prior:
        """The prior on the pulse of the start ``theta`` whose peak is nearer the expected one."""
        return cls(expected, int(abs(theta[5] - expected["log_peak"]) < abs(theta[1] - expected["log_peak"])))

    def chi2(self, theta) -> float:
        return float(np.sum(((theta[self.index] - self.mean) * self.weight) ** 2))

    def wrap(self, model):
        index = self.index

        def fitted(theta, jacobian: bool = False):
            out = model(theta, jacobian)
            f, j = out if jacobian else (out, None)
            f = np.concatenate([f, theta[index]])
            if not jacobian:
                return f
            rows = np.zeros((index.size, theta.size))
            rows[np.arange(index.size), index] = 1.0
            return f, np.vstack([j, rows])

        return fitted


def _implausibility(parts, restitution) -> float:
    """How far the parts' restitutions fall below the lane's fruit (0 without a lane value): a fruit has the
    restitution of the lane's fruit and a rebound, landing slower, a higher one (x = c V is smaller), so a part
    far below it is the other pulse's tail traded for its amplitude."""
    if restitution is None:
        return 0.0
    return sum(max(0.0, restitution - RESTITUTION_SPREAD - part["restitution"]) for part, _ in parts)


def _separated(model, ts, y, noise, weights, theta, args, t_ref, prior=None):
    """(χ², misfit, the two parts) of the joint fit started at ``theta`` when it is accepted (module docstring),
    else None."""
    fitted, data, w = model, y, weights
    if prior is not None:
        fitted, data, w = prior.wrap(model), np.concatenate([y, prior.mean]), np.concatenate([weights, prior.weight])
    try:  # a trial step far out (a duration of e^700) is a failed separation, not an error
        with np.errstate(all="ignore"):
            theta, jac, _, iterations, converged, _ = levenberg_marquardt(fitted, data, theta, w, bounded=(3, 7))
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None
    try:  # a degenerate pulse (a peak or duration beyond double precision) is a failed separation
        with np.errstate(all="ignore"):
            residual = model(theta) - y
            rms = float(np.sqrt(np.mean(residual ** 2)))
            peaks = math.exp(theta[1]), math.exp(theta[5])
            misfit = math.sqrt(max(rms ** 2 - noise ** 2, 0.0)) / max(peaks)
            durations = math.exp(theta[2]), math.exp(theta[6])
            # the window may end a little before the last pulse does (cut before the next contact's rise):
            # its last ~10 % carries ~1 % of the impulse, so the fit still sees the whole pulse
            late = max(theta[0] + durations[0] - ts[-1], theta[4] + durations[1] - ts[-1], 0.0)
            if not (converged and misfit <= MISFIT_LIMIT and ts[0] <= theta[0] < theta[4]
                    and late <= END_ALLOWANCE * min(durations)
                    and min(peaks) > MIN_PEAK_SNR * noise and theta[3] < X_MAX and theta[7] < X_MAX):
                return None
            covariance = np.linalg.inv(jac.T @ jac)
            chi2 = float(np.sum((residual / noise) ** 2)) + (prior.chi2(theta) if prior is not None else 0.0)
            return chi2, misfit, _parts(theta, covariance, args, t_ref, ts, rms, noise, iterations, model, y)
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None


def _starts(ts: np.ndarray, y: np.ndarray, noise: float, marks):
    """Starting θ of the joint fit, most likely first: from the landmarks (two maxima and a dip) when there are
    any, then the ``GRID_STARTS`` best pulse pairs of a grid (module docstring)."""
    step = ts[1] - ts[0]
    level = 3.0 * noise
    if marks is not None and marks[0] < marks[1] < marks[2]:
        first, dip, second = marks
        start_a = _onset(y, first, level)
        rise_a = max(ts[first] - ts[start_a], 3 * step)
        start_b = dip - max(2, round(0.25 * (second - dip)))
        rise_b = max(ts[second] - ts[start_b], 3 * step)
        peak_a = max(float(y[first]), level)
        peak_b = max(float(y[second] - 0.5 * y[dip]), level)
        yield np.array([ts[start_a], math.log(peak_a), math.log(_DURATION_OVER_RISE * rise_a), 1.0,
                        ts[start_b], math.log(peak_b), math.log(_DURATION_OVER_RISE * rise_b), 1.0])
    # the contact: from the last sample at the noise level before its maximum to the first after it (a lone
    # noise sample above 3 sd elsewhere in the window must not stretch it)
    top = int(np.argmax(y))
    after = np.flatnonzero(y[top:] <= level)
    if not after.size:
        return
    onset, end = ts[_onset(y, top, level)], ts[top + int(after[0])]
    span = end - onset
    if span < 8 * step:
        return
    shape = PulseModel(ts)
    unit = {}  # (onset, duration) → the unit pulse at x = 1

    def pulse(t0, duration):
        key = (t0, duration)
        if key not in unit:
            unit[key] = shape.pulse((t0, 0.0, math.log(duration), 1.0)).copy()
        return unit[key]

    candidates = []
    durations = [f * span for f in GRID_DURATIONS]
    for onset_b in onset + np.linspace(3 * step, span - 0.5 * min(durations), GRID_ONSETS):
        for duration_a in durations:
            for duration_b in durations:
                a, b = pulse(onset, duration_a), pulse(float(onset_b), duration_b)
                gram = np.array([[a @ a, a @ b], [a @ b, b @ b]])
                try:
                    peaks = np.linalg.solve(gram, np.array([a @ y, b @ y]))
                except np.linalg.LinAlgError:
                    continue
                if not (peaks > level).all():
                    continue
                rest = y - peaks[0] * a - peaks[1] * b
                candidates.append((float(rest @ rest), float(onset_b), duration_a, duration_b, *peaks))
    candidates.sort()
    for _, onset_b, duration_a, duration_b, peak_a, peak_b in candidates[:GRID_STARTS]:
        yield np.array([onset, math.log(peak_a), math.log(duration_a), 1.0,
                        onset_b, math.log(peak_b), math.log(duration_b), 1.0])


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
