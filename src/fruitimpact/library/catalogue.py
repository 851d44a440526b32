"""The fruit and surface libraries: sourced property values with ranges (issue 7, item 3).

Data live in ``data/fruits.csv`` and ``data/surfaces.csv`` (SI units, one row per entry); this
module reads them once with the standard library only (no pandas, no numpy), checks them and
serves them as frozen records.  docs/library.md has the tables and what the flags mean.

>>> fruit("jonathan-apple").inputs()["modulus"]
3000000.0
>>> surface("foam-pad").model
'layer'

Every number is a :class:`Value`: a central value, a range [low, high], its unit, the source it
was read in, and ``confirmed``: ``True`` where the value was read in that source (an article, its
abstract, an engineering table), or derived from read values by the arithmetic the source text
states after ``derived:``; ``False`` where it was not checked in a source, with a ``note`` saying
what it rests on.  ``low == high`` where one value was read and no spread was given.

Sources (full references in the CSVs' ``*_source`` columns): the founding paper, "Theoretical
aspects about simulating the reaction to impact of apples on rigid plane surfaces" (the Jonathan
apple); Gorji Chakespari et al., Modern Applied Science, and Food & Machinery 31(5) (apple flesh
failure stress and moduli); Int. J. Food Properties doi 10.1080/10942912.2013.831444 (apple
density); Int. J. Biosystems Eng. article 35202 (apple bruise susceptibility); Stropek & Gołacki
2020 (pear bruise susceptibility); Fu et al., "'Jazz' apple impact bruise responses to different
cushioning materials" (foam pads); engineering tables after Halliday et al., Gere and Ashby, and
the Mechanical Engineering Handbook (steel, concrete, PVC, rubber).
"""

from __future__ import annotations

import csv
import functools
import io
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields
from importlib import resources
from types import MappingProxyType

from fruitimpact.library.textfiles import table_lines

__all__ = ["ENERGY_BASED", "FILE_CHECKS", "ENERGY_BASES", "FITTED_BY", "FRUIT_COLUMNS", "FRUIT_UNITS", "SURFACE_MODELS",
           "SURFACE_UNITS", "Fruit", "FruitRegistry", "LibraryError", "Surface", "Value", "fitted_criterion",
           "fitted_criterion_message", "fruit",
           "fruit_file_text", "fruit_rows", "fruits", "is_fruit_file", "load_fruit_file",
           "read_fruit_file", "surface", "surface_rows", "surfaces"]

#: The numeric fields of a fruit and their SI units.
FRUIT_UNITS = {
    "mass": "kg", "diameter": "m", "density": "kg/m^3", "modulus": "Pa", "poisson": "", "failure_stress": "Pa",
    "restitution": "", "alpha": "s/m", "bruise_susceptibility": "m^3/J", "bruise_threshold_energy": "J",
    "bruise_width_ratio": "",
}
#: The numeric fields of a surface and their SI units.
SURFACE_UNITS = {"modulus": "Pa", "poisson": "", "thickness": "m", "radius": "m", "crush_stress": "Pa"}
#: Surface values that only some surfaces have (the others leave them empty).
_SURFACE_OPTIONAL = ("crush_stress",)
#: Contact models of a surface: Hertz half-space through E* and R; elastic-foundation (Winkler) layer of
#: thickness h on a rigid substrate; an identical free fruit.
SURFACE_MODELS = ("half-space", "layer", "fruit")

_FRUIT_REQUIRED = ("mass", "diameter", "modulus", "poisson")
#: Bruise values defined per joule or in joules, and the energies a source can have measured them on.
ENERGY_BASED = ("bruise_susceptibility", "bruise_threshold_energy")
ENERGY_BASES = ("impact", "absorbed")
#: The columns of a fruit row, in the order of ``data/fruits.csv``: the row's texts, then per property X of
#: ``FRUIT_UNITS`` X, X_low, X_high, X_confirmed, X_source, X_note (and X_basis for ``ENERGY_BASED``).  A fruit
#: file (``read_fruit_file``) has exactly these.
FRUIT_COLUMNS = ("name", "description", "modulus_kind", "source", "criterion", "criterion_source", "criterion_note",
                 *(column for field in FRUIT_UNITS
                   for column in (field, f"{field}_low", f"{field}_high", f"{field}_confirmed", f"{field}_source",
                                  f"{field}_note", *((f"{field}_basis",) if field in ENERGY_BASED else ()))))
