"""Fuzz target: ``POST /v1/clip/segments`` with a binary (``application/octet-stream``) body.

The app runs in this process (Starlette's TestClient, lifespan started). An input is:

- byte 0: ``method`` (one of five, or left out);
- byte 1: ``mode`` (exact, approx or left out) and ``verify`` (true, false, all or left
  out);
- byte 2: ``n`` and ``max_depth``, valid or not (``n=1``, ``max_depth=33``...);
- byte 3: ``tolerance`` and ``resolution``, valid or not;
- bytes 4-35: the window ``xmin, ymin, xmax, ymax`` as little-endian float64 (any bits:
  NaN, infinities, subnormals; fewer than 32 bytes leave bounds out);
- the rest: the body, little-endian float64 rows ``x0, y0, x1, y1`` (any length).

A finding is any of: a 5xx; an error that is not an RFC 9457 problem document
(``application/problem+json`` whose ``status`` is the response's); a 4xx for a request
the reference says is valid (beyond the documented work-budget refusal); a 200 for one
it says is not; a 200 whose pieces differ from the library's own answer for the same
request, or from the reference clip.

References
----------
Validity: a request is valid if the window is four finite numbers with ``xmin < xmax``
and ``ymin < ymax``, the body a whole number of finite rows whose coordinate differences
do not overflow, and the options within the API's documented ranges.

Pieces: `tests.cases.exact_clip`, the clip of each segment in exact rational arithmetic
(Python's fractions) rounded once at the end, judged by `tests.checks`: exact mode (and
the analytic methods in any mode) within 1e-9 of the window's size of the exact piece;
approx mode never more than the true clip and within one leaf of it at each cut end;
every piece inside the closed window, its ``t`` interval reproducing it, sources
increasing. Also, when the service verified its answer against Shapely, the
verification must have passed where GEOS can judge (`tests.checks.shapely_can_judge`:
no segment over 1e5 windows long, no coordinate below 2**-500); beyond that the
service's verification is known to fail correct answers (GEOS overflows), which is
reported, not asserted.
"""

from __future__ import annotations

import math
import struct
import warnings

import numpy as np
import orjson

import rnsca
from rnsca.errors import RnscaError
from service import Settings, create_app
from tests.checks import (
    assert_inside_window,
    assert_piece_is_expected,
    assert_t_matches_pieces,
    assert_well_formed,
    exact_pieces,
    shapely_can_judge,
)

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # Starlette prefers httpx2 now
    from fastapi.testclient import TestClient

__all__ = ["MAX_LEN", "setup", "test_one_input"]

#: Longest input: 36 bytes of options and window, then up to 60 segments.
MAX_LEN = 36 + 60 * 32

METHODS = ("rnsca", "cohen_sutherland", "liang_barsky", "nicholl_lee_nicholl", "midpoint",
           None)
MODES = (None, "exact", "approx")
VERIFY = (None, "true", "false", "all")
# Values of n and max_depth; the API takes n from 2 to 64 and max_depth from 0 to 32.
N_VALUES = (None, 2, 3, 7, 64, 1, 65, 0)
DEPTHS = (None, 0, 1, 5, 32, 33, -1)
TOLERANCES = (None, "0.001", "0", "-1", "nan", "inf")
RESOLUTIONS = (None, "16px", "0.5", "0px", "abc")

_client: TestClient | None = None


def setup() -> None:
    """Start the app and compile the segment kernels of every method and mode."""
    global _client
    # No time limit of its own: the first requests compile, and libFuzzer times inputs.
    settings = Settings(warm_up=False, log_level="critical", request_time_limit=3600,
                        graceful_shutdown_seconds=3600)
    _client = TestClient(create_app(settings))
    _client.__enter__()
    body = np.array([[-5.0, 5.0, 15.0, 5.0], [1.0, 1.0, 2.0, 2.0]], dtype="<f8").tobytes()
    for method in METHODS[:-1]:
        for mode in MODES[1:]:
            for n in (None, 3):
                params = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10, "method": method,
                          "mode": mode} | ({} if n is None else {"n": n})
                response = _client.post("/v1/clip/segments", content=body, params=params,
                                        headers={"Content-Type": "application/octet-stream"})
                assert response.status_code == 200, response.text


