// Loads a fetchscope report or compare page in real headless Chromium (Debian's, through
// playwright-core) and prints what it found as one JSON object on stdout; the C++ test
// (tests/browser_test.cc) makes the assertions.
//   node check_page.mjs --page DIR/index.html --screenshot OUT.png [--sort-column N]
//        [--chromium /usr/bin/chromium] [--timeout-ms 30000] [--url http://... instead of file://]
//        [--seek F: before the screenshot, every video shows the frame at F (0..1) of its length]
// The screenshot is of the whole page (tools/docs-screenshots.sh makes README's with it too).
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join, resolve} from 'node:path';
import {pathToFileURL} from 'node:url';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', 'sort-column': '2', 'timeout-ms': '30000'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!(args.page || args.url) || !args.screenshot) {
  console.error('usage: node check_page.mjs --page FILE.html --screenshot OUT.png [--sort-column N]');
  process.exit(2);
}
const timeout = Number(args['timeout-ms']);
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: [], network_requests: [], failed_requests: []};
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium,
    headless: true,
    viewport: {width: 1280, height: 900},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update', '--no-first-run', '--autoplay-policy=no-user-gesture-required'],
  });
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
  page.on('pageerror', (e) => result.page_errors.push(String(e)));
  // any request beyond the page's own folder (file:// or the server that serves it) is a network fetch
  const own = (u) => /^(file|data|blob):/.test(u) || (args.url && new URL(u).origin === new URL(args.url).origin);
  page.on('request', (r) => { if (!own(r.url())) result.network_requests.push(r.url()); });
  page.on('requestfailed', (r) => result.failed_requests.push(`${r.url()}: ${r.failure() && r.failure().errorText}`));
  const url = args.url || pathToFileURL(resolve(args.page)).href;
  result.url = url;
  await page.goto(url, {waitUntil: 'load', timeout});
  await page.waitForSelector('body[data-ready="1"]', {timeout});
  result.title = await page.title();

  // every video: wait for readyState >= 2 (HAVE_CURRENT_DATA), then read duration and size
  const deadline = Date.now() + timeout;
  let videos;
  do {
    videos = await page.$$eval('video', (vs) => vs.map((v) => ({
      src: v.getAttribute('src'), ready_state: v.readyState, duration: v.duration,
      width: v.videoWidth, height: v.videoHeight, error: v.error ? v.error.code : null})));
    if (videos.every((v) => v.ready_state >= 2 || v.error)) break;
    await page.$$eval('video', (vs) => vs.forEach((v) => { if (v.readyState < 2 && v.preload !== 'auto') { v.preload = 'auto'; v.load(); } }));
    await page.waitForTimeout(200);
  } while (Date.now() < deadline);
  result.videos = videos;

  // every gif shown as an image (a gif-only run's clips): loaded and decoded
  result.images = await page.$$eval('img.clip', (imgs) => imgs.map((i) => ({
    src: i.getAttribute('src'), complete: i.complete, natural_width: i.naturalWidth, natural_height: i.naturalHeight})));
  // the links to each episode's video files, by their text, row by row of the episode table
  result.video_links = await page.$$eval('#episode-table tbody tr', (trs) =>
    trs.map((tr) => [...tr.querySelectorAll('a.video-link')].map((a) => ({text: a.textContent, href: a.getAttribute('href')}))));

  // every plot: its canvas, how many pixels uPlot painted, and per series (uPlot's own record,
  // window.fetchscopeCharts): its label, colour, how many values it has, and how many pixels of
  // its colour lie inside the plotting area
  result.plots = await page.$$eval('.plot', (boxes) => boxes.map((box) => {
    const canvas = box.querySelector('canvas');
    if (!canvas) return {id: box.id, painted: 0, width: 0, height: 0, series: []};
    const pixels = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
    let painted = 0;
    for (let i = 3; i < pixels.length; i += 4) painted += pixels[i] !== 0;
    const chart = (window.fetchscopeCharts || {})[box.id];
    const series = [];
    if (chart) {
      const rgb = (colour) => {  // '#rrggbb' or '#rgb' -> [r, g, b]; anything else: null
        const m = /^#([0-9a-f]{3}|[0-9a-f]{6})$/i.exec(colour || '');
        if (!m) return null;
        const hex = m[1].length === 3 ? m[1].replace(/./g, '$&$&') : m[1];
        return [0, 2, 4].map((i) => parseInt(hex.slice(i, i + 2), 16));
      };
      const {left, top, width, height} = chart.bbox;  // canvas pixels
      const inside = (c) => {  // pixels within 24 levels of colour c in every channel
        let n = 0;
        for (let y = Math.ceil(top); y < top + height; ++y) {
          for (let x = Math.ceil(left); x < left + width; ++x) {
            const i = (y * canvas.width + x) * 4;
            if (pixels[i + 3] > 200 && Math.abs(pixels[i] - c[0]) <= 24 && Math.abs(pixels[i + 1] - c[1]) <= 24 &&
                Math.abs(pixels[i + 2] - c[2]) <= 24) ++n;
          }
        }
        return n;
      };
      const counted = {};
      chart.series.forEach((s, i) => {
        if (i === 0) return;  // the x values
        const stroke = typeof s.stroke === 'function' ? s.stroke(chart, i) : s.stroke;
        const c = rgb(stroke);
        const key = String(stroke);
        if (c && !(key in counted)) counted[key] = inside(c);
        series.push({label: s.label, stroke: key, values: chart.data[i].filter((v) => v !== null && v !== undefined).length,
                     sum: chart.data[i].reduce((a, v) => a + (typeof v === 'number' ? v : 0), 0),
                     colour_pixels: c ? counted[key] : null});
      });
    }
    const caption = box.querySelector('.caption');
    return {id: box.id, painted, width: canvas.width, height: canvas.height, series,
            caption: caption ? caption.textContent : null};
  }));

  // what a page built without uPlot says in place of its plots (web/src/no-uplot.js)
  result.missing_plot_notes = await page.$$eval('.missing-plot', (els) => els.map((e) => e.textContent));

  // the episode table: the rows (first column, the episode) and the chosen column's cells before
  // and after one and two clicks on its header
  const column = Number(args['sort-column']);
  const rows = () => page.$$eval(`#episode-table tbody tr`, (trs, c) =>
    ({rows: trs.map((tr) => tr.children[0].textContent), cells: trs.map((tr) => tr.children[c].textContent)}), column);
  const header = page.locator('#episode-table thead th').nth(column);
  result.table = {header: await header.textContent(), before: await rows()};
  await header.click();
  result.table.first_click = {aria_sort: await header.getAttribute('aria-sort'), ...await rows()};
  await header.click();
  result.table.second_click = {aria_sort: await header.getAttribute('aria-sort'), ...await rows()};
  await page.locator('#episode-table thead th').nth(0).click();  // back to episode order

  if (args.seek) {
    await page.$$eval('video', (vs, f) => Promise.all(vs.map((v) => new Promise((done) => {
      v.addEventListener('seeked', done, {once: true});
      v.currentTime = v.duration * f;
    }))), Number(args.seek));
    // a still picture: the frame itself, without the player's controls (which a full-page
    // capture draws in their not-yet-loaded state)
    await page.$$eval('video', (vs) => vs.forEach((v) => { v.controls = false; }));
  }
  // the episode cards are content-visibility: auto (a 1,000-episode page lays out only those near
  // the viewport); a whole-page picture must draw them all, as scrolling to each would
  await page.addStyleTag({content: '.episode { content-visibility: visible !important; }'});
  await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done))));
  await page.screenshot({path: args.screenshot, fullPage: true});
  result.screenshot = resolve(args.screenshot);
} catch (e) {
  result.exception = String(e && e.stack || e);
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
process.stdout.write(JSON.stringify(result) + '\n');
process.exit(result.exception ? 1 : 0);
