// The report page of one record run (fetchscope report DIR): drawn from FS.data, see
// inspect/report.cc ReportData and inspect/viewer.h AddEpisodeViewers for its fields.
(() => {
  const {data, colors, el, num, percent} = FS;
  // a randomized look in a few words: its kinds, its seed and the object's colour
  const lookText = (look, seed) => `${look.kinds.join(', ')} (seed ${seed})` +
      (look.colors && look.colors.object ? `, object rgb ${look.colors.object.slice(0, 3).map((v) => v.toFixed(2)).join(' ')}` : '');
  const page = document.getElementById('page');
  const episodes = data.episodes;
  const recorded = episodes.filter((e) => e.status !== 'missing');
  const s = data.summary;

  page.append(el('h1', {}, data.title));
  page.append(el('p', {class: 'subtitle'},
      `${s.recorded} of ${s.expected} episodes recorded · success ${s.successes}/${s.complete}` +
      (s.rate === null ? '' : ` = ${percent(s.rate)} (95 % Wilson interval ${percent(s.wilson_low)} – ${percent(s.wilson_high)})`)));
  if (data.notes.length) page.append(el('ul', {class: 'notes', id: 'notes'}, data.notes.map((n) => el('li', {}, n))));

  page.append(el('h2', {}, 'Provenance'));
  page.append(FS.provenanceTable(data.provenance));

  // --- plots
  page.append(el('h2', {}, 'Plots'));
  const withCurves = recorded.filter((e) => e.distances && e.distances.length);
  const longest = Math.max(1, ...withCurves.map((e) => e.distances.length));
  const steps = Array.from({length: longest}, (_, t) => t);
  const h = data.returns_histogram;
  const r = data.running_success;
  FS.plots(page, [{
    id: 'plot-distance', wide: true, title: 'Distance to goal over steps',
    caption: [FS.swatch(colors.success), 'success', FS.swatch(colors.failure), 'failure',
              ...(s.incomplete ? [FS.swatch(colors.interrupted), 'interrupted'] : []),
              FS.swatch(colors.threshold, true), `threshold ${data.threshold} m`],
    build: (width) => {
      const series = [{label: 'step'}];
      const values = [steps];
      for (const e of withCurves) {
        const stroke = !e.complete ? colors.interrupted : e.success ? colors.success : colors.failure;
        series.push({label: `episode ${e.label}`, stroke,
                     width: 1.25, points: {show: false}});
        values.push(steps.map((t) => (t < e.distances.length ? e.distances[t] : null)));
      }
      series.push({label: 'threshold', stroke: colors.threshold, dash: [6, 4], width: 1.5, points: {show: false}});
      values.push(steps.map(() => data.threshold));
      return [{
        width, legend: {show: false},
        scales: {x: {time: false}, y: {range: (u, lo, hi) => [0, Math.max(hi, data.threshold) * 1.05]}},
        axes: [{label: 'step', incrs: FS.integerSteps}, {label: 'distance (m)', size: 60}],
        series,
      }, values];
    },
  }, {
    id: 'plot-returns', title: 'Histogram of returns',
    // an interrupted episode's return covers only the steps it made: left out, as from the rate
    caption: `${s.complete} complete episode(s)` +
        (s.incomplete ? `; ${s.incomplete} interrupted episode(s) left out` : '') +
        `; bin width ${num(h.width, 3)}`,
    build: (width) => {
      const lo = h.centres.length ? h.centres[0] - h.width / 2 : 0;
      const hi = h.centres.length ? h.centres[h.centres.length - 1] + h.width / 2 : 1;
      return [{
        width, legend: {show: false},
        scales: {x: {time: false, range: [lo, hi]}, y: {range: (u, a, b) => [0, Math.max(1, b) * 1.1]}},
        axes: [{label: 'return'}, {label: 'episodes', size: 50, incrs: FS.integerSteps}],
        series: [{label: 'return'},
                 {label: 'episodes', stroke: colors.accent, fill: 'rgba(44,109,178,0.55)',
                  paths: uPlot.paths.bars({size: [0.92, Infinity], align: 0}), points: {show: false}}],
      }, [h.centres, h.counts]];
    },
  }, {
    id: 'plot-success', title: 'Success rate with its 95 % Wilson interval',
    caption: s.rate === null ? 'no complete episode' :
      `after ${s.complete} complete episode(s), in index order: ${s.successes}/${s.complete} = ${percent(s.rate)}, ` +
      `interval ${percent(s.wilson_low)} – ${percent(s.wilson_high)}`,
    build: (width) => [{
      width, legend: {show: false},
      scales: {x: {time: false, range: [0.5, Math.max(1, r.n.length) + 0.5]}, y: {range: [0, 1]}},
      axes: [{label: 'episodes counted', incrs: FS.integerSteps}, {label: 'success rate', size: 50}],
      series: [{label: 'episodes'},
               {label: 'rate', stroke: colors.accent, width: 2, points: {show: r.n.length < 40, size: 6}},
               {label: 'low', stroke: 'rgba(44,109,178,0.5)', width: 1, points: {show: false}},
               {label: 'high', stroke: 'rgba(44,109,178,0.5)', width: 1, points: {show: false}}],
      bands: [{series: [3, 2], fill: colors.band}],
    }, [r.n, r.rate, r.low, r.high]],
  }]);

  performance.mark('fetchscope-plots');
  // --- table
  page.append(el('h2', {}, 'Episodes'));
  const numeric = (v) => (typeof v === 'number' ? v : null);
  const status = (e) => (e.status === 'missing' ? el('span', {}, 'missing') :
      el('span', {class: e.success ? 'ok' : 'fail'}, e.success ? 'success' : 'failure'));
  const outcome = (e) => (e.status === 'missing' ? 'missing' : e.success ? 'success' : 'failure');
  // the first and last frame: their tiles of the contact sheet, loaded once the row is on screen
  const thumbObserver = new IntersectionObserver((entries) => {
    for (const entry of entries) {
      if (!entry.isIntersecting) continue;
      entry.target.style.backgroundImage = `url("${entry.target.dataset.sheet}")`;
      thumbObserver.unobserve(entry.target);
    }
  }, {rootMargin: '200px'});
  const thumb = (e, which) => {
    const th = e.thumbs, scale = 64 / th.tile[0];
    const t = which === 'first' ? 0 : e.frames - 1;
    const box = el('a', {class: 'thumb', href: `#episode=${e.index}&t=${t}`, 'data-sheet': e.sheet, title: `frame ${t}`,
        style: `width:64px;height:${Math.round(th.tile[1] * scale)}px;background-size:${th.sheet[0] * scale}px ${th.sheet[1] * scale}px;` +
               `background-position:${-th[which][0] * scale}px ${-th[which][1] * scale}px`});
    thumbObserver.observe(box);
    return box;
  };
  const columns = [
    {label: 'episode', value: (e) => e.index, numeric: true,
     render: (e) => (e.status === 'missing' ? e.label : el('a', {href: `#episode=${e.index}`, title: 'open in the viewer'}, e.label))},
    {label: 'success', value: (e) => (e.status === 'missing' ? null : e.success ? 1 : 0), render: status},
    {label: 'return', value: (e) => numeric(e.return), render: (e) => num(e.return, 3), numeric: true},
    {label: 'final distance (m)', value: (e) => numeric(e.final_distance), render: (e) => num(e.final_distance, 4), numeric: true},
    {label: 'length', value: (e) => numeric(e.length), render: (e) => num(e.length, 0), numeric: true},
    {label: 'complete', value: (e) => (e.status === 'missing' ? null : e.complete ? 1 : 0),
     render: (e) => (e.status === 'missing' ? e.reason : e.complete ? 'yes' : 'no (interrupted)')},
  ];
  if (data.has_hindsight) {
    columns.push({label: 'HER relabelled successes', value: (e) => (e.hindsight ? e.hindsight.relabelled_successes : null),
                  render: (e) => (e.hindsight ? String(e.hindsight.relabelled_successes) : '—'), numeric: true});
    columns.push({label: 'original successes', value: (e) => (e.hindsight ? e.hindsight.original_successes : null),
                  render: (e) => (e.hindsight ? String(e.hindsight.original_successes) : '—'), numeric: true});
  }
  if (data.has_look) {  // --randomize: each episode's draw (its seed and kinds; the whole draw in the tooltip)
    columns.push({label: 'look', value: (e) => (e.look ? e.look.seed : null),
                  render: (e) => (e.look ? el('span', {class: 'look', title: JSON.stringify(e.look)}, lookText(e.look, e.look_seed)) : 'plain')});
  }
  if (data.has_replay) {  // record --from DATASET: the reset used, and the first divergence
    columns.push({label: 'reset', value: (e) => (e.replay ? e.replay.reset : null), render: (e) => (e.replay ? e.replay.reset : '—')});
    // a difference in its unit, metres as mm (as the console says it)
    const amount = (v, unit) => (v === null || v === undefined ? 'not finite'
      : unit === 'm' || unit === 'm/step' ? `${(v * 1000).toPrecision(3)} mm${unit.slice(1)}`
        : `${v.toPrecision(3)}${unit ? ' ' + unit : ''}`);
    const largest = (r) => (r.max_step === undefined ? 'largest 0'
      : `largest ${amount(r.max_difference, r.max_unit)} in ${r.max_component || r.max_where} at step ${r.max_step}`);
    columns.push({label: 'divergence', value: (e) => (e.replay ? (e.replay.first_step ?? -1) : null),
                  // two lines that wrap in a narrow column: the table fits 1,280 px
                  render: (e) => (!e.replay ? '—' : el('span', {class: 'divergence'},
                    e.replay.first_step === null ? `none (within ${e.replay.tolerance})`
                      : `step ${e.replay.first_step}, ${e.replay.component || e.replay.where} off by ${amount(e.replay.difference, e.replay.unit)}`,
                    el('br'), largest(e.replay))), numeric: true});
  }
  columns.push({label: 'first / last frame', value: () => null,
                render: (e) => (e.thumbs && e.sheet ? el('span', {class: 'thumbs'}, thumb(e, 'first'), thumb(e, 'last')) : '')});
  // a per-layer video "episode_000_segmentation.mp4" is linked as "segmentation.mp4"
  const shortName = (e, file) => file.replace(/^.*\//, '').replace(`episode_${e.label}_`, '');
  columns.push({label: 'files', value: () => null, render: (e) => (e.status === 'missing' ? '' : [
    ...e.videos.flatMap((v) => [el('a', {href: v.file, class: 'video-link'}, v.format), ' ']),
    ...e.layers.flatMap((l) => [
      ...l.videos.flatMap((v) => [el('a', {href: v.file, class: 'video-link'}, `${l.name}.${v.format}`), ' ']),
      ...(l.legend ? [el('a', {href: l.legend}, `${l.name} legend`), ' '] : [])]),
    ...e.other_videos.flatMap((file) => [el('a', {href: file, class: 'video-link'}, shortName(e, file)), ' ']),
    e.sheet ? el('a', {href: e.sheet}, 'sheet') : null, ' ',
    e.trajectory ? el('a', {href: e.trajectory}, 'json') : null])});
  let viewer = null;
  const table = FS.sortableTable(columns, episodes,
      (e) => [e.status === 'missing' ? 'missing' : null, viewer && viewer.episode === e.index ? 'current' : null].filter(Boolean).join(' ') || null,
      (e) => ({'data-episode': e.index, 'data-outcome': outcome(e)}));
  table.id = 'episode-table';
  table.dataset.filter = 'all';
  // filter: every episode, the successes or the failures (the others' rows are hidden)
  const filter = el('div', {class: 'episode-filter', id: 'episode-filter', role: 'group', 'aria-label': 'show episodes'}, 'Show: ');
  for (const [value, text] of [['all', 'all'], ['success', 'successes'], ['failure', 'failures']]) {
    filter.append(el('button', {type: 'button', 'data-filter': value, 'aria-pressed': value === 'all' ? 'true' : 'false', onclick: () => {
      table.dataset.filter = value;
      filter.querySelectorAll('button').forEach((b) => b.setAttribute('aria-pressed', b.dataset.filter === value ? 'true' : 'false'));
    }}, text));
  }
  page.append(filter, FS.scrolling(table));

  performance.mark('fetchscope-table');
  // --- the episode viewer: one episode's video and per-step signals on one step cursor
  page.append(el('h2', {}, 'Episode viewer'));
  const viewable = recorded.filter((e) => e.video || e.viewer);
  // a link to an episode the viewer does not have (#episode=99 of a 10-episode run) says so
  const missing = el('p', {class: 'notes viewer-missing'});
  missing.hidden = true;
  page.append(missing);
  const headline = (e) => `episode ${e.label} — ${e.success ? 'success' : 'failure'}, return ${num(e.return, 2)}, ` +
      `final distance ${num(e.final_distance, 3)} m` + (e.complete ? '' : ', interrupted') +
      (e.look ? ` · look: ${lookText(e.look, e.look_seed)}` : '');
  // the markers drawn in the frames (the videos' and the sheets'), each in its colour
  const markerLegend = (id) => (data.overlay_legend && data.overlay_legend.length
    ? el('p', {class: 'caption overlay-legend', id}, 'Markers in the frames:',
         data.overlay_legend.map((m) => el('span', {class: 'overlay-marker', 'data-marker': m.name, title: m.meaning},
                                            FS.swatch(m.color), m.name)))
    : null);
  const v = data.viewer || {};
  // record --from DATASET: the replay's position errors against the dataset, for their plot
  const withReplay = (s, replay) => (s && replay && replay.position_error_mm
    ? Object.assign({}, s, {replay_error: replay.position_error_mm}) : s);
  viewer = FSViewer.create(page, {
    id: 'viewer', fps: data.fps, threshold: data.threshold, linkable: true, legend: markerLegend('viewer-overlay-legend'),
    has_object: v.has_object, gripper_command: v.gripper_command, layout: v.layout || {},
    episodes: viewable.map((e) => ({index: e.index, label: e.label, title: headline(e), className: e.success ? 'ok' : 'fail',
      tracks: () => [{name: `episode ${e.label}`, video: e.video, format: e.video_format, image: e.video_image, frames: e.frames,
                      signals: e.viewer ? withReplay(FSViewer.episodeSignals(`fetchscope-episode-${e.index}`), e.replay) : null}]})),
    // the episodes ↑/↓ visit: the table's rows in their order, those the filter shows
    visible: () => [...table.tBodies[0].rows]
        .filter((row) => row.dataset.outcome !== 'missing' && (table.dataset.filter === 'all' || row.dataset.outcome === table.dataset.filter))
        .map((row) => Number(row.dataset.episode)).filter((k) => viewable.some((e) => e.index === k)),
    onOpen: (k) => table.querySelectorAll('tbody tr').forEach((row) => row.classList.toggle('current', Number(row.dataset.episode) === k)),
  });
  window.fetchscopeViewer = viewer;
  const openFromHash = (scroll) => {
    const link = FSViewer.parseHash(location.hash);
    missing.hidden = true;
    if (!link) return false;
    if (!viewer.open(link.episode, link.t)) {
      const range = viewable.length ? `episodes ${viewable[0].label}–${viewable[viewable.length - 1].label}` : 'no episodes';
      missing.textContent = `#episode=${link.episode}: this run's viewer has no episode ${link.episode} (${range}, ` +
          `${viewable.length} in all)` + (viewable.length ? `; showing episode ${viewable[0].label}` : '');
      missing.hidden = false;
      return false;
    }
    // after the page's first layout, which it would otherwise force while the page is built
    if (scroll) requestAnimationFrame(() => viewer.element.scrollIntoView({block: 'start'}));
    return true;
  };
  if (!openFromHash(true) && viewable.length) viewer.open(viewable[0].index, 0);
  window.addEventListener('hashchange', () => openFromHash(true));

  performance.mark('fetchscope-viewer');
  // --- each episode
  page.append(el('h2', {}, 'Videos and contact sheets'));
  const sheetLegend = markerLegend('sheet-overlay-legend');
  if (sheetLegend) page.append(sheetLegend);
  const grid = el('div', {class: 'episodes'});
  // A large run's cards get their player and sheet when they come near the screen: a thousand
  // video elements would take seconds to create and lay out, and load nothing anyone looks at.
  const lazy = recorded.length > 50;
  const media = (e) => {
    // the best format a browser plays (mp4, then webm) as a video; an image format's file (a
    // gif-only run's gif: the format table's flag, video_image) as an image
    if (e.video && e.video_image) return el('img', {class: 'clip', src: e.video, alt: `episode ${e.label} (${e.video_format})`});
    if (e.video) return el('video', {src: e.video, controls: true, muted: true, playsinline: true, preload: lazy ? 'metadata' : 'auto'});
    return null;
  };
  const sheet = (e) => (e.sheet ? el('a', {href: e.sheet}, el('img', {src: e.sheet, alt: `contact sheet of episode ${e.label}`, loading: 'lazy'})) : null);
  const cardObserver = lazy ? new IntersectionObserver((entries) => {
    for (const entry of entries) {
      if (!entry.isIntersecting) continue;
      const e = episodes[Number(entry.target.dataset.position)];
      entry.target.querySelector('.card-media').replaceChildren(...[media(e), sheet(e)].filter(Boolean));
      cardObserver.unobserve(entry.target);
    }
  }, {rootMargin: '400px'}) : null;
  episodes.forEach((e, position) => {
    const card = el('section', {class: 'episode' + (e.status === 'missing' ? ' missing' : ''), id: `episode-${e.label}`});
    if (e.status === 'missing') {
      card.append(el('h3', {}, `episode ${e.label} — missing`), el('p', {}, e.reason));
      grid.append(card);
      return;
    }
    const heading = `episode ${e.label} — ${e.success ? 'success' : 'failure'}, return ${num(e.return, 2)}, ` +
        `final distance ${num(e.final_distance, 3)} m` + (e.complete ? '' : ', interrupted');
    card.append(el('h3', {class: e.success ? 'ok' : 'fail'}, heading));
    if (e.hindsight) {
      card.append(el('p', {}, `hindsight (HER future, k = 4): ${e.hindsight.relabelled_successes} relabelled ` +
          `successes against ${e.hindsight.original_successes} original`));
    }
    if (lazy) {
      card.dataset.position = position;
      card.append(el('div', {class: 'card-media lazy'}));
      cardObserver.observe(card);
    } else {
      card.append(...[media(e), sheet(e)].filter(Boolean));
    }
    card.append(el('div', {class: 'links'}, [
      ...e.videos.map((v) => el('a', {href: v.file, class: 'video-link'}, v.file)),
      ...e.layers.flatMap((l) => [
        ...l.videos.map((v) => el('a', {href: v.file, class: 'video-link'}, v.file)),
        l.legend ? el('a', {href: l.legend}, `${l.name} legend`) : null]),
      ...e.other_videos.map((file) => el('a', {href: file, class: 'video-link'}, file)),
      e.sheet ? el('a', {href: e.sheet}, 'contact sheet') : null,
      e.trajectory ? el('a', {href: e.trajectory}, 'trajectory JSON') : null]));
    grid.append(card);
  });
  page.append(grid);
  page.append(FS.footer());
  document.body.dataset.ready = '1';
  performance.mark('fetchscope-ready');
  // the first frame drawn after it (for tools/bench-viewer.sh)
  requestAnimationFrame(() => setTimeout(() => performance.mark('fetchscope-painted')));
})();
