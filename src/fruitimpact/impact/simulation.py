"""The friendly single-impact API: fruit, surface, impact result.

>>> from fruitimpact import Fruit, simulate
>>> result = simulate(Fruit(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37),
...                   velocity=1.0, restitution=0.577)
>>> round(result.characteristics.restitution, 6)
0.577

Everything is SI; strings with units are accepted too (``Fruit(mass="115g")``).
``simulate()`` is ``impact.evaluation.evaluate`` of one row: the same validation (a
``ValueError`` with the CLI's message, naming the argument), the same
kernels and the same judgement of the result (``status``, ``message``,
``warnings``).  The common case (an ok impact with no warning) is answered by
``impact.single`` without the table's bookkeeping, 30 times faster, with the
same result to the bit (``tests/test_single.py``); every other call takes the
table path.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from functools import cached_property

import numpy as np

from fruitimpact.physics.calibrate import law_params
from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.engine import forces
from fruitimpact.physics import FAMILIES, ForceFamily
from fruitimpact.impact.quantities import INPUTS
from fruitimpact.impact.status import STATUS_NAMES
from fruitimpact.impact.validation import InputError, check_choice, check_value, read_value


_FIELD_NAMES: dict = {}


def _unvalidated(cls, values: dict):
    """An instance of the frozen dataclass ``cls`` whose values were validated already (by the table, or by
    ``impact.single``): every field from ``values`` (None where absent), without ``__init__``'s checks."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(item.name for item in fields(cls))
    instance = object.__new__(cls)
    instance.__dict__.update({name: values.get(name) for name in names})  # frozen: no __setattr__ per field
    return instance


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

    Values may be strings with units (``"115g"``); out-of-range values raise
    ``ValueError`` with the same one line as the CLI (``quantities.INPUTS``).
    """

    mass: float = INPUTS["mass"].default
    diameter: float = INPUTS["diameter"].default
    modulus: float = INPUTS["modulus"].default
    poisson: float = INPUTS["poisson"].default
    stiffness: float | None = None

    def __post_init__(self):
        for item in fields(self):
            value = getattr(self, item.name)
            if value is not None or item.name != "stiffness":
                object.__setattr__(self, item.name, check_value(item.name, value))

    @classmethod
    def _checked(cls, **values) -> "Fruit":
        """A Fruit of values that have just passed the same checks (no second validation)."""
        return _unvalidated(cls, values)

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
    thickness : float
        Thickness h [m] of a cushion on a rigid substrate (``inf``: a half-space); with
        ``surface_model="layer"`` the elastic-foundation model of ``engine.plastic``.
    crush_stress : float
        Flat-crush strength σ_c [Pa] of a layer that crushes (corrugated board; ``inf``: it does not),
        ``engine.plastic.crushing_characteristics``.
    """

    modulus: float = INPUTS["surface_modulus"].default
    poisson: float = INPUTS["surface_poisson"].default
    radius: float = INPUTS["surface_radius"].default
    thickness: float = INPUTS["surface_thickness"].default
    crush_stress: float = INPUTS["surface_crush_stress"].default

    def __post_init__(self):
        for item in fields(self):
            object.__setattr__(self, item.name, check_value("surface_" + item.name, getattr(self, item.name)))


    @classmethod
    def _checked(cls, **values) -> "Surface":
        """A Surface of values that have just passed the same checks (no second validation)."""
        return _unvalidated(cls, values)


