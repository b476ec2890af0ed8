"""Exception hierarchy of dualarm_qp.

Every error the library raises on purpose derives from :class:`DualArmError`, so a
caller can catch them all with one ``except`` clause. Errors caused by bad input also
derive from :class:`ValueError` (or :class:`FileNotFoundError`) so that generic code
that already handles those keeps working.
"""

from __future__ import annotations

from collections.abc import Sequence


class DualArmError(Exception):
    """Root of every exception raised by dualarm_qp."""


class InvalidInputError(DualArmError, ValueError):
    """An argument has the wrong shape, a non-finite value or an inconsistent value."""


class ShapeError(InvalidInputError):
    """An array argument has the wrong shape.

    Attributes
    ----------
    name : str
        Name of the offending argument.
    expected : tuple
        Expected shape.
    got : tuple
        Shape that was passed.
    """

    def __init__(self, name: str, expected: tuple[int, ...], got: tuple[int, ...]) -> None:
        self.name = name
        self.expected = expected
        self.got = got
        super().__init__(f"{name} must have shape {expected}, got {got}")


class NonFiniteError(InvalidInputError):
    """An array argument contains NaN or infinity."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__(f"{name} contains NaN or infinite values")


class LimitsError(InvalidInputError):
    """Lower and upper limits are inconsistent (lower > upper) or malformed."""


class SupportLostError(InvalidInputError):
    """A supporting follower (the paper's Case 2) would have to pull to hold the object.

    Raised by a step (the run then fails on criterion ``support``) and, for the start, at
    configuration time.
    """


class ObstacleOverlapError(InvalidInputError):
    """An obstacle overlaps an arm or the object at the start.

    Attributes
    ----------
    obstacle : str
        The obstacle's name.
    """

    def __init__(self, message: str, obstacle: str) -> None:
        super().__init__(message)
        self.obstacle = obstacle


class ConfigError(DualArmError, ValueError):
    """A configuration file is malformed, has unknown keys or wrong types.

    Attributes
    ----------
    path : str or None
        File the error was found in.
    key : str or None
        Dotted path of the offending key.
    valid : tuple of str
        Valid choices for the key, when known.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        key: str | None = None,
        valid: Sequence[str] = (),
    ) -> None:
        self.path = path
        self.key = key
        self.valid = tuple(valid)
        parts = []
        if path is not None:
            parts.append(f"{path}:")
        if key is not None:
            parts.append(f"key '{key}':")
        parts.append(message)
        if self.valid:
            parts.append(f"(valid: {', '.join(self.valid)})")
        super().__init__(" ".join(parts))


class KinematicsError(DualArmError):
    """A kinematic computation failed (unreachable pose, singular configuration)."""


class IKError(KinematicsError):
    """Inverse kinematics found no solution within the joint limits.

    Attributes
    ----------
    position_error : float
        Best position error reached [m].
    rotation_error : float
        Best rotation error reached [rad].
    """

    def __init__(self, message: str, *, position_error: float = float("nan"),
                 rotation_error: float = float("nan")) -> None:
        self.position_error = position_error
        self.rotation_error = rotation_error
        super().__init__(message)


class KernelError(DualArmError, ImportError):
    """The compiled kernel (``dualarm_qp._kernel``) is missing or built from other sources."""


class SolverError(DualArmError):
    """A step solver failed in a way that is not an ordinary infeasible step."""


class SolverNotFoundError(SolverError, KeyError):
    """The requested solver is unknown or its backend is not installed.

    Attributes
    ----------
    name : str
        Name that was asked for.
    available : tuple of str
        Solvers usable on this machine.
    extra : str or None
        The pip extra that installs the missing backend, if known.
    """

    def __init__(self, name: str, *, available: Sequence[str], extra: str | None = None,
                 known: bool = False) -> None:
        self.name = name
        self.available = tuple(available)
        self.extra = extra
        if known and extra is not None:
            msg = (f"solver '{name}' is not installed here; install it with "
                   f"pip install 'dualarm-qp[{extra}]'")
        else:
            msg = f"unknown solver '{name}'"
        msg += f" (available: {', '.join(self.available)})"
        super().__init__(msg)

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


class PairingError(SolverError, InvalidInputError):
    """A step's parts need what the solver cannot take (rows, a full cost).

    Attributes
    ----------
    solver : str
        The solver's registry name.
    limits : tuple of str
        The limits it cannot take.
    able : tuple of str
        The available solvers that can.
    """

    def __init__(self, message: str, *, solver: str, limits: Sequence[str] = (),
                 able: Sequence[str] = ()) -> None:
        self.solver = solver
        self.limits = tuple(limits)
        self.able = tuple(able)
        super().__init__(message)


class InfeasibleStepError(SolverError):
    """A step has no solution that meets the equality and the bounds.

    Attributes
    ----------
    conflicts : tuple of str
        Human-readable names of the bounds that conflict, each once.
    reason : str
        The message without the list of conflicts (to build on it without repeating
        the list).
    """

    def __init__(self, message: str, *, conflicts: Sequence[str] = ()) -> None:
        self.conflicts = tuple(dict.fromkeys(conflicts))
        self.reason = message
        if self.conflicts:
            message = f"{message} (conflicting bounds: {', '.join(self.conflicts)})"
        super().__init__(message)
