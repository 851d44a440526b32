"""Peak memory and time of ``fruitimpact analyze`` on a long recording, beside ``fruitimpact stream`` (issue 13).

One command:

    python benchmarks/analyze_memory.py [--quick] [--minutes M] [--snapshot] [--markdown FILE]

What is measured, and why
    Issue 13 item 4: ``analyze`` reads a recording in chunks through the streaming detector, so its memory is
    bounded by the chunk, not by the file (goal: ≤ 400 MB peak for any length), and it is at least as fast as
    ``stream`` on the same file.  Acceptance: "``analyze`` peak memory and time on a ≥ 1 h 4-lane recording
    beside ``stream``'s, in the same run".  This benchmark writes such a recording (default 60 min, 4 lanes,
    20 kHz, raw float32: ~1.15 GB), runs both installed console scripts on it, one after the other, and reports
    for each: contacts reported, wall time, × real time and peak resident memory (RSS).  ``analyze`` is also run
    on a recording a quarter as long, to show that its memory does not grow with the length.

The recording
    A block of the 4-lane scenario ``lanes4`` of ``tests/linegen.py`` (the independent line generator: it does
    not import fruitimpact), at 20 kHz instead of its 25 kHz (``dataclasses.replace``): apples and pears at
    7 fruit/s/lane, one rebound each, 5 cm drop, 50 Hz hum, drift, noise, plate ringing at 3 kHz.  The block is
    ``BLOCK_FRUIT`` fruit per lane (~14.6 s; ``--quick``: ``QUICK_BLOCK_FRUIT``) and is written again and again
    (tiled) until the recording is at least ``--minutes`` long (whole blocks only, so the truth is exactly
    contacts per block × blocks).  Only one block is ever in memory; the file is written block by block.

    The seam between two blocks is made continuous, so the detector sees a plausible line and no step:
      * the block starts with the generator's quiet signal (≥ 0.15 s before the first fruit) and is cut in the
        quiet signal after its last contact (≥ ``TAIL`` + ``LEVEL_WINDOW`` s after the last contact's end);
      * the cut is placed, within that quiet tail, at the sample where the mains hum has done a whole number
        of its periods (the generator's hum frequency is in the truth), so hum and its 3rd harmonic run on
        across the seam (residual phase error printed);
      * the baseline (offset + drift) of each lane is levelled: a linear ramp is subtracted so the quiet level
        at the end of the block equals that at its start (levels are means over ``LEVEL_WINDOW`` s of quiet
        signal; the random-walk drift inside the block is kept).  The step left at the seam (mean of the last
        vs the first hum period of the block, largest over the lanes) is printed beside the noise sd.
    So between two blocks the line is quiet for ~0.3 s (about two feed pitches without fruit on every lane).

The runs (each a subprocess of the installed console script, one after the other)
    (a) ``fruitimpact analyze FILE --rate 20000 --lanes 4 --json --drop-height 5cm``
    (b) ``fruitimpact stream --rate 20000 --lanes 4 --format f32 --drop-height 5cm < FILE`` (stdin is the file,
        read as fast as ``stream`` takes it)
    (c) both again with ``--fit`` (not with ``--quick``);
    (d) ``analyze`` as (a) on the quarter-length recording.
    Standard output goes to a file in the temporary folder (not a terminal, not a pipe the benchmark must keep
    reading); its lines are counted (one JSON line per contact) and (a) and (b) are checked to have written the
    same number of contacts, and the same bytes (``analyze --json`` and ``stream`` write the same objects; the
    first differing line and keys are shown otherwise).  Each run's count is also checked to be exactly
    (``analyze`` on one block alone) × blocks: the seams add and lose no contact.

    The truth column is the generator's contacts per block × blocks (fruit and rebounds).  The runs report
    fewer: a rebound that lands on the next fruit's contact is one "overlap" report for two truth contacts.
    How ``analyze`` on one block alone compares with its truth (``linegen.score``: recall, missed, extra,
    rebounds taken for fruit) is printed beside the table, so the count can be read.

    Before the timed runs, both commands run once on one block (not timed), so numba's on-disk cache is
    compiled and every timed run only loads it, as a line's program would after its first start.

How peak memory and time are taken
    Each command runs under a tiny launcher (``LAUNCHER``: ``python -I -S -c ...``, a fresh process of ~10 MB)
    that starts it with ``subprocess.Popen``, reaps it with ``os.wait4(pid)`` and writes that one child's
    resource usage to a file: ``ru_maxrss`` is its peak resident set size (KiB on Linux; the console script runs
    in that process, it starts no other), user + system time its CPU time.  Wall time is the launcher's
    ``time.perf_counter()`` from just before ``Popen`` to the return of ``wait4``, so it includes the command's
    start-up (imports, numba cache loading) but not the launcher's.  × real time = recording duration / wall
    time.  MB = 10⁶ bytes.

    Why a launcher: Linux keeps, in the ``ru_maxrss`` of a process, the peak RSS of the memory image it had
    before ``exec`` — for a child of this benchmark, the benchmark's own peak (generating a block with linegen
    takes ~380 MB).  Measured directly, every command would show at least that.  (Differences of
    ``getrusage(RUSAGE_CHILDREN)`` are no better: it keeps the maximum over all children.)  The launcher's own
    pre-``exec`` image is small; its VmHWM is reported as the floor below which no peak can read, and checked
    to be well below every peak.

Goals checked
    analyze peak RSS ≤ 400 MB at every length, and no more than 10 % above on the full length than on the
    quarter; analyze wall time and CPU time (user + system, from ``wait4``: far less sensitive than wall time to
    other work on the machine) ≤ stream's on the same file, with and without ``--fit``; analyze writes what
    stream writes.  The 1-minute load average at the end of each run is shown ("load"): on a 2-core machine
    shared with other work, wall times are only comparable at similar load.

Which code runs
    By default the installed console script imports the package as installed (editable: the working tree).
    When others edit ``src/`` while the benchmark runs, the runs would measure different code: the package's
    Python files are fingerprinted before the first and after the last run and a change is reported as a
    missed check.  ``--snapshot`` runs the last commit instead: ``git archive HEAD src`` is unpacked in the
    temporary folder and put first on ``PYTHONPATH`` of every child (the console script is the same); the
    report names the commit.

Space and clean-up
    The recordings go to a temporary folder under ``/tmp`` (or ``/work`` when ``/tmp`` has not enough room:
    recording + quarter + outputs + 1 GB margin, checked with ``shutil.disk_usage``).  The folder is deleted at
    the end, also on an error, Ctrl-C or SIGTERM; a running child is killed first.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import itertools
import json
import math
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import linegen as lg  # noqa: E402  (tests/linegen.py: the independent generator)
from bench_common import console_script, machine  # noqa: E402

#: Issue 13 item 4: analyze's peak resident memory for any length [MB].
GOAL_RSS_MB = 400.0
#: Sample rate [Hz] and lanes of the recording.
RATE = 20_000.0
LANES = 4
#: Fruit per lane in one block (full run; --quick).
BLOCK_FRUIT = 100
QUICK_BLOCK_FRUIT = 40
#: Quiet signal kept after the last contact of a block before the cut [s].
TAIL = 0.05
#: Window of quiet signal whose mean is the baseline level at either end of a block [s].
LEVEL_WINDOW = 0.04
#: Options of every run (the line's drop height; the recording's format for analyze).
ANALYZE = ["--rate", f"{RATE:g}", "--lanes", str(LANES), "--json", "--drop-height", "5cm"]
STREAM = ["--rate", f"{RATE:g}", "--lanes", str(LANES), "--format", "f32", "--drop-height", "5cm"]
#: Free space wanted beyond the files themselves [bytes].
MARGIN = 1 << 30


# ---------------------------------------------------------------------------------------------------------------
# The recording
# ---------------------------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Block:
    """One block of line signal (samples × lanes float32 [N]) ready to be tiled, and what it holds."""

    samples: np.ndarray
    fruit: int            # truth fruit (first contacts) in the block, all lanes
    rebounds: int         # truth rebounds in the block
    hum_error_deg: float  # hum phase mismatch at the seam [degrees of the fundamental]
    step: float           # largest residual baseline step at the seam over the lanes [N]
    noise_sd: float       # the generator's white-noise sd [N]
    truth: dict           # the generator's truth (every contact lies before the cut)

    @property
    def contacts(self) -> int:
        return self.fruit + self.rebounds

    @property
    def seconds(self) -> float:
        return self.samples.shape[0] / RATE


def make_block(fruit_per_lane: int) -> Block:
    """Generate a ``lanes4`` block at 20 kHz, cut it in its quiet tail where the hum has done whole periods and
    level each lane's baseline so the block's end joins its start (see the module docstring)."""
    scenario = dataclasses.replace(lg.SCENARIOS["lanes4"], rate=RATE)
    recording, truth = lg.generate(scenario, fruit_per_lane)
    contacts = truth["contacts"]
    first_start = min(c["start_time"] for c in contacts)
    last_end = max(c["end_time"] for c in contacts)
    hum = truth["sensor"]["hum_frequency"]

    # Cut: the sample n in the quiet tail where hum × n / rate is closest to a whole number of periods.
    lo = int(math.ceil((last_end + TAIL + LEVEL_WINDOW) * RATE))
    hi = recording.shape[0]
    if lo >= hi:
        raise RuntimeError("the generated block has no quiet tail to cut in")
    n = np.arange(lo, hi + 1)
    cycles = hum * n / RATE
    miss = np.abs(cycles - np.round(cycles))
    cut = int(n[np.argmin(miss)])
    hum_error_deg = float(miss.min() * 360.0)

    # Levelling: subtract a ramp so the quiet level at the end equals the quiet level at the start.
    w = int(round(LEVEL_WINDOW * RATE))
    if w > first_start * RATE:
        raise RuntimeError("the generated block has too little quiet signal before its first fruit")
    block = recording[:cut].astype(np.float64)
    start_level = block[:w].mean(axis=0)
    end_level = block[cut - w:].mean(axis=0)
    slope = (end_level - start_level) / (cut - w)  # per sample, between the two windows' centres
    block -= np.arange(cut)[:, None] * slope[None, :]
    # The step left at the seam: mean of the block's last vs first hum period (the hum cancels in each).
    period = int(round(RATE / hum))
    step = float(np.max(np.abs(block[cut - period:].mean(axis=0) - block[:period].mean(axis=0))))

    rebounds = sum(1 for c in contacts if c["is_rebound"])
    return Block(samples=block.astype("<f4"), fruit=len(contacts) - rebounds, rebounds=rebounds,
                 hum_error_deg=hum_error_deg, step=step, noise_sd=float(truth["sensor"]["noise_sd"]), truth=truth)


def write_tiled(path: Path, block: Block, copies: int) -> None:
    """Write ``copies`` blocks one after the other as raw interleaved little-endian float32 (one block in memory)."""
    data = np.ascontiguousarray(block.samples, dtype="<f4").tobytes()
    with open(path, "wb") as f:
        for _ in range(copies):
            f.write(data)


# ---------------------------------------------------------------------------------------------------------------
# Running a command
# ---------------------------------------------------------------------------------------------------------------

@dataclasses.dataclass
class Run:
    """One measured child: what ran, on what, and what it cost."""

    label: str
    argv: list[str]
    stdin: Path | None
    minutes: float = 0.0
    size_mb: float = 0.0
    truth: int = 0
    blocks: int = 0
    contacts: int = 0
    wall: float = math.nan
    cpu: float = math.nan
    peak_mb: float = math.nan
    load: float = math.nan
    floor_mb: float = math.nan   # the launcher's own peak RSS: the lowest peak the command could show
    output: Path | None = None   # its standard output, while kept
    stderr: str = ""

    @property
    def real_time(self) -> float:
        return self.minutes * 60.0 / self.wall

    @property
    def command(self) -> str:
        return self.argv[1] + (" --fit" if "--fit" in self.argv else "")

    def shell(self) -> str:
        """The command as a user would type it (console script by name, recordings by file name)."""
        shown = ["fruitimpact"] + [Path(a).name if a.endswith(".f32") else a for a in self.argv[1:]]
        return shlex.join(shown) + (f" < {self.stdin.name}" if self.stdin is not None else "") + " > /dev/null"


#: The launcher: a small fresh Python that starts the measured command, reaps it with ``os.wait4`` and writes
#: its wall time, exit code, peak RSS and CPU time as JSON to the file given first (see the module docstring:
#: why the benchmark does not take ``ru_maxrss`` of its own children).  Its own VmHWM is written too: the
#: command's peak can never read below it.
LAUNCHER = r"""
import json, os, subprocess, sys, time
result, argv = sys.argv[1], sys.argv[2:]
with open("/proc/self/status") as f:
    floor = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
