// roomlight viewer: a 2.5D area light (an emissive mesh around the capture point) seen from inside,
// with a probe lit by the light at the probe's position, next to the same probe under the env map.
// Shading: the mesh is rendered into a cube map from the probe every frame (linear radiance,
// half float); the mirror probe looks it up along the reflected ray, the diffuse probe (albedo
// 0.8) sums it over a fixed set of directions weighted by the cosine. The env map is the same
// panorama at infinity, which is the mesh seen from the capture point: its cube is rendered once
// there. Display: clip(radiance * 2^stops, 0, 1)^(1/2.2), as roomlight's PNG previews.
// A fit-photo's page shows the photograph as the backdrop, seen through its own camera (letterboxed
// to its aspect), with the photograph's depth mesh as an invisible occluder the probe is dragged on.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const D = JSON.parse(document.getElementById('roomlight-data').textContent);
const args = new URLSearchParams(location.hash.slice(1));
const vec = (s, d) => (s ? s.split(',').map(Number) : d);
function decode(s, T) {
  const bin = atob(s), u8 = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
  return new T(u8.buffer);
}

const canvas = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;  // the shaders write display values themselves
renderer.toneMapping = THREE.NoToneMapping;
renderer.autoClear = false;

const U = { uExposure: { value: 1 }, uRaw: { value: 0 } };  // shared by every material
const DISPLAY = `
uniform float uExposure; uniform float uRaw;
vec4 display(vec3 L) {
  if (uRaw > 0.5) return vec4(L, 1.0);
  return vec4(pow(clamp(L * uExposure, 0.0, 1.0), vec3(1.0 / ${D.gamma.toFixed(4)})), 1.0);
}`;

// ---- the emitter: positions, uv (v = 0 at the top row), inward faces, linear radiance texture
const tex = new THREE.DataTexture(decode(D.radiance, Uint16Array), D.width, D.height, THREE.RGBAFormat,
  THREE.HalfFloatType);
tex.wrapS = THREE.RepeatWrapping; tex.wrapT = THREE.ClampToEdgeWrapping;
tex.magFilter = THREE.LinearFilter; tex.minFilter = THREE.LinearFilter;
tex.generateMipmaps = false; tex.flipY = false; tex.colorSpace = THREE.NoColorSpace; tex.needsUpdate = true;

function geometry(m) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(decode(m.positions, Float32Array), 3));
  if (m.uv) g.setAttribute('uv', new THREE.BufferAttribute(decode(m.uv, Float32Array), 2));
  g.setIndex(new THREE.BufferAttribute(decode(m.faces, Uint32Array), 1));
  g.computeVertexNormals();
  return g;
}
const emitter = new THREE.Mesh(geometry(D.mesh), new THREE.ShaderMaterial({
  uniforms: { ...U, uRadiance: { value: tex } }, side: THREE.DoubleSide,
  vertexShader: 'varying vec2 vUv; void main() { vUv = uv; gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
  fragmentShader: `${DISPLAY}\nuniform sampler2D uRadiance; varying vec2 vUv;
    void main() { gl_FragColor = display(texture2D(uRadiance, vUv).rgb); }`,
}));
const scene = new THREE.Scene();
scene.add(emitter);  // layer 0: the only thing the cube cameras see

