#pragma once
// The HTML and JavaScript of knnocc view pages (view_page.hpp puts three.js and the map data
// between them). Written for three.js r111. The exposed faces become one indexed mesh of quads
// with 16-bit integer corners (cell units, scaled by the mesh) and a colour per face (height
// ramp times a fixed light): in headless Chromium's software WebGL this draws about 3x faster
// than instanced quads with the same work in the vertex shader (bench/bench_view_page). An
// orbit control of its own (drag: turn, shift/right drag: move, wheel: zoom). When the first
// frame is drawn (gl.finish), document.title becomes "knnocc view: drawn in N ms" (N from the
// start of navigation).

namespace knnocc::cli::detail {

// The head after its Content-Security-Policy (view_page.hpp writes the lines before it).
inline const char* const kViewPageHead = R"html(<title>knnocc view</title>
<style>
html,body{margin:0;height:100%;overflow:hidden;background:#f4f5f7;font:13px sans-serif;color:#222}
#c{display:block;width:100%;height:100%}
#panel{position:absolute;top:8px;left:8px;background:rgba(255,255,255,.92);padding:8px 10px;
border:1px solid #ccc;border-radius:4px;max-width:420px}
#panel h1{font-size:14px;margin:0 0 4px}
#maps button{margin:2px 4px 2px 0;padding:2px 8px;border:1px solid #888;background:#fff;cursor:pointer}
#maps button.on{background:#345;color:#fff}
#note{color:#a40;margin-top:4px}
#legend{position:absolute;right:10px;top:10px;background:rgba(255,255,255,.92);padding:8px;
border:1px solid #ccc;border-radius:4px;font-size:12px}
#bar{width:16px;height:180px;display:inline-block;vertical-align:top;
background:linear-gradient(to top,#2640d9,#1abfe6,#33cc40,#f2d926,#d9261a)}
#ticks{display:inline-block;position:relative;height:180px;width:60px;vertical-align:top;margin-bottom:8px}
#ticks div{position:absolute;left:4px;transform:translateY(-50%)}
#help{color:#666;font-size:11px;margin-top:4px}
</style></head>
<body><canvas id="c"></canvas>
<div id="panel"><h1>knnocc view</h1><div id="maps"></div><div id="info"></div>
<label><input type="checkbox" id="free"> free voxels</label><div id="note"></div>
<div id="help">drag: turn &middot; shift or right drag: move &middot; wheel: zoom &middot; r: reset</div></div>
<div id="legend"><div id="ltitle">height (m)</div><div id="bar"></div><div id="ticks"></div>
<div><span style="display:inline-block;width:16px;height:10px;background:#c8ccd2"></span> free</div>
<div style="color:#666">clipped to 2-98 %</div></div>
)html";

// The page's own script (view_page.hpp puts it in a <script> element and lists its hash).
inline const char* const kViewPageScript = R"js(
(function () {
'use strict';
const D = KNNOCC_DATA;
const canvas = document.getElementById('c');
const renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: false, preserveDrawingBuffer: true});
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setSize(window.innerWidth, window.innerHeight, false);
renderer.setClearColor(0xf4f5f7);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.01, 1e5);

function bytes(b64) {
  const s = atob(b64), a = new Uint8Array(s.length);
  for (let i = 0; i < s.length; ++i) a[i] = s.charCodeAt(i);
  return a;
}
const stops = [[0.15, 0.25, 0.85], [0.10, 0.75, 0.90], [0.20, 0.80, 0.25], [0.95, 0.85, 0.15],
               [0.85, 0.15, 0.10]];  // the pictures' height ramp
const light = [0.35 / 1.2, 1.0 / 1.2, 0.55 / 1.2];
// Exposed faces as quads with integer corners in cell units (mesh scale: metres per cell); one
// colour per face: height ramp times a fixed light.
function faceMesh(m) {
  const cells = new Uint16Array(bytes(m.cellData).buffer), masks = bytes(m.maskData);
  let nf = 0;
  for (let i = 0; i < masks.length; ++i) for (let f = 0; f < 6; ++f) nf += (masks[i] >> f) & 1;
  const pos = new Uint16Array(nf * 12), col = new Uint8Array(nf * 12), idx = new Uint32Array(nf * 6);
  const cellM = m.res * Math.pow(2, m.level), span = D.heightHi - D.heightLo;
  const c = [0, 0, 0], rgb = [0, 0, 0];
  let k = 0;
  for (let i = 0; i < masks.length; ++i) {
    const mk = masks[i];
    c[0] = cells[3 * i]; c[1] = cells[3 * i + 1]; c[2] = cells[3 * i + 2];
    const s = Math.min(1, Math.max(0, (m.origin[1] + (c[1] + 0.5) * cellM - D.heightLo) / span)) * 4;
    const j = Math.min(3, Math.floor(s)), fr = s - j;
    for (let a = 0; a < 3; ++a) rgb[a] = stops[j][a] + (stops[j + 1][a] - stops[j][a]) * fr;
    for (let f = 0; f < 6; ++f) {
      if (!((mk >> f) & 1)) continue;
      const axis = f >> 1, neg = f & 1;
      let t = (axis + 1) % 3, b = (axis + 2) % 3;
      if (neg) { const q = t; t = b; b = q; }
      const shade = 255 * (0.5 + 0.5 * Math.max(neg ? -light[axis] : light[axis], 0) - (axis === 0 ? 0.06 : 0));
      const o = 12 * k;
      for (let v = 0; v < 4; ++v) {
        const p = o + 3 * v;
        pos[p + axis] = c[axis] + (neg ? 0 : 1);
        pos[p + t] = c[t] + (v === 1 || v === 2 ? 1 : 0);
        pos[p + b] = c[b] + (v >= 2 ? 1 : 0);
        col[p] = rgb[0] * shade; col[p + 1] = rgb[1] * shade; col[p + 2] = rgb[2] * shade;
      }
      const q = 6 * k, base = 4 * k;
      idx[q] = base; idx[q + 1] = base + 1; idx[q + 2] = base + 2;
      idx[q + 3] = base; idx[q + 4] = base + 2; idx[q + 5] = base + 3;
      ++k;
    }
  }
  const g = new THREE.BufferGeometry();
  g.setIndex(new THREE.BufferAttribute(idx, 1));
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.BufferAttribute(col, 3, true));
  const mesh = new THREE.Mesh(g, new THREE.MeshBasicMaterial({vertexColors: THREE.VertexColors}));
  mesh.position.set(m.origin[0], m.origin[1], m.origin[2]);
  mesh.scale.set(cellM, cellM, cellM);
  mesh.frustumCulled = false;
  return {mesh: mesh, faces: nf};
}
const groups = D.maps.map(function (m) {
  const group = new THREE.Group();
  const fm = faceMesh(m), mesh = fm.mesh, nf = fm.faces;
  group.add(mesh);
  // Free voxels: points at their cell centres, drawn on demand.
  const fd = new Uint16Array(bytes(m.freeData).buffer), fs = Math.pow(2, m.freeLevel);
  const pos = new Float32Array(fd.length);
  for (let i = 0; i < fd.length; i += 3)
    for (let a = 0; a < 3; ++a) pos[i + a] = m.origin[a] + (fd[i + a] + 0.5) * fs * m.res;
  const pg = new THREE.BufferGeometry();
  pg.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  const points = new THREE.Points(pg, new THREE.PointsMaterial(
      {color: 0x9aa3ad, size: 2, sizeAttenuation: false, transparent: true, opacity: 0.35, depthWrite: false}));
  points.visible = false;
  group.add(points);
  group.userData = {mesh: mesh, points: points, faces: nf};
  group.visible = false;
  scene.add(group);
  return group;
});

