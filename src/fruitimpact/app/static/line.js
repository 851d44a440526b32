// The line audit: the line's table and the lot → /api/line → numbers per point, charts, verdict, what-if, exports;
// or, in place of the table, an instrumented sphere's log uploaded → /api/sphere → the measured points' numbers.
"use strict";

const lot = document.getElementById("lot");
const sphereForm = document.getElementById("sphere");
const body = document.querySelector("#points tbody");
const statusLine = document.getElementById("status");
const whatIfPoint = document.getElementById("what-if-point");
const whatIfSurface = document.getElementById("what-if-surface");
const COLORS = {here: "#2b5f9e", sofar: "#a9c1de", volume: "#8a4b9c", volumeSofar: "#d3bddb"};
const COLUMNS = 12;  // of the line's table
let choices = null, last = null, timer = null, inFlight = false, pending = false, changedAt = null;
// The sphere's uploads ({upload, file, size}, by the input naming them), its last answer and the upload limit.
const sphereFiles = {log: null, sphere_calibration: null};
let lastSphere = null, uploadMax = 200 * 1024 * 1024;
// What a test or a curious user can read: answers drawn, the last one's latency [ms] (edit → page drawn), the answer
// (the typed table's: `last`; the sphere log's: `sphere`).
window.fruitimpact = {updates: 0, sphereUpdates: 0, refusals: 0, latency: null, last: null, sphere: null};

const percent = (share) => share === null || share === undefined ? "–" : `${fmt(share * 100, 3)} %`;
const mm3 = (volume) => volume === null || volume === undefined ? "–" : `${fmt(volume * 1e9, 4)} mm³`;
const points = (share) => `${fmt(Math.abs(share * 100), 3)} point${Math.abs(share * 100) === 1 ? "" : "s"}`;
const make = (tag, props = {}, children = []) => {
  const node = Object.assign(document.createElement(tag), props);
  node.append(...children);
  return node;
};

// ------------------------------------------------------------------------------------------ the line's table
function rows() { return [...body.querySelectorAll("tr.point")]; }

function cell(kind, child) { return make("td", {className: kind}, child ? [child] : []); }

function addRow(point, after) {
  const tr = make("tr", {className: "point"});
  const name = make("input", {type: "text", value: point.name, ariaLabel: "transfer point name"});
  const height = make("input", {type: "text", value: point.drop_height, ariaLabel: "drop height"});
  const surface = make("select", {ariaLabel: "surface"});
  fill(surface, choices.surfaces, point.surface);
  const flag = make("input", {type: "checkbox", checked: point.fruit_on_fruit, ariaLabel: "fruit on fruit"});
  name.dataset.column = "name"; height.dataset.column = "drop_height";
  surface.dataset.column = "surface"; flag.dataset.column = "fruit_on_fruit";
  // a measured half-space (e.g. a sphere's reading): the line CSV's optional surface_modulus and surface_poisson,
  // both or neither; blank: the library surface's own
  const measured = make("td", {className: "measured"});
  for (const [column, label, hint] of [["surface_modulus", "measured surface modulus", "E"], ["surface_poisson", "measured surface Poisson's ratio", "ν"]]) {
    const input = make("input", {type: "text", value: point[column] ?? "", placeholder: hint, ariaLabel: label});
    input.dataset.column = column;
    measured.append(input);
  }
  tr.append(cell("index"), cell("name", name), cell("height", height), cell("surface", surface), cell("flag", flag), measured);
  for (const out of ["incidence", "mean_bruise_volume", "cumulative_incidence", "cumulative_bruise_volume", "mean_peak_force"]) {
    const td = cell("out");
    td.dataset.out = out;
    td.textContent = "…";
    tr.append(td);
  }
  const button = (text, label, action) => {
    const b = make("button", {type: "button", textContent: text, title: label, ariaLabel: label});
    b.dataset.action = action;
    return b;
  };
  tr.append(make("td", {className: "actions"}, [button("↑", "move up", "up"), button("↓", "move down", "down"), button("✕", "remove", "remove")]));
  if (after) after.after(tr); else body.append(tr);
  return tr;
}

// Row numbers, the buttons that cannot act, a fruit-on-fruit point's surface shown as not met.
function renumber() {
  const all = rows();
  all.forEach((tr, i) => {
    tr.dataset.index = i;
    tr.querySelector("td.index").textContent = i + 1;
    tr.querySelector("[data-action=up]").disabled = i === 0;
    tr.querySelector("[data-action=down]").disabled = i === all.length - 1;
    tr.querySelector("[data-action=remove]").disabled = all.length === 1;
    const onFruit = tr.querySelector("[data-column=fruit_on_fruit]").checked;
    const surface = tr.querySelector("[data-column=surface]");
    const measured = [...tr.querySelectorAll("td.measured input")];
    const isMeasured = measured.some((input) => input.value.trim());
    surface.classList.toggle("unused", onFruit);
    surface.title = onFruit ? "the fruit lands on a resting fruit: this surface is not met"
      : isMeasured ? "names the measured surface; its modulus and Poisson's ratio are those typed beside" : "";
    for (const input of measured) input.classList.toggle("unused", onFruit);
  });
  refreshWhatIf();
}

