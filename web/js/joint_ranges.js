// Joint-range geometry for display: the swing–twist factorization of docs/character-format.md
// (range frame x axis = nominal link direction; swing a = (a_y, a_z) = vector part of the swing
// quaternion; twist limits interpolated barycentrically over the range triangles) and the hinge
// angle of 1-DOF joints. The page only draws ranges; the server enforces them.
// Quaternions here are arrays [w, x, y, z].

export function qmul(a, b) {
  return [
    a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
    a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
    a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
    a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
  ];
}
export const qconj = (q) => [q[0], -q[1], -q[2], -q[3]];

/** Rotates vector v by unit quaternion q. */
export function qrotate(q, v) {
  const r = qmul(qmul(q, [0, v[0], v[1], v[2]]), qconj(q));
  return [r[1], r[2], r[3]];
}

function wrapAngle(a) {
  while (a > Math.PI) a -= 2 * Math.PI;
  while (a <= -Math.PI) a += 2 * Math.PI;
  return a;
}

/** Swing–twist of a rotation given in range-frame coordinates (as core::swing_twist). */
export function swingTwist(q) {
  const c = Math.hypot(q[0], q[1]);
  if (c < 1e-9) {
    const n = Math.hypot(q[2], q[3]) || 1;
    return { ay: q[2] / n, az: q[3] / n, twist: 0, singular: true };
  }
  const ct = q[0] / c;
  const st = q[1] / c;
  return {
    ay: ct * q[2] - st * q[3],
    az: st * q[2] + ct * q[3],
    twist: wrapAngle(2 * Math.atan2(q[1], q[0])),
    singular: false,
  };
}

/** The swing quaternion of swing vector (ay, az). */
export function swingQuat(ay, az) {
  const s2 = ay * ay + az * az;
  return [Math.sqrt(Math.max(0, 1 - s2)), 0, ay, az];
}

/** Direction (range frame) of the nominal axis after swing (ay, az). */
export function swingDirection(ay, az) {
  return qrotate(swingQuat(ay, az), [1, 0, 0]);
}

/** Swing angle φ (rad) of a swing vector: |a| = sin(φ/2). */
export const swingAngle = (ay, az) => 2 * Math.asin(Math.min(1, Math.hypot(ay, az)));

function barycentric(p, a, b, c) {
  const v0x = b[0] - a[0], v0y = b[1] - a[1];
  const v1x = c[0] - a[0], v1y = c[1] - a[1];
  const v2x = p[0] - a[0], v2y = p[1] - a[1];
  const den = v0x * v1y - v1x * v0y;
  if (Math.abs(den) < 1e-300) return null;
  const v = (v2x * v1y - v1x * v2y) / den;
  const w = (v0x * v2y - v2x * v0y) / den;
  return [1 - v - w, v, w];
}

/**
 * The range test for a spherical joint with joint rotation qJoint ([w,x,y,z], joint frame):
 * {inside, swing: {ay, az, twist}, twistLower, twistUpper, violation (rad)}.
 */
export function checkSphericalRange(range, qJoint, tolerance = 1e-3) {
  const F = range.frame || [1, 0, 0, 0];
  const st = swingTwist(qmul(qmul(qconj(F), qJoint), F));
  const out = { inside: true, swing: st, twistLower: -Math.PI, twistUpper: Math.PI, violation: 0 };
  const V = range.vertices || [];
  const T = range.triangles || [];
  if (!T.length) return out;
  const p = [st.ay, st.az];
  let best = Infinity;
  for (const [i, j, k] of T) {
    const bc = barycentric(p, V[i], V[j], V[k]);
    if (!bc) continue;
    const m = Math.min(bc[0], bc[1], bc[2]);
    if (m >= -1e-9) {
      const lo = bc[0] * V[i][2] + bc[1] * V[j][2] + bc[2] * V[k][2];
      const hi = bc[0] * V[i][3] + bc[1] * V[j][3] + bc[2] * V[k][3];
      out.twistLower = lo;
      out.twistUpper = hi;
      // twist accepted modulo 2π
      let excess = Infinity;
      for (const t of [st.twist - 2 * Math.PI, st.twist, st.twist + 2 * Math.PI]) {
        excess = Math.min(excess, Math.max(0, lo - t, t - hi));
      }
      out.violation = excess;
      out.inside = excess <= tolerance;
      return out;
    }
    best = Math.min(best, -m);
  }
  // outside every triangle: distance to the union's boundary, in swing angle
  out.inside = false;
  out.violation = distanceOutside(p, V, T);
  if (out.violation <= tolerance * 0.5) out.inside = true;
  return out;
}

function distanceOutside(p, V, T) {
  let d = Infinity;
  for (const tri of T) {
    for (let e = 0; e < 3; e++) {
      const a = V[tri[e]], b = V[tri[(e + 1) % 3]];
      const abx = b[0] - a[0], aby = b[1] - a[1];
      const len2 = abx * abx + aby * aby || 1;
      const t = Math.max(0, Math.min(1, ((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / len2));
      d = Math.min(d, Math.hypot(p[0] - a[0] - t * abx, p[1] - a[1] - t * aby));
    }
  }
  return 2 * d; // |a| = sin(φ/2): near the rim a change of |a| by δ is about 2δ of swing angle
}

/** Edges of the range's outline: those used by exactly one triangle, as [i, j] pairs. */
export function boundaryEdges(range) {
  const count = new Map();
  for (const [i, j, k] of range.triangles || []) {
    for (const [a, b] of [[i, j], [j, k], [k, i]]) {
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      const c = count.get(key);
      count.set(key, c ? { n: c.n + 1, a: c.a, b: c.b } : { n: 1, a, b });
    }
  }
  return [...count.values()].filter((c) => c.n === 1).map((c) => [c.a, c.b]);
}

/** Hinge angle of a 1-DOF rotation qJoint about axis (joint frame). */
export function hingeAngle(qJoint, axis) {
  const s = qJoint[1] * axis[0] + qJoint[2] * axis[1] + qJoint[3] * axis[2];
  return wrapAngle(2 * Math.atan2(s, qJoint[0]));
}

/** Limit status of any joint: {kind: 'hinge'|'spherical'|null, inside, value, violation, ...}. */
export function jointLimitStatus(link, qJoint, tolerance = 1e-3) {
  if (!qJoint) return { kind: null, inside: true };
  if (link.joint_type === 'revolute' && link.limits && link.axis) {
    const angle = hingeAngle(qJoint, link.axis);
    const [lo, hi] = link.limits;
    const violation = Math.max(0, lo - angle, angle - hi);
    return { kind: 'hinge', inside: violation <= tolerance, angle, lower: lo, upper: hi, violation };
  }
  if (link.joint_type === 'spherical' && link.range && (link.range.triangles || []).length) {
    return { kind: 'spherical', ...checkSphericalRange(link.range, qJoint, tolerance) };
  }
  return { kind: null, inside: true };
}
