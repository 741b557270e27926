// The flexmbs viewer: draws the bodies of each analysis from their undeformed surface, the
// shapes of its vertices and, per frame, each body's floating frame and elastic coordinates
// (crate docs). three.js is inlined in the page as text and imported from a Blob URL, so the
// page needs no server and no network.
const THREE = await import(URL.createObjectURL(new Blob(
  [document.getElementById('three-src').textContent], { type: 'text/javascript' })));

const data = JSON.parse(document.getElementById('flexmbs-data').textContent);

// ---- data -------------------------------------------------------------------------------

function bytes(b64) {
  const s = atob(b64);
  const out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
  return out.buffer;
}
const f32 = (b64) => new Float32Array(b64 ? bytes(b64) : new ArrayBuffer(0));
const u32 = (b64) => new Uint32Array(b64 ? bytes(b64) : new ArrayBuffer(0));

for (const a of data.analyses) {
  for (const b of a.bodies) {
    b.vertices = f32(b.vertices);
    b.triangles = u32(b.triangles);
    b.lines = u32(b.lines);
    b.vertex_node = u32(b.vertex_node);
    b.shapes = f32(b.shapes);
    b.stress = f32(b.stress);
    b.stressed = u32(b.stressed);
    b.nv = b.vertices.length / 3;
  }
  for (const s of a.sensors) {
    s.x = f32(s.x);
    s.values = f32(s.values);
  }
}

// ---- kinematics -------------------------------------------------------------------------

// The rotation matrix (row-major) of the unit quaternion [x, y, z, w].
function rotation(q) {
  const [x, y, z, w] = q;
  return [
    1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
    2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
    2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
  ];
}
function qmul(a, b) {
  const [ax, ay, az, aw] = a, [bx, by, bz, bw] = b;
  return [
    aw * bx + ax * bw + ay * bz - az * by,
    aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw,
    aw * bw - ax * bx - ay * by - az * bz,
  ];
}
const qconj = (q) => [-q[0], -q[1], -q[2], q[3]];
// q^s for a unit quaternion (the rotation of q with its angle times s).
function qpow(q, s) {
  let [x, y, z, w] = q;
  if (w < 0) { x = -x; y = -y; z = -z; w = -w; }
  const sn = Math.hypot(x, y, z);
  if (sn < 1e-300) return [0, 0, 0, 1];
  const half = Math.atan2(sn, w) * s;
  const k = Math.sin(half) / sn;
  return [x * k, y * k, z * k, Math.cos(half)];
}

// The elastic displacement (body axes) of every vertex for coordinates eta, into out (3 nv).
function elastic(b, eta, out) {
  out.fill(0);
  const n3 = 3 * b.nv;
  for (let k = 0; k < b.n_shapes; k++) {
    const e = eta[k];
    if (!e) continue;
    const base = n3 * k;
    for (let j = 0; j < n3; j++) out[j] += b.shapes[base + j] * e;
  }
  return out;
}

// World positions of the vertices of b at pose p, the elastic part times scale.
function positions(b, p, scale, out) {
  const u = elastic(b, p.eta, new Float64Array(3 * b.nv));
  const R = rotation(p.q);
  const v = b.vertices;
  for (let i = 0; i < b.nv; i++) {
    const x = v[3 * i] + scale * u[3 * i], y = v[3 * i + 1] + scale * u[3 * i + 1], z = v[3 * i + 2] + scale * u[3 * i + 2];
    out[3 * i] = p.r[0] + R[0] * x + R[1] * y + R[2] * z;
    out[3 * i + 1] = p.r[1] + R[3] * x + R[4] * y + R[5] * z;
    out[3 * i + 2] = p.r[2] + R[6] * x + R[7] * y + R[8] * z;
  }
  return out;
}

const hasStress = (b) => b.stress.length > 0;
// The von Mises stress (Pa) of vertex i of b at coordinates eta; NaN without a stress there.
function vonMises(b, eta, i) {
  if (!hasStress(b) || (b.stressed.length && !b.stressed[i])) return NaN;
  const s = [0, 0, 0, 0, 0, 0];
  const n6 = 6 * b.nv;
  for (let k = 0; k < b.n_shapes; k++) {
    const e = eta[k];
    if (!e) continue;
    for (let c = 0; c < 6; c++) s[c] += b.stress[n6 * k + 6 * i + c] * e;
  }
  const [xx, yy, zz, xy, yz, zx] = s;
  return Math.sqrt(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3 * (xy * xy + yz * yz + zx * zx));
}
function displacementOf(b, eta, i) {
  let ux = 0, uy = 0, uz = 0;
  const n3 = 3 * b.nv;
  for (let k = 0; k < b.n_shapes; k++) {
    const e = eta[k];
    if (!e) continue;
    ux += b.shapes[n3 * k + 3 * i] * e; uy += b.shapes[n3 * k + 3 * i + 1] * e; uz += b.shapes[n3 * k + 3 * i + 2] * e;
  }
  return Math.hypot(ux, uy, uz);
}