_POSITIVE = {"mass", "diameter", "density", "modulus", "failure_stress", "alpha", "bruise_susceptibility",
             "bruise_threshold_energy", "bruise_width_ratio", "thickness", "radius"}


class LibraryError(ValueError):
    """A library CSV breaks a rule (missing source, value outside its range, duplicate name...)."""


@dataclass(frozen=True)
class Value:
    """One sourced number.

    Attributes
    ----------
    value : float
        The central value [``unit``], SI.
    low, high : float
        Its range [``unit``]; ``low <= value <= high``.
    unit : str
        SI unit (``""`` for dimensionless).
    source : str
        Where it was read (or ``derived: ...`` and from what).
    confirmed : bool
        ``True``: read in ``source`` or derived from read values; ``False``: not checked in a source.
    note : str
        What the value is and what it rests on; never empty when not confirmed.
    basis : str
        For an energy-based bruise value (``ENERGY_BASED``): the energy its source measured it on,
        ``"impact"`` (½ m V², e.g. a pendulum's) or ``"absorbed"`` (½ m V² (1 − e²)); else ``""``.
    """

    value: float
    low: float
    high: float
    unit: str
    source: str
    confirmed: bool
    note: str = ""
    basis: str = ""

    @property
    def derived(self) -> bool:
        """Whether the value was computed from other values (its source starts with ``derived``)."""
        return self.source.lower().startswith("derived")

    def to_dict(self) -> dict:
        """The value as a plain dict (JSON-ready; ``inf`` stays a float)."""
        return {item.name: getattr(self, item.name) for item in fields(self)}


@dataclass(frozen=True)
class Fruit:
    """A fruit of the library: each property a :class:`Value` in SI, or ``None`` where unknown.

    Attributes
    ----------
    name, description : str
    modulus_kind : str
        Which modulus ``modulus`` is (impact/apparent Hertz modulus or quasi-static compression modulus).
    source : str
        The row's main sources.
    mass : Value
        M [kg].
    diameter : Value
        d [m]; the local contact radius is d/2 (non-spherical fruit: an equal-volume or equatorial
        diameter, see the note).
    density : Value or None
        ρ [kg/m³].
    modulus : Value
        Young's modulus E [Pa] (see ``modulus_kind``).
    poisson : Value
        ν [-].
    failure_stress : Value or None
        Flesh failure (bioyield) stress σ_f [Pa].
    restitution : Value or None
        Coefficient of restitution on a rigid plate [-].
    alpha : Value or None
        Hunt–Crossley α [s/m] (k = 1 − α V_i, the paper's eq 6).
    bruise_susceptibility : Value or None
        Bruise volume per unit energy [m³/J] (1 cm³/J = 1e-6 m³/J).
    bruise_threshold_energy : Value or None
        Energy below which no bruise formed [J].
    bruise_width_ratio : Value or None
        Contact width over the width of the bruise it leaves [-] (pear: 1.4).
    criterion, criterion_source, criterion_note : str
        The bruise criterion the literature read supports for this fruit (``pressure``, ``shear`` or
        ``energy``; None where none was found), where that was read and what it rests on
        (``--criterion preset`` takes it).
    """

    name: str
    description: str
    modulus_kind: str
    source: str
    mass: Value
    diameter: Value
    density: Value | None
    modulus: Value
    poisson: Value
    failure_stress: Value | None
    restitution: Value | None
    alpha: Value | None
    bruise_susceptibility: Value | None
    bruise_threshold_energy: Value | None
    bruise_width_ratio: Value | None = None
    criterion: str | None = None
    criterion_source: str = ""
    criterion_note: str = ""

    def values(self) -> dict[str, Value]:
        """The known numeric properties, by field name."""
        return {name: getattr(self, name) for name in FRUIT_UNITS if getattr(self, name) is not None}

    def inputs(self) -> dict[str, float]:
        """Simulator inputs in SI: ``mass`` [kg], ``diameter`` [m], ``modulus`` [Pa], ``poisson`` [-], and
        where known ``failure_stress`` [Pa], ``bruise_susceptibility`` [m³/J], ``bruise_threshold_energy``
        [J], ``restitution`` [-] (central values, confirmed or not)."""
        names = ("mass", "diameter", "modulus", "poisson", "failure_stress", "bruise_susceptibility",
                 "bruise_threshold_energy", "restitution", "bruise_width_ratio")
        return {name: getattr(self, name).value for name in names if getattr(self, name) is not None}

    def bases(self) -> dict[str, str]:
        """The energy basis (``"impact"`` or ``"absorbed"``) of each known energy-based bruise value."""
        return {name: getattr(self, name).basis for name in ENERGY_BASED if getattr(self, name) is not None}


