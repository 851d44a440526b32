"""Impact detection on force signals, as one causal state machine (issue 8, items 2 and 6).

A force signal [N] sampled at ``rate`` [Hz] (one or more lanes sampled together) goes through a
per-sample state machine compiled with numba.  Everything the machine remembers — the filters'
delay lines, the baseline, hum and noise estimates, the impact in progress, the impacts waiting for
emission and a ring of recent samples — lives in small per-lane state arrays carried from one call
to the next.  So feeding a stream in chunks of any size gives exactly (bit for bit) what feeding the
whole array at once gives: ``detect(force, rate)`` *is* a ``Detector`` fed the whole array and
flushed.

Per sample and lane, in this order:

0. **Mains hum found** (``hum_frequency="auto"``): the first ``HUM_WINDOW`` of samples are held and
   ``find_mains_hum`` decides 50, 60 Hz or none before anything else; then they are processed as any others.
1. **Clipping**: the raw sample at or beyond ``clip_low``/``clip_high`` marks the impact in progress
   ``clipped``.
1b. **Discharge restoration** (``discharge_time``: τ given, measured, or ``math.inf``: none): a piezoelectric
   chain (quartz sensor and charge amplifier, or IEPE) is a first-order high-pass, dy/dt = dx/dt − y/τ, so a
   contact of impulse I droops by up to I/τ and the signal undershoots by ≈ I/τ after it (a few % of the peak at
   τ = 0.1 s: the fitted stiffness was ~10 % off in the scorecard's lines). Its inverse is x = y + (1/τ) ∫ y dt;
   the integral is the trapezoidal sum of the raw samples, leaking with ``DISCHARGE_LEAK`` · τ so that the
   acquisition's own offset stays bounded (the chain and its inverse together are then a high-pass of time
   constant ``DISCHARGE_LEAK`` · τ, whose droop over a contact is a hundredth of the sensor's; the offset comes
   out ``DISCHARGE_LEAK`` + 1 times larger and is the baseline the next stage removes), started in its steady
   state for the first sample. Measured (τ None): at each lone contact's emission (``_measure_discharge``) the
   window's samples after the contact, against the level before its foot, sit at −κ times the window's running
   integral, κ = 1/τ still missing; each measurement's standard error counts the noise's lag-1 correlation (a
   low-passed noise), one faster than ``MIN_DISCHARGE_TIME`` is dropped. The lane restores the median of its last
   ``DISCHARGE_KEPT`` once it exceeds ``DISCHARGE_SHOWN`` standard errors (from ``DISCHARGE_SCATTER_FROM``
   measurements on, also their own scatter's), keeps it above ``DISCHARGE_HELD``, restores the window that showed
   it, keeps the signal continuous where the gain changes (an offset), and drops it at an overlong contact. The
   integral leaks with ``DISCHARGE_AUTO_LEAK``. Contacts at rates where fewer than 3 samples follow the contact
   in its window, or so long (≥ ~12 ms at 20 kHz) that none precede its foot in the window, measure nothing.
2. **Low-pass** (optional): a causal Butterworth of ``lowpass_order`` at ``lowpass_cutoff``, a cascade
   of biquads designed here (bilinear transform with prewarping; no SciPy at run time), started in
   its steady state for the first sample.
3. **Baseline and hum**: the zero/drift b (level and slope s per sample) and the mains hum
   h(n) = Σ_k a_k cos(k ω n) + d_k sin(k ω n) (harmonics k of ``hum_frequency``, optional) are tracked by
   one adaptive canceller driven by the prediction error r = y − b − h and updated **only while no
   impact is in progress**: b ← b + s + (1 − λ²) r, s ← s + (1 − λ)² r with λ = exp(−1/(τ_b · rate))
   (Brown's double exponential smoothing of the quiet signal, time constant ``baseline_time_constant``:
   it follows a linear drift without lag, where a plain exponential average lags by slope × τ_b),
   a_k ← a_k + g r cos, d_k ← d_k + g r sin with g = 2π f_hum / (Q · rate).  During an impact the
   baseline is extrapolated linearly from the onset, b + s (n − start), and resumes from there after
   it.  While it adapts, the hum part *is* a causal IIR notch at each harmonic with a −3 dB bandwidth
   of ≈ f_hum/Q (Widrow et al. 1975, "Adaptive noise cancelling", Proc. IEEE 63:1692; simulated:
   47.3–52.9 Hz for 50 Hz, Q = 10 at 20 kHz, beside the baseline loop's own −3 dB corner at ≈ 4 Hz).
   Frozen during an impact, it does not notch the pulse (a fixed notch would remove the pulse's own
   50 Hz content and ring for Q/(π f) s afterwards) and extrapolates the hum across the contact.
4. **Noise**: σ is a robust running standard deviation of r over the quiet samples: an exponential
   average (``noise_time_constant``) of |r| clipped at 3σ, scaled by 1/0.79712 (the mean of
   min(|N(0,1)|, 3)).
5. **Onset / offset** (hysteresis): quiet → impact when r > max(k_on σ, ``threshold_floor``); the onset
   (``start_index``) is that first sample above.  Baseline and σ are frozen there.  The impact ends
   when r stays below max(k_off σ, ``threshold_floor`` · k_off/k_on) for ``offset_hold`` consecutive
   samples; ``end_index`` is the last sample above that offset threshold.  A contact shorter than
   ``min_duration`` (end − start + 1 samples) is discarded; one longer than ``max_duration`` is ended
   there, flagged ``overlong``, and the detector re-learns the baseline (a new warm-up).
6. **Neighbours**: each impact records the end of the previous impact of its lane (``previous_end``)
   and, at emission, the onset of the next one when it began inside this impact's window
   (``next_start``), so that the indices and the fit use only the samples that belong to it
   (two fruit a few milliseconds apart are two impacts, never one fitted through both).  Whether an
   impact is the rebound of an earlier one is not decided here but from the fruit's physics, after
   the indices (``signals.rebounds``).

Warm-up: the first ``warmup`` seconds of a lane (and the ``warmup`` after an overlong impact) only learn
the baseline level and slope (from the medians of the two halves, or by least squares together with
the hum terms when hum removal is on) and σ (1.4826 × the median absolute residual); no impact can
start during a warm-up.  The stream should begin with that much quiet signal.

Emission (what ``feed`` returns, and when)
-----------------------------------------
An impact of a lane is emitted, as a ``DetectedImpact``, while processing sample n = end_index +
post-trigger samples: its end has been confirmed (``offset_hold`` samples below the offset threshold, or
``max_duration``) and its window is complete.  Nothing waits for a later impact, so the latency from the
last sample above the offset threshold to the emission is max(post-trigger, offset_hold) samples
(``emitted_at`` = n + 1 samples consumed) and every field is final.  Within a lane impacts are emitted in
order; one ``feed`` returns them sorted by (``emitted_at``, lane).  ``flush()`` ends the stream: an impact in
progress is ended at its last sample above the offset threshold and emitted with ``truncated = True``
(regardless of ``min_duration``), then every impact still held is emitted with the window cut at the last
sample fed (``emitted_at`` = samples fed).  After ``flush`` the detector accepts no more samples
(``reset()`` starts a new stream).

The window of an impact holds the samples from start_index − pre-trigger to end_index + post-trigger
(cut at the stream's start and, at flush, its end), low-pass filtered and with hum removed as
configured, minus the impact's baseline (frozen at the onset and extrapolated with its slope): ready
for the indices (``signals.indices``) and a model fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.impact.validation import check_integer
from fruitimpact.signals.filters import butterworth_sos, solve_small
from fruitimpact.signals.mains import HUM_WINDOW, MAD_TO_SIGMA, find_mains_hum
from fruitimpact.signals.settings import HUM_AUTO, MIN_DISCHARGE_TIME, DetectorSettings, at_rate, check_rate

__all__ = ["DetectedImpact", "Detector", "DetectorSettings", "butterworth_sos", "detect", "find_mains_hum"]

# ---------------------------------------------------------------------------------------------------------
# Settings


# ---------------------------------------------------------------------------------------------------------
# The detected impact


@dataclass(frozen=True, eq=False)
class DetectedImpact:
    """One impact found by the detector (indices are sample numbers since the stream's start).

    Attributes
    ----------
    lane : int
        Lane (column) of the signal.
    sequence : int
        Number of this impact in its lane (0, 1, …; discarded short contacts are not counted).
    start_index : int
        Onset: the first sample above the onset threshold.
    end_index : int
        The last sample above the offset threshold (the contact as detected is start..end inclusive).
    peak_index : int
        The largest window sample of the contact (raw; the indices refine it).
    peak_value : float
        That sample's value [N] (baseline-subtracted, filtered).
    baseline : float
        Baseline [N] at the onset sample.
    baseline_slope : float
        Its slope [N/s] at the onset: the window has baseline + slope · (index − start_index)/rate
        subtracted (the baseline extrapolated linearly across the impact).
    noise : float
        Noise σ [N] at the onset.
    previous_end : int or None
        ``end_index`` of the previous impact of the lane (None for its first).
    next_start : int or None
        ``start_index`` of the next impact of the lane when it began before this impact's window
        ended (its samples from there on are not this impact's), else None.
    clipped : bool
        A raw sample reached ``clip_low``/``clip_high`` between the onset and the confirmed end.
    truncated : bool
        Still in progress when the stream ended (``flush``): end_index is its last sample above the
        offset threshold so far.
    overlong : bool
        Ended by ``max_duration``.
    window_start : int
        Sample index of ``window[0]``.
    window : numpy.ndarray
        Samples [N] from window_start (read-only): filtered as configured, hum and baseline removed.
    emitted_at : int
        Samples consumed by the detector when the impact was emitted (its latency is
        emitted_at − 1 − end_index samples).
    discharge_time : float or None
        τ [s] of the sensor chain's discharge restored in the lane when the impact was emitted (given, or
        measured on the lane's contacts: step 1b); None when nothing was restored.
    """

    lane: int
    sequence: int
    start_index: int
    end_index: int
    peak_index: int
    peak_value: float
    baseline: float
    baseline_slope: float
    noise: float
    previous_end: int | None
    next_start: int | None
    clipped: bool
    truncated: bool
    overlong: bool
    window_start: int
    window: np.ndarray
    emitted_at: int
    discharge_time: float | None = None

    __hash__ = None

    def __eq__(self, other):
        if not isinstance(other, DetectedImpact):
            return NotImplemented
        for name in self.__dataclass_fields__:
            a, b = getattr(self, name), getattr(other, name)
            if name == "window":
                if a.shape != b.shape or not np.array_equal(a, b):
                    return False
            elif a != b or type(a) is not type(b):
                return False
        return True

    @property
    def window_end(self) -> int:
        """Sample index just after the window's last sample."""
        return self.window_start + self.window.shape[0]


#: The discharge restoration's leak, in units of the sensor's time constant τ (step 1b of the module docstring).
DISCHARGE_LEAK = 100.0
#: The leak [s] of the integral when the discharge is measured (τ not given): 100 times the τ of ~1 s beyond which
#: one contact's undershoot is within its noise, ten times the longest restored (``DISCHARGE_LONGEST``).
DISCHARGE_AUTO_LEAK = 100.0
#: The longest τ [s] restored when measured: a slower discharge droops a contact by < 1e-3 of its impulse (and
#: on a noise-free signal any residual would otherwise count as shown).
DISCHARGE_LONGEST = 10.0
#: Measurements of the discharge a lane keeps (its last lone contacts').
DISCHARGE_KEPT = 31
#: The measured discharge is restored when the median of those exceeds this many of its standard errors.
DISCHARGE_SHOWN = 5.0
#: The samples after a contact that measure its undershoot start this long after its end [s] (past the pulse's
#: tail below the offset threshold).
DISCHARGE_MARGIN = 0.5e-3
#: Fewest samples before the contact's foot and after that margin for a measurement.
DISCHARGE_MIN_SAMPLES = 3
#: Once restored, the gain stays while the median exceeds this many standard errors (hysteresis).
DISCHARGE_HELD = 2.0
#: From this many measurements on, the median's standard error is also read from their own scatter.
DISCHARGE_SCATTER_FROM = 5
#: 1/√(2/π): the standard error of a median over that of a mean, for normal scatter.
MEDIAN_SE = 1.2533141373155001

# ---------------------------------------------------------------------------------------------------------
# State layout (per lane).  Floats in F, integers in I; the FIFO of ended impacts waiting for emission
# follows the fixed fields (FIFO_F floats and FIFO_I integers per slot).

F_B, F_SIG, F_PC, F_PS, F_PEAK, F_CB, F_CSIG, F_THROFF, F_D, F_CD = range(10)
F_HUM = 10                      # a_k, d_k for up to 4 harmonics
# the discharge restoration (step 1b): its leaky integral [N·samples], the last raw sample, the gain g [1/samples],
# the offset that keeps the restored signal continuous where g changes [N], and the lane's last DISCHARGE_KEPT
# measurements of the gain (values, then their standard errors)
F_DIS, F_DPREV, F_DGAIN, F_DOFF = F_HUM + 8, F_HUM + 9, F_HUM + 10, F_HUM + 11
# the quiet residual's running variance and lag-1 covariance (clipped at 3 σ) and its last value: how correlated the
# noise is (a low-pass, the acquisition's anti-alias filter), for the discharge measurement's standard error
F_C0, F_C1, F_RPREV = F_HUM + 12, F_HUM + 13, F_HUM + 14
F_DRING = F_HUM + 15
F_DRSE = F_DRING + DISCHARGE_KEPT
F_FIFO = F_DRSE + DISCHARGE_KEPT
FIFO_F = 4                      # peak value, baseline, noise, baseline slope
P_PEAK, P_B, P_SIG, P_D = range(4)

I_COUNT, I_STATE, I_WARMN, I_START, I_PEAKI, I_LAST, I_BELOW, I_CLIP, I_SEQ, I_NPEND, I_HEAD, I_PREV, I_DN = range(13)
I_FIFO = 13
FIFO_I = 9
Q_START, Q_END, Q_PEAKI, Q_SEQ, Q_PREV, Q_CLIP, Q_TRUNC, Q_LONG, Q_EMIT = range(9)

S_WARM, S_QUIET, S_IN = 0, 1, 2

# Output records
O_LANE, O_SEQ, O_START, O_END, O_PEAKI, O_PREV, O_NEXT, O_CLIP, O_TRUNC, O_LONG, O_WSTART, O_WLEN, \
    O_WOFF, O_EMIT = range(14)
N_OI = 14
N_OF = 5  # peak value, baseline, noise, baseline slope per sample, discharge gain per sample

# Parameters
PF_AB, PF_AS, PF_KON, PF_KOFF, PF_FLOORON, PF_FLOOROFF, PF_G, PF_CW, PF_SW, PF_CLIPLO, PF_CLIPHI, PF_AD, \
    PF_DGAIN, PF_DLEAK, PF_DAUTO, PF_DCAP, PF_DFLOOR = range(17)
N_PF = 17
PI_HOLD, PI_MINLEN, PI_MAXLEN, PI_PRE, PI_POST, PI_WARMN, PI_L, PI_FIFO, PI_NSEC, PI_NH, PI_MAXWIN, \
    PI_DMARGIN = range(12)
N_PI = 12

#: E[min(|Z|, 3)] for a standard normal Z: the clipped mean absolute deviation of unit noise.
CLIPPED_MAD = math.sqrt(2 / math.pi) * (1 - math.exp(-4.5)) + 3 * math.erfc(3 / math.sqrt(2))

_JIT = {"cache": CACHE, "error_model": "numpy"}


@nb.njit(**_JIT)
def _harmonic_terms(pc, ps, harm, hc, hs):
    """cos and sin of k ω n for each harmonic k from the fundamental's phasor (pc, ps)."""
    pr = 1.0
    pi_ = 0.0
    done = 0
    for j in range(harm.shape[0]):
        while done < harm[j]:
            pr, pi_ = pr * pc - pi_ * ps, pr * ps + pi_ * pc
            done += 1
        hc[j] = pr
        hs[j] = pi_


@nb.njit(**_JIT)
def _warm_fit(lane, gi, F, I, R, WY, WC, WS, harm, nh, L):
    """End of a warm-up: baseline level and slope and σ (MAD) from the warm-up samples.  Without hum
    removal the level and slope come from the medians of the two halves (robust); with it, from a
    least-squares fit of level, slope and hum terms, and the ring entries of the warm-up samples are
    rewritten with the fitted hum removed; a contact in the warm-up (residuals beyond 6 robust sd) is left out,
    with a quarter of the warm-up on each side, and the fit done again (with less than half left: the robust
    level and slope, no hum until the canceller learns it).  The level is set for the next sample."""
    wn = I[lane, I_WARMN]
    y = WY[lane, :wn]
    hc = np.empty(4)
    hs = np.empty(4)
    resid = np.empty(wn)
    mid = 0.5 * (wn - 1)
    if nh == 0:
        half = wn // 2
        m1 = np.median(y[:half])
        m2 = np.median(y[wn - half:])
        d = (m2 - m1) / (wn - half)
        level = 0.5 * (m1 + m2)
        for i in range(wn):
            resid[i] = abs(y[i] - level - d * (i - mid))
    else:
        p = 2 + 2 * nh
        a = np.zeros((p, p))
        rhs = np.zeros(p)
        x = np.empty(p)
        use = np.ones(wn, dtype=np.bool_)
        robust = False
        # contacts screened first against the robust level and slope (medians of the halves) and their MAD: a
        # least-squares fit through them is no screen when they fill the warm-up (40 fruit/s: two contacts in
        # 50 ms pulled the fit's spread to 11 sd, above every contact, and the lane's σ with it: 8 of 200 found)
        half = wn // 2
        m1 = np.median(y[:half])
        m2 = np.median(y[wn - half:])
        d0 = (m2 - m1) / (wn - half)
        for i in range(wn):
            resid[i] = abs(y[i] - 0.5 * (m1 + m2) - d0 * (i - mid))
        screen = 6.0 * MAD_TO_SIGMA * np.median(resid)
        margin = wn // 4
        if screen > 0.0:
            for i in range(wn):
                if resid[i] > screen:
                    for k in range(max(i - margin, 0), min(i + margin + 1, wn)):
                        use[k] = False
            robust = np.count_nonzero(use) < wn // 2  # too little left for the hum: the robust level and slope
        for attempt in range(0 if robust else 2):  # a contact in the warm-up is no hum: left out, fit again
            a[:, :] = 0.0
            rhs[:] = 0.0
            for i in range(wn):
                if not use[i]:
                    continue
                _harmonic_terms(WC[lane, i], WS[lane, i], harm, hc, hs)
                x[0] = 1.0
                x[1] = i - mid
                for j in range(nh):
                    x[2 + 2 * j] = hc[j]
                    x[3 + 2 * j] = hs[j]
                for r in range(p):
                    rhs[r] += x[r] * y[i]
                    for c in range(p):
                        a[r, c] += x[r] * x[c]
            if not solve_small(a, rhs, p):
                rhs[:] = 0.0
                rhs[0] = np.median(y)
            if attempt == 1:
                break
            for i in range(wn):
                _harmonic_terms(WC[lane, i], WS[lane, i], harm, hc, hs)
                h = 0.0
                for j in range(nh):
                    h += rhs[2 + 2 * j] * hc[j] + rhs[3 + 2 * j] * hs[j]
                resid[i] = abs(y[i] - h - rhs[0] - rhs[1] * (i - mid))
            spread = MAD_TO_SIGMA * np.median(resid[use])
            limit = 6.0 * spread if spread > 0.0 else 1e-12 * (1.0 + np.max(np.abs(y)))
            outliers = 0
            for i in range(wn):
                if use[i] and resid[i] > limit:
                    outliers += 1
                    for k in range(max(i - margin, 0), min(i + margin + 1, wn)):
                        use[k] = False
            if outliers == 0:
                break
            if np.count_nonzero(use) < wn // 2:  # too little left for the hum: the robust level and slope alone
                robust = True
                break
        if robust:
            half = wn // 2
            m1 = np.median(y[:half])
            m2 = np.median(y[wn - half:])
            rhs[:] = 0.0
            rhs[1] = (m2 - m1) / (wn - half)
            rhs[0] = 0.5 * (m1 + m2)
        level = rhs[0]
        d = rhs[1]
        for j in range(nh):
            F[lane, F_HUM + 2 * j] = rhs[2 + 2 * j]
            F[lane, F_HUM + 2 * j + 1] = rhs[3 + 2 * j]
        first = gi - wn + 1
        kept = 0
        for i in range(wn):
            _harmonic_terms(WC[lane, i], WS[lane, i], harm, hc, hs)
            h = 0.0
            for j in range(nh):
                h += rhs[2 + 2 * j] * hc[j] + rhs[3 + 2 * j] * hs[j]
            z = y[i] - h
            if robust or use[i]:  # σ from the samples the fit used: a contact left out is no noise
                resid[kept] = abs(z - level - d * (i - mid))
                kept += 1
            if gi - (first + i) < L:
                R[lane, (first + i) % L] = z
        resid = resid[:kept]
    F[lane, F_B] = level + d * (wn - mid)
    F[lane, F_D] = d
    F[lane, F_SIG] = MAD_TO_SIGMA * np.median(resid)
    I[lane, I_STATE] = S_QUIET


@nb.njit(**_JIT)
def _finish(lane, end, truncated, overlong, F, I, IP):
    """End the impact in progress at ``end``: discard it (too short) or queue it for emission."""
    start = I[lane, I_START]
    if not truncated and not overlong and end - start + 1 < IP[PI_MINLEN]:
        return
    fifo = IP[PI_FIFO]
    npend = I[lane, I_NPEND]
    if npend >= fifo:
        raise RuntimeError("detector FIFO overflow (internal error)")
    seq = I[lane, I_SEQ]
    I[lane, I_SEQ] = seq + 1
    slot = (I[lane, I_HEAD] + npend) % fifo
    q = I_FIFO + slot * FIFO_I
    I[lane, q + Q_START] = start
    I[lane, q + Q_END] = end
    I[lane, q + Q_PEAKI] = I[lane, I_PEAKI]
    I[lane, q + Q_SEQ] = seq
    I[lane, q + Q_PREV] = I[lane, I_PREV] - 1  # stored + 1 (0: none yet)
    I[lane, I_PREV] = end + 1
    I[lane, q + Q_CLIP] = I[lane, I_CLIP]
    I[lane, q + Q_TRUNC] = 1 if truncated else 0
    I[lane, q + Q_LONG] = 1 if overlong else 0
    I[lane, q + Q_EMIT] = end + IP[PI_POST]
    f = F_FIFO + slot * FIFO_F
    F[lane, f + P_PEAK] = F[lane, F_PEAK]
    F[lane, f + P_B] = F[lane, F_CB]
    F[lane, f + P_SIG] = F[lane, F_CSIG]
    F[lane, f + P_D] = F[lane, F_CD]
    I[lane, I_NPEND] = npend + 1


@nb.njit(**_JIT)
def _measure_discharge(lane, F, I, PF, IP, OW, off, ws, we, start, end, peak, sigma):
    """Step 1b's measurement on one lone contact's window OW[off:off + we − ws + 1] (module docstring): the gain
    still missing, from the undershoot after the contact against the window's running integral; the lane's gain
    becomes the median of its last ``DISCHARGE_KEPT`` measurements where shown, and the restored signal is kept
    continuous where the gain changes.  True when the gain changed (and the window with it)."""
    foot = int(math.ceil(0.3 * max(peak - start, 0))) + 2
    n_pre = start - foot - ws
    first = end + 1 + IP[PI_DMARGIN]
    n_post = we - first + 1
    if n_pre < DISCHARGE_MIN_SAMPLES or n_post < DISCHARGE_MIN_SAMPLES or not sigma > 0.0:
        return False
    pre = 0.0
    for idx in range(n_pre):
        pre += OW[off + idx]
    pre /= n_pre
    # the running trapezoidal integral of the window less its level before the contact, and the mean of the
    # window and of that integral after the contact
    integral = np.zeros(we - ws + 1)
    integral_post = 0.0
    level_post = 0.0
    for idx in range(1, we - ws + 1):
        value = OW[off + idx] - pre
        integral[idx] = integral[idx - 1] + 0.5 * (value + OW[off + idx - 1] - pre)
        if ws + idx >= first:
            integral_post += integral[idx]
            level_post += value
    integral_post /= n_post
    level_post /= n_post
    if not integral_post > 0.0:
        return False
    missing = -level_post / integral_post
    # the variance of a mean of n correlated samples: σ² (1 + ρ)/((1 − ρ) n) for noise of lag-1 correlation ρ (an
    # AR(1) approximation of a low-passed noise), at most σ² (the samples no more than one)
    rho = F[lane, F_C1] / F[lane, F_C0] if F[lane, F_C0] > 0.0 else 0.0
    rho = min(max(rho, 0.0), 0.999)
    factor = (1.0 + rho) / (1.0 - rho)
    error = sigma * math.sqrt(min(1.0, factor / n_post) + min(1.0, factor / n_pre)) / integral_post
    total = F[lane, F_DGAIN] + missing
    if total > PF[PF_DCAP]:  # a discharge faster than MIN_DISCHARGE_TIME is no sensor's: a misread contact
        return False
    count = I[lane, I_DN]
    slot = count % DISCHARGE_KEPT
    F[lane, F_DRING + slot] = total
    F[lane, F_DRSE + slot] = error
    count += 1
    I[lane, I_DN] = count
    n = min(count, DISCHARGE_KEPT)
    values = F[lane, F_DRING:F_DRING + n]
    median = np.median(values)
    spread = MEDIAN_SE * np.median(F[lane, F_DRSE:F_DRSE + n]) / math.sqrt(n)
    if n >= DISCHARGE_SCATTER_FROM:  # and never less than the measurements' own scatter says
        scatter = MAD_TO_SIGMA * np.median(np.abs(values - median))
        spread = max(spread, MEDIAN_SE * scatter / math.sqrt(n))
    # hysteresis: a gain restored stays while its median is above DISCHARGE_HELD errors (no flicker at the edge)
    shown = DISCHARGE_SHOWN if F[lane, F_DGAIN] == 0.0 else DISCHARGE_HELD
    gain = median if median > shown * spread and median > PF[PF_DFLOOR] else 0.0
    change = gain - F[lane, F_DGAIN]
    F[lane, F_DOFF] -= change * F[lane, F_DIS]
    F[lane, F_DGAIN] = gain
    if change != 0.0:
        # this window was taken with the old gain: restore the change in it too (its pre-contact level is that
        # of a lone contact, so the window's own inverse holds), and the lane's first contact is restored as well
        for idx in range(1, we - ws + 1):
            OW[off + idx] += change * integral[idx]
    return change != 0.0


@nb.njit(**_JIT)
def _emit_head(lane, gi, F, I, R, PF, IP, OF, OI, OW, cnt):
    """Emit the oldest queued impact of the lane after sample ``gi`` (window cut at gi), with the onset of
    the next impact of the lane when it began inside the window."""
    fifo = IP[PI_FIFO]
    L = IP[PI_L]
    slot = I[lane, I_HEAD]
    q = I_FIFO + slot * FIFO_I
    f = F_FIFO + slot * FIFO_F
    start = I[lane, q + Q_START]
    end = I[lane, q + Q_END]
    ws = start - IP[PI_PRE]
    oldest = gi - L + 1
    ws = max(ws, oldest)
    ws = max(ws, 0)
    we = end + IP[PI_POST]
    we = min(we, gi)
    nxt = -1
    if I[lane, I_NPEND] > 1:
        nxt = I[lane, I_FIFO + ((slot + 1) % fifo) * FIFO_I + Q_START]
    elif I[lane, I_STATE] == S_IN and I[lane, I_START] > end:
        nxt = I[lane, I_START]
    if nxt > we:
        nxt = -1
    b = F[lane, f + P_B]
    d = F[lane, f + P_D]
    k = cnt[0]
    off = cnt[1]
    for idx in range(ws, we + 1):
        OW[off + idx - ws] = R[lane, idx % L] - (b + d * (idx - start))
    if PF[PF_DAUTO] > 0.0 and nxt < 0 and I[lane, q + Q_CLIP] == 0 and I[lane, q + Q_TRUNC] == 0 \
            and I[lane, q + Q_LONG] == 0 and I[lane, q + Q_PREV] + IP[PI_POST] < ws \
            and _measure_discharge(lane, F, I, PF, IP, OW, off, ws, we, start, end, I[lane, q + Q_PEAKI],
                                   F[lane, f + P_SIG]):
        # the window was restored with the new gain: its peak taken again
        top = start
        for idx in range(start, end + 1):
            if OW[off + idx - ws] > OW[off + top - ws]:
                top = idx
        I[lane, q + Q_PEAKI] = top
        F[lane, f + P_PEAK] = OW[off + top - ws]
    OF[k, 0] = F[lane, f + P_PEAK]
    OF[k, 1] = b
    OF[k, 2] = F[lane, f + P_SIG]
    OF[k, 3] = d
    OF[k, 4] = F[lane, F_DGAIN]  # the gain this window was restored with
    OI[k, O_LANE] = lane
    OI[k, O_SEQ] = I[lane, q + Q_SEQ]
    OI[k, O_START] = start
    OI[k, O_END] = end
    OI[k, O_PEAKI] = I[lane, q + Q_PEAKI]
    OI[k, O_PREV] = I[lane, q + Q_PREV]
    OI[k, O_NEXT] = nxt
    OI[k, O_CLIP] = I[lane, q + Q_CLIP]
    OI[k, O_TRUNC] = I[lane, q + Q_TRUNC]
    OI[k, O_LONG] = I[lane, q + Q_LONG]
    OI[k, O_WSTART] = ws
    OI[k, O_WLEN] = we - ws + 1
    OI[k, O_WOFF] = off
    OI[k, O_EMIT] = gi + 1
    cnt[0] = k + 1
    cnt[1] = off + we - ws + 1
    I[lane, I_HEAD] = (slot + 1) % fifo
    I[lane, I_NPEND] -= 1


@nb.njit(**_JIT)
def _run(x, pos, F, I, Z, R, WY, WC, WS, PF, IP, harm, sos, OF, OI, OW, cnt):
    """Process x[pos[lane]:, lane] for every lane, stopping early (pos tells where) when the output
    buffers might overflow; all state is read from and written back to the arrays."""
    n, lanes = x.shape
    ab = PF[PF_AB]
    ad = PF[PF_AD]
    a_s = PF[PF_AS]
    k_on = PF[PF_KON]
    k_off = PF[PF_KOFF]
    floor_on = PF[PF_FLOORON]
    floor_off = PF[PF_FLOOROFF]
    g = PF[PF_G]
    cw = PF[PF_CW]
    sw = PF[PF_SW]
    clip_lo = PF[PF_CLIPLO]
    clip_hi = PF[PF_CLIPHI]
    dleak = PF[PF_DLEAK]
    hold = IP[PI_HOLD]
    maxlen = IP[PI_MAXLEN]
    warm_n = IP[PI_WARMN]
    L = IP[PI_L]
    fifo = IP[PI_FIFO]
    nsec = IP[PI_NSEC]
    nh = IP[PI_NH]
    maxwin = IP[PI_MAXWIN]
    rec_cap = OF.shape[0] - fifo
    win_cap = OW.shape[0] - fifo * maxwin
    kc = 1.0 / CLIPPED_MAD
    hc = np.zeros(4)
    hs = np.zeros(4)
    for lane in range(lanes):
        k = pos[lane]
        if k >= n:
            continue
        gi = I[lane, I_COUNT]
        state = I[lane, I_STATE]
        b = F[lane, F_B]
        d = F[lane, F_D]
        sig = F[lane, F_SIG]
        pc = F[lane, F_PC]
        ps = F[lane, F_PS]
        while k < n:
            if cnt[0] > rec_cap or cnt[1] > win_cap:
                break
            xv = x[k, lane]
            y = xv
            # 1b. discharge restoration (module docstring): x = y + (1/τ) ∫ y dt, the trapezoidal integral leaking
            # with τ_leak, started in its steady state for the first sample
            if dleak > 0.0:
                if gi == 0:
                    F[lane, F_DIS] = xv / (1.0 - dleak)
                else:
                    F[lane, F_DIS] = dleak * F[lane, F_DIS] + 0.5 * (xv + F[lane, F_DPREV])
                F[lane, F_DPREV] = xv
                y = xv + F[lane, F_DGAIN] * F[lane, F_DIS] + F[lane, F_DOFF]
            # 2. low-pass (DF-II transposed biquads), steady state at the first sample
            y0 = y
            if nsec > 0:
                if gi == 0:
                    for s in range(nsec):
                        Z[lane, s, 1] = (sos[s, 2] - sos[s, 5]) * y0
                        Z[lane, s, 0] = (sos[s, 1] - sos[s, 4]) * y0 + Z[lane, s, 1]
                for s in range(nsec):
                    v = sos[s, 0] * y + Z[lane, s, 0]
                    Z[lane, s, 0] = sos[s, 1] * y - sos[s, 4] * v + Z[lane, s, 1]
                    Z[lane, s, 1] = sos[s, 2] * y - sos[s, 5] * v
                    y = v
            # 3. hum prediction for this sample
            h = 0.0
            if nh > 0:
                _harmonic_terms(pc, ps, harm, hc, hs)
                for j in range(nh):
                    h += F[lane, F_HUM + 2 * j] * hc[j] + F[lane, F_HUM + 2 * j + 1] * hs[j]
            z = y - h
            R[lane, gi % L] = z
            if state == S_QUIET:
                r = z - b
                thr = k_on * sig
                thr = max(thr, floor_on)
                if r > thr:
                    state = S_IN
                    I[lane, I_START] = gi
                    I[lane, I_PEAKI] = gi
                    I[lane, I_LAST] = gi
                    I[lane, I_BELOW] = 0
                    I[lane, I_CLIP] = 1 if (xv <= clip_lo or xv >= clip_hi) else 0
                    F[lane, F_PEAK] = r
                    F[lane, F_CB] = b
                    F[lane, F_CD] = d
                    F[lane, F_CSIG] = sig
                    thr = k_off * sig
                    thr = max(thr, floor_off)
                    F[lane, F_THROFF] = thr
                else:
                    b += d + ab * r
                    d += ad * r
                    for j in range(nh):
                        F[lane, F_HUM + 2 * j] += g * r * hc[j]
                        F[lane, F_HUM + 2 * j + 1] += g * r * hs[j]
                    a = abs(r)
                    if sig > 0.0 and a > 3.0 * sig:
                        a = 3.0 * sig
                    sig += a_s * (kc * a - sig)
                    clipped = min(max(r, -3.0 * sig), 3.0 * sig)
                    F[lane, F_C0] += a_s * (clipped * clipped - F[lane, F_C0])
                    F[lane, F_C1] += a_s * (clipped * F[lane, F_RPREV] - F[lane, F_C1])
                    F[lane, F_RPREV] = clipped
            elif state == S_IN:
                r = z - (F[lane, F_CB] + F[lane, F_CD] * (gi - I[lane, I_START]))
                if xv <= clip_lo or xv >= clip_hi:
                    I[lane, I_CLIP] = 1
                if r > F[lane, F_PEAK]:
                    F[lane, F_PEAK] = r
                    I[lane, I_PEAKI] = gi
                if r >= F[lane, F_THROFF]:
                    I[lane, I_LAST] = gi
                    I[lane, I_BELOW] = 0
                else:
                    I[lane, I_BELOW] += 1
                if I[lane, I_BELOW] >= hold:
                    _finish(lane, I[lane, I_LAST], False, False, F, I, IP)
                    state = S_QUIET
                    # the baseline resumes from its extrapolation across the contact
                    b = F[lane, F_CB] + F[lane, F_CD] * (gi + 1 - I[lane, I_START])
                    d = F[lane, F_CD]
                elif gi - I[lane, I_START] + 1 >= maxlen:
                    _finish(lane, gi, False, True, F, I, IP)
                    if PF[PF_DAUTO] > 0.0 and F[lane, F_DGAIN] != 0.0:
                        # a contact that never ended under a measured restoration: the measurement was wrong
                        # (restoring too much keeps the force above the baseline); it is dropped and measured anew
                        F[lane, F_DOFF] += F[lane, F_DGAIN] * F[lane, F_DIS]
                        F[lane, F_DGAIN] = 0.0
                        I[lane, I_DN] = 0
                    state = S_WARM
                    I[lane, I_WARMN] = 0
            else:  # warm-up
                wn = I[lane, I_WARMN]
                WY[lane, wn] = y
                WC[lane, wn] = pc
                WS[lane, wn] = ps
                I[lane, I_WARMN] = wn + 1
                if wn + 1 == warm_n:
                    _warm_fit(lane, gi, F, I, R, WY, WC, WS, harm, nh, L)
                    b = F[lane, F_B]
                    d = F[lane, F_D]
                    sig = F[lane, F_SIG]
                    state = S_QUIET
            # advance the hum phasor (renormalised to unit length every sample)
            if nh > 0:
                pc, ps = pc * cw - ps * sw, ps * cw + pc * sw
                norm = 1.5 - 0.5 * (pc * pc + ps * ps)
                pc *= norm
                ps *= norm
            # emission of the queued impacts that are final
            I[lane, I_STATE] = state  # read by _emit_head (an impact in progress is the next one)
            while I[lane, I_NPEND] > 0 and gi >= I[lane, I_FIFO + I[lane, I_HEAD] * FIFO_I + Q_EMIT]:
                _emit_head(lane, gi, F, I, R, PF, IP, OF, OI, OW, cnt)
            gi += 1
            k += 1
        I[lane, I_COUNT] = gi
        I[lane, I_STATE] = state
        F[lane, F_B] = b
        F[lane, F_D] = d
        F[lane, F_SIG] = sig
        F[lane, F_PC] = pc
        F[lane, F_PS] = ps
        pos[lane] = k


@nb.njit(**_JIT)
def _flush(F, I, R, PF, IP, OF, OI, OW, cnt):
    """End of stream: end the impact in progress (truncated) and emit everything queued."""
    lanes = F.shape[0]
    for lane in range(lanes):
        gi = I[lane, I_COUNT] - 1
        if I[lane, I_STATE] == S_IN:
            _finish(lane, I[lane, I_LAST], True, False, F, I, IP)
            I[lane, I_STATE] = S_QUIET
        while I[lane, I_NPEND] > 0:
            _emit_head(lane, gi, F, I, R, PF, IP, OF, OI, OW, cnt)


# ---------------------------------------------------------------------------------------------------------
# The Python front end


class Detector:
    """Causal impact detector over ``lanes`` force lanes sampled at ``rate`` [Hz] (module docstring).

    ``feed(samples)`` takes the next samples — shape (n,) for one lane or (n, lanes) — and returns the
    impacts that became final; ``flush()`` ends the stream and returns the rest.  Any split of a stream
    into ``feed`` calls gives identical impacts.
    """

    def __init__(self, rate: float, settings: DetectorSettings | None = None, lanes: int = 1):
        rate = check_rate(rate)
        if rate is None:
            raise ValueError("rate must be a finite number of Hz > 0; got None")
        check_integer("lanes", lanes, 1, 1024)
        if settings is None:
            settings = DetectorSettings()
        if not isinstance(settings, DetectorSettings):
            raise ValueError(  # noqa: TRY004 (the project's rule: ValueError, one line)
                f"settings must be a DetectorSettings or None; got {type(settings).__name__}")
        rate = float(rate)
        s = settings
        self.rate, self.settings, self.lanes = rate, s, int(lanes)
        windows = at_rate(s, rate)  # every check against the rate (settings.at_rate)
        hold, min_len, max_len = windows["offset_hold"], windows["min_duration"], windows["max_duration"]
        pre, post, warm_n, gain = windows["pre_trigger"], windows["post_trigger"], windows["warmup"], windows["hum_gain"]
        sos = (butterworth_sos(s.lowpass_cutoff, s.lowpass_order, rate) if s.lowpass_cutoff is not None
               else np.zeros((0, 6)))
        fifo = post // (min_len + hold) + 4
        ring = pre + max_len + post + hold + 2
        self._maxwin = pre + max_len + post + 1
        decay = math.exp(-1 / (s.baseline_time_constant * rate))
        # step 1b: a given τ fixes the gain; none given (None): the gain measured on the lane's contacts, the
        # integral leaking with DISCHARGE_AUTO_LEAK; math.inf: a sensor that holds a static force, nothing restored
        tau = s.discharge_time
        leak_time = DISCHARGE_AUTO_LEAK if tau is None else DISCHARGE_LEAK * tau if math.isfinite(tau) else None
        self._discharge_gain = 1.0 / (tau * rate) if tau is not None and math.isfinite(tau) else 0.0
        self._pf = np.array([1 - decay * decay,
                             1 - math.exp(-1 / (s.noise_time_constant * rate)),
                             s.k_on, s.k_off, s.threshold_floor, s.threshold_floor * s.k_off / s.k_on,
                             0.0, 1.0, 0.0,  # the hum's gain and phasor step: _set_hum
                             -math.inf if s.clip_low is None else s.clip_low,
                             math.inf if s.clip_high is None else s.clip_high, (1 - decay) ** 2,
                             self._discharge_gain, 0.0 if leak_time is None else math.exp(-1.0 / (leak_time * rate)),
                             1.0 if tau is None else 0.0, 1.0 / (MIN_DISCHARGE_TIME * rate),
                             1.0 / (DISCHARGE_LONGEST * rate)])
        self._pi = np.array([hold, min_len, max_len, pre, post, warm_n, ring, fifo, sos.shape[0],
                             0, self._maxwin, math.ceil(DISCHARGE_MARGIN * rate)], dtype=np.int64)
        self._sos = np.ascontiguousarray(sos)
        self._hum_auto = s.hum_frequency == HUM_AUTO
        self._hum_window = max(warm_n, math.ceil(HUM_WINDOW * rate))
        self.hum_found: tuple | None = None
        self._set_hum(None if self._hum_auto else s.hum_frequency, gain)
        self._fifo, self._ring_len, self._warm_n = fifo, ring, warm_n
        #: Samples between an impact's end_index and its emission (max(post-trigger, offset hold)).
        self.latency_samples = max(post, hold)
        self.reset()

    def _set_hum(self, frequency: float | None, gain: float | None = None) -> None:
        """Remove the hum at ``frequency`` [Hz] with the settings' harmonics (those below rate/2), or none."""
        s = self.settings
        harmonics = () if frequency is None else tuple(k for k in s.hum_harmonics if k * frequency < self.rate / 2)
        if gain is None and frequency is not None:
            gain = 2 * math.pi * frequency / (s.hum_q * self.rate)
        if not harmonics or not gain < 0.5:  # auto at a rate too low for a notch there: none
            frequency, harmonics, gain = None, (), 0.0
        omega = 2 * math.pi * (frequency or 0.0) / self.rate
        self._harm = np.array(harmonics, dtype=np.int64)
        self._pf[PF_G], self._pf[PF_CW], self._pf[PF_SW] = gain, math.cos(omega), math.sin(omega)
        self._pi[PI_NH] = len(harmonics)
        #: The mains frequency [Hz] whose hum is removed (given, or found: ``find_mains_hum``), None when none.
        self.hum_frequency = frequency

    def reset(self) -> None:
        """Forget everything: the next sample fed is sample 0 of a new stream."""
        lanes, fifo = self.lanes, self._fifo
        if self._hum_auto:  # the hum is found again on the new stream's first samples
            self._set_hum(None)
            self._held: list[np.ndarray] | None = []
            #: (frequency [Hz] or None, largest fundamental amplitude [N], its standard error [N]) found
            self.hum_found = None
        self._F = np.zeros((lanes, F_FIFO + fifo * FIFO_F))
        self._F[:, F_PC] = 1.0
        self._F[:, F_DGAIN] = self._pf[PF_DGAIN]
        self._I = np.zeros((lanes, I_FIFO + fifo * FIFO_I), dtype=np.int64)
        self._Z = np.zeros((lanes, max(self._sos.shape[0], 1), 2))
        self._R = np.zeros((lanes, self._ring_len))
        self._WY = np.zeros((lanes, self._warm_n))
        self._WC = np.zeros((lanes, self._warm_n))
        self._WS = np.zeros((lanes, self._warm_n))
        self._out_f = np.zeros((4 * lanes * fifo, N_OF))
        self._out_i = np.zeros((4 * lanes * fifo, N_OI), dtype=np.int64)
        self._out_w = np.zeros(4 * lanes * fifo * self._maxwin)
        self._cnt = np.zeros(2, dtype=np.int64)
        self._flushed = False

    def discharge_time(self, lane: int) -> float | None:
        """τ [s] of the sensor discharge the lane restores now (step 1b: given, or measured on its contacts),
        None when it restores none."""
        return self._tau(float(self._F[lane, F_DGAIN]))

    def _tau(self, gain: float) -> float | None:
        """τ [s] of a restoration gain [1/samples]: the given one as given, a measured one, or None."""
        if gain <= 0.0:
            return None
        given = self.settings.discharge_time
        return given if given is not None and math.isfinite(given) else 1.0 / (gain * self.rate)

    @property
    def samples_fed(self) -> int:
        """Samples per lane consumed since the stream's start (those held to find the hum included)."""
        return int(self._I[0, I_COUNT]) + self._held_count()

    def _held_count(self) -> int:
        return sum(x.shape[0] for x in self._held) if self._hum_auto and self._held is not None else 0

    def _release(self, x: np.ndarray | None, final: bool = False) -> np.ndarray | None:
        """With the hum found automatically: hold the samples until the first ``HUM_WINDOW`` are in, then find
        the hum on them (``find_mains_hum``) and return everything held; at the stream's end (``final``) decide on what
        there is.  Without: ``x`` itself."""
        if not self._hum_auto or self._held is None:
            return x
        if x is not None and x.shape[0]:
            self._held.append(x.copy())  # the caller may reuse its buffer before the hum is found
        if self._held_count() < self._hum_window and not final:
            return None
        held = np.concatenate(self._held) if self._held else np.zeros((0, self.lanes))
        self._held = None
        self.hum_found = find_mains_hum(held[:self._hum_window], self.rate, self.settings.hum_harmonics)
        self._set_hum(self.hum_found[0])
        return held

    def _as_samples(self, samples) -> np.ndarray:
        x = np.asarray(samples)
        if x.dtype.kind not in "iuf":
            raise ValueError(f"samples must be a numeric array (integers or floats); got dtype {x.dtype}")
        if x.ndim == 1 and self.lanes == 1:
            x = x[:, None]
        if x.ndim != 2 or x.shape[1] != self.lanes:
            expected = "(n,) or (n, 1)" if self.lanes == 1 else f"(n, {self.lanes})"
            raise ValueError(f"samples must have shape {expected} for {self.lanes} lane(s); got {x.shape}")
        x = np.ascontiguousarray(x, dtype=np.float64)
        if not np.isfinite(x).all():
            raise ValueError("samples must be finite (no NaN or infinity); replace or drop them before feeding")
        return x

    def feed(self, samples) -> list[DetectedImpact]:
        """Process the next samples (shape (n,) with one lane, or (n, lanes)); return the impacts that
        became final, sorted by (emitted_at, lane)."""
        if self._flushed:
            raise RuntimeError("this Detector was flushed (its stream ended); call reset() to start a new stream")
        x = self._release(self._as_samples(samples))
        return self._process(x) if x is not None and x.shape[0] else []

    def _process(self, x: np.ndarray) -> list[DetectedImpact]:
        pos = np.zeros(self.lanes, dtype=np.int64)
        self._cnt[:] = 0
        while True:
            _run(x, pos, self._F, self._I, self._Z, self._R, self._WY, self._WC, self._WS, self._pf, self._pi,
                 self._harm, self._sos, self._out_f, self._out_i, self._out_w, self._cnt)
            if (pos >= x.shape[0]).all():
                break
            self._grow()
        return self._collect()

    def flush(self) -> list[DetectedImpact]:
        """End the stream: emit the impact in progress (``truncated``) and every impact still held."""
        if self._flushed:
            return []
        early = []
        held = self._release(None, final=True)
        if held is not None and held.shape[0]:
            early = self._process(held)
        self._cnt[:] = 0
        if self._out_f.shape[0] < self.lanes * self._fifo or \
                self._out_w.shape[0] < self.lanes * self._fifo * self._maxwin:
            self._grow()
        _flush(self._F, self._I, self._R, self._pf, self._pi, self._out_f, self._out_i, self._out_w, self._cnt)
        self._flushed = True
        return early + self._collect()

    def _grow(self) -> None:
        n_rec, n_win = self._cnt
        self._out_f = np.concatenate([self._out_f, np.zeros_like(self._out_f)])
        self._out_i = np.concatenate([self._out_i, np.zeros_like(self._out_i)])
        self._out_w = np.concatenate([self._out_w, np.zeros_like(self._out_w)])
        assert n_rec <= self._out_f.shape[0] and n_win <= self._out_w.shape[0]

    def _collect(self) -> list[DetectedImpact]:
        count = int(self._cnt[0])
        if count == 0:
            return []
        oi, of, ow = self._out_i[:count], self._out_f[:count], self._out_w
        order = np.lexsort((oi[:, O_LANE], oi[:, O_EMIT]))
        impacts = []
        for k in order:
            row = oi[k].tolist()
            window = ow[row[O_WOFF]:row[O_WOFF] + row[O_WLEN]].copy()
            window.setflags(write=False)
            impacts.append(DetectedImpact(
                lane=row[O_LANE], sequence=row[O_SEQ], start_index=row[O_START], end_index=row[O_END],
                peak_index=row[O_PEAKI], peak_value=float(of[k, 0]), baseline=float(of[k, 1]),
                baseline_slope=float(of[k, 3]) * self.rate, noise=float(of[k, 2]),
                previous_end=None if row[O_PREV] < 0 else row[O_PREV],
                next_start=None if row[O_NEXT] < 0 else row[O_NEXT],
                clipped=bool(row[O_CLIP]), truncated=bool(row[O_TRUNC]), overlong=bool(row[O_LONG]),
                window_start=row[O_WSTART], window=window, emitted_at=row[O_EMIT],
                discharge_time=self._tau(float(of[k, 4]))))
        self._cnt[:] = 0
        return impacts


def detect(force, rate: float, settings: DetectorSettings | None = None) -> list[DetectedImpact]:
    """Every impact in ``force`` [N] — shape (n,) or (n, lanes) — sampled at ``rate`` [Hz]: a ``Detector``
    fed the whole array, then flushed (so identical to any streaming of the same samples)."""
    x = np.asarray(force)
    lanes = x.shape[1] if x.ndim == 2 else 1
    detector = Detector(rate, settings, lanes)
    return detector.feed(x) + detector.flush()
