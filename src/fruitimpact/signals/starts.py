"""Where the joint fit of two pulses in one contact starts (``signals.split``).

Two pulses a few milliseconds apart show no dip: the second lands on the first one's rise or peak and only a
shoulder shows, so the joint fit is started from several places (``joint_starts``): the two maxima and the dip
between them when the force falls and rises again (``landmarks``), then the best of a grid of pulse pairs (the
first starting with the contact, the second anywhere in it, each ``GRID_DURATIONS`` of the contact's span,
x = 1; and, for each expected rebound, that rebound's own pulse beside a fruit pulse), each pair's two peaks by
linear least squares, ranked by χ² with the prior's (``_pair_table``, compiled: a contact holding two pulses
is the tail of a stream's latency).  The best start of each hypothesis comes first.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.signals.indices import SECOND_PULSE_SMOOTHING, departure_from_one_peak
from fruitimpact.signals.pulse import PulseModel

__all__ = ["GRID_DURATIONS", "GRID_ONSETS", "Prior", "joint_starts", "landmarks"]

#: Ratio T/t_c of the starting guesses (a Hunt–Crossley pulse with e ≈ 0.6; the fit moves it).
_DURATION_OVER_RISE = 3.2
#: The grid of starts: second onsets over the contact, durations as shares of the contact's span (one pulse
#: alone spans 100 %; two that overlap each span less).
GRID_ONSETS = 12
GRID_DURATIONS = (0.55, 0.7, 0.85)
#: Least peak of either pulse of a start, as a share of the contact's peak.
MIN_SHARE = 0.1


class Prior:
    """Gaussian priors on one pulse's (ln F_max, ln T, x): extra rows (θ[index] − mean) · weight of the least
    squares (``leastsquares.fit_pulse_sum``)."""

    KEYS = ("log_peak", "log_duration", "x")

    def __init__(self, expected: dict, pulse: int):
        self.index = np.array([4 * pulse + 1, 4 * pulse + 2, 4 * pulse + 3])
        self.mean = np.array([expected[k] for k in self.KEYS], dtype=float)
        self.weight = 1.0 / np.array([expected[f"{k}_sd"] for k in self.KEYS], dtype=float)

    def chi2(self, theta) -> float:
        return float(np.sum(((theta[self.index] - self.mean) * self.weight) ** 2))


def landmarks(y: np.ndarray) -> tuple[int, int, int] | None:
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


def joint_starts(ts: np.ndarray, y: np.ndarray, noise: float, marks, expected, limit: int) -> list:
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
    priors = np.array([[guess[key] for key in Prior.KEYS] + [guess[f"{key}_sd"] for key in Prior.KEYS]
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
        prior = Prior(expected[on[i, 0]], int(on[i, 1])) if on[i, 0] >= 0 else None
        starts.append((theta[i].copy(), prior))
    return starts[:limit]


@nb.njit(cache=CACHE, error_model="numpy")
def _pair_table(ts, y, noise, units, first, grid, shape_durations, shape_x, n_generic, priors, floor):
    """The pairs of unit pulses of ``joint_starts``, solved (compiled: this was ~40 NumPy calls and 0.5–1.9 ms per
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


def _nearest_prior(theta, expected) -> Prior | None:
    """The prior of the expected pulse nearest either pulse of ``theta`` (least prior χ²), or None."""
    priors = [Prior(guess, pulse) for guess in expected for pulse in (0, 1)]
    return min(priors, key=lambda prior: prior.chi2(theta), default=None)