@dataclass(frozen=True)
class Surface:
    """A surface of the library.

    Attributes
    ----------
    name, description : str
    model : str
        ``half-space`` (Hertz through E* and R), ``layer`` (elastic-foundation/Winkler layer of
        thickness h on a rigid substrate, k = (1−ν)E/((1+ν)(1−2ν)h)) or ``fruit`` (an identical free fruit).
    source : str
        The row's main sources.
    modulus : Value or None
        Young's modulus E₂ [Pa]; ``None`` for ``fruit`` (taken from the fruit).
    poisson : Value or None
        ν₂ [-]; ``None`` for ``fruit``.
    thickness : Value or None
        h [m]; ``inf`` for a half-space; ``None`` for ``fruit``.
    radius : Value or None
        Radius of curvature R₂ [m]; ``inf`` is flat; ``None`` for ``fruit`` (the fruit's d/2).
    partner : str or None
        ``"fruit"`` for the identical free fruit, else ``None``.
    crush_stress : Value or None
        Flat-crush strength σ_c [Pa] of a layer that collapses (corrugated board): the layer bottoms out where
        the pressure under the fruit reaches it; ``None``: the layer does not crush.
    """

    name: str
    description: str
    model: str
    source: str
    modulus: Value | None
    poisson: Value | None
    thickness: Value | None
    radius: Value | None
    partner: str | None
    crush_stress: Value | None = None

    def values(self) -> dict[str, Value]:
        """The known numeric properties, by field name."""
        return {name: getattr(self, name) for name in SURFACE_UNITS if getattr(self, name) is not None}

    def inputs(self, fruit: Fruit | None = None) -> dict:
        """Simulator inputs in SI: ``surface_modulus`` [Pa], ``surface_poisson`` [-], ``surface_radius`` [m],
        ``surface_thickness`` [m] (``inf`` for a half-space), ``surface_model`` (text).

        For the ``fruit`` surface the numbers are the fruit's (modulus, Poisson ratio, radius d/2, an
        infinite thickness) when ``fruit`` is given, else ``None``; the reduced mass m/2 is the
        caller's to apply.
        """
        if self.partner != "fruit":
            modulus, poisson = self.modulus.value, self.poisson.value
            radius, thickness = self.radius.value, self.thickness.value
        elif fruit is None:
            modulus = poisson = radius = thickness = None
        else:
            modulus, poisson = fruit.modulus.value, fruit.poisson.value
            radius, thickness = fruit.diameter.value / 2.0, math.inf
        crush = self.crush_stress.value if self.crush_stress is not None else None
        return {"surface_modulus": modulus, "surface_poisson": poisson, "surface_radius": radius,
                "surface_thickness": thickness, "surface_crush_stress": crush, "surface_model": self.model}


# ----------------------------------------------------------------------------------------------- loading

def _read(filename: str) -> list[dict[str, str]]:
    text = resources.files("fruitimpact.library").joinpath("data", filename).read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
    return list(csv.DictReader(lines))


def _number(text: str, where: str) -> float:
    try:
        number = float(text)
    except ValueError:
        raise LibraryError(f"{where}: {text!r} is not a number") from None
    if math.isnan(number):
        raise LibraryError(f"{where}: NaN is not a value")
    return number


