// viewer.js - the 3D view of one output frame: every particle drawn with its shape's mesh, size,
// position and orientation (one instanced mesh per shape), walls translucent, z up, orbit with
// the left button, zoom with the wheel, pan with the right button. Uses three.js from Debian's
// libjs-three (the global THREE, served by the daemon at /vendor/three/); renders on demand.
//
//   const v = new Viewer(container);
//   v.setScene({shapes: [{name, kind, vertices, triangles}], particles: {shape, size}, walls});
//   v.setFrame({time, position, orientation, walls});

import { flat } from './api.js';

const PALETTE = [0xc8793f, 0x4f86c6, 0x6aa84f, 0xb45fc1, 0xd4b13f, 0x47a9a6, 0xc0504d];

export function webglAvailable() {
  return typeof THREE !== 'undefined';
}

export class Viewer {
  constructor(container) {
    if (!webglAvailable()) throw new Error('three.js is not loaded (/vendor/three/three.min.js)');
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(0xf6f8fa);
    container.append(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 1e-4, 1e3);
    this.camera.up.set(0, 0, 1);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 0.65));
    const sun = new THREE.DirectionalLight(0xffffff, 0.55);
    sun.position.set(0.3, -0.5, 1);
    this.camera.add(sun);
    this.scene.add(this.camera);
    this.meshes = []; // per shape: {mesh, particles: [index...]}
    this.walls = new THREE.Group();
    this.scene.add(this.walls);
    this.fitted = false;
    this.controls = THREE.OrbitControls
      ? new THREE.OrbitControls(this.camera, this.renderer.domElement)
      : new SimpleOrbit(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  // Shapes (body-frame meshes for size 1), each particle's shape index and size [m], walls [m].
  setScene(info) {
    for (const { mesh } of this.meshes) {
      this.scene.remove(mesh);
      mesh.geometry.dispose();
      mesh.material.dispose();
    }
    this.walls.clear ? this.walls.clear() : this.walls.children.slice().forEach((c) => this.walls.remove(c));
    this.wallParts = new Map(); // name -> {triangles, mesh, edges}, to move a moving wall
    const shapeOf = info.particles.shape;
    this.size = Float64Array.from(info.particles.size);
    this.meshes = info.shapes.map((s, k) => {
      const particles = [];
      for (let i = 0; i < shapeOf.length; i++) if (shapeOf[i] === k) particles.push(i);
      const mat = new THREE.MeshLambertMaterial({ color: PALETTE[k % PALETTE.length] });
      const mesh = new THREE.InstancedMesh(geometry(s.vertices, s.triangles), mat, Math.max(1, particles.length));
      mesh.count = particles.length;
      mesh.frustumCulled = false; // instances are far from the mesh's own bounds
      this.scene.add(mesh);
      return { mesh, particles };
    });
    for (const w of info.walls || []) {
      // a faint surface and its edges: walls frame the scene without hiding the particles
      const g = geometry(w.vertices, w.triangles);
      const m = new THREE.Mesh(g, new THREE.MeshLambertMaterial({
        color: 0x8c959f, transparent: true, opacity: 0.12, depthWrite: false, side: THREE.DoubleSide,
      }));
      m.name = w.name;
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(g, 20),
        new THREE.LineBasicMaterial({ color: 0x6e7781, transparent: true, opacity: 0.6 }));
      this.walls.add(m);
      this.walls.add(edges);
      this.wallParts.set(w.name, { triangles: w.triangles, mesh: m, edges });
    }
    this.fitted = false;
  }

  // One frame: position (N x 3, m) and orientation (N x 4, w x y z), nested or flat; walls
  // {name: vertices [m]} for the walls that move, drawn where they are at this frame.
  setFrame(frame) {
    for (const [name, vertices] of Object.entries(frame.walls || {})) {
      const w = this.wallParts && this.wallParts.get(name);
      if (!w) continue;
      const g = geometry(vertices, w.triangles);
      w.mesh.geometry.dispose();
      w.mesh.geometry = g;
      w.edges.geometry.dispose();
      w.edges.geometry = new THREE.EdgesGeometry(g, 20);
    }
    const p = flat(frame.position), q = flat(frame.orientation);
    const m = new THREE.Matrix4(), pos = new THREE.Vector3(), rot = new THREE.Quaternion();
    const scl = new THREE.Vector3();
    for (const { mesh, particles } of this.meshes) {
      particles.forEach((i, slot) => {
        pos.set(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
        rot.set(q[4 * i + 1], q[4 * i + 2], q[4 * i + 3], q[4 * i]).normalize();
        const s = this.size[i];
        scl.set(s, s, s);
        m.compose(pos, rot, scl);
        mesh.setMatrixAt(slot, m);
      });
      mesh.instanceMatrix.needsUpdate = true;
    }
    if (!this.fitted) this.fit([p]);
    this.render();
  }

  // Camera on the bounding box of the particles in the given frames' positions (e.g. the first
  // and the last frame, so that everything they do stays in view), looking from the
  // front-right, slightly above.
  // Of many particles, the 5% furthest out along each axis are left out (a few that fly off
  // would shrink the rest to a speck).
  fit(positions) {
    const axes = [[], [], []];
    let rmax = 0;
    for (const p of positions) {
      for (let i = 0; i < p.length / 3; i++) {
        if (!Number.isFinite(p[3 * i] + p[3 * i + 1] + p[3 * i + 2])) continue;
        for (let k = 0; k < 3; k++) axes[k].push(p[3 * i + k]);
        rmax = Math.max(rmax, (this.size[i] || 0) / 2);
      }
    }
    const n = axes[0].length;
    if (!n) return;
    const cut = n >= 50 ? Math.floor(0.05 * n) : 0;
    const lo = [], hi = [];
    for (const a of axes) {
      a.sort((x, y) => x - y);
      lo.push(a[cut] - rmax);
      hi.push(a[n - 1 - cut] + rmax);
    }
    const box = new THREE.Box3(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    // Seen from slightly above, the box spans about its horizontal diagonal across and its
    // height plus part of that diagonal up; back off until both fit.
    const across = Math.max(Math.hypot(size.x, size.y), 1e-3);
    const up = size.z + 0.5 * across;
    const tan = Math.tan((this.camera.fov * Math.PI) / 360);
    const dist = 1.15 * Math.max(up / 2 / tan, across / 2 / (tan * this.camera.aspect)) + across / 2;
    const dir = new THREE.Vector3(0.55, -1, 0.6).normalize();
    this.camera.position.copy(centre).addScaledVector(dir, dist);
    this.camera.near = dist / 100;
    this.camera.far = dist * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.fitted = true;
    this.render();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }
}

// A flat-shaded BufferGeometry from vertices ([[x, y, z]] or flat) and triangles.
function geometry(vertices, triangles) {
  const v = flat(vertices), t = flat(triangles);
  const g = new THREE.BufferGeometry();
  const pos = new Float32Array(t.length * 3);
  for (let k = 0; k < t.length; k++) {
    pos[3 * k] = v[3 * t[k]];
    pos[3 * k + 1] = v[3 * t[k] + 1];
    pos[3 * k + 2] = v[3 * t[k] + 2];
  }
  (g.setAttribute || g.addAttribute).call(g, 'position', new THREE.BufferAttribute(pos, 3));
  g.computeVertexNormals();
  return g;
}

// Spheres of each particle's size, for a daemon that does not send shapes: sizes from the
// scenario's particle groups (listed sizes, or a distribution's mean).
export function sceneFromScenario(scenario, n) {
  const size = [];
  for (const g of scenario.particles || []) {
    if (Array.isArray(g.list)) for (const e of g.list) size.push(e.size);
    else {
      const s = g.size;
      const d = typeof s === 'number' ? s : s && (s.mean || (s.min + s.max) / 2);
      for (let i = 0; i < (g.count || 0); i++) size.push(d || 0.01);
    }
  }
  while (size.length < n) size.push(size[size.length - 1] || 0.01);
  const ico = new THREE.IcosahedronBufferGeometry(0.5, 1);
  const vertices = Array.from(ico.attributes.position.array);
  const triangles = Array.from({ length: vertices.length / 3 }, (_, i) => i);
  const walls = (scenario.walls || []).filter((w) => w.box).map((w) => boxMesh(w.name, w.box.min, w.box.max));
  return {
    shapes: [{ name: 'sphere', kind: 'sphere', vertices, triangles }],
    particles: { shape: new Array(n).fill(0), size: size.slice(0, n) },
    walls,
  };
}

export function boxMesh(name, a, b) {
  const vertices = [];
  for (let i = 0; i < 8; i++) vertices.push([i & 1 ? b[0] : a[0], i & 2 ? b[1] : a[1], i & 4 ? b[2] : a[2]]);
  const triangles = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
    [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]];
  return { name, vertices, triangles };
}

