"""Geometry of the step's equality ``A x = b`` (private).

The tools every solver, the certificate and the policies share, computed by the
compiled kernel (:mod:`dualarm_qp._compiled`; this module maps its arrays to typed results):

* :func:`factor`, the one truncated SVD that takes every rank decision;
* :func:`null_basis`, what the exact solver and the certificate need of ``A`` (its
  pseudo-inverse and null space), from a QR factorisation where that proves the SVD's
  decision (full row rank), from :func:`factor` otherwise;
* :func:`affine_solutions` writes every solution of ``A x = b`` as ``x0 + N t``;
* :func:`least_distance_eq`, the one equality-constrained least-distance kernel:
  the minimiser of Eq. 37 over an affine set, with its multipliers.

Every decision about a dimension in the solvers, the certificate and here (the rank
of ``A`` or of a column subset of it, hence the null-space dimension; whether a
variable moves along a null direction) is taken from a singular value decomposition
with the one relative tolerance :data:`RANK_RTOL` (:func:`null_basis` skips the SVD only
where Frobenius bounds of its QR factor prove the SVD would keep every singular value).
None rests on an LU pivot, on the
``info`` of a LAPACK solve, or on a machine-dependent default cut-off, so the decided
dimension is the same on every CPU and BLAS build unless a singular value lies within
rounding (about 1e-15 relative) of the cut-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..step.problem import StepProblem, cost_root

FloatArray = NDArray[np.float64]

#: Relative rank tolerance (dimensionless). A singular value ``sigma_i`` of ``A`` with
#: ``sigma_i <= RANK_RTOL * sigma_1`` is zero: its direction belongs to the null space.
#: Dropping it is a backward perturbation of ``A`` of at most ``RANK_RTOL * ||A||_2``,
#: the same relative size as :data:`CONSISTENCY_TOL` and far inside the 1e-7 of
#: ``base.Tolerance``; it is also 1e6 times the rounding of a double-precision SVD
#: (about ``n * eps * sigma_1``, 1.6e-15 for n = 7), so rounding noise, LU-pivot-sized
#: residues (1e-17) and perturbations up to 1e-10 never change the decision. A step is
#: called full rank only if no direction of ``x`` is amplified by more than 1e9 / ||A||
#: into ``x0``. The same number decides when a null direction "does not move" a
#: variable (a component ``|z_i| <= RANK_RTOL * max |z|`` of a unit null vector is zero).
RANK_RTOL: float = kernel.RANK_RTOL  # 1e-9, defined in src/kernel/constants.hpp

#: Relative residual above which ``A x = b`` is called inconsistent (rank-deficient ``A``
#: and ``b`` outside its numerical range): ``max |A x0 - b| > CONSISTENCY_TOL *
#: max(1, max |b|, sigma_1 max |x0|)`` for the minimum-norm ``x0`` (dimensionless; the
#: same size as :data:`RANK_RTOL`, whose truncation it must tolerate).
CONSISTENCY_TOL: float = kernel.CONSISTENCY_TOL  # 1e-9


@dataclass(frozen=True, slots=True)
class Factor:
    """Rank-revealing (singular value) decomposition of an ``m x n`` matrix ``A``.

    Only the numerical range and null space are kept: ``A ~= U diag(sigma) V^T`` with
    the singular values at or below :data:`RANK_RTOL` times the largest dropped.

    Attributes
    ----------
    U : ndarray, shape (m, r)
        Orthonormal basis of the numerical range of ``A`` (r = numerical rank).
    sigma : ndarray, shape (r,)
        The kept singular values, decreasing (units of ``A``).
    V : ndarray, shape (n, r)
        Orthonormal basis of the numerical row space of ``A``.
    N : ndarray, shape (n, n - r)
        Orthonormal basis of the numerical null space of ``A``.
    """

    U: FloatArray
    sigma: FloatArray
    V: FloatArray
    N: FloatArray

    @property
    def rank(self) -> int:
        """Numerical rank ``r`` of ``A`` (at tolerance :data:`RANK_RTOL`)."""
        return int(self.sigma.size)

    @property
    def nullity(self) -> int:
        """Numerical null-space dimension ``n - r``."""
        return int(self.N.shape[1])

    def solve(self, b: FloatArray) -> FloatArray:
        """Minimum-norm least-squares solution of ``A x = b`` (truncated pseudoinverse)."""
        return self.V @ ((self.U.T @ b) / self.sigma)

    def solve_transposed(self, g: FloatArray) -> FloatArray:
        """Minimum-norm least-squares solution of ``A^T y = g`` (truncated pseudoinverse)."""
        return self.U @ ((self.V.T @ g) / self.sigma)


def factor(A: FloatArray) -> Factor:
    """Singular value decomposition of ``A`` truncated at :data:`RANK_RTOL`.

    Computed by the kernel (Eigen's two-sided Jacobi SVD with a column-pivoting QR
    preconditioner: accurate to rounding in every singular value, no convergence
    failure to fall back from).

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Any real matrix (m or n may be 0).

    Returns
    -------
    Factor
        Range, kept singular values, row space and null space of ``A``.
    """
    f = kernel.factor(np.ascontiguousarray(A, dtype=np.float64))
    return Factor(f.U, f.sigma, f.V, f.N)


def least_distance(problem: StepProblem, N: FloatArray, x0: FloatArray) -> FloatArray:
    """Minimiser of Eq. 37, ``|R (x - c)|^2``, over ``x = x0 + N t``.

    ``N`` has orthonormal columns and ``R`` (``W = R^T R``) is invertible, so ``R N``
    has full column rank (for a diagonal cost its singular values lie in
    ``[min sqrt(w), max sqrt(w)]``): no rank decision, one Householder QR solve of
    ``min |R (x0 + N t - c)|`` (not the normal equations, whose condition is the square
    of that, up to 1e9 with a sliding weight of 1e9). The exact solver's unconstrained
    minimiser is the same computation, in the kernel.

    Parameters
    ----------
    problem : StepProblem
        Supplies the cost ``W`` and the centre ``c`` (units of ``x``).
    N : ndarray, shape (n, d)
        Orthonormal null-space basis (``d = 0`` returns ``x0``).
    x0 : ndarray, shape (n,)
        A point of the affine set (units of ``x``).
    """
    w_diag, w_full, root_full = cost_arrays(problem)
    return np.asarray(kernel.least_distance(N, x0, w_diag, w_full, root_full,
                                            problem.center))


def cost_arrays(problem: StepProblem) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return the cost as the kernel takes it: ``(w, empty, empty)`` or ``(empty, W, R)``.

    A diagonal cost is its weights (the kernel takes their square roots); a full one is
    ``W`` with its upper Cholesky factor ``R`` (:meth:`StepProblem.cost_root`, which
    raises on a matrix that is not positive definite).
    """
    w = problem.weights
    if w.ndim == 1:
        return w, _EMPTY_MATRIX, _EMPTY_MATRIX
    return _EMPTY_VECTOR, w, problem.cost_root()


