"""Reading a sphere's log: one row per impact, or a raw acceleration trace; vendors' headers mapped.

No vendor publishes its export format (docs/tasks/sphere.md), so the reader is built around names, not
layouts.  A log of **readings** is a CSV with a header and the columns (contract)

    time [s], peak_acceleration [g = 9.80665 m/s²], velocity_change [m/s: in + out speed],
    duration [s] (optional), point (optional: the transfer point's label).

A **raw trace** has ``time`` [s] and ``acceleration`` [g] (or ``acceleration_x``, ``_y``, ``_z``, whose
magnitude is taken), sampled uniformly: its impacts are found by the detector ``analyze`` uses
(``signals.detect``) and each becomes a reading through the Hunt–Crossley pulse fitted to its window
(``signals.fit.fit_impact``): the model's peak, ΔV = (1 + e) V and contact duration, whose onset and end are
not cut where the signal crossed the threshold.

``columns`` maps our names onto a vendor's headers, with their units: ``{"peak_acceleration": "Peak G",
"velocity_change": "dV:km/h", "duration": "Dur:ms"}`` (``header:unit``; a cell may also carry its own unit,
``12ms``).  Unknown columns and missing required ones refuse the file; a row whose cell is empty, not a
number, not finite, or impossible (a peak, ΔV or duration that is not positive) is reported with its row and
column and skipped, and a log with no usable row is refused.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Columns of a log of readings: (name, dimension of ``impact.units``, its unit when a cell has none, required).
READING_COLUMNS = {
    "time": ("time", "s", True),
    "peak_acceleration": ("acceleration", "g", True),
    "velocity_change": ("velocity", "m/s", True),
    "duration": ("time", "s", False),
    "point": (None, "", False),
}
#: Columns of a raw trace.
TRACE_COLUMNS = {
    "time": ("time", "s", True),
    "acceleration": ("acceleration", "g", False),
    "acceleration_x": ("acceleration", "g", False),
    "acceleration_y": ("acceleration", "g", False),
    "acceleration_z": ("acceleration", "g", False),
    "point": (None, "", False),
}
#: Units of acceleration a cell or a mapping may name (factors to m/s²).
ACCELERATION_UNITS = {"g": STANDARD_GRAVITY, "m/s2": 1.0, "m/s^2": 1.0, "m/s²": 1.0}
#: Readings beyond these are legal but implausible for a sphere on a handling line: one warning.
IMPLAUSIBLE_PEAK = 2000.0 * STANDARD_GRAVITY
IMPLAUSIBLE_CHANGE = 20.0
#: A pulse's fit misfit counts as a shape the model does not have (``shape_misfit``) above this many noise sd.
SHAPE_NOISE = 3.0
#: A trace's sample times may differ from uniform by this share of the period.
TRACE_JITTER = 0.01
#: Most rows of one log (readings: a survey logs thousands; a raw trace: about 80 min at 10 kHz).  The reader
#: holds the file's rows in memory (about 1 GB per million rows), so the bound keeps it within a workstation's.
MAX_ROWS = 5_000_000


@dataclass
class SphereLog:
    """Readings of a log, SI: ``time`` [s], ``peak`` a_max [m/s²], ``change`` ΔV [m/s], ``duration`` T [s]
    (NaN where not logged), ``point`` (labels, or None), ``rows`` (the file's row number of each), ``skipped``
    ([(row, column, reason)]), ``kind`` (``readings`` or ``trace``), ``sample_period`` [s] of a trace (0 for
    readings), ``warnings``, ``shape_misfit`` (a trace's: the Hunt–Crossley fit's rms misfit over the peak where it
    exceeds ``SHAPE_NOISE`` noise sd, else 0; None for readings)."""

    time: np.ndarray
    peak: np.ndarray
    change: np.ndarray
    duration: np.ndarray
    point: list | None
    rows: np.ndarray
    skipped: list = field(default_factory=list)
    kind: str = "readings"
    sample_period: float = 0.0
    warnings: list = field(default_factory=list)
    shape_misfit: np.ndarray | None = None  # a trace's: rms misfit of each pulse's fit over its peak (0: within noise)

    def __len__(self) -> int:
        return self.time.size


def parse_columns(text: str | dict | None, names) -> dict[str, tuple[str, str | None]]:
    """``"time=Time,peak_acceleration=G"`` (or a dict) → {our name: (vendor header, unit or None)};
    ``ValueError`` naming ``columns`` for an unknown name, a name mapped twice or an entry without ``=``."""
    if text is None:
        return {}
    items = list(text.items()) if isinstance(text, dict) else []
    if not isinstance(text, dict):
        for entry in str(text).split(","):
            name, sep, header = entry.partition("=")
            if not sep or not name.strip() or not header.strip():
                raise ValueError(f"columns: expected name=Header entries separated by commas; got {entry!r}")
            items.append((name.strip(), header.strip()))
    mapping = {}
    for name, header in items:
        if name not in names:
            raise ValueError(f"columns: unknown name {name!r} (names: {', '.join(names)})")
        if name in mapping:
            raise ValueError(f"columns: {name} is mapped twice")
        unit = None
        head, colon, tail = str(header).rpartition(":")
        if colon and head:
            header, unit = head.strip(), tail.strip()
        mapping[name] = (str(header), unit)
    return mapping


def _unit_factor(dimension: str, unit: str, where: str) -> float:
    from fruitimpact.impact.units import UNITS

    table = ACCELERATION_UNITS if dimension == "acceleration" else UNITS[dimension]
    if unit not in table:
        raise ValueError(f"{where}: unknown unit {unit!r} (units allowed: {', '.join(u for u in table if u)})")
    return table[unit]


def _cell(text: str, dimension: str, factor: float) -> float:
    """A cell in SI: a plain number times the column's unit ``factor``, or a number with its own unit."""
    from fruitimpact.impact.units import number_and_unit

    parsed = number_and_unit(text)
    if parsed is None:
        raise ValueError(f"{text!r} is not a number")
    number, unit = parsed
    value = number * (factor if not unit else _unit_factor(dimension, unit, "cell"))
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


def _table(path, mapping: dict, schema: dict, hint: str = "; map a vendor's headers with --columns name=Header"):
    """(our name of each header cell, unit factors, data rows with their line numbers); ``mapping`` as
    ``parse_columns`` returns it; ``hint`` ends the message of an unknown column."""
    from fruitimpact.library.textfiles import table_lines

    lines = table_lines(path)
    if not lines:
        raise ValueError(f"{path} is empty: expected a header")
    if len(lines) - 1 > MAX_ROWS:
        raise ValueError(f"{path}: {len(lines) - 1} rows; at most {MAX_ROWS}")
    rows = list(csv.reader(line for _, line in lines))
    header = [cell.strip() for cell in rows[0]]
    unknown = [name for name in mapping if name not in schema]
    if unknown:
        raise ValueError(f"columns: {unknown[0]} is not a column of a {'raw trace' if 'acceleration' in schema else 'log of readings'} "
                         f"(columns: {', '.join(schema)})")
    vendor = {head: name for name, (head, _) in mapping.items()}
    named = []
    for cell in header:
        name = vendor.get(cell, cell if cell in schema and cell not in mapping else None)
        if name is None:
            raise ValueError(f"{path}: unknown column {cell!r} (columns: {', '.join(schema)}{hint})")
        if name in named:
            raise ValueError(f"{path}: column {name} appears twice")
        named.append(name)
    for name, (head, _) in mapping.items():
        if name not in named:
            raise ValueError(f"{path}: --columns maps {name} to {head!r}, which is not in the header")
    factors = {}
    for name in named:
        dimension, default, _ = schema[name]
        if dimension is not None:
            unit = mapping.get(name, (None, None))[1]
            factors[name] = _unit_factor(dimension, unit or default, f"columns: {name}")
    data = [(lines[k][0], row) for k, row in enumerate(rows[1:], start=1)]
    return named, factors, data


def read_table(path, schema: dict, mapping: dict | None = None, label: str = "",
               hint: str = "; map a vendor's headers with --columns name=Header"):
    """Rows of a CSV with the columns of ``schema`` ({name: (dimension, default unit, required)}), in SI.

    Returns (values {name: array, NaN where absent}, labels of a ``point`` column or None, usable (bool per
    row), the file's row numbers, skipped [(row, column, reason)]).  ``ValueError`` for what refuses the whole
    file: unreadable, unknown or missing columns, no rows."""
    named, factors, data = _table(path, mapping or {}, schema, hint)
    required = [name for name, (_, _, needed) in schema.items() if needed and name not in named]
    if required:
        raise ValueError(f"{path}: missing column(s) {', '.join(required)}{label}")
    if not data:
        raise ValueError(f"{path}: no rows below the header")
    values = {name: np.full(len(data), np.nan) for name in schema if name != "point"}
    labels = [""] * len(data) if "point" in named else None
    good = np.ones(len(data), dtype=bool)
    skipped = []
    for k, (number, row) in enumerate(data):
        if len(row) != len(named):
            skipped.append((number, None, f"{len(row)} fields, the header has {len(named)}"))
            good[k] = False
            continue
        for name, text in zip(named, row):
            text = text.strip()
            if name == "point":
                if not text:
                    skipped.append((number, name, "empty (every row of a log with a point column names its point)"))
                    good[k] = False
                    break
                labels[k] = text
                continue
            if not text and name == "duration":
                continue  # a device that logs the duration of some impacts only
            if not text:
                skipped.append((number, name, "empty"))
                good[k] = False
                break
            try:
                value = _cell(text, schema[name][0], factors[name])
            except ValueError as exc:
                skipped.append((number, name, str(exc)))
                good[k] = False
                break
            if name != "time" and not name.startswith("acceleration") and not value > 0.0:
                skipped.append((number, name, f"must be > 0; got {text!r}"))
                good[k] = False
                break
            values[name][k] = value
    return values, labels, good, np.array([number for number, _ in data]), skipped


def read_log(path, columns=None) -> SphereLog:
    """Read a sphere log (readings or a raw trace, told apart by their columns).

    Parameters
    ----------
    path : str or path
        The CSV file.
    columns : str or dict, optional
        Our names → the vendor's headers (``"peak_acceleration=Peak G,velocity_change=dV:km/h"``).

    Returns
    -------
    SphereLog

    Raises
    ------
    ValueError
        The file cannot be read, has unknown or missing columns, or no usable row (naming the file, the row
        and the column).
    """
    mapping = parse_columns(columns, tuple(dict.fromkeys([*READING_COLUMNS, *TRACE_COLUMNS])))
    trace = any(name.startswith("acceleration") for name in mapping) or _header_is_trace(path, mapping)
    schema = TRACE_COLUMNS if trace else READING_COLUMNS
    values, labels, good, numbers, skipped = read_table(path, schema, mapping)
    if trace:
        axes = ("acceleration_x", "acceleration_y", "acceleration_z")
        if np.isnan(values["acceleration"]).all() and any(np.isnan(values[a]).all() for a in axes):
            raise ValueError(f"{path}: missing column(s) acceleration (or acceleration_x, acceleration_y, "
                             f"acceleration_z)")
        return _trace(path, values, labels, good, numbers, skipped)
    if not good.any():
        raise ValueError(f"{path}: no usable row ({_skipped_text(skipped)})")
    keep = np.flatnonzero(good)
    log = SphereLog(values["time"][keep], values["peak_acceleration"][keep], values["velocity_change"][keep],
                    values["duration"][keep], None if labels is None else [labels[k] for k in keep], numbers[keep],
                    skipped)
    log.warnings += _implausible(log)
    return log


def _skipped_text(skipped) -> str:
    number, column, reason = skipped[0]
    more = f"; {len(skipped) - 1} more" if len(skipped) > 1 else ""
    return f"row {number}{', ' + column if column else ''}: {reason}{more}"


def skipped_lines(path, skipped) -> list[str]:
    """One line per skipped row: ``LOG, row N, column: reason``."""
    return [f"{path}, row {number}{', ' + column if column else ''}: {reason}; row skipped"
            for number, column, reason in skipped]


def _implausible(log: SphereLog) -> list[str]:
    warnings = []
    for values, limit, what in ((log.peak, IMPLAUSIBLE_PEAK, f"peak acceleration above "
                                                               f"{IMPLAUSIBLE_PEAK / STANDARD_GRAVITY:.0f} g"),
                                (log.change, IMPLAUSIBLE_CHANGE, f"velocity change above {IMPLAUSIBLE_CHANGE:g} m/s")):
        count = int(np.count_nonzero(values > limit))
        if count:
            warnings.append(f"{count} reading(s) with a {what}: implausible on a handling line (computed as given)")
    return warnings


def _header_is_trace(path, mapping) -> bool:
    """Whether the file's header names a trace's acceleration column (without a mapping)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            for line in handle:
                if line.strip() and not line.lstrip().startswith("#"):
                    header = [cell.strip() for cell in next(csv.reader([line]))]
                    return any(cell in ("acceleration", "acceleration_x") for cell in header) and \
                        "peak_acceleration" not in header
    except (OSError, UnicodeDecodeError):
        return False  # _table says why
    return False


def _trace(path, values, labels, good, numbers, skipped) -> SphereLog:
    """The impacts of a raw trace, found by the detector ``analyze`` uses, as readings."""
    from fruitimpact.signals.detect import DetectorSettings, detect

    if not good.all():  # a trace is a time series: a missing sample is a gap, not a row to skip
        number, column, reason = skipped[0]
        raise ValueError(f"{path}, row {number}{', ' + column if column else ''}: {reason} (a raw trace needs every "
                         f"sample)")
    time = values["time"]
    if time.size < 64:
        raise ValueError(f"{path}: a raw trace of {time.size} samples; at least 64")
    steps = np.diff(time)
    period = float(np.median(steps))
    if not period > 0.0 or np.max(np.abs(steps - period)) > TRACE_JITTER * period:
        raise ValueError(f"{path}: time must grow by one sample period per row (within {TRACE_JITTER:.0%}); "
                         f"the steps range from {steps.min():.6g} to {steps.max():.6g} s")
    if not np.isnan(values["acceleration"]).all():
        signal = values["acceleration"]
    else:
        signal = np.sqrt(values["acceleration_x"] ** 2 + values["acceleration_y"] ** 2 + values["acceleration_z"] ** 2)
    rate = 1.0 / period
    in_g = signal / STANDARD_GRAVITY
    # floor 2 g: a sphere at rest reads 1 g on a 3-axis magnitude; devices trigger at 5-10 g (Luo et al. 2012: 8 g)
    # windows wide enough for the fit to see the pulse's tails, which fall below the threshold long before the
    # contact ends on a soft pad (a 10 ms pulse was 7 ms above it)
    settings = DetectorSettings(threshold_floor=2.0, min_duration=max(2.0 / rate, 2e-4),
                                offset_hold=max(2.0 / rate, 2e-4), warmup=max(16.0 / rate, 0.01),
                                pre_trigger=3e-3, post_trigger=10e-3)
    found = detect(in_g, rate, settings)
    if not found:
        raise ValueError(f"{path}: no impact found in the trace (none rises 6 noise σ and 2 g above its baseline)")
    from fruitimpact.signals.fit import fit_impact

    peak, change, duration, times, rows, names, misfit = [], [], [], [], [], [], []
    unfitted = 0
    for impact in found:
        start, end = impact.start_index, impact.end_index
        window = impact.window * STANDARD_GRAVITY  # [m/s²], baseline (1 g at rest on a 3-axis magnitude) removed
        # the Hunt-Crossley pulse fitted to the whole window: its onset and end are the model's, not where the
        # signal crossed the detector's threshold (which cuts the t^1.5 tails: a 3 cm drop read 6 % low); only K/m
        # enters the motion, so a unit mass gives the sphere's own V, e, T and peak acceleration
        stamps = (impact.window_start + np.arange(window.size)) * period
        fit = fit_impact(stamps, window, mass=1.0, noise=max(impact.noise * STANDARD_GRAVITY, 1e-9))
        if fit["converged"] and np.isfinite(fit["contact_duration"]):
            peak.append(float(fit["peak_force"]))
            change.append(float(fit["impulse"]))
            duration.append(float(fit["contact_duration"]))
            beyond = fit["fit_residual"] > SHAPE_NOISE * fit["noise"]
            misfit.append(float(fit["fit_residual_relative"]) if beyond else 0.0)
        else:  # the samples themselves: the threshold-crossing contact
            unfitted += 1
            contact = window[start - impact.window_start: end - impact.window_start + 1]
            peak.append(float(contact.max()))
            change.append(float(np.sum(contact) * period))  # ∫ a dt over the contact (rectangle rule)
            duration.append((end - start + 1) * period)
            misfit.append(math.nan)
        times.append(float(time[start]))
        rows.append(int(numbers[start]))
        names.append(labels[start] if labels is not None else None)
    log = SphereLog(np.array(times), np.array(peak), np.array(change), np.array(duration),
                    names if labels is not None else None, np.array(rows), [], "trace", period,
                    shape_misfit=np.array(misfit))
    if unfitted:
        log.warnings.append(f"{unfitted} of {len(found)} impacts of the trace could not be fitted by a Hunt-Crossley "
                            f"pulse: their readings are the samples' (threshold-crossing duration, cut tails)")
    return log


__all__ = ["ACCELERATION_UNITS", "READING_COLUMNS", "SphereLog", "TRACE_COLUMNS", "parse_columns", "read_log",
           "skipped_lines"]
