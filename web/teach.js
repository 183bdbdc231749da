// The teaching page: dials, pictures and plots around shadelab's engine (shadelab_web.wasm).
// Every number the page shows comes from the engine: this file only reads the controls, calls
// the engine through its plain C ABI (web/engine/src/lib.rs) and draws what comes back.
"use strict";

// ---- Defaults and the URL (shareable states) ----

const DEFAULTS = {
  stimulus: "gaussian",
  light: { tilt: 0, slant: 45 },
  assume: { tilt: 0, slant: 45 },
  size: 128,
  rotate: false,
  prior: false,
  kappa: 2,
  pi: 0.5,
};
const PRIOR_TILT = 26; // degrees to the left of vertical (Mamassian & Goutcher 2001)
const SIZE_RANGE = [32, 512];
const problems = []; // what was wrong with the URL, shown on the page

function showMessage(text) {
  const box = document.getElementById("message");
  box.textContent = text;
  box.classList.toggle("shown", text !== "");
}

// "tilt:T,slant:S" (either part may be missing) → {tilt, slant}, or null with a problem noted.
function parseLight(name, text, fallback) {
  const light = { ...fallback };
  for (const part of text.split(",")) {
    const [key, value] = part.split(":");
    const v = Number(value);
    if ((key !== "tilt" && key !== "slant") || value === undefined || value.trim() === "" || !Number.isFinite(v)) {
      problems.push(`${name}=${text}: give ${name}=tilt:T,slant:S with numbers in degrees, e.g. ${name}=tilt:0,slant:45`);
      return fallback;
    }
    light[key] = v;
  }
  if (light.slant < 0 || light.slant >= 90) {
    problems.push(`${name}=${text}: the slant must be in 0..90 degrees`);
    return fallback;
  }
  light.tilt = ((light.tilt % 360) + 360) % 360;
  return light;
}

function readUrl(names) {
  const q = new URLSearchParams(location.search);
  const state = { ...DEFAULTS, light: { ...DEFAULTS.light }, assume: { ...DEFAULTS.assume } };
  if (q.has("stimulus")) {
    const s = q.get("stimulus");
    if (names.includes(s)) state.stimulus = s;
    else problems.push(`stimulus=${s}: unknown; choose one of ${names.join(", ")}`);
  }
  if (q.has("light")) state.light = parseLight("light", q.get("light"), state.light);
  if (q.has("assume")) state.assume = parseLight("assume", q.get("assume"), state.assume);
  if (q.has("size")) {
    const n = Number(q.get("size"));
    if (Number.isInteger(n) && n >= SIZE_RANGE[0] && n <= SIZE_RANGE[1]) state.size = n;
    else problems.push(`size=${q.get("size")}: give a whole number of pixels from ${SIZE_RANGE[0]} to ${SIZE_RANGE[1]}`);
  }
  if (q.has("rotate")) state.rotate = q.get("rotate") === "1" || q.get("rotate") === "180";
  if (q.has("prior")) state.prior = q.get("prior") !== "0" && q.get("prior") !== "off";
  for (const [key, lo, hi] of [["kappa", 0, 8], ["pi", 0.01, 0.99]]) {
    if (!q.has(key)) continue;
    const v = Number(q.get(key));
    if (Number.isFinite(v) && v >= lo && v <= hi) state[key] = v;
    else problems.push(`${key}=${q.get(key)}: give a number from ${lo} to ${hi}`);
  }
  const bench = q.has("bench") ? Number(q.get("bench")) : 0;
  if (q.has("bench") && !(Number.isInteger(bench) && bench > 0 && bench <= 1000)) {
    problems.push(`bench=${q.get("bench")}: give a number of frames from 1 to 1000`);
  }
  return { state, bench: Number.isInteger(bench) && bench > 0 && bench <= 1000 ? bench : 0 };
}

// The current state in the address bar, so that a state can be shared.
function writeUrl(state) {
  const q = new URLSearchParams(location.search);
  q.set("stimulus", state.stimulus);
  q.set("light", `tilt:${Math.round(state.light.tilt)},slant:${Math.round(state.light.slant)}`);
  q.set("assume", `tilt:${Math.round(state.assume.tilt)},slant:${Math.round(state.assume.slant)}`);
  q.set("size", state.size);
  if (state.rotate) q.set("rotate", "1"); else q.delete("rotate");
  if (state.prior) q.set("prior", "1"); else q.delete("prior");
  history.replaceState(null, "", "?" + q.toString());
}

// ---- The engine ----