// ---- state ------------------------------------------------------------------------------

const state = {
  analysis: null,
  frame: 0,
  mode: 0,
  phase: Math.PI / 2,
  playing: false,
  speed: 1,
  scale: 1,
  color: 'body',
  time: 0,
  frameCount: 0,
};

// The pose of body j now: a frame's, or between the base and the mode's shape.
function poseOf(a, j, amplitude) {
  if (a.modes.length) {
    const base = a.base ? a.base.poses[j] : null;
    const mode = a.modes[state.mode].pose.poses[j];
    const b0 = base || { r: mode.r, q: [0, 0, 0, 1], eta: mode.eta.map(() => 0) };
    const s = amplitude;
    return {
      r: b0.r.map((x, c) => x + s * (mode.r[c] - x)),
      q: qmul(qpow(qmul(mode.q, qconj(b0.q)), s), b0.q),
      eta: b0.eta.map((x, k) => x + s * (mode.eta[k] - x)),
    };
  }
  return a.frames[state.frame].poses[j];
}
// The position of marker k now: the frame's, between the base and the mode's, or its own.
function markerAt(a, k, amplitude) {
  const own = a.markers[k].position;
  if (a.modes.length) {
    const m = a.modes[state.mode].pose.markers[k];
    const b = a.base && a.base.markers.length ? a.base.markers[k] : own;
    return m ? b.map((x, c) => x + amplitude * (m[c] - x)) : own;
  }
  const f = a.frames[state.frame];
  return f && f.markers.length ? f.markers[k] : own;
}
// The point at body coordinates x of a body at pose p (world axes).
function bodyPoint(p, x) {
  const R = rotation(p.q);
  return [0, 1, 2].map((c) => p.r[c] + R[3 * c] * x[0] + R[3 * c + 1] * x[1] + R[3 * c + 2] * x[2]);
}
// A mode is drawn as a linear displacement field, as it is one: each vertex at x0 + s (x1 - x0),
// with x0 its position at the base (s = 0) and x1 at the mode's pose (s = 1). Scaling the
// frame's rotation as an angle instead would move points the mode keeps still, such as a
// clamped end, at the second order in s: centimetres on a 2 m column at a scale factor of 10.
// Both ends are kept for the mode shown.
function modeEnds(a, j) {
  const d = drawn[j], b = a.bodies[j];
  if (d.mode !== state.mode) {
    d.x0 = positions(b, poseOf(a, j, 0), 1, d.x0 || new Float64Array(3 * b.nv));
    d.x1 = positions(b, poseOf(a, j, 1), 1, d.x1 || new Float64Array(3 * b.nv));
    d.mode = state.mode;
  }
  return d;
}
// The amplitude of the mode now (a mode's pose has amplitude 1): the values shown are at it.
function amplitudeNow(a) {
  return a.modes.length ? Math.sin(state.phase) : 1;
}
// The amplitude drawn: the mode's normalisation and the deformation scale factor applied.
function drawnAmplitude(a) {
  return amplitudeNow(a) * (a.modeNorm[state.mode] || 1) * state.scale;
}

// ---- three.js scene ----------------------------------------------------------------------

