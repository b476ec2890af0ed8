"""Figures of runs, reproductions and the HTML report's pictures (matplotlib, no pyplot).

Imported only when a figure is drawn: ``import dualarm_qp`` and the command line's help
do not import matplotlib.

- :mod:`.canvas`: the Agg canvas, limit lines, shaded out-of-range spans, speed axes;
- :mod:`.rundata`: a run's ``trajectory.csv`` and the limits it had;
- :mod:`.run_figures`: the PNG figures of one run;
- :mod:`.clearance`: a run's clearance against the safety and influence distances;
- :mod:`.compare`: one quantity of several runs (the reproduction's Figs. 5 and 6);
- :mod:`.avoidance`: several runs' clearance and grasp travel (``dualarm-qp collisions``).
"""

from .avoidance import avoidance_figure
from .clearance import CLEARANCE_FIGURE, clearance_figure
from .compare import Curve, comparison_figure
from .run_figures import (
    RUN_FIGURES,
    closure_figure,
    grasp_figure,
    joints_figure,
    rates_figure,
    tracking_figure,
    write_run_figures,
)
from .rundata import DisplayUnits, PlotLimits, RunData

__all__ = ["CLEARANCE_FIGURE", "RUN_FIGURES", "Curve", "DisplayUnits", "PlotLimits", "RunData",
           "avoidance_figure", "clearance_figure", "closure_figure", "comparison_figure",
           "grasp_figure", "joints_figure", "rates_figure", "tracking_figure",
           "write_run_figures"]