class Engine {
  constructor(instance) {
    this.x = instance.exports;
  }
  text() {
    return new TextDecoder().decode(new Uint8Array(this.x.memory.buffer, this.x.sl_text_ptr(), this.x.sl_text_len()));
  }
  stimuli() {
    if (!this.x.sl_stimuli()) throw new Error(this.text());
    return JSON.parse(this.text());
  }
  // One frame; returns {summary, picture, depthRgba, depth, target} or throws the engine's error.
  frame(s) {
    const name = new TextEncoder().encode(s.stimulus);
    const ptr = this.x.sl_alloc(name.length);
    new Uint8Array(this.x.memory.buffer, ptr, name.length).set(name);
    const ok = this.x.sl_frame(ptr, name.length, s.size, s.light.tilt, s.light.slant,
      s.rotate ? 1 : 0, s.assume.tilt, s.assume.slant);
    this.x.sl_free(ptr, name.length);
    if (!ok) throw new Error(this.text());
    const summary = JSON.parse(this.text());
    const n = summary.width * summary.height;
    const mem = this.x.memory.buffer; // read after the call: memory may have grown
    return {
      summary,
      picture: new Uint8ClampedArray(mem, this.x.sl_buffer(0), 4 * n).slice(),
      depthRgba: new Uint8ClampedArray(mem, this.x.sl_buffer(1), 4 * n).slice(),
      depth: new Float32Array(mem, this.x.sl_buffer(2), n).slice(),
      target: new Uint8Array(mem, this.x.sl_buffer(3), n).slice(),
    };
  }
  pConvex(theta, kappa, pi) {
    return this.x.sl_p_convex(theta, PRIOR_TILT, kappa, pi, 0);
  }
}

// ---- Dials: tilt is the angle (0 = up, +90 = left), slant the distance from the centre ----

class Dial {
  constructor(svg, state, onChange) {
    this.svg = svg;
    this.state = state; // {tilt, slant}, changed in place
    this.onChange = onChange;
    const ns = "http://www.w3.org/2000/svg";
    const el = (tag, attrs) => {
      const e = document.createElementNS(ns, tag);
      for (const k in attrs) e.setAttribute(k, attrs[k]);
      svg.appendChild(e);
      return e;
    };
    el("circle", { r: 96, fill: "#fff", stroke: "#999", "stroke-width": 2 });
    for (const r of [32, 64]) el("circle", { r, fill: "none", stroke: "#ddd" });
    el("line", { x1: 0, y1: -96, x2: 0, y2: 96, stroke: "#eee" });
    el("line", { x1: -96, y1: 0, x2: 96, y2: 0, stroke: "#eee" });
    for (const [t, x, y] of [["above", 0, -80], ["left", -74, 4], ["right", 74, 4], ["below", 0, 88]]) {
      const label = el("text", { x, y, "text-anchor": "middle", "font-size": 13, fill: "#888" });
      label.textContent = t;
    }
    this.ray = el("line", { x1: 0, y1: 0, stroke: "#c45a00", "stroke-width": 3 });
    this.sun = el("circle", { r: 12, fill: "#ffc83d", stroke: "#c45a00", "stroke-width": 3 });
    svg.addEventListener("pointerdown", (e) => {
      svg.setPointerCapture(e.pointerId);
      this.pointer(e);
    });
    svg.addEventListener("pointermove", (e) => {
      if (svg.hasPointerCapture(e.pointerId)) this.pointer(e);
    });
    svg.addEventListener("keydown", (e) => this.key(e));
    this.draw();
  }
  pointer(e) {
    const box = this.svg.getBoundingClientRect();
    const x = ((e.clientX - box.left) / box.width) * 200 - 100;
    const y = ((e.clientY - box.top) / box.height) * 200 - 100;
    const r = Math.min(Math.hypot(x, y), 96);
    this.set(Math.atan2(-x, -y) * 180 / Math.PI, Math.min(89, (r / 96) * 90));
    e.preventDefault();
  }
  key(e) {
    const step = e.shiftKey ? 15 : 5;
    const moves = { ArrowLeft: [step, 0], ArrowRight: [-step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] };
    const m = moves[e.key];
    if (!m) return;
    this.set(this.state.tilt + m[0], Math.max(0, Math.min(89, this.state.slant + m[1])));
    e.preventDefault();
  }
  set(tilt, slant) {
    this.state.tilt = ((Math.round(tilt) % 360) + 360) % 360;
    this.state.slant = Math.round(slant);
    this.draw();
    this.onChange();
  }
  draw() {
    const r = (this.state.slant / 90) * 96;
    const a = this.state.tilt * Math.PI / 180;
    const x = -Math.sin(a) * r, y = -Math.cos(a) * r;
    this.ray.setAttribute("x2", x);
    this.ray.setAttribute("y2", y);
    this.sun.setAttribute("cx", x);
    this.sun.setAttribute("cy", y);
    this.svg.setAttribute("aria-valuemin", 0);
    this.svg.setAttribute("aria-valuemax", 359);
    this.svg.setAttribute("aria-valuenow", this.state.tilt);
    this.svg.setAttribute("aria-valuetext", describeLight(this.state));
  }
}

