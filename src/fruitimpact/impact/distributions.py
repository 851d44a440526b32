"""Distributions of impact inputs for Monte Carlo populations.

A spec string names a distribution and its parameters, each parameter a number
with an optional unit of the input's dimension (``fruitimpact.impact.units``)::

    0.115 | 115g                      constant
    normal(mean, sd)                  normal (Gaussian)
    lognormal(median, sigma)          log-normal: ln X ~ N(ln median, sigma²);
                                      median in the input's unit, sigma dimensionless
                                      (the sd of ln X, e.g. 0.1 ≈ 10 % spread)
    uniform(lo, hi)                   uniform on [lo, hi)
    truncnormal(mean, sd, lo, hi)     normal truncated to [lo, hi] (rejection sampling)
    sample(FILE[:COLUMN])             bootstrap (draw with replacement) from a measured
                                      sample: a CSV or Parquet column, cells may carry units

``parse_distribution(text, dimension)`` returns a frozen dataclass with
``draw(rng, size) -> ndarray`` [SI] and ``identity()`` (a JSON-able description
used to recognise a job).  Bad specs raise ``ValueError`` with one line.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fruitimpact.impact.units import parse_quantity

_CALL = re.compile(r"^\s*([A-Za-z_][A-Za-z_0-9]*)\s*\((.*)\)\s*$", re.DOTALL)
#: Below this probability of [lo, hi] under the untruncated normal, truncnormal is refused.
TRUNCNORMAL_MIN_MASS = 1e-3


@dataclass(frozen=True)
class Constant:
    """Every member has the same value [SI]."""

    value: float

    def draw(self, rng, size: int) -> np.ndarray:
        return np.full(size, self.value)

    def identity(self) -> dict:
        return {"constant": self.value}

    def describe(self) -> str:
        return f"{self.value:.6g}"


@dataclass(frozen=True)
class Normal:
    """Normal distribution: ``mean`` and standard deviation ``sd`` [SI]."""

    mean: float
    sd: float
    signature = "normal(mean, sd)"

    def __post_init__(self):
        if not (math.isfinite(self.mean) and math.isfinite(self.sd) and self.sd >= 0):
            raise ValueError("normal(mean, sd) needs finite values and sd >= 0")

    def draw(self, rng, size: int) -> np.ndarray:
        return rng.normal(self.mean, self.sd, size)

    def identity(self) -> dict:
        return {"normal": [self.mean, self.sd]}

    def describe(self) -> str:
        return f"normal(mean={self.mean:.6g}, sd={self.sd:.6g})"


@dataclass(frozen=True)
class LogNormal:
    """Log-normal distribution: ln X ~ N(ln ``median``, ``sigma``²).

    ``median`` [SI] is the median of X (= exp of the mean of ln X); ``sigma``
    [-] is the standard deviation of ln X."""

    median: float
    sigma: float
    signature = "lognormal(median, sigma)"
    dimensionless = (1,)  # sigma has no unit

    def __post_init__(self):
        if not (math.isfinite(self.median) and self.median > 0 and math.isfinite(self.sigma) and self.sigma >= 0):
            raise ValueError("lognormal(median, sigma) needs median > 0 and sigma >= 0 "
                             "(sigma is the sd of ln X, dimensionless)")

    def draw(self, rng, size: int) -> np.ndarray:
        return self.median * np.exp(rng.normal(0.0, self.sigma, size))

    def identity(self) -> dict:
        return {"lognormal": [self.median, self.sigma]}

    def describe(self) -> str:
        return f"lognormal(median={self.median:.6g}, sigma={self.sigma:.6g})"


@dataclass(frozen=True)
class Uniform:
    """Uniform distribution on [``lo``, ``hi``) [SI]."""

    lo: float
    hi: float
    signature = "uniform(lo, hi)"

    def __post_init__(self):
        if not (math.isfinite(self.lo) and math.isfinite(self.hi) and self.lo < self.hi):
            raise ValueError("uniform(lo, hi) needs finite values and lo < hi")

    def draw(self, rng, size: int) -> np.ndarray:
        return rng.uniform(self.lo, self.hi, size)

    def identity(self) -> dict:
        return {"uniform": [self.lo, self.hi]}

    def describe(self) -> str:
        return f"uniform({self.lo:.6g}, {self.hi:.6g})"


def _normal_cdf(x: float) -> float:
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


@dataclass(frozen=True)
class TruncNormal:
    """Normal(``mean``, ``sd``) truncated to [``lo``, ``hi``] [SI].

    Drawn by rejection (draw, keep those inside, redraw the rest), so it is exact
    and reproducible; refused if [lo, hi] holds less than ``TRUNCNORMAL_MIN_MASS``
    of the untruncated distribution."""

    mean: float
    sd: float
    lo: float
    hi: float
    signature = "truncnormal(mean, sd, lo, hi)"

    def __post_init__(self):
        if not all(math.isfinite(v) for v in (self.mean, self.sd, self.lo, self.hi)) or self.sd <= 0 \
                or not self.lo < self.hi:
            raise ValueError("truncnormal(mean, sd, lo, hi) needs finite values, sd > 0 and lo < hi")
        mass = _normal_cdf((self.hi - self.mean) / self.sd) - _normal_cdf((self.lo - self.mean) / self.sd)
        if mass < TRUNCNORMAL_MIN_MASS:
            raise ValueError(f"truncnormal: [lo, hi] holds only {mass:.2g} of normal(mean, sd) "
                             f"(at least {TRUNCNORMAL_MIN_MASS:g} needed)")

    def draw(self, rng, size: int) -> np.ndarray:
        out = rng.normal(self.mean, self.sd, size)
        bad = np.flatnonzero((out < self.lo) | (out > self.hi))
        while bad.size:
            out[bad] = rng.normal(self.mean, self.sd, bad.size)
            bad = bad[(out[bad] < self.lo) | (out[bad] > self.hi)]
        return out

    def identity(self) -> dict:
        return {"truncnormal": [self.mean, self.sd, self.lo, self.hi]}

    def describe(self) -> str:
        return f"truncnormal(mean={self.mean:.6g}, sd={self.sd:.6g}, lo={self.lo:.6g}, hi={self.hi:.6g})"


@dataclass(frozen=True)
class SplitNormal:
    """Two half-normals joined at the ``median`` [SI]: below it |N(0, ``sd_low``)| is subtracted, above it
    |N(0, ``sd_high``)| added, each side with probability ½ and truncated to [``lo``, ``hi``] (by redrawing that
    side), so the median is exactly ``median`` however asymmetric the range.  A library value with its range
    [low, high] read as a ±2 sd band on each side: ``sd_low = (median − lo)/2``, ``sd_high = (hi − median)/2``."""

    median: float
    sd_low: float
    sd_high: float
    lo: float
    hi: float
    signature = "splitnormal(median, sd_low, sd_high, lo, hi)"

    def __post_init__(self):
        values = (self.median, self.sd_low, self.sd_high, self.lo, self.hi)
        if not all(math.isfinite(v) for v in values) or not self.lo <= self.median <= self.hi \
                or self.sd_low < 0 or self.sd_high < 0 or not self.lo < self.hi:
            raise ValueError("splitnormal(median, sd_low, sd_high, lo, hi) needs finite values, sd >= 0 and "
                             "lo <= median <= hi, lo < hi")

    def _side(self, rng, size: int, sd: float, limit: float) -> np.ndarray:
        if sd == 0.0 or size == 0:
            return np.zeros(size)
        out = np.abs(rng.normal(0.0, sd, size))
        bad = np.flatnonzero(out > limit)
        while bad.size:
            out[bad] = np.abs(rng.normal(0.0, sd, bad.size))
            bad = bad[out[bad] > limit]
        return out

    def draw(self, rng, size: int) -> np.ndarray:
        upper = rng.random(size) < 0.5
        out = np.full(size, self.median)
        n_up = int(upper.sum())
        out[upper] += self._side(rng, n_up, self.sd_high, self.hi - self.median)
        out[~upper] -= self._side(rng, size - n_up, self.sd_low, self.median - self.lo)
        return out

    def identity(self) -> dict:
        return {"splitnormal": [self.median, self.sd_low, self.sd_high, self.lo, self.hi]}

    def describe(self) -> str:
        return (f"splitnormal(median={self.median:.6g}, sd below={self.sd_low:.6g}, sd above={self.sd_high:.6g}, "
                f"in [{self.lo:.6g}, {self.hi:.6g}])")


@dataclass(frozen=True)
class Sample:
    """Bootstrap: members drawn with replacement from measured ``values`` [SI]."""

    source: str
    values: np.ndarray = field(repr=False)

    def draw(self, rng, size: int) -> np.ndarray:
        return self.values[rng.integers(0, self.values.size, size)]

    def identity(self) -> dict:
        digest = hashlib.sha256(np.ascontiguousarray(self.values, dtype=float).tobytes()).hexdigest()
        return {"sample": self.source, "n": int(self.values.size), "sha256": digest}

    def describe(self) -> str:
        return f"sample({self.source}, n={self.values.size})"


#: Cells read as "no value" in a sample CSV (pandas' default NA tokens, so that a file reads as it did with
#: pandas): such a fruit was not measured, and it is left out of the sample, never given a value.
_MISSING = frozenset(token.lower() for token in ("", "#N/A", "#N/A N/A", "#NA", "-1.#IND", "-1.#QNAN", "-NaN",
                                                  "1.#IND", "1.#QNAN", "<NA>", "N/A", "NA", "NULL", "NaN", "None"))


def _choose_column(path: str, header, column: str | None, default_column: str | None) -> str:
    header = list(header)
    named = [name for name in header if str(name).strip()]  # an unnamed (empty) column is no candidate
    if column is None:
        if default_column is not None and default_column in header:
            column = default_column
        elif len(named) == 1:
            column = named[0]
        else:
            raise ValueError(f"sample: {path!r} has columns {', '.join(map(str, named))}; name one as "
                             f"sample(FILE:COLUMN)")
    if column not in header:
        raise ValueError(f"sample: {path!r} has no column {column!r}")
    if header.count(column) > 1:  # which of the two would be the sample is a guess
        raise ValueError(f"sample: {path!r}: column {column!r} is given twice")
    return column


def _csv_cells(path: str, column: str | None, default_column: str | None) -> tuple[str, list[str]]:
    """(column, its cells that hold a value) of a sample CSV, read with the csv module (no pandas: a refusal in
    ≤ 0.25 s).  Refused: a file that is not UTF-8 CSV, a column not in the header, and a row whose number of
    fields is not the header's (a short row's missing cells would be measurements nobody made)."""
    import csv

    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:  # a BOM is not in a name
            reader = csv.reader(handle)
            header = next((row for row in reader if row), [])  # blank lines before the header are skipped
            header = [name.strip() for name in header]
            if not header:
                raise ValueError(f"sample: {path!r} is empty: it needs a header and at least one value")
            column = _choose_column(path, header, column, default_column)
            index, cells = header.index(column), []
            for row in reader:
                if not row:  # a blank line is no row
                    continue
                if len(row) != len(header):
                    raise ValueError(f"sample: line {reader.line_num} of {path!r} has {len(row)} field"
                                     f"{'' if len(row) == 1 else 's'} where the header has {len(header)}: a "
                                     f"ragged row is not read")
                if row[index].strip().lower() not in _MISSING:
                    cells.append(row[index].strip())
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"sample: cannot read {path!r}: {exc}") from None
    return column, cells


def _parquet_cells(path: str, column: str | None, default_column: str | None) -> tuple[str, object, bool]:
    """(column, its values, whether they are numbers) of a sample Parquet file, read with pyarrow (no pandas):
    numbers (integer or floating) as floats, text as its cells (units allowed); nulls are no value.  Any other
    type (true/false, a date, a structure, a list, bytes) is refused: it is no measurement of a quantity."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        schema = pq.read_schema(path)
    except (OSError, ValueError, pa.ArrowException) as exc:  # not Parquet: one line
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        raise ValueError(f"sample: cannot read {path!r}: {lines[0] if lines else type(exc).__name__}") from None
    # pandas writes its index as a column of its own: not a measurement
    names = [name for name in schema.names if not str(name).startswith("__index_level_")]
    column = _choose_column(path, names, column, default_column)
    kind = schema.field(column).type
    if pa.types.is_dictionary(kind):  # a pandas categorical: its values are what it holds
        kind = kind.value_type
    numeric = pa.types.is_integer(kind) or pa.types.is_floating(kind) or pa.types.is_decimal(kind)
    if not (numeric or pa.types.is_string(kind) or pa.types.is_large_string(kind)):
        raise ValueError(f"sample: column {column!r} of {path!r} holds {kind}: give numbers [SI] or text with "
                         f"units")
    try:
        data = pq.read_table(path, columns=[column]).column(0).drop_null()
        if pa.types.is_dictionary(data.type):
            data = data.cast(kind)
    except (OSError, ValueError, pa.ArrowException) as exc:
        raise ValueError(f"sample: cannot read {path!r}: {str(exc).splitlines()[0]}") from None
    if not numeric:
        return column, [str(cell).strip() for cell in data.to_pylist()], False
    from fruitimpact.impact.inputs import arrow_floats

    return column, arrow_floats(data), True


