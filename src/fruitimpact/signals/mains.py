"""The mains hum on a stream's first samples: 50 Hz, 60 Hz or none (``find_mains_hum``), for the detector's
``hum_frequency="auto"`` (``signals.detect``, step 0): a least-squares test, no state, no I/O."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["HUM_WINDOW", "MAINS_FREQUENCIES", "find_mains_hum"]

#: 1/Φ⁻¹(3/4): σ of normal noise from its median absolute deviation.
MAD_TO_SIGMA = 1.482602218505602
#: The mains frequencies [Hz] ``find_mains_hum`` looks for.
MAINS_FREQUENCIES = (50.0, 60.0)
#: The samples held to find the hum [s]: 10 cycles of 50 Hz, over which 50 and 60 Hz are orthogonal.
HUM_WINDOW = 0.2
#: The chance [-] that noise alone shows a hum, over every lane and both frequencies.
HUM_FALSE_ALARM = 1e-6
#: Around a contact in the window, this much [s] on each side is left out (its rise and its ringing).
HUM_MASK = 0.015
#: At most about this many samples per lane are fitted (a faster acquisition's are taken every k-th).
HUM_SAMPLES = 40_000
#: No hum below this amplitude [N] is removed (a constant lane's rounding is no hum).
HUM_FLOOR = 1e-3


def find_mains_hum(samples: np.ndarray, rate: float, harmonics=(1, 3)) -> tuple[float | None, float, float]:
    """The mains hum in the first samples [N] (samples × lanes) at ``rate`` [Hz]: (50.0, 60.0 or None, the
    fundamental's amplitude [N] on the lane that shows it best, its standard error [N]).

    Each lane's contacts are masked first (samples beyond 6 robust sd of the median, ±``HUM_MASK`` around them),
    then the rest is fitted by least squares with a level, a slope, a curvature and, for both 50 and 60 Hz, the
    cosine and sine of each of ``harmonics`` below rate/2.  A frequency is found where its fundamental's
    (cos, sin) pair is significant against its own covariance from the fit, σ² (XᵀX)⁻¹ (χ² with 2 degrees of
    freedom, beyond a false-alarm chance of ``HUM_FALSE_ALARM`` over every lane and both frequencies), more so than
    the other frequency's, and above ``HUM_FLOOR``.  A lane with fewer than ``HUM_WINDOW`` / 2 of samples left, or
    a window shorter than 2 cycles of 50 Hz, finds none."""
    x = np.asarray(samples, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    none = (None, 0.0, math.inf)
    if x.shape[0] < 2 * rate / MAINS_FREQUENCIES[0]:
        return none
    stride = max(1, x.shape[0] // HUM_SAMPLES)  # 0.2 s at 10 MHz: every k-th sample, ≥ 100 per mains cycle
    x, rate = x[::stride], rate / stride
    n, lanes = x.shape
    t = np.arange(n) / rate
    u = (t - t.mean()) / max(t[-1] - t[0], 1.0 / rate)
    columns = [np.ones(n), u, u * u]
    pairs = {}
    for frequency in MAINS_FREQUENCIES:
        for k in harmonics:
            if k * frequency < rate / 2:
                if frequency not in pairs:
                    pairs[frequency] = len(columns)
                columns += [np.cos(2 * math.pi * k * frequency * t), np.sin(2 * math.pi * k * frequency * t)]
    if not pairs:
        return none
    design = np.column_stack(columns)
    threshold = -2.0 * math.log(HUM_FALSE_ALARM / (len(pairs) * lanes))  # χ²₂ beyond it with that chance
    best = none
    best_stat = threshold
    margin = int(math.ceil(HUM_MASK * rate))
    for lane in range(lanes):
        y = x[:, lane]
        centre = float(np.median(y))
        spread = MAD_TO_SIGMA * float(np.median(np.abs(y - centre)))
        # a quantised quiet signal has no spread: then any departure from it is a contact
        limit = 6.0 * spread if spread > 0.0 else 1e-12 * (1.0 + float(np.max(np.abs(y))))
        outside = np.abs(y - centre) > limit
        if outside.any():  # a contact in the window: it and its ringing are no hum
            outside = np.convolve(outside, np.ones(2 * margin + 1), mode="same") > 0
        keep = ~outside
        if np.count_nonzero(keep) < max(n // 2, 2 * design.shape[1]):
            continue
        a, b = design[keep], y[keep]
        coefficients, *_ = np.linalg.lstsq(a, b, rcond=None)
        residual = b - a @ coefficients
        dof = b.size - a.shape[1]
        sigma2 = float(residual @ residual) / dof
        try:
            covariance = np.linalg.inv(a.T @ a)
        except np.linalg.LinAlgError:
            continue
        stats = {}
        for frequency, j in pairs.items():
            beta = coefficients[j:j + 2]
            block = covariance[j:j + 2, j:j + 2] * sigma2
            try:
                stats[frequency] = (float(beta @ np.linalg.solve(block, beta)), float(np.hypot(*beta)),
                                    math.sqrt(0.5 * float(np.trace(block))))
            except np.linalg.LinAlgError:
                stats[frequency] = (0.0, 0.0, math.inf)
        frequency = max(stats, key=lambda f: stats[f][0])
        stat, amplitude, error = stats[frequency]
        others = [stats[f][0] for f in stats if f != frequency]
        if stat > best_stat and amplitude > HUM_FLOOR and all(stat > other for other in others):
            best, best_stat = (frequency, amplitude, error), stat
    return best
