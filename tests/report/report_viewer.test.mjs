// End to end: simulate a small stack, solve it (which writes report.html),
// write the report again with `lightstage report`, open it in headless
// Chromium (Debian's /usr/bin/chromium, driven by playwright-core), and check
// that every image loaded, nothing was logged as an error, no request left the
// page, the keyboard moves the light, and that after a scripted pointer drag on
// the hemisphere the canvas matches `lightstage relight` for the same light
// (mean difference < 1%); the same for a bi-polynomial (glossy) solve.
// Screenshots: SCRATCH/screenshot.png and viewer.png (SCRATCH/glossy/ for the second).
//
// Environment (set by tests/report/CMakeLists.txt):
//   LIGHTSTAGE_BIN        the lightstage program
//   LIGHTSTAGE_REFERENCE  tests' report_render_reference (used when `relight` is missing)
//   LIGHTSTAGE_NODE_DEPS  the folder npm ci installed playwright-core into
//   LIGHTSTAGE_SCRATCH    a scratch folder of the build tree (emptied first)
//   LIGHTSTAGE_CHROMIUM   the browser (default /usr/bin/chromium)
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { readImage } from './image_files.mjs';

const env = (name, fallback) => {
  const value = process.env[name] ?? fallback;
  if (value === undefined) throw new Error(`the test needs ${name} in its environment`);
  return value;
};
const bin = env('LIGHTSTAGE_BIN');
const reference = env('LIGHTSTAGE_REFERENCE');
const nodeDeps = env('LIGHTSTAGE_NODE_DEPS');
const scratch = env('LIGHTSTAGE_SCRATCH');
const chromiumPath = env('LIGHTSTAGE_CHROMIUM', '/usr/bin/chromium');

const require = createRequire(path.join(nodeDeps, 'package.json'));
const { chromium } = require('playwright-core');

function lightstage(args) {
  const result = spawnSync(bin, args, { encoding: 'utf8' });
  if (result.status !== 0) {
    throw new Error(`lightstage ${args.join(' ')} exited ${result.status}:\n${result.stdout}\n${result.stderr}`);
  }
  return result.stdout;
}

function hasRelight() {
  return spawnSync(bin, ['relight', '--help'], { encoding: 'utf8' }).status === 0;
}

// The same light through the CLI (or the C++ reference of the same shading
// when `lightstage relight` is not built): linear values, object pixels only.
// `scale` is the viewer's white (relight writes min(v / scale, 1) · 65535).
function referenceImage(resultDir, light, scale, outDir) {
  const [x, y, z] = light.map((v) => v.toPrecision(9));
  if (hasRelight()) {
    const out = path.join(outDir, 'relight');
    const run = spawnSync(bin, ['relight', '--input', resultDir, '--light', `${x},${y},${z}`, '--scale',
      String(scale), '--out', out], { encoding: 'utf8' });
    if (run.status !== 0) throw new Error(`lightstage relight failed:\n${run.stdout}\n${run.stderr}`);
    return { source: 'lightstage relight', ...relightOutput(out) };
  }
  const file = path.join(outDir, 'reference.pfm');
  execFileSync(reference, [resultDir, x, y, z, file]);
  return { source: 'C++ reference (report::relight; `lightstage relight` not built)', image: readImage(file), linear: true };
}

// What `lightstage relight --out DIR` wrote: a float map when there is one, else a PNG.
function relightOutput(out) {
  const files = fs.statSync(out).isDirectory() ? fs.readdirSync(out).map((f) => path.join(out, f)) : [out];
  const pfm = files.find((f) => f.endsWith('.pfm'));
  if (pfm) return { image: readImage(pfm), linear: true, file: pfm };
  const png = files.find((f) => f.endsWith('.png'));
  if (png) return { image: readImage(png), linear: false, file: png };
  throw new Error(`lightstage relight wrote no .pfm or .png in ${out}`);
}

async function launch(t) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'lightstage-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: chromiumPath,
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
    viewport: { width: 1280, height: 1000 },
  });
  t.after(async () => {
    await context.close();
    fs.rmSync(profile, { recursive: true, force: true });
  });
  return context;
}

