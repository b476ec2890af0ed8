"""cvxopt: an interior-point method, through qpsolvers (its options are not checked here)."""

from __future__ import annotations

from .base import Backend

BACKEND = Backend("cvxopt", "cvxopt", profile={
    "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10, "maxiters": 100})


__all__ = ["BACKEND"]
