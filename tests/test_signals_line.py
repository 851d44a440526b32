"""Sorting lines the project's own ``synth`` does not make (issue 13, items 5 and 6).

The recordings come from ``tests/linegen.py``, an independent generator (its own Hunt–Crossley integration with
SciPy, its own feed, rebound and sensor models; it imports nothing from fruitimpact).  Each scenario is written
to a file and analysed by the command line as a user would (``fruitimpact analyze FILE --json --fit
--drop-height H --hum F …``), then scored against the generator's truth with ``linegen.score``.

The first group of tests checks the generator itself against physics it does not use to compute (the Hertz
closed forms, the Hunt–Crossley first integral, the impulse–momentum theorem, the ballistic flight), and the
scorer against hand-made reports, so that a failing scenario test points at the analysis, not at the truth.

The goals are the issue's, for every scenario, with the reasons for each tolerance:

* recall 100 % and 0 extra: every contact is a pulse of tens of newtons (second rebounds ≥ ~20 N) against a
  noise σ of ~1 N, 20–130 σ: a detector at 6 σ must find all of them and invent none.  Contacts that overlap (a rebound
  landing on the next fruit) count as found when an "overlap" report covers them (item 2).
* 0 fruit taken for rebounds and 0 rebounds taken for fruit: a rebound is the same fruit after a flight of
  2 e V / g (±10 % for spin and off-axis bounce) at e V less a few %: that is decidable from the previous
  impact's own fit; a fruit fed by the chain is not (item 1).
* peak force within 1 % (p95): at 1 % noise and 20 kHz the peak of a ~2 ms rising pulse is estimated to a few
  tenths of a percent; the 2–3 kHz plate resonance with DC gain 1 changes F_max by (ω_pulse/ω_n)² ≈ 0.2 %.
* time to peak within 2 % (p95): the onset extrapolated from the Hertz rising edge (F ∝ t^1.5) and the peak of
  a smooth maximum give t_c to ~0.6 % sd at this noise: 2 % is ~3 sd.
* fitted stiffness within 2 % (median) and 5 % (p95): the Cramér–Rao limit of k_c for one pulse at 1 % noise
  is ~1.1 %; 5 % is the tail with hum residuals and ringing on top.
* restitution within 0.03 (p95): e follows from the impulse m (1 + e) V with V known from the drop height;
  0.03 covers the tail of the fit's e at this noise (its sd is ~0.005).

Many scenario tests fail before issue 13's rebound logic lands: the detector takes a fruit fed at 7–10/s for the
rebound of the one before (the default rebound window is 2V/g + 10 ms ≈ 0.21 s at 5 cm), and fits it at e V.
That is the bug the issue is about; the goals are not relaxed for it.
"""

from __future__ import annotations

import ast
import dataclasses
import json
import math
from pathlib import Path

import linegen as lg
import numpy as np
import pytest
from conftest import G
from scipy.integrate import quad
from scipy.optimize import brentq

from fruitimpact.signals.read import read_recording

#: Why each goal has its tolerance (printed with a failure).
REASONS = {
    "recall": "every contact is 20-130 noise sd high: all must be found (overlaps count when an overlap report "
              "covers them)",
    "extra": "no pulse is invented at 6 sd",
    "fruit_taken_for_rebounds": "a fruit is a rebound only at the flight 2eV/g (±10 %) with the same fruit's pulse",
    "rebounds_taken_for_fruit": "a rebound arrives after its parent's predicted flight, at e V",
    "peak_force_p95": "1 % noise, 20 kHz, DC-gain-1 resonance: F_max to a few 0.1 %",
    "time_to_peak_p95": "Hertz-edge onset and smooth peak: t_c sd ~0.6 %",
    "stiffness_median": "Cramér–Rao limit of k_c at 1 % noise ~1.1 %",
    "stiffness_p95": "tail of the k_c fit with hum residual and ringing",
    "restitution_p95": "e from the impulse m(1+e)V with V known: sd ~0.005",
}


# ---------------------------------------------------------------------------------------------------------------
# The generator against independent physics
# ---------------------------------------------------------------------------------------------------------------

