// The measured markers of a fitted marker trial (a C3D opened with "Load clip…"): in the frame
// shown, each marker is a point where the capture saw it, joined by a line to the model's virtual
// marker (its link's pose times its calibrated offset). Point and line are coloured by that
// residual: green at 1 cm or less, through yellow, to red at 4 cm or more (a good fit has a mean
// under 1 cm and every marker under 4 cm). The residual is taken from the pose drawn, so it also
// shows how far an edit has taken the figure from the capture. The markers come once per clip
// (GET /api/sessions/{id}/markers, revalidated by its revision); the "markers" view option hides
// them, and a legend names the frame's mean and worst marker.

import * as THREE from 'three';

const GOOD_M = 0.01;
const BAD_M = 0.04;
const MISSING_COLOR = new THREE.Color(0x8a8f98);

/** Green → yellow → red as the residual goes from GOOD_M to BAD_M. */
export function residualColor(residual, out = new THREE.Color()) {
  const t = Math.min(1, Math.max(0, (residual - GOOD_M) / (BAD_M - GOOD_M)));
  // hue 120° (green) down to 0° (red), through 60° (yellow)
  return out.setHSL((1 - t) / 3, 0.85, 0.5);
}

export function createMarkersView(state, viewport, skeleton, api) {
  const { signals } = state;
  let markers = null; // {revision, rate, names, links, offsets, frames}
  let fetching = null; // the revision being fetched
  const stats = { visible: false, revision: null, frame: -1, shown: 0, missing: 0, mean: 0, max: 0, worst: null, residuals: [], measured: [] };

  const pointsGeometry = new THREE.BufferGeometry();
  const points = new THREE.Points(
    pointsGeometry,
    new THREE.PointsMaterial({ size: 7, sizeAttenuation: false, vertexColors: true, depthTest: false, transparent: true }),
  );
  const virtualGeometry = new THREE.BufferGeometry();
  const virtualPoints = new THREE.Points(
    virtualGeometry,
    new THREE.PointsMaterial({ size: 4, sizeAttenuation: false, color: 0xf4f6fa, depthTest: false, transparent: true }),
  );
  const linesGeometry = new THREE.BufferGeometry();
  const lines = new THREE.LineSegments(linesGeometry, new THREE.LineBasicMaterial({ vertexColors: true, depthTest: false, transparent: true }));
  const group = new THREE.Group();
  group.name = 'markers';
  for (const o of [lines, points, virtualPoints]) {
    o.frustumCulled = false;
    o.renderOrder = 11;
    group.add(o);
  }
  group.visible = false;
  viewport.scene.add(group);

  const legend = document.createElement('div');
  legend.className = 'marker-legend';
  legend.id = 'marker-legend';
  legend.hidden = true;

  function allocate(n) {
    pointsGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
    pointsGeometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
    virtualGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
    linesGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6 * n), 3));
    linesGeometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(6 * n), 3));
  }

  const measured = new THREE.Vector3();
  const virtual = new THREE.Vector3();
  const color = new THREE.Color();

  // the frame of the pose drawn: the clip's time at the trial's rate
  function frameNow() {
    const time = state.pose?.time ?? state.session?.playback?.time ?? 0;
    return Math.min(markers.frames.length - 1, Math.max(0, Math.round(time * markers.rate)));
  }

  function place() {
    const visible = !!markers && state.view.markers !== false;
    group.visible = visible;
    legend.hidden = !visible;
    stats.visible = visible;
    if (!visible) return signals.renderRequested.dispatch();
    const f = frameNow();
    const row = markers.frames[f];
    const p = pointsGeometry.attributes.position.array;
    const c = pointsGeometry.attributes.color.array;
    const v = virtualGeometry.attributes.position.array;
    const l = linesGeometry.attributes.position.array;
    const lc = linesGeometry.attributes.color.array;
    let shown = 0;
    let sum = 0;
    let worst = null;
    let max = 0;
    const residuals = [];
    const seen = [];
    for (let k = 0; k < markers.names.length; k++) {
      skeleton.linkPointWorld(markers.links[k], markers.offsets[k], virtual);
      v.set([virtual.x, virtual.y, virtual.z], 3 * k);
      if (row[3 * k] === null) {
        residuals.push(null);
        seen.push(null);
        continue;
      }
      measured.set(row[3 * k], row[3 * k + 1], row[3 * k + 2]);
      const r = measured.distanceTo(virtual);
      residuals.push(r);
      seen.push([measured.x, measured.y, measured.z]);
      residualColor(r, color);
      p.set([measured.x, measured.y, measured.z], 3 * shown);
      c.set([color.r, color.g, color.b], 3 * shown);
      l.set([measured.x, measured.y, measured.z, virtual.x, virtual.y, virtual.z], 6 * shown);
      lc.set([color.r, color.g, color.b, color.r, color.g, color.b], 6 * shown);
      shown++;
      sum += r;
      if (r >= max) {
        max = r;
        worst = markers.names[k];
      }
    }
    pointsGeometry.setDrawRange(0, shown);
    linesGeometry.setDrawRange(0, 2 * shown);
    virtualGeometry.setDrawRange(0, markers.names.length);
    for (const a of [pointsGeometry.attributes.position, pointsGeometry.attributes.color, virtualGeometry.attributes.position]) a.needsUpdate = true;
    for (const a of [linesGeometry.attributes.position, linesGeometry.attributes.color]) a.needsUpdate = true;
    Object.assign(stats, { visible, revision: markers.revision, frame: f, shown, missing: markers.names.length - shown, mean: shown ? sum / shown : 0, max, worst, residuals, measured: seen });
    const mm = (m) => `${(m * 1000).toFixed(0)} mm`;
    legend.textContent = shown
      ? `markers, frame ${f}: ${shown} seen, mean ${mm(stats.mean)}, worst ${worst} ${mm(max)}`
      : `markers, frame ${f}: none seen`;
    legend.style.borderLeftColor = `#${residualColor(stats.mean, color).getHexString()}`;
    signals.renderRequested.dispatch();
  }

  function clear() {
    markers = null;
    fetching = null;
    group.visible = false;
    legend.hidden = true;
    Object.assign(stats, { visible: false, revision: null, frame: -1, shown: 0, missing: 0, mean: 0, max: 0, worst: null, residuals: [], measured: [] });
    signals.renderRequested.dispatch();
  }

  async function load(revision) {
    fetching = revision;
    try {
      const body = await api.markers();
      if (fetching !== revision) return; // another clip arrived meanwhile
      const links = body.markers.map((m) => state.linkIndex.get(m.link));
      if (links.some((i) => i === undefined)) throw new Error('markers: a marker names a link the character does not have');
      markers = {
        revision: body.revision,
        rate: body.rate,
        names: body.markers.map((m) => m.name),
        links,
        offsets: body.markers.map((m) => m.offset),
        frames: body.frames,
      };
      allocate(markers.names.length);
      place();
    } catch (err) {
      if (fetching === revision) fetching = null;
      signals.notify.dispatch({ text: `${err.message}: the trial's markers are not drawn`, kind: 'error' });
    }
  }

  signals.sessionStateChanged.add((session) => {
    const wanted = session?.markers?.revision ?? null;
    if (wanted === null) {
      if (markers || fetching !== null) clear();
      return;
    }
    if (markers?.revision === wanted || fetching === wanted) return;
    load(wanted);
  });
  signals.characterLoaded.add(clear);
  signals.poseChanged.add(() => markers && place());
  signals.viewOptionsChanged.add(() => {
    if (markers) place();
    else legend.hidden = true;
  });

  return {
    legend,
    /** What is drawn now: {visible, revision, frame, shown, missing, mean, max, worst, residuals,
     * measured} (metres; per marker of the set, null where the frame lacks it). */
    stats: () => ({ ...stats, residuals: stats.residuals.slice(), measured: stats.measured.slice() }),
  };
}
