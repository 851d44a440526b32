"""The pulse shape H(σ; x) of the simulator's Hunt–Crossley law, tabulated, and its model on sample times.

The force of an impact with the law F = K δ^1.5 (1 + c δ̇) (``engine.powerlaw``) is F_max · H((t − t0)/T; x)
inside [t0, t0 + T], with one shape H for each x = c·V, in units of its own peak and duration (σ ∈ [0, 1],
max H = 1).  ``PulseModel`` gives F(t; θ), θ = (t0, ln F_max, ln T, x), and its Jacobian on fixed sample
times, for the fits of one pulse (``signals.fit``) and of sums of pulses (``signals.leastsquares``,
``signals.split``).

The exact engine's ``powerlaw_curves`` costs ~6 µs per sample (one Newton inversion of a
Gauss–Jacobi time integral each), i.e. ~2 ms for a 300-sample window and twice that with a Jacobian
in x: too slow for a 10 ms budget over several iterations.  So H is tabulated once per process
(~0.25 s, on first use) from the exact engine: in the angle θ with σ = (1 − cos θ)/2, H is analytic
on [0, π] (the τ^1.5 onset and (T − τ)^1.5 separation become smooth in √σ and √(1 − σ)), so a
Chebyshev series of ``THETA_NODES`` terms in θ represents it; its coefficients are in turn piecewise
Chebyshev series in ln(1 + x).  ``shape_table_error`` measures the table against the exact engine
at random (σ, x): at most 1e-5 of F_max over x ∈ [0, X_MAX] (the worst near X_MAX, e ≈ 0.1), 1e-7 for
x ≤ 4 (e ≥ 0.24: every fruit on a plate) and ~2e-9 for x ≤ 1.5 (e ≥ 0.49), three to six orders below a
1 % noise.  (64 terms gave 1e-7 over the whole range and cost a third more per fit iteration, the joint fits
of overlapping pulses being the tail of a stream's latency.)  The reported quantities and ``model_curve`` use the exact
engine, not the table.  The recurrences of H and its derivatives run term by term over all samples of a
pulse at once (independent samples: vector instructions).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.codes import CONTACT_DURATION, PEAK_FORCE
from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.powerlaw import powerlaw_characteristics, powerlaw_curves_batch

__all__ = ["PulseModel", "STIFFNESS_SCALE", "THETA_NODES", "X_MAX", "shape_table", "shape_table_error", "table_shape"]

#: Largest x = c·V the fits explore (e ≈ 0.100); the projection keeps x in [0, X_MAX].
X_MAX = 10.0
#: Chebyshev terms of H in the angle θ (error ≤ 1e-5 of the peak at x near X_MAX, ≤ 1e-7 for x ≤ 4).
THETA_NODES = 48
#: Panels in ln(1 + x) and Chebyshev terms per panel for the x dependence of the θ coefficients.
X_PANELS = 10
X_DEGREE = 12
#: K of the dimensionless pulse, (n + 1)/2: with m = V = 1 and K = 1.25 the Hertz scales δ_H = t_H = 1.
STIFFNESS_SCALE = 1.25
_TABLE: list = []


def _chebyshev_transform(values: np.ndarray, axis: int) -> np.ndarray:
    """Chebyshev coefficients from values at the first-kind points cos(π (i + ½)/N), along ``axis``."""
    n = values.shape[axis]
    i = np.arange(n)
    basis = np.cos(np.pi * np.outer(np.arange(n), i + 0.5) / n) * (2.0 / n)  # [k, i]
    basis[0] *= 0.5
    return np.moveaxis(np.tensordot(basis, np.moveaxis(values, axis, 0), axes=(1, 0)), 0, axis)


def _exact_shape(x: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """H(σ; x) from the exact engine, one row per x: F/F_max at t = σ T(x)."""
    x = np.asarray(x, dtype=float)
    ones = np.ones_like(x)
    chars = powerlaw_characteristics(ones, STIFFNESS_SCALE * ones, x, ones, ones)
    times = np.asarray(sigma, dtype=float) * chars[:, CONTACT_DURATION][:, None]
    force = powerlaw_curves_batch(ones, STIFFNESS_SCALE * ones, x, ones, times)[2]
    return force / chars[:, PEAK_FORCE][:, None]


def shape_table() -> tuple[np.ndarray, float]:
    """(coefficients [panel, k (x), j (θ)], panel width in ln(1 + x)); built once per process."""
    if _TABLE:
        return _TABLE[0]
    width = math.log1p(X_MAX) / X_PANELS
    x_nodes = np.cos(np.pi * (np.arange(X_DEGREE) + 0.5) / X_DEGREE)
    u = width * (np.arange(X_PANELS)[:, None] + 0.5 * (1.0 + x_nodes[None, :]))  # [panel, k]
    theta_nodes = np.cos(np.pi * (np.arange(THETA_NODES) + 0.5) / THETA_NODES)
    sigma = 0.5 * (1.0 - np.cos(0.5 * np.pi * (theta_nodes + 1.0)))
    values = _exact_shape(np.expm1(u).ravel(), np.broadcast_to(sigma, (u.size, THETA_NODES)))
    values = values.reshape(X_PANELS, X_DEGREE, THETA_NODES)
    coefficients = _chebyshev_transform(_chebyshev_transform(values, 2), 1)
    _TABLE.append((np.ascontiguousarray(coefficients), width))
    return _TABLE[0]


@nb.njit(cache=CACHE, error_model="numpy")
def _theta_coefficients(x, coefficients, width, a, da):
    """Chebyshev coefficients in θ of H(·; x) into ``a`` and their x derivatives into ``da``."""
    v = math.log1p(x)
    panel = min(max(int(v / width), 0), coefficients.shape[0] - 1)
    s = 2.0 * (v / width - panel) - 1.0
    scale = 2.0 / width / (1.0 + x)  # d s/dx
    for j in range(coefficients.shape[2]):
        a[j] = 0.0
        da[j] = 0.0
    t_prev, t_cur = 1.0, s  # T_k(s)
    d_prev, d_cur = 0.0, 1.0  # T_k'(s)
    for k in range(coefficients.shape[1]):
        if k == 0:
            t_k, d_k = 1.0, 0.0
        elif k == 1:
            t_k, d_k = s, 1.0
        else:
            t_k = 2.0 * s * t_cur - t_prev
            d_k = 2.0 * t_cur + 2.0 * s * d_cur - d_prev
            t_prev, t_cur = t_cur, t_k
            d_prev, d_cur = d_cur, d_k
        for j in range(coefficients.shape[2]):
            a[j] += coefficients[panel, k, j] * t_k
            da[j] += coefficients[panel, k, j] * d_k * scale


@nb.njit(cache=CACHE, error_model="numpy")
def _pulse(t, t0, peak, duration, a, da, model, jacobian):
    """F = peak · H((t − t0)/duration) at each t (ascending) and, if ``jacobian`` has rows, ∂F/∂(t0, ln peak,
    ln duration, x) there (H from the θ coefficients ``a``, ∂H/∂x from ``da``).  The Chebyshev recurrences run
    term by term over all samples of the pulse at once (independent samples: vector instructions), not sample
    by sample (a chain of dependent operations)."""
    want = jacobian.shape[0] > 0
    n_terms = a.shape[0]
    n = t.shape[0]
    lo, hi = n, 0
    for i in range(n):
        sigma = (t[i] - t0) / duration
        if 0.0 < sigma < 1.0:
            lo = min(lo, i)
            hi = i + 1
        else:
            model[i] = 0.0
            if want:
                for col in range(4):
                    jacobian[i, col] = 0.0
    if hi <= lo:
        return
    m = hi - lo
    sig = np.empty(m)
    s = np.empty(m)
    for k in range(m):
        sig[k] = (t[lo + k] - t0) / duration
        s[k] = 2.0 * math.acos(1.0 - 2.0 * sig[k]) / math.pi - 1.0
    if not want:  # the value alone: Clenshaw's recurrence, a third of the work
        b1 = np.zeros(m)
        b2 = np.zeros(m)
        for j in range(n_terms - 1, 0, -1):
            aj = a[j]
            for k in range(m):
                value = 2.0 * s[k] * b1[k] - b2[k] + aj
                b2[k] = b1[k]
                b1[k] = value
        for k in range(m):
            model[lo + k] = peak * (s[k] * b1[k] - b2[k] + a[0])
        return
    h = np.empty(m)
    hx = np.empty(m)
    hs = np.empty(m)
    t_prev, t_cur = np.ones(m), s.copy()
    d_prev, d_cur = np.zeros(m), np.ones(m)
    for k in range(m):
        h[k] = a[0] + a[1] * s[k]
        hx[k] = da[0] + da[1] * s[k]
        hs[k] = a[1]
    for j in range(2, n_terms):
        aj, daj = a[j], da[j]
        for k in range(m):
            t_j = 2.0 * s[k] * t_cur[k] - t_prev[k]
            d_j = 2.0 * t_cur[k] + 2.0 * s[k] * d_cur[k] - d_prev[k]
            h[k] += aj * t_j
            hx[k] += daj * t_j
            hs[k] += aj * d_j
            t_prev[k], t_cur[k] = t_cur[k], t_j
            d_prev[k], d_cur[k] = d_cur[k], d_j
    for k in range(m):
        i = lo + k
        model[i] = peak * h[k]
        # dH/dσ = dH/ds · (2/π) · dθ/dσ,  dθ/dσ = 1/√(σ(1 − σ))
        h_sigma = hs[k] * (2.0 / math.pi) / math.sqrt(sig[k] * (1.0 - sig[k]))
        jacobian[i, 0] = -peak * h_sigma / duration
        jacobian[i, 1] = model[i]
        jacobian[i, 2] = -peak * h_sigma * sig[k]
        jacobian[i, 3] = peak * hx[k]


class PulseModel:
    """The tabulated pulse F(t; θ) on fixed sample times, plus an optional baseline polynomial
    b0 + b1 u (u = t scaled to [-1, 1] over the window) in θ[4:], with its Jacobian."""

    def __init__(self, t: np.ndarray, baseline_terms: int = 0):
        self.coefficients, self.width = shape_table()
        self.t = t
        self.terms = baseline_terms
        self.n_params = 4 + baseline_terms
        span = t[-1] - t[0] if t.size > 1 else 1.0
        u = (2.0 * (t - t[0]) / span - 1.0) if t.size > 1 else np.zeros_like(t)
        self.basis = np.column_stack([u ** k for k in range(baseline_terms)]) if baseline_terms \
            else np.empty((t.size, 0))
        self.a = np.empty(THETA_NODES)
        self.da = np.empty(THETA_NODES)
        self.model = np.empty_like(t)
        self.jacobian = np.empty((t.shape[0], 4))
        self._no_jacobian = np.empty((0, 4))

    def pulse(self, theta, jacobian: bool = False):
        t0, log_peak, log_duration, x = theta[:4]
        _theta_coefficients(x, self.coefficients, self.width, self.a, self.da)
        _pulse(self.t, t0, math.exp(log_peak), math.exp(log_duration), self.a, self.da, self.model,
               self.jacobian if jacobian else self._no_jacobian)
        return (self.model, self.jacobian) if jacobian else self.model

    def __call__(self, theta, jacobian: bool = False):
        """F(t; θ) (a new array) and, if asked, the Jacobian ∂F/∂θ (a new array)."""
        out = self.pulse(theta, jacobian)
        model = out[0] if jacobian else out
        model = model + self.basis @ np.asarray(theta[4:], dtype=float) if self.terms else model.copy()
        if not jacobian:
            return model
        return model, np.hstack([out[1], self.basis]) if self.terms else out[1].copy()


def table_shape(x: float, sigma: np.ndarray) -> np.ndarray:
    model = PulseModel(np.ascontiguousarray(sigma, dtype=float))
    return model((0.0, 0.0, 0.0, x))


def shape_table_error(samples: int = 400, seed: int = 1, x_max: float = X_MAX) -> float:
    """Largest |H_table − H_exact| (in units of the peak) at ``samples`` random (σ, x), x ∈ [0, x_max]."""
    rng = np.random.default_rng(seed)
    x = np.expm1(rng.uniform(0.0, math.log1p(x_max), samples))
    sigma = rng.uniform(0.0, 1.0, (samples, 64))
    exact = _exact_shape(x, sigma)
    table = np.array([table_shape(x[i], sigma[i]) for i in range(samples)])
    return float(np.max(np.abs(table - exact)))
