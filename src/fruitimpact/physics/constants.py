"""Physical constants and the built-in default fruit, with sources."""

from __future__ import annotations

#: Standard gravity g [m/s²] (CGPM 1901, ISO 80000-3), for v = sqrt(2 g h).
STANDARD_GRAVITY = 9.80665

#: The paper's Jonathan apple (section 3, worked example): M = 115 g,
#: d = 65 mm, E = 3 MPa, ν = 0.37, k = 0.577 at V_i = 1 m/s.
#: Source: the founding paper, "Theoretical aspects about simulating the reaction to impact of apples on rigid plane surfaces", section 3 and eqs 26–27.
JONATHAN_APPLE = dict(mass=0.115, diameter=0.065, modulus=3.0e6, poisson=0.37)
JONATHAN_RESTITUTION = 0.577
JONATHAN_VELOCITY = 1.0
JONATHAN_SOURCE = ("Jonathan apple of the founding paper (section 3 worked example): "
                   "M = 115 g, d = 65 mm, E = 3 MPa, nu = 0.37, k = 0.577, V_i = 1 m/s")
