"""Many impacts at once: a table of inputs in, a table of characteristics out.

``evaluate(frame)`` takes rows named like ``fruitimpact simulate``'s options
(mass, diameter, modulus, poisson, stiffness, velocity, drop_height,
restitution, alpha, model, calibration, method, step; plain SI numbers or
strings with units) and returns, per row, the resolved inputs, the contact
law, every characteristic, a ``status`` ("ok", "invalid" or "failed") and a
``message``.  A bad row never stops the others.  The numbers come from the
same compiled kernels as ``simulate``, so a batch row equals the single
impact with the same inputs.
"""

from __future__ import annotations

import math

import numpy as np

from . import contact
from .calibrate import damping_factor as calibrated_damping_factor
from .calibrate import law_params
from .constants import JONATHAN_APPLE, JONATHAN_RESTITUTION, JONATHAN_VELOCITY, STANDARD_GRAVITY
from .engine import forces
from .engine.powerlaw import CHARACTERISTIC_COLUMNS, N_CHARACTERISTICS
from .models import CALIBRATIONS, DAMPING_LAWS
from .solvers import SOLVERS, judge_batch, max_rk4_step
from .units import parse_quantity
from .validation import positive_message, range_message

#: Input columns, their dimension and default (None: optional, NaN when absent).
INPUT_COLUMNS = {
    "mass": ("mass", JONATHAN_APPLE["mass"]),
    "diameter": ("length", JONATHAN_APPLE["diameter"]),
    "modulus": ("modulus", JONATHAN_APPLE["modulus"]),
    "poisson": ("dimensionless", JONATHAN_APPLE["poisson"]),
    "stiffness": ("stiffness", None),
    "velocity": ("velocity", None),
    "drop_height": ("length", None),
    "restitution": ("dimensionless", None),
    "alpha": ("alpha", None),
    "step": ("time", 1e-4),
}
TEXT_COLUMNS = {"model": "hunt-crossley", "calibration": "exact", "method": "accurate"}
LAW_COLUMNS = ("stiffness", "damping", "damping_factor")
# the requested restitution is reported as target_restitution (k, or 1 - α V_i), since
# "restitution" is the achieved one
OUTPUT_COLUMNS = (tuple(c for c in INPUT_COLUMNS if c != "restitution") + tuple(TEXT_COLUMNS) + ("target_restitution",)
                  + ("law_stiffness", "damping", "damping_factor") + CHARACTERISTIC_COLUMNS + ("status", "message"))


def _numeric_column(frame, name, dimension, default, rows, messages):
    """Column as float64 (NaN = not given); unit strings parsed cell by cell."""
    if name not in frame:
        return np.full(rows, np.nan if default is None else default)
    column = frame[name]
    values = np.asarray(column.to_numpy() if hasattr(column, "to_numpy") else column)
    unreadable = np.zeros(rows, dtype=bool)
    if values.dtype.kind in "fiu":
        out = values.astype(float)
    else:
        out = np.empty(rows)
        for i, cell in enumerate(values):
            if cell is None or (isinstance(cell, float) and math.isnan(cell)) or (isinstance(cell, str) and not cell.strip()):
                out[i] = np.nan
                continue
            try:
                out[i] = parse_quantity(cell, dimension)
            except ValueError as exc:
                out[i] = np.nan
                unreadable[i] = True
                messages[i] = messages[i] or f"{name}: {exc}"
            else:
                if not math.isfinite(out[i]):
                    messages[i] = messages[i] or f"{name} must be a finite number; got {cell!r}"
    if default is not None:  # an empty cell takes the default, as an omitted option does
        out = np.where(np.isnan(out) & ~unreadable, default, out)
    return out


def _require(mask_bad, message, messages):
    for i in np.flatnonzero(mask_bad):
        if not messages[i]:
            messages[i] = message


