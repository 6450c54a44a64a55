// The 3D views of the tgsis browser view (three.js, shipped beside this file).
//
// Meshes come from /api/... as one binary body (tgsis/view/meshes.py): a uint32
// header length, a JSON header, then little-endian float32/uint32 arrays that
// become three.js buffers without a copy. After each new frame is drawn,
// document.body.dataset.frame is incremented and dataset.state is "ready"
// (the browser tests wait for it); an error shows in #status and sets
// dataset.state to "error".
import * as THREE from "three";
import { OrbitControls } from "/static/vendor/three/OrbitControls.js";

const statusBox = () => document.getElementById("status");

function setState(state, text) {
  document.body.dataset.state = state;
  const box = statusBox();
  if (box && text !== undefined) box.textContent = text;
}

// after a render: wait for the GPU (one pixel read back), then count the frame
function drawn(viewer) {
  if (viewer) {
    const gl = viewer.renderer.getContext();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
  }
  document.body.dataset.frame = String(Number(document.body.dataset.frame || "0") + 1);
}

export async function fetchMesh(url) {
  const early = window.tgsisEarly && window.tgsisEarly.get(url);   // asked for by the page before this module ran
  if (early) window.tgsisEarly.delete(url);
  const response = await (early || fetch(url));
  if (!response.ok) {
    let message = response.statusText;
    try { message = (await response.json()).error; } catch (e) { /* not JSON */ }
    throw new Error(`${response.status}: ${message}`);
  }
  const buffer = await response.arrayBuffer();
  const n = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n)));
  const arrays = {};
  let offset = 4 + n;
  for (const item of header.arrays) {
    arrays[item.name] = item.type === "uint32" ? new Uint32Array(buffer, offset, item.count)
                                               : new Float32Array(buffer, offset, item.count);
    offset += 4 * item.count;
  }
  return { header, arrays };
}

// viridis, five stops
const STOPS = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383],
               [0.993, 0.906, 0.144]];
const HIGHLIGHT = [0.9, 0.1, 0.1];
const FLAG_COLOURS = { 0: [0.75, 0.75, 0.75], 1: [1.0, 0.55, 0.0], 2: [0.15, 0.4, 1.0], 3: [0.85, 0.0, 0.85] };

function ramp(u, out, i) {
  const x = Math.min(Math.max(u, 0), 1) * (STOPS.length - 1);
  const k = Math.min(Math.floor(x), STOPS.length - 2);
  const f = x - k;
  for (let c = 0; c < 3; c++) out[3 * i + c] = STOPS[k][c] * (1 - f) + STOPS[k + 1][c] * f;
}

