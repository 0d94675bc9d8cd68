"""GeoJSON documents that mix 2D and 3D positions: each comes out in the dimension it came in.

The oracle is the clip of the same document made wholly 3D by filling each missing Z,
twice, with two unrelated fills (the all-3D path predates mixed documents):

- x and y, and the nesting, of the mixed document's output are those of the filled ones
  (Z never steers the clip);
- a position written with Z has the Z of both filled outputs: the Z written never depends
  on a Z that was missing (nothing invented);
- a geometry whose positions are all 3D comes out as it does in the filled documents
  (all 3D), one whose positions are all 2D comes out all 2D;
- the list output serializes like the array output, with no NaN or null anywhere;
- `rnsca.verify` (Shapely, in 2D) reports on it exactly as on a filled document.

Geometries come from the shared strategies with Z (a function of x and y, so a ring's
ends agree); whether a position keeps its Z is drawn per distinct x, y, so a ring's
first and last positions have one dimension, as the reader requires.
"""

from __future__ import annotations

import math

import numpy as np
import orjson
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from shapely.geometry import mapping

import rnsca
from rnsca.io.geojson import dumps, from_geojson, to_geojson
from tests.property.geometry_strategies import cases

ALL_KINDS = ["point", "multipoint", "linestring", "multilinestring", "polygon", "multipolygon"]
#: How each geometry keeps its Z: all of it, none, or per position (drawn).
PLANS = ["3d", "2d", "mixed"]


def _positions(coordinates):
    """Yield every position (a list of numbers) of a coordinates member."""
    if coordinates and isinstance(coordinates[0], (int, float)):
        yield coordinates
        return
    for item in coordinates:
        yield from _positions(item)


def _documents(geometries, plans, keep_z):
    """Return the mixed document and its two filled versions (lists of floats).

    `keep_z(x, y)` says whether a position of a "mixed" geometry keeps its Z.
    """
    docs = []
    for fill in (None, -1e3, 2.5e5):
        features = []
        for k, (geometry, plan) in enumerate(zip(geometries, plans, strict=True)):
            g = orjson.loads(orjson.dumps(mapping(geometry)))
            for position in _positions(g["coordinates"]):
                drop = plan == "2d" or (plan == "mixed" and not keep_z(*position[:2]))
                if drop:
                    if fill is None:
                        del position[2]
                    else:
                        # A fill of one's own per position: a function of x and y, so a
                        # ring's ends stay equal.
                        position[2] = fill + (position[0] * 0.37 - position[1] * 1.91) % 97.0
            features.append({"type": "Feature", "id": k, "properties": {"plan": plan},
                             "geometry": g})
        docs.append({"type": "FeatureCollection", "features": features})
    return docs


@pytest.mark.parametrize("boundary", ["closed", "interior"])
@given(kind=st.sampled_from(ALL_KINDS), data=st.data())
def test_mixed_documents_write_each_position_in_the_dimension_it_came_in(
        boundary, kind, data):
    geometries, window = data.draw(cases(kind, z=True))
    plans = data.draw(st.lists(st.sampled_from(PLANS), min_size=len(geometries),
                               max_size=len(geometries)), label="plans")
    salt = data.draw(st.integers(0, 2**32 - 1), label="which positions keep Z")

    def keep_z(x, y):
        return hash((x, y, salt)) % 2 == 0

    mixed, filled_a, filled_b = _documents(geometries, plans, keep_z)
    layout = from_geojson(mixed)
    event(f"partial_z={layout.partial_z}")
    result = rnsca.clip_geojson(mixed, window, boundary=boundary, keep_empty=True)
    arrays, _ = rnsca.clip_geojson(mixed, window, boundary=boundary, keep_empty=True,
                                   arrays=True)
    text = dumps(arrays)
    assert text == orjson.dumps(result.document)
    assert b"null" not in text and b"NaN" not in text
    filled_result = rnsca.clip_geojson(filled_a, window, boundary=boundary, keep_empty=True)
    out_a = filled_result.document
    out_b, _ = rnsca.clip_geojson(filled_b, window, boundary=boundary, keep_empty=True)

    for plan, got, a, b in zip(plans, result.document["features"], out_a["features"],
                               out_b["features"], strict=True):
        assert got["geometry"]["type"] == a["geometry"]["type"] == b["geometry"]["type"]
        if plan == "3d":
            assert got["geometry"] == a["geometry"]
            continue
        ours = list(_positions(got["geometry"]["coordinates"]))
        theirs_a = list(_positions(a["geometry"]["coordinates"]))
        theirs_b = list(_positions(b["geometry"]["coordinates"]))
        assert len(ours) == len(theirs_a) == len(theirs_b)
        for p, pa, pb in zip(ours, theirs_a, theirs_b, strict=True):
            assert len(p) in (2, 3) and all(math.isfinite(v) for v in p)
            assert p[:2] == pa[:2] == pb[:2]
            if plan == "2d":
                assert len(p) == 2
            elif len(p) == 3:
                assert p[2] == pa[2] == pb[2]  # never computed from a missing Z
        if plan == "mixed":
            event(f"mixed geometry: {sorted({len(p) for p in ours})} numbers per position")

    # Verification (Shapely, in 2D) judges the mixed document as the filled one: Z never
    # reaches it. (Its verdict itself is the business of the vs-Shapely tests.)
    ours_v = rnsca.verify(None, result, window, boundary=boundary)
    theirs_v = rnsca.verify(None, filled_result, window, boundary=boundary)
    assert ours_v == theirs_v


@given(kind=st.sampled_from(["linestring", "polygon", "multipoint"]), data=st.data())
def test_a_mixed_document_is_written_back_unchanged(kind, data):
    """Read and written without a clip, every position keeps its numbers."""
    geometries, _ = data.draw(cases(kind, z=True))
    salt = data.draw(st.integers(0, 2**32 - 1), label="which positions keep Z")
    plans = ["mixed"] * len(geometries)
    mixed, _, _ = _documents(geometries, plans, lambda x, y: hash((x, y, salt)) % 2 == 0)
    layout = from_geojson(mixed)
    assert to_geojson(layout) == mixed
    assert dumps(to_geojson(layout, arrays=True)) == orjson.dumps(mixed)
    # The layout holds every position in document order (one kind here), Z NaN where none.
    coords = np.concatenate([layout.points[1], layout.lines[1], layout.polygons[1]])
    dims = [len(p) for f in mixed["features"] for p in _positions(f["geometry"]["coordinates"])]
    assert layout.partial_z == (len(set(dims)) == 2)
    has_z = ~np.isnan(coords[:, 2]) if layout.has_z else np.zeros(coords.shape[0], bool)
    assert has_z.tolist() == [n == 3 for n in dims]
