"""The Hunt–Crossley pulse fit (issue 8, item 3): ``fruitimpact.signals.fit``.

Pulses are built here from the exact engine (``powerlaw_curves``) with known (K, c, m, V) on a
20 kHz grid with a random sub-sample onset and 1 % Gaussian noise (seeded), then fitted.  Over 50
seeds the fit must recover K, e and m (given V) and V (given m), with standard errors that describe
its scatter; the model-based peak force and time to peak must beat the raw max-sample estimates;
SciPy's ``least_squares`` on the exact engine (not the fit's table) must find the same optimum.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fruitimpact.physics.hertz import rigid_plane_stiffness
from fruitimpact.engine.powerlaw import (
    powerlaw_curves,
    powerlaw_single,
    x_of_restitution,
)
from fruitimpact.signals.fit import RESULT_KEYS, fit_impact, model_curve
from fruitimpact.signals.pulse import shape_table_error

RATE = 20_000.0  # Hz
# an apple: 200 g, 75 mm, E = 3 MPa, ν = 0.35, dropped 5.1 cm (V = 1 m/s), e = 0.5
MASS, DIAMETER, MODULUS, POISSON, VELOCITY, RESTITUTION = 0.2, 0.075, 3e6, 0.35, 1.0, 0.5
STIFFNESS = float(rigid_plane_stiffness(MODULUS, POISSON, DIAMETER))
DAMPING = x_of_restitution(RESTITUTION) / VELOCITY
TRUE = powerlaw_single(MASS, STIFFNESS, 1.5, DAMPING, VELOCITY, DIAMETER / 2)  # F_max, t_c, T, ...
PEAK, TIME_TO_PEAK, DURATION = TRUE[0], TRUE[1], TRUE[2]
SEEDS = range(50)


def pulse(seed, noise=0.01, ringing=0.0, offset=0.0, mass=MASS, stiffness=STIFFNESS, damping=DAMPING,
          velocity=VELOCITY, before=40, after=200, start=1.0):
    """(time, force, onset): the exact pulse sampled at 20 kHz from ``before`` samples before the
    onset (a random fraction of a sample after a grid point) to ``after`` samples after it, with
    Gaussian noise of ``noise`` · F_max, an optional damped 2.5 kHz ringing of amplitude
    ``ringing`` · F_max (ζ = 0.03, from the onset on) and a constant ``offset`` · F_max."""
    rng = np.random.default_rng(seed)
    peak = powerlaw_single(mass, stiffness, 1.5, damping, velocity, 0.03)[0]
    grid = np.arange(-before, after) / RATE
    onset = rng.uniform(0.0, 1.0) / RATE
    force = powerlaw_curves(mass, stiffness, damping, velocity, grid - onset)[2]
    if ringing:
        lag = np.maximum(grid - onset, 0.0)
        omega = 2.0 * math.pi * 2500.0
        force = force + ringing * peak * np.sin(omega * lag) * np.exp(-0.03 * omega * lag)
    force = force + offset * peak + noise * peak * rng.standard_normal(grid.size)
    return grid + start, force, onset + start


@pytest.fixture(scope="module")
def trials():
    """Per seed: the fits given V and given m, and the raw max-sample peak and time to peak."""
    rows = []
    for seed in SEEDS:
        time, force, onset = pulse(seed)
        top = int(np.argmax(force))
        rows.append({"v": fit_impact(time, force, velocity=VELOCITY), "m": fit_impact(time, force, mass=MASS),
                     "raw_peak": force[top], "raw_time_to_peak": time[top] - onset, "onset": onset})
    return rows


def errors(trials, fit, key, truth, relative=True):
    values = np.array([t[fit][key] for t in trials])
    stderr = np.array([t[fit][key + "_stderr"] for t in trials])
    error = values / truth - 1.0 if relative else values - truth
    return error, (stderr / truth if relative else stderr)


# ------------------------------------------------------------------------------------------ the model

def test_the_shape_table_matches_the_exact_engine():
    """The tabulated pulse shape against the exact engine (``engine.powerlaw``, its own quadrature) at random
    (σ, x), in units of the peak: three orders below a 1 % noise over the whole range of x (the worst near
    X_MAX, e ≈ 0.1, a truncated Chebyshev series converges slowest where the pulse is least smooth) and five
    orders below it for x ≤ 4 (e ≥ 0.24, every fruit on a plate)."""
    assert shape_table_error(samples=100) < 1e-5
    assert shape_table_error(samples=100, seed=2, x_max=4.0) < 2e-7  # 9.8e-8 the largest of 12,000 samples


def test_noise_free_pulse_is_recovered_to_the_table_accuracy():
    time, force, onset = pulse(3, noise=0.0)
    result = fit_impact(time, force, velocity=VELOCITY)
    assert result["converged"], result["message"]
    assert result["stiffness"] == pytest.approx(STIFFNESS, rel=1e-5)
    assert result["mass"] == pytest.approx(MASS, rel=1e-5)
    assert result["restitution"] == pytest.approx(RESTITUTION, abs=1e-6)
    assert result["start_time"] == pytest.approx(onset, abs=1e-9)
    assert result["fit_residual_relative"] < 1e-6


def test_result_has_every_key_of_the_contract(trials):
    assert set(trials[0]["v"]) == set(RESULT_KEYS)
    failed = fit_impact(np.arange(100) / RATE, np.zeros(100), velocity=1.0)
    assert set(failed) == set(RESULT_KEYS)
    assert trials[0]["v"]["converged"] is True and failed["converged"] is False


# ------------------------------------------------------------------------------- accuracy over seeds

def test_all_converge_quickly(trials):
    assert all(t["v"]["converged"] and t["m"]["converged"] for t in trials)
    assert max(t["v"]["iterations"] for t in trials) <= 30


def test_given_velocity_recovers_stiffness_restitution_and_mass(trials):
    k, k_sd = errors(trials, "v", "stiffness", STIFFNESS)
    e, _ = errors(trials, "v", "restitution", RESTITUTION, relative=False)
    m, _ = errors(trials, "v", "mass", MASS)
    # measured: K mean |err| 0.87 %, 94 % of seeds within 2 %, worst 3.9 % (a 4.0 stderr seed);
    # the stderr of K is 1.1 % here: the Cramér–Rao limit at 1 % noise, not the optimiser
    assert np.mean(np.abs(k)) < 0.01
    assert np.mean(np.abs(k) < 0.02) >= 0.9
    assert np.max(np.abs(k)) < 4.5 * np.mean(k_sd)
    # e: mean |err| 0.004, worst 0.017; m: mean 0.37 %, worst 1.8 %
    assert np.max(np.abs(e)) < 0.02 and np.mean(np.abs(e)) < 0.006
    assert np.max(np.abs(m)) < 0.02 and np.mean(np.abs(m)) < 0.005
    assert abs(np.mean(k)) < 3 * np.std(k) / math.sqrt(len(k))  # no bias
    assert all(t["v"]["velocity"] == VELOCITY and t["v"]["velocity_stderr"] == 0.0 for t in trials)


def test_given_mass_recovers_velocity(trials):
    v, _ = errors(trials, "m", "velocity", VELOCITY)
    e, _ = errors(trials, "m", "restitution", RESTITUTION, relative=False)
    k, k_sd = errors(trials, "m", "stiffness", STIFFNESS)
    assert np.max(np.abs(v)) < 0.02 and np.mean(np.abs(v)) < 0.005
    assert np.max(np.abs(e)) < 0.02
    # given m, K ∝ F_s^-0.5 t_s^-3 is twice as sensitive to the time scale as given V (K ∝ F_s t_s^-1.5):
    # stderr 1.8 %, measured mean |err| 1.4 %, worst 6.8 % (3.8 stderr), 78 % of seeds within 2 %
    assert np.mean(np.abs(k)) < 0.02
    assert np.max(np.abs(k)) < 4.5 * np.mean(k_sd)
    assert all(t["m"]["mass"] == MASS and t["m"]["mass_stderr"] == 0.0 for t in trials)


@pytest.mark.parametrize("fit, key, truth", [("v", "stiffness", STIFFNESS), ("v", "restitution", RESTITUTION),
                                              ("v", "mass", MASS), ("m", "velocity", VELOCITY),
                                              ("m", "stiffness", STIFFNESS), ("v", "peak_force", PEAK),
                                              ("v", "time_to_peak", TIME_TO_PEAK),
                                              ("v", "contact_duration", DURATION)])
def test_standard_errors_describe_the_scatter(trials, fit, key, truth):
    error, stderr = errors(trials, fit, key, truth, relative=False)
    z = error / stderr
    assert np.mean(np.abs(z) <= 2.0) >= 0.88  # 95 % for a Gaussian; measured 92–96 %
    assert 0.75 < np.std(z) < 1.35
    assert np.max(stderr) < 1.5 * np.min(stderr)  # stable from seed to seed


def test_model_peak_and_time_to_peak_beat_the_raw_samples(trials):
    peak = np.array([t["v"]["peak_force"] for t in trials]) / PEAK - 1.0
    t_c = np.array([t["v"]["time_to_peak"] for t in trials]) / TIME_TO_PEAK - 1.0
    raw_peak = np.array([t["raw_peak"] for t in trials]) / PEAK - 1.0
    raw_t_c = np.array([t["raw_time_to_peak"] for t in trials]) / TIME_TO_PEAK - 1.0
    # measured: fit peak worst 0.41 %, t_c worst 0.64 %; raw peak +1.06 % mean (worst 2.3 %),
    # raw t_c ±4 % (worst 8 %)
    assert np.max(np.abs(peak)) < 0.01 and np.max(np.abs(t_c)) < 0.02
    assert np.mean(raw_peak) > 0.007  # the raw maximum sample's upward bias
    assert np.mean(np.abs(peak)) < np.mean(np.abs(raw_peak)) / 4
    assert np.mean(np.abs(t_c)) < np.mean(np.abs(raw_t_c)) / 4
    onset = np.array([t["v"]["start_time"] - t["onset"] for t in trials])
    assert np.max(np.abs(onset)) < 0.5 / RATE  # the onset to better than half a sample


def test_firmness_indices_come_from_the_model(trials):
    result = trials[0]["v"]
    assert result["firmness_c"] == pytest.approx(result["peak_force"] / result["time_to_peak"])
    assert result["firmness_c_star"] == pytest.approx(result["peak_force"] / result["time_to_peak"] ** 2)
    c = np.array([t["v"]["firmness_c"] for t in trials]) / (PEAK / TIME_TO_PEAK) - 1
    assert np.max(np.abs(c)) < 0.02


def test_impulse_is_momentum_change_and_the_model_integral(trials):
    for t in trials[:2]:
        result = t["v"]
        assert result["impulse"] == pytest.approx(result["mass"] * (1 + result["restitution"]) * VELOCITY, rel=1e-12)
        grid = np.linspace(result["start_time"] - 1e-4, result["start_time"] + 1.1 * result["contact_duration"],
                           20_001)
        assert np.trapezoid(model_curve(grid, result), grid) == pytest.approx(result["impulse"], rel=1e-6)
    impulse, stderr = errors(trials, "v", "impulse", MASS * (1 + RESTITUTION) * VELOCITY)
    assert np.max(np.abs(impulse)) < 0.01
    assert np.mean(np.abs(impulse) <= 2 * stderr) >= 0.88


def test_model_curve_draws_the_fit():
    time, force, _ = pulse(7)
    result = fit_impact(time, force, velocity=VELOCITY)
    drawn = model_curve(time, result)
    assert np.sqrt(np.mean((force - drawn) ** 2)) == pytest.approx(result["fit_residual"], rel=1e-5)
    assert np.all(drawn[time < result["start_time"]] == 0.0)
    assert np.all(drawn[time > result["start_time"] + result["contact_duration"]] == 0.0)
    fine = np.linspace(time[0], time[-1], 5000)
    assert np.max(model_curve(fine, result)) == pytest.approx(result["peak_force"], rel=1e-4)
    assert np.all(np.isnan(model_curve(time, fit_impact(time, 0 * force, velocity=1.0))))


# -------------------------------------------------------------------------------- modulus, options

def test_modulus_from_stiffness_with_diameter_and_poisson():
    time, force, _ = pulse(11)
    result = fit_impact(time, force, velocity=VELOCITY, diameter=DIAMETER, poisson=POISSON)
    k = result["stiffness"]
    assert result["modulus"] == pytest.approx((1 - POISSON ** 2) * 3 * k / (4 * math.sqrt(DIAMETER / 2)), rel=1e-12)
    assert float(rigid_plane_stiffness(result["modulus"], POISSON, DIAMETER)) == pytest.approx(k, rel=1e-12)
    assert result["modulus_stderr"] / result["modulus"] == pytest.approx(result["stiffness_stderr"] / k, rel=1e-6)
    assert abs(result["modulus"] / MODULUS - 1) < 3 * result["modulus_stderr"] / result["modulus"]
    assert math.isnan(fit_impact(time, force, velocity=VELOCITY)["modulus"])


def test_given_noise_sets_the_standard_errors():
    time, force, _ = pulse(5)
    estimated = fit_impact(time, force, velocity=VELOCITY)
    known = fit_impact(time, force, velocity=VELOCITY, noise=0.01 * PEAK)
    assert known["stiffness"] == pytest.approx(estimated["stiffness"], rel=1e-6)  # same optimum
    assert known["noise"] == 0.01 * PEAK
    assert known["stiffness_stderr"] == pytest.approx(estimated["stiffness_stderr"] * known["noise"]
                                                      / estimated["noise"], rel=1e-6)
    assert known["stiffness_stderr"] == pytest.approx(estimated["stiffness_stderr"], rel=0.15)


def test_time_origin_does_not_matter():
    time, force, _ = pulse(2, start=0.0)
    a = fit_impact(time, force, velocity=VELOCITY)
    b = fit_impact(time + 1000.0, force, velocity=VELOCITY)
    assert b["start_time"] - 1000.0 == pytest.approx(a["start_time"], abs=1e-9)
    assert b["stiffness"] == pytest.approx(a["stiffness"], rel=1e-6)


def test_undamped_pulse_reaches_restitution_one():
    time, force, _ = pulse(4, damping=0.0)
    result = fit_impact(time, force, velocity=VELOCITY)
    assert result["converged"], result["message"]
    assert result["restitution"] > 0.985
    assert result["stiffness"] == pytest.approx(STIFFNESS, rel=0.03)


@pytest.mark.parametrize("restitution", [0.3, 0.7, 0.9])
def test_other_restitutions(restitution):
    damping = x_of_restitution(restitution) / VELOCITY
    for seed in range(5):
        time, force, _ = pulse(seed, damping=damping, after=300)
        result = fit_impact(time, force, velocity=VELOCITY)
        assert result["converged"], result["message"]
        assert abs(result["restitution"] - restitution) < 4 * result["restitution_stderr"] + 1e-3
        assert abs(result["stiffness"] / STIFFNESS - 1) < 4 * result["stiffness_stderr"] / STIFFNESS


# --------------------------------------------------------------------------------------- robustness

def test_ringing_is_tolerated():
    """A 2.5 kHz damped ringing of 5 % of F_max (ζ = 0.03) from the onset on.  The pulse's spectrum
    is −60 dB at 1.6 kHz, so the ringing is nearly orthogonal to the model's Jacobian: it adds
    structured residual, not bias.  Measured over 20 seeds: K worst 3.95 % (mean +0.04 %; 3.93 %
    without the ringing: the same outlier seed), e worst 0.018, peak worst 0.34 %, t_c worst
    0.58 % — the noise-only figures.  Tolerances: K 4.5 %, e 0.02, peak 1 %, t_c 2 %."""
    k, e, peak, t_c = [], [], [], []
    for seed in range(20):
        time, force, _ = pulse(seed, ringing=0.05)
        result = fit_impact(time, force, velocity=VELOCITY)
        assert result["converged"], result["message"]
        k.append(result["stiffness"] / STIFFNESS - 1)
        e.append(result["restitution"] - RESTITUTION)
        peak.append(result["peak_force"] / PEAK - 1)
        t_c.append(result["time_to_peak"] / TIME_TO_PEAK - 1)
    assert np.max(np.abs(k)) < 0.045 and abs(np.mean(k)) < 0.01
    assert np.max(np.abs(e)) < 0.02
    assert np.max(np.abs(peak)) < 0.01 and np.max(np.abs(t_c)) < 0.02


def test_mains_hum_converges_with_a_stated_bias():
    """50 Hz hum of 1 % of F_max (random phase) left in the signal: over the 8 ms contact it is a
    sloped, curved baseline under the weak tail, so it moves T and with it K.  Measured over 20
    seeds: all converge; K mean |err| 4.9 % (worst 11 %), e worst 0.05, peak worst 1.2 %, t_c
    worst 1.3 %.  Remove hum before fitting (a local fit with a 50 Hz sine, see the detection)."""
    k, e, peak, t_c = [], [], [], []
    for seed in range(20):
        time, force, _ = pulse(seed)
        phase = np.random.default_rng(100 + seed).uniform(0, 2 * math.pi)
        result = fit_impact(time, force + 0.01 * PEAK * np.sin(2 * math.pi * 50 * time + phase), velocity=VELOCITY)
        assert result["converged"], result["message"]
        k.append(result["stiffness"] / STIFFNESS - 1)
        e.append(result["restitution"] - RESTITUTION)
        peak.append(result["peak_force"] / PEAK - 1)
        t_c.append(result["time_to_peak"] / TIME_TO_PEAK - 1)
    assert np.max(np.abs(k)) < 0.12 and np.max(np.abs(e)) < 0.06
    assert np.max(np.abs(peak)) < 0.015 and np.max(np.abs(t_c)) < 0.02


def test_a_residual_baseline_needs_the_baseline_option():
    """A 1 % offset under the long tail biases T and so K (the fit stretches the tail); fitting
    a linear baseline with the pulse removes the bias at ~10 % more stderr."""
    time, force, _ = pulse(6, offset=0.01)
    plain = fit_impact(time, force, velocity=VELOCITY)
    assert not plain["converged"] or abs(plain["stiffness"] / STIFFNESS - 1) > 0.1
    for baseline in ("offset", "linear"):
        fitted = fit_impact(time, force, velocity=VELOCITY, baseline=baseline)
        assert fitted["converged"], fitted["message"]
        assert abs(fitted["stiffness"] / STIFFNESS - 1) < 3 * fitted["stiffness_stderr"] / STIFFNESS
        assert abs(fitted["restitution"] - RESTITUTION) < 0.02


def test_clipped_samples_are_excluded_by_mask():
    time, force, _ = pulse(8)
    clipped = np.minimum(force, 0.85 * PEAK)
    naive = fit_impact(time, clipped, velocity=VELOCITY)
    assert "clipped" in naive["message"]
    assert naive["peak_force"] < 0.95 * PEAK
    masked = fit_impact(time, clipped, velocity=VELOCITY, mask=clipped < 0.85 * PEAK)
    assert masked["converged"], masked["message"]
    assert masked["peak_force"] == pytest.approx(PEAK, rel=0.01)
    assert masked["stiffness"] == pytest.approx(STIFFNESS, rel=0.04)
    assert "clipped" not in masked["message"]


def test_nan_samples_can_be_masked_out():
    time, force, _ = pulse(9)
    force[100] = np.nan
    result = fit_impact(time, force, velocity=VELOCITY, mask=np.isfinite(force))
    assert result["converged"]


def test_too_short_pulse_is_not_converged():
    # a berry on a stiff plate: T ≈ 0.24 ms, 4–5 samples in contact at 20 kHz
    time, force, _ = pulse(1, mass=0.0005, stiffness=2e7, velocity=0.5, before=20, after=40)
    result = fit_impact(time, force, velocity=0.5)
    assert result["converged"] is False
    assert "short" in result["message"] or "samples" in result["message"]


@pytest.mark.parametrize("force", [np.zeros(200), np.full(200, 3.0),
                                   np.random.default_rng(0).normal(0.0, 1.0, 200)], ids=["zero", "flat", "noise"])
def test_flat_signal_is_not_converged(force):
    result = fit_impact(np.arange(200) / RATE, force, velocity=1.0)
    assert result["converged"] is False and result["message"]
    assert math.isnan(result["stiffness"])


def test_pulse_cut_by_the_window_is_not_converged():
    time, force, _ = pulse(2, after=120)  # the window ends at 0.76 T
    result = fit_impact(time, force, velocity=VELOCITY)
    assert result["converged"] is False and "window" in result["message"]


def _cut_fits(restitution, noise, seeds):
    """Per seed: the exact engine's pulse cut at the detector's last sample above 3 noise sd (a following contact
    rising there), fitted with ``open_end``, and the same pulse's full-window fit."""
    damping = x_of_restitution(restitution) / VELOCITY
    peak = powerlaw_single(MASS, STIFFNESS, 1.5, damping, VELOCITY, DIAMETER / 2)[0]
    rows = []
    for seed in range(seeds):
        time, force, onset = pulse(seed, noise=noise, damping=damping, after=400)
        exact = powerlaw_curves(MASS, STIFFNESS, damping, VELOCITY, time - onset)[2]
        end = int(np.nonzero(exact >= 3 * noise * peak)[0][-1]) + 1
        cut = fit_impact(time[:end + 1], force[:end + 1], velocity=VELOCITY, open_end=True, noise=noise * peak)
        full = fit_impact(time, force, velocity=VELOCITY, noise=noise * peak)
        rows.append((cut, full, time[:end + 1], force[:end + 1]))
    return rows