// Opens `pageFile`, checks images, errors, requests, keyboard and a pointer
// drag, and compares the canvas with the CLI's rendering of `resultDir` for
// the dragged light. Screenshots and the CLI's images go to `outDir`.
async function checkReport(context, pageFile, resultDir, outDir) {
  const summary = JSON.parse(fs.readFileSync(path.join(resultDir, 'summary.json'), 'utf8'));
  const page = await context.newPage();
  const errors = [];
  const requests = [];
  page.on('console', (message) => {
    if (message.type() === 'error') errors.push(`console: ${message.text()}`);
  });
  page.on('pageerror', (error) => errors.push(`page error: ${error.message}`));
  page.on('request', (request) => {
    if (!request.url().startsWith('data:') && !request.url().startsWith('file:')) requests.push(request.url());
  });
  await page.goto(`file://${pageFile}`, { waitUntil: 'load' });
  await page.evaluate(() => window.lightstageViewer.ready);

  // Every image loaded.
  const images = await page.evaluate(() =>
    Array.from(document.images, (img) => ({ alt: img.alt, complete: img.complete, width: img.naturalWidth })));
  assert.ok(images.length >= 5, `expected the report's pictures, found ${images.length}`);
  for (const image of images) assert.ok(image.complete && image.width > 0, `image '${image.alt}' did not load`);
  const meta = await page.evaluate(() => window.lightstageViewer.meta);
  assert.equal(meta.width, summary.width);
  assert.equal(meta.height, summary.height);

  // The keyboard moves the light (orthographic disc: ArrowLeft = x − 0.05).
  const widget = page.locator('#viewer-hemisphere');
  await widget.focus();
  const before = await page.evaluate(() => window.lightstageViewer.getLight());
  await page.keyboard.press('ArrowLeft');
  const after = await page.evaluate(() => window.lightstageViewer.getLight());
  assert.ok(Math.abs(after[0] - (before[0] - 0.05)) < 1e-9, `ArrowLeft moved the light from ${before} to ${after}`);

  // A pointer drag across the widget: from the centre to a point right and up.
  const box = await widget.boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const rendersBefore = await page.evaluate(() => window.lightstageViewer.renders);
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 0.25 * box.width, cy - 0.15 * box.height, { steps: 12 });
  await page.mouse.up();
  const light = await page.evaluate(() => window.lightstageViewer.getLight());
  const rendersAfter = await page.evaluate(() => window.lightstageViewer.renders);
  assert.ok(rendersAfter - rendersBefore >= 5, `the drag re-rendered the canvas (${rendersAfter - rendersBefore} times)`);
  assert.ok(light[0] > 0.4 && light[1] > 0.2 && light[2] > 0.5, `the drag put the light right and up: ${light}`);

  const pixels = await page.evaluate(() => {
    const data = window.lightstageViewer.getImageData();
    return { width: data.width, height: data.height, rgba: Array.from(data.data) };
  });
  await page.screenshot({ path: path.join(outDir, 'screenshot.png'), fullPage: true });
  await page.locator('#viewer').screenshot({ path: path.join(outDir, 'viewer.png') });

  // Compare with the CLI for the same light, over the object's pixels.
  const ref = referenceImage(resultDir, light, meta.display.scale, outDir);
  assert.equal(ref.image.width, pixels.width);
  assert.equal(ref.image.height, pixels.height);
  const scale = meta.display.scale;
  let sumDiff = 0, sumRef = 0, count = 0, worst = 0;
  for (let p = 0; p < pixels.width * pixels.height; ++p) {
    if (pixels.rgba[4 * p + 3] === 0) continue;  // no normal: transparent
    const shown = pixels.rgba[4 * p] / 255;
    const value = ref.image.data[p * ref.image.channels];
    const expected = ref.linear ? Math.min(1, Math.max(0, value / scale)) : value / ref.image.max;
    const diff = Math.abs(shown - expected);
    sumDiff += diff;
    sumRef += expected;
    worst = Math.max(worst, diff);
    ++count;
  }
  assert.ok(count > 1000, `object pixels compared: ${count}`);
  const meanDiff = sumDiff / count, meanRef = sumRef / count;
  console.log(`${meta.model.kind} viewer vs ${ref.source}: light (${light.map((v) => v.toFixed(4))}), ${count} ` +
    `pixels, mean |diff| ${(100 * meanDiff).toFixed(3)}% of full scale (${(100 * meanDiff / meanRef).toFixed(3)}% ` +
    `of the mean value), max ${(100 * worst).toFixed(2)}%`);
  assert.ok(meanDiff / meanRef < 0.01, `mean difference ${(100 * meanDiff / meanRef).toFixed(3)}% of the mean`);
  assert.ok(meanDiff < 0.01, `mean difference ${(100 * meanDiff).toFixed(3)}% of full scale`);

  assert.deepEqual(errors, [], 'the page logged errors');
  assert.deepEqual(requests, [], 'the page made network requests');
  await page.close();
  return meta;
}

