"""Fixtures of the sweep tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from sweep_tools import Cluster


@pytest.fixture
def cluster() -> Iterator[Cluster]:
    """A ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1."""
    c = Cluster(workers=2)
    try:
        yield c
    finally:
        c.close()
