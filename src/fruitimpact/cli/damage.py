"""Damage commands: ``drop``, ``safe-height``, ``line``, and the libraries ``fruits`` and ``surfaces``."""

from __future__ import annotations

import math
import sys

from fruitimpact.cli.common import (PROG, UsageError, _add_impact_options, _library_call, _simulate_kwargs,
                                    add_spread_option, check_outputs, dump_json, print_spreads, read_option_count)
from fruitimpact.impact.outputs import CSV_FORMAT, FIGURE_FORMATS
from fruitimpact.impact.quantities import INPUTS, OUTPUTS


def _without_velocity(args) -> dict:
    kwargs = _simulate_kwargs(args)
    for name in ("velocity",):
        if name in kwargs:
            raise UsageError(f"argument --{name}: the {args.command} command sets the velocity from the drop height")
    return kwargs


def _print_warnings(command: str, warnings) -> None:
    for warning in warnings:
        print(f"{PROG} {command}: warning: {warning}", file=sys.stderr)


# ----------------------------------------------------------------------------------------------- drop
def cmd_drop(args) -> int:
    from fruitimpact.handling.drops import drop

    kwargs = _without_velocity(args)
    height = kwargs.pop("drop_height", None)
    report = _library_call(drop, height, max_impacts=args.max_impacts, bounces=args.bounces, **kwargs)
    _print_warnings("drop", report["warnings"])
    if args.json:
        print(dump_json(report))
    else:
        print(f"drop from {report['drop_height'] * 100:.4g} cm: {report['impact_count']} impacts, at rest after "
              f"{report['rest_time']:.3g} s; criterion {report['criterion']}; bounces: {report['bounces']}")
        print(f"{'#':>3} {'V [m/s]':>9} {'e':>7} {'F_max [N]':>10} {'p_0 [MPa]':>10} {'W_p [mJ]':>9} "
              f"{'W_v [mJ]':>9} {'bruised':>8} {'BV [mm³]':>9}")
        for impact in report["impacts"]:
            bruised = "-" if impact["bruised"] is None else ("yes" if impact["bruised"] else "no")
            volume = impact["bruise_volume"] * 1e9 if math.isfinite(impact["bruise_volume"]) else math.nan
            print(f"{impact['impact']:>3} {impact['velocity']:>9.4g} {impact['restitution']:>7.4g} "
                  f"{impact['peak_force']:>10.4g} {impact['max_pressure'] / 1e6:>10.4g} "
                  f"{impact['plastic_work'] * 1e3:>9.4g} {impact['viscous_work'] * 1e3:>9.4g} {bruised:>8} "
                  f"{volume:>9.4g}")
        print(f"absorbed {report['total_absorbed_energy'] * 1e3:.4g} mJ (plastic {report['total_plastic_work'] * 1e3:.4g}"
              f" mJ, viscous {report['total_viscous_work'] * 1e3:.4g} mJ)"
              + ("" if report["bruise_volume"] is None else
                 "; bruise volume unknown (no bruise susceptibility)" if math.isnan(report["bruise_volume"]) else
                 f"; bruise volume {report['bruise_volume'] * 1e9:.4g} mm³"))
        print(f"rule: {report['accumulation_rule']}")
        if report["status"] != "ok":
            print(f"{report['status'].upper()}: {report['message']}")
    return 0 if report["status"] == "ok" else 1


