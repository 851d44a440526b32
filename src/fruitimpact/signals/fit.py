"""Fit the simulator's Hunt–Crossley pulse to one measured impact (issue 8, item 3).

The force of an impact with the law F = K δ^1.5 (1 + c δ̇) (``engine.powerlaw``) is

    F(t) = F_s · f((t − t0)/t_s; x),   F_s = K δ_H^1.5,  t_s = δ_H/V,  δ_H = (1.25 m V²/K)^0.4,

zero outside [t0, t0 + T], with one dimensionless shape f for each x = c·V (which alone fixes the
restitution e).  So one pulse determines exactly three of (K, c, m, V) plus the onset t0: given the
impact velocity V the fit recovers K, e and m; given the mass m it recovers V (and K, e).  The
impulse check ∫F dt = m (1 + e) V then holds by construction, and with the contact diameter d and
Poisson's ratio ν the modulus follows from Hertz on a rigid plate: E = (1 − ν²) · 3K / (4 √(d/2)).

Parametrisation
---------------
The least-squares fit (``signals.leastsquares``: Levenberg–Marquardt with Marquardt's diagonal scaling,
Nielsen's damping update and the analytic Jacobian of ``signals.pulse``) runs in

    θ = (t0, ln F_max, ln T, x),   F(t) = F_max · H((t − t0)/T; x),

where H(σ; x) is the pulse in units of its own peak and duration (σ ∈ [0, 1], max H = 1): the
force and time scales are the peak and the contact duration, so the amplitude column is nearly
orthogonal to the others (correlations ≤ 0.5; ln T and x stay correlated, ~0.97 at e = 0.5, since
the weak tail carries both), and x = c·V is kept in [0, X_MAX] by projection (e from 1 down to
e(X_MAX) ≈ 0.1).  The start comes from the raw indices: the (3-point smoothed) peak and the two
half-maximum crossings fix t0 and T for each x of a grid, and the x with the least squared residual
wins.  The iteration stops when every step is below ``leastsquares.STEP_TOLERANCE`` of its parameter's
standard error (with noise, Gauss–Newton converges only linearly near the optimum; the last digits are noise).
Optionally (``baseline=``) a constant or a linear residual baseline is fitted alongside.

H is tabulated once per process from the exact engine (``signals.pulse``: at most 1e-7 of F_max off).
Everything reported is derived from θ with the exact engine (``powerlaw_single``); the standard
errors are the covariance s² (JᵀJ)⁻¹ (s² the residual variance; or (Jᵀ W J)⁻¹ with a given noise)
pushed through the Jacobian of that map (central differences).  They assume white noise: structured
residuals (ringing, hum) make them optimistic.

Accuracy (tests/test_signals_fit.py; apple, T = 7.9 ms, 20 kHz, 1 % noise, 50 seeds): given V,
K ±1.2 % (stderr 1.1 %, the Cramér–Rao limit; 94 % of seeds within 2 %), e ±0.006, m ±0.5 %;
F_max ±0.17 %, t_c ±0.22 %, onset ±4 µs.  Given m, V ±0.5 % and K ±1.9 %.  K's precision falls with
e (stderr ~4.5 % at e = 0.35, ~10 % at e = 0.2): the long weak tail fixes the time scale poorly.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.engine.codes import CONTACT_DURATION, PEAK_FORCE, RESTITUTION, TIME_TO_PEAK
from fruitimpact.engine.powerlaw import exact_x, powerlaw_curves, powerlaw_single, restitution_of_x
from fruitimpact.signals.leastsquares import fit_pulse_sum, levenberg_marquardt
from fruitimpact.signals.pulse import STIFFNESS_SCALE, X_MAX, PulseModel, shape_table, table_shape

# The public names; derived and named_result also serve split.py.
__all__ = ["MIN_CONTACT_SAMPLES", "RESULT_KEYS", "at_velocity", "fit_impact", "model_curve", "prepare"]

#: Fewer (unmasked) samples than this inside the fitted contact: converged = False.
MIN_CONTACT_SAMPLES = 8
#: The share of a contact's fitted duration that may lie after a window cut by the next contact (``fit_impact``'s
#: ``open_end``).  A damped Hunt–Crossley pulse ends in a long low tail: below the detector's offset threshold (3
#: noise sd) lie its last 6 % (e = 0.7, 1 % noise) to 16 % (e = 0.45), 30–37 % (e = 0.35–0.40 at 2 % noise).  The
#: force law fixed by the sampled rise, peak and fall extrapolates it only where the samples still fix the damping
#: (``OPEN_END_EVIDENCE``); this bound only stops a fit that wandered off to a far longer pulse.
OPEN_END_MAX = 0.25
#: An extrapolated tail is kept only when the samples fix the damping: a fit with the restitution ``OPEN_END_DE``
#: lower (the tail longer) must be worse by at least ``OPEN_END_EVIDENCE`` in χ² (3 sd).  Where the cut took what
#: fixed it, the free fit drifts to a livelier, stiffer pulse (e 0.35–0.40 at 2 % noise: K +12 to +42 %, its stderr
#: covering a third of that) and the lower restitution fits within Δχ² 0.5–2; where the extrapolation is sound
#: (e ≥ 0.5 at 1 % noise, e 0.7 at 2 %) Δχ² is 22–190, and at e = 0.45 (1 % noise) 6.5–14: some of those are
#: refused (unfitted, never a wrong stiffness).  Measured on the exact engine's pulses (tests/test_signals_fit.py).
OPEN_END_DE, OPEN_END_EVIDENCE = 0.05, 9.0
#: A peak below this many noise standard deviations is no pulse.
MIN_PEAK_SNR = 5.0

_FIT_NAMES = ("stiffness", "restitution", "mass", "velocity", "damping_factor", "modulus", "start_time",
              "peak_force", "time_to_peak", "contact_duration", "firmness_c", "firmness_c_star", "impulse")
#: Every key of the dict ``fit_impact`` returns (NaN where a value could not be computed).
RESULT_KEYS = _FIT_NAMES + tuple(name + "_stderr" for name in _FIT_NAMES) + (
    "fit_residual", "fit_residual_relative", "noise", "samples_in_contact", "converged", "iterations", "message")

_BASELINE_TERMS = {None: 0, "none": 0, "offset": 1, "linear": 2}


# ---------------------------------------------------------------------------------------------------------
# Starting values from the raw indices

_START_X = np.array([0.0, 0.17, 0.35, 0.63, 1.0, 1.43, 2.0, 2.8, 4.0, 5.9, 9.0])  # e ≈ 1 … 0.11
_START: list = []


def _start_table() -> np.ndarray:
    """[x, σ of the rising half maximum, σ of the falling half maximum] for each starting x."""
    if not _START:
        sigma = np.linspace(0.0, 1.0, 8001)
        rows = []
        for x in _START_X:
            h = table_shape(x, sigma)
            top = int(np.argmax(h))
            rise = np.interp(0.5, h[:top + 1], sigma[:top + 1])
            fall = np.interp(0.5, h[top:][::-1], sigma[top:][::-1])
            rows.append((x, rise, fall))
        _START.append(np.array(rows))
    return _START[0]


def _half_crossings(t: np.ndarray, y: np.ndarray, top: int, level: float) -> tuple[float, float] | None:
    """Times where y crosses ``level`` going outward from index ``top``, linearly interpolated."""
    below = np.flatnonzero(y[:top] < level)
    after = np.flatnonzero(y[top + 1:] < level)
    if below.size == 0 or after.size == 0:
        return None
    i = below[-1]
    j = top + 1 + after[0]
    rise = t[i] + (level - y[i]) * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    fall = t[j - 1] + (y[j - 1] - level) * (t[j] - t[j - 1]) / (y[j - 1] - y[j])
    return rise, fall


def _smooth(y: np.ndarray) -> np.ndarray:
    """Three-point moving average (ends kept): only for the starting values."""
    out = y.copy()
    if y.size >= 3:
        out[1:-1] = (y[:-2] + y[1:-1] + y[2:]) / 3.0
    return out


def _noise_estimate(y: np.ndarray) -> float:
    """Robust white-noise sd from second differences (MAD · 1.4826 / √6); the pulse's own
    curvature at ≥ 10 samples per time-to-peak is far below a 1 % noise."""
    if y.size < 5:
        return 0.0
    d2 = y[:-2] - 2.0 * y[1:-1] + y[2:]
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def _start(t, y, model: PulseModel, weights) -> tuple[np.ndarray | None, str]:
    """Starting θ: the smoothed peak, the half-maximum crossings, and for each x of a grid the
    t0 and T that put the model's half-maximum points on the measured ones; the x with the least
    squared residual wins (the baseline terms, if any, fitted to the samples outside the pulse)."""
    smooth = _smooth(y)
    top = int(np.argmax(smooth))
    peak = float(smooth[top])
    crossings = _half_crossings(t, smooth, top, 0.5 * peak)
    if crossings is None:
        return None, "the pulse does not fall below half its peak on both sides inside the window"
    rise, fall = crossings
    if not fall > rise:
        return None, "no pulse width could be measured"
    best, best_value = None, math.inf
    for x, s_rise, s_fall in _start_table():
        duration = (fall - rise) / (s_fall - s_rise)
        t0 = rise - s_rise * duration
        theta = np.array([t0, math.log(peak), math.log(duration), x])
        rest = y - model.pulse(theta)
        if model.terms:
            outside = (t < t0) | (t > t0 + duration)
            rows = outside if np.count_nonzero(outside) >= model.terms + 2 else np.ones(t.shape, dtype=bool)
            coefficients = np.linalg.lstsq(model.basis[rows], rest[rows], rcond=None)[0]
            rest = rest - model.basis @ coefficients
            theta = np.concatenate([theta, coefficients])
        if weights is not None:
            rest = rest * weights
        value = float(rest @ rest)
        if value < best_value:
            best, best_value = theta, value
    return best, ""


# ---------------------------------------------------------------------------------------------------------
# From θ to the reported quantities

def _dimensionless(x: float) -> np.ndarray:
    """The exact engine's characteristics of the unit impact at x = c V (``derived``)."""
    return powerlaw_single(1.0, STIFFNESS_SCALE, 1.5, max(x, 0.0), 1.0, 1.0)


