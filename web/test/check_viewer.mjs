// Drives a report's episode viewer in real headless Chromium (Debian's, through playwright-core)
// and prints what it found as one JSON object on stdout; tests/browser_test.cc makes the
// assertions.
//   node check_viewer.mjs --page DIR/index.html --links 3:7,0:12 --grab-dir OUT
//        [--click-step K] [--chromium /usr/bin/chromium] [--timeout-ms 30000]
//        [--screenshot OUT.png: the viewer at the first link, for the README]
// For each link E:T it opens index.html#episode=E&t=T in a fresh page load and records the
// viewer's state (data-episode, data-step, data-steps, the video's currentTime) and the video
// frame on screen, a screenshot of the video at its natural size, written to OUT/grab_E_T.png. At the first link it
// then presses → (state and frame again: OUT/right_E_T.png), clicks the distance plot at step
// K, presses End and Home, drags along the distance plot from step 2 to K - 1, reads the data every viewer plot holds, filters the table (success, failure, all; on a
// report), presses ↓ (under the success filter on a report), then plays the episode for a
// moment with space and pauses it with space again.
import {mkdtempSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join, resolve} from 'node:path';
import {pathToFileURL} from 'node:url';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', 'timeout-ms': '30000', 'click-step': '5'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.page || !args.links || !args['grab-dir']) {
  console.error('usage: node check_viewer.mjs --page FILE.html --links E:T[,E:T...] --grab-dir DIR');
  process.exit(2);
}
const timeout = Number(args['timeout-ms']);
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: [], links: []};
let context;

// the viewer's state once its video has settled on a frame
async function settle(page) {
  await page.waitForFunction(() => {
    const v = document.querySelector('#viewer video');
    return v && v.readyState >= 2 && !v.seeking;
  }, null, {timeout});
  // one more frame, so that the compositor shows what the decoder produced
  await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done))));
  return page.evaluate(() => {
    const root = document.getElementById('viewer');
    const v = root.querySelector('video');
    return {episode: Number(root.dataset.episode), step: Number(root.dataset.step), steps: Number(root.dataset.steps),
            current_time: v.currentTime, duration: v.duration, hash: location.hash,
            label: root.querySelector('.viewer-step').textContent};
  });
}

// the frame the video shows, as a PNG file: a screenshot of the video element drawn at its
// natural size in the page's top-left corner (a canvas grab of a file:// video is refused: the
// canvas is tainted)
async function grab(page, file) {
  const size = await page.evaluate(() => {
    const v = document.querySelector('#viewer video');
    Object.assign(v.style, {position: 'fixed', left: '0px', top: '0px', zIndex: '1000', maxWidth: 'none',
                            width: `${v.videoWidth}px`, height: `${v.videoHeight}px`});
    return {width: v.videoWidth, height: v.videoHeight};
  });
  await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done))));
  await page.screenshot({path: file, clip: {x: 0, y: 0, ...size}});
  await page.evaluate(() => { document.querySelector('#viewer video').removeAttribute('style'); });
  return resolve(file);
}

