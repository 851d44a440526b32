"""Reading input tables for runs (issue 6, C): pyarrow, streamed; ragged rows, NaN and empty
cells; the shipped example; and figures written atomically."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from fruitimpact import runs
from fruitimpact.cli import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "fruit.csv"


def chunks_of(path, chunk_rows=1000):
    """(columns as Python lists, errors) of every chunk a TableSource gives."""
    source = runs.TableSource.open(path)
    out = []
    for _, (table, errors) in source.payloads(chunk_rows):
        out.append((table.to_pydict(), errors))
    return out


def cli_ok(capsys, *argv) -> str:
    status = main([*map(str, argv)])
    out, err = capsys.readouterr()
    assert status == 0, err
    return out


# --------------------------------------------------------------------------- C.10 ragged rows
def test_a_ragged_row_keeps_its_place_and_shifts_nothing(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("mass,velocity\n0.1,1,7\n0.12,1.5\n0.13\n0.14,2\n")
    [(columns, errors)] = chunks_of(path)
    assert columns["mass"] == [None, 0.12, None, 0.14] and columns["velocity"] == [None, 1.5, None, 2.0]
    assert errors[0].startswith("row has 3 fields; the header has 2")
    assert errors[2].startswith("row has 1 fields; the header has 2")
    assert errors[1] is None and errors[3] is None


def test_ragged_rows_across_chunk_boundaries(tmp_path):
    path = tmp_path / "in.csv"
    lines = [f"{0.1 + i / 1000},1" if i % 4 else f"{0.1 + i / 1000},1,x" for i in range(10)]
    path.write_text("mass,velocity\n" + "\n".join(lines) + "\n")
    got = chunks_of(path, chunk_rows=3)
    assert [len(c["mass"]) for c, _ in got] == [3, 3, 3, 1]
    masses = [m for c, _ in got for m in c["mass"]]
    errors = [e for c, errs in got for e in (errs or [None] * len(c["mass"]))]
    assert [e is not None for e in errors] == [i % 4 == 0 for i in range(10)]
    assert masses == [None if i % 4 == 0 else pytest.approx(0.1 + i / 1000) for i in range(10)]


def test_batch_marks_a_ragged_row_invalid_and_the_others_unshifted(tmp_path, capsys):
    path = tmp_path / "in.csv"
    path.write_text("mass,velocity\n0.1,1,7\n0.12,1.5\n")
    assert "2 rows: 1 ok, 1 invalid" in cli_ok(capsys, "batch", path, "-o", tmp_path / "out.csv")
    out = pd.read_csv(tmp_path / "out.csv")
    assert out.loc[0, "status"] == "invalid" and "3 fields" in out.loc[0, "message"]
    assert (out.loc[1, "mass"], out.loc[1, "velocity"], out.loc[1, "status"]) == (0.12, 1.5, "ok")


# --------------------------------------------------------------------------- C.11 NaN and empty cells
def test_empty_cells_are_null_and_nan_spellings_are_given(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("mass,velocity,model\n,nan,\n0.1,NaN,chen\n0.1,NA,\n0.1, 2 ,\n")
    [(columns, errors)] = chunks_of(path)
    assert errors is None
    assert columns["mass"] == [None, 0.1, 0.1, 0.1] and columns["model"] == [None, "chen", None, None]
    assert columns["velocity"] == ["nan", "NaN", "NA", " 2 "]  # given, all of them: left to evaluate
    path.write_text("mass,velocity\n,nan\n0.1,NaN\n0.1,\n")
    [(columns, _)] = chunks_of(path)
    velocity = columns["velocity"]
    assert np.isnan(velocity[0]) and np.isnan(velocity[1]) and velocity[2] is None


def test_plain_number_columns_are_read_as_numbers_and_unit_columns_as_text(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("mass,velocity,model\n115g,1,chen\n0.2,2e0,hertz\n")
    source = runs.TableSource.open(path)
    [(_, (table, _))] = list(source.payloads(10))
    assert table.schema.field("velocity").type == pa.float64()
    assert table.schema.field("mass").type == pa.string() and table.schema.field("model").type == pa.string()


def test_batch_nan_cells_are_invalid_and_empty_cells_take_the_default(tmp_path, capsys):
    path = tmp_path / "in.csv"
    path.write_text("mass,velocity\n0.1,nan\n0.1,NaN\n0.1,NA\n0.1,\n,1.2\n")
    cli_ok(capsys, "batch", path, "-o", tmp_path / "out.csv")
    out = pd.read_csv(tmp_path / "out.csv")
    assert list(out["status"]) == ["invalid", "invalid", "invalid", "ok", "ok"]
    assert out.loc[3, "velocity"] == 1.0 and out.loc[4, "mass"] == 0.115  # the defaults


def test_unknown_and_hyphenated_columns(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("mass,drop-height\n0.1,30cm\n")
    [(columns, _)] = chunks_of(path)
    assert set(columns) == {"mass", "drop_height"}
    path.write_text("mass,velocty\n0.1,1\n")
    with pytest.raises(ValueError, match="velocty"):
        runs.TableSource.open(path)


def test_parquet_input_keeps_nulls_and_types(tmp_path):
    path = tmp_path / "in.parquet"
    pd.DataFrame({"mass": [0.1, None, 0.12], "velocity": ["1 m/s", None, "2"]}).to_parquet(path)
    [(columns, errors)] = chunks_of(path)
    assert errors is None and columns["mass"] == [0.1, None, 0.12] and columns["velocity"] == ["1 m/s", None, "2"]


# --------------------------------------------------------------------------- C.18 the shipped example
def test_the_shipped_example_runs_clean(tmp_path, capsys):
    assert "12 rows: 12 ok, 0 invalid, 0 failed" in cli_ok(capsys, "batch", EXAMPLE, "-o", tmp_path / "r.parquet")
    result = pd.read_parquet(tmp_path / "r.parquet")
    assert result["model"].nunique() >= 5 and result["mass"].min() < 0.01 and result["mass"].max() > 1


# --------------------------------------------------------------------------- figures
def test_save_figure_is_atomic_and_takes_the_format_from_the_extension(tmp_path):
    pytest.importorskip("matplotlib")
    from fruitimpact.plotting import histogram_figure, save_figure

    fig = histogram_figure(np.random.default_rng(0).normal(size=(100, 1)), ("peak_force",), True)
    save_figure(fig, tmp_path / "h.svg")
    assert (tmp_path / "h.svg").read_text().lstrip().startswith("<?xml")
    (tmp_path / "h.png").write_bytes(b"the old figure")

    def full_disk(path, **kwargs):
        Path(path).write_bytes(b"half a figure")
        raise OSError(28, os.strerror(28))

    fig = histogram_figure(np.ones((3, 1)), ("peak_force",), True)
    fig.savefig = full_disk
    with pytest.raises(ValueError, match="argument --plot: .* no space left"):
        save_figure(fig, tmp_path / "h.png", "--plot")
    assert (tmp_path / "h.png").read_bytes() == b"the old figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["h.png", "h.svg"]
