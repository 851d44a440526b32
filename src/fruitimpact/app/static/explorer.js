// The explorer: controls → /api/explore → plots, characteristics, verdict, safe height, command.
"use strict";

const form = document.getElementById("controls");
const statusLine = document.getElementById("status");
const slider = document.getElementById("height-slider");
const HEIGHT_MIN = 0.005, HEIGHT_MAX = 2.0;  // the slider's range [m], logarithmic
const G = 9.80665;
let options = null, last = null, sequence = 0, timer = null;
// What a test or a curious user can read: the last update's latency [ms] (control changed → page drawn).
window.fruitimpact = {updates: 0, latency: null, last: null};

const heightOf = (position) => HEIGHT_MIN * Math.pow(HEIGHT_MAX / HEIGHT_MIN, position / 1000);
const positionOf = (height) => 1000 * Math.log(height / HEIGHT_MIN) / Math.log(HEIGHT_MAX / HEIGHT_MIN);
// a length in the unit that suits it, to 3 digits (rounded first: 0.99999 m is "1 m", not "100 cm")
const lengthText = (h) => {
  const r = Number(h.toPrecision(3));
  return r >= 1 ? `${fmt(r, 3)} m` : r >= 0.01 ? `${fmt(r * 100, 3)} cm` : `${fmt(r * 1000, 3)} mm`;
};

function describe(kind) {
  const name = form.elements[kind].value;
  const item = options[kind === "fruit" ? "fruits" : "surfaces"].find((entry) => entry.name === name);
  document.getElementById(`${kind}-description`).textContent = item ? item.description : "";
}

let currentMode = "velocity";  // how the impact is given: "velocity" or "drop_height"
function mode() { return currentMode; }

// The request: only what differs from `fruitimpact simulate`'s defaults, so that its command is the CLI's own.
function request() {
  const out = {};
  const controls = options.controls;
  for (const name of ["fruit", "surface", "model", "calibration", "criterion"]) {
    const value = form.elements[name].value;
    if (value !== String(controls[name].default)) out[name] = value;
  }
  for (const name of ["mass", "diameter", "modulus", "poisson", "failure_stress", "bruise_energy", "restitution"]) {
    const value = form.elements[name].value.trim();
    if (value) out[name] = value;
  }
  if (mode() === "velocity") {
    const value = form.elements.velocity.value.trim();
    if (value && value !== "1") out.velocity = value;
  } else {
    out.drop_height = form.elements.drop_height.value.trim();
  }
  return out;
}

function clearErrors() {
  for (const node of form.querySelectorAll(".field-error")) node.remove();
  for (const node of form.querySelectorAll(".invalid")) node.classList.remove("invalid");
  document.getElementById("form-error").hidden = true;
}

function showError(message, argument) {
  const names = Array.isArray(argument) ? argument : [argument];
  const control = names.map((name) => form.querySelector(`[data-input="${name}"]`)).find(Boolean);
  document.querySelector(".results").classList.add("stale");
  if (control) {
    const closed = control.closest("details:not([open])");
    if (closed) closed.open = true;  // an error inside folded controls must be seen
    control.classList.add("invalid");
    const note = document.createElement("p");
    note.className = "field-error";
    note.setAttribute("role", "alert");
    note.textContent = message;
    (control.closest("label") || control).after(note);
  } else {
    const box = document.getElementById("form-error");
    box.textContent = message;
    box.hidden = false;
  }
  statusLine.textContent = "input refused";
}

function schedule(delay = 60) {
  clearTimeout(timer);
  const started = performance.now();
  timer = setTimeout(() => update(started), delay);
}

async function update(started) {
  const mine = ++sequence;
  statusLine.textContent = "computing…";
  let status, body;
  try {
    [status, body] = await postJSON("/api/explore", request());
  } catch (error) {
    if (mine === sequence) statusLine.textContent = `the server did not answer (${error})`;
    return;
  }
  if (mine !== sequence) return;  // a newer request is on its way
  clearErrors();
  if (status !== 200 || body.refused) {
    showError(body.error, body.argument);
    return;
  }
  last = body;
  document.querySelector(".results").classList.remove("stale");
  render(body);
  const latency = performance.now() - started;
  window.fruitimpact.updates += 1;
  window.fruitimpact.latency = latency;
  window.fruitimpact.last = body;
  statusLine.textContent = `${body.status === "ok" ? "ok" : body.status}: updated in ${latency.toFixed(0)} ms`;
}

