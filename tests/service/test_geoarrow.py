"""POST /v1/clip/geoarrow through the app: Arrow IPC streams in and out, problems for bad input."""

from __future__ import annotations

import numpy as np
import orjson
import pyarrow as pa
import pytest
import shapely

from service.admission import PEAK_BYTES_PER_BODY_BYTE
from tests.geoarrow_tables import (
    ARROW_STREAM,
    decode,
    encode,
    from_stream,
    raw_native,
    table,
    to_stream,
)

WINDOW = {"xmin": 0, "ymin": 0, "xmax": 10, "ymax": 10}
ZIGZAG = shapely.from_wkt("LINESTRING (-5 1, 5 1, 5 20, 8 20, 8 5, 15 5)")
AWAY = shapely.from_wkt("LINESTRING (20 20, 30 30)")
PROBLEM = "application/problem+json"


def post(client, body: bytes, media: str = ARROW_STREAM, **params):
    return client.post("/v1/clip/geoarrow", content=body, params={**WINDOW, **params},
                       headers={"Content-Type": media})


def assert_problem(r, status: int, slug: str, *words: str) -> dict:
    assert r.status_code == status, r.text
    assert r.headers["content-type"] == PROBLEM
    body = r.json()
    assert body["type"] == f"urn:rnsca:problem:{slug}", body
    for word in words:
        assert word in body["detail"], body
    return body


@pytest.mark.parametrize("encoding", ["separated", "interleaved", "wkb"])
def test_lines_come_back_clipped_in_their_encoding_with_the_other_columns(client, encoding):
    r = post(client, to_stream(table([ZIGZAG, None, AWAY], "linestring", encoding, False)))
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == ARROW_STREAM
    got = from_stream(r.content)
    assert r.headers["X-Rnsca-Rows"] == "1" and got.num_rows == 1
    assert got.column("id").to_pylist() == [0] and got.column("name").to_pylist() == ["row 0"]
    assert got.schema.metadata == {b"source": b"tests"}
    [clipped] = decode(got.column("geometry"), got.schema.field("geometry"))
    assert shapely.equals(clipped, shapely.from_wkt(
        "MULTILINESTRING ((0 1, 5 1, 5 10), (8 10, 8 5, 10 5))"))
    stats = orjson.loads(r.headers["X-Rnsca-Stats"])
    assert stats["geometries_in"] == 2 and stats["geometries_out"] == 1
    assert orjson.loads(r.headers["X-Rnsca-Verification"])["passed"] is True


def test_keep_empty_keeps_every_row_and_nulls_stay_null(client):
    r = post(client, to_stream(table([ZIGZAG, None, AWAY], "linestring", "interleaved", False)),
             keep_empty="true")
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    assert got.column("id").to_pylist() == [0, 1, 2]
    geometries = decode(got.column("geometry"), got.schema.field("geometry"))
    assert geometries[1] is None and geometries[2].is_empty


def test_polygons_with_z_come_back_as_multipolygons_with_z(client):
    square = shapely.from_wkt("POLYGON Z ((-5 -5 1, 5 -5 1, 5 5 1, -5 5 1, -5 -5 1))")
    r = post(client, to_stream(table([square], "polygon", "separated", True)))
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    field = got.schema.field("geometry")
    assert field.metadata[b"ARROW:extension:name"] == b"geoarrow.multipolygon"
    assert field.metadata[b"ARROW:extension:metadata"] == b'{"crs": "OGC:CRS84"}'
    [clipped] = decode(got.column("geometry"), field)
    assert shapely.has_z(clipped)
    assert shapely.equals(clipped, shapely.box(0, 0, 5, 5))


def test_points_and_options_from_the_query(client):
    points = [shapely.Point(0, 5), shapely.Point(5, 5), shapely.Point(20, 5)]
    body = to_stream(table(points, "point", "interleaved", False))
    closed = from_stream(post(client, body).content)
    assert closed.column("id").to_pylist() == [0, 1]
    interior = from_stream(post(client, body, boundary="interior").content)
    assert interior.column("id").to_pylist() == [1]


def test_the_column_can_be_named(client):
    column, field = encode([ZIGZAG], "linestring", "wkb", False)
    t = pa.Table.from_arrays([column, column], schema=pa.schema(
        [field.with_name("a"), field.with_name("b")]))
    assert_problem(post(client, to_stream(t)), 422, "parse-error", "several geometry columns")
    r = post(client, to_stream(t), column="b")
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    assert got.column("a").to_pylist() == column.to_pylist()  # passed through as it was
    assert got.column("b").to_pylist() != column.to_pylist()


