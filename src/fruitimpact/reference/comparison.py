"""How well each damping law keeps its promise: the restitution it really
produces against the one it was given (``fruitimpact models``).

For every law, target e and impact velocity the law's *published*
calibration is applied and the impact integrated exactly (first integral for
the power-law family, the compiled adaptive integrator otherwise); the
achieved restitution is read off.  Laws of the power-law family and the
Tsuji and Kelvin–Voigt laws give a restitution independent of velocity, mass
and stiffness; Kuwabara–Kono's depends on them through b = B (K/m)^(2/5) v0^(1/5).
"""

from __future__ import annotations

import numpy as np

from fruitimpact.physics.calibrate import achieved_restitution, damping_factor
from fruitimpact.engine.powerlaw import exact_restitution
from fruitimpact.impact.simulation import Fruit, resolve_stiffness
from fruitimpact.physics import DAMPING_LAWS

DEFAULT_TARGETS = (0.1, 0.3, 0.5, 0.7, 0.9)
DEFAULT_VELOCITIES = (0.5, 1.0, 3.0)


def unique_laws(names=None):
    """The registered laws (aliases once), or those named."""
    if names:
        return [DAMPING_LAWS[name] for name in names]
    seen, laws = set(), []
    for law in DAMPING_LAWS.values():
        if law.name not in seen:
            seen.add(law.name)
            laws.append(law)
    return laws


def restitution_table(laws=None, targets=DEFAULT_TARGETS, velocities=DEFAULT_VELOCITIES, fruit: Fruit | None = None):
    """Achieved restitution of each law's published calibration.

    Parameters
    ----------
    laws : list of str, optional
        Law names (default: all registered laws).
    targets : sequence of float
        Requested restitution coefficients e in (0, 1].
    velocities : sequence of float
        Impact velocities [m/s].
    fruit : Fruit, optional
        Mass and stiffness used (default: the paper's Jonathan apple).

    Returns
    -------
    pandas.DataFrame
        Long form: law, title, family, target, velocity [m/s], damping_factor,
        achieved (restitution), error (achieved - target).
    """
    import pandas as pd

    fruit = fruit or Fruit()
    stiffness, _ = resolve_stiffness(fruit)
    grid_e, grid_v = np.meshgrid(np.asarray(targets, float), np.asarray(velocities, float), indexing="ij")
    e, v = grid_e.ravel(), grid_v.ravel()
    m = np.full_like(e, fruit.mass)
    k = np.full_like(e, stiffness)
    frames = []
    for law in unique_laws(laws):
        factor = damping_factor(law, "paper", e, m, k, v)
        if law.force_family.first_integral:
            achieved = exact_restitution(factor * v)
        else:
            achieved = achieved_restitution(law, factor, m, k, v)
        frames.append(pd.DataFrame(dict(law=law.name, title=law.title, family=law.force_family.formula,
                                        clamp=law.clamp, target=e, velocity=v, damping_factor=factor,
                                        achieved=achieved, error=achieved - e)))
    return pd.concat(frames, ignore_index=True)


def format_restitution_table(table) -> str:
    """One block per law: target rows × velocity columns of achieved e."""
    lines = []
    velocities = sorted(table["velocity"].unique())
    for name, block in table.groupby("law", sort=False):
        law = DAMPING_LAWS[name]
        lines.append(f"{name}: {law.title}   [{law.force_family.formula}{', clamped' if law.clamp and not law.force_family.first_integral else ''}]")
        lines.append(f"  validity: {law.validity}")
        if law.note:
            lines.append(f"  note: {law.note}")
        lines.append("  target e | achieved e at V_i = " + "  ".join(f"{v:>7.3g} m/s" for v in velocities))
        for target, rows in block.groupby("target"):
            values = rows.set_index("velocity")["achieved"]
            lines.append(f"  {target:>8.3f} | " + " " * 20 + "  ".join(f"{values[v]:>11.4f}" for v in velocities))
        lines.append("")
    return "\n".join(lines)
