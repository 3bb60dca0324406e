// End to end in a browser: `lightstage serve --simulated` at 128x128, driven
// in headless Chromium (Debian's, through playwright-core) as an operator
// would: take control, light an LED on the map, take a live frame, calibrate
// (the chrome sphere captured at two positions, its outline moved by hand on
// one), capture the object, solve it with the calibration, export a PTM and
// open the report. No console errors, no request off the station; a
// screenshot of each page in SCRATCH/.
//
// Environment (tests/station/CMakeLists.txt):
//   LIGHTSTAGE_BIN, LIGHTSTAGE_NODE_DEPS (playwright-core), LIGHTSTAGE_SCRATCH, LIGHTSTAGE_CHROMIUM
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';

const env = (name, fallback) => {
  const value = process.env[name] ?? fallback;
  if (value === undefined) throw new Error(`the test needs ${name} in its environment`);
  return value;
};
const bin = env('LIGHTSTAGE_BIN');
const scratch = env('LIGHTSTAGE_SCRATCH');
const chromiumPath = env('LIGHTSTAGE_CHROMIUM', '/usr/bin/chromium');
const require = createRequire(path.join(env('LIGHTSTAGE_NODE_DEPS'), 'package.json'));
const { chromium } = require('playwright-core');

// Starts the station; resolves with its address once it printed it.
function startStation(data, more = []) {
  const child = spawn(bin, ['serve', '--simulated', '--width', '128', '--height', '128', '--noise', 'none',
    '--listen', '127.0.0.1:0', '--data', data, ...more], { stdio: ['ignore', 'pipe', 'pipe'] });
  let output = '';
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no address from lightstage serve:\n${output}`)), 60000);
    const read = (chunk) => {
      output += chunk;
      const match = output.match(/the station is at (http:\/\/\S+)/);
      if (match) {
        clearTimeout(timer);
        resolve({ child, url: match[1], output: () => output });
      }
    };
    child.stdout.on('data', read);
    child.stderr.on('data', read);
    child.on('exit', (code) => reject(new Error(`lightstage serve exited ${code}:\n${output}`)));
  });
}

// Clicks what starts a job and waits for the job bar to show it (a new job id).
async function startJob(page, click) {
  const before = await page.$eval('body', () => document.querySelector('#job')?.dataset.id ?? '');
  await click();
  await page.waitForFunction((before) => {
    const id = document.querySelector('#job')?.dataset.id;
    return id && id !== before;
  }, before, { timeout: 30000 });
}

// Waits for the job bar to show the job ended, and says how.
async function jobEnds(page, timeout = 180000) {
  await page.waitForFunction(() => {
    const state = document.querySelector('#job-state')?.textContent;
    return state && state !== 'running';
  }, null, { timeout });
  const state = await page.textContent('#job-state');
  const error = await page.$eval('#job', (e) => e.querySelector('.job-error')?.textContent ?? '');
  assert.equal(state, 'done', `the job ended ${state}: ${error}`);
}

test('an operator runs the simulated dome from the page, calibration to report', { timeout: 900000 }, async () => {
  fs.rmSync(scratch, { recursive: true, force: true });
  fs.mkdirSync(scratch, { recursive: true });
  const station = await startStation(path.join(scratch, 'data'));
  const origin = new URL(station.url).origin;
  const browser = await chromium.launch({
    executablePath: chromiumPath,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
  const problems = [];
  const watch = (page, name) => {
    page.on('console', (m) => { if (m.type() === 'error') problems.push(`${name} console: ${m.text()}`); });
    page.on('pageerror', (e) => problems.push(`${name} page error: ${e.message}`));
    page.on('request', (r) => {
      const url = r.url();
      if (!url.startsWith(origin) && !url.startsWith('data:') && !url.startsWith('blob:')) problems.push(`${name} left the station: ${url}`);
    });
  };
  try {
    const context = await browser.newContext({ viewport: { width: 1280, height: 900 } });
    const page = await context.newPage();
    watch(page, 'station');
    await page.goto(station.url);
    await page.waitForSelector('#led-map circle[data-led]');
    assert.match(await page.textContent('#dome-state'), /dome idle/);
    // The token-free loopback station: read-only until control is taken.
    assert.ok(await page.isDisabled('#test-sequence'));
    await page.fill('#operator-name', 'Ann');
    await page.click('#take-control');
    await page.waitForSelector('#release');

    // A second operator's tab: read-only while Ann has control.
    const other = await (await browser.newContext({ viewport: { width: 1280, height: 900 } })).newPage();
    watch(other, 'second tab');
    await other.goto(station.url);
    await other.waitForFunction(() => /Ann controls the dome/.test(document.querySelector('.role.viewer')?.textContent ?? ''));
    assert.ok(await other.isDisabled('#test-sequence'));
    assert.equal(await other.$$eval('#led-map circle.pickable', (c) => c.length), 0);
    await other.screenshot({ path: path.join(scratch, 'viewer.png') });
    await other.close();

    // Dome: an LED lit from the map, then put out.
    await page.click('#led-map circle[data-led="5"]');
    await page.waitForFunction(() => document.querySelector('#leds-on')?.textContent.trim() === '5');
    await page.waitForSelector('#led-map circle[data-led="5"].lit');
    await page.screenshot({ path: path.join(scratch, 'dome.png') });
    await page.click('#led-map circle[data-led="5"]');
    await page.waitForFunction(() => document.querySelector('#leds-on')?.textContent.trim() === 'none');

    // Live view: a frame with its histogram and figures.
    await page.click('#tab-live');
    await page.fill('#live-led', '40');
    await page.fill('#live-exposure', '20000');
    await page.click('#live-take');
    await page.waitForSelector('#live-image');
    await page.waitForFunction(() => document.querySelector('#live-image').naturalWidth === 128);
    const sharpness = parseFloat(await page.textContent('#live-sharpness'));
    assert.ok(sharpness > 0, `sharpness ${sharpness}`);
    await page.screenshot({ path: path.join(scratch, 'live.png') });

    // Calibration: the sphere at two positions, each captured; one outline moved by hand.
    await page.click('#tab-calibration');
    for (const k of [1, 2]) {
      await page.click(`.step button.place[data-place="chrome-${k}"]`);
      await page.waitForFunction((k) => document.querySelector(`.step button.place[data-place="chrome-${k}"]`)?.disabled, k);
      await startJob(page, () => page.click(`button.capture-sphere[data-stack="chrome-${k}"]`));
      await jobEnds(page);
      await page.waitForSelector(`.sphere-editor[data-stack="chrome-${k}"] .sphere-outline`);
    }
    const editor = '.sphere-editor[data-stack="chrome-1"]';
    const found = await (await fetch(`${origin}/api/stacks/chrome-1/sphere`)).json();
    assert.ok(found.circle, `the sphere was not found: ${found.error}`);
    // Drag the outline by (1, 1) image pixels and keep it: the calibration uses what was drawn.
    const box = await page.$eval(`${editor} svg.outline`, (svg) => {
      const r = svg.getBoundingClientRect();
      return { x: r.x, y: r.y, w: r.width, h: r.height };
    });
    const scale = box.w / found.width;
    const from = { x: box.x + found.circle.x_px * scale, y: box.y + found.circle.y_px * scale };
    await page.mouse.move(from.x, from.y);
    await page.mouse.down();
    await page.mouse.move(from.x + scale * 0.5, from.y + scale * 0.5, { steps: 3 });
    await page.mouse.move(from.x + scale, from.y + scale, { steps: 3 });
    await page.mouse.up();
    await page.click(`${editor} .sphere-save`);
    await page.waitForFunction((e) => document.querySelector(`${e} p`)?.textContent.includes('as drawn'), editor);
    const drawn = await (await fetch(`${origin}/api/stacks/chrome-1/sphere`)).json();
    assert.ok(drawn.drawn);
    assert.ok(Math.abs(drawn.circle.x_px - found.circle.x_px - 1) < 0.75,
      `moved by ${drawn.circle.x_px - found.circle.x_px} px, not 1`);
    // A pixel off is far too much for LED positions: forget the drawing, detect again.
    await page.click(`${editor} .sphere-forget`);
    await page.waitForFunction((e) => document.querySelector(`${e} p`)?.textContent.includes('Sphere found'), editor);
    const again = await (await fetch(`${origin}/api/stacks/chrome-1/sphere`)).json();
    assert.equal(again.drawn, false);
    assert.ok(Math.abs(again.circle.x_px - found.circle.x_px) < 1e-6);
    await startJob(page, () => page.click('#calibrate'));
    await jobEnds(page);
    await page.waitForSelector('#calibration-result img');
    await page.waitForFunction(() => document.querySelector('#calibration-result img').naturalWidth > 0);
    await page.waitForFunction(() => /96 of 96 lights measured/.test(document.querySelector('#calibration-result').textContent));
    // The simulator's LEDs are where the rig says: the calibrated directions must agree.
    const rig = await (await fetch(`${origin}/api/rig`)).json();
    const calibration = JSON.parse(fs.readFileSync(path.join(scratch, 'data', 'calibrations', 'calibration', 'calibration.json'), 'utf8'));
    const nominal = new Map(rig.leds.map((l) => [l.id, l.direction]));
    const angles = calibration.lights.map((l) => {
      const n = nominal.get(l.led_id);
      const dot = l.direction.reduce((sum, v, i) => sum + v * n[i], 0);
      return (Math.acos(Math.min(1, dot)) * 180) / Math.PI;
    });
    const meanAngle = angles.reduce((a, b) => a + b, 0) / angles.length;
    assert.ok(meanAngle < 0.5, `calibrated directions ${meanAngle.toFixed(3)} deg from the simulator's`);
    await page.screenshot({ path: path.join(scratch, 'calibration.png'), fullPage: true });

    // Capture: the object placed, 96 frames followed to the end.
    await page.click('#tab-capture');
    await page.click('input[data-place="object"]');
    await page.waitForFunction(() => document.querySelector('input[data-place="object"]').checked);
    await page.fill('#capture-name', 'bunny');
    await startJob(page, () => page.click('#capture-start'));
    // Paused part way, then resumed from the stack list. Stopped at the first frame shown: the
    // simulated dome takes the 96 in a few seconds, and a loaded machine's page can lag that much.
    await page.waitForFunction(() => {
      const done = /(\d+) \/ 96 frames/.exec(document.querySelector('#job')?.textContent ?? '');
      return done && Number(done[1]) >= 1;
    }, null, { timeout: 60000 });
    await page.click('#job-stop');
    await page.waitForFunction(() => {
      const state = document.querySelector('#job-state')?.textContent;
      return state && state !== 'running';
    }, null, { timeout: 60000 });
    assert.equal(await page.textContent('#job-state'), 'stopped', 'the capture ended before the stop reached it');
    await page.waitForSelector('#stacks tr[data-stack="bunny"] button.resume');
    assert.match(await page.textContent('#stacks tr[data-stack="bunny"]'), /incomplete/);
    await page.screenshot({ path: path.join(scratch, 'capture-paused.png'), fullPage: true });
    await startJob(page, () => page.click('#stacks tr[data-stack="bunny"] button.resume'));
    await jobEnds(page);
    await page.waitForSelector('#stacks tr[data-stack="bunny"]');
    assert.match(await page.textContent('#stacks tr[data-stack="bunny"]'), /96 \/ 96/);
    await page.screenshot({ path: path.join(scratch, 'capture.png'), fullPage: true });

    // Results: solved with the calibration, exported as PTM, the report opened.
    await page.click('#tab-results');
    await page.selectOption('#solve-stack', 'bunny');
    await page.selectOption('#solve-method', 'l2');
    await page.selectOption('#solve-calibration', 'calibration');
    await startJob(page, () => page.click('#solve-start'));
    await jobEnds(page);
    const row = '#results tr[data-result="bunny-l2"]';
    await page.waitForSelector(`${row} a.report-link`);
    await startJob(page, () => page.click(`${row} button.export[data-format="ptm"]`));
    await jobEnds(page);
    await page.waitForSelector(`${row} a[href*="exports/bunny-l2.ptm"]`);
    const ptm = await (await fetch(new URL(await page.getAttribute(`${row} a[href*="exports"]`, 'href'), origin))).arrayBuffer();
    assert.match(Buffer.from(ptm.slice(0, 12)).toString('latin1'), /^PTM_1\.2/);
    await page.screenshot({ path: path.join(scratch, 'results.png'), fullPage: true });
    const [report] = await Promise.all([context.waitForEvent('page'), page.click(`${row} a.report-link`)]);
    watch(report, 'report');
    await report.waitForLoadState('load');
    assert.match(await report.title(), /.+/);
    await report.waitForTimeout(500);
    await report.screenshot({ path: path.join(scratch, 'report.png') });

    // Every action in the audit log, by the operator who took control.
    const audit = fs.readFileSync(path.join(scratch, 'data', 'audit.log'), 'utf8').trim().split('\n').map(JSON.parse);
    for (const action of ['control.take', 'job.stop', 'capture.resume', 'leds.set', 'preview', 'place', 'capture.start', 'sphere.draw', 'sphere.forget',
      'calibration.start', 'solve.start', 'export.start']) {
      assert.ok(audit.some((l) => l.action === action && l.outcome === 'ok' && l.name === 'Ann'), `no ${action} by Ann in the audit log`);
    }
    assert.deepEqual(problems, []);
  } finally {
    await browser.close();
    station.child.kill('SIGTERM');
  }
});

