// A synthetic rig for testing the monitor page without the C++ pipeline:
// three pinhole cameras around a bending 160 mm tube, the monitor
// protocol's messages for it (hello, shape, truth, target, controller,
// health, stats) and binary camera frames with a real JPEG (a small
// grey-scale baseline JPEG encoder, no packages). World frame in mm, z up.

const W = 640, H = 480, F = 600;

function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
function scale(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function norm(a) { const n = Math.hypot(a[0], a[1], a[2]); return scale(a, 1 / n); }
const round = (v, d = 2) => Number(v.toFixed(d));
const roundV = (v, d = 2) => v.map((x) => round(x, d));

// Cameras on a circle of 450 mm, 260 mm up, looking at (0, 0, 90).
export function makeCameras(count = 3) {
  const cameras = [];
  for (let i = 0; i < count; i++) {
    const a = (i * 2 * Math.PI) / count + 0.3;
    const C = [450 * Math.cos(a), 450 * Math.sin(a), 260];
    const forward = norm(sub([0, 0, 90], C));
    const right = norm(cross(forward, [0, 0, 1]));
    const down = cross(forward, right);
    const R = [right, down, forward]; // rows: world → camera
    const ray = (u, v, depth) => {
      const p = [((u - W / 2) / F) * depth, ((v - H / 2) / F) * depth, depth];
      return add(C, add(add(scale(right, p[0]), scale(down, p[1])), scale(forward, p[2])));
    };
    cameras.push({
      name: 'cam' + i, width: W, height: H, C, R,
      frustum: [C, ray(0, 0, 150), ray(W, 0, 150), ray(W, H, 150), ray(0, H, 150)].map((p) => roundV(p)),
    });
  }
  return cameras;
}

export function project(camera, X) {
  const d = sub(X, camera.C);
  const x = dot(camera.R[0], d), y = dot(camera.R[1], d), z = dot(camera.R[2], d);
  return [F * (x / z) + W / 2, F * (y / z) + H / 2, z];
}

// A constant-curvature arc of `length` mm from the origin going up +z,
// bending by `angle` rad towards the direction `plane` (rad) of the x-y plane.
export function arc(angle, plane, length = 160, n = 41) {
  const d = [Math.cos(plane), Math.sin(plane), 0];
  const points = [];
  for (let i = 0; i < n; i++) {
    const s = (length * i) / (n - 1);
    let side, up;
    if (Math.abs(angle) < 1e-6) { side = 0; up = s; } else {
      const r = length / angle;
      side = r * (1 - Math.cos(s / r));
      up = r * Math.sin(s / r);
    }
    points.push([d[0] * side, d[1] * side, up]);
  }
  return points;
}

export const MARKER_FRACTIONS = [0.25, 0.55, 0.85];

export function shapeAt(t) {
  const angle = 1.3 * Math.sin((2 * Math.PI * t) / 8);
  const plane = 0.35 * t;
  return { angle, plane, centerline: arc(angle, plane) };
}

function pointAt(centerline, fraction) {
  const x = fraction * (centerline.length - 1);
  const i = Math.min(centerline.length - 2, Math.floor(x));
  const f = x - i;
  return add(scale(centerline[i], 1 - f), scale(centerline[i + 1], f));
}

export function shapeMessage(type, seq, t, options = {}) {
  const { angle, plane, centerline } = shapeAt(t);
  const noise = type === 'shape' ? 0.4 : 0;
  const jitter = (p, k) => p.map((x, j) => x + noise * Math.sin(seq * 0.7 + k * 0.15 + j * 2.1));
  const line = centerline.map((p, k) => roundV(jitter(p, k)));
  const kappa = angle / 160;
  const stages = [
    { stage: 'capture', ms: round(1.0 + 0.3 * Math.sin(seq / 7)) },
    { stage: 'carving', ms: round(3.0 + 0.8 * Math.sin(seq / 5)) },
    { stage: 'shape', ms: round(4.0 + 1.0 * Math.sin(seq / 11)) },
    { stage: 'transport', ms: round(2.0 + 0.5 * Math.sin(seq / 3)) },
  ];
  return {
    type, trigger_seq: seq, trigger_utime: Math.round(t * 1e6) + (options.epochUs || 0),
    valid: options.valid !== false, error: options.valid === false ? 'too few voxels' : '',
    centerline: line,
    markers: MARKER_FRACTIONS.map((f) => roundV(pointAt(line, f))),
    tip: line[line.length - 1],
    q: [round(kappa * Math.sin(plane), 6), round(-kappa * Math.cos(plane), 6), 0.01, 0.02],
    length: round(160 - noise * 0.5, 1), residual_mm: type === 'shape' ? round(0.3 + 0.1 * Math.sin(seq / 9), 3) : 0,
    stages: type === 'shape' ? stages : [],
    latency_ms: type === 'shape' ? round(stages.reduce((a, s) => a + s.ms, 0) + 12) : 0,
  };
}

export function targetMessage(t, utime) {
  const angle = 1.3 * Math.sin((2 * Math.PI * (t + 1.0)) / 8);
  const plane = 0.35 * (t + 1.0);
  const centerline = arc(angle, plane).map((p) => roundV(p));
  const kappa = angle / 160;
  return {
    type: 'target', kind: 'configuration',
    q: [round(kappa * Math.sin(plane), 6), round(-kappa * Math.cos(plane), 6), 0.01, 0.02],
    tip: centerline[centerline.length - 1], centerline, duration_s: 2.0, source: 'demo', utime,
  };
}

export function controllerMessage(t, utime) {
  const commanded = [0, 1, 2, 3].map((i) => round(4 * Math.sin((2 * Math.PI * t) / 8 + (i * Math.PI) / 2), 3));
  const actual = [0, 1, 2, 3].map((i) => round(4 * Math.sin((2 * Math.PI * (t - 0.15)) / 8 + (i * Math.PI) / 2), 3));
  return {
    type: 'controller', utime, mode: 'closed_loop', gate: Math.floor(t) % 10 === 9 ? 'held' : 'ok',
    gate_reasons: Math.floor(t) % 10 === 9 ? ['rate limited'] : [],
    commanded_mm: commanded, actual_mm: actual, tensions_n: actual.map((a) => round(5 + a, 2)),
    tip_error_mm: round(1.2 + 0.6 * Math.sin(t * 1.3), 3),
  };
}

export const PROGRAMS = [
  { host: 'cam-host', program: 'capture' },
  { host: 'cam-host', program: 'carving' },
  { host: 'cam-host', program: 'shape' },
  { host: 'cam-host', program: 'rig_sim' },
  { host: 'control', program: 'controller' },
  { host: 'operator', program: 'lcm-logger' },
  { host: 'cam-host', program: 'monitor' },
];

// `killed`: program → seconds since it was killed (state stale at once, missing after `missingAfterS`).
export function healthMessage(t, nowUtime, killed = new Map(), missingAfterS = 1.0) {
  const rows = PROGRAMS.map((p, i) => {
    const since = killed.get(p.program);
    if (since !== undefined) {
      return { host: p.host, program: p.program, state: since >= missingAfterS ? 'missing' : 'stale',
        status_age_s: round(since + 0.5, 1) };
    }
    return {
      host: p.host, program: p.program, state: 'up', pid: 4000 + i * 17, uptime_s: round(t + 3600 * i, 1),
      status_age_s: 0.2, input_rate_hz: p.program === 'lcm-logger' ? 120 : 29.9, output_rate_hz: 29.9,
      received: Math.round(t * 30), published: Math.round(t * 30), dropped: i === 1 ? 2 : 0, rejected: 0,
      errors: 0, queue_depth: i % 3, cpu_percent: round(5 + 10 * i, 1), rss_bytes: (40 + 12 * i) * 1048576,
      clock_offsets_ms: p.host === 'cam-host' ? { control: 0.12, operator: -0.31 } : { 'cam-host': -0.12 },
      clock_warning: '', last_error: i === 4 ? 'target rejected: outside the workspace' : '', auth: 'on (keys 1)',
    };
  });
  rows.push({ host: 'stray', program: 'unknown-tool', state: 'unexpected', pid: 999, uptime_s: 12 });
  return { type: 'health', now_utime: nowUtime, rows };
}

export function statsMessage(t, utime, lostSets = 3) {
  return {
    type: 'stats', utime, frame_set_rate_hz: round(29.8 + 0.2 * Math.sin(t)), shape_rate_hz: round(29.6 + 0.3 * Math.sin(t * 0.7)),
    lost_sets: lostSets, invalid_shapes: Math.floor(t / 20),
    latency_ms: { capture: 1.0, carving: 3.0, shape: 4.0, total: 25.0 }, p99_latency_ms: round(38 + 3 * Math.sin(t)),
  };
}

// The tube's silhouette in one camera (full-resolution runs) and its overlays.
export function cameraOverlay(camera, shape) {
  const mask = new Uint8Array(W * H); // 1 tube, 2 tape
  const line = shape.centerline;
  const paint = (u, v, r, value) => {
    const r2 = r * r;
    for (let y = Math.max(0, Math.floor(v - r)); y <= Math.min(H - 1, Math.ceil(v + r)); y++) {
      for (let x = Math.max(0, Math.floor(u - r)); x <= Math.min(W - 1, Math.ceil(u + r)); x++) {
        if ((x - u) ** 2 + (y - v) ** 2 <= r2 && mask[y * W + x] < value) mask[y * W + x] = value;
      }
    }
  };
  const n = line.length;
  for (let k = 0; k < n - 1; k++) {
    const a = project(camera, line[k]), b = project(camera, line[k + 1]);
    const steps = Math.max(1, Math.ceil(Math.hypot(b[0] - a[0], b[1] - a[1])));
    for (let s = 0; s <= steps; s++) {
      const f = s / steps;
      const u = a[0] + (b[0] - a[0]) * f, v = a[1] + (b[1] - a[1]) * f, z = a[2] + (b[2] - a[2]) * f;
      const frac = (k + f) / (n - 1);
      const tape = MARKER_FRACTIONS.some((m) => Math.abs(frac - m) * 160 < 2);
      paint(u, v, (F * 3) / z, tape ? 2 : 1);
    }
  }
  const runs = { mask: [], tape: [] };
  for (let y = 0; y < H; y++) {
    for (const [value, list] of [[1, runs.mask], [2, runs.tape]]) {
      let begin = -1;
      for (let x = 0; x <= W; x++) {
        const on = x < W && (value === 1 ? mask[y * W + x] >= 1 : mask[y * W + x] === 2);
        if (on && begin < 0) begin = x;
        if (!on && begin >= 0) { list.push([y, begin, x]); begin = -1; }
      }
    }
  }
  const uv = (p) => { const q = project(camera, p); return [round(q[0], 1), round(q[1], 1)]; };
  return {
    mask,
    silhouette: runs,
    centerline: line.map(uv),
    markers: shape.markers.map(uv),
    tip: uv(shape.tip),
  };
}

// A grey picture of the scene at `jpegScale` of full resolution.
export function cameraImage(mask, seq, jpegScale = 0.5) {
  const w = Math.round(W * jpegScale), h = Math.round(H * jpegScale);
  const pixels = new Uint8Array(w * h);
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const m = mask[Math.min(H - 1, Math.floor(y / jpegScale)) * W + Math.min(W - 1, Math.floor(x / jpegScale))];
      let g = 70 + 50 * (y / h) + 12 * Math.sin((x + seq * 2) / 23) * Math.cos(y / 17);
      if (((x >> 4) + (y >> 4)) % 2 === 0 && y > h * 0.75) g += 25; // a checker "table"
      if (m === 1) g = 215;
      if (m === 2) g = 40;
      pixels[y * w + x] = Math.max(0, Math.min(255, g));
    }
  }
  return encodeGreyJpeg(pixels, w, h, 80);
}