// ---- scene objects (layer 1), the capture point (layer 1), the probe (layer 2)
const plain = (color) => new THREE.ShaderMaterial({
  uniforms: { uColor: { value: new THREE.Color(color) } },
  vertexShader: 'varying vec3 vN; void main() { vN = normalize(normalMatrix * normal); gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
  fragmentShader: 'uniform vec3 uColor; varying vec3 vN; void main() { gl_FragColor = vec4(uColor * (0.45 + 0.55 * abs(vN.z)), 1.0); }',
});
// a fit-photo: the backdrop, and the photograph's depth mesh, which writes depth but no colour, so the
// probe hides behind what the photograph shows in front of it, and which the dragged probe rests on
let photoTex = null;
const surfaces = [];
if (D.photo) {
  const img = new Image();
  photoTex = new THREE.Texture(img);
  photoTex.colorSpace = THREE.NoColorSpace;  // sRGB values shown as they are, like the display() output
  img.onload = () => { photoTex.needsUpdate = true; document.body.dataset.photo = 'loaded'; };
  img.src = `data:image/png;base64,${D.photo.png}`;
}
for (const o of D.objects) {
  if (o.role === 'photo') {
    const m = new THREE.Mesh(geometry(o), new THREE.MeshBasicMaterial({ colorWrite: false, side: THREE.DoubleSide }));
    m.layers.set(1); m.renderOrder = -1; m.name = o.id; scene.add(m); surfaces.push(m);
    continue;
  }
  const m = new THREE.Mesh(geometry(o), plain(o.role.includes('eval') ? 0x8fb7d9 : 0xc9b48f));
  m.material.side = THREE.DoubleSide; m.layers.set(1); m.name = o.id; scene.add(m);
}
const capture = new THREE.Mesh(new THREE.SphereGeometry(0.03, 16, 8), plain(0xffd21f));
capture.layers.set(1); scene.add(capture);

function cubeTarget(size) {
  return new THREE.WebGLCubeRenderTarget(size, { type: THREE.HalfFloatType, generateMipmaps: true,
    minFilter: THREE.LinearMipmapLinearFilter, magFilter: THREE.LinearFilter });
}
const probeCube = cubeTarget(D.cube_size), envCube = cubeTarget(D.cube_size);
const probeCam = new THREE.CubeCamera(0.005, 1e4, probeCube), envCam = new THREE.CubeCamera(0.005, 1e4, envCube);
const LOD = Math.max(0, Math.log2(D.cube_size) - 3).toFixed(1);
const PROBE_FRAG = `${DISPLAY}
uniform samplerCube uCube; uniform float uDiffuse; varying vec3 vN; varying vec3 vPos;
void main() {
  vec3 n = normalize(vN);
  if (uDiffuse < 0.5) { gl_FragColor = display(textureLod(uCube, reflect(normalize(vPos - cameraPosition), n), 0.0).rgb); return; }
  vec3 e = vec3(0.0);  // albedo 0.8: (0.8 / pi) * sum L cos * (4 pi / N)
  for (int k = 0; k < 256; k++) {
    float y = 1.0 - (float(k) + 0.5) / 128.0, r = sqrt(1.0 - y * y), phi = 2.39996323 * float(k);
    vec3 d = vec3(r * cos(phi), y, r * sin(phi));
    e += textureLod(uCube, d, ${LOD}).rgb * max(dot(n, d), 0.0);
  }
  gl_FragColor = display(e * (0.8 * 4.0 / 256.0));
}`;
function probeMaterial(cube, diffuse) {
  return new THREE.ShaderMaterial({
    uniforms: { ...U, uCube: { value: cube.texture }, uDiffuse: { value: diffuse ? 1 : 0 } },
    vertexShader: 'varying vec3 vN; varying vec3 vPos; void main() { vN = normalize(mat3(modelMatrix) * normal); vec4 p = modelMatrix * vec4(position, 1.0); vPos = p.xyz; gl_Position = projectionMatrix * viewMatrix * p; }',
    fragmentShader: PROBE_FRAG,
  });
}
const ball = new THREE.SphereGeometry(1, 64, 32);
const probe = new THREE.Mesh(ball, probeMaterial(probeCube, args.get('material') === 'diffuse'));
probe.scale.setScalar(args.has('radius') ? +args.get('radius') : D.probe_radius); probe.layers.set(2); scene.add(probe);
probe.position.fromArray(vec(args.get('probe'), D.probe));

// ---- insets: mirror and diffuse probes under the 2.5D light (left) and under the env map (right)
const insets = [probeCube, envCube].map((cube) => {
  const s = new THREE.Scene();
  const a = new THREE.Mesh(ball, probeMaterial(cube, false)), b = new THREE.Mesh(ball, probeMaterial(cube, true));
  a.position.x = -1.1; b.position.x = 1.1; s.add(a, b);
  return s;
});
const insetCam = new THREE.PerspectiveCamera(30, 2, 0.1, 100);

