"""Write the seed inputs of every target into ``fuzz/corpus/<target>``.

Seeds come from the project's own examples and the peer test cases in
``tests/data/peer`` (GEOS, lineclip, geojson-vt), so the fuzzers start from inputs that
reach deep; ``python -m fuzz.run --merge`` then keeps the ones that add coverage. Run
once, when a target is added: ``python -m fuzz.seed``.
"""

from __future__ import annotations

import hashlib
import json
import struct
from pathlib import Path

import numpy as np
import shapely

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "fuzz" / "corpus"
PEER = ROOT / "tests" / "data" / "peer"
EXAMPLES = ROOT / "service" / "static" / "examples"

PATHS = [
    "M0,0 L10,10 Q 20,0 30,10 Z", "M0 0 L1 x", "m1 2 3 4", "M0 0 H5 V5 Z m1 1 h1v1z",
    "M0 0 A1 2 30 0 1 6 6 a-1 .5 45 1 0 3 -2 A0 1 0 0 0 3 3 A1 1 0 0 0 3 3",
    "M0 0a1 1 0 00 1 1", "M0 0 Q1 1 2 0 T 4 0 S 5 5 6 6 Z l1 1", "M1e999 0",
    "M-.5.5e-3 1. 1e+2,3E-2", "M 1 2 Z L 2 2", "M0 0 C1 2 3 4 5 6 s1 1 2 2 t3 3",
    "  ", "M0 0 L1 1e5e", "M1 2\0M3 4 5 6\0m0 0h1", "M1 1 L1.7976931348623157e308 0 l1e308 0",
    "M0 0 A1e300 1e-300 30 0 1 6 6", "M0 0 L12345678901234567890.5 .123456789012345678901",
]


def _write(target: str, data: bytes) -> None:
    folder = CORPUS / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / hashlib.sha1(data).hexdigest()).write_bytes(data)


def _peer_geometries() -> list:
    records = []
    for path in sorted(PEER.glob("*.jsonl")):
        records += [json.loads(line) for line in path.read_text().splitlines() if line]
    return records


def main() -> None:
    """Write every target's seeds."""
    glyphs = (EXAMPLES / "glyphs-dejavu-sans.txt").read_text().splitlines()
    for d in PATHS + glyphs[:3]:
        _write("svg_path", d.encode())

    records = _peer_geometries()
    for record in records:
        geometry = shapely.from_wkt(record["input_wkt"])
        text = shapely.to_geojson(geometry)
        _write("geojson_reader", text.encode())
        _write("geojson_reader", json.dumps({"type": "Feature", "properties": {"id": 1},
                                             "geometry": json.loads(text)}).encode())
    # Documents for both GeoJSON targets; the file reader's also as files hold them, and
    # as sequences ("S" first).
    example = (EXAMPLES / "polygons-with-holes.geojson").read_bytes()
    documents = [example] + [doc.encode() for doc in (
        '{"type":"MultiPoint","coordinates":[[1,2,3],[1,2]]}',
        '{"type":"LineString","coordinates":[[-5,5,1,2],[15,5,3,4]]}',
        '{"type":"GeometryCollection","geometries":[{"type":"Point","coordinates":[]},'
        '{"type":"MultiPolygon","coordinates":[[]]}]}',
        '{"type":"LineString","coordinates":[[0,-0.0],[18446744073709551615,1e308]]}')]
    features = [{"type": "Feature", "id": i, "properties": {"rank": i, "name": f"n{i}"},
                 "geometry": json.loads(shapely.to_geojson(shapely.from_wkt(r["input_wkt"])))}
                for i, r in enumerate(records[:40])]
    files = documents + [doc.encode() for doc in (
        '{"type":"Feature","geometry":null,"properties":{"coordinates":[1,2]}}',
        '{"type":"LineString","coordinates":[[0,-0.0],[1.7976931348623157e308,'
        '-4.9e-324],[123456789012345678901234,0.1000000000000000055511151231257827]]}',
        '{"type":"Polygon","coordinates":[[[0,0],[1,0],[1,1],[0,0]],[]]}')] + [
        json.dumps({"type": "FeatureCollection", "features": features[:8]}).encode(),
        json.dumps({"type": "FeatureCollection", "features": features}, indent=1).encode(),
        b"S" + "\n".join(json.dumps(f) for f in features[8:16]).encode(),
        b"S\x1e" + "\n\x1e".join(json.dumps(f["geometry"]) for f in features[16:20]).encode()]
    for data in documents:
        _write("geojson_reader", data)
    for data in files:
        _write("geojson_file", data)
    # MessagePack: "M", dim, k, sizes, then the bytes (float64, int and float32 numbers).
    _write("geojson_reader", b"M\x02\x01\x01\x91\x91\x92\xcb" + struct.pack(">d", 1.5)
           + b"\x01")
    _write("geojson_reader", b"M\x03\x02\x01\x00\x92\x91\x94\xca" + struct.pack(">f", 2.5)
           + b"\xd0\xff\xcd\x01\x00\x03\x90")

    window = struct.pack("<4d", 0.0, 0.0, 10.0, 10.0)
    for head in (b"\0\0\0\0", b"\2\1\1\0", b"\0\2\x09\0", b"\1\4\0\6", b"\4\2\0\7"):
        rows = np.array([[-5, 5, 15, 5], [1, 1, 2, 2], [-1, -1, -2, -2], [0, 0, 10, 10],
                         [5, -5, 5, 15], [0, 10, 10, 10]], dtype="<f8")
        _write("segments_endpoint", head + window + rows.tobytes())
    for record in records:
        if record["kind"] != "line":
            continue
        coords = shapely.get_coordinates(shapely.from_wkt(record["input_wkt"]))
        rows = np.hstack([coords[:-1], coords[1:]]).astype("<f8")
        _write("segments_endpoint", b"\0\0\0\0" + struct.pack("<4d", *record["window"])
               + rows[:60].tobytes())

    svg = 'xmlns="http://www.w3.org/2000/svg"'
    for doc in (
            f'<svg {svg}><path d="M-5 5L15 5L5 15"/></svg>',
            f'<?xml version="1.0"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "x.dtd">\n'
            f'<!-- c --><svg {svg} viewBox="0 0 100 100" width="10cm" height="10cm">'
            f'<g transform="translate(10 20) rotate(30) scale(2,1)" fill="none">'
            f'<rect x="-10" y="10%" width="200" height="20" rx="3"/><circle r="50"/>'
            f'<ellipse cx="5" rx="10" ry="4"/><line x2="200" y2="20" stroke="red"/>'
            f'<polyline points="0,0 50,50 150,0"/><polygon points="0 0 50 50 150 0"/>'
            f'</g><?pi data?><text>keep</text></svg>\n<!-- after -->',
            '<s:svg xmlns:s="http://www.w3.org/2000/svg"><s:path style="fill:none" '
            'd="M0 0 C50 200 200 -50 150 50"/></s:svg>',
            f'<!DOCTYPE svg [<!ENTITY a "b">]><svg {svg}/>',
            f'<svg {svg}><path d="M0 0 L1 x"/></svg>',
            f'<svg {svg}><g transform="matrix(1 0 0 0 0 0)"><path d="M0 0L9 9"/></g></svg>'):
        _write("svg_document", doc.encode())


if __name__ == "__main__":
    main()