export function cameraFrame(camera, shape, seq, options = {}) {
  const overlay = cameraOverlay(camera, shape);
  const jpeg = options.noJpeg ? new Uint8Array(0) : cameraImage(overlay.mask, seq, options.jpegScale ?? 0.5);
  const meta = {
    type: 'camera', camera: camera.name, trigger_seq: seq, width: W, height: H,
    silhouette: overlay.silhouette, centerline: overlay.centerline, markers: overlay.markers, tip: overlay.tip,
  };
  return packCameraFrame(meta, jpeg);
}

export function packCameraFrame(meta, jpeg) {
  const json = Buffer.from(JSON.stringify(meta), 'utf8');
  const out = Buffer.alloc(4 + json.length + jpeg.length);
  out.writeUInt32LE(json.length, 0);
  json.copy(out, 4);
  Buffer.from(jpeg.buffer, jpeg.byteOffset, jpeg.byteLength).copy(out, 4 + json.length);
  return out;
}

export function helloMessage(cameras, options = {}) {
  return {
    type: 'hello', version: 1, host: options.host || 'cam-host', rig_prefix: '', estop_enabled: !!options.estopEnabled,
    started_utime: options.startedUtime || Date.now() * 1000,
    cameras: cameras.map((c) => ({ name: c.name, width: c.width, height: c.height, frustum: c.frustum })),
  };
}

