"""The founding paper's Table 1 and worked example, reproduced (published table
as the reference).  Tolerances per column follow the printed resolution:
δ_max in 1e-5 m, T and t_c in whole 1e-4 s steps, F_max in 0.01 N (the issue
allows 1 %: the printed forces carry ±0.5 % scatter, docs/paper.md)."""

import pytest

from fruitimpact.reference.paper import load_table1, paper_report


@pytest.fixture(scope="module")
def report():
    return paper_report()


def test_table_as_printed():
    table = load_table1()
    assert len(table) == 9
    assert table[0]["F_max_hc"] == 67.89 and table[8]["C_chen"] == 1.499


def test_deflection_and_duration_reproduced_exactly(report):
    # δ_max rounded to the printed 1e-5 m and T as the last grid time with δ > 0:
    # all 18 entries equal the printed integers.
    for entry in report["table1"]:
        assert round(entry["paper_method"]["delta_max"]) == entry["printed"]["delta_max"], entry["case"]
        assert round(entry["paper_method"]["T"]) == entry["printed"]["T"], entry["case"]


def test_peak_force_within_one_percent_except_the_misprint(report):
    for entry in report["table1"]:
        deviation = abs(entry["deviation"]["F_max_percent"])
        if (entry["case"], entry["law"]) == (6, "chen"):
            # printed 44.28 N where every method gives 47.23 N: a misprint (explained)
            assert entry["paper_method"]["F_max"] == pytest.approx(47.23, abs=0.01)
            assert any("misprint" in note for note in entry["notes"])
        else:
            assert deviation < 1.0, (entry["case"], entry["law"], deviation)


def test_time_to_peak_within_the_scatter_and_every_mismatch_explained(report):
    for entry in report["table1"]:
        # printed t_c lies within 1.3 steps of the exact t_c in every entry
        assert abs(entry["printed"]["t_c"] - entry["accurate"]["t_c"]) < 1.3
        if not all(entry["reproduced"].values()):
            assert entry["notes"], (entry["case"], entry["law"])



def test_firmness_c_is_truncated_ratio_of_printed_values(report):
    for entry in report["table1"]:
        assert entry["C_from_printed"] == pytest.approx(entry["printed"]["C"], abs=1e-9)


def test_worked_example_follows_from_printed_coefficients_at_0_8_m_per_s(report):
    we = report["worked_example"]
    run = we["runs"]["printed eq 26 coefficients at V_i = 0.8 m/s"]["paper_method"]
    assert run["F_max"] == pytest.approx(50.96, rel=1e-3)
    assert run["t_c"] == pytest.approx(2.4e-3, abs=1e-9)
    assert run["T_first_nonpositive"] == pytest.approx(6.3e-3, abs=1e-9)
    stated = we["runs"]["as stated: V_i = 1 m/s, λ = 1.5 α k_c (eq 5)"]["accurate"]
    assert stated["F_max"] > 65.0  # the stated inputs cannot give 51 N
    assert we["checks"]["damping_stated_formula"] == pytest.approx(1.5 * 0.423 * 0.835e6, rel=1e-12)


def test_paper_calibrations_miss_the_requested_restitution(report):
    # first-order calibrations: for k = 0.5..0.64 they return e 0.09..0.23 too high;
    # the exact calibration hits k (to rounding)
    for entry in report["table1"]:
        r = entry["restitution"]
        assert 0.09 < r["paper_calibration"] - r["target"] < 0.24
        assert r["exact_calibration"] == pytest.approx(r["target"], rel=1e-12)