function range(valueArrays) {
  let lo = Infinity, hi = -Infinity;
  for (const values of valueArrays) {
    for (let i = 0; i < values.length; i++) {
      const v = values[i];
      if (Number.isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
    }
  }
  if (!Number.isFinite(lo)) return [0, 1];
  return hi > lo ? [lo, hi] : [lo - 0.5, lo + 0.5];
}

function heights(mesh) {
  const p = mesh.arrays.positions, z0 = mesh.header.origin[2];
  const values = new Float64Array(p.length / 3);
  for (let i = 0; i < values.length; i++) values[i] = p[3 * i + 2] + z0;
  return values;
}

// colours: (n,) values on the [lo, hi] ramp; NaN or a set flag in `changed` in red
function colours(values, [lo, hi], changed) {
  const out = new Float32Array(values.length * 3);
  for (let i = 0; i < values.length; i++) {
    if ((changed && changed[i] > 0) || !Number.isFinite(values[i])) {
      out.set(HIGHLIGHT, 3 * i);
    } else {
      ramp((values[i] - lo) / (hi - lo), out, i);
    }
  }
  return out;
}

function flagColours(flags) {
  const out = new Float32Array(flags.length * 3);
  for (let i = 0; i < flags.length; i++) out.set(FLAG_COLOURS[flags[i]] || HIGHLIGHT, 3 * i);
  return out;
}

function object3d(mesh, colour, sceneOrigin) {
  const { header, arrays } = mesh;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(arrays.positions, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(colour, 3));
  let object;
  if (header.kind === "triangles") {
    geometry.setIndex(new THREE.BufferAttribute(arrays.indices, 1));
    geometry.computeVertexNormals();
    object = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  } else if (header.kind === "lines") {
    geometry.setIndex(new THREE.BufferAttribute(arrays.indices, 1));
    object = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
  } else {
    object = new THREE.Points(geometry, new THREE.PointsMaterial({ vertexColors: true, size: 3, sizeAttenuation: false }));
  }
  object.position.set(header.origin[0] - sceneOrigin[0], header.origin[1] - sceneOrigin[1],
                      header.origin[2] - sceneOrigin[2]);
  object.userData.header = header;
  return object;
}

// the flagged vertices as large dots drawn over everything, so that a few changed vertices of a big mesh show
function markers(mesh, flags, colourOf, sceneOrigin) {
  const p = mesh.arrays.positions;
  const picked = [];
  for (let i = 0; i < flags.length; i++) if (flags[i] > 0) picked.push(i);
  if (!picked.length) return null;
  const positions = new Float32Array(picked.length * 3), colour = new Float32Array(picked.length * 3);
  picked.forEach((v, k) => {
    positions.set(p.subarray(3 * v, 3 * v + 3), 3 * k);
    colour.set(colourOf(flags[v]), 3 * k);
  });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(colour, 3));
  const dots = new THREE.Points(geometry, new THREE.PointsMaterial(
    { vertexColors: true, size: 5, sizeAttenuation: false, depthTest: false }));
  dots.renderOrder = 1;
  const o = mesh.header.origin;
  dots.position.set(o[0] - sceneOrigin[0], o[1] - sceneOrigin[1], o[2] - sceneOrigin[2]);
  return dots;
}

function dispose(object) {
  object.geometry.dispose();
  object.material.dispose();
}

// One canvas, one camera (z up) and orbit controls; one scene, or two side by side (split).
class Viewer {
  constructor(canvas, split = false) {
    this.canvas = canvas;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(1);
    this.renderer.setSize(canvas.width, canvas.height, false);
    this.split = split;
    this.scenes = (split ? [0, 1] : [0]).map(() => {
      const scene = new THREE.Scene();
      scene.background = new THREE.Color(0xf4f4f0);
      scene.add(new THREE.AmbientLight(0xffffff, 1.2));
      const light = new THREE.DirectionalLight(0xffffff, 1.8);
      light.position.set(0.3, -0.5, 1);
      scene.add(light);
      const group = new THREE.Group();
      scene.add(group);
      return { scene, group };
    });
    const aspect = (split ? canvas.width / 2 : canvas.width) / canvas.height;
    this.camera = new THREE.PerspectiveCamera(40, aspect, 1, 1e7);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, canvas);
    // the user's orbit, pan and zoom redraw; fit() moves the camera without drawing (its callers draw once,
    // after everything is set: each frame of 2M triangles is about a second on a software renderer)
    this.fitting = false;
    this.controls.addEventListener("change", () => { if (!this.fitting) this.render(); });
    this.fitted = false;
  }

  setExaggeration(factor) {
    for (const { group } of this.scenes) group.scale.set(1, 1, factor);
    this.render();
  }

  replace(index, key, object) {
    const { group } = this.scenes[index];
    const old = group.children.find((o) => o.userData.key === key);
    if (old) { group.remove(old); dispose(old); }
    if (object) { object.userData.key = key; group.add(object); }
  }

  fit() {
    const box = new THREE.Box3();
    for (const { group } of this.scenes) box.expandByObject(group);
    if (box.isEmpty()) return;
    const size = box.getSize(new THREE.Vector3()).length() || 1;
    const centre = box.getCenter(new THREE.Vector3());
    const [px, py] = this.facing();
    this.controls.target.copy(centre);
    this.camera.position.set(centre.x + 1.1 * px * size, centre.y + 1.1 * py * size, centre.z + 0.6 * size);
    this.camera.near = size / 1000;
    this.camera.far = size * 100;
    this.camera.updateProjectionMatrix();
    this.fitting = true;
    try { this.controls.update(); } finally { this.fitting = false; }
    this.fitted = true;
  }

  // the horizontal direction to look from: across the objects' longest horizontal extent (from its south side)
  facing() {
    let n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (const { group } of this.scenes) {
      for (const object of group.children) {
        const p = object.geometry.getAttribute("position").array;
        const step = Math.max(1, Math.floor(p.length / 3 / 20000));
        for (let i = 0; i < p.length / 3; i += step) {
          const x = p[3 * i] + object.position.x, y = p[3 * i + 1] + object.position.y;
          n += 1; sx += x; sy += y; sxx += x * x; syy += y * y; sxy += x * y;
        }
      }
    }
    if (n < 2) return [0.5, -0.85];
    const cxx = sxx / n - (sx / n) ** 2, cyy = syy / n - (sy / n) ** 2, cxy = sxy / n - (sx / n) * (sy / n);
    const angle = 0.5 * Math.atan2(2 * cxy, cxx - cyy);       // of the principal axis
    let [qx, qy] = [-Math.sin(angle), Math.cos(angle)];       // across it
    if (qy > 0) { qx = -qx; qy = -qy; }
    // a little to the side, so that a flat surface is not seen edge on
    return [qx * 0.94 + qy * 0.34, qy * 0.94 - qx * 0.34];
  }

  render() {
    const w = this.canvas.width, h = this.canvas.height;
    if (!this.split) {
      this.renderer.setViewport(0, 0, w, h);
      this.renderer.render(this.scenes[0].scene, this.camera);
      return;
    }
    this.renderer.setScissorTest(true);
    this.scenes.forEach(({ scene }, i) => {
      this.renderer.setViewport(i * w / 2, 0, w / 2, h);
      this.renderer.setScissor(i * w / 2, 0, w / 2, h);
      this.renderer.render(scene, this.camera);
    });
    this.renderer.setScissorTest(false);
  }
}

