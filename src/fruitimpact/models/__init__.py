"""Contact models: force families, the published damping laws, and their registry.

* ``families``: one record per form of contact force (power law, Kelvin–Voigt,
  Kuwabara–Kono, Tsuji);
* ``laws``: one documented function per published damping law, e → damping group;
* ``registry``: ``DAMPING_LAWS`` (the ``--model`` names) and ``CALIBRATIONS``.
"""

from .families import (FAMILIES, HERTZ_DURATION_FACTOR, ForceFamily, hertz_equivalent_linear_stiffness)
from .laws import KUWABARA_KONO_C1
from .registry import CALIBRATIONS, DAMPING_LAWS, Calibration, DampingLaw, get_calibration, get_law, register

__all__ = ["CALIBRATIONS", "DAMPING_LAWS", "FAMILIES", "HERTZ_DURATION_FACTOR", "KUWABARA_KONO_C1", "Calibration",
           "DampingLaw", "ForceFamily", "get_calibration", "get_law", "hertz_equivalent_linear_stiffness", "register"]
