// thermogel planner page: plain JS over the service's JSON routes, plots as inline SVG.
// Every input is checked against the bounds the server publishes in /openapi.json (one
// definition); server errors are shown next to the field they name.
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const FIELDS = ["t_start", "t_end", "dry_radius_um", "doses", "rests", "interfacial_length",
  "size_cv", "drug_d0", "drug_radius", "drug_mesh", "drug_load"];
// the drug inputs: page id -> the HTTP drug field (DrugIn), its unit
const DRUG_FIELDS = { drug_d0: ["diffusivity_cm2_s", "cm²/s"], drug_radius: ["solute_radius_nm", "nm"],
  drug_mesh: ["mesh_size_nm", "nm"], drug_load: ["load_ug", "µg"] };
const LABELS = { t_start: "T_start", t_end: "T_end", dry_radius_um: "dry radius",
  doses: "dose", rests: "rest", interfacial_length: "interfacial length",
  sweep_t_end: "T_end", sweep_radius: "dry radius", sweep_doses: "dose" };
const SWEEP_FIELDS = ["sweep_t_end", "sweep_radius", "sweep_doses"];
const GEL_PARAMS = ["omega", "a0", "b0", "a1", "b1"];
const GEL_FIELDS = ["gel_name", ...GEL_PARAMS.map((p) => `gel_${p}`)];
const SAVED_KEY = "thermogel.gels";
for (const p of GEL_PARAMS) LABELS[`gel_${p}`] = p === "omega" ? "Omega" : p.toUpperCase();
LABELS.gel_name = "gel name";
LABELS.size_cv = "size CV";
Object.assign(LABELS, { drug_d0: "D0", drug_radius: "solute radius", drug_mesh: "mesh size",
  drug_load: "load", size_table: "size table" });
let sizeTable = null; // an uploaded size table: {name, sizes_um, counts}
let presets = {}; // preset name -> its parameters (from /v1/gels)
let fittedGels = {}; // stored fitted gel name -> its parameters (from /v1/gels, on the server)
let bounds = {};
let requestCount = 0; // requests this page sent to /v1 (shown in the page state)
let pollTimer = null;
let scheduleToken = 0; // the latest schedule asked: an older schedule job's poll stops showing

// ----------------------------------------------------------------------------- helpers

function fmt(x, digits = 4) {
  if (x === null || x === undefined || !isFinite(x)) return "–";
  const a = Math.abs(x);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return x.toExponential(digits - 1);
  return Number(x.toPrecision(digits)).toString();
}

function esc(text) {
  // text for innerHTML
  const d = document.createElement("span");
  d.textContent = String(text);
  return d.innerHTML;
}

function pct(x) { return x === null || x === undefined ? "–" : `${fmt(100 * x, 3)} %`; }

function numberSchema(schema) {
  // the number member of a schema (nullable fields are anyOf [number, null])
  if (!schema) return {};
  if (schema.anyOf) return numberSchema(schema.anyOf.find((s) => s.type === "number" ||
    s.type === "array") || {});
  return schema;
}

function boundOf(schema) {
  const s = numberSchema(schema);
  return { min: s.minimum, max: s.maximum, exclMin: s.exclusiveMinimum,
    exclMax: s.exclusiveMaximum, maxItems: s.maxItems, description: schema && schema.description };
}

function rangeText(b, scale, unit) {
  const lo = b.min !== undefined ? `${fmt(b.min * scale, 6)} <= ` :
    b.exclMin !== undefined ? `${fmt(b.exclMin * scale, 6)} < ` : "";
  const hi = b.max !== undefined ? ` <= ${fmt(b.max * scale, 6)}` :
    b.exclMax !== undefined ? ` < ${fmt(b.exclMax * scale, 6)}` : "";
  return `${lo}value${hi}${unit ? " " + unit : ""}`;
}

function checkValue(name, text, b, scale = 1, unit = "") {
  // a number within the server's bounds (scale: shown units per server unit), or an error
  const t = String(text).trim().replace(/%$/, "");
  const v = Number(t);
  if (t === "" || !isFinite(v)) return { error: `${LABELS[name]}: a number is needed (${rangeText(b, scale, unit)})` };
  const x = v / scale;
  const bad = (b.min !== undefined && x < b.min) || (b.max !== undefined && x > b.max) ||
    (b.exclMin !== undefined && x <= b.exclMin) || (b.exclMax !== undefined && x >= b.exclMax);
  if (bad) return { error: `${LABELS[name]} = ${t}${unit ? " " + unit : ""} is out of range: ${rangeText(b, scale, unit)}` };
  return { value: x };
}

function hasUnit(text) {
  // a value written with a unit ("29 degC", "10 min", "0.1 mm"): the server's one unit
  // parser (dosing.quantity, the HTTP models) converts and checks it
  const t = String(text).trim();
  return t !== "" && !isFinite(Number(t)) && /[a-zA-Zµμ°℃]/.test(t);
}

function checkQuantity(name, text, b, unit) {
  // a plain number checked against the bounds here; a value with a unit sent as written
  if (hasUnit(text)) return { value: String(text).trim() };
  return checkValue(name, text, b, 1, unit);
}

function checkRests(text, b) {
  // rests in units of tau (plain numbers, or '0.5 tau'), or times with a unit ('10 min',
  // '600 s': sent as rests_seconds, converted by the server); not both in one list
  const parts = String(text).split(/[,;]+/).map((p) => p.trim()).filter((p) => p !== "");
  const tau = [], secs = [];
  for (const p of parts) {
    const m = /^(.*?)\s*(tau|τ)$/i.exec(p);
    if (m || !hasUnit(p)) {
      const r = checkValue("rests", m ? m[1] : p, b, 1, "τ");
      if (r.error) return r;
      tau.push(r.value);
    } else secs.push(p);
  }
  if (tau.length && secs.length)
    return { error: "rest: give every rest in units of tau, or every one with a time unit (10 min), not both" };
  if (b.maxItems !== undefined && parts.length > b.maxItems)
    return { error: `rest: at most ${b.maxItems} values` };
  return { value: secs.length ? { rests_seconds: secs } : { rests: tau }, count: parts.length };
}

function checkList(name, text, b, scale, unit) {
  const parts = String(text).split(/[,;\s]+/).filter((p) => p !== "");
  const out = [];
  for (const p of parts) {
    const r = checkValue(name, p, b, scale, unit);
    if (r.error) return r;
    out.push(r.value);
  }
  if (b.maxItems !== undefined && out.length > b.maxItems)
    return { error: `${LABELS[name]}: at most ${b.maxItems} values` };
  return { value: out };
}

function showError(field, msg) {
  const el = $(`err-${field}`);
  if (el) {
    el.textContent = msg;
    const input = $(field);
    if (input) input.classList.add("invalid");
  } else {
    $("form-error").textContent = ($("form-error").textContent + " " + msg).trim();
  }
}

function clearErrors() {
  for (const f of [...FIELDS, ...GEL_FIELDS]) {
    $(`err-${f}`).textContent = "";
    $(f).classList.remove("invalid");
  }
  $("err-size_table").textContent = "";
  $("form-error").textContent = "";
}

async function api(method, path, body) {
  requestCount += 1;
  document.body.dataset.requests = String(requestCount);
  const resp = await fetch(path, { method, headers: body ? { "Content-Type": "application/json" } : {},
    body: body ? JSON.stringify(body) : undefined });
  let data = null;
  try { data = await resp.json(); } catch (e) { data = { detail: await resp.text() }; }
  return { status: resp.status, data, headers: resp.headers };
}

function fieldOf(loc) {
  // the page's input for a server error's loc: ['body', 'dose_fraction'] -> doses
  const parts = (loc || []).filter((p) => !["body", "query", "custom", "preset"].includes(p));
  const name = parts.length ? String(parts[0]) : "";
  if (name === "dose_fraction" || name === "doses") return { input: "doses", name: parts.join(".") };
  if (name === "rests" || name === "rests_seconds") return { input: "rests", name: parts.join(".") };
  if (name === "swollen_radius_um") return { input: "dry_radius_um", name: parts.join(".") };
  if (name === "size_distribution") return { input: $("size-clear").hidden ? "size_cv" : "size_table", name: parts.join(".") };
  if (name === "drug") {
    const page = Object.keys(DRUG_FIELDS).find((k) => DRUG_FIELDS[k][0] === String(parts[1]));
    if (page) $("drug-inputs").open = true;
    return { input: page || null, name: parts.join(".") };
  }
  if (name === "gel" && GEL_PARAMS.includes(String(parts[1]))) {
    $("custom-gel").open = true;
    return { input: `gel_${parts[1]}`, name: parts.join(".") };
  }
  return { input: FIELDS.includes(name) ? name : null, name: parts.join(".") || "request" };
}

function showServerError(res) {
  if (res.status === 429) {
    const retry = res.headers.get("Retry-After");
    $("form-error").textContent = `The server's queue is full: try again in ${retry || "a few"} s.`;
    return;
  }
  const detail = res.data && res.data.detail;
  if (Array.isArray(detail)) {
    for (const item of detail) {
      const f = fieldOf(item.loc);
      const msg = `${f.name}: ${item.msg}`;
      if (f.input) showError(f.input, msg); else showError("form", msg);
    }
  } else {
    $("form-error").textContent = `HTTP ${res.status}: ${detail || "error"}`;
  }
}

