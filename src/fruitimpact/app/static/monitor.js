// The live monitor: a WebSocket to /ws/monitor; the server runs the stream's detector on a replayed recording or
// on samples arriving over TCP and sends a frame of new reports every 100 ms; each lane shows its latest force
// curves, its rolling firmness and its class counts.
"use strict";

const form = document.getElementById("controls");
const statusLine = document.getElementById("status");
const CURVES_SHOWN = 5;       // latest force curves per lane
const FIRMNESS_SHOWN = 120;   // fruit in a lane's rolling firmness chart
const RATE_WINDOW = 5;        // fruit per second over this much signal [s]
let socket = null, upload = null, lanes = {}, state = null, limit = 200 * 1024 * 1024, dirty = false;
// What a test or a curious user can read: every count the page shows, and the stream's own summary.
window.fruitimpact = {contacts: 0, fruit: 0, summaries: [], ended: false, started: null, frames: 0};

const source = () => form.querySelector("input[name=source]:checked").value;

function inputs() {
  const out = {source: source()};
  for (const element of form.querySelectorAll("[data-input]")) {
    if (element.closest("[hidden]")) continue;
    const name = element.dataset.input;
    if (element.type === "checkbox") { out[name] = element.checked; continue; }
    const value = element.value.trim();
    if (value) out[name] = value;
  }
  if (out.source === "replay" && upload) out.upload = upload.upload;
  return out;
}

const clearErrors = () => clearFormErrors(form);

function refuse(body) {
  showRefusal(form, body);
  document.getElementById("results").classList.add("stale");  // the figures are the last run's
  statusLine.textContent = "refused: see the form";
  setRunning(false);
}

function setRunning(running) {
  document.getElementById("start").disabled = running;
  document.getElementById("stop").disabled = !running;
}

async function sendFile(file) {
  clearErrors();
  upload = null;
  statusLine.textContent = `uploading ${file.name}…`;
  const answer = await uploadFile(file, limit);
  if (answer.refused) return refuse(answer);
  upload = answer;
  statusLine.textContent = `${answer.file} ready to replay`;
}

function start() {
  clearErrors();
  if (source() === "replay" && !upload) return refuse({error: "choose a recording to replay first", argument: "file"});
  setRunning(true);
  lanes = {};
  document.getElementById("lanes").replaceChildren();
  document.getElementById("messages").replaceChildren();
  Object.assign(window.fruitimpact, {contacts: 0, fruit: 0, summaries: [], ended: false, started: null, frames: 0});
  state = {contacts: 0, fruit: 0, figures: null, classes: null};
  showFigures();
  const open = () => socket.send(JSON.stringify({action: "start", ...inputs()}));
  if (socket && socket.readyState === WebSocket.OPEN) return open();
  socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws/monitor`);
  socket.onopen = open;
  socket.onmessage = (event) => receive(JSON.parse(event.data));
  socket.onclose = () => { socket = null; setRunning(false); };
}

function stop() {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({action: "stop"}));
  document.getElementById("stop").disabled = true;
  statusLine.textContent = "stopping: the detector flushes its last contacts…";
}

// A line of the stream's log: plain for news (a client, the summary when every report arrived), coloured for a
// problem (warn) or an error (bad).
function note(text, kind) {
  const item = document.createElement("li");
  item.textContent = text;
  if (kind) item.className = kind;
  document.getElementById("messages").appendChild(item);
}

function receive(message) {
  if (message.type === "refused") return refuse(message);
  if (message.type === "started") return started(message);
  if (message.type === "frame") return frame(message);
  if (message.type === "end") {
    window.fruitimpact.ended = true;
    setRunning(false);
    document.getElementById("state").textContent = "ended";
    statusLine.textContent = `ended: ${state.contacts} contacts received`;
  }
}

function started(message) {
  document.getElementById("results").classList.remove("stale");
  window.fruitimpact.started = message;
  state.classes = message.classes;
  document.getElementById("state").textContent = "running";
  document.getElementById("source-note").textContent = message.source === "tcp"
    ? `Listening on 127.0.0.1:${message.port} for ${message.lanes.length} lane(s) at ${fmt(message.rate / 1000, 4)} kHz: send the samples there (text lines, or raw float32 with format f32), e.g. your acquisition's output through nc 127.0.0.1 ${message.port}.`
    : `Replaying ${message.file} (${message.lanes.length} lane(s) at ${fmt(message.rate / 1000, 4)} kHz) ${message.speed ? `at ${message.speed} × real time` : "as fast as the detector goes"}.`;
  statusLine.textContent = "running";
  for (const name of message.lanes) addLane(name);
}

function addLane(name) {
  const card = document.createElement("div");
  card.className = "panel lane";
  card.innerHTML = `<h3><span class="name"></span><span class="figure" data-figure="count"></span><span class="figure" data-figure="rate"></span></h3>
    <svg class="chart small" data-chart="curves" role="img" aria-label="latest force curves"></svg>
    <svg class="chart small" data-chart="firmness" role="img" aria-label="rolling firmness"></svg>
    <div class="counts" data-figure="classes"></div>`;
  card.querySelector(".name").textContent = name;
  document.getElementById("lanes").appendChild(card);
  lanes[name] = {card, curves: [], firmness: [], times: [], fruit: 0, contacts: 0, classes: {}};
}

