"""The founding paper, reproduced: Table 1, the worked example, the restitution
each calibration really gives.  See docs/paper.md for the discussion.

The paper's method (section 3): RK4 at Δt = 1e-4 s, the paper's calibration
(eq 6 with eq 5 for Hunt–Crossley; eq 21 for "Chen"), M = 0.115 kg, and the
k_c printed in Table 1 (with k_c from E by eq 9 instead, δ_max of case 6 HC
rounds to 156, not the printed 155: the authors fed the rounded k_c to their
program).  Read-off, found by matching all 18 printed δ_max and T: the peak
force, its time and δ_max are the largest grid samples, and T is the last
grid time with δ > 0.
"""

from __future__ import annotations

import csv
import math
from importlib import resources

from fruitimpact.impact.simulation import Fruit, simulate

PAPER_MASS = 0.115  # kg, the worked example's M (Table 1 does not print it)
PAPER_DIAMETER = 0.065  # m
PAPER_POISSON = 0.37
PAPER_STEP = 1e-4  # s
LAWS = {"hc": "hunt-crossley", "chen": "chen"}
LAW_TITLES = {"hc": "Hunt-Crossley (eqs 5, 6, 11, 13)", "chen": "'Chen' = Lankarani-Nikravesh (eqs 21-23)"}

#: Per-entry findings that are not visible from the numbers alone (docs/paper.md).
KNOWN_MISPRINTS = {
    (6, "chen", "F_max"): ("misprint: every method gives 47.23 N for this row, whose δ_max, T and t_c all "
                           "match; the printed C = 1.771 = 44.28/25 was computed from the misprinted force "
                           "(with 47.23 N, C = 1.889)"),
}


def load_table1() -> list[dict]:
    """Table 1 as printed (units in the CSV header: V m/s, E MPa, k_c 1e6 N/m^1.5,
    F N, δ_max 1e-5 m, T and t_c 1e-4 s, C 1e4 N/s)."""
    text = resources.files("fruitimpact.reference").joinpath("data/table1.csv").read_text()
    rows = [line for line in text.splitlines() if line and not line.startswith("#")]
    table = []
    for row in csv.DictReader(rows):
        table.append({key: (value if key == "code" else float(value)) for key, value in row.items()})
    for row in table:
        row["case"] = int(row["case"])
    return table


def paper_readoff(result) -> dict:
    """The paper's read-off from an RK4 result's grid (curves end with the
    interpolated separation point, which the paper did not have)."""
    curves = result.curves
    t, d, f = curves.time[:-1], curves.deflection[:-1], curves.force[:-1]
    peak = int(f.argmax())
    return dict(F_max=float(f[peak]), t_c=float(t[peak]), delta_max=float(d.max()),
                T=float(t[d > 0.0][-1]))


def _case_simulations(row, law_key):
    fruit = Fruit(mass=PAPER_MASS, diameter=PAPER_DIAMETER, modulus=row["E"] * 1e6, poisson=PAPER_POISSON,
                  stiffness=row["k_c"] * 1e6)
    common = dict(velocity=row["V_i"], restitution=row["k"], model=LAWS[law_key])
    paper_method = simulate(fruit, calibration="paper", method="rk4", step=PAPER_STEP, **common)
    accurate = simulate(fruit, calibration="paper", method="accurate", **common)
    exact = simulate(fruit, calibration="exact", method="accurate", **common)
    return paper_method, accurate, exact


