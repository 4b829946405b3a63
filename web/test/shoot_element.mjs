// Photographs one element of a page in headless Chromium (Debian's, through playwright-core), for
// tools/docs-screenshots.sh: the page is opened (a deep link may follow '#'), the element waited
// for, and its screenshot written. Prints {"console_errors", "page_errors"} as JSON.
//   node shoot_element.mjs --page FILE.html#LINK --selector CSS --out FILE.png [--chromium PATH]
import {mkdtempSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join, resolve} from 'node:path';
import {pathToFileURL} from 'node:url';
import {chromium} from 'playwright-core';

const args = {chromium: '/usr/bin/chromium'};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
const [file, link] = args.page.split('#');
const profile = mkdtempSync(join(tmpdir(), 'fetchscope-chromium-'));
const result = {console_errors: [], page_errors: []};
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium, headless: true, viewport: {width: 1280, height: 900},
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--no-first-run'],
  });
  const page = context.pages()[0] || await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') result.console_errors.push(m.text()); });
  page.on('pageerror', (e) => result.page_errors.push(String(e)));
  await page.goto(pathToFileURL(resolve(file)).href + (link ? '#' + link : ''));
  const element = page.locator(args.selector);
  await element.waitFor({timeout: 30000});
  await element.scrollIntoViewIfNeeded();
  await page.waitForTimeout(300);
  await element.screenshot({path: args.out});
} catch (e) {
  result.page_errors.push(String(e));
} finally {
  if (context) await context.close();
  rmSync(profile, {recursive: true, force: true});
}
console.log(JSON.stringify(result));
