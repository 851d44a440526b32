"""Hertz contact of a fruit with a surface (pure functions, SI).

A fruit near its contact point is treated as a sphere of radius R pressed on
a half-space.  Hertz's solution gives F = K δ^(3/2) with

    K = (4/3) E* sqrt(R),   1/E* = (1-ν1²)/E1 + (1-ν2²)/E2,   1/R = 1/R1 + 1/R2.

For a sphere of diameter d on a rigid plane (E2 → ∞, R2 → ∞) this is the
paper's eq 9, k_c = 0.943 E/(1-ν²) sqrt(d), whose 0.943 is (4/3)/sqrt(2).

Sources: H. Hertz, J. reine angew. Math. 92 (1882) 156–171; K. L. Johnson,
*Contact Mechanics*, Cambridge University Press (1985), §4.2 (eqs 4.22–4.24);
the founding paper, "Theoretical aspects about simulating the reaction to impact of apples on rigid plane surfaces", eqs 7–9.
"""

from __future__ import annotations

import math

import numpy as np

#: (4/3)/sqrt(2): the paper's eq 9 constant 0.943, exactly.
RIGID_PLANE_FACTOR = 4.0 / 3.0 / math.sqrt(2.0)


def effective_modulus(modulus_1, poisson_1, modulus_2=math.inf, poisson_2=0.0):
    """Contact modulus E* [Pa]: 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2 (Johnson 1985, eq 4.22).

    ``modulus_2 = inf`` (the default) is a rigid surface, E* = E1/(1-ν1²)."""
    compliance = (1.0 - np.square(poisson_1)) / modulus_1 + (1.0 - np.square(poisson_2)) / modulus_2
    return 1.0 / compliance


def effective_radius(radius_1, radius_2=math.inf):
    """Effective radius R [m]: 1/R = 1/R1 + 1/R2; ``radius_2 = inf`` is a plane."""
    return 1.0 / (1.0 / np.asarray(radius_1, dtype=float) + 1.0 / np.asarray(radius_2, dtype=float))


def hertz_stiffness(contact_modulus, radius):
    """Hertz contact stiffness K = (4/3) E* sqrt(R) [N/m^1.5] (Johnson 1985, eq 4.23)."""
    return 4.0 / 3.0 * np.asarray(contact_modulus, dtype=float) * np.sqrt(radius)


def rigid_plane_stiffness(modulus, poisson, diameter):
    """k_c = (4/3)/sqrt(2) · E/(1-ν²) · sqrt(d) [N/m^1.5]: a sphere of diameter
    d [m] on a rigid plane, the paper's eq 9 (its 0.943 rounded)."""
    return hertz_stiffness(effective_modulus(modulus, poisson), np.asarray(diameter, dtype=float) / 2.0)


def contact_radius(radius, deflection):
    """Hertz contact radius a = sqrt(R δ) [m] (Johnson 1985, eq 4.23)."""
    return np.sqrt(np.asarray(radius, dtype=float) * deflection)


def hertz_peak_pressure(force, radius, deflection):
    """Peak (centre) contact pressure p0 = 3F/(2π a²) with a² = R δ [Pa]
    (Johnson 1985, eq 4.24)."""
    return 3.0 * np.asarray(force, dtype=float) / (2.0 * math.pi * np.asarray(radius, dtype=float) * deflection)


def hertz_max_deflection(mass, stiffness, velocity, exponent=1.5):
    """Maximum deflection of an undamped impact, δ = ((n+1) m v² / (2K))^(1/(n+1)) [m];
    for n = 3/2, (5 m v²/(4K))^(2/5) (Johnson 1985, §11.4)."""
    n = exponent
    return ((n + 1.0) * np.asarray(mass, dtype=float) * np.square(velocity) / (2.0 * stiffness)) ** (1.0 / (n + 1.0))


def hertz_contact_duration(mass, stiffness, velocity):
    """Contact duration of an undamped Hertz impact (n = 3/2) [s]:
    T = (4/5) B(1/2, 2/5) δ_max/v0 = 2.9432 δ_max/v0, B the Euler beta function
    (Johnson 1985, §11.4; from integrating the energy equation)."""
    beta = math.gamma(0.5) * math.gamma(0.4) / math.gamma(0.9)
    return 0.8 * beta * hertz_max_deflection(mass, stiffness, velocity) / np.asarray(velocity, dtype=float)
