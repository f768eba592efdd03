#!/usr/bin/env node
// Checks a LIVE shapesense monitor through its web page in headless Chromium
// (playwright-core, the system's /usr/bin/chromium). Used by a ctest test
// once the pipeline runs; exits 0 when every check passes, 1 naming the
// failed checks, 2 on a usage error, 3 when Chromium cannot start.
//
//   node monitor_page_check.mjs --url http://127.0.0.1:PORT/ --out DIR
//        [--expect carving,shape,capture,rig_sim]
//        [--kill-program NAME (--kill-command "CMD" | --kill-command-file FILE)]
//        [--blank-screenshot] [--kill-max-s 3] [--min-rate 10] [--rate-window-s 5]
//        [--wait-s 30] [--timeout-s 240] [--diff-fraction 0.02] [--diff-level 16]
//        [--chromium /usr/bin/chromium] [--allow-bad-messages]
//
// Checks, in order (each wait bounded; the browser always closed):
//   page        the page loads, gets `hello` from the server, and its hooks exist
//   blank       a second page at URL#nows (the page fed nothing; it does not
//               connect): before.png, and the pixels of its 3-D canvas and,
//               once fed the live hello, of its empty camera panes
//   frames      the live page decodes >= 1 camera frame for every hello camera
//               and gets >= 1 shape; after.png
//   cameras     each camera canvas differs from its blank pane: in > diff-fraction
//               of its 160x120 cells, the darkest or brightest grey pixel moved
//               by > diff-level levels (cells keep thin lines at any canvas size)
//   view3d      #view3d (WebGL) differs from the blank page's likewise
//   rate        shapesenseMonitor.updates grows >= min-rate per second over rate-window-s
//   health      every --expect program has a health row (data-testid=health-row,
//               data-program) whose data-state is "up" (waits up to --wait-s)
//   messages    no malformed message (shapesenseMonitor.errors == 0), no uncaught
//               page error, no request to another origin
//   kill        (with --kill-program) runs the command (sh -c; --kill-command-file
//               is read when the kill starts, so a harness may write it late), then
//               polls every 100 ms: the program's row must say "missing" within
//               --kill-max-s of the command's exit; the delay is printed
// Writes DIR/before.png, DIR/after.png, DIR/monitor.png (full page at
// 1600x1000, before any kill), DIR/killed.png and DIR/result.json (all numbers).
// --blank-screenshot is the default (kept so a harness can say it); the blank
// reference is what makes the pixel checks meaningful.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const CHROMIUM_ARGS = [
  '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync',
  // WebGL on SwiftShader (no GPU here): allowed explicitly, as newer Chromium asks.
  '--enable-unsafe-swiftshader',
];
const VIEWPORT = { width: 1600, height: 1000 };
const SAMPLE_W = 160, SAMPLE_H = 120;

function usage(message) {
  if (message) console.error('monitor_page_check: ' + message);
  console.error('usage: node monitor_page_check.mjs --url URL --out DIR [--expect a,b] [--kill-program NAME ' +
    '(--kill-command CMD | --kill-command-file FILE)] [--kill-max-s 3] [--min-rate 10] [--rate-window-s 5] ' +
    '[--wait-s 30] [--timeout-s 240] [--diff-fraction 0.02] [--diff-level 16] [--blank-screenshot] ' +
    '[--chromium PATH] [--allow-bad-messages]');
  process.exit(2);
}

