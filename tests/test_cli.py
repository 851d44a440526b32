"""The command-line contract of ``fruitimpact simulate``.

Most tests call ``fruitimpact.cli.main([...])`` in-process (fast); a few run the
installed console script in a subprocess to prove the real entry point: exit
status, one line on stderr, no traceback.

The physics checks recompute each number independently of the package (paper
eq 9 for k_c, energy balance, the undamped Hertz closed forms with
``scipy.special.beta``) instead of calling the package's own helpers.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import beta


G = 9.80665  # standard gravity, m/s^2
PREFIX = "fruitimpact simulate: error: "

#: Keys the JSON object must hold, each a finite number.
CHARACTERISTIC_KEYS = (
    "peak_force", "time_to_peak", "contact_duration", "max_deflection", "exit_velocity",
    "restitution", "absorbed_energy", "firmness_c", "firmness_c_star", "max_pressure",
    "contact_radius", "stiffness", "damping",
)
#: The paper's Jonathan apple, the CLI's defaults.
DEFAULT_INPUTS = dict(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37, velocity=1.0)


# --------------------------------------------------------------------------- helpers
def characteristics(result: dict) -> dict:
    return {k: result[k] for k in CHARACTERISTIC_KEYS}


# --------------------------------------------------------------------------- JSON contract
def test_json_has_every_characteristic_as_a_finite_number(cli):
    result = cli.json("simulate")
    for key in CHARACTERISTIC_KEYS:
        assert key in result, key
        value = result[key]
        assert isinstance(value, (int, float)) and not isinstance(value, bool), (key, value)
        assert math.isfinite(value), (key, value)
    for key in ("peak_force", "time_to_peak", "contact_duration", "max_deflection", "exit_velocity",
                "absorbed_energy", "firmness_c", "firmness_c_star", "max_pressure", "contact_radius",
                "stiffness", "damping"):
        assert result[key] > 0, key
    assert 0 < result["time_to_peak"] < result["contact_duration"]


def test_json_includes_the_inputs(cli):
    result = cli.json("simulate")
    for key, value in DEFAULT_INPUTS.items():
        assert result[key] == pytest.approx(value, rel=1e-15), key
    assert result["model"] == "hunt-crossley"
    assert result["calibration"] == "exact"
    assert result["method"] == "accurate"
    assert result["target_restitution"] == pytest.approx(0.577, rel=1e-15)
    assert result["success"] is True


def test_json_is_one_strict_json_object(cli):
    status, out, err = cli.run("simulate", "--json")
    assert status == 0 and err == ""
    # strict JSON: no NaN/Infinity tokens
    parsed = json.loads(out, parse_constant=lambda token: pytest.fail(f"non-strict JSON token {token}"))
    assert isinstance(parsed, dict)


# --------------------------------------------------------------------------- units
@pytest.mark.parametrize("with_units, si", [
    (["--mass", "115g", "--diameter", "65mm", "--modulus", "3MPa", "--velocity", "1m/s", "--step", "10ms"],
     ["--mass", "0.115", "--diameter", "0.065", "--modulus", "3e6", "--velocity", "1", "--step", "0.01"]),
    (["--mass", "180 g", "--diameter", "7.5cm", "--modulus", "2500kPa", "--poisson", "35%",
      "--drop-height", "30cm"],
     ["--mass", "0.18", "--diameter", "0.075", "--modulus", "2.5e6", "--poisson", "0.35",
      "--drop-height", "0.3"]),
    (["--stiffness", "1.2MN/m^1.5", "--velocity", "150cm/s", "--alpha", "0.2s/m"],
     ["--stiffness", "1.2e6", "--velocity", "1.5", "--alpha", "0.2"]),
    (["--method", "rk4", "--step", "0.1ms", "--velocity", "3.6km/h"],
     ["--method", "rk4", "--step", "1e-4", "--velocity", "1"]),
])
def test_units_give_the_same_result_as_si_numbers(cli, with_units, si):
    a = cli.json("simulate", *with_units)
    b = cli.json("simulate", *si)
    assert a.keys() == b.keys()
    for key, value in a.items():
        if isinstance(value, float):
            assert value == pytest.approx(b[key], rel=1e-12), key
        elif key != "inputs":
            assert value == b[key], key
    assert a["inputs"]["step"] == pytest.approx(b["inputs"]["step"], rel=1e-12)


def test_step_with_unit_is_recorded_in_si(cli):
    result = cli.json("simulate", "--step", "10ms")
    assert result["inputs"]["step"] == pytest.approx(0.01, rel=1e-15)
    result = cli.json("simulate", "--method", "rk4", "--step", "50us")
    assert result["step"] == pytest.approx(5e-5, rel=1e-12)


# --------------------------------------------------------------------------- velocity, alpha, stiffness
def test_drop_height_gives_free_fall_velocity(cli):
    result = cli.json("simulate", "--drop-height", "30cm")
    assert result["velocity"] == pytest.approx(math.sqrt(2 * G * 0.3), rel=1e-15)
    assert result["drop_height"] == pytest.approx(0.3, rel=1e-15)
    # the restitution still applies at that velocity
    assert result["restitution"] == pytest.approx(0.577, abs=1e-8)
    assert result["exit_velocity"] == pytest.approx(0.577 * math.sqrt(2 * G * 0.3), rel=1e-8)


def test_alpha_zero_is_elastic(cli):
    """α = 0 is λ = 0 (eq 5): the elastic Hertz impact.  Any α ≥ 0: test_damping_inputs.py."""
    result = cli.json("simulate", "--alpha", "0")
    assert result["target_restitution"] is None
    assert result["restitution"] == pytest.approx(1.0, abs=1e-12)
    assert result["damping"] == 0.0


def test_alpha_with_paper_calibration_is_hunt_crossley_eq6(cli):
    """Paper calibration of hunt-crossley: λ = (3/2) α k_c (eqs 5, 6, 11)."""
    result = cli.json("simulate", "--alpha", "0.3", "--velocity", "1.2", "--calibration", "paper")
    assert result["damping_factor"] == pytest.approx(1.5 * 0.3, rel=1e-12)
    assert result["damping"] == pytest.approx(1.5 * 0.3 * result["stiffness"], rel=1e-12)


def test_stiffness_overrides_modulus_and_poisson(cli):
    direct = cli.json("simulate", "--stiffness", "1.2e6")
    overridden = cli.json("simulate", "--stiffness", "1.2e6", "--modulus", "50MPa", "--poisson", "0.1")
    assert direct["stiffness"] == 1.2e6
    assert overridden["stiffness"] == 1.2e6
    assert characteristics(direct) == characteristics(overridden)
    hertz = cli.json("simulate")
    assert hertz["stiffness"] != pytest.approx(1.2e6, rel=1e-3)
    assert hertz["peak_force"] != pytest.approx(direct["peak_force"], rel=1e-6)


# --------------------------------------------------------------------------- physics consistency
FRUITS = [
    [],  # the Jonathan apple
    ["--mass", "0.2", "--diameter", "0.08", "--modulus", "5e6", "--poisson", "0.3", "--velocity", "2",
     "--restitution", "0.4"],
    ["--mass", "0.05", "--diameter", "0.03", "--modulus", "1.5e6", "--poisson", "0.45", "--drop-height",
     "0.1", "--restitution", "0.8", "--model", "chen"],
    ["--model", "chen", "--calibration", "paper", "--restitution", "0.7"],
    ["--method", "rk4", "--restitution", "0.5"],
]


@pytest.mark.parametrize("argv", FRUITS, ids=["jonathan", "big", "small-chen", "chen-paper", "rk4"])
def test_physics_consistency(cli, argv):
    r = cli.json("simulate", *argv)
    m, v, e = r["mass"], r["velocity"], r["restitution"]
    # λ = c·k_c
    assert r["damping"] == pytest.approx(r["stiffness"] * r["damping_factor"], rel=1e-12)
    # paper eq 9: k_c = (4/3)/sqrt(2) · E/(1-ν²) · sqrt(d)  (0.943 in the paper)
    k_c = (4.0 / 3.0) / math.sqrt(2.0) * r["modulus"] / (1.0 - r["poisson"] ** 2) * math.sqrt(r["diameter"])
    assert r["stiffness"] == pytest.approx(k_c, rel=1e-12)
    # energy balance: absorbed = ½ m v² (1 - e²)
    assert r["absorbed_energy"] == pytest.approx(0.5 * m * v ** 2 * (1.0 - e ** 2), rel=1e-9)
    assert r["exit_velocity"] == pytest.approx(e * v, rel=1e-9)
    # firmness (eqs 1, 2, 28)
    assert r["firmness_c"] == pytest.approx(r["peak_force"] / r["time_to_peak"], rel=1e-12)
    assert r["firmness_c_star"] == pytest.approx(r["peak_force"] / r["time_to_peak"] ** 2, rel=1e-12)
    # Hertz contact radius a = sqrt(R δ_max), R = d/2
    assert r["contact_radius"] == pytest.approx(math.sqrt(r["diameter"] / 2 * r["max_deflection"]), rel=1e-9)


@pytest.mark.parametrize("model", ["hunt-crossley", "chen"])
@pytest.mark.parametrize("k", [0.2, 0.577, 0.9, 1.0])
@pytest.mark.parametrize("velocity", ["0.5", "3"])
def test_exact_calibration_hits_requested_restitution(cli, model, k, velocity):
    r = cli.json("simulate", "--model", model, "--calibration", "exact", "--restitution", k, "--velocity", velocity)
    assert r["restitution"] == pytest.approx(k, abs=1e-8)
    assert r["exit_velocity"] == pytest.approx(k * float(velocity), rel=1e-8)


def test_paper_calibration_differs_from_exact(cli):
    """Sanity check that --calibration is honoured: the published first-order laws miss k = 0.577."""
    for model in ("hunt-crossley", "chen"):
        paper = cli.json("simulate", "--model", model, "--calibration", "paper")
        assert paper["calibration"] == "paper"
        assert abs(paper["restitution"] - 0.577) > 0.01


HERTZ_DURATION_FACTOR = 0.8 * beta(0.5, 0.4)  # (4/5)·B(1/2, 2/5) = 2.9432752...


def test_hertz_duration_constant():
    assert HERTZ_DURATION_FACTOR == pytest.approx(2.9432752, abs=5e-8)


@pytest.mark.parametrize("argv", [
    [],
    ["--velocity", "3", "--mass", "0.3", "--stiffness", "2e6"],
    ["--drop-height", "5cm", "--restitution", "0.3"],  # restitution is ignored by hertz
])
def test_hertz_closed_forms(cli, argv):
    r = cli.json("simulate", "--model", "hertz", *argv)
    m, v, k_c = r["mass"], r["velocity"], r["stiffness"]
    assert r["restitution"] == pytest.approx(1.0, abs=1e-12)
    assert r["damping"] == 0.0
    delta_max = (5.0 * m * v ** 2 / (4.0 * k_c)) ** 0.4
    assert r["max_deflection"] == pytest.approx(delta_max, rel=1e-9)
    assert r["contact_duration"] == pytest.approx(HERTZ_DURATION_FACTOR * delta_max / v, rel=1e-9)
    # symmetric pulse: peak force at δ_max, at half the contact, F = k_c δ_max^1.5
    assert r["time_to_peak"] == pytest.approx(r["contact_duration"] / 2, rel=1e-9)
    assert r["peak_force"] == pytest.approx(k_c * delta_max ** 1.5, rel=1e-9)
    assert r["absorbed_energy"] == pytest.approx(0.0, abs=1e-12 * m * v ** 2)


# --------------------------------------------------------------------------- CSV
def _read_csv(path: Path, min_rows: int = 100):
    lines = path.read_text().splitlines()
    assert lines[0] == "time_s,deflection_m,rate_m_per_s,force_N"
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert data.ndim == 2 and data.shape[1] == 4 and data.shape[0] > min_rows
    assert np.all(np.isfinite(data))
    return data.T


def test_csv_curves_match_characteristics(cli, tmp_path):
    """Accurate solver: the CSV samples F(t) on a uniform grid over [0, T].

    Tolerance: the sampled maximum cannot exceed F_max (beyond the 12
    significant digits the CSV is written with) and falls short of it by at most
    ½·|F''|·(h/2)², h the sample spacing, because the grid point nearest to
    t_c lies within h/2 of it and F'(t_c) = 0.  |F''| is estimated from second
    differences of the samples near the peak (with a factor 2 of safety); for
    the 1001-point default the bound is ~2e-5 relative (the actual shortfall
    is ~1e-8).
    """
    path = tmp_path / "curves.csv"
    r = cli.json("simulate", "--csv", path)
    t, deflection, rate, force = _read_csv(path)
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert t[-1] == pytest.approx(r["contact_duration"], rel=1e-10)
    h = float(np.max(np.diff(t)))
    i = int(np.argmax(force))
    curvature = np.abs(np.diff(force[max(i - 5, 0): i + 6], 2)).max() / h ** 2
    shortfall = 2 * 0.5 * curvature * (h / 2) ** 2
    assert force[i] <= r["peak_force"] * (1 + 1e-11)
    assert force[i] >= r["peak_force"] - shortfall
    assert abs(force[i] - r["peak_force"]) < 1e-4 * r["peak_force"]
    assert abs(t[i] - r["time_to_peak"]) <= h
    # deflection: same argument for δ_max; initial state δ = 0, δ̇ = v0
    assert deflection.max() <= r["max_deflection"] * (1 + 1e-11)
    assert deflection.max() == pytest.approx(r["max_deflection"], rel=1e-4)
    assert deflection[0] == 0.0
    assert rate[0] == pytest.approx(r["velocity"], rel=1e-12)
    assert rate[-1] == pytest.approx(-r["exit_velocity"], rel=1e-6)


def test_csv_rk4_peak_is_a_grid_sample(cli, tmp_path):
    """RK4 reads F_max off its own grid, so the CSV maximum equals it to the CSV's 12 digits."""
    path = tmp_path / "rk4.csv"
    r = cli.json("simulate", "--method", "rk4", "--step", "1e-4", "--csv", path)
    t, _, _, force = _read_csv(path, min_rows=50)  # 6.3 ms contact at 0.1 ms
    assert np.allclose(np.diff(t)[:-1], 1e-4, rtol=1e-9, atol=0)  # fixed step (last may be partial)
    assert force.max() == pytest.approx(r["peak_force"], rel=1e-11)
    assert t[int(np.argmax(force))] == pytest.approx(r["time_to_peak"], rel=1e-11)


