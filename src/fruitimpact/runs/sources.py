"""Sources of input rows: table files (CSV, Parquet), grids of a sweep, populations.

A source knows its ``rows`` (None for a CSV file until read), its ``identity``
(what determines the rows, for the job's fingerprint), the ``payloads`` the
driver reads chunk by chunk, and the ``inputs`` a chunk's task hands to
``impact.evaluation.evaluate``.

Table files are read with pyarrow, streamed block by block: only empty cells
are null ("not given"); a NaN, in any spelling, is a given value (refused by
``evaluate``); text stays text.  A ragged CSV row (more or fewer fields than
the header) keeps its place and row number and becomes an invalid row whose
message names its field count; its cells are not read.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fruitimpact.impact.outputs import TABLE_FORMATS
from fruitimpact.impact.quantities import INPUTS
from fruitimpact.impact.units import parse_quantity
from fruitimpact.runs.plan import MAX_AXIS_VALUES, check_count

#: Bytes of a CSV file parsed at a time.
CSV_BLOCK_BYTES = 8 << 20
#: Bytes of a CSV file's start sampled to estimate its row count.
_ESTIMATE_BYTES = 1 << 20


def table_format(path, option: str = "file") -> str:
    """'csv' or 'parquet' from the extension of ``path``; ``ValueError`` otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in TABLE_FORMATS:
        raise ValueError(f"{option} {str(path)!r} must end in .csv or .parquet")
    return TABLE_FORMATS[suffix]


