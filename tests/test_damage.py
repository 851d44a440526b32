"""Damage commands: drops, safe heights, line audits, their contracts and refusals (issue 7).

Independent references: the closed-form onset height of elastic Hertz on a rigid flat,
h = π⁴ p⁵ / (80 g ρ E*⁴) (p = σ_f for the pressure criterion, p = σ_f p_0/Y(ν) for the
shear criterion, derived from ½ m V² = (2/5) F δ and p_0 = (2E*/π) √(δ/R)), written out
here; energy conservation over a drop; the batch evaluation of the same members for a line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fruitimpact.impact import evaluation as batch
from fruitimpact.handling.drops import drop
from fruitimpact.handling.heights import safe_height
from fruitimpact.handling.line import TransferPoint, audit, read_line
from fruitimpact.library.catalogue import fruits

G = 9.80665
APPLE = dict(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37)


def _onset_height(pressure, mass, diameter, modulus, poisson):
    """π⁴ p⁵/(80 g ρ E*⁴): the height at which an undamped Hertz impact's centre pressure reaches p."""
    density = mass / (math.pi * diameter ** 3 / 6.0)
    contact_modulus = modulus / (1.0 - poisson ** 2)
    return math.pi ** 4 * pressure ** 5 / (80.0 * G * density * contact_modulus ** 4)


def _tau_factor(poisson):
    """τ_max/p_0 on the Hertz axis by a fine grid of Johnson's eq 3.45 (a method unlike the module's Newton)."""
    z = np.linspace(1e-4, 3.0, 300001)
    sigma_z = -1.0 / (1.0 + z * z)
    sigma_r = -(1.0 + poisson) * (1.0 - z * np.arctan(1.0 / z)) + 0.5 / (1.0 + z * z)
    return float(np.max(0.5 * np.abs(sigma_z - sigma_r)))


@pytest.mark.parametrize("criterion", ["pressure", "shear"])
def test_safe_height_of_undamped_hertz_is_the_closed_form(criterion):
    # the root is found to 1e-9 in h; the grid maximum of τ/p0 is exact to ~1e-10 (spacing 1e-5, quadratic peak)
    result = safe_height(criterion=criterion, model="hertz", failure_stress=3e5, **APPLE)
    pressure = 3e5 if criterion == "pressure" else 3e5 / (2.0 * _tau_factor(0.37))
    expected = _onset_height(pressure, **APPLE)
    assert result["safe_height"] == pytest.approx(expected, rel=1e-8)
    # h ∝ σ⁵ E*⁻⁴ ρ⁻¹: at a fixed diameter the mass is the density (elasticity −1), not the size (0)
    assert result["sensitivity"]["modulus"] == pytest.approx(-4.0, abs=1e-6)
    assert result["sensitivity"]["failure_stress"] == pytest.approx(5.0, abs=1e-6)
    assert result["sensitivity"]["mass"] == pytest.approx(-1.0, abs=1e-6)


@pytest.mark.parametrize("model", ["tsuji", "kuwabara-kono"])
def test_laws_with_a_hertz_elastic_part_answer_the_stress_criteria(model):
    """Issue 14 item 7 (before: p0 = inf, bruised "-"): Tsuji and Kuwabara–Kono take p0 from their Hertz term
    K δ^1.5.  Undamped they are Hertz's impact, so the onset is the closed form π⁴p⁵/(80 g ρ E*⁴) (to the
    root finder's 1e-8); damped, the fruit is stopped at a smaller deflection, so the elastic p0 at a given
    height is lower and the onset higher (a conservation argument: energy dissipated before δ_max)."""
    undamped = safe_height(criterion="shear", model=model, failure_stress=3e5, restitution=1.0, **APPLE)
    expected = _onset_height(3e5 / (2.0 * _tau_factor(0.37)), **APPLE)
    assert undamped["safe_height"] == pytest.approx(expected, rel=1e-6)
    damped = safe_height(criterion="shear", model=model, failure_stress=3e5, restitution=0.55, **APPLE)
    assert math.isfinite(damped["safe_height"]) and damped["safe_height"] > 1.05 * expected


def test_safe_height_does_not_depend_on_fruit_size_at_fixed_density():
    density = APPLE["mass"] / (math.pi * APPLE["diameter"] ** 3 / 6.0)
    heights = [safe_height(criterion="pressure", model="hertz", failure_stress=3e5, sensitivity=False,
                           diameter=d, mass=density * math.pi * d ** 3 / 6.0, modulus=3e6, poisson=0.37)["safe_height"]
               for d in (0.04, 0.065, 0.09)]
    assert heights[0] == pytest.approx(heights[1], rel=1e-8) == pytest.approx(heights[2], rel=1e-8)


def test_safe_height_ordered_by_surface():
    """Acceptance: steel ≤ wood < rubber belt < foam pad (the hard surfaces are rigid for Hertz)."""
    heights = {s: safe_height(criterion="shear", surface=s, failure_stress=3e5, sensitivity=False)["safe_height"]
               for s in ("steel", "wood", "rubber-belt", "foam-pad")}
    assert heights["steel"] <= heights["wood"] < heights["rubber-belt"] < heights["foam-pad"]
    assert heights["wood"] / heights["steel"] - 1 < 0.05  # wood across the grain: ~1 % softer contact


def test_a_failed_evaluation_inside_the_bracket_is_not_taken_for_no_bruise(monkeypatch):
    """An impact that fails (status failed, no margin) between 2 and 5 cm: its NaN margin is neither side of the
    root.  The search used to keep narrowing on it and answer 5 cm with "ok" (the root is 3.3 cm); it must say it
    failed, and where."""
    from fruitimpact.handling import heights

    honest = safe_height(fruit="apple", criterion="shear", sensitivity=False)
    assert 0.02 < honest["safe_height"] < 0.05 and honest["status"] == "ok"
    real = heights._margins

    def failing_between_2_and_5_cm(table, drops):
        margins, result = real(table, drops)
        inside = (np.asarray(drops) > 0.02) & (np.asarray(drops) < 0.05)
        result.status[inside] = 2  # failed
        result.messages.set(inside, "the solver did not reach separation (injected)")
        return np.where(inside, np.nan, margins), result

    monkeypatch.setattr(heights, "_margins", failing_between_2_and_5_cm)
    report = safe_height(fruit="apple", criterion="shear", sensitivity=False)
    assert math.isnan(report["safe_height"]) and report["status"] == "failed"
    assert "the search failed at h = " in report["message"] and "(injected)" in report["message"]


def test_a_firmness_map_follows_hertz_scaling():
    """On a rigid plane at a fixed restitution the peak pressure is Hertzian, p0 ∝ (E*⁴ m V²/R³)^(1/5) (the
    damping shapes the pulse, x = c V is fixed by e), and so is the shear stress (τ_max/p0 depends on ν only): the
    safe height h ∝ V² ∝ p_f⁵/E*⁴ falls as E⁻⁴ across the map.  Tolerance: the root search's 1e-9 on ln h."""
    from fruitimpact.handling.heights import risk_map

    risk = risk_map(by="firmness", fruit="apple", criterion="shear")
    moduli = [float(c) for c in risk["columns"]]
    heights = [risk["safe_height"][str(c)] for c in risk["columns"]]
    expected = [heights[0] * (moduli[0] / e) ** 4 for e in moduli]
    assert heights == pytest.approx(expected, rel=1e-7)


