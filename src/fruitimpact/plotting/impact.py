"""The four-panel figure of single impacts.

``impact_figure`` draws the paper's Figures 4–7 as one four-panel figure:
δ(t) (Fig 4), δ̇(t) (Fig 5), F(δ) (Fig 6) and F(t) (Fig 7), for one or several
results overlaid (models, calibrations, solvers).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from fruitimpact.plotting._backend import _pyplot


def _label(result) -> str:
    inputs = result.inputs
    return f"{inputs.model}, {inputs.calibration}, {inputs.method} (e = {result.characteristics.restitution:.3f})"


def impact_figure(results, labels: Sequence[str] | None = None, title: str | None = None):
    """Four-panel figure of one or several ``ImpactResult`` (or a mapping label → result).

    Returns the matplotlib Figure; save it with ``save_figure``."""
    plt = _pyplot()
    if isinstance(results, Mapping):
        labels = list(results.keys())
        results = list(results.values())
    elif not isinstance(results, Sequence):
        results = [results]
    labels = list(labels) if labels is not None else [_label(r) for r in results]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), constrained_layout=True)
    (ax_d, ax_v), (ax_fd, ax_ft) = axes
    for result, label in zip(results, labels):
        curves = result.curves
        t_ms = curves.time * 1e3
        d_mm = curves.deflection * 1e3
        style = dict(marker="." if result.inputs.method == "rk4" else None, markersize=3, label=label)
        ax_d.plot(t_ms, d_mm, **style)
        ax_v.plot(t_ms, curves.rate, **style)
        ax_fd.plot(d_mm, curves.force, **style)
        ax_ft.plot(t_ms, curves.force, **style)
        c = result.characteristics
        ax_ft.plot([c.time_to_peak * 1e3], [c.peak_force], "o", color=ax_ft.lines[-1].get_color(), ms=4)
    ax_d.set(xlabel="time t [ms]", ylabel="deflection δ [mm]", title="Deflection (paper Fig. 4)")
    ax_v.set(xlabel="time t [ms]", ylabel="deflection rate δ̇ [m/s]", title="Deflection rate (paper Fig. 5)")
    ax_v.axhline(0.0, color="0.6", lw=0.8)
    ax_fd.set(xlabel="deflection δ [mm]", ylabel="force F [N]", title="Force–deflection (paper Fig. 6)")
    ax_ft.set(xlabel="time t [ms]", ylabel="force F [N]", title="Force–time (paper Fig. 7)")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return fig
