"""Large runs: batch files, parameter sweeps and Monte Carlo populations.

A run is a ``Plan``: a *source* of input rows (a table file, a grid, a
population of distributions), cut into chunks of ``chunk_rows`` rows.  Each
chunk is evaluated by ``fruitimpact.batch.evaluate`` and written, atomically,
as a Parquet part file in a sidecar work directory, together with a small
summary file (status counts; for populations exact streamed statistics and a
seeded uniform sample for percentiles) that marks the chunk as complete.
The work directory holds a manifest with the job's fingerprint, so a
different job is refused instead of mixed in.  When every chunk is complete,
the parts are merged by streaming into the output (Parquet row groups or CSV
appends) and the work directory is removed.  An interrupted run, re-run with
the same command, skips the complete chunks: no row is lost or doubled.

Chunks run in this process (engine ``inprocess``) or as tasks on a Dask
cluster (engine ``dask``), with the same output.  Memory stays bounded by a
few chunks, whatever the number of rows.

Population members are drawn from generators derived from
``SeedSequence(seed, spawn_key=(block, input))`` for fixed blocks of
``BLOCK_ROWS`` rows, so a member's inputs depend only on the seed and its row
number: the same for any chunk size, engine, or interruption.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shutil
import sys
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .batch import INPUT_COLUMNS, TEXT_COLUMNS
from .quantities import CHARACTERISTICS, DEFAULT_SUMMARY, INPUTS, Quantity
from .units import parse_quantity

#: Rows per chunk by default: large enough that the per-chunk overhead is small next to evaluation.
CHUNK_ROWS = 500_000
#: Rows per block of a population's random streams (a member's inputs depend only on seed and row).
BLOCK_ROWS = 65_536
#: Target size of the uniform sample kept for percentiles; populations up to this size are exact.
SAMPLE_ROWS = 2_000_000
#: Default percentiles reported for populations [%].
PERCENTILES = (5.0, 25.0, 50.0, 75.0, 95.0)
#: Random stream of the percentile-sample keys (beside the input streams 0 .. len(INPUT_COLUMNS)-1).
_KEY_STREAM = 1000
#: Format version of the work directory (part files, summaries, manifest).
WORK_FORMAT = 1
#: Table formats by file extension.
FORMATS = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet"}


class RunError(Exception):
    """A run that cannot start or continue (work directory of another job, bad file): one line."""


assert tuple(INPUTS) == tuple(INPUT_COLUMNS), "runs.INPUTS must follow batch.INPUT_COLUMNS"


def characteristic(name: str) -> Quantity:
    """The ``Quantity`` of an output column; ``ValueError`` naming the known ones."""
    if name not in CHARACTERISTICS:
        raise ValueError(f"unknown characteristic {name!r} (known: {', '.join(CHARACTERISTICS)})")
    return CHARACTERISTICS[name]


def characteristics_list(text: str) -> tuple[str, ...]:
    """``"peak_force,contact_duration"`` → validated names."""
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise ValueError("give at least one characteristic")
    for name in names:
        characteristic(name)
    return names


# --------------------------------------------------------------------------- thresholds
_OPERATORS = {">=": np.greater_equal, "<=": np.less_equal, ">": np.greater, "<": np.less}


@dataclass(frozen=True)
class Threshold:
    """``characteristic op value`` (op one of > >= < <=; value [SI]); counted exactly over ok rows."""

    name: str
    op: str
    value: float
    text: str

    @classmethod
    def parse(cls, text: str) -> "Threshold":
        match = re.match(r"^\s*([A-Za-z_][A-Za-z_0-9]*)\s*(>=|<=|>|<)\s*(.+?)\s*$", text)
        if match is None:
            raise ValueError(f"a threshold is NAME>VALUE (or >=, <, <=), e.g. peak_force>60N; got {text!r}")
        name, op, value = match.groups()
        return cls(name, op, characteristic(name).parse(value), text.strip())

    def count(self, values: np.ndarray) -> int:
        with np.errstate(invalid="ignore"):
            return int(np.count_nonzero(_OPERATORS[self.op](values, self.value)))

    def identity(self) -> list:
        return [self.name, self.op, self.value]


# --------------------------------------------------------------------------- sources
def table_format(path, option: str = "file") -> str:
    """'csv' or 'parquet' from the extension of ``path``; ``ValueError`` otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{option} {str(path)!r} must end in .csv or .parquet")
    return FORMATS[suffix]


