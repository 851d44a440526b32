"""Firmness classes (issue 8, item 5): calibrated thresholds against a brute-force search."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fruitimpact.signals.sort import FirmnessClasses, calibrate, confusion


def _balanced(values, labels, classes, thresholds):
    predicted = FirmnessClasses("firmness_c", tuple(thresholds), tuple(classes)).classify(values)
    return confusion(labels, predicted, classes)["balanced_accuracy"]


@pytest.mark.parametrize("seed", range(8))
def test_calibration_is_the_best_separation_by_brute_force(seed):
    """Independent reference: every pair of thresholds at the midpoints of the sorted values (O(n²) pairs)."""
    rng = np.random.default_rng(seed)
    classes = ("soft", "medium", "firm")
    centers = {"soft": 10.0, "medium": 20.0, "firm": 30.0}
    labels = rng.choice(classes, size=40, p=[0.2, 0.5, 0.3])
    labels[:3] = classes  # every class present
    values = np.array([rng.normal(centers[c], 6.0) for c in labels])
    got = calibrate(values, labels, classes, "firmness_c")
    v = np.sort(values)
    candidates = [v[0] - 1.0] + list(0.5 * (v[1:] + v[:-1])) + [v[-1] + 1.0]
    best = max(_balanced(values, labels, classes, (a, b)) for a, b in itertools.combinations(candidates, 2))
    assert _balanced(values, labels, classes, got.thresholds) == pytest.approx(best, abs=1e-12)


def test_separable_classes_are_sorted_perfectly_and_the_matrix_counts():
    values = np.array([1, 2, 3, 10, 11, 12, 20, 21], dtype=float)
    labels = np.array(["soft"] * 3 + ["medium"] * 3 + ["firm"] * 2, dtype=object)
    classes = ("soft", "medium", "firm")
    sorted_into = calibrate(values, labels, classes, "firmness_c_star")
    assert 3 < sorted_into.thresholds[0] < 10 and 12 < sorted_into.thresholds[1] < 20
    report = confusion(labels, sorted_into.classify(values), classes)
    assert report["matrix"] == [[3, 0, 0], [0, 3, 0], [0, 0, 2]]
    assert report["accuracy"] == 1.0 and report["accuracy_per_class"]["firm"] == 1.0


@pytest.mark.parametrize("kwargs, message", [
    (dict(by="colour", thresholds=(1.0,), labels=("a", "b")), "by must be one of"),
    (dict(by="firmness_c", thresholds=(1.0, 2.0), labels=("a", "b")), "one threshold fewer"),
    (dict(by="firmness_c", thresholds=(2.0, 1.0), labels=("a", "b", "c")), "strictly ascending"),
    (dict(by="firmness_c", thresholds=(1.0,), labels=("a", "a")), "distinct"),
])
def test_bad_classes_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        FirmnessClasses(**kwargs)


def test_calibration_refuses_what_it_cannot_use():
    with pytest.raises(ValueError, match="no fruit of class"):
        calibrate([1.0, 2.0], ["soft", "soft"], ("soft", "firm"), "firmness_c")
    with pytest.raises(ValueError, match="not among the classes"):
        calibrate([1.0, 2.0], ["soft", "ripe"], ("soft", "firm"), "firmness_c")
    with pytest.raises(ValueError, match="finite"):
        calibrate([1.0, float("nan")], ["soft", "firm"], ("soft", "firm"), "firmness_c")
