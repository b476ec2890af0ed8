"""Figures of runs, reproductions and the HTML report's pictures (matplotlib, no pyplot).

Imported only when a figure is drawn: ``import dualarm_qp``, the command line's help
and this package itself do not import matplotlib (the names below are imported on
first access).

- :mod:`.canvas`: the Agg canvas, limit lines, shaded out-of-range spans, speed axes;
- :mod:`.rundata`: a run's ``trajectory.csv`` and the limits it had;
- :mod:`.lanes`: the joints and joint rates, one axis per arm and one lane per joint;
- :mod:`.lane_model`: a lane's scale (a joint against its limits) and its label;
- :mod:`.run_figures`: the PNG figures of one run;
- :mod:`.process`: a run's figures drawn in other processes while the run goes on;
- :mod:`.ready`: a run's figures' axes, built by the drawing process before the trace comes;
- :mod:`.clearance`: a run's clearance against the safety and influence distances;
- :mod:`.compare`: one quantity of several runs (the reproduction's Figs. 5 and 6);
- :mod:`.avoidance`: several runs' clearance and grasp travel (``dualarm-qp collisions``).
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from ..._lazy import lazy_names as _lazy_names

if _TYPE_CHECKING:
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

#: Names imported on first access, and the module each comes from.
_LAZY = {
    "avoidance_figure": "avoidance",
    "CLEARANCE_FIGURE": "clearance",
    "clearance_figure": "clearance",
    "Curve": "compare",
    "comparison_figure": "compare",
    "RUN_FIGURES": "run_figures",
    "closure_figure": "run_figures",
    "grasp_figure": "run_figures",
    "joints_figure": "run_figures",
    "rates_figure": "run_figures",
    "tracking_figure": "run_figures",
    "write_run_figures": "run_figures",
    "DisplayUnits": "rundata",
    "PlotLimits": "rundata",
    "RunData": "rundata",
}

__all__ = ["CLEARANCE_FIGURE", "RUN_FIGURES", "Curve", "DisplayUnits", "PlotLimits", "RunData",
           "avoidance_figure", "clearance_figure", "closure_figure", "comparison_figure",
           "grasp_figure", "joints_figure", "rates_figure", "tracking_figure",
           "write_run_figures"]


#: Import a name of :data:`_LAZY` from its module on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
