// brainpainter's page: upload -> check report -> live preview -> jobs. Plain JS, no build step,
// nothing from outside this server (the Content-Security-Policy allows only 'self').
"use strict";

const $ = (id) => document.getElementById(id);
const state = { uploadId: null, files: null, name: null, report: null, meta: null, isMap: false,
                previewCtl: null, previewTimer: null, previewUrl: null, seq: 0, scale: null,
                tractsId: null, tractReport: null, tractFiles: null, summary: "", layers: [],
                mapId: null, mapReport: null, contourId: null, contourReport: null,
                connectomeId: null, connectomeReport: null };
const DEFAULT_VIEWS = ["lateral-left", "medial-left", "subcortical"];
const MAP_VIEWS = ["lateral-left", "medial-left", "lateral-right", "medial-right"];  // a map's default
const TRACT_VIEWS = ["subcortical", "subcortical-dorsal"];  // tracts alone: the views that show them
const CONNECTOME_VIEWS = ["dorsal", "lateral-left"];  // a connectome alone: through the glass cortex
const CONNECTOME_ROLES = { "connectome-matrix": "matrix", "connectome-nodes": "nodes",
                           "connectome-values": "node_values", "connectome-categories": "node_categories" };

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") node.textContent = v;
    else if (v !== null && v !== undefined && v !== false) node.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) node.append(c);
  return node;
}

// Messages in their own place: an upload's refusal beside its field (kept until that field's next upload
// is accepted or removed), a preview's or a job's error in their panel.
function say(id, message) {
  const box = $(id);
  box.textContent = message || "";
  box.hidden = !message;
}
const showError = (message) => say("error", message);
const showPreviewError = (message) => say("preview-error", message);

// A number for people: 4 significant digits (-4.699817180633545 -> -4.7).
function fmt(x) {
  return typeof x === "number" && Number.isFinite(x) ? String(Number(x.toPrecision(4))) : String(x);
}

// The server's messages name CLI flags (--vmin); the page names its fields (“vmin”).
function pageWords(text) {
  return String(text).replace(/--([a-z][a-z-]*)/g, (flag, name) => {
    const label = document.querySelector(`label[for="${name.replace(/-/g, "_")}"]`);
    return label ? `“${label.textContent.trim()}”` : flag;
  });
}

// An option error names a CLI flag (--size) or an API field (options.size, movie.hold): shown next to
// that field, under the field's label, and the message says the label instead of the flag.
function fieldError(message) {
  for (const old of document.querySelectorAll(".field-error")) old.remove();
  for (const n of document.querySelectorAll("[aria-invalid]")) {
    n.removeAttribute("aria-invalid"); n.removeAttribute("aria-errormessage");
  }
  if (!message) return message;
  // a message about a value names the core setting ("width must be ..."): the field that sets it
  const SETTING = { width: "size", height: "size", azimuth: "views", elevation: "views", zoom: "views" };
  const m = message.match(/--([a-z][a-z-]*)/) || message.match(/'(?:options|movie|figure)\.([a-z_]+)'/);
  const w = m ? null : message.match(/^([a-z_]+) must\b/);
  const id = m ? m[1].replace(/-/g, "_") : w ? (SETTING[w[1]] || w[1]) : null;
  const input = id ? $(id) : null;
  if (!input) return message;
  const label = document.querySelector(`label[for="${id}"]`) || input.closest("fieldset")?.querySelector("legend");
  const name = label ? label.textContent.trim() : id;
  const text = m ? message.split(m[0]).join(`“${name}”`) : `“${name}”: ${message}`;
  const note = el("div", { class: "field-error", id: `${id}-error`, role: "alert", text });
  input.setAttribute("aria-invalid", "true"); input.setAttribute("aria-errormessage", note.id);
  input.insertAdjacentElement("afterend", note);
  const details = input.closest("details");
  if (details) details.open = true;
  return text;
}

// The colour bars under the preview, one per layer with a scale of its own (the check report's layers,
// as render's figures draw them): its label, colours from vmin to vmax and ticks, or a label map's key.
function showBars(layers) {
  const shown = (layers || []).filter((l) => l.scale && l.scale.ramp);
  const extra = $("layer-bars");
  extra.replaceChildren();
  if (!shown.length) { $("preview-bar").hidden = true; return; }
  fillBar($("preview-bar"), shown[0]);
  for (const layer of shown.slice(1)) {
    const bar = el("div", { class: "cbar", role: "img" }, el("div", { class: "cbar-label" }),
                   el("div", { class: "ramp" }), el("div", { class: "ticks" }));
    fillBar(bar, layer);
    extra.append(bar);
  }
}

function fillBar(bar, layer) {
  const scale = layer.scale;
  bar.querySelector(".cbar-label").textContent = shownLabel(layer);
  const ramp = bar.querySelector(".ramp"), ticks = bar.querySelector(".ticks");
  const key = (scale.categories || []).length > 0;
  ramp.hidden = key;
  ramp.style.background = `linear-gradient(to right, ${scale.ramp.join(", ")})`;
  ticks.className = key ? "key" : "ticks";
  ticks.replaceChildren(...(key ? scale.categories.slice(0, 40).map((c) => {
    const span = el("span", { text: c.name });
    span.style.setProperty("--swatch", c.color);
    return span;
  }) : scale.ticks.map((t) => {
    const span = el("span", { text: t.label });
    span.style.left = `${(100 * t.at).toFixed(2)}%`;
    return span;
  })));
  const said = key ? `key of ${scale.categories.length} labels` : scale.ticks.map((t) => t.label).join(", ");
  bar.setAttribute("aria-label", `Colour bar of ${shownLabel(layer)} (${scale.name}): ${said}`);
  bar.hidden = !$("preview").src;
}

