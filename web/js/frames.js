// Frames of the timeline: the clip's frame time (30 per second without a clip) and the time a key
// lands on, the nearest frame (the one the time display shows) unless snapping is off.

export function frameTimeOf(state) {
  return state.session?.clip?.frame_time || 1 / 30;
}

export function keyTime(state, t) {
  if (!state.view.snapKeys) return t;
  const frameTime = frameTimeOf(state);
  return Math.round(t / frameTime) * frameTime;
}
