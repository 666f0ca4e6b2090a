// The control panel: WebSocket to `quadctl serve`, the 3D view from the device's readback,
// the pose sliders previewed by kin-core in WebAssembly, the device's onboard motions and the
// walk's joystick, the inertial sensor's horizon and the leveling switch, plots, calibration.
//
// Units: SI on the wire (rad, m); degrees and millimetres only on the sliders.
// `window.panel` exposes the page's state for the browser tests and for debugging.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { loadKin } from './kin.js';

const DEG = Math.PI / 180;
const TRACE_LEN = 400;
const PLOT_S = 10;

const panel = {
  ready: false,
  pageId: null,
  controller: null,
  get controlling() { return this.pageId !== null && this.controller === this.pageId; },
  robot: null,
  order: 5,
  state: null,
  states: 0,
  preview: null,
  posesSent: 0,
  lastSent: null,
  // No pose or stance change in flight or waiting to be sent.
  get idle() { return !inFlight && pending === null; },
  notSent: 0,
  errors: [],
  done: [],
  latencies: [], // slider input -> the device's readback of that pose drawn, ms
  arrivals: [], // slider input -> the device's readback of that pose received, ms
  motionLatencies: [], // Start clicked -> the first readback of the started motion drawn, ms
  motionStatus: null, // the device's motion engine, from the last state
  walking: false,
  velocitiesSent: 0,
  renderedPoseId: 0,
  renderedAngles: null,
  velocity: { vx: 0, vy: 0, yaw: 0 },
  wasmBytes: 0,
  kin: null,
};
window.panel = panel;

const $ = (id) => document.getElementById(id);
const message = (text) => { $('message').textContent = text; };

// ---------------------------------------------------------------- sliders
const SLIDERS = [
  { key: 'roll', label: 'roll', unit: '°', min: -30, max: 30, step: 0.5, value: 0 },
  { key: 'pitch', label: 'pitch', unit: '°', min: -30, max: 30, step: 0.5, value: 0 },
  { key: 'yaw', label: 'yaw', unit: '°', min: -30, max: 30, step: 0.5, value: 0 },
  { key: 'x', label: 'x', unit: 'mm', min: -150, max: 150, step: 1, value: 0 },
  { key: 'y', label: 'y', unit: 'mm', min: -150, max: 150, step: 1, value: 0 },
  { key: 'z', label: 'z', unit: 'mm', min: -150, max: 150, step: 1, value: 0 },
  { key: 'stance', label: 'stance height', unit: 'mm', min: 100, max: 600, step: 1, value: 400 },
];
const sliders = {};

function buildSliders() {
  const box = $('sliders');
  for (const s of SLIDERS) {
    const row = document.createElement('div');
    row.className = 'slider';
    row.innerHTML = `<label for="s-${s.key}">${s.label}</label>
      <input id="s-${s.key}" type="range" min="${s.min}" max="${s.max}" step="${s.step}" value="${s.value}">
      <output id="o-${s.key}"></output>`;
    box.appendChild(row);
    const input = row.querySelector('input');
    sliders[s.key] = input;
    input.addEventListener('input', () => onSlider(s.key === 'stance'));
  }
  $('reset-pose').addEventListener('click', () => {
    for (const k of ['roll', 'pitch', 'yaw', 'x', 'y', 'z']) sliders[k].value = 0;
    onSlider(false);
  });
}

function sliderPose() {
  const v = (k) => Number(sliders[k].value);
  return {
    roll_rad: v('roll') * DEG, pitch_rad: v('pitch') * DEG, yaw_rad: v('yaw') * DEG,
    x_m: v('x') / 1000, y_m: v('y') / 1000, z_m: v('z') / 1000,
  };
}
const sliderStance = () => Number(sliders.stance.value) / 1000;

// ---------------------------------------------------------------- preview and sending
let nextPoseId = 1;
let inFlight = false;
let pending = null; // the latest reachable target not yet sent: { kind, ... }
const sentAt = new Map(); // pose id -> performance.now() of the slider input

function legColour(leg) {
  if (leg.status !== 'ok') return new THREE.Color(0xff3b30);
  // Green at >= 40 mm and >= 0.35 rad of margin, through yellow to red at 0.
  const m = Math.min(leg.workspaceMarginM / 0.04, leg.jointMarginRad / 0.35, 1);
  const t = Math.max(0, m);
  return new THREE.Color().setHSL(0.33 * t, 0.9, 0.5);
}

function showPreview(p) {
  const out = SLIDERS.map((s) => {
    const el = $(`o-${s.key}`);
    el.textContent = `${Number(sliders[s.key].value).toFixed(s.step < 1 ? 1 : 0)} ${s.unit}`;
    return el;
  });
  void out;
  const legs = p.legs.map((l) => {
    const c = legColour(l);
    const margin = l.status === 'ok'
      ? `${(l.workspaceMarginM * 1000).toFixed(0)} mm, ${(l.jointMarginRad / DEG).toFixed(1)}°`
      : l.status;
    return `<span class="leg" style="background:#${c.getHexString()}">${l.name}</span>${margin}`;
  }).join('<br>');
  $('preview-status').innerHTML = (p.reachable
    ? 'reachable (margins: workspace, joint limit)<br>'
    : `<span class="unreachable">unreachable: ${p.firstLeg} ${p.legs.find((l) => l.name === p.firstLeg).status} — shown, not sent</span><br>`) + legs;
}

function onSlider(stanceChanged) {
  if (!panel.kin) return;
  const t0 = performance.now();
  const pose = sliderPose();
  const h = sliderStance();
  const p = panel.kin.preview(pose, h, panel.order);
  panel.preview = { pose, stanceHeightM: h, ...p };
  showPreview(p);
  setGhost(pose, p);
  if (!p.reachable) {
    panel.notSent += 1;
    pending = null;
    return;
  }
  if (!panel.controlling) return;
  if (stanceChanged) {
    pending = { kind: 'stance', stanceHeightM: h, pose, t0 };
  } else {
    pending = { kind: 'pose', pose, t0 };
  }
  pump();
}

