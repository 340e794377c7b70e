// brdfz view: draws the values brdfz.view computed (the JSON in #brdfz-data) on 2D canvases, and
// renders the lit sphere with WebGPU through the exported shaders. No network, no library.
"use strict";
(() => {
const DATA = JSON.parse(document.getElementById("brdfz-data").textContent);
const $ = (id) => document.getElementById(id);

function decode(b64) {
  const s = atob(b64), u = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
  return u;
}
const f32 = (b64) => new Float32Array(decode(b64).buffer);
// brdfz.view._packed reversed: gunzip, then the even bytes and the odd ones interleaved again.
async function unpack(b64, bytes) {
  const stream = new Blob([decode(b64)]).stream().pipeThrough(new DecompressionStream("gzip"));
  const s = new Uint8Array(await new Response(stream).arrayBuffer()), half = bytes / 2, out = new Uint8Array(bytes);
  if (s.length !== bytes) throw new Error(`a layout unpacked to ${s.length} bytes, not ${bytes}`);
  for (let i = 0; i < half; i++) { out[2 * i] = s[i]; out[2 * i + 1] = s[half + i]; }
  return out;
}

const THETA_I = DATA.theta_i, ANGLES = f32(DATA.polar_angles), ALBEDO_THETA = f32(DATA.albedo_theta);
const [LOBE_EL, LOBE_AZ] = DATA.lobe_res, LOBE_DIRS = f32(DATA.lobe_dirs);
const SLICE = DATA.slice_res, SLICE_ELEVATION = f32(DATA.slice_wi_elevation);
const SPHERE = DATA.sphere;
const DEG = Math.PI / 180;

// Each material's views, decoded once: polar and albedo keep r, g, b; mean3 takes their average.
const views = DATA.materials.map((m) => ({
  polar: f32(m.views.polar), lobe: f32(m.views.lobe), slice: f32(m.views.slice), albedo: f32(m.views.albedo),
}));
const mean3 = (rgb) => { const n = rgb.length / 3, out = new Float64Array(n);
  for (let i = 0; i < n; i++) out[i] = (rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2]) / 3; return out; };
const polarMean = views.map((v) => mean3(v.polar));

const state = { a: 0, b: DATA.b, error: "relative", lobeTheta: THETA_I.length - 1,
  log: true, light: normalise(SPHERE.light), yaw: -0.6, pitch: 0.5 };

function normalise(v) { const n = Math.hypot(v[0], v[1], v[2]); return [v[0] / n, v[1] / n, v[2] / n]; }

// ------------------------------------------------------------------------------------------ colours

const THETA_COLOURS = ["#3b528b", "#21918c", "#5ec962", "#b5de2b"];
function heat(t) {  // dark to bright, an inferno-like ramp
  t = Math.min(Math.max(t, 0), 1);
  const stops = [[0, 0, 4], [87, 16, 110], [188, 55, 84], [249, 142, 9], [252, 255, 164]];
  const x = t * (stops.length - 1), i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
  return stops[i].map((c, k) => Math.round(c + f * (stops[i + 1][k] - c)));
}
// Errors of B against A, relative ((B − A) / A) or absolute (B − A: where A is tiny, a relative error
// can be large and still not matter). Shown linear to ±lin, logarithmic beyond, up to ±top; blue below,
// red above. lin: 1 % for relative errors, a hundredth of the top for absolute ones.
function errorOf(a, b) { return state.error === "absolute" ? b - a : a > 0 ? (b - a) / a : NaN; }
const errorLin = (top) => (state.error === "absolute" ? top / 100 || Number.MIN_VALUE : 0.01);
const stretch = (x, lin) => (Math.abs(x) <= lin ? Math.abs(x) / lin : 1 + Math.log10(Math.abs(x) / lin));
const unstretch = (t, lin) => (t <= 1 ? t * lin : lin * 10 ** (t - 1));
function errorScale(e, top) {
  const lin = errorLin(top);
  return Math.sign(e) * Math.min(stretch(e, lin) / stretch(Math.max(top, lin), lin), 1);
}
function diverging(e, top) {
  const s = errorScale(e, top), t = Math.abs(s);
  const far = s < 0 ? [33, 102, 172] : [178, 24, 43];
  return [0, 1, 2].map((k) => Math.round(247 + t * (far[k] - 247)));
}
const MASKED = [160, 160, 160];
function percentile(values, q) {
  const v = Array.from(values).filter((x) => Number.isFinite(x)).sort((x, y) => x - y);
  return v.length ? v[Math.min(v.length - 1, Math.floor(q * (v.length - 1)))] : 0;
}
const errorTop = (errors) => percentile(errors.map(Math.abs), 0.995) || 1;

// ------------------------------------------------------------------------------------------ canvases

function canvas(id) {
  const c = $(id);
  if (!c.sized) { c.width = 300; c.height = 220; c.sized = true; }
  const g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  g.font = "11px system-ui, sans-serif";
  return [c, g];
}
function label(g, text, x, y, colour = "#333", align = "left") { g.fillStyle = colour; g.textAlign = align; g.fillText(text, x, y); }

// Cartesian axes over [x0, x1] × [y0, y1]; returns the mapping to pixels.
function axes(g, c, [x0, x1], [y0, y1], xlabel, ylabel, ticks) {
  const L = 42, R = 8, T = 10, B = 28, w = c.width - L - R, h = c.height - T - B;
  const X = (x) => L + (x - x0) / (x1 - x0) * w, Y = (y) => T + (1 - (y - y0) / (y1 - y0)) * h;
  g.strokeStyle = "#999"; g.lineWidth = 1; g.strokeRect(L, T, w, h);
  for (const x of ticks.x) { label(g, ticks.fx ? ticks.fx(x) : String(x), X(x), T + h + 12, "#555", "center"); }
  for (const y of ticks.y) { label(g, ticks.fy ? ticks.fy(y) : String(y), L - 3, Y(y) + 4, "#555", "right"); }
  label(g, xlabel, L + w / 2, c.height - 3, "#333", "center");
  g.save(); g.translate(10, T + h / 2); g.rotate(-Math.PI / 2); label(g, ylabel, 0, 0, "#333", "center"); g.restore();
  return { X, Y, L, T, w, h };
}
function line(g, xs, ys, X, Y, colour, width = 1.5) {
  g.strokeStyle = colour; g.lineWidth = width; g.beginPath();
  let pen = false;
  for (let i = 0; i < xs.length; i++) {
    if (!Number.isFinite(ys[i])) { pen = false; continue; }
    if (pen) g.lineTo(X(xs[i]), Y(ys[i])); else g.moveTo(X(xs[i]), Y(ys[i]));
    pen = true;
  }
  g.stroke();
}
// Error curves on the symmetric scale of errorScale.
function errorAxes(g, c, xrange, xlabel, top, xt) {
  const lin = errorLin(top), scale = stretch(Math.max(top, lin), lin);
  const fy = (s) => {
    const v = Math.sign(s) * unstretch(Math.abs(s) * scale, lin);
    return s === 0 ? "0" : state.error === "absolute" ? v.toPrecision(2) : (Math.abs(v) >= 0.1 ? v.toFixed(1) : v.toFixed(3));
  };
  return axes(g, c, xrange, [-1, 1], xlabel, state.error === "absolute" ? "B − A" : "(B − A) / A", { x: xt, y: [-1, -0.5, 0, 0.5, 1], fy });
}

// ------------------------------------------------------------------------------------------ polar

function drawPolar(which) {
  const [c, g] = canvas(`polar-${which}`);
  const m = state[which], v = polarMean[m];
  const n = ANGLES.length, both = [...polarMean[state.a], ...polarMean[state.b]].filter(Number.isFinite);
  const top = Math.max(...both) || 1, low = top * 1e-4;
  const radius = (f) => (state.log ? Math.max(0, Math.log10(Math.max(f, low) / low) / Math.log10(top / low)) : f / top);
  const cx = c.width / 2, cy = c.height - 16, R = Math.min(cx - 10, cy - 10);
  g.strokeStyle = "#ddd"; g.lineWidth = 1;
  for (const r of [0.25, 0.5, 0.75, 1]) { g.beginPath(); g.arc(cx, cy, R * r, Math.PI, 2 * Math.PI); g.stroke(); }
  for (let a = -90; a <= 90; a += 30) { g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx + R * Math.sin(a * DEG), cy - R * Math.cos(a * DEG)); g.stroke(); }
  THETA_I.forEach((t, k) => {
    g.strokeStyle = THETA_COLOURS[k]; g.lineWidth = 1.5; g.beginPath();
    for (let i = 0; i < n; i++) {
      const r = R * radius(v[k * n + i]), a = ANGLES[i] * DEG, x = cx + r * Math.sin(a), y = cy - r * Math.cos(a);
      if (i) g.lineTo(x, y); else g.moveTo(x, y);
    }
    g.stroke();
    label(g, "✶", cx - (R + 4) * Math.sin(t * DEG) - 4, cy - (R + 4) * Math.cos(t * DEG) + 4, THETA_COLOURS[k]);
    label(g, `θi ${t}°`, 4, 12 + 12 * k, THETA_COLOURS[k]);
  });
  label(g, state.log ? `log, ${low.toPrecision(2)} to ${top.toPrecision(3)} /sr` : `0 to ${top.toPrecision(3)} /sr`, c.width - 4, 12, "#555", "right");
  plotted.polar[which] = { material: m, theta_i: THETA_I, angles: Array.from(ANGLES), values: Array.from(v) };
}

