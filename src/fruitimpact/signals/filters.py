"""Small numeric pieces of the signal analysis: a causal Butterworth low-pass design and an in-place
solver of small linear systems (the least-squares fits of the detector's warm-up and of a peak).
NumPy and numba only: no SciPy at run time."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from fruitimpact.engine.jitcache import CACHE
from fruitimpact.signals.settings import check_cutoff

__all__ = ["butterworth_sos", "solve_small"]


def butterworth_sos(cutoff: float, order: int, rate: float) -> np.ndarray:
    """Second-order sections (rows b0, b1, b2, 1, a1, a2, SciPy's layout) of a causal digital Butterworth
    low-pass of ``order`` with its −3 dB point at ``cutoff`` [Hz] for ``rate`` [Hz]: the analogue
    prototype's pole pairs at angles π(2k − 1)/(2N) from the imaginary axis, bilinear transform with
    the cutoff prewarped (K = tan(π f_c/rate)); each section has unit gain at DC."""
    check_cutoff(cutoff, rate)
    k = math.tan(math.pi * cutoff / rate)
    rows = []
    for j in range(order // 2):
        q = 1.0 / (2.0 * math.sin(math.pi * (2 * j + 1) / (2 * order)))
        norm = 1.0 / (1.0 + k / q + k * k)
        b0 = k * k * norm
        rows.append([b0, 2 * b0, b0, 1.0, 2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm])
    if order % 2:
        rows.append([k / (1 + k), k / (1 + k), 0.0, 1.0, (k - 1) / (k + 1), 0.0])
    return np.array(rows, dtype=float)


@nb.njit(cache=CACHE, error_model="numpy")
def solve_small(a, b, n):
    """Solve the leading n × n block of a x = b in place (Gaussian elimination with partial pivoting):
    on return b[:n] holds x.  False (a and b undone only partly) when the block is singular."""
    for col in range(n):
        piv = col
        for row in range(col + 1, n):
            if abs(a[row, col]) > abs(a[piv, col]):
                piv = row
        if a[piv, col] == 0.0:
            return False
        if piv != col:
            for k in range(n):
                a[col, k], a[piv, k] = a[piv, k], a[col, k]
            b[col], b[piv] = b[piv], b[col]
        for row in range(col + 1, n):
            f = a[row, col] / a[col, col]
            for k in range(col, n):
                a[row, k] -= f * a[col, k]
            b[row] -= f * b[col]
    for col in range(n - 1, -1, -1):
        s = b[col]
        for k in range(col + 1, n):
            s -= a[col, k] * b[k]
        b[col] = s / a[col, col]
    return True
