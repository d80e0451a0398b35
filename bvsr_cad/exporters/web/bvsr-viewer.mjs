/* The report's 3D view: three.js draws, GLTFLoader reads the export's GLB scenes, OrbitControls moves the
   camera. What is left here: scene buttons, a camera that frames each scene from its stated direction, a
   light over the viewer's shoulder, the caption and its legend. */
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const V = window.BVSRViewer;
const FOV_DEG = 35;

async function gunzip(base64) {
  const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  return new Response(stream).arrayBuffer();
}

/* The distance at which every corner of the scene's box is in view, looking along -dir (as the viewer
   that framed scenes by hand: a tight fit rather than the bounding sphere's). */
function fitDistance(box, centre, dir, up, aspect) {
  const z = dir.clone().normalize(), x = new THREE.Vector3().crossVectors(up, z).normalize();
  const y = new THREE.Vector3().crossVectors(z, x), ty = Math.tan(THREE.MathUtils.degToRad(FOV_DEG) / 2);
  const tx = ty * Math.max(0.2, aspect);
  let dist = 0;
  for (let k = 0; k < 8; k++) {
    const q = new THREE.Vector3(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y,
                                k & 4 ? box.max.z : box.min.z).sub(centre);
    dist = Math.max(dist, q.dot(z) + Math.abs(q.dot(x)) / tx, q.dot(z) + Math.abs(q.dot(y)) / ty);
  }
  return 1.1 * dist;
}

function caption(info, gltfScene) {
  const meta = gltfScene.userData, kinds = new Map();
  let objects = 0, triangles = 0;
  gltfScene.traverse((o) => {
    if (!o.isMesh) return;
    objects += 1;
    triangles += (o.geometry.index ? o.geometry.index.count : o.geometry.attributes.position.count) / 3;
    if (!kinds.has(o.material.name)) kinds.set(o.material.name, o.material.color.getStyle());
  });
  info.textContent = "";
  const title = document.createElement("b");
  title.textContent = meta.title + ". ";
  info.append(title, `${meta.note}. ${objects} objects, ${triangles} triangles. `);
  for (const [kind, colour] of kinds) {
    const swatch = document.createElement("span");
    swatch.className = "swatch";
    swatch.style.background = colour;
    info.append(swatch, kind.replace(/_/g, " ") + " ");
  }
}

function start(opts) {
  const canvas = document.getElementById(opts.canvas), info = document.getElementById(opts.info);
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  const camera = new THREE.PerspectiveCamera(FOV_DEG, 1, 1e-4, 100);
  const controls = new OrbitControls(camera, canvas);
  const light = new THREE.DirectionalLight(0xffffff, 2.2);
  light.position.set(0.35, 0.55, 0.76);  /* in the camera's frame: over the viewer's shoulder */
  camera.add(light);
  const world = new THREE.Scene();
  world.background = new THREE.Color("#edf2f7");
  world.add(camera, new THREE.AmbientLight(0xffffff, 0.9));
  const loaded = {};
  let current = null;

  const render = () => {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.round(w * devicePixelRatio) || canvas.height !== Math.round(h * devicePixelRatio)) {
      renderer.setPixelRatio(devicePixelRatio);
      renderer.setSize(w, h, false);
      camera.aspect = w / Math.max(1, h);
      camera.updateProjectionMatrix();
    }
    renderer.render(world, camera);
  };
  const frame = () => {
    const meta = current.userData, up = new THREE.Vector3(...meta.up), dir = new THREE.Vector3(...meta.eye);
    const box = new THREE.Box3().setFromObject(current), centre = box.getCenter(new THREE.Vector3());
    camera.aspect = canvas.clientWidth / Math.max(1, canvas.clientHeight);
    const dist = fitDistance(box, centre, dir, up, camera.aspect);
    camera.up.copy(up);
    camera.position.copy(centre).addScaledVector(dir.normalize(), dist);
    camera.near = dist / 100;
    camera.far = dist * 10;
    camera.updateProjectionMatrix();
    controls.target.copy(centre);
    controls.update();
    render();
  };
  const show = async (name) => {
    for (const b of document.querySelectorAll(`#${opts.buttons} button`)) {
      b.className = b.dataset.scene === name ? "active" : "";
    }
    if (!loaded[name]) {
      const entry = opts.scenes.find((s) => s.name === name);
      info.textContent = `loading ${entry.title} ...`;
      const data = await V.scene(entry);
      loaded[name] = (await new GLTFLoader().parseAsync(await gunzip(data), "")).scene;
    }
    if (current) world.remove(current);
    current = loaded[name];
    world.add(current);
    caption(info, current);
    frame();
  };

  controls.addEventListener("change", render);
  canvas.addEventListener("dblclick", () => current && frame());
  addEventListener("resize", render);
  for (const b of document.querySelectorAll(`#${opts.buttons} button`)) {
    b.addEventListener("click", () => show(b.dataset.scene));
  }
  const hash = decodeURIComponent(location.hash.slice(1));
  show(hash.startsWith("viewer=") ? hash.slice(7) : opts.initial).catch((e) => { info.textContent = String(e); });
}

V.run = start;
if (V.opts) start(V.opts);