def test_a_risk_map_drops_a_lot_at_every_point():
    """Issue 14 item 4: the map's incidence is the share of a lot drawn from the fruit's library spreads.
    Checks, each against something the map does not compute itself: (a) the same fruit fall at every point and
    each fruit's stress rises with its speed (Hertz: p0 ∝ V^(2/5)), so a column's incidence never falls with
    height; (b) a point's incidence is exactly that of a line audit of one transfer point at that height and
    surface with the same lot (seed, size, spreads: the same draws through ``impact.lots``); (c) a lot of
    identical fruit (no spreads) is bruised all or nothing, switching at the typical fruit's safe height, which is
    then also its 10 % and 50 % heights; (d) the 50 % height (an order statistic of the fruit's own safe heights,
    a root search independent of the grid's evaluations) lies between the two grid heights where the grid's
    incidence crosses 1/2."""
    import fruitimpact as fi
    from fruitimpact.handling.heights import risk_map
    from fruitimpact.handling.line import TransferPoint

    risk = risk_map(by="surface", fruit="apple", criterion="shear", rows=100, seed=3)
    heights = np.asarray(risk["heights"])
    assert risk["lot"]["rows"] == 100 and risk["lot"]["seed"] == 3 and risk["lot"]["spreads"]
    for column in risk["columns"]:
        incidence = np.array([row["incidence"] for row in risk["rows"] if row["surface"] == column])
        assert np.all(np.diff(incidence) >= 0.0), column  # (a)
        above = int(np.flatnonzero(incidence >= 0.5)[0])
        h50 = risk["incidence_heights"][column]["50%"]
        assert (above == 0 and h50 <= heights[0]) or heights[above - 1] <= h50 <= heights[above], column  # (d)
    k = 12  # (b): one grid point, steel
    point = next(row for row in risk["rows"] if row["surface"] == "steel" and row["drop_height"] == heights[k])
    audit = fi.audit_line([TransferPoint("p", float(heights[k]), "steel")], rows=100, seed=3, fruit="apple", criterion="shear", alternatives=())
    assert 0.0 < point["incidence"] < 1.0
    assert point["incidence"] == audit["points"][0]["incidence"]
    same = risk_map(by="surface", fruit="apple", criterion="shear", rows=50, spreads=False)  # (c)
    for column in same["columns"]:
        incidence = np.array([row["incidence"] for row in same["rows"] if row["surface"] == column])
        assert set(np.unique(incidence)) <= {0.0, 1.0}
        safe = same["safe_height"][column]
        if math.isfinite(safe) and heights[0] < safe < heights[-1]:
            assert np.all(incidence[heights < safe] == 0.0) and np.all(incidence[heights > safe] == 1.0), column
        assert same["incidence_heights"][column] == {"10%": safe, "50%": safe}
    none = risk_map(by="surface", fruit="apple", criterion="shear", rows=0)
    assert "lot" not in none and "incidence" not in none["rows"][0]
    firm = risk_map(by="firmness", fruit="apple", criterion="shear", rows=20)  # the axis is not drawn
    assert "modulus" not in firm["lot"]["inputs"] and "mass" in firm["lot"]["inputs"]


def test_safe_height_edges_are_said():
    never = safe_height(criterion="energy", bruise_energy=100.0, sensitivity=False)
    assert never["safe_height"] == math.inf and "no bruise up to" in never["message"]
    with pytest.raises(ValueError, match="criterion must be given"):
        safe_height(fruit="tomato")  # no criterion named, and none in the tomato's library entry
    with pytest.raises(ValueError, match="criterion must be given"):
        safe_height(criterion="none")
    with pytest.raises(ValueError, match="drop_height is what safe-height finds"):
        safe_height(criterion="shear", drop_height=0.1)


def test_drop_energy_is_conserved_and_plastic_work_only_on_the_first_impact():
    report = drop(0.1, yield_pressure=3e5, criterion="shear", failure_stress=3e5, bruise_susceptibility=4e-6)
    impacts = report["impacts"]
    mass = 0.115
    # the bookkeeping of the sequence: everything the fruit had at release is absorbed by the impacts or still in
    # the last rebound (each impact's own balance W_p + W_v = ½mV²(1 − e²) is checked against an independent
    # integration in tests/test_plastic.py; here the chaining V_{n+1} = e_n V_n and V_1 = √(2gh) are what can fail)
    released = mass * G * 0.1
    assert report["total_absorbed_energy"] + report["energy_left"] == pytest.approx(released, rel=1e-9)
    for before, after in zip(impacts, impacts[1:]):
        assert after["velocity"] == pytest.approx(before["restitution"] * before["velocity"], rel=1e-12)
    assert impacts[0]["plastic_work"] > 0.0
    # the flattened spot reloads elastically while its Hertz pressure stays under p_y, then yields again
    assert all(i["plastic_work"] < 0.1 * impacts[0]["plastic_work"] for i in impacts[1:])
    assert impacts[0]["velocity"] == pytest.approx(math.sqrt(2 * G * 0.1), rel=1e-12)
    # the rebound height of the last impact is below the rest height (1 mm)
    assert impacts[-1]["exit_velocity"] ** 2 / (2 * G) < 1e-3
    assert report["bruise_volume"] == pytest.approx(sum(i["bruise_volume"] for i in impacts), rel=1e-12)


def test_drop_refuses_a_free_partner_and_a_velocity():
    for partner in ({"surface": "fruit"}, {"surface": " fruit "}, {"partner_mass": 0.1}):  # as resolved
        with pytest.raises(ValueError, match="a drop bounces on a fixed surface, not a free partner"):
            drop(0.1, **partner)
    with pytest.raises(ValueError, match="velocity is set by the drop"):
        drop(0.1, velocity=2.0)
    with pytest.raises(ValueError, match="drop_height must be given"):
        drop(None)  # was an "ok" drop at the default 1 m/s with a NaN height
    assert drop(0.1, velocity=None)["status"] == "ok"  # None is "not given", as everywhere


def test_line_incidence_is_the_batch_bruise_rate_of_the_same_members(tmp_path):
    rng = np.random.default_rng(3)
    rows = 400
    members = {"mass": rng.normal(0.15, 0.02, rows), "modulus": rng.lognormal(np.log(3e6), 0.2, rows),
               "failure_stress": np.full(rows, 3e5), "bruise_susceptibility": np.full(rows, 4e-6)}
    points = [TransferPoint("a", 0.02, "pvc-belt"), TransferPoint("b", 0.3, "foam-pad"),
              TransferPoint("c", 0.05, "steel", fruit_on_fruit=True)]
    report = audit(points, members, rows, "shear", {})
    bruised_any = np.zeros(rows, dtype=bool)
    for point, row in zip(points, report["points"]):
        frame = batch.evaluate({**members, "drop_height": np.full(rows, point.drop_height),
                                "surface": "fruit" if point.fruit_on_fruit else point.surface, "criterion": "shear"})
        bruised = frame["bruised"].to_numpy() > 0.5
        bruised_any |= bruised
        assert row["incidence"] == pytest.approx(bruised.mean(), abs=1e-12)
        assert row["mean_bruise_volume"] == pytest.approx(frame["bruise_volume"].mean(), rel=1e-12, abs=1e-18)
        assert row["cumulative_incidence"] == pytest.approx(bruised_any.mean(), abs=1e-12)
    worst = max(report["points"], key=lambda p: (p["incidence"], p["mean_bruise_volume"]))
    assert report["worst_point"] == worst["name"]