// ----------------------------------------------------------------------------- SVG plots

function el(tag, attrs, parent, text) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  if (parent) parent.appendChild(e);
  return e;
}

function ticks(lo, hi, n = 5) {
  const span = hi - lo || 1;
  const raw = span / n;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => span / s <= n) || 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

function panel(svg, box, xlim, ylim, xlabel, ylabel) {
  // axes in box {x, y, w, h}; returns the scales
  const sx = (x) => box.x + (x - xlim[0]) / (xlim[1] - xlim[0]) * box.w;
  const sy = (y) => box.y + box.h - (y - ylim[0]) / (ylim[1] - ylim[0]) * box.h;
  const g = el("g", { class: "axis" }, svg);
  for (const t of ticks(ylim[0], ylim[1], 4)) {
    el("line", { x1: box.x, x2: box.x + box.w, y1: sy(t), y2: sy(t), class: "grid" }, g);
    el("text", { x: box.x - 4, y: sy(t) + 4, "text-anchor": "end" }, g, fmt(t, 3));
  }
  for (const t of ticks(xlim[0], xlim[1], 5)) {
    el("line", { x1: sx(t), x2: sx(t), y1: box.y + box.h, y2: box.y + box.h + 4 }, g);
    if (xlabel !== null) el("text", { x: sx(t), y: box.y + box.h + 15, "text-anchor": "middle" }, g, fmt(t, 3));
  }
  el("rect", { x: box.x, y: box.y, width: box.w, height: box.h, fill: "none", stroke: "#888" }, g);
  if (xlabel) el("text", { x: box.x + box.w / 2, y: box.y + box.h + 30, "text-anchor": "middle" }, g, xlabel);
  el("text", { x: 12, y: box.y + box.h / 2, transform: `rotate(-90 12 ${box.y + box.h / 2})`,
    "text-anchor": "middle" }, g, ylabel);
  return { sx, sy };
}

function polyline(svg, s, xs, ys, attrs) {
  const pts = xs.map((x, i) => `${s.sx(x).toFixed(1)},${s.sy(ys[i]).toFixed(1)}`).join(" ");
  return el("polyline", { points: pts, fill: "none", "stroke-width": 2, ...attrs }, svg);
}

function legend(svg, x, y, items) {
  items.forEach((it, i) => {
    el("line", { x1: x, x2: x + 18, y1: y + 14 * i, y2: y + 14 * i, stroke: it.color,
      "stroke-width": 2, "stroke-dasharray": it.dash || "" }, svg);
    el("text", { x: x + 22, y: y + 14 * i + 4 }, svg, it.label);
  });
}

function clear(svg) { while (svg.firstChild) svg.removeChild(svg.firstChild); }

function drawCurve(curve, marks, tau, batch) {
  // radius and front against time (seconds with a bead size), each dose marked; a batch
  // (the curve is its mean bead's): the batch's own dose time as a dashed line
  const svg = $("curve-plot");
  clear(svg);
  const k = tau || 1;
  const t = curve.t.map((x) => x * k);
  const tMax = Math.max(...marks.map((m) => m.time * k * 1.15), curve.t_stop * k * 0.25,
    batch ? batch.time * k * 1.15 : 0);
  const keep = t.map((x, i) => i).filter((i) => t[i] <= tMax);
  const ymax = curve.start_radius * 1.05;
  const s = panel(svg, { x: 55, y: 12, w: 445, h: 235 }, [0, tMax], [0, ymax],
    tau ? "time (s)" : "time (units of τ)", "radius (dry radii)");
  polyline(svg, s, keep.map((i) => t[i]), keep.map((i) => curve.radius[i]), { stroke: "#1f6fb2", id: "curve-radius" });
  polyline(svg, s, keep.map((i) => t[i]), keep.map((i) => curve.front[i]), { stroke: "#d9822b", "stroke-dasharray": "5 3" });
  el("line", { x1: s.sx(0), x2: s.sx(tMax), y1: s.sy(curve.final_radius), y2: s.sy(curve.final_radius),
    stroke: "#999", "stroke-dasharray": "2 3" }, svg);
  for (const m of marks) {
    const x = s.sx(m.time * k);
    el("line", { x1: x, x2: x, y1: s.sy(0), y2: s.sy(ymax), stroke: "#b3261e", "stroke-width": 1.2, class: "dose-mark" }, svg);
    el("circle", { cx: x, cy: s.sy(m.radius), r: 4, fill: "#b3261e" }, svg);
    el("text", { x: x + 4, y: s.sy(m.radius) - 6 }, svg, m.label);
  }
  if (batch) {
    const x = s.sx(batch.time * k);
    el("line", { x1: x, x2: x, y1: s.sy(0), y2: s.sy(ymax), stroke: "#6a3d9a", "stroke-width": 1.5,
      "stroke-dasharray": "6 3", class: "batch-mark" }, svg);
    el("text", { x: x + 4, y: s.sy(ymax) + 14 }, svg, batch.label);
  }
  legend(svg, 330, 180, [{ color: "#1f6fb2", label: "bead radius a(t)" },
    { color: "#d9822b", label: "front R_f(t)", dash: "5 3" },
    { color: "#999", label: "equilibrium at T_end", dash: "2 3" }]);
}

function releaseAt(curve, time) {
  // fraction of the stored fluid released by hold time t, from the front curve
  const a0 = curve.start_radius;
  let a = curve.radius[curve.radius.length - 1];
  for (let i = 1; i < curve.t.length; i++) {
    if (curve.t[i] >= time) {
      const w = (time - curve.t[i - 1]) / (curve.t[i] - curve.t[i - 1]);
      a = curve.radius[i - 1] + w * (curve.radius[i] - curve.radius[i - 1]);
      break;
    }
  }
  return (a0 ** 3 - a ** 3) / (a0 ** 3 - 1);
}

function drawTimeline(rows, rests, tStart, tEnd, tau, curve, linearWhy) {
  // the protocol (heat at T_end, rest at T_start) and cumulative release against clock time
  const svg = $("timeline-plot");
  clear(svg);
  const k = tau || 1;
  const clockT = [0], temp = [tStart], relT = [0], rel = [0];
  let clock = 0;
  rows.forEach((r, i) => {
    temp.push(tStart); clockT.push(clock); temp.push(tEnd); clockT.push(clock);
    const n = 24;
    for (let j = 1; j <= n; j++) {
      const hold = r.start + (r.end - r.start) * j / n;
      relT.push((clock + hold - r.start) * k);
      rel.push(100 * (curve ? releaseAt(curve, hold) : r.cumulative_fraction * j / n +
        (r.cumulative_fraction - r.dose_fraction) * (1 - j / n)));
    }
    clock += r.end - r.start;
    clockT.push(clock); temp.push(tEnd); clockT.push(clock); temp.push(tStart);
    const rest = i < rests.length ? rests[i] : 0;
    if (rest > 0) { clock += rest; relT.push(clock * k); rel.push(rel[rel.length - 1]); }
  });
  const end = clock * 1.05 || 1;
  clockT.push(end); temp.push(tStart);
  relT.push(end * k); rel.push(rel[rel.length - 1]);
  const xl = [0, end * k];
  const top = panel(svg, { x: 55, y: 10, w: 445, h: 80 }, xl, [tStart - 1, tEnd + 1], null, "T (K)");
  polyline(svg, top, clockT.map((x) => x * k), temp, { stroke: "#b3261e", id: "timeline-temperature" });
  const bot = panel(svg, { x: 55, y: 115, w: 445, h: 140 }, xl, [0, 100],
    tau ? "clock time (s)" : "clock time (units of τ)", "released (%)");
  polyline(svg, bot, relT, rel, { stroke: "#1f6fb2", id: "timeline-release" });
  if (!curve) el("text", { x: 62, y: 128 }, svg, linearWhy || "release drawn linearly within each heating (no front-model curve)");
  let acc = 0;
  rows.forEach((r, i) => {
    acc += r.end - r.start + (i > 0 && i - 1 < rests.length ? rests[i - 1] : 0);
    el("text", { x: bot.sx(acc * k) - 2, y: bot.sy(100 * r.cumulative_fraction) - 5, "text-anchor": "end" },
      svg, `${fmt(100 * r.cumulative_fraction, 3)}%`);
  });
}

function heatFor(seconds, time) {
  return seconds !== null && seconds !== undefined ? `${fmt(seconds)} s` : `${fmt(time)} τ`;
}

