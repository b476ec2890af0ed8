"""Shared test set-up: this folder is on ``sys.path``, so every test imports the one
independent DH oracle (``dh_oracle``) the same way.

Fitted capsules are kept in a folder of the test session (``DUALARM_QP_CACHE``), not in
the user's cache folder.

Tests marked ``@pytest.mark.sigint`` send or simulate SIGINT: they run with Python's
own SIGINT handler installed, whatever SIGINT state pytest inherited (see ``sigint.py``).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from sigint import python_sigint


@pytest.fixture(autouse=True, scope="session")
def _capsule_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """Fitted capsules kept in a folder of this test session, not in the user's cache.

    The processes the tests start inherit it.
    """
    from dualarm_qp.geometry.capsule_cache import CACHE_ENV

    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(CACHE_ENV, str(tmp_path_factory.mktemp("capsule_cache")))
        yield


@pytest.fixture(autouse=True)
def _sigint_state(request: pytest.FixtureRequest) -> Iterator[None]:
    """Python's SIGINT handler for a ``sigint`` test; nothing changed for the others."""
    if request.node.get_closest_marker("sigint") is None:
        yield
        return
    with python_sigint():
        yield


def pytest_configure(config: pytest.Config) -> None:
    """One clear message, not a collection error per file, when the package is missing.

    The tests need the project installed with its test extras (the README's test
    command makes ``.venv`` for it); a stale compiled kernel is reported the same way.
    """
    import importlib

    try:  # the package first: it asks NumPy's BLAS for one thread before NumPy loads
        for name in ("dualarm_qp", "pinocchio"):
            importlib.import_module(name)
    except ImportError as err:
        raise pytest.UsageError(
            f"the tests cannot import what they test ({err}). Install the project and "
            "run its pytest (the README's test command): python3 -m venv .venv && "
            ".venv/bin/pip install -r requirements-build.txt && .venv/bin/pip install "
            "--no-build-isolation -e \".[dev]\" && .venv/bin/pytest -n 2") from None
