"""``fruitimpact sphere LOG``: an instrumented sphere's log → equivalent drops → the lot's bruises per point."""

from __future__ import annotations

import math
import sys

from fruitimpact.cli.common import PROG, _library_call, check_outputs, dump_json, print_spreads
from fruitimpact.impact.outputs import FIGURE_FORMATS

#: The sphere's own options: (dest, option, metavar, help).  Values are read by the library (units accepted).
SPHERE_OPTIONS = (
    ("sphere_mass", "--sphere-mass", "MASS", "the sphere's mass (e.g. 312g)"),
    ("sphere_diameter", "--sphere-diameter", "LENGTH", "the sphere's diameter (e.g. 89mm)"),
    ("sphere_modulus", "--sphere-modulus", "MODULUS", "the sphere's Young's modulus (e.g. 40MPa); or a calibration"),
    ("sphere_poisson", "--sphere-poisson", "NU", "the sphere's Poisson ratio, in (-1, 0.5]"),
    ("sphere_calibration", "--sphere-calibration", "FILE",
     "drops of the sphere onto a rigid plate (CSV drop_height,peak_acceleration,velocity_change[,duration]): "
     "fits its stiffness and damping, and says how well"),
    ("sphere_restitution", "--sphere-restitution", "E",
     "restitution of readings without a duration (required then: peak and velocity change alone leave it open)"),
    ("surface_poisson", "--surface-poisson", "NU", "Poisson ratio of the surfaces (default 0.3)"),
    ("columns", "--columns", "MAP", "our column names onto the vendor's headers, with units: "
                                    "time=Time,peak_acceleration=G,velocity_change=dV:km/h,duration=T:ms"),
    ("points", "--points", "FILE", "transfer points as time windows (CSV name,start,end), for a log without a point "
                                   "column"),
    ("point_gap", "--point-gap", "TIME", "readings closer than this are one visit of a point (default 1s)"),
    ("pass_gap", "--pass-gap", "TIME", "a gap longer than this starts a new pass through the line (default 20s)"),
    ("uncertainty", "--uncertainty", "FRACTION", "relative standard uncertainty of each reading (default 2%%)"),
    ("logger_rate", "--logger-rate", "HZ", "the logger's sample rate: logged durations are rounded to its period"),
    ("target", "--target", "FRACTION", "incidence above which a point gets cushion advice (default 5%%)"),
    ("pad", "--pad", "MODULUS:THICKNESS", "a pad of given modulus and thickness tried with the library's cushions "
                                          "(e.g. 0.3MPa:10mm)"),
)