def derived(theta, velocity, mass, diameter, poisson, dimless=None) -> np.ndarray:
    """The quantities of ``_FIT_NAMES`` (in that order) from θ, through the exact engine (``dimless``: its
    characteristics at θ's x when already computed, ``_dimensionless``)."""
    t0, log_peak, log_duration, x = theta
    peak, duration = math.exp(log_peak), math.exp(log_duration)
    if dimless is None:
        dimless = _dimensionless(x)
    t_scale = duration / dimless[CONTACT_DURATION]  # t_H
    f_scale = peak * STIFFNESS_SCALE / dimless[PEAK_FORCE]  # K δ_H^1.5
    e = dimless[RESTITUTION]
    if velocity is not None:
        v = velocity
        m = f_scale * t_scale / (STIFFNESS_SCALE * v)  # K δ_H^2.5 = 1.25 m V², δ_H = V t_H
    else:
        m = mass
        v = f_scale * t_scale / (STIFFNESS_SCALE * m)
    delta_h = v * t_scale
    k = f_scale / delta_h ** 1.5
    modulus = (1.0 - poisson ** 2) * 3.0 * k / (4.0 * math.sqrt(diameter / 2.0)) \
        if diameter is not None else math.nan
    time_to_peak = dimless[TIME_TO_PEAK] * t_scale
    return np.array([k, e, m, v, x / v, modulus, t0, peak, time_to_peak, duration, peak / time_to_peak,
                     peak / time_to_peak ** 2, m * v * (1.0 + e)])


