"""The published damping laws, one documented function each.

Each function turns a restitution coefficient e ∈ (0, 1] into the
dimensionless damping group of its force family (``physics.families``), as
its authors published it:

* power-law family F = K δ^1.5 (1 + c δ̇): χ = c·V_i;
* Kelvin–Voigt F = k δ + b δ̇: the damping ratio ζ = b / (2 sqrt(k m));
* Kuwabara–Kono F = K (δ^1.5 + B δ^0.5 δ̇): b = B (K/m)^(2/5) V_i^(1/5);
* Tsuji F = K δ^1.5 + η δ^0.25 δ̇: α = η / sqrt(m K).

Whether the published formula really gives back e (most do only to first
order in 1 − e) is measured by ``fruitimpact models`` and discussed in
docs/models.md.  The transcriptions were checked against the sources and
public implementations listed there; two remain unconfirmed and say so.
All functions take and return NumPy arrays (or floats).
"""

from __future__ import annotations

import math

import numpy as np

#: First-order coefficient of the Kuwabara–Kono restitution, e = 1 - C1 b + ...,
#: b = B (K/m)^(2/5) v0^(1/5):  C1 = Γ(3/5) √π / (2^(1/5) 5^(2/5) Γ(21/10)) = 1.153449
#: (Schwager & Pöschel, Phys. Rev. E 78 (2008) 051304; Ramírez et al., Phys. Rev. E 60 (1999) 4465).
KUWABARA_KONO_C1 = math.gamma(0.6) * math.sqrt(math.pi) / (2 ** 0.2 * 5 ** 0.4 * math.gamma(2.1))


def hunt_crossley(e):
    """χ = 3(1 − e)/2: K. H. Hunt, F. R. E. Crossley, Coefficient of restitution interpreted as
    damping in vibroimpact, J. Appl. Mech. 42 (1975) 440–445.  The apple paper's eqs 5–6
    (λ = 1.5 α k_c with e = 1 − α V_i), first order in 1 − e."""
    return 1.5 * (1.0 - np.asarray(e, dtype=float))


def herbert_mcwhannell(e):
    """χ = 6(1 − e)/((2e − 1)² + 3): R. G. Herbert, D. C. McWhannell, Shape and frequency
    composition of pulses from an impact pair, J. Eng. Ind. 99 (1977) 513–518; transcription
    as in Machado et al., Mech. Mach. Theory 53 (2012) 99–121."""
    e = np.asarray(e, dtype=float)
    return 6.0 * (1.0 - e) / ((2.0 * e - 1.0) ** 2 + 3.0)


def lee_wang(e):
    """χ = 3(1 − e)/4: T. W. Lee, A. C. Wang, On the dynamics of intermittent-motion mechanisms,
    part 1, J. Mech. Transm. Autom. Des. 105 (1983) 534–540; transcription as in Machado et al.
    2012.  Half the Hunt–Crossley damping, even as e → 1."""
    return 0.75 * (1.0 - np.asarray(e, dtype=float))


def lankarani_nikravesh(e):
    """χ = 3(1 − e²)/4: H. M. Lankarani, P. E. Nikravesh, A contact force model with hysteresis
    damping for impact analysis of multibody systems, J. Mech. Des. 112 (1990) 369–376.  The apple
    paper's eqs 21, 23, which it attributes to Chen & De Baerdemaeker 1995 ("Chen")."""
    e = np.asarray(e, dtype=float)
    return 0.75 * (1.0 - e * e)


def gonthier(e):
    """χ = (1 − e²)/e: Y. Gonthier, J. McPhee, C. Lange, J.-C. Piedbœuf, A regularized contact
    model with asymmetric damping and dwell-time dependent friction, Multibody Syst. Dyn. 11 (2004)
    209–233."""
    e = np.asarray(e, dtype=float)
    return (1.0 - e * e) / e


