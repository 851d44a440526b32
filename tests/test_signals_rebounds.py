"""Rebound or new fruit, and fruit that land together (issue 13, items 1 and 2).

Independent reference for the rules of item 1: the exact engine's characteristics (``powerlaw_characteristics``,
itself checked against SciPy in tests/test_engine_powerlaw.py) of one fruit (m, K, c) at its impact speed V and
of the same fruit at its exit speed e V: what a rebound *is*.  A rebound lands after the flight 2 e V/g of a
body leaving at e V (no drag).  Each test states the physical fact it checks and why its margin is what it is.

Item 2 is checked on signals built from the exact pulses (``powerlaw_curves``) with 1 % white noise: two fruit a
few milliseconds apart are two contacts measured each on its own samples; two fruit in one contact are told
apart by a joint fit of two pulses, or are one report with status "overlap" and no firmness: never one fruit
fitted through both.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from fruitimpact.physics.constants import STANDARD_GRAVITY as G
from fruitimpact.engine.codes import RESTITUTION
from fruitimpact.engine.powerlaw import exact_x, powerlaw_characteristics, powerlaw_curves
from fruitimpact.signals.analysis import Analysis
from fruitimpact.signals.detect import detect
from fruitimpact.signals.rebounds import TOLERANCES, from_indices, judge, refine

RATE = 20_000.0
MASS, DIAMETER, POISSON, MODULUS = 0.19, 0.075, 0.35, 3.5e6
STIFFNESS = 4 / 3 * MODULUS / (1 - POISSON ** 2) * math.sqrt(DIAMETER / 2)
V_LINE = math.sqrt(2 * G * 0.05)


def impact(mass=MASS, stiffness=STIFFNESS, c=None, velocity=V_LINE, restitution=0.577):
    """The exact characteristics of one impact: F_max, t_c, T, e, impulse m (1 + e) V, and its c."""
    c = float(exact_x(restitution)) / V_LINE if c is None else c
    row = powerlaw_characteristics(mass, stiffness, c, velocity, DIAMETER / 2)[0]
    e = row[RESTITUTION]
    return {"F": row[0], "tc": row[1], "T": row[2], "e": e, "impulse": mass * velocity * (1 + e), "c": c,
            "V": velocity, "m": mass, "K": stiffness}


def summary(imp, onset, sequence, velocity=None):
    """What the analysis knows of a contact: the raw indices, refined by the shape fit (its x, e and end; e to
    ±0.006, the fit's standard error at 1 % noise: tests/test_signals_fit.py)."""
    report = {"start_time": onset, "peak_force": imp["F"], "time_to_peak": imp["tc"], "impulse": imp["impulse"]}
    fit = {"converged": True, "restitution": imp["e"], "restitution_stderr": 0.006, "damping_factor": imp["c"],
           "velocity": imp["V"], "start_time": onset, "contact_duration": imp["T"]}
    return refine(from_indices(report, sequence, 0.01 * imp["F"], velocity), fit)


def fruit_and_rebound(flight_factor=1.0, speed_factor=1.0, stiffness_factor=1.0):
    """A fruit at the line's speed and the same fruit (same m and c) coming back at e V × speed_factor after
    the flight 2 e V/g × flight_factor."""
    first = impact()
    second = impact(c=first["c"], velocity=first["e"] * V_LINE * speed_factor,
                    stiffness=STIFFNESS * stiffness_factor)
    flight = 2 * first["e"] * V_LINE / G * flight_factor
    parent = summary(first, 0.1, 0, V_LINE)
    candidate = summary(second, parent.separation + flight, 1)
    return parent, candidate, first, second


def test_the_same_fruit_at_its_exit_speed_after_its_flight_is_its_rebound():
    """The defining case: same m, K, c at e V after 2 e V/g.  The speed ratio recovered from the impulses is e
    (to the shape table's interpolation, 1e-4), every deviation is far inside its tolerance."""
    parent, candidate, first, _ = fruit_and_rebound()
    verdict = judge(candidate, [parent], max_flight=1.0)
    assert verdict.rebound and verdict.parent == 0 and not verdict.ambiguous
    assert verdict.speed_ratio == pytest.approx(first["e"], rel=1e-4)
    assert verdict.evidence["flight_predicted"] == pytest.approx(verdict.evidence["flight_observed"], rel=1e-3)
    assert verdict.evidence["peak_predicted"] == pytest.approx(candidate.peak_force, rel=1e-3)
    assert verdict.evidence["score"] < 0.05


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "flores"])
@pytest.mark.parametrize("e0", [0.45, 0.6, 0.75])
def test_the_rebound_of_a_fruit_whose_restitution_does_not_change_with_speed_is_its_rebound(law, e0):
    """With Hunt–Crossley's c a constant of the fruit, a slower impact is livelier (x = c V falls with V); with the
    laws of Lankarani–Nikravesh (1990) and Flores et al. (2011), both named by "Theoretical aspects about
    simulating the reaction to impact of apples on rigid plane surfaces", c = χ(e₀)/V and the restitution is the
    same at every speed.  Which holds for fruit is not settled, so a rebound's x may lie anywhere from r x_p to x_p
    (``pulses.DAMPING_EXPONENT``).  The same fruit (m, K, χ) at e V after 2 e V/g is its rebound, every deviation
    ~0 (it was a new fruit for e₀ ≤ 0.6 when x_r = r x_p was assumed: shape 1.06–beyond)."""
    import linegen  # the laws' c = χ(e₀)/v, as the independent generator applies them

    damping = linegen.DAMPING_LAWS[law]
    first = impact(c=damping({"e0": e0}, V_LINE))
    second = impact(c=damping({"e0": e0}, first["e"] * V_LINE), velocity=first["e"] * V_LINE)
    assert second["e"] == pytest.approx(first["e"], rel=1e-6)  # the law's defining property
    parent = summary(first, 0.1, 0, V_LINE)
    candidate = summary(second, parent.separation + 2 * first["e"] * V_LINE / G, 1)
    verdict = judge(candidate, [parent], max_flight=1.0)
    assert verdict.rebound and not verdict.ambiguous
    assert verdict.evidence["score"] < 0.05


def test_the_lines_own_damping_law_tells_a_light_soft_fruit_from_a_rebound():
    """A fruit of 0.6 the mass and 0.6 the stiffness, with about the lot's restitution, landing when the
    rebound would.  Its x is a fruit's at V (≈ x_p), inside the range r x_p … x_p an unknown damping law allows,
    and there its peak and time to peak pass for the rebound's (score 0.79): taken.  Once the line's rebounds have
    shown their law (``LineAnalyzer.damping_exponent``: here β in 0.75–1, Hunt–Crossley's c a constant of the
    fruit), the rebound's x must lie near r x_p, and this is a new fruit.  (On the lines of tests/linegen.py such
    fruit, 15 ms before the real rebound, were taken at seeds 1–8 until the range was read from the rebounds.)"""
    import dataclasses

    first = impact()
    parent = summary(first, 0.1, 0, V_LINE)
    fruit = impact(mass=0.6 * MASS, restitution=0.6, stiffness=0.6 * STIFFNESS)
    candidate = summary(fruit, parent.separation + 2 * first["e"] * V_LINE / G, 1)
    assert judge(candidate, [parent], max_flight=1.0).rebound  # the law unknown: why the line's own is read
    lot = dataclasses.replace(candidate, damping_exponent=(0.75, 1.0))
    assert not judge(lot, [parent], max_flight=1.0).rebound


@pytest.mark.parametrize("factor", [0.85, 1.15])
def test_a_flight_perturbed_by_spin_within_its_tolerance_is_still_a_rebound(factor):
    """A spinning or off-axis fruit's flight is off by ±10–20 %: within the ±25 % flight tolerance."""
    parent, candidate, _, _ = fruit_and_rebound(flight_factor=factor)
    assert judge(candidate, [parent], max_flight=1.0).rebound


@pytest.mark.parametrize("factor", [0.6, 1.6])
def test_a_contact_far_from_the_predicted_flight_is_a_new_fruit(factor):
    """The same pulse arriving 40 % early or 60 % late is not what the fruit would do: a new fruit (the flight
    test is |ln(observed/predicted)| / ln-tolerance 0.25, so 0.51 and 0.47 are 2× beyond)."""
    parent, candidate, _, _ = fruit_and_rebound(flight_factor=factor)
    verdict = judge(candidate, [parent], max_flight=1.0)
    assert not verdict.rebound


def test_without_the_impact_speed_the_flight_is_not_predicted_but_the_pulse_still_decides():
    """No drop height: the flight cannot be predicted; the pulse of the same fruit at e V still identifies it."""
    parent, candidate, _, _ = fruit_and_rebound(flight_factor=1.6)
    unknown = parent.with_velocity(None)
    verdict = judge(candidate, [unknown], max_flight=1.0)
    assert verdict.rebound and verdict.evidence["flight_predicted"] is None


def test_a_fruit_cannot_come_back_faster_than_it_left():
    """Energy: the exit speed is e V, so a 'rebound' at 1.3 e V (which would need e > its own) is a new fruit,
    though its pulse is the same fruit's at that speed and its flight is 2 (1.3 e V)/g."""
    first = impact()
    faster = impact(c=first["c"], velocity=1.3 * first["e"] * V_LINE)
    parent = summary(first, 0.1, 0, V_LINE)
    candidate = summary(faster, parent.separation + 2 * 1.3 * first["e"] * V_LINE / G, 1)
    verdict = judge(candidate, [parent], max_flight=1.0)
    assert not verdict.rebound
    assert verdict.evidence is None or verdict.evidence["deviations"]["speed_ratio"] > 1.0


def test_a_contact_faster_than_its_parent_is_no_rebound_however_uncertain_the_parents_restitution():
    """Energy bounds the speed ratio by 1 whatever e_p is: a rebound lands at most at its parent's exit speed
    e_p V_p < V_p.  A slow contact (0.45 V, itself a rebound) whose restitution is poorly measured (sd 0.3, as a
    piece of an overlap's can be) and then a new fruit of the same kind at the line's speed, landing after the
    flight of a body leaving at V: r = 2.2, and the tolerance on r/e_p, widened by e_p's sd, had let it pass
    (deviation 0.90; seen on a Flores line of tests/linegen.py at r = 1.75).  The impulse ratio needs no e: a
    rebound carries I_p r (1 + e_j)/(1 + e_p) ≤ 2 e_p/(1 + e_p) I_p < I_p, so a ratio beyond 1 by more than 3 ×
    the impulses' error rules it out."""
    import dataclasses

    slow = impact(velocity=0.45 * V_LINE)
    parent = dataclasses.replace(summary(slow, 0.1, 0, 0.45 * V_LINE), restitution_sd=0.3)
    fruit = impact(c=slow["c"])
    candidate = summary(fruit, parent.separation + 2 * V_LINE / G, 1)
    assert not judge(candidate, [parent], max_flight=1.0).rebound


def test_a_smaller_fruit_arriving_when_the_rebound_would_is_a_new_fruit():
    """The old rule's failure ("smaller and soon"): a fruit of 0.6 the mass at the line's speed, landing exactly
    when the rebound would.  Its impulse gives r ≈ 0.6 ≈ e, but the same fruit at 0.6 V would peak at
    0.6^1.2 F and take 0.6^-0.2 t_c; this one peaks at 0.6^0.6 F (F ∝ m^0.6) in 0.6^0.4 t_c (t_c ∝ m^0.4):
    27 % and 24 % off, against tolerances of ~12 %."""
    first = impact()
    small = impact(mass=0.6 * MASS, c=first["c"])
    parent = summary(first, 0.1, 0, V_LINE)
    candidate = summary(small, parent.separation + 2 * first["e"] * V_LINE / G, 1)
    verdict = judge(candidate, [parent], max_flight=1.0)
    assert small["F"] < first["F"] and not verdict.rebound


def test_a_rebound_landing_on_a_stiffer_spot_is_still_a_rebound():
    """The rebound lands on another spot of the fruit: local K ±5 % moves F_max and t_c by ±2 % (K^±0.4),
    inside the 4 % spot allowance."""
    parent, candidate, _, _ = fruit_and_rebound(stiffness_factor=1.05)
    assert judge(candidate, [parent], max_flight=1.0).rebound


def test_the_rebound_of_an_earlier_fruit_landing_after_the_next_fruit_finds_its_own_parent():
    """On a fast feed the next fruit lands before the previous one's rebound: the parent is the earlier fruit
    whose physics the rebound matches, not the contact just before it."""
    parent, candidate, first, _ = fruit_and_rebound()
    other = impact(mass=0.8 * MASS, restitution=0.5)
    between = summary(other, (parent.onset + candidate.onset) / 2, 1, V_LINE)
    candidate = summary(impact(c=first["c"], velocity=first["e"] * V_LINE), candidate.onset, 2)
    verdict = judge(candidate, [parent, between], max_flight=1.0)
    assert verdict.rebound and verdict.parent == 0


def test_a_contact_rebounds_once():
    """A contact that already has its rebound cannot have a second one: the second candidate is a new fruit
    (or the rebound's rebound, which has the first rebound as parent)."""
    parent, candidate, _, _ = fruit_and_rebound()
    verdict = judge(candidate, [parent.taken()], max_flight=1.0)
    assert not verdict.rebound


def test_the_feed_prior_moves_the_threshold_and_near_decisions_carry_their_evidence():
    """A borderline case (the flight 32 % long: score 1.1 on the flight test alone) is a new fruit but
    ambiguous, with the evidence; on the feed's pitch grid it is a clear new fruit (threshold 0.8), off the grid
    a rebound (threshold 1.25)."""
    parent, candidate, _, _ = fruit_and_rebound(flight_factor=1.32)
    plain = judge(candidate, [parent], max_flight=1.0)
    assert not plain.rebound and plain.ambiguous
    for key in ("flight_observed", "flight_predicted", "peak_observed", "peak_predicted", "speed_ratio", "score"):
        assert key in plain.evidence
    on_grid = judge(candidate, [parent], max_flight=1.0, last_fruit_onset=candidate.onset - 0.1, pitch=0.1)
    assert not on_grid.rebound and not on_grid.ambiguous
    off_grid = judge(candidate, [parent], max_flight=1.0, last_fruit_onset=candidate.onset - 0.05, pitch=0.1)
    assert off_grid.rebound and off_grid.ambiguous
    assert TOLERANCES["flight"] == 0.25


# ---------------------------------------------------------------------------------------------------------------
# Item 2: fruit that land close together or together


def _signal(onsets, impacts, n, seed=3):
    x = np.zeros(n)
    t = np.arange(n) / RATE
    for onset, imp in zip(onsets, impacts):
        inside = (t > onset) & (t < onset + imp["T"])
        x[inside] += powerlaw_curves(imp["m"], imp["K"], imp["c"], imp["V"], t[inside] - onset)[2]
    return x + np.random.default_rng(seed).normal(0, 0.01 * impacts[0]["F"], n)


