"""Reading force recordings from files: CSV, NumPy ``.npy``, raw float32 and NI TDMS.

``read_recording(path)`` returns a ``Recording`` (force [N], rate [Hz], SI
throughout).  The format comes from the extension, or from ``format``:

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

CSV
    Lines starting with ``#`` (after optional blanks) are comments and blank
    lines are skipped, anywhere in the file.  The first other line is the
    header; its delimiter is the first of ``,``, tab and ``;`` it contains (a
    header without any is one column).  A column named ``time`` or ``t`` (any
    case) is the time column; its unit must be in the header: ``time [s]``,
    ``time (ms)``, ``time_ms``, ``t [us]`` (units ``s``, ``ms``, ``us``, ``µs``).
    Every other column is a force lane, named by its header without the unit;
    its unit is ``N``, ``kN`` or ``mN`` written the same ways (``left [kN]``,
    ``right_mN``); **a force column without a unit is read as newtons**.  With
    a time column the rate is derived from it (the times must increase strictly
    and be uniform within 1e-6 of the interval, so write them with enough
    digits); without one, ``rate`` must be given.  Every used cell must be a
    finite number; ragged rows are refused with their line number.

NPY / raw float32
    Lanes are named ``lane0``, ``lane1`` …; the files carry no time, so
    ``rate`` is required and the start time is 0.

TDMS
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

Every refusal is one ``ValueError`` line naming the file and what is allowed,
raised before the samples are used.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from pathlib import Path

import numpy as np

from ..validation import InputError
from .recording import Recording

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

_ALLOWED_EXTENSIONS = ", ".join(EXTENSIONS)


def _error(path, reason: str, argument: str = "path") -> InputError:
    return InputError(f"cannot read {str(path)!r}: {reason}", argument)


# --------------------------------------------------------------------------- arguments and files

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


def _check_file(path) -> Path:
    if path is None or str(path) == "":
        raise InputError("path must name a recording file; got an empty name", "path")
    path = Path(path)
    try:
        if not path.exists():
            raise _error(path, "no such file")
        if path.is_dir():
            raise _error(path, "it is a folder, not a recording file")
        if not os.access(path, os.R_OK):
            raise _error(path, "no permission to read it")
    except OSError as exc:
        raise _error(path, exc.strerror or str(exc)) from None
    return path


def _read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as exc:
        raise _error(path, exc.strerror or str(exc)) from None


def _check_rate(rate) -> float | None:
    if rate is None:
        return None
    if isinstance(rate, (bool, np.bool_)) or not isinstance(rate, (int, float, np.integer, np.floating)):
        raise InputError(f"rate must be a number of samples per second [Hz] > 0; got {rate!r}", "rate")
    rate = float(rate)
    if not math.isfinite(rate) or rate <= 0.0:
        raise InputError(f"rate must be a finite number > 0 Hz; got {rate!r}", "rate")
    return rate


def _need_rate(path, rate, why: str) -> float:
    if rate is None:
        raise _error(path, f"rate is required: {why}; give rate= [Hz]", "rate")
    return rate


def _agree(path, rate_file: float, rate, what: str) -> float:
    """The file's rate, or ``rate`` when given and agreeing within ``RATE_TOLERANCE``."""
    if rate is None:
        return rate_file
    if abs(rate_file - rate) > RATE_TOLERANCE * rate:
        raise _error(path, f"rate={rate:.10g} Hz disagrees with {what} ({rate_file:.10g} Hz; "
                           f"allowed: {RATE_TOLERANCE:g} relative)", "rate")
    return rate


def _select(path, names: list[str], column) -> list[str]:
    if column is None:
        return names
    if column not in names:
        raise _error(path, f"unknown column {column!r} (available: {', '.join(map(repr, names))})", "column")
    return [column]


def _check_finite(path, name: str, values: np.ndarray, first_row: int = 0) -> None:
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise _error(path, f"sample {bad[0] + first_row} of lane {name!r} is {float(values[bad[0]])!r}; "
                           f"force samples must be finite numbers")


