// The episode viewer: an episode's video and its per-step signals (computed by fetchscope, see
// inspect/viewer.h) on one step cursor. Step t shows frame t of the video (t = 0: the reset
// frame), reached by seeking to the middle of that frame, (t + 0.5) / fps; the cursor follows
// playback. Clicking or dragging on a plot seeks; ←/→ step, space plays/pauses, Home/End jump,
// ↑/↓ go to the previous/next episode. The state is in the DOM (data-episode, data-step,
// data-steps on the viewer element; the video's currentTime) and in window.fetchscopeViewer.
// Each episode's signals are parsed from its JSON element only when its view opens.
'use strict';

const FSViewer = (() => {
  const {el} = FS;
  const axisColors = ['#d62728', '#2ca02c', '#1f77b4', '#9467bd'];  // x, y, z, gripper
  const trackDash = [null, [4, 3]];  // run A solid, run B dashed (compare)

  const parsed = new Map();  // element id -> parsed JSON
  function episodeSignals(id) {
    if (!parsed.has(id)) {
      const node = document.getElementById(id);
      parsed.set(id, node ? JSON.parse(node.textContent) : null);
    }
    return parsed.get(id);
  }

  const fmt = (v, digits) => (v === null || v === undefined ? '—' : Number(v).toFixed(digits));
  const at = (list, t) => (list && t < list.length ? list[t] : null);

  // The plots of one view, from the tracks' signals (any may be null). Each: id, title, y label,
  // series [{label, stroke, dash, values, scale}], readout(t) text.
  function plotSpecs(tracks, options) {
    const specs = [];
    const named = (track, label) => (tracks.length > 1 ? `${track.name} ${label}` : label);
    const each = (fn) => tracks.flatMap((track, i) => (track.signals ? fn(track, track.signals, i) : []));
    const readouts = (fn) => (t) => tracks.filter((tr) => tr.signals)
        .map((tr) => (tracks.length > 1 ? tr.name + ': ' : '') + fn(tr.signals, t)).join(' · ');
    specs.push({id: 'distance', title: 'Distance to goal', unit: 'm',
      series: [...each((tr, s, i) => [{label: named(tr, 'distance'), stroke: FS.colors.accent, dash: trackDash[i], values: s.distance}]),
               {label: 'threshold', stroke: FS.colors.threshold, dash: [6, 4], values: 'threshold'}],
      readout: readouts((s, t) => `${fmt(at(s.distance, t), 4)} m (threshold ${options.threshold} m)`)});
    specs.push({id: 'reward', title: 'Reward', unit: '',
      series: each((tr, s, i) => [{label: named(tr, 'reward'), stroke: '#e08214', dash: trackDash[i], values: s.reward, points: true}]),
      readout: readouts((s, t) => fmt(at(s.reward, t), 4))});
    specs.push({id: 'action', title: 'Action a[0:4] as the policy gave it', unit: '',
      series: each((tr, s, i) => ['x', 'y', 'z', 'gripper'].map((n, j) =>
        ({label: named(tr, `a[${j}] ${n}`), stroke: axisColors[j], dash: trackDash[i], values: s.action[j]}))),
      readout: readouts((s, t) => '(' + s.action.map((a) => fmt(at(a, t), 3)).join(', ') + ')')});
    ['x', 'y', 'z'].forEach((axis, j) => specs.push({
      id: `displacement-${axis}`, unit: 'm',
      title: `Gripper displacement along ${axis}: commanded (0.05 m × clipped a[${j}], dashed) vs achieved (grip_pos[t] − grip_pos[t−1])`,
      series: each((tr, s, i) => [
        {label: named(tr, `commanded ${axis}`), stroke: axisColors[j], dash: [5, 4], width: 1.25, values: s.commanded[j]},
        {label: named(tr, `achieved ${axis}`), stroke: i ? '#333' : '#111', dash: trackDash[i], width: 2, values: s.achieved[j]}]),
      readout: readouts((s, t) => `commanded ${fmt(at(s.commanded[j], t), 4)} m, achieved ${fmt(at(s.achieved[j], t), 4)} m`)}));
    // where the plotted values are in the observation: the report's data says (src/observation_layout.h)
    const layout = options.layout || {};
    const where = (text) => (text ? ` (${text})` : '');
    specs.push({id: 'fingers', unit: 'm',
      title: `Finger width${where(layout.finger_width)}` + (options.gripper_command ? ' and gripper command (clipped a[3], right axis)' : ''),
      series: each((tr, s, i) => [
        {label: named(tr, 'finger width'), stroke: '#8c510a', dash: trackDash[i], values: s.finger_width},
        ...(s.gripper_command ? [{label: named(tr, 'gripper command'), stroke: axisColors[3], dash: [5, 4], values: s.gripper_command, scale: 'cmd'}] : [])]),
      readout: readouts((s, t) => `width ${fmt(at(s.finger_width, t), 4)} m` +
        (s.gripper_command ? `, command ${fmt(at(s.gripper_command, t), 3)}` : ''))});
    if (options.has_object) {
      specs.push({id: 'object', title: `Object height${where(layout.object_height)} and object–goal distance`, unit: 'm',
        series: each((tr, s, i) => [
          {label: named(tr, 'object height'), stroke: '#35978f', dash: trackDash[i], values: s.object_height},
          {label: named(tr, 'object–goal distance'), stroke: '#c51b7d', dash: trackDash[i], values: s.object_goal_distance}]),
        readout: readouts((s, t) => `height ${fmt(at(s.object_height, t), 4)} m, to goal ${fmt(at(s.object_goal_distance, t), 4)} m`)});
    }
    if (tracks.some((tr) => tr.signals && tr.signals.contacts)) {  // --signals contacts
      const first = tracks.find((tr) => tr.signals && tr.signals.contacts).signals.contacts;
      specs.push({id: 'contacts', unit: 'N',
        title: 'Finger forces on the object (normal, N); shaded where both fingers press it (grasped)',
        band: first.grasped, bandColor: 'rgba(255, 26, 191, 0.12)',
        series: each((tr, s, i) => (s.contacts ? [
          {label: named(tr, 'left finger'), stroke: s.contacts.colors['finger-object'], dash: trackDash[i], values: s.contacts.left_finger_force},
          {label: named(tr, 'right finger'), stroke: '#7a0a5c', dash: trackDash[i] || [5, 3], values: s.contacts.right_finger_force}] : [])),
        readout: readouts((s, t) => (s.contacts ? `left ${fmt(at(s.contacts.left_finger_force, t), 1)} N, right ${fmt(at(s.contacts.right_finger_force, t), 1)} N` +
          (at(s.contacts.grasped, t) ? ', grasped' : '') + (at(s.contacts.object_on_table, t) ? ', object on the table' : '') : '—'))});
    }
    if (tracks.some((tr) => tr.signals && tr.signals.replay_error)) {  // record --from DATASET
      specs.push({id: 'replay', title: 'Replayed vs recorded: how far the replay is from the dataset (the ghost)', unit: 'mm',
        series: each((tr, s, i) => (s.replay_error ? [
          {label: named(tr, 'gripper error'), stroke: '#111', dash: trackDash[i], values: s.replay_error.gripper},
          ...(s.replay_error.object ? [{label: named(tr, 'object error'), stroke: '#35978f', dash: trackDash[i], values: s.replay_error.object}] : [])] : [])),
        readout: readouts((s, t) => (s.replay_error ? `gripper ${fmt(at(s.replay_error.gripper, t), 3)} mm` +
          (s.replay_error.object ? `, object ${fmt(at(s.replay_error.object, t), 3)} mm` : '') : '—'))});
    }
    if (tracks.some((tr) => tr.signals && tr.signals.her)) {
      specs.push({id: 'her', title: 'HER relabelled rewards (future, k = 4) of the transition into step t', unit: '',
        series: each((tr, s, i) => (s.her ? s.her.rewards.map((r, j) =>
          ({label: named(tr, `goal ${j + 1}`), stroke: ['#542788', '#8073ac', '#b2abd2', '#2d004b'][j], dash: trackDash[i], values: r, points: true})) : [])),
        readout: readouts((s, t) => (s.her ? `${at(s.her.successes, t) ?? '—'} of ${s.her.k} relabelled goals succeed` : '—'))});
    }
    return specs;
  }

  // One viewer in `parent`. options: {id, fps, threshold, has_object, gripper_command,
  // onStep(episode, t) (called whenever the cursor moves), noLink (no "link to this moment"),
  // keysAnywhere (its keys act wherever the page is scrolled: a page that is all viewer), play() and isPlaying() (a page that plays
  // the steps itself, without videos: serve),
  // layout: {finger_width, object_height} (the observation indices the titles name), legend (an
  // element under the videos: the markers the frames show),
  // episodes: [{index, label, title, tracks: () => [{name, caption, video, format, image, signals, frames,
  // noMedia (signals only)}]}],
  // visible: () => indices allowed by the page's filter, onOpen(index)}.
  function create(parent, options) {
    const root = el('section', {class: 'viewer', id: options.id || 'viewer', tabindex: '-1'});
    const title = el('h3', {class: 'viewer-title'});
    const media = el('div', {class: 'viewer-media'});
    const stepLabel = el('span', {class: 'viewer-step', 'aria-live': 'polite'});
    const slider = el('input', {type: 'range', min: 0, max: 0, value: 0, step: 1, class: 'viewer-slider', 'aria-label': 'step'});
    const playButton = el('button', {type: 'button', class: 'viewer-play', title: 'play / pause (space)'}, 'play');
    const button = (text, hint, fn) => el('button', {type: 'button', title: hint, onclick: fn}, text);
    const controls = el('div', {class: 'viewer-controls'},
        button('↑', 'previous episode (↑)', () => nextEpisode(-1)),
        button('Home', 'first step (Home)', () => seek(0)),
        button('◀', 'one step back (←)', () => seek(state.step - 1)),
        playButton,
        button('▶', 'one step on (→)', () => seek(state.step + 1)),
        button('End', 'last step (End)', () => seek(state.steps)),
        button('↓', 'next episode (↓)', () => nextEpisode(1)),
        stepLabel, slider);
    const hint = el('p', {class: 'caption'},
        '←/→ one step · space play/pause · Home/End first/last step · ↑/↓ previous/next episode · click or drag on a plot to seek. ' +
        'The frame shown for step t is the one recorded after step t (t = 0: after reset).' + (options.noLink ? '' : ' Link to this moment: '));
    const link = el('a', {class: 'viewer-link', href: '#'}, '');
    if (!options.noLink) hint.append(link);
    const plotsBox = el('div', {class: 'viewer-plots'});
    root.append(title, media, ...(options.legend ? [options.legend] : []), controls, hint, plotsBox);
    parent.append(root);
    playButton.addEventListener('click', () => togglePlay());
    slider.addEventListener('input', () => seek(Number(slider.value)));

    const state = {episode: null, step: 0, steps: 0, tracks: [], videos: [], charts: {}, specs: []};
    // the keys act while the viewer is on screen (so they do not take the page's scrolling away)
    const onScreen = () => {
      const box = root.getBoundingClientRect();
      return box.bottom > 0 && box.top < window.innerHeight;
    };

    function playing() {
      return options.isPlaying ? options.isPlaying() : state.videos.some((v) => !v.paused && !v.ended);
    }

    // the cursor line of each plot and the values at the step
    function drawCursor() {
      for (const spec of state.specs) {
        const chart = state.charts[spec.id];
        if (!chart) continue;
        const line = chart.over.querySelector('.viewer-cursor');
        line.style.left = `${chart.valToPos(state.step, 'x')}px`;
        chart.root.parentNode.parentNode.querySelector('.viewer-readout').textContent = `t = ${state.step}: ${spec.readout(state.step)}`;
      }
    }

    function render(updateHash) {
      root.dataset.episode = state.episode;
      root.dataset.step = state.step;
      root.dataset.steps = state.steps;
      root.dataset.playing = playing() ? '1' : '0';
      stepLabel.textContent = `t = ${state.step} / ${state.steps}`;
      slider.max = state.steps;
      slider.value = state.step;
      playButton.textContent = playing() ? 'pause' : 'play';
      const hash = `#episode=${state.episode}&t=${state.step}`;
      link.href = hash;
      link.textContent = hash;
      if (updateHash && options.linkable && location.hash !== hash) history.replaceState(null, '', hash);
      drawCursor();
      if (options.onStep) options.onStep(state.episode, state.step);
    }

    // Shows step t: the cursor, and every video at the middle of frame t.
    function seek(t, {fromVideo = false} = {}) {
      if (state.episode === null) return;
      const step = Math.max(0, Math.min(state.steps, Math.round(Number(t) || 0)));
      state.step = step;
      if (!fromVideo) {
        for (const v of state.videos) {
          if (!v.paused) v.pause();
          const time = (step + 0.5) / options.fps;
          if (v.readyState >= 1) v.currentTime = time;
          else v.addEventListener('loadedmetadata', () => { v.currentTime = (state.step + 0.5) / options.fps; }, {once: true});
        }
      }
      render(!fromVideo || !playing());
    }

    // the step on screen while a video plays: the frame being shown
    function follow(video) {
      const fromTime = (time) => seek(Math.min(state.steps, Math.floor(time * options.fps + 1e-6)), {fromVideo: true});
      if ('requestVideoFrameCallback' in video) {
        const onFrame = (now, meta) => {
          if (video !== state.videos[0]) return;
          if (!video.paused) fromTime(meta.mediaTime);  // a paused video shows what seek() asked for
          video.requestVideoFrameCallback(onFrame);
        };
        video.requestVideoFrameCallback(onFrame);
      } else {
        video.addEventListener('timeupdate', () => { if (!video.paused) fromTime(video.currentTime); });
      }
      video.addEventListener('pause', () => {
        // a pause from the play button or space stays on the step on screen: the frame the video
        // last presented (state.step). Its currentTime can lag that frame's time by a few ms on a
        // busy machine (frames are presented a little early), so the video is put at the middle
        // of that frame, and its time and the cursor agree.
        if (video === state.videos[0] && !video.seeking && stoppedByUser) seek(state.step);
        stoppedByUser = false;
        render(true);
      });
      video.addEventListener('ended', () => { if (video === state.videos[0]) seek(state.steps, {fromVideo: true}); });
      video.addEventListener('play', () => render(false));
    }

    let stoppedByUser = false;  // a pause from the play button or space: show the frame it stopped on
    function togglePlay() {
      if (options.play) { options.play(); return; }  // a page that plays without videos (serve)
      if (!state.videos.length) return;
      if (playing()) {
        stoppedByUser = true;
        state.videos.forEach((v) => v.pause());
      } else {
        if (state.step >= state.steps) seek(0);
        state.videos.forEach((v) => v.play().catch(() => {}));
      }
      render(false);
    }

    // The width of one plot, from the window's and the grid's sizes (page.css: main at most 1180 px
    // with 24 px padding, the viewer's 10 px padding and border, cells at least 520 px, 10 px
    // apart, each with 6 px padding and a border), so that opening a view forces no layout of a
    // page that may hold a thousand table rows; fit() corrects it once the page is drawn.
    function plotWidth() {
      const grid = Math.min(1180, window.innerWidth) - 2 * 24 - 2 * 11;
      const columns = Math.max(1, Math.floor((grid + 10) / (520 + 10)));
      return Math.max(300, Math.floor((grid - 10 * (columns - 1)) / columns) - 2 * 7);
    }

    // shades the steps where the plot's band (state.specs, so that a refresh's data shows) holds
    function drawBand(u, id) {
      const spec = state.specs.find((sp) => sp.id === id);
      if (!spec || !spec.band) return;
      const {ctx, bbox} = u;
      ctx.save();
      ctx.fillStyle = spec.bandColor;
      for (let t = 0; t < spec.band.length; t++) {
        if (!spec.band[t]) continue;
        const a = u.valToPos(t - 0.5, 'x', true), b = u.valToPos(t + 0.5, 'x', true);
        const left = Math.max(bbox.left, a), right = Math.min(bbox.left + bbox.width, b);
        if (right > left) ctx.fillRect(left, bbox.top, right - left, bbox.height);
      }
      ctx.restore();
    }

    // a plot's data: the step axis, then each series' value at every step
    function plotValues(spec, xs) {
      return [xs, ...spec.series.map((s) => (s.values === 'threshold' ? xs.map(() => options.threshold) : xs.map((t) => at(s.values, t))))];
    }

    function buildPlots() {
      for (const chart of Object.values(state.charts)) chart.destroy();
      state.charts = {};
      plotsBox.replaceChildren();
      state.specs = plotSpecs(state.tracks, options).filter((spec) => spec.series.some((s) => Array.isArray(s.values)));
      if (!state.specs.length) {
        plotsBox.append(el('p', {class: 'caption'}, 'No per-step data for this episode (its trajectory is missing).'));
        return;
      }
      const xs = Array.from({length: state.steps + 1}, (_, t) => t);
      // every box first, then one width for all (the grid's cells are alike): one layout, not one per plot
      const targets = state.specs.map((spec) => {
        const box = el('div', {class: 'vplot', id: `vplot-${spec.id}`});
        const target = el('div', {class: 'chart'});
        box.append(el('h4', {}, spec.title), el('div', {class: 'viewer-readout'}), target);
        plotsBox.append(box);
        return target;
      });
      const width = plotWidth();
      for (const [i, spec] of state.specs.entries()) {
        const target = targets[i];
        const hasCmd = spec.series.some((s) => s.scale === 'cmd');
        const series = [{label: 'step'}];
        const values = plotValues(spec, xs);
        for (const s of spec.series) {
          series.push({label: s.label, stroke: s.stroke, dash: s.dash || undefined, width: s.width || 1.5, scale: s.scale || 'y',
                       points: {show: !!s.points || state.steps <= 60, size: s.points ? 5 : 3}, spanGaps: false});
        }
        const chart = new uPlot({
          width, height: 150,
          legend: {show: true, live: false},
          cursor: {drag: {x: false, y: false, setScale: false}, sync: {key: `${root.id}-steps`}},
          // the x range follows the steps (they grow in serve's live episode: refresh)
          scales: {x: {time: false, range: () => [0, Math.max(1, state.steps)]}, ...(hasCmd ? {cmd: {range: [-1.05, 1.05]}} : {})},
          axes: [{incrs: FS.integerSteps}, {label: spec.unit, size: 62},
                 ...(hasCmd ? [{scale: 'cmd', side: 1, size: 40, grid: {show: false}}] : [])],
          series,
          // a band (the grasp): the steps where it holds, shaded under the curves
          hooks: spec.band ? {drawClear: [(u) => drawBand(u, spec.id)]} : {},
        }, values, target);
        const line = el('div', {class: 'viewer-cursor'});
        chart.over.append(line);
        // click or drag on the plot: seek to the step under the pointer
        const stepAt = (event) => chart.posToVal(event.clientX - chart.over.getBoundingClientRect().left, 'x');
        chart.over.addEventListener('pointerdown', (event) => {
          event.preventDefault();
          seek(stepAt(event));
          const move = (e) => seek(stepAt(e));
          const up = () => { window.removeEventListener('pointermove', move); window.removeEventListener('pointerup', up); };
          window.addEventListener('pointermove', move);
          window.addEventListener('pointerup', up);
        });
        state.charts[spec.id] = chart;
      }
    }

    // Opens episode `index` at step t.
    function open(index, t = 0) {
      const episode = options.episodes.find((e) => e.index === Number(index));
      if (!episode) return false;
      if (state.episode !== episode.index) {
        state.videos.forEach((v) => { v.pause(); v.removeAttribute('src'); v.load(); });
        state.episode = episode.index;
        state.tracks = episode.tracks();
        state.steps = Math.max(0, ...state.tracks.map((tr) => (tr.signals ? tr.signals.frames : tr.frames || 1) - 1));
        title.replaceChildren(...[].concat(episode.title));
        title.className = 'viewer-title ' + (episode.className || '');
        media.replaceChildren();
        state.videos = [];
        for (const track of state.tracks) {
          if (track.noMedia) continue;  // compare: B's signals, its frames are in A's video
          const figure = el('figure', {class: 'viewer-track'});
          if (track.video && track.image) {  // an image format (gif, apng): not seekable
            figure.append(el('img', {src: track.video, alt: `${track.name} (${track.format}: not seekable)`}));
          } else if (track.video) {
            const video = el('video', {src: track.video, muted: true, playsinline: true, preload: 'auto', class: 'viewer-video'});
            video.muted = true;
            follow(video);
            state.videos.push(video);
            figure.append(video);
          } else {
            figure.append(el('p', {class: 'caption'}, 'no video'));
          }
          if (state.tracks.length > 1) figure.append(el('figcaption', {}, track.caption || track.name));
          media.append(figure);
        }
        buildPlots();
        requestAnimationFrame(() => setTimeout(fit));
        if (options.onOpen) options.onOpen(episode.index);
      }
      seek(t);
      return true;
    }

    function nextEpisode(direction) {
      const order = options.visible();
      if (!order.length) return;
      const i = order.indexOf(state.episode);
      const next = i < 0 ? order[0] : order[Math.max(0, Math.min(order.length - 1, i + direction))];
      if (next !== state.episode) open(next, 0);
    }

    document.addEventListener('keydown', (event) => {
      if (!(options.keysAnywhere || onScreen()) || event.altKey || event.ctrlKey || event.metaKey || state.episode === null) return;
      const target = event.target;
      if (target && (/^(INPUT|TEXTAREA|SELECT)$/.test(target.tagName) && target !== slider || target.isContentEditable)) return;
      const actions = {ArrowLeft: () => seek(state.step - 1), ArrowRight: () => seek(state.step + 1),
                       Home: () => seek(0), End: () => seek(state.steps), ' ': () => togglePlay(),
                       ArrowUp: () => nextEpisode(-1), ArrowDown: () => nextEpisode(1)};
      const action = actions[event.key];
      if (!action) return;
      event.preventDefault();
      action();
    });
    // every plot at its cell's width (after a resize, and once a view's first frame is drawn)
    function fit() {
      for (const chart of Object.values(state.charts)) {
        const width = Math.max(300, Math.floor(chart.root.parentNode.clientWidth || 520));
        if (width !== chart.width) chart.setSize({width, height: 150});
      }
      drawCursor();
    }
    window.addEventListener('resize', fit);

    // The open episode's tracks read again (their signals grew or shrank: serve's live episode),
    // the plots rebuilt, and the cursor put at step t (default: where it is, within the steps).
    function refresh(t) {
      if (state.episode === null) return;
      const episode = options.episodes.find((e) => e.index === state.episode);
      if (!episode) return;
      state.tracks = episode.tracks();
      state.steps = Math.max(0, ...state.tracks.map((tr) => (tr.signals ? tr.signals.frames : tr.frames || 1) - 1));
      const specs = plotSpecs(state.tracks, options).filter((spec) => spec.series.some((s) => Array.isArray(s.values)));
      const same = specs.length === state.specs.length && specs.length > 0 &&
          specs.every((spec, i) => spec.id === state.specs[i].id && spec.series.length === state.specs[i].series.length);
      if (same) {  // the same plots with more (or fewer) steps: new data, no new charts
        const xs = Array.from({length: state.steps + 1}, (_, k) => k);
        state.specs = specs;
        for (const spec of specs) state.charts[spec.id].setData(plotValues(spec, xs));
      } else {
        buildPlots();
        requestAnimationFrame(() => setTimeout(fit));
      }
      seek(t === undefined ? Math.min(state.step, state.steps) : t);
    }

    const api = {element: root, open, seek, togglePlay, nextEpisode, refresh,
                 get episode() { return state.episode; }, get step() { return state.step; },
                 get steps() { return state.steps; }, get charts() { return state.charts; },
                 get tracks() { return state.tracks; }, get videos() { return state.videos; }};
    return api;
  }

  // "#episode=3&t=23" -> {episode: 3, t: 23}; null when the hash is not a viewer link.
  function parseHash(hash) {
    const params = new URLSearchParams(String(hash || '').replace(/^#/, ''));
    if (!params.has('episode')) return null;
    const episode = Number(params.get('episode'));
    const t = Number(params.get('t') || 0);
    return Number.isInteger(episode) ? {episode, t: Number.isFinite(t) ? t : 0} : null;
  }

  return {create, episodeSignals, parseHash};
})();
