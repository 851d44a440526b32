"""Packing-line audit: a population of fruit through a sequence of transfer points.

A line is a table of transfer points, in the order the fruit meets them:
``name``, ``drop_height`` [m] (or with a unit), ``surface`` (a library surface)
and optionally ``fruit_on_fruit`` (true: the fruit lands on another fruit
resting there, an identical free fruit; the approach speed is that of the
drop).  Every member of the population meets every point once; the impacts
at different points land on different spots of the fruit (independent
impacts: bruise volumes add, a fruit is bruised on the line if it is bruised
at any point).  Per point: the bruise incidence (fraction of the fruit the
criterion calls bruised there), the mean bruise volume per fruit, the mean
peak force; cumulated along the line: the incidence of fruit bruised at least
once so far and the mean accumulated bruise volume.  The point that bruises
the most fruit (ties: the larger mean bruise volume) is named.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.library.textfiles import table_lines, yes_or_no

#: Columns of a line table; ``fruit_on_fruit`` is optional.
#: The optional columns of a measured surface (both or neither in a row; blank: the library surface's own).
MEASURED_SURFACE_COLUMNS = ("surface_modulus", "surface_poisson")
#: The columns of a line CSV: the first three required, the rest optional.
LINE_COLUMNS = ("name", "drop_height", "surface", "fruit_on_fruit", *MEASURED_SURFACE_COLUMNS)
#: Transfer points of a line at most.
MAX_POINTS = 200


@dataclass(frozen=True)
class TransferPoint:
    """One transfer point: where the fruit drops ``drop_height`` [m] onto ``surface``.

    ``surface_modulus`` [Pa] and ``surface_poisson`` [-], when given, are a measured half-space in place of the
    library surface's own values (an instrumented sphere's reading, ``spheres``); ``surface`` then names the
    library surface nearest to it, for the report."""

    name: str
    drop_height: float
    surface: str
    fruit_on_fruit: bool = False
    surface_modulus: float | None = None
    surface_poisson: float | None = None


def _points(line) -> list[TransferPoint]:
    """The transfer points of ``line``: a line file (a path) read by :func:`read_line`, or a non-empty sequence of
    :class:`TransferPoint`, each checked as a file's row is (``_checked_point``); ``InputError`` naming ``line``."""
    import os

    from fruitimpact.impact.validation import InputError

    if isinstance(line, (str, os.PathLike)):
        return read_line(line)
    if not isinstance(line, (list, tuple)) or not line or not all(isinstance(p, TransferPoint) for p in line):
        raise InputError("line must be a line CSV (a path) or a non-empty list of TransferPoint; got "
                         f"{type(line).__name__}", "line")
    if len(line) > MAX_POINTS:
        raise InputError(f"line has {len(line)} transfer points; at most {MAX_POINTS}", "line")
    try:
        return _distinct([_checked_point(point, f"transfer point {point.name!r}") for point in line], "line")
    except ValueError as exc:
        raise InputError(str(exc), "line") from None


def measured_surface(cells: dict, where: str) -> tuple[float | None, float | None]:
    """(surface_modulus [Pa], surface_poisson [-]) of a row's cells (texts; units accepted: ``"2.5MPa"``), or
    (None, None) when the row gives neither (blank or absent): then the library surface's own values hold.
    ``ValueError`` naming ``where`` and the column otherwise (one without the other, not a number); the ranges are
    ``_checked_point``'s."""
    from fruitimpact.impact.units import parse_quantity

    texts = {column: str(cells.get(column, "") or "").strip() for column in MEASURED_SURFACE_COLUMNS}
    if not any(texts.values()):
        return None, None
    missing = next(column for column in MEASURED_SURFACE_COLUMNS if not texts[column]) \
        if not all(texts.values()) else None
    if missing is not None:
        given = next(column for column in MEASURED_SURFACE_COLUMNS if column != missing)
        raise ValueError(f"{where}: {missing} must be given with {given} (a measured half-space needs both; "
                         f"leave both blank for the library surface's own)")
    values = []
    for column, dimension in zip(MEASURED_SURFACE_COLUMNS, ("modulus", "dimensionless")):
        try:
            values.append(parse_quantity(texts[column], dimension))
        except ValueError as exc:
            raise ValueError(f"{where}: {column}: {exc}") from None
    return values[0], values[1]