def _derived_stderr(theta, covariance, args, dimless) -> np.ndarray:
    """Standard errors of ``derived`` by the delta method (central differences in θ; ``dimless``: the engine's
    characteristics at θ's x, the same for the steps in t0, peak and duration)."""
    sd = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    floor = np.array([1e-9 * math.exp(theta[2]), 1e-9, 1e-9, 1e-9])
    steps = np.maximum(1e-4 * sd, floor)
    columns = []
    for i in range(4):
        up, down = theta.copy(), theta.copy()
        up[i] += steps[i]
        down[i] -= steps[i]
        if i == 3 and down[3] < 0.0:  # one-sided at the bound x = 0
            down[3] = theta[3]
        if i == 3 and up[3] > X_MAX:
            up[3] = theta[3]
        at = dimless if i < 3 else None
        columns.append((derived(up, *args, at) - derived(down, *args, at)) / (up[i] - down[i]))
    g = np.column_stack(columns)
    variance = np.einsum("qi,ij,qj->q", g, covariance, g)
    return np.sqrt(np.maximum(variance, 0.0))


def named_result(theta, covariance, args, t_ref: float) -> dict:
    """The fitted quantities and their standard errors by name, from one pulse's θ (4 values, its start
    relative to ``t_ref`` [s]) and its 4×4 covariance; ``args`` = (velocity, mass, diameter, poisson) as
    given to the fit (a given velocity or mass has standard error 0; no diameter, no modulus error)."""
    velocity, mass, diameter, _ = args
    dimless = _dimensionless(theta[3])
    values = derived(theta, *args, dimless)
    errors = _derived_stderr(theta, covariance, args, dimless) if np.all(np.isfinite(covariance)) \
        else np.full(values.shape, np.nan)
    result = {}
    for name, value, error in zip(_FIT_NAMES, values, errors):
        result[name] = float(value)
        result[name + "_stderr"] = float(error)
    result["start_time"] += t_ref
    for given, name in ((velocity, "velocity"), (mass, "mass")):
        if given is not None:
            result[name + "_stderr"] = 0.0
    if diameter is None:
        result["modulus_stderr"] = math.nan
    return result


