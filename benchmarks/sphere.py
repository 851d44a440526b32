"""Sphere-audit benchmark (issue 18): ``fruitimpact sphere`` on a log of 10,000 impacts, a lot of 10,000 fruit
per transfer point, end to end (a subprocess, as users run it): wall time and peak memory, beside

* the line audit (``fi.audit_line``, in the same process) of the same transfer points: the same drops, the
  same measured surfaces, lot and cushions tried — what the lot costs, so the ratio is what reading, inverting
  and grouping the log add;
* pandas ``read_csv`` of the same log: the I/O floor of reading it.

Run alone with ``python benchmarks/sphere.py`` (about a minute).  The log's readings come from the sphere's own
pulse relations at known drops (speed is measured here; accuracy against solve_ivp is tests/test_sphere.py's).
"""

from __future__ import annotations

import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

POINTS = 20
IMPACTS = 10_000
FRUIT = 10_000
SPHERE = ["--sphere", "is-1987", "--sphere-modulus", "37.5MPa", "--sphere-poisson", "0.5"]


def make_log(path: Path) -> None:
    """A log of IMPACTS readings over POINTS transfer points (rigid and 2-30 MPa surfaces, 2-30 cm drops), with
    2 % noise."""
    from fruitimpact.spheres.devices import Sphere
    from fruitimpact.spheres.pulse import contact_duration, peak_force

    rng = np.random.default_rng(18)
    sphere = Sphere(0.312, 0.089, 50e6)
    heights = np.geomspace(0.02, 0.30, POINTS)
    moduli = [math.inf if k % 3 == 0 else float(m) for k, m in enumerate(np.geomspace(2e6, 30e6, POINTS))]
    rows = ["time,peak_acceleration,velocity_change,duration,point"]
    per_point = IMPACTS // POINTS
    t = 0.0
    for k in range(POINTS):
        contact = sphere.contact_modulus_on(moduli[k], 0.3)
        stiffness = 4.0 / 3.0 * contact * math.sqrt(sphere.radius)
        velocity = math.sqrt(2 * 9.80665 * heights[k])
        e = 0.6
        peak = float(peak_force(e, sphere.mass, stiffness, velocity)) / sphere.mass / 9.80665
        duration = float(contact_duration(e, sphere.mass, stiffness, velocity))
        for _ in range(per_point):
            rows.append(f"{t:.3f},{peak * (1 + 0.02 * rng.standard_normal()):.5g},"
                        f"{(1 + e) * velocity * (1 + 0.02 * rng.standard_normal()):.5g},{duration:.6f},p{k}")
            t += 3.0
    path.write_text("\n".join(rows) + "\n")


#: The CLI in a child that reports its own peak RSS (RUSAGE_CHILDREN would be the largest of all children).
_CHILD = ("import resource, sys\nfrom fruitimpact.cli import main\nrc = main(sys.argv[1:])\n"
          "sys.stderr.write(f'MAXRSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}\\n')\nsys.exit(rc)\n")


def timed(arguments: list[str]) -> tuple[float, float]:
    """(wall time [s], peak RSS [MB]) of one ``fruitimpact`` run in a child process."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _CHILD, *arguments], capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode not in (0, 1):
        raise RuntimeError(done.stderr)
    peak = next(int(line.split()[1]) for line in done.stderr.splitlines() if line.startswith("MAXRSS"))
    return wall, peak / 1024.0


def main() -> None:
    import pandas as pd

    import fruitimpact as fi
    from fruitimpact.handling.line import TransferPoint

    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "log.csv"
        make_log(log)
        options = dict(sphere="is-1987", sphere_modulus="37.5MPa", sphere_poisson=0.5, fruit="apple")
        fi.sphere_audit(log, rows=100, **options)  # warm: numba caches, the pulse table
        start = time.perf_counter()
        report = fi.sphere_audit(log, rows=FRUIT, **options)
        audit_time = time.perf_counter() - start
        points = [TransferPoint(p["name"], p["drop_height"], p["surface"],
                                surface_modulus=p["surface_modulus"],
                                surface_poisson=None if p["surface_modulus"] is None else 0.3)
                  for p in report["points"]]
        cushions = ["cardboard", "rubber-belt", "foam-pad"]
        start = time.perf_counter()
        baseline = fi.audit_line(points, rows=FRUIT, fruit="apple", alternatives=cushions)
        line_time = time.perf_counter() - start
        assert [p["incidence"] for p in baseline["points"]] == [p["incidence"] for p in report["points"]]
        start = time.perf_counter()
        pd.read_csv(log)
        io_floor = time.perf_counter() - start
        cli_time, cli_memory = timed(["sphere", str(log), "--sphere", "is-1987", "--sphere-modulus", "37.5MPa",
                                      "--sphere-poisson", "0.5", "--fruit", "apple", "-n", str(FRUIT), "--json"])
    print(f"sphere audit, {IMPACTS} impacts, {POINTS} points x {FRUIT} fruit (in process): {audit_time:.2f} s")
    print(f"  the line audit of the same points and lot, 3 cushions tried: {line_time:.2f} s "
          f"(sphere / line {audit_time / line_time:.2f}x: the log's share {audit_time - line_time:.2f} s)")
    print(f"  pandas read_csv of the log (the I/O floor): {io_floor * 1e3:.1f} ms")
    print(f"  fruitimpact sphere ... --json end to end: {cli_time:.2f} s, peak RSS {cli_memory:.0f} MB")


if __name__ == "__main__":
    main()
