"""Impacts grouped into transfer points, and each point's impacts into passes (visits of the sphere).

Three ways, in this order of preference:

1. ``point`` labels in the log: the points in the order they first appear;
2. a ``--points`` file of time windows (CSV ``name,start,end`` [s]; a name may have one window per pass):
   a reading in no window belongs to no point (counted in a warning);
3. clustering along the run: readings closer in time than ``point_gap`` are one visit (the sphere's impact
   at a transfer point and its bounces there); visits separated by more than ``pass_gap`` start a new pass
   (the sphere carried back to the start of the line).  When every pass has the same number of visits, the
   k-th visit of each pass is point k ("point 1", "point 2", …); otherwise the visits cannot be matched
   between passes and each is its own point, with a warning.

Within a point, its readings are split into visits by the same ``point_gap`` rule: ``passes`` is their
number.  Survey practice is three passes per point (WSU-TFREC, Postharvest Information Network J3I3B).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: Readings closer than this [s] are one visit of one point (a drop and its bounces).
POINT_GAP = 1.0
#: A gap longer than this [s] starts a new pass of the sphere through the line.
PASS_GAP = 20.0
#: Most transfer points of one log (as a line file).
MAX_POINTS = 200


@dataclass
class Groups:
    """``names`` of the points in order; per reading ``point`` (index into names, −1: in no point) and
    ``visit`` (index of its visit within its point); ``passes`` per point; ``method``; ``warnings``."""

    names: list
    point: np.ndarray
    visit: np.ndarray
    passes: list
    method: str
    warnings: list = field(default_factory=list)


def _visits(time: np.ndarray, gap: float) -> np.ndarray:
    """Visit number of each reading of one point (times in any order): a new visit after a gap > ``gap``."""
    order = np.argsort(time, kind="stable")
    breaks = np.concatenate([[0], (np.diff(time[order]) > gap).astype(int)])
    visit = np.empty(time.size, dtype=int)
    visit[order] = np.cumsum(breaks)
    return visit


def read_windows(path) -> list[tuple[str, float, float]]:
    """The windows of a ``--points`` file: CSV ``name,start,end`` (times [s], units accepted), start < end;
    ``ValueError`` naming the file, line and column."""
    import csv

    from fruitimpact.library.textfiles import table_lines
    from fruitimpact.impact.units import parse_quantity

    lines = table_lines(path, "points: ")
    rows = list(csv.reader(line for _, line in lines))
    if not rows or [c.strip() for c in rows[0]] != ["name", "start", "end"]:
        raise ValueError(f"points: {path} must have the header name,start,end")
    windows = []
    for (number, _), row in zip(lines[1:], rows[1:]):
        if len(row) != 3:
            raise ValueError(f"points: {path}, line {number}: {len(row)} fields, the header has 3")
        name = row[0].strip()
        if not name:
            raise ValueError(f"points: {path}, line {number}, name: empty")
        try:
            start, end = (parse_quantity(cell.strip(), "time") for cell in row[1:])
        except ValueError as exc:
            raise ValueError(f"points: {path}, line {number}: {exc}") from None
        if not (math.isfinite(start) and math.isfinite(end) and start < end):
            raise ValueError(f"points: {path}, line {number}: start must be before end; got {row[1]!r}, {row[2]!r}")
        windows.append((name, start, end))
    if not windows:
        raise ValueError(f"points: {path} has no window below its header")
    ordered = sorted(windows, key=lambda w: w[1])
    for (name_a, start_a, end_a), (name_b, start_b, end_b) in zip(ordered, ordered[1:]):
        if start_b <= end_a:  # a reading in both would belong to one of them by the order of the file
            raise ValueError(f"points: {path}: the windows of {name_a!r} ({start_a:g}-{end_a:g} s) and {name_b!r} "
                             f"({start_b:g}-{end_b:g} s) overlap")
    if len({name for name, _, _ in windows}) > MAX_POINTS:
        raise ValueError(f"points: {path} names more than {MAX_POINTS} points")
    return windows


def group(time, labels=None, windows=None, *, point_gap: float = POINT_GAP, pass_gap: float = PASS_GAP) -> Groups:
    """Group readings at ``time`` [s] into transfer points and visits (see the module)."""
    time = np.asarray(time, dtype=float)
    n = time.size
    warnings = []
    if labels is not None:
        names = list(dict.fromkeys(labels))
        index = {name: k for k, name in enumerate(names)}
        point = np.array([index[label] for label in labels], dtype=int)
        method = "column"
    elif windows is not None:
        names = list(dict.fromkeys(name for name, _, _ in windows))
        index = {name: k for k, name in enumerate(names)}
        point = np.full(n, -1, dtype=int)
        for name, start, end in windows:  # windows do not overlap (read_windows)
            inside = (point < 0) & (time >= start) & (time <= end)
            point[inside] = index[name]
        outside = int(np.count_nonzero(point < 0))
        if outside:
            warnings.append(f"{outside} of {n} readings fall in no window of the points file and belong to no point")
        method = "windows"
    else:
        order = np.argsort(time, kind="stable")
        gaps = np.diff(time[order])
        visit_of = np.concatenate([[0], np.cumsum(gaps > point_gap)])
        pass_of = np.concatenate([[0], np.cumsum(gaps > pass_gap)])
        visits_per_pass = [len(set(visit_of[pass_of == p])) for p in range(pass_of[-1] + 1 if n else 0)]
        point = np.empty(n, dtype=int)
        if len(visits_per_pass) > 1 and len(set(visits_per_pass)) == 1:
            first = {p: visit_of[pass_of == p].min() for p in range(len(visits_per_pass))}
            point[order] = visit_of - np.array([first[p] for p in pass_of])
            names = [f"point {k + 1}" for k in range(visits_per_pass[0])]
        else:
            if len(visits_per_pass) > 1:
                warnings.append(f"the passes have different numbers of visits ({', '.join(map(str, visits_per_pass))}):"
                                f" they cannot be matched, so each visit is its own point (give a point column or a "
                                f"--points file)")
            point[order] = visit_of
            names = [f"point {k + 1}" for k in range(int(visit_of[-1]) + 1 if n else 0)]
        method = "clustered"
    if len(names) > MAX_POINTS:
        raise ValueError(f"log: {len(names)} transfer points; at most {MAX_POINTS} (check --point-gap: readings "
                         f"more than {point_gap:g} s apart are different visits)")
    visit = np.full(n, -1, dtype=int)
    passes = []
    for k in range(len(names)):
        members = np.flatnonzero(point == k)
        visit[members] = _visits(time[members], point_gap)
        passes.append(int(visit[members].max()) + 1 if members.size else 0)
    return Groups(names, point, visit, passes, method, warnings)


__all__ = ["Groups", "MAX_POINTS", "PASS_GAP", "POINT_GAP", "group", "read_windows"]
