// What every page of the app shares: number formats, downloads, uploads and refusals shown next to a control.
"use strict";

// A number to `digits` significant digits, grouped ("–" for none, NaN or infinity).
const fmt = (v, digits = 4) => v === null || v === undefined || !Number.isFinite(v) ? "–" : Number(v.toPrecision(digits)).toLocaleString("en-US", {maximumSignificantDigits: digits});
const mb = (bytes) => `${(bytes / 1048576).toLocaleString("en-US", {maximumFractionDigits: 1})} MB`;

// Fill a <select> with `items` (names, or {name, label, description}), `selected` chosen.
function fill(select, items, selected) {
  select.replaceChildren(...items.map((item) => {
    const name = typeof item === "string" ? item : item.name;
    const option = new Option(item.label || name, name, false, name === selected);
    if (item.description) option.title = item.description;
    return option;
  }));
}

// POST `body` as JSON: [HTTP status, the answer's JSON].
async function postJSON(path, body) {
  const response = await fetch(path, {method: "POST", headers: {"Content-Type": "application/json"}, body: JSON.stringify(body)});
  return [response.status, await response.json()];
}

// Save a Blob as a file the browser downloads.
function download(name, blob) {
  const link = Object.assign(document.createElement("a"), {href: URL.createObjectURL(blob), download: name});
  document.body.appendChild(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(link.href), 1000);
}

// The server's upload limit [bytes], shown in the element `id` (the pages that upload).
async function uploadLimit(id) {
  const options = await (await fetch("/api/options")).json();
  document.getElementById(id).textContent = mb(options.upload_limit);
  return options.upload_limit;
}

// Upload a recording: its bytes as the body, its name in the query. The answer, or a refusal naming "file".
async function uploadFile(file, limit) {
  if (file.size > limit) return {refused: true, argument: "file", error: `file ${JSON.stringify(file.name)} is ${mb(file.size)}: the upload limit is ${mb(limit)}; analyse it with \`fruitimpact analyze\` instead`};
  const response = await fetch(`/api/upload?name=${encodeURIComponent(file.name)}`, {method: "POST", body: file, headers: {"Content-Type": "application/octet-stream"}});
  const answer = await response.json();
  return response.ok ? answer : {refused: true, argument: "file", error: answer.error || `the server answered ${response.status}`};
}

// Remove the refusals shown in `form`.
function clearFormErrors(form) {
  for (const node of form.querySelectorAll(".field-error")) node.remove();
  for (const node of form.querySelectorAll(".invalid")) node.classList.remove("invalid");
  form.querySelector(".error").hidden = true;
}

// A refusal: the CLI's line next to the control it names (its `data-input`, or #file), else under the form.
function showRefusal(form, body) {
  clearFormErrors(form);
  const name = Array.isArray(body.argument) ? body.argument[0] : body.argument;
  const control = name === "file" ? form.querySelector("input[type=file]") : form.querySelector(`[data-input="${name}"]`);
  if (control && !control.closest("[hidden]")) {
    control.classList.add("invalid");
    const line = Object.assign(document.createElement("p"), {className: "field-error", textContent: body.error});
    control.closest("label").after(line);
  } else {
    const line = form.querySelector(".error");
    line.textContent = body.error;
    line.hidden = false;
  }
}
