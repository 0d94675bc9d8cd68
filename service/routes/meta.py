"""``/v1/capabilities`` and ``/metrics``."""

from __future__ import annotations

import orjson
from fastapi import APIRouter
from prometheus_client import CONTENT_TYPE_LATEST
from starlette.responses import Response

import rnsca
from rnsca.backends.base import Operation
from rnsca.options import Method, Mode
from service import convert
from service.deps import MetricsDep, RunnerDep, SettingsDep
from service.schemas import Capabilities

__all__ = ["router", "v1_router"]

v1_router = APIRouter(prefix="/v1", tags=["meta"])
router = APIRouter(tags=["operations"])


@v1_router.get("/capabilities", response_model=Capabilities, summary="What this server can do")
async def capabilities(settings: SettingsDep, runner: RunnerDep) -> Response:
    """Return the methods, modes, backends (and devices), and the limits of requests."""
    body = {
        "version": rnsca.__version__,
        "methods": [m.value for m in Method],
        "modes": [m.value for m in Mode],
        # Per kind of input (many windows is a way to clip one, not a kind of its own).
        "operations": {op.value: {"methods": [m.value for m in op.methods],
                                  "modes": [m.value for m in op.modes]}
                       for op in Operation if op.methods and op is not Operation.WINDOWS},
        "backends": convert.backend_report(),
        "threading_layer": runner.threading_layer,
        "serialized": runner.serialized,
        "svg": True,
        "limits": {
            "max_body_bytes": settings.max_body_bytes,
            "max_vertices": settings.max_vertices,
            "work_budget": settings.work_budget,
            "request_time_limit": settings.request_time_limit,
            "verify_max_vertices": settings.verify_max_vertices,
            "stream_chunk_bytes": settings.stream_chunk_bytes,
            "stream_chunk_records": settings.stream_chunk_records,
            "stream_max_record_bytes": settings.stream_max_record_bytes,
            "max_tiles": settings.max_tiles,
        },
    }
    return Response(orjson.dumps(body), media_type="application/json")


@router.get("/metrics", summary="Prometheus metrics",
            responses={200: {"content": {CONTENT_TYPE_LATEST: {}},
                             "description": "Prometheus text exposition"}})
async def metrics(metrics: MetricsDep) -> Response:
    """Return request counts and latencies by route and status, and clipping counters."""
    return Response(metrics.render(), media_type=CONTENT_TYPE_LATEST)