def _entry(row, law_key):
    paper_method, accurate, exact = _case_simulations(row, law_key)
    grid = paper_readoff(paper_method)
    acc = accurate.characteristics
    printed = dict(F_max=row[f"F_max_{law_key}"], delta_max=row[f"delta_max_{law_key}"],
                   T=row[f"T_{law_key}"], t_c=row[f"t_c_{law_key}"], C=row[f"C_{law_key}"])
    method = dict(F_max=grid["F_max"], delta_max=grid["delta_max"] / 1e-5, T=grid["T"] / 1e-4,
                  t_c=grid["t_c"] / 1e-4, C=grid["F_max"] / grid["t_c"] / 1e4)
    accurate_values = dict(F_max=acc.peak_force, delta_max=acc.max_deflection / 1e-5,
                           T=acc.contact_duration / 1e-4, t_c=acc.time_to_peak / 1e-4, C=acc.firmness_c / 1e4)
    checks = {
        "F_max": abs(printed["F_max"] / method["F_max"] - 1.0) <= 0.01,
        "delta_max": round(method["delta_max"]) == printed["delta_max"],
        "T": round(method["T"]) == printed["T"],
        "t_c": round(method["t_c"]) == printed["t_c"],
    }
    # C was computed by the authors from the printed F_max and integer t_c, truncated to 3 decimals
    c_from_printed = math.floor(printed["F_max"] / printed["t_c"] * 1000 + 1e-9) / 1000
    notes = []
    for key, ok in checks.items():
        if (row["case"], law_key, key) in KNOWN_MISPRINTS:
            notes.append(f"{key}: " + KNOWN_MISPRINTS[(row["case"], law_key, key)])
        elif not ok and key == "t_c":
            steps = printed["t_c"] - accurate_values["t_c"]
            if abs(steps) < 1.0:
                notes.append(f"t_c: printed {printed['t_c']:g} is within one step of the exact "
                             f"{accurate_values['t_c']:.2f} but is not the grid sample of the peak "
                             f"({method['t_c']:.0f}); the printed F_max and t_c carry scatter that no read-off "
                             f"convention or input change reproduces (docs/paper.md)")
            else:
                notes.append(f"t_c: printed {printed['t_c']:g} is {abs(steps):.2f} steps from the exact "
                             f"{accurate_values['t_c']:.2f}: no sampling of this model gives it (unexplained "
                             f"scatter in the printed t_c)")
        elif not ok:
            notes.append(f"{key}: printed {printed[key]:g} vs paper's method {method[key]:.4g} (unexplained)")
    if printed["F_max"] > accurate_values["F_max"] * (1 + 1e-4) and (row["case"], law_key, "F_max") not in KNOWN_MISPRINTS:
        notes.append(f"F_max: printed {printed['F_max']:g} N exceeds the exact peak {accurate_values['F_max']:.3f} N, "
                     f"which no grid sampling can do; within the 1 % band, so it counts as reproduced")
    if abs(c_from_printed - printed["C"]) > 1e-9:
        notes.append(f"C: printed {printed['C']:g} is not trunc(F/t_c) of the printed values ({c_from_printed:g})")
    return dict(
        case=row["case"], code=row["code"], law=LAWS[law_key],
        inputs=dict(V_i=row["V_i"], E=row["E"] * 1e6, k=row["k"], k_c=row["k_c"] * 1e6,
                    k_c_eq9=_eq9(row["E"] * 1e6),
                    mass=PAPER_MASS, damping=paper_method.law.damping),
        printed=printed, paper_method=method, accurate=accurate_values,
        deviation=dict(F_max_percent=100.0 * (printed["F_max"] / method["F_max"] - 1.0),
                       delta_max=printed["delta_max"] - method["delta_max"],
                       T_steps=printed["T"] - method["T"], t_c_steps=printed["t_c"] - method["t_c"]),
        discretisation_error=dict(F_max_percent=100.0 * (method["F_max"] / accurate_values["F_max"] - 1.0),
                                  T_percent=100.0 * (method["T"] / accurate_values["T"] - 1.0),
                                  t_c_percent=100.0 * (method["t_c"] / accurate_values["t_c"] - 1.0),
                                  C_percent=100.0 * (method["C"] / accurate_values["C"] - 1.0)),
        reproduced=checks, C_from_printed=c_from_printed,
        restitution=dict(target=row["k"], paper_calibration=acc.restitution,
                         exact_calibration=exact.characteristics.restitution,
                         damping_ratio_needed=exact.law.damping / paper_method.law.damping),
        notes=notes,
    )


def _eq9(modulus):
    from fruitimpact.physics.hertz import rigid_plane_stiffness

    return float(rigid_plane_stiffness(modulus, PAPER_POISSON, PAPER_DIAMETER))