def _column_name(name) -> str:
    return str(name).strip().replace("-", "_")


def _file_digest(path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


@dataclass(frozen=True)
class TableSource:
    """Rows of a CSV or Parquet file, columns named like ``simulate``'s options.

    The file is read chunk by chunk in the driving process; each chunk's rows
    travel to the task that evaluates them."""

    path: str
    format: str
    columns: tuple
    digest: str
    size: int
    rows: int | None = None  # known for Parquet, counted while reading for CSV

    @classmethod
    def open(cls, path) -> "TableSource":
        fmt = table_format(path, "input")
        if not Path(path).is_file():
            raise ValueError(f"input {str(path)!r}: no such file")
        if fmt == "csv":
            import pandas as pd

            try:
                columns = tuple(pd.read_csv(path, nrows=0).columns)
            except (ValueError, UnicodeDecodeError) as exc:
                raise ValueError(f"input {str(path)!r}: cannot read as CSV ({exc})") from None
            rows = None
        else:
            import pyarrow.parquet as pq

            try:
                meta = pq.ParquetFile(path).metadata
            except Exception as exc:  # pyarrow raises its own ArrowInvalid for a bad file
                raise ValueError(f"input {str(path)!r}: cannot read as Parquet ({exc})") from None
            columns, rows = tuple(meta.schema.names), meta.num_rows
        known = set(INPUT_COLUMNS) | set(TEXT_COLUMNS)
        unknown = [c for c in columns if _column_name(c) not in known]
        if unknown:
            raise ValueError(f"input {str(path)!r}: unknown column(s) {', '.join(map(repr, unknown))} "
                             f"(columns: {', '.join(known_order())}; the output's 'row' column "
                             f"joins results back to other data)")
        return cls(str(Path(path).resolve()), fmt, columns, _file_digest(path), Path(path).stat().st_size, rows)

    def identity(self) -> dict:
        return {"table": self.path, "sha256": self.digest, "bytes": self.size}

    def payloads(self, chunk_rows: int):
        """(index, DataFrame) per chunk, exactly ``chunk_rows`` rows each but the last (one empty
        chunk for a file without rows, so that the output still gets its columns)."""
        count = 0
        for index, frame in self._chunks(chunk_rows):
            count += 1
            yield index, frame
        if count == 0:
            import pandas as pd

            yield 0, pd.DataFrame({_column_name(c): pd.Series([], dtype=object) for c in self.columns})

    def _chunks(self, chunk_rows: int):
        if self.format == "csv":
            import pandas as pd

            reader = pd.read_csv(self.path, chunksize=chunk_rows)
            for index, frame in enumerate(reader):
                if len(frame):
                    yield index, frame.rename(columns=_column_name)
            return
        import pyarrow as pa
        import pyarrow.parquet as pq

        pending, have, index = [], 0, 0
        for batch in pq.ParquetFile(self.path).iter_batches(batch_size=chunk_rows):
            pending.append(batch)
            have += batch.num_rows
            while have >= chunk_rows:
                table = pa.Table.from_batches(pending)
                yield index, table.slice(0, chunk_rows).to_pandas().rename(columns=_column_name)
                index += 1
                rest = table.slice(chunk_rows)
                pending, have = rest.to_batches(), rest.num_rows
        if have:
            yield index, pa.Table.from_batches(pending).to_pandas().rename(columns=_column_name)

    def inputs(self, start: int, stop: int, payload):
        return payload  # batch.evaluate reads text columns of any dtype


def known_order() -> list[str]:
    return list(INPUT_COLUMNS) + list(TEXT_COLUMNS)


@dataclass(frozen=True)
class Axis:
    """One swept input: its name and values ([SI] numbers, or text such as model names)."""

    name: str
    values: tuple
    log: bool = False

    @property
    def numeric(self) -> bool:
        return not isinstance(self.values[0], str)


def parse_axis(name: str, text: str) -> Axis:
    """A sweep spec for input ``name``: ``START:STOP:COUNT`` (inclusive, linear),
    ``log:START:STOP:COUNT`` (geometric), ``V1,V2,...`` or one value; units allowed."""
    if name in TEXT_COLUMNS:
        values = tuple(v.strip() for v in text.split(",") if v.strip())
        if not values:
            raise ValueError(f"give one or more values; got {text!r}")
        return Axis(name, values)
    dimension = INPUT_COLUMNS[name][0]
    body, log = (text[4:], True) if text.lower().startswith("log:") else (text, False)
    if ":" in body:
        parts = body.split(":")
        if len(parts) != 3:
            raise ValueError(f"a range is START:STOP:COUNT, e.g. 0.3:1.5:25 or log:1:100:21; got {text!r}")
        start, stop = (parse_quantity(p, dimension) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            count = 0
        if count < 1 or str(count) != parts[2].strip():
            raise ValueError(f"the COUNT of START:STOP:COUNT must be an integer >= 1; got {parts[2]!r}")
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise ValueError(f"START and STOP must be finite; got {text!r}")
        if log:
            if not (start > 0 and stop > 0):
                raise ValueError(f"a log range needs START > 0 and STOP > 0; got {text!r}")
            values = np.geomspace(start, stop, count)
        else:
            values = np.linspace(start, stop, count)
        return Axis(name, tuple(float(v) for v in values), log)
    if log:
        raise ValueError(f"log: needs a range log:START:STOP:COUNT; got {text!r}")
    return Axis(name, tuple(parse_quantity(v, dimension) for v in body.split(",")))


@dataclass(frozen=True)
class GridSource:
    """The Cartesian product of ``axes`` (first axis slowest, as nested loops), row = flat index."""

    axes: tuple  # of Axis (each with at least one value)

    @property
    def shape(self) -> tuple:
        return tuple(len(a.values) for a in self.axes)

    @property
    def rows(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64))

    def identity(self) -> dict:
        return {"grid": [[a.name, list(a.values)] for a in self.axes]}

    def payloads(self, chunk_rows: int):
        for index in range(-(-self.rows // chunk_rows)):
            yield index, None

    def inputs(self, start: int, stop: int, payload) -> dict:
        where = np.unravel_index(np.arange(start, stop), self.shape)
        return {axis.name: np.asarray(axis.values, dtype=object if not axis.numeric else float)[i]
                for axis, i in zip(self.axes, where)}


def _generator(seed: int, block: int, stream: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(block, stream))))


@dataclass(frozen=True)
class PopulationSource:
    """``rows`` members; numeric inputs drawn from distributions, text inputs fixed.

    Input ``name`` of the rows in block ``b`` (rows ``b*BLOCK_ROWS`` onwards) is
    drawn, a whole block at a time, from the generator of
    ``SeedSequence(seed, spawn_key=(b, i))``, ``i`` the input's place in
    ``batch.INPUT_COLUMNS``; so each input has its own stream and a member's
    inputs depend only on ``seed`` and its row number."""

    distributions: tuple  # of (name, distribution)
    text: tuple  # of (name, value)
    rows: int
    seed: int

    def identity(self) -> dict:
        return {"population": {name: dist.identity() for name, dist in self.distributions},
                "text": dict(self.text), "rows": self.rows, "seed": self.seed, "block": BLOCK_ROWS}

    def payloads(self, chunk_rows: int):
        for index in range(-(-self.rows // chunk_rows)):
            yield index, None

    def _stream(self, start: int, stop: int, stream: int, draw) -> np.ndarray:
        if stop <= start:
            return np.empty(0)
        blocks = range(start // BLOCK_ROWS, (stop - 1) // BLOCK_ROWS + 1)
        values = np.concatenate([draw(_generator(self.seed, b, stream), BLOCK_ROWS) for b in blocks])
        offset = blocks[0] * BLOCK_ROWS
        return values[start - offset:stop - offset]

    def inputs(self, start: int, stop: int, payload) -> dict:
        from .distributions import Constant

        columns = {}
        order = list(INPUT_COLUMNS)
        for name, dist in self.distributions:
            if isinstance(dist, Constant):
                columns[name] = np.full(stop - start, dist.value)
            else:
                columns[name] = self._stream(start, stop, order.index(name), dist.draw)
        for name, value in self.text:
            columns[name] = np.full(stop - start, value, dtype=object)
        # with every input at its default there would be no column to carry the row count
        columns.setdefault("model", np.full(stop - start, TEXT_COLUMNS["model"], dtype=object))
        return columns

    def keys(self, start: int, stop: int) -> np.ndarray:
        """Uniform [0, 1) keys of rows start..stop-1, for the percentile sample."""
        return self._stream(start, stop, _KEY_STREAM, lambda rng, n: rng.random(n))


# --------------------------------------------------------------------------- plan
@dataclass(frozen=True)
class Plan:
    """What a run computes: a source cut into chunks, and what is kept of each chunk.

    ``write_rows``: keep every row (part files, merged into the output).
    ``stats``: columns with exact streamed statistics and a uniform sample of
    about ``sample_rows`` rows for percentiles (populations).
    ``thresholds``: exact counts of ok rows beyond each threshold."""

    kind: str
    source: object
    chunk_rows: int = CHUNK_ROWS
    write_rows: bool = True
    stats: tuple = ()
    thresholds: tuple = ()
    sample_rows: int = SAMPLE_ROWS

    def __post_init__(self):
        if self.chunk_rows < 1:
            raise ValueError("chunk_rows must be >= 1")

    @property
    def rows(self) -> int | None:
        return getattr(self.source, "rows", None)

    @property
    def chunks(self) -> int | None:
        return None if self.rows is None else -(-self.rows // self.chunk_rows)

    @property
    def sample_probability(self) -> float:
        return 1.0 if self.rows is None or self.rows <= self.sample_rows else self.sample_rows / self.rows

    def identity(self) -> dict:
        from . import __version__

        return {"kind": self.kind, "format": WORK_FORMAT, "fruitimpact": __version__,
                "source": self.source.identity(), "chunk_rows": self.chunk_rows, "write_rows": self.write_rows,
                "stats": list(self.stats), "thresholds": [t.identity() for t in self.thresholds],
                "sample_rows": self.sample_rows if self.stats else None}

    def fingerprint(self) -> str:
        return hashlib.sha256(json.dumps(self.identity(), sort_keys=True).encode()).hexdigest()


def _part(workdir, index: int) -> Path:
    return Path(workdir) / f"part-{index:07d}.parquet"


def _summary_path(workdir, index: int) -> Path:
    return Path(workdir) / f"part-{index:07d}.summary.npz"


def _atomic(path: Path, write) -> None:
    """``write(tmp)`` then rename to ``path`` (never a half-written ``path``)."""
    tmp = path.with_name(f"{path.name}.tmp-{os.getpid()}-{uuid.uuid4().hex[:8]}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _frame_table(frame):
    """The chunk as an Arrow table with a schema that depends only on the columns' kinds."""
    import pyarrow as pa

    arrays, fields = [], []
    for name in frame.columns:
        column = frame[name]
        kind = column.dtype.kind
        if kind in "fiub":
            array = pa.array(column.to_numpy(), type=pa.int64() if kind in "iu" else
                             pa.bool_() if kind == "b" else pa.float64())
        else:
            array = pa.array(column.astype(object).to_numpy(), type=pa.string())
        arrays.append(array)
        fields.append(pa.field(str(name), array.type))
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields))


def evaluate_rows(inputs, start: int):
    """``batch.evaluate`` of ``inputs`` with a ``row`` column (row numbers from ``start``) in front.

    Power-law rows always use the engine's table, so results do not depend on
    where the chunk boundaries fall."""
    from .batch import evaluate

    result = evaluate(inputs, tabulated=True)
    result.insert(0, "row", np.arange(start, start + len(result), dtype=np.int64))
    return result


def _moments(values: np.ndarray) -> tuple:
    if values.size == 0:
        return 0, 0.0, 0.0, math.inf, -math.inf
    mean = float(values.mean())
    return values.size, mean, float(np.sum((values - mean) ** 2)), float(values.min()), float(values.max())


def run_chunk(plan: Plan, index: int, payload, workdir: str, numba_threads: int | None = None) -> dict:
    """Evaluate chunk ``index`` and write its part file and summary (the completion marker).

    Returns the chunk's index and status counts.  ``numba_threads`` limits the compiled
    kernels' threads (1 on Dask workers, which parallelise over chunks)."""
    if numba_threads:
        import numba

        numba.set_num_threads(min(numba_threads, numba.config.NUMBA_NUM_THREADS))
    start = index * plan.chunk_rows
    inputs = plan.source.inputs(start, start + plan.chunk_rows if plan.rows is None
                                else min(start + plan.chunk_rows, plan.rows), payload)
    result = evaluate_rows(inputs, start)
    if plan.write_rows:
        import pyarrow.parquet as pq

        table = _frame_table(result)
        _atomic(_part(workdir, index), lambda tmp: pq.write_table(table, tmp, compression="snappy"))
    status = result["status"].to_numpy(dtype=object)
    ok = status == "ok"
    summary = {"rows": np.int64(len(result)), "ok": np.int64(ok.sum()),
               "invalid": np.int64(np.count_nonzero(status == "invalid")),
               "failed": np.int64(np.count_nonzero(status == "failed"))}
    if plan.stats:
        data = {name: result[name].to_numpy(dtype=float)[ok] for name in plan.stats}
        summary["moments"] = np.array([_moments(v[np.isfinite(v)]) for v in data.values()], dtype=float)
        summary["thresholds"] = np.array([t.count(result[t.name].to_numpy(dtype=float)[ok])
                                          for t in plan.thresholds], dtype=np.int64)
        probability = plan.sample_probability
        chosen = ok if probability >= 1.0 else ok & (plan.source.keys(start, start + len(result)) < probability)
        summary["sample"] = np.column_stack([result[name].to_numpy(dtype=float)[chosen] for name in plan.stats])
    _atomic(_summary_path(workdir, index), lambda tmp: _save_npz(tmp, summary))
    return {"index": index, **{k: int(summary[k]) for k in ("rows", "ok", "invalid", "failed")}}


def _save_npz(path: Path, arrays: dict) -> None:
    with open(path, "wb") as handle:
        np.savez(handle, **arrays)


# --------------------------------------------------------------------------- engines
def _progress(plan: Plan):
    """A tqdm bar on stderr when stderr is a terminal, else a silent stand-in."""
    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=plan.rows, unit="row", unit_scale=True, file=sys.stderr, desc=plan.kind, leave=False)


@dataclass(frozen=True)
class InProcessEngine:
    """Chunks one after the other in this process (the compiled kernels use every core)."""

    name = "inprocess"

    def run(self, plan: Plan, payloads, workdir: str, done) -> None:
        for index, payload in payloads:
            done(index, run_chunk(plan, index, payload, workdir))


@dataclass(frozen=True)
class DaskEngine:
    """Chunks as tasks on a Dask cluster: ``scheduler`` (address) or a local cluster of ``workers``
    single-threaded worker processes.  Each task evaluates one chunk with single-threaded kernels
    and writes its part file itself (the work directory must be shared with the workers)."""

    scheduler: str | None = None
    workers: int = 2
    name = "dask"

    def run(self, plan: Plan, payloads, workdir: str, done) -> None:
        import logging

        from distributed import Client, LocalCluster, as_completed

        cluster = None
        if self.scheduler is None:
            cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=":0", silence_logs=logging.ERROR)
            client = Client(cluster)
        else:
            try:
                client = Client(self.scheduler, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise RunError(f"argument --scheduler: cannot connect to {self.scheduler!r} ({exc})") from None
        try:
            slots = max(1, sum(client.nthreads().values()))
            shared = client.scatter(plan, broadcast=True)
            running = as_completed(with_results=True)
            for index, payload in payloads:
                running.add(client.submit(run_chunk, shared, index, payload, workdir, 1, pure=False))
                while running.count() >= 2 * slots:  # bounded: at most two chunks per worker thread in flight
                    _, counts = next(running)
                    done(counts["index"], counts)
            for _, counts in running:
                done(counts["index"], counts)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


#: Engines by name.
ENGINES = {"inprocess": InProcessEngine, "dask": DaskEngine}


# --------------------------------------------------------------------------- summaries
@dataclass
class RunSummary:
    """What a run produced: status counts; for populations statistics and threshold counts."""

    kind: str
    rows: int
    ok: int
    invalid: int
    failed: int
    output: str | None = None
    resumed_chunks: int = 0
    statistics: dict = field(default_factory=dict)
    thresholds: list = field(default_factory=list)
    percentiles: dict = field(default_factory=dict)  # method, sample size, exact or not
    sample: np.ndarray | None = None  # the percentile sample, one column per statistic
    columns: dict = field(default_factory=dict)  # columns read back for figures (keep_columns)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "rows": self.rows, "ok": self.ok, "invalid": self.invalid, "failed": self.failed,
                "output": self.output, "resumed_chunks": self.resumed_chunks, "percentile_method": self.percentiles,
                "statistics": self.statistics, "thresholds": self.thresholds}


def _combine(summaries: list, plan: Plan, percentiles) -> dict:
    """Merge chunk summaries (in chunk order) into statistics, threshold counts and percentiles."""
    counts = {k: int(sum(int(s[k]) for s in summaries)) for k in ("rows", "ok", "invalid", "failed")}
    if not plan.stats:
        return counts
    stats = {}
    moments = np.stack([s["moments"] for s in summaries])  # chunks × stats × (n, mean, m2, min, max)
    sample = np.concatenate([s["sample"] for s in summaries]) if summaries else np.empty((0, len(plan.stats)))
    exact = plan.sample_probability >= 1.0
    for j, name in enumerate(plan.stats):
        n, mean, m2 = 0, 0.0, 0.0
        for cn, cmean, cm2, _, _ in moments[:, j]:  # Chan et al.: exact merge of counts, means, M2
            if cn == 0:
                continue
            total = n + cn
            delta = cmean - mean
            mean += delta * cn / total
            m2 += cm2 + delta * delta * n * cn / total
            n = total
        column = sample[:, j]
        column = column[np.isfinite(column)]
        quantity = CHARACTERISTICS[name]
        stats[name] = {
            "unit": quantity.si_unit, "count": int(n),
            "mean": mean if n else math.nan, "sd": math.sqrt(m2 / (n - 1)) if n > 1 else math.nan,
            "min": float(moments[:, j, 3].min()) if n else math.nan,
            "max": float(moments[:, j, 4].max()) if n else math.nan,
            "percentiles": {f"{p:g}": (float(np.percentile(column, p)) if column.size else math.nan)
                            for p in percentiles},
        }
    threshold_counts = np.sum([s["thresholds"] for s in summaries], axis=0) if plan.thresholds else []
    counts["statistics"] = stats
    counts["thresholds"] = [{"threshold": t.text, "characteristic": t.name, "op": t.op, "value": t.value,
                             "unit": CHARACTERISTICS[t.name].si_unit, "count": int(c), "of": counts["ok"],
                             "share": int(c) / counts["ok"] if counts["ok"] else math.nan}
                            for t, c in zip(plan.thresholds, threshold_counts)]
    counts["percentiles"] = {
        "exact": exact, "sample_rows": int(sample.shape[0]), "method": "numpy.percentile, linear interpolation",
        "note": ("exact: every ok row" if exact else
                 f"estimate from a seeded uniform sample of {sample.shape[0]} ok rows "
                 f"(each row kept with probability {plan.sample_probability:.3g})")}
    counts["sample"] = sample
    return counts


# --------------------------------------------------------------------------- driver
def default_workdir(output, plan: Plan) -> Path:
    """``OUTPUT.parts`` beside the output; without one, a job-named directory here."""
    if output is not None:
        return Path(str(output) + ".parts")
    return Path(f".fruitimpact-{plan.kind}-{plan.fingerprint()[:12]}.parts")


def _prepare_workdir(workdir: Path, plan: Plan, fresh: bool) -> None:
    manifest = workdir / "manifest.json"
    fingerprint = plan.fingerprint()
    if workdir.exists() and fresh:
        shutil.rmtree(workdir)
    if workdir.exists():
        try:
            found = json.loads(manifest.read_text())["fingerprint"]
        except (OSError, ValueError, KeyError):
            found = None
        if found != fingerprint:
            raise RunError(f"{workdir} holds the parts of a different job (or is not a fruitimpact work "
                           f"directory); finish that job, delete {workdir}, or pass --fresh")
        for stale in workdir.glob("*.tmp-*"):  # a chunk interrupted while being written
            stale.unlink()
        return
    workdir.mkdir(parents=True)
    text = json.dumps({"fingerprint": fingerprint, "job": plan.identity()}, indent=2, sort_keys=True)
    _atomic(manifest, lambda tmp: tmp.write_text(text))


def _complete(workdir: Path, plan: Plan, index: int) -> bool:
    return _summary_path(workdir, index).exists() and (not plan.write_rows or _part(workdir, index).exists())


def merge_parts(workdir: Path, chunks: int, output) -> None:
    """Stream the part files, in order, into ``output`` (Parquet row groups or CSV), atomically."""
    import pyarrow.parquet as pq

    output = Path(output)
    fmt = table_format(output, "output")

    def write(tmp):
        writer = None
        try:
            for index in range(chunks):
                table = pq.read_table(_part(workdir, index))
                if writer is None:
                    if fmt == "parquet":
                        writer = pq.ParquetWriter(tmp, table.schema, compression="snappy")
                    else:
                        import pyarrow.csv as pacsv

                        writer = pacsv.CSVWriter(tmp, table.schema,
                                                 write_options=pacsv.WriteOptions(quoting_style="needed"))
                writer.write_table(table)
        finally:
            if writer is not None:
                writer.close()

    _atomic(output, write)


def execute(plan: Plan, output=None, *, engine=None, workdir=None, fresh: bool = False,
            percentiles=PERCENTILES, keep_columns=()) -> RunSummary:
    """Run ``plan``: evaluate the missing chunks, merge, summarise, clean up.

    Parameters
    ----------
    plan : Plan
    output : path or None
        CSV or Parquet file for every row (by extension); None keeps no rows.
    engine : InProcessEngine or DaskEngine
        Default ``InProcessEngine()``.
    workdir : path or None
        Work directory of the parts; default ``default_workdir(output, plan)``.
    fresh : bool
        Discard an existing work directory (even another job's) instead of resuming.
    percentiles : sequence of float
        Percentiles [%] of the population statistics.
    keep_columns : sequence of str
        Output columns returned whole in ``RunSummary.columns`` (for figures; needs ``write_rows``).

    Returns a ``RunSummary``; raises ``RunError`` for a work directory of another
    job.  The work directory is removed after a complete run and kept (for the
    resume) when interrupted.
    """
    engine = engine or InProcessEngine()
    workdir = (Path(workdir) if workdir is not None else default_workdir(output, plan)).resolve()
    if output is not None:
        table_format(output, "output")
    _prepare_workdir(workdir, plan, fresh)
    seen, resumed = [], []
    bar = _progress(plan)

    def pending():
        for index, payload in plan.source.payloads(plan.chunk_rows):
            seen.append(index)
            if _complete(workdir, plan, index):
                resumed.append(index)
                if bar is not None:
                    bar.update(len(payload) if payload is not None else
                               min(plan.chunk_rows, plan.rows - index * plan.chunk_rows))
                continue
            yield index, payload

    def done(index, counts):
        if bar is not None:
            bar.update(counts["rows"])

    try:
        engine.run(plan, pending(), str(workdir), done)
    finally:
        if bar is not None:
            bar.close()
    chunks = len(seen)
    missing = [i for i in range(chunks) if not _complete(workdir, plan, i)]
    if missing:
        raise RunError(f"chunks {missing[:5]} of {workdir} are missing after the run; re-run to complete them")
    summaries = []
    for index in range(chunks):
        with np.load(_summary_path(workdir, index)) as data:
            summaries.append({k: data[k] for k in data.files})
    combined = _combine(summaries, plan, percentiles)
    if output is not None and plan.write_rows:
        merge_parts(workdir, chunks, output)
    columns = {name: read_column(workdir, chunks, name) for name in keep_columns}
    shutil.rmtree(workdir, ignore_errors=True)
    return RunSummary(plan.kind, combined["rows"], combined["ok"], combined["invalid"], combined["failed"],
                      None if output is None else str(output), len(resumed),
                      combined.get("statistics", {}), combined.get("thresholds", []),
                      combined.get("percentiles", {}), combined.get("sample"), columns)


def read_column(workdir: Path, chunks: int, name: str) -> np.ndarray:
    """One column of every part, in row order (for plots of sweeps)."""
    import pyarrow.parquet as pq

    return np.concatenate([pq.read_table(_part(workdir, i), columns=[name]).column(0).to_numpy(zero_copy_only=False)
                           for i in range(chunks)]) if chunks else np.empty(0)


# --------------------------------------------------------------------------- figures
def sweep_figure(grid: GridSource, values: np.ndarray, name: str):
    """Heat map (two swept inputs, the second with more than 8 values) or line plot of
    characteristic ``name`` over the swept axes of ``grid``; invalid points are left blank."""
    from .plotting import _pyplot

    plt = _pyplot()
    quantity = CHARACTERISTICS[name]
    swept = [(i, a) for i, a in enumerate(grid.axes) if len(a.values) > 1]
    cube = np.asarray(values, dtype=float).reshape(grid.shape) * quantity.scale
    cube = cube.reshape([len(a.values) for _, a in swept]) if swept else cube.reshape(1)
    if len(swept) == 2 and not swept[0][1].numeric and swept[1][1].numeric:
        swept, cube = swept[::-1], cube.T
    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    x_axis = swept[0][1]
    x_q = INPUTS.get(x_axis.name)
    x = np.asarray(x_axis.values, dtype=float) * x_q.scale if x_axis.numeric else list(x_axis.values)
    if len(swept) == 2 and swept[1][1].numeric and len(swept[1][1].values) > 8 and x_axis.numeric:
        y_axis = swept[1][1]
        y_q = INPUTS[y_axis.name]
        mesh = ax.pcolormesh(x, np.asarray(y_axis.values) * y_q.scale, cube.T, shading="nearest")
        fig.colorbar(mesh, ax=ax, label=quantity.axis_label)
        ax.set_ylabel(y_q.axis_label)
        if y_axis.log:
            ax.set_yscale("log")
    else:
        if len(swept) == 2:
            other = swept[1][1]
            o_q = INPUTS.get(other.name)
            for j, value in enumerate(other.values):
                label = value if not other.numeric else f"{o_q.label} = {value * o_q.scale:.4g} {o_q.unit}".rstrip()
                ax.plot(x, cube[:, j], marker="." if len(x) < 40 else None, label=label)
            ax.legend(fontsize=8)
        else:
            ax.plot(x, cube, marker="." if len(x) < 40 else None)
        ax.set_ylabel(quantity.axis_label)
        ax.grid(True, alpha=0.3)
    ax.set_xlabel(x_q.axis_label if x_q is not None else x_axis.name)
    if x_axis.numeric and x_axis.log:
        ax.set_xscale("log")
    ax.set_title(f"fruitimpact sweep: {quantity.label}")
    return fig


def histogram_figure(sample: np.ndarray, names: tuple, exact: bool):
    """Histograms of the population's characteristics ``names`` (columns of ``sample``)."""
    from .plotting import _pyplot

    plt = _pyplot()
    cols = min(3, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), constrained_layout=True, squeeze=False)
    for ax, (j, name) in zip(axes.flat, enumerate(names)):
        quantity = CHARACTERISTICS[name]
        column = sample[:, j]
        column = column[np.isfinite(column)] * quantity.scale
        low, high = (float(column.min()), float(column.max())) if column.size else (0.0, 1.0)
        pad = 1e-6 * max(abs(low), abs(high), 1e-300)
        if high - low <= pad:  # (nearly) constant: one bar
            ax.hist(column, bins=1, range=(low - pad, high + pad), color="tab:blue", alpha=0.8)
        else:
            ax.hist(column, bins=60, color="tab:blue", alpha=0.8)
        ax.set(xlabel=quantity.axis_label, ylabel="members")
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[len(names):]:
        ax.set_visible(False)
    fig.suptitle("fruitimpact population" + ("" if exact else f" (uniform sample of {sample.shape[0]} members)"))
    return fig


__all__ = ["BLOCK_ROWS", "CHARACTERISTICS", "CHUNK_ROWS", "DEFAULT_SUMMARY", "ENGINES", "INPUTS", "PERCENTILES",
           "SAMPLE_ROWS", "Axis", "DaskEngine", "GridSource", "InProcessEngine", "Plan", "PopulationSource",
           "Quantity", "RunError", "RunSummary", "TableSource", "Threshold", "characteristic",
           "characteristics_list", "evaluate_rows", "execute", "histogram_figure", "merge_parts",
           "parse_axis", "read_column", "run_chunk", "sweep_figure", "table_format"]
