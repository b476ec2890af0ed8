// dualarm_qp 3D view: builds the scene described in #dualarm-data with the three.js of
// the inlined MeshCat viewer bundle, then replays the recorded samples (a run's
// animation) or follows samples streamed from Python (the live view, over /events).
// Page address options: #t=SECONDS shows that instant, paused; &shapes=1 (or 0) turns the
// collision shapes on (or off), as their checkbox does.
(function () {
  "use strict";
  const report = window.__dualarm;
  const THREE = MeshCat.THREE;
  const DATA = JSON.parse(document.getElementById("dualarm-data").textContent);
  const SCENE = DATA.scene;
  const LIMIT_COLOURS = [null, "#ffb000", "#e00000"];  // near, outside (inside: arm colour)
  const $ = (id) => document.getElementById(id);

  if (SCENE.collision) {  // a fourth row in the panel, before the pane is sized
    document.body.classList.add("collision");
    $("collision-row").hidden = false;
  }
  const viewer = new MeshCat.Viewer($("view"));
  const root = new THREE.Group();
  viewer.scene.add(root);  // MeshCat's scene is z-up, like ours
  viewer.set_property(["Grid"], "visible", false);  // ours lies on the floor, below
  viewer.set_property(["Axes"], "visible", false);
  function fitPane() {  // the pane, not the window: the panel sits below it
    viewer.set_3d_pane_size($("view").clientWidth, $("view").clientHeight);
    viewer.set_dirty();
  }
  window.onload = fitPane;
  window.addEventListener("resize", fitPane);
  fitPane();

  function fixed(obj, pose) {
    obj.matrixAutoUpdate = false;
    obj.matrix.fromArray(pose);
    return obj;
  }
  function material(colour) {
    return new THREE.MeshPhongMaterial({color: new THREE.Color(colour), shininess: 40});
  }
  // Triangle buffers of the URDF arms' meshes, decoded once, shared by every part.
  const notes = (SCENE.notes || []).slice();
  const meshes = (SCENE.meshes || []).map((m) => {
    try {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(
        new Float32Array(bytes(m.positions).buffer), 3));
      const raw = bytes(m.indices).buffer;
      g.setIndex(new THREE.BufferAttribute(
        m.index_bytes === 4 ? new Uint32Array(raw) : new Uint16Array(raw), 1));
      g.computeVertexNormals();
      return g;
    } catch (err) {
      notes.push("mesh " + m.name + " not drawn (" + err + ")");
      return null;
    }
  });
  function shape(part, mat) {
    let g;
    if (part.shape === "capsule") return capsule(part, mat);
    if (part.shape === "mesh") {
      if (!meshes[part.mesh]) return null;
      const obj = fixed(new THREE.Mesh(meshes[part.mesh], mat), part.pose);
      obj.matrix.scale(new THREE.Vector3(part.scale[0], part.scale[1], part.scale[2]));
      return obj;
    }
    if (part.shape === "cylinder") {
      g = new THREE.CylinderGeometry(part.radius, part.radius, part.length, 24);
    } else if (part.shape === "sphere") {
      g = new THREE.SphereGeometry(part.radius, 20, 14);
    } else {
      g = new THREE.BoxGeometry(part.size[0], part.size[1], part.size[2]);
    }
    return fixed(new THREE.Mesh(g, mat), part.pose);
  }

  // A capsule from its two endpoints (a sphere when they coincide): a group along the
  // axis, an open cylinder between two half-spheres (no overlap: they may be translucent).
  function capsule(part, mat) {
    const a = new THREE.Vector3().fromArray(part.a);
    const axis = new THREE.Vector3().fromArray(part.b).sub(a);
    const length = axis.length();
    const r = part.radius;
    const group = new THREE.Group();
    if (length < 1e-9) {
      group.add(new THREE.Mesh(new THREE.SphereGeometry(r, 20, 14), mat));
      group.position.copy(a);
      return group;
    }
    group.add(new THREE.Mesh(new THREE.CylinderGeometry(r, r, length, 24, 1, true), mat));
    [1, -1].forEach((side) => {
      const cap = new THREE.Mesh(
        new THREE.SphereGeometry(r, 20, 8, 0, 2 * Math.PI, 0, Math.PI / 2), mat);
      cap.position.y = side * length / 2;
      if (side < 0) cap.rotation.x = Math.PI;
      group.add(cap);
    });
    group.position.copy(a).addScaledVector(axis, 0.5);
    group.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis.normalize());
    return group;
  }

  // --- the scene ------------------------------------------------------------------
  const arms = SCENE.arms.map((arm) => {
    const nodes = [];
    for (let i = 0; i < arm.nodes; i++) {
      const node = new THREE.Group();
      root.add(node);
      nodes.push(node);
    }
    const body = material(arm.colour);
    body.side = THREE.DoubleSide;  // some meshes' triangles do not all face outwards
    arm.parts.forEach((p) => {
      const obj = shape(p, body);
      if (obj) nodes[p.node].add(obj);
    });
    const joints = arm.joints.map((j) => {
      const marker = material("#333333");
      const mesh = shape(Object.assign({shape: "cylinder"}, j), marker);
      if (arm.markers_on_top) {  // inside a mesh: drawn over it, so always seen
        marker.depthTest = false;
        mesh.renderOrder = 2;
      }
      nodes[j.node].add(mesh);
      return mesh;
    });
    return {spec: arm, nodes: nodes, joints: joints, state: joints.map(() => -1)};
  });
  // Joint axes: every one, or only those of joints near a limit or outside their range.
  const allAxes = $("all-axes");
  allAxes.checked = SCENE.all_joint_axes !== false;
  function showAxes() {
    arms.forEach((arm) => arm.joints.forEach((mesh, i) => {
      mesh.visible = allAxes.checked || arm.state[i] > 0;
    }));
  }
  allAxes.addEventListener("change", () => { showAxes(); viewer.set_dirty(); });
  const objectNode = new THREE.Group();
  root.add(objectNode);
  const bar = material(SCENE.object.colour);
  SCENE.object.parts.forEach((p) => objectNode.add(shape(p, bar)));
  const strip = material(SCENE.object.range_colour);
  SCENE.object.range.forEach((p) => objectNode.add(shape(p, strip)));
  // The grasp: a ball scaled to the object, drawn over the gripper that holds it.
  const graspMaterial = material(SCENE.object.grasp_colour);
  graspMaterial.depthTest = false;
  const graspPoint = new THREE.Mesh(
    new THREE.SphereGeometry(SCENE.object.grasp_radius || 0.018, 24, 16), graspMaterial);
  graspPoint.renderOrder = 3;
  objectNode.add(graspPoint);
  // The collision scene: obstacles always, the links' and the object's shapes on a
  // toggle, the nearest pair within the influence distance (a segment, its label).
  const COLL = SCENE.collision || null;
  const obstacles = new THREE.Group();
  root.add(obstacles);
  const shapeObjects = [];
  const shapesBox = $("shapes");
  const nearest = new THREE.Group();
  let nearestBar = null;
  if (COLL) {
    $("legend-obstacle").style.background = COLL.colours.obstacle;
    $("legend-nearest").style.background = COLL.colours.nearest;
    const solid = material(COLL.colours.obstacle);
    COLL.obstacles.forEach((o) => {
      const obj = shape(o.part, solid);
      obj.name = o.name;
      obstacles.add(obj);
    });
    const glass = material(COLL.colours.shape);
    glass.transparent = true;
    glass.opacity = COLL.shape_opacity;
    glass.depthWrite = false;
    const byOwner = {object: [objectNode]};
    arms.forEach((arm) => { byOwner[arm.spec.name] = arm.nodes; });
    COLL.shapes.forEach((s) => {
      const obj = shape(s.part, glass);
      obj.visible = false;
      obj.renderOrder = 1;
      byOwner[s.owner][s.node].add(obj);
      shapeObjects.push(obj);
    });
    shapesBox.addEventListener("change", () => {
      shapeObjects.forEach((obj) => { obj.visible = shapesBox.checked; });
      viewer.set_dirty();
      afterRender(measure);
    });
    const mark = material(COLL.colours.nearest);
    mark.depthTest = false;  // over whatever hides it, as the grasp ball
    nearestBar = new THREE.Mesh(
      new THREE.CylinderGeometry(COLL.nearest_radius, COLL.nearest_radius, 1, 12), mark);
    nearest.add(nearestBar);
    [0, 1].forEach(() => nearest.add(
      new THREE.Mesh(new THREE.SphereGeometry(COLL.witness_radius, 16, 10), mark)));
    nearest.children.forEach((m) => { m.renderOrder = 4; });
    nearest.visible = false;
    root.add(nearest);
  }
  const pathGeometry = new THREE.BufferGeometry().setFromPoints(
    SCENE.path.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
  root.add(new THREE.Line(pathGeometry, new THREE.LineBasicMaterial(
    {color: new THREE.Color(SCENE.path_colour)})));

  // --- the samples ----------------------------------------------------------------
  const F = {t: [], path_t: [], grasp: [], scale: [], status: [], nodes: [], limits: [],
             local: [], nearPair: [], nearDistance: [], nearPoints: []};
  const perSample = arms.reduce((s, a) => s + 7 * a.nodes.length, 0) + 7;
  const nJoints = arms.reduce((s, a) => s + a.joints.length, 0);
  function bytes(b64) {
    const raw = atob(b64);
    const out = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) out[i] = raw.charCodeAt(i);
    return out;
  }
  function addSamples(d) {
    const count = d.t.length;
    const nodes = d.nodes_b64 !== undefined
      ? new Float32Array(bytes(d.nodes_b64).buffer) : Float32Array.from(d.nodes);
    const limits = d.limits_b64 !== undefined ? bytes(d.limits_b64) : Uint8Array.from(d.limits);
    const local = d.local_b64 !== undefined
      ? new Float32Array(bytes(d.local_b64).buffer) : Float32Array.from(d.grasp_local);
    const near = d.near_points !== undefined
      ? new Float32Array(bytes(d.near_points).buffer) : null;
    for (let k = 0; k < count; k++) {
      F.t.push(d.t[k]);
      F.path_t.push(d.path_t[k]);
      F.grasp.push(d.grasp[k]);
      F.scale.push(d.scale ? d.scale[k] : null);
      F.status.push(d.status_names ? d.status_names[d.status[k]] : d.status[k]);
      F.nodes.push(nodes.subarray(k * perSample, (k + 1) * perSample));
      F.limits.push(limits.subarray(k * nJoints, (k + 1) * nJoints));
      F.local.push(local.subarray(k * 3, (k + 1) * 3));
      F.nearPair.push(d.near_pair ? d.near_pair[k] : -1);
      F.nearDistance.push(d.near_distance ? d.near_distance[k] : null);
      F.nearPoints.push(near ? near.subarray(k * 6, (k + 1) * 6) : (d.near ? d.near[k] : null));
    }
  }
  if (DATA.frames) {
    const d = DATA.frames;
    addSamples(Object.assign({}, d, {nodes_b64: d.nodes, limits_b64: d.limits,
                                     local_b64: d.grasp_local}));
  }

  // --- showing one sample -----------------------------------------------------------
  let current = -1;
  function setPose(obj, a, o) {
    obj.position.set(a[o], a[o + 1], a[o + 2]);
    obj.quaternion.set(a[o + 3], a[o + 4], a[o + 5], a[o + 6]);
  }
  function fmt(x, digits) {
    return (x === null || x === undefined || !isFinite(x)) ? "n/a" : x.toFixed(digits);
  }
  function show(k) {
    if (k < 0 || k >= F.t.length) return;
    current = k;
    const a = F.nodes[k];
    let o = 0, j = 0;
    const flagged = [];
    arms.forEach((arm) => {
      arm.nodes.forEach((node) => { setPose(node, a, o); o += 7; });
      const names = [];
      arm.joints.forEach((mesh, i) => {
        const s = F.limits[k][j++];
        if (s !== arm.state[i]) {
          mesh.material.color.set(s === 0 ? "#333333" : LIMIT_COLOURS[s]);
          arm.state[i] = s;
        }
        if (s > 0) names.push(arm.spec.joint_names[i] + (s === 2 ? " outside" : " near"));
      });
      flagged.push(arm.spec.name + ": " + (names.length ? names.join(", ") : "all inside"));
    });
    showAxes();
    setPose(objectNode, a, o);
    graspPoint.position.set(F.local[k][0], F.local[k][1], F.local[k][2]);
    $("scrub").max = String(F.t.length - 1);
    $("scrub").value = String(k);
    $("r-t").textContent = fmt(F.t[k], 3);
    $("r-path").textContent = fmt(F.path_t[k], 3);
    $("r-grasp").textContent = fmt(F.grasp[k] * 1e3, 1);
    $("r-status").textContent = F.status[k] || "n/a";
    $("r-scale").textContent = fmt(F.scale[k], 3);
    $("r-limits").textContent = flagged.join("; ");
    if (COLL) showNearest(k);
    viewer.set_dirty();
    afterRender(measure);
  }
  // The nearest pair of sample k, when it is closer than the influence distance.
  const UP = new THREE.Vector3(0, 1, 0);
  function showNearest(k) {
    const pair = F.nearPair[k];
    const p = F.nearPoints[k];
    const on = pair !== undefined && pair >= 0 && p !== null && p !== undefined;
    nearest.visible = on;
    const dI = fmt(COLL.influence_distance * 1e3, 0);
    if (!on) {
      $("near-label").hidden = true;
      $("r-clearance").textContent = "none within d_i = " + dI + " mm";
      return;
    }
    const a = new THREE.Vector3(p[0], p[1], p[2]);
    const b = new THREE.Vector3(p[3], p[4], p[5]);
    const axis = b.clone().sub(a);
    const length = axis.length();
    nearest.children[1].position.copy(a);
    nearest.children[2].position.copy(b);
    nearestBar.position.copy(a).addScaledVector(axis, 0.5);
    nearestBar.scale.set(1, Math.max(length, 1e-6), 1);
    if (length > 1e-9) nearestBar.quaternion.setFromUnitVectors(UP, axis.normalize());
    const text = COLL.pairs[pair] + ": " + fmt(F.nearDistance[k] * 1e3, 1) + " mm";
    $("near-label").textContent = text;
    $("near-label").hidden = false;
    $("r-clearance").textContent = text + " (d_i = " + dI + " mm)";
    placeLabel();
  }
  // The label beside the segment's middle, on screen (again whenever the camera moves).
  function screenOf(obj) {
    const rect = viewer.renderer.domElement.getBoundingClientRect();
    root.updateMatrixWorld(true);
    viewer.camera.updateMatrixWorld(true);
    const v = obj.getWorldPosition(new THREE.Vector3()).project(viewer.camera);
    return [rect.left + (v.x + 1) / 2 * rect.width, rect.top + (1 - v.y) / 2 * rect.height];
  }
  function placeLabel() {
    if (!COLL || !nearest.visible) return;
    const xy = screenOf(nearestBar);
    $("near-label").style.left = Math.round(xy[0]) + "px";
    $("near-label").style.top = Math.round(xy[1]) + "px";
  }

  // --- camera ------------------------------------------------------------------------
  function partBox(part) {  // a shape's box in world coordinates (obstacles: the world)
    const out = new THREE.Box3();
    if (part.shape === "capsule") {
      [part.a, part.b].forEach((c) => out.union(new THREE.Sphere(
        new THREE.Vector3().fromArray(c), part.radius).getBoundingBox(new THREE.Box3())));
      return out;
    }
    const size = part.size || [0, 0, 0];
    const m = new THREE.Matrix4().fromArray(part.pose);
    [-0.5, 0.5].forEach((x) => [-0.5, 0.5].forEach((y) => [-0.5, 0.5].forEach((z) => {
      out.expandByPoint(new THREE.Vector3(x * size[0], y * size[1], z * size[2]).applyMatrix4(m));
    })));
    return out;
  }
  let floor = null;
  function fitCamera() {
    const box = new THREE.Box3();
    const p = new THREE.Vector3();
    F.nodes.forEach((a) => {
      for (let o = 0; o + 7 <= a.length; o += 7) box.expandByPoint(p.set(a[o], a[o + 1], a[o + 2]));
    });
    SCENE.path.forEach((q) => box.expandByPoint(p.set(q[0], q[1], q[2])));
    if (box.isEmpty()) box.expandByPoint(p.set(0, 0, 0));
    if (COLL && COLL.obstacles.length) {  // the obstacles near the arms and the path
      const near = box.clone().expandByScalar(0.5);
      COLL.obstacles.forEach((o) => box.union(partBox(o.part).intersect(near)));
    }
    const c = box.getCenter(new THREE.Vector3());
    const r = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.5);
    if (floor) root.remove(floor);
    floor = new THREE.GridHelper(Math.ceil(6 * r), Math.ceil(6 * r) * 4, 0x888888, 0xbbbbbb);
    floor.rotation.x = Math.PI / 2;  // three.js grids lie in x-z; ours in x-y
    floor.position.set(c.x, c.y, box.min.z);
    root.add(floor);
    // The camera lives in MeshCat's y-up frame: z-up (x, y, z) is (x, z, -y) there.
    const eye = [c.x + 0.75 * r, c.y - 1.05 * r, c.z + 0.6 * r];
    viewer.camera.position.set(eye[0], eye[2], -eye[1]);
    viewer.controls.target.set(c.x, c.z, -c.y);
    viewer.controls.update();
    viewer.set_dirty();
  }

  // --- status for tests: errors, requests made, where the arms are on screen -----------
  function afterRender(fn) {
    requestAnimationFrame(() => requestAnimationFrame(fn));
  }
  function measure() {
    const st = $("dualarm-status");
    const canvas = viewer.renderer.domElement;
    const rect = canvas.getBoundingClientRect();
    root.updateMatrixWorld(true);
    viewer.camera.updateMatrixWorld(true);
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    const v = new THREE.Vector3();
    arms.forEach((arm) => arm.nodes.forEach((node) => {
      node.getWorldPosition(v).project(viewer.camera);
      const x = rect.left + (v.x + 1) / 2 * rect.width;
      const y = rect.top + (1 - v.y) / 2 * rect.height;
      x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y);
    }));
    const requests = performance.getEntriesByType("resource")
      .filter((e) => !/^(data|blob):/.test(e.name)).map((e) => e.name);
    st.dataset.frame = String(current);
    st.dataset.armBox = [x0, y0, x1, y1].map((z) => Math.round(z)).join(",");
    st.dataset.canvas = [rect.left, rect.top, rect.width, rect.height].map(Math.round).join(",");
    st.dataset.requests = String(requests.length);
    let shown = 0, flaggedAxes = 0, total = 0;
    arms.forEach((arm) => arm.joints.forEach((mesh, i) => {
      total += 1;
      shown += mesh.visible ? 1 : 0;
      flaggedAxes += arm.state[i] > 0 ? 1 : 0;
    }));
    st.dataset.axes = [shown, flaggedAxes, total].join(",");
    st.dataset.allAxes = allAxes.checked ? "1" : "0";
    if (COLL) {
      st.dataset.obstacles = String(obstacles.children.length);
      st.dataset.shapes = [shapeObjects.filter((o) => o.visible).length,
                           shapeObjects.length].join(",");
      st.dataset.shapesOn = shapesBox.checked ? "1" : "0";
      st.dataset.near = nearest.visible ? $("near-label").textContent : "";
    }
    st.dataset.errors = String(report.errors.length);
    $("dualarm-errors").textContent = report.errors.concat(requests).join("\n");
    st.dataset.ready = "1";
  }

  // --- playback ---------------------------------------------------------------------
  let playing = true, clock = 0, last = null;
  const speed = () => parseFloat($("speed").value);
  function indexAt(t) {
    let lo = 0, hi = F.t.length - 1;
    if (hi < 0) return -1;
    if (t <= F.t[0]) return 0;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (F.t[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function setPlaying(on) {
    playing = on;
    $("play").textContent = on ? "Pause" : "Play";
    last = null;
  }
  function tick(now) {
    requestAnimationFrame(tick);
    placeLabel();  // the camera may have moved
    if (!playing || F.t.length === 0) return;
    if (DATA.live) {
      if (current !== F.t.length - 1) show(F.t.length - 1);
      return;
    }
    if (last !== null) clock += (now - last) / 1000 * speed();
    last = now;
    const end = F.t[F.t.length - 1];
    if (clock > end + 1.0) clock = F.t[0];  // loop after a one-second hold
    const k = indexAt(clock);
    if (k !== current) show(k);
  }
  function seekFromHash() {
    const shapes = /(?:^#|&)shapes=([01])/.exec(location.hash);
    if (shapes && COLL && shapesBox.checked !== (shapes[1] === "1")) shapesBox.click();
    const m = /(?:^#|&)t=([-0-9.eE+]+)/.exec(location.hash);
    if (!m || F.t.length === 0) return false;
    setPlaying(false);
    clock = parseFloat(m[1]);
    show(indexAt(clock));
    return true;
  }
  $("play").addEventListener("click", () => {
    if (!playing && !DATA.live && clock >= F.t[F.t.length - 1]) clock = F.t[0];
    setPlaying(!playing);
  });
  $("scrub").addEventListener("input", (e) => {
    setPlaying(false);
    const k = parseInt(e.target.value, 10);
    clock = F.t[k];
    show(k);
  });
  window.addEventListener("hashchange", seekFromHash);

  // --- live samples ---------------------------------------------------------------------
  if (DATA.live) {
    $("speed").disabled = true;
    const source = new EventSource("events");
    source.onmessage = (e) => {
      const fresh = F.t.length === 0;
      addSamples(JSON.parse(e.data));
      if (fresh) { fitCamera(); show(0); }
      $("scrub").max = String(F.t.length - 1);
    };
    source.addEventListener("close", () => source.close());
  }

  $("title").textContent = SCENE.title;
  $("notes").textContent = notes.join("; ");
  fitCamera();
  if (!seekFromHash()) {
    if (F.t.length) show(0);
    else afterRender(measure);
  }
  requestAnimationFrame(tick);
  window.dualarmView = {show: show, count: () => F.t.length};
})();
