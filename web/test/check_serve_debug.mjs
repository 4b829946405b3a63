// Drives serve's page as a researcher debugging a policy would (docs/guide/serve.md, "Debugging
// a policy"), in real headless Chromium, and prints what it found as one JSON object on stdout;
// tests/browser_test.cc makes the assertions.
//   node check_serve_debug.mjs --url http://127.0.0.1:PORT/?token=T --out DIR --steps 3,17,40
//        [--live-source 1] [--chromium /usr/bin/chromium] [--timeout-ms 90000]
// 1. The step inspector of the first served episode at each of --steps: every field's value.
//    A click on obs[5] plots it over the episode. The overlays the view cannot apply. The episode
//    browser's filters (--filters, separated by |): the episodes each leaves.
// 2. A grasp from the keys on the live env (--live-source, PickAndPlace): open, chords of two
//    axes over the block, down, close (latched), four lift presses; each step's row.
// 3. Play the policy from the reset: it stops at the TimeLimit. Play again (past it), Save while
//    it plays, then pause: nine pause clicks, each must stop the steps.
// 4. Unsaved steps: closing the page asks first (a beforeunload dialog).
// 5. 13 pages opened and closed one after another: the last still gets a live session.
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join} from 'node:path';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium', 'timeout-ms': '90000', steps: '3,17,40', 'live-source': '1'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.url || !args.out) {
  console.error('usage: node check_serve_debug.mjs --url URL --out DIR [--steps 3,17,40]');
  process.exit(2);
}
const timeout = Number(args['timeout-ms']);
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: [], failed_responses: []};
let context;

const liveSteps = (page) => page.evaluate(() => Number(document.querySelector('.serve-live').dataset.steps || -1));
const lastRow = (page) => page.evaluate(() => {
  const rows = window.fetchscopeServe.state.live.rows;
  return rows[rows.length - 1];
});
// One env step with every key of `keys` pressed at once: a single key through the keyboard; a
// chord as its key events dispatched together (two real presses are two CDP calls apart, which
// a loaded machine can stretch past the page's chord window)
async function press(page, keys) {
  const n = await liveSteps(page);
  if (keys.length === 1) {
    await page.keyboard.press(keys[0]);
  } else {
    await page.evaluate((ks) => {
      for (const key of ks) document.dispatchEvent(new KeyboardEvent('keydown', {key, bubbles: true}));
      for (const key of ks) document.dispatchEvent(new KeyboardEvent('keyup', {key, bubbles: true}));
    }, keys);
  }
  await page.waitForFunction((m) => Number(document.querySelector('.serve-live').dataset.steps) >= m + 1, n, {timeout});
  await page.waitForTimeout(CHORD_SETTLE_MS);
  return (await liveSteps(page)) - n;  // the steps it took: 1
}
const CHORD_SETTLE_MS = 120;

