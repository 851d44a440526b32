"""Reading force recordings from files: CSV, NumPy ``.npy``, raw float32 and NI TDMS.

``open_recording(path)`` checks a file and returns a ``RecordingSource``: its rate [Hz], lane names,
start time [s] and ADC limits [N], and ``chunks(samples)``, the force samples [N] in order as
float64 arrays of shape (samples, lanes), read in memory bounded by the chunk, not the file.
``read_recording(path)`` is the same reading, all chunks joined into a ``Recording`` (force [N],
rate [Hz], SI throughout).  The format comes from the extension, or from ``format``:

========  ========================  ================================================
format    extensions                content
========  ========================  ================================================
``csv``   ``.csv``, ``.txt``        text table with a header line (see below)
``npy``   ``.npy``                  1-D (one lane) or 2-D (samples × lanes) numbers;
                                    needs ``rate``
``f32``   ``.f32``, ``.bin``,       raw little-endian float32, ``lanes`` lanes
          ``.raw``                  interleaved (sample-major); needs ``rate``
``tdms``  ``.tdms``                 National Instruments TDMS (read with ``nptdms``)
========  ========================  ================================================

CSV (module ``csvtable``)
    Lines starting with ``#`` (after optional blanks) are comments and blank
    lines are skipped, anywhere in the file.  The first other line is the
    header; its delimiter is the first of ``,``, tab and ``;`` it contains (a
    header without any is one column).  A column named ``time`` or ``t`` (any
    case) is the time column; its unit must be in the header: ``time [s]``,
    ``time (ms)``, ``time_ms``, ``t [us]`` (units ``s``, ``ms``, ``us``, ``µs``).
    Every other column is a force lane, named by its header without the unit;
    its unit is ``N``, ``kN`` or ``mN`` written the same ways (``left [kN]``,
    ``right_mN``); **a force column without a unit is read as newtons**.  With
    a time column the rate is derived from it: (n − 1)/(t[n−1] − t[0]) over its
    first n = min(rows, 65536) rows, so it is known before the rest is read;
    the times must increase strictly and every interval of the file must be
    within 1e-6 of that mean interval (so write them with enough digits);
    without a time column, ``rate`` must be given.  Every used cell must be a
    finite number; ragged rows are refused with their line number.

NPY / raw float32 (module ``binary``)
    Lanes are named ``lane0``, ``lane1`` …; the files carry no time, so
    ``rate`` is required and the start time is 0.

TDMS (module ``tdms``)
    Every channel of numbers is a lane named ``group/channel`` (empty channels
    and channels of text or timestamps are skipped); ``column`` selects one by
    ``channel`` or ``group/channel``.  The rate is ``1/wf_increment`` (waveform
    channels; ``rate`` is required for channels without it), the start time is
    ``wf_start_offset`` [s] (0 when absent).  ``unit_string`` ``N``, ``kN`` or
    ``mN`` is honoured, a channel without one is read as newtons, any other
    unit (e.g. ``Volts``) is refused.  Channel properties ``clip_low`` and
    ``clip_high`` (in the channel's unit) become the recording's ADC limits.
    All lanes must share length, rate and start: otherwise choose one with
    ``column``.

Every refusal is one ``ValueError`` line naming the file and what is allowed.
What can be checked without reading every sample (the file, the format, the
arguments, the header, units, channels and properties, the rate) is refused by
``open_recording``; a bad row or sample further on (a ragged CSV row at line N,
a NaN in an ``.npy`` file, an interval off the rate) is refused by ``chunks``
when it is met, with its line or sample number, after the chunks before it.
"""

from __future__ import annotations

import numbers
from pathlib import Path

import numpy as np

from fruitimpact.impact.validation import InputError, is_boolean
from fruitimpact.signals.recording import Recording
from fruitimpact.signals.read.binary import open_f32, open_npy
from fruitimpact.signals.read.common import (
    CHUNK_SAMPLES,
    EXTENSIONS,
    FORCE_UNITS,
    FORMATS,
    RATE_TOLERANCE,
    TIME_NAMES,
    TIME_UNITS,
    RecordingSource,
    check_file,
    check_rate,
)
from fruitimpact.signals.read.csvtable import _column, open_csv  # noqa: F401 - _column: synth checks lane names it writes with it
from fruitimpact.signals.read.tdms import open_tdms

_ALLOWED_EXTENSIONS = ", ".join(EXTENSIONS)
#: Samples per lane of each chunk ``read_recording`` joins.
_READ_CHUNK = CHUNK_SAMPLES


def recording_format(path, format: str | None = None, argument: str = "format") -> str:
    """The format name (``csv``, ``npy``, ``f32``, ``tdms``) of ``path``: ``format`` when given
    (a name or an extension such as ``.csv``), else from the extension."""
    if format is not None:
        if not isinstance(format, str):
            raise InputError(f"{argument} must be one of {', '.join(FORMATS)}; got {format!r}", argument)
        key = format.strip().lower()
        if key in FORMATS:
            return key
        if key in EXTENSIONS:
            return EXTENSIONS[key]
        raise InputError(f"{argument} must be one of {', '.join(FORMATS)} (or an extension {_ALLOWED_EXTENSIONS}); "
                         f"got {format!r}", argument)
    suffix = Path(path).suffix.lower()
    if suffix not in EXTENSIONS:
        shown = suffix if suffix else "(no extension)"
        raise InputError(f"unsupported format {shown} of {str(path)!r} (allowed: {_ALLOWED_EXTENSIONS}; "
                         f"or give format=)", "path")
    return EXTENSIONS[suffix]


