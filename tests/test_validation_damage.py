"""Validation of the damage predictions against published drop and pendulum tests (issue 14 item 2).

Every test compares a prediction of the library (the fruit's own library entry, no value given by hand except
where the published test fixes it, e.g. a foam's firmness) with a figure a published test measured, and the
tolerance is the spread that test allows: an interval between two tested levels, a one-sided bound ("no bruise
at or below", "bruised at"), or the range over cultivars. No test compares the code with its own earlier output;
one (the potato restitution) is a consistency check by construction and says so.

Where the prediction lies outside the published spread the test is ``xfail(strict=True)`` with the reason: a
change that brings it inside turns the test red (XPASS), and docs/validation-damage.md must then be updated. Where
the library refuses the prediction (no sourced failure stress), the test is ``xfail(strict=True, raises=ValueError)``:
it turns red as soon as the refusal goes, whether the new prediction is inside the spread (XPASS) or not
(AssertionError). The table, the commands and the explanations are in docs/validation-damage.md.
"""

from __future__ import annotations

import numpy as np
import pytest

from fruitimpact.impact import evaluation as batch
from fruitimpact.handling.heights import safe_height

G = 9.80665


def _onset(fruit, surface, criterion="shear", **given):
    return safe_height(fruit=fruit, surface=surface, criterion=criterion, sensitivity=False, **given)


# --- apple: Fu et al. (ASABE AIM 2016 paper 162461461; journal version "'Jazz' apple impact bruise responses to
# different cushioning materials"): a pendulum plate strikes a resting 'Jazz' apple at 7 force levels, n = 50 per
# level and impact zone.  The onset lies between the largest force with no bruise and the force at which every
# fruit was still Extra Fancy (bruises present, but small): the test compares the predicted peak force at onset.

@pytest.mark.xfail(strict=True, reason="bare plate: the shear onset is at 59.6 N, above Fu's 22-50 N; the apple "
                   "entry's modulus is a quasi-static tangent (2.2 MPa), the onset force goes as sigma^3 R^2/E*^2")
def test_fu_bare_aluminium_plate_onset_force():
    """Fu et al. 2016: no bruise at or below 22 N on the bare aluminium plate in any zone; 100 % Extra Fancy at
    50 N (bruised, but within the grade). Tolerance: the onset force lies in (22 N, 50 N], the two tested levels
    that bracket it. Aluminium (~70 GPa) is rigid for an apple, so the library's steel stands in for it."""
    force = _onset("apple", "steel")["peak_force"]
    assert 22.0 < force <= 50.0


def test_fu_foam_1_onset_force():
    """Fu et al. 2016, foam 1: 12.7 mm PU foam of 2.1 kPa firmness at 25 % deflection; no bruise at 95 N,
    100 % Extra Fancy at 115 N. Tolerance: the onset force lies in (95 N, 115 N]. The pad is the library's
    12.7 mm foam-pad with the modulus of this foam, 2.1 kPa / 0.25 = 8.4 kPa (the library's own derivation)."""
    force = _onset("apple", "foam-pad", surface_modulus=8.4e3)["peak_force"]
    assert 95.0 < force <= 115.0


@pytest.mark.xfail(strict=True, reason="foam-pad: the shear onset is at 130 N, below Fu's 160-171 N (linear "
                   "Winkler layer: no plateau or densification, bottoms out; issue 14 item 5e)")
def test_fu_foam_2_onset_force():
    """Fu et al. 2016, foam 2 (the library's foam-pad: 12.7 mm, 4.8 kPa at 25 %, 19.2 kPa): no bruise at 160 N,
    100 % Extra Fancy at 171 N. Tolerance: the onset force lies in (160 N, 171 N]."""
    force = _onset("apple", "foam-pad")["peak_force"]
    assert 160.0 < force <= 171.0


def test_fu_foam_3_onset_force():
    """Fu et al. 2016, foam 3: 12.7 mm, 9.7-11 kPa at 25 % (38.8-44 kPa); no bruise at 160 N, 100 % Extra Fancy
    at 180 N. Tolerance: the firmness is published as a range, so the predicted onset forces over that range
    (softest to firmest) must overlap the measured interval (160 N, 180 N]."""
    soft = _onset("apple", "foam-pad", surface_modulus=38.8e3)["peak_force"]
    firm = _onset("apple", "foam-pad", surface_modulus=44e3)["peak_force"]
    assert soft <= 180.0 and firm > 160.0


def test_komarnicki_stopa_30_mm_causes_no_plastic_deformation():
    """Komarnicki & Stopa 2013 ("Investigation of apples sensitivity to bruising at impact loading", Inżynieria
    Rolnicza 3(146)): a 30 mm pendulum drop height "does not cause plastic deformations". Tolerance: one-sided,
    the onset height on a rigid plate must exceed 30 mm (the surface under their pressure film is taken as rigid
    steel; the abstract gives no upper bound)."""
    assert _onset("apple", "steel")["safe_height"] > 0.030