const canvas = document.getElementById('view');
// The WebGL implementation's name, from a throwaway context: the page's own context fixes its
// multisampling when it is created.
function webglRendererName() {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return '';
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  const lose = gl.getExtension('WEBGL_lose_context');
  if (lose) lose.loseContext();
  return name;
}
// Multisampled edges cost a GPU almost nothing, but a software rasteriser (SwiftShader,
// llvmpipe: a browser without a GPU or in a virtual machine) draws every sample on the CPU, and
// a 30k-node body plays at half the frame rate. There the page draws without multisampling.
const glName = webglRendererName();
const softwareGl = /swiftshader|llvmpipe|softpipe|software/i.test(glName);
const renderer = new THREE.WebGLRenderer({ canvas, antialias: !softwareGl, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0xf4f5f7);
const camera = new THREE.PerspectiveCamera(35, 1, 1e-4, 1e4);
scene3.add(new THREE.AmbientLight(0xffffff, 0.55));
const light = new THREE.DirectionalLight(0xffffff, 1.7);
camera.add(light);
light.position.set(1, 1, 2);
scene3.add(camera);
let group = new THREE.Group();
scene3.add(group);

const palette = [0x4e79a7, 0xf28e2b, 0x59a14f, 0xe15759, 0x76b7b2, 0xedc948, 0xb07aa1, 0xff9da7, 0x9c755f, 0xbab0ac];
// A perceptual blue-to-red ramp (turbo-like) for values in [0, 1].
function ramp(t) {
  t = Math.min(1, Math.max(0, t));
  const stops = [[0.19, 0.07, 0.23], [0.16, 0.47, 0.93], [0.1, 0.84, 0.65], [0.64, 0.99, 0.24], [0.98, 0.73, 0.22], [0.85, 0.23, 0.05], [0.48, 0.02, 0.01]];
  const x = t * (stops.length - 1), k = Math.min(stops.length - 2, Math.floor(x)), f = x - k;
  return stops[k].map((c, i) => c + f * (stops[k + 1][i] - c));
}

// The ramp in three.js's working colour space (linear RGB) at 256 levels: vertex colours are
// linear and the screen shows their sRGB encoding, so the model's colours are the legend bar's,
// which a 2D canvas draws in sRGB.
const rampLinear = Array.from({ length: 256 }, (_, k) => {
  const c = new THREE.Color().setRGB(...ramp(k / 255), THREE.SRGBColorSpace);
  return [c.r, c.g, c.b];
});
const noValue = (() => { const c = new THREE.Color().setRGB(0.75, 0.75, 0.75, THREE.SRGBColorSpace); return [c.r, c.g, c.b]; })();

// The markers' colours by kind, shown in the legend's key.
const markerColors = { joint: 0xd62728, ground: 0x333333, mass: 0x888888, interface: 0x2ca02c, load: 0xff7f0e, moment: 0x9467bd };
const markerNames = { joint: 'joint', ground: 'ground, support', mass: 'point mass', interface: 'interface', load: 'load', moment: 'moment' };

let drawn = [];   // per body: { mesh, lines, points, pos (Float64Array), geometry }
let markers = []; // per marker: { mesh, marker }
let bounds = { center: new THREE.Vector3(), radius: 1 };

function buildAnalysis(a) {
  scene3.remove(group);
  group = new THREE.Group();
  scene3.add(group);
  drawn = [];
  markers = [];
  a.bodies.forEach((b, j) => {
    const d = { pos: new Float64Array(3 * b.nv) };
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * b.nv), 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * b.nv), 3));
    d.geometry = geometry;
    if (b.triangles.length) {
      geometry.setIndex(new THREE.BufferAttribute(b.triangles, 1));
      d.mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
      d.mesh.userData.body = j;
      group.add(d.mesh);
    }
    if (b.lines.length) {
      const lg = new THREE.BufferGeometry();
      lg.setAttribute('position', geometry.getAttribute('position'));
      lg.setAttribute('color', geometry.getAttribute('color'));
      lg.setIndex(new THREE.BufferAttribute(b.lines, 1));
      d.lines = new THREE.LineSegments(lg, new THREE.LineBasicMaterial({ vertexColors: true }));
      group.add(d.lines);
    }
    if (!b.triangles.length) {
      d.points = new THREE.Points(geometry, new THREE.PointsMaterial({ vertexColors: true, size: 9, sizeAttenuation: false }));
      d.points.userData.body = j;
      group.add(d.points);
    }
    drawn.push(d);
  });
  // The extent of the model over its frames (first, middle, last) sets the camera and the markers' size.
  const box = new THREE.Box3();
  const keys = a.frames.length ? [0, Math.floor(a.frames.length / 2), a.frames.length - 1] : [0];
  for (const k of keys) {
    a.bodies.forEach((b, j) => {
      const p = a.frames.length ? a.frames[k].poses[j] : (a.base ? a.base.poses[j] : a.modes[0].pose.poses[j]);
      const pos = positions(b, p, 0, new Float64Array(3 * b.nv));
      for (let i = 0; i < b.nv; i++) box.expandByPoint(new THREE.Vector3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]));
    });
  }
  for (const m of a.markers) if (m.body == null) box.expandByPoint(new THREE.Vector3(...m.position));
  if (box.isEmpty()) box.expandByPoint(new THREE.Vector3());
  bounds.center = box.getCenter(new THREE.Vector3());
  bounds.size = box.getSize(new THREE.Vector3());
  bounds.radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const size = bounds.radius * 0.018;
  for (const m of a.markers) {
    const color = markerColors[m.kind] ?? markerColors.mass;
    let mesh;
    if (m.direction) {
      // A force: an arrow onto its point; a moment: an arrow from its point along its axis.
      const dir = new THREE.Vector3(...m.direction).normalize();
      const len = bounds.radius * 0.15;
      const tail = m.kind === 'moment' ? new THREE.Vector3() : dir.clone().multiplyScalar(-len);
      mesh = new THREE.Group();
      mesh.add(new THREE.ArrowHelper(dir, tail, len, color, 0.3 * len, 0.15 * len));
    } else {
      const geom = m.kind === 'ground' ? new THREE.BoxGeometry(2 * size, 2 * size, 2 * size) : new THREE.SphereGeometry(m.kind === 'interface' ? 0.7 * size : size, 12, 8);
      mesh = new THREE.Mesh(geom, new THREE.MeshLambertMaterial({ color }));
    }
    // Drawn over the bodies: a joint or an interface sits inside a beam's tube.
    mesh.traverse((o) => { if (o.material) o.material.depthTest = false; o.renderOrder = 1; });
    group.add(mesh);
    markers.push({ mesh, marker: m });
  }
  // Mode normalisation: each mode's largest displacement a tenth of the model's size.
  a.modeNorm = a.modes.map((mode, k) => {
    let largest = 0;
    a.bodies.forEach((b, j) => {
      const p0 = a.base ? a.base.poses[j] : { r: mode.pose.poses[j].r, q: [0, 0, 0, 1], eta: mode.pose.poses[j].eta.map(() => 0) };
      const x0 = positions(b, p0, 1, new Float64Array(3 * b.nv));
      const x1 = positions(b, mode.pose.poses[j], 1, new Float64Array(3 * b.nv));
      for (let i = 0; i < b.nv; i++) largest = Math.max(largest, Math.hypot(x1[3 * i] - x0[3 * i], x1[3 * i + 1] - x0[3 * i + 1], x1[3 * i + 2] - x0[3 * i + 2]));
    });
    // A static displacement is drawn at its size (the scale factor enlarges it).
    if (a.kind === 'static') return 1;
    return largest > 0 ? 0.1 * bounds.radius / largest : 1;
  });
  a.ranges = {};
}

