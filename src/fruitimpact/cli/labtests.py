"""Laboratory tests: ``fit-damage`` (bruise threshold, susceptibility and failure stress from drop or pendulum
tests, and the fitted fruit as a fruit file)."""

from __future__ import annotations

import sys

from fruitimpact.cli.common import PROG, _checked, _library_call, check_outputs, dump_json
from fruitimpact.impact.outputs import CSV_FORMAT


def _shown(value, scale: float, digits: str = ".4g") -> str:
    return "–" if value is None else f"{value * scale:{digits}}"


#: The rows of the text report: (label, key, scale, unit).
_ROWS = (("bruise threshold energy  W_th", "bruise_energy", 1.0, "J"),
         ("bruise susceptibility    BS", "bruise_susceptibility", 1e6, "cm³/J"),
         ("failure stress           σ_f", "failure_stress", 1e-6, "MPa"))


def cmd_fit_damage(args) -> int:
    from fruitimpact.handling.droptests import fit_damage

    check_outputs(("-o/--output", args.output, CSV_FORMAT), args=args)
    report = _library_call(fit_damage, args.tests, fruit=args.fruit, criterion=args.criterion, name=args.name,
                           output=args.output)
    for warning in report["warnings"]:
        print(f"{PROG} fit-damage: warning: {warning}", file=sys.stderr)
    if args.json:
        print(dump_json(report))
        return 0 if report["status"] == "ok" else 1
    print(f"fit-damage {report['tests_file']}: {report['tests']} tests, {report['bruised']} bruised "
          f"({report['outcome']}); energy {report['energy_min']:.4g}-{report['energy_max']:.4g} J on the "
          f"{report['basis']} basis ({report['basis_note']})")
    for label, key, scale, unit in _ROWS:
        low, high = report[f"{key}_low"], report[f"{key}_high"]
        interval = f"95 % [{_shown(low, scale)}, {_shown(high, scale)}]" if (low, high) != (None, None) else ""
        spread = report["fruit_ranges"].get(key)
        ranged = f"  fruit to fruit [{_shown(spread[0], scale)}, {_shown(spread[1], scale)}]" if spread else ""
        print(f"  {label:<31}{_shown(report[key], scale):>10} {unit:<6} {interval}{ranged}")
    if report["threshold_spread"] is not None:
        scatter = ("" if report["volume_scatter"] is None else
                   f", volume scatter σ_v = {report['volume_scatter']:.3g}")
        print(f"  spread of the fruit's thresholds σ_t = {report['threshold_spread']:.3g} (lognormal){scatter}")
    by_surface = report["failure_stress_by_surface"]
    if len(by_surface) > 1:
        for surface, entry in by_surface.items():
            stress = ("" if entry["failure_stress"] is None else
                      f", σ_f {_shown(entry['failure_stress'], 1e-6)} MPa "
                      f"[{_shown(entry['failure_stress_low'], 1e-6)}, {_shown(entry['failure_stress_high'], 1e-6)}]")
            print(f"  on {surface} ({entry['tests']} tests): W_th {_shown(entry['bruise_energy'], 1.0)} J "
                  f"[{_shown(entry['bruise_energy_low'], 1.0)}, {_shown(entry['bruise_energy_high'], 1.0)}]{stress}")
    if report["failure_stress"] is not None:
        print(f"  failure stress: the {report['failure_stress_rule']} stress at W_th on "
              f"{report['failure_stress_surface']} (criterion {report['criterion']}, the {report['fruit']} flesh)")
    print(f"{report['status']}: {report['message']}")
    if report["output"]:
        print(f"fitted fruit {report['name']} written to {report['output']} (use it as --fruit {report['output']})")
    return 0 if report["status"] == "ok" else 1


def add_parsers(sub) -> None:
    from fruitimpact.impact.registries import REGISTRIES

    fit = sub.add_parser(
        "fit-damage", help="fit bruise threshold energy, susceptibility and failure stress to drop or pendulum tests",
        description="Fit the bruise threshold energy and bruise susceptibility (on the energy the simulator compares: "
                    "the fruit's share of the impact energy on each test's surface) and, where the tests bracket the "
                    "threshold, the failure stress to a table of drop or pendulum tests (at most 20,000), by maximum "
                    "likelihood with unbruised fruit censored; 95 % profile-likelihood intervals.")
    fit.add_argument("tests", metavar="TESTS",
                     help="CSV of tests: drop_height [m] or energy [J], surface, mass [kg], optional diameter [m], "
                          "and one outcome: bruise_volume [m³], bruise_diameter [m] or bruised (0/1)")
    fit.add_argument("--fruit", metavar="NAME|FILE", type=_checked("fruit", REGISTRIES["fruit"]),
                     help="the fruit whose flesh and size give the failure stress, and the template of the fitted "
                          "fruit: a library fruit or a fruit file (default jonathan-apple)")
    fit.add_argument("--criterion", metavar="{" + ",".join(REGISTRIES["criterion"]) + "}",
                     type=_checked("criterion", REGISTRIES["criterion"]),
                     help="the criterion whose stress at onset is the failure stress (default: the fruit's own; none: "
                          "no failure stress)")
    fit.add_argument("--name", metavar="NAME", help="name of the fitted fruit (default <fruit>-fitted-<file stem>)")
    fit.add_argument("-o", "--output", metavar="FILE",
                     help="write the fitted fruit, in the fruit library's format (.csv), for --fruit FILE (not TESTS "
                          "itself)")
    fit.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    fit.set_defaults(func=cmd_fit_damage)