@pytest.mark.parametrize("restitution,noise", [(0.6, 0.01), (0.7, 0.01), (0.7, 0.03)])
def test_a_window_cut_by_the_next_contact_extrapolates_the_tail(restitution, noise):
    """A fruit landing just after this one ended cuts the window at the detector's offset (3 noise sd): the tail
    below it, 6–14 % of these damped Hunt–Crossley pulses, is not sampled.  Where the samples still fix the damping,
    ``open_end`` extrapolates it by the force law: the exact engine's K is recovered with no bias (mean within 3
    standard errors of the mean), a standard error that describes the scatter (rms error/stderr < 1.5; measured
    0.75–1.0) and a scatter within 1.5 times the full window's (measured 1.0–1.1); without ``open_end`` the fit is
    refused."""
    rows = _cut_fits(restitution, noise, 30)
    errors, z, full_errors = [], [], []
    for k, (cut, full, time, force) in enumerate(rows):
        if k < 3:
            closed = fit_impact(time, force, velocity=VELOCITY)
            assert closed["converged"] is False and "window" in closed["message"]
        if not cut["converged"]:
            continue
        assert "not sampled" in cut["message"]
        errors.append(cut["stiffness"] / STIFFNESS - 1.0)
        z.append(errors[-1] * STIFFNESS / cut["stiffness_stderr"])
        full_errors.append(full["stiffness"] / STIFFNESS - 1.0)
    errors = np.array(errors)
    assert len(errors) >= 25  # measured 27–30 of 30
    assert abs(np.mean(errors)) < 3 * np.std(errors) / math.sqrt(len(errors))
    assert math.sqrt(np.mean(np.square(z))) < 1.5
    assert np.mean(np.abs(errors)) < 1.5 * np.mean(np.abs(full_errors))


