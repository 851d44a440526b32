"""α is Hunt–Crossley's damping parameter; λ may be given directly (issue 6, item 14).

The paper defines λ = 1.5 α k_c (eq 5); k = 1 − α V_i (eq 6) is only its
first-order consequence.  So ``--alpha A`` must give damping = 1.5·A·k_c for
any A ≥ 0 and V > 0, whatever the calibration, and the restitution that the
Hunt–Crossley law really produces for c = λ/k_c = 1.5 A.  The reference for
that restitution is the exact relation of the first integral,
(1 + x) = (1 − e x) exp((1 + e) x) with x = c V (Hunt & Crossley 1975),
solved here by SciPy's brentq, and, for a few cases, a direct SciPy
integration of m δ̈ = −K δ^1.5 (1 + c δ̇) (tests/reference.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import fruitimpact
from fruitimpact.impact.evaluation import evaluate
from reference import reference_powerlaw

STIFFNESS = 1.0e6  # N/m^1.5
MASS = 0.115  # kg


def exact_restitution(x: float) -> float:
    """Root e in (0, 1] of (1 + x) = (1 − e x) exp((1 + e) x) (independent of the package)."""
    if x == 0.0:
        return 1.0
    f = lambda e: (1.0 - e * x) * math.exp((1.0 + e) * x) - (1.0 + x)  # noqa: E731
    upper = min(1.0, 1.0 / x) * (1.0 - 1e-15)
    if f(upper) > 0.0:  # heavy damping: e = (1 - (1 + x) e^-(1+e)x)/x is 1/x to double precision
        return min(1.0, 1.0 / x)
    return brentq(f, 1e-300, upper, xtol=1e-300, rtol=1e-15, maxiter=500)


ALPHAS = [0.0, 0.1, 0.5, 0.69, 1.0, 2.0, 10.0]
VELOCITIES = [0.2, 1.0, 2.0, 5.0]


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("velocity", VELOCITIES)
def test_alpha_gives_hunt_crossley_damping_and_its_exact_restitution(cli, alpha, velocity):
    report = cli.json("simulate", "--alpha", alpha, "--velocity", velocity, "--stiffness", STIFFNESS,
                      "--mass", MASS)
    # before: α = 0.5 s/m at 1 m/s gave λ = 1.43e6 instead of 0.75e6, and α ≥ 1/V was refused
    assert report["damping"] == pytest.approx(1.5 * alpha * STIFFNESS, rel=1e-15)
    assert report["restitution"] == pytest.approx(exact_restitution(1.5 * alpha * velocity), rel=1e-10, abs=1e-12)
    assert report["target_restitution"] is None  # nothing was requested: the restitution follows


@pytest.mark.parametrize("model", ["hunt-crossley", "chen", "flores", "exact"])
@pytest.mark.parametrize("calibration", ["paper", "exact"])
def test_alpha_makes_law_and_calibration_irrelevant_in_the_power_law_family(model, calibration):
    result = fruitimpact.simulate(alpha=0.69, velocity=2.0, model=model, calibration=calibration)
    reference = fruitimpact.simulate(alpha=0.69, velocity=2.0)
    assert result.law.damping == reference.law.damping
    assert result.characteristics.peak_force == pytest.approx(reference.characteristics.peak_force, rel=1e-13)


def test_jonathan_apple_from_twenty_centimetres_with_the_papers_largest_alpha():
    """The paper's α up to 0.69 s/m at 2 m/s (20 cm) is a valid Hunt–Crossley impact: integrate it directly."""
    fruit = fruitimpact.Fruit(stiffness=STIFFNESS, mass=MASS)
    result = fruitimpact.simulate(fruit, alpha=0.69, velocity=2.0)
    assert result.success
    reference = reference_powerlaw(MASS, STIFFNESS, 1.5 * 0.69, 2.0)
    assert result.characteristics.restitution == pytest.approx(reference["restitution"], rel=1e-8)
    assert result.characteristics.peak_force == pytest.approx(reference["peak_force"], rel=1e-8)


def test_damping_gives_lambda_directly():
    result = fruitimpact.simulate(fruitimpact.Fruit(stiffness=STIFFNESS), damping=0.75e6, velocity=1.0)
    assert result.law.damping == pytest.approx(0.75e6, rel=1e-15)
    assert result.law.damping_factor == pytest.approx(0.75, rel=1e-15)
    assert result.characteristics.restitution == pytest.approx(exact_restitution(0.75), rel=1e-10)


@pytest.mark.parametrize("model, unit", [("kelvin-voigt-clamped", "N·s/m"), ("tsuji", "N·s/m^1.25"),
                                         ("kuwabara-kono", "N·s/m^1.5")])
def test_damping_of_the_other_families_is_their_own_coefficient(model, unit):
    result = fruitimpact.simulate(damping=2.0, model=model)
    assert result.law.damping == pytest.approx(2.0, rel=1e-14)
    assert result.to_dict()["damping_unit"] == unit


@pytest.mark.parametrize("model", ["kelvin-voigt", "tsuji-clamped", "kuwabara-kono"])
def test_alpha_is_refused_where_it_means_nothing(cli, model):
    with pytest.raises(ValueError) as info:
        fruitimpact.simulate(alpha=0.2, model=model)
    assert "alpha is Hunt–Crossley's damping parameter of the power-law laws" in str(info.value)
    assert "give restitution, or damping" in str(info.value)
    line = cli.error("simulate", "--alpha", "0.2", "--model", model)
    assert line == f"fruitimpact simulate: error: argument --alpha: {info.value}"


def test_only_one_of_restitution_alpha_damping(cli):
    with pytest.raises(ValueError, match="^give either restitution or alpha, not both$"):
        fruitimpact.simulate(restitution=0.5, alpha=0.1)
    line = cli.error("simulate", "--alpha", "0.1", "--damping", "3")
    assert line == "fruitimpact simulate: error: give either --alpha or --damping, not both"


def test_alpha_and_damping_in_a_batch():
    table = evaluate({"alpha": [0.5, None, None], "damping": [None, 7.5e5, None], "stiffness": STIFFNESS,
                      "velocity": [1.0, 1.0, 1.0]})
    assert list(table["status"]) == ["ok", "ok", "ok"]
    np.testing.assert_allclose(table["damping"][:2], [7.5e5, 7.5e5], rtol=1e-15)
    assert np.isnan(table.loc[0, "target_restitution"]) and table.loc[2, "target_restitution"] == 0.577
