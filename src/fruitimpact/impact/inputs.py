"""Reading a table of impact inputs: any container of columns → SI arrays.

``read_columns`` accepts a pandas DataFrame, a mapping of column name to
values (lists, NumPy arrays, pandas Series, pyarrow arrays; a scalar is
repeated on every row) or a pyarrow Table.  For every input of the table of
quantities it returns a float64 array [SI] and a mask of the cells that were
*given*; text inputs come back as object arrays with the default filled in.

What counts as given (the rule of the whole package):

* not given, so the default applies: a column that is absent, ``None``,
  ``pd.NA``, an Arrow null (an empty CSV cell read by pyarrow), an empty or
  blank string;
* given: any number, including NaN and ±inf, and any other string.  A NaN
  is refused with a message, never taken for "use the default"; a string
  that is not a number with a known unit is refused with a message.

Unknown column names are refused as a whole, before any work
(``check_columns``): a misspelt ``velocty`` would otherwise silently leave
the default velocity in place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fruitimpact.impact.labels import Labels, factorize
from fruitimpact.impact.quantities import INPUTS, NUMERIC_INPUTS, TEXT_INPUTS
from fruitimpact.impact.units import parse_quantity
from fruitimpact.impact.validation import MessageBook, nan_message, unreadable_message


def column_key(name) -> str:
    """The input a column name means: ``drop-height`` and ``drop_height`` are the same."""
    return str(name).strip().replace("-", "_")


def unknown_columns_message(unknown) -> str:
    return (f"unknown column(s) {', '.join(map(repr, unknown))} (columns: {', '.join(INPUTS)}; "
            f"keep other data in your own table and join the results on their row order)")


def check_columns(names) -> dict[str, object]:
    """Map each column name to its input; ``ValueError`` naming every unknown or repeated one."""
    keys, unknown, seen = {}, [], set()
    for name in names:
        key = column_key(name)
        if key not in INPUTS:
            unknown.append(name)
        elif key in seen:
            raise ValueError(f"column {key!r} is given twice")
        else:
            seen.add(key)
            keys[name] = key
    if unknown:
        raise ValueError(unknown_columns_message(unknown))
    return keys


@dataclass
class InputColumns:
    """Inputs of ``rows`` impacts: ``values[name]`` float64 [SI] (NaN where not given or
    unreadable), ``given[name]`` bool, ``text[name]`` ``Labels`` (defaults filled in).
    ``evaluation`` writes each input's default into its own row where it was not given (the
    inputs as used, without a fresh column each): read ``values`` where ``given`` only.

    The numeric inputs are rows of one matrix, ``matrix`` (inputs × rows, in the order of
    ``quantities.NUMERIC_INPUTS``) with ``given_matrix`` beside it: the range checks of
    every input are then a few whole-matrix operations, whatever the number of rows."""

    rows: int
    values: dict
    given: dict
    text: dict
    matrix: np.ndarray
    given_matrix: np.ndarray

    def given_inputs(self) -> list[int]:
        """Indices (in ``NUMERIC_INPUTS``) of the inputs given on at least one row."""
        return np.flatnonzero(self.given_matrix.any(axis=1)).tolist()


def _as_columns(table) -> dict:
    """Name → column of any supported container (pyarrow Table, DataFrame, mapping)."""
    if _is_arrow(table):
        return {name: table.column(name) for name in table.column_names}
    if hasattr(table, "columns") and hasattr(table, "__getitem__") and not isinstance(table, dict):
        return {name: table[name] for name in table.columns}  # a DataFrame
    if not hasattr(table, "items"):
        raise ValueError(f"inputs must be a DataFrame, a mapping of column name to values or a pyarrow "
                         f"Table; got {type(table).__name__}")
    return dict(table.items())


def _length(column) -> int | None:
    """Rows of a column; None for a scalar (repeated on every row)."""
    if isinstance(column, (str, bytes)):
        return None
    if isinstance(column, np.ndarray):
        return None if column.ndim == 0 else len(column)
    return len(column) if hasattr(column, "__len__") else None


def _is_arrow(column) -> bool:
    """A pyarrow array or chunked array (checked without importing pyarrow)."""
    return type(column).__module__.startswith("pyarrow")


def _blank(strings: np.ndarray) -> np.ndarray:
    return np.array([isinstance(s, str) and not s.strip() for s in strings], dtype=bool)


def _object_cells(column) -> tuple[np.ndarray, np.ndarray]:
    """(cells as an object array, not-given mask) of a column of any container."""
    if _is_arrow(column):
        missing = column.is_null().to_numpy(zero_copy_only=False)
        cells = np.asarray(column.to_numpy(zero_copy_only=False), dtype=object)
        return cells, np.asarray(missing, dtype=bool)
    if hasattr(column, "dtype") and hasattr(column, "isna") and not isinstance(column, np.ndarray):
        import pandas as pd

        series = column
        cells = series.to_numpy(dtype=object, na_value=None) if not isinstance(series.dtype, np.dtype) \
            else series.to_numpy(dtype=object)
        missing = np.array([c is None or c is pd.NA for c in cells], dtype=bool)
        return cells, missing
    cells = np.empty(len(column), dtype=object)
    cells[:] = list(column)
    missing = np.array([c is None or _is_pd_na(c) for c in cells], dtype=bool)
    return cells, missing


def _is_pd_na(cell) -> bool:
    return type(cell).__name__ == "NAType"


def arrow_floats(column) -> np.ndarray:
    """A pyarrow Array or ChunkedArray of numbers without nulls as float64 [as stored], from its buffers: Arrow's
    own ``to_numpy`` imports pandas (0.3 s, also in a refusal, and an import a Ctrl-C can interrupt)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    column = pc.cast(column, pa.float64())
    chunks = column.chunks if isinstance(column, pa.ChunkedArray) else [column]
    if not chunks:
        return np.empty(0)
    return np.concatenate([np.frombuffer(chunk.buffers()[1], dtype=np.float64, count=len(chunk),
                                         offset=chunk.offset * 8) for chunk in chunks])


