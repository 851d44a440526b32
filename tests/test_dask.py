"""The Dask engine on a real ``distributed.LocalCluster`` (worker processes, no mocks):
batch, sweep and population give the same output as the in-process engine.

One module-wide cluster of two single-threaded worker processes serves the
``--scheduler ADDRESS`` tests; one test lets ``--engine dask`` start its own."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from fruitimpact.cli import main

distributed = pytest.importorskip("distributed")

POP = ("population", "--mass", "normal(115g,10g)", "--velocity", "uniform(0.5,1.5)", "--seed", 3, "-n", 5000,
       "--chunk-size", 1000, "--threshold", "peak_force>60N", "--json")


@pytest.fixture(scope="module")
def scheduler():
    import logging

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address


def run(capsys, *argv) -> str:
    status = main([*map(str, argv)])
    out, err = capsys.readouterr()
    assert status == 0, err
    return out


def test_population_on_a_scheduler_equals_in_process(tmp_path, capsys, scheduler):
    local = json.loads(run(capsys, *POP, "-o", tmp_path / "local.parquet"))
    remote = json.loads(run(capsys, *POP, "-o", tmp_path / "dask.parquet", "--scheduler", scheduler))
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "local.parquet"),
                                  pd.read_parquet(tmp_path / "dask.parquet"))
    for key in ("rows", "ok", "statistics", "thresholds", "percentile_method"):
        assert local[key] == remote[key], key
    assert not (tmp_path / "dask.parquet.parts").exists()


def test_batch_and_sweep_on_a_scheduler(tmp_path, capsys, scheduler):
    source = tmp_path / "in.csv"
    source.write_text("mass,velocity,model\n115g,1,hunt-crossley\n-1,1,\n0.2,2 m/s,chen\n0.1,0.5,nope\n0.15,1.2,\n")
    run(capsys, "batch", source, "-o", tmp_path / "a.csv", "--chunk-size", 2)
    out = run(capsys, "batch", source, "-o", tmp_path / "b.csv", "--chunk-size", 2, "--scheduler", scheduler)
    assert "5 rows: 3 ok, 2 invalid, 0 failed" in out
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "a.csv"), pd.read_csv(tmp_path / "b.csv"))
    sweep = ("sweep", "--velocity", "0.3:1.5:9", "--model", "hertz,chen", "--chunk-size", 5)
    run(capsys, *sweep, "-o", tmp_path / "s1.parquet")
    run(capsys, *sweep, "-o", tmp_path / "s2.parquet", "--engine", "dask", "--scheduler", scheduler)
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "s1.parquet"), pd.read_parquet(tmp_path / "s2.parquet"))


def test_engine_dask_starts_a_local_cluster(tmp_path, capsys):
    local = json.loads(run(capsys, *POP))
    report = json.loads(run(capsys, *POP, "--engine", "dask", "--workers", 2, "-o", tmp_path / "p.csv"))
    assert report["statistics"] == local["statistics"] and report["thresholds"] == local["thresholds"]
    assert len(pd.read_csv(tmp_path / "p.csv")) == 5000
