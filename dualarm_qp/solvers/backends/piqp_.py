"""piqp: a proximal interior-point method, through qpsolvers (dense)."""

from __future__ import annotations

from .base import Backend, OptionType, options_from_attributes


def piqp_options() -> dict[str, OptionType]:
    """Return the attributes of ``piqp.DenseSolver().settings``."""
    import piqp

    return options_from_attributes(piqp.DenseSolver().settings)


BACKEND = Backend("piqp", "piqp", profile={
    "eps_abs": 1e-8, "eps_rel": 1e-9, "max_iter": 100},
    infeasible_words=("PRIMAL_INFEASIBLE",), options=piqp_options)


__all__ = ["BACKEND", "piqp_options"]