function parseArgs(argv) {
  const o = {
    url: null, out: null, expect: [], killProgram: null, killCommand: null, killCommandFile: null, killMaxS: 3,
    minRate: 10, rateWindowS: 5, waitS: 30, timeoutS: 240, diffFraction: 0.02, diffLevel: 16, blankScreenshot: true,
    chromium: process.env.CHROMIUM || '/usr/bin/chromium', allowBadMessages: false,
  };
  const numbers = { '--kill-max-s': 'killMaxS', '--min-rate': 'minRate', '--rate-window-s': 'rateWindowS', '--wait-s': 'waitS',
    '--timeout-s': 'timeoutS', '--diff-fraction': 'diffFraction', '--diff-level': 'diffLevel' };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => { if (i + 1 >= argv.length) usage(a + ' needs a value'); return argv[++i]; };
    if (a === '--url') o.url = value();
    else if (a === '--out') o.out = value();
    else if (a === '--expect') o.expect = value().split(',').map((s) => s.trim()).filter(Boolean);
    else if (a === '--kill-program') o.killProgram = value();
    else if (a === '--kill-command') o.killCommand = value();
    else if (a === '--kill-command-file') o.killCommandFile = value();
    else if (a === '--chromium') o.chromium = value();
    else if (a === '--blank-screenshot') o.blankScreenshot = true;
    else if (a === '--allow-bad-messages') o.allowBadMessages = true;
    else if (a in numbers) {
      const v = Number(value());
      if (!Number.isFinite(v) || v < 0) usage(a + ' needs a number >= 0');
      o[numbers[a]] = v;
    } else if (a === '--help' || a === '-h') usage();
    else usage('unknown argument ' + a);
  }
  if (!o.url) usage('--url is required');
  if (!o.out) usage('--out is required');
  try { new URL(o.url); } catch { usage('--url is not a URL: ' + o.url); }
  if (o.killProgram && !o.killCommand && !o.killCommandFile) usage('--kill-program needs --kill-command or --kill-command-file');
  if (!o.killProgram && (o.killCommand || o.killCommandFile)) usage('--kill-command needs --kill-program');
  return o;
}

const options = parseArgs(process.argv.slice(2));
fs.mkdirSync(options.out, { recursive: true });
const started = Date.now();
const result = { url: options.url, options: { ...options }, started: new Date(started).toISOString(), checks: [] };
const out = (name) => path.join(options.out, name);
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
// An error's first line, without the terminal colours playwright adds.
const short = (e) => String(e && e.message ? e.message : e).replace(/\x1b\[[0-9;]*m/g, '').split('\n')[0];
const elapsed = () => ((Date.now() - started) / 1000).toFixed(1) + ' s';

function record(name, ok, detail, data) {
  result.checks.push({ name, ok, detail, ...(data ? { data } : {}) });
  console.log((ok ? 'PASS ' : 'FAIL ') + name + ': ' + detail + '  [' + elapsed() + ']');
  return ok;
}

function writeResult() {
  result.finished = new Date().toISOString();
  result.passed = result.checks.filter((c) => c.ok).length;
  result.failed = result.checks.filter((c) => !c.ok).length;
  fs.writeFileSync(out('result.json'), JSON.stringify(result, null, 2) + '\n');
}

// Polls `fn` (async, returns a truthy value when done) every `everyMs` until `timeoutMs`.
async function poll(fn, timeoutMs, everyMs = 100) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const value = await fn();
    if (value) return value;
    if (Date.now() >= end) return null;
    await sleep(everyMs);
  }
}

// In the page: a canvas at its own resolution, in grey levels, pooled into a
// SAMPLE_W x SAMPLE_H grid of cells keeping each cell's darkest and brightest
// pixel (so a thin line or a small tube still counts at any canvas size).
function sampleInPage([selector, w, h]) {
  const canvas = document.querySelector(selector);
  if (!canvas) return { error: 'no element ' + selector };
  const cw = canvas.width, ch = canvas.height;
  if (cw < 1 || ch < 1) return { error: selector + ' has no pixels (' + cw + 'x' + ch + ')' };
  const full = document.createElement('canvas');
  full.width = cw;
  full.height = ch;
  const ctx = full.getContext('2d', { willReadFrequently: true });
  let data;
  try {
    ctx.drawImage(canvas, 0, 0);
    data = ctx.getImageData(0, 0, cw, ch).data;
  } catch (e) {
    return { error: 'cannot read ' + selector + ': ' + e.message };
  }
  const max = new Array(w * h).fill(0), min = new Array(w * h).fill(255);
  let sum = 0, sum2 = 0;
  for (let y = 0; y < ch; y++) {
    const row = Math.min(h - 1, Math.floor((y * h) / ch)) * w;
    for (let x = 0; x < cw; x++) {
      const i = (y * cw + x) * 4;
      const g = (299 * data[i] + 587 * data[i + 1] + 114 * data[i + 2]) / 1000;
      const k = row + Math.min(w - 1, Math.floor((x * w) / cw));
      if (g > max[k]) max[k] = g;
      if (g < min[k]) min[k] = g;
      sum += g;
      sum2 += g * g;
    }
  }
  const n = cw * ch, mean = sum / n;
  return { max: max.map(Math.round), min: min.map(Math.round), mean, std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), size: [cw, ch] };
}

