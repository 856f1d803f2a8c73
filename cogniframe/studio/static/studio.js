// cogniframe studio: the page's side. Sends the edited values over a WebSocket, shows the figures
// (every element with data-metric="<dotted path in check --json>"), the CLI's message beside a bad
// value's field, the 3D view (the report's viewer, cogniframe/report/viewer/viewer.js) and the
// progress of the background work. Nothing is fetched from anywhere but this server.
import * as THREE from "three";
import { OrbitControls } from "/viewer/OrbitControls.js";
import { start as startViewer } from "/viewer/viewer.js";

const form = document.getElementById("params");
const statusEl = document.getElementById("status");
const saveBtn = document.getElementById("save");
const buildBtn = document.getElementById("build");
const modelEl = document.getElementById("model");
const banner = document.getElementById("error-banner");
const timing = document.getElementById("timing");

const changed = {};          // dotted key -> what the field holds, for every field edited since the last save
let seq = 0;                 // the newest edit sent
let shownSeq = -1;           // the edit the figures show
let lastEdited = null;
let valid = true;
const sentAt = {};           // seq -> performance.now() when sent
window.cogniframeStudio = { latencies: [], events: [] };

const ws = new WebSocket(`ws://${location.host}/ws`);
ws.addEventListener("open", () => setStatus("connected"));
ws.addEventListener("close", () => setStatus("disconnected: restart `cogniframe studio` and reload", "bad"));
ws.addEventListener("message", (m) => handle(JSON.parse(m.data)));

function setStatus(text, cls = "") {
  statusEl.textContent = text;
  statusEl.className = cls;
}

function fieldValue(el) {
  return el.type === "checkbox" ? el.checked : el.value;
}

let timer = null;
function onEdit(ev) {
  const el = ev.target;
  if (!el.name) return;
  changed[el.name] = fieldValue(el);
  lastEdited = el.name;
  clearTimeout(timer);
  timer = setTimeout(send, el.type === "checkbox" || el.tagName === "SELECT" ? 0 : 30);  // typing: one check per pause
}
form.addEventListener("input", onEdit);
form.addEventListener("change", onEdit);

function send() {
  seq += 1;
  sentAt[seq] = performance.now();
  ws.send(JSON.stringify({ type: "edit", seq, values: changed, replace: true, edited: lastEdited }));
  saveBtn.disabled = true;
  setStatus("checking…");
}

function lookup(obj, path) {
  let node = obj;
  for (const part of path.split(".")) {
    if (node === null || node === undefined) return undefined;
    node = Array.isArray(node) ? node[Number(part)] : node[part];
  }
  return node;
}

function format(v, digits) {
  if (v === null || v === undefined) return "–";
  if (typeof v === "number") return digits === undefined ? String(v) : v.toFixed(Number(digits));
  return String(v);
}

function showFigures(ev) {
  const check = ev.check;
  // the peak at the design drop: its index in peak_g.heights, so the element names its real path
  const design = lookup(check, "stiffness.design_drop_height_cm");
  const heights = lookup(check, "peak_g.heights") || [];
  const idx = heights.findIndex((h) => h.height_cm === design);
  for (const el of document.querySelectorAll("[data-metric^='peak_g.heights.']")) {
    if (idx >= 0) el.dataset.metric = `peak_g.heights.${idx}.peak_g`;
  }
  for (const el of document.querySelectorAll("[data-metric]")) {
    el.textContent = format(lookup(check, el.dataset.metric), el.dataset.digits);
  }
  const verdict = document.querySelector(".verdict");
  verdict.dataset.verdict = check.verdict;
  const problems = document.getElementById("problems");
  problems.replaceChildren(...(check.problems || []).map((p) => Object.assign(document.createElement("li"), { textContent: p })));
  modelEl.dataset.model = ev.pending_fe ? "analytic-pending" : (ev.model || "");
  modelEl.textContent = ev.pending_fe ? "fast model (analytic joints): solving the joints' FE…"
    : ev.model === "fe" ? (ev.after_fe ? "FE joints (just solved)" : "FE joints")
    : ev.model === "analytic" ? "analytic joints (model.stiffness_model)" : (ev.model || "");
  document.body.dataset.figuresSeq = String(ev.client);
  document.body.dataset.model = modelEl.dataset.model;
}

function clearErrors() {
  for (const el of form.querySelectorAll(".error[data-error-for]")) { el.hidden = true; el.textContent = ""; }
  for (const el of form.querySelectorAll("[aria-invalid]")) el.removeAttribute("aria-invalid");
  banner.hidden = true;
}

function showError(ev) {
  clearErrors();
  const where = [ev.edited, ev.key].filter((k, i, a) => k && a.indexOf(k) === i);
  let placed = false;
  for (const key of where) {
    const box = form.querySelector(`.error[data-error-for="${CSS.escape(key)}"]`);
    const input = form.querySelector(`[name="${CSS.escape(key)}"]`);
    if (box) { box.textContent = ev.message; box.hidden = false; placed = true; }
    if (input) input.setAttribute("aria-invalid", "true");
  }
  if (!placed) { banner.textContent = ev.message; banner.hidden = false; }
  const first = where.length ? form.querySelector(`.field[data-key="${CSS.escape(where[0])}"]`) : null;
  if (first) first.closest("details")?.setAttribute("open", "");
}