function tableRows() {
  return rows().map((tr) => ({
    name: tr.querySelector("[data-column=name]").value,
    drop_height: tr.querySelector("[data-column=drop_height]").value,
    surface: tr.querySelector("[data-column=surface]").value,
    fruit_on_fruit: tr.querySelector("[data-column=fruit_on_fruit]").checked,
    surface_modulus: tr.querySelector("[data-column=surface_modulus]").value,
    surface_poisson: tr.querySelector("[data-column=surface_poisson]").value,
  }));
}

function newName() {
  const names = new Set(tableRows().map((row) => row.name.trim()));
  for (let i = rows().length + 1; ; i++) if (!names.has(`point ${i}`)) return `point ${i}`;
}

// ---------------------------------------------------------------------------------------------- what if
// The points a what-if may change (a fruit-on-fruit point's surface is not met) and the surfaces it may try.
function refreshWhatIf() {
  if (!choices) return;
  const line = tableRows();
  const chosen = whatIfPoint.value;
  const candidates = line.filter((row) => !row.fruit_on_fruit && row.name.trim()).map((row) => row.name.trim());
  fill(whatIfPoint, [{name: "", label: "— choose a point —"}, ...candidates], candidates.includes(chosen) ? chosen : "");
  const point = line.find((row) => row.name.trim() === whatIfPoint.value);
  const surface = whatIfSurface.value;
  const surfaces = choices.alternatives.filter((name) => !point || name !== point.surface);
  fill(whatIfSurface, [{name: "", label: "— choose a surface —"}, ...surfaces], surfaces.includes(surface) ? surface : "");
}

function whatIf() {
  return whatIfPoint.value && whatIfSurface.value ? {point: whatIfPoint.value, surface: whatIfSurface.value} : null;
}

// ------------------------------------------------------------------------------------------------ request
// Where the transfer points come from: "table" (typed) or "sphere" (a sphere's log).
const mode = () => document.querySelector("input[name=source]:checked").value;

// The lot, as both sources send it.
function lotRequest() {
  const out = {fruit: lot.elements.fruit.value, criterion: lot.elements.criterion.value, spreads: lot.elements.spreads.checked};
  for (const name of ["rows", "seed", "mass", "diameter", "modulus", "failure_stress"]) {
    const value = lot.elements[name].value.trim();
    if (value) out[name] = value;
  }
  return out;
}

function request() {
  const out = {points: tableRows(), ...lotRequest(),
    alternatives: [...document.querySelectorAll("#alternatives input:checked")].map((box) => box.value)};
  const change = whatIf();
  if (change) out.what_if = change;
  return out;
}

// The sphere's log: its uploads by their ids, the sphere's fields as typed, and the lot.
function sphereRequest() {
  const out = lotRequest();
  for (const [name, stored] of Object.entries(sphereFiles)) if (stored) out[name] = stored.upload;
  for (const control of sphereForm.querySelectorAll("input[data-input]:not([type=file]), select[data-input]")) {
    const value = control.value.trim();
    if (value) out[control.dataset.input] = value;
  }
  return out;
}

// An edit asks for an audit after `delay` ms; one audit at a time: an edit made meanwhile sends the next one
// when it returns, and an answer an edit has overtaken (sent, or waiting for its delay) is not drawn.
function schedule(delay) {
  if (changedAt === null) changedAt = performance.now();
  clearTimeout(timer);
  timer = setTimeout(() => { timer = null; send(); }, delay);
}

async function send() {
  if (inFlight) { pending = true; return; }
  const kind = mode();
  if (kind === "sphere" && !sphereFiles.log) {  // nothing to audit yet
    changedAt = null;
    statusLine.textContent = "choose the sphere's log";
    return;
  }
  inFlight = true;
  statusLine.textContent = "computing…";
  let status, answer;
  try {
    [status, answer] = kind === "sphere" ? await postJSON("/api/sphere", sphereRequest()) : await postJSON("/api/line", request());
  } catch (error) {
    statusLine.textContent = `the server did not answer (${error})`;
    answer = null;
  } finally {
    inFlight = false;
  }
  if (pending) { pending = false; send(); return; }  // overtaken by an edit: audit that instead
  if (!answer || timer !== null || kind !== mode()) return;  // an edit is about to be audited, or the source changed
  clearErrors();
  if (status !== 200 || answer.refused) {
    window.fruitimpact.refusals += 1;
    showError(answer.error, answer.argument);
    changedAt = null;
    return;
  }
  const latency = performance.now() - (changedAt ?? performance.now());
  changedAt = null;
  window.fruitimpact.latency = latency;
  const report = answer.report;
  if (kind === "sphere") {
    lastSphere = answer;
    renderSphere(answer);
    window.fruitimpact.sphereUpdates += 1;
    window.fruitimpact.sphere = answer;
    statusLine.textContent = `${report.status}: ${report.rows.toLocaleString("en-US")} fruit audited in ${latency.toFixed(0)} ms`;
    return;
  }
  last = answer;
  render(answer);
  window.fruitimpact.updates += 1;
  window.fruitimpact.last = answer;
  statusLine.textContent = `${report.status}: ${report.rows.toLocaleString("en-US")} fruit audited in ${latency.toFixed(0)} ms`;
}