def test_generator_imports_nothing_from_fruitimpact():
    """Independence: linegen.py must not import the package it tests."""
    tree = ast.parse(Path(lg.__file__).read_text())
    names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    names += [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    assert not [n for n in names if n.split(".")[0] == "fruitimpact"], names


@pytest.mark.parametrize("damping", [0.0, 1e-7])
def test_undamped_limit_is_the_hertz_impact(damping):
    """c → 0: e → 1 and the classic Hertz impact (Johnson, Contact Mechanics §11.4): δ_m = (5 m V²/(4K))^0.4,
    F_max = K δ_m^1.5, time to peak = 1.4716 δ_m / V (= δ_m/V ∫₀¹ dx/√(1 − x^2.5)), contact twice that."""
    K, m, V = 1.0e6, 0.2, 1.0
    p = lg.contact(K, m, damping, V)
    dm = (5.0 * m * V ** 2 / (4.0 * K)) ** 0.4
    integral = quad(lambda x: 1.0 / math.sqrt(1.0 - x ** 2.5), 0.0, 1.0, limit=200)[0]
    assert p.restitution == pytest.approx(1.0, abs=1e-6)
    assert p.max_deflection == pytest.approx(dm, rel=1e-7)
    assert p.peak_force == pytest.approx(K * dm ** 1.5, rel=1e-7)
    assert p.time_to_peak == pytest.approx(integral * dm / V, rel=1e-7)
    assert p.time_to_peak == pytest.approx(1.4715 * dm / V, rel=1e-4)
    assert p.duration == pytest.approx(2.0 * p.time_to_peak, rel=1e-7)


@pytest.mark.parametrize("cv", [0.3, 0.7, 1.1, 1.7])
def test_restitution_and_deflection_follow_the_hunt_crossley_first_integral(cv):
    """m v dv/dδ = −K δ^1.5 (1 + c v) integrates once (Hunt & Crossley 1975) to
    c V − ln(1 + c V) = −c V_out − ln(1 − c V_out) (separation, δ = 0) and
    δ_m^2.5 = 2.5 m/(K c²) (c V − ln(1 + c V)) (maximum compression): independent of the integrator."""
    K, m, V = 9.0e5, 0.18, 0.99
    c = cv / V
    p = lg.contact(K, m, c, V)
    lhs = cv - math.log1p(cv)
    b = brentq(lambda b: -b - math.log1p(-b) - lhs, 1e-12, 1.0 - 1e-15, xtol=1e-15)
    assert p.restitution == pytest.approx(b / cv, rel=1e-7)
    assert p.max_deflection == pytest.approx((2.5 * m / (K * c ** 2) * lhs) ** 0.4, rel=1e-7)
    # the same fruit (same c) rebounding at the lower speed e V has a higher restitution
    assert lg.contact(K, m, c, p.exit_velocity).restitution > p.restitution


@pytest.mark.parametrize("law", ["lankarani-nikravesh", "flores"])
def test_the_restitution_constant_damping_laws_keep_e_at_every_speed(law):
    """``damping_law`` of a scenario: with c = χ(e₀)/v (Lankarani & Nikravesh 1990; Flores et al. 2011) the
    contact's x = c v is χ at every speed, and Hunt–Crossley's e depends on x alone (the first integral above),
    so a rebound has its fruit's restitution; e₀ is the fruit's Hunt–Crossley e at the line's speed V, and
    Flores's χ was fitted to return e ≈ e₀ (within a few % for e₀ ≥ 0.4), Lankarani–Nikravesh's only near 1."""
    K, m, V = 1.1e6, 0.21, 0.99
    fruit = {"damping": 1.1, "e0": lg.contact(K, m, 1.1, V).restitution}
    damping = lg.DAMPING_LAWS[law]
    e_line = lg.contact(K, m, damping(fruit, V), V).restitution
    assert lg.contact(K, m, damping(fruit, 0.5 * V), 0.5 * V).restitution == pytest.approx(e_line, rel=1e-7)
    if law == "flores":
        assert e_line == pytest.approx(fruit["e0"], rel=0.05)
    else:
        assert e_line > fruit["e0"]  # derived for e near 1: it under-damps a soft fruit


def test_impulse_of_the_tabulated_force_is_m_one_plus_e_v():
    """Impulse–momentum: ∫F dt over the contact = m (V + V_out) = m (1 + e) V, for the force table the
    recordings are built from (checks the table, not only the integrator's end state)."""
    K, m, c, V = 1.1e6, 0.21, 1.1, 0.99
    p = lg.contact(K, m, c, V)
    assert np.trapezoid(p.table_f, p.table_t) == pytest.approx(m * (1.0 + p.restitution) * V, rel=1e-6)
    assert 0.45 < p.restitution < 0.70
    assert p.peak_force == pytest.approx(p.table_f.max(), rel=1e-9)


@pytest.mark.parametrize("exponent", [1.3, 1.7])
def test_a_force_law_other_than_hertz_conserves_energy_and_keeps_hertz_force_at_the_reference(exponent):
    """The generator's fruit whose force law is K_n δ^n (``force_exponent``, a fruit that is not a homogeneous
    Hertz sphere: Blahovec, Int. Agrophys. 10(2):89–95, 1996, finds exponents between 1 and 2): undamped, the
    fruit leaves at the speed it came (e = 1 to the integrator's 1e-8) and compresses to the closed form of the
    energy balance, ½ m V² = K_n δ^(n+1)/(n+1), with K_n δ_r^n = K δ_r^1.5 at δ_r, Hertz's compression at the
    reference speed (to 1e-6: the table's resolution of the maximum).  A rebound keeps its fruit's law: at half the
    speed with the fruit's reference, the force at δ_r is still Hertz's."""
    K, m, V = 1.1e6, 0.21, 0.99
    hertz = lg.hertz_max_deflection(K, m, V)
    k_law = K * hertz ** (1.5 - exponent)
    p = lg.contact(K, m, 0.0, V, exponent=exponent)
    assert p.restitution == pytest.approx(1.0, abs=1e-8)
    assert p.max_deflection == pytest.approx(((exponent + 1) * m * V ** 2 / (2 * k_law)) ** (1 / (exponent + 1)),
                                             rel=1e-6)
    assert p.K == K  # the truth keeps the Hertz stiffness the fruit's modulus gives
    slow = lg.contact(K, m, 0.0, 0.5 * V, exponent=exponent, reference_velocity=V)
    assert slow.peak_force == pytest.approx(k_law * slow.max_deflection ** exponent, rel=1e-6)
    # damped: the peak event (dF/dt = 0 with its c·δ̈ term) is the force table's maximum
    damped = lg.contact(K, m, 1.1, V, exponent=exponent)
    assert damped.peak_force == pytest.approx(damped.table_f.max(), rel=1e-9)
    assert 0.3 < damped.restitution < 0.8


def test_fruit_stiffness_is_the_hertz_sphere_on_a_plate():
    """K = (4/3) E/(1 − ν²) √(d/2) [N/m^1.5]; G is standard gravity as in conftest."""
    assert lg.stiffness(3e6, 0.35, 0.08) == pytest.approx(4 / 3 * 3e6 / (1 - 0.35 ** 2) * math.sqrt(0.04))
    assert lg.G == G


def test_rebounds_follow_the_flight_of_their_parent():
    """A rebound leaves at its parent's exit speed V_up and flies 2 V_up/g (ballistic) perturbed by ±10 %; it
    lands at V_up less 0–4 % (spin), on another spot (K ±5 %), same mass and damping; pads stop rebounds."""
    _, truth = lg.generate("chain10", 12)
    contacts = truth["contacts"]
    rebounds = [c for c in contacts if c["is_rebound"]]
    assert len(rebounds) >= 12 and any(c["rebound_of"] is not None and contacts[c["rebound_of"]]["is_rebound"]
                                       for c in rebounds)  # second rebounds exist
    factors = []
    for c in rebounds:
        parent = contacts[c["rebound_of"]]
        fruit = truth["fruit"][c["fruit_id"]]
        assert parent["fruit_id"] == c["fruit_id"] and parent["end_time"] < c["start_time"]
        v_up = parent["exit_velocity"]
        flight = c["start_time"] - parent["end_time"]
        assert flight == pytest.approx(c["flight_time"], abs=1e-12)
        factors.append(flight / (2.0 * v_up / G))
        assert 0.96 - 1e-12 <= c["velocity"] / v_up <= 1.0
        assert abs(c["stiffness"] / fruit["stiffness"] - 1.0) <= 0.05 + 1e-12
        assert c["mass"] == fruit["mass"] and c["damping"] == fruit["damping"]
        assert c["restitution"] > contacts[c["rebound_of"]]["restitution"] - 0.02  # slower: more elastic
    assert 0.9 - 1e-12 <= min(factors) < 0.95 and 1.05 < max(factors) <= 1.1 + 1e-12
    _, pad = lg.generate("pad", 10)
    assert not any(c["is_rebound"] for c in pad["contacts"])


def test_chain_feed_pitch_jitter_and_close_arrivals():
    """Chain: consecutive slots are P (1 ± 2 × 8 %) apart; close arrivals land 2–20 ms after the previous
    fruit's contact ended; the recording starts with ≥ 0.1 s of quiet signal."""
    _, truth = lg.generate("close", 40)
    sc = lg.SCENARIOS["close"]
    pitch = 1.0 / sc.fruit_rate
    first = [c for c in truth["contacts"] if not c["is_rebound"]]
    assert first[0]["start_time"] >= 0.1
    closes = 0
    for a, b in zip(first, first[1:]):
        if b["close_arrival"]:
            closes += 1
            assert 0.002 <= b["start_time"] - a["end_time"] <= 0.020
        elif not a["close_arrival"]:
            assert 0.84 * pitch - 1e-12 <= b["start_time"] - a["start_time"] <= 1.16 * pitch + 1e-12
    assert closes == 2  # 5 % of 40


def test_overlaps_in_the_truth_are_symmetric_and_real():
    """A contact listed as overlapping another shares time with it on the same lane."""
    _, truth = lg.generate("chain10", 15)
    contacts = truth["contacts"]
    listed = 0
    for c in contacts:
        for j in c["overlaps"]:
            d = contacts[j]
            listed += 1
            assert c["index"] in d["overlaps"] and d["lane"] == c["lane"]
            assert c["start_time"] < d["end_time"] and d["start_time"] < c["end_time"]
    assert listed > 0


def test_resonance_discretisation_keeps_dc_gain_and_the_resonance():
    """Bilinear transform prewarped at ω_n: H(z = 1) = 1 (DC gain 1: impulses kept) and |H(e^{jω_n T})| =
    |H(jω_n)| = 1/(2ζ) exactly."""
    b, a = lg.resonance_coefficients(2500.0, 0.05, 160_000.0)
    assert b.sum() / a.sum() == pytest.approx(1.0, rel=1e-12)
    z = np.exp(1j * 2 * math.pi * 2500.0 / 160_000.0)
    h = np.polyval(b[::-1], 1 / z) / np.polyval(a[::-1], 1 / z)
    assert abs(h) == pytest.approx(1.0 / (2 * 0.05), rel=1e-9)


def test_sensor_chain_keeps_each_lanes_impulse_and_peaks():
    """Without offset, drift, hum and noise, each lane's samples sum (× 1/rate) to the sum of its contacts'
    impulses m (1 + e) V (the resonance has DC gain 1), and an isolated contact's sampled maximum is its true
    peak within 1 % (the resonance's quasi-static error ~0.2 %, sampling ≤ 0.1 %)."""
    recording, truth = lg.generate("lanes4", 3, clean=True)
    rate = truth["rate"]
    for lane in range(4):
        impulses = sum(c["impulse"] for c in truth["contacts"] if c["lane"] == lane)
        assert recording[:, lane].astype(float).sum() / rate == pytest.approx(impulses, rel=2e-4)
    for c in truth["contacts"]:
        if c["overlaps"]:
            continue
        i0, i1 = int(c["start_time"] * rate), int(c["end_time"] * rate) + 2
        assert recording[i0:i1, c["lane"]].max() == pytest.approx(c["peak_force"], rel=0.01)


def test_the_discharge_stage_is_the_first_order_high_pass_of_a_piezo_chain():
    """``discharge_time`` τ: H(s) = s/(s + 1/τ) by the bilinear transform (the impact-sensor background note's stage
    3).  Its DC gain is 0 (b sums to 0: a static force decays) and its gain at half the grid's rate is 1.  On a clean
    pad line, each lone contact of impulse I leaves the signal I/τ below where it was, within 6 % (the chain's
    own decay during the 5–9 ms contact, e^(−T/τ) ≈ 0.94–0.96, and the contact before's tail), and 3 τ later
    the undershoot has decayed to e^(−3) = 0.05 of that (< 0.08 with the contact before's own tail)."""
    b, a = lg.discharge_coefficients(0.1, 160_000.0)
    assert b.sum() == pytest.approx(0.0, abs=1e-15)
    assert abs(np.polyval(b[::-1], -1.0) / np.polyval(a[::-1], -1.0)) == pytest.approx(1.0, rel=1e-12)
    tau = 0.1
    scenario = dataclasses.replace(lg.SCENARIOS["pad"], discharge_time=tau, fruit_rate=2.0)
    recording, truth = lg.generate(scenario, 4, clean=True)
    rate = truth["rate"]
    for c in truth["contacts"][1:-1]:  # the last one: the recording ends 0.15 s after it
        before = recording[int((c["start_time"] - 1e-3) * rate), 0]
        after = recording[int((c["end_time"] + 1e-3) * rate), 0]
        assert after - before == pytest.approx(-c["impulse"] / tau, rel=0.06)
        later = recording[int((c["end_time"] + 3 * tau) * rate), 0]  # before the next fruit, 0.46–0.54 s on
        assert abs(later) < 0.08 * c["impulse"] / tau


@pytest.mark.parametrize("told", [False, True])
def test_a_line_whose_sensor_discharges_meets_the_issue_goals(cli, tmp_path, told):
    """A piezoelectric chain with τ = 0.1 s (a charge amplifier's short time constant; ``linegen``
    ``discharge_time``): each contact droops by up to I/τ, ~2 % of its peak, and the signal undershoots by that
    after it. Analysed as before this change (``--discharge-time none``), this pad line missed the issue's goals:
    fitted stiffness median 7.9 % and p95 13.6 % off (40 fruit; 0.8 % and 2.2 % restored). Told the sensor's τ
    (``--discharge-time 0.1s``), the detector restores the force, x = y + (1/τ) ∫ y dt (``signals.detect`` step 1b);
    not told, it measures τ on the lane's lone contacts from their undershoot, restores it from the first contact
    on, and each report names the τ it restored. Every goal of issue 13 item 6 is then met, and the τ measured is
    the sensor's within 15 % from the first contact and 3 % in the median (the undershoot of one contact is 2–3 N
    against a noise sd of 1 N, averaged over ~30 samples; the lane's median of ≤ 31 such)."""
    scenario = dataclasses.replace(lg.SCENARIOS["pad"], discharge_time=0.1, discharge_told=told)
    path, truth = lg.write(scenario, tmp_path, 2 * scenario.quick_size)  # p95 over 40 fruit, not the 2nd worst of 20
    options = lg.analyze_options(truth)
    assert ("--discharge-time" in options) == told
    status, out, err = cli.run("analyze", path, *options)
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    card = lg.score(reports, truth)
    missed = [f"{key} = {card[key]:.4g}" for key, ok in lg.check(card).items() if not ok]
    assert not missed, missed
    measured = [r["discharge_time"] for r in reports]
    if told:
        assert all(tau == pytest.approx(0.1, rel=1e-9) for tau in measured)  # the τ given, never re-measured
    else:
        assert all(tau == pytest.approx(0.1, rel=0.15) for tau in measured), measured
        assert float(np.median(measured)) == pytest.approx(0.1, rel=0.03)
        status, out, err = cli.run("analyze", path, *[o for o in options if o != "--json"])
        assert status == 0, err
        summary = out.splitlines()[-1]
        head = ("sensor discharge measured on each lane's contacts and restored (no --discharge-time given): "
                f"{truth['lanes'][0]} τ = ")
        assert summary.startswith(head) and summary.endswith(" s"), summary
        assert float(summary[len(head):-2]) == pytest.approx(measured[-1], rel=5e-3)


def test_a_strain_gauge_line_restores_no_discharge(cli, tmp_path):
    """The same line with a sensor that holds a static force: no contact undershoots, so no τ is shown in any
    report and the analysis is the one without step 1b (the scorecard's lines give identical tables with and
    without ``--discharge-time none``), also where the noise is not white."""
    scenario = lg.SCENARIOS["chain7"]
    path, truth = lg.write(scenario, tmp_path, 2 * scenario.quick_size)
    options = lg.analyze_options(truth)
    status, out, err = cli.run("analyze", path, *options)
    assert status == 0, err
    status, out_none, err = cli.run("analyze", path, *options, "--discharge-time", "none")
    assert status == 0, err
    assert all(json.loads(line)["discharge_time"] is None for line in out.splitlines())
    assert out == out_none
    # low-passed (--lowpass 500): the noise is correlated over ~20 samples, and a measurement's standard error taken
    # for white noise was 4–5 times too small: this line's reports had carried a τ in 71 of 79 (a review's sweep:
    # 10 of 12 recordings); the error now counts the noise's lag-1 correlation, and from 5 measurements on their
    # own scatter
    status, out, err = cli.run("analyze", path, *options, "--lowpass", "500")
    assert status == 0, err
    assert all(json.loads(line)["discharge_time"] is None for line in out.splitlines())


def test_noise_and_hum_levels():
    """White noise σ = 1 % and hum 1.5 % of the median primary peak (noisy): on the quiet start, a least-squares
    fit of offset, slope and the hum's 1st and 3rd harmonics leaves the noise σ within 10 %, and finds the hum."""
    recording, truth = lg.generate("noisy", 4)
    s = truth["sensor"]
    n = int(0.1 * truth["rate"])
    t = np.arange(n) / truth["rate"]
    w = 2 * math.pi * s["hum_frequency"]
    basis = np.column_stack([np.ones(n), t, np.sin(w * t), np.cos(w * t), np.sin(3 * w * t), np.cos(3 * w * t)])
    coef, *_ = np.linalg.lstsq(basis, recording[:n, 0].astype(float), rcond=None)
    residual = recording[:n, 0] - basis @ coef
    assert np.std(residual) == pytest.approx(s["noise_sd"], rel=0.1)
    assert math.hypot(coef[2], coef[3]) == pytest.approx(s["hum_amplitude"], rel=0.1)
    assert s["noise_sd"] == pytest.approx(0.01 * s["typical_peak"])


@pytest.mark.parametrize("fmt", ["csv", "f32", "tdms", "npy"])
def test_files_read_back_with_the_truths_lane_names(tmp_path, fmt):
    """The writers produce what the reader expects: the lane names it reports are the truth's (reports carry
    them in ``lane``), the rate and the samples are the generator's."""
    recording, truth = lg.generate("lanes4", 2)
    path = tmp_path / f"x{lg.EXTENSION[fmt]}"
    lg.write_recording(path, recording, truth["rate"], fmt)
    rec = read_recording(path, rate=None if fmt in ("csv", "tdms") else truth["rate"], lanes=4 if fmt == "f32" else 1)
    assert list(rec.lanes) == lg.lane_names(fmt, 4)
    assert rec.rate == pytest.approx(truth["rate"], rel=1e-9)
    for i, name in enumerate(rec.lanes):
        np.testing.assert_allclose(rec.lanes[name], recording[:, i], rtol=1e-7, atol=1e-6)


def _perfect_reports(truth):
    return [dict(lane=c["lane_name"], start_time=c["start_time"] + 2e-4, peak_force=c["peak_force"],
                 time_to_peak=c["time_to_peak"], contact_duration=c["contact_duration"], rebound=c["is_rebound"],
                 stiffness=c["stiffness"], restitution=c["restitution"], sequence=c["index"],
                 rebound_of=c["rebound_of"], extra_key="ignored", **{"class": c["class"]})
            for c in truth["contacts"]]


def test_score_of_a_perfect_and_of_a_spoilt_analysis():
    """The scorer: the truth as reports scores perfectly; each kind of mistake is counted where it belongs."""
    _, truth = lg.generate("chain10", 8)
    reports = _perfect_reports(truth)
    card = lg.score(reports, truth)
    assert all(lg.check(card).values()) and card["wrong_parent"] == 0, card
    contacts = truth["contacts"]
    primary = next(i for i, c in enumerate(contacts) if not c["is_rebound"] and not c["overlaps"])
    rebound = next(i for i, c in enumerate(contacts) if c["is_rebound"] and not c["overlaps"])
    spoilt = [dict(r) for r in reports]
    spoilt[primary].update(rebound=True, stiffness=2 * contacts[primary]["stiffness"])
    spoilt[rebound]["rebound"] = False
    del spoilt[-1]                                                       # one missed
    spoilt.append(dict(spoilt[0], start_time=spoilt[0]["start_time"] + 0.05))  # one invented
    card = lg.score(spoilt, truth)
    assert card["recall"] == pytest.approx((len(contacts) - 1) / len(contacts))
    assert card["extra"] == 1 and card["missed"] == 1
    assert card["fruit_taken_for_rebounds"] == 1 and card["rebounds_taken_for_fruit"] == 1
    assert card["stiffness_p95"] > 0.5 and card["stiffness_median"] == 0.0
    # an overlap report covering two contacts: both found, neither in the error statistics
    a, b = next((c, contacts[j]) for c in contacts for j in c["overlaps"] if j > c["index"])
    merged = [r for r in reports if r["sequence"] not in (a["index"], b["index"])]
    merged.append(dict(lane=a["lane_name"], start_time=a["start_time"], status="overlap", rebound=False,
                       peak_force=3 * a["peak_force"], time_to_peak=1.0,
                       contact_duration=b["end_time"] - a["start_time"]))
    card = lg.score(merged, truth)
    assert card["recall"] == 1.0 and card["extra"] == 0 and card["overlaps"] == 1
    assert card["peak_force_p95"] == 0.0 and card["time_to_peak_p95"] == 0.0


def test_grade_counts_classes_of_the_clear_fruit():
    """Grading: the class of each fruit's first contact; right/total over fruit ≥ 5 % from a threshold whose
    first contact overlaps nothing; the confusion matrix over every fruit."""
    _, truth = lg.generate("grades", 30)
    reports = _perfect_reports(truth)
    g = lg.grade(reports, truth)
    assert g["clear_accuracy"] == 1.0 and g["ungraded"] == 0
    assert sum(sum(row.values()) for row in g["confusion"].values()) == 30
    fruit = next(f for f in truth["fruit"] if not truth["contacts"][f["contacts"][0]]["overlaps"]
                 and all(abs(f["modulus"] / t - 1) >= 0.05 for t in truth["thresholds"]))
    wrong = next(k for k in truth["classes"] if k != fruit["class"])
    reports[fruit["contacts"][0]]["class"] = wrong
    assert lg.grade(reports, truth)["clear_right"] == g["clear_right"] - 1


# ---------------------------------------------------------------------------------------------------------------
# The analysis on the line scenarios
# ---------------------------------------------------------------------------------------------------------------

def _analyse(cli, tmp_path, name):
    scenario = lg.SCENARIOS[name]
    path, truth = lg.write(scenario, tmp_path, scenario.quick_size)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    return [json.loads(line) for line in out.splitlines()], truth


#: Scenarios whose goals are still open (strict xfail: this must shrink when one is met).  Empty since split pieces
#: are held to ±1 % on their peak (``analysis.PIECE_PRECISION``): chain10 and noisy, where a rebound lands on the
#: next fruit in 20–35 % of the contacts, had pieces at p95 2.5–4.5 % before.
OPEN: dict[str, str] = {}


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.xfail(name in OPEN, reason=OPEN.get(name, ""),
                                                                              strict=True))
                                  for name in lg.SCENARIOS if not lg.SCENARIOS[name].grading])
