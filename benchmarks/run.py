"""fruitimpact benchmarks: one command, baselines in the same run.

    python benchmarks/run.py [--quick] [--markdown FILE]

It also runs interactive.py (per-call latency, start-up) and the signal-path benchmarks (signals.py,
signals_fit.py, scorecard.py, latency.py,
analyze_memory.py --quick and sphere.py), which print their own tables; the one-hour memory run of analyze_memory.py is a
command of its own (37 min).

Each line compares fruitimpact with the obvious baseline doing the same job:
SciPy ``solve_ivp`` (DOP853, rtol 1e-10, terminal event at δ = 0, peak force by
a root of dF/dt on the dense output) and the paper's RK4 at 1e-4 s.  Accuracy
is measured against a tight reference (DOP853 at rtol 1e-12) on a sample.
"""

from __future__ import annotations

import argparse
from pathlib import Path
import platform
import shutil
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fruitimpact import simulate
from fruitimpact.engine import forces
from fruitimpact.engine.powerlaw import (CHARACTERISTIC_COLUMNS, exact_x, powerlaw_characteristics,
                                         powerlaw_single)
from fruitimpact.engine.rk4 import rk4_batch

KEYS = ("peak_force", "time_to_peak", "contact_duration", "max_deflection", "restitution")
COL = [CHARACTERISTIC_COLUMNS.index(k) for k in KEYS]


def scipy_impact(mass, stiffness, damping_factor, velocity, rtol=1e-10):
    """The baseline: what a user would write with SciPy for the same characteristics."""
    k, c, m = stiffness, damping_factor, mass

    def rhs(t, y):
        d = max(y[0], 0.0)
        return [y[1], -k * d ** 1.5 * (1.0 + c * y[1]) / m]

    def separation(t, y):
        return y[0] if t > 0 else 1.0

    separation.terminal = True
    separation.direction = -1
    t_end = 50.0 * ((1.25 * m * velocity ** 2 / k) ** 0.4) / velocity
    sol = solve_ivp(rhs, [0.0, t_end], [0.0, velocity], method="DOP853", rtol=rtol,
                    atol=[rtol * 1e-3 * velocity * t_end, rtol * 1e-3 * velocity], events=separation,
                    dense_output=True)
    duration = sol.t_events[0][0]
    exit_rate = sol.y_events[0][0][1]

    def force_rate(t):
        d, v = sol.sol(t)
        d = max(d, 1e-300)
        acc = -k * d ** 1.5 * (1.0 + c * v) / m
        return k * 1.5 * d ** 0.5 * v * (1.0 + c * v) + k * d ** 1.5 * c * acc

    t_max = brentq(lambda t: sol.sol(t)[1], 1e-3 * duration, 0.999 * duration, xtol=1e-15)
    t_peak = brentq(force_rate, 1e-4 * duration, t_max, xtol=1e-15) if c > 0 else t_max
    d_peak, v_peak = sol.sol(t_peak)
    return np.array([k * d_peak ** 1.5 * (1 + c * v_peak), t_peak, duration, sol.sol(t_max)[0],
                     -exit_rate / velocity])


