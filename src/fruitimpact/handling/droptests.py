"""Drop and pendulum tests → the fruit's bruise threshold energy, bruise susceptibility and failure stress.

A table of tests (one row per fruit hit once): ``drop_height`` [m] (a drop onto ``surface``) or ``energy`` [J] (a
pendulum's impact energy), ``surface`` (a library surface, or ``rigid``), ``mass`` [kg], optionally ``diameter``
[m], and one outcome: ``bruise_volume`` [m³], ``bruise_diameter`` [m] or ``bruised`` (0/1).  Cells may carry units
("10cm", "120g", "350mm3"; ``impact.units``).  At most ``MAX_TESTS`` rows.  :func:`fit_damage` fits, by maximum
likelihood (:mod:`fruitimpact.damage.fitting`):

* on the energy **the simulator compares**: each test's impact energy (m g h of a drop, the pendulum's energy)
  times the fruit's share of it on that test's surface, computed per test by the project's own impact
  (``impact.evaluation``) of the ``fruit``'s flesh with the test's mass, size and surface.  That is what a
  simulation applies a fruit's ``bruise_*_basis = impact`` values to (the fruit's share of ½ m V² on a compliant
  surface), so that ``safe-height --fruit fitted.csv --surface S`` puts onset at the fitted threshold on every
  surface: all of m g h on steel (1 − 1e-5 of it), 9–78 % of it on the foam pad for drops of 2–55 cm;
* the **threshold energy** W_th (the median of the fruit's thresholds: half the fruit bruise at W_th) and the
  **bruise susceptibility** BS (the median volume per joule above a fruit's threshold; the volume's scatter is
  lognormal), with 95 % profile-likelihood intervals; unbruised fruit are censored thresholds, not zeros of a
  line; from 0/1 outcomes the threshold only (BS is null: a 0/1 outcome has no volume);
* the **failure stress** σ_f, per surface, where that surface's tests bracket their threshold (bruised and
  unbruised fruit, tests on both sides of it): the stress of the criterion at the impact of the ``fruit`` (its
  own mass and size) whose compared energy is that surface's threshold, found by the safe-height root
  (``handling.heights.safe_heights``) and computed with the project's impact: ``pressure`` σ_f = p0, ``shear``
  σ_f = 2 τ_max (``damage.bruise.CRITERIA``'s ratio at σ_f = 1 Pa), and for ``energy`` (no stress of its own) the
  Hertz peak pressure p0.  Its interval is that of the threshold carried through the same impact.  Surfaces whose
  stresses agree within their intervals give one (their precision-weighted geometric mean); surfaces that disagree
  give none (the report holds each one; the fitted fruit then has the energy criterion).

A measured **bruise diameter** w is turned into a volume with the library's bruise shape, the spherical cap
(``damage.bruise.cap_volume``): the library's bruise of an impact is 2a/1.4 wide (``bruise_geometry``: contact
width 1.4 × bruise width) and 2.5 δ_max deep (both Stropek & Gołacki 2020, pear, at the three highest speeds),
δ_max and a being the project's impact of that test; a measured width keeps that shape, depth/width =
2.5 δ_max · 1.4/(2a), so the depth scales with the width, and the cap is at most a hemisphere (depth ≤ w/2).  Pear
data applied to any fruit: the output says so.

The fitted fruit (``output``) is the ``fruit`` with these values, written in the fruit library's own format
(``library.catalogue.fruit_file_text``); every command's ``fruit`` input accepts that file.  Its ranges are the
fruit-to-fruit spreads the fit found (±2 lognormal σ: what a lot draws from, ``impact.presets.lot_spreads``); the
95 % intervals of the estimates stay in the report and the values' notes.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, replace

import numpy as np

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
_TRUE, _FALSE = {"1", "true", "yes", "y"}, {"0", "false", "no", "n"}
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

        from fruitimpact.impact.textfiles import table_lines

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
    if text in _TRUE or text in _FALSE:
        return 1.0 if text in _TRUE else 0.0
    try:  # 1, 0, 1.0, "1.0", "0.0": read as numbers are
        number = float(cell if not isinstance(cell, str) else text)
    except (TypeError, ValueError):
        number = math.nan
    if number in (0.0, 1.0):
        return number
    raise ValueError(f"bruised must be 1 or 0 (true/false, yes/no); got {cell!r}")


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
        for column, ((where, text), count) in self.seen.items():
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


# ------------------------------------------------------------------------------------------------- physics

@dataclass
class Impacts:
    """The project's impact of each test (the ``fruit``'s flesh, the test's mass, size, speed and surface):
    ``energy`` [J] the energy the simulator compares with a threshold on the impact basis (the fruit's share of
    ½ m V²), ``max_deflection`` and ``contact_radius`` [m], ``ok`` where it was computed, ``messages`` why not."""

    energy: np.ndarray
    max_deflection: np.ndarray
    contact_radius: np.ndarray
    ok: np.ndarray
    messages: list


def _impacts(fruit: str, tests: Tests) -> Impacts:
    """Every test's impact, in one ``impact.evaluation.evaluation`` of the table: the energy criterion with the
    threshold set to the test's own impact energy E on the impact basis, so that 1 + bruise_margin is the share
    of E the simulator compares (its own code path: ``_damage_columns``' ``impact_share``)."""
    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.impact.status import INACCURATE

    n = tests.energy.size
    table = {"fruit": [fruit] * n, "surface": list(tests.surface), "criterion": ["energy"] * n,
             "mass": tests.mass, "velocity": np.sqrt(2.0 * tests.energy / tests.mass),
             "bruise_energy": tests.energy, "bruise_basis": ["impact"] * n,
             "diameter": [None if math.isnan(d) else float(d) for d in tests.diameter]}
    result = evaluation(table)
    margin = np.asarray(result.columns["bruise_margin"], dtype=float)
    ok = (result.status <= INACCURATE) & np.isfinite(margin) & (margin > -1.0)
    energy = np.where(ok, tests.energy * (1.0 + margin), np.nan)
    messages = [result.messages.text(i) if not ok[i] else "" for i in range(n)]
    return Impacts(energy, np.asarray(result.columns["max_deflection"], dtype=float),
                   np.asarray(result.columns["contact_radius"], dtype=float), ok, messages)


def _diameter_volumes(tests: Tests, fruit: str, impacts: Impacts | None = None):
    """Bruise volumes [m³] of measured bruise diameters (module docstring: the cap of width w whose depth keeps the
    library's bruise shape of that impact, at most a hemisphere), the rows kept, and the rows whose impact could not
    be computed (where, message)."""
    from fruitimpact.damage.bruise import CONTACT_TO_BRUISE_WIDTH, cap_volume
    from fruitimpact.library.catalogue import fruits

    impacts = impacts if impacts is not None else _impacts(fruit, tests)
    entry = fruits()[fruit]
    ratio = entry.bruise_width_ratio.value if entry.bruise_width_ratio is not None else CONTACT_TO_BRUISE_WIDTH
    ok = impacts.ok & np.isfinite(impacts.max_deflection) & (impacts.contact_radius > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        shape = DEPTH_TO_DEFORMATION * impacts.max_deflection * ratio / (2.0 * impacts.contact_radius)
    shape = np.where(ok, np.minimum(shape, MAX_DEPTH_TO_WIDTH), 0.0)
    width = np.where(ok, tests.value, 0.0)
    volumes = np.where(width > 0.0, cap_volume(shape * width, width), 0.0)
    failed = [(tests.where[i], f"its impact could not be computed: {impacts.messages[i] or 'no contact'}")
              for i in np.flatnonzero(~ok)]
    return volumes, ok, failed


#: Outcomes fitted as another: name → (the converter of a table's values, a description of it for the fruit).
CONVERSIONS = {"bruise_diameter": (_diameter_volumes, lambda fruit: (
    f"bruise volume = the spherical cap (damage.bruise.cap_volume) of the measured diameter w, its depth keeping the "
    f"shape of the library's bruise of that test's impact: {DEPTH_TO_DEFORMATION:g} x the peak deformation deep and "
    f"2a/1.4 wide (contact radius a; the {fruit} flesh), so depth = {DEPTH_TO_DEFORMATION:g} delta_max w/(2a/1.4), "
    f"at most w/2 (a hemisphere) (Stropek & Golacki 2020, pear data applied to any fruit)"))}


def _onset_heights(fruit: str, surfaces, energies):
    """The drop height [m] of ``fruit`` (its own mass and size) on each surface at which the energy the simulator
    compares is each energy [J]: the safe-height root of the energy criterion with that threshold on the impact
    basis (``handling.heights.safe_heights``), so that a safe height of the fitted fruit finds the same onset."""
    from fruitimpact.handling.heights import safe_heights

    n = len(energies)
    table = {"fruit": [fruit] * n, "surface": list(surfaces), "criterion": ["energy"] * n,
             "bruise_energy": np.asarray(energies, dtype=float), "bruise_basis": ["impact"] * n}
    heights, _ = safe_heights(table, n)
    return np.where(np.isfinite(heights) & (heights > 0.0), heights, np.nan)


def _onset_stresses(fruit: str, criterion: str, surfaces, energies):
    """The failure stress [Pa] whose criterion onset sits at each compared energy [J] on each surface: the stress
    criteria's own stress at σ_f = 1 Pa (their ratio is stress/σ_f), the Hertz peak pressure for a criterion
    without a stress, at the impact ``_onset_heights`` finds; NaN where there is none."""
    from fruitimpact.damage.bruise import CRITERIA
    from fruitimpact.impact.evaluation import evaluation

    heights = _onset_heights(fruit, surfaces, energies)
    found = np.isfinite(heights)
    rule = CRITERIA[criterion if "failure_stress" in CRITERIA[criterion].inputs else "pressure"]
    stress = np.full(len(energies), np.nan)
    if found.any():
        n = int(found.sum())
        result = evaluation({"fruit": [fruit] * n, "surface": [s for s, f in zip(surfaces, found) if f],
                             "criterion": ["none"] * n, "drop_height": heights[found]})
        pressure = np.asarray(result.columns["max_pressure"], dtype=float)
        poisson = np.asarray(result.columns["poisson"], dtype=float)
        given = {"peak_pressure": pressure, "poisson": poisson, "failure_stress": 1.0}
        ratio = np.asarray(rule.ratio(**{name: given[name] for name in rule.inputs}), dtype=float)
        stress[found] = np.where(result.status == 0, ratio, np.nan)
    return stress, rule.name


# ------------------------------------------------------------------------------------------- fitted fruit

def _name(label: str, fruit: str, name) -> str:
    from fruitimpact.impact.validation import InputError
    from fruitimpact.library.catalogue import fruits, is_fruit_file

    if name is None:
        base = fruits()[fruit].name
        stem = os.path.splitext(os.path.basename(label))[0] if label != "tests" else ""
        slug = re.sub(r"[^a-z0-9]+", "-", stem.lower()).strip("-")
        return f"{base}-fitted" + (f"-{slug}" if slug else "")
    if not isinstance(name, str) or not name or name != name.lower() or " " in name or is_fruit_file(name):
        raise InputError(f"the fitted fruit's name must be lower-case without spaces (not a .csv path); got {name!r}",
                         "fitted_name")
    if name in fruits().library:
        raise InputError(f"the fitted fruit's name must not be a library fruit's ({', '.join(fruits().library)}); got "
                         f"{name!r}", "fitted_name")
    return name


def _shown(number) -> str:
    return "open" if number is None else f"{number:.6g}"


def _value(estimate, spread, interval, unit: str, source: str, what: str, spread_text: str, basis: str = ""):
    """A library ``Value`` of a fitted estimate: its range the fruit-to-fruit ``spread`` (low, high) the fit found
    (what a lot draws from), or the value itself where the fit resolved none (the library's "no spread known");
    the 95 % interval of the estimate in the note."""
    from fruitimpact.library.catalogue import Value

    low95, high95 = interval
    if spread is None:
        low = high = estimate
        ranged = "range: the value (the tests do not resolve a fruit-to-fruit spread)"
    else:
        low, high = min(spread[0], estimate), max(spread[1], estimate)
        ranged = (f"range: the fruit-to-fruit spread the fit found, ±{RANGE_SIGMAS:g} lognormal σ ({spread_text}), "
                  f"which a lot draws from as it draws a library range")
    note = (f"{what}; {ranged}; the estimate's {INTERVAL} 95 % interval: [{_shown(low95)}, {_shown(high95)}] {unit}"
            + ("; an open end: the tests do not bound it on that side" if None in (low95, high95) else ""))
    return Value(estimate, low, high, unit, source, True, note, basis)


def _fitted_fruit(report: dict, template, name: str):
    """The template fruit with the fitted values (none borrowed: a value not fitted is left empty), their ranges the
    fruit-to-fruit spreads, and the criterion the fitted values support."""
    from fruitimpact.library.catalogue import FITTED_BY

    count = report["tests"]
    source = f"derived: {FITTED_BY} to {report['tests_file']}, {count} tests"
    basis = ("impact: the fruit's share of the impact energy (m g h of a drop, the pendulum's energy) on each test's "
             "surface, as a simulation compares it")
    ranges = report["fruit_ranges"]
    fields = {"bruise_susceptibility": None, "bruise_threshold_energy": None, "failure_stress": None}
    if report["bruise_susceptibility"] is not None:
        fields["bruise_susceptibility"] = _value(
            report["bruise_susceptibility"], ranges.get("bruise_susceptibility"),
            (report["bruise_susceptibility_low"], report["bruise_susceptibility_high"]), "m^3/J", source,
            f"the median bruise volume per joule above a fruit's threshold, maximum-likelihood estimate "
            f"({MODEL_TEXT[report['model_name']]}); basis: {basis}",
            f"the volume scatter σ_v = {report['volume_scatter']:.3g}, which holds the measurement's scatter too: an "
            f"upper bound of the fruit-to-fruit spread" if report["volume_scatter"] is not None else "", "impact")
    if report["bruise_energy"] is not None:
        fields["bruise_threshold_energy"] = _value(
            report["bruise_energy"], ranges.get("bruise_energy"),
            (report["bruise_energy_low"], report["bruise_energy_high"]), "J", source,
            f"median of the fruit's thresholds (half the fruit bruise at it), maximum-likelihood estimate; basis: "
            f"{basis}",
            f"the thresholds' spread σ_t = {report['threshold_spread']:.3g}" if report["threshold_spread"] is not None
            else "", "impact")
    criterion, criterion_source, criterion_note = None, "", ""
    if report["failure_stress"] is not None:
        fields["failure_stress"] = _value(
            report["failure_stress"], ranges.get("failure_stress"),
            (report["failure_stress_low"], report["failure_stress_high"]), "Pa",
            f"{source} (the {report['failure_stress_rule']} criterion's stress at the threshold energy on "
            f"{report['failure_stress_surface']}, with the {template.name} entry's modulus, Poisson ratio, size and "
            f"mass)", f"stress at bruise onset under the {report['criterion']} criterion",
            "the stress at the thresholds ±2 σ_t through the same impact")
        criterion = report["criterion"]
        criterion_source = (f"{FITTED_BY} to {report['tests_file']}, {count} tests: the failure stress is this "
                            f"criterion's stress at the fitted threshold energy")
        criterion_note = ("the criterion the failure stress was fitted under; under another criterion it would need "
                          "its own (a command that uses it under another says so)")
    elif report["bruise_energy"] is not None:
        criterion = "energy"
        criterion_source = (f"{FITTED_BY} to {report['tests_file']}, {count} tests: the threshold energy is fitted "
                            f"and no failure stress")
        criterion_note = (f"the criterion the fitted values support: no failure stress was fitted "
                          f"({report['failure_stress_reason'] or 'criterion none'}), so only the energy criterion "
                          f"uses the fitted threshold")
    fitted = [label for key, label in (("bruise_threshold_energy", "bruise threshold energy"),
                                       ("bruise_susceptibility", "bruise susceptibility"),
                                       ("failure_stress", "failure stress")) if fields[key] is not None]
    return replace(template, name=name, criterion=criterion, criterion_source=criterion_source,
                   criterion_note=criterion_note, **fields,
                   description=f"{template.name} fitted to {report['tests_file']} ({count} tests): "
                               f"{', '.join(fitted) or 'nothing'} fitted by fruitimpact fit-damage; the other values "
                               f"are the {template.name} entry's",
                   source=f"{FITTED_BY} to {report['tests_file']}, {count} tests; other values: "
                          f"the {template.name} entry of the fruit library ({template.source})")


def _same_file(one, two) -> bool:
    try:
        return os.path.samefile(one, two)
    except OSError:
        return os.path.normcase(os.path.realpath(one)) == os.path.normcase(os.path.realpath(two))


# ----------------------------------------------------------------------------------------------------- fit

def fit_damage(tests, *, fruit: str | None = None, criterion: str | None = None, name: str | None = None,
               output=None) -> dict:
    """Fit a fruit's bruise threshold energy, bruise susceptibility and failure stress to drop or pendulum tests.

    Maximum likelihood with unbruised fruit censored (each fruit has its own threshold, lognormal around W_th) and
    lognormal scatter on the volume (:mod:`fruitimpact.damage.fitting` gives the model and why); 95 %
    profile-likelihood intervals.  The energies are those the simulator compares with the fitted values: each
    test's impact energy (m g h of a drop, the pendulum's energy) times the fruit's share of it on that test's
    surface, by the project's impact of the ``fruit``'s flesh (all of it on steel, a part on a pad).  The failure
    stress is the criterion's stress at the threshold, per surface, by the project's impact, where a surface's tests
    bracket their threshold.

    Parameters
    ----------
    tests : str, path, mapping or DataFrame
        The tests, one row per fruit (at most ``MAX_TESTS``): ``drop_height`` [m] or ``energy`` [J], ``surface`` (a
        library surface or ``rigid``), ``mass`` [kg], optional ``diameter`` [m], and one outcome: ``bruise_volume``
        [m³], ``bruise_diameter`` [m] (turned into a volume: the cap of that width with the library's bruise shape
        of that impact, the module's docstring) or ``bruised`` (0/1).  Cells may carry units ("10cm", "120g").  A
        CSV may have ``#`` comments.  In a DataFrame, NaN in the one of ``drop_height`` and ``energy`` a row does
        not use is "not given".
    fruit : str, optional
        The fruit whose flesh gives each test's compared energy, whose modulus, Poisson's ratio, size, mass and
        restitution give the failure stress, and the template of the fitted fruit: a library name or a fruit file
        (default: the project's default fruit).
    criterion : str, optional
        ``pressure``, ``shear`` or ``energy`` (the stress whose onset is fitted); None or ``preset``: the fruit's
        own (without one, no failure stress is fitted); ``none``: no failure stress.
    name : str, optional
        The fitted fruit's name (lower case, no spaces); default ``<fruit>-fitted-<tests file stem>``.
    output : str or path, optional
        Write the fitted fruit there (``.csv``, not the table of tests itself), in the fruit library's format,
        atomically.

    Returns
    -------
    dict
        ``bruise_susceptibility`` [m³/J] (the median volume per joule above a fruit's threshold; None from 0/1
        outcomes), ``bruise_energy`` [J] (the median threshold), ``failure_stress`` [Pa] (None where no surface's
        tests bracket their threshold, or where surfaces disagree), each with ``_low`` and ``_high`` (the 95 %
        interval of the estimate; None where the data leave that side open); ``fruit_ranges`` (name → [low, high]:
        the fruit-to-fruit spread written as the fitted fruit's range); ``basis`` (``impact``), ``basis_note`` and
        ``energy_share_by_surface`` (surface → the least and greatest share of the impact energy compared);
        ``tests``, ``bruised``, ``unbruised``, ``energy_min``, ``energy_max`` [J] (compared energies);
        ``threshold_spread`` σ_t and ``volume_scatter`` σ_v [-] (lognormal σ; None where not fitted);
        ``failure_stress_surface`` (the surfaces it is from), ``failure_stress_by_surface`` (surface → its tests,
        threshold and stress with their intervals, and why none), ``failure_stress_rule`` (the criterion whose
        stress it is), ``failure_stress_reason`` (why it is None), ``failure_stress_note`` (what its interval
        holds); ``outcome``, ``model`` and ``model_name`` (``volume`` or ``incidence``), ``interval``,
        ``log_likelihood``, ``volume_conversion``, ``rows_skipped`` (row, message), ``tests_file``, ``fruit``,
        ``criterion``, ``name``, ``output``; ``status`` (``ok``, or ``failed``: nothing could be fitted),
        ``message`` (what was fitted, or why nothing was) and ``warnings``.

    Raises
    ------
    ValueError
        (``InputError``) before any work: a table that cannot be read, more than ``MAX_TESTS`` rows, unknown
        columns, no outcome column, neither drop_height nor energy, an unknown surface, no usable row; a fruit or
        criterion that is not known; an output that cannot be written or is the table of tests.  The message names
        the argument, the row and the column.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.fit_damage("examples/drop-tests.csv", fruit="apple", criterion="shear")  # doctest: +SKIP
    >>> report["bruise_energy"], report["bruise_energy_low"], report["bruise_energy_high"]  # doctest: +SKIP

    References
    ----------
    Bruise volume BV = BS (W − W_th)₊: L. O. Opara & P. B. Pathare, Postharvest Biol. Technol. 91 (2014) 9–24.
    Censored (Tobit) likelihood: J. Tobin, Econometrica 26 (1958) 24–36.  Profile-likelihood intervals:
    D. J. Venzon & S. H. Moolgavkar, Appl. Statist. 37 (1988) 87–94.  Bruise depth 2.5 × peak deformation and
    contact width 1.4 × bruise width: Z. Stropek & K. Gołacki, Postharvest Biol. Technol. 163 (2020) 111120.
    Criteria: docs/bruise.md.
    """
    from fruitimpact.damage.fitting import MODELS as FIT_MODELS
    from fruitimpact.impact.outputs import CSV_FORMAT, atomic_write, check_output
    from fruitimpact.impact.quantities import INPUTS
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.impact.validation import InputError, check_choice, fruit_file_warnings
    from fruitimpact.library.catalogue import fruit_file_text, fruits, is_fruit_file, read_fruit_file

    fruit = check_choice("fruit", fruit if fruit is not None else INPUTS["fruit"].default, fruits())
    template = fruits()[fruit]
    warnings = [text for _, text in fruit_file_warnings(fruit)] if is_fruit_file(fruit) else []
    if criterion is not None:
        check_choice("criterion", criterion, REGISTRIES["criterion"])
    if criterion in (None, "preset"):
        used = template.criterion
        if used is None:
            warnings.append(f"failure stress: null: the {template.name} entry names no bruise criterion (give "
                            f"criterion pressure, shear or energy to fit one)")
    else:
        used = None if criterion == "none" else criterion
        if used is None:
            warnings.append("failure stress: null: criterion none")
    if output is not None:
        check_output(output, "output", CSV_FORMAT)
        if isinstance(tests, (str, os.PathLike)) and _same_file(output, tests):
            raise InputError(f"output: {os.fspath(output)!r} is the table of tests itself: write the fitted fruit to "
                             f"another file", "output")
    table = read_tests(tests, fruit_diameter=template.diameter.value)
    fitted_name = _name(table.label, fruit, name)
    warnings += table.warnings
    skipped = list(table.skipped)
    impacts = _impacts(fruit, table)
    keep = impacts.ok.copy()
    skipped += [(table.where[i], f"its impact could not be computed: {impacts.messages[i]}")
                for i in np.flatnonzero(~keep)]
    conversion = None
    values = table.value
    if table.outcome.name in CONVERSIONS:  # an outcome fitted as another (a diameter as a volume)
        convert, describe = CONVERSIONS[table.outcome.name]
        values, converted, failed = convert(table, fruit, impacts)
        skipped += [item for item, i in zip(failed, np.flatnonzero(~converted)) if keep[i]]
        keep &= converted
        conversion = describe(fruit)
        warnings.append(f"bruise volumes derived from bruise diameters: {conversion}")
    if not keep.any():
        raise InputError(f"{table.label}: no usable test: no test's impact could be computed (the first: "
                         f"{skipped[0][0]}: {skipped[0][1]})", "tests")
    for where, message in skipped:
        warnings.append(f"{where}: {message}; the row is skipped")
    energy, outcome, impact_energy = impacts.energy[keep], values[keep], table.energy[keep]
    surfaces = [s for s, k in zip(table.surface, keep) if k]
    model = FIT_MODELS[table.outcome.model]
    fit = model(energy, outcome)
    names = _by_use(surfaces)
    fits = {names[0]: fit} if len(names) == 1 else {
        s: model(energy[mask], outcome[mask]) for s, mask in ((s, np.array([x == s for x in surfaces])) for s in names)}
    bruised = int((outcome > 0.0).sum())
    drops = int(table.drop[keep].sum())
    shares = {}
    for s in names:
        ratio = [e / w for e, w, x in zip(energy, impact_energy, surfaces) if x == s]
        shares[s] = {"min": float(min(ratio)), "max": float(max(ratio))}
    basis_note = ("the fruit's share of the impact energy ("
                  + " and ".join(part for part in (f"m g h of each drop, {drops} tests" if drops else "",
                                                  f"the pendulum's energy, {energy.size - drops} tests"
                                                  if energy.size - drops else "") if part)
                  + f") on each test's surface, which the simulator compares with impact-basis values, by the "
                    f"project's impact of the {template.name} flesh; share: "
                  + ", ".join(f"{s} {v['min']:.5g}" if v["max"] - v["min"] < 5e-5 else
                              f"{s} {v['min']:.3g}-{v['max']:.3g}" for s, v in shares.items()))
    estimates, intervals = fit.estimates, fit.intervals
    report = {
        "tests_file": table.label, "fruit": fruit, "criterion": used, "outcome": table.outcome.name,
        "basis": "impact", "basis_note": basis_note, "energy_share_by_surface": shares,
        "tests": int(energy.size), "bruised": bruised, "unbruised": int(energy.size) - bruised,
        "rows_skipped": [{"row": where, "message": message} for where, message in skipped],
        "energy_min": float(energy.min()), "energy_max": float(energy.max()),
    }
    for key in ("bruise_susceptibility", "bruise_energy"):
        low, high = intervals.get(key, (None, None))
        report.update({key: estimates.get(key), f"{key}_low": low, f"{key}_high": high})
    report.update(failure_stress=None, failure_stress_low=None, failure_stress_high=None,
                  failure_stress_surface=None, failure_stress_by_surface={}, failure_stress_rule=None,
                  failure_stress_reason=None,
                  threshold_spread=estimates.get("threshold_spread"), volume_scatter=estimates.get("volume_scatter"),
                  failure_stress_note=STRESS_NOTE, fruit_ranges={},
                  model=MODEL_TEXT[fit.model], model_name=fit.model, interval=INTERVAL, volume_conversion=conversion,
                  log_likelihood=fit.log_likelihood if math.isfinite(fit.log_likelihood) else None)
    for key, spread in (("bruise_susceptibility", "volume_scatter"), ("bruise_energy", "threshold_spread")):
        if report[key] is not None and report[spread] is not None:
            report["fruit_ranges"][key] = [report[key] * math.exp(-RANGE_SIGMAS * report[spread]),
                                           report[key] * math.exp(RANGE_SIGMAS * report[spread])]
    warnings += fit.notes
    if "bruise_susceptibility" not in estimates:  # the model has none: 0/1 outcomes
        warnings.append("bruise susceptibility: null: 0/1 outcomes carry no bruise volume, so none is fitted")
    if used is None:
        report["failure_stress_reason"] = ("criterion none" if criterion == "none" else
                                           f"the {template.name} entry names no bruise criterion")
    warnings += _failure_stress(report, fits, energy, outcome, surfaces, fruit, used)
    warnings += _mismatch(template, table, keep)
    status = "ok" if fit.status == "ok" and (report["bruise_energy"] is not None
                                            or report["bruise_susceptibility"] is not None) else "failed"
    report["name"] = fitted_name
    report["output"] = None
    if status == "ok" and output is not None:
        entry = _fitted_fruit(report, template, fitted_name)
        text = fruit_file_text(entry, f"fruit {fitted_name}: fitted by fruitimpact fit-damage to {table.label} "
                                      f"({report['tests']} tests; ranges: the fruit-to-fruit spreads, the 95 % "
                                      f"intervals in the notes); the fruit library's format (docs/library.md): give "
                                      f"this file as --fruit to any command")

        def write(tmp):
            with open(tmp, "w", encoding="utf-8", newline="") as handle:
                handle.write(text)

        atomic_write(output, write, "output")
        read_fruit_file(output)  # the file must load as the library's: it is read back with the same checks
        report["output"] = os.fspath(output)
    elif output is not None:
        warnings.append(f"nothing fitted: {output} is not written")
    report["status"] = status
    report["message"] = _summary(report) if status == "ok" else _failure(fit)
    report["warnings"] = warnings
    return report


def _failure(fit) -> str:
    """Why a fit gave nothing (a failed fit says it; one that ran but bounds nothing, by its notes)."""
    if fit.status != "ok":
        return fit.message
    why = "; ".join(fit.notes) or "the tests determine neither the threshold energy nor the susceptibility"
    extra = "; 0/1 outcomes carry no bruise volume, so there is no susceptibility either" \
        if "bruise_susceptibility" not in fit.estimates else ""
    return f"nothing fitted: {why}{extra}"


def _by_use(surfaces) -> list:
    """The surfaces of the tests, the most used first (ties: in table order)."""
    names = list(dict.fromkeys(surfaces))
    names.sort(key=lambda s: -surfaces.count(s))
    return names


def _bracket(fit, energy, outcome) -> str:
    """Why a surface's tests do not bound the stress at onset ("" where they do)."""
    threshold = fit.estimates.get("bruise_energy")
    low, high = fit.intervals.get("bruise_energy", (None, None))
    if fit.status != "ok":
        return f"the threshold energy is not fitted ({fit.message})"
    if threshold is None:
        return "the threshold energy is not fitted" + (f" ({fit.notes[0]})" if fit.notes else "")
    bruised = outcome > 0.0
    reasons = [text for text, missing in (
        ("no test was unbruised", bruised.all()), ("no test bruised", not bruised.any()),
        (f"no test below the threshold {threshold:.4g} J", energy.min() >= threshold),
        (f"no test above the threshold {threshold:.4g} J", energy.max() <= threshold),
        ("its interval is open below", low is None), ("its interval is open above", high is None)) if missing]
    if reasons:
        return (f"the tests do not bracket the threshold energy ({'; '.join(reasons)}), so they do not bound the "
                f"stress at onset")
    return ""


def _agree(intervals) -> bool:
    """Whether 95 % intervals (low, high) share a point."""
    return max(low for low, _ in intervals) <= min(high for _, high in intervals)


def _failure_stress(report, fits, energy, outcome, surfaces, fruit, criterion) -> list:
    """The onset stress on each surface whose tests bracket their own threshold (``failure_stress_by_surface``), and
    the one failure stress they give: one surface's, their precision-weighted geometric mean where they agree within
    their 95 % intervals, none where they disagree.  Returns the warnings."""
    names = _by_use(surfaces)
    by_surface, warnings = {}, []
    for s in names:
        mask = np.array([x == s for x in surfaces])
        fit = fits[s]
        low, high = fit.intervals.get("bruise_energy", (None, None))
        by_surface[s] = {"tests": int(mask.sum()), "bruised": int((outcome[mask] > 0.0).sum()),
                         "bruise_energy": fit.estimates.get("bruise_energy"), "bruise_energy_low": low,
                         "bruise_energy_high": high, "threshold_spread": fit.estimates.get("threshold_spread"),
                         "failure_stress": None, "failure_stress_low": None, "failure_stress_high": None,
                         "failure_stress_range": None, "note": _bracket(fit, energy[mask], outcome[mask])}
    report["failure_stress_by_surface"] = by_surface
    bounded = [s for s in names if by_surface[s]["bruise_energy"] is not None
               and None not in (by_surface[s]["bruise_energy_low"], by_surface[s]["bruise_energy_high"])]
    if len(bounded) > 1 and not _agree([(by_surface[s]["bruise_energy_low"], by_surface[s]["bruise_energy_high"])
                                        for s in bounded]):
        listing = ", ".join(f"{s} {by_surface[s]['bruise_energy']:.4g} J [{by_surface[s]['bruise_energy_low']:.4g}, "
                            f"{by_surface[s]['bruise_energy_high']:.4g}]" for s in bounded)
        warnings.append(f"the surfaces disagree on the threshold energy beyond their 95 % intervals ({listing}): one "
                        f"threshold of the compared energy does not describe these tests, and the one fitted to all "
                        f"of them lies between theirs")
    if criterion is None:
        return warnings
    todo = [s for s in names if not by_surface[s]["note"]]
    if todo:
        rows, levels = [], []
        for s in todo:
            entry = by_surface[s]
            spread = entry["threshold_spread"] or 0.0
            w = entry["bruise_energy"]
            levels += [w, entry["bruise_energy_low"], entry["bruise_energy_high"],
                       w * math.exp(-RANGE_SIGMAS * spread), w * math.exp(RANGE_SIGMAS * spread)]
            rows += [s] * 5
        stresses, rule = _onset_stresses(fruit, criterion, rows, levels)
        report["failure_stress_rule"] = rule
        for k, s in enumerate(todo):
            value, low, high, down, up = (float(x) if math.isfinite(x) else None for x in stresses[5 * k:5 * k + 5])
            if None in (value, low, high):
                by_surface[s]["note"] = f"the impact at the threshold on {s} could not be computed"
                continue
            by_surface[s].update(failure_stress=value, failure_stress_low=low, failure_stress_high=high,
                                 failure_stress_range=None if None in (down, up) else [down, up])
    given = [s for s in names if by_surface[s]["failure_stress"] is not None]
    if not given:
        reason = by_surface[names[0]]["note"] if len(names) == 1 else \
            "on no surface do the tests bound it (" + "; ".join(f"{s}: {by_surface[s]['note']}" for s in names) + ")"
        report["failure_stress_reason"] = reason
        warnings.append(f"failure stress: null: {reason}")
        return warnings
    listing = ", ".join(f"{s} {by_surface[s]['failure_stress'] / 1e6:.4g} MPa "
                        f"[{by_surface[s]['failure_stress_low'] / 1e6:.4g}, "
                        f"{by_surface[s]['failure_stress_high'] / 1e6:.4g}]" for s in given)
    if len(given) > 1 and not _agree([(by_surface[s]["failure_stress_low"], by_surface[s]["failure_stress_high"])
                                      for s in given]):
        reason = (f"the surfaces disagree on the {criterion} criterion's stress at onset beyond their 95 % intervals "
                  f"({listing})")
        report["failure_stress_reason"] = reason
        warnings.append(f"failure stress: null: {reason}: one failure stress does not describe these tests, so none "
                        f"is given or written (each surface's: failure_stress_by_surface; the fitted fruit takes the "
                        f"energy criterion); fit each surface's tests on their own for its stress")
        return warnings
    if len(given) == 1:
        entry = by_surface[given[0]]
        value, low, high, spread = (entry["failure_stress"], entry["failure_stress_low"], entry["failure_stress_high"],
                                    entry["failure_stress_range"])
    else:  # agreeing surfaces: inverse-variance weights of ln σ_f, each variance from its 95 % interval
        entries = [by_surface[s] for s in given]
        logs = np.log([e["failure_stress"] for e in entries])
        errors = np.array([math.log(e["failure_stress_high"] / e["failure_stress_low"]) / (2.0 * _Z95)
                           for e in entries])
        weights = 1.0 / np.maximum(errors, 1e-12) ** 2
        centre = float(np.sum(weights * logs) / np.sum(weights))
        error = 1.0 / math.sqrt(float(np.sum(weights)))
        value, low, high = (math.exp(centre + k * _Z95 * error) for k in (0.0, -1.0, 1.0))
        # the fruit-to-fruit range: each surface's, relative to its stress, averaged in ln
        ranged = [e for e in entries if e["failure_stress_range"]]
        spread = None if not ranged else [
            value * math.exp(float(np.mean([math.log(e["failure_stress_range"][end] / e["failure_stress"])
                                            for e in ranged]))) for end in (0, 1)]
        warnings.append(f"the tests on {len(given)} surfaces agree on the failure stress within their 95 % intervals "
                        f"({listing}): the value given and written is their precision-weighted geometric mean")
    if len(given) < len(names):
        warnings.append(f"the failure stress is from the tests on {', '.join(given)} only ("
                        + "; ".join(f"{s}: {by_surface[s]['note']}" for s in names if s not in given) + ")")
    report.update(failure_stress=value, failure_stress_low=low, failure_stress_high=high,
                  failure_stress_surface=", ".join(given))
    if spread is not None:
        report["fruit_ranges"]["failure_stress"] = spread
    return warnings


def _mismatch(template, table: Tests, keep) -> list:
    """Warnings where the tested fruit differ from the fruit whose flesh and size give the failure stress."""
    notes = []
    mass = float(np.median(table.mass[keep]))
    if abs(mass / template.mass.value - 1.0) > MASS_MISMATCH:
        notes.append(f"the tested fruit (median mass {mass * 1e3:.4g} g) are not the {template.name} entry's "
                     f"{template.mass.value * 1e3:.4g} g, whose mass and size give the failure stress: give --fruit "
                     f"a fruit like the tested ones")
    return notes


def _summary(report: dict) -> str:
    parts = []
    if report["bruise_energy"] is not None:
        parts.append(f"threshold energy {report['bruise_energy']:.4g} J")
    elif report["bruise_energy_high"] is not None:
        parts.append(f"threshold energy below {report['bruise_energy_high']:.4g} J (not bounded below)")
    if report["bruise_susceptibility"] is not None:
        parts.append(f"bruise susceptibility {report['bruise_susceptibility'] * 1e6:.4g} cm³/J (median)")
    if report["failure_stress"] is not None:
        parts.append(f"failure stress {report['failure_stress'] / 1e6:.4g} MPa ({report['criterion']} on "
                     f"{report['failure_stress_surface']})")
    return (f"fitted to {report['tests']} tests ({report['bruised']} bruised), on the energy the simulator compares "
            f"(the fruit's share of the impact energy): " + ", ".join(parts))


__all__ = ["CONVERSIONS", "DEPTH_TO_DEFORMATION", "ENERGY_COLUMNS", "INTERVAL", "MAX_DEPTH_TO_WIDTH", "MAX_TESTS",
           "MODEL_TEXT", "OUTCOMES", "Outcome", "RANGE_SIGMAS", "SPEED_LIMITS", "TEST_COLUMNS", "Tests", "fit_damage",
           "read_tests"]
