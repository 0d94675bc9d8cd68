"""From route to kernel in at most five hops (issue 14): the request's own frames, counted.

A hop is one call on the way from the route to the compiled kernel: route -> conversion
-> library -> ... -> kernel. The route hands the body to the clip pool (`runner.run`,
thread-pool plumbing, not a hop); from there the stack of the pool thread is read at the
kernel's entry, and the frames of rnsca and service code between the pool and the
kernel are the hops after the first.
"""

import inspect
import pathlib

import pytest

import rnsca
import service
from rnsca.kernels import bezier, polygons, polylines
from tests.service.conftest import make_client

ROOTS = tuple(str(pathlib.Path(p.__file__).parent) for p in (rnsca, service))
PLUMBING = ("runner.py",)  # the pool's entry: `ClipRunner._call`
LIMIT = 5


def _frames_to_kernel(monkeypatch, module, name, path, body):
    """Return the rnsca/service frames (file, function) between the pool and `module.name`."""
    seen = []
    kernel = getattr(module, name)

    def recording(*args, **kwargs):
        if not seen:
            seen.extend((pathlib.Path(f.filename).name, f.function)
                        for f in inspect.stack()[1:]
                        if f.filename.startswith(ROOTS) and not f.filename.endswith(PLUMBING))
        return kernel(*args, **kwargs)

    monkeypatch.setattr(module, name, recording)
    # No warm-up (it would call the kernel first); the first request may compile the
    # kernels, so the time limit leaves room for a cold cache on a busy machine.
    with make_client(warm_up=False, request_time_limit=600,
                     graceful_shutdown_seconds=600) as client:
        r = client.post(path, json=body)
    assert r.status_code == 200, r.text
    assert seen, f"{name} was not called"
    return list(reversed(seen))  # outermost first


LINE = {"type": "LineString", "coordinates": [[-5, 5], [15, 5]]}
SQUARE = {"type": "Polygon", "coordinates": [[[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]]}


@pytest.mark.parametrize("module, kernel, request_", [
    (polylines, "clip_lines", ("/v1/clip/geojson", {"window": [0, 0, 10, 10], "geojson": LINE,
                                                    "verify": False})),
    (polygons, "clip_polygon_blocks", ("/v1/clip/geojson", {
        "window": [0, 0, 10, 10], "geojson": SQUARE, "verify": False})),
    (bezier, "clip_path_blocks", ("/v1/clip/svg", {
        "window": [0, 0, 10, 10], "paths": ["M -5 5 C 0 15 10 -5 15 5"], "verify": False})),
], ids=["geojson-lines", "geojson-polygons", "svg"])
def test_a_request_reaches_its_kernel_in_at_most_five_hops(monkeypatch, module, kernel,
                                                           request_):
    path, body = request_
    frames = _frames_to_kernel(monkeypatch, module, kernel, path, body)
    # route -> first frame is one hop, each frame -> the next one more, the last -> kernel.
    hops = len(frames) + 1
    assert hops <= LIMIT, " -> ".join(f"{f}:{fn}" for f, fn in frames)
