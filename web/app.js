// The results browser: sweeps, the submit form with the paper's presets,
// figures with error bars, and single piles. Plain JavaScript, no build step;
// everything comes from the service's own API.
"use strict";

const { errorBarPlot, linePlot, pilePlot, svgText, download, downloadPng, theory, fmt } = window.plots;
const view = document.getElementById("view");
let timer = null;

const METRIC_LABELS = {
  theta_r: "θ_R, method 3 (°)",
  theta_r_line: "θ_R, method 2 (°)",
  theta_r_endpoints: "θ_R, method 1 (°)",
  theta_t: "θ_T (°)",
  theta_ms_mean: "steady pile angle, flux (°)",
  theta_ms_max: "largest pile angle, flux (°)",
};
const AXIS_LABELS = {
  "contact.mu": "friction coefficient μ",
  "box.width": "box width W (cm)",
  "box.height": "box height H (cm)",
  "contact.k_n": "k_n (dyn/cm^1.5)",
  "contact.gamma_n": "γ_n (1/s)",
};
const axisLabel = k => AXIS_LABELS[k] || k;

// The sweeps behind the paper's figures, queued as they are (20 samples a point).
const PRESETS = [
  { label: "Figure 2a: θ_R against H", spec: { name: "Figure 2a: θ_R against H (W = 2, μ = 0.2)", protocol: "fill_release",
      base: { box: { width: 2.0 }, contact: { mu: 0.2 } }, axes: { "box.height": [2, 3, 4, 5, 6, 7, 8] }, samples: 20, fidelity: "standard" } },
  { label: "Figure 2b: θ_R against W", spec: { name: "Figure 2b: θ_R against W, H/W = 2", protocol: "fill_release",
      base: { box: { aspect: 2.0 } }, axes: { "box.width": [1.5, 2, 2.5, 3, 3.5, 4], "contact.mu": [0.1, 0.2, 0.3] }, samples: 20, fidelity: "standard" } },
  { label: "Figure 3: θ_R against μ", spec: { name: "Figure 3: θ_R against μ (W = H = 4)", protocol: "fill_release",
      base: { box: { width: 4.0, height: 4.0 } }, axes: { "contact.mu": [0.0, 0.05, 0.1, 0.15, 0.2] }, samples: 20, fidelity: "standard" } },
  { label: "Figure 4: θ_T against μ", spec: { name: "Figure 4: θ_T against μ (W = H = 4)", protocol: "tilt",
      base: { box: { width: 4.0, height: 4.0 } }, axes: { "contact.mu": [0.05, 0.1, 0.15, 0.2] }, samples: 20, fidelity: "standard" } },
  { label: "Figure 5: constant flux", spec: { name: "Figure 5: constant flux (μ = 0.2, W = 4)", protocol: "flux",
      base: { box: { width: 4.0 }, contact: { mu: 0.2 }, flux: { v_cut: 0.1, insertions: 400 } }, samples: 1, fidelity: "standard" } },
];

async function api(path, options = {}) {
  const resp = await fetch(path, { headers: { "content-type": "application/json" }, ...options });
  let body = null;
  try { body = await resp.json(); } catch (_) { body = null; }
  return { ok: resp.ok, status: resp.status, body };
}

function h(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "onclick" || k === "onchange" || k === "onsubmit" || k === "oninput") e[k] = v;
    else if (v !== null && v !== undefined && v !== false) e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined || c === false) continue;
    e.appendChild(typeof c === "string" || typeof c === "number" ? document.createTextNode(String(c)) : c);
  }
  return e;
}

function setView(...children) {
  view.replaceChildren(...children);
  view.focus({ preventScroll: true });
}

function progressBar(p) {
  const total = p.queued + p.running + p.done + p.failed + p.cancelled || 1;
  const span = (cls, n) => h("span", { class: cls, style: `width:${(100 * n / total).toFixed(1)}%` });
  return h("div", { class: "bar", role: "img", "aria-label": `${p.done} done, ${p.running} running, ${p.queued} queued, ${p.failed} errored` },
    span("done", p.done), span("running", p.running), span("failed", p.failed), span("cancelled", p.cancelled));
}

