// The rnsca playground: load GeoJSON or SVG path data, drag a clip window over it, and
// draw what POST /v1/clip/geojson or /v1/clip/svg answers; or, in the tile view
// (tiles.js), see the vector tile grid over GeoJSON and what a tile holds. Plain
// JavaScript modules, no build step and nothing fetched from outside the service.
//
// Coordinates: the drawing lives in <g id="world">, in the input's own units. GeoJSON
// has y pointing up, so that group flips y for it; SVG path data has y pointing down
// and is drawn as is. Pointer positions are mapped back through the group's screen
// matrix, so dragging works the same in both.
//
// Test hooks: <body data-state> is "loading", "busy", "idle" or "error";
// #results[data-window] is the window (JSON) of the result or error shown; summary
// values and statistics carry their full-precision number in data-value; #copy-status
// has data-copied="true" once the result is on the clipboard; <body> has the class
// view-tiles while the tile view is shown (tiles.js lists its own hooks).

import { createTileView } from "./tiles.js";

const API = { geojson: "v1/clip/geojson", svg: "v1/clip/svg", capabilities: "v1/capabilities" };
const EXAMPLES = "playground/examples/";
const SVG_NS = "http://www.w3.org/2000/svg";
const BOUNDS = ["xmin", "ymin", "xmax", "ymax"];
const HANDLE_PX = 5;
// The statistics shown, in this order (the per-level lists are drawn as bars).
const STAT_KEYS = [
  "segments_in", "pieces_out", "fragments_evaluated", "accepted", "rejected", "subdivided",
  "clipped", "dropped", "intersections", "deepest_level", "geometries_in", "geometries_out",
  "vertices_in", "vertices_out", "runs_evaluated", "runs_accepted", "runs_rejected",
  "runs_subdivided", "runs_segmented", "runs_deepest_level", "invalid_polygons",
  "decided_shallow_fraction",
];

// One format for every count shown (vertices, paths, statistics, limits): digits grouped.
const COUNT = new Intl.NumberFormat("en");
const count = (n) => COUNT.format(n);

const $ = (id) => document.getElementById(id);
const canvas = $("canvas");
const world = $("world");

const state = {
  format: null,          // "geojson" or "svg" once an input is loaded
  geojson: null,         // the parsed GeoJSON document
  geojsonText: null,     // and its text (sent as is: JSON.parse rounds integers past 2**53)
  paths: null,           // the SVG path data strings
  inputError: false,     // the text could not be read (the error is shown)
  // What the numeric inputs hold (maybe invalid: the server says); none before an input.
  window: [NaN, NaN, NaN, NaN],
  capabilities: null,
  examples: [],
  result: null,          // what Copy and Download give: {text, type, filename, label}
  inFlight: false,
  pending: false,
  drag: null,
  inputTimer: 0,
  view: "clip",          // "clip" or "tiles": which view is shown
};
let tiles = null;        // the tile view (tiles.js), once the page is set up

class InputError extends Error {}

// --- input -------------------------------------------------------------------------

function parseInput(text) {
  const trimmed = text.trim();
  if (!trimmed) return { format: null };
  if (trimmed[0] === "{" || trimmed[0] === "[") {
    let doc;
    try {
      doc = JSON.parse(trimmed);
    } catch (e) {
      throw new InputError(`The input is not valid JSON: ${e.message}`);
    }
    if (!doc || typeof doc !== "object" || Array.isArray(doc) || typeof doc.type !== "string") {
      throw new InputError('GeoJSON must be an object with a "type" (a Geometry, Feature ' +
                           "or FeatureCollection).");
    }
    return { format: "geojson", geojson: doc, text: trimmed };
  }
  if (trimmed[0] === "<") {
    const doc = new DOMParser().parseFromString(trimmed, "image/svg+xml");
    const problem = doc.querySelector("parsererror");
    if (problem) throw new InputError(`The SVG document is not well-formed XML: ${problem.textContent}`);
    const elements = [...doc.getElementsByTagNameNS(SVG_NS, "path")];
    const paths = elements.map((p) => p.getAttribute("d")).filter((d) => d && d.trim());
    if (!paths.length) throw new InputError("The SVG document has no <path> with a d attribute.");
    const transformed = doc.querySelector("[transform]") !== null;
    return { format: "svg", paths, warning: transformed ?
      "The document has transform attributes: they are not applied (path data only)." : "" };
  }
  return { format: "svg", paths: trimmed.split(/\r?\n/).map((s) => s.trim()).filter(Boolean) };
}

