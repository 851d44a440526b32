"""fit-damage (issue 18 item 4): the bruise threshold energy, bruise susceptibility and failure stress fitted to drop
or pendulum tests by maximum likelihood with unbruised fruit censored, their 95 % intervals, the fitted fruit as a
fruit file, and that file accepted by every command's --fruit.

Every test names its reference and why its tolerance is what it is.  The synthetic truths are drawn here with
numpy from the model the fit assumes (damage/fitting.py): each fruit's threshold lognormal around W_th, bruise
volume BS (W − T) with lognormal scatter; the published set is the one the library's apple susceptibility comes
from (docs/library.md [6], docs/validation-damage.md row A8), and what it can show is said in its test.

W is the energy the simulator compares with the fitted values: the fruit's share of the impact energy on the test's
surface (on steel 1 − 1e-5 of m g h, ``steel_share`` below, computed here from the library's moduli).  A truth
drawn on m g h onto steel is therefore the fit's truth to 1e-5, far inside every tolerance here."""

from __future__ import annotations

import csv
import json
import math
from importlib import resources

import numpy as np
import pytest

import fruitimpact as fi
from fruitimpact.damage import fitting
from fruitimpact.handling import droptests
from fruitimpact.library import catalogue

#: Standard gravity [m/s²] (CGPM 1901), written here for independent checks.
G = 9.80665
#: The synthetic truth: an apple-like lot (BS 4.5 cm³/J and W_th 0.06 J, the order of the library apple's 4.66 cm³/J
#: and 0.08 J), thresholds spread 25 % and volumes 20 % (lognormal σ).
TRUTH = dict(susceptibility=4.5e-6, threshold=0.06, spread=0.25, scatter=0.2)
HEIGHTS_CM = (1.5, 2.5, 3.5, 5, 7, 10, 14, 20, 28, 40, 55)


def lognormal_pdf(x: float, sigma: float, median: float) -> float:
    """The lognormal density [1/unit of x], written out (scipy.stats' is the same, 50 times slower in quad)."""
    if x <= 0.0:
        return 0.0
    z = math.log(x / median) / sigma
    return math.exp(-0.5 * z * z) / (x * sigma * math.sqrt(2.0 * math.pi))


def drop_tests(seed: int, per_height: int = 8, outcome: str = "bruise_volume", truth=TRUTH) -> dict:
    """Synthetic drop tests onto steel: ``per_height`` fruit of 180 ± 15 g at each height of ``HEIGHTS_CM``."""
    rng = np.random.default_rng(seed)
    heights = np.repeat(np.array(HEIGHTS_CM) / 100.0, per_height)
    mass = rng.normal(0.18, 0.015, heights.size)
    energy = mass * G * heights
    thresholds = truth["threshold"] * np.exp(truth["spread"] * rng.standard_normal(heights.size))
    volume = np.where(energy > thresholds, truth["susceptibility"] * (energy - thresholds)
                      * np.exp(truth["scatter"] * rng.standard_normal(heights.size)), 0.0)
    result = volume if outcome == "bruise_volume" else (volume > 0.0).astype(int)
    return {"drop_height": heights.tolist(), "surface": "steel", "mass": mass.tolist(), outcome: result.tolist()}


def steel_share() -> float:
    """The fruit's share of the impact energy on the steel plate, written out: the share of the contact's
    compliance that is the apple's, (1 − ν₁²)/E₁ over (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂ (Hertz, Johnson 1985 §4.2), from the
    library's apple and steel."""
    apple, steel = catalogue.fruit("apple"), catalogue.surface("steel")
    fruit = (1 - apple.poisson.value ** 2) / apple.modulus.value
    return fruit / (fruit + (1 - steel.poisson.value ** 2) / steel.modulus.value)


def compared_energy(fruit, surface: str, drop_height: float, mass: float | None = None) -> float:
    """The energy the simulator compares with an impact-basis threshold, read from ``fi.evaluate``'s own outputs:
    ½ m V² times the fruit's share, fruit_energy / absorbed_energy (the columns of docs/damage.md), a path through
    the outputs independent of the fit's (which reads the energy criterion's margin)."""
    row = {"fruit": str(fruit), "surface": surface, "drop_height": drop_height, "criterion": "none"}
    if mass is not None:
        row["mass"] = mass
    out = fi.evaluate({k: [v] for k, v in row.items()})
    share = float(out["fruit_energy"][0] / out["absorbed_energy"][0])
    return 0.5 * float(out["mass"][0]) * float(out["velocity"][0]) ** 2 * share


def write_csv(path, header, rows):
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return path


# ------------------------------------------------------------------------------- (1) recovery of a known truth

@pytest.mark.slow
def test_recovers_a_known_susceptibility_and_threshold_with_intervals_that_cover_them():
    """Ten synthetic lots of 88 drop tests each.  Tolerances: BS within 10 % and W_th within 30 % in every lot (the
    issue's); with 88 tests, about 60 bruised, σ_v = 0.2 gives BS a standard error near 0.2/√60 ≈ 2.6 %, so 10 %
    is almost 4 standard errors (a 40-lot run of this design, seeds 0–39: BS error mean +0.1 %, sd 3.2 %, at most
    7.8 %; W_th mean +1.0 %, sd 6.2 %, at most 16 %).  Coverage: a 95 % interval holds the truth in 95 % of lots;
    over ten lots at least 8 must (with a true 95 %, P(at most 7 of 10) = 1.2 %).  The 40-lot run covered 38 of
    40 (BS) and 36 of 40 (W_th), inside the binomial range of a true 95 % (docs/tasks/fit-damage.md)."""
    covered = {"bruise_susceptibility": 0, "bruise_energy": 0}
    truth = {"bruise_susceptibility": TRUTH["susceptibility"], "bruise_energy": TRUTH["threshold"]}
    errors = []
    for seed in range(10):
        report = fi.fit_damage(drop_tests(seed), fruit="apple", criterion="none")
        assert report["status"] == "ok", report["message"]
        assert report["basis"] == "impact"
        bs_error = report["bruise_susceptibility"] / truth["bruise_susceptibility"] - 1.0
        th_error = report["bruise_energy"] / truth["bruise_energy"] - 1.0
        errors.append((bs_error, th_error))
        assert abs(bs_error) < 0.10, (seed, bs_error)
        assert abs(th_error) < 0.30, (seed, th_error)
        for name, value in truth.items():
            covered[name] += report[f"{name}_low"] <= value <= report[f"{name}_high"]
    print(f"largest errors: BS {max(abs(e[0]) for e in errors):.1%}, W_th {max(abs(e[1]) for e in errors):.1%}; "
          f"coverage {covered}")
    assert covered["bruise_susceptibility"] >= 8 and covered["bruise_energy"] >= 8, covered


@pytest.mark.slow
def test_bruised_or_not_gives_the_threshold_and_no_susceptibility():
    """0/1 outcomes of lots of the same design: the probit's 50 % point is W_th.  Tolerance 30 % (the issue's); 0/1
    data carry less than volumes: a 40-lot run (seeds 100–139) gave an error sd of 9 %, at most 24.5 %, and 37 of 40
    covered, so at least 8 of 10 here (as above).  BS is null with a message: 0/1 data have no volume."""
    covered = 0
    for seed in range(10):
        report = fi.fit_damage(drop_tests(100 + seed, outcome="bruised"), fruit="apple", criterion="none")
        assert report["status"] == "ok"
        assert abs(report["bruise_energy"] / TRUTH["threshold"] - 1.0) < 0.30
        covered += report["bruise_energy_low"] <= TRUTH["threshold"] <= report["bruise_energy_high"]
        assert report["bruise_susceptibility"] is None and report["bruise_susceptibility_low"] is None
        assert any(w.startswith("bruise susceptibility: null") for w in report["warnings"])
    assert covered >= 8, covered


