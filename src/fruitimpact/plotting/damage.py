"""Figures of damage: a bruise-risk map (height × surface or height × firmness) and a packing-line audit."""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.plotting._backend import _pyplot


def risk_map_figure(key: str, columns, heights, rows, safe: dict, criterion: str):
    """Bruise margin over drop height (x, log) and surface or modulus (y), with each column's safe
    height marked; ``rows`` as from ``handling.heights.risk_map`` (column-major: all heights of the first
    column first)."""
    plt = _pyplot()
    margin = np.array([row["bruise_margin"] for row in rows], dtype=float).reshape(len(columns), len(heights))
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(columns) + 2.2), constrained_layout=True)
    limit = np.nanmax(np.abs(margin[np.isfinite(margin)])) if np.isfinite(margin).any() else 1.0
    limit = min(max(limit, 1e-3), 5.0)
    labels = [str(c) if key == "surface" else f"{c / 1e6:g} MPa" for c in columns]
    logs = np.log(np.asarray(heights, dtype=float) * 100.0)
    edges = np.exp(np.concatenate(([1.5 * logs[0] - 0.5 * logs[1]], 0.5 * (logs[1:] + logs[:-1]),
                                   [1.5 * logs[-1] - 0.5 * logs[-2]])))
    image = ax.pcolormesh(edges, np.arange(len(columns) + 1) - 0.5,
                          np.clip(margin, -limit, limit), cmap="RdYlGn_r", vmin=-limit, vmax=limit)
    for j, column in enumerate(columns):
        height = safe.get(str(column), math.nan)
        if math.isfinite(height) and height > 0:
            ax.plot([height * 100.0] * 2, [j - 0.45, j + 0.45], color="black", lw=2)
    ax.set_xscale("log")
    ax.set_yticks(range(len(columns)), labels)
    ax.set_xlabel("drop height h [cm]")
    ax.set_ylabel("surface" if key == "surface" else "Young's modulus E")
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
