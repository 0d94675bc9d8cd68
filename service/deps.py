"""Dependencies of the routes, as `Annotated` aliases read back from ``app.state``.

They are coroutines on purpose: FastAPI runs a plain ``def`` dependency in its thread
pool, so three of them cost each request three thread hops (found in the load
benchmark's profile; see benchmarks/README.md, "Service load").
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from service.config import Settings
from service.metrics import Metrics
from service.runner import ClipRunner

__all__ = ["SettingsDep", "RunnerDep", "MetricsDep", "get_settings", "get_runner",
           "get_metrics"]


async def get_settings(request: Request) -> Settings:
    """Return the settings the app was built with."""
    return request.app.state.settings


async def get_runner(request: Request) -> ClipRunner:
    """Return the app's clipping thread pool."""
    return request.app.state.runner


async def get_metrics(request: Request) -> Metrics:
    """Return the app's metrics."""
    return request.app.state.metrics


SettingsDep = Annotated[Settings, Depends(get_settings)]
RunnerDep = Annotated[ClipRunner, Depends(get_runner)]
MetricsDep = Annotated[Metrics, Depends(get_metrics)]
