"""Where chunks run: in this process, or as tasks on a Dask cluster.

An engine's ``run(plan, payloads, workdir, done)`` evaluates every (index,
payload) of ``payloads`` with ``chunks.run_chunk`` and calls ``done(result)``
in the driving process as each chunk completes.  The output and the summary
are the same whichever engine ran the chunks.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from fruitimpact.runs.plan import RunError

#: A Dask scheduler address: ``tcp://host:port``, ``host:port`` (no spaces; Dask needs the port).
_ADDRESS = re.compile(r"^(?:[a-z][a-z0-9+.-]*://)?[^\s/:]+:\d{1,5}(?:/\S*)?$")


def check_scheduler(address: str) -> str:
    """``address`` if it looks like a Dask scheduler address, else ``ValueError``."""
    if not _ADDRESS.match(address or ""):
        raise ValueError(f"a scheduler address is like tcp://10.0.0.5:8786 or 10.0.0.5:8786; got {address!r}")
    return address


#: What the writer thread uses, imported by the driving thread before the writer starts (``preload_writer_modules``).
WRITER_MODULES = ("pandas", "pyarrow", "pyarrow.csv", "pyarrow.ipc", "pyarrow.parquet")


def preload_writer_modules() -> None:
    """Import every module the writer thread needs, here, before it starts.  An import in that thread can deadlock
    a Ctrl-C: a KeyboardInterrupt that lands inside an import of the driving thread (Arrow imports pandas on its
    first conversion to NumPy) leaves CPython's import lock held, and the interrupted run then waits for the
    writer, which waits for that lock (found by an attack: 8 of 28 Ctrl-Cs half a second into a batch hung for
    good).  With nothing left to import, the writer never needs the lock.  pandas is the driving thread's own lazy
    import (Arrow's conversions), loaded here too although it costs a run 0.18 s: a Ctrl-C inside that import can
    come back as an ImportError that Arrow takes for "no pandas" and goes on, and the run then ignores the
    interrupt and ends with exit 0 (5 of 10 Ctrl-Cs 0.45-0.65 s into a batch without it; 0 of 15 with it)."""
    import importlib

    for name in WRITER_MODULES:
        importlib.import_module(name)


@dataclass(frozen=True)
class InProcessEngine:
    """Chunks one after the other in this process (the compiled kernels use every core); each
    chunk's rows come back to the driver, which writes them straight into the output.

    Writing overlaps computing: while chunk i+1 is read and evaluated, one writer thread stores chunk
    i (its part file, hashed as written) and hands it to ``done`` (the manifest line, then the rows
    into the output), so ``done`` runs in that thread, in chunk order, one chunk at a time.  pyarrow
    and hashlib release the GIL while they write and hash.  At most one chunk is in flight in each
    half; an error in the writer (a full disk) is raised here at the next chunk, and an interruption
    marks the writer, which drops the chunk it is writing at its next slice (``runs.abandon``): only chunks
    whose files are complete are kept."""

    name = "inprocess"

    def run(self, plan, payloads, workdir: str, done) -> None:
        import threading
        from concurrent.futures import ThreadPoolExecutor

        from fruitimpact.runs import abandon

        from fruitimpact.runs.chunks import compute_chunk, store_chunk  # here: the CLI parser reads ENGINES cheaply

        preload_writer_modules()

        stop = threading.Event()

        def store(computed):
            abandon.attach(stop)
            done(store_chunk(plan, computed, workdir, keep_rows=True))

        with ThreadPoolExecutor(1, thread_name_prefix="fruitimpact-writer") as writer:
            try:
                writing = None
                for index, payload in payloads:
                    computed = compute_chunk(plan, index, payload)
                    if writing is not None:
                        writing.result()  # the previous chunk is stored (or its error raised) before the next
                    writing = writer.submit(store, computed)
                if writing is not None:
                    writing.result()
            except KeyboardInterrupt:
                stop.set()  # the chunk being written is dropped at its next slice, not waited for
                raise


@dataclass(frozen=True)
class DaskEngine:
    """Chunks as tasks on a Dask cluster: ``scheduler`` (address) or a local cluster of ``workers``
    single-threaded worker processes.  Each task evaluates one chunk with single-threaded kernels
    and writes its part file itself (the work folder must be shared with the workers); the driver
    reads the parts back, verified, into the output."""

    scheduler: str | None = None
    workers: int = 2
    name = "dask"

    def __post_init__(self):
        if self.scheduler is not None:
            check_scheduler(self.scheduler)

    def run(self, plan, payloads, workdir: str, done) -> None:
        from fruitimpact.runs.chunks import run_chunk  # here: the CLI parser reads ENGINES cheaply

        import logging

        try:
            from distributed import Client, LocalCluster, as_completed
        except ImportError:
            raise RunError("--engine dask needs dask: pip install 'fruitimpact[dask]'") from None
        cluster = None
        if self.scheduler is None:
            cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                   dashboard_address=":0", silence_logs=logging.ERROR)
            client = Client(cluster)
        else:
            try:
                client = Client(self.scheduler, timeout="10s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise RunError(f"argument --scheduler: cannot connect to {self.scheduler!r} "
                               f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
        try:
            slots = max(1, sum(client.nthreads().values()))
            shared = client.scatter(plan, broadcast=True)
            running = as_completed(with_results=True)
            for index, payload in payloads:
                running.add(client.submit(run_chunk, shared, index, payload, workdir, 1, pure=False))
                while running.count() >= 2 * slots:  # bounded: at most two chunks per worker thread in flight
                    done(next(running)[1])
            for _, result in running:
                done(result)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


#: Engines by name.
ENGINES = {"inprocess": InProcessEngine, "dask": DaskEngine}

__all__ = ["ENGINES", "WRITER_MODULES", "DaskEngine", "InProcessEngine", "check_scheduler", "preload_writer_modules"]