// The fraction of cells whose darkest or brightest pixel moved by more than --diff-level.
function compare(a, b) {
  let differing = 0;
  for (let i = 0; i < a.max.length; i++) {
    if (Math.abs(a.max[i] - b.max[i]) > options.diffLevel || Math.abs(a.min[i] - b.min[i]) > options.diffLevel) differing++;
  }
  return differing / a.max.length;
}

const summary = (s) => ({ mean: +s.mean.toFixed(1), std: +s.std.toFixed(1), size: s.size });
const afterFrames = (page, n = 3) => page.evaluate((count) => new Promise((resolve) => {
  let left = count;
  const step = () => (--left <= 0 ? resolve() : requestAnimationFrame(step));
  requestAnimationFrame(step);
}), n);

function runCommand(command, timeoutMs) {
  return new Promise((resolve) => {
    const child = spawn('sh', ['-c', command], { stdio: ['ignore', 'pipe', 'pipe'] });
    let output = '';
    child.stdout.on('data', (d) => { output += d; });
    child.stderr.on('data', (d) => { output += d; });
    const timer = setTimeout(() => child.kill('SIGKILL'), timeoutMs);
    child.on('error', (e) => { clearTimeout(timer); resolve({ code: -1, output: e.message }); });
    child.on('close', (code, signal) => { clearTimeout(timer); resolve({ code: code ?? signal, output: output.slice(-2000) }); });
  });
}

let browser = null;
let exitCode = 0;
const watchdog = setTimeout(async () => {
  record('timeout', false, 'the whole check took longer than --timeout-s ' + options.timeoutS + ' s');
  writeResult();
  console.log(result.passed + ' passed, ' + result.failed + ' failed');
  try { if (browser) await browser.close(); } catch { /* closing anyway */ }
  process.exit(1);
}, options.timeoutS * 1000);