@pytest.mark.parametrize("restitution,noise", [(0.3, 0.01), (0.35, 0.02), (0.4, 0.02), (0.45, 0.01)])
def test_a_cut_that_takes_what_fixes_the_damping_is_refused_not_misfitted(restitution, noise):
    """Below e ≈ 0.45 (and at 2–3 % noise) the tail below 3 sd is 21–37 % of the pulse and holds what fixes the
    damping: a free fit drifts to a livelier, stiffer pulse (K +12 to +42 %, its stderr covering a third of that)
    that a restitution 0.05 lower fits as well (Δχ² 0.5–2).  Those are refused ("damping undetermined"), never
    reported: every fit admitted is within 10 % of K and 5 of its standard errors (worst measured: 7.5 %, 4.3
    stderr, at e = 0.45), and they average within 2.5 % (at e = 0.45, 1 % noise, where 22–35 of 40–60 are
    admitted, measured +1.4–1.6 %: the edge of the regime, where the stderr understates the error a little)."""
    rows = _cut_fits(restitution, noise, 30)
    admitted = [cut for cut, _, _, _ in rows if cut["converged"]]
    undetermined = sum("damping undetermined" in cut["message"] for cut, _, _, _ in rows)
    assert undetermined >= 2
    errors = np.array([cut["stiffness"] / STIFFNESS - 1.0 for cut in admitted])
    for cut, error in zip(admitted, errors):
        assert abs(error) < 0.10 and abs(error) * STIFFNESS < 5 * cut["stiffness_stderr"], cut["message"]
    if len(errors):
        assert abs(np.mean(errors)) < 0.025