start = time.perf_counter()
child = subprocess.Popen(argv)
_, status, usage = os.wait4(child.pid, 0)
wall = time.perf_counter() - start
with open(result, "w") as f:
    json.dump(dict(wall=wall, code=os.waitstatus_to_exitcode(status), maxrss_kib=usage.ru_maxrss,
                   cpu=usage.ru_utime + usage.ru_stime, floor_kib=floor), f)
"""


def run(child: Run, folder: Path, env: dict, name: str) -> Run:
    """Run ``child.argv`` under the launcher, its standard output to ``folder/NAME.jsonl`` (kept: the caller
    compares and deletes it); take its wall time, CPU time and peak RSS, count its lines and note the 1-minute
    load average when it ended."""
    child.output = folder / f"{name}.jsonl"
    err_path = folder / f"{name}.err"
    result_path = folder / f"{name}.rusage.json"
    launcher = [sys.executable, "-I", "-S", "-c", LAUNCHER, str(result_path)]
    with open(child.output, "wb") as out, open(err_path, "wb") as err, \
            (open(child.stdin, "rb") if child.stdin is not None else open(os.devnull, "rb")) as stdin:
        # Its own session: on Ctrl-C or SIGTERM the benchmark ends the launcher and the command together.
        proc = subprocess.Popen(launcher + child.argv, stdin=stdin, stdout=out, stderr=err, env=env,
                                start_new_session=True)
        try:
            proc.wait()
        except BaseException:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            raise
    child.stderr = err_path.read_text(errors="replace").strip()
    err_path.unlink()
    if not result_path.exists():
        raise RuntimeError(f"the launcher of {child.shell()} failed ({proc.returncode}):\n{child.stderr[-2000:]}")
    measured = json.loads(result_path.read_text())
    result_path.unlink()
    if measured["code"] != 0:
        raise RuntimeError(f"{child.shell()} exited with {measured['code']}:\n{child.stderr[-2000:]}")
    child.wall = measured["wall"]
    child.cpu = measured["cpu"]
    child.peak_mb = measured["maxrss_kib"] * 1024 / 1e6  # ru_maxrss is in KiB on Linux
    child.floor_mb = measured["floor_kib"] * 1024 / 1e6
    child.load = os.getloadavg()[0]
    with open(child.output, "rb") as f:
        child.contacts = sum(piece.count(b"\n") for piece in iter(lambda: f.read(1 << 20), b""))
    return child


def drop_output(child: Run) -> None:
    if child.output is not None:
        child.output.unlink(missing_ok=True)
        child.output = None


def first_difference(a: Path, b: Path) -> str | None:
    """None when the two JSON-lines files are byte for byte equal, else where and how they first differ."""
    with open(a, "rb") as fa, open(b, "rb") as fb:
        for number, (la, lb) in enumerate(itertools.zip_longest(fa, fb), start=1):
            if la == lb:
                continue
            if la is None or lb is None:
                return f"line {number}: only in {'the second' if la is None else 'the first'}"
            ja, jb = json.loads(la), json.loads(lb)
            keys = sorted(k for k in set(ja) | set(jb) if ja.get(k, "<absent>") != jb.get(k, "<absent>"))
            shown = ", ".join(f"{k}: {ja.get(k, '<absent>')!r} vs {jb.get(k, '<absent>')!r}" for k in keys[:4])
            return f"line {number} (lane {ja.get('lane')}, start {ja.get('start_time')}): {shown}" + \
                (f" (+{len(keys) - 4} keys)" if len(keys) > 4 else "")
    return None



def package_dir(env: dict) -> Path:
    """Where the console script's Python imports ``fruitimpact`` from, with this environment."""
    out = subprocess.run([sys.executable, "-c", "import fruitimpact; print(fruitimpact.__file__)"], env=env,
                         capture_output=True, text=True, check=True).stdout.strip()
    return Path(out).parent