function drawPolarError() {
  const [c, g] = canvas("polar-e");
  const A = polarMean[state.a], B = polarMean[state.b], n = ANGLES.length, tmax = DATA.materials[state.a].theta_max;
  const errs = THETA_I.map((t, k) => Array.from(ANGLES, (_, i) => (t * DEG > tmax ? NaN : errorOf(A[k * n + i], B[k * n + i]))));
  const top = errorTop(errs.flat());
  const ax = errorAxes(g, c, [-90, 90], "θo (°)", top, [-90, -45, 0, 45, 90]);
  errs.forEach((e, k) => line(g, ANGLES, e.map((x) => errorScale(x, top)), ax.X, ax.Y, THETA_COLOURS[k]));
  plotted.polarError = { mode: state.error, materials: [state.a, state.b], values: errs.flat() };
  THETA_I.forEach((t, k) => label(g, `θi ${t}°${t * DEG > tmax ? " (masked)" : ""}`, ax.L + 4, ax.T + 12 + 12 * k, THETA_COLOURS[k]));
}

// ------------------------------------------------------------------------------------------ lobe

function project(p) {  // turn by yaw about z, tilt by pitch, then the screen's x right, y up
  const cy = Math.cos(state.yaw), sy = Math.sin(state.yaw), cp = Math.cos(state.pitch), sp = Math.sin(state.pitch);
  const x = cy * p[0] - sy * p[1], y = sy * p[0] + cy * p[1], z = p[2];
  return [x, cp * z + sp * y];
}
function lobePoints(m) {
  const k = state.lobeTheta, v = views[m].lobe, n = LOBE_EL * (LOBE_AZ + 1);
  return Array.from({ length: n }, (_, i) => [v[k * n + i], LOBE_DIRS.subarray(3 * i, 3 * i + 3)]);
}
function drawLobeMesh(c, g, points, radius, colourOf) {
  const cx = c.width / 2, cy = c.height * 0.78, R = c.height * 0.7;
  const at = (i) => { const [f, d] = points[i], r = radius(f), q = project([r * d[0], r * d[1], r * d[2]]); return [cx + R * q[0], cy - R * q[1]]; };
  g.lineWidth = 1;
  // Floor and normal for orientation.
  g.strokeStyle = "#ccc"; g.beginPath();
  for (let a = 0; a <= 64; a++) {
    const q = project([Math.cos(a / 32 * Math.PI), Math.sin(a / 32 * Math.PI), 0]), x = cx + R * q[0], y = cy - R * q[1];
    if (a) g.lineTo(x, y); else g.moveTo(x, y);
  }
  g.stroke();
  const t = THETA_I[state.lobeTheta] * DEG, wi = project([Math.sin(t), 0, Math.cos(t)]);
  g.strokeStyle = "#e0a000"; g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx + R * wi[0], cy - R * wi[1]); g.stroke();
  const W = LOBE_AZ + 1;
  for (let e = 0; e < LOBE_EL; e++)
    for (let a = 0; a < W; a++) {
      const i = e * W + a;
      for (const j of [a + 1 < W ? i + 1 : -1, e + 1 < LOBE_EL ? i + W : -1]) {
        if (j < 0) continue;
        g.strokeStyle = colourOf(i, j); g.beginPath();
        const p = at(i), q = at(j); g.moveTo(p[0], p[1]); g.lineTo(q[0], q[1]); g.stroke();
      }
    }
}
// f to the lobe's radius, one scale for A and B: linear, or 3 decades of log10.
function lobeRadius() {
  const k = state.lobeTheta, n = LOBE_EL * (LOBE_AZ + 1);
  let top = 0;
  for (const m of [state.a, state.b]) for (let i = 0; i < n; i++) top = Math.max(top, views[m].lobe[k * n + i]);
  top = top || 1;
  const low = top * 1e-3;
  return state.log ? (f) => Math.max(0, Math.log10(Math.max(f, low) / low) / 3) : (f) => f / top;
}
function drawLobe(which) {
  const [c, g] = canvas(`lobe-${which}`);
  drawLobeMesh(c, g, lobePoints(state[which]), lobeRadius(), () => "rgba(40, 70, 140, 0.55)");
  label(g, `θi ${THETA_I[state.lobeTheta]}° (light: orange)`, 4, 12);
}
function drawLobeError() {
  const [c, g] = canvas("lobe-e");
  const A = lobePoints(state.a), B = lobePoints(state.b);
  const masked = THETA_I[state.lobeTheta] * DEG > DATA.materials[state.a].theta_max;
  const e = A.map(([f], i) => (masked ? NaN : errorOf(f, B[i][0])));
  const top = errorTop(e);
  drawLobeMesh(c, g, A, lobeRadius(), (i, j) => {
    const x = (e[i] + e[j]) / 2;
    return Number.isFinite(x) ? `rgb(${diverging(x, top).map((v) => Math.min(v, 230))})` : "rgb(160,160,160)";
  });
  label(g, `A's lobe coloured by B's error, ±${top.toPrecision(2)}${masked ? " (masked)" : ""}`, 4, 12);
}