def test_an_open_end_does_not_admit_a_pulse_cut_at_its_middle():
    time, force, _ = pulse(2, after=95)  # the window ends at 0.6 T: 39 % of the contact unsampled
    result = fit_impact(time, force, velocity=VELOCITY, open_end=True)
    assert result["converged"] is False and "after the window" in result["message"]


# ------------------------------------------------------------------------------------------ refusals

def test_refusals():
    time, force, _ = pulse(0)
    with pytest.raises(ValueError, match="velocity.*mass"):
        fit_impact(time, force)
    with pytest.raises(ValueError, match="not both"):
        fit_impact(time, force, velocity=1.0, mass=0.2)
    with pytest.raises(ValueError, match="same length"):
        fit_impact(time[:-1], force, velocity=1.0)
    bad = force.copy()
    bad[50] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        fit_impact(time, bad, velocity=1.0)
    with pytest.raises(ValueError, match="NaN"):
        fit_impact(np.where(np.arange(time.size) == 3, np.nan, time), force, velocity=1.0)
    with pytest.raises(ValueError, match="increasing"):
        fit_impact(time[::-1], force, velocity=1.0)
    with pytest.raises(ValueError, match="velocity"):
        fit_impact(time, force, velocity=-1.0)
    with pytest.raises(ValueError, match="together"):
        fit_impact(time, force, velocity=1.0, diameter=0.07)
    with pytest.raises(ValueError, match="poisson"):
        fit_impact(time, force, velocity=1.0, diameter=0.07, poisson=0.7)
    with pytest.raises(ValueError, match="mask"):
        fit_impact(time, force, velocity=1.0, mask=np.ones(time.size))
    with pytest.raises(ValueError, match="noise"):
        fit_impact(time, force, velocity=1.0, noise=0.0)
    with pytest.raises(ValueError, match="baseline"):
        fit_impact(time, force, velocity=1.0, baseline="quadratic")
    with pytest.raises(ValueError, match="1-D"):
        fit_impact(time[None, :], force[None, :], velocity=1.0)