def _numbers(cells, dimension: str) -> np.ndarray:
    """Cells (text) → values [SI]: plain numbers at once, else each through the unit parser (which also refuses
    what Python's float() alone would take, such as "1_0")."""
    if not any("_" in cell for cell in cells):
        try:
            return np.array(cells, dtype=float)
        except ValueError:  # a unit or a word in a cell
            pass
    return np.array([parse_quantity(c, dimension) for c in cells], dtype=float)


def _read_sample(argument: str, dimension: str, default_column: str | None) -> Sample:
    """``FILE[:COLUMN]`` → Sample; the column defaults to ``default_column`` or the file's only column."""
    path, column = argument, None
    if not Path(path).exists() and ":" in argument:
        path, column = argument.rsplit(":", 1)
    if not Path(path).is_file():
        raise ValueError(f"sample: no such file {path!r}")
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".parquet", ".pq"):
        raise ValueError(f"sample: {path!r} must be .csv or .parquet")
    if suffix == ".csv":
        column, cells = _csv_cells(path, column, default_column)
        numeric = False
    else:
        column, cells, numeric = _parquet_cells(path, column, default_column)
    try:
        values = cells if numeric else _numbers(cells, dimension)
    except ValueError as exc:
        raise ValueError(f"sample: column {column!r}: {exc}") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"sample: column {column!r} of {path!r} must hold at least one value, all finite")
    return Sample(source=f"{path}:{column}", values=values)


