"""Force families: the form of the contact force, one record each.

A *family* is a force law F(δ, δ̇) with a stiffness and a damping
coefficient; the published *damping laws* (``physics.laws``) only say how the
damping follows from a restitution coefficient, and each belongs to one
family.  The record says everything the rest of the package needs to know of
a family: its engine code (``engine.forces``), the symbols and units of its
coefficients, the dimensionless damping group on which alone its restitution
depends, whether Hunt–Crossley's α means anything for it, and whether its
motion has a first integral (exact engine and curves) or is integrated.

Sources: Hunt & Crossley 1975 (power law); Schwager & Pöschel, Granular
Matter 9 (2007) 465 (Kelvin–Voigt); Brilliantov et al., Phys. Rev. E 53
(1996) 5382 and Schwager & Pöschel, Phys. Rev. E 78 (2008) 051304
(Kuwabara–Kono); Tsuji, Tanaka & Ishida, Powder Technol. 71 (1992) 239.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fruitimpact.engine import codes as forces

#: Undamped Hertz contact duration T = HERTZ_DURATION_FACTOR · δ_H / v0 = (4/5) B(1/2, 2/5) δ_H/v0.
HERTZ_DURATION_FACTOR = 0.8 * math.gamma(0.5) * math.gamma(0.4) / math.gamma(0.9)


def hertz_equivalent_linear_stiffness(mass, stiffness, velocity):
    """k [N/m] of the linear spring whose undamped contact duration π sqrt(m/k)
    equals the Hertz one at this impact, 2.943 δ_H/v0 (the usual way DEM codes
    match a linear law to a Hertz contact).  NaN where the scales under- or
    overflow (never a division error)."""
    mass, stiffness, velocity = (np.asarray(a, dtype=float) for a in (mass, stiffness, velocity))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        delta_h = (1.25 * mass * velocity ** 2 / stiffness) ** 0.4
        duration = HERTZ_DURATION_FACTOR * delta_h / velocity
        k = mass * (math.pi / duration) ** 2
    k = np.where(np.isfinite(k) & (k > 0), k, np.nan)
    return k if k.ndim else float(k)


def _same_stiffness(mass, stiffness, velocity):
    return stiffness


# The dimensionless damping group of each family, from the damping factor and back.
# K is always the Hertz contact stiffness k_c; Kelvin–Voigt converts it to its linear k.
def _x_group(factor, m, k, v):
    return factor * v  # x = c V_i


def _x_factor(x, m, k, v):
    return x / v


def _kv_group(factor, m, k_hertz, v):
    k = hertz_equivalent_linear_stiffness(m, k_hertz, v)
    return factor * k / (2.0 * np.sqrt(k * m))  # ζ


def _kv_factor(zeta, m, k_hertz, v):
    k = hertz_equivalent_linear_stiffness(m, k_hertz, v)
    return 2.0 * zeta * np.sqrt(k * m) / k  # b/k [s]


def _kk_group(factor, m, k, v):
    return factor * (k / m) ** 0.4 * v ** 0.2  # b


def _kk_factor(b, m, k, v):
    return b / ((k / m) ** 0.4 * v ** 0.2)  # B [s]


def _tsuji_group(factor, m, k, v):
    return factor * k / np.sqrt(m * k)  # α


def _tsuji_factor(alpha, m, k, v):
    return alpha * np.sqrt(m * k) / k  # η/K [s·m^0.25]


@dataclass(frozen=True)
class ForceFamily:
    """One form of contact force.

    Attributes
    ----------
    code : int
        The engine's code (``engine.forces``).
    name, formula : str
    stiffness_symbol, stiffness_unit, damping_symbol, damping_unit, factor_unit : str
        Symbols and SI units of the stiffness, the damping (the coefficient of the
        rate term) and the damping factor = damping / stiffness.
    alpha : bool
        Whether Hunt–Crossley's α (λ = 1.5 α k_c, eq 5) applies.
    first_integral : bool
        The motion has a first integral: exact characteristics and curves
        (``engine.powerlaw``); otherwise the adaptive integrator.
    group_doc : str
        The dimensionless damping group on which alone e depends.
    to_group, from_group : callable
        (damping factor, m, k_c, v0) → group, and its inverse (group, m, k_c, v0) → factor.
    damping_slot : int
        Where the damping goes in the engine's parameter vector (stiffness, ·, ·).
    damping_scaled : bool
        The engine takes damping = factor × stiffness there (else the factor itself).
    elastic_stiffness : callable
        (m, k_c, v0) → the stiffness the force uses (k_c, or a matched linear k).
    pressure : str
        How the peak contact pressure p_0 = 3 (F/δ)_max / (2π R) (Hertz: a² = R δ) is read from the force:
        ``"whole force"`` (the power law: Hunt–Crossley damping scales the Hertz force by (1 + c δ̇), so
        the whole force has the Hertz distribution), ``"elastic part"`` (K δ_max^0.5 from the Hertz term
        alone: a dashpot ∝ δ^0.5 δ̇ or δ^0.25 δ̇ has no Hertz distribution and would make F/a² unbounded at
        first touch), or ``""`` (no Hertz part: no contact pressure, stress criteria refused).
    """

    code: int
    name: str
    formula: str
    stiffness_symbol: str
    stiffness_unit: str
    damping_symbol: str
    damping_unit: str
    factor_unit: str
    alpha: bool
    first_integral: bool
    group_doc: str
    to_group: Callable
    from_group: Callable
    damping_slot: int = 1
    damping_scaled: bool = False
    elastic_stiffness: Callable = _same_stiffness
    pressure: str = "whole force"

    def params(self, stiffness, damping_factor, exponent: float = 1.5) -> np.ndarray:
        """Parameter matrix (rows, 3) of the engine's force (``engine.forces``): the stiffness,
        then the damping in its slot (the power law keeps its exponent n in slot 1)."""
        stiffness, damping_factor = np.broadcast_arrays(np.asarray(stiffness, dtype=float),
                                                        np.asarray(damping_factor, dtype=float))
        params = np.zeros(stiffness.shape + (3,))
        params[..., 0] = stiffness
        params[..., self.damping_slot] = damping_factor * stiffness if self.damping_scaled else damping_factor
        if self.damping_slot == 2:
            params[..., 1] = exponent
        return params

    @property
    def units(self) -> tuple:
        """((stiffness symbol, unit), (damping symbol, unit), damping-factor unit)."""
        return ((self.stiffness_symbol, self.stiffness_unit), (self.damping_symbol, self.damping_unit),
                self.factor_unit)


POWER_LAW = ForceFamily(
    forces.POWER_LAW, "power-law", "F = K δ^1.5 (1 + c δ̇)", "k_c", "N/m^1.5", "λ", "N·s/m^2.5", "s/m",
    alpha=True, first_integral=True, group_doc="x = c V_i", to_group=_x_group, from_group=_x_factor,
    damping_slot=2)  # c [s/m]; slot 1 holds n
KELVIN_VOIGT = ForceFamily(
    forces.KELVIN_VOIGT, "kelvin-voigt", "F = k δ + b δ̇", "k", "N/m", "b", "N·s/m", "s",
    alpha=False, first_integral=False, group_doc="ζ = b / (2 sqrt(k m))", to_group=_kv_group, from_group=_kv_factor,
    damping_scaled=True,  # b = c k
    elastic_stiffness=hertz_equivalent_linear_stiffness, pressure="")
KUWABARA_KONO = ForceFamily(
    forces.KUWABARA_KONO, "kuwabara-kono", "F = K (δ^1.5 + B δ^0.5 δ̇)", "K", "N/m^1.5", "K·B", "N·s/m^1.5", "s",
    alpha=False, first_integral=False, group_doc="b = B (K/m)^(2/5) V_i^(1/5)",
    to_group=_kk_group, from_group=_kk_factor, pressure="elastic part")
TSUJI = ForceFamily(
    forces.TSUJI, "tsuji", "F = K δ^1.5 + η δ^0.25 δ̇", "K", "N/m^1.5", "η", "N·s/m^1.25", "s·m^0.25",
    alpha=False, first_integral=False, group_doc="α = η / sqrt(m K)",
    to_group=_tsuji_group, from_group=_tsuji_factor, damping_scaled=True,  # η = c K
    pressure="elastic part")

#: Families by engine code.
FAMILIES: dict[int, ForceFamily] = {f.code: f for f in (POWER_LAW, KELVIN_VOIGT, KUWABARA_KONO, TSUJI)}

__all__ = ["FAMILIES", "ForceFamily", "HERTZ_DURATION_FACTOR", "KELVIN_VOIGT", "KUWABARA_KONO", "POWER_LAW",
           "TSUJI", "hertz_equivalent_linear_stiffness"]
