"""``fruitimpact batch``, ``sweep`` and ``population``: many impacts, chunked and resumable.

Every option, output path, figure path, the work folder and the limits of a
run are checked before any work: a bad one is one line naming the option and
its allowed range, exit status 2.
"""

from __future__ import annotations

import argparse
import decimal
import importlib.util
import math
import sys
from pathlib import Path

from fruitimpact.cli.common import PROG, UsageError, _with_option, add_spread_option, dump_json, lot_distributions, print_spreads

#: Inputs whose range depends on other inputs: not checked alone when constant.
_DEPENDENT_INPUTS = ("alpha", "step")
#: Most worker processes of a local Dask cluster.
MAX_WORKERS = 256


class _Ordered(argparse.Action):
    """Store the value and remember the order in which the options were given (sweep axes)."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.order = [d for d in (getattr(namespace, "order", None) or []) if d != self.dest] + [self.dest]


def _count(option: str, text: str, low: int, high: int | None = None) -> int:
    """An exact integer in [low, high] from ``"10000000"`` or ``"1e7"`` (never through a float,
    so that a seed above 2^53 keeps every digit)."""
    allowed = f"an integer >= {low:,}" if high is None else f"an integer in [{low:,}, {high:,}]"
    try:
        value = decimal.Decimal(str(text).strip())
    except decimal.InvalidOperation:
        value = None
    if value is None or not value.is_finite() or value != value.to_integral_value() \
            or value < low or (high is not None and value > high):
        raise UsageError(f"argument {option}: must be {allowed}; got {text!r}")
    return int(value)


def _run_inputs():
    """(option, name, quantity) of every input of the table of quantities, numeric first."""
    from fruitimpact.impact.quantities import INPUTS

    return [(quantity.option or "--" + name.replace("_", "-"), name, quantity) for name, quantity in INPUTS.items()]


def _add_run_options(parser: argparse.ArgumentParser, output_required: bool) -> None:
    from fruitimpact.runs import CHUNK_ROWS, ENGINES, MAX_CHUNK_ROWS

    group = parser.add_argument_group("run (chunks, resume, engines)")
    group.add_argument("-o", "--output", metavar="OUT", required=output_required,
                       help="every row (inputs, characteristics, status, message) as CSV or Parquet, by extension")
    group.add_argument("--chunk-size", default=str(CHUNK_ROWS), metavar="ROWS",
                       help=f"rows per chunk, 1 to {MAX_CHUNK_ROWS:,} (default {CHUNK_ROWS}); chunks are written "
                            f"to the work folder and resumed from it")
    group.add_argument("--engine", choices=list(ENGINES), default=None,
                       help="inprocess (default) or dask (a LocalCluster of --workers processes, or --scheduler)")
    group.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786 "
                                                              "(implies --engine dask)")
    group.add_argument("--workers", default="2", metavar="N", help=f"worker processes of the local Dask cluster, "
                                                                  f"1 to {MAX_WORKERS} (default 2; one thread each)")
    group.add_argument("--workdir", metavar="DIR", help="work folder of the part files (default OUT.parts); a new "
                                                        "or empty folder, or one fruitimpact made")
    group.add_argument("--fresh", action="store_true",
                       help="discard the parts of another job in the work folder (only ever a folder fruitimpact "
                            "made and marked) instead of resuming")


def _check_output(option: str, path, formats) -> None:
    """``outputs.check_output`` as a one-line UsageError (an OSError of the file system too)."""
    from fruitimpact.impact.outputs import check_output

    try:
        check_output(path, option, formats)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:  # e.g. a name too long to even look up
        raise UsageError(f"argument {option}: cannot write {str(path)!r}: {exc.strerror}") from None


def _check_figure(option: str, path) -> None:
    """A figure path is writable and matplotlib is there, before any work."""
    from fruitimpact.impact.outputs import FIGURE_FORMATS

    if path is None:
        return
    _check_output(option, path, FIGURE_FORMATS)
    if importlib.util.find_spec("matplotlib") is None:
        raise UsageError(f"argument {option}: figures need matplotlib: pip install 'fruitimpact[plot]'")


def _check_run_options(args, plan):
    """The output, the work folder and the engine of ``args``, checked before any work; returns
    (engine, work folder)."""
    from fruitimpact import runs
    from fruitimpact.impact.outputs import TABLE_FORMATS, check_folder

    if args.output is not None:
        _check_output("-o/--output", args.output, TABLE_FORMATS)
    workers = _count("--workers", args.workers, 1, MAX_WORKERS)
    if args.scheduler is not None:
        try:
            runs.engines.check_scheduler(args.scheduler)
        except ValueError as exc:
            raise UsageError(f"argument --scheduler: {exc}") from None
    dask = (args.engine or ("dask" if args.scheduler else "inprocess")) == "dask"
    if dask and importlib.util.find_spec("distributed") is None:
        raise UsageError("argument --engine: dask needs dask[distributed]: pip install 'fruitimpact[dask]'")
    engine = runs.DaskEngine(scheduler=args.scheduler, workers=workers) if dask else runs.InProcessEngine()
    workdir = Path(args.workdir) if args.workdir else runs.default_workdir(args.output, plan)
    existing = workdir
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    try:
        if existing.exists() and not existing.is_dir():
            raise ValueError(f"argument --workdir: cannot use {str(workdir)!r}: {str(existing)!r} is not a folder")
        check_folder(existing, "--workdir", workdir)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return engine, workdir


def _run(args, plan, keep_columns=(), percentiles=None):
    """Execute ``plan`` with the run options of ``args``; one-line errors, resumable interruption."""
    from fruitimpact import runs

    engine, workdir = _check_run_options(args, plan)
    try:
        return runs.execute(plan, args.output, engine=engine, workdir=workdir, fresh=args.fresh,
                            keep_columns=keep_columns, percentiles=percentiles or runs.PERCENTILES)
    except (runs.RunError, ValueError) as exc:
        raise UsageError(str(exc)) from None
    except KeyboardInterrupt:
        print(f"{PROG} {args.command}: interrupted; completed chunks are kept in {workdir}: "
              f"run the same command again to resume", file=sys.stderr)
        return None


def _status_line(summary) -> str:
    """``N rows: a ok, b invalid, c failed`` and any other status evaluate reported."""
    counts = {"ok": summary.ok, "invalid": summary.invalid, "failed": summary.failed}
    others = {k: v for k, v in summary.statuses.items() if k not in counts}
    line = f"{summary.rows} rows: " + ", ".join(f"{v} {k}" for k, v in {**counts, **others}.items())
    if summary.resumed_chunks:
        line += f" ({summary.resumed_chunks} chunks resumed from an earlier run)"
    return line


def _check_constants(constants: dict, text: dict, given=()) -> None:
    """Refuse a constant input out of its range, or an input that a constant needs and nobody gave (the
    energy criterion's threshold), before any chunk runs (one row through impact.evaluation.evaluate)."""
    from fruitimpact.impact.evaluation import evaluate
    from fruitimpact.impact.quantities import INPUTS

    if not constants and not text:
        return
    probe = evaluate({**{k: [v] for k, v in constants.items()}, **{k: [v] for k, v in text.items()}})
    message = str(probe["message"].iloc[0])
    first = message.split(" ", 1)[0]
    if str(probe["status"].iloc[0]) != "invalid" or first in _DEPENDENT_INPUTS:
        return
    # a refusal naming an input nobody gave is one the constants cause (a threshold the energy criterion needs,
    # a failure stress the fruit lacks): it would refuse every member
    if first in set(constants) | set(text) or (first in INPUTS and first not in set(given)):
        raise UsageError(_with_option(message))


def _check_text(name: str, values) -> None:
    from fruitimpact.impact.quantities import option_of
    from fruitimpact.impact.registries import REGISTRIES

    registry = REGISTRIES[name]
    for value in values:
        if value not in registry:
            raise UsageError(f"argument {option_of(name)}: {name} must be one of {', '.join(registry)}; "
                             f"got {value!r}")


def _check_conflicts(given) -> None:
    from fruitimpact.impact.quantities import ALTERNATIVES

    for group in ALTERNATIVES:
        named = [name for name in group if name in given]
        if len(named) > 1:
            options = " or ".join("--" + name.replace("_", "-") for name in named)
            raise UsageError(f"give either {options}, not both")


def cmd_batch(args) -> int:
    from fruitimpact.runs import MAX_CHUNK_ROWS, Plan, TableSource

    try:
        source = TableSource.open(args.input)
    except ValueError as exc:
        raise UsageError(f"argument IN: {exc}") from None
    if args.output and source.path == str(Path(args.output).resolve()):
        raise UsageError("argument -o/--output: must differ from the input file")
    plan = Plan("batch", source, _count("--chunk-size", args.chunk_size, 1, MAX_CHUNK_ROWS))
    summary = _run(args, plan)
    if summary is None:
        return 130
    print(f"batch: {_status_line(summary)}; written to {summary.output}")
    return 0


def cmd_sweep(args) -> int:
    from fruitimpact import runs

    axes, constants, text = [], {}, {}
    order = list(getattr(args, "order", None) or [])
    for dest in order:
        option = "--" + dest.replace("_", "-")
        try:
            axis = runs.parse_axis(dest, getattr(args, dest))
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        if not axis.numeric:
            _check_text(dest, axis.values)
        if len(axis.values) > 1:
            axes.append(axis)
        elif axis.numeric:
            constants[dest] = axis.values[0]
        else:
            text[dest] = axis.values[0]
    _check_conflicts(order)
    _check_constants(constants, text, order)
    try:
        name = runs.characteristic(args.characteristic).name
    except ValueError as exc:
        raise UsageError(f"argument --characteristic: {exc}") from None
    if args.plot and not 1 <= len(axes) <= 2:
        raise UsageError(f"argument --plot: draws one or two swept inputs; {len(axes)} are swept"
                         + (f" ({', '.join(a.name for a in axes)})" if axes else " (give START:STOP:COUNT)"))
    if not (args.output or args.plot):
        raise UsageError("argument -o/--output: give -o OUT and/or --plot FILE")
    _check_figure("--plot", args.plot)
    points = math.prod(len(a.values) for a in axes)
    if points > runs.MAX_ROWS:
        raise UsageError(f"the grid has {points:,} points ({' × '.join(str(len(a.values)) for a in axes)}); "
                         f"a sweep has at most {runs.MAX_ROWS:,}")
    fixed = [runs.Axis(k, (v,)) for k, v in {**constants, **text}.items()]
    grid = runs.GridSource(tuple(axes + fixed))
    plan = runs.Plan("sweep", grid, _count("--chunk-size", args.chunk_size, 1, runs.MAX_CHUNK_ROWS))
    summary = _run(args, plan, keep_columns=(name,) if args.plot else ())
    if summary is None:
        return 130
    shape = " × ".join(f"{len(a.values)} {a.name}" for a in axes) or "1 point"
    print(f"sweep: {shape}; {_status_line(summary)}" + (f"; written to {summary.output}" if summary.output else ""))
    if args.plot:
        _save("--plot", runs.sweep_figure(grid, summary.columns[name], name), args.plot)
        print(f"figure written to {args.plot}")
    return 0


def _save(option: str, fig, path) -> None:
    from fruitimpact.plotting import save_figure

    try:
        save_figure(fig, path, option)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _format_population(summary, names) -> str:
    from fruitimpact.runs import CHARACTERISTICS

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
    from fruitimpact import runs
    from fruitimpact.impact.distributions import Constant, parse_distribution

    rows = _count("-n/--rows", args.rows, 1, runs.MAX_ROWS)
    seed = _count("--seed", args.seed, 0)
    distributions, constants, text = [], {}, {}
    for option, dest, quantity in _run_inputs():
        spec = getattr(args, dest)
        if spec is None:
            continue
        if not quantity.numeric:
            _check_text(dest, [spec])
            text[dest] = spec
            continue
        try:
            dist = parse_distribution(spec, quantity.dimension, dest)
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        distributions.append((dest, dist))
        if isinstance(dist, Constant):
            constants[dest] = dist.value
    _check_conflicts([d for d, _ in distributions])
    _check_constants(constants, text, [d for d, _ in distributions] + list(text))
    spreads, density, spread_lines = lot_distributions(args, text.get("fruit"), [d for d, _ in distributions],
                                                       text.get("criterion"))
    distributions += list(spreads)
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
    _check_figure("--hist", args.hist)
    source = runs.PopulationSource(tuple(distributions), tuple(text.items()), rows, seed, density)
    plan = runs.Plan("population", source, _count("--chunk-size", args.chunk_size, 1, runs.MAX_CHUNK_ROWS),
                     write_rows=args.output is not None, stats=names, thresholds=tuple(thresholds),
                     sample_rows=_count("--sample-size", args.sample_size, 1, runs.MAX_SAMPLE_ROWS))
    summary = _run(args, plan, percentiles=percentiles)
    if summary is None:
        return 130
    if args.hist:
        _save("--hist", runs.histogram_figure(summary.sample, names, summary.percentiles["exact"]), args.hist)
    if args.json:
        report = summary.to_dict()
        report["seed"], report["inputs"] = seed, {name: dist.describe() for name, dist in distributions}
        report["spreads"] = list(spread_lines)
        print(dump_json(report))
    else:
        print_spreads("population", spread_lines)
        print(_format_population(summary, names))
        for what, path in (("rows", summary.output), ("histograms", args.hist)):
            if path:
                print(f"{what} written to {path}")
    return 0


def _input_help(quantity) -> str:
    unit = f" [{quantity.si_unit}]" if quantity.si_unit else ""
    return f"{quantity.name}{unit}"


def add_parsers(sub) -> None:
    """The parsers of ``batch``, ``sweep`` and ``population``."""
    from fruitimpact.runs import MAX_AXIS_VALUES, MAX_ROWS, MAX_SAMPLE_ROWS, PERCENTILES, SAMPLE_ROWS

    bat = sub.add_parser("batch", help="characteristics of every row of a CSV/Parquet file of inputs",
                         description="Rows of inputs (columns named like simulate's options: mass, diameter, "
                                     "modulus, poisson, stiffness, velocity, drop_height, restitution, alpha, "
                                     "model, calibration, method, step, ...; numbers in SI or strings with units; "
                                     "an empty cell takes the default, NaN is invalid) → OUT with the inputs as "
                                     "used, the characteristics, status and message, and the input row number in "
                                     "column 'row'. A bad row (also a ragged CSV row) is marked, never fatal.")
    bat.add_argument("input", metavar="IN", help="input table, .csv or .parquet")
    _add_run_options(bat, output_required=True)
    bat.set_defaults(func=cmd_batch)

    swp = sub.add_parser("sweep", help="characteristics over a grid of inputs",
                         description=f"A grid over ranges of inputs: START:STOP:COUNT (inclusive, linear), "
                                     f"log:START:STOP:COUNT (geometric), V1,V2,... or one value; units allowed "
                                     f"(e.g. --velocity 0.3:1.5:25 --modulus 2MPa:6MPa:41). The first swept "
                                     f"option given varies slowest. Text options take comma lists. At most "
                                     f"{MAX_AXIS_VALUES:,} values per input and {MAX_ROWS:,} grid points.")
    group = swp.add_argument_group("inputs (ranges, lists or values; plain numbers are SI)")
    for option, dest, quantity in _run_inputs():
        if quantity.numeric:
            group.add_argument(option, dest=dest, action=_Ordered, metavar="RANGE", help=_input_help(quantity))
        else:
            group.add_argument(option, dest=dest, action=_Ordered, metavar="LIST",
                               help=f"{dest} name(s), comma-separated")
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
    for option, dest, quantity in _run_inputs():
        if quantity.numeric:
            group.add_argument(option, dest=dest, metavar="SPEC", help=_input_help(quantity))
        else:
            group.add_argument(option, dest=dest, metavar="NAME", help=f"{dest} (one name)")
    group.add_argument("-n", "--rows", default="10000", metavar="N",
                       help=f"members, 1 to {MAX_ROWS:,} (default 10000; 1e7 allowed)")
    group.add_argument("--seed", default="0", metavar="S", help="random seed, integer >= 0, exact (default 0)")
    add_spread_option(group)
    stats = pop.add_argument_group("summary")
    stats.add_argument("--characteristics", metavar="LIST",
                       help="characteristics summarised and histogrammed, comma-separated (default: all twelve)")
    stats.add_argument("--percentiles", default=",".join(f"{p:g}" for p in PERCENTILES), metavar="LIST",
                       help="percentiles [%%] (default 5,25,50,75,95)")
    stats.add_argument("--threshold", action="append", metavar="EXPR",
                       help="count members beyond a threshold, e.g. peak_force>60N (>, >=, <, <=; repeatable)")
    stats.add_argument("--sample-size", default=str(SAMPLE_ROWS), metavar="ROWS",
                       help=f"percentiles are exact up to this many members, above it estimated from a seeded "
                            f"uniform sample of about this size (default {SAMPLE_ROWS}, at most "
                            f"{MAX_SAMPLE_ROWS:,})")
    stats.add_argument("--hist", metavar="FILE", help="histograms of the characteristics (PNG/SVG/PDF)")
    stats.add_argument("--json", action="store_true", help="print the summary as JSON (SI)")
    _add_run_options(pop, output_required=False)
    pop.set_defaults(func=cmd_population)