RIGID_PLANE = Surface()


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
        Force family code of ``engine.forces`` (``force_family`` is its record).
    clamp : bool
        Whether the fruit separates as soon as the force would become tensile.
    """

    stiffness: float
    damping_factor: float
    exponent: float = 1.5
    family: int = forces.POWER_LAW
    clamp: bool = True

    @property
    def force_family(self) -> ForceFamily:
        return FAMILIES[self.family]

    @property
    def damping(self) -> float:
        """Coefficient of the rate term: λ [N·s/m^2.5] (F_d = λ δ^1.5 δ̇; the paper's
        λ1, A or β), b [N·s/m] (Kelvin–Voigt), K·B (Kuwabara–Kono), η (Tsuji)."""
        return self.damping_factor * self.stiffness

    @property
    def units(self) -> tuple:
        """((stiffness symbol, unit), (damping symbol, unit), damping-factor unit) of this family."""
        return self.force_family.units

    def params(self) -> np.ndarray:
        """Parameter vector for the compiled force of ``family``."""
        return law_params(self.family, self.stiffness, self.damping_factor, self.exponent)


@dataclass(frozen=True)
class ImpactInputs:
    """Everything that defines one impact, validated, SI.  ``velocity`` is the impact
    velocity as used (from ``drop_height`` when that was given); ``restitution``,
    ``alpha`` and ``damping`` are as given (at most one), None when not."""

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
    damping: float | None = None
    target_restitution: float | None = None


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

    def to_csv(self, path, argument: str = "path") -> None:
        """Write the curves as CSV (columns time_s, deflection_m, rate_m_per_s, force_N), checked
        first and written atomically (``outputs``); ``ValueError`` naming ``argument`` otherwise."""
        from fruitimpact.impact.outputs import CSV_FORMAT, atomic_write, check_output

        check_output(path, argument, CSV_FORMAT)
        header = "time_s,deflection_m,rate_m_per_s,force_N"
        table = np.column_stack([self.time, self.deflection, self.rate, self.force])
        atomic_write(path, lambda tmp: np.savetxt(tmp, table, delimiter=",", header=header, comments="",
                                                  fmt="%.12g"), argument)


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of ``simulate``: inputs, resolved force law, characteristics, curves
    (computed on first access), the ``status`` (ok, inaccurate, failed), a
    ``message`` saying what went wrong and by how much, and ``warnings``
    (implausible inputs, a contact beyond Hertz's range)."""

    inputs: ImpactInputs
    law: ContactLaw
    characteristics: Characteristics
    status: str = "ok"
    message: str = "ok"
    warnings: tuple = ()
    curve_points: int = field(default=1001, repr=False)
    damage: dict = field(default_factory=dict)
    names: dict = field(default_factory=dict)
    damage_inputs: dict = field(default_factory=dict)
    plastic: bool = False
    plastic_arguments: dict = field(default_factory=dict, repr=False)

    @property
    def success(self) -> bool:
        """True when the status is ok (physical and within the method's accuracy)."""
        return self.status == "ok"

    @cached_property
    def curves(self) -> Curves:
        """δ(t), δ̇(t), F(t) over the contact, from the same solver (the RK4 grid for rk4)."""
        from fruitimpact.physics import get_law
        from fruitimpact.impact.solvers import get_solver

        if not math.isfinite(self.characteristics.contact_duration):
            raise ValueError(f"no curves: the impact {self.status} ({self.message})")
        if self.plastic:  # elastic-plastic or layered: the plastic engine's own curves
            from fruitimpact.engine.plastic import plastic_curves

            return Curves(*plastic_curves(self.curve_points, **self.plastic_arguments))
        solver = get_solver(self.inputs.method)
        law = get_law(self.inputs.model)
        # the mass that moves: the reduced mass m m2/(m + m2) against a free partner (the characteristics' own)
        return Curves(*solver.samples(law, self.law.stiffness, self.law.damping_factor, self.plastic_arguments["mass"],
                                      self.inputs.velocity, self.inputs.step, self.curve_points,
                                      self.characteristics.contact_duration))

    def to_dict(self) -> dict:
        """Flat JSON-ready dict: characteristics, stiffness, damping, inputs (SI), status,
        message, warnings."""
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
            success=self.success, status=self.status, message=self.message, warnings=list(self.warnings),
        )
        flat.update(self.damage)
        flat.update(self.damage_inputs)
        flat.update(self.names)
        flat["inputs"] = {"fruit": fruit, "surface": asdict(inputs.surface),
                          "velocity": inputs.velocity, "drop_height": inputs.drop_height,
                          "restitution": inputs.restitution, "alpha": inputs.alpha, "damping": inputs.damping,
                          "model": inputs.model, "calibration": inputs.calibration,
                          "method": inputs.method, "step": inputs.step}
        return flat


def impact_velocity(drop_height: float) -> float:
    """Free-fall impact velocity v = sqrt(2 g h) [m/s] from a drop height h [m]
    (no air drag; below 1 m drag changes v by < 0.5 % for an apple)."""
    return math.sqrt(2.0 * STANDARD_GRAVITY * drop_height)


def resolve_stiffness(fruit: Fruit, surface: Surface = RIGID_PLANE) -> tuple[float, float]:
    """(k_c [N/m^1.5], effective radius R [m]) of the fruit on the surface."""
    from fruitimpact.physics import hertz as contact

    radius = float(contact.effective_radius(fruit.radius, surface.radius))
    if fruit.stiffness is not None:
        return fruit.stiffness, radius
    e_star = float(contact.effective_modulus(fruit.modulus, fruit.poisson, surface.modulus, surface.poisson))
    return float(contact.hertz_stiffness(e_star, radius)), radius