function query(params) {
  const q = new URLSearchParams();
  for (const [k, v] of Object.entries(params)) if (v !== null && v !== undefined && v !== "") q.set(k, v);
  return q.toString();
}

function count(meshes) {
  return meshes.reduce((n, m) => n + m.header.n_vertices, 0) + " vertices, " +
         meshes.reduce((n, m) => n + m.header.n_cells, 0) + " cells";
}

// The scene of one or several features: colour by height or a property, vertical exaggeration, time slider.
export function sceneView(config) {
  const viewer = new Viewer(document.getElementById("scene"));
  const loaded = new Map();          // id -> mesh
  let sceneOrigin = null;
  let serial = 0;
  let t = config.t;
  let colour = config.color;
  // ms: when the page's code started (from navigation), and of the last frame: download, build, draw
  const timings = { start: performance.now() };

  function paint() {
    const meshes = [...loaded.values()].filter((m) => m.header.kind !== "none");
    const values = new Map(meshes.map((m) => [m.header.id, colour === "height" ? heights(m) : m.arrays.values]));
    const span = range(values.values());
    const built = performance.now();
    for (const mesh of meshes) {
      viewer.replace(0, mesh.header.id, object3d(mesh, colours(values.get(mesh.header.id), span), sceneOrigin));
    }
    timings.build = performance.now() - built;
    for (const mesh of loaded.values()) if (mesh.header.kind === "none") viewer.replace(0, mesh.header.id, null);
    if (!viewer.fitted) viewer.fit();
    const rendering = performance.now();
    viewer.setExaggeration(Number(document.getElementById("exaggeration").value));
    timings.render = performance.now() - rendering;
    const absent = [...loaded.values()].filter((m) => m.header.kind === "none").map((m) => m.header.id);
    setState("ready", (t !== null ? `t = ${t}: ` : "") + count(meshes) +
             (absent.length ? ` (not there at t: ${absent.join(", ")})` : "") +
             (colour === "height" ? "" : `; colour: ${colour}`) + `; range ${span[0].toPrecision(6)} to ${span[1].toPrecision(6)}`);
    const rendered = performance.now();
    drawn(viewer);
    timings.draw = performance.now() - rendered + timings.render;
    document.body.dataset.timings = JSON.stringify(timings);
  }

  async function load(ids, first = false) {
    const mine = ++serial;
    setState("loading", "loading…");
    try {
      const asked = performance.now();
      const meshes = await Promise.all(ids.map((id) => fetchMesh(first ? config.urls[String(id)] :
        `/api/mesh/${id}?` + query({ t: config.temporal.includes(id) ? t : null,
                                     color: colour === "height" ? null : colour }))));
      if (mine !== serial) return;    // a later request replaced this one
      timings.download = performance.now() - asked;
      for (const mesh of meshes) {
        loaded.set(mesh.header.id, mesh);
        if (sceneOrigin === null && mesh.header.kind !== "none") sceneOrigin = mesh.header.origin;
      }
      if (sceneOrigin === null) sceneOrigin = [0, 0, 0];
      paint();
    } catch (error) {
      if (mine === serial) setState("error", String(error.message || error));
    }
  }

  const exaggeration = document.getElementById("exaggeration");
  exaggeration.addEventListener("input", () => {
    document.getElementById("exaggeration-value").textContent = exaggeration.value;
    viewer.setExaggeration(Number(exaggeration.value));
  });
  document.getElementById("color").addEventListener("change", (event) => {
    colour = event.target.value;
    load(config.ids);
  });
  const slider = document.getElementById("time");
  if (slider) {
    let timer = null;
    slider.addEventListener("input", () => {
      t = Number(slider.value);
      document.getElementById("time-value").textContent = String(t);
      const url = new URL(window.location.href);
      url.searchParams.set("t", String(t));
      window.history.replaceState(null, "", url);
      clearTimeout(timer);
      timer = setTimeout(() => load(config.temporal), 60);
    });
  }
  load(config.ids, true);
}

