"""Safe drop heights: the greatest height from which the fruit does not bruise, by root finding.

The bruise margin of an impact (``bruise_margin``: the criterion's stress or
energy over its threshold, minus 1) rises with the drop height; the safe drop
height is its root, found on the logarithm of the height by the Illinois
variant of regula falsi (bracketed, superlinear) on all rows of a table at
once: every iteration is one ``impact.evaluation.evaluate`` of the table.  It is a root,
not a scan: to a relative tolerance of 1e-9 in h.

Checked (tests/test_damage.py) against the closed form of elastic Hertz on a
rigid flat, h = π⁴ p⁵ / (80 g ρ E*⁴) (p = σ_f for the pressure criterion,
p = σ_f p_0/Y(ν) for the shear criterion): independent of the fruit's size,
with d ln h/d ln E = −4 and d ln h/d ln σ_f = 5.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.impact.status import STATUS_NAMES
from fruitimpact.physics.constants import STANDARD_GRAVITY

#: The heights searched [m]: below the lowest the fruit bruises "from any height", above the highest never.
LOWEST, HIGHEST = 1e-5, 10.0
#: Relative tolerance of the root.
TOLERANCE = 1e-9
#: Relative step of the sensitivities (central differences; h is a smooth power of each input).
SENSITIVITY_STEP = 0.01
#: The inputs whose elasticity d ln h / d ln x is reported, by criterion.
SENSITIVITY_INPUTS = {"pressure": ("modulus", "mass", "failure_stress"),
                      "shear": ("modulus", "mass", "failure_stress"),
                      "energy": ("modulus", "mass", "bruise_energy")}


def _margins(table: dict, heights: np.ndarray):
    """(ln(1 + margin), the evaluation) at ``heights``: ln of the criterion's stress (or energy) over its
    threshold, whose root is the margin's.  In ln h it is nearly a straight line (an elastic Hertz impact's
    stresses go as h^(1/5), its energy as h), so the secant steps of ``safe_heights`` converge in a few
    evaluations where the margin itself, bent, took ten."""
    from fruitimpact.impact.evaluation import evaluation

    result = evaluation({**table, "drop_height": heights})
    margin = np.asarray(result.columns["bruise_margin"], dtype=float)
    with np.errstate(divide="ignore"):
        return np.log1p(np.maximum(margin, -1.0)), result


def _rows_of(table: dict, index: np.ndarray, rows: int) -> dict:
    """The rows ``index`` of ``table`` (a column ``rows`` long is cut, a constant kept)."""
    if index.size == rows:
        return table
    cut = {}
    for name, value in table.items():
        if isinstance(value, np.ndarray) and value.ndim == 1 and value.shape[0] == rows:
            cut[name] = value[index]
        elif isinstance(value, (list, tuple)) and len(value) == rows:
            cut[name] = [value[i] for i in index]
        else:
            cut[name] = value
    return cut


def safe_heights(table: dict, rows: int) -> tuple[np.ndarray, list]:
    """Safe drop height [m] of every row of ``table`` (columns of inputs, ``rows`` long, with a
    ``criterion``; no velocity or drop height), and a message per row ("ok", or why not).

    A row that bruises even from ``LOWEST`` gets 0, one that does not bruise from ``HIGHEST``
    gets inf, an invalid row NaN (its message says why)."""
    low = np.full(rows, math.log(LOWEST))
    high = np.full(rows, math.log(HIGHEST))
    f_low, first = _margins(table, np.exp(low))
    f_high, last = _margins(table, np.exp(high))
    messages = ["ok"] * rows
    heights = np.full(rows, np.nan)
    status = first.status
    active = np.ones(rows, dtype=bool)
    for i in range(rows):
        if status[i] != 0 or last.status[i] != 0 or math.isnan(f_low[i]) or math.isnan(f_high[i]):
            text = first.messages.text(i) if status[i] != 0 else last.messages.text(i)
            messages[i] = text if text and text != "ok" else "no bruise margin: give a criterion (pressure, shear, energy)"
            active[i] = False
        elif f_low[i] >= 0.0:
            heights[i], messages[i] = 0.0, f"bruises from any height: already at {LOWEST * 1e3:g} mm"
            active[i] = False
        elif f_high[i] < 0.0:
            heights[i], messages[i] = math.inf, f"no bruise up to {HIGHEST:g} m"
            active[i] = False
    side = np.zeros(rows, dtype=np.int8)
    previous = np.full(rows, np.nan)  # the last secant point: two within TOLERANCE end the search there
    estimate = np.full(rows, np.nan)
    for _ in range(200):
        if not active.any():
            break
        x = np.where(active, high - f_high * (high - low) / (f_high - f_low), 0.5 * (low + high))
        # regula falsi converges from one side: the far end of the bracket stays where it is, so the bracket's
        # width does not shrink although the points have converged (36 evaluations on a straight line); two
        # secant points within TOLERANCE end the search (before the check below, which would send a point that
        # converged onto the bracket's end to the bisection)
        settled = active & np.isfinite(x) & (np.abs(x - previous) <= TOLERANCE)
        estimate[settled] = x[settled]
        bad = ~((x > low) & (x < high))
        x[bad] = 0.5 * (low[bad] + high[bad])
        active &= ~settled
        previous = np.where(active & ~bad, x, np.nan)
        if not active.any():
            break
        # only the rows still searching are evaluated (rows are independent: the same numbers, fewer impacts)
        searching = np.flatnonzero(active)
        f_searching, step = _margins(_rows_of(table, searching, rows), np.exp(x[searching]))
        f_x = np.full(rows, np.nan)
        f_x[searching] = f_searching
        failed = np.zeros(rows, dtype=bool)
        failed[searching] = (step.status != 0) | np.isnan(f_searching)
        where = np.full(rows, -1)
        where[searching] = np.arange(searching.size)
        # a row whose evaluation inside the bracket failed has no margin there: it is not a root, and its NaN
        # must not count as "no bruise" (that narrowed the bracket onto a wrong height reported as ok)
        lost = active & failed
        for i in np.flatnonzero(lost):
            text = step.messages.text(int(where[i]))
            messages[i] = (f"the search failed at h = {math.exp(x[i]):.4g} m: "
                           f"{text if text and text != 'ok' else 'no bruise margin there'}")
            low[i] = high[i] = math.nan
        active &= ~lost
        hit = active & (f_x == 0.0)  # the root itself: a bracket end at 0 would stall the secant on that end
        estimate[hit] = x[hit]
        active &= ~hit
        above = f_x >= 0.0
        # Illinois: halve the retained end's value when the same end is kept twice
        keep_low = active & above
        keep_high = active & ~above
        f_low = np.where(keep_low & (side == -1), 0.5 * f_low, f_low)
        f_high = np.where(keep_high & (side == 1), 0.5 * f_high, f_high)
        high = np.where(keep_low, x, high)
        f_high = np.where(keep_low, f_x, f_high)
        low = np.where(keep_high, x, low)
        f_low = np.where(keep_high, f_x, f_low)
        side = np.where(keep_low, -1, np.where(keep_high, 1, side)).astype(np.int8)
        active &= (high - low) > TOLERANCE
    done = np.isnan(heights) & np.isfinite(low) & np.array([m == "ok" for m in messages])
    heights[done] = np.exp(np.where(np.isfinite(estimate), estimate, 0.5 * (low + high))[done])
    return heights, messages


def _checked_inputs(inputs: dict, finder: str, axis: tuple[str, ...] = ()):
    """(inputs, probe) of one safe-height question, checked as one row before any work (the same checks for
    :func:`safe_height` and :func:`risk_map`): no velocity or drop height (``finder`` finds it) nor an input
    of the map's ``axis`` (it would override the value each column names), no unknown input, a criterion (the
    fruit's own when none is given, issue 14 item 5c).  ``probe`` is the row's evaluation at 1 cm: its
    warnings are the inputs' own."""
    from fruitimpact.impact.presets import fruit_criterion
    from fruitimpact.impact.validation import InputError, check_input_name

    for name in ("velocity", "drop_height", *axis):
        if inputs.get(name) is not None:
            raise InputError(f"{name} is what {finder}: leave it out", name)
    for name in inputs:
        check_input_name(name)
    inputs = {**inputs, "criterion": fruit_criterion(inputs.get("fruit"), inputs.get("criterion"), "a safe height")}
    given = {name: value for name, value in inputs.items() if value is not None}
    return given, _check_row(given)


