"""verify's oracle for lines, Shapely's clip of each segment, against two others.

`rnsca.verify` asks GEOS for the intersection of each segment with the window instead of
the whole line's (whose overlay nodes a line against itself: quadratic for one that
crosses itself often). The two are the same point set, so a clip that either oracle
accepts the other must accept too. Checked on drawn lines and windows
(`tests.property.geometry_strategies`): Shapely's clip of the whole line, for lines that
never meet themselves (x strictly increasing; simple once mapped) where GEOS is accurate
(`tests.geometry_checks.shapely_can_judge`), and the clip in exact rational arithmetic
(`tests.geometry_checks.exact_line_clip`, without its pieces of no length: a line of one
repeated point has no lineal part), for any drawn line, must both pass with the deviation
within the exact promise and the same length.
"""

import math

import shapely
from hypothesis import assume, given
from hypothesis import strategies as st

import rnsca
from tests.geometry_checks import (
    TOLERANCE,
    exact_line_clip,
    parts_of_dimension,
    shapely_can_judge,
)
from tests.property.geometry_strategies import frames, lines, monotone_lines, window_for


def _assert_accepted(line, clipped, window):
    v = rnsca.verify(line, clipped, window)
    assert v.passed, (line.wkt, window, clipped.wkt, v)
    assert v.max_deviation <= TOLERANCE * rnsca.Window.of(window).size
    assert math.isclose(v.ratio, 1.0, rel_tol=1e-9) or (
        shapely.length(clipped) == 0.0 and v.ratio == 1.0), (line.wkt, window, v)


@given(data=st.data())
def test_shapely_clip_of_a_whole_simple_line_passes(data):
    frame = data.draw(frames())
    relative = data.draw(monotone_lines(frame))
    window = data.draw(window_for(frame, [relative]))
    line = frame.geometry(relative)
    # Mapped to a float frame, nearly equal x may round to equal ones (and a line run
    # back over itself, whose overlap the whole line's overlay counts once).
    assume(shapely.is_simple(line) and shapely_can_judge([line], window, "closed"))
    box = shapely.box(*rnsca.Window.of(window).bounds)
    _assert_accepted(line, parts_of_dimension(shapely.intersection(line, box), 1), window)


@given(data=st.data())
def test_exact_clip_of_any_line_passes(data):
    frame = data.draw(frames())
    relative = data.draw(lines(frame))
    window = data.draw(window_for(frame, [relative]))
    line = frame.geometry(relative)
    pieces = shapely.get_parts(exact_line_clip(line, window, "closed"))
    _assert_accepted(line, shapely.MultiLineString(list(pieces[shapely.length(pieces) > 0])),
                     window)