def read_line(path) -> list[TransferPoint]:
    """The transfer points of a line CSV (header ``name,drop_height,surface[,fruit_on_fruit]
    [,surface_modulus,surface_poisson]``; ``#`` comment lines allowed).  ``surface_modulus`` [Pa, units accepted]
    and ``surface_poisson`` [-], given together, make the point's surface a measured half-space (e.g. an
    instrumented sphere's reading, ``fruitimpact sphere``), ``surface`` then naming it in the report.
    ``ValueError`` naming the line and the column of the first problem: unknown or missing columns, ragged rows,
    unknown surfaces, heights that are not positive, a modulus without its Poisson's ratio."""
    import csv
    import os

    if not isinstance(path, (str, os.PathLike)):  # an integer would be taken as a file descriptor, and closed
        raise ValueError(f"line must be a path to a line CSV; got {path!r}")
    lines = list(table_lines(path))
    reader = csv.reader(text for _, text in lines)
    rows, numbers = [], []  # each row and the file's line number it starts on (comment lines are counted)
    for row in reader:
        rows.append(row)
        numbers.append(lines[reader.line_num - 1][0])
    if not rows:
        raise ValueError(f"{path} is empty: expected a header {','.join(LINE_COLUMNS[:3])}"
                         f"[,{','.join(LINE_COLUMNS[3:])}]")
    header = [cell.strip().replace("-", "_") for cell in rows[0]]
    unknown = [cell for cell in header if cell not in LINE_COLUMNS]
    if unknown:
        raise ValueError(f"{path}: unknown column(s) {', '.join(map(repr, unknown))} (columns: "
                         f"{', '.join(LINE_COLUMNS)})")
    twice = [cell for k, cell in enumerate(header) if cell in header[:k]]
    if twice:
        raise ValueError(f"{path}: column {twice[0]!r} is given twice; give each column once")
    missing = [name for name in LINE_COLUMNS[:3] if name not in header]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
    if len(rows) < 2:
        raise ValueError(f"{path}: no transfer points below the header")
    if len(rows) - 1 > MAX_POINTS:
        raise ValueError(f"{path}: {len(rows) - 1} transfer points; at most {MAX_POINTS}")
    points = []
    for number, row in zip(numbers[1:], rows[1:]):
        where = f"{path}, line {number}"
        if len(row) != len(header):
            raise ValueError(f"{where}: {len(row)} fields, the header has {len(header)}")
        points.append(read_point(dict(zip(header, (cell.strip() for cell in row))), where))
    return _distinct(points, str(path))


def read_point(cells: dict, where: str) -> TransferPoint:
    """One transfer point from a row's cells as a line CSV holds them (texts: heights and moduli with units,
    ``fruit_on_fruit`` true/false/yes/no/1/0 or blank, or already a bool as the web page sends it), checked as every
    point is (``_checked_point``).  ``ValueError`` "<where>: <column> …" naming the first refused cell."""
    from fruitimpact.impact.units import parse_quantity

    try:
        height = parse_quantity(cells["drop_height"], "length")
    except ValueError as exc:
        raise ValueError(f"{where}: drop_height: {exc}") from None
    flag = cells.get("fruit_on_fruit", "")
    if not isinstance(flag, bool):
        answer = yes_or_no(flag, blank=False) if isinstance(flag, str) else None
        if answer is None:
            raise ValueError(f"{where}: fruit_on_fruit must be true or false; got {flag!r}")
        flag = answer
    modulus, poisson = measured_surface(cells, where)
    return _checked_point(TransferPoint(cells["name"], height, cells["surface"], flag, modulus, poisson), where)


def _distinct(points: list, where: str) -> list:
    """``points`` if their names differ: a report names each point (its figures, the changes), and two of one
    name could not be told apart.  ValueError otherwise."""
    seen = set()
    for point in points:
        if point.name in seen:
            raise ValueError(f"{where}: transfer point {point.name!r} is named twice; give each point its own name")
        seen.add(point.name)
    return points


