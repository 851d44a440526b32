"""fruitimpact: simulate and measure the impact of a fruit on a surface.

Three layers: pure model functions (``contact``, ``models``, ``engine``),
solvers and result objects (``solvers``, ``batch``, ``impact``), and the CLI,
I/O and plots (``cli``, ``runs``, ``plotting``, ``paper``).  SI units throughout.

The names below are imported on first use, so that ``import fruitimpact.cli``
(and ``fruitimpact --help``) does not compile the engine.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    "JONATHAN_SOURCE": "constants", "STANDARD_GRAVITY": "constants",
    "Characteristics": "impact", "ContactLaw": "impact", "Curves": "impact", "Fruit": "impact",
    "ImpactInputs": "impact", "ImpactResult": "impact", "Surface": "impact", "impact_velocity": "impact",
    "simulate": "impact",
    "CALIBRATIONS": "models", "DAMPING_LAWS": "models", "Calibration": "models", "DampingLaw": "models",
    "SOLVERS": "solvers", "evaluate": "batch",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fruitimpact' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
