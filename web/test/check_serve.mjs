// Drives fetchscope serve's page in real headless Chromium (Debian's, through playwright-core),
// as a user would over an ssh -L tunnel (a localhost URL), and prints what it found as one JSON
// object on stdout; tests/browser_test.cc makes the assertions.
//   node check_serve.mjs --url http://127.0.0.1:PORT/?token=T --out DIR [--keys w,w,w]
//        [--live-source N] [--chromium /usr/bin/chromium] [--timeout-ms 60000]
// Page A opens the URL (the token becomes a cookie), waits for the first lossless frame, drags
// across the live view (the camera text and the frame change; JPEG while moving, PNG at rest),
// hovers its centre (what the segmentation layer shows there), starts the live env of source N,
// presses each of --keys (one env step each), steps the policy once, steps back once, saves
// (the record command), and checks the --camera option the page shows. Page B (a second tab of
// the same browser) opens the page too: its session must differ and see nothing of A's live
// episode. Screenshots: DIR/serve_page.png (page A after the keys), DIR/frame_before.png and
// DIR/frame_after.png (the live view before and after the drag).
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join} from 'node:path';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', 'timeout-ms': '60000', keys: 'w,w,w,w,w', 'live-source': '1'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.url || !args.out) {
  console.error('usage: node check_serve.mjs --url URL --out DIR [--keys w,w] [--live-source N]');
  process.exit(2);
}
const timeout = Number(args['timeout-ms']);
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: [], foreign_requests: [], failed_responses: []};
let context;

const serveState = (page) => page.evaluate(() => {
  const s = window.fetchscopeServe;
  return {camera: s.state.camera, session: s.state.session, source: s.state.source, t: s.state.t,
          moving: s.state.moving, live_steps: s.state.live ? s.state.live.steps : null,
          received: s.stats.received, requested: s.stats.requested, dropped: s.stats.dropped,
          errors: s.stats.errors, last_error: s.stats.lastError, last_format: s.stats.lastFormat,
          last_camera: s.stats.lastCamera};
});

// waits until the frame of the view at rest (PNG) has arrived and nothing is on its way
async function atRest(page) {
  await page.waitForFunction(() => {
    const s = window.fetchscopeServe;
    return s && s.stats.received > 0 && s.stats.lastFormat === 'png' && !s.state.moving &&
        document.querySelector('img.serve-frame').complete;
  }, null, {timeout});
  await page.waitForTimeout(300);  // a frame still on its way would have started by now
  await page.waitForFunction(() => window.fetchscopeServe.stats.lastFormat === 'png', null, {timeout});
}

async function liveSteps(page) {
  return page.evaluate(() => Number(document.querySelector('.serve-live').dataset.steps || -1));
}