def test_not_an_arrow_stream_is_422_naming_it(client):
    assert_problem(post(client, b"{}"), 422, "invalid-body", "not a valid Arrow IPC stream")


def test_inconsistent_offsets_are_422(client):
    values = pa.array([[0.0, 0.0], [20.0, 20.0]], pa.list_(pa.field("xy", pa.float64()), 2))
    broken = pa.ListArray.from_arrays(pa.array([0, 2], pa.int32()), values)
    body = bytearray(to_stream(pa.table({"g": broken}, schema=pa.schema([pa.field(
        "g", broken.type, metadata={"ARROW:extension:name": "geoarrow.linestring"})]))))
    # The offsets buffer holds 0 and 2 as int32: make the end point past the coordinates.
    end = bytes(body).rindex(np.array([0, 2], "<i4").tobytes()) + 4
    body[end:end + 4] = np.array([9], "<i4").tobytes()
    assert_problem(post(client, bytes(body)), 422, "invalid-body", "Arrow IPC stream")


def test_no_geometry_column_is_422(client):
    body = to_stream(pa.table({"id": [1, 2]}))
    assert_problem(post(client, body), 422, "parse-error", "no geometry column", "['id']")


def test_an_unknown_extension_is_422(client):
    field = pa.field("g", pa.binary(), metadata={"ARROW:extension:name": "geoarrow.box"})
    body = to_stream(pa.Table.from_arrays([pa.array([b""])], schema=pa.schema([field])))
    assert_problem(post(client, body), 422, "unsupported-geometry", "geoarrow.box")


def test_mixed_kinds_are_422(client):
    body = to_stream(table([ZIGZAG, shapely.box(0, 0, 1, 1)], "linestring", "wkb", False))
    assert_problem(post(client, body), 422, "unsupported-geometry", "one kind")


def test_nan_coordinates_are_422_naming_the_row(client):
    bad = shapely.LineString([(0, 0), (np.nan, 1)])
    body = to_stream(table([ZIGZAG, None, bad], "linestring", "separated", False))
    problem = assert_problem(post(client, body), 422, "invalid-geometry", "row 2")
    assert problem["path"] == "geometry[2]"


def test_an_unclosed_ring_is_422(client):
    ring = [[{"x": 0.0, "y": 0.0}, {"x": 1.0, "y": 0.0}, {"x": 1.0, "y": 1.0},
             {"x": 0.0, "y": 1.0}]]
    storage = pa.list_(pa.field("rings", pa.list_(pa.field("vertices", pa.struct(
        [("x", pa.float64()), ("y", pa.float64())])))))
    field = pa.field("g", storage, metadata={"ARROW:extension:name": "geoarrow.polygon"})
    body = to_stream(pa.Table.from_arrays([pa.array([ring], storage)],
                                          schema=pa.schema([field])))
    assert_problem(post(client, body), 422, "invalid-geometry", "row 0")


def test_unknown_query_parameters_and_a_missing_window_are_422(client):
    body = to_stream(table([ZIGZAG], "linestring", "wkb", False))
    assert post(client, body, keep_emtpy="true").json()["path"] == "query.keep_emtpy"
    r = client.post("/v1/clip/geoarrow", content=body, params={"xmin": 0},
                    headers={"Content-Type": ARROW_STREAM})
    assert r.status_code == 422 and r.json()["path"].startswith("query.")


def test_another_media_type_is_415(client):
    body = to_stream(table([ZIGZAG], "linestring", "wkb", False))
    assert_problem(post(client, body, media="application/json"), 415,
                   "unsupported-media-type", ARROW_STREAM)


def test_the_memory_admission_has_a_ratio_for_arrow_bodies():
    assert PEAK_BYTES_PER_BODY_BYTE[("geoarrow", "arrow")] > 1


def test_the_openapi_description_names_the_media_type(client):
    operation = client.get("/openapi.json").json()["paths"]["/v1/clip/geoarrow"]["post"]
    assert ARROW_STREAM in operation["requestBody"]["content"]
    assert ARROW_STREAM in operation["responses"]["200"]["content"]
    assert {p["name"] for p in operation["parameters"]} >= {"xmin", "keep_empty", "column"}