def _reports(x, **analysis):
    analyzer = Analysis(RATE, fit=True, velocity=V_LINE, **analysis).analyzer()
    return [report for i in detect(x, RATE) for report in analyzer.reports(i)]


def test_fruit_a_few_ms_apart_are_two_contacts_each_measured_on_its_own_samples():
    """A second, larger fruit 3 ms after the first contact ends: two reports, both ok, neither a rebound, each
    peak within 1 % and each fitted stiffness within 3 % of its own fruit (the second's rise is cut from the
    first's window and the first's tail from the second's)."""
    a = impact()
    b = impact(mass=1.2 * MASS, restitution=0.5)
    x = _signal([0.1, 0.1 + a["T"] + 0.003], [a, b], 6000)
    first, second = _reports(x)
    for report, imp in ((first, a), (second, b)):
        assert report["status"] == "ok" and not report["rebound"], report["message"]
        assert report["peak_force"] == pytest.approx(imp["F"], rel=0.01)
        assert report["stiffness"] == pytest.approx(imp["K"], rel=0.03)


@pytest.mark.parametrize("later,mass", [(0.6, 0.9), (0.8, 1.2), (0.35, 0.5)])
def test_a_fruit_landing_during_another_contact_is_told_apart_by_a_joint_fit(later, mass):
    """A second fruit landing after the first one's peak (35–80 % into its contact): the force falls and rises
    again, and forces on one plate add, so the contact is the sum of two Hunt–Crossley pulses.  Fitted jointly
    (signals/split.py), each fruit gets its own report, onset within 0.1 ms, peak within 2 % and stiffness
    within 3 % of its own (8 % for the small one landing early, whose rise shares the first's peak: its
    parameters correlate with the first's), never one fruit fitted through both."""
    a = impact()
    b = impact(mass=mass * MASS, restitution=0.5)
    onsets = [0.1, 0.1 + later * a["T"]]
    first, second = _reports(_signal(onsets, [a, b], 6000))
    for report, imp, onset in ((first, a, onsets[0]), (second, b, onsets[1])):
        assert report["status"] == "ok" and "two fruit in one contact" in report["message"]
        assert not report["rebound"]
        assert report["start_time"] == pytest.approx(onset, abs=1e-4)
        assert report["peak_force"] == pytest.approx(imp["F"], rel=0.02)
        assert report["stiffness"] == pytest.approx(imp["K"], rel=0.08 if mass < 0.6 else 0.03)
    assert second["sequence"] == first["sequence"] + 1


def test_an_overlap_that_cannot_be_told_apart_has_no_firmness():
    """Three fruit in one contact (the two-pulse fit cannot account for it): one report, status "overlap", no
    firmness, no fit, no class, the contact as detected."""
    from fruitimpact.signals.sort import FirmnessClasses

    a = impact()
    b = impact(mass=0.9 * MASS)
    c = impact(mass=0.8 * MASS)
    x = _signal([0.1, 0.1 + 0.55 * a["T"], 0.1 + 1.1 * a["T"]], [a, b, c], 6000)
    classes = FirmnessClasses("stiffness", (STIFFNESS,), ("soft", "firm"))
    (report,) = _reports(x, classes=classes)
    assert report["status"] == "overlap" and "two pulses" in report["message"]
    assert math.isnan(report["firmness_c"]) and math.isnan(report["firmness_c_star"])
    assert report["class"] is None and "stiffness" not in report
    assert report["contact_duration"] > 1.5 * a["T"]  # the contact as detected: all pulses


@pytest.mark.parametrize("seed", range(4))
def test_two_fruit_landing_together_are_told_apart_though_no_dip_shows(seed):
    """Two fruit touching 3 ms apart (about 1.5 times to peak, 2.0 ms) make one unimodal pulse (no dip: the second
    lands on the first's rise), but no single fruit's force law fits it (it misses by several % of the peak
    beyond the noise, above analysis.MISFIT_LIMIT's 1.8 %), and the joint fit started from the grid of pulse
    pairs (signals/split.py) tells them apart: two reports, each onset within 0.1 ms of its fruit's, peaks
    within 2 % (a piece is kept only when the joint fit fixes its peak to ±1 %, analysis.PIECE_PRECISION: 2 sd;
    4 seeds gave ≤ 0.65 %), stiffness within 8 % (it also rests on the tail, which lies under the other pulse)."""
    a = impact()
    b = impact(mass=0.7 * MASS)
    gap = 3.0e-3
    first, second = _reports(_signal([0.1, 0.1 + gap], [a, b], 6000, seed=seed))
    for report, imp, onset in ((first, a, 0.1), (second, b, 0.1 + gap)):
        assert report["status"] == "ok" and "two fruit in one contact" in report["message"]
        assert report["start_time"] == pytest.approx(onset, abs=1e-4)
        assert report["peak_force"] == pytest.approx(imp["F"], rel=0.02)
        assert report["stiffness"] == pytest.approx(imp["K"], rel=0.08)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("gap", [1.5e-3, 2.0e-3])
def test_two_fruit_whose_pulses_the_samples_cannot_separate_are_one_overlap(gap, seed):
    """Two fruit 1.5–2 ms apart: two pulses fit, but the samples fix the second one's peak only to ±2–6 % (the
    joint fit's standard error; at 3 % allowed, errors of 1–7 % were seen), above analysis.PIECE_PRECISION's
    1 %: one report with status "overlap", no firmness, no class: never two grades the data do not support,
    never one fruit fitted through both."""
    a = impact()
    b = impact(mass=0.7 * MASS)
    (report,) = _reports(_signal([0.1, 0.1 + gap], [a, b], 6000, seed=seed))
    assert report["status"] == "overlap" and "could not be told apart" in report["message"]
    assert math.isnan(report["firmness_c"]) and "stiffness" not in report or report.get("stiffness") is None


def test_two_fruit_on_a_noise_free_signal_are_never_one_fruit():
    """A clean signal (a simulation, or a sensor whose noise is below its resolution: the detector's σ decays to 0)
    of two fruit 1.5 ms apart: one unimodal pulse that the force law misses by 2.7 % of its peak.  With no noise
    that misfit has no scatter, so it always counts (``onepulse.MISFIT_SD`` weighs a misfit against the noise's
    χ² scatter; a review found the test switched off at σ = 0, and the two fruit graded as one).  Never one fruit
    fitted through both: an overlap, or two pieces."""
    a = impact()
    b = impact(mass=0.7 * MASS)
    t = np.arange(6000) / RATE
    x = np.zeros(t.size)
    for onset, imp in ((0.1, a), (0.1015, b)):
        inside = (t > onset) & (t < onset + imp["T"])
        x[inside] += powerlaw_curves(imp["m"], imp["K"], imp["c"], imp["V"], t[inside] - onset)[2]
    reports = _reports(x)
    assert not (len(reports) == 1 and reports[0]["status"] == "ok"), reports[0]["message"]
    assert all(r["status"] == "overlap" or "fruit in one contact" in r["message"] for r in reports)


def _fruit_then_rebound_with_the_next(gap, next_mass, seed=5):
    """A fruit at 0.1 s, its rebound (the same m, K, c at e V) after the flight 2 e V/g, and the next fruit
    ``gap`` [s] before that rebound (negative: after it)."""
    a = impact()
    rebound = impact(velocity=a["e"] * V_LINE, c=a["c"])
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    b = impact(mass=next_mass * MASS, restitution=0.5)
    return a, rebound, b, landing, _signal([0.1, landing - gap, landing], [a, b, rebound], 10000, seed=seed)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("gap", [0.0, 2e-4])
def test_a_rebound_ended_by_the_next_fruits_landing_is_measured_and_stays_a_rebound(gap, seed):
    """The next fruit lands as the rebound's contact ends (0–0.2 ms after): the rebound's window stops where that
    fruit rises, before its own tail below the detector's offset (3 noise sd: its last ~10 % here).  The fit
    extrapolates the tail by the force law (``fit_impact(open_end=True)``; tests/test_signals_fit.py) instead of
    refusing it: the rebound is measured (peak within 1 %, e within 0.03: the fit's tolerances at 1 % noise) and
    judged on it, the rebound of the first fruit; the next fruit is a fruit.  Without the extrapolation the
    rebound was "unfitted" and, unrefined, could not be judged against a fruit hidden in an overlap."""
    a = impact()
    rebound = impact(velocity=a["e"] * V_LINE, c=a["c"])
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    b = impact(mass=1.1 * MASS, restitution=0.5)
    x = _signal([0.1, landing, landing + rebound["T"] + gap], [a, rebound, b], 10000, seed=seed)
    first, back, new = _reports(x)
    assert back["status"] == "ok" and back["fit_converged"], back["message"]
    assert back["rebound"] and back["rebound_of"] == first["sequence"]
    assert "not sampled" in back["fit_message"]
    assert back["peak_force"] == pytest.approx(rebound["F"], rel=0.01)
    assert back["restitution"] == pytest.approx(rebound["e"], abs=0.03)
    assert new["status"] == "ok" and not new["rebound"]
    assert new["stiffness"] == pytest.approx(b["K"], rel=0.03)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("gap", [2.0e-3, -3.0e-3])
def test_a_rebound_and_the_next_fruit_landing_together_are_told_apart(gap, seed):
    """The previous fruit's rebound is due (its flight 2 e V/g from its own measured e and the line's V) and the
    next fruit lands 2–3 ms from it: one smooth pulse that one force law fits within the misfit limit, but two
    pulses fit it far better (rebounds.rebounds_due, onepulse.SPLIT_GAIN), so it is split: the rebound is the
    first fruit's (rebound_of), the next fruit a new one, graded from its own piece.  Tolerances from 20 seeds
    per gap (max seen in brackets): onsets 0.2 ms, the new fruit's peak 2 % (1.2 %: its piece is fixed to ±1 %,
    analysis.PIECE_PRECISION) and stiffness 10 % (8.5 %).  The rebound landing 2 ms after the next fruit, on its
    peak, is fixed only to ±1.5–3 %: it keeps its parent but is an "overlap" without firmness or fit (its
    amplitude traded off against the fruit's); 3 ms before it, it is measured, peak within 2 % (0.7 %)."""
    a, rebound, b, landing, x = _fruit_then_rebound_with_the_next(gap, 1.1, seed=seed)
    first, *rest = _reports(x)
    assert first["status"] == "ok" and not first["rebound"]
    assert len(rest) == 2
    (back,) = [r for r in rest if r["rebound"]]
    (new,) = [r for r in rest if not r["rebound"]]
    assert back["rebound_of"] == first["sequence"]
    assert back["start_time"] == pytest.approx(landing, abs=2e-4)
    assert new["status"] == "ok" and "two fruit in one contact" in new["message"]
    assert new["start_time"] == pytest.approx(landing - gap, abs=2e-4)
    assert new["peak_force"] == pytest.approx(b["F"], rel=0.02)
    assert new["stiffness"] == pytest.approx(b["K"], rel=0.10)
    if gap > 0:
        assert back["status"] == "overlap" and "determined to" in back["message"]
        assert math.isnan(back["firmness_c"]) and math.isnan(back["stiffness"])
    else:
        assert back["status"] == "ok" and back["peak_force"] == pytest.approx(rebound["F"], rel=0.02)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("gap", [1.2e-3, -1.0e-3])
def test_a_rebound_and_the_next_fruit_landing_within_a_millisecond_are_one_overlap(gap, seed):
    """The same 1–1.2 ms apart: two pulses fit far better than one, but the joint fit fixes the new fruit's peak
    only to a few % (at 3 % allowed, its peak was off by up to 6 % and its stiffness by 8 %): one "overlap" report,
    no firmness, no class (analysis.PIECE_PRECISION)."""
    *_, x = _fruit_then_rebound_with_the_next(gap, 1.1, seed=seed)
    first, *rest = _reports(x)
    assert first["status"] == "ok" and not first["rebound"]
    (overlap,) = rest
    assert overlap["status"] == "overlap" and "could not be told apart" in overlap["message"]
    assert math.isnan(overlap["firmness_c"]) and overlap.get("stiffness") is None


def test_a_fruit_alone_where_a_rebound_is_due_stays_one_fruit():
    """A fruit landing alone where the previous fruit's rebound is due (a pad caught that rebound): its single
    fit leaves only the noise, so no joint fit is even tried (onepulse.may_split), and it is one new fruit,
    peak within 1 % and stiffness within 3 % (the single-pulse precision of tests/test_signals_fit.py)."""
    a = impact()
    b = impact(mass=1.1 * MASS, restitution=0.5)
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    first, second = _reports(_signal([0.1, landing], [a, b], 10000))
    assert second["status"] == "ok" and second["message"] == "" and not second["rebound"]
    assert second["peak_force"] == pytest.approx(b["F"], rel=0.01)
    assert second["stiffness"] == pytest.approx(b["K"], rel=0.03)


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_a_fruit_and_two_rebounds_landing_together_are_never_graded_from_unfixed_pieces(seed):
    """Two fruit whose rebounds are both due where a third fruit lands: the new fruit, the first's rebound 1.2 ms
    later and the second's 3.5 ms later make one contact.  Split in two (the first's rebound apart), the rest
    tried again as two (analysis._split_further); three overlapping rises share their amplitudes, and no piece's
    peak is fixed to ±1 % (analysis.PIECE_PRECISION; at 3 % allowed, 11 of 20 seeds gave three contacts with
    peaks up to 11 % off): every report is an overlap without firmness, and the rebound piece keeps its parent."""
    a, b = impact(), impact(mass=0.9 * MASS, restitution=0.5)
    back_a = impact(velocity=a["e"] * V_LINE, c=a["c"])
    back_b = impact(mass=0.9 * MASS, velocity=b["e"] * V_LINE, c=b["c"])
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    onset_b = landing + 0.0035 - b["T"] - 2 * b["e"] * V_LINE / G  # b's rebound lands 3.5 ms after a's
    c = impact(mass=1.1 * MASS, restitution=0.55)
    onsets = [landing - 0.0012, landing, landing + 0.0035]
    x = _signal([0.1, onset_b, *onsets], [a, b, c, back_a, back_b], 12000, seed=seed)
    first, second, *rest = _reports(x)
    assert rest and all(r["status"] == "overlap" and math.isnan(r["firmness_c"]) for r in rest), rest
    assert {r["rebound_of"] for r in rest if r["rebound"]} <= {first["sequence"], second["sequence"]}


