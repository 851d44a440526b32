"""The registries that the text inputs name (``quantities.Quantity.choices``):
``--model`` (damping laws), ``--calibration``, ``--method`` (solvers).
Importing this module compiles nothing."""

from __future__ import annotations

from .models import CALIBRATIONS, DAMPING_LAWS
from .solvers import SOLVERS

REGISTRIES = {"model": DAMPING_LAWS, "calibration": CALIBRATIONS, "method": SOLVERS}

__all__ = ["REGISTRIES"]