def _value(row: dict[str, str], name: str, unit: str, where: str) -> Value | None:
    keys = [name, f"{name}_low", f"{name}_high", f"{name}_confirmed", f"{name}_source", f"{name}_note"]
    missing = [key for key in keys if key not in row]
    if missing:
        raise LibraryError(f"{where}: missing columns {', '.join(missing)}")
    text = row[name].strip()
    if not text:
        filled = [key for key in keys[1:] if row[key].strip()]
        if filled:
            raise LibraryError(f"{where}: {name} is empty but {', '.join(filled)} is not")
        return None
    where = f"{where}, {name}"
    value = _number(text, where)
    low = _number(row[f"{name}_low"].strip(), f"{where}_low")
    high = _number(row[f"{name}_high"].strip(), f"{where}_high")
    if not low <= value <= high:
        raise LibraryError(f"{where}: value {value:g} is outside its range [{low:g}, {high:g}]")
    confirmed = row[f"{name}_confirmed"].strip().lower()
    if confirmed not in ("true", "false"):
        raise LibraryError(f"{where}_confirmed must be true or false; got {confirmed!r}")
    source = row[f"{name}_source"].strip()
    note = row[f"{name}_note"].strip()
    if not source:
        raise LibraryError(f"{where} has no source")
    if confirmed == "false" and not note:
        raise LibraryError(f"{where} is not confirmed and has no note saying why")
    if name in _POSITIVE and not low > 0.0:
        raise LibraryError(f"{where} must be positive; its range starts at {low:g}")
    if name == "poisson" and not (-1.0 < low and high < 0.5):
        raise LibraryError(f"{where} must lie in (-1, 0.5); its range is [{low:g}, {high:g}]")
    if name in ("restitution", "poisson") and math.isinf(high):
        raise LibraryError(f"{where} must be finite")
    basis = ""
    if name in ENERGY_BASED:
        basis = (row.get(f"{name}_basis") or "").strip()
        if basis not in ENERGY_BASES:
            raise LibraryError(f"{where}_basis must be one of {', '.join(ENERGY_BASES)} (the energy the source "
                               f"measured it on); got {basis!r}")
    return Value(value, low, high, unit, source, confirmed == "true", note, basis)


def _common(row: dict[str, str], kind: str, number: int, names: set[str], table: str | None = None) -> tuple[str, str]:
    name = (row.get("name") or "").strip()
    where = f"{table or kind + 's.csv'} row {number} ({name or 'no name'})"
    if not name or name != name.lower() or " " in name:
        raise LibraryError(f"{where}: a name is lower-case without spaces; got {name!r}")
    if name in names:
        raise LibraryError(f"{where}: duplicate name {name!r}")
    if not (row.get("source") or "").strip():
        raise LibraryError(f"{where} has no source")
    names.add(name)
    return name, where


def _fruit(row: dict[str, str], number: int, names: set[str], table: str | None = None) -> Fruit:
    """The fruit of one row of the library's format, checked (``table``: the file named in messages)."""
    name, where = _common(row, "fruit", number, names, table)
    values = {field: _value(row, field, unit, where) for field, unit in FRUIT_UNITS.items()}
    absent = [field for field in _FRUIT_REQUIRED if values[field] is None]
    if absent:
        raise LibraryError(f"{where}: {', '.join(absent)} must be given")
    modulus_kind = row["modulus_kind"].strip()
    if not modulus_kind:
        raise LibraryError(f"{where}: modulus_kind must say which modulus is stored")
    criterion = (row.get("criterion") or "").strip() or None
    if criterion is not None and criterion not in ("pressure", "shear", "energy"):
        raise LibraryError(f"{where}: criterion must be pressure, shear or energy (or empty); got {criterion!r}")
    if criterion is not None and not (row.get("criterion_source") or "").strip():
        raise LibraryError(f"{where}: criterion has no source")
    return Fruit(name=name, description=row["description"].strip(), modulus_kind=modulus_kind,
                 source=row["source"].strip(), criterion=criterion,
                 criterion_source=(row.get("criterion_source") or "").strip(),
                 criterion_note=(row.get("criterion_note") or "").strip(), **values)


@functools.cache
def fruits() -> FruitRegistry:
    """The fruit library, read-only, in file order (read and checked once); fruit files resolve through it too
    (:class:`FruitRegistry`)."""
    table, names = {}, set()
    for number, row in enumerate(_read("fruits.csv"), start=1):
        entry = _fruit(row, number, names)
        table[entry.name] = entry
    return FruitRegistry(table)


