"""Impact detection, raw indices and the streaming front end (signals.detect, .indices, .stream).

Independent references:
* the recordings are built here, not by ``signals.synth``: each contact force is the exact
  Hunt–Crossley solution of the engine (``powerlaw_curves``, checked against closed forms and SciPy in
  test_engine_powerlaw.py), the true F_max, t_c, T from ``powerlaw_characteristics`` and the impulse from
  momentum, m V (1 + e) (impact-sensors.md §5.4).  The plate/transducer resonance (2.5 kHz, ζ = 0.03) is
  SciPy's ``lsim`` (first-order hold, exact for the piecewise-linear input) on a 16× finer grid.
  Rebounds follow the physics of §1: flight 2 e V/g, same damping factor c at the exit speed e V.
* the low-pass is compared with ``scipy.signal.butter`` / ``sosfilt``;
* the streaming equivalence is exact equality with the whole-array ``detect``.

Disturbances (impact-sensors.md §3.1, themselves [UNCONFIRMED] estimates): white noise σ = 1 % of the
median F_max, an offset of 5 %, a ramp of 1 %, a 0.3 Hz wander of 2 %, 50.1 Hz hum of 0.5 % with a
third harmonic at 30 % of that, at 20 kHz.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import signal
import socket
import threading

import numpy as np
import pytest
from scipy import signal as sps

from fruitimpact.engine.powerlaw import (
    exact_restitution,
    exact_x,
    powerlaw_characteristics,
    powerlaw_curves,
)
from fruitimpact.signals.detect import (
    DetectedImpact,
    Detector,
    DetectorSettings,
    butterworth_sos,
    detect,
    find_mains_hum,
)
from fruitimpact.signals.indices import INDEX_KEYS, impact_indices
from fruitimpact.signals.stream import Float32Source, StreamAnalyzer, TextSource, serve

RATE = 20_000.0
G = 9.80665  # standard gravity [m/s²], written here for independence
OVERSAMPLE = 16
PLATE_HZ, PLATE_ZETA = 2500.0, 0.03
SETTINGS = DetectorSettings(hum_frequency=50.0, hum_harmonics=(1, 3))
#: Quiet time [s] after each event group before the next fruit (beside a random 0.05–0.2 s).
GROUP_GAP = 0.2


# ---------------------------------------------------------------------------------------------------------
# Synthetic impacts built here


def hunt_crossley(mass, modulus, velocity, restitution=None, damping=None, diameter=0.075, poisson=0.35):
    """One fruit on a rigid plate: K = (4/3) E/(1 − ν²) √R; c from e (or given); exact characteristics."""
    stiffness = 4 / 3 * modulus / (1 - poisson ** 2) * math.sqrt(diameter / 2)
    c = float(exact_x(restitution)) / velocity if damping is None else damping
    e = float(exact_restitution(c * velocity))
    row = powerlaw_characteristics(mass, stiffness, c, velocity, diameter / 2)[0]
    return {"mass": mass, "K": stiffness, "c": c, "V": velocity, "e": e, "F": row[0], "tc": row[1], "T": row[2],
            "impulse": mass * velocity * (1 + e)}


def sensor_samples(imp, onset, n, plate=True):
    """(sample indices, values) of the sensor output for one impact touching at ``onset`` [s]."""
    tail = 12 / (PLATE_ZETA * 2 * math.pi * PLATE_HZ) if plate else 0.0
    k0 = max(0, math.floor(onset * RATE) - 2)
    k1 = min(n, math.ceil((onset + imp["T"] + tail) * RATE) + 2)
    fine = (k0 + np.arange((k1 - k0) * OVERSAMPLE + 1) / OVERSAMPLE) / RATE
    _, _, force, _ = powerlaw_curves(imp["mass"], imp["K"], imp["c"], imp["V"], fine - onset)
    force[(fine <= onset) | (fine >= onset + imp["T"])] = 0.0
    if plate:
        w = 2 * math.pi * PLATE_HZ
        _, force, _ = sps.lsim(sps.lti([w * w], [1, 2 * PLATE_ZETA * w, w * w]), force, fine - fine[0])
    return np.arange(k0, k1), force[::OVERSAMPLE][:k1 - k0]


def lane_events(rng, duration):
    """Primary impacts (F_max within about ±25 %, e 0.4–0.7), half followed by their rebound, a fifth by a
    second, larger fruit (same mass and modulus, 1.3× the speed) 2–5 ms after the first contact ends."""
    events = []
    t = 0.12
    while t < duration - 0.6:
        mass = rng.uniform(0.14, 0.25)
        modulus = 3.5e6 * (mass / 0.19) ** -1.5 * rng.uniform(0.9, 1.1)
        imp = hunt_crossley(mass, modulus, rng.uniform(0.9, 1.1), rng.uniform(0.4, 0.7))
        events.append((t, imp, "primary"))
        end = t + imp["T"]
        kind = rng.uniform()
        if kind < 0.5:
            exit_speed = imp["e"] * imp["V"]
            rebound = hunt_crossley(mass, modulus, exit_speed, damping=imp["c"])
            events.append((end + 2 * exit_speed / G, rebound, "rebound"))
            end = events[-1][0] + rebound["T"]
        elif kind < 0.7:
            close = hunt_crossley(mass, modulus, 1.3 * imp["V"], rng.uniform(0.4, 0.7))  # 1.37× F_max
            events.append((end + rng.uniform(2e-3, 5e-3), close, "close"))
            end = events[-1][0] + close["T"]
        t = end + GROUP_GAP + rng.uniform(0.05, 0.2)
    return events


def disturbances(rng, n, scale):
    t = np.arange(n) / RATE
    return scale * (0.01 * rng.normal(size=n) + 0.05 + 0.01 * t / t[-1] + 0.02 * np.sin(2 * np.pi * 0.3 * t + 1.0)
                    + 0.005 * np.sin(2 * np.pi * 50.1 * t + 0.3) + 0.0015 * np.sin(2 * np.pi * 150.3 * t + 1.1))


@pytest.fixture(scope="module")
def recording():
    """Two lanes of 1,000,000 samples (50 s at 20 kHz) and their true events."""
    rng = np.random.default_rng(20240611)
    n = 1_000_000
    x = np.zeros((n, 2))
    truth = []
    for lane in range(2):
        events = lane_events(rng, n / RATE)
        for onset, imp, kind in events:
            idx, values = sensor_samples(imp, onset, n)
            x[idx, lane] += values
        truth.append(events)
    scale = np.median([imp["F"] for events in truth for _, imp, kind in events if kind == "primary"])
    for lane in range(2):
        x[:, lane] += disturbances(rng, n, scale)
    return x, truth, scale


@pytest.fixture(scope="module")
def detected(recording):
    x, _, _ = recording
    return detect(x, RATE, SETTINGS)


def matched(impacts, truth):
    """Pairs (impact, (onset, imp, kind)) matched by onset (the detected start_time within 1 ms)."""
    pairs = []
    for lane, events in enumerate(truth):
        mine = [i for i in impacts if i.lane == lane]
        starts = np.array([impact_indices(i, RATE)["start_time"] for i in mine])
        for event in events:
            k = int(np.argmin(np.abs(starts - event[0])))
            assert abs(starts[k] - event[0]) < 1e-3, (lane, event[0], event[2])
            pairs.append((mine[k], event))
    return pairs


# ---------------------------------------------------------------------------------------------------------
# Detection


def test_every_impact_found_none_extra(recording, detected):
    _, truth, _ = recording
    for lane, events in enumerate(truth):
        assert sum(i.lane == lane for i in detected) == len(events)
    pairs = matched(detected, truth)
    assert len({id(i) for i, _ in pairs}) == len(detected)  # one-to-one
    kinds = {kind for events in truth for _, _, kind in events}
    assert kinds == {"primary", "rebound", "close"}
    assert not any(i.truncated or i.overlong or i.clipped for i in detected)
    # sequences count 0, 1, … per lane, in onset order
    for lane in range(2):
        mine = [i for i in detected if i.lane == lane]
        assert [i.sequence for i in mine] == list(range(len(mine)))
        assert all(a.start_index < b.start_index for a, b in itertools.pairwise(mine))


def test_rebounds_flagged_and_close_fruit_separate(recording, detected):
    """Rule 1 of issue 13 on a generator with no known drop height (V 0.9–1.1 m/s, e 0.4–0.7 per fruit):
    a rebound is the same fruit (m, K, c) at e V after a flight of 2 e V/g, so its impulse, peak, time to
    peak and shape follow from its parent's by the Hertz scalings (signals/rebounds/); a larger fruit
    2–5 ms after a contact (rule 2) is a separate new fruit, never a rebound, and never fitted through."""
    from fruitimpact.signals.analysis import Analysis

    _, truth, _ = recording
    analyzer = Analysis(RATE).analyzer()
    reports = {}
    for i in detected:  # in emission order; no two fruit share a contact here, so one report each
        (reports[(i.lane, i.sequence)],) = analyzer.reports(i)
    for impact, (_, _, kind) in matched(detected, truth):
        report = reports[(impact.lane, impact.sequence)]
        assert report["status"] == "ok", report["message"]
        if kind == "rebound":
            assert report["rebound"] and report["rebound_of"] == impact.sequence - 1, report["rebound_evidence"]
        else:  # a primary, or a larger fruit right after one: separate, not a rebound
            assert not report["rebound"] and report["rebound_of"] is None, (kind, report["rebound_evidence"])
    closes = [i for i, e in matched(detected, truth) if e[2] == "close"]
    assert closes
    by_key = {(i.lane, i.sequence): i for i in detected}
    for impact in closes:  # the gap before it was only a few ms: each has its own samples
        previous = by_key[(impact.lane, impact.sequence - 1)]
        # the detected gap: the true 2–5 ms plus the previous contact's tail below the offset threshold
        assert (impact.start_index - previous.end_index) / RATE < 0.01
        assert impact.previous_end == previous.end_index
        post = round(SETTINGS.post_trigger * RATE)
        if impact.start_index <= previous.end_index + post:
            assert previous.next_start == impact.start_index


def test_emission_times(detected):
    """Emission rule (detect.py): every impact at end + max(post-trigger, offset hold), whatever follows it
    (the rebound decision does not wait for later contacts), with its neighbours' indices."""
    post = round(SETTINGS.post_trigger * RATE)
    hold = round(SETTINGS.offset_hold * RATE)
    for lane in range(2):
        mine = [i for i in detected if i.lane == lane]
        for before, impact, following in zip([None] + mine[:-1], mine, mine[1:] + [None]):
            assert impact.emitted_at - 1 == impact.end_index + max(post, hold)
            assert impact.window_start == impact.start_index - round(SETTINGS.pre_trigger * RATE)
            assert impact.window_end == impact.end_index + post + 1
            assert impact.previous_end == (None if before is None else before.end_index)
            inside = following is not None and following.start_index <= impact.end_index + post
            assert impact.next_start == (following.start_index if inside else None)