// Two versions of a surface: b coloured by displacement from a, or a and b side by side.
export function compareView(config) {
  const side = config.mode === "side";
  const viewer = new Viewer(document.getElementById("scene"), side);
  const url = (which) => `/api/compare/${config.id}?` + query({ a: config.a, b: config.b, side: which });
  setState("loading", "loading…");
  Promise.all((side ? ["a", "b"] : ["b"]).map((which) => fetchMesh(url(which)))).then((meshes) => {
    const origin = meshes[0].header.origin;
    if (side) {
      const span = range(meshes.map(heights));
      meshes.forEach((m, i) => {
        viewer.replace(i, m.header.side, object3d(m, colours(heights(m), span, m.arrays.changed), origin));
        viewer.replace(i, m.header.side + ":marks", markers(m, m.arrays.changed, () => HIGHLIGHT, origin));
      });
    } else {
      // the displacement of each vertex from the one of the same stored id; red: no such vertex in a
      const m = meshes[0];
      viewer.replace(0, "b", object3d(m, colours(m.arrays.displacement, range([m.arrays.displacement])), origin));
      viewer.replace(0, "b:marks", markers(m, m.arrays.changed, () => HIGHLIGHT, origin));
    }
    const marks = document.getElementById("marks");
    const showMarks = () => {
      for (const { group } of viewer.scenes) {
        for (const o of group.children) if (String(o.userData.key).endsWith(":marks")) o.visible = marks.checked;
      }
      viewer.render();
    };
    marks.addEventListener("change", showMarks);
    viewer.fit();
    showMarks();
    const changed = meshes.map((m) => m.arrays.changed.reduce((n, f) => n + (f > 0 ? 1 : 0), 0));
    const maxShift = side ? null : range([meshes[0].arrays.displacement])[1];
    setState("ready", `${count(meshes)}; vertices highlighted: ${changed.join(" and ")}` +
             (maxShift === null ? "" : `; largest displacement ${maxShift.toPrecision(6)}`));
    document.body.dataset.highlighted = changed.join(",");
    drawn(viewer);
  }).catch((error) => setState("error", String(error.message || error)));
}

// a text as one word of a shell command line, as Python's shlex.quote writes it (a version name with a space)
export function shellQuote(word) {
  if (word === "") return "''";
  if (/^[A-Za-z0-9_@%+=:,.\/-]+$/.test(word)) return word;
  return "'" + word.replaceAll("'", "'\"'\"'") + "'";
}

