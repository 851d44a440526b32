"""``fit_damage``: the censored-likelihood fit of threshold, susceptibility and failure stress to a table of
tests, per surface and pooled, with its report."""

from __future__ import annotations

import math
import os

import numpy as np

from fruitimpact.handling.droptests.fruitfile import _fitted_fruit, _name, _same_file
from fruitimpact.handling.droptests.impacts import CONVERSIONS, _impacts, _onset_stresses
from fruitimpact.handling.droptests.table import (INTERVAL, MASS_MISMATCH, MODEL_TEXT, RANGE_SIGMAS, STRESS_NOTE, Tests,
                                                  _Z95, read_tests)


def fit_damage(tests, *, fruit: str | None = None, criterion: str | None = None, name: str | None = None,
               output=None) -> dict:
    """Fit a fruit's bruise threshold energy, bruise susceptibility and failure stress to drop or pendulum tests.

    Maximum likelihood with unbruised fruit censored (each fruit has its own threshold, lognormal around W_th) and
    lognormal scatter on the volume (:mod:`fruitimpact.damage.fitting` gives the model and why); 95 %
    profile-likelihood intervals.  The energies are those the simulator compares with the fitted values: each
    test's impact energy (m g h of a drop, the pendulum's energy) times the fruit's share of it on that test's
    surface, by the project's impact of the ``fruit``'s flesh (all of it on steel, a part on a pad).  The failure
    stress is the criterion's stress at the threshold, per surface, by the project's impact, where a surface's tests
    bracket their threshold.

    Parameters
    ----------
    tests : str, path, mapping or DataFrame
        The tests, one row per fruit (at most ``MAX_TESTS``): ``drop_height`` [m] or ``energy`` [J], ``surface`` (a
        library surface or ``rigid``), ``mass`` [kg], optional ``diameter`` [m], and one outcome: ``bruise_volume``
        [m³], ``bruise_diameter`` [m] (turned into a volume: the cap of that width with the library's bruise shape
        of that impact, the module's docstring) or ``bruised`` (0/1).  Cells may carry units ("10cm", "120g").  A
        CSV may have ``#`` comments.  In a DataFrame, NaN in the one of ``drop_height`` and ``energy`` a row does
        not use is "not given".
    fruit : str, optional
        The fruit whose flesh gives each test's compared energy, whose modulus, Poisson's ratio, size, mass and
        restitution give the failure stress, and the template of the fitted fruit: a library name or a fruit file
        (default: the project's default fruit).
    criterion : str, optional
        ``pressure``, ``shear`` or ``energy`` (the stress whose onset is fitted); None or ``preset``: the fruit's
        own (without one, no failure stress is fitted); ``none``: no failure stress.
    name : str, optional
        The fitted fruit's name (lower case, no spaces); default ``<fruit>-fitted-<tests file stem>``.
    output : str or path, optional
        Write the fitted fruit there (``.csv``, not the table of tests itself), in the fruit library's format,
        atomically.

    Returns
    -------
    dict
        ``bruise_susceptibility`` [m³/J] (the median volume per joule above a fruit's threshold; None from 0/1
        outcomes), ``bruise_energy`` [J] (the median threshold), ``failure_stress`` [Pa] (None where no surface's
        tests bracket their threshold, or where surfaces disagree), each with ``_low`` and ``_high`` (the 95 %
        interval of the estimate; None where the data leave that side open); ``fruit_ranges`` (name → [low, high]:
        the fruit-to-fruit spread written as the fitted fruit's range); ``basis`` (``impact``), ``basis_note`` and
        ``energy_share_by_surface`` (surface → the least and greatest share of the impact energy compared);
        ``tests``, ``bruised``, ``unbruised``, ``energy_min``, ``energy_max`` [J] (compared energies);
        ``threshold_spread`` σ_t and ``volume_scatter`` σ_v [-] (lognormal σ; None where not fitted);
        ``failure_stress_surface`` (the surfaces it is from), ``failure_stress_by_surface`` (surface → its tests,
        threshold and stress with their intervals, and why none), ``failure_stress_rule`` (the criterion whose
        stress it is), ``failure_stress_reason`` (why it is None), ``failure_stress_note`` (what its interval
        holds); ``outcome``, ``model`` and ``model_name`` (``volume`` or ``incidence``), ``interval``,
        ``log_likelihood``, ``volume_conversion``, ``rows_skipped`` (row, message), ``tests_file``, ``fruit``,
        ``criterion``, ``name``, ``output``; ``status`` (``ok``, or ``failed``: nothing could be fitted),
        ``message`` (what was fitted, or why nothing was) and ``warnings``.

    Raises
    ------
    ValueError
        (``InputError``) before any work: a table that cannot be read, more than ``MAX_TESTS`` rows, unknown
        columns, no outcome column, neither drop_height nor energy, an unknown surface, no usable row; a fruit or
        criterion that is not known; an output that cannot be written or is the table of tests.  The message names
        the argument, the row and the column.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.fit_damage("examples/drop-tests.csv", fruit="apple", criterion="shear")  # doctest: +SKIP
    >>> report["bruise_energy"], report["bruise_energy_low"], report["bruise_energy_high"]  # doctest: +SKIP

    References
    ----------
    Bruise volume BV = BS (W − W_th)₊: L. O. Opara & P. B. Pathare, Postharvest Biol. Technol. 91 (2014) 9–24.
    Censored (Tobit) likelihood: J. Tobin, Econometrica 26 (1958) 24–36.  Profile-likelihood intervals:
    D. J. Venzon & S. H. Moolgavkar, Appl. Statist. 37 (1988) 87–94.  Bruise depth 2.5 × peak deformation and
    contact width 1.4 × bruise width: Z. Stropek & K. Gołacki, Postharvest Biol. Technol. 163 (2020) 111120.
    Criteria: docs/bruise.md.
    """
    from fruitimpact.impact.outputs import CSV_FORMAT, atomic_write, check_output
    from fruitimpact.impact.quantities import INPUTS
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.impact.validation import InputError, check_choice, fruit_file_warnings
    from fruitimpact.library.catalogue import fruit_file_text, fruits, is_fruit_file, read_fruit_file

    fruit = check_choice("fruit", fruit if fruit is not None else INPUTS["fruit"].default, fruits())
    template = fruits()[fruit]
    warnings = [text for _, text in fruit_file_warnings(fruit)] if is_fruit_file(fruit) else []
    if criterion is not None:
        check_choice("criterion", criterion, REGISTRIES["criterion"])
    if criterion in (None, "preset"):
        used = template.criterion
        if used is None:
            warnings.append(f"failure stress: null: the {template.name} entry names no bruise criterion (give "
                            f"criterion pressure, shear or energy to fit one)")
    else:
        used = None if criterion == "none" else criterion
        if used is None:
            warnings.append("failure stress: null: criterion none")
    if output is not None:
        check_output(output, "output", CSV_FORMAT)
        if isinstance(tests, (str, os.PathLike)) and _same_file(output, tests):
            raise InputError(f"output: {os.fspath(output)!r} is the table of tests itself: write the fitted fruit to "
                             f"another file", "output")
    table = read_tests(tests, fruit_diameter=template.diameter.value)
    fitted_name = _name(table.label, fruit, name)
    warnings += table.warnings
    skipped = list(table.skipped)
    impacts = _impacts(fruit, table)
    keep = impacts.ok.copy()
    skipped += [(table.where[i], f"its impact could not be computed: {impacts.messages[i]}")
                for i in np.flatnonzero(~keep)]
    conversion = None
    values = table.value
    if table.outcome.name in CONVERSIONS:  # an outcome fitted as another (a diameter as a volume)
        convert, describe = CONVERSIONS[table.outcome.name]
        values, converted, failed = convert(table, fruit, impacts)
        skipped += [item for item, i in zip(failed, np.flatnonzero(~converted)) if keep[i]]
        keep &= converted
        conversion = describe(fruit)
        warnings.append(f"bruise volumes derived from bruise diameters: {conversion}")
    if not keep.any():
        raise InputError(f"{table.label}: no usable test: no test's impact could be computed (the first: "
                         f"{skipped[0][0]}: {skipped[0][1]})", "tests")
    for where, message in skipped:
        warnings.append(f"{where}: {message}; the row is skipped")
    energy, outcome, impact_energy = impacts.energy[keep], values[keep], table.energy[keep]
    surfaces = [s for s, k in zip(table.surface, keep) if k]
    from fruitimpact.damage.fitting import MODELS as FIT_MODELS  # numpy from here: every argument is answered

    model = FIT_MODELS[table.outcome.model]
    fit = model(energy, outcome)
    names = _by_use(surfaces)
    fits = {names[0]: fit} if len(names) == 1 else {
        s: model(energy[mask], outcome[mask]) for s, mask in ((s, np.array([x == s for x in surfaces])) for s in names)}
    bruised = int((outcome > 0.0).sum())
    drops = int(table.drop[keep].sum())
    shares = {}
    for s in names:
        ratio = [e / w for e, w, x in zip(energy, impact_energy, surfaces) if x == s]
        shares[s] = {"min": float(min(ratio)), "max": float(max(ratio))}
    basis_note = ("the fruit's share of the impact energy ("
                  + " and ".join(part for part in (f"m g h of each drop, {drops} tests" if drops else "",
                                                  f"the pendulum's energy, {energy.size - drops} tests"
                                                  if energy.size - drops else "") if part)
                  + f") on each test's surface, which the simulator compares with impact-basis values, by the "
                    f"project's impact of the {template.name} flesh; share: "
                  + ", ".join(f"{s} {v['min']:.5g}" if v["max"] - v["min"] < 5e-5 else
                              f"{s} {v['min']:.3g}-{v['max']:.3g}" for s, v in shares.items()))
    estimates, intervals = fit.estimates, fit.intervals
    report = {
        "tests_file": table.label, "fruit": fruit, "criterion": used, "outcome": table.outcome.name,
        "basis": "impact", "basis_note": basis_note, "energy_share_by_surface": shares,
        "tests": int(energy.size), "bruised": bruised, "unbruised": int(energy.size) - bruised,
        "rows_skipped": [{"row": where, "message": message} for where, message in skipped],
        "energy_min": float(energy.min()), "energy_max": float(energy.max()),
    }
    for key in ("bruise_susceptibility", "bruise_energy"):
        low, high = intervals.get(key, (None, None))
        report.update({key: estimates.get(key), f"{key}_low": low, f"{key}_high": high})
    report.update(failure_stress=None, failure_stress_low=None, failure_stress_high=None,
                  failure_stress_surface=None, failure_stress_by_surface={}, failure_stress_rule=None,
                  failure_stress_reason=None,
                  threshold_spread=estimates.get("threshold_spread"), volume_scatter=estimates.get("volume_scatter"),
                  failure_stress_note=STRESS_NOTE, fruit_ranges={},
                  model=MODEL_TEXT[fit.model], model_name=fit.model, interval=INTERVAL, volume_conversion=conversion,
                  log_likelihood=fit.log_likelihood if math.isfinite(fit.log_likelihood) else None)
    for key, spread in (("bruise_susceptibility", "volume_scatter"), ("bruise_energy", "threshold_spread")):
        if report[key] is not None and report[spread] is not None:
            report["fruit_ranges"][key] = [report[key] * math.exp(-RANGE_SIGMAS * report[spread]),
                                           report[key] * math.exp(RANGE_SIGMAS * report[spread])]
    warnings += fit.notes
    if "bruise_susceptibility" not in estimates:  # the model has none: 0/1 outcomes
        warnings.append("bruise susceptibility: null: 0/1 outcomes carry no bruise volume, so none is fitted")
    if used is None:
        report["failure_stress_reason"] = ("criterion none" if criterion == "none" else
                                           f"the {template.name} entry names no bruise criterion")
    warnings += _failure_stress(report, fits, energy, outcome, surfaces, fruit, used)
    warnings += _mismatch(template, table, keep)
    status = "ok" if fit.status == "ok" and (report["bruise_energy"] is not None
                                            or report["bruise_susceptibility"] is not None) else "failed"
    report["name"] = fitted_name
    report["output"] = None
    if status == "ok" and output is not None:
        entry = _fitted_fruit(report, template, fitted_name)
        text = fruit_file_text(entry, f"fruit {fitted_name}: fitted by fruitimpact fit-damage to {table.label} "
                                      f"({report['tests']} tests; ranges: the fruit-to-fruit spreads, the 95 % "
                                      f"intervals in the notes); the fruit library's format (docs/library.md): give "
                                      f"this file as --fruit to any command")

        def write(tmp):
            with open(tmp, "w", encoding="utf-8", newline="") as handle:
                handle.write(text)
            read_fruit_file(tmp)  # it must load as the library's, with the same checks, before it replaces anything

        atomic_write(output, write, "output")
        report["output"] = os.fspath(output)
    elif output is not None:
        warnings.append(f"nothing fitted: {output} is not written")
    report["status"] = status
    report["message"] = _summary(report) if status == "ok" else _failure(fit)
    report["warnings"] = warnings
    return report