// a layer's label as the page shows it: the layer's kind with its label (a file name, or the one given)
function shownLabel(layer) {
  const kind = { regions: "Regions", map: "Map", tracts: "Tracts", edges: "Edges", nodes: "Nodes" }[layer.kind]
    || layer.kind;
  return layer.label ? `${kind}: ${layer.label}` : kind;
}

async function api(path, opts = {}) {
  const res = await fetch(path, opts);
  if (!res.ok) {
    let msg = `${res.status} ${res.statusText}`;
    try { const j = await res.json(); if (j.error) msg = j.error; } catch (e) { /* not JSON */ }
    const err = new Error(msg); err.status = res.status; throw err;
  }
  return res;
}

// -- the form ----------------------------------------------------------------------------
function viewIcon(name) {
  // A top view of the head (nose up) with the camera's direction, or a side glyph for views from above/below.
  const ns = "http://www.w3.org/2000/svg";
  const svg = document.createElementNS(ns, "svg");
  svg.setAttribute("width", "22"); svg.setAttribute("height", "22"); svg.setAttribute("viewBox", "-11 -11 22 22");
  svg.setAttribute("aria-hidden", "true");
  const head = document.createElementNS(ns, "ellipse");
  head.setAttribute("rx", "6"); head.setAttribute("ry", "7.5");
  head.setAttribute("fill", name.startsWith("subcortical") ? "#f3e1c9" : "#e7b8a8");
  head.setAttribute("stroke", "#555"); head.setAttribute("stroke-width", "1");
  svg.append(head);
  const az = { "lateral-left": 180, "medial-left": 0, "lateral-right": 0, "medial-right": 180,
               anterior: 90, posterior: 270, subcortical: 160, "subcortical-left": 180 }[name];
  if (az !== undefined) {
    const a = (az * Math.PI) / 180, x = 9.5 * Math.cos(a), y = -9.5 * Math.sin(a);
    const dot = document.createElementNS(ns, "circle");
    dot.setAttribute("cx", x.toFixed(1)); dot.setAttribute("cy", y.toFixed(1)); dot.setAttribute("r", "2.2");
    dot.setAttribute("fill", "#1a5fb4");
    svg.append(dot);
  } else {
    const mark = document.createElementNS(ns, "text");
    mark.setAttribute("text-anchor", "middle"); mark.setAttribute("dy", "3.5"); mark.setAttribute("font-size", "9");
    mark.textContent = name.startsWith("flat") ? "▭" : name.includes("dorsal") ? "↓" : "↑";
    svg.append(mark);
  }
  return svg;
}

function fillForm(meta) {
  for (const a of meta.atlases) $("atlas").append(el("option", { value: a, text: a }));
  for (const a of meta.atlases) $("outline").append(el("option", { value: a, text: a }));
  for (const c of meta.cmaps) $("cmap").append(el("option", { value: c, text: c, selected: c === "viridis" }));
  for (const kind of ["map", "tracts"]) layerFields(kind, meta.cmaps);
  const views = $("views");
  for (const v of meta.views) {
    const box = el("input", { type: "checkbox", name: "views", value: v, checked: DEFAULT_VIEWS.includes(v) });
    views.append(el("label", {}, box, viewIcon(v), v));
  }
  for (const g of meta.hide_groups) {
    $("hide-groups").append(el("label", { class: "check" },
      el("input", { type: "checkbox", name: "hide-group", value: g }), g));
  }
  for (const v of meta.views) $("pview").append(el("option", { value: v, text: v }));
  for (const s of meta.tract_spaces || []) $("tracts_space").append(el("option", { value: s, text: s }));
  for (const c of meta.cortex_modes || []) $("cortex").append(el("option", { value: c, text: c }));
  const d = meta.defaults;
  $("size").value = d.size ?? ""; $("glass_opacity").value = d.glass_opacity;
  if (d.tracts_space) $("tracts_space").value = d.tracts_space;
  if (d.cortex) $("cortex").value = d.cortex;
  if (d.max_streamlines) $("max_streamlines").value = d.max_streamlines;
  if (meta.limits.max_streamlines) $("max_streamlines").max = meta.limits.max_streamlines;
}

function numberOrNull(id) {
  const v = $(id).value.trim();
  return v === "" ? null : Number(v);
}

function textOrNull(id) {
  const v = $(id).value.trim();
  return v === "" ? null : v;
}

function options() {
  const useCmap = $("use-cmap").checked;
  const views = [...document.querySelectorAll('input[name="views"]:checked')].map((b) => b.value);
  const hide = [...document.querySelectorAll('input[name="hide-group"]:checked')].map((b) => b.value);
  const more = $("hide").value.split(",").map((s) => s.trim()).filter(Boolean);
  return {
    atlas: textOrNull("atlas"), image_column: textOrNull("image_column"), value: textOrNull("value"),
    region_column: textOrNull("region_column"), strict: $("strict").checked,
    views: views.join(",") || "lateral-left", surface: $("surface").value,
    gradient: useCmap ? null : textOrNull("gradient"), cmap: useCmap ? $("cmap").value : null,
    vmin: numberOrNull("vmin"), vmax: numberOrNull("vmax"), center: numberOrNull("center"),
    nan_color: $("nan_color").value, missing_color: $("missing_color").value,
    hide: [...hide, ...more], background: $("background").value, transparent: $("transparent").checked,
    size: $("size").value.trim(), quality: $("quality").value, shading: $("shading").value,
    lighting: $("lighting").value, glass_opacity: Number($("glass_opacity").value || 0),
    underlay: $("underlay").value, threshold: numberOrNull("threshold"), outline: textOrNull("outline"),
    outline_threshold: $("outline_threshold").checked, outline_width: Number($("outline_width").value || 0),
    outline_color: $("outline_color").value, outline_style: $("outline_style").value,
    contour_width: Number($("contour_width").value || 0), contour_color: textOrNull("contour_color"),
    contour_style: $("contour_style").value,
    // a volume upload drawn as blobs; cut-away planes ("x<0; z>20")
    volume_surface: state.isMap && $("volume_surface").checked,
    min_cluster_mm3: Number($("min_cluster_mm3").value || 0),
    clip: $("clip").value.split(/[;,]/).map((s) => s.trim()).filter(Boolean),
    // tracts: drawn with the table (the table is the upload), or alone (the tract upload is the upload)
    tracts: state.tractsId && state.tractsId !== state.uploadId ? state.tractsId : null,
    tracts_space: $("tracts_space").value || undefined, cortex: $("cortex").value || undefined,
    tracts_affine: textOrNull("tracts_affine"), max_streamlines: numberOrNull("max_streamlines") ?? undefined,
    tract_radius: numberOrNull("tract_radius"), tract_value: textOrNull("tract_value"),
    // a connectome: drawn with the table (option connectome), or alone (the connectome is the upload)
    connectome: state.connectomeId && state.connectomeId !== state.uploadId ? state.connectomeId : null,
    edge_threshold: textOrNull("edge_threshold"), top_edges: numberOrNull("top_edges"),
    edges_of: textOrNull("edges_of"), directed: $("directed").checked,
    node_labels: $("node_labels").checked, node_labels_top: numberOrNull("node_labels_top"),
    node_labels_per_category: $("node_labels_per_category").checked,
    ...layerOptions(),
  };
}

