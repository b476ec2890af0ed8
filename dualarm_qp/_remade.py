"""Objects that hold what a pickle cannot: pickled without it, made again (private).

The kernel's chains, waypoint paths and support planes pickle themselves. Three things
do not: the kernel's loop over the step's parts (``kernel.Step``, whose parts may be
Python objects the kernel only refers to: it is made again from them), the collision
scene's coal solvers, and a native QP solver's module or set-up solver (OSQP,
ProxQP). A class that holds one names it in ``_kernel_attributes`` and makes it in
``_remake``: its pickles (``copy.deepcopy`` pickles too) leave it out, and unpickling
makes it again from the rest of the state.
"""

from __future__ import annotations

from typing import Any, ClassVar


class KernelHolder:
    """Mixin of a class whose attributes ``_kernel_attributes`` hold kernel objects.

    The class makes them in :meth:`_remake` (its constructor may call it too); a pickle
    holds every other attribute.
    """

    _kernel_attributes: ClassVar[tuple[str, ...]] = ()

    def _remake(self) -> None:
        """Make the kernel objects from the other attributes (after unpickling)."""
        raise NotImplementedError

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        for name in self._kernel_attributes:
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._remake()


__all__ = ["KernelHolder"]