function pump() {
  if (inFlight || !pending || !socket || socket.readyState !== WebSocket.OPEN) return;
  const job = pending;
  pending = null;
  if (job.kind === 'stance') {
    // The server solves the held pose again at the new stance; send the pose after it.
    send({ type: 'set_stance_height', stance_height_m: job.stanceHeightM });
    pending = pending ?? { kind: 'pose', pose: job.pose, t0: job.t0 };
  } else {
    const id = nextPoseId++;
    sentAt.set(id, job.t0);
    panel.posesSent += 1;
    panel.lastSent = { id, pose: job.pose };
    send({ type: 'set_pose', id, pose: job.pose });
  }
  inFlight = true;
}

// ---------------------------------------------------------------- WebSocket
let socket = null;

// The server answers every message with one `done` or `error`, in order: the commands awaiting
// their answer, oldest first.
let awaiting = [];

function send(msg) {
  if (socket && socket.readyState === WebSocket.OPEN) {
    socket.send(JSON.stringify(msg));
    awaiting.push(msg.type);
  }
}
panel.send = send;
// A raw text message, for the tests of the server's validation.
panel.sendRaw = (text) => { socket.send(text); awaiting.push('raw'); };

// An answer came: the command it answers.
function answered() {
  const cmd = awaiting.shift();
  if (cmd === 'set_velocity') velocitiesInFlight = Math.max(0, velocitiesInFlight - 1);
  return cmd;
}

// Leaving the page closes its socket at once (the server also drops a silent page).
window.addEventListener('pagehide', () => { if (socket) socket.close(); });

function connect() {
  socket = new WebSocket(`ws://${location.host}/ws`);
  socket.onopen = () => { $('conn').textContent = 'connected'; $('conn').className = 'badge ok'; };
  socket.onclose = () => {
    $('conn').textContent = 'disconnected';
    $('conn').className = 'badge bad';
    panel.controller = null;
    awaiting = [];
    velocitiesInFlight = 0;
    balancePending = false;
    updateControl();
    setTimeout(connect, 1000);
  };
  socket.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    switch (msg.type) {
      case 'welcome': onWelcome(msg); break;
      case 'state': onState(msg); break;
      case 'done':
        answered();
        panel.done.push(msg.command);
        if (msg.command === 'start_motion' && motionClick !== null) {
          // The next state carries the started motion's first readback (the server sends a
          // command's state after its answer).
          motionStarted = motionClick;
          motionClick = null;
        }
        if (['set_pose', 'set_stance_height'].includes(msg.command)) { inFlight = false; pump(); }
        if (msg.command === 'set_balance') balanceAnswered(null);
        break;
      case 'error': {
        const cmd = answered();
        panel.errors.push(msg.message);
        message(msg.message);
        if (msg.field) showRefusal(msg.message, msg.field);
        if (cmd === 'start_motion') motionClick = null;
        if (cmd === 'set_balance') balanceAnswered(msg.message);
        inFlight = false;
        pump();
        break;
      }
      default: break;
    }
  };
}

function onWelcome(msg) {
  panel.pageId = msg.page_id;
  panel.robot = msg.robot;
  panel.order = msg.rotation_order;
  panel.servos = msg.servos;
  panel.linkLossAction = msg.link_loss_action;
  $('robot-name').textContent = `${msg.robot_name} · ${msg.target} · link loss: ${msg.link_loss_action}`;
  panel.kin.setRobot(msg.robot);
  const reach = msg.robot.leg.femur_m + msg.robot.leg.tibia_m + msg.robot.leg.d_ax_m;
  sliders.stance.min = Math.round(reach * 200);
  sliders.stance.max = Math.round(reach * 1050);
  buildRobotMeshes(msg.robot);
  buildCalibration(msg.servos);
  panel.ready = true;
}

function onState(msg) {
  const first = panel.state === null;
  panel.state = msg;
  panel.states += 1;
  panel.controller = msg.controller;
  if (first) {
    sliders.stance.value = Math.round(msg.stance_height_m * 1000);
    onSlider(false);
  }
  if (motionStarted !== null && msg.motion.kind !== null) {
    motionSeen = motionStarted;
    motionStarted = null;
  }
  showMotion(msg.motion);
  if (msg.pose_id && sentAt.has(msg.pose_id)) {
    readbackSeen = { id: msg.pose_id, t0: sentAt.get(msg.pose_id) };
    panel.arrivals.push(performance.now() - readbackSeen.t0);
    for (const id of sentAt.keys()) if (id <= msg.pose_id) sentAt.delete(id);
  }
  updateControl();
  updateReadback(msg);
  pushPlots(msg);
  showHealth(msg);
  showImu(msg.imu, msg.flags);
  showCalibration(msg);
  showGuide(msg.guide);
}

function updateControl() {
  const mine = panel.controlling;
  const other = panel.controller !== null && !mine;
  $('control-badge').textContent = mine ? 'in control' : other ? `page ${panel.controller} controls` : 'watching';
  $('control-badge').className = `badge ${mine ? 'mine' : ''}`;
  $('take-control').disabled = mine;
  $('release-control').disabled = !mine;
  for (const id of ['outputs-on', 'outputs-off', 'cal-save', 'cal-read', 'cal-set-center', 'cal-set-direction', 'motion-start', 'motion-stop', 'guide-start']) {
    $(id).disabled = !mine;
  }
  for (const b of document.querySelectorAll('[data-jog]')) b.disabled = !mine;
  $('balance-switch').disabled = !mine || balancePending || !panel.state || panel.state.imu === null;
}

