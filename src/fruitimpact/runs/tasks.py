"""The three runs of many impacts as Python functions: ``batch``, ``sweep`` and ``population``.

Each is the CLI command of the same name (``fruitimpact batch``, ``sweep``, ``population``) and goes
through the same checks, in the same order, before any work: the CLI calls the ``*_plan`` functions
and ``run`` below and only adds its figures and its printing.  A refused argument is an
``impact.validation.InputError`` (a ``ValueError``) naming the argument; a run that cannot start or
continue (a work folder of another job, a lock held, a full disk) is a ``RunError``.  An interrupted run
(Ctrl-C) keeps its completed chunks in the work folder: the same call resumes it.
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Mapping
from pathlib import Path


from fruitimpact.impact.validation import (InputError, check_choice, check_conflicts, check_flag, check_input_name, is_boolean,
                                           read_count, refuse_out_of_range, spec_text)
from fruitimpact.impact.lots import PRECHECK_ROWS
from fruitimpact.runs.plan import (CHUNK_ROWS, MAX_CHUNK_ROWS, MAX_ROWS, MAX_SAMPLE_ROWS, PERCENTILES, SAMPLE_ROWS,
                                   Plan, Threshold, characteristic, characteristics_list,
                                   check_criterion_for)

#: Most worker processes of a local Dask cluster.
MAX_WORKERS = 256
#: Processes of a local Dask cluster when ``workers`` is not given.
DEFAULT_WORKERS = 2
#: Most grid points ``sweep`` returns as a DataFrame (about 1 kB a row); larger grids go to a file.
MAX_FRAME_ROWS = 2_000_000


# --- the run: output, work folder, engine ------------------------------------------------------------------------

def check_run(plan, output=None, *, engine=None, scheduler=None, workers=None, workdir=None):
    """The output, the engine and the work folder of a run, checked before any work: (engine, work folder).

    ``engine``: ``"inprocess"`` (default) or ``"dask"`` (implied by ``scheduler``, a Dask address such as
    ``tcp://10.0.0.5:8786``); ``workers``: processes of a local Dask cluster, 1 to ``MAX_WORKERS``;
    ``workdir``: the folder of the part files (default ``OUTPUT.parts``), new, empty or one fruitimpact made."""
    from fruitimpact import runs
    from fruitimpact.impact.outputs import TABLE_FORMATS, check_folder, check_output

    if output is not None:
        try:
            check_output(output, "output", TABLE_FORMATS)
        except ValueError as exc:
            raise InputError(str(exc), "output") from None
    workers = DEFAULT_WORKERS if workers is None else read_count("workers", workers, 1, MAX_WORKERS)
    if scheduler is not None:
        try:
            runs.engines.check_scheduler(scheduler)
        except ValueError as exc:
            raise InputError(f"scheduler: {exc}", "scheduler") from None
    engine = check_choice("engine", engine or ("dask" if scheduler else "inprocess"), tuple(runs.ENGINES))
    if engine == "dask" and importlib.util.find_spec("distributed") is None:
        raise InputError("engine dask needs dask[distributed]: pip install 'fruitimpact[dask]'", "engine")
    chosen = runs.DaskEngine(scheduler=scheduler, workers=workers) if engine == "dask" else runs.InProcessEngine()
    folder = Path(workdir) if workdir else runs.default_workdir(output, plan)
    if output is not None and folder.resolve() == Path(output).resolve():
        raise InputError(f"workdir: cannot use {str(folder)!r}: it is the output file's own name", "workdir")
    # the folder itself may be made (and is removed with the parts), never the folders above it: a run removes
    # only what it made, and a chain of new folders would stay behind (as an output in a missing folder is refused)
    existing = folder if folder.exists() else folder.parent
    try:
        if existing.exists() and not existing.is_dir():
            raise ValueError(f"workdir: cannot use {str(folder)!r}: {str(existing)!r} is not a folder")
        check_folder(existing, "workdir", folder)
    except ValueError as exc:
        raise InputError(str(exc), "workdir") from None
    return chosen, folder


def run(plan, output=None, *, engine=None, scheduler=None, workers=None, workdir=None, fresh: bool = False,
        keep_columns=(), percentiles=PERCENTILES):
    """Execute ``plan`` (``runs.execute``) after ``check_run``; returns the ``RunSummary``.  ``fresh`` discards
    the parts of another job in the work folder (only a folder fruitimpact made and marked)."""
    fresh = check_flag("fresh", fresh)
    checked = check_run(plan, output, engine=engine, scheduler=scheduler, workers=workers, workdir=workdir)
    return start(plan, output, checked, fresh=fresh, keep_columns=keep_columns, percentiles=percentiles)


def start(plan, output, checked, *, fresh: bool = False, keep_columns=(), percentiles=PERCENTILES):
    """``run`` once ``check_run`` has answered ``checked`` (engine, work folder), for a caller that needs the
    work folder before the run starts (the CLI names it when interrupted)."""
    from fruitimpact.runs.driver import execute

    engine, folder = checked
    return execute(plan, output, engine=engine, workdir=folder, fresh=fresh, keep_columns=keep_columns,
                   percentiles=percentiles)


# --- the inputs of a grid ------------------------------------------------------------------------------------------

def _texts(inputs: Mapping) -> dict[str, str]:
    """The given inputs (None: not given) as the CLI's texts, each name checked."""
    return {name: spec_text(name, value) for name, value in inputs.items()
            if check_input_name(name) and value is not None}


# --- batch -----------------------------------------------------------------------------------------------------------

def batch_plan(input, output=None, chunk_size=CHUNK_ROWS) -> Plan:
    """The plan of ``batch``: the table file ``input`` (CSV or Parquet, streamed) in chunks of ``chunk_size``."""
    from fruitimpact.runs.sources import TableSource

    chunk_size = read_count("chunk_size", chunk_size, 1, MAX_CHUNK_ROWS)
    if output:  # before the input is read and hashed (1 s per GB): a bad output is answered at once
        from fruitimpact.impact.outputs import TABLE_FORMATS, check_output

        check_output(output, "-o/--output", TABLE_FORMATS)
        if Path(input).exists() and Path(output).exists() and Path(output).samefile(input):
            raise InputError("output must differ from the input file", "output")
    try:
        source = TableSource.open(input)
    except ValueError as exc:
        raise InputError(f"input: {exc}", "input") from None
    if output and source.path == str(Path(output).resolve()):
        raise InputError("output must differ from the input file", "output")
    return Plan("batch", source, chunk_size)


def batch(input, output, *, chunk_size=CHUNK_ROWS, engine=None, scheduler=None, workers=None, workdir=None,
          fresh: bool = False):
    """Characteristics of every row of a CSV or Parquet file of inputs, into a CSV or Parquet file.

    Parameters
    ----------
    input : str or Path
        Rows of inputs, columns named like :func:`fruitimpact.simulate`'s inputs (``mass`` [kg], ``diameter``
        [m], ``modulus`` [Pa], ``velocity`` [m/s], ``drop_height`` [m], ``restitution``, ``model``, ...; SI
        numbers or strings with units; an empty cell takes the default, NaN is invalid).  An unknown column is refused.
    output : str or Path
        ``.csv``, ``.parquet`` or ``.pq``: every row with its inputs as used, the characteristics, ``status``,
        ``message`` and ``warnings``, and the input row number in ``row``.  Written atomically.
    chunk_size : int or str
        Rows per chunk, 1 to 10,000,000 (default 500,000; ``"1e6"`` accepted); each chunk is written to the work
        folder as soon as it is done, and an interrupted run resumes from there.
    engine : str, optional
        ``"inprocess"`` (default: this process, every core through the compiled kernels) or ``"dask"``.
    scheduler : str, optional
        A Dask scheduler address (``tcp://10.0.0.5:8786``); implies ``engine="dask"``.
    workers : int or str, optional
        Worker processes of a local Dask cluster, 1 to 256 (default 2).
    workdir : str or Path, optional
        The work folder of the part files (default ``OUTPUT.parts``): new, empty, or one fruitimpact made.
    fresh : bool
        Discard the parts of another job in the work folder (only a folder fruitimpact made and marked) instead
        of refusing.

    Returns
    -------
    RunSummary
        Rows per status (``ok``, ``invalid``, ``failed``, ``statuses``), ``output``, ``resumed_chunks``.

    Raises
    ------
    ValueError
        An input file that cannot be read or has unknown columns, an output that cannot be written or is the
        input, an argument out of range (the message names it).  A bad row never raises: it is ``invalid``.
    RunError
        A work folder of another job or in use, an input changed during the run, a failed write (the completed
        chunks are kept: the same call resumes).

    Examples
    --------
    >>> import fruitimpact as fi
    >>> summary = fi.batch("examples/fruit.csv", "results.parquet")  # doctest: +SKIP
    >>> summary.rows, summary.ok, summary.invalid  # doctest: +SKIP
    (12, 12, 0)

    References
    ----------
    Each row as :func:`fruitimpact.evaluate` (the founding paper's model, "Theoretical aspects about
    simulating the reaction to impact of apples on rigid plane surfaces", and the damping laws' sources).
    """
    if output is None:
        raise InputError("output must be given: a .csv or .parquet file for every row", "output")
    plan = batch_plan(input, output, chunk_size)
    return run(plan, output, engine=engine, scheduler=scheduler, workers=workers, workdir=workdir, fresh=fresh)


# --- sweep ------------------------------------------------------------------------------------------------------------

def sweep_plan(axes_text: Mapping, chunk_size=CHUNK_ROWS, write_rows: bool = True):
    """(plan, swept axes) of a sweep over ``axes_text`` (input → ``START:STOP:COUNT``, ``log:...``, a comma
    list or one value, in the order given: the first varies slowest)."""
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.runs.sources import Axis, GridSource, parse_axis

    chunk_size = read_count("chunk_size", chunk_size, 1, MAX_CHUNK_ROWS)
    if not axes_text:
        raise InputError("give at least one input to sweep: a range START:STOP:COUNT, a list or a value (e.g. "
                         "velocity 0.3:1.5:25)")
    axes, constants, text = [], {}, {}
    for name, spec in axes_text.items():
        try:
            axis = parse_axis(name, spec)
        except ValueError as exc:
            raise InputError(f"{name}: {exc}", name) from None
        if not axis.numeric:
            for value in axis.values:
                check_choice(name, value, REGISTRIES[name])
        if len(axis.values) > 1:
            axes.append(axis)
        elif axis.numeric:
            constants[name] = axis.values[0]
        else:
            text[name] = axis.values[0]
    check_conflicts(list(axes_text))
    refuse_out_of_range(constants)  # at once: the one-row evaluation below loads the engine (numba)
    from fruitimpact.impact.refusals import refuse_constants

    refuse_constants(constants, text, list(axes_text))
    points = math.prod(len(a.values) for a in axes)
    if points > MAX_ROWS:
        raise InputError(f"the grid has {points:,} points ({' × '.join(str(len(a.values)) for a in axes)}); "
                         f"a sweep has at most {MAX_ROWS:,}")
    fixed = [Axis(k, (v,)) for k, v in {**constants, **text}.items()]
    grid = GridSource(tuple(axes + fixed))
    if points <= PRECHECK_ROWS:  # a bound that depends on the swept inputs (rk4's step), judged on the whole grid
        from fruitimpact.impact.refusals import refuse_lot

        refuse_lot(grid.inputs(0, points, None)[0], list(axes_text), f"the grid's {points:,} points")
    return Plan("sweep", grid, chunk_size, write_rows=write_rows), tuple(axes)


def sweep(output=None, *, chunk_size=CHUNK_ROWS, engine=None, scheduler=None, workers=None, workdir=None,
          fresh: bool = False, **inputs):
    """Characteristics over a grid of inputs.

    Parameters
    ----------
    output : str or Path, optional
        A ``.csv`` or ``.parquet`` file for every grid point (a chunked, resumable run, as ``fruitimpact sweep
        -o``).  Without it the grid (at most 2,000,000 points) is returned as a DataFrame.
    **inputs
        Each input of :func:`fruitimpact.evaluate` by name: a range ``"START:STOP:COUNT"`` (inclusive,
        linear; units allowed, ``"2MPa:6MPa:41"``), ``"log:START:STOP:COUNT"`` (geometric), a list of values
        (``[0.5, 1.0]``, ``"chen,flores"``) or one value.  The first swept input given varies slowest.
    chunk_size : int or str
        With ``output`` only, as the other run options below.  Rows per chunk, 1 to 10,000,000 (default 500,000; ``"1e6"`` accepted); each chunk is written to the work
        folder as soon as it is done, and an interrupted run resumes from there.
    engine : str, optional
        ``"inprocess"`` (default: this process, every core through the compiled kernels) or ``"dask"``.
    scheduler : str, optional
        A Dask scheduler address (``tcp://10.0.0.5:8786``); implies ``engine="dask"``.
    workers : int or str, optional
        Worker processes of a local Dask cluster, 1 to 256 (default 2).
    workdir : str or Path, optional
        The work folder of the part files (default ``OUTPUT.parts``): new, empty, or one fruitimpact made.
    fresh : bool
        Discard the parts of another job in the work folder (only a folder fruitimpact made and marked) instead
        of refusing.

    Returns
    -------
    pandas.DataFrame or RunSummary
        Without ``output``: one row per grid point, the columns of :func:`fruitimpact.evaluate`.  With it
        (as ``pandas.DataFrame.to_csv`` returns nothing once given a path): the ``RunSummary``.

    Raises
    ------
    ValueError
        An unknown input, a bad range (a COUNT that is not an integer in [1, 1,000,000], a log range through
        0), a constant out of range, conflicting inputs (``velocity`` and ``drop_height``), a grid too large;
        the message names the argument.  A bad grid point never raises: it is ``invalid``.
    RunError
        As :func:`batch`.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> grid = fi.sweep(velocity="0.5:1.5:3", modulus="2MPa,4MPa")
    >>> grid[["velocity", "modulus", "status"]].shape
    (6, 3)
    >>> round(float(grid["restitution"].iloc[0]), 3)
    0.577

    References
    ----------
    Each point as :func:`fruitimpact.evaluate`.
    """
    plan, axes = sweep_plan(_texts(inputs), chunk_size)
    if output is not None:
        return run(plan, output, engine=engine, scheduler=scheduler, workers=workers, workdir=workdir, fresh=fresh)
    asked = {"engine": engine is not None, "scheduler": scheduler is not None, "workers": workers is not None,
             "workdir": workdir is not None, "fresh": bool(fresh)}
    for name, given in asked.items():
        if given:  # a run option without a run would be silently ignored
            raise InputError(f"{name} applies to a run into a file: give output (a .csv or .parquet file) with it, "
                             f"or leave {name} out for a DataFrame", name)
    if plan.rows > MAX_FRAME_ROWS:
        raise InputError(f"output must be given for a grid of {plan.rows:,} points (more than {MAX_FRAME_ROWS:,} "
                         f"are written to a file, not returned)", "output")
    from fruitimpact.runs.chunks import evaluate_rows

    columns, _ = plan.source.inputs(0, plan.rows, None)
    return evaluate_rows(columns, 0).frame()  # the rows a chunk of the file run would write


# --- population --------------------------------------------------------------------------------------------------------

def population_plan(inputs: Mapping, *, rows=10_000, seed=0, spreads: bool = True, characteristics=None,
                    thresholds=(), sample_size=SAMPLE_ROWS, chunk_size=CHUNK_ROWS, write_rows: bool = False):
    """(plan, lines describing the library spreads) of a population; ``inputs``: input → a constant or a
    distribution text (``"normal(115g,10g)"``).  The drawn distributions are ``plan.source.distributions``."""
    from fruitimpact.impact.lots import MAX_SEED, read_lot
    from fruitimpact.impact.quantities import DEFAULT_SUMMARY

    spreads = check_flag("spreads", spreads)
    rows = read_count("rows", rows, 1, MAX_ROWS)
    seed = read_count("seed", seed, 0, MAX_SEED)
    source, _, described = read_lot(inputs, rows=rows, seed=seed, spreads=spreads)
    try:
        if characteristics is None:
            names = DEFAULT_SUMMARY
        elif isinstance(characteristics, str):
            names = characteristics_list(characteristics)
        else:
            names = tuple(characteristic(str(name)).name for name in characteristics)
            if not names:
                raise ValueError("give at least one characteristic")
    except ValueError as exc:
        raise InputError(f"characteristics: {exc}", "characteristics") from None
    check_criterion_for(names, inputs.get("criterion"))
    parsed = []
    if thresholds is None or not isinstance(thresholds, (str, list, tuple)):
        raise InputError(f"threshold: thresholds are texts such as 'peak_force>60N', one or a list; got "
                         f"{thresholds!r}", "threshold")
    for item in [thresholds] if isinstance(thresholds, str) else thresholds:
        try:
            parsed.append(item if isinstance(item, Threshold) else Threshold.parse(str(item)))
        except ValueError as exc:
            raise InputError(f"threshold: {exc}", "threshold") from None
    plan = Plan("population", source, read_count("chunk_size", chunk_size, 1, MAX_CHUNK_ROWS), write_rows=write_rows,
                stats=tuple(names), thresholds=tuple(parsed),
                sample_rows=read_count("sample_size", sample_size, 1, MAX_SAMPLE_ROWS))
    return plan, tuple(described)


def check_percentiles(percentiles) -> tuple[float, ...]:
    """Percentiles [%], each in [0, 100]: a sequence or a comma list ``"5,50,95"``."""
    try:
        items = percentiles.split(",") if isinstance(percentiles, str) else list(percentiles)
        if any(is_boolean(p) for p in items):
            raise TypeError
        values = tuple(float(p) for p in items)
    except (TypeError, ValueError):
        values = (math.nan,)
    if not values or not all(0 <= p <= 100 for p in values):
        raise InputError(f"percentiles: each must be a number in [0, 100]; got {percentiles!r}", "percentiles")
    return values


def population(rows=10_000, *, seed=0, spreads: bool = True, characteristics=None, percentiles=PERCENTILES,
               thresholds=(), sample_size=SAMPLE_ROWS, output=None, chunk_size=CHUNK_ROWS, engine=None,
               scheduler=None, workers=None, workdir=None, fresh: bool = False, **inputs):
    """A Monte Carlo population of impacts: statistics, percentiles and threshold shares.

    Parameters
    ----------
    rows : int or str
        Members, 1 to 1,000,000,000 (``"1e7"`` accepted).
    seed : int or str
        Random seed ≥ 0, exact: the same call gives the same members, for any chunk size or engine.
    spreads : bool
        Draw the inputs not given from the fruit's library spreads (a real lot varies); False: identical fruit.
    characteristics : str or sequence of str, optional
        Characteristics summarised (default: all twelve).
    percentiles : sequence of float or str
        Percentiles [%] (default 5, 25, 50, 75, 95).
    thresholds : sequence of str
        Members beyond a threshold, counted exactly, e.g. ``"peak_force>60N"`` (>, >=, <, <=).
    sample_size : int
        Percentiles are exact up to this many members, above it estimated from a seeded uniform sample.
    output : str or Path, optional
        Also write every member's row (CSV or Parquet).
    chunk_size : int or str
        Rows per chunk, 1 to 10,000,000 (default 500,000; ``"1e6"`` accepted); each chunk is written to the work
        folder as soon as it is done, and an interrupted run resumes from there.
    engine : str, optional
        ``"inprocess"`` (default: this process, every core through the compiled kernels) or ``"dask"``.
    scheduler : str, optional
        A Dask scheduler address (``tcp://10.0.0.5:8786``); implies ``engine="dask"``.
    workers : int or str, optional
        Worker processes of a local Dask cluster, 1 to 256 (default 2).
    workdir : str or Path, optional
        The work folder of the part files (default ``OUTPUT.parts``): new, empty, or one fruitimpact made.
    fresh : bool
        Discard the parts of another job in the work folder (only a folder fruitimpact made and marked) instead
        of refusing.
    **inputs
        Each input a constant (``mass=0.115``, ``"115g"``) or a distribution: ``"normal(mean,sd)"``,
        ``"lognormal(median,sigma)"``, ``"uniform(lo,hi)"``, ``"truncnormal(mean,sd,lo,hi)"``,
        ``"sample(FILE[:COLUMN])"`` (units allowed inside).

    Returns
    -------
    RunSummary
        ``statistics`` (per characteristic: mean, sd, min, max, percentiles [SI]), ``thresholds`` (count, of,
        share), ``percentiles`` (the method), status counts; ``to_dict()`` is ``fruitimpact population
        --json`` (with ``seed``, ``inputs`` and ``spreads``).

    Raises
    ------
    ValueError
        An unknown input, a distribution or constant out of range, conflicting inputs, a bad threshold or
        percentile; the message names the argument.
    RunError
        As :func:`batch`.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> lot = fi.population(2000, fruit="apple", drop_height="uniform(5cm,30cm)", criterion="shear",
    ...                     thresholds=["peak_force>60N"])
    >>> lot.ok, sorted(lot.statistics)[:2]
    (2000, ['absorbed_energy', 'contact_duration'])

    References
    ----------
    Each member as :func:`fruitimpact.evaluate`; the lot spreads: docs/library.md.
    """
    percentiles = check_percentiles(percentiles)
    from fruitimpact.impact.lots import lot_details

    plan, described = population_plan(
        inputs, rows=rows, seed=seed, spreads=spreads, characteristics=characteristics, thresholds=thresholds,
        sample_size=sample_size, chunk_size=chunk_size, write_rows=output is not None)
    summary = run(plan, output, engine=engine, scheduler=scheduler, workers=workers, workdir=workdir, fresh=fresh,
                  percentiles=percentiles)
    summary.details = lot_details(plan.source, described)
    return summary


__all__ = ["MAX_FRAME_ROWS", "MAX_WORKERS", "batch", "batch_plan", "check_percentiles", "check_run", "population",
           "population_plan", "run", "start", "sweep", "sweep_plan"]
