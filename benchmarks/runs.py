"""End-to-end speed of batch and population runs, each against its baseline in the same run.

    python benchmarks/runs.py [--rows 1000000] [--population 2000000] [--evaluate 2000000]

* ``batch``: ``fruitimpact batch IN.csv -o OUT.parquet`` on a CSV of ``--rows`` rows,
  against the I/O floor: ``pyarrow.csv.read_csv`` of IN plus
  ``pyarrow.parquet.write_table`` of a table with the output's size and schema.
  Measured as a subprocess (start-up included) and in-process; the in-process run
  is also given without ``fi.evaluate`` (its time measured on the same rows).
* ``evaluate``: ``fi.evaluate`` of ``--evaluate`` rows against the plain NumPy floor of ``run.numpy_floor``
  (k_c, e and δ_max of the same rows, nothing checked).
* ``population``: ``population -n N`` (summary only, in-process, start-up
  excluded) against ``fi.evaluate`` of the same drawn members.

Every figure is the best of ``--repeats`` runs.  From ``benchmarks/run.py``:
``from runs import main as runs_main; runs_main(["--rows", "200000"])``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def best_of(func, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def peak_memory(command) -> float:
    """Peak resident memory [KiB] of ``command``, measured by a small Python parent: a child forked from this
    process would count this process's pages (the 10-million-row frames) in its own peak."""
    probe = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, capture_output=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    return float(subprocess.run([sys.executable, "-c", probe, *map(str, command)], check=True, capture_output=True,
                                text=True).stdout)


def make_csv(path: Path, rows: int) -> None:
    """A realistic batch input: five numeric columns and a model name."""
    import pandas as pd

    rng = np.random.default_rng(0)
    pd.DataFrame({"mass": rng.uniform(0.08, 0.3, rows), "diameter": rng.uniform(0.05, 0.09, rows),
                  "modulus": rng.uniform(2e6, 5e6, rows), "velocity": rng.uniform(0.3, 3.0, rows),
                  "restitution": rng.uniform(0.3, 0.9, rows),
                  "model": rng.choice(["hunt-crossley", "chen", "flores"], rows)}).to_csv(path, index=False)


def batch(rows: int, repeats: int, folder: Path) -> list[tuple]:
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    from fruitimpact import runs
    from fruitimpact.impact.evaluation import evaluate
    from fruitimpact.cli import main

    source = folder / "in.csv"
    make_csv(source, rows)
    out = folder / "out.parquet"
    main(["batch", str(source), "-o", str(out)])  # warm-up: compiled kernels, page cache
    table = pq.read_table(out)

    def floor():
        pacsv.read_csv(source)
        pq.write_table(table, folder / "floor.parquet", compression="snappy")

    exe = shutil.which("fruitimpact") or sys.executable
    command = [exe, "batch", str(source), "-o", str(out)] if exe != sys.executable else \
        [exe, "-m", "fruitimpact.cli", "batch", str(source), "-o", str(out)]
    io_floor = best_of(floor, repeats)
    sub = best_of(lambda: subprocess.run(command, check=True, capture_output=True), repeats)
    peak = peak_memory(command) / 1024 ** 2  # KiB → GiB
    size = source.stat().st_size / 1024 ** 3
    inproc = best_of(lambda: main(["batch", str(source), "-o", str(out)]), repeats)
    inputs = [t for _, (t, _) in runs.TableSource.open(source).payloads(runs.CHUNK_ROWS)]
    evaluation = best_of(lambda: [evaluate(t, tabulated=True) for t in inputs], repeats)
    print(f"batch {rows:,} rows: peak memory of the command {peak:.2f} GiB for a {size:.2f} GiB CSV",
          file=sys.stderr, flush=True)
    return [(f"batch {rows:,} rows CSV → Parquet, subprocess", sub, "I/O floor", io_floor),
            (f"batch {rows:,} rows CSV → Parquet, in-process", inproc, "I/O floor", io_floor),
            (f"batch {rows:,} rows, in-process without evaluate", inproc - evaluation, "I/O floor", io_floor),
            (f"fi.evaluate of the same {rows:,} rows", evaluation, "I/O floor", io_floor)]


def population(rows: int, repeats: int, folder: Path) -> list[tuple]:
    from fruitimpact import runs
    from fruitimpact.impact.evaluation import evaluate
    from fruitimpact.cli import main
    from fruitimpact.impact.distributions import parse_distribution

    specs = {"mass": ("normal(115g,10g)", "mass"), "velocity": ("uniform(0.5,1.5)", "velocity"),
             "modulus": ("lognormal(3MPa,0.2)", "modulus"),
             "restitution": ("truncnormal(0.55,0.05,0.3,0.8)", "dimensionless")}
    argv = ["population", "-n", str(rows), "--seed", "1", "--threshold", "peak_force>60N"]
    for name, (spec, _) in specs.items():
        argv += ["--" + name, spec]
    source = runs.PopulationSource(tuple((n, parse_distribution(s, d, n)) for n, (s, d) in specs.items()), (),
                                   rows, 1)
    members = [source.inputs(start, min(start + runs.CHUNK_ROWS, rows), None)[0]
               for start in range(0, rows, runs.CHUNK_ROWS)]
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        main(argv)  # warm-up
        run = best_of(lambda: main(argv), repeats)
    finally:
        os.chdir(cwd)
    evaluation = best_of(lambda: [evaluate(m, tabulated=True) for m in members], repeats)
    return [(f"population -n {rows:,}, summary only, in-process", run, "fi.evaluate, same members", evaluation)]


def evaluate_floor(rows: int, repeats: int) -> list[tuple]:
    from run import fruit_columns, numpy_floor  # the same floor as the engine table

    from fruitimpact.impact.evaluation import evaluate

    columns = fruit_columns(rows)
    evaluate({k: a[:50_000] for k, a in columns.items()}, tabulated=True)  # compiled, tables built
    floor = best_of(lambda: numpy_floor(columns), repeats)
    ours = best_of(lambda: evaluate(columns, tabulated=True), repeats)
    return [(f"fi.evaluate, {rows:,} rows (all characteristics, status)", ours, "NumPy: k_c, e, δ_max only", floor)]


def main(argv=None) -> list:
    """Run the benchmarks, print them, and return (task, seconds, baseline, baseline seconds) lines."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000, help="rows of the batch CSV (default 1e6)")
    parser.add_argument("--population", type=int, default=2_000_000, help="members (default 2e6)")
    parser.add_argument("--evaluate", type=int, default=0, help="rows of fi.evaluate against NumPy (default: "
                                                                  "none)")
    parser.add_argument("--repeats", type=int, default=3, help="best of this many runs (default 3)")
    args = parser.parse_args(argv)
    import contextlib
    import io

    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
        lines = batch(args.rows, args.repeats, Path(tmp)) + population(args.population, args.repeats, Path(tmp))
        lines += evaluate_floor(args.evaluate, args.repeats) if args.evaluate else []
    for task, value, baseline, base in lines:
        print(f"{task:<58} {value:8.2f} s | {baseline:<30} {base:8.2f} s  ratio {value / base:5.2f}×", flush=True)
    return lines


if __name__ == "__main__":
    main()