function describeLight(l) {
  const t = Math.round(l.tilt);
  const side = t === 0 ? "from above" : t === 180 ? "from below" : t < 180 ? `${t}° toward the left` : `${360 - t}° toward the right`;
  return `tilt ${t}° (${side}), slant ${Math.round(l.slant)}°`;
}

// ---- Drawing ----

// Draws an RGBA buffer of w×h pixels scaled into a canvas, keeping its proportions.
function drawPicture(canvas, rgba, w, h) {
  const off = document.createElement("canvas");
  off.width = w;
  off.height = h;
  off.getContext("2d").putImageData(new ImageData(rgba, w, h), 0, 0);
  canvas.height = Math.round((canvas.width * h) / w); // the picture's proportions
  const ctx = canvas.getContext("2d");
  const scale = Math.min(canvas.width / w, canvas.height / h);
  const [dw, dh] = [w * scale, h * scale];
  const [x0, y0] = [(canvas.width - dw) / 2, (canvas.height - dh) / 2];
  ctx.fillStyle = "#000";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.imageSmoothingEnabled = true;
  ctx.drawImage(off, x0, y0, dw, dh);
  return { x0, y0, scale };
}

// Outlines the target's bounding box with corner marks.
function markTarget(canvas, place, target, w, h) {
  let [c0, r0, c1, r1] = [w, h, -1, -1];
  for (let i = 0; i < target.length; i++) {
    if (!target[i]) continue;
    const c = i % w, r = (i / w) | 0;
    c0 = Math.min(c0, c); c1 = Math.max(c1, c); r0 = Math.min(r0, r); r1 = Math.max(r1, r);
  }
  if (c1 < 0) return;
  const ctx = canvas.getContext("2d");
  const x = place.x0 + c0 * place.scale - 3, y = place.y0 + r0 * place.scale - 3;
  const bw = (c1 - c0 + 1) * place.scale + 6, bh = (r1 - r0 + 1) * place.scale + 6;
  const k = Math.min(bw, bh) / 5;
  ctx.strokeStyle = "#ff8c1a";
  ctx.lineWidth = 3;
  ctx.beginPath();
  for (const [px, py, dx, dy] of [[x, y, 1, 1], [x + bw, y, -1, 1], [x, y + bh, 1, -1], [x + bw, y + bh, -1, -1]]) {
    ctx.moveTo(px + dx * k, py);
    ctx.lineTo(px, py);
    ctx.lineTo(px, py + dy * k);
  }
  ctx.stroke();
}

// A 3-D view of the depth map: rows as ridge lines seen from slightly above the front, far
// rows first, each filled white below so nearer rows hide what lies behind them.
function drawRelief(canvas, depth, w, h) {
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  let lo = Infinity, hi = -Infinity;
  for (const z of depth) { lo = Math.min(lo, z); hi = Math.max(hi, z); }
  const span = hi - lo || 1;
  const lines = Math.min(48, h);
  const margin = 16;
  const rise = canvas.height * 0.35; // the tallest relief, pixels on screen
  const floor = (canvas.height - 2 * margin - rise) / Math.max(1, lines - 1);
  const width = canvas.width - 2 * margin;
  for (let k = 0; k < lines; k++) {
    const r = Math.round((k * (h - 1)) / Math.max(1, lines - 1));
    const base = margin + rise + k * floor;
    ctx.beginPath();
    ctx.moveTo(margin, base);
    for (let c = 0; c < w; c++) {
      const z = (depth[r * w + c] - lo) / span;
      ctx.lineTo(margin + (c / (w - 1)) * width, base - z * rise);
    }
    ctx.lineTo(margin + width, base);
    ctx.closePath();
    ctx.fillStyle = "#fff";
    ctx.fill();
    ctx.strokeStyle = `hsl(215, 45%, ${55 - (25 * k) / lines}%)`;
    ctx.lineWidth = 1.2;
    ctx.stroke();
  }
  ctx.fillStyle = "#888";
  ctx.font = "12px system-ui, sans-serif";
  ctx.fillText("top of the picture (far rows)", margin, 12);
}