def test_khorasan_bruise_susceptibility_per_impact_energy():
    """"Determination and Comparison of Susceptibility of Different Apple Varieties (KHORASAN Region) to Impact
    Damage" (Int. J. Biosystems Eng.): pendulum impacts of 0.276, 0.590 and 0.976 J, BS 3.71-6.23 cm³/J over five
    cultivars. The library's 4.66 cm³/J is their mean, so this checks the energy basis it is applied on, not the
    value: the predicted slope of bruise volume against impact energy between the lowest and highest energies must
    lie in the cultivar range [3.71, 6.23] cm³/J. Each impact is one impact of the library apple on a rigid flat
    with the impact energy of the pendulum (m g h = E)."""
    mass = float(batch.evaluate({"fruit": "apple", "surface": "steel", "criterion": "shear",
                                 "drop_height": [0.1]})["mass"][0])
    energies = np.array([0.276, 0.976])
    frame = batch.evaluate({"fruit": "apple", "surface": "steel", "criterion": "shear",
                            "drop_height": energies / (mass * G)})
    volume = frame["bruise_volume"].to_numpy()
    slope = (volume[1] - volume[0]) / (energies[1] - energies[0]) * 1e6  # cm³/J
    assert 3.71 <= slope <= 6.23


# --- apple: Słupska, Syguła, Komarnicki, Szulczewski & Stopa 2022, "Simple Method for Apples' Bruise Area
# Prediction", Materials 15(1):139: Idared, Golden Delicious and Jonagold dropped 10-150 mm in 10 mm steps onto
# wood, concrete, corrugated cardboard and foam (foam type and board flute not in the abstract).

@pytest.mark.xfail(strict=True, reason="foam: the library foam-pad's shear onset is 262 mm, above the 50-150 mm "
                   "where Słupska's foam stopped protecting (their foam is not identified in the abstract)")
def test_slupska_foam_protects_up_to_50_mm_only():
    """Słupska et al. 2022: "the foam protected apples from bruising up to a drop height of 50 mm". Tolerance:
    the onset lies above 50 mm (no bruise there) and at or below 150 mm, the highest height tested (protection
    "up to 50 mm" says bruising was seen above it)."""
    assert 0.050 < _onset("apple", "foam-pad")["safe_height"] <= 0.150


def test_slupska_cardboard_bruises_like_wood_at_the_highest_drops():
    """Słupska et al. 2022: "as the drop height increased, the cardboard degraded and the apple bruising level
    reached the results as for wood and concrete". Tolerance: the weakest reading of that sentence, that the
    apple bruises on cardboard by the highest drop tested, 150 mm (onset at or below 150 mm). Passes since the
    board crushes at its flat-crush stress (issue 14 item 3; before, a never-crushing layer gave 941 mm); that
    stress is unsourced in the library, so this holds the structure, not the board's values."""
    assert _onset("apple", "cardboard")["safe_height"] <= 0.150


# --- kiwifruit

def test_mencarelli_kiwifruit_is_damaged_by_30_cm_onto_steel():
    """Mencarelli et al. 1996 ("Influence of impact surface and temperature on the ripening response of
    kiwifruit", Postharvest Biol. Technol. 8(3):165-177): a 30 cm drop onto a steel plate is their impact-injury
    treatment (flesh deformation, SSC rise). Tolerance: one-sided, the onset must be at or below 30 cm. Loose by
    construction: the library kiwifruit is ripe (day-6 bio-yield 24 kPa), theirs at harvest; the test only guards
    against a prediction of no damage at 30 cm."""
    assert _onset("kiwifruit", "steel")["safe_height"] <= 0.30


# --- potato: Stropek & Gołacki 2022, "Studies concerning the response of potatoes to impact", Int. Agrophys.
# 36(2):115-122: 'Ramos' tubers of 160-190 g on an impact plate.

def test_stropek_potato_restitution():
    """Stropek & Gołacki 2022: "The restitution coefficient changed to an insignificant extent which amounted to
    0.44-0.49 in the tested range of the impact velocity" (bruise onset at 1 m/s, tested up to 1.75 m/s).
    Tolerance: the published range, at 1 m/s (51 mm) and at 1.75 m/s (156 mm).  A consistency check, the one
    exception to this module's rule: the library's 0.465 is that range's midpoint and e is calibrated to it at
    each speed, so this checks the calibration carries the library value through, not the physics."""
    frame = batch.evaluate({"fruit": "potato", "surface": "steel", "drop_height": [0.051, 0.156]})
    restitution = frame["restitution"].to_numpy()
    assert np.all((restitution >= 0.44) & (restitution <= 0.49))


