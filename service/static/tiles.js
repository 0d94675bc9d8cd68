// The playground's tile view: the GeoJSON input (lon/lat) drawn in Web Mercator with the
// WebMercatorQuad tile grid of one zoom over it, and a click on a tile asks
// POST /v1/tiles/{z}/{x}/{y} for it and shows its decoded content (mvt.js).
//
// Coordinates: the grid is drawn in 256 units per tile of the chosen zoom, from the
// top-left corner of its first tile (x east, y south), so every tile is the same square
// and the numbers stay small at any zoom. A decoded tile is drawn in its own units (0..extent,
// y down), the buffer around it.
//
// Test hooks: #grid-tiles rect[data-tile="z/x/y"] are the tiles drawn; #tile-result has
// data-tile and data-bytes of the tile shown, and #tile-json its decoded content (JSON:
// {tile, bytes, layers: [{name, version, extent, keys, values, features: [{id, type,
// properties, geometry}]}]}, geometry as GeoJSON in tile coordinates).

import { decodeTile, tileJson } from "./mvt.js";

const API = "v1/tiles";
const MAX_ZOOM = 24;                 // as the route accepts
const MAX_GRID_TILES = 1024;         // more are not drawn (a note says which zoom fits)
const FIT_TILES = 16;                // a fitted zoom shows at most this many tiles
const FIT_MAX_ZOOM = 18;
const MAX_LATITUDE = 85.0511287798066;  // Web Mercator's edge: atan(sinh(pi)), degrees
const MAX_LISTED = 200;              // features listed per layer (the JSON has them all)
const CELL = 256;                    // drawing units per tile of the grid

export function lonLatToWorld([lon, lat]) {
  // World coordinates of WebMercatorQuad on the unit square: x east from the
  // antimeridian, y south from the top edge; latitudes clamped to the square.
  const phi = (Math.max(-MAX_LATITUDE, Math.min(MAX_LATITUDE, lat)) * Math.PI) / 180;
  const y = 0.5 - Math.asinh(Math.tan(phi)) / (2 * Math.PI);
  return [(lon + 180) / 360, Math.max(0, Math.min(1, y))];  // (tan rounds at the edge)
}

export function tileRange(box, z) {
  // The tiles of zoom z that the world box [x0, y0, x1, y1] touches: the tile holding
  // its top-left corner to the one holding its bottom-right (an edge on a tile line
  // belongs to the tile east / south of it, as for a point), clamped to the world.
  const n = 2 ** z;
  const clamp = (v) => Math.max(0, Math.min(n - 1, v));
  const x0 = clamp(Math.floor(box[0] * n)), y0 = clamp(Math.floor(box[1] * n));
  const x1 = clamp(Math.max(Math.floor(box[0] * n), Math.ceil(box[2] * n) - 1));
  const y1 = clamp(Math.max(Math.floor(box[1] * n), Math.ceil(box[3] * n) - 1));
  return { z, x0, y0, x1, y1, count: (x1 - x0 + 1) * (y1 - y0 + 1) };
}

