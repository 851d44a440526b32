"""Command-line interface: ``fruitimpact simulate | paper | ...``.

Bad input is answered with one line on stderr naming the argument and its
allowed range, exit status 2, never a traceback.  Heavy imports (matplotlib,
pandas, scipy) happen only in the subcommands that need them.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path

from .quantities import CHARACTERISTICS
from .units import parse_quantity

PROG = "fruitimpact"


class UsageError(Exception):
    """Bad command-line input: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block
        raise UsageError(message)


# (option, dimension, help) of the impact inputs; option names are a contract.
IMPACT_OPTIONS = (
    ("--mass", "mass", "fruit mass M (e.g. 115g) [kg]"),
    ("--diameter", "length", "fruit diameter d (e.g. 65mm) [m]"),
    ("--modulus", "modulus", "Young's modulus E of the flesh (e.g. 3MPa) [Pa]"),
    ("--poisson", "dimensionless", "Poisson's ratio ν, in (-1, 0.5)"),
    ("--stiffness", "stiffness", "contact stiffness k_c [N/m^1.5]; overrides E, ν, d (eq 9)"),
    ("--velocity", "velocity", "impact velocity V_i (e.g. 1m/s) [m/s]"),
    ("--drop-height", "length", "drop height h instead of --velocity (e.g. 30cm) [m]"),
    ("--restitution", "dimensionless", "restitution coefficient k, in (0, 1]"),
    ("--alpha", "alpha", "Hunt-Crossley α instead of k, k = 1 - α V_i (eq 6) [s/m]"),
)


def _dest(option: str) -> str:
    return option.lstrip("-").replace("-", "_")


def _quantities(args, options=IMPACT_OPTIONS) -> dict:
    """Parse the unit-bearing options; a bad one raises UsageError naming it."""
    values = {}
    for option, dimension, _ in options:
        text = getattr(args, _dest(option), None)
        if text is None:
            continue
        try:
            values[_dest(option)] = parse_quantity(text, dimension)
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
    return values


def _library_call(func, *args, **kwargs):
    """Run a library call, turning its ValueError into the CLI's one-line error."""
    try:
        return func(*args, **kwargs)
    except ValueError as exc:
        raise UsageError(_with_option(str(exc))) from None


def _with_option(message: str) -> str:
    """Prefix a library message with the CLI option it concerns ("mass ..." → "argument --mass: mass ...")."""
    if message.startswith("give either"):  # a conflict: name both options as typed
        words = message.split()
        return f"give either --{words[2].replace('_', '-')} or --{words[4].rstrip(',').replace('_', '-')}, not both"
    name = message.split(" ", 1)[0]
    option = "--" + name.replace("_", "-")
    known = {o for o, _, _ in IMPACT_OPTIONS} | {"--model", "--calibration", "--method", "--step"}
    if option in known:
        return f"argument {option}: {message}"
    return message


def _add_impact_options(parser: argparse.ArgumentParser) -> None:
    from .models import CALIBRATIONS, DAMPING_LAWS
    from .solvers import SOLVERS

    group = parser.add_argument_group("fruit and impact (plain numbers are SI; units accepted)")
    for option, _, text in IMPACT_OPTIONS:
        group.add_argument(option, metavar="VALUE", help=text)
    group.add_argument("--model", default="hunt-crossley", metavar="{" + ",".join(DAMPING_LAWS) + "}",
                       help="damping law (default hunt-crossley)")
    group.add_argument("--calibration", default="exact", metavar="{" + ",".join(CALIBRATIONS) + "}",
                       help="exact: λ gives exactly the requested k (default); paper: the law's formula")
    group.add_argument("--method", default="accurate", metavar="{" + ",".join(SOLVERS) + "}",
                       help="accurate (default) or rk4, the paper's fixed-step method")
    group.add_argument("--step", default="1e-4", metavar="VALUE", help="RK4 time step (default 1e-4 s) [s]")