def test_clipped_impact_flagged():
    imp = hunt_crossley(0.2, 3.5e6, 1.0, 0.5)
    n = 12_000
    x = np.zeros(n)
    for onset in (0.1, 0.3, 0.5):
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values * (1.3 if onset == 0.3 else 1.0)
    x += np.random.default_rng(1).normal(0, 0.01 * imp["F"], n)
    limit = 1.1 * imp["F"]
    impacts = detect(np.minimum(x, limit), RATE, DetectorSettings(clip_high=limit, clip_low=-limit))
    assert [i.clipped for i in impacts] == [False, True, False]
    assert [impact_indices(i, RATE)["clipped"] for i in impacts] == [False, True, False]


def test_flush_emits_held_and_truncated():
    imp = hunt_crossley(0.2, 3.5e6, 1.0, 0.5)
    n = 4000
    x = np.zeros(n)
    idx, values = sensor_samples(imp, 0.1, n, plate=False)
    x[idx] += values
    cut = int((0.18 + 0.15 * imp["T"]) * RATE)  # the recording ends during the second contact, before its peak
    idx, values = sensor_samples(imp, 0.18, n, plate=False)
    x[idx] += values
    detector = Detector(RATE)
    (first,) = detector.feed(x[:cut])  # emitted once its end is confirmed and its window complete
    assert not first.truncated and first.emitted_at < cut
    (second,) = detector.flush()
    held = [first, second]
    assert second.truncated and second.previous_end == first.end_index
    assert second.emitted_at == cut == detector.samples_fed
    assert second.window_end == detector.samples_fed
    assert impact_indices(second, RATE)["truncated"] is True
    assert math.isnan(impact_indices(second, RATE)["contact_duration"])
    with pytest.raises(RuntimeError):
        detector.feed(x[:10])
    detector.reset()
    assert detector.feed(x[:cut]) + detector.flush() == held