# ------------------------------------------------------------------ an independent optimiser and model

def test_scipy_least_squares_on_the_exact_engine_finds_the_same_optimum():
    """SciPy's trust-region least squares on the exact engine (``powerlaw_curves``, not the fit's
    table), in the physical parameters (t0, ln K, ln m, x) with finite-difference Jacobian, started
    from the true values, must land on the fit's optimum."""
    least_squares = pytest.importorskip("scipy.optimize").least_squares
    time, force, onset = pulse(12)
    ours = fit_impact(time, force, velocity=VELOCITY)

    def residual(p):
        t0, log_k, log_m, x = p
        return powerlaw_curves(math.exp(log_m), math.exp(log_k), x / VELOCITY, VELOCITY, time - t0)[2] - force

    start = [onset, math.log(STIFFNESS), math.log(MASS), DAMPING * VELOCITY]
    theirs = least_squares(residual, start, x_scale=[1e-5, 0.01, 0.01, 0.03], xtol=1e-12, ftol=1e-12,
                           gtol=1e-12)
    assert theirs.success
    k, m = math.exp(theirs.x[1]), math.exp(theirs.x[2])
    assert abs(k - ours["stiffness"]) < 0.02 * ours["stiffness_stderr"]
    assert abs(m - ours["mass"]) < 0.02 * ours["mass_stderr"]
    assert abs(theirs.x[0] - ours["start_time"]) < 0.02 * ours["start_time_stderr"]
    rms = math.sqrt(2 * theirs.cost / time.size)
    assert rms == pytest.approx(ours["fit_residual"], rel=1e-6)


