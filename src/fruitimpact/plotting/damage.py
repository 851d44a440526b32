"""Figures of damage: a bruise-risk map (height × surface or height × firmness) and a packing-line audit."""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.plotting._backend import _pyplot


def risk_map_figure(key: str, columns, heights, rows, safe: dict, criterion: str):
    """Over drop height (x, log) and surface or modulus (y): the share of the lot bruised where the map dropped a
    lot (``incidence``), else the typical fruit's bruise margin; each column's safe height (the typical fruit)
    marked.  ``rows`` as from ``handling.heights.risk_map`` (column-major: all heights of the first column
    first)."""
    plt = _pyplot()
    lot = "incidence" in rows[0]
    name = "incidence" if lot else "bruise_margin"
    values = np.array([row[name] for row in rows], dtype=float).reshape(len(columns), len(heights))
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(columns) + 2.2), constrained_layout=True)
    labels = [str(c) if key == "surface" else f"{c / 1e6:g} MPa" for c in columns]
    logs = np.log(np.asarray(heights, dtype=float) * 100.0)
    edges = np.exp(np.concatenate(([1.5 * logs[0] - 0.5 * logs[1]], 0.5 * (logs[1:] + logs[:-1]),
                                   [1.5 * logs[-1] - 0.5 * logs[-2]])))
    if lot:
        image = ax.pcolormesh(edges, np.arange(len(columns) + 1) - 0.5, values * 100.0, cmap="RdYlGn_r",
                              vmin=0.0, vmax=100.0)
    else:
        limit = np.nanmax(np.abs(values[np.isfinite(values)])) if np.isfinite(values).any() else 1.0
        limit = min(max(limit, 1e-3), 5.0)
        image = ax.pcolormesh(edges, np.arange(len(columns) + 1) - 0.5, np.clip(values, -limit, limit),
                              cmap="RdYlGn_r", vmin=-limit, vmax=limit)
    for j, column in enumerate(columns):
        height = safe.get(str(column), math.nan)
        if math.isfinite(height) and height > 0:
            ax.plot([height * 100.0] * 2, [j - 0.45, j + 0.45], color="black", lw=2)
    ax.set_xscale("log")
    ax.set_yticks(range(len(columns)), labels)
    ax.set_xlabel("drop height h [cm]")
    ax.set_ylabel("surface" if key == "surface" else "Young's modulus E")
    if lot:
        ax.set_title(f"bruise risk, criterion {criterion}: share of the lot bruised; black: the typical fruit's "
                     f"safe drop height")
        fig.colorbar(image, ax=ax, label="bruised fruit [%]")
    else:
        ax.set_title(f"bruise risk, criterion {criterion}: margin (≥ 0 bruised); black: safe drop height")
        fig.colorbar(image, ax=ax, label="bruise margin [-]")
    return fig


def line_figure(report: dict):
    """Incidence and mean bruise volume at each transfer point, and cumulated along the line."""
    plt = _pyplot()
    points = report["points"]
    names = [p["name"] for p in points]
    x = np.arange(len(points))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(max(6, 0.9 * len(points) + 3), 6.5), sharex=True,
                                      constrained_layout=True)
    top.bar(x, [p["incidence"] * 100 for p in points], color="tab:red", alpha=0.7, label="at the point")
    top.plot(x, [p["cumulative_incidence"] * 100 for p in points], "k-o", label="cumulated along the line")
    top.set_ylabel("bruised fruit [%]")
    top.legend()
    top.set_title(f"packing-line audit ({report['fruit']} fruit, criterion {report['criterion']}); "
                  f"most harmful: {report['worst_point']}")
    bottom.bar(x, [p["mean_bruise_volume"] * 1e9 for p in points], color="tab:purple", alpha=0.7,
               label="at the point")
    bottom.plot(x, [p["cumulative_bruise_volume"] * 1e9 for p in points], "k-o", label="cumulated")
    bottom.set_ylabel("mean bruise volume [mm³]")
    bottom.set_xticks(x, names, rotation=30, ha="right")
    bottom.legend()
    return fig


__all__ = ["line_figure", "risk_map_figure"]
