"""Figures (optional extra ``plot``: matplotlib is imported only inside this package, on first use).

* ``impact_figure``: the paper's Figures 4–7 of one or several impacts;
* ``sweep_figure``, ``histogram_figure``: a sweep over its grid, a population's histograms;
* ``restitution_figure``: achieved against requested restitution of every damping law;
* ``risk_map_figure``, ``line_figure``: bruise risk over height and surface, a packing-line audit;
* ``save_figure``: writes any of them atomically, the format chosen by the extension.
"""

from fruitimpact.plotting._backend import save_figure
from fruitimpact.plotting.damage import line_figure, risk_map_figure
from fruitimpact.plotting.impact import impact_figure
from fruitimpact.plotting.models import restitution_figure
from fruitimpact.plotting.runs import histogram_figure, sweep_figure

__all__ = ["histogram_figure", "impact_figure", "line_figure", "restitution_figure", "risk_map_figure", "save_figure",
           "sweep_figure"]