// ------------------------------------------------------------------------------------------------ refusals
function clearErrors() {
  for (const node of document.querySelectorAll(".field-error, tr.error-row")) node.remove();
  for (const node of document.querySelectorAll(".invalid")) node.classList.remove("invalid");
  for (const id of ["form-error", "points-error", "sphere-error"]) document.getElementById(id).hidden = true;
  for (const id of STALE) document.getElementById(id).classList.remove("stale");
}

function note(message) {
  return make("p", {className: "field-error", textContent: message, role: "alert"});
}

// What a refusal leaves pale: the last good numbers.
const STALE = ["results", "points", "what-if", "sphere-results"];

// The CLI's line next to what it is about: a cell of the line (["points", row, column]), a what-if select, a lot
// or sphere control; anything else above the table (under the sphere's fields) or under the lot.
function showError(message, argument) {
  for (const id of STALE) document.getElementById(id).classList.add("stale");
  statusLine.textContent = "input refused";
  if (Array.isArray(argument) && argument[0] === "points") {
    const tr = rows()[argument[1]];
    if (tr) {
      const control = tr.querySelector(`[data-column="${argument[2]}"]`) || tr.querySelector("[data-column=name]");
      control.classList.add("invalid");
      const errorRow = make("tr", {className: "error-row"}, [make("td", {colSpan: COLUMNS}, [note(message)])]);
      tr.after(errorRow);
      return;
    }
  }
  if (Array.isArray(argument) && argument[0] === "what_if") {
    const control = document.querySelector(`[data-input="what_if.${argument[1]}"]`);
    control.classList.add("invalid");
    control.closest("label").after(note(message));
    return;
  }
  const control = typeof argument === "string" ? lot.querySelector(`[data-input="${argument}"]`) || sphereForm.querySelector(`[data-input="${argument}"]`) : null;
  if (control) {
    const closed = control.closest("details:not([open])");
    if (closed) closed.open = true;  // a refusal inside folded controls must be seen
    control.classList.add("invalid");
    (control.tagName === "FIELDSET" ? control : control.closest("label") || control).after(note(message));
    return;
  }
  const box = document.getElementById(argument === "points" ? "points-error" : mode() === "sphere" ? "sphere-error" : "form-error");
  box.textContent = message;
  box.hidden = false;
}

// ------------------------------------------------------------------------------------------------ drawing
function render(answer) {
  const report = answer.report;
  const worst = report.points.findIndex((point) => point.name === answer.worst_point);
  rows().forEach((tr, i) => {
    const point = report.points[i];
    tr.classList.toggle("worst", i === worst);
    if (!point) return;
    const put = (name, text, unit) => {
      const td = tr.querySelector(`td[data-out="${name}"]`);
      td.replaceChildren(text, ...(unit && text !== "–" ? [make("span", {className: "unit", textContent: ` ${unit}`})] : []));
    };
    put("incidence", fmt(point.incidence === null ? null : point.incidence * 100, 3), "%");
    put("mean_bruise_volume", fmt(point.mean_bruise_volume === null ? null : point.mean_bruise_volume * 1e9, 4), "mm³");
    put("cumulative_incidence", fmt(point.cumulative_incidence === null ? null : point.cumulative_incidence * 100, 3), "%");
    put("cumulative_bruise_volume", fmt(point.cumulative_bruise_volume === null ? null : point.cumulative_bruise_volume * 1e9, 4), "mm³");
    put("mean_peak_force", fmt(point.mean_peak_force, 4), "N");
  });
  renderVerdict(answer, worst);
  renderCharts(answer, worst);
  renderWhatIf(answer);
  renderChanges(answer);
  const warnings = [...report.warnings, ...(report.status !== "ok" ? [`${report.status}: ${report.message}`] : [])];
  document.getElementById("warnings").replaceChildren(...warnings.map((text) => make("li", {textContent: text})));
  // the library's spreads as the CLI describes them, and the distributions given on the page
  const described = new Set(report.spreads.map((text) => text.split(":")[0]));
  const given = Object.entries(report.inputs).filter(([name]) => !described.has(name)).map(([name, how]) => `${name}: ${how}`);
  const lines = [...report.spreads, ...given];
  document.getElementById("lot-lines").replaceChildren(...(lines.length ? lines : ["identical fruit: nothing is drawn"])
    .map((text) => make("li", {textContent: text})));
  document.getElementById("command").textContent = answer.command;
  // the what-if's change is in the list its command prints: the audit's own command when it tries that surface
  const change = answer.what_if;
  const own = change && change.command !== answer.command;
  document.getElementById("what-if-command").textContent = own ? change.command : "";
  document.getElementById("what-if-command").hidden = !own;
  const intro = document.getElementById("what-if-command-intro");
  intro.hidden = !change;
  intro.textContent = own ? "The what-if (its change is in the list this command prints):" : "The what-if's change is in the list this command prints.";
}

