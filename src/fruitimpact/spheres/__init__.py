"""Instrumented spheres: from a sphere's log of impacts to the bruises of a lot at each transfer point.

Modules, one job each: ``devices`` (the sphere: built-in profiles and its properties), ``pulse`` (the
sphere's Hunt–Crossley impact in units of the impact, tabulated from the engine), ``inversion``
(a reading → impact velocity, restitution and surface modulus), ``calibration`` (the sphere's own
stiffness and damping from drops onto a rigid plate), ``log`` (reading a log: per-impact readings or a
raw acceleration trace, vendors' headers mapped), ``points`` (impacts grouped into transfer points and
passes) and ``audit`` (the lot dropped at each point, the cushion advice; ``sphere_audit``).
"""
