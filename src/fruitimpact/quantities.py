"""Named quantities of the output and inputs: label, display unit and scale.

One table for every place that shows a characteristic or an input to a person
(the simulate table, run summaries, axis labels, thresholds)."""

from __future__ import annotations

from dataclasses import dataclass

from .units import parse_quantity


@dataclass(frozen=True)
class Quantity:
    """A column of the output: label, display unit and scale, and units accepted in thresholds."""

    name: str
    label: str
    unit: str  # display unit
    scale: float  # display value = SI value * scale
    si_unit: str
    dimension: str  # a key of fruitimpact.units.UNITS, for parsing values

    @property
    def axis_label(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    def parse(self, text: str) -> float:
        """A value of this quantity (plain number = SI, or with a unit) → SI."""
        return parse_quantity(text, self.dimension)


def _q(name, label, unit, scale, si_unit, dimension):
    return name, Quantity(name, label, unit, scale, si_unit, dimension)


#: Characteristics (and law columns) of the output: what can be summarised, plotted, thresholded.
CHARACTERISTICS = dict((
    _q("peak_force", "peak force F_max", "N", 1.0, "N", "force"),
    _q("time_to_peak", "time to peak t_c", "ms", 1e3, "s", "time"),
    _q("contact_duration", "contact duration T", "ms", 1e3, "s", "time"),
    _q("max_deflection", "max deflection δ_max", "mm", 1e3, "m", "length"),
    _q("time_to_max_deflection", "time to max deflection", "ms", 1e3, "s", "time"),
    _q("exit_velocity", "exit velocity", "m/s", 1.0, "m/s", "velocity"),
    _q("restitution", "restitution e", "", 1.0, "", "dimensionless"),
    _q("absorbed_energy", "absorbed energy", "mJ", 1e3, "J", "energy"),
    _q("firmness_c", "firmness C = F_max/t_c", "N/ms", 1e-3, "N/s", "firmness"),
    _q("firmness_c_star", "firmness C* = F_max/t_c²", "N/ms²", 1e-6, "N/s²", "firmness_star"),
    _q("max_pressure", "max contact pressure p_0", "MPa", 1e-6, "Pa", "modulus"),
    _q("contact_radius", "contact radius a", "mm", 1e3, "m", "length"),
    _q("law_stiffness", "contact stiffness k_c", "N/m^1.5", 1.0, "N/m^1.5", "stiffness"),
    _q("damping", "damping λ", "N·s/m^2.5", 1.0, "N·s/m^2.5", "damping"),
    _q("damping_factor", "damping factor c = λ/k_c", "s/m", 1.0, "s/m", "alpha"),
    _q("target_restitution", "target restitution k", "", 1.0, "", "dimensionless"),
))
#: The characteristics proper (summarised by default), in the engine's column order.
DEFAULT_SUMMARY = tuple(list(CHARACTERISTICS)[:12])

#: Numeric inputs: dimension and axis label of each (columns of batch.evaluate).
INPUTS = dict((
    _q("mass", "mass M", "g", 1e3, "kg", "mass"),
    _q("diameter", "diameter d", "mm", 1e3, "m", "length"),
    _q("modulus", "Young's modulus E", "MPa", 1e-6, "Pa", "modulus"),
    _q("poisson", "Poisson's ratio ν", "", 1.0, "", "dimensionless"),
    _q("stiffness", "contact stiffness k_c", "N/m^1.5", 1.0, "N/m^1.5", "stiffness"),
    _q("velocity", "impact velocity V_i", "m/s", 1.0, "m/s", "velocity"),
    _q("drop_height", "drop height h", "cm", 1e2, "m", "length"),
    _q("restitution", "restitution k", "", 1.0, "", "dimensionless"),
    _q("alpha", "Hunt–Crossley α", "s/m", 1.0, "s/m", "alpha"),
    _q("step", "RK4 step", "ms", 1e3, "s", "time"),
))
