"""clip_svg and clip_paths: literal behaviour cases (issue 4)."""

import numpy as np
import pytest

import rnsca
from rnsca import InvalidOptionError, ParseError, clip_paths, clip_svg, parse_paths

W = (0, 0, 10, 10)


def clipped(d, **options):
    return clip_svg(d, W, precision=6, **options)[0]


@pytest.mark.parametrize("d, expected", [
    ("M-5 5 L15 5", "M0 5H10"),
    ("M-5 5 Q5 15 15 5", "M0 8.75Q5 11.25 10 8.75"),
    ("M-5 5 C0 10 10 10 15 5", "M0 7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398"),
    ("M20 20 L30 30", ""),
    ("M-5 -5 L5 5 15 -5", "M0 0 5 5 10 0"),
    ("M5 5", "M5 5"),          # a lone moveto in the window: a dot for round caps
    ("M50 5", ""),
    ("", ""),
])
def test_strokes_keep_the_visible_parts_with_their_degree(d, expected):
    assert clipped(d) == expected


def test_a_stroke_that_leaves_and_returns_gives_separate_subpaths():
    assert clipped("M-5 2 L5 2 L5 20 L8 20 L8 5 L15 5") == "M0 2H5V10M8 10V5H10"


def test_a_closed_stroke_visible_whole_stays_closed():
    assert clipped("M2 2 h6 v5 h-6 z") == "M2 2H8V7H2Z"


def test_a_closed_stroke_cut_is_joined_at_its_start():
    # The rectangle leaves through the right edge: one open piece, starting where the
    # outline re-enters, running through the original start point.
    assert clipped("M2 2 h20 v5 h-20 z") == "M10 7H2V2H10"
    assert clipped("M5 5 L20 5 L20 8 L5 8 Z") == "M10 8H5V5H10"


def test_subpaths_outside_leave_nothing():
    assert clipped("M2 2 L8 2 L8 8 Z M20 20 L30 20 L30 30 Z") == "M2 2H8V8Z"


@pytest.mark.parametrize("fill", ["nonzero", "evenodd"])
def test_fill_closes_the_visible_part_along_the_window_edge(fill):
    # Clean (the default): the ring starts with the visible curve; Z draws the last line.
    # Nonzero keeps the outline's direction (the winding numbers); evenodd turns every
    # ring with the painted side on its left (counter-clockwise, y up): here backwards.
    expected = ("M0 7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398V5H0Z"
                if fill == "nonzero" else
                "M10 7.97398C6.82356 9.00867 3.17644 9.00867 0 7.97398V5H10Z")
    assert clipped("M-5 5 C0 10 10 10 15 5", fill=fill) == expected
    # Raw: the clamped subpath, from the clamped start, closed by a drawn line.
    assert clipped("M-5 5 C0 10 10 10 15 5", fill=fill, fill_output="raw") == \
        "M0 5V7.97398C3.17644 9.00867 6.82356 9.00867 10 7.97398V5H0Z"


def test_fill_of_a_shape_around_the_window_is_the_window():
    assert clipped("M-20 -20 h50 v50 h-50 z", fill="nonzero") == "M0 0H10V10H0Z"
    assert clipped("M-20 -20 h50 v50 h-50 z", fill="evenodd") == "M0 0H10V10H0Z"
    assert clipped("M-20 -20 h50 v50 h-50 z", fill="nonzero", fill_output="raw") == \
        "M0 0H10V10H0V0Z"
    assert clipped("M-20 -20 h50 v50 h-50 z") == ""  # its outline is not in the window


@pytest.mark.parametrize("fill", ["nonzero", "evenodd"])
def test_fill_of_a_ring_whose_hole_holds_the_window_paints_nothing(fill):
    out = parse_paths([clipped("M-20 -20 h50 v50 h-50 z M-10 -10 v30 h30 v-30 z",
                               fill=fill)])
    from tests.curve_checks import signed_area
    assert signed_area(out) == 0.0


def test_fill_inside_the_window_is_the_shape_closed():
    assert clipped("M2 2 h6 v5 h-6 z", fill="nonzero") == "M2 2H8V7H2Z"
    assert clipped("M2 2 h6 v5 h-6 z", fill="nonzero", fill_output="raw") == "M2 2H8V7H2V2Z"


def test_fill_of_a_shape_beside_the_window_is_dropped():
    assert clipped("M20 2 h6 v5 h-6 z", fill="nonzero") == ""
    assert clipped("M-20 2 h6 v50 h-6 z", fill="nonzero") == ""


