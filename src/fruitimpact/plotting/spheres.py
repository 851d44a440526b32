"""Figures of a sphere audit: the line (equivalent drops, incidence and cushion savings per point) and the chart
of peak g against ΔV with the lot's own incidence lines."""

from __future__ import annotations

import numpy as np

from fruitimpact.plotting._backend import _pyplot


def sphere_figure(report: dict):
    """Three panels: equivalent drop per point (median of the passes, and the largest), incidence per point with
    the cumulated line and what the advised cushion saves, and peak g against ΔV (each reading a point, by
    transfer point) with the 10 % and 50 % incidence lines of the lot (``report["chart"]``)."""
    plt = _pyplot()
    points = [p for p in report["points"] if p["incidence"] is not None]
    names = [p["name"] for p in points]
    x = np.arange(len(points))
    fig = plt.figure(figsize=(max(11, 0.9 * len(points) + 7), 7.5), constrained_layout=True)
    grid = fig.add_gridspec(2, 2, width_ratios=(1.2, 1))
    drops, incidence, chart = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[1, 0]), fig.add_subplot(grid[:, 1])
    drops.bar(x, [p["drop_height"] * 100 for p in points], color="tab:blue", alpha=0.7, label="median of the passes")
    drops.plot(x, [p["drop_height_max"] * 100 for p in points], "kv", label="largest reading")
    drops.set_ylabel("equivalent drop height [cm]")
    drops.set_xticks(x, [])
    drops.legend()
    drops.set_title(f"sphere {report['sphere']['name']}: {report['readings']} readings; lot of {report['rows']} "
                    f"fruit, criterion {report['criterion']}")
    incidence.bar(x, [p["incidence"] * 100 for p in points], color="tab:red", alpha=0.7, label="at the point")
    incidence.plot(x, [p["cumulative_incidence"] * 100 for p in points], "k-o", label="cumulated along the line")
    advised = [(k, p["cushion"]) for k, p in enumerate(points) if p.get("cushion") and p["cushion"]["surface"]]
    if advised:
        incidence.bar([k for k, _ in advised], [c["incidence"] * 100 for _, c in advised], width=0.4,
                      color="tab:green")
        # a marker too: a cushion that saves every fruit has a bar of height 0
        incidence.plot([k for k, _ in advised], [c["incidence"] * 100 for _, c in advised], "v", color="tab:green",
                       ms=9, label="with the advised cushion")
    incidence.axhline(report["target"] * 100, color="grey", ls=":", label="target")
    incidence.set_ylabel("bruised fruit [%]")
    incidence.set_xticks(x, names, rotation=30, ha="right")
    incidence.legend(fontsize="small")
    incidence.set_title(f"most harmful: {report['worst_point']}")
    by_point = {}
    for impact in report["impacts"]:
        if impact["status"] == "ok":
            by_point.setdefault(impact["point"], []).append(impact)
    for name, impacts in by_point.items():
        chart.plot([i["velocity_change"] for i in impacts], [i["peak_acceleration"] / 9.80665 for i in impacts],
                   "o", ms=4, alpha=0.7, label=str(name))
    styles = {"0.1": ("tab:orange", "10 % of this lot bruised"), "0.5": ("tab:red", "50 % of this lot bruised")}
    for fraction, line in (report.get("chart") or {}).get("fractions", {}).items():
        if line:
            color, label = styles.get(fraction, ("black", fraction))
            chart.plot([p["velocity_change"] for p in line], [p["peak_g"] for p in line], "-", color=color, lw=2,
                       label=label)
    chart.set_xlabel("velocity change ΔV [m/s]")
    chart.set_ylabel("peak acceleration [g]")
    chart.set_yscale("log")
    chart.legend(fontsize="small", ncol=2)
    chart.set_title("readings; lines: soft surfaces (right) to rigid (left)")
    return fig


__all__ = ["sphere_figure"]