def _merged_warnings(result, what: str) -> list[str]:
    """Each distinct warning of an evaluation once, with how many of its rows (``what``) carry it."""
    rows = result.warnings.masks.size
    return [f"{text} ({int(np.count_nonzero(result.warnings.masks >> bit & 1))} of {rows} {what})"
            for bit, text in enumerate(result.warnings.texts)]


def safe_height(*, sensitivity: bool = True, **inputs) -> dict:
    """The safe drop height of one fruit on one surface [m], with its sensitivities.

    Parameters
    ----------
    sensitivity : bool
        Also compute the elasticities d ln h / d ln x of the modulus, the mass and the
        failure stress (or threshold energy), by central differences of ±1 %.
    **inputs
        Inputs of ``quantities.INPUTS`` (not the velocity or drop height), with a
        ``criterion`` (``pressure``, ``shear`` or ``energy``).

    Returns
    -------
    dict
        ``safe_height`` [m] (0: bruises from any height; inf: none up to 10 m),
        ``safe_velocity`` [m/s], ``criterion``, ``message``, ``sensitivity`` (name →
        elasticity), and the bruise figures at that height.

    Raises
    ------
    ValueError
        An input outside its range or unknown, ``velocity`` or ``drop_height`` given, ``criterion`` ``none``
        or a fruit whose library entry names no criterion when none is given; the message names the argument.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.safe_height(fruit="apple", surface="steel", criterion="shear")
    >>> round(report["safe_height"] * 100, 1)  # [cm]
    3.3

    References
    ----------
    Onset of bruising under the Hertz contact: K. L. Johnson, *Contact Mechanics* (1985) eq 3.45 and §11.4;
    the shear criterion after Yuwana & Duprat (1998); docs/bruise.md.
    """
    from fruitimpact.impact.validation import check_flag

    sensitivity = check_flag("sensitivity", sensitivity)
    given, base = _checked_inputs(inputs, "safe-height finds")
    criterion = given["criterion"]
    names = SENSITIVITY_INPUTS.get(criterion, ())
    cases = [given]
    if sensitivity:
        for name in names:
            value = float(base.columns[name][0])
            for factor in (1.0 + SENSITIVITY_STEP, 1.0 - SENSITIVITY_STEP):
                cases.append({**given, name: value * factor})
    table = {name: [case.get(name) for case in cases] for name in set().union(*cases)}
    heights, messages = safe_heights(table, len(cases))
    height = float(heights[0])
    report = {"safe_height": height, "safe_velocity": math.sqrt(2.0 * STANDARD_GRAVITY * height)
              if math.isfinite(height) else height, "criterion": criterion,
              "status": "failed" if math.isnan(height) else "ok", "message": messages[0],
              "warnings": base.warnings.row(0)}
    if sensitivity:
        report["sensitivity"] = {}
        for k, name in enumerate(names):
            up, down = heights[1 + 2 * k], heights[2 + 2 * k]
            ok = all(math.isfinite(v) and v > 0 for v in (up, down))
            report["sensitivity"][name] = (math.log(up / down) / math.log((1 + SENSITIVITY_STEP) /
                                                                         (1 - SENSITIVITY_STEP)) if ok else math.nan)
    if math.isfinite(height) and height > 0:
        from fruitimpact.impact.evaluation import evaluation

        at = evaluation({name: [value] for name, value in {**given, "drop_height": height}.items()})
        report["warnings"] += [text for text in at.warnings.row(0) if text not in report["warnings"]]
        if at.status[0] != 0:  # the height stands (its bracket was computed); the figures at it do not
            report["warnings"].append(f"the impact at the safe height is {STATUS_NAMES[int(at.status[0])]}: "
                                      f"{at.messages.text(0)}")
        for name in ("peak_force", "max_pressure", "max_shear_stress", "fruit_energy", "absorbed_energy",
                     "restitution", "failure_stress", "bruise_energy"):
            report[name] = float(at.columns[name][0])
    return report