def test_the_volume_likelihood_is_the_integral_over_each_fruits_threshold():
    """The quadrature of ``_volume_terms`` (in the threshold's normal variable z, around the integrand's peak)
    against the integral as the model defines it, ∫₀^W f_T(t) f_V(BV | BS (W − t)) dt in t, summed by scipy's
    adaptive quad with breakpoints at both densities' centres and ±1…8 of their widths (without them quad
    misses the volume density's peak when it is narrow and close to t = W).  Tolerance 0.01 in ln p where
    ln p > −50 (a test the parameters explain at all): a 0.01 error per test moves 2 Δℓ by far less than the
    interval's resolution; below that, only that the value is below −40 (such parameters are far from any
    maximum: the fit never rests there)."""
    from scipy import integrate

    checked = 0
    for bs, threshold, spread, scatter in ((5e-6, 0.06, 0.25, 0.3), (5e-6, 0.06, 0.05, 0.05), (4e-6, 0.1, 1.0, 0.5),
                                           (5e-6, 0.06, 0.02, 0.3), (5e-6, 0.06, 0.3, 0.02)):
        theta = (math.log(bs), math.log(threshold), math.log(spread), math.log(scatter))
        for energy in (0.03, 0.05, 0.08, 0.3):
            for volume in (1e-9, 2e-8, 1e-7, 5e-7):
                def integrand(t):
                    return lognormal_pdf(t, spread, threshold) * lognormal_pdf(volume, scatter, bs * (energy - t))
                excess = volume / bs
                points = [threshold * math.exp(k * spread) for k in range(-8, 9)] + \
                    [energy - excess * math.exp(k * scatter) for k in range(-8, 9)]
                points = sorted(p for p in points if 0.0 < p < energy)
                reference = sum(integrate.quad(integrand, a, b, limit=200, epsabs=0.0, epsrel=1e-10)[0]
                                for a, b in zip([0.0] + points, points + [energy]))
                got = fitting._volume_terms(theta, np.array([math.log(energy)]), np.array([math.log(volume)]),
                                            np.array([]))
                if reference > math.exp(-50.0):
                    assert got == pytest.approx(math.log(reference), abs=0.01), (theta, energy, volume)
                    checked += 1
                else:
                    assert got < -40.0
    assert checked > 40


def test_the_maximum_is_the_maximum_of_an_independent_likelihood():
    """The fit's estimate against scipy's Nelder–Mead on the likelihood written here independently (the lognormal
    density written out, scipy's norm and quad for each bruised fruit), started at the fit's estimate: it must
    find no better point by more than 0.02 in ℓ (the quadrature's error over 33 tests, above) nor move the
    estimates by more than 2 % (a fraction of their 10–20 % intervals)."""
    from scipy import integrate, optimize, stats

    data = drop_tests(7, per_height=3)
    energy = np.array(data["mass"]) * G * np.array(data["drop_height"])
    volume = np.array(data["bruise_volume"])
    fit = fitting.fit_volumes(energy, volume)
    estimate = np.log([fit.estimates[k] for k in ("bruise_susceptibility", "bruise_energy", "threshold_spread",
                                                  "volume_scatter")])

    def negative(theta):
        bs, threshold, spread, scatter = np.exp(theta)
        total = 0.0
        for w, v in zip(energy, volume):
            if v == 0.0:
                total += stats.norm.logsf(math.log(w / threshold) / spread)
                continue
            value, _ = integrate.quad(lambda t: lognormal_pdf(t, spread, threshold)
                                      * lognormal_pdf(v, scatter, bs * (w - t)), 0.0, w,
                                      points=[p for p in (threshold, w - v / bs) if 0 < p < w], limit=200)
            total += math.log(max(value, 1e-300))
        return -total

    at_fit = negative(estimate)
    assert at_fit == pytest.approx(-fit.log_likelihood, abs=0.02)
    better = optimize.minimize(negative, estimate, method="Nelder-Mead",
                               options={"xatol": 1e-4, "fatol": 1e-5, "maxfev": 400})
    assert at_fit - better.fun < 0.02
    assert np.all(np.abs(better.x[:2] - estimate[:2]) < 0.02), (better.x, estimate)


def test_log_ndtr_matches_scipy_in_both_tails():
    """``log_ndtr`` against scipy.special.log_ndtr from −60 to 40: 1e-12 relative (erfc down to −37, there 1e-296;
    below, the asymptotic series, whose first omitted term, 945/x¹⁰, is below 2e-13 of the result)."""
    from scipy.special import log_ndtr

    x = np.concatenate([np.linspace(-60, 40, 2001), [-37.0000001, -36.9999999]])
    assert np.allclose(fitting.log_ndtr(x), log_ndtr(x), rtol=1e-12, atol=1e-300)


# --------------------------------------------------------------------------- (2) the published set reproduced

def test_reproduces_the_khorasan_pendulum_susceptibility_the_library_apple_holds():
    """"Determination and Comparison of Susceptibility of Different Apple Varieties (KHORASAN Region) to Impact
    Damage", Int. J. Biosystems Eng. (ijbse.ut.ac.ir article 35202), abstract: five cultivars hit by a pendulum at
    0.276, 0.590 and 0.976 J (impact energies); mean bruise susceptibility 3.71 (Abbasi), 3.95 (red Lobnani), 4.12
    (yellow Lobnani), 5.29 (Golshahi) and 6.23 (Aroos) ml/J.  The library apple's 4.66 cm³/J is their mean
    (docs/library.md; validation-damage.md A8).  The abstract gives no per-fruit volumes, so the table is the
    cultivar means at each energy, BV = BS_c · E (the definition BS = BV/E; docs/library.md notes the defining
    equation was not read): 15 pendulum tests, all bruised.

    What this can and cannot show.  The table is rebuilt from the published means with BV = BS·E, so it is
    circular for BS: it shows that the fit, the pendulum path (``energy`` as given, the steel impactor's share) and
    the units reproduce a published susceptibility to a few %, and that a table with every test bruised bounds the
    threshold from above only (no threshold, no failure stress).  It cannot show that the threshold, the spreads or
    the censored likelihood are right on real fruit: there is no unbruised test and no near-threshold impact in it.
    No published per-fruit (or per-energy) table with near-threshold impacts was found to take its place (searched:
    Słupska et al., Materials 15 (2022) 139, apples dropped 10–150 mm; Shen & Shan, UBC undergraduate report, Royal
    Gala threshold 0.08 J; Jarimopas et al., bruise probability vs pendulum energy; Stropek & Gołacki 2020; Pathare &
    Al-Dairi 2021: their abstracts give summary values only, not the tests); the threshold and the intervals are
    checked on synthetic lots drawn from known truths above.

    Expected: BS within 5 % of 4.66 cm³/J and inside the cultivar spread 3.71–6.23 (the model's pooled estimate lies
    between the geometric, 4.57, and arithmetic, 4.66, means of the five depending on how much of the cultivar
    difference the threshold spread absorbs: 2 % apart, so 5 %), its 95 % interval holding 4.66; the threshold
    bounded only from above, below the lowest energy 0.276 J (every test bruised: the abstract says the lowest
    energy bruised even the least susceptible cultivars), so no threshold and no failure stress."""
    cultivars = {"Abbasi": 3.71, "red Lobnani": 3.95, "yellow Lobnani": 4.12, "Golshahi": 5.29, "Aroos": 6.23}
    energies = (0.276, 0.590, 0.976)
    table = {"energy": [f"{e}J" for _ in cultivars for e in energies], "surface": "steel", "mass": "180g",
             "bruise_volume": [f"{bs * e:.6f}ml" for bs in cultivars.values() for e in energies]}
    report = fi.fit_damage(table, fruit="apple")
    assert report["status"] == "ok" and report["tests"] == 15 and report["bruised"] == 15
    assert report["basis"] == "impact" and "pendulum" in report["basis_note"]
    bs = report["bruise_susceptibility"] * 1e6
    assert bs == pytest.approx(4.66, rel=0.05)
    assert 3.71 <= bs <= 6.23
    assert report["bruise_susceptibility_low"] * 1e6 <= 4.66 <= report["bruise_susceptibility_high"] * 1e6
    assert report["bruise_energy"] is None and report["bruise_energy_low"] is None
    assert report["bruise_energy_high"] < 0.276
    assert report["failure_stress"] is None
    assert any("do not bound the threshold energy from below" in w for w in report["warnings"])


# ------------------------------------------------------------------------------------------ (3) refusals

def test_the_function_returns_what_json_prints_and_is_documented(cli, tmp_path):
    """``fi.fit_damage`` is the command (one path): its dict, as JSON, is ``--json``'s object, with at least the
    issue's keys; its docstring has the sections of every task function (tests/test_api.py's rule)."""
    from fruitimpact.impact.outputs import dump_json

    data = drop_tests(4, per_height=3)
    path = write_csv(tmp_path / "lot.csv", list(data), zip(*[data[k] if isinstance(data[k], list) else
                                                             [data[k]] * len(data["mass"]) for k in data]))
    printed = cli.json("fit-damage", path, "--fruit", "apple")
    assert printed == json.loads(dump_json(fi.fit_damage(str(path), fruit="apple")))
    for key in ("bruise_susceptibility", "bruise_energy", "failure_stress"):
        assert {key, f"{key}_low", f"{key}_high"} <= set(printed)
    assert {"basis", "tests", "bruised", "status", "message", "warnings"} <= set(printed)
    doc = fi.fit_damage.__doc__
    assert all(f"{section}\n    ---" in doc for section in ("Parameters", "Returns", "Raises", "Examples",
                                                             "References"))