def test_csv_in_table_mode_is_announced(cli, tmp_path):
    path = tmp_path / "c.csv"
    status, out, err = cli.run("simulate", "--csv", path)
    assert status == 0 and err == ""
    assert path.exists()
    assert f"curves written to {path}" in out


# --------------------------------------------------------------------------- plots
MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "svg": None, "pdf": b"%PDF"}


@pytest.mark.parametrize("ext", ["png", "svg", "pdf"])
def test_plot_writes_figure(cli, tmp_path, ext):
    pytest.importorskip("matplotlib")
    path = tmp_path / f"impact.{ext}"
    status, out, err = cli.run("simulate", "--plot", path)
    assert status == 0, err
    assert path.stat().st_size > 1000
    head = path.read_bytes()[:4096]
    if ext == "svg":
        assert b"<svg" in head
    else:
        assert head.startswith(MAGIC[ext])
    assert f"figure written to {path}" in out


# --------------------------------------------------------------------------- readable table
def test_table_lists_the_characteristics(cli):
    status, out, err = cli.run("simulate")
    assert status == 0 and err == ""
    r = cli.json("simulate")
    for label in ("peak force", "time to peak", "contact duration", "max deflection", "exit velocity",
                  "restitution", "absorbed energy", "firmness C ", "firmness C*", "contact pressure",
                  "contact radius"):
        assert label in out, label
    # values in the table's display units, 6 significant digits
    for value in (r["peak_force"], r["time_to_peak"] * 1e3, r["contact_duration"] * 1e3,
                  r["max_deflection"] * 1e3, r["absorbed_energy"] * 1e3, r["contact_radius"] * 1e3):
        assert f"{value:.6g}" in out, value
    # the inputs and the resolved law are shown too
    assert "115 g" in out and "65 mm" in out and "3 MPa" in out
    assert "hunt-crossley" in out and "exact" in out and "accurate" in out