function scheduleTable(rows, reading) {
  // leads with the headline times (the corrected ones once corrected); the rough hold
  // reading beside them when they are corrected, or labelled as such when it is all there is
  const lead = reading === "corrected" ? "heat for (corrected)" :
    reading === "hold" ? "heat for (rough hold reading)" : "heat for";
  const holdCol = reading === "corrected" && rows.some((r) => r.hold_time !== undefined);
  const errHead = reading === "corrected" ? "shooting residual" : "error estimate (the single dose's)";
  const head = `<tr><th>dose</th><th>cumulative</th><th>${lead}</th><th>${errHead}</th>` +
    `${holdCol ? "<th>rough hold reading</th>" : ""}</tr>`;
  const body = rows.map((r) => `<tr><td>${pct(r.dose_fraction)}</td><td>${pct(r.cumulative_fraction)}</td>` +
    `<td class="heat-for" data-value="${r.actuation_seconds ?? ""}">${heatFor(r.actuation_seconds, r.actuation_time)}</td>` +
    `<td>${pct(r.error_estimate)}</td>` +
    `${holdCol ? `<td class="hold-reading">${r.hold_time === undefined ? "–" : heatFor(r.hold_seconds, r.hold_time)}</td>` : ""}</tr>`).join("");
  $("schedule-table").innerHTML = `<table>${head}${body}</table>`;
  $("schedule-table").dataset.reading = reading || "";
}

function scheduleRows(s) {
  // a schedule answer's rows: its headline times (``actuation_times``/``actuation_seconds``:
  // the corrected times when ``reading`` is 'corrected', else the hold reading), each with
  // the rough hold reading's time beside it
  const hold = s.hold || [];
  const corrected = s.reading === "corrected" && s.corrected;
  const times = s.actuation_times || hold.map((r) => r.actuation_time);
  const secs = s.actuation_seconds || null;
  const errs = corrected ? (corrected.relative_errors || []).map((e) => Math.abs(e)) :
    hold.map((r) => r.error_estimate);
  let cum = 0;
  let clock = 0;
  return s.doses.map((d, k) => {
    cum = hold[k] ? hold[k].cumulative_fraction : cum + d;
    const start = corrected || !hold[k] ? clock : hold[k].start;
    const end = corrected || !hold[k] ? clock + times[k] : hold[k].end;
    clock = end;
    return { dose_fraction: d, cumulative_fraction: cum, start, end, actuation_time: times[k],
      actuation_seconds: secs ? secs[k] : null, error_estimate: errs[k],
      hold_time: hold[k] ? hold[k].actuation_time : undefined,
      hold_seconds: hold[k] ? hold[k].actuation_seconds : undefined };
  });
}

// ----------------------------------------------------------------------------- the form

function readForm() {
  // the request fields, or null after showing every input error (no request is sent)
  clearErrors();
  const b = bounds;
  const out = { gel: gelSpec() };
  let ok = true;
  const take = (name, r) => { if (r.error) { showError(name, r.error); ok = false; } else out[name] = r.value; };
  // temperatures in K, or with a unit ("29 degC"): the server converts them
  take("t_start", checkQuantity("t_start", $("t_start").value, b.t_start, "K"));
  take("t_end", checkQuantity("t_end", $("t_end").value, b.t_end, "K"));
  out.size_kind = $("size_kind").value;  // 'dry' or 'swollen' (at T_start)
  const rb = out.size_kind === "swollen" ? b.swollen_radius_um : b.dry_radius_um;
  if ($("dry_radius_um").value.trim() !== "")
    take("dry_radius_um", checkQuantity("dry_radius_um", $("dry_radius_um").value, rb, "µm"));
  if (sizeTable) {  // a batch: the uploaded table of sizes
    out.size_table = sizeTable;
  } else if ($("size_cv").value.trim() !== "") {  // a batch: a lognormal whose mean is the radius
    take("size_cv", checkValue("size_cv", $("size_cv").value, b.size_cv));
    if (out.dry_radius_um === undefined && $("dry_radius_um").value.trim() === "") {
      showError("size_cv", "size CV: give the radius too (the batch's number-weighted mean)");
      ok = false;
    }
  }
  const drug = {};
  for (const [id, [field, unit]] of Object.entries(DRUG_FIELDS)) {
    if ($(id).value.trim() === "") continue;
    const r = checkQuantity(id, $(id).value, b.drug[field] || {}, unit);
    if (r.error) { showError(id, r.error); ok = false; } else drug[field] = r.value;
  }
  if (Object.keys(drug).length) out.drug = drug;
  if ($("interfacial_length").value.trim() !== "")  // empty: the bead's own (xi_dry / a_d)
    take("interfacial_length", checkValue("interfacial_length", $("interfacial_length").value, b.interfacial_length));
  const doses = checkList("doses", $("doses").value, { ...b.dose_fraction, maxItems: b.doses.maxItems }, 100, "%");
  if (!doses.error && doses.value.length === 0) doses.error = "dose: give one dose, or several separated by commas";
  take("doses", doses);
  const rests = checkRests($("rests").value, b.rests);
  out.rests = [];
  if (rests.error) { showError("rests", rests.error); ok = false; } else Object.assign(out, rests.value);
  const nRests = rests.count || 0;
  if (ok && nRests && nRests !== out.doses.length - 1) {
    showError("rests", `rest: give ${out.doses.length - 1} rests (one between consecutive doses), or none`);
    ok = false;
  }
  if (ok && out.doses.reduce((a, x) => a + x, 0) > 1) {
    showError("doses", `dose: the doses add up to more than 100 % of the ${out.drug ? "load" : "stored fluid"}`);
    ok = false;
  }
  out.validate = $("validate").checked;
  return ok ? out : null;
}

function sizeBody(f, body) {
  // the bead size as the HTTP API takes it: dry_radius_um or swollen_radius_um, and a
  // batch's size_distribution (a lognormal by CV, or the uploaded table) in the same state
  if (f.dry_radius_um !== undefined) body[f.size_kind === "swollen" ? "swollen_radius_um" : "dry_radius_um"] = f.dry_radius_um;
  if (f.size_table) {
    body.size_distribution = { kind: "table", sizes_um: f.size_table.sizes_um,
      state: f.size_kind, measure: $("size_measure").value };
    if (f.size_table.counts) body.size_distribution.counts = f.size_table.counts;
  } else if (f.size_cv !== undefined) {
    body.size_distribution = { kind: "lognormal", cv: f.size_cv };
    if (f.size_kind === "swollen") body.size_distribution.state = "swollen";
  }
  return body;
}

function doseBody(f, fraction, validate) {
  const body = { gel: f.gel, t_start: f.t_start, t_end: f.t_end, dose_fraction: fraction,
    interfacial_length: f.interfacial_length };
  sizeBody(f, body);
  if (f.drug) body.drug = f.drug;
  if (validate) body.validate = true;
  return body;
}

function parseSizeTable(text, name) {
  // a CSV of sizes (um), one per row, optionally a second column of counts; a header may
  // name the measure ('diameter') and the state ('swollen'); '#' lines are comments
  const rows = text.split(/\r?\n/).map((l, i) => [i + 1, l.trim()]).filter(([, l]) => l !== "" && !l.startsWith("#"));
  if (!rows.length) return { error: `size table ${name}: no rows` };
  const cells = (l) => l.split(/[,;\t]/).map((c) => c.trim());
  let header = null;
  if (!isFinite(Number(cells(rows[0][1])[0]))) header = rows.shift()[1].toLowerCase();
  const sizes = [], counts = [];
  for (const [line, l] of rows) {
    const c = cells(l);
    const x = Number(c[0]);
    if (c[0] === "" || !isFinite(x) || x <= 0) return { error: `size table ${name}, line ${line}: '${c[0]}' is not a size > 0 (um)` };
    sizes.push(x);
    if (c.length > 1 && c[1] !== "") {
      const n = Number(c[1]);
      if (!isFinite(n) || n < 0) return { error: `size table ${name}, line ${line}: '${c[1]}' is not a count >= 0` };
      counts.push(n);
    }
  }
  if (counts.length && counts.length !== sizes.length) return { error: `size table ${name}: give a count on every row, or on none` };
  return { value: { name, sizes_um: sizes, counts: counts.length ? counts : null,
    measure: header && /diam/.test(header) ? "diameter" : header && /radi/.test(header) ? "radius" : null,
    state: header && /swollen|swell/.test(header) ? "swollen" : header && /dry/.test(header) ? "dry" : null } };
}

async function uploadSizes(ev) {
  const file = ev.target.files && ev.target.files[0];
  if (!file) return;
  $("err-size_table").textContent = "";
  const r = parseSizeTable(await file.text(), file.name);
  ev.target.value = "";
  if (r.error) { $("err-size_table").textContent = r.error; document.body.dataset.sizeTable = "invalid"; return; }
  sizeTable = r.value;
  if (r.value.measure) $("size_measure").value = r.value.measure;
  if (r.value.state) $("size_kind").value = r.value.state;
  $("size-table-status").textContent = `${file.name}: ${r.value.sizes_um.length} sizes` +
    (r.value.counts ? " with counts" : "") + " (the batch; the size CV is not used)";
  $("size-clear").hidden = false;
  document.body.dataset.sizeTable = "loaded";
}

function clearSizes() {
  sizeTable = null;
  $("size-table-status").textContent = "";
  $("err-size_table").textContent = "";
  $("size-clear").hidden = true;
  delete document.body.dataset.sizeTable;
}

