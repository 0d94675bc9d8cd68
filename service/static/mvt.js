// A Mapbox Vector Tile decoder (specification 2.1, vector_tile.proto): the protobuf wire
// format read by hand, then each feature's geometry commands turned into GeoJSON-like
// geometry in tile coordinates (x right, y down, 0..extent, the buffer outside it).
//
//   Tile    { repeated Layer layers = 3; }
//   Layer   { uint32 version = 15; string name = 1; repeated Feature features = 2;
//             repeated string keys = 3; repeated Value values = 4; uint32 extent = 5; }
//   Feature { uint64 id = 1; packed uint32 tags = 2; GeomType type = 3;
//             packed uint32 geometry = 4; }
//   Value   { string = 1; float = 2; double = 3; int64 = 4; uint64 = 5; sint64 = 6; bool = 7 }
//
// Integers that do not fit a double exactly (past 2**53: ids, int64 values) are BigInts.

const WIRE = { VARINT: 0, FIXED64: 1, BYTES: 2, FIXED32: 5 };
const GEOM_TYPES = ["Unknown", "Point", "LineString", "Polygon"];
const COMMAND = { MOVE_TO: 1, LINE_TO: 2, CLOSE_PATH: 7 };
const TWO_64 = 1n << 64n;

class Reader {
  // Protobuf fields of one message: bytes [pos, end) of `view`.
  constructor(bytes, pos = 0, end = bytes.length, view = null) {
    this.bytes = bytes;
    this.view = view || new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.pos = pos;
    this.end = end;
  }

  more() { return this.pos < this.end; }

  byte() {
    if (this.pos >= this.end) throw new Error("truncated message");
    return this.bytes[this.pos++];
  }

  varint() {
    // An unsigned varint as a Number: exact up to 2**53 (lengths, tags, uint32 fields).
    let value = 0, scale = 1, b;
    do {
      b = this.byte();
      value += (b & 0x7f) * scale;
      scale *= 128;
    } while (b & 0x80);
    return value;
  }

  varint64() {
    // An unsigned varint as a BigInt (up to 10 bytes: 64 bits).
    let value = 0n, shift = 0n, b;
    do {
      b = this.byte();
      value |= BigInt(b & 0x7f) << shift;
      shift += 7n;
    } while (b & 0x80);
    return value % TWO_64;
  }

  fixed(size) {
    // The offset of the next `size` bytes (a float or double), moving past them.
    if (this.pos + size > this.end) throw new Error("truncated message");
    this.pos += size;
    return this.pos - size;
  }

  key() {
    const key = this.varint();
    return { field: Math.floor(key / 8), wire: key % 8 };
  }

  sub() {
    // The next length-delimited field as a Reader of its own.
    const length = this.varint();
    const end = this.pos + length;
    if (end > this.end) throw new Error("truncated message");
    const reader = new Reader(this.bytes, this.pos, end, this.view);
    this.pos = end;
    return reader;
  }

  string() {
    const r = this.sub();
    return new TextDecoder().decode(this.bytes.subarray(r.pos, r.end));
  }

  packed(wire, out) {
    // A repeated uint32: packed (one length-delimited run) or one value per field.
    if (wire === WIRE.BYTES) {
      const r = this.sub();
      while (r.more()) out.push(r.varint());
    } else {
      out.push(this.varint());
    }
  }

  skip(wire) {
    if (wire === WIRE.VARINT) this.varint();
    else if (wire === WIRE.FIXED64) this.fixed(8);
    else if (wire === WIRE.BYTES) this.sub();
    else if (wire === WIRE.FIXED32) this.fixed(4);
    else throw new Error(`unsupported wire type ${wire}`);
  }
}

function number(big) {
  // A BigInt as a Number where that is exact, else the BigInt.
  return big >= -(2n ** 53n) && big <= 2n ** 53n ? Number(big) : big;
}

function readValue(r) {
  let value = null;
  while (r.more()) {
    const { field, wire } = r.key();
    if (field === 1 && wire === WIRE.BYTES) value = r.string();
    else if (field === 2 && wire === WIRE.FIXED32) value = r.view.getFloat32(r.fixed(4), true);
    else if (field === 3 && wire === WIRE.FIXED64) value = r.view.getFloat64(r.fixed(8), true);
    else if (field === 4 && wire === WIRE.VARINT) value = number(BigInt.asIntN(64, r.varint64()));
    else if (field === 5 && wire === WIRE.VARINT) value = number(r.varint64());
    else if (field === 6 && wire === WIRE.VARINT) {
      const n = r.varint64();                       // zigzag: 0, -1, 1, -2, ... -> 0, 1, 2, 3
      value = number((n >> 1n) ^ -(n & 1n));
    } else if (field === 7 && wire === WIRE.VARINT) value = r.varint() !== 0;
    else r.skip(wire);
  }
  return value;
}

function readFeature(r) {
  const feature = { id: null, type: 0, tags: [], geometry: [] };
  while (r.more()) {
    const { field, wire } = r.key();
    if (field === 1 && wire === WIRE.VARINT) feature.id = number(r.varint64());
    else if (field === 2) r.packed(wire, feature.tags);
    else if (field === 3 && wire === WIRE.VARINT) feature.type = r.varint();
    else if (field === 4) r.packed(wire, feature.geometry);
    else r.skip(wire);
  }
  return feature;
}