def evaluate(frame, tabulated: bool | None = None) -> "pandas.DataFrame":  # noqa: F821
    """Characteristics of every row of ``frame`` (a DataFrame or a dict of columns).

    ``tabulated`` is passed to ``engine.powerlaw.powerlaw_characteristics``: True
    makes power-law rows independent of how a run is split into chunks (the
    table agrees with the exact kernel to ~1e-13; by default it is used for
    groups of more than 20000 rows).

    Returns a DataFrame with ``OUTPUT_COLUMNS``: the inputs as used (SI), the
    contact law (``law_stiffness`` [N/m^1.5, N/m for Kelvin–Voigt], ``damping``,
    ``damping_factor``), the characteristics, ``status`` and ``message``.
    """
    import pandas as pd

    if not isinstance(frame, pd.DataFrame):
        frame = pd.DataFrame(frame)
    rows = len(frame)
    messages = np.array([""] * rows, dtype=object)
    values = {name: _numeric_column(frame, name, dim, default, rows, messages)
              for name, (dim, default) in INPUT_COLUMNS.items()}
    text = {}
    for name, default in TEXT_COLUMNS.items():
        column = (frame[name].astype(object).where(frame[name].notna(), default).astype(str).str.strip()
                  if name in frame else None)
        text[name] = column.to_numpy(dtype=object) if column is not None else np.full(rows, default, dtype=object)

    # -- validation: one message per bad row, the same wording as simulate()
    def positive(name, unit, optional):
        value = values[name]
        bad = ~(np.isfinite(value) & (value > 0))
        if optional:
            bad &= ~np.isnan(value)
        _require(bad, positive_message(name, unit), messages)

    for name, unit in (("mass", "kg"), ("diameter", "m"), ("modulus", "Pa"), ("step", "s")):
        positive(name, unit, optional=False)
    for name, unit in (("stiffness", "N/m^1.5"), ("velocity", "m/s"), ("drop_height", "m")):
        positive(name, unit, optional=True)
    poisson = values["poisson"]
    _require(~((poisson > -1) & (poisson < 0.5)), range_message("poisson", -1, 0.5), messages)
    _require(~np.isnan(values["velocity"]) & ~np.isnan(values["drop_height"]),
             "give either velocity or drop_height, not both", messages)
    _require(~np.isnan(values["restitution"]) & ~np.isnan(values["alpha"]),
             "give either restitution or alpha, not both", messages)
    for name, registry, label in (("model", DAMPING_LAWS, "model"), ("calibration", CALIBRATIONS, "calibration"),
                                  ("method", SOLVERS, "method")):
        _require(~np.isin(text[name], list(registry)), f"{label} must be one of {', '.join(registry)}", messages)

    with np.errstate(invalid="ignore"):  # a given velocity wins, so a conflicting row records what was given
        velocity = np.where(~np.isnan(values["velocity"]), values["velocity"],
                            np.where(np.isnan(values["drop_height"]), JONATHAN_VELOCITY,
                                     np.sqrt(2.0 * STANDARD_GRAVITY * np.abs(values["drop_height"]))))
    with np.errstate(invalid="ignore", divide="ignore"):
        alpha = values["alpha"]
        bad_alpha = ~np.isnan(alpha) & ~((alpha >= 0) & (alpha < 1.0 / velocity))
        _require(bad_alpha, "alpha must be in [0, 1/V_i) s/m (so that k = 1 - alpha*V_i is in (0, 1])", messages)
        target = np.where(np.isnan(alpha), np.where(np.isnan(values["restitution"]), JONATHAN_RESTITUTION,
                                                    values["restitution"]), 1.0 - alpha * velocity)
        _require(np.isnan(alpha) & ~((target > 0) & (target <= 1)),
                 range_message("restitution", 0, 1, high_inclusive=True), messages)
        hertz = contact.rigid_plane_stiffness(values["modulus"], poisson, values["diameter"])
    stiffness = np.where(np.isnan(values["stiffness"]), hertz, values["stiffness"])
    radius = values["diameter"] / 2.0
    mass = values["mass"]
    rk4 = text["method"] == "rk4"
    _require(rk4 & ~(values["step"] <= max_rk4_step(mass, stiffness, velocity)),
             "step must be at most 1/20 of the contact duration for rk4 (at least 20 steps per contact)", messages)

    valid = messages == ""
    out = np.full((rows, N_CHARACTERISTICS), np.nan)
    law_stiffness = np.full(rows, np.nan)
    factor = np.full(rows, np.nan)
    status = np.where(valid, "ok", "invalid").astype(object)

    # -- resolve the damping and integrate, group by (model, calibration, method)
    codes, labels = zip(*(pd.factorize(text[name]) for name in TEXT_COLUMNS))
    keys = (codes[0] * len(labels[1]) + codes[1]) * len(labels[2]) + codes[2]
    for key in np.unique(keys[valid]):
        rest, method_code = divmod(int(key), len(labels[2]))
        model_code, calibration_code = divmod(rest, len(labels[1]))
        model, calibration, method = labels[0][model_code], labels[1][calibration_code], labels[2][method_code]
        law = DAMPING_LAWS[model]
        idx = np.flatnonzero(valid & (keys == key))
        m, k, v, e, r = mass[idx], stiffness[idx], velocity[idx], target[idx], radius[idx]
        factor[idx] = calibrated_damping_factor(law, calibration, e, m, k, v)
        law_stiffness[idx] = law.linear_stiffness(m, k, v)
        out[idx] = SOLVERS[method].batch(law.family, law.clamp, law_stiffness[idx], factor[idx], m, v, r,
                                         values["step"][idx], tabulated)
    computed = valid & ~judge_batch(out)
    status[computed] = "failed"
    messages[computed] = "solver did not reach separation (non-finite characteristics)"
    messages[status == "ok"] = "ok"

    data = {name: values[name] for name in INPUT_COLUMNS if name != "restitution"}
    data["velocity"] = velocity
    data["stiffness"] = stiffness
    data.update(text)
    data["target_restitution"] = target
    data["law_stiffness"] = law_stiffness
    data["damping"] = factor * law_stiffness
    data["damping_factor"] = factor
    for j, name in enumerate(CHARACTERISTIC_COLUMNS):
        data[name] = out[:, j]
    data["status"] = status
    data["message"] = messages
    return pd.DataFrame(data, columns=list(OUTPUT_COLUMNS))