def test_approx_mode_computes_no_crossing_and_stays_inside():
    out, stats = clip_svg("M-5 5 C0 10 10 10 15 5", W, mode="approx")
    assert stats.intersections == 0
    assert stats.dropped > 0
    p = parse_paths([out])
    assert (p.controls >= 0).all() and (p.controls <= 10).all()


def test_flatten_mode_gives_lines_within_the_tolerance():
    out = clip_svg("M-5 5 C0 10 10 10 15 5", W, curves="flatten", tolerance=0.01)[0]
    p = parse_paths([out])
    assert set(p.degree.tolist()) == {1}
    assert p.controls[0, 0, 0] == 0.0 and p.controls[-1, 3, 0] == 10.0


def test_many_paths_at_once_keep_their_order():
    out, stats = clip_svg(["M-5 5 L15 5", "M20 20 L30 30", "M1 1 L2 2"], W, precision=6)
    assert out == ["M0 5H10", "", "M1 1 2 2"]
    assert stats.geometries_in == 3 and stats.geometries_out == 2
    assert clip_svg([], W)[0] == []


def test_stats_count_segments_and_decisions():
    stats = clip_svg("M-5 5 L15 5 M1 1 L2 2 M20 20 L30 30", W)[1]
    assert stats.segments_in == 3
    assert stats.pieces_out == 2
    assert stats.accepted == 1 and stats.rejected == 1 and stats.clipped == 1
    assert (stats.accepted + stats.rejected + stats.subdivided + stats.clipped
            + stats.dropped) == stats.fragments_evaluated


def test_a_curve_tangent_to_an_edge_from_outside_gives_nothing():
    # y(t) peaks at exactly 10 at t = 1/2, from above: it touches the top edge only.
    assert clipped("M2 15 Q5 5 8 15") == ""


def test_a_curve_along_an_edge_is_kept():
    assert clipped("M-5 10 C2 10 4 10 15 10") == "M0 10C2.89675 10 5.46779 10 10 10"


def test_quadratics_stay_quadratics_and_cubics_cubics():
    result = clip_paths(parse_paths(["M-5 5 Q5 15 15 5 C20 0 0 -5 5 5"]), W)
    assert result.paths.degree.tolist() == [2, 3]


@pytest.mark.parametrize("options, message", [
    ({"curves": "bezier"}, "curves must be one of"),
    ({"fill": "winding"}, "fill must be"),
    ({"fill": "nonzero", "fill_output": "tidy"}, "fill_output must be one of 'clean', 'raw'"),
    ({"method": "liang_barsky"}, "method='rnsca' only"),
    ({"n": 1}, "n must be"),
    ({"max_depth": 40}, "max_depth"),
    ({"tolerance": 0}, "tolerance must be"),
    ({"tolerance": float("nan")}, "tolerance must be"),
    ({"mode": "fast"}, "mode must be one of"),
])
def test_bad_options_are_named(options, message):
    with pytest.raises(InvalidOptionError, match=message):
        clip_svg("M0 0 L1 1", W, **options)


def test_bad_path_data_names_the_position():
    with pytest.raises(ParseError, match="position 8"):
        clip_svg("M0 0 L1 x", W)
    with pytest.raises(ParseError, match="path 1"):
        clip_svg(["M0 0", "L1 1"], W)


def test_bad_windows_and_inputs_are_refused():
    with pytest.raises(ValueError):
        clip_svg("M0 0 L1 1", (0, 0, 0, 10))
    with pytest.raises(TypeError):
        clip_svg(42, W)


def test_a_joined_closed_stroke_drops_the_freed_entry():
    result = clip_paths(parse_paths(["M2 2 h20 v5 h-20 z"]), W)
    assert result.paths.closed.tolist() == [False]
    assert np.diff(result.paths.subpath_offsets).tolist() == [3]


def test_the_public_names_are_exported():
    for name in ("clip_svg", "clip_paths", "flatten_paths", "PathArrays", "parse_path",
                 "write_path", "Curves", "Fill", "clip_svg_document"):
        assert hasattr(rnsca, name)


