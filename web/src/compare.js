// The compare page of two record runs (fetchscope compare A B --out DIR): drawn from FS.data, see
// cli/compare.cc RunCompare for its fields.
(() => {
  const {data, colors, el, num} = FS;
  const page = document.getElementById('page');
  const s = data.summary;
  const rows = data.episodes;

  page.append(el('h1', {}, data.title));
  page.append(el('p', {class: 'subtitle'},
      el('span', {class: 'verdict ' + (s.same ? 'same' : 'different'), id: 'verdict'}, s.same ? 'same run' : 'different'),
      ` ${s.differing_episodes} of ${s.episodes} episode(s) differ · state tolerance ${s.tolerance}` +
      (s.states_only ? ' · states only' : ` · pixel tolerance ${s.pixel_tolerance}`)));
  page.append(el('p', {}, 'A = ', data.report_a ? el('a', {href: data.report_a}, data.run_a) : data.run_a,
      ' · B = ', data.report_b ? el('a', {href: data.report_b}, data.run_b) : data.run_b));

  page.append(el('h2', {}, 'Provenance'));
  page.append(FS.provenanceTable(data.provenance_a, data.provenance_b));

  // --- plots: state difference (log scale; zero drawn at the floor) and pixel difference
  page.append(el('h2', {}, 'Differences over steps'));
  const floor = 1e-16;
  const longest = Math.max(1, ...rows.map((r) => r.state_difference.length));
  const steps = Array.from({length: longest}, (_, t) => t);
  const palette = ['#2c6db2', '#d73027', '#1a9850', '#7b3294', '#f98e09', '#4d4d4d', '#b8860b', '#00a3a3'];
  const specs = [{
    id: 'plot-state', title: 'State difference max |A − B| over steps',
    caption: [`log scale; a difference of 0 is drawn at ${floor}; `, FS.swatch(colors.threshold, true), `tolerance ${s.tolerance}`],
    build: (width) => {
      const series = [{label: 'step'}];
      const values = [steps];
      rows.forEach((r, i) => {
        series.push({label: `episode ${r.label}`, stroke: palette[i % palette.length], width: 1.5, points: {show: false}});
        values.push(steps.map((t) => {
          const v = r.state_difference[t];
          return t < r.state_difference.length ? (typeof v === 'number' ? Math.max(v, floor) : 1e300) : null;
        }));
      });
      series.push({label: 'tolerance', stroke: colors.threshold, dash: [6, 4], width: 1.5, points: {show: false}});
      values.push(steps.map(() => Math.max(s.tolerance, floor)));
      return [{width, legend: {show: rows.length <= 12}, scales: {x: {time: false}, y: {distr: 3, log: 10}},
               axes: [{label: 'step', incrs: FS.integerSteps},
                      {label: 'max |A − B|', size: 70,
                       // every decade gets a grid line, about six of them a label
                       values: (u, splits) => {
                         const decade = (v) => v !== null && v > 0 && Math.abs(Math.log10(v) - Math.round(Math.log10(v))) < 1e-9;
                         const every = Math.max(1, Math.ceil(splits.filter(decade).length / 6));
                         return splits.map((v) => (decade(v) && Math.round(Math.log10(v)) % every === 0 ? v.toExponential(0) : ''));
                       }}],
               series}, values];
    },
  }];
  if (!s.states_only) {
    const frames = Math.max(1, ...rows.map((r) => (r.pixel_difference || []).length));
    const xs = Array.from({length: frames}, (_, t) => t);
    specs.push({
      id: 'plot-pixels', title: 'Largest pixel difference per frame (0..255)',
      caption: 'frame t shows the state after step t (frame 0: reset); frames are compared as decoded ' +
               'from H.264, so frames of equal states can differ a little where the encoder chose differently ' +
               'for the frames around them',
      build: (width) => {
        const series = [{label: 'frame'}];
        const values = [xs];
        rows.forEach((r, i) => {
          series.push({label: `episode ${r.label}`, stroke: palette[i % palette.length], width: 1.5, points: {show: false}});
          values.push(xs.map((t) => (t < (r.pixel_difference || []).length ? r.pixel_difference[t] : null)));
        });
        return [{width, legend: {show: rows.length <= 12}, scales: {x: {time: false}, y: {range: [0, 255]}},
                 axes: [{label: 'frame', incrs: FS.integerSteps}, {label: 'max channel difference', size: 60}], series}, values];
      },
    });
  }
  FS.plots(page, specs);

  // --- summary table
  page.append(el('h2', {}, 'Episodes'));
  const number = (v) => (typeof v === 'number' ? v : null);
  const pair = (r, f, d) => `${num(f(r.a), d)} / ${num(f(r.b), d)}`;
  const columns = [
    {label: 'episode', value: (r) => r.index, render: (r) => el('a', {href: `#pair-${r.label}`}, r.label), numeric: true},
    {label: 'verdict', value: (r) => (r.same ? 1 : 0), render: (r) => el('span', {class: r.same ? 'ok' : 'fail'}, r.same ? 'same' : 'different')},
    {label: 'first divergence step', value: (r) => number(r.first_divergence_step),
     render: (r) => (r.first_divergence_step === null ? '—' : String(r.first_divergence_step)), numeric: true},
    {label: 'max state difference', value: (r) => number(r.max_state_difference),
     render: (r) => (typeof r.max_state_difference === 'number' ? r.max_state_difference.toExponential(2) : r.max_state_difference), numeric: true},
    {label: 'max pixel difference', value: (r) => number(r.max_pixel_difference),
     render: (r) => (r.video ? String(r.max_pixel_difference) : '—'), numeric: true},
    {label: 'mean pixel difference', value: (r) => number(r.mean_pixel_difference),
     render: (r) => (r.video ? num(r.mean_pixel_difference, 3) : '—'), numeric: true},
    {label: 'success A / B', value: (r) => (r.a.success ? 2 : 0) + (r.b.success ? 1 : 0),
     render: (r) => `${r.a.success ? 'yes' : 'no'} / ${r.b.success ? 'yes' : 'no'}`},
    {label: 'return A / B', value: (r) => number(r.a.return), render: (r) => pair(r, (x) => x.return, 3), numeric: true},
    {label: 'final distance A / B (m)', value: (r) => number(r.a.final_distance), render: (r) => pair(r, (x) => x.final_distance, 4), numeric: true},
    {label: 'steps A / B', value: (r) => r.steps_a, render: (r) => `${r.steps_a} / ${r.steps_b}`, numeric: true},
  ];
  // runs recorded with --signals contacts: where their contact sequences first differ
  if (data.episodes.some((r) => r.first_contact_difference)) {
    columns.splice(3, 0,
    {label: 'contacts first differ', value: (r) => (r.first_contact_difference ? number(r.first_contact_difference.step) : null),
     render: (r) => {
       const c = r.first_contact_difference;
       if (!c) return '—';  // a run without --signals contacts
       if (c.step === null) return 'never';
       return el('span', {title: `only in A: ${c.only_a.join(', ') || 'none'}; only in B: ${c.only_b.join(', ') || 'none'}`}, `step ${c.step}`);
     }, numeric: true});
  }
  const table = FS.sortableTable(columns, rows, null, (r) => ({'data-episode': r.index}));
  table.id = 'episode-table';
  page.append(FS.scrolling(table));

  // --- the episode viewer: A (solid) and B (dashed) on one step cursor over the comparison video
  page.append(el('h2', {}, 'Episode viewer: A and B step by step'));
  const v = data.viewer || {};
  const viewer = FSViewer.create(page, {
    id: 'viewer', fps: data.fps || 25, threshold: v.threshold || 0.05, linkable: true,
    has_object: v.has_object, gripper_command: v.gripper_command, layout: v.layout || {},
    episodes: rows.map((r) => ({index: r.index, label: r.label, className: r.same ? 'ok' : 'fail',
      title: `episode ${r.label} — ` + (r.first_divergence_step === null ? 'states equal within the tolerance'
          : `states diverge at step ${r.first_divergence_step}`) + ' · A solid, B dashed',
      tracks: () => [
        {name: 'A', caption: 'A | B | difference', video: r.video, format: 'mp4', frames: r.steps_a + 1,
         signals: r.viewer_a ? FSViewer.episodeSignals(`fetchscope-a-episode-${r.index}`) : null},
        {name: 'B', noMedia: true, frames: r.steps_b + 1,
         signals: r.viewer_b ? FSViewer.episodeSignals(`fetchscope-b-episode-${r.index}`) : null}]})),
    visible: () => [...table.tBodies[0].rows].map((row) => Number(row.dataset.episode)),
  });
  window.fetchscopeViewer = viewer;
  const openFromHash = (scroll) => {
    const link = FSViewer.parseHash(location.hash);
    if (!link || !viewer.open(link.episode, link.t)) return false;
    // after the page's first layout, which it would otherwise force while the page is built
    if (scroll) requestAnimationFrame(() => viewer.element.scrollIntoView({block: 'start'}));
    return true;
  };
  if (!openFromHash(true) && rows.length) viewer.open(rows[0].index, 0);
  window.addEventListener('hashchange', () => openFromHash(true));

  // --- side-by-side videos
  if (!s.states_only) {
    page.append(el('h2', {}, 'Side by side: A | B | per-pixel difference heat map (black: equal; 4× amplified)'));
    const list = el('div', {class: 'pairs'});
    for (const r of rows) {
      const box = el('section', {class: 'pair', id: `pair-${r.label}`});
      box.append(el('h3', {class: r.same ? 'ok' : 'fail'}, `episode ${r.label} — ` + (r.first_divergence_step === null
          ? 'states equal within the tolerance' : `states diverge at step ${r.first_divergence_step}`)));
      box.append(el('video', {src: r.video, controls: true, muted: true, playsinline: true, preload: rows.length <= 50 ? 'auto' : 'metadata'}));
      list.append(box);
    }
    page.append(list);
  }
  page.append(FS.footer());
  document.body.dataset.ready = '1';
})();
