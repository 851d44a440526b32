"""Two fruit in one contact, told apart (issue 13, item 2).

When a second fruit (or a rebound) lands on the plate while another is still in contact, forces on one plate
add and both contacts are the simulator's Hunt–Crossley pulse, so the contact is fitted as the sum of two,

    F(t) = F_A · H((t − t0_A)/T_A; x_A) + F_B · H((t − t0_B)/T_B; x_B),

with the tabulated shape H of one pulse (``signals.pulse``), eight parameters, by the same Levenberg–Marquardt
compiled for a sum of pulses (``leastsquares.fit_pulse_sum``).

Starts.  Two pulses a few milliseconds apart show no dip: the second lands on the first one's rise or peak and
only a shoulder shows.  So the fit is started from several places (``_starts``): the two maxima and the dip
between them when the force falls and rises again, then the best of a grid of pulse pairs (the first starting
with the contact, the second anywhere in it, each 55–85 % of the contact's span, x = 1), each pair's two peaks
from linear least squares, and ``fits`` of them are fitted (the best of each hypothesis first; a pair with an
expected rebound's own pulse is one hypothesis per duration of the fruit beside it).  With a rebound due, a fit
that leaves only the noise (``GOOD_MISFIT``, and a χ² within ``NOISE_CHI2_SD`` of the samples') and agrees with
the rebound ends the search.  The pairs of the grid are solved by one compiled routine (``_pair_table``), and the
starts' fits run side by side on worker threads (``PARALLEL_FITS``; the compiled iteration releases the GIL),
their results taken in the starts' order so that the choice is the one a single thread makes: a contact holding
two pulses is the tail of a stream's latency (benchmarks/latency.py).

Choice.  The first pulse's tail lies under the second, so several fits can leave the same residual (two fits
of one overlap: e 0.34 with 94.6 N, or e 0.71 with 99.9 N).  Physics chooses.  When an earlier fruit's rebound
is due in the contact, that rebound is the same fruit at its exit speed: its peak, duration and x are known
within the spread of the speed ratio and the spot it lands on (``rebounds.expected_rebound``).  They enter as
Gaussian priors on one pulse (extra rows of the least squares; the grid also holds pairs with that pulse
itself), and the least χ² of data and prior together wins.  Of fits whose χ² are alike (with a rebound due or
without), the one whose restitutions do not fall below the lane's fruit (a rebound lands slower, so its e is
higher).

Acceptance.  A separation is kept only when the sum leaves nothing but the noise (``MISFIT_LIMIT`` of the
larger peak beyond it, as for one pulse), both pulses lie in the window in order (the last may end a little
after a window cut before the next contact) and each is well above the noise; then each pulse is reported as
its own contact, its indices measured on the samples less the other pulse's model, its fit the corresponding
block of the joint fit (its standard errors from the joint covariance, so the other pulse's uncertainty is in
them).  Otherwise the contact stays one report with status ``overlap`` (``analysis``).
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from contextlib import closing
from functools import partial

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.powerlaw import restitution_of_x
from fruitimpact.signals.fit import MIN_PEAK_SNR, RESULT_KEYS, named_result
from fruitimpact.signals.leastsquares import fit_pulse_sum
from fruitimpact.signals.pulse import X_MAX, PulseModel
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
#: alone spans 100 %; two that overlap each span less).
GRID_ONSETS = 12
GRID_DURATIONS = (0.55, 0.7, 0.85)
#: Starts fitted: a contact held for two pulses (a dip or a misfit), and one that one pulse fits but in which a
#: rebound is due (``FITS_DUE``: most contacts of a busy line; each fit costs 2–5 ms).
FITS = 4
FITS_DUE = 4
#: Joint fits run side by side, each start on its own thread (the compiled iteration releases the GIL): as many
#: as the process may use cores, up to ``FITS``.  The results are taken in the starts' order, whatever finishes
#: first, so the choice is the one a single thread makes (1: one after the other, on the calling thread).
PARALLEL_FITS = min(FITS, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
#: A fit whose prior χ² (three parameters) is within this (the 95 % point of χ² with 3 degrees of freedom) agrees
#: with the expected rebound.
PLAUSIBLE_PRIOR_CHI2 = 7.81
#: Least peak of either pulse of a start, as a share of the contact's peak.
MIN_SHARE = 0.1
#: Iterations of one joint fit: from these starts an accepted fit converges in ≤ 20 (90 %) and 52 at most (the
#: line scenarios); one still moving after 40 is a start in the wrong valley, and another start is tried.
SPLIT_ITERATIONS = 40
#: How far a pulse may end after the window [share of its duration]: the window is cut before the next
#: contact's rise, and a Hunt–Crossley pulse's last 15 % carry ~2 % of its impulse (its force ~(T − t)^1.5).
END_ALLOWANCE = 0.15
#: A separation that leaves at most this share of the peak beyond the noise and whose pulse agrees with the
#: expected rebound is taken at once (the rest of the starts are not fitted: latency); otherwise every start
#: is fitted and the choice below made.  Without a prior no fit is taken early: wrong local minima of two fruit
#: 1 ms apart leave as little (0.2–0.3 %).
GOOD_MISFIT = 0.004
#: ... and only when the samples' χ² is what the noise alone leaves: within this many sd (√(2n)) of the n samples.
#: A wrong valley can leave less than ``GOOD_MISFIT`` of a large peak (0.38 % of 104 N, χ² 326 for 268 samples,
#: 2.7 sd, where the right pair left χ² 269).
NOISE_CHI2_SD = 2.0
#: Separations whose χ² lie within this of the least are alike (3 sd of one parameter): the data cannot choose
#: between them, the lane's restitution does (``_implausibility``).
ALIKE_CHI2 = 9.0
#: A part's restitution may lie this far below the lane's fruit before it counts as implausible (the lot's
#: spread of e: c varies ±25 % between fruit, e by ±0.1 at e ≈ 0.6).
RESTITUTION_SPREAD = 0.12


class _TwoPulses:
    """F(t; θ_A) + F(t; θ_B) and its Jacobian (the fitted model, for residuals and the separated forces)."""

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
                  restitution=None, expected=(), fits: int = FITS, dip: bool = True):
    """Fit two pulses to one contact (module docstring).

    ``time`` [s] and ``force`` [N] are the contact's window (baseline removed), ``noise`` the noise sd [N];
    ``velocity`` or ``mass`` and ``diameter``/``poisson`` as for ``fit.fit_impact`` (applied to both).
    ``restitution``: the lane's typical fruit restitution, when known, to choose between separations that fit
    alike; ``expected``: the pulses one of the two may be (``rebounds.expected_rebound`` of each earlier contact
    whose rebound is due), each as Gaussian priors on its peak, duration and x (module docstring); ``fits``: how
    many of the best starts are fitted; ``dip``: the force falls and rises again (the landmarks then give the
    first start; without a dip, landmarks found in the noise would only waste a fit).
    Returns ((result_A, separated force A), (result_B, separated force B)) in time order, each result a dict
    with the keys of ``fit.RESULT_KEYS``, or None when the contact is not separated."""
    t = np.asarray(time, dtype=float)
    y = np.asarray(force, dtype=float)
    if t.size < 24 or not noise > 0:
        return None
    t_ref = float(t[0])
    ts = t - t_ref
    model = _TwoPulses(ts)
    weights = np.full(ts.shape, 1.0 / noise)
    args = (velocity if mass is None else None, mass, diameter, poisson)
    found = []
    starts = _starts(ts, y, noise, _landmarks(y) if dip else None, expected, fits)
    with closing(_in_order([partial(_joint_fit, ts, y, weights, theta, prior) for theta, prior in starts])) as fitted:
        for (_, prior), result in zip(starts, fitted):
            fit = _separated(model, ts, y, noise, result, prior)
            if fit is None:
                continue
            found.append(fit)
            prior_chi2 = prior.chi2(fit[2]) if prior is not None else math.inf
            if prior_chi2 <= PLAUSIBLE_PRIOR_CHI2 and fit[1] <= GOOD_MISFIT \
                    and fit[0] - prior_chi2 <= ts.size + NOISE_CHI2_SD * math.sqrt(2.0 * ts.size):
                break  # it leaves only the noise and one pulse is the rebound that was due: taken (latency)
    if not found:
        return None
    # the least χ² (with a rebound due, the posterior: the data's χ² and the prior's); of fits alike in it, the one
    # whose restitutions are plausible for the lane (two fits of a fruit and a due rebound 3.5 ms later on a noisy
    # line: χ² 374.6 with the fruit at e 0.30, 377.3 with it at 0.57, the lane's fruit at 0.55)
    least = min(fit[0] for fit in found)
    alike = [fit for fit in found if fit[0] <= least + ALIKE_CHI2]
    best = min(alike, key=lambda fit: (_implausibility(fit[2], restitution), fit[0]))
    _, _, theta, covariance, rms, iterations = best
    try:
        return _parts(theta, covariance, args, t_ref, ts, rms, noise, iterations, model, y)
    except (OverflowError, ValueError, np.linalg.LinAlgError):  # a part beyond double precision: not separated
        return None


class _Prior:
    """Gaussian priors on one pulse's (ln F_max, ln T, x): extra rows (θ[index] − mean) · weight of the least
    squares (``leastsquares.fit_pulse_sum``)."""

    KEYS = ("log_peak", "log_duration", "x")

    def __init__(self, expected: dict, pulse: int):
        self.index = np.array([4 * pulse + 1, 4 * pulse + 2, 4 * pulse + 3])
        self.mean = np.array([expected[k] for k in self.KEYS], dtype=float)
        self.weight = 1.0 / np.array([expected[f"{k}_sd"] for k in self.KEYS], dtype=float)

    def chi2(self, theta) -> float:
        return float(np.sum(((theta[self.index] - self.mean) * self.weight) ** 2))



def _implausibility(theta, restitution) -> float:
    """How far the parts' restitutions fall below the lane's fruit (0 without a lane value): a fruit has the
    restitution of the lane's fruit and a rebound, landing slower, a higher one (x = c V is smaller), so a part
    far below it is the other pulse's tail traded for its amplitude."""
    if restitution is None:
        return 0.0
    return sum(max(0.0, restitution - RESTITUTION_SPREAD - restitution_of_x(float(x))) for x in theta[3::4])


