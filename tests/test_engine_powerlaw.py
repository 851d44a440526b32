"""The exact power-law engine against independent references.

References: closed forms of the undamped Hertz impact (Johnson 1985, §11.4),
the first integral of the Hunt–Crossley law with the Lambert-W form of e
(contact-models.md, re-derived in docs/physics.md), a tight SciPy DOP853
integration (tests/reference.py), energy conservation, and SciPy's
Gauss–Jacobi rules.
"""

import math

import numpy as np
import pytest
from reference import reference_powerlaw, state_at
from scipy.special import beta, lambertw, roots_jacobi

from fruitimpact.engine import powerlaw
from fruitimpact.engine.powerlaw import (CHARACTERISTIC_COLUMNS, exact_restitution, exact_x,
                                         powerlaw_characteristics, powerlaw_curves)
from fruitimpact.engine.quadrature import gauss_jacobi

COL = {name: i for i, name in enumerate(CHARACTERISTIC_COLUMNS)}
APPLE = dict(mass=0.115, stiffness=0.8355e6, velocity=1.0, radius=0.0325)


def characteristics(mass, stiffness, damping_factor, velocity, radius=0.0325):
    row = powerlaw_characteristics(mass, stiffness, damping_factor, velocity, radius)[0]
    return {name: row[i] for name, i in COL.items()}


@pytest.mark.parametrize("n_nodes,a,b", [(10, -0.6, 0.0), (48, 0.0, -0.6), (7, 0.3, -0.5)])
def test_gauss_jacobi_matches_scipy(n_nodes, a, b):
    # Golub–Welsch vs SciPy's own construction: nodes to rounding, weights to 1e-11
    # (the eigenvector route loses a few digits on the smallest weights).
    nodes, weights = gauss_jacobi(n_nodes, a, b)
    ref_nodes, ref_weights = roots_jacobi(n_nodes, a, b)
    np.testing.assert_allclose(nodes, ref_nodes, atol=1e-14)
    np.testing.assert_allclose(weights, ref_weights, rtol=1e-10, atol=1e-12 * ref_weights.max())


@pytest.mark.parametrize("mass,stiffness,velocity", [(0.115, 0.8355e6, 1.0), (0.3, 2e6, 0.3), (0.05, 3e5, 4.0)])
def test_undamped_hertz_closed_forms(mass, stiffness, velocity):
    # Hertz impact: δ_max = (5 m v²/(4K))^(2/5), T = (4/5) B(1/2, 2/5) δ_max/v0, t_c = T/2,
    # F_max = K δ_max^1.5, e = 1 (Johnson 1985 §11.4).  The engine integrates exactly
    # (Gauss–Jacobi), so agreement is to rounding: 1e-12.
    got = characteristics(mass, stiffness, 0.0, velocity)
    d_max = (5 * mass * velocity ** 2 / (4 * stiffness)) ** 0.4
    duration = 0.8 * beta(0.5, 0.4) * d_max / velocity
    assert got["max_deflection"] == pytest.approx(d_max, rel=1e-12)
    assert got["contact_duration"] == pytest.approx(duration, rel=1e-12)
    assert got["time_to_peak"] == pytest.approx(duration / 2, rel=1e-12)
    assert got["peak_force"] == pytest.approx(stiffness * d_max ** 1.5, rel=1e-12)
    assert got["restitution"] == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("x", [0.05, 0.3, 1.0, 2.5, 8.0])
def test_restitution_matches_lambert_w(x):
    # e = [1 + W0(-(1+x) e^-(1+x))]/x; well conditioned for x ≳ 0.05 (near the branch
    # point W0 loses digits as sqrt(eps)/x), hence 1e-9 there.
    closed = (1.0 + lambertw(-(1 + x) * math.exp(-(1 + x))).real) / x
    assert exact_restitution(x) == pytest.approx(closed, rel=1e-9)


def _restitution_decimal(x: float) -> float:
    """e from (1 + x) = (1 - e x) exp((1 + e) x) by bisection in 50-digit decimal
    arithmetic: an independent reference free of the cancellations of doubles."""
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 50
        xd = Decimal(x)
        lhs = (1 + xd).ln()

        def g(e):  # decreasing in e on (0, 1/x), positive below the root
            return (1 - e * xd).ln() + (1 + e) * xd - lhs

        lo, hi = Decimal(0), min(Decimal(1), (1 / xd) * (1 - Decimal(10) ** -40))
        for _ in range(170):
            mid = (lo + hi) / 2
            if g(mid) > 0:
                lo = mid
            else:
                hi = mid
        return float((lo + hi) / 2)