def test_line_scenario_meets_the_issue_goals(cli, tmp_path, name):
    """Every goal of issue 13 item 6 on one scenario (≥ 20 contacts); the message lists every goal missed, the
    physics behind its tolerance, and the whole scorecard."""
    reports, truth = _analyse(cli, tmp_path, name)
    card = lg.score(reports, truth)
    assert card["contacts"] >= 20
    missed = [f"{key} = {card[key]:.4g} (goal {op} {limit}: {REASONS[key]})"
              for key, (op, limit) in lg.GOALS.items() if not lg.check(card)[key]]
    assert not missed, f"{name}: " + "; ".join(missed) + f"\nscorecard: {card}"


@pytest.mark.parametrize("name, law", [("chain10", "lankarani-nikravesh"), ("chain7", "flores"), ("close", "flores")])
def test_line_of_fruit_whose_restitution_does_not_change_with_speed_meets_the_issue_goals(cli, tmp_path, name, law):
    """The same goals on lines whose fruit keep their restitution at every speed (``linegen.DAMPING_LAWS``:
    Lankarani–Nikravesh, Flores, both named by the founding paper), where the scenarios' Hunt–Crossley fruit come
    back livelier.  A rebound's damping is then not that of the same c at r V; when the rebound tests assumed it
    (x₂ = r x₁), 268 rebounds in six such recordings at benchmark size were taken for new fruit
    (``rebounds.rebound_x``)."""
    scenario = dataclasses.replace(lg.SCENARIOS[name], damping_law=law)
    path, truth = lg.write(scenario, tmp_path, scenario.quick_size)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    card = lg.score([json.loads(line) for line in out.splitlines()], truth)
    assert card["contacts"] >= 20
    missed = [f"{key} = {card[key]:.4g} (goal {op} {limit}: {REASONS[key]})"
              for key, (op, limit) in lg.GOALS.items() if not lg.check(card)[key]]
    assert not missed, f"{name}/{law}: " + "; ".join(missed) + f"\nscorecard: {card}"


