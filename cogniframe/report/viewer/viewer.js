// cogniframe report viewer: the assembly as a list of named meshes with metadata, drawn with three.js.
// Data-driven: every object is {name, kind: part|rod|vitamin, material, mass_g, qty, plate, colour,
// note, geometry, matrix}; geometries are quantised uint16 positions + uint16/uint32 triangle indices
// packed in one base64 buffer (see cogniframe/report/viewer/__init__.py). No network access.

export function start(THREE, OrbitControls, root, scene_data, geometry_b64) {
  const canvas = root.querySelector("canvas");
  const info = root.querySelector(".cf-info");
  const bytes = Uint8Array.from(atob(geometry_b64.trim()), (c) => c.charCodeAt(0));
  const buffer = bytes.buffer;

  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  const background = new THREE.Color(scene_data.background);
  renderer.setClearColor(background, 1);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(35, 1, 1, 10000);
  camera.up.set(0, 0, 1);  // the frame's z is up
  scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(0.4, -0.6, 1.0);
  camera.add(sun);
  scene.add(camera);

  // geometries
  const geometries = scene_data.geometries.map((g) => {
    const q = new Uint16Array(buffer, g.positions, g.n_vertices * 3);
    const pos = new Float32Array(g.n_vertices * 3);
    for (let i = 0; i < pos.length; i++) pos[i] = g.min[i % 3] + q[i] * g.step[i % 3];
    const Index = g.index_bytes === 2 ? Uint16Array : Uint32Array;
    const index = new Index(buffer, g.indices, g.n_triangles * 3);
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    geo.setIndex(new THREE.BufferAttribute(index, 1));
    geo.computeBoundingSphere();
    return geo;
  });

  // objects
  const meshes = [];
  const byKind = {};
  for (const o of scene_data.objects) {
    const material = new THREE.MeshPhongMaterial({ color: new THREE.Color(o.colour), flatShading: true, shininess: 20 });
    const mesh = new THREE.Mesh(geometries[o.geometry], material);
    mesh.matrixAutoUpdate = false;
    mesh.matrix.fromArray(o.matrix);  // column-major, world <- mesh
    mesh.userData = o;
    scene.add(mesh);
    meshes.push(mesh);
    (byKind[o.kind] = byKind[o.kind] || []).push(mesh);
  }
  scene.updateMatrixWorld(true);

  const box = new THREE.Box3();
  for (const m of meshes) box.expandByObject(m);
  const centre = box.getCenter(new THREE.Vector3());
  const radius = box.getSize(new THREE.Vector3()).length() / 2 || 100;

  const controls = new OrbitControls(camera, canvas);
  controls.enableDamping = false;
  function home() {
    const dir = new THREE.Vector3(1, 1, 0.8).normalize();  // as the iso render: y is the front
    camera.position.copy(centre).addScaledVector(dir, radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 0.92);
    camera.near = radius / 50;
    camera.far = radius * 20;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
  }

  function resize() {
    const w = Math.max(200, root.clientWidth);
    const h = Math.round(Math.min(560, Math.max(320, w * 0.6)));
    renderer.setSize(w, h, true);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }

  let pending = false;
  function render() {
    renderer.render(scene, camera);
  }
  function requestRender() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; render(); });
  }
  controls.addEventListener("change", requestRender);

  // selection
  let selected = null;
  const raycaster = new THREE.Raycaster();
  function fmt(o) {
    const rows = [["name", o.name], ["kind", o.kind], ["material", o.material]];
    if (o.mass_g !== null && o.mass_g !== undefined) rows.push(["mass", `${o.mass_g.toFixed(2)} g each`]);
    rows.push(["quantity", String(o.qty)]);
    rows.push(["plate", o.plate || (o.kind === "part" ? "-" : "not printed")]);
    if (o.note) rows.push(["note", o.note]);
    return rows;
  }
  function show(o) {
    info.replaceChildren();
    if (!o) { info.textContent = "Click a part to see its name, material, mass, quantity and print plate."; return; }
    const dl = document.createElement("dl");
    for (const [k, v] of fmt(o)) {
      const dt = document.createElement("dt"); dt.textContent = k;
      const dd = document.createElement("dd"); dd.textContent = v; dd.dataset.field = k;
      dl.append(dt, dd);
    }
    info.append(dl);
  }
  function select(mesh) {
    if (selected) selected.material.emissive.setHex(0x000000);
    selected = mesh;
    if (mesh) mesh.material.emissive.setHex(0x3a6df0);
    root.dataset.selected = mesh ? mesh.userData.name : "";
    show(mesh ? mesh.userData : null);
    requestRender();
  }
  function ndc(clientX, clientY) {
    const r = canvas.getBoundingClientRect();
    return new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
  }
  function pick(clientX, clientY) {
    raycaster.setFromCamera(ndc(clientX, clientY), camera);
    const hits = raycaster.intersectObjects(meshes.filter((m) => m.visible), false);
    return hits.length ? hits[0].object : null;
  }
  let down = null;
  canvas.addEventListener("pointerdown", (e) => { down = [e.clientX, e.clientY]; });
  canvas.addEventListener("pointerup", (e) => {
    if (!down) return;
    const moved = Math.hypot(e.clientX - down[0], e.clientY - down[1]);
    down = null;
    if (moved < 5) select(pick(e.clientX, e.clientY));  // a click, not a drag
  });

  // toggles: one checkbox per kind that can be hidden (data-kind="rod" / "vitamin")
  for (const box of root.querySelectorAll("input[data-kind]")) {
    const kind = box.dataset.kind;
    const count = (byKind[kind] || []).length;
    box.disabled = count === 0;
    box.parentElement.title = count ? `${count} ${kind}s` : `no ${kind}s in this design yet`;
    box.addEventListener("change", () => {
      for (const m of byKind[kind] || []) m.visible = box.checked;
      if (selected && !selected.visible) select(null);
      requestRender();
    });
  }
  const reset = root.querySelector(".cf-reset");
  if (reset) reset.addEventListener("click", () => { home(); requestRender(); });

  // A client point (page pixels) where `name` is the first object hit, or null: lets a test click a part.
  function screenPointOf(name) {
    const mesh = meshes.find((m) => m.userData.name === name);
    if (!mesh || !mesh.visible) return null;
    const pos = mesh.geometry.attributes.position;
    const r = canvas.getBoundingClientRect();
    const v = new THREE.Vector3();
    const step = Math.max(1, Math.floor(pos.count / 200));
    for (let i = 0; i < pos.count; i += step) {
      v.fromBufferAttribute(pos, i).applyMatrix4(mesh.matrixWorld).lerp(mesh.geometry.boundingSphere.center.clone().applyMatrix4(mesh.matrixWorld), 0.15);
      v.project(camera);
      if (Math.abs(v.x) > 0.98 || Math.abs(v.y) > 0.98) continue;
      const x = r.left + (v.x + 1) / 2 * r.width, y = r.top + (1 - v.y) / 2 * r.height;
      if (pick(x, y) === mesh) return { x, y };
    }
    return null;
  }

  home();
  new ResizeObserver(resize).observe(root);
  resize();
  show(null);
  const api = { objects: meshes.length, kinds: Object.fromEntries(Object.entries(byKind).map(([k, v]) => [k, v.length])),
                select: (name) => select(meshes.find((m) => m.userData.name === name) || null), screenPointOf, render };
  window.cogniframeViewer = api;
  root.dataset.ready = "1";
  return api;
}