REFUSED = [
    ("no outcome", ["drop_height", "surface", "mass"], [["0.1", "steel", "0.18"]], "no outcome column"),
    ("two outcomes", ["drop_height", "surface", "mass", "bruised", "bruise_volume"],
     [["0.1", "steel", "0.18", "1", "1e-7"]], "one outcome column, not 2"),
    ("no energy", ["surface", "mass", "bruised"], [["steel", "0.18", "1"]], "give drop_height [m]"),
    ("unknown column", ["drop_height", "surface", "mass", "bruised", "colour"], [["0.1", "steel", "0.18", "1", "red"]],
     "unknown column(s) 'colour'"),
    ("unknown surface", ["drop_height", "surface", "mass", "bruised"], [["0.1", "granite", "0.18", "1"]],
     "line 2: surface must be one of rigid, steel"),
    ("no mass column", ["drop_height", "surface", "bruised"], [["0.1", "steel", "1"]], "the mass column is missing"),
    ("no usable row", ["drop_height", "surface", "mass", "bruised"], [["-1", "steel", "0.18", "1"],
                                                                     ["abc", "steel", "0.18", "0"]],
     "no usable test: every row was refused (the first: "),
    ("header only", ["drop_height", "surface", "mass", "bruised"], [], "no tests below the header"),
]


@pytest.mark.parametrize("case, header, rows, message", REFUSED, ids=[c[0] for c in REFUSED])
def test_a_bad_table_is_refused_with_one_line_and_the_same_value_error(cli, tmp_path, case, header, rows, message):
    """The CLI's refusal (exit 2, one line, no traceback: conftest's ``cli.error``) is the library's ValueError
    with the argument named, before any work (issue 18 item 4; README "Bad input is refused ...")."""
    path = write_csv(tmp_path / "tests.csv", header, rows)
    line = cli.error("fit-damage", path)
    assert message in line, line
    with pytest.raises(ValueError) as info:
        fi.fit_damage(str(path))
    assert line == f"fruitimpact fit-damage: error: argument TESTS: {info.value}"


@pytest.mark.parametrize("argv, message", [
    (("--fruit", "nowhere.csv"), "argument --fruit: fruit must be one of jonathan-apple"),
    (("--fruit", "folder.csv"), "argument --fruit: fruit must be one of jonathan-apple, apple, pear, peach, tomato, "
                                "potato, kiwifruit or a fruit file (.csv); 'folder.csv' is a directory, not a file"),
    # the CLI refuses an output over any file it reads (cli.common.check_outputs) before the library's own check
    (("-o", "tests.csv"), "argument -o/--output: 'tests.csv' is the file TESTS the command reads: write to another "
                          "file"),
    (("-o", "./sub/../tests.csv"), "argument -o/--output: './sub/../tests.csv' is the file TESTS the command reads"),
    (("--fruit", "banana"), "argument --fruit: fruit must be one of jonathan-apple"),
    (("--criterion", "bend"), "argument --criterion: criterion must be one of"),
    (("--name", "Fitted Apple"), "argument --name: the fitted fruit's name must be lower-case"),
    (("--name", "apple"), "must not be a library fruit's"),
    (("-o", "fitted.parquet"), "argument -o/--output: cannot write 'fitted.parquet': unsupported format"),
])
def test_bad_options_are_refused_naming_them(cli, tmp_path, monkeypatch, argv, message):
    """Every option checked before the fit, with the project's own words (``check_choice``, ``check_output``): a
    directory given as --fruit is said to be one (review item 15), and an output that is the table of tests itself,
    however spelt, is refused and the table left as it was (review item 4)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder.csv").mkdir()
    (tmp_path / "sub").mkdir()
    path = write_csv(tmp_path / "tests.csv", ["drop_height", "surface", "mass", "bruised"],
                     [["0.1", "steel", "0.18", "1"]])
    before = path.read_bytes()
    assert message in cli.error("fit-damage", "tests.csv", *argv)
    assert path.read_bytes() == before
    if argv[0] == "-o" and "tests.csv" in argv[1]:
        with pytest.raises(ValueError, match="is the table of tests itself"):
            fi.fit_damage("tests.csv", output=argv[1])


def test_rows_with_bad_values_are_skipped_and_reported(cli, tmp_path):
    """Like ``batch``: a bad row gets its message and never stops the others; units in cells are read
    (impact.units: "3cm", "180g", "75mm", "120mm3")."""
    data = drop_tests(3, per_height=4)
    rows = [[f"{h * 100:g}cm", "steel", f"{m * 1e3:.3f}g", "75mm", f"{v * 1e9:.6f}mm3"]
            for h, m, v in zip(data["drop_height"], data["mass"], data["bruise_volume"])]
    bad = [["-2cm", "steel", "180g", "75mm", "0"], ["5cm", "steel", "heavy", "75mm", "0"],
           ["5cm", "steel", "180g", "75mm", "-3mm3"], ["5cm", "steel", "180g"]]
    path = write_csv(tmp_path / "tests.csv", ["drop_height", "surface", "mass", "diameter", "bruise_volume"],
                     rows + bad)
    report = cli.json("fit-damage", path, "--fruit", "apple")
    assert report["tests"] == len(rows)
    assert [r["row"].rsplit(" ", 1)[1] for r in report["rows_skipped"]] == [str(len(rows) + k) for k in (2, 3, 4, 5)]
    messages = [r["message"] for r in report["rows_skipped"]]
    assert messages[0].startswith("drop_height must be a finite number > 0 m")
    assert messages[1].startswith("mass must be a number")
    assert messages[2].startswith("bruise_volume must be >= 0")
    assert messages[3] == "3 fields, the header has 5"


def test_a_pendulum_table_uses_the_given_energy_and_says_so(tmp_path):
    """energy [J] is the impact energy as given (a pendulum's), not m g h: the same volumes at the same energies
    fit the same BS whatever the mass column says (the mass only enters the failure stress)."""
    data = drop_tests(5, per_height=4)
    energy = [m * G * h for m, h in zip(data["mass"], data["drop_height"])]
    pendulum = {"energy": [f"{e * 1e3:.9f}mJ" for e in energy], "surface": "steel", "mass": 0.3,
                "bruise_volume": data["bruise_volume"]}
    one = fi.fit_damage(pendulum, fruit="apple", criterion="none")
    two = fi.fit_damage(data, fruit="apple", criterion="none")
    assert one["basis_note"].startswith("the fruit's share of the impact energy (the pendulum's energy, 44 tests)")
    # on steel the share is the moduli's, whatever the speed: 1 − 1e-5 (steel_share), to rounding
    assert one["energy_share_by_surface"]["steel"]["min"] == pytest.approx(steel_share(), rel=1e-9)
    assert one["energy_share_by_surface"]["steel"]["max"] == pytest.approx(steel_share(), rel=1e-9)
    assert one["bruise_susceptibility"] == pytest.approx(two["bruise_susceptibility"], rel=1e-6)
    assert one["bruise_energy"] == pytest.approx(two["bruise_energy"], rel=1e-6)


def test_a_bruise_diameter_becomes_the_cap_of_the_librarys_bruise_geometry():
    """bruise_diameter → volume (review item 5): the spherical cap π d (3 w² + 4 d²)/24 (docs/bruise.md, written out
    here) of width w = D whose depth keeps the library's bruise shape of that impact, 2.5 δ_max deep (Stropek
    & Gołacki 2020) for the library's width 2a/1.4 (``bruise_geometry``, the same study): d = 2.5 δ_max w/(2a/1.4),
    at most w/2 (a hemisphere).  δ_max and a from ``fi.simulate`` of that test (the fruit's flesh, the test's mass,
    diameter and speed √(2 W/m)).  So the depth scales with the width: a 1 mm bruise is 1/15 as deep as a 15 mm one
    from the same impact, not 2.5 δ_max deep like it.  Tolerance 1e-9 relative: the same engine, two paths."""
    table = droptests.read_tests({"drop_height": ["10cm", "3cm", "20cm", "10cm", "1cm"],
                                  "surface": ["steel", "wood", "steel", "steel", "foam-pad"],
                                  "mass": ["180g", "175g", "190g", "180g", "180g"],
                                  "diameter": ["75mm", "", "80mm", "75mm", ""],
                                  "bruise_diameter": ["18mm", "0", "25mm", "1.2mm", "3mm"]})
    volumes, ok, failed = droptests.impacts._diameter_volumes(table, "apple")
    assert ok.all() and not failed
    shapes = []
    for k in range(5):
        energy = table.mass[k] * G * [0.10, 0.03, 0.20, 0.10, 0.01][k]
        kwargs = {} if math.isnan(table.diameter[k]) else {"diameter": table.diameter[k]}
        result = fi.simulate("apple", surface=table.surface[k], mass=table.mass[k],
                             velocity=math.sqrt(2.0 * energy / table.mass[k]), **kwargs).characteristics
        width = table.value[k]
        shape = min(2.5 * result.max_deflection / (2 * result.contact_radius / 1.4), 0.5)
        shapes.append(shape)
        depth = shape * width
        cap = math.pi * depth * (3 * width ** 2 + 4 * depth ** 2) / 24 if width > 0 else 0.0  # 0: not bruised
        assert volumes[k] == pytest.approx(cap, rel=1e-9, abs=0)
    assert volumes[3] / volumes[0] == pytest.approx((1.2 / 18) ** 3, rel=1e-9)  # same impact: the shape is kept
    assert 0.0 < min(shapes) < 0.5 and max(shapes) == 0.5  # both ends met: a shallow cap, and the hemisphere bound
    report = fi.fit_damage({"drop_height": [0.03, 0.05, 0.1, 0.15, 0.2, 0.3], "surface": "steel", "mass": 0.18,
                            "bruise_diameter": [0, 0.008, 0.014, 0.017, 0.02, 0.024]}, fruit="apple")
    assert report["status"] == "ok" and report["volume_conversion"].startswith("bruise volume = the spherical cap")
    assert any(w.startswith("bruise volumes derived from bruise diameters") for w in report["warnings"])


def test_a_bruise_wider_or_larger_than_the_fruit_is_refused_for_its_row():
    """A bruise diameter beyond the fruit's own (its diameter column, else the --fruit's: the apple's 75 mm), and a
    bruise volume beyond the fruit's own volume π d³/6, are impossible: the row is refused, naming the column and
    the value, and the others are fitted (review items 5 and 9)."""
    data = drop_tests(2, per_height=3)
    diameters = [0.0 if v == 0 else 0.012 for v in data["bruise_volume"]]
    table = {"drop_height": data["drop_height"] + [0.2, 0.2, 0.2], "surface": "steel",
             "mass": data["mass"] + [0.18] * 3, "diameter": [None] * len(diameters) + [0.07, None, None],
             "bruise_diameter": diameters + [0.071, 0.076, 0.02]}
    report = fi.fit_damage(table, fruit="apple", criterion="none")
    skipped = {r["row"]: r["message"] for r in report["rows_skipped"]}
    n = len(diameters)
    assert skipped == {f"tests row {n + 1}": "bruise_diameter must not exceed the fruit's diameter 0.07 m; got 0.071",
                       f"tests row {n + 2}": "bruise_diameter must not exceed the --fruit's diameter 0.075 m; got "
                                             "0.076"}
    volume = {"drop_height": [0.1, 0.2, 0.3, 0.4], "surface": "steel", "mass": 0.18,
              "bruise_volume": ["0", "200mm3", "1e9mm3", "500mm3"]}
    report = fi.fit_damage(volume, fruit="apple", criterion="none")
    assert [r["message"] for r in report["rows_skipped"]] == [
        f"bruise_volume must not exceed the volume of the fruit itself, {math.pi * 0.075 ** 3 / 6:.4g} m³ (a sphere "
        f"of the --fruit's diameter 0.075 m); got '1e9mm3'"]


def test_fits_from_diameters_recover_the_truth_as_fits_from_volumes_do():
    """The recovery check of volumes (above), redone with diameters (review item 5): each synthetic lot's volumes
    are turned into the diameters the conversion reads back (w from the cap of the impact's shape k, V =
    π k w³ (3 + 4 k²)/24, k from ``fi.simulate`` of each test as above), and fitted.  Reference: the volume fit of
    the same lot, to 1e-4 relative (the diameters round-trip the volumes to 1e-12; the rest is the optimiser's
    tolerance), and the truth within the recovery test's tolerances (BS 10 %, W_th 30 %)."""
    for seed in (30, 31):
        data = drop_tests(seed, per_height=6)
        heights, masses = np.array(data["drop_height"]), np.array(data["mass"])
        widths = []
        for h, m, v in zip(heights, masses, data["bruise_volume"]):
            c = fi.simulate("apple", surface="steel", mass=m, drop_height=h).characteristics
            k = min(2.5 * c.max_deflection * 1.4 / (2 * c.contact_radius), 0.5)
            widths.append((24 * v / (math.pi * k * (3 + 4 * k * k))) ** (1 / 3))
        volumes = fi.fit_damage(data, fruit="apple", criterion="none")
        diameters = fi.fit_damage({**{k: v for k, v in data.items() if k != "bruise_volume"},
                                   "bruise_diameter": widths}, fruit="apple", criterion="none")
        for key in ("bruise_susceptibility", "bruise_energy"):
            assert diameters[key] == pytest.approx(volumes[key], rel=1e-4), (seed, key)
        assert abs(diameters["bruise_susceptibility"] / TRUTH["susceptibility"] - 1) < 0.10
        assert abs(diameters["bruise_energy"] / TRUTH["threshold"] - 1) < 0.30


