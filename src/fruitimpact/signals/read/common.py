"""What the readers share: formats and units, the one-line refusals, and ``RecordingSource``.

A reader opens a file with every check that can be made without reading the samples and returns
a ``RecordingSource``: the metadata (rate [Hz], lane names, start time [s], ADC limits [N]) and
a way to read the samples again and again, block by block, in memory bounded by the block.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fruitimpact.impact.validation import InputError
from fruitimpact.signals.settings import check_rate  # noqa: F401  (the one check of a rate, re-exported)

#: Formats and their extensions (the first extension is the one written by default).
FORMATS = {"csv": (".csv", ".txt"), "npy": (".npy",), "f32": (".f32", ".bin", ".raw"), "tdms": (".tdms",)}
#: Extension → format.
EXTENSIONS = {ext: name for name, exts in FORMATS.items() for ext in exts}
#: Force units accepted in CSV headers and TDMS ``unit_string`` → factor to N.
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "mN": 1e-3}
#: Time units accepted in CSV headers → factor to s (``µs`` with the micro sign or the Greek mu).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6}
#: Names of the CSV time column (compared in lower case, without the unit).
TIME_NAMES = ("time", "t")
#: Largest relative disagreement between two rates (time column vs ``rate``, lanes of a TDMS file),
#: and between one sampling interval and the mean interval.
RATE_TOLERANCE = 1e-6
#: Samples per lane of one chunk of ``RecordingSource.chunks`` by default.
CHUNK_SAMPLES = 1 << 16
#: Fewest samples per lane a binary reader (npy, f32, TDMS) reads at once: smaller chunks are cut from
#: blocks of this size, larger ones are read whole.
BLOCK_SAMPLES = 1 << 16


def error(path, reason: str, argument: str = "path") -> InputError:
    """The refusal of file ``path``: ``cannot read 'PATH': REASON``, about ``argument``."""
    return InputError(f"cannot read {str(path)!r}: {reason}", argument)


def check_file(path) -> Path:
    """``path`` as a ``Path`` when it names a readable file; else the refusal (missing, a folder, …)."""
    if path is None or str(path) == "":
        raise InputError("path must name a recording file; got an empty name", "path")
    path = Path(path)
    try:
        if not path.exists():
            raise error(path, "no such file")
        if path.is_dir():
            raise error(path, "it is a folder, not a recording file")
        if not os.access(path, os.R_OK):
            raise error(path, "no permission to read it")
    except OSError as exc:
        raise error(path, exc.strerror or str(exc)) from None
    return path


def open_file(path: Path, buffering: int = -1):
    """``open(path, "rb")`` with an ``OSError`` turned into the one-line refusal."""
    try:
        return open(path, "rb", buffering=buffering)
    except OSError as exc:
        raise error(path, exc.strerror or str(exc)) from None


def read_some(handle, path, size: int) -> bytes:
    """Up to ``size`` bytes of ``handle`` from where it is (fewer at the end of the file), an ``OSError``
    turned into the one-line refusal."""
    try:
        return handle.read(size)
    except OSError as exc:
        raise error(path, exc.strerror or str(exc)) from None


def read_exactly(handle, path, position: int, size: int) -> bytes:
    """``size`` bytes of ``handle`` from byte ``position``; a file that ends (or fails) before is refused."""
    try:
        handle.seek(position)
        data = handle.read(size)
    except OSError as exc:
        raise error(path, exc.strerror or str(exc)) from None
    if len(data) != size:
        raise error(path, f"the file ends at byte {position + len(data)}, before byte {position + size} its "
                          f"header promises (truncated, or changed since it was opened)")
    return data


def need_rate(path, rate, why: str) -> float:
    """``rate`` [Hz], which the file cannot give (``why``): refused when None."""
    if rate is None:
        raise error(path, f"rate is required: {why}; give the sample rate [Hz] (--rate; rate= in Python)", "rate")
    return rate


def agree(path, rate_file: float, rate, what: str) -> float:
    """The file's rate [Hz], or ``rate`` when given and agreeing within ``RATE_TOLERANCE``."""
    if rate is None:
        return rate_file
    if abs(rate_file - rate) > RATE_TOLERANCE * rate:
        raise error(path, f"rate={rate:.10g} Hz disagrees with {what} ({rate_file:.10g} Hz; "
                          f"allowed: {RATE_TOLERANCE:g} relative)", "rate")
    return rate


def select(path, names: list[str], column) -> list[str]:
    """The lanes read: all ``names``, or the one named ``column`` (refused when unknown)."""
    if column is None:
        return names
    if column not in names:
        raise error(path, f"unknown column {column!r} (available: {', '.join(map(repr, names))})", "column")
    return [column]