// ---------------------------------------------------------------- 3D view
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.prepend(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x14171c);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 50);
camera.up.set(0, 0, 1);
camera.position.set(1.1, -1.3, 0.6);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, -0.2);
controls.update();
controls.addEventListener('change', () => { viewDirty = true; });
scene.add(new THREE.HemisphereLight(0xffffff, 0x334455, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(1, -1, 2);
scene.add(sun);
const grid = new THREE.GridHelper(3, 30, 0x556070, 0x2c3440);
grid.rotation.x = Math.PI / 2;
scene.add(grid);

function resize() {
  const w = view.clientWidth;
  const h = view.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  viewDirty = true;
}
window.addEventListener('resize', resize);

// A robot drawn from joint points: a body plate through the four hip mounts, a cylinder per
// link, a sphere per joint.
function makeRobot(radius, opacity) {
  const group = new THREE.Group();
  const transparent = opacity < 1;
  const bodyMat = new THREE.MeshStandardMaterial({ color: 0x7088a8, transparent, opacity, side: THREE.DoubleSide });
  const bodyGeo = new THREE.BufferGeometry();
  bodyGeo.setAttribute('position', new THREE.Float32BufferAttribute(new Array(18).fill(0), 3));
  const body = new THREE.Mesh(bodyGeo, bodyMat);
  group.add(body);
  const legs = [];
  const cyl = new THREE.CylinderGeometry(radius, radius, 1, 12);
  const ball = new THREE.SphereGeometry(radius * 1.5, 12, 8);
  for (let i = 0; i < 4; i++) {
    const mat = new THREE.MeshStandardMaterial({ color: 0xc8ccd4, transparent, opacity });
    const links = [0, 1, 2].map(() => { const m = new THREE.Mesh(cyl, mat); group.add(m); return m; });
    const joints = [0, 1, 2, 3].map(() => { const m = new THREE.Mesh(ball, mat); group.add(m); return m; });
    legs.push({ mat, links, joints });
  }
  scene.add(group);
  return { group, body, legs };
}

const Y = new THREE.Vector3(0, 1, 0);
function placeLink(mesh, a, b) {
  const d = new THREE.Vector3().subVectors(b, a);
  const len = d.length();
  mesh.visible = len > 1e-6;
  mesh.position.copy(a).addScaledVector(d, 0.5);
  mesh.scale.set(1, Math.max(len, 1e-6), 1);
  if (len > 1e-6) mesh.quaternion.setFromUnitVectors(Y, d.normalize());
}

function drawRobot(robot, pts) {
  const p = (leg, k) => new THREE.Vector3(pts[12 * leg + 3 * k], pts[12 * leg + 3 * k + 1], pts[12 * leg + 3 * k + 2]);
  // Body: two triangles FL, FR, RR and FL, RR, RL.
  const [fl, fr, rl, rr] = [0, 1, 2, 3].map((i) => p(i, 0));
  const pos = robot.body.geometry.attributes.position;
  [fl, fr, rr, fl, rr, rl].forEach((v, i) => pos.setXYZ(i, v.x, v.y, v.z));
  pos.needsUpdate = true;
  robot.body.geometry.computeVertexNormals();
  robot.body.geometry.computeBoundingSphere();
  for (let i = 0; i < 4; i++) {
    const j = [0, 1, 2, 3].map((k) => p(i, k));
    robot.legs[i].links.forEach((m, k) => placeLink(m, j[k], j[k + 1]));
    robot.legs[i].joints.forEach((m, k) => m.position.copy(j[k]));
  }
}

let actual = null;
let ghost = null;
const traces = [];

function buildRobotMeshes(robot) {
  if (actual) return;
  const scale = robot.leg.femur_m + robot.leg.tibia_m;
  actual = makeRobot(scale * 0.018, 1);
  ghost = makeRobot(scale * 0.012, 0.35);
  for (let i = 0; i < 4; i++) {
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.Float32BufferAttribute(new Float32Array(TRACE_LEN * 3), 3));
    geo.setDrawRange(0, 0);
    const line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: [0xff9f43, 0x54a0ff, 0x1dd1a1, 0xf368e0][i] }));
    scene.add(line);
    traces.push({ line, n: 0 });
  }
  const d = scale * 2.2;
  camera.position.set(d * 0.9, -d * 1.1, d * 0.5);
  controls.target.set(0, 0, -scale * 0.4);
  controls.update();
}

function setGhost(pose, p) {
  if (!ghost) return;
  panel.ghostPoints = panel.kin.points(pose, p.angles, panel.order);
  drawRobot(ghost, panel.ghostPoints);
  p.legs.forEach((l, i) => ghost.legs[i].mat.color.copy(legColour(l)));
  viewDirty = true;
}

const NEUTRAL = { roll_rad: 0, pitch_rad: 0, yaw_rad: 0, x_m: 0, y_m: 0, z_m: 0 };
let readbackSeen = null;
let dirty = false; // a new readback to draw
let viewDirty = true; // the camera, the preview or the size changed

// The rigid motion that best puts the points `from` onto `to` (least squares; Horn's unit
// quaternion method): the quaternion is the dominant eigenvector of a symmetric 4x4 matrix of
// the cross-covariance, found by power iteration (three.js has no eigen-solver; four points
// need nothing larger). Returns p -> R (p - cFrom) + cTo.
function rigidFit(from, to) {
  const n = from.length;
  const cf = new THREE.Vector3(); const ct = new THREE.Vector3();
  from.forEach((p) => cf.addScaledVector(p, 1 / n));
  to.forEach((p) => ct.addScaledVector(p, 1 / n));
  const S = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  for (let i = 0; i < n; i++) {
    const a = from[i].clone().sub(cf).toArray();
    const b = to[i].clone().sub(ct).toArray();
    for (let r = 0; r < 3; r++) for (let c = 0; c < 3; c++) S[r][c] += a[r] * b[c];
  }
  const [[xx, xy, xz], [yx, yy, yz], [zx, zy, zz]] = S;
  const N = [
    [xx + yy + zz, yz - zy, zx - xz, xy - yx],
    [yz - zy, xx - yy - zz, xy + yx, zx + xz],
    [zx - xz, xy + yx, -xx + yy - zz, yz + zy],
    [xy - yx, zx + xz, yz + zy, -xx - yy + zz],
  ];
  // Shifted by Gershgorin's bound so that every eigenvalue is >= 0: the largest then dominates.
  const shift = Math.max(0, ...N.map((row, r) => row.reduce((m, v, c) => m + (c === r ? -v : Math.abs(v)), 0)));
  let q = [1, 0, 0, 0];
  for (let k = 0; k < 100; k++) {
    const next = N.map((row, r) => row.reduce((acc, v, c) => acc + v * q[c], 0) + shift * q[r]);
    const len = Math.hypot(...next);
    q = next.map((v) => v / len);
  }
  const rot = new THREE.Quaternion(q[1], q[2], q[3], q[0]);
  return (p) => p.clone().sub(cf).applyQuaternion(rot).add(ct);
}

