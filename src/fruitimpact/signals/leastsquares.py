"""Levenberg–Marquardt for the pulse model (``signals.pulse``): one pulse in NumPy, a sum of pulses compiled.

``levenberg_marquardt`` minimises Σ (w (F(θ) − y))² for any model that returns F(θ) and its Jacobian
(``PulseModel``, with optional baseline terms); ``fit_pulse_sum`` is the same iteration compiled for a sum of
pulses with optional Gaussian priors on some parameters (extra rows (θ_k − μ)/sd): Marquardt's diagonal
scaling, Nielsen's damping update (``_damping_update``, shared), each x projected on [0, X_MAX], and the stop
when every step is below ``STEP_TOLERANCE`` of its parameter's standard error (with noise, Gauss–Newton
converges only linearly near the optimum; the last digits are noise).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.signals.filters import solve_small
from fruitimpact.signals.pulse import THETA_NODES, X_MAX, PulseModel, _pulse, _theta_coefficients, shape_table

__all__ = ["MAX_ITERATIONS", "STEP_TOLERANCE", "fit_pulse_sum", "levenberg_marquardt"]

MAX_ITERATIONS = 100
#: The iteration stops when every parameter's step is below this fraction of its standard error.
STEP_TOLERANCE = 1e-3


@nb.njit(cache=CACHE)
def _damping_update(cost, cost_trial, predicted, lam, nu):
    """One Levenberg–Marquardt damping decision (Nielsen's update): (step accepted, λ, ν, stop at a minimum)."""
    if cost_trial < cost:
        rho = (cost - cost_trial) / predicted if predicted > 0.0 else 1.0
        return True, lam * max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), 2.0, False
    lam, nu = lam * nu, nu * 2.0
    # no decrease even for vanishing steps: θ is a (projected) minimum (never at a non-finite cost)
    return False, lam, nu, math.isfinite(cost) and (lam > 1e16 or predicted <= 1e-14 * cost)


def levenberg_marquardt(model: PulseModel, y: np.ndarray, theta: np.ndarray, weights, bounded=(3,),
                        max_iterations: int = MAX_ITERATIONS):
    """Minimise Σ (w (F(θ) − y))² over θ = (t0, ln F_max, ln T, x, baseline…) with each x (the entries
    ``bounded``) projected on [0, X_MAX], in at most ``max_iterations``.
    Marquardt's diagonal scaling, Nielsen's damping update.  Returns (θ, J at θ, residual, iterations,
    converged, message)."""

    n_params = theta.size

    def evaluate(th, jac=False):
        out = model(th, jac)
        if jac:
            f, j = out
            r = f - y
            return (r * weights, j * weights[:, None]) if weights is not None else (r, j)
        r = out - y
        return r * weights if weights is not None else r

    r, jac = evaluate(theta, True)
    cost = float(r @ r)
    lam, nu = 1e-3, 2.0
    message = "the iteration limit was reached"
    converged = False
    iterations = 0
    for iterations in range(1, max_iterations + 1):
        a = jac.T @ jac
        g = jac.T @ r
        scale = np.sqrt(np.diag(a))
        if not np.all(scale > 0.0):
            return theta, jac, r, iterations, False, "the model does not depend on every parameter here"
        a_n = a / np.outer(scale, scale)
        g_n = g / scale
        accepted = False
        while not accepted:
            try:
                step = -np.linalg.solve(a_n + lam * np.eye(n_params), g_n) / scale
            except np.linalg.LinAlgError:
                lam *= nu
                nu *= 2.0
                if lam > 1e16:
                    return theta, jac, r, iterations, False, "the normal equations are singular"
                continue
            trial = theta + step
            for k in bounded:
                trial[k] = min(max(trial[k], 0.0), X_MAX)
            step = trial - theta
            r_trial = evaluate(trial)
            cost_trial = float(r_trial @ r_trial)
            predicted = -(2.0 * g @ step + step @ a @ step)  # decrease of the linear model
            accepted, lam, nu, stop = _damping_update(cost, cost_trial, float(predicted), lam, nu)
            if stop:
                return theta, jac, r, iterations, True, "converged"
        decrease = cost - cost_trial
        theta = trial
        r, jac = evaluate(theta, True)
        cost = float(r @ r)
        # Stop once the step is far below the parameters' standard errors (with noise the
        # Gauss–Newton model misses the residual curvature and the last digits come only
        # linearly), or the cost no longer decreases (noise-free data).
        try:
            sd = np.sqrt(np.abs(np.diag(np.linalg.inv(a_n))) * cost / max(y.size - n_params, 1)) / scale
        except np.linalg.LinAlgError:
            sd = np.zeros(n_params)
        if np.all(np.abs(step) <= STEP_TOLERANCE * sd) or decrease <= 1e-12 * cost or cost == 0.0:
            converged = True
            message = "converged"
            break
    return theta, jac, r, iterations, converged, message