def fingerprint(package: Path) -> str:
    """SHA-256 over the package's Python files (relative path and content): did the code change during the run?"""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def snapshot(folder: Path) -> tuple[Path, str]:
    """``git archive HEAD src`` into ``folder/snapshot``; → (its src folder, the commit)."""
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, check=True).stdout.strip()
    target = folder / "snapshot"
    target.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "HEAD", "src"], capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, check=True)
    return target / "src", commit


# ---------------------------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------------------------

def block_score(lines: list[str], truth: dict) -> str:
    """analyze's reports on one block against the generator's truth (``linegen.score``: pairing by lane and start
    time within 1 ms; a truth contact covered by an "overlap" report counts as found).  The contact count of the
    long runs is below the truth count by the contacts that touch another (a rebound landing on the next fruit):
    one overlap report stands for both."""
    reports = [json.loads(line) for line in lines]
    with warnings.catch_warnings():  # no --fit: the stiffness errors are NaN, their percentiles warn
        warnings.simplefilter("ignore", RuntimeWarning)
        card = lg.score(reports, truth)
    overlap_reports = sum(1 for r in reports if r.get("status") == "overlap")
    touching = sum(1 for c in truth["contacts"] if c["overlaps"])
    return (f"{len(reports)} reports ({overlap_reports} 'overlap') for {len(truth['contacts'])} truth contacts "
            f"({touching} touching another); recall {card['recall'] * 100:.1f} %, missed {card['missed']}, "
            f"extra {card['extra']}, rebounds taken for fruit {card['rebounds_taken_for_fruit']}, "
            f"fruit taken for rebounds {card['fruit_taken_for_rebounds']}")