@pytest.mark.parametrize("fill", ["nonzero", "evenodd"])
def test_a_boundary_run_that_grows_then_vanishes_is_not_written(fill):
    # The run along the bottom edge goes (2,0) -> (3,0), grows to (1,0), then comes back
    # to (2,0) and is dropped: the write pass must not write past the counted output.
    raw = {"fill": fill, "fill_output": "raw"}
    assert clipped("M2 -1L1 1L3 -1L1 -1Z", **raw) == "M2 0H1.5L1 1 2 0Z"
    assert clip_svg("M2 -1L1 1L3 -1L1 -1Z", W, curves="flatten", precision=6,
                    **raw)[0] == "M2 0H1.5L1 1 2 0Z"
    # Clean: the run along the edge is the one line from (2, 0) back to (1.5, 0), drawn
    # by Z (nonzero keeps the outline's turning; evenodd turns rings counter-clockwise).
    expected = "M1.5 0 1 1 2 0Z" if fill == "nonzero" else "M2 0 1 1 1.5 0Z"
    assert clipped("M2 -1L1 1L3 -1L1 -1Z", fill=fill) == expected
    assert clip_svg("M2 -1L1 1L3 -1L1 -1Z", W, fill=fill, curves="flatten",
                    precision=6)[0] == expected


def test_a_closed_subpath_visible_whole_with_an_implicit_closing_line():
    assert clipped("M0 0L1 0L1 1Z") == "M0 0H1V1Z"


def _blobs(rng, n):
    """Return closed cubic outlines of 3 to 9 segments scattered around W."""
    paths = []
    for _ in range(n):
        k = int(rng.integers(3, 10))
        knots = rng.uniform(-8, 18, 2) + rng.uniform(-6, 6, (k, 2))
        pts = [f"M{knots[0, 0]:.3f} {knots[0, 1]:.3f}"]
        for j in range(k):
            a, b = knots[j], knots[(j + 1) % k]
            c1, c2 = a + rng.uniform(-4, 4, 2), b + rng.uniform(-4, 4, 2)
            pts.append(f"C{c1[0]:.3f} {c1[1]:.3f} {c2[0]:.3f} {c2[1]:.3f} {b[0]:.3f} {b[1]:.3f}")
        paths.append(" ".join(pts) + ("Z" if rng.random() < 0.5 else ""))
    return parse_paths(paths)


@pytest.mark.parametrize("options", [{}, {"fill": "nonzero"}, {"fill": "evenodd"},
                                     {"fill": "nonzero", "fill_output": "raw"},
                                     {"fill": "evenodd", "mode": "approx"},
                                     {"curves": "flatten", "tolerance": 1e-3},
                                     {"mode": "approx"}, {"max_depth": 3}])
def test_the_output_keeps_the_path_layout(options):
    # clip_paths builds its output unchecked (PathArrays.from_kernel): the constructor's
    # checks (continuity, unused rows, offsets, finiteness) must all pass on it.
    out = clip_paths(_blobs(np.random.default_rng(7), 300), W, **options).paths
    assert out.degree.shape[0] > 100
    checked = rnsca.PathArrays(controls=out.controls, degree=out.degree,
                               subpath_offsets=out.subpath_offsets, closed=out.closed,
                               start=out.start, path_offsets=out.path_offsets)
    assert checked == out
    assert out.controls.dtype == np.float64 and out.degree.dtype == np.int8
    assert out.subpath_offsets.dtype == np.int64 and out.path_offsets.dtype == np.int64
    assert out.closed.dtype == np.bool_ and out.start.dtype == np.float64


def test_flatten_paths_names_the_backends_it_runs_on():
    paths = parse_paths(["M0 0 Q 5 9 9 1"])
    with pytest.raises(InvalidOptionError, match="'numba', 'opencl'.*'numpy'"):
        rnsca.flatten_paths(paths, 0.1, backend="numpy")
    with pytest.raises(InvalidOptionError, match="'numba', 'opencl'.*'numpy'"):
        clip_paths(paths, (0, 0, 1, 1), backend="numpy")


def test_flattening_into_more_points_than_the_limit_is_a_clear_error_not_memory_error():
    from rnsca.backends.numba_cpu import MAX_FLATTENED_POINTS
    from rnsca.clip_svg import flatten_paths
    from rnsca.errors import LimitExceededError
    from rnsca.kernels.bezier import flatten_steps

    curve = parse_paths(["M0 0C 0 1e6 1e6 -1e6 1e6 0"])
    per_curve = int(flatten_steps(curve.controls, curve.degree, 1e-9)[0])
    copies = MAX_FLATTENED_POINTS // per_curve + 1  # just past the limit
    with pytest.raises(LimitExceededError, match="more than the limit"):
        flatten_paths(parse_paths(["M0 0C 0 1e6 1e6 -1e6 1e6 0"] * copies), 1e-9)
    assert len(flatten_paths(curve, 1e-9).coords) == per_curve + 1  # one curve is fine