# ------------------------------------------------------------------------------------------ sums of pulses

def _two_pulses(noise, seed=2, gap=1.5e-3):
    """Two exact pulses (the exact engine's curves, not the fit's table) ``gap`` apart, sampled at 20 kHz, with
    noise ``noise`` · F_max; and the θ of each: (onset, ln F_max, ln T, x = c V)."""
    rng = np.random.default_rng(seed)
    second_mass, second_damping = 0.7 * MASS, x_of_restitution(0.7) / VELOCITY
    grid = np.arange(-40, 260) / RATE
    force = (powerlaw_curves(MASS, STIFFNESS, DAMPING, VELOCITY, grid)[2]
             + powerlaw_curves(second_mass, STIFFNESS, second_damping, VELOCITY, grid - gap)[2])
    force = force + noise * PEAK * rng.standard_normal(grid.size)
    second = powerlaw_single(second_mass, STIFFNESS, 1.5, second_damping, VELOCITY, 0.03)
    theta = np.array([0.0, math.log(PEAK), math.log(DURATION), DAMPING * VELOCITY,
                      gap, math.log(second[0]), math.log(second[2]), second_damping * VELOCITY])
    return grid, force, theta


def test_a_sum_of_two_noise_free_pulses_is_recovered():
    """The compiled least squares of a sum of pulses (leastsquares.fit_pulse_sum, used by signals.split) against the
    exact engine's own pulses, 1.5 ms apart, started 5-10 % off: every parameter back to 1e-5 (the table's
    accuracy is 7.5e-8 of F_max; x and ln T are the least determined, by the pulses' weak tails)."""
    from fruitimpact.signals.leastsquares import fit_pulse_sum

    t, force, truth = _two_pulses(0.0)
    start = truth * np.array([1, 1, 1, 1.1, 1.05, 1, 1, 0.9]) + np.array([2e-5, 0.05, -0.05, 0, 0, -0.08, 0.05, 0])
    theta, _, _, _, converged, _ = fit_pulse_sum(t, force, np.full(t.size, 1.0), start)
    assert converged
    assert np.allclose(theta, truth, rtol=1e-5, atol=1e-8), theta - truth