def test_fruit_whose_force_law_is_not_hertz_are_graded_not_reported_as_overlaps(cli, tmp_path):
    """A fruit whose force rises as δ^1.3 instead of Hertz's δ^1.5 (``linegen`` ``force_exponent``; real fruit are
    not homogeneous spheres) leaves about 1 % of its peak that one Hertz pulse cannot fit, as much as the noise.
    A second pulse takes that up, so each contact in which a rebound was due was fitted better as two (by more
    than ``onepulse.SPLIT_GAIN``) and reported as two pulses that could not be told apart, no firmness: 13 of the
    22 fruit on this pad line (44 of 80 at benchmark size).  The lane now learns what its lone fruit leave
    (``onepulse.LaneMisfits``) and a split has to gain more than that: only the contacts before the lane has
    ``LANE_MISFITS_MIN`` behind it can still be taken for overlaps.  Every contact is found, none invented, none
    misread as a rebound.  The stiffness fitted with Hertz's law to such a pulse is off by ~4.5 % (the law's own
    error, not the line's): the issue's 2 % goal is for Hertz's fruit and is not asserted here."""
    from fruitimpact.signals.onepulse import LANE_MISFITS_MIN

    scenario = dataclasses.replace(lg.SCENARIOS["pad"], force_exponent=1.3)
    path, truth = lg.write(scenario, tmp_path, scenario.quick_size)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    card = lg.score(reports, truth)
    assert (card["recall"], card["extra"], card["fruit_taken_for_rebounds"], card["rebounds_taken_for_fruit"]) \
        == (1.0, 0, 0, 0), card
    pairs = lg.match(reports, truth)["pairs"]
    taken = [r for c, r in pairs if not c["is_rebound"] and not c["overlaps"] and r.get("status") == "overlap"]
    # only contacts judged before the lane had learnt (its first LANE_MISFITS_MIN, of which the first fruit has no
    # rebound due and the second is fitted before any other fruit was): 13 before, 2 now
    assert len(taken) <= LANE_MISFITS_MIN - 2, [r["message"] for r in taken]
    assert card["stiffness_median"] < 0.08  # Hertz's law fitted to δ^1.3: biased, not lost


