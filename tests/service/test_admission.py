"""Admission by memory: the budget, the reservations, and the answers past them."""

import asyncio
import threading

import orjson
import pytest

from service.admission import (
    BASE_BYTES,
    PEAK_BYTES_PER_BODY_BYTE,
    MemoryBudget,
    Reservation,
    current_reservation,
    estimate_bytes,
)
from service.errors import TimeLimitError
from service.runner import ClipRunner
from tests.service.conftest import make_client

WINDOW = [0, 0, 10, 10]
LINE = {"window": WINDOW, "geojson": {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}}


def test_a_reservation_is_released_when_its_last_holder_lets_go():
    budget = MemoryBudget(100)
    first = Reservation(budget)
    assert first.grow(60) and budget.in_use == 60
    second = Reservation(budget)
    assert not second.grow(41) and second.nbytes == 0 and budget.in_use == 60
    first.hold()  # a thread working for the request
    first.release()  # the answer is sent
    assert budget.in_use == 60
    first.release()  # the thread is done
    assert budget.in_use == 0
    assert second.grow(100)


def test_the_estimate_grows_with_the_body_by_the_measured_ratio():
    assert estimate_bytes("geojson", "json", 0) == BASE_BYTES
    assert estimate_bytes("geojson", "json", 10**6) == (
        BASE_BYTES + int(PEAK_BYTES_PER_BODY_BYTE[("geojson", "json")] * 10**6))
    assert estimate_bytes("segments", "binary", 10**6) < estimate_bytes("segments", "json",
                                                                        10**6)


def test_a_request_that_can_never_fit_is_413_and_a_full_budget_is_503_retry_after():
    body = orjson.dumps(LINE)
    need = estimate_bytes("geojson", "json", len(body))
    with make_client(warm_up=False, memory_budget_bytes=need - 1) as client:
        r = client.post("/v1/clip/geojson", content=body,
                        headers={"Content-Type": "application/json"})
        assert r.status_code == 413, r.text
        assert r.headers["content-type"] == "application/problem+json"
        assert r.json()["type"].endswith("over-memory-budget")
        assert "MiB" in r.json()["detail"]
    with make_client(warm_up=False, memory_budget_bytes=need + 10) as client:
        budget: MemoryBudget = client.app.state.memory
        held = Reservation(budget)
        assert held.grow(20)  # another request in flight
        r = client.post("/v1/clip/geojson", content=body,
                        headers={"Content-Type": "application/json"})
        assert r.status_code == 503, r.text
        assert r.json()["type"].endswith("memory-budget-full")
        assert r.headers["Retry-After"] == "1"
        held.release()
        r = client.post("/v1/clip/geojson", content=body,
                        headers={"Content-Type": "application/json"})
        assert r.status_code == 200, r.text
        assert budget.in_use == 0  # released once answered


def test_a_body_without_content_length_reserves_as_it_arrives():
    body = orjson.dumps(LINE)
    ratio = PEAK_BYTES_PER_BODY_BYTE[("geojson", "json")]

    def chunks():
        yield body[:10]
        yield body[10:]

    with make_client(warm_up=False,
                     memory_budget_bytes=BASE_BYTES + int(ratio * 10) + 5) as client:
        r = client.post("/v1/clip/geojson", content=chunks(),
                        headers={"Content-Type": "application/json"})
        assert r.status_code == 413 and r.json()["type"].endswith("over-memory-budget")
        assert client.app.state.memory.in_use == 0
    with make_client(warm_up=False) as client:
        r = client.post("/v1/clip/geojson", content=chunks(),
                        headers={"Content-Type": "application/json"})
        assert r.status_code == 200, r.text


def test_the_memory_stays_reserved_while_a_timed_out_clip_still_runs():
    runner = ClipRunner(threads=1, time_limit=0.05)
    runner.ready.set()
    budget = MemoryBudget(100)
    reservation = Reservation(budget)
    assert reservation.grow(80)
    release = threading.Event()

    async def request():
        current_reservation.set(reservation)
        with pytest.raises(TimeLimitError):
            await runner.run(release.wait, 10)
        reservation.release()  # the answer (503) is sent

    asyncio.run(request())
    assert budget.in_use == 80  # the thread still works for it
    release.set()
    runner.shutdown()
    assert budget.in_use == 0