def _simulate_kwargs(args) -> dict:
    from .impact import Fruit

    values = _quantities(args)
    try:
        step = parse_quantity(args.step, "time")
    except ValueError as exc:
        raise UsageError(f"argument --step: {exc}") from None
    fruit_fields = {k: values[k] for k in ("mass", "diameter", "modulus", "poisson", "stiffness") if k in values}
    fruit = _library_call(Fruit, **fruit_fields)
    return dict(fruit=fruit, velocity=values.get("velocity"), drop_height=values.get("drop_height"),
                restitution=values.get("restitution"), alpha=values.get("alpha"), model=args.model,
                calibration=args.calibration, method=args.method, step=step)


# --------------------------------------------------------------------------- tables


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
        + (f", target k = {inputs.target_restitution:.4g}" if inputs.target_restitution is not None else ""),
        f"law        {inputs.model}, calibration {inputs.calibration}, method {inputs.method}"
        + (f" (step {inputs.step:g} s)" if inputs.method == "rk4" else ""),
        _law_line(result.law),
        "",
        f"{'characteristic':<28}{'value':>14}  unit",
        f"{'-' * 28}{'-' * 14}  {'-' * 6}",
    ]
    for quantity in list(CHARACTERISTICS.values())[:12]:
        value = getattr(c, quantity.name) * quantity.scale
        lines.append(f"{quantity.label:<28}{value:>14.6g}  {quantity.unit}")
    if not math.isnan(c.max_deflection_closed_form):
        lines += ["", "closed-form self-check (first integral of the force law):",
                  f"  δ_max = {c.max_deflection_closed_form * 1e3:.9g} mm "
                  f"(relative difference {c.max_deflection / c.max_deflection_closed_form - 1:+.1e})",
                  f"  e     = {c.restitution_closed_form:.9g} "
                  f"(relative difference {c.restitution / c.restitution_closed_form - 1:+.1e})"]
    if not result.success:
        lines += ["", f"FAILED: {result.message}"]
    return "\n".join(lines)


def _json_default(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)