# ---------------------------------------------------------------------------------------- safe height
def cmd_safe_height(args) -> int:
    from fruitimpact.handling.heights import safe_height

    kwargs = _without_velocity(args)
    if "drop_height" in kwargs:
        raise UsageError("argument --drop-height: safe-height finds the drop height; leave it out")
    check_outputs(("--map-csv", args.map_csv, CSV_FORMAT), ("--plot", args.plot, FIGURE_FORMATS), args=args)
    if (args.map_csv or args.plot) and not args.map:
        args.map = "surface"
    for option, value in (("--map-fruit", args.map_fruit), ("--map-seed", args.map_seed),
                          ("--no-spreads", args.no_spreads or None)):
        if value is not None and not args.map:
            raise UsageError(f"argument {option}: applies to the risk map: give --map surface or --map firmness")
    risk = None
    if args.map:  # first: its arguments are answered before either search runs
        from fruitimpact.handling.heights import AXIS_INPUTS, MAP_AXES, MAP_FRUIT, MAX_MAP_FRUIT, risk_map
        from fruitimpact.impact.lots import MAX_SEED

        fruit = read_option_count("--map-fruit", args.map_fruit if args.map_fruit is not None else MAP_FRUIT, 0,
                                  MAX_MAP_FRUIT)
        seed = read_option_count("--map-seed", args.map_seed if args.map_seed is not None else 0, 0, MAX_SEED)
        for option, value in (("--map-seed", args.map_seed), ("--no-spreads", args.no_spreads or None)):
            if value is not None and fruit == 0:
                raise UsageError(f"argument {option}: applies to the map's lot, and --map-fruit 0 draws none")
        # the map spans every value of its axis: what the command gives for it (the modulus, or the surface and
        # its properties) is the safe height's, below, and each column's own value is the map's
        axis = AXIS_INPUTS[MAP_AXES[args.map]]
        risk = _library_call(risk_map, by=args.map, rows=fruit, seed=seed, spreads=not args.no_spreads,
                             **{k: v for k, v in kwargs.items() if k not in axis})
    report = _library_call(safe_height, sensitivity=not args.no_sensitivity, **kwargs)
    if risk is not None:
        key, columns, heights, rows, safe = (risk[name] for name in ("by", "columns", "heights", "rows",
                                                                     "safe_height"))
        report["risk_map"] = {"by": key, "safe_height": safe}
        if "lot" in risk:
            report["risk_map"].update(incidence_heights=risk["incidence_heights"], lot=risk["lot"])
            if risk["lot"]["spreads"] and not args.json:  # (in the JSON: risk_map.lot.spreads)
                print_spreads("safe-height", risk["lot"]["spreads"])
        # the map's warnings say on how many grid points: one the safe height already gave is not said twice
        given = report["warnings"]
        report["warnings"] += [text for text in risk["warnings"]
                               if not any(text == known or text.startswith(known + " (") for known in given)]
        if args.map_csv:
            from fruitimpact.impact.outputs import atomic_write

            def write(tmp):
                with open(tmp, "w", encoding="utf-8") as handle:
                    names = list(rows[0])
                    handle.write(",".join(names) + "\n")
                    for row in rows:
                        handle.write(",".join(f"{row[name]:.10g}" if isinstance(row[name], float) else
                                              str(row[name]) for name in names) + "\n")

            _library_call(atomic_write, args.map_csv, write, "--map-csv")
        if args.plot:
            from fruitimpact.plotting import save_figure
            from fruitimpact.plotting.damage import risk_map_figure

            _library_call(save_figure, risk_map_figure(key, columns, heights, rows, safe, report["criterion"]),
                          args.plot, "--plot")
    _print_warnings("safe-height", report["warnings"])
    height = report["safe_height"]
    if args.json:
        print(dump_json(report))
    else:
        shown = "inf" if math.isinf(height) else "not found" if math.isnan(height) else f"{height * 100:.4g} cm"
        print(f"safe drop height {shown} (criterion {report['criterion']}): {report['message']}")
        for name in ("peak_force", "max_pressure", "max_shear_stress", "fruit_energy"):
            if name in report:
                quantity = OUTPUTS[name]
                print(f"  at that height: {quantity.label} = {quantity.display(report[name])}")
        for name, value in report.get("sensitivity", {}).items():
            print(f"  d ln h / d ln {name} = {value:.4g}")
        if args.map:
            mapped = report["risk_map"]
            shares = mapped.get("incidence_heights", {})
            lot = mapped.get("lot")
            print(f"safe height by {mapped['by']} (the typical fruit)"
                  + (f"; the drop heights at which 10 % and 50 % of a lot of {lot['rows']} bruise:" if lot else ":"))

            def cm(value):
                return ("inf" if math.isinf(value) else "any" if value == 0.0 else "unknown" if math.isnan(value)
                        else f"{value * 100:.4g} cm")

            for column, value in mapped["safe_height"].items():
                extra = "".join(f"  {share}: {cm(height):>8}" for share, height in shares.get(column, {}).items())
                print(f"  {column:>14}  {cm(value):>8}{extra}")
        for what, path in (("risk map", args.map_csv), ("figure", args.plot)):
            if path:
                print(f"{what} written to {path}")
    return 0 if report["status"] == "ok" else 1


# ------------------------------------------------------------------------------------------------ line
def _surface_label(point: dict) -> str:
    """What a line report's point was dropped onto, for the table: ``fruit``, the library surface, or the measured
    half-space's modulus (``surface_modulus``, in place of the library surface's values)."""
    if point["fruit_on_fruit"]:
        return "fruit"
    if point.get("surface_modulus") is None:
        return point["surface"]
    return f"{point['surface_modulus'] / 1e6:.3g} MPa"


