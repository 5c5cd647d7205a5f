// brainpainter's HTML export viewer (brainpainter.media.export.html_page): inflate and load the inlined GLB
// (gzip; quantised, without normals: computed here), light it, orbit controls, a tooltip from a raycast
// (region and value), part toggles, flat (unlit, exact) colours.
// window.brainpainterReady turns true once drawn.
(function () {
  const T = window.BPTHREE;
  const cfg = JSON.parse(document.getElementById("brainpainter-config").textContent);
  const glbElement = document.getElementById("brainpainter-glb");
  const bytes = Uint8Array.from(atob(glbElement.textContent.trim()), (c) => c.charCodeAt(0));
  const view = document.getElementById("view"), tip = document.getElementById("tip");
  let renderer;
  try {
    renderer = new T.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    const err = document.getElementById("error");
    err.textContent = "This browser cannot show 3D graphics (WebGL is off); "
      + "the .glb file opens in other viewers.";
    err.style.display = "block";
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.outputColorSpace = T.SRGBColorSpace;
  view.appendChild(renderer.domElement);
  const scene = new T.Scene();
  scene.background = new T.Color(cfg.background);
  const camera = new T.PerspectiveCamera(30, 1, 1, 5000);
  const controls = new T.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;
  const hemi = new T.HemisphereLight(0xffffff, 0x888888, 1.6);
  const key = new T.DirectionalLight(0xffffff, 1.6);
  camera.add(key); key.position.set(0.3, 0.5, 1);
  scene.add(hemi); scene.add(camera);
  const meshes = [], lit = new Map(), flat = new Map();
  let home = null;

  function draw() { renderer.render(scene, camera); }
  function resize() {
    const w = view.clientWidth || window.innerWidth, h = view.clientHeight || window.innerHeight;
    renderer.setSize(w, h); camera.aspect = w / h; camera.updateProjectionMatrix(); draw();
  }
  function reset() {
    if (!home) return;
    const a = cfg.azimuth * Math.PI / 180;  // RAS azimuth -> glTF: x = cos a, z = -sin a
    camera.position.set(home.c.x + home.d * Math.cos(a), home.c.y, home.c.z - home.d * Math.sin(a));
    camera.up.set(0, 1, 0); controls.target.copy(home.c); controls.update(); draw();
  }

  function glb() {  // the GLB's bytes, inflated (DecompressionStream: Chromium 80, Firefox 113, Safari 16.4)
    if (glbElement.dataset.encoding !== "gzip") return Promise.resolve(bytes.buffer);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
    return new Response(stream).arrayBuffer();
  }
  function unpack(buffer) {
    // undo brainpainter.media.glb.packed in place: in each view whose extras name a filter, the low
    // bytes of all values come before the high bytes; "delta": int16 (x, y, z, pad) rows as differences
    // from the row before; "hwm": indices as the distance below the highest index before them
    const n = new DataView(buffer).getUint32(12, true), bin = 20 + n + 8;
    const doc = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 20, n)));
    (doc.bufferViews || []).forEach((view, i) => {
      const filter = view.extras && view.extras.filter;
      if (!filter) return;
      const u8 = new Uint8Array(buffer, bin + (view.byteOffset || 0), view.byteLength);
      if (filter === "delta") {
        const rows = u8.length / 8, out = new Int16Array(rows * 4);
        for (let c = 0; c < 4; c++) {
          const lo = 2 * c * rows, hi = lo + rows;
          for (let r = 0, acc = 0; r < rows; r++) {
            acc = (acc + (u8[lo + r] | (u8[hi + r] << 8))) << 16 >> 16; out[4 * r + c] = acc;
          }
        }
        u8.set(new Uint8Array(out.buffer));
      } else if (filter === "hwm") {
        const acc = doc.accessors.find((a) => a.bufferView === i), size = acc.componentType === 5123 ? 2 : 4;
        const m = acc.count, out = size === 2 ? new Uint16Array(m) : new Uint32Array(m);
        for (let j = 0, high = -1; j < m; j++) {
          let d = 0;
          for (let b = 0; b < size; b++) d += u8[b * m + j] * 2 ** (8 * b);
          const f = high + 1 - d; out[j] = f; if (f > high) high = f;
        }
        u8.set(new Uint8Array(out.buffer));
      }
    });
    return buffer;
  }
  function smoothNormals(objs) {
    // vertex normals of meshes without them, summed over each part: a vertex on a region border (one
    // position in two meshes; quantised positions are exact integers) gets one normal, so no seam shows
    const sums = new Map(), keys = new Map(), a = new T.Vector3(), b = new T.Vector3(), c = new T.Vector3();
    const todo = objs.filter((o) => !o.geometry.attributes.normal), parts = cfg.parts;
    todo.forEach((o) => {
      const p = o.geometry.attributes.position, idx = o.geometry.index.array, k = new Float64Array(p.count);
      const base = (parts.indexOf(o.userData.part) + 1) * 2 ** 48;  // a key per part and int16 position
      for (let i = 0; i < p.count; i++) {
        k[i] = base + (p.getX(i) + 32768) * 2 ** 32 + (p.getY(i) + 32768) * 65536 + (p.getZ(i) + 32768);
        if (!sums.has(k[i])) sums.set(k[i], new T.Vector3());
      }
      keys.set(o, k);
      for (let f = 0; f < idx.length; f += 3) {
        a.fromBufferAttribute(p, idx[f]); b.fromBufferAttribute(p, idx[f + 1]); c.fromBufferAttribute(p, idx[f + 2]);
        c.sub(b); a.sub(b); c.cross(a);  // (c - b) x (a - b), area-weighted, as three.js's computeVertexNormals
        for (let j = 0; j < 3; j++) sums.get(k[idx[f + j]]).add(c);
      }
    });
    todo.forEach((o) => {
      o.geometry.computeVertexNormals();  // the attribute (the vendored build has no BufferAttribute)
      const k = keys.get(o), n = o.geometry.attributes.normal.array;
      for (let i = 0; i < k.length; i++) {
        const s = sums.get(k[i]).normalize(); n[3 * i] = s.x; n[3 * i + 1] = s.y; n[3 * i + 2] = s.z;
      }
      o.material.flatShading = false; o.material.needsUpdate = true;
    });
  }

  glb().then((buffer) => new T.GLTFLoader().parse(unpack(buffer), "", (gltf) => {
    const found = [];
    gltf.scene.traverse((o) => { if (o.isMesh) found.push(o); });
    smoothNormals(found);
    const glass = cfg.glass || [];  // the cortex over a connectome: see-through, drawn after what is inside
    found.forEach((o) => {
      meshes.push(o);
      if (glass.indexOf(o.userData.part) >= 0) {
        o.material = o.material.clone();
        Object.assign(o.material, { transparent: true, opacity: 0.18, depthWrite: false });
        o.renderOrder = 1;
      }
      lit.set(o, o.material);
      const m = o.material.clone();
      flat.set(o, new T.MeshBasicMaterial({ color: m.color, side: m.side, vertexColors: m.vertexColors,
                                            transparent: m.transparent, opacity: m.opacity,
                                            depthWrite: m.depthWrite }));
    });
    scene.add(gltf.scene);
    const box = new T.Box3().setFromObject(gltf.scene);
    const c = box.getCenter(new T.Vector3()), size = box.getSize(new T.Vector3());
    home = { c: c, d: 1.45 * Math.max(size.y, size.z) / (2 * Math.tan(camera.fov * Math.PI / 360)) };
    if (flatBox.checked) setFlat(true);
    resize(); reset();
    window.brainpainterViewer = {
      scene: scene, camera: camera, controls: controls, meshes: meshes, renderer: renderer, draw: draw };
    window.brainpainterReady = true;
  }, (e) => { console.error("brainpainter: cannot read the 3D model: " + e); }))
    .catch((e) => { console.error("brainpainter: cannot inflate the 3D model: " + e); });

  controls.addEventListener("change", draw);
  window.addEventListener("resize", resize);
  renderer.domElement.addEventListener("dblclick", reset);
  document.querySelectorAll("input[data-part]").forEach((box) => box.addEventListener("change", () => {
    meshes.forEach((o) => { if (o.userData.part === box.dataset.part) o.visible = box.checked; });
    draw();
  }));
  const flatBox = document.getElementById("flat");
  function setFlat(on) { meshes.forEach((o) => { o.material = on ? flat.get(o) : lit.get(o); }); draw(); }
  flatBox.addEventListener("change", () => setFlat(flatBox.checked));
  if (location.hash === "#flat") flatBox.checked = true;  // applied once the model is read

  const ray = new T.Raycaster(), ndc = new T.Vector2();
  renderer.domElement.addEventListener("pointermove", (ev) => {
    const r = renderer.domElement.getBoundingClientRect();
    ndc.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    ray.setFromCamera(ndc, camera);
    const hits = ray.intersectObjects(meshes.filter((o) => o.visible), false);
    // through the glass cortex: what lies inside it (a connectome's nodes and edges) is named first
    const hit = hits.find((h) => (cfg.glass || []).indexOf(h.object.userData.part) < 0) || hits[0];
    if (!hit) { tip.style.display = "none"; return; }
    const value = hit.object.userData.value;
    tip.textContent = (hit.object.userData.name || hit.object.name) + (value === undefined ? "" : ": " + value);
    tip.style.left = (ev.clientX + 14) + "px"; tip.style.top = (ev.clientY + 10) + "px";
    tip.style.display = "block";
  });
  renderer.domElement.addEventListener("pointerleave", () => { tip.style.display = "none"; });
})();