def test_the_readme_example_runs_as_written(client, monkeypatch):
    import pathlib

    import httpx

    text = (pathlib.Path(__file__).parents[2] / "README.md").read_text()
    start = text.index("import httpx, pyarrow as pa, shapely")
    code = text[start:text.index("```", start)]
    monkeypatch.setattr(httpx, "post", lambda url, **kw: client.post(
        url.removeprefix("http://localhost:8000"), **kw))
    scope: dict = {}
    exec(code, scope)  # noqa: S102 - our own README
    clipped = scope["clipped"]
    assert clipped.column("name").to_pylist() == ["road"]
    assert clipped.column("geometry").to_pylist() == [
        [[[0.0, 1.0], [5.0, 1.0], [5.0, 10.0]], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]]]]


def test_a_stream_of_several_batches_is_one_table(client):
    t = table([ZIGZAG, AWAY, ZIGZAG], "linestring", "interleaved", False)
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, t.schema) as writer:
        for batch in t.to_batches(max_chunksize=1):
            writer.write_batch(batch)
    r = post(client, sink.getvalue().to_pybytes())
    assert r.status_code == 200, r.text
    assert from_stream(r.content).column("id").to_pylist() == [0, 2]


def test_a_truncated_stream_is_422(client):
    body = to_stream(table([ZIGZAG], "linestring", "interleaved", False))
    assert_problem(post(client, body[:-40]), 422, "invalid-body", "Arrow IPC stream")


def test_a_field_name_that_is_not_utf8_is_422(client):
    body = to_stream(pa.table({"idx": [1]}))
    broken = body.replace(b"idx", b"\xfbdx")
    assert_problem(post(client, broken), 422, "invalid-body", "Arrow IPC stream")


def test_mutated_streams_never_fail_as_anything_but_a_problem():
    """Random bytes changed in valid streams: every failure is a mapped error (never a 500)."""
    from rnsca.errors import RnscaError
    from rnsca.window import Window
    from service import Settings
    from service.convert import clip_geoarrow
    from service.errors import ServiceError
    from service.schemas import GeometryOptions

    rng = np.random.default_rng(7)
    bodies = [to_stream(table([shapely.box(-5, -5, 5, 5), None], "polygon", encoding, z))
              for encoding in ("separated", "interleaved", "wkb") for z in (False, True)]
    bodies.append(to_stream(table([shapely.Point(1, 1), shapely.Point(20, 1)], "point",
                                  "interleaved", False)))
    settings = Settings(warm_up=False)
    for i in range(700):
        body = bytearray(bodies[i % len(bodies)])
        for _ in range(rng.integers(1, 4)):
            body[rng.integers(0, len(body))] = rng.integers(0, 256)
        try:
            clip_geoarrow(bytes(body), Window(0, 0, 10, 10),
                          GeometryOptions(keep_empty=bool(i % 2)), None, None, settings)
        except (RnscaError, ServiceError):
            pass


# --- degenerate parts: valid GeoArrow that Shapely 2.2 crashes on (verification on) ------

SQUARE_XY = [[-5, -5], [5, -5], [5, 5], [-5, 5], [-5, -5]]
HOLE_XY = [[1, 1], [1, 2], [2, 2], [2, 1], [1, 1]]
CLIPPED_SQUARE = shapely.box(0, 0, 5, 5)


@pytest.mark.parametrize("verify", ["true", "all", "false"])
def test_a_polygon_of_no_rings_in_a_multipolygon_is_an_empty_part(client, verify):
    # Row 0: [no rings, the square]; row 1: [no rings] only.
    body = raw_native("multipolygon", SQUARE_XY, [0, 2, 3], [0, 0, 1, 1], [0, 5])
    r = post(client, body, verify=verify, keep_empty="true")
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    first, second = decode(got.column("geometry"), got.schema.field("geometry"))
    assert shapely.equals(first, CLIPPED_SQUARE) and second.is_empty
    if verify != "false":
        assert orjson.loads(r.headers["X-Rnsca-Verification"])["passed"] is True


