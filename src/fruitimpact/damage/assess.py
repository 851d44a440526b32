"""The bruise columns of a table of impacts: one criterion per row, named in every output.

The rules (docs/damage.md):

* the criterion compares the impact's peak contact pressure p_0 (``pressure``),
  the largest subsurface shear τ_max = (τ_max/p_0)(ν) p_0 of Hertz's field
  (``shear``), or the energy absorbed by the fruit W_f (``energy``) with its
  threshold (σ_f, σ_f/2 or W_th);
* the bruise volume is BS (W_f − W_th)₊ where the criterion says bruised, 0
  elsewhere (Opara & Pathare 2014: BV = BS (E − E_th)₊), W_f being the fruit's
  share of the absorbed energy ½ m* V² (1 − e²).  Under a stress criterion W_th
  is the fruit energy at the criterion's own onset, so the volume grows from 0
  there as published bruises do (issue 14 item 5b; before, it jumped from 0 to
  ~190 mm³): at a fixed restitution the impact is the same dimensionless
  impact at every speed (power law, Tsuji, Kuwabara–Kono: e fixes the damping
  group), so p0 and τ_max go as V^0.4 (Hertz scales, δ ∝ V^0.8) and W_f as V²;
  the onset energy is W_f (threshold/quantity)⁵ exactly.  On a cushion layer
  or with plastic contact p0 does not scale so; there it is the same Hertz
  estimate (docs/damage.md says so);
* the bruise is a spherical cap of width 2a/ratio (a the contact radius, the ratio
  the fruit's own contact-to-bruise width ratio: pear 1.4, Stropek & Gołacki 2020;
  unknown for the others) holding that volume, which fixes its depth.
"""

from __future__ import annotations

import numpy as np

from fruitimpact.damage import bruise

#: Criterion codes of the ``criterion`` text input (``none`` first).
CRITERION_NAMES = ("none", "pressure", "shear", "energy")


def bruise_columns(criterion: np.ndarray, *, peak_pressure, poisson, fruit_energy, failure_stress,
                   threshold_energy, susceptibility, contact_radius, valid, volume_energy=None,
                   width_ratio=bruise.CONTACT_TO_BRUISE_WIDTH) -> dict[str, np.ndarray]:
    """``max_shear_stress``, ``bruise_margin``, ``bruised``, ``bruise_volume``, ``bruise_depth``,
    ``bruise_width`` and ``bruise_energy`` (the threshold W_th the volume used) of every row (arrays of the table's length; NaN where no criterion applies or
    the row is not ``valid``).  ``criterion`` holds indices into ``CRITERION_NAMES``.  ``fruit_energy`` [J] is
    the energy on the basis of ``threshold_energy`` (the energy criterion compares them), ``volume_energy``
    [J] the energy on the basis of ``susceptibility`` (default: the same); the threshold is carried over to
    the susceptibility's basis by their ratio for the volume.  The ``bruise_energy`` output is on the
    threshold's basis."""
    if volume_energy is None:
        volume_energy = fruit_energy
    rows = criterion.shape[0]
    out = {name: np.full(rows, np.nan) for name in ("bruise_margin", "bruised", "bruise_volume", "bruise_depth",
                                                   "bruise_width")}
    out["bruise_energy"] = np.where(valid, np.asarray(threshold_energy, dtype=float), np.nan)
    # a law without a Hertz pressure (Kelvin–Voigt: NaN) has no stress criterion; the energy criterion needs none
    energy_ok = valid & np.isfinite(fruit_energy)
    finite = energy_ok & np.isfinite(peak_pressure)
    shear_ok = finite & (poisson >= 0.0) & (poisson <= 0.5)
    everywhere = bool(shear_ok.all())
    nu = poisson if everywhere else poisson[shear_ok]
    if nu.size and nu.min() == nu.max():  # one fruit material: τ_max/p0 once, not a sort of every row
        shear = float(bruise.hertz_max_shear(float(nu[0]))[0]) * (peak_pressure if everywhere else
                                                                    peak_pressure[shear_ok])
    else:
        shear = bruise.max_shear_stress(peak_pressure if everywhere else peak_pressure[shear_ok], nu) \
            if nu.size else np.empty(0)
    if everywhere:
        out["max_shear_stress"] = np.asarray(shear, dtype=float)
    else:
        out["max_shear_stress"] = np.full(rows, np.nan)
        out["max_shear_stress"][shear_ok] = shear
    for code, name in enumerate(CRITERION_NAMES):
        if name == "none":
            continue
        rows_of = np.flatnonzero((energy_ok if name == "energy" else finite) & (criterion == code)
                                 & (shear_ok if name == "shear" else True))
        if rows_of.size == 0:
            continue
        margin = bruise.CRITERIA[name].margin(
            peak_pressure=peak_pressure[rows_of], poisson=poisson[rows_of], absorbed_energy=fruit_energy[rows_of],
            failure_stress=failure_stress[rows_of], threshold_energy=threshold_energy[rows_of])
        out["bruise_margin"][rows_of] = margin
        bruised = margin >= 0.0
        out["bruised"][rows_of] = bruised
        threshold = threshold_energy[rows_of]
        if name != "energy":  # the fruit energy at the stress criterion's onset (module docstring)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                onset = fruit_energy[rows_of] * (1.0 + margin) ** -5.0
            threshold = np.maximum(threshold, np.where(np.isfinite(onset), onset, 0.0))
            out["bruise_energy"][rows_of] = threshold
        energy = volume_energy[rows_of]
        if volume_energy is not fruit_energy:  # the threshold on the susceptibility's basis
            with np.errstate(divide="ignore", invalid="ignore"):
                carried = threshold * energy / fruit_energy[rows_of]
            # a fruit that absorbed nothing (e = 1: an elastic law) is below any positive threshold on its own
            # basis, which no ratio carries over (it was inf, and one such row refused the whole table): its
            # threshold on the volume's basis is then the energy itself, so its volume is 0
            threshold = np.where(threshold > 0.0, np.where(np.isfinite(carried), carried, energy), 0.0)
        volume = bruise.bruise_volume(energy, susceptibility[rows_of], threshold, bruised)
        ratio = np.broadcast_to(np.asarray(width_ratio, dtype=float), (rows,))[rows_of]
        depth, width = bruise.bruise_geometry(volume, contact_radius[rows_of], ratio)
        out["bruise_volume"][rows_of] = volume
        out["bruise_depth"][rows_of] = depth
        out["bruise_width"][rows_of] = width
    return out


__all__ = ["CRITERION_NAMES", "bruise_columns"]