// ---- camera, controls, dragging
const camera = new THREE.PerspectiveCamera(D.fov, 1, 0.01, 1e4);
camera.layers.enable(1); camera.layers.enable(2);
camera.up.fromArray(D.up);
camera.position.fromArray(vec(args.get('camera'), D.camera.origin));
const controls = new OrbitControls(camera, canvas);
controls.target.fromArray(vec(args.get('target'), D.camera.target));
controls.update();

const ray = new THREE.Raycaster(); ray.layers.set(2);
const surfaceRay = new THREE.Raycaster(); surfaceRay.layers.set(1);
const plane = new THREE.Plane(), hit = new THREE.Vector3(), grab = new THREE.Vector3();
let dragging = false;
// the part of the canvas the main view uses (CSS pixels from the top left): all of it, or the
// photograph's aspect, letterboxed, while the photograph is the backdrop
const view = { x: 0, y: 0, w: 1, h: 1 };
let photoOn = !!D.photo;
function pointer(e) {
  const r = canvas.getBoundingClientRect();
  const ndc = new THREE.Vector2(((e.clientX - r.left - view.x) / view.w) * 2 - 1, -((e.clientY - r.top - view.y) / view.h) * 2 + 1);
  ray.setFromCamera(ndc, camera); surfaceRay.setFromCamera(ndc, camera);
}
// Put the probe on the surface a ray meets, resting on it along the surface's normal; false if it meets none.
function restOnSurface(raycaster) {
  const h = raycaster.intersectObjects(surfaces, false)[0];
  if (!h || !h.face) return false;
  const n = h.face.normal.clone().transformDirection(h.object.matrixWorld);
  if (n.dot(raycaster.ray.direction) > 0) n.negate();
  setProbe(...h.point.clone().addScaledVector(n, probe.scale.x).toArray());
  return true;
}
// (u, v) in [0, 1] across the photograph (v down): the probe dropped on the surface seen there
function dropAt(u, v) {
  surfaceRay.setFromCamera(new THREE.Vector2(2 * u - 1, 1 - 2 * v), camera);
  return restOnSurface(surfaceRay) ? probe.position.toArray() : null;
}
canvas.addEventListener('pointerdown', (e) => {
  pointer(e);
  const h = ray.intersectObject(probe)[0];
  if (!h) return;
  dragging = true; controls.enabled = false;
  plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), probe.position);
  ray.ray.intersectPlane(plane, hit); grab.subVectors(probe.position, hit);
});
canvas.addEventListener('pointermove', (e) => {
  if (!dragging) return;
  pointer(e);
  if (surfaces.length && restOnSurface(surfaceRay)) return;
  if (ray.ray.intersectPlane(plane, hit)) setProbe(...hit.add(grab).toArray());
});
window.addEventListener('pointerup', () => { dragging = false; controls.enabled = true; });

// WASD / QE move the camera and its target together (first-person walking)
window.addEventListener('keydown', (e) => {
  const f = camera.getWorldDirection(new THREE.Vector3()), r = new THREE.Vector3().crossVectors(f, camera.up).normalize();
  const step = { w: f, s: f.clone().negate(), d: r, a: r.clone().negate(), e: camera.up.clone(), q: camera.up.clone().negate() }[e.key];
  if (!step || e.target.tagName === 'INPUT') return;
  step.multiplyScalar(0.05); camera.position.add(step); controls.target.add(step); controls.update();
});

