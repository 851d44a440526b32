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
#: in about half a second (Arrow IPC, Parquet; a Parquet row group of this size is as good as a larger one).
WRITE_SLICE = 1 << 19
#: The same for CSV text, which is written 4-5 times slower than Parquet (a slice of ``WRITE_SLICE`` rows took
#: 0.8-1.4 s in a batch's writer thread): slices of CSV change no byte of the file, only when the mark is seen.
CSV_WRITE_SLICE = 1 << 16

_HELD = threading.local()


def attach(stop: threading.Event) -> None:
    """This thread writes for the run whose stop event is ``stop``."""
    _HELD.stop = stop


def check() -> None:
    """KeyboardInterrupt in a writer thread whose run was interrupted."""
    stop = getattr(_HELD, "stop", None)
    if stop is not None and stop.is_set():
        raise KeyboardInterrupt


def slices(table, text: bool = False):
    """``table`` in slices of at most ``WRITE_SLICE`` rows (``CSV_WRITE_SLICE`` for ``text``; the table itself when
    it is smaller), with a look at the mark between two slices: a chunk of one slice is always written whole (it
    takes well under a second)."""
    size = CSV_WRITE_SLICE if text else WRITE_SLICE
    if table.num_rows <= size:
        yield table
        return
    for start in range(0, table.num_rows, size):
        if start:
            check()
        yield table.slice(start, size)


__all__ = ["CSV_WRITE_SLICE", "WRITE_SLICE", "attach", "check", "slices"]
