"""The one table of quantities: every input and output of an impact, once.

Each ``Quantity`` says what a value is (name, symbol, label, doc), how it is
shown (display unit and scale) and read (its dimension in
``fruitimpact.impact.units``), the range a value must lie in to be accepted
(``allowed``: outside it the input is refused with one line) and the range
that is plausible for fruit (``plausible``: outside it the result carries a
warning), its default, and the CLI option that sets it.  From this table come
the options of ``fruitimpact simulate``, ``sweep`` and ``population``, the
columns ``impact.evaluation.evaluate`` accepts and returns, the validation of inputs,
the fields of results and every label, unit and axis of the tables and
figures.  Add a quantity here, and it is an option, a column and a result.

Plausible ranges are for fruit and vegetables handled on packing lines:
berries of a gram to melons of several kilograms; flesh moduli from ripe
tomato (~0.1 MPa) to unripe apple and potato (~10–20 MPa); drops from a few
millimetres to a few metres.  Sources and the reasoning are in
docs/glossary.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.physics.constants import JONATHAN_APPLE, JONATHAN_RESTITUTION, JONATHAN_VELOCITY
from fruitimpact.impact.units import SI_UNIT, parse_quantity


@dataclass(frozen=True)
class Range:
    """An interval of accepted (or plausible) values [SI]."""

    low: float = -math.inf
    high: float = math.inf
    low_inclusive: bool = False
    high_inclusive: bool = False

    def contains(self, values):
        """Boolean mask of ``values`` inside the interval (NaN is outside); a bool for a float."""
        if isinstance(values, float):
            above = values >= self.low if self.low_inclusive else values > self.low
            return above and (values <= self.high if self.high_inclusive else values < self.high)
        values = np.asarray(values, dtype=float)
        above = values >= self.low if self.low_inclusive else values > self.low  # NaN compares False: outside
        below = values <= self.high if self.high_inclusive else values < self.high
        return above & below

    def describe(self, unit: str = "") -> str:
        """``(0, 1]``, ``> 0 kg``, ``>= 0 s/m`` …, for messages."""
        unit = f" {unit}" if unit else ""
        if self.high == math.inf and not self.high_inclusive:
            return f"{'>=' if self.low_inclusive else '>'} {self.low:g}{unit}"
        left = "[" if self.low_inclusive else "("
        right = "]" if self.high_inclusive else ")"
        return f"in {left}{self.low:g}, {self.high:g}{right}{unit}"


POSITIVE = Range(0.0, math.inf)
NON_NEGATIVE = Range(0.0, math.inf, low_inclusive=True)
#: Positive, infinity allowed (a rigid or flat surface).
POSITIVE_OR_INFINITE = Range(0.0, math.inf, high_inclusive=True)


@dataclass(frozen=True)
class Quantity:
    """One named quantity of the table.

    Attributes
    ----------
    name : str
        Keyword, column and JSON key (``peak_force``).
    symbol : str
        The paper's symbol (``F_max``).
    label : str
        Words and symbol for tables and axes (``peak force F_max``).
    dimension : str
        Key of ``fruitimpact.impact.units.UNITS``: how values with units are read.
    unit : str
        Display unit of tables and figures.
    scale : float
        Display value = SI value × scale.
    doc : str
        One line of meaning.
    allowed : Range or None
        Inputs: values outside are refused.
    plausible : Range or None
        Inputs: values outside are accepted with a warning.
    default : float or str or None
        Inputs: the value when not given (None: optional, no default).
    option : str or None
        Inputs: the CLI option (a contract: never renamed).
    choices : str or None
        Text inputs: the registry whose names are allowed (``model`` …).
    """

    name: str
    symbol: str
    label: str
    dimension: str
    unit: str
    scale: float
    doc: str
    allowed: Range | None = None
    plausible: Range | None = None
    default: float | str | None = None
    option: str | None = None
    choices: str | None = None

    @property
    def si_unit(self) -> str:
        return SI_UNIT.get(self.dimension, "")

    @property
    def numeric(self) -> bool:
        return self.choices is None

    @property
    def axis_label(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    def parse(self, text) -> float:
        """A value of this quantity (plain number = SI, or with a unit) → SI."""
        return parse_quantity(text, self.dimension)

    def display(self, value: float) -> str:
        """``value`` [SI] in display units, e.g. ``180 g``."""
        return f"{value * self.scale:.6g} {self.unit}".rstrip()


def _table(*quantities: Quantity) -> dict[str, Quantity]:
    return {q.name: q for q in quantities}


_JONATHAN = "(default: the paper's Jonathan apple)"

#: Inputs of one impact: keywords of ``simulate``, columns of ``impact.evaluation.evaluate``,
#: options of ``simulate``/``sweep``/``population``.  Numeric inputs first, then text.
INPUTS: dict[str, Quantity] = _table(
    Quantity("mass", "M", "mass M", "mass", "g", 1e3, f"fruit mass {_JONATHAN}",
             POSITIVE, Range(1e-3, 20.0, True, True), JONATHAN_APPLE["mass"], "--mass"),
    Quantity("diameter", "d", "diameter d", "length", "mm", 1e3,
             f"fruit diameter; the local contact radius is d/2 {_JONATHAN}",
             POSITIVE, Range(5e-3, 0.4, True, True), JONATHAN_APPLE["diameter"], "--diameter"),
    Quantity("modulus", "E", "Young's modulus E", "modulus", "MPa", 1e-6,
             f"Young's modulus of the flesh {_JONATHAN}",
             POSITIVE, Range(2e4, 1e8, True, True), JONATHAN_APPLE["modulus"], "--modulus"),
    Quantity("poisson", "ν", "Poisson's ratio ν", "dimensionless", "", 1.0,
             f"Poisson's ratio of the flesh {_JONATHAN}",
             Range(-1.0, 0.5), Range(0.1, 0.5, True, False), JONATHAN_APPLE["poisson"], "--poisson"),
    Quantity("stiffness", "k_c", "contact stiffness k_c", "stiffness", "N/m^1.5", 1.0,
             "contact stiffness given directly; overrides the Hertz value from E, ν, d (eq 9)",
             POSITIVE, None, None, "--stiffness"),
    Quantity("velocity", "V_i", "impact velocity V_i", "velocity", "m/s", 1.0,
             "impact velocity (default 1 m/s)",
             POSITIVE, Range(0.01, 15.0, True, True), None, "--velocity"),
    Quantity("drop_height", "h", "drop height h", "length", "cm", 1e2,
             "drop height instead of the velocity: V_i = sqrt(2 g h)",
             POSITIVE, Range(1e-3, 10.0, True, True), None, "--drop-height"),
    Quantity("restitution", "e", "restitution e", "dimensionless", "", 1.0,
             "restitution coefficient the damping is calibrated to (eq 3; default 0.577)",
             Range(0.0, 1.0, high_inclusive=True), None, None, "--restitution"),
    Quantity("alpha", "α", "Hunt–Crossley α", "alpha", "s/m", 1.0,
             "Hunt–Crossley damping parameter instead of e: λ = 1.5 α k_c (eq 5); power-law laws only",
             NON_NEGATIVE, None, None, "--alpha"),
    Quantity("damping", "λ", "damping λ", "damping", "N·s/m^2.5", 1.0,
             "damping coefficient given directly instead of e: λ of F = k_c δ^1.5 + λ δ^1.5 δ̇ "
             "(b [N·s/m] for kelvin-voigt, K·B [N·s/m^1.5] for kuwabara-kono, η [N·s/m^1.25] for tsuji)",
             NON_NEGATIVE, None, None, "--damping"),
    Quantity("surface_modulus", "E_2", "surface modulus E_2", "modulus", "MPa", 1e-6,
             "Young's modulus of the surface (default inf: rigid)",
             POSITIVE_OR_INFINITE, None, math.inf, "--surface-modulus"),
    Quantity("surface_poisson", "ν_2", "surface Poisson's ratio ν_2", "dimensionless", "", 1.0,
             "Poisson's ratio of the surface (default 0.3; no effect on a rigid surface)",
             Range(-1.0, 0.5), None, 0.3, "--surface-poisson"),
    Quantity("surface_radius", "R_2", "surface radius R_2", "length", "mm", 1e3,
             "radius of curvature of the surface (default inf: flat)",
             POSITIVE_OR_INFINITE, None, math.inf, "--surface-radius"),
    Quantity("surface_thickness", "h", "surface thickness h", "length", "mm", 1e3,
             "thickness of a cushion, pad or belt cover on a rigid substrate (default inf: a half-space)",
             POSITIVE_OR_INFINITE, None, math.inf, "--surface-thickness"),
    Quantity("surface_crush_stress", "σ_c", "surface crush stress σ_c", "modulus", "kPa", 1e-3,
             "flat-crush strength of a cushion layer (corrugated board: its flutes collapse when the pressure under "
             "the fruit reaches it, and the fruit meets the floor; default: the --surface's, else none)",
             POSITIVE_OR_INFINITE, None, math.inf, "--surface-crush-stress"),
    Quantity("partner_mass", "m_2", "partner mass m_2", "mass", "g", 1e3,
             "mass of a free partner (another fruit): the reduced mass m m_2/(m + m_2) moves; --velocity is then "
             "the approach speed (default inf: a fixed surface)",
             POSITIVE_OR_INFINITE, Range(1e-3, math.inf, True, True), math.inf, "--partner-mass"),
    Quantity("yield_pressure", "p_y", "yield pressure p_y", "modulus", "MPa", 1e-6,
             "Thornton's limiting contact pressure: elastic-perfectly plastic contact above it "
             "(default inf: elastic; with --model hertz pure Thornton)",
             POSITIVE_OR_INFINITE, Range(1e4, 2e7, True, True), math.inf, "--yield-pressure"),
    Quantity("bioyield_force", "F_pc", "bioyield force F_pc", "force", "N", 1.0,
             "the paper's critical force of the bioyield element (eq 17), read as Thornton's yield force: "
             "instead of --yield-pressure",
             POSITIVE, Range(0.01, 1e4, True, True), None, "--bioyield-force"),
    Quantity("failure_stress", "σ_f", "failure stress σ_f", "modulus", "MPa", 1e-6,
             "failure (bioyield) stress of the flesh for the bruise criterion (needs --criterion; "
             "default: the --fruit's own; a fruit without one refuses the stress criteria)",
             POSITIVE, Range(1e4, 5e6, True, True), None, "--failure-stress"),
    Quantity("bruise_susceptibility", "BS", "bruise susceptibility BS", "susceptibility", "cm³/J", 1e6,
             "bruise volume per joule of absorbed energy above the threshold (default: the --fruit's own; "
             "without one the bruise volume is unknown)",
             NON_NEGATIVE, Range(1e-7, 5e-5, True, True), None, "--bruise-susceptibility"),
    Quantity("bruise_width_ratio", "", "contact-to-bruise width ratio", "dimensionless", "", 1.0,
             "contact width over the width of the bruise it leaves: sets the bruise width 2a/ratio and, with the "
             "volume, its depth (default: the --fruit's own, measured on pears only: 1.4; without one the bruise "
             "depth and width are unknown)",
             POSITIVE, Range(0.5, 5.0, True, True), None, "--bruise-width-ratio"),
    Quantity("bruise_energy", "W_th", "bruise threshold energy W_th", "energy", "mJ", 1e3,
             "absorbed energy at bruise onset, subtracted from the fruit's energy in the bruise volume: the "
             "energy criterion's threshold (default: the --fruit's); under a stress criterion the fruit "
             "energy at that criterion's own onset (an output)",
             NON_NEGATIVE, Range(0.0, 5.0, True, True), None, "--bruise-energy"),
    Quantity("step", "Δt", "RK4 step Δt", "time", "ms", 1e3, "RK4 time step (default 1e-4 s, the paper's)",
             POSITIVE, None, 1e-4, "--step"),
    Quantity("model", "", "damping law", "text", "", 1.0, "damping law (fruitimpact models)",
             default="hunt-crossley", option="--model", choices="model"),
    Quantity("calibration", "", "calibration", "text", "", 1.0,
             "exact: the damping gives exactly the requested e; paper: the law's published formula",
             default="exact", option="--calibration", choices="calibration"),
    Quantity("method", "", "method", "text", "", 1.0,
             "accurate (exact) or rk4 (the paper's fixed-step method)",
             default="accurate", option="--method", choices="method"),
    Quantity("fruit", "", "fruit", "text", "", 1.0,
             "a fruit of the library (fruitimpact fruits), or a fruit file (.csv in the library's format, e.g. "
             "written by fit-damage --output): its mass, diameter, modulus, Poisson's ratio and damage properties, "
             "each overridden by its own option",
             default="jonathan-apple", option="--fruit", choices="fruit"),
    Quantity("surface", "", "surface", "text", "", 1.0,
             "a surface of the library (fruitimpact surfaces; fruit: an identical free fruit), each property "
             "overridden by its own option",
             default="rigid", option="--surface", choices="surface"),
    Quantity("surface_model", "", "surface model", "text", "", 1.0,
             "half-space (Hertz through E* and R) or layer (elastic-foundation cushion of thickness h on a rigid "
             "substrate); default: the --surface's",
             default="preset", option="--surface-model", choices="surface_model"),
    Quantity("criterion", "", "bruise criterion", "text", "", 1.0,
             "bruise onset: pressure (p_0 >= σ_f), shear (τ_max >= σ_f/2) or energy (W >= W_th); none: no "
             "bruise assessment",
             default="none", option="--criterion", choices="criterion"),
    Quantity("bruise_basis", "", "energy basis of the given bruise values", "text", "", 1.0,
             "the energy a given --bruise-susceptibility and --bruise-energy were measured on: absorbed "
             "(½ m V² (1 − e²), the fruit's share) or impact (½ m V², the fruit's share; e.g. a pendulum's "
             "energy); the library's values carry their own (fruitimpact fruits)",
             default="absorbed", option="--bruise-basis", choices="bruise_basis"),
)

#: Inputs given in several ways: at most one of each group (the first is the default way).
ALTERNATIVES = (("velocity", "drop_height"), ("restitution", "alpha", "damping"),
                ("yield_pressure", "bioyield_force"))
#: Defaults of the optional inputs when no alternative of their group is given.
GROUP_DEFAULTS = {"velocity": JONATHAN_VELOCITY, "restitution": JONATHAN_RESTITUTION}

NUMERIC_INPUTS = tuple(name for name, q in INPUTS.items() if q.numeric)
TEXT_INPUTS = tuple(name for name, q in INPUTS.items() if not q.numeric)


def _bounds(ranges) -> tuple[np.ndarray, ...]:
    """(low, high, low inclusive, high inclusive) columns of ranges (None: everything inside)."""
    ranges = [r if r is not None else Range(-math.inf, math.inf, True, True) for r in ranges]
    return tuple(np.array([getattr(r, field) for r in ranges])[:, None]
                 for field in ("low", "high", "low_inclusive", "high_inclusive"))


def inside(bounds, matrix: np.ndarray, which=None) -> np.ndarray:
    """Mask of the entries of ``matrix`` (inputs × rows) inside each input's range of ``bounds``
    (NaN is outside).  ``which`` (indices of inputs) restricts the check to those inputs' rows
    of the matrix; the result then has one row per index."""
    low, high, low_inclusive, high_inclusive = bounds
    if which is not None:
        matrix = matrix[which]
        low, high, low_inclusive, high_inclusive = low[which], high[which], low_inclusive[which], high_inclusive[which]
    if matrix.size <= 4096:  # a few rows (one impact): four operations on the whole matrix
        above = np.where(low_inclusive, matrix >= low, matrix > low)
        return above & np.where(high_inclusive, matrix <= high, matrix < high)
    out = np.empty(matrix.shape, dtype=bool)
    for j in range(matrix.shape[0]):  # one comparison per bound: a whole row at a time
        row = matrix[j]
        above = row >= low[j, 0] if low_inclusive[j, 0] else row > low[j, 0]
        np.logical_and(above, row <= high[j, 0] if high_inclusive[j, 0] else row < high[j, 0], out=out[j])
    return out


#: The array forms of the table, built on first use (module ``__getattr__``) so that reading the table, as the
#: command line's parser does, never imports NumPy (``--help`` and usage errors answer in a tenth of a second):
#: ``ALLOWED_BOUNDS`` and ``PLAUSIBLE_BOUNDS``, the bounds of the numeric inputs' allowed and plausible ranges in
#: ``NUMERIC_INPUTS`` order, and ``NUMERIC_DEFAULTS``, their defaults (NaN: none) as a column for ``numpy.where``.
_ARRAYS = {
    "ALLOWED_BOUNDS": lambda: _bounds(INPUTS[name].allowed for name in NUMERIC_INPUTS),
    "PLAUSIBLE_BOUNDS": lambda: _bounds(INPUTS[name].plausible for name in NUMERIC_INPUTS),
    "NUMERIC_DEFAULTS": lambda: np.array([INPUTS[name].default if INPUTS[name].default is not None else math.nan
                                          for name in NUMERIC_INPUTS])[:, None],
}


def __getattr__(name: str):
    build = _ARRAYS.get(name)
    if build is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = globals()[name] = build()
    return value


#: Outputs of one impact (the characteristics, then the contact law as used).
OUTPUTS: dict[str, Quantity] = _table(
    Quantity("peak_force", "F_max", "peak force F_max", "force", "N", 1.0, "largest contact force"),
    Quantity("time_to_peak", "t_c", "time to peak t_c", "time", "ms", 1e3, "time from first touch to F_max"),
    Quantity("contact_duration", "T", "contact duration T", "time", "ms", 1e3,
             "time from first touch to separation"),
    Quantity("max_deflection", "δ_max", "max deflection δ_max", "length", "mm", 1e3,
             "largest deflection of the fruit at the contact"),
    Quantity("time_to_max_deflection", "t_m", "time to max deflection", "time", "ms", 1e3,
             "time from first touch to δ_max"),
    Quantity("exit_velocity", "V_e", "exit velocity", "velocity", "m/s", 1.0,
             "rebound speed, away from the surface"),
    Quantity("restitution", "e", "restitution e", "dimensionless", "", 1.0,
             "exit speed / impact speed (eq 3), as simulated"),
    Quantity("absorbed_energy", "W", "absorbed energy", "energy", "mJ", 1e3, "½ m V_i² (1 − e²)"),
    Quantity("firmness_c", "C", "firmness C = F_max/t_c", "firmness", "N/ms", 1e-3, "F_max / t_c (eqs 1, 28)"),
    Quantity("firmness_c_star", "C*", "firmness C* = F_max/t_c²", "firmness_star", "N/ms²", 1e-6,
             "F_max / t_c² (eq 2)"),
    Quantity("max_pressure", "p_0", "max contact pressure p_0", "modulus", "MPa", 1e-6,
             "largest Hertz centre pressure 3F/(2π R δ) during the contact"),
    Quantity("contact_radius", "a", "contact radius a", "length", "mm", 1e3, "Hertz contact radius √(R δ_max)"),
    Quantity("law_stiffness", "k_c", "contact stiffness k_c", "stiffness", "N/m^1.5", 1.0,
             "the elastic coefficient the law uses (k [N/m] for kelvin-voigt)"),
    Quantity("damping", "λ", "damping λ", "damping", "N·s/m^2.5", 1.0,
             "the coefficient of the law's rate term, as used (λ; b, K·B or η for the other families)"),
    Quantity("damping_factor", "c", "damping factor c = λ/k_c", "alpha", "s/m", 1.0,
             "damping / stiffness (s/m for the power-law family)"),
    Quantity("target_restitution", "e_0", "target restitution", "dimensionless", "", 1.0,
             "the restitution the damping was calibrated for (NaN when α or λ was given)"),
    Quantity("yield_velocity", "V_y", "yield velocity V_y", "velocity", "m/s", 1.0,
             "impact velocity at which the contact starts to yield (inf: elastic)"),
    Quantity("permanent_deflection", "δ_p", "permanent deflection δ_p", "length", "mm", 1e3,
             "deflection left after the impact (Thornton's unloading)"),
    Quantity("plastic_work", "W_p", "plastic work W_p", "energy", "mJ", 1e3,
             "work of the rate-independent force around its loop ∮F_T dδ"),
    Quantity("viscous_work", "W_v", "viscous work W_v", "energy", "mJ", 1e3,
             "work of the damping, ∫ c F_T δ̇² dt; W_p + W_v = absorbed energy"),
    Quantity("fruit_energy", "W_f", "energy absorbed by the fruit", "energy", "mJ", 1e3,
             "the fruit's share of the absorbed energy (the rest is the partner's or the pad's)"),
    Quantity("max_shear_stress", "τ_max", "max shear stress τ_max", "modulus", "MPa", 1e-6,
             "largest subsurface shear stress under the contact, τ_max/p_0 from Hertz's field for the fruit's ν"),
    Quantity("bruise_margin", "", "bruise margin", "dimensionless", "", 1.0,
             "criterion's stress (or energy) over its threshold, minus 1: >= 0 is a bruise"),
    Quantity("bruised", "", "bruised", "boolean", "", 1.0, "1 where the criterion says bruised (NaN: no criterion)"),
    Quantity("bruise_volume", "BV", "bruise volume BV", "volume", "mm³", 1e9,
             "BS (W_f − W_th)₊ where bruised"),
    Quantity("bruise_depth", "d_b", "bruise depth", "length", "mm", 1e3,
             "depth of a spherical-cap bruise of that volume and width"),
    Quantity("bruise_width", "w_b", "bruise width", "length", "mm", 1e3,
             "surface width of the bruise: contact width / 1.4 (Stropek & Gołacki 2020)"),
)

#: The damage outputs (issue 7), after the law columns.
DAMAGE_NAMES = ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work", "fruit_energy",
                "max_shear_stress", "bruise_margin", "bruised", "bruise_volume", "bruise_depth", "bruise_width")

#: The characteristics proper (the engine's columns, in its order): summarised by default.
CHARACTERISTIC_NAMES = tuple(list(OUTPUTS)[:12])
#: Output quantities by name (characteristics and the law columns): what runs summarise and plot.
CHARACTERISTICS = OUTPUTS
DEFAULT_SUMMARY = CHARACTERISTIC_NAMES


def option_of(name: str) -> str:
    """The CLI option of input ``name`` (``drop_height`` → ``--drop-height``)."""
    quantity = INPUTS.get(name)
    return quantity.option if quantity is not None and quantity.option else "--" + name.replace("_", "-")


#: The fruit fields (columns of the fruit library and of a fruit file) a simulation takes as inputs, and the input
#: each one is: a fruit's value passes that input's checks, as the option would, and fills that input's rows.
FRUIT_FIELD_INPUTS = {"mass": "mass", "diameter": "diameter", "modulus": "modulus", "poisson": "poisson",
                      "failure_stress": "failure_stress", "restitution": "restitution", "alpha": "alpha",
                      "bruise_susceptibility": "bruise_susceptibility", "bruise_threshold_energy": "bruise_energy",
                      "bruise_width_ratio": "bruise_width_ratio"}

__all__ = ["DAMAGE_NAMES", "FRUIT_FIELD_INPUTS", "ALLOWED_BOUNDS", "ALTERNATIVES", "CHARACTERISTICS", "CHARACTERISTIC_NAMES", "DEFAULT_SUMMARY",
           "GROUP_DEFAULTS", "INPUTS", "NON_NEGATIVE", "NUMERIC_DEFAULTS", "PLAUSIBLE_BOUNDS", "inside", "NUMERIC_INPUTS", "OUTPUTS", "POSITIVE", "POSITIVE_OR_INFINITE", "Quantity",
           "Range", "TEXT_INPUTS", "option_of"]
