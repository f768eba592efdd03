#!/usr/bin/env node
// A stand-in for the monitor server, for developing and testing the page
// without the C++ pipeline: serves services/monitor/web/ at / and three.js
// at /vendor/, and speaks the monitor's WebSocket protocol at /ws with the
// synthetic rig of synthetic_rig.mjs (hello, shape and truth at 30 Hz,
// camera frames at 10 Hz each, controller, target, health and stats).
//
//   node fake_monitor.mjs [--port 0] [--duration-s 600] [--estop-token T]
//                         [--control-dir DIR] [--missing-after-s 1.0] [--camera-hz 10]
//
// Prints "listening on http://127.0.0.1:PORT/" when ready, and stops by
// itself after --duration-s. With --control-dir, creating DIR/kill-PROGRAM
// "kills" that program: its health row goes stale at once and missing after
// --missing-after-s (a pipeline program also stops the shapes and frames).
// Listens on 127.0.0.1 only. No packages: node's http, crypto and fs.
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import * as rig from './synthetic_rig.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
// The page's folder: beside this one in the repository, or where SHAPESENSE_MONITOR_WEB says
// (the build tree runs a copy of these scripts next to its node_modules).
export const WEB_DIR = process.env.SHAPESENSE_MONITOR_WEB || path.resolve(HERE, '../../services/monitor/web');
export const VENDOR = {
  'three.min.js': '/usr/share/javascript/three/build/three.min.js',
  'OrbitControls.js': '/usr/share/javascript/three/examples/js/controls/OrbitControls.js',
};
const TYPES = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8', '.css': 'text/css; charset=utf-8',
  '.json': 'application/json', '.png': 'image/png', '.svg': 'image/svg+xml' };
const PIPELINE = new Set(['capture', 'carving', 'shape', 'rig_sim']);

