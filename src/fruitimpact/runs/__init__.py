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
* ``driver``: the driver (``execute``).

Population members are drawn from generators derived from
``SeedSequence(seed, spawn_key=(block, stream))`` for fixed blocks of
``BLOCK_ROWS`` rows, so a member's inputs depend only on the seed and its row
number: the same for any chunk size, engine, or interruption.
"""

import importlib

# Imported on first use (PEP 562), so that the CLI's parser can read the limits of a run without
# loading pyarrow, the engine or plotting.
_EXPORTS = {
    "histogram_figure": "fruitimpact.plotting.runs", "sweep_figure": "fruitimpact.plotting.runs",
    "CHARACTERISTICS": "fruitimpact.impact.quantities", "DEFAULT_SUMMARY": "fruitimpact.impact.quantities",
    "INPUTS": "fruitimpact.impact.quantities", "Quantity": "fruitimpact.impact.quantities",
    "evaluate_rows": "fruitimpact.runs.chunks", "run_chunk": "fruitimpact.runs.chunks",
    "ENGINES": "fruitimpact.runs.engines", "DaskEngine": "fruitimpact.runs.engines",
    "InProcessEngine": "fruitimpact.runs.engines",
    "default_workdir": "fruitimpact.runs.driver", "execute": "fruitimpact.runs.driver",
    "merge_parts": "fruitimpact.runs.driver", "read_column": "fruitimpact.runs.driver",
    "RunSummary": "fruitimpact.runs.summaries",
    **{name: "fruitimpact.runs.plan" for name in (
        "CHUNK_ROWS", "MAX_AXIS_VALUES", "MAX_CHUNK_ROWS", "MAX_ROWS", "MAX_SAMPLE_ROWS",
        "PERCENTILES", "SAMPLE_ROWS", "Plan", "RunError", "Threshold", "characteristic", "characteristics_list")},
    **{name: "fruitimpact.runs.sources" for name in (
        "Axis", "GridSource", "TableSource", "parse_axis", "table_format")},
    # a lot is drawn the same way by a population run and a line audit: it lives with the impacts
    "BLOCK_ROWS": "fruitimpact.impact.lots", "PopulationSource": "fruitimpact.impact.lots",
}


_MODULES = ("chunks", "driver", "engines", "locking", "plan", "sources", "summaries", "workdir")


def __getattr__(name: str):
    if name == "execute_module":  # the driver module itself, for tests that patch it
        return importlib.import_module("fruitimpact.runs.driver")
    if name in _MODULES:
        return importlib.import_module(f"fruitimpact.runs.{name}")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fruitimpact.runs' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


__all__ = ["BLOCK_ROWS", "CHARACTERISTICS", "CHUNK_ROWS", "DEFAULT_SUMMARY", "ENGINES", "INPUTS", "MAX_AXIS_VALUES",
           "MAX_CHUNK_ROWS", "MAX_ROWS", "MAX_SAMPLE_ROWS", "PERCENTILES", "SAMPLE_ROWS", "Axis", "DaskEngine",
           "GridSource", "InProcessEngine", "Plan", "PopulationSource", "Quantity", "RunError", "RunSummary",
           "TableSource", "Threshold", "characteristic", "characteristics_list", "default_workdir", "evaluate_rows",
           "execute", "histogram_figure", "merge_parts", "parse_axis", "read_column", "run_chunk", "sweep_figure",
           "table_format"]