function geometries(doc) {
  // Every geometry of a GeoJSON document (features without one are skipped).
  if (!doc) return [];
  if (doc.type === "FeatureCollection") return (doc.features || []).flatMap(geometries);
  if (doc.type === "Feature") return doc.geometry ? [doc.geometry] : [];
  if (doc.type === "GeometryCollection") return (doc.geometries || []).flatMap(geometries);
  return [doc];
}

function fmt(x) {
  // Shortest round-trip text of a coordinate, as the server writes it.
  return String(x);
}

function ringData(ring, close) {
  if (!ring.length) return "";
  const [first, ...rest] = ring;
  let d = `M${fmt(first[0])} ${fmt(first[1])}`;
  if (rest.length) d += "L" + rest.map((p) => `${fmt(p[0])} ${fmt(p[1])}`).join(" ");
  return close ? d + "Z" : d;
}

function geometryShapes(geom) {
  // [{d, kind}] to draw one GeoJSON geometry; kind is "point", "line" or "area".
  const c = geom.coordinates;
  switch (geom.type) {
    case "Point": return c && c.length ? [{ d: `M${fmt(c[0])} ${fmt(c[1])}Z`, kind: "point" }] : [];
    case "MultiPoint": return c.map((p) => ({ d: `M${fmt(p[0])} ${fmt(p[1])}Z`, kind: "point" }));
    case "LineString": return c.length ? [{ d: ringData(c, false), kind: "line" }] : [];
    case "MultiLineString": return c.filter((l) => l.length).map((l) => ({ d: ringData(l, false), kind: "line" }));
    case "Polygon": return c.length ? [{ d: c.map((r) => ringData(r, true)).join(""), kind: "area" }] : [];
    case "MultiPolygon": return c.filter((p) => p.length).map((p) => ({ d: p.map((r) => ringData(r, true)).join(""), kind: "area" }));
    case "GeometryCollection": return (geom.geometries || []).flatMap(geometryShapes);
    default: throw new InputError(`Unknown geometry type ${JSON.stringify(geom.type)}.`);
  }
}

function drawShapes(layer, shapes, fillRule) {
  layer.replaceChildren(...shapes.map(({ d, kind }) => {
    const path = document.createElementNS(SVG_NS, "path");
    path.setAttribute("d", d);
    if (kind) path.setAttribute("class", kind);
    if (fillRule) path.setAttribute("fill-rule", fillRule);
    return path;
  }));
}

function svgShapes(paths) {
  const fill = $("fill").value;
  return paths.filter((d) => d).map((d) => ({ d, kind: fill ? "area" : "line" }));
}

function drawInput() {
  const layer = $("input-layer");
  if (state.format === "geojson") {
    drawShapes(layer, geometries(state.geojson).flatMap(geometryShapes), "evenodd");
  } else if (state.format === "svg") {
    drawShapes(layer, svgShapes(state.paths), $("fill").value || null);
  } else {
    layer.replaceChildren();
  }
}

function loadInput({ keepWindow }) {
  let parsed;
  state.inputError = false;
  $("error").hidden = true;
  try {
    parsed = parseInput($("input-text").value);
    Object.assign(state, { format: parsed.format, geojson: parsed.geojson || null,
                           geojsonText: parsed.text || null, paths: parsed.paths || null });
    document.body.classList.toggle("format-geojson", state.format === "geojson");
    document.body.classList.toggle("format-svg", state.format === "svg");
    world.setAttribute("transform", state.format === "geojson" ? "scale(1 -1)" : "");
    drawInput();
  } catch (e) {
    if (!(e instanceof InputError)) throw e;
    Object.assign(state, { format: null, geojson: null, geojsonText: null, paths: null,
                           inputError: true });
    $("input-layer").replaceChildren();
    clearResult();
    if (state.view === "tiles") tiles.showInput();
    showError({ title: "Input not readable", detail: e.message });
    setState("error");
    return;
  }
  const info = $("input-info");
  if (!state.format) {
    info.textContent = "";
    clearResult();
    offerOptions();
    if (state.view === "tiles") tiles.showInput();
    setState("idle");
    return;
  }
  if (state.format === "geojson") {
    const m = measure(state.geojson);
    info.textContent = `GeoJSON: ${count(m.geometries)} geometries, ${count(m.vertices)} vertices`;
  } else {
    info.textContent = `SVG path data: ${count(state.paths.length)} path(s)` +
      (state.capabilities && !state.capabilities.svg ? " (this server has no SVG clipping)" : "");
  }
  if (parsed.warning) info.innerHTML += ` <span class="warning">${escapeHtml(parsed.warning)}</span>`;
  offerOptions();
  if (state.view === "tiles") {  // the clip view is hidden: its window waits until shown
    tiles.showInput();
    return;
  }
  const box = $("input-layer").getBBox();
  if (!keepWindow || !overlaps(state.window, box)) {
    // The middle half of the input; a flat input (a horizontal line) still gets a window.
    const size = Math.max(box.width, box.height) || 1;
    const w = Math.max(box.width, size / 2) / 4, h = Math.max(box.height, size / 2) / 4;
    const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
    setWindow(roundWindow([cx - w, cy - h, cx + w, cy + h], { width: size, height: size }));
  }
  fitView();
  requestClip();
}