def table(runs: list[Run]) -> list[list[str]]:
    head = ["run", "command", "minutes", "file [MB]", "contacts", "truth", "wall [s]", "× real time", "CPU [s]",
            "peak RSS [MB]", "load"]
    rows = [head]
    for r in runs:
        rows.append([r.label, r.command, f"{r.minutes:.1f}", f"{r.size_mb:.0f}", str(r.contacts), str(r.truth),
                     f"{r.wall:.1f}", f"{r.real_time:.1f}", f"{r.cpu:.1f}", f"{r.peak_mb:.0f}", f"{r.load:.1f}"])
    return rows


def text_table(rows: list[list[str]]) -> str:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(row, widths)))
             for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def markdown_table(rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(rows[0]) + " |",
             "|" + "|".join("---" if i < 2 else "---:" for i in range(len(rows[0]))) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows[1:]]
    return "\n".join(lines)


def goals(runs: dict[str, Run], per_block: int, differences: dict[str, str | None]) -> list[tuple[str, bool, str]]:
    """(goal, met, figures) for every goal the runs can check.  ``per_block``: contacts analyze reports on one
    block alone (the tiled recordings must give that many per block: the seams neither add nor lose any);
    ``differences``: per pair of runs, where analyze's output first differs from stream's (None: identical)."""
    out = []
    for key in ("a", "d", "c-analyze"):
        if key in runs:
            r = runs[key]
            out.append((f"analyze{' --fit' if 'fit' in r.command else ''} peak RSS ≤ {GOAL_RSS_MB:.0f} MB "
                        f"({r.minutes:.1f} min)", r.peak_mb <= GOAL_RSS_MB, f"{r.peak_mb:.0f} MB"))
    if "a" in runs and "d" in runs:
        a, d = runs["a"], runs["d"]
        out.append(("analyze memory does not grow with length (full vs quarter, within 10 %)",
                    a.peak_mb <= 1.10 * d.peak_mb, f"{a.peak_mb:.0f} MB at {a.minutes:.1f} min vs "
                                                   f"{d.peak_mb:.0f} MB at {d.minutes:.1f} min"))
    for an, st in (("a", "b"), ("c-analyze", "c-stream")):
        if an in runs and st in runs:
            a, s = runs[an], runs[st]
            what = " --fit" if "--fit" in a.argv else ""
            out.append((f"analyze{what} at least as fast as stream{what}, wall time", a.wall <= s.wall,
                        f"{a.wall:.1f} s vs {s.wall:.1f} s (load {a.load:.1f} / {s.load:.1f})"))
            out.append((f"analyze{what} at least as fast as stream{what}, CPU time", a.cpu <= s.cpu,
                        f"{a.cpu:.1f} s vs {s.cpu:.1f} s (analyze / stream = {a.cpu / s.cpu:.3f})"))
            out.append((f"analyze{what} reports the same contacts as stream{what}", a.contacts == s.contacts,
                        f"{a.contacts} vs {s.contacts}"))
            diff = differences.get(an)
            out.append((f"analyze{what} --json writes exactly what stream{what} writes", diff is None,
                        "identical bytes" if diff is None else f"first difference: {diff}"))
    if runs:
        floor = max(r.floor_mb for r in runs.values())
        lowest = min(r.peak_mb for r in runs.values())
        out.append(("the launcher's own peak (the floor of every reading) is below half of every peak",
                    floor < 0.5 * lowest, f"floor {floor:.0f} MB, lowest peak {lowest:.0f} MB"))
    tiled = [r for r in runs.values() if "--fit" not in r.argv]
    if tiled:
        out.append(("every run without --fit reports one block's contacts × blocks (seams add or lose none)",
                    all(r.contacts == per_block * r.blocks for r in tiled),
                    f"{per_block} per block; " + ", ".join(f"{r.label} {r.contacts} = {r.contacts / per_block:g} "
                                                           f"× {per_block} ({r.blocks} blocks)" for r in tiled)))
    return out