def cmd_line(args) -> int:
    from fruitimpact.handling.line import audit_line, read_line

    try:
        points = read_line(args.line)
    except ValueError as exc:
        raise UsageError(f"argument LINE: {exc}") from None
    check_outputs(("--plot", args.plot, FIGURE_FORMATS), args=args)
    report = _library_call(audit_line, points, rows=args.rows, seed=args.seed, spreads=not args.no_spreads,
                           alternatives=args.alternatives, **lot_inputs(args))
    criterion = report["criterion"]
    spread_lines = report["spreads"]
    _print_warnings("line", report["warnings"])
    if not args.json:
        print_spreads("line", spread_lines)
    if args.plot:
        from fruitimpact.plotting import save_figure
        from fruitimpact.plotting.damage import line_figure

        _library_call(save_figure, line_figure(report), args.plot, "--plot")
    if args.json:
        print(dump_json(report))
    else:
        print(f"line {args.line}: {report['rows']} fruit, criterion {criterion}; bruised on the line "
              f"{report['incidence'] * 100:.3g} %, mean bruise volume {report['mean_bruise_volume'] * 1e9:.4g} mm³")
        print(f"{'transfer point':<22}{'h [cm]':>8}{'surface':>13}{'incidence':>11}{'BV [mm³]':>10}"
              f"{'cum. inc.':>11}{'cum. BV':>10}{'F_max [N]':>11}")
        for point in report["points"]:
            surface = _surface_label(point)
            print(f"{point['name'][:21]:<22}{point['drop_height'] * 100:>8.4g}{surface:>13}"
                  f"{point['incidence'] * 100:>10.3g}%{point['mean_bruise_volume'] * 1e9:>10.4g}"
                  f"{point['cumulative_incidence'] * 100:>10.3g}%{point['cumulative_bruise_volume'] * 1e9:>10.4g}"
                  f"{point['mean_peak_force']:>11.4g}")
        print(f"most harmful transfer point: {report['worst_point']}")
        measured = {point["name"]: _surface_label(point) for point in report["points"]
                    if point.get("surface_modulus") is not None}
        for change in report["changes"][:5]:
            replaced = measured.get(change["point"], change["from"])
            print(f"  {change['to']} in place of {replaced} at {change['point']}: line incidence "
                  f"{change['incidence'] * 100:.3g} % (saves {change['incidence_saved'] * 100:.3g} points), mean "
                  f"bruise volume {change['mean_bruise_volume'] * 1e9:.4g} mm³ (saves "
                  f"{change['bruise_volume_saved'] * 1e9:.4g})")
        if args.plot:
            print(f"figure written to {args.plot}")
        if report["status"] != "ok":
            print(f"{report['status'].upper()}: {report['message']}")
    return 0 if report["status"] == "ok" else 1


# ------------------------------------------------------------------------------------------ libraries
def _library_listing(args, rows, kind: str) -> int:
    if args.json:
        print(dump_json(rows))
        return 0
    for row in rows:
        print(f"{row['name']}: {row.get('description', '')}")
        for key, value in row.items():
            if isinstance(value, dict) and "value" in value:
                unit = value.get("unit") or ""
                mark = "" if value.get("confirmed", True) else "  (unconfirmed)"
                print(f"  {key:<24}{value['value']!s:>12} {unit:<6} [{value.get('low')}, {value.get('high')}]"
                      f"{mark}  {value.get('source', '')}")
            elif key not in ("name", "description") and value not in (None, ""):
                print(f"  {key:<24}{value}")
    print(f"sources and notes: docs/library.md ({len(rows)} {kind})")
    return 0


def cmd_fruits(args) -> int:
    from fruitimpact.library.catalogue import fruit_rows

    return _library_listing(args, fruit_rows(), "fruits")


def cmd_surfaces(args) -> int:
    from fruitimpact.library.catalogue import surface_rows

    status = _library_listing(args, surface_rows(), "surfaces")
    if not args.json:
        print("rigid: the default --surface: no library values, the --surface-* options as given (a rigid flat)")
    return status


def _lot_quantities():
    """The inputs of a lot: every input of the table with an option except those each transfer point sets
    (velocity, drop height, the surface's)."""
    from fruitimpact.handling.heights import AXIS_INPUTS

    return [quantity for quantity in INPUTS.values()
            if quantity.option and quantity.name not in ("velocity", "drop_height", *AXIS_INPUTS["surface"])]


