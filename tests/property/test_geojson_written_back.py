"""GeoJSON output keeps the input's coordinate lists exactly where the clip changes nothing.

`rnsca.clip_geojson` with nested lists (the default) writes a geometry the clip leaves
as it was with the input's own ``coordinates`` member (see
`rnsca.io.geojson.to_geojson`). This property checks that it is invisible: the
output serializes byte for byte like the NumPy-array output, which always writes the
clip's arrays, so a shared member is exactly what the clip returned. Inputs are parsed
JSON (lists of floats) from the shared strategies.
"""

from __future__ import annotations

import orjson
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from shapely.geometry import mapping

import rnsca
from rnsca.io.geojson import dumps
from tests.property.geometry_strategies import cases

ALL_KINDS = ["point", "multipoint", "linestring", "multilinestring", "polygon", "multipolygon"]


@pytest.mark.parametrize("boundary", ["closed", "interior"])
@given(kind=st.sampled_from(ALL_KINDS), data=st.data())
def test_list_output_is_the_array_output_and_shares_only_unchanged_geometries(
        boundary, kind, data):
    geometries, window = data.draw(cases(kind, z=None))
    features = [{"type": "Feature", "id": k, "properties": {"k": k}, "geometry": mapping(g)}
                for k, g in enumerate(geometries)]
    doc = orjson.loads(orjson.dumps({"type": "FeatureCollection", "features": features}))
    listed, stats = rnsca.clip_geojson(doc, window, boundary=boundary, keep_empty=True)
    arrays, array_stats = rnsca.clip_geojson(doc, window, boundary=boundary, keep_empty=True,
                                             arrays=True)
    assert dumps(arrays) == orjson.dumps(listed)
    assert stats == array_stats
    # The array output writes the clip's own arrays: equal bytes mean that a shared
    # member is exactly what the clip gave, parts and coordinates.
    for source, out in zip(doc["features"], listed["features"], strict=True):
        if out["geometry"]["coordinates"] is source["geometry"]["coordinates"]:
            assert out["geometry"]["type"] == source["geometry"]["type"]
            event("a geometry's coordinates shared")