// During a sway the device holds the feet on their stance points and rotates the body over
// them; the readback has the joints but not the body's pose. The body is placed where the
// readback's feet land on the stance points: the view shows the body swaying over still feet.
function placeOnHeldFeet(pts, stanceHeightM) {
  const stance = panel.kin.preview(NEUTRAL, stanceHeightM, panel.order);
  if (!stance.reachable) return pts;
  const held = panel.kin.points(NEUTRAL, stance.angles, panel.order);
  const foot = (a, leg) => new THREE.Vector3(a[12 * leg + 9], a[12 * leg + 10], a[12 * leg + 11]);
  const place = rigidFit([0, 1, 2, 3].map((i) => foot(pts, i)), [0, 1, 2, 3].map((i) => foot(held, i)));
  const out = [];
  for (let k = 0; k < pts.length; k += 3) out.push(...place(new THREE.Vector3(pts[k], pts[k + 1], pts[k + 2])).toArray());
  return out;
}

function updateReadback(s) {
  if (!actual) return;
  // The body is placed by the pose the device acked (none while a motion runs: level at the
  // origin, or on the held feet during a sway); every joint comes from its readback.
  let pts = panel.kin.points(s.pose ?? NEUTRAL, s.angles_rad, panel.order);
  if (s.motion.kind === 'sway') pts = placeOnHeldFeet(pts, s.stance_height_m);
  drawRobot(actual, pts);
  panel.renderedAngles = s.angles_rad;
  panel.renderedPoints = pts;
  const on = s.flags.outputs_enabled;
  actual.legs.forEach((l) => l.mat.color.set(on ? 0xe8ecf4 : 0x8a8f99));
  grid.position.z = -s.stance_height_m;
  for (let i = 0; i < 4; i++) {
    const t = traces[i];
    const pos = t.line.geometry.attributes.position;
    const x = pts[12 * i + 9]; const y = pts[12 * i + 10]; const z = pts[12 * i + 11];
    if (t.n === TRACE_LEN) {
      pos.array.copyWithin(0, 3);
      t.n -= 1;
    }
    pos.setXYZ(t.n, x, y, z);
    t.n += 1;
    t.line.geometry.setDrawRange(0, t.n);
    pos.needsUpdate = true;
  }
  dirty = true;
}

// Draws only when something changed (a state, the preview, the camera): software WebGL on a
// busy machine would otherwise keep the page's thread from reading its socket.
function frame() {
  controls.update();
  if (dirty || viewDirty) {
    viewDirty = false;
    renderer.render(scene, camera);
  }
  if (dirty && panel.state) {
    dirty = false;
    panel.renderedPoseId = panel.state.pose_id;
    if (readbackSeen) {
      panel.latencies.push(performance.now() - readbackSeen.t0);
      readbackSeen = null;
    }
    if (motionSeen !== null) {
      panel.motionLatencies.push(performance.now() - motionSeen);
      motionSeen = null;
    }
  }
  pollInputs();
  requestAnimationFrame(frame);
}

// ---------------------------------------------------------------- plots
// Twelve traces on a 2D canvas: a few lines of drawing code instead of a chart library for two
// fixed plots.
const history = [];
const COLOURS = ['#ff9f43', '#ffc880', '#ffe0b0', '#54a0ff', '#8cc0ff', '#c0dcff', '#1dd1a1', '#70e6c4', '#b0f2dc', '#f368e0', '#f79ae9', '#fbc8f3'];

function pushPlots(s) {
  history.push({ t: s.t_ms / 1000, a: s.angles_rad, p: s.pulses_us });
  while (history.length && history[0].t < s.t_ms / 1000 - PLOT_S) history.shift();
  plot($('plot-angles'), (h) => h.a.map((v) => v / DEG), 'joint angle, °');
  plot($('plot-pulses'), (h) => h.p, 'pulse, µs (0: off)');
}

function plot(canvas, values, title) {
  const g = canvas.getContext('2d');
  const { width: w, height: h } = canvas;
  g.clearRect(0, 0, w, h);
  if (history.length < 2) return;
  const rows = history.map(values);
  let lo = Infinity; let hi = -Infinity;
  for (const r of rows) for (const v of r) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (hi - lo < 1e-3) { hi += 1; lo -= 1; }
  const t1 = history[history.length - 1].t;
  const x = (t) => w - ((t1 - t) / PLOT_S) * w;
  const y = (v) => h - 14 - ((v - lo) / (hi - lo)) * (h - 24);
  for (let j = 0; j < 12; j++) {
    g.strokeStyle = COLOURS[j];
    g.beginPath();
    history.forEach((s, k) => { const py = y(rows[k][j]); if (k) g.lineTo(x(s.t), py); else g.moveTo(x(s.t), py); });
    g.stroke();
  }
  g.fillStyle = '#99a';
  g.fillText(`${title}   [${lo.toFixed(1)}, ${hi.toFixed(1)}]   last ${PLOT_S} s`, 4, h - 3);
}

function showHealth(s) {
  const l = s.link;
  $('health').innerHTML = `link ${s.link_up ? 'up' : '<span class="unreachable">down</span>'} · acked ${l.acked} · nacked ${l.nacked} · lost ${l.lost} · retries ${l.retries} · timeouts ${l.timeouts} · bad frames ${l.bad_frames}<br>
    round trip ${l.rtt_ms.toFixed(2)} ms (max ${l.rtt_max_ms.toFixed(2)}) · device frames ok ${l.device_frames_ok}, bad ${l.device_frames_bad}`;
  const f = s.flags;
  $('device').innerHTML = `outputs <b>${f.outputs_enabled ? 'ON' : 'off'}</b> · failsafe ${f.failsafe_active ? 'ACTIVE' : 'idle'}${f.watchdog_reset ? ' · <span class="unreachable">WATCHDOG RESET</span>' : ''} · calibration ${f.calibration_unsaved ? 'unsaved' : f.calibration_default ? 'defaults' : 'saved'} · motion: ${s.motion.kind ?? 'none'}<br>
    stance ${(s.stance_height_m * 1000).toFixed(0)} mm · poses sent ${s.poses_sent} · pages ${s.pages}`;
}

// ---------------------------------------------------------------- inertial sensor and balance
// The device's `Imu` report (protocol 2.3; the server reads it 10 times a second): an
// artificial horizon from its roll and pitch, the sensor's health, the leveling and a latched
// fall, and the leveling switch (`set_balance`).

