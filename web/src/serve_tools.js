// serve's page (serve.js), the parts that stand alone: the step inspector's fields of a row,
// the small per-step plots, and the episode browser with its filter. window.FSServeTools.
'use strict';

window.FSServeTools = (() => {
  const {el} = FS;
  const DEFAULT_FREE = {lookat: [1.3, 0.75, 0.55], distance: 2.5, azimuth: 132, elevation: -14};

  // ---- the camera as numbers, and as the --camera text the server renders

  const round = (v, digits) => String(Number(v.toFixed(digits)));
  function cameraText(free) {
    const pose = `distance=${round(free.distance, 3)},azimuth=${round(free.azimuth, 2)},elevation=${round(free.elevation, 2)}`;
    if (free.track) return `track:body=${free.track},${pose}`;
    return `free:lookat=${free.lookat.map((v) => round(v, 4)).join(',')},${pose}`;
  }
  // the numbers of a camera text we can orbit from (free, track, default, a model camera's preset)
  function parseCamera(text, source) {
    const t = String(text).trim();
    if (t === 'default' || t === 'free') return {...DEFAULT_FREE, lookat: DEFAULT_FREE.lookat.slice()};
    if (t === 'track') return {lookat: DEFAULT_FREE.lookat.slice(), distance: 1, azimuth: 132, elevation: -20, track: 'robot0:gripper_link'};
    const preset = (source && source.cameras || []).find((c) => c.name === t);
    if (preset) return parseCamera(preset.free, source);
    const m = /^(free|track):(.*)$/.exec(t);
    if (!m || t.includes(',free') || t.includes(',track')) return null;  // several views: not orbited
    const free = {...DEFAULT_FREE, lookat: DEFAULT_FREE.lookat.slice()};
    if (m[1] === 'track') Object.assign(free, {distance: 1, azimuth: 132, elevation: -20, track: 'robot0:gripper_link'});
    const parts = m[2].split(',');
    for (let i = 0; i < parts.length; i++) {
      const [key, value] = parts[i].split('=');
      if (key === 'lookat') { free.lookat = [Number(value), Number(parts[i + 1]), Number(parts[i + 2])]; i += 2; }
      else if (key === 'body') free.track = value;
      else if (key in free) free[key] = Number(value);
    }
    return free;
  }

  // ---- a live episode's lists: a step's values appended, a step back's cut (the page keeps the
  // episode; the server answers a step with that step alone)

  function growLists(target, step) {
    for (const [key, value] of Object.entries(step)) {
      if (key === 'colors' || !(key in target)) continue;
      const list = target[key];
      if (Array.isArray(list) && Array.isArray(list[0])) list.forEach((l, i) => l.push(value[i]));
      else if (Array.isArray(list)) list.push(value);
      else if (list && typeof list === 'object') growLists(list, value);
    }
  }
  function cutLists(target, length) {
    for (const [key, list] of Object.entries(target)) {
      if (key === 'colors') continue;
      if (Array.isArray(list) && Array.isArray(list[0])) list.forEach((l) => { l.length = Math.min(l.length, length); });
      else if (Array.isArray(list)) list.length = Math.min(list.length, length);
      else if (list && typeof list === 'object') cutLists(list, length);
    }
  }

  function fields(row, source) {
    const labels = source.observation_labels || [];
    const out = [['t', row.t, '', () => row.t], ['success', row.is_success, '', (r) => (r.is_success ? 1 : 0)],
                 ['reward', row.reward, '', (r) => r.reward]];
    (row.action || [null, null, null, null]).forEach((v, i) => out.push([`action[${i}]`, v, '', (r) => (r.action ? r.action[i] : null)]));
    ['achieved_goal', 'desired_goal'].forEach((k) => row[k].forEach((v, i) => out.push([`${k}[${i}]`, v, 'm', (r) => r[k][i]])));
    row.observation.forEach((v, i) => out.push([`obs[${i}] ${labels[i] ? labels[i].name : ''}`, v, labels[i] ? labels[i].unit : '', (r) => r.observation[i]]));
    if (row.contacts) {
      for (const k of ['left_finger_force', 'right_finger_force']) out.push([`contacts.${k}`, row.contacts[k], 'N', (r) => (r.contacts ? r.contacts[k] : null)]);
      for (const k of ['grasped', 'object_on_table']) out.push([`contacts.${k}`, row.contacts[k], '', (r) => (r.contacts ? (r.contacts[k] ? 1 : 0) : null)]);
    }
    return out;
  }
  const shownValue = (v) => (v === null || v === undefined ? '—' : typeof v === 'boolean' ? (v ? 'yes' : 'no')
                            : typeof v === 'number' && !Number.isInteger(v) ? v.toPrecision(6) : String(v));
  // a small line plot of `values` (one per step; null where none), step `t` marked
  function stepPlot(values, t) {
    const finite = values.filter((v) => typeof v === 'number' && Number.isFinite(v));
    const W = 340, H = 120, lo = Math.min(...finite), hi = Math.max(...finite), span = hi - lo || 1;
    const x = (i) => 4 + (W - 8) * i / Math.max(1, values.length - 1), y = (v) => H - 14 - (H - 24) * (v - lo) / span;
    const points = values.map((v, i) => (typeof v === 'number' && Number.isFinite(v) ? `${x(i)},${y(v)}` : null)).filter(Boolean).join(' ');
    const svg = document.createElementNS('http://www.w3.org/2000/svg', 'svg');
    svg.setAttribute('viewBox', `0 0 ${W} ${H}`);
    svg.setAttribute('width', '100%');
    svg.setAttribute('height', String(H));
    svg.innerHTML = `<polyline fill="none" stroke="#2166ac" stroke-width="1.5" points="${points}"/>` +
        `<line x1="${x(t)}" x2="${x(t)}" y1="0" y2="${H - 12}" stroke="#b2182b"/>` +
        `<text x="4" y="${H - 2}" font-size="10">${FS.num(lo, 4)} … ${FS.num(hi, 4)} over steps 0–${values.length - 1}</text>`;
    return {svg, points: finite.length};
  }
  // ---- the episode browser: the listed columns, then those of each episode's rows; a filter
  // such as "success = no", "distance > 0.05", "dropped" or "first_success <= 10, grasped"

  const FILTER_COLUMNS = {episode: 'index', steps: 'steps', success: 'success', return: 'return', complete: 'complete',
                          distance: 'final_distance', first_success: 'first_success',
                          displacement: 'object_displacement', grasped: 'grasped_at', dropped: 'dropped_at',
                          diverges: 'diverges_at'};
  // the filter as a test of a row; throws an Error naming what it cannot read
  function parseFilter(text) {
    const clauses = text.split(/,|\band\b/).map((c) => c.trim()).filter(Boolean);
    const tests = clauses.map((clause) => {
      const m = /^(not\s+|!)?([a-z_]+)\s*(?:(==|=|!=|>=|<=|>|<)\s*(\S+))?$/.exec(clause);
      if (!m) throw new Error(`cannot read '${clause}': use NAME, not NAME, or NAME OP VALUE (=, !=, <, <=, >, >=)`);
      const key = FILTER_COLUMNS[m[2]];
      if (!key) throw new Error(`unknown column '${m[2]}': use ${Object.keys(FILTER_COLUMNS).join(', ')}`);
      if (!m[3]) {
        const truthy = (r) => r[key] !== null && r[key] !== undefined && r[key] !== false;
        return m[1] ? (r) => !truthy(r) : truthy;
      }
      const word = m[4].toLowerCase();
      const value = word === 'yes' || word === 'true' ? true : word === 'no' || word === 'false' ? false
                  : word === 'none' || word === 'null' ? null : Number(m[4]);
      if (typeof value === 'number' && Number.isNaN(value)) throw new Error(`'${m[4]}' is not a number, yes, no or none`);
      const op = m[3];
      return (r) => {
        const v = r[key] === undefined ? null : r[key];
        if (op === '=' || op === '==') return v === value;
        if (op === '!=') return v !== value;
        if (v === null || value === null) return false;
        return op === '>' ? v > value : op === '>=' ? v >= value : op === '<' ? v < value : v <= value;
      };
    });
    return (r) => tests.every((t) => t(r));
  }
  function episodeBrowser(i, rows, showError, open) {
    const element = el('div', {class: 'serve-browser', 'data-source': i});
    const filter = el('input', {type: 'text', class: 'serve-filter', spellcheck: 'false', placeholder: 'filter: success = no, distance > 0.05, dropped',
                                'aria-label': 'filter the episodes'});
    const note = el('p', {class: 'caption serve-filter-note'});
    const tableBox = el('div', {class: 'table-wrap'});
    const extra = [];  // the columns of the episodes' rows, once known
    const mm = (v) => (v === null || v === undefined ? '—' : (1000 * v).toFixed(1));
    const stepOf = (v) => (v === null || v === undefined ? '—' : String(v));
    const columns = () => [
      {label: 'episode', numeric: true, value: (r) => r.index,
       render: (r) => el('a', {href: '#', 'data-episode': r.index, onclick: (ev) => { ev.preventDefault(); open(r.index); }}, String(r.index))},
      {label: 'steps', numeric: true, value: (r) => r.steps, render: (r) => String(r.steps) + (r.complete ? '' : ' (cut short)')},
      {label: 'success', value: (r) => r.success, render: (r) => (r.success === null ? '—' : r.success ? 'yes' : 'no')},
      {label: 'return', numeric: true, value: (r) => r.return, render: (r) => FS.num(r.return, 2)},
      ...extra,
    ];
    let shown = rows;
    function draw() {
      const began = performance.now();
      let test = () => true;
      try {
        test = parseFilter(filter.value);
        note.classList.remove('error');
      } catch (e) {
        note.textContent = e.message;
        note.classList.add('error');
        return;
      }
      shown = rows.filter(test);
      note.textContent = `${shown.length} of ${rows.length} episodes`;
      element.dataset.shown = String(shown.length);
      tableBox.replaceChildren(FS.sortableTable(columns(), shown, (r) => (r.success ? 'ok' : 'fail')));
      performance.measure('fetchscope-serve-browser-drawn', {start: began});  // bench reads it
    }
    let timer = null;
    filter.addEventListener('input', () => { clearTimeout(timer); timer = setTimeout(draw, 120); });
    element.append(filter, note, tableBox);
    draw();
    return {
      element,
      addColumns(listing) {
        const byIndex = new Map(listing.map((e) => [e.index, e]));
        rows.forEach((r) => Object.assign(r, byIndex.get(r.index) || {}));
        extra.push({label: 'final dist. mm', numeric: true, value: (r) => r.final_distance, render: (r) => mm(r.final_distance)},
                   {label: 'first success', numeric: true, value: (r) => r.first_success, render: (r) => stepOf(r.first_success)});
        if (listing.some((e) => e.object_displacement !== null && e.object_displacement !== undefined)) {
          extra.push({label: 'object moved mm', numeric: true, value: (r) => r.object_displacement, render: (r) => mm(r.object_displacement)});
        }
        if (listing.some((e) => 'diverges_at' in e)) {  // a dataset replayed against its rows
          extra.push({label: 'diverges at', numeric: true, value: (r) => r.diverges_at, render: (r) => stepOf(r.diverges_at)},
                     {label: 'reset', value: (r) => r.reset, render: (r) => r.reset || '—'});
        }
        if (listing.some((e) => 'grasped_at' in e)) {
          extra.push({label: 'grasped at', numeric: true, value: (r) => r.grasped_at, render: (r) => stepOf(r.grasped_at)},
                     {label: 'dropped at', numeric: true, value: (r) => r.dropped_at, render: (r) => stepOf(r.dropped_at)});
        }
        element.dataset.columns = 'full';
        draw();
        performance.mark('fetchscope-serve-columns');
      },
    };
  }

  // ---- the step inspector: the step's observation by name, goals, action, reward, success and
  // contacts, each value as the trajectory JSON holds it (data-value); a click plots it over the
  // episode; the step copies as JSON

  function inspector({data, state, after}) {
    const inspector = el('div', {class: 'serve-inspector'});
    const fieldPlot = el('div', {class: 'serve-field-plot'});
    let plotted = null;  // {label, value(row)} of the field plotted
    function showInspector() {
      const rows = state.rows;
      const row = rows && rows[Math.min(state.t, rows.length - 1)];
      if (!row) { inspector.replaceChildren(); return; }
      const source = data.sources[state.source === 'live' ? state.live.source : state.source];
      const table = el('table', {class: 'serve-fields'}, el('tr', {}, el('th', {}, 'field'), el('th', {}, 'value'), el('th', {}, 'unit')));
      for (const [label, value, unit, getter] of fields(row, source)) {
        table.append(el('tr', {'data-field': label, 'data-value': JSON.stringify(value), title: 'click: plot it over the episode',
                               onclick: () => { plotted = {label, value: getter}; drawFieldPlot(); }},
                        el('td', {}, label), el('td', {class: 'num'}, shownValue(value)), el('td', {}, unit)));
      }
      const copy = el('button', {type: 'button', class: 'serve-copy-step',
          onclick: () => navigator.clipboard && navigator.clipboard.writeText(JSON.stringify(row))}, 'copy the step as JSON');
      inspector.replaceChildren(el('h3', {}, `Step ${row.t}`), copy, fieldPlot, table);
      inspector.dataset.t = String(row.t);
      drawFieldPlot();
      after();
    }
    // the plotted field over the episode's steps, the current step marked
    function drawFieldPlot() {
      const rows = state.rows;
      if (!plotted || !rows) { fieldPlot.replaceChildren(); return; }
      const {svg, points} = stepPlot(rows.map((r) => plotted.value(r)), state.t);
      fieldPlot.replaceChildren(el('p', {class: 'caption'}, `${plotted.label} over the episode`), svg);
      fieldPlot.dataset.field = plotted.label;
      fieldPlot.dataset.points = String(points);
    }
    return {element: inspector, show: showInspector};
  }

  // ---- side by side: a second served episode, its own view at the same step (the overlays and
  // size of the first; its own camera, else the first's), compare's first state difference and the
  // difference's plot

  function sideBySide({data, state, api, viewParams, showError}) {
    const other = {source: null, episode: null, rows: null, inFlight: false, again: false, url: null};
    const otherImage = el('img', {class: 'serve-other-frame', alt: 'the second episode', draggable: 'false'});
    const otherCaption = el('p', {class: 'caption serve-other-caption'});
    const otherDiff = el('div', {class: 'serve-other-diff'});
    const otherCamera = el('input', {type: 'text', class: 'serve-other-camera', spellcheck: 'false', list: 'serve-other-cameras',
                                     'aria-label': 'camera of the second view', placeholder: 'its camera: empty for the first view\'s'});
    const cameraList = el('datalist', {id: 'serve-other-cameras'});
    otherCamera.addEventListener('change', () => requestOtherFrame());
    const otherBox = el('div', {class: 'serve-other', hidden: true}, otherCaption, otherImage,
                        el('div', {class: 'serve-row'}, 'camera ', otherCamera, cameraList), otherDiff);
    const otherSelect = el('select', {'aria-label': 'side by side with', class: 'serve-other-select'});
    otherSelect.addEventListener('change', () => {
      if (!otherSelect.value) { other.source = null; otherBox.hidden = true; return; }
      const [source, episode] = otherSelect.value.split('/').map(Number);
      openOther(source, episode);
    });
    function fillOtherSelect() {
      const options = [el('option', {value: ''}, 'side by side with… (none)')];
      data.sources.forEach((s, i) => (s.episodes || []).forEach((e) =>
        options.push(el('option', {value: `${i}/${e.index}`}, `${s.kind} ${i}: episode ${e.index}`))));
      otherSelect.replaceChildren(...options);
    }
    async function openOther(source, episode) {
      try {
        const {body} = await api('/api/episode', {source, episode});
        Object.assign(other, {source, episode, rows: body.rows});
        cameraList.replaceChildren(...['default', 'track', ...(data.sources[source].cameras || []).map((c) => c.name)]
            .map((name) => el('option', {value: name})));
        otherBox.hidden = false;
        otherBox.dataset.episode = `${source}/${episode}`;
        requestOtherFrame();
        showDifference();
      } catch (e) {
        showError(e.message);
      }
    }
    function requestOtherFrame() {
      if (other.source === null) return;
      if (other.inFlight) { other.again = true; return; }
      other.inFlight = true;
      other.again = false;
      const t = Math.min(state.t, other.rows.length - 1);
      const params = {...viewParams(state.moving || state.playing ? 'jpeg' : 'png'), source: other.source, episode: other.episode, t};
      if (otherCamera.value.trim()) params.camera = otherCamera.value.trim();
      api('/api/frame', params).then(({body, response}) => {
        if (other.url) URL.revokeObjectURL(other.url);
        other.url = URL.createObjectURL(body);
        otherImage.dataset.step = String(t);
        otherImage.dataset.camera = response.headers.get('X-Fetchscope-Camera') || '';
        otherImage.src = other.url;
        otherCaption.textContent = `${data.sources[other.source].title} · episode ${other.episode} · step ${t}` +
            (t < state.t ? ` (it ends at step ${other.rows.length - 1})` : '');
      }).catch((e) => showError(e.message)).finally(() => {
        other.inFlight = false;
        if (other.again) requestOtherFrame();
      });
    }
    // the first step and field where the two episodes' states differ (as `compare` finds it), and
    // the size of the difference of their observations at each step
    function showDifference() {
      const a = state.rows, b = other.rows;
      if (!a || !b || other.source === null) return;
      const source = data.sources[state.source === 'live' ? state.live.source : state.source];
      const n = Math.min(a.length, b.length);
      let first = null;
      const sizes = [];
      for (let t = 0; t < n; t++) {
        const fa = fields(a[t], source), fb = fields(b[t], source);
        let sum = 0;
        fa.forEach(([label, va], i) => {
          const vb = fb[i] ? fb[i][1] : undefined;
          if (label.startsWith('obs[') && typeof va === 'number' && typeof vb === 'number') sum += (va - vb) * (va - vb);
          if (!first && label !== 't' && !label.startsWith('contacts') && JSON.stringify(va) !== JSON.stringify(vb)) {
            first = {t, label, a: va, b: vb};
          }
        });
        sizes.push(Math.sqrt(sum));
      }
      const {svg} = stepPlot(sizes, Math.min(state.t, n - 1));
      otherDiff.replaceChildren(
          el('p', {class: 'serve-first-difference'}, first ? `first difference: step ${first.t}, ${first.label}: ${shownValue(first.a)} against ${shownValue(first.b)}`
                                                          : `no difference over the ${n} steps both have`),
          el('p', {class: 'caption'}, '|observation A − observation B| per step'), svg);
      otherDiff.dataset.firstStep = first ? String(first.t) : '';
      otherDiff.dataset.firstField = first ? first.label : '';
    }
    return {box: otherBox, select: otherSelect, fill: fillOtherSelect, requestFrame: requestOtherFrame, showDifference};
  }

  // ---- the look: the episode's own (a stored look, else serve's --randomize), plain, or another
  // draw (a seed); the frame's answer says which look it drew (X-Fetchscope-Look)

  function lookControl(onChange) {
    const select = el('select', {'aria-label': 'look', class: 'serve-look'},
        el('option', {value: ''}, 'look: the episode\'s own'), el('option', {value: 'plain'}, 'look: plain'),
        el('option', {value: 'draw'}, 'look: a draw…'));
    const seed = el('input', {type: 'number', min: '0', step: '1', value: '1', class: 'serve-look-seed', 'aria-label': 'draw seed', hidden: true});
    const next = el('button', {type: 'button', class: 'serve-look-next', hidden: true, title: 'the next seed: another draw of the same step'}, 'another draw');
    const shown = el('span', {class: 'caption serve-look-shown'});
    const value = () => (select.value === 'draw' ? String(Math.max(0, Math.floor(Number(seed.value) || 0))) : select.value);
    const changed = () => { seed.hidden = next.hidden = select.value !== 'draw'; onChange(value()); };
    select.addEventListener('change', changed);
    seed.addEventListener('change', changed);
    next.addEventListener('click', () => { seed.value = String((Math.floor(Number(seed.value)) || 0) + 1); changed(); });
    // what the frame was drawn with: "plain", or the draw's seed and kinds
    function show(text) {
      let look = null;
      try { look = text ? JSON.parse(text) : null; } catch (e) { look = null; }
      const seed = look ? (/"seed":\s*([0-9]+)/.exec(text) || [])[1] : '';  // 64 bits: as text
      shown.textContent = look ? `drawn: ${look.kinds.join(', ')} (look seed ${seed})` : 'plain';
      shown.dataset.seed = seed || '';
    }
    return {element: el('span', {class: 'serve-look-box'}, select, seed, next, shown), value, show};
  }

  // ---- placing a live env's reset: where the block and the goal start, typed or clicked on the
  // view (the next click's world point), sent with the start (goal=x,y,z, object=x,y); the saved
  // session records it, so that its record command resets there too

  function placementForm({source, index, start, armPick}) {
    const number = (label) => el('input', {type: 'number', step: '0.001', class: 'serve-place-value', 'aria-label': label, placeholder: 'as drawn'});
    const block = [number('block x'), number('block y')];
    const goal = [number('goal x'), number('goal y'), number('goal z')];
    const note = el('p', {class: 'caption serve-place-note'}, 'empty: where the seed\'s reset puts it');
    const pick = (what, inputs) => el('button', {type: 'button', class: `serve-place-pick-${what}`,
        title: `the next click on the view sets the ${what} to the world point under the pointer (x, y${inputs.length > 2 ? ', z' : ''})`,
        onclick: () => {
          note.textContent = `click the view where the ${what} should start`;
          armPick((point) => {
            inputs.forEach((input, i) => { input.value = point[i].toFixed(4); });
            note.textContent = `${what} at (${inputs.map((i) => i.value).join(', ')}) m`;
          });
        }}, `${what} ← click`);
    const read = (inputs) => {
      const values = inputs.map((i) => i.value.trim());
      if (values.every((v) => v === '')) return null;
      if (values.some((v) => v === '' || !Number.isFinite(Number(v)))) throw new Error('give every coordinate, or none');
      return values.join(',');
    };
    const go = el('button', {type: 'button', class: 'serve-start-placed', 'data-source': index, onclick: () => {
      try {
        const params = {env: index};
        const g = read(goal);
        const b = source.has_object ? read(block) : null;
        if (g) params.goal = g;
        if (b) params.object = b;
        start(params);
      } catch (e) {
        note.textContent = `not started: ${e.message}`;
      }
    }}, 'start placed');
    const rows = [];
    if (source.has_object) rows.push(el('div', {class: 'serve-row'}, 'block x ', block[0], ' y ', block[1], pick('block', block)));
    rows.push(el('div', {class: 'serve-row'}, 'goal x ', goal[0], ' y ', goal[1], ' z ', goal[2], pick('goal', goal)));
    const element = el('details', {class: 'serve-place'}, el('summary', {}, 'place the block and goal, then start'), ...rows,
                       el('div', {class: 'serve-row'}, go), note);
    // a live episode's reset (the seed's, or placed) fills the empty fields, for editing
    function fill(row) {
      const values = [...goal.map((_, i) => row.desired_goal[i])];
      goal.forEach((input, i) => { if (input.value === '') input.value = values[i].toFixed(4); });
      if (source.has_object) block.forEach((input, i) => { if (input.value === '') input.value = row.observation[3 + i].toFixed(4); });
    }
    return {element, fill};
  }

  return {fields, shownValue, stepPlot, parseFilter, episodeBrowser, inspector, sideBySide, placementForm, lookControl,
          growLists, cutLists, cameraText, parseCamera, DEFAULT_FREE};
})();