// --- options offered for the input --------------------------------------------------

function inputOperations() {
  // The kinds of input (keys of /v1/capabilities' "operations") the loaded input holds;
  // points take any method and mode.
  if (state.format === "svg") return ["paths"];
  if (state.format !== "geojson") return [];
  const kinds = new Set();
  for (const g of geometries(state.geojson)) {
    if (g.type === "LineString" || g.type === "MultiLineString") kinds.add("lines");
    if (g.type === "Polygon" || g.type === "MultiPolygon") kinds.add("polygons");
  }
  return [...kinds];
}

function offerOptions() {
  // Offer only the methods and modes the server accepts for this input (a polygon
  // refuses approx mode; curves take method rnsca only): the others are disabled, with
  // the reason, and a choice no longer offered falls back to the first one that is.
  const operations = (state.capabilities && state.capabilities.operations) || {};
  const kinds = inputOperations().filter((kind) => kind in operations);
  const notes = [];
  for (const [id, key] of [["method", "methods"], ["mode", "modes"]]) {
    const select = $(id);
    for (const option of select.options) {
      const refusing = kinds.filter((kind) => !operations[kind][key].includes(option.value));
      option.disabled = refusing.length > 0;
      option.textContent = option.value + (refusing.length ? ` (not for ${refusing.join(", ")})` : "");
      option.title = refusing.length ? `the server refuses ${id} ${option.value} for ${refusing.join(" and ")}` : "";
    }
    if (select.selectedOptions[0] && select.selectedOptions[0].disabled) {
      const first = [...select.options].find((o) => !o.disabled);
      if (first) select.value = first.value;
    }
    for (const kind of kinds) {
      const accepted = operations[kind][key];
      if (accepted.length < select.options.length) notes.push(`${kind}: ${id} ${accepted.join(" or ")} only`);
    }
  }
  $("options-note").textContent = notes.length ? `For this input, ${notes.join("; ")}.` : "";
}

function overlaps(w, box) {
  return w.every(Number.isFinite) && w[0] < box.x + box.width && w[2] > box.x &&
         w[1] < box.y + box.height && w[3] > box.y;
}

// --- view and window -------------------------------------------------------------

function fitView() {
  let box;
  try {
    box = $("input-layer").getBBox();
  } catch {
    box = { x: 0, y: 0, width: 0, height: 0 };
  }
  let [x0, y0, x1, y1] = [box.x, box.y, box.x + box.width, box.y + box.height];
  if (state.window.every(Number.isFinite)) {
    x0 = Math.min(x0, state.window[0]); y0 = Math.min(y0, state.window[1]);
    x1 = Math.max(x1, state.window[2]); y1 = Math.max(y1, state.window[3]);
  }
  const pad = 0.05 * Math.max(x1 - x0, y1 - y0, 1e-9);
  [x0, y0, x1, y1] = [x0 - pad, y0 - pad, x1 + pad, y1 + pad];
  const top = state.format === "geojson" ? -y1 : y0;
  canvas.setAttribute("viewBox", `${x0} ${top} ${x1 - x0} ${y1 - y0}`);
  const backdrop = $("backdrop");
  const w = x1 - x0, h = y1 - y0;
  // The backdrop shows "outside the window"; larger than the view, which 'meet' may widen.
  for (const [k, v] of [["x", x0 - 10 * w], ["y", top - 10 * h], ["width", 21 * w], ["height", 21 * h]]) {
    backdrop.setAttribute(k, v);
  }
  state.viewSize = Math.max(w, h);
  drawWindow();
}

function worldPoint(event) {
  const p = canvas.createSVGPoint();
  p.x = event.clientX;
  p.y = event.clientY;
  return p.matrixTransform(world.getScreenCTM().inverse());
}

function pixelSize() {
  const m = world.getScreenCTM();
  return m ? 1 / Math.hypot(m.a, m.b) : 1;
}

// Each handle moves the bounds it names; a missing axis stays at the middle.
const HANDLES = [["xmin", "ymin"], ["xmax", "ymin"], ["xmin", "ymax"], ["xmax", "ymax"],
                 ["xmin", null], ["xmax", null], [null, "ymin"], [null, "ymax"]];

