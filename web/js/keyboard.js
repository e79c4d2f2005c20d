// Keyboard shortcuts (Blender / three.js editor habits): Space play, Ctrl+Z / Ctrl+Shift+Z undo and
// redo, P pin, I key, arrows step, W/E gizmo mode, F focus, Esc cancels a drag. Keys typed into
// form fields are left alone.

export function bindKeyboard(state, actions, drag, viewport, skeleton) {
  const { signals } = state;
  const toggleView = (key) => {
    state.view[key] = !state.view[key];
    signals.viewOptionsChanged.dispatch({ ...state.view });
  };

  // F centres the selected link, or frames the whole figure when nothing is selected
  signals.focusRequested.add((i) => {
    const w = i >= 0 ? skeleton.linkWorld(i) : null;
    if (w) viewport.focus(w.position.clone());
    else viewport.home();
  });

  window.addEventListener('keydown', (e) => {
    const t = e.target;
    if (t && (t.tagName === 'INPUT' || t.tagName === 'SELECT' || t.tagName === 'TEXTAREA' || t.isContentEditable)) {
      if (e.key === 'Escape') t.blur();
      return;
    }
    const ctrl = e.ctrlKey || e.metaKey;
    const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    let handled = true;
    if (ctrl && key === 'z') {
      if (e.shiftKey) actions.redo();
      else actions.undo();
    } else if (ctrl && key === 'y') {
      actions.redo();
    } else if (ctrl || e.altKey) {
      handled = false;
    } else {
      switch (key) {
        case ' ':
          actions.playPause();
          break;
        case 'p': {
          const i = state.hover >= 0 ? state.hover : state.selected;
          if (i >= 0) actions.togglePin(i);
          break;
        }
        case 'i':
          actions.insertKey();
          break;
        case 'Delete':
        case 'Backspace':
          actions.deleteKey();
          break;
        case 'ArrowLeft':
          actions.step(-1);
          break;
        case 'ArrowRight':
          actions.step(1);
          break;
        case 'Home':
          actions.first();
          break;
        case 'End':
          actions.last();
          break;
        case 'r':
          actions.toggleRecord();
          break;
        case 'w':
          signals.gizmoModeChanged.dispatch('translate');
          break;
        case 'e':
          signals.gizmoModeChanged.dispatch('rotate');
          break;
        case 'f':
          if (e.shiftKey) viewport.home();
          else signals.focusRequested.dispatch(state.selected);
          break;
        case 'h':
          toggleView('handles');
          break;
        case 'l':
          toggleView('limits');
          break;
        case '?':
          signals.helpToggled.dispatch();
          break;
        case 'Escape':
          if (drag.active) drag.cancel();
          else if (state.selected >= 0) signals.selectionChanged.dispatch(-1);
          signals.helpToggled.dispatch(false);
          break;
        default:
          handled = false;
      }
    }
    if (handled) e.preventDefault();
  });
}