const HORIZON_PX_PER_DEG = 2.5; // pitch: the horizon moves this far per degree
const ROLL_TICKS_DEG = [-60, -45, -30, -20, -10, 0, 10, 20, 30, 45, 60];

// The attitude indicator: sky and ground split by the horizon, turned by the roll (positive:
// right side down) and moved by the pitch (positive: nose down, the horizon goes up), a pitch ladder every 10° (unlabelled), the roll
// scale on the rim with its pointer and the fall angle in red, the body's symbol fixed in the
// middle; the numbers, in degrees, only at the edge.
function drawHorizon(imu, fallLatched) {
  const c = $('horizon');
  const g = c.getContext('2d');
  const { width: w, height: h } = c;
  const r = Math.min(w, h) / 2 - 2;
  const cx = w / 2; const cy = h / 2;
  const ok = imu !== null && imu.health === 'ok';
  const roll = ok ? imu.roll_rad / DEG : 0;
  const pitch = ok ? imu.pitch_rad / DEG : 0;
  g.clearRect(0, 0, w, h);
  g.save();
  g.beginPath();
  g.arc(cx, cy, r, 0, 2 * Math.PI);
  g.clip();
  g.translate(cx, cy);
  // A body rolled right (positive roll) sees the horizon turn left.
  g.rotate(-roll * DEG);
  // Positive pitch (zyx, about y to the left) is nose down: the horizon goes up.
  const dy = -pitch * HORIZON_PX_PER_DEG;
  g.globalAlpha = ok ? 1 : 0.35;
  g.fillStyle = '#3b79b8';
  g.fillRect(-2 * r, -2 * r + dy, 4 * r, 2 * r);
  g.fillStyle = '#7a5530';
  g.fillRect(-2 * r, dy, 4 * r, 2 * r);
  g.strokeStyle = '#fff';
  g.lineWidth = 2;
  g.beginPath(); g.moveTo(-2 * r, dy); g.lineTo(2 * r, dy); g.stroke();
  g.lineWidth = 1;
  for (let p = -30; p <= 30; p += 10) {
    if (p === 0) continue;
    const y = dy - p * HORIZON_PX_PER_DEG;
    const half = Math.abs(p) % 20 === 0 ? r * 0.3 : r * 0.18;
    g.beginPath(); g.moveTo(-half, y); g.lineTo(half, y); g.stroke();
  }
  g.restore();
  // The roll scale, fixed on the rim, and the pointer that turns with the horizon.
  g.save();
  g.translate(cx, cy);
  g.strokeStyle = '#dde';
  for (const t of ROLL_TICKS_DEG) {
    g.save();
    g.rotate(t * DEG);
    g.beginPath(); g.moveTo(0, -r); g.lineTo(0, -r + (t % 30 === 0 ? 12 : 7)); g.stroke();
    g.restore();
  }
  if (imu !== null && imu.fall_detection) {
    for (const s of [-1, 1]) {
      g.save();
      g.rotate(s * imu.fall_angle_rad);
      g.strokeStyle = '#ff5c5c';
      g.lineWidth = 3;
      g.beginPath(); g.moveTo(0, -r); g.lineTo(0, -r + 12); g.stroke();
      g.restore();
    }
  }
  g.save();
  g.rotate(-roll * DEG);
  g.fillStyle = '#ffd34d';
  g.beginPath(); g.moveTo(0, -r + 13); g.lineTo(-6, -r + 23); g.lineTo(6, -r + 23); g.closePath(); g.fill();
  g.restore();
  // The body, fixed.
  g.strokeStyle = '#ffd34d';
  g.lineWidth = 3;
  g.beginPath(); g.moveTo(-r * 0.45, 0); g.lineTo(-r * 0.15, 0); g.lineTo(0, r * 0.1); g.lineTo(r * 0.15, 0); g.lineTo(r * 0.45, 0); g.stroke();
  g.fillStyle = '#ffd34d';
  g.beginPath(); g.arc(0, 0, 2.5, 0, 2 * Math.PI); g.fill();
  g.restore();
  // The rim: red while a fall is latched.
  g.strokeStyle = fallLatched ? '#ff3b30' : '#556070';
  g.lineWidth = fallLatched ? 4 : 2;
  g.beginPath(); g.arc(cx, cy, r, 0, 2 * Math.PI); g.stroke();
  // The numbers at the edge only.
  g.font = '11px system-ui, sans-serif';
  g.fillStyle = '#eef';
  g.textBaseline = 'bottom';
  g.textAlign = 'left';
  g.fillText(ok ? `R ${roll >= 0 ? '+' : '−'}${Math.abs(roll).toFixed(1)}°` : '', 2, h - 1);
  g.textAlign = 'right';
  g.fillText(ok ? `P ${pitch >= 0 ? '+' : '−'}${Math.abs(pitch).toFixed(1)}°` : '', w - 2, h - 1);
  if (!ok) {
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    g.fillStyle = '#fc8';
    g.fillText(imu === null ? 'no report' : `no attitude: ${imu.health}`, cx, cy + r * 0.45);
  }
  panel.horizon = { roll_deg: roll, pitch_deg: pitch, ok, fallLatched, drawn: (panel.horizon?.drawn ?? 0) + 1 };
}

const FAULT_WORDS = { wrong_id: 'wrong id', nak: 'no acknowledge', stuck: 'stuck data', bus_held: 'bus held' };
const signed = (rad) => `${rad >= 0 ? '+' : '−'}${Math.abs(rad / DEG).toFixed(2)}°`;