def _joint_fit(ts, y, weights, theta, prior):
    """``fit_pulse_sum`` of two pulses from the start ``theta`` with its prior (None: none).  Safe on any thread:
    it shares no buffer (``_separated`` then judges the result on the calling thread, with the model's)."""
    with np.errstate(all="ignore"):  # a trial step far out (a duration of e^700) is a failed separation
        return fit_pulse_sum(ts, y, weights, theta,
                             *((prior.index, prior.mean, prior.weight) if prior is not None else ()),
                             max_iterations=SPLIT_ITERATIONS)


_POOL: dict = {}


def _in_order(jobs: list):
    """The results of ``jobs`` (callables) in their order, computed up to ``PARALLEL_FITS`` at a time on worker
    threads; those not yet begun are cancelled when the caller stops early (``closing``).  A forked child (the web
    app's workers) gets its own pool: the parent's threads do not exist there."""
    if PARALLEL_FITS < 2 or len(jobs) < 2:
        for job in jobs:
            yield job()
        return
    pool = _POOL.get(os.getpid())
    if pool is None:
        _POOL.clear()
        pool = _POOL[os.getpid()] = ThreadPoolExecutor(PARALLEL_FITS, thread_name_prefix="fruitimpact-fit")
    futures = [pool.submit(job) for job in jobs]
    try:
        for future in futures:
            yield future.result()
    finally:
        for future in futures:
            future.cancel()