function showBatch(bt) {
  // a batch's answer (docs/batch.md): its dose time, the beads delivered, the spread
  const label = $("answer-batch-label");
  const dd = $("answer-batch");
  label.hidden = dd.hidden = !bt;
  if (!bt) { dd.textContent = ""; delete dd.dataset.value; return; }
  const secs = (x) => (x === null || x === undefined ? "–" : `${fmt(x)} s`);
  const p = bt.percentile_seconds || [];
  dd.innerHTML = `the batch's own time <b id="answer-batch-seconds">${secs(bt.seconds)}</b> ` +
    `(${bt.delay >= 0 ? "+" : ""}${pct(bt.delay)} against the mean bead, t = ${fmt(bt.time)} τ); ` +
    `${pct(bt.fraction_delivered)} of the beads have delivered their own dose by then; ` +
    `the 10th–90th percentile bead's own time ${secs(p[0])} – ${secs(p[2])}. ` +
    `<span class="hint">${bt.description}; quadrature ${bt.quadrature.nodes} nodes, error ` +
    `${bt.quadrature.error.toExponential(1)}</span>`;
  dd.dataset.value = String(bt.time);
  dd.dataset.seconds = bt.seconds === null || bt.seconds === undefined ? "" : String(bt.seconds);
}

function showReference(ref) {
  // a batch: its mean bead's own time, secondary to the batch's (``reference_bead``)
  const label = $("answer-reference-label");
  const dd = $("answer-reference");
  label.hidden = dd.hidden = !ref;
  if (!ref) { dd.textContent = ""; delete dd.dataset.value; delete dd.dataset.time; return; }
  dd.innerHTML = `<span id="answer-reference-seconds">${heatFor(ref.seconds, ref.time)}</span> ` +
    `<span class="hint">(t = ${fmt(ref.time)} τ: the number-weighted mean bead alone, ` +
    `${fmt(ref.dry_radius_um)} µm dry, ${ref.model} model)</span>`;
  dd.dataset.value = ref.seconds === null || ref.seconds === undefined ? "" : String(ref.seconds);
  dd.dataset.time = String(ref.time);
}

function showAnswer(a, total) {
  // the headline is the answer's own (``headline``, ``time``, ``seconds``): a batch's own
  // time for a batch, its mean bead's beside it (``reference_bead``)
  $("answer-panel").hidden = false;
  const ref = a.reference_bead || null;
  $("answer-headline").textContent = a.headline || "";
  const secs = $("answer-seconds");
  secs.textContent = heatFor(a.seconds, a.time);
  secs.dataset.value = a.seconds === null || a.seconds === undefined ? "" : String(a.seconds);
  const t = $("answer-time");
  t.textContent = `(t = ${fmt(a.time)} in units of τ${ref ? " of the mean bead: the batch's own time" : ""}` +
    `${total > 1 ? `; all ${total} doses` : ""})`;
  t.dataset.value = String(a.time);
  showReference(ref);
  $("answer-model").textContent = a.behaviour ? `${a.model} (${a.behaviour})` : a.model;
  $("answer-error").textContent = `± ${pct(a.error_estimate)}` + (ref ? " (the mean bead's)" : "");
  $("answer-release").textContent = `${pct(a.dose_fraction)} of the ${a.drug ? "drug load" : "stored fluid"}` +
    (a.expelled_volume_ul !== null && a.expelled_volume_ul !== undefined ?
      `: ${fmt(a.expelled_volume_ul)} µL of ${fmt(a.stored_volume_ul)} µL; radius ${fmt(a.start_radius)} → ${fmt(a.final_radius)} dry radii (${fmt(a.final_radius_um)} µm)` :
      `; radius ${fmt(a.start_radius)} → ${fmt(a.final_radius)} dry radii`) +
    (ref ? " (the mean bead's)" : "");
  $("answer-tau").textContent = (a.timescale_seconds ? `${fmt(a.timescale_seconds)} s` : "give a bead size") +
    (ref && a.timescale_seconds ? " (the mean bead's: the batch's times are in its units)" : "");
  $("answer-error-parts").textContent = a.error_explanation || "";
  $("answer-note").textContent = `${a.truth ? "Truth: " + a.truth + ". " : ""}${a.note || ""}`;
  showBatch(a.batch);
}

function showValidation(v, started) {
  $("validation-panel").hidden = false;
  const widths = { pending: "15%", running: "55%", done: "100%", failed: "100%" };
  $("validation-bar").style.width = widths[v.status] || "5%";
  $("validation-bar").style.background = v.status === "failed" ? "#b3261e" : "";
  const secs = ((Date.now() - started) / 1000).toFixed(0);
  $("validation-status").textContent = `validation ${v.id}: ${v.status} (${secs} s)`;
  $("validation-panel").dataset.status = v.status;
  if (v.status === "failed") $("validation-result").textContent = v.error || "failed";
  if (v.status !== "done" || !v.result) return;
  const r = v.result;
  const rows = (r.runs || []).map((e) => `<tr><td>${e.grid}</td><td>${e.n}</td><td>${fmt(e.interfacial_length)}</td>` +
    `<td>${fmt(e.time)}</td><td>${fmt(e.wall_seconds, 3)} s</td></tr>`).join("");
  $("validation-result").innerHTML =
    `<p>Truth (${r.model}): t = <b>${fmt(r.time)}</b> τ ± ${pct(r.error)}` +
    (r.front_time === null || r.front_time === undefined ? " (no front model on this jump).</p>" :
      `; front model t = ${fmt(r.front_time)} τ, time error ${pct(r.front_time_error)}, ` +
      `volume error ${pct(r.front_volume_error)}.</p>`) +
    `<table><tr><th>grid</th><th>N</th><th>ℓ</th><th>time (τ)</th><th>wall</th></tr>${rows}</table>`;
}

function poll(vid, onDone) {
  const started = Date.now();
  if (pollTimer) clearTimeout(pollTimer);
  const step = async () => {
    const res = await api("GET", `/v1/validations/${encodeURIComponent(vid)}`);
    if (res.status !== 200) { showServerError(res); return; }
    showValidation(res.data, started);
    if (res.data.status === "done" || res.data.status === "failed") { if (onDone) onDone(res.data); return; }
    pollTimer = setTimeout(step, 1000);
  };
  step();
}

function resetSchedule() {
  for (const id of ["schedule-headline", "schedule-status", "schedule-note", "schedule-table"]) $(id).textContent = "";
  $("schedule-caption").textContent = "Schedule: the heat/rest steps and cumulative release";
  $("answer-heat-label").textContent = "Heat for";
  delete $("schedule-headline").dataset.value;
  delete $("schedule-headline").dataset.reading;
  for (const k of ["schedule", "scheduleJob", "scheduleBatch"]) delete document.body.dataset[k];
}

function batchWords(s) {
  // a batch schedule's batch: its size CV and its reference bead
  const cv = s.distribution && s.distribution.cv !== null && s.distribution.cv !== undefined ?
    `size CV ${fmt(s.distribution.cv, 3)}` : esc(s.description || "a batch");
  return `${cv}; times in the reference bead's units, the number-weighted mean bead of ` +
    `${fmt(s.reference_dry_radius_um)} µm dry (τ = ${fmt(s.timescale_seconds)} s)`;
}

function kelvinText(k) {
  return `${fmt(k, 5)} K (${fmt(k - 273.15, 4)} °C)`;
}

function spanText(e) {
  // a step's duration: seconds (and minutes past two), or tau without a bead size
  if (e.duration_s === null || e.duration_s === undefined) return `${fmt(e.duration_tau)} τ`;
  return e.duration_s >= 120 ? `${fmt(e.duration_s)} s (${fmt(e.duration_s / 60)} min)` : `${fmt(e.duration_s)} s`;
}