def file_digest(path) -> str:
    """SHA-256 of the file at ``path``, read in blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


def _column_names(path, fmt: str) -> tuple:
    """The column names of a table file, read from its header (CSV) or schema (Parquet)."""
    if fmt == "csv":
        import pyarrow.csv as pacsv

        reader = pacsv.open_csv(path, read_options=pacsv.ReadOptions(block_size=_ESTIMATE_BYTES),
                                parse_options=pacsv.ParseOptions(invalid_row_handler=lambda row: "skip"))
        return tuple(reader.schema.names)
    import pyarrow.parquet as pq

    return tuple(pq.ParquetFile(path).schema_arrow.names)


def _estimate_csv_rows(path, size: int) -> int:
    """Data rows of a CSV file estimated from the line lengths of its first megabyte."""
    with open(path, "rb") as handle:
        head = handle.read(_ESTIMATE_BYTES)
    lines = head.count(b"\n") + (not head.endswith(b"\n") and bool(head))
    if len(head) >= size:
        return max(lines - 1, 0)
    return max(int(size * lines / len(head)) - 1, 0)


def numeric_fast_path(column):
    """A column of plain numbers as float64 (nulls kept), else the column unchanged.

    Text cells with units (``115g``) are left to ``impact.evaluation.evaluate``, which parses
    them cell by cell; columns of plain numbers, the common case, are converted
    here in one vectorised cast."""
    import pyarrow as pa
    import pyarrow.compute as pc

    if not (pa.types.is_string(column.type) or pa.types.is_large_string(column.type)):
        return column
    try:
        return pc.cast(pc.utf8_trim_whitespace(column), pa.float64())
    except pa.ArrowInvalid:
        return column


def _with_keys(table):
    """``table`` with its columns named by input (``drop-height`` → ``drop_height``) and plain
    numeric columns as float64."""
    from fruitimpact.impact.inputs import column_key

    import pyarrow as pa

    import pyarrow.compute as pc

    names = [column_key(name) for name in table.column_names]
    columns = []
    for name, column in zip(names, table.columns):
        if INPUTS[name].choices is not None:  # a name; a Parquet column of numbers (model = 1) is read as text
            columns.append(column if pa.types.is_string(column.type) else pc.cast(column, pa.string()))
        else:
            columns.append(numeric_fast_path(column))
    return pa.Table.from_arrays(columns, names=names)


def _stamp(path) -> tuple:
    """What any write to a file changes: size, modification and change times [ns], inode."""
    info = Path(path).stat()
    return info.st_size, info.st_mtime_ns, info.st_ctime_ns, info.st_ino


@dataclass(frozen=True)
class TableSource:
    """Rows of a CSV or Parquet file, columns named like ``simulate``'s options.

    The file is read chunk by chunk in the driving process; each chunk's rows
    (a pyarrow Table, and the per-row messages of ragged rows) travel to the
    task that evaluates them."""

    path: str
    format: str
    columns: tuple
    digest: str
    size: int
    rows: int | None = None  # known for Parquet, counted while reading for CSV
    estimated_rows: int = 0
    stamp: tuple = ()  # (size, mtime_ns, ctime_ns, inode) taken before the file was hashed

    @classmethod
    def open(cls, path) -> "TableSource":
        """Check the file and its columns (unknown ones refused) before any work; ``ValueError``."""
        from fruitimpact.impact.inputs import check_columns

        fmt = table_format(path, "input")
        if not Path(path).is_file():
            raise ValueError(f"input {str(path)!r}: no such file")
        try:
            columns = _column_names(path, fmt)
        except (OSError, ValueError) as exc:  # pyarrow's ArrowInvalid is a ValueError
            kind = "CSV" if fmt == "csv" else "Parquet"
            raise ValueError(f"input {str(path)!r}: cannot read as {kind} ({str(exc).splitlines()[0]})") from None
        try:
            check_columns(columns)
        except ValueError as exc:
            raise ValueError(f"input {str(path)!r}: {exc}") from None
        if fmt == "parquet":  # cells are numbers or text: a list or a record cannot be an input
            import pyarrow as pa
            import pyarrow.parquet as pq

            for field in pq.ParquetFile(path).schema_arrow:
                plain = (pa.types.is_integer(field.type) or pa.types.is_floating(field.type)
                         or pa.types.is_string(field.type) or pa.types.is_large_string(field.type)
                         or pa.types.is_boolean(field.type) or pa.types.is_null(field.type)
                         or pa.types.is_dictionary(field.type))
                if not plain:
                    raise ValueError(f"input {str(path)!r}: column {field.name!r} holds {field.type} values; an "
                                     f"input column holds numbers or text")
        stamp = _stamp(path)
        size = stamp[0]
        if fmt == "csv":
            rows, estimated = None, _estimate_csv_rows(path, size)
        else:
            import pyarrow.parquet as pq

            rows = pq.ParquetFile(path).metadata.num_rows
            estimated = rows
        return cls(str(Path(path).resolve()), fmt, columns, file_digest(path), size, rows, estimated, stamp)

    def identity(self) -> dict:
        return {"table": self.path, "sha256": self.digest, "bytes": self.size}

    def changed(self) -> bool:
        """Whether the file now differs from what ``open`` hashed: unchanged if its size, times
        and inode are those seen before hashing (any write changes them), else hashed again."""
        try:
            if _stamp(self.path) == self.stamp:
                return False
            return file_digest(self.path) != self.digest
        except OSError:
            return True

    def payloads(self, chunk_rows: int):
        """(index, (table, errors)) per chunk of exactly ``chunk_rows`` rows but the last; ``errors``
        is None or a message per row (ragged rows).  A file without rows gives one empty chunk,
        so that the output still gets its columns."""
        import pyarrow as pa

        count = 0
        pieces = self._csv_pieces() if self.format == "csv" else self._parquet_pieces()
        schema = pa.schema([(name, pa.string()) for name in self.columns])  # a CSV file's, all text
        for index, (table, errors) in enumerate(_cut(pieces, chunk_rows, schema)):
            count += 1
            yield index, (_with_keys(table), errors)
        if count == 0:
            empty = pa.table({name: pa.array([], type=pa.string()) for name in self.columns})
            yield 0, (_with_keys(empty), None)

    def inputs(self, start: int, stop: int, payload):
        """(rows, errors) of a chunk: the payload itself, read by the driver."""
        return payload

    def _parquet_pieces(self):
        import pyarrow as pa
        import pyarrow.parquet as pq

        for batch in pq.ParquetFile(self.path).iter_batches(batch_size=1 << 16):
            yield pa.Table.from_batches([batch]), None

    def _csv_pieces(self):
        """(table, None) runs of well-formed rows and (None, message) for each bad row, in file order: a ragged
        row (its field count), or a row with a cell that is not UTF-8 text (its cells are not read)."""
        import pyarrow as pa
        import pyarrow.csv as pacsv

        ragged = []  # (data row index, message), in file order

        def skip(row):
            # row.number counts parsed rows from 1, the header included (known without threads)
            ragged.append((row.number - 2, f"row has {row.actual_columns} fields; the header has "
                                           f"{row.expected_columns} (row skipped, its cells not read)"))
            return "skip"

        # cells are read as bytes and checked as UTF-8 batch by batch: one undecodable cell makes its row invalid
        # instead of stopping the file (pyarrow's own string conversion refuses the whole file at that cell)
        reader = pacsv.open_csv(
            self.path,
            read_options=pacsv.ReadOptions(use_threads=False, block_size=CSV_BLOCK_BYTES),
            parse_options=pacsv.ParseOptions(newlines_in_values=True, invalid_row_handler=skip),
            convert_options=pacsv.ConvertOptions(column_types={name: pa.binary() for name in self.columns},
                                                 null_values=[""], strings_can_be_null=True))
        position = 0
        for batch in reader:
            text, undecodable = _as_text(batch)
            taken = 0
            while taken < batch.num_rows:
                if ragged and ragged[0][0] == position:  # a ragged row is not in the batch: it keeps its place
                    yield None, ragged.pop(0)[1]
                    position += 1
                    continue
                if taken in undecodable:
                    yield None, (f"row has a cell that is not UTF-8 text (column {undecodable[taken]!r}); its cells "
                                 f"not read")
                    taken += 1
                    position += 1
                    continue
                run = batch.num_rows - taken
                if ragged:
                    run = min(run, ragged[0][0] - position)
                later = [row for row in undecodable if row > taken]
                if later:
                    run = min(run, min(later) - taken)
                yield text.slice(taken, run), None
                taken += run
                position += run
        for _, message in ragged:
            yield None, message


def _as_text(batch):
    """(table of text columns, {row: column} of the rows with a cell that is not UTF-8) of a batch read as bytes;
    such a row's cells become null (the row is refused with a message, never read)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    columns, undecodable = [], {}
    for name, column in zip(batch.schema.names, batch.columns):
        try:
            columns.append(pc.cast(column, pa.string()))
            continue
        except pa.ArrowInvalid:
            pass
        cells = column.to_pylist()
        for row, cell in enumerate(cells):
            try:
                cells[row] = None if cell is None else cell.decode("utf-8")
            except UnicodeDecodeError:
                cells[row] = None
                undecodable.setdefault(row, name)
        columns.append(pa.array(cells, type=pa.string()))
    if undecodable:  # every cell of such a row is withheld, not only the bad one
        keep = pa.array([row not in undecodable for row in range(batch.num_rows)])
        columns = [pc.if_else(keep, column, pa.nulls(batch.num_rows, pa.string())) for column in columns]
    return pa.Table.from_arrays(columns, names=batch.schema.names), undecodable