function drawWindow() {
  const [x0, y0, x1, y1] = state.window;
  const valid = state.window.every(Number.isFinite) && x0 < x1 && y0 < y1;
  for (const id of ["window-rect", "window-fill"]) {
    const r = $(id);
    r.style.display = valid ? "" : "none";
    if (valid) {
      r.setAttribute("x", x0); r.setAttribute("y", y0);
      r.setAttribute("width", x1 - x0); r.setAttribute("height", y1 - y0);
    }
  }
  const handles = $("handles");
  if (!valid) { handles.replaceChildren(); return; }
  const radius = HANDLE_PX * pixelSize();
  const at = { xmin: x0, xmax: x1, ymin: y0, ymax: y1 };
  handles.replaceChildren(...HANDLES.map(([hx, hy]) => {
    const c = document.createElementNS(SVG_NS, "circle");
    c.setAttribute("cx", hx ? at[hx] : (x0 + x1) / 2);
    c.setAttribute("cy", hy ? at[hy] : (y0 + y1) / 2);
    c.setAttribute("r", radius);
    c.dataset.handle = [hx, hy].filter(Boolean).join(",");
    c.style.cursor = hx && hy ? "nwse-resize" : hx ? "ew-resize" : "ns-resize";
    return c;
  }));
}

function roundWindow(bounds, box) {
  // Round to about a thousandth of the view, so the inputs show short numbers and the
  // request sends exactly what they show.
  const size = box ? Math.max(box.width, box.height) : state.viewSize || 1;
  const digits = Math.max(0, -Math.floor(Math.log10(size / 1000)));
  const step = 10 ** -digits;
  return bounds.map((v) => Number((Math.round(v / step) * step).toFixed(Math.min(digits, 20))));
}

function setWindow(bounds) {
  state.window = bounds.slice();
  BOUNDS.forEach((name, i) => { $(name).value = Number.isFinite(bounds[i]) ? String(bounds[i]) : ""; });
  drawWindow();
}

function readWindowInputs() {
  state.window = BOUNDS.map((name) => {
    const text = $(name).value.trim();
    return text === "" ? NaN : Number(text);
  });
  drawWindow();
}

function startDrag(event) {
  const target = event.target;
  let keys;
  if (target.dataset && target.dataset.handle) keys = target.dataset.handle.split(",");
  else if (target.id === "window-rect") keys = BOUNDS;
  else return;
  event.preventDefault();
  canvas.setPointerCapture(event.pointerId);
  state.drag = { keys, start: worldPoint(event), from: state.window.slice(), pointer: event.pointerId };
}

function moveDrag(event) {
  const drag = state.drag;
  if (!drag || event.pointerId !== drag.pointer) return;
  const p = worldPoint(event);
  const dx = p.x - drag.start.x, dy = p.y - drag.start.y;
  const next = drag.from.slice();
  for (const key of drag.keys) {
    const i = BOUNDS.indexOf(key);
    next[i] = drag.from[i] + (i % 2 === 0 ? dx : dy);
  }
  // Keep the window at least a few pixels wide: a handle pushed past the opposite edge stops.
  const least = 4 * pixelSize();
  for (const [lo, hi] of [[0, 2], [1, 3]]) {
    if (next[hi] - next[lo] < least) {
      if (drag.keys.includes(BOUNDS[lo]) && !drag.keys.includes(BOUNDS[hi])) next[lo] = next[hi] - least;
      else next[hi] = next[lo] + least;
    }
  }
  setWindow(roundWindow(next));
  if ($("auto").checked) requestClip();
}

function endDrag(event) {
  if (!state.drag || event.pointerId !== state.drag.pointer) return;
  state.drag = null;
  canvas.releasePointerCapture(event.pointerId);
  requestClip();
}

// --- the request -----------------------------------------------------------------

function numberInput(id, parse) {
  const text = $(id).value.trim();
  return text === "" ? undefined : parse(text);
}

function buildRequest() {
  const options = { method: $("method").value, mode: $("mode").value };
  const n = numberInput("n", Number);
  if (n !== undefined) options.n = n;
  const depth = numberInput("max_depth", Number);
  if (depth !== undefined) options.max_depth = depth;
  const tolerance = numberInput("tolerance", Number);
  if (tolerance !== undefined) options.tolerance = tolerance;
  if ($("backend").value) options.backend = $("backend").value;
  // Window bounds that are not numbers go as null: the server names the bad one.
  const body = { window: state.window.map((v) => (Number.isFinite(v) ? v : null)) };
  const approx = options.mode === "approx";
  if (state.format === "geojson") {
    options.boundary = $("boundary").value;
    body.geojson = state.geojson;
    body.options = options;
    const bound = numberInput("approx_bound", Number);
    if (approx && bound !== undefined) body.approx_bound = bound;
    // Approx results are only judged against a bound: without one, leave it to the server.
    if (!$("verify").checked) body.verify = false;
    else if (!approx || bound !== undefined) body.verify = true;
  } else {
    options.curves = $("curves").value;
    options.fill = $("fill").value || null;
    body.paths = state.paths;
    body.options = options;
    if (!$("verify").checked) body.verify = false;
  }
  return body;
}

