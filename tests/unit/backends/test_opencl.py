"""The OpenCL backend: device selection, missing OpenCL, float32 and its bound, stats.

The agreement of its pieces and counters with the other backends is in
tests/property/test_backends_agree.py; the other segment tests run it through the
`backend` fixture. Tests that need a device take the `opencl` fixture (skipped where
OpenCL is missing, a failure in CI).
"""

import dataclasses
import json
import sys
import threading

import numpy as np
import pytest

import rnsca
from rnsca import Window, clip_segments, constants
from rnsca.backends import registry
from rnsca.errors import BackendUnavailableError, InvalidGeometryError, InvalidWindowError
from rnsca.options import Method, Mode, Precision, SegmentOptions
from tests.unit.test_constants import clip_cl_macros

pytestmark = pytest.mark.opencl

W = Window(0.0, 0.0, 10.0, 20.0)


@pytest.fixture
def opencl_module(opencl):
    from rnsca.backends import opencl as module

    return module


@pytest.fixture
def default_configuration():
    """Restore the registry's default OpenCL configuration after the test."""
    yield
    registry.configure_opencl()


def fake_devices(*entries):
    return [{"id": f"{p}:{d}", "platform": platform, "device": name, "type": kind,
             "fp64": fp64, "version": "OpenCL 3.0", "max_work_group_size": 256}
            for p, d, platform, name, kind, fp64 in entries]


# --- device selection --------------------------------------------------------------------


def test_the_default_device_is_the_first_gpu(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Portable Computing Language", "cpu-x", "cpu", True),
                           (1, 0, "NVIDIA CUDA", "RTX", "gpu", True),
                           (1, 1, "NVIDIA CUDA", "RTX 2", "gpu", True))
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    assert opencl_module.select_device(None)["id"] == "1:0"
    assert opencl_module.select_device("  ")["id"] == "1:0"


def test_without_a_gpu_the_default_device_is_the_first_device(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Intel(R) OpenCL", "cpu-a", "cpu", True),
                           (1, 0, "Portable Computing Language", "cpu-b", "cpu", True))
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    assert opencl_module.select_device(None)["id"] == "0:0"


def test_a_device_is_named_by_index_or_by_part_of_its_name(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Intel(R) OpenCL", "cpu-a", "cpu", True),
                           (1, 0, "Portable Computing Language", "pthread-cpu", "cpu", True),
                           (1, 1, "NVIDIA CUDA", "GeForce RTX 4090", "gpu", False))
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    assert opencl_module.select_device("1:1")["device"] == "GeForce RTX 4090"
    assert opencl_module.select_device("portable")["id"] == "1:0"
    assert opencl_module.select_device("rtx 4090")["id"] == "1:1"


