// The 3D view: renderer, camera, orbit controls, lights and ground. It draws only when something
// set it dirty (requestRender / the renderRequested signal / the orbit controls' change event).

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const CAMERA_HOME = { position: new THREE.Vector3(1.7, 1.45, 3.3), target: new THREE.Vector3(0, 0.92, 0) };

export function createViewport(state) {
  const { signals } = state;
  const element = document.createElement('div');
  element.className = 'viewport';

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFShadowMap;
  renderer.domElement.className = 'viewport-canvas';
  renderer.domElement.tabIndex = 0;
  element.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x24272d);

  const camera = new THREE.PerspectiveCamera(35, 1, 0.02, 200);
  camera.position.copy(CAMERA_HOME.position);

  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(CAMERA_HOME.target);
  controls.enableDamping = false;
  controls.screenSpacePanning = true;
  controls.minDistance = 0.3;
  controls.maxDistance = 30;
  // the camera stays above the floor: it orbits no lower than a few degrees under the horizon of
  // its target, and neither it nor the target is panned below the ground
  controls.maxPolarAngle = Math.PI / 2 + 0.15;
  const MIN_CAMERA_HEIGHT = 0.05; // m
  const keepAboveFloor = () => {
    if (controls.target.y < 0) controls.target.y = 0;
    if (camera.position.y < MIN_CAMERA_HEIGHT) camera.position.y = MIN_CAMERA_HEIGHT;
  };
  controls.addEventListener('change', keepAboveFloor);
  controls.update();

  // lights: soft sky/ground fill and one key light that casts shadows on the floor
  scene.add(new THREE.HemisphereLight(0xdfe8ff, 0x3a3228, 1.6));
  const key = new THREE.DirectionalLight(0xffffff, 2.2);
  key.position.set(2.5, 5, 3.5);
  key.castShadow = true;
  key.shadow.mapSize.set(1024, 1024);
  key.shadow.camera.left = -2.5;
  key.shadow.camera.right = 2.5;
  key.shadow.camera.top = 2.5;
  key.shadow.camera.bottom = -2.5;
  key.shadow.camera.near = 0.5;
  key.shadow.camera.far = 15;
  key.shadow.bias = -0.0005;
  scene.add(key);
  const rim = new THREE.DirectionalLight(0x9fb8ff, 0.6);
  rim.position.set(-3, 2.5, -3);
  scene.add(rim);

  // ground: a shadow catcher and a metre grid (major lines every metre, minor every 10 cm)
  const ground = new THREE.Group();
  ground.name = 'ground';
  const floor = new THREE.Mesh(
    new THREE.PlaneGeometry(40, 40),
    new THREE.ShadowMaterial({ color: 0x000000, opacity: 0.28 }),
  );
  floor.rotation.x = -Math.PI / 2;
  floor.receiveShadow = true;
  ground.add(floor);
  const minor = new THREE.GridHelper(10, 100, 0x34383f, 0x34383f);
  minor.position.y = 0.0005;
  ground.add(minor);
  const major = new THREE.GridHelper(10, 10, 0x59606b, 0x474c55);
  major.position.y = 0.001;
  ground.add(major);
  const axes = new THREE.AxesHelper(0.25);
  axes.position.y = 0.002;
  ground.add(axes);
  scene.add(ground);

  let needsRender = true;
  const requestRender = () => {
    needsRender = true;
  };
  controls.addEventListener('change', requestRender);
  signals.renderRequested.add(requestRender);
  signals.viewOptionsChanged.add((v) => {
    ground.visible = v.grid;
    requestRender();
  });

  function resize() {
    const w = Math.max(1, element.clientWidth);
    const h = Math.max(1, element.clientHeight);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    requestRender();
  }
  new ResizeObserver(resize).observe(element);

  const stats = { renders: 0 };
  function loop() {
    requestAnimationFrame(loop);
    if (!needsRender) return;
    needsRender = false;
    renderer.render(scene, camera);
    stats.renders++;
  }
  requestAnimationFrame(loop);

  const ndc = new THREE.Vector3();
  return {
    element,
    scene,
    camera,
    renderer,
    controls,
    stats,
    requestRender,
    resize,
    /** Pointer event -> normalized device coordinates. */
    toNdc(event, out = new THREE.Vector2()) {
      const r = renderer.domElement.getBoundingClientRect();
      out.set(((event.clientX - r.left) / r.width) * 2 - 1, -((event.clientY - r.top) / r.height) * 2 + 1);
      return out;
    },
    /** World point -> client (CSS pixel) coordinates, and whether it is in front of the camera. */
    toClient(point) {
      const r = renderer.domElement.getBoundingClientRect();
      ndc.copy(point).project(camera);
      return { x: r.left + ((ndc.x + 1) / 2) * r.width, y: r.top + ((1 - ndc.y) / 2) * r.height, visible: ndc.z < 1 };
    },
    /** Where Home view looks: a function returning the subject's bounding box (THREE.Box3). */
    subjectBounds: null,
    /** Home view: the whole subject framed from the front-right, or the default view without one. */
    home() {
      const box = this.subjectBounds ? this.subjectBounds() : null;
      if (box && !box.isEmpty()) {
        this.frame(box);
        return;
      }
      camera.position.copy(CAMERA_HOME.position);
      controls.target.copy(CAMERA_HOME.target);
      controls.update();
      requestRender();
    },
    /** Frames a box of any size: the camera looks at its centre from the home direction, at the
     *  distance that fits its bounding sphere in the view, and the zoom limits and clipping planes
     *  follow its size (a 1 cm gripper and a 70 m giant are both framed). */
    frame(box) {
      const center = box.getCenter(new THREE.Vector3());
      const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.01);
      const halfFov = THREE.MathUtils.degToRad(camera.fov / 2) * Math.min(1, camera.aspect);
      const distance = (radius / Math.sin(halfFov)) * 1.05;
      controls.minDistance = radius * 0.05;
      controls.maxDistance = distance * 10;
      camera.near = Math.max(1e-4, radius * 0.01);
      camera.far = distance * 40;
      camera.updateProjectionMatrix();
      const direction = CAMERA_HOME.position.clone().sub(CAMERA_HOME.target).normalize();
      controls.target.copy(center);
      if (controls.target.y < 0) controls.target.y = 0;
      camera.position.copy(controls.target).addScaledVector(direction, distance);
      controls.update();
      requestRender();
    },
    focus(point) {
      const offset = camera.position.clone().sub(controls.target);
      controls.target.copy(point);
      camera.position.copy(point).add(offset);
      controls.update();
      requestRender();
    },
  };
}