function requestClip() {
  if (!state.format) {  // nothing to clip: no input, or one that could not be read
    if (!state.inFlight) setState(state.inputError ? "error" : "idle");
    return;
  }
  if (state.inFlight) {
    state.pending = true;  // one request at a time; the latest window goes next
    return;
  }
  sendClip();
}

async function sendClip() {
  state.inFlight = true;
  state.pending = false;
  setState("busy");
  const body = buildRequest();
  const format = state.format;
  const shown = JSON.stringify({ ...body, geojson: undefined, paths: undefined }, null, 1);
  $("request").textContent = `POST ${API[format]}\n${shown}\n(+ the input as "${format === "geojson" ? "geojson" : "paths"}")`;
  const started = performance.now();
  let ok = false;
  try {
    const response = await fetch(API[format], {
      method: "POST", headers: { "Content-Type": "application/json", Accept: "application/json" },
      body: JSON.stringify(body),
    });
    const text = await response.text();
    let data;
    try {
      data = JSON.parse(text);
    } catch {
      data = { title: response.statusText, detail: text.slice(0, 500) };
    }
    const elapsed = performance.now() - started;
    $("results").dataset.window = JSON.stringify(body.window);
    if (response.ok) {
      showResult(format, data, body);
      $("status").textContent = `${response.status} in ${elapsed.toFixed(0)} ms`;
      ok = true;
    } else {
      clearResult();
      showError({ status: response.status, ...data });
      $("status").textContent = `${response.status} in ${elapsed.toFixed(0)} ms`;
    }
  } catch (e) {
    $("results").dataset.window = JSON.stringify(body.window);
    clearResult();
    showError({ title: "Could not reach the server", detail: String(e) });
  } finally {
    state.inFlight = false;
    if (state.pending && state.format) sendClip();
    else if (state.view === "clip") setState(ok ? "idle" : "error");  // (else tiles.js says)
  }
}

// --- the answer ------------------------------------------------------------------

function ringArea(ring) {
  let sum = 0;
  for (let i = 0; i + 1 < ring.length; i++) sum += ring[i][0] * ring[i + 1][1] - ring[i + 1][0] * ring[i][1];
  return Math.abs(sum) / 2;
}

function lineLength(line) {
  let sum = 0;
  for (let i = 0; i + 1 < line.length; i++) sum += Math.hypot(line[i + 1][0] - line[i][0], line[i + 1][1] - line[i][1]);
  return sum;
}

function measure(doc) {
  // Counts, length of lines and area of polygons of a GeoJSON document.
  const m = { geometries: 0, parts: 0, vertices: 0, points: 0, length: 0, area: 0 };
  const polygon = (rings) => {
    if (!rings.length) return;
    m.parts += 1;
    m.area += ringArea(rings[0]) - rings.slice(1).reduce((s, r) => s + ringArea(r), 0);
    m.vertices += rings.reduce((s, r) => s + r.length, 0);
  };
  const line = (coords) => {
    if (!coords.length) return;
    m.parts += 1;
    m.vertices += coords.length;
    m.length += lineLength(coords);
  };
  const visit = (g) => {
    const c = g.coordinates;
    switch (g.type) {
      case "Point": if (c && c.length) { m.points += 1; m.vertices += 1; } break;
      case "MultiPoint": m.points += c.length; m.vertices += c.length; break;
      case "LineString": line(c); break;
      case "MultiLineString": c.forEach(line); break;
      case "Polygon": polygon(c); break;
      case "MultiPolygon": c.forEach(polygon); break;
      case "GeometryCollection": (g.geometries || []).forEach(visit); break;
      default: break;
    }
  };
  for (const g of geometries(doc)) {
    const before = m.vertices;
    visit(g);
    if (m.vertices > before) m.geometries += 1;
  }
  return m;
}

