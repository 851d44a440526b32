"""Firmness classes: thresholds on a firmness index, calibrated on a labelled reference set.

A sorting line assigns each fruit a class (``soft``, ``medium``, ``firm`` …) by
thresholds on one index: C = F_max/t_c (``firmness_c``), C* = F_max/t_c²
(``firmness_c_star``) or the fitted Young's modulus (``modulus``).  The classes are
ordered from the softest (lowest index) to the firmest.

Calibration: given reference fruit whose class is known, the K − 1 thresholds that
maximise the balanced accuracy (the mean over classes of the share of each class
sorted into itself; robust to a reference set with few soft fruit) are found exactly
by dynamic programming over the sorted index values (O(K n) after the sort): every
threshold lies midway between two consecutive reference values.  The confusion
matrix and the accuracy per class go with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The indices a class may be based on.
SORT_INDICES = ("firmness_c", "firmness_c_star", "modulus", "stiffness", "peak_force")


@dataclass(frozen=True)
class FirmnessClasses:
    """Classes ``labels`` (softest first) separated by ascending ``thresholds`` of the index ``by``
    [SI units of that index]: class k holds thresholds[k-1] <= value < thresholds[k]."""

    by: str
    thresholds: tuple
    labels: tuple

    def __post_init__(self):
        for name in ("labels", "thresholds"):  # "ab" is two letters, not two class names
            if isinstance(getattr(self, name), (str, bytes)) or not hasattr(getattr(self, name), "__iter__"):
                raise ValueError(f"{name} must be a sequence (labels: class names, softest first); "
                                 f"got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(getattr(self, name)))
        if len(self.labels) < 2:
            raise ValueError(f"classes need at least two labels (one threshold between them); got "
                             f"{list(self.labels)}")
        if self.by not in SORT_INDICES:
            raise ValueError(f"by must be one of {', '.join(SORT_INDICES)}; got {self.by!r}")
        if len(self.labels) != len(self.thresholds) + 1:
            raise ValueError(f"classes need one threshold fewer than labels: {len(self.labels)} labels, "
                             f"{len(self.thresholds)} thresholds")
        if len(set(self.labels)) != len(self.labels) or not all(isinstance(x, str) and x for x in self.labels):
            raise ValueError(f"class labels must be distinct non-empty names; got {list(self.labels)}")
        values = [float(t) for t in self.thresholds]
        if not all(math.isfinite(t) for t in values) or any(b <= a for a, b in zip(values, values[1:])):
            raise ValueError(f"thresholds must be finite and strictly ascending; got {values}")

    def classify(self, values) -> np.ndarray:
        """The class label of each value (object array); NaN values get None."""
        values = np.asarray(values, dtype=float)
        index = np.searchsorted(np.asarray(self.thresholds, dtype=float), values, side="right")
        labels = np.asarray(self.labels, dtype=object)[np.minimum(index, len(self.labels) - 1)]
        labels[np.isnan(values)] = None
        return labels

    def to_dict(self) -> dict:
        return {"by": self.by, "thresholds": list(self.thresholds), "labels": list(self.labels)}


def calibrate(values, labels, classes, by: str) -> FirmnessClasses:
    """Thresholds of ``by`` that best separate the reference fruit: ``values`` of the index, their known
    ``labels``, and ``classes`` the class names from the softest to the firmest.  Maximises the balanced
    accuracy exactly (dynamic programming over the sorted values).

    Parameters
    ----------
    values : array of float
        The index ``by`` of each reference fruit [SI: N/s for C, N/s² for C*, Pa for the modulus …].
    labels : array of str
        The known class of each reference fruit (one of ``classes``).
    classes : sequence of str
        The class names, softest first.
    by : str
        The index: one of ``SORT_INDICES`` (``firmness_c``, ``firmness_c_star``, ``modulus``, ``stiffness``,
        ``peak_force``).

    Returns
    -------
    FirmnessClasses
        ``by``, the ascending ``thresholds`` and the ``classes``; ``classify(values)`` sorts new fruit.

    Raises
    ------
    ValueError
        Values and labels of different lengths, a value that is not finite, a label not among ``classes``,
        fewer than two classes.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> classes = fi.calibrate_classes([1e5, 2e5, 5e5, 6e5], ["soft", "soft", "firm", "firm"], ("soft", "firm"),
    ...                                "firmness_c_star")
    >>> classes.classify([1.5e5, 5.5e5]).tolist()
    ['soft', 'firm']

    References
    ----------
    The indices C and C*: eqs 1–2 of "Theoretical aspects about simulating the reaction to impact of apples on
    rigid plane surfaces"; the balanced accuracy: Brodersen et al., ICPR 2010.
    """
    if isinstance(classes, str):
        raise ValueError(f"classes must be a sequence of class names, softest first (e.g. ('soft', 'firm')); "
                         f"got the string {classes!r}")
    if len(classes) < 2:
        raise ValueError(f"classes must name at least two classes, softest first; got {list(classes)}")
    values = np.asarray(values, dtype=float)
    labels = np.asarray(labels, dtype=object)
    classes = tuple(classes)
    if values.shape != labels.shape or values.ndim != 1:
        raise ValueError("values and labels must be 1-D and of the same length")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"the reference {by} values must be finite numbers (row {int(np.flatnonzero(~np.isfinite(values))[0]) + 1})")
    unknown = sorted({str(x) for x in labels} - set(classes))
    if unknown:
        raise ValueError(f"labels {unknown} are not among the classes {list(classes)}")
    missing = [c for c in classes if not np.any(labels == c)]
    if missing:
        raise ValueError(f"the reference set has no fruit of class(es) {missing}: cannot place their thresholds")
    order = np.argsort(values, kind="stable")
    v, lab = values[order], labels[order]
    n, k_count = v.size, len(classes)
    # weight of a fruit: 1 / (fruit of its class): the sum over a class's correctly sorted fruit is its recall
    weights = np.zeros((k_count, n + 1))
    for k, name in enumerate(classes):
        member = lab == name
        weights[k, 1:] = np.cumsum(member / member.sum())
    # cuts only between distinct values (equal values must fall into one class)
    allowed = np.ones(n + 1, dtype=bool)
    allowed[1:n] = v[1:] > v[:-1]
    best = np.where(allowed, weights[0], -np.inf)  # class 0 holds sorted fruit [0, i)
    choice = np.zeros((k_count, n + 1), dtype=np.int64)
    for k in range(1, k_count):
        # best_k[i] = max_{j <= i, allowed j} best_{k-1}[j] - W_k[j] + W_k[i]
        candidate = best - weights[k]
        running = np.maximum.accumulate(candidate)
        where = np.zeros(n + 1, dtype=np.int64)
        arg = 0
        for i in range(n + 1):  # argmax positions of the running maximum
            if candidate[i] >= candidate[arg]:
                arg = i
            where[i] = arg
        best = np.where(allowed, running + weights[k], -np.inf)
        choice[k] = where
    cuts = []
    i = n
    for k in range(k_count - 1, 0, -1):
        j = choice[k, i]
        cuts.append(j)
        i = j
    cuts = cuts[::-1]
    thresholds = []
    for j in cuts:
        if j <= 0:
            low = v[0] - 1.0 if n else 0.0
            thresholds.append(low if not thresholds else np.nextafter(thresholds[-1], math.inf))
        elif j >= n:
            thresholds.append(float(v[-1]) + abs(float(v[-1])) * 1e-9 + 1e-300)
        else:
            thresholds.append(0.5 * (float(v[j - 1]) + float(v[j])))
    for m in range(1, len(thresholds)):  # strictly ascending even when a class got no fruit
        if thresholds[m] <= thresholds[m - 1]:
            thresholds[m] = float(np.nextafter(thresholds[m - 1], math.inf))
    return FirmnessClasses(by, tuple(float(t) for t in thresholds), classes)


def confusion(true_labels, predicted, classes) -> dict:
    """Confusion matrix (rows: true class, columns: sorted into), accuracy per class (recall), overall and
    balanced accuracy."""
    true_labels = np.asarray(true_labels, dtype=object)
    predicted = np.asarray(predicted, dtype=object)
    classes = tuple(classes)
    matrix = np.zeros((len(classes), len(classes)), dtype=np.int64)
    for i, a in enumerate(classes):
        for j, b in enumerate(classes):
            matrix[i, j] = int(np.sum((true_labels == a) & (predicted == b)))
    totals = matrix.sum(axis=1)
    per_class = {c: (float(matrix[i, i] / totals[i]) if totals[i] else math.nan) for i, c in enumerate(classes)}
    correct = int(np.trace(matrix))
    return {"classes": list(classes), "matrix": matrix.tolist(), "accuracy_per_class": per_class,
            "accuracy": correct / max(int(totals.sum()), 1),
            "balanced_accuracy": float(np.nanmean(list(per_class.values())))}


__all__ = ["SORT_INDICES", "FirmnessClasses", "calibrate", "confusion"]