def _finite(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    return obj


def dump_json(obj) -> str:
    """JSON with NaN/inf written as null (strict JSON)."""
    return json.dumps(_finite(obj), indent=2, default=_json_default, allow_nan=False)


# --------------------------------------------------------------------------- commands
def _overlays(args) -> list[dict]:
    """--overlay MODEL[:CALIBRATION[:METHOD]] → simulate() overrides, checked against the registries."""
    from .models import CALIBRATIONS, DAMPING_LAWS
    from .solvers import SOLVERS

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
    from .impact import simulate

    kwargs = _simulate_kwargs(args)
    result = _library_call(simulate, **kwargs)
    if args.csv:
        result.curves.to_csv(args.csv)
    if args.plot:
        from .plotting import impact_figure, save_figure

        results = [result] + [_library_call(simulate, **{**kwargs, **overlay}) for overlay in _overlays(args)]
        save_figure(impact_figure(results, title="fruitimpact: impact of the fruit on the surface"), args.plot)
    if args.json:
        print(dump_json(result.to_dict()))
    else:
        print(format_result_table(result))
        for what, path in (("curves", args.csv), ("figure", args.plot)):
            if path:
                print(f"{what} written to {path}")
    return 0 if result.success else 1


def cmd_paper(args) -> int:
    from .paper import paper_report, format_paper_report

    report = paper_report()
    if args.figures:
        from .paper import write_paper_figures

        report["figures"] = write_paper_figures(args.figures)
    if args.json:
        print(dump_json(report))
    else:
        print(format_paper_report(report))
    return 0


def _float_list(option: str, text: str, low: float, high: float, high_inclusive: bool) -> list[float]:
    """"0.3,0.5,0.7" → floats, each in (low, high) or (low, high]."""
    values = []
    for item in text.split(","):
        try:
            value = float(parse_quantity(item, "velocity" if option == "--velocities" else "dimensionless"))
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        if not (math.isfinite(value) and low < value and (value <= high if high_inclusive else value < high)):
            bracket = "]" if high_inclusive else ")"
            raise UsageError(f"argument {option}: each value must be in ({low:g}, {high:g}{bracket}; got {item!r}")
        values.append(value)
    return values


def cmd_models(args) -> int:
    from .comparison import format_restitution_table, restitution_figure, restitution_table
    from .models import DAMPING_LAWS

    for name in args.model or ():
        if name not in DAMPING_LAWS:
            raise UsageError(f"argument --model: model must be one of {', '.join(DAMPING_LAWS)}; got {name!r}")
    targets = _float_list("--targets", args.targets, 0.0, 1.0, True)
    velocities = _float_list("--velocities", args.velocities, 0.0, math.inf, False)
    table = restitution_table(args.model, targets, velocities)
    if args.csv:
        table.to_csv(args.csv, index=False)
    if args.plot:
        from .plotting import save_figure

        save_figure(restitution_figure(table), args.plot)
    if args.json:
        print(dump_json(table.to_dict(orient="records")))
    else:
        print("Restitution each law's published calibration really produces (Jonathan apple: M = 115 g, "
              "k_c = 0.835e6 N/m^1.5)\n")
        print(format_restitution_table(table))
        for what, path in (("table", args.csv), ("figure", args.plot)):
            if path:
                print(f"{what} written to {path}")
    return 0


# --------------------------------------------------------------------------- batch, sweep, population
#: Numeric inputs of sweep and population: (option, column, dimension); text inputs: (option, column).
RUN_NUMERIC = tuple((option, _dest(option), dimension) for option, dimension, _ in IMPACT_OPTIONS) \
    + (("--step", "step", "time"),)
RUN_TEXT = (("--model", "model"), ("--calibration", "calibration"), ("--method", "method"))
#: Inputs whose range depends on other inputs: not checked alone when constant.
_DEPENDENT_INPUTS = ("alpha", "step")


class _Ordered(argparse.Action):
    """Store the value and remember the order in which the options were given (sweep axes)."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.order = [d for d in (getattr(namespace, "order", None) or []) if d != self.dest] + [self.dest]


def _positive_count(option: str, text: str, minimum: int = 1) -> int:
    """"1e7" or "10000000" → int >= minimum."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value == int(value) and value >= minimum):
        raise UsageError(f"argument {option}: must be an integer >= {minimum}; got {text!r}")
    return int(value)


def _add_run_options(parser: argparse.ArgumentParser, output_required: bool) -> None:
    from .runs import CHUNK_ROWS, ENGINES

    group = parser.add_argument_group("run (chunks, resume, engines)")
    group.add_argument("-o", "--output", metavar="OUT", required=output_required,
                       help="every row (inputs, characteristics, status, message) as CSV or Parquet, by extension")
    group.add_argument("--chunk-size", default=str(CHUNK_ROWS), metavar="ROWS",
                       help=f"rows per chunk (default {CHUNK_ROWS}); chunks are written to OUT.parts/ and merged")
    group.add_argument("--engine", choices=list(ENGINES), default=None,
                       help="inprocess (default) or dask (a LocalCluster of --workers processes, or --scheduler)")
    group.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address (implies --engine dask)")
    group.add_argument("--workers", default="2", metavar="N", help="worker processes of the local Dask cluster "
                                                                  "(default 2; one thread each)")
    group.add_argument("--workdir", metavar="DIR", help="work directory of the part files (default OUT.parts)")
    group.add_argument("--fresh", action="store_true",
                       help="discard the work directory of an earlier (or another) job instead of resuming")


def _run(args, plan, keep_columns=(), percentiles=None):
    """Execute ``plan`` with the run options of ``args``; one-line errors, resumable interruption."""
    from . import runs

    try:
        import pyarrow  # noqa: F401  (part files are Parquet)
    except ImportError:
        raise UsageError("batch, sweep and population need pyarrow: pip install 'fruitimpact[parquet]'") from None
    if args.output is not None:
        try:
            runs.table_format(args.output, "output")
        except ValueError as exc:
            raise UsageError(f"argument -o/--output: {exc}") from None
    workers = _positive_count("--workers", args.workers)
    engine = runs.InProcessEngine() if (args.engine or ("dask" if args.scheduler else "inprocess")) == "inprocess" \
        else runs.DaskEngine(scheduler=args.scheduler, workers=workers)
    workdir = args.workdir or runs.default_workdir(args.output, plan)
    try:
        return runs.execute(plan, args.output, engine=engine, workdir=workdir, fresh=args.fresh,
                            keep_columns=keep_columns, percentiles=percentiles or runs.PERCENTILES)
    except runs.RunError as exc:
        raise UsageError(str(exc)) from None
    except KeyboardInterrupt:
        print(f"{PROG} {args.command}: interrupted; completed chunks are kept in {workdir}: "
              f"run the same command again to resume", file=sys.stderr)
        return None


def _status_line(summary) -> str:
    line = f"{summary.rows} rows: {summary.ok} ok, {summary.invalid} invalid, {summary.failed} failed"
    if summary.resumed_chunks:
        line += f" ({summary.resumed_chunks} chunks resumed from an earlier run)"
    return line


def _check_constants(constants: dict, text: dict) -> None:
    """Refuse a constant input out of its range before any chunk runs (one row through batch.evaluate)."""
    from .batch import evaluate

    if not constants and not text:
        return
    probe = evaluate({**{k: [v] for k, v in constants.items()}, **{k: [v] for k, v in text.items()}})
    message = probe["message"].iloc[0]
    if probe["status"].iloc[0] == "invalid" and message.split(" ", 1)[0] in set(constants) | set(text) \
            and message.split(" ", 1)[0] not in _DEPENDENT_INPUTS:
        raise UsageError(_with_option(message))


def _check_text(name: str, values) -> None:
    from .models import CALIBRATIONS, DAMPING_LAWS
    from .solvers import SOLVERS

    registry = {"model": DAMPING_LAWS, "calibration": CALIBRATIONS, "method": SOLVERS}[name]
    for value in values:
        if value not in registry:
            raise UsageError(f"argument --{name}: {name} must be one of {', '.join(registry)}; got {value!r}")


def _check_conflicts(given) -> None:
    for first, second in (("velocity", "drop_height"), ("restitution", "alpha")):
        if first in given and second in given:
            raise UsageError(f"give either --{first.replace('_', '-')} or --{second.replace('_', '-')}, not both")


def cmd_batch(args) -> int:
    from .runs import Plan, TableSource

    try:
        source = TableSource.open(args.input)
    except ValueError as exc:
        raise UsageError(f"argument IN: {exc}") from None
    if args.output and source.path == str(Path(args.output).resolve()):
        raise UsageError("argument -o/--output: must differ from the input file")
    plan = Plan("batch", source, _positive_count("--chunk-size", args.chunk_size))
    summary = _run(args, plan)
    if summary is None:
        return 130
    print(f"batch: {_status_line(summary)}; written to {summary.output}")
    return 0


def cmd_sweep(args) -> int:
    from . import runs

    axes, constants, text = [], {}, {}
    order = list(getattr(args, "order", None) or [])
    for dest in order:
        option = "--" + dest.replace("_", "-")
        try:
            axis = runs.parse_axis(dest, getattr(args, dest))
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        if dest in ("model", "calibration", "method"):
            _check_text(dest, axis.values)
        if len(axis.values) > 1:
            axes.append(axis)
        elif axis.numeric:
            constants[dest] = axis.values[0]
        else:
            text[dest] = axis.values[0]
    _check_conflicts(order)
    _check_constants(constants, text)
    try:
        name = runs.characteristic(args.characteristic).name
    except ValueError as exc:
        raise UsageError(f"argument --characteristic: {exc}") from None
    if args.plot and not 1 <= len(axes) <= 2:
        raise UsageError(f"argument --plot: draws one or two swept inputs; {len(axes)} are swept"
                         + (f" ({', '.join(a.name for a in axes)})" if axes else " (give START:STOP:COUNT)"))
    if not (args.output or args.plot):
        raise UsageError("argument -o/--output: give -o OUT and/or --plot FILE")
    fixed = [runs.Axis(k, (v,)) for k, v in {**constants, **text}.items()]
    grid = runs.GridSource(tuple(axes + fixed))
    plan = runs.Plan("sweep", grid, _positive_count("--chunk-size", args.chunk_size))
    summary = _run(args, plan, keep_columns=(name,) if args.plot else ())
    if summary is None:
        return 130
    shape = " × ".join(f"{len(a.values)} {a.name}" for a in axes) or "1 point"
    print(f"sweep: {shape}; {_status_line(summary)}" + (f"; written to {summary.output}" if summary.output else ""))
    if args.plot:
        from .plotting import save_figure

        save_figure(runs.sweep_figure(grid, summary.columns[name], name), args.plot)
        print(f"figure written to {args.plot}")
    return 0


def _format_population(summary, names) -> str:
    from .runs import CHARACTERISTICS

    method = summary.percentiles
    lines = [f"population: {_status_line(summary)}",
             "percentiles: " + ("exact (every ok member)" if method.get("exact") else method.get("note", "")), ""]
    pcts = list(next(iter(summary.statistics.values()))["percentiles"]) if summary.statistics else []
    header = f"{'characteristic':<28}{'unit':>7}{'mean':>12}{'sd':>12}{'min':>12}" \
        + "".join(f"{'p' + p:>12}" for p in pcts) + f"{'max':>12}"
    lines += [header, "-" * len(header)]
    for name in names:
        stats, quantity = summary.statistics[name], CHARACTERISTICS[name]
        values = [stats["mean"], stats["sd"], stats["min"], *stats["percentiles"].values(), stats["max"]]
        lines.append(f"{quantity.label:<28}{quantity.unit:>7}" + "".join(f"{v * quantity.scale:>12.5g}" for v in values))
    if summary.thresholds:
        lines += ["", "thresholds (exact counts over ok members):"]
        for t in summary.thresholds:
            lines.append(f"  {t['threshold']:<32} {t['count']} of {t['of']} ({100 * t['share']:.4g} %)")
    return "\n".join(lines)


def cmd_population(args) -> int:
    from . import runs
    from .distributions import Constant, parse_distribution

    rows = _positive_count("-n/--rows", args.rows)
    seed = _positive_count("--seed", args.seed, minimum=0)
    distributions, constants, text = [], {}, {}
    for option, dest, dimension in RUN_NUMERIC:
        spec = getattr(args, dest)
        if spec is None:
            continue
        try:
            dist = parse_distribution(spec, dimension, dest)
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        distributions.append((dest, dist))
        if isinstance(dist, Constant):
            constants[dest] = dist.value
    for option, dest in RUN_TEXT:
        if getattr(args, dest) is not None:
            _check_text(dest, [getattr(args, dest)])
            text[dest] = getattr(args, dest)
    _check_conflicts([d for d, _ in distributions])
    _check_constants(constants, text)
    try:
        names = runs.characteristics_list(args.characteristics) if args.characteristics else runs.DEFAULT_SUMMARY
    except ValueError as exc:
        raise UsageError(f"argument --characteristics: {exc}") from None
    thresholds = []
    for item in args.threshold or ():
        try:
            thresholds.append(runs.Threshold.parse(item))
        except ValueError as exc:
            raise UsageError(f"argument --threshold: {exc}") from None
    try:
        percentiles = tuple(float(p) for p in args.percentiles.split(","))
    except ValueError:
        percentiles = (math.nan,)
    if not all(0 <= p <= 100 for p in percentiles):
        raise UsageError(f"argument --percentiles: each must be a number in [0, 100]; got {args.percentiles!r}")
    source = runs.PopulationSource(tuple(distributions), tuple(text.items()), rows, seed)
    plan = runs.Plan("population", source, _positive_count("--chunk-size", args.chunk_size),
                     write_rows=args.output is not None, stats=names, thresholds=tuple(thresholds),
                     sample_rows=_positive_count("--sample-size", args.sample_size))
    summary = _run(args, plan, percentiles=percentiles)
    if summary is None:
        return 130
    if args.hist:
        from .plotting import save_figure

        save_figure(runs.histogram_figure(summary.sample, names, summary.percentiles["exact"]), args.hist)
    if args.json:
        report = summary.to_dict()
        report["seed"], report["inputs"] = seed, {name: dist.describe() for name, dist in distributions}
        print(dump_json(report))
    else:
        print(_format_population(summary, names))
        for what, path in (("rows", summary.output), ("histograms", args.hist)):
            if path:
                print(f"{what} written to {path}")
    return 0


def _add_run_commands(sub) -> None:
    """The parsers of ``batch``, ``sweep`` and ``population``."""
    from .runs import PERCENTILES, SAMPLE_ROWS

    bat = sub.add_parser("batch", help="characteristics of every row of a CSV/Parquet file of inputs",
                         description="Rows of inputs (columns named like simulate's options: mass, diameter, "
                                     "modulus, poisson, stiffness, velocity, drop_height, restitution, alpha, "
                                     "model, calibration, method, step; numbers in SI or strings with units) "
                                     "→ OUT with the inputs as used, the characteristics, status and message, "
                                     "and the input row number in column 'row'. A bad row is marked, never fatal.")
    bat.add_argument("input", metavar="IN", help="input table, .csv or .parquet")
    _add_run_options(bat, output_required=True)
    bat.set_defaults(func=cmd_batch)

    swp = sub.add_parser("sweep", help="characteristics over a grid of inputs",
                         description="A grid over ranges of inputs: START:STOP:COUNT (inclusive, linear), "
                                     "log:START:STOP:COUNT (geometric), V1,V2,... or one value; units allowed "
                                     "(e.g. --velocity 0.3:1.5:25 --modulus 2MPa:6MPa:41). The first swept "
                                     "option given varies slowest. Text options take comma lists.")
    group = swp.add_argument_group("inputs (ranges, lists or values; plain numbers are SI)")
    for option, dest, _ in RUN_NUMERIC:
        group.add_argument(option, action=_Ordered, metavar="RANGE", help=f"{dest} [{_SI_OF[dest]}]".replace(" []", ""))
    for option, dest in RUN_TEXT:
        group.add_argument(option, action=_Ordered, metavar="LIST", help=f"{dest} name(s), comma-separated")
    out = swp.add_argument_group("figure")
    out.add_argument("--plot", metavar="FILE", help="heat map (two swept inputs) or lines (one, or a second with "
                                                    "at most 8 values) of --characteristic (PNG/SVG/PDF)")
    out.add_argument("--characteristic", default="peak_force", metavar="NAME",
                     help="characteristic plotted (default peak_force)")
    _add_run_options(swp, output_required=False)
    swp.set_defaults(func=cmd_sweep)

    pop = sub.add_parser("population", help="Monte Carlo population: percentiles and threshold shares",
                         description="Each input a constant or a distribution (units allowed inside): "
                                     "normal(mean,sd); lognormal(median,sigma) with ln X ~ N(ln median, sigma²), "
                                     "sigma dimensionless; uniform(lo,hi); truncnormal(mean,sd,lo,hi) (normal "
                                     "truncated to [lo,hi]); sample(FILE[:COLUMN]) (bootstrap from a CSV/Parquet "
                                     "column). Seeded: the same command gives the same members.")
    group = pop.add_argument_group("inputs (constants or distributions; plain numbers are SI)")
    for option, dest, _ in RUN_NUMERIC:
        group.add_argument(option, metavar="SPEC", help=f"{dest} [{_SI_OF[dest]}]".replace(" []", ""))
    for option, dest in RUN_TEXT:
        group.add_argument(option, metavar="NAME", help=f"{dest} (one name)")
    group.add_argument("-n", "--rows", default="10000", metavar="N", help="members (default 10000; 1e7 allowed)")
    group.add_argument("--seed", default="0", metavar="S", help="random seed, integer >= 0 (default 0)")
    stats = pop.add_argument_group("summary")
    stats.add_argument("--characteristics", metavar="LIST",
                       help="characteristics summarised and histogrammed, comma-separated (default: all twelve)")
    stats.add_argument("--percentiles", default=",".join(f"{p:g}" for p in PERCENTILES), metavar="LIST",
                       help="percentiles [%%] (default 5,25,50,75,95)")
    stats.add_argument("--threshold", action="append", metavar="EXPR",
                       help="count members beyond a threshold, e.g. peak_force>60N (>, >=, <, <=; repeatable)")
    stats.add_argument("--sample-size", default=str(SAMPLE_ROWS), metavar="ROWS",
                       help=f"percentiles are exact up to this many members, above it estimated from a seeded "
                            f"uniform sample of about this size (default {SAMPLE_ROWS})")
    stats.add_argument("--hist", metavar="FILE", help="histograms of the characteristics (PNG/SVG/PDF)")
    stats.add_argument("--json", action="store_true", help="print the summary as JSON (SI)")
    _add_run_options(pop, output_required=False)
    pop.set_defaults(func=cmd_population)


_SI_OF = {"mass": "kg", "diameter": "m", "modulus": "Pa", "poisson": "", "stiffness": "N/m^1.5", "velocity": "m/s",
          "drop_height": "m", "restitution": "", "alpha": "s/m", "step": "s"}


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Simulate and measure fruit impacts on surfaces (SI units).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

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

    pap = sub.add_parser("paper", help="reproduce the founding paper's Table 1 and worked example")
    pap.add_argument("--json", action="store_true", help="print everything as JSON")
    pap.add_argument("--figures", metavar="DIR", help="write the worked example's figures to DIR")
    pap.set_defaults(func=cmd_paper)

    mod = sub.add_parser("models", help="achieved vs requested restitution of every damping law",
                         description="For each damping law, the restitution its published calibration really "
                                     "produces against the one it was given.")
    mod.add_argument("--model", action="append", metavar="NAME", help="only this law (repeatable)")
    mod.add_argument("--targets", default="0.1,0.3,0.5,0.7,0.9", metavar="LIST",
                     help="requested restitution coefficients, comma-separated, each in (0, 1]")
    mod.add_argument("--velocities", default="0.5,1,3", metavar="LIST",
                     help="impact velocities, comma-separated, each > 0 [m/s]")
    mod.add_argument("--json", action="store_true", help="print the table as JSON records")
    mod.add_argument("--csv", metavar="FILE", help="write the table as CSV")
    mod.add_argument("--plot", metavar="FILE", help="write achieved vs requested e (PNG/SVG/PDF)")
    mod.set_defaults(func=cmd_models)

    _add_run_commands(sub)
    return parser


_NEGATIVE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def _attach_negative_values(argv: list[str]) -> list[str]:
    """Let "--drop-height -3cm" reach our range check instead of argparse's
    "expected one argument": glue a value that starts with "-<digit>" to its option."""
    glued = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if (token.startswith("--") and "=" not in token and i + 1 < len(argv)
                and _NEGATIVE.match(argv[i + 1])):
            glued.append(f"{token}={argv[i + 1]}")
            i += 2
            continue
        glued.append(token)
        i += 1
    return glued


def _numba_without_blas() -> None:
    """Start numba's CPU target without letting it import SciPy's BLAS.

    On its first compiled call numba imports ``scipy.linalg.cython_blas`` (about
    0.2 s) only to offer ``np.dot`` inside compiled code, which the engine never
    uses.  In the CLI's own process we refuse that import while the target
    initialises; library users (who may want numba's np.dot) are not affected."""
    if "scipy.linalg.cython_blas" in sys.modules:
        return
    sys.modules["scipy.linalg.cython_blas"] = None  # makes the import raise ImportError
    try:
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()
    finally:
        del sys.modules["scipy.linalg.cython_blas"]


def main(argv=None) -> int:
    if argv is None:  # the console script; in-process callers keep numba's defaults
        _numba_without_blas()
    parser = build_parser()
    argv = _attach_negative_values(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
        if getattr(args, "func", None) is None:
            parser.print_help()
            return 2
        return args.func(args)
    except UsageError as exc:
        command = getattr(locals().get("args"), "command", None) or next(
            (token for token in argv if token in ("simulate", "paper", "models", "batch", "sweep", "population")), None)
        prefix = f"{PROG} {command}" if command else PROG
        print(f"{prefix}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. piped into head
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