// Orbit (left drag), zoom (wheel) and pan (right drag) around a target with z up, for a
// libjs-three without OrbitControls.
class SimpleOrbit extends (typeof THREE !== 'undefined' ? THREE.EventDispatcher : Object) {
  constructor(camera, dom) {
    super();
    this.camera = camera;
    this.target = new THREE.Vector3();
    let drag = null;
    dom.addEventListener('contextmenu', (e) => e.preventDefault());
    dom.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey };
      dom.setPointerCapture(e.pointerId);
    });
    dom.addEventListener('pointerup', () => (drag = null));
    dom.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX;
      drag.y = e.clientY;
      const off = camera.position.clone().sub(this.target);
      if (drag.pan) {
        const s = off.length() / dom.clientHeight;
        const right = new THREE.Vector3().crossVectors(off, camera.up).normalize();
        const up = new THREE.Vector3().crossVectors(right, off).normalize();
        const move = right.multiplyScalar(dx * s).add(up.multiplyScalar(dy * s));
        this.target.add(move);
        camera.position.add(move);
      } else {
        const sph = new THREE.Spherical().setFromVector3(new THREE.Vector3(off.x, off.z, -off.y));
        sph.theta -= (2 * Math.PI * dx) / dom.clientHeight;
        sph.phi = Math.min(Math.PI - 0.01, Math.max(0.01, sph.phi - (2 * Math.PI * dy) / dom.clientHeight));
        const v = new THREE.Vector3().setFromSpherical(sph);
        camera.position.copy(this.target).add(new THREE.Vector3(v.x, -v.z, v.y));
      }
      this.update();
    });
    dom.addEventListener('wheel', (e) => {
      e.preventDefault();
      const off = camera.position.clone().sub(this.target);
      off.multiplyScalar(Math.exp(Math.sign(e.deltaY) * 0.1));
      camera.position.copy(this.target).add(off);
      this.update();
    }, { passive: false });
  }

  update() {
    this.camera.lookAt(this.target);
    this.dispatchEvent({ type: 'change' });
  }
}
