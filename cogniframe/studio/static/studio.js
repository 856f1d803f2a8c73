// cogniframe studio: the page's side. The design this page shows lives here: the file's text it
// started from (`base`, its hash) and the values changed from it (`changes`), also kept in the
// address (#frame.width=220&...), so a reload, a bookmark or a link shows the same design, and no
// other page can change it. Every message to the server carries both; the server checks them and
// sends back the figures (every element with data-metric="<dotted path in check --json>"), the
// CLI's message beside a bad value's field, the 3D view (the report's viewer, viewer.js) and the
// progress of the background work. Nothing is fetched from anywhere but this server.
import * as THREE from "three";
import { OrbitControls } from "/viewer/OrbitControls.js";
import { start as startViewer } from "/viewer/viewer.js";

const form = document.getElementById("params");
const statusEl = document.getElementById("status");
const saveBtn = document.getElementById("save");
const buildBtn = document.getElementById("build");
const undoBtn = document.getElementById("undo");
const redoBtn = document.getElementById("redo");
const modelEl = document.getElementById("model");
const banner = document.getElementById("error-banner");
const timing = document.getElementById("timing");
const notice = document.getElementById("notice");
const rebaseBtn = document.getElementById("rebase");
const inputs = [...form.querySelectorAll("[name]")];
const byName = new Map(inputs.map((el) => [el.name, el]));
const paramsPath = document.body.dataset.params;

let base = document.body.dataset.base;  // the hash of the file text this page's design starts from
const baseValues = new Map(inputs.map((el) => [el.name, fieldValue(el)]));  // what each field shows for `base`
let seq = 0;                 // the newest edit sent
let valid = true;
let stale = false;           // the file was saved from another page: Save refuses until `rebase`
let editStart = null;        // performance.now() of the first input event not sent yet
const sentAt = {};           // seq -> the first input event of that edit (or the send)
let requests = 0;            // ids of save / rebase / compare
const past = [];             // undo: what every field showed before each edit
const future = [];           // redo
let committed = {};          // what every field showed at the newest edit sent
let wantedScene = null;      // the geometry of the figures shown: the 3D view to show
const sceneUrls = {};        // scenes the server said are ready: key -> url
const standIns = {};         // provisional scenes of geometries whose exact view is not ready yet: key -> event
const geometryAt = {};       // a new geometry's key -> the input event of the edit that asked for it (its view is timed)
let lastFigures = null;
const pendingSaves = {};  // save id -> the changes it saves
window.cogniframeStudio = { latencies: [], sceneLatencies: [], events: [], changes: () => changes(), base: () => base };

const FAST_NAMES = { analytic: "analytic joints", surrogate: "the joints' FE surrogate" };

function fieldValue(el) {
  return el.type === "checkbox" ? (el.checked ? "true" : "false") : el.value;
}

function setField(el, value) {
  if (el.type === "checkbox") el.checked = value === "true";
  else el.value = value;
}

// the values that differ from the file the page started from: the design, in short
function changes() {
  const out = {};
  for (const el of inputs) {
    const v = fieldValue(el);
    if (v !== baseValues.get(el.name)) out[el.name] = v;
  }
  return out;
}

function sendable(state) {  // a checkbox as true/false, everything else as typed
  const out = {};
  for (const [k, v] of Object.entries(state)) out[k] = byName.get(k)?.type === "checkbox" ? v === "true" : v;
  return out;
}

function showState(state) {  // `state`: changed values; the other fields show the file's
  for (const el of inputs) setField(el, Object.hasOwn(state, el.name) ? state[el.name] : baseValues.get(el.name));
}

function fields() {  // what every field shows: undo, redo and snapshots keep this, so a Save between changes nothing
  return Object.fromEntries(inputs.map((el) => [el.name, fieldValue(el)]));
}

function showFields(all) {
  for (const el of inputs) if (Object.hasOwn(all, el.name)) setField(el, all[el.name]);
}

function changesOf(all) {  // the changed values of a full set of fields, against the file this page is on now
  const out = {};
  for (const [k, v] of Object.entries(all)) if (baseValues.has(k) && v !== baseValues.get(k)) out[k] = v;
  return out;
}

function sameState(a, b) {
  const ka = Object.keys(a), kb = Object.keys(b);
  return ka.length === kb.length && ka.every((k) => b[k] === a[k]);
}

