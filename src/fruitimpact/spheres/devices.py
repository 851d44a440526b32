"""The instrumented sphere: its mass, size and contact stiffness, and the built-in device profiles.

A reading converts to an impact only through the body that made it.  The Hertz contact of a sphere of
radius R on a half-space is F = K δ^1.5 with K = (4/3) E* √R and 1/E* = 1/E*_s + (1 − ν_w²)/E_w
(Johnson 1985, eqs 4.22–4.23): the sphere enters through its own contact modulus E*_s = E_s/(1 − ν_s²)
alone, which is what a calibration on a rigid plate measures (``spheres.calibration``).

Profiles: the published devices are not described to their stiffness.  What a source gives is kept
(mass and diameter); the stiffness then comes from ``--sphere-modulus``/``--sphere-poisson`` or from a
calibration, and a profile without either is refused, never completed with a guess.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType


@dataclass(frozen=True)
class SphereDevice:
    """A device profile: what a source publishes of it.

    Attributes
    ----------
    name, description, source : str
    mass : float
        [kg].
    diameter : float
        [m].
    """

    name: str
    description: str
    mass: float
    diameter: float
    source: str


#: Built-in profiles (the sources in ``source``; background: docs/tasks/sphere.md).
DEVICES = MappingProxyType({device.name: device for device in (
    SphereDevice("is-1987", "Instrumented Sphere (apple handling, 1987): electronics cast in beeswax", 0.312, 0.089,
                 "\"Apple handling impact data acquisition and analysis with an instrumented sphere\" (1987): "
                 "89 mm, 312 g"),
    SphereDevice("is-nz", "Instrumented Sphere of the New Zealand apple-line studies", 0.336, 0.089,
                 "Pang, Studman & Banks 1992, NZ J. Crop Hortic. Sci. 20:159-166: 89 mm, 336 g"),
)})


@dataclass(frozen=True)
class Sphere:
    """The sphere a log was recorded with.

    Attributes
    ----------
    mass : float
        m [kg].
    diameter : float
        d [m]; the contact radius on a flat surface is d/2.
    contact_modulus : float
        E*_s = E_s/(1 − ν_s²) [Pa], its own share of the Hertz contact modulus.
    name : str
        The device profile, or ``"custom"``.
    stiffness_source : str
        Where ``contact_modulus`` comes from (the options, or the calibration and its fit).
    contact_modulus_sd : float
        Relative standard uncertainty of ``contact_modulus`` [-]: a calibration's (0 for a value given).
    """

    mass: float
    diameter: float
    contact_modulus: float
    name: str = "custom"
    stiffness_source: str = "--sphere-modulus and --sphere-poisson"
    contact_modulus_sd: float = 0.0

    @property
    def radius(self) -> float:
        return self.diameter / 2.0

    def surface_compliance(self, contact_modulus):
        """(1 − ν_w²)/E_w [1/Pa] of the surface whose contact with the sphere has ``contact_modulus`` E* [Pa]."""
        return 1.0 / contact_modulus - 1.0 / self.contact_modulus

    def contact_modulus_on(self, surface_modulus, surface_poisson):
        """E* [Pa] of the sphere on a half-space of ``surface_modulus`` [Pa] (``inf``: rigid)."""
        return 1.0 / (1.0 / self.contact_modulus + (1.0 - surface_poisson ** 2) / surface_modulus)


def build_sphere(*, device: str | None = None, mass=None, diameter=None, modulus=None, poisson=None,
                 calibrated_modulus: float | None = None, calibration_source: str = "",
                 calibrated_sd: float = 0.0) -> Sphere:
    """The sphere from a profile and/or explicit values (explicit values win over the profile's).

    ``calibrated_modulus``: E*_s [Pa] fitted by a calibration, with its relative standard uncertainty
    ``calibrated_sd`` (then ``modulus``/``poisson`` must not be given: two stiffnesses for one sphere).  ``InputError`` naming the option that is missing or out of range."""
    from fruitimpact.impact.validation import InputError, check_number

    if device is not None and device not in DEVICES:
        raise InputError(f"sphere must be one of {', '.join(DEVICES)}; got {device!r}", "sphere")
    profile = DEVICES.get(device)
    mass = mass if mass is not None else (profile.mass if profile else None)
    diameter = diameter if diameter is not None else (profile.diameter if profile else None)
    for name, value in (("sphere_mass", mass), ("sphere_diameter", diameter)):
        if value is None:
            raise InputError(f"{name} is needed: give --{name.replace('_', '-')} or --sphere NAME "
                             f"({', '.join(DEVICES)})", name)
    mass = check_number("sphere_mass", mass, low=0.001, high=10.0, high_inclusive=True)
    diameter = check_number("sphere_diameter", diameter, low=0.005, high=0.5, high_inclusive=True)
    if calibrated_modulus is not None:
        if modulus is not None or poisson is not None:
            raise InputError("sphere_modulus: give either the sphere's modulus (--sphere-modulus, --sphere-poisson) "
                             "or a calibration (--sphere-calibration), not both", "sphere_modulus")
        return Sphere(mass, diameter, calibrated_modulus, device or "custom", calibration_source, calibrated_sd)
    if modulus is None or poisson is None:
        missing = "sphere_modulus" if modulus is None else "sphere_poisson"
        raise InputError(f"{missing} is needed: the sphere's stiffness is not published for "
                         f"{'the ' + device + ' profile' if device else 'a custom sphere'}; give --sphere-modulus "
                         f"and --sphere-poisson, or --sphere-calibration FILE (drops onto a rigid plate)", missing)
    modulus = check_number("sphere_modulus", modulus, low=1e4, high=1e12, high_inclusive=True)
    poisson = check_number("sphere_poisson", poisson, low=-1.0, low_inclusive=False, high=0.5, high_inclusive=True)
    return Sphere(mass, diameter, modulus / (1.0 - poisson ** 2), device or "custom")


__all__ = ["DEVICES", "Sphere", "SphereDevice", "build_sphere"]