def _fast_float(column, rows: int):
    """(values, given) without looking at cells, for purely numeric columns; None otherwise."""
    if isinstance(column, list):
        if all(type(c) is float or type(c) is int for c in column):
            try:
                return np.asarray(column, dtype=float), np.ones(rows, dtype=bool)
            except OverflowError:  # an integer beyond a float: cell by cell, refused on its row
                return None
        return None
    if _is_arrow(column):
        import pyarrow as pa

        if pa.types.is_floating(column.type) or pa.types.is_integer(column.type):
            given = ~np.asarray(column.is_null().to_numpy(zero_copy_only=False), dtype=bool) \
                if column.null_count else np.ones(rows, dtype=bool)
            values = np.asarray(column.to_numpy(zero_copy_only=False), dtype=float)
            return values, given
        if pa.types.is_null(column.type):
            return np.full(rows, np.nan), np.zeros(rows, dtype=bool)
        return None
    dtype = getattr(column, "dtype", None)
    if isinstance(dtype, np.dtype) and dtype.kind in "fiu":
        return np.asarray(column, dtype=float), np.ones(rows, dtype=bool)
    if dtype is not None and not isinstance(dtype, np.dtype) and getattr(dtype, "kind", "O") in "fiu":
        # a pandas nullable or Arrow-backed numeric column: NA = not given
        missing = np.asarray(column.isna(), dtype=bool)
        values = column.to_numpy(dtype=float, na_value=np.nan)
        if missing.any() and hasattr(column, "array"):
            # pandas keeps NaN and NA apart in nullable columns: NaN cells are given
            values = np.where(missing, np.nan, values)
        return values, ~missing
    if isinstance(column, tuple) and all(type(c) is float or type(c) is int for c in column):
        return np.asarray(column, dtype=float), np.ones(rows, dtype=bool)
    return None


def _numeric(name: str, column, rows: int, messages: MessageBook) -> tuple[np.ndarray, np.ndarray]:
    """(values [SI], given) of numeric input ``name``; unreadable cells and NaNs get a message."""
    quantity = INPUTS[name]
    fast = _fast_float(column, rows)
    if fast is not None:
        values, given = fast
    else:
        cells, missing = _object_cells(column)
        values = np.full(rows, np.nan)
        given = ~missing
        is_str = np.array([isinstance(c, str) for c in cells], dtype=bool)
        blank = np.zeros(rows, dtype=bool)
        if is_str.any():
            blank[is_str] = _blank(cells[is_str])
        given &= ~blank
        numbers = given & ~is_str
        for i in np.flatnonzero(numbers):
            cell = cells[i]
            try:
                values[i] = float(cell) if not isinstance(cell, bool) else np.nan
            except (TypeError, ValueError, OverflowError):
                values[i] = np.nan
                if isinstance(cell, int):  # an integer beyond a float: unreadable, not a NaN given
                    messages.set_row(i, unreadable_message(quantity, cell), name)
                    continue
            if isinstance(cell, bool) or not np.isfinite(values[i]) and not _is_number(cell):
                messages.set_row(i, unreadable_message(quantity, cell), name)
        texts = given & is_str
        if texts.any():
            unique, inverse = np.unique(cells[texts].astype(str), return_inverse=True)
            parsed = np.empty(len(unique))
            bad = np.zeros(len(unique), dtype=bool)
            for j, text in enumerate(unique):
                try:
                    parsed[j] = parse_quantity(text, quantity.dimension)
                except ValueError:
                    parsed[j] = np.nan
                    bad[j] = True
            rows_text = np.flatnonzero(texts)
            values[rows_text] = parsed[inverse]
            for j in np.flatnonzero(bad):
                messages.set(_rows_mask(rows_text[inverse == j], rows), unreadable_message(quantity, str(unique[j])), name)
    return values, given


def _rows_mask(index: np.ndarray, rows: int) -> np.ndarray:
    mask = np.zeros(rows, dtype=bool)
    mask[index] = True
    return mask


def _is_number(cell) -> bool:
    try:
        float(cell)
    except (TypeError, ValueError):
        return False
    return True