// ---- the panel
const $ = (id) => document.getElementById(id);
function setExposure(stops) {
  U.uExposure.value = Math.pow(2, stops);
  $('exposure').value = stops; $('exposure-value').textContent = `${(+stops).toFixed(1)} stops`;
}
function setProbe(x, y, z) {
  probe.position.set(x, y, z);
  ['x', 'y', 'z'].forEach((k, i) => { $(`probe-${k}`).value = [x, y, z][i]; });
  $('probe-value').textContent = `(${[x, y, z].map((v) => v.toFixed(2)).join(', ')}) m`;
}
$('exposure').addEventListener('input', (e) => setExposure(+e.target.value));
for (const [i, k] of ['x', 'y', 'z'].entries()) {
  const el = $(`probe-${k}`);
  el.min = D.bounds[0][i]; el.max = D.bounds[1][i]; el.step = 0.01;
  el.addEventListener('input', () => setProbe(+$('probe-x').value, +$('probe-y').value, +$('probe-z').value));
}
$('material').addEventListener('change', (e) => { probe.material.uniforms.uDiffuse.value = e.target.value === 'diffuse' ? 1 : 0; });
$('material').value = args.get('material') === 'diffuse' ? 'diffuse' : 'mirror';
function setPhoto(on) {
  photoOn = !!(on && D.photo);
  if (photoOn) camera.layers.disable(0); else camera.layers.enable(0);  // the backdrop replaces the light
  capture.visible = !photoOn;  // the capture point may be the camera itself
  $('photo').checked = photoOn;
}
if (D.photo) {
  $('photo').addEventListener('change', (e) => setPhoto(e.target.checked));
  setPhoto(args.get('photo') !== '0');
} else {
  $('photo-row').style.display = 'none';
}
setExposure(args.has('exposure') ? +args.get('exposure') : D.exposure_stops);
setProbe(...probe.position.toArray());

// ---- render loop
function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== w || canvas.height !== h) renderer.setSize(w, h, false);
  let vw = w, vh = h;
  if (photoOn) {  // the photograph's aspect, as large as fits
    const a = D.photo.width / D.photo.height;
    if (w / h > a) vw = Math.round(h * a); else vh = Math.round(w / a);
  }
  Object.assign(view, { x: Math.round((w - vw) / 2), y: Math.round((h - vh) / 2), w: vw, h: vh });
  if (Math.abs(camera.aspect - vw / vh) > 1e-6) { camera.aspect = vw / vh; camera.updateProjectionMatrix(); }
}
function cube(cam, at) {
  U.uRaw.value = 1; cam.position.copy(at); cam.update(renderer, scene); U.uRaw.value = 0;
}
let frames = 0;
function frame() {
  resize();
  if (frames === 0) cube(envCam, new THREE.Vector3());
  cube(probeCam, probe.position);
  const w = canvas.width, h = canvas.height;
  renderer.setScissorTest(true);
  renderer.setViewport(0, 0, w, h); renderer.setScissor(0, 0, w, h);
  renderer.setClearColor(0x000000); renderer.clear();
  const vy = h - view.y - view.h;  // WebGL counts from the bottom
  renderer.setViewport(view.x, vy, view.w, view.h); renderer.setScissor(view.x, vy, view.w, view.h);
  scene.background = photoOn ? photoTex : null;
  renderer.render(scene, camera);
  scene.background = null;  // never in the cube maps
  // insets at the top right, 2:1 each, looking where the main camera looks
  const iw = D.inset_width, ih = iw / 2;
  const dir = camera.getWorldDirection(new THREE.Vector3());
  insetCam.position.copy(dir).multiplyScalar(-7); insetCam.up.copy(camera.up); insetCam.lookAt(0, 0, 0);
  insets.forEach((s, k) => {
    const x = w - (2 - k) * (iw + 8), y = h - ih - 8;
    renderer.setViewport(x, y, iw, ih); renderer.setScissor(x, y, iw, ih);
    renderer.setClearColor(0x202020); renderer.clear(); renderer.render(s, insetCam);
  });
  renderer.setScissorTest(false);
  frames += 1;
  document.body.dataset.frames = frames;
  requestAnimationFrame(frame);
}
window.roomlight = { setProbe, setExposure, setPhoto, dropAt, probe, camera, controls, data: D, frames: () => frames };
if (args.has('at')) { resize(); camera.updateMatrixWorld(); dropAt(...vec(args.get('at'))); }
requestAnimationFrame(frame);