def _failure(fit) -> str:
    """Why a fit gave nothing (a failed fit says it; one that ran but bounds nothing, by its notes)."""
    if fit.status != "ok":
        return fit.message
    why = "; ".join(fit.notes) or "the tests determine neither the threshold energy nor the susceptibility"
    extra = "; 0/1 outcomes carry no bruise volume, so there is no susceptibility either" \
        if "bruise_susceptibility" not in fit.estimates else ""
    return f"nothing fitted: {why}{extra}"


def _by_use(surfaces) -> list:
    """The surfaces of the tests, the most used first (ties: in table order)."""
    names = list(dict.fromkeys(surfaces))
    names.sort(key=lambda s: -surfaces.count(s))
    return names


def _bracket(fit, energy, outcome) -> str:
    """Why a surface's tests do not bound the stress at onset ("" where they do)."""
    threshold = fit.estimates.get("bruise_energy")
    low, high = fit.intervals.get("bruise_energy", (None, None))
    if fit.status != "ok":
        return f"the threshold energy is not fitted ({fit.message})"
    if threshold is None:
        return "the threshold energy is not fitted" + (f" ({fit.notes[0]})" if fit.notes else "")
    bruised = outcome > 0.0
    reasons = [text for text, missing in (
        ("no test was unbruised", bruised.all()), ("no test bruised", not bruised.any()),
        (f"no test below the threshold {threshold:.4g} J", energy.min() >= threshold),
        (f"no test above the threshold {threshold:.4g} J", energy.max() <= threshold),
        ("its interval is open below", low is None), ("its interval is open above", high is None)) if missing]
    if reasons:
        return (f"the tests do not bracket the threshold energy ({'; '.join(reasons)}), so they do not bound the "
                f"stress at onset")
    return ""


