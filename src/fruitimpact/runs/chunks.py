"""One chunk of a run: evaluate its rows, summarise them, write its files.

``run_chunk`` is what a task does, in this process or on a Dask worker: it
reads its inputs from the source, calls ``batch.evaluate``, writes the part
file (every row, when the run keeps rows) and the summary file (populations),
and returns the manifest record of the chunk, which the driver appends once
the files are in place.
"""

from __future__ import annotations

import math

import numpy as np

from .workdir import write_part, write_summary


def evaluate_rows(inputs, start: int, errors=None):
    """``batch.evaluate`` of ``inputs`` with a ``row`` column (row numbers from ``start``) in front.

    ``errors``: None, or a message per row that makes the row invalid unread (ragged CSV rows).
    Power-law rows always use the engine's table, so results do not depend on where
    the chunk boundaries fall."""
    from ..batch import evaluate

    options = {"errors": errors} if errors is not None else {}
    result = evaluate(inputs, tabulated=True, **options)
    result.insert(0, "row", np.arange(start, start + len(result), dtype=np.int64))
    return result


def arrow_table(frame):
    """The chunk as an Arrow table whose schema depends only on the columns' kinds
    (int64, float64, bool, string), so that every chunk of a run has the same schema."""
    import pyarrow as pa

    arrays = []
    for name in frame.columns:
        column = frame[name]
        kind = getattr(column.dtype, "kind", "O")
        if kind in "iu":
            arrays.append(pa.array(column.to_numpy(), type=pa.int64()))
        elif kind == "f":
            arrays.append(pa.array(column.to_numpy(), type=pa.float64()))
        elif kind == "b":
            arrays.append(pa.array(column.to_numpy(), type=pa.bool_()))
        else:  # text: categorical, pandas strings or objects
            array = pa.array(column, from_pandas=True)
            if pa.types.is_dictionary(array.type):
                array = array.dictionary_decode()
            arrays.append(array.cast(pa.string()))
    return pa.Table.from_arrays(arrays, names=[str(name) for name in frame.columns])


def status_counts(frame) -> dict[str, int]:
    """Rows per status (whatever statuses ``evaluate`` reports)."""
    counts = frame["status"].astype(str).value_counts(sort=False)
    return {str(status): int(count) for status, count in counts.items() if count}


def _moments(values: np.ndarray) -> tuple:
    if values.size == 0:
        return 0, 0.0, 0.0, math.inf, -math.inf
    mean = float(values.mean())
    return values.size, mean, float(np.sum((values - mean) ** 2)), float(values.min()), float(values.max())


def summarise(plan, frame, start: int) -> dict | None:
    """The summary arrays of a chunk of a population (None without statistics): moments
    (n, mean, M2, min, max) and threshold counts of the ok rows, and the rows kept in
    the percentile sample (every ok row, or those whose seeded key is below the sample
    probability)."""
    if not plan.stats:
        return None
    ok = (frame["status"] == "ok").to_numpy(dtype=bool)
    data = {name: frame[name].to_numpy(dtype=float) for name in set(plan.stats) | {t.name for t in plan.thresholds}}
    moments = []
    for name in plan.stats:
        values = data[name][ok]
        moments.append(_moments(values[np.isfinite(values)]))
    probability = plan.sample_probability
    chosen = ok if probability >= 1.0 else ok & (plan.source.keys(start, start + len(frame)) < probability)
    sample = np.empty((int(chosen.sum()), len(plan.stats)))
    for j, name in enumerate(plan.stats):
        sample[:, j] = data[name][chosen]
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
    start = index * plan.chunk_rows
    stop = start + plan.chunk_rows if plan.rows is None else min(start + plan.chunk_rows, plan.rows)
    inputs, errors = plan.source.inputs(start, stop, payload)
    frame = evaluate_rows(inputs, start, errors)
    summary = summarise(plan, frame, start)
    record = {"chunk": index, "start": start, "rows": len(frame), "statuses": status_counts(frame),
              "part": None, "summary": None}
    table = None
    if plan.write_rows:
        table = arrow_table(frame)
        record["part"] = write_part(workdir, index, table)
    if summary is not None:
        record["summary"] = write_summary(workdir, index, summary)
    return {"record": record, "summary": summary, "table": table if keep_rows else None}