function eventsTable(s) {
  // the schedule's events (one row per step: heat, rest, a drug's wait), the corrected
  // times when corrected; every column named for what it is
  const ev = s.events || [];
  const reading = ev.length ? ev[0].reading : s.reading;
  const rough = ev.length && ev[0].rough;
  const of = s.drug ? "of the load" : "of the stored fluid";
  const resHead = reading === "corrected" ? "shooting residual (delivered / asked − 1)" :
    reading === "checked" ? "full-solver error (delivered / asked − 1)" : null;
  const hold = s.hold || [];
  const holdCol = reading === "corrected" && hold.length > 0;
  const head = `<tr><th>#</th><th>step</th><th>start</th><th>duration</th><th>set temperature</th>` +
    `<th>delivers (${of})</th><th>released so far</th><th>dose asked</th>` +
    `${resHead ? `<th>${resHead}</th>` : ""}${holdCol ? "<th>rough hold reading</th>" : ""}</tr>`;
  const body = ev.map((e) => {
    const heat = e.kind === "heat";
    const h = heat ? hold[e.heating - 1] : null;
    const start = e.start_s === null || e.start_s === undefined ? `${fmt(e.start_tau)} τ` : `${fmt(e.start_s)} s`;
    const what = heat ? (e.program ? `heat: ${esc(e.program)}` : "heat") :
      e.kind === "rest" ? "rest" : "hold (wait at T_start)";
    return `<tr class="${e.kind}"><td>${e.step}</td><td class="kind">${what}</td><td>${start}</td>` +
      `<td class="${heat ? "heat-for" : "rest-for"}" data-value="${e.duration_s ?? ""}">${spanText(e)}</td>` +
      `<td>${kelvinText(e.temperature_K)}</td><td>${pct(e.dose_fraction)}</td><td>${pct(e.released_fraction)}</td>` +
      `<td>${heat ? pct(e.target_fraction) : "–"}</td>` +
      `${resHead ? `<td class="residual">${heat && e.dose_error !== null ? `${e.dose_error >= 0 ? "+" : ""}${pct(e.dose_error)}` : "–"}</td>` : ""}` +
      `${holdCol ? `<td class="hold-reading">${h ? heatFor(h.actuation_seconds, h.actuation_time) : "–"}</td>` : ""}</tr>`;
  }).join("");
  const cap = rough ? "The hold reading (rough: one continuous heating, not checked on the full solver)" :
    reading === "corrected" ? "The corrected schedule: each step as a bath controller or a lab notebook takes it" :
      "The hold times as the full solver runs them (not corrected)";
  const csv = `data:text/csv;charset=utf-8,${encodeURIComponent(eventsCsv(ev))}`;
  $("schedule-table").innerHTML = `<table><caption>${cap}</caption>${head}${body}</table>` +
    `<p class="hint"><a id="schedule-download" href="${csv}" download="schedule-events.csv">` +
    "The steps as CSV</a> (one row per step, units in the headers)</p>";
  $("schedule-table").dataset.reading = reading || "";
}

// the events' columns as the CSV export names them (dosing.question.events.EVENT_COLUMNS)
const EVENT_UNITS = [["step", "1"], ["kind", ""], ["start_s", "s"], ["duration_s", "s"],
  ["temperature_K", "K"], ["dose_fraction", "1"], ["released_fraction", "1"], ["amount_ul", "uL"],
  ["amount_ug", "ug"], ["target_fraction", "1"], ["dose_error", "1"], ["uptake_fraction", "1"],
  ["heating", "1"], ["start_tau", "1"], ["duration_tau", "1"], ["program", ""], ["reading", ""],
  ["rough", "1"]];