def read_recording(path, *, rate: float | None = None, column: str | None = None, format: str | None = None,
                   lanes: int = 1) -> Recording:
    """Read a force recording.

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
    Recording
        Force [N] of every lane (float64), the rate [Hz], the start time [s]
        (the first time of a CSV time column, ``wf_start_offset`` of a TDMS
        waveform, else 0), the ADC limits when the file states them (TDMS
        ``clip_low``/``clip_high``), and ``source`` = the path.

    Raises ``ValueError`` (one line naming the file or the argument and what is
    allowed) for a missing file, a folder, an unsupported format, garbage or
    empty content, a missing ``rate``, an unknown ``column`` (the available ones
    are listed), lanes without samples, and the CSV errors described in the
    module docstring.
    """
    rate = _check_rate(rate)
    if column is not None and not isinstance(column, str):
        raise InputError(f"column must be a lane name (a string) or None; got {column!r}", "column")
    if isinstance(lanes, (bool, np.bool_)) or not isinstance(lanes, (int, np.integer)) or lanes < 1:
        raise InputError(f"lanes must be an integer >= 1 (interleaved lanes of a raw float32 file); got {lanes!r}",
                         "lanes")
    kind = recording_format(path, format)
    if lanes != 1 and kind != "f32":
        raise InputError(f"lanes applies to raw float32 files only (.f32, .bin, .raw); got lanes={lanes} for a "
                         f"{kind} file", "lanes")
    path = _check_file(path)
    if kind == "csv":
        return _read_csv(path, rate, column)
    if kind == "npy":
        return _read_npy(path, rate, column)
    if kind == "f32":
        return _read_f32(path, rate, column, int(lanes))
    return _read_tdms(path, rate, column)


# --------------------------------------------------------------------------- CSV

_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?\Z")
_BRACKETED = re.compile(r"(?P<name>.*?)\s*(?:\[(?P<square>[^\[\]]*)\]|\((?P<round>[^()]*)\))\Z")
_SKIPPED = re.compile(r"^[ \t]*(?:#.*)?\r?$", re.MULTILINE)
#: Rows per block when looking for a bad row of a large CSV file.
_BLOCK = 8192


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return [line]
    return next(csv.reader([line], delimiter=delimiter, quotechar='"'))


def _column(path, cell: str, index: int) -> tuple[str, bool, float]:
    """(lane name, is time, factor to SI) of one header cell."""
    text = cell.strip()
    if not text:
        raise _error(path, f"column {index + 1} of the header has no name")
    if _NUMBER.match(text):
        raise _error(path, f"the first line that is not a comment looks like data ({text!r}), not a header; "
                           f"a CSV needs a header line such as 'time [s],force [N]'")
    match = _BRACKETED.match(text)
    unit = None
    name = text
    if match and match["name"]:
        name, unit = match["name"].strip(), (match["square"] if match["square"] is not None else match["round"])
        unit = unit.strip()
    else:
        base, _, suffix = text.rpartition("_")
        if base and ((base.strip().lower() in TIME_NAMES and suffix in TIME_UNITS) or suffix in FORCE_UNITS):
            name, unit = base.strip(), suffix
    is_time = name.lower() in TIME_NAMES
    if is_time:
        if unit is None:
            raise _error(path, f"the time column {text!r} has no unit; write it in the header: "
                               f"'{name} [s]', '{name} [ms]' or '{name} [us]'")
        if unit not in TIME_UNITS:
            raise _error(path, f"column {text!r}: time unit {unit!r} is not allowed (allowed: s, ms, us)")
        return name, True, TIME_UNITS[unit]
    if unit is not None and unit not in FORCE_UNITS:
        raise _error(path, f"column {text!r}: force unit {unit!r} is not allowed (allowed: N, kN, mN; "
                           f"a column without a unit is read as N)")
    return name, False, FORCE_UNITS[unit] if unit is not None else 1.0


