"""The step problem: the value one controller step hands to a solver.

A step problem is built once per control step by the builder
(:mod:`dualarm_qp.step.build`), which stacks the step's parts (tasks, a cost, limits),
and is handed unchanged to any solver in the registry. It knows nothing of robots:
only the linear algebra of one step.

Find ``x`` (both arms' joint rates [rad/s] followed by the grasp sliding speeds [m/s],
see :class:`~dualarm_qp.step.layout.Layout`) that

    minimises   (x - center)^T W (x - center)                        (Eq. 37)
    subject to  A x = s b                                             (Eqs. 14, 25)
                lower <= x <= upper                                   (boxes: Eqs. 33-36)
                G x <= h                                              (rows)

``W`` is ``diag(weights)``, or ``weights`` itself when it is a full symmetric positive
definite matrix. ``s`` is the task scale of the infeasible-step policy: it multiplies
the whole right-hand side, feedback included (at ``s = 0`` the step holds still and
corrects nothing); ``s = 1`` is the full task, ``A x = b``.

The problem converts to and from :class:`qpsolvers.Problem` (:meth:`StepProblem.to_qpsolvers`,
:meth:`StepProblem.from_qpsolvers`), the exchange value of the QP backends.
"""

from __future__ import annotations

import dataclasses
import math
import operator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..errors import InvalidInputError, NonFiniteError, ShapeError

if TYPE_CHECKING:
    import qpsolvers

FloatArray = NDArray[np.float64]


class Names(NamedTuple):
    """The names a problem's messages use: variables, rows, and the limit of each bound."""

    variables: tuple[str, ...]
    rows: tuple[str, ...]
    lower_by: tuple[str, ...]
    upper_by: tuple[str, ...]

    def bound(self, index: int, upper: bool) -> str:
        """Name of one bound with the limit that set it, e.g. ``"qf3 upper (joint speed)"``."""
        side = "upper" if upper else "lower"
        source = (self.upper_by if upper else self.lower_by)[index]
        return f"{self.variables[index]} {side}" + (f" ({source})" if source else "")


@dataclass(frozen=True)
class Inequalities:
    """Every finite inequality of a problem as rows ``C x <= e`` (unit-norm rows).

    Attributes
    ----------
    C : ndarray, shape (k, n)
        Upper boxes (``+e_i``), lower boxes (``-e_i``), then the general rows, each
        divided by its Euclidean norm (rows of zeros are kept as they are).
    e : ndarray, shape (k,)
        Right-hand sides in the same units (of ``x``).
    kind : ndarray of int, shape (k,)
        ``+1`` upper box, ``-1`` lower box, ``0`` general row.
    index : ndarray of int, shape (k,)
        The variable (boxes) or the row of ``G`` (general rows).
    names : Names
        The names of the problem's variables, rows and bound sources (for the names of
        the rows, made on demand). The names, not the problem: a problem keeps its
        inequalities, and a reference back would make every step's problem a cycle
        that only the garbage collector frees (a pause of milliseconds in a 1 kHz loop).
    """

    C: FloatArray
    e: FloatArray
    kind: NDArray[np.int8]
    index: NDArray[np.intp]
    names: Names = field(repr=False, compare=False)

    def label(self, i: int) -> str:
        """Name of row ``i``: ``"qf4 upper (joint speed)"``, ``"wall"``."""
        k, j = int(self.kind[i]), int(self.index[i])
        if k == 0:
            return self.names.rows[j]
        return self.names.bound(j, k > 0)

    def labels(self, rows: Any = None) -> tuple[str, ...]:
        """Names of ``rows`` (indices; default every row), each once, in order."""
        picked = range(self.C.shape[0]) if rows is None else rows
        return tuple(dict.fromkeys(self.label(int(i)) for i in picked))


def cost_root(weights: FloatArray) -> FloatArray:
    """``R`` with ``R^T R = W`` for the weights of a problem (:meth:`StepProblem.cost_root`).

    ``diag(sqrt(w))`` for a diagonal cost (a vector ``w``), the upper Cholesky factor of a
    full ``W`` otherwise.

    Raises
    ------
    InvalidInputError
        A full weighting matrix that is not positive definite.
    """
    if weights.ndim == 1:
        return np.diag(np.sqrt(weights))
    try:
        return np.linalg.cholesky(weights).T
    except np.linalg.LinAlgError as err:
        raise InvalidInputError("the weighting matrix is not positive definite") from err