// The range of the colour field over the frames (or the mode at full amplitude), cached.
function range(a, what) {
  const key = a.modes.length ? `${what}:${state.mode}` : what;
  if (a.ranges[key]) return a.ranges[key];
  let hi = 0;
  const poses = a.modes.length ? [null] : a.frames.map((f) => f);
  for (const f of poses) {
    a.bodies.forEach((b, j) => {
      const eta = f ? f.poses[j].eta : poseOf(a, j, 1).eta;
      for (let i = 0; i < b.nv; i++) {
        const v = what === 'von-mises' ? vonMises(b, eta, i) / 1e6 : displacementOf(b, eta, i) * 1e3;
        if (v > hi) hi = v;
      }
    });
  }
  return (a.ranges[key] = [0, hi > 0 ? hi : 1]);
}

// The value shown for vertex i of body j (MPa or mm), from the coordinates at scale 1.
function valueAt(a, j, i) {
  const b = a.bodies[j];
  const eta = poseOf(a, j, amplitudeNow(a)).eta;
  if (state.color === 'von-mises') return vonMises(b, eta, i) / 1e6;
  if (state.color === 'displacement') return displacementOf(b, eta, i) * 1e3;
  return j;
}

function update() {
  const a = state.analysis;
  if (!a) return;
  const amp = amplitudeNow(a);
  const field = state.color !== 'body';
  const [lo, hi] = field ? range(a, state.color) : [0, 1];
  a.bodies.forEach((b, j) => {
    const d = drawn[j];
    const p = a.modes.length ? null : a.frames[state.frame].poses[j];
    // Frames: the elastic part scaled; modes: the whole motion of the mode scaled.
    if (p) positions(b, p, state.scale, d.pos);
    else {
      const s = drawnAmplitude(a), { x0, x1 } = modeEnds(a, j);
      for (let c = 0; c < x0.length; c++) d.pos[c] = x0[c] + s * (x1[c] - x0[c]);
    }
    const attr = d.geometry.getAttribute('position');
    attr.array.set(d.pos);
    attr.needsUpdate = true;
    const col = d.geometry.getAttribute('color');
    const base = new THREE.Color(palette[j % palette.length]);
    const eta = p ? p.eta : poseOf(a, j, amp).eta;
    for (let i = 0; i < b.nv; i++) {
      let c = [base.r, base.g, base.b];
      if (field) {
        const v = state.color === 'von-mises' ? vonMises(b, eta, i) / 1e6 : displacementOf(b, eta, i) * 1e3;
        c = Number.isNaN(v) ? noValue : rampLinear[Math.round(255 * Math.min(1, Math.max(0, (Math.abs(v) - lo) / (hi - lo))))];
      }
      col.array[3 * i] = c[0]; col.array[3 * i + 1] = c[1]; col.array[3 * i + 2] = c[2];
    }
    col.needsUpdate = true;
    if (d.mesh) d.geometry.computeVertexNormals();
    d.geometry.computeBoundingSphere();
  });
  markers.forEach(({ mesh, marker }, k) => {
    if (marker.body == null) {
      mesh.position.set(...markerAt(a, k, a.modes.length ? drawnAmplitude(a) : 1));
    } else if (!a.modes.length) {
      mesh.position.set(...bodyPoint(poseOf(a, marker.body, 1), marker.position));
    } else {
      const x0 = bodyPoint(poseOf(a, marker.body, 0), marker.position);
      const x1 = bodyPoint(poseOf(a, marker.body, 1), marker.position);
      const s = drawnAmplitude(a);
      mesh.position.set(...x0.map((x, c) => x + s * (x1[c] - x)));
    }
  });
  legend(field, lo, hi);
  keyText();
  drawPlots();
  render();
}