def _row(fruit, surface, keywords: dict) -> dict:
    """The one-row table of a ``simulate`` call, every value checked to be a single value.
    ``fruit`` and ``surface`` are objects (their fields are inputs) or library names."""
    row = {}
    if isinstance(fruit, str):
        keywords = {"fruit": fruit, **keywords}
    elif isinstance(fruit, Fruit):
        row.update({name: [value] for name, value in asdict(fruit).items() if value is not None})
    elif fruit is not None:
        raise InputError(f"fruit must be a Fruit, a fruit of the library (fruitimpact fruits) or None for the "
                         f"paper's Jonathan apple; got {fruit!r}", "fruit")
    if isinstance(surface, str):
        keywords = {"surface": surface, **keywords}
    elif isinstance(surface, Surface):
        # a crush stress of inf is "does not crush", the default: given, it would be refused off a layer
        row.update({"surface_" + name: [value] for name, value in asdict(surface).items()
                    if not (name == "crush_stress" and math.isinf(value))})
    elif surface is not None:
        raise InputError(f"surface must be a Surface, a surface of the library (fruitimpact surfaces) or None for "
                         f"a rigid plane; got {surface!r}", "surface")
    from fruitimpact.impact.registries import REGISTRIES

    for name, value in keywords.items():
        if name not in INPUTS:
            raise InputError(f"unknown input {name!r} (inputs: {', '.join(INPUTS)})", name)
        if name in REGISTRIES:
            row[name] = [check_choice(name, value, REGISTRIES[name])]
        elif value is not None:
            row[name] = [read_value(name, value)]
    return row


def simulate(fruit: Fruit | str | None = None, *, velocity=None, drop_height=None, restitution=None,
             alpha=None, damping=None, model: str = INPUTS["model"].default,
             calibration: str = INPUTS["calibration"].default, method: str = INPUTS["method"].default,
             step=INPUTS["step"].default, surface: Surface | str | None = None,
             curve_points: int = 1001, **inputs) -> ImpactResult:
    """Simulate one impact of ``fruit`` on ``surface``.

    Parameters
    ----------
    fruit : Fruit or str, optional
        A Fruit, or the name of a fruit of the library (``library.fruits()``: its
        properties, each overridden by a keyword of ``inputs``); default: the paper's
        Jonathan apple (``constants.JONATHAN_SOURCE``).
    velocity : float, optional
        Impact velocity V_i [m/s]; default 1 m/s.
    drop_height : float, optional
        Drop height h [m], instead of ``velocity``: V_i = sqrt(2 g h).
    restitution : float, optional
        Restitution coefficient e in (0, 1] (eq 3) the damping is calibrated to;
        default 0.577.
    alpha : float, optional
        Hunt–Crossley's α ≥ 0 [s/m] instead of e, for the power-law laws: the damping
        is λ = 1.5 α k_c (eq 5), whatever the calibration; the restitution follows.
    damping : float, optional
        The damping coefficient ≥ 0 instead of e: λ [N·s/m^2.5] of the power-law laws
        (b [N·s/m] Kelvin–Voigt, K·B [N·s/m^1.5] Kuwabara–Kono, η [N·s/m^1.25] Tsuji).
    model : str
        Damping law, a key of ``models.DAMPING_LAWS`` (``hertz``,
        ``hunt-crossley``, ``chen``, ...).
    calibration : str
        ``exact`` (default): the damping such that the simulated restitution equals e;
        ``paper``: the law's published formula (eq 6 with eq 5, or eq 21).
    method : str
        ``accurate`` (default, exact end of contact) or ``rk4`` (the paper's
        fixed-step integration at ``step`` [s], checked against ``accurate``).
    step : float
        RK4 time step [s] (default 1e-4 s, the paper's).
    surface : Surface or str, optional
        A Surface, or the name of a surface of the library (``library.surfaces()``;
        ``"fruit"``: an identical free fruit, ``velocity`` then being the approach
        speed); default a rigid plane.
    curve_points : int
        Samples of the ``accurate`` curves over [0, T].
    **inputs
        Any other input of ``quantities.INPUTS`` by name, e.g. the damage inputs
        ``yield_pressure`` [Pa] (Thornton's p_y), ``bioyield_force`` [N],
        ``failure_stress`` [Pa], ``criterion`` (``pressure``, ``shear``, ``energy``),
        ``bruise_susceptibility`` [m³/J], ``bruise_energy`` [J], ``partner_mass`` [kg],
        ``surface_model``, or the fruit's ``mass``, ``diameter`` … without a Fruit.
        Numbers may be given as strings with units (``velocity="2 m/s"``).

    Returns
    -------
    ImpactResult
        ``status`` is not ok (with a message saying what and by how much) when the
        solver failed or missed its accuracy; inputs out of range raise ``ValueError``
        (an ``InputError`` naming the argument) instead.

    Raises
    ------
    ValueError
        An input outside its allowed range, unknown, or NaN; conflicting inputs (``velocity`` and
        ``drop_height``); the message names the argument and its allowed range.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> result = fi.simulate()  # the founding paper's Jonathan apple at 1 m/s
    >>> result.status, round(result.characteristics.restitution, 3)
    ('ok', 0.577)

    References
    ----------
    "Theoretical aspects about simulating the reaction to impact of apples on rigid plane surfaces" (the
    nonlinear Kelvin–Voigt model, eqs 7–12, and its worked example, section 3); H. Hertz (1882);
    K. H. Hunt, F. R. E. Crossley, J. Appl. Mech. 42 (1975) 440–445.
    """
    from fruitimpact.impact.validation import check_integer

    curve_points = check_integer("curve_points", curve_points, 2, 10_000_000)
    keywords = dict(velocity=velocity, drop_height=drop_height, restitution=restitution, alpha=alpha,
                    damping=damping, model=model, calibration=calibration, method=method, step=step, **inputs)
    from fruitimpact.impact import single

    result = single.impact(fruit, surface, keywords, curve_points)  # the common case, without the table
    return result if result is not None else _simulate_table(fruit, surface, keywords, curve_points)


