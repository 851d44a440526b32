"""Streaming moments of a column, in one compiled pass.

``column_moments`` gives the count, mean, sum of squared deviations (M2),
minimum and maximum of the finite entries of a column that a mask selects,
by Welford's update (B. P. Welford, Technometrics 4 (1962) 419): exact to
rounding, one pass, no temporary arrays.  Chunks are merged with Chan,
Golub & LeVeque's pairwise formula (``runs.summaries``).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE


@nb.njit(cache=CACHE)
def _moments(column, mask, out):
    n = 0
    mean = 0.0
    m2 = 0.0
    low = math.inf
    high = -math.inf
    for i in range(column.shape[0]):
        value = column[i]
        if not mask[i] or not math.isfinite(value):
            continue
        n += 1
        delta = value - mean
        mean += delta / n
        m2 += delta * (value - mean)
        if value < low:
            low = value
        if value > high:
            high = value
    out[0] = n
    out[1] = mean
    out[2] = m2
    out[3] = low
    out[4] = high


def column_moments(column: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(n, mean, M2, min, max) of the finite entries of ``column`` where ``mask``; for no entry
    (0, 0, 0, inf, -inf)."""
    out = np.empty(5)
    _moments(np.ascontiguousarray(column, dtype=float), np.ascontiguousarray(mask, dtype=np.bool_), out)
    return out





@nb.njit(cache=CACHE)
def _block_summary(block, columns, ok, chosen, threshold_columns, threshold_ops, threshold_values,
                   moments, counts, sample):
    k = columns.shape[0]
    for j in range(k):
        moments[j, 0] = 0.0
        moments[j, 1] = 0.0
        moments[j, 2] = 0.0
        moments[j, 3] = math.inf
        moments[j, 4] = -math.inf
    for t in range(threshold_columns.shape[0]):
        counts[t] = 0
    kept = 0
    for i in range(block.shape[0]):
        if not ok[i]:
            continue
        for j in range(k):
            value = block[i, columns[j]]
            if not math.isfinite(value):
                continue
            moments[j, 0] += 1.0
            delta = value - moments[j, 1]
            moments[j, 1] += delta / moments[j, 0]
            moments[j, 2] += delta * (value - moments[j, 1])
            if value < moments[j, 3]:
                moments[j, 3] = value
            if value > moments[j, 4]:
                moments[j, 4] = value
        for t in range(threshold_columns.shape[0]):
            value = block[i, threshold_columns[t]]
            op = threshold_ops[t]
            limit = threshold_values[t]
            if (op == 0 and value > limit) or (op == 1 and value >= limit) or (op == 2 and value < limit) \
                    or (op == 3 and value <= limit):
                counts[t] += 1
        if chosen[i]:
            for j in range(k):
                sample[kept, j] = block[i, columns[j]]
            kept += 1


#: Threshold operators by code (``block_summary``).
OPERATORS = (">", ">=", "<", "<=")


def block_summary(block: np.ndarray, columns, ok: np.ndarray, chosen: np.ndarray, thresholds=()):
    """One pass over a characteristics block (rows × columns, row-major as the engine writes it):
    the moments (n, mean, M2, min, max; Welford) of the finite values of ``columns`` over the ``ok``
    rows, the count of ok rows beyond each threshold ``(column, operator, value)`` (operator one of
    ``OPERATORS``; NaN is never beyond), and the ``chosen`` rows' values of ``columns`` (the
    percentile sample, rows × columns).  ``chosen`` must select ok rows only."""
    columns = np.asarray(columns, dtype=np.int64)
    ok = np.ascontiguousarray(ok, dtype=np.bool_)
    chosen = np.ascontiguousarray(chosen, dtype=np.bool_)
    t_columns = np.array([c for c, _, _ in thresholds], dtype=np.int64)
    t_ops = np.array([OPERATORS.index(op) for _, op, _ in thresholds], dtype=np.int64)
    t_values = np.array([v for _, _, v in thresholds], dtype=float)
    moments = np.empty((columns.size, 5))
    counts = np.empty(t_columns.size, dtype=np.int64)
    sample = np.empty((int(chosen.sum()), columns.size))
    _block_summary(block, columns, ok, chosen, t_columns, t_ops, t_values, moments, counts, sample)
    return moments, counts, sample
__all__ = ["OPERATORS", "block_summary", "column_moments"]