function item(label, content, id) {
  const value = make("b", {}, Array.isArray(content) ? content : [content]);
  if (id) value.id = id;
  return make("div", {className: "item"}, [make("span", {textContent: label}), value]);
}

// The lot in a few words: its size and seed, and how many fruit went through the whole line when not all did.
function lotText(report) {
  const size = `${report.rows.toLocaleString("en-US")} fruit, seed ${report.seed}`;
  return report.fruit_computed === report.rows ? size : `${size}: ${report.fruit_computed.toLocaleString("en-US")} computed at every point`;
}

// The verdict in `box`: the share of the lot bruised on the line (`lotLabel`: how it was drawn; `interval`: its
// 95 % interval, or null), the mean bruise volume per fruit and the most harmful point (`worst`: its name, or null,
// and `detail`). Its figures' ids start with `prefix`.
function verdict(box, prefix, {lotLabel, incidence, interval, volume, worst, detail, status = "ok", message = ""}) {
  // an audit that is not ok says so first, in the headline, not only in the notes under the tables
  const failed = status === "ok" ? [] : [make("div", {className: "item failed-headline", id: `${prefix}verdict-status`}, [
    make("span", {textContent: "the audit is not ok"}), make("b", {}, [`${status}: ${message}`])])];
  box.classList.toggle("not-ok", status !== "ok");
  box.replaceChildren(...failed,
    item(`bruised on the line (${lotLabel})${status === "ok" ? "" : " — of the points computed"}`, [
      make("strong", {className: "big", id: `${prefix}verdict-incidence`, textContent: percent(incidence)}),
      make("small", {className: "interval", textContent: interval ? ` (95 %: ${percent(interval[0])} to ${percent(interval[1])})` : ""})]),
    item("mean bruise volume per fruit", mm3(volume), `${prefix}verdict-volume`),
    worst === null ? item("most harmful transfer point", "none found (no fruit computed)", `${prefix}worst-point`)
      : item("most harmful transfer point", [make("strong", {className: "big worst", id: `${prefix}worst-point`, textContent: worst}),
        make("small", {className: "interval detail", textContent: detail})]));
}

function renderVerdict(answer, worst) {
  const report = answer.report;
  const point = report.points[worst];
  const onto = point && (point.fruit_on_fruit ? "onto fruit" : point.surface_modulus ? `onto ${point.surface} (measured: ${fmt(point.surface_modulus / 1e6, 3)} MPa, ν ${fmt(point.surface_poisson, 2)})` : `onto ${point.surface}`);
  verdict(document.getElementById("verdict"), "", {
    status: report.status, message: report.message,
    lotLabel: `criterion ${report.criterion}, ${lotText(report)}`, incidence: report.incidence,
    interval: answer.incidence_interval, volume: report.mean_bruise_volume, worst: point ? point.name : null,
    detail: point && `${fmt(point.drop_height * 100, 3)} cm ${onto}: ${percent(point.incidence)} bruised there, ${mm3(point.mean_bruise_volume)}`});
}

function renderCharts(answer, worst) {
  drawBars(answer.report.points, worst, "chart-incidence", "chart-volume", "mean_bruise_volume");
}

// The two bar charts of a line's points (in the SVGs `incidenceId` and `volumeId`): the share bruised and the mean
// bruise volume per fruit (`volumeKey`), at each point and cumulated, the most harmful point (`worst`) shaded.
function drawBars(points, worst, incidenceId, volumeId, volumeKey) {
  const names = points.map((point) => point.name);
  const share = (key) => points.map((point) => point[key] === null ? NaN : point[key] * 100);
  const volume = (key) => points.map((point) => point[key] === null || point[key] === undefined ? NaN : point[key] * 1e9);
  Charts.bars(document.getElementById(incidenceId), {
    categories: names, highlight: worst, yLabel: "bruised [%]", xLabel: "transfer points, in the order the fruit meets them", yMax: 130, tick: (t) => t <= 100 ? String(t) : "",
    format: (v) => `${fmt(v, 3)} %`,
    series: [{values: share("incidence"), color: COLORS.here, label: "at the point"},
             {values: share("cumulative_incidence"), color: COLORS.sofar, label: "so far along the line"}]});
  const volumes = [...volume(volumeKey), ...volume("cumulative_bruise_volume")].filter(Number.isFinite);
  Charts.bars(document.getElementById(volumeId), {
    categories: names, highlight: worst, yLabel: "bruise volume [mm³]", xLabel: "transfer points, in the order the fruit meets them", yMax: Math.max(1, ...volumes) * 1.3,
    format: (v) => `${fmt(v, 4)} mm³`,
    series: [{values: volume(volumeKey), color: COLORS.volume, label: "at the point"},
             {values: volume("cumulative_bruise_volume"), color: COLORS.volumeSofar, label: "accumulated"}]});
}

