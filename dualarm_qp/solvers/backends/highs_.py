"""HiGHS: an active-set QP method, through qpsolvers (sparse, the raw cost).

HiGHS checks its option values itself (:func:`check_highs_values`), and prints a banner
from its first instance in a process, which is sent to /dev/null
(:func:`silence_highs_banner`) before a solver of this backend is made.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from typing import Any

from ..registry import SolverOptionError
from .base import MANAGED_OPTIONS, TIME_LIMIT_S, Backend, OptionType


def highs_options() -> dict[str, OptionType]:
    """Return every option name ``Highs.getOptionType`` knows, with its type and default."""
    import highspy

    h = quiet_highs()
    kinds = {highspy.HighsOptionType.kBool: "bool",
             highspy.HighsOptionType.kInt: "int",
             highspy.HighsOptionType.kDouble: "float",
             highspy.HighsOptionType.kString: "str"}
    out = {}
    for name in dir(highspy.HighsOptions()):
        if name.startswith("_") or name in MANAGED_OPTIONS:
            continue
        status, kind = h.getOptionType(name)
        if status == highspy.HighsStatus.kOk and kind in kinds:
            out[name] = OptionType(kinds[kind], h.getOptionValue(name)[1])
    return out


def check_highs_values(name: str, options: dict[str, Any]) -> None:
    """HiGHS's own check of each value (range, type), through a silent instance.

    Raises
    ------
    SolverOptionError
        Naming the option HiGHS refuses.
    """
    import highspy

    h = quiet_highs()
    for key, value in options.items():
        if h.setOptionValue(key, value) != highspy.HighsStatus.kOk:
            raise SolverOptionError(name, key, f"HiGHS refuses the value {value!r} (out of "
                                    "its range or of the wrong type)")


def quiet_highs() -> Any:
    """Return a HiGHS instance that prints nothing, for checking option names and values."""
    import highspy

    silence_highs_banner()
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    return h


_HIGHS_BANNER_DONE = False


def silence_highs_banner() -> None:
    """Let HiGHS print its once-per-process banner into /dev/null.

    HiGHS (highspy 1.16) prints "Running HiGHS ... Copyright ..." from the constructor
    of its first instance in a process, before any option (``output_flag``,
    ``log_to_console``) can be set; later instances print nothing. One instance is
    built here with file descriptor 1 pointed at /dev/null, once per process. Whatever
    another thread writes to stdout in that moment (about a millisecond) is lost too.
    """
    global _HIGHS_BANNER_DONE
    if _HIGHS_BANNER_DONE:
        return
    _HIGHS_BANNER_DONE = True
    try:
        import highspy
    except ImportError:
        return
    with contextlib.suppress(OSError, ValueError, AttributeError):
        sys.stdout.flush()
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                try:
                    highspy.Highs()
                finally:
                    with contextlib.suppress(OSError, AttributeError, TypeError):
                        ctypes.CDLL(None).fflush(None)  # C stdio's buffer: to /dev/null
                    os.dup2(saved, 1)
        finally:
            os.close(saved)


BACKEND = Backend("highs", "highs", sparse=True, normalise_cost=False, profile={
    "primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10,
    "time_limit": TIME_LIMIT_S, "qp_iteration_limit": 1000},
    infeasible_words=("kInfeasible",), options=highs_options,
    check_values=check_highs_values, prepare=silence_highs_banner)


__all__ = ["BACKEND", "check_highs_values", "highs_options", "quiet_highs",
           "silence_highs_banner"]
