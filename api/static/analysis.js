// thermogel release analysis page (issue 38): reads CSV files in the browser and sends their
// text to POST /v1/fit/empirical (a job, polled) and POST /v1/compare; plain JS, no build.
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2"];

function esc(text) {
  const d = document.createElement("div");
  d.textContent = String(text);
  return d.innerHTML;
}

function fmt(x, digits = 4) {
  if (x === null || x === undefined) return "-";
  return Number(x).toPrecision(digits);
}

function readFile(input) {
  return new Promise((resolve, reject) => {
    const f = input.files && input.files[0];
    if (!f) { reject(new Error(`choose a CSV file (${input.id})`)); return; }
    const r = new FileReader();
    r.onload = () => resolve(r.result);
    r.onerror = () => reject(new Error(`could not read ${f.name}`));
    r.readAsText(f);
  });
}

function errorText(body, status) {
  if (body && Array.isArray(body.detail)) return body.detail.map((d) => d.msg).join("; ");
  if (body && body.detail) return String(body.detail);
  return `HTTP ${status}`;
}

async function post(url, payload) {
  const r = await fetch(url, { method: "POST", headers: { "content-type": "application/json" },
                               body: JSON.stringify(payload) });
  const body = await r.json().catch(() => null);
  if (!r.ok && r.status !== 202) throw new Error(errorText(body, r.status));
  return body;
}

async function poll(url) {
  for (;;) {
    const r = await fetch(url);
    const body = await r.json();
    if (!r.ok) throw new Error(errorText(body, r.status));
    if (body.status === "done") return body.result;
    if (body.status === "failed") throw new Error(body.error || "the job failed");
    await new Promise((res) => setTimeout(res, 300));
  }
}

