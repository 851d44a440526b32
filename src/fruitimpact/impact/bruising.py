"""The damage stage of an evaluation (``impact.evaluation``): the refusals that need the presets (a layer without a
usable thickness, bruise inputs without a criterion, a criterion without its fruit's value), the warnings where a
surface model is used outside its range, and the damage columns of every row (``quantities.DAMAGE_NAMES``), each
bruise value applied on the energy its source measured it on."""

from __future__ import annotations

import numpy as np

from fruitimpact.damage.assess import CRITERION_NAMES, bruise_columns
from fruitimpact.engine.codes import COLUMN, CONTACT_RADIUS, N_CHARACTERISTICS
from fruitimpact.engine.plasticforms import PLASTIC_COLUMNS
from fruitimpact.impact import fruitfiles
from fruitimpact.impact.inputs import InputColumns
from fruitimpact.impact.quantities import DAMAGE_NAMES
from fruitimpact.impact.validation import MessageBook, WarningBook


#: Thinnest cushion the layer model takes [m]: below it the pad is a coating (use a half-space).
MIN_LAYER_THICKNESS = 0.5e-3
#: Bruise inputs that mean nothing without a criterion.
BRUISE_INPUTS = ("failure_stress", "bruise_susceptibility", "bruise_energy", "bruise_width_ratio")


def check_damage_inputs(inputs: InputColumns, resolved, layer, used, thickness, messages: MessageBook,
                        warnings: WarningBook) -> None:
    """Refusals that need the presets: layers without a usable thickness, bruise inputs without a
    criterion, an energy criterion without a threshold."""
    given = inputs.given
    if layer.any():
        no_thickness = layer & ~np.isfinite(thickness)
        messages.set(no_thickness & ~messages.flagged,
                     "surface_thickness must be given (finite) for a layer surface: the elastic-foundation model "
                     "is a cushion of thickness h on a rigid substrate", "surface_thickness")
        thin = layer & (thickness < MIN_LAYER_THICKNESS)
        messages.set(thin & ~messages.flagged,
                     f"surface_thickness must be >= {MIN_LAYER_THICKNESS * 1e3:g} mm for a layer surface (a thinner "
                     f"pad is a coating: use --surface-model half-space or a rigid surface)", "surface_thickness")
        rigid = layer & ~np.isfinite(used["surface_modulus"])
        messages.set(rigid & ~messages.flagged, "surface_modulus must be finite for a layer surface",
                     "surface_modulus")
    if given["surface_crush_stress"].any():
        messages.set(given["surface_crush_stress"] & ~layer & ~messages.flagged,
                     "surface_crush_stress is the flat-crush strength of a cushion layer: give it with a layer "
                     "surface (--surface cardboard, or --surface-model layer --surface-thickness H)",
                     "surface_crush_stress")
    criteria = inputs.text["criterion"]
    for code, name in enumerate(criteria.labels):
        where = criteria.codes == code
        if name == "none":
            for key in BRUISE_INPUTS:
                if given[key].any():
                    messages.set(where & given[key] & ~messages.flagged,
                                 f"{key} is a bruise input: give --criterion pressure, shear or energy with it "
                                 f"(the criterion changes the onset height by an order of magnitude)", key)
        elif name == "energy":
            messages.set(where & resolved.no_threshold & ~given["bruise_energy"] & ~messages.flagged,
                         "bruise_energy must be given for the energy criterion (the absorbed energy at bruise onset "
                         "[J]; the --fruit's library entry has none)", "bruise_energy")
            messages.set(where & given["bruise_energy"] & ~(inputs.values["bruise_energy"] > 0.0) & ~messages.flagged,
                         "bruise_energy must be > 0 J for the energy criterion (its threshold)", "bruise_energy")
        if name in ("pressure", "shear"):
            fruitfiles.fitted_stress_warnings(inputs, resolved, where, name, messages, warnings)
            lacking = where & resolved.missing["failure_stress"] & ~given["failure_stress"] & ~messages.flagged
            for fruit in sorted(set(resolved.fruit_of[lacking])):
                messages.set(lacking & (resolved.fruit_of == fruit),
                             f"failure_stress is not in the {fruit} entry of the fruit library (no sourced failure or "
                             f"bioyield stress) and the {name} criterion needs it: give --failure-stress (the flesh's failure "
                             f"stress [Pa], e.g. 0.3MPa, from a compression test of that fruit), or --criterion energy "
                             f"with --bruise-energy", "failure_stress")
        if name != "none":
            lacking = where & resolved.missing["bruise_susceptibility"] & ~given["bruise_susceptibility"] \
                & ~messages.flagged
            for fruit in sorted(set(resolved.fruit_of[lacking])):
                warnings.add(lacking & (resolved.fruit_of == fruit),
                             f"bruise_susceptibility is not in the {fruit} entry of the fruit library: bruise onset is "
                             f"judged, bruise volume is not (give --bruise-susceptibility [m^3/J], e.g. 3e-6)")
            lacking = where & resolved.missing["bruise_width_ratio"] & ~given["bruise_width_ratio"] \
                & ~messages.flagged
            for fruit in sorted(set(resolved.fruit_of[lacking])):
                warnings.add(lacking & (resolved.fruit_of == fruit),
                             f"bruise_width_ratio is not in the {fruit} entry of the fruit library (measured on "
                             f"pears only): bruise depth and width are unknown (give --bruise-width-ratio, the "
                             f"contact width over the bruise width, e.g. 1.4)")
        if name == "shear":
            poisson = used["poisson"]
            messages.set(where & ~((poisson >= 0.0) & (poisson <= 0.5)) & ~messages.flagged,
                         "poisson must be in [0, 0.5) for the shear criterion (Hertz's subsurface field)", "poisson")