@pytest.mark.parametrize("name", ["chain7", "close"])
def test_noise_alone_does_not_make_a_contact_two_pulses(cli, tmp_path, name):
    """At 3 % noise (σ = 3 % of the median fruit's peak: 2.4 N) a rebound of 35 N rises again after its top by 2σ
    of its own noise, 12–14 % of its peak: above ``onepulse.OVERLAP_FRACTION``, so it was reported as two pulses
    (3 lone contacts on chain7 at this size; on close, 3 overlaps whose start, the trigger, lay more than 1 ms after
    the onset: missed and extra).  A dip counts now only beyond ``DIP_NOISE_SD`` = 4 σ (one pulse's noise reaches
    3.7 σ at most on these lines), and a misfit only beyond 3 sd of its own χ² scatter (``MISFIT_SD``).  Every
    contact is found, none invented, and every report of a dip holds two contacts: its own and one landing within
    it or up to 2 ms after the end the detector saw (a neighbour's rise enters the window before the neighbour's
    force crosses the detector's threshold, 6 σ: 17 % of an 84 N fruit at this noise)."""
    scenario = dataclasses.replace(lg.SCENARIOS[name], noise=0.03)
    path, truth = lg.write(scenario, tmp_path, scenario.quick_size)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    card = lg.score(reports, truth)
    assert (card["recall"], card["extra"]) == (1.0, 0), card
    dips = [r for r in reports if r.get("status") == "overlap" and "falls and rises again" in r.get("message", "")]
    for r in dips:
        inside = [c for c in truth["contacts"] if c["lane_name"] == r["lane"]
                  and r["start_time"] - 1e-3 <= c["start_time"] <= r["start_time"] + r["contact_duration"] + 2e-3]
        assert len(inside) >= 2, (r["start_time"], r["message"])