// -- layers: each upload's own colours (regions_*, map_*, tracts_*: the API's LayerOptions fields) ------
const LAYER_NAMES = { map: "Map", tracts: "Tracts" };

// The first layer: what the main upload is (its colours are the plain ones).
function mainKind() {
  if (state.isMap) return "map";
  if (state.uploadId && state.uploadId === state.connectomeId) return "edges";
  return state.uploadId && state.uploadId === state.tractsId ? "tracts" : "regions";
}

// Which layers are drawn over the main upload: a map over a table, tracts with a table or a map.
function overLayers() {
  const table = Boolean(state.uploadId) && mainKind() === "regions";
  return { map: table && Boolean(state.mapId),
           tracts: Boolean(state.uploadId) && mainKind() !== "tracts" && Boolean(state.tractsId) };
}

function layerOptions() {
  const out = { [`${mainKind()}_label`]: textOrNull("main_label") };
  const over = overLayers();
  if (over.map) out.map = state.mapId;
  if (state.contourId && (state.isMap || over.map)) {
    out.contour = state.contourId; out.contour_levels = textOrNull("contour_levels");
  }
  for (const kind of ["map", "tracts"]) {
    if (!over[kind]) continue;
    const cmap = textOrNull(`${kind}_cmap`);
    Object.assign(out, { [`${kind}_cmap`]: cmap, [`${kind}_vmin`]: numberOrNull(`${kind}_vmin`),
                         [`${kind}_vmax`]: numberOrNull(`${kind}_vmax`),
                         [`${kind}_center`]: numberOrNull(`${kind}_center`),
                         [`${kind}_label`]: textOrNull(`${kind}_label`) });
    if (kind === "map") out.map_alpha = Number($("map_alpha").value || 1);
  }
  return out;
}

// A layer's colour fields beside its upload: colour map (empty: the plain colours), range, label.
function layerFields(kind, cmaps) {
  const name = LAYER_NAMES[kind];
  const box = $(`${kind}-scale`);
  const field = (id, text, input) => el("div", {}, el("label", { for: id, text }), input);
  const cmap = el("select", { id: `${kind}_cmap`, name: `${kind}_cmap` },
                  el("option", { value: "", text: "as the main colours" }),
                  ...cmaps.map((c) => el("option", { value: c, text: c })));
  const number = (suffix, extra = {}) => el("input", { id: `${kind}_${suffix}`, name: `${kind}_${suffix}`,
                                                       type: "number", step: "any", ...extra });
  box.append(el("p", { class: "label", text: `${name}: its own colours` }),
    el("div", { class: "grid2" },
      field(`${kind}_cmap`, `${name} colour map`, cmap),
      field(`${kind}_label`, `${name} colour-bar label`,
            el("input", { id: `${kind}_label`, name: `${kind}_label`, maxlength: "200" })),
      field(`${kind}_vmin`, `${name} vmin`, number("vmin")), field(`${kind}_vmax`, `${name} vmax`, number("vmax")),
      field(`${kind}_center`, `${name} centre`, number("center")),
      ...(kind === "map" ? [field("map_alpha", "Map opacity (0-1)",
                                  number("alpha", { min: "0", max: "1", step: "0.05", value: "1" }))] : [])));
  for (const ev of ["input", "change"]) box.addEventListener(ev, () => schedulePreview());
}

// A map drawn over the table (option map) or a contour map (option contour): an upload of its own (POST
// /api/uploads, as the main one); `kind` is "map" or "contour", the prefix of its fields and state.
async function uploadLayerMap(kind, files) {
  const q = new URLSearchParams();
  for (const f of files) q.append("name", f.name);
  if (files.length > 1) for (const f of files) q.append("size", String(f.size));
  const shown = files.map((f) => f.name).join(" + ");
  say(`${kind}-error`, "");
  $(`${kind}-status`).textContent = `Checking ${shown}…`;
  try {
    const res = await api(`/api/uploads?${q}`, { method: "POST", body: new Blob(files.map((f) => f.blob)),
                                                 headers: { "content-type": "application/octet-stream" } });
    const j = await res.json();
    if (j.report.kind !== "map") throw new Error(`${shown} is a table; give a map here (or upload it above)`);
    state[`${kind}Id`] = j.upload_id; state[`${kind}Report`] = j.report;
    $(`${kind}-status`).textContent = `OK: ${j.report.summary}`;
    $(`${kind}-clear`).disabled = false;
    showFieldsets();
    schedulePreview(0);
  } catch (e) {
    say(`${kind}-error`, refused(shown, e.message));
    const kept = state[`${kind}Report`];
    $(`${kind}-status`).textContent = kept ? `Still drawn: ${kept.summary}` : `No ${kind} is drawn.`;
  }
}