# --------------------------------------------------------------------------- bad input
POSITIVE = {"--mass": "kg", "--diameter": "m", "--modulus": "Pa", "--stiffness": "N/m^1.5",
            "--velocity": "m/s", "--drop-height": "m", "--step": "s"}
NON_POSITIVE = ["0", "-1", "nan", "inf", "-inf"]

BAD_CASES = []  # (argv, options named, substrings stating the allowed range/units/choices)
for _option, _unit in POSITIVE.items():
    for _value in NON_POSITIVE:
        BAD_CASES.append(([_option, _value], [_option], ["> 0", _unit]))
BAD_CASES += [
    (["--mass=-1"], ["--mass"], ["> 0"]),
    (["--mass", "-115g"], ["--mass"], ["> 0"]),
    (["--drop-height", "-30cm"], ["--drop-height"], ["> 0"]),
    (["--step", "-1ms"], ["--step"], ["> 0"]),
    (["--step", "0", "--method", "rk4"], ["--step"], ["> 0"]),
    (["--modulus", "0MPa"], ["--modulus"], ["> 0"]),
    (["--mass", "1e-400"], ["--mass"], ["> 0"]),   # underflows to 0
    (["--mass", "1e400"], ["--mass"], ["> 0"]),    # overflows to inf
]
for _value in ["-1", "0.5", "-1.5", "0.7", "nan", "inf", "-inf", "50%"]:
    BAD_CASES.append((["--poisson", _value], ["--poisson"], ["(-1, 0.5)"]))
for _value in ["0", "-0.1", "1.0001", "nan", "inf", "2"]:
    BAD_CASES.append((["--restitution", _value], ["--restitution"], ["(0, 1]"]))
BAD_CASES += [
    (["--model", "foo"], ["--model"], ["hertz", "hunt-crossley", "chen"]),
    (["--model", "HERTZ"], ["--model"], ["hertz", "hunt-crossley", "chen"]),
    (["--calibration", "approx"], ["--calibration"], ["paper", "exact"]),
    (["--method", "euler"], ["--method"], ["accurate", "rk4"]),
    (["--mass", "5furlongs"], ["--mass"], ["units allowed: kg, g, mg"]),
    (["--mass", "3MPa"], ["--mass"], ["units allowed: kg, g, mg"]),
    (["--mass", "abc"], ["--mass"], ["units allowed: kg, g, mg"]),
    (["--mass", ""], ["--mass"], ["units allowed: kg, g, mg"]),
    (["--diameter", "5furlongs"], ["--diameter"], ["units allowed: m, cm, mm"]),
    (["--diameter", "65kg"], ["--diameter"], ["units allowed: m, cm, mm"]),
    (["--modulus", "3MPascal"], ["--modulus"], ["units allowed: Pa, kPa, MPa, GPa"]),
    (["--velocity", "1km/s"], ["--velocity"], ["units allowed: m/s, cm/s, mm/s, km/h"]),
    (["--velocity", "fast"], ["--velocity"], ["units allowed: m/s"]),
    (["--drop-height", "1ft"], ["--drop-height"], ["units allowed: m, cm, mm"]),
    (["--stiffness", "1e6N/m"], ["--stiffness"], ["units allowed: N/m^1.5"]),
    (["--step", "1min"], ["--step"], ["units allowed: s, ms, us"]),
    (["--step", "abc"], ["--step"], ["units allowed: s, ms, us"]),
    (["--poisson", "0.3m"], ["--poisson"], ["units allowed: %"]),
    (["--restitution", "high"], ["--restitution"], ["units allowed: %"]),
    (["--alpha", "0.1m/s"], ["--alpha"], ["units allowed: s/m"]),
    # conflicts: both options named
    (["--velocity", "1", "--drop-height", "30cm"], ["--velocity", "--drop-height"], ["not both"]),
    (["--drop-height", "0.3", "--velocity", "2m/s"], ["--velocity", "--drop-height"], ["not both"]),
    (["--restitution", "0.5", "--alpha", "0.1"], ["--restitution", "--alpha"], ["not both"]),
    # α is any number >= 0 (eq 5); only negative numbers and NaN are refused
    (["--alpha", "-0.1"], ["--alpha"], [">= 0 s/m"]),
    (["--alpha", "nan"], ["--alpha"], [">= 0 s/m"]),
]


