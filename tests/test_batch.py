"""batch.evaluate and batch.curves: rows equal single impacts; bad rows marked."""

import numpy as np
import pandas as pd
import pytest

from fruitimpact import Fruit, simulate
from fruitimpact.impact.evaluation import curves, evaluate
from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS

MODELS = ["hertz", "hunt-crossley", "chen", "flores", "exact", "kelvin-voigt", "kelvin-voigt-clamped",
          "tsuji", "tsuji-clamped", "kuwabara-kono"]


def test_rows_equal_single_impacts():
    rng = np.random.default_rng(5)
    rows = []
    for model in MODELS:
        for calibration in ("paper", "exact"):
            for method in ("accurate", "rk4"):
                rows.append(dict(mass=rng.uniform(0.05, 0.3), diameter=rng.uniform(0.04, 0.09),
                                 modulus=rng.uniform(2e6, 6e6), poisson=0.35, velocity=rng.uniform(0.4, 3.0),
                                 restitution=rng.uniform(0.3, 0.9), model=model, calibration=calibration,
                                 method=method, step=2e-5))
    frame = pd.DataFrame(rows)
    result = evaluate(frame)
    assert (result["status"] == "ok").all(), list(result.loc[result.status != "ok", "message"])
    for i, row in frame.iterrows():
        single = simulate(Fruit(mass=row.mass, diameter=row.diameter, modulus=row.modulus, poisson=row.poisson),
                          velocity=row.velocity, restitution=row.restitution, model=row.model,
                          calibration=row.calibration, method=row.method, step=row.step).characteristics
        for name in CHARACTERISTIC_COLUMNS:
            expected = getattr(single, name)
            got = result.loc[i, name]
            if np.isfinite(expected):
                assert got == pytest.approx(expected, rel=1e-9, abs=1e-300), (row.model, row.method, name)
            else:
                assert not np.isfinite(got)


def test_bad_rows_are_marked_and_the_rest_complete():
    frame = {  # None: not given (the default); a list keeps None apart from NaN
        "mass": ["115g", "-1", "0.1", "abc", 0.2, 0.1, 0.1],
        "velocity": [1.0, 1.0, None, 1.0, 1.0, 1.0, 1.0],
        "drop_height": [None, None, 0.3, None, 0.2, None, None],
        "restitution": [0.5, 0.5, 0.5, 0.5, 0.5, 1.5, 0.5],
        "model": ["chen", "chen", "chen", "chen", "chen", "chen", "nonsense"],
    }
    result = evaluate(frame)
    assert list(result["status"]) == ["ok", "invalid", "ok", "invalid", "invalid", "invalid", "invalid"]
    assert "mass must be a finite number > 0" in result.loc[1, "message"]
    assert "mass must be a number" in result.loc[3, "message"] and "'abc'" in result.loc[3, "message"]
    assert "either velocity or drop_height" in result.loc[4, "message"]
    assert "restitution must be in (0, 1]" in result.loc[5, "message"]
    assert "model must be one of" in result.loc[6, "message"]
    assert result.loc[0, "mass"] == 0.115
    assert result.loc[2, "velocity"] == pytest.approx(np.sqrt(2 * 9.80665 * 0.3))
    assert np.isnan(result.loc[1, "peak_force"])


def test_batch_curves_equal_single_curves():
    frame = {"mass": [0.1, 0.2], "model": ["hunt-crossley", "tsuji"], "velocity": [1.0, 2.0]}
    got = curves(frame, points=101)
    for i, (mass, model, velocity) in enumerate(zip(*frame.values())):
        single = simulate(Fruit(mass=mass), velocity=velocity, model=model, curve_points=101).curves
        np.testing.assert_allclose(got["time"][i], single.time, rtol=1e-12)
        np.testing.assert_allclose(got["force"][i], single.force, rtol=1e-9, atol=1e-9 * single.force.max())
    common = curves(frame, times=np.linspace(0, 2e-3, 11))
    assert common["deflection"].shape == (2, 11)