function el(name, attrs, parent) {
  const e = document.createElementNS(SVGNS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

// a plot frame: x in [0, xmax], y in [0, 105] %; returns the mapping functions
function frame(svg, xmax, xlabel) {
  svg.innerHTML = "";
  const W = 520, H = 320, L = 50, R = 10, T = 10, B = 40;
  const sx = (x) => L + (W - L - R) * x / xmax;
  const sy = (y) => H - B - (H - T - B) * y / 105;
  el("rect", { x: L, y: T, width: W - L - R, height: H - T - B, fill: "none", stroke: "#ccc" }, svg);
  const clip = el("clipPath", { id: `${svg.id}-clip` }, el("defs", {}, svg));
  el("rect", { x: L, y: T, width: W - L - R, height: H - T - B }, clip);
  for (const y of [0, 25, 50, 75, 100]) {
    el("line", { x1: L, x2: W - R, y1: sy(y), y2: sy(y), stroke: "#eee" }, svg);
    el("text", { x: L - 6, y: sy(y) + 4, "text-anchor": "end", "font-size": 11 }, svg).textContent = y;
  }
  for (let k = 0; k <= 4; k++) {
    const x = xmax * k / 4;
    el("text", { x: sx(x), y: H - B + 16, "text-anchor": "middle", "font-size": 11 }, svg)
      .textContent = String(Number(x.toPrecision(3)));
  }
  el("text", { x: (L + W - R) / 2, y: H - 6, "text-anchor": "middle", "font-size": 12 }, svg)
    .textContent = xlabel;
  el("text", { x: 14, y: (T + H - B) / 2, "text-anchor": "middle", "font-size": 12,
               transform: `rotate(-90 14 ${(T + H - B) / 2})` }, svg).textContent = "released (%)";
  return { sx, sy, clip: `url(#${svg.id}-clip)`, legendX: L + 8, legendY: T + 14 };
}

function legend(svg, m, k, text, color) {
  el("text", { x: m.legendX + 205, y: m.legendY + 14 * k + 150, "font-size": 11,
               style: `fill: ${color}` }, svg).textContent = text;
}

function polyline(svg, xs, ys, m, attrs) {
  const pts = xs.map((x, i) => `${m.sx(x).toFixed(1)},${m.sy(ys[i]).toFixed(1)}`).join(" ");
  return el("polyline", { points: pts, fill: "none", "clip-path": m.clip, ...attrs }, svg);
}

function band(svg, xs, mean, sd, m, color) {
  if (!sd) return;
  const up = xs.map((x, i) => `${m.sx(x).toFixed(1)},${m.sy(mean[i] + sd[i]).toFixed(1)}`);
  const dn = xs.map((x, i) => `${m.sx(x).toFixed(1)},${m.sy(mean[i] - sd[i]).toFixed(1)}`).reverse();
  el("polygon", { points: up.concat(dn).join(" "), fill: color, "fill-opacity": 0.18,
                  "clip-path": m.clip }, svg);
}

function dots(svg, xs, ys, m, color) {
  xs.forEach((x, i) => el("circle", { cx: m.sx(x), cy: m.sy(ys[i]), r: 3, fill: color }, svg));
}

function showEmpirical(rep) {
  const rows = Object.entries(rep.models).map(([name, f]) => {
    const pars = Object.entries(f.parameters).map(([p, v]) => {
      const iv = f.intervals[p];
      return `${esc(p)} = ${fmt(v)} ${esc(f.units[p])}` +
        (iv ? ` [${fmt(iv[0], 3)}, ${fmt(iv[1], 3)}]` : "");
    }).join("<br>");
    const mech = f.interpretation ? `<br><em>${esc(f.interpretation.mechanism)}</em>` : "";
    const tag = name === rep.best ? " (best)" : (f.delta_aic === null ? " (60 % window)" : "");
    return `<tr class="${name === rep.best ? "best" : ""}" data-model="${esc(name)}">` +
      `<td class="l">${esc(f.title)}${tag}</td><td>${fmt(f.aic)}</td><td>${fmt(f.r2_adjusted, 5)}</td>` +
      `<td>${fmt(f.msc)}</td><td class="l">${pars}${mech}</td></tr>`;
  }).join("");
  const errs = Object.entries(rep.errors).map(([n, e]) => `<li>${esc(n)}: ${esc(e)}</li>`).join("");
  $("emp-result").innerHTML =
    `<p id="emp-best">best by AIC: <strong>${esc(rep.best)}</strong>; times in ${esc(rep.time_unit)}` +
    `${rep.weighted ? ", weighted by the units' spread" : ""}</p>` +
    `<table><tr><th class="l">model</th><th>AIC</th><th>R&sup2; adj</th><th>MSC</th>` +
    `<th class="l">parameters (95 %)</th></tr>${rows}</table>` + (errs ? `<ul>${errs}</ul>` : "");
  const p = rep.profile;
  const xmax = Math.max(...p.time);
  const svg = $("emp-plot");
  const m = frame(svg, xmax, `time (${rep.time_unit})`);
  band(svg, p.time, p.mean_percent, p.sd_percent, m, "#000");
  Object.entries(rep.models).forEach(([name, f], k) => {
    const color = COLORS[k % COLORS.length];
    polyline(svg, f.curve_time, f.curve, m, { stroke: color,
                                               "stroke-width": name === rep.best ? 2.5 : 1 });
    legend(svg, m, k, f.title + (name === rep.best ? " (best)" : ""), color);
  });
  dots(svg, p.time, p.mean_percent, m, "#000");
}

function showComparison(c, time) {
  const conds = Object.values(c.conditions).map((x) =>
    `<li>${x.met ? "met" : "<strong>not met</strong>"}: ${esc(x.rule)}</li>`).join("");
  const b = c.bootstrap;
  $("cmp-result").innerHTML =
    `<p id="cmp-f2">${esc(c.outcome)}</p><p>${esc(c.f1_outcome)}</p>` +
    `<p>${esc(c.notes[0])}</p><ul>${conds}</ul>` +
    `<p id="cmp-boot-out">${b ? esc(b.outcome) : "no bootstrap: no replicate units"}</p>`;
  const svg = $("cmp-plot");
  const m = frame(svg, Math.max(...time), `time (${c.time_unit})`);
  const sides = [[c.reference, "#1f77b4", "reference"], [c.test, "#d62728", "test"]];
  for (const [k, [side, color, who]] of sides.entries()) {
    legend(svg, m, k, `${who}: mean, +- 1 SD of ${side.n_units} units`, color);
    band(svg, time, side.mean_percent, side.sd_percent, m, color);
    polyline(svg, time, side.mean_percent, m, { stroke: color, "stroke-width": 2 });
    dots(svg, time, side.mean_percent, m, color);
  }
}

async function run(prefix, work) {
  $(`${prefix}-error`).textContent = "";
  $(`${prefix}-status`).textContent = "working...";
  $(`${prefix}-go`).disabled = true;
  document.body.dataset[prefix] = "busy";
  try {
    await work();
    document.body.dataset[prefix] = "done";
  } catch (e) {
    $(`${prefix}-error`).textContent = e.message;
    document.body.dataset[prefix] = "error";
  } finally {
    $(`${prefix}-status`).textContent = "";
    $(`${prefix}-go`).disabled = false;
  }
}

$("emp-go").addEventListener("click", () => run("emp", async () => {
  const csv = await readFile($("emp-file"));
  const loaded = $("emp-loaded").value.trim();
  const body = { csv, lag: $("emp-lag").checked };
  if (loaded) body.loaded_ug = Number(loaded);
  const job = await post("/v1/fit/empirical", body);
  showEmpirical(await poll(job.status_url));
}));

$("cmp-go").addEventListener("click", () => run("cmp", async () => {
  const [ref, test] = await Promise.all([readFile($("cmp-ref")), readFile($("cmp-test"))]);
  const c = await post("/v1/compare", { reference: { csv: ref }, test: { csv: test },
                                        n_boot: Number($("cmp-boot").value),
                                        seed: Number($("cmp-seed").value) });
  showComparison(c, c.reference.time);
}));
