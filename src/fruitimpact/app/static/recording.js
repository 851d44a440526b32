// The recording page: upload → /api/recording (the analysis of `fruitimpact analyze`) → overview, histogram,
// classes, impacts table; a click on an impact → /api/impact (its samples and the fitted model).
"use strict";

const form = document.getElementById("controls");
const statusLine = document.getElementById("status");
const results = document.getElementById("results");
// neighbouring lanes in colours told apart in thin traces (the first two were a dark green and a dark blue)
const LANE_COLORS = ["#2b5d9b", "#c4640a", "#2f6f4f", "#b3261e", "#7a3e9d", "#4d7f8c", "#6b6b2f", "#8c4d6b"];
const CLASS_COLORS = ["#c98b2b", "#6f9f5f", "#2f6f4f", "#2b5d9b", "#7a3e9d", "#444"];
const SHOWN_ROWS = 2000;  // rows drawn in the table (the CSV has them all)
let upload = null, last = null, selected = null, sequence = 0, timer = null, limit = 200 * 1024 * 1024;
// What a test or a curious user can read: analyses done, the last answer, the impact drawn.
window.fruitimpact = {analyses: 0, last: null, impact: null};


// The table's columns: key, heading, scale to the unit shown.
const COLUMNS = [
  // the status beside the contact's number: a flag must be seen without scrolling the table sideways
  ["#", "#", null], ["lane", "lane", null], ["status", "status", null], ["start_time", "start [s]", 1],
  ["peak_force", "F_max [N]", 1], ["time_to_peak", "t_c [ms]", 1e3], ["contact_duration", "T [ms]", 1e3],
  ["firmness_c", "C [N/s]", 1], ["firmness_c_star", "C* [N/s²]", 1], ["stiffness", "k [N/m^1.5]", 1],
  ["restitution", "e", 1], ["mass", "m [g]", 1e3], ["class", "class", null], ["rebound_of", "rebound of", null],
];

function inputs() {
  const out = {};
  for (const element of form.querySelectorAll("[data-input]")) {
    const name = element.dataset.input;
    if (element.type === "checkbox") { out[name] = element.checked; continue; }
    const value = element.value.trim();
    if (value) out[name] = value;
  }
  return out;
}

const clearErrors = () => clearFormErrors(form);

// A refusal: the CLI's line next to its control, the last results kept, pale.
function refuse(body) {
  showRefusal(form, body);
  results.classList.toggle("stale", last !== null);
  if (last === null) document.getElementById("summary").textContent = "Refused: the reason is next to its control on the left.";
  statusLine.textContent = "refused: see the form";
}

// The answer, or a refusal when the server answered with an HTTP error.
async function post(path, body) {
  const [status, answer] = await postJSON(path, body);
  if (!(status >= 200 && status < 300)) return {refused: true, error: answer.error || `the server answered ${status}`, argument: null};
  return answer;
}

async function send(file) {
  clearErrors();
  upload = null;
  statusLine.textContent = `uploading ${file.name} (${mb(file.size)})…`;
  const answer = await uploadFile(file, limit);
  if (answer.refused) return refuse(answer);
  upload = answer;
  analyse();
}

async function analyse() {
  if (!upload) return;
  const mine = ++sequence;
  const began = performance.now();
  statusLine.textContent = `analysing ${upload.file}…`;
  const answer = await post("/api/recording", {upload: upload.upload, ...inputs()});
  if (mine !== sequence) return;  // a later request supersedes this one
  if (answer.refused) return refuse(answer);
  clearErrors();
  results.classList.remove("stale");
  last = answer;
  selected = null;
  draw(answer);
  window.fruitimpact.analyses += 1;
  window.fruitimpact.last = answer;
  window.fruitimpact.impact = null;  // the impact shown before belongs to the replaced analysis
  statusLine.textContent = `${answer.contacts} contacts analysed in ${((performance.now() - began) / 1000).toFixed(1)} s`;
  if (answer.impacts.length) show(firstFruit(answer));
}

function firstFruit(answer) {
  const k = answer.impacts.findIndex((row) => !row.rebound && row.status === "ok");
  return k >= 0 ? k : 0;
}

// The sensor discharge each lane measured and restored (--discharge-time auto), when any did.
function discharge(a, item) {
  const measured = Object.entries(a.discharge || {}).filter(([, tau]) => tau !== null);
  if (!measured.length) return "";
  const text = measured.map(([lane, tau]) => (a.lanes.length > 1 ? `${escapeText(lane)} ` : "") + `${fmt(tau, 3)} s`);
  return item("sensor discharge τ (measured)", text.join(", "));
}

