"""Benchmark of the Hunt–Crossley pulse fit (issue 8, item 3): ``fruitimpact.signals.fit.fit_impact``.

    python benchmarks/signals_fit.py [--quick]

Synthetic apple impacts (m 0.13–0.26 kg, d 65–85 mm, E 2–8 MPa, e 0.4–0.7, V 0.63–1.25 m/s) from the
exact engine at 20 kHz, random sub-sample onset, 1 % Gaussian noise, a window from 2 ms before the
onset to 1.3 T after it.  Each figure is measured beside its baseline in the same run:

* ``fit_impact`` (everything: validation, start, Levenberg–Marquardt, derived quantities and their
  standard errors) against ``scipy.optimize.least_squares`` (trust-region reflective, bounds on x)
  minimising the same tabulated model with the same analytic Jacobian from the same start;
* against ``least_squares`` on the exact engine (``powerlaw_curves``, ~6 µs a sample) with a
  finite-difference Jacobian: what one writes without the table.

The agreement column is the largest difference in K between the optimisers, in K's standard errors.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from fruitimpact.engine.powerlaw import (
    powerlaw_curves,
    powerlaw_single,
    x_of_restitution,
)
from fruitimpact.signals import fit as fitmod
from fruitimpact.signals.fit import fit_impact
from fruitimpact.signals.pulse import X_MAX, PulseModel

RATE = 20_000.0


def population(n: int, seed: int = 3):
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        m = rng.uniform(0.13, 0.26)
        d = rng.uniform(0.065, 0.085)
        k = 4 / 3 * rng.uniform(2e6, 8e6) / (1 - 0.35 ** 2) * math.sqrt(d / 2)
        e = rng.uniform(0.4, 0.7)
        v = rng.uniform(0.63, 1.25)
        c = x_of_restitution(e) / v
        chars = powerlaw_single(m, k, 1.5, c, v, d / 2)
        grid = np.arange(-int(0.002 * RATE), int(1.3 * chars[2] * RATE)) / RATE
        onset = rng.uniform(0.0, 1.0) / RATE
        force = powerlaw_curves(m, k, c, v, grid - onset)[2]
        force = force + 0.01 * chars[0] * rng.standard_normal(grid.size)
        rows.append({"time": grid, "force": force, "mass": m, "stiffness": k, "velocity": v, "restitution": e})
    return rows


def scipy_table(row):
    """least_squares on the fit's own tabulated model and Jacobian, from the fit's start."""
    from scipy.optimize import least_squares

    t, y = row["time"] - row["time"][0], row["force"]
    model = PulseModel(np.ascontiguousarray(t))
    start, _ = fitmod._start(t, y, model, None)
    sol = least_squares(lambda p: model(p) - y, start, jac=lambda p: model(p, True)[1],
                        bounds=([-np.inf, -np.inf, -np.inf, 0.0], [np.inf, np.inf, np.inf, X_MAX]),
                        x_scale="jac", xtol=1e-10, ftol=1e-10)
    return fitmod.derived(sol.x, row["velocity"], None, None, None)[0], sol.nfev


def scipy_exact(row):
    """least_squares on the exact engine in (t0, ln K, ln m, x), 2-point Jacobian, from the fit's start."""
    from scipy.optimize import least_squares

    t, y, v = row["time"] - row["time"][0], row["force"], row["velocity"]
    model = PulseModel(np.ascontiguousarray(t))
    start, _ = fitmod._start(t, y, model, None)
    derived = fitmod.derived(start, v, None, None, None)
    p0 = [start[0], math.log(derived[0]), math.log(derived[2]), start[3]]

    def residual(p):
        return powerlaw_curves(math.exp(p[2]), math.exp(p[1]), p[3] / v, v, t - p[0])[2] - y

    sol = least_squares(residual, p0, bounds=([-np.inf, -np.inf, -np.inf, 0.0], [np.inf] * 4),
                        x_scale=[1e-5, 0.01, 0.01, 0.03], xtol=1e-10, ftol=1e-10)
    return math.exp(sol.x[1]), sol.nfev


