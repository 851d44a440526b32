"""The registries that the text inputs name (``quantities.Quantity.choices``):
``--model`` (damping laws), ``--calibration``, ``--method`` (solvers), ``--fruit`` and
``--surface`` (the libraries), ``--surface-model`` and ``--criterion``.
Importing this module compiles nothing."""

from __future__ import annotations

from types import MappingProxyType

from fruitimpact.library import catalogue as library
from fruitimpact.physics import CALIBRATIONS, DAMPING_LAWS
from fruitimpact.impact.solvers import SOLVERS

#: ``--surface``: ``rigid`` (the default: the surface options as given, a rigid flat unless told otherwise)
#: and the library's surfaces.
SURFACE_CHOICES = MappingProxyType({"rigid": None, **library.surfaces()})
#: ``--surface-model``: ``preset`` takes the ``--surface``'s model.
SURFACE_MODELS = MappingProxyType({
    "preset": "the --surface's model (half-space when no library surface is named)",
    "half-space": "Hertz contact through E* and R (Johnson 1985, §4.2)",
    "layer": "elastic-foundation (Winkler) layer of thickness h on a rigid substrate, in series with the fruit",
})
#: ``--criterion``: bruise onset criteria (``damage.bruise.CRITERIA``) and ``none``.
CRITERION_CHOICES = MappingProxyType({
    "none": "no bruise assessment",
    "pressure": "peak contact pressure p_0 >= failure stress σ_f",
    "shear": "largest subsurface shear stress τ_max >= σ_f / 2 (Tresca, Hertz's field for the fruit's ν)",
    "energy": "energy absorbed by the fruit >= threshold W_th",
    "preset": "the criterion the literature supports for the --fruit (fruitimpact fruits: apple shear, potato "
              "pressure); refused for a fruit without one",
})

#: ``--bruise-basis``: the energy a given bruise susceptibility and threshold energy were measured on.
BRUISE_BASES = MappingProxyType({
    "absorbed": "the energy the fruit absorbs, ½ m V² (1 − e²) (its share on a compliant surface)",
    "impact": "the impact energy ½ m V² (its share on a compliant surface), as in pendulum studies",
})

REGISTRIES = {"model": DAMPING_LAWS, "calibration": CALIBRATIONS, "method": SOLVERS,
              "fruit": library.fruits(), "surface": SURFACE_CHOICES, "surface_model": SURFACE_MODELS,
              "criterion": CRITERION_CHOICES, "bruise_basis": BRUISE_BASES}

__all__ = ["BRUISE_BASES", "CRITERION_CHOICES", "REGISTRIES", "SURFACE_CHOICES", "SURFACE_MODELS"]
