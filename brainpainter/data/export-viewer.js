// brainpainter's HTML export viewer (brainpainter.media.export.html_page): load the inlined GLB, light it,
// orbit controls, a tooltip from a raycast, part toggles, flat (unlit, exact) colours.
// window.brainpainterReady turns true once drawn.
(function () {
  const T = window.BPTHREE;
  const cfg = JSON.parse(document.getElementById("brainpainter-config").textContent);
  const b64 = document.getElementById("brainpainter-glb").textContent.trim();
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
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

  new T.GLTFLoader().parse(bytes.buffer, "", (gltf) => {
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      meshes.push(o);
      lit.set(o, o.material);
      const m = o.material.clone();
      flat.set(o, new T.MeshBasicMaterial({ color: m.color, side: m.side, vertexColors: m.vertexColors }));
    });
    scene.add(gltf.scene);
    const box = new T.Box3().setFromObject(gltf.scene);
    const c = box.getCenter(new T.Vector3()), size = box.getSize(new T.Vector3());
    home = { c: c, d: 1.45 * Math.max(size.y, size.z) / (2 * Math.tan(camera.fov * Math.PI / 360)) };
    resize(); reset();
    window.brainpainterViewer = {
      scene: scene, camera: camera, controls: controls, meshes: meshes, renderer: renderer, draw: draw };
    window.brainpainterReady = true;
  }, (e) => { console.error("brainpainter: cannot read the 3D model: " + e); });

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
  if (location.hash === "#flat") { flatBox.checked = true; setTimeout(() => setFlat(true), 0); }

  const ray = new T.Raycaster(), ndc = new T.Vector2();
  renderer.domElement.addEventListener("pointermove", (ev) => {
    const r = renderer.domElement.getBoundingClientRect();
    ndc.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    ray.setFromCamera(ndc, camera);
    const hit = ray.intersectObjects(meshes.filter((o) => o.visible), false)[0];
    if (!hit) { tip.style.display = "none"; return; }
    tip.textContent = hit.object.name;
    tip.style.left = (ev.clientX + 14) + "px"; tip.style.top = (ev.clientY + 10) + "px";
    tip.style.display = "block";
  });
  renderer.domElement.addEventListener("pointerleave", () => { tip.style.display = "none"; });
})();