# ------------------------------------------------------------------ (4) the fitted fruit, a file for --fruit

@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """One fit of a synthetic lot, written with --output: (folder, the fit's JSON, the fruit file)."""
    from fruitimpact.cli import main

    folder = tmp_path_factory.mktemp("fit")
    data = drop_tests(11)
    tests = write_csv(folder / "lot.csv", ["drop_height", "surface", "mass", "bruise_volume"],
                      zip(data["drop_height"], ["steel"] * len(data["mass"]), data["mass"], data["bruise_volume"]))
    out = folder / "report.json"
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        status = main(["fit-damage", str(tests), "--fruit", "apple", "--criterion", "shear",
                       "-o", str(folder / "fitted.csv"), "--json"])
    assert status == 0
    out.write_text(buffer.getvalue())
    return folder, json.loads(buffer.getvalue()), folder / "fitted.csv"


def test_the_fitted_fruit_file_is_the_librarys_format_with_the_fitted_values(fitted):
    """The header is fruits.csv's own, the row loads with the library's checks, and its values are the fit's with
    sources "fitted by fruitimpact fit-damage to <file>, N tests", confirmed and derived; their ranges are the
    fruit-to-fruit spreads the fit found, ±2 lognormal σ (review item 16: a lot draws a library range as a
    split normal whose ends are ±2 sd, impact/presets.py ``lot_spreads``), written out here: W_th e^(±2 σ_t),
    BS e^(±2 σ_v), and the failure stress at W_th e^(±2 σ_t) through the same impact (σ_f ∝ W^(1/5) for an elastic
    Hertz impact, so its ends are W's to the 1/5 power, to 1e-3: the restitution's and steel's small departures
    from that law); the 95 % intervals of the estimates stay in the report and in the values' notes."""
    folder, report, path = fitted
    packaged = resources.files("fruitimpact.library").joinpath("data", "fruits.csv").read_text(encoding="utf-8")
    header = next(csv.reader([line for line in packaged.splitlines() if line and not line.startswith("#")]))
    written = next(csv.reader([line for line in path.read_text().splitlines() if not line.startswith("#")]))
    assert written == header
    entry = catalogue.read_fruit_file(path)
    assert entry.name == report["name"] == "apple-fitted-lot"
    for field, key in (("bruise_susceptibility", "bruise_susceptibility"), ("bruise_threshold_energy", "bruise_energy"),
                       ("failure_stress", "failure_stress")):
        value = getattr(entry, field)
        assert (value.value, value.low, value.high) == (report[key], *report["fruit_ranges"][key])
        assert f"95 % interval: [{report[f'{key}_low']:.6g}, {report[f'{key}_high']:.6g}]" in value.note
        assert value.confirmed and value.derived
        assert f"fitted by fruitimpact fit-damage to {folder / 'lot.csv'}, {report['tests']} tests" in value.source
    spread_t, spread_v = report["threshold_spread"], report["volume_scatter"]
    threshold, bs, stress = entry.bruise_threshold_energy, entry.bruise_susceptibility, entry.failure_stress
    assert (threshold.low, threshold.high) == pytest.approx(
        (threshold.value * math.exp(-2 * spread_t), threshold.value * math.exp(2 * spread_t)), rel=1e-12)
    assert (bs.low, bs.high) == pytest.approx((bs.value * math.exp(-2 * spread_v), bs.value * math.exp(2 * spread_v)),
                                              rel=1e-12)
    assert (stress.low, stress.high) == pytest.approx(
        (stress.value * math.exp(-0.4 * spread_t), stress.value * math.exp(0.4 * spread_t)), rel=1e-3)
    assert entry.bruise_susceptibility.basis == entry.bruise_threshold_energy.basis == "impact"
    assert entry.criterion == "shear"
    # a lot of it draws BS and σ_f from those ranges: a split normal, median the value, sd half the way to each end
    from fruitimpact.impact.presets import lot_spreads

    drawn = dict(lot_spreads(str(path), ()).distributions)
    assert "bruise_susceptibility" in drawn and "failure_stress" in drawn
    assert any(f"[{bs.low:g}, {bs.high:g}]" in line for line in lot_spreads(str(path), ()).described)
    apple = catalogue.fruit("apple")
    assert (entry.mass, entry.modulus, entry.poisson, entry.restitution) == \
        (apple.mass, apple.modulus, apple.poisson, apple.restitution)


