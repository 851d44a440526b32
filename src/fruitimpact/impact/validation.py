"""Checks at the boundary, driven by the table of quantities.

One path for one value and for a column of a million: ``check_value`` (a
``Fruit`` field, a keyword of ``simulate``) and ``out_of_range`` (a column
of ``impact.evaluation.evaluate``) use the same ``Quantity.allowed`` range and the same
words (``range_message``).  A refused input raises ``InputError``, a
``ValueError`` that carries the name of the argument it is about, so that
the CLI can name the option without reading the message.

Per-row outcomes of a batch are kept as small integer codes with one text
per distinct message (``MessageBook``) and bit masks of warnings
(``WarningBook``): a million rows do not cost a million strings.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from fruitimpact.impact.quantities import FRUIT_FIELD_INPUTS, INPUTS, Quantity, Range, option_of
from fruitimpact.impact.units import UNITS, parse_quantity


class InputError(ValueError):
    """A refused input: one line (``str(error)``) and the ``argument`` it is about
    (an input name such as ``mass``, or None when it concerns several)."""

    def __init__(self, message: str, argument: str | None = None):
        super().__init__(message)
        self.argument = argument


def range_message(quantity: Quantity, allowed: Range | None = None) -> str:
    """``mass must be a finite number > 0 kg``, ``poisson must be in (-1, 0.5)`` …"""
    allowed = allowed or quantity.allowed
    unit = quantity.si_unit
    text = allowed.describe(unit)
    if allowed.high == math.inf and not allowed.high_inclusive:
        return f"{quantity.name} must be a finite number {text}"
    if allowed.high == math.inf:
        return f"{quantity.name} must be a number {text} (inf allowed)"
    return f"{quantity.name} must be {text}"


def unreadable_message(quantity: Quantity, text) -> str:
    """The refusal of a cell or value that is not a number with a unit of ``quantity``."""
    units = ", ".join(u for u in UNITS[quantity.dimension] if u)
    plain = quantity.si_unit or "dimensionless"
    allowed = f"units allowed: {units}; a plain number is {plain}" if units else "a plain number, no unit"
    return f"{quantity.name} must be a number ({allowed}); got {text!r}"


def nan_message(quantity: Quantity) -> str:
    """A NaN is a value, never a request for the default."""
    must = range_message(quantity).split(" ", 1)[1]
    return (f"{quantity.name} is NaN; it {must} (leave it out to take the default: an empty CSV cell, "
            f"None or pd.NA)")


def is_boolean(value) -> bool:
    """True for a Python or a NumPy boolean.  NumPy is consulted only for its own objects, so that validating
    the command line's options never imports it (``numbers.Real`` covers NumPy's numbers the same way)."""
    return isinstance(value, bool) or (type(value).__module__ == "numpy" and isinstance(value, np.bool_))


def read_value(name: str, value) -> float:
    """``value`` of input ``name`` as a float [SI]: numbers as they are, strings with
    units parsed (``"115g"``).  ``InputError`` if it is not a number."""
    quantity = INPUTS[name]
    if is_boolean(value):  # True is not 1.0
        raise InputError(unreadable_message(quantity, value), name)
    if isinstance(value, numbers.Real):
        try:
            return float(value)
        except OverflowError:  # an integer beyond a float (10**400)
            raise InputError(unreadable_message(quantity, value), name) from None
    if isinstance(value, str):
        try:
            return parse_quantity(value, quantity.dimension)
        except ValueError:
            raise InputError(unreadable_message(quantity, value), name) from None
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(unreadable_message(quantity, value), name) from None


def check_value(name: str, value) -> float:
    """Input ``name`` read (``read_value``) and checked against its allowed range;
    ``InputError`` with the one-line message (the same as a batch row's) otherwise."""
    quantity = INPUTS[name]
    number = read_value(name, value)
    if math.isnan(number):
        raise InputError(f"{nan_message(quantity)}; got {number!r}", name)
    if not quantity.allowed.contains(number):
        raise InputError(f"{range_message(quantity)}; got {number!r}", name)
    return number


def choice_message(name: str, value, registry) -> str:
    """The refusal of ``value`` for text input ``name``: the registry's own reason where it has one (a fruit file
    that cannot be read, ``library.catalogue.FruitRegistry.refusal``), else the names it holds."""
    explain = getattr(registry, "refusal", None)
    reason = explain(value) if callable(explain) else None
    return reason or f"{name} must be one of {', '.join(registry)}; got {value!r}"


def check_choice(name: str, value, registry) -> str:
    """A text input (``model`` …) that must be a key of ``registry`` (for ``fruit``: a library name or a fruit
    file)."""
    if not isinstance(value, str) or value not in registry:
        raise InputError(choice_message(name, value, registry), name)
    return value


def check_number(name: str, value, *, owner: str = "", low=None, low_inclusive: bool = True, high=None,
                 high_inclusive: bool = False, optional: bool = False):
    """A finite float in a range (None passes when ``optional``), else ``InputError`` naming ``name``
    (``owner.name`` in the message): the check of settings objects outside the table of quantities."""
    if value is None and optional:
        return None
    label = f"{owner}.{name}" if owner else name
    if is_boolean(value) or not isinstance(value, numbers.Real):
        raise InputError(f"{label} must be a number; got {value!r}", name)
    value = float(value)
    ok = math.isfinite(value)
    if ok and low is not None:
        ok = value >= low if low_inclusive else value > low
    if ok and high is not None:
        ok = value <= high if high_inclusive else value < high
    if not ok:
        bounds = []
        if low is not None:
            bounds.append(f"{'>=' if low_inclusive else '>'} {low:g}")
        if high is not None:
            bounds.append(f"{'<=' if high_inclusive else '<'} {high:g}")
        rule = " and ".join(bounds)
        raise InputError(f"{label} must be a finite number{' ' + rule if rule else ''}; got {value!r}", name)
    return value


def check_integer(name: str, value, low: int, high: int | None = None, *, owner: str = "") -> int:
    """An integer in [low, high] (``high`` None: no upper bound), else ``InputError`` naming ``name``."""
    label = f"{owner}.{name}" if owner else name
    if is_boolean(value) or not isinstance(value, numbers.Integral) or value < low \
            or (high is not None and value > high):
        allowed = f"in [{low}, {high}]" if high is not None else f">= {low}"
        raise InputError(f"{label} must be an integer {allowed}; got {value!r}", name)
    return int(value)


def check_flag(name: str, value) -> bool:
    """``value`` if it is True or False (a numpy bool too), else ``InputError`` naming ``name``: a text such as
    ``"no"`` is truthy and would do the opposite of what was meant."""
    if not is_boolean(value):
        raise InputError(f"{name} must be True or False; got {value!r}", name)
    return bool(value)


def check_input_name(name: str) -> Quantity:
    """The quantity of input ``name`` (``quantities.INPUTS``); ``InputError`` naming it if it is unknown."""
    quantity = INPUTS.get(name)
    if quantity is None:
        raise InputError(f"unknown input {name!r} (inputs: {', '.join(INPUTS)})", name)
    return quantity


def spec_text(name: str, value) -> str:
    """A Python value of input ``name`` as the CLI's text (a sweep axis, a distribution, a constant): a string
    as it is, a number by ``repr``, a sequence joined by commas; ``InputError`` for anything else."""
    def scalar(item) -> str:
        if isinstance(item, str):
            return item
        if is_boolean(item) or not isinstance(item, numbers.Real):
            raise TypeError  # True is not 1.0; a nested list is not a value
        return repr(float(item))

    try:
        if isinstance(value, (list, tuple)) or (hasattr(value, "__array__") and getattr(value, "ndim", 0) == 1):
            return ",".join(scalar(item) for item in value)
        return scalar(value.item() if hasattr(value, "__array__") and getattr(value, "ndim", 1) == 0 else value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name} must be a number, a text with units or a range; got {value!r}", name) from None


def check_conflicts(given) -> None:
    """Refuse two of the inputs ``given`` that are alternatives (``quantities.ALTERNATIVES``: velocity and
    drop_height, ...), naming both."""
    from fruitimpact.impact.quantities import ALTERNATIVES

    for group in ALTERNATIVES:
        named = [name for name in group if name in given]
        if len(named) > 1:
            raise InputError(conflict_message(named), tuple(named))


#: Most digits of a count read from text (Python's own limit for converting text to int is 4300).
_MAX_DIGITS = 4000


#: Inputs whose range depends on other inputs (alpha on the law, step on the impact): a constant within its own
#: range is not refused for that dependent bound alone (a lot's other fruit may meet it).
DEPENDENT_INPUTS = ("alpha", "step")


def refuse_out_of_range(constants: dict) -> None:
    """Refuse the first constant input (name → a number [SI]; in the table's order of inputs) outside its allowed
    range, with the message a row of the table gets (``range_message``), before anything loads the engine: the
    check a run's one-row evaluation (``refusals.refuse_constants``) would make first, answered at once (a usage
    error in ≤ 0.25 s, issue 15 item 4).  ``DEPENDENT_INPUTS`` are checked against their own range here (a step
    of 0 is no step for any fruit); the bound that depends on other inputs, NaN and what is not a number are left
    to that evaluation."""
    for name, quantity in INPUTS.items():
        value = constants.get(name)
        if not isinstance(value, numbers.Real) or is_boolean(value) or math.isnan(value):
            continue
        if not quantity.allowed.contains(float(value)):
            raise InputError(range_message(quantity), name)


def read_count(name: str, value, low: int, high: int | None = None) -> int:
    """An exact integer in [low, high] from an int or a text such as ``"10000000"`` or ``"1e7"`` (read as a
    decimal, never through a float, so that a seed above 2^53 keeps every digit); ``InputError`` naming
    ``name`` otherwise (a bool, a fraction, NaN)."""
    import decimal

    allowed = f">= {low:,}" if high is None else f"in [{low:,}, {high:,}]"
    number = None
    if isinstance(value, numbers.Integral) and not is_boolean(value):
        number = decimal.Decimal(int(value))
    elif isinstance(value, str):
        try:
            number = decimal.Decimal(value.strip())
        except decimal.InvalidOperation:
            number = None
    # a bound before any int(): "1e9999999" would otherwise become a ten-million-digit integer
    if number is None or not number.is_finite() or number.adjusted() > _MAX_DIGITS or number < low \
            or (high is not None and number > high) or number != number.to_integral_value():
        raise InputError(f"{name} must be an integer {allowed}; got {value!r}", name)
    return int(number)


def conflict_message(names) -> str:
    """``give either velocity or drop_height, not both`` (or one of three)."""
    names = list(names)
    listed = " or ".join(names) if len(names) == 2 else ", ".join(names[:-1]) + " or " + names[-1]
    return f"give either {listed}, not both" if len(names) == 2 else f"give only one of {listed}"


class MessageBook:
    """One message per row as a small integer code (0: none), with one text per code.

    The first message set on a row wins (a row is refused for its first problem)."""

    def __init__(self, rows: int):
        self.codes = np.zeros(rows, dtype=np.int32)
        self.texts: list[str] = [""]
        self.arguments: list[str | None] = [None]
        self._index: dict[str, int] = {"": 0}

    def code(self, text: str, argument: str | None = None) -> int:
        code = self._index.get(text)
        if code is None:
            code = self._index[text] = len(self.texts)
            self.texts.append(text)
            self.arguments.append(argument)
        return code

    def set(self, mask, text: str, argument: str | None = None) -> None:
        """Give ``text`` to the rows of boolean ``mask`` that have no message yet."""
        mask = np.asarray(mask, dtype=bool)
        if mask.any():
            self.codes[mask & (self.codes == 0)] = self.code(text, argument)

    def set_row(self, row: int, text: str, argument: str | None = None) -> None:
        if self.codes[row] == 0:
            self.codes[row] = self.code(text, argument)

    @property
    def flagged(self) -> np.ndarray:
        return self.codes != 0

    def text(self, row: int) -> str:
        return self.texts[self.codes[row]]

    def argument(self, row: int) -> str | None:
        return self.arguments[self.codes[row]]


class WarningBook:
    """Warnings per row as bits of an integer mask, with one text per bit; rows may
    carry several.  ``render`` joins a row's texts with "; "."""

    def __init__(self, rows: int):
        self.masks = np.zeros(rows, dtype=np.int64)
        self.texts: list[str] = []
        self._index: dict[str, int] = {}

    def add(self, mask, text: str) -> None:
        mask = np.asarray(mask, dtype=bool)
        if not mask.any():
            return
        bit = self._index.get(text)
        if bit is None:
            if len(self.texts) >= 62:  # more distinct warnings than bits: keep the first 62
                return
            bit = self._index[text] = len(self.texts)
            self.texts.append(text)
        self.masks[mask] |= np.int64(1) << np.int64(bit)

    def row(self, row: int) -> list[str]:
        mask = int(self.masks[row])
        return [text for bit, text in enumerate(self.texts) if mask >> bit & 1]

    def counts(self) -> dict[str, int]:
        """Rows carrying each warning, by its text."""
        return {text: int(np.count_nonzero(self.masks & (np.int64(1) << np.int64(bit))))
                for bit, text in enumerate(self.texts)}

    def categories(self) -> tuple[np.ndarray, list[str]]:
        """(codes, categories): each row's joined warning text as a categorical."""
        masks = self.masks
        # a table's rows carry few distinct warning sets: found by hashing and coded by comparison, O(n) each
        # (sorting 500,000 rows to group them took 75-85 ms a chunk: 28 % of evaluating it, in benchmarks/runs.py)
        try:
            unique = np.sort(np.unique(masks, sorted=False))  # NumPy >= 2.3 hashes
        except TypeError:  # an older NumPy (>= 1.26 is supported) has no unsorted unique: it sorts
            unique = np.unique(masks)
        if unique.size <= 16:
            codes = np.zeros(masks.size, dtype=np.int64)
            for code, mask in enumerate(unique[1:], 1):
                codes[masks == mask] = code
        else:
            unique, codes = np.unique(masks, return_inverse=True)
        categories = []
        for mask in unique:
            categories.append("; ".join(t for bit, t in enumerate(self.texts) if int(mask) >> bit & 1))
        return codes.astype(np.int32), categories


def implausible_message(quantity: Quantity, value: float | None = None) -> str:
    """The warning of an input outside the plausible range for fruit (with its value, for one impact)."""
    plausible = quantity.plausible
    unit = f" {quantity.si_unit}" if quantity.si_unit else ""
    plain = f"; a plain number is read in {quantity.si_unit}" if quantity.si_unit else ""
    shown = f" = {float(value):.6g}{unit}" if value is not None else ""
    return (f"{quantity.name}{shown} is outside the plausible range for fruit, "
            f"[{plausible.low:g}, {plausible.high:g}]{unit}{plain}")


def usage_message(exc: ValueError) -> str:
    """A library error as the CLI's line, and the web app's next to its control: the option named from the
    error's argument (a message that starts with the argument's own name and a colon, ``workdir: ...``, names it
    once)."""
    argument = getattr(exc, "argument", None)
    if isinstance(argument, tuple):  # a conflict between inputs given together
        return conflict_message([option_of(name) for name in argument])
    if isinstance(argument, str) and (argument in INPUTS or argument in COMMAND_ARGUMENTS):
        text = str(exc)
        if text.startswith("argument "):  # worded by the option already (the analysis options)
            return text
        text = text[len(argument) + 2:] if text.startswith(argument + ": ") else text
        return f"argument {COMMAND_ARGUMENTS.get(argument) or option_of(argument)}: {text}"
    return str(exc)


#: Library arguments of the commands that are not table inputs, and their CLI options (``drop``'s
#: ``bounces``, ``line``'s ``alternatives``, the run options of ``batch``, ``sweep`` and ``population``).
COMMAND_ARGUMENTS = {"bounces": "--bounces", "max_impacts": "--max-impacts", "alternatives": "--alternatives",
                     "rows": "-n/--rows", "seed": "--seed", "chunk_size": "--chunk-size", "workers": "--workers",
                     "scheduler": "--scheduler", "engine": "--engine", "workdir": "--workdir",
                     "output": "-o/--output", "input": "IN", "characteristics": "--characteristics",
                     "threshold": "--threshold", "percentiles": "--percentiles", "sample_size": "--sample-size",
                     "rate": "--rate", "file": "FILE",  # file: analyze's recording (the web app's upload)
                     # sphere's own (its log, the sphere, how readings are grouped and judged)
                     "log": "LOG", "sphere": "--sphere", "sphere_mass": "--sphere-mass",
                     "sphere_diameter": "--sphere-diameter", "sphere_modulus": "--sphere-modulus",
                     "sphere_poisson": "--sphere-poisson", "sphere_calibration": "--sphere-calibration",
                     "sphere_restitution": "--sphere-restitution", "columns": "--columns", "points": "--points",
                     "point_gap": "--point-gap", "pass_gap": "--pass-gap", "uncertainty": "--uncertainty",
                     "logger_rate": "--logger-rate", "target": "--target", "pad": "--pad", "spreads": "--no-spreads",
                     # fit-damage's table of tests and its fitted fruit's name
                     "tests": "TESTS", "fitted_name": "--name"}




def check_fruit_file(entry, shown: str) -> None:
    """A fruit file's values (and their ranges' ends, which a lot draws from) inside the allowed range of the input
    each one is (``quantities.FRUIT_FIELD_INPUTS``): the check ``--mass``, ``--modulus``, … get, refused the same way (naming the
    file, the column and the value)."""
    from fruitimpact.library.catalogue import LibraryError

    for field, name in FRUIT_FIELD_INPUTS.items():
        value = getattr(entry, field)
        if value is None:
            continue
        quantity = INPUTS[name]
        for column, number in ((field, value.value), (f"{field}_low", value.low), (f"{field}_high", value.high)):
            if not quantity.allowed.contains(float(number)):
                text = range_message(quantity).replace(quantity.name, column, 1)
                raise LibraryError(f"fruit file {shown!r}: {text} (as {quantity.option} must be); got {number!r}")


def fruit_file_warnings(path) -> list[tuple[str, str]]:
    """The plausibility warnings of a fruit file's values, as the options get them: (input name, warning) for each
    value of ``quantities.FRUIT_FIELD_INPUTS`` outside its input's plausible range for fruit (``implausible_message``, naming the
    file).  The file is loaded (:func:`load_fruit_file`; ``LibraryError`` if it cannot be)."""
    import os

    from fruitimpact.library.catalogue import load_fruit_file

    entry = load_fruit_file(path)
    out = []
    for field, name in FRUIT_FIELD_INPUTS.items():
        value = getattr(entry, field)
        quantity = INPUTS[name]
        if value is None or quantity.plausible is None or quantity.plausible.contains(float(value.value)):
            continue
        out.append((name, f"{implausible_message(quantity, value.value)} (the fruit file {os.fspath(path)}'s "
                          f"{field})"))
    return out


def _register_fruit_file_checks() -> None:
    from fruitimpact.library.catalogue import FILE_CHECKS

    if check_fruit_file not in FILE_CHECKS:
        FILE_CHECKS.append(check_fruit_file)


_register_fruit_file_checks()


__all__ = ["InputError", "check_fruit_file", "fruit_file_warnings", "MessageBook", "WarningBook", "check_choice", "check_conflicts", "check_flag", "choice_message",
           "check_input_name", "spec_text", "check_value", "conflict_message",
           "implausible_message", "nan_message", "range_message", "read_count", "read_value",
           "unreadable_message", "COMMAND_ARGUMENTS", "usage_message", "is_boolean"]
