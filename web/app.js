// The results browser: sweeps, the submit form, the papers' figures, and
// single samples. Plain JavaScript, no build step. Everything comes from the
// service's own API: the protocols and their metrics (/api/protocols), the
// papers' studies and figures with their theory curves (/api/studies), and
// the stored sweeps. The page holds no physics and no list of metrics.
"use strict";

const { figurePlot, linePlot, pilePlot, sideViewPlot, svgText, download, downloadPng, fmt } = window.plots;
const view = document.getElementById("view");
let timer = null;

// ---------------------------------------------------------------- registry
// Protocols and studies, fetched once.
const registry = { protocols: new Map(), studies: [], loaded: null };

function loadRegistry() {
  if (!registry.loaded) {
    registry.loaded = Promise.all([api("/api/protocols"), api("/api/studies")]).then(([p, s]) => {
      for (const proto of (p.body && p.body.protocols) || []) registry.protocols.set(proto.name, proto);
      registry.studies = (s.body && s.body.studies) || [];
    });
  }
  return registry.loaded;
}

// The metrics a protocol declares, headline first.
function metricsOf(protocol) {
  const p = registry.protocols.get(protocol);
  return p ? p.metrics : [];
}

// A metric's label with its unit, e.g. "θ_R (°)".
function metricLabel(name) {
  for (const p of registry.protocols.values()) {
    const m = p.metrics.find(m => m.name === name);
    if (m) return m.unit ? `${m.label} (${m.unit})` : m.label;
  }
  return name;
}

// A server open beyond loopback guards changes (and, if private, reading)
// with a bearer token: asked once on the first 401 and kept for the tab.
function authHeaders() {
  const token = sessionStorage.getItem("repose-token");
  return token ? { authorization: `Bearer ${token}` } : {};
}

