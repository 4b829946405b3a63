// Loads a fetchscope report or compare page in real headless Chromium (Debian's, through
// playwright-core) and prints what it found as one JSON object on stdout; the C++ test
// (tests/browser_test.cc) makes the assertions.
//   node check_page.mjs --page DIR/index.html --screenshot OUT.png [--sort-column N]
//        [--chromium /usr/bin/chromium] [--timeout-ms 30000] [--url http://... instead of file://]
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

  // every plot: its canvas and how many pixels uPlot painted
  result.plots = await page.$$eval('.plot', (boxes) => boxes.map((box) => {
    const canvas = box.querySelector('canvas');
    if (!canvas) return {id: box.id, painted: 0, width: 0, height: 0};
    const pixels = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
    let painted = 0;
    for (let i = 3; i < pixels.length; i += 4) painted += pixels[i] !== 0;
    return {id: box.id, painted, width: canvas.width, height: canvas.height};
  }));

  // the episode table: the chosen column's cells before and after one and two clicks on its header
  const column = Number(args['sort-column']);
  const cells = () => page.$$eval(`#episode-table tbody tr`, (trs, c) =>
    trs.map((tr) => tr.children[c].textContent), column);
  const header = page.locator('#episode-table thead th').nth(column);
  result.table = {header: await header.textContent(), before: await cells()};
  await header.click();
  result.table.first_click = {aria_sort: await header.getAttribute('aria-sort'), cells: await cells()};
  await header.click();
  result.table.second_click = {aria_sort: await header.getAttribute('aria-sort'), cells: await cells()};
  await page.locator('#episode-table thead th').nth(0).click();  // back to episode order

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