def _agree(intervals) -> bool:
    """Whether 95 % intervals (low, high) share a point."""
    return max(low for low, _ in intervals) <= min(high for _, high in intervals)


def _failure_stress(report, fits, energy, outcome, surfaces, fruit, criterion) -> list:
    """The onset stress on each surface whose tests bracket their own threshold (``failure_stress_by_surface``), and
    the one failure stress they give: one surface's, their precision-weighted geometric mean where they agree within
    their 95 % intervals, none where they disagree.  Returns the warnings."""
    names = _by_use(surfaces)
    by_surface, warnings = {}, []
    for s in names:
        mask = np.array([x == s for x in surfaces])
        fit = fits[s]
        low, high = fit.intervals.get("bruise_energy", (None, None))
        by_surface[s] = {"tests": int(mask.sum()), "bruised": int((outcome[mask] > 0.0).sum()),
                         "bruise_energy": fit.estimates.get("bruise_energy"), "bruise_energy_low": low,
                         "bruise_energy_high": high, "threshold_spread": fit.estimates.get("threshold_spread"),
                         "failure_stress": None, "failure_stress_low": None, "failure_stress_high": None,
                         "failure_stress_range": None, "note": _bracket(fit, energy[mask], outcome[mask])}
    report["failure_stress_by_surface"] = by_surface
    bounded = [s for s in names if by_surface[s]["bruise_energy"] is not None
               and None not in (by_surface[s]["bruise_energy_low"], by_surface[s]["bruise_energy_high"])]
    if len(bounded) > 1 and not _agree([(by_surface[s]["bruise_energy_low"], by_surface[s]["bruise_energy_high"])
                                        for s in bounded]):
        listing = ", ".join(f"{s} {by_surface[s]['bruise_energy']:.4g} J [{by_surface[s]['bruise_energy_low']:.4g}, "
                            f"{by_surface[s]['bruise_energy_high']:.4g}]" for s in bounded)
        warnings.append(f"the surfaces disagree on the threshold energy beyond their 95 % intervals ({listing}): one "
                        f"threshold of the compared energy does not describe these tests, and the one fitted to all "
                        f"of them lies between theirs")
    if criterion is None:
        return warnings
    todo = [s for s in names if not by_surface[s]["note"]]
    if todo:
        rows, levels = [], []
        for s in todo:
            entry = by_surface[s]
            spread = entry["threshold_spread"] or 0.0
            w = entry["bruise_energy"]
            levels += [w, entry["bruise_energy_low"], entry["bruise_energy_high"],
                       w * math.exp(-RANGE_SIGMAS * spread), w * math.exp(RANGE_SIGMAS * spread)]
            rows += [s] * 5
        stresses, rule = _onset_stresses(fruit, criterion, rows, levels)
        report["failure_stress_rule"] = rule
        for k, s in enumerate(todo):
            value, low, high, down, up = (float(x) if math.isfinite(x) else None for x in stresses[5 * k:5 * k + 5])
            if None in (value, low, high):
                by_surface[s]["note"] = f"the impact at the threshold on {s} could not be computed"
                continue
            by_surface[s].update(failure_stress=value, failure_stress_low=low, failure_stress_high=high,
                                 failure_stress_range=None if None in (down, up) else [down, up])
    given = [s for s in names if by_surface[s]["failure_stress"] is not None]
    if not given:
        reason = by_surface[names[0]]["note"] if len(names) == 1 else \
            "on no surface do the tests bound it (" + "; ".join(f"{s}: {by_surface[s]['note']}" for s in names) + ")"
        report["failure_stress_reason"] = reason
        warnings.append(f"failure stress: null: {reason}")
        return warnings
    listing = ", ".join(f"{s} {by_surface[s]['failure_stress'] / 1e6:.4g} MPa "
                        f"[{by_surface[s]['failure_stress_low'] / 1e6:.4g}, "
                        f"{by_surface[s]['failure_stress_high'] / 1e6:.4g}]" for s in given)
    if len(given) > 1 and not _agree([(by_surface[s]["failure_stress_low"], by_surface[s]["failure_stress_high"])
                                      for s in given]):
        reason = (f"the surfaces disagree on the {criterion} criterion's stress at onset beyond their 95 % intervals "
                  f"({listing})")
        report["failure_stress_reason"] = reason
        warnings.append(f"failure stress: null: {reason}: one failure stress does not describe these tests, so none "
                        f"is given or written (each surface's: failure_stress_by_surface; the fitted fruit takes the "
                        f"energy criterion); fit each surface's tests on their own for its stress")
        return warnings
    if len(given) == 1:
        entry = by_surface[given[0]]
        value, low, high, spread = (entry["failure_stress"], entry["failure_stress_low"], entry["failure_stress_high"],
                                    entry["failure_stress_range"])
    else:  # agreeing surfaces: inverse-variance weights of ln σ_f, each variance from its 95 % interval
        entries = [by_surface[s] for s in given]
        logs = np.log([e["failure_stress"] for e in entries])
        errors = np.array([math.log(e["failure_stress_high"] / e["failure_stress_low"]) / (2.0 * _Z95)
                           for e in entries])
        weights = 1.0 / np.maximum(errors, 1e-12) ** 2
        centre = float(np.sum(weights * logs) / np.sum(weights))
        error = 1.0 / math.sqrt(float(np.sum(weights)))
        value, low, high = (math.exp(centre + k * _Z95 * error) for k in (0.0, -1.0, 1.0))
        # the fruit-to-fruit range: each surface's, relative to its stress, averaged in ln
        ranged = [e for e in entries if e["failure_stress_range"]]
        spread = None if not ranged else [
            value * math.exp(float(np.mean([math.log(e["failure_stress_range"][end] / e["failure_stress"])
                                            for e in ranged]))) for end in (0, 1)]
        warnings.append(f"the tests on {len(given)} surfaces agree on the failure stress within their 95 % intervals "
                        f"({listing}): the value given and written is their precision-weighted geometric mean")
    if len(given) < len(names):
        warnings.append(f"the failure stress is from the tests on {', '.join(given)} only ("
                        + "; ".join(f"{s}: {by_surface[s]['note']}" for s in names if s not in given) + ")")
    report.update(failure_stress=value, failure_stress_low=low, failure_stress_high=high,
                  failure_stress_surface=", ".join(given))
    if spread is not None:
        report["fruit_ranges"]["failure_stress"] = spread
    return warnings