#: Distribution name → class; every class takes its parameters in its signature's order.
DISTRIBUTIONS = {"normal": Normal, "lognormal": LogNormal, "uniform": Uniform, "truncnormal": TruncNormal}


def parse_distribution(text: str, dimension: str, name: str | None = None):
    """Parse a spec (see the module docstring) for an input of ``dimension``.

    ``name`` is the input's column name, the default column of ``sample(FILE)``.
    Returns a distribution object; raises ``ValueError`` with one line."""
    match = _CALL.match(str(text))
    if match is None:
        return Constant(parse_quantity(text, dimension))
    kind, inner = match.group(1).lower(), match.group(2).strip()
    if kind == "sample":
        if not inner:
            raise ValueError("sample(FILE[:COLUMN]) needs a file")
        return _read_sample(inner, dimension, name)
    if kind not in DISTRIBUTIONS:
        raise ValueError(f"unknown distribution {kind!r} in {text!r} (known: "
                         + ", ".join([cls.signature for cls in DISTRIBUTIONS.values()] + ["sample(FILE[:COLUMN])"])
                         + ")")
    cls = DISTRIBUTIONS[kind]
    args = [a.strip() for a in inner.split(",")] if inner else []
    arity = len(cls.__dataclass_fields__)
    if len(args) != arity:
        raise ValueError(f"{cls.signature} takes {arity} values; got {len(args)} in {text!r}")
    dimensionless = getattr(cls, "dimensionless", ())
    values = [parse_quantity(a, "dimensionless" if i in dimensionless else dimension) for i, a in enumerate(args)]
    return cls(*values)


__all__ = ["Constant", "Normal", "LogNormal", "Uniform", "TruncNormal", "SplitNormal", "Sample", "DISTRIBUTIONS",
           "TRUNCNORMAL_MIN_MASS", "parse_distribution"]
