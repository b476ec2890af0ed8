"""The holders of kernel objects: pickled without them, made again when unpickled."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from dualarm_qp._compiled import kernel
from dualarm_qp._remade import KernelHolder


class _Path(KernelHolder):
    """A waypoint path of the kernel's, made from two poses."""

    _kernel_attributes = ("_path",)

    def __init__(self, offset: float) -> None:
        self.offset = offset
        self.made = 0
        self._remake()

    def _remake(self) -> None:
        T = np.eye(4)
        T[0, 3] = self.offset
        self._path = kernel.WaypointPath([0.0, 1.0], np.concatenate([np.eye(4), T]))
        self.made += 1


def test_the_kernel_object_is_left_out_and_made_again() -> None:
    holder = _Path(0.5)
    state = holder.__getstate__()
    assert "_path" not in state and state["offset"] == 0.5
    with pytest.raises(TypeError):
        pickle.dumps(holder._path)  # what the mixin is for
    for other in (pickle.loads(pickle.dumps(holder)), copy.deepcopy(holder), copy.copy(holder)):
        assert other._path is not holder._path
        assert other.made == 2 and other.offset == 0.5
    assert holder.made == 1  # the original is untouched


class _Bare(KernelHolder):
    """A holder that does not say how to make its kernel object."""

    _kernel_attributes = ("_x",)


def test_a_holder_without_its_maker_is_an_error() -> None:
    bare = _Bare()
    bare._x = 1  # type: ignore[attr-defined]
    with pytest.raises(NotImplementedError):
        pickle.loads(pickle.dumps(bare))
