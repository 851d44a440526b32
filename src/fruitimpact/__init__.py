"""fruitimpact: simulate and measure the impact of a fruit on a surface.

Three layers: pure model functions (``contact``, ``models``, ``engine``),
solvers and result objects (``solvers``, ``impact``), and the CLI, I/O and
plots (``cli``, ``plotting``, ``paper``).  SI units throughout.
"""

from .constants import JONATHAN_SOURCE, STANDARD_GRAVITY
from .impact import (Characteristics, ContactLaw, Curves, Fruit, ImpactInputs, ImpactResult,
                     Surface, impact_velocity, simulate)
from .models import CALIBRATIONS, DAMPING_LAWS, Calibration, DampingLaw
from .solvers import SOLVERS

__version__ = "0.1.0"

__all__ = [
    "CALIBRATIONS", "DAMPING_LAWS", "JONATHAN_SOURCE", "SOLVERS", "STANDARD_GRAVITY",
    "Calibration", "Characteristics", "ContactLaw", "Curves", "DampingLaw", "Fruit",
    "ImpactInputs", "ImpactResult", "Surface", "impact_velocity", "simulate", "__version__",
]
