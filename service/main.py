"""Put the app together: settings, thread pool, middleware, handlers, routers.

Run it with ``rnsca serve`` or ``python -m service`` (settings from ``RNSCA_*``), or
``uvicorn --factory service.main:create_app``.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from starlette.middleware import Middleware
from starlette.middleware.cors import CORSMiddleware
from starlette.middleware.gzip import DEFAULT_EXCLUDED_CONTENT_TYPES, GZipMiddleware

import rnsca
from rnsca.backends.registry import configure_opencl
from rnsca.runtime import configure_process
from service.admission import AdmissionMiddleware, MemoryBudget
from service.config import Settings
from service.convert import ARROW_STREAM
from service.errors import install_handlers
from service.logs import configure_logging
from service.metrics import Metrics
from service.middleware import AccessMiddleware, BodyLimitMiddleware, InflateMiddleware
from service.routes import api_router
from service.runner import ClipRunner
from service.schemas import REQUEST_MODELS
from service.warmup import ENDPOINT_STEPS, steps_for

__all__ = ["create_app", "UNCOMPRESSED_MEDIA_TYPES"]

#: Answers sent as they are even to a client that accepts gzip: Starlette's defaults
#: (images, archives, event streams) and the binary answers, Arrow IPC streams and
#: binary segments. Their float64 coordinates barely compress: gzip saved ~12% of the
#: bytes of 200k binary segments and took 1.7 s against 24 ms unencoded.
UNCOMPRESSED_MEDIA_TYPES = (*DEFAULT_EXCLUDED_CONTENT_TYPES, ARROW_STREAM,
                            "application/octet-stream")

_DESCRIPTION = """\
Clip geometry against an axis-aligned window with the Recursive N-Subdivision Clipping
Algorithm (RNSCA): GeoJSON (whole, or streamed as text sequences), GeoArrow tables, SVG
path data and line segments (JSON or binary). Every
answer carries the clipping statistics and, on request (by default for small inputs), the
comparison with Shapely's exact intersection. Errors are RFC 9457 problem documents
(`application/problem+json`).
"""


def create_app(settings: Settings | None = None) -> FastAPI:
    """Return the service's ASGI app, configured by `settings` (default: the environment).

    Examples
    --------
    >>> app = create_app(Settings(warm_up=False))
    >>> sorted(p for p in app.openapi()["paths"] if p.startswith("/v1"))
    ... # doctest: +NORMALIZE_WHITESPACE
    ['/v1/capabilities', '/v1/clip/geoarrow', '/v1/clip/geojson', '/v1/clip/geojson-seq',
     '/v1/clip/segments', '/v1/clip/svg', '/v1/tiles', '/v1/tiles/{z}/{x}/{y}']
    """
    settings = settings or Settings()
    configure_logging(settings.log_level)
    # The service owns its process: idle OpenMP threads sleep, the environment's OpenCL
    # drivers are found (before any kernel runs or device is listed).
    configure_process()
    configure_opencl(settings.opencl_device, settings.opencl_precision)
    runner = ClipRunner(settings.clip_threads, settings.request_time_limit)
    runner.prepare(settings.threading_layer)
    metrics = Metrics()
    memory = MemoryBudget(settings.memory_budget_bytes // settings.workers)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        if settings.warm_up:
            warming = asyncio.create_task(runner.start(
                steps_for(), ENDPOINT_STEPS, settings.warm_up_processes))
        else:
            warming = None
            runner.ready.set()
        try:
            yield
        finally:
            if warming is not None:
                await warming  # a thread cannot be stopped; let it finish
            await asyncio.get_running_loop().run_in_executor(None, runner.shutdown)

    middleware = [Middleware(AccessMiddleware, metrics=metrics),
                  Middleware(GZipMiddleware, minimum_size=settings.gzip_min_bytes,
                             exclude_content_types=UNCOMPRESSED_MEDIA_TYPES)]
    if settings.cors_origins:
        middleware.append(Middleware(
            CORSMiddleware, allow_origins=settings.cors_origins,
            allow_methods=["GET", "POST"], allow_headers=["Content-Type"],
            expose_headers=["X-Rnsca-Pieces", "X-Rnsca-Layout", "X-Rnsca-Stats",
                            "X-Rnsca-Verification"]))
    middleware.append(Middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes))
    middleware.append(Middleware(InflateMiddleware, max_bytes=settings.max_body_bytes))
    # Innermost: it sees bodies inflated, and the route's thread holds its reservation.
    middleware.append(Middleware(AdmissionMiddleware, budget=memory, stream_bytes=max(
        settings.stream_chunk_bytes, settings.stream_max_record_bytes)))

    app = FastAPI(title="rnsca", version=rnsca.__version__, description=_DESCRIPTION,
                  lifespan=lifespan, middleware=middleware, openapi_url="/openapi.json",
                  # /docs and /redoc are service.routes.docs: assets served from here.
                  docs_url=None, redoc_url=None)
    app.state.settings = settings
    app.state.runner = runner
    app.state.metrics = metrics
    app.state.memory = memory
    install_handlers(app)
    app.include_router(api_router)
    app.openapi = lambda: _openapi(app)  # type: ignore[method-assign]  # as FastAPI documents
    return app


def _openapi(app: FastAPI) -> dict:
    """Return the OpenAPI schema, with the request models the routes validate themselves.

    The clip routes read their bodies as bytes and validate them in the worker thread
    (`service.convert`), so FastAPI does not see those models: they are added here.
    """
    if app.openapi_schema is None:
        schema = get_openapi(title=app.title, version=app.version,
                             description=app.description, routes=app.routes)
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        for model in REQUEST_MODELS:
            found = model.model_json_schema(ref_template="#/components/schemas/{model}")
            for name, definition in found.pop("$defs", {}).items():
                components.setdefault(name, definition)
            components[model.__name__] = found
        app.openapi_schema = schema
    return app.openapi_schema