def _request(data: bytes) -> tuple[dict, list[float | None], bytes]:
    """Return the query parameters, the window bounds and the body an input encodes."""
    head = data[:4].ljust(4, b"\0")
    method = METHODS[head[0] % len(METHODS)]
    mode, verify = MODES[head[1] % 3], VERIFY[head[1] // 3 % 4]
    n, depth = N_VALUES[head[2] % 8], DEPTHS[head[2] // 8 % 7]
    tolerance, resolution = TOLERANCES[head[3] % 6], RESOLUTIONS[head[3] // 6 % 5]
    window_bytes = data[4:36]
    bounds: list[float | None] = [
        struct.unpack_from("<d", window_bytes, 8 * k)[0] if len(window_bytes) >= 8 * k + 8
        else None for k in range(4)]
    options = {"method": method, "mode": mode, "verify": verify, "n": n, "max_depth": depth,
               "tolerance": tolerance, "resolution": resolution}
    params = {name: value for name, value in options.items() if value is not None}
    params |= {name: repr(b) for name, b in zip(("xmin", "ymin", "xmax", "ymax"), bounds,
                                                strict=True) if b is not None}
    return params, bounds, data[36:]


def _valid_options(params: dict) -> bool | None:
    """Return whether the options are valid: True, False, or None if the API decides.

    ``tolerance`` and ``resolution`` have rules of their own (per mode); the reference
    does not predict them.
    """
    if "tolerance" in params or "resolution" in params:
        return None
    n, depth = params.get("n", 2), params.get("max_depth", 0)
    return 2 <= n <= 64 and 0 <= depth <= 32


def _valid_geometry(bounds: list[float | None], body: bytes) -> bool:
    """Return whether the window and the segments are valid (see the module docstring)."""
    if None in bounds or not all(map(math.isfinite, bounds)):
        return False
    xmin, ymin, xmax, ymax = bounds
    if not (xmin < xmax and ymin < ymax) or len(body) % 32:
        return False
    rows = np.frombuffer(body, dtype="<f8").reshape(-1, 4)
    with np.errstate(over="ignore", invalid="ignore"):
        return bool(np.isfinite(rows).all() and np.isfinite(rows[:, 2:] - rows[:, :2]).all())


def _check_problem(response) -> None:
    """Check that an error response is an RFC 9457 problem document."""
    assert response.status_code < 500, f"{response.status_code}: {response.text}"
    assert response.headers["content-type"].startswith("application/problem+json"), (
        response.headers["content-type"], response.text)
    problem = orjson.loads(response.content)
    assert problem["status"] == response.status_code, problem
    assert isinstance(problem["type"], str) and isinstance(problem["title"], str), problem
    assert isinstance(problem["detail"], str), problem


def _library(rows: np.ndarray, bounds: list[float], params: dict):
    """Return the library's clip for the request, as the service should compute it."""
    options: dict = {name: params[name] for name in ("method", "mode") if name in params}
    for name in ("n", "max_depth"):
        if name in params:
            options[name] = params[name]
    if "tolerance" in params:
        options["tolerance"] = float(params["tolerance"])
    if "resolution" in params:
        text = params["resolution"]
        try:
            options["resolution"] = float(text)
        except ValueError:
            options["resolution"] = text
    return rnsca.clip_segments(rows, rnsca.Window(*bounds), **options)


def test_one_input(data: bytes) -> None:
    """Send the request an input encodes and check the answer."""
    assert _client is not None, "call setup() first"
    params, bounds, body = _request(data)
    response = _client.post("/v1/clip/segments", content=body, params=params,
                            headers={"Content-Type": "application/octet-stream"})
    valid = _valid_geometry(bounds, body) and _valid_options(params)
    if response.status_code != 200:
        _check_problem(response)
        budget = response.status_code == 422 and orjson.loads(response.content)[
            "type"].endswith("work-over-budget")
        assert valid is not True or budget, f"refused a valid request: {response.text}"
        return
    assert valid is not False, f"200 for an invalid request {params}, {len(body)} bytes"
    rows = np.frombuffer(body, dtype="<f8").reshape(-1, 4).copy()
    m = int(response.headers["X-Rnsca-Pieces"])
    content = response.content
    assert len(content) == 56 * m, (len(content), m)
    pieces = np.frombuffer(content[:32 * m], dtype="<f8").reshape(m, 4)
    source = np.frombuffer(content[32 * m:40 * m], dtype="<i8")
    t = np.frombuffer(content[40 * m:], dtype="<f8").reshape(m, 2)
    stats = orjson.loads(response.headers["X-Rnsca-Stats"])
    assert stats["segments_in"] == rows.shape[0] and stats["pieces_out"] == m, stats
    if "X-Rnsca-Verification" in response.headers and shapely_can_judge(
            rnsca.Window(*bounds), rows).all():
        # Shapely (GEOS) cannot judge every segment (see `shapely_can_judge`): there, a
        # failed verification is a limit of the oracle, not a finding.
        verification = orjson.loads(response.headers["X-Rnsca-Verification"])
        assert verification["passed"], f"the service's own verification failed: {verification}"
    try:
        result = _library(rows, bounds, params)
    except RnscaError as error:
        raise AssertionError(f"the service answered 200, the library raised {error!r}") \
            from None
    assert np.array_equal(result.segments, pieces) and np.array_equal(result.source, source) \
        and np.array_equal(result.t, t), "the service's pieces differ from the library's"
    window = rnsca.Window(*bounds)
    assert_well_formed(result, rows.shape[0])
    assert_inside_window(result, window)
    assert_t_matches_pieces(result, rows)
    assert_piece_is_expected(result, rows, exact_pieces(rows, window), window,
                             result.method, result.mode)