@nb.njit(cache=CACHE)
def _dot(u, v) -> float:
    """u · v (loops: numba's np.dot needs SciPy's BLAS, which fruitimpact does not require)."""
    total = 0.0
    for i in range(u.shape[0]):
        total += u[i] * v[i]
    return total


@nb.njit(cache=CACHE)
def _quadratic(a, v) -> float:
    """v · (a v)."""
    total = 0.0
    for i in range(v.shape[0]):
        for j in range(v.shape[0]):
            total += v[i] * a[i, j] * v[j]
    return total


@nb.njit(cache=CACHE)
def _normal_equations(jac, r, a, g):
    """a = JᵀJ and g = Jᵀr, in place."""
    rows, m = jac.shape
    a[:, :] = 0.0
    g[:] = 0.0
    for k in range(rows):
        for i in range(m):
            ji = jac[k, i]
            if ji == 0.0:
                continue
            g[i] += ji * r[k]
            for j in range(i, m):
                a[i, j] += ji * jac[k, j]
    for i in range(m):
        for j in range(i):
            a[i, j] = a[j, i]


@nb.njit(cache=CACHE, error_model="numpy")
def _sum_residuals(t, y, weights, theta, coefficients, width, prior_index, prior_mean, prior_weight, r, jac, want,
                   a, da, part, part_jac):
    """Weighted residuals of a sum of pulses (θ in blocks of (t0, ln F_max, ln T, x)) and the prior rows, and
    their Jacobian when ``want``."""
    n = t.shape[0]
    pulses = theta.shape[0] // 4
    for i in range(n):
        r[i] = 0.0
    if want:
        jac[:, :] = 0.0
    empty = np.empty((0, 4))
    for p in range(pulses):
        _theta_coefficients(theta[4 * p + 3], coefficients, width, a, da)
        _pulse(t, theta[4 * p], math.exp(theta[4 * p + 1]), math.exp(theta[4 * p + 2]), a, da, part,
               part_jac if want else empty)
        for i in range(n):
            r[i] += part[i]
            if want:
                for c in range(4):
                    jac[i, 4 * p + c] = part_jac[i, c] * weights[i]
    for i in range(n):
        r[i] = (r[i] - y[i]) * weights[i]
    for k in range(prior_index.shape[0]):
        r[n + k] = (theta[prior_index[k]] - prior_mean[k]) * prior_weight[k]
        if want:
            jac[n + k, prior_index[k]] = prior_weight[k]