def _c_array(value: Any) -> FloatArray:
    """``value`` as a C-ordered float64 array (a copy only when it is not one already).

    The kernel maps matrices as numpy holds them; a view with a zero stride (a
    broadcast) or another layout is copied here, once, so that every kernel call reads
    plain arrays.
    """
    arr = np.asarray(value, dtype=np.float64)
    return arr if arr.flags.c_contiguous else np.ascontiguousarray(arr)


#: The arrays :meth:`StepProblem.__post_init__` checks for NaN (and infinity, the first
#: five), in ``kernel.problem_check``'s order.
_CHECKED = ("A", "b", "weights", "center", "G", "lower", "upper", "h")


@dataclass(frozen=True)
class StepProblem:
    """One step: an equality, boxes, general rows and a weighted least-distance cost.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Equality matrix (12 rows for a controller step: the object's path, the closure).
    b : ndarray, shape (m,)
        Right-hand side of the full task (``s = 1``) [m/s; rad/s].
    weights : ndarray, shape (n,) or (n, n)
        The weighting matrix ``W`` of Eq. 37: its diagonal, or the whole symmetric
        positive definite matrix.
    center : ndarray, shape (n,)
        Centre of the cost ``dqhat_c`` (Eqs. 38-40) [rad/s, m/s].
    lower, upper : ndarray, shape (n,)
        Boxes on ``x`` (may be infinite). ``lower[i] > upper[i]`` means an empty box:
        solvers report the step infeasible.
    G : ndarray, shape (p, n), optional
        General inequality rows ``G x <= h`` (default: none).
    h : ndarray, shape (p,), optional
        Their right-hand side.
    n_grasp : int
        Number of trailing variables that are grasp sliding speeds (default 1).
    x_prev : ndarray, shape (n,), optional
        A warm start (the previous step's answer), never a constraint.
    names : tuple of str, optional
        Variable names (default ``x1..xn``).
    row_names : tuple of str, optional
        Names of the rows of ``G`` (default ``row1..rowp``).
    eq_names : tuple of str, optional
        Names of the equality rows (default ``eq1..eqm``).
    lower_by, upper_by : tuple of str, optional
        The limit that set each variable's lower and upper bound (for messages).
    build_time : float
        Seconds the builder spent assembling this problem.
    """

    A: FloatArray
    b: FloatArray
    weights: FloatArray
    center: FloatArray
    lower: FloatArray
    upper: FloatArray
    # Typed as arrays: None (the default) becomes an empty array in __post_init__.
    G: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    h: FloatArray = field(default_factory=lambda: np.zeros(0))
    n_grasp: int = 1
    x_prev: FloatArray | None = None
    names: tuple[str, ...] = ()
    row_names: tuple[str, ...] = ()
    eq_names: tuple[str, ...] = ()
    lower_by: tuple[str, ...] = ()
    upper_by: tuple[str, ...] = ()
    build_time: float = 0.0

    def __post_init__(self) -> None:
        try:  # float64 C-ordered arrays (the builder's): checked in one kernel pass
            code = kernel.problem_check(self.A, self.b, self.weights, self.center, self.lower,
                                        self.upper, self.G, self.h)
        except TypeError:  # anything else: converted once, then checked
            code = kernel.problem_check(*self._converted())
        if code:
            raise self._defect(code)
        m, n = self.A.shape
        p = self.G.shape[0]
        if p == 0 and self.G.shape != (0, n):  # no rows (the default)
            object.__setattr__(self, "G", np.zeros((0, n)))
            object.__setattr__(self, "h", np.zeros(0))
        if self.x_prev is not None:
            xp = _c_array(self.x_prev)
            if xp.shape != (n,):
                raise ShapeError("x_prev", (n,), xp.shape)
            object.__setattr__(self, "x_prev", xp)
        if not 0 <= self.n_grasp <= n:
            raise InvalidInputError(f"n_grasp must be in [0, {n}], got {self.n_grasp}")
        # The names' lengths first, in one expression; each field is named or refused only
        # when one is off (five calls less a step: 1 to 2 us of the PUMA step's 75 us).
        if (len(self.names) != n or len(self.row_names) != p or len(self.eq_names) != m
                or len(self.lower_by) != n or len(self.upper_by) != n):
            self._name("names", n, "x")
            self._name("row_names", p, "row")
            self._name("eq_names", m, "eq")
            self._name("lower_by", n, "")
            self._name("upper_by", n, "")

    def _name(self, field_name: str, count: int, prefix: str) -> None:
        """Check a tuple of ``count`` names, or give the default (``prefix1..``, or "")."""
        given = getattr(self, field_name)
        if not given:
            object.__setattr__(self, field_name, tuple(
                f"{prefix}{i + 1}" if prefix else "" for i in range(count)))
        elif len(given) != count:
            raise ShapeError(field_name, (count,), (len(given),))

    def _converted(self) -> tuple[FloatArray, ...]:
        """Set every array as a C-ordered float64 one (no rows: ``G`` of shape (0, n))."""
        for name in ("A", "b", "weights", "center", "lower", "upper", "G", "h"):
            object.__setattr__(self, name, _c_array(getattr(self, name)))
        return (self.A, self.b, self.weights, self.center, self.lower, self.upper, self.G,
                self.h)

    def _defect(self, code: int) -> InvalidInputError:
        """Return the error of ``kernel.problem_check``'s ``code`` (src/kernel/bind_step.cpp)."""
        if code == 1:
            return ShapeError("A", (-1, -1), np.shape(self.A))
        m, n = self.A.shape
        shapes = {2: ("b", (m,)), 3: ("center", (n,)), 4: ("lower", (n,)),
                  5: ("upper", (n,)), 6: ("weights", (n,)), 7: ("G", (-1, n)),
                  8: ("h", (np.shape(self.G)[0],))}
        if code in shapes:
            name, shape = shapes[code]
            return ShapeError(name, shape, np.shape(getattr(self, name)))
        if 10 <= code < 18:
            return NonFiniteError(_CHECKED[code - 10])
        if code == 20:
            return InvalidInputError("weights must be strictly positive")
        return InvalidInputError("a full weighting matrix must be symmetric")

    # -- sizes ---------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of variables."""
        return int(self.A.shape[1])

    @property
    def m(self) -> int:
        """Number of equality rows."""
        return int(self.A.shape[0])

    @property
    def p(self) -> int:
        """Number of general inequality rows."""
        return int(self.G.shape[0])

    @property
    def diagonal_cost(self) -> bool:
        """Whether ``W`` is diagonal (given by its diagonal)."""
        return self.weights.ndim == 1

    # -- the right-hand side and the cost -------------------------------------------------
    def scaled(self, scale: float, *, x_prev: FloatArray | None = None) -> StepProblem:
        """Return the problem whose full task is this one's at task scale ``scale``.

        Its right-hand side is ``scale b``; ``x_prev`` replaces the warm start when given.
        """
        if not math.isfinite(scale):
            raise NonFiniteError("scale")
        if abs(scale) <= 1.0:  # the policies' scales: no overflow possible
            b = scale * self.b
        else:
            with np.errstate(over="ignore"):
                b = scale * self.b
            if kernel.first_defect([b], []) >= 0:
                raise NonFiniteError("b (scaled)")
        return dataclasses.replace(self, b=b, x_prev=self.x_prev if x_prev is None else x_prev)

    def weight_matrix(self) -> FloatArray:
        """``W`` as an ``n x n`` matrix."""
        return np.diag(self.weights) if self.weights.ndim == 1 else self.weights

    def cost_root(self) -> FloatArray:
        """``R`` with ``R^T R = W`` (so that Eq. 37 is ``|R (x - c)|^2``), ``n x n``.

        ``diag(sqrt(w))`` for a diagonal cost, the upper Cholesky factor otherwise.

        Raises
        ------
        InvalidInputError
            A full weighting matrix that is not positive definite.
        """
        return cost_root(self.weights)

    def gradient(self, x: FloatArray) -> FloatArray:
        """``W (x - c)``, half the gradient of Eq. 37 at ``x``."""
        d = np.asarray(x, dtype=np.float64) - self.center
        return self.weights * d if self.weights.ndim == 1 else self.weights @ d

    def objective(self, x: FloatArray) -> float:
        """Value of Eq. 37, ``(x - c)^T W (x - c)``, at ``x``."""
        if self.weights.ndim == 2:
            d = np.asarray(x, dtype=np.float64) - self.center
            return float(d @ self.weights @ d)
        # Python floats: for a handful of variables cheaper than three numpy calls.
        diff = list(map(operator.sub, np.asarray(x, dtype=np.float64).tolist(),
                        self.center.tolist()))
        return float(sum(map(operator.mul, self.weights.tolist(),
                             map(operator.mul, diff, diff))))

    # -- the inequalities ----------------------------------------------------------------
    def empty_bounds(self) -> tuple[str, ...]:
        """Names of the variables whose box is empty (``lower > upper``)."""
        return tuple(self.names[i] for i in np.flatnonzero(self.lower > self.upper))

    def has_empty_box(self) -> bool:
        """Whether some variable's box is empty (``lower > upper``)."""
        return bool((self.lower > self.upper).any())

    def bound_label(self, index: int, upper: bool) -> str:
        """Name of one bound with the limit that set it, e.g. ``"qf3 upper (joint speed)"``."""
        return Names(self.names, self.row_names, self.lower_by, self.upper_by).bound(index,
                                                                                    upper)

    def inequalities(self) -> Inequalities:
        """Every finite inequality as unit-norm rows ``C x <= e`` (one kernel call).

        Built by the compiled kernel (``src/kernel/rows.cpp``), which the exact solver
        uses.
        """
        r = kernel.inequalities(self.lower, self.upper, self.G, self.h)
        return Inequalities(r.C, r.e, r.kind, r.index,
                            Names(self.names, self.row_names, self.lower_by, self.upper_by))

    def row_violation(self, x: FloatArray) -> float:
        """Largest violation of a general row, ``max((G x - h) / |G_i|, 0)`` [units of x]."""
        if not self.p:
            return 0.0
        G, h = self.G, self.h
        norms = np.linalg.norm(G, axis=1)
        gap = (G @ x - h) / np.where(norms > 0.0, norms, 1.0)
        return float(max(0.0, float(np.nanmax(gap))))

    # -- qpsolvers -----------------------------------------------------------------------
    def to_qpsolvers(self, scale: float = 1.0) -> qpsolvers.Problem:
        """Return the step at task scale ``scale`` as ``qpsolvers.Problem`` (in ``x``).

        ``minimise 1/2 x^T P x + q^T x`` with ``P = 2 W`` and ``q = -2 W c`` (Eq. 37 up
        to its constant), ``G x <= h``, ``A x = scale b``, ``lb <= x <= ub``.
        """
        import qpsolvers

        P = 2.0 * self.weight_matrix()
        q = -P @ self.center
        G, h = self.G, self.h
        return qpsolvers.Problem(P, q, G=G if self.p else None, h=h if self.p else None,
                                 A=self.A if self.m else None,
                                 b=scale * self.b if self.m else None,
                                 lb=self.lower, ub=self.upper)

    @classmethod
    def from_qpsolvers(cls, qp: qpsolvers.Problem, **fields: Any) -> StepProblem:
        """Build a step problem from ``qpsolvers.Problem`` (dense data; ``P`` positive definite).

        ``fields`` are further :class:`StepProblem` fields (``names``, ``n_grasp``, ...).

        Raises
        ------
        InvalidInputError
            ``P`` is not positive definite.
        """
        P = np.asarray(qp.P.toarray() if hasattr(qp.P, "toarray") else qp.P, dtype=float)
        n = P.shape[0]
        W = 0.25 * (P + P.T)  # P = 2 W
        try:
            np.linalg.cholesky(W)
        except np.linalg.LinAlgError as err:
            raise InvalidInputError("qpsolvers problem: P is not positive definite") from err
        center = np.linalg.solve(W, -0.5 * np.asarray(qp.q, dtype=float))
        diagonal = np.count_nonzero(W - np.diag(np.diag(W))) == 0
        def dense(M: Any) -> FloatArray | None:
            return None if M is None else np.asarray(
                M.toarray() if hasattr(M, "toarray") else M, dtype=float)

        A = dense(qp.A)
        G = dense(qp.G)
        inf = np.full(n, np.inf)
        return cls(A=np.zeros((0, n)) if A is None else A,
                   b=np.zeros(0) if qp.b is None else np.asarray(qp.b, dtype=float),
                   weights=np.diag(W).copy() if diagonal else W, center=center,
                   lower=-inf if qp.lb is None else np.asarray(qp.lb, dtype=float),
                   upper=inf if qp.ub is None else np.asarray(qp.ub, dtype=float),
                   G=np.zeros((0, n)) if G is None else G,
                   h=np.zeros(0) if qp.h is None else np.asarray(qp.h, dtype=float),
                   **fields)


__all__ = ["Inequalities", "Names", "StepProblem", "cost_root"]
