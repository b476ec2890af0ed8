"""The QP backends of the ``qp:<backend>`` solvers: one module each, and their registry.

Each module holds one :class:`~.base.Backend` (``BACKEND``): its qpsolvers name, pip
extra, tolerance profile and limits, how its status says "infeasible", how to read the
options of the installed package, and, for osqp and proxsuite, a native solver object
kept across steps. A backend is called through qpsolvers (:mod:`.qpsolvers_`) unless it
has a native object; every call gives a :class:`~.answer.BackendAnswer`, which carries
its own residuals. Adding a backend is one module here and one line below.
"""

from __future__ import annotations

import importlib.util

from . import (
    clarabel_,
    cvxopt_,
    daqp_,
    ecos_,
    highs_,
    osqp_,
    piqp_,
    proxsuite_,
    qpalm_,
    quadprog_,
    scs_,
)
from .answer import BackendAnswer
from .base import TIME_LIMIT_S, Backend, NativeQP, OptionType
from .qpsolvers_ import installed, solve_with_qpsolvers

#: Registry name suffix (``qp:<key>``) -> backend, in the listing order.
BACKENDS: dict[str, Backend] = {
    "osqp": osqp_.BACKEND,
    "proxsuite": proxsuite_.BACKEND,
    "daqp": daqp_.BACKEND,
    "clarabel": clarabel_.BACKEND,
    "piqp": piqp_.BACKEND,
    "highs": highs_.BACKEND,
    "quadprog": quadprog_.BACKEND,
    "cvxopt": cvxopt_.BACKEND,
    "ecos": ecos_.BACKEND,
    "scs": scs_.BACKEND,
    "qpalm": qpalm_.BACKEND,
}

#: qpsolvers backend name -> the maker of its native object, for the installed backends
#: that have one.
NATIVE = {backend.solver: backend.native for backend in BACKENDS.values()
          if backend.native is not None
          and importlib.util.find_spec(backend.native_module) is not None}

__all__ = ["BACKENDS", "NATIVE", "TIME_LIMIT_S", "Backend", "BackendAnswer", "NativeQP",
           "OptionType", "installed", "solve_with_qpsolvers"]
