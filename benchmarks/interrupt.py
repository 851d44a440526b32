"""Ctrl-C on a long command (issue 15 item 5: stop within 1 s of SIGINT, one line "interrupted", exit 130).

    python benchmarks/interrupt.py [--rows 3000000] [--chunk-size 3000000] [--format csv] [--delays 1-20]

Writes the batch CSV of ``runs.make_csv`` (``--rows`` rows), then for each delay starts
``fruitimpact batch IN.csv -o OUT --chunk-size N`` as a subprocess, sends it one real SIGINT after that many
seconds and measures the time to its "interrupted" line on stderr and to its exit.  A run that ended before the
signal is counted as such.  The baseline beside it is the same command left to finish (its wall time), so that a
delay can be read as a share of the run.  The goal is absolute: the exit within 1 s of the signal.
"""

from __future__ import annotations

import argparse
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_common import console_script, machine  # noqa: E402
from runs import make_csv  # noqa: E402


def delays(text: str) -> list[float]:
    if "-" in text:
        low, high = (int(x) for x in text.split("-"))
        return [float(d) for d in range(low, high + 1)]
    return [float(d) for d in text.split(",")]


def interrupted(command: list[str], output: Path, delay: float) -> tuple[float | None, float | None, int, str]:
    """(seconds to the first stderr line, to the exit, exit status, that line) of ``command`` sent SIGINT after
    ``delay`` s; the times are None when it ended before the signal."""
    for stale in (output, Path(str(output) + ".parts")):
        shutil.rmtree(stale, ignore_errors=True) if stale.is_dir() else stale.unlink(missing_ok=True)
    process = subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL)
    time.sleep(delay)
    if process.poll() is not None:
        return None, None, process.returncode, process.stderr.read().decode().strip().splitlines()[0]
    sent = time.perf_counter()
    process.send_signal(signal.SIGINT)
    line = process.stderr.readline().decode().strip()
    said = time.perf_counter() - sent
    process.wait()
    return said, time.perf_counter() - sent, process.returncode, line


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=3_000_000, help="rows of the batch CSV (default 3e6)")
    parser.add_argument("--chunk-size", type=int, default=3_000_000, help="--chunk-size of the batch (default 3e6)")
    parser.add_argument("--format", choices=("csv", "parquet"), default="csv", help="the output's format")
    parser.add_argument("--delays", default="1-20", help="seconds before the SIGINT, e.g. 1-20 or 2,5,9")
    args = parser.parse_args(argv)
    print(machine())
    with tempfile.TemporaryDirectory() as tmp:
        source, output = Path(tmp) / "in.csv", Path(tmp) / f"out.{args.format}"
        make_csv(source, args.rows)
        command = [console_script(), "batch", str(source), "-o", str(output), "--chunk-size", str(args.chunk_size)]
        start = time.perf_counter()
        subprocess.run(command, capture_output=True, check=False)
        whole = time.perf_counter() - start
        print(f"{' '.join(command[1:2])} of {args.rows:,} rows into {args.format}, chunks of {args.chunk_size:,}: "
              f"{whole:.1f} s uninterrupted")
        print(f"{'SIGINT after':>13} {'line':>7} {'exit':>7} {'status':>7}  line")
        exits = []
        for delay in delays(args.delays):
            said, ended, status, line = interrupted(command, output, delay)
            if said is None:
                print(f"{delay:>12g}s {'-':>7} {'-':>7} {status:>7}  (ended before the signal)")
                continue
            exits.append(ended)
            print(f"{delay:>12g}s {said:>6.2f}s {ended:>6.2f}s {status:>7}  {line[:70]}")
        if exits:
            print(f"{len(exits)} interrupted: exit after {min(exits):.2f}-{max(exits):.2f} s "
                  f"({sum(e <= 1.0 for e in exits)} of {len(exits)} within 1 s)")


if __name__ == "__main__":
    main()