function showResult(format, data, body) {
  $("error").hidden = true;
  keepResult(format, data, body);
  const summary = [];
  if (format === "geojson") {
    drawShapes($("output-layer"), geometries(data.geojson).flatMap(geometryShapes), "evenodd");
    const m = measure(data.geojson);
    summary.push(["geometries", m.geometries], ["parts", m.parts], ["vertices", m.vertices]);
    if (m.points) summary.push(["points", m.points]);
    if (m.length) summary.push(["length", m.length]);
    if (m.area) summary.push(["area", m.area]);
  } else {
    const fillRule = body.options.fill;
    drawShapes($("output-layer"), svgShapes(data.paths), fillRule || null);
    const drawn = [...$("output-layer").children];
    const length = drawn.reduce((s, p) => s + p.getTotalLength(), 0);
    summary.push(["paths", data.paths.filter((d) => d).length],
                 ["subpaths", data.paths.reduce((s, d) => s + (d.match(/[Mm]/g) || []).length, 0)],
                 ["outline length", length]);
  }
  $("summary").replaceChildren(...summary.flatMap(([key, value]) => {
    const dt = document.createElement("dt");
    dt.textContent = key;
    const dd = document.createElement("dd");
    dd.dataset.key = key.replace(/ /g, "_");
    dd.dataset.value = String(value);
    dd.textContent = Number.isInteger(value) ? count(value) : value.toPrecision(8);
    return [dt, dd];
  }));
  showStats(data.stats);
  showVerification(data.verification, format, body);
}

function showStats(stats) {
  const rows = STAT_KEYS.filter((k) => k in stats).map((key) => {
    const tr = document.createElement("tr");
    tr.dataset.key = key;
    const name = document.createElement("td");
    name.textContent = key.replace(/_/g, " ");
    const value = document.createElement("td");
    value.dataset.value = String(stats[key]);
    value.textContent = Number.isInteger(stats[key]) ? count(stats[key])
                                                      : Number(stats[key]).toFixed(3);
    tr.append(name, value);
    return tr;
  });
  $("stats").tBodies[0].replaceChildren(...rows);
  drawLevels(stats.decided_per_level || []);
}

function drawLevels(levels) {
  // Bars of the fragments decided at each subdivision level, up to the deepest used.
  let last = levels.length - 1;
  while (last > 0 && !levels[last]) last--;
  const shown = levels.slice(0, last + 1);
  const box = $("levels");
  if (!shown.some((v) => v)) { box.replaceChildren(); return; }
  const peak = Math.max(...shown);
  const svg = document.createElementNS(SVG_NS, "svg");
  const width = Math.max(shown.length, 4) * 22;
  svg.setAttribute("viewBox", `0 0 ${width} 60`);
  svg.setAttribute("preserveAspectRatio", "xMinYMid meet");
  shown.forEach((v, i) => {
    const h = v ? Math.max(1, (v / peak) * 40) : 0;
    const r = document.createElementNS(SVG_NS, "rect");
    Object.entries({ x: i * 22 + 2, y: 46 - h, width: 18, height: h }).forEach(([k, a]) => r.setAttribute(k, a));
    const title = document.createElementNS(SVG_NS, "title");
    title.textContent = `level ${i}: ${count(v)} fragments decided`;
    r.append(title);
    const t = document.createElementNS(SVG_NS, "text");
    t.setAttribute("x", i * 22 + 11); t.setAttribute("y", 57); t.setAttribute("text-anchor", "middle");
    t.textContent = i;
    svg.append(r, t);
  });
  const caption = document.createElement("div");
  caption.className = "note";
  caption.textContent = "fragments decided per subdivision level";
  box.replaceChildren(caption, svg);
}

function showVerification(v, format, body) {
  const box = $("verification");
  if (!v) {
    let why = "not verified";
    if (body.verify === false) why += " (verify is off)";
    else if (body.options.mode === "approx") {
      why += format === "geojson" ? ": approx mode is judged against a bound; set an approx bound"
                                  : " (approx mode)";
    } else if (state.capabilities) {
      why += ` (the input is over the server's verify_max_vertices, ${count(state.capabilities.limits.verify_max_vertices)})`;
    }
    box.innerHTML = `<p class="note">${escapeHtml(why)}</p>`;
    box.dataset.passed = "";
    return;
  }
  box.dataset.passed = String(v.passed);
  const rows = [["max deviation", v.max_deviation], ["allowed deviation", v.allowed_deviation],
                ["false positives", v.false_positives], ["ratio to Shapely", v.ratio],
                ["valid output", v.valid], ["mode", v.mode],
                ["inputs compared", `${count(v.checked)} of ${count(v.inputs)}`]];
  // null: not every input chosen was compared (time limit, or too costly), none failed.
  const [verdict, text] = v.passed === null ? ["undecided", "? no verdict"]
    : v.passed ? ["passed", "✓ passed"] : ["failed", "✗ failed"];
  box.innerHTML = `<p class="verdict ${verdict}">${text}</p>` +
    "<table>" + rows.map(([k, value]) => `<tr><td>${k}</td><td>${escapeHtml(
      typeof value !== "number" ? String(value) : Number.isInteger(value) ? count(value)
        : value.toPrecision(6))}</td></tr>`).join("") +
    "</table>" + (v.note ? `<p class="note">${escapeHtml(v.note)}</p>` : "");
}

