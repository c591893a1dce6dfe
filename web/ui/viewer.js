// A 3D view of a mesh with three.js: orbit controls, a wireframe toggle and the triangle count.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { STLLoader } from 'three/addons/loaders/STLLoader.js';

// OFF (ASCII): header, counts, vertices, polygons fanned into triangles.
function parseOff(text) {
  const tokens = text.replace(/#[^\n]*/g, ' ').trim().split(/\s+/);
  let i = 0;
  if (!/^[CN]*OFF$/.test(tokens[i])) throw new Error('OFF: expected the header "OFF" at the start');
  i++;
  const nv = parseInt(tokens[i++], 10), nf = parseInt(tokens[i++], 10); i++;
  if (!(nv >= 0 && nf >= 0)) throw new Error('OFF: expected vertex and face counts after the header');
  const pos = new Float32Array(nv * 3);
  for (let v = 0; v < nv * 3; v++) pos[v] = parseFloat(tokens[i++]);
  const index = [];
  for (let f = 0; f < nf; f++) {
    const n = parseInt(tokens[i++], 10);
    const ids = tokens.slice(i, i + n).map((t) => parseInt(t, 10)); i += n;
    for (let k = 1; k + 1 < n; k++) index.push(ids[0], ids[k], ids[k + 1]);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setIndex(index);
  return g;
}

// Mesh bytes to a BufferGeometry, by file name (PLY, OBJ, OFF, STL).
export function parseMesh(name, buffer) {
  const ext = (name.split('.').pop() || 'ply').toLowerCase();
  if (ext === 'ply') return new PLYLoader().parse(buffer);
  if (ext === 'stl') return new STLLoader().parse(buffer);
  const text = new TextDecoder().decode(buffer);
  if (ext === 'off') return parseOff(text);
  if (ext === 'obj') {
    const group = new OBJLoader().parse(text);
    let geometry = null;
    group.traverse((o) => { if (o.isMesh && !geometry) geometry = o.geometry; });
    if (!geometry) throw new Error('OBJ: no faces found');
    return geometry;
  }
  throw new Error(`cannot show .${ext} files (PLY, OBJ, OFF, STL)`);
}

export function triangleCount(geometry) {
  return geometry.index ? geometry.index.count / 3 : geometry.attributes.position.count / 3;
}

// Puts a viewer into `container` (a figure); returns { setGeometry, dispose }.
export function createViewer(container, label) {
  container.innerHTML = '';
  const canvasBox = document.createElement('div');
  canvasBox.className = 'viewer';
  canvasBox.setAttribute('role', 'img');
  canvasBox.setAttribute('aria-label', `${label}: 3D view (drag to orbit, scroll to zoom)`);
  const caption = document.createElement('figcaption');
  const count = document.createElement('span');
  count.className = 'triangles';
  const toggleLabel = document.createElement('label');
  toggleLabel.style.display = 'inline';
  const toggle = document.createElement('input');
  toggle.type = 'checkbox';
  toggleLabel.append(toggle, ' Wireframe');
  caption.append(`${label} — `, count, ' ', toggleLabel);
  container.append(canvasBox, caption);

  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  canvasBox.append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef1f5);
  const camera = new THREE.PerspectiveCamera(45, 1, 0.001, 1000);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2.0));
  const light = new THREE.DirectionalLight(0xffffff, 1.5);
  camera.add(light);
  scene.add(camera);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = true;
  const material = new THREE.MeshStandardMaterial({ color: 0x8aa4c8, side: THREE.DoubleSide, flatShading: true });
  let mesh = null;
  let running = true;

  function resize() {
    const w = canvasBox.clientWidth || 300, h = canvasBox.clientHeight || 300;
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = '100%';
    renderer.domElement.style.height = '100%';
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  const observer = new ResizeObserver(resize);
  observer.observe(canvasBox);
  toggle.addEventListener('change', () => { material.wireframe = toggle.checked; });
  (function loop() {
    if (!running) return;
    controls.update();
    renderer.render(scene, camera);
    requestAnimationFrame(loop);
  })();

  return {
    setGeometry(geometry) {
      if (mesh) { scene.remove(mesh); mesh.geometry.dispose(); }
      geometry.computeVertexNormals();
      geometry.computeBoundingSphere();
      mesh = new THREE.Mesh(geometry, material);
      scene.add(mesh);
      const { center, radius } = geometry.boundingSphere;
      controls.target.copy(center);
      camera.position.set(center.x + radius * 1.6, center.y + radius * 0.8, center.z + radius * 1.6);
      camera.near = radius / 100; camera.far = radius * 100;
      camera.updateProjectionMatrix();
      count.textContent = `${triangleCount(geometry).toLocaleString('en')} triangles`;
      container.dataset.triangles = String(triangleCount(geometry));
      resize();
    },
    dispose() { running = false; observer.disconnect(); renderer.dispose(); },
  };
}
