"""The sphere's own stiffness and damping, from drops onto a rigid plate from known heights.

Devices are not published to their stiffness and read differently on hard surfaces (Praeger et al. 2013,
Sensors 13:7140), so the sphere is calibrated as the field does it: dropped from known heights onto a
rigid plate.  On a rigid plate the contact is the sphere's alone, and each drop gives, by the same pulse
relations as the inversion (``spheres.pulse``):

    V = √(2 g h),   e = ΔV/V − 1,   K = (m a_max / (f(e) m^(3/5) V^(6/5)))^(5/2),   E*_s = 3K/(4√R),

and the Hunt–Crossley damping factor c = x(e)/V (``engine.powerlaw.exact_x``).  The fit is the geometric
mean of E*_s over the drops, with a 95 % interval of that mean (t-free, ± 1.96 s/√n in ln) and the scatter
of a single drop (s, relative); the damping factor likewise.  Where the drops logged their durations, the
durations the fitted sphere predicts are compared with them (``duration_residual``: rms relative) — a direct
test of the Hertz law for this device.  The calibration says how well it holds: ``status`` is ``poor`` when
a single drop's stiffness scatters by more than ``POOR_SCATTER`` or the durations miss by more than
``POOR_DURATION``, with the figures.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.spheres.log import _skipped_text, read_table
from fruitimpact.spheres.pulse import E_MIN, contact_duration, stiffness_from_peak

#: Columns of a calibration file.
CALIBRATION_COLUMNS = {
    "drop_height": ("length", "m", True),
    "peak_acceleration": ("acceleration", "g", True),
    "velocity_change": ("velocity", "m/s", True),
    "duration": ("time", "s", False),
}
#: A sphere's contact modulus no solid exceeds [Pa] (diamond's E* on a rigid plate is ~1.2 TPa): a calibration
#: giving more has ``failed``.
MAX_SPHERE_MODULUS = 1.2e12
#: A single drop's stiffness scattering by more than this (relative sd), or durations missed by more than
#: POOR_DURATION (rms), make a calibration ``poor``: the sphere is then not a Hertz body to its readings'
#: precision, and every surface modulus it gives is that uncertain.
POOR_SCATTER = 0.10
POOR_DURATION = 0.10


#: Calibration drops higher than this [m] are legal but implausible for a sphere meant for handling lines.
IMPLAUSIBLE_HEIGHT = 3.0


def calibrate(sphere_mass: float, sphere_diameter: float, drop_height, peak_acceleration, velocity_change,
              duration=None, rows=None) -> dict:
    """Fit the sphere's contact modulus E*_s and Hunt–Crossley damping to drops onto a rigid plate.

    Parameters
    ----------
    sphere_mass : float
        m [kg].
    sphere_diameter : float
        d [m].
    drop_height : array_like
        h [m] of each drop.
    peak_acceleration : array_like
        a_max [m/s²].
    velocity_change : array_like
        ΔV [m/s].
    duration : array_like, optional
        T [s] (NaN where not logged).
    rows : array_like of int, optional
        The file's row number of each drop, for the messages.

    Returns
    -------
    dict
        ``contact_modulus`` E*_s [Pa] with ``_low``/``_high`` (95 % of the mean) and ``contact_modulus_scatter``
        (relative sd of one drop); ``damping_factor`` c [s/m] with its scatter; ``restitution`` (per drop);
        ``duration_residual`` (rms relative, NaN without durations); ``drops``; ``status`` (``ok``, ``poor``),
        ``message`` and ``warnings``.
    """
    height = np.atleast_1d(np.asarray(drop_height, dtype=float))
    peak = np.asarray(peak_acceleration, dtype=float)
    change = np.asarray(velocity_change, dtype=float)
    velocity = np.sqrt(2.0 * STANDARD_GRAVITY * height)
    e = change / velocity - 1.0
    bad = np.flatnonzero(~((e > 0.0) & (e <= 1.0 + 0.02)))
    if bad.size:
        i = int(bad[0])
        where = f"row {int(rows[i])}" if rows is not None else f"drop {i + 1}"
        raise ValueError(f"sphere_calibration: {where} (h = {height[i]:.4g} m) reads ΔV = {change[i]:.4g} m/s, "
                         f"a restitution of {e[i]:.3g} on the plate (ΔV must lie in (V, 2V] = ({velocity[i]:.4g}, "
                         f"{2 * velocity[i]:.4g}] m/s): not a free drop from that height")
    e = np.clip(e, E_MIN, 1.0)  # within 2 % above 1: elastic to the readings' precision
    radius = sphere_diameter / 2.0
    stiffness = stiffness_from_peak(e, sphere_mass, velocity, sphere_mass * peak)
    modulus = 0.75 * stiffness / math.sqrt(radius)
    log_modulus = np.log(modulus)
    n = modulus.size
    scatter = float(np.std(log_modulus, ddof=1)) if n > 1 else math.nan
    centre = float(np.exp(np.mean(log_modulus)))
    half = 1.96 * scatter / math.sqrt(n) if n > 1 else math.nan
    from fruitimpact.engine.powerlaw import exact_x

    factor = exact_x(e) / velocity
    fitted_k = 4.0 / 3.0 * centre * math.sqrt(radius)
    residual = math.nan
    if duration is not None and np.isfinite(np.asarray(duration, float)).any():
        duration = np.asarray(duration, dtype=float)
        timed = np.isfinite(duration)
        predicted = contact_duration(e[timed], sphere_mass, fitted_k, velocity[timed])
        residual = float(np.sqrt(np.mean((predicted / duration[timed] - 1.0) ** 2)))
    status, message = "ok", (f"{n} drops: E*_s = {centre / 1e6:.4g} MPa (one drop scatters by "
                             f"{scatter:.1%}{'' if math.isnan(residual) else f', durations predicted within {residual:.1%} rms'})")
    if n < 3:
        status, message = "poor", f"{n} drop(s): at least 3 are needed to say how well the sphere is calibrated"
    elif scatter > POOR_SCATTER or residual > POOR_DURATION:
        status = "poor"
        message = (f"the sphere is not a Hertz body to its readings' precision: one drop's stiffness scatters by "
                   f"{scatter:.1%} (limit {POOR_SCATTER:.0%})" + ("" if math.isnan(residual) else
                   f", durations predicted within {residual:.1%} rms (limit {POOR_DURATION:.0%})") +
                   "; surface moduli from this sphere are that uncertain")
    if not centre <= MAX_SPHERE_MODULUS:
        status = "failed"
        message = (f"E*_s = {centre / 1e6:.4g} MPa: stiffer than any solid (above {MAX_SPHERE_MODULUS / 1e9:g} GPa, "
                   f"diamond's E*): these readings are not the sphere's drops onto a rigid plate")
    warnings = []
    high = int(np.count_nonzero(height > IMPLAUSIBLE_HEIGHT))
    if high:
        warnings.append(f"{high} calibration drop(s) from above {IMPLAUSIBLE_HEIGHT:g} m: implausible for a handling "
                        f"sphere (computed as given)")
    return {"drops": int(n), "contact_modulus": centre,
            "contact_modulus_low": centre * math.exp(-half) if n > 1 else math.nan,
            "contact_modulus_high": centre * math.exp(half) if n > 1 else math.nan,
            "contact_modulus_scatter": scatter,
            "damping_factor": float(np.mean(factor)),
            "damping_factor_scatter": float(np.std(factor, ddof=1) / np.mean(factor)) if n > 1 and np.mean(factor) > 0
            else math.nan,
            "restitution": [float(v) for v in e], "duration_residual": residual, "status": status,
            "message": message, "warnings": warnings}


def read_calibration_table(path, columns=None) -> tuple[dict, np.ndarray]:
    """The readings of a calibration file (``drop_height`` [m], ``peak_acceleration`` [g], ``velocity_change``
    [m/s], optionally ``duration`` [s]) and their file line numbers; ``ValueError`` naming ``sphere_calibration``,
    the row and the column of a problem (a calibration is small and must be whole: a bad row refuses it).  No
    compiled code: a usage error is answered at once."""
    from fruitimpact.spheres.log import parse_columns

    mapping = parse_columns(columns, tuple(CALIBRATION_COLUMNS)) if columns else {}
    try:
        values, _, good, numbers, skipped = read_table(path, CALIBRATION_COLUMNS, mapping, hint="")
    except ValueError as exc:
        raise ValueError(f"sphere_calibration: {exc}") from None
    if not good.all():
        raise ValueError(f"sphere_calibration: {path}, {_skipped_text(skipped)}")
    return values, numbers


def read_calibration(path, sphere_mass: float, sphere_diameter: float, columns=None, table=None) -> dict:
    """``calibrate`` on a calibration file's readings (``read_calibration_table``, or ``table`` as it returned
    them); ``ValueError`` as that function raises it."""
    values, numbers = table if table is not None else read_calibration_table(path, columns)
    report = calibrate(sphere_mass, sphere_diameter, values["drop_height"], values["peak_acceleration"],
                       values["velocity_change"], values["duration"], numbers)
    report["file"] = str(path)
    return report


__all__ = ["CALIBRATION_COLUMNS", "calibrate", "read_calibration", "read_calibration_table"]
