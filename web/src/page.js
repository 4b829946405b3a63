// Shared by the report and compare pages: the data, element building, formatting, the sortable
// table and uPlot plots. The pages are drawn entirely from the JSON in #fetchscope-data, which
// fetchscope computed; nothing is fetched.
'use strict';

const FS = (() => {
  const data = JSON.parse(document.getElementById('fetchscope-data').textContent);
  const colors = {success: '#1a9850', failure: '#d73027', interrupted: '#8a8f94', threshold: '#555', accent: '#2c6db2',
                  band: 'rgba(44,109,178,0.18)', diff: '#7b3294'};

  // el('td', {class: 'num'}, 'text', childNode, ...): attributes, then children (strings are text).
  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    for (const [key, value] of Object.entries(attrs || {})) {
      if (value === undefined || value === null || value === false) continue;
      if (key.startsWith('on')) node.addEventListener(key.slice(2), value);
      else node.setAttribute(key, value === true ? '' : value);
    }
    for (const child of children.flat()) {
      if (child === undefined || child === null) continue;
      node.append(child instanceof Node ? child : document.createTextNode(String(child)));
    }
    return node;
  }

  function num(value, digits) {
    if (value === null || value === undefined) return '—';
    if (typeof value === 'string') return value;  // "nan", "inf"
    return Number(value).toFixed(digits);
  }

  function percent(value) {
    return value === null || value === undefined ? '—' : (100 * value).toFixed(1) + ' %';
  }

  function provenanceTable(rows, bRows) {
    const table = el('table', {class: 'provenance'});
    if (bRows) table.append(el('thead', {}, el('tr', {}, el('th', {}), el('th', {}, 'run A'), el('th', {}, 'run B'))));
    const body = el('tbody');
    if (!bRows) {
      for (const row of rows) {
        body.append(el('tr', {}, el('th', {}, row.label),
            el('td', {}, row.href ? el('a', {href: row.href}, row.value) : row.value)));
      }
    } else {
      const labels = [];
      for (const row of rows.concat(bRows)) if (!labels.includes(row.label)) labels.push(row.label);
      const find = (list, label) => (list.find((r) => r.label === label) || {value: ''}).value;
      for (const label of labels) {
        const a = find(rows, label), b = find(bRows, label);
        const cls = a === b ? null : 'differs';
        body.append(el('tr', {}, el('th', {}, label), el('td', {class: cls}, a), el('td', {class: cls}, b)));
      }
    }
    table.append(body);
    return table;
  }

  // columns: [{label, value: row => sortable value (null sorts last), render: row => node|text,
  // numeric}]. Clicking a header sorts by it; clicking again reverses. rowAttrs(row): more
  // attributes of the row's <tr> (such as data-episode).
  function sortableTable(columns, rows, rowClass, rowAttrs) {
    const table = el('table', {class: 'sortable'});
    const headRow = el('tr');
    const body = el('tbody');
    const fill = (ordered) => {
      body.replaceChildren(...ordered.map((row) => el('tr', {class: rowClass ? rowClass(row) : null, ...(rowAttrs ? rowAttrs(row) : {})},
          columns.map((c) => el('td', {class: c.numeric ? 'num' : null}, c.render(row))))));
    };
    columns.forEach((column, i) => {
      const th = el('th', {class: column.numeric ? 'num' : null, scope: 'col', title: 'sort'}, column.label);
      th.addEventListener('click', () => {
        const descending = th.getAttribute('aria-sort') === 'ascending';
        headRow.querySelectorAll('th').forEach((h) => h.removeAttribute('aria-sort'));
        th.setAttribute('aria-sort', descending ? 'descending' : 'ascending');
        const sign = descending ? -1 : 1;
        const ordered = rows.slice().sort((a, b) => {
          const va = column.value(a), vb = column.value(b);
          const na = va === null || va === undefined || Number.isNaN(va);
          const nb = vb === null || vb === undefined || Number.isNaN(vb);
          if (na || nb) return na === nb ? 0 : na ? 1 : -1;  // unknown values last either way
          return (va < vb ? -1 : va > vb ? 1 : 0) * sign;
        });
        fill(ordered);
      });
      if (i === 0) th.setAttribute('aria-sort', 'ascending');
      headRow.append(th);
    });
    table.append(el('thead', {}, headRow), body);
    fill(rows);
    return table;
  }

  // A wide table scrolls sideways inside the page instead of widening it.
  function scrolling(table) {
    return el('div', {class: 'table-wrap'}, table);
  }

  // uPlot charts in titled boxes inside `parent`: specs [{id, title, caption, wide, build}], where
  // build(width) returns [options, data]. Every box is placed first and then drawn at the width
  // the layout gave it.
  function plots(parent, specs) {
    const grid = el('div', {class: 'plots'});
    parent.append(grid);
    const targets = specs.map((spec) => {
      const box = el('div', {class: 'plot' + (spec.wide ? ' wide' : ''), id: spec.id});
      const target = el('div', {class: 'chart'});
      box.append(el('h3', {}, spec.title), target);
      if (spec.caption) box.append(el('p', {class: 'caption'}, spec.caption));
      grid.append(box);
      return target;
    });
    return specs.map((spec, i) => {
      const width = Math.max(320, Math.floor(targets[i].clientWidth || 520));
      const [options, values] = spec.build(width);
      options.width = width;
      options.height = options.height || 300;
      const chart = new uPlot(options, values, targets[i]);
      charts[spec.id] = chart;
      return chart;
    });
  }

  // the uPlot charts by plot id, for a look from the browser's console (and the browser tests)
  const charts = {};
  window.fetchscopeCharts = charts;

  // axis tick steps for counts: whole numbers only
  const integerSteps = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000];

  function swatch(color, dashed) {
    return el('span', {class: 'legend-swatch', style: `background:${dashed ? 'repeating-linear-gradient(90deg,' + color + ' 0 5px,transparent 5px 8px)' : color}`});
  }

  function footer() {
    return el('footer', {}, `Made by ${data.generator}; plots by uPlot ${data.uplot} (MIT), inlined: `,
        'this page loads nothing from the network.');
  }

  return {data, colors, el, num, percent, provenanceTable, sortableTable, plots, swatch, footer, integerSteps, scrolling};
})();