def test_a_measured_surface_in_a_line_file_is_that_half_space(tmp_path):
    """surface_modulus and surface_poisson make a point's surface a measured half-space (an instrumented sphere's
    reading).  Given wood's own library values (0.7 GPa, ν 0.35) they are wood: the same incidence, bruise volume
    and peak force to the last digit for the same lot.  A softer half-space (20 MPa) is hit more gently: Hertz's
    E* = (1/E*_fruit + (1 − ν²)/E_surface)⁻¹ falls, so does the peak force (F ∝ E*^(2/5)), and the incidence
    with it.  Blank cells are the library surface's own values; the report names the half-space it used."""
    path = tmp_path / "line.csv"
    path.write_text("name,drop_height,surface,fruit_on_fruit,surface_modulus,surface_poisson\n"
                    "library,4cm,wood,false,,\nmeasured,4cm,wood,false,0.7GPa,0.35\nsoft,4cm,wood,false,20MPa,0.35\n")
    points = read_line(path)
    assert points[0].surface_modulus is None and points[1].surface_modulus == 0.7e9
    rng = np.random.default_rng(5)
    rows = 2000
    members = {"mass": rng.normal(0.17, 0.02, rows), "modulus": rng.lognormal(np.log(3e6), 0.2, rows),
               "failure_stress": np.full(rows, 3e5), "bruise_susceptibility": np.full(rows, 4e-6)}
    library, measured, soft = audit(points, members, rows, "shear", {}, alternatives=())["points"]
    for key in ("incidence", "mean_bruise_volume", "mean_peak_force"):
        assert measured[key] == library[key], key
    assert (library["surface_modulus"], measured["surface_modulus"], measured["surface_poisson"]) == (None, 0.7e9, 0.35)
    assert soft["mean_peak_force"] < 0.97 * library["mean_peak_force"] and soft["incidence"] < library["incidence"]


@pytest.mark.parametrize("text, message", [
    ("name,drop_height,surface\na,10cm,granite\n", "surface must be one of"),
    ("name,drop_height,surface\na,-10cm,steel\n", "drop_height must be in (0, 10] m"),
    ("name,drop_height,surface\na,10cm,steel,extra\n", "4 fields, the header has 3"),
    ("name,height,surface\na,10cm,steel\n", "unknown column(s) 'height'"),
    ("name,drop_height\na,10cm\n", "missing column(s) surface"),
    ("name,drop_height,surface,fruit_on_fruit\na,10cm,steel,maybe\n", "fruit_on_fruit must be true or false"),
    ("name,drop_height,surface\na,nan,steel\n", "drop_height must be in (0, 10] m"),
    ("name,drop_height,surface,surface_modulus\na,10cm,wood,20MPa\n",
     "surface_poisson must be given with surface_modulus"),
    ("name,drop_height,surface,surface_modulus,surface_poisson\na,10cm,wood,soft,0.3\n", "surface_modulus: cannot read"),
    ("name,drop_height,surface,surface_modulus,surface_poisson\na,10cm,wood,0Pa,0.3\n",
     "surface_modulus must be > 0 Pa"),
    ("name,drop_height,surface,surface_modulus,surface_poisson\na,10cm,wood,20MPa,0.5\n",
     "surface_poisson must be in (-1, 0.5)"),
    ("name,drop_height,surface,fruit_on_fruit,surface_modulus,surface_poisson\na,10cm,steel,true,20MPa,0.3\n",
     "but fruit_on_fruit lands the fruit on another fruit"),
    ("name,drop_height,surface,surface_modulus,surface_poisson,surface_modulus\na,10cm,steel,20MPa,0.3,5MPa\n",
     "column 'surface_modulus' is given twice"),
    ("name,drop_height,surface\n# a comment\n\na,-10cm,steel\n", "line 4: drop_height"),  # the file's own line
])
def test_bad_lines_are_refused_with_their_line_number(tmp_path, text, message):
    path = tmp_path / "line.csv"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        read_line(path)
    assert message in str(info.value)


# ---------------------------------------------------------------------------- CLI contract (issue 7)
SIMULATE_KEYS = ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work", "max_shear_stress",
                 "bruised", "bruise_volume", "bruise_depth", "bruise_width", "criterion")


def test_simulate_json_has_the_damage_keys(cli):
    report = cli.json("simulate", "--fruit", "apple", "--surface", "steel", "--yield-pressure", "0.3MPa",
                      "--failure-stress", "0.3MPa", "--criterion", "shear", "--drop-height", "10cm")
    assert set(SIMULATE_KEYS) <= set(report)
    assert report["criterion"] == "shear" and report["bruised"] is True
    assert report["plastic_work"] + report["viscous_work"] == pytest.approx(report["absorbed_energy"], rel=1e-9)
    pure = cli.json("simulate", "--model", "hertz", "--yield-pressure", "0.3MPa", "--velocity", "1")
    assert pure["viscous_work"] == pytest.approx(0.0, abs=1e-12 * pure["absorbed_energy"])  # pure Thornton
    for surface in ("steel", "concrete", "wood", "pvc-belt", "rubber-belt", "foam-pad", "cardboard", "fruit"):
        assert cli.json("simulate", "--surface", surface)["surface"] == surface


def test_drop_and_safe_height_json_contracts(cli):
    report = cli.json("drop", "--drop-height", "10cm", "--yield-pressure", "0.3MPa", "--criterion", "pressure",
                      "--failure-stress", "0.3MPa")
    assert isinstance(report["impacts"], list) and report["impacts"]
    for key in ("velocity", "restitution", "peak_force", "plastic_work"):
        assert key in report["impacts"][0]
    safe = cli.json("safe-height", "--criterion", "pressure", "--model", "hertz", "--failure-stress", "0.3MPa")
    assert safe["criterion"] == "pressure"
    assert safe["safe_height"] == pytest.approx(_onset_height(3e5, **APPLE), rel=1e-8)


def test_runs_accept_the_damage_inputs(cli, tmp_path):
    table = tmp_path / "in.csv"
    table.write_text("drop_height,surface,yield_pressure,criterion,failure_stress\n"
                     "10cm,steel,0.3MPa,shear,0.3MPa\n5cm,foam-pad,,pressure,0.3MPa\n")
    out = tmp_path / "out.csv"
    cli.ok("batch", table, "-o", out)
    import csv

    with open(out) as handle:
        rows = list(csv.DictReader(handle))
    assert rows[0]["criterion"] == "shear" and float(rows[0]["plastic_work"]) > 0
    assert rows[1]["surface"] == "foam-pad" and rows[1]["status"] == "ok"
    cli.ok("sweep", "--drop-height", "1cm:30cm:3", "--surface", "rubber-belt", "--criterion", "shear", "--fruit", "apple",
           "-o", tmp_path / "sweep.csv")
    summary = cli.json("population", "-n", "500", "--drop-height", "uniform(1cm,20cm)", "--criterion", "shear",
                       "--failure-stress", "0.3MPa",
                       "--yield-pressure", "0.3MPa", "--characteristics", "bruised,bruise_volume")
    assert 0.0 < summary["statistics"]["bruised"]["mean"] <= 1.0  # the probability of bruising


