"""Registry of damping laws and of calibrations.

A *damping law* says which force family the contact follows
(``physics.families``) and how its damping follows from a restitution
coefficient e: the published formula is a function of ``physics.laws``.
A *calibration* says which e → damping rule is applied: the law's own
published formula (``paper``), or the exact inverse of the restitution the
law really produces (``exact``), which makes the simulated restitution equal
the requested one.

Formulas were checked against the sources and public implementations listed
in docs/models.md; the achieved-restitution tables there are produced by
``fruitimpact models`` and verified by an independent integration in
tests/test_models.py.  Add a law by writing its function in ``physics.laws``
and registering a ``DampingLaw`` here; nothing else needs to change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fruitimpact.engine import codes as forces
from fruitimpact.physics import laws
from fruitimpact.physics.families import FAMILIES, ForceFamily


@dataclass(frozen=True)
class DampingLaw:
    """A published contact damping law.

    Attributes
    ----------
    name : str
        Registry key (CLI ``--model``).
    title : str
        Authors and year.
    source : str
        Full citation of the formula, and where its transcription was checked.
    validity : str
        The range of e for which the source derived or recommends it.
    family : int
        Engine code of the force family (``force_family`` is its record).
    clamp : bool
        Whether the fruit separates as soon as the force would become tensile.
    published : callable or None
        The law's function of ``physics.laws``: e → the family's dimensionless damping
        group as published; None means undamped (λ = 0).
    note : str
        What else a user should know (aliases, unconfirmed transcriptions).
    exact_by_construction : bool
        The published calibration already gives the requested e exactly.
    """

    name: str
    title: str
    source: str
    validity: str
    family: int = forces.POWER_LAW
    clamp: bool = True
    published: Callable | None = None
    note: str = ""
    exact_by_construction: bool = False

    @property
    def force_family(self) -> ForceFamily:
        return FAMILIES[self.family]

    @property
    def undamped(self) -> bool:
        return self.published is None

    def linear_stiffness(self, mass, stiffness, velocity):
        """The stiffness the law's force uses: K for the Hertz-type laws, the
        Hertz-equivalent linear k for Kelvin–Voigt."""
        return self.force_family.elastic_stiffness(mass, stiffness, velocity)

    def group(self, factor, mass, stiffness, velocity):
        """The dimensionless damping group of a damping factor (``ForceFamily.to_group``)."""
        return self.force_family.to_group(factor, mass, stiffness, velocity)

    def from_group(self, group, mass, stiffness, velocity):
        """The damping factor of a dimensionless damping group (``ForceFamily.from_group``)."""
        return self.force_family.from_group(group, mass, stiffness, velocity)

    def published_damping_factor(self, restitution, mass, stiffness, velocity):
        """Damping factor (see ``impact.ContactLaw``) by the law's own formula."""
        if self.published is None:
            return np.zeros_like(np.asarray(restitution, dtype=float))
        return self.from_group(self.published(restitution), mass, stiffness, velocity)


_MACHADO = ("transcription as in Machado et al., Mech. Mach. Theory 53 (2012) 99-121, and in the public DyS code "
            "that follows it; the original was not available to check")

DAMPING_LAWS: dict[str, DampingLaw] = {}


def register(law: DampingLaw, *aliases: str) -> DampingLaw:
    """Add ``law`` to ``DAMPING_LAWS`` under its name and any aliases."""
    for key in (law.name, *aliases):
        DAMPING_LAWS[key] = law
    return law


register(DampingLaw(
    name="hertz", title="Hertz (undamped)",
    source="H. Hertz, J. reine angew. Math. 92 (1882) 156-171; apple paper eqs 7-9.",
    validity="e = 1 (elastic impact)", note="λ = 0; any restitution given is ignored."))
register(DampingLaw(
    name="hunt-crossley", title="Hunt & Crossley 1975",
    source=("K. H. Hunt, F. R. E. Crossley, Coefficient of restitution interpreted as damping in vibroimpact, "
            "J. Appl. Mech. 42 (1975) 440-445; apple paper eqs 5, 6, 11: λ = (3/2) α k_c with e = 1 - α v0 "
            "(as in Simbody's HuntCrossleyForce and Marhefka & Orin 1999)."),
    published=laws.hunt_crossley,
    validity="first order in (1 - e): e close to 1; gives e too high below 0.9"))
