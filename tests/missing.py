"""What a test does when something it needs is not installed: skip here, fail in CI.

Under ``CI=true`` every dependency must be there (`.ci/run` installs the Debian
packages, `make test` the Python ones), so a missing one is a failure, never a skip
that would hide the tests it gates.
"""

from __future__ import annotations

import os
from typing import NoReturn

import pytest

__all__ = ["IN_CI", "missing"]

#: Whether this run is CI's (``CI=true``).
IN_CI = os.environ.get("CI", "").lower() == "true"


def missing(message: str) -> NoReturn:
    """Fail (in CI) or skip (elsewhere) the calling test, saying what is missing."""
    if IN_CI:
        pytest.fail(message)
    pytest.skip(message)
