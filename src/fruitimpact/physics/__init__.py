"""The physics of one contact: Hertz's elastic contact, the published damping laws, their registry and
calibration, and the physical constants.

* ``hertz``: Hertz contact of a sphere on a half-space (stiffness, contact radius, peak pressure, duration);
* ``families``: one record per form of contact force (power law, Kelvin–Voigt,
  Kuwabara–Kono, Tsuji);
* ``laws``: one documented function per published damping law, e → damping group;
* ``registry``: ``DAMPING_LAWS`` (the ``--model`` names) and ``CALIBRATIONS``;
* ``calibrate``: the damping parameter of a law from a restitution coefficient;
* ``constants``: standard gravity and the founding paper's reference values.

The integrators and closed forms that solve these laws are in :mod:`fruitimpact.engine`; plastic
contact (Thornton, bioyield) is :mod:`fruitimpact.engine.plastic`; bruise criteria are
:mod:`fruitimpact.damage`.
"""

from fruitimpact.physics.families import (FAMILIES, HERTZ_DURATION_FACTOR, ForceFamily, hertz_equivalent_linear_stiffness)
from fruitimpact.physics.laws import KUWABARA_KONO_C1
from fruitimpact.physics.registry import CALIBRATIONS, DAMPING_LAWS, Calibration, DampingLaw, get_calibration, get_law, register

__all__ = ["CALIBRATIONS", "DAMPING_LAWS", "FAMILIES", "HERTZ_DURATION_FACTOR", "KUWABARA_KONO_C1", "Calibration",
           "DampingLaw", "ForceFamily", "get_calibration", "get_law", "hertz_equivalent_linear_stiffness", "register"]