def open_recording(path, *, rate: float | None = None, column: str | None = None, format: str | None = None,
                   lanes: int = 1) -> RecordingSource:
    """Open a force recording for reading chunk by chunk.

    Parameters
    ----------
    path : str or Path
        The file (``.csv``/``.txt``, ``.npy``, ``.f32``/``.bin``/``.raw``, ``.tdms``).
    rate : float, optional
        Sample rate [Hz].  Required for ``.npy`` and raw files and for CSV files
        without a time column and TDMS channels without ``wf_increment``;
        otherwise, when given, it must agree with the file within 1e-6 relative
        (the given value is then used).
    column : str, optional
        Read only this lane: a CSV force column (name without unit, or the
        header cell as written), ``lane<k>`` of ``.npy``/raw files, or a TDMS
        ``channel`` or ``group/channel``.
    format : str, optional
        ``csv``, ``npy``, ``f32`` or ``tdms`` (or an extension), overriding the
        file's extension.
    lanes : int
        Number of interleaved float32 lanes of a raw file (1 by default); only
        for raw files.

    Returns
    -------
    RecordingSource
        ``rate`` [Hz], ``lane_names``, ``start_time`` [s] (the first time of a
        CSV time column, ``wf_start_offset`` of a TDMS waveform, else 0),
        ``clip_low``/``clip_high`` [N] (TDMS ``clip_low``/``clip_high``, else
        None), ``samples`` per lane (None for a CSV file longer than the rows
        that gave its rate), ``source`` = the path, and ``chunks(samples)``.

    Raises
    ------
    ValueError
        One line naming the file or the argument and what is allowed: a missing file, a folder, an unsupported
        format, garbage or empty content, a missing ``rate``, an unknown ``column`` (the available ones are
        listed), lanes without samples, and the errors of the header, units, channels and properties described
        in the module docstring; the arguments are checked before the file.
    """
    rate = check_rate(rate)
    if column is not None and not isinstance(column, str):
        raise InputError(f"column must be a lane name (a string) or None; got {column!r}", "column")
    if is_boolean(lanes) or not isinstance(lanes, numbers.Integral) or lanes < 1:  # NumPy's too, without loading it
        raise InputError(f"lanes must be an integer >= 1 (interleaved lanes of a raw float32 file); got {lanes!r}",
                         "lanes")
    if format is None and Path(path).suffix.lower() not in EXTENSIONS:
        check_file(path)  # a missing file is said to be missing, not to have an unsupported extension
    kind = recording_format(path, format)
    if lanes != 1 and kind != "f32":
        raise InputError(f"lanes applies to raw float32 files only (.f32, .bin, .raw); got lanes={lanes} for a "
                         f"{kind} file", "lanes")
    path = check_file(path)
    try:
        if kind == "csv":
            return open_csv(path, rate, column)
        if kind == "npy":
            return open_npy(path, rate, column)
        if kind == "f32":
            return open_f32(path, rate, column, int(lanes))
        return open_tdms(path, rate, column)
    except OSError as exc:  # a file that vanished or cannot be read after the first checks
        raise InputError(f"cannot read {str(path)!r}: {exc.strerror or exc}", "path") from None


def read_recording(path, *, rate: float | None = None, column: str | None = None, format: str | None = None,
                   lanes: int = 1) -> Recording:
    """Read a whole force recording: ``open_recording`` with the same arguments, every chunk joined.

    Memory: the recording itself, two (three for CSV) times over while it is built; use
    ``open_recording(...).chunks()`` for files larger than memory.

    Parameters
    ----------
    path : str or Path
        The file (``.csv``/``.txt``, ``.npy``, ``.f32``/``.bin``/``.raw``, ``.tdms``).
    rate : float or str, optional
        Sample rate [Hz] (or with a unit, ``"20kHz"``), as for ``open_recording``.
    column : str, optional
        Read only this lane, as for ``open_recording``.
    format : str, optional
        ``csv``, ``npy``, ``f32`` or ``tdms``; default from the extension.
    lanes : int
        Interleaved lanes of a raw float32 file.

    Returns
    -------
    Recording
        Force [N] of every lane (float64), the rate [Hz], the start time [s], the ADC limits [N] when the file
        states them, and ``source`` = the path.

    Raises
    ------
    ValueError
        As ``open_recording`` and its ``chunks`` (one line): a file that cannot be read or is not a recording (a
        ragged row, a non-finite sample, no unit on the time column), an unsupported format, a rate that is
        missing or disagrees with the file; the message names the row, column or argument.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> recording = fi.read_recording("line.tdms")  # doctest: +SKIP
    >>> recording.rate, list(recording.lanes)  # doctest: +SKIP

    References
    ----------
    TDMS: NI's TDMS file format (read with nptdms); the other formats: docs/signals.md.
    """
    source = open_recording(path, rate=rate, column=column, format=format, lanes=lanes)
    if source.samples is not None:  # lane by lane from the start: each lane one contiguous array
        lanes_first = np.empty((len(source.lane_names), source.samples))
        start = 0
        for chunk in source.chunks(_READ_CHUNK):
            lanes_first[:, start:start + chunk.shape[0]] = chunk.T
            start += chunk.shape[0]
    else:
        parts = list(source.chunks(_READ_CHUNK))
        lanes_first = (parts[0] if len(parts) == 1 else np.concatenate(parts)).T
        del parts
    return Recording(rate=source.rate, lanes=dict(zip(source.lane_names, lanes_first, strict=True)),
                     start_time=source.start_time, clip_low=source.clip_low, clip_high=source.clip_high,
                     source=source.source)


__all__ = ["CHUNK_SAMPLES", "EXTENSIONS", "FORCE_UNITS", "FORMATS", "RATE_TOLERANCE", "TIME_NAMES", "TIME_UNITS",
           "RecordingSource", "open_recording", "read_recording", "recording_format"]