// ------------------------------------------------------------------------------------------ θh × θd

function drawImage(id, rows, cols, colour, caption) {
  const [c, g] = canvas(id);
  const L = 42, T = 10, w = c.width - L - 8, h = c.height - T - 28;
  const img = g.createImageData(cols, rows);
  for (let r = 0; r < rows; r++)
    for (let q = 0; q < cols; q++) {
      const o = 4 * ((rows - 1 - r) * cols + q), rgb = colour(r * cols + q);
      img.data[o] = rgb[0]; img.data[o + 1] = rgb[1]; img.data[o + 2] = rgb[2]; img.data[o + 3] = 255;
    }
  const tmp = document.createElement("canvas"); tmp.width = cols; tmp.height = rows;
  tmp.getContext("2d").putImageData(img, 0, 0);
  g.imageSmoothingEnabled = false;
  g.drawImage(tmp, L, T, w, h);
  const ax = axes(g, c, [0, 90], [0, 90], "θh (°)", "θd (°)", { x: [0, 30, 60, 90], y: [0, 30, 60, 90] });
  const width = g.measureText(caption).width;  // on a dark box: the image may be white or black there
  g.fillStyle = "rgba(0, 0, 0, 0.6)"; g.fillRect(ax.L + ax.w - width - 8, ax.T + 1, width + 7, 15);
  label(g, caption, ax.L + ax.w - 4, ax.T + 12, "#fff", "right");
}
function sliceRange() {
  const both = [...views[state.a].slice, ...views[state.b].slice].filter((x) => x > 0);
  const top = percentile(both, 0.995) || 1;
  return [top * 1e-4, top];
}
function drawSlice(which) {
  const v = views[state[which]].slice, [low, top] = sliceRange();
  drawImage(`slice-${which}`, SLICE, SLICE, (i) => (v[i] > 0 ? heat(state.log ? Math.log(v[i] / low) / Math.log(top / low) : v[i] / top) : [255, 255, 255]),
    state.log ? `log ${low.toPrecision(2)}–${top.toPrecision(3)}` : `0–${top.toPrecision(3)}`);
  plotted.slice[which] = { material: state[which], bins: SLICE, phi_d: DATA.slice_phi_d, values: Array.from(v) };
}
function drawSliceError() {
  const A = views[state.a].slice, B = views[state.b].slice, tmax = DATA.materials[state.a].theta_max;
  const e = Array.from(A, (a, i) => (SLICE_ELEVATION[i] > tmax ? NaN : errorOf(a, B[i])));
  const top = errorTop(e);
  drawImage("slice-e", SLICE, SLICE, (i) => (Number.isFinite(e[i]) ? diverging(e[i], top) : MASKED), `±${top.toPrecision(2)}`);
}