def _separated(model, ts, y, noise, result, prior=None):
    """(χ², misfit, θ, covariance, rms, iterations) of a joint fit (``_joint_fit``'s result) when it is accepted
    (module docstring), else None."""
    theta, jac, _, iterations, converged, _ = result
    if not np.all(np.isfinite(theta)):
        return None
    try:  # a degenerate pulse (a peak or duration beyond double precision) is a failed separation
        with np.errstate(all="ignore"):
            residual = model(theta) - y
            rms = float(np.sqrt(np.mean(residual ** 2)))
            peaks = math.exp(theta[1]), math.exp(theta[5])
            misfit = math.sqrt(max(rms ** 2 - noise ** 2, 0.0)) / max(peaks)
            durations = math.exp(theta[2]), math.exp(theta[6])
            # the window may end a little before the last pulse does (cut before the next contact's rise):
            # its last 15 % carries ~2 % of the impulse, so the fit still sees the whole pulse
            late = max(theta[0] + durations[0] - ts[-1], theta[4] + durations[1] - ts[-1], 0.0)
            if not (converged and misfit <= MISFIT_LIMIT and ts[0] <= theta[0] < theta[4]
                    and late <= END_ALLOWANCE * min(durations)
                    and min(peaks) > MIN_PEAK_SNR * noise and theta[3] < X_MAX and theta[7] < X_MAX):
                return None
            # the posterior: the samples and, with a rebound due, what physics expects of it (the fruit piece is
            # then determined given that the other pulse is that rebound; the rebound piece's own values are
            # drawn toward the expected ones within their spread, so its rebound test confirms consistency)
            covariance = np.linalg.inv(jac.T @ jac)
            chi2 = float(np.sum((residual / noise) ** 2)) + (prior.chi2(theta) if prior is not None else 0.0)
            return chi2, misfit, theta, covariance, rms, iterations
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None