def _case_id(case):
    return " ".join(case[0]) or "''"


@pytest.mark.parametrize("argv, options, allowed", BAD_CASES, ids=[_case_id(c) for c in BAD_CASES])
def test_bad_input_is_one_line_exit_2(cli, argv, options, allowed):
    line = cli.error("simulate", *argv)
    assert line.startswith(PREFIX), line
    if len(options) == 1:
        assert f"argument {options[0]}: " in line, line
    else:
        for option in options:
            assert option in line, (option, line)
    for text in allowed:
        assert text in line, (text, line)


@pytest.mark.parametrize("argv", [["--mass"], ["--bogus", "1"], ["--json=yes"]])
def test_argparse_errors_are_one_line_exit_2(cli, argv):
    status, out, err = cli.run("simulate", *argv)
    assert status == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "error:" in err


# --------------------------------------------------------------------------- the real console script
def test_script_default_run(script):
    proc = script("simulate", )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    assert "peak force" in proc.stdout and "contact duration" in proc.stdout


def test_script_json_matches_in_process(cli, script):
    proc = script("simulate", "--json", "--mass", "115g")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    assert json.loads(proc.stdout) == cli.json("simulate")


@pytest.mark.parametrize("argv, option", [
    (["--mass", "-1"], "--mass"),
    (["--model", "foo"], "--model"),
    (["--velocity", "1", "--drop-height", "30cm"], "--drop-height"),
    (["--diameter", "5furlongs"], "--diameter"),
])
def test_script_bad_input(argv, option, script):
    proc = script("simulate", *argv)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(PREFIX) and option in lines[0]


# --------------------------------------------------------------------------- coarse RK4 step
def test_rk4_step_longer_than_contact_is_refused(cli):
    # a step that leaves fewer than 20 steps per contact is bad input, not a silent success
    status, out, err = cli.run("simulate", "--method", "rk4", "--step", "10ms", "--json")
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and "--step" in err and "at least 20 steps" in err


def test_plot_overlays_other_models(cli, tmp_path):
    path = tmp_path / "overlay.png"
    status, out, err = cli.run("simulate", "--plot", str(path), "--overlay", "chen:paper", "--overlay", "hunt-crossley:paper:rk4")
    assert status == 0 and path.stat().st_size > 10_000
    status, out, err = cli.run("simulate", "--plot", str(path), "--overlay", "chen:bogus")
    assert status == 2 and "--overlay" in err and err.count("\n") == 1


# --------------------------------------------------------------------------- Ctrl-C
def test_ctrl_c_during_start_up_is_one_line(cli, monkeypatch):
    """A KeyboardInterrupt while the parser is built (imports, registries) is one line, exit 130."""
    import fruitimpact.cli as package

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(package, "build_parser", interrupted)
    status, out, err = cli.run("simulate")
    assert status == 130 and out == ""
    assert err == "fruitimpact simulate: interrupted\n"


def _console_with_parser(body: str, interrupted: bool):
    """Run the console script's ``main`` (``fruitimpact simulate``) in a fresh interpreter whose parser builder is
    ``body`` (the lines of a function, indented by 4; ``INTERRUPT`` there is replaced by a real SIGINT to the
    process, given time to arrive, or by nothing).  Returns the finished process (its SIGINT at the default action:
    ``conftest.sigint_default``)."""
    import subprocess
    import sys
    import textwrap

    from conftest import sigint_default

    interrupt = "os.kill(os.getpid(), signal.SIGINT); time.sleep(5)" if interrupted else "pass"
    script = "\n".join(["import atexit, os, signal, sys, time", "import fruitimpact.cli as cli",
                         "def build_parser():", textwrap.indent(body.replace("INTERRUPT", interrupt), "    "),
                         "cli.build_parser = build_parser", 'sys.argv = ["fruitimpact", "simulate"]',
                         "sys.exit(cli.main())"])
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                          preexec_fn=sigint_default)


def test_a_ctrl_c_that_c_code_turned_into_another_error_is_still_an_interrupt():
    """A Ctrl-C inside an import run by C code can come back as another error: NumPy's C extension imports
    datetime through PyCapsule_Import, which replaces the KeyboardInterrupt by an ImportError (seen once in a
    fresh-clone CI: a traceback instead of "interrupted").  Mimicked in the console script: a real SIGINT while
    the parser is built, answered by an ImportError raised outside the handler (no exception chain left, as the
    C code leaves none): one line "interrupted", exit 130, no traceback.  The same ImportError without a Ctrl-C
    is a real failure and keeps its traceback."""
    body = """try:
    INTERRUPT
except KeyboardInterrupt:
    pass
raise ImportError('PyCapsule_Import could not import module "datetime"')"""
    done = _console_with_parser(body, interrupted=True)
    assert (done.returncode, done.stdout, done.stderr) == (130, "", "fruitimpact simulate: interrupted\n")
    done = _console_with_parser(body, interrupted=False)
    assert done.returncode == 1 and "Traceback" in done.stderr and "PyCapsule_Import" in done.stderr


def test_what_fails_in_finalizers_after_an_interrupt_is_not_a_traceback():
    """A Ctrl-C inside llvmlite's start-up can leave a half-built object whose __del__ raises when the process ends
    (seen once on a fresh clone: "Exception ignored in ObjectRef.__del__ … AttributeError" after "interrupted").
    Mimicked: an object whose __del__ raises, alive until the end, and a real SIGINT: one line, exit 130.  The
    same object at the end of a command that was not interrupted is still reported (Python's own report)."""
    body = """class HalfBuilt:
    def __del__(self):
        raise AttributeError("'_FunctionsIterator' object has no attribute '_as_parameter_'")
sys.modules["__main__"].kept = HalfBuilt()
atexit.register(lambda: delattr(sys.modules["__main__"], "kept"))  # its __del__ as the process ends
INTERRUPT
raise SystemExit(0)"""
    done = _console_with_parser(body, interrupted=True)
    assert (done.returncode, done.stdout, done.stderr) == (130, "", "fruitimpact simulate: interrupted\n")
    done = _console_with_parser(body, interrupted=False)
    assert done.returncode == 0 and "Exception ignored" in done.stderr and "AttributeError" in done.stderr


