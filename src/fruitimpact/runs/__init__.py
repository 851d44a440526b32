"""Large runs: batch files, parameter sweeps and Monte Carlo populations.

A run is a ``Plan``: a *source* of input rows (a table file, a grid, a
population of distributions), cut into chunks of ``chunk_rows`` rows.  Each
chunk is evaluated by ``fruitimpact.impact.evaluation.evaluate``; its rows are written as
a part file in a work folder (and, in this process, straight into the output),
with a summary file for populations, and recorded with their SHA-256 in the
folder's manifest.  A different job is refused instead of mixed in; an
interrupted run, re-run with the same command, skips the verified complete
chunks: no row is lost or doubled.  Chunks run in this process or as tasks on
a Dask cluster, with the same output.  Memory stays bounded by a few chunks.

One module per job:

* ``plan``: ``Plan``, ``Threshold``, the limits of a run, ``RunError``;
* ``sources``: table files (pyarrow, streamed), grids, populations;
* ``chunks``: evaluating, summarising and writing one chunk (``run_chunk``);
* ``workdir``: the work folder: ownership marker, manifest, verification, cleanup;
* ``locking``: one run at a time on a work folder and on an output;
* ``engines``: in-process and Dask;
* ``summaries``: status counts, streamed statistics, percentiles;
* ``execute``: the driver.

Population members are drawn from generators derived from
``SeedSequence(seed, spawn_key=(block, stream))`` for fixed blocks of
``BLOCK_ROWS`` rows, so a member's inputs depend only on the seed and its row
number: the same for any chunk size, engine, or interruption.
"""

from fruitimpact.plotting.runs import histogram_figure, sweep_figure
from fruitimpact.impact.quantities import CHARACTERISTICS, DEFAULT_SUMMARY, INPUTS, Quantity
from fruitimpact.runs.chunks import evaluate_rows, run_chunk
from fruitimpact.runs.engines import ENGINES, DaskEngine, InProcessEngine
from fruitimpact.runs import execute as execute_module  # noqa: F401  (the module, for tests that patch it)
from fruitimpact.runs.execute import default_workdir, execute, merge_parts, read_column
from fruitimpact.runs.plan import (BLOCK_ROWS, CHUNK_ROWS, MAX_AXIS_VALUES, MAX_CHUNK_ROWS, MAX_ROWS, MAX_SAMPLE_ROWS, PERCENTILES,
                   SAMPLE_ROWS, Plan, RunError, Threshold, characteristic, characteristics_list)
from fruitimpact.runs.sources import Axis, GridSource, PopulationSource, TableSource, parse_axis, table_format
from fruitimpact.runs.summaries import RunSummary

__all__ = ["BLOCK_ROWS", "CHARACTERISTICS", "CHUNK_ROWS", "DEFAULT_SUMMARY", "ENGINES", "INPUTS", "MAX_AXIS_VALUES",
           "MAX_CHUNK_ROWS", "MAX_ROWS", "MAX_SAMPLE_ROWS", "PERCENTILES", "SAMPLE_ROWS", "Axis", "DaskEngine",
           "GridSource", "InProcessEngine", "Plan", "PopulationSource", "Quantity", "RunError", "RunSummary",
           "TableSource", "Threshold", "characteristic", "characteristics_list", "default_workdir", "evaluate_rows",
           "execute", "histogram_figure", "merge_parts", "parse_axis", "read_column", "run_chunk", "sweep_figure",
           "table_format"]
