"""Abandoning a writer thread's chunk when its run is interrupted.

The in-process engine stores chunk i in a writer thread while chunk i+1 is computed.  A Ctrl-C then waits for
that chunk to be stored, which with large chunks took seconds (7.8 s for 3,000,000 rows: an attack).  Instead the
interrupted run sets its own stop event, which its writer thread holds (``attach``), and the writer stops at its
next slice of ``WRITE_SLICE`` rows: the part file's temporary is removed unrenamed (so the chunk is not kept, and
computed again on resume), and the output's temporary is discarded with the interrupted run.  An event per run,
held by that run's writer thread: another run of the process is never stopped by it.
"""

from __future__ import annotations

import threading

#: Rows written between two looks at the mark: a default chunk (500,000 rows) is one slice, and a slice is written
#: in about half a second (CSV text; a Parquet row group of this size is as good as a larger one).
WRITE_SLICE = 1 << 19

_HELD = threading.local()


def attach(stop: threading.Event) -> None:
    """This thread writes for the run whose stop event is ``stop``."""
    _HELD.stop = stop


def check() -> None:
    """KeyboardInterrupt in a writer thread whose run was interrupted."""
    stop = getattr(_HELD, "stop", None)
    if stop is not None and stop.is_set():
        raise KeyboardInterrupt


def slices(table):
    """``table`` in slices of at most ``WRITE_SLICE`` rows (the table itself when it is smaller), with a look at the
    mark between two slices: a chunk of one slice is always written whole (it takes well under a second)."""
    if table.num_rows <= WRITE_SLICE:
        yield table
        return
    for start in range(0, table.num_rows, WRITE_SLICE):
        if start:
            check()
        yield table.slice(start, WRITE_SLICE)


__all__ = ["WRITE_SLICE", "attach", "check", "slices"]