def _mismatch(template, table: Tests, keep) -> list:
    """Warnings where the tested fruit differ from the fruit whose flesh and size give the failure stress."""
    notes = []
    mass = float(np.median(table.mass[keep]))
    if abs(mass / template.mass.value - 1.0) > MASS_MISMATCH:
        notes.append(f"the tested fruit (median mass {mass * 1e3:.4g} g) are not the {template.name} entry's "
                     f"{template.mass.value * 1e3:.4g} g, whose mass and size give the failure stress: give --fruit "
                     f"a fruit like the tested ones")
    return notes


def _summary(report: dict) -> str:
    parts = []
    if report["bruise_energy"] is not None:
        parts.append(f"threshold energy {report['bruise_energy']:.4g} J")
    elif report["bruise_energy_high"] is not None:
        parts.append(f"threshold energy below {report['bruise_energy_high']:.4g} J (not bounded below)")
    if report["bruise_susceptibility"] is not None:
        parts.append(f"bruise susceptibility {report['bruise_susceptibility'] * 1e6:.4g} cm³/J (median)")
    if report["failure_stress"] is not None:
        parts.append(f"failure stress {report['failure_stress'] / 1e6:.4g} MPa ({report['criterion']} on "
                     f"{report['failure_stress_surface']})")
    return (f"fitted to {report['tests']} tests ({report['bruised']} bruised), on the energy the simulator compares "
            f"(the fruit's share of the impact energy): " + ", ".join(parts))