// ------------------------------------------------------------------ JPEG
// Baseline, grey-scale, standard (Annex K) luminance tables.
const ZIGZAG = [0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34, 27, 20, 13, 6, 7, 14,
  21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47,
  55, 62, 63];
const STD_Q = [16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69, 56, 14, 17, 22, 29,
  51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81, 104, 113, 92, 49, 64, 78, 87, 103, 121, 120, 101, 72,
  92, 95, 98, 112, 100, 103, 99];
const DC_BITS = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];
const DC_VALS = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11];
const AC_BITS = [0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 0x7d];
const AC_VALS = [0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07, 0x22, 0x71,
  0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52, 0xd1, 0xf0, 0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0a,
  0x16, 0x17, 0x18, 0x19, 0x1a, 0x25, 0x26, 0x27, 0x28, 0x29, 0x2a, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45,
  0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69, 0x6a,
  0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96,
  0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9,
  0xba, 0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2,
  0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa];

function huffmanCodes(bits, vals) {
  const codes = new Map();
  let code = 0, k = 0;
  for (let length = 1; length <= 16; length++) {
    for (let i = 0; i < bits[length - 1]; i++) codes.set(vals[k++], [code++, length]);
    code <<= 1;
  }
  return codes;
}
const DC_CODES = huffmanCodes(DC_BITS, DC_VALS);
const AC_CODES = huffmanCodes(AC_BITS, AC_VALS);
const COS = Array.from({ length: 64 }, (_, i) => {
  const x = i >> 3, u = i & 7;
  return Math.cos(((2 * x + 1) * u * Math.PI) / 16) * (u === 0 ? Math.SQRT1_2 : 1);
});