register(DampingLaw(
    name="herbert-mcwhannell", title="Herbert & McWhannell 1977",
    source=("R. G. Herbert, D. C. McWhannell, Shape and frequency composition of pulses from an impact pair, "
            "J. Eng. Ind. 99 (1977) 513-518; χ = 6(1-e)/((2e-1)² + 3); " + _MACHADO + "."),
    published=laws.herbert_mcwhannell,
    validity=("tends to Hunt-Crossley as e → 1; χ stays finite at e = 0, so achieved e never falls below 0.487 "
              "(χ(0) = 1.5)")))
register(DampingLaw(
    name="lee-wang", title="Lee & Wang 1983",
    source=("T. W. Lee, A. C. Wang, On the dynamics of intermittent-motion mechanisms, part 1, J. Mech. Transm. "
            "Autom. Des. 105 (1983) 534-540; χ = 3(1-e)/4; " + _MACHADO + "."),
    published=laws.lee_wang,
    validity="half the Hunt-Crossley damping even as e → 1 (achieved 1-e ≈ (1-target)/2): inconsistent with this "
             "force law; kept for comparison only"))
register(DampingLaw(
    name="chen", title="Lankarani & Nikravesh 1990 (the paper's 'Chen')",
    source=("H. M. Lankarani, P. E. Nikravesh, A contact force model with hysteresis damping for impact analysis "
            "of multibody systems, J. Mech. Des. 112 (1990) 369-376; apple paper eqs 21, 23 (attributed there to "
            "Chen & De Baerdemaeker 1995): λ = β = (3/4) k_c (1 - e²)/v0."),
    published=laws.lankarani_nikravesh,
    validity="first order in (1 - e), from the energy lost along the undamped path: e close to 1",
    note="The paper calls it 'Chen'; it is the Lankarani–Nikravesh form. Alias: lankarani-nikravesh."),
    "lankarani-nikravesh")
register(DampingLaw(
    name="gonthier", title="Gonthier, McPhee, Lange & Piedbœuf 2004",
    source=("Y. Gonthier, J. McPhee, C. Lange, J.-C. Piedbœuf, A regularized contact model with asymmetric damping "
            "and dwell-time dependent friction, Multibody Syst. Dyn. 11 (2004) 209-233; χ = (1 - e²)/e "
            "(confirmed in two public implementations)."),
    published=laws.gonthier,
    validity="all e in (0, 1]; over-damps slightly near e = 1 (target 0.9 gives 0.876)"))
register(DampingLaw(
    name="zhiying-qishao", title="Zhiying & Qishao 2006",
    source=("Q. Zhiying, L. Qishao, Analysis of impact process based on restitution coefficient, J. Dyn. Control "
            "4 (2006) 294-298; χ = 3(1 - e²) exp(2(1 - e))/4; " + _MACHADO + "."),
    published=laws.zhiying_qishao,
    validity=("good for e ≈ 0.4-0.9; χ finite at e = 0, so achieved e never falls below 0.178 "
              "(χ(0) = 0.75 exp 2 ≈ 5.54)")))
register(DampingLaw(
    name="flores", title="Flores, Machado, Silva & Martins 2011",
    source=("P. Flores, M. Machado, M. T. Silva, J. M. Martins, On the continuous contact force models for soft "
            "materials in multibody dynamics, Multibody Syst. Dyn. 25 (2011) 357-375; χ = 8(1 - e)/(5e) "
            "(confirmed in the OpenSees documentation and three public implementations)."),
    published=laws.flores,
    validity="derived for soft materials over the whole range of e; over-damps slightly (target 0.5 gives 0.470)"))
register(DampingLaw(
    name="hu-guo", title="Hu & Guo 2015",
    source=("S. Hu, X. Guo, A dissipative contact force model for impact analysis in multibody dynamics, "
            "Multibody Syst. Dyn. 35 (2015) 131-151; χ = 3(1 - e)/(2e)."),
    published=laws.hu_guo,
    validity="all e in (0, 1]",
    note="UNCONFIRMED transcription: the only public implementation found uses 3(1 - e)/(4e)."))
register(DampingLaw(
    name="gharib-hurmuzlu", title="Gharib & Hurmuzlu 2012",
    source=("M. Gharib, Y. Hurmuzlu, A new contact force model for low coefficient of restitution impact, "
            "J. Appl. Mech. 79 (2012) 064506; χ = (1 - e)/e."),
    published=laws.gharib_hurmuzlu,
    validity="meant for low e (matches the exact e → 1/χ limit); under-damps near e = 1",
    note="UNCONFIRMED transcription: no public source of the formula could be found."))
register(DampingLaw(
    name="exact", title="Exact inverse of the Hunt-Crossley first integral",
    source=("this package: χ solves (1 + χ) = (1 - e χ) exp((1 + e) χ), the exact restitution of "
            "F = K δ^n (1 + c δ̇) (first integral of Hunt & Crossley 1975; docs/physics.md)."),
    validity="all e in (0, 1]: the simulated restitution equals e", published=laws.exact_power_law,
    exact_by_construction=True))