def test_overlong_contact_ends_and_baseline_relearnt():
    imp = hunt_crossley(0.2, 3.5e6, 1.0, 0.5)
    n = 40_000
    x = np.random.default_rng(2).normal(0, 0.01 * imp["F"], n)
    x[int(0.5 * RATE):] += 0.5 * imp["F"]  # a permanent step (e.g. a fruit resting on the plate)
    for onset in (0.2, 1.5):
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values
    impacts = detect(x, RATE, DetectorSettings(max_duration=0.1))
    assert [i.overlong for i in impacts] == [False, True, False]
    assert impacts[1].end_index - impacts[1].start_index + 1 == round(0.1 * RATE)
    last = impact_indices(impacts[2], RATE)
    assert last["peak_force"] == pytest.approx(imp["F"], rel=0.02)
    assert last["start_time"] == pytest.approx(1.5, abs=1e-4)


# ---------------------------------------------------------------------------------------------------------
# Indices against the truth


def test_indices_against_truth(recording, detected):
    """Primaries and close fruit (σ ≈ 0.7–1.3 % of their own F_max) at 20 kHz, through the 2.5 kHz plate.

    Tolerances and why: impact-sensors.md §5.3 shows that per-impact F_max within 1 % and t_c within 2 %
    at 1 % noise need smoothing plus a model fit (the raw maximum is +1.0 ± 0.6 %; Savitzky–Golay leaves
    5–6 % of impacts outside 2 % in t_c).  These raw indices measured F_max −0.0 ± 0.3 %, t_c −0.2 ± 0.7 %,
    impulse −0.05 ± 0.23 % over 712 such impacts, so we require
      F_max:   |mean| ≤ 0.3 %, ≥ 99 % of impacts within 1 %, all within 1.5 % (1 % is ≈ 3 sd);
      t_c:     |mean| ≤ 0.5 %, ≥ 95 % within 2 %, all within 3.5 % (2 % is ≈ 2.8 sd; the model fit
               of signals.fit does per-impact 2 %);
      impulse: |mean| ≤ 0.3 %, ≥ 99 % within 1 %, all within 1.25 % (the noise of the sum over the
               ~150 contact samples alone is ≈ 0.15 %, with the baseline's ≈ 0.23 %: 1 % is ≈ 4 sd,
               and impacts with e ≈ 0.4 have the longest, noisiest tails);
      onset:   within 50 µs (2.5 % of the shortest t_c; the plate delays the signal by 2ζ/ω ≈ 4 µs).
    The plate resonance preserves the impulse; its peak error (§3.3, up to +3 % for short pulses) is
    largely averaged out by the fit window, so the truth is the contact force itself.
    """
    _, truth, _ = recording
    errors = []
    for impact, (onset, imp, kind) in matched(detected, truth):
        if kind == "rebound":
            continue
        got = impact_indices(impact, RATE)
        assert list(got) == list(INDEX_KEYS)
        errors.append((got["peak_force"] / imp["F"] - 1, got["time_to_peak"] / imp["tc"] - 1,
                       got["impulse"] / imp["impulse"] - 1, got["start_time"] - onset))
        assert got["firmness_c"] == pytest.approx(got["peak_force"] / got["time_to_peak"], rel=1e-12)
        assert got["firmness_c_star"] == pytest.approx(got["peak_force"] / got["time_to_peak"] ** 2, rel=1e-12)
    force, tc, impulse, onset = np.array(errors).T * np.array([[100], [100], [100], [1]])
    assert len(force) > 200
    assert abs(force.mean()) <= 0.3 and np.mean(np.abs(force) <= 1.0) >= 0.99 and np.abs(force).max() <= 1.5
    assert abs(tc.mean()) <= 0.5 and np.mean(np.abs(tc) <= 2.0) >= 0.95 and np.abs(tc).max() <= 3.5
    assert abs(impulse.mean()) <= 0.3 and np.mean(np.abs(impulse) <= 1.0) >= 0.99
    assert np.abs(impulse).max() <= 1.25
    assert np.abs(onset).max() <= 50e-6