// the address holds the changed values only: #frame.width=220&core.battery.mass=70
function stateFromAddress() {
  const state = {}, unknown = [];
  for (const [k, v] of new URLSearchParams(location.hash.slice(1))) {
    if (byName.has(k)) state[k] = v; else unknown.push(k);
  }
  if (unknown.length) showNotice(`The address names values this form does not have (${unknown.slice(0, 5).join(", ")}); they are left out.`);
  return state;
}

function writeAddress(state) {
  const text = new URLSearchParams(Object.entries(state)).toString();
  const url = location.pathname + location.search + (text ? `#${text}` : "");
  if (url !== location.pathname + location.search + location.hash) history.replaceState(null, "", url);
}

function setStatus(text, cls = "") {
  statusEl.textContent = text;
  statusEl.className = cls;
}

// a refusal stays on the page until it is dismissed (the next status does not replace it)
function showNotice(text, { rebase = false } = {}) {
  notice.querySelector(".notice-text").textContent = text;
  rebaseBtn.hidden = !rebase;
  notice.hidden = false;
}
document.getElementById("dismiss").addEventListener("click", () => { notice.hidden = true; });

function showDirty() {
  const dirty = Object.keys(changes()).length > 0;
  saveBtn.disabled = !valid || !dirty;
  undoBtn.disabled = past.length === 0;
  redoBtn.disabled = future.length === 0;
  return dirty;
}