def scipy_general(family, params, clamp, mass, velocity, rtol):
    """Baseline for any force family: DOP853 with separation (δ = 0, or F = 0 when
    clamped) and the peak force (root of the analytic dF/dt next to the largest of
    400 samples) located on the dense output."""
    k0, k1 = params[0], params[1]

    def force_rate(t):  # dF/dt = ∂F/∂δ δ̇ + ∂F/∂δ̇ δ̈
        d, v = sol.sol(t)
        d = max(d, 1e-300)
        acc = -force(d, v) / mass
        if family == forces.KELVIN_VOIGT:
            return k0 * v + k1 * acc
        if family == forces.KUWABARA_KONO:
            return k0 * (1.5 * d ** 0.5 * v + 0.5 * k1 * d ** -0.5 * v * v + k1 * d ** 0.5 * acc)
        if family == forces.TSUJI:
            return k0 * 1.5 * d ** 0.5 * v + k1 * (0.25 * d ** -0.75 * v * v + d ** 0.25 * acc)
        n, c = params[1], params[2]
        return k0 * (n * d ** (n - 1) * v * (1 + c * v) + d ** n * c * acc)

    def force(d, v):
        d = max(d, 0.0)
        if family == forces.KELVIN_VOIGT:
            return k0 * d + k1 * v
        if family == forces.KUWABARA_KONO:
            return k0 * (d ** 1.5 + k1 * d ** 0.5 * v)
        if family == forces.TSUJI:
            return k0 * d ** 1.5 + k1 * d ** 0.25 * v
        return k0 * d ** params[1] * (1 + params[2] * v)

    def rhs(t, y):
        f = force(y[0], y[1])
        return [y[1], -(max(f, 0.0) if clamp else f) / mass]

    def separation(t, y):
        return y[0] if t > 0 else 1.0

    def force_zero(t, y):
        return force(y[0], y[1]) if (t > 0 and y[1] < 0) else 1.0

    separation.terminal = force_zero.terminal = True
    separation.direction = force_zero.direction = -1
    t_end = 50.0 * ((1.25 * mass * velocity ** 2 / 1e6) ** 0.4) / velocity
    sol = solve_ivp(rhs, [0.0, t_end], [0.0, velocity], method="DOP853", rtol=rtol,
                    atol=[rtol * 1e-6, rtol * 1e-3 * velocity], events=[separation, force_zero] if clamp else [separation],
                    dense_output=True)
    duration = min(ev[0] for ev in sol.t_events if len(ev))
    exit_rate = sol.sol(duration)[1]
    ts = np.linspace(0.0, duration, 400)
    f = np.array([force(*sol.sol(t)) for t in ts])
    i = int(f.argmax())
    if 0 < i < len(ts) - 1 and force_rate(ts[i - 1]) > 0 > force_rate(ts[i + 1]):
        t_peak = brentq(force_rate, ts[i - 1], ts[i + 1], xtol=1e-16, rtol=1e-15)
        f_peak = force(*sol.sol(t_peak))
    else:  # peak at first touch (a dashpot's jump)
        t_peak, f_peak = ts[i], f[i]
    t_max = brentq(lambda t: sol.sol(t)[1], 1e-6 * duration, duration, xtol=1e-15)
    return np.array([f_peak, t_peak, duration, sol.sol(t_max)[0], -exit_rate / velocity])


def population(rows, seed=1):
    rng = np.random.default_rng(seed)
    mass = rng.uniform(0.08, 0.3, rows)
    stiffness = rng.uniform(4e5, 2e6, rows)
    velocity = rng.uniform(0.3, 3.0, rows)
    restitution = rng.uniform(0.3, 0.9, rows)
    damping_factor = exact_x(restitution) / velocity
    return mass, stiffness, damping_factor, velocity


def best_of(func, repeats=5):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def max_rel_error(values, reference):
    return float(np.max(np.abs(values / reference - 1.0)))


def fruit_columns(rows, seed=1):
    """A population as ``fi.evaluate`` takes it: mass, modulus, velocity and restitution [SI]."""
    rng = np.random.default_rng(seed)
    return {"mass": rng.normal(0.115, 0.01, rows), "modulus": 3e6 * np.exp(rng.normal(0.0, 0.2, rows)),
            "velocity": rng.uniform(0.5, 1.5, rows), "restitution": rng.uniform(0.3, 0.8, rows)}


def numpy_floor(columns):
    """The floor of ``fi.evaluate``: a plain NumPy evaluation, on the same arrays, of only the
    contact stiffness (eq 9), the restitution of the paper's Hunt–Crossley damping (Newton on the
    exact relation (1 + x) = (1 - e x) exp((1 + e) x), 8 steps) and δ_max in closed form."""
    m, E, v, e0 = columns["mass"], columns["modulus"], columns["velocity"], columns["restitution"]
    k = 4.0 / 3.0 * E / (1.0 - 0.37 ** 2) * np.sqrt(0.0325)
    x = 1.5 * (1.0 - e0)  # the paper's calibration, c V = 1.5 (1 - e) (eqs 5-6)
    e = e0.copy()
    for _ in range(8):
        grow = np.exp((1.0 + e) * x)
        g = (1.0 - e * x) * grow - (1.0 + x)
        e = e - g / (x * grow * (1.0 - e * x - 1.0))
    r = (x - np.log1p(x)) / x ** 2
    return e, (2.5 * m * v ** 2 * r / k) ** 0.4


