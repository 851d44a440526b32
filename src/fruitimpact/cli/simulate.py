"""``fruitimpact simulate``: one impact, as a table, JSON, curves and a figure."""

from __future__ import annotations

import math
import sys

from fruitimpact.impact.quantities import CHARACTERISTIC_NAMES, CHARACTERISTICS, OUTPUTS
from fruitimpact.cli.common import (PROG, UsageError, _add_impact_options, _library_call, _simulate_kwargs,
                                    check_outputs, dump_json)
from fruitimpact.impact.outputs import CSV_FORMAT, FIGURE_FORMATS


def _law_line(law) -> str:
    (k_symbol, k_unit), (d_symbol, d_unit), c_unit = law.units
    return (f"contact    {k_symbol} = {law.stiffness:.5g} {k_unit}, {d_symbol} = {law.damping:.5g} {d_unit}"
            f" (damping factor {d_symbol}/{k_symbol} = {law.damping_factor:.5g} {c_unit})")


def format_result_table(result) -> str:
    """A readable table of one result's inputs and characteristics."""
    inputs = result.inputs
    fruit = inputs.fruit
    c = result.characteristics
    lines = [
        f"fruit      M = {fruit.mass * 1e3:.4g} g, d = {fruit.diameter * 1e3:.4g} mm, "
        f"E = {fruit.modulus / 1e6:.4g} MPa, ν = {fruit.poisson:.4g}",
        f"impact     V_i = {inputs.velocity:.4g} m/s"
        + (f" (drop {inputs.drop_height * 100:.4g} cm)" if inputs.drop_height is not None else "")
        + (f", target e = {inputs.target_restitution:.4g}" if inputs.target_restitution is not None else "")
        + (f", α = {inputs.alpha:.4g} s/m" if inputs.alpha is not None else ""),
        f"law        {inputs.model}, calibration {inputs.calibration}, method {inputs.method}"
        + (f" (step {inputs.step:g} s)" if inputs.method == "rk4" else ""),
        _law_line(result.law),
        "",
        f"{'characteristic':<28}{'value':>14}  unit",
        f"{'-' * 28}{'-' * 14}  {'-' * 6}",
    ]
    for quantity in (CHARACTERISTICS[name] for name in CHARACTERISTIC_NAMES):
        value = getattr(c, quantity.name) * quantity.scale
        lines.append(f"{quantity.label:<28}{value:>14.6g}  {quantity.unit}")
    damage = result.damage
    names = result.names
    if names.get("surface", "rigid") != "rigid" or names.get("fruit", "jonathan-apple") != "jonathan-apple":
        lines.insert(1, f"library    fruit {names.get('fruit')}, surface {names.get('surface')}")
    shown = [name for name in ("yield_velocity", "permanent_deflection", "plastic_work", "viscous_work",
                               "fruit_energy", "max_shear_stress", "bruise_volume", "bruise_depth", "bruise_width")
             if result.plastic or names.get("criterion", "none") != "none"]
    if shown:
        lines += ["", f"damage (criterion {names.get('criterion', 'none')}"
                      + (f": {'bruised' if damage['bruised'] else 'not bruised'}, margin "
                         f"{damage['bruise_margin']:+.3g}" if damage.get("bruised") is not None else "") + ")"]
        for name in shown:
            quantity = OUTPUTS[name]
            value = damage[name]
            if math.isnan(value):
                continue
            lines.append(f"{quantity.label:<28}{value * quantity.scale:>14.6g}  {quantity.unit}")
    if not math.isnan(c.max_deflection_closed_form):
        lines += ["", "closed-form self-check (first integral of the force law):",
                  f"  δ_max = {c.max_deflection_closed_form * 1e3:.9g} mm "
                  f"(relative difference {c.max_deflection / c.max_deflection_closed_form - 1:+.1e})",
                  f"  e     = {c.restitution_closed_form:.9g} "
                  f"(relative difference {c.restitution / c.restitution_closed_form - 1:+.1e})"]
    if not result.success:
        lines += ["", f"{result.status.upper()}: {result.message}"]
    return "\n".join(lines)



def _overlays(args) -> list[dict]:
    """--overlay MODEL[:CALIBRATION[:METHOD]] → simulate() overrides, checked against the registries."""
    from fruitimpact.physics import CALIBRATIONS, DAMPING_LAWS
    from fruitimpact.impact.solvers import SOLVERS

    overlays = []
    for text in args.overlay or ():
        parts = text.split(":")
        names = dict(zip(("model", "calibration", "method"), parts))
        for key, registry in (("model", DAMPING_LAWS), ("calibration", CALIBRATIONS), ("method", SOLVERS)):
            if key in names and names[key] not in registry:
                raise UsageError(f"argument --overlay: {key} must be one of {', '.join(registry)}; got {names[key]!r}")
        if len(parts) > 3 or not parts[0]:
            raise UsageError(f"argument --overlay: expected MODEL[:CALIBRATION[:METHOD]]; got {text!r}")
        overlays.append(names)
    return overlays


def cmd_simulate(args) -> int:
    kwargs = _simulate_kwargs(args)
    overlays = _overlays(args)
    check_outputs(("--csv", args.csv, CSV_FORMAT), ("--plot", args.plot, FIGURE_FORMATS), args=args)
    from fruitimpact.impact.simulation import simulate  # the engine (numba) only once the options are good

    result = _library_call(simulate, **kwargs)
    results = [result]
    if (args.csv or args.plot) and result.status != "failed":
        # every engine call before the first line is printed: an interpreted run that must go compiled
        # (cli.interpreted) starts again from scratch, and nothing may be printed twice
        if args.plot:
            results += [_library_call(simulate, **{**kwargs, **overlay}) for overlay in overlays]
        for each in results:
            _ = each.curves
    for warning in result.warnings:
        print(f"{PROG} simulate: warning: {warning}", file=sys.stderr)
    if args.csv and result.status != "failed":
        _library_call(result.curves.to_csv, args.csv, argument="--csv")
    if args.plot and result.status != "failed":
        from fruitimpact.plotting import impact_figure, save_figure

        _library_call(save_figure, impact_figure(results, title="fruitimpact: impact of the fruit on the surface"),
                      args.plot, "--plot")
    if args.json:
        print(dump_json(result.to_dict()))
    else:
        print(format_result_table(result))
        for what, path in (("curves", args.csv), ("figure", args.plot)):
            if path and result.status != "failed":
                print(f"{what} written to {path}")
    return 0 if result.success else 1


def add_parser(sub) -> None:
    sim = sub.add_parser("simulate", help="simulate one impact (default: the paper's Jonathan apple)",
                         description="Simulate one impact; defaults are the paper's Jonathan apple "
                                     "(M = 115 g, d = 65 mm, E = 3 MPa, ν = 0.37, k = 0.577, V_i = 1 m/s).")
    _add_impact_options(sim)
    out = sim.add_argument_group("output")
    out.add_argument("--json", action="store_true", help="print one JSON object (SI) instead of a table")
    out.add_argument("--csv", metavar="FILE", help="write the curves t, δ, δ̇, F as CSV")
    out.add_argument("--plot", metavar="FILE", help="write the four-panel figure (PNG/SVG/PDF by extension)")
    out.add_argument("--overlay", action="append", metavar="MODEL[:CALIBRATION[:METHOD]]",
                     help="also draw this model (and calibration, method) on --plot; repeatable, "
                          "e.g. --overlay chen:paper --overlay hunt-crossley:paper:rk4")
    sim.set_defaults(func=cmd_simulate)
