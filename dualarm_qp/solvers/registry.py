"""Registry of step solvers, by name.

A solver module registers itself with one call to :func:`register`; importing
:mod:`dualarm_qp.solvers` imports every solver module. Unavailable solvers (a backend
that is not installed) stay listed, with the pip extra that installs them.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..errors import InvalidInputError, PairingError, SolverNotFoundError
from .base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance, failed
from .certify import certify

if TYPE_CHECKING:

    from ..step.problem import StepProblem


@dataclass(frozen=True)
class SolverInfo:
    """One registry entry.

    Attributes
    ----------
    name : str
        Registry name, e.g. ``"nullspace"`` or ``"qp:osqp"``.
    description : str
        One line for ``dualarm-qp solvers``.
    available : bool
        Whether the solver can run on this machine (asked of its backend the first time
        it is read: ``register`` may give a function).
    extra : str or None
        The pip extra of dualarm-qp that installs what the solver needs.
    hard_bounds : bool
        Whether the solver guarantees the bounds (False for the paper's reference step).
    takes_rows : bool
        Whether the solver keeps general rows ``G x <= h`` (collision, wall, torque
        limits); a solver that takes boxes only refuses a problem with rows.
    dense_cost : bool
        Whether the solver takes a full (non-diagonal) weighting matrix ``W``.
    certifies_in_kernel : bool
        Whether the solver (an instance of ``factory``, a class) has
        ``solve_certified(problem, tol, claims_bounds)``: its solve and the kernel's
        certificate of the answer in one call, the verdict given by
        :func:`~.certify.verdict` as for every solver (the exact ``nullspace`` solver).
    """

    name: str
    description: str
    _available: bool | Callable[[], bool]
    extra: str | None
    hard_bounds: bool
    factory: Callable[..., StepSolver]
    takes_rows: bool = True
    dense_cost: bool = True
    certifies_in_kernel: bool = False

    @property
    def available(self) -> bool:
        """Whether the solver can run on this machine (see the class docstring)."""
        found = self._available
        if not isinstance(found, bool):
            found = bool(found())
            object.__setattr__(self, "_available", found)
        return found

    def refusal(self, row_limits: Iterable[str] = (), dense_cost: bool = False) -> str | None:
        """Why this solver cannot take a step with these parts, or None if it can.

        Parameters
        ----------
        row_limits : iterable of str
            Names of the limits of the step that give general rows.
        dense_cost : bool
            Whether the step's cost is a full matrix.
        """
        rows = tuple(row_limits)
        if rows and not self.takes_rows:
            able = [i.name for i in _REGISTRY.values()
                    if i.takes_rows and i.available and i.hard_bounds]
            what = "keeps no limits" if not self.hard_bounds else "takes boxes only"
            return (f"solver '{self.name}' {what}, and the limit "
                    f"{', '.join(repr(r) for r in rows)} gives rows; solvers that keep "
                    f"rows: {', '.join(able)}")
        if dense_cost and not self.dense_cost:
            able = [i.name for i in _REGISTRY.values()
                    if i.dense_cost and i.available and i.hard_bounds]
            return (f"solver '{self.name}' takes a diagonal cost only; solvers that take "
                    f"a full weighting matrix: {', '.join(able)}")
        return None


def check_pairing(info: SolverInfo, row_limits: Iterable[str] = (),
                  dense_cost: bool = False) -> None:
    """Check that a solver can take a step's parts (the one pairing check).

    Called where a controller is built (before anything runs) and, for a problem handed
    to a solver directly, by :class:`CertifiedSolver` (which then answers ERROR).

    Raises
    ------
    PairingError
        ``info``'s solver takes boxes only and some limit gives rows, or it takes a
        diagonal cost only and the cost is full. The message names the solver, the
        limits and the solvers that can take them.
    """
    rows = tuple(dict.fromkeys(row_limits))
    why = info.refusal(rows, dense_cost)
    if why is not None:
        able = [i.name for i in _REGISTRY.values() if i.available and i.hard_bounds
                and (i.takes_rows or not rows) and (i.dense_cost or not dense_cost)]
        raise PairingError(why, solver=info.name, limits=rows, able=able)


class SolverOptionError(InvalidInputError):
    """A solver option with an unknown name, a wrong type or a value out of range.

    Attributes
    ----------
    solver : str
        Registry name of the solver.
    option : str
        The offending option.
    valid : tuple of str
        The option names the solver accepts (for an unknown name), else empty.
    """

    def __init__(self, solver: str, option: str, message: str, *,
                 valid: Iterable[str] = ()) -> None:
        self.solver = solver
        self.option = option
        self.valid = tuple(valid)
        self.reason = message
        text = f"solver '{solver}' option '{option}': {message}"
        if self.valid:
            text += f" (valid: {', '.join(self.valid)})"
        super().__init__(text)


def check_number(solver: str, option: str, value: Any, *, integer: bool = False,
                 minimum: float | None = None, strict: bool = False) -> None:
    """Check one numeric option of a solver (the constructors' shared check).

    Parameters
    ----------
    solver, option : str
        Names for the message.
    value : object
        The value given.
    integer : bool
        Require an integer.
    minimum : float, optional
        Lower bound.
    strict : bool
        The bound is exclusive (``value > minimum``).

    Raises
    ------
    SolverOptionError
        A boolean, a non-number, NaN or infinity, a non-integer where one is needed,
        or a value below the bound.
    """
    kind = "an integer" if integer else "a number"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SolverOptionError(solver, option, f"expected {kind}, got {value!r}")
    if integer and not isinstance(value, int):
        raise SolverOptionError(solver, option, f"expected {kind}, got {value!r}")
    if not math.isfinite(value):
        raise SolverOptionError(solver, option, f"expected a finite number, got {value!r}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        rel = ">" if strict else ">="
        raise SolverOptionError(solver, option, f"must be {rel} {minimum:g}, got {value!r}")


def check_tolerance(solver: str, value: Any) -> None:
    """Check a solver's ``tol`` argument (a :class:`~.base.Tolerance`).

    Raises
    ------
    SolverOptionError
        ``value`` is not a Tolerance (a file cannot give one).
    """
    from .base import Tolerance

    if not isinstance(value, Tolerance):
        raise SolverOptionError(solver, "tol", f"expected a Tolerance object, got {value!r}")


_REGISTRY: dict[str, SolverInfo] = {}
_ALIASES: dict[str, str] = {}


def register(
    name: str,
    factory: Callable[..., StepSolver],
    *,
    description: str,
    available: bool | Callable[[], bool] = True,
    extra: str | None = None,
    hard_bounds: bool = True,
    takes_rows: bool = True,
    dense_cost: bool = True,
    aliases: tuple[str, ...] = (),
    certifies_in_kernel: bool = False,
) -> None:
    """Add a solver to the registry (one line per solver module).

    ``aliases`` are other names :func:`get_solver` accepts for it (e.g. ``"qp:proxqp"``
    for ``"qp:proxsuite"``); they are not listed separately. ``available`` may be a
    function, called the first time the entry's availability is read (a backend that
    is slow to import is then imported only by a command that asks about it).
    """
    _REGISTRY[name] = SolverInfo(name, description, available, extra, hard_bounds, factory,
                                 takes_rows, dense_cost, certifies_in_kernel)
    for alias in aliases:
        _ALIASES[alias] = name


def list_solvers() -> list[SolverInfo]:
    """Every registered solver, available or not, in registration order."""
    return list(_REGISTRY.values())


def available_solvers() -> list[str]:
    """Names of the solvers that can run here."""
    return [info.name for info in _REGISTRY.values() if info.available]


def solver_info(name: str) -> SolverInfo:
    """Registry entry of ``name``.

    Raises
    ------
    SolverNotFoundError
        Unknown name, or a solver whose backend is not installed (the message names
        the pip extra).
    """
    info = _REGISTRY.get(name) or _REGISTRY.get(_ALIASES.get(name, ""))
    if info is None:
        raise SolverNotFoundError(name, available=available_solvers())
    if not info.available:
        raise SolverNotFoundError(
            name, available=available_solvers(), extra=info.extra, known=True
        )
    return info


def canonical_name(name: str) -> str:
    """Registry name of ``name`` (an alias such as ``qp:proxqp`` gives ``qp:proxsuite``)."""
    return _ALIASES.get(name, name)


def option_names(name: str) -> list[str] | None:
    """Keyword options of a solver whose factory lists them, or None if it takes any."""
    info = solver_info(name)
    try:
        params = inspect.signature(info.factory).parameters.values()
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params if not p.name.startswith("_")
            and p.kind in (inspect.Parameter.KEYWORD_ONLY,
                           inspect.Parameter.POSITIONAL_OR_KEYWORD)]


class CertifiedSolver:
    """A solver whose every answer is certified once (:func:`~.certify.certify`).

    What :func:`get_solver` hands out. ``solve`` returns the certified answer; a
    problem with rows handed to a solver that takes boxes only (or a full cost to one
    that takes a diagonal cost only) is refused (ERROR, with the reason: the pairing
    check of :meth:`SolverInfo.refusal`). Every other attribute is the wrapped
    solver's.

    Parameters
    ----------
    solver : StepSolver
        The solver built by the registry's factory (or a user's own).
    info : SolverInfo
        Its registry entry (what it takes, whether it keeps the bounds).
    tol : Tolerance, optional
        The certificate's tolerances; default the solver's own ``tol`` (or
        :data:`~.base.DEFAULT_TOLERANCE`).
    """

    def __init__(self, solver: StepSolver, info: SolverInfo,
                 tol: Tolerance | None = None) -> None:
        self.inner = solver
        self.info = info
        self.name = solver.name
        self.tol = tol if tol is not None else getattr(solver, "tol", DEFAULT_TOLERANCE)
        # The registry's own solver class only (not a user's solver of the same name):
        # its solve and the kernel's certificate in one call.
        self._in_kernel: Callable[..., StepSolution] | None = (
            solver.solve_certified  # type: ignore[attr-defined]
            if info.certifies_in_kernel and type(solver) is info.factory else None)
        # A solver that takes rows and a full cost refuses no problem.
        self._may_refuse = not (info.takes_rows and info.dense_cost)

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve ``problem`` and certify the answer against it."""
        if self._may_refuse:
            why = self.info.refusal(tuple(dict.fromkeys(problem.row_names))[:3],
                                    not problem.diagonal_cost)
            if why is not None:
                return failed(problem, Status.ERROR, self.name, why)
        if self._in_kernel is not None:
            return self._in_kernel(problem, self.tol, self.info.hard_bounds)
        return certify(problem, self.inner.solve(problem), self.tol,
                       claims_bounds=self.info.hard_bounds)

    def __getattr__(self, key: str) -> Any:
        # The wrapped solver's attributes. Never this object's own: while it is unpickled
        # or copied, "inner" is not set yet, and looking it up here would recurse.
        if key == "inner" or key.startswith("__"):
            raise AttributeError(key)
        return getattr(self.inner, key)

    def __repr__(self) -> str:
        return f"CertifiedSolver({self.inner!r})"