function saving(value, format, unit) {
  if (value === null) return make("span", {className: "saved", textContent: "–"});
  if (value === 0) return make("span", {className: "saved", textContent: "saves nothing"});
  const kind = value > 0 ? "saved saving" : "saved cost";
  return make("span", {className: kind, textContent: `${value > 0 ? "saves" : "costs"} ${format(Math.abs(value))}${unit}`});
}

function renderWhatIf(answer) {
  const box = document.getElementById("what-if-result");
  const change = answer.what_if;
  if (!change) {
    box.replaceChildren(make("p", {className: "hint", textContent: "Choose a transfer point and a surface: the same fruit pass the line again with that one change, and the page shows what it saves."}));
    return;
  }
  if (!change.after) { box.replaceChildren(make("p", {className: "error", textContent: change.message})); return; }
  // each figure now → with the change, and what the change saves (or costs)
  const figure = (label, before, after, saved, id) => {
    const savedText = saved;
    savedText.id = id;
    return [make("dt", {textContent: label}), make("dd", {}, [make("b", {textContent: `${before} → ${after}`}), savedText])];
  };
  const list = make("dl", {className: "compare"}, [
    ...figure("bruised on the line", percent(change.before.incidence), percent(change.after.incidence),
      saving(change.incidence_saved, (v) => points(v), ""), "what-if-saved-incidence"),
    ...figure("mean bruise volume per fruit", mm3(change.before.mean_bruise_volume), mm3(change.after.mean_bruise_volume),
      saving(change.bruise_volume_saved, (v) => fmt(v * 1e9, 4), " mm³"), "what-if-saved-volume"),
  ]);
  box.replaceChildren(make("p", {textContent: `${change.to} in place of ${change.from} at ${change.point}, for the same ${change.fruit.toLocaleString("en-US")} fruit (paired, not a second sample):`}), list);
}

function renderChanges(answer) {
  const changes = answer.report.changes;
  const rowsOut = changes.map((change) => {
    const tryIt = make("button", {type: "button", textContent: "what if", title: "show this change in the what-if"});
    tryIt.addEventListener("click", () => {
      whatIfPoint.value = change.point;
      refreshWhatIf();
      whatIfSurface.value = change.to;
      schedule(0);
    });
    return make("tr", {}, [
      make("td", {textContent: `${change.to} in place of ${change.from} at ${change.point}`}),
      make("td", {textContent: percent(change.incidence)}),
      make("td", {}, [saving(change.incidence_saved, (v) => points(v), "")]),
      make("td", {textContent: mm3(change.mean_bruise_volume)}),
      make("td", {}, [saving(change.bruise_volume_saved, (v) => fmt(v * 1e9, 4), " mm³")]),
      make("td", {}, [tryIt])]);
  });
  document.querySelector("#changes tbody").replaceChildren(...rowsOut);
  document.getElementById("changes").hidden = !changes.length;
  const tried = answer.request.alternatives;
  const none = answer.report.incidence !== null && changes.length && changes.every((change) => change.incidence_saved <= 0);
  document.getElementById("changes-hint").textContent = !tried.length ? "No surface to try: tick some under Surfaces to try."
    : !changes.length ? "No transfer point can take these surfaces (a fruit-on-fruit point's surface is not met)."
    : none ? "No single change saves any fruit from bruising: every fruit is bruised at more than one point, so the line needs more than one change. The bruise volume saved still ranks them."
    : "";
}

// ------------------------------------------------------------------------------------------- a sphere's log
// A figure to `digits` significant digits with its unit, the unit small ("–" alone when there is none).
function withUnit(value, unit, digits = 3) {
  const text = fmt(value, digits);
  return text === "–" ? [text] : [text, make("span", {className: "unit", textContent: ` ${unit}`})];
}