def _checked_point(point: TransferPoint, where: str) -> TransferPoint:
    """A transfer point as a line accepts it, whether read from a file or given in Python; ValueError
    prefixed with ``where`` otherwise."""
    from fruitimpact.impact.registries import SURFACE_CHOICES

    if not isinstance(point.name, str) or not point.name:
        raise ValueError(f"{where}: name must be a non-empty text; got {point.name!r}")
    height = point.drop_height
    if isinstance(height, bool) or not isinstance(height, (int, float)) or not 0.0 < height <= MAX_POINT_HEIGHT:
        raise ValueError(f"{where}: drop_height must be in (0, {MAX_POINT_HEIGHT:g}] m; got {height!r}")
    if point.surface not in SURFACE_CHOICES or point.surface == "fruit":
        raise ValueError(f"{where}: surface must be one of {', '.join(s for s in SURFACE_CHOICES if s != 'fruit')}; "
                         f"got {point.surface!r} (fruit on fruit: set fruit_on_fruit to true)")
    if not isinstance(point.fruit_on_fruit, bool):
        raise ValueError(f"{where}: fruit_on_fruit must be True or False; got {point.fruit_on_fruit!r}")
    if (point.surface_modulus is None) != (point.surface_poisson is None):
        raise ValueError(f"{where}: a measured surface needs both surface_modulus and surface_poisson")
    if point.fruit_on_fruit and point.surface_modulus is not None:
        raise ValueError(f"{where}: surface_modulus is a measured surface, but fruit_on_fruit lands the fruit on "
                         f"another fruit: give one or the other")
    if point.surface_modulus is not None and not (
            isinstance(point.surface_modulus, float) and 0.0 < point.surface_modulus < math.inf):
        raise ValueError(f"{where}: surface_modulus must be > 0 Pa and finite; got {point.surface_modulus!r}")
    if point.surface_poisson is not None and not (
            isinstance(point.surface_poisson, float) and -1.0 < point.surface_poisson < 0.5):
        raise ValueError(f"{where}: surface_poisson must be in (-1, 0.5); got {point.surface_poisson!r}")
    return point


@dataclass(frozen=True)
class Pad:
    """A cushion of given properties tried as an alternative: a layer of ``modulus`` E [Pa], ``thickness`` h [m] and
    ``poisson`` ν [-] on a rigid floor (the library layers' Winkler model, k = (1−ν)E/((1+ν)(1−2ν)h));
    ``name`` labels it in the report."""

    name: str
    modulus: float
    thickness: float
    poisson: float = 0.3

    def inputs(self) -> dict:
        return {"surface": "rigid", "surface_model": "layer", "surface_modulus": self.modulus,
                "surface_thickness": self.thickness, "surface_poisson": self.poisson}


#: The surface tried in place of each transfer point's by default (``audit``'s ``alternatives``).
DEFAULT_ALTERNATIVES = ("foam-pad",)