def test_a_contact_the_samples_cannot_judge_says_so_where_a_rebound_was_due(cli, tmp_path):
    """At 3 % noise a small rebound (20–25 N under 2.4 N of noise, the detector's 6 σ threshold at 60 % of its
    peak) can leave neither a falling edge for the indices nor a converged fit: no pulse for the rebound tests, and
    it was reported as a new fruit (``rebound`` false) in silence.  Where a parent's rebound was due in it (its
    flight within the tolerances), the report now says it could not judge: ``rebound_ambiguous`` true, evidence
    ``judged: false`` with the parents due.  On grades at this size: 6 such contacts, every one a rebound in the
    truth, none graded."""
    scenario = dataclasses.replace(lg.SCENARIOS["grades"], noise=0.03)
    path, truth = lg.write(scenario, tmp_path, scenario.quick_size)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    unjudged = [(c, r) for c, r in lg.match(reports, truth)["pairs"]
                if (r.get("rebound_evidence") or {}).get("judged") is False]
    assert unjudged
    for contact, report in unjudged:
        assert contact["is_rebound"] and report["rebound_ambiguous"] and report["status"] != "ok", report
        assert report["rebound_evidence"]["due"] and "was due here" in report["rebound_evidence"]["reason"]
        # a fit that did not converge measured nothing: no stiffness, mass or restitution from its last iterate
        # (these had shown e = 0.10 and m = 73 g, the fit's bounds, in the web app's table)
        if report["status"] == "unfitted":
            for key in ("stiffness", "mass", "restitution"):
                assert report.get(key) is None or math.isnan(report[key]), (key, report[key])


