"""scs: a first-order conic method, through qpsolvers (its options are not checked here)."""

from __future__ import annotations

from .base import TIME_LIMIT_S, Backend

BACKEND = Backend("scs", "scs", sparse=True, profile={
    "eps_abs": 1e-9, "eps_rel": 0.0, "max_iters": 100000, "time_limit_secs": TIME_LIMIT_S},
    infeasible_words=("infeasible",))


__all__ = ["BACKEND"]