function sphereRow(point, index, worst, target) {
  const out = (children, title) => make("td", {className: "out", title: title || ""}, children);
  const cells = [make("td", {className: "index", textContent: index + 1}), make("td", {className: "name", textContent: point.name}),
    out([String(point.passes)]),
    out([point.impacts_reproduced === point.impacts ? String(point.impacts) : `${point.impacts_reproduced} of ${point.impacts}`],
      point.impacts_reproduced === point.impacts ? "" : "the others are reproduced by no impact of the sphere")];
  if (point.incidence === null) {  // no reading of the point reproduced: its message in place of its figures
    cells.push(make("td", {className: "message", colSpan: 7, textContent: point.message}));
    return make("tr", {className: "point failed"}, cells);
  }
  const cm = (value) => withUnit(value === null ? null : value * 100, "cm");
  const interval = make("span", {className: "range", textContent: `${fmt(point.drop_height_low * 100, 3)}–${fmt(point.drop_height_high * 100, 3)}`});
  const advice = point.cushion;
  cells.push(
    make("td", {className: "out drop"}, [...cm(point.drop_height), interval]),
    out(cm(point.drop_height_max)),
    make("td", {className: "surface", title: point.message}, [make("b", {}, point.surface_modulus === null ? ["rigid"] : withUnit(point.surface_modulus / 1e6, "MPa")),
      make("span", {className: "range", textContent: `nearest: ${point.surface}`})]),
    out(withUnit(point.incidence === null ? null : point.incidence * 100, "%")),
    out(withUnit(point.bruise_volume === null ? null : point.bruise_volume * 1e9, "mm³", 4)),
    out(withUnit(point.cumulative_incidence === null ? null : point.cumulative_incidence * 100, "%")),
    // the cushion, the point's incidence with it and the bruised fruit it saves per 10,000
    make("td", {className: "cushion", title: advice ? advice.message : ""},
      !advice ? [make("span", {className: "unit", textContent: `not needed (≤ ${fmt(target * 100, 3)} % target)`})]
        : advice.surface ? [make("b", {textContent: advice.surface}), ` → ${percent(advice.incidence)}`,
          make("span", {className: "range saved", textContent: `saves ${fmt(advice.saved_per_10000, 4)} per 10,000`})]
        : [make("span", {className: "none", textContent: advice.message})]));
  const tr = make("tr", {className: worst ? "point worst" : "point"}, cells);
  tr.dataset.name = point.name;
  return tr;
}

function renderSphere(answer) {
  const report = answer.report;
  document.getElementById("sphere-results").hidden = false;
  const worst = report.points.findIndex((point) => point.name === answer.worst_point);
  const point = report.points[worst];
  const surface = point && (point.surface_modulus === null ? `a rigid surface (${point.surface})` : `${fmt(point.surface_modulus / 1e6, 3)} MPa (nearest ${point.surface})`);
  verdict(document.getElementById("sphere-verdict"), "sphere-", {
    status: report.status, message: report.message,
    lotLabel: `criterion ${report.criterion}, ${report.rows.toLocaleString("en-US")} fruit, seed ${report.seed}`,
    incidence: report.incidence, interval: null, volume: report.mean_bruise_volume, worst: point ? point.name : null,
    detail: point && `${fmt(point.drop_height * 100, 3)} cm onto ${surface}: ${percent(point.incidence)} bruised there, ${mm3(point.bruise_volume)}`});
  document.querySelector("#sphere-points tbody").replaceChildren(...report.points.map((p, i) => sphereRow(p, i, i === worst, report.target)));
  const reproduced = report.impacts.filter((impact) => impact.status === "ok").length;
  document.getElementById("sphere-points-note").textContent = `from ${answer.file}: ${report.points.length} transfer points, ${reproduced} of ${report.readings} readings reproduced by an impact`;
  drawBars(report.points, worst, "sphere-chart-incidence", "sphere-chart-volume", "bruise_volume");
  const sphere = report.sphere;
  const lines = [`sphere ${sphere.name}: ${fmt(sphere.mass * 1e3, 4)} g, ${fmt(sphere.diameter * 1e3, 4)} mm, E*_s ${fmt(sphere.contact_modulus / 1e6, 4)} MPa (${sphere.stiffness_source})`,
    ...(report.calibration ? [`calibration: ${report.calibration.status}: ${report.calibration.message}`] : []),
    `log ${answer.file}: ${report.readings} readings (${report.kind}), ${reproduced} reproduced by an impact, ${answer.skipped.length} rows skipped; points by ${report.grouping}`];
  document.getElementById("sphere-lines").replaceChildren(...lines.map((text) => make("li", {textContent: text})));
  const warnings = [...report.warnings, ...(report.status !== "ok" ? [`${report.status}: ${report.message}`] : [])];
  document.getElementById("sphere-warnings").replaceChildren(...warnings.map((text) => make("li", {textContent: text})));
  document.getElementById("sphere-skipped").replaceChildren(...answer.skipped.map((text) => make("li", {textContent: text})));
  document.getElementById("sphere-command").textContent = answer.command;
}

// A file chosen for the sphere (`input`: the log's or the calibration's): uploaded, then the log audited.
async function uploadSphereFile(input) {
  const name = input.dataset.input;
  const file = input.files[0];
  sphereFiles[name] = null;
  document.getElementById("sphere-calibration-clear").hidden = !(name === "sphere_calibration" ? file : sphereFiles.sphere_calibration);
  if (!file) { schedule(10); return; }
  clearErrors();
  statusLine.textContent = `uploading ${file.name} (${mb(file.size)})…`;
  const answer = await uploadFile(file, uploadMax);
  if (answer.refused) {
    window.fruitimpact.refusals += 1;
    showError(answer.error, name);  // the upload's refusal, next to the file it is about
    return;
  }
  sphereFiles[name] = answer;
  schedule(0);
}

