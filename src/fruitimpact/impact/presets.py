"""Library presets (``--fruit NAME``, ``--surface NAME``) as per-row defaults of the inputs.

A preset replaces the *defaults* of the inputs it knows, never a value the user
gave: ``--fruit apple --mass 150g`` is the library apple with a 150 g mass.  The
``fruit`` surface is an identical free fruit: its modulus, Poisson's ratio and
radius are the fruit's as used, and its mass the partner mass (the reduced mass
m/2 moves, ``--velocity`` is the approach speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.library import catalogue as library
from fruitimpact.impact.quantities import FRUIT_FIELD_INPUTS, INPUTS

#: The library's names of fruit properties that differ from the inputs' names.
_FRUIT_KEYS = {field: name for field, name in FRUIT_FIELD_INPUTS.items() if field != name}
_LIBRARY_KEYS = {value: key for key, value in _FRUIT_KEYS.items()}
#: Surface models as codes.
HALF_SPACE, LAYER = 0, 1
#: The damage inputs a row takes from its fruit's library entry (every row has a fruit: the default one when
#: none is given), and their value before it: unknown, never another fruit's (issue 14 item 1; what the entry
#: lacks is in ``Resolved.missing`` and the criterion needing it is refused), but no threshold energy.
DAMAGE_DEFAULTS = {"failure_stress": math.nan, "bruise_susceptibility": math.nan, "bruise_energy": 0.0}


@dataclass
class Resolved:
    """The per-row defaults after presets: ``defaults`` (input name → a float for every row, or an
    array of one value per row; only the inputs that presets or damage defaults touch), the
    surface model code per row, the default target restitution (float or per row), the rows
    whose ``bruise_energy`` comes from nobody (neither given nor in the fruit's library entry), and
    ``missing``: for each damage input of ``DAMAGE_DEFAULTS`` and for ``restitution``, the rows whose ``--fruit``
    entry has no value for it (NaN there unless the user gives one; the restitution: the default target), with ``fruit_of`` the fruit name of each row ("" without);
    ``impact_basis``: for ``bruise_susceptibility`` and ``bruise_energy``, the rows whose value is on the
    impact-energy basis (the user's ``bruise_basis`` for a value given, the library's for the fruit's own;
    else absorbed)."""

    defaults: dict
    surface_model: np.ndarray
    restitution: np.ndarray | float
    no_threshold: np.ndarray
    missing: dict
    fruit_of: np.ndarray
    impact_basis: dict

    def apply(self, used: dict, given: dict) -> None:
        """Replace the table defaults in ``used`` (name → array, written in place) where the input was not given."""
        for name, value in self.defaults.items():
            if not np.all(given[name]):
                np.copyto(used[name], value, where=~given[name])


class _Defaults(dict):
    """name → scalar, or per-row array once two groups of rows differ."""

    def __init__(self, rows: int):
        super().__init__()
        self.rows = rows

    def put(self, name: str, where, value, everywhere: bool) -> None:
        if everywhere:
            self[name] = value
            return
        current = self.get(name, INPUTS[name].default if INPUTS[name].default is not None else math.nan)
        if np.ndim(current) == 0:
            current = np.full(self.rows, current, dtype=float)
            self[name] = current
        current[where] = value


def resolve(inputs, default_restitution: float) -> Resolved:
    """Per-row defaults of ``inputs`` (``inputs.InputColumns``) from the ``fruit`` and ``surface``
    presets and the damage defaults."""
    rows = inputs.rows
    defaults = _Defaults(rows)
    for name, value in DAMAGE_DEFAULTS.items():
        defaults[name] = value
    no_threshold = np.ones(rows, dtype=bool)
    missing = {name: np.zeros(rows, dtype=bool) for name in (*DAMAGE_DEFAULTS, "restitution", "bruise_width_ratio")}
    impact_basis = {name: np.zeros(rows, dtype=bool) for name in ("bruise_susceptibility", "bruise_energy")}
    fruit_of = np.full(rows, "", dtype=object)
    restitution = default_restitution
    fruit_labels = inputs.text["fruit"]
    fruits = library.fruits()
    single = len(fruit_labels.labels) == 1
    for code, name in enumerate(fruit_labels.labels):
        if name not in fruits:
            continue  # refused by the text check
        where = slice(None) if single else fruit_labels.codes == code
        fruit_of[where] = name
        entry = fruits[name].inputs()
        for key in ("restitution", "bruise_width_ratio"):
            if entry.get(key) is None:
                missing[key][where] = True
        for key in DAMAGE_DEFAULTS:
            if key != "bruise_energy" and entry.get(_LIBRARY_KEYS.get(key, key)) is None:
                defaults.put(key, where, math.nan, single)
                missing[key][where] = True
        for key, basis in fruits[name].bases().items():
            impact_basis[_FRUIT_KEYS.get(key, key)][where] = basis == "impact"
        for key, value in entry.items():
            key = _FRUIT_KEYS.get(key, key)
            if value is None:
                continue
            if key == "restitution":
                if single:
                    restitution = value
                else:
                    if np.ndim(restitution) == 0:
                        restitution = np.full(rows, restitution)
                    restitution[where] = value
                continue
            defaults.put(key, where, value, single)
            if key == "bruise_energy":
                no_threshold[where] = False

    basis_labels = inputs.text["bruise_basis"]
    for code, label in enumerate(basis_labels.labels):
        rows_of = basis_labels.codes == code
        for key, flags in impact_basis.items():
            given_here = rows_of & inputs.given[key]
            flags[given_here] = label == "impact"

    def used(name):
        value = defaults.get(name, INPUTS[name].default)
        return np.where(inputs.given[name], inputs.values[name], value)

    surface_model = np.zeros(rows, dtype=np.int8)
    surface_labels = inputs.text["surface"]
    surfaces = library.surfaces()
    single = len(surface_labels.labels) == 1
    for code, name in enumerate(surface_labels.labels):
        if name not in surfaces:
            continue  # rigid (no preset) or refused by the text check
        where = slice(None) if single else surface_labels.codes == code
        preset = surfaces[name].inputs()
        if preset["surface_model"] == "fruit":
            for key, source in (("surface_modulus", "modulus"), ("surface_poisson", "poisson"),
                                ("partner_mass", "mass")):
                defaults.put(key, where, used(source)[where], single)
            defaults.put("surface_radius", where, used("diameter")[where] / 2.0, single)
            continue
        for key in ("surface_modulus", "surface_poisson", "surface_radius", "surface_thickness", "surface_crush_stress"):
            if preset[key] is not None:
                defaults.put(key, where, preset[key], single)
        if preset["surface_model"] == "layer":
            surface_model[where] = LAYER
    model_labels = inputs.text["surface_model"]
    for code, name in enumerate(model_labels.labels):
        if name in ("half-space", "layer"):
            surface_model[model_labels.codes == code] = LAYER if name == "layer" else HALF_SPACE
    return Resolved(dict(defaults), surface_model, restitution, no_threshold, missing, fruit_of, impact_basis)


#: The inputs a lot draws from its fruit's library spreads (issue 14 item 4), in this order (each the library field
#: of ``FRUIT_FIELD_INPUTS``); the diameter follows the mass at the fruit's density where the library has one.
LOT_SPREADS = ("mass", "diameter", "modulus", "failure_stress", "bruise_susceptibility", "bruise_energy")
#: Those that only a bruise criterion uses (not drawn without one).
_BRUISE_SPREADS = ("failure_stress", "bruise_susceptibility", "bruise_energy")
#: Those that only the energy criterion draws: the threshold energy is its onset.  Under a stress criterion the
#: onset is the failure stress's and the volume counts from its W_f; a threshold energy given (and a drawn one is
#: given) would be counted from instead, so drawing it there would change the bruise volumes, not only print a
#: spread.  A fruit-to-fruit spread of it is what a lab's drop tests give (``fit-damage``: the fruit's thresholds,
#: lognormal), so that a lot near onset is bruised in part, as drop tests see, not all or none.
_ENERGY_SPREADS = ("bruise_energy",)


@dataclass(frozen=True)
class LotSpreads:
    """What a lot of ``fruit`` varies by default: ``distributions`` ((input name, distribution) pairs: each a
    split normal with its median at the library's value and each side's sd half the distance to that end of
    the library range, truncated to the range), ``diameter_density`` (the density [kg/m³] each fruit's
    diameter follows its mass at, or None), ``described``: one line per property, for the output, and
    ``bruise_bases``: for each drawn bruise value (input name), the energy basis (``impact`` or ``absorbed``) the
    library records it was measured on (the lot's rows must carry it: a drawn value is a given one, and a given
    value's basis is ``bruise_basis``'s; ``impact.lots.read_lot``)."""

    fruit: str
    distributions: tuple
    diameter_density: float | None
    described: tuple
    bruise_bases: tuple = ()


def lot_spreads(fruit: str, fixed, bruise: bool = True, energy: bool = False) -> LotSpreads:
    """The library spreads a lot of ``fruit`` is drawn from, leaving out the inputs in ``fixed`` (those the
    user gave, as constants or distributions; a given ``stiffness`` fixes the contact, so the modulus is not
    drawn), without a bruise criterion (``bruise`` False) the failure stress, susceptibility and threshold
    energy, and the threshold energy unless the criterion is ``energy`` (``energy`` True).  A
    property whose library range is one value stays that value; one the entry lacks is left to the inputs' own
    rules (a criterion needing it is refused).  The diameter follows each fruit's mass (drawn here or given)
    at the library density unless the diameter is given.  ``fruit`` must be a library name."""
    from fruitimpact.impact.distributions import SplitNormal

    entries = library.fruits()
    if fruit not in entries:
        raise ValueError(f"fruit must be one of {', '.join(entries)}; got {fruit!r}")
    entry = entries[fruit]
    fixed = set(fixed)
    out, lines, density = [], [], None
    for name in LOT_SPREADS:
        field = _LIBRARY_KEYS.get(name, name)
        value = getattr(entry, field)
        if name in fixed:
            lines.append(f"{name}: as given")
            continue
        if name in _BRUISE_SPREADS and not bruise or name in _ENERGY_SPREADS and not energy:
            continue
        if name == "modulus" and "stiffness" in fixed:
            lines.append("modulus: not drawn (the given stiffness fixes the contact)")
            continue
        if value is None:
            continue
        if name == "diameter" and entry.density is not None:
            density = entry.density.value
            lines.append(f"diameter: from each fruit's mass at the {fruit} density {density:g} kg/m³ "
                         f"(d = (6 m/(π ρ))^(1/3))")
            continue
        if not value.low < value.high:
            lines.append(f"{name}: {value.value:g} {value.unit} (the library gives no spread)")
            continue
        low_sd, high_sd = (value.value - value.low) / 2.0, (value.high - value.value) / 2.0
        out.append((name, SplitNormal(value.value, low_sd, high_sd, value.low, value.high)))
        lines.append(f"{name}: median {value.value:g}, sd {low_sd:.3g} below and {high_sd:.3g} above, in "
                     f"[{value.low:g}, {value.high:g}] {value.unit} (the {fruit} library value and range, "
                     f"each side a ±2 sd band)")
    recorded = entry.bases()
    bases = tuple((name, recorded[_LIBRARY_KEYS.get(name, name)]) for name, _ in out
                  if name in _BRUISE_SPREADS and _LIBRARY_KEYS.get(name, name) in recorded)
    return LotSpreads(fruit, tuple(out), density, tuple(lines), bases)


def fruit_criterion(fruit: str | None, criterion: str | None, task: str = "") -> str:
    """The bruise criterion a ``task`` that needs one uses (a safe height, a line audit): ``criterion`` as given
    (checked against the registry), or, when it is None or ``preset``, the one the literature supports for
    ``fruit`` (its library entry; the default fruit when None).  ValueError naming ``criterion`` for ``none``,
    a misspelt criterion, or a fruit that names none."""
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.impact.validation import InputError, check_choice

    if criterion == "none":
        raise InputError(f"criterion must be given for {task or 'this task'}: pressure, shear or energy (the onset "
                         f"height changes by an order of magnitude between them)", "criterion")
    if criterion not in (None, "preset"):
        return check_choice("criterion", criterion, REGISTRIES["criterion"])
    name = check_choice("fruit", fruit or INPUTS["fruit"].default, library.fruits())  # a misspelt fruit is said so
    entry = library.fruits()[name]
    if entry.criterion is None:
        raise InputError(f"criterion must be given: the {name} entry of the fruit library names no bruise criterion "
                         f"the literature supports (pressure, shear or energy; the onset height changes by an "
                         f"order of magnitude between them)", "criterion")
    return entry.criterion


def effective_mass(mass, partner_mass):
    """Reduced mass m m_2/(m + m_2) [kg]; a fixed surface (m_2 = inf) leaves m."""
    mass = np.asarray(mass, dtype=float)
    partner_mass = np.asarray(partner_mass, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.where(np.isinf(partner_mass), mass, mass * partner_mass / (mass + partner_mass))


assert all(name in INPUTS for name in DAMAGE_DEFAULTS)


def lot_distributions(fruit: str | None, given, criterion: str | None, spreads: bool = True):
    """(extra distributions, diameter density or None, lines describing the spreads, the energy basis of each drawn
    bruise value: ``LotSpreads.bruise_bases``) of a lot of ``fruit``
    (the default fruit when None): the library spreads (``lot_spreads``) of the inputs not in ``given``,
    the bruise inputs only with a ``criterion`` (issue 14 item 4); none when ``spreads`` is False (identical
    fruit at the library values).  ValueError naming ``fruit`` for a fruit that is not in the library."""
    fruit = fruit or INPUTS["fruit"].default
    if not spreads:
        return (), None, (f"identical {fruit} fruit (--no-spreads): each input at its library value",), ()
    from fruitimpact.impact.validation import InputError

    try:
        effective = criterion
        if criterion == "preset" and fruit in library.fruits():  # the fruit's own (a misspelt fruit: refused below)
            effective = library.fruits()[fruit].criterion
        lot = lot_spreads(fruit, given, bruise=criterion not in (None, "none"), energy=effective == "energy")
    except ValueError as exc:
        raise InputError(str(exc), "fruit") from None
    described = lot.described
    fitted = library.fitted_criterion(library.fruits()[fruit]) if library.is_fruit_file(fruit) else None
    drawn = {name for name, _ in lot.distributions}
    if fitted is not None and criterion in ("pressure", "shear") and criterion != fitted and "failure_stress" in drawn:
        # the lot's rows carry the drawn stress as given: the evaluation's warning of it is said here, once
        described += (f"warning: {library.fitted_criterion_message(fruit, fitted, criterion)}",)
    return lot.distributions, lot.diameter_density, described, lot.bruise_bases


__all__ = ["DAMAGE_DEFAULTS", "HALF_SPACE", "LAYER", "fruit_criterion", "lot_distributions", "LOT_SPREADS", "LotSpreads", "Resolved", "effective_mass",
           "lot_spreads", "resolve"]