def test_the_lanes_own_misfit_is_its_median_beyond_what_hertz_lines_leave():
    """``onepulse.LaneMisfits``: nothing until ``LANE_MISFITS_MIN`` contacts are in, then the median of the
    last ``LANE_MISFITS_KEPT`` (two fruit landing together among them do not move it) beyond
    ``HERTZ_LINE_MISFIT`` in quadrature (what plate ringing and hum leave on Hertz's own pulses); per lane."""
    from fruitimpact.signals.onepulse import HERTZ_LINE_MISFIT, LANE_MISFITS_KEPT, LANE_MISFITS_MIN, LaneMisfits

    lanes = LaneMisfits()
    for _ in range(LANE_MISFITS_MIN - 1):
        lanes.seen(0, 0.01)
    assert lanes.share(0) == 0.0
    lanes.seen(0, 0.01)
    assert lanes.share(0) == pytest.approx(math.sqrt(0.01 ** 2 - HERTZ_LINE_MISFIT ** 2))
    for _ in range(LANE_MISFITS_KEPT):
        lanes.seen(1, 0.004)
    lanes.seen(1, 0.08)  # a fruit and a rebound landing together
    assert lanes.share(1) == 0.0  # a Hertz line's ringing and hum: no force-law misfit
    lanes.seen(1, math.nan)  # a contact without a single fit leaves the lane as it was
    assert lanes.share(1) == 0.0 and lanes.share(0) > 0.0


@pytest.mark.parametrize("law, inside, outside", [("hunt-crossley", 1.0, 0.0), ("lankarani-nikravesh", 0.0, 1.0)])
def test_the_analysis_reads_the_lines_damping_law_from_its_rebounds(law, inside, outside):
    """Each clear rebound shows β = ln(x_r/x_p)/ln r (x_r = r^β x_p: 1 for Hunt–Crossley's constant c, 0 for a
    constant restitution); after a chain10 line's ~15 rebounds the range its rebounds are judged with
    (``LineAnalyzer.damping_exponent``) holds the generator's law and not the other."""
    from fruitimpact.signals.analysis import Analysis
    from fruitimpact.signals.detect import detect

    scenario = dataclasses.replace(lg.SCENARIOS["chain10"], damping_law=law)
    recording, _ = lg.generate(scenario, scenario.quick_size)
    analyzer = Analysis(scenario.rate, fit=True, velocity=scenario.velocity).analyzer()
    for impact in detect(recording[:, 0].astype(float), scenario.rate):
        analyzer.reports(impact)
    low, high = analyzer.damping_exponent()
    assert low <= inside <= high and not low <= outside <= high, (low, high)


def test_line_grading_meets_the_issue_goal(cli, tmp_path):
    """Item 5: a lot with a known lognormal modulus population, rebounds (1–2), 5 % close arrivals, hum, drift
    and 2.5 kHz ringing, analysed with one nominal diameter (lot spread 3 %: E ∝ d^−1/2 → 1.5 % sd) and ν:
    ≥ 98 % of the fruit whose true modulus lies ≥ 5 % from a threshold get the right class.  5 % is ~3 sd of
    the modulus estimate (fit ~1 % and diameter 1.5 %), so a right rebound decision leaves ~0.1 % wrong."""
    reports, truth = _analyse(cli, tmp_path, "grades")
    g = lg.grade(reports, truth)
    assert g["clear"] >= 30
    assert g["clear_accuracy"] >= lg.GRADING_GOAL, (g["clear_right"], g["clear"], g["confusion"], g["wrong"])
    # a clear fruit on which a rebound landed is told apart and graded, or is an overlap without a class (item 2:
    # a piece whose peak the samples do not fix to ±1 % gets none): never a wrong class (0 of 16 at benchmark size)
    assert g["overlapped_wrong"] == 0, (g["overlapped_clear"], g["overlapped_right"], g["confusion"])


