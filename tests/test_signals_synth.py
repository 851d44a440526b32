"""The synthetic impact sensor (issue 8, item 4): ``signals.synthesize`` and its truth.

Independent references:
- the impulse ∫F dt = m (1 + e) V of a contact with restitution e (momentum
  balance), with V = √(2 g h) and g written here (conftest.G);
- a SciPy DOP853 integration of m δ̈ = −k δ^1.5 (1 + c δ̇) (tests/reference.py,
  no code shared with the engine), with k = (4/3) E/(1 − ν²) √(d/2) (Hertz) and
  c = x/V from e through the Lambert-W form e = [1 + W0(−(1+x) e^−(1+x))]/x;
- ``fruitimpact.simulate`` for the same inputs (the public single-impact path);
- the closed forms of the sensor stages: the flight time 2 V₂/g of a rebound,
  the damped natural frequency f_n √(1 − ζ²) of the plate, the low-frequency
  group delay Σ 1/(Q_k ω_c) = 2.6131/ω_c of a 4th-order Butterworth, the ADC
  step (clip_high − clip_low)/2^bits, the noise's standard deviation and the
  hum's frequency measured on the samples.
Each tolerance is explained where it is used.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import G
from reference import reference_powerlaw, state_at
from scipy.optimize import brentq
from scipy.special import lambertw

from fruitimpact import Fruit, simulate
from fruitimpact.signals import (
    Impact,
    Population,
    SensorModel,
    read_recording,
    synthesize,
    truth_path,
    write_recording,
    write_truth,
)

APPLE = {"mass": 0.18, "diameter": 0.075, "modulus": 3e6, "poisson": 0.35}
HEIGHT = 0.05
E = 0.5
ONSET = 0.0123456789  # between samples at every rate used here
CLASSES = (("soft", 2.5e6), ("medium", 4.5e6), ("firm", math.inf))


def _apple(**kwargs):
    values = dict(APPLE, time=ONSET, drop_height=HEIGHT, restitution=E)
    values.update(kwargs)
    return Impact(**values)


def _independent_contact(mass, diameter, modulus, poisson, velocity, restitution):
    """(k_c, c) from Hertz and the Lambert-W restitution relation, without the package."""
    stiffness = 4.0 / 3.0 * modulus / (1.0 - poisson ** 2) * math.sqrt(diameter / 2.0)

    def restitution_of(x):
        return (1.0 + lambertw(-(1.0 + x) * math.exp(-(1.0 + x))).real) / x

    x = brentq(lambda x: restitution_of(x) - restitution, 1e-3, 50.0, xtol=1e-15, rtol=1e-15)
    return stiffness, x / velocity


# --------------------------------------------------------------------------- the contact force

def test_impulse_of_the_noiseless_high_rate_signal():
    rec, truth = synthesize(SensorModel(rate=1e6), [_apple()])
    (impact,) = truth["impacts"]
    velocity = math.sqrt(2 * G * HEIGHT)
    expected = APPLE["mass"] * (1 + E) * velocity
    # the truth's impulse is m (1 + e) V: the engine's e and V agree with the inputs to rounding
    assert impact["impulse"] == pytest.approx(expected, rel=1e-12)
    # the trapezoid of the 1 MHz samples (≈ 7600 over the contact) errs by O((h/T)^2) ~ 1e-8,
    # and the onset between samples by O(h^2.5): 1e-6 leaves two orders of margin
    area = np.trapezoid(rec.lanes["lane0"], dx=1.0 / rec.rate)
    assert area == pytest.approx(expected, rel=1e-6)


def test_peak_and_time_to_peak_match_independent_references():
    rec, truth = synthesize(SensorModel(rate=1e6), [_apple()])
    (impact,) = truth["impacts"]
    velocity = math.sqrt(2 * G * HEIGHT)
    result = simulate(Fruit(**APPLE), drop_height=HEIGHT, restitution=E)
    # the same solver behind the public single-impact call: to rounding
    assert impact["peak_force"] == pytest.approx(result.characteristics.peak_force, rel=1e-12)
    assert impact["time_to_peak"] == pytest.approx(result.characteristics.time_to_peak, rel=1e-12)
    assert impact["contact_duration"] == pytest.approx(result.characteristics.contact_duration, rel=1e-12)
    # an independent DOP853 integration (rtol 1e-12, peak by root finding): 1e-8
    stiffness, damping = _independent_contact(**APPLE, velocity=velocity, restitution=E)
    assert impact["stiffness"] == pytest.approx(stiffness, rel=1e-12)
    ref = reference_powerlaw(APPLE["mass"], stiffness, damping, velocity)
    for key in ("peak_force", "time_to_peak", "contact_duration"):
        assert impact[key] == pytest.approx(ref[key], rel=1e-8), key
    assert impact["firmness_c"] == pytest.approx(ref["peak_force"] / ref["time_to_peak"], rel=1e-8)
    assert impact["firmness_c_star"] == pytest.approx(ref["peak_force"] / ref["time_to_peak"] ** 2, rel=1e-8)
    # the samples: the largest is F_max within the parabola's drop over half a sample
    # (F'' h²/8 ≈ 3e-8 relative at 1 MHz), at the sample nearest ONSET + t_c
    force = rec.lanes["lane0"]
    peak = int(np.argmax(force))
    assert force[peak] == pytest.approx(ref["peak_force"], rel=1e-6)
    assert abs(rec.time()[peak] - (ONSET + ref["time_to_peak"])) <= 0.5 / rec.rate + 1e-12


def test_samples_follow_the_curve_from_a_sub_sample_onset():
    # at 20 kHz every sample is the independent solution at t_n − t0 (the onset lies between samples)
    rec, _ = synthesize(SensorModel(rate=20000.0), [_apple()])
    velocity = math.sqrt(2 * G * HEIGHT)
    stiffness, damping = _independent_contact(**APPLE, velocity=velocity, restitution=E)
    ref = reference_powerlaw(APPLE["mass"], stiffness, damping, velocity)
    t = rec.time()
    inside = (t > ONSET) & (t < ONSET + ref["contact_duration"])
    deflection, rate = state_at(ref["solution"], t[inside] - ONSET)
    expected = stiffness * np.maximum(deflection, 0.0) ** 1.5 * (1.0 + damping * rate)
    # dense output of DOP853 at rtol 1e-12: 1e-7 of the peak
    np.testing.assert_allclose(rec.lanes["lane0"][inside], expected, atol=1e-7 * ref["peak_force"])
    assert np.all(rec.lanes["lane0"][~inside] == 0.0)
    assert inside.sum() == pytest.approx(ref["contact_duration"] * rec.rate, abs=1)


def test_rebounds_land_after_the_flight_time():
    rec, truth = synthesize(SensorModel(rate=20000.0), [_apple(rebounds=2)])
    first, second, third = truth["impacts"]
    assert [i["rebound"] for i in truth["impacts"]] == [False, True, True]
    assert (second["of"], third["of"]) == (0, 1) and first["of"] is None
    for parent, child in ((first, second), (second, third)):
        v2 = parent["restitution"] * parent["velocity"]  # V2 = e V1
        assert child["velocity"] == pytest.approx(v2, rel=1e-12)
        # leaves at separation, lands after 2 V2/g (free flight, g written here)
        assert child["start_time"] - parent["end_time"] == pytest.approx(2 * v2 / G, rel=1e-12)
        # same material (Hunt–Crossley c is a constant) at a lower speed: higher restitution
        assert child["damping_factor"] == pytest.approx(parent["damping_factor"], rel=1e-12)
        assert child["restitution"] > parent["restitution"]
        assert child["peak_force"] < parent["peak_force"]
    # the rebound's pulse is in the signal: at its peak time the sample is its peak force
    # within the curve's drop over one sample (F'' h²/2 ≈ 1 % at 20 kHz)
    k = round((second["start_time"] + second["time_to_peak"]) * rec.rate)
    assert rec.lanes["lane0"][k] == pytest.approx(second["peak_force"], rel=0.01)
    t = rec.time()
    gap = (t > first["end_time"]) & (t < second["start_time"])
    assert np.all(rec.lanes["lane0"][gap] == 0.0)


# --------------------------------------------------------------------------- the sensor chain

def test_noise_sd_on_a_flat_stretch():
    rec, _ = synthesize(SensorModel(noise_sd=0.8, seed=3), [], duration=1.0)
    # 20000 samples: the sample sd's own scatter is 1/√(2N) = 0.5 %, 5 % is ten of those
    assert np.std(rec.lanes["lane0"]) == pytest.approx(0.8, rel=0.05)
    assert abs(np.mean(rec.lanes["lane0"])) < 5 * 0.8 / math.sqrt(rec.samples)
    again, _ = synthesize(SensorModel(noise_sd=0.8, seed=3), [], duration=1.0)
    np.testing.assert_array_equal(again.lanes["lane0"], rec.lanes["lane0"])  # the seed repeats the run


def test_relative_noise_is_a_fraction_of_the_median_peak():
    impacts = [_apple(time=0.02), _apple(time=0.05, modulus=5e6), _apple(time=0.08, modulus=2e6)]
    rec, truth = synthesize(SensorModel(noise=0.01, seed=1), impacts, duration=0.2)
    peaks = [i["peak_force"] for i in truth["impacts"]]
    assert truth["sensor"]["noise_sd_used"] == pytest.approx(0.01 * sorted(peaks)[1], rel=1e-12)
    flat = rec.lanes["lane0"][rec.time() > 0.1]  # 2000 samples after the last contact: sd to ±1.6 % (1 sd)
    assert np.std(flat) == pytest.approx(truth["sensor"]["noise_sd_used"], rel=0.08)


def test_hum_frequency_and_amplitude_from_the_spectrum():
    rec, _ = synthesize(SensorModel(hum_amplitude=0.5, hum_frequency=60.0, seed=2), [], duration=1.0)
    x = rec.lanes["lane0"]
    spectrum = np.abs(np.fft.rfft(x))
    frequencies = np.fft.rfftfreq(x.size, 1.0 / rec.rate)
    # 1 s holds 60 whole periods: all the power sits in the 60 Hz bin, |X| = A N / 2
    assert frequencies[np.argmax(spectrum)] == 60.0
    assert 2.0 * spectrum.max() / x.size == pytest.approx(0.5, rel=1e-9)


def test_drift_and_offset():
    rec, _ = synthesize(SensorModel(drift=0.3, drift_offset=-2.0), [], duration=0.5)
    slope, intercept = np.polyfit(rec.time(), rec.lanes["lane0"], 1)
    assert slope == pytest.approx(0.3, rel=1e-9) and intercept == pytest.approx(-2.0, rel=1e-9)


def test_quantisation_step():
    sensor = SensorModel(noise_sd=0.5, adc_bits=12, clip_low=-250.0, clip_high=250.0, seed=4)
    rec, truth = synthesize(sensor, [_apple()])
    step = 500.0 / 2 ** 12
    assert truth["sensor"]["quantisation_step"] == step
    codes = (rec.lanes["lane0"] + 250.0) / step
    # every sample is a level clip_low + k·step (to the rounding of k·step in doubles)
    np.testing.assert_allclose(codes, np.rint(codes), atol=1e-9)
    levels = np.unique(np.rint(codes))
    assert np.min(np.diff(levels)) == 1.0 and len(levels) > 100


def test_clipped_samples_equal_the_limits():
    sensor = SensorModel(noise_sd=0.2, adc_bits=16, clip_low=-1.0, clip_high=60.0, seed=5)
    rec, truth = synthesize(sensor, [_apple()])
    x = rec.lanes["lane0"]
    assert truth["impacts"][0]["peak_force"] > 60.0
    assert (rec.clip_low, rec.clip_high) == (-1.0, 60.0)
    assert np.sum(x == 60.0) >= 5 and x.max() == 60.0 and x.min() >= -1.0
    # the clipped run covers the part of the pulse above the limit: between its first and last sample
    # the force exceeds 60 N (noise 0.2 N cannot bring it back below)
    at = np.flatnonzero(x == 60.0)
    assert np.all(x[at[0]:at[-1] + 1] > 59.0)
    plain, _ = synthesize(SensorModel(clip_high=60.0), [_apple()])
    assert plain.lanes["lane0"].max() == 60.0 and np.sum(plain.lanes["lane0"] == 60.0) >= 5


def test_plate_resonance_rings_at_the_damped_frequency_and_keeps_the_impulse():
    f_n, zeta = 1500.0, 0.02
    rec, truth = synthesize(SensorModel(rate=50000.0, plate_frequency=f_n, plate_damping=zeta), [_apple()],
                            duration=0.2)
    (impact,) = truth["impacts"]
    x, t = rec.lanes["lane0"], rec.time()
    # a unit-DC-gain resonator moves no area: the impulse over the ring-down (200 ms ≫ 1/(ζω) = 5 ms)
    # is kept to the trapezoid's error of the ringing at 33 samples per period (1e-6)
    assert np.trapezoid(x, dx=1 / rec.rate) == pytest.approx(impact["impulse"], rel=1e-6)
    # after separation the plate rings freely at f_n √(1 − ζ²): zero crossings (linear interpolation
    # between samples, exact up to the sinusoid's curvature, which cancels on average) over 20 periods: 1e-4
    tail = x[(t > impact["end_time"] + 1e-3) & (t < impact["end_time"] + 1e-3 + 20 / f_n)]
    times = t[(t > impact["end_time"] + 1e-3)][:tail.size]
    crossing = np.flatnonzero(np.sign(tail[:-1]) != np.sign(tail[1:]))
    exact = times[crossing] - tail[crossing] * (times[crossing + 1] - times[crossing]) / \
        (tail[crossing + 1] - tail[crossing])
    period = 2 * np.mean(np.diff(exact))
    assert 1 / period == pytest.approx(f_n * math.sqrt(1 - zeta ** 2), rel=1e-4)
    # the peak overshoots (impact-sensors.md §3.3: a few % for f_n = 1–2 kHz)
    assert 1.0 < x.max() / impact["peak_force"] < 1.1


def test_antialias_filter_delays_the_peak_by_its_group_delay():
    cutoff = 5000.0
    sensor = SensorModel(rate=500000.0, antialias_cutoff=cutoff, oversample=4)
    rec, truth = synthesize(sensor, [_apple()], duration=0.03)
    (impact,) = truth["impacts"]
    x = rec.lanes["lane0"]
    k = int(np.argmax(x))
    a, b, c = x[k - 1], x[k], x[k + 1]
    peak_time = rec.time()[k] + 0.5 * (a - c) / (a - 2 * b + c) / rec.rate  # parabola through 3 samples
    # Butterworth 4: two sections with Q = 1/(2 cos π/8), 1/(2 cos 3π/8); the delay at frequencies
    # ≪ f_c is Σ 1/(Q ω_c) = 2.6131/ω_c = 83.2 µs; the pulse's content lies below 1 kHz, where the delay
    # is flat to ~1e-3 of itself, and the 3-point parabola at 2 µs spacing errs by ~0.01 µs: 0.5 µs
    delay = (2 * math.cos(math.pi / 8) + 2 * math.cos(3 * math.pi / 8)) / (2 * math.pi * cutoff)
    assert peak_time - (ONSET + impact["time_to_peak"]) == pytest.approx(delay, abs=5e-7)
    # the peak itself barely changes (< 0.02 % in impact-sensors.md §1.7)
    assert x.max() == pytest.approx(impact["peak_force"], rel=2e-4)
    assert np.trapezoid(x, dx=1 / rec.rate) == pytest.approx(impact["impulse"], rel=1e-6)


def test_lanes_are_independent():
    impacts = [_apple(lane=0), _apple(lane=2, time=0.03)]
    rec, truth = synthesize(SensorModel(noise_sd=0.1, seed=9), impacts, lanes=3)
    assert rec.lane_names == ("lane0", "lane1", "lane2")
    assert [i["lane"] for i in truth["impacts"]] == ["lane0", "lane2"]
    assert rec.lanes["lane1"].max() < 1.0  # noise only
    assert not np.array_equal(rec.lanes["lane0"][:100], rec.lanes["lane1"][:100])


# --------------------------------------------------------------------------- populations

def test_population_slots_classes_and_seed():
    population = Population(count=20, interval=0.1, **APPLE, drop_height=HEIGHT, restitution=E, classes=CLASSES,
                            modulus_spread=0.4, mass_spread=0.1, jitter=0.03, start=0.2, lanes=2, seed=11)
    impacts = population.impacts()
    assert len(impacts) == 40 and impacts == population.impacts()  # the seed repeats the draw
    for impact in impacts:
        k = [i for i in impacts if i.lane == impact.lane].index(impact)
        assert abs(impact.time - (0.2 + (k + 0.5) * 0.1)) <= 0.03
        expected = "soft" if impact.modulus < 2.5e6 else "medium" if impact.modulus < 4.5e6 else "firm"
        assert impact.label == expected
        # same density and shape: d ∝ m^(1/3)
        assert impact.diameter / APPLE["diameter"] == pytest.approx((impact.mass / APPLE["mass"]) ** (1 / 3))
    assert {i.label for i in impacts} == {"soft", "medium", "firm"}
    moduli = np.log([i.modulus for i in impacts])
    assert np.std(moduli) == pytest.approx(0.4, rel=0.35)  # 40 draws: the sd's scatter is ±11 %


def test_population_synthesis_truth_is_json_and_round_trips(tmp_path):
    population = Population(count=4, interval=0.05, **APPLE, velocity=1.0, alpha=0.9, classes=CLASSES,
                            rebounds=1, seed=1)
    rec, truth = synthesize(SensorModel(noise=0.005, seed=2), population)
    assert len(truth["impacts"]) == 8  # every rebound lands inside the default duration
    assert [i["start_time"] for i in truth["impacts"]] == sorted(i["start_time"] for i in truth["impacts"])
    for i, impact in enumerate(truth["impacts"]):
        if impact["rebound"]:
            parent = truth["impacts"][impact["of"]]
            assert impact["start_time"] > parent["end_time"] and impact["class"] == parent["class"]
        assert impact["complete"] and impact["damping_factor"] == pytest.approx(1.35)  # c = 1.5 α
    assert rec.duration >= max(i["end_time"] for i in truth["impacts"]) + 0.02
    written = write_truth(truth, tmp_path / "run.csv")
    assert written == tmp_path / "run.truth.json" == truth_path(tmp_path / "run.csv")
    assert json.loads(written.read_text()) == truth
    back = read_recording(write_recording(rec, tmp_path / "run.csv"))
    np.testing.assert_array_equal(back.lanes["lane0"], rec.lanes["lane0"])


def test_writing_is_atomic_and_checked(tmp_path):
    rec, _ = synthesize(SensorModel(noise_sd=1.0, seed=1), [], duration=0.01)
    with pytest.raises(ValueError, match=r"unsupported format \.wav"):
        write_recording(rec, tmp_path / "a.wav")
    with pytest.raises(ValueError, match=r"folder .* does not exist"):
        write_recording(rec, tmp_path / "missing" / "a.csv")
    path = write_recording(rec, tmp_path / "a.tdms")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.tdms"]  # no temporary left behind
    assert read_recording(path).samples == rec.samples
    with pytest.raises(ValueError, match=r"lane name 'a,b' cannot be written to a CSV header"):
        from fruitimpact.signals import Recording
        write_recording(Recording(rate=1.0, lanes={"a,b": [1.0]}), tmp_path / "x.csv")
    with pytest.raises(ValueError, match=r"truth cannot be written as JSON"):
        write_truth({"x": math.nan}, tmp_path / "t.json")


# --------------------------------------------------------------------------- refusals

@pytest.mark.parametrize("kwargs,match", [
    ({"noise_sd": 1.0, "noise": 0.01}, r"give noise_sd \[N\] or noise"),
    ({"adc_bits": 12}, r"adc_bits needs both clip_low and clip_high"),
    ({"adc_bits": 12, "clip_low": 1.0, "clip_high": -1.0}, r"clip_low must be below clip_high"),
    ({"plate_frequency": 2000.0}, r"plate_damping .* is required with plate_frequency"),
    ({"antialias_cutoff": 10000.0}, r"antialias_cutoff must be a finite number >= 0 and < 10000"),
    ({"hum_frequency": 0.0}, r"hum_frequency must be a finite number > 0"),
    ({"rate": -5.0}, r"rate must be a finite number of Hz in \(0, 1e\+07\]"),
    ({"rate": 5e7}, r"rate must be a finite number of Hz in \(0, 1e\+07\]"),
    ({"noise": 5.0}, r"SensorModel.noise must be a finite number >= 0 and <= 1"),
    ({"noise_sd": math.nan}, r"noise_sd must be a finite number >= 0"),
    ({"adc_bits": 1.5}, r"adc_bits must be an integer in \[0, 32\]"),
    ({"plate_frequency": 50000.0, "plate_damping": 0.05}, r"plate_frequency must be .* < 16000"),
])
def test_sensor_refuses(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SensorModel(**kwargs)


@pytest.mark.parametrize("kwargs,match", [
    ({"velocity": 1.0}, r"exactly one of velocity \[m/s\] and drop_height"),
    ({"drop_height": None}, r"exactly one of velocity \[m/s\] and drop_height"),
    ({"alpha": 0.5}, r"exactly one of restitution and alpha"),
    ({"time": -0.1}, r"Impact.time must be a finite number >= 0"),
    ({"mass": math.nan}, r"Impact.mass must be a finite number"),
    ({"rebounds": 3}, r"rebounds must be an integer in \[0, 2\]"),
])
def test_impact_refuses(kwargs, match):
    with pytest.raises(ValueError, match=match):
        _apple(**kwargs)


def test_synthesize_refuses_before_work():
    sensor = SensorModel()
    with pytest.raises(ValueError, match=r"impacts\[0\] is on lane 1 but the recording has lanes=1"):
        synthesize(sensor, [_apple(lane=1)])
    with pytest.raises(ValueError, match=r"impacts\[0\] starts at 0.0123457 s, not before duration=0.01 s"):
        synthesize(sensor, [_apple()], duration=0.01)
    with pytest.raises(ValueError, match=r"impacts\[1\]: modulus must be a finite number > 0 Pa"):
        synthesize(sensor, [_apple(), _apple(modulus=-1.0)])
    with pytest.raises(ValueError, match=r"impacts\[0\]: poisson must be"):
        synthesize(sensor, [_apple(poisson=0.7)])
    with pytest.raises(ValueError, match=r"duration is required when there are no impacts"):
        synthesize(sensor, [])
    with pytest.raises(ValueError, match=r"noise is relative to the typical peak force"):
        synthesize(SensorModel(noise=0.01), [], duration=1.0)
    with pytest.raises(ValueError, match=r"impacts must be a sequence of Impact or a Population"):
        synthesize(sensor, _apple())
    with pytest.raises(ValueError, match=r"sensor must be a SensorModel"):
        synthesize({"rate": 1.0}, [])


@pytest.mark.parametrize("classes", [(("soft", 2e6),), (("a", 3e6), ("b", 2e6), ("c", math.inf)), ("soft",), ()])
def test_population_refuses_bad_classes(classes):
    with pytest.raises(ValueError, match=r"Population.classes must"):
        Population(count=2, interval=0.1, **APPLE, velocity=1.0, restitution=E, classes=classes)


def test_population_refuses_jitter_beyond_half_a_slot():
    with pytest.raises(ValueError, match=r"Population.jitter must be a finite number >= 0 and <= 0.05"):
        Population(count=2, interval=0.1, **APPLE, velocity=1.0, restitution=E, classes=CLASSES, jitter=0.06)


@pytest.mark.parametrize("name", ["modulus_spread", "mass_spread"])
def test_population_refuses_a_spread_whose_draws_overflow(name):
    # a lognormal sd of 6e5 (a modulus typed where its spread goes) drew E = inf: a StopIteration traceback in
    # the class lookup.  Beyond 2 (a factor e² per sd) no fruit population is meant.
    with pytest.raises(ValueError, match=rf"Population.{name} must be a finite number >= 0 and <= 2"):
        Population(count=2, interval=0.1, **APPLE, velocity=1.0, restitution=E, classes=CLASSES, **{name: 6e5})


@pytest.mark.parametrize("argv,expected", [
    (("--seed", "x"), "argument --seed: seed must be an integer >= 0; got 'x'"),  # was "SensorModel.seed ... -1"
    (("--rebounds", "3"), "argument --rebounds: rebounds must be an integer in [0, 2]; got '3'"),
    (("--adc-bits", "40"), "argument --adc-bits: adc_bits must be an integer in [0, 32]; got '40'"),
])
def test_synth_integer_options_are_named_with_their_range(cli, tmp_path, argv, expected):
    assert cli.error("synth", "-o", tmp_path / "r.csv", *argv) == f"fruitimpact synth: error: {expected}"


def test_synth_truth_names_its_recording_by_checksum(cli, tmp_path):
    """The recording and its truth are two files, each written atomically; a run killed between them left a new
    recording beside an earlier run's truth, and nothing told them apart (an attack).  The truth now carries the
    recording's SHA-256 (hashlib over the file as written): an earlier truth does not match a new recording."""
    import hashlib
    import json

    out = tmp_path / "rec.csv"
    cli.ok("synth", "-o", out, "--count", "3", "--seed", "1")
    first = json.loads((tmp_path / "rec.truth.json").read_text())
    assert first["recording"] == {"file": "rec.csv", "sha256": hashlib.sha256(out.read_bytes()).hexdigest()}
    cli.ok("synth", "-o", out, "--count", "3", "--seed", "2")
    assert first["recording"]["sha256"] != hashlib.sha256(out.read_bytes()).hexdigest()
