"""The driver's batch sizes: large while many points are left, one point at the end."""

from __future__ import annotations

import contextlib
from types import SimpleNamespace

from dualarm_qp.sweep import driver as driver_module
from dualarm_qp.sweep.driver import MAX_BATCH, _Remote, batch_size


def remote(batch: int | None, workers: int, first: int) -> _Remote:
    r = _Remote(SimpleNamespace(batch=batch), contextlib.ExitStack(), "code")
    r.client, r.workers = object(), workers  # as open() leaves them
    r.size = batch or batch_size(first, workers)
    return r


def test_batches_shrink_to_one_point_as_the_queue_empties():
    r = remote(None, workers=2, first=221)
    sizes, left = [], 221
    while left:
        n = r.batch_for(left)
        sizes.append(n)
        left -= n
    assert sizes[0] == MAX_BATCH == max(sizes)
    assert sizes == sorted(sizes, reverse=True)  # never growing
    assert sizes[-3:] == [1, 1, 1]
    assert sum(sizes) == 221


def test_a_batch_size_given_is_kept_to_the_end():
    r = remote(5, workers=2, first=221)
    assert {r.batch_for(left) for left in (221, 40, 3, 1)} == {5}


def test_no_batch_is_larger_than_the_first(monkeypatch):
    monkeypatch.setattr(driver_module, "MAX_BATCH", 1000)
    r = remote(None, workers=1, first=8)  # a rerun: few points left at the start
    assert r.size == 2
    assert r.batch_for(8) == 2 and r.batch_for(80) == 2
