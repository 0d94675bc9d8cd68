"""The one place that decides which backends exist here and builds them.

The OpenCL backend is optional: it needs pyopencl and an OpenCL device. Asking for it
where either is missing raises `BackendUnavailableError` with the reason; nothing ever
runs on another backend instead. Its device and precision are set with
`configure_opencl` (the service passes its ``RNSCA_OPENCL_DEVICE`` and
``RNSCA_OPENCL_PRECISION`` settings; the CLI its options); by default the first GPU,
else the first device, in float64 where the device has it.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from rnsca.backends.base import ClipBackend
from rnsca.errors import BackendUnavailableError
from rnsca.options import Backend, Precision

__all__ = ["get_backend", "available_backends", "configure_opencl", "opencl_report",
           "opencl_available"]

_BUILT: dict[Backend, ClipBackend] = {}
_LOCK = threading.RLock()


@dataclass
class _OpenCLSettings:
    """What `configure_opencl` last set: the device asked for (None: the default one)."""

    device: str | None = None
    precision: Precision = Precision.AUTO


_OPENCL = _OpenCLSettings()
_OPENCL_FAILURE: list[str] = []  # why the configured OpenCL backend could not be built


def get_backend(kind: Backend | str) -> ClipBackend:
    """Return the backend for `kind`, built once (OpenCL: once per configuration).

    (``"auto"`` is resolved per call by `rnsca.backends.auto.backend_for`.)

    Raises
    ------
    BackendUnavailableError
        If that backend cannot run here (never replaced by another one silently).
    """
    kind = Backend(kind)
    with _LOCK:
        if kind not in _BUILT:
            _BUILT[kind] = _build(kind)
        return _BUILT[kind]


def _build(kind: Backend) -> ClipBackend:
    if kind is Backend.NUMBA:
        from rnsca.backends.numba_cpu import NumbaBackend

        return NumbaBackend()
    opencl = _opencl_module()
    return opencl.OpenCLBackend(_OPENCL.device, _OPENCL.precision)


def configure_opencl(device: str | None = None, precision: Precision | str = "auto") -> None:
    """Set the device and precision that ``backend="opencl"`` uses from now on.

    Parameters
    ----------
    device : str, optional
        ``"platform:device"`` indices or part of a device's name (see ``rnsca backends``);
        None: the first GPU, else the first device.
    precision : {"auto", "float64", "float32"}
        ``"auto"``: float64 where the device has ``cl_khr_fp64``, else float32.

    Nothing is checked until the backend is next asked for; then a device that is not
    there raises `BackendUnavailableError`.
    """
    precision = Precision(precision)
    with _LOCK:
        _OPENCL.device = device
        _OPENCL.precision = precision
        _BUILT.pop(Backend.OPENCL, None)
        _OPENCL_FAILURE.clear()


def _opencl_module() -> ModuleType:
    """Return ``rnsca.backends.opencl``, or raise BackendUnavailableError naming why not."""
    try:
        import pyopencl  # noqa: F401
    except ImportError as exc:
        raise BackendUnavailableError(
            f"backend 'opencl' needs pyopencl and an OpenCL driver: pip install "
            f"'rnsca[opencl]' (PoCL, for the CPU) ({exc})") from None
    from rnsca.backends import opencl

    return opencl


def _opencl_reason() -> str | None:
    """Return why ``backend="opencl"`` cannot run as configured, or None if it can.

    Builds the backend (and its program) once per configuration; a failure is kept too,
    so asking again costs nothing.
    """
    with _LOCK:
        if Backend.OPENCL in _BUILT:
            return None
        if _OPENCL_FAILURE:
            return _OPENCL_FAILURE[0]
        try:
            get_backend(Backend.OPENCL)
        except BackendUnavailableError as exc:
            _OPENCL_FAILURE.append(str(exc))
            return str(exc)
        return None


def opencl_report() -> dict[str, Any]:
    """Return what OpenCL offers here, for listings (CLI, ``/v1/capabilities``).

    Keys: ``available`` (the configured device can run the kernels), ``reason`` (if
    not), ``devices`` (every device found: ``id`` "platform:device", ``platform``,
    ``device``, ``type``, ``fp64``, ``version``), ``selected`` (the configured device's
    id, or None) and ``precision`` (the one in use, or the one asked for).
    """
    reason = _opencl_reason()
    report: dict[str, Any] = {"available": reason is None}
    if reason is not None:
        report["reason"] = reason
    try:
        opencl = _opencl_module()
        report["devices"] = opencl.list_devices()
    except BackendUnavailableError:
        report["devices"] = []
    if reason is None:
        # The backend's capabilities name its one device and the precision it resolved
        # ("auto" becomes float64 or float32).
        capabilities = get_backend(Backend.OPENCL).capabilities
        report["selected"] = capabilities.devices[0]
        report["precision"] = capabilities.precision.value
    else:
        report["selected"] = None
        report["precision"] = _OPENCL.precision.value
    return report


def opencl_available() -> bool:
    """Return whether ``backend="opencl"`` can run as configured (checked once)."""
    return _opencl_reason() is None


def available_backends() -> list[Backend]:
    """Return the backends that can run here, default first."""
    present = [Backend.NUMBA]
    if _opencl_reason() is None:
        present.append(Backend.OPENCL)
    return present
