"""The friendly single-impact API: fruit, surface, impact result.

>>> from fruitimpact import Fruit, simulate
>>> result = simulate(Fruit(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37),
...                   velocity=1.0, restitution=0.577)
>>> round(result.characteristics.restitution, 6)
0.577

Everything is SI.  Inputs are validated here (``ValueError`` with the CLI's
message); the numeric engine below takes plain floats.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from functools import cached_property

import numpy as np

from . import contact
from .calibrate import damping_factor as calibrated_damping_factor
from .calibrate import law_params
from .constants import (JONATHAN_APPLE, JONATHAN_RESTITUTION, JONATHAN_VELOCITY,
                        STANDARD_GRAVITY)
from .engine import forces
from .models import get_calibration, get_law
from .solvers import get_solver, max_rk4_step
from .validation import check_exclusive, check_positive, check_range


@dataclass(frozen=True)
class Fruit:
    """A fruit, locally a sphere at the contact point.

    Attributes
    ----------
    mass : float
        M [kg].
    diameter : float
        d [m]; the local contact radius is d/2.
    modulus : float
        Young's modulus E of the flesh [Pa].
    poisson : float
        Poisson's ratio ν [-], in (-1, 0.5).
    stiffness : float or None
        Contact stiffness k_c [N/m^1.5] given directly; overrides the Hertz
        value from E, ν, d (eq 9).
    """

    mass: float = JONATHAN_APPLE["mass"]
    diameter: float = JONATHAN_APPLE["diameter"]
    modulus: float = JONATHAN_APPLE["modulus"]
    poisson: float = JONATHAN_APPLE["poisson"]
    stiffness: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "mass", check_positive("mass", self.mass, "kg"))
        object.__setattr__(self, "diameter", check_positive("diameter", self.diameter, "m"))
        object.__setattr__(self, "modulus", check_positive("modulus", self.modulus, "Pa"))
        object.__setattr__(self, "poisson", check_range("poisson", self.poisson, -1.0, 0.5))
        if self.stiffness is not None:
            object.__setattr__(self, "stiffness", check_positive("stiffness", self.stiffness, "N/m^1.5"))

    @property
    def radius(self) -> float:
        """Local radius of curvature at the contact, d/2 [m]."""
        return self.diameter / 2.0


@dataclass(frozen=True)
class Surface:
    """The surface the fruit hits; the default is rigid and flat.

    Attributes
    ----------
    modulus : float
        Young's modulus [Pa]; ``inf`` is rigid.
    poisson : float
        Poisson's ratio [-].
    radius : float
        Radius of curvature [m]; ``inf`` is a plane.
    """

    modulus: float = math.inf
    poisson: float = 0.0
    radius: float = math.inf

    def __post_init__(self):
        object.__setattr__(self, "modulus", check_range("surface modulus", self.modulus, 0.0, math.inf,
                                                        high_inclusive=True, unit="Pa"))
        object.__setattr__(self, "poisson", check_range("surface poisson", self.poisson, -1.0, 0.5))
        object.__setattr__(self, "radius", check_range("surface radius", self.radius, 0.0, math.inf,
                                                       high_inclusive=True, unit="m"))


RIGID_PLANE = Surface()


#: Per force family: (stiffness symbol, unit), (damping symbol, unit), damping-factor unit.
FAMILY_UNITS = {
    forces.POWER_LAW: (("k_c", "N/m^1.5"), ("λ", "N·s/m^2.5"), "s/m"),
    forces.KELVIN_VOIGT: (("k", "N/m"), ("b", "N·s/m"), "s"),
    forces.KUWABARA_KONO: (("K", "N/m^1.5"), ("K·B", "N·s/m^1.5"), "s"),
    forces.TSUJI: (("K", "N/m^1.5"), ("η", "N·s/m^1.25"), "s·m^0.25"),
}


@dataclass(frozen=True)
class ContactLaw:
    """The resolved force law of one impact.

    Attributes
    ----------
    stiffness : float
        The elastic coefficient: k_c = K [N/m^1.5] for the Hertz-type laws, the
        linear k [N/m] for Kelvin–Voigt.
    damping_factor : float
        damping/stiffness: c = λ/k_c [s/m] for F = K δ^n (1 + c δ̇); b/k [s] for
        Kelvin–Voigt; B [s] for Kuwabara–Kono; η/K [s·m^0.25] for Tsuji.
    exponent : float
        n [-] of the power-law family (3/2, Hertz).
    family : int
        Force family code of ``engine.forces``.
    clamp : bool
        Whether the fruit separates as soon as the force would become tensile.
    """

    stiffness: float
    damping_factor: float
    exponent: float = 1.5
    family: int = forces.POWER_LAW
    clamp: bool = True

    @property
    def damping(self) -> float:
        """Coefficient of the rate term: λ [N·s/m^2.5] (F_d = λ δ^1.5 δ̇; the paper's
        λ1, A or β), b [N·s/m] (Kelvin–Voigt), K·B (Kuwabara–Kono), η (Tsuji)."""
        return self.damping_factor * self.stiffness

    @property
    def units(self) -> tuple:
        """((stiffness symbol, unit), (damping symbol, unit), damping-factor unit) of this family."""
        return FAMILY_UNITS[self.family]

    def params(self) -> np.ndarray:
        """Parameter vector for the compiled force of ``family``."""
        return law_params(self.family, self.stiffness, self.damping_factor, self.exponent)


@dataclass(frozen=True)
class ImpactInputs:
    """Everything that defines one impact, validated, SI."""

    fruit: Fruit
    surface: Surface
    velocity: float
    drop_height: float | None
    restitution: float | None
    alpha: float | None
    model: str
    calibration: str
    method: str
    step: float

    @property
    def target_restitution(self) -> float | None:
        """The restitution the damping was calibrated for: k, or 1 - α V_i (eq 6)."""
        if self.alpha is not None:
            return 1.0 - self.alpha * self.velocity
        return self.restitution


@dataclass(frozen=True)
class Characteristics:
    """Characteristics of one impact (SI).

    peak_force F_max [N]; time_to_peak t_c [s]; contact_duration T [s];
    max_deflection δ_max [m]; time_to_max_deflection [s]; exit_velocity
    (rebound speed, away from the surface) [m/s]; restitution e [-];
    absorbed_energy ½ m v0² (1 - e²) [J]; firmness_c C = F_max/t_c [N/s]
    (eqs 1, 28); firmness_c_star C* = F_max/t_c² [N/s²] (eq 2); max_pressure,
    the largest Hertz centre pressure 3F/(2π R δ) during the contact [Pa];
    contact_radius a = sqrt(R δ_max) [m]; max_deflection_closed_form and
    restitution_closed_form, the first-integral values for the power-law
    family (a self-check beside the solver's numbers; NaN otherwise).
    """

    peak_force: float
    time_to_peak: float
    contact_duration: float
    max_deflection: float
    time_to_max_deflection: float
    exit_velocity: float
    restitution: float
    absorbed_energy: float
    firmness_c: float
    firmness_c_star: float
    max_pressure: float
    contact_radius: float
    max_deflection_closed_form: float = math.nan
    restitution_closed_form: float = math.nan

    def as_dict(self) -> dict[str, float]:
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}


@dataclass(frozen=True)
class Curves:
    """Time histories of one impact: t [s], δ [m], δ̇ [m/s], F [N] (paper Figs 4–7)."""

    time: np.ndarray
    deflection: np.ndarray
    rate: np.ndarray
    force: np.ndarray

    def to_dataframe(self):
        """The curves as a pandas DataFrame with unit-suffixed column names."""
        import pandas as pd

        return pd.DataFrame({"time_s": self.time, "deflection_m": self.deflection,
                             "rate_m_per_s": self.rate, "force_N": self.force})

    def to_csv(self, path) -> None:
        """Write the curves as CSV (columns time_s, deflection_m, rate_m_per_s, force_N)."""
        header = "time_s,deflection_m,rate_m_per_s,force_N"
        np.savetxt(path, np.column_stack([self.time, self.deflection, self.rate, self.force]),
                   delimiter=",", header=header, comments="", fmt="%.12g")


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of ``simulate``: inputs, resolved force law, characteristics,
    curves (computed on first access), and a success flag with a message."""

    inputs: ImpactInputs
    law: ContactLaw
    characteristics: Characteristics
    success: bool = True
    message: str = "ok"
    curve_points: int = field(default=1001, repr=False)

    @cached_property
    def curves(self) -> Curves:
        """δ(t), δ̇(t), F(t) over the contact, from the same solver."""
        solver = get_solver(self.inputs.method)
        return Curves(*solver.curves(self.law, self.inputs.fruit.mass, self.inputs.velocity,
                                     self.inputs.step, self.curve_points))

    def to_dict(self) -> dict:
        """Flat JSON-ready dict: characteristics, stiffness, damping, inputs (SI)."""
        inputs = self.inputs
        fruit = asdict(inputs.fruit)
        flat = dict(self.characteristics.as_dict())
        flat.update(
            stiffness=self.law.stiffness,
            damping=self.law.damping,
            damping_factor=self.law.damping_factor,
            stiffness_unit=self.law.units[0][1],
            damping_unit=self.law.units[1][1],
            mass=fruit["mass"], diameter=fruit["diameter"], modulus=fruit["modulus"],
            poisson=fruit["poisson"], velocity=inputs.velocity, drop_height=inputs.drop_height,
            target_restitution=inputs.target_restitution, alpha=inputs.alpha,
            model=inputs.model, calibration=inputs.calibration, method=inputs.method,
            step=inputs.step,
            success=self.success, message=self.message,
        )
        flat["inputs"] = {"fruit": fruit, "surface": asdict(inputs.surface),
                          "velocity": inputs.velocity, "drop_height": inputs.drop_height,
                          "restitution": inputs.restitution, "alpha": inputs.alpha,
                          "model": inputs.model, "calibration": inputs.calibration,
                          "method": inputs.method, "step": inputs.step}
        return flat


def impact_velocity(drop_height: float) -> float:
    """Free-fall impact velocity v = sqrt(2 g h) [m/s] from a drop height h [m]
    (no air drag; below 1 m drag changes v by < 0.5 % for an apple)."""
    return math.sqrt(2.0 * STANDARD_GRAVITY * drop_height)


def resolve_stiffness(fruit: Fruit, surface: Surface = RIGID_PLANE) -> tuple[float, float]:
    """(k_c [N/m^1.5], effective radius R [m]) of the fruit on the surface."""
    radius = float(contact.effective_radius(fruit.radius, surface.radius))
    if fruit.stiffness is not None:
        return fruit.stiffness, radius
    e_star = float(contact.effective_modulus(fruit.modulus, fruit.poisson, surface.modulus, surface.poisson))
    return float(contact.hertz_stiffness(e_star, radius)), radius


def prepare(fruit: Fruit | None = None, *, velocity=None, drop_height=None, restitution=None,
            alpha=None, model: str = "hunt-crossley", calibration: str = "exact",
            method: str = "accurate", step: float = 1e-4,
            surface: Surface | None = None) -> tuple[ImpactInputs, ContactLaw, float]:
    """Validate the inputs of one impact and resolve its force law.

    Returns (inputs, law, effective radius [m]).  Raises ValueError with the
    CLI's one-line message on bad input."""
    fruit = fruit if fruit is not None else Fruit()
    surface = surface if surface is not None else RIGID_PLANE
    check_exclusive("velocity", velocity, "drop_height", drop_height)
    check_exclusive("restitution", restitution, "alpha", alpha)
    law = get_law(model)
    cal = get_calibration(calibration)
    get_solver(method)
    step = check_positive("step", step, "s")
    if drop_height is not None:
        drop_height = check_positive("drop_height", drop_height, "m")
        velocity = impact_velocity(drop_height)
    elif velocity is None:
        velocity = JONATHAN_VELOCITY
    velocity = check_positive("velocity", velocity, "m/s")
    if alpha is not None:
        alpha = check_range("alpha", alpha, 0.0, 1.0 / velocity, low_inclusive=True,
                            unit="s/m (so that k = 1 - alpha*V_i is in (0, 1])")
        target = 1.0 - alpha * velocity
    else:
        if restitution is None:
            restitution = JONATHAN_RESTITUTION
        restitution = check_range("restitution", restitution, 0.0, 1.0, high_inclusive=True)
        target = restitution
    stiffness, radius = resolve_stiffness(fruit, surface)
    if method == "rk4":
        step = check_range("step", step, 0.0, float(max_rk4_step(fruit.mass, stiffness, velocity)),
                           high_inclusive=True, unit="s for this impact (at least 20 steps per contact)")
    factor = float(calibrated_damping_factor(law, cal.name, target, fruit.mass, stiffness, velocity))
    inputs = ImpactInputs(fruit=fruit, surface=surface, velocity=velocity, drop_height=drop_height,
                          restitution=restitution, alpha=alpha, model=law.name, calibration=cal.name,
                          method=method, step=step)
    force_law = ContactLaw(stiffness=float(law.linear_stiffness(fruit.mass, stiffness, velocity)),
                           damping_factor=factor, family=law.family, clamp=law.clamp)
    return inputs, force_law, radius


def simulate(fruit: Fruit | None = None, *, velocity=None, drop_height=None, restitution=None,
             alpha=None, model: str = "hunt-crossley", calibration: str = "exact",
             method: str = "accurate", step: float = 1e-4, surface: Surface | None = None,
             curve_points: int = 1001) -> ImpactResult:
    """Simulate one impact of ``fruit`` on ``surface``.

    Parameters
    ----------
    fruit : Fruit, optional
        Default: the paper's Jonathan apple (``constants.JONATHAN_SOURCE``).
    velocity : float, optional
        Impact velocity V_i [m/s]; default 1 m/s.
    drop_height : float, optional
        Drop height h [m], instead of ``velocity``: V_i = sqrt(2 g h).
    restitution : float, optional
        Restitution coefficient k in (0, 1] (eq 3); default 0.577.
    alpha : float, optional
        Hunt–Crossley α [s/m] instead of k: k = 1 - α V_i (eq 6).
    model : str
        Damping law, a key of ``models.DAMPING_LAWS`` (``hertz``,
        ``hunt-crossley``, ``chen``, ...).
    calibration : str
        ``exact`` (default): λ such that the simulated restitution equals k;
        ``paper``: the law's published formula (eq 6 with eq 5, or eq 21).
    method : str
        ``accurate`` (default, exact end of contact) or ``rk4`` (the paper's
        fixed-step integration at ``step`` [s]).
    surface : Surface, optional
        Default rigid plane.
    curve_points : int
        Samples of the ``accurate`` curves over [0, T].

    Returns
    -------
    ImpactResult
        ``success`` is False (with a message) if the solver failed; inputs
        that are out of range raise ``ValueError`` instead.
    """
    inputs, law, radius = prepare(fruit, velocity=velocity, drop_height=drop_height,
                                  restitution=restitution, alpha=alpha, model=model,
                                  calibration=calibration, method=method, step=step, surface=surface)
    solver = get_solver(method)
    values, success, message = solver.characteristics(law, inputs.fruit.mass, inputs.velocity, radius, step)
    closed = solver.closed_forms(law, inputs.fruit.mass, inputs.velocity)
    characteristics = Characteristics(*values, *closed)
    return ImpactResult(inputs=inputs, law=law, characteristics=characteristics, success=success,
                        message=message, curve_points=curve_points)
