"""The chart sphere users know — peak g against ΔV — with the incidence lines of *their* lot.

Vendors draw one empirical boundary pooled over varieties (Techmark's apple line: 10 % bruise likelihood
over five varieties).  Here the boundary is computed for the lot being audited: for surfaces from soft to
rigid (half-spaces of modulus E_w, and rigid), the drop height at which ``fraction`` of the lot bruises
(``line``'s audit of the same lot, interpolated in ln h), and the reading the same sphere would make there
(the pulse relations of ``spheres.pulse``, at the log's median restitution): each surface gives one point
(ΔV, peak g) of the line.  Softer surfaces need a higher ΔV for the same damage, so the line slopes as the
vendor's does, but it is this lot's.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.spheres.pulse import peak_force

#: Surface moduli [Pa] of the chart's lines (and rigid); heights [m] searched for each.
CHART_MODULI = (0.5e6, 1e6, 2e6, 4e6, 8e6, 16e6, 32e6, 64e6, 128e6, math.inf)
CHART_HEIGHTS = tuple(float(h) for h in np.geomspace(0.002, 1.5, 24))
#: Fruit of the lot for the chart's lines (at most: the lines are of a lot, not of a sample's noise).
CHART_FRUIT = 2000
FRACTIONS = (0.1, 0.5)


def incidence_lines(sphere, restitution: float, surface_poisson: float, *, rows: int, seed: int, criterion: str,
                    spreads: bool, inputs: dict) -> dict:
    """{"fractions": {"0.1": [{"surface_modulus", "drop_height", "velocity_change", "peak_g"}, …], …}}: the
    readings of ``sphere`` at which each fraction of the lot bruises, one per surface of ``CHART_MODULI``
    (None for rigid); a surface on which the fraction is not reached within ``CHART_HEIGHTS`` is left out."""
    from fruitimpact.handling.line import TransferPoint, audit_line

    rows = min(rows, CHART_FRUIT)
    lines = {str(f): [] for f in FRACTIONS}
    for modulus in CHART_MODULI:
        rigid = math.isinf(modulus)
        points = [TransferPoint(f"{h:.6g}", h, "steel", surface_modulus=None if rigid else float(modulus),
                                surface_poisson=None if rigid else float(surface_poisson)) for h in CHART_HEIGHTS]
        report = audit_line(points, rows=rows, seed=seed, criterion=criterion, alternatives=(), spreads=spreads,
                            **inputs)
        incidence = np.array([p["incidence"] for p in report["points"]], dtype=float)
        heights = np.array(CHART_HEIGHTS)
        contact = sphere.contact_modulus_on(modulus, surface_poisson)
        stiffness = 4.0 / 3.0 * contact * math.sqrt(sphere.radius)
        for fraction in FRACTIONS:
            above = np.flatnonzero(incidence >= fraction)
            if above.size == 0:
                continue
            k = int(above[0])
            if k == 0:
                height = heights[0]
            else:  # interpolate in ln h between the heights that bracket the fraction
                low, high = incidence[k - 1], incidence[k]
                share = (fraction - low) / (high - low) if high > low else 1.0
                height = float(np.exp(np.log(heights[k - 1]) + share * (np.log(heights[k]) - np.log(heights[k - 1]))))
            velocity = math.sqrt(2.0 * STANDARD_GRAVITY * height)
            force = float(peak_force(restitution, sphere.mass, stiffness, velocity))
            lines[str(fraction)].append({"surface_modulus": None if rigid else float(modulus), "drop_height": height,
                                         "velocity_change": (1.0 + restitution) * velocity,
                                         "peak_g": force / sphere.mass / STANDARD_GRAVITY})
    return {"restitution": restitution, "fruit": rows, "fractions": lines}


__all__ = ["CHART_MODULI", "FRACTIONS", "incidence_lines"]