try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1400, height: 1000},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
  const origin = new URL(args.url).origin;
  const watch = (page) => {
    page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
    page.on('pageerror', (e) => result.page_errors.push(String(e)));
    page.on('response', async (r) => {
      if (r.status() >= 400) result.failed_responses.push(`${r.status()} ${r.url().replace(/session=[0-9a-f]+/, 'session=S')} ${await r.text().catch(() => '')}`);
    });
    page.on('request', (r) => { if (!r.url().startsWith(origin) && !r.url().startsWith('blob:') && !r.url().startsWith('data:')) result.foreign_requests.push(r.url()); });
  };
  const a = context.pages()[0] || await context.newPage();
  watch(a);
  await a.goto(args.url);
  result.url_after_token = a.url();
  await atRest(a);
  result.first = await serveState(a);
  const frame = a.locator('img.serve-frame');
  await frame.screenshot({path: join(args.out, 'frame_before.png')});

  // drag across the view: orbit
  const box = await frame.boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const before = await serveState(a);
  const formats = new Set();
  await a.mouse.move(cx, cy);
  await a.mouse.down();
  const dragStart = Date.now();
  for (let i = 1; i <= 40; i++) {
    await a.mouse.move(cx + 4 * i, cy + 1.5 * i);
    formats.add(await a.evaluate(() => window.fetchscopeServe.stats.lastFormat));
    await a.waitForTimeout(10);
  }
  const dragMs = Date.now() - dragStart;
  const during = await serveState(a);
  await a.mouse.up();
  await atRest(a);
  const after = await serveState(a);
  await frame.screenshot({path: join(args.out, 'frame_after.png')});
  result.drag = {camera_before: before.camera, camera_after: after.camera, shown_camera: after.last_camera,
                 frames_during: during.received - before.received, drag_ms: dragMs,
                 requested_during: during.requested - before.requested, formats: [...formats],
                 camera_option: await a.locator('.serve-camera-option').textContent(),
                 camera_input: await a.locator('input.serve-camera').inputValue()};

  // hover: the segmentation layer under the pointer
  await a.mouse.move(cx - 20, cy + 30);
  await a.mouse.move(cx - 21, cy + 30);
  // the text of the pick at that pixel (an earlier pick, at the drag's end, may answer first)
  const hoverBox = await frame.boundingBox();
  const [w, h] = await a.evaluate(() => [window.fetchscopeServe.state.width, window.fetchscopeServe.state.height]);
  const at = `${Math.floor((cx - 21 - hoverBox.x) * w / hoverBox.width)},${Math.floor((cy + 30 - hoverBox.y) * h / hoverBox.height)}`;
  await a.waitForFunction((want) => document.querySelector('.serve-hover').dataset.at === want, at, {timeout});
  result.hover = {text: await a.locator('.serve-hover').textContent(),
                  body: await a.evaluate(() => document.querySelector('.serve-hover').dataset.body),
                  at};

  // live: the env of --live-source, then the keys
  await a.locator(`button.serve-start-env[data-source="${args['live-source']}"]`).click();
  await a.waitForFunction(() => window.fetchscopeServe.state.live !== null, null, {timeout});
  result.live_start = await serveState(a);
  const keys = args.keys.split(',').filter(Boolean);
  const stepTimes = [];
  for (const key of keys) {
    const n = await liveSteps(a);
    const t0 = Date.now();
    await a.keyboard.press(key);
    await a.waitForFunction((m) => Number(document.querySelector('.serve-live').dataset.steps) === m + 1, n, {timeout});
    await atRest(a);
    stepTimes.push(Date.now() - t0);
  }
  result.key_step_ms = stepTimes;
  result.live_rows = await a.evaluate(() => window.fetchscopeServe.state.live.rows.map((r) => r.achieved_goal));
  result.live_actions = await a.evaluate(() => window.fetchscopeServe.state.live.signals.action);
  await a.screenshot({path: join(args.out, 'serve_page.png'), fullPage: true});
  // the policy once, then back once: the step count goes up and down again
  const n0 = await liveSteps(a);
  await a.keyboard.press('p');
  await a.waitForFunction((m) => Number(document.querySelector('.serve-live').dataset.steps) === m + 1, n0, {timeout});
  await a.keyboard.press('b');
  await a.waitForFunction((m) => Number(document.querySelector('.serve-live').dataset.steps) === m, n0, {timeout});
  result.after_policy_and_back = await liveSteps(a);
  // save: the files and the record command
  await a.locator('button.serve-save-button').click();
  await a.waitForFunction(() => document.querySelector('.serve-save').dataset.command !== undefined, null, {timeout});
  result.save = await a.evaluate(() => {
    const d = document.querySelector('.serve-save').dataset;
    return {command: d.command, episode_file: d.episodeFile, files: JSON.parse(d.files || '[]'),
            shown: document.querySelector('.serve-command') ? document.querySelector('.serve-command').textContent : ''};
  });
  result.page_a = await serveState(a);

  // a second page: its own session, none of A's live episode
  const b = await context.newPage();
  watch(b);
  await b.goto(origin + '/');
  await atRest(b);
  result.page_b = await serveState(b);
  result.page_b.has_live = await b.evaluate(() => window.fetchscopeServe.state.live !== null);
} catch (e) {
  result.error = String(e && e.stack || e);
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
console.log(JSON.stringify(result));