async function api(path, options = {}, asked = false) {
  const headers = { "content-type": "application/json", ...authHeaders() };
  const resp = await fetch(path, { ...options, headers });
  if (resp.status === 401 && !asked) {
    const token = window.prompt("This server needs its access token:");
    if (token) {
      sessionStorage.setItem("repose-token", token.trim());
      return api(path, options, true);
    }
  }
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

function unfinished(p) { return p.queued + p.running > 0; }

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

async function cancel(id, after) {
  const r = await api(`/api/sweeps/${id}/cancel`, { method: "POST" });
  if (!r.ok) alert(r.body ? r.body.error : "cancel failed");
  after();
}

// Queues the sweep behind a paper's figures: the same sweep `repose reproduce` queues.
async function queueStudySweep(paper, key, body = {}) {
  return api(`/api/studies/${paper}/sweeps/${key}`, { method: "POST", body: JSON.stringify(body) });
}

// ---------------------------------------------------------------- sweeps
async function sweepsView() {
  const table = h("tbody");
  const body = h("div", {},
    h("h1", {}, "Sweeps"),
    h("p", { class: "muted" }, "Every sweep of this study, newest first; the list refreshes while workers run. ",
      h("a", { href: "#/new" }, "Queue a sweep"), " or ", h("a", { href: "#/papers" }, "one behind a paper's figures"), "."),
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

// Shows an API error answer beside the fields it names.
function errorShower(err, axesBox, general) {
  return body => {
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
}

// The papers' study sweeps as one-click buttons.
function studyButtons(onError) {
  return registry.studies.map(st => h("div", {},
    h("h3", {}, st.title),
    h("div", { class: "presets" }, ...st.sweeps.map(sw => h("button", { type: "button", class: "secondary", "data-study": `${st.key}/${sw.key}`, onclick: async () => {
      const r = await queueStudySweep(st.key, sw.key);
      if (r.ok) location.hash = `#/sweep/${r.body.id}`; else onError(r.body);
    } }, sw.title)))));
}

async function newView() {
  await loadRegistry();
  const err = {};
  const errBox = name => (err[name] = h("div", { class: "field-error", id: `err-${name.replace(/[^\w]/g, "-")}`, role: "alert" }));
  const name = h("input", { type: "text", id: "f-name", placeholder: "optional" });
  const protocol = h("select", { id: "f-protocol" }, ...[...registry.protocols.values()].map(p => h("option", { value: p.name, title: p.about }, p.name)));
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
  const showErrors = errorShower(err, axesBox, general);

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

  const onSubmit = async ev => {
    ev.preventDefault();
    const spec = collect();
    if (!spec) return;
    const r = await submitSpec(spec);
    if (r.ok) location.hash = `#/sweep/${r.body.id}`;
    else showErrors(r.body);
  };

  setView(
    h("h1", {}, "New sweep"),
    h("div", { class: "panel" },
      h("h2", {}, "The papers' figures"),
      h("p", { class: "muted" }, "One click queues the sweep behind a paper's figures, at the paper's number of samples and the standard fidelity — the same sweep `repose reproduce` queues. ",
        h("a", { href: "#/papers" }, "See the figures"), "."),
      ...studyButtons(showErrors)),
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
// A sweep's points as figure data: one metric along an axis, one series per
// value of another, with every sample.
function genericFigure(points, samples, chosen) {
  const key = v => JSON.stringify(v);
  const groups = new Map();
  for (const p of points) {
    const s = chosen.series ? p.point[chosen.series] : null;
    if (!groups.has(key(s))) groups.set(key(s), { name: chosen.series ? `${chosen.series} = ${s}` : "", kind: "measured", value: s, points: [] });
    const m = p.metrics[chosen.y] || {};
    const vals = samples.filter(q => key(q.point) === key(p.point)).map(q => q.metrics[chosen.y]).filter(Number.isFinite);
    groups.get(key(s)).points.push({ x: p.point[chosen.x], y: m.mean, sd: m.sd, sem: m.sem, n: m.n, failures: p.failures, samples: vals });
  }
  const series = [...groups.values()].map(g => ({ ...g, points: g.points.sort((a, b) => a.x - b.x) }))
    .sort((a, b) => (a.value ?? 0) - (b.value ?? 0));
  return { series, x_label: chosen.x, y_label: metricLabel(chosen.y), log_x: false };
}

function plotControls(axes, metrics, chosen, redraw, figures, id) {
  const sel = (sid, options, value, onchange, label) => h("label", {}, label + " ",
    h("select", { id: sid, onchange }, ...options.map(([v, t]) => h("option", { value: v, selected: v === value }, t))));
  return h("div", { class: "controls" },
    sel("plot-x", axes.map(a => [a, a]), chosen.x, e => { chosen.x = e.target.value; redraw(); }, "x"),
    sel("plot-series", [["", "none"], ...axes.filter(a => a !== chosen.x).map(a => [a, a])], chosen.series, e => { chosen.series = e.target.value; redraw(); }, "series"),
    sel("plot-y", metrics.map(m => [m.name, metricLabel(m.name)]), chosen.y, e => { chosen.y = e.target.value; redraw(); }, "y"),
    sel("plot-errors", [["sd", "error bars: sd"], ["sem", "error bars: sem"]], chosen.errors, e => { chosen.errors = e.target.value; redraw(); }, ""),
    ...figures.map(f => h("a", { class: "button secondary", href: `#/sweep/${id}/figure/${f.paper}/${f.figure}` }, `${f.paper} figure ${f.figure}`)));
}

// The metric a sweep's target_sem is for: the one it names, else the
// protocol's headline metric.
function targetOf(spec, metrics) {
  if (!spec || !spec.target_sem) return null;
  return { value: spec.target_sem, metric: spec.target_metric || (metrics[0] && metrics[0].name) };
}

// A point's standard error against the sweep's target, as a cell.
function targetCell(q, target) {
  const a = q.metrics[target.metric] || {};
  const met = a.sem !== null && a.sem !== undefined && a.sem <= target.value;
  return h("td", { class: "num target" }, `${fmt(a.sem)} / ${fmt(target.value)} `,
    h("span", { class: `tag ${met ? "completed" : "running"}` }, met ? "reached" : "sampling"));
}

function pointsTable(points, metrics, spec) {
  const cols = metrics.filter(m => points.some(q => q.metrics[m.name] && q.metrics[m.name].n > 0));
  const target = targetOf(spec, metrics);
  return h("div", { class: "panel" }, h("table", { id: "points" },
    h("thead", {}, h("tr", {}, h("th", {}, "Point"), h("th", { class: "num" }, "n"), h("th", { class: "num" }, "no result"),
      ...cols.map(m => h("th", { class: "num" }, `${metricLabel(m.name)} mean ± sd (sem)`)),
      target ? h("th", { class: "num" }, `sem of ${metricLabel(target.metric)} / target`) : "")),
    h("tbody", {}, ...points.map(q => h("tr", {}, h("td", {}, JSON.stringify(q.point)), h("td", { class: "num" }, String(q.samples)),
      h("td", { class: "num" }, String(q.failures)),
      ...cols.map(m => { const a = q.metrics[m.name] || {}; return h("td", { class: "num" }, a.n ? `${fmt(a.mean)} ± ${fmt(a.sd)} (${fmt(a.sem)})` : "–"); }),
      target ? targetCell(q, target) : "")))));
}

// "3 samples a point", or the range a target_sem sweep may use.
function samplesText(spec) {
  const least = spec.samples || 1;
  if (!spec.target_sem) return `${least} samples a point`;
  return `${least}–${spec.max_samples || 10 * least} samples a point until the sem reaches ${fmt(spec.target_sem)}`;
}

function samplesTable(samples, metrics) {
  const cols = metrics.slice(0, 2);
  return h("div", { class: "panel" }, h("table", { id: "samples" },
    h("thead", {}, h("tr", {}, h("th", {}, "Point"), h("th", { class: "num" }, "Seed"), h("th", {}, "Outcome"),
      ...cols.map(m => h("th", { class: "num" }, metricLabel(m.name))), h("th", { class: "num" }, "grains"), h("th", { class: "num" }, "wall s"))),
    h("tbody", {}, ...samples.map(q => h("tr", {}, h("td", {}, JSON.stringify(q.point)), h("td", { class: "num" }, String(q.seed)),
      h("td", {}, h("a", { href: `#/sample/${q.sample_hash}` }, h("span", { class: `tag ${q.outcome}` }, q.outcome)),
        q.reason ? h("div", { class: "reason muted" }, q.reason) : ""),
      ...cols.map(m => h("td", { class: "num" }, fmt(q.metrics[m.name]))),
      h("td", { class: "num" }, `${q.grains_initial}→${q.grains_final}`), h("td", { class: "num" }, fmt(q.wall_time, 2)))))));
}

async function sweepView(id) {
  await loadRegistry();
  const head = h("div"), plotBox = h("div"), pointsBox = h("div"), samplesBox = h("div");
  setView(head, plotBox, pointsBox, samplesBox);
  let chosen = null;
  const figs = await api(`/api/sweeps/${id}/figures`);
  const figures = (figs.ok && figs.body.figures) || [];

  const draw = (sweep, points, samples) => {
    const axes = Object.keys(sweep.spec.axes || {});
    if (!axes.length) {
      plotBox.replaceChildren(h("p", { class: "muted" }, "This sweep has no axes: see its samples below."));
      return;
    }
    const metrics = metricsOf(sweep.protocol);
    if (!chosen) chosen = { x: axes[0], series: axes[1] || "", y: metrics.length ? metrics[0].name : "", errors: "sd" };
    const figBox = h("div", { class: "figure", id: "generic-plot" });
    const redraw = () => figBox.replaceChildren(figurePlot({ fig: genericFigure(points, samples, chosen), errors: chosen.errors }));
    redraw();
    plotBox.replaceChildren(h("h2", {}, "Plot"), plotControls(axes, metrics, chosen, redraw, figures, id), figBox,
      downloads(() => figBox.querySelector("svg"), `sweep-${id}`, id));
  };

  const refresh = async () => {
    const [s, p, smp] = await Promise.all([api(`/api/sweeps/${id}`), api(`/api/sweeps/${id}/points`), api(`/api/sweeps/${id}/samples`)]);
    if (!s.ok) { setView(h("h1", {}, "Sweep not found"), h("p", { class: "error" }, s.body ? s.body.error : "")); clearInterval(timer); return; }
    const sweep = s.body;
    head.replaceChildren(
      h("h1", {}, sweep.name),
      h("div", { class: "panel" },
        h("p", {}, stateTag(sweep), " ", sweep.protocol, " · ", axesSummary(sweep.spec),
          " · ", `${samplesText(sweep.spec)} · fidelity ${sweep.spec.fidelity || "standard"}`,
          sweep.study ? ` · queued for ${sweep.study}` : ""),
        h("div", { class: "controls" }, progressBar(sweep.progress), h("span", {}, counts(sweep.progress)), h("span", {}, `ETA ${eta(sweep.eta_seconds)}`),
          sweep.state === "active" && unfinished(sweep.progress) ? h("button", { class: "danger", onclick: () => cancel(id, refresh) }, "Cancel sweep") : "")));
    const points = p.body.points, samples = smp.body.samples;
    draw(sweep, points, samples);
    const metrics = metricsOf(sweep.protocol);
    pointsBox.replaceChildren(h("h2", {}, "Points"), pointsTable(points, metrics, sweep.spec));
    samplesBox.replaceChildren(h("h2", {}, `Samples (${samples.length})`), samplesTable(samples, metrics));
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

// ---------------------------------------------------------------- figures
// A figure as the API serves it, with a choice of error bars.
function figurePanel(fig, name, sweepId) {
  let errors = "sd";
  const box = h("div", { class: "figure", id: "figure-plot" });
  const draw = () => box.replaceChildren(figurePlot({ fig, errors, title: `Figure ${fig.figure}: ${fig.title}` }));
  draw();
  const errSel = h("select", { id: "figure-errors", onchange: e => { errors = e.target.value; draw(); } },
    h("option", { value: "sd" }, "error bars: sample sd (the paper's)"), h("option", { value: "sem" }, "error bars: standard error"));
  return h("div", {}, h("div", { class: "controls" }, errSel), box, h("p", { class: "muted" }, fig.caption),
    fitsTable(fig.fits || []),
    downloads(() => box.querySelector("svg"), name, sweepId),
    h("p", { class: "muted" }, "Large dots: mean over samples, with error bars; faint dots: single samples; open circles: the paper's quoted values; dashed: theory, evaluated by the service. Hover or focus a point for its numbers."));
}

// The fits a figure draws: each constant with its standard error and 95 %
// interval, or why the fit could not be made.
function fitsTable(fits) {
  if (!fits.length) return "";
  const constants = f => f.fit ? f.fit.params.map(p => `${p.name} = ${fmt(p.value, 4)} ± ${fmt(p.se, 4)} [${fmt(p.lo, 4)}, ${fmt(p.hi, 4)}]`).join("; ") : f.error;
  return h("table", { id: "fits" },
    h("thead", {}, h("tr", {}, h("th", {}, "fit"), h("th", {}, "constants ± standard error [95 % interval]"), h("th", {}, "R²"), h("th", {}, "points"))),
    h("tbody", {}, ...fits.map(f => h("tr", { class: f.fit ? "fit" : "fit failed" },
      h("td", {}, f.label), h("td", {}, constants(f)),
      h("td", { class: "num" }, f.fit ? fmt(f.fit.r2, 4) : "—"), h("td", { class: "num" }, f.fit ? String(f.fit.points) : "—")))));
}

// One sweep drawn as a paper's figure.
async function sweepFigureView(id, paper, figure) {
  const f = await api(`/api/sweeps/${id}/figures/${paper}/${figure}`);
  if (!f.ok) { setView(h("h1", {}, `Figure ${figure}`), h("p", { class: "error", role: "alert" }, f.body ? f.body.error : "not available")); return; }
  setView(h("p", {}, h("a", { href: `#/sweep/${id}` }, "← back to the sweep")),
    h("h1", {}, `${paper} figure ${f.body.figure}`), figurePanel(f.body, `${paper}-figure-${figure}`, id));
}

// The papers and their figures.
async function papersView() {
  await loadRegistry();
  setView(h("h1", {}, "Papers"),
    ...registry.studies.map(st => h("section", { class: "panel", "data-paper": st.key },
      h("h2", {}, st.title), h("p", { class: "muted" }, st.citation, " · ", h("a", { href: `#/doc/${st.report}`, class: "report" }, "its reproduction report")),
      h("ul", { class: "figures" }, ...st.figures.map(f => h("li", {},
        h("a", { href: `#/paper/${st.key}/figure/${f.key}` }, `Figure ${f.key}: ${f.title}`),
        h("span", { class: "muted" }, ` — from ${f.sweeps.join(", ")}`)))))));
}

// A paper's figure from the newest sweeps queued for it, with buttons to
// queue the sweeps it still lacks.
async function paperFigureView(paper, figure) {
  await loadRegistry();
  const f = await api(`/api/studies/${paper}/figures/${figure}`);
  if (!f.ok) { setView(h("h1", {}, `Figure ${figure}`), h("p", { class: "error", role: "alert" }, f.body ? f.body.error : "not available")); return; }
  const fig = f.body;
  const study = registry.studies.find(s => s.key === paper);
  const titleOf = key => ((study && study.sweeps.find(s => s.key === key)) || { title: key }).title;
  const from = Object.entries(fig.sweeps).map(([key, id]) => h("li", {}, `${titleOf(key)}: `, h("a", { href: `#/sweep/${id}` }, "the sweep")));
  const missing = fig.missing.map(key => h("li", {}, `${titleOf(key)}: not queued yet `,
    h("button", { class: "secondary", onclick: async () => { const r = await queueStudySweep(paper, key); if (r.ok) route(); else alert(r.body.error); } }, "Queue it")));
  setView(h("p", {}, h("a", { href: "#/papers" }, "← all figures")),
    h("h1", {}, `${study ? study.title.split(":")[0] : paper}, figure ${fig.figure}`),
    figurePanel(fig, `${paper}-figure-${figure}`, null),
    h("div", { class: "panel" }, h("h2", {}, "Data"), h("ul", {}, ...from, ...missing)));
}

// ---------------------------------------------------------------- one sample
// An outcome's reason as the sample listings give it (report.rs `Outcome::reason`).
function outcomeReason(o) {
  if (o.phase && o.reason) return `${o.phase}: ${o.reason}`;
  if (o.reason) return o.reason;
  return o.phase ? `cancelled during ${o.phase}` : "";
}

// The report's measured metrics and theory values.
function anglesTable(rep) {
  const rows = [];
  for (const m of metricsOf(rep.protocol)) {
    if (Number.isFinite(rep.metrics[m.name])) rows.push([`${m.label} — ${m.description}`, `${fmt(rep.metrics[m.name])}${m.unit}`]);
  }
  for (const q of rep.theory || []) rows.push([q.label, `${fmt(q.value)}°`]);
  return h("table", { id: "angles" }, h("tbody", {}, ...rows.map(([k, v]) => h("tr", {}, h("th", {}, k), h("td", { class: "num" }, v)))));
}

// The final state in the plane of its first and last axes (a side view in 3D).
function pileFigure(rep) {
  const st = rep.final_state || { grains: [], contacts: [], walls: [] };
  const up = (rep.dimension || 2) - 1;
  const side = v => [v[0], v[up]];
  const grains = st.grains.map(g => ({ ...g, position: side(g.position) }));
  const walls = (st.walls || []).filter(w => (rep.dimension || 2) === 2 || Math.abs(w.normal[1]) < 1e-9)
    .map(w => ({ ...w, point: side(w.point), normal: side(w.normal) }));
  const box = rep.scene.box;
  return pilePlot({ grains, contacts: st.contacts, walls, width: box ? box.width : 0,
    surface: (rep.profiles || [])[0], angle: rep.metrics.theta_r });
}

function curves(rep) {
  return (rep.series || []).map(c => h("div", {}, h("h2", {}, c.title),
    h("div", { class: "figure", id: `series-${c.name}` }, linePlot({ points: c.points.map(([x, y]) => ({ x, y })), xLabel: c.x_label, yLabel: c.y_label, band: c.band || null })),
    c.band ? h("p", { class: "muted" }, `Band: ${fmt(c.band.mean)} ± ${fmt(c.band.hi - c.band.mean)} (mean ± sd).`) : ""));
}

// A 3D sample's grains in 3D, to turn and zoom.
function grains3d(rep, title) {
  const grains = (rep.final_state || { grains: [] }).grains;
  const canvas = h("canvas", { id: "grains3d", width: 760, height: 460, tabindex: "0",
    "aria-label": `${title} in 3D: drag or use the arrow keys to turn it, the wheel or + and − to zoom` });
  const panels = [h("h2", {}, `${title}: ${grains.length} grains`), canvas,
    h("p", { class: "muted" }, "Drag or use the arrow keys to turn it; the wheel or + and − zoom. Colour: height.")];
  const after = () => { if (!window.heap3d.viewer(canvas, grains)) canvas.replaceWith(h("p", { class: "muted" }, "WebGL is not available in this browser.")); };
  return { panels, after };
}

// A poured heap: the heap in 3D, and its two side views with the
// equal-area triangles that give θ_r.
function heapPanels(rep) {
  const three = grains3d(rep, "The heap");
  const views = (rep.details && rep.details.side_views) || {};
  const d = rep.scene.grains.diameter, plate = rep.scene.heap.plate;
  const sides = (rep.profiles || []).map((profile, k) => {
    const label = k === 0 ? "xz" : "yz", view = views[label];
    return view ? h("div", { class: "figure", id: `side-${label}` }, sideViewPlot({ profile, d, plate, view, label })) : "";
  });
  return { panels: [...three.panels, h("h2", {}, "Side views"), h("div", { class: "two" }, ...sides)], after: three.after };
}

// A packed column: φ in each of the four sub-columns of the slab, and the
// column in 3D.
function packingPanels(rep) {
  const det = rep.details || {};
  const quarters = det.quarters || [];
  const rows = quarters.map((phi, k) => h("tr", {}, h("th", {}, `sub-column ${k + 1}`), h("td", { class: "num" }, fmt(phi, 4))));
  const slab = det.slab ? `between ${fmt(det.slab[0], 3)} d and ${fmt(det.slab[1], 3)} d` : "";
  const three = grains3d(rep, "The column");
  return { panels: [h("h2", {}, `Packing fraction of the four sub-columns ${slab}`), h("table", { id: "quarters" }, h("tbody", {}, ...rows)), ...three.panels], after: three.after };
}

// What a sample page shows beyond the common panels, by protocol.
function specialPanels(rep) {
  if (!rep.final_state || rep.dimension !== 3) return { panels: [], after: () => {} };
  if (rep.protocol === "heap") return heapPanels(rep);
  if (rep.protocol === "packing") return packingPanels(rep);
  return grains3d(rep, "The grains");
}

async function sampleView(hash) {
  await loadRegistry();
  const r = await api(`/api/samples/${hash}`);
  if (!r.ok) { setView(h("h1", {}, "Sample not found"), h("p", { class: "error" }, r.body ? r.body.error : "")); return; }
  const rep = r.body;
  const trace = rep.energy_trace || [];
  const markers = [];
  trace.forEach((p, i) => { if (i > 0 && p.phase !== trace[i - 1].phase) markers.push({ x: p.iteration, label: p.phase }); });
  const ke = h("div", { class: "figure", id: "energy" }, trace.length ? linePlot({ points: trace.map(p => ({ x: p.iteration, y: p.kinetic_energy })),
    xLabel: "iteration", yLabel: "kinetic energy per grain", title: "Kinetic energy (fig. 1b)", logY: true, markers }) : h("p", { class: "muted" }, "no trace"));
  const physics = Object.entries(rep.options.physics || {}).map(([k, v]) => `, ${k.replace(/_/g, " ")} ${v}`).join("");
  const sceneText = JSON.stringify(rep.scene, null, 2);
  const copied = h("span", { class: "muted", "aria-live": "polite" });
  const special = specialPanels(rep);
  const pile = rep.dimension === 3 ? [] : [h("h2", {}, rep.outcome.status === "completed" ? "Final pile, force chains (fig. 1a)" : "Grains when the run stopped, force chains"),
    h("div", { class: "figure", id: "pile" }, pileFigure(rep))];
  setView(
    h("h1", {}, `Sample: ${rep.protocol}, seed ${rep.seed}`),
    h("div", { class: "panel" },
      h("p", {}, h("span", { class: `tag ${rep.outcome.status}` }, rep.outcome.status), " ", outcomeReason(rep.outcome),
        ` · ${rep.dimension}D, model ${rep.model} · ${rep.grains.initial} grains at start, ${rep.grains.lost} lost, ${rep.grains.final} at end · ${rep.iterations} steps, ${fmt(rep.simulated_time)} s simulated, ${fmt(rep.wall_time, 2)} s wall · ${rep.options.integrator}${physics} · ${rep.engine}`),
      anglesTable(rep)),
    ...special.panels,
    pile.length ? h("div", { class: "two" }, h("div", {}, ...pile), h("div", {}, h("h2", {}, "Energy"), ke)) : h("div", {}, h("h2", {}, "Energy"), ke),
    ...curves(rep),
    h("h2", {}, "Scene"),
    h("p", {}, h("button", { class: "secondary", id: "copy-scene", onclick: async () => {
      try { await navigator.clipboard.writeText(sceneText); copied.textContent = "Copied. Save it as scene.json and run: repose run scene.json"; }
      catch (_) { copied.textContent = "Select the text below and copy it; then: repose run scene.json"; }
    } }, "Copy scene JSON"), " ", copied),
    h("pre", { id: "scene-json" }, sceneText));
  special.after();
}

// ---------------------------------------------------------------- help
async function fetchDoc(name) {
  const r = await fetch(`/docs/${name}.md`);
  if (!r.ok) return null;
  return window.markdown.render(await r.text(), "/docs/");
}

function presetsText() {
  const p = registry.protocols.get("fill_release") || [...registry.protocols.values()][0];
  if (!p) return "";
  return Object.entries(p.presets).map(([name, settings]) =>
    `${name} (${Object.entries(settings).map(([k, v]) => `${k} = ${v}`).join(", ")})`).join("; ");
}

// The notes of docs/ beside the papers' reports (which the studies name).
const DOC_LINKS = [
  ["speed-vs-accuracy", "Speed against accuracy of the 2D piles"],
  ["tradeoff-heap", "Speed against accuracy of the 3D heap"],
  ["model", "The 2D model"],
  ["model-3d", "The 3D model and its open choices"],
  ["scene", "Scene files"],
  ["service", "The service"],
  ["benchmarks", "Benchmarks"],
];

async function helpView() {
  await loadRegistry();
  const intro = h("div", { class: "panel" },
    h("p", {}, "repose runs parameter studies of granular piles. A sweep varies scene values (axes) over a base scene, with several samples (seeds) per point; workers run the samples and this page shows what they measured."),
    h("ul", {}, ...[...registry.protocols.values()].map(p => h("li", {}, h("strong", {}, p.name), `: ${p.about}. Measures ${p.metrics.map(m => m.label).join(", ") || "nothing but its final state"}.`))),
    h("p", {}, "Error bars show the sample standard deviation (the paper's error bar) or the standard error; points without a result (not settled, blown up) are counted apart."),
    h("p", {}, `Fidelity presets (fill_release): ${presetsText()}. What each costs and how far it moves the angles is measured below. The API is described at `,
      h("a", { href: "/api/openapi.json" }, "/api/openapi.json"), "."),
    h("p", {}, "Reports and notes:"),
    h("ul", { class: "reports" },
      ...registry.studies.map(st => h("li", {}, h("a", { href: `#/doc/${st.report}` }, `The reproduction of ${st.citation}`))),
      ...DOC_LINKS.map(([name, text]) => h("li", {}, h("a", { href: `#/doc/${name}` }, text)))));
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
    else if (parts[0] === "new") await newView();
    else if (parts[0] === "papers") await papersView();
    else if (parts[0] === "paper" && parts[2] === "figure") await paperFigureView(parts[1], parts[3]);
    else if (parts[0] === "help") await helpView();
    else if (parts[0] === "doc" && parts[1]) await docView(parts[1]);
    else if (parts[0] === "sweep" && parts[2] === "figure") await sweepFigureView(parts[1], parts[3], parts[4]);
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