@pytest.mark.parametrize("x", [1e-6, 1e-3, 0.01, 0.3, 2.0, 10.0, 40.0])
def test_restitution_against_high_precision(x):
    # 50-digit reference; doubles allow ~1e-15 relative (the engine's Newton stops at 4e-16).
    assert exact_restitution(x) == pytest.approx(_restitution_decimal(x), rel=2e-15)
    if x <= 1e-3:
        assert exact_restitution(x) == pytest.approx(1 - 2 * x / 3, abs=x * x)  # Hunt–Crossley limit


@pytest.mark.parametrize("e", [0.05, 0.2, 0.5, 0.577, 0.9, 0.999])
def test_exact_inverse(e):
    # x(e) inverts e(x) to rounding (both are root finds on the same relation).
    assert exact_restitution(exact_x(e)) == pytest.approx(e, rel=1e-13)


@pytest.mark.parametrize("damping_factor", [0.05, 0.63, 1.07, 3.0, 12.0])
def test_max_deflection_closed_form(damping_factor):
    # δ_max = [(n+1) m (c v0 - ln(1 + c v0)) / (K c²)]^(1/(n+1)) with n = 3/2, written
    # out with plain logs (no cancellation at these c v0).
    m, k, v = APPLE["mass"], APPLE["stiffness"], APPLE["velocity"]
    x = damping_factor * v
    closed = (2.5 * m * (x - math.log(1 + x)) / (k * damping_factor ** 2)) ** 0.4
    assert characteristics(m, k, damping_factor, v)["max_deflection"] == pytest.approx(closed, rel=1e-12)


@pytest.mark.parametrize(
    "mass,stiffness,damping_factor,velocity",
    [(0.115, 0.8355e6, 0.6345, 1.0), (0.115, 0.892e6, 0.75, 1.0), (0.115, 1.672e6, 0.969, 0.65),
     (0.2, 5e5, 3.0, 2.0), (0.05, 3e6, 0.1, 0.3), (0.115, 0.8355e6, 20.0, 1.0)],
)
def test_against_tight_integration(mass, stiffness, damping_factor, velocity):
    # SciPy DOP853 at rtol 1e-12 with event location: the reference is good to ~1e-10;
    # 1e-8 leaves margin for the peak time, located by a root of dF/dt on the dense output.
    got = characteristics(mass, stiffness, damping_factor, velocity)
    ref = reference_powerlaw(mass, stiffness, damping_factor, velocity)
    for key in ("peak_force", "time_to_peak", "contact_duration", "max_deflection",
                "time_to_max_deflection", "restitution"):
        assert got[key] == pytest.approx(ref[key], rel=1e-8), key


@pytest.mark.parametrize("damping_factor", [0.3, 1.07, 4.0])
def test_energy_balance(damping_factor):
    # The work of the damping force c K δ^n δ̇² integrated alongside the motion equals
    # the kinetic energy lost, ½ m v0² (1 - e²).  Tolerance 1e-8: the reference integration.
    m, k, v = APPLE["mass"], APPLE["stiffness"], APPLE["velocity"]
    got = characteristics(m, k, damping_factor, v)
    ref = reference_powerlaw(m, k, damping_factor, v)
    assert got["absorbed_energy"] == pytest.approx(ref["damping_work"], rel=1e-8)
    assert got["absorbed_energy"] == pytest.approx(0.5 * m * v * v * (1 - got["restitution"] ** 2), rel=1e-14)


def test_curves_match_tight_integration():
    # δ(t), δ̇(t) from inverting the exact t(ζ) vs the dense output of the reference
    # (rtol 1e-12): 1e-9 of the scale δ_max, v0.
    m, k, c, v = APPLE["mass"], APPLE["stiffness"], 1.0678, APPLE["velocity"]
    ref = reference_powerlaw(m, k, c, v)
    times = np.linspace(0.0, ref["contact_duration"], 401)
    deflection, rate, force, duration = powerlaw_curves(m, k, c, v, times)
    ref_d, ref_v = state_at(ref["solution"], times)
    assert duration == pytest.approx(ref["contact_duration"], rel=1e-10)
    np.testing.assert_allclose(deflection, ref_d, atol=1e-9 * ref["max_deflection"])
    np.testing.assert_allclose(rate, ref_v, atol=1e-9 * v)
    assert np.all(force >= 0.0)
    assert force.max() <= ref["peak_force"] * (1 + 1e-12)