@pytest.mark.parametrize("seed", range(20))
def test_a_fruit_and_two_rebounds_never_make_one_fruit_fitted_through_two(seed):
    """The same contact over 20 seeds (11 of them give the three contacts above): whatever the split, every report
    that is not an overlap is one pulse: its impulse (∫F dt = m (1 + e) V, what a pulse carries whatever its
    shape) within 35 % of one of the three, where a fruit fitted through itself and a rebound carries both (58 %
    more than the fruit) and the pieces seen are within 25 % (a rebound piece is drawn toward the expected
    rebound within that expectation's spread); a piece in which two pulses stay together is an "overlap"
    without firmness (analysis._split_further)."""
    a, b = impact(), impact(mass=0.9 * MASS, restitution=0.5)
    back_a = impact(velocity=a["e"] * V_LINE, c=a["c"])
    back_b = impact(mass=0.9 * MASS, velocity=b["e"] * V_LINE, c=b["c"])
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    onset_b = landing + 0.0035 - b["T"] - 2 * b["e"] * V_LINE / G
    c = impact(mass=1.1 * MASS, restitution=0.55)
    x = _signal([0.1, onset_b, landing - 0.0012, landing, landing + 0.0035], [a, b, c, back_a, back_b], 12000,
                seed=seed)
    _, _, *rest = _reports(x)
    assert rest
    for report in rest:
        if report["status"] == "overlap":
            assert math.isnan(report["firmness_c"]) and report.get("class") is None
        else:
            assert min(abs(report["impulse"] / imp["impulse"] - 1) for imp in (c, back_a, back_b)) < 0.35, report


def _lane_fruit(count=8, seed=11):
    """Summaries of a lane's measured fruit: masses ±15 %, restitution 0.52–0.62 at the line's speed (the exact
    engine's characteristics, refined as a shape fit would)."""
    rng = np.random.default_rng(seed)
    fruit = []
    for k in range(count):
        imp = impact(mass=MASS * rng.uniform(0.85, 1.15), restitution=rng.uniform(0.52, 0.62))
        fruit.append(summary(imp, 0.1 * k, k, velocity=V_LINE))
    return fruit


def test_the_rebound_of_a_fruit_hidden_in_an_overlap_is_judged_against_the_lanes_fruit():
    """A fruit hidden in an overlap (no pulse of its own) lands at the line's speed and is one of the lane's:
    its rebound (the same fruit at e V, after 2 e V/g) is a rebound of the overlap, while a new fruit landing
    at the same moment (impulse m V (1 + e), restitution the lane's) is a new fruit, and so is a contact that
    would be a rebound but comes at twice the flight, or a lively light fruit whose pulse at the rebound's speed
    would need a fruit far stiffer than the lot (rebounds.judge_unmeasured)."""
    from fruitimpact.signals.rebounds import judge_unmeasured

    fruit = _lane_fruit()
    hidden = impact(restitution=0.57)
    back = impact(velocity=hidden["e"] * V_LINE, c=hidden["c"])
    left = 1.0 + hidden["T"]
    flight = 2 * 0.95 * hidden["e"] * V_LINE / G  # a little spin
    verdict = judge_unmeasured(summary(back, left + flight, 99), 42, 1.0, fruit, V_LINE)
    assert verdict.rebound and verdict.parent == 42, verdict.evidence
    assert verdict.evidence["rebound_distance"] < verdict.evidence["new_fruit_distance"]
    new = judge_unmeasured(summary(impact(mass=0.95 * MASS, restitution=0.58), left + flight, 99), 42, 1.0, fruit,
                           V_LINE)
    assert not new.rebound, new.evidence
    # a light, lively new fruit landing when the rebound is due (mass 0.77 of the lane's, e 0.66): its impulse and
    # restitution are a rebound's, but read at the rebound's speed r V its pulse needs a fruit r^-1.5 ≈ 2.4 times
    # stiffer than the lot (K ∝ V^-1.5 for one pulse): a new fruit, not even ambiguous
    from fruitimpact.signals.rebounds.lane import EXPECTED_RATIO, LOT_STIFFNESS_SD, _log_stiffness

    lively_pulse = summary(impact(mass=0.77 * MASS, restitution=0.66), left + flight, 99)
    lively = judge_unmeasured(lively_pulse, 42, 1.0, fruit, V_LINE)
    assert not lively.rebound and not lively.ambiguous
    r = EXPECTED_RATIO * np.median([f.restitution for f in fruit])
    lane_k = np.median([_log_stiffness(f, V_LINE)[0] for f in fruit])
    assert _log_stiffness(lively_pulse, r * V_LINE)[0] - lane_k > 5 * LOT_STIFFNESS_SD
    assert abs(_log_stiffness(lively_pulse, V_LINE)[0] - math.log(STIFFNESS)) < 0.03  # read at its own speed: K
    late = judge_unmeasured(summary(back, left + 2 * flight, 99), 42, 1.0, fruit, V_LINE)
    assert not late.rebound, late.evidence


def test_an_overlap_carrying_two_fruit_keeps_a_slot_for_each():
    """Impulse is conserved through a contact: an overlap that could not be split carries the sum of its pulses'
    impulses, each fruit m (1 + e) V of the lane's.  One carrying two fruit's impulse beyond the rebound due in it,
    over more than 1.5 fruit contacts, hides a second fruit, which landed last: it ended with the overlap, so it
    landed one fruit contact before the overlap's end.  One fruit and a rebound (1.6 fruit's impulse), or one
    fruit's impulse over a long contact, hide one (analysis.LineAnalyzer._second_hidden_fruit)."""
    import dataclasses

    from fruitimpact.signals.analysis import TWO_FRUIT_DURATION, TWO_FRUIT_IMPULSE
    from fruitimpact.signals.rebounds import hidden_rebound, median_of

    analyzer = Analysis(RATE, fit=True, velocity=V_LINE).analyzer()
    fruit = _lane_fruit(8)
    analyzer._fruit = {0: fruit}
    impulse = median_of([f.impulse for f in fruit])
    duration = median_of([f.separation - f.onset for f in fruit])
    two = {"start_time": 2.0, "impulse": 2.0 * impulse, "contact_duration": 2.4 * duration}
    assert analyzer._second_hidden_fruit(0, two, []) == pytest.approx(2.0 + 1.4 * duration)
    fruit_and_rebound = {**two, "impulse": 1.6 * impulse}
    assert analyzer._second_hidden_fruit(0, fruit_and_rebound, []) is None
    assert 1.6 < TWO_FRUIT_IMPULSE < 2.0 and TWO_FRUIT_DURATION <= 2.4
    close = {**two, "contact_duration": 1.2 * duration}  # two fruit landing together: one pulse, one slot
    assert analyzer._second_hidden_fruit(0, close, []) is None
    # a rebound due in it is taken out first: a fruit, its neighbour's rebound and another fruit's 0.3 of impulse
    parent = fruit[3]
    rebound = hidden_rebound(parent, -1, 2.0).impulse
    due_parent = dataclasses.replace(parent, onset=2.0 - 0.2, separation=2.0 - 0.2 + duration)
    held = {**two, "impulse": 1.3 * impulse + rebound}
    assert analyzer._second_hidden_fruit(0, held, [due_parent]) is None
    assert analyzer._second_hidden_fruit(0, {**held, "impulse": 2.0 * impulse + rebound}, [due_parent]) is not None


def test_a_lane_with_few_measured_fruit_is_judged_by_the_fruit_of_every_lane():
    """One lot on one line at the one speed the analysis is given: until a lane has measured LANE_FRUIT_MIN fruit
    of its own (a lane just started, or one whose first fruit were hidden in overlaps), the fruit a hidden fruit
    is judged against are those of every lane; from then on, its own."""
    from fruitimpact.signals.rebounds import LANE_FRUIT_MIN

    analyzer = Analysis(RATE, fit=True, velocity=V_LINE).analyzer()
    analyzer._fruit = {0: _lane_fruit(8), 1: _lane_fruit(LANE_FRUIT_MIN - 1, seed=12)}
    assert len(analyzer._lane_fruit(1)) == 8 + LANE_FRUIT_MIN - 1
    assert analyzer._lane_fruit(0) == analyzer._fruit[0]
    analyzer._fruit[1] = _lane_fruit(LANE_FRUIT_MIN, seed=12)
    assert analyzer._lane_fruit(1) == analyzer._fruit[1]
    analyzer._fruit = {0: _lane_fruit(8)}  # lane 1 has measured none yet (its first fruit hidden in overlaps)
    assert analyzer._lane_fruit(1) == analyzer._fruit[0]
    single = Analysis(RATE, fit=True, velocity=V_LINE).analyzer()
    single._fruit = {0: _lane_fruit(2)}
    assert single._lane_fruit(0) == single._fruit[0]  # a line of one lane has only its own


def test_the_bounce_of_a_rebound_hidden_in_an_overlap_is_a_rebound_of_the_overlap():
    """A fruit's rebound lands together with the next fruit (one overlap, no pulse of its own): the fruit's next
    bounce (the same m, K, c at e₂ e₁ V after the flight 2 e₂ e₁ V/g from the overlap) is a rebound of that
    overlap (rebounds.hidden_rebound), not a new fruit; a new fruit at the line's speed landing at the same
    moment is a new fruit; and the bounce is not mistaken for the rebound of the fruit hidden beside it, whose
    flight is about 1/e₁ times longer (rebounds.judge_unmeasured scores it farther).  Margins: the prediction's
    own spread (r = 0.92 e ± 10 %, the spot), as for a measured parent."""
    from fruitimpact.signals.rebounds import hidden_rebound, judge_unmeasured, likeliest_hidden

    first = impact()
    parent = summary(first, 0.1, 0, V_LINE)
    early = summary(impact(), 0.0, 5, V_LINE)  # due too (rebounds_due is wide), but predicted 0.1 s off
    landing0 = parent.separation + 2 * 0.92 * first["e"] * V_LINE / G
    assert likeliest_hidden([early, parent], landing0) is parent  # one hidden rebound per overlap: the best timed
    landing = parent.separation + 2 * 0.95 * first["e"] * V_LINE / G  # its rebound lands, a little spin
    virtual = hidden_rebound(parent, 7, landing)
    assert virtual.velocity == pytest.approx(0.92 * first["e"] * V_LINE) and virtual.refined
    speed = 0.95 * first["e"] * V_LINE  # the rebound's real speed
    rebound = impact(c=first["c"], velocity=speed)
    bounce = impact(c=first["c"], velocity=0.95 * rebound["e"] * speed)
    when = landing + rebound["T"] + 2 * 0.95 * rebound["e"] * speed / G
    verdict = judge(summary(bounce, when, 8), [parent.taken(), virtual], max_flight=1.0)
    assert verdict.rebound and verdict.parent == 7, verdict.evidence
    new = judge(summary(impact(mass=0.95 * MASS, restitution=0.58), when, 8), [parent.taken(), virtual],
                max_flight=1.0)
    assert not new.rebound, new.evidence
    beside = judge_unmeasured(summary(bounce, when, 8), 7, landing, _lane_fruit(), V_LINE)
    assert beside.evidence["score"] > verdict.evidence["score"], (beside.evidence, verdict.evidence)


def test_without_the_lanes_fruit_or_speed_a_hidden_fruits_rebound_is_not_guessed():
    """No measured fruit, or no line speed: nothing stands for the hidden fruit, so no decision.  One measured
    fruit is enough (HIDDEN_FRUIT_MIN), its spreads a lot's: the hidden fruit's rebound, landing after
    2 · 0.95 e V/g (a little spin), is found from a recording's first fruit."""
    from fruitimpact.signals.rebounds import HIDDEN_FRUIT_MIN, NEW_FRUIT, judge_unmeasured

    hidden = impact()
    speed = 0.95 * hidden["e"] * V_LINE
    back = summary(impact(velocity=speed, c=hidden["c"]), 1.0 + hidden["T"] + 2 * speed / G, 99)
    assert judge_unmeasured(back, 42, 1.0, _lane_fruit(HIDDEN_FRUIT_MIN - 1), V_LINE) is NEW_FRUIT
    assert judge_unmeasured(back, 42, 1.0, _lane_fruit(), None) is NEW_FRUIT
    first = judge_unmeasured(back, 42, 1.0, _lane_fruit(HIDDEN_FRUIT_MIN), V_LINE)
    assert first.rebound and first.parent == 42, first.evidence
    new = judge_unmeasured(summary(impact(mass=0.95 * MASS, restitution=0.58), back.onset, 99), 42, 1.0,
                           _lane_fruit(HIDDEN_FRUIT_MIN), V_LINE)
    assert not new.rebound, new.evidence


def test_one_fruit_alone_is_never_an_overlap():
    """The same fruit alone at 1 % noise, 20 seeds: status ok every time (its residual is the noise)."""
    a = impact()
    for seed in range(20):
        (report,) = _reports(_signal([0.1], [a], 4000, seed=seed))
        assert report["status"] == "ok", report["message"]


@pytest.mark.parametrize("seed", range(4))
def test_the_rebound_of_a_fruit_hidden_in_an_overlap_reports_its_pulse_without_mass_or_stiffness(seed):
    """Six measured fruit, then two fruit 1.5 ms apart (one overlap: the second's peak is fixed only to ±6 %), then
    the first hidden fruit's rebound alone: a rebound of the overlap (rebounds.judge_unmeasured).  Its impact
    speed was never measured, so the fit cannot split m from K (only the pulse's shape and c V are fixed): mass
    and stiffness are null and the message says why, but it is a fitted pulse, status ok, whose peak force and
    time to peak are within 1 % and 2 % of the exact engine's (the single-pulse precision of
    tests/test_signals_fit.py) and whose restitution is within 0.03 (the issue's goal)."""
    rng = np.random.default_rng(4)
    fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(6)]
    hidden, beside = impact(restitution=0.57), impact(mass=0.7 * MASS)
    back = impact(velocity=hidden["e"] * V_LINE, c=hidden["c"])
    landing = 0.8 + hidden["T"] + 2 * hidden["e"] * V_LINE / G
    x = _signal([0.1 + 0.1 * k for k in range(6)] + [0.8, 0.8015, landing], [*fruit, hidden, beside, back],
                int(1.1 * RATE), seed=seed)
    *_, overlap, rebound = _reports(x)
    assert overlap["status"] == "overlap"
    assert rebound["rebound"] and rebound["rebound_of"] == overlap["sequence"]
    assert rebound["status"] == "ok" and "not split" in rebound["message"]
    assert math.isnan(rebound["mass"]) and math.isnan(rebound["stiffness"])
    assert rebound["peak_force"] == pytest.approx(back["F"], rel=0.01)
    assert rebound["time_to_peak"] == pytest.approx(back["tc"], rel=0.02)
    assert rebound["restitution"] == pytest.approx(back["e"], abs=0.03)