function clearLayerMap(kind) {
  state[`${kind}Id`] = null; state[`${kind}Report`] = null;
  $(`${kind}-status`).textContent = ""; $(`${kind}-clear`).disabled = true; $(`${kind}-files`).value = "";
  say(`${kind}-error`, "");
  showFieldsets();
  schedulePreview(0);
}

// -- upload and the check report ----------------------------------------------------------
// `files`: one table, or a map (one or two files: lh and rh, or one volume), sent one after the
// other in one body with their names and sizes; the server tells a map from a table by the names.
const GRADIENT = "white,yellow,orange,red";

// "x.csv was refused: ...", without the server's own "x.csv: " in front
function refused(shown, message) {
  const m = String(message);
  return `${shown} was refused: ${m.startsWith(`${shown}: `) ? m.slice(shown.length + 2) : m}`;
}

async function upload(files) {
  const names = files.map((f) => f.name);
  const shown = names.join(" + ");
  $("file-name").textContent = `Checking ${shown}…`;
  showError(""); fieldError("");
  const o = options();
  const q = new URLSearchParams();
  for (const n of names) q.append("name", n);
  if (files.length > 1) for (const f of files) q.append("size", String(f.size));
  for (const k of ["atlas", "image_column", "value", "region_column"]) if (o[k]) q.set(k, o[k]);
  if (o.strict) q.set("strict", "true");
  setReady(false);
  $("report").textContent = "Checking…";
  try {
    const res = await api(`/api/uploads?${q}`, { method: "POST", body: new Blob(files.map((f) => f.blob)),
                                                 headers: { "content-type": "application/octet-stream" } });
    const j = await res.json();
    state.files = files; state.name = shown;
    $("file-name").textContent = shown;
    state.uploadId = j.upload_id; state.report = j.report;
    state.isMap = j.report.kind === "map";
    // a map's own default colours (viridis, RdBu_r for signed values) unless the user chose a gradient
    if (state.isMap && $("gradient").value === GRADIENT && $("use-gradient").checked) $("gradient").value = "";
    if (!state.isMap && $("gradient").value === "") $("gradient").value = GRADIENT;
    setDefaultViews(state.isMap ? MAP_VIEWS : DEFAULT_VIEWS);
    showReport(j.report);
    fillRows(j.images, j.report.n_images);
    showFieldsets();
    setReady(true);
    schedulePreview(0);
  } catch (e) {
    // the last good upload stays in use (its report, rows and preview), or the page says there is none
    if (state.uploadId) {
      $("file-name").textContent = `In use: ${state.name}`;
      showError(`${refused(shown, e.message)} Still in use: ${state.name}.`);
      showReport(state.report);
      setReady(true);
    } else {
      $("file-name").textContent = "";
      showError(refused(shown, e.message));
      $("report").textContent = "";
      noUpload();
    }
  }
}

// Nothing to draw: no image, no colour bar, no command, and a caption that says so.
function noUpload() {
  $("preview").hidden = true; showBars([]); $("reproduce").hidden = true; $("preview-reproduce").hidden = true;
  state.previewShown = false;
  $("preview-status").textContent = "No table or map in use: upload one to see a preview.";
  $("row").replaceChildren();
  setReady(false);
}

// Only the options that apply to what was uploaded (all of them before any upload).
function showFieldsets() {
  const any = Boolean(state.uploadId || state.tractsId || state.connectomeId);
  $("tract-options").hidden = any && !state.tractsId;
  $("connectome-options").hidden = any && !state.connectomeId;
  const over = overLayers();
  $("map-box").hidden = any && (state.isMap || mainKind() === "tracts");
  $("contour-box").hidden = any && !state.isMap && !over.map;
  $("map-scale").hidden = !over.map; $("tracts-scale").hidden = !over.tracts;
  const maps = !any || state.isMap || over.map;
  for (const n of document.querySelectorAll("[data-map-only]")) n.hidden = !maps;
  $("map-options").querySelector("legend").textContent = maps ? "Maps and outlines" : "Outlines";
}

// the default views of a map (both hemispheres) or a table, unless the user chose others
function setDefaultViews(wanted) {
  const boxes = [...document.querySelectorAll('input[name="views"]')];
  const now = boxes.filter((b) => b.checked).map((b) => b.value).join(",");
  if (![DEFAULT_VIEWS, MAP_VIEWS, TRACT_VIEWS, CONNECTOME_VIEWS].some((v) => now === v.join(","))) return;
  for (const b of boxes) b.checked = wanted.includes(b.value);
}

