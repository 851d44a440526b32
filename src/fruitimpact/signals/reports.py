"""A contact's report: its columns, the detector's status, the fit merged into it and restated for the contact's
own speed (``signals.analysis`` builds the reports; this module holds what a report is made of).

The keys here are contracts: ``REPORT_KEYS`` and ``FIT_KEYS`` are JSON keys of ``analyze --json`` and ``stream``,
and ``report_columns`` gives the columns of ``analyze``'s table whichever contacts a recording holds.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.signals.detect import DetectedImpact
from fruitimpact.signals.indices import INDEX_KEYS
from fruitimpact.signals.settings import Analysis


#: Keys of a fit that join the report (a contract: analyze --fit).
FIT_KEYS = ("stiffness", "restitution", "mass", "velocity", "modulus")


#: Keys of every report beside the indices (a contract of analyze --json and stream).
REPORT_KEYS = ("sequence", "status", "message", "rebound", "rebound_of", "rebound_ambiguous", "rebound_evidence",
               "discharge_time")


#: Firmness indices withheld from an overlap (they would describe neither fruit).
FIRMNESS_KEYS = ("firmness_c", "firmness_c_star")


#: Marks a fit restated for a rebound whose first impact's speed is unknown (``restated``): shape only.
UNSPLIT = "_unsplit"


def without_firmness(report: dict, fit: bool = False) -> None:
    """Blank a report's firmness (an overlap has none): the indices' and their measured ``raw_`` values, and with
    ``fit`` the fitted values and their standard errors too (a piece whose fit is no measurement)."""
    keys = (*FIRMNESS_KEYS, *(f"raw_{key}" for key in FIRMNESS_KEYS))
    if fit:
        keys += tuple(k for key in FIT_KEYS for k in (key, f"{key}_stderr"))
    for key in keys:
        if key in report or key in FIRMNESS_KEYS:
            report[key] = math.nan


def detector_status(impact: DetectedImpact) -> tuple[str, str]:
    """A contact's status and message from the detector's own flags (the first that holds), else ``ok``."""
    if impact.truncated:
        return "truncated", "the stream ended during this contact: its indices are incomplete"
    if impact.overlong:
        return "overlong", "the contact lasted longer than the detector's max_duration: ended there"
    if impact.clipped:
        return "clipped", "the signal reached the acquisition's limits during this contact: the peak is a lower bound"
    return "ok", ""


#: Indices a rebound test reads (``rebounds.from_indices``).
SUMMARY_KEYS = ("start_time", "peak_force", "time_to_peak", "impulse")


#: Indices the fit restates (the measured ones kept as ``raw_<key>``).
RESTATED_KEYS = ("start_time", "peak_force", "time_to_peak", "contact_duration", "firmness_c", "firmness_c_star",
                 "impulse")


def report_columns(analysis: Analysis) -> tuple[str, ...]:
    """Every key a report of ``analysis`` may have, in the order a report builds them: the columns of
    ``analyze``'s table whichever contacts a recording holds (a fit that did not converge on any contact, or a
    quiet recording, still gives the columns)."""
    columns = [*INDEX_KEYS, "sequence", "rebound", "rebound_of", "rebound_ambiguous", "rebound_evidence"]
    if analysis.fit:
        columns += [f"raw_{key}" for key in RESTATED_KEYS]
        for key in FIT_KEYS:
            columns += [key, f"{key}_stderr"]
        columns += ["fit_residual", "fit_residual_relative", "fit_converged", "fit_message"]
    if analysis.classes is not None:
        columns += ["class", "class_by"]
    return (*columns, "status", "message", "discharge_time")


def merge_fit(report: dict, result: dict) -> None:
    for key in RESTATED_KEYS:
        if key in result and result.get("converged") and is_finite_number(result[key]):
            report[f"raw_{key}"] = report.get(key)
            report[key] = result[key]
    converged = bool(result.get("converged", False))
    for key in FIT_KEYS:
        if key in result:  # a fit that did not converge measured nothing: its last iterate is not a value
            report[key] = result[key] if converged else math.nan
            report[f"{key}_stderr"] = result.get(f"{key}_stderr", math.nan) if converged else math.nan
    report["fit_residual"] = result.get("fit_residual", math.nan)
    report["fit_residual_relative"] = result.get("fit_residual_relative", math.nan)
    report["fit_converged"] = converged
    report["fit_message"] = result.get("message", "")
    report["_fit"] = result  # the whole fit (for figures); not part of the JSON


def public(report: dict) -> dict:
    """The JSON object of a report: without its private entries (the whole fit)."""
    return {key: value for key, value in report.items() if not key.startswith("_")}


def is_finite_number(value) -> bool:
    return isinstance(value, (int, float, np.floating)) and math.isfinite(float(value))


def shape_fit(impact: DetectedImpact, analysis: Analysis) -> dict:
    """The simulator's pulse fitted to the contact's own samples: with the given mass, or at a unit
    velocity (the shape, indices and relative errors do not depend on it; ``restated`` splits the
    Hertz scales for the contact's real speed)."""
    from fruitimpact.signals.fit import fit_impact

    time = (impact.window_start + np.arange(impact.window.size)) / analysis.rate
    # the detector records the next contact's onset only when it began inside this one's window, and ``isolated``
    # then stops the window before that contact's rise: possibly before this contact's own tail
    cut = impact.next_start is not None
    try:
        return fit_impact(time, impact.window, velocity=1.0 if analysis.mass is None else None,
                          mass=analysis.mass, diameter=analysis.diameter, poisson=analysis.poisson,
                          noise=impact.noise or None, open_end=cut)
    except ValueError as exc:  # one bad pulse never stops the others
        return {"converged": False, "message": f"fit refused: {exc}"}


def restated(shape: dict, analysis: Analysis, velocity) -> dict:
    """The shape fit for this contact's knowns: the given mass as it is, else its impact speed."""
    from fruitimpact.signals.fit import at_velocity

    if analysis.mass is not None or not shape.get("converged"):
        return shape
    if velocity is None:  # the pulse's shape (peak, times, e: c V is fitted as one) holds; m and K do not split
        unsplit = {name: math.nan for name in ("mass", "stiffness", "modulus", "velocity")}
        unsplit.update({f"{name}_stderr": math.nan for name in unsplit})
        return {**shape, **unsplit, UNSPLIT: True,
                "message": "a rebound whose first impact's speed is unknown: its mass and stiffness are not split "
                           "(peak force, times and restitution are the pulse fit's)"}
    return at_velocity(shape, velocity)


__all__ = ["FIRMNESS_KEYS", "FIT_KEYS", "REPORT_KEYS", "RESTATED_KEYS", "SUMMARY_KEYS", "UNSPLIT", "detector_status",
           "is_finite_number", "merge_fit", "public", "report_columns", "restated", "shape_fit", "without_firmness"]
