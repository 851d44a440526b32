"""A sphere's log → equivalent drops per transfer point → the bruises of the user's own lot there.

``sphere_audit`` reads the log (``spheres.log``), inverts every reading (``spheres.inversion``), groups the
readings into transfer points and passes (``spheres.points``) and, per point, takes

* the **drop of each pass**: the largest equivalent drop of each visit (the sphere's landing; the smaller
  readings of a visit are its bounces there) — ``drop_height`` is their median over the passes,
  ``drop_height_max`` the largest equivalent drop of any reading of the point;
* the **surface**: the median surface modulus of those landings, or *rigid* when most of them are rigid to
  the sphere (their modulus cannot be measured by it); ``surface`` names the library surface on which the
  same sphere, dropped from that height, would read the nearest peak acceleration (on a rigid point: the
  stiffest half-space, since all stiff ones read alike), ``surfaces_alike`` those it cannot tell apart.

The lot (``line``'s options: ``fruit``, ``mass`` …, ``rows``, ``seed``, ``criterion``, the fruit's library
spreads) is then dropped at every point as ``line`` drops it (``handling.line.audit``: same engine, same
criteria, same lot): from the point's median drop height onto the measured half-space, or onto the named
library surface where the sphere found it rigid.  Hence a point's incidence equals ``line`` on the same drop
and surface.  **Cushion advice**: for each point whose incidence is above ``target``, the thinnest cushion of
the library that brings the point below it (laid on the point's surface, taken as rigid under the cushion)
and the fruit it saves per 10,000.
"""

from __future__ import annotations

import math

import numpy as np

#: A trace's pulse whose Hunt–Crossley fit misses it by more than this share of its peak (rms, and by more
#: than ``log.SHAPE_NOISE`` noise sd) is not the sphere's impact on a half-space (the fit of a clean pulse misses
#: by its noise alone; the library foam pad's bottoming, hit by a 312 g sphere from 10 and 30 cm, by 8 % and
#: 1.6 %).
SHAPE_MISFIT = 0.01
#: Incidence above which a point gets cushion advice, by default.
TARGET = 0.05


def _nearest_surfaces(sphere, velocity, restitution, peak, rigid, spread) -> list[tuple[str, list[str]]]:
    """Per point, (the nearest library surface, the surfaces alike): the engine drops ``sphere`` at ``velocity``
    [m/s] with ``restitution`` on every library surface; those whose peak acceleration lies within ``spread``
    (the readings' relative 95 % uncertainty) of the point's ``peak`` [m/s²] read alike to this sphere.  The
    nearest is the one of least peak misfit — except on a point ``rigid`` to the sphere, where every stiff
    half-space reads alike (steel, concrete, wood: none deforms beside a fruit or the sphere) and the noise alone
    would pick among them: there it is the stiffest half-space."""
    from fruitimpact.impact.evaluation import evaluation
    from fruitimpact.library.catalogue import surfaces

    library = surfaces()
    names = [name for name, entry in library.items() if entry.partner is None]
    count = len(velocity)
    table = {"mass": np.full(count * len(names), sphere.mass), "diameter": np.full(count * len(names), sphere.diameter),
             # the sphere's own contact modulus E*_s = E_s/(1 − ν_s²) enters through E = E*_s and ν = 0
             "modulus": np.full(count * len(names), sphere.contact_modulus), "poisson": np.zeros(count * len(names)),
             "velocity": np.repeat(velocity, len(names)), "restitution": np.repeat(restitution, len(names)),
             "surface": np.tile(np.array(names, dtype=object), count)}
    result = evaluation(table)
    predicted = np.asarray(result.columns["peak_force"], dtype=float).reshape(count, len(names)) / sphere.mass
    with np.errstate(invalid="ignore", divide="ignore"):
        misfit = np.abs(np.log(predicted / np.asarray(peak)[:, None]))
    misfit = np.where(np.isfinite(misfit), misfit, np.inf)
    stiffness = {name: (entry.modulus.value / (1.0 - entry.poisson.value ** 2) if entry.model == "half-space"
                        else -math.inf) for name, entry in library.items() if entry.partner is None}
    answers = []
    for row, is_rigid in zip(misfit, rigid):
        alike = [names[k] for k in np.argsort(row) if row[k] <= spread]
        if is_rigid:
            candidates = [name for name in (alike or names) if library[name].model == "half-space"] or \
                [name for name in names if library[name].model == "half-space"]
            answers.append((max(candidates, key=stiffness.get), alike))
        else:
            answers.append((names[int(np.argmin(row))], alike))
    return answers