def _starts(ts: np.ndarray, y: np.ndarray, noise: float, marks, expected=(), limit: int = FITS) -> list:
    """The ``limit`` most likely starts of the joint fit, as (θ, prior or None): from the landmarks (two maxima
    and a dip) when there are any, then pulse pairs of a grid ranked by their χ² (module docstring): the generic
    pairs (the second onset anywhere in the contact, each pulse ``GRID_DURATIONS`` of its span, x = 1) and, for
    each expected rebound, that pulse (its own duration and x) at every onset of the grid beside a fruit pulse
    starting with the contact, or starting with the contact beside a fruit pulse anywhere; each pair's two peaks
    by linear least squares, its χ² counted with the prior's.  A start with a prior has it on the pulse it
    expects (for a generic pair, the expected pulse nearest either of its pulses).  Onsets lie on samples, so
    each pulse shape is computed once and shifted, and every pair is solved at once from their inner products."""
    step = ts[1] - ts[0]
    level = 3.0 * noise
    starts = []
    if marks is not None and marks[0] < marks[1] < marks[2]:
        first, dip, second = marks
        start_a = _onset(y, first, level)
        rise_a = max(ts[first] - ts[start_a], 3 * step)
        start_b = dip - max(2, round(0.25 * (second - dip)))
        rise_b = max(ts[second] - ts[start_b], 3 * step)
        peak_a = max(float(y[first]), level)
        peak_b = max(float(y[second] - 0.5 * y[dip]), level)
        theta = np.array([ts[start_a], math.log(peak_a), math.log(_DURATION_OVER_RISE * rise_a), 1.0,
                          ts[start_b], math.log(peak_b), math.log(_DURATION_OVER_RISE * rise_b), 1.0])
        starts.append((theta, _nearest_prior(theta, expected)))
    # the contact: from the last sample at the noise level before its maximum to the first after it (a lone
    # noise sample above 3 sd elsewhere in the window must not stretch it)
    n = ts.size
    top = int(np.argmax(y))
    after = np.flatnonzero(y[top:] <= level)
    if not after.size:
        return starts[:limit]
    first = _onset(y, top, level)
    span = float(ts[top + int(after[0])] - ts[first])
    if span < 8 * step:
        return starts[:limit]
    durations = [f * span for f in GRID_DURATIONS]
    last = first + max(int((span - 0.5 * min(durations)) / step), 4)
    grid = np.unique(np.linspace(first + 3, last, GRID_ONSETS).round().astype(int))
    grid = [int(k) for k in grid[grid < n]]
    model = PulseModel(ts - ts[0])
    # the unit pulses (peak 1): each shape (duration, x) once, at the window's first sample; the compiled kernel
    # shifts them to each onset and solves every pair
    shapes = [(duration, 1.0) for duration in durations] + \
        [(math.exp(guess["log_duration"]), guess["x"]) for guess in expected]
    units = np.empty((len(shapes), n))
    for s_index, (duration, x) in enumerate(shapes):
        units[s_index] = model.pulse((0.0, 0.0, math.log(duration), x))
    priors = np.array([[guess[key] for key in _Prior.KEYS] + [guess[f"{key}_sd"] for key in _Prior.KEYS]
                       for guess in expected], dtype=float).reshape(len(expected), 6)
    # a second pulse below a tenth of the contact's peak is the noise or the plate's ringing, not a fruit (a
    # rebound lands with ≥ 20 % of a fruit's peak): such pairs would only waste a fit
    floor = max(level, MIN_SHARE * float(y[top]))
    table, theta, score, on = _pair_table(ts, y, noise, units, first, np.array(grid, dtype=np.int64),
                                          np.array([duration for duration, _ in shapes]),
                                          np.array([x for _, x in shapes]), len(durations), priors, floor)
    ranked = np.argsort(score, kind="stable")
    ranked = ranked[np.isfinite(score[ranked])]
    # the best start of each hypothesis (which expected rebound is which pulse, with that rebound's own pulse or
    # a generic one) first, the rebound's own pulse before the generic: the grid's coarse χ² alone would spend
    # every fit on one hypothesis, and a generic pulse as the rebound can lead into a valley where the rebound
    # took the fruit's tail (χ² 234 against 210 for the right pair, in one case of tests/test_signals_rebounds)
    # and a pair with the expected rebound's own pulse is one hypothesis per duration of the fruit beside it: the
    # coarse grid (x = 1) ranks a fruit too short first when the fruit is a damped one, and a fit started there
    # stays in the valley where the rebound took part of the fruit's tail (χ² 332 against 270, peak 22 % high)
    fruit_duration = np.where(table[ranked, 7] == 1, table[ranked, 2], table[ranked, 3])
    own = table[ranked, 6] >= 0
    fruit_index = np.where(own, np.searchsorted(durations, fruit_duration * (1 - 1e-9)) + 1, 0)
    keys = np.column_stack([(table[ranked, 6] < 0).astype(int), on[ranked, 0], on[ranked, 1], fruit_index])
    # one row per (generic, k, pulse, fruit duration): each key packed into one integer (k ≥ −1, pulse ≥ −1 and
    # the duration index ≤ len(durations) + 1 are small), whose 1-D unique is several times faster than by rows
    packed = ((keys[:, 0] * (len(expected) + 1) + keys[:, 1] + 1) * 3 + keys[:, 2] + 1) * (len(durations) + 2) \
        + keys[:, 3]
    _, first_seen = np.unique(packed, return_index=True)
    firsts = {tuple(int(v) for v in keys[j]): int(ranked[j]) for j in np.sort(first_seen)}  # in ranked order
    chosen = [firsts[key] for key in sorted(firsts, key=lambda key: (key[0], score[firsts[key]]))]
    wanted = max(limit - len(starts), 0)
    taken = set(chosen)
    order = chosen + [int(i) for i in ranked[:wanted + len(chosen)] if int(i) not in taken]
    for i in order[:wanted]:
        prior = _Prior(expected[on[i, 0]], int(on[i, 1])) if on[i, 0] >= 0 else None
        starts.append((theta[i].copy(), prior))
    return starts[:limit]