def test_safe_height_drop_and_line_take_the_file_and_give_the_values_fitted(cli, fitted):
    """The fitted fruit in other commands: safe-height onto steel (the tests' surface) under shear is the drop whose
    compared energy, the fruit's share of m g h (``steel_share``), is the fitted W_th (the failure stress was fitted
    as the shear stress there): 1e-6, the root's tolerance 1e-9 and the bracket of the threshold's own root; drop and
    line count the bruise volume from that onset, BS (share · m g h − W_th) on the impact basis: 1e-4 (the
    Hertz-scaling onset estimate W (σ_f/τ)^5 is exact for an elastic contact on a half-space at a fixed restitution,
    docs/damage.md; only the rounding of the fitted stress is left)."""
    folder, report, path = fitted
    mass = catalogue.fruit("apple").mass.value
    share = steel_share()
    safe = cli.json("safe-height", "--fruit", path, "--surface", "steel", "--no-sensitivity")
    assert safe["criterion"] == "shear"
    assert safe["safe_height"] * mass * G * share == pytest.approx(report["bruise_energy"], rel=1e-6)
    height = 0.15
    expected = report["bruise_susceptibility"] * (share * mass * G * height - report["bruise_energy"])
    drop = cli.json("drop", "--fruit", path, "--surface", "steel", "--drop-height", f"{height}", "--criterion",
                    "shear")
    assert drop["impacts"][0]["bruise_volume"] == pytest.approx(expected, rel=1e-4)
    line = write_csv(folder / "line.csv", ["name", "drop_height", "surface"], [["tipper", "15cm", "steel"]])
    audit = cli.json("line", line, "--fruit", path, "-n", "20", "--no-spreads", "--alternatives", "none")
    assert audit["criterion"] == "shear"
    assert audit["points"][0]["incidence"] == 1.0
    assert audit["points"][0]["mean_bruise_volume"] == pytest.approx(expected, rel=1e-4)
    energy = cli.json("simulate", "--fruit", path, "--surface", "steel", "--drop-height", f"{height}", "--criterion",
                      "energy")
    # the energy criterion counts the fruit's share of the impact energy, the fit's own W: exact to rounding
    assert energy["bruise_volume"] == pytest.approx(expected, rel=1e-9)


def test_a_batch_column_and_fit_damage_itself_take_the_file(cli, fitted, tmp_path):
    """The ``fruit`` column of a batch, and fit-damage's own --fruit, accept the file like a library name."""
    folder, report, path = fitted
    rows = write_csv(tmp_path / "rows.csv", ["fruit", "drop_height", "surface", "criterion"],
                     [[str(path), "0.15", "steel", "energy"], ["apple", "0.15", "steel", "energy"]])
    cli.ok("batch", rows, "-o", tmp_path / "out.csv")
    with open(tmp_path / "out.csv", newline="") as handle:
        out = list(csv.DictReader(handle))
    assert [r["status"] for r in out] == ["ok", "ok"]
    assert float(out[0]["bruise_energy"]) == pytest.approx(report["bruise_energy"], rel=1e-12)
    again = cli.json("fit-damage", folder / "lot.csv", "--fruit", path, "--criterion", "none")
    assert again["fruit"] == str(path)
    assert again["bruise_energy"] == pytest.approx(report["bruise_energy"], rel=1e-9)


def test_a_rewritten_file_is_read_again(cli, tmp_path):
    """A long-lived process (the web app, a notebook) sees the file as it is now: a fit written twice to one path
    gives the second fit's threshold."""
    path = tmp_path / "fitted.csv"
    heights = []
    for truth in (0.05, 0.09):
        data = drop_tests(21, per_height=4, truth={**TRUTH, "threshold": truth})
        report = fi.fit_damage(data, fruit="apple", criterion="energy", name="apple-lot", output=path)
        safe = fi.safe_height(fruit=str(path), surface="steel", criterion="energy", sensitivity=False)
        heights.append(safe["safe_height"])
        # the energy criterion: the fruit's share of m g h on steel (as above), to the root's tolerance
        assert safe["safe_height"] * 0.18 * G * steel_share() == pytest.approx(report["bruise_energy"], rel=1e-6)
    assert heights[1] > heights[0]


def test_fruit_files_are_checked_like_the_library(tmp_path, cli):
    """read_fruit_file refuses what the library's loader refuses, and a file whose fruit takes a library fruit's
    name with other values is refused; the same values under the same name are the same fruit.  The library's
    listing stays the library's."""
    apple = catalogue.fruit("apple")
    good = tmp_path / "same.csv"
    good.write_text(catalogue.fruit_file_text(apple))
    assert catalogue.read_fruit_file(good) == apple
    assert cli.json("simulate", "--fruit", good, "--velocity", "1")["status"] == "ok"
    text = catalogue.fruit_file_text(apple)
    broken = {
        "extra.csv": text.replace("name,description", "colour,name,description", 1).replace("\napple,",
                                                                                              "\nred,apple,"),
        "two.csv": text + text.splitlines()[-1] + "\n",
        "range.csv": text.replace(",0.18,0.098,0.278,", ",0.5,0.098,0.278,"),
        "clash.csv": text.replace(",0.18,0.098,0.278,", ",0.2,0.098,0.278,"),
    }
    expected = {"extra.csv": "unknown column(s) 'colour'", "two.csv": "holds 2 rows",
                "range.csv": "outside its range", "clash.csv": "a fruit of the library with other values"}
    for name, content in broken.items():
        (tmp_path / name).write_text(content)
        line = cli.error("drop", "--fruit", tmp_path / name, "--drop-height", "10cm")
        assert line.startswith("fruitimpact drop: error: argument --fruit: ") and expected[name] in line, line
    assert "my-apple" not in list(catalogue.fruits())
    assert catalogue.FRUIT_COLUMNS == tuple(next(csv.reader([line for line in text.splitlines()
                                                              if not line.startswith("#")])))


def test_fruit_files_are_found_by_their_path_only(tmp_path, cli):
    """What a name means must not depend on what was loaded before (review item 7): a fruit file is found by its
    path, never by its fruit's name, so two files may name their fruits alike with other values (in either order)
    and a fitted fruit's bare name is no fruit, before or after its file was used; refitting to a new file under
    the same name in one session is no clash."""
    text = catalogue.fruit_file_text(catalogue.fruit("apple"))
    first, other = tmp_path / "first.csv", tmp_path / "other.csv"
    first.write_text(text.replace("\napple,", "\nmy-apple,"))
    other.write_text(text.replace("\napple,", "\nmy-apple,").replace(",0.18,0.098,0.278,", ",0.2,0.098,0.278,"))
    assert "my-apple" not in catalogue.fruits()
    masses = [cli.json("simulate", "--fruit", path, "--velocity", "1")["mass"] for path in (first, other, first)]
    assert masses == [0.18, 0.2, 0.18]
    assert "my-apple" not in catalogue.fruits()
    line = cli.error("simulate", "--fruit", "my-apple", "--velocity", "1")
    assert "argument --fruit: fruit must be one of jonathan-apple" in line
    data = drop_tests(22, per_height=3)
    for k in (1, 2):
        report = fi.fit_damage(data, fruit="apple", criterion="energy", name="lab-apple", output=tmp_path / f"{k}.csv")
        assert report["output"] == str(tmp_path / f"{k}.csv")
    assert "lab-apple" not in catalogue.fruits()


