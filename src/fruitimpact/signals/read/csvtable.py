"""CSV recordings, read block by block (see ``signals.read`` for the format).

The header (after ``#`` comments and blank lines) is read and checked when the file is opened; the
rows follow in blocks of ``BLOCK_BYTES`` cut at line ends, each parsed by Arrow and, when Arrow
refuses a block or finds an empty or non-finite cell, row by row, so that the first bad row is
refused with its line number.  The rate comes from the first ``RATE_ROWS`` rows of the time column;
every interval of the file is then checked against their mean interval, across block boundaries.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fruitimpact.signals.read.common import (
    FORCE_UNITS,
    RATE_TOLERANCE,
    TIME_NAMES,
    TIME_UNITS,
    RecordingSource,
    agree,
    error,
    need_rate,
    open_file,
    read_some,
    select,
)

#: Rows of the time column that give the rate [Hz] (all rows of a shorter file): (rows - 1) / span.
RATE_ROWS = 1 << 16
#: Bytes read and parsed at once (a block ends at a line end; a longer line makes a longer block).
BLOCK_BYTES = 1 << 22
#: Rows per sub-block when looking for the bad row of a block Arrow refused.
_SUB_BLOCK = 8192
_BOM = b"\xef\xbb\xbf"
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?\Z")
_BRACKETED = re.compile(r"(?P<name>.*?)\s*(?:\[(?P<square>[^\[\]]*)\]|\((?P<round>[^()]*)\))\Z")
_SKIPPED = re.compile(r"^[ \t]*(?:#.*)?\r?$", re.MULTILINE)


@dataclass(frozen=True)
class _Layout:
    """What the header says: where the rows start and which cells of a row are used."""

    header: tuple[str, ...]           # the header cells as written
    delimiter: str | None
    used: tuple[int, ...]             # columns parsed: the time column first (if any), then the lanes
    time_factor: float | None         # time unit → s, None without a time column
    factors: tuple[float, ...]        # force unit → N of each lane read
    names: tuple[str, ...]            # the lanes read
    body_offset: int                  # byte offset of the line after the header
    body_line: int                    # its line number (from 1)


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return [line]
    return next(csv.reader([line], delimiter=delimiter, quotechar='"'))


def _column(path, cell: str, index: int) -> tuple[str, bool, float]:
    """(lane name, is time, factor to SI) of one header cell."""
    text = cell.strip()
    if not text:
        raise error(path, f"column {index + 1} of the header has no name")
    if _NUMBER.match(text):
        raise error(path, f"the first line that is not a comment looks like data ({text!r}), not a header; "
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
            raise error(path, f"the time column {text!r} has no unit; write it in the header: "
                              f"'{name} [s]', '{name} [ms]' or '{name} [us]'")
        if unit not in TIME_UNITS:
            raise error(path, f"column {text!r}: time unit {unit!r} is not allowed (allowed: s, ms, us)")
        return name, True, TIME_UNITS[unit]
    if unit is not None and unit not in FORCE_UNITS:
        raise error(path, f"column {text!r}: force unit {unit!r} is not allowed (allowed: N, kN, mN; "
                          f"a column without a unit is read as N)")
    return name, False, FORCE_UNITS[unit] if unit is not None else 1.0


def _decode(path, data: bytes, offset: int) -> str:
    """``data`` (which starts at byte ``offset`` of the file) as text; refused unless UTF-8."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(path, f"not UTF-8 text (undecodable byte at offset {offset + exc.start}), "
                          f"not a CSV file") from None


def _header_line(path: Path) -> tuple[str, int, int]:
    """(header line, byte offset of the next line, its line number): the first line that is neither
    blank nor a ``#`` comment, after an optional byte-order mark."""
    with open_file(path) as handle:
        data = read_some(handle, path, max(BLOCK_BYTES, len(_BOM)))
        base = 0  # file offset of data[0]
        position = len(_BOM) if data.startswith(_BOM) else 0
        number = 1
        blank = True
        while True:
            end = data.find(b"\n", position)
            if end < 0:
                more = read_some(handle, path, BLOCK_BYTES)
                if more:
                    data, base, position = data[position:] + more, base + position, 0
                    continue
                end = len(data)
            raw = data[position:end]
            if b"\x00" in raw:
                raise error(path, "binary content (NUL bytes), not CSV text")
            line = _decode(path, raw, base + position).rstrip("\r")
            if not _SKIPPED.fullmatch(line):
                return line, base + end + 1, number + 1
            blank = blank and not raw.strip()
            if end >= len(data):
                raise error(path, "empty file" if blank else "empty file (only comments and blank lines)")
            position, number = end + 1, number + 1