function frame(message) {
  window.fruitimpact.frames += 1;
  for (const row of message.reports) {
    const lane = lanes[row.lane] || (addLane(row.lane), lanes[row.lane]);
    lane.contacts += 1;
    state.contacts += 1;
    if (row.rebound) continue;
    lane.fruit += 1;
    state.fruit += 1;
    lane.times.push(row.start_time);
    const value = row[state.classes ? state.classes.by : "firmness_c_star"];
    if (Number.isFinite(value)) lane.firmness.push([row.start_time, value, row.class]);
    if (lane.firmness.length > FIRMNESS_SHOWN) lane.firmness.shift();
    if (row.class) lane.classes[row.class] = (lane.classes[row.class] || 0) + 1;
  }
  for (const [name, curve] of Object.entries(message.curves)) {
    const lane = lanes[name];
    if (!lane) continue;
    lane.curves.push(curve);
    if (lane.curves.length > CURVES_SHOWN) lane.curves.shift();
  }
  for (const item of message.messages) {
    if (item.type === "summary") {
      window.fruitimpact.summaries.push(item.summary);
      const all = state.contacts === window.fruitimpact.summaries.reduce((s, x) => s + x.impacts, 0);
      note(`the stream reported ${item.summary.impacts} contacts in ${item.summary.samples.toLocaleString("en-US")} samples per lane` +
           (item.dropped ? `; ${item.dropped} samples dropped` : "") + "; this page received " + state.contacts +
           (all ? " (all)" : " (MISSING SOME)"), all && !item.dropped ? "" : "problem");
    } else if (item.type === "client") note(`client ${item.client} connected from ${item.address}`);
    else note(item.message, item.type === "error" ? "error" : "problem");  // the stream's problems and errors
  }
  state.figures = message.figures;
  window.fruitimpact.contacts = state.contacts;
  window.fruitimpact.fruit = state.fruit;
  dirty = true;
}

function showFigures() {
  const f = state.figures;
  document.getElementById("fruit").textContent = state.fruit.toLocaleString("en-US");
  document.getElementById("contacts").textContent = state.contacts.toLocaleString("en-US");
  if (!f) return;
  const now = f.signal_seconds;
  let total = 0;
  for (const lane of Object.values(lanes)) {
    const recent = lane.times.filter((t) => t > now - RATE_WINDOW).length / Math.min(RATE_WINDOW, Math.max(now, 1e-9));
    total += recent;
    lane.card.querySelector('[data-figure="rate"]').textContent = `${fmt(recent, 3)} fruit/s`;
    lane.card.querySelector('[data-figure="count"]').textContent = `${lane.fruit} fruit, ${lane.contacts - lane.fruit} rebounds`;
  }
  document.getElementById("rate").textContent = fmt(total, 3);
  document.getElementById("clock").textContent = `${fmt(f.signal_seconds, 3)} s / ${fmt(f.elapsed, 3)} s` + (f.lag > 0.05 ? ` (behind by ${fmt(f.lag, 2)} s)` : "");
  document.getElementById("dropped").textContent = f.dropped.toLocaleString("en-US");
  document.getElementById("latency").textContent = f.latency_p50 === null ? "–" : `${fmt(f.latency_p50 * 1e3, 3)} / ${fmt(f.latency_p99 * 1e3, 3)} ms`;
}

function drawLane(lane) {
  const n = lane.curves.length;
  const series = lane.curves.map((curve, i) => ({x: curve.time, y: curve.force, color: i === n - 1 ? "#2f6f4f" : "#b9c7bf",
                                                label: i === n - 1 ? `latest: F_max ${fmt(curve.peak_force, 3)} N` : ""}));
  const latest = lane.curves[n - 1];
  if (latest && latest.model) series.push({x: latest.time, y: latest.model, color: "#b3261e", dash: "5 3", label: "fitted model"});
  Charts.line(lane.card.querySelector('[data-chart="curves"]'), {series, xLabel: "time in the window [ms]", yLabel: "force [N]", empty: "no contact yet"});
  const by = state.classes ? state.classes.by : "firmness_c_star";
  const points = lane.firmness;
  Charts.line(lane.card.querySelector('[data-chart="firmness"]'), {
    series: [{x: points.map((p) => p[0]), y: points.map((p) => p[1]), color: "#2b5d9b"}],
    xLabel: "time [s]", yLabel: by === "firmness_c_star" ? "C* [N/s²]" : by, empty: "no fruit yet",
    hLines: state.classes ? state.classes.thresholds : [], dots: true,
  });
  const counts = lane.card.querySelector('[data-figure="classes"]');
  if (state.classes) {
    counts.replaceChildren(...state.classes.labels.map((label) => {
      const span = document.createElement("span");
      span.innerHTML = `<b></b> `;
      span.firstChild.textContent = lane.classes[label] || 0;
      span.appendChild(document.createTextNode(label));
      return span;
    }));
  }
}

// Drawn on the browser's own clock (at most once per animation frame), never per message.
function render() {
  if (dirty && state) {
    dirty = false;
    showFigures();
    for (const lane of Object.values(lanes)) drawLane(lane);
  }
  requestAnimationFrame(render);
}
requestAnimationFrame(render);

for (const radio of form.querySelectorAll("input[name=source]")) {
  radio.addEventListener("change", () => {
    document.getElementById("replay-controls").hidden = source() !== "replay";
    document.getElementById("tcp-controls").hidden = source() !== "tcp";
    clearErrors();
  });
}
document.getElementById("file").addEventListener("change", (event) => { if (event.target.files[0]) sendFile(event.target.files[0]); });
document.getElementById("start").addEventListener("click", start);
document.getElementById("stop").addEventListener("click", stop);
form.addEventListener("submit", (event) => event.preventDefault());
uploadLimit("upload-limit").then((bytes) => { limit = bytes; });
