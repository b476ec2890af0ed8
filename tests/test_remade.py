"""The holders of objects a pickle cannot hold: pickled without them, made again."""

from __future__ import annotations

import copy
import pickle
import threading

import pytest

from dualarm_qp._remade import KernelHolder


class _Path(KernelHolder):
    """An object that holds one a pickle cannot hold (a lock stands for a native solver)."""

    _kernel_attributes = ("_path",)

    def __init__(self, offset: float) -> None:
        self.offset = offset
        self.made = 0
        self._remake()

    def _remake(self) -> None:
        self._path = threading.Lock()
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