def _lane_then_fruit_with_rebound(seed, next_mass=1.0, with_rebound=True, gap=5e-5):
    """Six measured fruit of a lot (masses ±10 %), a seventh whose rebound is due 2 e V/g after it leaves, and a
    new fruit landing ``gap`` [s] before that rebound (or alone, ``with_rebound=False``: a pad caught it)."""
    rng = np.random.default_rng(seed)
    fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(7)]
    last = fruit[-1]
    back = impact(mass=last["m"], velocity=last["e"] * V_LINE, c=last["c"])
    landing = 0.7 + last["T"] + 2 * last["e"] * V_LINE / G
    new = impact(mass=next_mass * MASS, restitution=0.57)
    onsets, impacts = [0.1 + 0.1 * k for k in range(7)] + [landing - gap], [*fruit, new]
    if with_rebound:
        onsets, impacts = onsets + [landing], impacts + [back]
    x = _signal(onsets, impacts, int(0.95 * RATE), seed=seed)
    # noise of a line (2.2 % of the peak in all): it hides the misfit of the summed pulse, as hum and ringing did
    return new, x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * fruit[0]["F"], x.size)


@pytest.mark.parametrize("seed", range(4))
def test_a_fruit_and_a_rebound_landing_within_a_tenth_of_a_millisecond_are_an_overlap(seed):
    """A new fruit and the previous fruit's rebound landing 0.05 ms apart add up to one pulse that one force law
    fits to the noise of a line (2.2 % of the peak here; at 1 % the joint fit still finds two pulses, which it
    cannot part: an overlap too); fitted as one fruit it has about the summed mass and
    stiffness, a wrong grade (seen on tests/linegen.py's chain10: stiffness 56 % off, status ok).  Its impulse
    betrays it: ~1.6 times the lane's fruit, beyond 3 sd of a lot (mass spread at least 15 %,
    rebounds.LOT_IMPULSE_SD) and near a fruit and that rebound together (rebounds.landed_with_rebound): one
    overlap, no firmness, with the evidence.  The same fruit alone (its rebound caught by a pad), or a fruit 1.3
    times the lot's mass where the rebound was due, is one fruit: measured, not flagged."""
    new, x = _lane_then_fruit_with_rebound(seed)
    report = _reports(x)[-1]
    assert report["status"] == "overlap" and "a fruit and a rebound landing together" in report["message"]
    assert math.isnan(report["firmness_c"]) and report.get("stiffness") is None
    assert report["rebound_evidence"]["landed_with_rebound_of"] == 6
    for alone in (_lane_then_fruit_with_rebound(seed, with_rebound=False)[1],
                  _lane_then_fruit_with_rebound(seed, next_mass=1.3, with_rebound=False)[1]):
        report = _reports(alone)[-1]
        assert report["status"] == "ok" and not report["rebound"], report["message"]
        assert not math.isnan(report["firmness_c"])
        assert not report["rebound_ambiguous"], report["rebound_evidence"]  # 1.3 times: 1.75 sd, not flagged


@pytest.mark.parametrize("seed", range(3))
def test_a_fruit_that_may_carry_a_due_rebound_is_graded_and_flagged(seed):
    """A light fruit (0.85 of the lot's mass) and the previous fruit's rebound landing 0.05 ms apart carry
    ~1.45 times a fruit's impulse (impulse is conserved through a contact; a rebound at r ≈ e carries
    e (1 + e_r)/(1 + e) ≈ 0.6 of its fruit's): 2.5 sd above a lot whose mass spreads 15 %
    (rebounds.LOT_IMPULSE_SD), nearer a fruit and that rebound together than a fruit alone, but not beyond the
    3 sd that would make it an overlap.  A fruit of 1.45 times the lot's mass landing alone where the rebound is due
    carries the same impulse, so the pulse cannot tell them apart: it is graded as the fruit it may be and flagged
    (``rebound_ambiguous``, the evidence with ``ambiguous``: rebounds.LANDED_AMBIGUOUS_Z), never silently.  A
    fruit 1.3 times the lot's mass (1.75 sd) is not flagged (the test above).  (With the rebound, a joint fit may
    also find two pulses it cannot part: an overlap, no firmness, as honest.)"""
    for with_rebound, mass in ((True, 0.85), (False, 1.45)):
        report = _reports(_lane_then_fruit_with_rebound(seed, next_mass=mass, with_rebound=with_rebound)[1])[-1]
        if with_rebound and report["status"] == "overlap" and "could not be told apart" in report["message"]:
            assert math.isnan(report["firmness_c"])
            continue
        assert report["status"] == "ok" and not report["rebound"], report["message"]
        assert not math.isnan(report["firmness_c"])
        evidence = report["rebound_evidence"]
        assert report["rebound_ambiguous"] and evidence["ambiguous"], evidence
        assert evidence["landed_with_rebound_of"] == 6 and 2.0 < evidence["fruit_distance"] <= 3.0, evidence
        assert evidence["together_distance"] < evidence["fruit_distance"]
        assert "perhaps a fruit and a rebound landing together" in report["message"]


@pytest.mark.parametrize("seed", [0, 2])
def test_a_weak_rebound_whose_falling_edge_is_lost_in_the_noise_is_judged_on_its_fit(seed):
    """A rebound ~11 noise sd high (noise 8 % of its peak): its falling edge from 30 % of the peak down lies within
    3 sd of the noise, so the samples give no end and no impulse (indices.py: NaN), while the shape fit, which
    uses every sample, converges.  The rebound test then reads the fitted pulse: a rebound of its fruit, not a new
    fruit (on tests/linegen.py's grades scenario such a rebound of 18 N had been taken for a fruit)."""
    a = impact()
    back = impact(velocity=a["e"] * V_LINE, c=a["c"])
    landing = 0.1 + a["T"] + 2 * a["e"] * V_LINE / G
    x = _signal([0.1, landing], [a, back], int(0.3 * RATE), seed=seed)
    x = x + np.random.default_rng(50 + seed).normal(0.0, 0.08 * back["F"], x.size)
    first, second = _reports(x)
    assert math.isnan(second["raw_impulse"])  # the premise: the samples alone give no impulse
    assert second["status"] == "ok" and second["rebound"] and second["rebound_of"] == first["sequence"]
    assert second["impulse"] == pytest.approx(back["impulse"], rel=0.05)


def _two_rebounds_due(seed, landing_pulses):
    """Six measured fruit (e 0.55–0.60, masses ±10 %), then fruit A (e 0.6) and fruit B (e 0.5, 20 ms later) whose
    rebounds are due at the same moment; ``landing_pulses(a, b, landing)`` gives the (onsets, impacts) that land
    then.  The line's noise as in ``_lane_then_fruit_with_rebound``."""
    rng = np.random.default_rng(seed)
    fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(6)]
    a, b = impact(restitution=0.6), impact(mass=0.95 * MASS, restitution=0.5)
    landing = 0.7 + a["T"] + 2 * a["e"] * V_LINE / G
    onset_b = landing - b["T"] - 2 * b["e"] * V_LINE / G + 5e-5
    onsets, impacts = landing_pulses(a, b, landing)
    x = _signal([0.1 + 0.1 * k for k in range(6)] + [0.7, onset_b, *onsets], [*fruit, a, b, *impacts],
                int(0.95 * RATE), seed=seed)
    return x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * fruit[0]["F"], x.size)


@pytest.mark.parametrize("seed", range(4))
def test_two_rebounds_landing_together_are_no_fruit(seed):
    """A's rebound and B's land 0.05 ms apart: one pulse that a single force law fits, which the rebound test of
    either parent alone rejects (it carries both impulses) and which had been reported as a new fruit, graded.
    It carries what the two rebounds carry together, the impulse of each (the same fruit at 0.92 e V) added and a
    rebound's restitution (0.7 against the lane's 0.58: a slower impact), where a new fruit of the lane lies far
    (rebounds.rebounds_landed_together): one overlap report, a rebound, no firmness, both parents in its evidence.
    A typical new fruit landing there alone (its e and mass the lane's, or 1.3 times the mass) is a new fruit."""
    def rebounds(a, b, landing):
        return [landing, landing + 5e-5], [impact(mass=a["m"], velocity=a["e"] * V_LINE, c=a["c"]),
                                           impact(mass=b["m"], velocity=b["e"] * V_LINE, c=b["c"])]
    *_, first, second, both = _reports(_two_rebounds_due(seed, rebounds))
    assert both["status"] == "overlap" and both["message"].startswith("two rebounds landing together")
    assert both["rebound"] and math.isnan(both["firmness_c"]) and both.get("class") is None
    assert not both["rebound_ambiguous"], both["rebound_evidence"]
    assert sorted(both["rebound_evidence"]["parents"]) == [first["sequence"], second["sequence"]]
    for mass in (1.0, 1.3):
        new = _reports(_two_rebounds_due(seed, lambda a, b, landing: ([landing], [impact(mass=mass * MASS,
                                                                                         restitution=0.58)])))[-1]
        assert new["status"] == "ok" and not new["rebound"], new["message"]


def test_two_rebounds_after_an_overlap_and_their_own_bounces(tmp_path):
    """Found by a review.  (1) A fruit hidden in an earlier overlap leaves an ambiguous verdict on the pulse of two
    rebounds landing together: the analysis used to crash (the hidden fruit's verdict dropped, its flag kept);
    it is an overlap that is a rebound.  (2) The two rebounds each bounce again: both hidden rebounds carry the
    overlap's sequence, and each bounce must mark the one it matched (rebounds.claimed_parent), so that neither
    bounce is taken for a new fruit (it was, 1 seed in 4; bounces landing close again are an overlap, no fruit).  (3) A new fruit landing with the two rebounds carries
    2.2 times a lot fruit's impulse: an overlap, never one fruit of twice the mass, graded."""
    def lane(seed, extra):
        rng = np.random.default_rng(seed)
        fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(6)]
        return [0.1 + 0.1 * k for k in range(6)], fruit, extra

    def build(seed, hidden_at=None, bounces=False, new_fruit=False):
        onsets, impacts, _ = lane(seed, None)
        a, b = impact(mass=0.5 * MASS if hidden_at else MASS, restitution=0.6), \
            impact(mass=0.5 * MASS if hidden_at else 0.95 * MASS, restitution=0.5)
        landing = 0.7 + a["T"] + 2 * a["e"] * V_LINE / G
        onset_b = landing - b["T"] - 2 * b["e"] * V_LINE / G + 5e-5
        ra, rb = (impact(mass=f["m"], velocity=f["e"] * V_LINE, c=f["c"]) for f in (a, b))
        onsets, impacts = onsets + [0.7, onset_b, landing, landing + 5e-5], impacts + [a, b, ra, rb]
        if hidden_at:
            onsets, impacts = onsets + [hidden_at, hidden_at + 0.0015], impacts + [impact(restitution=0.57),
                                                                                impact(mass=0.7 * MASS)]
        if new_fruit:
            onsets, impacts = onsets + [landing + 1e-4], impacts + [impact(mass=MASS, restitution=0.58)]
        if bounces:
            for r in (ra, rb):
                speed = r["e"] * r["V"]
                onsets.append(landing + r["T"] + 2 * speed / G)
                impacts.append(impact(mass=r["m"], velocity=speed, c=r["c"]))
        order = np.argsort(onsets)
        x = _signal([onsets[k] for k in order], [impacts[k] for k in order], int(1.1 * RATE), seed=seed)
        return x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * impacts[0]["F"], x.size), landing

    x, landing = build(0, hidden_at=0.64)
    (pair,) = [r for r in _reports(x) if abs(r["start_time"] - landing) < 2e-3]
    assert pair["status"] == "overlap" and pair["rebound"]
    for seed in range(4):
        x, landing = build(seed, bounces=True)
        reports = _reports(x)
        (pair,) = [r for r in reports if abs(r["start_time"] - landing) < 2e-3]
        later = [r for r in reports if r["start_time"] > landing + 0.01]
        # each is a rebound of the pair's contact, or (the two bounces landing close again) an overlap: no fruit
        assert later and all(r["rebound"] or r["status"] == "overlap" for r in later), \
            [(r["status"], r["message"]) for r in later]
        assert all(r["rebound_of"] == pair["sequence"] for r in later if r["rebound"])
    for seed in (2, 3):
        x, landing = build(seed, new_fruit=True)
        (three,) = [r for r in _reports(x) if abs(r["start_time"] - landing) < 2e-3]
        assert three["status"] == "overlap" and math.isnan(three["firmness_c"]), three["message"]
        assert len(three["rebound_evidence"]["parents"]) == 2


def test_a_rebound_piece_reported_as_an_overlap_carries_no_firmness_of_any_kind():
    """A rebound landing on the next fruit's peak 2 ms after it (fixed only to ±1.5–3 %): its report is an overlap,
    and no firmness remains in it, raw or fitted, nor a fit said to have converged (a review found raw_firmness_c
    and fit_converged true left in such reports)."""
    for seed in range(3):
        *_, x = _fruit_then_rebound_with_the_next(2.0e-3, 1.1, seed=seed)
        (back,) = [r for r in _reports(x)[1:] if r["rebound"]]
        assert back["status"] == "overlap"
        for key in ("firmness_c", "firmness_c_star", "raw_firmness_c", "raw_firmness_c_star", "stiffness"):
            assert key not in back or back[key] is None or math.isnan(back[key]), (key, back[key])
        assert back.get("fit_converged") is not True


def test_a_pulse_too_light_for_a_fruit_that_a_rebound_explains_is_a_rebound():
    """A fruit lands at the line's speed V with the lane's impulse m (1 + e) V; a rebound lands at r V
    (r ≈ 0.92 e) with r (1 + e_r)/(1 + e) of it and the higher restitution e(r x) of a slower impact.  A pulse that
    no measured contact claims is taken for such a rebound (rebounds.too_light_for_fruit) when its impulse lies
    more than z = 3 sd (sd ≥ LOT_IMPULSE_SD = 0.15) below the lane's and a rebound of one of the lane's fruit
    explains its restitution, impulse and stiffness read at r V within χ²₃(99 %) and better than a new fruit.
    Here the parent (e 0.57) bounces with 5 % spin loss: its rebound carries 0.63 of the lane's median impulse
    (−3.1 sd: caught; without the spin loss 0.66, −2.8 sd, is not: first rebounds above ~0.64 of the lane's
    impulse never are, the rule's stated limit) and its second bounce 0.45 (−5.4 sd).  Light fruit as light as
    that are new fruit: one of 0.55 of the lot's mass with its restitution, and a lively one (e 0.70): read at the
    rebound's speed r V its pulse needs a fruit r^-1.5 ≈ 2.4 times stiffer than the lot."""
    from fruitimpact.signals.rebounds import LANE_FRUIT_MIN, too_light_for_fruit

    fruit = _lane_fruit()
    median = np.median([f.impulse for f in fruit])
    parent = impact(restitution=0.57)
    speed = 0.95 * parent["e"] * V_LINE
    back = impact(velocity=speed, c=parent["c"])
    bounce = impact(velocity=0.95 * back["e"] * speed, c=parent["c"])
    for pulse, bounce_number in ((back, 1), (bounce, 2)):
        evidence = too_light_for_fruit(summary(pulse, 2.0, 40), fruit)
        assert evidence is not None and evidence["fruit_distance"] < -3, (pulse, evidence)
        assert evidence["bounce"] == bounce_number and evidence["rebound_distance"] < evidence["new_fruit_distance"]
    for mass, restitution in ((0.55, 0.57), (0.55, 0.70)):
        light = impact(mass=mass * MASS, restitution=restitution)
        assert light["impulse"] / median < 0.64  # as light as a caught rebound
        assert too_light_for_fruit(summary(light, 2.0, 40), fruit) is None, (mass, restitution)
    assert too_light_for_fruit(summary(impact(mass=0.9 * MASS), 2.0, 40), fruit) is None
    assert too_light_for_fruit(summary(back, 2.0, 40), _lane_fruit(LANE_FRUIT_MIN - 1)) is None