def sphere_audit(log, *, sphere: str | None = None, sphere_mass=None, sphere_diameter=None, sphere_modulus=None,
                 sphere_poisson=None, sphere_calibration=None, sphere_restitution=None, surface_poisson=0.3,
                 columns=None, points=None, point_gap=None, pass_gap=None, uncertainty=None, logger_rate=None,
                 target=TARGET, pad=None, rows=None, seed: int = 0, criterion: str | None = None, spreads: bool = True,
                 chart: bool = False, **inputs) -> dict:
    """Audit a handling line from an instrumented sphere's log: equivalent drops, surfaces and the lot's bruises.

    Parameters
    ----------
    log : str or path
        The sphere's log, CSV: ``time`` [s], ``peak_acceleration`` [g], ``velocity_change`` [m/s], optionally
        ``duration`` [s] and ``point``; or a raw trace ``time``, ``acceleration`` [g] (``spheres.log``).
    sphere : str, optional
        A built-in device profile (``spheres.devices.DEVICES``): its mass and diameter.
    sphere_mass, sphere_diameter : float or str
        [kg], [m] (units accepted: ``"312g"``, ``"89mm"``); override the profile's.
    sphere_modulus, sphere_poisson : float or str
        E_s [Pa] and ν_s [-] of the sphere; or instead ``sphere_calibration``.
    sphere_calibration : str or path, optional
        Drops of the sphere onto a rigid plate (``drop_height``, ``peak_acceleration``, ``velocity_change``,
        optionally ``duration``): its stiffness is fitted (``spheres.calibration``).
    sphere_restitution : float, optional
        e of the impacts whose reading has no duration (then required: peak and ΔV alone leave e open).
    surface_poisson : float
        ν of the surfaces [-] (0.3).
    columns : str or dict, optional
        Our column names → the vendor's headers (``"peak_acceleration=G,velocity_change=dV:km/h"``).
    points : str or path, optional
        A file of time windows (``name,start,end``) when the log has no ``point`` column.
    point_gap, pass_gap : float or str
        [s] readings closer than ``point_gap`` are one visit (1 s); a gap over ``pass_gap`` starts a new pass
        (20 s).
    uncertainty : float or str
        Relative standard uncertainty of each reading (``"2%"``, the default).
    logger_rate : float or str, optional
        The logger's sample rate [Hz]: logged durations are rounded to its period.
    target : float or str
        Incidence above which a point gets cushion advice (``"5%"``).
    pad : str, optional
        A pad of given modulus and thickness tried with the library's cushions, ``"MODULUS:THICKNESS"``
        (``"0.3MPa:10mm"``; a layer on a rigid floor, Poisson ratio ``surface_poisson``).
    chart : bool
        Also compute the chart's incidence lines (``spheres.chart``: the readings at which 10 % and 50 % of the
        lot bruise, surface by surface), returned as ``chart``.
    rows, seed, criterion, spreads, **inputs
        The lot, as :func:`fruitimpact.audit_line` takes it (``fruit``, ``mass`` …; not ``velocity``,
        ``drop_height`` or the surface, which each point sets).

    Returns
    -------
    dict
        ``impacts`` (per reading: ``time``, ``point``, ``velocity``, ``drop_height``, ``restitution``,
        ``surface_modulus`` (None: rigid or not reproduced), ``status``, ``message``, the readings and 95 %
        intervals), ``points`` (per point: ``name``, ``passes``, ``impacts``, ``drop_height`` (median of the
        passes' landings), ``drop_height_max``, ``surface_modulus`` (median; None for rigid), ``surface``,
        ``incidence``, ``bruise_volume``, ``cumulative_incidence``, ``cushion``), ``worst_point``, ``sphere``,
        ``calibration``, the lot (``rows``, ``seed``, ``criterion``, ``spreads``), ``skipped``, ``warnings``,
        ``status`` and ``message``.

    Raises
    ------
    ValueError
        Any option out of range or missing (the sphere's stiffness, ``sphere_restitution`` for readings without a
        duration), a log or file that cannot be read or has no usable row; the message names the argument.

    References
    ----------
    Hunt & Crossley 1975; Johnson 1985, Contact Mechanics §4.2; the founding paper, "Theoretical aspects about
    simulating the reaction to impact of apples on rigid plane surfaces"; docs/tasks/sphere.md.
    """
    from fruitimpact.handling.heights import AXIS_INPUTS
    from fruitimpact.handling.line import LINE_FRUIT, MAX_LINE_FRUIT, MAX_POINT_HEIGHT, Pad, TransferPoint, audit_line
    from fruitimpact.impact.lots import MAX_SEED, read_lot
    from fruitimpact.impact.presets import fruit_criterion
    from fruitimpact.impact.units import parse_quantity
    from fruitimpact.impact.validation import InputError, check_flag, check_number, read_count
    from fruitimpact.library.catalogue import surfaces
    from fruitimpact.spheres.calibration import read_calibration, read_calibration_table
    from fruitimpact.spheres.devices import build_sphere
    from fruitimpact.spheres.inversion import DEFAULT_UNCERTAINTY, Z95, invert
    from fruitimpact.spheres.log import read_log
    from fruitimpact.spheres.points import PASS_GAP, POINT_GAP, group, read_windows

    def quantity(name, value, dimension, default=None):
        if value is None:
            return default
        try:
            return parse_quantity(value, dimension)
        except ValueError as exc:
            raise InputError(f"{name}: {exc}", name) from None

    # every argument answered before any work
    spreads = check_flag("spreads", spreads)
    chart = check_flag("chart", chart)
    rows = read_count("rows", LINE_FRUIT if rows is None else rows, 1, MAX_LINE_FRUIT)
    seed = read_count("seed", seed, 0, MAX_SEED)
    mass = quantity("sphere_mass", sphere_mass, "mass")
    diameter = quantity("sphere_diameter", sphere_diameter, "length")
    modulus = quantity("sphere_modulus", sphere_modulus, "modulus")
    poisson = quantity("sphere_poisson", sphere_poisson, "dimensionless")
    restitution = quantity("sphere_restitution", sphere_restitution, "dimensionless")
    if restitution is not None:
        check_number("sphere_restitution", restitution, low=0.0, low_inclusive=False, high=1.0, high_inclusive=True)
    nu = check_number("surface_poisson", quantity("surface_poisson", surface_poisson, "dimensionless"), low=-1.0,
                      low_inclusive=False, high=0.5)
    point_gap = check_number("point_gap", quantity("point_gap", point_gap, "time", POINT_GAP), low=0.0,
                             low_inclusive=False, high=3600.0, high_inclusive=True)
    pass_gap = check_number("pass_gap", quantity("pass_gap", pass_gap, "time", PASS_GAP), low=point_gap,
                            low_inclusive=False, high=86400.0, high_inclusive=True)
    error = check_number("uncertainty", quantity("uncertainty", uncertainty, "dimensionless", DEFAULT_UNCERTAINTY),
                         low=1e-4, high=0.5, high_inclusive=True)  # a reading is never exact
    rate = quantity("logger_rate", logger_rate, "frequency")
    if rate is not None:
        check_number("logger_rate", rate, low=10.0, high=1e7, high_inclusive=True)
    target = check_number("target", quantity("target", target, "dimensionless"), low=0.0, high=1.0)
    extra = []
    if pad is not None:
        modulus_text, colon, thickness_text = str(pad).partition(":")
        if not colon:
            raise InputError(f"pad must be MODULUS:THICKNESS, e.g. 0.3MPa:10mm; got {pad!r}", "pad")
        pad_modulus = check_number("pad", quantity("pad", modulus_text.strip(), "modulus"), low=1e3, high=1e11)
        pad_thickness = check_number("pad", quantity("pad", thickness_text.strip(), "length"), low=1e-4, high=0.5,
                                     high_inclusive=True)
        extra.append(Pad(f"pad {pad_modulus / 1e6:.4g} MPa {pad_thickness * 1e3:.4g} mm", pad_modulus, pad_thickness,
                         nu))
    criterion = fruit_criterion(inputs.get("fruit"), criterion, "a sphere audit")
    # the files before the lot: the lot is checked by an evaluation of one row (the engine, numba: ~0.5 s), and a
    # log that is not there is answered at once
    try:
        windows = read_windows(points) if points is not None else None
    except ValueError as exc:
        raise InputError(str(exc), "points") from None
    try:
        readings = read_log(log, columns)
    except ValueError as exc:
        raise InputError(f"log: {exc}" if not str(exc).startswith("columns") else str(exc),
                         "columns" if str(exc).startswith("columns") else "log") from None
    # the sphere and its calibration file before the lot too (the calibration's fit comes after it)
    calibration = table = None
    if sphere_calibration is not None:
        # a modulus given beside a calibration is refused here ("not both"), as after the fit
        probe = build_sphere(device=sphere, mass=mass, diameter=diameter, modulus=modulus, poisson=poisson,
                             calibrated_modulus=1.0)
        try:
            table = read_calibration_table(sphere_calibration)
        except ValueError as exc:
            raise InputError(str(exc), "sphere_calibration") from None
    else:
        body = build_sphere(device=sphere, mass=mass, diameter=diameter, modulus=modulus, poisson=poisson)
    read_lot(inputs, rows=1, seed=seed, spreads=spreads, criterion=criterion,
             excluded=("velocity", "drop_height", *AXIS_INPUTS["surface"]),
             excluded_reason="is set by each transfer point the sphere measured")
    # before the calibration's fit (the compiled pulse table): the bound needs the sphere's mass and size only
    _refuse_coarse_step(inputs, rows, seed, spreads, criterion, probe if sphere_calibration is not None else body,
                        readings, readings.sample_period or (1.0 / rate if rate else 0.0))
    if sphere_calibration is not None:
        try:
            calibration = read_calibration(sphere_calibration, probe.mass, probe.diameter, table=table)
        except ValueError as exc:
            raise InputError(str(exc), "sphere_calibration") from None
        # the fit's 95 % interval of its mean, as a relative standard uncertainty (one drop: its scatter unknown)
        half = math.log(calibration["contact_modulus_high"] / calibration["contact_modulus"]) \
            if math.isfinite(calibration["contact_modulus_high"]) else 0.0
        body = build_sphere(device=sphere, mass=mass, diameter=diameter, modulus=modulus, poisson=poisson,
                            calibrated_modulus=calibration["contact_modulus"],
                            calibration_source=f"calibration {sphere_calibration}", calibrated_sd=half / 1.96)
    untimed = int(np.count_nonzero(np.isnan(readings.duration)))
    if untimed and restitution is None:
        raise InputError(f"sphere_restitution is needed: {untimed} of {len(readings)} readings have no duration, and "
                         f"peak acceleration and velocity change alone fit a line of (drop height, restitution) — e.g. "
                         f"a 5 cm drop at e = 0.6 reads like a 7.5 cm drop at e = 0.3; give --sphere-restitution or "
                         f"log durations", "sphere_restitution")
    if windows is not None and readings.point is not None:
        raise InputError("points: the log has a point column; a points file would assign the readings twice", "points")

    ignored = []
    if restitution is not None and not untimed:
        ignored.append("--sphere-restitution is not used: every reading has a duration, which gives its own e")
    if rate is not None and readings.kind == "trace":
        ignored.append(f"--logger-rate is not used: the trace's own sample period is "
                       f"{readings.sample_period:.6g} s")

    # the work
    period = readings.sample_period or (1.0 / rate if rate else 0.0)
    result = invert(body, readings.peak, readings.change, readings.duration, restitution=restitution,
                    surface_poisson=nu, uncertainty=error, sample_period=period)
    groups = group(readings.time, readings.point, windows, point_gap=point_gap, pass_gap=pass_gap)
    warnings = ignored + list(readings.warnings) + list(groups.warnings)
    if calibration is not None:
        warnings += [f"sphere calibration: {text}" for text in calibration["warnings"]]
        if calibration["status"] != "ok":
            warnings.append(f"sphere calibration: {calibration['message']}")
    if readings.shape_misfit is not None:
        # the pulse is not the sphere's Hunt–Crossley impact on a half-space (a cushion bottoming out, a layer, an
        # oblique or double hit): its three numbers still fit one, so say so rather than trust its drop height
        odd = np.flatnonzero((readings.shape_misfit > SHAPE_MISFIT) & (result.status == 0))
        for i in odd:
            result.message[i] = ((result.message[i] + "; ") if result.message[i] else "") + (
                f"the pulse's shape is not a Hunt-Crossley impact on a half-space (the fit misses it by "
                f"{readings.shape_misfit[i]:.1%} of its peak, rms): a layer that bottoms out, an oblique or a double "
                f"hit; its drop height and surface are those of the half-space impact that matches its peak, "
                f"velocity change and duration, and may be far off")
        if odd.size:
            warnings.append(f"{odd.size} of {len(readings)} pulses of the trace are not shaped as a Hunt-Crossley "
                            f"impact on a half-space (fit misfit above {SHAPE_MISFIT:.0%} of the peak): their drop "
                            f"heights may be far off (see their messages)")
    ok = result.status == 0
    # a reading whose equivalent drop lies beyond what a transfer point may have is no handling impact: left out
    # like a reading no impact reproduces (it had refused the whole line audit)
    beyond = ok & ~(result.drop_height <= MAX_POINT_HEIGHT)
    if beyond.any():
        first = int(np.flatnonzero(beyond)[0])
        warnings.append(f"{int(beyond.sum())} of {len(readings)} readings give an equivalent drop above the "
                        f"{MAX_POINT_HEIGHT:g} m a transfer point may have (the first, row "
                        f"{int(readings.rows[first])}: {result.drop_height[first]:.4g} m); left out of the points' "
                        f"figures")
        ok &= ~beyond
    bad = int(np.count_nonzero(~ok & ~beyond))
    if bad:
        first = int(np.flatnonzero(~ok)[0])
        warnings.append(f"{bad} of {len(readings)} readings reproduced by no impact (the first, row "
                        f"{int(readings.rows[first])}: {result.message[first]}); left out of the points' figures")
    summaries = []
    for k in range(len(groups.names)):
        members = np.flatnonzero((groups.point == k) & ok)
        if members.size == 0:
            summaries.append(None)
            continue
        # each visit's landing: its largest equivalent drop (sorted by visit, then by drop: the last of each visit)
        order = members[np.lexsort((result.drop_height[members], groups.visit[members]))]
        visits = groups.visit[order]
        landings = order[np.append(visits[1:] != visits[:-1], True)]
        rigid = result.rigid[landings]
        measured = landings[~rigid]
        is_rigid = rigid.sum() * 2 > landings.size
        summaries.append({
            "members": members, "landings": landings,
            "drop_height": float(np.median(result.drop_height[landings])),
            # the landings' own 95 % intervals, their medians: what one pass can say of the point's drop
            "drop_height_low": float(np.median(result.bounds["drop_height_low"][landings])),
            "drop_height_high": float(np.median(result.bounds["drop_height_high"][landings])),
            "drop_height_max": float(np.max(result.drop_height[members])),
            "velocity": float(np.median(result.velocity[landings])),
            "restitution": float(np.median(result.restitution[landings])),
            "peak": float(np.median(readings.peak[landings])),
            "surface_modulus": None if is_rigid else float(np.median(result.surface_modulus[measured])),
            "mixed": bool(rigid.any() and not rigid.all())})
    known = [s for s in summaries if s is not None]
    if not known:
        raise InputError(f"log: no reading of {log} is reproduced by an impact of this sphere ({result.message[0]})",
                         "log")
    spread = Z95 * math.hypot(error, error)  # a peak's and a velocity's relative uncertainty, 95 %
    nearest = _nearest_surfaces(body, np.array([s["velocity"] for s in known]),
                                np.array([s["restitution"] for s in known]), np.array([s["peak"] for s in known]),
                                [s["surface_modulus"] is None for s in known], spread)
    for summary, (surface, alike) in zip(known, nearest):
        summary["surface"], summary["alike"] = surface, alike
    line_points = []
    for name, summary in zip(groups.names, summaries):
        if summary is None:
            continue
        modulus_w = summary["surface_modulus"]
        line_points.append(TransferPoint(name, summary["drop_height"], summary["surface"],
                                         surface_modulus=None if modulus_w is None else float(modulus_w),
                                         surface_poisson=None if modulus_w is None else float(nu)))
    # the cushions tried, thinnest first: the library's layers and the user's pad
    thickness = {name: entry.thickness.value for name, entry in surfaces().items() if entry.model == "layer"}
    thickness.update({p.name: p.thickness for p in extra})
    cushions = sorted(thickness, key=thickness.get)
    tried = [next((p for p in extra if p.name == name), name) for name in cushions]
    report = audit_line(line_points, rows=rows, seed=seed, criterion=criterion, alternatives=tried,
                        spreads=spreads, **inputs)
    by_name = {point["name"]: point for point in report["points"]}
    point_rows = []
    for k, (name, summary) in enumerate(zip(groups.names, summaries)):
        members = np.flatnonzero(groups.point == k)
        entry = {"name": name, "passes": groups.passes[k], "impacts": int(members.size),
                 "impacts_reproduced": 0 if summary is None else int(summary["members"].size)}
        if summary is None:
            entry.update(drop_height=None, drop_height_max=None, surface_modulus=None, surface=None, incidence=None,
                         bruise_volume=None, cumulative_incidence=None, cushion=None, status="failed",
                         message="no reading of this point is reproduced by an impact of the sphere" if members.size
                         else "no reading falls in this point's window(s)")
            point_rows.append(entry)
            continue
        line = by_name[name]
        entry.update(drop_height=summary["drop_height"], drop_height_max=summary["drop_height_max"],
                     drop_height_low=summary["drop_height_low"], drop_height_high=summary["drop_height_high"],
                     velocity=summary["velocity"], restitution=summary["restitution"],
                     surface_modulus=summary["surface_modulus"], rigid=summary["surface_modulus"] is None,
                     surface=summary["surface"], surfaces_alike=summary["alike"], incidence=line["incidence"],
                     bruise_volume=line["mean_bruise_volume"], mean_peak_force=line["mean_peak_force"],
                     cumulative_incidence=line["cumulative_incidence"],
                     cumulative_bruise_volume=line["cumulative_bruise_volume"], status="ok",
                     message=("rigid to the sphere: the lot is dropped on " + summary["surface"]
                              if summary["surface_modulus"] is None else
                              "the lot is dropped on the measured half-space") +
                     ("; its landings read rigid and measurable surfaces both (the majority decides)"
                      if summary["mixed"] else ""))
        entry["cushion"] = _advice(name, line["incidence"], target, report["changes"], cushions)
        point_rows.append(entry)
    impacts = []
    for i in range(len(readings)):
        row = result.row(i)
        k = int(groups.point[i])
        impacts.append({"time": float(readings.time[i]), "point": groups.names[k] if k >= 0 else None,
                        "row": int(readings.rows[i]),
                        "peak_acceleration": float(readings.peak[i]), "velocity_change": float(readings.change[i]),
                        "duration": None if math.isnan(readings.duration[i]) else float(readings.duration[i]),
                        "velocity": row["velocity"], "drop_height": row["drop_height"],
                        "restitution": row["restitution"],
                        "surface_modulus": None if math.isnan(row["surface_modulus"]) else row["surface_modulus"],
                        "rigid": row["rigid"], "residual": row["residual"], "status": row["status"],
                        "message": row["message"],
                        **{key: row[key] for key in ("velocity_low", "velocity_high", "drop_height_low",
                                                     "drop_height_high", "restitution_low", "restitution_high",
                                                     "surface_modulus_low", "surface_modulus_high")}})
    lines = None
    if chart:
        from fruitimpact.spheres.chart import incidence_lines

        lines = incidence_lines(body, float(np.median(result.restitution[ok])), nu, rows=rows, seed=seed,
                                criterion=criterion, spreads=spreads, inputs=inputs)
    worst = report["worst_point"]
    status, message = "ok", ""
    if calibration is not None and calibration["status"] == "failed":
        status, message = "failed", f"the sphere's calibration failed: {calibration['message']}"
    elif any(entry["incidence"] is None for entry in point_rows):
        status, message = "failed", "a transfer point has no reading reproduced by an impact (see its message)"
    elif report["status"] != "ok":
        status, message = report["status"], report["message"]
    return {
        "log": str(log), "kind": readings.kind, "readings": len(readings), "skipped": readings.skipped,
        "sphere": {"name": body.name, "mass": body.mass, "diameter": body.diameter,
                   "contact_modulus": body.contact_modulus, "stiffness_source": body.stiffness_source},
        "calibration": calibration, "grouping": groups.method, "uncertainty": error, "target": target,
        "impacts": impacts, "points": point_rows, "worst_point": worst, "chart": lines,
        "incidence": report["incidence"], "mean_bruise_volume": report["mean_bruise_volume"],
        "criterion": report["criterion"], "rows": report["rows"], "seed": report.get("seed", seed),
        "spreads": report.get("spreads"), "inputs": report.get("inputs"),
        "warnings": warnings + report["warnings"], "status": status, "message": message,
    }