# ---------------------------------------------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------------------------------------------

def temporary_folder(need: int) -> Path:
    """A new folder under /tmp, or /work when /tmp lacks ``need`` bytes."""
    for base in ("/tmp", "/work"):
        if os.path.isdir(base) and shutil.disk_usage(base).free >= need:
            return Path(tempfile.mkdtemp(prefix="analyze_memory.", dir=base))
    raise SystemExit(f"not enough free space on /tmp or /work: {need / 1e9:.1f} GB needed")


def _terminated(signum, frame):
    raise KeyboardInterrupt


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a 3-minute recording, no --fit runs")
    parser.add_argument("--minutes", type=float, help="length of the recording [min] (default 60; --quick: 3)")
    parser.add_argument("--snapshot", action="store_true",
                        help="run the code of the last commit (git archive HEAD src, first on PYTHONPATH), not "
                             "the working tree, so edits made while it runs do not mix into the figures")
    parser.add_argument("--markdown", metavar="FILE", help="also write the results as Markdown")
    args = parser.parse_args(argv)
    minutes = args.minutes if args.minutes is not None else (3.0 if args.quick else 60.0)
    if not minutes > 0:
        parser.error("--minutes must be > 0")
    exe = console_script()
    command = shlex.join(["python", "benchmarks/analyze_memory.py"] + (sys.argv[1:] if argv is None else argv))

    # SIGTERM ends the run like Ctrl-C, so the folder is removed.
    signal.signal(signal.SIGTERM, _terminated)

    t0 = time.perf_counter()
    fruit_per_lane = QUICK_BLOCK_FRUIT if args.quick else BLOCK_FRUIT
    print(f"generating a lanes4 block at {RATE:g} Hz ({fruit_per_lane} fruit per lane) with tests/linegen.py ...",
          flush=True)
    block = make_block(fruit_per_lane)
    copies = max(1, math.ceil(minutes * 60.0 / block.seconds))
    quarter = max(1, round(copies / 4))
    bytes_per_block = block.samples.nbytes
    seam = (f"hum phase error {block.hum_error_deg:.2f}°, baseline step ≤ {block.step:.3f} N "
            f"(noise sd {block.noise_sd:.2f} N)")
    print(f"  block: {block.seconds:.2f} s, {block.fruit} fruit + {block.rebounds} rebounds, "
          f"{bytes_per_block / 1e6:.1f} MB; seam: {seam}; generated in {time.perf_counter() - t0:.0f} s", flush=True)
    # The recordings, two outputs kept side by side (JSON lines, < 4 kB per contact) and a margin.
    need = (copies + quarter + 1) * bytes_per_block + 2 * copies * block.contacts * 4096 + MARGIN
    folder = temporary_folder(need)
    runs: dict[str, Run] = {}
    differences: dict[str, str | None] = {}
    try:
        env = dict(os.environ)
        if args.snapshot:
            src, commit = snapshot(folder)
            env["PYTHONPATH"] = os.pathsep.join([str(src)] + [p for p in [env.get("PYTHONPATH")] if p])
            code = f"commit {commit} (git archive HEAD src, snapshot taken at the start)"
        else:
            commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                                    text=True).stdout.strip() or "?"
            code = f"working tree at commit {commit}"
        package = package_dir(env)
        before = fingerprint(package)
        code += f"; package {package}"
        print(f"  code: {code}", flush=True)

        full, part, one = folder / "line_full.f32", folder / "line_quarter.f32", folder / "line_block.f32"
        write_tiled(full, block, copies)
        write_tiled(part, block, quarter)
        write_tiled(one, block, 1)
        mb = lambda n: n * bytes_per_block / 1e6  # noqa: E731
        mins = lambda n: n * block.seconds / 60.0  # noqa: E731
        print(f"  wrote {full} ({copies} blocks, {mins(copies):.1f} min, {mb(copies):.0f} MB) and the quarter "
              f"({quarter} blocks, {mins(quarter):.1f} min)", flush=True)

        print("warming numba's cache (one block, not timed) ...", flush=True)
        fits = [[]] if args.quick else [[], ["--fit"]]
        for extra in fits:
            warm = run(Run("warm", [exe, "analyze", str(one), *ANALYZE, *extra], None), folder, env, "warm")
            if not extra:
                per_block = warm.contacts
                scored = block_score(warm.output.read_text().splitlines(), block.truth)
            drop_output(warm)
            drop_output(run(Run("warm", [exe, "stream", *STREAM, *extra], one), folder, env, "warm"))
        print(f"  one block alone, analyze vs truth: {scored}", flush=True)

        plan = [("a", "(a)", [exe, "analyze", str(full), *ANALYZE], None, copies),
                ("b", "(b)", [exe, "stream", *STREAM], full, copies)]
        if not args.quick:
            plan += [("c-analyze", "(c)", [exe, "analyze", str(full), *ANALYZE, "--fit"], None, copies),
                     ("c-stream", "(c)", [exe, "stream", *STREAM, "--fit"], full, copies)]
        plan += [("d", "(d)", [exe, "analyze", str(part), *ANALYZE], None, quarter)]
        pairs = {"b": "a", "c-stream": "c-analyze"}  # stream run → the analyze run its output is compared with
        for key, label, argv_, stdin, n in plan:
            child = Run(label, argv_, stdin, mins(n), mb(n), n * block.contacts, blocks=n)
            print(f"{label} {child.shell()} ...", flush=True)
            run(child, folder, env, key)
            print(f"    {child.contacts} contacts, {child.wall:.1f} s, CPU {child.cpu:.1f} s, "
                  f"{child.peak_mb:.0f} MB peak", flush=True)
            runs[key] = child
            if key in pairs:
                analyzed = runs[pairs[key]]
                differences[pairs[key]] = first_difference(analyzed.output, child.output)
                drop_output(analyzed)
            if key not in pairs.values():
                drop_output(child)
        after = fingerprint(package)
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    ordered = list(runs.values())
    rows = table(ordered)
    checks = goals(runs, per_block, differences)
    checks.append(("the code did not change while the benchmark ran", before == after,
                   "unchanged" if before == after else "CHANGED: the runs mix code versions (try --snapshot)"))
    recording = (f"lanes4 of tests/linegen.py at {RATE:g} Hz, 4 lanes: {block.fruit} fruit + {block.rebounds} "
                 f"rebounds = {block.contacts} truth contacts per {block.seconds:.2f} s block, tiled (seam: {seam})")
    total = time.perf_counter() - t0
    print()
    print(f"analyze vs stream on one recording ({command}; {total:.0f} s)")
    print(text_table(rows))
    print(f"recording: {recording}")
    print(f"one block alone, analyze vs truth: {scored}")
    for r in ordered:
        print(f"  {r.label} {r.shell()}")
    print("goals:")
    for name, ok, figures in checks:
        print(f"  [{'met' if ok else 'MISSED'}] {name}: {figures}")
    print(f"code: {code}")
    print(f"machine: {machine()}")
    if args.markdown:
        md = [f"`{command}` ({total / 60:.0f} min)", "", markdown_table(rows), "",
              f"Recording: {recording}.", "", f"One block alone, analyze vs truth: {scored}.", "",
              "Commands (the recordings in a temporary folder):", ""]
        md += [f"- {r.label} `{r.shell()}`" for r in ordered]
        md += ["", "Goals:", ""]
        md += [f"- {'met' if ok else '**missed**'}: {name}: {figures}" for name, ok, figures in checks]
        md += ["", f"Code: {code}.", "", f"Machine: {machine()}.", ""]
        Path(args.markdown).write_text("\n".join(md))
        print(f"Markdown written to {args.markdown}")
    return 0 if all(ok for _, ok, _ in checks) else 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("interrupted: temporary recordings removed", file=sys.stderr)
        sys.exit(130)