@nb.njit(cache=CACHE, error_model="numpy")
def _lm_pulse_sum(t, y, weights, theta, coefficients, width, prior_index, prior_mean, prior_weight, max_iterations,
                  step_tolerance, x_max):
    """``levenberg_marquardt`` for a sum of pulses with Gaussian priors on some parameters, compiled: the same
    scaling, damping update, projection of each x on [0, x_max] and stopping rules.  Returns (θ, weighted
    Jacobian, weighted residuals, iterations, status): status 1 converged, 0 iteration limit, −1 the model
    does not depend on every parameter, −2 the normal equations are singular, −3 the start's residuals are not
    finite."""
    n, m = t.shape[0], theta.shape[0]
    rows = n + prior_index.shape[0]
    a_c, da_c = np.empty(THETA_NODES), np.empty(THETA_NODES)
    part, part_jac = np.empty(n), np.empty((n, 4))
    r, jac = np.empty(rows), np.empty((rows, m))
    r_trial, jac_unused = np.empty(rows), np.empty((rows, m))
    theta = theta.copy()
    _sum_residuals(t, y, weights, theta, coefficients, width, prior_index, prior_mean, prior_weight, r, jac, True,
                   a_c, da_c, part, part_jac)
    cost = _dot(r, r)
    if not math.isfinite(cost):  # where levenberg_marquardt's math.exp overflows
        return theta, jac, r, 0, -3
    lam, nu = 1e-3, 2.0
    step = np.empty(m)
    a, g = np.empty((m, m)), np.empty(m)
    trial = np.empty(m)
    a_n = np.empty((m, m))
    iterations = 0
    for iterations in range(1, max_iterations + 1):
        _normal_equations(jac, r, a, g)
        scale = np.sqrt(np.diag(a))
        for k in range(m):
            if not scale[k] > 0.0:
                return theta, jac, r, iterations, -1
        for i in range(m):
            for j in range(m):
                a_n[i, j] = a[i, j] / (scale[i] * scale[j])
        g_n = g / scale
        accepted = False
        cost_trial = cost
        while not accepted:
            damped = a_n.copy()
            for k in range(m):
                damped[k, k] += lam
                step[k] = -g_n[k]
            if not solve_small(damped, step, m):
                lam *= nu
                nu *= 2.0
                if lam > 1e16:
                    return theta, jac, r, iterations, -2
                continue
            for k in range(m):
                trial[k] = theta[k] + step[k] / scale[k]
                if k % 4 == 3:
                    trial[k] = min(max(trial[k], 0.0), x_max)
                step[k] = trial[k] - theta[k]
            _sum_residuals(t, y, weights, trial, coefficients, width, prior_index, prior_mean, prior_weight, r_trial,
                           jac_unused, False, a_c, da_c, part, part_jac)
            cost_trial = _dot(r_trial, r_trial)
            predicted = -(2.0 * _dot(g, step) + _quadratic(a, step))
            accepted, lam, nu, stop = _damping_update(cost, cost_trial, predicted, lam, nu)
            if stop:
                return theta, jac, r, iterations, 1
        decrease = cost - cost_trial
        theta[:] = trial
        _sum_residuals(t, y, weights, theta, coefficients, width, prior_index, prior_mean, prior_weight, r, jac, True,
                       a_c, da_c, part, part_jac)
        cost = _dot(r, r)
        # the step against the parameters' standard errors, as levenberg_marquardt: diag((A_n)^-1) by columns
        small = True
        column = np.empty(m)
        singular = False
        for k in range(m):
            column[:] = 0.0
            column[k] = 1.0
            if not solve_small(a_n.copy(), column, m):
                singular = True
                break
            sd = math.sqrt(abs(column[k]) * cost / max(rows - m, 1)) / scale[k]
            if not abs(step[k]) <= step_tolerance * sd:  # a NaN sd is not a small step
                small = False
        if singular:
            small = step_tolerance * 0.0 >= np.max(np.abs(step))
        if small or decrease <= 1e-12 * cost or cost == 0.0:
            return theta, jac, r, iterations, 1
    return theta, jac, r, iterations, 0


def fit_pulse_sum(t, y, weights, theta, prior_index=None, prior_mean=None, prior_weight=None,
                  max_iterations: int = MAX_ITERATIONS):
    """Least squares of a sum of pulses (θ in blocks of (t0, ln F_max, ln T, x)) to samples ``y`` [N] at times
    ``t`` [s] with ``weights`` (1/σ), and Gaussian priors (extra rows (θ[prior_index] − prior_mean) ·
    prior_weight): the compiled form of ``levenberg_marquardt`` with the pulse model.  Returns what it returns:
    (θ, weighted Jacobian, weighted residuals, iterations, converged, message)."""
    coefficients, width = shape_table()
    empty_i, empty_f = np.empty(0, np.int64), np.empty(0)
    theta, jac, r, iterations, status = _lm_pulse_sum(
        np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(y, dtype=float),
        np.ascontiguousarray(weights, dtype=float), np.asarray(theta, dtype=float),
        coefficients, width, empty_i if prior_index is None else np.asarray(prior_index, np.int64),
        empty_f if prior_mean is None else np.asarray(prior_mean, float),
        empty_f if prior_weight is None else np.asarray(prior_weight, float),
        int(max_iterations), STEP_TOLERANCE, X_MAX)
    converged = status == 1 and bool(np.all(np.isfinite(theta)))
    return theta, jac, r, iterations, converged, _LM_MESSAGES.get(status, "converged" if converged else
                                                                   "the fit left the range of double precision")


#: The messages of ``levenberg_marquardt`` for the compiled fit's status codes.
_LM_MESSAGES = {0: "the iteration limit was reached", -1: "the model does not depend on every parameter here",
                -2: "the normal equations are singular", -3: "the start's residuals are not finite"}