// Job counts. A job is done when its sample is stored, whatever the sample's
// outcome; "errored" counts jobs whose worker gave up on them.
function counts(p) {
  return `${p.done} done · ${p.running} running · ${p.queued} queued · ${p.failed} errored` + (p.cancelled ? ` · ${p.cancelled} cancelled` : "");
}

// A sweep's state as a user reads it: an active sweep with nothing left to run has finished.
function stateTag(s) {
  const label = s.state === "active" ? (unfinished(s.progress) ? "running" : "finished") : s.state;
  return h("span", { class: `tag ${label}` }, label);
}

function eta(s) {
  if (s === null || s === undefined) return "–";
  if (s === 0) return "done";
  if (s < 90) return `${Math.round(s)} s`;
  if (s < 5400) return `${Math.round(s / 60)} min`;
  return `${(s / 3600).toFixed(1)} h`;
}

function axesSummary(spec) {
  const axes = Object.entries(spec.axes || {});
  if (!axes.length) return "—";
  return axes.map(([k, v]) => `${k} ∈ {${v.join(", ")}}`).join(" × ");
}

function unfinished(p) { return p.queued + p.running > 0; }

async function cancel(id, after) {
  const r = await api(`/api/sweeps/${id}/cancel`, { method: "POST" });
  if (!r.ok) alert(r.body ? r.body.error : "cancel failed");
  after();
}

// ---------------------------------------------------------------- sweeps
async function sweepsView() {
  const table = h("tbody");
  const body = h("div", {},
    h("h1", {}, "Sweeps"),
    h("p", { class: "muted" }, "Every sweep of this study, newest first; the list refreshes while workers run. ",
      h("a", { href: "#/new" }, "Queue a sweep"), " or one of the paper's figures."),
    h("div", { class: "panel" }, h("table", { id: "sweeps" },
      h("thead", {}, h("tr", {}, h("th", {}, "Name"), h("th", {}, "Protocol"), h("th", {}, "Axes"), h("th", {}, "Samples"),
        h("th", {}, "Progress"), h("th", {}, "ETA"), h("th", {}, "State"), h("th", {}, ""))),
      table)));
  setView(body);
  const refresh = async () => {
    const r = await api("/api/sweeps");
    if (!r.ok) { table.replaceChildren(h("tr", {}, h("td", { colspan: 8, class: "error" }, "Cannot load sweeps."))); return; }
    const rows = r.body.sweeps.map(s => h("tr", { "data-id": s.id },
      h("td", {}, h("a", { href: `#/sweep/${s.id}` }, s.name)),
      h("td", {}, s.protocol),
      h("td", {}, axesSummary(s.spec)),
      h("td", { class: "num" }, String(s.spec.samples || 1)),
      h("td", {}, progressBar(s.progress), h("div", { class: "muted" }, counts(s.progress))),
      h("td", {}, eta(s.eta_seconds)),
      h("td", {}, stateTag(s)),
      h("td", {}, s.state === "active" && unfinished(s.progress)
        ? h("button", { class: "danger", onclick: () => cancel(s.id, refresh), "aria-label": `cancel ${s.name}` }, "Cancel") : "")));
    table.replaceChildren(...(rows.length ? rows : [h("tr", {}, h("td", { colspan: 8, class: "muted" }, "No sweeps yet."))]));
  };
  await refresh();
  timer = setInterval(refresh, 2000);
}

// ---------------------------------------------------------------- new sweep
function parseValues(text) {
  // "0.1, 0.2, 0.3" or a range "start:stop:step" (inclusive)
  const t = text.trim();
  const range = t.match(/^(-?[\d.eE+-]+)\s*:\s*(-?[\d.eE+-]+)\s*:\s*(-?[\d.eE+-]+)$/);
  if (range) {
    const [a, b, s] = range.slice(1).map(Number);
    if (!(s > 0) || !(b >= a)) return null;
    const out = [];
    for (let k = 0; a + k * s <= b + s * 1e-9 && k < 10000; k++) out.push(Number((a + k * s).toPrecision(12)));
    return out;
  }
  if (!t) return [];
  return t.split(/[,\s]+/).filter(Boolean).map(v => (/^-?[\d.]+([eE][+-]?\d+)?$/.test(v) ? Number(v) : v));
}

async function submitSpec(spec) {
  return api("/api/sweeps", { method: "POST", body: JSON.stringify(spec) });
}

