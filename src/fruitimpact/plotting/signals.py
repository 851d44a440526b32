"""Figures of measured impacts: a recording with its impacts, and the first impacts' data with their fits."""

from __future__ import annotations

import numpy as np

from fruitimpact.plotting._backend import _pyplot

#: Impacts drawn in detail (data and fit).
DETAIL = 4


def analysis_figure(recording, impacts, reports, analysis):
    """Top: every lane's force over time with the impacts marked (rebounds in orange). Bottom: the first
    ``DETAIL`` impacts' samples (baseline removed) with the fitted simulator pulse when ``analysis.fit``."""
    plt = _pyplot()
    detail = min(len(impacts), DETAIL)
    fig = plt.figure(figsize=(10, 6.5 if detail else 3.5), constrained_layout=True)
    grid = fig.add_gridspec(2 if detail else 1, max(detail, 1))
    top = fig.add_subplot(grid[0, :])
    time = recording.time()
    step = max(1, recording.samples // 200_000)  # enough points for the eye
    for name in recording.lane_names:
        top.plot(time[::step], recording.lanes[name][::step], lw=0.6, label=name)
    for impact, report in zip(impacts, reports):
        colour = "tab:orange" if report.get("rebound") else "tab:red"
        top.axvline(report["start_time"], color=colour, lw=0.5, alpha=0.6)
    top.set_xlabel("time [s]")
    top.set_ylabel("force [N]")
    top.set_title(f"{len(impacts)} impacts (red; rebounds orange)")
    if len(recording.lanes) > 1:
        top.legend(fontsize=8)
    if detail:
        from fruitimpact.signals.fit import model_curve

        for k in range(detail):
            impact, report = impacts[k], reports[k]
            ax = fig.add_subplot(grid[1, k])
            t = (impact.window_start + np.arange(impact.window.size)) / recording.rate
            ax.plot((t - t[0]) * 1e3, impact.window, ".", ms=2, color="0.3", label="data")
            if analysis.fit and report.get("fit_converged"):
                fine = np.linspace(t[0], t[-1], 600)
                ax.plot((fine - t[0]) * 1e3, model_curve(fine, report["_fit"]), color="tab:red", lw=1.2,
                        label="fit")
            ax.set_xlabel("time in window [ms]")
            ax.set_title(f"#{k + 1}: F_max {report['peak_force']:.3g} N", fontsize=9)
            if k == 0:
                ax.set_ylabel("force [N]")
                ax.legend(fontsize=7)
    return fig


__all__ = ["analysis_figure"]
