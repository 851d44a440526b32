"""Drop and pendulum tests → the fruit's bruise threshold energy, bruise susceptibility and failure stress.

A table of tests (one row per fruit hit once): ``drop_height`` [m] (a drop onto ``surface``) or ``energy`` [J] (a
pendulum's impact energy), ``surface`` (a library surface, or ``rigid``), ``mass`` [kg], optionally ``diameter``
[m], and one outcome: ``bruise_volume`` [m³], ``bruise_diameter`` [m] or ``bruised`` (0/1).  Cells may carry units
("10cm", "120g", "350mm3"; ``impact.units``).  :func:`fit_damage` fits, by maximum likelihood
(:mod:`fruitimpact.damage.fitting`):

* on the energy basis the tests measured: the **impact energy**, m g h of a drop or the pendulum's energy, never
  the absorbed share (the library records the basis, ``bruise_*_basis = impact``, and applies the values on it);
* the **threshold energy** W_th (the median of the fruit's thresholds: half the fruit bruise at W_th) and the
  **bruise susceptibility** BS (volume per joule above the threshold), with 95 % profile-likelihood intervals;
  unbruised fruit are censored thresholds, not zeros of a line; from 0/1 outcomes the threshold only (BS is
  null: a 0/1 outcome has no volume);
* the **failure stress** σ_f where the tests bracket the threshold (bruised and unbruised fruit, tests on both
  sides of W_th): the stress of the fruit's bruise criterion at W_th on the tests' surface, computed with the
  project's own impact (``impact.evaluation``) for the ``fruit`` given (its modulus, Poisson's ratio, size, mass,
  restitution): ``pressure`` σ_f = p0, ``shear`` σ_f = 2 τ_max (``damage.bruise.CRITERIA``'s ratio at σ_f = 1 Pa),
  and for ``energy`` (no stress of its own) the Hertz peak pressure p0.  Its interval is that of W_th carried
  through the same impact (the stress rises with the energy).

A measured **bruise diameter** is turned into a volume with the library's bruise shape, the spherical cap
(``damage.bruise.cap_volume``) of width D, and the depth that the library's source for the bruise geometry relates to
the impact: 2.5 × the peak deformation δ_max (Stropek & Gołacki 2020, pear, at the three highest speeds; the same
study gives the contact-to-bruise width ratio 1.4), δ_max being the project's impact of that test (its mass,
diameter, energy and surface, the ``fruit``'s flesh).  Pear data applied to any fruit: the output says so.

The fitted fruit (``output``) is the ``fruit`` with these values, written in the fruit library's own format
(``library.catalogue.fruit_file_text``); every command's ``fruit`` input accepts that file.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, replace

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Bruise depth over the peak deformation of the impact that made it (Stropek & Gołacki 2020, Postharvest Biol.
#: Technol. 163:111120, pear, three highest impact speeds): the depth of a bruise whose diameter alone was measured.
DEPTH_TO_DEFORMATION = 2.5
#: The interval every fit reports.
INTERVAL = "95 % profile likelihood"
#: Test masses whose median differs from the fruit's by more than this share are said to (the failure stress uses
#: the fruit's own mass and size).
MASS_MISMATCH = 0.25
_TRUE, _FALSE = {"1", "true", "yes", "y"}, {"0", "false", "no", "n"}
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
              "with lognormal scatter (volume_scatter); unbruised fruit censored (T_i >= W)",
    "incidence": "per-fruit threshold lognormal around W_th: probit in ln W, P(bruised) = Phi((ln W - ln W_th) / "
                 "threshold_spread); W_th is the 50 % point",
}


@dataclass
class Tests:
    """The usable tests of a table: ``label`` (the file, or "tests"), per row its place ``where``, energy [J] on
    the impact basis, ``drop`` (True: a drop), mass [kg], diameter [m] (NaN: the fruit's), surface, outcome value
    (SI, or 0/1), and the rows refused (``skipped``: (where, message)) and kept with a warning (``warnings``)."""

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


def _table(tests):
    """(label, header, rows): rows as (where, cells or None for a ragged line, its message)."""
    if isinstance(tests, (str, os.PathLike)):
        import csv

        label = os.fspath(tests)
        try:
            with open(tests, newline="", encoding="utf-8-sig") as handle:  # an Excel export starts with a BOM
                numbered = [(n, line) for n, line in enumerate(handle, start=1)
                            if line.strip() and not line.lstrip().startswith("#")]
        except OSError as exc:
            raise _refuse(f"cannot read {label}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise _refuse(f"cannot read {label}: not a UTF-8 text file") from None
        if not numbered:
            raise _refuse(f"{label} is empty: expected a header ({', '.join(TEST_COLUMNS)})")
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
    header = list(columns)
    cells = [list(value) if not isinstance(value, (str, bytes)) and hasattr(value, "__len__") else [value] * count
             for value in columns.values()]
    return "tests", header, [(f"tests row {i + 1}", [column[i] for column in cells], "") for i in range(count)]


def _blank(cell) -> bool:
    if cell is None or type(cell).__name__ == "NAType":
        return True
    return isinstance(cell, str) and not cell.strip()


def _number(column: str, cell, dimension: str) -> float:
    """A cell of a numeric column in SI (units parsed); ValueError naming the column otherwise."""
    from fruitimpact.impact.units import SI_UNIT, UNITS, parse_quantity

    if isinstance(cell, bool):
        raise ValueError(f"{column} must be a number; got {cell!r}")
    try:
        value = parse_quantity(cell if isinstance(cell, str) else float(cell), dimension)
    except (TypeError, ValueError):
        units = ", ".join(u for u in UNITS[dimension] if u)
        raise ValueError(f"{column} must be a number (units allowed: {units}; a plain number is "
                         f"{SI_UNIT[dimension]}); got {cell!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{column} must be a finite number; got {cell!r}")
    return value


def _flag(cell) -> float:
    text = str(cell).strip().lower()
    if isinstance(cell, bool):
        return float(cell)
    if isinstance(cell, (int, float)) and not isinstance(cell, bool) and cell in (0, 1):
        return float(cell)
    if text in _TRUE or text in _FALSE:
        return 1.0 if text in _TRUE else 0.0
    raise ValueError(f"bruised must be 1 or 0 (true/false, yes/no); got {cell!r}")


def read_tests(tests) -> Tests:
    """The usable tests of ``tests`` (a CSV path, a mapping of columns or a DataFrame).

    The table is refused as a whole (``InputError`` naming ``tests``, before any work) for unknown or repeated
    columns, no outcome column or more than one, neither ``drop_height`` nor ``energy``, no ``mass`` or
    ``surface`` column, an unknown surface, or no usable row; a row with a bad value (not a number, ≤ 0, NaN, a
    ragged line, both or neither of ``drop_height`` and ``energy``) is skipped and reported."""
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
    parsed, skipped, warnings = [], [], []
    for where, cells, ragged in rows:
        if cells is None:
            skipped.append((where, ragged))
            continue
        row = {key: cell for key, cell in zip(keys, cells) if not _blank(cell)}
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
                if not INPUTS["drop_height"].plausible.contains(height):
                    warnings.append(f"{where}: {implausible_message(INPUTS['drop_height'], height)}")
            else:
                energy, drop = _number("energy", row[key], "energy"), False
                if energy <= 0.0:
                    raise ValueError(f"energy must be a finite number > 0 J; got {row[key]!r}")
            diameter = check_value("diameter", row["diameter"]) if "diameter" in row else math.nan
            for name, value in (("mass", mass), ("diameter", diameter)):
                if math.isfinite(value) and not INPUTS[name].plausible.contains(value):
                    warnings.append(f"{where}: {implausible_message(INPUTS[name], value)}")
            if outcome.name not in row:
                raise ValueError(f"{outcome.name} must be given ({outcome.doc})")
            if outcome.dimension is None:
                value = _flag(row[outcome.name])
            else:
                value = _number(outcome.name, row[outcome.name], outcome.dimension)
                if value < 0.0:
                    raise ValueError(f"{outcome.name} must be >= 0 (0: not bruised); got {row[outcome.name]!r}")
                if outcome.name == "bruise_diameter" and math.isfinite(diameter) and value > diameter:
                    raise ValueError(f"bruise_diameter must not exceed the fruit's diameter {diameter:g} m; got "
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
                 np.array(columns[3]), np.array(columns[4]), list(columns[5]), np.array(columns[6]), skipped, warnings)


# ------------------------------------------------------------------------------------------------- physics

def _impacts(fruit: str, surfaces, energies, masses, diameters=None):
    """The project's impacts of ``fruit`` (library name or fruit file) at impact energies [J] with masses [kg] on
    ``surfaces``: ``impact.evaluation.evaluation`` of one row each, no bruise criterion (the stresses only)."""
    from fruitimpact.impact.evaluation import evaluation

    energies, masses = np.asarray(energies, dtype=float), np.asarray(masses, dtype=float)
    table = {"fruit": [fruit] * energies.size, "surface": list(surfaces), "criterion": ["none"] * energies.size,
             "mass": masses, "velocity": np.sqrt(2.0 * energies / masses)}
    if diameters is not None:
        table["diameter"] = [None if math.isnan(d) else float(d) for d in diameters]
    return evaluation(table)


def _diameter_volumes(tests: Tests, fruit: str):
    """Bruise volumes [m³] of measured bruise diameters: the cap of width D and depth 2.5 δ_max (module docstring),
    and the rows whose impact could not be computed (where, message)."""
    from fruitimpact.damage.bruise import cap_volume

    result = _impacts(fruit, tests.surface, tests.energy, tests.mass, tests.diameter)
    ok = result.status == 0
    depth = DEPTH_TO_DEFORMATION * np.asarray(result.columns["max_deflection"], dtype=float)
    volumes = np.where(tests.value > 0.0, cap_volume(np.where(ok, depth, 0.0), tests.value), 0.0)
    failed = [(tests.where[i], f"its impact could not be computed: {result.messages.text(i)}")
              for i in np.flatnonzero(~ok)]
    return volumes, ok, failed


#: Outcomes fitted as another: name → (the converter of a table's values, a description of it for the fruit).
CONVERSIONS = {"bruise_diameter": (_diameter_volumes, lambda fruit: (
    f"bruise volume = the spherical cap (damage.bruise.cap_volume) of the measured diameter and depth "
    f"{DEPTH_TO_DEFORMATION:g} x the peak deformation of that test's impact (the {fruit} flesh; Stropek & Golacki "
    f"2020, pear data applied to any fruit)"))}


def _onset_stresses(fruit: str, criterion: str, surfaces, energies):
    """The failure stress [Pa] whose criterion onset sits at each impact energy [J] on each surface: the stress
    criteria's own stress at σ_f = 1 Pa (their ratio is stress/σ_f), the Hertz peak pressure for a criterion
    without a stress; NaN where the impact failed."""
    from fruitimpact.damage.bruise import CRITERIA
    from fruitimpact.library.catalogue import fruits

    mass = fruits()[fruit].mass.value
    result = _impacts(fruit, surfaces, energies, np.full(len(energies), mass))
    pressure = np.asarray(result.columns["max_pressure"], dtype=float)
    poisson = np.asarray(result.columns["poisson"], dtype=float)
    rule = CRITERIA[criterion if "failure_stress" in CRITERIA[criterion].inputs else "pressure"]
    given = {"peak_pressure": pressure, "poisson": poisson, "failure_stress": 1.0}
    stress = np.asarray(rule.ratio(**{name: given[name] for name in rule.inputs}), dtype=float)
    return np.where(result.status == 0, stress, np.nan), rule.name


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


def _value(estimate, interval, unit: str, source: str, what: str, basis: str = ""):
    """A library ``Value`` of a fitted estimate: its range the 95 % interval, an end the data leave open being the
    value itself (the library's "no spread known" on that side), said in the note."""
    from fruitimpact.library.catalogue import Value

    low, high = interval
    open_ends = [side for side, end in (("below", low), ("above", high)) if end is None]
    note = (f"{what}; range: the {INTERVAL} interval" + (f"; the tests do not bound it {' or '.join(open_ends)}: "
                                                          f"that end of the range is the value" if open_ends else ""))
    return Value(estimate, estimate if low is None else min(low, estimate), estimate if high is None else
                 max(high, estimate), unit, source, True, note, basis)


def _fitted_fruit(report: dict, template, name: str):
    """The template fruit with the fitted values (none borrowed: a value not fitted is left empty)."""
    count = report["tests"]
    source = f"derived: fitted by fruitimpact fit-damage to {report['tests_file']}, {count} tests"
    basis = "impact (m g h of a drop, or the pendulum's energy)"
    fields = {"bruise_susceptibility": None, "bruise_threshold_energy": None, "failure_stress": None}
    if report["bruise_susceptibility"] is not None:
        fields["bruise_susceptibility"] = _value(
            report["bruise_susceptibility"],
            (report["bruise_susceptibility_low"], report["bruise_susceptibility_high"]), "m^3/J", source,
            f"maximum-likelihood estimate ({MODEL_TEXT[report['model_name']]}); basis: {basis}", "impact")
    if report["bruise_energy"] is not None:
        fields["bruise_threshold_energy"] = _value(
            report["bruise_energy"], (report["bruise_energy_low"], report["bruise_energy_high"]), "J", source,
            f"median of the fruit's thresholds (half the fruit bruise at it), maximum-likelihood estimate; basis: "
            f"{basis}", "impact")
    criterion, criterion_source, criterion_note = template.criterion, template.criterion_source, template.criterion_note
    if report["failure_stress"] is not None:
        fields["failure_stress"] = _value(
            report["failure_stress"], (report["failure_stress_low"], report["failure_stress_high"]), "Pa",
            f"{source} (the {report['failure_stress_rule']} criterion's stress at the threshold energy on "
            f"{report['failure_stress_surface']}, with the {template.name} entry's modulus, Poisson ratio, size and "
            f"mass)", f"stress at bruise onset under the {report['criterion']} criterion")
        criterion = report["criterion"]
        criterion_source = (f"fitted by fruitimpact fit-damage to {report['tests_file']}, {count} tests: the failure "
                            f"stress is this criterion's stress at the fitted threshold energy")
        criterion_note = "the criterion the failure stress was derived under; another criterion would need its own"
    fitted = [label for key, label in (("bruise_threshold_energy", "bruise threshold energy"),
                                       ("bruise_susceptibility", "bruise susceptibility"),
                                       ("failure_stress", "failure stress")) if fields[key] is not None]
    return replace(template, name=name, criterion=criterion, criterion_source=criterion_source,
                   criterion_note=criterion_note, **fields,
                   description=f"{template.name} fitted to {report['tests_file']} ({count} tests): "
                               f"{', '.join(fitted) or 'nothing'} fitted by fruitimpact fit-damage; the other values "
                               f"are the {template.name} entry's",
                   source=f"fitted by fruitimpact fit-damage to {report['tests_file']}, {count} tests; other values: "
                          f"the {template.name} entry of the fruit library ({template.source})")


# ----------------------------------------------------------------------------------------------------- fit

def fit_damage(tests, *, fruit: str | None = None, criterion: str | None = None, name: str | None = None,
               output=None) -> dict:
    """Fit a fruit's bruise threshold energy, bruise susceptibility and failure stress to drop or pendulum tests.

    Maximum likelihood with unbruised fruit censored (each fruit has its own threshold, lognormal around W_th) and
    lognormal scatter on the volume (:mod:`fruitimpact.damage.fitting` gives the model and why); 95 %
    profile-likelihood intervals.  The energies are the tests' own, on the impact basis: m g h of a drop, the
    pendulum's energy.  The failure stress is the fruit's criterion's stress at W_th on the tests' surface, by the
    project's impact, where the tests bracket the threshold.

    Parameters
    ----------
    tests : str, path, mapping or DataFrame
        The tests, one row per fruit: ``drop_height`` [m] or ``energy`` [J], ``surface`` (a library surface or
        ``rigid``), ``mass`` [kg], optional ``diameter`` [m], and one outcome: ``bruise_volume`` [m³],
        ``bruise_diameter`` [m] (turned into a volume: the cap of that width 2.5 δ_max deep, the module's
        docstring) or ``bruised`` (0/1).  Cells may carry units ("10cm", "120g").  A CSV may have ``#`` comments.
    fruit : str, optional
        The fruit whose modulus, Poisson's ratio, size, mass and restitution give the failure stress, and the
        template of the fitted fruit: a library name or a fruit file (default: the project's default fruit).
    criterion : str, optional
        ``pressure``, ``shear`` or ``energy`` (the stress whose onset is fitted); None or ``preset``: the fruit's
        own (without one, no failure stress is fitted); ``none``: no failure stress.
    name : str, optional
        The fitted fruit's name (lower case, no spaces); default ``<fruit>-fitted-<tests file stem>``.
    output : str or path, optional
        Write the fitted fruit there (``.csv``), in the fruit library's format, atomically.

    Returns
    -------
    dict
        ``bruise_susceptibility`` [m³/J] (None from 0/1 outcomes), ``bruise_energy`` [J], ``failure_stress`` [Pa]
        (None where the tests do not bracket the threshold), each with ``_low`` and ``_high`` (the 95 % interval;
        None where the data leave that side open); ``basis`` (``impact``) and ``basis_note``; ``tests``,
        ``bruised``, ``unbruised``, ``energy_min``, ``energy_max`` [J]; ``threshold_spread`` σ_t and
        ``volume_scatter`` σ_v [-] (lognormal σ; None where not fitted); ``failure_stress_surface``,
        ``failure_stress_by_surface`` (surface → the stress and its interval), ``failure_stress_rule`` (the
        criterion whose stress it is), ``failure_stress_note`` (what its interval holds); ``outcome``, ``model``
        and ``model_name`` (``volume`` or ``incidence``), ``interval``, ``log_likelihood``, ``volume_conversion``,
        ``rows_skipped`` (row, message), ``tests_file``, ``fruit``, ``criterion``, ``name``, ``output``; ``status``
        (``ok``, or ``failed``: nothing could be fitted), ``message`` and ``warnings``.

    Raises
    ------
    ValueError
        (``InputError``) before any work: a table that cannot be read, unknown columns, no outcome column, neither
        drop_height nor energy, an unknown surface, no usable row; a fruit or criterion that is not known; an
        output that cannot be written.  The message names the argument, the row and the column.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.fit_damage("examples/drop-tests.csv", fruit="apple", criterion="shear")  # doctest: +SKIP
    >>> report["bruise_energy"], report["bruise_energy_low"], report["bruise_energy_high"]  # doctest: +SKIP

    References
    ----------
    Bruise volume BV = BS (W − W_th)₊: L. O. Opara & P. B. Pathare, Postharvest Biol. Technol. 91 (2014) 9–24.
    Censored (Tobit) likelihood: J. Tobin, Econometrica 26 (1958) 24–36.  Profile-likelihood intervals:
    D. J. Venzon & S. H. Moolgavkar, Appl. Statist. 37 (1988) 87–94.  Bruise depth 2.5 × peak deformation:
    Z. Stropek & K. Gołacki, Postharvest Biol. Technol. 163 (2020) 111120.  Criteria: docs/bruise.md.
    """
    from fruitimpact.damage.fitting import MODELS as FIT_MODELS
    from fruitimpact.impact.outputs import CSV_FORMAT, atomic_write, check_output
    from fruitimpact.impact.quantities import INPUTS
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.impact.validation import check_choice
    from fruitimpact.library.catalogue import fruit_file_text, fruits, read_fruit_file

    fruit = check_choice("fruit", fruit if fruit is not None else INPUTS["fruit"].default, fruits())
    template = fruits()[fruit]
    warnings = []
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
    table = read_tests(tests)
    fitted_name = _name(table.label, fruit, name)
    warnings += table.warnings
    skipped = list(table.skipped)
    conversion = None
    values, keep = table.value, np.ones(table.energy.size, dtype=bool)
    if table.outcome.name in CONVERSIONS:  # an outcome fitted as another (a diameter as a volume)
        convert, describe = CONVERSIONS[table.outcome.name]
        values, keep, failed = convert(table, fruit)
        skipped += failed
        conversion = describe(fruit)
        warnings.append(f"bruise volumes derived from bruise diameters: {conversion}")
    for where, message in skipped:
        warnings.append(f"{where}: {message}; the row is skipped")
    energy, outcome = table.energy[keep], values[keep]
    surfaces = [s for s, k in zip(table.surface, keep) if k]
    fit = FIT_MODELS[table.outcome.model](energy, outcome)
    bruised = int((outcome > 0.0).sum())
    drops = int(table.drop[keep].sum())
    basis_note = ("impact energy: " + "; ".join(part for part in (
        f"m g h of each drop ({drops} tests)" if drops else "",
        f"the pendulum's energy ({energy.size - drops} tests)" if energy.size - drops else "") if part)
        + "; never the share the fruit absorbs")
    estimates, intervals = fit.estimates, fit.intervals
    report = {
        "tests_file": table.label, "fruit": fruit, "criterion": used, "outcome": table.outcome.name,
        "basis": "impact", "basis_note": basis_note,
        "tests": int(energy.size), "bruised": bruised, "unbruised": int(energy.size) - bruised,
        "rows_skipped": [{"row": where, "message": message} for where, message in skipped],
        "energy_min": float(energy.min()), "energy_max": float(energy.max()),
    }
    for key in ("bruise_susceptibility", "bruise_energy"):
        low, high = intervals.get(key, (None, None))
        report.update({key: estimates.get(key), f"{key}_low": low, f"{key}_high": high})
    report.update(failure_stress=None, failure_stress_low=None, failure_stress_high=None,
                  failure_stress_surface=None, failure_stress_by_surface={}, failure_stress_rule=None,
                  threshold_spread=estimates.get("threshold_spread"), volume_scatter=estimates.get("volume_scatter"),
                  failure_stress_note=STRESS_NOTE,
                  model=MODEL_TEXT[fit.model], model_name=fit.model, interval=INTERVAL, volume_conversion=conversion,
                  log_likelihood=fit.log_likelihood if math.isfinite(fit.log_likelihood) else None)
    warnings += fit.notes
    if "bruise_susceptibility" not in estimates:  # the model has none: 0/1 outcomes
        warnings.append("bruise susceptibility: null: 0/1 outcomes carry no bruise volume, so none is fitted")
    stress_note = _failure_stress(report, fit, energy, outcome, surfaces, fruit, used)
    if stress_note:
        warnings.append(stress_note)
    warnings += _mismatch(template, table, keep, surfaces)
    status = "ok" if fit.status == "ok" and (report["bruise_energy"] is not None
                                            or report["bruise_susceptibility"] is not None) else "failed"
    report["name"] = fitted_name
    report["output"] = None
    if status == "ok" and output is not None:
        entry = _fitted_fruit(report, template, fitted_name)
        text = fruit_file_text(entry, f"fruit {fitted_name}: fitted by fruitimpact fit-damage to {table.label} "
                                      f"({report['tests']} tests, {INTERVAL} ranges); the fruit library's format "
                                      f"(docs/library.md): give this file as --fruit to any command")

        def write(tmp):
            with open(tmp, "w", encoding="utf-8", newline="") as handle:
                handle.write(text)

        atomic_write(output, write, "output")
        read_fruit_file(output)  # the file must load as the library's: it is read back with the same checks
        report["output"] = os.fspath(output)
    elif output is not None:
        warnings.append(f"nothing fitted: {output} is not written")
    report["status"] = status
    report["message"] = fit.message if status == "failed" else _summary(report)
    report["warnings"] = warnings
    return report


def _failure_stress(report, fit, energy, outcome, surfaces, fruit, criterion) -> str:
    """Fill in the failure stress where the tests bracket the threshold; the reason when not."""
    threshold = report["bruise_energy"]
    low, high = report["bruise_energy_low"], report["bruise_energy_high"]
    bruised = outcome > 0.0
    if criterion is None:
        return ""  # said where the criterion was resolved
    if fit.status != "ok" or threshold is None:
        return "failure stress: null: the threshold energy is not fitted"
    reasons = [text for text, missing in (
        ("no test was unbruised", bruised.all()), ("no test bruised", not bruised.any()),
        (f"no test below the threshold {threshold:.4g} J", energy.min() >= threshold),
        (f"no test above the threshold {threshold:.4g} J", energy.max() <= threshold),
        ("its interval is open below", low is None), ("its interval is open above", high is None)) if missing]
    if reasons:
        return (f"failure stress: null: the tests do not bracket the threshold energy ({'; '.join(reasons)}), so they "
                f"do not bound the stress at onset")
    names = list(dict.fromkeys(surfaces))  # in table order; the most used first
    names.sort(key=lambda s: -surfaces.count(s))
    stresses, rule = _onset_stresses(fruit, criterion, [s for s in names for _ in range(3)],
                                     [w for _ in names for w in (threshold, low, high)])
    by_surface = {}
    for k, surface in enumerate(names):
        value, lo, hi = (float(x) if math.isfinite(x) else None for x in stresses[3 * k:3 * k + 3])
        by_surface[surface] = {"failure_stress": value, "failure_stress_low": lo, "failure_stress_high": hi,
                               "tests": surfaces.count(surface)}
    main = by_surface[names[0]]
    report.update(failure_stress=main["failure_stress"], failure_stress_low=main["failure_stress_low"],
                  failure_stress_high=main["failure_stress_high"], failure_stress_surface=names[0],
                  failure_stress_by_surface=by_surface, failure_stress_rule=rule)
    if main["failure_stress"] is None:
        return f"failure stress: null: the impact at the threshold on {names[0]} could not be computed"
    if len(names) > 1:
        spread = ", ".join(f"{s} {v['failure_stress'] / 1e6:.4g} MPa" for s, v in by_surface.items()
                           if v["failure_stress"] is not None)
        return (f"the tests used {len(names)} surfaces; one threshold energy is fitted to all of them, and the "
                f"failure stress is given on the most used ({names[0]}); on each: {spread}")
    return ""


def _mismatch(template, table: Tests, keep, surfaces) -> list:
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
        parts.append(f"bruise susceptibility {report['bruise_susceptibility'] * 1e6:.4g} cm³/J")
    if report["failure_stress"] is not None:
        parts.append(f"failure stress {report['failure_stress'] / 1e6:.4g} MPa ({report['criterion']} on "
                     f"{report['failure_stress_surface']})")
    return (f"fitted to {report['tests']} tests ({report['bruised']} bruised), impact-energy basis: "
            + ", ".join(parts))


__all__ = ["CONVERSIONS", "DEPTH_TO_DEFORMATION", "ENERGY_COLUMNS", "INTERVAL", "MODEL_TEXT", "OUTCOMES", "Outcome", "TEST_COLUMNS",
           "Tests", "fit_damage", "read_tests"]