def check_finite(path, names, block: np.ndarray, first_row: int) -> None:
    """Refuse the first sample of ``block`` (rows × lanes, its first row is sample ``first_row`` of the
    file) that is NaN or infinite, lane by lane in order."""
    if np.isfinite(block).all():
        return
    for k, name in enumerate(names):
        bad = np.flatnonzero(~np.isfinite(block[:, k]))
        if bad.size:
            raise error(path, f"sample {int(bad[0]) + first_row} of lane {name!r} is {float(block[bad[0], k])!r}; "
                              f"force samples must be finite numbers")


def rechunk(blocks: Iterable[np.ndarray], size: int) -> Iterator[np.ndarray]:
    """The rows of ``blocks`` (arrays of any length, 1-D or rows × lanes) in pieces of exactly ``size``
    rows, the last one shorter when the rows run out.  A piece inside one block is a view of it; a piece
    across blocks is a new C-contiguous array."""
    pending: list[np.ndarray] = []
    have = 0
    for block in blocks:
        rows = block.shape[0]
        start = 0
        if have:
            if have + rows < size:
                pending.append(block)
                have += rows
                continue
            start = size - have
            pending.append(block[:start])
            yield np.concatenate(pending)
            pending, have = [], 0
        while rows - start >= size:
            yield block[start:start + size]
            start += size
        if start < rows:
            pending, have = [block[start:]], rows - start
    if have:
        yield pending[0] if len(pending) == 1 else np.concatenate(pending)


@dataclass(frozen=True, eq=False)
class RecordingSource:
    """An opened recording file: its metadata, checked, and its samples read chunk by chunk.

    Made by ``open_recording`` after every check that needs no full pass over the samples (the file,
    the format, the rate, the column, the header and units); what can only be found while reading (a
    bad CSV row, a NaN sample, a file cut short) is refused by ``chunks`` where it is met, with the
    line or sample number.

    Attributes
    ----------
    source : str
        The path, as given.
    format : str
        ``csv``, ``npy``, ``f32`` or ``tdms``.
    rate : float
        Sample rate [Hz] (from the file, or the ``rate`` given).
    lane_names : tuple of str
        The lanes read, in order (the columns of every chunk).
    start_time : float
        Time of the first sample [s].
    clip_low, clip_high : float or None
        The ADC's limits [N] when the file states them (TDMS), else None.
    samples : int or None
        Samples per lane, or None when only a full pass could tell (a CSV file longer than the rows read
        to find its rate).
    notes : tuple of str
        What the reader found odd but could read (a TDMS file's last segment cut short), one line each, for
        the caller's warnings.
    """

    source: str
    format: str
    rate: float
    lane_names: tuple[str, ...]
    start_time: float = 0.0
    clip_low: float | None = None
    clip_high: float | None = None
    samples: int | None = None
    notes: tuple[str, ...] = ()
    #: ``_blocks(hint)``: a fresh generator of float64 blocks (rows × lanes, C-contiguous) covering the
    #: file in order, of any length, each of at most max(hint, a reader's own block) rows.
    _blocks: Callable[[int], Iterator[np.ndarray]] = field(default=None, repr=False)

    @property
    def duration(self) -> float | None:
        """Time covered [s]: ``samples / rate``, or None when ``samples`` is unknown."""
        return None if self.samples is None else self.samples / self.rate

    def chunks(self, samples: int = CHUNK_SAMPLES) -> Iterator[np.ndarray]:
        """The force samples [N], in order: C-contiguous float64 arrays of shape (n, lanes) with
        n = ``samples`` for every chunk but the last (1 ≤ n ≤ ``samples``).

        Each call reads the file again from its start.  Memory is bounded by the chunk and the reader's
        block (a few MB), not by the file.  Raises ``ValueError`` (one line: the file, the line or
        sample, what is allowed) at the first bad row or sample, after yielding the chunks before it.
        """
        if isinstance(samples, (bool, np.bool_)) or not isinstance(samples, (int, np.integer)) or samples < 1:
            raise InputError(f"samples must be an integer >= 1 (samples per lane in a chunk); got {samples!r}",
                             "samples")
        return rechunk(self._blocks(int(samples)), int(samples))

    def __repr__(self) -> str:
        return (f"RecordingSource(source={self.source!r}, format={self.format!r}, rate={self.rate!r}, "
                f"lane_names={self.lane_names!r}, samples={self.samples!r}, start_time={self.start_time!r}, "
                f"clip_low={self.clip_low!r}, clip_high={self.clip_high!r})")


__all__ = ["BLOCK_SAMPLES", "CHUNK_SAMPLES", "EXTENSIONS", "FORCE_UNITS", "FORMATS", "RATE_TOLERANCE", "TIME_NAMES",
           "TIME_UNITS", "RecordingSource", "agree", "check_file", "check_finite", "check_rate", "error",
           "need_rate", "open_file", "read_exactly", "read_some", "rechunk", "select"]