def _layout(path: Path, rate, column) -> _Layout:
    line, body_offset, body_line = _header_line(path)
    delimiter = next((d for d in (",", "\t", ";") if d in line), None)
    cells = _split(line, delimiter)
    columns = [_column(path, cell, i) for i, cell in enumerate(cells)]
    times = [i for i, (_, is_time, _) in enumerate(columns) if is_time]
    if len(times) > 1:
        raise error(path, f"more than one time column ({', '.join(repr(cells[i].strip()) for i in times)})")
    force = [i for i, (_, is_time, _) in enumerate(columns) if not is_time]
    if not force:
        raise error(path, "no force column (only a time column)")
    names = [columns[i][0] for i in force]
    duplicated = sorted({name for name in names if names.count(name) > 1})
    if duplicated:
        raise error(path, f"duplicate column names {', '.join(map(repr, duplicated))}")
    if column is not None:
        by_header = {cells[i].strip(): columns[i][0] for i in force}
        if column in by_header:
            column = by_header[column]
        elif times and column in (cells[times[0]].strip(), columns[times[0]][0]):
            raise error(path, f"column {column!r} is the time column; choose a force column "
                              f"(available: {', '.join(map(repr, names))})", "column")
    selected = select(path, names, column)
    lanes = [force[names.index(name)] for name in selected]
    if not times and rate is None:
        raise error(path, "rate is required: the file has no time column (time [s], time [ms], time [us])", "rate")
    return _Layout(header=tuple(cells), delimiter=delimiter, used=tuple(times[:1] + lanes),
                   time_factor=columns[times[0]][2] if times else None,
                   factors=tuple(columns[i][2] for i in lanes), names=tuple(selected),
                   body_offset=body_offset, body_line=body_line)


# --------------------------------------------------------------------------- rows, block by block

def _rows(path: Path, layout: _Layout):
    """(values: rows × used columns, line number of each row, index of the first row) of every block
    of data rows, in order (blocks without data rows are skipped)."""
    with open_file(path) as handle:
        handle.seek(layout.body_offset)
        offset, line, row0, carry = layout.body_offset, layout.body_line, 0, b""
        while True:
            data = read_some(handle, path, BLOCK_BYTES)
            if data:
                data = carry + data if carry else data
                cut = data.rfind(b"\n") + 1
                if cut == 0:
                    carry = data
                    continue
                block, carry = data[:cut], data[cut:]
            elif carry:
                block, carry = carry, b""
            else:
                return
            values, numbers, newlines = _block_values(path, block, offset, line, row0, layout)
            offset += len(block)
            line += newlines
            if values.shape[0]:
                yield values, numbers, row0
                row0 += values.shape[0]


#: Bytes that make a line a blank line or the start of one (the lines are then filtered one by one); built on
#: first use, so that importing the reader (``analyze`` answering a missing file) does not load NumPy.
_BLANK_BYTES = b" \t\r\n"
_BLANK_TABLE: list = []


def _blank_start():
    if not _BLANK_TABLE:
        table = np.zeros(256, dtype=bool)
        table[list(_BLANK_BYTES)] = True
        _BLANK_TABLE.append(table)
    return _BLANK_TABLE[0]