def test_quadrature_converged_over_damping_range():
    # Going from the engine's Gauss–Jacobi rule to 96 nodes changes no characteristic by
    # more than 1e-12 for restitution down to 0.05: the rule in use is converged.
    e = np.array([0.05, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 1.0])
    c = exact_x(e)
    args = (np.full_like(c, 0.115), np.full_like(c, 0.8355e6), 1.5, c, np.ones_like(c), np.full_like(c, 0.0325))
    out_a = np.empty((len(e), len(CHARACTERISTIC_COLUMNS)))
    out_b = np.empty_like(out_a)
    powerlaw._characteristics_kernel_serial(*args, *powerlaw._rules(1.5, powerlaw.QUADRATURE_NODES), out_a)
    powerlaw._characteristics_kernel_serial(*args, *powerlaw._rules(1.5, 96), out_b)
    np.testing.assert_allclose(out_a, out_b, rtol=1e-12)


def test_batch_equals_rows_and_parallel_equals_serial():
    rng = np.random.default_rng(3)
    rows = 5000
    m = rng.uniform(0.05, 0.4, rows)
    k = rng.uniform(2e5, 5e6, rows)
    c = rng.uniform(0.0, 5.0, rows)
    v = rng.uniform(0.2, 5.0, rows)
    parallel = powerlaw_characteristics(m, k, c, v, 0.03, parallel=True)
    serial = powerlaw_characteristics(m, k, c, v, 0.03, parallel=False)
    np.testing.assert_array_equal(parallel, serial)
    one = powerlaw_characteristics(m[17], k[17], c[17], v[17], 0.03)[0]
    np.testing.assert_array_equal(one, serial[17])


def test_tabulated_batch_path_equals_exact_kernel():
    # The batch path interpolates the dimensionless characteristics (functions of
    # x = c v0 only) from the exact kernel; it must agree with it to 1e-12 over the
    # table's whole range, at x = 0 and beyond the table (where it falls back).
    rng = np.random.default_rng(11)
    rows = 30000
    m = rng.uniform(0.02, 1.0, rows)
    k = rng.uniform(1e5, 1e7, rows)
    v = rng.uniform(0.1, 8.0, rows)
    x = np.concatenate([[0.0, 1e-9, powerlaw.TABLE_X_MAX, powerlaw.TABLE_X_MAX * 1.5],
                        np.expm1(rng.uniform(0, np.log1p(powerlaw.TABLE_X_MAX), rows - 4))])
    c = x / v
    tab = powerlaw_characteristics(m, k, c, v, 0.03, tabulated=True)
    exact = powerlaw_characteristics(m, k, c, v, 0.03, tabulated=False)
    energy = COL["absorbed_energy"]
    others = [j for j in range(tab.shape[1]) if j != energy]
    np.testing.assert_allclose(tab[:, others], exact[:, others], rtol=1e-12)
    # ½ m v0² (1 - e²) cancels as e → 1 in both paths alike: compare on the scale ½ m v0²
    np.testing.assert_array_less(np.abs(tab[:, energy] - exact[:, energy]), 1e-14 * 0.5 * m * v * v)
    assert powerlaw.powerlaw_table(1.5)[1] < 1e-12


def test_a_uniform_column_gets_the_root_of_its_value_on_every_row():
    """A column of one restitution (a table's default or a fruit's value) is solved once and filled
    (``powerlaw._uniform``): every row equals the root of that value solved alone, and e(x) of it returns the
    value (the exact relation, to 1e-12); a column that differs in one row is solved row by row."""
    rows = powerlaw.PARALLEL_MIN_ROWS * 3
    e = np.full(rows, 0.57)
    x = exact_x(e)
    assert np.all(x == exact_x(np.array([0.57]))[0])
    assert np.allclose(exact_restitution(x), 0.57, rtol=0, atol=1e-12)
    e[rows // 2] = 0.3
    x = exact_x(e)
    assert x[rows // 2] == exact_x(np.array([0.3]))[0] and x[0] == exact_x(np.array([0.57]))[0]