function handle(ev) {
  window.cogniframeStudio.events.push(ev.type);
  if (ev.type === "figures") {
    if (ev.client < seq && !ev.after_fe) return;  // a newer edit is on its way
    shownSeq = ev.client;
    valid = true;
    document.body.dataset.state = "valid";
    clearErrors();
    showFigures(ev);
    if (sentAt[ev.client] !== undefined && !ev.after_fe) {
      const ms = performance.now() - sentAt[ev.client];
      delete sentAt[ev.client];
      window.cogniframeStudio.latencies.push({ seq: ev.client, ms, server_ms: ev.ms, pending_fe: ev.pending_fe });
      timing.textContent = `updated ${ms.toFixed(0)} ms after the edit (check: ${ev.ms.toFixed(0)} ms)`;
    }
    const dirty = Object.keys(changed).length > 0;
    saveBtn.disabled = !dirty;
    setStatus(dirty ? "edited, not saved" : "saved", dirty ? "dirty" : "");
  } else if (ev.type === "invalid") {
    if (ev.client < seq) return;
    valid = false;
    document.body.dataset.state = "invalid";  // the figures shown are the last valid design's
    showError(ev);
    saveBtn.disabled = true;
    setStatus("not saved: fix the value marked in red", "bad");
  } else if (ev.type === "scene") {
    loadScene(ev);
  } else if (ev.type === "progress") {
    progress(ev);
  } else if (ev.type === "saved") {
    for (const k of Object.keys(changed)) delete changed[k];
    saveBtn.disabled = true;
    setStatus(`saved ${ev.path}`, "ok");
  } else if (ev.type === "save-error") {
    setStatus(ev.message, "bad");
  } else if (ev.type === "build-started") {
    document.getElementById("build-box").hidden = false;
    document.getElementById("downloads").replaceChildren();
    buildBtn.disabled = true;
  } else if (ev.type === "built") {
    buildBtn.disabled = false;
    const box = document.getElementById("build-box");
    box.hidden = false;
    box.dataset.verdict = ev.verdict;
    const list = document.getElementById("downloads");
    const head = Object.assign(document.createElement("li"), {
      textContent: `${ev.up_to_date ? "up to date" : "wrote"} ${ev.out_dir} (${ev.count} files), verdict ${ev.verdict}`,
    });
    list.replaceChildren(head, ...ev.files.map((f) => {
      const li = document.createElement("li");
      const a = Object.assign(document.createElement("a"), { href: f.url, textContent: f.name, download: f.name.split("/").pop() });
      if (f.name.endsWith(".html")) { a.removeAttribute("download"); a.target = "_blank"; }
      li.append(a);
      return li;
    }));
    setStatus(`built ${ev.out_dir}`, "ok");
  } else if (ev.type === "build-error") {
    buildBtn.disabled = false;
    document.getElementById("build-box").hidden = false;
    document.getElementById("downloads").replaceChildren(Object.assign(document.createElement("li"), { className: "error", textContent: ev.message }));
    setStatus("build failed", "bad");
  }
}

function progress(ev) {
  const box = document.getElementById(ev.task === "build" ? "build-progress" : "view-progress");
  if (!box) return;
  const bar = box.querySelector("progress");
  const label = box.querySelector("span");
  const active = ev.done < ev.total || (ev.text && ev.done === 0);
  if (ev.task === "view") box.hidden = !active && !ev.error;
  bar.max = Math.max(1, ev.total);
  bar.value = ev.done;
  label.textContent = ev.error ? ev.error : ev.text || "";
  box.dataset.active = active ? "1" : "0";
  box.dataset.error = ev.error || "";
  if (ev.task === "fe" && ev.error && modelEl.dataset.model === "analytic-pending") {
    // the figures stay the fast model's: say so, instead of a wait that never ends
    modelEl.dataset.model = document.body.dataset.model = "analytic-fe-failed";
    modelEl.textContent = `fast model (analytic joints): the joints' FE failed: ${ev.error}`;
  }
}

let sceneKey = null;
async function loadScene(ev) {
  if (ev.key === sceneKey) return;
  const res = await fetch(ev.url);
  if (!res.ok) return;  // replaced by a newer one already
  const data = await res.json();
  sceneKey = ev.key;
  const slot = document.getElementById("view-slot");
  const old = slot.querySelector("canvas");
  if (old) {  // free the old WebGL context now, not when it is collected
    const gl = old.getContext("webgl2") || old.getContext("webgl");
    gl?.getExtension("WEBGL_lose_context")?.loseContext();
  }
  const root = document.createElement("div");
  root.id = "cf-viewer";
  root.className = "cf-viewer";
  root.dataset.objects = String(data.meta.objects.length);
  root.dataset.scene = ev.key;
  const counts = {};
  for (const o of data.meta.objects) counts[o.kind] = (counts[o.kind] || 0) + 1;
  root.innerHTML = `<canvas id="cf-canvas" width="960" height="560" aria-label="3D view of the design"></canvas>
    <div class="cf-bar"><label><input type="checkbox" data-kind="rod" checked> rods (${counts.rod || 0})</label>
    <label><input type="checkbox" data-kind="vitamin" checked> bought parts (${counts.vitamin || 0})</label>
    <button type="button" class="cf-reset">reset view</button></div><div class="cf-info"></div>`;
  slot.replaceChildren(root);
  try {
    startViewer(THREE, OrbitControls, root, data.meta, data.geometry);
  } catch (e) {
    root.dataset.error = String(e);
    root.querySelector(".cf-info").textContent = `The 3D view could not start here (${e}).`;
  }
}

saveBtn.addEventListener("click", () => {
  if (!valid) return;
  ws.send(JSON.stringify({ type: "save" }));
  setStatus("saving…");
});
buildBtn.addEventListener("click", () => {
  ws.send(JSON.stringify({ type: "build" }));
  setStatus("building…");
});
