"""One chunk of a run: evaluate its rows, summarise them, write its files.

``run_chunk`` is what a task does, in this process or on a Dask worker: it
reads its inputs from the source, calls ``impact.evaluation.evaluate``, writes the part
file (every row, when the run keeps rows) and the summary file (populations),
and returns the manifest record of the chunk, which the driver appends once
the files are in place.
"""

from __future__ import annotations


import numpy as np

from fruitimpact.runs.workdir import write_part, write_summary


def evaluate_rows(inputs, start: int, errors=None):
    """``impact.evaluation.evaluation`` of ``inputs`` (an ``Evaluation``: arrays and codes, no DataFrame).

    ``errors``: None, or a message per row that makes the row invalid unread (ragged CSV rows).
    Power-law rows always use the engine's table, so results do not depend on where
    the chunk boundaries fall; ``start`` numbers the rows (``Evaluation.table(start)``)."""
    from fruitimpact.impact.evaluation import evaluation

    return evaluation(inputs, tabulated=True, errors=errors)


def summarise(plan, result, start: int) -> dict | None:
    """The summary arrays of a chunk of a population (None without statistics): moments
    (n, mean, M2, min, max) and threshold counts of the ok rows, and the rows kept in
    the percentile sample (every ok row, or those whose seeded key is below the sample
    probability)."""
    if not plan.stats:
        return None
    from fruitimpact.engine.codes import COLUMN
    from fruitimpact.engine.moments import block_summary

    ok = result.status == 0
    probability = plan.sample_probability
    chosen = ok if probability >= 1.0 else ok & (plan.source.keys(start, start + result.rows) < probability)
    names = list(plan.stats) + [t.name for t in plan.thresholds]
    if all(name in COLUMN for name in names):  # characteristics only: one compiled pass over the block
        moments, counts, sample = block_summary(
            result.block, [COLUMN[name] for name in plan.stats], ok, chosen,
            [(COLUMN[t.name], t.op, t.value) for t in plan.thresholds])
        return {"moments": moments, "thresholds": counts, "sample": sample}
    from fruitimpact.engine.moments import column_moments

    data = {name: np.asarray(result.columns[name], dtype=float) for name in set(names)}
    moments = [column_moments(data[name], ok) for name in plan.stats]
    every = bool(chosen.all())
    sample = np.empty((int(chosen.sum()), len(plan.stats)))
    for j, name in enumerate(plan.stats):
        sample[:, j] = data[name] if every else data[name][chosen]
    return {"moments": np.array(moments, dtype=float).reshape(len(plan.stats), 5),
            "thresholds": np.array([t.count(data[t.name][ok]) for t in plan.thresholds], dtype=np.int64),
            "sample": sample}


def run_chunk(plan, index: int, payload, workdir: str, numba_threads: int | None = None,
              keep_rows: bool = False) -> dict:
    """Evaluate chunk ``index`` of ``plan`` and write its files into ``workdir``.

    Parameters
    ----------
    plan : Plan
    index : int
        The chunk: rows ``index * plan.chunk_rows`` onwards.
    payload
        What the source's ``payloads`` gave for this chunk (a table's rows, or None).
    workdir : str
        The work folder (shared with Dask workers).
    numba_threads : int, optional
        Limit of the compiled kernels' threads (1 on Dask workers, which parallelise over chunks).
    keep_rows : bool
        Return the rows (pyarrow Table) too, for the driver to write into the output.

    Returns a dict: ``record`` (the manifest line: chunk, start, rows, statuses, and the
    part and summary files with size and SHA-256), ``summary`` (the summary arrays or
    None) and ``table`` (the rows, or None).
    """
    if numba_threads:
        import numba

        numba.set_num_threads(min(numba_threads, numba.config.NUMBA_NUM_THREADS))
    return store_chunk(plan, compute_chunk(plan, index, payload), workdir, keep_rows)


def compute_chunk(plan, index: int, payload) -> dict:
    """The computing half of ``run_chunk``: the chunk's ``record`` (without its files yet), ``summary`` and
    ``table`` (its rows, when the run keeps rows); no file is touched."""
    start = index * plan.chunk_rows
    stop = start + plan.chunk_rows if plan.rows is None else min(start + plan.chunk_rows, plan.rows)
    inputs, errors = plan.source.inputs(start, stop, payload)
    result = evaluate_rows(inputs, start, errors)
    record = {"chunk": index, "start": start, "rows": result.rows, "statuses": result.status_counts(),
              "warnings": result.warnings.counts(), "part": None, "summary": None}
    return {"record": record, "summary": summarise(plan, result, start),
            "table": result.table(start) if plan.write_rows else None}


def store_chunk(plan, computed: dict, workdir: str, keep_rows: bool = False) -> dict:
    """The writing half of ``run_chunk``: the part and summary files of a ``compute_chunk`` result, entered
    (name, size, SHA-256) in its record; the rows are dropped unless ``keep_rows``."""
    record, summary, table = computed["record"], computed["summary"], computed["table"]
    if table is not None:
        record["part"] = write_part(workdir, record["chunk"], table)
    if summary is not None:
        record["summary"] = write_summary(workdir, record["chunk"], summary)
    return {"record": record, "summary": summary, "table": table if keep_rows else None}
