// haptloop's viewer: draws a run's scene with three.js (the global THREE of
// the inlined bundle) from the JSON in <script id="data">, either replayed
// from its samples (view.html) or streamed over a WebSocket from a running
// session (run --live), where the tips of virtual devices can be dragged.
'use strict';
(function () {
  const D = JSON.parse(document.getElementById('data').textContent);
  const $ = (id) => document.getElementById(id);
  const api = (window.haptloop = { ready: false, frames: 0, error: null });

  function fail(text) {
    const m = $('message');
    m.textContent = text;
    m.hidden = false;
    api.error = text;
  }

  // WebGL first: without it, say so in words rather than show a blank page.
  function webglMissing() {
    try {
      const c = document.createElement('canvas');
      return !(c.getContext('webgl2') || c.getContext('webgl'));
    } catch (e) {
      return true;
    }
  }
  if (typeof THREE === 'undefined') {
    fail('The three.js library inlined in this page did not load, so the scene cannot be drawn.');
    return;
  }
  if (webglMissing()) {
    fail('This page draws the scene with WebGL, which this browser does not offer (it is turned off, ' +
      'or the graphics driver is blocked). Turn hardware acceleration or WebGL on and reload. ' +
      'The run\'s figures are in summary.json and the SVG plots beside this file.');
    api.webgl = false;
    return;
  }
  api.webgl = true;

  const S = D.scene;
  $('title').textContent = S.scene + (D.live ? ' (live)' : '');
  $('description').textContent = S.description;
  const size = Math.max(S.size_m || 0.1, 1e-3);
  const COLOURS = [0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf];
  const FINGER = [0xd62728, 0x2ca02c, 0x9467bd, 0xff7f0e];

  // Renderer, camera, controls. Up is against gravity (z in most scenes).
  const view = $('view');
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    fail('WebGL is present but refused to start (' + e.message + '), so the scene cannot be drawn.');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xfbfbfa);
  view.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const g = new THREE.Vector3().fromArray(S.gravity_m_s2);
  const up = g.lengthSq() > 0 ? g.clone().negate().normalize() : new THREE.Vector3(0, 0, 1);
  const camera = new THREE.PerspectiveCamera(40, 1, size / 100, size * 200);
  camera.up.copy(up);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;
  // Drawn on demand (a change of time, a frame, the camera), not at every
  // display refresh: a software-rendered page must not eat the machine the
  // session runs on.
  let dirty = true;
  controls.addEventListener('change', () => (dirty = true));
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.copy(up).multiplyScalar(3 * size).add(new THREE.Vector3(size, size, 0));
  scene.add(sun);

  // Bodies: shapes, or links between the anchors of shape-less bodies.
  const bodies = S.bodies.map((b, k) => {
    const group = new THREE.Group();
    group.name = b.name;
    const colour = b.fixed ? 0x9a9a9a : b.fingertip ? 0x5a5a5a : COLOURS[k % COLOURS.length];
    const mat = new THREE.MeshStandardMaterial({ color: colour, roughness: 0.6, metalness: 0.1,
      transparent: !!b.fixed && !!b.shape, opacity: b.fixed && b.shape ? 0.55 : 1 });
    const add = (geom, at) => {
      const m = new THREE.Mesh(geom, mat);
      if (at) m.position.copy(at);
      m.userData.body = b.name;
      group.add(m);
      return m;
    };
    const sh = b.shape;
    if (sh && sh.box) add(new THREE.BoxGeometry(2 * sh.box[0], 2 * sh.box[1], 2 * sh.box[2]));
    else if (sh && sh.sphere !== undefined) add(new THREE.SphereGeometry(sh.sphere, 24, 16));
    else if (sh && sh.capsule) {
      const m = add(new THREE.CapsuleGeometry(sh.capsule.radius, 2 * sh.capsule.half_height, 8, 16));
      m.rotation.x = Math.PI / 2; // three's capsule runs along y, ours along z
    } else if (sh && sh.convex) {
      add(new THREE.ConvexGeometry(sh.convex.map((p) => new THREE.Vector3().fromArray(p))));
    } else {
      const pts = b.links.map((p) => new THREE.Vector3().fromArray(p));
      const r = size * 0.015;
      pts.forEach((p) => add(new THREE.SphereGeometry(r * 1.6, 16, 12), p));
      const centre = pts.reduce((a, p) => a.add(p), new THREE.Vector3()).multiplyScalar(1 / Math.max(pts.length, 1));
      const ends = pts.length === 2 ? [[pts[0], pts[1]]] : pts.map((p) => [p, centre]);
      for (const [a, c] of ends) {
        const len = a.distanceTo(c);
        if (len < 1e-9) continue;
        const m = add(new THREE.CylinderGeometry(r, r, len, 12), a.clone().add(c).multiplyScalar(0.5));
        m.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), c.clone().sub(a).normalize());
      }
    }
    group.position.fromArray(b.position_m);
    const o = b.orientation;
    group.quaternion.set(o[1], o[2], o[3], o[0]);
    scene.add(group);
    return group;
  });

  // Fingers: the device point, the fingertip, the line between them (the
  // coupling), the rendered force as an arrow. Virtual devices also show the
  // mouse's target.
  const peak = Math.max(1e-3, ...S.devices.map((d) => d.peak_force_n || 0));
  // Arrows: half the mechanism's size for 5 N (or the peak, if lower).
  const arrowPerN = (size * 0.5) / Math.min(peak, 5);
  const virtualDevices = S.devices.filter((d) => d.model === 'virtual').map((d) => d.name);
  const fingers = S.fingers.map((f, k) => {
    const c = FINGER[k % FINGER.length];
    const dev = new THREE.Mesh(new THREE.SphereGeometry(size * 0.025, 20, 14),
      new THREE.MeshStandardMaterial({ color: c, emissive: c, emissiveIntensity: 0.25 }));
    dev.userData.finger = k;
    const tip = new THREE.Mesh(new THREE.SphereGeometry(size * 0.012, 16, 12),
      new THREE.MeshStandardMaterial({ color: 0x222222 }));
    const lineGeom = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
    const line = new THREE.Line(lineGeom, new THREE.LineBasicMaterial({ color: c }));
    const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1e-6, c,
      size * 0.08, size * 0.05);
    arrow.children.forEach((ch) => (ch.userData.finger = k));
    const isVirtual = virtualDevices.includes(f.device);
    const target = new THREE.Mesh(new THREE.SphereGeometry(size * 0.03, 20, 14),
      new THREE.MeshBasicMaterial({ color: c, wireframe: true }));
    target.visible = false;
    scene.add(dev, tip, line, arrow, target);
    return { info: f, dev, tip, line, arrow, target, isVirtual, force: new THREE.Vector3() };
  });

  // Contacts: points and normals, drawn from a pool of line segments.
  const MAX_CONTACTS = 256;
  const cGeom = new THREE.BufferGeometry();
  cGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(MAX_CONTACTS * 6), 3));
  const normals = new THREE.LineSegments(cGeom, new THREE.LineBasicMaterial({ color: 0x000000 }));
  const pGeom = new THREE.BufferGeometry();
  pGeom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(MAX_CONTACTS * 3), 3));
  const points = new THREE.Points(pGeom, new THREE.PointsMaterial({ color: 0x000000, size: 6, sizeAttenuation: false }));
  scene.add(normals, points);
  function drawContacts(rows) {
    const n = Math.min(rows.length, MAX_CONTACTS);
    const L = cGeom.attributes.position.array, P = pGeom.attributes.position.array;
    for (let i = 0; i < n; i++) {
      const r = rows[i];
      for (let a = 0; a < 3; a++) {
        P[3 * i + a] = r[a];
        L[6 * i + a] = r[a];
        L[6 * i + 3 + a] = r[a] + r[3 + a] * size * 0.15;
      }
    }
    cGeom.setDrawRange(0, 2 * n);
    pGeom.setDrawRange(0, n);
    cGeom.attributes.position.needsUpdate = true;
    pGeom.attributes.position.needsUpdate = true;
  }

  // A floor grid through the lowest point, facing up, for orientation.
  (function floor() {
    const box = new THREE.Box3();
    bodies.forEach((b) => box.expandByObject(b));
    if (box.isEmpty()) return;
    const c = box.getCenter(new THREE.Vector3());
    const low = Math.min(...[box.min, box.max].map((p) => p.dot(up)));
    const span = Math.max(box.getSize(new THREE.Vector3()).length() * 2, size * 2);
    const step = Math.pow(10, Math.floor(Math.log10(span / 4)));
    const div = Math.max(2, Math.round(span / step));
    const grid = new THREE.GridHelper(div * step, div, 0xcccccc, 0xe4e4e4);
    grid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), up);
    grid.position.copy(c).add(up.clone().multiplyScalar(low - c.dot(up)));
    scene.add(grid);
  })();

  // Frame the initial scene: centre on the moving bodies and fingers.
  (function frame() {
    const box = new THREE.Box3();
    S.bodies.forEach((b, k) => { if (!b.fixed || S.bodies.every((x) => x.fixed)) box.expandByObject(bodies[k]); });
    if (box.isEmpty()) box.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(size, size, size));
    const c = box.getCenter(new THREE.Vector3());
    const span = Math.max(box.getSize(new THREE.Vector3()).length(), size);
    const side = new THREE.Vector3(1, -1.6, 0).normalize();
    if (Math.abs(side.dot(up)) > 0.9) side.set(1, 0, 0);
    camera.position.copy(c).add(side.multiplyScalar(2.2 * span)).add(up.clone().multiplyScalar(1.1 * span));
    controls.target.copy(c);
    camera.near = Math.min(size, span) / 100;
    camera.far = Math.max(size, span) * 200;
    camera.updateProjectionMatrix();
    controls.update();
  })();

  function setFinger(k, d, t, f) {
    const F = fingers[k];
    F.dev.position.set(d[0], d[1], d[2]);
    F.tip.position.set(t[0], t[1], t[2]);
    const pos = F.line.geometry.attributes.position;
    pos.setXYZ(0, d[0], d[1], d[2]);
    pos.setXYZ(1, t[0], t[1], t[2]);
    pos.needsUpdate = true;
    F.force.set(f[0], f[1], f[2]);
    const n = F.force.length();
    F.arrow.position.copy(F.dev.position);
    F.arrow.visible = n > 1e-6;
    if (n > 1e-6) {
      F.arrow.setDirection(F.force.clone().multiplyScalar(1 / n));
      const len = Math.max(n * arrowPerN, size * 0.1);
      F.arrow.setLength(len, Math.min(size * 0.08, 0.3 * len), Math.min(size * 0.05, 0.2 * len));
    }
  }

  function setPose(k, p) {
    const b = bodies[k];
    b.position.set(p[0], p[1], p[2]);
    b.quaternion.set(p[4], p[5], p[6], p[3]);
  }

  // Which bodies are in the scene at time t: those not absent at the start,
  // then each `add` and `remove` event up to t, in time order. A body
  // declared but not yet added (or already removed) is not drawn.
  const bodyIndex = new Map(S.bodies.map((b, k) => [b.name, k]));
  function showPresent(events, t) {
    const present = S.bodies.map((b) => !b.absent);
    for (const e of events) {
      if (e.t_s > t) break;
      const k = bodyIndex.get(e.body);
      if (k === undefined) continue;
      if (e.kind === 'add') present[k] = true;
      else if (e.kind === 'remove') present[k] = false;
    }
    bodies.forEach((o, k) => (o.visible = present[k]));
  }
  showPresent([], 0);
  api.visible = (name) => (bodyIndex.has(name) ? bodies[bodyIndex.get(name)].visible : null);

  // ---- plots (none that would stay empty) ----
  $('box-violation').hidden = !S.joints;
  $('box-penetration').hidden = !S.bodies.some((b) => b.shape && !b.fixed);
  const plots = {
    force: { el: $('plot-force'), log: false },
    violation: { el: $('plot-violation'), log: true },
    penetration: { el: $('plot-penetration'), log: false },
  };
  function drawPlot(p, series, tMax, now, limits) {
    const ctx = p.el.getContext('2d');
    const W = p.el.width, H = p.el.height, L = 44, B = 16;
    ctx.clearRect(0, 0, W, H);
    let lo = Infinity, hi = -Infinity;
    for (const s of series) for (const v of s.v) if (Number.isFinite(v) && (!p.log || v > 0)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    for (const l of limits || []) hi = Math.max(hi, l.v * 1.05);
    if (!isFinite(hi)) { lo = p.log ? 1e-12 : 0; hi = 1; }
    if (p.log) { lo = Math.max(lo, hi * 1e-12); lo = Math.pow(10, Math.floor(Math.log10(lo))); hi = Math.pow(10, Math.ceil(Math.log10(hi))); }
    else { lo = 0; hi = hi > 0 ? hi * 1.1 : 1; }
    const tx = (t) => L + ((W - L - 4) * t) / Math.max(tMax, 1e-9);
    const ty = (v) => p.log ? H - B - ((H - B - 4) * (Math.log10(Math.max(v, lo)) - Math.log10(lo))) / (Math.log10(hi) - Math.log10(lo) || 1)
      : H - B - ((H - B - 4) * (v - lo)) / (hi - lo || 1);
    ctx.strokeStyle = '#bbb'; ctx.strokeRect(L, 2, W - L - 4, H - B - 2);
    ctx.fillStyle = '#555'; ctx.font = '10px sans-serif';
    const fmt = (v) => p.log ? v.toExponential(0) : v.toPrecision(2);
    ctx.fillText(fmt(hi), 2, 10); ctx.fillText(fmt(lo), 2, H - B);
    ctx.fillText('0', L, H - 4); ctx.fillText(tMax.toFixed(1) + ' s', W - 40, H - 4);
    for (const l of limits || []) {
      ctx.setLineDash([4, 3]); ctx.strokeStyle = l.colour; ctx.beginPath();
      ctx.moveTo(L, ty(l.v)); ctx.lineTo(W - 4, ty(l.v)); ctx.stroke(); ctx.setLineDash([]);
      ctx.fillStyle = l.colour; ctx.fillText(l.label, L + 4, ty(l.v) - 2);
    }
    for (const s of series) {
      ctx.strokeStyle = s.colour; ctx.beginPath();
      let pen = false;
      for (let i = 0; i < s.t.length; i++) {
        const v = s.v[i];
        if (!Number.isFinite(v)) { pen = false; continue; }
        const x = tx(s.t[i]), y = ty(v);
        if (pen) ctx.lineTo(x, y); else ctx.moveTo(x, y);
        pen = true;
      }
      ctx.stroke();
    }
    ctx.strokeStyle = '#000'; ctx.beginPath(); ctx.moveTo(tx(now), 2); ctx.lineTo(tx(now), H - B); ctx.stroke();
  }
  const hex = (c) => '#' + c.toString(16).padStart(6, '0');
  function forceLimits() {
    const out = [];
    const seen = new Set();
    for (const d of S.devices) {
      if (seen.has(d.model)) continue;
      seen.add(d.model);
      out.push({ v: d.peak_force_n, colour: '#a33', label: d.model + ' peak ' + d.peak_force_n + ' N' });
      if (d.continuous_force_n < d.peak_force_n)
        out.push({ v: d.continuous_force_n, colour: '#c80', label: 'continuous ' + d.continuous_force_n + ' N' });
    }
    return out;
  }

  // ---- hover: body names and force values ----
  const ray = new THREE.Raycaster();
  const mouse = new THREE.Vector2();
  function pick(ev, objects) {
    const r = renderer.domElement.getBoundingClientRect();
    mouse.set(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    ray.setFromCamera(mouse, camera);
    return ray.intersectObjects(objects, true)[0];
  }
  renderer.domElement.addEventListener('mousemove', (ev) => {
    if (drag) return;
    const hit = pick(ev, [...fingers.map((f) => f.arrow), ...fingers.map((f) => f.dev), ...bodies]);
    const tip = $('tip');
    if (!hit) { tip.hidden = true; return; }
    let o = hit.object, text = null;
    if (o.userData.finger !== undefined) {
      const F = fingers[o.userData.finger];
      text = F.info.name + ' (' + F.info.device + '): ' + F.force.length().toFixed(3) + ' N' +
        (F.isVirtual && D.live ? ' — drag to move' : '');
    } else {
      while (o && !o.userData.body && o.parent) o = o.parent;
      text = o && o.userData.body ? o.userData.body : null;
    }
    if (!text) { tip.hidden = true; return; }
    const r = view.getBoundingClientRect();
    tip.textContent = text;
    tip.style.left = ev.clientX - r.left + 12 + 'px';
    tip.style.top = ev.clientY - r.top + 12 + 'px';
    tip.hidden = false;
  });

  function resize() {
    const w = view.clientWidth, h = view.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();

  // Screen position (CSS px in the page) of a scene point, and how many
  // metres one pixel is at its depth in the plane facing the camera.
  api.screenOf = (p) => {
    const v = new THREE.Vector3().fromArray(p).project(camera);
    const r = renderer.domElement.getBoundingClientRect();
    return [r.left + ((v.x + 1) / 2) * r.width, r.top + ((1 - v.y) / 2) * r.height];
  };
  api.camera = () => {
    camera.updateMatrixWorld();
    return {
      position: camera.position.toArray(), fov_deg: camera.fov, up: camera.up.toArray(),
      direction: camera.getWorldDirection(new THREE.Vector3()).toArray(),
      view: camera.matrixWorldInverse.toArray(), projection: camera.projectionMatrix.toArray(),
    };
  };
  api.devicePoint = (k) => fingers[k].dev.position.toArray();
  api.canvasRect = () => { const r = renderer.domElement.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; };

  let drag = null;
  const ui = { playing: false, speed: 1, t: 0, tMax: 0 };
  $('speed').addEventListener('change', (e) => (ui.speed = parseFloat(e.target.value)));

  if (D.live) live(); else replay();

  // ---------------- replay of a run's files ----------------
  function replay() {
    const T = D.t, moving = D.moving;
    const FT = D.fingers.t;
    ui.tMax = Math.max(T.length ? T[T.length - 1] : 0, FT.length ? FT[FT.length - 1] : 0);
    const slider = $('time');
    slider.max = ui.tMax;
    slider.step = Math.max(ui.tMax / 2000, 1e-4);
    $('help').textContent = 'drag: orbit · right-drag: pan · wheel: zoom · space: play/pause · hover: names and forces';
    const marks = $('marks');
    for (const e of D.events) {
      const s = document.createElement('span');
      s.style.left = (100 * e.t_s) / Math.max(ui.tMax, 1e-9) + '%';
      s.title = e.t_s.toFixed(3) + ' s: ' + e.text;
      marks.appendChild(s);
      const li = document.createElement('li');
      li.textContent = e.t_s.toFixed(3) + ' s  ' + e.text;
      li.dataset.t = e.t_s;
      $('events').appendChild(li);
    }
    // Contacts grouped by time.
    const cTimes = [], cRows = [];
    for (let i = 0; i < D.contacts.length; i += 8) {
      const t = D.contacts[i];
      if (cTimes[cTimes.length - 1] !== t) { cTimes.push(t); cRows.push([]); }
      cRows[cRows.length - 1].push(D.contacts.slice(i + 1, i + 8));
    }
    const q0 = new THREE.Quaternion(), q1 = new THREE.Quaternion();
    const lower = (arr, t) => { let a = 0, b = arr.length - 1; if (b < 0 || t <= arr[0]) return 0; if (t >= arr[b]) return b; while (b - a > 1) { const m = (a + b) >> 1; if (arr[m] <= t) a = m; else b = m; } return a; };
    function show(t) {
      ui.t = t;
      if (T.length) {
        const i = lower(T, t), j = Math.min(i + 1, T.length - 1);
        const u = j > i ? Math.min(Math.max((t - T[i]) / (T[j] - T[i]), 0), 1) : 0;
        moving.forEach((k, s) => {
          const P = D.poses[s], a = 7 * i, b = 7 * j;
          const p = [0, 1, 2].map((c) => P[a + c] + u * (P[b + c] - P[a + c]));
          q0.set(P[a + 4], P[a + 5], P[a + 6], P[a + 3]);
          q1.set(P[b + 4], P[b + 5], P[b + 6], P[b + 3]);
          q0.slerp(q1, u);
          setPose(k, [p[0], p[1], p[2], q0.w, q0.x, q0.y, q0.z]);
        });
      }
      if (FT.length) {
        const i = lower(FT, t);
        fingers.forEach((_, k) => {
          const s = (a) => a[k].slice(3 * i, 3 * i + 3);
          setFinger(k, s(D.fingers.device), s(D.fingers.tip), s(D.fingers.force));
        });
      }
      showPresent(D.events, t);
      const ci = lower(cTimes, t);
      drawContacts(cTimes.length && Math.abs(cTimes[ci] - t) < 0.02 ? cRows[ci] : []);
      slider.value = t;
      $('clock').textContent = t.toFixed(3) + ' s';
      readout(t);
      for (const li of $('events').children) li.className = parseFloat(li.dataset.t) <= t ? 'past' : '';
      drawPlots(t);
      api.time = t;
    }
    api.setTime = (t) => { ui.playing = false; $('play').textContent = '▶'; show(Math.min(Math.max(t, 0), ui.tMax)); render(); return ui.t; };
    function readout(t) {
      const lines = fingers.map((F) => F.info.name.padEnd(8) + ' ' + F.force.length().toFixed(3) + ' N');
      $('readout').textContent = lines.join('\n');
    }
    function drawPlots(t) {
      const st = D.series.t;
      drawPlot(plots.force, D.series.force.map((v, k) => ({ t: st, v, colour: hex(FINGER[k % FINGER.length]) })), ui.tMax, t, forceLimits());
      drawPlot(plots.violation, [{ t: st, v: D.series.violation, colour: '#1f77b4' }], ui.tMax, t);
      drawPlot(plots.penetration, [{ t: D.series.penetration.map((p) => p[0]), v: D.series.penetration.map((p) => p[1] * 1e3), colour: '#8c564b' }], ui.tMax, t);
    }
    slider.addEventListener('input', () => { show(parseFloat(slider.value)); dirty = true; });
    const toggle = () => { ui.playing = !ui.playing; if (ui.playing && ui.t >= ui.tMax) ui.t = 0; $('play').textContent = ui.playing ? '❚❚' : '▶'; };
    $('play').addEventListener('click', toggle);
    window.addEventListener('keydown', (e) => { if (e.code === 'Space') { e.preventDefault(); toggle(); } });
    let last = performance.now();
    function loop(now) {
      const dt = (now - last) / 1000;
      last = now;
      if (ui.playing) {
        let t = ui.t + dt * ui.speed;
        if (t >= ui.tMax) { t = ui.tMax; toggle(); }
        show(t);
        dirty = true;
      }
      if (dirty) render();
      requestAnimationFrame(loop);
    }
    show(0);
    requestAnimationFrame(loop);
  }

  function render() {
    dirty = false;
    renderer.render(scene, camera);
    api.frames += 1;
    api.ready = true;
  }
  window.addEventListener('resize', () => (dirty = true));

  // ---------------- live: a running session over a WebSocket ----------------
  function live() {
    $('play').disabled = true;
    $('speed').disabled = true;
    $('time').disabled = true;
    $('help').textContent = virtualDevices.length
      ? 'drag a coloured ball (a virtual device) to move it · wheel while dragging: depth · arrows / PgUp / PgDn: move the last one · elsewhere: orbit, pan, zoom'
      : 'drag: orbit · right-drag: pan · wheel: zoom · hover: names and forces';
    const hist = { t: [], force: fingers.map(() => []), violation: [], pen: [] };
    const WINDOW_S = 20;
    let ws;
    try {
      ws = new WebSocket('ws://' + location.host + '/ws');
    } catch (e) {
      fail('Cannot open the live connection: ' + e.message);
    }
    let selected = fingers.findIndex((f) => f.isVirtual);
    const targets = fingers.map(() => null);
    let lastSent = 0;
    let liveEvents = [];
    function send(k, p) {
      targets[k] = p.clone();
      fingers[k].target.position.copy(p);
      fingers[k].target.visible = true;
      dirty = true;
      if (ws && ws.readyState === 1) {
        ws.send(JSON.stringify({ type: 'pointer', device: fingers[k].info.device, target: p.toArray() }));
        api.sent = (api.sent || 0) + 1;
      }
    }
    if (ws) {
      ws.onmessage = (ev) => {
        const m = JSON.parse(ev.data);
        if (m.type === 'frame') frame(m);
        else if (m.type === 'end') { $('clock').textContent += ' (ended)'; fail('The session ended; its report and files are where `haptloop run` said.'); }
      };
      ws.onclose = () => { if (!api.error) fail('The live connection closed: the session has ended or stopped.'); };
      ws.onerror = () => { if (!api.error) fail('The live connection failed: is `haptloop run --live` still running?'); };
    }
    function frame(m) {
      (m.poses || []).forEach((p, s) => setPose(D.moving[s], p));
      (m.fingers || []).forEach((f, k) => setFinger(k, f.device, f.tip, f.force));
      drawContacts(m.contacts || []);
      ui.t = m.t;
      $('clock').textContent = m.t.toFixed(3) + ' s';
      $('readout').textContent = fingers.map((F) => F.info.name.padEnd(8) + ' ' + F.force.length().toFixed(3) + ' N').join('\n');
      hist.t.push(m.t);
      fingers.forEach((F, k) => hist.force[k].push(F.force.length()));
      hist.violation.push(m.violation);
      hist.pen.push(1e3 * Math.max(0, ...(m.contacts || []).map((c) => -c[6])));
      while (hist.t.length && hist.t[0] < m.t - WINDOW_S) { hist.t.shift(); hist.force.forEach((a) => a.shift()); hist.violation.shift(); hist.pen.shift(); }
      if (m.events) liveEvents = m.events;
      showPresent(liveEvents, m.t);
      if (m.events) {
        const ol = $('events');
        ol.textContent = '';
        for (const e of m.events) { const li = document.createElement('li'); li.textContent = e.t_s.toFixed(3) + ' s  ' + e.text; ol.appendChild(li); }
      }
      const t0 = hist.t[0] || 0, rel = hist.t.map((t) => t - t0);
      drawPlot(plots.force, hist.force.map((v, k) => ({ t: rel, v, colour: hex(FINGER[k % FINGER.length]) })), Math.max(m.t - t0, 1e-3), m.t - t0, forceLimits());
      drawPlot(plots.violation, [{ t: rel, v: hist.violation, colour: '#1f77b4' }], Math.max(m.t - t0, 1e-3), m.t - t0);
      drawPlot(plots.penetration, [{ t: rel, v: hist.pen, colour: '#8c564b' }], Math.max(m.t - t0, 1e-3), m.t - t0);
      api.time = m.t;
      api.lastFrame = m;
      dirty = true;
    }
    // Dragging a virtual device's ball: the plane through it facing the
    // camera; the wheel moves the target along the view direction.
    const plane = new THREE.Plane();
    const el = renderer.domElement;
    // The virtual device's ball nearest the pointer, within 14 px of its
    // drawn centre (small balls are hard to hit exactly).
    function grab(ev) {
      let best = -1, bestD = 14;
      fingers.forEach((F, k) => {
        if (!F.isVirtual) return;
        const [x, y] = api.screenOf(F.dev.position.toArray());
        const d = Math.hypot(x - ev.clientX, y - ev.clientY);
        if (d < bestD) { best = k; bestD = d; }
      });
      return best;
    }
    el.addEventListener('pointerdown', (ev) => {
      const k = grab(ev);
      if (k < 0) return;
      pick(ev, []);
      selected = k;
      $('tip').hidden = true;
      const start = (targets[k] || fingers[k].dev.position).clone();
      api.dragStart = start.toArray();
      plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), start);
      const at = new THREE.Vector3();
      ray.ray.intersectPlane(plane, at);
      drag = { k, offset: start.clone().sub(at), id: ev.pointerId };
      controls.enabled = false;
      el.setPointerCapture(ev.pointerId);
      ev.preventDefault();
    });
    el.addEventListener('pointermove', (ev) => {
      if (!drag) return;
      pick(ev, []);
      const at = new THREE.Vector3();
      if (!ray.ray.intersectPlane(plane, at)) return;
      const now = performance.now();
      if (now - lastSent < 8) return;
      lastSent = now;
      send(drag.k, at.add(drag.offset));
    });
    const release = (ev) => {
      if (!drag) return;
      pick(ev, []);
      const at = new THREE.Vector3();
      if (ray.ray.intersectPlane(plane, at)) send(drag.k, at.add(drag.offset));
      drag = null;
      controls.enabled = true;
    };
    el.addEventListener('pointerup', release);
    el.addEventListener('pointercancel', release);
    el.addEventListener('wheel', (ev) => {
      if (!drag) return;
      ev.preventDefault();
      ev.stopPropagation();
      const dir = camera.getWorldDirection(new THREE.Vector3());
      const p = (targets[drag.k] || fingers[drag.k].dev.position).clone().add(dir.multiplyScalar(-Math.sign(ev.deltaY) * size * 0.02));
      plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), p);
      send(drag.k, p);
    }, { capture: true, passive: false });
    window.addEventListener('keydown', (ev) => {
      if (selected < 0) return;
      const step = (ev.shiftKey ? 0.01 : 0.002) * Math.max(size / 0.1, 0.1);
      const dir = camera.getWorldDirection(new THREE.Vector3());
      const right = dir.clone().cross(camera.up).normalize();
      const upv = right.clone().cross(dir).normalize();
      const moves = { ArrowLeft: right.clone().negate(), ArrowRight: right, ArrowUp: upv, ArrowDown: upv.clone().negate(), PageUp: dir, PageDown: dir.clone().negate() };
      const d = moves[ev.key];
      if (!d) return;
      ev.preventDefault();
      send(selected, (targets[selected] || fingers[selected].dev.position).clone().add(d.multiplyScalar(step)));
    });
    (function loop() { if (dirty) render(); requestAnimationFrame(loop); })();
  }
})();
