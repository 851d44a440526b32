"""Running a plan: lock, evaluate the missing chunks, write the output, summarise, clean up.

The output is written once, in row order, into a temporary file beside it
(``outputs.atomic_write``) while the chunks complete: rows computed in this
process go straight from memory into it, rows of earlier runs (the resume) and
of Dask workers are read back from their verified part files.  When every
chunk is in, and the input file is checked unchanged, the output is renamed
into place and the work folder is cleaned up.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from fruitimpact.impact.outputs import TABLE_FORMATS, atomic_write, check_output, remove_stale_temporaries
from fruitimpact.runs.abandon import slices
from fruitimpact.runs.engines import InProcessEngine
from fruitimpact.runs.locking import RunLock
from fruitimpact.runs.plan import PERCENTILES, RunError
from fruitimpact.runs.sources import table_format
from fruitimpact.runs.summaries import RunSummary, add_statuses, combine
from fruitimpact.runs.workdir import WorkDir, read_part, read_summary

#: Runs expected to take longer than this [s] announce an estimate on stderr.
ESTIMATE_AFTER = 60.0


def default_workdir(output, plan) -> Path:
    """``OUTPUT.parts`` beside the output; without one, a job-named folder in the system's temporary folder (a
    run that writes no file of the user's needs no writable current folder; the same job finds it to resume)."""
    if output is not None:
        return Path(str(output) + ".parts")
    import tempfile

    return Path(tempfile.gettempdir()) / f"fruitimpact-{plan.kind}-{plan.fingerprint()[:12]}.parts"


def output_lock_path(output) -> Path:
    """The lock file of ``output``: beside it, named as fruitimpact's own."""
    output = Path(output)
    return output.with_name(f".{output.name}.fruitimpact-lock")


class TableWriter:
    """Tables, in order, into one Parquet (a row group per chunk) or CSV file, opened on the first."""

    def __init__(self, path, fmt: str):
        self.path = path
        self.format = fmt
        self.writer = None

    def write(self, table) -> None:
        if self.writer is None:
            if self.format == "parquet":
                import pyarrow as pa
                import pyarrow.parquet as pq

                # dictionary encoding only where it pays (the text columns): tried on the float columns it
                # makes writing twice as slow and the file no smaller
                text = [f.name for f in table.schema if not pa.types.is_floating(f.type)
                        and not pa.types.is_integer(f.type)]
                self.writer = pq.ParquetWriter(self.path, table.schema, compression="snappy", use_dictionary=text)
            else:
                import pyarrow.csv as pacsv

                self.writer = pacsv.CSVWriter(self.path, table.schema,
                                              write_options=pacsv.WriteOptions(quoting_style="needed"))
        # an interrupted run's writer stops between slices (``runs.abandon``)
        for part in slices(table, text=self.format == "csv"):
            self.writer.write_table(part)

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()


def merge_parts(workdir, records: dict, writer: TableWriter, first: int, stop: int) -> int:
    """Stream the verified part files of chunks ``first`` .. ``stop - 1`` into ``writer``; returns ``stop``."""
    for index in range(first, stop):
        writer.write(read_part(workdir, records[index]["part"]))
    return stop


def read_column(workdir, records: dict, name: str):
    """One column of every part, in row order, verified (for figures of sweeps)."""
    import numpy as np

    return np.concatenate([read_part(workdir, records[i]["part"]).column(name).to_numpy(zero_copy_only=False)
                           for i in sorted(records)]) if records else np.empty(0)