export function createTileView(ui) {
  // ui: the page's shared helpers ($, state, setState, showError, geometries,
  // geometryShapes, drawShapes, count).
  const { $ } = ui;
  const SVG_NS = "http://www.w3.org/2000/svg";
  // box: the input's world bounds; projected: its geometries in world coordinates;
  // range: the tiles drawn; selected: the tile shown; latest: the number of the last
  // tile request (older answers are dropped).
  const view = { box: null, projected: [], range: null, selected: null, latest: 0,
                 zoomChosen: false };

  function project(geom) {
    // A copy of a GeoJSON geometry in world coordinates.
    const map = (c) => (typeof c[0] === "number" ? lonLatToWorld(c) : c.map(map));
    if (geom.type === "GeometryCollection") {
      return { ...geom, geometries: (geom.geometries || []).map(project) };
    }
    return { ...geom, coordinates: geom.coordinates ? map(geom.coordinates) : [] };
  }

  function worldBox(projected) {
    let box = [Infinity, Infinity, -Infinity, -Infinity];
    const visit = (c) => {
      if (typeof c[0] === "number") {
        box = [Math.min(box[0], c[0]), Math.min(box[1], c[1]),
               Math.max(box[2], c[0]), Math.max(box[3], c[1])];
      } else c.forEach(visit);
    };
    const walk = (g) => (g.type === "GeometryCollection" ? g.geometries.forEach(walk)
                                                         : visit(g.coordinates));
    projected.forEach(walk);
    return box.every(Number.isFinite) ? box : null;
  }

  function fitZoom(box) {
    let z = 0;
    while (z < FIT_MAX_ZOOM && tileRange(box, z + 1).count <= FIT_TILES) z += 1;
    return z;
  }

  function options() {
    return { z: Number($("zoom").value), extent: $("tile-extent").value.trim(),
             buffer: $("tile-buffer").value.trim() };
  }

  // --- the grid ---------------------------------------------------------------------

  function showInput() {
    // Draw the input (the page's state) and the grid; the tile shown stays if the grid
    // still has it (asked again, for the new input), else it is cleared.
    const state = ui.state;
    const note = $("grid-note");
    if (state.format !== "geojson") {
      view.box = view.range = null;
      $("grid-input").replaceChildren();
      $("grid-tiles").replaceChildren();
      note.textContent = state.format === "svg"
        ? "The tile view takes GeoJSON in lon/lat (EPSG:4326); this input is SVG path data." : "";
      dropTile();
      ui.setState(state.inputError ? "error" : "idle");
      return;
    }
    const projected = ui.geometries(state.geojson).map(project);
    view.box = worldBox(projected);
    if (view.box && (!view.zoomChosen || tileRange(view.box, options().z).count > MAX_GRID_TILES)) {
      $("zoom").value = String(fitZoom(view.box));
    }
    view.projected = projected;
    drawGrid();
    if (view.selected && inRange(view.selected)) requestTile(view.selected);
    else {
      dropTile();
      ui.setState("idle");
    }
  }

  function inRange({ z, x, y }) {
    const r = view.range;
    return r !== null && r.z === z && x >= r.x0 && x <= r.x1 && y >= r.y0 && y <= r.y1;
  }

  function drawGrid() {
    const note = $("grid-note");
    const tiles = $("grid-tiles");
    if (!view.box) {
      view.range = null;
      $("grid-input").replaceChildren();
      tiles.replaceChildren();
      note.textContent = "The input has no coordinates.";
      return;
    }
    const { z } = options();
    const range = tileRange(view.box, z);
    const n = 2 ** z;
    // Grid units: CELL per tile of zoom z, from the first tile's corner.
    const toGrid = (c) => (typeof c[0] === "number"
      ? [(c[0] * n - range.x0) * CELL, (c[1] * n - range.y0) * CELL] : c.map(toGrid));
    const inGrid = (g) => (g.type === "GeometryCollection"
      ? { ...g, geometries: g.geometries.map(inGrid) } : { ...g, coordinates: toGrid(g.coordinates) });
    ui.drawShapes($("grid-input"), view.projected.map(inGrid).flatMap(ui.geometryShapes), "evenodd");
    const [w, h] = [(range.x1 - range.x0 + 1) * CELL, (range.y1 - range.y0 + 1) * CELL];
    const pad = 0.04 * Math.max(w, h);
    $("grid-canvas").setAttribute("viewBox", `${-pad} ${-pad} ${w + 2 * pad} ${h + 2 * pad}`);
    if (range.count > MAX_GRID_TILES) {
      view.range = null;
      tiles.replaceChildren();
      let fits = z;
      while (fits > 0 && tileRange(view.box, fits).count > MAX_GRID_TILES) fits -= 1;
      note.textContent = `The input touches ${ui.count(range.count)} tiles at zoom ${z}: ` +
        `the grid is drawn up to ${ui.count(MAX_GRID_TILES)} tiles (zoom ${fits} or less).`;
      return;
    }
    view.range = range;
    const cells = [];
    for (let y = range.y0; y <= range.y1; y++) {
      for (let x = range.x0; x <= range.x1; x++) {
        const id = `${z}/${x}/${y}`;
        const g = document.createElementNS(SVG_NS, "g");
        const rect = document.createElementNS(SVG_NS, "rect");
        Object.entries({ x: (x - range.x0) * CELL, y: (y - range.y0) * CELL, width: CELL,
                         height: CELL, tabindex: 0,
                         role: "button", "aria-label": `tile ${id}` })
          .forEach(([k, v]) => rect.setAttribute(k, v));
        rect.dataset.tile = id;
        if (view.selected && `${view.selected.z}/${view.selected.x}/${view.selected.y}` === id) {
          rect.classList.add("selected");
        }
        const label = document.createElementNS(SVG_NS, "text");
        label.setAttribute("x", (x - range.x0 + 0.5) * CELL);
        label.setAttribute("y", (y - range.y0 + 0.5) * CELL);
        label.textContent = id;
        g.append(rect, label);
        cells.push(g);
      }
    }
    tiles.replaceChildren(...cells);
    note.textContent = `Zoom ${z}: ${ui.count(range.count)} tile(s) over the input's bounds ` +
      `(x ${range.x0}–${range.x1}, y ${range.y0}–${range.y1}); click one to see it.`;
  }

  // --- one tile ---------------------------------------------------------------------

  async function requestTile(tile) {
    const state = ui.state;
    if (state.format !== "geojson") return;
    const { extent, buffer } = options();
    const id = `${tile.z}/${tile.x}/${tile.y}`;
    view.selected = tile;
    for (const rect of $("grid-tiles").querySelectorAll("rect")) {
      rect.classList.toggle("selected", rect.dataset.tile === id);
    }
    const query = new URLSearchParams();
    if (extent !== "") query.set("extent", extent);
    if (buffer !== "") query.set("buffer", buffer);
    const url = `${API}/${id}` + (query.size ? `?${query}` : "");
    const mine = ++view.latest;      // a later click wins over an answer still on its way
    ui.setState("busy");
    $("request").textContent = `POST ${url}\nContent-Type: application/geo+json\n(the input as the body)`;
    const started = performance.now();
    let ok = false;
    try {
      const response = await fetch(url, {
        method: "POST", body: state.geojsonText,
        headers: { "Content-Type": "application/geo+json",
                   Accept: "application/vnd.mapbox-vector-tile, application/problem+json" },
      });
      const bytes = new Uint8Array(await response.arrayBuffer());
      if (mine !== view.latest) return;
      $("status").textContent = `${response.status} in ${(performance.now() - started).toFixed(0)} ms`;
      if (!response.ok) {
        const text = new TextDecoder().decode(bytes);
        let problem;
        try {
          problem = JSON.parse(text);
        } catch {
          problem = { title: response.statusText, detail: text.slice(0, 500) };
        }
        clearTile();
        ui.showError({ status: response.status, ...problem });
        return;
      }
      let layers;
      try {
        layers = decodeTile(bytes);       // 204 (no feature reaches the tile): no layer
      } catch (e) {
        clearTile();
        ui.showError({ title: `Could not decode tile ${id}`, detail: e.message });
        return;
      }
      $("error").hidden = true;
      showTile(id, bytes.length, layers, Number(extent || 4096), Number(buffer || 64),
               response.headers.get("X-Rnsca-Features"));
      ok = true;
    } catch (e) {
      if (mine !== view.latest) return;
      clearTile();
      ui.showError({ title: "Could not reach the server", detail: String(e) });
    } finally {
      // Unless a later change (typing: "loading") already says the page is not done.
      if (mine === view.latest && document.body.dataset.state === "busy") {
        ui.setState(ok ? "idle" : "error");
      }
    }
  }

  function dropTile() {
    // Clear the tile shown, and forget any answer still on its way.
    view.latest += 1;
    view.selected = null;
    clearTile();
  }

  function clearTile() {
    const box = $("tile-result");
    delete box.dataset.tile;
    delete box.dataset.bytes;
    $("tile-features").replaceChildren();
    $("tile-summary").replaceChildren();
    const hint = document.createElement("p");
    hint.className = "note";
    hint.textContent = ui.state.format === "geojson" ? "Click a tile of the grid to see what it holds." : "";
    $("tile-layers").replaceChildren(hint);
    $("tile-json").textContent = "";
    $("tile-json-details").hidden = true;
    $("tile-title").textContent = "Tile";
    $("tile-canvas").style.display = "none";
  }

  function showTile(id, bytes, layers, extent, buffer, inputFeatures) {
    const box = $("tile-result");
    box.dataset.tile = id;
    box.dataset.bytes = String(bytes);
    $("tile-title").textContent = `Tile ${id}`;
    // The tile's own extent (the layer's) is drawn; the buffer is the one asked for.
    const size = layers.length ? layers[0].extent : extent;
    const margin = 0.03 * (size + 2 * buffer);
    const svg = $("tile-canvas");
    svg.style.display = "";
    svg.setAttribute("viewBox", `${-buffer - margin} ${-buffer - margin} ` +
                                `${size + 2 * (buffer + margin)} ${size + 2 * (buffer + margin)}`);
    for (const [rectId, at, side] of [["tile-buffer-rect", -buffer, size + 2 * buffer],
                                      ["tile-extent-rect", 0, size]]) {
      const rect = $(rectId);
      Object.entries({ x: at, y: at, width: side, height: side }).forEach(([k, v]) => rect.setAttribute(k, v));
    }
    const shapes = layers.flatMap((layer) => layer.features)
      .filter((f) => f.geometry.type !== "Unknown")
      .flatMap((f) => ui.geometryShapes(f.geometry));
    ui.drawShapes($("tile-features"), shapes, "evenodd");

    const features = layers.reduce((s, l) => s + l.features.length, 0);
    const summary = [["bytes", bytes], ["layers", layers.length], ["features", features]];
    if (inputFeatures !== null) summary.push(["input features", Number(inputFeatures)]);
    $("tile-summary").replaceChildren(...summary.flatMap(([key, value]) => {
      const dt = document.createElement("dt");
      dt.textContent = key;
      const dd = document.createElement("dd");
      dd.dataset.key = key.replace(/ /g, "_");
      dd.dataset.value = String(value);
      dd.textContent = ui.count(value);
      return [dt, dd];
    }));
    $("tile-layers").replaceChildren(...(layers.length ? layers.map(layerTable) : [emptyNote()]));
    $("tile-json").textContent = tileJson({ tile: id, bytes, layers });
    $("tile-json-details").hidden = false;
  }

  function emptyNote() {
    const p = document.createElement("p");
    p.className = "note";
    p.textContent = "No feature reaches this tile (204 No Content).";
    return p;
  }

  function vertices(geometry) {
    const walk = (c) => (typeof c[0] === "number" ? 1 : c.reduce((s, x) => s + walk(x), 0));
    return geometry.coordinates.length ? walk(geometry.coordinates) : 0;
  }

  function layerTable(layer) {
    const section = document.createElement("section");
    section.className = "tile-layer";
    section.dataset.layer = layer.name;
    const title = document.createElement("h3");
    title.textContent = `layer “${layer.name}”`;
    const about = document.createElement("p");
    about.className = "note";
    about.textContent = `version ${layer.version}, extent ${ui.count(layer.extent)}, ` +
      `${ui.count(layer.features.length)} feature(s), ${ui.count(layer.keys)} key(s), ` +
      `${ui.count(layer.values)} value(s)`;
    const table = document.createElement("table");
    const head = table.createTHead().insertRow();
    for (const name of ["id", "geometry", "vertices", "properties"]) {
      const th = document.createElement("th");
      th.textContent = name;
      head.append(th);
    }
    const body = table.createTBody();
    for (const feature of layer.features.slice(0, MAX_LISTED)) {
      const row = body.insertRow();
      const props = Object.entries(feature.properties)
        .map(([k, v]) => `${k}: ${tileJson(v)}`).join(", ");
      for (const text of [feature.id === null ? "–" : String(feature.id), feature.geometry.type,
                          ui.count(vertices(feature.geometry)), props]) {
        row.insertCell().textContent = text;
      }
    }
    section.append(title, about, table);
    if (layer.features.length > MAX_LISTED) {
      const more = document.createElement("p");
      more.className = "note";
      more.textContent = `… and ${ui.count(layer.features.length - MAX_LISTED)} more (all in the JSON below)`;
      section.append(more);
    }
    return section;
  }

  // --- set-up -----------------------------------------------------------------------

  function tileOf(target) {
    const rect = target.closest && target.closest("rect[data-tile]");
    if (!rect) return null;
    const [z, x, y] = rect.dataset.tile.split("/").map(Number);
    return { z, x, y };
  }

  $("zoom").replaceChildren(...Array.from({ length: MAX_ZOOM + 1 }, (_, z) => {
    const option = document.createElement("option");
    option.value = option.textContent = String(z);
    return option;
  }));
  $("zoom").value = "0";
  $("zoom").addEventListener("change", () => {
    view.zoomChosen = true;
    dropTile();
    if (view.box) drawGrid();
    if (document.body.dataset.state === "busy") ui.setState("idle");
  });
  for (const id of ["tile-extent", "tile-buffer"]) {
    $(id).addEventListener("change", () => {
      if (view.selected && inRange(view.selected)) requestTile(view.selected);
    });
  }
  $("grid-tiles").addEventListener("click", (e) => {
    const tile = tileOf(e.target);
    if (tile) requestTile(tile);
  });
  $("grid-tiles").addEventListener("keydown", (e) => {
    const tile = tileOf(e.target);
    if (tile && (e.key === "Enter" || e.key === " ")) {
      e.preventDefault();
      requestTile(tile);
    }
  });
  clearTile();

  return {
    showInput,
    newInput() { view.zoomChosen = false; view.selected = null; },
    hide() { view.latest += 1; },    // an answer still on its way is not shown
  };
}
