"""Quantities with units at the boundary (CLI, batch files); SI inside.

``parse_quantity("65mm", "length") -> 0.065``.  A plain number is taken as SI.
Only the units a user of this field types are known; anything else is a clear
``ValueError``.
"""

from __future__ import annotations

import math
import re

#: Units accepted per dimension, as factors to SI.
UNITS: dict[str, dict[str, float]] = {
    "mass": {"kg": 1.0, "g": 1e-3, "mg": 1e-6},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254},
    "modulus": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m2": 1.0, "N/m^2": 1.0,
                "N/mm2": 1e6, "N/mm^2": 1e6},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "km/h": 1.0 / 3.6},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
    "stiffness": {"N/m^1.5": 1.0, "N/m1.5": 1.0, "kN/m^1.5": 1e3, "MN/m^1.5": 1e6},
    "alpha": {"s/m": 1.0},
    "damping": {"Ns/m^2.5": 1.0, "N*s/m^2.5": 1.0, "N.s/m^2.5": 1.0},
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3},
    "firmness": {"N/s": 1.0, "N/ms": 1e3},
    "firmness_star": {"N/s^2": 1.0, "N/s2": 1.0, "N/s²": 1.0, "N/ms^2": 1e6, "N/ms2": 1e6, "N/ms²": 1e6},
    "energy": {"J": 1.0, "mJ": 1e-3},
    "frequency": {"Hz": 1.0, "kHz": 1e3},
    "susceptibility": {"m3/J": 1.0, "m^3/J": 1.0, "cm3/J": 1e-6, "cm^3/J": 1e-6, "ml/J": 1e-6, "mm3/J": 1e-9,
                       "mm^3/J": 1e-9},
    "volume": {"m3": 1.0, "m^3": 1.0, "cm3": 1e-6, "cm^3": 1e-6, "ml": 1e-6, "mm3": 1e-9, "mm^3": 1e-9},
    "boolean": {"": 1.0},
    "dimensionless": {"": 1.0, "%": 1e-2},
}

#: The SI unit shown in messages and tables, per dimension.
SI_UNIT = {
    "mass": "kg", "length": "m", "modulus": "Pa", "velocity": "m/s", "time": "s",
    "stiffness": "N/m^1.5", "alpha": "s/m", "damping": "N·s/m^2.5", "force": "N", "energy": "J",
    "firmness": "N/s", "firmness_star": "N/s²",
    "frequency": "Hz", "dimensionless": "", "susceptibility": "m³/J", "volume": "m³", "boolean": "",
}

_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf(?:inity)?|[-+]?nan)\s*(.*?)\s*$",
                     re.IGNORECASE)


def number_and_unit(text: str) -> tuple[float, str] | None:
    """``"12ms"`` → (12.0, "ms"), ``"3"`` → (3.0, ""); None when the text does not start with a number."""
    match = _NUMBER.match(str(text))
    return None if match is None else (float(match.group(1)), match.group(2))


def parse_quantity(text: str | float, dimension: str) -> float:
    """Parse ``text`` (``"115g"``, ``"3 MPa"``, ``"0.065"``) to a float in SI.

    Parameters
    ----------
    text : str or float
        A number, optionally followed by a unit of ``dimension``.
    dimension : str
        A key of ``UNITS``.

    Raises
    ------
    ValueError
        If the text is not a number with a known unit of that dimension.
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return float(text)
    match = _NUMBER.match(str(text))
    units = UNITS[dimension]
    allowed = ", ".join(u for u in units if u) or "none"
    if not match:
        raise ValueError(f"cannot read {text!r} as a number with a unit "
                         f"(units allowed: {allowed}; a plain number is {SI_UNIT[dimension] or 'dimensionless'})")
    number, unit = match.groups()
    if unit == "":
        return float(number)
    if unit not in units:
        raise ValueError(f"unknown unit {unit!r} in {text!r} (units allowed: {allowed}; "
                         f"a plain number is {SI_UNIT[dimension] or 'dimensionless'})")
    return float(number) * units[unit]


def format_si(value: float, dimension: str, digits: int = 5) -> str:
    """``value`` with ``digits`` significant digits and its SI unit."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    unit = SI_UNIT[dimension]
    return f"{value:.{digits}g} {unit}".rstrip()