function showReport(r) {
  const box = $("report");
  box.replaceChildren();
  state.scale = r.values ? r.values.scale : null;
  state.layers = r.layers || (state.scale ? [{ kind: mainKind(), label: "", scale: state.scale }] : []);
  showBars(state.layers);
  showReproduce(r.reproduce);
  showPreviewReproduce(r.reproduce_preview);
  if (state.summary !== r.summary) {  // the live region says one line, and only when it changes
    state.summary = r.summary;
    $("report-summary").textContent = `Checked: ${r.summary}`;
  }
  box.append(el("p", { class: "ok", text: `OK: ${r.summary}` }));
  const dl = el("dl");
  const add = (k, v) => dl.append(el("dt", { text: k }), el("dd", { text: v }));
  if (r.kind === "map") { showMapReport(r, box, dl, add); showScaleUsed(state.scale, r.values.range); return; }
  if (r.kind === "tracts") { showTractReport(r, box, dl, add); showScaleUsed(state.scale, null); return; }
  if (r.kind === "connectome") { showConnectomeReport(r, box, dl, add); showScaleUsed(state.scale, null); return; }
  showScaleUsed(state.scale, r.values.range);
  for (const i of r.inputs) { add("format", i.format); add("shape", i.shape.description); }
  add("atlas", r.atlas.name + (r.atlas.inferred ? ` (inferred: ${r.atlas.reason})` : " (given)"));
  add("images", `${r.n_images}: ${r.images.slice(0, 6).join(", ")}${r.n_images > 6 ? ", …" : ""}`);
  add("regions", `${r.n_regions_with_value} of ${r.n_regions_in_atlas} have a value`);
  if (r.values.range) add("values", `${fmt(r.values.range[0])} .. ${fmt(r.values.range[1])}`);
  if (r.values.scale) add("scale", `${r.values.scale.name}: ${fmt(r.values.scale.vmin)} .. ${fmt(r.values.scale.vmax)}`);
  add("empty cells", String(r.cells.n_empty));
  box.append(dl);
  const list = (title, items) => {
    if (!items.length) return;
    box.append(el("h3", { text: title }));
    const ul = el("ul");
    for (const t of items) ul.append(el("li", { text: t }));
    box.append(ul);
  };
  list("Columns and the regions they set", r.names.filter((n) => n.status === "region")
    .map((n) => `${n.name} → ${n.regions.join(", ")}`));
  list("Unmatched names", r.names.filter((n) => n.status === "unmatched")
    .map((n) => `${n.name}` + (n.closest && n.closest.length ? ` (closest: ${n.closest.join(", ")})` : "")
      + (n.region_of_atlas && n.region_of_atlas.length ? ` (a region of ${n.region_of_atlas.join(", ")})` : "")));
  list("Set aside (not regions)", r.names.filter((n) => n.status === "ignored").map((n) => `${n.name}: ${n.reason}`));
  list("Notes", [...r.values.hints, ...r.notes].map(pageWords));
}

// What the colours are, as drawn: the scale's name and range (an automatic one says so), the range as
// placeholders of vmin and vmax, and values beyond it reported as saturated.
function showScaleUsed(scale, range) {
  const p = $("scale-used");
  if (!scale) { p.hidden = true; return; }
  const auto = $("use-gradient").checked && !$("gradient").value.trim();
  let text = `Drawn: ${scale.name}, ${fmt(scale.vmin)} to ${fmt(scale.vmax)}` +
    (scale.center !== null && scale.center !== undefined ? `, centre ${fmt(scale.center)}` : "") +
    (auto ? " (chosen for the data; type a gradient or choose a colour map to change it)." : ".");
  if (range && (range[0] < scale.vmin || range[1] > scale.vmax)) {
    text += ` Values ${range[0] < scale.vmin ? `below ${fmt(scale.vmin)}` : ""}` +
      `${range[0] < scale.vmin && range[1] > scale.vmax ? " and " : ""}` +
      `${range[1] > scale.vmax ? `above ${fmt(scale.vmax)}` : ""} are saturated (drawn in the end colours).`;
  }
  p.textContent = text; p.hidden = false;
  $("vmin").placeholder = fmt(scale.vmin); $("vmax").placeholder = fmt(scale.vmax);
  $("gradient").placeholder = auto ? `automatic: ${scale.name}` : "";
}

// The command line and Python call that make the same images (from the server: the CLI's own options).
function showReproduce(r) {
  if (!r) return;
  $("command").textContent = r.command; $("python").textContent = r.python;
  $("reproduce").hidden = false;
}

// The command line and Python call of the preview shown (its row and view), beside it once it is drawn.
function showPreviewReproduce(r) {
  if (!r || !state.previewShown) return;
  $("preview-command").textContent = r.command; $("preview-python").textContent = r.python;
  $("preview-reproduce").hidden = false;
}

function showMapReport(r, box, dl, add) {
  add("files", r.files.join(" + "));
  add("surface", Object.entries(r.surfaces).map(([h, s]) => `${h}: ${s}`).join(", "));
  add("images", `${r.n_images}: ${r.images.slice(0, 6).join(", ")}${r.n_images > 6 ? ", …" : ""}`);
  if (r.categories) add("labels", `${r.categories.length}: ${r.categories.slice(0, 8).join(", ")}…`);
  if (r.values.range) add("values", `${fmt(r.values.range[0])} .. ${fmt(r.values.range[1])}`);
  if (r.values.scale) {
    const t = r.values.scale.threshold;
    add("scale", `${r.values.scale.name}: ${fmt(r.values.scale.vmin)} .. ${fmt(r.values.scale.vmax)}` +
        (t ? ` (|value| < ${fmt(t)} shows the underlay)` : ""));
  }
  box.append(dl);
}

function showTractReport(r, box, dl, add) {
  state.scale = r.scale || null;
  state.layers = r.layers || (state.scale ? [{ kind: "tracts", label: "", scale: state.scale }] : []);
  showBars(state.layers);
  add("bundles", r.bundles.map((b) => `${b.name} (${b.drawn} of ${b.streamlines})`).join(", "));
  if (r.values) add("values", `${r.values.file}: ${r.values.nodes ? `profiles of ${r.values.nodes} nodes` : "one value per bundle"}`);
  if (r.scale) add("scale", `${r.scale.name}: ${fmt(r.scale.vmin)} .. ${fmt(r.scale.vmax)}`);
  if (r.subject) add("subject", `${r.subject} (of ${r.subjects.length})`);
  box.append(dl);
  if (r.notes.length) {
    box.append(el("h3", { text: "Notes" }));
    const ul = el("ul");
    for (const t of r.notes) ul.append(el("li", { text: pageWords(t) }));
    box.append(ul);
  }
}

function showConnectomeReport(r, box, dl, add) {
  state.scale = r.scale || null;
  state.layers = r.layers || [];
  showBars(state.layers);
  add("nodes", `${r.nodes}${r.named ? " (named by the matrix)" : " (in the atlas's order)"}`);
  add("weights", String(r.edges));
  if (r.drawn) add("edges drawn", String(r.drawn.n_edges));
  add("files", Object.values(r.files).join(", "));
  box.append(dl);
}