// ---- camera controls -----------------------------------------------------------------------

const view = { target: new THREE.Vector3(), distance: 5, azimuth: 0, elevation: 0 };
function placeCamera() {
  const ce = Math.cos(view.elevation);
  const dir = new THREE.Vector3(ce * Math.sin(view.azimuth), Math.sin(view.elevation), ce * Math.cos(view.azimuth));
  camera.position.copy(view.target).addScaledVector(dir, view.distance);
  camera.up.set(0, 1, 0);
  if (Math.abs(dir.y) > 0.999) camera.up.set(0, 0, dir.y > 0 ? -1 : 1);
  camera.lookAt(view.target);
  camera.near = view.distance / 1000;
  camera.far = view.distance * 1000;
  camera.updateProjectionMatrix();
  render();
}
function setView(name) {
  const eps = 0;
  const views = {
    x: [Math.PI / 2, eps], '-x': [-Math.PI / 2, eps], y: [0, Math.PI / 2], '-y': [0, -Math.PI / 2],
    z: [0, 0], '-z': [Math.PI, 0], iso: [Math.PI / 4, Math.atan(1 / Math.SQRT2)],
  };
  if (views[name]) [view.azimuth, view.elevation] = views[name];
  view.target.copy(bounds.center);
  view.distance = bounds.radius / Math.sin((camera.fov * Math.PI) / 360) * 1.1;
  placeCamera();
}
let drag = null;
canvas.addEventListener('pointerdown', (e) => {
  drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2 };
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('contextmenu', (e) => e.preventDefault());
canvas.addEventListener('pointermove', (e) => {
  if (!drag) { probe(e); return; }
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX; drag.y = e.clientY;
  if (drag.pan) {
    const s = (2 * view.distance * Math.tan((camera.fov * Math.PI) / 360)) / canvas.clientHeight;
    const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
    const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
    view.target.addScaledVector(right, -dx * s).addScaledVector(up, dy * s);
  } else {
    view.azimuth -= dx * 0.01;
    view.elevation = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, view.elevation + dy * 0.01));
  }
  placeCamera();
});
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  view.distance *= Math.exp(e.deltaY * 0.001);
  placeCamera();
}, { passive: false });

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (!w || !h) return;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}
window.addEventListener('resize', resize);
let frames = 0;
function render() {
  renderer.render(scene3, camera);
  frames++;
}

// ---- the value under the pointer ------------------------------------------------------------

const raycaster = new THREE.Raycaster();
const probeBox = document.getElementById('probe');
function nodeName(b, i) {
  const n = b.vertex_node[i];
  const label = b.node_labels[n];
  return label != null ? `node ${label} (index ${n})` : `node index ${n}`;
}
function fmt(x, digits = 4) {
  return Number.isFinite(x) ? x.toPrecision(digits) : '–';
}
function probe(e) {
  const a = state.analysis;
  if (!a) return;
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  raycaster.params.Points.threshold = bounds.radius * 0.02;
  const hit = raycaster.intersectObjects(group.children.filter((o) => o.userData.body != null), false)[0];
  if (!hit) { probeBox.textContent = ''; return; }
  const j = hit.object.userData.body, b = a.bodies[j], d = drawn[j];
  let i = hit.index;
  if (hit.face) {
    let best = Infinity;
    for (const k of [hit.face.a, hit.face.b, hit.face.c]) {
      const dist = hit.point.distanceToSquared(new THREE.Vector3(d.pos[3 * k], d.pos[3 * k + 1], d.pos[3 * k + 2]));
      if (dist < best) { best = dist; i = k; }
    }
  }
  const eta = poseOf(a, j, amplitudeNow(a)).eta;
  const lines = [`body ${b.name}, ${nodeName(b, i)}`,
    `position (${fmt(d.pos[3 * i])}, ${fmt(d.pos[3 * i + 1])}, ${fmt(d.pos[3 * i + 2])}) m`];
  if (hasStress(b)) lines.push(`von Mises ${fmt(vonMises(b, eta, i) / 1e6)} MPa`);
  if (b.n_shapes) lines.push(`elastic displacement ${fmt(displacementOf(b, eta, i) * 1e3)} mm`);
  probeBox.textContent = lines.join('\n');
}