@pytest.mark.xfail(strict=True, raises=ValueError, reason="no prediction: the potato entry has no sourced "
                   "failure stress, the shear criterion is refused")
def test_stropek_potato_bruise_onset():
    """Stropek & Gołacki 2022: "the initiation of the bruise was found to occur at an impact velocity of 1 m s-1.
    This corresponded to a bruise threshold (drop height) of 50 mm". Tolerance: one-sided, the onset at or below
    1 m/s (51 mm); the velocity below it that did not bruise is not in the abstract."""
    assert _onset("potato", "steel")["safe_height"] <= 1.0 / (2 * G)


def test_stropek_potato_energy_onset_at_1_m_s():
    """The potato's threshold energy is derived from the same source (½ m V² at its onset velocity 1 m/s, m the
    tested 160-190 g): a consistency check by construction, of the energy basis. The value was read as an
    *impact* energy, so a 175 g tuber must reach onset at exactly V = 1 m/s (h = 1/(2g) = 51.0 mm) whatever its
    restitution and surface; had the code applied it to the absorbed energy ½ m V² (1 − e²) the onset would be
    1/√(1 − 0.465²) = 1.13× faster. Tolerance 5e-5: the threshold applies to the fruit's share of the energy, and
    steel (E = 200 GPa, against the tuber's E* ≈ 2.5 MPa) stores about 1e-5 of it (measured 1.1e-5 higher)."""
    got = _onset("potato", "steel", criterion="energy", mass=0.175)["safe_height"]
    assert 0.0 <= got / (1.0 / (2 * G)) - 1.0 < 5e-5


@pytest.mark.parametrize("surface,bound", [("steel", 0.15), ("rubber-belt", 0.25)])
def test_rady_soliman_potato_damage_heights(surface, bound):
    """Rady & Soliman 2015 ("Evaluation of mechanical damage of Lady Rosetta potato tubers using different
    methods", Int. J. Postharvest Technol. Innov. 5(2):125-148, abstract): "The minimum dropping heights causing
    unallowable damage were 15, 15, and 25 cm on steel sheet, steel rods, and rubber-coated steel rods". A bound
    from above on the bruise onset (unallowable damage comes at or after the first bruise), for another cultivar
    (threshold from 'Ramos'); their rubber-coated rods are taken as the library rubber belt. One-sided."""
    got = _onset("potato", surface, criterion="energy")["safe_height"]
    assert got <= bound


@pytest.mark.xfail(strict=True, reason="potato onto potato: the energy onset is 17.9 cm, half of the ~36 cm a "
                   "grower talk reports (secondary source; the lower tuber of a pile is not a free identical "
                   "sphere, and Idaho cultivars are not 'Ramos'); docs/validation-damage.md Po4")
def test_potato_onto_potato_no_bruise_below_36_cm():
    """N. Olsen (University of Idaho), reported by Potato News Today, 2021-02-04: "If you drop a potato onto a
    potato, you may not see a bruise until a drop of 14 inches" (35.6 cm). Low authority (a news report of a
    talk); tolerance: the onset within 25 % of 35.6 cm ("may not see": not a measured onset)."""
    got = _onset("potato", "fruit", criterion="energy")["safe_height"]
    assert abs(got / 0.356 - 1.0) < 0.25


# --- peach and tomato: refused today

@pytest.mark.xfail(strict=True, raises=ValueError, reason="no prediction: the peach entry has no sourced failure "
                   "stress, the shear criterion is refused")
def test_peach_bruises_from_31_cm_onto_steel():
    """"Peach bruising: susceptibility to impact, vibration, and compression abuse" (Trans. ASAE): "Impacts from
    drops of 31 cm are often sufficient to cause bruising" (31-91 cm onto a flat steel plate; 31 cm was the
    lowest height). Tolerance: one-sided, the onset at or below 31 cm."""
    assert _onset("peach", "steel")["safe_height"] <= 0.31


@pytest.mark.xfail(strict=True, raises=ValueError, reason="no prediction: the tomato entry has no sourced failure "
                   "stress, the shear criterion is refused")
def test_tomato_internal_bruising_below_60_cm_onto_steel():
    """Thomson & Lopresti 2008 ("Impact collisions during handling and their effect on internal bruising and
    surface splitting of 'Tempest' tomatoes", NZ J. Crop Hort. Sci. 36(1):41-51), mature-green 'Tempest': "severity
    of internal bruising generally increased with increasing drop-height, and drops above 60 cm onto steel caused
    injury that was considered commercially important". Tolerance: one-sided, internal bruising starts at or
    below 60 cm (it grows with height and is commercially important above 60 cm)."""
    assert _onset("tomato", "steel")["safe_height"] <= 0.60