// -- a connectome: its own upload (matrix, nodes, node values, categories), with the table or alone -------
async function uploadConnectome() {
  const files = [], roles = [];
  for (const [id, role] of Object.entries(CONNECTOME_ROLES)) {
    const f = $(id).files[0];
    if (f) { files.push({ blob: f, name: f.name, size: f.size }); roles.push(role); }
  }
  if (!roles.includes("matrix")) { $("connectome-status").textContent = "Choose the matrix first."; return; }
  const q = new URLSearchParams();
  files.forEach((f, i) => { q.append("name", f.name); q.append("size", String(f.size)); q.append("role", roles[i]); });
  const shown = files.map((f) => f.name).join(" + ");
  say("connectome-error", "");
  $("connectome-status").textContent = "Reading the connectome…";
  try {
    const res = await api(`/api/connectomes?${q}`, { method: "POST", body: new Blob(files.map((f) => f.blob)),
                                                     headers: { "content-type": "application/octet-stream" } });
    const j = await res.json();
    const alone = !state.uploadId || state.uploadId === state.connectomeId;
    state.connectomeId = j.upload_id; state.connectomeReport = j.report;
    $("connectome-status").textContent = `OK: ${j.report.summary}`;
    $("connectome-clear").disabled = false;
    if (alone) {  // no table: the connectome alone, through the glass cortex
      state.uploadId = j.upload_id; state.files = null; state.isMap = false;
      setDefaultViews(CONNECTOME_VIEWS);
      showReport(j.report);
      fillRows([files[0].name.split(".")[0] || "connectome"], 1);
      setReady(true);
    }
    showFieldsets();
    schedulePreview(0);
  } catch (e) {
    say("connectome-error", refused(shown, e.message));
    $("connectome-status").textContent = state.connectomeId ? `Still drawn: ${state.connectomeReport.summary}`
      : "No connectome is drawn.";
    $("connectome-clear").disabled = false;
  }
}

function clearConnectome() {
  if (state.uploadId && state.uploadId === state.connectomeId) {
    state.uploadId = null; setReady(false); $("report").textContent = "";
  }
  state.connectomeId = null; state.connectomeReport = null;
  for (const id of Object.keys(CONNECTOME_ROLES)) $(id).value = "";
  $("connectome-status").textContent = ""; $("connectome-clear").disabled = true; say("connectome-error", "");
  showFieldsets();
  schedulePreview(0);
}

// -- tracts: their own upload, drawn with the table (option tracts) or alone --------------------
async function uploadTracts(files, subject = null) {
  const q = new URLSearchParams();
  for (const f of files) q.append("name", f.name);
  if (files.length > 1) for (const f of files) q.append("size", String(f.size));
  if (subject) q.set("subject", subject);
  const shown = files.map((f) => f.name).join(" + ");
  say("tract-error", "");
  $("tract-status").textContent = "Reading the tractograms…";
  try {
    const res = await api(`/api/tracts?${q}`, { method: "POST", body: new Blob(files.map((f) => f.blob)),
                                                headers: { "content-type": "application/octet-stream" } });
    const j = await res.json();
    const alone = !state.uploadId || state.uploadId === state.tractsId;
    state.tractsId = j.upload_id; state.tractReport = j.report; state.tractFiles = files;
    $("tract-status").textContent = `OK: ${j.report.summary}`;
    $("tract-clear").disabled = false;
    showSubjects(j.report);
    showFieldsets();
    if (alone && j.report.values) {  // no table: the tracts alone, coloured by their values table
      state.uploadId = j.upload_id; state.files = null; state.isMap = false;
      if ($("gradient").value === "") $("gradient").value = GRADIENT;
      setDefaultViews(TRACT_VIEWS);
      showReport(j.report);
      fillRows(j.report.values.images, j.report.values.images.length);
      setReady(true);
    } else if (alone) {
      $("tract-status").textContent += " — now upload a table (or add a table of bundle values to the tracts).";
    }
    schedulePreview(0);
  } catch (e) {
    say("tract-error", refused(shown, e.message));
    $("tract-status").textContent = state.tractsId ? `Still drawn: ${state.tractReport.summary}`
      : "No tracts are drawn.";
    $("tract-clear").disabled = false;
  }
}

// A zip of subject folders: choose the subject (the upload is read again for it).
function showSubjects(report) {
  const subjects = report.subjects || [];
  $("subject-box").hidden = subjects.length < 2;
  $("subject").replaceChildren(...subjects.map((s) => el("option", { value: s, text: s })));
  if (report.subject) $("subject").value = report.subject;
}

function clearTracts() {
  if (state.uploadId && state.uploadId === state.tractsId) {
    state.uploadId = null; setReady(false); $("report").textContent = "";
  }
  state.tractsId = null; state.tractReport = null; state.tractFiles = null;
  $("tract-status").textContent = ""; $("tract-clear").disabled = true; $("tract-files").value = "";
  say("tract-error", ""); $("subject-box").hidden = true;
  showFieldsets();
  schedulePreview(0);
}

function fillRows(images, total) {
  const sel = $("row");
  sel.replaceChildren();
  images.forEach((name, i) => sel.append(el("option", { value: String(i), text: name })));
  if (total > images.length) sel.append(el("option", { disabled: true, text: `… ${total - images.length} more` }));
  sel.value = String(Math.max(0, images.length - 1));
  state.nRows = total;
  movieLength();
}

function setReady(on) {
  for (const b of document.querySelectorAll("#render-all, button[data-kind]")) b.disabled = !on;
}

// -- live preview -----------------------------------------------------------------------
function schedulePreview(delay = 200) {
  clearTimeout(state.previewTimer);
  state.previewTimer = setTimeout(preview, delay);
}