def _progress(plan):
    """A tqdm bar on stderr when stderr is a terminal, else None."""
    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=plan.rows, unit="row", unit_scale=True, file=sys.stderr, desc=plan.kind, leave=False)


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class _Driver:
    """The driver's side of a run: records completed chunks, writes their rows in order,
    shows progress and, for a long run, an estimate."""

    def __init__(self, plan, work: WorkDir, records: dict, summaries: dict, writer: TableWriter | None):
        self.plan, self.work, self.records, self.summaries, self.writer = plan, work, records, summaries, writer
        self.written = 0  # chunks written into the output
        self.seen = 0  # chunks the source has
        self.bar = _progress(plan)
        self.started = time.perf_counter()
        self.computed_rows = 0
        self.estimated = False

    def pending(self):
        """The (index, payload) of the chunks still to compute."""
        for index, payload in self.plan.source.payloads(self.plan.chunk_rows):
            self.seen = index + 1
            if index in self.records:
                if self.bar is not None:
                    self.bar.update(self.records[index]["rows"])
                continue
            yield index, payload

    def done(self, result: dict) -> None:
        record = result["record"]
        index = record["chunk"]
        self.work.append(record)
        self.records[index] = record
        if result["summary"] is not None:
            self.summaries[index] = result["summary"]
        if self.writer is not None and result["table"] is not None and index >= self.written:
            self.written = merge_parts(self.work.path, self.records, self.writer, self.written, index)
            self.writer.write(result["table"])
            self.written = index + 1
        if self.bar is not None:
            self.bar.update(record["rows"])
        self.computed_rows += record["rows"]
        if not self.estimated:
            self._estimate(record["rows"])

    def _estimate(self, rows: int) -> None:
        """After the first chunk: extrapolate its time to the rows left; say it if over a minute."""
        self.estimated = True
        elapsed = time.perf_counter() - self.started
        total = self.plan.rows if self.plan.rows is not None else getattr(self.plan.source, "estimated_rows", 0)
        left = total - sum(r["rows"] for r in self.records.values())
        remaining = elapsed / max(rows, 1) * max(left, 0)
        if remaining > ESTIMATE_AFTER:
            print(f"fruitimpact {self.plan.kind}: about {_duration(remaining)} more for about {max(left, 0):,} rows "
                  f"(extrapolated from the first chunk: {rows:,} rows in {elapsed:.1f} s)", file=sys.stderr,
                  flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def execute(plan, output=None, *, engine=None, workdir=None, fresh: bool = False,
            percentiles=PERCENTILES, keep_columns=()) -> RunSummary:
    """Run ``plan``: evaluate the missing chunks, write the output, summarise, clean up.

    Parameters
    ----------
    plan : Plan
    output : path or None
        CSV or Parquet file for every row (by extension); None keeps no rows.
    engine : InProcessEngine or DaskEngine
        Default ``InProcessEngine()``.
    workdir : path or None
        Work folder of the parts; default ``default_workdir(output, plan)``.  It must be
        new, empty, or a fruitimpact work folder (with its marker file).
    fresh : bool
        Discard the files of another job in the work folder (only a fruitimpact work
        folder) instead of refusing.
    percentiles : sequence of float
        Percentiles [%] of the population statistics.
    keep_columns : sequence of str
        Output columns returned whole in ``RunSummary.columns`` (for figures; needs ``write_rows``).

    Returns a ``RunSummary``.  Raises ``ValueError`` for an output that cannot be written,
    ``RunError`` (one line) for a work folder that is not ours or of another job, a lock
    held by another run, an input file changed during the run, or a failed write (full
    disk): the completed chunks are then kept for the resume.
    """
    engine = engine or InProcessEngine()
    if output is not None:
        output = check_output(output, "-o/--output", TABLE_FORMATS)
    workdir = Path(workdir) if workdir is not None else default_workdir(output, plan)
    output_lock = None
    if output is not None and plan.write_rows:
        output_lock = RunLock(output_lock_path(output), f"output {str(output)!r}").acquire()
    try:
        if output_lock is not None:
            remove_stale_temporaries(output)
        work = WorkDir.open(workdir, plan.fingerprint(), plan.identity(), fresh=fresh, spare=output)
        try:
            summary = _run(plan, work, output, engine, percentiles, keep_columns)
        except BaseException as exc:
            # an interrupt is known to have stopped every writer only in this process (a cluster's running tasks
            # go on writing into the folder): only then may the folder go
            settled = isinstance(exc, Exception) or isinstance(engine, InProcessEngine)
            if settled and not _kept(work):
                # failed or interrupted before any chunk was kept (a Dask scheduler that does not answer, a Ctrl-C
                # in the first chunk): nothing to resume, so the folder's own files go, and the folder if this run
                # made it (kept, it refused the next, different job to that output as "another job's parts")
                work.remove()
            else:
                work.release()
            raise
        work.remove()
        return summary
    finally:
        if output_lock is not None:
            output_lock.release(remove=True)


def _kept(work: WorkDir) -> bool:
    """Whether the work folder holds a completed chunk (or a manifest that cannot be read: kept, to be looked at)."""
    try:
        return bool(work.records())
    except Exception:
        return True


def _run(plan, work: WorkDir, output, engine, percentiles, keep_columns) -> RunSummary:
    """The body of ``execute`` once the output and the work folder are locked."""
    records = {i: r for i, r in work.records().items() if work.verified(r)}  # others are computed again
    summaries = {}
    for index, record in list(records.items()):
        if record.get("summary"):
            summaries[index] = read_summary(work.path, record["summary"])
            if summaries[index] is None:  # changed since verified: compute again
                del records[index], summaries[index]
    resumed = len(records)
    write_rows = output is not None and plan.write_rows

    def body(tmp):
        writer = TableWriter(tmp, table_format(output, "output")) if tmp is not None else None
        driver = _Driver(plan, work, records, summaries, writer)
        try:
            engine.run(plan, driver.pending(), str(work.path), driver.done)
            missing = [i for i in range(driver.seen) if i not in records]
            if missing:
                raise RunError(f"chunks {missing[:5]} of {work.path} are missing after the run; "
                               f"run the same command again to complete them")
            if plan.source.changed():
                raise RunError(f"input {plan.source.path!r} changed during the run (its SHA-256 differs from the "
                               f"start); its rows would mix two versions: run again with --fresh")
            if writer is not None:
                merge_parts(work.path, records, writer, driver.written, driver.seen)
                writer.close()
        except OSError as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            if not records:
                raise RunError(f"writing failed ({reason}) before any chunk was completed: fix that and run the "
                               f"same command again") from None
            raise RunError(f"writing failed ({reason}); the {len(records)} completed chunks are kept in "
                           f"{work.path}: fix that and run the same command again to resume") from None
        finally:
            driver.close()

    if write_rows:
        try:
            atomic_write(output, body, "-o/--output")
        except ValueError as exc:
            raise RunError(str(exc)) from None
    else:
        body(None)
    statuses = add_statuses(records[i] for i in sorted(records))
    rows = sum(statuses.values())
    ok = statuses.get("ok", 0)
    combined = combine([summaries[i] for i in sorted(summaries)], plan, percentiles, ok) if plan.stats else {}
    columns = {name: read_column(work.path, records, name) for name in keep_columns}
    return RunSummary(plan.kind, rows, ok, statuses.get("invalid", 0), statuses.get("failed", 0),
                      None if not write_rows else str(output), resumed, combined.get("statistics", {}),
                      combined.get("thresholds", []), combined.get("percentiles", {}), combined.get("sample"),
                      columns, statuses, add_statuses((records[i] for i in sorted(records)), "warnings"))