def test_a_ctrl_c_inside_the_import_system_is_delivered_after_it():
    """A Ctrl-C that lands in the import system's own frames (its module-lock bookkeeping) is not raised there:
    raised in ``_lock_unlock_module`` it escaped as a traceback printed before the one line (a fresh-clone CI run,
    test below).  It is delivered again 5 ms later by a one-shot SIGALRM; anywhere else it is raised at once."""
    import signal
    import sys
    import types

    from fruitimpact import cli

    if not hasattr(signal, "setitimer"):
        pytest.skip("no one-shot timer on this platform: the interrupt is raised where it lands")
    frame = types.SimpleNamespace(f_code=types.SimpleNamespace(co_filename="<frozen importlib._bootstrap>"))
    previous = signal.getsignal(signal.SIGALRM)
    try:
        assert cli._deliver_interrupt(signal.SIGINT, frame) is None
        assert signal.getsignal(signal.SIGALRM) is cli._deliver_interrupt
        assert 0 < signal.getitimer(signal.ITIMER_REAL)[0] <= 0.005
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    with pytest.raises(KeyboardInterrupt):
        cli._deliver_interrupt(signal.SIGINT, sys._getframe())


def _before_the_program(err: str) -> bool:
    """Whether ``err`` is CPython's own report of an interrupt during its start-up, before the program's first line:
    "Fatal Python error: init_import_site" (Python/pylifecycle.c) or "Could not import runpy module"
    (Modules/main.c)."""
    return err.startswith(("Fatal Python error: init_import_site", "Could not import runpy module"))