def _lines_from(text: str, start: int):
    """(line number from 1, line without its end) of ``text`` from offset ``start`` (a line start)."""
    number = text.count("\n", 0, start) + 1
    position = start
    while position < len(text):
        end = text.find("\n", position)
        if end < 0:
            end = len(text)
        yield number, text[position:end].rstrip("\r"), end + 1
        number += 1
        position = end + 1


def _read_csv(path: Path, rate, column) -> Recording:
    raw = _read_bytes(path)
    if not raw.strip():
        raise _error(path, "empty file")
    if b"\x00" in raw:
        raise _error(path, "binary content (NUL bytes), not CSV text")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise _error(path, f"not UTF-8 text (undecodable byte at offset {exc.start}), not a CSV file") from None
    header = None
    for number, line, following in _lines_from(text, 0):
        if not _SKIPPED.fullmatch(line):
            header = (number, line, following)
            break
    if header is None:
        raise _error(path, "empty file (only comments and blank lines)")
    _, line, body_start = header
    delimiter = next((d for d in (",", "\t", ";") if d in line), None)
    cells = _split(line, delimiter)
    columns = [_column(path, cell, i) for i, cell in enumerate(cells)]
    times = [i for i, (_, is_time, _) in enumerate(columns) if is_time]
    if len(times) > 1:
        raise _error(path, f"more than one time column ({', '.join(repr(cells[i].strip()) for i in times)})")
    force = [i for i, (_, is_time, _) in enumerate(columns) if not is_time]
    if not force:
        raise _error(path, "no force column (only a time column)")
    names = [columns[i][0] for i in force]
    duplicated = sorted({name for name in names if names.count(name) > 1})
    if duplicated:
        raise _error(path, f"duplicate column names {', '.join(map(repr, duplicated))}")
    if column is not None:
        by_header = {cells[i].strip(): columns[i][0] for i in force}
        if column in by_header:
            column = by_header[column]
        elif times and column in (cells[times[0]].strip(), columns[times[0]][0]):
            raise _error(path, f"column {column!r} is the time column; choose a force column "
                               f"(available: {', '.join(map(repr, names))})", "column")
    selected = _select(path, names, column)
    used = ([times[0]] if times else []) + [force[names.index(name)] for name in selected]
    if not times and rate is None:
        raise _error(path, "rate is required: the file has no time column (time [s], time [ms], time [us])", "rate")
    values, line_numbers = _csv_values(path, text, body_start, len(cells), delimiter, used, cells)
    if values.shape[0] == 0:
        raise _error(path, "all lanes empty: the file has a header but no data rows")
    start_time = 0.0
    if times:
        t = values[:, 0] * columns[times[0]][2]
        start_time = float(t[0])
        if t.size == 1:
            rate = _need_rate(path, rate, "one sample cannot give the rate")
        else:
            rate = _agree(path, _time_rate(path, t, line_numbers), rate, "the time column")
    lanes = {name: values[:, k + (1 if times else 0)] * columns[force[names.index(name)]][2]
             for k, name in enumerate(selected)}
    return Recording(rate=rate, lanes=lanes, start_time=start_time, source=str(path))


def _time_rate(path, t: np.ndarray, line_numbers) -> float:
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0.0))
    if bad.size:
        i = int(bad[0])
        raise _error(path, f"non-monotonic time at row {i + 2} (line {line_numbers[i + 1]}): {float(t[i + 1])!r} s "
                           f"after {float(t[i])!r} s; time must increase strictly")
    span = float(t[-1] - t[0])
    interval = span / (t.size - 1)
    slack = RATE_TOLERANCE * interval + 8.0 * np.finfo(float).eps * max(abs(t[0]), abs(t[-1]))
    bad = np.flatnonzero(np.abs(steps - interval) > slack)
    if bad.size:
        i = int(bad[0])
        raise _error(path, f"non-uniform sampling at row {i + 2} (line {line_numbers[i + 1]}): interval "
                           f"{steps[i]:.9g} s, mean interval {interval:.9g} s (allowed: {RATE_TOLERANCE:g} "
                           f"relative; write the times with more digits, or drop the time column and give rate=)")
    return (t.size - 1) / span