// a number for people: six significant digits, no trailing zeros
const short = (x) => String(Number(Number(x).toPrecision(6)));
const plural = (n, one, many) => `${n} ${n === 1 ? one : many}`;

// The merge regions of one feature (its header's `regions`, the positions `region_vertices`, `region_cells` in
// its arrays): the regions' cells (triangles, or segments) as an unlit overlay in their state's colour, their
// vertices as dots (darker over cells; a point set's points in the state's colour itself).
// Returns [overlay or null, dots or null]; each has userData.regionOf: the region entry of each of its items.
function regionObjects(mesh, palette, sceneOrigin) {
  const { header, arrays } = mesh;
  const regions = header.regions || [];
  if (!regions.length) return [null, null];
  const cells = arrays.region_cells, vertices = arrays.region_vertices;
  const k = header.kind === "triangles" ? 3 : header.kind === "lines" ? 2 : 0;
  const p = arrays.positions, idx = arrays.indices;
  const positions = new Float32Array(cells.length * 3 * k), colour = new Float32Array(cells.length * 3 * k);
  const regionOf = new Uint32Array(cells.length), dotRegion = new Uint32Array(vertices.length);
  const dots = new Float32Array(vertices.length * 3), dotColour = new Float32Array(vertices.length * 3);
  const shade = k ? 0.3 : 1.0;
  let c = 0, v = 0;
  regions.forEach((region, r) => {
    const rgb = palette[region.state];
    for (let j = 0; j < region.drawn.cells; j++, c++) {
      for (let corner = 0; corner < k; corner++) {
        const at = idx[k * cells[c] + corner];
        positions.set(p.subarray(3 * at, 3 * at + 3), 3 * (k * c + corner));
        colour.set(rgb, 3 * (k * c + corner));
      }
      regionOf[c] = r;
    }
    for (let j = 0; j < region.drawn.vertices; j++, v++) {
      const at = vertices[v];
      dots.set(p.subarray(3 * at, 3 * at + 3), 3 * v);
      dotColour.set(rgb.map((x) => shade * x), 3 * v);
      dotRegion[v] = r;
    }
  });
  const o = header.origin;
  const place = (object, items) => {
    object.position.set(o[0] - sceneOrigin[0], o[1] - sceneOrigin[1], o[2] - sceneOrigin[2]);
    object.userData.header = header;
    object.userData.regionOf = items;
    return object;
  };
  const buffers = (xyz, rgb) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(xyz, 3));
    geometry.setAttribute("color", new THREE.BufferAttribute(rgb, 3));
    return geometry;
  };
  let overlay = null;
  if (k === 3 && cells.length) {
    // unlit, so that each state keeps its colour; pulled in front of the mesh's own (same) triangles
    overlay = place(new THREE.Mesh(buffers(positions, colour), new THREE.MeshBasicMaterial({
      vertexColors: true, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: -1, polygonOffsetUnits: -4 })),
      regionOf);
  } else if (k === 2 && cells.length) {
    overlay = place(new THREE.LineSegments(buffers(positions, colour),
      new THREE.LineBasicMaterial({ vertexColors: true, depthTest: false })), regionOf);
  }
  if (overlay) overlay.renderOrder = 1;
  let points = null;
  if (vertices.length) {
    points = place(new THREE.Points(buffers(dots, dotColour), new THREE.PointsMaterial(
      { vertexColors: true, size: k ? 6 : 9, sizeAttenuation: false, depthTest: false })), dotRegion);
    points.renderOrder = 2;
  }
  return [overlay, points];
}

