// Opens golden check's (or update's) review page (OUT/index.html) in headless Chromium (Debian's,
// through playwright-core) and reports what a reviewer sees, for tests/browser_golden_test.cc
// and tools/docs-screenshots.sh: each scene section (its heading, its images loaded or not and
// their shown size, the changed-region box's rectangle and whether it lies inside its image),
// the diff scale, console and page errors, and requests leaving the page's folder. Writes a
// screenshot of the whole page. Prints one JSON object.
//   node check_golden_review.mjs --page OUT/index.html --screenshot FILE.png [--chromium PATH]
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join, resolve} from 'node:path';
import {pathToFileURL} from 'node:url';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: [], network_requests: []};
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1100, height: 800},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run'],
  });
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
  page.on('pageerror', (e) => result.page_errors.push(String(e)));
  page.on('request', (r) => { if (!/^(file|data):/.test(r.url())) result.network_requests.push(r.url()); });
  await page.goto(pathToFileURL(resolve(args.page)).href, {waitUntil: 'load', timeout: 30000});
  result.title = await page.title();
  result.sections = await page.$$eval('section', (sections) => sections.map((s) => ({
    id: s.id, status: s.className, heading: s.querySelector('h2').textContent,
    items: [...s.querySelectorAll('li')].map((li) => li.textContent),
    figures: [...s.querySelectorAll('figure')].map((f) => {
      const img = f.querySelector('img');
      const box = f.querySelector('.box');
      const ir = img.getBoundingClientRect();
      const br = box ? box.getBoundingClientRect() : null;
      return {caption: f.querySelector('figcaption').textContent, src: img.getAttribute('src'),
              complete: img.complete, natural_width: img.naturalWidth, shown_width: ir.width,
              box: br ? {x: br.x - ir.x, y: br.y - ir.y, width: br.width, height: br.height,
                         inside: br.x >= ir.x - 0.5 && br.y >= ir.y - 0.5 &&
                                 br.right <= ir.right + 0.5 && br.bottom <= ir.bottom + 0.5,
                         border: getComputedStyle(box).borderTopWidth} : null};
    }),
  })));
  result.scale = await page.$eval('.scale img', (img) => ({complete: img.complete, natural_width: img.naturalWidth,
    ticks: [...document.querySelectorAll('.ticks span')].map((s) => s.textContent)}));
  result.others = await page.$$eval('#others li', (lis) => lis.map((li) => li.textContent));
  await page.screenshot({path: args.screenshot, fullPage: true});
} catch (e) {
  result.page_errors.push(String(e));
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
console.log(JSON.stringify(result));