const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(document.body.dataset.token)}`);
ws.addEventListener("open", () => { setStatus("connected"); send(); });
ws.addEventListener("close", () => setStatus("disconnected: restart `cogniframe studio` and reload (your edits are in the address)", "bad"));
ws.addEventListener("message", (m) => handle(JSON.parse(m.data)));

function post(message) {
  if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(message));
}

let timer = null;
let lastEdited = null;
function onEdit(ev) {
  const el = ev.target;
  if (!el.name) return;
  lastEdited = el.name;
  if (editStart === null) editStart = performance.now();
  clearTimeout(timer);
  timer = setTimeout(commit, el.type === "checkbox" || el.tagName === "SELECT" ? 0 : 30);  // typing: one check per pause
}
form.addEventListener("input", onEdit);
form.addEventListener("change", onEdit);

function commit() {  // an edit: into the undo history, the address, and to the server
  if (sameState(fields(), committed)) { editStart = null; return; }  // e.g. the change event of a field left: nothing new
  past.push(committed);
  future.length = 0;
  send();
}

function send() {
  clearTimeout(timer);
  const state = changes();
  committed = fields();
  writeAddress(state);
  seq += 1;
  sentAt[seq] = editStart ?? performance.now();
  editStart = null;
  post({ type: "edit", seq, base, values: sendable(state), edited: lastEdited });
  showDirty();
  saveBtn.disabled = true;  // until this edit's figures say it is valid
  setStatus("checking…");
}

function undo() {
  if (!past.length) return;
  future.push(fields());
  showFields(past.pop());
  lastEdited = null;
  send();
}
function redo() {
  if (!future.length) return;
  past.push(fields());
  showFields(future.pop());
  lastEdited = null;
  send();
}
undoBtn.addEventListener("click", undo);
redoBtn.addEventListener("click", redo);
document.addEventListener("keydown", (e) => {
  if (!(e.ctrlKey || e.metaKey) || e.key.toLowerCase() !== "z" || e.target.closest?.("input, select, textarea")) return;
  e.preventDefault();
  (e.shiftKey ? redo : undo)();
});

// leaving with unsaved edits asks first (a reload keeps them: they are in the address)
window.addEventListener("beforeunload", (e) => {
  if (Object.keys(changes()).length === 0) return;
  e.preventDefault();
  e.returnValue = "";
});

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
  // the fast model: the closed forms, or the FE's surrogate for a link with none (the pegs)
  modelEl.dataset.model = ev.pending_fe ? `${ev.model}-pending` : (ev.model || "");
  modelEl.textContent = ev.pending_fe ? `fast model (${FAST_NAMES[ev.model] || ev.model}): solving the joints' FE…`
    : ev.model === "fe" ? (ev.after_fe ? "FE joints (just solved)" : "FE joints")
    : ev.model === "analytic" ? "analytic joints (model.stiffness_model)" : (ev.model || "");
  document.body.dataset.figuresSeq = String(ev.seq);
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
    if (ev.seq < seq) return;  // a newer edit is on its way
    valid = true;
    lastFigures = ev;
    document.body.dataset.state = "valid";
    clearErrors();
    showFigures(ev);
    if (sentAt[ev.seq] !== undefined && !ev.after_fe) {
      const ms = performance.now() - sentAt[ev.seq];
      if (ev.geometry !== sceneKey && geometryAt[ev.geometry] === undefined) geometryAt[ev.geometry] = sentAt[ev.seq];
      delete sentAt[ev.seq];
      window.cogniframeStudio.latencies.push({ seq: ev.seq, ms, server_ms: ev.ms, cpu_ms: ev.cpu_ms, pending_fe: ev.pending_fe });
      timing.textContent = `updated ${ms.toFixed(0)} ms after the edit (check: ${ev.ms.toFixed(0)} ms)`;
    }
    wantedScene = ev.geometry;
    if (sceneUrls[wantedScene]) loadScene({ key: wantedScene, url: sceneUrls[wantedScene] });
    else if (standIns[wantedScene]) loadScene(standIns[wantedScene]);
    const dirty = showDirty();
    if (dirty || !statusEl.textContent.startsWith("saved")) setStatus(dirty ? "edited, not saved" : "as in the file", dirty ? "dirty" : "");
  } else if (ev.type === "invalid") {
    if (ev.seq < seq) return;
    valid = false;
    document.body.dataset.state = "invalid";  // the figures shown are the last valid design's
    showError(ev);
    showDirty();
    setStatus("not saved: fix the value marked in red", "bad");
  } else if (ev.type === "refused") {
    showNotice(ev.message);
    setStatus("refused", "bad");
  } else if (ev.type === "scene") {
    if (ev.provisional) {  // the new frame at once; its exact view follows and replaces it
      if (sceneUrls[ev.key]) return;
      standIns[ev.key] = ev;
    } else {
      sceneUrls[ev.key] = ev.url;
      delete standIns[ev.key];
    }
    if (ev.key === wantedScene) loadScene(ev);
  } else if (ev.type === "progress") {
    if (ev.task === "view" && ev.key && ev.key !== wantedScene) return;  // another page's view
    progress(ev);
  } else if (ev.type === "saved") {
    const saved = pendingSaves[ev.id] || {};
    delete pendingSaves[ev.id];
    base = ev.base;
    document.body.dataset.base = base;
    for (const [k, v] of Object.entries(saved)) baseValues.set(k, v);
    stale = false;
    const dirty = showDirty();
    writeAddress(changes());
    setStatus(dirty ? `saved ${ev.path} (edits made since are not saved)` : `saved ${ev.path}`, dirty ? "dirty" : "ok");
    document.body.dataset.saved = String(ev.id);
  } else if (ev.type === "save-error") {
    delete pendingSaves[ev.id];
    showNotice(ev.message, { rebase: ev.reason === "changed-on-disk" });
    setStatus("not saved", "bad");
  } else if (ev.type === "file-saved") {
    if (ev.base === base) return;
    stale = true;
    if (Object.keys(changes()).length === 0) { rebase(); return; }  // nothing to lose: follow the file
    showNotice(`Another page saved ${ev.path}. This page's edits are not in it, and its Save refuses until you take the saved file under them.`,
      { rebase: true });
  } else if (ev.type === "rebased") {
    const state = changes();  // this page's edits, put on the file as it is now
    base = ev.base;
    document.body.dataset.base = base;
    for (const [k, v] of Object.entries(ev.values)) if (baseValues.has(k)) baseValues.set(k, v);
    past.push(fields());
    future.length = 0;
    showState(state);
    stale = false;
    notice.hidden = true;
    send();
  } else if (ev.type === "rebase-error") {
    showNotice(ev.message, { rebase: true });
  } else if (ev.type === "compared") {
    showCompare(ev);
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
    showNotice(ev.message);
    setStatus("build failed", "bad");
  }
}

function rebase() {
  requests += 1;
  post({ type: "rebase", id: requests });
}
rebaseBtn.addEventListener("click", rebase);

