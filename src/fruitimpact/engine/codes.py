"""Codes of the force families and the column order of the characteristics.

Plain integers, importable without compiling anything (the command line's
``--help`` and the registries need them; the compiled kernels read them as
constants).
"""

from __future__ import annotations

#: F = K δ^n (1 + c δ̇); params (K [N/m^n], n [-], c [s/m]).  Hunt & Crossley 1975.
POWER_LAW = 0
#: F = k δ + b δ̇; params (k [N/m], b [N·s/m]).  Linear Kelvin–Voigt spring–dashpot.
KELVIN_VOIGT = 1
#: F = K (δ^1.5 + B δ^0.5 δ̇); params (K [N/m^1.5], B [s]).  Kuwabara & Kono 1987, Brilliantov et al. 1996.
KUWABARA_KONO = 2
#: F = K δ^1.5 + η δ^0.25 δ̇; params (K [N/m^1.5], η [N·s/m^1.25]).  Tsuji, Tanaka & Ishida 1992.
TSUJI = 3

#: Column order of the characteristics array returned by the kernels; the
#: column indices below name them.
CHARACTERISTIC_COLUMNS = (
    "peak_force",
    "time_to_peak",
    "contact_duration",
    "max_deflection",
    "time_to_max_deflection",
    "exit_velocity",
    "restitution",
    "absorbed_energy",
    "firmness_c",
    "firmness_c_star",
    "max_pressure",
    "contact_radius",
)
N_CHARACTERISTICS = len(CHARACTERISTIC_COLUMNS)
PEAK_FORCE = 0
TIME_TO_PEAK = 1
CONTACT_DURATION = 2
MAX_DEFLECTION = 3
TIME_TO_MAX_DEFLECTION = 4
EXIT_VELOCITY = 5
RESTITUTION = 6
ABSORBED_ENERGY = 7
FIRMNESS_C = 8
FIRMNESS_C_STAR = 9
MAX_PRESSURE = 10
CONTACT_RADIUS = 11
#: Column index by name.
COLUMN = {name: index for index, name in enumerate(CHARACTERISTIC_COLUMNS)}
assert all(COLUMN[name.lower()] == value for name, value in dict(
    PEAK_FORCE=PEAK_FORCE, TIME_TO_PEAK=TIME_TO_PEAK, CONTACT_DURATION=CONTACT_DURATION,
    MAX_DEFLECTION=MAX_DEFLECTION, TIME_TO_MAX_DEFLECTION=TIME_TO_MAX_DEFLECTION, EXIT_VELOCITY=EXIT_VELOCITY,
    RESTITUTION=RESTITUTION, ABSORBED_ENERGY=ABSORBED_ENERGY, FIRMNESS_C=FIRMNESS_C,
    FIRMNESS_C_STAR=FIRMNESS_C_STAR, MAX_PRESSURE=MAX_PRESSURE, CONTACT_RADIUS=CONTACT_RADIUS).items())