def curves(frame, times=None, points: int = 201):
    """Curves of every valid row of ``frame``: a dict with ``row`` (the row numbers),
    ``time`` [s], ``deflection`` [m], ``rate`` [m/s] and ``force`` [N], each of shape
    (rows, points).  ``times`` [s] is a common grid (points,) or one grid per row
    (rows, points); by default each row gets ``points`` samples over its own [0, T]."""
    results = evaluate(frame)
    rows = np.flatnonzero(results["status"].to_numpy() == "ok")
    ok = results.iloc[rows]
    if times is None:
        grid = np.linspace(0.0, 1.0, int(points))[None, :] * ok["contact_duration"].to_numpy()[:, None]
    else:
        grid = np.broadcast_to(np.asarray(times, dtype=float), (len(rows), np.shape(times)[-1])).copy()
    shape = grid.shape
    deflection, rate, force = np.empty(shape), np.empty(shape), np.empty(shape)
    for model, group in ok.groupby("model", sort=False):
        law = DAMPING_LAWS[model]
        idx = np.flatnonzero(ok["model"].to_numpy() == model)
        m, v = group["mass"].to_numpy(), group["velocity"].to_numpy()
        k, c = group["law_stiffness"].to_numpy(), group["damping_factor"].to_numpy()
        if law.family == forces.POWER_LAW:
            from .engine.powerlaw import powerlaw_curves_batch

            deflection[idx], rate[idx], force[idx] = powerlaw_curves_batch(m, k, c, v, grid[idx])
        else:
            from .engine.adaptive import adaptive_curves

            params = law_params(law.family, k, c)
            for j, i in enumerate(idx):
                deflection[i], rate[i], force[i], _ = adaptive_curves(law.family, params[j], law.clamp, m[j], v[j],
                                                                      grid[i])
    return dict(row=rows, time=grid, deflection=deflection, rate=rate, force=force)