@pytest.mark.parametrize("argv, option", [
    (("simulate", "--fruit", "banana"), "--fruit"),
    (("simulate", "--surface", "granite"), "--surface"),
    (("drop", "--drop-height", "-10cm"), "--drop-height"),
    (("simulate", "--surface", "foam-pad", "--surface-thickness", "0.2mm"), "--surface-thickness"),
    (("simulate", "--yield-pressure", "0"), "--yield-pressure"),
    (("simulate", "--yield-pressure", "-1MPa"), "--yield-pressure"),
    (("simulate", "--failure-stress", "0.3MPa"), "--failure-stress"),
    (("simulate", "--criterion", "energy"), "--bruise-energy"),
    (("simulate", "--criterion", "pain"), "--criterion"),
    (("simulate", "--yield-pressure", "1MPa", "--bioyield-force", "20N"), "--yield-pressure"),
    (("safe-height", "--fruit", "pear"), "--criterion"),
    (("safe-height",), "--failure-stress"),  # the paper apple: shear by default, no failure stress of its own
    (("safe-height", "--criterion", "shear", "--drop-height", "1m"), "--drop-height"),
    (("drop", "--drop-height", "10cm", "--surface", "fruit"), "--surface"),
    (("simulate", "--model", "tsuji", "--yield-pressure", "1MPa"), "--yield-pressure"),
    (("simulate", "--method", "rk4", "--yield-pressure", "1MPa"), "--method"),
    # issue 14 item 7: a linear Kelvin–Voigt spring has no Hertz pressure, a stress criterion is refused
    (("drop", "--model", "kelvin-voigt", "--criterion", "shear", "--drop-height", "10cm"), "--criterion"),
    (("safe-height", "--model", "kelvin-voigt", "--criterion", "pressure"), "--criterion"),
])
def test_bad_damage_inputs_are_one_line_errors(cli, argv, option):
    line = cli.error(*argv)
    assert option in line, line


# ------------------------------------------------------------------ defects found by attacking the CLI
def test_a_bad_energy_threshold_is_one_invalid_row_not_a_dead_batch(cli, tmp_path):
    """Before: --bruise-energy 0 with the energy criterion raised from the bruise module (a traceback in sweep,
    a fatal error in batch that left a work folder blocking the retry)."""
    table = tmp_path / "in.csv"
    table.write_text("drop_height,criterion,bruise_energy\n10cm,energy,0\n10cm,energy,0.05\n")
    out = tmp_path / "out.csv"
    cli.ok("batch", table, "-o", out)
    import csv

    with open(out) as handle:
        rows = list(csv.DictReader(handle))
    assert rows[0]["status"] == "invalid" and "bruise_energy must be > 0" in rows[0]["message"]
    assert rows[1]["status"] == "ok"
    assert "--bruise-energy" in cli.error("sweep", "--drop-height", "1cm:1m:3", "--criterion", "energy",
                                          "--bruise-energy", "0", "-o", tmp_path / "s.csv")
    assert "--bruise-energy" in cli.error("population", "-n", "100", "--criterion", "energy", "--drop-height", "10cm")


def test_the_fruit_threshold_belongs_to_the_energy_criterion():
    """Before: the apple's 0.08 J threshold was subtracted under the pressure criterion: bruised, volume 0."""
    frame = batch.evaluate({"fruit": ["apple", "apple"], "criterion": ["pressure", "energy"], "drop_height": [0.3, 0.3]})
    # the energy row subtracts the library's 0.08 J; the pressure row its own onset energy (not the 0.08 J)
    assert frame.loc[1, "bruise_energy"] == 0.08
    assert 0.0 < frame.loc[0, "bruise_energy"] < frame.loc[0, "fruit_energy"] and frame.loc[0, "bruise_energy"] != 0.08
    assert frame.loc[0, "bruised"] == 1.0 and frame.loc[0, "bruise_volume"] > 0.0


def test_failed_rows_carry_no_damage_figures():
    frame = batch.evaluate({"yield_pressure": [1e-300], "criterion": ["pressure"], "failure_stress": [3e5]})
    assert frame.loc[0, "status"] == "failed"
    assert np.isnan(frame.loc[0, "bruised"]) and np.isnan(frame.loc[0, "plastic_work"])


def test_line_counts_invalid_fruit_and_uses_one_population(tmp_path, cli):
    line = tmp_path / "line.csv"
    line.write_bytes("\ufeffname,drop_height,surface\nA,20cm,steel\nB,5cm,pvc-belt\n".encode("utf-8"))  # a BOM
    status, out, err = cli.run("line", line, "--criterion", "pressure", "--failure-stress", "0.3MPa", "-n", "500",
                               "--mass", "normal(180g,200g)",
                               "--json")
    assert status == 0
    import json

    report = json.loads(out)
    assert report["warnings"] and "not computed" in err
    first = report["points"][0]
    assert first["cumulative_incidence"] == pytest.approx(first["incidence"], abs=1e-12)


def test_a_safe_height_that_cannot_be_found_is_not_a_result(cli):
    status, out, err = cli.run("safe-height", "--criterion", "pressure", "--failure-stress", "0.3MPa", "--yield-pressure", "1e-300",
                               "--no-sensitivity")
    assert status == 1 and "nan" not in out


# ---------------------------------------------------------------- issue 14 item 1: no fruit borrows another's values
def _library_value(fruit, key):
    value = fruits()[fruit].inputs().get(key)
    return math.nan if value is None else value


@pytest.mark.parametrize("fruit", sorted(fruits()))
def test_each_fruit_uses_only_its_own_damage_values(fruit):
    """The rule, checked on every library entry: a fruit's failure stress and bruise susceptibility are its own
    library values; where its entry has none, a stress criterion is refused naming --failure-stress (before:
    pear, peach and tomato borrowed the apple's 0.32 MPa), and the bruise volume is unknown (NaN, with a
    warning), never another fruit's figure."""
    stress = _library_value(fruit, "failure_stress")
    frame = batch.evaluate({"fruit": [fruit], "criterion": ["shear"], "drop_height": [0.3]})
    if math.isnan(stress):
        assert frame.loc[0, "status"] == "invalid"
        assert "failure_stress is not in the " + fruit in frame.loc[0, "message"]
        assert "--failure-stress" in frame.loc[0, "message"]
        frame = batch.evaluate({"fruit": [fruit], "criterion": ["shear"], "drop_height": [0.3],
                                "failure_stress": [2e5]})
        stress = 2e5
    assert frame.loc[0, "status"] == "ok", frame.loc[0, "message"]
    assert frame.loc[0, "failure_stress"] == stress
    susceptibility = _library_value(fruit, "bruise_susceptibility")
    if math.isnan(susceptibility):
        assert math.isnan(frame.loc[0, "bruise_susceptibility"])
        assert "bruise_susceptibility is not in the " + fruit in frame.loc[0, "warnings"]
        assert frame.loc[0, "bruised"] == 0.0 or math.isnan(frame.loc[0, "bruise_volume"])
    else:
        assert frame.loc[0, "bruise_susceptibility"] == susceptibility


def test_a_fruit_without_a_failure_stress_is_refused_on_the_command_line(cli):
    line = cli.error("safe-height", "--fruit", "pear", "--criterion", "shear")
    assert "--failure-stress" in line and "pear" in line
    report = cli.json("safe-height", "--fruit", "pear", "--criterion", "shear", "--failure-stress", "0.2MPa",
                      "--no-sensitivity")
    assert report["status"] == "ok"