function newView() {
  const err = {};
  const errBox = name => (err[name] = h("div", { class: "field-error", id: `err-${name.replace(/[^\w]/g, "-")}`, role: "alert" }));
  const name = h("input", { type: "text", id: "f-name", placeholder: "optional" });
  const protocol = h("select", { id: "f-protocol" }, ...["fill_release", "tilt", "flux"].map(p => h("option", { value: p }, p)));
  const base = h("textarea", { id: "f-base", rows: 4, "aria-describedby": "err-base" });
  base.value = JSON.stringify({ box: { width: 4.0, height: 4.0 } });
  const samples = h("input", { type: "number", id: "f-samples", value: 10, min: 1, "aria-describedby": "err-samples" });
  const fidelity = h("select", { id: "f-fidelity" }, ...["quick", "standard", "paper"].map(p => h("option", { value: p, selected: p === "standard" }, p)));
  const seed = h("input", { type: "number", id: "f-seed", value: 0, min: 0 });
  const axesBox = h("div", { id: "f-axes" });
  const addAxis = (key = "", values = "") => {
    const k = h("input", { type: "text", class: "key", value: key, placeholder: "contact.mu", "aria-label": "axis key" });
    const v = h("input", { type: "text", class: "values", value: values, placeholder: "0.1, 0.2, 0.3  or  0.1:0.3:0.05", "aria-label": "axis values" });
    const e = h("div", { class: "field-error", role: "alert" });
    const row = h("div", {}, h("div", { class: "axis-row" }, k, v,
      h("button", { type: "button", class: "secondary", onclick: () => row.remove(), "aria-label": "remove axis" }, "×")), e);
    row.axis = { k, v, e };
    axesBox.appendChild(row);
  };
  addAxis("contact.mu", "0.1, 0.2, 0.3");
  const general = h("div", { class: "field-error", role: "alert", id: "err-general" });

  const collect = () => {
    for (const e of Object.values(err)) e.textContent = "";
    for (const row of axesBox.children) row.axis.e.textContent = "";
    general.textContent = "";
    let baseObj = {};
    try { baseObj = base.value.trim() ? JSON.parse(base.value) : {}; } catch (e) { err.base.textContent = `base: not valid JSON (${e.message})`; return null; }
    const axes = {};
    for (const row of axesBox.children) {
      const key = row.axis.k.value.trim();
      if (!key) continue;
      const vals = parseValues(row.axis.v.value);
      if (vals === null) { row.axis.e.textContent = "a range is start:stop:step with step > 0"; return null; }
      axes[key] = vals;
    }
    const spec = { protocol: protocol.value, base: baseObj, axes, fidelity: fidelity.value,
      samples: samples.value === "" ? null : Number(samples.value), seed_base: Number(seed.value || 0) };
    if (name.value.trim()) spec.name = name.value.trim();
    return spec;
  };

  const showErrors = body => {
    const errors = (body && body.errors) || [];
    if (!errors.length) general.textContent = (body && body.error) || "The server refused the sweep.";
    for (const e of errors) {
      const f = e.field || "";
      const msg = `${f}: ${e.message}`;
      if (f.startsWith("axes.")) {
        const row = [...axesBox.children].find(r => f === `axes.${r.axis.k.value.trim()}` || f.startsWith(`axes.${r.axis.k.value.trim()}.`));
        if (row) { row.axis.e.textContent = msg; continue; }
      }
      if (f.startsWith("base")) { err.base.textContent = msg; continue; }
      const top = f.split(/[.[]/)[0];
      if (err[top]) { err[top].textContent = msg; continue; }
      general.textContent += (general.textContent ? "\n" : "") + msg;
    }
  };

  const onSubmit = async ev => {
    ev.preventDefault();
    const spec = collect();
    if (!spec) return;
    const r = await submitSpec(spec);
    if (r.ok) location.hash = `#/sweep/${r.body.id}`;
    else showErrors(r.body);
  };

  const presetButtons = PRESETS.map(p => h("button", { type: "button", class: "secondary", onclick: async () => {
    const r = await submitSpec(p.spec);
    if (r.ok) location.hash = `#/sweep/${r.body.id}`; else showErrors(r.body);
  } }, p.label));

  setView(
    h("h1", {}, "New sweep"),
    h("div", { class: "panel" },
      h("h2", {}, "The paper's figures"),
      h("p", { class: "muted" }, "One click queues the sweep behind a figure of Lee & Herrmann (1993), 20 samples a point."),
      h("div", { class: "presets" }, ...presetButtons)),
    h("form", { class: "panel", onsubmit: onSubmit, id: "sweep-form", novalidate: true },
      h("h2", {}, "Your own"),
      h("div", { class: "form-grid" },
        h("label", { for: "f-name" }, "Name"), name,
        h("label", { for: "f-protocol" }, "Protocol"), h("div", {}, protocol, errBox("protocol")),
        h("label", { for: "f-base" }, "Base scene (JSON)"), h("div", {}, base, errBox("base"),
          h("div", { class: "muted" }, "Any scene key, e.g. {\"box\": {\"width\": 4}, \"contact\": {\"k_n\": 1e5}}")),
        h("label", {}, "Axes"), h("div", {}, axesBox, errBox("axes"),
          h("button", { type: "button", class: "secondary", onclick: () => addAxis() }, "Add axis")),
        h("label", { for: "f-samples" }, "Samples per point"), h("div", {}, samples, errBox("samples")),
        h("label", { for: "f-fidelity" }, "Fidelity"), h("div", {}, fidelity, errBox("fidelity")),
        h("label", { for: "f-seed" }, "Seed base"), h("div", {}, seed, errBox("seed_base"))),
      general,
      h("p", {}, h("button", { type: "submit", id: "f-submit" }, "Queue sweep"))));
}

// ---------------------------------------------------------------- one sweep
function figureFor(spec) {
  const axes = Object.keys(spec.axes || {});
  const out = [];
  if (axes.includes("box.height")) out.push("2a");
  if (axes.includes("box.width") && axes.includes("contact.mu")) out.push("2b");
  if (axes.includes("contact.mu") && spec.protocol !== "tilt") out.push("3");
  if (axes.includes("contact.mu") && spec.protocol === "tilt") out.push("4");
  return out;
}

async function sweepView(id) {
  const head = h("div");
  const plotBox = h("div");
  const pointsBox = h("div");
  const samplesBox = h("div");
  setView(head, plotBox, pointsBox, samplesBox);
  let chosen = null;

  const draw = async (sweep, points, samples) => {
    const axes = Object.keys(sweep.spec.axes || {});
    if (!axes.length) {
      plotBox.replaceChildren(h("p", { class: "muted" }, "This sweep has no axes: see its samples below."));
      return;
    }
    const metrics = Object.keys(METRIC_LABELS).filter(m => points.some(p => p.metrics[m] && p.metrics[m].n > 0));
    if (!chosen) chosen = { x: axes[0], series: axes[1] || "", y: metrics[0] || "theta_r", errors: "sd" };
    const sel = (id, options, value, onchange, label) => h("label", {}, label + " ",
      h("select", { id, onchange }, ...options.map(([v, t]) => h("option", { value: v, selected: v === value }, t))));
    const controls = h("div", { class: "controls" },
      sel("plot-x", axes.map(a => [a, a]), chosen.x, e => { chosen.x = e.target.value; redraw(); }, "x"),
      sel("plot-series", [["", "none"], ...axes.filter(a => a !== chosen.x).map(a => [a, a])], chosen.series, e => { chosen.series = e.target.value; redraw(); }, "series"),
      sel("plot-y", (metrics.length ? metrics : ["theta_r"]).map(m => [m, METRIC_LABELS[m]]), chosen.y, e => { chosen.y = e.target.value; redraw(); }, "y"),
      sel("plot-errors", [["sd", "error bars: sd"], ["sem", "error bars: sem"]], chosen.errors, e => { chosen.errors = e.target.value; redraw(); }, ""),
      ...figureFor(sweep.spec).map(f => h("a", { class: "button secondary", href: `#/sweep/${id}/figure/${f}` }, `Figure ${f}`)));
    const figBox = h("div", { class: "figure", id: "generic-plot" });
    const redraw = () => {
      const key = v => JSON.stringify(v);
      const groups = new Map();
      for (const p of points) {
        const s = chosen.series ? p.point[chosen.series] : null;
        if (!groups.has(key(s))) groups.set(key(s), { name: chosen.series ? `${chosen.series} = ${s}` : "", value: s, points: [], samples: [] });
        const m = p.metrics[chosen.y] || {};
        groups.get(key(s)).points.push({ x: p.point[chosen.x], mean: m.mean, sd: m.sd, sem: m.sem, n: m.n, failures: p.failures });
      }
      for (const smp of samples) {
        const s = chosen.series ? smp.point[chosen.series] : null;
        const g = groups.get(key(s));
        if (g) g.samples.push({ x: smp.point[chosen.x], y: smp[chosen.y] });
      }
      const series = [...groups.values()].map(g => ({ ...g, points: g.points.sort((a, b) => a.x - b.x) }))
        .sort((a, b) => (a.value ?? 0) - (b.value ?? 0));
      const svg = errorBarPlot({ series, errors: chosen.errors, xLabel: axisLabel(chosen.x), yLabel: METRIC_LABELS[chosen.y] });
      figBox.replaceChildren(svg);
    };
    redraw();
    plotBox.replaceChildren(h("h2", {}, "Plot"), controls, figBox, downloads(() => figBox.querySelector("svg"), `sweep-${id}`, id));
  };

  const refresh = async () => {
    const [s, p, smp] = await Promise.all([api(`/api/sweeps/${id}`), api(`/api/sweeps/${id}/points`), api(`/api/sweeps/${id}/samples`)]);
    if (!s.ok) { setView(h("h1", {}, "Sweep not found"), h("p", { class: "error" }, s.body ? s.body.error : "")); clearInterval(timer); return; }
    const sweep = s.body;
    head.replaceChildren(
      h("h1", {}, sweep.name),
      h("div", { class: "panel" },
        h("p", {}, stateTag(sweep), " ", sweep.protocol, " · ", axesSummary(sweep.spec),
          " · ", `${sweep.spec.samples || 1} samples a point · fidelity ${sweep.spec.fidelity || "standard"}`),
        h("div", { class: "controls" }, progressBar(sweep.progress), h("span", {}, counts(sweep.progress)), h("span", {}, `ETA ${eta(sweep.eta_seconds)}`),
          sweep.state === "active" && unfinished(sweep.progress) ? h("button", { class: "danger", onclick: () => cancel(id, refresh) }, "Cancel sweep") : "")));
    const points = p.body.points, samples = smp.body.samples;
    await draw(sweep, points, samples);
    const metricCols = Object.keys(METRIC_LABELS).filter(m => points.some(q => q.metrics[m] && q.metrics[m].n > 0));
    pointsBox.replaceChildren(h("h2", {}, "Points"), h("div", { class: "panel" }, h("table", { id: "points" },
      h("thead", {}, h("tr", {}, h("th", {}, "Point"), h("th", { class: "num" }, "n"), h("th", { class: "num" }, "no result"),
        ...metricCols.map(m => h("th", { class: "num" }, `${METRIC_LABELS[m]} mean ± sd (sem)`)))),
      h("tbody", {}, ...points.map(q => h("tr", {}, h("td", {}, JSON.stringify(q.point)), h("td", { class: "num" }, String(q.samples)),
        h("td", { class: "num" }, String(q.failures)),
        ...metricCols.map(m => { const a = q.metrics[m]; return h("td", { class: "num" }, a.n ? `${fmt(a.mean)} ± ${fmt(a.sd)} (${fmt(a.sem)})` : "–"); })))))));
    samplesBox.replaceChildren(h("h2", {}, `Samples (${samples.length})`), h("div", { class: "panel" }, h("table", { id: "samples" },
      h("thead", {}, h("tr", {}, h("th", {}, "Point"), h("th", { class: "num" }, "Seed"), h("th", {}, "Outcome"),
        h("th", { class: "num" }, "θ_R (m3)"), h("th", { class: "num" }, "θ_T"), h("th", { class: "num" }, "grains"), h("th", { class: "num" }, "wall s"))),
      h("tbody", {}, ...samples.map(q => h("tr", {}, h("td", {}, JSON.stringify(q.point)), h("td", { class: "num" }, String(q.seed)),
        h("td", {}, h("a", { href: `#/sample/${q.sample_hash}` }, h("span", { class: `tag ${q.outcome}` }, q.outcome)),
          q.reason ? h("div", { class: "reason muted" }, q.reason) : ""),
        h("td", { class: "num" }, fmt(q.theta_r)), h("td", { class: "num" }, fmt(q.theta_t)),
        h("td", { class: "num" }, `${q.grains_initial}→${q.grains_final}`), h("td", { class: "num" }, fmt(q.wall_time, 2))))))));
    if (!unfinished(sweep.progress)) clearInterval(timer);
  };
  await refresh();
  timer = setInterval(refresh, 2000);
}

function downloads(getSvg, name, sweepId) {
  return h("div", { class: "controls" },
    h("button", { class: "secondary", onclick: () => download(`${name}.svg`, svgText(getSvg()), "image/svg+xml") }, "Download SVG"),
    h("button", { class: "secondary", onclick: () => downloadPng(`${name}.png`, getSvg()) }, "Download PNG"),
    sweepId ? h("a", { class: "button secondary", href: `/api/sweeps/${sweepId}/points?format=csv` }, "Points CSV") : "",
    sweepId ? h("a", { class: "button secondary", href: `/api/sweeps/${sweepId}/samples?format=csv` }, "Samples CSV") : "");
}

// ---------------------------------------------------------------- paper figures
async function figureView(id, name) {
  const [f, smp, p] = await Promise.all([api(`/api/sweeps/${id}/figures/${name}`), api(`/api/sweeps/${id}/samples`), api(`/api/sweeps/${id}/points`)]);
  if (!f.ok) { setView(h("h1", {}, `Figure ${name}`), h("p", { class: "error", role: "alert" }, f.body ? f.body.error : "not available")); return; }
  const fig = f.body, samples = smp.body.samples, points = p.body.points;
  let errors = "sd";
  const box = h("div", { class: "figure", id: "figure-plot" });
  const draw = () => {
    const groups = new Map();
    for (const q of fig.points) {
      const k = JSON.stringify(q.series);
      if (!groups.has(k)) groups.set(k, { name: fig.series ? `${fig.series} = ${q.series}` : "", value: q.series, points: [], samples: [] });
      groups.get(k).points.push(q);
    }
    for (const s of samples) {
      const k = JSON.stringify(fig.series ? s.point[fig.series] : null);
      if (groups.has(k)) groups.get(k).samples.push({ x: s.point[fig.x], y: s[fig.y] });
    }
    const theoryCurves = [];
    if (fig.x === "contact.mu" && fig.y === "theta_r") {
      const xs = fig.points.map(q => q.x), lo = Math.min(...xs), hi = Math.max(...xs);
      const pts = [];
      for (let k = 0; k <= 50; k++) { const mu = lo + (hi - lo) * k / 50; pts.push({ x: mu, y: theory.marginal(mu) }); }
      theoryCurves.push({ name: "θ_MS = atan(3μ), eq. (3)", points: pts });
    }
    if (fig.y === "theta_t") {
      // eq. (4) with the measured θ_R of the same tilted piles
      const pts = points.map(q => ({ x: q.point["contact.mu"], y: theory.tilting(q.point["contact.mu"], q.metrics.theta_r.mean) }))
        .filter(q => Number.isFinite(q.y)).sort((a, b) => a.x - b.x);
      if (pts.length) theoryCurves.push({ name: "θ_T from eq. (4) with measured θ_R", points: pts });
    }
    box.replaceChildren(errorBarPlot({ series: [...groups.values()], theory: theoryCurves, errors,
      xLabel: axisLabel(fig.x), yLabel: METRIC_LABELS[fig.y], title: `Figure ${fig.figure}: ${fig.title}`, yFloor: 0 }));
  };
  draw();
  const errSel = h("select", { id: "figure-errors", onchange: e => { errors = e.target.value; draw(); } },
    h("option", { value: "sd" }, "error bars: sample sd (the paper's)"), h("option", { value: "sem" }, "error bars: standard error"));
  setView(h("p", {}, h("a", { href: `#/sweep/${id}` }, "← back to the sweep")),
    h("h1", {}, `Figure ${fig.figure}`), h("div", { class: "controls" }, errSel), box,
    downloads(() => box.querySelector("svg"), `figure-${fig.figure}`, id),
    h("p", { class: "muted" }, "Large dots: mean over samples, with error bars; faint dots: single samples. Hover or focus a mean for n, mean and sd."));
}

// ---------------------------------------------------------------- one sample
// An outcome's reason as the sample listings give it (report.rs `Outcome::reason`).
function outcomeReason(o) {
  if (o.phase && o.reason) return `${o.phase}: ${o.reason}`;
  if (o.reason) return o.reason;
  return o.phase ? `cancelled during ${o.phase}` : "";
}

async function sampleView(hash) {
  const r = await api(`/api/samples/${hash}`);
  if (!r.ok) { setView(h("h1", {}, "Sample not found"), h("p", { class: "error" }, r.body ? r.body.error : "")); return; }
  const rep = r.body;
  const st = rep.final_state || { grains: [], contacts: [], walls: [] };
  const a = rep.repose;
  const angleRows = [];
  if (a) angleRows.push(["θ_R method 1 (endpoints)", a.endpoints], ["θ_R method 2 (line)", a.line_fit], ["θ_R method 3 (parabola, headline)", a.cumulative_fit]);
  if (rep.tilt) angleRows.push(["θ_T", rep.tilt.angle]);
  if (rep.flux && rep.flux.steady) angleRows.push(["pile angle, steady mean", rep.flux.steady.mean], ["pile angle, steady sd", rep.flux.steady.sd], ["pile angle, largest", rep.flux.max]);
  angleRows.push(["θ_MS = atan(3μ), eq. (3)", rep.theory.marginal_stability]);
  if (rep.theory.tilting !== null && rep.theory.tilting !== undefined) angleRows.push(["θ_T by eq. (4)", rep.theory.tilting]);

  const pile = h("div", { class: "figure", id: "pile" }, pilePlot({ grains: st.grains, contacts: st.contacts, walls: st.walls,
    width: rep.scene.box.width, surface: rep.surface, angle: a ? a.cumulative_fit : NaN }));
  const trace = rep.energy_trace || [];
  const markers = [];
  trace.forEach((p, i) => { if (i > 0 && p.phase !== trace[i - 1].phase) markers.push({ x: p.iteration, label: p.phase }); });
  const ke = h("div", { class: "figure", id: "energy" }, trace.length ? linePlot({ points: trace.map(p => ({ x: p.iteration, y: p.kinetic_energy })),
    xLabel: "iteration", yLabel: "kinetic energy per grain (erg)", title: "Kinetic energy (fig. 1b)", logY: true, markers }) : h("p", { class: "muted" }, "no trace"));
  let fluxBox = "";
  if (rep.flux && rep.flux.series.length) {
    const s = rep.flux.steady;
    fluxBox = h("div", {}, h("h2", {}, "Pile angle before each insertion (fig. 5)"), h("div", { class: "figure", id: "flux" },
      linePlot({ points: rep.flux.series.map(p => ({ x: p.iteration, y: p.angle })), xLabel: "iteration", yLabel: "pile angle (°)",
        band: s ? { lo: s.mean - s.sd, hi: s.mean + s.sd, mean: s.mean } : null })),
      s ? h("p", { class: "muted" }, `Steady part: ${fmt(s.mean)} ± ${fmt(s.sd)}° over ${s.n} insertions (band: mean ± sd).`) : "");
  }
  const sceneText = JSON.stringify(rep.scene, null, 2);
  const copied = h("span", { class: "muted", "aria-live": "polite" });
  setView(
    h("h1", {}, `Sample: ${rep.protocol}, seed ${rep.seed}`),
    h("div", { class: "panel" },
      h("p", {}, h("span", { class: `tag ${rep.outcome.status}` }, rep.outcome.status), " ", outcomeReason(rep.outcome),
        ` · ${rep.grains.initial} grains at start, ${rep.grains.lost} lost, ${rep.grains.final} at end · ${rep.iterations} steps, ${fmt(rep.simulated_time)} s simulated, ${fmt(rep.wall_time, 2)} s wall · ${rep.options.integrator}, normal force ${rep.options.normal_force}, shear spring ${rep.options.shear_spring} · ${rep.engine}`),
      h("table", { id: "angles" }, h("tbody", {}, ...angleRows.map(([k, v]) => h("tr", {}, h("th", {}, k), h("td", { class: "num" }, `${fmt(v)}°`)))))),
    h("div", { class: "two" },
      h("div", {}, h("h2", {}, rep.outcome.status === "completed" ? "Final pile, force chains (fig. 1a)" : "Grains when the run stopped, force chains"), pile),
      h("div", {}, h("h2", {}, "Energy"), ke)),
    fluxBox,
    h("h2", {}, "Scene"),
    h("p", {}, h("button", { class: "secondary", id: "copy-scene", onclick: async () => {
      try { await navigator.clipboard.writeText(sceneText); copied.textContent = "Copied. Save it as scene.json and run: repose run scene.json"; }
      catch (_) { copied.textContent = "Select the text below and copy it; then: repose run scene.json"; }
    } }, "Copy scene JSON"), " ", copied),
    h("pre", { id: "scene-json" }, sceneText));
}

// ---------------------------------------------------------------- help
async function fetchDoc(name) {
  const r = await fetch(`/docs/${name}.md`);
  if (!r.ok) return null;
  return window.markdown.render(await r.text(), "/docs/");
}

async function helpView() {
  const intro = h("div", { class: "panel" },
    h("p", {}, "repose runs parameter studies of the 2D granular piles of Lee & Herrmann (1993). A sweep varies scene values (axes) over a base scene, with several samples (seeds) per point; workers run the samples and this page shows their angles."),
    h("ul", {},
      h("li", {}, "θ_R: angle of repose after a box loses its side wall, by three slope methods (method 3 is the paper's headline)."),
      h("li", {}, "θ_T: the tilt at which the released pile starts to move."),
      h("li", {}, "Constant flux: grains added one at a time; the pile angle before each insertion traces the angle of marginal stability."),
      h("li", {}, "Error bars show the sample standard deviation (the paper's error bar) or the standard error; points without a result (not settled, blown up) are counted apart.")),
    h("p", {}, "Fidelity presets: quick (Verlet, coarser step, shorter equilibrium window), standard (Verlet at the default step), paper (Gear-5, the paper's integrator). What each costs and how far it moves the angles is measured below. The API is described at ",
      h("a", { href: "/api/openapi.json" }, "/api/openapi.json"), "."),
    h("p", {}, "Reports: ",
      h("a", { href: "#/doc/reproduction" }, "the reproduction of the paper's figures"), " · ",
      h("a", { href: "#/doc/speed-vs-accuracy" }, "speed against accuracy"), "."));
  setView(h("h1", {}, "Help"), intro, h("p", { class: "muted" }, "Loading the speed/accuracy report…"));
  const doc = await fetchDoc("speed-vs-accuracy");
  setView(h("h1", {}, "Help"), intro,
    h("section", { class: "panel", id: "speed-accuracy" }, doc || h("p", { class: "muted" }, "The speed/accuracy report is not available.")));
}

async function docView(name) {
  const doc = await fetchDoc(name);
  if (!doc) {
    setView(h("h1", {}, "Not found"), h("p", {}, `There is no report named ${name}. `, h("a", { href: "#/help" }, "Help")));
    return;
  }
  setView(h("section", { class: "panel" }, doc));
}

// ---------------------------------------------------------------- routing
async function route() {
  if (timer) { clearInterval(timer); timer = null; }
  const parts = location.hash.replace(/^#\/?/, "").split("/").filter(Boolean);
  try {
    if (!parts.length) await sweepsView();
    else if (parts[0] === "new") newView();
    else if (parts[0] === "help") await helpView();
    else if (parts[0] === "doc" && parts[1]) await docView(parts[1]);
    else if (parts[0] === "sweep" && parts[2] === "figure") await figureView(parts[1], parts[3]);
    else if (parts[0] === "sweep") await sweepView(parts[1]);
    else if (parts[0] === "sample") await sampleView(parts[1]);
    else setView(h("h1", {}, "Not found"), h("p", {}, h("a", { href: "#/" }, "Back to the sweeps")));
  } catch (e) {
    setView(h("h1", {}, "Something went wrong"), h("p", { class: "error" }, String(e)));
  }
}

async function health() {
  const r = await api("/api/health");
  document.getElementById("health").textContent = r.ok ? `${r.body.engine} · ${r.body.database}` : "server unreachable";
}

window.addEventListener("hashchange", route);
route();
health();