// where each region's drawn cells and vertices fall on the canvas (CSS pixels from its top left corner, border
// included, as a screenshot of the canvas has them): {"feature:region": [x0, y0, x1, y1]}
function regionBoxes(viewer, objects) {
  const canvas = viewer.canvas, w = canvas.clientWidth, h = canvas.clientHeight;
  const boxes = {};
  const point = new THREE.Vector3();
  for (const object of objects) {
    const p = object.geometry.getAttribute("position").array, regionOf = object.userData.regionOf;
    const per = p.length / 3 / Math.max(regionOf.length, 1);       // vertices of each item (3, 2 or 1)
    const header = object.userData.header;
    object.updateMatrixWorld();
    for (let i = 0; i < regionOf.length; i++) {
      const key = `${header.id}:${header.regions[regionOf[i]].index}`;
      const box = boxes[key] || (boxes[key] = [Infinity, Infinity, -Infinity, -Infinity]);
      for (let corner = 0; corner < per; corner++) {
        point.fromArray(p, 3 * (per * i + corner)).applyMatrix4(object.matrixWorld).project(viewer.camera);
        const x = (point.x + 1) / 2 * w + canvas.clientLeft, y = (1 - point.y) / 2 * h + canvas.clientTop;
        box[0] = Math.min(box[0], x); box[1] = Math.min(box[1], y);
        box[2] = Math.max(box[2], x); box[3] = Math.max(box[3], y);
      }
    }
  }
  return boxes;
}

function sideText(side, region) {
  const s = region[side];
  if (!s.vertices && !s.cells) return `${side} changed nothing here`;
  return `${side} changed ${plural(s.vertices, "vertex", "vertices")}, ${plural(s.cells, "cell", "cells")}, ` +
         `largest displacement ${short(s.largest_displacement)}`;
}

// the slice a region of a model-2/3 feature belongs to, as the Python messages name it; "" for model 1
function sliceText(slice) {
  if (!slice) return "";
  return slice.timem === undefined ? `instant ${short(slice.times)}`
    : `geometry instant ${short(slice.times)} of the period starting at ${short(slice.timem)}`;
}

function regionText(header, region, labels) {
  const missing = region.missing.vertices + region.missing.cells;
  const at = region.slice ? ` at ${sliceText(region.slice)}` : "";
  return `feature ${header.id} region ${region.index}${at}: ${labels[region.state]}; solution: ${region.solution}. ` +
         `${sideText("parent", region)}; ${sideText("child", region)}. ` +
         `${plural(region.ids.vertices, "vertex", "vertices")} and ${plural(region.ids.cells, "cell", "cells")}` +
         ` (margin included)` +
         (missing ? `, of which ${region.missing.vertices} vertices and ${region.missing.cells} cells are not drawn ` +
                    `(not in ${header.version}'s mesh: the parent's new rows or those ${header.version} removed; ` +
                    `or tetrahedra inside the solid)` : "");
}

function regionRow(header, region, labels, palette) {
  const row = document.createElement("tr");
  row.dataset.feature = String(header.id);
  row.dataset.region = String(region.index);
  row.dataset.state = region.state;
  row.dataset.drawn = String(region.at_t !== false);      // a region of another instant is listed, not drawn
  if (region.at_t === false) row.classList.add("elsewhere");
  const cells = [String(header.id), String(region.index), null, region.solution,
                 sideText("parent", region).replace(/^parent /, ""), sideText("child", region).replace(/^child /, ""),
                 `${plural(region.ids.vertices, "vertex", "vertices")}, ${plural(region.ids.cells, "cell", "cells")}`,
                 sliceText(region.slice)];
  for (const text of cells) {
    const td = document.createElement("td");
    if (text === null) {
      const swatch = document.createElement("span");
      swatch.className = "swatch";
      swatch.style.background = palette[region.state];
      td.append(swatch, " " + labels[region.state]);
    } else {
      td.textContent = text;
    }
    row.append(td);
  }
  return row;
}