function render(result) {
  const curves = result.curves;
  if (curves) {
    const ms = curves.time.map((t) => t * 1e3), mm = curves.deflection.map((d) => d * 1e3);
    Charts.line(document.getElementById("chart-ft"), {series: [{x: ms, y: curves.force, color: "#2f6f4f"}], xLabel: "time t [ms]", yLabel: "force F [N]", xMin: 0});
    Charts.line(document.getElementById("chart-fd"), {series: [{x: mm, y: curves.force, color: "#8a4b9c"}], xLabel: "deflection δ [mm]", yLabel: "force F [N]", xMin: 0});
    Charts.line(document.getElementById("chart-dt"), {series: [{x: ms, y: mm, color: "#2b5f9e"}], xLabel: "time t [ms]", yLabel: "deflection δ [mm]", xMin: 0});
  }
  renderBounces(result);
  renderVerdict(result);
  const rows = result.characteristics.map((c) => {
    const tr = document.createElement("tr");
    tr.dataset.name = c.name;
    tr.innerHTML = "<td class=label></td><td class=value></td><td class=unit></td>";
    tr.children[0].textContent = c.label;
    tr.children[1].textContent = fmt(c.value, 5);
    tr.children[2].textContent = c.name === "law_stiffness" ? result.law.stiffness_unit : c.name === "damping" ? result.law.damping_unit : c.unit;
    return tr;
  });
  document.querySelector("#characteristics tbody").replaceChildren(...rows);
  const dropWarnings = result.drop && result.drop.warnings ? result.drop.warnings.filter((w) => !result.warnings.includes(w)) : [];
  const warnings = [...result.warnings, ...(result.status !== "ok" ? [`${result.status}: ${result.message}`] : []),
    ...dropWarnings.map((w) => `drop: ${w}`)];
  document.getElementById("warnings").replaceChildren(...warnings.map((text) => Object.assign(document.createElement("li"), {textContent: text})));
  document.getElementById("command").textContent = result.command;
  document.getElementById("drop-command").textContent = result.drop && result.drop.command ? result.drop.command : "";
  slider.value = positionOf(Math.min(Math.max(result.drop_height, HEIGHT_MIN), HEIGHT_MAX));  // the slider is the height
}

// The fruit's height between impacts: each flight a parabola from the exit speed, up to the rest.
function renderBounces(result) {
  const svg = document.getElementById("chart-bounce");
  const drop = result.drop;
  const caption = document.getElementById("bounce-caption");
  if (!drop || drop.error) {
    caption.textContent = `bounce sequence: ${drop ? drop.error : "no drop"}`;
    Charts.line(svg, {series: [], xLabel: "time [s]", yLabel: "height [cm]", empty: "no bounce sequence (see above)"});
    return;
  }
  const x = [], y = [];
  const h0 = result.drop_height, t1 = drop.impacts.length ? drop.impacts[0].time : 0;
  for (let i = 0; i <= 40; i++) { const t = t1 * i / 40; x.push(t); y.push((h0 - 0.5 * G * t * t) * 100); }
  for (const impact of drop.impacts) {
    const v = impact.exit_velocity, flight = 2 * v / G;
    for (let i = 0; i <= 30; i++) { const t = flight * i / 30; x.push(impact.time + t); y.push(Math.max(0, (v * t - 0.5 * G * t * t) * 100)); }
  }
  // every impact that bruises is marked; the first mark says how many
  const bruising = drop.impacts.filter((impact) => impact.bruised);
  const markers = bruising.map((impact, i) => ({x: impact.time, label: i ? "" : `${bruising.length} bruising impact${bruising.length > 1 ? "s" : ""}`}));
  Charts.line(svg, {series: [{x, y, color: "#9a5b00"}], xLabel: "time [s]", yLabel: "height [cm]", xMin: 0, yMin: 0, markers});
  const end = drop.status === "ok" && !drop.warnings.length ? `at rest after ${fmt(drop.rest_time, 3)} s` : `${drop.status}, see the warnings`;
  caption.textContent = `bounce sequence: ${drop.impacts.length} impacts from ${lengthText(h0)}, ${end}`;
}

function renderVerdict(result) {
  const box = document.getElementById("verdict");
  const parts = [];
  const verdict = result.verdict;
  const item = (label, html) => `<div class="item"><span>${label}</span>${html}</div>`;
  if (verdict) {
    const bruised = verdict.bruised;
    const word = bruised === null ? "no verdict" : bruised ? "bruised" : "no bruise";
    const kind = bruised === null ? "neutral" : bruised ? "bruised" : "sound";
    parts.push(item(`criterion ${verdict.criterion}`, `<b class="big ${kind}" id="verdict-word">${word}</b>`));
    parts.push(item("bruise margin", `<b id="verdict-margin">${verdict.margin === null ? "–" : (verdict.margin >= 0 ? "+" : "") + fmt(verdict.margin * 100, 3) + " %"}</b>`));
    parts.push(item("bruise volume", `<b>${verdict.volume === null ? "–" : fmt(verdict.volume * 1e9, 3) + " mm³"}</b>`));
  } else {
    parts.push(item("bruise", `<b class="big neutral" id="verdict-word">no criterion</b>`));
    parts.push(item("", "choose a bruise criterion to judge damage and find the safe height"));
  }
  const safe = result.safe_height;
  const mark = document.getElementById("safe-mark");
  if (safe && !safe.error && safe.height !== null) {
    parts.push(item("safe drop height", `<b id="safe-height">${lengthText(safe.height)}</b>`));
    const position = positionOf(Math.min(Math.max(safe.height, HEIGHT_MIN), HEIGHT_MAX));
    mark.style.left = `calc(${position / 10}% - 1px)`;
    mark.hidden = false;
  } else {
    mark.hidden = true;
    if (safe && safe.error) parts.push(item("safe drop height", `<b>–</b>`));
  }
  parts.push(item("impact", `<b>V = ${fmt(result.velocity, 4)} m/s (h = ${lengthText(result.drop_height)})</b>`));
  box.innerHTML = parts.join("");
}