// ------------------------------------------------------------------------------------------ albedo

function drawAlbedo(which) {
  const [c, g] = canvas(`albedo-${which}`);
  const v = views[state[which]].albedo, n = ALBEDO_THETA.length;
  const top = Math.max(...views[state.a].albedo, ...views[state.b].albedo) * 1.1 || 1;
  const ax = axes(g, c, [0, 90], [0, top], "θo (°)", "albedo", { x: [0, 30, 60, 90], y: [0, top / 2, top].map((x) => +x.toPrecision(2)) });
  ["#d33", "#3a3", "#33d"].forEach((colour, k) => line(g, ALBEDO_THETA, Array.from({ length: n }, (_, i) => v[3 * i + k]), ax.X, ax.Y, colour, 1));
  line(g, ALBEDO_THETA, mean3(v), ax.X, ax.Y, "#222", 2);
}
function drawAlbedoError() {
  const [c, g] = canvas("albedo-e");
  const A = mean3(views[state.a].albedo), B = mean3(views[state.b].albedo), tmax = DATA.materials[state.a].theta_max;
  const e = Array.from(A, (a, i) => (ALBEDO_THETA[i] * DEG > tmax ? NaN : errorOf(a, B[i])));
  const top = errorTop(e);
  const ax = errorAxes(g, c, [0, 90], "θo (°)", top, [0, 30, 60, 90]);
  line(g, ALBEDO_THETA, e.map((x) => errorScale(x, top)), ax.X, ax.Y, "#222");
}