// The sensor's part of a state: `imu` (null: a device older than 2.3) and the flags.
function showImu(imu, flags) {
  panel.imu = imu;
  const fallLatched = flags.fall_detected || (imu !== null && imu.fall !== null);
  drawHorizon(imu, fallLatched);
  const badge = $('imu-health');
  const sw = $('balance-switch');
  if (imu === null) {
    badge.textContent = 'no report';
    badge.className = 'badge';
    $('imu-detail').textContent = 'the device speaks a protocol older than 2.3: no inertial sensor';
    $('imu-leveling').textContent = 'leveling: not available';
    $('imu-fall').textContent = '';
    $('imu-fall').className = '';
    $('balance-note').textContent = '';
    sw.checked = false;
    sw.disabled = true;
    return;
  }
  const health = imu.health === 'fault' ? `fault (${FAULT_WORDS[imu.fault_kind] ?? imu.fault_kind})` : imu.health;
  badge.textContent = health;
  badge.className = `badge ${imu.health === 'ok' ? 'ok' : imu.health === 'starting' ? '' : 'bad'}`;
  $('imu-detail').textContent = {
    absent: 'nothing answers on the sensor bus: the motions run open loop',
    starting: 'measuring the gyro bias: keep the robot still',
    ok: `attitude estimated · ${imu.samples} samples`,
    fault: 'the last reading failed: leveling is off until it is switched on again',
  }[imu.health] ?? '';
  let lev;
  if (!imu.leveling) lev = 'leveling <b>off</b>';
  else if (!imu.leveling_active) lev = 'leveling <b>on</b>, waiting (needs the sensor ok and a stance held or a sway running)';
  else lev = `leveling <b>on</b> · correction roll ${signed(imu.correction_roll_rad)} pitch ${signed(imu.correction_pitch_rad)}${imu.correction_limited ? ' (limited)' : ''}`;
  $('imu-leveling').innerHTML = lev;
  const fall = $('imu-fall');
  if (fallLatched) {
    const kind = imu.fall === 'free_fall' ? 'free fall' : imu.fall === 'tilt' ? 'tilt' : 'fall';
    fall.textContent = `FALL latched (${kind}): the outputs went to their safe state (${imu.safe_state}). `
      + 'Set the robot on its feet, then a motion (Stand on the Motion tab), a pose or Outputs on clears it.';
    fall.className = 'latched';
  } else {
    fall.textContent = imu.fall_detection
      ? `fall detection on (beyond ${(imu.fall_angle_rad / DEG).toFixed(0)}° → ${imu.safe_state})`
      : 'fall detection off';
    fall.className = '';
  }
  $('balance-note').textContent = imu.health === 'absent'
    ? 'no sensor: the device refuses leveling'
    : imu.health === 'fault' ? 'sensor fault: the device refuses leveling' : '';
  if (!balancePending) sw.checked = imu.leveling;
  sw.disabled = !panel.controlling || balancePending;
}
panel.showImu = showImu;

let balancePending = false;
function buildBalance() {
  const sw = $('balance-switch');
  sw.addEventListener('change', () => {
    $('balance-error').textContent = '';
    balancePending = true;
    sw.disabled = true;
    panel.balanceRequests = (panel.balanceRequests ?? 0) + 1;
    send({ type: 'set_balance', leveling: sw.checked });
  });
}

// The switch's answer: done, or the device's refusal in words; the switch shows the device's
// setting again either way.
function balanceAnswered(error) {
  balancePending = false;
  $('balance-error').textContent = error ?? '';
  if (panel.state) showImu(panel.state.imu, panel.state.flags);
}

// ---------------------------------------------------------------- motions and teleop
// Each motion's parameters as the form shows them (degrees and millimetres on the page, SI on
// the wire, as the sliders); a duration of 0 runs until Stop.
const LEGS = ['all', 'FL', 'FR', 'RL', 'RR'];
const MOTION_FORMS = {
  stand: { label: 'stand', fields: [] },
  sit: { label: 'sit', fields: [] },
  rest: { label: 'rest (then outputs off)', fields: [] },
  sway: {
    label: 'sway',
    fields: [['axis', ['roll', 'pitch', 'yaw']], ['amplitude_deg', 8], ['period_s', 2], ['duration_s', 0]],
  },
  yaw_turn: {
    label: 'yaw turn',
    fields: [['yaw_rate_deg_s', 10], ['step_period_s', 1], ['lift_height_mm', 30], ['duration_s', 0]],
  },
  foot_path: {
    label: 'foot path',
    fields: [['path', ['bezier', 'rectangle', 'semicircle', 'ellipse', 'cycloid']], ['leg', LEGS],
      ['stride_mm', 60], ['step_height_mm', 30], ['duty_factor', 0.5], ['cycle_s', 1], ['duration_s', 0]],
  },
  walk: {
    label: 'trot / walk',
    fields: [['gait', ['trot', 'walk']], ['body_height_mm', 400], ['step_height_mm', 40], ['cycle_s', 0.8],
      ['velocity_timeout_ms', 500]],
  },
};

// The message's field of each form input whose unit differs on the page.
const FIELD_OF_INPUT = {
  amplitude_deg: 'amplitude_rad', yaw_rate_deg_s: 'yaw_rate_rad_s', lift_height_mm: 'lift_height_m',
  stride_mm: 'stride_m', step_height_mm: 'step_height_m', body_height_mm: 'body_height_m',
};

// The `start_motion` message of the form's values: the protocol's motion request in its text
// form, `"stand_up"` or `{ sway: { axis: 'roll', ... } }` (snake_case names, SI units).
function motionMessage(kind, values) {
  const v = values;
  const dur = (s) => (Number(s) > 0 ? Number(s) : null);
  const mm = (x) => Number(x) / 1000;
  switch (kind) {
    case 'sway':
      return { sway: { axis: v.axis, amplitude_rad: Number(v.amplitude_deg) * DEG, period_s: Number(v.period_s), duration_s: dur(v.duration_s) } };
    case 'yaw_turn':
      return { yaw_turn: { yaw_rate_rad_s: Number(v.yaw_rate_deg_s) * DEG, step_period_s: Number(v.step_period_s), lift_height_m: mm(v.lift_height_mm), duration_s: dur(v.duration_s) } };
    case 'foot_path':
      return { foot_path: { path: v.path, legs: v.leg === 'all' ? 'all' : { one: v.leg }, stride_m: mm(v.stride_mm), step_height_m: mm(v.step_height_mm), duty_factor: Number(v.duty_factor), cycle_s: Number(v.cycle_s), duration_s: dur(v.duration_s) } };
    case 'walk':
      return { walk: { gait: v.gait, body_height_m: mm(v.body_height_mm), step_height_m: mm(v.step_height_mm), cycle_s: Number(v.cycle_s), velocity_timeout_ms: Number(v.velocity_timeout_ms) } };
    case 'stand':
      return 'stand_up';
    default:
      return kind;
  }
}