async function preview() {
  if (!state.uploadId) return;
  if (state.previewCtl) state.previewCtl.abort();
  const ctl = new AbortController();
  state.previewCtl = ctl;
  const seq = ++state.seq;
  const t0 = performance.now();
  $("preview-status").textContent = "Rendering preview…";
  const body = { upload_id: state.uploadId, options: options(), row: Number($("row").value || 0),
                 view: $("pview").value };
  const shown = { row: $("row").selectedOptions[0]?.textContent || null, view: body.view };
  refreshScale(body.options, ctl.signal, shown);
  try {
    const res = await api("/api/preview", { method: "POST", signal: ctl.signal,
      headers: { "content-type": "application/json" }, body: JSON.stringify(body) });
    const blob = await res.blob();
    if (seq !== state.seq) return;
    if (state.previewUrl) URL.revokeObjectURL(state.previewUrl);
    state.previewUrl = URL.createObjectURL(blob);
    const img = $("preview");
    img.src = state.previewUrl; img.hidden = false;
    showBars(state.layers);
    img.dataset.seq = String(seq);
    img.alt = `Preview of ${$("row").selectedOptions[0]?.textContent || "row"} from ${body.view}`;
    $("preview-status").textContent =
      `${$("row").selectedOptions[0]?.textContent || ""} · ${body.view} · rendered in ${res.headers.get("x-render-ms")} ms ` +
      `(round trip ${Math.round(performance.now() - t0)} ms)` +
      (body.options.quality === "high" ? " · previews are drawn at default quality; jobs draw high" : "");
    showPreviewError(""); fieldError("");
    state.previewShown = true;
    showPreviewReproduce(state.report && state.report.reproduce_preview);
  } catch (e) {
    if (e.name === "AbortError") return;
    $("preview-status").textContent = "No preview.";
    state.previewShown = false; $("preview-reproduce").hidden = true;
    showPreviewError(pageWords(fieldError(e.message)));
  }
}

async function refreshScale(opts, signal, shown) {
  // the check report again with the colour options: value range against the scale, hints; with the
  // preview's row and view, the command that draws the preview
  try {
    const res = await api("/api/check", { method: "POST", signal, headers: { "content-type": "application/json" },
                                          body: JSON.stringify({ upload_id: state.uploadId, options: opts,
                                                                 preview: shown }) });
    state.report = await res.json();
    showReport(state.report);
  } catch (e) { /* the preview shows the error */ }
}

// -- jobs -------------------------------------------------------------------------------
async function submit(kind, format) {
  if (!state.uploadId) return;
  say("job-error", "");
  const body = { upload_id: state.uploadId, kind, options: options() };
  if (kind === "figure") {
    body.figure = { format, dpi: Number($("dpi").value), font_size: Number($("font_size").value),
                    fig_width: numberOrNull("fig_width"),
                    slices: $("slices").value.split(";").map((s) => s.trim()).filter(Boolean),
                    projections: $("projections").value.trim() || null };
  }
  if (kind === "movie") {
    body.movie = { format, frames_per_step: Number($("frames_per_step").value), hold: Number($("hold").value),
                   easing: $("easing").value, fps: Number($("fps").value),
                   clip_sweep: $("clip_sweep").value || null };
  }
  if (kind === "export") body.export = { row: Number($("row").value || 0) };
  let job;
  try {
    const res = await api("/api/jobs", { method: "POST", headers: { "content-type": "application/json" },
                                         body: JSON.stringify(body) });
    job = await res.json();
    fieldError("");
  } catch (e) { say("job-error", pageWords(fieldError(e.message))); return; }
  const label = kind === "images" ? "All images" : kind === "export"
    ? `interactive 3D (HTML) of ${$("row").selectedOptions[0]?.textContent || "the row"}`
    : `${kind} (${format.toUpperCase()})`;
  const box = el("div", { class: "job", "data-job": job.id });
  const progId = `prog-${job.id.slice(0, 8)}`;
  const status = el("p", { text: `${label}: queued` });
  const prog = el("progress", { id: progId, max: String(Math.max(1, job.total)), value: "0" });
  const cancel = el("button", { type: "button", text: "Cancel" });
  cancel.addEventListener("click", () => api(job.url, { method: "DELETE" }).catch((e) => say("job-error", e.message)));
  box.append(el("label", { for: progId, text: label }), prog, status, cancel);
  $("jobs").prepend(box);
  for (let i = 0; i < 7200; i++) { // bounded: at most about an hour of polling
    await new Promise((r) => setTimeout(r, 500));
    try { job = await (await api(job.url)).json(); } catch (e) { status.textContent = e.message; return; }
    prog.value = job.progress;
    prog.max = Math.max(1, job.total);
    status.textContent = `${label}: ${jobStep(job)}`;
    if (["done", "failed", "cancelled", "expired"].includes(job.status)) break;
  }
  cancel.remove();
  if (job.status !== "done") { status.textContent = `${label}: ${job.status}${job.error ? ": " + job.error : ""}`; return; }
  showResult(box, job, label);
}

// What a job is doing: images or frames drawn, then the step after them.
function jobStep(job) {
  const unit = job.kind === "movie" ? " frames" : " images";
  if (job.status === "running" && job.total > 0 && job.progress >= job.total && job.kind !== "images") {
    return job.kind === "figure" ? `composing figure (${job.total} images drawn)`
      : `encoding movie (${job.total} frames drawn)`;
  }
  const counted = job.kind === "movie" || job.kind === "images" || (job.kind === "figure" && job.total > 1);
  return `${job.status} (${job.progress}/${job.total}${counted ? unit : ""})`;
}