@pytest.mark.parametrize("criterion", ["pressure", "shear"])
def test_bruise_volume_grows_from_zero_at_the_stress_onset(criterion):
    """Issue 14 item 5b (before: W_th = 0 under the stress criteria, so the volume jumped from 0 to ~190 mm³ at
    onset).  Published bruises grow as BS (W − W_th) above a threshold.  Reference: the onset height h_s of the
    root search (an independent path: Illinois on ln h to 1e-9) and the energy of a drop at fixed e on the
    basis the apple's susceptibility was measured on (impact, ½ m V² = m g h; absorbed would add (1 − e²)); so
    above onset BV = BS m g (h − h_s) exactly, and 0 just below it."""
    assert fruits()["apple"].bases() == {"bruise_susceptibility": "impact", "bruise_threshold_energy": "impact"}
    hs = safe_height(criterion=criterion, fruit="apple", sensitivity=False)["safe_height"]
    heights = [0.999 * hs, 1.001 * hs, 2.0 * hs, 10.0 * hs]
    frame = batch.evaluate({"fruit": ["apple"] * 4, "criterion": [criterion] * 4, "drop_height": heights})
    mass, bs = frame.loc[0, "mass"], frame.loc[0, "bruise_susceptibility"]
    assert frame.loc[0, "bruised"] == 0.0 and frame.loc[0, "bruise_volume"] == 0.0
    for k, h in enumerate(heights[1:], start=1):
        expected = bs * mass * G * (h - hs)
        # 1e-6 relative: the root's 1e-9 in ln h is 1e-9·h_s in h, i.e. ≤ 1e-6 of (h − h_s) at 1.001 h_s
        assert frame.loc[k, "bruise_volume"] == pytest.approx(expected, rel=1e-6)
        assert frame.loc[k, "bruise_energy"] == pytest.approx(mass * G * hs, rel=1e-8)


def test_each_bruise_value_is_applied_on_the_energy_its_source_measured():
    """Issue 14 item 5a: published susceptibilities and thresholds are per impact energy in pendulum studies
    (the library's apple: Khorasan cultivars, 'Royal Gala'), per absorbed energy elsewhere; each is applied on
    its own basis (before: always on the absorbed energy, ~30 % low volumes and ~44 % high energy onsets at
    e = 0.55).  Reference: the energies of a drop at fixed e, ½ m V² = m g h and ½ m V² (1 − e²)."""
    h = 0.1
    frame = batch.evaluate({"criterion": ["energy"] * 3, "drop_height": [h] * 3, "fruit": ["apple"] * 3,
                            "bruise_energy": [None, 0.05, 0.05], "bruise_susceptibility": [None, 5e-6, 5e-6],
                            "bruise_basis": ["absorbed", "absorbed", "impact"]})
    mass, e = frame.loc[0, "mass"], frame.loc[0, "restitution"]
    impact, absorbed = mass * G * h, mass * G * h * (1.0 - e ** 2)
    assert frame.loc[0, "bruise_volume"] == pytest.approx(4.66e-6 * (impact - 0.08), rel=1e-9)  # library: impact
    assert frame.loc[1, "bruise_volume"] == pytest.approx(5e-6 * (absorbed - 0.05), rel=1e-9)   # given, absorbed
    assert frame.loc[2, "bruise_volume"] == pytest.approx(5e-6 * (impact - 0.05), rel=1e-9)     # given, impact
    # a threshold on another basis than the susceptibility: carried over by this impact's ratio (1 − e²)
    mixed = batch.evaluate({"criterion": ["energy"], "drop_height": [h], "fruit": ["pear"], "bruise_energy": [0.05],
                            "bruise_basis": ["impact"]})
    m, ee = mixed.loc[0, "mass"], mixed.loc[0, "restitution"]
    assert fruits()["pear"].bases()["bruise_susceptibility"] == "absorbed"
    assert mixed.loc[0, "bruise_volume"] == pytest.approx(3e-6 * (m * G * h - 0.05) * (1.0 - ee ** 2), rel=1e-9)



def test_a_drop_keeps_the_fruit_damping_and_e_follows_the_law():
    """Issue 14 item 6: the damping factor c = λ/k_c is calibrated once, at the first impact, and kept, so
    each later e is the Hunt–Crossley law's at its own speed.  Reference: SciPy DOP853 (rtol 1e-11) of
    m δ̈ = −k_c δ^1.5 (1 + c δ̇) with that c at each later speed, e = exit/entry speed (tolerance 1e-6: the
    event location on the dense output, ~1e-9, and the engine's exact quadrature, ~1e-12).  The constant rule
    keeps e fixed; the material rule gives e rising as the fruit slows, as drop tests report."""
    from scipy.integrate import solve_ivp

    from fruitimpact.impact import evaluation as batch_module

    report = drop(0.3, fruit="apple")
    assert report["bounces"] == "material"
    first = batch_module.evaluate({"fruit": ["apple"], "drop_height": [0.3]})
    k, c, m = first.loc[0, "law_stiffness"], first.loc[0, "damping_factor"], first.loc[0, "mass"]

    def restitution(v0):
        def rhs(t, y):
            d, v = y
            return [v, -k * max(d, 0.0) ** 1.5 * (1.0 + c * v) / m]

        def out(t, y):
            return y[0]
        out.terminal, out.direction = True, -1
        sol = solve_ivp(rhs, (0.0, 1.0), [0.0, v0], method="DOP853", rtol=1e-11, atol=1e-15, events=out)
        return -sol.y_events[0][0][1] / v0

    impacts = report["impacts"]
    assert impacts[0]["restitution"] == pytest.approx(0.55, rel=1e-9)
    for impact in impacts[1:4]:
        assert impact["restitution"] == pytest.approx(restitution(impact["velocity"]), rel=1e-6)
    assert all(b["restitution"] > a["restitution"] for a, b in zip(impacts, impacts[1:]))
    constant = drop(0.3, fruit="apple", bounces="constant")["impacts"]
    assert all(i["restitution"] == pytest.approx(0.55, rel=1e-9) for i in constant)
    with pytest.raises(ValueError, match="bounces must be one of"):
        drop(0.3, bounces="elastic")