def test_a_light_fruit_of_a_wide_lot_is_not_taken_for_a_rebound():
    """In a lot spread 3 : 1 in mass and 4 : 1 in contact stiffness, a light fruit (0.3 of the nominal mass, e 0.66,
    0.7 of the nominal stiffness) is 3.1 sd below the lane's impulse, and the lane's wide spread of stiffness
    leaves its pulse read at a rebound's speed within reach of the lot: a rebound of a lane fruit lies at 3.0 sd,
    a new fruit at 4.3.  That is no evidence for a rebound: rebounds.too_light_for_fruit asks for a new fruit
    ORPHAN_MARGIN = 2 times farther (the rebounds it finds on the line scenarios lie 3.6–11 times nearer a
    rebound), so the pulse stays a new fruit; with a margin of 1 it would have been taken."""
    from fruitimpact.signals import rebounds

    rng = np.random.default_rng(0)
    fruit = [summary(impact(mass=MASS * m, restitution=rng.uniform(0.52, 0.62),
                            stiffness=STIFFNESS * rng.uniform(0.5, 2.0)), 0.1 * k, k, velocity=V_LINE)
             for k, m in enumerate(np.exp(rng.uniform(math.log(0.5), math.log(1.6), 12)))]
    light = summary(impact(mass=0.3 * MASS, restitution=0.66, stiffness=0.7 * STIFFNESS), 2.0, 40)
    assert rebounds.too_light_for_fruit(light, fruit) is None
    evidence = rebounds.lane._as_lane_rebound(light, fruit, rebounds.lane_fruit(fruit), 1.0,
                                              rebounds.EXPECTED_RATIO * rebounds.lane_fruit(fruit).restitution)
    assert evidence["rebound2"] < evidence["new_fruit2"] < rebounds.ORPHAN_MARGIN ** 2 * evidence["rebound2"]


def test_rebounds_whose_parent_was_not_measured_are_not_new_fruit():
    """A fruit's first impact is not on the plate's record as itself (on a line: it landed within a fraction of a
    millisecond of another fruit's rebound and the two read as one heavier fruit; here, more simply, it struck
    the plate's frame), then its rebound and its second bounce land on the plate.  No measured contact predicts
    the rebound, so the rebound tests cannot claim it.  It may not be graded as a new fruit: it is too light for
    the lot (0.58 of its impulse) and as lively as a rebound (rebounds.too_light_for_fruit), so it is reported a
    rebound, its parent unknown (rebound_of null), ambiguous, with no class; the second bounce is then the
    rebound of that rebound.  A light fruit of the lot (0.6 of its mass, its restitution) landing after them is
    still a new fruit, graded."""
    from fruitimpact.signals.sort import FirmnessClasses

    lot = [impact(mass=MASS * m, restitution=e) for m, e in ((1.0, 0.57), (1.1, 0.55), (0.92, 0.6), (1.05, 0.58))]
    onsets = [0.1 + 0.25 * k for k in range(len(lot))]
    a = impact(restitution=0.58)
    t_a = onsets[-1] + 0.25  # its impact is not recorded
    speed = 0.95 * a["e"] * V_LINE
    back = impact(velocity=speed, c=a["c"])
    landing = t_a + a["T"] + 2 * speed / G
    speed_2 = 0.95 * back["e"] * speed
    bounce = impact(velocity=speed_2, c=a["c"])
    t_bounce = landing + back["T"] + 2 * speed_2 / G
    light = impact(mass=0.6 * MASS, restitution=0.57)
    t_light = t_bounce + 0.2
    pulses = [*zip(onsets, lot), (landing, back), (t_bounce, bounce), (t_light, light)]
    x = _signal([p[0] for p in pulses], [p[1] for p in pulses], int((t_light + 0.1) * RATE))
    reports = _reports(x, classes=FirmnessClasses("stiffness", (STIFFNESS,), ("soft", "firm")))
    assert len(reports) == len(pulses), [(r["start_time"], r["message"]) for r in reports]
    assert not any(r["rebound"] for r in reports[:len(lot)])
    orphan, second = reports[len(lot):len(lot) + 2]
    assert orphan["status"] == "ok" and orphan["rebound"] and orphan["rebound_of"] is None, orphan["message"]
    assert orphan["rebound_ambiguous"] and orphan["class"] is None
    assert "not measured as it was" in orphan["message"]
    assert orphan["rebound_evidence"]["kind"] == "parent_not_measured"
    assert math.isnan(orphan["mass"]) and math.isnan(orphan["stiffness"])  # its speed is not measured: m, K unsplit
    # the second bounce: judged against the first rebound's own pulse
    assert second["rebound"] and second["class"] is None, second["message"]
    assert second["rebound_of"] == orphan["sequence"], second["rebound_evidence"]
    last = reports[-1]
    assert not last["rebound"] and last["class"] is not None, last["message"]


def test_a_fruit_landing_with_the_rebound_of_a_fruit_hidden_in_an_overlap_is_an_overlap():
    """Three fruit land in one contact (an overlap: no fruit measured); the first one's rebound, the lane's typical
    fruit at r V (rebounds.unmeasured_fruit), then lands 0.2 ms before a new, heavier fruit.  Fitted as one pulse
    the two carry 1.7 times a fruit's impulse: more than 3 sd above the lane's (sd floored at 15 %), and within
    1 sd of a fruit and that rebound together.  No measured contact's rebound is due there, only the hidden
    fruit's, so without it that contact was one heavy fruit, graded; it is an overlap without firmness or class,
    its evidence naming the earlier overlap (rebounds.landed_with_rebound), and the hidden fruit's second bounce
    (r ≈ 0.92 e of the first rebound's speed, after its flight) is the rebound of that contact.  The other fruit's
    rebounds are left out of the signal so that these two contacts are the only ones after the overlap."""
    from fruitimpact.signals.sort import FirmnessClasses

    lot = [impact(mass=MASS * m, restitution=e) for m, e in ((1.0, 0.57), (1.04, 0.56), (0.96, 0.58), (1.02, 0.57),
                                                              (0.98, 0.57))]
    onsets = [0.1 + 0.25 * k for k in range(len(lot))]
    a, b, c = impact(), impact(mass=0.9 * MASS), impact(mass=0.8 * MASS)
    t_a = onsets[-1] + 0.25
    speed = 0.92 * a["e"] * V_LINE
    back = impact(velocity=speed, c=a["c"])
    landing = t_a + a["T"] + 2 * speed / G
    heavy = impact(mass=1.1 * MASS, restitution=0.57)
    speed_2 = 0.92 * back["e"] * speed  # the hidden fruit's second bounce
    bounce = impact(velocity=speed_2, c=a["c"])
    t_bounce = landing + back["T"] + 2 * speed_2 / G
    pulses = [*zip(onsets, lot), (t_a, a), (t_a + 0.55 * a["T"], b), (t_a + 1.1 * a["T"], c), (landing, back),
              (landing + 0.0002, heavy), (t_bounce, bounce)]
    x = _signal([p[0] for p in pulses], [p[1] for p in pulses], int((t_bounce + 0.1) * RATE))
    reports = _reports(x, classes=FirmnessClasses("stiffness", (STIFFNESS,), ("soft", "firm")))
    assert [r["status"] for r in reports[:len(lot)]] == ["ok"] * len(lot)
    overlap, together, second = reports[len(lot):]
    assert overlap["status"] == "overlap", overlap["message"]
    assert together["status"] == "overlap" and together["class"] is None, together["message"]
    assert math.isnan(together["firmness_c"])
    evidence = together["rebound_evidence"]
    assert evidence["landed_with_rebound_of"] == overlap["sequence"] and evidence["fruit_distance"] > 3, evidence
    # the hidden fruit's rebound was seen there: its second bounce is the rebound of that contact
    assert second["rebound"] and second["rebound_of"] == together["sequence"], second["rebound_evidence"]


def _lane_with_rebounds(seed, count=6, flights=None):
    """``count`` fruit of a lot (masses ±10 %, e 0.55–0.6) 0.25 s apart at the line's speed, each followed by its
    rebound (the same fruit at e V) after 2 e V/g times a factor within ±10 % (spin, an off-axis bounce), or the
    factors ``flights``; then the ``_lane_then_fruit_with_rebound`` ending: a fruit whose rebound is due and a
    new fruit landing 0.05 ms before it.  Returns the new fruit and the signal (2.2 % noise)."""
    rng = np.random.default_rng(seed)
    onsets, impacts = [], []
    for k in range(count):
        fruit = impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6))
        back = impact(mass=fruit["m"], velocity=fruit["e"] * V_LINE, c=fruit["c"])
        onset = 0.1 + 0.25 * k
        factor = rng.uniform(0.9, 1.1) if flights is None else flights[k]
        flight = 2 * fruit["e"] * V_LINE / G * factor
        onsets += [onset, onset + fruit["T"] + flight]
        impacts += [fruit, back]
    last = impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=0.57)
    back = impact(mass=last["m"], velocity=last["e"] * V_LINE, c=last["c"])
    start = 0.1 + 0.25 * count
    landing = start + last["T"] + 2 * last["e"] * V_LINE / G
    new = impact(mass=MASS, restitution=0.57)
    onsets += [start, landing - 5e-5, landing]
    impacts += [last, new, back]
    x = _signal(onsets, impacts, int((landing + 0.05) * RATE), seed=seed)
    return new, x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * impacts[0]["F"], x.size)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_without_the_drop_height_the_line_speed_is_read_from_its_rebounds(seed):
    """A rebound flies 2 r V/g between leaving the plate and landing again, r its speed ratio (measured from the
    two pulses: impulse, restitution and shape of the same fruit), so each clear first rebound of a new fruit
    shows the line's impact speed V = g · flight / (2 r) (signals.analysis.LineAnalyzer.line_speed).  With the
    flights spread ±10 % (spin), the median of six is within 8 % of the speed the fruit fell at.  Analysed
    without the drop height (indices only), a fruit and a rebound landing 0.05 ms apart are then told to be an
    overlap as they are with it (rebounds.landed_with_rebound; without the speed no rebound is ever due, and they
    were one fruit, graded; the pulse carries 1.6 times the lane's impulse, 3.2 sd above it: seed 0, at 2.9 sd, is
    one fruit with the drop height too).  Until SPEED_MIN_REBOUNDS rebounds agree there is no speed."""
    from fruitimpact.signals.analysis import SPEED_MIN_REBOUNDS

    _, x = _lane_with_rebounds(seed)
    analyzer = Analysis(RATE).analyzer()
    reports, speeds = [], []
    for found in detect(x, RATE):
        reports += analyzer.reports(found)
        speeds.append(analyzer.line_speed(0))
    rebounds = [r for r in reports if r["rebound"]]
    assert len(rebounds) >= 6, [r["message"] for r in reports]
    assert speeds[2 * SPEED_MIN_REBOUNDS - 2] is None  # one rebound short
    # each reading: the flight's ±10 % (uniform: sd 5.8 %) and r measured from two pulses at 2.2 % noise (~2 %);
    # the median of six about 3 % sd: 8 % is 2.5 sd
    assert analyzer.line_speed(0) == pytest.approx(V_LINE, rel=0.08)
    last = reports[-1]
    assert last["status"] == "overlap" and "a fruit and a rebound landing together" in last["message"], last
    assert math.isnan(last["firmness_c"])
    # with the drop height given, the same: the speed read is the one the analysis is told
    given = Analysis(RATE, velocity=V_LINE).analyzer()
    reports = [r for found in detect(x, RATE) for r in given.reports(found)]
    assert given.line_speed(0) == V_LINE and reports[-1]["status"] == "overlap"


def test_rebounds_that_disagree_on_the_line_speed_give_none():
    """Flights scattered over 0.55–1.45 times 2 e V/g (no line flies like that): the speeds their rebounds show
    spread beyond SPEED_SPREAD (median absolute deviation ~30 % of the median), so the line has no speed, and
    nothing is predicted from one."""
    from fruitimpact.signals.analysis import SPEED_SPREAD

    _, x = _lane_with_rebounds(1, flights=[0.55, 1.45, 0.8, 1.2, 1.0, 0.65])
    analyzer = Analysis(RATE).analyzer()
    for found in detect(x, RATE):
        analyzer.reports(found)
    speeds = np.asarray(analyzer._speeds[0])
    assert len(speeds) >= 4
    assert np.median(np.abs(speeds - np.median(speeds))) > SPEED_SPREAD * np.median(speeds)
    assert analyzer.line_speed(0) is None