function draw(a) {
  const summary = document.getElementById("summary");
  const item = (label, value) => `<div class="item"><span>${label}</span><b>${value}</b></div>`;
  summary.innerHTML = item("file", escapeText(a.file)) + item("lanes", a.lanes.length) +
    item("duration", `${fmt(a.duration, 4)} s at ${fmt(a.rate / 1000, 4)} kHz`) +
    item("fruit", `<span class="big">${a.fruit}</span>`) + item("rebounds", a.rebounds) + item("contacts", a.contacts) +
    item("mains hum removed", a.hum ? `${fmt(a.hum, 3)} Hz` : "none") + discharge(a, item);
  drawOverview(a);
  drawHistogram(a);
  drawTable(a);
  document.getElementById("command").textContent = a.command;
}

function escapeText(text) {
  const node = document.createElement("span");
  node.textContent = text;
  return node.innerHTML;
}

function drawOverview(a) {
  const o = a.overview, series = [];
  a.lanes.forEach((name, k) => {
    const lane = o.lanes[name];
    if (!lane) return;
    const color = LANE_COLORS[k % LANE_COLORS.length];
    series.push({x: o.time, y: lane.high, color, label: a.lanes.length > 1 ? name : ""});
    series.push({x: o.time, y: lane.low, color});
  });
  const markers = a.impacts.length <= 400 ? a.impacts.filter((row) => !row.rebound).map((row) => ({x: row.start_time, label: "", color: "#c9ced4"})) : [];
  Charts.line(document.getElementById("chart-overview"), {series, markers, xLabel: "time [s]", yLabel: "force [N]", empty: "no samples"});
}

function drawHistogram(a) {
  const h = a.histogram;
  const label = {firmness_c_star: "firmness C* [N/s²]", firmness_c: "firmness C [N/s]", peak_force: "peak force [N]",
                 stiffness: "fitted stiffness", modulus: "fitted modulus [Pa]"}[h.index] || h.index;
  document.getElementById("histogram-caption").textContent = h.fruit === a.fruit
    ? `${label} of the ${a.fruit} fruit (first contacts; rebounds left out)`
    : `${label} of ${h.fruit} of the ${a.fruit} fruit (the others, overlaps and clipped contacts, have none)`;
  const classOf = (x) => h.thresholds.filter((t) => x >= t).length;
  const colors = h.thresholds.length ? h.edges.slice(0, -1).map((e, i) => CLASS_COLORS[classOf((e + h.edges[i + 1]) / 2) % CLASS_COLORS.length]) : null;
  Charts.histogram(document.getElementById("chart-histogram"), {
    edges: h.edges, counts: h.counts, colors, xLabel: label, yLabel: "fruit",
    markers: h.thresholds.map((t, i) => ({x: t, label: `${a.class_names[i]} | ${a.class_names[i + 1]}`})),
    empty: "no fruit with this index",
  });
  const body = document.querySelector("#classes tbody");
  body.replaceChildren(...a.class_names.map((name) => {
    const row = document.createElement("tr");
    const count = a.classes[name] || 0;
    row.innerHTML = `<td>${escapeText(name)}</td><td class="value">${count}</td><td class="unit">${a.fruit ? fmt(100 * count / a.fruit, 3) : "–"} %</td>`;
    return row;
  }));
}

// rebound_of is the parent's sequence number in its lane: the table shows the parent's row number (#)
let rowOf = new Map();
const parentRow = (row) => rowOf.get(`${row.lane}\u0000${row.rebound_of}`);

function cell(row, key, scale, index) {
  if (key === "#") return String(index + 1);
  const value = row[key];
  // a rebound whose parent was not measured as it was (rebound_of null): said, not left blank like a fruit's
  if (key === "rebound_of" && row.rebound && (value === undefined || value === null)) return "not measured";
  if (value === undefined || value === null) return key === "rebound_of" || key === "class" ? "" : "–";
  if (key === "rebound_of") { const k = parentRow(row); return k === undefined ? `${row.lane} ${value}` : String(k + 1); }
  if (typeof value === "number" && scale !== null) return fmt(value * scale, 4);
  return String(value);
}

function drawTable(a) {
  rowOf = new Map(a.impacts.map((row, k) => [`${row.lane}\u0000${row.sequence}`, k]));
  const present = COLUMNS.filter(([key]) => key === "#" || a.columns.includes(key));
  const head = document.querySelector("#impacts thead");
  head.innerHTML = "<tr>" + present.map(([, title]) => `<th>${title}</th>`).join("") + "</tr>";
  const body = document.querySelector("#impacts tbody");
  const rows = a.impacts.slice(0, SHOWN_ROWS).map((row, k) => {
    const tr = document.createElement("tr");
    tr.dataset.index = k;
    if (row.rebound) tr.className = "rebound";
    for (const [key, , scale] of present) {
      const td = document.createElement("td");
      td.textContent = cell(row, key, scale, k);
      if (key === "status" && row.status !== "ok") { td.className = "flag"; td.title = row.message || ""; }
      else if (key === "status" && row.rebound_ambiguous) {  // kept as read, but the evidence was not clear-cut
        td.textContent = "ok, ambiguous";
        td.className = "flag";
        td.title = row.message || "the rebound decision is ambiguous: see rebound_evidence in the JSON lines";
      }
      tr.appendChild(td);
    }
    return tr;
  });
  body.replaceChildren(...rows);
  document.getElementById("impacts-note").textContent = a.impacts.length > SHOWN_ROWS
    ? `the first ${SHOWN_ROWS.toLocaleString("en-US")} of ${a.impacts.length.toLocaleString("en-US")} (the CSV has them all)`
    : `${a.impacts.length} contacts; rebounds in grey; click one to see it`;
}