def _check_row(given: dict):
    """The row's evaluation at 1 cm; bad inputs refused before the search, with the table's message."""
    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.impact.status import INVALID
    from fruitimpact.impact.validation import InputError

    probe = evaluation({name: [value] for name, value in {**given, "drop_height": 0.01}.items()})
    if probe.status[0] == INVALID:
        raise InputError(probe.messages.text(0), probe.messages.argument(0))
    return probe


__all__ = ["HIGHEST", "LOWEST", "SENSITIVITY_INPUTS", "safe_height", "safe_heights"]


#: Rows of a risk map: heights [m] from 5 mm to 2 m, log-spaced.
MAP_HEIGHTS = 30
#: Fruit of a risk map's lot by default, and at most (each is dropped at every grid point: 30 heights × up to
#: 10 columns).
MAP_FRUIT = 200
MAX_MAP_FRUIT = 20_000
#: The shares of a lot whose drop heights a risk map reports per column.
MAP_SHARES = (0.1, 0.5)
#: Moduli of a firmness map [Pa].
MAP_MODULI = (1e6, 1.5e6, 2e6, 2.5e6, 3e6, 4e6, 5e6, 6e6, 8e6, 10e6)
#: What a risk map can run across (the ``--map`` choices) → the input it varies.
MAP_AXES = {"surface": "surface", "firmness": "modulus"}
#: The inputs each axis sets: giving one would override the value a column names.
AXIS_INPUTS = {"surface": ("surface", "surface_model", "surface_modulus", "surface_poisson", "surface_radius",
                           "surface_thickness", "surface_crush_stress", "partner_mass"),
               "modulus": ("modulus", "stiffness")}