@functools.cache
def surfaces() -> Mapping[str, Surface]:
    """The surface library, read-only, in file order (read and checked once)."""
    table, names = {}, set()
    for number, row in enumerate(_read("surfaces.csv"), start=1):
        name, where = _common(row, "surface", number, names)
        model = row["model"].strip()
        partner = row["partner"].strip() or None
        values = {field: _value(row, field, unit, where) for field, unit in SURFACE_UNITS.items()}
        if model not in SURFACE_MODELS:
            raise LibraryError(f"{where}: model must be one of {', '.join(SURFACE_MODELS)}; got {model!r}")
        given = [field for field, value in values.items() if value is not None]
        if values["crush_stress"] is not None and model != "layer":
            raise LibraryError(f"{where}: only a layer can crush (crush_stress)")
        if model == "fruit":
            if partner != "fruit" or given:
                raise LibraryError(f"{where}: a fruit surface has partner 'fruit' and no numbers")
        else:
            if partner is not None:
                raise LibraryError(f"{where}: only a fruit surface has a partner")
            absent = [field for field, value in values.items() if value is None and field not in _SURFACE_OPTIONAL]
            if absent:
                raise LibraryError(f"{where}: {', '.join(absent)} must be given")
            thickness = values["thickness"]
            if model == "half-space" and not math.isinf(thickness.value):
                raise LibraryError(f"{where}: a half-space has an infinite thickness")
            if model == "layer" and math.isinf(thickness.high):
                raise LibraryError(f"{where}: a layer has a finite thickness")
        table[name] = Surface(name=name, description=row["description"].strip(), model=model,
                              source=row["source"].strip(), partner=partner, **values)
    return MappingProxyType(table)


def fruit(name: str) -> Fruit:
    """The library fruit ``name``, or the fruit of a fruit file (a path to a ``.csv``, :func:`load_fruit_file`);
    ``ValueError`` naming the known fruits otherwise."""
    table = fruits()
    try:
        return table[name]
    except (KeyError, TypeError):
        raise ValueError(table.refusal(name) or f"fruit must be one of {', '.join(table)}; got {name!r}") from None


def surface(name: str) -> Surface:
    """The library surface ``name``; ``ValueError`` naming the known surfaces otherwise."""
    table = surfaces()
    try:
        return table[name]
    except (KeyError, TypeError):
        raise ValueError(f"surface must be one of {', '.join(table)}; got {name!r}") from None


# ------------------------------------------------------------------------------------------- fruit files

def is_fruit_file(value) -> bool:
    """Whether ``value`` names a fruit file rather than a library fruit: a path (text or ``os.PathLike``) ending in
    ``.csv``.  Whether the file exists is not asked."""
    return isinstance(value, (str, os.PathLike)) and os.fspath(value).lower().endswith(".csv")


def read_fruit_file(path) -> Fruit:
    """The one fruit of a fruit file: a CSV with the columns of the fruit library (``FRUIT_COLUMNS``, the header
    of ``data/fruits.csv``; ``#`` comment lines allowed) and one row, checked as the library's rows are (a source
    for every value, each value inside its range, positive where it must be, …).

    Raises
    ------
    LibraryError
        (a ``ValueError``) naming the file, and the row and column of the first problem: a file that cannot be
        read, unknown or missing columns, a ragged line, not exactly one fruit, any check of the library's.
    """
    shown = os.fspath(path)
    if os.path.isdir(path):
        raise LibraryError(f"the fruit file {shown!r} is a directory, not a fruit file (a .csv in the fruit "
                           f"library's format)")
    try:
        lines = [line for _, line in table_lines(path, name=f"the fruit file {shown!r}")]
    except ValueError as exc:
        raise LibraryError(str(exc)) from None
    rows = list(csv.reader(lines))
    if not rows:
        raise LibraryError(f"fruit file {shown!r} is empty: expected the header of the fruit library (fruits.csv)")
    header = [cell.strip() for cell in rows[0]]
    unknown = [cell for cell in header if cell not in FRUIT_COLUMNS]
    if unknown:
        raise LibraryError(f"fruit file {shown!r}: unknown column(s) {', '.join(map(repr, unknown))} (a fruit file "
                           f"has the columns of the fruit library, fruits.csv)")
    missing = [column for column in FRUIT_COLUMNS if column not in header]
    if missing:
        raise LibraryError(f"fruit file {shown!r}: missing column(s) {', '.join(missing)}")
    if len(rows) != 2:
        raise LibraryError(f"fruit file {shown!r} holds {len(rows) - 1} rows; a fruit file holds one fruit")
    if len(rows[1]) != len(header):
        raise LibraryError(f"fruit file {shown!r}: the fruit's row has {len(rows[1])} fields, the header "
                           f"{len(header)}")
    entry = _fruit(dict(zip(header, rows[1])), 1, set(), f"fruit file {shown!r}")
    _check_inputs(entry, shown)
    return entry