def worked_example() -> dict:
    """Section 3's example: eqs 26–27 and the text's F_max ≈ 51 N, T = 6.3 ms,
    t_c = 2.4 ms, C = 21.23, checked against the stated inputs and against the
    input that reproduces them (V_i = 0.8 m/s)."""
    k_c_eq9 = _eq9(3e6)
    alpha = (1.0 - 0.577) / 1.0
    printed_k_c, printed_lambda = 0.835e6, 0.438e6
    stated_lambda = 1.5 * alpha * printed_k_c
    runs = {}
    scenarios = {
        "as stated: V_i = 1 m/s, λ = 1.5 α k_c (eq 5)": (1.0, stated_lambda),
        "printed eq 26 coefficients at V_i = 1 m/s": (1.0, printed_lambda),
        "printed eq 26 coefficients at V_i = 0.8 m/s": (0.8, printed_lambda),
    }
    for label, (velocity, lam) in scenarios.items():
        fruit = Fruit(mass=PAPER_MASS, diameter=PAPER_DIAMETER, modulus=3e6, poisson=PAPER_POISSON,
                      stiffness=printed_k_c)
        # the damping is given as λ directly (eq 26's coefficient)
        rk4 = simulate(fruit, velocity=velocity, damping=lam, model="hunt-crossley", method="rk4", step=PAPER_STEP)
        acc = simulate(fruit, velocity=velocity, damping=lam, model="hunt-crossley", method="accurate")
        grid = paper_readoff(rk4)
        t_first = grid["T"] + PAPER_STEP  # first grid time with δ ≤ 0, as read off the δ(t) plot
        runs[label] = dict(
            velocity=velocity, damping=lam,
            paper_method=dict(F_max=grid["F_max"], t_c=grid["t_c"], T_last_positive=grid["T"],
                              T_first_nonpositive=t_first, C=grid["F_max"] / grid["t_c"]),
            accurate=dict(F_max=acc.characteristics.peak_force, t_c=acc.characteristics.time_to_peak,
                          T=acc.characteristics.contact_duration, C=acc.characteristics.firmness_c,
                          restitution=acc.characteristics.restitution),
        )
    return dict(
        printed=dict(k_c=printed_k_c, alpha=0.423, damping=printed_lambda, eq27_damping_over_mass=3.809e6,
                     eq27_stiffness_over_mass=7.261e6, F_max=50.96, T=6.3e-3, t_c=2.4e-3, C=21.23),
        checks=dict(k_c_eq9=k_c_eq9, alpha=alpha, damping_stated_formula=stated_lambda,
                    eq27_damping_over_mass=printed_lambda / PAPER_MASS,
                    eq27_stiffness_over_mass=printed_k_c / PAPER_MASS),
        runs=runs,
        findings=[
            "k_c = 0.835e6 follows from eq 9 (0.8357e6, truncated); the text says 'equation (5)' but means eq 9.",
            "alpha = (1 - 0.577)/1 = 0.423 s/m follows from eq 6 at V_i = 1 m/s.",
            f"λ = 0.438e6 (eq 26) does not follow from eq 5: 1.5·α·k_c = {stated_lambda / 1e6:.4f}e6. No formula "
            "of the paper gives 0.438e6; the nearest is eq 21 (Chen) with α = 0.423 at V_i = 0.8 m/s (0.440e6).",
            "Eq 27 is eq 26 divided by M = 0.115 kg (3.809e6 and 7.261e6): consistent.",
            "The text's F_max ≈ 50.96 N, t_c = 2.4 ms and T = 6.3 ms do not follow at V_i = 1 m/s (there "
            "F_max ≈ 66 N, t_c ≈ 2.2 ms, T ≈ 6.0 ms for any λ); they follow from the printed coefficients at "
            "V_i = 0.8 m/s, with T read as the first grid time with δ ≤ 0 (Table 1 uses the last with δ > 0).",
            "C = 50.96/2.4 = 21.23 is in N/ms (2.123e4 N/s), not N/s as printed.",
        ],
    )