// --- copy and download -------------------------------------------------------------

function svgDocument(paths, window, fill) {
  // The clipped paths as an SVG document whose view is the clip window.
  const [x0, y0, x1, y1] = window;
  const paint = fill ? `fill="black" fill-rule="${fill}"`
    : 'fill="none" stroke="black" stroke-width="1" vector-effect="non-scaling-stroke"';
  return `<svg xmlns="${SVG_NS}" viewBox="${x0} ${y0} ${x1 - x0} ${y1 - y0}">\n` +
    paths.filter((d) => d).map((d) => `<path d="${escapeHtml(d)}" ${paint}/>\n`).join("") +
    "</svg>\n";
}

function keepResult(format, data, body) {
  state.result = format === "geojson"
    ? { text: JSON.stringify(data.geojson), type: "application/geo+json",
        filename: "clipped.geojson", label: "GeoJSON" }
    : { text: svgDocument(data.paths, body.window, body.options.fill), type: "image/svg+xml",
        filename: "clipped.svg", label: "SVG" };
  $("copy").textContent = `Copy ${state.result.label}`;
  $("download").textContent = `Download .${state.result.filename.split(".").pop()}`;
  $("download").title = `save as ${state.result.filename}`;
  $("copy").disabled = $("download").disabled = false;
  $("copy-status").textContent = "";
  delete $("copy-status").dataset.copied;
}

async function copyResult() {
  const result = state.result;
  if (!result) return;
  const status = $("copy-status");
  try {
    await navigator.clipboard.writeText(result.text);
    status.textContent = `${result.label} copied (${count(result.text.length)} characters)`;
    status.dataset.copied = "true";
  } catch (e) {  // no clipboard (a page not served over https or from localhost), or denied
    status.textContent = `Could not copy: ${e.message}; use Download`;
    status.dataset.copied = "false";
  }
}

function downloadResult() {
  const result = state.result;
  if (!result) return;
  const url = URL.createObjectURL(new Blob([result.text], { type: result.type }));
  const link = document.createElement("a");
  link.href = url;
  link.download = result.filename;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60_000);  // once the download has read it
}

function clearResult() {
  state.result = null;
  $("copy").disabled = $("download").disabled = true;
  $("copy-status").textContent = "";
  delete $("copy-status").dataset.copied;
  $("output-layer").replaceChildren();
  $("summary").replaceChildren();
  $("stats").tBodies[0].replaceChildren();
  $("levels").replaceChildren();
  $("verification").replaceChildren();
  delete $("verification").dataset.passed;
}

function showError(problem) {
  const box = $("error");
  const lines = [`<div class="title">${escapeHtml(
    [problem.status, problem.title].filter((x) => x !== undefined && x !== "").join(" "))}</div>`];
  if (problem.detail) lines.push(`<div class="detail">${escapeHtml(problem.detail)}</div>`);
  if (problem.path) lines.push(`<div>at <code class="path">${escapeHtml(problem.path)}</code></div>`);
  if (problem.position !== undefined && problem.position !== null) {
    lines.push(`<div>at character ${escapeHtml(String(problem.position))}</div>`);
  }
  if (Array.isArray(problem.errors) && problem.errors.length > 1) {
    lines.push("<ul>" + problem.errors.map((e) =>
      `<li><code>${escapeHtml(e.path || "")}</code>: ${escapeHtml(e.message || "")}</li>`).join("") + "</ul>");
  }
  if (problem.type) lines.push(`<div class="note">${escapeHtml(problem.type)}</div>`);
  box.innerHTML = lines.join("");
  box.hidden = false;
}

function escapeHtml(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
}

function setState(value) {
  document.body.dataset.state = value;
}

// --- set-up ----------------------------------------------------------------------

function fillSelect(select, values, chosen) {
  select.replaceChildren(...values.map(({ value, label, disabled, title }) => {
    const option = document.createElement("option");
    option.value = value;
    option.textContent = label ?? value;
    option.disabled = Boolean(disabled);
    if (title) option.title = title;
    option.selected = value === chosen;
    return option;
  }));
}

