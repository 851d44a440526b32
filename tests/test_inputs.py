"""Never compute with inputs the user did not give (issue 6, items 10–13).

The rule: an absent column, None, pd.NA, an Arrow null or an empty string is
"not given" (the default); any number, NaN included, is given, and a NaN is
refused; unknown columns are refused before any work; a row the reader
found broken is invalid with the reader's message and the others are
unaffected; implausible but legal values are computed and warned about.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

import fruitimpact
from fruitimpact.impact.evaluation import evaluate
from fruitimpact.impact.inputs import unknown_columns_message


def test_nan_is_invalid_and_none_takes_the_default():
    table = evaluate({"mass": [0.1, math.nan, None, "nan", "NaN", ""], "velocity": 1.0})
    assert list(table["status"]) == ["ok", "invalid", "ok", "invalid", "invalid", "ok"]
    assert table.loc[1, "message"].startswith("mass is NaN")
    assert table.loc[2, "mass"] == 0.115 and table.loc[5, "mass"] == 0.115  # the default, as documented
    assert np.isnan(table.loc[1, "peak_force"])


def test_pandas_nan_is_refused_and_nullable_na_is_not_given():
    frame = pd.DataFrame({"mass": pd.array([0.1, None], dtype="Float64"), "velocity": [1.0, np.nan]})
    table = evaluate(frame)
    assert table.loc[0, "status"] == "ok" and table.loc[0, "mass"] == 0.1
    assert table.loc[1, "status"] == "invalid" and table.loc[1, "message"].startswith("velocity is NaN")


def test_arrow_null_is_not_given_and_arrow_nan_is_refused():
    table = pa.table({"mass": pa.array([0.2, None, float("nan")], type=pa.float64()),
                      "model": pa.array(["chen", None, "chen"])})
    result = evaluate(table)
    assert list(result["status"]) == ["ok", "ok", "invalid"]
    assert list(result["mass"][:2]) == [0.2, 0.115]
    assert result.loc[1, "model"] == "hunt-crossley"


def test_rows_marked_by_the_reader_are_invalid_and_the_others_unaffected():
    # what a CSV reader hands over for "mass,velocity\n0.1,1,7\n0.12,1.5\n": the ragged row is not read
    result = evaluate({"mass": [None, 0.12], "velocity": [None, 1.5]},
                      errors=["row 1 has 3 fields; the header has 2", ""])
    assert list(result["status"]) == ["invalid", "ok"]
    assert result.loc[0, "message"] == "row 1 has 3 fields; the header has 2"
    assert result.loc[1, "mass"] == 0.12 and result.loc[1, "velocity"] == 1.5


def test_misspelt_column_is_refused_with_the_cli_message():
    with pytest.raises(ValueError) as info:
        evaluate({"mass": [0.18], "velocty": [3.0]})
    assert str(info.value) == unknown_columns_message(["velocty"])
    assert "'velocty'" in str(info.value)


def test_columns_of_different_lengths_are_refused():
    with pytest.raises(ValueError, match="different lengths"):
        evaluate({"mass": [0.1, 0.2], "velocity": [1.0]})


def test_dash_and_underscore_names_are_the_same_input():
    a = evaluate({"drop-height": [0.3]})
    b = evaluate({"drop_height": [0.3]})
    assert a.loc[0, "velocity"] == b.loc[0, "velocity"] == pytest.approx(math.sqrt(2 * 9.80665 * 0.3))


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(fruit=fruitimpact.Fruit(mass=180)), "mass = 180 kg is outside the plausible range for fruit, [0.001, 20] kg"),
    (dict(fruit=fruitimpact.Fruit(diameter=75)), "diameter = 75 m is outside the plausible range"),
    (dict(velocity=300), "velocity = 300 m/s is outside the plausible range"),
])
def test_implausible_inputs_are_computed_with_a_warning(kwargs, fragment):
    result = fruitimpact.simulate(**kwargs)
    assert any(fragment in w for w in result.warnings), result.warnings
    assert any("a plain number is read in" in w for w in result.warnings)
    assert result.to_dict()["warnings"] == list(result.warnings)


def test_leaving_hertz_range_is_a_warning():
    # 300 m/s: δ_max = 154 mm on a 65 mm fruit and a contact radius larger than the fruit
    result = fruitimpact.simulate(velocity=300)
    c = result.characteristics
    assert c.contact_radius > 0.0325
    assert any("leaves Hertz's range" in w for w in result.warnings)
    # the default apple stays inside: no warning at all
    assert fruitimpact.simulate().warnings == ()


def test_warnings_are_one_line_each_on_stderr(cli):
    status, out, err = cli.run("simulate", "--mass", "180", "--json")
    assert status == 0
    lines = err.splitlines()
    assert lines and all(line.startswith("fruitimpact simulate: warning: ") for line in lines)
    assert any("mass = 180 kg" in line for line in lines)
    import json

    assert json.loads(out)["warnings"]


def test_batch_rows_carry_their_warnings():
    result = evaluate({"mass": [0.1, 180.0]})
    assert result.loc[0, "warnings"] == ""
    assert "mass is outside the plausible range" in result.loc[1, "warnings"]
    assert list(result["status"]) == ["ok", "ok"]


def test_a_number_or_nan_in_a_text_column_refuses_its_row_not_the_table():
    """A text column holding a number or a NaN (pandas' missing cell of a string column) was refused on its row by
    the registry check, then raised TypeError while the output's categories were built (found by a fuzz of
    fi.evaluate): a batch must never die on one bad row.  The row is invalid, named with what it holds; the others
    are computed."""
    import fruitimpact as fi

    for column, cell in (("fruit", 1.5), ("fruit", float("nan")), ("surface", float("nan"))):
        df = fi.evaluate({"mass": [0.1, 0.2], column: ["apple" if column == "fruit" else "steel", cell]})
        assert df["status"].tolist() == ["ok", "invalid"], column
        assert df["message"][1].startswith(f"{column} must be one of") and df["message"][1].endswith(f"got {cell}")
