"""Each test's impact by the project's engine: the energy the simulator compares (the fruit's share on that
surface), bruise diameters turned into volumes, and the onset height and stress at a threshold energy."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.handling.droptests.table import DEPTH_TO_DEFORMATION, MAX_DEPTH_TO_WIDTH, Tests


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
    of E the simulator compares (its own code path: ``impact.bruising.damage_columns``' ``impact_share``)."""
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
