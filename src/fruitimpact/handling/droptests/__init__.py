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

Modules, one job each: ``table`` (the table of tests, read and checked), ``impacts`` (each test's impact by the
engine: the compared energy, diameters to volumes, onset stresses), ``fruitfile`` (the fitted fruit, in the
library's format) and ``fit`` (``fit_damage`` and its report).
"""

from __future__ import annotations

from fruitimpact.handling.droptests.fit import fit_damage
from fruitimpact.handling.droptests.impacts import CONVERSIONS
from fruitimpact.handling.droptests.table import (DEPTH_TO_DEFORMATION, ENERGY_COLUMNS, INTERVAL, MAX_DEPTH_TO_WIDTH,
                                                  MAX_TESTS, MODEL_TEXT, OUTCOMES, RANGE_SIGMAS, SPEED_LIMITS,
                                                  TEST_COLUMNS, Outcome, Tests, read_tests)


__all__ = ["CONVERSIONS", "DEPTH_TO_DEFORMATION", "ENERGY_COLUMNS", "INTERVAL", "MAX_DEPTH_TO_WIDTH", "MAX_TESTS",
           "MODEL_TEXT", "OUTCOMES", "Outcome", "RANGE_SIGMAS", "SPEED_LIMITS", "TEST_COLUMNS", "Tests", "fit_damage",
           "read_tests"]
