"""Maximum-likelihood fits of the bruise model to drop or pendulum tests (numpy and math only, SI).

Two models, one definition of the threshold energy W_th: the median of the per-fruit thresholds, i.e. the energy
at which half the fruit bruise.

**Volumes** (:func:`fit_volumes`; a measured bruise volume per test, 0 where the fruit did not bruise).  Fruit i
hit with energy W_i has its own threshold T_i, lognormal around W_th with spread σ_t (ln T_i ~ N(ln W_th, σ_t²));
it bruises when W_i > T_i, and then its volume is BV_i = BS (W_i − T_i) e^(σ_v ε_i), ε_i ~ N(0, 1) (a
multiplicative scatter of the susceptibility and of the measurement).  BS is therefore the **median** volume per
joule above a fruit's threshold: the mean is BS e^(σ_v²/2) (2 % more at σ_v = 0.2, 13 % at σ_v = 0.5).  The
simulator's BV = BS (W − W_th)₊ with the fitted BS gives that median bruise.  Why this model:

* an unbruised fruit is *censored*, not a zero of a line: all it says is T_i ≥ W_i, with probability
  1 − Φ((ln W_i − ln W_th)/σ_t).  A least-squares line through the zeros drags BS down and W_th below the energies
  that did not bruise;
* the median volume is the published BV = BS (W − W_th)₊ (Opara & Pathare 2014) for identical fruit (σ_t → 0),
  and near the threshold it rises smoothly, as pooled data do, because only the weaker fruit bruise there;
* volumes are positive and scatter in proportion to their size, so the scatter is lognormal, not additive;
* with no test below the threshold the model still fits BS and W_th from the volumes (the intercept of the line);
  the data then bound W_th only from above, and the fit says so.

The likelihood of a bruised fruit is the integral over its unknown threshold,
p(BV_i) = ∫₀^{W_i} f_T(t) f_V(BV_i | BS (W_i − t)) dt, computed in the threshold's standard normal variable around
the integrand's one peak, found by Newton's method (``_volume_terms``), in log space so that no term underflows;
the tests check it against scipy's adaptive quadrature to 0.01 in ln p.  An unbruised fruit contributes ln Φ(−z_i).

**Incidence** (:func:`fit_incidence`; bruised or not, 0/1).  The same per-fruit lognormal threshold gives a
probit in ln W: P(bruised | W) = Φ((ln W − ln W_th)/σ_t).  W_th is its 50 % point and σ_t its spread.  A 0/1
outcome carries no volume, so it cannot give a susceptibility.

**Intervals.** 95 % profile-likelihood intervals: the values ψ of the parameter at which
2 (ℓ_max − max_{others} ℓ(ψ, others)) = χ²₁(0.95) = 3.841, each found by a secant on the signed root of that
statistic from a first step of 1.96 standard errors; an end that is not reached inside the search box
(``SPREAD_BOUNDS``, ``THRESHOLD_BELOW``, ``THRESHOLD_ABOVE``) is ``None`` (the data do not bound the parameter on
that side; a threshold open below is then no estimate at all: the likelihood is flat down to no threshold).
Profile intervals follow the likelihood where it is skewed (a threshold barely bracketed) and are invariant to the
parametrisation; their coverage is checked by simulation in tests/test_fit_damage.py.
The maximisation is Nelder–Mead (Gao & Han 2012 adaptive coefficients) in (ln BS, ln W_th, ln σ_t, ln σ_v), from
several starts, on energies and volumes divided by their geometric means (the model is invariant to the units: a
table in joules and cubic metres, or one of 1e-300 J, fits the same, with no linear algebra on raw values).

References
----------
L. O. Opara & P. B. Pathare, Postharvest Biol. Technol. 91 (2014) 9–24 (BV = BS (W − W_th)₊);
J. Tobin, Econometrica 26 (1958) 24–36 (censored regression); D. J. Finney, *Probit Analysis* (1971) (threshold
tolerance distributions); D. J. Venzon & S. H. Moolgavkar, Appl. Statist. 37 (1988) 87–94 (profile-likelihood
intervals); F. Gao & L. Han, Comput. Optim. Appl. 51 (2012) 259–277 (adaptive Nelder–Mead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: 2 Δℓ at the ends of a 95 % profile-likelihood interval: the 0.95 quantile of χ² with one degree of freedom.
CHI2_95 = 3.841458820694124
#: The spreads σ_t and σ_v are searched in [0.01, 3] (lognormal σ): below 1 % no test could tell them from 0, and a
#: bound keeps the likelihood finite when a few tests fit exactly.
SPREAD_BOUNDS = (0.01, 3.0)
#: ln W_th is searched from ``THRESHOLD_BELOW`` below the lowest tested ln W to ``THRESHOLD_ABOVE`` above the highest:
#: a threshold 400 times below every test is "not bounded below" (every test bruised), 20 times above "not bounded
#: above" (none bruised).
THRESHOLD_BELOW, THRESHOLD_ABOVE = 6.0, 3.0
#: Fewest bruised tests of a volume fit (BS, W_th and the volume scatter need three), and fewest tests of each
#: outcome of an incidence fit.
MIN_BRUISED = 3
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)
#: Quadrature nodes: the coarse grid over [−10, z_W] (fractions), the volume density's own (in σ_v), the peak's
#: (in Laplace widths).
_UNIFORM = np.linspace(0.0, 1.0, 49)
_VOLUME = np.linspace(-8.0, 8.0, 17)
_PEAK = np.linspace(-8.0, 8.0, 41)
_FLOOR = -60.0
_ERFC = np.frompyfunc(math.erfc, 1, 1)


def log_ndtr(x) -> np.ndarray:
    """ln Φ(x), the log of the standard normal distribution function, accurate in both tails [-]."""
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    tail = x < -37.0  # erfc(26) ≈ 1e-296: erfc serves down to here
    upper = x > 0.0
    body = ~tail & ~upper
    # Φ(x) = erfc(−x/√2)/2 (erfc is relative-accurate down to 1e-308); above 0, ln(1 − Q) with Q = erfc(x/√2)/2
    # by log1p, so that Φ's last 1e-17 is not rounded away
    with np.errstate(divide="ignore"):
        out[body] = np.log(0.5 * _ERFC(-x[body] / math.sqrt(2.0)).astype(float))
        out[upper] = np.log1p(-0.5 * _ERFC(x[upper] / math.sqrt(2.0)).astype(float))
    # below −37: Mills' ratio series, ln Φ(x) = −x²/2 − ln(−x) − ln √(2π)
    # + ln(1 − 1/x² + 3/x⁴ − 15/x⁶ + 105/x⁸), its next term below 1e-12 there
    xt = x[tail]
    inv = 1.0 / (xt * xt)
    series = inv * (-1.0 + inv * (3.0 + inv * (-15.0 + 105.0 * inv)))
    out[tail] = -0.5 * xt * xt - np.log(-xt) - _LOG_SQRT_2PI + np.log1p(series)
    return out


def nelder_mead(func, x0, step, *, tolerance: float = 1e-9, max_evaluations: int = 5000):
    """Minimise ``func`` (a float of a 1-D array) from ``x0`` by the Nelder–Mead simplex with Gao & Han's
    dimension-adapted coefficients; ``step``: the initial simplex's edge per coordinate.  Stops when the simplex's
    values agree to ``tolerance`` (absolute, ``func`` is a negative log-likelihood) and its points to 1e-7, and is
    restarted once from its best point (a collapsed simplex can stop short).  Returns (x, func(x))."""
    x = np.asarray(x0, dtype=float)
    best, value = x, float(func(x))
    for _ in range(2):
        best, value = _simplex(func, best, value, np.asarray(step, dtype=float), tolerance, max_evaluations)
    return best, value


def _best_of(negative, starts, step):
    """The minimum of ``negative`` over several starts: each run coarsely (to 1e-3), the best polished
    (:func:`nelder_mead`), so that a second mode costs a few hundred evaluations, not a full run."""
    coarse = [_simplex(negative, start, float(negative(start)), step, 1e-3, 800) for start in starts]
    x, _ = min(coarse, key=lambda pair: pair[1])
    return nelder_mead(negative, x, 0.3 * step)


def _simplex(func, x0, f0, step, tolerance, max_evaluations):
    n = x0.size
    # Gao & Han's coefficients; in one dimension their shrink (1 − 1/n = 0) would collapse the simplex: halve it
    alpha, gamma, rho, sigma = 1.0, 1.0 + 2.0 / n, 0.75 - 0.5 / n, max(1.0 - 1.0 / n, 0.5)
    points = np.vstack([x0] + [x0 + np.eye(n)[i] * step[i] for i in range(n)])
    values = np.array([f0] + [float(func(p)) for p in points[1:]])
    evaluations = n
    while evaluations < max_evaluations:
        order = np.argsort(values, kind="stable")
        points, values = points[order], values[order]
        if values[-1] - values[0] <= tolerance and np.max(np.abs(points[1:] - points[0])) <= max(1e-7, tolerance):
            break
        centroid = points[:-1].mean(axis=0)
        reflected = centroid + alpha * (centroid - points[-1])
        f_r = float(func(reflected))
        evaluations += 1
        if f_r < values[0]:
            expanded = centroid + gamma * (reflected - centroid)
            f_e = float(func(expanded))
            evaluations += 1
            points[-1], values[-1] = (expanded, f_e) if f_e < f_r else (reflected, f_r)
        elif f_r < values[-2]:
            points[-1], values[-1] = reflected, f_r
        else:
            outside = f_r < values[-1]
            contracted = centroid + rho * ((reflected if outside else points[-1]) - centroid)
            f_c = float(func(contracted))
            evaluations += 1
            if f_c < (f_r if outside else values[-1]):
                points[-1], values[-1] = contracted, f_c
            else:  # shrink towards the best point
                points[1:] = points[0] + sigma * (points[1:] - points[0])
                values[1:] = [float(func(p)) for p in points[1:]]
                evaluations += n
    k = int(np.argmin(values))
    return points[k], float(values[k])


# ------------------------------------------------------------------------------------------------ the models

def _volume_terms(theta, ln_w_bruised, ln_volume, ln_w_unbruised):
    """ℓ of the volume model at θ = (ln BS, ln W_th, ln σ_t, ln σ_v): per unbruised test ln Φ(−z), per bruised
    test the log of the integral over its threshold, in the threshold's standard normal variable z (t = W_th e^(σ_t z),
    the fruit bruised: z < z_W = ln(W/W_th)/σ_t):

        p(BV) = ∫_{−∞}^{z_W} φ(z) f_V(BV | BS (W − t(z))) dz.

    The integrand is one peak (the product of the threshold's normal and the volume's lognormal, in z) that can be
    far narrower than either: it is found by Newton's method on its logarithm h from the best of a coarse grid (z
    over [−10, z_W] and the volume density's own nodes), and the trapezoidal rule then runs on 41 nodes across
    ±8 Laplace widths (−h'')^(−1/2) of it, joined to the coarse grid (any other mass)."""
    ln_bs, ln_th, ln_st, ln_sv = theta
    sigma_t, sigma_v = math.exp(ln_st), math.exp(ln_sv)
    total = float(log_ndtr(-(ln_w_unbruised - ln_th) / sigma_t).sum()) if ln_w_unbruised.size else 0.0
    if not ln_w_bruised.size:
        return total
    z_w = ((ln_w_bruised - ln_th) / sigma_t)[:, None]
    lw = ln_w_bruised[:, None]
    centre = (ln_volume - ln_bs)[:, None]  # ln u where the volume density peaks (u = W − t, the excess energy)

    def log_u(z):  # ln(W − W_th e^(σ_t z)) = ln W + ln(1 − e^(σ_t (z − z_W))), −inf at z_W
        with np.errstate(divide="ignore"):
            return lw + np.log(-np.expm1(sigma_t * np.minimum(z - z_w, 0.0)))

    def h(z):  # ln of the integrand, without its constants
        return -0.5 * z * z - 0.5 * ((log_u(z) - centre) / sigma_v) ** 2

    low = np.minimum(-10.0, z_w - 10.0)
    grid = low + (z_w - low) * _UNIFORM
    with np.errstate(divide="ignore", invalid="ignore"):
        at_volume = z_w + np.log(-np.expm1(np.minimum(centre + sigma_v * _VOLUME - lw, 0.0))) / sigma_t
    # the volume density's nodes may lie far below the grid (a volume the fruit's threshold hardly allows): kept down
    # to z = −60 (φ < e^−1800), so that the peak between the two densities is found even there
    at_volume = np.where(np.isfinite(at_volume), np.clip(at_volume, _FLOOR, z_w), low)
    coarse = np.concatenate([grid, at_volume], axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        values = h(coarse)
    values = np.where(np.isnan(values), -np.inf, values)
    z = np.take_along_axis(coarse, np.argmax(values, axis=1)[:, None], axis=1)
    curvature = np.full_like(z, -1.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(12):
            q = np.exp(sigma_t * np.minimum(z - z_w, 0.0))
            d1 = -sigma_t * q / (1.0 - q)  # d ln u / dz
            d2 = -sigma_t * sigma_t * q / (1.0 - q) ** 2
            g = log_u(z) - centre
            slope = -z - g * d1 / (sigma_v * sigma_v)
            curvature = -1.0 - (d1 * d1 + g * d2) / (sigma_v * sigma_v)
            step = np.where(curvature < 0.0, -slope / curvature, np.sign(slope) * 0.5)
            step = np.clip(np.nan_to_num(step), -2.0, 2.0)
            # never past z_W: halfway to it instead
            z = np.where(z + step < z_w, z + step, 0.5 * (z + z_w))
        width = np.where(curvature < 0.0, 1.0 / np.sqrt(-curvature), 0.5)
    width = np.where(np.isfinite(width), width, 0.5)
    peak = np.clip(z + width * _PEAK, _FLOOR, z_w)
    nodes = np.sort(np.concatenate([coarse, peak, z_w], axis=1), axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        log_g = h(nodes)
    log_g = np.where(np.isnan(log_g), -np.inf, log_g)
    top = np.max(log_g, axis=1, keepdims=True)
    if not np.all(np.isfinite(top)):
        return -math.inf
    scaled = np.exp(log_g - top)
    integral = np.sum(np.diff(nodes, axis=1) * 0.5 * (scaled[:, 1:] + scaled[:, :-1]), axis=1)
    constants = -2.0 * _LOG_SQRT_2PI - ln_sv - ln_volume  # φ's and f_V's normalisations, f_V's 1/BV
    with np.errstate(divide="ignore"):
        return total + float(np.sum(top[:, 0] + np.log(integral) + constants))


def _incidence_terms(theta, ln_w_bruised, ln_w_unbruised):
    """ℓ of the probit in ln W at θ = (ln W_th, ln σ_t)."""
    ln_th, ln_st = theta
    sigma = math.exp(ln_st)
    return float(log_ndtr((ln_w_bruised - ln_th) / sigma).sum() + log_ndtr(-(ln_w_unbruised - ln_th) / sigma).sum())


# ---------------------------------------------------------------------------------------------- the fitting

@dataclass(frozen=True)
class BruiseFit:
    """The outcome of a fit.

    Attributes
    ----------
    model : str
        ``"volume"`` or ``"incidence"``.
    estimates : dict
        Name → maximum-likelihood estimate in SI, or None where the data do not determine it: ``bruise_energy``
        W_th [J] (the median threshold), ``bruise_susceptibility`` BS [m³/J] (volume model only; the median volume
        per joule above a fruit's threshold, the volume's scatter being lognormal), ``threshold_spread`` σ_t [-] and
        ``volume_scatter`` σ_v [-] (volume model only).
    intervals : dict
        Name → (low, high) of the 95 % profile-likelihood interval [SI]; an end is None where the data do not
        bound the parameter on that side (``bruise_energy`` and ``bruise_susceptibility``).
    log_likelihood : float
        ℓ at the estimate (volumes in m³: the density of ln-scale data shifts it by a constant).
    status : str
        ``"ok"`` or ``"failed"`` (too few bruised or unbruised tests to fit; ``message`` says which).
    message : str
        What was fitted, or why nothing could be (a ``failed`` fit's message always says why).
    notes : list of str
        Caveats (a threshold not bounded on one side, a spread at the end of its search range).
    """

    model: str
    estimates: dict
    intervals: dict
    log_likelihood: float
    status: str
    message: str
    notes: list = field(default_factory=list)


def _checked(energy, outcome, name: str):
    energy = np.asarray(energy, dtype=float)
    outcome = np.asarray(outcome, dtype=float)
    if energy.ndim != 1 or energy.shape != outcome.shape:
        raise ValueError(f"energy and {name} must be 1-D arrays of one length; got shapes {energy.shape} and "
                         f"{outcome.shape}")
    if not (np.all(np.isfinite(energy)) and np.all(energy > 0.0)):
        raise ValueError("energy must be finite and > 0 J in every test")
    if not np.all(np.isfinite(outcome)) or np.any(outcome < 0.0):
        raise ValueError(f"{name} must be finite and >= 0 in every test")
    return energy, outcome


def _box(ln_w):
    return (float(ln_w.min()) - THRESHOLD_BELOW, float(ln_w.max()) + THRESHOLD_ABOVE)


def _penalised(loglik, low, high):
    """A negative log-likelihood for the simplex: θ outside the box is clipped into it and pays its distance
    squared, so the simplex returns inside without a wall it could stick to."""
    def negative(theta):
        inside = np.clip(theta, low, high)
        value = loglik(inside)
        if not math.isfinite(value):
            return 1e100
        return -value + 1e3 * float(np.sum((theta - inside) ** 2))
    return negative


def _half_widths(negative, theta_hat) -> np.ndarray:
    """First guesses of the 95 % half-widths of every coordinate: 1.96 standard errors from the curvature of
    ``negative`` at the estimate (central differences, one Hessian for all), 0.2 where it is not positive
    definite."""
    n, h = theta_hat.size, 1e-3
    hessian = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            shifts = [(1, 1), (1, -1), (-1, 1), (-1, -1)]
            values = []
            for a, b in shifts:
                theta = theta_hat.copy()
                theta[i] += a * h
                theta[j] += b * h
                values.append(negative(theta))
            hessian[i, j] = hessian[j, i] = (values[0] - values[1] - values[2] + values[3]) / (4.0 * h * h)
    widths = np.full(n, 0.2)
    if not np.all(np.isfinite(hessian)):
        return widths  # a step left the likelihood's finite region: no curvature (and no LAPACK on NaN)
    try:
        variance = np.diag(np.linalg.inv(hessian))
    except np.linalg.LinAlgError:
        return widths
    good = np.isfinite(variance) & (variance > 0.0)
    widths[good] = 1.96 * np.sqrt(variance[good])
    return widths


def _profile(negative, theta_hat, index, value_hat, low, high, first: float | None = None):
    """The (low, high) ends of the 95 % profile interval of coordinate ``index`` (None where not reached inside the
    box): where the signed root r(ψ) = √(2 (ℓ̂ − ℓ_p(ψ))) reaches 1.96.  r is nearly linear in ψ, so a secant
    on it from a first step of 1.96 standard errors converges in a few profile maximisations, each started from the
    previous one's optimum; a bracket, once found, is kept (bisection where the secant leaves it)."""
    others = [k for k in range(theta_hat.size) if k != index]
    target = math.sqrt(CHI2_95)

    def root(psi, start):
        if not others:
            return math.sqrt(max(0.0, 2.0 * (negative(np.array([psi])) - value_hat))), start

        def restricted(rest):
            theta = np.empty(theta_hat.size)
            theta[index] = psi
            theta[others] = rest
            return negative(theta)

        rest, value = _simplex(restricted, start, restricted(start), np.full(len(others), 0.03), 1e-5, 4000)
        return math.sqrt(max(0.0, 2.0 * (value - value_hat))), rest

    if first is None:  # the first step: 1.96 standard errors (``_half_widths``, computed once by callers of several)
        first = float(_half_widths(negative, theta_hat)[index])
    ends = []
    for direction, limit in ((-1.0, low[index]), (1.0, high[index])):
        psi_hat = theta_hat[index]
        points = [(psi_hat, 0.0)]
        rest = theta_hat[others]
        below, above = psi_hat, None  # the bracket: r < target at ``below``, ≥ target at ``above``
        found = None
        for _ in range(40):
            (psi_a, r_a), (psi_b, r_b) = points[-2] if len(points) > 1 else points[0], points[-1]
            if len(points) == 1:
                psi = psi_hat + direction * first
            elif r_b > r_a:
                psi = psi_b + (target - r_b) * (psi_b - psi_a) / (r_b - r_a)
            else:
                psi = psi_b + direction * 2.0 * abs(psi_b - psi_hat)
            if above is not None:  # stay inside the bracket, away from its ends
                lo, hi = sorted((below, above))
                if not lo + 0.05 * (hi - lo) < psi < hi - 0.05 * (hi - lo):
                    psi = 0.5 * (lo + hi)
            elif (psi - psi_hat) * direction > 4.0 * abs(psi_b - psi_hat) + first:
                psi = psi_b + direction * (3.0 * abs(psi_b - psi_hat) + first)  # grow at most fourfold
            at_limit = (psi - limit) * direction >= 0.0
            psi = limit if at_limit else psi
            r, rest = root(psi, rest)
            if abs(r - target) < 2e-3 or (above is not None and abs(above - below) < 1e-4):
                found = psi
                break
            if r < target:
                below = psi
                if at_limit:
                    break
            else:
                above = psi
            points.append((psi, r))
        ends.append(found if found is not None else (None if above is None else 0.5 * (below + above)))
    return ends[0], ends[1]


def fit_volumes(energy, volume) -> BruiseFit:
    """Fit BS, W_th and the two spreads to tests with a bruise volume each (the module's volume model).

    Parameters
    ----------
    energy : array
        Energy of each test W_i [J], > 0, on one basis for all (``handling.droptests`` passes the energy the
        simulator compares with the threshold: the fruit's share of the impact energy on each test's surface).
    volume : array
        Bruise volume of each test BV_i [m³], ≥ 0; 0: the fruit did not bruise (a censored threshold).

    Returns
    -------
    BruiseFit
        ``estimates`` and ``intervals`` of ``bruise_susceptibility`` [m³/J] (the median volume per joule above a
        fruit's threshold; the mean is e^(σ_v²/2) times it) and ``bruise_energy`` [J] (the median threshold), with
        ``threshold_spread`` and ``volume_scatter``; ``status`` ``failed`` with fewer than ``MIN_BRUISED`` bruised
        tests.

    Raises
    ------
    ValueError
        Arrays of different shapes, an energy that is not finite and positive, a volume that is not finite and ≥ 0.
    """
    energy, volume = _checked(energy, volume, "volume")
    bruised = volume > 0.0
    count = int(bruised.sum())
    if count < MIN_BRUISED:
        above = f"; the threshold is above {energy.max():.4g} J" if count == 0 else ""
        return BruiseFit("volume", _empty("volume"), {}, math.nan, "failed",
                         f"{count} of {energy.size} tests bruised: a volume fit needs at least {MIN_BRUISED} bruised "
                         f"tests (bruise susceptibility, threshold and volume scatter){above}")
    # in units of the tests' own geometric means (the model is scale-invariant): W' = W/w0, V' = V/v0, so that
    # ln BS = ln BS' + ln(v0/w0), ln W_th = ln W_th' + ln w0 (the spreads are ratios: unchanged), and ℓ with volumes
    # in m³ is ℓ' − (bruised tests) ln v0
    ln_w0 = float(np.mean(np.log(energy)))
    ln_v0 = float(np.mean(np.log(volume[bruised])))
    ln_w = np.log(energy) - ln_w0
    ln_wb, ln_v, ln_wu = ln_w[bruised], np.log(volume[bruised]) - ln_v0, ln_w[~bruised]
    th_low, th_high = _box(ln_w)
    ratio = ln_v - ln_wb
    low = np.array([ratio.min() - 10.0, th_low, math.log(SPREAD_BOUNDS[0]), math.log(SPREAD_BOUNDS[0])])
    high = np.array([ratio.max() + 10.0, th_high, math.log(SPREAD_BOUNDS[1]), math.log(SPREAD_BOUNDS[1])])
    negative = _penalised(lambda theta: _volume_terms(theta, ln_wb, ln_v, ln_wu), low, high)
    starts = _volume_starts(np.exp(ln_w), _scattered(bruised, np.exp(ln_v)), bruised)
    theta, value = _best_of(negative, [np.clip(start, low, high) for start in starts], np.full(4, 0.3))
    shift = np.array([ln_v0 - ln_w0, ln_w0, 0.0, 0.0])  # scaled θ → θ in SI
    intervals = {}
    widths = _half_widths(negative, theta)  # one Hessian for both profiles
    for index, name in ((0, "bruise_susceptibility"), (1, "bruise_energy")):
        ends = _profile(negative, theta, index, value, low, high, float(widths[index]))
        intervals[name] = tuple(None if end is None else math.exp(end + shift[index]) for end in ends)
    estimates = {"bruise_susceptibility": math.exp(theta[0] + shift[0]), "bruise_energy": math.exp(theta[1] + shift[1]),
                 "threshold_spread": math.exp(theta[2]), "volume_scatter": math.exp(theta[3])}
    notes = _bound_notes(theta, low, high, energy, estimates, intervals, ("threshold_spread", "volume_scatter"))
    return BruiseFit("volume", estimates, intervals, -value - count * ln_v0, "ok",
                     f"volume model fitted to {energy.size} tests ({count} bruised)", notes)


def _scattered(bruised, values):
    """``values`` (one per bruised test) put back at the bruised tests' places, 0 elsewhere."""
    out = np.zeros(bruised.size)
    out[bruised] = values
    return out


def _volume_starts(energy, volume, bruised):
    """Starting points (ln BS, ln W_th, ln σ_t, ln σ_v): a line through the bruised volumes gives the threshold (its
    intercept, kept below the lowest bruising energy), the unbruised tests a second guess, each with a narrow and a
    wide spread."""
    wb, vb = energy[bruised], volume[bruised]
    guesses = [0.5 * wb.min()]
    if wb.size >= 2 and np.ptp(wb) > 0.0:
        # the least-squares line written out (no LAPACK: scaled values, and nothing for it to complain about)
        dw = wb - wb.mean()
        slope = float(np.sum(dw * (vb - vb.mean())) / np.sum(dw * dw))
        intercept = float(vb.mean() - slope * wb.mean())
        if slope > 0.0 and 0.0 < -intercept / slope < wb.min():
            guesses.append(-intercept / slope)
    unbruised = energy[~bruised]
    if unbruised.size:
        guesses.append(math.sqrt(unbruised.max() * wb.min()) if unbruised.max() < wb.min() else
                       float(np.median(np.concatenate([unbruised, wb]))))
    starts = []
    for threshold in guesses:
        excess = np.maximum(wb - threshold, 0.05 * wb)
        ln_bs = float(np.median(np.log(vb / excess)))
        scatter = float(np.std(np.log(vb / excess) - ln_bs)) if wb.size > 1 else 0.3
        for spread in (0.1, 0.4):
            starts.append(np.array([ln_bs, math.log(threshold), math.log(spread), math.log(max(scatter, 0.05))]))
    return starts


def _bound_notes(theta, low, high, energy, estimates, intervals, spreads):
    """Caveats of estimates at the ends of the search box."""
    notes = []
    lower, upper = intervals.get("bruise_energy", (None, None))
    if lower is None or theta[1] - low[1] < 0.01:
        # the likelihood stays within the 95 % level down to 400 times below the lowest test: the data are as
        # likely with no threshold at all, and a maximum on that plateau is no estimate; nor is the spread of a
        # threshold the data do not see
        estimates["bruise_energy"] = estimates["threshold_spread"] = None
        intervals["bruise_energy"] = (None, upper)
        notes.append("the tests do not bound the threshold energy from below (every test far above it bruised): "
                     + (f"it is below {upper:.4g} J at 95 %" if upper is not None else "no upper bound either"))
        return notes
    if upper is None or high[1] - theta[1] < 0.01:
        estimates["bruise_energy"] = estimates["threshold_spread"] = None
        intervals["bruise_energy"] = (lower, None)
        notes.append(f"the tests do not bound the threshold energy from above (it is beyond the highest tested "
                     f"{energy.max():.4g} J)")
        return notes
    for index, name in zip(range(len(theta) - len(spreads), len(theta)), spreads):
        if estimates.get(name) is not None and (theta[index] - low[index] < 0.01 or high[index] - theta[index] < 0.01):
            side = "lower" if theta[index] - low[index] < 0.01 else "upper"
            notes.append(f"{name} is at the {side} end of its search range [{SPREAD_BOUNDS[0]:g}, "
                         f"{SPREAD_BOUNDS[1]:g}] (the tests do not resolve it)")
    return notes


def _empty(model: str) -> dict:
    names = ("bruise_energy", "threshold_spread") + (("bruise_susceptibility", "volume_scatter")
                                                     if model == "volume" else ())
    return {name: None for name in names}


def fit_incidence(energy, bruised) -> BruiseFit:
    """Fit the probit in ln W (the per-fruit lognormal threshold) to tests that only say bruised or not.

    Parameters
    ----------
    energy : array
        Energy of each test W_i [J], > 0.
    bruised : array
        1 where the fruit bruised, 0 where not.

    Returns
    -------
    BruiseFit
        ``bruise_energy`` W_th [J] (the 50 % point) with its 95 % profile interval, and ``threshold_spread`` σ_t;
        ``status`` ``failed`` when every test, or none, bruised (the threshold is then only bounded on one side).

    Raises
    ------
    ValueError
        Arrays of different shapes, an energy that is not finite and positive, an outcome that is not 0 or 1.
    """
    energy, bruised = _checked(energy, bruised, "bruised")
    if np.any((bruised != 0.0) & (bruised != 1.0)):
        raise ValueError("bruised must be 0 or 1 in every test")
    yes = bruised == 1.0
    count = int(yes.sum())
    if count == 0 or count == energy.size:
        side = (f"above the highest tested energy {energy.max():.4g} J" if count == 0 else
                f"below the lowest tested energy {energy.min():.4g} J")
        return BruiseFit("incidence", _empty("incidence"), {}, math.nan, "failed",
                         f"{count} of {energy.size} tests bruised: the threshold is {side}; the tests must include "
                         f"bruised and unbruised fruit")
    ln_w0 = float(np.mean(np.log(energy)))  # in units of the tests' geometric mean energy (scale-invariant)
    ln_w = np.log(energy) - ln_w0
    ln_wb, ln_wu = ln_w[yes], ln_w[~yes]
    th_low, th_high = _box(ln_w)
    low = np.array([th_low, math.log(SPREAD_BOUNDS[0])])
    high = np.array([th_high, math.log(SPREAD_BOUNDS[1])])
    negative = _penalised(lambda theta: _incidence_terms(theta, ln_wb, ln_wu), low, high)
    notes = []
    separated = ln_wu.max() < ln_wb.min()
    if separated:
        # every fruit below a gap unbruised, every one above bruised: the likelihood is flat across the gap and
        # maximal as σ_t → 0; the estimate is the gap's geometric middle, the spread its lower bound
        theta = np.array([0.5 * (ln_wu.max() + ln_wb.min()), low[1]])
        value = negative(theta)
        notes.append(f"the outcomes are completely separated (no bruise up to {energy[~yes].max():.4g} J, a bruise "
                     f"from {energy[yes].min():.4g} J): the threshold is the geometric middle of that gap and its "
                     f"spread is not resolved")
    else:
        starts = [np.array([float(np.median(ln_w)), math.log(s)]) for s in (0.1, 0.5)]
        theta, value = _best_of(negative, starts, np.array([0.2, 0.3]))
    ends = _profile(negative, theta, 0, value, low, high)
    intervals = {"bruise_energy": tuple(None if end is None else math.exp(end + ln_w0) for end in ends)}
    estimates = {"bruise_energy": math.exp(theta[0] + ln_w0), "threshold_spread": math.exp(theta[1])}
    if not separated:
        notes += _bound_notes(np.array([0.0, *theta]), np.array([0.0, *low]), np.array([0.0, *high]), energy,
                              estimates, intervals, ("threshold_spread",))
    return BruiseFit("incidence", estimates, intervals, -value, "ok",
                     f"probit in ln W fitted to {energy.size} tests ({count} bruised)", notes)


#: The models by name (``BruiseFit.model``): each fits (energies [J], outcomes) and returns a ``BruiseFit``.
MODELS = {"volume": fit_volumes, "incidence": fit_incidence}

__all__ = ["BruiseFit", "CHI2_95", "MIN_BRUISED", "MODELS", "SPREAD_BOUNDS", "fit_incidence", "fit_volumes",
           "log_ndtr", "nelder_mead"]