def test_rebound_indices(recording, detected):
    """Rebounds (F_max 30–65 % of the primary: σ up to 3 % of their own peak) still within 3 % / 6 %."""
    _, truth, _ = recording
    for impact, (_, imp, kind) in matched(detected, truth):
        if kind == "rebound":
            got = impact_indices(impact, RATE)
            assert got["peak_force"] == pytest.approx(imp["F"], rel=0.03)
            assert got["time_to_peak"] == pytest.approx(imp["tc"], rel=0.06)


@pytest.mark.parametrize("restitution", [0.3, 0.4, 0.5, 0.7, 0.95])
def test_noise_free_indices(restitution):
    """Noise-free pulses at 7 sub-sample onsets: the edge and peak estimators' own biases (documented in
    indices.py): onset within 0.5 % of t_c, F_max within 0.5 %, t_c within 0.5 % (2 % at e = 0.95, where
    the weighted cubic puts the symmetric Hertz peak early), impulse exact to 0.02 %."""
    imp = hunt_crossley(0.19, 3.5e6, 1.0, restitution)
    for sub in np.arange(7) / 7:
        onset = 0.06 + sub / RATE
        n = int((onset + imp["T"] + 0.01) * RATE)
        x = np.zeros(n)
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] = values
        (impact,) = detect(x, RATE, DetectorSettings(post_trigger=4e-3))
        got = impact_indices(impact, RATE)
        assert abs(got["start_time"] - onset) <= 0.005 * imp["tc"]
        assert got["peak_force"] == pytest.approx(imp["F"], rel=5e-3)
        assert got["time_to_peak"] == pytest.approx(imp["tc"], rel=0.02 if restitution > 0.9 else 5e-3)
        assert got["impulse"] == pytest.approx(imp["impulse"], rel=2e-4)


def test_hum_removal_needed_and_sufficient():
    """Hum of 3 % of F_max (far above §3.1's ≲ 1 %): with the canceller F_max stays within 1 %, at 50 Hz given or
    found (``"auto"``); without it, the hum under the pulse moves F_max by more."""
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 60_000
    rng = np.random.default_rng(3)
    t = np.arange(n) / RATE
    x = 0.03 * imp["F"] * np.sin(2 * np.pi * 50.0 * t + 0.7) + rng.normal(0, 0.002 * imp["F"], n)
    onsets = 0.3 + 0.25 * np.arange(10) + rng.uniform(0, 0.02, 10)
    for onset in onsets:
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values
    for hum, limit in ((50.0, 0.01), ("auto", 0.01), (None, None)):
        impacts = detect(x, RATE, DetectorSettings(hum_frequency=hum, warmup=0.1))
        assert len(impacts) == len(onsets)
        worst = max(abs(impact_indices(i, RATE)["peak_force"] / imp["F"] - 1) for i in impacts)
        if limit:
            assert worst < limit
        else:
            assert worst > 0.01


@pytest.mark.parametrize("frequency", [50.0, 60.0, None])
def test_the_mains_hum_is_found_on_the_first_samples(frequency):
    """``find_mains_hum`` on the first 0.2 s at 20 kHz (σ = 1 N noise, a level and a slope, a 3rd harmonic at
    30 %, a 100 N contact inside the window, a 20 Hz vibration of 1 σ): hum of 0.5 N (0.5 σ, half the impact-sensor
    note's "≲ 1 % of F_max" for a 100 N fruit) at 50 or 60 Hz ±0.2 % is found at its frequency, its amplitude
    within 4 standard errors; the standard error is the least-squares fit's own, ≈ σ √(2/n) over 10 cycles where
    the columns are near orthogonal (σ with the vibration's variance, n without the contact's samples).  Without
    hum nothing is
    found: at 40 seeds on one lane, at 10 seeds on 16 lanes (the false-alarm chance is 1e-6 over all lanes), nor on
    a constant lane beside a noisy one (its residual is rounding: no hum below 1 mN counts)."""
    n = 4000
    t = np.arange(n) / RATE
    imp = hunt_crossley(0.2, 3.5e6, 1.0, 0.55)
    for seed in range(40 if frequency is None else 10):
        rng = np.random.default_rng(seed)
        x = 3.0 + 20.0 * t + rng.standard_normal(n) + np.sin(2 * np.pi * 20.0 * t + rng.uniform(0, 6))
        idx, values = sensor_samples(imp, rng.uniform(0.05, 0.15), n, plate=False)
        x[idx] += values
        if frequency is not None:
            f = frequency * (1 + rng.uniform(-0.002, 0.002))
            x += 0.5 * np.sin(2 * np.pi * f * t + rng.uniform(0, 6)) + 0.15 * np.sin(6 * np.pi * f * t + 1.0)
        found, amplitude, error = find_mains_hum(x, RATE)
        assert found == frequency, (seed, amplitude, error)
        if frequency is not None:
            # σ √(2/n) at best; the vibration, unmodelled, adds half a variance and the contact's 40 ms are left out
            assert math.sqrt(2 / n) < error < math.sqrt(1.5) * math.sqrt(2 / (0.75 * n))
            assert abs(amplitude - 0.5) < 4 * error
    if frequency is None:
        for seed in range(10):
            noise = np.random.default_rng(100 + seed).standard_normal((n, 16))
            assert find_mains_hum(noise, RATE)[0] is None
        lanes = np.column_stack([np.full(n, 7.3), np.random.default_rng(1).standard_normal(n)])
        assert find_mains_hum(lanes, RATE)[0] is None


