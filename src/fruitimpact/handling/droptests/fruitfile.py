"""The fitted fruit: the template fruit with the fitted values, written in the fruit library's own format."""

from __future__ import annotations

import os
import re
from dataclasses import replace

from fruitimpact.handling.droptests.table import INTERVAL, MODEL_TEXT, RANGE_SIGMAS


def _name(label: str, fruit: str, name) -> str:
    from fruitimpact.impact.validation import InputError
    from fruitimpact.library.catalogue import fruits, is_fruit_file

    if name is None:
        base = fruits()[fruit].name
        stem = os.path.splitext(os.path.basename(label))[0] if label != "tests" else ""
        slug = re.sub(r"[^a-z0-9]+", "-", stem.lower()).strip("-")
        return f"{base}-fitted" + (f"-{slug}" if slug else "")
    if not isinstance(name, str) or not name or name != name.lower() or " " in name or is_fruit_file(name):
        raise InputError(f"the fitted fruit's name must be lower-case without spaces (not a .csv path); got {name!r}",
                         "fitted_name")
    if name in fruits().library:
        raise InputError(f"the fitted fruit's name must not be a library fruit's ({', '.join(fruits().library)}); got "
                         f"{name!r}", "fitted_name")
    return name


def _shown(number) -> str:
    return "open" if number is None else f"{number:.6g}"


def _value(report: dict, key: str, unit: str, source: str, what: str, spread_text: str, basis: str = ""):
    """A library ``Value`` of the fitted estimate ``report[key]``: its range the fruit-to-fruit spread the fit found
    (``report["fruit_ranges"][key]``: what a lot draws from), or the value itself where the fit resolved none (the
    library's "no spread known"); the 95 % interval (``report[key + "_low"]``, ``report[key + "_high"]``) in the
    note."""
    from fruitimpact.library.catalogue import Value

    estimate, spread = report[key], report["fruit_ranges"].get(key)
    low95, high95 = report[f"{key}_low"], report[f"{key}_high"]
    if spread is None:
        low = high = estimate
        ranged = "range: the value (the tests do not resolve a fruit-to-fruit spread)"
    else:
        low, high = min(spread[0], estimate), max(spread[1], estimate)
        ranged = (f"range: the fruit-to-fruit spread the fit found, ±{RANGE_SIGMAS:g} lognormal σ ({spread_text}), "
                  f"which a lot draws from as it draws a library range")
    note = (f"{what}; {ranged}; the estimate's {INTERVAL} 95 % interval: [{_shown(low95)}, {_shown(high95)}] {unit}"
            + ("; an open end: the tests do not bound it on that side" if None in (low95, high95) else ""))
    return Value(estimate, low, high, unit, source, True, note, basis)


def _fitted_fruit(report: dict, template, name: str):
    """The template fruit with the fitted values (none borrowed: a value not fitted is left empty), their ranges the
    fruit-to-fruit spreads, and the criterion the fitted values support."""
    from fruitimpact.library.catalogue import FITTED_BY

    count = report["tests"]
    source = f"derived: {FITTED_BY} to {report['tests_file']}, {count} tests"
    basis = ("impact: the fruit's share of the impact energy (m g h of a drop, the pendulum's energy) on each test's "
             "surface, as a simulation compares it")
    fields = {"bruise_susceptibility": None, "bruise_threshold_energy": None, "failure_stress": None}
    if report["bruise_susceptibility"] is not None:
        fields["bruise_susceptibility"] = _value(
            report, "bruise_susceptibility", "m^3/J", source,
            f"the median bruise volume per joule above a fruit's threshold, maximum-likelihood estimate "
            f"({MODEL_TEXT[report['model_name']]}); basis: {basis}",
            f"the volume scatter σ_v = {report['volume_scatter']:.3g}, which holds the measurement's scatter too: an "
            f"upper bound of the fruit-to-fruit spread" if report["volume_scatter"] is not None else "", "impact")
    if report["bruise_energy"] is not None:
        fields["bruise_threshold_energy"] = _value(
            report, "bruise_energy", "J", source,
            f"median of the fruit's thresholds (half the fruit bruise at it), maximum-likelihood estimate; basis: "
            f"{basis}",
            f"the thresholds' spread σ_t = {report['threshold_spread']:.3g}" if report["threshold_spread"] is not None
            else "", "impact")
    criterion, criterion_source, criterion_note = None, "", ""
    if report["failure_stress"] is not None:
        fields["failure_stress"] = _value(
            report, "failure_stress", "Pa",
            f"{source} (the {report['failure_stress_rule']} criterion's stress at the threshold energy on "
            f"{report['failure_stress_surface']}, with the {template.name} entry's modulus, Poisson ratio, size and "
            f"mass)", f"stress at bruise onset under the {report['criterion']} criterion",
            "the stress at the thresholds ±2 σ_t through the same impact")
        criterion = report["criterion"]
        criterion_source = (f"{FITTED_BY} to {report['tests_file']}, {count} tests: the failure stress is this "
                            f"criterion's stress at the fitted threshold energy")
        criterion_note = ("the criterion the failure stress was fitted under; under another criterion it would need "
                          "its own (a command that uses it under another says so)")
    elif report["bruise_energy"] is not None:
        criterion = "energy"
        criterion_source = (f"{FITTED_BY} to {report['tests_file']}, {count} tests: the threshold energy is fitted "
                            f"and no failure stress")
        criterion_note = (f"the criterion the fitted values support: no failure stress was fitted "
                          f"({report['failure_stress_reason'] or 'criterion none'}), so only the energy criterion "
                          f"uses the fitted threshold")
    fitted = [label for key, label in (("bruise_threshold_energy", "bruise threshold energy"),
                                       ("bruise_susceptibility", "bruise susceptibility"),
                                       ("failure_stress", "failure stress")) if fields[key] is not None]
    return replace(template, name=name, criterion=criterion, criterion_source=criterion_source,
                   criterion_note=criterion_note, **fields,
                   description=f"{template.name} fitted to {report['tests_file']} ({count} tests): "
                               f"{', '.join(fitted) or 'nothing'} fitted by fruitimpact fit-damage; the other values "
                               f"are the {template.name} entry's",
                   source=f"{FITTED_BY} to {report['tests_file']}, {count} tests; other values: "
                          f"the {template.name} entry of the fruit library ({template.source})")


def _same_file(one, two) -> bool:
    try:
        return os.path.samefile(one, two)
    except OSError:
        return os.path.normcase(os.path.realpath(one)) == os.path.normcase(os.path.realpath(two))
