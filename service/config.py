"""Settings of the service: the one place that reads the environment (prefix ``RNSCA_``)."""

from __future__ import annotations

import os
from typing import Annotated, Literal

from pydantic import Field, PositiveFloat, PositiveInt, field_validator, model_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from rnsca.options import Backend, Precision

__all__ = ["Settings", "LogLevel", "ThreadingLayer"]

LogLevel = Literal["critical", "error", "warning", "info", "debug"]
#: Numba threading layers the service accepts. ``threadsafe`` lets Numba pick one that
#: allows concurrent callers (``tbb`` or ``omp``); ``workqueue`` is not thread-safe, so
#: the service then serializes its parallel kernel calls (see `service.runner`).
ThreadingLayer = Literal["threadsafe", "tbb", "omp", "workqueue"]


class Settings(BaseSettings):
    """Everything an operator can set, from ``RNSCA_*`` variables (or a ``.env`` file).

    Invalid values stop the process at start-up, before it listens.

    Examples
    --------
    >>> Settings(max_vertices=10).max_vertices
    10
    >>> Settings(port=0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pydantic_core._pydantic_core.ValidationError: 1 validation error for Settings
    ...
    """

    model_config = SettingsConfigDict(env_prefix="RNSCA_", env_file=".env",
                                      env_file_encoding="utf-8", extra="ignore")

    host: str = "127.0.0.1"
    """Address `rnsca serve` listens on (the Docker image sets 0.0.0.0)."""
    port: int = Field(8000, ge=1, le=65535)
    """TCP port."""
    workers: PositiveInt = 1
    """uvicorn worker processes; each compiles nothing (kernels load from the cache)."""
    max_body_bytes: PositiveInt = 64 * 2**20
    """Request bodies larger than this are refused with 413 while they are read."""
    max_vertices: PositiveInt = 5_000_000
    """Largest input, in vertices (a segment counts 2); more gives 413."""
    work_budget: PositiveInt = 500_000_000
    """Largest estimated work of one request, in fragments evaluated (about 20 ns each on
    one core, see `service.budget`); more gives 422 before any clipping."""
    max_tiles: PositiveInt = 100_000
    """Most tiles ``POST /v1/tiles`` cuts in one zoom (a short line across the world makes
    millions at zoom 20); more gives 413, checked after each zoom's cut."""
    memory_budget_bytes: PositiveInt = 2 * 2**30
    """Memory the clip requests in flight may use, all workers together (each worker
    takes its share); a request's need is estimated from its body (`service.admission`).
    Past it: 503 with Retry-After; a request that needs more than a worker's share: 413."""
    stream_chunk_bytes: PositiveInt = 4 * 2**20
    """Streamed GeoJSON (``POST /v1/clip/geojson-seq``) is clipped in chunks of records
    holding about this many bytes of text (a chunk ends before the record that would take
    it past this), or `stream_chunk_records` records, whichever comes first."""
    stream_chunk_records: PositiveInt = 5000
    """Records (GeoJSON texts) of a streamed chunk, at most."""
    stream_max_record_bytes: PositiveInt = 8 * 2**20
    """Longest record of a streamed body; a longer one is refused (413 before the answer
    has started, else a problem record ends it). The memory a stream reserves is that of a
    JSON body of ``max(stream_chunk_bytes, stream_max_record_bytes)`` (`service.admission`),
    whatever the stream's length: ``max_body_bytes`` does not apply to it."""
    request_time_limit: PositiveFloat = 30.0
    """Seconds a request may wait for and use a clipping thread; past it: 503."""
    clip_threads: PositiveInt = 2
    """Requests clipped at once (more wait their turn); kernels are parallel inside each."""
    verify_max_vertices: int = Field(100_000, ge=0)
    """``verify`` defaults to true for inputs of at most this many vertices."""
    verify_cost_ratio: float = Field(1.0, gt=0)
    """Verification (``verify`` true or by default) may take this many times the clip's
    own time; past it a random sample of the inputs is compared, and the answer says so.
    ``verify: "all"`` compares every input, within the request's time limit: comparing
    stops in time to answer (`request_time_limit`), and the answer says how many were
    compared."""
    verify_max_crossings: int = Field(1000, ge=0)
    """An input whose comparison would make GEOS node an outline crossing itself more
    than about this many times (an invalid polygon, a filled path) is not compared, and
    the answer counts it in ``skipped``: GEOS cannot be interrupted, and its time grows
    faster than the square of the crossings (``make_valid``: 0.3 s for 800)."""
    default_backend: Backend = Backend.NUMBA
    """Backend of requests that name none."""
    opencl_device: str | None = None
    """OpenCL device of ``backend: opencl``: "platform:device" (as `rnsca backends` lists
    them) or part of its name; unset: the first GPU, else the first device."""
    opencl_precision: Precision = Precision.AUTO
    """OpenCL precision: auto (float64 where the device has it, else float32), float64 or
    float32."""
    cors_origins: Annotated[list[str], NoDecode] = []
    """Origins allowed by CORS, comma-separated (``*`` for any); empty: no CORS headers."""
    gzip_min_bytes: PositiveInt = 1024
    """Responses at least this large are gzip-compressed when the client accepts it, except
    binary ones (Arrow IPC streams, binary segments: `service.main.UNCOMPRESSED_MEDIA_TYPES`)."""
    log_level: LogLevel = "info"
    """Level of the JSON log lines (one per request at ``info``)."""
    warm_up: bool = True
    """Compile (or load from the cache) the kernels before `/readyz` answers 200."""
    warm_up_processes: int = Field(default_factory=lambda: os.cpu_count() or 1, ge=0)
    """On a cold kernel cache, compile in this many child processes at once (default: one
    per core; 0: in the worker itself). Each endpoint is served once its kernels are."""
    threading_layer: ThreadingLayer = "threadsafe"
    """Numba threading layer, applied unless ``NUMBA_THREADING_LAYER`` is set."""
    graceful_shutdown_seconds: PositiveFloat = 60.0
    """On SIGTERM, how long requests in flight may take to finish."""
    header_timeout_seconds: PositiveFloat = 10.0
    """Seconds a request head (request line and headers) may take to arrive, on a new
    connection or the next request of a kept-alive one; past it the connection is closed.
    The body has the request's time limit (408 past it)."""
    idle_timeout_seconds: PositiveInt = 5
    """A kept-alive connection idle this long after a response is closed."""
    max_connections: PositiveInt = 512
    """Open connections (and requests in flight) at most, per worker; past it uvicorn
    answers 503 at once (its own plain-text answer)."""

    @field_validator("cors_origins", mode="before")
    @classmethod
    def _split_origins(cls, value: object) -> object:
        if isinstance(value, str):
            return [part.strip() for part in value.split(",") if part.strip()]
        return value

    @field_validator("log_level", mode="before")
    @classmethod
    def _lower_level(cls, value: object) -> object:
        return value.lower() if isinstance(value, str) else value

    @model_validator(mode="after")
    def _consistent(self) -> Settings:
        if self.graceful_shutdown_seconds < self.request_time_limit:
            raise ValueError("graceful_shutdown_seconds must be at least request_time_limit, "
                             "so a request in flight at SIGTERM can finish")
        return self
