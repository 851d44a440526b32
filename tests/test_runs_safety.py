"""Runs never lose or invent data (issue 6, B and D): work folders fruitimpact may delete,
verified part files, input files that change, locks, full disks, limits and exact seeds.

All through ``cli.main`` in-process, on small runs with several chunks."""

from __future__ import annotations

import errno
import json
import math
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from fruitimpact import runs
from fruitimpact.impact.quantities import DEFAULT_SUMMARY


class Interrupt:
    """Stand-in for runs.chunks.compute_chunk that raises KeyboardInterrupt after ``chunks`` chunks."""

    real = staticmethod(runs.chunks.compute_chunk)

    def __init__(self, chunks):
        self.chunks = chunks

    def __call__(self, *args, **kwargs):
        if self.chunks == 0:
            raise KeyboardInterrupt
        self.chunks -= 1
        return self.real(*args, **kwargs)


def velocities_csv(path, rows=50):
    pd.DataFrame({"velocity": np.linspace(0.2, 2.0, rows), "mass": ["100g"] * rows}).to_csv(path, index=False)
    return path


def dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


# --------------------------------------------------------------------------- B.1, B.2, B.5 ownership
def test_fresh_never_deletes_a_folder_fruitimpact_did_not_make(tmp_path, cli, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "userdata").mkdir()
    (tmp_path / "userdata" / "notes.txt").write_text("x")
    line = cli.error("population", "-n", 1000, "--workdir", "userdata", "--fresh")
    assert "userdata" in line and "not fruitimpact's" in line
    assert (tmp_path / "userdata" / "notes.txt").read_text() == "x"
    line = cli.error("population", "-n", 1000, "--workdir", ".", "--fresh")
    assert "not fruitimpact's" in line and (tmp_path / "userdata" / "notes.txt").exists()


def test_an_empty_folder_is_adopted_and_kept(tmp_path, cli):
    (tmp_path / "wd").mkdir()
    cli.ok("population", "-n", 3000, "--chunk-size", 1000, "--workdir", tmp_path / "wd")
    assert (tmp_path / "wd").is_dir() and list((tmp_path / "wd").iterdir()) == []


def test_output_inside_the_work_folder_survives_cleanup(tmp_path, cli):
    wd = tmp_path / "wd"
    wd.mkdir()
    out = cli.ok("sweep", "--velocity", "0.5:1:3", "-o", wd / "out.csv", "--workdir", wd)
    assert "written to" in out
    assert len(pd.read_csv(wd / "out.csv")) == 3
    assert sorted(p.name for p in wd.iterdir()) == ["out.csv"]
    # the same command again: the folder holds only our output, and the run goes through
    cli.ok("sweep", "--velocity", "0.5:1:3", "-o", wd / "out.csv", "--workdir", wd)
    assert sorted(p.name for p in wd.iterdir()) == ["out.csv"]