def audit(points: list[TransferPoint], members: dict, rows: int, criterion: str, constants: dict,
          alternatives=DEFAULT_ALTERNATIVES) -> dict:
    """Pass ``rows`` fruit (``members``: input columns of the population) through ``points``.

    ``constants``: inputs shared by all (criterion inputs, model …).  Returns a dict with
    ``points`` (one dict per transfer point: ``name``, ``drop_height``, ``surface``,
    ``fruit_on_fruit``, ``surface_modulus`` and ``surface_poisson`` (a measured half-space, None for the library
    surface's own values), ``velocity``, ``incidence``, ``mean_bruise_volume``, ``mean_peak_force``,
    ``mean_max_pressure``, ``cumulative_incidence``, ``cumulative_bruise_volume``, ``invalid``,
    ``failed``), ``worst_point``, ``incidence`` (on the whole line), ``mean_bruise_volume``,
    ``criterion`` and ``warnings``.  A point's figures are over the fruit computed there; the
    cumulated ones over the fruit computed at every point so far (a warning counts the others).

    ``alternatives``: library surfaces (or :class:`Pad`) tried in place of each point's own (not at fruit-on-fruit
    points):
    ``changes`` lists, best first, each (point, surface) with the line's incidence and mean bruise volume
    with that one change and what it saves (the same fruit, so the saving is paired, not a sampling
    difference); ``point_incidence`` is the point's own incidence with the change."""
    from fruitimpact.impact.validation import InputError
    from fruitimpact.physics.constants import STANDARD_GRAVITY

    alternatives = checked_alternatives(alternatives)
    from fruitimpact.impact.evaluation import evaluation  # the engine only now: the arguments are answered without it
    bruised_any = np.zeros(rows, dtype=bool)
    volume_total = np.zeros(rows)
    valid_so_far = np.ones(rows, dtype=bool)  # fruit computed at every point so far: the cumulation's population
    report = []
    warnings = []
    noted: dict[str, list] = {}  # warning → [(transfer point, fruit)]
    per_point = []  # (bruised, volume) of each point, for the changes
    bruise_count = np.zeros(rows, dtype=np.int64)  # points where each fruit bruised

    def run(point, surface):
        table = {**members, **constants, "drop_height": np.full(rows, point.drop_height),
                 "surface": surface, "criterion": criterion}
        if surface is None:  # the point's measured half-space
            table.update(surface="rigid", surface_modulus=point.surface_modulus,
                         surface_poisson=point.surface_poisson)
        elif isinstance(surface, Pad):
            table.update(surface.inputs())
        return evaluation(table)

    for point in points:
        result = run(point, "fruit" if point.fruit_on_fruit else
                     None if point.surface_modulus is not None else point.surface)
        status = result.status
        ok = status == 0
        if not ok.any() and (status == 3).all():
            argument = result.messages.argument(0)  # a point's own input, or one of the whole lot
            where = f"transfer point {point.name!r}: " if argument in ("drop_height", "surface", "velocity") else ""
            raise InputError(f"{where}{result.messages.text(0)}", argument)
        bruised = np.where(ok, np.nan_to_num(result.columns["bruised"]), 0.0) > 0.5
        # a bruised fruit without a volume (no bruise susceptibility) leaves the mean volume unknown, never 0
        volume = np.where(bruised, result.columns["bruise_volume"], 0.0)
        per_point.append((bruised, volume))
        bruise_count += bruised
        bruised_any |= bruised
        volume_total += volume
        valid_so_far &= ok
        count = int(ok.sum())  # no fruit computed at a point: its figures are unknown (NaN), never 0
        for bit, text in enumerate(result.warnings.texts):  # the inputs' and the impacts' own warnings
            carrying = int(np.count_nonzero(result.warnings.masks >> bit & 1))
            noted.setdefault(text, []).append((point.name, carrying))
        if not ok.all():
            first = int(np.flatnonzero(~ok)[0])
            warnings.append(f"transfer point {point.name!r}: {int((~ok).sum())} of {rows} fruit not computed "
                            f"(invalid or failed; the first: {result.messages.text(first)}); the figures are of the "
                            f"others")
        kept = int(valid_so_far.sum())
        report.append({
            "name": point.name, "drop_height": point.drop_height, "surface": point.surface,
            "fruit_on_fruit": point.fruit_on_fruit,
            # a measured half-space in place of the library surface's values (None: the library's own)
            "surface_modulus": point.surface_modulus, "surface_poisson": point.surface_poisson,
            "velocity": math.sqrt(2.0 * STANDARD_GRAVITY * point.drop_height),
            "incidence": _share(bruised[ok].sum(), count),
            "mean_bruise_volume": _share(volume[ok].sum(), count),
            "mean_peak_force": float(np.mean(result.columns["peak_force"][ok])) if ok.any() else math.nan,
            "mean_max_pressure": float(np.mean(result.columns["max_pressure"][ok])) if ok.any() else math.nan,
            "cumulative_incidence": _share(bruised_any[valid_so_far].sum(), kept),
            "cumulative_bruise_volume": _share(volume_total[valid_so_far].sum(), kept),
            "invalid": int((status == 3).sum()), "failed": int((status == 2).sum()),
        })
    for text, where in noted.items():  # each warning once, with where and for how many fruit
        places = ", ".join(f"{name!r} ({count} of {rows})" for name, count in where)
        warnings.append(f"{text} (at {places})" if len(where) < len(points) else
                        f"{text} (at every transfer point, {max(c for _, c in where)} of {rows} fruit at most)")
    known = [i for i in range(len(report)) if not math.isnan(report[i]["incidence"])]
    worst = max(known, key=lambda i: (report[i]["incidence"], _or_zero(report[i]["mean_bruise_volume"]))) \
        if known else None
    kept = int(valid_so_far.sum())
    incidence = _share(bruised_any[valid_so_far].sum(), kept)
    mean_volume = _share(volume_total[valid_so_far].sum(), kept)
    changes = []
    for k, point in enumerate(points):
        if point.fruit_on_fruit:
            continue
        # what the other points do to each fruit: the same for every alternative at this point
        others_bruised = (bruise_count - per_point[k][0]) > 0
        others_volume = np.zeros(rows)
        for j, (_, v) in enumerate(per_point):
            if j != k:
                others_volume += v  # summed, not subtracted: a point's unknown (NaN) volume stays its own
        for surface in alternatives:
            if surface == point.surface and point.surface_modulus is None:
                continue
            result = run(point, surface)
            ok = (result.status == 0) & valid_so_far
            if not ok.any():
                continue
            bruised = np.where(ok, np.nan_to_num(result.columns["bruised"]), 0.0) > 0.5
            volume = np.where(bruised, result.columns["bruise_volume"], 0.0)
            changed = float((others_bruised | bruised)[ok].mean())
            changed_volume = float((others_volume + volume)[ok].mean())
            base = float(bruised_any[ok].mean())
            base_volume = float(volume_total[ok].mean())
            changes.append({"point": point.name, "from": point.surface,
                            "to": surface.name if isinstance(surface, Pad) else surface, "incidence": changed,
                            "point_incidence": float(bruised[ok].mean()),
                            "incidence_saved": base - changed, "mean_bruise_volume": changed_volume,
                            "bruise_volume_saved": base_volume - changed_volume, "fruit": int(ok.sum())})
    changes.sort(key=lambda c: (-c["incidence_saved"], -c["bruise_volume_saved"]))
    status, message = "ok", ""
    if kept == 0:  # no fruit went through the whole line: there is no line figure to report
        status = "failed"
        message = (f"no fruit of the {rows} was computed at every transfer point (each was invalid or failed at one "
                   f"of them; see the warnings): the line's incidence and bruise volume are unknown")
    return {"criterion": criterion, "fruit": rows, "fruit_computed": kept, "status": status, "message": message,
            "points": report, "worst_point": report[worst]["name"] if worst is not None else None,
            "incidence": incidence, "mean_bruise_volume": mean_volume, "changes": changes, "warnings": warnings}


