"""The options of a ``qp:<backend>`` solver: their names and types, read from the backend.

A file or the command line may set any option the installed backend has
(:func:`backend_options`); :func:`check_backend_options` checks the names, the types and
the usual ranges before the backend sees them, and the backend judges the rest itself
once per set (``QPSolver``'s probe solve, silenced by :func:`quiet_output`).
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import math
import os
import sys
from typing import Any

from .backends import BACKENDS, Backend, OptionType
from .backends.base import MANAGED_OPTIONS
from .registry import SolverOptionError

#: Iteration limits that must be at least 1 (0 iterations never solves a step).
_ITERATION_LIMITS = frozenset({"max_iter", "max_iters", "maxiters", "iter_limit",
                               "qp_iteration_limit", "max_iter_in"})


def backend_of(solver: str) -> Backend | None:
    """Return the backend whose qpsolvers name is ``solver``, or None."""
    return next((b for b in BACKENDS.values() if b.solver == solver), None)


@functools.cache
def backend_options(solver: str) -> dict[str, OptionType] | None:
    """Option names and types of a qpsolvers backend, read from the installed package.

    Each backend module says how (``options`` of its :class:`~.backends.base.Backend`):
    osqp: the fields of its ``OSQPSettings`` (plus ``solver_type`` and
    ``cg_preconditioner``, which its wrapper translates); proxqp: the attributes of
    ``proxqp.dense.QP(...).settings``; daqp: the keywords of ``daqp.solve``; piqp: the
    attributes of ``DenseSolver().settings``; clarabel: those of ``DefaultSettings()``;
    highs: every name ``Highs.getOptionType`` knows (the value is then checked by
    ``setOptionValue``); quadprog: none. Enum-valued settings, which a file cannot give,
    and ``verbose`` (dualarm-qp keeps the backends silent) are left out. None for a
    backend that is not installed here or has no known list.
    """
    backend = backend_of(solver)
    if backend is None or backend.options is None:
        return None
    try:
        return backend.options()
    except ImportError:
        return None


def check_backend_options(name: str, solver: str, options: dict[str, Any]) -> dict[str, Any]:
    """Check option names, types and the usual ranges against the installed backend.

    Rules beyond the type: every number is finite (an infinite time limit or bound is
    allowed), integers are >= 0, iteration limits (``max_iter``, ``iter_limit``, ...)
    are >= 1, and tolerances (names with ``eps`` or ``tol``) are >= 0 unless the
    backend's default is negative. A HiGHS value is also checked by HiGHS itself
    (``setOptionValue``). An integer given for a real option becomes a float.

    Parameters
    ----------
    name : str
        Registry name (``"qp:osqp"``), for the messages.
    solver : str
        qpsolvers backend name.
    options : dict
        The options given.

    Returns
    -------
    dict
        The options, integers for real options converted to float.

    Raises
    ------
    SolverOptionError
        Naming the option: an unknown name (with the valid names), a wrong type (with
        the expected type) or a value out of range.
    """
    known = backend_options(solver)
    out: dict[str, Any] = {}
    for key, value in options.items():
        if key in MANAGED_OPTIONS:
            raise SolverOptionError(name, key, "set by dualarm-qp (the backends run "
                                    "silently); leave it out")
        if known is None:
            out[key] = value
            continue
        if key not in known:
            raise SolverOptionError(name, key, "unknown option",
                                    valid=sorted(known) or [f"none: {solver} takes no options"])
        out[key] = _check_value(name, key, value, known[key])
    backend = backend_of(solver)
    if backend is not None and backend.check_values is not None and out:
        backend.check_values(name, out)
    return out


def _check_value(name: str, key: str, value: Any, spec: OptionType) -> Any:
    """One option's value against its type and the range rules of check_backend_options."""
    def refuse(what: str) -> SolverOptionError:
        return SolverOptionError(name, key, what)

    if spec.choices is not None:
        if value not in spec.choices:
            raise SolverOptionError(name, key, f"invalid value {value!r}",
                                    valid=[str(c).lower() if c is None else str(c)
                                           for c in spec.choices])
        return value
    if spec.kind == "bool":
        if not isinstance(value, bool):
            raise refuse(f"expected true or false, got {value!r}")
        return value
    if spec.kind == "str":
        if not isinstance(value, str):
            raise refuse(f"expected text, got {value!r}")
        return value
    if isinstance(value, bool):
        if spec.kind == "int" and spec.flag:
            return int(value)
        raise refuse(f"expected {'an integer' if spec.kind == 'int' else 'a number'}, "
                     f"got {str(value).lower()}")
    if spec.kind == "int":
        if not isinstance(value, int):
            raise refuse(f"expected an integer, got {value!r}")
        low = 1 if key in _ITERATION_LIMITS else 0
        if value < low:
            raise refuse(f"must be >= {low}, got {value}")
        return value
    if not isinstance(value, (int, float)):
        raise refuse(f"expected a number, got {value!r}")
    number = float(value)
    if math.isnan(number) or (math.isinf(number) and not any(
            w in key for w in ("limit", "bound", "infinite", "max_time"))):
        raise refuse(f"expected a finite number, got {value!r}")
    default = spec.default if isinstance(spec.default, (int, float)) else 0.0
    if ("tol" in key or "eps" in key or "time" in key) and default >= 0 and number < 0:
        raise refuse(f"must be >= 0, got {value!r}")
    return number


@contextlib.contextmanager
def quiet_output() -> Any:
    """Send what C code prints to file descriptors 1 and 2 to /dev/null meanwhile.

    osqp prints "ERROR in validate_settings ..." from C when it refuses a setting; the
    refusal is reported as one SolverOptionError instead.
    """
    saved: list[int] = []
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        with open(os.devnull, "w") as null:
            for fd in (1, 2):
                saved.append(os.dup(fd))
                os.dup2(null.fileno(), fd)
    except (OSError, ValueError, AttributeError):
        pass  # no real descriptors (an embedded interpreter): let it print
    try:
        yield
    finally:
        with contextlib.suppress(OSError, AttributeError, TypeError):
            ctypes.CDLL(None).fflush(None)
        for fd, copy in zip((1, 2), saved, strict=False):
            os.dup2(copy, fd)
            os.close(copy)


__all__ = ["backend_of", "backend_options", "check_backend_options", "quiet_output"]
