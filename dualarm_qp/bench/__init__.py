"""Benchmarks: every configuration with every solver, and the step-instance suite.

This package sits at the top of the library beside :mod:`dualarm_qp.experiments`: it
may import from everything below it, and nothing below imports it.

* :mod:`.runner`: (configuration x solver) rollouts and replays, stored one JSON line
  per finished pair so that an interrupted bench resumes;
* :mod:`.suite`: scoring of solvers on a file of recorded step problems, the way
  qpbenchmark scores QP solvers;
* :mod:`.report`: table, CSV, JSON and plot;
* :mod:`.store`: the result store shared by concurrent benches (a job cut short by
  SIGINT / SIGTERM is never stored: see :mod:`.runner` and :mod:`dualarm_qp._signals`).
"""

from .report import COLUMNS, format_table, objective_gaps, write_report
from .runner import BenchInterrupted, BenchResult, BenchSettings, run_bench, run_job

__all__ = [
    "COLUMNS",
    "BenchInterrupted",
    "BenchResult",
    "BenchSettings",
    "format_table",
    "objective_gaps",
    "run_bench",
    "run_job",
    "write_report",
]