// Orbit camera around a target (y up).
const view = {target: new THREE.Vector3(), dist: 10, az: 0.8, el: 0.6};
function reset() {
  const m = D.maps[current];
  view.target.set(m.centre[0], m.centre[1], m.centre[2]);
  const r = Math.sqrt(m.half[0] * m.half[0] + m.half[1] * m.half[1] + m.half[2] * m.half[2]);
  view.dist = r / Math.sin(camera.fov * Math.PI / 360) * 1.15;
  view.az = 0.6; view.el = 0.65;
}
function place() {
  const ce = Math.cos(view.el);
  camera.position.set(view.target.x + view.dist * ce * Math.sin(view.az),
                      view.target.y + view.dist * Math.sin(view.el),
                      view.target.z + view.dist * ce * Math.cos(view.az));
  camera.near = view.dist / 1000; camera.far = view.dist * 100;
  camera.updateProjectionMatrix();
  camera.lookAt(view.target);
}
let pending = false;
function draw() { if (!pending) { pending = true; requestAnimationFrame(function () { pending = false; place(); renderer.render(scene, camera); }); } }
let drag = null;
canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
canvas.addEventListener('pointerdown', function (e) { drag = {x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2}; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointerup', function () { drag = null; });
canvas.addEventListener('pointermove', function (e) {
  if (!drag) return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX; drag.y = e.clientY;
  if (drag.pan) {
    const s = view.dist * 0.0015, right = new THREE.Vector3(), up = new THREE.Vector3();
    camera.matrix.extractBasis(right, up, new THREE.Vector3());
    view.target.addScaledVector(right, -dx * s).addScaledVector(up, dy * s);
  } else {
    view.az -= dx * 0.008;
    view.el = Math.max(-1.55, Math.min(1.55, view.el + dy * 0.008));
  }
  draw();
});
canvas.addEventListener('wheel', function (e) { e.preventDefault(); view.dist *= Math.pow(1.0015, e.deltaY); draw(); }, {passive: false});
window.addEventListener('keydown', function (e) { if (e.key === 'r') { reset(); draw(); } });
window.addEventListener('resize', function () {
  renderer.setSize(window.innerWidth, window.innerHeight, false);
  camera.aspect = window.innerWidth / window.innerHeight; draw();
});

let current = 0;
const freeBox = document.getElementById('free');
function fmt(n) { return n.toLocaleString('en-US'); }
function show(i) {
  current = i;
  groups.forEach(function (g, k) { g.visible = k === i; g.userData.points.visible = freeBox.checked; });
  const m = D.maps[i];
  document.querySelectorAll('#maps button').forEach(function (b, k) { b.className = k === i ? 'on' : ''; });
  // Names come from file names and flags: text nodes only, never markup.
  const info = document.getElementById('info'), name = document.createElement('b');
  name.textContent = m.name;
  info.replaceChildren(name, ': ' + m.res + ' m voxels, ' + fmt(m.occupied) + ' occupied, ' +
      fmt(m.free) + ' free', document.createElement('br'), 'up = ' + D.up + ' (right ' + D.right +
      ', forward ' + D.forward + '); ' + fmt(groups[i].userData.faces) + ' faces drawn');
  const cellM = m.res * Math.pow(2, m.level);
  let note = '';
  if (m.level > 0)
    note += 'Subset: drawn at ' + cellM.toPrecision(3) + ' m cells (' + Math.pow(2, m.level) +
        '\u00d7 coarser, a cell is occupied when any voxel in it is): ' + fmt(m.cells) +
        ' cells for ' + fmt(m.occupied) + ' voxels. ';
  if (freeBox.checked && m.freeLevel > 0)
    note += 'Free voxels: ' + fmt(m.freeCells) + ' points at ' + (m.res * Math.pow(2, m.freeLevel)).toPrecision(3) + ' m.';
  document.getElementById('note').textContent = note;
  draw();
}
const mapsDiv = document.getElementById('maps');
D.maps.forEach(function (m, i) {
  const b = document.createElement('button');
  b.textContent = m.name; b.onclick = function () { show(i); };
  mapsDiv.appendChild(b);
});
freeBox.onchange = function () { show(current); };
const ticks = document.getElementById('ticks');
document.getElementById('ltitle').textContent = 'height (m, up = ' + D.up + ')';
const span = D.heightHi - D.heightLo, step = Math.pow(10, Math.floor(Math.log10(span / 4)));
const st = span / step > 20 ? step * 5 : span / step > 8 ? step * 2 : step;
for (let v = Math.ceil(D.heightLo / st) * st; v <= D.heightHi + 1e-9; v += st) {
  const d = document.createElement('div');
  d.style.top = ((D.heightHi - v) / span * 180) + 'px';
  d.textContent = '- ' + (Math.abs(v) < 1e-9 ? 0 : v).toFixed(st < 1 ? (st < 0.1 ? 2 : 1) : 0);
  ticks.appendChild(d);
}
// page.html#N shows map N first (0-based); page.html#N,free with the free voxels.
const hash = location.hash.slice(1).split(',');
const first = Math.min(D.maps.length - 1, Math.max(0, parseInt(hash[0], 10) || 0));
freeBox.checked = hash.indexOf('free') >= 0;
current = first;
reset();
show(first);
// First frame now, synchronously, and report when the GPU has finished it.
place();
renderer.render(scene, camera);
const gl = renderer.getContext();
gl.finish();
gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
const ms = Math.round(performance.now());
document.body.setAttribute('data-drawn-ms', ms);
document.title = 'knnocc view: drawn in ' + ms + ' ms';
})();
)js";

}  // namespace knnocc::cli::detail