#: Margin on a logged contact duration in the step bound below: a duration read from a threshold crossing, or a
#: damped contact, may differ from the Hertz duration of the same stiffness by tens of percent; 1.5 in T is 2.8 in
#: stiffness, so the bound can only be loose, never tight.
DURATION_MARGIN = 1.5


def _refuse_coarse_step(inputs, rows, seed, spreads, criterion, body, readings, period) -> None:
    """Refuse, before the inversion (the compiled pulse table, ~0.6 s), an rk4 step that every fruit of the lot
    would be refused for at every point the log measured: the step above ``solvers.max_rk4_step`` (1/20 of the
    Hertz contact duration) of the longest contact any fruit can have there.

    The bound holds whatever the inversion finds.  Each reading's surface is at least as stiff as the sphere saw it:
    the sphere's Hertz stiffness from its duration (lengthened by ``DURATION_MARGIN`` and half a logger period) at
    the fastest landing its velocity change allows (V_in = ΔV, e → 0) bounds E*_sw from below, and E'_w ≥ E*_sw.
    The fruit lands at least at ΔV/2 (e ≤ 1) of the slowest reading, with its own modulus and ν = 0 (the softest).
    The fruit's mass, diameter and modulus are those the rows will use: drawn, given, or the fruit's library
    entry (``presets.resolve``, as ``evaluate`` reads them; ``--no-spreads`` draws none).  A step that some fruit
    may meet is left to the rows (the exact check after the inversion), and so is every step when a reading has
    no duration."""
    from fruitimpact.handling.heights import AXIS_INPUTS
    from fruitimpact.impact import presets
    from fruitimpact.impact.inputs import read_columns
    from fruitimpact.impact.labels import Labels
    from fruitimpact.impact.lots import read_lot
    from fruitimpact.impact.quantities import INPUTS
    from fruitimpact.impact.solvers import RK4_MIN_STEPS_PER_CONTACT, RK4_STEP_REFUSAL, max_rk4_step
    from fruitimpact.impact.validation import InputError
    from fruitimpact.physics.hertz import effective_modulus, hertz_contact_duration, hertz_stiffness

    if inputs.get("step") is None or inputs.get("stiffness") is not None:
        return
    timed = np.isfinite(readings.duration) & (readings.duration > 0) & np.isfinite(readings.change) \
        & (readings.change > 0)
    if not timed.all():
        # a reading without a duration (its e from --sphere-restitution) may put a point on a surface softer, or
        # at a speed lower, than any timed reading says: no bound (found by a review)
        return
    source, _, _ = read_lot(inputs, rows=rows, seed=seed, spreads=spreads, criterion=criterion,
                            excluded=("velocity", "drop_height", *AXIS_INPUTS["surface"]),
                            excluded_reason="is set by each transfer point the sphere measured")
    columns = source.inputs(0, rows, None)[0]
    method = columns.get("method")
    if not (isinstance(method, Labels) and set(method.labels) == {"rk4"}) \
            or not isinstance(columns.get("step"), np.ndarray):
        return
    lot, _ = read_columns(columns, rows=rows)
    defaults = presets.resolve(lot, math.nan).defaults

    def used(name):  # given (or drawn) where given, else the fruit's library value or the quantity's default
        default = INPUTS[name].default
        return np.where(lot.given[name], lot.values[name],
                        defaults.get(name, math.nan if default is None else default)).astype(float)

    columns = {name: used(name) for name in ("mass", "diameter", "modulus")} | {"step": columns["step"]}
    if not all(np.all(np.isfinite(value) & (value > 0)) for value in columns.values()):
        return  # refused by the rows' own validation, with its own message
    longest = (readings.duration + period / 2.0) * DURATION_MARGIN
    # T ∝ K^(-2/5) at given m and v: the stiffness whose Hertz duration is the longest reading, at V_in = ΔV
    sphere_stiffness = (hertz_contact_duration(body.mass, 1.0, readings.change) / longest) ** 2.5
    surface = float(np.min(sphere_stiffness / hertz_stiffness(1.0, body.diameter / 2.0)))  # E*_sw [Pa]
    fruit_stiffness = hertz_stiffness(effective_modulus(columns["modulus"], 0.0, surface, 0.0),
                                      columns["diameter"] / 2.0)
    bound = max_rk4_step(columns["mass"], fruit_stiffness, float(np.min(readings.change)) / 2.0)
    step = columns["step"]
    if np.all(step > bound):
        raise InputError(f"{RK4_STEP_REFUSAL}; got {float(np.max(step)):.6g} s, and no fruit of the lot has a "
                         f"contact longer than {float(np.max(bound)) * RK4_MIN_STEPS_PER_CONTACT * 1e3:.3g} ms at the "
                         f"points this log measured (at most {float(np.max(bound)):.3g} s)", "step")


def _advice(point: str, incidence: float, target: float, changes: list, cushions: list) -> dict | None:
    """The thinnest library cushion that brings ``point`` below ``target`` and what it saves per 10,000 fruit;
    None when the point is at or below the target already."""
    if math.isnan(incidence) or incidence <= target:
        return None
    tried = {change["to"]: change for change in changes if change["point"] == point}
    for name in cushions:  # thinnest first
        change = tried.get(name)
        if change is not None and change["point_incidence"] < target:
            return {"surface": name, "incidence": change["point_incidence"],
                    "saved_per_10000": round((incidence - change["point_incidence"]) * 10_000.0, 1),
                    "message": f"{name} brings it to {change['point_incidence']:.1%} (target {target:.0%})"}
    best = min((tried[name] for name in cushions if name in tried), key=lambda c: c["point_incidence"], default=None)
    return {"surface": None, "incidence": None, "saved_per_10000": None,
            "message": f"no library cushion brings it below {target:.0%}" + (
                "" if best is None else f" (the best, {best['to']}, gives {best['point_incidence']:.1%})")}


__all__ = ["TARGET", "sphere_audit"]
