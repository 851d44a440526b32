"""A table of drop or pendulum tests: its columns and outcomes, read and checked row by row (``read_tests``);
the constants the fit shares.  Package overview: :mod:`fruitimpact.handling.droptests`."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from fruitimpact.library.textfiles import table_lines, yes_or_no
from fruitimpact.physics.constants import STANDARD_GRAVITY


#: Bruise depth over the peak deformation of the impact that made it (Stropek & Gołacki 2020, Postharvest Biol.
#: Technol. 163:111120, pear, three highest impact speeds), for a bruise of the library's width 2a/1.4.
DEPTH_TO_DEFORMATION = 2.5
#: The deepest cap a measured bruise diameter w is given: a hemisphere, depth w/2.
MAX_DEPTH_TO_WIDTH = 0.5
#: The interval every fit reports.
INTERVAL = "95 % profile likelihood"
#: Rows a table of tests may have: the fit costs about 10 ms per test for volumes (20,000 tests ≈ 3–4 min on one
#: core, 2,000 ≈ 20 s), far less for 0/1 outcomes; above this the table is refused.
MAX_TESTS = 20_000
#: The impact speeds √(2 E/m) a test may have [m/s]: 100 times beyond the plausible range for fruit
#: (``INPUTS["velocity"].plausible``, 0.01–15 m/s) on either side; outside it no fruit impact is computed.
SPEED_LIMITS = (1e-4, 1.5e3)
#: Fruit-to-fruit ranges written to the fitted fruit: ±2 lognormal σ (a lot draws a library range as a split
#: normal whose ends are ±2 sd, ``impact.presets.lot_spreads``).
RANGE_SIGMAS = 2.0
#: Test masses whose median differs from the fruit's by more than this share are said to (the failure stress uses
#: the fruit's own mass and size).
MASS_MISMATCH = 0.25
#: The standard normal's 97.5 % point: a 95 % interval is ±1.96 standard errors.
_Z95 = 1.959963984540054
#: What the failure stress's interval holds, and what it does not.
STRESS_NOTE = ("its interval is the threshold energy's carried through the same impact (for Hertz contact the stress "
               "goes as W^(1/5), so it is narrow); the fruit's modulus, Poisson ratio and size are taken as exact, and "
               "the stress goes as E*^(4/5): their uncertainty is not in it")


@dataclass(frozen=True)
class Outcome:
    """An outcome column: what it measures, its dimension for units (``impact.units``; None: 0/1) and the model
    it is fitted by (``damage.fitting``)."""

    name: str
    doc: str
    dimension: str | None
    model: str


#: The outcome columns a table of tests may have (one of them).
OUTCOMES = {outcome.name: outcome for outcome in (
    Outcome("bruise_volume", "bruise volume [m³] (0: not bruised)", "volume", "volume"),
    Outcome("bruise_diameter", "bruise diameter at the surface [m] (0: not bruised), turned into a volume",
            "length", "volume"),
    Outcome("bruised", "bruised or not (1/0, true/false, yes/no)", None, "incidence"),
)}
#: How the energy of a test is given: the column, what it is, and its dimension.
ENERGY_COLUMNS = {"drop_height": ("a drop: the impact energy is m g h", "length"),
                  "energy": ("a pendulum's impact energy [J]", "energy")}
#: Every column of a table of tests.
TEST_COLUMNS = (*ENERGY_COLUMNS, "surface", "mass", "diameter", *OUTCOMES)
#: What each model of ``damage.fitting.MODELS`` is, for the report.
MODEL_TEXT = {
    "volume": "per-fruit threshold lognormal around W_th (spread threshold_spread); bruised fruit BV = BS (W - T_i) "
              "with lognormal scatter (volume_scatter), so BS is the median volume per joule; unbruised fruit "
              "censored (T_i >= W)",
    "incidence": "per-fruit threshold lognormal around W_th: probit in ln W, P(bruised) = Phi((ln W - ln W_th) / "
                 "threshold_spread); W_th is the 50 % point",
}


@dataclass
class Tests:
    """The usable tests of a table: ``label`` (the file, or "tests"), per row its place ``where``, ``energy`` [J]
    the impact energy (m g h of a drop, the pendulum's energy), ``drop`` (True: a drop), mass [kg], diameter [m]
    (NaN: the fruit's), surface, outcome value (SI, or 0/1), and the rows refused (``skipped``: (where, message))
    and the table's warnings (``warnings``: one per column with implausible values)."""

    label: str
    outcome: Outcome
    where: list
    energy: np.ndarray
    drop: np.ndarray
    mass: np.ndarray
    diameter: np.ndarray
    surface: list
    value: np.ndarray
    skipped: list
    warnings: list


# ------------------------------------------------------------------------------------------------- reading

def _refuse(message: str):
    from fruitimpact.impact.validation import InputError

    return InputError(message, "tests")


def _too_many(label: str, count: int):
    return _refuse(f"{label}: {count} tests; a table holds at most {MAX_TESTS:,} (the fit costs about 10 ms per "
                   f"test: split the table, or fit a random sample of it)")


def _plain(cell):
    """A cell as Python has it: numpy scalars as floats, ints and bools (messages show 0.5, not np.float64(0.5))."""
    return cell.item() if isinstance(cell, np.generic) else cell


def _table(tests):
    """(label, header, rows): rows as (where, cells or None for a ragged line, its message)."""
    if isinstance(tests, (str, os.PathLike)):
        import csv

        label = os.fspath(tests)
        try:
            numbered = table_lines(tests)
        except ValueError as exc:
            raise _refuse(str(exc)) from None
        if not numbered:
            raise _refuse(f"{label} is empty: expected a header ({', '.join(TEST_COLUMNS)})")
        if len(numbered) - 1 > MAX_TESTS:
            raise _too_many(label, len(numbered) - 1)
        header = next(csv.reader([numbered[0][1]]))
        rows = []
        for number, line in numbered[1:]:
            cells = next(csv.reader([line]))
            where = f"{label}, line {number}"
            rows.append((where, cells if len(cells) == len(header) else None,
                         f"{len(cells)} fields, the header has {len(header)}"))
        return label, header, rows
    if hasattr(tests, "columns") and hasattr(tests, "__getitem__") and not isinstance(tests, dict):
        columns = {name: list(tests[name]) for name in tests.columns}  # a DataFrame
    elif hasattr(tests, "items"):
        columns = dict(tests.items())
    else:
        raise _refuse(f"tests must be a CSV file (a path), a mapping of column name to values or a DataFrame; got "
                      f"{type(tests).__name__}")
    lengths = {len(value) for value in columns.values() if not isinstance(value, (str, bytes))
               and hasattr(value, "__len__")}
    if len(lengths) > 1:
        raise _refuse(f"tests: the columns have different lengths ({', '.join(map(str, sorted(lengths)))})")
    count = lengths.pop() if lengths else 1
    if count > MAX_TESTS:
        raise _too_many("tests", count)
    header = list(columns)
    cells = [[_plain(c) for c in value] if not isinstance(value, (str, bytes)) and hasattr(value, "__len__")
             else [_plain(value)] * count for value in columns.values()]
    return "tests", header, [(f"tests row {i + 1}", [column[i] for column in cells], "") for i in range(count)]


def _blank(cell) -> bool:
    if cell is None or type(cell).__name__ == "NAType":
        return True
    return isinstance(cell, str) and not cell.strip()


def _missing_number(cell) -> bool:
    """A float NaN of a DataFrame or mapping (not the text "nan" of a CSV): pandas' mark of a value not given."""
    return isinstance(cell, float) and math.isnan(cell)


def _number(column: str, cell, dimension: str) -> float:
    """A cell of a numeric column in SI (units parsed); ValueError naming the column otherwise."""
    from fruitimpact.impact.units import SI_UNIT, UNITS, parse_quantity

    if isinstance(cell, bool):
        raise ValueError(f"{column} must be a number; got {cell!r}")
    try:
        value = parse_quantity(cell if isinstance(cell, str) else float(cell), dimension)
    except (TypeError, ValueError, OverflowError):
        units = ", ".join(u for u in UNITS[dimension] if u)
        raise ValueError(f"{column} must be a number (units allowed: {units}; a plain number is "
                         f"{SI_UNIT[dimension]}); got {cell!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{column} must be a finite number; got {cell!r}")
    return value


def _flag(cell) -> float:
    if isinstance(cell, bool):
        return float(cell)
    text = str(cell).strip().lower()
    answer = yes_or_no(text)
    if answer is not None:
        return float(answer)
    try:  # 1, 0, 1.0, "1.0", "0.0": read as numbers are
        number = float(cell if not isinstance(cell, str) else text)
    except (TypeError, ValueError):
        number = math.nan
    if number in (0.0, 1.0):
        return number
    raise ValueError(f"bruised must be 1 or 0 (true/false, yes/no); got {cell!r}")


#: How far beyond the plausible range for fruit (``INPUTS[name].plausible``) a test's mass or diameter may lie
#: before its row is refused: a factor of 100 either side (a typo of units stays a warning, an absurd value is no
#: fruit impact and would overflow the impact's arithmetic).
SIZE_FACTOR = 100.0


def _size_check(name: str, value: float, cell) -> None:
    from fruitimpact.impact.quantities import INPUTS

    plausible = INPUTS[name].plausible
    low, high = plausible.low / SIZE_FACTOR, plausible.high * SIZE_FACTOR
    if not low <= value <= high:
        raise ValueError(f"{name} must lie within [{low:g}, {high:g}] {INPUTS[name].si_unit} (100 times beyond the "
                         f"plausible range for fruit), where no fruit impact is computed; got {cell!r}")


def _speed_check(column: str, speed: float, cell) -> None:
    low, high = SPEED_LIMITS
    if not low <= speed <= high:
        raise ValueError(f"{column}: its impact speed √(2 E/m) = {speed:.3g} m/s is outside [{low:g}, {high:g}] m/s "
                         f"(100 times beyond the plausible 0.01–15 m/s for fruit), where no fruit impact is "
                         f"computed; got {cell!r}")


class _Implausible:
    """Values outside the plausible range, collected per column: one warning for the table."""

    def __init__(self):
        self.seen = {}

    def add(self, column: str, where: str, text: str) -> None:
        first, count = self.seen.get(column, (None, 0))
        self.seen[column] = (first or (where, text), count + 1)

    def warnings(self, rows: int) -> list:
        out = []
        for (where, text), count in self.seen.values():
            more = f"; {count} of {rows} rows are" if count > 1 else ""
            out.append(f"{text} ({where}{more})")
        return out


def read_tests(tests, *, fruit_diameter: float | None = None) -> Tests:
    """The usable tests of ``tests`` (a CSV path, a mapping of columns or a DataFrame; at most ``MAX_TESTS`` rows).

    The table is refused as a whole (``InputError`` naming ``tests``, before any work) for more than ``MAX_TESTS``
    rows, unknown or repeated columns, no outcome column or more than one, neither ``drop_height`` nor ``energy``,
    no ``mass`` or ``surface`` column, an unknown surface, or no usable row; a row with a bad value (not a number,
    ≤ 0, NaN, a ragged line, both or neither of ``drop_height`` and ``energy``, an impact speed outside
    ``SPEED_LIMITS``, a bruise wider or larger than the fruit: its ``diameter``, else ``fruit_diameter`` [m]) is
    skipped and reported.  In a DataFrame or mapping a NaN in ``drop_height`` or ``energy`` where the row gives the
    other is "not given" (a table mixing drops and pendulum tests).  A column with implausible values (outside the
    plausible range of that input for fruit) gives one warning for the table."""
    from fruitimpact.impact.quantities import INPUTS
    from fruitimpact.impact.registries import SURFACE_CHOICES
    from fruitimpact.impact.validation import check_value, implausible_message

    label, header, rows = _table(tests)
    keys = [str(name).strip().replace("-", "_") for name in header]
    unknown = [name for name, key in zip(header, keys) if key not in TEST_COLUMNS]
    if unknown:
        raise _refuse(f"{label}: unknown column(s) {', '.join(map(repr, unknown))} (columns: "
                      f"{', '.join(TEST_COLUMNS)})")
    twice = sorted({key for key in keys if keys.count(key) > 1})
    if twice:
        raise _refuse(f"{label}: column {twice[0]!r} is given twice")
    outcomes = [key for key in keys if key in OUTCOMES]
    if len(outcomes) != 1:
        listed = "; ".join(f"{o.name}: {o.doc}" for o in OUTCOMES.values())
        raise _refuse(f"{label}: " + (f"no outcome column: give one of {listed}" if not outcomes else
                                      f"one outcome column, not {len(outcomes)} ({', '.join(outcomes)})"))
    if not any(key in ENERGY_COLUMNS for key in keys):
        raise _refuse(f"{label}: give drop_height [m] (drop tests, energy m g h) or energy [J] (pendulum tests); "
                      f"neither column is there")
    for required, what in (("mass", "the fruit's mass [kg]"), ("surface", "a library surface")):
        if required not in keys:
            raise _refuse(f"{label}: the {required} column is missing ({what}, in every test)")
    if not rows:
        raise _refuse(f"{label}: no tests below the header")
    outcome = OUTCOMES[outcomes[0]]
    surfaces = [name for name in SURFACE_CHOICES if name != "fruit"]
    parsed, skipped, implausible = [], [], _Implausible()
    velocity = INPUTS["velocity"]
    for where, cells, ragged in rows:
        if cells is None:
            skipped.append((where, ragged))
            continue
        row = {key: cell for key, cell in zip(keys, cells) if not _blank(cell)}
        if all(key in row for key in ENERGY_COLUMNS):  # a DataFrame mixing drops and pendulum tests: NaN is "not this"
            missing = [key for key in ENERGY_COLUMNS if _missing_number(row[key])]
            if len(missing) == 1:
                del row[missing[0]]
        surface = row.get("surface")
        surface = surface.strip() if isinstance(surface, str) else surface
        if surface is not None and surface not in surfaces:  # a misspelt surface is the table's, not one row's
            raise _refuse(f"{where}: surface must be one of {', '.join(surfaces)}; got {surface!r}"
                          + (" (a test lands on a fixed surface; fruit on fruit is not a drop test)"
                             if surface == "fruit" else ""))
        try:
            given = [key for key in ENERGY_COLUMNS if key in row]
            if len(given) != 1:
                raise ValueError("give drop_height or energy, not both" if given else
                                 "drop_height or energy must be given")
            if surface is None:
                raise ValueError(f"surface must be given ({', '.join(surfaces)})")
            if "mass" not in row:
                raise ValueError("mass must be given [kg]")
            mass = check_value("mass", row["mass"])
            _size_check("mass", mass, row["mass"])
            key = given[0]
            if key == "drop_height":
                height = check_value("drop_height", row[key])
                energy, drop = mass * STANDARD_GRAVITY * height, True
                _speed_check(key, math.sqrt(2.0 * STANDARD_GRAVITY * height), row[key])
                if not INPUTS["drop_height"].plausible.contains(height):
                    implausible.add(key, where, implausible_message(INPUTS["drop_height"], height))
            else:
                energy, drop = _number("energy", row[key], "energy"), False
                if energy <= 0.0:
                    raise ValueError(f"energy must be a finite number > 0 J; got {row[key]!r}")
                speed = math.sqrt(2.0 * energy / mass)
                _speed_check(key, speed, row[key])
                if not velocity.plausible.contains(speed):
                    implausible.add(key, where, f"energy = {energy:.6g} J is a {speed:.3g} m/s impact on a "
                                                f"{mass * 1e3:.4g} g fruit, outside the plausible range for fruit, "
                                                f"[{velocity.plausible.low:g}, {velocity.plausible.high:g}] m/s")
            diameter = check_value("diameter", row["diameter"]) if "diameter" in row else math.nan
            if "diameter" in row:
                _size_check("diameter", diameter, row["diameter"])
            for name, value in (("mass", mass), ("diameter", diameter)):
                if math.isfinite(value) and not INPUTS[name].plausible.contains(value):
                    implausible.add(name, where, implausible_message(INPUTS[name], value))
            if outcome.name not in row:
                raise ValueError(f"{outcome.name} must be given ({outcome.doc})")
            if outcome.dimension is None:
                value = _flag(row[outcome.name])
            else:
                value = _number(outcome.name, row[outcome.name], outcome.dimension)
                if value < 0.0:
                    raise ValueError(f"{outcome.name} must be >= 0 (0: not bruised); got {row[outcome.name]!r}")
                size = diameter if math.isfinite(diameter) else fruit_diameter
                whose = "the fruit's diameter" if math.isfinite(diameter) else "the --fruit's diameter"
                if size is not None and outcome.name == "bruise_diameter" and value > size:
                    raise ValueError(f"bruise_diameter must not exceed {whose} {size:g} m; got "
                                     f"{row[outcome.name]!r}")
                if size is not None and outcome.name == "bruise_volume" and value > math.pi * size ** 3 / 6.0:
                    raise ValueError(f"bruise_volume must not exceed the volume of the fruit itself, "
                                     f"{math.pi * size ** 3 / 6.0:.4g} m³ (a sphere of {whose} {size:g} m); got "
                                     f"{row[outcome.name]!r}")
        except ValueError as exc:
            skipped.append((where, str(exc)))
            continue
        parsed.append((where, energy, drop, mass, diameter, surface, value))
    if not parsed:
        first = f" (the first: {skipped[0][0]}: {skipped[0][1]})" if skipped else ""
        raise _refuse(f"{label}: no usable test: every row was refused{first}")
    columns = list(zip(*parsed))
    return Tests(label, outcome, list(columns[0]), np.array(columns[1]), np.array(columns[2], dtype=bool),
                 np.array(columns[3]), np.array(columns[4]), list(columns[5]), np.array(columns[6]), skipped,
                 implausible.warnings(len(rows)))
