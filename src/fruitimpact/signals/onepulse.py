"""One pulse or two: when a contact's own samples show a second pulse (issue 13 item 2).

A contact holds two pulses (two fruit, or a fruit and a rebound) when its force falls and rises again by more
than the noise can (``is_dip``), when one pulse of the force law misses it by more than a lone fruit of its lane
does and the samples show that misfit (``misfit_limit``, ``misfit_shown``), or, where a rebound is due, when two
pulses fit it better by more than chance and the lane's own misfit (``may_split``, ``split_gain``,
``LaneMisfits``).  Plain floats and arrays; ``signals.analysis`` applies these rules to each contact.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.signals.reports import is_finite_number
from fruitimpact.signals.split import MISFIT_LIMIT

#: A second rise (or an earlier fall) larger than this share of the peak is a second fruit in the contact ...
OVERLAP_FRACTION = 0.10
#: ... when it is also beyond this many noise sd: one pulse's own noise makes the smoothed force rise again after
#: its top by 1.4–1.6 σ at the median, 2.4–2.7 σ at p99 and 3.7 σ at most (tests/linegen.py's chain10, grades and
#: noisy at 1 % and 3 % noise); 2 σ at 3 % noise is 12–14 % of a 35–40 N rebound's peak: before this bound,
#: 219 contacts in 16 such recordings were reported as overlaps of pulses that were not there.  At 1 % noise
#: every overlap whose dip exceeds 10 % of its peak lies beyond 4 σ, so nothing changes there.
DIP_NOISE_SD = 4.0
#: The single-pulse misfit counts only when the samples show it: its excess variance (rms² − σ²)/σ² beyond this
#: many sd of its own scatter, √(2/n) over n samples (χ²/n of the noise alone).  A misfit of 2 % on a 35 N
#: rebound under 2.4 N of noise is 0.1 σ², inside that scatter (0.14 σ² per sd at 100 samples).
MISFIT_SD = 3.0
#: A contact in which a rebound is due (``rebounds.rebounds_due``) but that one pulse fits is split only when two
#: pulses fit it better by this much (χ² per sample, in noise variances; ``split_gain``): over ~240 samples that
#: is Δχ² ≈ 50 for 4 more parameters, far beyond chance.  Measured on the line scenarios of tests/linegen.py
#: (every contact where a rebound was due and a split was found): 527 single fruit gained at most 0.08 (a second
#: Hertz pulse cannot follow plate ringing or hum), 10 fruit and rebounds landing 0–1.5 ms apart gained
#: 0.22–2.2.  Below it the contact stays one fruit.
SPLIT_GAIN = 0.2
#: What one fruit of a lane leaves of its own pulse beyond the noise when the force law is not exactly the fit's
#: (an exponent of 1.3 where Hertz has 1.5, a fruit that is not a homogeneous sphere): its single-pulse misfit
#: (excess rms over the peak force) is learnt per lane as the median of the last ``LANE_MISFITS_KEPT`` contacts'
#: (a few fruit landing together do not move a median), once ``LANE_MISFITS_MIN`` are in.  Of that median, the
#: part beyond ``HERTZ_LINE_MISFIT`` (in quadrature) is the force law's: up to it, Hertz's own pulses leave it
#: through plate ringing, hum and drift, which no second pulse takes up (tests/linegen.py's eight scenarios: lane
#: medians 0–0.2 %, 0.5 % on ``noisy``).  A second pulse fitted to such a fruit takes up the force law's misfit,
#: not a second fruit: a split then has to gain, beyond ``SPLIT_GAIN``, ``MODEL_MARGIN`` times that share (1.5²:
#: a lone fruit's own misfit reaches 1.2–1.5 times the lane's median), and ``split.MISFIT_LIMIT`` is widened by
#: the same share.  Measured on tests/linegen.py's pulses with the force law's exponent at 1.3 (the same force at
#: the fruit's deflection): lone fruit left 0.8–1.0 % of their peak at the median, and 364 of them in 16
#: recordings (about 1,900 contacts) were reported as two pulses that could not be told apart; 18 now.  An
#: exponent of 1.7 leaves 0.5 %, as much as ringing and hum do on ``noisy``: the misfit does not tell the two
#: apart, and such a line still loses grades to overlaps (104 → 73; docs/signals.md).
LANE_MISFITS_KEPT, LANE_MISFITS_MIN, MODEL_MARGIN, HERTZ_LINE_MISFIT = 15, 5, 2.25, 0.005


def is_dip(second: float, peak: float, noise: float) -> bool:
    """Whether a contact's second rise (``indices.second_pulse``, [N]) is a second pulse: beyond
    ``OVERLAP_FRACTION`` of its peak [N] and beyond ``DIP_NOISE_SD`` noise sd [N]."""
    return is_finite_number(peak) and peak > 0 and second > max(OVERLAP_FRACTION * peak, DIP_NOISE_SD * noise)


def single_misfit(residual: float, noise: float, peak: float) -> float:
    """What one pulse leaves of a contact beyond the noise, over its peak: √(rms² − σ²)/F_max (NaN when the fit
    gave no residual)."""
    if not (is_finite_number(residual) and is_finite_number(peak) and peak > 0):
        return math.nan
    return math.sqrt(max(residual ** 2 - noise ** 2, 0.0)) / peak


def misfit_limit(share: float) -> float:
    """The largest misfit of one fruit on a lane whose fruit leave ``share`` (``LaneMisfits.share``)."""
    return math.hypot(MISFIT_LIMIT, math.sqrt(MODEL_MARGIN) * share)


def misfit_shown(misfit: float, peak: float, noise: float, samples: int) -> bool:
    """Whether the samples show ``misfit`` (``MISFIT_SD``); without noise (a clean signal: the detector's σ
    decays to 0) a misfit has no scatter and is always shown."""
    return not noise > 0 or (misfit * peak / noise) ** 2 > MISFIT_SD * math.sqrt(2.0 / max(samples, 1))


class LaneMisfits:
    """The single-pulse misfit each lane's fruit leave (``LANE_MISFITS_KEPT``), learnt contact by contact."""

    def __init__(self):
        self._seen: dict[int, list[float]] = {}

    def share(self, lane: int) -> float:
        """The misfit the force law leaves on one fruit of ``lane`` (excess rms over the peak force): the median
        of its recent contacts' beyond ``HERTZ_LINE_MISFIT`` (in quadrature), 0 until ``LANE_MISFITS_MIN`` are
        in."""
        seen = self._seen.get(lane, [])
        if len(seen) < LANE_MISFITS_MIN:
            return 0.0
        return math.sqrt(max(float(np.median(seen)) ** 2 - HERTZ_LINE_MISFIT ** 2, 0.0))

    def seen(self, lane: int, misfit: float) -> None:
        """One more contact of ``lane`` whose single pulse left ``misfit`` (NaN: none to learn)."""
        if not is_finite_number(misfit):
            return
        seen = self._seen.setdefault(lane, [])
        seen.append(misfit)
        del seen[:-LANE_MISFITS_KEPT]

    def model_variance(self, lane: int, peak: float, noise: float) -> float:
        """What a split must gain beyond ``SPLIT_GAIN`` on ``lane`` for a contact of peak ``peak`` [N] under
        ``noise`` [N], in noise variances per sample (``MODEL_MARGIN``): 0 on a lane whose fruit the force law
        fits to the noise."""
        share = self.share(lane)
        if not (share > 0 and noise > 0 and is_finite_number(peak)):
            return 0.0
        return MODEL_MARGIN * (share * peak / noise) ** 2


