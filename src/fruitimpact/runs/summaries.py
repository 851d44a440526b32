"""What a run produced: status counts, and for populations exact streamed statistics,
threshold counts and percentiles, merged from the chunks' summaries."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from fruitimpact.impact.quantities import CHARACTERISTICS


@dataclass
class RunSummary:
    """What a run produced: rows per status; for populations statistics, threshold counts and the percentile
    method.

    Attributes
    ----------
    kind : str
        ``batch``, ``sweep`` or ``population``.
    rows : int
        Rows evaluated.
    ok, invalid, failed : int
        Rows of those statuses (``statuses`` has every status, ``inaccurate`` too).
    output : str or None
        The file every row was written to.
    resumed_chunks : int
        Chunks taken from an earlier, interrupted run of the same job.
    statistics : dict
        Population: per characteristic ``mean``, ``sd``, ``min``, ``max`` and ``percentiles`` [SI], of the ok rows.
    thresholds : list of dict
        Population: each threshold's ``count`` of ``of`` ok rows and ``share``.
    percentiles : dict
        Population: how the percentiles were found (``exact``, or from a seeded sample of ``sample_size`` rows).
    sample : numpy.ndarray or None
        Population: the rows the percentiles were taken from, one column per characteristic (for histograms).
    columns : dict
        Columns read back whole for a figure (a sweep's plotted characteristic).
    statuses : dict
        Rows per status name.
    warnings : dict
        Rows per warning text (an implausible value, a result to be read with care).
    details : dict
        What the run was asked: a population's ``seed``, ``inputs`` (each drawn input's distribution) and
        ``spreads``.
    """

    kind: str
    rows: int
    ok: int
    invalid: int
    failed: int
    output: str | None = None
    resumed_chunks: int = 0
    statistics: dict = field(default_factory=dict)
    thresholds: list = field(default_factory=list)
    percentiles: dict = field(default_factory=dict)  # method, sample size, exact or not
    sample: np.ndarray | None = None  # the percentile sample, one column per statistic
    columns: dict = field(default_factory=dict)  # columns read back for figures (keep_columns)
    statuses: dict = field(default_factory=dict)  # rows per status, every status evaluate reported
    warnings: dict = field(default_factory=dict)  # rows per warning text
    details: dict = field(default_factory=dict)  # what the run was asked (a population's seed, inputs, spreads)

    def warning_lines(self) -> list[str]:
        """Each warning the rows carry, once, with how many rows carry it."""
        return [f"{count:,} of {self.rows:,} rows: {text}" for text, count in self.warnings.items()]

    def to_dict(self) -> dict:
        """The summary as JSON-ready values (``fruitimpact population --json``)."""
        return {"kind": self.kind, "rows": self.rows, "ok": self.ok, "invalid": self.invalid, "failed": self.failed,
                "statuses": self.statuses, "warnings": self.warning_lines(), "output": self.output,
                "resumed_chunks": self.resumed_chunks,
                "percentile_method": self.percentiles, "statistics": self.statistics, "thresholds": self.thresholds,
                **self.details}


def add_statuses(records, key: str = "statuses") -> dict[str, int]:
    """Rows per status (or per warning text, ``key="warnings"``) over the chunk ``records`` (a record of an earlier
    version without warnings counts none)."""
    total: dict[str, int] = {}
    for record in records:
        for name, count in record.get(key, {}).items():
            total[name] = total.get(name, 0) + int(count)
    return total


def _merge_moments(moments: np.ndarray) -> tuple[int, float, float]:
    """Count, mean and M2 of chunks' (n, mean, M2) rows, merged exactly (Chan et al.)."""
    n, mean, m2 = 0, 0.0, 0.0
    for cn, cmean, cm2 in moments[:, :3]:
        if cn == 0:
            continue
        total = n + cn
        delta = cmean - mean
        mean += delta * cn / total
        m2 += cm2 + delta * delta * n * cn / total
        n = total
    return int(n), mean, m2


def _percentiles(column: np.ndarray, percentiles) -> dict:
    """``numpy.percentile`` (linear) of the finite values of ``column`` (a copy of its own, which
    is partitioned in place: one partition for all percentiles, no further copy)."""
    finite = np.isfinite(column)
    if not finite.all():
        column = column[finite]
    if not column.size:
        return {f"{p:g}": math.nan for p in percentiles}
    values = np.percentile(column, list(percentiles), overwrite_input=True)
    return {f"{p:g}": float(v) for p, v in zip(percentiles, values)}


def combine(summaries: list, plan, percentiles, ok: int) -> dict:
    """Merge chunk summaries (in chunk order) into statistics, threshold counts and percentiles
    of the ``ok`` rows."""
    moments = np.stack([s["moments"] for s in summaries])  # chunks × stats × (n, mean, m2, min, max)
    with np.errstate(over="ignore", invalid="ignore"):  # values beyond double range (a 1e300 kg sample, warned
        # of by the rows' own warning): their sd is NaN, said in the table rather than by NumPy on stderr
        return _combine(summaries, moments, plan, percentiles, ok)


def _combine(summaries: list, moments, plan, percentiles, ok: int) -> dict:
    sample = np.concatenate([s["sample"] for s in summaries]) if summaries else np.empty((0, len(plan.stats)))
    # numpy's partition releases the GIL: the columns' percentiles in parallel threads
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=min(len(plan.stats), os.cpu_count() or 1) or 1) as pool:
        quantiles = list(pool.map(lambda j: _percentiles(np.ascontiguousarray(sample[:, j]), percentiles),
                                  range(len(plan.stats))))
    stats = {}
    for j, name in enumerate(plan.stats):
        n, mean, m2 = _merge_moments(moments[:, j])
        stats[name] = {
            "unit": CHARACTERISTICS[name].si_unit, "count": n,
            "mean": mean if n else math.nan, "sd": math.sqrt(m2 / (n - 1)) if n > 1 else math.nan,
            "min": float(moments[:, j, 3].min()) if n else math.nan,
            "max": float(moments[:, j, 4].max()) if n else math.nan,
            "percentiles": quantiles[j],
        }
    threshold_counts = np.sum([s["thresholds"] for s in summaries], axis=0) if plan.thresholds else []
    thresholds = [{"threshold": t.text, "characteristic": t.name, "op": t.op, "value": t.value,
                   "unit": CHARACTERISTICS[t.name].si_unit, "count": int(c), "of": ok,
                   "share": int(c) / ok if ok else math.nan}
                  for t, c in zip(plan.thresholds, threshold_counts)]
    exact = plan.sample_probability >= 1.0
    method = {"exact": exact, "sample_rows": int(sample.shape[0]), "method": "numpy.percentile, linear interpolation",
              "note": ("exact: every ok row" if exact else
                       f"estimate from a seeded uniform sample of {sample.shape[0]} ok rows "
                       f"(each row kept with probability {plan.sample_probability:.3g})")}
    return {"statistics": stats, "thresholds": thresholds, "percentiles": method, "sample": sample}