#: Checks every fruit file passes when it is loaded, beside the library's own rules: ``check(entry, shown)`` raises
#: ``LibraryError``.  The checks of the options the file's values stand for live with those options (in
#: ``impact.validation``, a layer above this package), which adds them here when it is imported: a fruit file is
#: only ever resolved by the code that simulates with it, which imports it.
FILE_CHECKS: list = []


def _check_inputs(entry: Fruit, shown: str) -> None:
    for check in FILE_CHECKS:
        check(entry, shown)


#: What the source of a value fitted by ``fruitimpact fit-damage`` says (``handling.droptests`` writes it).
FITTED_BY = "fitted by fruitimpact fit-damage"


def fitted_criterion(entry: Fruit) -> str | None:
    """The criterion a fruit's failure stress was fitted under by ``fit-damage`` (its ``criterion`` column), or None
    where the failure stress was not fitted (a library value, a bioyield stress, is no criterion's)."""
    stress = entry.failure_stress
    if stress is None or FITTED_BY not in stress.source:
        return None
    return entry.criterion


def fitted_criterion_message(fruit: str, fitted: str, used: str) -> str:
    """The warning for the failure stress of fruit file ``fruit``, fitted under criterion ``fitted`` and used under
    ``used`` (the stress at onset differs between criteria)."""
    return (f"failure_stress of the fruit file {fruit} was fitted under the {fitted} criterion and is used here under "
            f"{used}: the onset moves (give --criterion {fitted}, or a failure stress fitted under {used})")


def _cell(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)  # every digit: the file gives back the very numbers written
    return "" if value is None else str(value)


