"""Gauss–Jacobi quadrature rules (Golub–Welsch), NumPy only.

The contact-time integrals of the power-law force family have integrable
endpoint singularities of the form (b - ζ)^(-p); a Gauss–Jacobi rule with
that weight integrates them to machine precision with a few dozen nodes
because the remaining factor is analytic.  We build the rules here rather
than call ``scipy.special.roots_jacobi`` so that the engine does not import
SciPy (start-up time of the CLI).

Source: G. H. Golub, J. H. Welsch, "Calculation of Gauss quadrature rules",
Math. Comp. 23 (1969) 221–230; recurrence coefficients of the monic Jacobi
polynomials from W. Gautschi, *Orthogonal Polynomials* (2004), Table 1.1.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=32)
def gauss_jacobi(n_nodes: int, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the ``n_nodes``-point rule for ∫_{-1}^{1} (1-u)^a (1+u)^b f(u) du.

    Parameters
    ----------
    n_nodes : int
        Number of nodes (≥ 1).
    a, b : float
        Jacobi exponents, each > -1.

    Returns
    -------
    nodes, weights : ndarray
        Read-only arrays of length ``n_nodes``, nodes ascending.
    """
    if n_nodes < 1 or not (a > -1.0 and b > -1.0):
        raise ValueError("gauss_jacobi needs n_nodes >= 1 and exponents > -1")
    k = np.arange(n_nodes, dtype=float)
    s = 2.0 * k + a + b
    with np.errstate(divide="ignore", invalid="ignore"):
        diag = (b * b - a * a) / (s * (s + 2.0))
    diag[0] = (b - a) / (a + b + 2.0)  # the general formula is 0/0 at k = 0 when a + b = 0
    k1 = np.arange(1, n_nodes, dtype=float)
    s1 = 2.0 * k1 + a + b
    off_sq = 4.0 * k1 * (k1 + a) * (k1 + b) * (k1 + a + b) / (s1 * s1 * (s1 + 1.0) * (s1 - 1.0))
    jacobi_matrix = np.diag(diag) + np.diag(np.sqrt(off_sq), 1) + np.diag(np.sqrt(off_sq), -1)
    nodes, vectors = np.linalg.eigh(jacobi_matrix)
    mu0 = math.exp(
        (a + b + 1.0) * math.log(2.0)
        + math.lgamma(a + 1.0)
        + math.lgamma(b + 1.0)
        - math.lgamma(a + b + 2.0)
    )
    weights = mu0 * vectors[0, :] ** 2
    nodes.setflags(write=False)
    weights.setflags(write=False)
    return nodes, weights