def test_a_fruit_files_values_get_the_checks_of_the_options(tmp_path, cli):
    """A fruit file's values pass the checks the options they stand for get (review item 6): outside the allowed
    range, refused with one line naming --fruit, the file, the column and the value (the range ends too, which a
    lot draws from); outside the plausible range, the very warning --mass or --modulus gives, naming the file.
    Reference: ``INPUTS`` (impact/quantities.py): restitution in (0, 1], modulus finite > 0; mass plausible to
    20 kg, modulus to 1e8 Pa."""
    text = catalogue.fruit_file_text(catalogue.fruit("apple")).replace("\napple,", "\nodd-apple,")
    cases = {"restitution.csv": (",0.55,0.4,0.7,", ",1.5,0.4,1.6,", "restitution must be in (0, 1] (as --restitution "
                                                                    "must be); got 1.5"),
             "modulus.csv": (",2175000.0,2080000.0,4880000.0,", ",inf,2080000.0,inf,",
                             "modulus must be a finite number > 0 Pa (as --modulus must be); got inf"),
             "high.csv": (",0.55,0.4,0.7,", ",0.55,0.4,1.2,", "restitution_high must be in (0, 1] (as --restitution "
                                                             "must be); got 1.2")}
    for name, (old, new, message) in cases.items():
        assert old in text, old
        (tmp_path / name).write_text(text.replace(old, new, 1))
        line = cli.error("simulate", "--fruit", tmp_path / name, "--velocity", "1")
        assert line == f"fruitimpact simulate: error: argument --fruit: fruit file '{tmp_path / name}': {message}"
    heavy = tmp_path / "heavy.csv"
    heavy.write_text(text.replace(",0.18,0.098,0.278,", ",50.0,0.098,60.0,", 1))
    status, out, err = cli.run("simulate", "--fruit", heavy, "--velocity", "1")
    _, _, option = cli.run("simulate", "--mass", "50", "--velocity", "1")
    expected = "mass = 50 kg is outside the plausible range for fruit, [0.001, 20] kg; a plain number is read in kg"
    assert status == 0 and expected in option
    lines = [line for line in err.splitlines() if expected in line]
    assert lines == [f"fruitimpact simulate: warning: {expected} (the fruit file {heavy}'s mass)"]
    _, _, given = cli.run("simulate", "--fruit", heavy, "--mass", "0.2", "--velocity", "1")
    assert expected not in given  # the option given replaces the file's value: no warning for it


# ------------------------------------------------------------------ (5) the energy the simulator compares

def surface_lot(seed: int, surface: str, truth=TRUTH, per_height: int = 8) -> dict:
    """Synthetic drop tests of 180 g apples onto ``surface`` whose truth is on the energy the simulator compares
    (``compared_energy``: the fruit's share of m g h there, by ``fi.evaluate``'s outputs), as a simulation of the
    fitted fruit applies it."""
    rng = np.random.default_rng(seed)
    heights = np.repeat(np.array([2, 3, 4, 5, 7, 10, 14, 20, 28, 40, 55]) / 100.0, per_height)
    levels = {h: compared_energy("apple", surface, h, 0.18) for h in np.unique(heights)}
    energy = np.array([levels[h] for h in heights])
    thresholds = truth["threshold"] * np.exp(truth["spread"] * rng.standard_normal(heights.size))
    volume = np.where(energy > thresholds, truth["susceptibility"] * (energy - thresholds)
                      * np.exp(truth["scatter"] * rng.standard_normal(heights.size)), 0.0)
    return {"drop_height": heights.tolist(), "surface": surface, "mass": 0.18, "bruise_volume": volume.tolist()}


@pytest.mark.parametrize("surface", ["foam-pad", "rubber-belt", "steel"])
def test_the_fit_uses_the_energy_the_simulator_compares_on_every_surface(tmp_path, surface):
    """Review item 1: the fit's energies are the simulator's own (the fruit's share of the impact energy on the
    test's surface: on the foam pad 9–78 % of m g h, on the rubber belt 86–89 %, on steel all but 1e-5), so that
    ``safe-height --fruit fitted.csv --surface S`` puts onset at the fitted threshold on S.  References: the truth
    (drawn on the compared energy, ``surface_lot``), which the fit's 95 % interval must hold (one lot each: a 95 %
    interval misses 1 in 20; these seeds are not chosen: 0, 1, 2 as listed); the onset, where the compared energy
    at the safe height (``compared_energy``, through fi.evaluate's outputs) must equal the fitted W_th to 1e-6 (the
    root's tolerance 1e-9 in h), under the energy criterion and under shear (the fitted failure stress, the shear
    stress at that onset)."""
    seed = ["foam-pad", "rubber-belt", "steel"].index(surface)
    data = surface_lot(seed, surface)
    path = tmp_path / "fitted.csv"
    report = fi.fit_damage(data, fruit="apple", criterion="shear", output=path)
    assert report["status"] == "ok", report["message"]
    assert report["bruise_energy_low"] <= TRUTH["threshold"] <= report["bruise_energy_high"]
    assert report["bruise_susceptibility_low"] <= TRUTH["susceptibility"] <= report["bruise_susceptibility_high"]
    assert report["basis"] == "impact" and f"share: {surface}" in report["basis_note"]
    share = report["energy_share_by_surface"][surface]
    assert 0.0 < share["min"] <= share["max"] <= 1.0
    for criterion in ("energy", "shear"):
        safe = fi.safe_height(fruit=str(path), surface=surface, criterion=criterion, sensitivity=False)
        onset = compared_energy(path, surface, safe["safe_height"])
        assert onset == pytest.approx(report["bruise_energy"], rel=1e-6), (criterion, onset)
    if surface == "foam-pad":  # on the pad m g h at onset is far above W_th: the old fit (m g h as is) was wrong here
        assert safe["safe_height"] * 0.18 * G > 1.2 * report["bruise_energy"]


def test_surfaces_that_disagree_on_the_failure_stress_give_none_and_say_so(tmp_path, cli):
    """Review item 2: tests on steel and on the foam pad drawn with one threshold of the compared energy (the energy
    criterion true) put the shear stress at onset twice as high on steel (0.32 against 0.16 MPa: the pad spreads the
    contact; on m g h, as the fit had it, 30 times): each surface's own threshold and stress are
    reported (``failure_stress_by_surface``), the stresses' 95 % intervals do not meet, so no failure stress is
    given or written, with a warning naming both; the fitted fruit takes the energy criterion (review item 8), and
    its onset is then the fitted W_th on either surface (1e-6, as above).  Reference: the per-surface values are
    each surface's fit alone (fit-damage on that surface's rows: the same numbers)."""
    steel, foam = surface_lot(10, "steel"), surface_lot(11, "foam-pad")
    both = {key: ([steel[key]] * len(steel["drop_height"]) if isinstance(steel[key], (str, float)) else steel[key])
            + ([foam[key]] * len(foam["drop_height"]) if isinstance(foam[key], (str, float)) else foam[key])
            for key in steel}
    path = tmp_path / "fitted.csv"
    report = fi.fit_damage(both, fruit="apple", criterion="shear", output=path)
    by = report["failure_stress_by_surface"]
    assert set(by) == {"steel", "foam-pad"} and report["failure_stress"] is None
    assert by["steel"]["failure_stress_low"] > 1.5 * by["foam-pad"]["failure_stress_high"]
    alone = fi.fit_damage(steel, fruit="apple", criterion="shear")
    assert by["steel"]["failure_stress"] == pytest.approx(alone["failure_stress"], rel=1e-9)
    assert by["steel"]["bruise_energy"] == pytest.approx(alone["bruise_energy"], rel=1e-9)
    assert report["failure_stress_reason"].startswith("the surfaces disagree on the shear criterion's stress")
    assert sum("failure stress: null: the surfaces disagree" in w for w in report["warnings"]) == 1
    entry = catalogue.read_fruit_file(path)
    assert entry.failure_stress is None and entry.criterion == "energy"
    for surface in ("steel", "foam-pad"):
        safe = fi.safe_height(fruit=str(path), surface=surface, sensitivity=False)
        assert safe["criterion"] == "energy"
        assert compared_energy(path, surface, safe["safe_height"]) == pytest.approx(report["bruise_energy"], rel=1e-6)
    printed = cli.ok("fit-damage", write_csv(tmp_path / "both.csv", list(both), zip(*[
        v if isinstance(v, list) else [v] * len(both["drop_height"]) for v in both.values()])), "--fruit", "apple",
        "--criterion", "shear")
    assert "on steel (88 tests)" in printed and "on foam-pad (88 tests)" in printed


