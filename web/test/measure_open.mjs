// Times how long a report page takes to open in headless Chromium (Debian's, through
// playwright-core), for tools/bench-viewer.sh. Prints one JSON object:
//   node measure_open.mjs --page DIR/index.html [--runs 5] [--link "episode=999&t=25"]
//        [--chromium /usr/bin/chromium]
// Per run, a fresh page load of index.html#LINK, measured by the page's own clock (from the
// navigation's start): "ready" when the page has drawn its plots, table and the viewer on the
// linked episode (the performance mark 'fetchscope-ready'), "load" at the load event; then
// "next_episode": the time ↓ takes to open the next episode (parse its data, draw its plots).
import {mkdtempSync, rmSync, statSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join, resolve} from 'node:path';
import {pathToFileURL} from 'node:url';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', runs: '5', link: 'episode=0&t=0'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {page: resolve(args.page), bytes: statSync(args.page).size, runs: [], errors: []};
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1280, height: 900},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
  const url = `${pathToFileURL(resolve(args.page)).href}#${args.link}`;
  for (let i = 0; i < Number(args.runs); ++i) {
    const page = await context.newPage();
    page.on('pageerror', (e) => result.errors.push(String(e)));
    await page.goto(url, {waitUntil: 'load', timeout: 60000});
    await page.waitForSelector('body[data-ready="1"]', {timeout: 60000});
    await page.waitForFunction(() => performance.getEntriesByName('fetchscope-painted').length > 0, null, {timeout: 60000});
    const run = await page.evaluate(() => ({
      ready_ms: performance.getEntriesByName('fetchscope-ready')[0].startTime,
      painted_ms: performance.getEntriesByName('fetchscope-painted')[0].startTime,
      // where the time went: the page's marks after its sections (plots, table, viewer, ready)
      marks: Object.fromEntries(performance.getEntriesByType('mark').map((m) => [m.name.replace('fetchscope-', ''), Math.round(m.startTime)])),
      dom_interactive_ms: performance.getEntriesByType('navigation')[0].domInteractive,
      load_ms: performance.getEntriesByType('navigation')[0].loadEventEnd,
      episode: Number(document.getElementById('viewer').dataset.episode),
      step: Number(document.getElementById('viewer').dataset.step),
      rows: document.querySelectorAll('#episode-table tbody tr').length,
    }));
    run.next_episode_ms = await page.evaluate(() => {
      document.getElementById('viewer').scrollIntoView();
      const start = performance.now();
      window.fetchscopeViewer.nextEpisode(1);
      return performance.now() - start;
    });
    result.runs.push(run);
    await page.close();
  }
  const median = (key) => {
    const v = result.runs.map((r) => r[key]).sort((a, b) => a - b);
    return v[Math.floor(v.length / 2)];
  };
  result.median = {ready_ms: median('ready_ms'), painted_ms: median('painted_ms'), load_ms: median('load_ms'), next_episode_ms: median('next_episode_ms')};
} catch (e) {
  result.exception = String(e && e.stack || e);
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
process.stdout.write(JSON.stringify(result) + '\n');
process.exit(result.exception ? 1 : 0);
