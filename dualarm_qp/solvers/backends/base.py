"""What a QP backend is to the ``qp:<backend>`` solvers: its profile, its options, its call.

A backend is one module of this package (``osqp_.py``, ``daqp_.py``, ...) that holds one
:class:`Backend`: the qpsolvers name, the pip extra that installs it, the tolerance
profile and limits it runs with, how its status says "infeasible", how to read the
options the installed package accepts (:class:`OptionType`), and, for osqp and
proxsuite, a native solver object kept across steps. The registry of backends is the
package (:data:`dualarm_qp.solvers.backends.BACKENDS`).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from ...step.problem import StepProblem
from .answer import BackendAnswer

#: Time limit [s] of one backend call where the backend takes one: a guard against a
#: runaway call (proxqp once took 49.6 s on one step), generous enough for a backend's
#: cold first call on a loaded machine (0.1 s was exceeded there).
TIME_LIMIT_S = 1.0

#: Options that dualarm-qp sets itself on every backend (output stays silent).
MANAGED_OPTIONS = frozenset({"verbose"})


@dataclass(frozen=True)
class OptionType:
    """Type of one backend option, read from the installed backend.

    Attributes
    ----------
    kind : str
        ``"bool"``, ``"int"``, ``"float"`` or ``"str"``.
    default : object
        The backend's default (decides the sign rule of tolerances).
    flag : bool
        An integer used as a switch (0 / 1): true and false are accepted too.
    choices : tuple, optional
        The values accepted, when only a few are.
    """

    kind: str
    default: Any = None
    flag: bool = False
    choices: tuple[Any, ...] | None = None


class NativeQP(Protocol):
    """A native backend object that solves a sequence of step QPs."""

    def solve(self, problem: StepProblem) -> BackendAnswer:
        """Update (or set up) the backend with ``problem`` and solve it."""
        ...


@dataclass(frozen=True)
class Backend:
    """How to call one qpsolvers backend on the step QP.

    Attributes
    ----------
    solver : str
        qpsolvers name of the backend (``"proxqp"``, ...).
    extra : str
        The dualarm-qp pip extra that installs it.
    sparse : bool
        Pass csc matrices (faster through qpsolvers for osqp, proxqp, clarabel, highs).
    warm_start : bool
        The backend uses ``initvals``; ``problem.x_prev`` is then passed when given.
    profile : dict
        Default options: tolerances and the iteration / time limit.
    infeasible_when_not_found : bool
        The backend reports no solution only for inconsistent constraints (quadprog).
    normalise_cost : bool
        Divide the cost by ``max(S)`` (:func:`.shifted.cost_weights`; same minimiser).
        Measured on 2,000 random and 1,975 recorded clearly feasible steps, misses
        before -> after: proxqp 8.5% / 17.9% -> 2.2% / 0.5%, clarabel 1.2% / 2.3% -> 0,
        quadprog 13% / 14% -> 0, piqp 0 / 0.4% -> 0; highs 0 / 0 -> 0.2% / 0.4%, so
        highs keeps the raw cost. The native osqp and proxqp paths always normalise.
    infeasible_words : tuple of str
        Words by which the backend's status text says the constraints are inconsistent.
    options : callable, optional
        Return the option names and types of the installed backend (may raise
        ImportError); None when there is no known list.
    check_values : callable, optional
        The backend's own check of option values, ``check_values(name, options)``
        (raises SolverOptionError).
    prepare : callable, optional
        Called once when a solver of this backend is made (HiGHS: its banner).
    native : callable, optional
        Make the native solver object kept across steps (from the options); None: the
        backend is called through qpsolvers.
    native_module : str
        The module the native object needs (it exists only where that is installed).
    """

    solver: str
    extra: str
    sparse: bool = False
    warm_start: bool = False
    profile: dict[str, Any] = field(default_factory=dict)
    infeasible_when_not_found: bool = False
    normalise_cost: bool = True
    infeasible_words: tuple[str, ...] = ()
    options: Callable[[], dict[str, OptionType] | None] | None = None
    check_values: Callable[[str, dict[str, Any]], None] | None = None
    prepare: Callable[[], None] | None = None
    native: Callable[[dict[str, Any]], NativeQP] | None = None
    native_module: str = ""

    def says_infeasible(self, text: str) -> bool:
        """Whether the backend's status text reports primal infeasibility."""
        return any(word.lower() in text.lower() for word in self.infeasible_words)


def kind_of(value: Any) -> str | None:
    """Return the option kind of a default value, or None when a file cannot give it."""
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int) and not isinstance(value, enum.Enum):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "str"
    return None  # enums, lists, methods: not settable from a file


def options_from_attributes(obj: Any) -> dict[str, OptionType]:
    """Return the options a settings object holds: its public attributes of a simple kind."""
    out: dict[str, OptionType] = {}
    for name in dir(obj):
        if name.startswith("_") or name in MANAGED_OPTIONS:
            continue
        try:
            value = getattr(obj, name)
        except Exception:  # a property that cannot be read is no option
            continue
        if callable(value) and not isinstance(value, (int, float, str)):
            continue
        kind = kind_of(value)
        if kind is not None:
            out[name] = OptionType(kind, value, flag=kind == "int" and value in (0, 1))
    return out


__all__ = ["MANAGED_OPTIONS", "TIME_LIMIT_S", "Backend", "NativeQP", "OptionType", "kind_of",
           "options_from_attributes"]