def test_surfaces_that_agree_give_their_weighted_failure_stress():
    """Tests on steel and on a rigid plane (stresses at onset 1e-5 apart, within their intervals) give one failure
    stress: the precision-weighted geometric mean of the two (written out here: weights 1/se², se from each 95 %
    interval / (2 × 1.96)), to 1e-9, inside both surfaces' intervals, named "steel, rigid"."""
    steel, rigid = surface_lot(12, "steel", per_height=4), surface_lot(13, "rigid", per_height=4)
    both = {"drop_height": steel["drop_height"] + rigid["drop_height"],
            "surface": ["steel"] * 44 + ["rigid"] * 44, "mass": 0.18,
            "bruise_volume": steel["bruise_volume"] + rigid["bruise_volume"]}
    report = fi.fit_damage(both, fruit="apple", criterion="pressure")
    by = report["failure_stress_by_surface"]
    logs = [math.log(by[s]["failure_stress"]) for s in ("steel", "rigid")]
    se = [(math.log(by[s]["failure_stress_high"]) - math.log(by[s]["failure_stress_low"])) / (2 * 1.959963984540054)
          for s in ("steel", "rigid")]
    weights = [1 / e ** 2 for e in se]
    expected = math.exp(sum(w * x for w, x in zip(weights, logs)) / sum(weights))
    assert report["failure_stress"] == pytest.approx(expected, rel=1e-9)
    assert report["failure_stress_surface"] in ("steel, rigid", "rigid, steel")
    assert any("agree on the failure stress" in w for w in report["warnings"])


def test_a_failure_stress_used_under_another_criterion_is_warned_once(cli, fitted, tmp_path):
    """Review item 3: the file stores the criterion its failure stress was fitted under (shear); a command using
    that stress under pressure says so in one line naming the file and both criteria (a lot of ``line`` or
    ``population``, which draws the stress from the file's range, says it once with the lot's spreads); under shear,
    or with --failure-stress given, nothing is said."""
    folder, report, path = fitted
    line = write_csv(tmp_path / "line.csv", ["name", "drop_height", "surface"], [["tipper", "15cm", "steel"]])
    for argv in (("population", "--surface", "steel", "--drop-height", "10cm", "-n", "50", "-o", tmp_path / "p.csv"),
                 ("line", line, "-n", "50")):
        status, out, err = cli.run(*argv[:1], *argv[1:], "--fruit", path, "--criterion", "pressure")
        assert status == 0, err
        assert sum("was fitted under the shear criterion and is used here under pressure" in x
                   for x in err.splitlines()) == 1, err
    for command in (("simulate", "--drop-height", "10cm"), ("safe-height", "--no-sensitivity"),
                    ("drop", "--drop-height", "10cm")):
        status, out, err = cli.run(command[0], "--fruit", path, "--surface", "steel", "--criterion", "pressure",
                                   *command[1:])
        lines = [line for line in err.splitlines() if "was fitted under" in line]
        assert status == 0 and lines == [
            f"fruitimpact {command[0]}: warning: failure_stress of the fruit file {path} was fitted under the shear "
            f"criterion and is used here under pressure: the onset moves (give --criterion shear, or a failure stress "
            f"fitted under pressure)"], err
    for extra in (("--criterion", "shear"), ("--criterion", "pressure", "--failure-stress", "0.3MPa")):
        _, _, err = cli.run("simulate", "--fruit", path, "--drop-height", "10cm", *extra)
        assert "was fitted under" not in err


def test_criterion_none_writes_the_criterion_the_fitted_values_support(tmp_path, cli):
    """Review item 8: ``--criterion none -o`` fits no failure stress, so the file's criterion is the one its values
    support, energy (not the template's shear with no stress to go with it): safe-height with the file's own
    criterion runs and puts onset at W_th (1e-6, as above).  A fit that gives a susceptibility and no threshold (every
    test bruised) writes no criterion."""
    data = drop_tests(40, per_height=3)
    path = tmp_path / "none.csv"
    report = fi.fit_damage(data, fruit="apple", criterion="none", output=path)
    entry = catalogue.read_fruit_file(path)
    assert entry.criterion == "energy" and entry.failure_stress is None and "criterion none" in entry.criterion_note
    safe = cli.json("safe-height", "--fruit", path, "--surface", "steel", "--no-sensitivity")
    assert safe["criterion"] == "energy"
    assert safe["safe_height"] * 0.18 * G * steel_share() == pytest.approx(report["bruise_energy"], rel=1e-6)
    bruised = {"energy": [0.3, 0.6, 0.9] * 3, "surface": "steel", "mass": 0.18,
               "bruise_volume": [1.1e-6, 2.4e-6, 3.5e-6, 1.3e-6, 2.2e-6, 3.9e-6, 1.0e-6, 2.6e-6, 3.6e-6]}
    report = fi.fit_damage(bruised, fruit="apple", output=tmp_path / "bs.csv")
    assert report["bruise_energy"] is None and report["bruise_susceptibility"] is not None
    entry = catalogue.read_fruit_file(tmp_path / "bs.csv")
    assert entry.criterion is None and entry.bruise_threshold_energy is None


# --------------------------------------------------------------------- (6) absurd input, limits, messages

def run_script(script, *argv):
    done = script("fit-damage", *argv)
    return done.returncode, done.stdout, done.stderr


def test_absurd_values_give_one_line_each_and_no_numerical_noise(tmp_path, script):
    """Review item 9, through the installed command (its whole stderr: no RuntimeWarning, no LAPACK line, no
    traceback): a 10 MJ pendulum, 1e300 J and 1e-300 J are refused for their row, naming the row and the column (an
    impact speed outside [1e-4, 1500] m/s, 100 times beyond the plausible 0.01–15 m/s); a 50 J pendulum (24 m/s) is
    legal but implausible: one warning for the table; drop heights of 12 m in many rows: one warning for the
    table, not one per row.  A table of nothing but tiny energies is refused with one line."""
    data = drop_tests(41, per_height=3)
    rows = [[m * G * h, "steel", m, v] for h, m, v in zip(data["drop_height"], data["mass"], data["bruise_volume"])]
    bad = [[1e7, "steel", 0.18, 1e-6], [1e300, "steel", 0.18, 1e-6], [1e-300, "steel", 0.18, 0],
           [50, "steel", 0.18, 2e-6], [52, "steel", 0.18, 3e-6]]
    path = write_csv(tmp_path / "tests.csv", ["energy", "surface", "mass", "bruise_volume"], rows + bad)
    status, out, err = run_script(script, path, "--fruit", "apple", "--criterion", "none")
    assert status == 0, err
    lines = err.splitlines()
    assert all(line.startswith("fruitimpact fit-damage: warning: ") for line in lines), err
    n = len(rows) + 1
    refused = [line for line in lines if "the row is skipped" in line]
    where = [line.split(": warning: ")[1].split(":")[0] for line in refused]
    assert where == [f"{path}, line {n + k}" for k in (1, 2, 3)]
    assert all("energy: its impact speed" in line for line in refused)
    assert sum("outside the plausible range for fruit, [0.01, 15] m/s" in line for line in lines) == 1
    assert f"{path}, line {n + 4}; 2 of {len(rows) + 5} rows are)" in err
    drops = [[h, "steel", m, v] for h, m, v in zip(data["drop_height"], data["mass"], data["bruise_volume"])]
    heights = write_csv(tmp_path / "high.csv", ["drop_height", "surface", "mass", "bruise_volume"],
                        drops + [[12, "steel", 0.18, 2e-5]] * 6)
    status, out, err = run_script(script, heights, "--fruit", "apple", "--criterion", "none")
    assert status == 0 and err.count("drop_height = 12 m is outside the plausible range") == 1, err
    tiny = write_csv(tmp_path / "tiny.csv", ["energy", "surface", "mass", "bruise_volume"],
                     [[f"{k}e-300", "steel", 0.18, "1e-9"] for k in (1, 2, 3, 4)])
    status, out, err = run_script(script, tiny, "--fruit", "apple")
    assert status == 2 and out == "" and len(err.splitlines()) == 1, err
    assert "no usable test: every row was refused" in err and "energy: its impact speed" in err


