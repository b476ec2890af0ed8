"""Stacking the limits' boxes and rows of a step: checked per limit, named per bound.

The step builder (:class:`~dualarm_qp.step.build.StepBuilder`) gets the boxes of the
limits with a compiled form from the kernel, and runs the other limits' ``constraint``
in Python. :class:`LimitStack` checks what each Python limit gives where it is taken
(naming the limit), merges the boxes with the kernel's in the limits' order,
intersects them (one kernel call: the largest lower and the smallest upper bound, a tie
kept by the earlier limit, a box empty by rounding only pinned) and names the limit
that set each bound. Its answers are what :meth:`StepProblem.assembled
<dualarm_qp.step.problem.StepProblem.assembled>` takes without a second check.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..errors import InvalidInputError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]

#: A box that the limits together leave empty by at most this (relative to
#: ``max(1, |lower|)``) is rounding, not an infeasible step (on an acceleration limit's
#: braking profile the box shrinks to one rate, and the distance left is a sum over many
#: samples): it is pinned at its lower end.
PIN_RTOL = 1e-9

#: Patterns of bound sources a stack keeps named (:meth:`LimitStack.box`).
_SOURCE_PATTERNS = 64


def pin_rounding(lower: FloatArray, upper: FloatArray) -> FloatArray:
    """Raise ``upper`` to ``lower`` where a box is empty by rounding only.

    See :data:`PIN_RTOL`; a box empty by more stays empty (an infeasible step). The
    kernel's box intersection, on one box.
    """
    box = kernel.intersect_boxes(lower[None], [0], upper[None], [0], lower.shape[0],
                                 PIN_RTOL)
    if box.nan_limit >= 0:
        raise NonFiniteError("the bounds")
    return box.upper


def checked_rates(x: object, name: str, n: int, *, finite: bool = True) -> FloatArray:
    """Return rates of every variable as a C-ordered float array, or raise.

    For a warm start and the last applied command: ``n`` numbers.

    Raises
    ------
    ShapeError
        Not ``n`` numbers.
    InvalidInputError
        Not real numbers (complex numbers included: their imaginary part is never
        dropped silently).
    NonFiniteError
        With ``finite``: a NaN or an infinity.
    """
    if (isinstance(x, np.ndarray) and x.shape == (n,) and x.dtype == np.float64
            and x.flags.c_contiguous):
        out = x
    else:
        try:
            given = np.asarray(x)
            if not np.iscomplexobj(given):
                out = np.ascontiguousarray(given, dtype=np.float64)
        except (TypeError, ValueError, OverflowError) as err:
            raise InvalidInputError(f"{name} is not numbers: {err}") from err
        if np.iscomplexobj(given):
            raise InvalidInputError(f"{name} is not real numbers (complex)")
        if out.shape != (n,):
            raise ShapeError(name, (n,), out.shape)
    if finite and kernel.first_defect([out], []) >= 0:
        raise NonFiniteError(name)
    return out


#: ``kernel.intersect_boxes``'s answer: lower, upper, lower_by, upper_by (the index of
#: the limit that set each bound, -1: none) and nan_limit, the first limit whose bounds
#: hold NaN.
CompiledBox = kernel.Box


class LimitStack:
    """The limits of one builder, by index: their boxes and rows stacked and checked.

    Parameters
    ----------
    labels : tuple of str
        Every limit's name, in the step's order (the index of a limit is its position).
    n : int
        Length of the decision vector.
    compiled_ids : list of int
        The limits whose boxes the kernel computes (one row each of its ``lowers`` and
        ``uppers``, in this order).
    """

    def __init__(self, labels: tuple[str, ...], n: int, compiled_ids: list[int]) -> None:
        self.labels = labels
        self.n = n
        self.compiled_ids = compiled_ids
        self._no_rows = np.zeros((0, n))
        self._no_rhs = np.zeros(0)
        self._no_bounds = np.zeros((0, n))
        self._sources: dict[bytes, tuple[tuple[str, ...], tuple[str, ...]]] = {}

    def box(self, compiled_lowers: FloatArray, compiled_uppers: FloatArray,
            compiled_box: CompiledBox, lowers: list[FloatArray], lower_ids: list[int],
            uppers: list[FloatArray], upper_ids: list[int]
            ) -> tuple[FloatArray, FloatArray, tuple[str, ...], tuple[str, ...]]:
        """Return the step's box and the limit that set each bound.

        Parameters
        ----------
        compiled_lowers, compiled_uppers : ndarray, shape (len(compiled_ids), n)
            The kernel's boxes of the compiled limits.
        compiled_box : kernel.Box
            Those boxes intersected by the kernel (``kernel.intersect_boxes``'s answer):
            the step's box when no other limit gives bounds.
        lowers, uppers : list of array_like
            The other limits' bounds (checked here), of the limits ``lower_ids`` and
            ``upper_ids``.

        Returns
        -------
        lower, upper : ndarray, shape (n,)
        lower_by, upper_by : tuple of str
            The name of the limit that set each bound ("" where none did).

        Raises
        ------
        ShapeError, InvalidInputError
            A limit's bounds are not one number per variable.
        NonFiniteError
            A limit's bounds hold NaN (named).
        """
        box = compiled_box
        if lowers or uppers:
            L, L_ids = self._with_compiled(compiled_lowers, lowers, lower_ids, "lower")
            U, U_ids = self._with_compiled(compiled_uppers, uppers, upper_ids, "upper")
            box = kernel.intersect_boxes(L, L_ids, U, U_ids, self.n, PIN_RTOL)
        if box.nan_limit >= 0:
            raise NonFiniteError(f"the bounds of the limit '{self.labels[box.nan_limit]}'")
        lower_by, upper_by = self._sources_of(box.lower_by, box.upper_by)
        return box.lower, box.upper, lower_by, upper_by

    def checked_rows(self, k: int, G: object, h: object, names: tuple[str, ...]
                     ) -> tuple[FloatArray, FloatArray]:
        """Return limit ``k``'s rows as ``G`` (p, n) and ``h`` (p,) float arrays.

        Raises
        ------
        ShapeError
            The rows are not ``(p, n)`` with ``p`` right-hand sides, or the limit names
            them with another number of names.
        InvalidInputError
            The rows are not numbers.
        """
        name = f"the rows of the limit '{self.labels[k]}'"
        try:
            G_k = np.atleast_2d(np.asarray(G, dtype=np.float64))
            h_k = np.atleast_1d(np.asarray(h, dtype=np.float64))
        except (TypeError, ValueError, OverflowError) as err:
            raise InvalidInputError(f"{name} are not numbers: {err}") from err
        if h_k.ndim != 1 or G_k.shape != (h_k.shape[0], self.n):
            raise ShapeError(name, (h_k.shape[0] if h_k.ndim == 1 else -1, self.n),
                             G_k.shape)
        if names and len(names) != h_k.shape[0]:
            raise ShapeError(f"the row names of the limit '{self.labels[k]}'",
                             (h_k.shape[0],), (len(names),))
        return G_k, h_k

    def rows(self, G_parts: list[FloatArray], h_parts: list[FloatArray], ids: list[int],
             all_checked: bool = False) -> tuple[FloatArray, FloatArray]:
        """Return the limits' checked rows stacked, ``G`` (p, n) and ``h`` (p,).

        ``all_checked``: every part is known finite (the kernel's rows of compiled row
        limits); one such part is returned as it is.

        Raises
        ------
        NonFiniteError
            A limit's rows hold NaN or infinity, or its right-hand sides NaN.
        """
        if not G_parts:
            return self._no_rows, self._no_rhs
        if all_checked:
            if len(G_parts) == 1:
                return G_parts[0], h_parts[0]
            return np.vstack(G_parts), np.concatenate(h_parts)
        G = np.vstack(G_parts)
        h = np.concatenate(h_parts)
        if kernel.first_defect([G], [h]) >= 0:
            for G_k, h_k, k in zip(G_parts, h_parts, ids, strict=True):
                if kernel.first_defect([np.ascontiguousarray(G_k)],
                                       [np.ascontiguousarray(h_k)]) >= 0:
                    raise NonFiniteError(f"the rows of the limit '{self.labels[k]}'")
        return G, h

    def _with_compiled(self, compiled: FloatArray, bounds: list[FloatArray], ids: list[int],
                       side: str) -> tuple[FloatArray, list[int]]:
        """Return the compiled limits' ``side`` bounds and the others', in the limits' order."""
        if not bounds:
            return compiled, self.compiled_ids
        rows = np.vstack([compiled, self._stacked(bounds, ids, side)])
        every = self.compiled_ids + ids
        order = sorted(range(len(every)), key=every.__getitem__)
        return rows[order], [every[i] for i in order]

    def _stacked(self, bounds: list[FloatArray], ids: list[int], side: str) -> FloatArray:
        """Return the limits' ``side`` bounds as rows of one array (k, n).

        Raises
        ------
        ShapeError
            A limit's bounds are not one number per variable.
        """
        n = self.n
        if not bounds:
            return self._no_bounds
        try:
            out = np.array(bounds, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            out = np.zeros(0)
        if out.shape != (len(bounds), n):
            for bound, k in zip(bounds, ids, strict=True):
                name = f"the {side} bounds of the limit '{self.labels[k]}'"
                if np.shape(bound) != (n,):
                    raise ShapeError(name, (n,), np.shape(bound))
                try:
                    np.asarray(bound, dtype=np.float64)
                except (TypeError, ValueError, OverflowError) as err:
                    raise InvalidInputError(f"{name} are not numbers: {err}") from err
            raise InvalidInputError(f"the limits' {side} bounds do not stack into "
                                    f"({len(bounds)}, {n}) numbers")
        return out

    def _sources_of(self, lo_by: NDArray[np.int64], up_by: NDArray[np.int64]
                    ) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Return ``lower_by`` and ``upper_by``: the limit that set each bound (by index).

        The sources rarely change from one step to the next: the names are kept per
        pattern of indices (a handful of patterns in a run).
        """
        key = lo_by.tobytes() + up_by.tobytes()
        known = self._sources.get(key)
        if known is None:
            labels = self.labels
            known = (tuple(labels[i] if i >= 0 else "" for i in lo_by.tolist()),
                     tuple(labels[i] if i >= 0 else "" for i in up_by.tolist()))
            if len(self._sources) >= _SOURCE_PATTERNS:
                self._sources.clear()
            self._sources[key] = known
        return known


__all__ = ["PIN_RTOL", "LimitStack", "checked_rates", "pin_rounding"]
