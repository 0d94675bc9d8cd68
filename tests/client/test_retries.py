"""Retries against scripted loopback servers: 503 then 200, Retry-After honoured and
bounded, failures to connect, no retry of a 4xx, and one connection reused."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

import rnsca_client
from rnsca_client import AsyncClient, Client, Retry
from tests.client.scripted import CLIP_GEOJSON_ANSWER, Reply, ScriptedServer, unavailable
from tests.e2e.server import free_port

LINE = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
WINDOW = (0, 0, 10, 10)
FAST = Retry(attempts=4, backoff=0.05, max_backoff=0.2, jitter=0.0)


def test_503_then_200_is_retried_and_honours_retry_after():
    script = [unavailable("0.3"), unavailable("0.3"), Reply(200, CLIP_GEOJSON_ANSWER)]
    with ScriptedServer(script) as scripted, Client(scripted.url, retries=FAST) as c:
        result = c.clip_geojson(LINE, WINDOW)
    assert result.geojson == CLIP_GEOJSON_ANSWER["geojson"]
    assert scripted.requests == 3
    assert all(gap >= 0.3 for gap in scripted.gaps()), scripted.gaps()
    assert scripted.bodies[0] == scripted.bodies[2]   # the same request each time


def test_503_without_retry_after_backs_off_exponentially():
    policy = Retry(attempts=4, backoff=0.1, max_backoff=10, jitter=0.0)
    script = [unavailable(), unavailable(), unavailable(), Reply()]
    with ScriptedServer(script) as scripted, Client(scripted.url, retries=policy) as c:
        assert c.health().status == "ok"
    gaps = scripted.gaps()
    assert scripted.requests == 4
    assert gaps[0] >= 0.1 and gaps[1] >= 0.2 and gaps[2] >= 0.4, gaps


def test_retry_after_is_bounded_and_the_last_503_is_raised():
    policy = Retry(attempts=3, backoff=0.05, max_retry_after=0.1, jitter=0.0)
    started = time.monotonic()
    with ScriptedServer([unavailable("3600")]) as scripted, \
            Client(scripted.url, retries=policy) as c, \
            pytest.raises(rnsca_client.ServiceUnavailableError) as info:
        c.clip_svg("M 0 0 L 1 1", WINDOW)
    # Honouring the server's hour would hang; the bound is 0.1 s per wait.
    assert time.monotonic() - started < 30
    assert scripted.requests == 3 and info.value.attempts == 3
    assert info.value.retry_after == 3600 and info.value.kind == "time-limit"


def test_http_date_retry_after_is_read():
    from email.utils import formatdate

    when = formatdate(time.time() + 1, usegmt=True)
    with ScriptedServer([unavailable(when), Reply()]) as scripted, \
            Client(scripted.url, retries=FAST) as c:
        c.health()
    assert scripted.requests == 2 and scripted.gaps()[0] >= 0.0


def test_4xx_is_not_retried():
    problem = {"type": "urn:rnsca:problem:invalid-window", "title": "Invalid window",
               "status": 422, "detail": "xmin must be < xmax", "path": "window"}
    with ScriptedServer([Reply(422, problem, content_type="application/problem+json")]) \
            as scripted, Client(scripted.url, retries=FAST) as c, \
            pytest.raises(rnsca_client.InvalidRequestError):
        c.clip_geojson(LINE, WINDOW)
    assert scripted.requests == 1


def test_readyz_503_is_an_answer_not_a_failure():
    with ScriptedServer([unavailable("1"), Reply(200, {"status": "ready"})]) as scripted, \
            Client(scripted.url, retries=FAST) as c:
        assert c.ready() is False
        assert scripted.requests == 1
        c.wait_until_ready(timeout=10, interval=0.05)
        assert scripted.requests == 2


def test_connection_refused_is_retried_until_the_server_is_up():
    port = free_port()
    servers = []
    starter = threading.Timer(0.4, lambda: servers.append(ScriptedServer([Reply()], port)))
    starter.start()
    policy = Retry(attempts=30, backoff=0.05, max_backoff=0.1, jitter=0.0)
    try:
        with Client(f"http://127.0.0.1:{port}", retries=policy) as c:
            assert c.health().status == "ok"
    finally:
        starter.join()
        for s in servers:
            s.close()
    assert servers[0].requests == 1


def test_one_connection_is_reused_for_many_calls():
    with ScriptedServer([Reply()]) as scripted, Client(scripted.url) as c:
        for _ in range(5):
            c.health()
    assert scripted.requests == 5 and scripted.connections == 1


def test_async_client_retries_503_and_reuses_its_connection():
    script = [unavailable("0.2"), Reply(200, CLIP_GEOJSON_ANSWER)]

    async def run(url):
        async with AsyncClient(url, retries=FAST) as c:
            first = await c.clip_geojson(LINE, WINDOW)
            second = await c.clip_geojson(LINE, WINDOW)
        return first, second

    with ScriptedServer(script) as scripted:
        first, second = asyncio.run(run(scripted.url))
    assert first == second and first.stats.pieces_out == 1
    assert scripted.requests == 3 and scripted.gaps()[0] >= 0.2
    assert scripted.connections == 1


def test_async_client_connect_error_after_the_retries():
    async def run():
        async with AsyncClient(f"http://127.0.0.1:{free_port()}",
                               retries=Retry(attempts=2, backoff=0.01)) as c:
            await c.health()

    with pytest.raises(rnsca_client.ConnectError) as info:
        asyncio.run(run())
    assert info.value.attempts == 2


def test_retry_policy_validation():
    assert Retry.of(None).attempts == 1 and Retry.of(3).attempts == 4
    with pytest.raises(ValueError, match="retries"):
        Retry.of(-1)
    with pytest.raises(ValueError, match="jitter"):
        Retry(jitter=2)