def cmd_sphere(args) -> int:
    from fruitimpact.cli.damage import lot_inputs
    from fruitimpact.spheres.audit import sphere_audit
    from fruitimpact.spheres.log import skipped_lines

    check_outputs(("--plot", args.plot, FIGURE_FORMATS), args=args)
    options = {dest: getattr(args, dest) for dest, *_ in SPHERE_OPTIONS if getattr(args, dest) is not None}
    report = _library_call(sphere_audit, args.log, sphere=args.sphere, rows=args.rows, seed=args.seed,
                           spreads=not args.no_spreads, chart=bool(args.plot), **options, **lot_inputs(args))
    for line in skipped_lines(args.log, report["skipped"]):
        print(f"{PROG} sphere: warning: {line}", file=sys.stderr)
    for warning in report["warnings"]:
        print(f"{PROG} sphere: warning: {warning}", file=sys.stderr)
    if args.plot:
        from fruitimpact.plotting import save_figure
        from fruitimpact.plotting.spheres import sphere_figure

        _library_call(save_figure, sphere_figure(report), args.plot, "--plot")
    if args.json:
        print(dump_json(report))
        return 0 if report["status"] == "ok" else 1
    print_spreads("sphere", report["spreads"] or [])
    sphere = report["sphere"]
    print(f"sphere {sphere['name']}: {sphere['mass'] * 1e3:.4g} g, {sphere['diameter'] * 1e3:.4g} mm, "
          f"E*_s {sphere['contact_modulus'] / 1e6:.4g} MPa ({sphere['stiffness_source']})")
    if report["calibration"]:
        print(f"calibration: {report['calibration']['status']}: {report['calibration']['message']}")
    reproduced = sum(impact["status"] == "ok" for impact in report["impacts"])
    print(f"log {args.log}: {report['readings']} readings ({report['kind']}), {reproduced} reproduced by an impact, "
          f"{len(report['skipped'])} rows skipped; points by {report['grouping']}")
    print(f"lot: {report['rows']} fruit, criterion {report['criterion']}; bruised on the line "
          f"{report['incidence'] * 100:.3g} %")
    print(f"{'transfer point':<20}{'passes':>7}{'impacts':>8}{'h [cm]':>8}{'h max':>8}{'E_w [MPa]':>10}"
          f"{'nearest':>13}{'incidence':>11}{'BV [mm³]':>10}{'cum. inc.':>11}")
    for point in report["points"]:
        if point["incidence"] is None:
            print(f"{point['name'][:19]:<20}{point['passes']:>7}{point['impacts']:>8}  {point['message']}")
            continue
        modulus = "rigid" if point["surface_modulus"] is None else f"{point['surface_modulus'] / 1e6:.3g}"
        print(f"{point['name'][:19]:<20}{point['passes']:>7}{point['impacts']:>8}{point['drop_height'] * 100:>8.3g}"
              f"{point['drop_height_max'] * 100:>8.3g}{modulus:>10}{point['surface']:>13}"
              f"{point['incidence'] * 100:>10.3g}%{_volume(point['bruise_volume']):>10}"
              f"{point['cumulative_incidence'] * 100:>10.3g}%")
    print(f"most harmful transfer point: {report['worst_point']}")
    for point in report["points"]:
        advice = point.get("cushion")
        if advice:
            saved = "" if advice["saved_per_10000"] is None else \
                f", saves {advice['saved_per_10000']:.0f} bruised fruit per 10,000"
            print(f"  {point['name']}: {advice['message']}{saved}")
    if args.plot:
        print(f"figure written to {args.plot}")
    if report["status"] != "ok":
        print(f"{report['status'].upper()}: {report['message']}")
    return 0 if report["status"] == "ok" else 1


def _volume(value) -> str:
    return "-" if value is None or math.isnan(value) else f"{value * 1e9:.4g}"


def add_parsers(sub) -> None:
    from fruitimpact.cli.damage import add_lot_options
    from fruitimpact.spheres.devices import DEVICES

    sp = sub.add_parser("sphere", help="instrumented-sphere log → equivalent drops → the lot's bruises per point",
                        description="Read an instrumented sphere's log (per-impact peak g and velocity change, "
                                    "optionally duration and point; or a raw acceleration trace), find each impact's "
                                    "velocity, equivalent drop height, restitution and surface modulus, and drop the "
                                    "lot at every transfer point as `line` does.")
    sp.add_argument("log", metavar="LOG", help="the sphere's log, CSV (time, peak_acceleration [g], velocity_change "
                                               "[m/s][, duration [s]][, point]) or a trace (time, acceleration [g])")
    group = sp.add_argument_group("the sphere and its readings (units accepted)")
    group.add_argument("--sphere", choices=tuple(DEVICES), help="a built-in device profile (its mass and diameter)")
    for dest, option, metavar, text in SPHERE_OPTIONS:
        group.add_argument(option, dest=dest, metavar=metavar, help=text)
    add_lot_options(sp)
    sp.add_argument("--plot", metavar="FILE", help="equivalent drops and incidence per point, and peak g against ΔV "
                                                   "with the lot's 10 %% and 50 %% incidence lines (PNG/SVG/PDF)")
    sp.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    sp.set_defaults(func=cmd_sphere)