function readLayer(r) {
  const layer = { version: 1, name: "", extent: 4096, keys: [], values: [], features: [] };
  while (r.more()) {
    const { field, wire } = r.key();
    if (field === 15 && wire === WIRE.VARINT) layer.version = r.varint();
    else if (field === 1 && wire === WIRE.BYTES) layer.name = r.string();
    else if (field === 2 && wire === WIRE.BYTES) layer.features.push(readFeature(r.sub()));
    else if (field === 3 && wire === WIRE.BYTES) layer.keys.push(r.string());
    else if (field === 4 && wire === WIRE.BYTES) layer.values.push(readValue(r.sub()));
    else if (field === 5 && wire === WIRE.VARINT) layer.extent = r.varint();
    else r.skip(wire);
  }
  return layer;
}

const zigzag = (n) => (n >>> 1) ^ -(n & 1);

function commandParts(geometry) {
  // The parts (point lists) of a feature's command integers: MoveTo starts a part,
  // LineTo extends it, ClosePath ends a ring. Parameters are zigzag deltas from a cursor
  // that runs through the whole feature.
  const parts = [];
  let part = null, x = 0, y = 0, i = 0;
  while (i < geometry.length) {
    const command = geometry[i] & 0x7, count = geometry[i] >>> 3;
    i += 1;
    if (command === COMMAND.CLOSE_PATH) {
      if (part) part.closed = true;
      continue;
    }
    if (command !== COMMAND.MOVE_TO && command !== COMMAND.LINE_TO) {
      throw new Error(`unknown geometry command ${command}`);
    }
    if (i + 2 * count > geometry.length) throw new Error("geometry ends inside a command");
    for (let k = 0; k < count; k++) {
      x += zigzag(geometry[i]);
      y += zigzag(geometry[i + 1]);
      i += 2;
      if (command === COMMAND.MOVE_TO) {
        part = { points: [], closed: false };
        parts.push(part);
      }
      if (!part) throw new Error("LineTo before any MoveTo");
      part.points.push([x, y]);
    }
  }
  return parts;
}

function signedArea(ring) {
  // Twice the surveyor's-formula area; positive for an exterior ring in tile coordinates.
  let sum = 0;
  for (let i = 0; i + 1 < ring.length; i++) sum += ring[i][0] * ring[i + 1][1] - ring[i + 1][0] * ring[i][1];
  return sum;
}

function toGeometry(type, parts) {
  // GeoJSON-like geometry of one feature, single or Multi* by its number of parts.
  const name = GEOM_TYPES[type] || "Unknown";
  if (name === "Point") {
    const points = parts.flatMap((p) => p.points);
    return points.length === 1 ? { type: "Point", coordinates: points[0] }
                               : { type: "MultiPoint", coordinates: points };
  }
  if (name === "LineString") {
    const lines = parts.map((p) => p.points);
    return lines.length === 1 ? { type: "LineString", coordinates: lines[0] }
                              : { type: "MultiLineString", coordinates: lines };
  }
  if (name === "Polygon") {
    // Spec 4.3.4.4: an exterior ring has positive area, each ring of negative area is a
    // hole of the exterior before it; rings of zero area are dropped. Rings are closed
    // here (the tile does not repeat the first point).
    const polygons = [];
    for (const part of parts) {
      const ring = part.points.slice();
      const [first, last] = [ring[0], ring[ring.length - 1]];
      if (first[0] !== last[0] || first[1] !== last[1]) ring.push(first);
      const area = signedArea(ring);
      if (area === 0) continue;
      if (area > 0 || !polygons.length) polygons.push([ring]);
      else polygons[polygons.length - 1].push(ring);
    }
    return polygons.length === 1 ? { type: "Polygon", coordinates: polygons[0] }
                                 : { type: "MultiPolygon", coordinates: polygons };
  }
  return { type: "Unknown", coordinates: parts.map((p) => p.points) };
}

export function decodeTile(buffer) {
  // The layers of an MVT (ArrayBuffer or Uint8Array): [{name, version, extent, keys,
  // values, features: [{id, type, properties, geometry}]}]; id null when the tile has none.
  const bytes = buffer instanceof Uint8Array ? buffer : new Uint8Array(buffer);
  const tile = new Reader(bytes);
  const layers = [];
  while (tile.more()) {
    const { field, wire } = tile.key();
    if (field === 3 && wire === WIRE.BYTES) layers.push(readLayer(tile.sub()));
    else tile.skip(wire);
  }
  return layers.map((layer) => ({
    name: layer.name, version: layer.version, extent: layer.extent,
    keys: layer.keys.length, values: layer.values.length,
    features: layer.features.map((f) => {
      if (f.tags.length % 2) throw new Error(`layer ${layer.name}: odd number of tags`);
      const properties = {};
      for (let i = 0; i < f.tags.length; i += 2) {
        const [key, value] = [layer.keys[f.tags[i]], layer.values[f.tags[i + 1]]];
        if (key === undefined || value === undefined) {
          throw new Error(`layer ${layer.name}: tag index out of range`);
        }
        properties[key] = value;
      }
      return { id: f.id, type: GEOM_TYPES[f.type] || "Unknown", properties,
               geometry: toGeometry(f.type, commandParts(f.geometry)) };
    }),
  }));
}

export function tileJson(value) {
  // JSON text of decoded content: BigInts as exact JSON numbers where the browser has
  // JSON.rawJSON, else as strings of their digits.
  const big = JSON.rawJSON ? (v) => JSON.rawJSON(v.toString()) : (v) => v.toString();
  return JSON.stringify(value, (key, v) => (typeof v === "bigint" ? big(v) : v), 1);
}