def _cut(pieces, chunk_rows: int, schema):
    """Regroup (table, None) / (None, message) pieces into (table, errors) chunks of ``chunk_rows``
    rows; a ragged row becomes a row of nulls of ``schema``."""
    import pyarrow as pa

    parts, messages, have = [], [], 0

    def chunk():
        tables = [t if t is not None else _null_row(schema) for t in parts]
        errors = messages if any(messages) else None
        return pa.concat_tables(tables), errors

    for table, message in pieces:
        while table is not None and have + table.num_rows > chunk_rows:
            head = chunk_rows - have
            parts.append(table.slice(0, head))
            messages.extend([None] * head)
            yield chunk()
            parts, messages, have = [], [], 0
            table = table.slice(head)
        if table is None:
            parts.append(None)
            messages.append(message)
            have += 1
        elif table.num_rows:
            parts.append(table)
            messages.extend([None] * table.num_rows)
            have += table.num_rows
        if have == chunk_rows:
            yield chunk()
            parts, messages, have = [], [], 0
    if have:
        yield chunk()


def _null_row(schema):
    """One row of nulls with ``schema`` (a ragged row's place)."""
    import pyarrow as pa

    return pa.table({field.name: pa.nulls(1, type=field.type) for field in schema}, schema=schema)


def known_order() -> list[str]:
    """The input columns a table may have, in the table of quantities' order."""
    return list(INPUTS)