function staticFile(urlPath, webDir) {
  let p = decodeURIComponent(urlPath.split(/[?#]/)[0]);
  if (p === '/') p = '/index.html';
  if (p.includes('..') || p.includes('\\') || p.includes('\0')) return null;
  if (p.startsWith('/vendor/')) return VENDOR[p.slice('/vendor/'.length)] || null;
  const file = path.join(webDir, p);
  return file.startsWith(webDir + path.sep) ? file : null;
}

// ---- minimal WebSocket (RFC 6455) server side: unmasked frames out, masked frames in.
function wsFrame(opcode, payload) {
  const n = payload.length;
  const head = n < 126 ? Buffer.from([0x80 | opcode, n])
    : n < 65536 ? Buffer.from([0x80 | opcode, 126, n >> 8, n & 255])
      : (() => { const b = Buffer.alloc(10); b[0] = 0x80 | opcode; b[1] = 127; b.writeBigUInt64BE(BigInt(n), 2); return b; })();
  return Buffer.concat([head, payload]);
}

class Client {
  constructor(socket, server) {
    this.socket = socket;
    this.server = server;
    this.buffer = Buffer.alloc(0);
    this.closed = false;
    socket.on('data', (d) => this.onData(d));
    socket.on('close', () => { this.closed = true; server.clients.delete(this); });
    socket.on('error', () => { this.closed = true; server.clients.delete(this); });
  }
  sendText(obj) { this.write(wsFrame(0x1, Buffer.from(typeof obj === 'string' ? obj : JSON.stringify(obj), 'utf8'))); }
  sendBinary(buf) {
    if (this.socket.writableLength > 2 * 1024 * 1024) { this.server.skipped++; return; } // a slow page gets fewer frames
    this.write(wsFrame(0x2, buf));
  }
  write(buf) { if (!this.closed) this.socket.write(buf); }
  onData(data) {
    this.buffer = Buffer.concat([this.buffer, data]);
    for (;;) {
      const b = this.buffer;
      if (b.length < 2) return;
      const opcode = b[0] & 0x0f, masked = (b[1] & 0x80) !== 0;
      let n = b[1] & 0x7f, at = 2;
      if (n === 126) { if (b.length < 4) return; n = b.readUInt16BE(2); at = 4; }
      else if (n === 127) { if (b.length < 10) return; n = Number(b.readBigUInt64BE(2)); at = 10; }
      if (n > 65536) { this.socket.destroy(); return; }
      const maskAt = at; if (masked) at += 4;
      if (b.length < at + n) return;
      const payload = Buffer.from(b.subarray(at, at + n));
      if (masked) for (let i = 0; i < n; i++) payload[i] ^= b[maskAt + (i & 3)];
      this.buffer = b.subarray(at + n);
      if (opcode === 0x8) { this.write(wsFrame(0x8, Buffer.alloc(0))); this.socket.end(); return; }
      if (opcode === 0x9) { this.write(wsFrame(0xa, payload)); continue; }
      if (opcode === 0x1) this.server.onClientText(this, payload.toString('utf8'));
    }
  }
}

export async function startFakeMonitor(options = {}) {
  const webDir = path.resolve(options.webDir || WEB_DIR);
  const cameras = rig.makeCameras(options.cameraCount || 3);
  const started = performance.now();
  const epochUs = Date.now() * 1000;
  const state = {
    clients: new Set(), skipped: 0, killed: new Map(), seq: 0, received: [],
    onClientText(client, text) {
      state.received.push(text);
      let m;
      try { m = JSON.parse(text); } catch { return; }
      if (m.type === 'estop') {
        const ok = !!options.estopToken && m.token === options.estopToken;
        client.sendText({ type: 'estop_result', ok, message: ok ? 'controller stopped' : 'bad token' });
      }
    },
  };
  const t = () => (performance.now() - started) / 1000;
  const utime = () => epochUs + Math.round(t() * 1e6);

  const server = http.createServer((req, res) => {
    const file = staticFile(req.url, webDir);
    if (!file || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found\n');
      return;
    }
    res.writeHead(200, { 'content-type': TYPES[path.extname(file)] || 'application/octet-stream', 'cache-control': 'no-cache' });
    fs.createReadStream(file).pipe(res);
  });
  server.on('upgrade', (req, socket) => {
    if (req.url !== '/ws' || !req.headers['sec-websocket-key']) { socket.destroy(); return; }
    const accept = crypto.createHash('sha1').update(req.headers['sec-websocket-key'] + '258EAFA5-E914-47DA-95CA-C5AB0DC85B11').digest('base64');
    socket.write('HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: ' + accept + '\r\n\r\n');
    socket.setNoDelay(true);
    const client = new Client(socket, state);
    state.clients.add(client);
    client.sendText(rig.helloMessage(cameras, { estopEnabled: !!options.estopToken, startedUtime: epochUs }));
    if (state.lastTarget) client.sendText(state.lastTarget);
    if (state.lastHealth) client.sendText(state.lastHealth);
  });
  await new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(options.port || 0, '127.0.0.1', resolve);
  });
  const port = server.address().port;
  const broadcast = (obj) => { const s = JSON.stringify(obj); for (const c of state.clients) c.sendText(s); };
  const pipelineDown = () => [...state.killed.keys()].some((p) => PIPELINE.has(p));
  const killedSince = () => new Map([...state.killed].map(([p, at]) => [p, t() - at]));

  const timers = [];
  const every = (ms, fn) => timers.push(setInterval(() => { try { fn(); } catch (e) { console.error('fake monitor:', e); } }, ms));
  let latestShape = null;
  every(33, () => {
    if (pipelineDown() || !state.clients.size) return;
    state.seq++;
    latestShape = rig.shapeMessage('shape', state.seq, t(), { epochUs, valid: state.seq % 300 !== 0 });
    broadcast(latestShape);
    broadcast(rig.shapeMessage('truth', state.seq, t(), { epochUs }));
  });
  every(50, () => { if (state.clients.size) broadcast(rig.controllerMessage(t(), utime())); });
  every(2000, () => { state.lastTarget = rig.targetMessage(t(), utime()); broadcast(state.lastTarget); });
  every(500, () => {
    state.lastHealth = rig.healthMessage(t(), utime(), killedSince(), options.missingAfterS ?? 1.0);
    broadcast(state.lastHealth);
    broadcast(rig.statsMessage(t(), utime()));
  });
  let cameraTurn = 0;
  every(Math.round(1000 / (options.cameraHz || 10) / cameras.length), () => { // each camera in turn
    if (pipelineDown() || !latestShape || !state.clients.size) return;
    const camera = cameras[cameraTurn++ % cameras.length];
    const frame = rig.cameraFrame(camera, latestShape, latestShape.trigger_seq);
    for (const c of state.clients) c.sendBinary(frame);
  });
  if (options.controlDir) {
    every(100, () => {
      for (const name of fs.readdirSync(options.controlDir)) {
        const m = /^kill-(.+)$/.exec(name);
        if (m && !state.killed.has(m[1])) state.killed.set(m[1], t());
      }
    });
  }
  const stop = async () => {
    for (const id of timers) clearInterval(id);
    for (const c of state.clients) c.socket.destroy();
    await new Promise((resolve) => server.close(resolve));
  };
  if (options.durationS) {
    const id = setTimeout(stop, options.durationS * 1000);
    id.unref();
  }
  return { port, url: 'http://127.0.0.1:' + port + '/', state, stop, cameras };
}

function parseArgs(argv) {
  const o = {};
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => { if (i + 1 >= argv.length) throw new Error(a + ' needs a value'); return argv[++i]; };
    if (a === '--port') o.port = Number(value());
    else if (a === '--duration-s') o.durationS = Number(value());
    else if (a === '--estop-token') o.estopToken = value();
    else if (a === '--control-dir') o.controlDir = value();
    else if (a === '--missing-after-s') o.missingAfterS = Number(value());
    else if (a === '--web-dir') o.webDir = value();
    else if (a === '--camera-hz') o.cameraHz = Number(value());
    else if (a === '--help' || a === '-h') {
      console.log('usage: node fake_monitor.mjs [--port N] [--duration-s S] [--estop-token T] [--control-dir DIR] [--missing-after-s S] [--camera-hz HZ] [--web-dir DIR]');
      process.exit(0);
    } else throw new Error('unknown argument ' + a);
  }
  return o;
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  let options;
  try {
    options = parseArgs(process.argv.slice(2));
  } catch (e) {
    console.error('fake_monitor: ' + e.message);
    process.exit(2);
  }
  options.durationS = options.durationS ?? 600;
  const fake = await startFakeMonitor(options);
  console.log('listening on ' + fake.url);
  const done = () => fake.stop().then(() => process.exit(0));
  process.on('SIGINT', done);
  process.on('SIGTERM', done);
  setTimeout(done, options.durationS * 1000 + 100);
}