def _text(name: str, column, rows: int) -> Labels:
    """Text input ``name`` as ``Labels``, the default where not given (the names are checked
    against their registry later).  Strings are stripped; numbers stay numbers (and are refused)."""
    default = INPUTS[name].default
    labels = None
    if isinstance(column, Labels):  # already coded (a constant of a run, a factorized column)
        labels = column
    elif isinstance(column, list) and len(column) == 1:  # one impact (simulate)
        labels = Labels(np.zeros(1, dtype=np.int32), (column[0],))
    elif _is_arrow(column):
        import pyarrow as pa
        import pyarrow.compute as pc

        if pa.types.is_string(column.type) or pa.types.is_large_string(column.type):
            array = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
            encoded = pc.dictionary_encode(array)
            indices = encoded.indices.fill_null(len(encoded.dictionary))
            labels = Labels(np.asarray(indices.to_numpy(zero_copy_only=False), dtype=np.int32),
                            tuple(encoded.dictionary.to_pylist()) + (None,))
        else:
            labels = factorize(_object_cells(column)[0])
    else:  # None, pd.NA and blanks become labels here, mapped to the default below
        cells = column.to_numpy(dtype=object) if hasattr(column, "to_numpy") else np.asarray(column, dtype=object)
        if cells.ndim != 1:
            cells = _object_cells(column)[0]
        labels = factorize(cells)
    cleaned = []
    for label in labels.labels:
        if label is None or _is_pd_na(label) or isinstance(label, str) and not label.strip():
            cleaned.append(default)
        else:
            cleaned.append(label.strip() if isinstance(label, str) else label)
    if len(set(map(_key, cleaned))) == len(cleaned):
        return Labels(labels.codes, tuple(cleaned))
    merged: dict = {}
    remap = np.empty(len(cleaned), dtype=np.int32)
    for j, label in enumerate(cleaned):
        remap[j] = merged.setdefault(_key(label), len(merged))
    unique = [None] * len(merged)
    for j, label in enumerate(cleaned):
        unique[remap[j]] = label
    return Labels(remap[labels.codes], tuple(unique))


def _key(label):
    return (type(label), repr(label)) if isinstance(label, float) else (type(label), label)


def read_columns(table, messages: MessageBook | None = None, rows: int | None = None) -> tuple[InputColumns, MessageBook]:
    """Read every input of ``table`` (see the module docstring).

    Returns (columns, messages): per-row messages of unreadable cells and NaNs in
    ``messages`` (created if not given).  Raises ``ValueError`` for unknown or
    repeated column names and columns of different lengths, before any work."""
    columns = _as_columns(table)
    keys = check_columns(columns)
    lengths = {key: _length(columns[name]) for name, key in keys.items()}
    sized = {n for n in lengths.values() if n is not None}
    if len(sized) > 1:
        raise ValueError("columns have different lengths: "
                         + ", ".join(f"{k} {n}" for k, n in lengths.items() if n is not None))
    if rows is None:
        rows = sized.pop() if sized else (1 if columns else 0)
    elif sized and sized.pop() != rows:
        raise ValueError("columns have a different length than the table")
    if messages is None:
        messages = MessageBook(rows)
    by_key = {key: columns[name] for name, key in keys.items()}
    for key, length in lengths.items():
        if length is None:  # a scalar: the same on every row
            value = by_key[key]
            by_key[key] = Labels.constant(value, rows) if key in TEXT_INPUTS else [value] * rows
    # filled input by input, not by one np.full of the whole matrix: at 3,000,000 rows that one call faults in
    # 550 MB of fresh memory (0.5-1 s on a VM) during which Python cannot answer a Ctrl-C
    matrix = np.empty((len(NUMERIC_INPUTS), rows))
    given_matrix = np.zeros((len(NUMERIC_INPUTS), rows), dtype=bool)
    values, given, text = {}, {}, {}
    for j, name in enumerate(NUMERIC_INPUTS):
        if name not in by_key:  # a given input's row is written whole below
            matrix[j] = np.nan
        else:
            column = by_key[name]
            plain = isinstance(column, list) and all(type(c) is float or type(c) is int for c in column)
            try:
                if plain:  # plain numbers (one impact from simulate, a list of floats)
                    matrix[j] = column
                    given_matrix[j] = True
            except OverflowError:  # an integer beyond a float: read cell by cell, refused on its row
                plain = False
            if not plain:
                matrix[j], given_matrix[j] = _numeric(name, column, rows, messages)
        values[name], given[name] = matrix[j], given_matrix[j]
    nan = given_matrix & np.isnan(matrix)  # a NaN is a value: refused, never the default
    if nan.any():
        for j in np.flatnonzero(nan.any(axis=1)):
            messages.set(nan[j] & ~messages.flagged, nan_message(INPUTS[NUMERIC_INPUTS[j]]), NUMERIC_INPUTS[j])
    for name in TEXT_INPUTS:
        text[name] = _text(name, by_key[name], rows) if name in by_key else \
            Labels.constant(INPUTS[name].default, rows)
    return InputColumns(rows, values, given, text, matrix, given_matrix), messages


__all__ = ["InputColumns", "check_columns", "column_key", "read_columns", "unknown_columns_message"]
