"""Objects that hold the kernel's objects: pickled without them, made again (private).

A kernel object (a ``dualarm_qp._kernel`` class: a chain, a waypoint path, the collision
scene's coal solvers) is no Python object that a pickle can hold; nor is a native QP
solver's module or set-up solver. A class that holds some names them in
``_kernel_attributes`` and makes them in ``_remake``: its pickles (of an arm, a task, a
collision scene, a controller; ``copy.deepcopy`` pickles too) leave them out, and
unpickling makes them again from the rest of the state.
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