def test_user_files_in_our_work_folder_are_kept(tmp_path, cli, monkeypatch):
    source = velocities_csv(tmp_path / "in.csv")
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(2))
    assert cli.run("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)[0] == 130
    monkeypatch.undo()
    (tmp_path / "out.csv.parts" / "mine.txt").write_text("keep me")
    cli.ok("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)
    assert [p.name for p in (tmp_path / "out.csv.parts").iterdir()] == ["mine.txt"]


def test_unrelated_parts_folders_where_work_folders_go_are_left_alone(tmp_path, cli, monkeypatch):
    import tempfile

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # a run without -o keeps its work folder there
    plan = runs.Plan("population", runs.PopulationSource((), (), 100, 0), runs.CHUNK_ROWS, write_rows=False,
                     stats=DEFAULT_SUMMARY, sample_rows=runs.SAMPLE_ROWS)
    same_name = tmp_path / runs.default_workdir(None, plan)
    other = tmp_path / "fruitimpact-population-0123456789ab.parts"
    for folder in (same_name, other):
        folder.mkdir()
        (folder / "data.bin").write_text("someone else's")
    # --no-spreads: the job of PopulationSource((), (), 100, 0), whose folder name the test took
    cli.ok("population", "-n", 100, "--seed", 1, "--no-spreads")  # another job: its own folder
    line = cli.error("population", "-n", 100, "--fresh", "--no-spreads")  # our job's name, not our folder
    assert "not fruitimpact's" in line
    assert (same_name / "data.bin").exists() and (other / "data.bin").exists()


# --------------------------------------------------------------------------- B.3 verified parts
@pytest.mark.parametrize("damage", ["replaced", "flipped", "truncated", "torn manifest"])
def test_damaged_parts_are_recomputed(tmp_path, cli, monkeypatch, damage):
    source = velocities_csv(tmp_path / "in.csv")
    cli.ok("batch", source, "-o", tmp_path / "full.csv", "--chunk-size", 7)
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(5))
    assert cli.run("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)[0] == 130
    monkeypatch.undo()
    parts = tmp_path / "out.csv.parts"
    part = parts / "part-0000002.arrow"
    data = bytearray(part.read_bytes())
    if damage == "replaced":
        part.write_bytes((parts / "part-0000001.arrow").read_bytes())
    elif damage == "flipped":
        data[len(data) // 2] ^= 0xFF
        part.write_bytes(bytes(data))
    elif damage == "truncated":
        part.write_bytes(bytes(data[:len(data) // 2]))
    else:
        with open(parts / "manifest.jsonl", "a") as handle:
            handle.write('{"chunk": 9, "start": ')  # a kill while appending
    out = cli.ok("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)
    assert "50 rows: 50 ok" in out
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out.csv"), pd.read_csv(tmp_path / "full.csv"))


def test_manifest_records_row_ranges_and_hashes(tmp_path, cli, monkeypatch):
    source = velocities_csv(tmp_path / "in.csv")
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(3))
    assert cli.run("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)[0] == 130
    lines = [json.loads(line) for line in (tmp_path / "out.parquet.parts" / "manifest.jsonl").read_text().splitlines()]
    assert "fingerprint" in lines[0]
    assert [(r["chunk"], r["start"], r["rows"]) for r in lines[1:]] == [(0, 0, 7), (1, 7, 7), (2, 14, 7)]
    assert all(len(r["part"]["sha256"]) == 64 and r["statuses"] == {"ok": 7} for r in lines[1:])


def test_an_input_file_changed_during_the_run_is_refused(tmp_path, cli, monkeypatch):
    source = velocities_csv(tmp_path / "in.csv")
    real = runs.chunks.compute_chunk

    def edit_after_first(plan, index, *args, **kwargs):
        result = real(plan, index, *args, **kwargs)
        if index == 0:
            with open(source, "a") as handle:
                handle.write("1.5,120g\n")
        return result

    monkeypatch.setattr(runs.chunks, "compute_chunk", edit_after_first)
    line = cli.error("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)
    assert "changed during the run" in line and "--fresh" in line
    assert not (tmp_path / "out.csv").exists()
    assert not [p for p in tmp_path.iterdir() if "fruitimpact-tmp" in p.name]


# --------------------------------------------------------------------------- B.4 locks, temporaries
def test_a_second_run_on_the_same_output_or_work_folder_is_refused(tmp_path, cli, monkeypatch):
    source = velocities_csv(tmp_path / "in.csv")
    out = tmp_path / "out.csv"
    held = runs.locking.RunLock(runs.execute_module.output_lock_path(out), "output").acquire()
    try:
        line = cli.error("batch", source, "-o", out, "--workdir", tmp_path / "elsewhere")
        assert "in use by another fruitimpact run" in line and f"pid {os.getpid()}" in line
    finally:
        held.release(remove=True)
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(1))
    assert cli.run("batch", source, "-o", out, "--chunk-size", 7)[0] == 130
    monkeypatch.undo()
    held = runs.locking.RunLock(tmp_path / "out.csv.parts" / ".fruitimpact-lock", "work folder").acquire()
    try:
        line = cli.error("batch", source, "-o", tmp_path / "other.csv", "--workdir", tmp_path / "out.csv.parts")
        assert "in use by another fruitimpact run" in line and f"pid {os.getpid()}" in line
    finally:
        held.release()
    cli.ok("batch", source, "-o", out, "--chunk-size", 7)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv", "out.csv"]


def test_stale_temporaries_of_the_output_are_removed(tmp_path, cli):
    out = tmp_path / "grid.parquet"
    stale = tmp_path / f".grid.parquet.fruitimpact-tmp-{dead_pid()}-0123abcd"
    stale.write_bytes(b"a merge killed half way")
    cli.ok("sweep", "--velocity", "0.5:1:3", "-o", out)
    assert not stale.exists() and len(pd.read_parquet(out)) == 3


# --------------------------------------------------------------------------- D: errors before work, full disk
@pytest.mark.parametrize("argv, words", [
    (["population", "-n", 100, "--hist", "h.xyz"], "argument --hist: cannot write 'h.xyz': unsupported format"),
    (["sweep", "--velocity", "1:2:3", "-o", "adir.csv"], "argument -o/--output: cannot write 'adir.csv': it is a folder"),
    (["sweep", "--velocity", "1:2:3", "-o", "nodir/sub/x.csv"], "argument -o/--output: cannot write 'nodir/sub/x.csv'"),
    (["sweep", "--velocity", "1:2:3", "-o", "x" * 240 + ".csv"], "the file name is longer than this file system allows"),
    (["sweep", "--velocity", "1:2:3", "-o", "x" * 300 + ".csv"], "argument -o/--output: cannot write"),
    (["sweep", "--velocity", "1:2:3", "--plot", "p.gif"], "argument --plot: cannot write 'p.gif': unsupported format"),
    (["population", "-n", 100, "--scheduler", "not an address"], "argument --scheduler: a scheduler address is like"),
    # no port: Dask cannot connect (it loaded dask, 0.6 s, and left OUT.parts behind)
    (["population", "-n", 100, "--scheduler", "notanaddress"], "argument --scheduler: a scheduler address is like"),
    (["population", "-n", 100, "--workdir", "afile/wd"], "argument --workdir"),
    (["population", "-n", "1e20"], "argument -n/--rows: rows must be an integer in [1, 1,000,000,000]; got '1e20'"),
    (["sweep", "--velocity", "0.3:1.5:100000000000", "-o", "x.csv"], "argument --velocity: the COUNT"),
    (["sweep", "--velocity", "0.3:1.5:1000000", "--mass", "0.1:0.2:1001", "-o", "x.csv"], "the grid has 1,001,000,000"),
    (["population", "--sample-size", "1e9"], "argument --sample-size: sample_size must be an integer in [1, 20,000,000]"),
    (["population", "--workers", "0", "--engine", "dask"], "argument --workers: workers must be an integer in [1, 256]"),
])
def test_bad_outputs_and_limits_are_one_line_before_work(tmp_path, cli, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir.csv").mkdir()
    (tmp_path / "afile").write_text("")
    line = cli.error(*argv)
    assert words in line, line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir.csv", "afile"]  # nothing was started


def test_a_full_disk_is_one_line_and_keeps_the_work_done(tmp_path, cli, monkeypatch):
    source = velocities_csv(tmp_path / "in.csv")
    real = runs.chunks.write_part

    def full_after_two(workdir, index, table):
        if index >= 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(workdir, index, table)

    monkeypatch.setattr(runs.chunks, "write_part", full_after_two)
    line = cli.error("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)
    assert "No space left on device" in line and "2 completed chunks are kept" in line
    assert not (tmp_path / "out.parquet").exists()
    monkeypatch.undo()
    assert "2 chunks resumed" in cli.ok("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)
    assert list(pd.read_parquet(tmp_path / "out.parquet")["row"]) == list(range(50))



def test_a_full_disk_before_any_chunk_leaves_nothing_behind(tmp_path, cli, monkeypatch):
    """Failing before any chunk was kept (a full disk at the first part, a Dask scheduler that does not answer)
    leaves nothing to resume: the work folder this run made goes, with its lock, marker and manifest (found by an
    attack: a refused --scheduler left OUT.parts behind, and the next job to the same output was refused as
    "a different job").  The files are the run's own; a folder that held the user's files stays (the tests
    above)."""
    source = velocities_csv(tmp_path / "in.csv")

    def full(workdir, index, table):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(runs.chunks, "write_part", full)
    line = cli.error("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)
    assert "No space left on device" in line and "before any chunk was completed" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv"]
    monkeypatch.undo()
    out = cli.ok("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 10)  # another job: not refused
    assert "resumed" not in out
    assert list(pd.read_parquet(tmp_path / "out.parquet")["row"]) == list(range(50))

def test_a_long_run_announces_an_estimate(cli, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runs.execute_module, "ESTIMATE_AFTER", 0.0)
    status, _, err = cli.run("population", "-n", 3000, "--chunk-size", 1000)
    assert status == 0 and "extrapolated from the first chunk: 1,000 rows in" in err


# --------------------------------------------------------------------------- D.17 seeds, counts
def test_seeds_above_2_53_are_exact(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    common = ("population", "-n", 50, "--mass", "normal(115g,10g)", "--json", "--characteristics", "peak_force")
    a = json.loads(cli.ok(*common, "--seed", 9007199254740993))
    b = json.loads(cli.ok(*common, "--seed", 9007199254740992))
    assert a["seed"] == 9007199254740993 and b["seed"] == 9007199254740992
    assert a["statistics"]["peak_force"]["mean"] != b["statistics"]["peak_force"]["mean"]
    assert json.loads(cli.ok("population", "-n", "1e3", "--json"))["rows"] == 1000


def test_status_line_counts_every_status():
    summary = runs.RunSummary("batch", 6, 3, 1, 1, statuses={"ok": 3, "invalid": 1, "failed": 1, "inaccurate": 1})
    from fruitimpact.cli.runs import _status_line

    assert _status_line(summary) == "6 rows: 3 ok, 1 invalid, 1 failed, 1 inaccurate"


def test_a_folder_turned_read_only_mid_run_gives_the_one_line_and_frees_the_lock(tmp_path, monkeypatch):
    """The output folder made read-only while a run writes (found by an attack run with DAC override dropped): the
    temporary file and the lock file can no longer be deleted.  That must neither replace the run's one-line error
    with a PermissionError nor leave the lock held: the same process could not run on that output again."""
    from pathlib import Path

    from fruitimpact.impact.outputs import atomic_write
    from fruitimpact.runs.locking import RunLock

    real_unlink = Path.unlink

    def read_only(self, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(self))

    def failing_write(tmp):
        Path(tmp).write_text("half")
        raise OSError(13, "Permission denied")

    out = tmp_path / "out.csv"
    lock = RunLock(tmp_path / ".out.lock", "output").acquire()
    monkeypatch.setattr(Path, "unlink", read_only)
    with pytest.raises(ValueError, match="cannot write"):
        atomic_write(out, failing_write, "-o/--output")
    lock.release(remove=True)
    monkeypatch.setattr(Path, "unlink", real_unlink)
    RunLock(tmp_path / ".out.lock", "output").acquire().release(remove=True)  # free again


def test_a_cell_that_is_not_utf8_or_a_column_of_another_type_is_a_bad_row_not_a_dead_batch(tmp_path, cli):
    """One undecodable byte stopped the whole file at its row (every rerun again), and a Parquet text column of
    numbers ended in a traceback: now those rows are invalid with their message, the others computed, and a
    refused row shows no default as an input it "used"."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    source = tmp_path / "in.csv"
    source.write_bytes(b"mass,velocity,model\n0.1,1,hunt-crossley\n0.1,1,h\xe9rtz\n0.12,1.2\n0.1,2,chen\n")
    cli.ok("batch", source, "-o", tmp_path / "out.csv")
    out = pd.read_csv(tmp_path / "out.csv")
    assert out["status"].tolist() == ["ok", "invalid", "invalid", "ok"]
    assert "not UTF-8" in out["message"][1] and "fields" in out["message"][2]
    assert out["mass"].isna().tolist() == [False, True, True, False]  # the unread rows used no input
    numbers = tmp_path / "model.parquet"
    pq.write_table(pa.table({"model": [1, 2], "velocity": [1.0, 1.0]}), numbers)
    status, _, err = cli.run("batch", numbers, "-o", tmp_path / "m.csv")  # written, every row said why; exit 1
    assert status == 1 and "no row is ok (2 rows: 0 ok, 2 invalid, 0 failed)" in err
    assert pd.read_csv(tmp_path / "m.csv")["message"].str.startswith("model must be one of").all()
    nested = tmp_path / "nested.parquet"
    pq.write_table(pa.table({"mass": [[1.0], [2.0]]}), nested)
    assert "holds list" in cli.error("batch", nested, "-o", tmp_path / "n.csv")


@pytest.mark.parametrize("argv,words", [
    (["batch", "IN", "-o", "x.csv/"], "argument -o/--output: cannot write 'x.csv/': the name ends in a slash"),
    (["batch", "IN", "-o", "w.csv", "--workdir", "w.csv"], "argument --workdir: cannot use 'w.csv': it is the output"),
    (["sweep", "-o", "a.csv"], "give at least one input to sweep"),
    (["sweep", "--velocity", "1,nan", "-o", "a.csv"], "argument --velocity: each value must be a number, not NaN"),
    (["sweep", "--veloc", "1,2", "-o", "a.csv"], "unrecognized arguments: --veloc"),  # no completion to --velocity
    (["population", "-n", "10", "--threshold", "peak_force>nan"], "a threshold's value must be a finite number"),
    (["population", "-n", "10", "--mass", "sample(rag.csv:mass)"],
     "sample: line 3 of 'rag.csv' has 3 fields where the header has 2: a ragged row is not read"),
    # a short row in another column than the sampled one: pandas would fill it, and the file is malformed
    (["population", "-n", "10", "--mass", "sample(short.csv:mass)"],
     "sample: line 4 of 'short.csv' has 1 field where the header has 2: a ragged row is not read"),
    (["line", "dup.csv", "-n", "10", "--fruit", "apple"], "transfer point 'a' is named twice"),
    # a constant that refuses every row (found by an attack: each ran and printed "0 ok, 10 invalid", exit 0)
    (["population", "-n", "10", "--step", "0"], "argument --step: step must be a finite number > 0 s"),
    # a work folder in a folder that does not exist: the chain of folders above it was made and left behind
    (["population", "-n", "10", "-o", "p.csv", "--workdir", "no/such/parts"],
     "argument --workdir: cannot write 'no/such/parts': folder 'no/such' does not exist"),
    (["population", "-n", "10", "--model", "kelvin-voigt", "--alpha", "0.3"],
     "argument --alpha: alpha is Hunt–Crossley's damping parameter of the power-law laws"),
    (["sweep", "--velocity", "0.5:1:3", "-o", "a.csv", "--step", "0"], "argument --step: step must be"),
])
def test_more_bad_runs_are_one_line_before_work(tmp_path, cli, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "IN").write_text("")
    (tmp_path / "in.csv").write_text("mass\n0.1\n")
    (tmp_path / "rag.csv").write_text("mass,velocity\n0.1,1\n0.12,1,3\n")
    (tmp_path / "short.csv").write_text("mass,velocity\n0.1,1\n\n0.12\n")
    (tmp_path / "dup.csv").write_text("name,drop_height,surface\na,10cm,steel\na,5cm,wood\n")
    argv = ["in.csv" if a == "IN" else a for a in argv]
    assert words in cli.error(*argv)
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "w.csv").exists()


def test_a_figure_with_nothing_to_draw_is_not_written(tmp_path, cli):
    # no criterion: no bruise volume anywhere; refused before the run (it used to run, then draw nothing, exit 1)
    line = cli.error("sweep", "--velocity", "0.5:1.5:4", "--plot", tmp_path / "p.png", "--characteristic",
                     "bruise_volume")
    assert line.startswith("fruitimpact sweep: error: argument --criterion: criterion must be given for bruise_volume")
    assert not (tmp_path / "p.png").exists()


def test_a_step_too_coarse_for_every_fruit_of_a_lot_or_grid_is_refused_before_work(tmp_path, cli):
    # rk4's step bound depends on the fruit (1/20 of the undamped Hertz contact duration): a constant step that is
    # refused for every member is a usage error (each run used to print "0 ok, N invalid" and exit 0)
    line = cli.error("population", "-n", "500", "--method", "rk4", "--step", "1s")
    assert line.startswith("fruitimpact population: error: argument --step: step must be at most 1/20 of the contact")
    assert line.endswith("every one of the lot's 500 fruit is refused for it")
    line = cli.error("sweep", "--velocity", "0.5:1:3", "-o", tmp_path / "a.csv", "--method", "rk4", "--step", "1s")
    assert line.endswith("every one of the grid's 3 points is refused for it")
    assert not (tmp_path / "a.csv").exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv, line", [
    # a mass drawn below zero, a lot or grid too large to validate whole before the run: computed, nothing ok
    (["population", "-n", "5000", "--method", "rk4", "--step", "1s"],
     "fruitimpact population: no row is ok (5000 rows: 0 ok, 5000 invalid, 0 failed)"),
    (["sweep", "--mass", "0.1:0.2:100", "--velocity", "0.5:1:100", "--method", "rk4", "--step", "1s", "-o", "g.csv"],
     "fruitimpact sweep: no row is ok (10000 rows: 0 ok, 10000 invalid, 0 failed); each row's message in g.csv"),
])
def test_a_run_with_no_row_ok_exits_1_and_says_so(tmp_path, cli, monkeypatch, argv, line):
    """A run whose every row is refused or failed computed nothing a user could take: it exited 0 and printed a
    table of NaN (an attack).  A lot or grid of at most 4,096 is validated whole before the run (usage error,
    exit 2, test above); a larger one is computed (one runnable fruit among them must run) and exits 1 with one
    line on stderr."""
    monkeypatch.chdir(tmp_path)
    status, _, err = cli.run(*argv)
    assert status == 1 and err.strip().splitlines()[-1].startswith(line), (status, err)


def test_a_step_that_some_fruit_of_a_lot_meet_leaves_the_others_to_their_rows(cli):
    # Hertz closed form of the undamped contact duration (Johnson 1985, §11.4), T = 2.9432 δ_max / v with
    # δ_max = (5 m v² / (4 K))^(2/5), K = 4/3 E* √R:
    # a step of T/20 at 1 m/s suits the slower half of a lot whose speed spans 0.5–1.5 m/s and not the faster
    # (T falls with v^(-1/5)), so the run goes ahead and the faster rows alone are invalid
    mass, radius, modulus, poisson = 0.115, 0.0325, 3e6, 0.3
    stiffness = 4.0 / 3.0 * modulus / (1 - poisson ** 2) * math.sqrt(radius)
    duration = 2.9432 * (5 * mass * 1.0 ** 2 / (4 * stiffness)) ** 0.4 / 1.0
    out = cli.ok("population", "-n", "400", "--no-spreads", "--fruit", "jonathan-apple", "--mass", "115g",
                 "--diameter", "65mm", "--modulus", "3MPa", "--poisson", "0.3", "--velocity", "uniform(0.5,1.5)",
                 "--method", "rk4", "--step", f"{duration / 20:.6g}", "--json")
    report = json.loads(out)
    assert 100 < report["ok"] < 300 and report["ok"] + report["invalid"] == 400, report["statuses"]


def test_the_writer_thread_imports_nothing(tmp_path):
    """A Ctrl-C half a second into a batch hung for good in 8 of 28 tries (an attack): the KeyboardInterrupt
    landed inside an import of the main thread (Arrow imports pandas on its first conversion), which kept
    CPython's import lock, and the interrupted run waited for the writer thread, itself waiting for that lock in
    ``import pyarrow.parquet``.  The writer's modules are now imported before it starts: in a fresh process, no
    import happens in the writer thread (an import hook records each module found, by thread)."""
    script = tmp_path / "run.py"
    (tmp_path / "in.csv").write_text("mass,velocity\n" + "".join(f"0.1{k % 10},1.{k % 7}\n" for k in range(3000)))
    script.write_text(
        "import sys, threading\n"
        "found = []\n"
        "class Spy:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        found.append((threading.current_thread().name, name))\n"
        "        return None\n"
        "sys.meta_path.insert(0, Spy())\n"
        "from fruitimpact.cli import main\n"
        "code = main(['batch', 'in.csv', '-o', 'out.parquet', '--chunk-size', '1000'])\n"
        "print(code, sorted({n for t, n in found if t.startswith('fruitimpact-writer')}))\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "0 []", done.stdout[-2000:]


@pytest.mark.parametrize("stop_at", [0, 2])
def test_ctrl_c_keeps_the_work_folder_only_with_a_chunk_in_it(tmp_path, cli, monkeypatch, stop_at):
    """A Ctrl-C before any chunk was stored left OUT.parts (lock file, marker, empty manifest) and said "completed
    chunks are kept": the next, different job to that output was then refused as "another job's parts" (an
    attack).  Now the folder goes when nothing is in it, and the message says so; with two chunks stored it stays,
    and the same command resumes them."""
    source = velocities_csv(tmp_path / "in.csv")
    real = runs.chunks.write_part

    def interrupted(workdir, index, table):
        if index >= stop_at:
            raise KeyboardInterrupt
        return real(workdir, index, table)

    monkeypatch.setattr(runs.chunks, "write_part", interrupted)
    status, out, err = cli.run("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)
    assert status == 130 and out == ""
    assert not (tmp_path / "out.parquet").exists()
    parts = tmp_path / "out.parquet.parts"
    if stop_at == 0:
        assert err.strip().endswith("interrupted; no chunk was complete: nothing kept") and not parts.exists()
    else:
        assert "completed chunks are kept in" in err and parts.exists()
    monkeypatch.undo()
    resumed = "2 chunks resumed" in cli.ok("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 7)
    assert resumed == (stop_at == 2)


@pytest.mark.parametrize("make, words", [
    (lambda: pa.table({"mass": [{"a": 1}]}), "column 'mass' of 'm.parquet' holds struct<a: int64>"),  # a traceback
    (lambda: pa.table({"mass": [True, False]}), "holds bool"),  # was read as 1 kg and 0 kg
    (lambda: pa.table({"mass": pa.array([0], pa.timestamp("us"))}), "holds timestamp[us]"),  # was 1.58e15 kg
])
def test_a_parquet_sample_holds_numbers_or_text(tmp_path, cli, monkeypatch, make, words):
    """sample(FILE.parquet:COLUMN) takes numbers or text with units; another type is no measurement (an attack
    found a structure crashing with a traceback, and true/false and dates read as masses)."""
    monkeypatch.chdir(tmp_path)
    pq.write_table(make(), tmp_path / "m.parquet")
    assert words in cli.error("population", "-n", "10", "--mass", "sample(m.parquet:mass)")


def test_sample_files_read_as_written(tmp_path, cli, monkeypatch):
    """A CSV sample: a header given twice is refused (which column was meant is a guess; batch refuses it too);
    blank lines before the header are skipped; "NAN" is a missing value like "NaN" and "nan" (it made the file be
    refused).  A Parquet sample's nulls are missing values, its text cells may carry units, its integers are
    numbers: the members are those values and no other (the sample's n and values are checked)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "twice.csv").write_text("mass,mass\n0.1,0.2\n")
    assert "sample: 'twice.csv': column 'mass' is given twice" in cli.error(
        "population", "-n", "10", "--mass", "sample(twice.csv:mass)")
    (tmp_path / "blank.csv").write_text("\n\nmass\n0.1\nNAN\nnan\n120g\n")
    pq.write_table(pa.table({"mass": ["115g", None, "0.1"]}), tmp_path / "text.parquet")
    for name, values in (("blank.csv", [0.1, 0.12]), ("text.parquet", [0.1, 0.115])):
        report = cli.json("population", "-n", "200", "--mass", f"sample({name}:mass)", "--no-spreads", "-o",
                          f"{name}.parquet")
        assert report["inputs"]["mass"] == f"sample({name}:mass, n=2)" and report["ok"] == 200
        assert sorted(set(np.round(pd.read_parquet(f"{name}.parquet")["mass"], 12))) == values


@pytest.mark.parametrize("output, words", [("x.txt", "unsupported format '.txt'"),
                                           ("no/such/x.csv", "folder 'no/such' does not exist"),
                                           ("in.csv", "output must differ from the input file")])
def test_a_bad_batch_output_is_refused_before_the_input_is_read(tmp_path, cli, monkeypatch, output, words):
    """The input was opened and hashed before -o was checked: on a 1 GB CSV an unsupported output took 1.0-1.4 s
    to refuse (an attack).  The output is checked first; the input is not opened (a source that fails if asked)."""
    monkeypatch.chdir(tmp_path)
    velocities_csv(tmp_path / "in.csv")

    def never(*args, **kwargs):
        raise AssertionError("the input was read before the output was checked")

    monkeypatch.setattr(runs.sources.TableSource, "open", never)
    assert words in cli.error("batch", "in.csv", "-o", output)


def test_an_implausible_value_in_a_run_is_said_once(tmp_path, cli, monkeypatch):
    """The brief: an implausible but legal value (a 180 kg fruit) gets one warning.  simulate said it; population,
    sweep and batch computed it without a word (an attack): each warning the rows carry is now said once on
    stderr with how many rows carry it, and listed in population's JSON."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.csv").write_text("mass,velocity\n180,1\n0.1,1\n")
    status, _, err = cli.run("batch", "b.csv", "-o", "b.parquet")
    lines = [line for line in err.splitlines() if "mass is outside the plausible range" in line]
    assert status == 0 and lines == ["fruitimpact batch: warning: 1 of 2 rows: mass is outside the plausible range "
                                     "for fruit, [0.001, 20] kg; a plain number is read in kg"]
    report = cli.json("population", "-n", "50", "--mass", "180kg")
    assert "50 of 50 rows: mass is outside the plausible range for fruit, [0.001, 20] kg; a plain number is read " \
           "in kg" in report["warnings"]


def test_ctrl_c_drops_a_large_chunk_being_written_instead_of_waiting(tmp_path, cli, monkeypatch):
    """A Ctrl-C waited for the chunk being written: 7.8 s with --chunk-size 3000000 (an attack).  A chunk larger
    than ``runs.abandon.WRITE_SLICE`` rows is written in slices, and an interrupted run's writer stops between two:
    the part file's temporary is removed, the chunk is not kept, nothing else is left.  Here slices of 5 rows, and
    the interrupt is raised once the writer has begun chunk 0 (so that it is caught mid-chunk)."""
    import threading
    import time

    from fruitimpact.runs import abandon

    source = velocities_csv(tmp_path / "in.csv")
    monkeypatch.setattr(abandon, "WRITE_SLICE", 5)
    monkeypatch.setattr(abandon, "CSV_WRITE_SLICE", 5)
    started = threading.Event()
    real_slices, real_compute = abandon.slices, runs.chunks.compute_chunk

    def slow_slices(table, text=False):
        for k, part in enumerate(real_slices(table, text)):
            started.set()
            time.sleep(0.05 if k else 0.0)  # the interrupt lands while this chunk is being written
            yield part

    def compute(plan, index, payload):
        if index == 1:
            assert started.wait(10)
            raise KeyboardInterrupt
        return real_compute(plan, index, payload)

    monkeypatch.setattr(runs.workdir, "slices", slow_slices)
    monkeypatch.setattr(runs.execute_module, "slices", slow_slices)
    monkeypatch.setattr(runs.chunks, "compute_chunk", compute)
    status, out, err = cli.run("batch", source, "-o", tmp_path / "out.parquet", "--chunk-size", 25)
    assert status == 130 and err.strip().endswith("interrupted; no chunk was complete: nothing kept"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv"]  # no part, no temporary, no output


def test_csv_written_in_small_slices_is_the_same_file(tmp_path, cli, monkeypatch):
    """CSV text is written 4-5 times slower than Parquet, so an interrupted run's writer looks at its mark every
    ``runs.abandon.CSV_WRITE_SLICE`` rows (a Ctrl-C into ``batch -o big.csv --chunk-size 3000000`` waited 0.9-1.9 s
    for a slice of 524,288 rows).  Slicing must change no byte of the output: the same batch with slices of 7
    rows, and written whole, give identical files."""
    from fruitimpact.runs import abandon

    source = velocities_csv(tmp_path / "in.csv")
    cli.ok("batch", source, "-o", tmp_path / "whole.csv", "--chunk-size", 40)
    monkeypatch.setattr(abandon, "CSV_WRITE_SLICE", 7)
    calls = []
    real = abandon.slices

    def counted(table, text=False):
        parts = list(real(table, text))
        calls.append(len(parts))
        yield from parts

    monkeypatch.setattr(runs.execute_module, "slices", counted)
    cli.ok("batch", source, "-o", tmp_path / "sliced.csv", "--chunk-size", 40)
    assert max(calls) > 1  # the output's chunks were written in slices
    assert (tmp_path / "sliced.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()


def test_ctrl_c_before_any_chunk_into_a_users_work_folder_says_nothing_was_kept(tmp_path, cli, monkeypatch):
    """With --workdir an existing (empty) folder of the user's, an interrupt before any chunk said "completed chunks
    are kept" because the folder was still there (it is the user's, so it stays): the message now follows the
    manifest (found by a review)."""
    source = velocities_csv(tmp_path / "in.csv")
    mine = tmp_path / "mine"
    mine.mkdir()
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(0))
    status, _, err = cli.run("batch", source, "-o", tmp_path / "out.csv", "--workdir", mine)
    assert status == 130 and err.strip().endswith("interrupted; no chunk was complete: nothing kept"), err
    assert mine.is_dir() and not list(mine.iterdir())


def test_sample_files_as_spreadsheets_and_pandas_write_them(tmp_path, cli, monkeypatch):
    """What the pandas-based reader read must still read (a review of the csv/pyarrow readers): a repeated header
    that is not the sampled column, an export's trailing unnamed columns, pandas' index column in a Parquet
    file, a categorical and a decimal column; and what float() alone would take but the unit parser refuses
    ("1_0") stays refused.  Each member is one of the file's values (checked in the written rows)."""
    import decimal

    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.csv").write_text("note,note,mass\na,b,0.1\nc,d,0.12\n")
    (tmp_path / "excel.csv").write_text("mass,,\n0.1,,\n0.12,,\n")
    pd.DataFrame({"weight": [0.1, 0.12]}, index=[5, 7]).to_parquet(tmp_path / "idx.parquet")
    pd.DataFrame({"mass": pd.Categorical(["100g", "0.12"])}).to_parquet(tmp_path / "cat.parquet")
    pq.write_table(pa.table({"mass": pa.array([decimal.Decimal("0.100"), decimal.Decimal("0.120")],
                                              pa.decimal128(5, 3))}), tmp_path / "dec.parquet")
    for spec in ("notes.csv:mass", "excel.csv", "idx.parquet", "cat.parquet:mass", "dec.parquet:mass"):
        cli.ok("population", "-n", "100", "--mass", f"sample({spec})", "--no-spreads", "-o", "p.parquet")
        assert sorted(set(np.round(pd.read_parquet("p.parquet")["mass"], 12))) == [0.1, 0.12], spec
    (tmp_path / "us.csv").write_text("mass\n1_0\n")
    assert "unknown unit '_0' in '1_0'" in cli.error("population", "-n", "10", "--mass", "sample(us.csv)")