# ---------------------------------------------------------------- issue 14 item 4: a lot varies by default
def test_a_population_draws_the_fruit_library_spreads_unless_fixed(cli, tmp_path):
    """Before: `population --fruit apple` was N identical apples.  Now mass, modulus, failure stress and
    susceptibility are drawn from the library ranges (a split normal with its median at the library value, each
    side's sd half the distance from the value to that end of the range, truncated to it) and the diameter follows the mass at the
    library density: every member satisfies m = ρ π d³/6 exactly (float rounding), and each drawn input stays in
    its library range.  The spread bound is loose on purpose: a tenth of the symmetric sd (range/4), so it fails
    only when an input is not drawn at all (sd 0), whatever the skew of the split normal."""
    apple = fruits()["apple"]
    out = tmp_path / "members.csv"
    cli.ok("population", "-n", "2000", "--fruit", "apple", "--drop-height", "4cm", "--criterion", "shear",
           "-o", out)
    import pandas as pd

    frame = pd.read_csv(out)
    for name in ("mass", "modulus", "failure_stress", "bruise_susceptibility"):
        value = getattr(apple, name)
        assert frame[name].std() > 0.1 * (value.high - value.low) / 4.0, name
        assert frame[name].between(value.low, value.high).all(), name
    density = apple.density.value
    assert np.allclose(frame["mass"], density * np.pi * frame["diameter"] ** 3 / 6.0, rtol=1e-9)
    # near onset (4 cm vs 3.3 cm for the central apple) incidence is a share, not 0 % or 100 %
    assert 0.05 < frame["bruised"].mean() < 0.99
    cli.ok("population", "-n", "200", "--fruit", "apple", "--mass", "150g", "--drop-height", "4cm",
           "-o", tmp_path / "fixed.csv")
    fixed = pd.read_csv(tmp_path / "fixed.csv")
    assert (fixed["mass"] == 0.15).all() and fixed["modulus"].std() > 0
    cli.ok("population", "-n", "200", "--fruit", "apple", "--no-spreads", "--drop-height", "4cm",
           "-o", tmp_path / "same.csv")
    same = pd.read_csv(tmp_path / "same.csv")
    assert same["mass"].nunique() == 1 and same["modulus"].nunique() == 1


def test_line_changes_are_the_audit_of_the_changed_line():
    """The saving of a change of surface is paired (the same fruit): the line incidence with foam-pad at a
    point equals the audit of the line with that point's surface replaced (an independent run)."""
    rng = np.random.default_rng(5)
    rows = 300
    members = {"mass": rng.normal(0.18, 0.02, rows), "modulus": rng.lognormal(np.log(3e6), 0.2, rows),
               "failure_stress": np.full(rows, 3e5), "bruise_susceptibility": np.full(rows, 4e-6)}
    points = [TransferPoint("tipper", 0.1, "steel"), TransferPoint("belt", 0.04, "pvc-belt")]
    report = audit(points, members, rows, "shear", {})
    change = next(c for c in report["changes"] if c["point"] == "tipper" and c["to"] == "foam-pad")
    changed = audit([TransferPoint("tipper", 0.1, "foam-pad"), points[1]], members, rows, "shear", {}, ())
    assert change["incidence"] == pytest.approx(changed["incidence"], abs=1e-12)
    assert change["incidence_saved"] == pytest.approx(report["incidence"] - changed["incidence"], abs=1e-12)
    assert change["mean_bruise_volume"] == pytest.approx(changed["mean_bruise_volume"], rel=1e-12)


def test_a_point_where_no_fruit_was_computed_is_unknown_not_harmless(monkeypatch, cli, tmp_path):
    """Every fruit failing at one transfer point: that point's incidence is unknown (NaN), not 0 %, it cannot be
    the most harmful point by default, the line as a whole is failed (no fruit went through it), and the command
    says so and exits 1."""
    from fruitimpact.impact import evaluation as module

    real = module.evaluation

    def failing_on_steel(table, **kwargs):
        result = real(table, **kwargs)
        if table.get("surface") == "steel":
            result.status[:] = 2
            result.messages.set(np.ones(result.rows, dtype=bool), "the solver did not reach separation (injected)")
        return result

    monkeypatch.setattr(module, "evaluation", failing_on_steel)
    rng = np.random.default_rng(5)
    rows = 50
    members = {"mass": rng.normal(0.18, 0.02, rows), "failure_stress": np.full(rows, 3e5)}
    points = [TransferPoint("tipper", 0.1, "steel"), TransferPoint("belt", 0.04, "pvc-belt")]
    report = audit(points, members, rows, "shear", {}, ())
    tipper, belt = report["points"]
    assert math.isnan(tipper["incidence"]) and math.isnan(tipper["mean_bruise_volume"])
    assert math.isfinite(belt["incidence"]) and report["worst_point"] == "belt"
    assert math.isnan(report["incidence"]) and report["fruit_computed"] == 0
    assert report["status"] == "failed" and "no fruit of the 50" in report["message"]
    line = tmp_path / "line.csv"
    line.write_text("name,drop_height,surface\ntipper,10cm,steel\nbelt,4cm,pvc-belt\n")
    status, out, _ = cli.run("line", line, "-n", "50", "--fruit", "apple", "--criterion", "shear")
    assert status == 1 and "FAILED: no fruit" in out


# ---------------------------------------------------------------- issue 14 item 3: corrugated board crushes
def test_a_crushed_board_hands_the_fruit_to_the_floor_with_the_energy_left():
    """The board is a Winkler layer up to its crush depth δ_c = σ_c/k; past the crush force F_c = K_L δ_c²
    it has taken W_c = K_L δ_c³/3 and the fruit meets the floor.  Reference for an undamped Hertz fruit
    (model hertz): Hertz's closed form at V' = √(V² − 2 W_c/m), F_max = K (5 m V'²/(4K))^(3/5) (Johnson 1985
    §11.4), restitution V'/V and absorbed energy W_c (conservation); tolerance 1e-9 (the exact engine)."""
    from fruitimpact.engine.plastic import winkler_stiffness

    mass, diameter, modulus, poisson = 0.18, 0.075, 3e6, 0.37
    e_star = modulus / (1 - poisson ** 2)
    radius = diameter / 2
    k_hertz = 4.0 / 3.0 * e_star * math.sqrt(radius)
    board_e, board_h, crush = 1e6, 0.004, 1.5e5
    k_l = winkler_stiffness(board_e, 0.0, board_h, radius)
    depth = crush * math.pi * radius / k_l
    w_c = k_l * depth ** 3 / 3.0
    v = math.sqrt(2 * G * 0.1)
    frame = batch.evaluate({"model": ["hertz"], "mass": [mass], "diameter": [diameter], "modulus": [modulus],
                            "poisson": [poisson], "drop_height": [0.1], "surface": ["cardboard"],
                            "surface_modulus": [board_e], "surface_poisson": [0.0], "surface_thickness": [board_h],
                            "surface_crush_stress": [crush]})
    v_left = math.sqrt(v ** 2 - 2 * w_c / mass)
    expected = k_hertz * (5 * mass * v_left ** 2 / (4 * k_hertz)) ** 0.6
    assert frame.loc[0, "peak_force"] == pytest.approx(expected, rel=1e-9)
    assert frame.loc[0, "restitution"] == pytest.approx(v_left / v, rel=1e-9)
    assert frame.loc[0, "absorbed_energy"] == pytest.approx(w_c, rel=1e-6)
    assert frame.loc[0, "fruit_energy"] == pytest.approx(0.0, abs=1e-9 * w_c)  # undamped: the board took it all
    assert "the board crushes" in frame.loc[0, "warnings"]


def test_cardboard_protects_only_below_its_crush():
    """The pattern of drop tests on corrugated board (Słupska 2022, apples 10–150 mm: the board helps at the
    lowest heights, then it crushes and bruising reaches the wood/concrete level): the onset height on the
    library cardboard lies within 25 % of steel's (before: 94 cm, 29× steel's), and a drop too low to crush
    it is a cushioned impact (peak force below steel's)."""
    steel = safe_height(criterion="shear", fruit="apple", surface="steel", sensitivity=False)["safe_height"]
    board = safe_height(criterion="shear", fruit="apple", surface="cardboard", sensitivity=False)["safe_height"]
    assert steel <= board < 1.25 * steel
    low = batch.evaluate({"fruit": ["apple"] * 2, "surface": ["steel", "cardboard"], "drop_height": [0.0005] * 2})
    assert low.loc[1, "peak_force"] < 0.9 * low.loc[0, "peak_force"]
    assert "the board crushes" not in low.loc[1, "warnings"]


