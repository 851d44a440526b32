"""``fruitimpact batch``, ``sweep`` and ``population``: many impacts, chunked and resumable.

Every option, output path, figure path, the work folder and the limits of a
run are checked before any work: a bad one is one line naming the option and
its allowed range, exit status 2.
"""

from __future__ import annotations

import argparse
import sys

from fruitimpact.cli.common import (PROG, UsageError, _library_call, _Ordered, add_spread_option, check_outputs,
                                    dump_json, print_spreads, usage_message)
from fruitimpact.impact.outputs import FIGURE_FORMATS

def _run_inputs():
    """(option, name, quantity) of every input of the table of quantities, numeric first."""
    from fruitimpact.impact.quantities import INPUTS

    return [(quantity.option or "--" + name.replace("_", "-"), name, quantity) for name, quantity in INPUTS.items()]


def _add_run_options(parser: argparse.ArgumentParser, output_required: bool) -> None:
    from fruitimpact.runs import CHUNK_ROWS, ENGINES, MAX_CHUNK_ROWS
    from fruitimpact.runs.tasks import DEFAULT_WORKERS, MAX_WORKERS

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
    group.add_argument("--workers", default=str(DEFAULT_WORKERS), metavar="N", help=f"worker processes of the local Dask cluster, "
                                                                  f"1 to {MAX_WORKERS} (default {DEFAULT_WORKERS}; one thread each)")
    group.add_argument("--workdir", metavar="DIR", help="work folder of the part files (default OUT.parts); a new "
                                                        "or empty folder, or one fruitimpact made")
    group.add_argument("--fresh", action="store_true",
                       help="discard the parts of another job in the work folder (only ever a folder fruitimpact "
                            "made and marked) instead of resuming")


def _run_options(args) -> dict:
    """The run options of ``args`` as ``runs.tasks.check_run`` names them."""
    return dict(engine=args.engine, scheduler=args.scheduler, workers=args.workers, workdir=args.workdir)


def _run(args, plan, keep_columns=(), percentiles=None):
    """``runs.tasks.run`` of ``plan`` with the run options of ``args``: the output, the work folder and the
    engine checked before any work; one-line errors; an interruption keeps the completed chunks."""
    from fruitimpact import runs
    from fruitimpact.runs import tasks

    checked = _library_call(tasks.check_run, plan, args.output, **_run_options(args))
    try:
        return tasks.start(plan, args.output, checked, fresh=args.fresh, keep_columns=keep_columns,
                           percentiles=percentiles or runs.PERCENTILES)
    except ValueError as exc:
        raise UsageError(usage_message(exc)) from None
    except runs.RunError as exc:
        raise UsageError(str(exc)) from None
    except KeyboardInterrupt:
        from fruitimpact.runs.workdir import recorded_chunks

        # what the manifest records, not whether the folder is there (a --workdir of the user's stays, empty)
        kept = (f"completed chunks are kept in {checked[1]}: run the same command again to resume"
                if checked[1] is not None and recorded_chunks(checked[1]) else "no chunk was complete: nothing kept")
        print(f"{PROG} {args.command}: interrupted; {kept}", file=sys.stderr)
        return None


def _outcome(command: str, summary) -> int:
    """The exit status of a finished run: 0, or 1 with one line on stderr when no row is ok (every row refused or
    failed: nothing was computed that a user could take, though each row's message says why).  Each warning the
    rows carry is said once on stderr, with how many rows carry it (a 180 kg fruit in a lot, as ``simulate`` says
    it for one)."""
    for line in summary.warning_lines():
        print(f"{PROG} {command}: warning: {line}", file=sys.stderr)
    if summary.rows and not summary.ok:
        where = f"; each row's message in {summary.output} says why" if summary.output else ""
        print(f"{PROG} {command}: no row is ok ({_status_line(summary)}){where}", file=sys.stderr)
        return 1
    return 0