def _simulate_table(fruit, surface, keywords: dict, curve_points: int) -> ImpactResult:
    """``simulate`` by the table path (``impact.evaluation``): every row, every message and warning."""
    from fruitimpact.impact.evaluation import evaluate_inputs
    from fruitimpact.impact.inputs import read_columns

    row = _row(fruit, surface, keywords)
    inputs, messages = read_columns(row)
    result = evaluate_inputs(inputs, messages, detail=True, closed_forms=True)
    code = int(result.status[0])
    if STATUS_NAMES[code] == "invalid":
        raise InputError(messages.text(0), messages.argument(0))
    columns = {name: array[0] for name, array in result.columns.items()}  # Labels give the label
    fruit_used = Fruit._checked(**{name: float(columns[name]) for name in ("mass", "diameter", "modulus", "poisson")},
                                stiffness=row["stiffness"][0] if "stiffness" in row else None)
    surface_used = Surface._checked(**{name: float(columns["surface_" + name])
                                       for name in ("modulus", "poisson", "radius", "thickness", "crush_stress")})
    given = {name: (row[name][0] if name in row else None) for name in ("restitution", "alpha", "damping")}
    target = float(columns["target_restitution"])
    inputs_used = ImpactInputs(fruit=fruit_used, surface=surface_used, velocity=float(columns["velocity"]),
                               drop_height=row["drop_height"][0] if "drop_height" in row else None,
                               restitution=given["restitution"], alpha=given["alpha"], model=columns["model"],
                               calibration=columns["calibration"], method=columns["method"],
                               step=float(columns["step"]), damping=given["damping"],
                               target_restitution=target if math.isfinite(target) else None)
    from fruitimpact.physics import get_law

    law = get_law(inputs_used.model)
    contact_law = ContactLaw(stiffness=float(columns["law_stiffness"]), damping_factor=float(columns["damping_factor"]),
                             family=law.family, clamp=law.clamp)
    from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS

    characteristics = Characteristics(**{name: float(columns[name]) for name in CHARACTERISTIC_COLUMNS},
                                      max_deflection_closed_form=float(result.closed_forms[0, 0]),
                                      restitution_closed_form=float(result.closed_forms[0, 1]))
    message = messages.text(0) or "ok"
    from fruitimpact.impact.quantities import DAMAGE_NAMES

    damage = {name: float(columns[name]) for name in DAMAGE_NAMES}
    damage["bruised"] = None if math.isnan(damage["bruised"]) else bool(damage["bruised"])
    names = {name: columns[name] for name in ("fruit", "surface", "surface_model", "criterion")}
    damage_inputs = {name: float(columns[name]) for name in
                     ("yield_pressure", "surface_thickness", "partner_mass", "failure_stress", "bruise_susceptibility",
                      "bruise_energy")}
    return ImpactResult(inputs=inputs_used, law=contact_law, characteristics=characteristics,
                        status=STATUS_NAMES[code], message=message, warnings=tuple(result.warnings.row(0)),
                        curve_points=curve_points, damage=damage, names=names, damage_inputs=damage_inputs,
                        plastic=bool(result.plastic[0]),
                        plastic_arguments={name: float(np.asarray(value)[0]) if np.ndim(value) else float(value)
                                           for name, value in result.kernel_arguments.items()})