@dataclass(frozen=True)
class Axis:
    """One swept input: its name and values ([SI] numbers, or text such as model names)."""

    name: str
    values: tuple
    log: bool = False

    @property
    def numeric(self) -> bool:
        return not isinstance(self.values[0], str)


def _axis_count(text: str) -> int:
    """The COUNT of a range: an integer in [1, MAX_AXIS_VALUES]; ``ValueError`` otherwise."""
    try:
        count = int(text.strip())
    except ValueError:
        count = 0
    if count < 1 or str(count) != text.strip():
        raise ValueError(f"the COUNT of START:STOP:COUNT must be an integer in [1, {MAX_AXIS_VALUES:,}]; "
                         f"got {text!r}")
    return check_count("the COUNT of START:STOP:COUNT", count, 1, MAX_AXIS_VALUES)


def parse_axis(name: str, text: str) -> Axis:
    """A sweep spec for input ``name``: ``START:STOP:COUNT`` (inclusive, linear),
    ``log:START:STOP:COUNT`` (geometric), ``V1,V2,...`` or one value; units allowed.
    At most ``MAX_AXIS_VALUES`` values; ``ValueError`` otherwise."""
    quantity = INPUTS[name]
    if not quantity.numeric:
        values = tuple(v.strip() for v in text.split(",") if v.strip())
        if not values:
            raise ValueError(f"give one or more values; got {text!r}")
        return Axis(name, values)
    body, log = (text[4:], True) if text.lower().startswith("log:") else (text, False)
    if ":" in body:
        parts = body.split(":")
        if len(parts) != 3:
            raise ValueError(f"a range is START:STOP:COUNT, e.g. 0.3:1.5:25 or log:1:100:21; got {text!r}")
        start, stop = (parse_quantity(p, quantity.dimension) for p in parts[:2])
        count = _axis_count(parts[2])
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
    items = body.split(",")
    check_count("the number of values", len(items), 1, MAX_AXIS_VALUES)
    values = tuple(parse_quantity(v, quantity.dimension) for v in items)
    if any(math.isnan(v) for v in values):  # a NaN is never a value to sweep over (a single one is refused too)
        raise ValueError(f"each value must be a number, not NaN; got {text!r}")
    return Axis(name, values)


@dataclass(frozen=True)
class GridSource:
    """The Cartesian product of ``axes`` (first axis slowest, as nested loops), row = flat index."""

    axes: tuple  # of Axis (each with at least one value)

    @property
    def shape(self) -> tuple:
        return tuple(len(a.values) for a in self.axes)

    @property
    def rows(self) -> int:
        return math.prod(self.shape)

    def identity(self) -> dict:
        return {"grid": [[a.name, list(a.values)] for a in self.axes]}

    def payloads(self, chunk_rows: int):
        for index in range(-(-self.rows // chunk_rows)):
            yield index, None

    def changed(self) -> bool:
        return False

    def inputs(self, start: int, stop: int, payload) -> tuple:
        """(columns, None): the grid points start..stop-1."""
        where = np.unravel_index(np.arange(start, stop), self.shape)
        return {axis.name: np.asarray(axis.values, dtype=object if not axis.numeric else float)[i]
                for axis, i in zip(self.axes, where)}, None


