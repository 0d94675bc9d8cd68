"""The backend contract: every backend runs every operation through one signature, and
the library asks a backend's capabilities, never which backend it holds."""

import inspect

import numpy as np
import pytest
import shapely

import rnsca
from rnsca.backends import base
from rnsca.backends.base import Capabilities, ClipBackend, Operation
from rnsca.backends.registry import get_backend
from rnsca.errors import BackendUnavailableError, InvalidOptionError
from rnsca.options import Backend, Method, Mode

OPERATIONS = ["clip_segments", "clip_segment_windows", "clip_lines", "clip_polygons",
              "clip_paths", "flatten_paths", "encode_segment_tiles", "warm_up"]


def test_every_backend_implements_every_operation_with_the_contracts_signature(backend):
    engine = get_backend(backend)
    for name in OPERATIONS:
        declared = inspect.signature(getattr(ClipBackend, name))
        implemented = inspect.signature(getattr(type(engine), name)).parameters
        # The contract's parameters, in order; an implementation may add keyword-only
        # ones with defaults (the Numba backend's `device`, for the OpenCL backend).
        # The contract's own keyword-only options (segments' `source` and `t`) are
        # there too, with the contract's defaults.
        def positional(parameters):
            return [p.name for p in parameters.values()
                    if not (p.kind is p.KEYWORD_ONLY and p.default is not p.empty)]

        assert positional(implemented) == positional(declared.parameters), name
        for p in declared.parameters.values():
            if p.kind is p.KEYWORD_ONLY:
                assert implemented[p.name].default == p.default, (name, p.name)
    capabilities = engine.capabilities
    assert capabilities.backend is backend
    assert capabilities.operations == frozenset(Operation)
    assert capabilities.modes == frozenset(Mode)


def test_capabilities_name_what_is_missing():
    only_segments = Capabilities(Backend.NUMBA, operations=frozenset({Operation.SEGMENTS}),
                                 modes=frozenset({Mode.EXACT}))
    assert only_segments.supports("segments") and not only_segments.supports("paths")
    with pytest.raises(BackendUnavailableError, match="does not clip polygons .*segments"):
        only_segments.require("polygons")
    with pytest.raises(BackendUnavailableError, match="does not run mode='approx'"):
        only_segments.require("segments", "approx")
    assert only_segments.to_dict() == {"backend": "numba", "operations": ["segments"],
                                       "modes": ["exact"], "precision": "float64",
                                       "devices": ["cpu"]}


@pytest.fixture
def segments_only(monkeypatch):
    """The Numba backend, claiming to run segments only."""
    engine = get_backend(Backend.NUMBA)
    limited = Capabilities(Backend.NUMBA, operations=frozenset({Operation.SEGMENTS}))
    monkeypatch.setattr(type(engine), "capabilities", property(lambda self: limited))
    return engine


def test_the_library_asks_the_capabilities_for_every_operation(segments_only):
    line = shapely.LineString([(-5, 5), (15, 5)])
    square = shapely.box(-5, -5, 5, 5)
    paths = rnsca.parse_paths(["M -5 5 C 0 15 10 -5 15 5"])
    assert len(rnsca.clip_segments([[-5, 5, 15, 5]], (0, 0, 10, 10))) == 1
    for call, what in [
            (lambda: rnsca.clip_ragged(*shapely.to_ragged_array([line]), (0, 0, 10, 10)),
             "lines"),
            (lambda: rnsca.clip(square, (0, 0, 10, 10)), "polygons"),
            (lambda: rnsca.clip_paths(paths, (0, 0, 10, 10)), "paths"),
            (lambda: rnsca.flatten_paths(paths, 0.1), "flatten")]:
        with pytest.raises(BackendUnavailableError, match=f"does not clip {what}"):
            call()


def test_no_code_outside_backends_asks_which_backend_it_holds():
    # The contract's promise, checked on the source of the library and the service:
    # no comparison with a Backend member, no backend class named, no device-only method.
    import pathlib
    import re

    import service

    pattern = re.compile(r"(is|is not|==|!=) Backend\.|in \(Backend\.|NumbaBackend\(|"
                         r"OpenCLBackend\(|\.classify_curves\(")
    offenders = []
    for package in (rnsca, service):
        root = pathlib.Path(package.__file__).parent
        for path in root.rglob("*.py"):
            if "backends" in path.relative_to(root).parts:
                continue
            for number, line in enumerate(path.read_text().splitlines(), 1):
                if pattern.search(line):
                    offenders.append(f"{path.name}:{number}: {line.strip()}")
    assert offenders == []


def test_results_are_the_contracts_types(backend):
    engine = get_backend(backend)
    segments = engine.clip_segments(np.array([[-5.0, 5.0, 15.0, 5.0]]), rnsca.Window(0, 0, 10, 10),
                                    rnsca.options.SegmentOptions.resolve(
                                        rnsca.Window(0, 0, 10, 10)))
    assert isinstance(segments, base.SegmentPieces)
    assert segments.source.tolist() == [0] and segments.pieces.tolist() == [[0, 5, 10, 5]]


# One input per clipping operation, by the public function that runs it.
_CLIP_BY_OPERATION = {
    Operation.SEGMENTS: lambda **o: rnsca.clip_segments([[-5.0, 5.0, 15.0, 5.0]],
                                                        (0, 0, 10, 10), **o),
    Operation.LINES: lambda **o: rnsca.clip(shapely.LineString([(-5, 5), (15, 5)]),
                                            (0, 0, 10, 10), **o),
    Operation.POLYGONS: lambda **o: rnsca.clip(shapely.box(-5, -5, 5, 5), (0, 0, 10, 10), **o),
    Operation.PATHS: lambda **o: rnsca.clip_svg(["M -5 5 C 0 15 10 -5 15 5"],
                                                (0, 0, 10, 10), **o),
}


@pytest.mark.parametrize("operation", list(_CLIP_BY_OPERATION), ids=lambda o: o.value)
def test_an_operation_accepts_exactly_the_methods_and_modes_it_lists(operation):
    """`Operation.methods` and `.modes` (what /v1/capabilities tells the playground) are
    what the library accepts: every other combination is refused with InvalidOptionError."""
    for method in Method:
        for mode in Mode:
            listed = method in operation.methods and mode in operation.modes
            try:
                _CLIP_BY_OPERATION[operation](method=method.value, mode=mode.value)
            except InvalidOptionError:
                assert not listed, (method, mode)
            else:
                assert listed, (method, mode)
    assert Operation.FLATTEN.methods == () and Operation.FLATTEN.modes == ()
