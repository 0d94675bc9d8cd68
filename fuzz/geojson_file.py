"""Fuzz target: the compiled GeoJSON file reader (`rnsca.io.geojson_file`) of `rnsca tiles`.

The first byte of an input picks the framing: ``S`` a GeoJSON text sequence (one
document per line, RS-prefixed or not), anything else one document; the rest are the
file's bytes. The compiled scan reads them with no bounds check of its own (it stops at
the zero bytes padded after the document), so the runner's Numba bounds checks are part
of the target.

A finding is an exception from the compiled reader (it returns None for anything it does
not take), an ``IndexError`` from the bounds checks, or a disagreement with the exact
reader: `rnsca.tiles.sources.read_features` with the compiled reader declining (orjson,
then `rnsca.io.geojson.from_geojson`; that reader is fuzzed by ``geojson_reader``).
Where the exact reader gives features, the compiled one gives the same (coordinates and
offsets bit for bit, properties and ids by value and type) or declines; where the exact
reader refuses the file (`ParseError`, `InvalidGeometryError`), the compiled one
declines.
"""

from __future__ import annotations

import atexit
import os
import tempfile
from pathlib import Path

import numpy as np
import orjson
import shapely

from rnsca.errors import InvalidGeometryError, ParseError, UnsupportedGeometryError
from rnsca.io.geojson_file import read_file_features
from rnsca.kernels.geojson_scan import PADDING
from rnsca.tiles import sources

__all__ = ["MAX_LEN", "setup", "test_one_input", "same_features"]

#: Longest input libFuzzer makes.
MAX_LEN = 4096
#: What the exact reader raises for a file it refuses.
_REFUSALS = (ParseError, InvalidGeometryError, UnsupportedGeometryError)

_work = Path(tempfile.mkdtemp(prefix="rnsca-fuzz-geojson-file-"))


def _exact(data: bytes, sequence: bool) -> sources.Features:
    """Return what `read_features` reads from `data` with the compiled reader declining."""
    path = _work / ("input.geojsonl" if sequence else "input.geojson")
    path.write_bytes(data)
    declining = sources.read_file_features
    sources.read_file_features = lambda *args, **kwargs: None
    try:
        return sources.read_features(path)
    finally:
        sources.read_file_features = declining


def same_features(fast: sources.Features, exact: sources.Features) -> None:
    """Raise AssertionError unless two `Features` are equal (arrays bit for bit)."""
    assert orjson.dumps(fast.properties) == orjson.dumps(exact.properties), "properties"
    assert orjson.dumps(fast.ids) == orjson.dumps(exact.ids), "ids"
    assert exact.geometries is None and exact.ragged is not None, "exact: collections"
    assert fast.ragged is not None and fast.sources is not None and exact.sources is not None
    for mine, theirs in zip(fast.ragged, exact.ragged, strict=True):
        assert mine.kind == theirs.kind and mine.partial_z == theirs.partial_z, "kind"
        assert mine.coords.shape == theirs.coords.shape, "coordinates' shape"
        assert np.array_equal(mine.coords.view(np.uint64), theirs.coords.view(np.uint64)), \
            "coordinates"
        assert len(mine.offsets) == len(theirs.offsets), "offsets' depth"
        for a, b in zip(mine.offsets, theirs.offsets, strict=True):
            assert np.array_equal(a, b), "offsets"
    for a, b in zip(fast.sources, exact.sources, strict=True):
        assert np.array_equal(a, b), "sources"


def setup() -> None:
    """Compile the scan and the build kernels before the first timed input."""
    test_one_input(b'{"type":"FeatureCollection","features":[{"type":"Feature","id":1,'
                   b'"properties":{"a":[1]},"geometry":{"type":"Polygon","coordinates":'
                   b'[[[0,0],[1e1,0],[1,1.5],[0,0]]]}}]}')
    test_one_input(b'S{"type":"Point","coordinates":[1,2,3]}\n\x1e{"type":"LineString",'
                   b'"coordinates":[[1,2],[3,4.25e-7]]}')


def test_one_input(data: bytes) -> None:
    """Check one input (see the module docstring)."""
    sequence = data[:1] == b"S"
    document = data[1:] if sequence else data
    padded = np.zeros(len(document) + PADDING, dtype=np.uint8)
    padded[:len(document)] = np.frombuffer(document, dtype=np.uint8)
    read = read_file_features(padded, len(document), sequence=sequence)
    fast = None if read is None else sources._of_file_features(read)
    try:
        exact = _exact(document, sequence)
    except _REFUSALS:
        assert fast is None, "the compiled reader took a file the exact reader refuses"
        return
    except (RecursionError, shapely.errors.GEOSException):
        # Past the exact reader's nesting or GEOS's: not this target's to judge.
        return
    if fast is not None:
        same_features(fast, exact)


@atexit.register
def _cleanup() -> None:
    for name in os.listdir(_work):
        os.unlink(_work / name)
    os.rmdir(_work)
