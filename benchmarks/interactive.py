"""Interactive latency (issue 15 item 4): what a notebook loop, an optimiser or a web page pays per call, and
what a terminal user waits for, each beside its baseline in the same run.

* one ``simulate()`` against one SciPy ``solve_ivp`` DOP853 impact at rtol 1e-10 (the same Hertz–Hunt–Crossley
  impact of the paper's Jonathan apple; goal ≥ 100×);
* ``drop`` from 30 cm with all its bounces and ``safe_height`` (goal ≤ 10 ms each), against one ``simulate()``;
* the console script as a subprocess: ``--help`` and a usage error (goal ≤ 0.25 s, no numba) and a warm
  ``fruitimpact simulate`` (goal ≤ 0.4 s), against a bare ``python -c pass``.

Times are the best of several repeats (the machine's other load only ever adds time).

    python benchmarks/interactive.py
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_common import console_script, machine  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def best(func, repeats: int, number: int) -> float:
    """Best time of one call [s] over ``repeats`` runs of ``number`` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            func()
        times.append((time.perf_counter() - start) / number)
    return min(times)


def wall(argv, repeats: int = 9) -> float:
    """Best wall time [s] of a subprocess."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(argv, capture_output=True)
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    import fruitimpact as fi
    from run import scipy_impact  # the same solve_ivp baseline as the engine table

    print(machine())
    fi.simulate()  # compiled kernels loaded
    simulate = best(fi.simulate, 5, 300)
    scipy = best(lambda: scipy_impact(mass=0.115, stiffness=0.8355e6, damping_factor=1.0678, velocity=1.0), 5, 30)
    drop = best(lambda: fi.drop("30cm", fruit="apple", surface="steel"), 5, 10)
    safe = best(lambda: fi.safe_height(fruit="apple", surface="steel", criterion="shear", sensitivity=False), 5, 10)
    safe_sens = best(lambda: fi.safe_height(fruit="apple", surface="steel", criterion="shear"), 5, 10)
    exe = console_script()
    bare = wall([sys.executable, "-c", "pass"])
    rows = [
        ("one simulate() (Jonathan apple, 1 m/s)", simulate * 1e6, "µs", "solve_ivp DOP853 1e-10", scipy * 1e6,
         f"{scipy / simulate:.0f}× faster", "≥ 100× faster"),
        ("drop from 30 cm, all bounces (apple on steel)", drop * 1e3, "ms", "one simulate()", simulate * 1e3,
         f"{drop / simulate:.0f}× one simulate()", "≤ 10 ms"),
        ("safe_height (apple on steel, shear)", safe * 1e3, "ms", "one simulate()", simulate * 1e3,
         f"{safe / simulate:.0f}× one simulate()", "≤ 10 ms"),
        ("safe_height with sensitivities", safe_sens * 1e3, "ms", "one simulate()", simulate * 1e3,
         f"{safe_sens / simulate:.0f}× one simulate()", ""),
        ("fruitimpact --help", wall([exe, "--help"]), "s", "python -c pass", bare, "", "≤ 0.25 s"),
        ("fruitimpact simulate --mass -1 (usage error)", wall([exe, "simulate", "--mass", "-1"]), "s",
         "python -c pass", bare, "", "≤ 0.25 s"),
        ("population --fruit pear --criterion shear (usage)",
         wall([exe, "population", "-n", "10", "--fruit", "pear", "--criterion", "shear"]), "s", "python -c pass", bare,
         "", "≤ 0.25 s"),
        ("sphere LOG --method rk4 --step 1s (usage)",
         wall([exe, "sphere", str(EXAMPLES / "sphere-log.csv"), "--sphere", "is-1987", "--sphere-calibration",
               str(EXAMPLES / "sphere-calibration.csv"), "--fruit", "apple", "--method", "rk4", "--step", "1s"]), "s",
         "python -c pass", bare, "", "≤ 0.25 s"),
        ("fruitimpact simulate (warm cache)", wall([exe, "simulate"], 5), "s", "python -c pass", bare, "",
         "≤ 0.4 s"),
    ]
    print(f"{'task':<48}{'value':>10} {'unit':<4} {'baseline':<24}{'value':>10}  {'ratio':<22} goal")
    for task, value, unit, base_name, base, ratio, goal in rows:
        scale = 1.0 if unit != "s" else 1.0
        print(f"{task:<48}{value * scale:>10.4g} {unit:<4} {base_name:<24}{base:>10.4g}  {ratio:<22} {goal}")


if __name__ == "__main__":
    main()