def test_the_compiled_sum_fit_agrees_with_levenberg_marquardt():
    """leastsquares.fit_pulse_sum is levenberg_marquardt (the one-pulse fit's NumPy loop) compiled for a sum of pulses:
    on the same noisy data from the same start the two reach the same optimum (1e-6: their sums are taken in
    another order), priors included (extra rows (θ_k − μ)/sd in both)."""
    from fruitimpact.signals.leastsquares import fit_pulse_sum, levenberg_marquardt
    from fruitimpact.signals.pulse import PulseModel

    t, force, truth = _two_pulses(0.01)
    start = truth + np.array([1e-5, 0.05, -0.05, 0.1, -1e-5, -0.08, 0.05, -0.05])
    weights = np.full(t.size, 1.0 / (0.01 * PEAK))
    index, mean, weight = np.array([5, 6, 7]), truth[5:] + 0.02, np.array([1 / 0.13, 1 / 0.04, 1 / 0.1])
    first, second = PulseModel(t), PulseModel(t)

    def model(theta, jacobian=False):
        if not jacobian:
            return np.concatenate([first.pulse(theta[:4]).copy() + second.pulse(theta[4:]), theta[index]])
        fa, ja = first.pulse(theta[:4], True)
        fb, jb = second.pulse(theta[4:], True)
        rows = np.zeros((3, 8))
        rows[[0, 1, 2], index] = 1.0
        return np.concatenate([fa + fb, theta[index]]), np.vstack([np.hstack([ja, jb]), rows])

    expected, *_, converged = levenberg_marquardt(model, np.concatenate([force, mean]), start.copy(),
                                                  np.concatenate([weights, weight]), bounded=(3, 7))
    theta, *_, compiled_converged, _ = fit_pulse_sum(t, force, weights, start, index, mean, weight)
    assert converged and compiled_converged
    assert np.allclose(theta, expected, rtol=1e-6, atol=1e-9), theta - expected