def end_to_end(record, quick):
    """The commands and calls users run, each against its floor in the same run (issue 6, section 5)."""
    from fruitimpact.impact.evaluation import evaluate
    from fruitimpact.physics.calibrate import damping_factor
    from fruitimpact.engine.adaptive import adaptive_characteristics
    from fruitimpact.physics.calibrate import law_params
    from fruitimpact.physics import DAMPING_LAWS

    n_eval = 200_000 if quick else 2_000_000
    columns = fruit_columns(n_eval)
    evaluate({k: a[:5000] for k, a in columns.items()}, tabulated=True)
    evaluate({k: a[:50000] for k, a in columns.items()}, tabulated=True)
    floor = best_of(lambda: numpy_floor(columns), 3)
    ours = best_of(lambda: evaluate(columns, tabulated=True), 3)
    record(f"fi.evaluate, {n_eval:,} rows (all characteristics, status)", ours,
           "NumPy: k_c, e and δ_max only", floor, "s", "target: within 3×", of_baseline=True)

    simulate(model="tsuji-clamped")
    n = 500 if quick else 3000
    hunt = best_of(lambda: [simulate() for _ in range(n)], 3) / n * 1e6
    tsuji = best_of(lambda: [simulate(model="tsuji-clamped") for _ in range(n)], 3) / n * 1e6
    record("one simulate(), tsuji-clamped, exact calibration", tsuji, "one hunt-crossley simulate()", hunt,
           "µs/impact", "target: within 3×", of_baseline=True)

    n_cal = 20_000 if quick else 200_000
    rng = np.random.default_rng(3)
    m, k, v = rng.uniform(0.08, 0.3, n_cal), rng.uniform(4e5, 2e6, n_cal), rng.uniform(0.3, 3.0, n_cal)
    e = rng.uniform(0.05, 0.95, n_cal)
    for name in ("tsuji-clamped", "kelvin-voigt-clamped", "kuwabara-kono"):
        law = DAMPING_LAWS[name]

        def run(calibration):
            factor = damping_factor(law, calibration, e, m, k, v)
            k_law = law.linear_stiffness(m, k, v)
            return adaptive_characteristics(np.full(n_cal, law.family), law_params(law.family, k_law, factor),
                                            np.full(n_cal, law.clamp), m, v, np.full(n_cal, 0.03))

        run("exact")
        exact = best_of(lambda: run("exact"), 3)
        paper = best_of(lambda: run("paper"), 3)
        record(f"{name}: exact calibration + engine, {n_cal:,} rows", n_cal / exact,
               "published calibration + engine", n_cal / paper, "rows/s", "target: no slower than the engine")

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from runs import main as runs_main

    lines = runs_main(["--rows", "200000" if quick else "1000000", "--population", "400000" if quick else "2000000",
                       "--repeats", "1" if quick else "2"])
    for task, value, baseline, base in lines:
        target = "target: within 2×" if task.startswith("batch") and "subprocess" in task else \
            "target: within 1.5×" if task.startswith("population") else ""
        record(task, value, baseline, base, "s", target, of_baseline=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes (for a smoke run)")
    parser.add_argument("--markdown", metavar="FILE", help="also write the table as Markdown")
    args = parser.parse_args(argv)
    rows = []

    def record(task, fruitimpact_value, baseline_name, baseline_value, unit, note, compare=True, of_baseline=False):
        if not compare:  # a reference point, not a competitor
            ratio = "–"
        elif of_baseline:  # a time as a multiple of its floor (lower is better; the targets are "within N×")
            ratio = f"{fruitimpact_value / baseline_value:.2f}× the baseline"
        elif unit.startswith("µs"):
            ratio = f"{baseline_value / fruitimpact_value:,.0f}×"
        else:
            ratio = f"{fruitimpact_value / baseline_value:,.0f}×"
        rows.append((task, fruitimpact_value, baseline_name, baseline_value, unit, ratio, note))
        print(f"{task:<56} {fruitimpact_value:>12.4g} {unit:<10} | {baseline_name:<26} {baseline_value:>10.4g}  "
              f"speed-up {ratio}  {note}", flush=True)

    apple = dict(mass=0.115, stiffness=0.8355e6, damping_factor=1.0678, velocity=1.0)
    # ------------------------------------------------------------------ single impacts
    simulate()  # warm-up: load compiled kernels
    n_api = 2000 if args.quick else 20000
    api = best_of(lambda: [simulate() for _ in range(n_api)], 3) / n_api * 1e6
    n_scipy = 20 if args.quick else 200
    scipy_single = best_of(lambda: [scipy_impact(**apple) for _ in range(n_scipy)], 3) / n_scipy * 1e6
    record("one accurate impact, Python API simulate()", api, "solve_ivp DOP853 1e-10", scipy_single, "µs/impact",
           "all characteristics + closed-form check")
    engine = best_of(lambda: [powerlaw_single(0.115, 0.8355e6, 1.5, 1.0678, 1.0, 0.0325) for _ in range(n_api)], 3)
    record("one accurate impact, engine call", engine / n_api * 1e6, "solve_ivp DOP853 1e-10", scipy_single,
           "µs/impact", "")
    simulate(method="rk4")
    rk4_api = best_of(lambda: [simulate(method="rk4") for _ in range(n_api // 4)], 3) / (n_api // 4) * 1e6
    record("one RK4 impact (paper, 1e-4 s), Python API", rk4_api, "solve_ivp DOP853 1e-10", scipy_single,
           "µs/impact", "~63 steps")

    # ------------------------------------------------------------------ batch
    n_batch = 200_000 if args.quick else 2_000_000
    m, k, c, v = population(n_batch)
    powerlaw_characteristics(m[:10], k[:10], c[:10], v[:10], 0.03, parallel=True)
    batch = best_of(lambda: powerlaw_characteristics(m, k, c, v, 0.03), 3)
    n_ref = 50 if args.quick else 300
    start = time.perf_counter()
    ref = np.array([scipy_impact(m[i], k[i], c[i], v[i], rtol=1e-10) for i in range(n_ref)])
    scipy_rate = n_ref / (time.perf_counter() - start)
    tight = np.array([scipy_impact(m[i], k[i], c[i], v[i], rtol=1e-12) for i in range(n_ref)])
    ours = powerlaw_characteristics(m[:n_ref], k[:n_ref], c[:n_ref], v[:n_ref], 0.03)[:, COL]
    err = max(max_rel_error(ours[:, j], tight[:, j]) for j in range(len(KEYS)))
    err_scipy = max(max_rel_error(ref[:, j], tight[:, j]) for j in range(len(KEYS)))
    record(f"power-law batch, {n_batch:,} impacts (2 cores)", n_batch / batch, "loop of solve_ivp 1e-10",
           scipy_rate, "impacts/s", f"max rel. err vs DOP853 1e-12: {err:.1e} (solve_ivp 1e-10: {err_scipy:.1e})")

    family = np.full(n_batch, forces.POWER_LAW, dtype=np.int64)
    params = np.column_stack([k, np.full(n_batch, 1.5), c])
    clamp = np.ones(n_batch, dtype=np.bool_)
    out = np.empty((n_batch, len(CHARACTERISTIC_COLUMNS)))
    step = np.full(n_batch, 1e-4)
    rk4_batch(family[:10], params[:10], clamp[:10], m[:10], v[:10], np.full(10, 0.03), step[:10], 10**6, out[:10])
    rk4_time = best_of(lambda: rk4_batch(family, params, clamp, m, v, np.full(n_batch, 0.03), step, 10**6, out), 3)
    rk4_err = max(max_rel_error(out[:n_ref, j], tight[:, i]) for i, j in enumerate(COL))
    record(f"paper's RK4 1e-4 s batch, {n_batch:,} impacts", n_batch / rk4_time, "loop of solve_ivp 1e-10",
           scipy_rate, "impacts/s", f"max rel. err (grid read-off): {rk4_err:.1e}")

    # ------------------------------------------------------------------ other laws (compiled adaptive)
    from fruitimpact.physics.calibrate import damping_factor, law_params
    from fruitimpact.engine.adaptive import adaptive_characteristics
    from fruitimpact.physics import DAMPING_LAWS

    n_other = 100_000 if args.quick else 1_000_000
    e_other = np.random.default_rng(2).uniform(0.3, 0.9, n_other)
    for name in ("tsuji-clamped", "kelvin-voigt-clamped", "kuwabara-kono"):
        law = DAMPING_LAWS[name]
        mm, kk, vv = m[:n_other], k[:n_other], v[:n_other]
        factor = damping_factor(law, "paper", e_other, mm, kk, vv)
        k_law = law.linear_stiffness(mm, kk, vv)
        params = law_params(law.family, k_law, factor)
        fam = np.full(n_other, law.family)
        clamp_law = np.full(n_other, law.clamp)
        adaptive_characteristics(fam[:10], params[:10], clamp_law[:10], mm[:10], vv[:10], np.full(10, 0.03))
        elapsed = best_of(lambda: adaptive_characteristics(fam, params, clamp_law, mm, vv, np.full(n_other, 0.03)), 3)
        got = adaptive_characteristics(fam[:n_ref], params[:n_ref], clamp_law[:n_ref], mm[:n_ref], vv[:n_ref],
                                       np.full(n_ref, 0.03))[:, COL]
        start = time.perf_counter()
        base = np.array([scipy_general(law.family, params[i], law.clamp, mm[i], vv[i], 1e-10) for i in range(n_ref)])
        base_rate = n_ref / (time.perf_counter() - start)
        tight = np.array([scipy_general(law.family, params[i], law.clamp, mm[i], vv[i], 1e-12) for i in range(n_ref)])
        finite = np.isfinite(tight) & (tight != 0)
        err = float(np.max(np.abs(got[finite] / tight[finite] - 1.0)))
        record(f"{name} batch, {n_other:,} impacts (2 cores)", n_other / elapsed, "loop of solve_ivp 1e-10",
               base_rate, "impacts/s", f"max rel. err vs DOP853 1e-12: {err:.1e}")

    # ------------------------------------------------------------------ end to end (issue 6, section 5)
    end_to_end(record, args.quick)

    # ------------------------------------------------------------------ damage (issue 7)
    sys.path.insert(0, str(Path(__file__).parent))
    from damage import damage_benchmarks

    damage_benchmarks(record, args.quick)

    # ------------------------------------------------------------------ sorting lines (issues 8, 13)
    # the signal-path benchmarks print their own tables (each figure beside its baseline or goal in the same run);
    # --quick runs their small sizes; the 1 h memory run is `python benchmarks/analyze_memory.py` (37 min) alone
    here = Path(__file__).parent
    for script, options in (("interactive.py", []),
                            ("signals.py", ["--quick"] if args.quick else []),
                            ("signals_fit.py", []),
                            ("scorecard.py", ["--quick"] if args.quick else []),
                            ("latency.py", ["--quick"] if args.quick else []),
                            ("analyze_memory.py", ["--quick"]),
                            ("sphere.py", [])):
        print(f"\n=== benchmarks/{script} {' '.join(options)}", flush=True)
        done = subprocess.run([sys.executable, str(here / script), *options])
        if done.returncode not in (0, 1):  # 1: a goal missed, which the script's own table shows
            print(f"benchmarks/{script} ended with status {done.returncode}", flush=True)

    # ------------------------------------------------------------------ CLI
    exe = shutil.which("fruitimpact")
    if exe:
        subprocess.run([exe, "simulate"], capture_output=True, check=True)
        cli = best_of(lambda: subprocess.run([exe, "simulate"], capture_output=True, check=True), 5)
        py = best_of(lambda: subprocess.run([sys.executable, "-c", "pass"], capture_output=True, check=True), 5)
        record("`fruitimpact simulate` wall time (warm cache)", cli, "bare `python -c pass`", py, "s",
               "includes interpreter start", compare=False)

    if args.markdown:
        with open(args.markdown, "w") as handle:
            handle.write(f"Machine: {platform.processor() or platform.machine()}, {platform.python_version()}, "
                         f"numpy {np.__version__}\n\n")
            handle.write("| task | fruitimpact | unit | baseline | baseline value | ratio | note |\n|---|---|---|---|---|---|---|\n")
            for task, ours_value, base, base_value, unit, ratio, note in rows:
                handle.write(f"| {task} | {ours_value:.4g} | {unit} | {base} | {base_value:.4g} | {ratio} | {note} |\n")


if __name__ == "__main__":
    main()