@pytest.mark.parametrize("hum", [50.0, "auto"])
def test_a_contact_in_the_warm_up_is_no_hum(hum):
    """A fruit landing in the first 50 ms (the detector's warm-up, where the hum's level is fitted by least squares):
    its pulse is left out of the fit (residuals beyond 6 robust sd, with a quarter of the warm-up each side) and the
    fit done again, so the hum removed is the mains' and the fruit after it keep their peak force within 1 %.
    Before, the pulse was fitted as hum: the next 0.3 s of fruit came out up to 17 % low (an attack on the CLI,
    ``synth --interval 0.08 --hum 0.5``)."""
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 40_000
    rng = np.random.default_rng(5)
    t = np.arange(n) / RATE
    x = 0.005 * imp["F"] * np.sin(2 * np.pi * 50.0 * t + 0.4) + rng.normal(0, 0.01 * imp["F"], n)
    onsets = [0.02] + [0.1 + 0.08 * k for k in range(20)]
    for onset in onsets:
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values
    impacts = detect(x, RATE, DetectorSettings(hum_frequency=hum, hum_harmonics=(1, 3)))
    later = [i for i in impacts if i.start_index > 0.09 * RATE]
    assert len(later) == 20
    worst = max(abs(impact_indices(i, RATE)["peak_force"] / imp["F"] - 1) for i in later)
    assert worst < 0.01, worst


@pytest.mark.parametrize("hum", [50.0, "auto"])
def test_contacts_that_fill_the_warm_up_leave_the_noise_level_true(hum):
    """A busy line, 40 fruit/s: the 50 ms warm-up holds two contacts (40 % of its samples).  Every later fruit must
    be found, the 95th percentile of its peak's error within 1.5 % (0.9 % with the hum given; 1.1 % with auto,
    which finds no hum of 0.5 % under contacts filling 40 % of its window), and the lane's σ within a factor 2 of
    the noise's (it reads ~1.5×, given hum or found: between contacts 25 ms apart the tracked σ holds the pulses'
    low tails; docs/signals.md, limits).  With the hum given, the least-squares fit through both contacts had
    set its own spread at 11 noise sd, above every contact: no outlier was left out, the lane's σ was 11× too
    large, and 4 of 100 fruit were found.  The contacts are now screened against the robust level (medians of
    the two halves) and its MAD first."""
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = int(3 * RATE)
    rng = np.random.default_rng(6)
    t = np.arange(n) / RATE
    noise = 0.01 * imp["F"]
    x = 0.005 * imp["F"] * np.sin(2 * np.pi * 50.0 * t + 0.4) + rng.normal(0, noise, n)
    onsets = [0.006 + 0.025 * k for k in range(100)]
    for onset in onsets:
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values
    impacts = detect(x, RATE, DetectorSettings(hum_frequency=hum, hum_harmonics=(1, 3)))
    later = [i for i in impacts if i.start_index > 0.25 * RATE]
    assert len(later) == sum(onset > 0.25 for onset in onsets)
    assert all(0.8 < i.noise / noise < 2.0 for i in later), sorted(i.noise / noise for i in later)[-3:]
    errors = [abs(impact_indices(i, RATE)["peak_force"] / imp["F"] - 1) for i in later]
    assert np.percentile(errors, 95) < 0.015, np.percentile(errors, 95)


def test_a_hum_found_removes_what_a_hum_given_does(recording, detected):
    """``hum_frequency="auto"`` on the two 50 s lanes (hum at 50.1 Hz, 0.5 % of the median peak): 50 Hz is found on
    the first 0.2 s, and the impacts are those of the detector told 50 Hz, every field, fed in random chunks (the
    samples are held until the first 0.2 s are in, copied: the caller may reuse its buffer)."""
    x, _, _ = recording
    auto = dataclasses.replace(SETTINGS, hum_frequency="auto")
    rng = np.random.default_rng(11)
    detector = Detector(RATE, auto, lanes=2)
    streamed, position = [], 0
    buffer = np.empty((50_000, 2))
    while position < x.shape[0]:
        size = min(int(np.exp(rng.uniform(0, math.log(50_000)))), x.shape[0] - position)
        buffer[:size] = x[position:position + size]
        streamed += detector.feed(buffer[:size])
        buffer[:size] = 0.0  # a reader reusing its buffer
        assert detector.samples_fed == position + size
        position += size
    streamed += detector.flush()
    assert detector.hum_frequency == 50.0 and detector.hum_found[0] == 50.0
    assert streamed == detected