// The transfer points typed in the table, or measured by the sphere: the controls and results of the one chosen.
function showSource() {
  const sphere = mode() === "sphere";
  for (const id of ["table-source", "add-point", "results", "what-if", "alternatives-section"]) document.getElementById(id).hidden = sphere;
  document.getElementById("sphere").hidden = !sphere;
  document.getElementById("sphere-results").hidden = !sphere || !lastSphere;  // nothing to show before a log
  clearErrors();
  redraw();  // charts drawn while hidden have no width
  schedule(10);  // the lot may have changed meanwhile
}

// The charts shown, drawn again to their width.
function redraw() {
  const worst = (answer) => answer.report.points.findIndex((point) => point.name === answer.worst_point);
  if (mode() === "table" && last) renderCharts(last, worst(last));
  if (mode() === "sphere" && lastSphere) drawBars(lastSphere.report.points, worst(lastSphere), "sphere-chart-incidence", "sphere-chart-volume", "bruise_volume");
}

// -------------------------------------------------------------------------------------------------- export
const csvField = (value) => {
  const text = value === null || value === undefined ? "" : String(value);
  return /[",\n]/.test(text) ? `"${text.replace(/"/g, '""')}"` : text;
};

async function exportAs(kind) {
  if (kind.startsWith("sphere-")) return exportSphere(kind);
  if (!last) return;
  const charts = ["chart-incidence", "chart-volume"].map((id) => document.getElementById(id));
  if (kind === "svg") for (const svg of charts) download(`${svg.id}.svg`, new Blob([Charts.serialize(svg)], {type: "image/svg+xml"}));
  if (kind === "png") for (const svg of charts) download(`${svg.id}.png`, await Charts.png(svg));
  if (kind === "json") download("line-audit.json", new Blob([JSON.stringify(last, null, 2)], {type: "application/json"}));
  if (kind === "line") download(last.file, new Blob([last.line_csv], {type: "text/csv"}));
  if (kind === "csv") {
    const columns = [["name", "name"], ["drop_height", "drop_height_m"], ["surface", "surface"], ["fruit_on_fruit", "fruit_on_fruit"],
      ["surface_modulus", "surface_modulus_Pa"], ["surface_poisson", "surface_poisson"], ["velocity", "velocity_m_s"], ["incidence", "incidence"], ["mean_bruise_volume", "mean_bruise_volume_m3"],
      ["cumulative_incidence", "cumulative_incidence"], ["cumulative_bruise_volume", "cumulative_bruise_volume_m3"],
      ["mean_peak_force", "mean_peak_force_N"], ["mean_max_pressure", "mean_max_pressure_Pa"], ["invalid", "invalid"], ["failed", "failed"]];
    const lines = [columns.map(([, header]) => header).join(","),
      ...last.report.points.map((point) => columns.map(([key]) => csvField(point[key])).join(","))];
    download("line-audit.csv", new Blob([lines.join("\n") + "\n"], {type: "text/csv"}));
  }
}

function exportSphere(kind) {
  if (!lastSphere) return;
  const stem = lastSphere.file.replace(/\.[^.]*$/, "");
  if (kind === "sphere-json") download(`${stem}-audit.json`, new Blob([JSON.stringify(lastSphere, null, 2)], {type: "application/json"}));
  if (kind === "sphere-svg") for (const id of ["sphere-chart-incidence", "sphere-chart-volume"]) download(`${stem}-${id.slice(7)}.svg`, new Blob([Charts.serialize(document.getElementById(id))], {type: "image/svg+xml"}));
  if (kind === "sphere-csv") {
    const columns = [["name", "name"], ["passes", "passes"], ["impacts", "impacts"], ["impacts_reproduced", "impacts_reproduced"],
      ["drop_height", "drop_height_m"], ["drop_height_low", "drop_height_low_m"], ["drop_height_high", "drop_height_high_m"],
      ["drop_height_max", "drop_height_max_m"], ["surface_modulus", "surface_modulus_Pa"], ["surface", "surface"],
      ["incidence", "incidence"], ["bruise_volume", "bruise_volume_m3"], ["cumulative_incidence", "cumulative_incidence"],
      ["cumulative_bruise_volume", "cumulative_bruise_volume_m3"], ["status", "status"], ["message", "message"]];
    const advice = [["surface", "cushion"], ["incidence", "cushion_incidence"], ["saved_per_10000", "cushion_saved_per_10000"]];
    const lines = [[...columns, ...advice].map(([, header]) => header).join(","),
      ...lastSphere.report.points.map((point) => [...columns.map(([key]) => csvField(point[key])),
        ...advice.map(([key]) => csvField(point.cushion ? point.cushion[key] : null))].join(","))];
    download(`${stem}-points.csv`, new Blob([lines.join("\n") + "\n"], {type: "text/csv"}));
  }
}

// ------------------------------------------------------------------------------------------------- start
function describeFruit() {
  const entry = choices.fruits.find((fruit) => fruit.name === lot.elements.fruit.value);
  document.getElementById("fruit-description").textContent = entry ? entry.description : "";
}

function setUp(answer) {
  choices = answer.choices;
  const asked = answer.request;
  fill(lot.elements.fruit, choices.fruits, asked.fruit);
  fill(lot.elements.criterion, choices.criteria.map((name) => ({name, label: name === "preset" ? "the fruit's own (preset)" : name})), asked.criterion);
  lot.elements.rows.value = asked.rows;
  lot.elements.seed.value = asked.seed;
  lot.elements.spreads.checked = asked.spreads;
  document.getElementById("rows-hint").textContent = `More fruit: finer figures, slower answers (10,000 take about 2 s on two cores). The page takes up to ${answer.max_rows.toLocaleString("en-US")}, the command line any number.`;
  const fieldset = document.getElementById("alternatives");
  fieldset.append(...choices.alternatives.map((name) => {
    const box = make("input", {type: "checkbox", value: name, checked: asked.alternatives.includes(name)});
    return make("label", {}, [box, name]);
  }));
  describeFruit();
  for (const point of asked.points) addRow(point);
  renumber();
}

function onTableEdit(event) {
  const target = event.target;
  if (!target.dataset.column) return;
  if (["fruit_on_fruit", "surface", "name", "surface_modulus", "surface_poisson"].includes(target.dataset.column)) renumber();
  schedule(target.type === "text" ? 200 : 10);  // typing: wait for a pause
}

function onTableClick(event) {
  const button = event.target.closest("button[data-action]");
  if (!button) return;
  const tr = button.closest("tr.point");
  const action = button.dataset.action;
  for (const node of body.querySelectorAll("tr.error-row")) node.remove();  // the row it named may move
  if (action === "remove" && rows().length > 1) tr.remove();
  if (action === "up" && tr.previousElementSibling) tr.previousElementSibling.before(tr);
  if (action === "down" && tr.nextElementSibling) tr.nextElementSibling.after(tr);
  renumber();
  schedule(10);
}

async function start() {
  let status, answer;
  try {
    [status, answer] = await postJSON("/api/line", {});  // the example line, with the page's defaults
  } catch (error) {
    statusLine.textContent = `the server did not answer (${error})`;
    return;
  }
  if (status !== 200 || answer.refused) { statusLine.textContent = `the server refused the example line: ${answer.error}`; return; }
  setUp(answer);
  last = answer;
  render(answer);
  window.fruitimpact.updates += 1;
  window.fruitimpact.last = answer;
  statusLine.textContent = `${answer.report.status}: ${answer.report.rows.toLocaleString("en-US")} fruit audited`;

  lot.addEventListener("input", (event) => {
    if (event.target.name === "fruit") describeFruit();
    schedule(event.target.tagName === "INPUT" && event.target.type === "text" ? 200 : 10);
  });
  lot.addEventListener("submit", (event) => { event.preventDefault(); schedule(0); });
  body.addEventListener("input", onTableEdit);
  body.addEventListener("click", onTableClick);
  body.addEventListener("keydown", (event) => { if (event.key === "Enter") schedule(0); });
  document.getElementById("add-point").addEventListener("click", () => {
    for (const node of body.querySelectorAll("tr.error-row")) node.remove();
    const all = rows();
    const tr = addRow({name: newName(), drop_height: "10cm", surface: "rubber-belt", fruit_on_fruit: false}, all[all.length - 1]);
    renumber();
    tr.querySelector("[data-column=name]").select();
    schedule(10);
  });
  whatIfPoint.addEventListener("input", () => { refreshWhatIf(); if (whatIf()) schedule(10); });
  whatIfSurface.addEventListener("input", () => { if (whatIf()) schedule(10); });
  document.getElementById("what-if-clear").addEventListener("click", () => {
    const had = whatIf();
    whatIfPoint.value = "";
    refreshWhatIf();
    if (had) schedule(10);
  });
  for (const button of document.querySelectorAll("[data-export]")) button.addEventListener("click", () => exportAs(button.dataset.export));
  window.addEventListener("resize", redraw);
  setUpSphere();
}

// The sphere's controls: the device profiles, the upload limit, the files and fields, the choice of source.
async function setUpSphere() {
  const offered = await (await fetch("/api/sphere/choices")).json();
  fill(sphereForm.elements.sphere, [{name: "", label: "custom", description: "no profile: its mass and diameter typed below"}, ...offered.devices], "");
  uploadMax = await uploadLimit("upload-limit");
  for (const input of sphereForm.querySelectorAll("input[type=file]")) input.addEventListener("change", () => uploadSphereFile(input));
  document.getElementById("sphere-calibration-clear").addEventListener("click", () => {
    const input = document.getElementById("sphere-calibration");
    input.value = "";
    uploadSphereFile(input);
  });
  sphereForm.addEventListener("input", (event) => {
    if (event.target.type === "file") return;
    schedule(event.target.tagName === "INPUT" ? 300 : 10);  // typing: wait for a pause
  });
  sphereForm.addEventListener("submit", (event) => { event.preventDefault(); schedule(0); });
  for (const radio of document.querySelectorAll("input[name=source]")) radio.addEventListener("change", showSource);
  if (mode() !== "table") showSource();  // a choice the browser restored on reload
}

start();