def add_lot_options(parser) -> None:
    """The lot of a line audit (``line``, ``sphere``): ``_lot_quantities``, ``-n``, ``--seed`` and
    ``--no-spreads``."""
    from fruitimpact.handling.line import LINE_FRUIT

    group = parser.add_argument_group("population (numbers, or normal(m,sd), lognormal(m,cv), uniform(a,b), ...)")
    for quantity in _lot_quantities():
        group.add_argument(quantity.option, dest=quantity.name, metavar="SPEC" if quantity.numeric else "NAME",
                           help=quantity.doc)
    group.add_argument("-n", "--rows", default=str(LINE_FRUIT), metavar="N",
                       help=f"fruit in the population (default {LINE_FRUIT})")
    group.add_argument("--seed", default="0", metavar="S", help="random seed, an integer from 0 to 2^128 - 1 (default 0)")
    add_spread_option(group)


def lot_inputs(args) -> dict:
    """The lot's inputs given on the command line, by name (as typed: the library reads the units)."""
    return {quantity.name: getattr(args, quantity.name) for quantity in _lot_quantities()
            if getattr(args, quantity.name, None) is not None}


def add_parsers(sub) -> None:
    from fruitimpact.handling.drops import BOUNCE_RULES, MAX_IMPACTS
    from fruitimpact.handling.heights import MAP_FRUIT

    dr = sub.add_parser("drop", help="drop a fruit from a height: the rebounds until it rests, damage per impact",
                        description="Drop a fruit from --drop-height onto a surface; every impact at its own "
                                    "velocity, its restitution from the model.")
    _add_impact_options(dr)
    dr.add_argument("--max-impacts", default=str(MAX_IMPACTS), metavar="N",
                    help=f"impacts followed at most (default {MAX_IMPACTS})")
    dr.add_argument("--bounces", default="material", choices=tuple(BOUNCE_RULES),
                    help="restitution of the later impacts: material (default: the damping calibrated at the "
                         "first impact is kept, e rises as the fruit slows, as drop tests show) or constant "
                         "(every impact at the same e)")
    dr.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    dr.set_defaults(func=cmd_drop)

    sh = sub.add_parser("safe-height", help="the greatest drop height without bruise onset (root finding)",
                        description="The greatest drop height without bruise onset for --criterion, by root "
                                    "finding, with its sensitivity to firmness, mass and failure stress.")
    _add_impact_options(sh)
    sh.add_argument("--no-sensitivity", action="store_true", help="skip the sensitivities")
    sh.add_argument("--map", choices=("surface", "firmness"), help="also a bruise-risk map: height × surface "
                                                                   "or height × modulus")
    sh.add_argument("--map-csv", metavar="FILE", help="write the risk map as CSV")
    sh.add_argument("--plot", metavar="FILE", help="draw the risk map (PNG/SVG/PDF)")
    sh.add_argument("--map-fruit", default=None, metavar="N",
                    help=f"fruit of the lot dropped at every point of the map, for its incidence (default {MAP_FRUIT}; "
                         f"0: the typical fruit only)")
    sh.add_argument("--map-seed", default=None, metavar="S", help="random seed of the map's lot (default 0)")
    add_spread_option(sh)
    sh.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    sh.set_defaults(func=cmd_safe_height)

    ln = sub.add_parser("line", help="packing-line audit: bruise incidence at each transfer point",
                        description="Pass a population of fruit through the transfer points of LINE "
                                    "(CSV: name,drop_height,surface[,fruit_on_fruit]"
                                    "[,surface_modulus,surface_poisson]: the last two, given together, a measured "
                                    "half-space, e.g. from `sphere`).")
    ln.add_argument("line", metavar="LINE", help="the line's transfer points, CSV")
    add_lot_options(ln)
    ln.add_argument("--alternatives", default="foam-pad", metavar="SURFACES",
                    help="library surfaces tried in place of each transfer point's, to say what each change would "
                         "save (comma-separated; default foam-pad; none to skip)")
    ln.add_argument("--plot", metavar="FILE", help="incidence and bruise volume along the line (PNG/SVG/PDF)")
    ln.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    ln.set_defaults(func=cmd_line)

    for name, func, text in (("fruits", cmd_fruits, "the fruit library, with sources"),
                             ("surfaces", cmd_surfaces, "the surface library, with sources")):
        parser = sub.add_parser(name, help=text, description=f"List {text}.")
        parser.add_argument("--json", action="store_true", help="print JSON")
        parser.set_defaults(func=func)