def test_a_device_matching_nothing_is_an_error_listing_the_devices(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Intel(R) OpenCL", "cpu-a", "cpu", True))
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    with pytest.raises(BackendUnavailableError, match=r"no OpenCL device matches '7:0'.*"
                                                      r"found: 0:0 Intel\(R\) OpenCL / cpu-a"):
        opencl_module.select_device("7:0")


def test_float64_on_a_device_without_fp64_is_an_error_not_float32(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Some GPU platform", "small-gpu", "gpu", False))
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    with pytest.raises(BackendUnavailableError, match="has no float64.*'float32' or 'auto'"):
        opencl_module.OpenCLBackend(precision="float64")


def test_a_device_with_small_work_groups_is_unavailable(opencl_module, monkeypatch):
    devices = fake_devices((0, 0, "Tiny platform", "tiny", "accelerator", True))
    devices[0]["max_work_group_size"] = 32
    monkeypatch.setattr(opencl_module, "list_devices", lambda: devices)
    with pytest.raises(BackendUnavailableError, match="at most 32 work-items per group"):
        opencl_module.OpenCLBackend()


def test_warm_up_runs_segments_lines_and_polygons(opencl):
    opencl.warm_up()


def test_the_listing_names_every_device_with_its_fp64_support(opencl_module, opencl):
    devices = opencl_module.list_devices()
    assert opencl.device in devices
    for device in devices:
        assert set(device) == {"id", "platform", "device", "type", "fp64", "version",
                               "max_work_group_size"}
        assert device["type"] in ("gpu", "cpu", "accelerator", "other")


def test_auto_precision_is_float64_where_the_device_has_it(opencl):
    expected = Precision.FLOAT64 if opencl.device["fp64"] else Precision.FLOAT32
    assert opencl.precision is expected


def test_the_registry_uses_the_configured_device(opencl, default_configuration):
    registry.configure_opencl(opencl.device["id"], "float32")
    engine = registry.get_backend("opencl")
    assert engine.device == opencl.device and engine.precision is Precision.FLOAT32
    r = clip_segments([[-5.0, 5.0, 15.0, 5.0]], W, backend="opencl")
    assert r.stats.device.precision == "float32"
    registry.configure_opencl("no such device")
    with pytest.raises(BackendUnavailableError, match="no OpenCL device matches"):
        clip_segments([[-5.0, 5.0, 15.0, 5.0]], W, backend="opencl")
    assert "opencl" not in [b.value for b in registry.available_backends()]


def test_programs_are_built_once_per_device_and_precision(opencl, opencl_module):
    again = opencl_module.OpenCLBackend(opencl.device["id"], opencl.precision)
    assert again._device is opencl._device
    double = opencl.precision is Precision.FLOAT64
    assert again._device.program(double) is opencl._device.program(double)


def test_programs_are_kept_by_their_build_options(opencl, opencl_module):
    double = opencl.precision is Precision.FLOAT64
    options = opencl_module._build_options(double)
    assert opencl._device.programs[options] is opencl._device.program(double)


# --- shared constants: rnsca.constants reaches clip.cl as build options ---------------------


def defined_by_options(options) -> dict[str, str]:
    return dict(option[2:].split("=", 1) for option in options if option.startswith("-D"))


@pytest.mark.parametrize("double", [False, True], ids=["float32", "float64"])
def test_the_build_options_give_clip_cl_every_shared_constant(opencl_module, double):
    given = defined_by_options(opencl_module._build_options(double))
    assert {name: int(given[name].strip("()")) for name in constants.__all__} == {
        name: getattr(constants, name) for name in constants.__all__}
    assert given["REAL_IS_DOUBLE"] == str(int(double))


def test_clip_cl_defines_no_name_it_is_given_as_a_build_option(opencl_module):
    given = set()
    for double in (False, True):
        given |= set(defined_by_options(opencl_module._build_options(double)))
    assert {"REAL_IS_DOUBLE", "LOCAL_SIZE", "LEFT", "COUNTERS_WIDTH"} <= given
    assert sorted(given & clip_cl_macros()) == []


def test_a_program_built_with_the_options_sees_the_shared_values(opencl, opencl_module):
    import pyopencl as cl

    names = constants.__all__
    body = "\n".join(f"    out[{k}] = {name};" for k, name in enumerate(names))
    source = f"__kernel void shared(__global long *out) {{\n{body}\n}}"
    context, queue = opencl._device.context, opencl._device.queue
    program = opencl_module._build_program(context, "test", source,
                                           opencl_module.constant_options())
    out = np.empty(len(names), dtype=np.int64)
    buffer = cl.Buffer(context, cl.mem_flags.WRITE_ONLY, out.nbytes)
    program.shared(queue, (1,), None, buffer)
    cl.enqueue_copy(queue, out, buffer)
    assert dict(zip(names, out.tolist(), strict=True)) == {
        name: getattr(constants, name) for name in names}


def test_only_ints_become_build_options(opencl_module, monkeypatch):
    monkeypatch.setattr(constants, "LEFT", 1.0)
    with pytest.raises(TypeError, match=r"rnsca.constants.LEFT = 1.0 is not an int"):
        opencl_module.constant_options()


# --- OpenCL missing: a clear error, never another backend ----------------------------------


def test_without_pyopencl_asking_for_opencl_says_what_to_install(monkeypatch,
                                                                 default_configuration):
    monkeypatch.setitem(sys.modules, "pyopencl", None)  # `import pyopencl` fails
    registry.configure_opencl()
    with pytest.raises(BackendUnavailableError, match=r"needs pyopencl.*rnsca\[opencl\]"):
        clip_segments([[0.0, 0.0, 1.0, 1.0]], W, backend="opencl")
    assert [b.value for b in registry.available_backends()] == ["numba"]
    report = registry.opencl_report()
    assert report["available"] is False and "needs pyopencl" in report["reason"]
    assert report["devices"] == []


def test_without_an_opencl_platform_asking_for_opencl_says_so(opencl_module, monkeypatch,
                                                              default_configuration):
    import pyopencl

    def no_platform():
        raise pyopencl.LogicError("clGetPlatformIDs failed: PLATFORM_NOT_FOUND_KHR")

    monkeypatch.setattr(pyopencl, "get_platforms", no_platform)
    registry.configure_opencl()
    with pytest.raises(BackendUnavailableError, match="no OpenCL platform found.*PoCL"):
        clip_segments([[0.0, 0.0, 1.0, 1.0]], W, backend="opencl")
    assert registry.opencl_report()["available"] is False


def test_a_platform_without_devices_is_no_device(opencl_module, monkeypatch):
    import pyopencl

    monkeypatch.setattr(pyopencl, "get_platforms", lambda: [])
    with pytest.raises(BackendUnavailableError, match="no OpenCL device found"):
        opencl_module.list_devices()


def test_a_driver_that_cannot_build_the_kernels_is_an_unavailable_backend(opencl,
                                                                          opencl_module):
    with pytest.raises(BackendUnavailableError,
                       match="'broken / device' could not build the kernels: .*error"):
        opencl_module._build_program(opencl._device.context, "broken / device",
                                     "this is not OpenCL C", [])


# --- stats -------------------------------------------------------------------------------


def test_stats_count_the_transfers_and_their_bytes(opencl, rng):
    segs = rng.uniform(-10.0, 30.0, size=(1000, 4))
    r = clip_segments(segs, W, backend="opencl")
    d = r.stats.device
    real = 8 if opencl.precision is Precision.FLOAT64 else 4
    m = len(r)
    assert d.device == opencl.name and d.precision == opencl.precision.value
    # Up: the window and the segments. Down: the row reduced on the device (41 counters,
    # the first non-finite segment and the count of pieces), the pieces, sources, t.
    assert d.transfers == 6
    assert d.bytes_to_device == 4 * real + 1000 * 4 * real
    assert d.bytes_from_device == 43 * 8 + m * (4 * real + 8 + 2 * real)
    assert d.kernel_seconds > 0 and d.transfer_seconds > 0


def test_nothing_kept_brings_back_only_the_counters(opencl):
    r = clip_segments([[20.0, 30.0, 40.0, 50.0]], W, backend="opencl")
    assert len(r) == 0 and r.stats.rejected == 1
    assert r.stats.device.transfers == 3  # window, segments up; the counter row down


def test_empty_input_moves_nothing_but_the_counters(opencl):
    r = clip_segments(np.empty((0, 4)), W, backend="opencl")
    assert len(r) == 0 and r.stats.segments_in == 0
    assert r.stats.device.bytes_to_device == 0 and r.stats.device.transfers == 0


def test_combined_stats_add_the_device_counters(opencl, rng):
    from rnsca.stats import ClipStats

    a = clip_segments(rng.uniform(-10, 30, (100, 4)), W, backend="opencl").stats
    b = clip_segments(rng.uniform(-10, 30, (50, 4)), W, backend="opencl").stats
    both = ClipStats.combine([a, b])
    assert both.device.transfers == a.device.transfers + b.device.transfers
    assert both.device.bytes_to_device == (2 + 100 + 50) * 4 * (
        8 if opencl.precision is Precision.FLOAT64 else 4)


def test_concurrent_calls_give_the_same_pieces(opencl, rng):
    segs = rng.uniform(-10.0, 30.0, size=(5000, 4))
    expected = clip_segments(segs, W, backend="numba")
    results = [None] * 4

    def run(k):
        results[k] = clip_segments(segs, W, backend="opencl")

    threads = [threading.Thread(target=run, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        np.testing.assert_array_equal(r.source, expected.source)
        np.testing.assert_allclose(r.segments, expected.segments, rtol=1e-12, atol=1e-12)


def test_two_backends_on_one_device_can_be_called_at_once(opencl, opencl_module, rng):
    # Both share the device's kernel objects (and so its call lock).
    other = opencl_module.OpenCLBackend(opencl.device["id"], opencl.precision)
    segs = rng.uniform(-10.0, 30.0, size=(20000, 4))
    options = SegmentOptions.resolve(W)
    expected = clip_segments(segs, W, backend="numba")
    results = [None] * 6

    def run(k):
        results[k] = (opencl if k % 2 else other).clip_segments(segs, W, options)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for out in results:
        np.testing.assert_array_equal(out.source, expected.source)
        np.testing.assert_allclose(out.pieces, expected.segments, rtol=1e-12, atol=1e-12)


# --- float32 -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def float32(opencl):
    from rnsca.backends.opencl import OpenCLBackend

    return OpenCLBackend(opencl.device["id"], "float32")


def _rounded(array):
    return np.asarray(array, dtype=np.float32).astype(np.float64)


@pytest.mark.parametrize("scale, offset", [(1.0, 0.0), (1e3, 1e6), (1e-3, 0.0), (1e10, -1e12),
                                           (1e-20, 1e-18)])
def test_float32_pieces_are_within_the_documented_bound(float32, method, mode, rng, scale,
                                                        offset):
    from rnsca.backends.opencl import FLOAT32_RELATIVE_BOUND

    window = Window(offset, offset, offset + scale, offset + 2 * scale)
    segs = np.concatenate([
        rng.uniform(-1.0, 3.0, size=(1500, 4)),
        rng.integers(-2, 5, size=(300, 4)) * 0.5,  # on edges and corners
    ]) * scale + offset
    options = SegmentOptions.resolve(window, method=method, mode=mode)
    out = float32.clip_segments(segs, window, options)
    pieces, source, stats = out.pieces, out.source, out.stats
    assert stats.device.precision == "float32"
    # The reference: the same input rounded to float32, clipped in float64 by Numba.
    ref = clip_segments(_rounded(segs), _rounded(window.bounds), method=method, mode=mode,
                        backend="numba")
    size = np.maximum(np.abs(segs).max(axis=1), np.abs(window.bounds).max())
    bound = FLOAT32_RELATIVE_BOUND * size
    common, mine, theirs = np.intersect1d(source, ref.source, return_indices=True)
    error = np.abs(pieces[mine] - ref.segments[theirs]).max(axis=1)
    assert (error <= bound[common]).all(), (error / bound[common]).max()
    # A piece only one of them has is a rounding sliver at a corner or an edge.
    for k in np.setdiff1d(source, common):
        p = pieces[np.flatnonzero(source == k)[0]]
        assert np.hypot(p[2] - p[0], p[3] - p[1]) <= bound[k]
    for k in np.setdiff1d(ref.source, common):
        p = ref.segments[np.flatnonzero(ref.source == k)[0]]
        assert np.hypot(p[2] - p[0], p[3] - p[1]) <= bound[k]
    # Never a point outside the window the caller gave.
    assert (pieces[:, 0::2] >= window.xmin).all() and (pieces[:, 0::2] <= window.xmax).all()
    assert (pieces[:, 1::2] >= window.ymin).all() and (pieces[:, 1::2] <= window.ymax).all()


def test_float32_refuses_coordinates_beyond_its_range(float32):
    segs = np.array([[0.0, 0.0, 1.0, 1.0], [-1e300, 5.0, 1e300, 5.0]])
    options = SegmentOptions.resolve(W)
    with pytest.raises(InvalidGeometryError, match="segment 1 does not fit float32") as info:
        float32.clip_segments(segs, W, options)
    assert info.value.row == 1
    # Coordinates that fit but whose difference does not.
    with pytest.raises(InvalidGeometryError, match="segment 0 does not fit float32"):
        float32.clip_segments(np.array([[-3e38, 0.0, 3e38, 0.0]]), W, options)


def test_float32_refuses_a_window_that_collapses(float32):
    window = Window(1e8, 0.0, 1e8 + 1.0, 1.0)  # 1e8 + 1 rounds to 1e8 in float32
    with pytest.raises(InvalidWindowError, match="empty or infinite in float32"):
        float32.clip_segments(np.array([[0.0, 0.5, 2e8, 0.5]]), window,
                              SegmentOptions.resolve(window))


def test_float32_gives_the_same_decisions_on_exact_inputs(float32):
    # Integers and halves are exact in float32: the same pieces, and in exact mode (which
    # decides at level 0 by outcodes) the same counters. Approx mode subdivides further
    # in float32: its rounding margins are wider.
    segs = np.array([[-5.0, 5.0, 15.0, 5.0], [1.0, 1.0, 2.0, 2.0], [20.0, 0.0, 30.0, 0.0],
                     [0.0, 0.0, 10.0, 20.0], [-1.0, 10.0, 11.0, 10.0]])
    for method in Method:
        for mode in Mode:
            options = SegmentOptions.resolve(W, method=method, mode=mode)
            out = float32.clip_segments(segs, W, options)
            pieces, source, stats = out.pieces, out.source, out.stats
            ref = clip_segments(segs, W, method=method, mode=mode, backend="numba")
            np.testing.assert_array_equal(source, ref.source)
            np.testing.assert_allclose(pieces, ref.segments, rtol=0, atol=2.0 ** -22 * 20)
            if mode is Mode.EXACT:
                assert stats == dataclasses.replace(ref.stats, device=stats.device)


def test_float32_lines_keep_the_input_vertices_and_cut_within_the_bound(
        opencl, rng, default_configuration):
    import shapely

    from rnsca.backends.opencl import FLOAT32_RELATIVE_BOUND
    from rnsca.ragged import clip_ragged

    walks = rng.normal(size=(4000, 2)).cumsum(axis=0) * 0.5 + 5.0
    lines = np.array([shapely.LineString(walks[i:i + 500]) for i in range(0, 4000, 500)],
                     dtype=object)
    triple = shapely.to_ragged_array(lines)
    window = (0.0, 0.0, 10.0, 10.0)
    ref = clip_ragged(*triple, window, backend="numba")
    registry.configure_opencl(opencl.device["id"], "float32")
    got = clip_ragged(*triple, window, backend="opencl")
    assert got.stats.device.precision == "float32"
    for a, b in zip(got.offsets, ref.offsets, strict=True):
        np.testing.assert_array_equal(a, b)
    size = max(np.abs(walks).max(), 10.0)
    np.testing.assert_allclose(got.coords, ref.coords, rtol=0,
                               atol=FLOAT32_RELATIVE_BOUND * size)
    # Vertices the clip did not cut are the float64 input vertices, bit for bit.
    inside = (ref.coords > 0.0).all(axis=1) & (ref.coords < 10.0).all(axis=1)
    np.testing.assert_array_equal(got.coords[inside], ref.coords[inside])
    assert (got.coords >= 0.0).all() and (got.coords <= 10.0).all()


def test_float32_lines_refuse_coordinates_beyond_its_range(opencl, default_configuration):
    from rnsca.ragged import clip_ragged

    registry.configure_opencl(opencl.device["id"], "float32")
    coords = np.array([[0.0, 0.0], [1.0, 1.0], [1e300, 1.0]])
    with pytest.raises(InvalidGeometryError, match="coordinate 2 does not fit float32"):
        clip_ragged("linestring", coords, (np.array([0, 3]),), W, backend="opencl")


def test_float32_polygons_are_valid_and_within_the_bound(opencl, rng, default_configuration):
    import shapely

    from rnsca.backends.opencl import FLOAT32_RELATIVE_BOUND

    polygons = []
    for _ in range(200):
        centre = rng.uniform(0.0, 10.0, 2)
        angles = np.sort(rng.uniform(0.0, 2 * np.pi, 40))
        r = rng.uniform(0.5, 3.0) * rng.uniform(0.5, 1.0, 40)
        polygons.append(shapely.Polygon(np.c_[centre[0] + r * np.cos(angles),
                                              centre[1] + r * np.sin(angles)]))
    polygons = np.array(polygons, dtype=object)
    window = (2.1, 2.3, 7.7, 7.9)  # bounds not representable in float32
    ref = rnsca.clip(polygons, window, backend="numba")
    registry.configure_opencl(opencl.device["id"], "float32")
    got = rnsca.clip(polygons, window, backend="opencl")
    assert shapely.is_valid(got).all()
    bound = FLOAT32_RELATIVE_BOUND * 14.0
    distance = shapely.hausdorff_distance(got, ref)
    both = ~shapely.is_empty(ref)
    assert (shapely.is_empty(got) == ~both).all()
    assert (distance[both] <= bound).all(), distance[both].max()
    xmin, ymin, xmax, ymax = shapely.bounds(got[both]).T
    assert (xmin >= 2.1).all() and (ymin >= 2.3).all() and (xmax <= 7.7).all() \
        and (ymax <= 7.9).all()


# --- curves --------------------------------------------------------------------------------

CURVES = ["M-5 5 C0 10 10 10 15 5 Q 20 -20 3 3 L 4 4 C 5 5 6 6 7 8 Z",
          "M1 1 Q 5 9 9 1 Z M 3 3 L 4 4", "M 2 2 C 3 9 7 9 8 2"]


def test_curves_run_on_the_device_and_count_their_transfers(opencl):
    paths = rnsca.parse_paths(CURVES)
    moved_up = paths.controls.nbytes + paths.degree.nbytes
    d, stats = rnsca.clip_svg(CURVES, (0, 0, 10, 10), curves="preserve", backend="opencl")
    assert d == rnsca.clip_svg(CURVES, (0, 0, 10, 10), curves="preserve")[0]
    # Up: the controls, degrees, and the one run's first and end segments (the first
    # path's 5 segments; the others have one per subpath); down: one class per segment
    # and the run's decision (nothing is flattened).
    assert (stats.device.transfers, stats.device.bytes_to_device,
            stats.device.bytes_from_device) == (6, moved_up + 16, paths.degree.shape[0] + 1)
    assert stats.device.device == opencl.name and stats.device.precision == "float64"
    d, stats = rnsca.clip_svg(CURVES, (0, 0, 10, 10), curves="flatten", backend="opencl")
    assert d == rnsca.clip_svg(CURVES, (0, 0, 10, 10), curves="flatten")[0]
    # Flatten: also the points' prefix sum and the points of the accepted curves (the
    # last cubic and the quadratic lie inside; their points make lines of the output).
    assert stats.device.transfers == 8
    assert stats.device.bytes_from_device > paths.degree.shape[0] + 8 * paths.degree.shape[0]


def test_the_device_classes_and_points_are_the_numba_kernels(opencl):
    from rnsca.kernels import bezier as BZ

    paths = rnsca.parse_paths(CURVES)
    window = Window(0.0, 0.0, 10.0, 10.0)
    classes, runs, point_start, points, _ = opencl.classify_curves(
        paths.controls, paths.degree, window, 0.01, "accepted")
    assert runs.shape == (0,)  # no subpaths given: no runs
    # Segments: the cubic crossing the left and right edges, the quadratic below, the
    # lines and curves inside; the closing lines are not segments.
    assert classes.tolist() == [BZ.SEGMENT_AMBIGUOUS, BZ.SEGMENT_AMBIGUOUS,
                                BZ.SEGMENT_ACCEPTED, BZ.SEGMENT_ACCEPTED,
                                BZ.SEGMENT_ACCEPTED, BZ.SEGMENT_ACCEPTED,
                                BZ.SEGMENT_ACCEPTED]
    steps = BZ.flatten_steps(paths.controls, paths.degree, 0.01)
    curve = (paths.degree > 1) & (classes == BZ.SEGMENT_ACCEPTED)
    np.testing.assert_array_equal(np.diff(point_start), np.where(curve, steps, 0))
    assert points.shape == (point_start[-1], 2)
    none = opencl.classify_curves(paths.controls, paths.degree, window, 0.01, "none")
    np.testing.assert_array_equal(none[0], classes)
    assert none[2].tolist() == [0] * 8 and none[3].shape == (0, 2)


def test_no_segments_move_nothing(opencl):
    empty = rnsca.parse_paths(["", "M 1 1"])
    classes, runs, point_start, points, device = opencl.classify_curves(
        empty.controls, empty.degree, Window(0, 0, 1, 1), 0.1, "all", empty.subpath_offsets)
    assert classes.shape == runs.shape == (0,)
    assert point_start.tolist() == [0] and points.shape == (0, 2)
    assert device.transfers == 0
    assert rnsca.clip_svg(["", "M 1 1"], (0, 0, 2, 2), backend="opencl")[0] == ["", "M1 1"]


@pytest.mark.parametrize("curves", ["preserve", "flatten"])
@pytest.mark.parametrize("mode", ["exact", "approx"])
@pytest.mark.parametrize("fill", [None, "nonzero"])
def test_curves_in_float32_give_the_float64_output_exactly(opencl, default_configuration,
                                                           curves, mode, fill):
    window = (0.1, 0.2, 9.7, 9.9)  # bounds between float32 values
    ref = rnsca.clip_paths(rnsca.parse_paths(CURVES), window, curves=curves, mode=mode,
                           fill=fill, backend="numba")
    registry.configure_opencl(opencl.device["id"], "float32")
    got = rnsca.clip_paths(rnsca.parse_paths(CURVES), window, curves=curves, mode=mode,
                           fill=fill, backend="opencl")
    for name in ("controls", "degree", "start", "subpath_offsets", "closed", "path_offsets"):
        np.testing.assert_array_equal(getattr(got.paths, name), getattr(ref.paths, name))
    assert dataclasses.replace(got.stats, device=None) == ref.stats
    assert got.stats.device.precision == "float32"
    paths = rnsca.parse_paths(CURVES)
    for got_part, ref_part in zip(rnsca.flatten_paths(paths, 0.01, backend="opencl"),
                                  rnsca.flatten_paths(paths, 0.01), strict=True):
        np.testing.assert_array_equal(got_part, ref_part)


def _edge_values(bound: float) -> list[float]:
    """Values around `bound` where float32 rounding could flip a comparison with it."""
    with np.errstate(over="ignore"):  # beyond float32's range: ±inf, left out below
        b32 = np.float32(bound)
    values = [bound, np.nextafter(bound, np.inf), np.nextafter(bound, -np.inf), float(b32),
              float(np.nextafter(b32, np.float32(np.inf))),
              float(np.nextafter(b32, np.float32(-np.inf))), (bound + float(b32)) / 2]
    return [float(v) for v in values if np.isfinite(v)]


def _float64_classes(controls, degree, bounds):
    """Each segment's class by its control points' outcodes, in float64, one by one."""
    from rnsca.kernels import bezier as BZ
    from rnsca.kernels.outcode import outcode

    classes = []
    for points, d in zip(controls, degree, strict=True):
        codes = [outcode(float(x), float(y), *bounds) for x, y in points[[0, 1, 2, 3][:d + 1]]
                 ] + [outcode(float(points[3, 0]), float(points[3, 1]), *bounds)]
        c_or = c_and = codes[0]
        for code in codes[1:]:
            c_or |= code
            c_and &= code
        classes.append(BZ.SEGMENT_ACCEPTED if c_or == 0 else
                       BZ.SEGMENT_REJECTED if c_and else BZ.SEGMENT_AMBIGUOUS)
    return np.array(classes)


# Windows whose edges lie between float32 values, at 0 (subnormals around it, which a
# device may flush to zero), subnormal themselves, and beyond float32's range.
EDGE_WINDOWS = [(0.1, 0.2, 0.7, 0.9), (1e8 + 0.3, -1e-7, 1e8 + 7.1, 3e-7),
                (0.0, -1e-40, 1e-39, 0.0), (-1e-300, 1e-310, 1e-300, 1e-30),
                (-1e39, 1e38, 3.5e38, 1e39)]


@pytest.mark.parametrize("bounds", EDGE_WINDOWS)
@pytest.mark.parametrize("denormals", ["kept", "flushed"])
def test_float32_device_classes_are_only_the_sure_ones(opencl, opencl_module, monkeypatch,
                                                       bounds, denormals, rng):
    from rnsca.kernels import bezier as BZ

    if denormals == "flushed":
        # A device that flushes subnormals to zero (many GPUs in float32), as far as the
        # driver honours the option (Intel's CPU runtime does).
        build = opencl_module._build_program
        monkeypatch.setattr(opencl_module, "_build_program",
                            lambda context, name, source, options: build(
                                context, name, source, [*options, "-cl-denorms-are-zero"]))
        monkeypatch.setattr(opencl_module._device(opencl.device), "programs", {})

    # Values at the edges, around 0, in the middle and well beyond each edge.
    xs, ys = ([*_edge_values(lo), *_edge_values(hi), 0.0, -0.0, 1e-45, -1e-45, (lo + hi) / 2,
               lo - 1.0 - abs(lo), hi + 1.0 + abs(hi)]
              for lo, hi in (bounds[0::2], bounds[1::2]))
    parts = []
    for _ in range(400):
        degree = int(rng.integers(1, 4))
        # One edge's values (or two edges', or every edge's) for each coordinate.
        pts = [(float(rng.choice(xs)), float(rng.choice(ys))) for _ in range(degree + 1)]
        parts.append(f"M{pts[0][0]!r} {pts[0][1]!r} " + "LQC"[degree - 1]
                     + " ".join(f"{x!r} {y!r}" for x, y in pts[1:]))
    paths = rnsca.parse_paths(parts)
    seen = {}
    from rnsca.backends.opencl import curves

    decide = curves.decide_ambiguous

    def record(classes, run_class, *args):
        seen["device"] = classes.copy()
        decide(classes, run_class, *args)

    monkeypatch.setattr(curves, "decide_ambiguous", record)
    float32 = opencl_module.OpenCLBackend(opencl.device["id"], "float32")
    window = Window(*bounds)
    classes, *_ = float32.classify_curves(paths.controls, paths.degree, window, 0.01, "none")
    exact = _float64_classes(paths.controls, paths.degree, bounds)
    device = seen["device"]
    sure = device != BZ.SEGMENT_AMBIGUOUS
    # What the device decided is right; it decided some; the host decided the rest.
    np.testing.assert_array_equal(device[sure], exact[sure])
    assert sure.any()
    np.testing.assert_array_equal(classes, exact)
    ref = rnsca.clip_paths(paths, window, backend="numba")
    registry.configure_opencl(opencl.device["id"], "float32")
    try:
        got = rnsca.clip_paths(paths, window, backend="opencl")
    finally:
        registry.configure_opencl()
    np.testing.assert_array_equal(got.paths.controls, ref.paths.controls)
    assert dataclasses.replace(got.stats, device=None) == ref.stats


def test_float32_curves_beyond_its_range_clip_as_in_float64(opencl, default_configuration):
    # Beyond float32's range a coordinate rounds to ±inf on the device: still ordered,
    # so its segment is only ambiguous (decided on the host) instead of an error.
    d = ["M -1e300 5 C 0 1e300 5 3 5 5 L 1e39 5 Q 5 -3e38 2 2 Z", "M 1 1 L 2 2"]
    registry.configure_opencl(opencl.device["id"], "float32")
    for window in [(0.0, 0.0, 10.0, 10.0), (-1e39, -1e39, 1e39, 1e39)]:
        for curves in ("preserve", "flatten"):
            got, stats = rnsca.clip_svg(d, window, curves=curves, backend="opencl")
            assert got == rnsca.clip_svg(d, window, curves=curves, backend="numba")[0]
            assert stats.device.precision == "float32"


def test_runs_of_sixteen_segments_are_decided_on_the_device(opencl):
    from rnsca.kernels import bezier as BZ

    inside = " ".join(f"L {1 + i % 2} {1 + i / 10}" for i in range(20))  # 0..19 inside
    outside = " ".join(f"Q {-5 - i % 2} {i} {-6} {i + 0.5}" for i in range(28))  # 21..48 left
    paths = rnsca.parse_paths([f"M 1 1 {inside} L -5 0 {outside} L 3 3"])
    window = Window(0.0, 0.0, 10.0, 10.0)
    for flatten, accepted in (("none", BZ._RUN_ACCEPTED), ("accepted", BZ._RUN_SEGMENTED)):
        _, runs, _, _, _ = opencl.classify_curves(paths.controls, paths.degree, window, 0.01,
                                                  flatten, paths.subpath_offsets)
        # Runs start at segments 0, 16, 32 and 48 (of 50); flattening accepts no run.
        expected = np.zeros(50, dtype=np.int8)
        expected[[0, 16, 32, 48]] = [accepted, BZ._RUN_SEGMENTED, BZ._RUN_REJECTED,
                                     BZ._RUN_SEGMENTED]
        assert runs.tolist() == expected.tolist()


def test_svg_documents_clip_on_the_device_from_the_command_line(opencl, tmp_path):
    from typer.testing import CliRunner

    from rnsca.cli import app

    drawing = tmp_path / "drawing.svg"
    drawing.write_text('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10">'
                       '<path d="M-5 5 C0 10 10 10 15 5 Q 20 -20 3 3 Z" fill="red"/>'
                       '<circle cx="5" cy="5" r="7" fill="none" stroke="black"/></svg>')
    runner = CliRunner()
    results = {backend: runner.invoke(app, ["clip", str(drawing), "--window", "0,0,10,10",
                                            "--curves", "flatten", "--backend", backend])
               for backend in ("numba", "opencl")}
    for result in results.values():
        assert result.exit_code == 0, result.output
    assert results["opencl"].stdout == results["numba"].stdout
    device = json.loads(results["opencl"].stderr.strip().splitlines()[-1])["stats"]["device"]
    assert device["device"] == opencl.name and device["transfers"] > 0