// ------------------------------------------------------------------------------------------ sphere

const gpu = { device: null, pipeline: null, buffers: new Map(), images: {}, error: null };

async function startGpu() {
  if (!SPHERE.wgsl) throw new Error(SPHERE.missing);
  if (!navigator.gpu) throw new Error("this browser has no WebGPU (Chrome or Edge have it; Chromium: --enable-unsafe-webgpu)");
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) throw new Error("WebGPU found no adapter (Chromium without a GPU: --enable-unsafe-webgpu)");
  const biggest = Math.max(...DATA.materials.map((m) => m.layout_bytes), 12 * SPHERE.size * SPHERE.size);
  if (biggest > adapter.limits.maxStorageBufferBindingSize) throw new Error(`a layout of ${biggest} bytes exceeds this GPU's storage buffers`);
  gpu.device = await adapter.requestDevice({ requiredLimits: {
    maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize, maxBufferSize: adapter.limits.maxBufferSize } });
  gpu.adapter = adapter.info ? `${adapter.info.vendor} ${adapter.info.architecture}`.trim() : "WebGPU";
  const module = gpu.device.createShaderModule({ code: SPHERE.wgsl });
  const info = await module.getCompilationInfo();
  const errors = info.messages.filter((m) => m.type === "error");
  if (errors.length) throw new Error("the sphere shader does not compile: " + errors.map((m) => m.message).join("; "));
  gpu.pipeline = await gpu.device.createComputePipelineAsync({ layout: "auto", compute: { module, entryPoint: "sphere_render" } });
}