def test_a_fruit_and_two_rebounds_within_ten_milliseconds(cli, tmp_path):
    """chain10 at seed 9 (10 fruit/s: the pitch is the rebound's flight 2eV/g) holds two contacts of three pulses.
    At 1.4987 s a fruit lands, and 6.4 and 8.4 ms later the second rebound of one fruit and the first of the next:
    the merged contact has no clean falling edge (its duration index is NaN), and the rebounds due in it were not
    looked for, so the joint fit took the two rebounds for one fruit (F 67 N: the two 38–40 N pulses).  Now the
    contact as detected bounds where a rebound may be due; both are found, as rebounds.  At 1.1994 s a fruit lands
    1.8 and 3.3 ms before two rebounds; two of the three pulses cannot be told apart, and the piece left beside
    them had absorbed part of one (F 66 N for a 39 N rebound) and was taken for a fruit: a piece fitted beside a
    pair the samples do not separate is no measurement (``analysis.reports``), so it is an overlap, never a
    fruit's grade.  Regression cases of the independent generator, scored as the scorecard scores them."""
    scenario = lg.SCENARIOS["chain10"]
    path, truth = lg.write(dataclasses.replace(scenario, seed=9), tmp_path)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    m = lg.match(reports, truth)
    report_of = {c["index"]: r for c, r in m["pairs"]}
    covered = {c["index"] for c in m["covered"]}
    for onset in (1.50509, 1.50708):  # the two rebounds behind the fruit at 1.49868
        contact = next(c for c in truth["contacts"] if abs(c["start_time"] - onset) < 5e-5)
        assert contact["is_rebound"] and contact["index"] in report_of, onset
        assert report_of[contact["index"]]["rebound"], report_of[contact["index"]]
    near = [r for r in reports if 1.199 < r["start_time"] < 1.204]
    fruit = next(c for c in truth["contacts"] if abs(c["start_time"] - 1.19942) < 5e-5)
    assert fruit["index"] in report_of or fruit["index"] in covered
    assert all(r["status"] == "overlap" or r["rebound"] for r in near[1:]), near  # the pieces after the fruit's
    card = lg.score(reports, truth)
    assert card["rebounds_taken_for_fruit"] == 0 and card["missed"] == 0, card


@pytest.mark.parametrize("name, seed, onset", [("chain10", 28, 0.62402), ("chain10", 8, 1.56479),
                                               ("chain10", 27, 3.81254),
                                               ("chain7", 26, 0.72130), ("chain10", 7, 2.49546),
                                               ("chain10", 36, 2.66313), ("lanes4", 6, 1.05291),
                                               ("grades", 9, 15.50611), ("grades", 18, 7.89466)])
def test_a_rebound_whose_parent_was_misread_is_still_a_rebound(cli, tmp_path, name, seed, onset):
    """Rebounds of the independent generator that had been graded as new fruit, each for a reason of its
    own (seen with ``benchmarks/scorecard.py --seeds 25-32``):

    * chain10, seed 28, 0.624 s: the bounce of an earlier rebound, landing where this fruit's rebound was due,
      had claimed the fruit as its parent; the pairing that explains both re-reads it (``rebounds.reassigned``).
      Since a rebound's damping may follow either law (``rebounds.rebound_x``) it is read right without the
      re-reading; chain10 at seed 8, 1.565 s, is now the case the re-reading decides (contact 29 had claimed 28);
    * chain10, seed 27, 3.812 s: its fruit landed 0.07 ms after another fruit's rebound and was read as one fruit
      with both impulses; it is judged against the fruit alone too (``rebounds.held_alternative``);
    * chain7, seed 26, 0.721 s: its fruit was hidden in an overlap, and was lighter and livelier than the lane's
      median that stands for it (score 1.42, beyond the ambiguous band), but no new fruit of the lane could have
      made that pulse (14.7 sd away; ``rebounds.judge_unmeasured``);
    * chain10, seed 7, 2.495 s: its fruit was hidden in an overlap of three pulses, and the bounce of a rebound
      hidden beside it (2.457 s) is judged a rebound by the same rule, its parent unnamed; such a verdict leaves the
      hidden fruit's slot open (``analysis``), and this is the hidden fruit's own rebound.  (This one was right
      before the rule too: it guards the open slot; a first version of the rule took it.)
    * chain10, seed 36, 2.663 s: two rebounds 1.5 ms apart and a fruit 10 ms later, one contact the joint fit
      split into two pieces where there were three; the piece holding both rebounds was graded as a fruit.  A
      piece judged a new fruit is now compared with the rebounds due in it, as a whole contact is
      (``rebounds.rebounds_landed_together``);
    * lanes4, seed 6, 1.053 s: its fruit landed 0.5 ms after the rebound of a fruit hidden in an earlier overlap and
      was read as one fruit carrying both impulses (1.6 times the lane's, 2.2 sd of a lane of four fruit: not
      flagged).  The fruit's own rebound is now judged against the fruit alone as well when the rebound due in it
      was a hidden fruit's, as it already was for a measured contact's (``rebounds.held_alternative``);
    * grades, seed 9, 15.506 s, and seed 18, 7.895 s: a fruit, a rebound and a second fruit 10-12 ms later in one
      15-18 ms overlap that could not be split; the overlap kept one hidden fruit's slot, the first fruit's rebound
      took it, and the second's had none.  An overlap that carries two fruit's impulse beyond the rebound due in it
      and lasts 1.5 fruit contacts now keeps a slot for each (``LineAnalyzer._second_hidden_fruit``).

    Each is a rebound (all but chain10 at seed 7 were graded as fruit before), and the recording's scorecard takes
    no fruit for a rebound."""
    scenario = dataclasses.replace(lg.SCENARIOS[name], seed=seed)
    path, truth = lg.write(scenario, tmp_path)
    status, out, err = cli.run("analyze", path, *lg.analyze_options(truth))
    assert status == 0, err
    reports = [json.loads(line) for line in out.splitlines()]
    contact = next(c for c in truth["contacts"] if abs(c["start_time"] - onset) < 5e-5)
    assert contact["is_rebound"]
    report = {c["index"]: r for c, r in lg.match(reports, truth)["pairs"]}[contact["index"]]
    assert report["rebound"], report
    assert lg.score(reports, truth)["fruit_taken_for_rebounds"] == 0