def test_the_starts_pair_table_is_linear_least_squares():
    """starts._pair_table (the compiled grid of starts of a joint fit) solves each pair of unit pulses for its two
    peaks by linear least squares: against NumPy's lstsq on the same two shifted columns, peaks to 1e-9 and χ² to
    1e-9 (the same normal equations summed in another order); the prior χ² of a pair with an expected rebound is
    Σ ((θ − μ)/sd)² over (ln F_max, ln T, x) of the pulse it names; pairs whose peak is below the floor score inf."""
    from fruitimpact.signals.pulse import PulseModel
    from fruitimpact.signals.starts import _pair_table

    t, force, truth = _two_pulses(0.01)
    ts = t - t[0]
    noise = 0.01 * PEAK
    model = PulseModel(ts)
    shapes = [(0.6 * DURATION, 1.0), (0.8 * DURATION, 1.0), (math.exp(truth[6]), truth[7])]
    units = np.array([model.pulse((0.0, 0.0, math.log(d), x)).copy() for d, x in shapes])
    first, grid = 38, np.arange(45, 200, 12)
    priors = np.array([[truth[5], truth[6], truth[7], 0.1, 0.05, 0.2]])
    floor = 3 * noise
    table, theta, score, on = _pair_table(ts, force, noise, units, first, grid, np.array([d for d, _ in shapes]),
                                          np.array([x for _, x in shapes]), 2, priors, floor)
    assert len(table) == grid.size * 2 * 2 + 2 * grid.size * 2
    checked = 0
    for j in range(len(table)):
        columns = []
        for unit, onset in ((int(table[j, 0]) // (grid.size + 1), first),
                            (int(table[j, 1]) // (grid.size + 1), int(table[j, 8]))):
            column = np.zeros(ts.size)
            column[onset:] = units[unit][:ts.size - onset]
            columns.append(column)
        a = np.column_stack(columns)
        peaks, *_ = np.linalg.lstsq(a, force, rcond=None)
        chi2 = float(np.sum((a @ peaks - force) ** 2)) / noise ** 2
        if min(peaks) <= floor:
            assert score[j] == math.inf
            continue
        each = [float(np.sum(((theta[j, [4 * p + 1, 4 * p + 2, 4 * p + 3]] - priors[0, :3]) / priors[0, 3:]) ** 2))
                for p in (0, 1)]
        prior = min(each) if table[j, 6] < 0 else each[int(table[j, 7])]  # a generic pair: the nearer pulse
        assert each[on[j, 1]] == prior
        assert np.allclose(np.exp(theta[j, [1, 5]]), peaks, rtol=1e-9)
        assert score[j] == pytest.approx(chi2 + prior, rel=1e-9)
        assert theta[j, 0] == ts[first] and theta[j, 4] == ts[int(table[j, 8])]
        # each pulse's ln T and x are those of the unit pulse its column was built from (not the table's own columns)
        for pulse, row in ((0, table[j, 0]), (1, table[j, 1])):
            duration, x = shapes[int(row) // (grid.size + 1)]
            assert theta[j, 4 * pulse + 2] == pytest.approx(math.log(duration), abs=1e-12)
            assert theta[j, 4 * pulse + 3] == x
        checked += 1
    assert checked > 20
