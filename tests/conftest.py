"""Fixtures shared by every test layer: Hypothesis profiles, a seeded generator, and the
backend, method and mode axes that the correctness tests run over.

Hypothesis profiles (pick one with ``HYPOTHESIS_PROFILE=<name>``):

- ``dev`` (default): random examples, 30 per test.
- ``ci`` (used when ``CI=true``): derandomized, so a run is reproducible and a failure in
  CI is the same failure on a laptop; 25 examples per test.
- ``thorough``: 1000 examples per test, for a long local hunt.

Every profile has ``deadline=None``: the first call of a kernel compiles it (or loads it
from Numba's cache), which would blow any per-example deadline.
"""

import os

import rnsca.runtime

# The tests own their process, as the CLI and the service do: OpenCL drivers of this
# environment, idle OpenMP threads asleep. Before any kernel runs.
rnsca.runtime.configure_process()

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402

from rnsca import Backend, Method, Mode  # noqa: E402
from rnsca.backends.registry import get_backend  # noqa: E402
from rnsca.errors import BackendUnavailableError  # noqa: E402
from tests.missing import IN_CI, missing  # noqa: E402

_COMMON = dict(deadline=None, print_blob=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("dev", max_examples=30, **_COMMON)
settings.register_profile("ci", max_examples=25, derandomize=True, **_COMMON)
settings.register_profile("thorough", max_examples=1000, **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE")
                      or ("ci" if IN_CI else "dev"))

#: The seed of every non-Hypothesis random input, so a failure reproduces exactly.
SEED = 20_241_122


@pytest.fixture
def rng() -> np.random.Generator:
    """Return a generator seeded with `SEED`, fresh for each test."""
    return np.random.default_rng(SEED)


# Session scope: Hypothesis refuses function-scoped fixtures in @given tests (they would
# not be reset between examples); these are plain values, so nothing needs resetting.
def require_backend(kind: Backend) -> Backend:
    """Return `kind` if it can run here; else skip with the reason (in CI: fail)."""
    try:
        get_backend(kind)
    except BackendUnavailableError as exc:
        missing(f"backend {kind.value!r} is not available here: {exc}")
    return kind


_BACKEND_PARAMS = [pytest.param(kind, marks=pytest.mark.opencl) if kind is Backend.OPENCL
                   else kind for kind in Backend]


@pytest.fixture(scope="session", params=_BACKEND_PARAMS, ids=lambda b: b.value)
def backend(request):
    """Each backend; OpenCL (marker ``opencl``) skips where it is missing, fails in CI."""
    return require_backend(request.param)


@pytest.fixture(scope="session")
def opencl():
    """The OpenCL backend (default device), skipped where missing, a failure in CI."""
    return get_backend(require_backend(Backend.OPENCL))


@pytest.fixture(scope="session")
def opencl64(opencl):
    """The OpenCL backend on a float64 device: what bit-for-bit agreement with Numba needs.

    Skipped on a float32 device (whose own tests cover it), a failure in CI, whose CPU
    runtimes all have float64.
    """
    from rnsca.options import Precision

    if opencl.precision is not Precision.FLOAT64:
        missing(f"the OpenCL device {opencl.name!r} runs float32: this test needs float64")
    return opencl


@pytest.fixture(scope="session", params=list(Method), ids=lambda m: m.value)
def method(request):
    """Each segment clipping method."""
    return request.param


@pytest.fixture(scope="session", params=list(Mode), ids=lambda m: m.value)
def mode(request):
    """Each mode: exact, approx."""
    return request.param