// what a provisional view shows, in words (it goes when the exact view is drawn)
function showViewNote(ev) {
  let note = document.getElementById("view-note");
  if (!note) {
    note = Object.assign(document.createElement("p"), { id: "view-note", className: "view-note" });
    note.setAttribute("role", "status");
    document.getElementById("view-slot").before(note);
  }
  document.body.dataset.view = ev.provisional ? "provisional" : "exact";
  note.hidden = !ev.provisional;
  if (!ev.provisional) { note.textContent = ""; return; }
  const changed = ev.changed || [], missing = ev.missing || [];
  note.textContent = `Provisional view of the new frame: the rods, bought parts and unchanged printed parts are exact; `
    + (changed.length ? `${changed.length} changed part${changed.length > 1 ? "s" : ""} (${changed.join(", ")}) `
      + `${changed.length > 1 ? "are" : "is"} drawn pale: the previous shape at the new place, grams estimated. ` : "")
    + (missing.length ? `Not shown yet: ${missing.join(", ")}. ` : "")
    + "The exact parts replace them when made.";
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
  if (ev.task === "view" && ev.error && sceneProvisional && ev.key === sceneKey) {  // no exact view follows: say so
    const note = document.getElementById("view-note");
    if (note) note.textContent = note.textContent.replace(/The exact parts replace them when made\.$/,
      `The exact parts could not be made (${ev.error}); the pale parts stay provisional.`);
  }
  if (ev.task === "fe" && ev.error && modelEl.dataset.model.endsWith("-pending")) {
    // the figures stay the fast model's: say so, instead of a wait that never ends
    const fast = modelEl.dataset.model.slice(0, -"-pending".length);
    modelEl.dataset.model = document.body.dataset.model = `${fast}-fe-failed`;
    modelEl.textContent = `fast model (${FAST_NAMES[fast] || fast}): the joints' FE failed: ${ev.error}`;
  }
}

let sceneKey = null;
let sceneProvisional = false;  // the view drawn is a provisional one (its exact one still to come)
const loading = new Set();     // urls being fetched
// drawn already: the same geometry, unless a provisional view gives way to the exact one
const drawn = (ev) => ev.key === sceneKey && (Boolean(ev.provisional) || !sceneProvisional);
async function loadScene(ev) {
  if (drawn(ev) || loading.has(ev.url)) return;
  loading.add(ev.url);
  let data = null;
  try {
    const res = await fetch(ev.url);
    if (res.ok) data = await res.json();  // else: replaced by a newer one already
  } finally {
    loading.delete(ev.url);
  }
  // meanwhile: another geometry wanted, this one drawn, or the exact view known (a provisional one is not drawn over it)
  if (!data || ev.key !== wantedScene || drawn(ev) || (ev.provisional && sceneUrls[ev.key])) return;
  sceneKey = ev.key;
  sceneProvisional = Boolean(ev.provisional);
  showViewNote(ev);
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
  root.dataset.provisional = ev.provisional ? "1" : "0";
  const counts = {};
  for (const o of data.meta.objects) counts[o.kind] = (counts[o.kind] || 0) + 1;
  root.innerHTML = `<canvas id="cf-canvas" width="960" height="560" aria-label="3D view of the design"></canvas>
    <div class="cf-bar"><label><input type="checkbox" data-kind="rod" checked> rods (${counts.rod || 0})</label>
    <label><input type="checkbox" data-kind="vitamin" checked> bought parts (${counts.vitamin || 0})</label>
    <button type="button" class="cf-reset">reset view</button></div><div class="cf-info"></div>`;
  slot.replaceChildren(root);
  try {
    startViewer(THREE, OrbitControls, root, data.meta, data.geometry);
    const t0 = geometryAt[ev.key];
    if (t0 !== undefined) {  // drawn: from the edit's input event to this view
      window.cogniframeStudio.sceneLatencies.push({ key: ev.key, ms: performance.now() - t0, provisional: Boolean(ev.provisional) });
      if (!ev.provisional) delete geometryAt[ev.key];
    }
  } catch (e) {
    root.dataset.error = String(e);
    root.querySelector(".cf-info").textContent = `The 3D view could not start here (${e}).`;
  }
}


saveBtn.addEventListener("click", () => {
  if (!valid) return;
  const state = changes();
  requests += 1;
  pendingSaves[requests] = state;
  post({ type: "save", id: requests, base, values: sendable(state) });
  setStatus("saving…");
});
buildBtn.addEventListener("click", () => {
  post({ type: "build", base, values: sendable(changes()) });
  setStatus("building…");
});