// ---- legend, time, plots -------------------------------------------------------------------

function legend(field, lo, hi) {
  const box = document.getElementById('legend');
  const a = state.analysis;
  if (!field) {
    box.innerHTML = '';
    a.bodies.forEach((b, j) => {
      const row = document.createElement('div');
      const sw = `<span style="display:inline-block;width:10px;height:10px;background:#${palette[j % palette.length].toString(16).padStart(6, '0')};margin-right:5px"></span>`;
      row.innerHTML = sw;
      row.appendChild(document.createTextNode(b.name));
      box.appendChild(row);
    });
    // The kinds of marker drawn, each with its colour.
    const kinds = [...new Set(a.markers.map((m) => m.kind))].filter((k) => k in markerNames);
    if (kinds.length) {
      const key = document.createElement('div');
      key.className = 'markers';
      key.innerHTML = kinds.map((k) => `<span class="marker" data-kind="${k}"><span style="display:inline-block;width:8px;height:8px;border-radius:4px;background:#${markerColors[k].toString(16).padStart(6, '0')};margin:0 4px 0 8px"></span>${markerNames[k]}</span>`).join('');
      box.appendChild(key);
    }
    return;
  }
  box.innerHTML = '<div id="legendTitle"></div><canvas id="legendBar" width="180" height="12"></canvas><div class="ends"><span id="legendMin"></span><span id="legendMax"></span></div>';
  document.getElementById('legendTitle').textContent = state.color === 'von-mises' ? 'von Mises stress [MPa]' : 'elastic displacement [mm]';
  const ctx = document.getElementById('legendBar').getContext('2d');
  for (let x = 0; x < 180; x++) {
    const [r, g, b] = ramp(x / 179);
    ctx.fillStyle = `rgb(${255 * r},${255 * g},${255 * b})`;
    ctx.fillRect(x, 0, 1, 12);
  }
  document.getElementById('legendMin').textContent = fmt(lo, 3);
  document.getElementById('legendMax').textContent = fmt(hi, 3);
}

function keyText() {
  const a = state.analysis;
  document.getElementById('keyText').textContent = '';
  document.getElementById('modeText').textContent = '';
  if (a.modes.length) {
    const m = a.modes[state.mode];
    const phase = `amplitude ${fmt(Math.sin(state.phase), 3)}`;
    document.getElementById('modeText').textContent = m.frequency != null ? `${fmt(m.frequency, 6)} Hz, ${phase}` : phase;
  } else if (a.frames.length) {
    const label = a.key_label || 't [s]';
    const [name, unit] = label.includes(' [') ? [label.slice(0, label.lastIndexOf(' [')), label.slice(label.lastIndexOf(' [') + 2, -1)] : [label, ''];
    document.getElementById('keyText').textContent = `${name} = ${fmt(a.frames[state.frame].key, 6)} ${unit} (frame ${state.frame + 1} of ${a.frames.length})`;
  }
}

function drawPlots() {
  const a = state.analysis;
  const x = a.frames.length ? a.frames[state.frame].key : null;
  for (const s of a.sensors) {
    const c = s.canvas;
    if (!c) continue;
    const w = (c.width = c.clientWidth * (window.devicePixelRatio || 1)), h = (c.height = c.clientHeight * (window.devicePixelRatio || 1));
    const ctx = c.getContext('2d');
    ctx.clearRect(0, 0, w, h);
    const n = s.x.length, m = s.columns.length;
    if (!n) continue;
    const x0 = s.x[0], x1 = s.x[n - 1] > x0 ? s.x[n - 1] : x0 + 1;
    let lo = Infinity, hi = -Infinity;
    for (const v of s.values) { if (v < lo) lo = v; if (v > hi) hi = v; }
    if (!(hi > lo)) { lo -= 1; hi += 1; }
    const px = (t) => 4 + ((t - x0) / (x1 - x0)) * (w - 8), py = (v) => h - 4 - ((v - lo) / (hi - lo)) * (h - 8);
    for (let k = 0; k < m; k++) {
      ctx.strokeStyle = `#${palette[k % palette.length].toString(16).padStart(6, '0')}`;
      ctx.lineWidth = 1.5;
      ctx.beginPath();
      for (let r = 0; r < n; r++) ctx[r ? 'lineTo' : 'moveTo'](px(s.x[r]), py(s.values[m * r + k]));
      ctx.stroke();
    }
    if (x != null) {
      ctx.strokeStyle = '#000';
      ctx.beginPath(); ctx.moveTo(px(x), 0); ctx.lineTo(px(x), h); ctx.stroke();
      // The row at the cursor: the values shown beside the plot. The sensor's keys are float32,
      // the frame's float64: equal to float32's precision is equal.
      let r = 0;
      const tol = 1e-6 * (Math.abs(x) + (x1 - x0));
      while (r + 1 < n && s.x[r + 1] <= x + tol) r++;
      s.readout.textContent = s.columns.map((col, k) => `${col} = ${fmt(s.values[m * r + k])}`).join(', ');
    }
  }
}

