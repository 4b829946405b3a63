// fetchscope serve's page: the episode viewer (viewer.js: the step cursor, the plots, the keys)
// over a live view that the server renders with the renderer of the videos. The page asks its own
// server for everything (frames, episode data, live steps), with the session it opens first.
// Frames: one request in flight at a time; a view that changes meanwhile is sent when it returns,
// so stale frames are dropped, never queued. JPEG while the view moves, PNG (lossless) at rest.
// The state and the frame statistics are in window.fetchscopeServe (tests and bench read them).
'use strict';

(() => {
  performance.mark('fetchscope-serve-script');
  const {el} = FS;
  const {episodeBrowser, placementForm, lookControl, growLists, cutLists, cameraText, parseCamera, DEFAULT_FREE} = FSServeTools;
  // serve accepts a POST on the cookie only with this Content-Type (and this page's Origin, which
  // the browser sends): a form or a no-cors fetch on another site's page cannot send it
  const POST_HEADERS = {'Content-Type': 'application/json'};
  const sessionRequest = fetch('/api/session', {method: 'POST', credentials: 'same-origin', headers: POST_HEADERS});
  const data = FS.data;
  const page = document.getElementById('page');
  const OVERLAYS = ['goal', 'achieved', 'hud', 'action', 'trail', 'labels', 'hindsight', 'ghost', 'contacts'];
  // what a model camera shows that may surprise (docs/guide/serve.md)
  const CAMERA_NOTES = {
    gripper_camera_rgb: 'the table close up: at the reset it looks straight down from 10 cm above the untextured table, which fills it; lower the gripper near the block to see the block',
  };
  const KEYS = {w: [0, 1], s: [0, -1], a: [1, 1], d: [1, -1], r: [2, 1], f: [2, -1], o: [3, 1], c: [3, -1]};

  const state = {
    session: null,
    source: null, episode: null, t: 0,  // what is shown: a served episode, or source 'live'
    live: null,                         // the live episode's data
    episodeData: null,
    camera: data.view.camera, overlay: data.view.overlay, layer: 'rgb',
    width: data.view.width, height: data.view.height,
    free: null,      // the camera as numbers while orbiting (a free or track camera)
    moving: false,   // the view is being dragged: JPEG frames
    playing: false, stepSize: 1, key: 0,
    gripper: 0,      // the latched gripper command every move carries: +1 open, -1 closed, 0 none
    savedSteps: 0,   // the live steps the last save holds (a reload with more asks first)
    rows: null,      // the rows of the episode shown (the step inspector's)
    placePick: null, // set by a placement form: the next click on the view gives it its world point
    look: '',        // the look control: '' the episode's own, 'plain', or a draw's seed
  };
  const stats = {requested: 0, received: 0, dropped: 0, errors: 0, lastError: '', renderMs: [], encodeMs: [],
                 roundTripMs: [], times: [], lastCamera: '', lastFormat: '',
                 shown: []};  // {at: performance.now(), step, camera, format} of each frame on screen
  window.fetchscopeServe = {state, stats};

  // ---- requests

  async function api(path, params, method = 'GET') {
    const query = new URLSearchParams({session: state.session, ...params});
    const response = await fetch(`${path}?${query}`,
        {method, credentials: 'same-origin', headers: method === 'POST' ? POST_HEADERS : {}});
    const type = response.headers.get('Content-Type') || '';
    const body = type.startsWith('application/json') ? await response.json() : await response.blob();
    if (!response.ok) throw new Error(body.error || `HTTP ${response.status}`);
    return {body, response};
  }

  function showError(message) {
    status.textContent = message;
    status.className = 'serve-status error';
    stats.errors++;
    stats.lastError = message;
  }

  // ---- the live view

  const image = el('img', {class: 'serve-frame', alt: 'live view', draggable: 'false'});
  let lastTiming = '';
  image.addEventListener('load', () => {
    const w = image.naturalWidth, h = image.naturalHeight;
    const tiled = w !== state.width || h !== state.height;
    if (status.className === 'serve-status') {
      status.textContent = `${image.dataset.format.toUpperCase()} ${w}×${h}` +
          (tiled ? ` (tiled views of ${state.width}×${state.height} each; only a single camera orbits)` : '') +
          ` · ${lastTiming}`;
    }
    stats.shown.push({at: performance.now(), step: Number(image.dataset.step), camera: image.dataset.camera,
                      format: image.dataset.format});
    if (stats.shown.length === 1) performance.mark('fetchscope-serve-first-frame');
  });
  const status = el('p', {class: 'serve-status'}, 'starting…');
  const hover = el('p', {class: 'serve-hover'}, '');
  let inFlight = false, dirty = false, restTimer = null, lastUrl = null, inFlightKey = '', shownKey = '';

  function viewParams(format) {
    const at = state.source === 'live' ? {source: 'live', t: state.t}
                                       : {source: state.source, episode: state.episode, t: state.t};
    return {...at, camera: state.camera, overlay: state.overlay, layer: state.layer,
            width: state.width, height: state.height, format, quality: 80, ...(state.look ? {look: state.look} : {})};
  }

  // Asks for the frame of the current view; while one is on its way, only remembers to ask again.
  function requestFrame() {
    if (state.source === null || state.session === null) return;
    updateOverlayAvailability();
    requestOtherFrame();
    const format = state.moving || state.playing ? 'jpeg' : 'png';
    const params = viewParams(format);
    // a live step's frame is new whenever the live episode changed (a step back, then another)
    const key = JSON.stringify([params, state.source === 'live' ? liveVersion : 0]);
    if (!inFlight && key === shownKey) return;  // that very frame is on screen
    if (inFlight) {
      if (key !== inFlightKey) { dirty = true; stats.dropped++; }  // the latest view goes next
      return;
    }
    inFlight = true;
    inFlightKey = key;
    dirty = false;
    const started = performance.now();
    stats.requested++;
    api('/api/frame', params).then(({body, response}) => {
      if (lastUrl) URL.revokeObjectURL(lastUrl);
      lastUrl = URL.createObjectURL(body);
      shownKey = key;
      image.dataset.format = format;
      image.dataset.step = String(params.t);
      image.dataset.camera = response.headers.get('X-Fetchscope-Camera') || '';
      look.show(response.headers.get('X-Fetchscope-Look') || '');
      image.src = lastUrl;
      stats.received++;
      const now = performance.now();
      stats.times.push(now);
      stats.roundTripMs.push(now - started);
      const timing = response.headers.get('Server-Timing') || '';
      const ms = (name) => Number((new RegExp(`${name};dur=([0-9.]+)`).exec(timing) || [])[1]);
      stats.renderMs.push(ms('render'));
      stats.encodeMs.push(ms('encode'));
      stats.lastCamera = response.headers.get('X-Fetchscope-Camera') || '';
      stats.lastFormat = format;
      status.className = 'serve-status';
      // the frame's real size is the image's: said once it is decoded (a tiled view is wider)
      lastTiming = `render ${ms('render').toFixed(1)} ms · encode ${ms('encode').toFixed(1)} ms · ${(now - started).toFixed(0)} ms round trip`;
      status.textContent = `${format.toUpperCase()} · ${lastTiming}`;
    }).catch((e) => showError(e.message)).finally(() => {
      inFlight = false;
      if (dirty) requestFrame();
      else if (format === 'jpeg' && !state.moving && !state.playing) requestFrame();  // the view at rest: lossless
    });
  }

  function setCamera(text, {moving = false} = {}) {
    state.camera = text;
    state.moving = moving;
    cameraInput.value = text;
    cameraOption.textContent = `--camera '${text}'`;
    requestFrame();
  }

  // drag: orbit; shift-drag or right-drag: pan; wheel: zoom; double-click: track the body there
  let drag = null;
  image.addEventListener('contextmenu', (e) => e.preventDefault());
  image.addEventListener('pointerdown', (e) => {
    if (state.placePick) {  // a placement form asked for the point under this click
      e.preventDefault();
      const give = state.placePick;
      state.placePick = null;
      pickAt(e).then((p) => (p && p.point ? give(p.point) : showError('no surface under the pointer: click the table or a body')));
      return;
    }
    const source = data.sources[state.source === 'live' ? state.live.source : state.source];
    const free = parseCamera(state.camera, source);
    if (!free) { showError('only one camera orbits: this view tiles several (choose one, or a free camera, to drag it)'); return; }
    e.preventDefault();
    image.setPointerCapture(e.pointerId);
    drag = {x: e.clientX, y: e.clientY, free, pan: e.shiftKey || e.button === 2};
  });
  image.addEventListener('pointermove', (e) => {
    if (!drag) { pickLater(e); return; }
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    const f = drag.free;
    if (drag.pan && !f.track) {
      const az = f.azimuth * Math.PI / 180, el2 = f.elevation * Math.PI / 180;
      const right = [Math.sin(az), -Math.cos(az), 0];
      const up = [-Math.sin(el2) * Math.cos(az), -Math.sin(el2) * Math.sin(az), Math.cos(el2)];
      const k = f.distance * 0.0015;
      for (let i = 0; i < 3; i++) f.lookat[i] += k * (-dx * right[i] + dy * up[i]);
    } else {
      f.azimuth = ((f.azimuth - 0.35 * dx) % 360 + 540) % 360 - 180;
      f.elevation = Math.max(-89, Math.min(89, f.elevation - 0.35 * dy));
    }
    setCamera(cameraText(f), {moving: true});
  });
  const endDrag = () => {
    if (!drag) return;
    drag = null;
    state.moving = false;
    requestFrame();
  };
  image.addEventListener('pointerup', endDrag);
  image.addEventListener('pointercancel', endDrag);
  image.addEventListener('wheel', (e) => {
    const source = data.sources[state.source === 'live' ? state.live.source : state.source];
    const free = parseCamera(state.camera, source);
    if (!free) return;
    e.preventDefault();
    free.distance = Math.max(0.05, Math.min(20, free.distance * Math.exp(0.0015 * e.deltaY)));
    setCamera(cameraText(free), {moving: true});
    clearTimeout(restTimer);
    restTimer = setTimeout(() => { state.moving = false; requestFrame(); }, 250);
  }, {passive: false});
  image.addEventListener('dblclick', async (e) => {
    const picked = await pickAt(e);
    const source = data.sources[state.source === 'live' ? state.live.source : state.source];
    const free = parseCamera(state.camera, source) || {...DEFAULT_FREE};
    if (picked && picked.body && picked.body !== 'world') {
      setCamera(cameraText({...free, distance: Math.min(free.distance, 1.2), track: picked.body}));
    } else {
      delete free.track;
      setCamera(cameraText({...free, lookat: free.lookat || DEFAULT_FREE.lookat.slice()}));
    }
  });

  // hover: what the segmentation layer shows under the pointer
  let pickBusy = false, pickNext = null;
  function framePixel(e) {
    const box = image.getBoundingClientRect();
    const x = Math.floor((e.clientX - box.left) * state.width / box.width);
    const y = Math.floor((e.clientY - box.top) * state.height / box.height);
    return x >= 0 && y >= 0 && x < state.width && y < state.height ? {x, y} : null;
  }
  async function pickAt(e) {
    const p = framePixel(e);
    if (!p || state.source === null) return null;
    const params = viewParams('png');
    delete params.format;
    delete params.quality;
    try {
      const {body} = await api('/api/pick', {...params, x: p.x, y: p.y});
      return body;
    } catch (error) {
      showError(error.message);
      return null;
    }
  }
  function pickLater(e) {
    pickNext = e;
    if (pickBusy) return;
    pickBusy = true;
    const next = pickNext;
    pickNext = null;
    const xyz = (v) => `(${v.map((c) => c.toFixed(3)).join(', ')}) m`;
    pickAt(next).then((p) => {
      hover.textContent = !p ? '' : p.body ? `body ${p.body}` + (p.geom ? ` · geom ${p.geom}` : '') + (p.site ? ` · site ${p.site}` : '') +
                                             (p.point ? ` · point ${xyz(p.point)}` : '') + (p.body_pos ? ` · body at ${xyz(p.body_pos)}` : '')
                                           : 'nothing (background)';
      hover.dataset.point = p && p.point ? JSON.stringify(p.point) : '';
      hover.dataset.at = p ? `${p.x},${p.y}` : '';  // the frame pixel the text is about
      hover.dataset.body = p && p.body ? p.body : '';
    }).finally(() => {
      pickBusy = false;
      if (pickNext) pickLater(pickNext);
    });
  }

  // ---- controls of the view

  const cameraInput = el('input', {type: 'text', class: 'serve-camera', spellcheck: 'false', 'aria-label': 'camera'});
  const cameraOption = el('code', {class: 'serve-camera-option'});
  cameraInput.addEventListener('change', () => setCamera(cameraInput.value.trim()));
  const copyButton = el('button', {type: 'button', onclick: () => navigator.clipboard && navigator.clipboard.writeText(`--camera '${state.camera}'`)}, 'copy');
  const presets = el('select', {'aria-label': 'camera presets'});
  presets.addEventListener('change', () => { if (presets.value) setCamera(presets.value); presets.value = ''; });
  function fillPresets(source) {
    presets.replaceChildren(el('option', {value: ''}, 'camera presets…'), el('option', {value: 'default'}, 'default'),
        el('option', {value: 'track'}, 'track (the gripper)'),
        ...(source.cameras || []).map((c) => el('option', {value: c.name, title: CAMERA_NOTES[c.name] || ''},
            CAMERA_NOTES[c.name] ? `${c.name} (${CAMERA_NOTES[c.name].split(':')[0]})` : c.name)));
  }
  const overlayBoxes = OVERLAYS.map((name) => {
    const box = el('input', {type: 'checkbox', value: name});
    box.addEventListener('change', () => {
      state.overlay = OVERLAYS.filter((n, i) => overlayBoxes[i].checked).join(',') || 'none';
      requestFrame();
    });
    return box;
  });
  // an overlay that cannot apply to what is shown is disabled, its reason in its tooltip
  const viewCount = (text) => (String(text).match(/(^|,)\s*(default|track|free:|[A-Za-z_][A-Za-z0-9_]*(?=\s*(,|$)))/g) || []).length;
  function overlayReasons() {
    const kind = state.source === 'live' ? 'live' : state.source === null ? null : data.sources[state.source].kind;
    return {
      labels: viewCount(state.camera) < 2 ? 'labels name the cameras of a tiled view: this view has one camera' : '',
      ghost: kind !== 'dataset' ? 'ghost shows a dataset\'s own achieved goal: this is not a dataset episode' : '',
      hindsight: kind !== 'recording' ? 'hindsight shows the goals HER relabels a recorded episode with: this is not a recording' : '',
    };
  }
  function updateOverlayAvailability() {
    const reasons = overlayReasons();
    OVERLAYS.forEach((name, i) => {
      const why = reasons[name] || '';
      overlayBoxes[i].disabled = !!why;
      overlayBoxes[i].parentElement && (overlayBoxes[i].parentElement.title = why);
      overlayBoxes[i].dataset.reason = why;
    });
  }
  function syncOverlayBoxes() {
    const on = state.overlay === 'default' ? ['goal', 'achieved', 'hud', 'labels', 'ghost']
             : state.overlay === 'all' ? OVERLAYS : state.overlay.split(',').map((s) => s.trim());
    OVERLAYS.forEach((name, i) => { overlayBoxes[i].checked = on.includes(name); });
  }
  const look = lookControl((value) => { state.look = value; requestFrame(); });
  const layerSelect = el('select', {'aria-label': 'layer'}, ...['rgb', 'depth', 'segmentation'].map((l) => el('option', {value: l}, l)));
  layerSelect.addEventListener('change', () => { state.layer = layerSelect.value; requestFrame(); });
  const sizeSelect = el('select', {'aria-label': 'size'},
      ...['480x480', '640x480', '960x720', '1280x720'].map((s) => el('option', {value: s}, s.replace('x', '×'))));
  sizeSelect.addEventListener('change', () => {
    [state.width, state.height] = sizeSelect.value.split('x').map(Number);
    requestFrame();
  });

  // ---- live: keys, the policy, back, save

  const liveBox = el('div', {class: 'serve-live'});
  const liveInfo = el('p', {class: 'caption'});
  const saveOut = el('div', {class: 'serve-save'});
  const stepSize = el('select', {'aria-label': 'step size', title: 'the size of each move: |a[i]| of a key press (0.05 m per unit)'},
      ...['1', '0.5', '0.25', '0.1', '0.05'].map((v) => el('option', {value: v}, `|a| = ${v}`)));
  const gripperState = el('span', {class: 'serve-gripper', 'data-command': '0'}, 'gripper: not commanded');
  const pastLimit = el('input', {type: 'checkbox', class: 'serve-past-limit'});
  stepSize.addEventListener('change', () => { state.stepSize = Number(stepSize.value); });
  const continueButton = el('button', {type: 'button', class: 'serve-continue', onclick: () => startLive({from: true})}, 'continue live from this step');
  const policyButton = el('button', {type: 'button', class: 'serve-policy', onclick: () => liveStep(null)}, `step the policy (${data.policy}) [p]`);
  const playPolicy = el('button', {type: 'button', class: 'serve-play-policy', onclick: () => togglePolicyPlay()}, 'play the policy');
  const backButton = el('button', {type: 'button', class: 'serve-back', onclick: () => liveBack()}, 'step back [b]');
  const saveButton = el('button', {type: 'button', class: 'serve-save-button', onclick: () => save()}, 'save');
  const keyButtons = Object.entries(KEYS).map(([key, [axis, sign]]) => el('button', {type: 'button', 'data-key': key,
      title: axis < 3 ? `a[${axis}] = ${sign > 0 ? '+' : '−'}step (key ${key}; hold two keys for two axes at once)`
                      : `${sign > 0 ? 'open' : 'close'} the gripper and keep it so: every move then carries a[3] = ${sign > 0 ? '+1' : '−1'} (key ${key})`,
      onclick: () => keyStep(key)},
      axis < 3 ? `${['x', 'y', 'z'][axis]}${sign > 0 ? '+' : '−'} [${key}]` : `${sign > 0 ? 'open' : 'close'} [${key}]`));
  liveBox.append(el('h3', {}, 'Live'), liveInfo,
      el('div', {class: 'serve-row'}, continueButton, stepSize, ...keyButtons),
      el('div', {class: 'serve-row'}, gripperState),
      el('div', {class: 'serve-row'}, policyButton, playPolicy, el('label', {title: 'play stops at the env\'s TimeLimit (50 steps) unless this is ticked'}, pastLimit, 'go past the TimeLimit'),
         backButton, saveButton),
      el('p', {class: 'caption'}, 'Keys (each one env step): w/s ±x, a/d ±y, r/f ±z (hold two for two axes at once), o opens and c closes the gripper ' +
        'and keeps it so (every move carries the command, so a grasp holds while you lift); ' +
        'p steps the policy, b steps back. Drag to orbit, shift- or right-drag to pan, wheel to zoom, double-click a body to track it.'),
      saveOut);

  // one live call at a time: a key pressed while a step is on its way is dropped (the next press
  // counts), while a save or a pause waits for it (whenLiveIdle) rather than being lost
  let busy = null, liveVersion = 0;
  async function liveCall(path, params, {wait = false, method = 'POST'} = {}) {
    if (busy && !wait) return null;
    while (busy) await busy.catch(() => {});
    const call = api(path, params, method);
    busy = call;
    try {
      const {body} = await call;
      return body;
    } catch (e) {
      showError(e.message);
      return null;
    } finally {
      if (busy === call) busy = null;
    }
  }

  // the answers: start gives the whole live episode; a step only the new step, a step back only
  // the new count (constant size however long the episode): the page keeps the rest here
  async function mergeLive(answer) {
    const live = state.live;
    const {step, ...head} = answer;
    if (!live || live.source !== head.source || live.episode !== head.episode ||
        (step ? head.steps !== live.steps + 1 : head.steps > live.steps)) {
      return liveCall('/api/live', {}, {wait: true, method: 'GET'});  // out of step: the whole
    }
    if (step) {
      live.rows.push(step.row);
      growLists(live.signals, step.signals);
    } else {
      live.rows.length = head.steps + 1;
      cutLists(live.signals, head.steps + 1);
    }
    live.signals.frames = head.steps + 1;
    return Object.assign(live, head);
  }

  function showLive(live) {
    liveVersion += 1;
    state.live = live;
    state.source = 'live';
    state.t = live.steps;
    state.rows = live.rows;
    requestFrame();  // the new step's frame first; the plots are rebuilt while it renders
    liveInfo.textContent = `live episode: ${data.sources[live.source].title}, episode ${live.episode}, ` +
        (live.prefix ? `continued from step ${live.prefix}, ` : '') + (live.placed ? 'reset placed, ' : '') +
        `${live.steps} steps, actions ${live.action_dtype}`;
    liveBox.dataset.steps = String(live.steps);
    showInspector();
    // the plots once the new step's frame is on screen (unless another step came meanwhile)
    frameShown().then(() => {
      if (state.live !== live || Number(liveBox.dataset.steps) !== live.steps) return;
      openInViewer({key: 'live', title: `live: ${data.sources[live.source].env_id} episode ${live.episode}`,
                    signals: live.signals, spec: data.sources[live.source]}, live.steps);
    });
  }

  async function startLive({from = false, env = null, place = {}} = {}) {
    const params = from ? {source: state.source, episode: state.episode, t: state.t} : {env, ...place};
    if (from && (state.source === null || state.source === 'live')) return;
    const live = await liveCall('/api/live/start', params);
    if (live) {
      state.savedSteps = 0;
      showLive(live);
      if (!from && placeForms[env]) placeForms[env].fill(live.rows[0]);
    }
  }
  async function liveStep(action, {wait = false} = {}) {
    if (!state.live) { showError('no live episode: start one (a live env, or "continue live from this step")'); return null; }
    const answer = await liveCall('/api/live/step', action ? {action: action.join(',')} : {}, {wait});
    const live = answer && await mergeLive(answer);
    if (live) showLive(live);
    return live;
  }
  // the move keys held down now: a chord (w and a together) moves along both axes in one step,
  // and every move carries the latched gripper command. A key's step waits CHORD_MS for the
  // other keys of a chord, so that pressing two at once is one step, not one and then another
  const keysDown = new Set(), keysPressed = new Set();
  const CHORD_MS = 50;
  let chordTimer = null;
  function chordKey(key) {
    keysDown.add(key);
    keysPressed.add(key);
    if (chordTimer) return;
    chordTimer = setTimeout(() => {
      chordTimer = null;
      const pressed = [...keysPressed];
      keysPressed.clear();
      liveStep(moveAction(pressed));
    }, CHORD_MS);
  }
  function moveAction(pressed) {
    const action = [0, 0, 0, state.gripper];
    for (const key of new Set([...keysDown, ...pressed])) {
      const [axis, sign] = KEYS[key];
      if (axis < 3) action[axis] = sign * state.stepSize;
    }
    return action;
  }
  function keyStep(key) {
    const [axis, sign] = KEYS[key];
    if (axis === 3) {  // o, c: latch the gripper open or closed (a[3] = ±1 from now on)
      setGripper(sign);
      return liveStep(moveAction([]));
    }
    return liveStep(moveAction([key]));
  }
  function setGripper(command) {
    state.gripper = command;
    gripperState.textContent = command > 0 ? 'gripper: open (latched)' : command < 0 ? 'gripper: closed (latched)' : 'gripper: not commanded';
    gripperState.dataset.command = String(command);
  }
  async function liveBack() {
    const answer = await liveCall('/api/live/back', {});
    const live = answer && await mergeLive(answer);
    if (live) showLive(live);
  }
  // play: one policy step after another until paused, the policy fails, or the TimeLimit. A
  // pause lets the step on its way land, then stops: "playing" ends only when no step can follow
  let policyPlaying = false, policyLoop = null;
  function setPolicyPlaying(on) {
    policyPlaying = on;
    playPolicy.textContent = on ? 'pause the policy' : 'play the policy';
    playPolicy.dataset.playing = String(on);
  }
  async function playLoop() {
    const limit = data.sources[state.live.source].max_episode_steps;
    while (policyPlaying) {
      if (state.live.steps >= limit && !pastLimit.checked) {
        showError(`stopped at the TimeLimit (${limit} steps): tick "go past the TimeLimit" to play on`);
        break;
      }
      const live = await liveStep(null, {wait: true});  // after a save on its way, not instead
      if (!live) break;
      await new Promise((done) => setTimeout(done, 40));
    }
  }
  async function togglePolicyPlay() {
    if (policyLoop) {  // pause: no step starts after the one on its way
      policyPlaying = false;
      playPolicy.textContent = 'pausing…';
      return;
    }
    if (!state.live) { showError('no live episode: start one first'); return; }
    setPolicyPlaying(true);
    policyLoop = playLoop();
    await policyLoop;
    policyLoop = null;
    setPolicyPlaying(false);
  }
  async function save() {
    const params = {camera: state.camera, overlay: state.overlay, width: state.width, height: state.height};
    const out = await liveCall('/api/live/save', params, {wait: true});  // after a step on its way
    if (!out) return;
    state.savedSteps = out.steps;
    saveOut.replaceChildren(el('p', {}, 'saved ', ...out.files.map((f) => el('code', {}, f + ' '))),
        out.command ? el('pre', {class: 'serve-command'}, out.command)
                    : el('p', {class: 'caption'}, out.why_no_command),
        out.command ? el('button', {type: 'button', onclick: () => navigator.clipboard && navigator.clipboard.writeText(out.command)}, 'copy the command') : null);
    saveOut.dataset.command = out.command || '';
    saveOut.dataset.episodeFile = out.episode_file || '';
    saveOut.dataset.files = JSON.stringify(out.files);
    saveOut.dataset.steps = String(out.steps);
  }

  // resolves once the frame on its way is on screen (at once when none is)
  function frameShown() {
    if (!inFlight) return Promise.resolve();
    return new Promise((done) => {
      const finish = () => { image.removeEventListener('load', finish); done(); };
      image.addEventListener('load', finish);
      setTimeout(finish, 2000);  // a frame that failed: draw the plots anyway
    });
  }

  // ---- the step inspector and side by side (serve_tools.js)

  const sideBySide = FSServeTools.sideBySide({data, state, api, viewParams: (f) => viewParams(f), showError: (m) => showError(m)});
  const {box: otherBox, select: otherSelect, fill: fillOtherSelect, requestFrame: requestOtherFrame} = sideBySide;
  const {element: inspector, show: showInspector} = FSServeTools.inspector({data, state, after: () => sideBySide.showDifference()});

  // ---- the viewer (viewer.js): one episode at a time, served or live

  let viewer = null, viewerKey = 0, shown = null;
  function openInViewer(item, t) {
    const same = shown && shown.key === item.key;
    shown = item;
    if (!viewer || !same) {
      if (viewer) viewer.element.remove();
      viewerKey += 1;
      viewer = FSViewer.create(viewerBox, {
        id: 'viewer', fps: 25, threshold: item.spec.threshold, has_object: item.spec.has_object,
        gripper_command: item.signals && !!item.signals.gripper_command, layout: {},
        episodes: [{index: viewerKey, label: String(viewerKey), title: item.title, tracks: () => [{name: item.title, signals: shown.signals, noMedia: true}]}],
        visible: () => [viewerKey], noLink: true, keysAnywhere: true,
        onStep: (episode, step) => { if (step !== state.t) { state.t = step; requestFrame(); showInspector(); } },
        play: () => togglePlay(), isPlaying: () => state.playing,
      });
      window.fetchscopeServe.viewer = viewer;
      viewer.open(viewerKey, t);
    } else {
      viewer.refresh(t);
    }
    state.t = t;
    requestFrame();
  }

  let playTimer = null;
  function togglePlay() {
    if (state.playing) { state.playing = false; clearTimeout(playTimer); requestFrame(); return; }
    state.playing = true;
    const tick = () => {
      if (!state.playing) return;
      if (viewer.step >= viewer.steps) { state.playing = false; requestFrame(); viewer.seek(viewer.steps); return; }
      viewer.seek(viewer.step + 1);
      playTimer = setTimeout(tick, 40);
    };
    tick();
  }

  async function openEpisode(source, episode, t = 0) {
    state.source = source;
    state.episode = episode;
    status.textContent = `replaying episode ${episode}…`;
    try {
      // the frame first (it replays the episode on the server when it is new), then its data;
      // the plots are drawn once the frame is on screen
      state.t = t;
      requestFrame();
      const {body} = await api('/api/episode', {source, episode});
      state.episodeData = body;
      state.rows = body.rows;
      showInspector();
      if (t > body.steps) {
        state.t = body.steps;
        requestFrame();
      }
      await frameShown();
      const s = data.sources[source];
      const replay = body.replay || {};
      const drift = replay.divergence ? ` · replay ${replay.reset}, ${replay.divergence.first_step === null ? 'no divergence' : 'diverges at step ' + replay.divergence.first_step}` : ' · replayed exactly';
      openInViewer({key: `${source}/${episode}`, title: `${s.env_id} · episode ${episode}${drift}`, signals: body.signals, spec: s}, Math.min(t, body.steps));
      fillPresets(s);
    } catch (e) {
      showError(e.message);
    }
  }

  // ---- the sources

  const sourcesBox = el('div', {class: 'serve-sources'});
  const listings = [];  // the episode tables, drawn after the first frame
  const placeForms = {};  // a live env's placement form, by source
  data.sources.forEach((s, i) => {
    const box = el('details', {class: 'serve-source', open: true}, el('summary', {}, s.title));
    if (s.kind === 'live') {
      const place = placeForms[i] = placementForm({source: s, index: i, start: ({env, ...at}) => startLive({env, place: at}),
                                                   armPick: (give) => { state.placePick = give; }});
      box.append(el('button', {type: 'button', class: 'serve-start-env', 'data-source': i, onclick: () => startLive({env: i})},
          `start ${s.env_id} (seed ${s.seed}) live`), place.element);
    } else {
      // the table is drawn once the first frame is on screen: a run of a thousand episodes makes
      // a thousand rows, which would hold the first frame back; the columns that need each
      // episode's rows (distance, first success, the object, grasp and drop) come after
      const rows = s.episodes.map((e) => ({...e, source: i}));
      const waiting = el('p', {class: 'caption'}, `${rows.length} episodes`);
      box.append(waiting);
      listings.push(() => {
        const browser = episodeBrowser(i, rows, showError, (episode) => openEpisode(i, episode));
        waiting.replaceWith(browser.element);
        api('/api/listing', {source: i}).then(({body}) => browser.addColumns(body.episodes))
            .catch((e) => showError(e.message));
      });
    }
    sourcesBox.append(box);
  });

  // ---- the page

  const viewerBox = el('div', {class: 'serve-viewer'});
  const overlayRow = el('div', {class: 'serve-row'}, 'overlays: ',
      ...OVERLAYS.map((name, i) => el('label', {}, overlayBoxes[i], name)));
  page.append(
      el('header', {}, el('h1', {}, 'fetchscope serve'),
         el('p', {class: 'caption'}, `rendered on the server by ${data.gl.renderer} (${data.gl.backend}) with the renderer of the videos`)),
      el('div', {class: 'serve-main'},
         el('div', {class: 'serve-view'}, image, status, hover, otherBox,
            el('div', {class: 'serve-row'}, 'camera ', cameraInput, copyButton, presets),
            el('p', {class: 'caption'}, 'as an option of render and record: ', cameraOption),
            overlayRow,
            el('div', {class: 'serve-row'}, 'layer ', layerSelect, ' size ', sizeSelect, ' ', otherSelect),
            el('div', {class: 'serve-row'}, look.element),
            liveBox),
         el('div', {class: 'serve-side'}, el('h3', {}, 'Served'), sourcesBox, inspector)),
      viewerBox);
  cameraInput.value = state.camera;
  cameraOption.textContent = `--camera '${state.camera}'`;
  sizeSelect.value = `${state.width}x${state.height}`;
  if (sizeSelect.value !== `${state.width}x${state.height}`) {
    sizeSelect.append(el('option', {value: `${state.width}x${state.height}`}, `${state.width}×${state.height}`));
    sizeSelect.value = `${state.width}x${state.height}`;
  }
  syncOverlayBoxes();
  fillPresets(data.sources[0]);
  fillOtherSelect();
  performance.mark('fetchscope-serve-built');

  document.addEventListener('keyup', (e) => keysDown.delete(e.key));
  window.addEventListener('blur', () => keysDown.clear());
  document.addEventListener('keydown', (e) => {
    if (e.altKey || e.ctrlKey || e.metaKey) return;
    const target = e.target;
    if (target && /^(INPUT|TEXTAREA|SELECT)$/.test(target.tagName)) return;
    if (KEYS[e.key]) {
      e.preventDefault();
      if (KEYS[e.key][0] < 3) chordKey(e.key);
      else keyStep(e.key);
      return;
    }
    if (e.key === 'p') { e.preventDefault(); liveStep(null); return; }
    if (e.key === 'b' || e.key === 'Backspace') { e.preventDefault(); liveBack(); return; }
    if (e.key === 'ArrowUp' || e.key === 'ArrowDown') {  // the previous or next episode of the source
      if (typeof state.source !== 'number') return;
      const list = data.sources[state.source].episodes.map((x) => x.index);
      const i = list.indexOf(state.episode) + (e.key === 'ArrowDown' ? 1 : -1);
      if (i >= 0 && i < list.length) openEpisode(state.source, list[i]);
    }
  });

  // a closed page frees its session (and its exec: child) at once; a reload or close with live
  // steps not saved asks first
  window.addEventListener('pagehide', () => {
    if (!state.session) return;
    fetch(`/api/session/close?session=${state.session}`,
          {method: 'POST', keepalive: true, credentials: 'same-origin', headers: POST_HEADERS}).catch(() => {});
  });
  window.addEventListener('beforeunload', (e) => {
    if (state.live && state.live.steps > state.savedSteps) {
      e.preventDefault();
      e.returnValue = '';  // the browser asks: "Leave site? Changes you made may not be saved."
    }
  });

  // the session (asked for before the page is built), then the first thing to show: the first
  // served episode, else the live env
  sessionRequest.then((r) => r.json()).then((body) => {
    if (!body.session) throw new Error(body.error || 'no session');
    state.session = body.session;
    document.body.dataset.session = body.session;
    const first = data.sources.findIndex((s) => s.kind !== 'live');
    if (first >= 0) openEpisode(first, data.sources[first].episodes[0].index);
    else startLive({env: 0});
    return frameShown();
  }).then(() => {
    setTimeout(() => {
      listings.forEach((list) => list());
      performance.mark('fetchscope-serve-listed');
    });
  }).catch((e) => showError(e.message));
})();