async function loadCapabilities() {
  const response = await fetch(API.capabilities, { headers: { Accept: "application/json" } });
  if (!response.ok) throw new Error(`GET ${API.capabilities} answered ${response.status}`);
  const caps = await response.json();
  state.capabilities = caps;
  fillSelect($("method"), caps.methods.map((m) => ({ value: m })), "rnsca");
  fillSelect($("mode"), caps.modes.map((m) => ({ value: m })), "exact");
  fillSelect($("backend"), [{ value: "", label: "server default" }, ...caps.backends.map((b) => ({
    value: b.name, label: b.available ? b.name : `${b.name} (not available)`,
    disabled: !b.available, title: b.reason || (b.devices || []).join(", "),
  }))], "");
  $("server-version").textContent = `rnsca ${caps.version}`;
  const l = caps.limits;
  $("limits").textContent = `Server limits: ${count(l.max_vertices)} vertices, ` +
    `${count(l.max_body_bytes)} bytes per request; verified by default up to ` +
    `${count(l.verify_max_vertices)} vertices.`;
}

async function loadExamples() {
  const response = await fetch(EXAMPLES + "index.json");
  state.examples = await response.json();
  const select = $("example");
  for (const ex of state.examples) {
    const option = document.createElement("option");
    option.value = ex.id;
    option.textContent = ex.title;
    select.append(option);
  }
}

async function chooseExample(id) {
  const ex = state.examples.find((e) => e.id === id);
  if (!ex) return;
  setState("loading");
  let text;
  try {
    const response = await fetch(EXAMPLES + ex.file);
    if (!response.ok) throw new Error(`${response.status} ${response.statusText}`);
    text = await response.text();
  } catch (e) {
    showError({ title: `Could not load the example ${ex.file}`, detail: String(e) });
    setState("error");
    return;
  }
  $("input-text").value = text;
  tiles.newInput();
  $("fill").value = ex.options.fill || "";
  $("curves").value = ex.options.curves || "preserve";
  $("example-about").textContent = ex.about;
  state.window = ex.window.slice();
  setWindow(ex.window);
  loadInput({ keepWindow: true });
}

function onOptionChange() {
  if (state.format === "svg") drawInput();  // the fill rule changes how the input is drawn
  if ($("auto").checked && state.format) requestClip();
  else if (!state.inFlight) setState("idle");
}

function showView(name) {
  // Switch between the clip view and the tile view; the input is drawn again for it.
  state.view = name;
  if (name !== "tiles") tiles.hide();
  document.body.classList.toggle("view-tiles", name === "tiles");
  $("status").textContent = "";
  $("request").textContent = "";
  loadInput({ keepWindow: true });
}

async function main() {
  tiles = createTileView({ $, state, setState, showError, geometries, geometryShapes,
                           drawShapes, count });
  for (const radio of document.querySelectorAll('input[name="view"]')) {
    radio.addEventListener("change", (e) => { if (e.target.checked) showView(e.target.value); });
  }
  canvas.addEventListener("pointerdown", startDrag);
  canvas.addEventListener("pointermove", moveDrag);
  canvas.addEventListener("pointerup", endDrag);
  canvas.addEventListener("pointercancel", endDrag);
  window.addEventListener("resize", drawWindow);
  $("example").addEventListener("change", (e) => chooseExample(e.target.value));
  $("file").addEventListener("change", async (e) => {
    const file = e.target.files[0];
    if (!file) return;
    setState("loading");
    $("input-text").value = await file.text();
    tiles.newInput();
    $("example").value = "";
    $("example-about").textContent = `from ${file.name}`;
    loadInput({ keepWindow: true });
  });
  // Typing is debounced; the page says it is not idle from the first keystroke.
  const later = (action, ms) => () => {
    clearTimeout(state.inputTimer);
    setState("loading");
    state.inputTimer = setTimeout(action, ms);
  };
  $("input-text").addEventListener("input", later(() => loadInput({ keepWindow: true }), 400));
  const windowChanged = () => {
    readWindowInputs();
    if ($("auto").checked) requestClip();
    else setState("idle");
  };
  for (const name of BOUNDS) {
    $(name).addEventListener("input", later(windowChanged, 300));
    $(name).addEventListener("change", () => { clearTimeout(state.inputTimer); windowChanged(); });
  }
  for (const id of ["method", "mode", "backend", "boundary", "curves", "fill", "verify"]) {
    $(id).addEventListener("change", onOptionChange);
  }
  for (const id of ["n", "max_depth", "tolerance", "approx_bound"]) {
    $(id).addEventListener("input", later(onOptionChange, 300));
    $(id).addEventListener("change", () => { clearTimeout(state.inputTimer); onOptionChange(); });
  }
  $("clip").addEventListener("click", requestClip);
  $("copy").addEventListener("click", copyResult);
  $("download").addEventListener("click", downloadResult);
  $("fit").addEventListener("click", fitView);
  try {
    await Promise.all([loadCapabilities(), loadExamples()]);
    offerOptions();
  } catch (e) {
    showError({ title: "Could not load the playground", detail: String(e) });
    setState("error");
    return;
  }
  setState("idle");
}

main();