async function risk() {
  const button = document.getElementById("risk-button");
  button.disabled = true;
  button.textContent = "computing…";
  try {
    const [status, body] = await postJSON("/api/risk", request());
    const svg = document.getElementById("chart-risk");
    if (status !== 200 || body.refused) { clearErrors(); showError(body.error, body.argument); return; }
    svg.removeAttribute("hidden");  // an SVG element has no `hidden` property
    const heights = body.heights, logs = heights.map(Math.log);
    const position = (h) => (Math.log(h) - logs[0]) / (logs[logs.length - 1] - logs[0]) * (heights.length - 1) + 0.5;
    const rowTicks = [0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2].filter((h) => h >= heights[0] && h <= heights[heights.length - 1]).map((h) => [position(h), lengthText(h)]);
    Charts.heat(svg, {columns: body.columns, rows: heights.map(lengthText), values: body.incidence, share: true,
      safe: body.columns.map((c) => body.safe_height[c]), position, rowTicks,
      xLabel: `surface: share of ${body.lot.rows} fruit bruised (— safe height of the typical fruit)`, yLabel: "drop height"});
  } finally {
    button.disabled = false;
    button.textContent = "compute (height × surface)";
  }
}

async function exportAs(kind) {
  if (!last) return;
  const charts = ["chart-ft", "chart-fd", "chart-dt", "chart-bounce", "chart-risk"].map((id) => document.getElementById(id)).filter((svg) => !svg.hasAttribute("hidden") && svg.firstChild);
  if (kind === "svg") for (const svg of charts) download(`${svg.id}.svg`, new Blob([Charts.serialize(svg)], {type: "image/svg+xml"}));
  if (kind === "png") for (const svg of charts) download(`${svg.id}.png`, await Charts.png(svg));
  if (kind === "json") download("impact.json", new Blob([JSON.stringify(last, null, 2)], {type: "application/json"}));
  if (kind === "csv" && last.curves) {
    const c = last.curves;
    const lines = ["time_s,deflection_m,force_N", ...c.time.map((t, i) => `${t},${c.deflection[i]},${c.force[i]}`)];
    download("curves.csv", new Blob([lines.join("\n") + "\n"], {type: "text/csv"}));
  }
}

function setMode(value) {
  if (last && value !== currentMode) {  // carry the impact over: the same impact, given the other way
    if (value === "velocity") form.elements.velocity.value = String(Number(last.velocity.toPrecision(4)));
    else form.elements.drop_height.value = lengthText(last.drop_height).replace(" ", "");
  }
  currentMode = value;
  form.querySelector(`input[name=mode][value=${value}]`).checked = true;
  document.getElementById("velocity-control").hidden = value !== "velocity";
  document.getElementById("height-control").hidden = value !== "drop_height";
}

async function start() {
  const response = await fetch("/api/options");
  options = await response.json();
  const controls = options.controls;
  fill(form.elements.fruit, options.fruits, controls.fruit.default);
  fill(form.elements.surface, options.surfaces, controls.surface.default);
  fill(form.elements.model, options.models, controls.model.default);
  fill(form.elements.calibration, options.calibrations, controls.calibration.default);
  fill(form.elements.criterion, options.criteria, controls.criterion.default);
  describe("fruit");
  describe("surface");
  document.getElementById("height-scale").replaceChildren(...[0.005, 0.05, 0.5, 2].map((h) => {
    const label = Object.assign(document.createElement("span"), {textContent: lengthText(h)});
    label.style.left = `${positionOf(h) / 10}%`;  // where the log slider puts that height
    return label;
  }));
  form.addEventListener("input", (event) => {
    if (event.target === slider) return;
    if (event.target.name === "mode") setMode(event.target.value);
    document.getElementById("chart-risk").setAttribute("hidden", "");  // drawn for other inputs
    if (event.target.name === "fruit" || event.target.name === "surface") describe(event.target.name);
    schedule(event.target.tagName === "INPUT" && event.target.type !== "radio" ? 120 : 10);  // typing: a pause
  });
  form.addEventListener("submit", (event) => { event.preventDefault(); schedule(0); });
  slider.addEventListener("input", () => {
    setMode("drop_height");
    form.elements.drop_height.value = lengthText(heightOf(Number(slider.value))).replace(" ", "");
    schedule(30);
  });
  document.getElementById("risk-button").addEventListener("click", risk);
  for (const button of document.querySelectorAll("[data-export]")) button.addEventListener("click", () => exportAs(button.dataset.export));
  window.addEventListener("resize", () => last && render(last));
  schedule(0);
}

start();