def test_a_crushed_board_stays_crushed_for_the_later_bounces():
    """Flat crush is permanent (the flutes under the fruit collapse and do not recover), and a drop's fruit lands
    on the same spot (the accumulation rule): once the first impact has crushed the library cardboard, the later
    impacts land on the floor that carried the force beyond the crush, rigid in the layer model, and the board does
    no more work.  Before, every bounce met a fresh board: 2.1 mJ of crush work at each of the first 8 impacts of
    an apple from 30 cm.  Independent of the drop loop: impact 2 equals one impact of the same fruit on the rigid
    surface at that speed with the drop's damping c = (c/k)·k (bounces material), to rounding; and the sequence
    keeps its energy (released = absorbed + left)."""
    report = drop(0.3, fruit="apple", surface="cardboard")
    impacts = report["impacts"]
    assert impacts[0]["plastic_work"] > 0.0  # the crush
    assert all(i["plastic_work"] == 0.0 for i in impacts[1:])
    first = batch.evaluate({"fruit": ["apple"], "surface": ["cardboard"], "drop_height": [0.3]})
    damping = float(first.loc[0, "damping_factor"]) * float(first.loc[0, "law_stiffness"])
    again = batch.evaluate({"fruit": ["apple"], "surface": ["rigid"], "velocity": [impacts[1]["velocity"]],
                            "damping": [damping]})
    for key in ("peak_force", "restitution", "contact_duration"):
        assert impacts[1][key] == pytest.approx(float(again.loc[0, key]), rel=1e-9), key
    released = float(first.loc[0, "mass"]) * G * 0.3
    assert report["total_absorbed_energy"] + report["energy_left"] == pytest.approx(released, rel=1e-9)


# ------------------------------------------------------- defects found by the review of issue 14 (helper attack)
@pytest.mark.parametrize("argv, option", [
    (("population", "-n", "50", "--fruit", "pear", "--drop-height", "4cm", "--criterion", "shear"), "--failure-stress"),
    (("sweep", "--fruit", "pear", "--criterion", "shear", "--velocity", "0.5:1:3", "-o", "{tmp}/sw.csv"),
     "--failure-stress"),
    (("line", "examples/line.csv", "--fruit", "banana", "--criterion", "shear", "-n", "10"), "--fruit"),
    (("line", "examples/line.csv", "--fruit", "apple", "--criterion", "shear", "-n", "10", "--alternatives", ""),
     "--alternatives"),
    (("line", "examples/line.csv", "--fruit", "apple", "--criterion", "shear", "-n", "10", "--alternatives", "rigid"),
     "--alternatives"),
    (("simulate", "--fruit", "apple", "--surface", "steel", "--surface-crush-stress", "150kPa"),
     "--surface-crush-stress"),
    (("drop", "--drop-height", "30cm", "--alpha", "0.3", "--bounces", "constant"), "--bounces"),
])
def test_issue14_options_refuse_what_they_cannot_do(cli, argv, option, monkeypatch, tmp_path):
    import pathlib

    monkeypatch.chdir(pathlib.Path(__file__).resolve().parents[1])  # examples/line.csv; outputs go to tmp_path
    assert option in cli.error(*(a.format(tmp=tmp_path) for a in argv))
    assert not list(tmp_path.iterdir())  # refused before any work: nothing written


def test_a_lot_without_a_criterion_draws_no_bruise_inputs(cli):
    """Before the review: the spreads drew failure stress and susceptibility without a criterion and every
    member was refused ("a bruise input: give --criterion"), exit 0."""
    report = cli.json("population", "--fruit", "apple", "-n", "100", "--drop-height", "4cm",
                      "--characteristics", "peak_force")
    assert report["ok"] == 100 and "failure_stress" not in report["inputs"]


def test_a_lot_at_its_median_threshold_energy_is_bruised_in_half(cli):
    """Under the energy criterion a lot draws each fruit's threshold energy from the fruit's spread (the potato's
    0.080–0.095 J, Stropek & Gołacki 2022, docs/library.md), so a lot dropped where every fruit meets the median
    0.0875 J (175 g fixed, onto steel, ½ m V² on the impact basis the value was measured on) is bruised in half:
    a share, as drop tests near onset see, not all or none.  4000 fruit: the binomial sd of the share is 0.8 %,
    so ±5 points is over 6 sd.  Identical fruit (--no-spreads): none bruised 2 % below that drop, all 2 % above."""
    def bruised(factor, *more):
        height = factor * 0.0875 / (0.175 * 9.80665)
        report = cli.json("population", "--fruit", "potato", "--mass", "175g", "--surface", "steel", "--criterion",
                          "energy", "--drop-height", f"{height!r}", "-n", "4000", "--seed", "3",
                          "--characteristics", "bruised", *more)
        return report["statistics"]["bruised"]["mean"], report["spreads"]

    share, spreads = bruised(1.0)
    assert any(line.startswith("bruise_energy: median 0.0875") for line in spreads)
    assert 0.45 < share < 0.55
    assert bruised(0.98, "--no-spreads")[0] == 0.0 and bruised(1.02, "--no-spreads")[0] == 1.0


def test_bruise_values_drawn_from_the_library_keep_the_basis_they_were_measured_on(cli):
    """The apple's bruise susceptibility is per impact energy (the Khorasan pendulum study, docs/library.md); a lot
    that draws it passes it to each row as a given value, whose basis is --bruise-basis's (default absorbed).
    Before, that default applied: bruise volumes (1 − e²) ≈ 0.7 of the identical fruit's at e = 0.55 (median 1.01
    against 1.38 mm³ at 20 cm onto steel).  Now the rows carry the library's basis: the lot's median volume is
    within 10 % of the identical fruit's (measured +5.7 %: the drawn moduli and stresses are not symmetric about
    their library values).  A row carries one basis for its given bruise values: where the user's (a
    --bruise-basis, or the default of a bruise value they gave) differs from a library value's, that value is not
    drawn but kept at the library value, on its own basis, and the spreads say so (it was refused for a while)."""
    common = ("population", "--fruit", "apple", "--surface", "steel", "--drop-height", "20cm", "--criterion",
              "shear", "-n", "4000", "--seed", "3", "--characteristics", "bruise_volume")
    lot = cli.json(*common)["statistics"]["bruise_volume"]["percentiles"]["50"]
    identical = cli.json(*common, "--no-spreads")["statistics"]["bruise_volume"]["percentiles"]["50"]
    assert 0.9 < lot / identical < 1.1
    for more in (("--bruise-basis", "absorbed"), ("--bruise-energy", "0.05J")):
        report = cli.json(*common, *more)
        assert "bruise_susceptibility" not in report["inputs"]
        (line,) = [line for line in report["spreads"] if line.startswith("bruise_susceptibility:")]
        assert "not drawn" in line and "impact energy" in line and "absorbed" in line


