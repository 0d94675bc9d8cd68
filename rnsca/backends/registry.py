"""The one place that decides which backends exist here and builds them."""

from __future__ import annotations

from functools import cache

from rnsca.backends.base import ClipBackend
from rnsca.errors import BackendUnavailableError
from rnsca.options import Backend

__all__ = ["get_backend", "available_backends"]


@cache
def get_backend(kind: Backend | str) -> ClipBackend:
    """Return the backend for `kind`, built once.

    Raises
    ------
    BackendUnavailableError
        If that backend cannot run here (never replaced by another one silently).
    """
    kind = Backend(kind)
    if kind is Backend.NUMBA:
        from rnsca.backends.numba_cpu import NumbaBackend

        return NumbaBackend()
    if kind is Backend.NUMPY:
        from rnsca.backends.numpy_ref import NumpyBackend

        return NumpyBackend()
    raise BackendUnavailableError(f"backend {kind.value!r} is not available")  # pragma: no cover


def available_backends() -> list[Backend]:
    """Return the backends that can run here, default first."""
    return [Backend.NUMBA, Backend.NUMPY]