def risk_map(*, by: str = "surface", rows: int = MAP_FRUIT, seed: int = 0, spreads: bool = True, **inputs) -> dict:
    """A bruise-risk map: drop height × library surface, or drop height × fruit modulus, with the safe
    height of each column, from one evaluation of the whole grid and one root search.

    Parameters
    ----------
    by : str
        ``"surface"`` (every library surface but the rigid plane) or ``"firmness"`` (the fruit modulus over
        ``MAP_MODULI``, 1–10 MPa).
    rows : int
        Fruit of the lot dropped at every grid point (default ``MAP_FRUIT``, 200; at most ``MAX_MAP_FRUIT``;
        0: none, the typical fruit only).  The lot is drawn once, reproducibly (``seed``), as ``population``
        and a line audit draw it: the inputs given are fixed, and unless ``spreads`` is False the fruit's
        library spreads are drawn for the inputs not given (issue 14 item 4).  The same fruit fall at every point, so a point's incidence never falls with height where
        each fruit's stress rises with its speed.
    seed : int
        Seed of the lot's draws (≥ 0).
    spreads : bool
        Draw the fruit's library spreads for the inputs not given (default); False: a lot of identical fruit.
    **inputs
        As for :func:`safe_height` (fruit, model, criterion, …; not the velocity, drop height or the
        mapped input), as numbers: each is fixed for the whole lot.

    Returns
    -------
    dict
        ``by`` (the input varied: ``surface`` or ``modulus``), ``columns`` (surface names or moduli [Pa]), ``heights`` (``MAP_HEIGHTS`` drop heights
        [m], 5 mm to 2 m, log-spaced), ``rows`` (one dict per grid point: the mapped value,
        ``drop_height``; the typical fruit's ``bruise_margin``, ``bruised``, ``bruise_volume`` [m³],
        ``peak_force`` [N] and ``status``; with a lot, ``incidence`` (the share of the lot bruised there) and
        ``mean_bruise_volume`` [m³] over the lot), ``safe_height`` (column → the typical fruit's safe height
        [m]) and, with a lot, ``incidence_heights`` (column → {"10%": h, "50%": h}: the drop height above which
        that share of the lot bruises [m], the order statistic of each fruit's own safe height; inf: not up to
        10 m; NaN: unknown) and
        ``lot`` (``rows``, ``seed``, ``inputs``: each drawn input's distribution, ``spreads``: the library
        spreads used, as text).

    Raises
    ------
    ValueError
        An unknown axis or input, or an input outside its range (the message names it).

    Examples
    --------
    >>> import fruitimpact as fi
    >>> risk = fi.risk_map(by="surface", fruit="apple", criterion="shear")
    >>> sorted(risk["safe_height"])[:2]  # doctest: +SKIP

    References
    ----------
    As :func:`safe_height`.
    """
    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.impact.lots import MAX_SEED, read_lot
    from fruitimpact.impact.registries import SURFACE_CHOICES
    from fruitimpact.impact.validation import InputError, check_flag, read_count

    if by not in MAP_AXES:
        raise InputError(f"by must be one of {', '.join(MAP_AXES)}; got {by!r}", "map")
    key = MAP_AXES[by]
    fruit = read_count("rows", rows, 0, MAX_MAP_FRUIT)
    seed = read_count("seed", seed, 0, MAX_SEED)
    spreads = check_flag("spreads", spreads)
    base, _ = _checked_inputs(inputs, "the risk map spans", axis=AXIS_INPUTS[key])
    lot = read_lot(inputs, rows=fruit, seed=seed, spreads=spreads, criterion=base["criterion"],
                   excluded=("velocity", "drop_height", *AXIS_INPUTS[key]), fixed=AXIS_INPUTS[key],
                   excluded_reason="is what the risk map spans: leave it out") if fruit else None
    heights = np.geomspace(5e-3, 2.0, MAP_HEIGHTS)
    columns = [name for name in SURFACE_CHOICES if name != "rigid"] if key == "surface" else list(MAP_MODULI)
    by = key
    n = len(columns) * heights.size
    table = {name: [value] * n for name, value in base.items()}
    table[by] = [c for c in columns for _ in heights]
    table["drop_height"] = [h for _ in columns for h in heights]
    result = evaluation(table)
    rows = [{by: table[by][i], "drop_height": table["drop_height"][i],
             "bruise_margin": float(result.columns["bruise_margin"][i]),
             "bruised": float(result.columns["bruised"][i]),
             "bruise_volume": float(result.columns["bruise_volume"][i]),
             "peak_force": float(result.columns["peak_force"][i]),
             "status": "ok" if result.status[i] == 0 else result.messages.text(i)} for i in range(n)]
    safe_table = {name: [value] * len(columns) for name, value in base.items()}
    safe_table[by] = columns
    safe, _ = safe_heights(safe_table, len(columns))
    report = {"by": by, "columns": columns, "heights": heights, "rows": rows,
              "warnings": _merged_warnings(result, "grid points"),
              "safe_height": {str(c): float(h) for c, h in zip(columns, safe)}}
    if fruit:
        figures, warnings = _lot_incidence(lot, by, columns, heights, rows, base["criterion"], report["warnings"])
        report.update(figures)
        report["warnings"] += warnings
    return report