function buildPlots(a) {
  const box = document.getElementById('plots');
  box.innerHTML = '';
  for (const s of a.sensors) {
    const div = document.createElement('div');
    div.className = 'plot';
    const name = document.createElement('div');
    name.className = 'name';
    name.textContent = `sensor ${s.name} (against ${s.x_label})`;
    s.canvas = document.createElement('canvas');
    s.canvas.title = s.columns.join(', ');
    s.readout = document.createElement('div');
    div.append(name, s.canvas, s.readout);
    box.appendChild(div);
  }
}

// ---- controls ------------------------------------------------------------------------------

const $ = (id) => document.getElementById(id);
$('title').textContent = data.title;
data.analyses.forEach((a, k) => {
  const o = document.createElement('option');
  o.value = k;
  o.textContent = `${a.name} (${a.kind})`;
  $('analysis').appendChild(o);
});

function selectAnalysis(k) {
  if (typeof k === 'string') k = data.analyses.findIndex((a) => a.name === k);
  const a = data.analyses[k];
  if (!a) throw new Error(`no analysis ${k}`);
  $('analysis').value = k;
  state.analysis = a;
  state.frame = 0;
  state.mode = 0;
  state.phase = Math.PI / 2;
  state.frameCount = a.frames.length;
  buildAnalysis(a);
  buildPlots(a);
  // Nothing to play in one frame (the model before it runs).
  $('timeBox').classList.toggle('hidden', a.frames.length < 2 && !a.modes.length);
  $('slider').classList.toggle('hidden', !a.frames.length);
  $('modeBox').classList.toggle('hidden', !a.modes.length);
  $('slider').max = Math.max(0, a.frames.length - 1);
  $('slider').value = 0;
  $('mode').innerHTML = '';
  a.modes.forEach((m, i) => {
    const o = document.createElement('option');
    o.value = i;
    o.textContent = m.frequency != null ? `${m.label}: ${fmt(m.frequency, 5)} Hz` : m.label;
    $('mode').appendChild(o);
  });
  const stress = a.bodies.some(hasStress);
  $('color').querySelector('[value="von-mises"]').disabled = !stress;
  if (state.color === 'von-mises' && !stress) state.color = 'body';
  if (state.color === 'body' && stress) state.color = 'von-mises';
  $('color').value = state.color;
  state.playing = a.modes.length > 0 && a.kind !== 'static';
  $('play').textContent = state.playing ? 'pause' : 'play';
  resize();
  // A planar model (thin along z) seen along z, any other from the corner.
  setView(bounds.size.z < 0.15 * Math.max(bounds.size.x, bounds.size.y) ? 'z' : 'iso');
  update();
}
function setFrame(k) {
  const a = state.analysis;
  state.frame = Math.max(0, Math.min(a.frames.length - 1, Math.round(k)));
  state.time = a.frames.length ? a.frames[state.frame].key : 0;
  $('slider').value = state.frame;
  update();
}
// The frame at time t: the last whose key is at most t (to round-off).
function setTime(t) {
  const a = state.analysis;
  let k = 0;
  const tol = 1e-9 * Math.max(1, Math.abs(t));
  while (k + 1 < a.frames.length && a.frames[k + 1].key <= t + tol) k++;
  setFrame(k);
  state.time = t;
}
$('analysis').addEventListener('change', (e) => selectAnalysis(Number(e.target.value)));
$('slider').addEventListener('input', (e) => { state.playing = false; $('play').textContent = 'play'; setFrame(Number(e.target.value)); });
$('play').addEventListener('click', () => {
  state.playing = !state.playing;
  const a = state.analysis;
  if (state.playing && a.frames.length && state.frame === a.frames.length - 1) setFrame(0);
  $('play').textContent = state.playing ? 'pause' : 'play';
});
$('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
$('mode').addEventListener('change', (e) => { state.mode = Number(e.target.value); update(); });
$('color').addEventListener('change', (e) => { state.color = e.target.value; update(); });
$('scale').addEventListener('input', (e) => { const s = Number(e.target.value); if (Number.isFinite(s)) { state.scale = s; update(); } });
for (const btn of document.querySelectorAll('#views button')) btn.addEventListener('click', () => setView(btn.dataset.view));

// Play on by dt seconds of the viewer's clock: the analysis's time moves by dt times the speed
// (a mode's phase by one period every 1.5 s at speed 1, whatever the frequency); at the last
// frame playing stops.
function advance(dt) {
  const a = state.analysis;
  if (!a) return;
  if (a.modes.length) {
    state.phase += (2 * Math.PI * dt * state.speed) / 1.5;
    update();
  } else if (a.frames.length > 1) {
    const t = state.time + dt * state.speed;
    const end = a.frames[a.frames.length - 1].key;
    if (t >= end) { setFrame(a.frames.length - 1); state.playing = false; $('play').textContent = 'play'; } else setTime(t);
  }
}
let last = performance.now();
function tick(now) {
  const dt = Math.min(0.1, (now - last) / 1000);
  last = now;
  if (state.playing) advance(dt);
  requestAnimationFrame(tick);
}

// ---- the API for tests and scripts ----------------------------------------------------------

function vertexOf(j, i) {
  const a = state.analysis, b = a.bodies[j];
  if (!b) throw new Error(`no body ${j}`);
  if (!(i >= 0 && i < b.nv)) throw new Error(`body ${b.name} has no vertex ${i}`);
  return b;
}
function bodyIndex(j) {
  return typeof j === 'string' ? state.analysis.bodies.findIndex((b) => b.name === j) : j;
}
window.flexmbsViewer = {
  analyses: () => data.analyses.map((a) => a.name),
  select: (k) => selectAnalysis(k),
  bodies: () => state.analysis.bodies.map((b) => b.name),
  frameCount: () => state.analysis.frames.length,
  frameKeys: () => state.analysis.frames.map((f) => f.key),
  setFrame: (k) => setFrame(k),
  setTime: (t) => setTime(t),
  frame: () => state.frame,
  time: () => (state.analysis.frames.length ? state.analysis.frames[state.frame].key : null),
  modeCount: () => state.analysis.modes.length,
  modes: () => state.analysis.modes.map((m) => ({ label: m.label, frequency: m.frequency })),
  setMode: (k) => { state.mode = k; $('mode').value = k; update(); },
  setPhase: (p) => { state.phase = p; update(); },
  play: () => { state.playing = true; },
  pause: () => { state.playing = false; },
  playing: () => state.playing,
  setColor: (c) => { state.color = c; $('color').value = c; update(); },
  setScale: (s) => { state.scale = s; $('scale').value = s; update(); },
  setView: (v) => setView(v),
  vertexCount: (j) => state.analysis.bodies[bodyIndex(j)].nv,
  // The vertices of body j at mesh node n.
  verticesOfNode: (j, n) => { const b = state.analysis.bodies[bodyIndex(j)]; const out = []; b.vertex_node.forEach((m, i) => { if (m === n) out.push(i); }); return out; },
  nodeOfVertex: (j, i) => vertexOf(bodyIndex(j), i).vertex_node[i],
  // The drawn position of vertex i of body j (m, world axes).
  vertexPosition: (j, i) => { j = bodyIndex(j); vertexOf(j, i); const d = drawn[j].pos; return [d[3 * i], d[3 * i + 1], d[3 * i + 2]]; },
  // The value of the colour field at vertex i of body j (MPa, mm or the body index).
  value: (j, i) => { j = bodyIndex(j); vertexOf(j, i); return valueAt(state.analysis, j, i); },
  vonMises: (j, i) => { j = bodyIndex(j); const b = vertexOf(j, i); return vonMises(b, poseOf(state.analysis, j, amplitudeNow(state.analysis)).eta, i); },
  // The analysis's time now (between frames while playing), and dt seconds of playing.
  clock: () => state.time,
  advance: (dt) => advance(dt),
  speed: () => state.speed,
  // The markers (joints, supports, point masses) as drawn now: name, kind, position (m).
  markers: () => markers.map(({ mesh, marker }) => ({ name: marker.name, kind: marker.kind, position: mesh.position.toArray(), direction: marker.direction ?? null })),
  // The colour of vertex i of body j before lighting: linear RGB in [0, 1], as three.js holds
  // it (the screen shows its sRGB encoding).
  vertexColor: (j, i) => { j = bodyIndex(j); vertexOf(j, i); return Array.from(drawn[j].geometry.getAttribute('color').array.slice(3 * i, 3 * i + 3)); },
  renders: () => frames,
  // The WebGL implementation drawing the page, and whether its edges are multisampled.
  rendering: () => ({ webgl: glName, software: softwareGl, antialias: !softwareGl }),
  ready: true,
};
if (data.analyses.length) {
  selectAnalysis(0);
} else {
  $('title').textContent = `${data.title}: no analysis of this run has bodies or sensors to show`;
  resize();
}
requestAnimationFrame(tick);