def weight_arrays(weights: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`cost_arrays` of any problem with these ``weights`` (a builder's, before a step).

    Raises
    ------
    InvalidInputError
        A full weighting matrix that is not positive definite.
    """
    if weights.ndim == 1:
        return weights, _EMPTY_MATRIX, _EMPTY_MATRIX
    return _EMPTY_VECTOR, weights, cost_root(weights)


_EMPTY_VECTOR = np.zeros(0)
_EMPTY_MATRIX = np.zeros((0, 0))


def least_distance_eq(problem: StepProblem, E: FloatArray, r: FloatArray
                      ) -> tuple[FloatArray, FloatArray]:
    """Minimise Eq. 37 of ``problem`` subject to ``E x = r`` only; with the multipliers.

    The one equality-constrained least-distance kernel of the package: the exact
    solver's subproblems, the KKT refinement of the QP backends, SNS's working sets and
    the certificate all reduce to it. ``E`` holds whatever is held as an equality (the
    step's ``A``, unit rows of variables held at a bound, active general rows); its
    rank is decided by :func:`factor` at :data:`RANK_RTOL`, so dependent rows are fine.

    Parameters
    ----------
    problem : StepProblem
        Supplies the cost ``W`` and the centre ``c``.
    E : ndarray, shape (k, n)
        Equality rows.
    r : ndarray, shape (k,)
        Their right-hand side (assumed consistent; least squares otherwise).

    Returns
    -------
    x : ndarray, shape (n,)
        The minimiser.
    multipliers : ndarray, shape (k,)
        The minimum-norm ``lam`` with ``W (x - c) = E^T lam``.
    """
    f = factor(E)
    x = least_distance(problem, f.N, f.solve(r))
    return x, f.solve_transposed(problem.gradient(x))


def null_basis(A: FloatArray) -> kernel.Basis:
    """Return what the exact solver and the certificate need of ``A`` (m x n): a basis.

    The rank is decided as :func:`factor` decides it, at :data:`RANK_RTOL` of the
    largest singular value. When ``A``'s QR factorisation ``A^T = Q R`` proves full row
    rank (Frobenius bounds: ``sigma_min >= 1 / |R^-1|_F > RANK_RTOL |R|_F >= RANK_RTOL
    sigma_max``), the basis comes from it: ``P = Q_1 R^-T`` and ``N = Q_2``, at a
    fifth of an SVD's cost; ``P`` is kept factored there (``Q``'s reflectors and
    ``R^-1``) and formed only when read. Any other ``A`` (near-singular,
    rank-deficient, more rows than columns) takes :func:`factor`'s SVD.

    The answer (a ``kernel.Basis``) has ``P`` (n, m), the (truncated) pseudo-inverse
    (``P b`` is the minimum-norm least-squares solution of ``A x = b``), formed when
    read; ``N`` (n, n - rank), an orthonormal basis of the numerical null space; ``rank``;
    ``nullity``; ``sigma_max``, the largest singular value (SVD path) or its Frobenius
    bound (QR path) [units of A]; ``qr``, whether the QR path proved full row rank. The
    kernel's functions take it as it is, so that the exact solver's two paths compute
    ``P b`` the same way, to the bit. It does not pickle: a basis is made again from
    ``A`` where it is needed.
    """
    return kernel.basis(np.ascontiguousarray(A, dtype=np.float64))


def problem_basis(problem: StepProblem) -> kernel.Basis:
    """:func:`null_basis` of ``problem.A``."""
    return null_basis(problem.A)


def problem_factor(problem: StepProblem) -> Factor:
    """:func:`factor` of ``problem.A``."""
    return factor(problem.A)


@dataclass(frozen=True, slots=True)
class AffineSet:
    """All solutions ``x = x0 + N t`` of ``A x = b``.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        The minimum-norm solution (same units as ``x``); orthogonal to ``N``, so
        ``|x0| <= |x|`` for every solution ``x`` (no cancellation in ``x0 + N t``).
    N : ndarray, shape (n, d)
        Orthonormal basis of the numerical null space of ``A`` (d = n - rank A, the
        rank decided with :data:`RANK_RTOL`); ``d = 0`` for a nonsingular square ``A``.
    factor : Factor
        The decomposition of ``A`` it came from (for multipliers, ``A^T y = g``).
    """

    x0: FloatArray
    N: FloatArray
    factor: Factor

    @property
    def nullity(self) -> int:
        """Null-space dimension ``d``."""
        return int(self.N.shape[1])


def affine_solutions(A: FloatArray, b: FloatArray) -> AffineSet | None:
    """Parametrise the solutions of ``A x = b`` as ``x0 + N t``.

    One truncated SVD (:func:`factor`): the rank is the number of singular values above
    ``RANK_RTOL * sigma_1``, ``x0`` is the minimum-norm solution and ``N`` the trailing
    right singular vectors. When ``A`` is rank-deficient, ``x0`` must solve ``A x = b``
    to :data:`CONSISTENCY_TOL` (backward error): ``max |A x0 - b| <= CONSISTENCY_TOL *
    max(1, max |b|, sigma_1 max |x0|)``, the rank decision may leave ``RANK_RTOL *
    sigma_1 |x|`` of ``b`` unmatched, which is scaled by the size of ``A x``. The exact
    solver takes the same decision in the kernel.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Equality matrix (units of ``b`` per unit of ``x``).
    b : ndarray, shape (m,)
        Right-hand side [m/s; rad/s].

    Returns
    -------
    AffineSet or None
        None when ``A x = b`` has no solution (``A`` rank-deficient, ``b`` outside its
        numerical range).
    """
    out = kernel.affine(np.ascontiguousarray(A, dtype=np.float64), b)
    if out is None:
        return None
    f = out.factor
    return AffineSet(out.x0, f.N, Factor(f.U, f.sigma, f.V, f.N))
