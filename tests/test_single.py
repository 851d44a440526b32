"""The per-call path of ``simulate()`` (``impact.single``) against the table path (``impact.evaluation``).

The table path is the reference: it validates, resolves, computes and judges every row, with every message
and warning of the CLI.  ``impact.single`` answers the common case without that bookkeeping (issue 15 item 4)
and must give *the same result to the last bit* wherever it answers, and hand every other row to the table
path.  Both call the same compiled row function of the engine and the same arithmetic in the same order,
so the tolerance here is zero: any difference is a second judgement or a formula written twice differently.

Rows are drawn at random (seeded) over everything ``simulate`` takes: library fruit and surfaces, Fruit and
Surface objects, every damping law, calibration, method and criterion, velocities or drop heights (numbers
and strings with units), restitution, α or λ, values inside and outside their plausible and allowed ranges,
conflicting alternatives and unknown inputs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import fruitimpact as fi
from fruitimpact.impact import single
from fruitimpact.impact.simulation import Fruit, Surface, _simulate_table
from fruitimpact.impact.validation import InputError
from fruitimpact.library import catalogue
from fruitimpact.physics import CALIBRATIONS, DAMPING_LAWS

FRUITS = list(catalogue.fruits())
SURFACES = list(catalogue.surfaces())


def _snapshot(result) -> str:
    """Everything a caller can read of a result, as text (NaN equals NaN; bits show in repr)."""
    return repr((result.to_dict(), result.plastic_arguments, result.plastic, result.curve_points,
                 result.law, result.inputs))


def _random_call(rng: np.random.Generator):
    """(fruit, surface, keywords) of one random ``simulate`` call."""
    pick = rng.random
    fruit = None
    if pick() < 0.4:
        fruit = FRUITS[rng.integers(len(FRUITS))]
    elif pick() < 0.5:
        fruit = Fruit(mass=float(10 ** rng.uniform(-3.5, 1.5)), diameter=float(rng.uniform(0.01, 0.12)),
                      modulus=float(10 ** rng.uniform(4, 8.5)), poisson=float(rng.uniform(-0.2, 0.49)),
                      stiffness=float(10 ** rng.uniform(4, 7)) if pick() < 0.15 else None)
    surface = None
    if pick() < 0.4:
        surface = SURFACES[rng.integers(len(SURFACES))]
    elif pick() < 0.3:
        surface = Surface(modulus=float(10 ** rng.uniform(6, 11)) if pick() < 0.8 else math.inf,
                          radius=float(rng.uniform(0.02, 1.0)) if pick() < 0.3 else math.inf,
                          thickness=float(rng.uniform(0.001, 0.05)) if pick() < 0.15 else math.inf)
    keywords = dict(velocity=None, drop_height=None, restitution=None, alpha=None, damping=None,
                    model="hunt-crossley", calibration="exact", method="accurate", step=1e-4)
    if pick() < 0.5:
        keywords["model"] = list(DAMPING_LAWS)[rng.integers(len(DAMPING_LAWS))]
    if pick() < 0.3:
        keywords["calibration"] = list(CALIBRATIONS)[rng.integers(len(CALIBRATIONS))]
    if pick() < 0.1:
        keywords["method"] = "rk4"
    if pick() < 0.5:
        keywords["velocity"] = float(10 ** rng.uniform(-2.5, 1.3))
    if pick() < 0.4:
        keywords["drop_height"] = f"{rng.uniform(0.5, 150):.3g}cm" if pick() < 0.5 else float(rng.uniform(0, 2))
    damped = rng.integers(5)
    if damped == 1 or pick() < 0.03:
        keywords["restitution"] = float(rng.choice([1.0, rng.uniform(0.01, 1.0), rng.uniform(-0.1, 1.2)]))
    if damped == 2:
        keywords["alpha"] = float(rng.uniform(0, 3))
    if damped == 3:
        keywords["damping"] = float(10 ** rng.uniform(3, 7))
    if pick() < 0.1:
        keywords["criterion"] = ["none", "pressure", "shear", "energy"][rng.integers(4)]
    if pick() < 0.05:
        keywords[["yield_pressure", "partner_mass", "surface_model", "bioyield_force", "masss"][rng.integers(5)]] = \
            ["0.3MPa", 0.2, "layer", 10.0, 1.0][rng.integers(5)]
    if pick() < 0.05:
        keywords["velocity"] = ["fast", math.nan, -1.0, True, "2 km/h"][rng.integers(5)]
    return fruit, surface, keywords


def _outcome(call, fruit, surface, keywords):
    try:
        return call(fruit, surface, dict(keywords), 1001)
    except InputError as error:
        return ("refused", str(error), error.argument)


def test_single_path_gives_the_table_paths_result_to_the_bit():
    rng = np.random.default_rng(20261125)
    answered = refused = 0
    for _ in range(2000):
        fruit, surface, keywords = _random_call(rng)
        table = _outcome(_simulate_table, fruit, surface, keywords)
        fast = single.impact(fruit, surface, dict(keywords), 1001)
        public = _outcome(lambda f, s, k, p: fi.simulate(f, surface=s, **k), fruit, surface, keywords)
        if isinstance(table, tuple):  # refused input: simulate raises the table path's own error
            refused += 1
            assert fast is None, (fruit, surface, keywords)
            assert public == table
            continue
        assert _snapshot(public) == _snapshot(table), (fruit, surface, keywords)
        if fast is not None:
            answered += 1
            # the per-call path answers only what the table judges ok with no message and no warning
            assert (table.status, table.message, table.warnings) == ("ok", "ok", ()), (fruit, surface, keywords)
            assert _snapshot(fast) == _snapshot(table), (fruit, surface, keywords)
    # the draw reaches both paths often enough for the comparison to mean something
    assert answered > 300 and refused > 100, (answered, refused)


def test_single_path_answers_the_common_calls():
    """The calls a notebook loop, an optimiser or the web explorer makes go the fast way (a result with a
    warning never does: checked above)."""
    keywords = dict(velocity=None, drop_height=None, restitution=None, alpha=None, damping=None,
                    model="hunt-crossley", calibration="exact", method="accurate", step=1e-4)
    for fruit, surface, extra in ((None, None, {}), ("apple", "steel", {"drop_height": "30cm"}),
                                  ("pear", "wood", {"velocity": 2.0, "restitution": 0.5}),
                                  (Fruit(mass=0.2), Surface(modulus=2e9), {"alpha": 0.3}),
                                  ("apple", None, {"model": "hertz"}),
                                  ("apple", "concrete", {"calibration": "paper", "model": "lankarani-nikravesh"})):
        result = single.impact(fruit, surface, {**keywords, **extra}, 1001)
        assert result is not None, (fruit, surface, extra)
        assert _snapshot(result) == _snapshot(_simulate_table(fruit, surface, {**keywords, **extra}, 1001))
        # its curves come from the same solver: the largest of 1001 samples of F(t) is the peak force, less
        # at most what a quadratic peak loses between samples, (T/1000)²-small: well below 1e-4 relative
        sampled, peak = np.max(result.curves.force), result.characteristics.peak_force
        assert peak * (1 - 1e-4) <= sampled <= peak * (1 + 1e-12)


def test_a_surface_object_is_simulated():
    """A Surface's default crush stress (inf, "does not crush") is not a crush stress given off a layer
    (it was refused: every simulate(surface=Surface(...)) failed)."""
    result = fi.simulate(surface=Surface(modulus=2e9))
    assert result.status == "ok"
    # Hertz: a softer surface lowers E*, hence k_c (Johnson 1985 eq 4.22–4.23), below the rigid plane's
    assert result.inputs.surface.modulus == 2e9
    assert result.law.stiffness < fi.simulate().law.stiffness


def test_a_numpy_boolean_is_not_a_number():
    """np.True_ was read as 1.0 (read_value tested for Python's bool only): refused as True is."""
    with pytest.raises(ValueError, match="restitution must be a number"):
        fi.simulate(restitution=np.True_)


def test_the_curves_of_a_fruit_on_fruit_impact_move_the_reduced_mass():
    """Against a free identical fruit the reduced mass m/2 moves (impact.presets.effective_mass): the curves used
    the whole mass, and peaked at 305 N where the characteristics said 201 N, still at 36 N at 'separation'.
    The reference is the impact's own characteristics, from the engine's exact first-integral kernel: the
    sampled peak within the sampling's (T/1000)² and a force back to 0 at T."""
    result = fi.simulate("apple", surface="fruit", drop_height="1m")
    peak, force = result.characteristics.peak_force, result.curves.force
    assert peak * (1 - 1e-4) <= force.max() <= peak * (1 + 1e-12)
    assert abs(force[-1]) < 1e-6 * peak