def test_a_contact_a_hidden_fruits_rebound_explains_only_a_little_better_than_a_new_fruit_is_a_new_fruit():
    """Between a hidden fruit's rebound (the lane's fruit at r V) and a new fruit (at V) lies a contact of the
    lane's fruit landing at an intermediate speed: where the rebound's distance is below the new fruit's but by
    less than STRONG_EVIDENCE in squared sd (2 ln B < 6: odds under 20 : 1, Kass & Raftery 1995), the evidence
    does not decide; it is a new fruit, said to be ambiguous, with both distances (seen on a lane of apples and
    pears: a fruit taken for a rebound at 2 ln B = 2.0).  The lane is as wide as such a lane: masses 0.6–1.4,
    stiffness 0.6–1.6 times the lot's, e 0.45–0.7 (a narrow lane leaves no such contact: its new fruit lie far)."""
    from fruitimpact.signals.rebounds import judge_unmeasured
    from fruitimpact.signals.rebounds.lane import STRONG_EVIDENCE

    rng = np.random.default_rng(11)
    fruit = [summary(impact(mass=MASS * rng.uniform(0.6, 1.4), stiffness=STIFFNESS * rng.uniform(0.6, 1.6),
                            restitution=rng.uniform(0.45, 0.7)), 0.1 * k, k, velocity=V_LINE) for k in range(8)]
    hidden = impact(restitution=0.57)
    left = 1.0 + hidden["T"]
    flight = 2 * hidden["e"] * V_LINE / G
    close = []
    for u in np.linspace(hidden["e"], 1.0, 200):
        candidate = summary(impact(velocity=u * V_LINE, c=hidden["c"]), left + flight, 99)
        verdict = judge_unmeasured(candidate, 42, 1.0, fruit, V_LINE)
        ev = verdict.evidence
        if ev and ev["score"] is not None and ev["score"] <= 1.0 and ev["rebound_distance"] is not None:
            margin = ev["new_fruit_distance"] ** 2 - ev["rebound_distance"] ** 2
            if 0 < margin < STRONG_EVIDENCE:
                close.append((margin, verdict))
    assert close, "no contact between the two hypotheses within the margin"
    for margin, verdict in close:
        assert not verdict.rebound and verdict.ambiguous, (margin, verdict.evidence)
        assert "about as well or better" in verdict.evidence["reason"]
    # nearer the rebound the evidence is strong: a rebound
    strong = judge_unmeasured(summary(impact(velocity=0.6 * V_LINE, c=hidden["c"]), left + flight, 99), 42, 1.0,
                              fruit, V_LINE)
    ev = strong.evidence
    assert ev["new_fruit_distance"] ** 2 - ev["rebound_distance"] ** 2 >= STRONG_EVIDENCE
    assert strong.rebound and strong.parent == 42, ev



def test_a_hidden_fruits_rebound_in_the_ambiguous_band_is_decided_by_the_comparison_with_a_new_fruit():
    """The rebound score (distance over the 99 % point of χ² with four degrees of freedom) is a scale, not a
    probability: in its ambiguous band above 1 (AMBIGUOUS) it cannot decide alone.  There the comparison with a
    new fruit of the lane does (2 ln B ≥ STRONG_EVIDENCE, Kass & Raftery 1995): the hidden fruit's own rebound,
    landing later than predicted (its flight 1.2–1.5 times: a livelier fruit than the lane's typical one, seen on
    chain7 at seed 1: score 1.22, 10.9 sd from any new fruit, 3.9 sd from the rebound), is that rebound, said to
    be ambiguous.  Beyond the band, up to HIDDEN_SCORE_MAX, it is still that rebound (said to be ambiguous, the
    hidden fruit's slot left open) when no new fruit of the lane could have made it (at least the 99.9 % point of
    χ² with three degrees of freedom away: a pulse of the same fruit at the rebound's speed, whose flight says the
    hidden fruit was livelier than the lane's median; chain7 at seed 26: score 1.42, 14.7 sd from any new fruit);
    further out it is a new fruit, said to be ambiguous or not at all."""
    from fruitimpact.signals.rebounds import judge_unmeasured
    from fruitimpact.signals.rebounds.pulses import AMBIGUOUS
    from fruitimpact.signals.rebounds.lane import HIDDEN_SCORE_MAX, NEW_FRUIT_EXCLUDED, STRONG_EVIDENCE

    fruit = _lane_fruit()
    hidden = impact(restitution=0.57)
    back = impact(velocity=hidden["e"] * V_LINE, c=hidden["c"])
    left = 1.0 + hidden["T"]
    flight = 2 * 0.95 * hidden["e"] * V_LINE / G
    taken = left_out = beyond = 0
    for late in np.linspace(1.0, 2.0, 101):
        verdict = judge_unmeasured(summary(back, left + late * flight, 99), 42, 1.0, fruit, V_LINE)
        ev = verdict.evidence
        if ev and ev["score"] is not None and 1.0 < ev["score"] <= AMBIGUOUS[1]:
            margin = ev["new_fruit_distance"] ** 2 - ev["rebound_distance"] ** 2
            assert verdict.ambiguous and verdict.rebound == (margin >= STRONG_EVIDENCE), (late, ev)
            taken += verdict.rebound
            left_out += not verdict.rebound
        elif not ev or ev["score"] is None or ev["score"] > AMBIGUOUS[1]:  # beyond the band: a flight too long
            beyond += 1  # for the fruit (it left faster than its rebound's e allows), so no exclusion either
            assert not verdict.rebound, (late, ev)
    assert taken >= 3 and beyond >= 3, (taken, left_out, beyond)  # the scan crosses the band: the checks ran
    # a hidden fruit ever lighter than the lane's, its rebound on time: beyond the band up to HIDDEN_SCORE_MAX it
    # is that rebound, since no new fruit of the lane could have made it; further out a new fruit
    excluded = far = 0
    for share in np.linspace(0.5, 0.2, 31):
        light = impact(mass=share * MASS, restitution=0.57)
        bounce = impact(mass=share * MASS, velocity=light["e"] * V_LINE, c=light["c"])
        verdict = judge_unmeasured(summary(bounce, 1.0 + light["T"] + flight, 99), 42, 1.0, fruit, V_LINE)
        ev = verdict.evidence
        if ev and ev.get("new_fruit_excluded"):
            excluded += 1
            assert verdict.rebound and verdict.ambiguous and AMBIGUOUS[1] < ev["score"] <= HIDDEN_SCORE_MAX
            assert ev["new_fruit_distance"] ** 2 >= NEW_FRUIT_EXCLUDED
            assert ev["new_fruit_distance"] ** 2 - ev["rebound_distance"] ** 2 >= STRONG_EVIDENCE
        elif not ev or ev["score"] is None or ev["score"] > HIDDEN_SCORE_MAX:
            far += 1
            assert not verdict.rebound, (share, ev)
    assert excluded >= 3 and far >= 3, (excluded, far)

def _fruit_with_rebounds_at(speeds, seed):
    """One fruit of the lot (masses ±10 %) every 0.25 s at each impact speed of ``speeds`` [m/s], each followed by
    its rebound (the same fruit at e V, e its own at that speed) after 2 e V/g × (1 ± 10 %); the signal at 2.2 %
    noise."""
    rng = np.random.default_rng(seed)
    onsets, impacts = [], []
    for k, speed in enumerate(speeds):
        fruit = impact(mass=MASS * rng.uniform(0.9, 1.1), velocity=speed)
        back = impact(mass=fruit["m"], velocity=fruit["e"] * speed, c=fruit["c"])
        onset = 0.1 + 0.25 * k
        onsets += [onset, onset + fruit["T"] + 2 * fruit["e"] * speed / G * rng.uniform(0.9, 1.1)]
        impacts += [fruit, back]
    x = _signal(onsets, impacts, int((onsets[-1] + 0.1) * RATE), seed=seed)
    return x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * impacts[0]["F"], x.size)


def test_a_speed_read_from_rebounds_follows_a_lane_whose_drop_changes():
    """A speed read from the lane's rebounds predicts when rebounds are due but is not a test of their flights
    (PulseSummary.speed_read): a wrong reading would otherwise reject the rebounds whose flights correct it.
    Six fruit from 5 cm, then twelve from 10 cm (the speed × 1.41): every rebound is still a rebound, none is a new
    fruit, and the lane's speed follows to the new drop (the median of the last SPEED_KEPT readings; within 8 %
    as above)."""
    speeds = [V_LINE] * 6 + [math.sqrt(2 * G * 0.10)] * 12
    analyzer = Analysis(RATE).analyzer()
    reports = [r for found in detect(_fruit_with_rebounds_at(speeds, 4), RATE) for r in analyzer.reports(found)]
    assert len(reports) == 2 * len(speeds)
    assert [r["rebound"] for r in reports] == [False, True] * len(speeds), [r["message"] for r in reports]
    assert analyzer.line_speed(0) == pytest.approx(speeds[-1], rel=0.08)


def test_each_lane_has_its_own_speed():
    """Two lanes of one line dropping from 5 and 10 cm: each lane's speed is read from its own rebounds."""
    import dataclasses

    analyzer = Analysis(RATE).analyzer()
    for lane, height in ((0, 0.05), (1, 0.10)):
        x = _fruit_with_rebounds_at([math.sqrt(2 * G * height)] * 6, 7 + lane)
        for found in detect(x, RATE):
            analyzer.reports(dataclasses.replace(found, lane=lane))
    assert analyzer.line_speed(0) == pytest.approx(math.sqrt(2 * G * 0.05), rel=0.08)
    assert analyzer.line_speed(1) == pytest.approx(math.sqrt(2 * G * 0.10), rel=0.08)


def test_analyze_says_the_speed_it_read_from_the_rebounds(cli, tmp_path):
    """Without --drop-height, ``analyze``'s summary says each lane's impact speed read from its rebounds and the drop
    it stands for, V²/2g (10 cm here, within 16 %: twice the speed's 8 %); with the drop height given it says
    nothing of the kind; a lane without four rebounds that agree is said to have none."""
    speed = math.sqrt(2 * G * 0.10)
    x = _fruit_with_rebounds_at([speed] * 6, 5)
    path = tmp_path / "lane.csv"
    np.savetxt(path, np.column_stack([np.arange(x.size) / RATE, x]), delimiter=",", header="time [s],force [N]",
               comments="")
    line = cli.ok("analyze", path).splitlines()[-1]
    assert line.startswith("impact speed read from each lane's rebounds (no --drop-height given): force "), line
    read, drop = (float(v) for v in re.search(r"force ([\d.]+) m/s \(a ([\d.]+) cm drop\)", line).groups())
    assert read == pytest.approx(speed, rel=0.08) and drop == pytest.approx(10.0, rel=0.16)
    assert "speed read" not in cli.ok("analyze", path, "--drop-height", "10cm")
    short = tmp_path / "short.csv"
    few = _fruit_with_rebounds_at([speed] * 3, 5)
    np.savetxt(short, np.column_stack([np.arange(few.size) / RATE, few]), delimiter=",", header="time [s],force [N]",
               comments="")
    assert cli.ok("analyze", short).splitlines()[-1].endswith("force none (fewer than 4 clear rebounds that agree)")


# ---------------------------------------------------------------------------------------------------------------
# Cascades: a rebound whose parent was not measured as it was, and its own bounces


def test_a_fruits_flight_measures_the_speed_it_lands_at():
    """The flight of a body leaving a plate at u, integrated by SciPy (z'' = −g from z = 0, ż = u, until z returns
    to 0; drag neglected; spin and an off-axis bounce change the path, not this vertical motion): its time in the
    air is ``flight_time(u)`` and the speed it lands at is ``landing_speed`` of that time, to the integrator's
    tolerance (rtol 1e-12).  No flight, no speed."""
    from scipy.integrate import solve_ivp

    from fruitimpact.signals.rebounds import flight_time, landing_speed

    def ground(t, y):
        return y[0]

    ground.terminal, ground.direction = True, -1
    for u in (0.05, 0.4, 1.3):
        sol = solve_ivp(lambda t, y: [y[1], -G], (0.0, 10.0), [0.0, u], events=ground, rtol=1e-12, atol=1e-15,
                        first_step=1e-6)
        flight, landed = sol.t_events[0][0], -sol.y_events[0][0][1]
        assert flight_time(u) == pytest.approx(flight, rel=1e-9)
        assert landing_speed(flight) == pytest.approx(landed, rel=1e-9)
        assert landed == pytest.approx(u, rel=1e-9)
    assert math.isnan(landing_speed(0.0)) and math.isnan(landing_speed(-0.01))
    assert math.isnan(landing_speed(math.nan))


def _a_rebound_taken_for_a_fruit(mass=1.3 * MASS, stiffness=1.4 * STIFFNESS, spin=0.95):
    """A heavy, stiff fruit hidden in an overlap lands at V; its rebound (r₁ = spin · e₁) carries about a typical
    fruit's impulse and was taken for a new fruit at the line's speed (its summary's speed V, as the analysis
    keeps it); its second bounce (r₂ = spin · e₂) lands 2 r₂ r₁ V/g after the rebound left.  Returns (the lane's
    fruit, the rebound's summary, the bounce's summary, r₁ V, r₂ r₁ V)."""
    fruit = _lane_fruit()
    hidden = impact(mass=mass, stiffness=stiffness, restitution=0.60)
    v1 = spin * hidden["e"] * V_LINE
    first = impact(mass=mass, stiffness=stiffness, c=hidden["c"], velocity=v1)
    v2 = spin * first["e"] * v1
    second = impact(mass=mass, stiffness=stiffness, c=hidden["c"], velocity=v2)
    taken = summary(first, 1.0, 30, V_LINE)  # the analysis's summary of a contact judged a fruit at V
    bounce = summary(second, taken.separation + 2.0 * v2 / G, 31)
    return fruit, taken, bounce, v1, v2


def test_the_bounce_of_a_rebound_taken_for_a_fruit_is_a_rebound_of_it():
    """The cascade: a rebound taken for a fruit at the line's speed V predicts its own rebound after 2 r V/g, but
    it moved at r₁ V, so its bounce lands after 2 r r₁ V/g, 0.6–0.7 of that: the flight test rejects it and the
    bounce was a new fruit too, graded.  Every test that does not need the parent's speed (speed ratio from the
    impulse ratio against e, peak force, time to peak, shape: the same fruit) passes, and the bounce's flight
    measures the speed it landed at, g · flight/2, so the parent moved at V_p = u/r, a rebound's share of V; as a
    new fruit of the lane the bounce is improbable (restitution, impulse and stiffness read at V beyond χ²₃ 99 %).
    rebounds.rebound_of_a_rebound takes it for the rebound of that contact, ambiguous (the parent's grade, given,
    is not revised), and reads the parent's speed to the spin loss the flight cannot see (within 3 %)."""
    from fruitimpact.signals.rebounds import rebound_of_a_rebound

    fruit, taken, bounce, v1, v2 = _a_rebound_taken_for_a_fruit()
    assert not judge(bounce, [taken], max_flight=1.0).rebound  # the cascade this rule ends
    verdict = rebound_of_a_rebound(bounce, [taken], fruit, V_LINE, 1.0)
    assert verdict.rebound and verdict.ambiguous and verdict.parent == taken.sequence, verdict.evidence
    evidence = verdict.evidence
    assert evidence["landing_speed"] == pytest.approx(v2, rel=1e-6)  # ballistic: exact up to rounding
    assert evidence["parent_speed"] == pytest.approx(v1, rel=0.03)  # r from the impulse ratio: the spin it misses
    assert evidence["new_fruit_distance"] ** 2 > 11.345
    assert "was itself a rebound" in evidence["reason"]


