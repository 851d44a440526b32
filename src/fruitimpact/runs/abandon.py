"""Abandoning a writer thread's chunk when its run is interrupted.

The in-process engine stores chunk i in a writer thread while chunk i+1 is computed.  A Ctrl-C then waits for
that chunk to be stored, which with large chunks took seconds (7.8 s for 3,000,000 rows: an attack).  Instead the
interrupted run marks its writer thread, and the writer stops at its next slice of ``WRITE_SLICE`` rows: the part
file's temporary is removed unrenamed (so the chunk is not kept, and computed again on resume), and the output's
temporary is discarded with the interrupted run.  Marked by thread, so that other runs of the process go on.
"""

from __future__ import annotations

import threading

#: Rows written between two looks at the mark: a default chunk (500,000 rows) is one slice, and a slice is written
#: in about half a second (CSV text; a Parquet row group of this size is as good as a larger one).
WRITE_SLICE = 1 << 19

_MARKED: set[int] = set()
_LOCK = threading.Lock()


def mark(threads) -> None:
    """Ask the threads ``threads`` (idents) to abandon what they write."""
    with _LOCK:
        _MARKED.update(threads)


def unmark(threads) -> None:
    with _LOCK:
        _MARKED.difference_update(threads)


def check() -> None:
    """KeyboardInterrupt in a marked thread: its run was interrupted."""
    if threading.get_ident() in _MARKED:
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


__all__ = ["WRITE_SLICE", "check", "mark", "slices", "unmark"]