def _status_line(summary) -> str:
    """``N rows: a ok, b invalid, c failed`` and any other status evaluate reported."""
    counts = {"ok": summary.ok, "invalid": summary.invalid, "failed": summary.failed}
    others = {k: v for k, v in summary.statuses.items() if k not in counts}
    line = f"{summary.rows} rows: " + ", ".join(f"{v} {k}" for k, v in {**counts, **others}.items())
    if summary.resumed_chunks:
        line += f" ({summary.resumed_chunks} chunks resumed from an earlier run)"
    return line


def cmd_batch(args) -> int:
    from fruitimpact.runs import tasks

    plan = _library_call(tasks.batch_plan, args.input, args.output, args.chunk_size)
    summary = _run(args, plan)
    if summary is None:
        return 130
    print(f"batch: {_status_line(summary)}; written to {summary.output}")
    return _outcome("batch", summary)


def cmd_sweep(args) -> int:
    from fruitimpact import runs
    from fruitimpact.runs import tasks

    order = list(getattr(args, "order", None) or [])
    check_outputs(("--plot", args.plot, FIGURE_FORMATS), args=args)
    plan, axes = _library_call(tasks.sweep_plan, {dest: getattr(args, dest) for dest in order}, args.chunk_size)
    try:
        name = runs.characteristic(args.characteristic).name
    except ValueError as exc:
        raise UsageError(f"argument --characteristic: {exc}") from None
    if args.plot:  # before the run: a figure of a bruise characteristic needs the criterion
        from fruitimpact.runs.plan import check_criterion_for

        _library_call(check_criterion_for, (name,), getattr(args, "criterion", None))
    if args.plot and not 1 <= len(axes) <= 2:
        raise UsageError(f"argument --plot: draws one or two swept inputs; {len(axes)} are swept"
                         + (f" ({', '.join(a.name for a in axes)})" if axes else " (give START:STOP:COUNT)"))
    if not (args.output or args.plot):
        raise UsageError("argument -o/--output: give -o OUT and/or --plot FILE")
    summary = _run(args, plan, keep_columns=(name,) if args.plot else ())
    if summary is None:
        return 130
    shape = " × ".join(f"{len(a.values)} {a.name}" for a in axes) or "1 point"
    print(f"sweep: {shape}; {_status_line(summary)}" + (f"; written to {summary.output}" if summary.output else ""))
    if args.plot:
        import numpy as np

        values = np.asarray(summary.columns[name], dtype=float)
        if not np.isfinite(values).any():  # an empty frame is not a figure of the sweep
            print(f"{PROG} sweep: no figure: {name} is not a finite number at any grid point (a bruise figure needs "
                  f"--criterion; see the rows' messages)", file=sys.stderr)
            return 1
        _save("--plot", runs.sweep_figure(plan.source, values, name), args.plot)
        print(f"figure written to {args.plot}")
    return _outcome("sweep", summary)


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
    from fruitimpact.runs import tasks

    inputs = {dest: getattr(args, dest) for _, dest, _ in _run_inputs() if getattr(args, dest) is not None}
    percentiles = _library_call(tasks.check_percentiles, args.percentiles)
    plan, spread_lines = _library_call(
        tasks.population_plan, inputs, rows=args.rows, seed=args.seed, spreads=not args.no_spreads,
        characteristics=args.characteristics, thresholds=args.threshold or (), sample_size=args.sample_size,
        chunk_size=args.chunk_size, write_rows=args.output is not None)
    check_outputs(("--hist", args.hist, FIGURE_FORMATS), args=args)
    summary = _run(args, plan, percentiles=percentiles)
    if summary is None:
        return 130
    from fruitimpact.impact.lots import lot_details

    summary.details = lot_details(plan.source, spread_lines)
    names = plan.stats
    if args.hist:
        _save("--hist", runs.histogram_figure(summary.sample, names, summary.percentiles["exact"]), args.hist)
    if args.json:
        print(dump_json(summary.to_dict()))
    else:
        print_spreads("population", spread_lines)
        print(_format_population(summary, names))
        for what, path in (("rows", summary.output), ("histograms", args.hist)):
            if path:
                print(f"{what} written to {path}")
    return _outcome("population", summary)


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
    group.add_argument("--seed", default="0", metavar="S", help="random seed, an integer from 0 to 2^128 - 1, exact (default 0)")
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
