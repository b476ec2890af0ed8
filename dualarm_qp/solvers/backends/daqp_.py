"""daqp: a dual active-set method for small dense problems, through qpsolvers."""

from __future__ import annotations

import inspect

from .base import TIME_LIMIT_S, Backend, OptionType, kind_of

#: Data arguments of ``daqp.solve`` (not options).
_DAQP_DATA = frozenset({"H", "f", "A", "bupper", "blower", "sense", "break_points", "is_avi",
                        "primal_start", "dual_start"})


def daqp_options() -> dict[str, OptionType]:
    """Return the keywords of ``daqp.solve`` that are options."""
    import daqp

    params = inspect.signature(daqp.solve).parameters
    return {name: OptionType(kind, p.default, flag=False)
            for name, p in params.items()
            if name not in _DAQP_DATA and (kind := kind_of(p.default)) is not None}


BACKEND = Backend("daqp", "daqp", profile={
    "primal_tol": 1e-10, "iter_limit": 1000, "time_limit": TIME_LIMIT_S},
    options=daqp_options)


__all__ = ["BACKEND", "daqp_options"]