// The slices of the model-2/3 regions (an instant; model 3: a geometry instant of a topology period, and a period's
// last geometry instant is the next one's start: one time, two slices): choosing one reloads the page at its t and,
// for model 3, its period's start timem (the regions of that slice drawn)
function timeChoice(config, meshes) {
  const slices = new Map();
  for (const m of meshes) {
    for (const r of m.header.regions) if (r.slice) slices.set(`${r.slice.times} ${r.slice.timem}`, r.slice);
  }
  if (!slices.size) return;
  const shown = meshes.find((m) => m.header.slice);
  const given = config.t !== null && config.t !== undefined;
  const drawn = shown ? shown.header.slice
    : given ? { times: config.t, timem: config.timem ?? undefined } : [...slices.values()][0];
  const key = `${drawn.times} ${drawn.timem}`;
  if (!slices.has(key)) slices.set(key, drawn);
  const sorted = [...slices.values()].sort((a, b) => a.times - b.times || (a.timem ?? 0) - (b.timem ?? 0));
  const select = document.getElementById("region-time");
  // six digits, unless another time reads the same in six digits (a t given near an instant): then every digit
  const label = (t) => sorted.some((o) => o.times !== t && short(o.times) === short(t)) ? String(t) : short(t);
  for (const s of sorted) {
    const option = document.createElement("option");
    option.value = String(s.times);
    if (s.timem !== undefined && s.timem !== null) option.dataset.timem = String(s.timem);
    const twice = sorted.filter((o) => o.times === s.times).length > 1;
    option.textContent = label(s.times) + (twice && option.dataset.timem ? ` (period starting at ${short(s.timem)})` : "");
    option.selected = s === drawn || (s.times === drawn.times && s.timem === drawn.timem);
    select.append(option);
  }
  select.addEventListener("change", () => {
    const url = new URL(window.location.href);
    const option = select.selectedOptions[0];
    url.searchParams.set("t", option.value);
    if (option.dataset.timem !== undefined) url.searchParams.set("timem", option.dataset.timem);
    else url.searchParams.delete("timem");
    window.location.assign(url);
  });
  document.getElementById("region-time-control").hidden = false;
}

