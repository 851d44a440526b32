"""From a restitution coefficient to the damping of a contact law (vectorised).

``damping_factor(law, calibration, e, m, K, v0)`` returns the law's damping
factor (``ContactLaw.damping_factor``) for arrays of impacts.  The ``exact``
calibration inverts the restitution the law really produces: in closed form
for the power-law family (``engine.powerlaw.exact_x``), by the published
formula where that is exact (unclamped Kelvin–Voigt and Tsuji), and otherwise
from a table of the inverse, ``group_table``.

Exact calibration of the laws without a first integral
------------------------------------------------------
Their restitution depends on one dimensionless damping group g alone
(``ForceFamily.to_group``: ζ, α or b), so the inverse g(e) is tabulated once
per law and evaluated per row, which costs far less than the impact itself.
With s = -ln e, the table holds y = ln(g/s) as a function of w = s + ln s in
piecewise Chebyshev series (``TABLE_PANELS`` panels of equal width in w,
degree ``TABLE_DEGREE``), from s = ``TABLE_S_MIN`` (e = 1 - 1e-8) to
s = -ln ``TABLE_E_MIN``.  These variables make the function smooth at both
ends: as e → 1, g ≈ s/C1, y tends to a constant and w ≈ ln s spreads the
panels geometrically; as e → 0, e falls as a power of g, y grows like s
and w ≈ s spreads them evenly.  Below ``TABLE_S_MIN`` y is held at its end
value (g/s changes by ~1e-8 there, e by ~1e-16).

The nodes are found by the compiled integrator at ``TABLE_RTOL`` on a
reference impact m = K = v0 = 1 (the integrator runs in units of the impact,
so every impact with the same g is that one), by secant steps in ln g
within brackets from a coarse forward table; the table's error is measured
when it is built, as the restitution the integrator gives for the tabulated
g between the nodes against the target (``group_table``): ≤ 2.4e-12.

Reach: for these four laws e(g) falls monotonically from 1 at g = 0 towards
0 as g → ∞, with power-law tails (clamped Kelvin–Voigt e ≈ 1/(4ζ²), clamped
Tsuji e ≈ 5/(4α²), clamped Kuwabara–Kono e ~ b^(-5/3), unclamped
Kuwabara–Kono e ≈ 5.16 b^(-5)): every e in (0, 1] is reachable, none has a
lowest e above 0.  The table stops at ``TABLE_E_MIN`` = 1e-4, where the
integrator at its default rtol (1e-10), whose error on e grows as e falls
(≤ 3e-10 for e ≥ 0.01, ≤ 4e-9 down to 1e-4), would no longer show the
calibration's accuracy: targets below give NaN.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.codes import RESTITUTION
from fruitimpact.engine.jitcache import CACHE
from fruitimpact.engine.powerlaw import exact_x

#: Exact-calibration table of the laws without a first integral: its range in
#: e, the panels and degree of its Chebyshev series, the integrator's rtol.
TABLE_E_MIN = 1e-4
TABLE_S_MIN = 1e-8
TABLE_PANELS = 24
TABLE_DEGREE = 16
TABLE_RTOL = 1e-13

#: Smallest positive normal double: below it a number has lost precision.
_TINY = np.finfo(float).tiny

def law_params(family, stiffness, damping_factor, exponent=1.5):
    """Parameter matrix for the compiled force of ``family`` (rows of impacts): see
    ``physics.families.ForceFamily.params``."""
    from fruitimpact.physics.families import FAMILIES

    return FAMILIES[family].params(stiffness, damping_factor, exponent)


def achieved_restitution(law, damping_factor, mass, stiffness, velocity):
    """Restitution the law really produces with this damping (compiled integrator
    for non-power-law families)."""
    from fruitimpact.engine.adaptive import DEFAULT_RTOL

    return _restitution(law, damping_factor, mass, stiffness, velocity, DEFAULT_RTOL)


def _restitution(law, damping_factor, mass, stiffness, velocity, rtol):
    """``achieved_restitution`` with the integrator at ``rtol``."""
    from fruitimpact.engine.adaptive import adaptive_characteristics

    mass, stiffness, velocity, damping_factor = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, dtype=float)) for a in (mass, stiffness, velocity, damping_factor)))
    law_k = law.linear_stiffness(mass, stiffness, velocity)
    params = law_params(law.family, law_k, damping_factor)
    out = adaptive_characteristics(np.full(mass.shape, law.family), params, np.full(mass.shape, law.clamp),
                                   mass, velocity, np.ones_like(mass), rtol)
    return out[:, RESTITUTION]


# ---------------------------------------------------------------------------
# The table of the inverse g(e) of each law without a first integral
# ---------------------------------------------------------------------------
_GROUP_TABLES: dict[str, tuple[np.ndarray, float]] = {}
_S_MAX = -math.log(TABLE_E_MIN)
_W_MIN = TABLE_S_MIN + math.log(TABLE_S_MIN)
_W_WIDTH = (_S_MAX + math.log(_S_MAX) - _W_MIN) / TABLE_PANELS


def _s_of_w(w):
    """s with s + ln s = w (array): Newton in ln s from the right of the root, where
    it converges monotonically (e^t + t is convex)."""
    t = np.where(w <= 1.0, w, np.log(np.maximum(w, 1.0)))
    for _ in range(60):
        step = (np.exp(t) + t - w) / (np.exp(t) + 1.0)
        t = t - step
        if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(t))):
            break
    return np.exp(t)


def _reference_s(law, group, rtol=TABLE_RTOL):
    """s = -ln e of ``law`` at dimensionless damping ``group`` (array), reference
    impact m = K = v0 = 1; +inf where the integration fails."""
    one = np.ones_like(group)
    e = _restitution(law, law.from_group(group, one, one, one), one, one, one, rtol)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(-np.log(e), nan=np.inf)


def _reference_groups(law, s):
    """g with s(g) = ``s`` (array, in [TABLE_S_MIN, -ln TABLE_E_MIN]) on the reference
    impact: a start interpolated in a forward table of s on a geometric grid of g, which
    also brackets each root, then secant steps in ln g (bisection where a step leaves
    the bracket), each over the rows not yet converged, until s is within 1e-13 of
    itself (at most 1e-13: s is ln e, the integrator's own accuracy at TABLE_RTOL is
    ~1e-12) or 4e-16 (2 ulp of e near 1)."""
    high = 1.0
    while _reference_s(law, np.array([high]))[0] <= _S_MAX:
        high *= 4.0
    grid = np.log(np.geomspace(0.1 * TABLE_S_MIN, high, 200))
    s_grid = _reference_s(law, np.exp(grid))
    index = np.clip(np.searchsorted(s_grid, s), 1, len(grid) - 1)
    lo, hi = grid[index - 1], grid[index]
    old = np.interp(s, s_grid, grid)
    f_old = _reference_s(law, np.exp(old)) - s
    u = old - f_old * (hi - lo) / (s_grid[index] - s_grid[index - 1])  # Newton step, the grid's slope
    active = np.flatnonzero(np.abs(f_old) > 1e-13 * np.minimum(s, 1.0) + 4e-16)
    u[f_old == 0.0] = old[f_old == 0.0]
    for _ in range(60):
        a = active
        u[a] = np.where((u[a] > lo[a]) & (u[a] < hi[a]), u[a], 0.5 * (lo[a] + hi[a]))
        f = _reference_s(law, np.exp(u[a])) - s[a]
        hi[a] = np.where(f > 0, u[a], hi[a])  # s above target: the root is below u
        lo[a] = np.where(f > 0, lo[a], u[a])
        with np.errstate(divide="ignore", invalid="ignore"):
            step = f * (u[a] - old[a]) / (f - f_old[a])
        old[a], f_old[a] = u[a], f
        u[a] = u[a] - np.nan_to_num(step, posinf=0.0, neginf=0.0)
        done = ((np.abs(f) <= 1e-13 * np.minimum(s[a], 1.0) + 4e-16)
                | (hi[a] - lo[a] <= 1e-15 * np.maximum(1.0, np.abs(u[a]))))
        u[a[done]] = old[a[done]]
        active = a[~done]
        if active.size == 0:
            break
    return np.exp(u)


@nb.njit(cache=CACHE, error_model="numpy")
def _table_groups(e, coefficients, w_min, width, e_min, out):
    """g(e) from the table (Clenshaw); NaN for e outside [TABLE_E_MIN, 1] or NaN."""
    panels = coefficients.shape[0]
    degree = coefficients.shape[1]
    for i in range(e.shape[0]):
        if e[i] == 1.0:  # undamped
            out[i] = 0.0
            continue
        if not (e[i] >= e_min and e[i] < 1.0):
            out[i] = math.nan
            continue
        s = -math.log(e[i])
        t = (s + math.log(s) - w_min) / width
        panel = min(int(t), panels - 1) if t > 0.0 else 0
        x = 2.0 * (t - panel) - 1.0 if t > 0.0 else -1.0  # below TABLE_S_MIN: the end value
        b1 = 0.0
        b2 = 0.0
        for k in range(degree - 1, 0, -1):
            b0 = 2.0 * x * b1 - b2 + coefficients[panel, k]
            b2 = b1
            b1 = b0
        out[i] = s * math.exp(x * b1 - b2 + coefficients[panel, 0])


def _evaluate(coefficients, e):
    e = np.ascontiguousarray(np.atleast_1d(np.asarray(e, dtype=float)).ravel())
    out = np.empty_like(e)
    _table_groups(e, coefficients, _W_MIN, _W_WIDTH, TABLE_E_MIN, out)
    return out


def group_table(law) -> tuple[np.ndarray, float]:
    """(Chebyshev coefficients [panel, k] of y = ln(g/s) in w = s + ln s, largest relative
    error of the restitution they give, measured between the nodes) for ``law``, a law
    without a first integral; built on first use (a few thousand integrations, tens of
    ms) and kept.  The error is |e_integrator(g_table(e)) / e - 1| at the panel edges
    and midway between all nodes, the integrator at TABLE_RTOL on the reference impact."""
    table = _GROUP_TABLES.get(law.name)
    if table is not None:
        return table
    theta = np.pi * (np.arange(TABLE_DEGREE) + 0.5) / TABLE_DEGREE
    nodes = np.cos(theta)  # Chebyshev points of the first kind on [-1, 1]
    w = _W_MIN + _W_WIDTH * (np.arange(TABLE_PANELS)[:, None] + 0.5 * (1.0 + nodes[None, :]))
    s = _s_of_w(w)
    y = np.log(_reference_groups(law, s.ravel()).reshape(s.shape) / s)  # (panel, node)
    coefficients = 2.0 / TABLE_DEGREE * y @ np.cos(np.outer(theta, np.arange(TABLE_DEGREE)))
    coefficients[:, 0] *= 0.5
    # check between the nodes: every panel edge and the midpoints of the node gaps
    probe_t = np.concatenate([[-1.0], 0.5 * (nodes[1:] + nodes[:-1])[::-1], [1.0]])
    probe_w = _W_MIN + _W_WIDTH * (np.arange(TABLE_PANELS)[:, None] + 0.5 * (1.0 + probe_t[None, :]))
    target = np.maximum(np.exp(-_s_of_w(probe_w.ravel())), TABLE_E_MIN)  # the last edge is TABLE_E_MIN
    achieved = np.exp(-_reference_s(law, _evaluate(coefficients, target)))
    error = float(np.max(np.abs(achieved / target - 1.0)))
    table = _GROUP_TABLES[law.name] = (coefficients, error)
    return table


def exact_groups(law, restitution):
    """The dimensionless damping group g (``ForceFamily.to_group``) at which ``law``, a
    law without a first integral, gives restitution e (array): 0 at e = 1, NaN for e
    outside [TABLE_E_MIN, 1] (see the module's note on reach) or NaN."""
    return _evaluate(group_table(law)[0], restitution).reshape(np.shape(restitution))


def damping_factor(law, calibration: str, restitution, mass, stiffness, velocity):
    """Damping factor of ``law`` for restitution e (arrays broadcast).

    Parameters
    ----------
    law : models.DampingLaw
    calibration : str
        ``paper`` (the law's published formula) or ``exact``.
    restitution : array_like
        Target e in (0, 1].
    mass, stiffness, velocity : array_like
        m [kg], Hertz contact stiffness k_c [N/m^1.5], v0 [m/s].

    Returns
    -------
    ndarray
        The damping factor (``ContactLaw.damping_factor``), 0 for e = 1 or an undamped
        law.  NaN, for the caller to report, never an exception: where the factor
        under- or overflows (not a finite normal number, e.g. c = x/v0 at v0 = 1e-310
        m/s, or the matched linear stiffness of Kelvin–Voigt at 1e-160 m/s), and with
        ``exact`` for the laws without a first integral where e < TABLE_E_MIN = 1e-4
        (no law here has a lowest reachable e above 0, but the table stops there: see
        the module's note) or e is not in (0, 1].  A factor that is representable is
        exact even where the impact's own scales are not (V = 1e-160 m/s: m V² is
        subnormal); the integrators return NaN for those impacts.
    """
    e, m, k, v = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (restitution, mass, stiffness, velocity)))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        if law.undamped:
            result = np.zeros_like(e)
        elif calibration == "paper" or law.exact_by_construction:
            result = np.asarray(law.published_damping_factor(e, m, k, v), dtype=float) * np.ones_like(e)
        elif law.force_family.first_integral:
            result = exact_x(e) / v
        else:
            result = np.asarray(law.from_group(exact_groups(law, e), m, k, v), dtype=float)
        size = np.abs(result)
        representable = (size >= _TINY) & (size < np.inf) | (result == 0) & ((e == 1) | law.undamped)
    return np.where(representable, result, np.nan)
