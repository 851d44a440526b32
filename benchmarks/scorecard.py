"""Sorting-line scorecard (issue 13, items 5 and 6): the analysis on recordings from an independent generator.

One command:

    python benchmarks/scorecard.py [--quick] [--markdown FILE] [--scenarios NAME,NAME]
    python benchmarks/scorecard.py --seeds 1-8 [--scenarios NAME,NAME]    (other lines of the same kinds)
    python benchmarks/scorecard.py --variants [--seeds 1,2]               (other settings of the generator)

For each scenario of ``tests/linegen.py`` (chain feeding at 7 and 10 fruit/s/lane with ±8 % jitter, pads and
plates with one or two rebounds whose flight is perturbed by ±10 %, close arrivals, hum + drift + 2–3 kHz plate
ringing, 4 lanes of apples and pears at 25 kHz, pears from 3 cm) the recording is generated at benchmark size
(≥ 80 contacts; ``--quick``: the tests' small sizes) in a temporary folder and analysed by the installed command
line exactly as a user would run it::

    fruitimpact analyze FILE --json --fit --drop-height H --hum 50|60 [--rate R --lanes K]

then scored against the generator's truth (``linegen.score``).  One row per scenario: contacts, recall, extra
reports, fruit taken for rebounds, rebounds taken for fruit, p95 |ΔF|/F (peak force), p95 |Δt_c|/t_c (time to
peak), median and p95 |ΔK|/K (fitted stiffness, fruit only), p95 |Δe| (restitution, fruit only), overlap reports
(and truth contacts that overlap another), analyze wall time; each goal of the issue marked ✓ or ✗ (recall 100 %,
0 extra, 0 misflagged, F ≤ 1 %, t_c ≤ 2 %, K ≤ 2 % median and ≤ 5 % p95, e ≤ 0.03).  Then the grading lot
(``grades``, analysed with ``--diameter --poisson --sort-by modulus --thresholds --classes``): its confusion
matrix and the share of fruit ≥ 5 % from a threshold that get the right class (goal ≥ 98 %).

``--seeds A-B``: every scenario generated with each of those seeds instead of its own (other lines of the same
kinds, at benchmark size), two at a time; one line per recording and the totals (recordings short of full recall,
extra reports, fruit taken for rebounds, rebounds taken for fruit, lone fruit reported as overlaps; fruit graded
through a rebound they carry, i.e. one pulse fitted through both, and how many of those say so with
``rebound_ambiguous``; lone fruit flagged that way).
``--variants``: the same at other settings of the generator (``VARIANTS``: flights ±20 %, spin to 15 %, 10 kHz,
twice the noise, 3 and 6 cm drops, a restitution that does not change with speed, fruit whose force law is not
Hertz's: δ^1.3 and δ^1.7, a piezoelectric sensor's discharge, a 2 kHz anti-alias filter, a 12-bit ADC), at seeds 1,2
or ``--seeds``.

The analysis run is whatever ``fruitimpact`` the current interpreter imports (PYTHONPATH is passed on).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import linegen as lg  # noqa: E402  (tests/linegen.py: the independent generator)
from bench_common import console_script, machine  # noqa: E402

#: Columns: (header, key in the scorecard, format, goal key or None).
COLUMNS = [
    ("contacts", "contacts", "{:d}", None),
    ("recall", "recall", "{:.1%}", "recall"),
    ("extra", "extra", "{:d}", "extra"),
    ("fruit→reb", "fruit_taken_for_rebounds", "{:d}", "fruit_taken_for_rebounds"),
    ("reb→fruit", "rebounds_taken_for_fruit", "{:d}", "rebounds_taken_for_fruit"),
    ("of them flagged", "rebounds_taken_for_fruit_flagged", "{:d}", None),
    ("p95 ΔF/F", "peak_force_p95", "{:.2%}", "peak_force_p95"),
    ("p95 Δtc/tc", "time_to_peak_p95", "{:.2%}", "time_to_peak_p95"),
    ("med ΔK/K", "stiffness_median", "{:.2%}", "stiffness_median"),
    ("p95 ΔK/K", "stiffness_p95", "{:.1%}", "stiffness_p95"),
    ("p95 Δe", "restitution_p95", "{:.3f}", "restitution_p95"),
    ("overlaps", "overlaps", "{}", None),
    ("time", "time", "{:.1f} s", None),
]


def run_scenario(scenario: lg.Scenario, size: int, folder: Path) -> dict:
    """Generate, analyse by the CLI, score: the scorecard row (plus the grading for a grading lot)."""
    t0 = time.perf_counter()
    path, truth = lg.write(scenario, folder, size)
    generated = time.perf_counter() - t0
    argv = [console_script(), "analyze", str(path), *lg.analyze_options(truth)]
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{scenario.name}: {' '.join(argv)} failed ({proc.returncode}):\n{proc.stderr}")
    reports = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
    card = lg.score(reports, truth)
    command = " ".join(["fruitimpact", "analyze", path.name, *argv[3:]])
    card.update(name=scenario.name, time=wall, generated=generated, command=command, goals=lg.check(card))
    if scenario.grading:
        card["grading"] = lg.grade(reports, truth)
    return card


def _cell(card: dict, key: str, fmt: str, goal: str | None, marks: bool) -> str:
    value = card[key]
    if key == "overlaps":
        text = f"{value}/{card['truth_overlaps']}"
    elif isinstance(value, float) and math.isinf(value):
        text = "inf"
    elif isinstance(value, float) and math.isnan(value):
        text = "nan"
    else:
        text = fmt.format(value)
    if marks and goal is not None:
        text += " ✓" if card["goals"][goal] else " ✗"
    return text


def table(cards: list[dict], markdown: bool = False) -> str:
    headers = ["scenario"] + [c[0] for c in COLUMNS]
    rows = [[card["name"]] + [_cell(card, key, fmt, goal, True) for _, key, fmt, goal in COLUMNS] for card in cards]
    signs = {">=": "≥ ", "<=": "≤ "}
    goals = ["goal"] + ["" if goal is None else signs[lg.GOALS[goal][0]] + _goal_text(goal)
                        for _, _, _, goal in COLUMNS]
    rows.append(goals)
    if markdown:
        lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        return "\n".join(lines)
    widths = [max(len(r[i]) for r in rows + [headers]) for i in range(len(headers))]

    def line(r):
        return "  ".join(v.rjust(w) if i else v.ljust(w) for i, (v, w) in enumerate(zip(r, widths)))

    return "\n".join([line(headers), line(["-" * w for w in widths])] + [line(r) for r in rows])


def _goal_text(goal: str) -> str:
    limit = lg.GOALS[goal][1]
    if goal == "recall":
        return "100%"
    if goal == "restitution_p95":
        return f"{limit:g}"
    if isinstance(limit, int):
        return str(limit)
    return f"{limit:.0%}"


def confusion_text(g: dict, markdown: bool = False) -> str:
    classes = list(g["confusion"])
    columns = classes + ["none"]
    headers = ["true \\ reported"] + columns
    rows = [[a] + [str(g["confusion"][a][b]) for b in columns] for a in classes]
    if markdown:
        lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        body = "\n".join(lines)
    else:
        widths = [max(len(r[i]) for r in rows + [headers]) for i in range(len(headers))]
        body = "\n".join("  ".join(v.rjust(w) for v, w in zip(r, widths)) for r in [headers] + rows)
    ok = g["clear_accuracy"] >= lg.GRADING_GOAL
    summary = (f"fruit {g['fruit']}; clear (true E ≥ 5 % from a threshold, first contact overlapping nothing) "
               f"{g['clear']}: right {g['clear_right']} = {g['clear_accuracy']:.1%} "
               f"(goal ≥ {lg.GRADING_GOAL:.0%}) {'✓' if ok else '✗'}; ungraded {g['ungraded']}; "
               f"overlapped first contacts {g['overlapped']} (of their {g['overlapped_clear']} clear fruit, "
               f"{g['overlapped_right']} right, {g['overlapped_wrong']} wrong)")
    return body + ("\n\n" if markdown else "\n") + summary


def _seeds(text: str) -> list[int]:
    """"1-8" or "3,5,9" → the seeds."""
    seeds = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        seeds += list(range(int(first), int(last or first) + 1))
    return seeds


#: Other settings of the same generator (``--variants``): what a line that differs from the scenarios' own does
#: to the goals.  Each (scenario, changes): flights off by ±20 % (the issue's upper bound for spin and off-axis
#: bounces), spin taking up to 15 % of the rebound's speed, a 10 kHz acquisition, twice the noise, drops of 3 and
#: 6 cm (the issue's 30–60 mm), and fruit whose restitution is the same at every speed (``linegen.DAMPING_LAWS``:
#: Lankarani–Nikravesh, Flores), where the Hunt–Crossley fruit of the scenarios come back livelier; fruit whose
#: force law is not Hertz's; and the stages of the impact-sensor note's sensor chain the scenarios leave out: a
#: piezoelectric chain's discharge (τ measured by the analysis, or told), a 2 kHz anti-alias low-pass, a 12-bit ADC.
VARIANTS = {
    "chain10/flight±20%": ("chain10", {"flight_jitter": 0.20}),
    "chain10/spin≤15%": ("chain10", {"spin_loss": (0.0, 0.15)}),
    "chain7/10kHz": ("chain7", {"rate": 10_000.0}),
    "pad/10kHz": ("pad", {"rate": 10_000.0}),
    "lanes4/noise×2": ("lanes4", {"noise": 0.02}),
    "close/3cm": ("close", {"drop_height": 0.03}),
    "chain7/6cm": ("chain7", {"drop_height": 0.06}),
    "pears3cm/6cm": ("pears3cm", {"drop_height": 0.06}),
    "chain10/LN": ("chain10", {"damping_law": "lankarani-nikravesh"}),
    "chain7/Flores": ("chain7", {"damping_law": "flores"}),
    "close/Flores": ("close", {"damping_law": "flores"}),
    "pad/n=1.3": ("pad", {"force_exponent": 1.3}),
    "chain10/n=1.3": ("chain10", {"force_exponent": 1.3}),
    "lanes4/n=1.7": ("lanes4", {"force_exponent": 1.7}),
    "pad/piezo 0.1 s": ("pad", {"discharge_time": 0.1, "discharge_told": False}),
    "chain10/piezo 0.1 s": ("chain10", {"discharge_time": 0.1, "discharge_told": False}),
    "lanes4/piezo 0.3 s": ("lanes4", {"discharge_time": 0.3, "discharge_told": False}),
    "grades/piezo 0.1 s told": ("grades", {"discharge_time": 0.1}),
    "chain7/anti-alias 2 kHz": ("chain7", {"antialias_order": 4, "antialias_cutoff": 0.1}),
    "close/12-bit ADC": ("close", {"adc_bits": 12}),
}


def sweep(jobs: list[tuple[str, int, "lg.Scenario"]]) -> int:
    """Each (label, seed, scenario) at benchmark size (``--seeds``, ``--variants``): a line per recording and the
    totals."""
    from concurrent.futures import ThreadPoolExecutor

    def one(job):
        label, seed, scenario = job
        with tempfile.TemporaryDirectory(prefix="scorecard-") as folder:
            path, truth = lg.write(scenario, Path(folder), scenario.size)
            proc = subprocess.run([console_script(), "analyze", str(path), *lg.analyze_options(truth)],
                                  capture_output=True, text=True)
        if proc.returncode != 0:
            raise SystemExit(f"{label} seed {seed}: analyze failed ({proc.returncode}):\n{proc.stderr}")
        reports = [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]
        card = lg.score(reports, truth)
        matched = lg.match(reports, truth)
        pairs = matched["pairs"]
        card["lone_fruit_overlaps"] = sum(1 for c, r in pairs if not c["is_rebound"] and not c["overlaps"]
                                          and r.get("status") == "overlap")
        card["carried"], card["carried_flagged"] = _carried(matched)
        # fruit that landed alone (overlapping no other contact) flagged as perhaps carrying a rebound: the flag's price
        card["lone_fruit_flagged"] = sum(1 for c, r in pairs if not c["is_rebound"] and not c["overlaps"]
                                         and r.get("status") == "ok" and _may_carry(r))
        return label, seed, card

    keys = ("extra", "fruit_taken_for_rebounds", "rebounds_taken_for_fruit", "lone_fruit_overlaps", "carried",
            "carried_flagged", "lone_fruit_flagged")
    totals = dict.fromkeys(keys, 0)
    short = 0
    t0 = time.perf_counter()
    width = max(10, *(len(label) + 2 for label, _, _ in jobs))
    print(f"{'scenario':<{width}}{'seed':>5}{'contacts':>10}{'recall':>9}{'extra':>7}{'fruit→reb':>11}"
          f"{'reb→fruit':>11}{'lone fruit as overlap':>23}{'carrying (flagged)':>20}{'p95 ΔF/F':>10}{'med ΔK/K':>10}"
          f"{'p95 ΔK/K':>10}")
    with ThreadPoolExecutor(2) as pool:
        for label, seed, card in pool.map(one, jobs):
            short += card["recall"] < 1.0
            for key in keys:
                totals[key] += card[key]
            print(f"{label:<{width}}{seed:>5}{card['contacts']:>10}{card['recall']:>9.1%}{card['extra']:>7}"
                  f"{card['fruit_taken_for_rebounds']:>11}{card['rebounds_taken_for_fruit']:>11}"
                  f"{card['lone_fruit_overlaps']:>23}{'{} ({})'.format(card['carried'], card['carried_flagged']):>20}"
                  f"{card['peak_force_p95']:>10.2%}{card['stiffness_median']:>10.2%}"
                  f"{card['stiffness_p95']:>10.1%}", flush=True)
    print(f"{len(jobs)} recordings in {time.perf_counter() - t0:.0f} s ({machine()}): "
          f"{short} short of full recall; extra {totals['extra']}, fruit taken for rebounds "
          f"{totals['fruit_taken_for_rebounds']}, rebounds taken for fruit {totals['rebounds_taken_for_fruit']}, "
          f"lone fruit as overlaps {totals['lone_fruit_overlaps']}; fruit graded through a rebound they carry "
          f"{totals['carried']} ({totals['carried_flagged']} of them flagged rebound_ambiguous), lone fruit so flagged "
          f"{totals['lone_fruit_flagged']}")
    return 0


def _may_carry(report: dict) -> bool:
    """The report says it may be a fruit and a rebound landed together (``rebound_evidence.ambiguous`` of
    ``rebounds.landed_with_rebound``)."""
    return (report.get("rebound_evidence") or {}).get("ambiguous") is True


def _carried(matched: dict) -> tuple[int, int]:
    """(fruit graded through a rebound they carry, of them flagged), from ``lg.match``: truth rebounds no report
    found whose truth contact overlaps a fruit paired with a graded report (status ok, no rebound: one pulse fitted
    through both, issue 13 item 2), and of those the reports that say so (``_may_carry``)."""
    graded = {c["index"]: r for c, r in matched["pairs"]
              if not c["is_rebound"] and r.get("status") == "ok" and not r.get("rebound")}
    carried = flagged = 0
    for c in (c for c in matched["missed"] if c["is_rebound"]):
        holder = next((graded[k] for k in c["overlaps"] if k in graded), None)
        if holder is not None:
            carried += 1
            flagged += _may_carry(holder)
    return carried, flagged


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the tests' small sizes (~20-40 contacts)")
    parser.add_argument("--markdown", metavar="FILE", help="also write the scorecard as Markdown")
    parser.add_argument("--scenarios", metavar="NAMES", help="comma-separated scenarios (default: all)")
    parser.add_argument("--seed", type=int, default=None, metavar="N",
                        help="generate every scenario with this seed instead of its own (other lines of the same kind)")
    parser.add_argument("--seeds", metavar="A-B", help="every scenario at each of these seeds (e.g. 1-8 or 3,5): "
                                                         "a line per recording and the totals")
    parser.add_argument("--variants", action="store_true",
                        help="other settings of the generator (VARIANTS: flights ±20 %%, spin to 15 %%, 10 kHz, "
                             "noise ×2, 3 and 6 cm drops, constant-restitution damping, force laws, sensor "
                             "chains) at seeds 1,2 (or --seeds): a line per recording")
    args = parser.parse_args(argv)
    names = args.scenarios.split(",") if args.scenarios else list(lg.SCENARIOS)
    unknown = [n for n in names if n not in lg.SCENARIOS]
    if unknown:
        parser.error(f"unknown scenarios {unknown}; known: {', '.join(lg.SCENARIOS)}")
    if args.seeds or args.variants:
        others = [flag for flag, given in (("--seed", args.seed is not None), ("--quick", args.quick),
                                           ("--markdown", args.markdown)) if given]
        if others:
            parser.error(f"--seeds and --variants run at benchmark size and print their own table: not with "
                         f"{', '.join(others)}")
        try:
            seeds = _seeds(args.seeds) if args.seeds else [1, 2]
        except ValueError:
            seeds = []
        if not seeds:
            parser.error(f"--seeds must be A-B (A ≤ B) or A,B,…; got {args.seeds!r}")
        if args.variants:
            jobs = [(label, seed, dataclasses.replace(lg.SCENARIOS[name], seed=seed, **changes))
                    for label, (name, changes) in VARIANTS.items() if name in names for seed in seeds]
        else:
            jobs = [(name, seed, dataclasses.replace(lg.SCENARIOS[name], seed=seed)) for name in names for seed in seeds]
        return sweep(jobs)
    cards = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="scorecard-") as folder:
        for name in names:
            scenario = lg.SCENARIOS[name]
            if args.seed is not None:
                scenario = dataclasses.replace(scenario, seed=args.seed)
            size = scenario.quick_size if args.quick else scenario.size
            card = run_scenario(scenario, size, Path(folder))
            cards.append(card)
            print(f"  {name}: {card['contacts']} contacts, generated in {card['generated']:.1f} s, "
                  f"analysed in {card['time']:.1f} s", file=sys.stderr, flush=True)
    total = time.perf_counter() - t0
    head = f"Sorting-line scorecard ({'quick' if args.quick else 'full'}), {machine()}, total {total:.0f} s"
    print(head)
    print()
    print(table(cards))
    graded = [c for c in cards if "grading" in c]
    for c in graded:
        print()
        print(f"Grading ({c['name']}, {c['contacts']} contacts):")
        print(confusion_text(c["grading"]))
    passed = sum(all(c["goals"].values()) for c in cards)
    print()
    print(f"{passed} of {len(cards)} scenarios meet every goal.")
    if args.markdown:
        text = [f"{head}", "", table(cards, markdown=True), ""]
        for c in graded:
            text += [f"Grading ({c['name']}, {c['contacts']} contacts):", "", confusion_text(c["grading"], True), ""]
        text += ["Commands:", ""] + [f"    {c['command']}" for c in cards] + [""]
        Path(args.markdown).write_text("\n".join(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
