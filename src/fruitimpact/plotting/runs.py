"""Figures of large runs: a sweep's characteristic over its grid, a population's histograms."""

from __future__ import annotations

import numpy as np

from fruitimpact.impact.quantities import CHARACTERISTICS, INPUTS
from fruitimpact.plotting._backend import _pyplot

#: A second swept input with more values than this is drawn as a heat map, not as lines.
MAX_LINES = 8


def sweep_figure(grid, values: np.ndarray, name: str):
    """Characteristic ``name`` over the swept axes of ``grid``; invalid points are left blank.

    Parameters
    ----------
    grid : fruitimpact.runs.GridSource
        The sweep's axes (first axis slowest).
    values : numpy.ndarray
        Column ``name`` of every grid point [SI], in row order.
    name : str
        A characteristic (``quantities.CHARACTERISTICS``), drawn in display units.

    Returns the matplotlib Figure: a heat map for two swept inputs whose second has more
    than ``MAX_LINES`` numeric values, else one line (per value of the second input).
    """
    plt = _pyplot()
    quantity = CHARACTERISTICS[name]
    swept = [(i, a) for i, a in enumerate(grid.axes) if len(a.values) > 1]
    cube = np.asarray(values, dtype=float).reshape(grid.shape) * quantity.scale
    cube = cube.reshape([len(a.values) for _, a in swept]) if swept else cube.reshape(1)
    if len(swept) == 2 and not swept[0][1].numeric and swept[1][1].numeric:
        swept, cube = swept[::-1], cube.T
    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    x_axis = swept[0][1]
    x_q = INPUTS.get(x_axis.name)
    x = np.asarray(x_axis.values, dtype=float) * x_q.scale if x_axis.numeric else list(x_axis.values)
    if len(swept) == 2 and swept[1][1].numeric and len(swept[1][1].values) > MAX_LINES and x_axis.numeric:
        y_axis = swept[1][1]
        y_q = INPUTS[y_axis.name]
        mesh = ax.pcolormesh(x, np.asarray(y_axis.values) * y_q.scale, cube.T, shading="nearest")
        fig.colorbar(mesh, ax=ax, label=quantity.axis_label)
        ax.set_ylabel(y_q.axis_label)
        if y_axis.log:
            ax.set_yscale("log")
    else:
        if len(swept) == 2:
            other = swept[1][1]
            o_q = INPUTS.get(other.name)
            for j, value in enumerate(other.values):
                label = value if not other.numeric else f"{o_q.label} = {value * o_q.scale:.4g} {o_q.unit}".rstrip()
                ax.plot(x, cube[:, j], marker="." if len(x) < 40 else None, label=label)
            ax.legend(fontsize=8)
        else:
            ax.plot(x, cube, marker="." if len(x) < 40 else None)
        ax.set_ylabel(quantity.axis_label)
        ax.grid(True, alpha=0.3)
    ax.set_xlabel(x_q.axis_label if x_q is not None else x_axis.name)
    if x_axis.numeric and x_axis.log:
        ax.set_xscale("log")
    ax.set_title(f"fruitimpact sweep: {quantity.label}")
    return fig


def histogram_figure(sample: np.ndarray, names: tuple, exact: bool):
    """Histograms of a population's characteristics.

    Parameters
    ----------
    sample : numpy.ndarray
        Values [SI], one column per name (``RunSummary.sample``).
    names : tuple of str
        The characteristics of the columns, drawn in display units.
    exact : bool
        Whether ``sample`` holds every ok member (else the title says it is a sample).

    Returns the matplotlib Figure.
    """
    plt = _pyplot()
    cols = min(3, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), constrained_layout=True, squeeze=False)
    for ax, (j, name) in zip(axes.flat, enumerate(names)):
        quantity = CHARACTERISTICS[name]
        column = sample[:, j]
        column = column[np.isfinite(column)] * quantity.scale
        low, high = (float(column.min()), float(column.max())) if column.size else (0.0, 1.0)
        pad = 1e-6 * max(abs(low), abs(high), 1e-300)
        if high - low <= pad:  # (nearly) constant: one bar
            ax.hist(column, bins=1, range=(low - pad, high + pad), color="tab:blue", alpha=0.8)
        else:
            ax.hist(column, bins=60, color="tab:blue", alpha=0.8)
        ax.set(xlabel=quantity.axis_label, ylabel="members")
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[len(names):]:
        ax.set_visible(False)
    fig.suptitle("fruitimpact population" + ("" if exact else f" (uniform sample of {sample.shape[0]} members)"))
    return fig