def test_a_new_fruit_after_a_rebound_taken_for_a_fruit_stays_a_new_fruit():
    """What the rule must not take: a typical new fruit of the lane landing when the bounce would (a plausible new
    fruit: the rule does not look further), a light fruit landing then (0.55 of the lot's mass: its pulse is
    shorter than a rebound's, t_c ∝ m^0.4 against r^-0.2 for the same fruit slower, so the shared tests fail), and
    the bounce itself where the flight says the parent moved at 0.9 V (a fruit's own rebound landing late, which
    the flight tolerance of ``judge`` covers: not a rebound's speed)."""
    from fruitimpact.signals.rebounds import NEW_FRUIT, SLOW_PARENT_RATIO, rebound_of_a_rebound

    fruit, taken, bounce, v1, v2 = _a_rebound_taken_for_a_fruit()
    when = bounce.onset
    typical = summary(impact(mass=MASS, restitution=0.57), when, 31)
    assert rebound_of_a_rebound(typical, [taken], fruit, V_LINE, 1.0) is NEW_FRUIT
    light = summary(impact(mass=0.55 * MASS, restitution=0.62), when, 31)
    assert rebound_of_a_rebound(light, [taken], fruit, V_LINE, 1.0) is NEW_FRUIT
    r = bounce.impulse / taken.impulse  # about the speed ratio
    late = summary(impact(mass=1.3 * MASS, stiffness=1.4 * STIFFNESS, c=impact(restitution=0.60)["c"],
                          velocity=v2), taken.separation + 2.0 * 0.9 * V_LINE * r / G * 1.05, 31)
    share = G * (late.onset - taken.separation) / 2.0 / r / V_LINE
    assert share > SLOW_PARENT_RATIO[1]
    assert rebound_of_a_rebound(late, [taken], fruit, V_LINE, 1.0) is NEW_FRUIT
    assert rebound_of_a_rebound(bounce, [taken], fruit[:2], V_LINE, 1.0) is NEW_FRUIT  # too few fruit to judge by
    assert rebound_of_a_rebound(bounce, [taken], fruit, None, 1.0) is NEW_FRUIT  # no line speed


@pytest.mark.parametrize("mass,stiffness,restitution,delay", [(0.6, 0.5, 0.70, 0.06), (0.6, 0.6, 0.75, 0.05)])
def test_a_soft_light_lively_fruit_after_a_measured_fruit_is_not_its_rebound(mass, stiffness, restitution, delay):
    """A lighter fruit mimics the pulse of a rebound of the fruit before it when it is also about r^1.5 softer (0.6
    of the mass, 0.5–0.7 of the stiffness: a lot's soft tail, the fruit grading exists to find), and lively, it
    is improbable as a new fruit: every test rebound_of_a_rebound asked of the candidate passes (found by a
    review).  What the flight would then say of the parent is false: the parent was measured as the fruit it is,
    and read at the slower speed the flight implies it would need a fruit about 2 times stiffer than the lot.  The
    parent must look like such a rebound: here it does not, so the new fruit stays a new fruit."""
    from fruitimpact.signals.rebounds import EXPECTED_RATIO, NEW_FRUIT, SLOW_PARENT_RATIO, rebound_of_a_rebound
    from fruitimpact.signals.rebounds.lane import _as_lane_rebound, lane_fruit
    from fruitimpact.signals.rebounds.measured import _hypothesis

    fruit = _lane_fruit()
    before = impact(mass=MASS, restitution=0.57)
    parent = summary(before, 1.0, 30, V_LINE)
    soft = summary(impact(mass=mass * MASS, stiffness=stiffness * STIFFNESS, restitution=restitution),
                   parent.separation + delay, 31)
    evidence = _hypothesis(soft, parent)
    # every test on the candidate passes: the same fruit as the parent on the speed-free tests, improbable as a
    # new fruit, landing when the parent would have moved at a rebound's share of V
    assert all(v <= 1.0 for k, v in evidence["deviations"].items() if k != "flight"), evidence
    lane = lane_fruit(fruit)
    assert _as_lane_rebound(soft, fruit, lane, V_LINE, EXPECTED_RATIO * lane.restitution)["new_fruit2"] > 11.345
    share = G * delay / 2.0 / evidence["speed_ratio"] / V_LINE
    assert SLOW_PARENT_RATIO[0] < share < SLOW_PARENT_RATIO[1]
    # the parent is what decides: a measured fruit, far from a rebound at that share of V
    parent_test = _as_lane_rebound(parent, fruit, lane, V_LINE, share)
    assert parent_test["rebound2"] > parent_test["new_fruit2"]
    assert rebound_of_a_rebound(soft, [parent], fruit, V_LINE, 1.0) is NEW_FRUIT


def test_a_lane_that_has_shown_no_rebound_needs_a_clear_one():
    """Fruit landing on a pad (or brush, or cup) do not come back: on such a lane a contact arriving when a
    rebound could is a new fruit unless the rebound is clear.  After QUIET_LANE_FRUIT fruit without a single
    rebound a rebound must score ≤ 0.8, as on the feed's pitch; a contact at 0.8–1 is then a new fruit, said to be
    ambiguous, with the reason in its evidence; a clear rebound is still one (a pad that lets a fruit bounce is
    still seen), and a lane that has shown a rebound keeps the threshold 1."""
    from fruitimpact.signals.rebounds import QUIET_LANE_FRUIT

    parent, near, *_ = fruit_and_rebound(flight_factor=1.26)
    loose = judge(near, [parent], max_flight=1.0)
    assert loose.rebound and 0.8 < loose.evidence["score"] <= 1.0, loose.evidence
    quiet = judge(near, [parent], max_flight=1.0, quiet_fruit=QUIET_LANE_FRUIT)
    assert not quiet.rebound and quiet.ambiguous, quiet.evidence
    assert "shown no rebound" in quiet.evidence["feed_prior"]
    assert judge(near, [parent], max_flight=1.0, quiet_fruit=QUIET_LANE_FRUIT - 1).rebound
    parent, clear, *_ = fruit_and_rebound()
    assert judge(clear, [parent], max_flight=1.0, quiet_fruit=5 * QUIET_LANE_FRUIT).rebound
    analyzer = Analysis(RATE, fit=True, velocity=V_LINE).analyzer()
    analyzer._quiet = {0: 12, 1: None}  # lane 1 has shown a rebound
    assert analyzer._quiet_fruit(0) == 12 and analyzer._quiet_fruit(1) == 0 and analyzer._quiet_fruit(2) == 0


@pytest.mark.parametrize("seed", range(3))
def test_two_rebounds_landing_together_before_the_lane_has_three_fruit(seed):
    """A recording's first two fruit, whose rebounds land 0.05 ms apart: one pulse carrying both impulses and a
    rebound's restitution.  With two measured fruit the lane's spread of e is not measured, so a lot's (0.06: the
    damping factor varies 20–30 % between fruit) stands in: the pair is found (rebounds.rebounds_landed_together),
    one overlap, a rebound, no firmness, where it had been a new fruit graded.  A typical new fruit landing there
    alone stays a fruit."""
    rng = np.random.default_rng(seed)
    a = impact(mass=MASS * rng.uniform(0.95, 1.05), restitution=0.6)
    b = impact(mass=0.95 * MASS, restitution=0.52)
    spin = 0.95  # a little spin (the rule expects r = 0.92 e ± 10 %)
    landing = 0.1 + a["T"] + 2 * spin * a["e"] * V_LINE / G
    onset_b = landing - b["T"] - 2 * spin * b["e"] * V_LINE / G + 5e-5
    backs = [impact(mass=f["m"], velocity=spin * f["e"] * V_LINE, c=f["c"]) for f in (a, b)]

    def reports(onsets, impacts):
        x = _signal(onsets, impacts, int(0.45 * RATE), seed=seed)
        return _reports(x + np.random.default_rng(100 + seed).normal(0.0, 0.02 * a["F"], x.size))

    first, second, both = reports([0.1, onset_b, landing, landing + 5e-5], [a, b, *backs])
    assert not first["rebound"] and not second["rebound"]
    assert both["status"] == "overlap" and both["rebound"], both["message"]
    assert both["message"].startswith("two rebounds landing together") and math.isnan(both["firmness_c"])
    assert not both["rebound_ambiguous"], both["rebound_evidence"]
    new = reports([0.1, onset_b, landing], [a, b, impact(mass=MASS, restitution=0.58)])[-1]
    assert new["status"] == "ok" and not new["rebound"], new["message"]


@pytest.mark.parametrize("seed", [0, 4, 6, 7])
def test_a_damped_fruit_and_a_due_rebound_three_ms_later_are_each_measured(seed):
    """A damped fruit (e 0.47, 200 g) lands 3 ms before the previous fruit's rebound (a line recording of
    tests/linegen.py, grades at seed 12, in these numbers): the joint fit of two pulses has a valley where the
    rebound takes part of the fruit's tail (a fruit too short and too lively, the rebound 12–20 % high, at seeds 6
    and 7 here, once reported a second fruit).  The right pair leaves only the noise (χ² within 2 sd of the
    samples'), the wrong one does not: a fit is taken early only when its χ² is the noise's, and the pair with the
    expected rebound is started beside every duration of the fruit.  The fruit's peak within 1 % of the exact
    engine's (the issue's goal), the rebound's within 2 % (a piece fixed to worse than ±1 % is reported as an
    overlap, its peak then what the samples hold), a rebound of its parent."""
    rng = np.random.default_rng(seed)
    fruit = [impact(mass=MASS * rng.uniform(0.8, 1.05), restitution=rng.uniform(0.55, 0.65)) for _ in range(6)]
    parent = impact(mass=0.155, stiffness=0.912e6, restitution=0.619)
    spin = 0.97
    back = impact(mass=0.155, stiffness=0.912e6, c=parent["c"], velocity=spin * parent["e"] * V_LINE)
    landing = 0.7 + parent["T"] + 2 * spin * parent["e"] * V_LINE / G
    damped = impact(mass=0.2, stiffness=1.05e6, restitution=0.472)
    onsets = [0.1 + 0.1 * k for k in range(6)] + [0.7, landing - 2.96e-3, landing]
    x = _signal(onsets, [*fruit, parent, damped, back], int(0.95 * RATE), seed=seed)
    reports = _reports(x + np.random.default_rng(100 + seed).normal(0.0, 0.0093 * damped["F"], x.size))
    new, rebound = reports[-2:]
    assert new["status"] == "ok" and not new["rebound"], new["message"]
    assert new["peak_force"] == pytest.approx(damped["F"], rel=0.01)
    assert rebound["rebound"] and rebound["rebound_of"] == reports[-3]["sequence"], rebound["rebound_evidence"]
    assert rebound["peak_force"] == pytest.approx(back["F"], rel=0.02)


def _pad_then(contacts_after, seed=0, bounce_first=False):
    """Eleven fruit 0.3 s apart on a lane whose fruit do not come back (a pad), the first one bouncing once if
    ``bounce_first``, the last a heavy one (1.6 times the lot's mass: its rebound carries a fruit's impulse, so
    only the rebound tests can call it one); then the (onset offset after the 11th fruit's separation, impact) of
    ``contacts_after``."""
    rng = np.random.default_rng(seed)
    fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(10)]
    fruit.append(impact(mass=1.6 * MASS, restitution=0.57))
    onsets, impacts = [0.1 + 0.3 * k for k in range(11)], list(fruit)
    if bounce_first:
        first = fruit[0]
        speed = 0.95 * first["e"] * V_LINE
        onsets.append(0.1 + first["T"] + 2 * speed / G)
        impacts.append(impact(mass=first["m"], velocity=speed, c=first["c"]))
    last_end = onsets[10] + fruit[10]["T"]
    for delay, imp in contacts_after(fruit[10]):
        onsets.append(last_end + delay)
        impacts.append(imp)
    order = np.argsort(onsets)
    return _reports(_signal([onsets[k] for k in order], [impacts[k] for k in order], int(3.6 * RATE), seed=seed))


def test_a_lane_of_fruit_that_never_came_back_is_told_by_the_analysis():
    """Through the analysis (its own tally of each lane's fruit and rebounds): eleven fruit that never came back,
    then a contact that is the eleventh's rebound except for a flight 26 % longer than predicted (its score
    0.8–1): a new fruit, said to be ambiguous, "shown no rebound" in its evidence.  The same contact on a lane
    whose first fruit bounced is that fruit's rebound.  And the near call itself counts against the lane being
    quiet: a second such contact after it is a rebound again."""
    def late_rebound(last, factor=1.26):
        speed = 0.95 * last["e"] * V_LINE
        return [(2 * speed / G * factor, impact(mass=last["m"], velocity=speed, c=last["c"]))]

    quiet = _pad_then(late_rebound)[-1]
    assert not quiet["rebound"] and quiet["rebound_ambiguous"], quiet["rebound_evidence"]
    assert "shown no rebound" in quiet["rebound_evidence"]["feed_prior"]
    plate = _pad_then(late_rebound, bounce_first=True)[-1]
    assert plate["rebound"], plate["rebound_evidence"]

    def twice(last):
        (delay, back), = late_rebound(last)
        again = impact(mass=last["m"], velocity=0.95 * back["e"] * back["V"], c=last["c"])
        return [(delay, back), (delay + back["T"] + 2 * again["V"] / G * 1.2, again)]

    near, after = _pad_then(twice)[-2:]
    assert not near["rebound"] and near["rebound_ambiguous"]
    assert after["rebound"], after["rebound_evidence"]


def test_a_hidden_fruits_rebound_carries_the_speed_its_flight_shows():
    """A fruit hidden in an overlap (it landed 1.5 ms before another) and its rebound: the analysis judges the
    rebound the hidden fruit's and keeps, for its next bounce, the speed it landed at, read from its flight as
    g · flight/2: within 3 % of the speed the signal was built with (0.95 e V; the hidden fruit's separation is
    estimated from the lane's median duration, ~1 %, and the onset is read at the noise's threshold).  That
    rebound's own bounce is then due at its flight and found as its rebound, with m and K split at the speed
    ratio times that speed: its mass within 5 % of the fruit's."""
    for seed in range(2):
        rng = np.random.default_rng(4)
        fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(6)]
        hidden, beside = impact(restitution=0.57), impact(mass=0.7 * MASS)
        back = impact(velocity=0.95 * hidden["e"] * V_LINE, c=hidden["c"])
        landing = 0.8 + hidden["T"] + 2 * back["V"] / G
        bounce = impact(velocity=0.95 * back["e"] * back["V"], c=hidden["c"])
        landing2 = landing + back["T"] + 2 * bounce["V"] / G
        analyzer = Analysis(RATE, fit=True, velocity=V_LINE).analyzer()
        x = _signal([0.1 + 0.1 * k for k in range(6)] + [0.8, 0.8015, landing, landing2],
                    [*fruit, hidden, beside, back, bounce], int(1.2 * RATE), seed=seed)
        reports = [report for i in detect(x, RATE) for report in analyzer.reports(i)]
        overlap, rebound, second = reports[-3:]
        assert overlap["status"] == "overlap"
        assert rebound["rebound"] and rebound["rebound_evidence"].get("unmeasured_parent") == overlap["sequence"]
        (kept,) = [s for s in analyzer._history[0] if s.sequence == rebound["sequence"]]
        assert kept.velocity == pytest.approx(back["V"], rel=0.03)
        assert second["rebound"] and second["rebound_of"] == rebound["sequence"], second["rebound_evidence"]
        assert second["mass"] == pytest.approx(MASS, rel=0.05)