// Depth along the row and the column through the target's centre.
function drawProfile(canvas, depth, w, h, centre) {
  const ctx = canvas.getContext("2d");
  const [W, H, m] = [canvas.width, canvas.height, 28];
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, W, H);
  const row = Math.round(centre[1]), col = Math.round(centre[0]);
  const across = Array.from({ length: w }, (_, c) => depth[row * w + c]);
  const down = Array.from({ length: h }, (_, r) => depth[r * w + col]);
  let lo = Math.min(...across, ...down), hi = Math.max(...across, ...down);
  if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
  const y = (z) => H - m - ((z - lo) / (hi - lo)) * (H - 2 * m);
  ctx.strokeStyle = "#ccc";
  ctx.beginPath();
  ctx.moveTo(m, m / 2); ctx.lineTo(m, H - m); ctx.lineTo(W - 8, H - m);
  ctx.stroke();
  ctx.fillStyle = "#666";
  ctx.font = "12px system-ui, sans-serif";
  ctx.save();
  ctx.translate(12, H / 2 + 30);
  ctx.rotate(-Math.PI / 2);
  ctx.fillText("nearer →", 0, 0);
  ctx.restore();
  const series = [[across, "#c45a00", "left → right through the target"], [down, "#2060b0", "top → bottom through the target"]];
  series.forEach(([values, colour, label], i) => {
    ctx.strokeStyle = colour;
    ctx.lineWidth = 2;
    ctx.beginPath();
    values.forEach((z, k) => {
      const x = m + (k / (values.length - 1)) * (W - m - 10);
      if (k === 0) ctx.moveTo(x, y(z)); else ctx.lineTo(x, y(z));
    });
    ctx.stroke();
    ctx.fillStyle = colour;
    ctx.fillText(label, m + 8, 14 + 15 * i);
  });
}

// ---- The page ----

