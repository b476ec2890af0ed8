"""clarabel: an interior-point method, through qpsolvers (sparse)."""

from __future__ import annotations

from .base import TIME_LIMIT_S, Backend, OptionType, options_from_attributes


def clarabel_options() -> dict[str, OptionType]:
    """Return the attributes of ``clarabel.DefaultSettings()``."""
    import clarabel

    return options_from_attributes(clarabel.DefaultSettings())


BACKEND = Backend("clarabel", "clarabel", sparse=True, profile={
    "max_iter": 100, "time_limit": TIME_LIMIT_S},
    infeasible_words=("PrimalInfeasible",), options=clarabel_options)


__all__ = ["BACKEND", "clarabel_options"]
