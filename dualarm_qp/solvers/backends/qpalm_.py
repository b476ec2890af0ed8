"""qpalm: a proximal augmented-Lagrangian method, through qpsolvers (options not checked here)."""

from __future__ import annotations

from .base import TIME_LIMIT_S, Backend

BACKEND = Backend("qpalm", "qpalm", sparse=True, profile={
    "eps_abs": 1e-9, "eps_rel": 0.0, "max_iter": 10000, "max_time": TIME_LIMIT_S},
    infeasible_words=("primal infeasible",))


__all__ = ["BACKEND"]