for _clamp in (False, True):
    _suffix = "-clamped" if _clamp else ""
    register(DampingLaw(
        name="kelvin-voigt" + _suffix,
        title="Kelvin-Voigt linear spring-dashpot" + (" (force clamped at 0)" if _clamp else ""),
        source=("linear spring-dashpot F = k δ + b δ̇ with ζ = b/(2 sqrt(k m)) = -ln e/sqrt(π² + ln² e), exact for "
                "the unclamped law; clamped, the fruit separates when F = 0 (T. Schwager, T. Pöschel, Coefficient "
                "of restitution and linear-dashpot model revisited, Granular Matter 9 (2007) 465-469). k is the "
                "linear stiffness with the Hertz contact duration at this impact."),
        validity=("exact for every e when unclamped (but the force is b·v0 at first touch and tensile before "
                  "separation)" if not _clamp else
                  "the published ζ(e) assumes no clamp: clamped, the achieved e is higher (target 0.5 gives 0.55)"),
        family=forces.KELVIN_VOIGT, clamp=_clamp, published=laws.kelvin_voigt_damping_ratio,
        exact_by_construction=not _clamp))
    register(DampingLaw(
        name="tsuji" + _suffix,
        title="Tsuji, Tanaka & Ishida 1992" + (" (force clamped at 0)" if _clamp else ""),
        source=("Y. Tsuji, T. Tanaka, T. Ishida, Lagrangian numerical simulation of plug flow of cohesionless "
                "particles in a horizontal pipe, Powder Technol. 71 (1992) 239-250: F = K δ^1.5 + α sqrt(m K) "
                "δ^(1/4) δ̇ with α = -sqrt(5) ln e/sqrt(ln² e + π²), the form of YADE, Chrono DEM-Engine and MUSEN."),
        validity=("exact for every e and velocity when unclamped (δ^(5/4) makes it a linear oscillator)"
                  if not _clamp else "clamped at F ≥ 0 the achieved e is higher: target 0.2 gives 0.325, 0.5 gives "
                                     "0.550, for any mass, stiffness and velocity"),
        family=forces.TSUJI, clamp=_clamp, published=laws.tsuji_alpha, exact_by_construction=not _clamp))
    register(DampingLaw(
        name="kuwabara-kono" + ("" if _clamp else "-unclamped"),
        title="Kuwabara & Kono 1987 / Brilliantov et al. 1996" + ("" if _clamp else " (force may go tensile)"),
        source=("G. Kuwabara, K. Kono, Jpn. J. Appl. Phys. 26 (1987) 1230; N. V. Brilliantov et al., Model for "
                "collisions in granular gases, Phys. Rev. E 53 (1996) 5382-5392: F = K (δ^1.5 + B δ^0.5 δ̇), "
                "B calibrated by the first-order restitution e = 1 - 1.153449 B (K/m)^(2/5) v0^(1/5) "
                "(Schwager & Pöschel, Phys. Rev. E 78 (2008) 051304)."),
        validity="first order in b = B (K/m)^(2/5) v0^(1/5): b ≲ 0.1 (e ≳ 0.9); far off at apple-like e ≈ 0.5",
        family=forces.KUWABARA_KONO, clamp=_clamp, published=laws.kuwabara_kono_first_order,
        note="" if _clamp else "Without the clamp the force turns tensile before δ returns to 0."))


@dataclass(frozen=True)
class Calibration:
    """A rule turning a restitution coefficient into the law's damping."""

    name: str
    description: str


CALIBRATIONS: dict[str, Calibration] = {
    "paper": Calibration("paper", "the law's published formula (for hunt-crossley α = (1-k)/V_i, eq 6; for chen eq 21)"),
    "exact": Calibration("exact", "damping chosen so that the simulated restitution equals the requested one exactly"),
}


def get_law(name: str) -> DampingLaw:
    """The damping law registered as ``name``; ValueError naming the choices otherwise."""
    try:
        return DAMPING_LAWS[name]
    except KeyError:
        raise ValueError(f"model must be one of {', '.join(DAMPING_LAWS)}; got {name!r}") from None


def get_calibration(name: str) -> Calibration:
    """The calibration registered as ``name``; ValueError naming the choices otherwise."""
    try:
        return CALIBRATIONS[name]
    except KeyError:
        raise ValueError(f"calibration must be one of {', '.join(CALIBRATIONS)}; got {name!r}") from None
