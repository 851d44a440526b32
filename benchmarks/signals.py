"""Signal benchmarks (issue 8): the streaming impact detector, the raw indices, the input parsers, and the
emission latency.  One command:

    python benchmarks/signals.py [--quick]

Each figure is measured beside its baseline in the same run (best of 3 wall-clock repeats, one core):

* the detector (``signals.detect``) over one lane, whole array and in chunks, against the floor of any
  detector: one plain NumPy pass over the same samples, ``np.abs(x - np.median(x)) > t`` plus ``np.diff``
  (threshold crossings, no baseline tracking, no state, no windows);
* several lanes at once (per-lane throughput);
* the raw indices per impact against a naive NumPy version (raw maximum, its index, and ``np.trapezoid``);
* the text and float32 parsers against ``np.array(text.split(), float)`` and ``np.frombuffer``;
* latency: samples from an impact's end to its emission (the design value is max(post-trigger, offset hold
  window) for an isolated impact), and, fed in real-time-sized chunks of 1 ms, the wall-clock time of the
  ``feed`` call that emits it (compute added on top of the design latency).

The signal: Hunt–Crossley apple impacts (one exact pulse shape from the engine at several amplitudes and
sub-sample onsets) every 0.1–0.3 s at 20 kHz, with 1 % white noise, 50 Hz hum and a slow drift.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from bench_common import machine
from fruitimpact.engine.powerlaw import (
    exact_x,
    powerlaw_characteristics,
    powerlaw_curves,
)
from fruitimpact.signals.detect import Detector, DetectorSettings, detect
from fruitimpact.signals.indices import impact_indices
from fruitimpact.signals.stream import Float32Source, StreamAnalyzer, TextSource

RATE = 20_000.0


def best_of(func, repeats=3):
    best = math.inf
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - start)
    return best, result


def signal_with_impacts(samples: int, lanes: int = 1, seed: int = 1) -> tuple[np.ndarray, int]:
    rng = np.random.default_rng(seed)
    mass, velocity, diameter = 0.19, 1.0, 0.075
    stiffness = 4 / 3 * 3.5e6 / (1 - 0.35 ** 2) * math.sqrt(diameter / 2)
    c = float(exact_x(0.5)) / velocity
    peak, _, duration = powerlaw_characteristics(mass, stiffness, c, velocity, diameter / 2)[0][:3]
    fine = np.linspace(0.0, duration, 4001)
    _, _, shape, _ = powerlaw_curves(mass, stiffness, c, velocity, fine)
    x = np.zeros((samples, lanes))
    count = 0
    t = np.arange(samples) / RATE
    for lane in range(lanes):
        onset = 0.1
        while onset < samples / RATE - 0.05:
            k0 = int(onset * RATE) + 1
            k1 = min(samples, int((onset + duration) * RATE) + 1)
            x[k0:k1, lane] += rng.uniform(0.7, 1.3) * np.interp(t[k0:k1] - onset, fine, shape)
            count += 1
            onset += rng.uniform(0.1, 0.3)
        x[:, lane] += peak * (0.01 * rng.normal(size=samples) + 0.05 + 0.005 * np.sin(2 * np.pi * 50.1 * t)
                              + 0.02 * np.sin(2 * np.pi * 0.3 * t))
    return (x[:, 0] if lanes == 1 else x), count


def numpy_floor(x: np.ndarray, threshold: float):
    above = np.abs(x - np.median(x)) > threshold
    return np.flatnonzero(np.diff(above.astype(np.int8)))


def chunked(detector: Detector, x: np.ndarray, size: int) -> list:
    out = []
    for start in range(0, x.shape[0], size):
        out += detector.feed(x[start:start + size])
    return out + detector.flush()


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 M samples instead of 20 M")
    args = parser.parse_args(argv)
    samples = 2_000_000 if args.quick else 20_000_000
    print(f"# fruitimpact signal benchmarks — {machine()}")
    print(f"# {samples:,} samples at {RATE:g} Hz per lane ({samples / RATE:g} s), one core\n")
    x, count = signal_with_impacts(samples)
    # warm up the JIT (compiled on first use, then cached on disk)
    detect(x[:200_000], RATE, DetectorSettings(hum_frequency=50.0, lowpass_cutoff=5000.0))
    impact_indices(detect(x[:200_000], RATE)[0], RATE)

    floor_time, _ = best_of(lambda: numpy_floor(x, 5.0))
    rows = [("NumPy floor: abs(x − median) > t, then diff", floor_time, None)]
    cases = [("detect, defaults (whole array)", DetectorSettings(), None),
             ("detect + hum canceller (50 Hz)", DetectorSettings(hum_frequency=50.0), None),
             ("detect + hum (1, 3) + 4th-order low-pass", DetectorSettings(hum_frequency=50.0, hum_harmonics=(1, 3),
                                                                            lowpass_cutoff=5000.0), None),
             ("detect, fed in chunks of 65,536", DetectorSettings(), 65_536),
             ("detect, fed in chunks of 1,024", DetectorSettings(), 1_024)]
    found = None
    for label, settings, size in cases:
        if size is None:
            elapsed, impacts = best_of(lambda s=settings: detect(x, RATE, s))
        else:
            elapsed, impacts = best_of(lambda s=settings, n=size: chunked(Detector(RATE, s), x, n))
        found = found or impacts
        rows.append((f"{label} [{len(impacts)} of {count} impacts]", elapsed, floor_time))
    print("| lane throughput | time [s] | samples/s | vs NumPy floor |")
    print("|---|---|---|---|")
    for label, elapsed, base in rows:
        ratio = "" if base is None else f"{elapsed / base:.2f}× its time"
        print(f"| {label} | {elapsed:.3f} | {samples / elapsed / 1e6:.1f} M | {ratio} |")

    lanes = 8
    xl, count_l = signal_with_impacts(samples // lanes, lanes, seed=2)
    floor_l, _ = best_of(lambda: [numpy_floor(xl[:, k], 5.0) for k in range(lanes)])
    elapsed, impacts = best_of(lambda: detect(xl, RATE, DetectorSettings(hum_frequency=50.0)))
    print(f"| {lanes} lanes × {samples // lanes:,} (hum on) [{len(impacts)} of {count_l} impacts] | {elapsed:.3f} | "
          f"{samples / elapsed / 1e6:.1f} M lane-samples | {elapsed / floor_l:.2f}× NumPy floor ({floor_l:.3f} s) |")

    # raw indices per impact
    sample = found[:2000]
    t_idx, _ = best_of(lambda: [impact_indices(i, RATE) for i in sample])
    t_naive, _ = best_of(lambda: [(float(np.max(i.window)), int(np.argmax(i.window)),
                                   float(np.trapezoid(i.window)) / RATE) for i in sample])
    print("\n| per impact | µs | impacts/s |")
    print("|---|---|---|")
    print(f"| impact_indices (edge fits, weighted cubic peak, impulse) | {t_idx / len(sample) * 1e6:.1f} | "
          f"{len(sample) / t_idx:,.0f} |")
    print(f"| baseline: raw max, argmax, np.trapezoid | {t_naive / len(sample) * 1e6:.1f} | "
          f"{len(sample) / t_naive:,.0f} |")

    # parsers
    n_text = min(samples, 1_000_000)
    text = "".join(f"{v:.6g}\n" for v in x[:n_text]).encode()
    raw = x.astype("<f4").tobytes()
    t_text, _ = best_of(lambda: [TextSource(1).parse(text[k:k + 65536]) for k in range(0, len(text), 65536)])
    t_text0, _ = best_of(lambda: np.array(text.split(), dtype=float))
    t_f32, _ = best_of(lambda: [Float32Source(1).parse(raw[k:k + (1 << 18)]) for k in range(0, len(raw), 1 << 18)])
    t_f320, _ = best_of(lambda: np.frombuffer(raw, dtype="<f4").astype(float))
    print("\n| parser | samples/s | baseline | baseline samples/s |")
    print("|---|---|---|---|")
    print(f"| TextSource, 64 kB chunks | {n_text / t_text / 1e6:.2f} M | np.array(text.split(), float) | "
          f"{n_text / t_text0 / 1e6:.2f} M |")
    print(f"| Float32Source, 256 kB chunks | {samples / t_f32 / 1e6:.0f} M | np.frombuffer(...).astype(float) | "
          f"{samples / t_f320 / 1e6:.0f} M |")

    # latency
    settings = DetectorSettings(hum_frequency=50.0)
    design = Detector(RATE, settings).latency_samples
    lat = np.array([i.emitted_at - 1 - i.end_index for i in found])
    print(f"\n| latency (defaults: post-trigger {settings.post_trigger * 1e3:g} ms, offset hold "
          f"{settings.offset_hold * 1e3:g} ms) | value |")
    print("|---|---|")
    print(f"| design: max(post, offset hold) after end_index | {design} samples = {design / RATE * 1e3:.1f} ms |")
    print(f"| measured, end_index → emission, over {lat.size} impacts | min {lat.min()}, median "
          f"{int(np.median(lat))}, max {lat.max()} samples |")
    seconds = min(samples, 2_000_000)
    chunk = int(RATE * 1e-3)
    analyzer = StreamAnalyzer(RATE, 1, settings, on_impact=lambda d: None, source="float32")
    data = x[:seconds].astype("<f4").tobytes()
    step = 4 * chunk
    feed_times, emit_times = [], []
    for k in range(0, len(data), step):
        start = time.perf_counter()
        emitted = analyzer.feed_bytes(data[k:k + step])
        elapsed = time.perf_counter() - start
        (emit_times if emitted else feed_times).append(elapsed)
    analyzer.close()
    feed_times, emit_times = np.array(feed_times) * 1e6, np.array(emit_times) * 1e6
    print(f"| StreamAnalyzer (float32 → detector → indices, shape fit, rebound test) fed 1 ms chunks: a chunk "
          f"without emission | "
          f"median {np.median(feed_times):.0f} µs, 99th pct {np.percentile(feed_times, 99):.0f} µs |")
    print(f"| … the chunk that emits an impact (adds to the design latency) | "
          f"median {np.median(emit_times):.0f} µs, "
          f"max {emit_times.max():.0f} µs (over {emit_times.size}) |")
    print(f"| baseline: the chunk's own duration | {chunk / RATE * 1e6:.0f} µs |")


if __name__ == "__main__":
    main()