def _csv_values(path, text: str, body_start: int, ncols: int, delimiter, used: list[int], header: list[str]):
    """The used columns of the data rows (rows × used) and the line number of every row."""
    body = text[body_start:].rstrip()
    first_line = text.count("\n", 0, body_start) + 1
    if not body:
        return np.empty((0, len(used))), np.empty(0, dtype=np.int64)
    lines = None
    numbers = None
    # a comment or blank line may be anywhere: then the lines are filtered one by one
    encoded = body.encode("utf-8")
    if _maybe_skipped(encoded):
        lines = [line.rstrip("\r") for line in body.split("\n")]
        keep = [i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
        numbers = first_line + np.array(keep, dtype=np.int64)
        lines = [lines[i] for i in keep]
        if not lines:
            return np.empty((0, len(used))), numbers
        encoded = "\n".join(lines).encode("utf-8")
    values = _fast_values(encoded, ncols, delimiter, used)
    if values is None:
        # find the first bad row block by block: Arrow on each block, Python only on a failing one
        if lines is None:
            lines = [line.rstrip("\r") for line in body.split("\n")]
            numbers = np.arange(first_line, first_line + len(lines), dtype=np.int64)
        blocks = []
        for begin in range(0, len(lines), _BLOCK):
            block = lines[begin:begin + _BLOCK]
            part = _fast_values("\n".join(block).encode("utf-8"), ncols, delimiter, used)
            if part is None:
                part = _slow_values(path, block, numbers[begin:begin + _BLOCK], begin, ncols, delimiter, used,
                                    header)
            blocks.append(part)
        values = np.concatenate(blocks)
    if numbers is None:
        numbers = np.arange(first_line, first_line + values.shape[0], dtype=np.int64)
    return values, numbers


def _maybe_skipped(data: bytes) -> bool:
    """Whether ``data`` may hold a comment or blank line: a ``#`` anywhere, or a line that starts
    with a blank, a line end or ``#`` (vectorised: a large file is scanned in a few passes)."""
    if b"#" in data:
        return True
    raw = np.frombuffer(data, dtype=np.uint8)
    starts = np.flatnonzero(raw[:-1] == 10) + 1
    first = raw[np.concatenate(([0], starts))] if raw.size else raw
    return bool(np.isin(first, np.frombuffer(b" \t\r\n", dtype=np.uint8)).any())


def _fast_values(clean: bytes, ncols: int, delimiter, used: list[int]):
    """The used columns parsed by Arrow's CSV reader, or None when any row needs a closer look
    (a parse error, an empty, NaN or infinite cell): the slow reader then says where."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    names = [f"c{i}" for i in range(ncols)]
    wanted = [names[i] for i in used]
    try:
        table = pacsv.read_csv(
            io.BytesIO(clean),
            read_options=pacsv.ReadOptions(column_names=names),
            parse_options=pacsv.ParseOptions(delimiter=delimiter or "\x1f", quote_char='"',
                                             newlines_in_values=False, ignore_empty_lines=True),
            convert_options=pacsv.ConvertOptions(column_types={name: pa.float64() for name in wanted},
                                                 include_columns=wanted))
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError):
        return None
    if table.num_rows != clean.count(b"\n") + 1:
        return None
    out = np.empty((table.num_rows, len(wanted)))
    for k, name in enumerate(wanted):
        array = table.column(name)
        if array.null_count:
            return None
        out[:, k] = array.to_numpy()
    if not np.isfinite(out).all():
        return None
    return out


def _slow_values(path, lines, numbers, first_row: int, ncols: int, delimiter, used: list[int],
                 header: list[str]) -> np.ndarray:
    """Row by row: the first ragged row or bad cell is refused with its line and column."""
    out = np.empty((len(lines), len(used)))
    for row, (line, number) in enumerate(zip(lines, numbers, strict=True), start=first_row):
        cells = _split(line, delimiter)
        if len(cells) != ncols:
            raise _error(path, f"line {number} has {len(cells)} cells, the header {ncols} (ragged row)")
        for k, index in enumerate(used):
            cell = cells[index].strip()
            where = f"line {number} (data row {row + 1}), column {header[index].strip()!r}"
            if not cell:
                raise _error(path, f"{where}: empty cell; every cell must be a number")
            if not _NUMBER.match(cell):
                raise _error(path, f"{where}: {cell!r} is not a number (NaN and infinities are not allowed)")
            value = float(cell)
            if not math.isfinite(value):
                raise _error(path, f"{where}: {cell!r} is beyond double precision")
            out[row - first_row, k] = value
    return out


# --------------------------------------------------------------------------- NPY and raw float32

def _lanes_of(path, matrix: np.ndarray, column) -> dict[str, np.ndarray]:
    names = [f"lane{k}" for k in range(matrix.shape[1])]
    selected = _select(path, names, column)
    lanes = {}
    for name in selected:
        values = matrix[:, names.index(name)].astype(np.float64)
        _check_finite(path, name, values)
        lanes[name] = values
    return lanes


def _read_npy(path: Path, rate, column) -> Recording:
    if path.stat().st_size == 0:
        raise _error(path, "empty file")
    try:
        array = np.load(path, allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises ValueError, OSError, EOFError … on foreign content
        raise _error(path, f"not a NumPy .npy file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") \
            from None
    if not isinstance(array, np.ndarray):
        if hasattr(array, "close"):
            array.close()
        raise _error(path, "a .npz archive, not a .npy array")
    if array.dtype.kind not in "iuf":
        raise _error(path, f"holds {array.dtype} values; a recording needs real numbers (integers or floats)")
    if array.ndim not in (1, 2):
        raise _error(path, f"array of shape {array.shape}; allowed: 1-D (one lane) or 2-D (samples × lanes)")
    matrix = array[:, None] if array.ndim == 1 else array
    if matrix.shape[1] == 0:
        raise _error(path, f"array of shape {array.shape} has no lanes")
    rate = _need_rate(path, rate, ".npy files hold no time")
    if matrix.shape[0] == 0:
        raise _error(path, f"all lanes empty (array of shape {array.shape})")
    return Recording(rate=rate, lanes=_lanes_of(path, matrix, column), source=str(path))


def _read_f32(path: Path, rate, column, lanes: int) -> Recording:
    size = path.stat().st_size
    if size == 0:
        raise _error(path, "empty file")
    if size % (4 * lanes):
        raise _error(path, f"{size} bytes is not a whole number of float32 samples × {lanes} lane(s) "
                           f"(a multiple of {4 * lanes} bytes)")
    rate = _need_rate(path, rate, "raw float32 files hold no time")
    try:
        data = np.fromfile(path, dtype="<f4")
    except OSError as exc:
        raise _error(path, exc.strerror or str(exc)) from None
    return Recording(rate=rate, lanes=_lanes_of(path, data.reshape(-1, lanes), column), source=str(path))


# --------------------------------------------------------------------------- TDMS

def _property_number(path, name: str, properties, key: str):
    if key not in properties:
        return None
    value = properties[key]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(float(value)):
        raise _error(path, f"channel {name!r}: property {key} = {value!r} is not a finite number")
    return float(value)


def _read_tdms(path: Path, rate, column) -> Recording:
    if path.stat().st_size == 0:
        raise _error(path, "empty file")
    try:
        from nptdms import TdmsFile
    except ImportError:
        raise _error(path, "reading TDMS needs the nptdms package (pip install nptdms)") from None
    try:
        tdms = TdmsFile.read(path)
        channels = [(f"{group.name}/{channel.name}", channel) for group in tdms.groups()
                    for channel in group.channels()]
    except Exception as exc:  # noqa: BLE001 - nptdms raises ValueError, KeyError, struct.error … on damaged files
        raise _error(path, f"not a readable TDMS file ({exc})") from None
    if not channels:
        raise _error(path, "no channels (not a TDMS recording, or an empty one)")
    if column is not None:
        chosen = [(name, channel) for name, channel in channels if name == column]
        if not chosen:
            chosen = [(name, channel) for name, channel in channels if channel.name == column]
        if not chosen:
            raise _error(path, f"unknown column {column!r} (available: {', '.join(repr(n) for n, _ in channels)})",
                         "column")
        if len(chosen) > 1:
            raise _error(path, f"column {column!r} is ambiguous: it matches {', '.join(repr(n) for n, _ in chosen)}; "
                               f"give group/channel", "column")
        name, channel = chosen[0]
        if channel.dtype.kind not in "iuf":
            raise _error(path, f"channel {name!r} holds {channel.dtype} values, not numbers", "column")
        if len(channel) == 0:
            raise _error(path, f"all lanes empty: channel {name!r} has no samples")
    else:
        numeric = [(name, channel) for name, channel in channels if channel.dtype.kind in "iuf"]
        if not numeric:
            raise _error(path, f"no channel of numbers (channels: {', '.join(repr(n) for n, _ in channels)})")
        chosen = [(name, channel) for name, channel in numeric if len(channel) > 0]
        if not chosen:
            raise _error(path, "all lanes empty: no channel has samples")
    lanes, rates, starts, lengths, clips = {}, {}, {}, {}, {}
    for name, channel in chosen:
        properties = channel.properties
        unit = str(properties.get("unit_string", "")).strip()
        if unit and unit not in FORCE_UNITS:
            raise _error(path, f"channel {name!r} has unit {unit!r}; a force lane must be in N, kN or mN "
                               f"(or carry no unit_string, read as N)")
        scale = FORCE_UNITS.get(unit, 1.0)
        x_unit = str(properties.get("wf_xunit_string", "s")).strip()
        if x_unit not in ("s", ""):
            raise _error(path, f"channel {name!r}: waveform time unit {x_unit!r} is not allowed (allowed: s)")
        increment = _property_number(path, name, properties, "wf_increment")
        if increment is not None and increment <= 0.0:
            raise _error(path, f"channel {name!r}: wf_increment = {increment!r} must be > 0 s")
        rates[name] = None if increment is None else 1.0 / increment
        starts[name] = _property_number(path, name, properties, "wf_start_offset") or 0.0
        low, high = (_property_number(path, name, properties, key) for key in ("clip_low", "clip_high"))
        clips[name] = (None if low is None else low * scale, None if high is None else high * scale)
        values = np.asarray(channel[:]).astype(np.float64) * scale
        _check_finite(path, name, values)
        lanes[name] = values
        lengths[name] = values.size
    advice = "; read one lane with column="

    def listing(mapping):
        return ", ".join(f"{name!r}: {value!r}" for name, value in mapping.items())

    if len(set(lengths.values())) > 1:
        raise _error(path, f"lanes differ in length ({listing(lengths)}){advice}")
    known = {name: value for name, value in rates.items() if value is not None}
    if known and len(known) < len(rates):
        raise _error(path, f"some channels have no wf_increment ({', '.join(n for n in rates if n not in known)})"
                           f"{advice}")
    if known:
        first = next(iter(known.values()))
        if any(abs(value - first) > RATE_TOLERANCE * first for value in known.values()):
            raise _error(path, f"lanes differ in rate ({listing(known)} Hz){advice}")
        rate = _agree(path, first, rate, "the file's wf_increment")
    else:
        rate = _need_rate(path, rate, "the channels have no wf_increment")
    if len(set(starts.values())) > 1:
        raise _error(path, f"lanes differ in wf_start_offset ({listing(starts)} s){advice}")
    if len(set(clips.values())) > 1:
        raise _error(path, f"lanes differ in clip_low/clip_high ({listing(clips)} N){advice}")
    clip_low, clip_high = next(iter(clips.values()))
    return Recording(rate=rate, lanes=lanes, start_time=next(iter(starts.values())), clip_low=clip_low,
                     clip_high=clip_high, source=str(path))


__all__ = ["EXTENSIONS", "FORCE_UNITS", "FORMATS", "RATE_TOLERANCE", "TIME_NAMES", "TIME_UNITS", "read_recording",
           "recording_format"]