def _lot_incidence(lot, by: str, columns, heights, grid_rows: list, criterion: str, known: list) -> tuple[dict, list]:
    """Drop the lot (``(source, constants, described)`` of ``impact.lots.read_lot``) at every grid point: each
    point's ``incidence`` and ``mean_bruise_volume`` into ``grid_rows``; per column the drop heights at which
    ``MAP_SHARES`` of the lot bruise, as order statistics of each fruit's own safe height (exact, not
    interpolated between grid heights): (the ``risk_map`` keys, the lot's warnings).  Of the lot's evaluations'
    own warnings only those not ``known`` already (the typical fruit's grid) are said: a spread fruit's, e.g. one
    that leaves Hertz's range where the typical one does not."""
    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.impact.lots import lot_details

    source, constants, described = lot
    fruit = source.rows
    members, _ = source.inputs(0, fruit, None)
    tiled = {name: np.tile(values, heights.size) for name, values in members.items()}
    drop = np.repeat(heights, fruit)
    warnings, crossing = [], {}
    noted: dict[str, int] = {}  # the lot's own warnings (inputs, impacts) → fruit-drops carrying them
    # each fruit's own safe height on every column, in one root search over them all (each iteration is one
    # evaluation of the whole table)
    onsets_all, _ = safe_heights({**{name: np.tile(values, len(columns)) for name, values in members.items()},
                                  **constants, "criterion": criterion, by: [column for column in columns
                                                                            for _ in range(fruit)]},
                                 fruit * len(columns))
    for c, column in enumerate(columns):
        result = evaluation({**tiled, **constants, "criterion": criterion, by: column, "drop_height": drop})
        ok = (result.status == 0).reshape(heights.size, fruit)
        bruised = np.where(ok, np.nan_to_num(result.columns["bruised"]).reshape(heights.size, fruit), 0.0) > 0.5
        volume = np.where(bruised, result.columns["bruise_volume"].reshape(heights.size, fruit), 0.0)
        counted = ok.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):  # a point where no fruit was computed: unknown
            incidence = np.where(counted > 0, bruised.sum(axis=1) / counted, np.nan)
            mean_volume = np.where(counted > 0, volume.sum(axis=1) / counted, np.nan)
        for h in range(heights.size):
            grid_rows[c * heights.size + h].update(incidence=float(incidence[h]),
                                                   mean_bruise_volume=float(mean_volume[h]))
        for bit, text in enumerate(result.warnings.texts):
            noted[text] = noted.get(text, 0) + int(np.count_nonzero(result.warnings.masks >> bit & 1))
        if not ok.all():
            warnings.append(f"{column}: {int((~ok).sum())} of {ok.size} fruit-drops not computed (the first: "
                            f"{result.messages.text(int(np.flatnonzero(~ok.ravel())[0]))}); the shares are of the "
                            f"others")
        onsets = onsets_all[c * fruit:(c + 1) * fruit]
        crossing[str(column)] = {f"{share:.0%}": _height_of_share(onsets, share) for share in MAP_SHARES}
        missing = int(np.isnan(onsets).sum())
        if missing:
            warnings.append(f"{column}: the safe height of {missing} of {fruit} fruit was not found; the heights "
                            f"of {' and '.join(f'{share:.0%}' for share in MAP_SHARES)} incidence are of the others")
    drops = fruit * heights.size * len(columns)
    warnings += [f"{text} ({count} of {drops} fruit-drops of the lot)" for text, count in noted.items()
                 if not any(line.startswith(text + " (") for line in known)]
    return {"incidence_heights": crossing, "lot": {"rows": fruit, **lot_details(source, described)}}, warnings


def _height_of_share(onsets: np.ndarray, share: float) -> float:
    """The drop height [m] above which ``share`` of the lot bruises: the order statistic k = ⌈share × n⌉ of the
    fruit's own safe heights ``onsets`` (NaN ones left out: their search failed); inf: that share does not
    bruise up to 10 m; NaN: no fruit's safe height was found."""
    known = np.sort(onsets[~np.isnan(onsets)])
    if not known.size:
        return math.nan
    return float(known[max(int(math.ceil(share * known.size)) - 1, 0)])