async function main() {
  try {
    browser = await chromium.launch({ executablePath: options.chromium, args: CHROMIUM_ARGS, timeout: 30000 });
  } catch (e) {
    console.error('monitor_page_check: cannot start Chromium (' + options.chromium + '): ' + short(e));
    result.checks.push({ name: 'chromium', ok: false, detail: short(e) });
    writeResult();
    return 3;
  }
  result.chromium = browser.version();
  const origin = new URL(options.url).origin;
  const pageErrors = [], externalRequests = [], httpErrors = [], consoleErrors = [];
  const watch = (page, label) => {
    page.on('pageerror', (e) => pageErrors.push(label + ': ' + e.message));
    page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(label + ': ' + m.text()); });
    page.on('request', (r) => {
      const u = r.url();
      if (!u.startsWith('data:') && !u.startsWith('blob:') && new URL(u).origin !== origin &&
          new URL(u).origin !== origin.replace(/^http/, 'ws')) externalRequests.push(u);
    });
    page.on('response', (r) => { if (r.status() >= 400) httpErrors.push(r.status() + ' ' + r.url()); });
  };

  try {
    // ---- the live page
    const live = await (await browser.newContext({ viewport: VIEWPORT })).newPage();
    watch(live, 'live');
    try {
      await live.goto(options.url, { waitUntil: 'load', timeout: 20000 });
    } catch (e) {
      record('page', false, 'cannot load ' + options.url + ': ' + short(e));
      return 1;
    }
    const gotHello = await live.waitForFunction(() => window.shapesenseMonitor && window.shapesenseMonitor.hello,
      null, { timeout: options.waitS * 1000 }).then(() => true, () => false);
    if (!gotHello) {
      const state = await live.evaluate(() => window.shapesenseMonitor
        ? { connectionState: window.shapesenseMonitor.connectionState, errors: window.shapesenseMonitor.errors,
            lastError: window.shapesenseMonitor.lastError } : null);
      record('page', false, 'no hello within ' + options.waitS + ' s (' + JSON.stringify(state) + ')');
      await live.screenshot({ path: out('after.png') }).catch(() => {});
      return 1;
    }
    const hello = await live.evaluate(() => window.shapesenseMonitor.hello);
    const cameraNames = hello.cameras.map((c) => c.name);
    result.hello = { host: hello.host, cameras: cameraNames, estop_enabled: hello.estop_enabled };
    record('page', true, 'loaded, hello from ' + hello.host + ' with cameras ' + (cameraNames.join(', ') || 'none'));

    // ---- the blank reference: the same page fed nothing
    const blankContext = await browser.newContext({ viewport: VIEWPORT });
    const blank = await blankContext.newPage();
    watch(blank, 'blank');
    const reference = { cameras: {} };
    try {
      await blank.goto(options.url + (options.url.includes('#') ? '&' : '#') + 'nows', { waitUntil: 'load', timeout: 20000 });
      await blank.waitForFunction(() => window.shapesenseMonitor && window.shapesenseMonitor.ready, null, { timeout: 10000 });
      await afterFrames(blank, 5);
      reference.view3d = await blank.evaluate(sampleInPage, ['#view3d', SAMPLE_W, SAMPLE_H]);
      if (options.blankScreenshot) await blank.screenshot({ path: out('before.png') });
      await blank.evaluate((h) => window.shapesenseMonitor.handleText(JSON.stringify(h)), hello);
      await afterFrames(blank, 5);
      for (const name of cameraNames) {
        reference.cameras[name] = await blank.evaluate(sampleInPage,
          ['canvas.camera-canvas[data-camera="' + CSS_escape(name) + '"]', SAMPLE_W, SAMPLE_H]);
      }
      record('blank', true, 'reference page rendered (before.png)', {
        view3d: reference.view3d.error || summary(reference.view3d),
        cameras: Object.fromEntries(Object.entries(reference.cameras).map(([k, v]) => [k, v.error || summary(v)])),
      });
    } catch (e) {
      record('blank', false, 'cannot render the blank reference page: ' + short(e));
    } finally {
      await blankContext.close();
    }

    // ---- frames on the live page
    const frames = await poll(() => live.evaluate((names) => {
      const m = window.shapesenseMonitor;
      const missing = names.filter((n) => !(m.cameras[n] && m.cameras[n].decoded >= 1));
      return missing.length === 0 && (m.updatesByType.shape || 0) >= 1 ? true : null;
    }, cameraNames), options.waitS * 1000, 200);
    const status = await live.evaluate(() => ({
      cameras: window.shapesenseMonitor.cameras, byType: window.shapesenseMonitor.updatesByType,
    }));
    result.frames = status;
    if (!frames) {
      const missing = cameraNames.filter((n) => !(status.cameras[n] && status.cameras[n].decoded >= 1));
      record('frames', false, 'within ' + options.waitS + ' s: ' +
        (missing.length ? 'no decoded frame from ' + missing.join(', ') : '') +
        (!(status.byType.shape >= 1) ? (missing.length ? '; ' : '') + 'no shape' : ''), status);
    } else {
      record('frames', true, 'a decoded frame from every camera (' + cameraNames.map((n) => n + ' ' +
        status.cameras[n].decoded).join(', ') + ') and ' + status.byType.shape + ' shapes');
    }
    await sleep(500);
    await afterFrames(live, 3);
    await live.screenshot({ path: out('after.png') });

    // ---- pixels: live canvases against the blank reference
    result.pixels = { cameras: {} };
    const cameraFailures = [];
    for (const name of cameraNames) {
      const sample = await live.evaluate(sampleInPage,
        ['canvas.camera-canvas[data-camera="' + CSS_escape(name) + '"]', SAMPLE_W, SAMPLE_H]);
      const ref = reference.cameras[name];
      if (sample.error || !ref || ref.error) {
        cameraFailures.push(name + ': ' + (sample.error || (ref && ref.error) || 'no blank reference'));
        continue;
      }
      const fraction = compare(sample, ref);
      result.pixels.cameras[name] = { differing_fraction: +fraction.toFixed(4), live: summary(sample), blank: summary(ref) };
      if (fraction <= options.diffFraction) cameraFailures.push(name + ' differs in only ' + (fraction * 100).toFixed(2) + ' %');
    }
    if (!cameraNames.length) cameraFailures.push('the server reports no cameras');
    record('cameras', cameraFailures.length === 0, cameraFailures.length ? cameraFailures.join('; ')
      : 'every camera canvas differs from the blank pane (' + cameraNames.map((n) => n + ' ' +
        (result.pixels.cameras[n].differing_fraction * 100).toFixed(1) + ' %').join(', ') + ')');

    const view = await live.evaluate(() => window.shapesenseMonitor.view3d());
    result.view3d = view;
    if (!view.ok) {
      record('view3d', false, '3-D view unavailable: ' + view.failure);
    } else {
      const sample = await live.evaluate(sampleInPage, ['#view3d', SAMPLE_W, SAMPLE_H]);
      if (sample.error || !reference.view3d || reference.view3d.error) {
        record('view3d', false, sample.error || (reference.view3d && reference.view3d.error) || 'no blank reference');
      } else {
        const fraction = compare(sample, reference.view3d);
        result.pixels.view3d = { differing_fraction: +fraction.toFixed(4), live: summary(sample), blank: summary(reference.view3d) };
        record('view3d', fraction > options.diffFraction, 'differs from the blank view in ' + (fraction * 100).toFixed(1) +
          ' % of its pixels (needs > ' + (options.diffFraction * 100).toFixed(1) + ' %; WebGL: ' + view.renderer + ')');
      }
    }

    // ---- update rate
    const a = await live.evaluate(() => [window.shapesenseMonitor.updates, performance.now()]);
    await sleep(options.rateWindowS * 1000);
    const b = await live.evaluate(() => [window.shapesenseMonitor.updates, performance.now(), window.shapesenseMonitor.updatesByType]);
    const rate = (b[0] - a[0]) / ((b[1] - a[1]) / 1000);
    result.rate = { updates_per_s: +rate.toFixed(2), updates: b[0] - a[0], window_s: +((b[1] - a[1]) / 1000).toFixed(3), by_type: b[2] };
    record('rate', rate >= options.minRate, rate.toFixed(1) + ' updates/s over ' + result.rate.window_s + ' s (needs >= ' + options.minRate + ')');

    // ---- health rows
    const rowsNow = () => live.evaluate(() => Array.from(document.querySelectorAll('[data-testid="health-row"]'))
      .map((r) => ({ host: r.dataset.host || '', program: r.dataset.program, state: r.dataset.state })));
    if (options.expect.length) {
      const allUp = await poll(async () => {
        const rows = await rowsNow();
        return options.expect.every((p) => rows.some((r) => r.program === p && r.state === 'up')) ? rows : null;
      }, options.waitS * 1000, 250);
      const rows = allUp || await rowsNow();
      result.health = rows;
      const notUp = options.expect.filter((p) => !rows.some((r) => r.program === p && r.state === 'up'));
      record('health', notUp.length === 0, notUp.length
        ? 'not up: ' + notUp.map((p) => p + ' (' + (rows.filter((r) => r.program === p).map((r) => r.host + ' ' + r.state).join(', ') || 'no row') + ')').join('; ')
        : 'up: ' + options.expect.join(', ') + ' (' + rows.length + ' rows)');
    } else {
      result.health = await rowsNow();
    }

    // ---- messages, page errors, external requests
    const m = await live.evaluate(() => ({ errors: window.shapesenseMonitor.errors, lastError: window.shapesenseMonitor.lastError,
      renderErrors: window.shapesenseMonitor.renderErrors || 0, lastRenderError: window.shapesenseMonitor.lastRenderError || null,
      ignored: window.shapesenseMonitor.ignoredByType }));
    result.messages = { ...m, pageErrors, externalRequests, httpErrors, consoleErrors };
    const problems = [];
    if (m.errors && !options.allowBadMessages) problems.push(m.errors + ' malformed messages (last: ' + m.lastError + ')');
    if (m.renderErrors) problems.push(m.renderErrors + ' drawing errors (last: ' + m.lastRenderError + ')');
    if (pageErrors.length) problems.push('uncaught page errors: ' + pageErrors.slice(0, 3).join(' | '));
    if (externalRequests.length) problems.push('requests to other origins: ' + externalRequests.slice(0, 3).join(', '));
    record('messages', problems.length === 0, problems.length ? problems.join('; ')
      : 'no malformed message, no page error, no external request' + (httpErrors.length ? ' (HTTP errors: ' + httpErrors.join(', ') + ')' : ''));

    // ---- the README picture, healthy
    await live.screenshot({ path: out('monitor.png'), fullPage: true });

    // ---- kill a program: its row must go "missing" within --kill-max-s
    if (options.killProgram) {
      const name = options.killProgram;
      const stateOf = () => live.evaluate((program) => Array.from(
        document.querySelectorAll('[data-testid="health-row"][data-program="' + program.replace(/"/g, '\\"') + '"]'))
        .map((r) => r.dataset.state), name);
      const before = await stateOf();
      let command = options.killCommand;
      if (!command) {
        try { command = fs.readFileSync(options.killCommandFile, 'utf8').trim(); } catch (e) { command = null; result.kill = { error: e.message }; }
      }
      if (!before.includes('up')) {
        record('kill', false, name + ' is not up before the kill (' + (before.join(', ') || 'no row') + ')');
      } else if (!command) {
        record('kill', false, 'no kill command: cannot read ' + options.killCommandFile);
      } else {
        const t0 = Date.now();
        const run = await runCommand(command, 10000);
        const tKilled = Date.now();
        result.kill = { program: name, command, exit: run.code, output: run.output, command_s: (tKilled - t0) / 1000 };
        if (run.code !== 0) {
          record('kill', false, 'the kill command exited ' + run.code + ': ' + run.output.trim().slice(-300));
        } else {
          let staleAt = null, states = before;
          const missing = await poll(async () => {
            states = await stateOf();
            if (staleAt === null && states.includes('stale')) staleAt = Date.now();
            return states.includes('missing') ? Date.now() : null;
          }, (options.killMaxS + 5) * 1000, 100);
          const delay = missing ? (missing - tKilled) / 1000 : null;
          Object.assign(result.kill, { missing_after_s: delay, stale_after_s: staleAt ? (staleAt - tKilled) / 1000 : null, states_at_end: states });
          await live.screenshot({ path: out('killed.png') }).catch(() => {});
          if (delay === null) {
            record('kill', false, name + ' never showed as missing in ' + (options.killMaxS + 5) + ' s after the kill (row: ' + (states.join(', ') || 'gone') + ')');
          } else {
            console.log('kill: ' + name + ' shows as missing ' + delay.toFixed(2) + ' s after the kill' +
              (staleAt ? ' (stale after ' + ((staleAt - tKilled) / 1000).toFixed(2) + ' s)' : ''));
            record('kill', delay <= options.killMaxS, name + ' missing after ' + delay.toFixed(2) + ' s (needs <= ' + options.killMaxS + ' s)');
          }
        }
      }
    }
  } finally {
    await browser.close().catch(() => {});
    browser = null;
  }
  return result.checks.some((c) => !c.ok) ? 1 : 0;
}

function CSS_escape(s) {
  return String(s).replace(/["\\]/g, '\\$&');
}

try {
  exitCode = await main();
} catch (e) {
  record('internal', false, 'the check itself failed: ' + (e && e.stack ? e.stack : e));
  exitCode = 1;
}
clearTimeout(watchdog);
writeResult();
console.log(result.passed + ' passed, ' + result.failed + ' failed');
if (exitCode !== 0) {
  const failed = result.checks.filter((c) => !c.ok).map((c) => c.name);
  console.error('monitor_page_check: FAILED ' + (failed.join(', ') || 'to run') + ' (see ' + out('result.json') + ')');
}
process.exit(exitCode);
