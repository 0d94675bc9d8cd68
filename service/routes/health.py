"""``/healthz`` (the process answers) and ``/readyz`` (the kernels are ready)."""

from __future__ import annotations

import orjson
from fastapi import APIRouter
from starlette.responses import Response

from service.deps import RunnerDep
from service.errors import NotReadyError
from service.schemas import Health, Problem

__all__ = ["router"]

router = APIRouter(tags=["operations"])


@router.get("/healthz", response_model=Health, summary="Liveness")
async def healthz() -> Response:
    """Answer 200 while the event loop runs (also during a long clip)."""
    return Response(orjson.dumps({"status": "ok"}), media_type="application/json")


@router.get("/readyz", response_model=Health, summary="Readiness",
            responses={503: {"model": Problem, "description": "Kernels not ready yet",
                             "content": {"application/problem+json": {}}}})
async def readyz(runner: RunnerDep) -> Response:
    """Answer 200 once the kernels are compiled or loaded from the cache, else 503.

    During warm-up each clipping endpoint is served as soon as its own kernels are
    ready: the 503 lists them (``served``: ``segments``, ``geojson``, ``svg``).
    """
    if runner.failure is not None:
        raise NotReadyError(f"warming up the kernels failed: {runner.failure}")
    if not runner.ready.is_set():
        served = sorted(runner.served)
        raise NotReadyError(
            "the kernels are being compiled or loaded from the cache"
            + (f"; served meanwhile: {', '.join(served)}" if served else ""),
            headers={"Retry-After": "2"}, served=served)
    return Response(orjson.dumps({"status": "ready"}), media_type="application/json")