async function materialBuffers(m) {
  if (!gpu.buffers.has(m)) {
    const make = (bytes) => {
      const b = gpu.device.createBuffer({ size: Math.max(bytes.length, 4), usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
      gpu.device.queue.writeBuffer(b, 0, bytes);
      return b;
    };
    const material = DATA.materials[m];
    gpu.buffers.set(m, [make(await unpack(material.layout, material.layout_bytes)), make(decode(material.desc))]);
  }
  return gpu.buffers.get(m);
}

// brdfz.examples.realtime.dispatches: bounded work per dispatch, against drivers' watchdogs.
function dispatches(size, n) {
  const per = Math.max(1, Math.min(n, Math.floor((1 << 20) / (size * size)))), out = [];
  for (let first = 0; first < Math.max(n, 1); first += per) out.push([first, Math.min(per, n - first)]);
  return out;
}

// Linear RGB radiance (size² × 3) of material m under the light with the draws of `seed`, as
// realtime.SphereRenderer.render.
async function renderSphere(m, light, seed) {
  const { device, pipeline } = gpu, size = SPHERE.size, n = SPHERE.env_samples;
  const [material, desc] = await materialBuffers(m);
  const bytes = 12 * size * size;
  const out = device.createBuffer({ size: bytes, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
  const read = device.createBuffer({ size: bytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const side = Math.max(Math.floor(Math.sqrt(n)), 1);
  const encoder = device.createCommandEncoder();
  for (const [first, count] of dispatches(size, n)) {
    const params = new ArrayBuffer(48), u = new Uint32Array(params), f = new Float32Array(params);
    u.set([size, n, first, count, seed, side]);
    f.set([1 / side, SPHERE.irradiance, light[0], light[1], light[2]], 6);
    const uniform = device.createBuffer({ size: 48, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(uniform, 0, params);
    const group = device.createBindGroup({ layout: pipeline.getBindGroupLayout(0), entries: [
      { binding: 0, resource: { buffer: material } }, { binding: 1, resource: { buffer: desc } },
      { binding: 2, resource: { buffer: uniform } }, { binding: 3, resource: { buffer: out } }] });
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline); pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(Math.ceil(size / 8), Math.ceil(size / 8));
    pass.end();
  }
  encoder.copyBufferToBuffer(out, 0, read, 0, bytes);
  device.queue.submit([encoder.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const image = new Float32Array(read.getMappedRange().slice(0));
  read.unmap(); out.destroy(); read.destroy();
  return image;
}

function exposureOf(image) {  // report.exposure_of: the 99th percentile of luminance to 0.8
  const lum = [];
  for (let i = 0; i < image.length; i += 3) { const l = (image[i] + image[i + 1] + image[i + 2]) / 3; if (l > 0) lum.push(l); }
  return 0.8 / Math.max(lum.length ? percentile(lum, 0.99) : 1, 1e-12);
}
function putSphere(id, colour) {
  const c = $(id), size = SPHERE.size;
  c.width = c.height = size;
  const g = c.getContext("2d"), img = g.createImageData(size, size);
  for (let p = 0; p < size * size; p++) { const rgb = colour(p); img.data.set([rgb[0], rgb[1], rgb[2], 255], 4 * p); }
  g.putImageData(img, 0, 0);
}
// The sun's elevation in each pixel's frame beyond A's measured range: plot.sun_elevation's mask.
function sunMasked(p, tmax, l) {
  const size = SPHERE.size, x = (2 * (p % size) + 1 - size) / size, y = (size - 2 * Math.floor(p / size) - 1) / size;
  const z = Math.sqrt(Math.max(0, 1 - x * x - y * y));
  const d = Math.hypot(x - l[0], y - l[1], z - l[2]);
  return 2 * Math.asin(Math.min(0.5 * d, 1)) > tmax;
}
function drawSpheres() {
  const A = gpu.images.a, B = gpu.images.b;
  if (!A || !B) return;
  const exposure = exposureOf(A);
  const tone = (v) => Math.round(255 * Math.min(Math.max(v * exposure, 0), 1) ** (1 / 2.2));
  for (const [which, im] of [["a", A], ["b", B]]) putSphere(`sphere-${which}`, (p) => [tone(im[3 * p]), tone(im[3 * p + 1]), tone(im[3 * p + 2])]);
  const tmax = DATA.materials[state.a].theta_max, n = SPHERE.size * SPHERE.size;
  const e = new Float64Array(n);
  for (let p = 0; p < n; p++) {
    const a = (A[3 * p] + A[3 * p + 1] + A[3 * p + 2]) / 3, b = (B[3 * p] + B[3 * p + 1] + B[3 * p + 2]) / 3;
    e[p] = a > 0 && !sunMasked(p, tmax, gpu.images.light) ? errorOf(a, b) : NaN;
  }
  const top = errorTop(e);
  putSphere("sphere-e", (p) => (Number.isFinite(e[p]) ? diverging(e[p], top) : (A[3 * p] > 0 ? MASKED : [0, 0, 0])));
}

// One render at a time; a light moved meanwhile is rendered next, the intermediate ones skipped. Pass p
// draws the sky with seed SPHERE.seed + p; the images shown are the means of the passes so far, so the
// sampling noise in the spheres and their error falls as the passes come in.
let rendering = null, pending = false;
function requestSpheres() {
  if (!gpu.pipeline) return Promise.resolve();
  if (rendering) { pending = true; return rendering; }
  rendering = (async () => {
    do {
      pending = false;
      const light = state.light.slice(), a = state.a, b = state.b;
      const sum = { a: new Float64Array(3 * SPHERE.size * SPHERE.size), b: new Float64Array(3 * SPHERE.size * SPHERE.size) };
      for (let p = 0; p < SPHERE.passes && !pending; p++) {
        const images = await Promise.all([renderSphere(a, light, SPHERE.seed + p), renderSphere(b, light, SPHERE.seed + p)]);
        const mean = {};
        for (const [k, which] of [[0, "a"], [1, "b"]]) {
          sum[which].forEach((v, i) => { sum[which][i] = v + images[k][i]; });
          mean[which] = sum[which].map((v) => v / (p + 1));
        }
        Object.assign(gpu.images, { a: mean.a, b: mean.b, light, materials: [a, b], passes: p + 1 });
        drawSpheres();
        $("sphere-draws").textContent = `; ${(p + 1) * SPHERE.env_samples} sky draws per pixel`;
      }
    } while (pending);
  })().catch((e) => { status(`sphere: ${e.message}`); console.warn(e); }).finally(() => { rendering = null; });
  return rendering;
}

// The mouse on a sphere is the sun's direction: on the disc, the normal there; off it, the horizon.
function lightFromMouse(event) {
  const r = event.target.getBoundingClientRect();
  let x = 2 * (event.clientX - r.left) / r.width - 1, y = 1 - 2 * (event.clientY - r.top) / r.height;
  const d = Math.hypot(x, y);
  if (d > 0.999) { x *= 0.999 / d; y *= 0.999 / d; }
  return normalise([x, y, Math.sqrt(Math.max(0, 1 - x * x - y * y))]);
}

// ------------------------------------------------------------------------------------------ page

function status(text) { $("status").textContent = text; }
function drawAll() {
  for (const w of ["a", "b"]) {
    const m = DATA.materials[state[w]];
    $(`head-${w}`).textContent = `${w.toUpperCase()}: ${m.label}`;
    $(`about-${w}`).textContent = `${w.toUpperCase()}: ${m.source}: ${m.describe} — ${m.bytes.toLocaleString("en")} bytes; `
      + `measured to θ ${(m.theta_max / DEG).toFixed(1)}°`
      + (m.sphere_describe.endsWith(m.describe) ? "" : `; its sphere draws ${m.sphere_describe}`);
    drawPolar(w); drawLobe(w); drawSlice(w); drawAlbedo(w);
  }
  $("head-e").textContent = state.error === "absolute" ? "absolute error B − A" : "relative error (B − A) / A";
  drawPolarError(); drawLobeError(); drawSliceError(); drawAlbedoError();
}

const plotted = { polar: {}, slice: {} };
// For tests and scripts: what the page drew, and a promise for the end of the spheres' rendering.
const api = {
  materials: DATA.materials.map((m) => m.label),
  gpu: () => gpu.adapter || null,
  error: () => gpu.error,
  light: () => state.light.slice(),
  // Linear radiance the GPU returned for A or B (row-major, r g b), with the light it was lit by.
  // The mean of `passes` renders, pass p with seed + p.
  sphere: (which) => ({ light: gpu.images.light, material: gpu.images.materials[which === "a" ? 0 : 1],
    size: SPHERE.size, env_samples: SPHERE.env_samples, seed: SPHERE.seed, passes: gpu.images.passes,
    pixels: Array.from(gpu.images[which]) }),
  polar: (which) => plotted.polar[which],
  // The polar error panel's values (θi-major, as polar's), in the error mode chosen.
  polarError: () => plotted.polarError,
  slice: (which) => plotted.slice[which],  // θd rows × θh columns at bin centres over [0, 90°)
  idle: async () => { while (rendering) await rendering; },
};
window.brdfzView = api;

function setup() {
  for (const w of ["a", "b"]) {
    const pick = $(`pick-${w}`);
    DATA.materials.forEach((m, k) => pick.add(new Option(m.label, k)));
    pick.value = state[w];
    pick.onchange = () => { state[w] = +pick.value; drawAll(); requestSpheres(); };
  }
  const theta = $("pick-theta");
  THETA_I.forEach((t, k) => theta.add(new Option(`${t}°`, k)));
  theta.value = state.lobeTheta;
  theta.onchange = () => { state.lobeTheta = +theta.value; drawAll(); };
  $("log").onchange = () => { state.log = $("log").checked; drawAll(); };
  $("pick-error").onchange = () => { state.error = $("pick-error").value; drawAll(); drawSpheres(); };
  for (const w of ["a", "b", "e"]) {
    const c = $(`sphere-${w}`);
    const move = (ev) => { if (ev.buttons & 1) { ev.preventDefault(); state.light = lightFromMouse(ev); requestSpheres(); } };
    c.addEventListener("mousedown", move); c.addEventListener("mousemove", move);
    const lobe = $(`lobe-${w}`);
    let last = null;
    lobe.addEventListener("mousedown", (ev) => { last = [ev.clientX, ev.clientY]; });
    window.addEventListener("mouseup", () => { last = null; });
    lobe.addEventListener("mousemove", (ev) => {
      if (!last || !(ev.buttons & 1)) return;
      state.yaw += (ev.clientX - last[0]) * 0.01;
      state.pitch = Math.min(Math.max(state.pitch + (ev.clientY - last[1]) * 0.01, -0.2), 1.5);
      last = [ev.clientX, ev.clientY];
      drawLobe("a"); drawLobe("b"); drawLobeError();
    });
  }
  $("slice-about").textContent = `f_r (mean) at φd = ${DATA.slice_phi_d}°`;
  drawAll();
  api.ready = startGpu().then(requestSpheres, (e) => {
    gpu.error = e.message;
    status(`sphere unavailable: ${e.message}`);
  });
}
setup();
})();