test('a station with a token refuses a page without it, and keeps it out of the address bar', { timeout: 120000 }, async () => {
  const dir = path.join(scratch, 'token');
  fs.rmSync(dir, { recursive: true, force: true });
  const station = await startStation(path.join(dir, 'data'), ['--token', '5be4c2a1d0e9f8a7b6c5d4e3f2a1b0c9']);
  assert.match(station.url, /\?token=5be4c2a1d0e9f8a7b6c5d4e3f2a1b0c9$/);
  const browser = await chromium.launch({
    executablePath: chromiumPath,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
  try {
    const page = await browser.newPage();
    const bare = new URL(station.url);
    bare.search = '';
    await page.goto(bare.href);
    await page.waitForSelector('#error');
    assert.match(await page.textContent('#error'), /token/);
    assert.match(await page.textContent('#dome-state'), /unreachable/);
    await page.goto(station.url);
    await page.waitForFunction(() => /dome idle/.test(document.querySelector('#dome-state')?.textContent ?? ''));
    assert.equal(new URL(page.url()).search, '', 'the token stayed in the address bar');
    await page.reload();
    await page.waitForFunction(() => /dome idle/.test(document.querySelector('#dome-state')?.textContent ?? ''));
  } finally {
    await browser.close();
    station.child.kill('SIGTERM');
  }
});