def range_warnings(warnings: WarningBook, out, plastic_block, layer, thickness, given_thickness, radius, done,
                   detail: bool, crushing) -> None:
    """Warnings where a surface model is used outside its range."""
    if out is None:
        return
    a = out[:, CONTACT_RADIUS]
    if layer.any():
        thick = done & layer & (a < thickness)
        if thick.any():
            ratio = f" ({float(a[0]) * 1e3:.3g} mm < {float(thickness[0]) * 1e3:.3g} mm)" if detail else ""
            warnings.add(thick, f"the contact radius is smaller than the layer thickness{ratio}: the "
                                f"elastic-foundation model assumes a thin layer (a >= h); treat the figures as an "
                                f"estimate")
        if plastic_block is not None:
            bottomed = done & layer & (plastic_block[:, PLASTIC_COLUMNS.index("bottomed_out")] == 1.0)
            crushed = bottomed & crushing
            if crushed.any():
                warnings.add(crushed, "the board crushes: the pressure under the fruit reaches its flat-crush "
                                      "strength, the flutes collapse and the force beyond is carried by the floor "
                                      "as if rigid")
            if (bottomed & ~crushing).any():
                warnings.add(bottomed & ~crushing, "the pad bottoms out: its deflection reaches its thickness, and "
                                                   "the force beyond that is carried by the substrate as if rigid")
    half_space_layer = done & ~layer & np.isfinite(given_thickness) & (a > given_thickness)
    if half_space_layer.any():
        warnings.add(half_space_layer, "the contact radius exceeds the surface thickness: Hertz's half-space does not "
                                       "hold; use --surface-model layer")


def damage_columns(out, plastic_block, done, mass, velocity, used, inputs, fruit_modulus, pair_modulus, layer,
                   resolved) -> dict:
    """The damage outputs (``quantities.DAMAGE_NAMES``) of every row."""
    rows = done.size
    if out is None:
        out = np.full((rows, N_CHARACTERISTICS), np.nan)
    absorbed = out[:, COLUMN["absorbed_energy"]]
    columns = {"yield_velocity": np.full(rows, np.inf), "permanent_deflection": np.zeros(rows),
               "plastic_work": np.zeros(rows), "viscous_work": absorbed.copy()}
    # the fruit's share of the compliance, (1/E_1*) / (1/E*): all of it on a rigid surface
    share = 1.0 if not layer.any() and np.isinf(used["surface_modulus"]).all() else pair_modulus / fruit_modulus
    if plastic_block is not None:
        computed = ~np.isnan(plastic_block[:, 0])
        for name in ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work"):
            columns[name] = np.where(computed, plastic_block[:, PLASTIC_COLUMNS.index(name)], columns[name])
        share = np.where(computed & layer, plastic_block[:, PLASTIC_COLUMNS.index("fruit_work_share")], share)
    ok = done & np.isfinite(absorbed)
    if ok.all():  # every row an impact (the common case): nothing to blank
        columns["fruit_energy"] = absorbed * share
    else:
        for name in ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work"):
            columns[name] = np.where(ok, columns[name], np.nan)
        columns["fruit_energy"] = np.where(ok, absorbed * share, np.nan)
    # each bruise value on the energy its source measured it on (issue 14 item 5a): the fruit's share of the
    # impact energy ½ m V² or of the absorbed energy; a threshold on another basis than the susceptibility is
    # carried over by this impact's own ratio of the two
    impact_share = np.where(ok, 0.5 * mass * velocity ** 2 * share, np.nan)
    basis = resolved.impact_basis
    threshold_energy = np.where(basis["bruise_energy"], impact_share, columns["fruit_energy"])
    volume_energy = np.where(basis["bruise_susceptibility"], impact_share, columns["fruit_energy"])
    criterion = inputs.text["criterion"]
    codes = np.asarray([CRITERION_NAMES.index(label) if label in CRITERION_NAMES else 0
                        for label in criterion.labels], dtype=np.int8)[criterion.codes] \
        if len(criterion.labels) else np.zeros(rows, dtype=np.int8)
    # the fruit's library threshold is the energy criterion's; the stress criteria subtract only a given one
    threshold = np.where((codes == CRITERION_NAMES.index("energy")) | inputs.given["bruise_energy"],
                         used["bruise_energy"], 0.0)
    columns.update(bruise_columns(codes, peak_pressure=out[:, COLUMN["max_pressure"]], poisson=used["poisson"],
                                  fruit_energy=threshold_energy, volume_energy=volume_energy,
                                  failure_stress=used["failure_stress"], threshold_energy=threshold,
                                  susceptibility=used["bruise_susceptibility"],
                                  contact_radius=out[:, CONTACT_RADIUS], valid=done,
                                  width_ratio=used["bruise_width_ratio"]))
    return {name: columns[name] for name in (*DAMAGE_NAMES, "bruise_energy")}


__all__ = ["BRUISE_INPUTS", "MIN_LAYER_THICKNESS", "check_damage_inputs", "damage_columns", "range_warnings"]
