"""When to try a request again, and how long to wait first.

Clipping is a pure function of the request, so every endpoint may be retried safely.
Retried: failures to connect (refused, unreachable, connect timeout: the request never
reached the server) and 503 (warming up, or over the request time limit because the
server is busy). Not retried: other errors (a 4xx stays a 4xx) and read timeouts (the
server is working on it; asking again would add to its load).
"""

from __future__ import annotations

import random
from dataclasses import dataclass

__all__ = ["Retry"]


@dataclass(frozen=True)
class Retry:
    """A retry policy: at most `attempts` tries in all, with exponential backoff.

    The wait before try k + 1 (k = 1, 2, ...) is ``backoff * 2**(k - 1)``, at most
    `max_backoff`, scaled by a random factor in ``[1 - jitter, 1]`` so that many
    clients do not come back in step. A 503 with ``Retry-After`` waits what the server
    asked instead, but never longer than `max_retry_after`.

    Examples
    --------
    >>> policy = Retry(attempts=5, backoff=0.5, max_backoff=2.0, jitter=0.0)
    >>> [policy.delay(k) for k in (1, 2, 3, 4)]
    [0.5, 1.0, 2.0, 2.0]
    >>> policy.delay(1, retry_after=120.0)   # bounded by max_retry_after
    30.0
    >>> Retry(attempts=0)
    Traceback (most recent call last):
    ...
    ValueError: attempts must be at least 1 (1: no retry), got 0
    """

    attempts: int = 4
    backoff: float = 0.25
    max_backoff: float = 8.0
    max_retry_after: float = 30.0
    jitter: float = 0.5

    def __post_init__(self) -> None:
        if self.attempts < 1:
            raise ValueError(f"attempts must be at least 1 (1: no retry), got {self.attempts}")
        for name in ("backoff", "max_backoff", "max_retry_after"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")
        if not 0 <= self.jitter <= 1:
            raise ValueError(f"jitter must be within [0, 1], got {self.jitter}")

    @classmethod
    def of(cls, retries: Retry | int | None) -> Retry:
        """Return `retries` as a policy: a Retry, a number of retries, or None (none)."""
        if isinstance(retries, Retry):
            return retries
        if retries is None:
            return cls(attempts=1)
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise ValueError(f"retries must be a Retry or a count >= 0, got {retries!r}")
        return cls(attempts=retries + 1)

    def delay(self, attempt: int, retry_after: float | None = None) -> float:
        """Return the seconds to wait after failed try number `attempt` (from 1)."""
        if retry_after is not None:
            return min(retry_after, self.max_retry_after)
        base = min(self.backoff * 2.0 ** (attempt - 1), self.max_backoff)
        return base * (1.0 - self.jitter * random.random())
