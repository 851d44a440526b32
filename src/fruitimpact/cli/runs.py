"""``fruitimpact batch``, ``sweep`` and ``population``: many impacts, chunked and resumable."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .common import (PROG, RUN_NUMERIC, RUN_TEXT, _SI_OF, UsageError, _positive_count, _with_option,
                     dump_json)


#: Inputs whose range depends on other inputs: not checked alone when constant.
_DEPENDENT_INPUTS = ("alpha", "step")


class _Ordered(argparse.Action):
    """Store the value and remember the order in which the options were given (sweep axes)."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.order = [d for d in (getattr(namespace, "order", None) or []) if d != self.dest] + [self.dest]



def _add_run_options(parser: argparse.ArgumentParser, output_required: bool) -> None:
    from ..runs import CHUNK_ROWS, ENGINES

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
    from .. import runs

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
    from ..batch import evaluate

    if not constants and not text:
        return
    probe = evaluate({**{k: [v] for k, v in constants.items()}, **{k: [v] for k, v in text.items()}})
    message = probe["message"].iloc[0]
    if probe["status"].iloc[0] == "invalid" and message.split(" ", 1)[0] in set(constants) | set(text) \
            and message.split(" ", 1)[0] not in _DEPENDENT_INPUTS:
        raise UsageError(_with_option(message))


def _check_text(name: str, values) -> None:
    from ..models import CALIBRATIONS, DAMPING_LAWS
    from ..solvers import SOLVERS

    registry = {"model": DAMPING_LAWS, "calibration": CALIBRATIONS, "method": SOLVERS}[name]
    for value in values:
        if value not in registry:
            raise UsageError(f"argument --{name}: {name} must be one of {', '.join(registry)}; got {value!r}")


def _check_conflicts(given) -> None:
    for first, second in (("velocity", "drop_height"), ("restitution", "alpha")):
        if first in given and second in given:
            raise UsageError(f"give either --{first.replace('_', '-')} or --{second.replace('_', '-')}, not both")


def cmd_batch(args) -> int:
    from ..runs import Plan, TableSource

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
    from .. import runs

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
        from ..plotting import save_figure

        save_figure(runs.sweep_figure(grid, summary.columns[name], name), args.plot)
        print(f"figure written to {args.plot}")
    return 0


def _format_population(summary, names) -> str:
    from ..runs import CHARACTERISTICS

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
    from .. import runs
    from ..distributions import Constant, parse_distribution

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
        from ..plotting import save_figure

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



def add_parsers(sub) -> None:
    """The parsers of ``batch``, ``sweep`` and ``population``."""
    from ..runs import PERCENTILES, SAMPLE_ROWS

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