function showMotionForm() {
  const kind = $('motion-kind').value;
  const box = $('motion-params');
  box.innerHTML = '';
  for (const [name, init] of MOTION_FORMS[kind].fields) {
    const label = document.createElement('label');
    label.textContent = `${name} `;
    let input;
    if (Array.isArray(init)) {
      input = document.createElement('select');
      for (const o of init) input.add(new Option(o, o));
    } else {
      input = document.createElement('input');
      input.type = 'number';
      input.step = 'any';
      input.value = init;
    }
    input.dataset.param = name;
    label.appendChild(input);
    box.appendChild(label);
  }
}

function buildMotion() {
  const sel = $('motion-kind');
  for (const [kind, f] of Object.entries(MOTION_FORMS)) sel.add(new Option(f.label, kind));
  sel.addEventListener('change', showMotionForm);
  showMotionForm();
  $('motion-start').addEventListener('click', () => {
    const values = {};
    for (const i of document.querySelectorAll('#motion-params [data-param]')) values[i.dataset.param] = i.value;
    const motion = motionMessage(sel.value, values);
    panel.lastMotion = motion;
    showRefusal('', null);
    motionClick = performance.now();
    send({ type: 'start_motion', motion });
  });
  $('motion-stop').addEventListener('click', () => send({ type: 'stop_motion' }));
  const pad = $('joystick');
  const setFromPointer = (ev) => {
    const r = pad.getBoundingClientRect();
    const u = ((ev.clientX - r.left) / r.width) * 2 - 1;
    const v = ((ev.clientY - r.top) / r.height) * 2 - 1;
    stick.x = Math.max(-1, Math.min(1, u));
    stick.y = Math.max(-1, Math.min(1, v));
  };
  pad.addEventListener('pointerdown', (ev) => { stick.active = true; pad.setPointerCapture(ev.pointerId); setFromPointer(ev); });
  pad.addEventListener('pointermove', (ev) => { if (stick.active) setFromPointer(ev); });
  pad.addEventListener('pointerup', () => { stick.active = false; stick.x = 0; stick.y = 0; });
  window.addEventListener('keydown', (ev) => { if (!(ev.target instanceof HTMLInputElement)) keys.add(ev.key.toLowerCase()); });
  window.addEventListener('keyup', (ev) => keys.delete(ev.key.toLowerCase()));
}
let motionClick = null; // Start clicked, its answer not yet in
let motionStarted = null; // Start acked, its first state not yet in
let motionSeen = null; // the started motion's first readback received, not yet drawn

// The device's motion engine in words: kind, stage, motion time, phase, and why the last
// motion stopped early.
function showMotion(m) {
  panel.motionStatus = m;
  panel.walking = m.kind === 'walk' && (m.stage === 'approach' || m.stage === 'run');
  const fault = m.fault ? ` · <span class="unreachable">stopped early: ${m.fault}</span>` : '';
  $('motion-status').innerHTML = m.kind === null
    ? `motion: idle${fault}`
    : `motion: <b>${m.kind}</b> · ${m.stage} · t ${m.t_s.toFixed(2)} s · phase ${m.phase.toFixed(2)}${fault}`;
}

// A refusal naming a field: the message under the form, the field's input marked.
function showRefusal(text, field) {
  $('motion-error').textContent = text;
  for (const i of document.querySelectorAll('#motion-params [data-param]')) {
    const name = FIELD_OF_INPUT[i.dataset.param] ?? i.dataset.param;
    i.classList.toggle('invalid', field !== null && name === field);
  }
}

const stick = { active: false, x: 0, y: 0 };
const keys = new Set();
const MAX_V = 0.2; // m/s
const MAX_YAW = 0.5; // rad/s
// 20 Hz, with room to spare: the device stops a walk whose velocity is not refreshed
// within its timeout (500 ms by default). At most a few commands awaiting their answer, so that
// a slow server or device gets recent velocities rather than a growing queue of old ones, while
// a round trip longer than the period (a busy machine) does not lower the rate.
const VELOCITY_PERIOD_MS = 50;
const VELOCITIES_IN_FLIGHT = 4;
let lastVelocitySent = 0;
let velocitiesInFlight = 0;

// The walk's velocity goes to the device only while the device reports a walk running, and
// often enough for its velocity timeout: on its own timer, not at the drawing's pace (a
// software-rendered view on a busy machine draws slowly).
function sendVelocity() {
  const now = performance.now();
  if (!panel.controlling || !panel.walking || velocitiesInFlight >= VELOCITIES_IN_FLIGHT
    || now - lastVelocitySent < VELOCITY_PERIOD_MS) return;
  const v = panel.velocity;
  lastVelocitySent = now;
  velocitiesInFlight += 1;
  panel.velocitiesSent += 1;
  send({ type: 'set_velocity', velocity: { forward_m_s: v.vx, lateral_m_s: v.vy, yaw_rate_rad_s: v.yaw } });
}
setInterval(sendVelocity, VELOCITY_PERIOD_MS / 5);

function pollInputs() {
  let vx = -stick.y; let vy = -stick.x; let yaw = 0;
  if (keys.has('w')) vx = 1; if (keys.has('s')) vx = -1;
  if (keys.has('a')) vy = 1; if (keys.has('d')) vy = -1;
  if (keys.has('q')) yaw = 1; if (keys.has('e')) yaw = -1;
  for (const gp of navigator.getGamepads ? navigator.getGamepads() : []) {
    if (!gp) continue;
    const dz = (v) => (Math.abs(v) < 0.1 ? 0 : v);
    if (dz(gp.axes[1]) || dz(gp.axes[0]) || dz(gp.axes[2] ?? 0)) {
      vx = -dz(gp.axes[1]); vy = -dz(gp.axes[0]); yaw = -dz(gp.axes[2] ?? 0);
    }
  }
  const v = { vx: vx * MAX_V, vy: vy * MAX_V, yaw: yaw * MAX_YAW };
  panel.velocity = v;
  sendVelocity();
  $('velocity').textContent = `vx ${v.vx.toFixed(3)} m/s · vy ${v.vy.toFixed(3)} m/s · yaw ${v.yaw.toFixed(3)} rad/s`;
  const pad = $('joystick');
  const g = pad.getContext('2d');
  g.clearRect(0, 0, pad.width, pad.height);
  g.fillStyle = '#54a0ff';
  g.beginPath();
  g.arc(pad.width / 2 - (v.vy / MAX_V) * 60, pad.height / 2 - (v.vx / MAX_V) * 60, 12, 0, 2 * Math.PI);
  g.fill();
}