test('the report of a Lambertian solve opens offline, relights on drag and agrees with relight', async (t) => {
  const dir = scratch;
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  const stack = path.join(dir, 'stack');
  const result = path.join(dir, 'result');
  lightstage(['simulate', '--scene', 'bumps', '--lights', 'distant', '--width', '128', '--height', '128',
    '--out', stack]);
  lightstage(['solve', '--input', stack, '--method', 'l2', '--shadow-threshold', '0.02', '--out', result]);
  assert.ok(fs.existsSync(path.join(result, 'report.html')), 'solve writes report.html into its result folder');
  const pageFile = path.join(dir, 'report.html');
  const written = JSON.parse(lightstage(['report', result, '--out', pageFile, '--json']));
  for (const id of ['viewer', 'surface', 'lights', 'light-statistics', 'residual', 'error']) {
    assert.ok(written.sections.includes(id), `section ${id} in ${written.sections}`);
  }
  const context = await launch(t);
  const meta = await checkReport(context, pageFile, result, dir);
  assert.equal(meta.model.kind, 'lambertian');
});

test('the report of a bi-polynomial solve relights with the fitted model', async (t) => {
  const dir = path.join(scratch, 'glossy');
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  const stack = path.join(dir, 'stack');
  const result = path.join(dir, 'result');
  lightstage(['simulate', '--scene', 'bumps', '--material', 'cook-torrance:roughness=0.3,ks=0.5', '--lights',
    'distant', '--width', '96', '--height', '96', '--out', stack]);
  lightstage(['solve', '--input', stack, '--method', 'biquadratic', '--out', result]);
  const context = await launch(t);
  const meta = await checkReport(context, path.join(result, 'report.html'), result, dir);
  // Cook–Torrance's highlight gets the relighting fit's specular lobe, which the viewer shades too.
  const summary = JSON.parse(fs.readFileSync(path.join(result, 'summary.json'), 'utf8'));
  const lobe = summary.reflectance.specular;
  assert.ok(lobe && lobe.width > 0, `no specular lobe: ${JSON.stringify(summary.reflectance.fit)}`);
  assert.deepEqual(meta.model, { kind: 'bipolynomial', order: 2, lobe_width: lobe.width });
});

// The README links the demo's report: the real pipeline (three processes,
// calibration, capture, near-light solve, surface) must give a page that opens
// cleanly with the depth relief and the calibrated lights. Its screenshot is
// SCRATCH/demo/screenshot.png.
test('the demo report shows the calibrated lights and the integrated surface', async (t) => {
  const dir = path.join(scratch, 'demo');
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  const out = path.join(dir, 'run');
  const summary = JSON.parse(lightstage(['demo', '--width', '128', '--height', '128', '--out', out, '--json']));
  assert.ok(summary.solve.error_vs_ground_truth.mean_deg < 2, `demo error ${summary.solve.error_vs_ground_truth.mean_deg}`);
  const result = path.join(out, 'result');
  const page = path.join(result, 'report.html');
  assert.equal(summary.report, page);
  const html = fs.readFileSync(page, 'utf8');
  assert.ok(html.includes('alt="depth"'), 'the demo report shows the integrated depth');
  assert.ok(html.includes('calibrated'), 'the demo report plots the calibrated lights');
  const context = await launch(t);
  const meta = await checkReport(context, page, result, dir);
  assert.equal(meta.model.kind, 'lambertian');
});
