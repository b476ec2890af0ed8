"""Type stub of the compiled kernel (src/kernel/module.cpp)."""

import numpy as np
from numpy.typing import ArrayLike, NDArray

_F = NDArray[np.float64]

SOURCE_HASH: str
RANK_RTOL: float
CONSISTENCY_TOL: float
ACTIVE_TOL: float
STEP_RTOL: float
ROUNDING: float
TIE_RTOL: float
PRICE_TOL: float
PIVOT_TOL: float

def factor(A: ArrayLike) -> tuple[_F, _F, _F, _F]: ...
def affine(A: ArrayLike, b: ArrayLike) -> tuple[_F, _F, _F, _F, _F] | None: ...
def inequalities(lower: ArrayLike, upper: ArrayLike, G: ArrayLike, h: ArrayLike
                 ) -> tuple[_F, _F, NDArray[np.int8], NDArray[np.int64]]: ...
def least_distance(N: ArrayLike, x0: ArrayLike, w_diag: ArrayLike, w_full: ArrayLike,
                   root_full: ArrayLike, center: ArrayLike) -> _F: ...
def solve_nullspace(A: ArrayLike, b: ArrayLike, C: ArrayLike, e: ArrayLike,
                    w_diag: ArrayLike, w_full: ArrayLike, root_full: ArrayLike,
                    center: ArrayLike, feas_tol: float, max_iter: int,
                    factor: tuple[_F, _F, _F, _F] | None
                    ) -> tuple[int, _F, list[int], int, int, tuple[_F, _F, _F, _F]]: ...
def dense_qp(R: ArrayLike, t_free: ArrayLike, M: ArrayLike, f: ArrayLike, feas_tol: float,
             max_iter: int) -> tuple[int, _F, list[int], list[float], int, int]: ...
def nnls(A: ArrayLike, b: ArrayLike, max_iter: int) -> tuple[_F, float, bool]: ...
def residuals(A: ArrayLike, b: ArrayLike, lower: ArrayLike, upper: ArrayLike,
              G: ArrayLike, h: ArrayLike, x: ArrayLike) -> tuple[float, float, float]: ...
def kkt_holds(A: ArrayLike, b: ArrayLike, U: ArrayLike, sigma: ArrayLike, V: ArrayLike,
              N: ArrayLike, C: ArrayLike, e: ArrayLike, w_diag: ArrayLike,
              w_full: ArrayLike, root_full: ArrayLike, center: ArrayLike, x: ArrayLike,
              bounds: bool) -> bool: ...
def scale_lp(M: ArrayLike, a: ArrayLike, g: ArrayLike, s_lo: float, s_hi: float
             ) -> tuple[int, _F, float, list[int]]: ...
