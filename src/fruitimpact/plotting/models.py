"""What each damping law really produces: achieved against requested restitution."""

from __future__ import annotations

import numpy as np

from fruitimpact.plotting._backend import _pyplot


def restitution_figure(table, velocity=None):
    """Achieved vs requested restitution, one line per law, at one velocity.

    Parameters
    ----------
    table : pandas.DataFrame
        ``comparison.restitution_table``'s long form (law, target, velocity [m/s], achieved).
    velocity : float, optional
        Impact velocity [m/s] drawn (default: the middle one of the table).

    Returns the matplotlib Figure; save it with ``save_figure``.
    """
    from fruitimpact.physics import DAMPING_LAWS

    plt = _pyplot()
    velocities = sorted(table["velocity"].unique())
    velocity = velocity if velocity is not None else velocities[len(velocities) // 2]
    fig, ax = plt.subplots(figsize=(7.5, 6), constrained_layout=True)
    subset = table[np.isclose(table["velocity"], velocity)]
    colours = plt.get_cmap("tab20").colors
    for i, (name, rows) in enumerate(subset.groupby("law", sort=False)):
        # a colour per law, a line style per kind of family: 18 laws stay distinguishable
        style = "-" if DAMPING_LAWS[name].force_family.first_integral else "--"
        ax.plot(rows["target"], rows["achieved"], style, marker="o", ms=3, color=colours[i % len(colours)],
                label=name)
    ax.plot([0, 1], [0, 1], color="0.3", lw=1, ls="--", label="achieved = requested")
    ax.set(xlabel="requested restitution e [-]", ylabel="achieved restitution e [-]", xlim=(0, 1), ylim=(0, 1),
           title=f"Published calibrations at V_i = {velocity:g} m/s")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig
