#!/usr/bin/env node
// Tests of the monitor page itself, without the C++ server: the page is
// served by fake_monitor.mjs (the same files, the same protocol, a
// synthetic rig) and driven in headless Chromium through playwright-core.
//
//   node monitor_page_test.mjs [--out DIR] [--chromium PATH] [--skip-check-script]
//
// Prints PASS/FAIL per test and "N passed, N failed"; exits 0 when all pass.
// Screenshots go to DIR (default: a fresh folder under the system's temp).
// The last test runs monitor_page_check.mjs against a fake monitor, kill
// included, so the live check is itself tested.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { startFakeMonitor } from './fake_monitor.mjs';
import * as rig from './synthetic_rig.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
const argValue = (name, fallback) => { const i = args.indexOf(name); return i >= 0 && i + 1 < args.length ? args[i + 1] : fallback; };
const OUT = argValue('--out', fs.mkdtempSync(path.join(os.tmpdir(), 'monitor-page-test-')));
const CHROMIUM = argValue('--chromium', process.env.CHROMIUM || '/usr/bin/chromium');
fs.mkdirSync(OUT, { recursive: true });
const ARGS = ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'];

const results = [];
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
function assert(condition, message) { if (!condition) throw new Error(message); }

async function test(name, fn) {
  const t0 = Date.now();
  try {
    await Promise.race([fn(), sleep(90000).then(() => { throw new Error('timed out after 90 s'); })]);
    results.push({ name, ok: true });
    console.log('PASS ' + name + ' (' + ((Date.now() - t0) / 1000).toFixed(1) + ' s)');
  } catch (e) {
    results.push({ name, ok: false, error: e.message });
    console.log('FAIL ' + name + ': ' + (e && e.message ? e.message : e));
  }
}

const pageProblems = [];
async function newPage(browser, url, options = {}) {
  const context = await browser.newContext({ viewport: options.viewport || { width: 1600, height: 1000 } });
  const page = await context.newPage();
  const origin = new URL(url).origin;
  page.on('pageerror', (e) => pageProblems.push('page error: ' + e.message));
  page.on('request', (r) => {
    const u = r.url();
    if (!u.startsWith('data:') && !u.startsWith('blob:') && new URL(u).origin !== origin) pageProblems.push('external request: ' + u);
  });
  if (options.init) await page.addInitScript(options.init);
  if (options.route) await page.route(options.route[0], options.route[1]);
  await page.goto(url, { waitUntil: 'load', timeout: 20000 });
  await page.waitForFunction(() => window.shapesenseMonitor && window.shapesenseMonitor.ready, null, { timeout: 10000 });
  return page;
}
const frames = (page, n = 3) => page.evaluate((count) => new Promise((resolve) => {
  let left = count;
  const step = () => (--left <= 0 ? resolve() : requestAnimationFrame(step));
  requestAnimationFrame(step);
}), n);
const monitor = (page) => page.evaluate(() => {
  const m = window.shapesenseMonitor;
  return { updates: m.updates, byType: m.updatesByType, errors: m.errors, lastError: m.lastError, connected: m.connected,
    hello: m.hello, health: m.health, cameras: m.cameras, view: m.view3d(), renderErrors: m.renderErrors || 0, ignored: m.ignoredByType };
});
const sendText = (page, message) => page.evaluate((m) => window.shapesenseMonitor.handleText(typeof m === 'string' ? m : JSON.stringify(m)), message);
const sendBinary = (page, bytes) => page.evaluate((b) => window.shapesenseMonitor.handleBinary(new Uint8Array(b).buffer), Array.from(bytes));

let browser;
const fakes = [];
try {
  browser = await chromium.launch({ executablePath: CHROMIUM, args: ARGS, timeout: 30000 });
  const fake = await startFakeMonitor({ estopToken: 'secret', durationS: 600 });
  fakes.push(fake);
  const cameras = rig.makeCameras(2);

  await test('live page: connects, gets hello, camera frames, shapes and health at 1600x1000 without scrolling', async () => {
    const page = await newPage(browser, fake.url);
    await page.waitForFunction(() => {
      const m = window.shapesenseMonitor;
      return m.hello && Object.values(m.cameras).length === 3 && Object.values(m.cameras).every((c) => c.decoded >= 2) &&
        m.health.length > 0 && (m.updatesByType.stats || 0) >= 2;
    }, null, { timeout: 20000 });
    await sleep(1500);
    const m = await monitor(page);
    assert(m.connected, 'not connected');
    assert(m.errors === 0, 'message errors: ' + m.lastError);
    assert(m.view.ok, '3-D view failed: ' + m.view.failure);
    const dom = await page.evaluate(() => ({
      scroll: [document.documentElement.scrollWidth, document.documentElement.scrollHeight],
      canvases: Array.from(document.querySelectorAll('canvas.camera-canvas')).map((c) => c.dataset.camera),
      rows: Array.from(document.querySelectorAll('[data-testid="health-row"]')).map((r) => [r.dataset.program, r.dataset.state]),
      count: document.getElementById('update-count').textContent,
      conn: document.getElementById('conn').textContent,
      estopHidden: document.getElementById('estop').hidden,
      gate: document.getElementById('ctl-gate').className,
      noData: document.querySelectorAll('.plot canvas').length,
    }));
    assert(dom.scroll[0] <= 1600 && dom.scroll[1] <= 1000, 'the page scrolls at 1600x1000: ' + dom.scroll);
    assert(dom.canvases.join() === 'cam0,cam1,cam2', 'camera canvases: ' + dom.canvases);
    assert(dom.rows.some(([p, s]) => p === 'carving' && s === 'up'), 'no carving row up: ' + JSON.stringify(dom.rows));
    assert(dom.rows.some(([p, s]) => p === 'unknown-tool' && s === 'unexpected'), 'no unexpected row');
    assert(Number(dom.count) > 0, 'update counter shows ' + dom.count);
    assert(dom.conn === 'connected', 'connection shows ' + dom.conn);
    assert(!dom.estopHidden, 'the e-stop button is hidden although hello.estop_enabled');
    assert(/badge (ok|warn)/.test(dom.gate), 'gate badge class ' + dom.gate);
    await page.screenshot({ path: path.join(OUT, 'live-1600x1000.png') });
    await page.context().close();
  });

  await test('layout at 1280x800: no page scroll sideways, every panel visible', async () => {
    const page = await newPage(browser, fake.url, { viewport: { width: 1280, height: 800 } });
    await page.waitForFunction(() => (window.shapesenseMonitor.updatesByType.health || 0) >= 1, null, { timeout: 15000 });
    await sleep(1000);
    const dom = await page.evaluate(() => {
      const box = (id) => { const r = document.getElementById(id).getBoundingClientRect(); return [r.width, r.height, r.bottom]; };
      return { scroll: [document.documentElement.scrollWidth, document.documentElement.scrollHeight],
        view: box('view3d'), plot: box('plot-tendons'), health: box('health-panel') };
    });
    assert(dom.scroll[0] <= 1280, 'horizontal page scroll: ' + dom.scroll);
    assert(dom.view[0] > 300 && dom.view[1] > 150, '3-D view too small: ' + dom.view);
    assert(dom.plot[1] > 60, 'plots too small: ' + dom.plot);
    assert(dom.health[2] <= 800 + 1, 'health panel below the fold: ' + dom.health);
    await page.screenshot({ path: path.join(OUT, 'live-1280x800.png') });
    await page.context().close();
  });

  await test('offline page (#nows): fed through the hooks, draws every layer and keeps the latest frame', async () => {
    const page = await newPage(browser, fake.url + '#nows');
    const m0 = await monitor(page);
    assert(!m0.connected && m0.updates === 0, 'the #nows page connected or counted updates');
    assert(await page.evaluate(() => document.getElementById('estop').hidden), 'e-stop visible before hello');
    const noData = await page.evaluate(() => document.querySelectorAll('.plot canvas').length);
    assert(noData === 5, 'expected 5 plots, found ' + noData);
    assert(await sendText(page, rig.helloMessage(cameras, { estopEnabled: false })), 'hello refused');
    for (let seq = 1; seq <= 5; seq++) {
      const shape = rig.shapeMessage('shape', seq, seq * 0.5);
      assert(await sendText(page, shape), 'shape refused');
      assert(await sendText(page, rig.shapeMessage('truth', seq, seq * 0.5)), 'truth refused');
      for (const c of cameras) assert(await sendBinary(page, rig.cameraFrame(c, shape, seq)), 'camera frame refused');
    }
    await sendText(page, rig.targetMessage(1, 1));
    await sendText(page, rig.controllerMessage(1, 1));
    await sendText(page, { ...rig.controllerMessage(2, 2), gate: 'estop', gate_reasons: ['e-stop pressed'], tip_error_mm: null });
    await sendText(page, rig.healthMessage(1, 1, new Map([['carving', 5]])));
    await sendText(page, rig.statsMessage(1, 1));
    // Many frames at once: only the latest is kept and shown.
    const burst = [];
    for (let seq = 6; seq <= 40; seq++) burst.push(Array.from(rig.cameraFrame(cameras[0], rig.shapeMessage('shape', seq, 3), seq)));
    await page.evaluate((frames) => { for (const f of frames) window.shapesenseMonitor.handleBinary(new Uint8Array(f).buffer); }, burst);
    await page.waitForFunction(() => window.shapesenseMonitor.cameras.cam0.trigger_seq === 40, null, { timeout: 10000 });
    await page.click('#layer3d-truth');
    await frames(page, 5);
    const m = await monitor(page);
    assert(m.errors === 0, 'errors: ' + m.lastError);
    assert(m.byType.shape === 5 && m.byType.camera === 45 && m.byType.hello === 1, 'counts: ' + JSON.stringify(m.byType));
    assert(m.cameras.cam0.decoded < 40, 'cam0 decoded every frame of the burst (' + m.cameras.cam0.decoded + '): no latest-only');
    assert(m.cameras.cam1.decoded >= 1, 'cam1 decoded nothing');
    const dom = await page.evaluate(() => ({
      rows: Array.from(document.querySelectorAll('[data-testid="health-row"]')).map((r) => r.dataset.program + ':' + r.dataset.state),
      gate: [document.getElementById('ctl-gate').textContent, document.getElementById('ctl-gate').className],
      reasons: document.getElementById('ctl-reasons').textContent,
      target: document.getElementById('ctl-target').textContent,
      caption: document.querySelector('.cam .cam-caption').textContent,
    }));
    assert(dom.rows.includes('carving:missing') && dom.rows.includes('shape:up'), 'health rows: ' + dom.rows);
    assert(dom.gate[0] === 'gate estop' && dom.gate[1].includes('bad'), 'gate: ' + dom.gate);
    assert(dom.reasons === 'e-stop pressed', 'reasons: ' + dom.reasons);
    assert(dom.target.startsWith('configuration'), 'target: ' + dom.target);
    assert(dom.caption.includes('seq 40'), 'caption: ' + dom.caption);
    // The picture is drawn: the pane is not one flat colour.
    const std = await page.evaluate(() => {
      const c = document.querySelector('canvas.camera-canvas[data-camera="cam0"]');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let s = 0, s2 = 0;
      for (let i = 0; i < d.length; i += 4) { s += d[i + 1]; s2 += d[i + 1] * d[i + 1]; }
      const n = d.length / 4;
      return Math.sqrt(s2 / n - (s / n) ** 2);
    });
    assert(std > 10, 'camera pane looks flat (std ' + std.toFixed(1) + ')');
    await page.screenshot({ path: path.join(OUT, 'fed-offline.png') });
    // Layer toggles redraw the panes (no error, still drawn).
    for (const id of ['#layer-silhouette', '#layer-centerline', '#layer-markers', '#layer-tip']) await page.click(id);
    await frames(page, 3);
    await page.screenshot({ path: path.join(OUT, 'fed-offline-no-layers.png') });
    await page.context().close();
  });

  await test('malformed messages are counted and ignored, never thrown', async () => {
    const page = await newPage(browser, fake.url + '#nows');
    await sendText(page, rig.helloMessage(cameras));
    const bad = [
      'not json', '[]', 'null', '42', '{"no_type":1}', '{"type":7}',
      '{"type":"shape","centerline":[[1,2]]}', '{"type":"shape","centerline":"x"}', '{"type":"shape","tip":[1,"a",3]}',
      '{"type":"hello","cameras":5}', '{"type":"hello","cameras":[{"name":"c","width":640,"height":480,"frustum":[[0,0,0]]}]}',
      '{"type":"health","rows":[{"host":"h"}]}', '{"type":"health"}', '{"type":"controller","commanded_mm":["x"]}',
      '{"type":"stats","latency_ms":[1,2]}', '{"type":"target","centerline":[[1,2,3],[4,5]]}',
    ];
    for (const text of bad) assert((await sendText(page, text)) === false, 'accepted: ' + text);
    const json = Buffer.from('{"type":"camera","camera":"cam0","width":640,"height":480}');
    const header = Buffer.alloc(4);
    header.writeUInt32LE(json.length + 100);
    const badBinary = [
      Buffer.from([1, 2]),
      Buffer.concat([header, json]),                                           // length past the end
      rig.packCameraFrame({ type: 'camera' }, new Uint8Array(0)),              // no camera name
      rig.packCameraFrame({ type: 'camera', camera: 'cam0', width: 640, height: 480, markers: [[1]] }, new Uint8Array(0)),
      Buffer.concat([Buffer.from([3, 0, 0, 0]), Buffer.from([0xff, 0xfe, 0xfd])]), // not UTF-8 JSON
    ];
    for (const b of badBinary) assert((await sendBinary(page, b)) === false, 'accepted a bad binary message');
    // A frame whose JPEG does not decode: accepted, then counted when decoding fails.
    const garbage = rig.packCameraFrame({ type: 'camera', camera: 'cam1', trigger_seq: 1, width: 640, height: 480 }, new Uint8Array(500).fill(7));
    assert(await sendBinary(page, garbage), 'garbage JPEG frame refused before decoding');
    await page.waitForFunction(() => window.shapesenseMonitor.cameras.cam1.decodeErrors === 1, null, { timeout: 5000 });
    // Not thrown even for odd argument types.
    const odd = await page.evaluate(() => [window.shapesenseMonitor.handleBinary('text'), window.shapesenseMonitor.handleBinary(null),
      window.shapesenseMonitor.handleText(undefined)]);
    assert(odd.every((v) => v === false), 'odd arguments: ' + odd);
    // A newer server's message type is ignored without being an error.
    assert((await sendText(page, '{"type":"future_thing","x":1}')) === false, 'unknown type applied');
    const m = await monitor(page);
    const expected = bad.length + badBinary.length + 1 + 3;
    assert(m.errors === expected, 'errors ' + m.errors + ', expected ' + expected + ' (last: ' + m.lastError + ')');
    assert(m.ignored.future_thing === 1, 'unknown type not counted as ignored');
    // Still works afterwards.
    assert(await sendText(page, rig.shapeMessage('shape', 1, 1)), 'a good shape after bad ones refused');
    await frames(page, 3);
    assert((await monitor(page)).renderErrors === 0, 'drawing errors');
    await page.context().close();
  });

  await test('3-D view: geometry is disposed (no leak over 300 shapes), truth layer toggles', async () => {
    const page = await newPage(browser, fake.url + '#nows');
    await sendText(page, rig.helloMessage(cameras));
    await page.evaluate((shapes) => {
      return new Promise((resolve) => {
        let i = 0;
        const step = () => {
          for (let k = 0; k < 10 && i < shapes.length; k++, i++) {
            window.shapesenseMonitor.handleText(shapes[i][0]);
            window.shapesenseMonitor.handleText(shapes[i][1]);
            window.shapesenseMonitor.handleText(shapes[i][2]);
          }
          if (i < shapes.length) requestAnimationFrame(step); else requestAnimationFrame(() => requestAnimationFrame(resolve));
        };
        step();
      });
    }, Array.from({ length: 300 }, (_, i) => [JSON.stringify(rig.shapeMessage('shape', i, i / 30)),
      JSON.stringify(rig.shapeMessage('truth', i, i / 30)), JSON.stringify(rig.targetMessage(i / 30, i))]));
    const m = await monitor(page);
    assert(m.view.ok, 'no WebGL: ' + m.view.failure);
    assert(m.view.geometries < 40, 'geometries keep growing: ' + m.view.geometries);
    await page.context().close();
  });

  await test('no WebGL: the 3-D pane says so and the rest works', async () => {
    const page = await newPage(browser, fake.url, {
      init: () => {
        const original = HTMLCanvasElement.prototype.getContext;
        HTMLCanvasElement.prototype.getContext = function (type, ...rest) {
          return /webgl/.test(type) ? null : original.call(this, type, ...rest);
        };
      },
    });
    await page.waitForFunction(() => Object.values(window.shapesenseMonitor.cameras).some((c) => c.decoded >= 1), null, { timeout: 15000 });
    const text = await page.evaluate(() => { const e = document.getElementById('view3d-message'); return e.hidden ? '' : e.textContent; });
    assert(/WebGL/.test(text), 'no WebGL message: "' + text + '"');
    const m = await monitor(page);
    assert(!m.view.ok && m.updates > 0, 'view ' + JSON.stringify(m.view) + ', updates ' + m.updates);
    await page.screenshot({ path: path.join(OUT, 'no-webgl.png') });
    await page.context().close();
  });

  await test('three.js missing: the 3-D pane says so and the rest works', async () => {
    const page = await newPage(browser, fake.url, { route: ['**/vendor/three.min.js', (route) => route.fulfill({ status: 404, body: '' })] });
    await page.waitForFunction(() => (window.shapesenseMonitor.updatesByType.shape || 0) > 3, null, { timeout: 15000 });
    const text = await page.evaluate(() => document.getElementById('view3d-message').textContent);
    assert(/three\.js did not load/.test(text), 'message: ' + text);
    await page.context().close();
    // OrbitControls.js itself throws without three.js: expected here, not the page's error.
    for (let i = pageProblems.length - 1; i >= 0; i--) if (/reading 'prototype'/.test(pageProblems[i])) pageProblems.splice(i, 1);
  });

  await test('e-stop: token from #token=, sent on click, result shown; a typed wrong token is refused', async () => {
    const before = fake.state.received.length;
    const page = await newPage(browser, fake.url + '#token=secret');
    await page.waitForFunction(() => window.shapesenseMonitor.hello, null, { timeout: 10000 });
    await page.waitForSelector('#estop:not([hidden])', { timeout: 5000 });
    await page.click('#estop');
    await page.waitForFunction(() => /accepted/.test(document.getElementById('estop-result').textContent), null, { timeout: 5000 });
    const sent = fake.state.received.slice(before).map((t) => JSON.parse(t));
    assert(sent.length === 1 && sent[0].type === 'estop' && sent[0].token === 'secret', 'sent: ' + JSON.stringify(sent));
    await page.context().close();

    const page2 = await newPage(browser, fake.url);
    await page2.waitForFunction(() => window.shapesenseMonitor.hello && window.shapesenseMonitor.connected, null, { timeout: 10000 });
    page2.once('dialog', (d) => d.accept('wrong'));
    await page2.click('#estop');
    await page2.waitForFunction(() => /refused/.test(document.getElementById('estop-result').textContent), null, { timeout: 5000 });
    await page2.screenshot({ path: path.join(OUT, 'estop-refused.png'), clip: { x: 0, y: 0, width: 1600, height: 60 } });
    await page2.context().close();
  });

  await test('reconnects after the server drops the connection', async () => {
    const page = await newPage(browser, fake.url);
    await page.waitForFunction(() => window.shapesenseMonitor.connected && window.shapesenseMonitor.hello, null, { timeout: 10000 });
    for (const c of fake.state.clients) c.socket.destroy();
    await page.waitForFunction(() => !window.shapesenseMonitor.connected, null, { timeout: 5000 });
    const shown = await page.evaluate(() => document.getElementById('conn').textContent);
    assert(shown === 'reconnecting', 'connection shows ' + shown);
    await page.waitForFunction(() => window.shapesenseMonitor.connected && window.shapesenseMonitor.updatesByType.hello === 2, null, { timeout: 5000 });
    await page.context().close();
  });

  if (!args.includes('--skip-check-script')) {
    await test('monitor_page_check.mjs passes against a fake monitor, kill included, and fails on a missing program', async () => {
      const control = fs.mkdtempSync(path.join(os.tmpdir(), 'fake-monitor-control-'));
      const fake2 = await startFakeMonitor({ controlDir: control, missingAfterS: 1.0, durationS: 300 });
      fakes.push(fake2);
      const killFile = path.join(control, 'kill-command');
      fs.writeFileSync(killFile, 'touch ' + JSON.stringify(path.join(control, 'kill-carving')) + '\n');
      const run = (extra) => new Promise((resolve) => {
        const child = spawn(process.execPath, [path.join(HERE, 'monitor_page_check.mjs'), '--url', fake2.url, '--chromium', CHROMIUM, ...extra],
          { stdio: ['ignore', 'pipe', 'pipe'] });
        let output = '';
        child.stdout.on('data', (d) => { output += d; });
        child.stderr.on('data', (d) => { output += d; });
        child.on('close', (code) => resolve({ code, output }));
      });
      const bad = await run(['--out', path.join(OUT, 'check-bad'), '--expect', 'carving,nonexistent', '--wait-s', '3', '--rate-window-s', '1']);
      assert(bad.code === 1 && /FAIL health: not up: nonexistent/.test(bad.output), 'the check did not fail on a missing program:\n' + bad.output);
      const good = await run(['--out', path.join(OUT, 'check'), '--expect', 'carving,shape,capture,rig_sim', '--kill-program', 'carving',
        '--kill-command-file', killFile, '--blank-screenshot']);
      assert(good.code === 0, 'the check failed:\n' + good.output);
      const result = JSON.parse(fs.readFileSync(path.join(OUT, 'check', 'result.json'), 'utf8'));
      assert(result.kill.missing_after_s > 0.5 && result.kill.missing_after_s <= 3, 'kill delay ' + result.kill.missing_after_s);
      for (const f of ['before.png', 'after.png', 'monitor.png', 'killed.png']) assert(fs.existsSync(path.join(OUT, 'check', f)), 'no ' + f);
    });
  }

  await test('no external request and no uncaught page error in any test', async () => {
    assert(pageProblems.length === 0, pageProblems.slice(0, 5).join('; '));
  });
} catch (e) {
  results.push({ name: 'setup', ok: false, error: e.message });
  console.log('FAIL setup: ' + (e && e.stack ? e.stack : e));
} finally {
  if (browser) await browser.close().catch(() => {});
  for (const f of fakes) await f.stop().catch(() => {});
}
const passed = results.filter((r) => r.ok).length, failed = results.length - passed;
console.log('screenshots: ' + OUT);
console.log(passed + ' passed, ' + failed + ' failed');
process.exit(failed ? 1 : 0);
