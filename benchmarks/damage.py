"""Damage benchmarks (issue 7): the plastic engine against SciPy, and the damage commands end to end.

Run alone with ``python benchmarks/damage.py`` or as part of ``python benchmarks/run.py``.
Each figure is measured beside its baseline in the same run:

* the elastic–plastic engine (Thornton, with and without viscous damping, on a half-space and on a cushion
  layer) against a loop of SciPy ``solve_ivp`` (DOP853, rtol 1e-10) integrating the same law with its history;
* ``safe-height`` (a root search of ~30 evaluations) against one ``fi.evaluate`` of the same row;
* a line audit against ``fi.evaluate`` of the same members at every transfer point.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from fruitimpact.engine.plastic import plastic_characteristics


def best_of(func, repeats=3):
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return best


def scipy_thornton(mass, velocity, stiffness, radius, modulus, yield_pressure, c, rtol=1e-10):
    """Restitution of one Thornton impact with F = F_T (1 + c δ̇), integrated by solve_ivp with its history."""
    from scipy.integrate import solve_ivp

    dy = radius * (math.pi * yield_pressure / (2 * modulus)) ** 2
    fy = stiffness * dy ** 1.5
    kp = math.pi * yield_pressure * radius

    def loading(_, y):
        d, v = y
        f = stiffness * max(d, 0.0) ** 1.5 if d <= dy else fy + kp * (d - dy)
        return [v, -f * (1 + c * v) / mass]

    turn = lambda _, y: y[1]  # noqa: E731
    turn.terminal, turn.direction = True, -1
    first = solve_ivp(loading, (0, 1.0), [0.0, velocity], method="DOP853", rtol=rtol, atol=1e-14, events=turn)
    d_star = first.y_events[0][0][0]
    f_star = stiffness * d_star ** 1.5 if d_star <= dy else fy + kp * (d_star - dy)
    if d_star > dy:
        r_p = 4 * modulus / (3 * f_star) * ((2 * f_star + fy) / (2 * math.pi * yield_pressure)) ** 1.5
        k_u = 4 / 3 * modulus * math.sqrt(r_p)
        d_p = d_star - (f_star / k_u) ** (2 / 3)
    else:
        k_u, d_p = stiffness, 0.0

    def unloading(_, y):
        d, v = y
        return [v, -k_u * max(d - d_p, 0.0) ** 1.5 * (1 + c * v) / mass]

    leave = lambda _, y: y[0] - d_p  # noqa: E731
    leave.terminal, leave.direction = True, -1
    second = solve_ivp(unloading, (0, 1.0), [d_star, 0.0], method="DOP853", rtol=rtol, atol=1e-14, events=leave)
    return -second.y_events[0][0][1] / velocity


def damage_benchmarks(record, quick: bool) -> None:
    rng = np.random.default_rng(7)
    rows = 20_000 if quick else 200_000
    mass = rng.uniform(0.08, 0.25, rows)
    radius = rng.uniform(0.025, 0.04, rows)
    modulus = rng.uniform(2e6, 6e6, rows) / (1 - 0.35 ** 2)
    stiffness = 4 / 3 * modulus * np.sqrt(radius)
    velocity = rng.uniform(0.5, 4.0, rows)
    yield_pressure = rng.uniform(0.2e6, 0.5e6, rows)
    n_ref = 20 if quick else 100
    for label, c in (("undamped (pure Thornton)", 0.0), ("damped, c = 0.5 s/m", 0.5)):
        plastic_characteristics(mass[:10], velocity[:10], stiffness[:10], radius[:10], modulus[:10],
                                yield_pressure[:10], damping_factor=c)
        elapsed = best_of(lambda: plastic_characteristics(mass, velocity, stiffness, radius, modulus, yield_pressure,
                                                           damping_factor=c))
        ours = plastic_characteristics(mass[:n_ref], velocity[:n_ref], stiffness[:n_ref], radius[:n_ref],
                                       modulus[:n_ref], yield_pressure[:n_ref], damping_factor=c)[0][:, 6]
        start = time.perf_counter()
        for i in range(n_ref):  # timed only: the accuracy is judged against the tight run below
            scipy_thornton(mass[i], velocity[i], stiffness[i], radius[i], modulus[i], yield_pressure[i], c)
        scipy_rate = n_ref / (time.perf_counter() - start)
        tight = np.array([scipy_thornton(mass[i], velocity[i], stiffness[i], radius[i], modulus[i],
                                         yield_pressure[i], c, rtol=1e-12) for i in range(n_ref)])
        err = float(np.max(np.abs(ours - tight)))
        record(f"Thornton batch {label}, {rows:,} impacts (2 cores)", rows / elapsed, "loop of solve_ivp 1e-10",
               scipy_rate, "impacts/s", f"max |Δe| vs DOP853 1e-12: {err:.1e}")

    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.handling.heights import safe_height

    safe_height(criterion="shear", fruit="apple", sensitivity=False)
    search = best_of(lambda: safe_height(criterion="shear", fruit="apple", sensitivity=False), 5)
    one = best_of(lambda: evaluation({"criterion": ["shear"], "fruit": ["apple"], "drop_height": [0.05]}), 5)
    record("safe-height root search (shear, library apple)", search * 1e3, "one fi.evaluate of that row",
           one * 1e3, "ms", "Illinois on ln h to 1e-9", of_baseline=True)

    from fruitimpact.handling.line import TransferPoint, audit

    n = 20_000 if quick else 200_000
    members = {"mass": rng.normal(0.18, 0.02, n), "modulus": rng.lognormal(math.log(3e6), 0.15, n),
               "fruit": np.full(n, "apple", dtype=object)}
    points = [TransferPoint("bin tipper", 0.3, "rubber-belt"), TransferPoint("conveyor", 0.05, "pvc-belt"),
              TransferPoint("singulator", 0.1, "steel"), TransferPoint("table", 0.08, "foam-pad", True),
              TransferPoint("carton", 0.15, "cardboard")]
    audit(points[:1], {k: v[:10] for k, v in members.items()}, 10, "shear", {}, ())
    line_time = best_of(lambda: audit(points, members, n, "shear", {}, ()), 1)

    def evaluate_all():
        for p in points:
            evaluation({**members, "drop_height": np.full(n, p.drop_height),
                        "surface": "fruit" if p.fruit_on_fruit else p.surface, "criterion": "shear"})

    floor = best_of(evaluate_all, 1)
    record(f"line audit, {n:,} fruit × 5 transfer points", line_time, "fi.evaluate of the same impacts", floor,
           "s", "incidence, volumes, cumulation", of_baseline=True)

    # issue 14 item 9: the line against one population of its N·P impacts (one table, every point's rows
    # together: what `population` evaluates), and plastic contact against elastic on the same line
    stacked = {k: np.concatenate([v] * len(points)) for k, v in members.items()}
    stacked["drop_height"] = np.concatenate([np.full(n, p.drop_height) for p in points])
    stacked["surface"] = np.concatenate([np.full(n, "fruit" if p.fruit_on_fruit else p.surface, dtype=object)
                                         for p in points])
    stacked["criterion"] = np.full(n * len(points), "shear", dtype=object)
    population = best_of(lambda: evaluation(stacked), 1)
    record(f"line audit against one population of its {n * len(points):,} impacts (goal ≤ 1.5×)", line_time,
           "fi.evaluate of the N·P impacts as one table", population, "s", "issue 14 item 9", of_baseline=True)
    plastic = {**members, "yield_pressure": np.full(n, 3.2e5)}
    audit(points[:1], {k: v[:10] for k, v in plastic.items()}, 10, "shear", {}, ())
    plastic_time = best_of(lambda: audit(points, plastic, n, "shear", {}, ()), 1)
    record(f"line audit with plastic contact (p_y 0.32 MPa), {n:,} × 5 (goal ≤ 2× elastic)", plastic_time,
           "the same line elastic", line_time, "s", "issue 14 item 9", of_baseline=True)
    alternatives = best_of(lambda: audit(points, members, n, "shear", {}, ("foam-pad",)), 1)
    record(f"line audit with --alternatives foam-pad, {n:,} × 5", alternatives, "the same line without",
           line_time, "s", "one evaluation per point and alternative", of_baseline=True)


if __name__ == "__main__":
    def _print(task, value, baseline_name, baseline_value, unit, note, compare=True, of_baseline=False):
        ratio = value / baseline_value
        print(f"{task:<60} {value:>12.4g} {unit:<10} | {baseline_name:<34} {baseline_value:>10.4g}  "
              f"ratio {ratio:,.2f}  {note}", flush=True)

    damage_benchmarks(_print, "--quick" in sys.argv)