def test_an_absurd_mass_or_diameter_skips_its_row_not_the_table(tmp_path, script):
    """A review found a 1e300 m diameter ending in an OverflowError traceback (its sphere volume) and a 1e200 kg
    mass refusing the whole table with an internal message ("threshold_energy must be … got inf"): values 100
    times beyond the plausible range for fruit are no fruit impact, so their row is refused, naming the row and the
    column, and the others are fitted; a legal but implausible mass (168 kg, grams typed without their unit) stays
    a warning, as for every input."""
    data = drop_tests(41, per_height=3)
    rows = [[h, "steel", m, 0.075, v] for h, m, v in zip(data["drop_height"], data["mass"], data["bruise_volume"])]
    bad = [[0.1, "steel", 0.18, 1e300, 1e-6], [0.1, "steel", 1e200, 0.075, 1e-6], [0.1, "steel", 168, 0.075, 1e-6]]
    path = write_csv(tmp_path / "tests.csv", ["drop_height", "surface", "mass", "diameter", "bruise_volume"],
                     rows + bad)
    status, out, err = run_script(script, path, "--fruit", "apple", "--criterion", "none", "--json")
    assert status == 0 and "Traceback" not in err, err
    n = len(rows) + 1
    assert f"line {n + 1}: diameter must lie within" in err and f"line {n + 2}: mass must lie within" in err
    assert err.count("the row is skipped") == 2
    assert err.count("mass = 168 kg is outside the plausible range for fruit") == 1


def test_the_fit_is_the_same_in_any_units_and_silent_at_extreme_scales():
    """The likelihood is invariant to the units (damage/fitting.py fits in units of the tests' geometric means): a
    lot with energies × 1e-200 and volumes × 1e-250 gives BS × 1e-50 and W_th × 1e-200 (1e-6 relative: the
    optimiser's tolerance), with no warning of any kind (numpy's overflow, division and invalid-value errors raised
    here; an underflow to 0 in the quadrature's far tail is exact enough) and no LAPACK output."""
    import warnings

    data = drop_tests(42, per_height=3)
    energy = np.array(data["mass"]) * G * np.array(data["drop_height"])
    volume = np.array(data["bruise_volume"])
    base = fitting.fit_volumes(energy, volume)
    with warnings.catch_warnings(), np.errstate(over="raise", divide="raise", invalid="raise"):  # underflow is 0
        warnings.simplefilter("error")
        tiny = fitting.fit_volumes(energy * 1e-200, volume * 1e-250)
        probit = fitting.fit_incidence(energy * 1e250, (volume > 0).astype(float))
    assert tiny.estimates["bruise_susceptibility"] == pytest.approx(base.estimates["bruise_susceptibility"] * 1e-50,
                                                                    rel=1e-6)
    assert tiny.estimates["bruise_energy"] == pytest.approx(base.estimates["bruise_energy"] * 1e-200, rel=1e-6)
    plain = fitting.fit_incidence(energy, (volume > 0).astype(float))
    assert probit.estimates["bruise_energy"] == pytest.approx(plain.estimates["bruise_energy"] * 1e250, rel=1e-6)


def test_a_table_above_the_row_limit_is_refused_before_any_work(cli, tmp_path):
    """Review item 10: at most ``MAX_TESTS`` = 20,000 tests (about 10 ms each for volumes: docs/tasks/fit-damage.md
    says so); one more is refused with one line, from a CSV and from a mapping, before any work (well under a
    second here)."""
    import time

    assert droptests.MAX_TESTS == 20_000
    rows = [["0.1", "steel", "0.18", "1"]] * 20_001
    path = write_csv(tmp_path / "big.csv", ["drop_height", "surface", "mass", "bruised"], rows)
    start = time.perf_counter()
    line = cli.error("fit-damage", path)
    assert time.perf_counter() - start < 5.0
    assert line == (f"fruitimpact fit-damage: error: argument TESTS: {path}: 20001 tests; a table holds at most "
                    f"20,000 (the fit costs about 10 ms per test: split the table, or fit a random sample of it)")
    with pytest.raises(ValueError, match="tests: 20001 tests; a table holds at most 20,000"):
        fi.fit_damage({"drop_height": [0.1] * 20_001, "surface": "steel", "mass": 0.18, "bruised": 1})


def test_a_failed_fit_says_why():
    """Review item 13: a failed status comes with the reason, not only what was tried: too few bruised tests for a
    volume fit; 0/1 outcomes whose threshold the tests do not bound (every fruit far above it bruised)."""
    few = fi.fit_damage({"energy": [0.05, 0.1, 0.2, 0.4], "surface": "steel", "mass": 0.18,
                         "bruise_volume": [0, 0, 1e-7, 3e-7]}, fruit="apple")
    assert few["status"] == "failed"
    assert few["message"] == ("2 of 4 tests bruised: a volume fit needs at least 3 bruised tests (bruise "
                              "susceptibility, threshold and volume scatter)")
    energies = [0.1, 0.2, 0.3, 0.5, 0.8] * 3
    far = fi.fit_damage({"energy": energies, "surface": "steel", "mass": 0.18,
                         "bruised": [1, 0] + [1] * (len(energies) - 2)}, fruit="apple")
    assert far["status"] == "failed", far["message"]
    assert far["message"].startswith("nothing fitted: the tests do not bound the threshold energy")
    assert far["message"].endswith("0/1 outcomes carry no bruise volume, so there is no susceptibility either")


def test_a_dataframe_mixing_drops_and_pendulum_tests_is_read_per_row():
    """Review item 14: in a DataFrame a row uses the energy column it has (NaN in the other is "not given"): the
    mixed table fits as its drop and pendulum halves do together (the same energies: 1e-9); "1.0"/"0.0" in
    ``bruised`` are read as 1.0/0.0 are; a bad numpy value is shown as a plain number, not np.float64(...)."""
    pd = pytest.importorskip("pandas")
    data = drop_tests(43, per_height=3, outcome="bruised")
    energy = [m * G * h for m, h in zip(data["mass"], data["drop_height"])]
    half = len(energy) // 2
    frame = pd.DataFrame({"drop_height": data["drop_height"][:half] + [np.nan] * (len(energy) - half),
                          "energy": [np.nan] * half + energy[half:], "surface": "steel", "mass": data["mass"],
                          "bruised": [f"{float(b):.1f}" for b in data["bruised"]]})
    mixed = fi.fit_damage(frame, fruit="apple", criterion="none")
    assert mixed["tests"] == len(energy) and not mixed["rows_skipped"]
    plain = fi.fit_damage(data, fruit="apple", criterion="none")
    assert mixed["bruise_energy"] == pytest.approx(plain["bruise_energy"], rel=1e-9)
    frame.loc[0, "drop_height"] = -1.0
    frame.loc[1, "energy"] = 0.5  # both given: refused for that row
    report = fi.fit_damage(frame, fruit="apple", criterion="none")
    messages = [r["message"] for r in report["rows_skipped"]]
    assert messages == ["drop_height must be a finite number > 0 m; got -1.0", "give drop_height or energy, not both"]
    assert not any("np." in w for w in report["warnings"])


def test_docstrings_say_the_susceptibility_is_the_median():
    """Review item 12: with lognormal scatter BS is the median volume per joule above a fruit's threshold (the
    mean is e^(σ_v²/2) times it); the module, the fit's result and fit_damage say so."""
    assert "BS is therefore the **median** volume per" in fitting.__doc__
    assert "median volume per joule" in fitting.fit_volumes.__doc__
    assert "the median volume per joule above a fruit's threshold" in fi.fit_damage.__doc__


def test_a_quoted_field_over_several_lines_is_one_field(tmp_path):
    """A spreadsheet cell holding line breaks (Alt+Enter) is exported as one quoted field spanning lines (RFC 4180);
    a blank line or one starting with # inside it is part of the field, not a blank or comment line.  The shared
    reader (library.textfiles) keeps such a record whole, with the number of its first line."""
    from fruitimpact.library.textfiles import table_lines

    path = tmp_path / "t.csv"
    path.write_text('a,b\n# a comment\n1,"x\n\n# not a comment\ny"\n\n2,"q""r"\n')
    assert table_lines(path) == [(1, "a,b\n"), (3, '1,"x\n\n# not a comment\ny"\n'), (8, '2,"q""r"\n')]
    # a stray quote would take every line after it into one field: refused, naming the line it opened on
    path.write_text('a,b\n1,"x\n2,y\n3,z\n')
    with pytest.raises(ValueError, match=r"line 2: a quoted field opened there is never closed"):
        table_lines(path)
    apple = catalogue.fruit("apple")
    text = catalogue.fruit_file_text(apple)
    header, row = text.rstrip("\n").split("\n")[-2:]
    assert row.startswith("apple,")
    # the description of the library apple, written over three lines in a quoted cell
    multi = text.replace(row, row.replace("apple,", 'apple,"a firm dessert apple\n\n# of several cultivars",', 1)
                         .replace(',generic firm dessert apple (Golden Delicious/Jonagold-like size); values pooled from '
                                  'several cultivars and studies', '', 1))
    (tmp_path / "mine.csv").write_text(multi)
    entry = catalogue.read_fruit_file(tmp_path / "mine.csv")
    assert entry.description == "a firm dessert apple\n\n# of several cultivars"