@nb.njit(cache=CACHE, error_model="numpy")
def _pair_table(ts, y, noise, units, first, grid, shape_durations, shape_x, n_generic, priors, floor):
    """The pairs of unit pulses of ``_starts``, solved (compiled: this was ~40 NumPy calls and 0.5–1.9 ms per
    contact, on the tail of a stream's latency).  ``units``: the unit pulses (peak 1) starting at ts[0], the first
    ``n_generic`` of the grid's durations (x = 1), then one per expected rebound; ``priors``: per expected rebound
    the means and sds of (ln F_max, ln T, x).  Pulse A starts at sample ``first``, pulse B at a ``grid`` sample.

    Returns (table, θ, score, on): per pair a row of ``table`` (unit row A, unit row B, duration A, duration B,
    x A, x B, expected k or −1, which pulse the expected one is, B's onset sample), its start θ (the two peaks by
    linear least squares), its score (χ² of the samples plus the prior's; inf when a peak is below ``floor`` or
    the pair is degenerate) and (k, pulse) of its prior (−1, −1 without).  The rows come in the order of the
    loops: the generic pairs by (onset, duration A, duration B), then per expected rebound, by (onset, duration of
    the fruit beside it), the pair with the fruit first and the pair with the rebound first."""
    n = ts.shape[0]
    n_g = grid.shape[0]
    n_o = n_g + 1
    n_e = priors.shape[0]
    onsets = np.empty(n_o, np.int64)
    onsets[0] = first
    onsets[1:] = grid
    # each unit pulse shifted to each onset: row (shape s, onset o) = s × n_o + o
    n_rows = units.shape[0] * n_o
    matrix = np.zeros((n_rows, n))
    for s_index in range(units.shape[0]):
        for o_index in range(n_o):
            at = onsets[o_index]
            for i in range(at, n):
                matrix[s_index * n_o + o_index, i] = units[s_index, i - at]
    norms, projection = np.empty(n_rows), np.empty(n_rows)
    for r in range(n_rows):
        aa, ay = 0.0, 0.0
        for i in range(n):
            aa += matrix[r, i] * matrix[r, i]
            ay += matrix[r, i] * y[i]
        norms[r], projection[r] = aa, ay
    yy = 0.0
    for i in range(n):
        yy += y[i] * y[i]
    n_pairs = n_g * n_generic * n_generic + n_e * 2 * n_g * n_generic
    table = np.empty((n_pairs, 9))
    j = 0
    for at in range(n_g):
        for da in range(n_generic):
            for db in range(n_generic):
                table[j, 0], table[j, 1] = da * n_o, db * n_o + 1 + at
                table[j, 2], table[j, 3] = shape_durations[da], shape_durations[db]
                table[j, 4], table[j, 5], table[j, 6], table[j, 7] = 1.0, 1.0, -1.0, 0.0
                table[j, 8] = grid[at]
                j += 1
    for k in range(n_e):
        own = n_generic + k
        for at in range(n_g):
            for d in range(n_generic):
                table[j, 0], table[j, 1] = d * n_o, own * n_o + 1 + at  # the fruit first
                table[j, 2], table[j, 3] = shape_durations[d], shape_durations[own]
                table[j, 4], table[j, 5], table[j, 6], table[j, 7] = 1.0, shape_x[own], k, 1.0
                table[j, 8] = grid[at]
                table[j + 1, 0], table[j + 1, 1] = own * n_o, d * n_o + 1 + at  # the rebound first
                table[j + 1, 2], table[j + 1, 3] = shape_durations[own], shape_durations[d]
                table[j + 1, 4], table[j + 1, 5], table[j + 1, 6], table[j + 1, 7] = shape_x[own], 1.0, k, 0.0
                table[j + 1, 8] = grid[at]
                j += 2
    theta = np.empty((n_pairs, 8))
    score = np.empty(n_pairs)
    on = np.full((n_pairs, 2), -1, np.int64)
    for j in range(n_pairs):
        a, b = int(table[j, 0]), int(table[j, 1])
        ab = 0.0
        for i in range(n):
            ab += matrix[a, i] * matrix[b, i]
        aa, bb, ay, by = norms[a], norms[b], projection[a], projection[b]
        det = aa * bb - ab * ab
        peak_a, peak_b = (ay * bb - by * ab) / det, (by * aa - ay * ab) / det
        chi2 = (yy - 2.0 * (peak_a * ay + peak_b * by) + peak_a ** 2 * aa + 2.0 * peak_a * peak_b * ab
                + peak_b ** 2 * bb) / noise ** 2
        good = det > 1e-12 * aa * bb and peak_a > floor and peak_b > floor
        theta[j, 0], theta[j, 1] = ts[first], math.log(peak_a) if good else 0.0
        theta[j, 2], theta[j, 3] = math.log(table[j, 2]), table[j, 4]
        theta[j, 4], theta[j, 5] = ts[int(table[j, 8])], math.log(peak_b) if good else 0.0
        theta[j, 6], theta[j, 7] = math.log(table[j, 3]), table[j, 5]
        # the prior of the expected pulse nearest either pulse (a generic pair) or of its own (a pair with it)
        best = math.inf if n_e else 0.0
        for k in range(n_e):
            for pulse in range(2):
                if not (table[j, 6] < 0 or (table[j, 6] == k and table[j, 7] == pulse)):
                    continue
                value = 0.0
                for i in range(3):
                    value += ((theta[j, 4 * pulse + 1 + i] - priors[k, i]) / priors[k, 3 + i]) ** 2
                if value < best:
                    best = value
                    on[j, 0], on[j, 1] = k, pulse
        score[j] = chi2 + best if good else math.inf
    return table, theta, score, on


def _nearest_prior(theta, expected) -> _Prior | None:
    """The prior of the expected pulse nearest either pulse of ``theta`` (least prior χ²), or None."""
    priors = [_Prior(guess, pulse) for guess in expected for pulse in (0, 1)]
    return min(priors, key=lambda prior: prior.chi2(theta), default=None)


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
