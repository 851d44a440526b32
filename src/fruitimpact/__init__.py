"""fruitimpact: simulate and measure the impact of a fruit on a surface.

Topic packages (docs/architecture.md): ``engine`` (compiled solvers), ``physics`` (Hertz contact, damping
laws), ``damage`` (bruise criteria), ``library`` (fruits and surfaces), ``impact`` (quantities, validation,
evaluate and simulate), ``handling`` (drops, safe heights, line audits), ``signals`` (force recordings),
``plotting``, ``reference`` (the founding paper), ``runs`` (large runs), ``spheres`` (instrumented-sphere
logs) and ``cli``.  SI units throughout.

The names below are imported on first use, so that ``import fruitimpact.cli``
(and ``fruitimpact --help``) does not compile the engine.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    "JONATHAN_SOURCE": "physics.constants", "STANDARD_GRAVITY": "physics.constants",
    "Characteristics": "impact.simulation", "ContactLaw": "impact.simulation", "Curves": "impact.simulation",
    "Fruit": "impact.simulation", "ImpactInputs": "impact.simulation", "ImpactResult": "impact.simulation",
    "Surface": "impact.simulation", "impact_velocity": "impact.simulation", "simulate": "impact.simulation",
    "CALIBRATIONS": "physics", "DAMPING_LAWS": "physics", "Calibration": "physics", "DampingLaw": "physics",
    "SOLVERS": "impact.solvers", "evaluate": "impact.evaluation",
    # one function per task (issue 15 item 2): the CLI command it matches is in brackets
    "drop": "handling.drops",                                   # fruitimpact drop
    "safe_height": "handling.heights", "risk_map": "handling.heights",  # fruitimpact safe-height [--map]
    "audit_line": "handling.line", "read_line": "handling.line",        # fruitimpact line
    "sphere_audit": "spheres.audit",                            # fruitimpact sphere
    "fit_damage": "handling.droptests",
    "analyze": "signals.offline",                               # fruitimpact analyze
    "read_recording": "signals.read", "open_recording": "signals.read", "Recording": "signals.recording",
    "fit_impact": "signals.fit",
    "Detector": "signals.detect", "DetectorSettings": "signals.detect",
    "StreamAnalyzer": "signals.stream",                         # fruitimpact stream (push samples, get impacts)
    "calibrate_classes": "signals.sort:calibrate", "confusion_matrix": "signals.sort:confusion",  # fruitimpact classes
    "FirmnessClasses": "signals.sort",
    "synthesize": "signals.synth", "SensorModel": "signals.synth", "Population": "signals.synth",
    "write_recording": "signals.synth",                         # fruitimpact synth
    "batch": "runs.tasks", "sweep": "runs.tasks", "population": "runs.tasks",  # fruitimpact batch/sweep/population
    "RunSummary": "runs.summaries",
    "fruits": "library", "surfaces": "library",                 # fruitimpact fruits / surfaces
    "paper_report": "reference.paper",                          # fruitimpact paper
    "restitution_table": "reference.comparison",                # fruitimpact models
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fruitimpact' has no attribute {name!r}")
    module, _, attribute = module.partition(":")  # "module:attribute" where the public name differs
    value = getattr(importlib.import_module(f".{module}", __name__), attribute or name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