def test_sigint_during_numba_start_up_exits_130_not_by_the_signal():
    """24 real SIGINTs 0.55–0.90 s into `fruitimpact simulate` (numba's start-up and cache loading on this
    machine): never exit status -2, the process killed by the signal after it had printed "interrupted" (4 of 72
    before cli._forget_unhandled_interrupt; at that rate 24 tries catch it 3 times in 4).  The whole contract
    (130 or 0, one line, no traceback) is test_sigint_to_the_console_script_never_shows_a_traceback's; here one
    run of 24 in a fresh-clone CI once ended by SIGSEGV (-11) during start-up, which 96 more tries (warm and cold
    numba cache, with a second loop beside it) did not reproduce: an open defect, not this test's subject."""
    import signal
    import subprocess
    import time

    from conftest import console_script, sigint_default

    statuses, before_start = [], 0
    for k in range(24):
        process = subprocess.Popen([console_script(), "simulate", "--model", "tsuji-clamped"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=sigint_default)
        time.sleep(0.55 + 0.35 * k / 23)
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
        if _before_the_program(err):
            # on a machine loaded past its cores the signal can land while the interpreter itself still starts
            # (its site module, runpy), before any line of the program runs: Python's own exit, no program can
            # handle it (seen with two test suites and a benchmark on two cores); not what this test is about
            before_start += 1
            continue
        assert "Traceback" not in err, err
        statuses.append(process.returncode)
    assert -signal.SIGINT not in statuses, statuses
    assert before_start <= 4, f"{before_start} of 24 signals landed before the interpreter had started"


@pytest.mark.parametrize("delay", [0.15, 0.3, 0.6])
def test_sigint_to_the_console_script_never_shows_a_traceback(delay):
    """A real SIGINT at several moments of `fruitimpact simulate` (imports, numba start-up, the impact)."""
    import signal
    import subprocess
    import time

    from conftest import console_script, sigint_default

    process = subprocess.Popen([console_script(), "simulate", "--model", "tsuji-clamped"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, preexec_fn=sigint_default)
    time.sleep(delay)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    if _before_the_program(err):  # the interpreter itself was still starting
        pytest.skip("the signal landed before the interpreter ran a line of the program (a machine loaded past its "
                    "cores): Python's own exit")
    assert "Traceback" not in err, err
    assert process.returncode in (0, 130), (process.returncode, err)
    if process.returncode == 130:
        assert err.strip().endswith("interrupted") and len(err.strip().splitlines()) == 1


def test_an_interrupt_swallowed_by_a_c_callback_is_delivered_again(monkeypatch):
    """Python reports a KeyboardInterrupt raised inside a ctypes callback (numba's LLVM object cache, seen on
    CI when Ctrl-C hit the first compilation) as "Exception ignored" and goes on; the console script's hook
    must deliver it again in Python code, so that the user's Ctrl-C is obeyed with its one line."""
    import signal
    import sys
    import time
    import types

    import fruitimpact.cli as package

    saved_hook, saved_alarm = sys.unraisablehook, signal.getsignal(signal.SIGALRM)
    monkeypatch.setattr(package, "_SWALLOWED", [])  # this process's record stays clean for later tests
    try:
        package._redeliver_interrupts_from_callbacks()
        sys.unraisablehook(types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(),
                                                 exc_traceback=None, err_msg=None, object=None))
        with pytest.raises(KeyboardInterrupt):
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline:  # the timer is 5 ms; 2 s only bounds a failure
                time.sleep(0.001)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        sys.unraisablehook = saved_hook
        signal.signal(signal.SIGALRM, saved_alarm)


@pytest.mark.parametrize("argv", [
    ["line", "examples/line.csv", "-n", "2000000", "--fruit", "apple"],
    ["population", "-n", "3e7", "--fruit", "apple", "--yield-pressure", "0.3MPa", "--surface", "steel",
     "-o", "{tmp}/members.parquet"],
])
def test_ctrl_c_stops_a_long_command_within_a_second(argv, tmp_path):
    """Issue 15 item 5: a real SIGINT to a long command (2 million fruit through a line: ~10 minutes of
    damped contact; 30 million plastic members) stops it: one line "interrupted", exit 130, no output
    written as if complete.  The compiled kernels get at most KERNEL_SLICE rows per call, so Python answers
    the signal between two slices (< 1 s on this machine; 5 s here leaves room for a loaded CI runner)."""
    import signal
    import subprocess
    import time
    from pathlib import Path

    from conftest import console_script, sigint_default

    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    process = subprocess.Popen([console_script(), *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, cwd=Path(__file__).resolve().parents[1], preexec_fn=sigint_default)
    time.sleep(8.0)  # past start-up and numba's compilation (cold cache on CI), into the kernels
    assert process.poll() is None, process.communicate()
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    waited = time.monotonic() - sent
    assert process.returncode == 130, (process.returncode, err)
    assert "Traceback" not in err and err.splitlines()[-1].startswith(f"fruitimpact {argv[0]}: interrupted"), err
    assert waited < 5.0, f"stopped {waited:.1f} s after SIGINT"
    assert out == ""
    assert not (tmp_path / "members.parquet").exists()  # no output that looks complete


def test_kernels_in_slices_give_the_same_rows(monkeypatch):
    """Cutting the rows into KERNEL_SLICE slices (so Ctrl-C is answered) changes no result: rows are
    independent; checked on elastic, plastic and adaptive rows with a slice of 7 rows."""
    import numpy as np

    from fruitimpact.impact import evaluation as module

    table = {"drop_height": list(np.linspace(0.01, 0.5, 40)), "fruit": "apple",
             "yield_pressure": ["0.3MPa"] * 20 + [None] * 20,
             "surface": ["cardboard", "foam-pad"] * 20,  # a group of plastic rows partly on crushing board
             "model": ["hunt-crossley"] * 30 + ["tsuji"] * 10}
    whole = module.evaluate(table)
    monkeypatch.setattr(module, "KERNEL_SLICE", 7)
    sliced = module.evaluate(table)
    assert whole["status"].tolist() == sliced["status"].tolist()
    for name in ("peak_force", "contact_duration", "restitution", "max_deflection"):
        np.testing.assert_array_equal(whole[name].to_numpy(), sliced[name].to_numpy(), err_msg=name)


def test_the_default_table_choice_is_the_whole_groups(monkeypatch):
    """Above TABLE_ROWS power-law rows the engine's table is used by default; the slices must not change that
    choice (review of issue 15: a slice alone never reached it, 3x slower, and numbers depended on the cut)."""
    import numpy as np

    from fruitimpact.impact import evaluation as module

    heights = np.linspace(0.01, 0.5, module.TABLE_ROWS + 5)
    monkeypatch.setattr(module, "KERNEL_SLICE", 4096)
    default = module.evaluate({"drop_height": heights, "fruit": "apple"})
    table = module.evaluate({"drop_height": heights, "fruit": "apple"}, tabulated=True)
    np.testing.assert_array_equal(default["peak_force"].to_numpy(), table["peak_force"].to_numpy())


def test_a_failure_caused_by_a_swallowed_ctrl_c_is_answered_as_the_interrupt(monkeypatch, capsys):
    """Seen on CI with a cold numba cache: a Ctrl-C swallowed in numba's object-cache callback leaves the compiler
    without its object, and it raises "RuntimeError: no compiled object yet" before the interrupt can be
    delivered again.  That failure is the interrupt's: one line, exit 130, no traceback."""
    import signal
    import sys
    import types

    import fruitimpact.cli as package

    def compile_interrupted():
        sys.unraisablehook(types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(),
                                                 exc_traceback=None, err_msg=None, object="callback"))
        raise RuntimeError("no compiled object yet for <Library '_kernel'>")

    saved_hook, saved_alarm = sys.unraisablehook, signal.getsignal(signal.SIGALRM)
    monkeypatch.setattr(package, "build_parser", compile_interrupted)
    monkeypatch.setattr(package, "_SWALLOWED", [])
    monkeypatch.setattr(sys, "argv", ["fruitimpact", "line", "examples/line.csv"])
    try:
        status = package.main()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        sys.unraisablehook = saved_hook
        signal.signal(signal.SIGALRM, saved_alarm)
    out, err = capsys.readouterr()
    assert status == 130 and err == "fruitimpact line: interrupted\n" and out == ""


@pytest.mark.parametrize("argv", [["--help"], ["simulate", "--help"], ["simulate", "--mass", "-1"],
                                  ["drop", "--mass", "0"], ["simulate", "--plot", "figure.bogus"],
                                  ["population", "-n", "-1"], ["stream", "--rate", "0"],
                                  ["sweep", "--mass", "1,2", "--plot", "figure.bogus"], ["simulate", "--mas", "1"],
                                  ["fit-damage", "no-such-tests.csv"], ["analyze", "no-such-recording.csv"],
                                  ["sphere", "no-such-log.csv", "--criterion", "energy", "--bruise-energy", "0.1J"],
                                  ["population", "--mass", "0g"], ["sweep", "--restitution", "1.5"],
                                  [],  # no command: one line on stderr (it was the help on stdout, stderr empty)
                                  # found by an attack, each 0.7 s with numba before: options of models and paper
                                  ["models", "--targets", "0"], ["models", "--plot", "out.gif"],
                                  ["paper", "--figures", "/proc/x"],
                                  # a detector option the file's rate refuses (1.2 s with numba before)
                                  ["stream", "--rate", "20kHz", "--sort-by", "nosuch", "--thresholds", "1"]])
def test_help_and_usage_errors_of_the_console_script_load_neither_numba_nor_numpy(argv, tmp_path):
    """Issue 15 item 4: ``--help`` and a usage error answer at once (0.25 s), so they may not start numba (0.7 s)
    or NumPy (0.15 s).  The console script itself is run, as a subprocess: ``main()`` in process shares the
    test's already imported modules and would prove nothing.  Python's own import log (-X importtime, set by
    PYTHONPROFILEIMPORTTIME) lists every module the process imported; the timing is in benchmarks/interactive.py."""
    import os
    import subprocess

    from conftest import console_script

    env = {**os.environ, "PYTHONPROFILEIMPORTTIME": "1"}
    done = subprocess.run([console_script(), *argv], capture_output=True, text=True, cwd=tmp_path, env=env,
                          timeout=60)
    assert done.returncode == (0 if "--help" in argv else 2), done.stderr[-2000:]
    said = [line for line in done.stderr.splitlines() if not line.startswith("import time:")]
    assert "--help" in argv or (len(said) == 1 and ": error: " in said[0] and done.stdout == ""), said
    imported = {line.rsplit("|", 1)[-1].strip() for line in done.stderr.splitlines() if line.startswith("import time:")}
    assert "fruitimpact.cli" in imported  # the log is there: the check below can fail
    assert not {name for name in imported if name.split(".")[0] in ("numba", "numpy")}, argv



@pytest.mark.parametrize("argv, line", [
    (["population", "-n", "10", "--fruit", "pear", "--criterion", "shear"],
     "argument --failure-stress: failure_stress is not in the pear entry of the fruit library"),
    (["safe-height", "--fruit", "pear", "--criterion", "energy"],
     "argument --bruise-energy: bruise_energy must be given for the energy criterion"),
    (["population", "-n", "10", "--model", "tsuji", "--yield-pressure", "1MPa"],
     "argument --yield-pressure: plastic contact (--yield-pressure, --bioyield-force) and cushion layers are built "
     "on the power-law family"),
    (["line", "--fruit", "pear", "--criterion", "energy", "LINE"], "argument --bruise-energy: bruise_energy must be given"),
    # found by an attack (0.7-0.8 s each, numba loaded first)
    (["drop", "--drop-height", "30cm", "--surface", "fruit"], "argument --surface: a drop bounces on a fixed surface"),
    (["drop", "--drop-height", "30cm", "--step", "1s", "--method", "rk4"], "argument --step: step must be in (0, "),
    (["line", "LINE", "--alternatives", "granite"], "argument --alternatives: alternatives must be library surfaces"),
    (["sphere", "LOG", "--sphere-mass", "0g", "--sphere-diameter", "89mm", "--sphere-modulus", "40MPa",
      "--sphere-poisson", "0.45"], "argument --sphere-mass: sphere_mass must be a finite number >= 0.001"),
    (["sphere", "LOG", "--sphere", "is-1987", "--sphere-calibration", "missing.csv"],
     "argument --sphere-calibration: cannot read missing.csv"),
    (["analyze", "REC", "--lowpass", "20kHz"], "argument --lowpass: must be a number in (0, 500)"),
    # a refusal after the lot's constants are validated (they are no longer computed): 0.7 s before
    (["sweep", "--velocity", "0.5:1:3", "--step", "1e-5"], "argument -o/--output: give -o OUT and/or --plot FILE"),
    (["population", "--mass", "sample(missing.csv)"], "argument --mass: sample: no such file 'missing.csv'"),
    (["population", "--mass", "sample(fruit.csv:nosuch)"], "argument --mass: sample: 'fruit.csv' has no column 'nosuch'")])
def test_a_usage_error_found_by_validating_inputs_starts_no_numba(argv, line, tmp_path):
    """Issue 15 item 4: a refusal found by validating the inputs (a criterion whose input the fruit lacks, a law
    that cannot carry plastic contact, a drop onto a free partner, an rk4 step too coarse for the impact, an
    unknown alternative surface, a sphere's setting or calibration file) may load NumPy (0.1 s) but not the
    compiled engine (numba, 0.7 s): it loads only where a row is computed.  Each was a 0.7-1 s answer before; a
    population of identical refusals (``--model tsuji --yield-pressure``) was 10 invalid rows and exit 0."""
    assert not {name for name in _refusal_imports(argv, line, tmp_path) if name.split(".")[0] == "numba"}, argv


@pytest.mark.parametrize("argv, line", [
    # the rate read from a recording's first rows (Arrow's to_numpy imported pandas: 0.43 s)
    (["analyze", "REC", "--lowpass", "20kHz"], "argument --lowpass: must be a number in (0, 500)"),
    # a sample CSV read with the csv module: a text column, a ragged row (pandas read the file: 0.41 s)
    (["population", "--mass", "sample(fruit.csv:model)"], "argument --mass: sample: column 'model': cannot read"),
    (["population", "--mass", "sample(ragged.csv:mass)"], "argument --mass: sample: line 3 of 'ragged.csv' has 1"),
    # a step refused for every fruit of the lot (it ran every row invalid and exited 0)
    (["population", "-n", "100", "--method", "rk4", "--step", "1s"], "every one of the lot's 100 fruit"),
    # a step no fruit can take at the points of a sphere's log (0.9 s: the calibration's fit and the inversion)
    (["sphere", "LOG", "--sphere", "is-1987", "--sphere-calibration", "CAL", "--fruit", "apple", "--method", "rk4",
      "--step", "1s"], "argument --step: step must be at most 1/20 of the contact duration for rk4"),
    (["sphere", "LOG", "--sphere", "is-1987", "--sphere-calibration", "CAL", "--fruit", "apple", "--method", "rk4",
      "--step", "1s", "--no-spreads"], "argument --step: step must be at most 1/20 of the contact duration for rk4")])
def test_a_usage_error_about_a_file_or_a_lot_loads_neither_numba_nor_pandas(argv, line, tmp_path):
    """Issue 15 item 4 (≤ 0.25 s): pandas alone takes 0.3 s to import; these refusals need neither it nor numba."""
    imported = _refusal_imports(argv, line, tmp_path)
    assert not {name for name in imported if name.split(".")[0] in ("numba", "pandas")}, argv


def _refusal_imports(argv, line, tmp_path) -> set:
    """The modules the console script imported to refuse ``argv`` (LINE, LOG, CAL, REC, fruit.csv and ragged.csv
    stand for files made here) with one line holding ``line``, exit 2."""
    import os
    import shutil
    import subprocess
    from pathlib import Path

    from conftest import console_script

    examples = Path(__file__).parents[1] / "examples"
    shutil.copy(examples / "line.csv", tmp_path / "line.csv")
    shutil.copy(examples / "sphere-log.csv", tmp_path / "sphere-log.csv")
    shutil.copy(examples / "fruit.csv", tmp_path / "fruit.csv")
    (tmp_path / "ragged.csv").write_text("mass,velocity\n0.1,1\n0.12\n")
    (tmp_path / "rec.csv").write_text("time [s],force [N]\n" + "".join(f"{k / 1000:.3f},0.0\n" for k in range(100)))
    shutil.copy(examples / "sphere-calibration.csv", tmp_path / "sphere-calibration.csv")
    files = {"LINE": str(tmp_path / "line.csv"), "LOG": str(tmp_path / "sphere-log.csv"), "REC": str(tmp_path / "rec.csv"),
             "CAL": str(tmp_path / "sphere-calibration.csv")}
    argv = [files.get(a, a) for a in argv]
    env = {**os.environ, "PYTHONPROFILEIMPORTTIME": "1"}
    done = subprocess.run([console_script(), *argv], capture_output=True, text=True, cwd=tmp_path, env=env,
                          timeout=60)
    messages = [text for text in done.stderr.splitlines() if not text.startswith("import time:")]
    assert done.returncode == 2 and len(messages) == 1 and line in messages[0], done.stderr[-2000:]
    imported = {text.rsplit("|", 1)[-1].strip() for text in done.stderr.splitlines() if text.startswith("import time:")}
    assert "fruitimpact.cli" in imported  # the log is there: the check below can fail
    return imported


@pytest.mark.parametrize("argv, line", [
    (["serve", "--port", "²"], "argument --port: port must be an integer in [0, 65,535]; got '²'"),
    (["serve", "--port", "70000"], "argument --port: port must be an integer in [0, 65,535]; got '70000'"),
    (["synth", "--count", "³", "-o", "x.csv"], "argument --count: count must be an integer in [1, 100,000]; got '³'"),
    (["stream", "--rate", "1000", "--lanes", "²"], "argument --lanes: lanes must be an integer in [1, 256]; got '²'"),
    (["analyze", "x.csv", "--lanes", "0"], "argument --lanes: lanes must be an integer >= 1; got '0'")])
def test_integer_options_are_read_as_integers(argv, line, script, tmp_path):
    """A superscript is a digit to str.isdigit but not to int(): it gave a traceback (exit 1), now the option's
    one line (exit 2), like every other count (impact.validation.read_count)."""
    done = script(*argv, cwd=tmp_path)
    assert done.returncode == 2 and done.stderr.strip().endswith(line), done.stderr


# ------------------------------------------------------------------ simulate from the console, without numba
_INTERPRETED_CASES = [
    [], ["--drop-height", "30cm", "--fruit", "apple", "--surface", "steel", "--criterion", "shear"],
    ["--model", "lankarani-nikravesh", "--calibration", "paper", "--restitution", "0.3"],
    ["--model", "tsuji"], ["--model", "kelvin-voigt"], ["--criterion", "pressure", "--failure-stress", "0.3MPa"],
    ["--fruit", "apple", "--surface", "rubber-belt", "--yield-pressure", "0.32MPa", "--criterion", "shear"],
    ["--fruit", "apple", "--surface", "cardboard", "--drop-height", "30cm", "--criterion", "shear"],
    ["--surface", "fruit", "--fruit", "apple"], ["--restitution", "0.001"], ["--velocity", "1e-9"],
    ["--mass", "180kg"], ["--model", "kuwabara-kono"], ["--method", "rk4"],
]


@pytest.mark.parametrize("arguments", _INTERPRETED_CASES, ids=lambda a: " ".join(a) or "defaults")
def test_simulate_interpreted_prints_what_compiled_prints(tmp_path, arguments):
    """Issue 15 item 4: the console's `simulate` runs the engine's own functions interpreted, numba never started
    (cli.interpreted).  It must print what the compiled engine prints: the table byte for byte (6 significant
    digits), the JSON numbers to 1e-14 relative (the last bits of libm and of LLVM's code differ), the warnings
    once each, also where interpretation hands over to the compiled engine (Kuwabara–Kono: over its time budget)
    and with --plot/--csv, whose curves are computed before anything is printed."""
    import os
    import subprocess
    import sys

    def run(extra, compiled):
        environment = {**os.environ, "FRUITIMPACT_COMPILED": "1" if compiled else "0"}
        done = subprocess.run([sys.executable, "-m", "fruitimpact", "simulate", *arguments, *extra],
                              capture_output=True, text=True, env=environment, cwd=tmp_path)
        return done.returncode, done.stdout, done.stderr

    # curves too where they matter: the defaults, a hand-over to compiled, a case with warnings (each run with a
    # figure imports matplotlib: 1 s)
    drawn = arguments in ([], ["--model", "kuwabara-kono"], ["--mass", "180kg"])
    for extra in ([], ["--plot", "f.png", "--csv", "c.csv"]) if drawn else ([],):
        assert run(extra, False) == run(extra, True)
    code, text, _ = run(["--json"], False)
    compiled_code, compiled_text, _ = run(["--json"], True)
    assert code == compiled_code and code in (0, 1)
    interpreted, compiled = json.loads(text), json.loads(compiled_text)
    assert interpreted.keys() == compiled.keys()
    for key, value in interpreted.items():
        if isinstance(value, float) and isinstance(compiled[key], float):
            assert value == pytest.approx(compiled[key], rel=1e-14, abs=1e-300), key
        else:
            assert value == compiled[key], key


def test_simulate_from_the_console_starts_no_numba(tmp_path):
    """The interpreted path is the one taken: Python's import log of `python -m fruitimpact simulate` names no
    numba module (and FRUITIMPACT_COMPILED=1 brings numba back)."""
    import os
    import subprocess
    import sys

    def imported(compiled):
        environment = {**os.environ, "FRUITIMPACT_COMPILED": compiled}
        done = subprocess.run([sys.executable, "-X", "importtime", "-m", "fruitimpact", "simulate"],
                              capture_output=True, text=True, env=environment)
        assert done.returncode == 0, done.stderr
        return [line for line in done.stderr.splitlines() if "| numba" in line or "|   numba" in line
                or line.rstrip().endswith(" numba")]

    assert imported("0") == []
    assert imported("1")


@pytest.mark.parametrize("extra,option", [
    (["--map-fruit", "-1"], "--map-fruit"), (["--map-fruit", "1e9"], "--map-fruit"), (["--map-fruit", "abc"], "--map-fruit"),
    (["--map-seed", "-3"], "--map-seed"), (["--map-seed", "1.5"], "--map-seed"),
    (["--map-fruit", "0", "--no-spreads"], "--no-spreads"), (["--map-fruit", "0", "--map-seed", "4"], "--map-seed")])
def test_the_risk_maps_lot_options_are_refused_by_their_own_names(cli, extra, option):
    """The map's lot options answer bad values with one line naming the option (not the library's rows/seed),
    and options that would do nothing (a seed or --no-spreads for a map without a lot) are refused, not ignored."""
    status, out, err = cli.run("safe-height", "--fruit", "apple", "--criterion", "shear", "--map", "surface",
                               "--no-sensitivity", *extra)
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert err.startswith(f"fruitimpact safe-height: error: argument {option}:"), err


def test_the_risk_map_spans_its_axis_whatever_the_command_gives_for_it(cli):
    """--modulus (or a surface and its properties) given with the map of that axis is the safe height's; the map
    spans every column alike, modulus and stiffness, surface and surface modulus (they were treated apart)."""
    report = cli.json("safe-height", "--fruit", "apple", "--criterion", "shear", "--map", "surface", "--no-sensitivity",
                      "--surface-modulus", "1e9", "--map-fruit", "20")
    plain = cli.json("safe-height", "--fruit", "apple", "--criterion", "shear", "--map", "surface", "--no-sensitivity",
                     "--map-fruit", "20")
    assert report["risk_map"]["safe_height"] == plain["risk_map"]["safe_height"]
    assert report["risk_map"]["incidence_heights"] == plain["risk_map"]["incidence_heights"]
    assert report["risk_map"]["lot"]["rows"] == 20


def test_no_output_is_written_over_a_file_the_command_reads(cli, tmp_path):
    """A review wrote a sphere's figure over its own log (--plot LOG) and a risk map over the fruit file it was
    drawn for (--map-csv FRUIT), both with exit 0: the user's data lost.  Every command's outputs are checked
    against the files it reads (cli.common.INPUT_FILE_ARGS), before any work, and the input is left as it was."""
    log = tmp_path / "log.png"
    log.write_bytes(open("examples/sphere-log.csv", "rb").read())
    before = log.read_bytes()
    status, out, err = cli.run("sphere", str(log), "--sphere", "is-1987", "--fruit", "apple", "-n", "20",
                               "--plot", str(log))
    assert status == 2 and out == "" and err.startswith("fruitimpact sphere: error: argument --plot:")
    assert "is the file LOG the command reads" in err and log.read_bytes() == before
    fruit = tmp_path / "fruit.csv"
    assert cli.run("fit-damage", "examples/drop-tests.csv", "--fruit", "apple", "-o", str(fruit))[0] == 0
    before = fruit.read_bytes()
    status, out, err = cli.run("safe-height", "--fruit", str(fruit), "--map", "surface", "--map-csv", str(fruit))
    assert status == 2 and "argument --map-csv:" in err and "is the file --fruit the command reads" in err
    assert fruit.read_bytes() == before


def test_serve_on_an_address_not_this_machines_is_one_line(script, tmp_path):
    """A refusal is one line: the warning that anyone on the network can use the app comes once it listens, not
    before an address it cannot take (found by an attack: the warning, then the error)."""
    done = script("serve", "--host", "192.0.2.1", "--port", "0", cwd=tmp_path)  # TEST-NET-1: never this machine's
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        "fruitimpact serve: error: argument --host: cannot listen on 192.0.2.1:0: Cannot assign requested address"]
