"""Checks at the boundary.  Each raises ``ValueError`` with one line that names
the argument and its allowed range; the CLI prints the same line."""

from __future__ import annotations

import math


def _as_float(name: str, value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number; got {value!r}") from None


def positive_message(name: str, unit: str = "") -> str:
    """The wording of a refused positive quantity (also used per row by ``batch``)."""
    return f"{name} must be a finite number > 0{(' ' + unit) if unit else ''}"


def range_message(name: str, low: float, high: float, low_inclusive: bool = False,
                  high_inclusive: bool = False, unit: str = "") -> str:
    """The wording of a value outside its interval (also used per row by ``batch``)."""
    interval = f"{'[' if low_inclusive else '('}{low:g}, {high:g}{']' if high_inclusive else ')'}"
    return f"{name} must be in {interval}{(' ' + unit) if unit else ''}"


def check_positive(name: str, value, unit: str = "") -> float:
    """``value`` as float if finite and > 0."""
    number = _as_float(name, value)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{positive_message(name, unit)}; got {value!r}")
    return number


def check_range(name: str, value, low: float, high: float, *, low_inclusive: bool = False,
                high_inclusive: bool = False, unit: str = "") -> float:
    """``value`` as float if it lies in the interval (or [ ]) from ``low`` to ``high``."""
    number = _as_float(name, value)
    above = number >= low if low_inclusive else number > low
    below = number <= high if high_inclusive else number < high
    if math.isnan(number) or not (above and below):
        raise ValueError(f"{range_message(name, low, high, low_inclusive, high_inclusive, unit)}; got {value!r}")
    return number


def check_exclusive(first: str, first_value, second: str, second_value) -> None:
    """Refuse two options that say the same thing in two ways."""
    if first_value is not None and second_value is not None:
        raise ValueError(f"give either {first} or {second}, not both")