def paper_report() -> dict:
    """Everything ``fruitimpact paper`` prints, as a dict (JSON-ready)."""
    table = load_table1()
    entries = [_entry(row, law_key) for law_key in LAWS for row in table]
    reproduced = sum(all(e["reproduced"].values()) for e in entries)
    return dict(
        method=dict(mass=PAPER_MASS, step=PAPER_STEP, stiffness="k_c as printed in Table 1",
                    readoff="largest grid samples for F_max, t_c, δ_max; T = last grid time with δ > 0",
                    calibration="paper: eq 6 + eq 5 (Hunt-Crossley), eq 21 (Chen)"),
        table1=entries,
        summary=dict(entries=len(entries), fully_reproduced=reproduced,
                     F_max_within_1_percent=sum(e["reproduced"]["F_max"] for e in entries),
                     delta_max=sum(e["reproduced"]["delta_max"] for e in entries),
                     T=sum(e["reproduced"]["T"] for e in entries),
                     t_c=sum(e["reproduced"]["t_c"] for e in entries)),
        worked_example=worked_example(),
    )


def _fmt_row(entry):
    p, m, a = entry["printed"], entry["paper_method"], entry["accurate"]
    ok = entry["reproduced"]
    mark = {True: " ", False: "*"}
    return (f"{entry['case']:>2} {entry['code']:>3} {entry['inputs']['V_i']:>4.2f} {entry['inputs']['k']:>4.2f} "
            f"| {p['F_max']:>6.2f} {m['F_max']:>6.2f} {a['F_max']:>6.2f} {entry['deviation']['F_max_percent']:>+6.2f}%{mark[ok['F_max']]}"
            f"| {p['delta_max']:>4.0f} {m['delta_max']:>6.1f} {a['delta_max']:>6.1f}{mark[ok['delta_max']]}"
            f"| {p['T']:>3.0f} {m['T']:>3.0f} {a['T']:>6.2f}{mark[ok['T']]}"
            f"| {p['t_c']:>3.0f} {m['t_c']:>3.0f} {a['t_c']:>6.2f}{mark[ok['t_c']]}"
            f"| {p['C']:>5.3f} {m['C']:>5.3f} {a['C']:>5.3f}")