function eventsCsv(ev) {
  // the events as tidy CSV ('name [unit]' headers), for a bath controller or a notebook
  const cell = (v) => {
    if (v === null || v === undefined) return "";
    if (typeof v === "boolean") return v ? "1" : "0";
    const t = String(v);
    return /[",\n]/.test(t) ? `"${t.replace(/"/g, '""')}"` : t;
  };
  const head = EVENT_UNITS.map(([n, u]) => (u ? `${n} [${u}]` : n)).join(",");
  return [head, ...ev.map((e) => EVENT_UNITS.map(([n]) => cell(e[n])).join(","))].join("\n") + "\n";
}

function drawEvents(s, ctx) {
  // the events on one clock: the set temperature (a protocol heating drawn as a ramp from
  // T_start to its end's set point) and the cumulative release, linear within each step
  const ev = s.events || [];
  const svg = $("timeline-plot");
  clear(svg);
  if (!ev.length) return;
  const secs = ev.every((e) => e.start_s !== null && e.start_s !== undefined);
  const t0 = (e) => (secs ? e.start_s : e.start_tau);
  const dt = (e) => (secs ? e.duration_s : e.duration_tau);
  const tStart = ctx.tStart;
  const clockT = [0], temp = [tStart], relT = [0], rel = [0];
  let prev = 0;
  for (const e of ev) {
    const a = t0(e), b = a + dt(e);
    clockT.push(a); temp.push(e.program ? tStart : e.temperature_K);
    clockT.push(b); temp.push(e.temperature_K);
    clockT.push(b); temp.push(tStart);
    relT.push(a); rel.push(100 * prev);
    relT.push(b); rel.push(100 * e.released_fraction);
    prev = e.released_fraction;
  }
  const last = ev[ev.length - 1];
  const end = (t0(last) + dt(last)) * 1.03 || 1;
  clockT.push(end); temp.push(tStart);
  relT.push(end); rel.push(100 * prev);
  const temps = ev.map((e) => e.temperature_K).concat([tStart]);
  const xl = [0, end];
  const top = panel(svg, { x: 55, y: 10, w: 445, h: 80 }, xl, [Math.min(...temps) - 1, Math.max(...temps) + 1], null, "T (K)");
  polyline(svg, top, clockT, temp, { stroke: "#b3261e", id: "timeline-temperature" });
  const ymax = Math.max(100, 100 * Math.max(...ev.map((e) => e.released_fraction)));
  const bot = panel(svg, { x: 55, y: 115, w: 445, h: 140 }, xl, [0, ymax],
    secs ? "clock time (s)" : "clock time (units of τ)", "released (%)");
  polyline(svg, bot, relT, rel, { stroke: "#1f6fb2", id: "timeline-release", "data-reading": ev[0].reading });
  for (const e of ev.filter((x) => x.kind === "heat")) {
    el("text", { x: bot.sx(t0(e) + dt(e)) - 2, y: bot.sy(100 * e.released_fraction) - 5, "text-anchor": "end",
      class: "release-mark" }, svg, `${fmt(100 * e.released_fraction, 3)}%`);
  }
  if (ev[0].rough) el("text", { x: 62, y: 128 }, svg, "rough: the hold reading (one continuous heating)");
}

function scheduleAnswerPending(a) {
  // a schedule queued: the answer panel says its one continuous heating is a rough reading
  $("answer-heat-label").textContent = "All doses in one heating (rough)";
  $("answer-headline").textContent = "A schedule: the corrected heat/rest times follow (the time below is one continuous heating, the rough hold reading).";
}

function scheduleAnswer(s) {
  // the answer panel leads with the schedule's heatings (the corrected ones when corrected)
  const ev = s.events || [];
  const heats = ev.filter((e) => e.kind === "heat");
  if (!heats.length) return;
  $("answer-heat-label").textContent = `Heat for (${ev[0].rough ? "rough hold reading" : ev[0].reading})`;
  const secs = $("answer-seconds");
  secs.textContent = heats.map((e) => (e.duration_s === null || e.duration_s === undefined ?
    `${fmt(e.duration_tau)} τ` : `${fmt(e.duration_s)} s`)).join(", ");
  secs.dataset.value = JSON.stringify(heats.map((e) => e.duration_s ?? e.duration_tau));
  const rests = ev.filter((e) => e.kind === "rest");
  $("answer-time").textContent = rests.length ? `with rests of ${rests.map(spanText).join(", ")} at ${kelvinText(ev.find((e) => e.kind === "rest").temperature_K)}` : "";
  $("answer-headline").textContent = s.headline || "";
}

function showSchedule(s, ctx) {
  // a schedule answer (200, or a schedule job's result): its events lead the headline, the
  // table and the plot (the corrected schedule when it was corrected: ``reading``)
  const ev = s.events || [];
  const heats = ev.filter((e) => e.kind === "heat");
  const corrected = s.reading === "corrected";
  const batch = s.batch === true;
  const secs = heats.every((e) => e.duration_s !== null && e.duration_s !== undefined);
  const times = heats.map((e) => (secs ? `${fmt(e.duration_s)} s` : `${fmt(e.duration_tau)} τ`));
  const h = $("schedule-headline");
  const who = batch ? "The batch's schedule: heat" : "Heat";
  const how = corrected ? "corrected by the full solver" : ev.length && ev[0].rough ?
    "the rough hold reading: one continuous heating" : "the hold times as the full solver runs them";
  h.innerHTML = `${who} for <b id="schedule-seconds">${times.join(", ")}</b> (${how})` +
    (batch ? `<br><span class="secondary" id="schedule-batch">${batchWords(s)}</span>` : "") +
    (s.headline ? `<br><span class="secondary">${esc(s.headline)}</span>` : "");
  h.dataset.reading = s.reading;
  h.dataset.value = JSON.stringify(heats.map((e) => (secs ? e.duration_s : e.duration_tau)));
  $("schedule-caption").textContent = corrected ?
    "Schedule: the corrected heat/rest steps and cumulative release" :
    `Schedule: the heat/rest steps and cumulative release (${ev.length && ev[0].rough ? "rough hold reading" : "not corrected"})`;
  eventsTable(s);
  drawEvents(s, ctx);
  scheduleAnswer(s);
  const c = s.corrected;
  $("schedule-note").textContent = corrected ?
    (batch ? `Corrected by the full solver, every size its own run: the batch's summed release meets each ` +
      `dose within ${pct(c.max_relative_error)} (quadrature over ${s.quadrature.nodes} sizes).` :
      `Corrected by the full solver: each heating meets its dose within ${pct(c.max_relative_error)} ` +
      "in the real heat/rest protocol (the shooting residual column).") +
      " The rough hold reading (one continuous heating) is beside it." :
    "Hold reading only (rough: one continuous heating; the protocol was not corrected).";
  $("schedule-status").textContent = "";
  document.body.dataset.schedule = s.reading;  // 'corrected' or 'hold'
}

function pollSchedule(vid, ctx, token) {
  // a schedule job (every batch's, and the protocol check and correction by default): its
  // state while queued or running, then its result's corrected times
  const started = Date.now();
  const step = async () => {
    if (token !== scheduleToken) return;
    const res = await api("GET", `/v1/validations/${encodeURIComponent(vid)}`);
    if (token !== scheduleToken) return;
    if (res.status !== 200) { showServerError(res); return; }
    const v = res.data;
    if (v.status === "failed") {
      $("schedule-status").textContent = "";
      $("schedule-note").textContent = `The schedule job failed: ${v.error || ""}`;
      document.body.dataset.schedule = "failed";
      return;
    }
    if (v.status !== "done") {
      const secs = ((Date.now() - started) / 1000).toFixed(0);
      $("schedule-status").textContent = `${ctx.batch ? "The batch's schedule" : "The schedule's protocol check"} ` +
        `is ${v.status === "pending" ? "queued" : "running"} (job ${vid}, ${secs} s).`;
      document.body.dataset.schedule = v.status === "pending" ? "queued" : "running";
      setTimeout(step, 1000);
      return;
    }
    showSchedule(v.result, ctx);
  };
  step();
}

async function plan(ev) {
  if (ev) ev.preventDefault();
  const f = readForm();
  if (!f) { document.body.dataset.state = "invalid"; return; }
  document.body.dataset.state = "busy";
  $("plan").disabled = true;
  $("busy").textContent = "planning…";
  try {
    await run(f);
  } catch (e) {
    $("form-error").textContent = `The page could not reach the service: ${e}`;
    document.body.dataset.state = "error";
  } finally {
    $("plan").disabled = false;
    $("busy").textContent = "";
  }
}

async function run(f) {
  const total = f.doses.reduce((a, x) => a + x, 0);
  const token = ++scheduleToken;  // an earlier schedule job's poll stops showing
  resetSchedule();
  const [dose, curveRes] = await Promise.all([
    api("POST", "/v1/dose-time", doseBody(f, total, f.validate)),
    api("POST", "/v1/front-curve", { gel: f.gel, t_start: f.t_start, t_end: f.t_end,
      interfacial_length: f.interfacial_length })]);
  if (dose.status >= 400) { showServerError(dose); document.body.dataset.state = "server-error"; return; }
  const curve = curveRes.status === 200 ? curveRes.data : null;
  $("curve-msg").textContent = curve ? "" : (curveRes.data.detail || []).map((d) => d.msg).join("; ");
  if (dose.status === 202) {
    $("answer-panel").hidden = true;
    $("form-error").textContent = "This jump needs the full solver: validating, the answer follows.";
    poll(dose.data.validation_id, () => plan());
    document.body.dataset.state = "pending";
    return;
  }
  const a = dose.data;
  // temperatures written with a unit ("29 degC") come back in K in the answer's request
  const req = a.request || {};
  if (typeof req.t_start === "number") f.t_start = req.t_start;
  if (req.heating && typeof req.heating.t_end === "number") f.t_end = req.heating.t_end;
  const phase = $("phase-map");
  phase.hidden = false;
  const gq = typeof f.gel === "string" ? { base: f.gel } : f.gel;
  phase.src = `/v1/phase-map.svg?${new URLSearchParams({ ...gq, t_start: f.t_start, t_end: f.t_end })}`;
  showAnswer(a, f.doses.length);
  const ref = a.reference_bead || null;  // a batch: a is the batch's own time, ref its mean bead's
  const tau = a.timescale_seconds;
  const ctx = { tau, rests: f.rests.length ? f.rests : [], tStart: f.t_start, tEnd: f.t_end, curve,
    batch: f.size_cv !== undefined || f.size_table !== undefined, drug: f.drug !== undefined };
  let rows = null;
  let answered = null;  // a schedule answered at once (200)
  let job = null;       // a schedule job (202): every batch's, and the correction by default
  if (f.doses.length > 1) {
    // a batch's schedule is the batch's own (its size_distribution kept): always a job
    const body = { ...doseBody(f, undefined, false), doses: f.doses };
    delete body.dose_fraction;
    if (f.rests.length) body.rests = f.rests;
    if (f.rests_seconds) body.rests_seconds = f.rests_seconds;
    const sch = await api("POST", "/v1/schedule", body);
    if (sch.status >= 400) { showServerError(sch); document.body.dataset.state = "server-error"; return; }
    if (sch.status === 200) {
      answered = sch.data;
      rows = scheduleRows(answered);
    } else {
      // a 202 may carry the hold reading, shown as the rough reading it is until the job
      // corrects it (a batch's has none: its hold reading needs every size's run)
      job = sch.data.validation_id;
      rows = sch.data.hold ? scheduleRows({ doses: f.doses, hold: sch.data.hold, reading: "hold" }) : null;
      document.body.dataset.schedule = "queued";
      document.body.dataset.scheduleJob = job;
      document.body.dataset.scheduleBatch = String(ctx.batch);
      const which = f.size_table ? `size table ${f.size_table.name}` : `size CV ${fmt(f.size_cv, 3)}`;
      $("schedule-headline").textContent = ctx.batch ?
        `The batch's schedule (${which}) is queued: every size of the batch ` +
        "runs on the full solver; its corrected times follow." :
        "Queued: the full solver checks and corrects the real heat/rest protocol; the corrected times follow.";
      scheduleAnswerPending(a);
      $("schedule-status").textContent = `queued (job ${job})`;
      $("schedule-note").textContent = rows ?
        "Below, the hold reading (rough: one continuous heating) until the job corrects it." : "";
    }
  } else {
    rows = [{ dose_fraction: a.dose_fraction, cumulative_fraction: a.dose_fraction, start: 0, end: a.time,
      actuation_time: a.time, actuation_seconds: a.seconds, error_estimate: a.error_estimate }];
  }
  if (curve) {
    // the front-model curve is one bead's: a batch marks its mean bead's dose time, and its
    // own time as a dashed line
    const a0 = curve.start_radius;
    const at = (cum) => Math.cbrt(a0 ** 3 - cum * (a0 ** 3 - 1));
    const holdRows = ref ? [] : answered ? scheduleRows({ ...answered, reading: "hold" }) : rows || [];
    const marks = ref ? [{ time: ref.time, radius: at(total), label: `${pct(total)} mean bead` }] :
      holdRows.map((r) => ({ time: r.end, radius: at(r.cumulative_fraction), label: pct(r.cumulative_fraction) }));
    drawCurve(curve, marks, tau, ref ? { time: a.time, label: `batch ${pct(total)}` } : null);
  } else {
    clear($("curve-plot"));
  }
  clear($("timeline-plot"));
  if (answered) {
    showSchedule(answered, ctx);
  } else if (rows) {
    drawTimeline(rows, ctx.rests, f.t_start, f.t_end, tau, ref ? null : curve,
      ref ? "release drawn linearly (a batch: the front-model curve is its mean bead's)" : undefined);
    scheduleTable(rows, f.doses.length > 1 ? "hold" : undefined);
  }
  if (job) pollSchedule(job, ctx, token);
  if (a.validation_id) {
    // once validated, the same request is answered with the full solver's verdict
    poll(a.validation_id, async (v) => {
      if (v.status !== "done") return;
      const again = await api("POST", "/v1/dose-time", doseBody(f, total, false));
      if (again.status !== 200) return;
      showAnswer(again.data, f.doses.length);
      if (f.doses.length === 1) scheduleTable([{ ...rows[0], error_estimate: again.data.error_estimate }]);
      document.body.dataset.validated = v.id;
    });
  }
  document.body.dataset.state = "answered";
}

// ----------------------------------------------------------------------------- design maps

function axis(name, text, b, log, unit) {
  // 'from, to, steps' as the list of values (log: geometric), each within the bounds
  const parts = String(text).split(/[,;\s]+/).filter((p) => p !== "");
  const steps = Number(parts[2]);
  if (parts.length !== 3 || !Number.isInteger(steps) || steps < 1 || steps > b.maxItems)
    return { error: `${LABELS[name]}: give from, to and a number of steps (1-${b.maxItems})` };
  const lo = checkValue(name, parts[0], b, 1, unit);
  if (lo.error) return lo;
  const hi = checkValue(name, parts[1], b, 1, unit);
  if (hi.error) return hi;
  const out = [];
  for (let i = 0; i < steps; i++) {
    const w = steps === 1 ? 0 : i / (steps - 1);
    out.push(log ? Math.exp(Math.log(lo.value) + w * (Math.log(hi.value) - Math.log(lo.value)))
      : lo.value + w * (hi.value - lo.value));
  }
  return { value: out };
}

async function sweep(ev) {
  ev.preventDefault();
  for (const f of SWEEP_FIELDS) { $(`err-${f}`).textContent = ""; $(f).classList.remove("invalid"); }
  $("sweep-error").textContent = "";
  const main = readForm();
  const tEnds = axis("sweep_t_end", $("sweep_t_end").value, bounds.sweep_t_ends, false, "K");
  const radii = axis("sweep_radius", $("sweep_radius").value, bounds.sweep_radii, true, "µm");
  const doses = checkList("sweep_doses", $("sweep_doses").value, bounds.sweep_doses, 100, "%");
  let ok = main !== null;
  for (const [name, r] of [["sweep_t_end", tEnds], ["sweep_radius", radii], ["sweep_doses", doses]]) {
    if (r.error) { showError(name, r.error); ok = false; }
  }
  if (!ok) { document.body.dataset.sweep = "invalid"; return; }
  const body = { gels: [main.gel], t_start: main.t_start, t_ends: tEnds.value,
    dry_radii_um: radii.value, doses: doses.value, interfacial_length: main.interfacial_length };
  const res = await api("POST", "/v1/sweep", body);
  if (res.status !== 202) {
    const detail = res.data && res.data.detail;
    $("sweep-error").textContent = Array.isArray(detail) ?
      detail.map((d) => `${fieldOf(d.loc).name}: ${d.msg}`).join("; ") : `HTTP ${res.status}: ${detail}`;
    document.body.dataset.sweep = "server-error";
    return;
  }
  document.body.dataset.sweep = "running";
  const url = res.data.sweep_url;
  const step = async () => {
    const st = await api("GET", url);
    if (st.status !== 200) { $("sweep-error").textContent = `HTTP ${st.status}`; return; }
    const s = st.data;
    $("sweep-bar").style.width = `${(100 * s.points_done / s.points).toFixed(0)}%`;
    $("sweep-status").textContent = `${s.status}: ${s.points_done} of ${s.points} points`;
    if (s.status === "failed") { $("sweep-error").textContent = s.error; return; }
    if (s.status !== "done") { setTimeout(step, 300); return; }
    const counts = Object.entries(s.result.counts).map(([k, v]) => `${v} ${k}`).join(", ");
    $("sweep-status").textContent = `done: ${counts} in ${fmt(s.result.seconds, 3)} s`;
    $("sweep-links").innerHTML = `Table: <a href="${url}/table.csv" download="sweep.csv">CSV</a> · ` +
      `<a href="${url}" target="_blank">JSON with units</a>`;
    const img = $("sweep-plot");
    img.src = `${url}/plot.svg`;
    img.hidden = false;
    document.body.dataset.sweep = "done";
  };
  step();
}

// ----------------------------------------------------------------------------- saved gels

function savedGels() {
  try { return JSON.parse(localStorage.getItem(SAVED_KEY) || "{}"); } catch (e) { return {}; }
}

function gelSpec() {
  // the request's gel: a preset name, or a saved gel's parameters (GelParameters)
  const v = $("gel").value;
  if (!v.startsWith("saved:")) return v;
  return savedGels()[v.slice(6)] || "ANB";
}

function gelOptions(selected) {
  const sel = $("gel");
  sel.innerHTML = "";
  const add = (value, text, folds) => {
    const o = document.createElement("option");
    o.value = value; o.textContent = text;
    if (folds !== undefined) o.dataset.folds = folds;
    sel.appendChild(o);
  };
  for (const [name, p] of Object.entries(presets)) add(name, name, p.folds);
  for (const [name, p] of Object.entries(fittedGels)) add(name, `${name} (fitted)`, p.folds);
  for (const name of Object.keys(savedGels())) add(`saved:${name}`, `${name} (saved)`);
  if (selected) sel.value = selected;
}

function fillGel(base) {
  const p = presets[base];
  if (!p) return;
  for (const k of GEL_PARAMS) $(`gel_${k}`).value = String(p.gel[k]);
}

function saveGel() {
  for (const f of GEL_FIELDS) { $(`err-${f}`).textContent = ""; $(f).classList.remove("invalid"); }
  const name = $("gel_name").value.trim();
  let ok = true;
  if (!name || Object.keys(presets).includes(name)) {
    showError("gel_name", "gel name: give a name that is not a preset's"); ok = false;
  }
  const spec = { base: $("gel_base").value };
  for (const k of GEL_PARAMS) {
    const r = checkValue(`gel_${k}`, $(`gel_${k}`).value, bounds.gel[k]);
    if (r.error) { showError(`gel_${k}`, r.error); ok = false; } else spec[k] = r.value;
  }
  if (!ok) { document.body.dataset.gel = "invalid"; return; }
  const all = savedGels();
  all[name] = spec;
  localStorage.setItem(SAVED_KEY, JSON.stringify(all));
  gelOptions(`saved:${name}`);
  showFolds();
  document.body.dataset.gel = "saved";
}

function deleteGel() {
  const v = $("gel").value;
  if (!v.startsWith("saved:")) return;
  const all = savedGels();
  delete all[v.slice(6)];
  localStorage.setItem(SAVED_KEY, JSON.stringify(all));
  gelOptions("ANB");
  showFolds();
}

async function showFolds() {
  const o = $("gel").selectedOptions[0];
  if (!o) return;
  if (o.dataset.folds !== undefined) { $("gel-folds").textContent = `folds: ${o.dataset.folds}`; return; }
  const t = Number($("t_start").value);
  const res = await api("POST", "/v1/equilibrium", { gel: gelSpec(), temperature: isFinite(t) ? t : 300 });
  $("gel-folds").textContent = res.status === 200 ?
    `folds: ${res.data.folds.map((x) => `${x.kind} at ${fmt(x.temperature, 5)} K`).join(", ") || "none in 273-373 K"}` :
    "this saved gel is refused by the server: " + JSON.stringify(res.data.detail);
}

async function init() {
  const spec = await (await fetch("/openapi.json")).json();
  const sc = spec.components.schemas;
  const dose = sc.DoseTimeRequest.properties;
  const sched = sc.ScheduleRequest.properties;
  bounds = { t_start: boundOf(dose.t_start), t_end: boundOf(dose.t_end),
    dry_radius_um: boundOf(dose.dry_radius_um), dose_fraction: boundOf(dose.dose_fraction),
    interfacial_length: boundOf(dose.interfacial_length), doses: boundOf(sched.doses),
    size_cv: boundOf(sc.SizeDistributionIn ? sc.SizeDistributionIn.properties.cv : { minimum: 0, maximum: 2 }),
    swollen_radius_um: boundOf(dose.swollen_radius_um),
    drug: Object.fromEntries(Object.entries(sc.DrugIn.properties).map(([k, v]) => [k, boundOf(v)])),
    rests: boundOf(numberSchema(sched.rests).items || {}) };
  const sw = sc.SweepRequest.properties;
  const items = (p) => ({ ...boundOf(p.items), maxItems: p.maxItems });
  bounds.sweep_t_ends = items(sw.t_ends);
  bounds.sweep_radii = items(sw.dry_radii_um);
  bounds.sweep_doses = items(sw.doses);
  for (const name of ["t_start", "t_end", "dry_radius_um", "interfacial_length"]) {
    $(name).title = bounds[name].description || "";
  }
  bounds.gel = Object.fromEntries(GEL_PARAMS.map((k) => [k, boundOf(sc.GelParameters.properties[k])]));
  const gels = await (await fetch("/v1/gels")).json();
  for (const g of gels.gels) {
    presets[g.gel.name] = { gel: g.gel,
      folds: g.folds.map((x) => `${x.kind} at ${fmt(x.temperature, 5)} K`).join(", ") };
  }
  for (const g of gels.fitted || []) {
    fittedGels[g.name] = { gel: g.gel, timescale: g.timescale,
      folds: g.folds.map((x) => `${x.kind} at ${fmt(x.temperature, 5)} K`).join(", ") };
  }
  gelOptions("ANB");
  $("gel").addEventListener("change", showFolds);
  showFolds();
  fillGel($("gel_base").value);
  $("gel_base").addEventListener("change", () => fillGel($("gel_base").value));
  $("save-gel").addEventListener("click", saveGel);
  $("delete-gel").addEventListener("click", deleteGel);
  $("plan-form").addEventListener("submit", plan);
  $("size-file").addEventListener("change", uploadSizes);
  $("size-clear").addEventListener("click", clearSizes);
  $("sweep-form").addEventListener("submit", sweep);
  for (const name of [...FIELDS, ...SWEEP_FIELDS, ...GEL_FIELDS]) {
    $(name).addEventListener("input", () => { $(`err-${name}`).textContent = ""; $(name).classList.remove("invalid"); });
  }
  document.body.dataset.state = "ready";
  document.body.dataset.requests = "0";
}

// ----------------------------------------------------------------------------- protocols

const PROTOCOL_PRESETS = {
  jump: (t1) => [`Hold at ${t1} K`],
  ramp: (t1) => [`Heat to ${t1} K at 5 K/min`],
  bath: (t1) => [`Bath at ${t1} K with a time constant of 30 s`],
};
let protocolTrace = null; // the uploaded trace: {name, csv}

function protocolRows() { return Array.from($("protocol-steps").querySelectorAll("tbody tr")); }

function addStep(text, trace) {
  const body = $("protocol-steps").querySelector("tbody");
  const tr = document.createElement("tr");
  const num = document.createElement("td");
  const cell = document.createElement("td");
  const inp = document.createElement("input");
  inp.type = "text";
  inp.className = "step-text";
  inp.value = text;
  if (trace) { inp.dataset.trace = JSON.stringify(trace); inp.readOnly = true; }
  cell.appendChild(inp);
  const err = document.createElement("span");
  err.className = "err step-err";
  err.setAttribute("role", "alert");
  cell.appendChild(err);
  const rm = document.createElement("td");
  const btn = document.createElement("button");
  btn.type = "button";
  btn.className = "secondary remove-step";
  btn.textContent = "Remove";
  btn.addEventListener("click", () => { tr.remove(); numberSteps(); });
  rm.appendChild(btn);
  tr.append(num, cell, rm);
  body.appendChild(tr);
  numberSteps();
}

function numberSteps() { protocolRows().forEach((tr, i) => { tr.firstChild.textContent = String(i); }); }

function setPreset(name) {
  for (const tr of protocolRows()) tr.remove();
  const t1 = $("t_end").value.trim() || "308";
  for (const step of PROTOCOL_PRESETS[name](t1)) addStep(step);
  document.body.dataset.protocolPreset = name;
}

function readSteps() {
  // the steps as the route takes them: text, or a structured trace
  return protocolRows().map((tr) => {
    const inp = tr.querySelector(".step-text");
    return inp.dataset.trace ? { step: "trace", ...JSON.parse(inp.dataset.trace) } : inp.value.trim();
  });
}

async function uploadTrace(ev) {
  const file = ev.target.files && ev.target.files[0];
  if (!file) return;
  const csv = await file.text();
  for (const tr of protocolRows()) tr.remove();
  protocolTrace = { name: file.name, csv };
  addStep(`Trace from ${file.name}`, protocolTrace);
  document.body.dataset.protocolPreset = "trace";
  ev.target.value = "";
}

function stepOf(loc) {
  // ['body', 'protocol'] or a ParameterError's field 'protocol[2].rate' -> step 2
  const text = (loc || []).join(".");
  const m = /protocol(?:\[|\.)(\d+)/.exec(text);
  return m ? Number(m[1]) : null;
}

function showProtocolError(res) {
  for (const e of document.querySelectorAll(".step-err")) e.textContent = "";
  const detail = res.data && res.data.detail;
  const items = Array.isArray(detail) ? detail : [{ loc: [], msg: String(detail || `HTTP ${res.status}`) }];
  const lines = [];
  for (const item of items) {
    const where = (item.loc || []).filter((p) => p !== "body").join(".");
    const msg = `${where ? where + ": " : ""}${item.msg}`;
    const k = stepOf([where, item.msg]);
    const row = k !== null ? protocolRows()[k] : null;
    if (row) row.querySelector(".step-err").textContent = msg;
    lines.push(msg);
  }
  $("protocol-error").textContent = lines.join("; ");
  document.body.dataset.protocol = "error";
}

function drawProtocol(a) {
  // temperature (left axis) and released fraction (right axis) on one time axis
  const svg = $("protocol-plot");
  clear(svg);
  const c = a.curve;
  const secs = c.seconds && c.seconds.length === c.time.length;
  const t = secs ? c.seconds : c.time;
  const tMax = Math.max(...t) || 1;
  const temps = c.temperature_k;
  const lo = Math.min(...temps) - 0.5;
  const hi = Math.max(...temps) + 0.5;
  const box = { x: 55, y: 12, w: 410, h: 235 };
  const s = panel(svg, box, [0, tMax], [lo, hi], secs ? "time (s)" : "time (units of τ)", "temperature (K)");
  polyline(svg, s, t, temps, { stroke: "#b3261e", id: "protocol-temperature" });
  const sf = { sx: s.sx, sy: (y) => box.y + box.h - y * box.h };
  polyline(svg, sf, t, c.released_fraction, { stroke: "#1f6fb2", id: "protocol-release" });
  const g = el("g", { class: "axis" }, svg);
  for (const v of [0, 0.25, 0.5, 0.75, 1]) {
    el("text", { x: box.x + box.w + 4, y: sf.sy(v) + 4 }, g, `${100 * v} %`);
  }
  const x = s.sx(secs ? a.seconds : a.time);
  el("line", { x1: x, x2: x, y1: box.y, y2: box.y + box.h, stroke: "#333", "stroke-dasharray": "3 3",
    class: "protocol-dose-mark" }, svg);
  legend(svg, 250, 190, [{ color: "#b3261e", label: "temperature T(t)" },
    { color: "#1f6fb2", label: "released fraction" }]);
}

function showProtocolAnswer(a) {
  $("protocol-answer").hidden = false;
  const s = $("protocol-seconds");
  s.textContent = a.seconds !== null && a.seconds !== undefined ? `${fmt(a.seconds)} s` : `${fmt(a.time)} τ`;
  s.dataset.value = a.seconds === null || a.seconds === undefined ? "" : String(a.seconds);
  $("protocol-time").textContent = `(t = ${fmt(a.time)} in units of τ at ${fmt(a.reference_temperature, 5)} K; ${pct(a.dose_fraction)} of the stored fluid)`;
  $("protocol-time").dataset.value = String(a.time);
  // which model answered and why (the slow-heating front model inside its measured region)
  $("protocol-model").textContent = a.model_reason ? `${a.model}: ${a.model_reason}` : a.model;
  $("protocol-model").dataset.value = a.model;
  $("protocol-text").textContent = a.protocol.join("; ");
  $("protocol-untils").textContent = a.until_steps.length ? a.until_steps.map((u) =>
    `step ${u.step} ends at ${u.end_seconds !== null ? fmt(u.end_seconds) + " s" : fmt(u.end) + " τ"}`).join("; ") : "none";
  $("protocol-program").textContent = `${a.program}. ${a.reference}.`;
  $("protocol-error-text").textContent = a.error_explanation;
  drawProtocol(a);
}

async function planProtocol() {
  clearErrors();
  $("protocol-error").textContent = "";
  for (const e of document.querySelectorAll(".step-err")) e.textContent = "";
  const f = { gel: gelSpec() };
  const t0 = checkQuantity("t_start", $("t_start").value, bounds.t_start, "K");
  const doses = checkList("doses", $("doses").value, { ...bounds.dose_fraction, maxItems: 1000 }, 100, "%");
  if (t0.error) { showError("t_start", t0.error); document.body.dataset.protocol = "invalid"; return; }
  if (doses.error || !doses.value.length) {
    showError("doses", doses.error || "dose: give one"); document.body.dataset.protocol = "invalid"; return;
  }
  const steps = readSteps();
  if (!steps.length || steps.some((x) => x === "")) {
    $("protocol-error").textContent = "protocol: give at least one step, none empty";
    document.body.dataset.protocol = "invalid";
    return;
  }
  const body = { gel: f.gel, t_start: t0.value, dose_fraction: doses.value[0], protocol: steps };
  if ($("dry_radius_um").value.trim() !== "") {
    const r = $("dry_radius_um").value.trim();
    body[$("size_kind").value === "swollen" ? "swollen_radius_um" : "dry_radius_um"] = hasUnit(r) ? r : Number(r);
  }
  if ($("interfacial_length").value.trim() !== "") body.interfacial_length = Number($("interfacial_length").value);
  document.body.dataset.protocol = "busy";
  $("plan-protocol").disabled = true;
  try {
    for (let round = 0; round < 20; round++) {
      $("protocol-status").textContent = round ? `full-solver runs, round ${round + 1}…` : "planning…";
      const res = await api("POST", "/v1/dose-time", body);
      if (res.status === 200) {
        showProtocolAnswer(res.data);
        $("protocol-status").textContent = "";
        document.body.dataset.protocol = "answered";
        return;
      }
      if (res.status !== 202) { showProtocolError(res); $("protocol-status").textContent = ""; return; }
      const vid = res.data.validation_id;
      for (;;) {
        await new Promise((r) => setTimeout(r, 1000));
        const v = await api("GET", `/v1/validations/${encodeURIComponent(vid)}`);
        if (v.status !== 200) { showProtocolError(v); return; }
        if (v.data.status === "failed") {
          $("protocol-error").textContent = `the full-solver run failed: ${v.data.error}`;
          document.body.dataset.protocol = "error";
          return;
        }
        if (v.data.status === "done") break;
      }
    }
    $("protocol-error").textContent = "the protocol needed more rounds of runs than expected";
    document.body.dataset.protocol = "error";
  } catch (e) {
    $("protocol-error").textContent = `The page could not reach the service: ${e}`;
    document.body.dataset.protocol = "error";
  } finally {
    $("plan-protocol").disabled = false;
  }
}

function initProtocol() {
  for (const name of Object.keys(PROTOCOL_PRESETS)) $(`preset-${name}`).addEventListener("click", () => setPreset(name));
  $("add-step").addEventListener("click", () => addStep(""));
  $("trace-file").addEventListener("change", uploadTrace);
  $("plan-protocol").addEventListener("click", planProtocol);
  setPreset("ramp");
}

initProtocol();

init().catch((e) => { $("form-error").textContent = `The page could not load the service's bounds: ${e}`; });