// A version's conflicting features: their merge regions coloured by what happens there (and the solution chosen);
// a feature that merges as a whole only coloured by who changed each vertex since the version's base.
export function conflictView(config) {
  const viewer = new Viewer(document.getElementById("scene"));
  const labels = {}, palette = {}, linear = {};
  for (const item of config.legend) {
    labels[item.state] = item.label;
    palette[item.state] = item.colour;
    const c = new THREE.Color(item.colour);            // sRGB in, the renderer's linear working space out
    linear[item.state] = [c.r, c.g, c.b];
  }
  const info = document.getElementById("region-info");
  setState("loading", "loading…");
  // one feature that cannot be drawn (deleted in the version, a kind the view does not draw) leaves the others
  const fetched = config.ids.map((id) => fetchMesh(`/api/conflict/${id}?` + query({ version: config.version, t: config.t, timem: config.timem }))
    .catch((error) => ({ failed: id, message: String(error.message || error) })));
  Promise.all(fetched)
    .then((results) => {
      const failed = results.filter((r) => r.failed !== undefined);
      const meshes = results.filter((r) => r.failed === undefined);
      if (!meshes.length) throw new Error(failed.map((f) => `feature ${f.failed}: ${f.message}`).join("; "));
      const origin = meshes[0].header.origin;
      const overlays = [];      // every overlay and dots object: what the pointer picks, what the boxes are of
      const grey = (n) => flagColours(new Float32Array(n));
      for (const m of meshes) {
        const [overlay, dots] = regionObjects(m, linear, origin);
        overlays.push(...[overlay, dots].filter((o) => o));
        if (m.header.regions.length) {
          viewer.replace(0, m.header.id, object3d(m, grey(m.header.n_vertices), origin));
          viewer.replace(0, `${m.header.id}:regions`, overlay);
          viewer.replace(0, `${m.header.id}:dots`, dots);
        } else {
          viewer.replace(0, m.header.id, object3d(m, flagColours(m.arrays.changed), origin));
          viewer.replace(0, `${m.header.id}:marks`, markers(m, m.arrays.changed, (f) => FLAG_COLOURS[f], origin));
        }
      }
      viewer.fit();
      viewer.render();
      const tbody = document.querySelector("#regions tbody"), notes = document.getElementById("region-notes");
      for (const f of failed) {
        const p = document.createElement("p");
        p.className = "note";
        p.textContent = `feature ${f.failed} is not drawn: ${f.message}`;
        notes.append(p);
      }
      timeChoice(config, meshes);
      for (const m of meshes) {
        for (const region of m.header.regions) tbody.append(regionRow(m.header, region, labels, palette));
        if (m.header.slice !== undefined && m.header.regions.some((r) => r.at_t === false)) {
          const p = document.createElement("p");
          p.className = "note";
          p.textContent = `feature ${m.header.id} is drawn ` +
            (m.header.slice ? `at ${sliceText(m.header.slice)}` : `at t = ${short(m.header.t)}, where no instant merges`) +
            `: its regions at other instants are listed, drawn when theirs is chosen (t above)`;
          notes.append(p);
        }
        const note = !m.header.merges_by_region ? `feature ${m.header.id} merges as a whole object only: ${m.header.reason}`
          : m.header.solutions === "stale" ? `feature ${m.header.id}: the solutions recorded for its regions were ` +
            `found on an earlier state of ${m.header.version} or ${m.header.parent}, so they do not hold and every ` +
            `conflict is shown unsolved; find the conflicts again (tgsis version conflicts ${shellQuote(m.header.version)})`
          : null;
        if (note) {
          const p = document.createElement("p");
          p.className = "note";
          p.textContent = note;
          notes.append(p);
        }
      }
      // the region under the pointer (or the one clicked) and its facts
      const raycaster = new THREE.Raycaster();
      const pickable = overlays;
      const size = new THREE.Box3().setFromObject(viewer.scenes[0].group).getSize(new THREE.Vector3()).length();
      raycaster.params.Line.threshold = size / 300;      // a segment or a dot a few pixels away is picked
      raycaster.params.Points.threshold = size / 300;
      let pinned = null;
      const at = (event) => {
        const rect = viewer.canvas.getBoundingClientRect();
        const ndc = new THREE.Vector2(((event.clientX - rect.left - viewer.canvas.clientLeft) / viewer.canvas.clientWidth) * 2 - 1,
                                      -((event.clientY - rect.top - viewer.canvas.clientTop) / viewer.canvas.clientHeight) * 2 + 1);
        raycaster.setFromCamera(ndc, viewer.camera);
        const hit = raycaster.intersectObjects(pickable, false)[0];
        if (!hit) return null;
        const header = hit.object.userData.header, regionOf = hit.object.userData.regionOf;
        const item = hit.object.isMesh ? hit.faceIndex : hit.object.isLineSegments ? Math.floor(hit.index / 2) : hit.index;
        return { header, region: header.regions[regionOf[item]] };
      };
      const show = (found) => {
        const shown = found || pinned;
        info.hidden = !shown;
        info.textContent = shown ? regionText(shown.header, shown.region, labels) : "no region here";
      };
      viewer.canvas.addEventListener("pointermove", (event) => show(at(event)));
      viewer.canvas.addEventListener("pointerleave", () => show(null));
      viewer.canvas.addEventListener("click", (event) => {
        pinned = at(event);
        for (const row of tbody.querySelectorAll("tr")) {
          row.classList.toggle("picked", !!pinned && row.dataset.feature === String(pinned.header.id) &&
                                         row.dataset.region === String(pinned.region.index));
        }
        show(pinned);
      });
      const tally = [0, 0, 0, 0];
      for (const m of meshes) for (const f of m.arrays.changed) tally[f] += 1;
      const regions = meshes.flatMap((m) => m.header.regions);
      const unsolved = regions.filter((r) => r.state === "unsolved").length;
      document.body.dataset.flags = tally.join(",");
      document.body.dataset.regions = String(regions.length);
      document.body.dataset.regionBoxes = JSON.stringify(regionBoxes(viewer, overlays));
      drawn(viewer);
      setState("ready", `${count(meshes)}; changed here ${tally[1]}, in the parent ${tally[2]}, on both sides ${tally[3]} vertices; ` +
               `${plural(regions.length, "region", "regions")}, ${regions.filter((r) => r.conflict).length} in conflict, ${unsolved} unsolved` +
               (failed.length ? `; ${plural(failed.length, "feature", "features")} not drawn` : ""));
    }).catch((error) => setState("error", String(error.message || error)));
}