def per_impact(func, rows, repeats=3):
    """Best-of-``repeats`` mean seconds per impact, and the last results."""
    best, out = math.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        out = [func(row) for row in rows]
        best = min(best, (time.perf_counter() - start) / len(rows))
    return best, out


def signals_fit_benchmarks(record, quick: bool) -> None:
    rows = population(50 if quick else 200)
    fit_impact(rows[0]["time"], rows[0]["force"], velocity=rows[0]["velocity"])  # table, JIT cache
    samples = np.array([row["time"].size for row in rows])
    ours_time, ours = per_impact(lambda r: fit_impact(r["time"], r["force"], velocity=r["velocity"]), rows)
    single = []
    for row in rows:
        start = time.perf_counter()
        fit_impact(row["time"], row["force"], velocity=row["velocity"])
        single.append(time.perf_counter() - start)
    k_err = np.array([o["stiffness"] / r["stiffness"] - 1 for o, r in zip(ours, rows)])
    e_err = np.array([o["restitution"] - r["restitution"] for o, r in zip(ours, rows)])
    converged = sum(o["converged"] for o in ours)

    table_time, table = per_impact(scipy_table, rows, repeats=1)
    gap = max(abs(k - o["stiffness"]) / o["stiffness_stderr"] for (k, _), o in zip(table, ours))
    record(f"fit_impact, {len(rows)} apple impacts, {samples.min()}–{samples.max()} samples",
           ours_time * 1e3, "least_squares, same table model + J", table_time * 1e3, "ms/impact",
           f"p95 {np.percentile(single, 95) * 1e3:.2f} ms, max {max(single) * 1e3:.2f} ms; "
           f"{converged}/{len(rows)} converged; max |ΔK| {gap:.1e} stderr; "
           f"scipy nfev {np.mean([n for _, n in table]):.1f}, ours iterations "
           f"{np.mean([o['iterations'] for o in ours]):.1f}", of_baseline=True)

    n_exact = 10 if quick else 20
    exact_time, exact = per_impact(scipy_exact, rows[:n_exact], repeats=1)
    gap = max(abs(k - o["stiffness"]) / o["stiffness_stderr"] for (k, _), o in zip(exact, ours))
    record(f"fit_impact vs the exact engine ({n_exact} impacts)", ours_time * 1e3,
           "least_squares, exact engine, 2-point J", exact_time * 1e3, "ms/impact",
           f"max |ΔK| {gap:.1e} stderr; scipy nfev {np.mean([n for _, n in exact]):.1f}", of_baseline=True)

    k_sd = np.array([o["stiffness_stderr"] / r["stiffness"] for o, r in zip(ours, rows)])
    z = k_err / k_sd
    record("fit accuracy over the population (1 % noise)", float(np.sqrt(np.mean(k_err ** 2))) * 100,
           "rms of the reported stderr of K", float(np.sqrt(np.mean(k_sd ** 2))) * 100, "% rms K err",
           f"K worst {np.max(np.abs(k_err)) * 100:.2f} % (stderr there {k_sd[np.argmax(np.abs(k_err))] * 100:.1f} %), "
           f"|ΔK| <= 2 stderr for {np.mean(np.abs(z) <= 2) * 100:.0f} %; e rms {np.sqrt(np.mean(e_err ** 2)):.4f} "
           f"worst {np.max(np.abs(e_err)):.4f}", compare=False)

if __name__ == "__main__":
    def _print(task, value, baseline_name, baseline_value, unit, note, compare=True, of_baseline=False):
        ratio = value / baseline_value
        print(f"{task:<58} {value:>9.4g} {unit:<12} | {baseline_name:<38} {baseline_value:>9.4g}  "
              f"ratio {ratio:,.3f}  {note}", flush=True)

    signals_fit_benchmarks(_print, "--quick" in sys.argv)