def _discharged(tau, count, noise=0.0, seed=3, gap=0.25):
    """(force, sensor output, impacts, rng) of ``count`` apples ``gap`` s apart through a piezo chain's discharge:
    the first-order high-pass s/(s + 1/τ) by SciPy's ``lsim`` (first-order hold, exact for the piecewise-linear
    input between samples), plus white noise of ``noise`` N."""
    rng = np.random.default_rng(seed)
    n = int((0.1 + count * gap) * RATE)
    force = np.zeros(n)
    impacts = []
    for k in range(count):
        imp = hunt_crossley(rng.uniform(0.15, 0.25), rng.uniform(2.5e6, 4.5e6), 1.0, rng.uniform(0.5, 0.65))
        idx, values = sensor_samples(imp, 0.1 + k * gap + rng.uniform(0.0, 0.02), n, plate=False)
        force[idx] += values
        impacts.append(imp)
    t = np.arange(n) / RATE
    _, sensed, _ = sps.lsim(sps.lti([1.0, 0.0], [1.0, 1.0 / tau]), force, t)
    return force, sensed + noise * rng.standard_normal(n), impacts, rng


def test_a_given_discharge_time_restores_the_force():
    """Step 1b with τ given: a piezo chain's output y (τ = 0.1 s: each apple droops by up to I/τ ≈ 2.7 N, 2.5 % of
    its peak, and leaves the signal that far below its baseline) is restored by x = y + (1/τ) ∫ y dt.  The windows
    then hold the force itself to 1e-3 of its peak: the inverse's leak leaves the droop of a 100 τ = 10 s chain
    (I/10 s ≈ 3e-4 of the peak) and the trapezoidal rule ~1e-7; the sensor's own output there misses the force by
    more than 2 % of the peak."""
    force, sensed, impacts, _ = _discharged(0.1, 3)
    found = detect(sensed, RATE, DetectorSettings(discharge_time=0.1))
    assert len(found) == 3
    for impact, imp in zip(found, impacts):
        k = np.arange(impact.window_start, impact.window_end)
        assert np.max(np.abs(impact.window - force[k])) < 1e-3 * imp["F"]
        assert np.max(np.abs(sensed[k] - sensed[k[0]] - force[k])) > 0.02 * imp["F"]
        assert impact.discharge_time == 0.1


def test_the_discharge_is_measured_on_the_lanes_contacts():
    """τ not given: each lone contact's undershoot after it, against the running integral of its window, measures
    what is missing; the lane restores the median of its last measurements once that is shown (5 standard errors).
    At 1 % noise every contact's window is restored (the first one with its own measurement), the τ found is the
    chain's within 15 %, and the peak force from the raw indices is the true one within 1 % (2–3 % low without
    the restoration).  Fed in chunks of any size, the detector gives the same impacts (its state at the emission
    of a contact decides; the chunking does not).  A sensor without discharge restores nothing."""
    force, sensed, impacts, rng = _discharged(0.1, 12, noise=1.0)
    found = detect(sensed, RATE, DetectorSettings())
    assert len(found) == 12
    for impact, imp in zip(found, impacts):
        assert impact.discharge_time == pytest.approx(0.1, rel=0.15)
        assert impact_indices(impact, RATE)["peak_force"] == pytest.approx(imp["F"], rel=0.01)
    unrestored = detect(sensed, RATE, DetectorSettings(discharge_time=math.inf))
    assert max(impact_indices(i, RATE)["peak_force"] / imp["F"] - 1 for i, imp in zip(unrestored, impacts)) < -0.01
    detector = Detector(RATE, DetectorSettings())
    chunked, at = [], 0
    while at < sensed.size:
        size = int(rng.integers(1, 3000))
        chunked += detector.feed(sensed[at:at + size])
        at += size
    chunked += detector.flush()
    assert chunked == found
    assert detector.discharge_time(0) == found[-1].discharge_time
    plain = detect(force + rng.standard_normal(force.size), RATE, DetectorSettings())
    assert len(plain) == 12 and all(impact.discharge_time is None for impact in plain)
    # a measurement faster than MIN_DISCHARGE_TIME is no sensor's and is dropped, not restored at that limit (a
    # review found one misread contact, measured at 0.8 ms and capped at 10 ms, had made every later contact
    # overlong): a 2 ms chain is left as it is
    _, fast, _, _ = _discharged(0.002, 6, noise=1.0)
    assert all(impact.discharge_time is None for impact in detect(fast, RATE, DetectorSettings()))


def test_lowpass_matches_scipy():
    for order in range(1, 9):
        for cutoff in (150.0, 3000.0, 9000.0):
            mine = butterworth_sos(cutoff, order, RATE)
            ref = sps.butter(order, cutoff, fs=RATE, output="sos")
            _, h_mine = sps.sosfreqz(mine, 2048, fs=RATE)
            _, h_ref = sps.sosfreqz(ref, 2048, fs=RATE)
            np.testing.assert_allclose(h_mine, h_ref, atol=1e-9)
    # in the detector: the window is SciPy's sosfilt output (zero baseline and noise: nothing subtracted)
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 4000
    x = np.zeros(n)
    idx, values = sensor_samples(imp, 0.1, n, plate=False)
    x[idx] = values
    (impact,) = detect(x, RATE, DetectorSettings(lowpass_cutoff=2000.0, lowpass_order=4))
    reference = sps.sosfilt(sps.butter(4, 2000.0, fs=RATE, output="sos"), x)
    k = np.arange(impact.window_start, impact.window_end)
    baseline = impact.baseline + impact.baseline_slope * (k - impact.start_index) / RATE
    assert abs(impact.baseline) < 1e-3 * imp["F"]  # moved only by the pulse's toe below the threshold
    np.testing.assert_allclose(impact.window + baseline, reference[k], rtol=0, atol=1e-12 * imp["F"])