def certified(solver: StepSolver, tol: Tolerance | None = None) -> CertifiedSolver:
    """``solver`` as a :class:`CertifiedSolver` (certifying with ``tol`` when given).

    A registered solver keeps its registry entry; a user's own solver (not in the
    registry) is taken to keep hard limits and to take rows and a full cost. The
    wrapped solver object itself is shared, not copied (its warm starts are kept).
    """
    if isinstance(solver, CertifiedSolver):
        if tol is None or tol is solver.tol or tol == solver.tol:
            return solver
        return CertifiedSolver(solver.inner, solver.info, tol)
    info = _REGISTRY.get(solver.name) or _REGISTRY.get(_ALIASES.get(solver.name, ""))
    if info is None:
        info = SolverInfo(solver.name, "a user's solver", True, None, True,
                          lambda **_: solver)
    return CertifiedSolver(solver, info, tol)


def get_solver(name: str, **options: Any) -> CertifiedSolver:
    """Build the solver registered as ``name`` with keyword ``options``.

    The solver is wrapped in :class:`CertifiedSolver`: every answer it gives is
    certified once against the problem it was asked.

    Raises
    ------
    SolverNotFoundError
        See :func:`solver_info`.
    SolverOptionError
        An option the solver does not know (the message lists the valid names), or a
        value of the wrong type or out of range.
    InvalidInputError
        Another refusal of the options by the solver.
    """
    info = solver_info(name)
    valid = option_names(name)
    if valid is not None:
        for key in options:
            if key not in valid:
                raise SolverOptionError(info.name, key, "unknown option",
                                        valid=valid or ["(none)"])
    try:
        return CertifiedSolver(info.factory(**options), info)
    except TypeError as err:
        raise InvalidInputError(f"bad options for solver '{name}': {err}") from err
