"""Parse a large GeoJSON request a slice of features at a time, so the GIL is let go often.

The event loop shares the GIL with the clipping threads, and one `model_validate_json`
of a large body holds it for the whole parse (measured: 157 ms for 8.3 MB), so `/healthz`
waits that long. Here a compiled scan (`feature_bounds`, which runs without the GIL)
finds where the elements of ``geojson.features`` begin and end; the request without
them is validated by pydantic as before, and the features are parsed by orjson a slice
of about `SLICE_BYTES` at a time, each call holding the GIL a few milliseconds.

The result is the one `ClipGeoJSONRequest.model_validate_json` gives. Anything the scan
does not vouch for (no such array, an escape in a key, a key twice, a slice orjson does not
read) falls back to the whole-body parse, which then also gives the usual error.
"""

from __future__ import annotations

import numpy as np
import orjson

from rnsca.kernels.jit import scalar
from service.schemas import ClipGeoJSONRequest

__all__ = ["SLICED_PARSE_BYTES", "SLICE_BYTES", "feature_bounds", "parse_geojson_request",
           "parse_sliced"]

#: Bodies at least this large are parsed a slice at a time.
SLICED_PARSE_BYTES = 1 << 20
#: About this many bytes of features per `orjson.loads` (a few milliseconds each).
SLICE_BYTES = 1 << 18

_QUOTE, _BACKSLASH, _COLON, _COMMA = 34, 92, 58, 44
_OPEN_OBJECT, _CLOSE_OBJECT, _OPEN_ARRAY, _CLOSE_ARRAY = 123, 125, 91, 93
_GEOJSON = np.frombuffer(b'"geojson"', dtype=np.uint8)
_FEATURES = np.frombuffer(b'"features"', dtype=np.uint8)


@scalar
def _is(data, start, end, word):
    if end - start != word.shape[0]:
        return False
    for k in range(word.shape[0]):
        if data[start + k] != word[k]:
            return False
    return True


@scalar
def feature_bounds(data: np.ndarray, geojson: np.ndarray, features: np.ndarray,
                   cuts: np.ndarray) -> int:
    """Find the elements of the top-level object's ``geojson.features`` array.

    Writes into `cuts` the offset of the array's ``[``, of each comma between its
    elements, and of its ``]`` (`cuts` must have room: one more than the commas of
    `data`). Returns how many it wrote, or -1 where the scan cannot vouch for the split:
    no such array, a key with an escape or written twice (at the two levels read), or
    `data` not well nested, an empty element in the array (``[,``, ``,,`` or ``,]``:
    not JSON, and a slice ending before it would not see it).
    """
    depth = 0
    in_string = False
    escaped = False
    string_start = -1
    key_start = np.full(3, -1, dtype=np.int64)  # last string closed at depth 1 and 2
    key_end = np.full(3, -1, dtype=np.int64)
    current_key = np.full(3, -1, dtype=np.int64)  # key of the value being read, by depth
    in_geojson = False
    geojson_seen = 0
    features_seen = 0
    element = False  # a byte of the current element of the array has been seen
    n = 0
    array_depth = -1
    for i in range(data.shape[0]):
        b = data[i]
        if in_string:
            if escaped:
                escaped = False
            elif b == _BACKSLASH:
                escaped = True
                if depth <= 2:
                    return -1  # a key may be spelt with escapes: the whole parse decides
            elif b == _QUOTE:
                in_string = False
                if depth <= 2:
                    key_start[depth] = string_start
                    key_end[depth] = i + 1
            continue
        if depth == array_depth and not (b == _COMMA or b == _CLOSE_ARRAY or b == 32
                                         or b == 9 or b == 10 or b == 13):
            element = True  # the element being read is not empty
        if b == _QUOTE:
            in_string = True
            string_start = i
        elif b == _COLON:
            if depth <= 2:
                current_key[depth] = key_start[depth]
                if depth == 1 and _is(data, key_start[1], key_end[1], geojson):
                    geojson_seen += 1
                if depth == 2 and in_geojson and _is(data, key_start[2], key_end[2], features):
                    features_seen += 1
        elif b == _OPEN_OBJECT or b == _OPEN_ARRAY:
            if depth == 1 and b == _OPEN_OBJECT and current_key[1] >= 0 and _is(
                    data, current_key[1], key_end[1], geojson):
                in_geojson = True
            if depth == 2 and in_geojson and b == _OPEN_ARRAY and current_key[2] >= 0 and _is(
                    data, current_key[2], key_end[2], features):
                if array_depth != -1:
                    return -1  # a second features array
                array_depth = depth + 1
                cuts[n] = i
                n += 1
            depth += 1
        elif b == _CLOSE_OBJECT or b == _CLOSE_ARRAY:
            depth -= 1
            if depth < 0:
                return -1
            if array_depth > 0 and depth == array_depth - 1:  # the features array closes
                if b != _CLOSE_ARRAY or (n > 1 and not element):
                    return -1  # not an array, or a comma before the bracket
                cuts[n] = i
                n += 1
                array_depth = -2
            if depth <= 2:
                current_key[depth] = -1
            if depth == 1:
                in_geojson = False
        elif b == _COMMA:
            if depth == array_depth:
                if not element:
                    return -1  # an empty element: ``[,`` or ``,,``
                element = False
                cuts[n] = i
                n += 1
            if depth <= 2:
                current_key[depth] = -1
    if depth != 0 or in_string or geojson_seen != 1 or features_seen != 1 or array_depth != -2:
        return -1
    return n


def parse_geojson_request(body: bytes) -> ClipGeoJSONRequest:
    """Return the request `body` validated, as `ClipGeoJSONRequest.model_validate_json`."""
    if len(body) >= SLICED_PARSE_BYTES:
        sliced = parse_sliced(body)
        if sliced is not None:
            return sliced
    return ClipGeoJSONRequest.model_validate_json(body)


def parse_sliced(body: bytes, slice_bytes: int | None = None) -> ClipGeoJSONRequest | None:
    """Return the request parsed a slice of features at a time, or None: parse it whole.

    Each slice is about `slice_bytes` (default `SLICE_BYTES`) of whole features.
    """
    step = SLICE_BYTES if slice_bytes is None else slice_bytes
    data = np.frombuffer(body, dtype=np.uint8)
    cuts = np.empty(body.count(b",") + 2, dtype=np.int64)
    n = feature_bounds(data, _GEOJSON, _FEATURES, cuts)
    if n < 2:
        return None
    cuts = cuts[:n]
    opening, closing = int(cuts[0]), int(cuts[-1])
    # The request with an empty features array: validated (window, options, ...) as ever.
    try:
        request = ClipGeoJSONRequest.model_validate_json(
            body[:opening + 1] + body[closing:])
    except ValueError:
        return None  # the whole parse gives the error, with its position
    features: list = []
    if n > 2 or body[opening + 1:closing].strip():
        # Element k spans cuts[k] + 1 .. cuts[k + 1]; slices of whole elements.
        first = 0
        while first < n - 1:
            last = int(np.searchsorted(cuts, cuts[first] + step, side="right")) - 1
            last = min(max(last, first + 1), n - 1)
            try:
                features += orjson.loads(b"[" + body[int(cuts[first]) + 1:int(cuts[last])]
                                         + b"]")
            except orjson.JSONDecodeError:
                return None
            first = last
    geojson = request.geojson
    if not isinstance(geojson.get("features"), list):
        return None
    geojson["features"] = features
    return request
