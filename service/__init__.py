"""The rnsca HTTP service: a FastAPI app over the `rnsca` library (see README.md).

`create_app` builds the app from `Settings`; `serve` runs it under uvicorn.

Both names are imported on first use, not with the package: ``python -m
service.healthcheck`` (the image's HEALTHCHECK, every 15 s) then needs only the standard
library, not the library's kernels (seconds of imports, and a Numba cache it can open).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from service.config import Settings
    from service.main import create_app

__all__ = ["Settings", "create_app"]

_HOMES = {"Settings": "service.config", "create_app": "service.main"}


def __getattr__(name: str) -> Any:
    """Return `Settings` or `create_app`, imported now (PEP 562)."""
    if name in _HOMES:
        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module 'service' has no attribute {name!r}")
