"""One impact's report: the raw indices, and with a fit the model's indices and parameters.

``Analysis`` holds what every impact of a recording or a stream is analysed with
(the detector settings, the fit's knowns, the firmness classes), so that
``fruitimpact analyze`` and ``fruitimpact stream`` produce the same JSON object for
the same samples: both call ``Analysis.report``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .detect import DetectedImpact
from .indices import impact_indices
from .sort import FirmnessClasses

#: Keys of a fit that join the report (a contract: analyze --fit).
FIT_KEYS = ("stiffness", "restitution", "mass", "velocity", "modulus")


@dataclass(frozen=True)
class Analysis:
    """How impacts are analysed: ``rate`` [Hz], whether to ``fit`` the simulator's force law, its knowns
    ``velocity`` [m/s] or ``mass`` [kg] (one of them), ``diameter`` [m] and ``poisson`` for the modulus,
    and optional firmness ``classes``."""

    rate: float
    fit: bool = False
    velocity: float | None = None
    mass: float | None = None
    diameter: float | None = None
    poisson: float | None = None
    classes: FirmnessClasses | None = None
    #: the fitted impacts of each lane by sequence number (a rebound's velocity is e V of the impact it rebounds from)
    _fitted: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        if self.fit and (self.velocity is None) == (self.mass is None):
            raise ValueError("the fit needs exactly one of the impact velocity (--velocity or --drop-height) and "
                             "the mass (--mass): one pulse determines three of k_c, c, m, V")
        if (self.diameter is None) != (self.poisson is None):
            raise ValueError("give both --diameter and --poisson (the modulus follows from k_c with both)")
        if self.classes is not None and self.classes.by in ("modulus", "stiffness") and not self.fit:
            raise ValueError(f"classes by {self.classes.by} need --fit")
        if self.classes is not None and self.classes.by == "modulus" and self.diameter is None:
            raise ValueError("classes by modulus need --diameter and --poisson")

    def report(self, impact: DetectedImpact) -> dict:
        """The dict of one impact (SI); ``public(report)`` is its JSON object."""
        report = impact_indices(impact, self.rate)
        report["rebound_of"] = impact.rebound_of
        report["sequence"] = impact.sequence
        if self.fit:
            time = (impact.window_start + np.arange(impact.window.size)) / self.rate
            velocity = self.velocity
            if impact.rebound and velocity is not None:
                # the fruit comes back at the rebound speed of the impact before: e V of its fit
                before = self._fitted.get((impact.lane, impact.rebound_of))
                velocity = before["restitution"] * before["velocity"] if before is not None and \
                    _finite(before.get("restitution")) and _finite(before.get("velocity")) else None
            result = _fit(time, impact, self, velocity) if velocity is not None or self.mass is not None else \
                {"converged": False, "message": "a rebound whose first impact was not fitted: its velocity is unknown"}
            self._fitted[(impact.lane, impact.sequence)] = result
            for stale in [key for key in self._fitted if key[0] == impact.lane and key[1] < impact.sequence - 8]:
                del self._fitted[stale]
            for key in ("start_time", "peak_force", "time_to_peak", "contact_duration", "firmness_c",
                        "firmness_c_star", "impulse"):
                if key in result and result.get("converged") and _finite(result[key]):
                    report[f"raw_{key}"] = report.get(key)
                    report[key] = result[key]
            for key in FIT_KEYS:
                if key in result:
                    report[key] = result[key]
                    report[f"{key}_stderr"] = result.get(f"{key}_stderr", math.nan)
            report["fit_residual"] = result.get("fit_residual", math.nan)
            report["fit_residual_relative"] = result.get("fit_residual_relative", math.nan)
            report["fit_converged"] = bool(result.get("converged", False))
            report["fit_message"] = result.get("message", "")
            report["_fit"] = result  # the whole fit (for figures); not part of the JSON
        if self.classes is not None:
            value = report.get(self.classes.by, math.nan)
            label = self.classes.classify([value if _finite(value) else math.nan])[0]
            report["class"] = label
            report["class_by"] = self.classes.by
        return report


def public(report: dict) -> dict:
    """The JSON object of a report: without its private entries (the whole fit)."""
    return {key: value for key, value in report.items() if not key.startswith("_")}


def _finite(value) -> bool:
    return isinstance(value, (int, float, np.floating)) and math.isfinite(float(value))


def _fit(time, impact: DetectedImpact, analysis: Analysis, velocity) -> dict:
    from .fit import fit_impact

    try:
        return fit_impact(time, impact.window, velocity=velocity if analysis.mass is None else None,
                          mass=analysis.mass,
                          diameter=analysis.diameter, poisson=analysis.poisson, noise=impact.noise or None)
    except ValueError as exc:  # one bad pulse never stops the others
        return {"converged": False, "message": f"fit refused: {exc}"}


__all__ = ["Analysis", "FIT_KEYS", "public"]
