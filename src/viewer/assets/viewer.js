// vkmesh's browser viewer (docs/VIEWER.md): keeps a replica of the mesh from the server's WebSocket messages
// (mesh-delta records, docs/DELTAS.md) in typed arrays indexed by vertex and triangle id, and draws it with
// three.js. Ids are dense (heap indices, chunk slots), so a removed triangle becomes (0, 0, 0), which draws
// nothing, and an update uploads only the id range it touched.
'use strict';
(function () {
  const MAGIC = 0x564D4B56, VERSION = 1, RESET = 1, HAS_CAMERA = 2, HEADER_WORDS = 30;
  const ID_MASK = 0x3FFFFFFF, REMOVED = 2, SOURCE_STREAM = 1, SOURCE_LIVE = 2;
  const params = new URLSearchParams(location.search);
  const el = (id) => document.getElementById(id);
  const status = (text) => { el('vkmesh-status').textContent = text; };

  const canvas = el('vkmesh-canvas');
  // Multisampling costs a software renderer (SwiftShader, llvmpipe) several times its frame time: off there, and
  // wherever ?aa=0 asks; on elsewhere (?aa=1 forces it).
  const software = (() => {
    const probe = document.createElement('canvas').getContext('webgl2');
    const info = probe && probe.getExtension('WEBGL_debug_renderer_info');
    const name = info ? String(probe.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
    if (probe && probe.getExtension('WEBGL_lose_context')) probe.getExtension('WEBGL_lose_context').loseContext();
    return /swiftshader|llvmpipe|softpipe/i.test(name);
  })();
  const antialias = params.has('aa') ? params.get('aa') !== '0' : !software;
  const gl = canvas.getContext('webgl2', { antialias: antialias });
  if (!gl) { status('WebGL2 is not available in this browser'); return; }
  const renderer = new THREE.WebGLRenderer({ canvas: canvas, context: gl, antialias: antialias });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x20242a);
  const camera = new THREE.PerspectiveCamera(50, 1, 0.01, 1000);
  camera.up.set(0, 0, 1);   // vkmesh's synthetic room: z up (a live camera's pose picks the axis, showCamera)
  camera.position.set(3, 3, 2);
  scene.add(camera);
  scene.add(new THREE.AmbientLight(0xffffff, 0.45));
  const headlight = new THREE.DirectionalLight(0xffffff, 0.75);
  headlight.position.set(0.3, 0.6, 1);
  camera.add(headlight);   // lit from the viewer: every side the user turns to is lit
  const controls = new THREE.OrbitControls(camera, canvas);
  let userMoved = false;
  controls.addEventListener('start', () => { userMoved = true; });

  // ---- the replica ----
  let vCap = 0, tCap = 0, vCount = 0, tCount = 0, tHigh = -1;
  let pos, nrm, col, idx, vAlive, tAlive;
  let geometry = null;
  let dirtyV = [Infinity, -1], dirtyT = [Infinity, -1];
  let anyNormal = false;
  const material = new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide });
  const mesh = new THREE.Mesh(new THREE.BufferGeometry(), material);
  mesh.frustumCulled = false;
  scene.add(mesh);
  const bboxMin = new THREE.Vector3(Infinity, Infinity, Infinity), bboxMax = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
  let fittedDiagonal = 0;

  function grow(oldArray, size, Type) {
    const a = new Type(size);
    if (oldArray) a.set(oldArray.subarray(0, Math.min(oldArray.length, size)));
    return a;
  }
  function rebuildGeometry() {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    g.setAttribute('normal', new THREE.BufferAttribute(nrm, 3));
    g.setAttribute('color', new THREE.BufferAttribute(col, 3, true));
    g.setIndex(new THREE.BufferAttribute(idx, 1));
    if (geometry) geometry.dispose();
    geometry = g;
    mesh.geometry = g;
    dirtyV = [0, vCap - 1];
    dirtyT = [0, tCap - 1];
  }
  function ensure(vNeed, tNeed) {
    if (vNeed <= vCap && tNeed <= tCap && geometry) return;
    let v = Math.max(vCap, 1024), t = Math.max(tCap, 1024);
    while (v < vNeed) v *= 2;
    while (t < tNeed) t *= 2;
    pos = grow(pos, 3 * v, Float32Array); nrm = grow(nrm, 3 * v, Float32Array); col = grow(col, 3 * v, Uint8Array);
    vAlive = grow(vAlive, v, Uint8Array);
    idx = grow(idx, 3 * t, Uint32Array); tAlive = grow(tAlive, t, Uint8Array);
    vCap = v; tCap = t;
    rebuildGeometry();
  }
  function clearAll() {
    if (vAlive) { vAlive.fill(0); tAlive.fill(0); idx.fill(0); }
    vCount = tCount = 0; tHigh = -1;
    bboxMin.set(Infinity, Infinity, Infinity); bboxMax.set(-Infinity, -Infinity, -Infinity);
    fittedDiagonal = 0;
    trajectory.length = 0;
    dirtyV = [0, vCap - 1]; dirtyT = [0, tCap - 1];
  }

  // ---- camera frustum and trajectory ----
  const frustum = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xffb000 }));
  frustum.geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(16 * 3), 3));
  frustum.visible = false;
  frustum.frustumCulled = false;
  scene.add(frustum);
  const trajectory = [];
  const trajectoryLine = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x30c0ff }));
  trajectoryLine.frustumCulled = false;
  scene.add(trajectoryLine);
  let upFromPose = false;
  function showCamera(p, intr, w, h) {
    // Pose rows of [R | t]: world = R * cameraPoint + t; camera looks along +z, y down (vkmesh's convention).
    const depth = 0.25;
    const fx = intr[0], fy = intr[1], cx = intr[2], cy = intr[3];
    const corners = [[0, 0], [w, 0], [w, h], [0, h]].map(([u, v]) => {
      const x = (u - cx) / fx * depth, y = (v - cy) / fy * depth, z = depth;
      return [p[0] * x + p[1] * y + p[2] * z + p[3], p[4] * x + p[5] * y + p[6] * z + p[7], p[8] * x + p[9] * y + p[10] * z + p[11]];
    });
    const o = [p[3], p[7], p[11]];
    const a = frustum.geometry.attributes.position.array;
    let k = 0;
    for (let i = 0; i < 4; ++i) {
      a.set(o, k); a.set(corners[i], k + 3); k += 6;
      a.set(corners[i], k); a.set(corners[(i + 1) % 4], k + 3); k += 6;
    }
    frustum.geometry.attributes.position.needsUpdate = true;
    frustum.visible = w > 0 && fx > 0;
    if (!upFromPose && !userMoved) {
      // The world axis closest to the sensor's up (-y) at the first frame: a dataset's world frame has some axis
      // up, and the sensor's own tilt and roll would turn the whole view.
      const up = [-p[1], -p[5], -p[9]];
      const axis = [0, 1, 2].reduce((best, i) => (Math.abs(up[i]) > Math.abs(up[best]) ? i : best), 2);
      camera.up.set(0, 0, 0).setComponent(axis, Math.sign(up[axis]) || 1);
      upFromPose = true;
    }
  }
  function showTrajectory() {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(trajectory.flat()), 3));
    trajectoryLine.geometry.dispose();
    trajectoryLine.geometry = g;
  }

  function fitCamera() {
    if (userMoved || !(bboxMax.x >= bboxMin.x)) return;
    const diagonal = bboxMin.distanceTo(bboxMax);
    if (fittedDiagonal > 0 && diagonal < fittedDiagonal * 1.1) return;   // refit only when the mesh grew
    fittedDiagonal = diagonal;
    const center = bboxMin.clone().add(bboxMax).multiplyScalar(0.5);
    const dir = new THREE.Vector3(1, -1.3, 0.9).normalize();
    if (Math.abs(camera.up.z) < 0.5) dir.set(1, 0.9, -1.3).normalize().projectOnPlane(camera.up).add(camera.up.clone().multiplyScalar(0.6)).normalize();
    camera.position.copy(center).addScaledVector(dir, Math.max(diagonal, 0.1) * 0.85);
    camera.near = Math.max(diagonal, 0.1) / 1000;
    camera.far = Math.max(diagonal, 0.1) * 20;
    camera.updateProjectionMatrix();
    controls.target.copy(center);
    controls.update();
  }

  // ---- messages ----
  let bytesReceived = 0, lastFrame = 0, firstMeshAt = 0;
  function apply(buffer) {
    const u32 = new Uint32Array(buffer), f32 = new Float32Array(buffer);
    if (u32.length < HEADER_WORDS || u32[0] !== MAGIC || u32[1] !== VERSION) throw new Error('not a vkmesh viewer message');
    const flags = u32[2], nTraj = u32[7], nV = u32[8], nT = u32[9];
    if (HEADER_WORDS + 3 * nTraj + 9 * nV + 4 * nT !== u32.length) throw new Error('viewer message size does not match its counts');
    if (flags & RESET) clearAll();
    let o = HEADER_WORDS;
    for (let i = 0; i < nTraj; ++i, o += 3) trajectory.push([f32[o], f32[o + 1], f32[o + 2]]);
    // Capacities first: the largest vertex id of the records and of the triangles' corners.
    let vMax = -1, tMax = -1;
    for (let i = 0, q = o; i < nV; ++i, q += 9) vMax = Math.max(vMax, u32[q] & ID_MASK);
    for (let i = 0, q = o + 9 * nV; i < nT; ++i, q += 4) {
      tMax = Math.max(tMax, u32[q] & ID_MASK);
      if ((u32[q] >>> 30) !== REMOVED) vMax = Math.max(vMax, u32[q + 1], u32[q + 2], u32[q + 3]);
    }
    ensure(vMax + 1, tMax + 1);
    for (let i = 0; i < nV; ++i, o += 9) {
      const id = u32[o] & ID_MASK;
      if ((u32[o] >>> 30) === REMOVED) { if (vAlive[id]) { vAlive[id] = 0; --vCount; } continue; }
      if (!vAlive[id]) { vAlive[id] = 1; ++vCount; }
      const x = f32[o + 1], y = f32[o + 2], z = f32[o + 3];
      pos[3 * id] = x; pos[3 * id + 1] = y; pos[3 * id + 2] = z;
      nrm[3 * id] = f32[o + 4]; nrm[3 * id + 1] = f32[o + 5]; nrm[3 * id + 2] = f32[o + 6];
      if (f32[o + 4] !== 0 || f32[o + 5] !== 0 || f32[o + 6] !== 0) anyNormal = true;
      const c = u32[o + 8];
      if (c >>> 24) { col[3 * id] = c & 255; col[3 * id + 1] = (c >>> 8) & 255; col[3 * id + 2] = (c >>> 16) & 255; }
      else { col[3 * id] = 200; col[3 * id + 1] = 200; col[3 * id + 2] = 200; }
      if (x < bboxMin.x) bboxMin.x = x; if (y < bboxMin.y) bboxMin.y = y; if (z < bboxMin.z) bboxMin.z = z;
      if (x > bboxMax.x) bboxMax.x = x; if (y > bboxMax.y) bboxMax.y = y; if (z > bboxMax.z) bboxMax.z = z;
      if (id < dirtyV[0]) dirtyV[0] = id; if (id > dirtyV[1]) dirtyV[1] = id;
    }
    for (let i = 0; i < nT; ++i, o += 4) {
      const id = u32[o] & ID_MASK;
      if ((u32[o] >>> 30) === REMOVED) {
        if (!tAlive[id]) continue;
        tAlive[id] = 0; --tCount;
        idx[3 * id] = idx[3 * id + 1] = idx[3 * id + 2] = 0;
      } else {
        if (!tAlive[id]) { tAlive[id] = 1; ++tCount; }
        idx[3 * id] = u32[o + 1]; idx[3 * id + 1] = u32[o + 2]; idx[3 * id + 2] = u32[o + 3];
        if (id > tHigh) tHigh = id;
      }
      if (id < dirtyT[0]) dirtyT[0] = id; if (id > dirtyT[1]) dirtyT[1] = id;
    }
    // A mesh without normals (a PLY that has none) is shaded from its triangles.
    if ((flags & RESET) && !anyNormal && tCount > 0) geometry.computeVertexNormals();
    if (flags & HAS_CAMERA) showCamera(f32.subarray(10, 22), f32.subarray(22, 26), u32[26], u32[27]);
    if (nTraj > 0 || (flags & RESET)) showTrajectory();
    lastFrame = u32[3];
    el('vkmesh-frame').textContent = String(u32[3]);
    el('vkmesh-frames').textContent = u32[4] ? String(u32[4]) : (live ? 'live' : '-');
    el('vkmesh-ms').textContent = f32[5] > 0 ? f32[5].toFixed(1) : '-';
    el('vkmesh-blocks').textContent = u32[6] ? String(u32[6]) : '-';
    el('vkmesh-triangles').textContent = String(tCount);
    el('vkmesh-vertices').textContent = String(vCount);
    if (stream) {
      slider.max = String(u32[4]);
      if (!dragging) slider.value = String(u32[3]);
      if (u32[3] === u32[4] && playing) { playing = false; playButton.textContent = 'play'; }   // the server stops at the end
    }
    fitCamera();
    if (!firstMeshAt && tCount > 0) firstMeshAt = -1;   // set at the first render that draws it
  }

  function upload() {
    if (!geometry) return;
    const a = geometry.attributes;
    if (dirtyV[1] >= dirtyV[0]) {
      for (const name of ['position', 'normal', 'color']) {
        a[name].updateRange.offset = 3 * dirtyV[0];
        a[name].updateRange.count = 3 * (dirtyV[1] - dirtyV[0] + 1);
        a[name].needsUpdate = true;
      }
    }
    if (dirtyT[1] >= dirtyT[0]) {
      geometry.index.updateRange.offset = 3 * dirtyT[0];
      geometry.index.updateRange.count = 3 * (dirtyT[1] - dirtyT[0] + 1);
      geometry.index.needsUpdate = true;
    }
    dirtyV = [Infinity, -1]; dirtyT = [Infinity, -1];
    geometry.setDrawRange(0, 3 * (tHigh + 1));
  }

  // ---- the player (stream files) ----
  const slider = el('vkmesh-slider'), playButton = el('vkmesh-play');
  let stream = false, live = false, playing = true, dragging = false;
  slider.addEventListener('input', () => { dragging = true; });
  slider.addEventListener('change', () => { dragging = false; send('seek ' + slider.value); });
  playButton.addEventListener('click', () => {
    playing = !playing;
    playButton.textContent = playing ? 'pause' : 'play';
    send(playing ? 'play' : 'pause');
  });

  // ---- the connection ----
  let ws = null;
  function send(text) { if (ws && ws.readyState === WebSocket.OPEN) ws.send(text); }
  function connect() {
    ws = new WebSocket((location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws');
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => status('connected');
    ws.onmessage = (event) => {
      if (!(event.data instanceof ArrayBuffer)) return;
      bytesReceived += event.data.byteLength;
      const source = event.data.byteLength >= 4 * HEADER_WORDS ? new Uint32Array(event.data, 0, HEADER_WORDS)[29] : 0;
      stream = source === SOURCE_STREAM;
      live = source === SOURCE_LIVE;
      el('vkmesh-player').hidden = !stream;
      try {
        apply(event.data);
      } catch (e) {
        status('error: ' + e.message);
        ws.close();
        return;
      }
      status(stream ? 'playing a stream file' : live ? 'live' : 'mesh');
      send('ack ' + lastFrame);
      el('vkmesh-mb').textContent = (bytesReceived / 1e6).toFixed(2);
    };
    ws.onclose = () => {
      status('disconnected (the server stopped?); retrying');
      setTimeout(connect, 2000);
    };
  }
  connect();

  // ---- drawing; ?bench=SECONDS orbits the mesh and reports frames per second ----
  const bench = Number(params.get('bench') || 0);
  let benchStart = 0, benchFrames = 0, loadMs = 0, fpsFrames = 0, fpsStart = performance.now();
  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(h, 1);
      camera.updateProjectionMatrix();
    }
  }
  function frame(now) {
    resize();
    upload();
    if (bench > 0 && loadMs > 0) {
      controls.autoRotate = true;
      controls.autoRotateSpeed = 6;   // a full turn in 10 s at 60 fps
      controls.update();
    }
    renderer.render(scene, camera);
    if (firstMeshAt === -1) {
      firstMeshAt = now;
      gl.finish();   // the load time includes the upload and first draw
      loadMs = performance.now();
      el('vkmesh-load-ms').textContent = loadMs.toFixed(0);
      benchStart = performance.now();
    }
    ++fpsFrames;
    if (now - fpsStart > 1000) {
      el('vkmesh-fps').textContent = (fpsFrames * 1000 / (now - fpsStart)).toFixed(1);
      fpsFrames = 0; fpsStart = now;
    }
    if (bench > 0 && benchStart > 0) {
      ++benchFrames;
      const elapsed = performance.now() - benchStart;
      if (elapsed > bench * 1000) {
        const fps = benchFrames * 1000 / elapsed;
        send('report fps=' + fps.toFixed(2) + ' load_ms=' + loadMs.toFixed(1) + ' triangles=' + tCount + ' frames=' + benchFrames);
        el('vkmesh-status').textContent = 'bench done: ' + fps.toFixed(2) + ' fps';
        window.vkmeshBench = { fps: fps, loadMs: loadMs, triangles: tCount, frames: benchFrames, seconds: elapsed / 1000,
                               antialias: antialias, software: software };
        benchStart = -1;
        controls.autoRotate = false;
      }
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
  window.vkmesh = { triangles: () => tCount, vertices: () => vCount, frame: () => lastFrame };
})();
