"""``fruitimpact batch | sweep | population``: chunked, resumable runs (fruitimpact.runs).

All in-process (``cli.main``) on small inputs; chunk sizes are kept small so that
every run has several chunks.  The Dask engine is tested in test_dask.py.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from fruitimpact import Fruit, runs, simulate
from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS

G = 9.80665


def read(path) -> pd.DataFrame:
    """The output's rows; text columns as plain strings (Parquet keeps them dictionary-encoded,
    with categories in the order each chunk met them)."""
    frame = pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)
    for name in frame.columns:
        if isinstance(frame[name].dtype, pd.CategoricalDtype):
            frame[name] = frame[name].astype(str)
    return frame


# --------------------------------------------------------------------------- batch
BATCH_CSV = """mass,diameter,modulus,drop-height,velocity,restitution,model,method,step
115g,65mm,3MPa,,1,0.5,hunt-crossley,,
0.2,0.07,4e6,30cm,,,chen,,
-1,0.065,,,1,,,,
0.1,abc,,,1,,,,
0.15,0.06,,,2 m/s,0.8,nope,,
0.15,0.06,,,1.5,0.3,hertz,rk4,2e-5
0.15,0.06,,20cm,1,,,,
180g,75mm,5MPa,,0.7,0.9,flores,,
"""


def expected_single(row: dict):
    """simulate() of one batch input row (SI numbers)."""
    fruit = Fruit(mass=row["mass"], diameter=row["diameter"], modulus=row["modulus"], poisson=0.37)
    kwargs = {k: row[k] for k in ("velocity", "drop_height", "restitution") if not pd.isna(row.get(k, math.nan))}
    return simulate(fruit, model=row["model"], method=row["method"], step=row["step"], **kwargs).characteristics


def test_batch_every_row_accounted_valid_rows_equal_simulate(tmp_path, cli):
    source = tmp_path / "in.csv"
    source.write_text(BATCH_CSV)
    out = cli.ok("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 3)
    assert "8 rows: 4 ok, 4 invalid, 0 failed" in out
    result = read(tmp_path / "out.csv")
    assert list(result["row"]) == list(range(8))
    assert list(result["status"]) == ["ok", "ok", "invalid", "invalid", "invalid", "ok", "invalid", "ok"]
    assert result.loc[2, "message"].startswith("mass must be")
    assert result.loc[3, "message"].startswith("diameter") and "'abc'" in result.loc[3, "message"]
    assert result.loc[4, "message"].startswith("model must be one of")
    assert result.loc[6, "message"] == "give either velocity or drop_height, not both"
    inputs = [dict(mass=0.115, diameter=0.065, modulus=3e6, velocity=1.0, restitution=0.5, model="hunt-crossley",
                   method="accurate", step=1e-4),
              dict(mass=0.2, diameter=0.07, modulus=4e6, drop_height=0.3, model="chen", method="accurate", step=1e-4),
              None, None, None,
              dict(mass=0.15, diameter=0.06, modulus=3e6, velocity=1.5, restitution=0.3, model="hertz",
                   method="rk4", step=2e-5),
              None,
              dict(mass=0.18, diameter=0.075, modulus=5e6, velocity=0.7, restitution=0.9, model="flores",
                   method="accurate", step=1e-4)]
    for i, row in enumerate(inputs):
        if row is None:
            assert np.isnan(result.loc[i, "peak_force"])
            continue
        single = expected_single(row)
        for name in CHARACTERISTIC_COLUMNS:
            assert result.loc[i, name] == pytest.approx(getattr(single, name), rel=1e-9), (i, name)
    assert result.loc[1, "velocity"] == pytest.approx(math.sqrt(2 * G * 0.3), rel=1e-15)
    assert not list(tmp_path.glob("*.parts"))  # work directory removed


def test_batch_csv_and_parquet_in_and_out_agree(tmp_path, cli):
    source = tmp_path / "in.csv"
    source.write_text(BATCH_CSV)
    frame = pd.read_csv(source, dtype=str)  # the same cells (strings with units) in Parquet
    frame.to_parquet(tmp_path / "in.parquet")
    cli.ok("batch", source, "-o", tmp_path / "a.parquet", "--chunk-size", 5)
    cli.ok("batch", tmp_path / "in.parquet", "-o", tmp_path / "b.csv", "--chunk-size", 3)
    cli.ok("batch", tmp_path / "in.parquet", "-o", tmp_path / "c.parquet")
    a, b, c = read(tmp_path / "a.parquet"), read(tmp_path / "b.csv"), read(tmp_path / "c.parquet")
    assert len(a) == len(b) == len(c) == 8
    pd.testing.assert_frame_equal(a, c)
    numeric = [k for k in a.columns if a[k].dtype.kind == "f"]
    np.testing.assert_array_equal(a[numeric].to_numpy(), b[numeric].to_numpy())  # CSV floats round-trip exactly
    assert list(a["status"]) == list(b["status"])


def test_batch_refuses_unknown_columns_and_formats(tmp_path, cli):
    (tmp_path / "in.csv").write_text("mass,velocty\n0.1,1\n")
    line = cli.error("batch", tmp_path / "in.csv", "-o", tmp_path / "o.csv")
    assert line.startswith("fruitimpact batch: error: argument IN:") and "'velocty'" in line
    (tmp_path / "in.txt").write_text("mass\n0.1\n")
    assert "must end in .csv or .parquet" in cli.error("batch", tmp_path / "in.txt", "-o", tmp_path / "o.csv")
    (tmp_path / "in.csv").write_text("mass\n0.1\n")
    line = cli.error("batch", tmp_path / "in.csv", "-o", tmp_path / "o.xlsx")
    assert "argument -o/--output" in line


# --------------------------------------------------------------------------- sweep
def test_sweep_grid_size_order_and_values(tmp_path, cli):
    out = cli.ok("sweep", "--velocity", "0.3:1.5:5", "--modulus", "2MPa:6MPa:3", "--mass", "150g",
             "--model", "hunt-crossley,chen", "-o", tmp_path / "s.parquet", "--chunk-size", 7)
    assert "5 velocity × 3 modulus × 2 model; 30 rows: 30 ok" in out
    s = read(tmp_path / "s.parquet")
    assert len(s) == 30 and list(s["row"]) == list(range(30))
    grid = [(v, e, m) for v in np.linspace(0.3, 1.5, 5) for e in (2e6, 4e6, 6e6) for m in ("hunt-crossley", "chen")]
    assert list(zip(s["velocity"], s["modulus"], s["model"])) == grid  # first option given varies slowest
    assert (s["mass"] == 0.15).all()
    row = s.iloc[17]
    single = simulate(Fruit(mass=0.15, diameter=0.065, modulus=row.modulus, poisson=0.37),
                      velocity=row.velocity, model=row.model).characteristics
    assert row.peak_force == pytest.approx(single.peak_force, rel=1e-9)


def test_sweep_log_spacing_list_and_plots(tmp_path, cli, monkeypatch):
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # where a run without -o keeps its work folder
    cli.ok("sweep", "--drop-height", "log:1cm:1m:5", "--restitution", "0.3,0.6", "-o", tmp_path / "s.csv",
       "--plot", tmp_path / "lines.png", "--characteristic", "contact_duration")
    s = read(tmp_path / "s.csv")
    np.testing.assert_allclose(sorted(set(s["drop_height"])), np.geomspace(0.01, 1.0, 5), rtol=1e-15)
    assert sorted(set(s["target_restitution"])) == [0.3, 0.6]
    cli.ok("sweep", "--velocity", "0.5:1.5:12", "--modulus", "2MPa:6MPa:10", "--plot", tmp_path / "heat.png")
    assert (tmp_path / "lines.png").stat().st_size > 0 and (tmp_path / "heat.png").stat().st_size > 0
    assert not list(tmp_path.glob("*.parts")) and not list(tmp_path.glob("*fruitimpact-*"))


@pytest.mark.parametrize("argv, option", [
    (["--velocity", "1:2"], "argument --velocity: a range is START:STOP:COUNT"),
    (["--velocity", "1:2:x"], "argument --velocity: the COUNT"),
    (["--modulus", "log:0:5MPa:4"], "argument --modulus: a log range needs"),
    (["--mass", "3MPa:4MPa:3"], "argument --mass: unknown unit 'MPa'"),
    (["--model", "hertz,nope"], "argument --model: model must be one of"),
    (["--velocity", "1:2:3", "--characteristic", "nope"], "argument --characteristic: unknown characteristic 'nope'"),
    (["--velocity", "1:2:3", "--mass", "-1"], "argument --mass: mass must be a finite number > 0"),
    (["--velocity", "1:2:3", "--drop-height", "1"], "give either --velocity or --drop-height, not both"),
    (["--velocity", "1:2:3", "--mass", "1:2:3", "--modulus", "1:2:3", "--plot", "x.png"], "argument --plot"),
    (["--velocity", "1:2:3"], "argument -o/--output: give -o OUT and/or --plot FILE"),
])
def test_sweep_bad_input_one_line(cli, argv, option):
    line = cli.error("sweep", *argv)
    assert line.startswith("fruitimpact sweep: error: " + option), line


# --------------------------------------------------------------------------- population
POP = ("population", "--mass", "normal(115g,10g)", "--velocity", "uniform(0.5m/s,1.5m/s)",
       "--modulus", "lognormal(3MPa,0.2)", "--restitution", "truncnormal(0.6,0.1,0.4,0.8)", "--seed", 7)


def population(tmp_path, cli, name, *extra, rows=6000, chunk=2000):
    out = tmp_path / name
    report = json.loads(cli.ok(*POP, "-n", rows, "--chunk-size", chunk, "-o", out, "--json", *extra))
    return read(out), report


def test_population_reproducible_and_independent_of_chunking(tmp_path, cli):
    a, report_a = population(tmp_path, cli, "a.parquet")
    b, _ = population(tmp_path, cli, "b.parquet")
    c, report_c = population(tmp_path, cli, "c.csv", chunk=777)
    d, _ = population(tmp_path, cli, "d.parquet", chunk=6000)
    pd.testing.assert_frame_equal(a, b)
    pd.testing.assert_frame_equal(a, d)
    numeric = [k for k in a.columns if a[k].dtype.kind in "fi"]
    np.testing.assert_array_equal(a[numeric].to_numpy(), c[numeric].to_numpy())
    for name, stats in report_a["statistics"].items():  # merged moments agree across chunkings
        assert stats["mean"] == pytest.approx(report_c["statistics"][name]["mean"], rel=1e-12)
        assert stats["percentiles"] == report_c["statistics"][name]["percentiles"]
    e, _ = population(tmp_path, cli, "e.parquet", rows=2500)  # a smaller population is a prefix
    pd.testing.assert_frame_equal(e, a.iloc[:2500])
    other = json.loads(cli.ok(*POP[:-1], 8, "-n", 6000, "--json"))
    assert other["statistics"]["peak_force"]["mean"] != report_a["statistics"]["peak_force"]["mean"]


def test_population_distributions(tmp_path, cli):
    a, _ = population(tmp_path, cli, "a.parquet", rows=20000, chunk=20000)
    assert a["mass"].mean() == pytest.approx(0.115, abs=3 * 0.01 / math.sqrt(20000))
    assert a["mass"].std() == pytest.approx(0.01, rel=0.03)
    assert a["velocity"].between(0.5, 1.5).all()
    assert np.median(a["modulus"]) == pytest.approx(3e6, rel=0.01)  # lognormal(median, sigma)
    assert np.log(a["modulus"]).std() == pytest.approx(0.2, rel=0.03)
    assert a["target_restitution"].between(0.4, 0.8).all()
    assert a["target_restitution"].mean() == pytest.approx(0.6, abs=0.005)
    sample = pd.DataFrame({"m": ["100g", "120g", "0.14"], "other": [1, 2, 3]})
    sample.to_csv(tmp_path / "measured.csv", index=False)
    s, report = population(tmp_path, cli, "s.parquet", "--mass", f"sample({tmp_path / 'measured.csv'}:m)",
                           rows=3000)
    assert set(s["mass"]) == {0.1, 0.12, 0.14}
    assert report["ok"] == 3000


def test_population_statistics_exact_for_small_n(tmp_path, cli):
    rows, report = population(tmp_path, cli, "a.parquet", "--threshold", "peak_force>60N", "--threshold",
                              "firmness_c_star>=2e7", "--threshold", "contact_duration<6.5ms",
                              "--percentiles", "1,50,99.5")
    good = rows[rows["status"] == "ok"]
    assert report["rows"] == 6000 and report["ok"] == len(good)
    assert report["percentile_method"]["exact"] is True
    for name in CHARACTERISTIC_COLUMNS:
        stats, values = report["statistics"][name], good[name].to_numpy()
        assert stats["count"] == len(values)
        assert stats["min"] == values.min() and stats["max"] == values.max()
        assert stats["mean"] == pytest.approx(values.mean(), rel=1e-13)
        assert stats["sd"] == pytest.approx(values.std(ddof=1), rel=1e-10, abs=1e-14 * abs(values.mean()))
        assert stats["percentiles"] == {p: np.percentile(values, float(p)) for p in ("1", "50", "99.5")}
    counts = [t["count"] for t in report["thresholds"]]
    assert counts == [int((good.peak_force > 60).sum()), int((good.firmness_c_star >= 2e7).sum()),
                      int((good.contact_duration < 6.5e-3).sum())]
    assert report["thresholds"][0]["share"] == counts[0] / len(good)


def test_population_percentiles_estimated_from_sample_above_sample_size(cli):
    report = json.loads(cli.ok(*POP, "-n", 6000, "--chunk-size", 2500, "--sample-size", 1000, "--json",
                           "--characteristics", "peak_force,max_deflection"))
    exact = json.loads(cli.ok(*POP, "-n", 6000, "--json", "--characteristics", "peak_force,max_deflection"))
    method = report["percentile_method"]
    assert method["exact"] is False and 800 < method["sample_rows"] < 1200
    assert "estimate" in method["note"] and str(method["sample_rows"]) in method["note"]
    for name in ("peak_force", "max_deflection"):
        a, b = report["statistics"][name], exact["statistics"][name]
        assert (a["count"], a["min"], a["max"]) == (b["count"], b["min"], b["max"])  # always exact
        assert a["mean"] == pytest.approx(b["mean"], rel=1e-12)
        assert a["percentiles"]["50"] == pytest.approx(b["percentiles"]["50"], rel=0.05)
    assert set(report["statistics"]) == {"peak_force", "max_deflection"}


def test_population_text_report_and_histograms(tmp_path, cli):
    out = cli.ok(*POP, "-n", 3000, "--threshold", "peak_force>60N", "--hist", tmp_path / "h.png",
             "--characteristics", "peak_force,firmness_c")
    assert "population: 3000 rows" in out and "percentiles: exact" in out
    assert "peak_force>60N" in out and "firmness C = F_max/t_c" in out and "N/ms" in out
    assert (tmp_path / "h.png").stat().st_size > 0
    assert not list(tmp_path.glob("*.parts"))


# --------------------------------------------------------------------------- resume
class Interrupt:
    """Stand-in for runs.chunks.compute_chunk that raises KeyboardInterrupt (Ctrl-C) after ``chunks`` chunks."""

    real = staticmethod(runs.chunks.compute_chunk)

    def __init__(self, chunks):
        self.chunks = chunks

    def __call__(self, *args, **kwargs):
        if self.chunks == 0:
            raise KeyboardInterrupt
        self.chunks -= 1
        return self.real(*args, **kwargs)


def test_interrupted_population_resumes_to_identical_output(tmp_path, monkeypatch, cli):
    full, _ = population(tmp_path, cli, "full.parquet", rows=7000, chunk=1000)
    out = tmp_path / "resumed.parquet"
    argv = (*POP, "-n", 7000, "--chunk-size", 1000, "-o", out, "--json")
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(3))
    status, _, err = cli.run(*argv)
    assert status == 130 and "interrupted" in err and "resume" in err
    parts = tmp_path / "resumed.parquet.parts"
    assert len(list(parts.glob("part-*.arrow"))) == 3 and not out.exists()
    stale = parts / ".part-0000009.arrow.fruitimpact-tmp-1-deadbeef"
    stale.write_bytes(b"half a chunk")  # killed while writing
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(2))
    assert cli.run(*argv)[0] == 130
    assert len(list(parts.glob("part-*.arrow"))) == 5 and not stale.exists()
    monkeypatch.undo()
    report = json.loads(cli.ok(*argv))
    assert report["resumed_chunks"] == 5
    resumed = read(out)
    assert len(resumed) == 7000 and resumed["row"].is_unique
    pd.testing.assert_frame_equal(resumed, full)
    assert not parts.exists()


def test_deleted_parts_are_recomputed(tmp_path, cli, monkeypatch):
    source = tmp_path / "in.csv"
    pd.DataFrame({"velocity": np.linspace(0.2, 2.0, 50), "mass": ["100g"] * 50}).to_csv(source, index=False)
    cli.ok("batch", source, "-o", tmp_path / "full.csv", "--chunk-size", 7)
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(6))
    assert cli.run("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)[0] == 130
    monkeypatch.undo()
    parts = tmp_path / "out.csv.parts"
    (parts / "part-0000002.arrow").unlink()
    (parts / "part-0000004.arrow").unlink()
    out = cli.ok("batch", source, "-o", tmp_path / "out.csv", "--chunk-size", 7)
    assert "50 rows: 50 ok" in out and "4 chunks resumed" in out
    pd.testing.assert_frame_equal(read(tmp_path / "out.csv"), read(tmp_path / "full.csv"))


def test_work_directory_of_another_job_is_refused(tmp_path, cli, monkeypatch):
    out = tmp_path / "pop.parquet"
    monkeypatch.setattr(runs.chunks, "compute_chunk", Interrupt(1))
    assert cli.run(*POP, "-n", 3000, "--chunk-size", 1000, "-o", out)[0] == 130
    monkeypatch.undo()
    for changed in (("--seed", 8), ("-n", 4000), ("--chunk-size", 500), ("--mass", "normal(116g,10g)")):
        argv = list(POP) + ["-n", 3000, "--chunk-size", 1000, "-o", out]
        argv[argv.index(changed[0]) + 1] = changed[1]
        line = cli.error(*argv)
        assert "pop.parquet.parts holds the parts of a different job" in line and "--fresh" in line
    assert not out.exists()
    cli.ok(*POP, "-n", 3000, "--chunk-size", 1000, "-o", out, "--seed", 9, "--fresh")
    assert len(read(out)) == 3000


# --------------------------------------------------------------------------- bad specs
@pytest.mark.parametrize("argv, message", [
    (["--mass", "normal(1)"], "argument --mass: normal(mean, sd) takes 2 values; got 1"),
    (["--mass", "gamma(1,2)"], "argument --mass: unknown distribution 'gamma'"),
    (["--mass", "normal(115g,-1g)"], "argument --mass: normal(mean, sd) needs"),
    (["--modulus", "lognormal(3MPa,2MPa)"], "argument --modulus: unknown unit 'MPa'"),
    (["--velocity", "uniform(2,1)"], "argument --velocity: uniform(lo, hi) needs"),
    (["--restitution", "truncnormal(0.5,0.01,0.9,1)"], "argument --restitution: truncnormal: [lo, hi] holds only"),
    (["--mass", "sample(nofile.csv)"], "argument --mass: sample: no such file"),
    (["--mass", "-1"], "argument --mass: mass must be a finite number > 0"),
    (["--velocity", "1", "--drop-height", "normal(1,0.1)"], "give either --velocity or --drop-height, not both"),
    (["--threshold", "peak_force>60kg"], "argument --threshold: unknown unit 'kg'"),
    (["--threshold", "nope>1"], "argument --threshold: unknown characteristic 'nope'"),
    (["--threshold", "peak_force=1"], "argument --threshold: a threshold is NAME>VALUE"),
    (["--characteristics", "peak_force,nope"], "argument --characteristics: unknown characteristic 'nope'"),
    (["--percentiles", "50,101"], "argument --percentiles"),
    (["-n", "0"], "argument -n/--rows: rows must be an integer in [1, 1,000,000,000]"),
    (["--seed", "-3"], "argument --seed: seed must be an integer in [0, 340,282,366,920,938,463,463,374,607,431,768,211,455]"),
    (["--seed", "1e9999999"], "argument --seed: seed must be an integer in [0, "),
    (["--model", "nope"], "argument --model: model must be one of"),
    (["--chunk-size", "1.5"], "argument --chunk-size: chunk_size must be an integer in [1, 10,000,000]"),
])
def test_population_bad_input_one_line(cli, argv, message):
    line = cli.error("population", *argv)
    assert line.startswith("fruitimpact population: error: " + message), line


def test_population_invalid_members_are_counted_not_fatal(cli):
    report = json.loads(cli.ok("population", "-n", 2000, "--mass", "normal(50g,40g)", "--json",
                           "--threshold", "peak_force>0"))
    assert report["invalid"] > 0 and report["ok"] + report["invalid"] + report["failed"] == 2000
    assert report["statistics"]["peak_force"]["count"] == report["ok"] == report["thresholds"][0]["count"]


def test_threshold_units_for_firmness():
    assert runs.Threshold.parse("firmness_c_star>2e7").value == 2e7
    assert runs.Threshold.parse("firmness_c_star > 20 N/ms^2").value == pytest.approx(2e7)
    assert runs.Threshold.parse("firmness_c>=30N/ms").value == pytest.approx(3e4)
    assert runs.Threshold.parse("max_deflection<2mm").value == pytest.approx(2e-3)


def test_batch_of_an_empty_file_writes_the_columns(tmp_path, cli):
    (tmp_path / "in.csv").write_text("mass,velocity\n")
    assert "0 rows: 0 ok, 0 invalid, 0 failed" in cli.ok("batch", tmp_path / "in.csv", "-o", tmp_path / "o.parquet")
    result = read(tmp_path / "o.parquet")
    assert len(result) == 0 and list(result.columns[:2]) == ["row", "mass"] and "peak_force" in result


def test_population_with_every_input_at_its_default(cli):
    # no distribution given and --no-spreads (by default a lot draws the fruit's library spreads): every member
    # is the default apple, and the row count holds even past the percentile sample size (regression: 0 rows)
    report = json.loads(cli.ok("population", "-n", 3000, "--chunk-size", 1000, "--sample-size", 500, "--no-spreads",
                               "--json"))
    assert report["rows"] == 3000 and report["ok"] == 3000
    default = simulate().characteristics.peak_force
    stats = report["statistics"]["peak_force"]
    assert stats["min"] == pytest.approx(default, rel=1e-12) and stats["max"] == pytest.approx(default, rel=1e-12)