def _share(total, count: int) -> float:
    """``total / count``, or NaN (unknown) when no fruit was counted."""
    return float(total / count) if count else math.nan


def _or_zero(value: float) -> float:
    return 0.0 if math.isnan(value) else value


__all__ = ["DEFAULT_ALTERNATIVES", "LINE_COLUMNS", "LINE_FRUIT", "MAX_LINE_FRUIT", "MAX_POINTS",
           "MEASURED_SURFACE_COLUMNS", "Pad", "TransferPoint", "audit", "audit_line", "measured_surface", "read_line",
           "read_point"]


#: Highest drop a transfer point may have [m] (the safe-height search's own ceiling, ``heights.HIGHEST``).
MAX_POINT_HEIGHT = 10.0
#: Most fruit of one line audit.
MAX_LINE_FRUIT = 10_000_000
#: Fruit in a line audit's lot by default (the command's and the function's).
LINE_FRUIT = 10_000


def checked_alternatives(alternatives) -> tuple:
    """The surfaces a line audit tries in place of each point's own: library surfaces that are no free partner,
    or :class:`Pad`; each once, in the order given.  ``InputError`` naming ``alternatives`` otherwise."""
    from fruitimpact.impact.validation import InputError
    from fruitimpact.library.catalogue import surfaces

    if isinstance(alternatives, str) or not all(isinstance(a, (str, Pad)) for a in alternatives):
        raise InputError("alternatives must be a sequence of library surface names (or Pad)", "alternatives")
    cushions = [name for name, entry in surfaces().items() if entry.partner is None]
    unknown = [a for a in alternatives if isinstance(a, str) and a not in cushions]
    if unknown:
        raise InputError(f"alternatives must be library surfaces ({', '.join(cushions)}); got {unknown[0]!r}",
                         "alternatives")
    return tuple(dict.fromkeys(alternatives))


