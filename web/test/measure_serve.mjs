// Measures fetchscope serve's page in headless Chromium (Debian's, through playwright-core), for
// tools/bench-serve.sh. Prints one JSON object:
//   node measure_serve.mjs --url http://127.0.0.1:PORT/?token=T [--drag-s 4] [--keys 10]
//        (the first URL is visited once, in a tab of its own, for the cookie)
//        [--live-source N] [--chromium /usr/bin/chromium]
// "open": from the navigation's start to the first lossless frame on screen (the performance mark
// fetchscope-serve-first-frame), to the load event, and to every episode listed (the tables are
// drawn after the first frame); "drag": the mouse moves at 60 Hz across the
// view for --drag-s seconds and the frames that reach the screen meanwhile are counted (each a
// JPEG of a newer camera; the page keeps one request in flight); "key_step": from a key press to
// the new step's frame on screen, --keys times (live env of source N); "seek": → to the next
// step's frame on screen, 10 times.
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join} from 'node:path';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', 'drag-s': '4', keys: '10', 'live-source': '1'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {errors: []};
const summary = (v) => {
  const s = v.slice().sort((a, b) => a - b);
  const at = (q) => s[Math.min(s.length - 1, Math.round(q * (s.length - 1)))];
  return {n: s.length, p50: at(0.5), p95: at(0.95), mean: s.reduce((a, b) => a + b, 0) / s.length};
};
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1400, height: 1000},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
  // the token becomes a cookie on a first tab; the page is then opened afresh in a second one (a
  // browser that has the cookie, as after the first visit)
  const first = context.pages()[0] || await context.newPage();
  await first.goto(args.url, {waitUntil: 'load'});
  await first.close();
  const page = await context.newPage();
  page.on('pageerror', (e) => result.errors.push(String(e)));
  await page.goto(new URL(args.url).origin + '/', {waitUntil: 'load'});
  await page.waitForFunction(() => performance.getEntriesByName('fetchscope-serve-first-frame').length > 0 &&
      performance.getEntriesByName('fetchscope-serve-listed').length > 0, null, {timeout: 60000});
  result.open = await page.evaluate(() => {
    const nav = performance.getEntriesByType('navigation')[0];
    const mark = (name) => (performance.getEntriesByName(name)[0] || {}).startTime;
    return {first_frame_ms: mark('fetchscope-serve-first-frame'), script_ms: mark('fetchscope-serve-script'),
            built_ms: mark('fetchscope-serve-built'), request_start_ms: nav.requestStart, response_end_ms: nav.responseEnd,
            dom_content_loaded_ms: nav.domContentLoadedEventEnd, listed_ms: mark('fetchscope-serve-listed'),
            load_ms: nav.loadEventEnd, episodes_listed: document.querySelectorAll('.serve-source tbody tr').length};
  });
  // the episode browser: every episode's columns (GET /api/listing, then the table redrawn),
  // then a filter typed: from the keystroke to the table drawn (the box waits 120 ms for more
  // keys first), and the draw alone
  await page.waitForFunction(() => performance.getEntriesByName('fetchscope-serve-columns').length > 0, null, {timeout: 120000});
  result.browser = await page.evaluate(() => {
    const listing = performance.getEntriesByType('resource').find((e) => e.name.includes('/api/listing'));
    const draws = performance.getEntriesByName('fetchscope-serve-browser-drawn');
    return {columns_ms: performance.getEntriesByName('fetchscope-serve-columns')[0].startTime,
            listing_request_ms: listing ? listing.duration : null, columns_draw_ms: draws[draws.length - 1].duration,
            rows: document.querySelectorAll('.serve-browser tbody tr').length};
  });
  for (const text of ['distance > 0.05', 'success = no, first_success > 10']) {
    const before = await page.evaluate(() => performance.getEntriesByName('fetchscope-serve-browser-drawn').length);
    const typed = await page.evaluate((t) => {
      const box = document.querySelector('.serve-filter');
      box.value = t;
      const at = performance.now();
      box.dispatchEvent(new Event('input', {bubbles: true}));
      return at;
    }, text);
    await page.waitForFunction((n) => performance.getEntriesByName('fetchscope-serve-browser-drawn').length > n, before, {timeout: 60000});
    result.browser[text] = await page.evaluate((at) => {
      const draws = performance.getEntriesByName('fetchscope-serve-browser-drawn');
      const last = draws[draws.length - 1];
      return {typed_to_drawn_ms: last.startTime + last.duration - at, draw_ms: last.duration,
              shown: Number(document.querySelector('.serve-browser').dataset.shown)};
    }, typed);
  }
  await page.evaluate(() => {
    const box = document.querySelector('.serve-filter');
    box.value = '';
    box.dispatchEvent(new Event('input', {bubbles: true}));
  });
  await page.waitForTimeout(500);
  // drag at the display's rate: a pointer move each animation frame (60 Hz headless), dispatched
  // on the view as the browser dispatches a real drag's
  const before = await page.evaluate(() => window.fetchscopeServe.stats.shown.length);
  const [t0, t1] = await page.evaluate((ms) => new Promise((done) => {
    const image = document.querySelector('img.serve-frame');
    const box = image.getBoundingClientRect();
    const cx = box.left + box.width / 2, cy = box.top + box.height / 2;
    const fire = (type, x, y) => image.dispatchEvent(new PointerEvent(type, {bubbles: true, clientX: x, clientY: y, pointerId: 1, button: 0, buttons: 1}));
    image.setPointerCapture = () => {};  // a synthetic pointer has nothing to capture
    fire('pointerdown', cx, cy);
    const start = performance.now();
    let i = 0;
    const frame = () => {
      const now = performance.now();
      if (now - start > ms) { fire('pointerup', cx, cy); done([start, now]); return; }
      i += 1;
      fire('pointermove', cx + 200 * Math.sin(i / 30), cy + 60 * Math.cos(i / 45));
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  }), Number(args['drag-s']) * 1000);
  result.drag = await page.evaluate(([from, a, b]) => {
    const s = window.fetchscopeServe.stats;
    const shown = s.shown.slice(from).filter((f) => f.at >= a && f.at <= b);
    const gaps = shown.slice(1).map((f, i) => f.at - shown[i].at);
    return {seconds: (b - a) / 1000, frames: shown.length, frames_per_s: shown.length / ((b - a) / 1000),
            jpeg: shown.filter((f) => f.format === 'jpeg').length, cameras: new Set(shown.map((f) => f.camera)).size,
            stale_replaced: s.dropped, max_gap_ms: Math.max(0, ...gaps),
            round_trip_ms_p50: s.roundTripMs.slice(-shown.length).sort((x, y) => x - y)[Math.floor(shown.length / 2)],
            server_render_ms_p50: s.renderMs.slice(-shown.length).sort((x, y) => x - y)[Math.floor(shown.length / 2)]};
  }, [before, t0, t1]);
  await page.waitForTimeout(500);
  // a seek: → one step, to the frame on screen
  const seek = [];
  for (let i = 0; i < 10; i++) {
    const n = await page.evaluate(() => window.fetchscopeServe.stats.shown.length);
    const want = await page.evaluate(() => window.fetchscopeServe.state.t + 1);
    const start = await page.evaluate(() => performance.now());
    await page.keyboard.press('ArrowRight');
    await page.waitForFunction(([m, w]) => window.fetchscopeServe.stats.shown.slice(m).some((f) => f.step === w), [n, want], {timeout: 30000});
    seek.push(await page.evaluate(([m, w]) => window.fetchscopeServe.stats.shown.slice(m).find((f) => f.step === w).at, [n, want]) - start);
  }
  result.seek_ms = summary(seek);
  // live key steps
  await page.locator(`button.serve-start-env[data-source="${args['live-source']}"]`).click();
  await page.waitForFunction(() => window.fetchscopeServe.state.live !== null);
  await page.waitForTimeout(500);
  const steps = [];
  for (let i = 0; i < Number(args.keys); i++) {
    const n = await page.evaluate(() => window.fetchscopeServe.stats.shown.length);
    const want = await page.evaluate(() => window.fetchscopeServe.state.live.steps + 1);
    const start = await page.evaluate(() => performance.now());
    await page.keyboard.press(i % 2 ? 'a' : 'w');
    await page.waitForFunction(([m, w]) => window.fetchscopeServe.stats.shown.slice(m).some((f) => f.step === w), [n, want], {timeout: 30000});
    steps.push(await page.evaluate(([m, w]) => window.fetchscopeServe.stats.shown.slice(m).find((f) => f.step === w).at, [n, want]) - start);
    await page.waitForTimeout(200);
  }
  result.key_step_ms = summary(steps);
} catch (e) {
  result.errors.push(String(e && e.stack || e));
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
console.log(JSON.stringify(result));