def _block_values(path, block: bytes, offset: int, first_line: int, row0: int, layout: _Layout):
    """(the used columns of the data rows, the line number of each, the count of line ends) of
    ``block``: whole lines from byte ``offset`` and line ``first_line`` of the file, its first data
    row being row ``row0`` of the file."""
    if b"\x00" in block:
        raise error(path, "binary content (NUL bytes), not CSV text")
    if not block.isascii():
        _decode(path, block, offset)
    raw = np.frombuffer(block, dtype=np.uint8)
    ends = np.flatnonzero(raw == 10)
    tail = block[-64:].rstrip()
    end = len(block) - min(len(block), 64) + len(tail) if tail else len(block.rstrip())  # trailing blanks cut
    if end == 0:
        return np.empty((0, len(layout.used))), np.empty(0, dtype=np.int64), ends.size
    inner = ends[:np.searchsorted(ends, end)]  # the line ends before the last line
    rows = inner.size + 1
    lines = numbers = None
    clean = memoryview(block)[:end]
    # a comment or blank line may be anywhere: then the lines are filtered one by one
    blank_start = _blank_start()
    if block.find(b"#", 0, end) >= 0 or blank_start[raw[0]] or blank_start[raw[inner + 1]].any():
        lines = [line.rstrip("\r") for line in block[:end].decode("utf-8").split("\n")]
        keep = [i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
        numbers = first_line + np.array(keep, dtype=np.int64)
        lines = [lines[i] for i in keep]
        if not lines:
            return np.empty((0, len(layout.used))), numbers, ends.size
        clean = "\n".join(lines).encode("utf-8")
        rows = len(lines)
    ncols = len(layout.header)
    values = _fast_values(clean, rows, ncols, layout.delimiter, layout.used)
    if values is None:
        # find the first bad row sub-block by sub-block: Arrow on each, Python only on a failing one
        if lines is None:
            lines = [line.rstrip("\r") for line in block[:end].decode("utf-8").split("\n")]
            numbers = np.arange(first_line, first_line + len(lines), dtype=np.int64)
        parts = []
        for begin in range(0, len(lines), _SUB_BLOCK):
            part_lines = lines[begin:begin + _SUB_BLOCK]
            part = _fast_values("\n".join(part_lines).encode("utf-8"), len(part_lines), ncols, layout.delimiter,
                                layout.used)
            if part is None:
                part = _slow_values(path, part_lines, numbers[begin:begin + _SUB_BLOCK], row0 + begin, layout)
            parts.append(part)
        values = np.concatenate(parts)
    if numbers is None:
        numbers = np.arange(first_line, first_line + values.shape[0], dtype=np.int64)
    return values, numbers, ends.size


def _fast_values(clean, rows: int, ncols: int, delimiter, used) -> np.ndarray | None:
    """The used columns of the ``rows`` lines of ``clean`` parsed by Arrow's CSV reader, or None when
    any row needs a closer look (a parse error, an empty, NaN or infinite cell): the slow reader then
    says where."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    from fruitimpact.impact.inputs import arrow_floats

    names = [f"c{i}" for i in range(ncols)]
    wanted = [names[i] for i in used]
    try:
        table = pacsv.read_csv(
            pa.BufferReader(clean),
            read_options=pacsv.ReadOptions(column_names=names),
            parse_options=pacsv.ParseOptions(delimiter=delimiter or "\x1f", quote_char='"',
                                             newlines_in_values=False, ignore_empty_lines=True),
            convert_options=pacsv.ConvertOptions(column_types={name: pa.float64() for name in wanted},
                                                 include_columns=wanted))
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError):
        return None
    if table.num_rows != rows:
        return None
    out = np.empty((table.num_rows, len(wanted)))
    for k, name in enumerate(wanted):
        array = table.column(name)
        if array.null_count:
            return None
        out[:, k] = arrow_floats(array)  # not Arrow's to_numpy: it imports pandas (0.3 s, in a usage error too)
    if not np.isfinite(out).all():
        return None
    return out


def _slow_values(path, lines, numbers, first_row: int, layout: _Layout) -> np.ndarray:
    """Row by row: the first ragged row or bad cell is refused with its line and column."""
    ncols, header = len(layout.header), layout.header
    out = np.empty((len(lines), len(layout.used)))
    for row, (line, number) in enumerate(zip(lines, numbers, strict=True), start=first_row):
        cells = _split(line, layout.delimiter)
        if len(cells) != ncols:
            raise error(path, f"line {number} has {len(cells)} cells, the header {ncols} (ragged row)")
        for k, index in enumerate(layout.used):
            cell = cells[index].strip()
            where = f"line {number} (data row {row + 1}), column {header[index].strip()!r}"
            if not cell:
                raise error(path, f"{where}: empty cell; every cell must be a number")
            if not _NUMBER.match(cell):
                raise error(path, f"{where}: {cell!r} is not a number (NaN and infinities are not allowed)")
            value = float(cell)
            if not math.isfinite(value):
                raise error(path, f"{where}: {cell!r} is beyond double precision")
            out[row - first_row, k] = value
    return out


# --------------------------------------------------------------------------- the time column

class _Clock:
    """Checks a time column [s] block by block, across block boundaries: strictly increasing, and every
    interval within ``RATE_TOLERANCE`` of ``interval`` [s] (plus rounding of times as large as these)."""

    def __init__(self, path, first: float, interval: float):
        self.path, self.first, self.interval = path, first, interval
        self.previous: float | None = None  # the last time checked

    def check(self, t: np.ndarray, numbers: np.ndarray, row0: int, uniform: bool = True) -> None:
        """``t``: the times [s] of rows ``row0``… (line numbers ``numbers``), following those checked."""
        later = 1 if self.previous is None else 0  # index in t of the later row of step 0
        times = t if self.previous is None else np.concatenate(([self.previous], t))
        steps = np.diff(times)
        bad = np.flatnonzero(~(steps > 0.0))
        if bad.size:
            i = int(bad[0])
            raise error(self.path, f"non-monotonic time at row {row0 + i + later + 1} (line {numbers[i + later]}): "
                                   f"{float(times[i + 1])!r} s after {float(times[i])!r} s; time must increase "
                                   f"strictly")
        if uniform:
            # a sample missing (or doubled) is a step far from the others: said where it is, before the small
            # deviations it causes everywhere once it is in the mean interval (it was reported at row 2)
            gross = np.flatnonzero(np.abs(steps - self.interval) > 0.5 * self.interval)
            if gross.size:
                i = int(gross[0])
                raise error(self.path, f"non-uniform sampling at row {row0 + i + later + 1} (line "
                                       f"{numbers[i + later]}): interval {steps[i]:.9g} s where the others are "
                                       f"about {self.interval:.9g} s (a sample missing or repeated?)")
            slack = RATE_TOLERANCE * self.interval + 8.0 * np.finfo(float).eps * max(abs(self.first),
                                                                                      abs(float(times[-1])))
            bad = np.flatnonzero(np.abs(steps - self.interval) > slack)
            if bad.size:
                i = int(bad[0])
                raise error(self.path, f"non-uniform sampling at row {row0 + i + later + 1} (line "
                                       f"{numbers[i + later]}): interval {steps[i]:.9g} s, mean interval "
                                       f"{self.interval:.9g} s (allowed: {RATE_TOLERANCE:g} relative; write the "
                                       f"times with more digits, or drop the time column and give --rate)")
        self.previous = float(t[-1])


# --------------------------------------------------------------------------- opening

def open_csv(path: Path, rate, column) -> RecordingSource:
    """Check the header, the column and the rate, and read the first ``RATE_ROWS`` rows (the rate
    and the start time come from their times)."""
    layout = _layout(path, rate, column)
    seen, rows, ended = [], 0, True
    blocks = _rows(path, layout)
    for item in blocks:
        seen.append(item)
        rows += item[0].shape[0]
        if rows >= RATE_ROWS:
            ended = False
            break
    blocks.close()
    if rows == 0:
        raise error(path, "all lanes empty: the file has a header but no data rows")
    start_time, clock = 0.0, None
    if layout.time_factor is not None:
        t = np.concatenate([values[:, 0] for values, _, _ in seen])[:RATE_ROWS] * layout.time_factor
        start_time = float(t[0])
        if t.size == 1:
            rate = need_rate(path, rate, "one sample cannot give the rate")
        else:
            span = float(t[-1] - t[0])
            clock = (start_time, span / (t.size - 1))
            check = _Clock(path, *clock)
            if not span > 0.0:  # a step back among these rows: refuse it, not the intervals around it
                for values, numbers, row0 in seen:
                    check.check(values[:, 0] * layout.time_factor, numbers, row0, uniform=False)
            check = _Clock(path, *clock)
            for values, numbers, row0 in seen:
                check.check(values[:, 0] * layout.time_factor, numbers, row0)
            rate = agree(path, (t.size - 1) / span, rate, "the time column")

    def forces(hint: int):
        check = None if clock is None else _Clock(path, *clock)
        offset = 0 if layout.time_factor is None else 1
        for values, numbers, row0 in _rows(path, layout):
            if check is not None:
                check.check(values[:, 0] * layout.time_factor, numbers, row0)
            out = np.empty((values.shape[0], len(layout.names)))
            for k, factor in enumerate(layout.factors):
                np.multiply(values[:, k + offset], factor, out=out[:, k])
            yield out

    return RecordingSource(source=str(path), format="csv", rate=rate, lane_names=layout.names, start_time=start_time,
                           samples=rows if ended else None, _blocks=forces)


__all__ = ["BLOCK_BYTES", "RATE_ROWS", "open_csv"]