// ---------------------------------------------------------------- calibration
let calServo = 0;
function buildCalibration(servos) {
  const sel = $('cal-servo');
  if (sel.options.length) return;
  servos.forEach((name, i) => sel.add(new Option(name, i)));
  sel.addEventListener('change', () => { calServo = Number(sel.value); showCalibration(panel.state, true); });
  for (const b of document.querySelectorAll('[data-jog]')) {
    b.addEventListener('click', () => send({ type: 'jog', servo: calServo, delta_us: Number(b.dataset.jog) }));
  }
  $('cal-set-center').addEventListener('click', () => send({ type: 'set_center', servo: calServo, center_us: Number($('cal-center').value) }));
  $('cal-set-direction').addEventListener('click', () => send({ type: 'set_direction', servo: calServo, reversed: $('cal-reversed').checked }));
  $('cal-save').addEventListener('click', () => send({ type: 'save_calibration' }));
  $('cal-read').addEventListener('click', () => send({ type: 'read_calibration' }));
  $('guide-start').addEventListener('click', () => send({ type: 'guide_start' }));
}

// The guided calibration: the server runs the step machine; the page shows its view and sends
// the keys of the step as buttons.
let shownGuide = null;
let shownGuideKeys = null;
function showGuide(g) {
  const box = $('guide');
  box.classList.toggle('hidden', !g);
  if (!g) return;
  const key = JSON.stringify(g) + panel.controlling;
  if (key === shownGuide) return;
  shownGuide = key;
  box.dataset.step = g.step;
  $('guide-prompt').textContent = g.prompt;
  $('guide-servo').textContent = g.servo
    ? `${g.servo}: centre ${g.center_us} µs (${g.center_us - g.start_center_us >= 0 ? '+' : ''}${g.center_us - g.start_center_us} µs from the start)`
    : g.changed.length ? `changed in RAM: ${g.changed.join(', ')}` : '';
  // The buttons are rebuilt only when the step's keys change (not under the pointer).
  const keysKey = JSON.stringify(g.keys);
  const keys = $('guide-keys');
  if (keysKey !== shownGuideKeys) {
    shownGuideKeys = keysKey;
    keys.replaceChildren(...g.keys.map((k) => {
      const b = document.createElement('button');
      b.textContent = `${k.key} · ${k.does}`;
      b.dataset.guideKey = k.key;
      if (k.key === 'q' || k.key === 's') b.className = 'warn';
      b.addEventListener('click', () => send({ type: 'guide_key', key: k.key }));
      return b;
    }));
  }
  for (const b of keys.children) b.disabled = !panel.controlling;
  $('guide-message').textContent = g.message ?? '';
  $('guide-message').className = g.refused ? 'unreachable' : 'note';
}

let shownCal = null;
function showCalibration(s, force) {
  if (!s || !panel.servos) return;
  const c = s.calibration[calServo];
  $('cal-live').innerHTML = `${panel.servos[calServo]}: angle ${(s.angles_rad[calServo] / DEG).toFixed(2)}° · pulse ${s.pulses_us[calServo].toFixed(1)} µs
    · centre ${c.center_us} µs · ${c.reversed ? 'reversed' : 'normal'} · travel [${c.min_us}, ${c.max_us}] µs`;
  const key = JSON.stringify(s.calibration);
  if (key !== shownCal || force) {
    shownCal = key;
    $('cal-center').value = c.center_us;
    $('cal-reversed').checked = c.reversed;
    const rows = s.calibration.map((k, i) => `<tr class="${i === calServo ? 'sel' : ''}"><td>${panel.servos[i]}</td><td>${k.center_us}</td><td>${k.reversed ? 'rev' : ''}</td><td>${(k.zero_rad / DEG).toFixed(1)}°</td><td>${k.us_per_rad.toFixed(0)}</td><td>${k.min_us}–${k.max_us}</td></tr>`);
    $('cal-table').innerHTML = `<tr><th>servo</th><th>centre µs</th><th>dir</th><th>zero</th><th>µs/rad</th><th>travel µs</th></tr>${rows.join('')}`;
  }
}

// ---------------------------------------------------------------- tabs, buttons, start
function tabs() {
  const panes = { 'tab-pose': 'pane-pose', 'tab-motion': 'pane-motion', 'tab-cal': 'pane-cal' };
  for (const [tab, pane] of Object.entries(panes)) {
    $(tab).addEventListener('click', () => {
      for (const [t, p] of Object.entries(panes)) {
        $(t).classList.toggle('active', t === tab);
        $(p).classList.toggle('hidden', p !== pane);
      }
    });
  }
  $('take-control').addEventListener('click', () => send({ type: 'take_control' }));
  $('release-control').addEventListener('click', () => send({ type: 'release_control' }));
  $('outputs-on').addEventListener('click', () => send({ type: 'set_outputs', enabled: true }));
  $('outputs-off').addEventListener('click', () => send({ type: 'set_outputs', enabled: false }));
}

// Body IK per second in the page: `n` previews through the WebAssembly module.
panel.benchIk = (n) => {
  const t0 = performance.now();
  for (let i = 0; i < n; i++) {
    const a = (i % 200) * 0.001;
    panel.kin.preview({ roll_rad: a, pitch_rad: -a, yaw_rad: a, x_m: 0, y_m: 0, z_m: 0 }, sliderStance(), panel.order);
  }
  return n / ((performance.now() - t0) / 1000);
};

async function main() {
  buildSliders();
  buildMotion();
  buildBalance();
  tabs();
  updateControl();
  resize();
  try {
    panel.kin = await loadKin('/kin.wasm');
    panel.wasmBytes = panel.kin.wasmBytes;
  } catch (e) {
    message(`kin-core (WebAssembly) failed to load: ${e.message}`);
    panel.errors.push(String(e));
    return;
  }
  connect();
  requestAnimationFrame(frame);
}

main();
