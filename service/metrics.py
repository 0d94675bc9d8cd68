"""Prometheus metrics of one app: requests by route and status, and clipping counters."""

from __future__ import annotations

from prometheus_client import CollectorRegistry, Counter, Histogram, generate_latest

from rnsca.stats import ClipStats

__all__ = ["Metrics"]

# Latency buckets (seconds): health checks in microseconds up to large clips in seconds.
_BUCKETS = (0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
            30.0, 60.0)


class Metrics:
    """The metrics of one app, in their own registry (several apps can share a process).

    With several uvicorn workers each process counts its own requests; scrape each, or
    run one worker per container (see docker/README.md).
    """

    def __init__(self) -> None:
        self.registry = CollectorRegistry()
        self.requests = Counter(
            "rnsca_http_requests", "HTTP requests answered, by route template and status.",
            ["method", "route", "status"], registry=self.registry)
        self.latency = Histogram(
            "rnsca_http_request_duration_seconds",
            "Time from the request's arrival to the end of its response.",
            ["method", "route", "status"], buckets=_BUCKETS, registry=self.registry)
        self.segments = Counter(
            "rnsca_segments_clipped", "Input segments (of lines and rings too) clipped.",
            registry=self.registry)
        self.pruned = Counter(
            "rnsca_fragments_pruned",
            "Fragments decided whole by their outcodes (accepted or rejected) without an "
            "intersection.", registry=self.registry)
        self.intersections = Counter(
            "rnsca_intersections", "Edge intersection parameters computed.",
            registry=self.registry)

        self.stream_spilled = Counter(
            "rnsca_stream_spilled_bytes",
            "Bytes of streamed answers that waited in a temporary file for a client that "
            "was not reading them yet (service.streaming).", registry=self.registry)

    def observe_request(self, method: str, route: str, status: int, seconds: float) -> None:
        """Count one answered request."""
        labels = (method, route, str(status))
        self.requests.labels(*labels).inc()
        self.latency.labels(*labels).observe(seconds)

    def observe_clip(self, stats: ClipStats) -> None:
        """Add the counters of one clipping call."""
        self.segments.inc(stats.segments_in)
        self.pruned.inc(stats.accepted + stats.rejected)
        self.intersections.inc(stats.intersections)

    def render(self) -> bytes:
        """Return the exposition text."""
        return generate_latest(self.registry)