def test_a_rebound_found_to_have_been_one_gives_the_feed_prior_its_last_fruit_back():
    """With the feed known (--pitch), each contact is judged against the phase of the lane's last fruit.  A rebound
    taken for a fruit moved that phase to its own onset, off the pitch; once its bounce shows it was a rebound
    (``rebound_of_a_rebound``, found by a review), the fruit before it is the last fruit again, so a fruit landing
    one pitch after that one is on the pitch (the stricter rebound threshold 0.8), not 0.45 pitch off it.  Its
    grade stands (not revised).  A fruit landed since keeps its place."""
    from fruitimpact.signals.rebounds.measured import _threshold

    pitch = 0.125
    analyzer = Analysis(RATE, fit=True, velocity=V_LINE, pitch=pitch).analyzer()
    analyzer._fruit_onsets = {0: [(4, 1.0 - pitch), (6, 1.0), (7, 1.0 + 0.055)]}  # #7: a rebound taken for a fruit
    next_fruit = summary(impact(), 1.0 + pitch, 9)
    assert _threshold(next_fruit, analyzer._last_fruit(0), pitch)[0] == 1.25  # 0.56 pitch after #7: off the pitch
    analyzer._not_a_fruit(0, 7)
    assert analyzer._last_fruit(0) == 1.0 and analyzer._fruit_onsets[0][-1] == (6, 1.0)
    assert _threshold(next_fruit, analyzer._last_fruit(0), pitch)[0] == 0.8  # one pitch after #6: on it
    analyzer._not_a_fruit(0, 4)  # not the last fruit any more: the last fruit stays, #4 is forgotten
    assert analyzer._last_fruit(0) == 1.0 and analyzer._fruit_onsets[0] == [(6, 1.0)]
    analyzer._not_a_fruit(0, 6)
    assert analyzer._last_fruit(0) is None
    # a contact found to be a rebound while a later fruit is the last never comes back (found by a review)
    analyzer._fruit_onsets = {0: [(4, 1.0 - pitch), (6, 1.0), (7, 1.055)]}
    analyzer._not_a_fruit(0, 6)
    analyzer._not_a_fruit(0, 7)
    assert analyzer._last_fruit(0) == 1.0 - pitch


def test_the_analysis_gives_the_feed_prior_its_last_fruit_back_when_a_bounce_shows_a_rebound(monkeypatch):
    """The wiring of the test above (a review found that removing the call left it passing): three fruit on the
    feed's pitch, and the third contact taken for the bounce of the second (``rebound_of_a_rebound`` stubbed to say
    so, with the evidence a real verdict carries): the lane's last fruit is then the first fruit again, the second's
    onset forgotten; without the stub the third is the last fruit."""
    import fruitimpact.signals.analysis as analysis_module
    from fruitimpact.signals.rebounds import NEW_FRUIT, Verdict

    pitch = 0.1
    fruit = [impact(), impact(mass=1.05 * MASS), impact(mass=0.95 * MASS)]
    x = _signal([0.1, 0.1 + pitch, 0.1 + 2 * pitch], fruit, int(0.45 * RATE))

    def run():
        analyzer = Analysis(RATE, fit=True, velocity=V_LINE, pitch=pitch).analyzer()
        reports = [report for i in detect(x, RATE) for report in analyzer.reports(i)]
        return analyzer, reports

    analyzer, reports = run()
    assert [r["rebound"] for r in reports] == [False, False, False]
    assert analyzer._last_fruit(0) == pytest.approx(reports[2]["start_time"])

    def stub(candidate, parents, lane_fruit, velocity, max_flight):
        if candidate.sequence != 2:
            return NEW_FRUIT
        evidence = {"kind": "rebound_of_a_rebound", "parent": 1, "score": 0.5, "threshold": 1.0, "landing_speed": 0.3,
                    "reason": "stubbed: the bounce of #1"}
        return Verdict(True, 1, True, 0.5, evidence)

    monkeypatch.setattr(analysis_module, "rebound_of_a_rebound", stub)
    monkeypatch.setattr(analysis_module, "QUIET_LANE_FRUIT", 100)  # three fruit: not a quiet lane yet either way
    analyzer, reports = run()
    assert reports[2]["rebound"] and reports[2]["rebound_of"] == 1
    assert analyzer._last_fruit(0) == pytest.approx(reports[0]["start_time"])


def _bounce_of(imp, velocity):
    """The same fruit (mass, stiffness, damping factor c) landing again at ``velocity`` [m/s]."""
    return impact(mass=imp["m"], stiffness=imp["K"], c=imp["c"], velocity=velocity)


def test_a_rebound_whose_parent_an_earlier_bounce_claimed_reclaims_it_when_that_bounce_has_another_parent():
    """Each contact rebounds once, and a rebound is judged when it lands: a bounce C of an earlier rebound Q that
    lands where fruit P's rebound was due may take P (its better score; seen on tests/linegen.py's chain10 at
    seed 28: 0.44 against P, 0.80 against Q).  P's own rebound D, landing later, then found P taken and was graded
    as a new fruit.  The pairing D → P, C → Q explains both contacts by the same tests (each within its
    tolerance), so D is P's rebound and C is re-read as Q's (rebounds.reassigned).  Without a free parent for C
    (Q's bounce already seen) there is no such pairing, and D stays a new fruit."""
    g = impact()
    q_pulse = _bounce_of(g, g["e"] * V_LINE)  # G's rebound Q, and Q's own bounce C (the same fruit again)
    g_sum = summary(g, 0.0, 0, V_LINE)
    q_onset = g_sum.separation + 2 * g["e"] * V_LINE / G
    q_sum = summary(q_pulse, q_onset, 1, g["e"] * V_LINE)
    c_pulse = _bounce_of(g, q_pulse["e"] * q_pulse["V"])
    c_sum = summary(c_pulse, q_sum.separation + 2 * q_pulse["e"] * q_pulse["V"] / G, 3, q_pulse["e"] * q_pulse["V"])
    p = impact(mass=0.9 * MASS, restitution=0.6)
    p_sum = summary(p, q_onset + 0.01, 2, V_LINE)
    d_sum = summary(_bounce_of(p, p["e"] * V_LINE), p_sum.separation + 2 * p["e"] * V_LINE / G, 4)
    assert judge(c_sum, [g_sum.taken(by=1), q_sum], max_flight=1.0).rebound  # the premise: C is Q's bounce
    earlier = [g_sum.taken(by=1), q_sum, p_sum.taken(by=3), c_sum]
    verdict = judge(d_sum, earlier, max_flight=1.0)
    assert verdict.rebound and verdict.parent == 2 and verdict.reassigned == (3, 1), verdict.evidence
    assert verdict.evidence["reassigned"]["score"] <= 1.0 and verdict.evidence["score"] <= 1.0
    assert not judge(d_sum, [g_sum.taken(by=1), q_sum.taken(by=9), p_sum.taken(by=3), c_sum], max_flight=1.0).rebound
    assert not judge(d_sum, [g_sum.taken(by=1), q_sum, p_sum.taken(), c_sum], max_flight=1.0).rebound  # unnamed
    # the analysis keeps the books: Q is now taken by C, whose speed is Q's r V (its own bounce is expected there)
    from fruitimpact.signals.analysis import LineAnalyzer

    history = list(earlier)
    LineAnalyzer._reassign(history, verdict)
    assert history[1].rebound_taken and history[1].taken_by == 3
    assert history[3].velocity == pytest.approx(verdict.evidence["reassigned"]["speed_ratio"] * q_sum.velocity)
    assert history[3].velocity == pytest.approx(q_pulse["e"] * q_pulse["V"], rel=0.03)


def test_the_rebound_of_a_fruit_read_together_with_a_rebound_is_judged_against_the_fruit_alone():
    """A new fruit and a due rebound landing within a fraction of a millisecond are one pulse even to a joint
    fit; when the lane's fruit spread widely it can pass as one fruit, its impulse and peak those of both.  The
    fruit's own rebound then fails against that contact (its speed ratio, read from the impulses, 1/(1 + I_R/I_F)
    too low) and was graded as a new fruit (tests/linegen.py's chain10 at seeds 27 and 32).  Against the fruit
    alone (the due rebound's predicted impulse and peak taken out, rebounds.without_held) it passes: a rebound,
    said to be ambiguous, naming the rebound held.  Not when that rebound was seen elsewhere (its parent taken),
    and a lone fruit whose due rebound landed elsewhere is judged as measured (its rebound passes the plain tests
    first).  New fruit of every mass, stiffness and e landing about when the fruit's rebound would: the
    alternative takes only light, soft and lively look-alikes of its rebound, whose pulses are the fruit's at
    e V within the tolerances; a fruit cannot come back faster than e V, so none heavier or stiffer (a review had
    found a 0.55·MASS fruit of e 0.72 taken, r = 1.23 e, before r was bounded)."""
    from dataclasses import replace

    from fruitimpact.signals.rebounds import expected_rebound, rebound_pulse

    earlier = impact(mass=1.1 * MASS, restitution=0.6)
    e_sum = summary(earlier, 0.0, 0, V_LINE)
    fruit = impact(mass=0.8 * MASS, restitution=0.57)
    held = (rebound_pulse(e_sum)[0], math.exp(expected_rebound(e_sum)["log_peak"]), 0)
    onset = e_sum.separation + 2 * earlier["e"] * V_LINE / G
    alone = summary(fruit, onset, 1, V_LINE)
    both = replace(alone, impulse=alone.impulse + held[0], peak_force=alone.peak_force + held[1])
    flight = 2 * fruit["e"] * V_LINE / G
    back = summary(_bounce_of(fruit, fruit["e"] * V_LINE), alone.separation + flight, 2)
    assert not judge(back, [e_sum, both], max_flight=1.0).rebound  # the failure it mends
    verdict = judge(back, [e_sum, replace(both, held=held)], max_flight=1.0)
    assert verdict.rebound and verdict.parent == 1 and verdict.ambiguous, verdict.evidence
    assert verdict.evidence["held_rebound"]["rebound_of"] == 0
    assert not judge(back, [e_sum.taken(by=9), replace(both, held=held)], max_flight=1.0).rebound  # seen elsewhere
    plain = judge(back, [e_sum, replace(alone, held=held)], max_flight=1.0)
    assert plain.rebound and plain.parent == 1 and "held_rebound" not in plain.evidence
    taken = 0
    for mass in np.linspace(0.3, 0.9, 13):
        for stiffness in (0.5, 0.7, 1.0, 1.4):
            for e in np.linspace(0.45, 0.8, 8):
                for late in (0.8, 1.0, 1.2):
                    new = summary(impact(mass=mass * MASS, stiffness=stiffness * STIFFNESS, restitution=e),
                                  alone.separation + late * flight, 2)
                    verdict = judge(new, [e_sum, replace(both, held=held)], max_flight=1.0)
                    if verdict.rebound and verdict.evidence.get("held_rebound") is not None:
                        taken += 1
                        # only a light, soft look-alike of the fruit's rebound (F's own rebound is 0.8·MASS at
                        # 0.57 V: its pulse that of a fruit of about half the mass and stiffness at V)
                        assert mass <= 0.5 and stiffness <= 0.7, (mass, stiffness, e, late, verdict.evidence)
                        assert verdict.evidence["speed_ratio"] <= 1.1 * fruit["e"] * 1.02  # never faster than e V
    assert taken >= 3  # the scan reaches the look-alikes: the checks ran


def test_a_fruit_of_the_lot_landing_off_a_hidden_fruits_rebound_flight_is_not_excluded_as_a_new_fruit():
    """Beyond the ambiguous band a hidden fruit's rebound is taken only when no fruit of the lot could have made
    the pulse.  A review found the restitution and stiffness tests alone excluded a real apple: 150 g, E 2.5 MPa
    (0.71 of the lane's stiffness), e 0.70, all inside a lot's ranges, landing at 0.6–0.7 or 1.4 times the hidden
    fruit's predicted flight (score 1.27–1.46, 4.7 sd from a new fruit): the lane's spreads of e and stiffness,
    from a few fruit, understate a lot's.  Its impulse is a fruit's (within 3 sd of the lane's), so it is a new
    fruit; a rebound carries about 0.3–0.6 of a fruit's impulse, which no fruit of the lot does
    (``rebounds.lane.impulse_distance``)."""
    from fruitimpact.signals.rebounds import judge_unmeasured

    fruit = _lane_fruit()
    hidden = impact(restitution=0.57)
    left = 1.0 + hidden["T"]
    flight = 2 * 0.92 * hidden["e"] * V_LINE / G
    apple = impact(mass=0.150, stiffness=0.71 * STIFFNESS, restitution=0.70)
    for late in (0.6, 0.65, 0.7, 1.4):
        verdict = judge_unmeasured(summary(apple, left + late * flight, 99), 42, 1.0, fruit, V_LINE)
        assert not verdict.rebound, (late, verdict.evidence)


def test_a_heavy_fruit_on_a_lane_whose_fruit_never_rebound_is_not_flagged():
    """On a lane whose first ``QUIET_LANE_FRUIT`` fruit showed no rebound at all (a pad, a brush or a cup stops
    them), no rebound is expected to land: a fruit 1.45 times the lot's mass (2.5 sd, where the last fruit's rebound
    would have been due on a plate) is graded without the "perhaps a fruit and a rebound" flag that the same fruit
    gets on a lane that has shown rebounds (test above)."""
    from fruitimpact.signals.rebounds import QUIET_LANE_FRUIT

    rng = np.random.default_rng(7)
    count = QUIET_LANE_FRUIT + 2
    fruit = [impact(mass=MASS * rng.uniform(0.9, 1.1), restitution=rng.uniform(0.55, 0.6)) for _ in range(count)]
    onsets = [0.1 + 0.1 * k for k in range(count)]
    last = fruit[-1]
    landing = onsets[-1] + last["T"] + 2 * last["e"] * V_LINE / G  # where its rebound would land on a plate
    x = _signal([*onsets, landing - 5e-5], [*fruit, impact(mass=1.45 * MASS, restitution=0.57)],
                int((landing + 0.1) * RATE), seed=7)
    x = x + np.random.default_rng(107).normal(0.0, 0.02 * fruit[0]["F"], x.size)
    reports = _reports(x)
    assert len(reports) == count + 1 and not any(r["rebound"] for r in reports)
    assert reports[-1]["status"] == "ok" and not reports[-1]["rebound_ambiguous"], reports[-1]["message"]