@pytest.mark.parametrize("kind", ["polygon", "multipolygon"])
def test_a_polygon_whose_exterior_is_empty_clips_to_nothing(client, kind):
    # Rings: an empty exterior and a hole; then the square (a second row).
    levels = ([0, 1, 2], [0, 2, 3]) if kind == "multipolygon" else ([0, 2, 3],)
    body = raw_native(kind, HOLE_XY + SQUARE_XY, *levels, [0, 0, 5, 10])
    r = post(client, body, check_validity="true")
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    assert got.column("id").to_pylist() == [1]
    assert orjson.loads(r.headers["X-Rnsca-Verification"])["passed"] is True


def test_lines_of_no_positions_and_multipoints_of_no_points_are_empty(client):
    line = [[-5, 1], [15, 1]]
    for kind, levels in (("linestring", ([0, 0, 2],)),
                         ("multilinestring", ([0, 1, 2], [0, 0, 2])),
                         ("multipoint", ([0, 0, 2],))):
        r = post(client, raw_native(kind, line, *levels))
        assert r.status_code == 200, (kind, r.text)
        assert from_stream(r.content).column("id").to_pylist() == (
            [1] if kind != "multipoint" else [])  # the points lie outside the window


def test_a_line_of_one_position_is_422_naming_the_row(client):
    body = raw_native("linestring", [[-5, 1], [15, 1], [3, 3]], [0, 2, 3])
    problem = assert_problem(post(client, body), 422, "invalid-geometry", "row 1",
                             "one position")
    assert problem["path"] == "geometry[1]"


def test_wkb_with_empty_parts_is_clipped_without_them(client):
    wkts = ["MULTIPOLYGON (EMPTY, ((-5 -5, 5 -5, 5 5, -5 5, -5 -5)))",
            "MULTIPOINT (EMPTY, (1 1), EMPTY)", "MULTIPOINT (EMPTY)"]
    for wkt, expected in zip(wkts, [CLIPPED_SQUARE, shapely.Point(1, 1), None], strict=True):
        body = to_stream(table([shapely.from_wkt(wkt)], "wkb", "wkb", False))
        r = post(client, body, keep_empty="true")
        assert r.status_code == 200, (wkt, r.text)
        got = from_stream(r.content)
        [clipped] = decode(got.column("geometry"), got.schema.field("geometry"))
        assert clipped.is_empty if expected is None else shapely.equals(clipped, expected)


# --- columns without a geometry, and WKB that mixes 2D and 3D ---------------------------

@pytest.mark.parametrize("encoding", ["separated", "interleaved", "wkb"])
@pytest.mark.parametrize("keep_empty", ["false", "true"])
def test_an_all_null_column_is_answered_as_nulls_are_in_any_column(client, encoding,
                                                                   keep_empty):
    body = to_stream(table([None, None, None], "polygon", encoding, False))
    r = post(client, body, keep_empty=keep_empty)
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    # Null rows are dropped, or kept as nulls with keep_empty, as beside present rows.
    expected = [0, 1, 2] if keep_empty == "true" else []
    assert got.column("id").to_pylist() == expected and r.headers["X-Rnsca-Rows"] == str(
        len(expected))
    assert got.column("geometry").null_count == len(expected)


def test_a_wkb_column_of_empty_values_is_answered_with_empties(client):
    body = to_stream(table([shapely.Polygon(), None], "polygon", "wkb", False))
    r = post(client, body, keep_empty="true")
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    empty, null = decode(got.column("geometry"), got.schema.field("geometry"))
    assert empty.is_empty and null is None


def test_wkb_values_keep_their_own_dimension_when_2d_and_3d_are_mixed(client):
    lines = shapely.from_wkt(["LINESTRING (-5 1, 15 1)", "LINESTRING Z (-5 2 7, 15 2 9)"])
    body = to_stream(table(list(lines), "linestring", "wkb", True))  # written with Z...
    t = from_stream(body)
    wkb = pa.array(list(shapely.to_wkb(lines, output_dimension=3)), pa.binary())  # ...or not
    body = to_stream(t.set_column(2, t.schema.field("geometry"), wkb))
    r = post(client, body)
    assert r.status_code == 200, r.text
    got = from_stream(r.content)
    flat, with_z = decode(got.column("geometry"), got.schema.field("geometry"))
    assert shapely.to_wkt(flat) == "LINESTRING (0 1, 10 1)"
    assert shapely.to_wkt(with_z) == "LINESTRING Z (0 2 7.5, 10 2 8.5)"
    assert orjson.loads(r.headers["X-Rnsca-Verification"])["passed"] is True
