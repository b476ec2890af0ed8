"""A package's names imported from their modules on first access (PEP 562; private)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, MutableMapping
from importlib import import_module
from typing import Any


def lazy_names(package: str, namespace: MutableMapping[str, Any],
               lazy: Mapping[str, str]) -> Callable[[str], Any]:
    """Return the module ``__getattr__`` of ``package`` for the names of ``lazy``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    namespace : dict
        The package's ``globals()``: a name, once imported, is kept there, so later
        accesses do not call the function.
    lazy : mapping
        Each public name and the module (relative to ``package``) that defines it.
    """

    def __getattr__(name: str) -> Any:
        where = lazy.get(name)
        if where is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f".{where}", package), name)
        namespace[name] = value
        return value

    return __getattr__


__all__ = ["lazy_names"]
