// Small SVG plotting for the results browser: figures as the API serves
// them (means with error bars, single samples, theory curves, quoted values,
// recorded curves with a band), line traces, and the pile with its force
// chains. No dependencies, and no physics: every curve comes from the API.
(() => {
"use strict";

const SVGNS = "http://www.w3.org/2000/svg";
const PALETTE = ["#2357b5", "#c0392b", "#1f7a3f", "#8e44ad", "#d35400", "#16a085"];

function el(name, attrs = {}, parent = null) {
  const e = document.createElementNS(SVGNS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function niceTicks(lo, hi, count = 6) {
  if (!(hi > lo)) { hi = lo + 1; }
  const span = hi - lo;
  const raw = span / count;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map(m => m * mag).find(s => span / s <= count) || 10 * mag;
  const start = Math.ceil(lo / step - 1e-9) * step;
  const ticks = [];
  for (let t = start; t <= hi + step * 1e-9; t += step) ticks.push(Math.abs(t) < step * 1e-9 ? 0 : t);
  return ticks;
}

function fmt(v, digits = 3) {
  if (v === null || v === undefined || Number.isNaN(v)) return "–";
  const a = Math.abs(v);
  if (a !== 0 && (a >= 1e7 || a < 1e-3)) return v.toExponential(2);
  if (a >= 1e4 && Number.isInteger(v)) return String(v);
  return Number(v.toFixed(digits)).toString();
}

function showTip(evt, text) {
  const tip = document.getElementById("tooltip");
  if (!tip) return;
  tip.textContent = text;
  tip.hidden = false;
  tip.style.left = (evt.clientX + 12) + "px";
  tip.style.top = (evt.clientY + 12) + "px";
}

function hideTip() {
  const tip = document.getElementById("tooltip");
  if (tip) tip.hidden = true;
}

// A frame with axes; returns {svg, x(), y(), plot group}.
function frame({ width = 720, height = 440, xRange, yRange, xLabel, yLabel, title, legendWidth = 0, xTick = null }) {
  width += legendWidth;
  const m = { left: 64, right: 20 + legendWidth, top: title ? 34 : 16, bottom: 52 };
  const svg = el("svg", {
    xmlns: SVGNS, width, height, viewBox: `0 0 ${width} ${height}`,
    role: "img", "aria-label": title || `${yLabel} against ${xLabel}`,
    "font-family": "system-ui, sans-serif", "font-size": "13",
  });
  el("rect", { x: 0, y: 0, width, height, fill: "#ffffff" }, svg);
  const pw = width - m.left - m.right, ph = height - m.top - m.bottom;
  const [x0, x1] = xRange, [y0, y1] = yRange;
  const x = v => m.left + (v - x0) / (x1 - x0 || 1) * pw;
  const y = v => m.top + ph - (v - y0) / (y1 - y0 || 1) * ph;
  if (title) {
    const t = el("text", { x: m.left, y: 20, "font-size": "14", "font-weight": "600", fill: "#1d2330" }, svg);
    t.textContent = title;
  }
  const axes = el("g", { stroke: "#667085", "stroke-width": "1" }, svg);
  el("line", { x1: m.left, y1: m.top + ph, x2: m.left + pw, y2: m.top + ph }, axes);
  el("line", { x1: m.left, y1: m.top, x2: m.left, y2: m.top + ph }, axes);
  for (const t of niceTicks(x0, x1)) {
    el("line", { x1: x(t), y1: m.top + ph, x2: x(t), y2: m.top + ph + 5 }, axes);
    const lab = el("text", { x: x(t), y: m.top + ph + 19, "text-anchor": "middle", fill: "#1d2330", stroke: "none" }, svg);
    lab.textContent = xTick ? xTick(t) : fmt(t);
  }
  for (const t of niceTicks(y0, y1)) {
    el("line", { x1: m.left - 5, y1: y(t), x2: m.left, y2: y(t) }, axes);
    el("line", { x1: m.left, y1: y(t), x2: m.left + pw, y2: y(t), stroke: "#eef0f4" }, svg);
    const lab = el("text", { x: m.left - 8, y: y(t) + 4, "text-anchor": "end", fill: "#1d2330" }, svg);
    lab.textContent = fmt(t);
  }
  const xl = el("text", { x: m.left + pw / 2, y: height - 10, "text-anchor": "middle", fill: "#1d2330" }, svg);
  xl.textContent = xLabel;
  const yl = el("text", { x: 16, y: m.top + ph / 2, "text-anchor": "middle", fill: "#1d2330",
    transform: `rotate(-90 16 ${m.top + ph / 2})` }, svg);
  yl.textContent = yLabel;
  const plot = el("g", {}, svg);
  return { svg, x, y, plot, m, pw, ph };
}

function extent(values, pad = 0.06) {
  const v = values.filter(Number.isFinite);
  if (!v.length) return [0, 1];
  let lo = Math.min(...v), hi = Math.max(...v);
  if (lo === hi) { lo -= 1; hi += 1; }
  const p = (hi - lo) * pad;
  return [lo - p, hi + p];
}

// The colour of a measured series, and the legend entry of any series.
function legendItems(series) {
  let k = 0;
  return series.filter(s => s.name).map(s => {
    if (s.kind === "measured" || s.kind === "recorded") return { name: s.name, kind: s.kind, colour: PALETTE[k++ % PALETTE.length] };
    return { name: s.name, kind: s.kind, colour: "#333" };
  });
}

const DASH = { theory: "6 4", level: "2 3", fit: "none" };

// A figure as the API serves it (see /api/openapi.json, FigureData):
// measured means with error bars and their single samples, theory curves,
// level lines, the paper's quoted values, and recorded curves with their
// band. errors: "sd" | "sem" for the measured means.
function figurePlot({ fig, errors = "sd", title = null }) {
  const tx = fig.log_x ? v => (v > 0 ? Math.log10(v) : NaN) : v => v;
  const xs = [], ys = [];
  for (const s of fig.series) {
    for (const p of s.points) {
      if (!Number.isFinite(p.y)) continue;
      const e = s.kind === "measured" ? ((errors === "sem" ? p.sem : p.sd) || 0) : (p.sd || 0);
      xs.push(tx(p.x)); ys.push(p.y - e, p.y + e);
      for (const v of p.samples || []) ys.push(v);
    }
    if (s.band) ys.push(s.band.lo, s.band.hi);
  }
  const items = legendItems(fig.series);
  const legendWidth = items.length ? 40 + 7.2 * Math.max(...items.map(it => it.name.length)) : 0;
  const xLabel = fig.log_x ? `${fig.x_label} (log scale)` : fig.x_label;
  const f = frame({ xRange: extent(xs), yRange: extent(ys), xLabel, yLabel: fig.y_label, title, legendWidth, xTick: fig.log_x ? t => fmt(Number(Math.pow(10, t).toPrecision(3))) : null });
  const X = v => f.x(tx(v));
  let k = 0;
  // A fitted curve takes the colour of the measured series it was fitted to.
  const colours = new Map();
  for (const s of fig.series) {
    let colour = (s.kind === "measured" || s.kind === "recorded") ? PALETTE[k++ % PALETTE.length] : "#333";
    const key = JSON.stringify(s.series_value === undefined ? null : s.series_value);
    if (s.kind === "measured") colours.set(key, colour);
    else if (s.kind === "fit" && colours.has(key)) colour = colours.get(key);
    const g = el("g", { class: `series ${s.kind}`, "data-series": s.name || "" }, f.plot);
    const pts = s.points.filter(p => Number.isFinite(p.y));
    if (s.kind === "measured") drawMeans(f, g, s, pts, X, colour, errors);
    else if (s.kind === "quoted") drawQuoted(f, g, s, pts, X);
    else {
      if (s.band) drawBand(f, g, s.band, colour);
      const line = pts.map(p => `${X(p.x)},${f.y(p.y)}`).join(" ");
      const cls = s.kind === "recorded" ? "trace" : s.kind;
      el("polyline", { points: line, fill: "none", stroke: colour, "stroke-width": "1.5", "stroke-dasharray": DASH[s.kind] || "none", class: cls }, g);
    }
  }
  drawLegend(f, items);
  return f.svg;
}

function drawMeans(f, g, s, pts, X, colour, errors) {
  for (const p of pts) for (const v of p.samples || []) {
    el("circle", { cx: X(p.x), cy: f.y(v), r: 3, fill: colour, "fill-opacity": "0.3", class: "sample" }, g);
  }
  if (pts.length > 1) el("polyline", { points: pts.map(p => `${X(p.x)},${f.y(p.y)}`).join(" "), fill: "none", stroke: colour, "stroke-opacity": "0.35" }, g);
  for (const p of pts) {
    const e = (errors === "sem" ? p.sem : p.sd) || 0;
    errorBar(f, g, X(p.x), p.y, e, colour);
    // A flagged point (e.g. regime I) is drawn open.
    const look = p.flag ? { fill: "#ffffff", stroke: colour, "stroke-width": "2", class: "mean flagged" } : { fill: colour, class: "mean" };
    const dot = el("circle", { cx: X(p.x), cy: f.y(p.y), r: 5, tabindex: "0", ...look }, g);
    const text = `${s.name ? s.name + "\n" : ""}x = ${fmt(p.x)}\nmean = ${fmt(p.y)}\nsd = ${fmt(p.sd)}\nsem = ${fmt(p.sem)}\nn = ${p.n}` +
      (p.failures ? `\nwithout result: ${p.failures}` : "") + (p.flag ? `\n${p.flag}` : "");
    tip(dot, text);
  }
}

function drawQuoted(f, g, s, pts, X) {
  for (const p of pts) {
    errorBar(f, g, X(p.x), p.y, p.sd || 0, "#333");
    const dot = el("circle", { cx: X(p.x), cy: f.y(p.y), r: 5, fill: "#ffffff", stroke: "#333", "stroke-width": "1.5", class: "quoted", tabindex: "0" }, g);
    tip(dot, `${s.name}\nx = ${fmt(p.x)}\n${fmt(p.y)} ± ${fmt(p.sd)}`);
  }
}

function errorBar(f, g, cx, y, e, colour) {
  const bar = el("g", { class: "errorbar", stroke: colour, "stroke-width": "1.5" }, g);
  el("line", { x1: cx, y1: f.y(y - e), x2: cx, y2: f.y(y + e) }, bar);
  el("line", { x1: cx - 5, y1: f.y(y - e), x2: cx + 5, y2: f.y(y - e) }, bar);
  el("line", { x1: cx - 5, y1: f.y(y + e), x2: cx + 5, y2: f.y(y + e) }, bar);
}

function drawBand(f, g, band, colour) {
  el("rect", { x: f.m.left, y: f.y(band.hi), width: f.pw, height: Math.max(0, f.y(band.lo) - f.y(band.hi)), fill: colour, "fill-opacity": "0.08", class: "band" }, g);
  for (const v of [band.lo, band.hi]) el("line", { x1: f.m.left, x2: f.m.left + f.pw, y1: f.y(v), y2: f.y(v), stroke: colour, "stroke-dasharray": "4 3" }, g);
}

function tip(dot, text) {
  el("title", {}, dot).textContent = text;
  dot.addEventListener("mousemove", ev => showTip(ev, text));
  dot.addEventListener("mouseleave", hideTip);
  dot.addEventListener("focus", () => { const r = dot.getBoundingClientRect(); showTip({ clientX: r.right, clientY: r.bottom }, text); });
  dot.addEventListener("blur", hideTip);
}

// The legend, to the right of the plot area.
function drawLegend(f, items) {
  items.forEach((it, k) => {
    const yy = f.m.top + 12 + 18 * k, xx = f.m.left + f.pw + 16;
    if (it.kind === "measured") el("circle", { cx: xx + 11, cy: yy - 4, r: 5, fill: it.colour }, f.svg);
    else if (it.kind === "quoted") el("circle", { cx: xx + 11, cy: yy - 4, r: 5, fill: "#fff", stroke: it.colour, "stroke-width": "1.5" }, f.svg);
    else el("line", { x1: xx, y1: yy - 4, x2: xx + 22, y2: yy - 4, stroke: it.colour, "stroke-dasharray": DASH[it.kind] || "none", "stroke-width": "1.5" }, f.svg);
    el("text", { x: xx + 30, y: yy, fill: "#1d2330" }, f.svg).textContent = it.name;
  });
}

// A line trace, optionally with a horizontal band [lo, hi] and a mean line.
function linePlot({ points, xLabel, yLabel, title, band = null, logY = false, colour = "#2357b5", markers = null }) {
  const tx = logY ? v => (v > 0 ? Math.log10(v) : NaN) : v => v;
  const ys = points.map(p => tx(p.y)).filter(Number.isFinite);
  if (band) ys.push(band.lo, band.hi);
  const f = frame({ xRange: extent(points.map(p => p.x), 0.02), yRange: extent(ys), xLabel, yLabel: logY ? `log₁₀ ${yLabel}` : yLabel, title });
  if (band) {
    el("rect", { x: f.m.left, y: f.y(band.hi), width: f.pw, height: Math.max(0, f.y(band.lo) - f.y(band.hi)), fill: "#2357b5", "fill-opacity": "0.08", class: "band" }, f.plot);
    for (const v of [band.lo, band.hi]) el("line", { x1: f.m.left, x2: f.m.left + f.pw, y1: f.y(v), y2: f.y(v), stroke: "#2357b5", "stroke-dasharray": "4 3" }, f.plot);
    el("line", { x1: f.m.left, x2: f.m.left + f.pw, y1: f.y(band.mean), y2: f.y(band.mean), stroke: "#2357b5", "stroke-width": "1.2" }, f.plot);
  }
  const pts = points.filter(p => Number.isFinite(tx(p.y))).map(p => `${f.x(p.x)},${f.y(tx(p.y))}`);
  el("polyline", { points: pts.join(" "), fill: "none", stroke: colour, "stroke-width": "1.3", class: "trace" }, f.plot);
  for (const mk of markers || []) {
    el("line", { x1: f.x(mk.x), x2: f.x(mk.x), y1: f.m.top, y2: f.m.top + f.ph, stroke: "#c0392b", "stroke-dasharray": "3 3" }, f.plot);
    el("text", { x: f.x(mk.x) + 4, y: f.m.top + 12, fill: "#c0392b", "font-size": "12" }, f.plot).textContent = mk.label;
  }
  return f.svg;
}

// The final pile: discs, walls, force chains scaled by normal force, the
// surface profile h(x) and the fitted slope (method 3).
function pilePlot({ grains, contacts, walls, width, surface, angle }) {
  let xmin = 0, xmax = width, ymax = 0;
  for (const g of grains) {
    xmin = Math.min(xmin, g.position[0] - g.radius);
    xmax = Math.max(xmax, g.position[0] + g.radius);
    ymax = Math.max(ymax, g.position[1] + g.radius);
  }
  xmin -= 0.15; xmax += 0.15; ymax += 0.3;
  const ymin = -0.15;
  const W = 760, scale = W / (xmax - xmin), H = Math.max(200, (ymax - ymin) * scale);
  const px = v => (v - xmin) * scale, py = v => (ymax - v) * scale;
  const svg = el("svg", { xmlns: SVGNS, width: W, height: H, viewBox: `0 0 ${W} ${H}`, role: "img", "aria-label": "final pile with force chains", "font-family": "system-ui, sans-serif" });
  el("rect", { x: 0, y: 0, width: W, height: H, fill: "#ffffff" }, svg);
  for (const w of walls || []) {
    const n = w.normal, t = [n[1], -n[0]];
    let a = [w.point[0] - 50 * t[0], w.point[1] - 50 * t[1]], b = [w.point[0] + 50 * t[0], w.point[1] + 50 * t[1]];
    for (const l of w.limits || []) {
      if (l.axis !== 0) continue;
      if (l.min !== undefined) { a[0] = Math.max(a[0], l.min); b[0] = Math.max(b[0], l.min); }
      if (l.max !== undefined) { a[0] = Math.min(a[0], l.max); b[0] = Math.min(b[0], l.max); }
    }
    const clip = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
    el("line", { x1: px(clip(a[0], xmin, xmax)), y1: py(clip(a[1], ymin, ymax)), x2: px(clip(b[0], xmin, xmax)), y2: py(clip(b[1], ymin, ymax)), stroke: "#333", "stroke-width": "3", class: "wall" }, svg);
  }
  const discs = el("g", { class: "grains" }, svg);
  for (const g of grains) {
    el("circle", { cx: px(g.position[0]), cy: py(g.position[1]), r: g.radius * scale, fill: "#e8dcc0", stroke: "#b8a57a", "stroke-width": "0.6", class: "grain" }, discs);
  }
  const byId = new Map(grains.map(g => [g.id, g]));
  const fmax = Math.max(0, ...(contacts || []).map(c => c.force));
  const chains = el("g", { class: "chains", stroke: "#202020", "stroke-linecap": "round" }, svg);
  for (const c of contacts || []) {
    const a = byId.get(c.a), b = byId.get(c.b);
    if (!a || !b || !(fmax > 0)) continue;
    el("line", { x1: px(a.position[0]), y1: py(a.position[1]), x2: px(b.position[0]), y2: py(b.position[1]), "stroke-width": (0.3 + 5 * c.force / fmax).toFixed(2), class: "chain" }, chains);
  }
  if (surface) {
    const pts = surface.x.map((x, i) => `${px(x)},${py(surface.h[i])}`);
    el("polyline", { points: pts.join(" "), fill: "none", stroke: "#c0392b", "stroke-width": "1.6", "stroke-dasharray": "5 3", class: "surface" }, svg);
    if (Number.isFinite(angle)) {
      // The fitted slope (method 3) through the mean of h(x).
      const n = surface.x.length;
      const xm = surface.x.reduce((s, v) => s + v, 0) / n, hm = surface.h.reduce((s, v) => s + v, 0) / n;
      const slope = -Math.tan(angle * Math.PI / 180);
      const x0 = surface.x[0], x1 = surface.x[n - 1];
      el("line", { x1: px(x0), y1: py(hm + slope * (x0 - xm)), x2: px(x1), y2: py(hm + slope * (x1 - xm)), stroke: "#2357b5", "stroke-width": "2", class: "fit" }, svg);
      const t = el("text", { x: W - 12, y: 22, "text-anchor": "end", fill: "#2357b5", "font-size": "15" }, svg);
      t.textContent = `θ_R = ${angle.toFixed(1)}° (method 3)`;
    }
  }
  return svg;
}

function svgText(svg) {
  return new XMLSerializer().serializeToString(svg);
}

function download(name, text, type) {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = document.createElement("a");
  a.href = url; a.download = name;
  document.body.appendChild(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

function downloadPng(name, svg) {
  const w = Number(svg.getAttribute("width")), h = Number(svg.getAttribute("height"));
  const img = new Image();
  img.onload = () => {
    const c = document.createElement("canvas");
    c.width = 2 * w; c.height = 2 * h;
    const ctx = c.getContext("2d");
    ctx.scale(2, 2);
    ctx.drawImage(img, 0, 0);
    c.toBlob(b => {
      const url = URL.createObjectURL(b);
      const a = document.createElement("a");
      a.href = url; a.download = name; document.body.appendChild(a); a.click(); a.remove();
      setTimeout(() => URL.revokeObjectURL(url), 1000);
    });
  };
  img.src = "data:image/svg+xml;charset=utf-8," + encodeURIComponent(svgText(svg));
}

// One side view of a heap: the outline of its projection (columns of
// `profile`, lengths in m, shown in grain diameters d) over the plate, and
// the triangle on the plate of the same area, whose slope is θ_r =
// atan(4A/b²) (`view`: the service's measurement of this projection).
function sideViewPlot({ profile, d, plate, view, label }) {
  const xs = profile.x.map(v => v / d), hs = profile.h.map(v => v / d), w = profile.cell_width / d;
  const half = plate / 2, apex = 2 * view.area / plate;
  const top = Math.max(apex, ...hs) * 1.15 + 0.5;
  const f = frame({ width: 560, height: 300, xRange: [-half - 1, half + 1], yRange: [0, top],
    xLabel: `${label[0]} (d)`, yLabel: "z (d)", title: `${label} projection: θ_r = ${fmt(view.theta_plate, 2)}°` });
  const outline = [`${f.x(xs[0] - w / 2)},${f.y(0)}`];
  xs.forEach((x, k) => { outline.push(`${f.x(x - w / 2)},${f.y(hs[k])}`, `${f.x(x + w / 2)},${f.y(hs[k])}`); });
  outline.push(`${f.x(xs[xs.length - 1] + w / 2)},${f.y(0)}`);
  el("polygon", { points: outline.join(" "), fill: "#2357b5", "fill-opacity": "0.35", stroke: "#2357b5", class: "outline" }, f.plot);
  el("polygon", { points: `${f.x(-half)},${f.y(0)} ${f.x(0)},${f.y(apex)} ${f.x(half)},${f.y(0)}`, fill: "none", stroke: "#b54a23", "stroke-width": "2", "stroke-dasharray": "6 4", class: "triangle" }, f.plot);
  el("line", { x1: f.x(-half), y1: f.y(0), x2: f.x(half), y2: f.y(0), stroke: "#1d2330", "stroke-width": "3" }, f.plot);
  const note = el("text", { x: f.x(-half) + 6, y: f.m.top + 14, fill: "#1d2330", "font-size": "12" }, f.svg);
  note.textContent = `area ${fmt(view.area, 3)} d², equal-area triangle on the ${fmt(plate)} d plate; roughness ${fmt(view.roughness, 2)} d`;
  return f.svg;
}

window.plots = { figurePlot, linePlot, pilePlot, sideViewPlot, svgText, download, downloadPng, fmt };
})();