# ---------------------------------------------------------------------------------------------------------
# Streaming


def test_stream_in_random_chunks_equals_whole_file(recording, detected):
    """≥ 1,000,000 samples per lane fed in chunks of 1 … 50,000 samples (log-uniform, seeded) give exactly
    the impacts of the whole-array ``detect``: every field, windows bit for bit."""
    x, _, _ = recording
    rng = np.random.default_rng(7)
    detector = Detector(RATE, SETTINGS, lanes=2)
    streamed = []
    position = 0
    sizes = []
    while position < x.shape[0]:
        size = int(np.exp(rng.uniform(0, math.log(50_000))))
        sizes.append(size)
        streamed += detector.feed(x[position:position + size])
        position += size
    streamed += detector.flush()
    assert min(sizes) == 1 and max(sizes) > 30_000 and len(sizes) > 100
    assert len(streamed) == len(detected) > 400
    assert streamed == detected
    for a, b in zip(streamed, detected):  # spelled out: every field equal, same types
        for name in DetectedImpact.__dataclass_fields__:
            if name == "window":
                assert np.array_equal(a.window, b.window)
            else:
                assert getattr(a, name) == getattr(b, name)


def _reports(impacts, settings_rate=RATE) -> list[dict]:
    """The reports a StreamAnalyzer gives for ``impacts`` (default analysis, lanes named lane<k>)."""
    from fruitimpact.signals.analysis import Analysis

    analyzer = Analysis(settings_rate).analyzer()
    out = []
    for impact in impacts:
        for report in analyzer.reports(impact):
            report["lane"] = f"lane{impact.lane}"
            out.append(report)
    return out


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(
        (isinstance(v, float) and math.isnan(v) and math.isnan(b[k])) or v == b[k] for k, v in a.items())


def test_float32_stream_with_partial_samples(recording):
    """Float32 bytes in chunks cut anywhere (inside samples too): the indices equal those of ``detect`` on
    the same float32 values; a trailing partial sample is reported and dropped."""
    x = recording[0][:300_000].astype("<f4")
    data = x.tobytes() + b"\x00\x01\x02"  # 3 stray bytes at the end
    problems = []
    analyzer = StreamAnalyzer(RATE, 2, SETTINGS, source="float32", on_problem=problems.append)
    rng = np.random.default_rng(8)
    cuts = np.sort(rng.choice(len(data), 400, replace=False))
    chunks = [data[a:b] for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(data)])]
    assert any(len(c) % 8 for c in chunks)
    summary = analyzer.run(iter(chunks))
    expected = _reports(detect(x.astype(float), RATE, SETTINGS))
    assert len(analyzer.results) == len(expected) > 30
    assert all(_same(a, b) for a, b in zip(analyzer.results, expected))
    assert summary["samples"] == 300_000 and summary["dropped_bytes"] == 3 and summary["interrupted"] is None
    assert len(problems) == 1 and "3 byte" in problems[0]


def test_float32_source_replaces_non_finite():
    problems = []
    source = Float32Source(2, problems.append)
    values = np.array([[1, 2], [np.nan, 3], [np.inf, np.nan], [4, 5]], dtype="<f4")
    data = values.tobytes()
    out = np.vstack([source.parse(data[:5]), source.parse(data[5:13]), source.parse(data[13:])])
    np.testing.assert_array_equal(out, [[1, 2], [1, 3], [1, 3], [4, 5]])
    assert source.replaced == 3 and len(problems) == 1 and source.problems == {"finite": 3}


def test_text_stream_malformed_lines_skipped_and_counted():
    lines = ["1.5, 2", "", "3 4", "5,6,7", "x 8", "9", "nan 1", "10\t11", "abc def", "12 ,13", "14 15 16"]
    text = ("\r\n".join(lines) + "\n17 18").encode()  # CRLF, and no newline at the end
    problems = []
    source = TextSource(2, problems.append)
    out = np.vstack([source.parse(text[i:i + 3]) for i in range(0, len(text), 3)] + [source.finish()])
    np.testing.assert_array_equal(out, [[1.5, 2], [3, 4], [10, 11], [12, 13], [17, 18]])
    assert source.malformed == 6 and source.samples == 5 and source.lines == 11
    assert source.problems == {"count": 3, "number": 2, "finite": 1}
    assert len(problems) == 3  # one message per kind of problem
    assert problems[0].startswith("line 4: expected 2 numbers, got 3")
    assert problems[1].startswith("line 5: not a number: 'x'")
    assert problems[2].startswith("line 7: NaN or infinite value")


def test_text_stream_analyzer_matches_detect():
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 20_000
    x = np.random.default_rng(4).normal(0, 0.01 * imp["F"], n)
    for onset in (0.2, 0.6):
        idx, values = sensor_samples(imp, onset, n, plate=False)
        x[idx] += values
    text = "".join(f"{float(v)!r}\n" for v in x[:12_000]) + "junk\n" + "".join(f"{float(v)!r}\n" for v in x[12_000:])
    data = text.encode()
    problems = []
    analyzer = StreamAnalyzer(RATE, 1, DetectorSettings(), on_problem=problems.append)
    summary = analyzer.run(data[i:i + 4096] for i in range(0, len(data), 4096))
    expected = _reports(detect(x, RATE, DetectorSettings()))
    assert len(expected) == 2 and all(_same(a, b) for a, b in zip(analyzer.results, expected))
    assert summary["malformed_lines"] == 1 and summary["samples"] == n and len(problems) == 1