def zhiying_qishao(e):
    """χ = 3(1 − e²) exp(2(1 − e))/4: Q. Zhiying, L. Qishao, Analysis of impact process based on
    restitution coefficient, J. Dyn. Control 4 (2006) 294–298; transcription as in Machado et al.
    2012."""
    e = np.asarray(e, dtype=float)
    return 0.75 * (1.0 - e * e) * np.exp(2.0 * (1.0 - e))


def flores(e):
    """χ = 8(1 − e)/(5e): P. Flores, M. Machado, M. T. Silva, J. M. Martins, On the continuous
    contact force models for soft materials in multibody dynamics, Multibody Syst. Dyn. 25 (2011)
    357–375."""
    e = np.asarray(e, dtype=float)
    return 1.6 * (1.0 - e) / e


def hu_guo(e):
    """χ = 3(1 − e)/(2e): S. Hu, X. Guo, A dissipative contact force model for impact analysis in
    multibody dynamics, Multibody Syst. Dyn. 35 (2015) 131–151.  UNCONFIRMED transcription: the
    only public implementation found uses 3(1 − e)/(4e)."""
    e = np.asarray(e, dtype=float)
    return 1.5 * (1.0 - e) / e


def gharib_hurmuzlu(e):
    """χ = (1 − e)/e: M. Gharib, Y. Hurmuzlu, A new contact force model for low coefficient of
    restitution impact, J. Appl. Mech. 79 (2012) 064506.  UNCONFIRMED transcription: no public
    source of the formula could be found."""
    e = np.asarray(e, dtype=float)
    return (1.0 - e) / e


def exact_power_law(e):
    """χ solving (1 + χ) = (1 − e χ) exp((1 + e) χ): the exact restitution of F = K δ^n (1 + c δ̇),
    from the first integral of Hunt & Crossley 1975 (this package; docs/physics.md)."""
    from fruitimpact.engine.powerlaw import exact_x

    return exact_x(e)


def kelvin_voigt_damping_ratio(e):
    """ζ = −ln e / sqrt(π² + ln² e): the damping ratio of a linear oscillator whose half-period
    decay is e, exact for the unclamped spring–dashpot (T. Schwager, T. Pöschel, Coefficient of
    restitution and linear-dashpot model revisited, Granular Matter 9 (2007) 465–469)."""
    log_e = np.log(np.asarray(e, dtype=float))
    return -log_e / np.sqrt(np.pi ** 2 + log_e ** 2)


def tsuji_alpha(e):
    """α = −sqrt(5) ln e / sqrt(ln² e + π²): Y. Tsuji, T. Tanaka, T. Ishida, Lagrangian numerical
    simulation of plug flow of cohesionless particles in a horizontal pipe, Powder Technol. 71
    (1992) 239–250, in the form of YADE, Chrono DEM-Engine and MUSEN; exact unclamped (the
    substitution w = δ^(5/4) makes the law a linear oscillator)."""
    log_e = np.log(np.asarray(e, dtype=float))
    return -np.sqrt(5.0) * log_e / np.sqrt(log_e ** 2 + np.pi ** 2)


def kuwabara_kono_first_order(e):
    """b = (1 − e)/C1, C1 = 1.153449: the first-order restitution of the viscoelastic sphere,
    e = 1 − C1 b (G. Kuwabara, K. Kono, Jpn. J. Appl. Phys. 26 (1987) 1230; N. V. Brilliantov et
    al., Phys. Rev. E 53 (1996) 5382; C1 from Schwager & Pöschel, Phys. Rev. E 78 (2008) 051304)."""
    return (1.0 - np.asarray(e, dtype=float)) / KUWABARA_KONO_C1


__all__ = ["KUWABARA_KONO_C1", "exact_power_law", "flores", "gharib_hurmuzlu", "gonthier", "herbert_mcwhannell",
           "hu_guo", "hunt_crossley", "kelvin_voigt_damping_ratio", "kuwabara_kono_first_order", "lankarani_nikravesh",
           "lee_wang", "tsuji_alpha", "zhiying_qishao"]