def fruit_file_text(entry: Fruit, comment: str = "") -> str:
    """``entry`` in the fruit library's own format: ``#`` lines of ``comment``, the header ``FRUIT_COLUMNS`` and
    one row (floats with every digit), as :func:`read_fruit_file` reads it back."""
    row = {"name": entry.name, "description": entry.description, "modulus_kind": entry.modulus_kind,
           "source": entry.source, "criterion": entry.criterion, "criterion_source": entry.criterion_source,
           "criterion_note": entry.criterion_note}
    for field in FRUIT_UNITS:
        value = getattr(entry, field)
        if value is not None:
            row.update({field: value.value, f"{field}_low": value.low, f"{field}_high": value.high,
                        f"{field}_confirmed": value.confirmed, f"{field}_source": value.source,
                        f"{field}_note": value.note})
            if field in ENERGY_BASED:
                row[f"{field}_basis"] = value.basis
    out = io.StringIO()
    for line in comment.splitlines():
        out.write(f"# {line}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(FRUIT_COLUMNS)
    writer.writerow([_cell(row.get(column)) for column in FRUIT_COLUMNS])
    return out.getvalue()


#: Fruit files loaded so far: real path → ((inode, size, mtime), fruit).  A file is found by its path only: its
#: fruit's name is no key (what a name means must not depend on which files were loaded before).
_FILES: dict = {}


def _numbers(entry: Fruit) -> tuple:
    """What makes two fruits the same fruit: every value with its range and basis, and the criterion."""
    return tuple((name, value.value, value.low, value.high, value.basis) for name, value in entry.values().items()) \
        + (entry.criterion,)


def load_fruit_file(path) -> Fruit:
    """The fruit of the fruit file ``path`` (:func:`read_fruit_file`), found again by its path only (never by its
    fruit's name: two files may name their fruits alike, and a name means the same in every process).  Read again
    only when the file changed.  A fruit whose name is a library fruit's is accepted only with the library fruit's
    values (``_numbers``): a file's ``apple`` is the library's apple.

    Raises
    ------
    LibraryError
        A file that cannot be read or breaks a rule of the library, or a clash of names, naming the file.
    """
    shown = os.fspath(path)
    real = os.path.realpath(path)
    if os.path.isdir(real):
        raise LibraryError(f"the fruit file {shown!r} is a directory, not a fruit file (a .csv in the fruit "
                           f"library's format)")
    try:
        status = os.stat(real)
    except OSError as exc:
        raise LibraryError(f"cannot read the fruit file {shown!r}: {exc.strerror or exc}") from None
    stamp = (status.st_ino, status.st_size, status.st_mtime_ns)  # atomic writes give a new inode
    known = _FILES.get(real)
    if known is not None and known[0] == stamp:
        return known[1]
    entry = read_fruit_file(path)
    library = fruits().library.get(entry.name)
    if library is not None and _numbers(library) != _numbers(entry):
        raise LibraryError(f"fruit file {shown!r} names its fruit {entry.name!r}, a fruit of the library with other "
                           f"values: give the fitted fruit another name")
    _FILES[real] = (stamp, entry)
    return entry


class FruitRegistry(Mapping):
    """The fruit library as a read-only mapping, name → :class:`Fruit`, that also resolves fruit files.

    Iterating gives the library's fruits in file order (what ``fruitimpact fruits`` lists and messages name).
    Looking up a path to an existing ``.csv`` file loads it (:func:`load_fruit_file`); so every ``fruit`` input
    (``--fruit``, a batch's ``fruit`` column, a Python ``fruit=``) accepts a fruit file wherever it accepts a library
    name.  A file is found by its path only: the name of its fruit is not a fruit (whatever was loaded before).  A
    file that breaks a rule is not in the registry; :meth:`refusal` says why."""

    def __init__(self, entries: dict[str, Fruit]):
        self.library = MappingProxyType(dict(entries))

    def __getitem__(self, key) -> Fruit:
        if isinstance(key, str):
            entry = self.library.get(key)
            if entry is not None:
                return entry
        if is_fruit_file(key) and os.path.isfile(key):
            return load_fruit_file(key)
        raise KeyError(key)

    def __contains__(self, key) -> bool:
        try:
            self[key]
        except (KeyError, TypeError, LibraryError):
            return False
        return True

    def __iter__(self) -> Iterator[str]:
        return iter(self.library)

    def __len__(self) -> int:
        return len(self.library)

    def refusal(self, key) -> str | None:
        """Why ``key`` names no fruit, when it names a fruit file (one line naming ``fruit``); None otherwise (the
        caller's own "must be one of" message applies)."""
        if not is_fruit_file(key) or key in self:
            return None
        if os.path.isdir(key):
            return (f"fruit must be one of {', '.join(self.library)} or a fruit file (.csv); {os.fspath(key)!r} is "
                    f"a directory, not a file")
        if not os.path.isfile(key):
            return (f"fruit must be one of {', '.join(self.library)} or a fruit file (.csv); the file "
                    f"{os.fspath(key)!r} does not exist")
        try:
            load_fruit_file(key)
        except LibraryError as exc:
            return str(exc)
        return None


# ----------------------------------------------------------------------------------------------- listing

def _row(entry, units: dict[str, str], text: tuple[str, ...]) -> dict:
    row = {key: getattr(entry, key) for key in text}
    for name, unit in units.items():
        value = getattr(entry, name)
        row.update({name: None if value is None else value.value,
                    f"{name}_low": None if value is None else value.low,
                    f"{name}_high": None if value is None else value.high,
                    f"{name}_unit": unit,
                    f"{name}_confirmed": None if value is None else value.confirmed,
                    f"{name}_source": None if value is None else value.source,
                    f"{name}_note": None if value is None else value.note})
    return row


def fruit_rows() -> list[dict]:
    """The fruit table for listing (``fruitimpact fruits``, table or JSON): one flat dict per fruit with
    ``name``, ``description``, ``modulus_kind``, ``source`` and, per property X of :data:`FRUIT_UNITS`,
    ``X`` (SI, ``None`` if unknown), ``X_low``, ``X_high``, ``X_unit``, ``X_confirmed``, ``X_source``,
    ``X_note``."""
    return [_row(entry, FRUIT_UNITS, ("name", "description", "modulus_kind", "source"))
            for entry in fruits().values()]


def surface_rows() -> list[dict]:
    """The surface table for listing (``fruitimpact surfaces``): one flat dict per surface with ``name``,
    ``description``, ``model``, ``partner``, ``source`` and, per property X of :data:`SURFACE_UNITS`,
    ``X``, ``X_low``, ``X_high``, ``X_unit``, ``X_confirmed``, ``X_source``, ``X_note``."""
    return [_row(entry, SURFACE_UNITS, ("name", "description", "model", "partner", "source"))
            for entry in surfaces().values()]


def __getattr__(name: str):
    """``FRUITS`` and ``SURFACES`` (the registries, same as :func:`fruits` and :func:`surfaces`), read on
    first use."""
    if name == "FRUITS":
        return fruits()
    if name == "SURFACES":
        return surfaces()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