try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1400, height: 1000},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--no-first-run'],
  });
  const watch = (page) => {
    page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
    page.on('pageerror', (e) => result.page_errors.push(String(e)));
    page.on('response', async (r) => {
      if (r.status() >= 400) result.failed_responses.push(`${r.status()} ${r.url().replace(/session=[0-9a-f]+/, 'session=S')} ${await r.text().catch(() => '')}`);
    });
  };
  const origin = new URL(args.url).origin;
  const a = context.pages()[0] || await context.newPage();
  watch(a);
  await a.goto(args.url);
  await a.waitForFunction(() => window.fetchscopeServe && window.fetchscopeServe.state.rows && window.fetchscopeServe.viewer, null, {timeout});

  // 1. the inspector at each step
  result.inspector = {};
  for (const t of args.steps.split(',').map(Number)) {
    await a.evaluate((step) => window.fetchscopeServe.viewer.seek(step), t);
    await a.waitForFunction((step) => document.querySelector('.serve-inspector').dataset.t === String(step), t, {timeout});
    result.inspector[t] = await a.evaluate(() => Object.fromEntries(
        [...document.querySelectorAll('.serve-fields tr[data-field]')].map((r) => [r.dataset.field, JSON.parse(r.dataset.value)])));
  }
  await a.locator('.serve-fields tr[data-field^="obs[5] "]').click();
  result.field_plot = await a.evaluate(() => ({...document.querySelector('.serve-field-plot').dataset}));
  result.overlays = await a.evaluate(() => Object.fromEntries(
      [...document.querySelectorAll('.serve-row input[type=checkbox]')].filter((b) => b.value)
          .map((b) => [b.value, {disabled: b.disabled, reason: b.dataset.reason || ''}])));
  await a.locator('.serve-side').screenshot({path: join(args.out, 'inspector.png')});

  // 1b. the episode browser: its columns from the episodes' rows, then filters
  await a.waitForFunction(() => document.querySelector('.serve-browser') &&
                                document.querySelector('.serve-browser').dataset.columns === 'full', null, {timeout});
  result.browser_headers = await a.evaluate(() => [...document.querySelectorAll('.serve-browser th')].map((h) => h.textContent));
  result.filters = {};
  for (const f of (args.filters || 'success = no|distance > 0.05|grasped|bogus > 1').split('|')) {
    await a.locator('.serve-filter').fill(f);
    await a.waitForTimeout(400);
    result.filters[f] = await a.evaluate(() => ({
      shown: Number(document.querySelector('.serve-browser').dataset.shown),
      note: document.querySelector('.serve-filter-note').textContent,
      episodes: [...document.querySelectorAll('.serve-browser tbody tr a[data-episode]')].map((x) => Number(x.dataset.episode)),
    }));
  }
  await a.locator('.serve-filter').fill('');

  // 1c. side by side: episode 1 beside episode 0, in step at t = 10 and 30
  await a.locator('select.serve-other-select').selectOption('0/1');
  result.side_by_side = [];
  for (const t of [10, 30]) {
    await a.evaluate((step) => window.fetchscopeServe.viewer.seek(step), t);
    await a.waitForFunction((step) => document.querySelector('img.serve-other-frame').dataset.step === String(step) &&
                                      document.querySelector('img.serve-frame').dataset.step === String(step), t, {timeout});
    result.side_by_side.push(await a.evaluate(() => ({
      main: document.querySelector('img.serve-frame').dataset.step,
      other: document.querySelector('img.serve-other-frame').dataset.step,
      first_step: document.querySelector('.serve-other-diff').dataset.firstStep,
      first_field: document.querySelector('.serve-other-diff').dataset.firstField,
      text: document.querySelector('.serve-first-difference').textContent,
    })));
  }
  // its own camera: the second view alone changes
  const mainCamera = await a.evaluate(() => document.querySelector('img.serve-frame').dataset.camera);
  await a.locator('input.serve-other-camera').fill('external_camera_0');
  await a.locator('input.serve-other-camera').dispatchEvent('change');
  await a.waitForFunction(() => document.querySelector('img.serve-other-frame').dataset.camera === 'external_camera_0', null, {timeout});
  result.side_by_side_cameras = await a.evaluate((before) => ({
    main_before: before, main: document.querySelector('img.serve-frame').dataset.camera,
    other: document.querySelector('img.serve-other-frame').dataset.camera}), mainCamera);
  await a.screenshot({path: join(args.out, 'side_by_side.png'), fullPage: false});
  await a.locator('select.serve-other-select').selectOption('');

  // 1d. the look control: a draw by seed, another draw, then the episode's own (plain here)
  const lookShown = () => a.evaluate(() => ({seed: document.querySelector('.serve-look-shown').dataset.seed,
                                              text: document.querySelector('.serve-look-shown').textContent}));
  result.looks = [];
  await a.locator('select.serve-look').selectOption('draw');
  await a.waitForFunction(() => document.querySelector('.serve-look-shown').dataset.seed, null, {timeout});
  result.looks.push(await lookShown());
  await a.locator('button.serve-look-next').click();
  await a.waitForFunction((s) => document.querySelector('.serve-look-shown').dataset.seed !== s, result.looks[0].seed, {timeout});
  result.looks.push(await lookShown());
  await a.locator('select.serve-look').selectOption('');
  await a.waitForFunction(() => document.querySelector('.serve-look-shown').dataset.seed === '', null, {timeout});
  result.looks.push(await lookShown());

  // 2. a grasp from the keys: open, over the block with two-axis chords, down, close, lift x4
  await a.locator(`button.serve-start-env[data-source="${args['live-source']}"]`).click();
  await a.waitForFunction(() => window.fetchscopeServe.state.live !== null, null, {timeout});
  await a.locator('select[aria-label="step size"]').selectOption('0.25');
  await a.locator('img.serve-frame').hover();  // the keys go to the page, not a control
  await a.mouse.click(5, 5);
  await press(a, ['o']);
  result.chords = 0;
  result.press_steps = [];
  for (let i = 0; i < 40; i++) {  // over the block: both horizontal axes in one step where both are off
    const row = await lastRow(a);
    const dx = row.observation[3] - row.observation[0], dy = row.observation[4] - row.observation[1];
    const keys = [];
    if (Math.abs(dx) > 0.006) keys.push(dx > 0 ? 'w' : 's');
    if (Math.abs(dy) > 0.006) keys.push(dy > 0 ? 'a' : 'd');
    if (!keys.length) break;
    result.press_steps.push(await press(a, keys));
    const action = (await lastRow(a)).action;
    if (keys.length === 2 && action[0] !== 0 && action[1] !== 0) result.chords++;
  }
  for (let i = 0; i < 30; i++) {  // down to the block's height
    const row = await lastRow(a);
    if (row.observation[2] - row.observation[5] < 0.005) break;
    await press(a, ['f']);
  }
  for (let i = 0; i < 4; i++) await press(a, ['c']);  // close on it (each press a step)
  result.closed = await lastRow(a);
  result.gripper_state = await a.evaluate(() => document.querySelector('.serve-gripper').dataset.command);
  result.lifts = [];
  for (let i = 0; i < 4; i++) {
    await press(a, ['r']);
    result.lifts.push(await lastRow(a));
  }
  result.lift_actions = await a.evaluate(() => window.fetchscopeServe.state.live.rows.slice(-4).map((r) => r.action));
  await a.screenshot({path: join(args.out, 'grasp.png'), fullPage: false});

  // 2b. a placed reset: the block typed, the goal clicked on the view (the pick's world point)
  await a.locator('details.serve-place summary').first().click();
  await a.locator('input[aria-label="block x"]').fill(args['block-x'] || '1.25');
  await a.locator('input[aria-label="block y"]').fill(args['block-y'] || '0.85');
  for (const axis of ['x', 'y', 'z']) await a.locator(`input[aria-label="goal ${axis}"]`).fill('');
  // a pixel on the table's top: hovered until the pick names the table
  const view = await a.locator('img.serve-frame').boundingBox();
  let at = null;
  for (const [fx, fy] of [[0.5, 0.62], [0.5, 0.7], [0.4, 0.66], [0.6, 0.66], [0.5, 0.55], [0.45, 0.75]]) {
    const p = {x: Math.round(view.x + view.width * fx), y: Math.round(view.y + view.height * fy)};
    await a.mouse.move(p.x, p.y);
    await a.waitForFunction(() => document.querySelector('.serve-hover').dataset.body !== undefined &&
                                  document.querySelector('.serve-hover').dataset.at !== '', null, {timeout});
    await a.waitForTimeout(300);
    if (await a.evaluate(() => document.querySelector('.serve-hover').dataset.body) === 'table0') { at = p; break; }
  }
  result.place_clicked_table = at !== null;
  await a.locator('button.serve-place-pick-goal').click();
  await a.mouse.click(at.x, at.y);
  await a.waitForFunction(() => document.querySelector('input[aria-label="goal z"]').value !== '', null, {timeout});
  result.place_fields = await a.evaluate(() => ['block x', 'block y', 'goal x', 'goal y', 'goal z']
      .map((l) => Number(document.querySelector(`input[aria-label="${l}"]`).value)));
  await a.locator('button.serve-start-placed').click();
  await a.waitForFunction(() => window.fetchscopeServe.state.live && window.fetchscopeServe.state.live.placed, null, {timeout});
  result.placed_reset = await a.evaluate(() => window.fetchscopeServe.state.live.rows[0]);
  result.placed_info = await a.evaluate(() => document.querySelector('.serve-live p.caption').textContent);

  // 3. the policy from the reset stops at the TimeLimit; past it, Save during play, pause x9
  await a.locator(`button.serve-start-env[data-source="${args['live-source']}"]`).click();
  await a.waitForFunction(() => window.fetchscopeServe.state.live && window.fetchscopeServe.state.live.steps === 0, null, {timeout});
  await a.locator('button.serve-play-policy').click();
  await a.waitForFunction(() => document.querySelector('.serve-play-policy').dataset.playing === 'false' &&
                                window.fetchscopeServe.state.live.steps > 0, null, {timeout: 5 * timeout});
  result.stopped_at = await liveSteps(a);
  await a.locator('input.serve-past-limit').check();
  result.pauses = [];
  for (let i = 0; i < 9; i++) {
    await a.locator('button.serve-play-policy').click();
    const start = await liveSteps(a);
    await a.waitForFunction((m) => Number(document.querySelector('.serve-live').dataset.steps) >= m + 2, start, {timeout});
    if (i === 0) {  // Save while it plays
      await a.locator('button.serve-save-button').click();
      await a.waitForFunction(() => document.querySelector('.serve-save').dataset.steps !== undefined, null, {timeout});
      result.saved_during_play = await a.evaluate(() => ({...document.querySelector('.serve-save').dataset}));
    }
    await a.locator('button.serve-play-policy').click();  // pause
    await a.waitForFunction(() => document.querySelector('.serve-play-policy').dataset.playing === 'false', null, {timeout});
    const paused = await liveSteps(a);
    await a.waitForTimeout(400);
    result.pauses.push({paused, later: await liveSteps(a)});
  }

  // 4. unsaved steps: closing the page asks first
  await press(a, ['w']);
  const dialogs = [];
  a.on('dialog', async (d) => { dialogs.push(d.type()); await d.dismiss(); });
  await a.close({runBeforeUnload: true});
  await new Promise((done) => setTimeout(done, 1000));
  result.unsaved_close_dialogs = dialogs;
  result.page_still_open = !a.isClosed();

  // 5. 13 pages, each closed before the next: the last still gets a live session
  result.pages = [];
  for (let i = 0; i < 13; i++) {
    const p = await context.newPage();
    watch(p);
    await p.goto(origin + '/');
    await p.waitForFunction(() => window.fetchscopeServe && window.fetchscopeServe.state.session, null, {timeout});
    if (i === 12) {
      await p.locator(`button.serve-start-env[data-source="${args['live-source']}"]`).click();
      await p.waitForFunction(() => window.fetchscopeServe.state.live !== null, null, {timeout});
      result.last_page_live = await p.evaluate(() => window.fetchscopeServe.state.live.steps);
    }
    result.pages.push(await p.evaluate(() => window.fetchscopeServe.stats.errors));
    await p.close();
  }
  // the page that was kept open (it dismissed the dialog) is closed for good now
  if (!a.isClosed()) await a.close();
} catch (e) {
  result.error = String(e && e.stack || e);
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
console.log(JSON.stringify(result));
