// Embedded instead of uPlot when fetchscope was built without it (web/node_modules absent when
// CMake configured: tools/install-deps.sh runs `npm ci` in web/). Every plot box then says so
// plainly, a note heads the page, and the rest of the page (tables, videos, the viewer's
// step cursor) works. The stand-in answers every call a chart gets with itself, so no caller
// needs to know.
(function () {
  'use strict';
  const message = 'This plot is missing: this fetchscope was built without uPlot. ' +
    'Run tools/install-deps.sh (it installs uPlot with npm into web/node_modules), then rebuild.';
  const nothing = new Proxy(function () {}, {
    get: (target, key) => (key === Symbol.toPrimitive ? () => 0 : key === 'then' ? undefined : nothing),
    apply: () => nothing,
    construct: () => nothing,
  });
  function uPlot(options, data, target) {
    if (target && target.append) {
      const p = document.createElement('p');
      p.className = 'missing-plot';
      p.textContent = message;
      target.append(p);
    }
    return nothing;
  }
  uPlot.paths = nothing;
  uPlot.missing = true;
  window.uPlot = uPlot;
  document.addEventListener('DOMContentLoaded', () => {
    const note = document.createElement('p');
    note.className = 'missing-plot';
    note.id = 'uplot-missing';
    note.textContent = 'The plots of this page are missing: this fetchscope was built without ' +
      'uPlot. Run tools/install-deps.sh, then rebuild.';
    document.body.prepend(note);
  });
})();