export function encodeGreyJpeg(pixels, width, height, quality = 80) {
  const s = quality < 50 ? 5000 / quality : 200 - 2 * quality;
  const q = STD_Q.map((v) => Math.max(1, Math.min(255, Math.floor((v * s + 50) / 100))));
  const out = [];
  const u16 = (v) => out.push((v >> 8) & 255, v & 255);
  out.push(0xff, 0xd8);
  out.push(0xff, 0xe0); u16(16); out.push(0x4a, 0x46, 0x49, 0x46, 0, 1, 1, 0); u16(1); u16(1); out.push(0, 0);
  out.push(0xff, 0xdb); u16(67); out.push(0); for (let k = 0; k < 64; k++) out.push(q[ZIGZAG[k]]);
  out.push(0xff, 0xc0); u16(11); out.push(8); u16(height); u16(width); out.push(1, 1, 0x11, 0);
  out.push(0xff, 0xc4); u16(3 + 16 + DC_VALS.length); out.push(0x00, ...DC_BITS, ...DC_VALS);
  out.push(0xff, 0xc4); u16(3 + 16 + AC_VALS.length); out.push(0x10, ...AC_BITS, ...AC_VALS);
  out.push(0xff, 0xda); u16(8); out.push(1, 1, 0x00, 0, 63, 0);

  let acc = 0, nbits = 0;
  const put = (code, length) => {
    for (let i = length - 1; i >= 0; i--) {
      acc = (acc << 1) | ((code >> i) & 1);
      if (++nbits === 8) {
        out.push(acc);
        if (acc === 0xff) out.push(0);
        acc = 0; nbits = 0;
      }
    }
  };
  const category = (v) => { let a = Math.abs(v), n = 0; while (a) { n++; a >>= 1; } return n; };
  const valueBits = (v, size) => (v >= 0 ? v : v + (1 << size) - 1);

  const block = new Float64Array(64), rows = new Float64Array(64), coef = new Int32Array(64);
  let prevDc = 0;
  for (let by = 0; by < height; by += 8) {
    for (let bx = 0; bx < width; bx += 8) {
      for (let y = 0; y < 8; y++) {
        for (let x = 0; x < 8; x++) {
          block[y * 8 + x] = pixels[Math.min(height - 1, by + y) * width + Math.min(width - 1, bx + x)] - 128;
        }
      }
      // Separable DCT: rows, then columns.
      for (let y = 0; y < 8; y++) {
        for (let u = 0; u < 8; u++) {
          let sum = 0;
          for (let x = 0; x < 8; x++) sum += block[y * 8 + x] * COS[x * 8 + u];
          rows[y * 8 + u] = sum;
        }
      }
      for (let u = 0; u < 8; u++) {
        for (let v = 0; v < 8; v++) {
          let sum = 0;
          for (let y = 0; y < 8; y++) sum += rows[y * 8 + u] * COS[y * 8 + v];
          coef[v * 8 + u] = Math.round(sum / 4 / q[v * 8 + u]);
        }
      }
      const dc = coef[0], diff = dc - prevDc;
      prevDc = dc;
      const dcSize = category(diff);
      put(...DC_CODES.get(dcSize));
      if (dcSize) put(valueBits(diff, dcSize), dcSize);
      let run = 0;
      for (let k = 1; k < 64; k++) {
        const v = coef[ZIGZAG[k]];
        if (v === 0) { run++; continue; }
        while (run > 15) { put(...AC_CODES.get(0xf0)); run -= 16; }
        const size = category(v);
        put(...AC_CODES.get((run << 4) | size));
        put(valueBits(v, size), size);
        run = 0;
      }
      if (run > 0) put(...AC_CODES.get(0x00));
    }
  }
  if (nbits > 0) put((1 << (8 - nbits)) - 1, 8 - nbits);
  out.push(0xff, 0xd9);
  return Uint8Array.from(out);
}