def _empty_result(message: str) -> dict:
    result = {name: math.nan for name in RESULT_KEYS}
    result.update(samples_in_contact=0, converged=False, iterations=0, message=message)
    return result


# ---------------------------------------------------------------------------------------------------------
# Public API

def _positive(name, value):
    """Argument ``name`` [SI] (a number, or a string with a unit: ``impact.validation.read_value``) > 0."""
    from fruitimpact.impact.validation import read_value

    if value is None:
        return None
    value = read_value(name, value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def fit_impact(time, force, *, velocity=None, mass=None, diameter=None, poisson=None, noise=None,
               mask=None, baseline=None, open_end=False) -> dict:
    """Fit the Hunt–Crossley pulse F(t − t0; K, c, m, V) of the simulator to one impact.

    Parameters
    ----------
    time : array_like, 1-D
        Sample times [s], strictly increasing, covering the pulse with some samples before the
        onset and after the end (a window; the onset is fitted, not given).
    force : array_like, 1-D
        Force [N] at ``time``, baseline removed.
    velocity : float, optional
        Impact velocity V [m/s] (e.g. from the line's drop height): the fit then gives the mass.
    mass : float, optional
        Fruit mass m [kg]: the fit then gives the velocity.  Exactly one of ``velocity`` and
        ``mass`` must be given (one pulse determines only three of K, c, m, V).
    diameter, poisson : float, optional
        Contact diameter d [m] and Poisson's ratio ν, both or neither: add the modulus
        E = (1 − ν²) · 3K / (4 √(d/2)) [Pa] (Hertz, rigid plate).
    noise : float or array_like, optional
        Standard deviation [N] of the force noise (a scalar, or one per sample: weighted fit).
        Given, the standard errors come from it; otherwise from the residual variance.
    mask : array_like of bool, optional
        True for the samples to use (e.g. False on clipped samples).
    baseline : None, "offset" or "linear"
        Fit a residual baseline together with the pulse: a constant, or a constant and a slope
        over the window, against a zero left over by the baseline removal (a 1 % offset biases K
        by tens of per cent through the weak tail; fitted, ~10 % more stderr).  It does not remove
        50 Hz hum, whose curvature over a contact is not linear.  None (the default) trusts the
        removed baseline.
    open_end : bool
        The window was cut short by a following contact (a fruit landing just after this one ended):
        the contact's end may then lie after the last sample, by at most ``OPEN_END_MAX`` of its
        duration, and is extrapolated by the force law, but only where the samples still fix the
        damping (a restitution ``OPEN_END_DE`` lower must fit worse by ``OPEN_END_EVIDENCE`` in χ²;
        otherwise ``converged = False``, "damping undetermined"); how much was extrapolated is noted in
        ``message``.  Not with ``baseline``.  False (the default): the end must be sampled.

    Returns
    -------
    dict
        With every key of ``RESULT_KEYS``: ``stiffness`` [N/m^1.5], ``restitution``, ``mass`` [kg],
        ``velocity`` [m/s] (the given one echoed with stderr 0), ``damping_factor`` c [s/m],
        ``modulus`` [Pa] (NaN without diameter and poisson), the model-based indices
        ``start_time`` [s], ``peak_force`` [N], ``time_to_peak`` [s] (from t0), ``contact_duration`` [s],
        ``firmness_c`` [N/s], ``firmness_c_star`` [N/s²], ``impulse`` [N s] = m (1 + e) V, each with
        ``<name>_stderr``; ``fit_residual`` (RMS residual [N]) and ``fit_residual_relative``
        (over the peak), ``noise`` (the noise sd behind the standard errors [N]),
        ``samples_in_contact``, ``converged``, ``iterations`` and ``message``.  A pulse that cannot
        be fitted (flat, too short, not inside the window) gives ``converged = False`` and a message,
        with NaN where nothing could be computed.

    Raises
    ------
    ValueError
        Neither or both of ``velocity`` and ``mass``; arrays of different lengths or not 1-D;
        NaN or infinite samples (in force, where the mask uses them); times not increasing;
        a non-positive velocity, mass, diameter or noise; ``diameter`` without ``poisson`` or
        the reverse; ``poisson`` outside [0, 0.5).

    Examples
    --------
    >>> import fruitimpact as fi
    >>> result = fi.simulate(drop_height="4cm")
    >>> fit = fi.fit_impact(result.curves.time, result.curves.force, velocity=result.inputs.velocity)
    >>> round(fit["restitution"], 3)  # doctest: +SKIP
    0.577

    References
    ----------
    The Hunt–Crossley force law of "Theoretical aspects about simulating the reaction to impact of apples on
    rigid plane surfaces" (eqs 10–12); K. H. Hunt, F. R. E. Crossley, J. Appl. Mech. 42 (1975) 440–445.
    """
    if velocity is None and mass is None:
        raise ValueError("fit_impact needs the impact velocity (velocity=, from the drop height) or the "
                         "fruit mass (mass=): one pulse determines only three of stiffness, damping, mass "
                         "and velocity")
    if velocity is not None and mass is not None:
        raise ValueError("give velocity or mass, not both: the fit determines the other (compare it with "
                         "yours afterwards)")
    if baseline not in _BASELINE_TERMS:
        raise ValueError(f"baseline must be None, 'offset' or 'linear', got {baseline!r}")
    terms = _BASELINE_TERMS[baseline]
    velocity = _positive("velocity", velocity)
    mass = _positive("mass", mass)
    if (diameter is None) != (poisson is None):
        raise ValueError("give diameter and poisson together (the modulus needs both)")
    diameter = _positive("diameter", diameter)
    if poisson is not None:
        from fruitimpact.impact.validation import read_value

        poisson = read_value("poisson", poisson)
        if not (0.0 <= poisson < 0.5):
            raise ValueError(f"poisson must be in [0, 0.5), got {poisson!r}")
    t = np.asarray(time, dtype=float)
    y = np.asarray(force, dtype=float)
    if t.ndim != 1 or y.ndim != 1:
        raise ValueError("time and force must be 1-D arrays")
    if t.shape != y.shape:
        raise ValueError(f"time and force must have the same length, got {t.size} and {y.size}")
    if mask is None:
        use = np.ones(t.shape, dtype=bool)
    else:
        use = np.asarray(mask)
        if use.dtype != bool or use.shape != t.shape:
            raise ValueError("mask must be a boolean array of the length of time")
    if not np.all(np.isfinite(t)):
        raise ValueError("time contains NaN or infinite values")
    if not np.all(np.isfinite(y[use])):
        raise ValueError("force contains NaN or infinite values (exclude such samples with mask=)")
    if t.size > 1 and not np.all(np.diff(t) > 0.0):
        raise ValueError("time must be strictly increasing")
    sigma = None
    if noise is not None:
        sigma = np.broadcast_to(np.asarray(noise, dtype=float), t.shape)
        if not np.all(np.isfinite(sigma[use]) & (sigma[use] > 0.0)):
            raise ValueError("noise must be finite and > 0")

    t_ref = float(t[0]) if t.size else 0.0
    ts = np.ascontiguousarray(t[use] - t_ref)
    ys = np.ascontiguousarray(y[use])
    weights = np.ascontiguousarray(1.0 / sigma[use]) if sigma is not None else None
    if ts.size < MIN_CONTACT_SAMPLES + 4:
        return _empty_result(f"too few samples ({ts.size}) to fit four parameters")

    noise_level = float(np.median(sigma[use])) if sigma is not None else _noise_estimate(ys)
    top = float(np.max(_smooth(ys)))
    if not (top > MIN_PEAK_SNR * noise_level) or top <= 0.0:
        return _empty_result(f"no pulse: the peak ({top:.3g} N) is not above {MIN_PEAK_SNR:g} noise sd "
                             f"({noise_level:.3g} N)")
    notes = []
    if mask is None:
        at_max = int(np.count_nonzero(y == np.max(y)))
        if at_max >= 3:
            notes.append(f"{at_max} samples equal the maximum: clipped? exclude them with mask=")

    model = PulseModel(ts, terms)

    theta, message = _start(ts, ys, model, weights)
    if theta is None:
        return _empty_result(message)
    with np.errstate(over="ignore", invalid="ignore"):  # a far trial step is rejected, not worth a warning
        if terms:
            theta, jac, r, iterations, converged, message = levenberg_marquardt(model, ys, theta, weights)
        else:  # the same iteration compiled (one pulse: ~1 ms less per contact on a sorting line)
            theta, jac, r, iterations, converged, message = fit_pulse_sum(
                ts, ys, weights if weights is not None else np.ones(ts.size), theta)

    t0, duration, x = theta[0], math.exp(theta[2]), theta[3]
    inside = int(np.count_nonzero((ts > t0) & (ts < t0 + duration)))
    if inside < MIN_CONTACT_SAMPLES:
        converged = False
        message = f"too short: {inside} samples in contact (at least {MIN_CONTACT_SAMPLES} needed)"
    elif t0 < ts[0] or t0 + duration > ts[-1] + (OPEN_END_MAX * duration if open_end and not terms else 0.0):
        converged = False
        message = "the fitted contact is not inside the window (onset or end not sampled)"
        if open_end and t0 >= ts[0]:
            message += (f": its last {(t0 + duration - ts[-1]) / duration:.0%} lies after the window, cut by the "
                        f"next contact (at most {OPEN_END_MAX:.0%} is extrapolated, without a fitted baseline)")
    elif x >= X_MAX:
        converged = False
        message = f"the restitution is below the fit's range (x = c V at its limit {X_MAX:g}, e < 0.1)"
    elif x <= 0.0 and converged:
        notes.append("x = c V at its bound 0: an undamped (e = 1) pulse")
    if converged and t0 + duration > ts[-1]:
        gain = _damping_evidence(ts, ys, weights, theta, model)
        if gain < OPEN_END_EVIDENCE:
            converged = False
            message = (f"the window, cut by the next contact before this contact's tail, leaves its damping "
                       f"undetermined: a restitution {OPEN_END_DE:g} lower fits the samples within Δχ² = {gain:.2g} "
                       f"(at least {OPEN_END_EVIDENCE:g} needed to extrapolate the tail)")
        else:
            notes.append(f"the contact's last {(t0 + duration - ts[-1]) * 1e3:.2g} ms "
                         f"({(t0 + duration - ts[-1]) / duration:.0%} of the fitted duration) not sampled (the window "
                         f"was cut by a following contact): its end extrapolated by the force law")

    residual = model(theta) - ys
    rms = float(np.sqrt(np.mean(residual ** 2)))
    dof = max(ts.size - theta.size, 1)
    a = jac.T @ jac
    scale = np.sqrt(np.diag(a))
    try:
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse = (np.linalg.inv(a / np.outer(scale, scale)) / np.outer(scale, scale))[:4, :4]
    except np.linalg.LinAlgError:
        inverse = np.full((4, 4), np.nan)
    if weights is None:
        s2 = float(r @ r) / dof
        noise_used = math.sqrt(s2)
    else:
        s2 = 1.0
        noise_used = noise_level
    covariance = s2 * inverse

    result = named_result(theta[:4], covariance, (velocity, mass, diameter, poisson), t_ref)
    result.update(fit_residual=rms, fit_residual_relative=rms / result["peak_force"], noise=noise_used,
                  samples_in_contact=inside, converged=bool(converged), iterations=int(iterations),
                  message="; ".join([message] + notes))
    return result


def _damping_evidence(ts, ys, weights, theta, model) -> float:
    """How much worse (Δχ², in noise variances) the samples fit with the restitution ``OPEN_END_DE`` below the fit's
    ``theta`` (the damping fixed there by a stiff prior row, the other parameters refitted): small when the samples
    do not fix the damping (a window cut before the contact's tail).  Without given noise the free fit's residual
    variance is the unit.  A fit with a fitted baseline (``model`` with terms) is not extrapolated: 0."""
    if theta.size != 4:
        return 0.0
    e_alt = float(restitution_of_x(float(theta[3]))) - OPEN_END_DE
    if not e_alt > 0.05:
        return 0.0
    x_alt = float(exact_x(e_alt))
    start = np.array(theta, dtype=float)
    start[3] = x_alt
    w = weights if weights is not None else np.ones(ts.size)
    with np.errstate(over="ignore", invalid="ignore"):
        alt, *_ = fit_pulse_sum(ts, ys, w, start, np.array([3]), np.array([x_alt]), np.array([1e6]))
        free = float(np.sum(((model(theta) - ys) * w) ** 2))
        other = float(np.sum(((model(alt) - ys) * w) ** 2))
    unit = 1.0 if weights is not None else free / max(ts.size - 4, 1)
    gain = (other - free) / unit if unit > 0 else 0.0
    return gain if math.isfinite(gain) else 0.0


def prepare() -> None:
    """Build the pulse-shape table now (~0.25 s, once per process), so that a stream's first fit does not
    pay for it while a fruit waits for its line."""
    shape_table()


def at_velocity(result: dict, velocity: float) -> dict:
    """A ``fit_impact`` result obtained with one impact velocity, restated for another [m/s].

    The fit itself (θ = t0, F_max, T, x) does not depend on the velocity; only the split of the Hertz
    scales does (module docstring): δ_H = V t_H, so K ∝ V^-1.5, m ∝ 1/V, c = x/V and E ∝ K, each with
    the same relative standard error (V is exact when given), and the indices are unchanged.  Exact, so
    one fit serves the shape (the rebound test) and the line's knowns alike."""
    velocity = _positive("velocity", velocity)
    if not (result.get("velocity_stderr") == 0.0 and _finite_positive(result.get("velocity"))):
        raise ValueError("at_velocity restates a fit that was given the velocity (velocity_stderr 0)")
    ratio = velocity / result["velocity"]
    out = dict(result)
    for name, power in (("stiffness", -1.5), ("modulus", -1.5), ("mass", -1.0), ("damping_factor", -1.0)):
        out[name] = result[name] * ratio ** power
        out[name + "_stderr"] = result[name + "_stderr"] * ratio ** power
    out["velocity"] = velocity
    return out


def _finite_positive(value) -> bool:
    return isinstance(value, (int, float)) and math.isfinite(value) and value > 0


def model_curve(time, result: dict) -> np.ndarray:
    """The fitted force [N] at ``time`` [s] (any grid: draw it over the data), from the exact engine
    with the ``stiffness``, ``damping_factor``, ``mass``, ``velocity`` and ``start_time`` of a
    ``fit_impact`` result; zero outside the contact, NaN everywhere if the result has no fit."""
    t = np.asarray(time, dtype=float)
    params = [result.get(key, math.nan) for key in ("mass", "stiffness", "damping_factor", "velocity",
                                                     "start_time")]
    if not all(isinstance(p, (int, float)) and math.isfinite(p) for p in params):
        return np.full(t.shape, np.nan)
    m, k, c, v, t0 = params
    return powerlaw_curves(m, k, c, v, t - t0)[2].reshape(t.shape)
