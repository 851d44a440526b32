"""Registry of contact damping laws and of calibrations.

A *damping law* says how the damping of the contact follows from a
restitution coefficient e.  For the power-law family used by the paper,
F = K δ^(3/2) (1 + c δ̇) (eqs 11, 14, 23; λ = c·K is the paper's λ1 or β),
each published law is a closed form χ(e) = c·v0.  A *calibration* says
which e → c rule is applied: the law's own published formula (``paper``) or
the exact inverse of the achieved restitution (``exact``), which makes the
simulated restitution equal the requested one for every law of the family.

Add a law by adding a ``DampingLaw`` to ``DAMPING_LAWS``; nothing else needs
to change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from .engine import forces
from .engine.powerlaw import x_of_restitution


@dataclass(frozen=True)
class DampingLaw:
    """A published damping law of the power-law family F = K δ^n (1 + c δ̇).

    Attributes
    ----------
    name : str
        Registry key (CLI ``--model``).
    title : str
        Authors and year.
    source : str
        Full citation of the formula.
    chi : callable or None
        χ(e) = c·v0 [-] as published; None for the undamped Hertz law.
    validity : str
        The range of e for which the source derived or recommends it.
    note : str
        What else a user should know (aliases, transcription issues).
    """

    name: str
    title: str
    source: str
    chi: Callable[[float], float] | None
    validity: str
    note: str = ""
    family: int = field(default=forces.POWER_LAW, repr=False)

    def published_damping_factor(self, restitution: float, velocity: float) -> float:
        """c = χ(e)/v0 [s/m] by the law's own formula."""
        if self.chi is None:
            return 0.0
        return self.chi(restitution) / velocity


@dataclass(frozen=True)
class Calibration:
    """A rule turning a restitution coefficient into the damping factor c."""

    name: str
    description: str
    rule: Callable[[DampingLaw, float, float], float] = field(repr=False)

    def damping_factor(self, law: DampingLaw, restitution: float, velocity: float) -> float:
        """c [s/m] for ``law`` at restitution e and impact velocity v0 [m/s]."""
        if law.chi is None:  # undamped Hertz: nothing to calibrate
            return 0.0
        return self.rule(law, restitution, velocity)


def exact_damping_factor(restitution: float, velocity: float) -> float:
    """c [s/m] such that F = K δ^n (1 + c δ̇) rebounds with exactly e
    (root of (1 + x) = (1 - e x) exp((1 + e) x), x = c v0; docs/physics.md)."""
    return x_of_restitution(float(restitution)) / velocity


DAMPING_LAWS: dict[str, DampingLaw] = {
    "hertz": DampingLaw(
        name="hertz",
        title="Hertz (undamped)",
        source="H. Hertz, J. reine angew. Math. 92 (1882) 156-171; apple paper eq 7-9.",
        chi=None,
        validity="e = 1 (elastic impact)",
        note="λ = 0; any restitution given is ignored.",
    ),
    "hunt-crossley": DampingLaw(
        name="hunt-crossley",
        title="Hunt & Crossley 1975",
        source=("K. H. Hunt, F. R. E. Crossley, Coefficient of restitution interpreted as damping in "
                "vibroimpact, J. Appl. Mech. 42 (1975) 440-445; apple paper eqs 5, 6, 11: "
                "λ = (3/2) α k_c with e = 1 - α v0."),
        chi=lambda e: 1.5 * (1.0 - e),
        validity="first order in (1 - e): e close to 1; gives e too high for e < 0.9",
    ),
    "chen": DampingLaw(
        name="chen",
        title="Lankarani & Nikravesh 1990 (the paper's 'Chen')",
        source=("H. M. Lankarani, P. E. Nikravesh, A contact force model with hysteresis damping for impact "
                "analysis of multibody systems, J. Mech. Des. 112 (1990) 369-376; apple paper eqs 21, 23 "
                "(attributed there to Chen & De Baerdemaeker 1995): λ = β = (3/4) k_c (1 - e²)/v0."),
        chi=lambda e: 0.75 * (1.0 - e * e),
        validity="first order in (1 - e): e close to 1",
        note="The paper calls it 'Chen'; it is the Lankarani–Nikravesh form. Alias: lankarani-nikravesh.",
    ),
}
DAMPING_LAWS["lankarani-nikravesh"] = DAMPING_LAWS["chen"]

CALIBRATIONS: dict[str, Calibration] = {
    "paper": Calibration(
        name="paper",
        description="the law's published formula (for hunt-crossley α = (1-k)/V_i, eq 6; for chen eq 21)",
        rule=lambda law, e, v: law.published_damping_factor(e, v),
    ),
    "exact": Calibration(
        name="exact",
        description="λ chosen so that the simulated restitution equals the requested one exactly",
        rule=lambda law, e, v: exact_damping_factor(e, v),
    ),
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