def test_run_flushes_on_sigterm():
    """SIGTERM while reading: the analyzer flushes (the impact in progress comes out truncated)."""
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 4000
    x = np.zeros(n)
    idx, values = sensor_samples(imp, 0.1, n, plate=False)
    x[idx] = values
    cut = int((0.1 + 0.5 * imp["T"]) * RATE)

    def chunks():
        yield x[:cut].astype("<f4").tobytes()
        signal.raise_signal(signal.SIGTERM)
        yield x[cut:].astype("<f4").tobytes()  # never read

    previous = signal.getsignal(signal.SIGTERM)
    analyzer = StreamAnalyzer(RATE, 1, source="float32")
    summary = analyzer.run(chunks())
    assert signal.getsignal(signal.SIGTERM) == previous  # handler restored
    assert summary["interrupted"] == "SIGTERM" and summary["samples"] == cut
    assert len(analyzer.results) == 1 and analyzer.results[0]["truncated"] is True


def test_tcp_serve_one_client():
    imp = hunt_crossley(0.19, 3.5e6, 1.0, 0.5)
    n = 8000
    x = np.random.default_rng(5).normal(0, 0.01 * imp["F"], n)
    idx, values = sensor_samples(imp, 0.2, n, plate=False)
    x[idx] += values
    port = []
    ready = threading.Event()
    results = []
    settings = DetectorSettings()

    def listening(p):
        port.append(p)
        ready.set()

    found = []
    server = threading.Thread(target=lambda: results.append(serve(
        0, RATE, 1, settings, on_listening=listening, max_clients=1, on_impact=results.append,
        on_detected=lambda impact, values: found.append(impact))))
    server.start()
    assert ready.wait(10)
    with socket.create_connection(("127.0.0.1", port[0])) as client:
        client.sendall("".join(f"{float(v)!r}\n" for v in x).encode())
    server.join(10)
    assert not server.is_alive()
    impacts, summaries = results[:-1], results[-1]
    assert len(summaries) == 1 and summaries[0]["samples"] == n and summaries[0]["impacts"] == 1
    (expected,) = _reports(detect(x, RATE, settings))
    assert len(impacts) == 1 and _same(impacts[0], expected)
    assert len(found) == 1 and found[0] == detect(x, RATE, settings)[0]


# ---------------------------------------------------------------------------------------------------------
# Validation


@pytest.mark.parametrize("name,value", [
    ("k_on", 0.0), ("k_on", math.nan), ("k_off", 6.0), ("k_off", -1.0), ("baseline_time_constant", 0.0),
    ("noise_time_constant", -1.0), ("warmup", math.inf), ("threshold_floor", -0.1), ("offset_hold", 0.0),
    ("min_duration", 0.0), ("max_duration", 1e-4), ("pre_trigger", -1e-3), ("post_trigger", math.nan),
    ("hum_frequency", 0.0), ("hum_q", 0.1),
    ("lowpass_cutoff", -5.0), ("lowpass_order", 0), ("lowpass_order", 9), ("lowpass_order", 2.0),
    ("hum_harmonics", (3, 1)), ("hum_harmonics", ()), ("clip_high", "high"), ("k_on", True),
    ("hum_frequency", "automatic"), ("discharge_time", 0.005), ("discharge_time", "auto"),
    ("discharge_time", -math.inf),
])
def test_settings_validation(name, value):
    with pytest.raises(ValueError) as info:
        DetectorSettings(**{name: value})
    message = str(info.value)
    assert message.startswith(name) and "\n" not in message


def test_clip_order_validation():
    with pytest.raises(ValueError, match="^clip_high must be > clip_low"):
        DetectorSettings(clip_low=5.0, clip_high=1.0)


@pytest.mark.parametrize("kwargs,settings,start", [
    ({"rate": 0.0}, None, "rate"), ({"rate": math.nan}, None, "rate"), ({"rate": RATE, "lanes": 0}, None, "lanes"),
    ({"rate": RATE}, DetectorSettings(lowpass_cutoff=10_000.0), "lowpass_cutoff"),
    ({"rate": RATE}, DetectorSettings(hum_frequency=5000.0, hum_harmonics=(1, 3)), "hum_frequency"),
    ({"rate": 1000.0}, DetectorSettings(warmup=0.01, offset_hold=2e-3, min_duration=2e-3), "warmup"),
    ({"rate": 1000.0}, DetectorSettings(offset_hold=1e-4), "offset_hold"),
    ({"rate": 1000.0}, DetectorSettings(min_duration=1e-4, offset_hold=2e-3), "min_duration"),
])
def test_detector_validation(kwargs, settings, start):
    with pytest.raises(ValueError) as info:
        Detector(settings=settings, **kwargs)
    assert str(info.value).startswith(start) and "\n" not in str(info.value)


def test_feed_validation():
    detector = Detector(RATE, lanes=2)
    for bad in (np.zeros(10), np.zeros((10, 3)), np.array([[0.0, math.nan]]), np.array([["a", "b"]])):
        with pytest.raises(ValueError, match="^samples must"):
            detector.feed(bad)
    assert detector.samples_fed == 0  # refused before any work
    with pytest.raises(ValueError, match="^source must"):
        StreamAnalyzer(RATE, 1, source="csv")
    with pytest.raises(ValueError, match="^port must"):
        serve(70_000, RATE)