try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1280, height: 900},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
  page.on('pageerror', (e) => result.page_errors.push(String(e)));
  const base = pathToFileURL(resolve(args.page)).href;
  const links = args.links.split(',').map((l) => l.split(':').map(Number));
  for (const [i, [episode, t]] of links.entries()) {
    await page.goto('about:blank');
    await page.goto(`${base}#episode=${episode}&t=${t}`, {waitUntil: 'load', timeout});
    await page.waitForSelector('body[data-ready="1"]', {timeout});
    const entry = {asked: {episode, t}, state: await settle(page)};
    entry.grab = await grab(page, join(args['grab-dir'], `grab_${episode}_${t}.png`));
    // the note of a link to an episode the viewer does not have (null: none shown)
    entry.missing_note = await page.evaluate(() => {
      const note = document.querySelector('.viewer-missing');
      return note && !note.hidden ? note.textContent : null;
    });
    result.links.push(entry);
    if (i > 0) continue;
    if (args.screenshot) {
      await page.locator('#viewer').screenshot({path: args.screenshot});
      result.screenshot = resolve(args.screenshot);
    }
    // → : one step on
    await page.keyboard.press('ArrowRight');
    entry.right = await settle(page);
    entry.right_grab = await grab(page, join(args['grab-dir'], `right_${episode}_${t}.png`));
    // a click on the distance plot at step K
    const k = Number(args['click-step']);
    const point = await page.evaluate((step) => {
      const chart = window.fetchscopeViewer.charts.distance;
      chart.root.scrollIntoView({block: 'center'});
      const box = chart.over.getBoundingClientRect();
      return {x: box.left + chart.valToPos(step, 'x'), y: box.top + box.height / 2};
    }, k);
    await page.mouse.click(point.x, point.y);
    entry.click = {step: k, state: await settle(page)};
    // End, then Home: the last step, then the reset frame
    await page.keyboard.press('End');
    entry.end = await settle(page);
    await page.keyboard.press('Home');
    entry.home = await settle(page);
    // a drag along the distance plot from step 2 to step K - 1: the cursor follows the pointer
    const at = (step) => page.evaluate((s) => {
      const chart = window.fetchscopeViewer.charts.distance;
      const box = chart.over.getBoundingClientRect();
      return {x: box.left + chart.valToPos(s, 'x'), y: box.top + box.height / 2};
    }, step);
    const from = await at(2), to = await at(k - 1);
    await page.mouse.move(from.x, from.y);
    await page.mouse.down();
    entry.drag = {from: 2, to: k - 1, steps_seen: []};
    for (let j = 1; j <= 8; ++j) {
      await page.mouse.move(from.x + (to.x - from.x) * j / 8, from.y);
      entry.drag.steps_seen.push(await page.evaluate(() => Number(document.getElementById('viewer').dataset.step)));
    }
    await page.mouse.up();
    entry.drag.state = await settle(page);
    // the data of every viewer plot: its series by label
    result.plots = await page.evaluate(() => Object.fromEntries(Object.entries(window.fetchscopeViewer.charts).map(([id, chart]) =>
      [id, Object.fromEntries(chart.series.slice(1).map((s, j) => [s.label, chart.data[j + 1]]))])));
    result.cursor_lines = await page.$$eval('#viewer .viewer-cursor', (lines) => lines.length);
    result.plot_titles = await page.$$eval('#viewer .viewer-plots h4', (hs) => hs.map((h) => h.textContent));
    // the markers' legends (the viewer's, the sheets'): each marker's name and swatch colour as rgb()
    result.overlay_legends = await page.evaluate(() => Object.fromEntries(
        ['viewer-overlay-legend', 'sheet-overlay-legend'].map((id) => [id, [...document.querySelectorAll(`#${id} .overlay-marker`)]
          .map((m) => ({name: m.dataset.marker, color: getComputedStyle(m.querySelector('.legend-swatch')).backgroundColor}))])));
    // the episode table's width against its box at this 1,280 px viewport (the report's)
    result.table = await page.evaluate(() => {
      const t = document.querySelector('#episode-table');
      return t ? {width: t.scrollWidth, box: t.parentElement.clientWidth} : null;
    });
    // the cursor's colour and every plotted series' stroke, as rgb() strings
    result.cursor_color = await page.$eval('#viewer .viewer-cursor', (line) => getComputedStyle(line).borderLeftColor);
    result.series_colors = await page.evaluate(() => {
      const probe = document.createElement('span');
      document.body.append(probe);
      const rgb = (c) => { probe.style.color = ''; probe.style.color = c; return getComputedStyle(probe).color; };
      const out = Object.values(window.fetchscopeViewer.charts).flatMap((chart) => chart.series.slice(1)
          .map((s) => (typeof s.stroke === 'function' ? s.stroke(chart, 1) : s.stroke)).filter((c) => typeof c === 'string').map(rgb));
      probe.remove();
      return [...new Set(out)];
    });
    // the table's filter (the report's; compare's page has none)
    if (await page.$('#episode-filter')) {
      const rows = () => page.$$eval('#episode-table tbody tr', (trs) => trs.filter((tr) => tr.offsetParent !== null)
          .map((tr) => ({episode: Number(tr.dataset.episode), outcome: tr.dataset.outcome})));
      result.filter = {all: await rows()};
      for (const f of ['success', 'failure']) {
        await page.click(`#episode-filter button[data-filter="${f}"]`);
        result.filter[f] = await rows();
      }
      // ↓ under the success filter: the next successful episode
      await page.click('#episode-filter button[data-filter="success"]');
    }
    await page.locator('#viewer').scrollIntoViewIfNeeded();
    await page.keyboard.press('ArrowDown');
    result.after_down = await settle(page);
    // space: play for a moment, the cursor following the video; space again: paused on a step
    await page.locator('#viewer').scrollIntoViewIfNeeded();
    await page.keyboard.press(' ');
    await page.waitForFunction(() => Number(document.getElementById('viewer').dataset.step) >= 3, null, {timeout});
    result.while_playing = await page.evaluate(() => ({playing: document.getElementById('viewer').dataset.playing,
        step: Number(document.getElementById('viewer').dataset.step)}));
    await page.keyboard.press(' ');
    await page.waitForFunction(() => document.querySelector('#viewer video').paused, null, {timeout});
    result.after_pause = await settle(page);
    if (await page.$('#episode-filter')) await page.click('#episode-filter button[data-filter="all"]');
    result.thumbs = await page.$$eval('#episode-table .thumb', (ts) => ts.length);
  }
} catch (e) {
  result.exception = String(e && e.stack || e);
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
process.stdout.write(JSON.stringify(result) + '\n');
process.exit(result.exception ? 1 : 0);
