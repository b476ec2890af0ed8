"""Frozen dataclasses made from values that were checked where they were made.

A frozen dataclass's constructor sets each field through ``object.__setattr__`` and
runs its ``__post_init__`` checks: about 0.1 us a field. A controller step makes a few
such objects (the problem, the build, the solution, the output) from the kernel's
arrays and its own checked settings, so it makes them with :func:`made` instead: one
dictionary update, no checks. Anything else uses the constructor.
"""

from __future__ import annotations

from dataclasses import MISSING, fields
from typing import Any, TypeVar

T = TypeVar("T")

#: Per class: the names of its init fields, and each other field's default (a value,
#: or a factory to call).
_PLANS: dict[type, tuple[frozenset[str], tuple[tuple[str, Any, Any], ...]]] = {}


def made(cls: type[T], values: dict[str, Any]) -> T:
    """Return an instance of the dataclass ``cls`` holding ``values``, unchecked.

    Parameters
    ----------
    cls : type
        A dataclass without slots.
    values : dict
        Every init field of ``cls`` by name, each already of the type and the shape the
        class documents (nothing is checked or copied; ``__post_init__`` does not run).
        A field that is not an init field gets its default.

    Raises
    ------
    TypeError
        ``values`` misses an init field of ``cls`` or names one it does not have.
    """
    plan = _PLANS.get(cls)
    if plan is None:
        plan = _PLANS[cls] = _plan(cls)
    names, others = plan
    if values.keys() != names:
        raise TypeError(f"{cls.__name__} is made from every init field by name: "
                        f"{', '.join(sorted(names ^ values.keys()))}")
    obj = object.__new__(cls)
    state = vars(obj)
    state.update(values)
    for name, default, factory in others:
        state[name] = default if factory is MISSING else factory()
    return obj


def _plan(cls: type) -> tuple[frozenset[str], tuple[tuple[str, Any, Any], ...]]:
    """Return ``cls``'s init field names and its other fields' defaults."""
    init = frozenset(f.name for f in fields(cls) if f.init)
    others = tuple((f.name, f.default, f.default_factory) for f in fields(cls) if not f.init)
    for name, default, factory in others:
        if default is MISSING and factory is MISSING:
            raise TypeError(f"{cls.__name__}.{name} is not an init field and has no default")
    return init, others