// A movie's length before it is made: frames as brainpainter movie plans them, and seconds.
function movieLength() {
  const rows = state.uploadId ? state.nRows || 0 : 0;
  const k = $("clip_sweep").value && rows === 1 ? 2 : rows;  // one row cut open by a sweeping plane
  const n = Number($("frames_per_step").value), hold = Number($("hold").value), fps = Number($("fps").value);
  if (k < 2 || !(n >= 1) || !(hold >= 0) || !(fps > 0)) {
    $("movie-length").textContent = k === 1 ? "A movie needs at least 2 rows." : "";
    return;
  }
  const frames = k * (1 + hold) + (k - 1) * (n - 1);
  $("movie-length").textContent = `A movie of these ${k} rows: ${frames} frames, ${(frames / fps).toFixed(1)} s ` +
    `at ${fmt(fps)} frames per second` +
    (hold ? `, holding each row ${(hold / fps).toFixed(1)} s.` : " (no hold on each row).");
}

function showResult(box, job, label) {
  const links = el("p", { class: "row wrap" });
  const gallery = el("div", { class: "gallery" });
  const images = job.kind === "images";
  for (const f of job.files) {
    if (!images || f.name.endsWith(".zip")) {
      links.append(el("a", { href: `${f.url}?download=1`, download: f.name,
                             text: images ? `Download all (${f.name})` : `Download ${f.name}` }));
    }
    if (f.name.endsWith(".mp4")) {
      gallery.append(el("figure", {}, el("video", { src: f.url, controls: true, preload: "metadata",
                                                     "aria-label": f.name })));
    } else if (f.name.endsWith(".png") || f.name.endsWith(".gif")) {
      gallery.append(el("figure", {}, el("img", { src: f.url, alt: f.name, loading: "lazy" }),
                        el("figcaption", { text: f.name })));
    }
  }
  if (!images) gallery.classList.add("wide");  // a figure or a movie: as wide as the panel, to judge it
  box.append(links, gallery);
  box.querySelector("p").textContent = `${label}: done`;
}

// -- wiring -----------------------------------------------------------------------------
function wire() {
  const drop = $("drop"), file = $("file");
  drop.addEventListener("click", () => file.click());
  drop.addEventListener("keydown", (e) => { if (e.key === "Enter" || e.key === " ") { e.preventDefault(); file.click(); } });
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  const picked = (list) => [...list].map((f) => ({ blob: f, name: f.name, size: f.size }));
  drop.addEventListener("drop", (e) => {
    e.preventDefault(); drop.classList.remove("over");
    if (e.dataTransfer.files.length) upload(picked(e.dataTransfer.files));
  });
  file.addEventListener("change", () => { if (file.files.length) upload(picked(file.files)); });
  $("paste-go").addEventListener("click", () => {
    const text = $("paste").value;
    const blob = new Blob([text], { type: "text/plain" });
    upload([{ blob, name: text.includes("\t") ? "pasted.tsv" : "pasted.csv", size: blob.size }]);
  });
  $("example").addEventListener("click", async () => {
    const res = await api("/static/brainpainter_dk.csv");
    const blob = await res.blob();
    upload([{ blob, name: "brainpainter_dk.csv", size: blob.size }]);
  });
  // table options: upload again (the check report changes); other options: new preview
  for (const node of document.querySelectorAll("[data-table]")) {
    node.addEventListener("change", () => { if (state.files && !state.isMap) upload(state.files); });
  }
  for (const r of document.querySelectorAll('input[name="scale"]')) {
    r.addEventListener("change", () => {
      $("cmap").disabled = !$("use-cmap").checked; $("gradient").disabled = $("use-cmap").checked;
    });
  }
  $("options").addEventListener("input", () => schedulePreview());
  $("options").addEventListener("change", () => schedulePreview());
  $("options").addEventListener("submit", (e) => e.preventDefault());
  $("row").addEventListener("change", () => schedulePreview(0));
  $("pview").addEventListener("change", () => schedulePreview(0));
  $("tract-files").addEventListener("change", () => {
    const list = $("tract-files").files;
    if (list.length) uploadTracts(picked(list));
  });
  $("tract-clear").addEventListener("click", clearTracts);
  for (const id of Object.keys(CONNECTOME_ROLES)) $(id).addEventListener("change", uploadConnectome);
  $("connectome-clear").addEventListener("click", clearConnectome);
  for (const kind of ["map", "contour"]) {
    $(`${kind}-files`).addEventListener("change", () => {
      const list = $(`${kind}-files`).files;
      if (list.length) uploadLayerMap(kind, picked(list));
    });
    $(`${kind}-clear`).addEventListener("click", () => clearLayerMap(kind));
  }
  $("contour_levels").addEventListener("input", () => schedulePreview());
  $("subject").addEventListener("change", () => {
    if (state.tractFiles) uploadTracts(state.tractFiles, $("subject").value);
  });
  for (const b of document.querySelectorAll("button.copy")) {
    const label = b.textContent;
    b.addEventListener("click", async () => {
      const text = $(b.dataset.copy).textContent;
      try { await navigator.clipboard.writeText(text); b.textContent = "Copied"; } catch (e) {
        getSelection().selectAllChildren($(b.dataset.copy)); b.textContent = "Selected: press Ctrl+C";
      }
      setTimeout(() => { b.textContent = label; }, 2000);
    });
  }
  for (const id of ["frames_per_step", "hold", "fps", "clip_sweep"]) $(id).addEventListener("input", movieLength);
  $("affine-file").addEventListener("change", async () => {
    const f = $("affine-file").files[0];
    if (!f) return;
    if (f.size > 2000) { showPreviewError(`${f.name} is ${f.size} bytes; an affine is 4 rows of 4 numbers.`); return; }
    $("tracts_affine").value = (await f.text()).trim();
    schedulePreview(0);
  });
  $("render-all").addEventListener("click", () => submit("images"));
  for (const b of document.querySelectorAll("button[data-kind]")) {
    b.addEventListener("click", () => submit(b.dataset.kind, b.dataset.format));
  }
}

async function start() {
  wire();
  try {
    state.meta = await (await api("/api/meta")).json();
    fillForm(state.meta);
  } catch (e) { showError(`The server did not answer: ${e.message}`); }
}

document.addEventListener("DOMContentLoaded", start);