def audit_line(line, *, rows: int = LINE_FRUIT, seed: int = 0, criterion: str | None = None,
               alternatives=DEFAULT_ALTERNATIVES, spreads: bool = True, **inputs) -> dict:
    """Audit a handling line: pass a lot of ``rows`` fruit through its transfer points and count the bruises.

    The lot is drawn reproducibly (:mod:`fruitimpact.impact.lots`): inputs given as numbers are fixed,
    inputs given as distributions (``"normal(3MPa, 0.4MPa)"``, ``"uniform(100g, 140g)"``; the syntax of
    ``population``) are drawn, and, unless ``spreads`` is False, the fruit's own library spreads are
    drawn for the inputs not given (mass with the diameter following it, modulus, and with a criterion
    the failure stress and bruise susceptibility).

    Parameters
    ----------
    line : str, path or list of TransferPoint
        A line CSV (``name,drop_height,surface[,fruit_on_fruit][,surface_modulus,surface_poisson]``, see
        :func:`read_line`) or its points.
    rows : int
        Fruit in the lot, 1 to 10,000,000 (default 10,000; ``"1e5"`` accepted).
    seed : int
        Seed of the lot's draws (≥ 0): the same seed gives the same fruit.
    criterion : str, optional
        ``pressure``, ``shear`` or ``energy``; None or ``preset``: the one the literature supports for
        the fruit (its library entry).
    alternatives : sequence of str
        Library surfaces tried in place of each point's own; the report ranks each change by what it saves.
    spreads : bool
        Draw the fruit's library spreads for the inputs not given (default); False: identical fruit.
    **inputs
        Inputs of ``quantities.INPUTS`` (``fruit``, ``model``, ``mass`` …), as numbers, unit strings or
        distributions; not ``velocity``, ``drop_height`` or ``surface`` (set by each transfer point).

    Returns
    -------
    dict
        The report of :func:`audit` (``points``, ``worst_point``, ``incidence``, ``mean_bruise_volume``,
        ``changes``, ``criterion``, ``warnings``) with ``rows``, ``seed``, ``inputs`` (each drawn input's
        distribution) and ``spreads`` (the library spreads used, as text).

    Raises
    ------
    ValueError
        An unknown input, a value or distribution out of range, a line file that cannot be read, a fruit
        with no criterion of its own when none is given; the message names the argument.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.audit_line("examples/line.csv", rows=2000, fruit="apple")  # doctest: +SKIP
    >>> report["worst_point"]  # doctest: +SKIP

    References
    ----------
    The bruise criteria and volumes: :mod:`fruitimpact.damage.bruise` (docs/bruise.md); the lot spreads:
    docs/library.md.
    """
    from fruitimpact.handling.heights import AXIS_INPUTS
    from fruitimpact.impact.lots import MAX_SEED, lot_details, read_lot
    from fruitimpact.impact.presets import fruit_criterion
    from fruitimpact.impact.validation import InputError, check_flag, read_count

    spreads = check_flag("spreads", spreads)
    rows = read_count("rows", rows, 1, MAX_LINE_FRUIT)
    seed = read_count("seed", seed, 0, MAX_SEED)
    points = _points(line)
    criterion = fruit_criterion(inputs.get("fruit"), criterion, "a line audit")
    if isinstance(alternatives, str):
        alternatives = () if alternatives.strip().lower() == "none" else \
            tuple(a.strip() for a in alternatives.split(","))
        if any(not a for a in alternatives):
            raise InputError("alternatives must be library surface names, comma-separated, or none", "alternatives")
    alternatives = checked_alternatives(alternatives)
    # every input checked (with the criterion) before the lot is drawn; each point sets its height and surface
    source, constants, described = read_lot(inputs, rows=rows, seed=seed, spreads=spreads, criterion=criterion,
                                            excluded=("velocity", "drop_height", *AXIS_INPUTS["surface"]),
                                            excluded_reason="is set by each transfer point of the line")
    members, _ = source.inputs(0, rows, None)
    report = audit(points, members, rows, criterion, constants, tuple(alternatives))
    report.update(rows=rows, **lot_details(source, described))
    return report