def test_the_lot_median_is_the_library_value():
    """The spreads are split normals with their median at the library value (the library ranges are
    asymmetric about it: a symmetric normal truncated to the range moved the apple's median modulus 23 % up)."""
    from fruitimpact.impact.presets import lot_spreads

    for fruit in ("apple", "peach", "potato"):
        for name, dist in lot_spreads(fruit, []).distributions:
            draws = dist.draw(np.random.default_rng(2), 100_000)
            value = getattr(fruits()[fruit], name)
            # the median of 1e5 draws is within ~0.4 % of the sd of the true median; 2 % of the range is ample
            assert abs(np.median(draws) - value.value) < 0.02 * (value.high - value.low), (fruit, name)
            assert draws.min() >= value.low and draws.max() <= value.high


def test_kelvin_voigt_answers_the_energy_criterion():
    """No Hertz pressure, but the energy criterion needs none (before: NaN bruised, status ok)."""
    frame = batch.evaluate({"fruit": ["apple"], "model": ["kelvin-voigt"], "criterion": ["energy"],
                            "drop_height": [0.3]})
    assert frame.loc[0, "status"] == "ok" and frame.loc[0, "bruised"] == 1.0
    assert frame.loc[0, "bruise_volume"] > 0


def test_a_board_that_bottoms_before_its_crush_stress_is_the_plain_layer():
    """A crush depth σ_c/k beyond the thickness: the board bottoms out first and never crushes (before: the
    crush model ran anyway, with another peak force and a wrong warning)."""
    common = {"fruit": ["apple"], "surface": ["cardboard"], "surface_thickness": [0.0015], "drop_height": [1.0]}
    plain = batch.evaluate({**common, "surface_crush_stress": [math.inf]})
    never = batch.evaluate({**common, "surface_crush_stress": [1e12]})
    assert never.loc[0, "peak_force"] == plain.loc[0, "peak_force"]
    assert "the board crushes" not in never.loc[0, "warnings"]


def test_an_estimated_onset_energy_is_said():
    """W_th = W_f (σ/q)^5 is exact only for elastic contact at a fixed e: plastic rows warn."""
    frame = batch.evaluate({"fruit": ["apple"] * 2, "criterion": ["shear"] * 2, "drop_height": [0.3] * 2,
                            "yield_pressure": [math.inf, 3.2e5]})
    assert "Hertz-scaling estimate" not in frame.loc[0, "warnings"]
    assert "Hertz-scaling estimate" in frame.loc[1, "warnings"]


def test_the_bruise_width_ratio_is_the_fruits_own():
    """Issue 14 item 5d: the contact-to-bruise width ratio 1.4 was measured on pears (Stropek & Gołacki 2020)
    and was applied to every fruit.  Now: pear w = 2a/1.4 (the cap of that width holding the volume sets the
    depth, Johnson-free geometry: V = π d (3w² + 4d²)/24); an apple has no ratio of its own, so its bruise
    depth and width are unknown (NaN, a warning) unless one is given."""
    frame = batch.evaluate({"fruit": ["pear", "apple", "apple"], "criterion": ["energy"] * 3,
                            "bruise_energy": [0.01] * 3, "drop_height": [0.2] * 3,
                            "bruise_width_ratio": [None, None, 2.0]})
    pear, apple, given = (frame.loc[k] for k in range(3))
    assert pear["bruise_width"] == pytest.approx(2 * pear["contact_radius"] / 1.4, rel=1e-12)
    w, d = pear["bruise_width"], pear["bruise_depth"]
    assert math.pi * d * (3 * w ** 2 + 4 * d ** 2) / 24 == pytest.approx(pear["bruise_volume"], rel=1e-9)
    assert apple["bruise_volume"] > 0 and math.isnan(apple["bruise_width"]) and math.isnan(apple["bruise_depth"])
    assert "bruise_width_ratio is not in the apple entry" in apple["warnings"]
    assert given["bruise_width"] == pytest.approx(given["contact_radius"], rel=1e-12)


def test_each_fruit_has_the_criterion_its_literature_supports():
    """Issue 14 item 5c: the pressure criterion predicts apple bruising at ~1 mm drops and ~14 N, where plate and
    pendulum tests see none at 22 N (Fu et al. 2016) and 30 mm (Komarnicki & Stopa 2013); the shear criterion
    (a subsurface stress, Yuwana & Duprat 1998) puts the onset above both.  The library names it per fruit and
    `--criterion preset` (and safe-height / line without --criterion) takes it; a fruit with none is refused."""
    assert fruits()["apple"].criterion == "shear" and fruits()["pear"].criterion is None
    preset = safe_height(fruit="apple", sensitivity=False)
    assert preset["criterion"] == "shear"
    pressure = safe_height(fruit="apple", criterion="pressure", sensitivity=False)
    assert pressure["safe_height"] < 0.005 < 0.03 < preset["safe_height"]  # below vs above the 30 mm with no damage
    with pytest.raises(ValueError, match="names no bruise criterion"):
        safe_height(fruit="peach", failure_stress=2e5, sensitivity=False)
    frame = batch.evaluate({"fruit": ["apple", "pear"], "criterion": ["preset"] * 2, "drop_height": [0.1] * 2})
    assert frame.loc[0, "criterion"] == "shear" and frame.loc[0, "status"] == "ok"
    assert frame.loc[1, "status"] == "invalid" and "--criterion" in frame.loc[1, "message"]


def test_a_flattened_spot_never_carries_more_than_the_yield_pressure():
    """Issue 14 item 8 (the defect): the later impacts of a drop reloaded the flattened spot as Hertz on R_p with
    no limit, and Thornton's unloading profile at F* peaks at 3F* p_y/(2F* + F_y), up to 1.5 p_y: more than the
    flesh carries.  Pure Thornton (model hertz, no viscous stress), 30 cm onto steel: every impact's contact
    pressure is at most p_y (to rounding), the spot yielding again where the reload would pass it; energy still
    balances (released = absorbed + left)."""
    report = drop(0.3, model="hertz", yield_pressure=3.2e5, fruit="apple")
    impacts = report["impacts"]
    assert len(impacts) > 2
    assert all(i["max_pressure"] <= 3.2e5 * (1 + 1e-9) for i in impacts)
    released = impacts[0]["velocity"] ** 2 / 2 * 0.18
    assert report["total_absorbed_energy"] + report["energy_left"] == pytest.approx(released, rel=1e-9)


@pytest.mark.parametrize("inputs", [dict(), dict(fruit="apple", surface="steel", criterion="shear"),
                                    dict(bounces="constant"), dict(model="lankarani-nikravesh", restitution=0.4)])
def test_bounces_evaluated_together_are_the_bounces_one_by_one(monkeypatch, inputs):
    """Issue 15 item 4: an elastic drop's later impacts are predicted (e a closed form of c V for the power-law
    family) and evaluated in one table; each prediction is checked against the rebound the impact before really
    had.  The result must be the one-by-one drop's to rounding (1e-12: one table row and one single-row table
    run the same kernel)."""
    from fruitimpact.handling import drops

    together = drops.drop("40cm", **inputs)
    monkeypatch.setattr(drops, "_bounces_at_once", lambda *args: None)
    alone = drops.drop("40cm", **inputs)
    assert together["impact_count"] == alone["impact_count"] > 3
    assert together["warnings"] == alone["warnings"] and together["status"] == alone["status"]
    for a, b in zip(together["impacts"], alone["impacts"]):
        for key, value in a.items():
            if isinstance(value, float) and math.isfinite(value):
                assert value == pytest.approx(b[key], rel=1e-12, abs=1e-300), key
            else:
                assert value == b[key] or (value != value and b[key] != b[key]), key
