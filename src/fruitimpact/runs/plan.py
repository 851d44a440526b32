"""What a run computes (``Plan``), the thresholds it counts, and the limits of a run."""

from __future__ import annotations

import hashlib
import math
import json
import operator
import re
from dataclasses import dataclass

import numpy as np

from fruitimpact.impact.quantities import CHARACTERISTICS, Quantity

#: Rows per chunk by default: large enough that the per-chunk overhead is small next to evaluation.
CHUNK_ROWS = 500_000
#: Target size of the uniform sample kept for percentiles; populations up to this size are exact.
SAMPLE_ROWS = 2_000_000
#: Default percentiles reported for populations [%].
PERCENTILES = (5.0, 25.0, 50.0, 75.0, 95.0)
#: Format version of the work folder (marker, manifest, part files, summaries).
WORK_FORMAT = 3

#: Most rows of one run (population members, grid points): about an hour of evaluation on a laptop.
MAX_ROWS = 1_000_000_000
#: Most values of one sweep axis (its COUNT).
MAX_AXIS_VALUES = 1_000_000
#: Most rows of one chunk: the driver holds a few chunks in memory (about 1 kB per row).
MAX_CHUNK_ROWS = 10_000_000
#: Largest percentile sample: 8 bytes × characteristics × sample rows stay in memory.
MAX_SAMPLE_ROWS = 20_000_000


class RunError(Exception):
    """A run that cannot start or continue (a work folder of another job, a lock held, a bad
    file, a full disk): one line, for the command line's error."""


def check_count(what: str, value: int, low: int, high: int) -> int:
    """``value`` if ``low <= value <= high``, else ``ValueError`` saying the allowed range."""
    if not low <= value <= high:
        raise ValueError(f"{what} must be an integer in [{low:,}, {high:,}]; got {value:,}")
    return value


def characteristic(name: str) -> Quantity:
    """The ``Quantity`` of an output column; ``ValueError`` naming the known ones."""
    if name not in CHARACTERISTICS:
        raise ValueError(f"unknown characteristic {name!r} (known: {', '.join(CHARACTERISTICS)})")
    return CHARACTERISTICS[name]


#: Characteristics that only a bruise criterion gives (NaN for every row without one).
CRITERION_CHARACTERISTICS = ("bruise_margin", "bruised", "bruise_volume", "bruise_depth", "bruise_width")


def check_criterion_for(names, criterion) -> None:
    """``InputError`` naming ``criterion`` when one of ``names`` needs a bruise criterion and none is given: a
    summary or figure of it would be empty while the run says ok."""
    from fruitimpact.impact.validation import InputError

    needing = [name for name in names if name in CRITERION_CHARACTERISTICS]
    if needing and (criterion is None or str(criterion).strip().lower() in ("", "none")):
        raise InputError(f"criterion must be given for {', '.join(needing)}: pressure, shear or energy (without one "
                         f"every row's {needing[0]} is NaN)", "criterion")


def characteristics_list(text: str) -> tuple[str, ...]:
    """``"peak_force,contact_duration"`` → validated names."""
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise ValueError("give at least one characteristic")
    for name in names:
        characteristic(name)
    return names


_OPERATORS = {">=": operator.ge, "<=": operator.le, ">": operator.gt, "<": operator.lt}  # elementwise on arrays


@dataclass(frozen=True)
class Threshold:
    """``characteristic op value`` (op one of > >= < <=; value [SI]); counted exactly over ok rows."""

    name: str
    op: str
    value: float
    text: str

    @classmethod
    def parse(cls, text: str) -> "Threshold":
        """``peak_force>60N`` (units of the characteristic, or SI) → Threshold; ``ValueError`` otherwise."""
        match = re.match(r"^\s*([A-Za-z_][A-Za-z_0-9]*)\s*(>=|<=|>|<)\s*(.+?)\s*$", text)
        if match is None:
            raise ValueError(f"a threshold is NAME>VALUE (or >=, <, <=), e.g. peak_force>60N; got {text!r}")
        name, op, value = match.groups()
        number = characteristic(name).parse(value)
        if not math.isfinite(number):  # "peak_force>nan" would count nothing and say 0 %
            raise ValueError(f"a threshold's value must be a finite number; got {value!r}")
        return cls(name, op, number, text.strip())

    def count(self, values: np.ndarray) -> int:
        """How many of ``values`` [SI] are beyond the threshold (NaN never is)."""
        with np.errstate(invalid="ignore"):
            return int(np.count_nonzero(_OPERATORS[self.op](values, self.value)))

    def identity(self) -> list:
        return [self.name, self.op, self.value]


@dataclass(frozen=True)
class Plan:
    """What a run computes: a source cut into chunks, and what is kept of each chunk.

    ``write_rows``: keep every row (part files, written into the output).
    ``stats``: columns with exact streamed statistics and a uniform sample of
    about ``sample_rows`` rows for percentiles (populations).
    ``thresholds``: exact counts of ok rows beyond each threshold.
    Limits (``MAX_ROWS``, ``MAX_CHUNK_ROWS``, ``MAX_SAMPLE_ROWS``) are checked here,
    before any work: ``ValueError``."""

    kind: str
    source: object
    chunk_rows: int = CHUNK_ROWS
    write_rows: bool = True
    stats: tuple = ()
    thresholds: tuple = ()
    sample_rows: int = SAMPLE_ROWS

    def __post_init__(self):
        check_count("chunk_rows", self.chunk_rows, 1, MAX_CHUNK_ROWS)
        check_count("sample_rows", self.sample_rows, 1, MAX_SAMPLE_ROWS)
        if self.rows is not None:
            check_count("rows", self.rows, 0, MAX_ROWS)

    @property
    def rows(self) -> int | None:
        return getattr(self.source, "rows", None)

    @property
    def chunks(self) -> int | None:
        return None if self.rows is None else -(-self.rows // self.chunk_rows)

    @property
    def sample_probability(self) -> float:
        return 1.0 if self.rows is None or self.rows <= self.sample_rows else self.sample_rows / self.rows

    def identity(self) -> dict:
        from fruitimpact import __version__

        return {"kind": self.kind, "format": WORK_FORMAT, "fruitimpact": __version__,
                "source": self.source.identity(), "chunk_rows": self.chunk_rows, "write_rows": self.write_rows,
                "stats": list(self.stats), "thresholds": [t.identity() for t in self.thresholds],
                "sample_rows": self.sample_rows if self.stats else None}

    def fingerprint(self) -> str:
        """SHA-256 of everything that determines the rows and the summaries."""
        return hashlib.sha256(json.dumps(self.identity(), sort_keys=True).encode()).hexdigest()