async function show(index) {
  if (!last) return;
  selected = index;
  for (const tr of document.querySelectorAll("#impacts tbody tr.selected")) tr.classList.remove("selected");
  const tr = document.querySelector(`#impacts tbody tr[data-index="${index}"]`);
  if (tr) tr.classList.add("selected");
  const analysis = last.analysis;
  const answer = await post("/api/impact", {analysis, index});
  // a newer analysis, or another click, since the request: its answer is not this view's (an answer for the same
  // index of the analysis before was shown with the new table: another impact's numbers)
  if (selected !== index || !last || last.analysis !== analysis) return;
  if (answer.refused) { document.getElementById("impact-caption").textContent = answer.error; return; }
  const row = answer.row;
  const series = [{x: answer.time, y: answer.force, color: "#5b6775", label: "samples"}];
  if (answer.model) series.push({x: answer.model.time, y: answer.model.force, color: "#b3261e", label: "fitted model"});
  document.getElementById("impact-caption").textContent =
    `impact ${index + 1} (${row.lane}, at ${fmt(row.start_time, 5)} s)${row.rebound ? (parentRow(row) === undefined ? ": rebound of a contact not measured as it was" : `: rebound of #${parentRow(row) + 1}`) : ""}` +
    (answer.model ? ": samples and the fitted Hunt–Crossley model" : last.columns.includes("fit_converged") ? ": the fit did not converge" : ": samples (tick the fit to see the model)");
  Charts.line(document.getElementById("chart-impact"), {series, xLabel: "time in the window [ms]", yLabel: "force [N]"});
  const shown = [["peak_force", "peak force F_max", "N", 1], ["time_to_peak", "time to peak t_c", "ms", 1e3],
                 ["contact_duration", "contact duration T", "ms", 1e3], ["firmness_c_star", "firmness C*", "N/s²", 1],
                 ["restitution", "restitution e (fit)", "", 1], ["mass", "mass (fit)", "g", 1e3],
                 ["modulus", "modulus E (fit)", "MPa", 1e-6], ["fit_residual_relative", "fit residual / peak", "", 1]];
  const body = document.querySelector("#impact-numbers tbody");
  body.replaceChildren(...shown.filter(([key]) => key in row).map(([key, label, unit, scale]) => {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td>${label}</td><td class="value">${fmt(row[key] === null ? null : row[key] * scale)}</td><td class="unit">${unit}</td>`;
    return tr;
  }));
  window.fruitimpact.impact = answer;
}

function csv(a) {
  const keys = a.columns;
  const quote = (v) => v === null || v === undefined ? "" : typeof v === "string" && /[",\n]/.test(v) ? `"${v.replace(/"/g, '""')}"` : typeof v === "object" ? `"${JSON.stringify(v).replace(/"/g, '""')}"` : String(v);
  return [keys.join(","), ...a.impacts.map((row) => keys.map((k) => quote(row[k])).join(","))].join("\n") + "\n";
}

document.querySelector(".export").addEventListener("click", (event) => {
  const kind = event.target.dataset && event.target.dataset.export;
  if (!kind || !last) return;
  const stem = last.file.replace(/\.[^.]*$/, "");
  if (kind === "csv") download(`${stem}-impacts.csv`, new Blob([csv(last)], {type: "text/csv"}));
  if (kind === "json") download(`${stem}-impacts.jsonl`, new Blob([last.impacts.map((row) => JSON.stringify(row)).join("\n") + "\n"], {type: "application/json"}));
  if (kind === "svg") for (const id of ["chart-overview", "chart-histogram", "chart-impact"]) download(`${stem}-${id.slice(6)}.svg`, new Blob([Charts.serialize(document.getElementById(id))], {type: "image/svg+xml"}));
});

document.querySelector("#impacts tbody").addEventListener("click", (event) => {
  const tr = event.target.closest("tr");
  if (tr) show(Number(tr.dataset.index));
});

document.getElementById("file").addEventListener("change", (event) => {
  const file = event.target.files[0];
  if (file) send(file);
});

form.addEventListener("input", (event) => {
  if (event.target.type === "file") return;
  clearTimeout(timer);
  timer = setTimeout(analyse, 500);  // typed options: analyse once the typing pauses
});
form.addEventListener("submit", (event) => event.preventDefault());

uploadLimit("upload-limit").then((bytes) => { limit = bytes; });