def split_gain(shape: dict, parts, noise: float) -> float:
    """How much better two pulses fit the contact's window than one: the drop of χ² per sample, in units of
    the noise variance ((rms₁² − rms₂²)/σ²; both fits are over the same samples)."""
    one, two = shape.get("fit_residual", math.nan), parts[0][1].get("fit_residual", math.nan)
    if not (is_finite_number(one) and is_finite_number(two) and noise > 0):
        return 0.0
    return (one ** 2 - two ** 2) / noise ** 2


def may_split(shape: dict, noise: float, model: float = 0.0) -> bool:
    """Whether two pulses might fit the contact better than one by ``SPLIT_GAIN`` (and ``model``, the lane's
    ``LaneMisfits.model_variance``), a screen before the joint fits (each costs ~1 ms): a second pulse only
    removes structure, not the noise, so a single fit whose residual is below (0.95 + ``SPLIT_GAIN`` + model) σ²
    leaves little for it.  Statistical, not a bound (χ²/n scatters by √(2/n), ~0.09 over a contact): on the line
    scenarios of tests/linegen.py it skipped 93 % of the single fruit where a rebound was due and none of the
    fruit and rebounds that were then told apart (their single fits left ≥ 1.2 σ²)."""
    residual = shape.get("fit_residual", math.nan)
    return is_finite_number(residual) and noise > 0 and residual ** 2 >= (0.95 + SPLIT_GAIN + model) * noise ** 2


__all__ = ["DIP_NOISE_SD", "HERTZ_LINE_MISFIT", "LANE_MISFITS_KEPT", "LANE_MISFITS_MIN", "LaneMisfits", "MISFIT_SD",
           "MODEL_MARGIN", "OVERLAP_FRACTION", "SPLIT_GAIN", "is_dip", "may_split", "misfit_limit", "misfit_shown",
           "single_misfit", "split_gain"]