// -- snapshots and compare: kept in this browser (localStorage), per params file --------------------
const snapKey = `cogniframe-studio:snapshots:${paramsPath}`;
const compareRows = JSON.parse(document.body.dataset.compareRows);

function snapshots() {
  try { return JSON.parse(localStorage.getItem(snapKey) || "[]"); } catch { return []; }
}

function storeSnapshots(list) {
  try { localStorage.setItem(snapKey, JSON.stringify(list)); } catch (e) { showNotice(`The snapshot could not be kept: ${e}`); }
  listSnapshots();
}

function listSnapshots() {
  const ul = document.getElementById("snapshots");
  const items = [["now", "now (this page's design)"], ...snapshots().map((s, i) => [String(i), s.name])];
  ul.replaceChildren(...items.map(([id, name]) => {
    const li = document.createElement("li");
    li.dataset.snapshot = id;
    const box = Object.assign(document.createElement("input"), { type: "checkbox", value: id, title: "compare this one" });
    const label = Object.assign(document.createElement("label"), { textContent: ` ${name}` });
    label.prepend(box);
    li.append(label);
    if (id !== "now") {
      const open = Object.assign(document.createElement("button"), { type: "button", textContent: "open", className: "snap-open",
        title: "show this design in the form (Undo goes back)" });
      open.addEventListener("click", () => {
        const snap = snapshots()[Number(id)];
        past.push(fields());
        future.length = 0;
        showFields(snap.fields);
        send();
      });
      const del = Object.assign(document.createElement("button"), { type: "button", textContent: "delete", className: "snap-delete" });
      del.addEventListener("click", () => storeSnapshots(snapshots().filter((_, j) => j !== Number(id))));
      li.append(" ", open, " ", del);
    }
    return li;
  }));
}

document.getElementById("snapshot-take").addEventListener("click", () => {
  const input = document.getElementById("snapshot-name");
  const list = snapshots();
  const name = input.value.trim() || `snapshot ${list.length + 1}`;
  list.push({ name, fields: fields() });
  input.value = "";
  storeSnapshots(list);
});

document.getElementById("compare-go").addEventListener("click", () => {
  const picked = [...document.querySelectorAll("#snapshots input:checked")].map((b) => b.value);
  if (picked.length < 2) { showNotice("Tick two or more designs to compare."); return; }
  const list = snapshots();
  // each design as its fields' values on the file this page is on now
  const designs = picked.map((id) => id === "now" ? { name: "now", base, values: sendable(changes()) }
    : { name: list[Number(id)].name, base, values: sendable(changesOf(list[Number(id)].fields || {})) });
  requests += 1;
  post({ type: "compare", id: requests, designs });
  document.getElementById("compare").replaceChildren(Object.assign(document.createElement("p"), { className: "note", textContent: "comparing…" }));
});

function showCompare(ev) {
  const table = document.createElement("table");
  table.className = "compare";
  const head = table.createTHead().insertRow();
  head.append(document.createElement("th"));
  for (const c of ev.columns) head.append(Object.assign(document.createElement("th"), { textContent: c.name }));
  const body = table.createTBody();
  for (const [key, label, unit, digits] of compareRows) {
    const row = body.insertRow();
    row.dataset.row = key;
    row.append(Object.assign(document.createElement("th"), { textContent: unit ? `${label} (${unit})` : label }));
    const texts = ev.columns.map((c) => c.error ? "–" : format(c.figures[key], digits ?? undefined));
    ev.columns.forEach((c, i) => {
      const td = row.insertCell();
      td.textContent = texts[i];
      if (c.error) { td.className = "error"; td.title = c.error; }
      else if (texts.some((t) => t !== texts[0])) td.classList.add("differs");  // the row differs: highlighted
      if (key === "verdict") td.dataset.verdict = texts[i];
    });
  }
  const box = document.getElementById("compare");
  box.replaceChildren(table, ...ev.columns.filter((c) => c.error).map((c) =>
    Object.assign(document.createElement("p"), { className: "error", textContent: `${c.name}: ${c.error}` })));
}

// the design in the address (a link, a bookmark, a reload) before the first edit is sent
showState(stateFromAddress());
committed = fields();
listSnapshots();
