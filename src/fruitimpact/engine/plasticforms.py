"""Closed forms of elastic–plastic contact and of a cushion layer: plain NumPy, no compiled code.

Thornton's yield force and its inverse (C. Thornton, Z. Ning, Powder Technol. 99 (1998) 154–162, "TN98"; the founding paper's bioyield force read as a limiting pressure), the
Winkler stiffness of a layer, and the columns the plastic engine (``plastic``) adds to the characteristics. They
live apart from the compiled engine so that validating a row (``impact.evaluation``, a usage error of the CLI)
needs no numba.
"""

from __future__ import annotations

import math

import numpy as np

#: Columns of the plastic block, after the characteristics.
PLASTIC_COLUMNS = ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work", "yield_force",
                   "bottomed_out", "fruit_work_share", "unloading_radius")
N_PLASTIC = len(PLASTIC_COLUMNS)


def yield_force(contact_modulus, radius, yield_pressure):
    """Thornton's yield force F_y = π³ p_y³ R² / (6 E*²) [N] (TN98 eq 16): the force at which the
    Hertz centre pressure reaches the limiting contact pressure p_y [Pa]; E* [Pa], R [m]."""
    return math.pi ** 3 * np.asarray(yield_pressure, dtype=float) ** 3 * np.square(radius) / \
        (6.0 * np.square(contact_modulus))


def yield_pressure_of_force(contact_modulus, radius, force):
    """The limiting pressure p_y [Pa] whose Thornton yield force is ``force`` [N]: the inverse of
    ``yield_force``, p_y = (6 E*² F / (π³ R²))^(1/3).  The founding paper's bioyield critical force
    F_pc (its eq 17) is read as F_y."""
    return np.cbrt(6.0 * np.square(contact_modulus) * np.asarray(force, dtype=float) /
                   (math.pi ** 3 * np.square(radius)))


def winkler_stiffness(modulus, poisson, thickness, radius):
    """K_L = π k R [N/m²] of an elastic-foundation layer under a sphere of radius R [m]:
    F = K_L δ², k = (1−ν)E/((1+ν)(1−2ν)h) [N/m³] (a laterally confined layer of thickness h [m]
    on a rigid substrate; Simbody ``ElasticFoundationForce``)."""
    poisson = np.asarray(poisson, dtype=float)
    k = (1.0 - poisson) * np.asarray(modulus, dtype=float) / ((1.0 + poisson) * (1.0 - 2.0 * poisson) *
                                                              np.asarray(thickness, dtype=float))
    return math.pi * k * np.asarray(radius, dtype=float)


__all__ = ["N_PLASTIC", "PLASTIC_COLUMNS", "winkler_stiffness", "yield_force", "yield_pressure_of_force"]