// The engine is compiled and every first frame (and a benchmark) drawn synchronously, while
// the page loads: the page works from file:// too, and a headless browser that saves the page
// at its load event sees the finished state with real frame times.
function main() {
  let engine;
  try {
    if (typeof SHADELAB_WASM_BASE64 !== "string") throw new Error("shadelab_web.js did not load");
    const text = atob(SHADELAB_WASM_BASE64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    engine = new Engine(new WebAssembly.Instance(new WebAssembly.Module(bytes), {}));
  } catch (e) {
    showMessage(`The engine could not start (${e.message}). This page needs a browser with WebAssembly; build it with web/build.sh.`);
    return;
  }
  const stimuli = engine.stimuli();
  const { state, bench } = readUrl(stimuli.map((s) => s.name));
  showMessage(problems.length ? `Some URL parameters were not understood and were left at their defaults: ${problems.join("; ")}.` : "");

  const $ = (id) => document.getElementById(id);
  const picker = $("stimulus");
  for (const s of stimuli) {
    const o = document.createElement("option");
    o.value = s.name;
    o.textContent = `${s.name} — ${s.summary}`;
    picker.appendChild(o);
  }
  picker.value = state.stimulus;
  $("rotate").setAttribute("aria-pressed", String(state.rotate));
  $("prior").checked = state.prior;
  $("kappa").value = state.kappa;
  $("pi").value = state.pi;

  let last = null;
  let pending = false;
  const schedule = () => {
    if (!pending) {
      pending = true;
      requestAnimationFrame(() => { pending = false; render(); });
    }
  };
  // The sideways discs are lit from the left or the right only: the true light snaps to the
  // side its tilt is on (the engine picks the side the same way: tilts 0..180 are left).
  const sideOnly = () => stimuli.find((x) => x.name === state.stimulus).lit === "side";
  const snapLight = () => {
    if (sideOnly()) state.light.tilt = state.light.tilt < 180 ? 90 : 270;
  };
  const lightDial = new Dial($("light-dial"), state.light, () => { snapLight(); lightDial.draw(); schedule(); });
  const assumeDial = new Dial($("assume-dial"), state.assume, schedule);

  function describeStimulus() {
    const s = stimuli.find((x) => x.name === state.stimulus);
    $("explanation").textContent = s.explanation;
    const link = $("docs-link");
    link.textContent = s.docs;
    link.href = s.docs; // build.sh copies docs/*.md beside the page
    const painted = s.lit === "painted";
    $("light-dial").setAttribute("aria-disabled", String(painted));
    $("light-dial").style.opacity = painted ? 0.4 : 1;
    snapLight();
    lightDial.draw();
  }

  // The observer's P(convex) for the last frame's bright side.
  function observe() {
    $("kappa-value").textContent = Number(state.kappa).toFixed(1);
    $("pi-value").textContent = Number(state.pi).toFixed(2);
    if (!last) return;
    const theta = last.summary.bright_side_deg;
    $("theta").textContent = `θ = ${describeLight({ tilt: theta, slant: 0 }).replace(/, slant.*/, "")}`;
    if (state.prior) {
      const p = engine.pConvex(theta, state.kappa, state.pi);
      $("p-convex").textContent = p.toFixed(2);
      $("p-bar").style.width = `${(100 * p).toFixed(1)}%`;
    } else {
      $("p-convex").textContent = "– (turn the prior on)";
      $("p-bar").style.width = "0";
    }
  }

  function render() {
    $("light-readout").textContent = describeLight(state.light);
    $("assume-readout").textContent = describeLight(state.assume);
    $("size-readout").textContent = `${state.size} (longer side)`;
    writeUrl(state);
    let f;
    const t0 = performance.now();
    try {
      f = engine.frame(state);
    } catch (e) {
      showMessage(`The engine could not show this: ${e.message}`);
      return null;
    }
    const ms = performance.now() - t0;
    $("frame-ms").textContent = ms.toFixed(1);
    last = f;
    const { width: w, height: h } = f.summary;
    const place = drawPicture($("picture"), f.picture, w, h);
    markTarget($("picture"), place, f.target, w, h);
    drawPicture($("depth"), f.depthRgba, w, h);
    drawRelief($("relief"), f.depth, w, h);
    drawProfile($("profile"), f.depth, w, h, f.summary.target_centre);
    const v = $("verdict");
    v.textContent = f.summary.verdict;
    v.dataset.verdict = f.summary.verdict;
    v.title = `convexity ${f.summary.convexity.toFixed(4)} of ${f.summary.target}`;
    observe();
    return ms;
  }

  picker.addEventListener("change", () => { state.stimulus = picker.value; describeStimulus(); schedule(); });
  const rotate = () => {
    state.rotate = !state.rotate;
    $("rotate").setAttribute("aria-pressed", String(state.rotate));
    schedule();
  };
  $("rotate").addEventListener("click", rotate);
  $("match").addEventListener("click", () => assumeDial.set(state.light.tilt, state.light.slant));
  $("opposite").addEventListener("click", () => assumeDial.set(state.assume.tilt + 180, state.assume.slant));
  $("prior").addEventListener("change", () => { state.prior = $("prior").checked; writeUrl(state); observe(); });
  $("kappa").addEventListener("input", () => { state.kappa = Number($("kappa").value); observe(); });
  $("pi").addEventListener("input", () => { state.pi = Number($("pi").value); observe(); });
  document.addEventListener("keydown", (e) => {
    if (e.target.closest && e.target.closest("input, select, .dial")) return;
    if (e.key === "r" || e.key === "R") rotate();
    if (e.key === "m" || e.key === "M") $("match").click();
    if (e.key === "o" || e.key === "O") $("opposite").click();
  });

  describeStimulus();
  render();

  // Benchmark mode (?bench=N): N frames, the assumed light turning in equal steps; the frame
  // times go into <output id="bench"> as JSON.
  if (bench) {
    const times = [];
    for (let i = 0; i < bench; i++) {
      state.assume.tilt = (i * 360) / bench;
      const ms = render();
      if (ms === null) break;
      times.push(ms);
    }
    assumeDial.draw();
    const sorted = [...times].sort((a, b) => a - b);
    const at = (q) => sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
    // Measured before the results are shown: the page as a class sees it.
    const pageHeight = document.documentElement.scrollHeight;
    const out = $("bench");
    out.hidden = false;
    out.textContent = JSON.stringify({
      frames: times.length, size: state.size, stimulus: state.stimulus,
      median_ms: at(0.5), p90_ms: at(0.9), max_ms: sorted[sorted.length - 1], times_ms: times,
      // The page's laid-out height against the window's: the page is meant to fit a 1280×900
      // lecture screen without scrolling.
      page_height: pageHeight, window_height: window.innerHeight,
      window_width: window.innerWidth,
    });
  }
  document.body.dataset.ready = "1";
}

try {
  main();
} catch (e) {
  showMessage(`The page failed: ${e.message}`);
}
