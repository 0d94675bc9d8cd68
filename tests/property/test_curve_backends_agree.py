"""Bézier paths on OpenCL give what the Numba backend gives: the same paths, coordinates
equal to 1e-12 relative in float64, the same counters, and the same flattened polylines;
on a float32 device (forced here on any device) exactly the same coordinates too.

On OpenCL each segment is classified by the outcodes of its control points, and in
flatten mode the curves accepted whole are flattened, on the device (`classify_bezier`,
a prefix sum, `flatten_bezier`); the runs, the ambiguous segments and the output are
done on the host by the Numba kernel from the device's decisions. Inputs: the
adversarial paths of the curve tests (loops, cusps, tangents to an edge, curves along an
edge, control points far outside) at scales from 2**-40 to 2**40, several per call,
open and closed, as strokes and fills; long random paths whose runs are pruned; glyph
outlines (TrueType quadratics, CFF cubics). In float32 the device's classes are only
the sure ones (the host decides the rest and flattens from the float64 input), so the
scales and the windows' edges between float32 values are what it must get right.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, note, settings
from hypothesis import strategies as st

from rnsca import PathArrays, clip_paths, parse_paths
from rnsca.backends import registry
from rnsca.clip_svg import flatten_paths
from tests.fonts import load_glyph, require_font
from tests.property.test_curves_vs_shapely import paths, scales, to_d

pytestmark = pytest.mark.opencl


@pytest.fixture(scope="module", params=["float64", "float32"])
def precision(request, opencl):
    """The OpenCL backend in float64 (where the device has it: else skipped) or float32."""
    if request.param == "float64" and not opencl.device["fp64"]:
        pytest.skip(f"the device {opencl.name!r} has no float64")
    registry.configure_opencl(opencl.device["id"], request.param)
    yield request.param
    registry.configure_opencl()

# The curve tests' window, one holding every drawn point (all accepted), a thin one.
WINDOWS = [(0.0, 0.0, 10.0, 10.0), (-600.0, -600.0, 600.0, 600.0), (2.0, 3.0, 4.0, 9.0)]


def assert_paths_equal(got: PathArrays, ref: PathArrays, where: str, precision: str) -> None:
    for name in ("degree", "subpath_offsets", "closed", "path_offsets"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name),
                                      err_msg=f"{name}: {where}")
    for name in ("controls", "start"):
        if precision == "float32":  # every output coordinate is the host's, in float64
            np.testing.assert_array_equal(getattr(got, name), getattr(ref, name),
                                          err_msg=f"{name}: {where}")
        else:
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-12,
                                       atol=0, err_msg=f"{name}: {where}")


def assert_curves_agree(source: PathArrays, window, precision: str, **options) -> None:
    """The clip of `source` is the same on Numba and OpenCL, counters included."""
    where = f"{options} window={window}"
    ref = clip_paths(source, window, backend="numba", **options)
    got = clip_paths(source, window, backend="opencl", **options)
    assert_paths_equal(got.paths, ref.paths, where, precision)
    # Every counter: in float32 the host decides what the device left open, exactly.
    assert dataclasses.replace(got.stats, device=None) == ref.stats, where
    assert ref.stats.device is None
    assert got.stats.device is not None and got.stats.device.precision == precision
    # The controls, degrees and runs (first and end segments) go to the device; the
    # classes, run decisions (and in float64 points) come back.
    offsets = source.subpath_offsets
    n_runs = sum(min(a + 16, last) - a >= 2
                 for first, last in zip(offsets[:-1], offsets[1:], strict=True)
                 for a in range(first, last, 16))
    controls = source.controls.nbytes // (2 if precision == "float32" else 1)
    assert got.stats.device.bytes_to_device == controls + source.degree.nbytes + 16 * n_runs
    assert got.stats.device.bytes_from_device >= source.degree.shape[0]


def assert_flattening_agrees(source: PathArrays, tolerance: float, close: bool,
                             precision: str) -> None:
    ref = flatten_paths(source, tolerance, close=close)
    got = flatten_paths(source, tolerance, close=close, backend="opencl")
    np.testing.assert_array_equal(got[1], ref[1])  # the same counts
    np.testing.assert_array_equal(got[2], ref[2])
    if precision == "float32":  # flattened on the host, in float64
        np.testing.assert_array_equal(got[0], ref[0])
    else:
        np.testing.assert_allclose(got[0], ref[0], rtol=1e-12, atol=0)


options = st.fixed_dictionaries({
    "curves": st.sampled_from(["flatten", "preserve"]),
    "fill": st.sampled_from([None, "nonzero", "evenodd"]),
    "mode": st.sampled_from(["exact", "approx"]),
    "n": st.sampled_from(["auto", 2, 3]),
    "max_depth": st.sampled_from([None, 0, 4]),
})


@settings(max_examples=60, deadline=None)
@given(drawn=st.lists(paths(), min_size=1, max_size=4), scale=scales, chosen=options,
       base=st.sampled_from(WINDOWS))
def test_drawn_paths_clip_the_same(precision, drawn, scale, chosen, base):
    d = [to_d(*path, scale) for path in drawn]
    note(f"d={d!r}")
    window = tuple(v * scale for v in base)
    assert_curves_agree(parse_paths(d), window, precision, tolerance=1e-3 * 10.0 * scale,
                        **chosen)


@settings(max_examples=40, deadline=None)
@given(drawn=st.lists(paths(), min_size=1, max_size=4), scale=scales,
       relative=st.sampled_from([1e-1, 1e-3, 1e-6]), close=st.booleans())
def test_drawn_paths_flatten_the_same(precision, drawn, scale, relative, close):
    d = [to_d(*path, scale) for path in drawn]
    note(f"d={d!r}")
    assert_flattening_agrees(parse_paths(d), relative * 10.0 * scale, close, precision)


def _random_path(rng, segments: int) -> str:
    """A long random walk of lines, quadratics and cubics: runs that prune."""
    here = rng.normal(size=2) * 5 + 5
    parts = [f"M{float(here[0])!r} {float(here[1])!r}"]
    for _ in range(segments):
        degree = int(rng.integers(1, 4))
        pts = here + np.cumsum(rng.normal(size=(degree, 2)), axis=0)
        parts.append("LQC"[degree - 1] + " ".join(f"{float(x)!r} {float(y)!r}" for x, y in pts))
        here = pts[-1]
    return " ".join(parts) + (" Z" if rng.random() < 0.5 else "")


@pytest.mark.parametrize("curves", ["flatten", "preserve"])
@pytest.mark.parametrize("fill", [None, "nonzero", "evenodd"])
def test_long_random_paths_clip_the_same(precision, rng, curves, fill):
    source = parse_paths([_random_path(rng, 300) for _ in range(20)])
    for window in [(0.0, 0.0, 10.0, 10.0), (-20.0, -20.0, 30.0, 30.0), (4.0, 4.5, 4.2, 7.0)]:
        assert_curves_agree(source, window, precision, curves=curves, fill=fill,
                            tolerance=1e-4)
    assert_flattening_agrees(source, 1e-4, fill is not None, precision)


@pytest.mark.parametrize("font, degree", [("dejavu-sans", 2), ("nimbus-roman", 3)])
def test_glyph_outlines_clip_the_same(precision, font, degree):
    require_font(font)
    glyphs = [load_glyph(font, char) for char in "gR@&"]
    source = parse_paths([g.d for g in glyphs])
    assert degree in set(source.degree.tolist())
    x0, y0, x1, y1 = glyphs[0].bounds
    w, h = x1 - x0, y1 - y0
    for window in [(x0 + 0.3 * w, y0 + 0.2 * h, x0 + 0.8 * w, y0 + 0.6 * h),
                   (x0 - w, y0 - h, x1 + w, y1 + h)]:
        for curves in ("flatten", "preserve"):
            for fill in (None, "nonzero", "evenodd"):
                assert_curves_agree(source, window, precision, curves=curves, fill=fill,
                                    tolerance=1e-3 * w)
        # Clean fills (the default above) are built on the host from the clip; raw too.
        assert_curves_agree(source, window, precision, fill="nonzero", fill_output="raw",
                            tolerance=1e-3 * w)
    assert_flattening_agrees(source, 1e-3 * w, True, precision)


@pytest.mark.parametrize("curves", ["flatten", "preserve"])
@pytest.mark.parametrize("fill", [None, "nonzero"])
def test_paths_in_ranges_clip_the_same(precision, rng, curves, fill, monkeypatch):
    """A call cut into many ranges of subpaths (the host counts one while the device
    classifies the next): the same output and counters as one range."""
    from rnsca.backends import opencl as module
    from rnsca.backends.opencl import curves as C

    finished = []
    finish = C.CurveCall.finish
    monkeypatch.setattr(module, "PIPELINE_SEGMENTS", 50)
    monkeypatch.setattr(C.CurveCall, "finish",
                        lambda call, r: finished.append(r) or finish(call, r))
    source = parse_paths([_random_path(rng, int(rng.integers(1, 120))) for _ in range(30)])
    for window in [(0.0, 0.0, 10.0, 10.0), (-20.0, -20.0, 30.0, 30.0)]:
        assert_curves_agree(source, window, precision, curves=curves, fill=fill,
                            tolerance=1e-4)
    assert len(finished) > 2 * 2  # several ranges per call
    # Many windows: ranges within each window's stretch of paths.
    windows = np.array([[0.0, 0.0, 10.0, 10.0], [-20.0, -20.0, 30.0, 30.0],
                        [4.0, 4.5, 4.2, 7.0]])
    ref = clip_paths(source, windows=windows, backend="numba", curves=curves, fill=fill,
                     tolerance=1e-4)
    got = clip_paths(source, windows=windows, backend="opencl", curves=curves, fill=fill,
                     tolerance=1e-4)
    assert_paths_equal(got.paths, ref.paths, "many windows", precision)
