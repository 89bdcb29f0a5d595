"""The Python package's tests (ctest -R python): the package from the build (PYTHONPATH=build/python,
set by tests/CMakeLists.txt) and the CLI binary as XB_BENCH."""
import os

import pytest


@pytest.fixture(scope="session")
def bench():
    path = os.environ.get("XB_BENCH", os.path.join(os.path.dirname(__file__), "..", "..", "build", "xpbd-bench"))
    assert os.path.exists(path), f"xpbd-bench not found at {path} (set XB_BENCH)"
    return path