def format_paper_report(report: dict) -> str:
    """Human-readable version of ``paper_report``."""
    lines = ["Table 1 of the founding paper, reproduced",
             "=========================================",
             "Paper's method: RK4, step 1e-4 s, paper calibration, M = 0.115 kg, k_c as printed; read-off: largest",
             "grid samples (F_max, t_c, δ_max), T = last grid time with δ > 0.  Columns: printed / paper's method /",
             "accurate (exact solution of the same inputs).  F_max deviation = printed vs paper's method.",
             "'*' = not reproduced at the printed resolution (F_max: outside 1 %); explained below the table.",
             ""]
    header = (" # cod  V_i    k |  F_max [N] pr / rk4 / exact  dev  | δ_max [1e-5 m]  | T [1e-4 s]     "
              "| t_c [1e-4 s]   | C [1e4 N/s]")
    for law_key, law in LAWS.items():
        lines += [LAW_TITLES[law_key], header, "-" * len(header)]
        entries = [e for e in report["table1"] if e["law"] == law]
        lines += [_fmt_row(e) for e in entries]
        lines.append("")
    s = report["summary"]
    lines += [f"Reproduced with the paper's method: F_max within 1 % in {s['F_max_within_1_percent']}/{s['entries']}, "
              f"δ_max {s['delta_max']}/{s['entries']}, T {s['T']}/{s['entries']}, t_c {s['t_c']}/{s['entries']}; "
              f"all four in {s['fully_reproduced']}/{s['entries']} entries.", "",
              "Entries that do not follow from the stated inputs, and why:"]
    for e in report["table1"]:
        for note in e["notes"]:
            lines.append(f"  case {e['case']} ({e['law']}): {note}")
    lines += ["  all: C is trunc(printed F_max / printed integer t_c, 3 decimals), so it inherits the scatter of "
              "t_c (up to ±3 %).", ""]

    we = report["worked_example"]
    lines += ["Worked example (section 3, eqs 26-27)", "-------------------------------------"]
    chk = we["checks"]
    lines.append(f"  k_c by eq 9 = {chk['k_c_eq9'] / 1e6:.4f}e6 N/m^1.5 (printed 0.835e6); α = {chk['alpha']:.3f} s/m; "
                 f"λ by eq 5 = {chk['damping_stated_formula'] / 1e6:.4f}e6 (printed 0.438e6)")
    lines.append(f"  eq 27: λ/M = {chk['eq27_damping_over_mass'] / 1e6:.4f}e6 (printed 3.809e6), "
                 f"k_c/M = {chk['eq27_stiffness_over_mass'] / 1e6:.4f}e6 (printed 7.261e6)")
    lines.append("  text: F_max ≈ 50.96 N, t_c = 2.4 ms, T = 6.3 ms, C = 21.23")
    for label, run in we["runs"].items():
        pm, acc = run["paper_method"], run["accurate"]
        lines.append(f"  {label}:")
        lines.append(f"      paper's method: F_max = {pm['F_max']:.2f} N, t_c = {pm['t_c'] * 1e3:.1f} ms, "
                     f"T = {pm['T_first_nonpositive'] * 1e3:.1f} ms (first δ ≤ 0), C = {pm['C'] / 1e3:.2f} N/ms")
        lines.append(f"      accurate:       F_max = {acc['F_max']:.3f} N, t_c = {acc['t_c'] * 1e3:.3f} ms, "
                     f"T = {acc['T'] * 1e3:.3f} ms, e = {acc['restitution']:.3f}")
    lines += [f"  - {finding}" for finding in we["findings"]]
    lines += ["", "Restitution each calibration really produces (accurate solver)",
              "---------------------------------------------------------------",
              " # law            target k   paper calibration   exact calibration   λ_exact/λ_paper"]
    for e in report["table1"]:
        r = e["restitution"]
        lines.append(f"{e['case']:>2} {e['law']:<14} {r['target']:>8.3f}   {r['paper_calibration']:>17.4f}   "
                     f"{r['exact_calibration']:>17.6f}   {r['damping_ratio_needed']:>15.2f}")
    lines += ["  The paper's calibrations are first order in (1 - k); for apples (k ≈ 0.5-0.64) they give a",
              "  restitution 0.09-0.23 too high.  The exact calibration solves (1+x) = (1-kx) exp((1+k)x), x = c V_i.",
              "", "Details and sources: docs/paper.md"]
    return "\n".join(lines)


def write_paper_figures(directory) -> list[str]:
    """The worked example's four-panel figures (as stated, and at V_i = 0.8 m/s),
    overlaying the paper's RK4 grid, the accurate solution of the same λ = 1.5 α k_c
    (eq 5), and the accurate solution calibrated exactly to k = 1 − α V_i (eq 6)."""

    from fruitimpact.impact.outputs import check_output_folder
    from fruitimpact.plotting import impact_figure, save_figure

    out = check_output_folder(directory, "directory", create=True)
    fruit = Fruit(mass=PAPER_MASS, diameter=PAPER_DIAMETER, modulus=3e6, poisson=PAPER_POISSON, stiffness=0.835e6)
    written = []
    for name, velocity, alpha in (("worked_example_stated", 1.0, 0.423),
                                  ("worked_example_printed_coefficients_0.8ms", 0.8, 0.438e6 / (1.5 * 0.835e6))):
        results = {
            "paper's method (RK4, 1e-4 s)": simulate(fruit, velocity=velocity, alpha=alpha, method="rk4",
                                                      step=PAPER_STEP),
            "accurate, λ = 1.5 α k_c (eq 5)": simulate(fruit, velocity=velocity, alpha=alpha),
            "accurate, exact calibration to k = 1 - α V_i": simulate(fruit, velocity=velocity,
                                                                     restitution=1.0 - alpha * velocity),
        }
        path = out / f"{name}.png"
        save_figure(impact_figure(results, title=f"Worked example, V_i = {velocity:g} m/s, α = {alpha:.3f} s/m"), path)
        written.append(str(path))
    return written
