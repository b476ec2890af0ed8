"""quadprog: Goldfarb and Idnani's dual active-set method, through qpsolvers (GPL).

It has no limit option: it is a finite dual active-set method (at most a few ``n``
iterations on this problem). It finds no solution only for inconsistent constraints.
"""

from __future__ import annotations

from .base import Backend, OptionType


def quadprog_options() -> dict[str, OptionType]:
    """Return quadprog's options: none."""
    return {}


BACKEND = Backend("quadprog", "quadprog", infeasible_when_not_found=True,
                  options=quadprog_options)


__all__ = ["BACKEND", "quadprog_options"]
