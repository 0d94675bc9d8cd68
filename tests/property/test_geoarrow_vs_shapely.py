"""Arrow tables through ``POST /v1/clip/geoarrow``'s conversion, against Shapely.

Each example is 1 to 3 geometries of one kind (`tests.property.geometry_strategies`,
2D or 3D) with a null row among them, written as a GeoArrow column by pyarrow itself
(`tests.geoarrow_tables.encode`: separated or interleaved coordinates, or WKB) beside
an id and a name column, sent as an Arrow IPC stream to `service.convert.clip_geoarrow`
(what the route runs), and the answer decoded with pyarrow's ``to_pylist``. Checked:
the answer's schema is the request's (native lines and polygons as their multi kinds),
the other columns stay with their rows, a null row stays null (``keep_empty``) or is
dropped, and each geometry matches Shapely's intersection
(`tests.geometry_checks.assert_matches_shapely`; a dropped row: Shapely's is empty too)
in its dimension: the column's, or for WKB each value's own (2D and 3D values mixed).
"""

from __future__ import annotations

import pytest
import shapely
from hypothesis import assume, given
from hypothesis import strategies as st

from rnsca.window import Window
from service import Settings
from service.convert import clip_geoarrow
from service.schemas import GeometryOptions
from tests.geoarrow_tables import ENCODINGS, decode, from_stream, table, to_stream
from tests.geometry_checks import assert_matches_shapely, shapely_can_judge
from tests.property.geometry_strategies import cases

SETTINGS = Settings(warm_up=False)
MULTI = {"linestring": "multilinestring", "polygon": "multipolygon"}


def _check(case, kind: str, encoding: str, keep_empty: bool) -> None:
    geometries, window = case
    assume(shapely_can_judge(geometries, window, "closed"))
    z = any(bool(shapely.has_z(g)) for g in geometries)  # WKB may mix 2D and 3D
    rows = [*geometries[:1], None, *geometries[1:]]  # a null row among them
    sent = table(rows, kind, encoding, z)
    outcome = clip_geoarrow(to_stream(sent), Window.of(window),
                            GeometryOptions(keep_empty=keep_empty), None, False, SETTINGS)
    assert outcome.media_type == "application/vnd.apache.arrow.stream"
    got = from_stream(outcome.content)
    assert got.schema.names == sent.schema.names
    assert got.schema.metadata == sent.schema.metadata
    field = got.schema.field("geometry")
    expected_name = "geoarrow.wkb" if encoding == "wkb" else f"geoarrow.{MULTI.get(kind, kind)}"
    assert field.metadata[b"ARROW:extension:name"].decode() == expected_name
    assert int(outcome.headers["X-Rnsca-Rows"]) == got.num_rows
    ids = got.column("id").to_pylist()
    assert got.column("name").to_pylist() == [f"row {i}" for i in ids]
    assert ids == sorted(ids)
    if keep_empty:
        assert ids == list(range(len(rows)))
    out = dict(zip(ids, decode(got.column("geometry"), field), strict=True))
    for row, geometry in enumerate(rows):
        if geometry is None:
            assert out.get(row, "dropped") is None if keep_empty else row not in out
            continue
        ours = out.get(row)
        assert ours is not None if keep_empty else (ours is None or not ours.is_empty), (
            f"row {row}: {ours}")
        if ours is None:
            ours = shapely.GeometryCollection()  # dropped: nothing left of it
        elif not ours.is_empty:
            # Native: the column's dimension; WKB: each value's own (2D beside 3D stays 2D).
            has_z = z if encoding != "wkb" else bool(shapely.has_z(geometry))
            assert shapely.has_z(ours) == has_z, ours.wkt
        assert_matches_shapely(ours, geometry, window, "closed", where=f"row {row}")


@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("z", [False, True], ids=["2d", "3d"])
@pytest.mark.parametrize("keep_empty", [False, True])
@pytest.mark.parametrize("kind", ["point", "multipoint", "linestring", "multilinestring",
                                  "polygon", "multipolygon"])
@given(data=st.data())
def test_each_kind_and_encoding_equals_shapely(kind, encoding, keep_empty, z, data):
    _check(data.draw(cases(kind, z=z), label="case"), kind, encoding, keep_empty)


@pytest.mark.parametrize("kind", ["point", "multipoint", "linestring", "multilinestring",
                                  "polygon", "multipolygon"])
@given(data=st.data())
def test_wkb_mixing_2d_and_3d_keeps_each_values_dimension(kind, data):
    geometries, window = data.draw(cases(kind, z=True), label="case")
    flat = data.draw(st.lists(st.booleans(), min_size=len(geometries),
                              max_size=len(geometries)), label="2d")
    mixed = [shapely.force_2d(g) if f else g for g, f in zip(geometries, flat, strict=True)]
    _check((mixed, window), kind, "wkb", keep_empty=True)
