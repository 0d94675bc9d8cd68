"""What the client accepts, turned into what the API reads (and Shapely back, if present).

Shapely and NumPy are optional: they are imported only when a caller hands over one of
their objects or asks for one back.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from rnsca_client.errors import InvalidInputError

__all__ = ["window_bounds", "arrow_stream", "geojson_document", "svg_paths", "segment_rows",
           "geometry_from_geojson", "is_numpy_array", "encode_json"]


def window_bounds(window: Any) -> list[float]:
    """Return `window` as ``[xmin, ymin, xmax, ymax]``.

    `window` is 4 numbers, an object with ``bounds`` (a Shapely geometry: its bounding
    box), or one with ``xmin, ymin, xmax, ymax`` attributes (``rnsca.Window``). The
    server checks the values (finite, min < max) and names the bound that is wrong.

    Examples
    --------
    >>> window_bounds((0, 0, 10, 5))
    [0.0, 0.0, 10.0, 5.0]
    >>> window_bounds([0, 1, 2])
    Traceback (most recent call last):
    ...
    rnsca_client.errors.InvalidInputError: window must be [xmin, ymin, xmax, ymax], got [0, 1, 2]
    """
    if hasattr(window, "xmin") and not isinstance(window, Sequence):
        window = (window.xmin, window.ymin, window.xmax, window.ymax)
    elif hasattr(window, "bounds") and not isinstance(window, Sequence):
        window = window.bounds
    try:
        bounds = [float(b) for b in window]
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"window must be [xmin, ymin, xmax, ymax] numbers, got {window!r}") from None
    if len(bounds) != 4:
        raise InvalidInputError(f"window must be [xmin, ymin, xmax, ymax], got {window!r}")
    return bounds


def geojson_document(obj: Any) -> dict[str, Any]:
    """Return `obj` as a GeoJSON Geometry, Feature or FeatureCollection dict.

    `obj` is such a dict, its JSON text, anything with ``__geo_interface__`` (Shapely
    geometries, GeoPandas frames), or a list, tuple or 1-D array of such geometries,
    features or None: a FeatureCollection of them, in order, each geometry (or None) a
    feature whose ``id`` is its position (the server keeps ids, so the answer says which
    are left: features clipped to nothing are dropped unless ``keep_empty``). The server
    validates the document itself.

    Examples
    --------
    >>> geojson_document('{"type": "Point", "coordinates": [1, 2]}')
    {'type': 'Point', 'coordinates': [1, 2]}
    >>> geojson_document([{"type": "Point", "coordinates": [1, 2]}, None])["features"]
    ... # doctest: +NORMALIZE_WHITESPACE
    [{'type': 'Feature', 'id': 0, 'properties': {},
      'geometry': {'type': 'Point', 'coordinates': [1, 2]}},
     {'type': 'Feature', 'id': 1, 'properties': {}, 'geometry': None}]
    """
    if isinstance(obj, (list, tuple)) or (is_numpy_array(obj) and obj.ndim == 1):
        return {"type": "FeatureCollection",
                "features": [_feature(item, i) for i, item in enumerate(obj)]}
    if isinstance(obj, (str, bytes)):
        try:
            obj = json.loads(obj)
        except json.JSONDecodeError as exc:
            raise InvalidInputError(f"the GeoJSON text is not JSON: {exc}") from None
    elif hasattr(obj, "__geo_interface__") and not isinstance(obj, dict):
        obj = obj.__geo_interface__
    if not isinstance(obj, dict):
        raise InvalidInputError(
            "expected a GeoJSON dict, its JSON text or an object with __geo_interface__ "
            f"(a Shapely geometry), got {type(obj).__name__}")
    return obj


def _feature(item: Any, position: int) -> dict[str, Any]:
    """Return item `position` of a list as a Feature (a Feature as it is)."""
    if item is None:
        return {"type": "Feature", "id": position, "properties": {}, "geometry": None}
    document = geojson_document(item)
    if document.get("type") == "Feature":
        return document
    if document.get("type") == "FeatureCollection":
        raise InvalidInputError(f"item {position} is a FeatureCollection; a list holds "
                                "geometries or features")
    return {"type": "Feature", "id": position, "properties": {}, "geometry": document}


def svg_paths(paths: str | Sequence[str]) -> list[str]:
    """Return the path data strings to send: one string, or a sequence of them.

    Examples
    --------
    >>> svg_paths("M 0 0 L 10 10")
    ['M 0 0 L 10 10']
    """
    if isinstance(paths, str):
        return [paths]
    listed = list(paths)
    for i, d in enumerate(listed):
        if not isinstance(d, str):
            raise InvalidInputError(
                f"paths[{i}] must be SVG path data (a str), got {type(d).__name__}")
    return listed


def is_numpy_array(obj: Any) -> bool:
    """Return whether `obj` is a NumPy array (without importing NumPy)."""
    return type(obj).__module__ == "numpy" and hasattr(obj, "__array_interface__")


def segment_rows(segments: Any) -> Any:
    """Return a NumPy array of segments as C-ordered little-endian float64 rows of 4."""
    import numpy as np

    array = np.ascontiguousarray(segments, dtype="<f8")
    if array.ndim != 2 or array.shape[1] != 4:
        raise InvalidInputError(
            f"segments must have shape (n, 4) rows [x0, y0, x1, y1], got {array.shape}")
    return array


def encode_json(payload: dict[str, Any]) -> bytes:
    """Return `payload` as JSON bytes; NaN or infinity (not JSON) is an InvalidInputError.

    Examples
    --------
    >>> encode_json({"window": [0, 0, 1, float("nan")]})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rnsca_client.errors.InvalidInputError: the request holds NaN or infinity, which JSON ...
    """
    try:
        return json.dumps(payload, allow_nan=False, separators=(",", ":")).encode()
    except ValueError as exc:
        if "not JSON compliant" not in str(exc):
            raise
        raise InvalidInputError(
            "the request holds NaN or infinity, which JSON cannot carry: the window and "
            "every coordinate must be finite") from None
    except TypeError as exc:
        raise InvalidInputError(f"the request cannot be sent as JSON: {exc}") from None


def geometry_from_geojson(geometry: dict[str, Any] | None) -> Any:
    """Return a GeoJSON geometry dict as a Shapely geometry (None stays None).

    A geometry that mixes 2D and 3D positions (the server answers each position in the
    dimension it came in) is 3D, with Z NaN where a position has none, as GEOS reads it.
    """
    try:
        import shapely
        import shapely.geometry
    except ImportError:
        raise ImportError("Shapely is needed for Shapely results: "
                          "pip install 'rnsca-client[shapely]'") from None
    if geometry is None:
        return None
    try:
        return shapely.geometry.shape(geometry)
    except ValueError:
        # `shape` reads a part's positions into one array, which refuses 2 and 3 numbers
        # mixed; GEOS's own GeoJSON reader takes them.
        return shapely.from_geojson(json.dumps(geometry))


def arrow_stream(table: Any) -> bytes:
    """Return an Arrow IPC stream: `table` itself if bytes, else a pyarrow table written."""
    if isinstance(table, (bytes, bytearray, memoryview)):
        return bytes(table)
    if type(table).__module__.split(".")[0] != "pyarrow":
        raise InvalidInputError(
            "send GeoArrow as the bytes of an Arrow IPC stream or a pyarrow Table or "
            f"RecordBatch, not {type(table).__name__}")
    import pyarrow as pa

    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as writer:
        writer.write(table)
    return sink.getvalue().to_pybytes()
