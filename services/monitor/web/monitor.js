// shapesense monitor: the page's state, message handling, WebSocket and
// drawing loop. Plain browser script (no modules, no build step); uses
// plots.js (ShapesensePlots) and view3d.js (ShapesenseView3D).
//
// Message handlers only validate and store; requestAnimationFrame draws
// what changed, so 30 Hz input never piles up and each camera pane keeps
// only its latest frame. A malformed message is counted
// (shapesenseMonitor.errors) and ignored; handlers never throw.
//
// Test hooks: window.shapesenseMonitor (see `api` below). URL fragment:
// `#nows` keeps the page from connecting (a blank reference for tests),
// `#token=...` is the e-stop token (else the page asks for it).
'use strict';

(function () {
  const PROTOCOL_VERSION = 1;
  const RECONNECT_MS = 1000;
  const STALE_S = 2.0;

  // ---------------------------------------------------------------- state
  const fragment = parseFragment(location.hash);
  const api = {
    updates: 0,
    updatesByType: {},
    ignoredByType: {},
    errors: 0,
    lastError: null,
    connected: false,
    connectionState: 'connecting',
    hello: null,
    health: [],
    latest: {},         // the latest validated message of each text type
    cameras: {},        // name → {received, decoded, trigger_seq, fps}
    estopResults: [],
    ready: false,
    handleText,
    handleBinary,
    view3d: () => (view ? view.stats() : { ok: false, failure: 'not started' }),
  };
  window.shapesenseMonitor = api;

  const dirty = { header: true, health: true, controller: true, sensing: true, cameras: true, info: true };
  const panes = new Map(); // camera name → CameraPane
  let view = null;
  let plots = null;
  let socket = null;
  let estopToken = fragment.get('token') || null;
  const receivedAt = {}; // type → performance.now() of the latest
  let lastLatencyFromShape = -Infinity;

  const $ = (id) => document.getElementById(id);
  const nowS = () => performance.now() / 1000;

  function parseFragment(hash) {
    const out = new Map();
    for (const part of hash.replace(/^#/, '').split('&')) {
      if (!part) continue;
      const eq = part.indexOf('=');
      const key = decodeURIComponent(eq < 0 ? part : part.slice(0, eq));
      const value = eq < 0 ? '' : decodeURIComponent(part.slice(eq + 1));
      out.set(key, value);
    }
    return out;
  }

  // ----------------------------------------------------------- validation
  class BadMessage extends Error {}
  const bad = (text) => new BadMessage(text);
  const isNum = (v) => typeof v === 'number' && Number.isFinite(v);

  function num(v, name, optional) {
    if (v === undefined || v === null) {
      if (optional) return null;
      throw bad(name + ' missing');
    }
    if (!isNum(v)) throw bad(name + ' is not a number');
    return v;
  }
  function str(v, name, optional) {
    if (v === undefined || v === null) {
      if (optional) return '';
      throw bad(name + ' missing');
    }
    if (typeof v !== 'string') throw bad(name + ' is not a string');
    return v;
  }
  function vec(v, n, name, optional) {
    if ((v === undefined || v === null) && optional) return null;
    if (!Array.isArray(v) || (n > 0 && v.length !== n) || !v.every(isNum)) {
      throw bad(name + ' is not ' + (n > 0 ? n + ' numbers' : 'a list of numbers'));
    }
    return v;
  }
  function vecs(v, n, name) {
    if (v === undefined || v === null) return [];
    if (!Array.isArray(v)) throw bad(name + ' is not a list');
    for (let i = 0; i < v.length; i++) vec(v[i], n, name + '[' + i + ']');
    return v;
  }
  function strings(v, name) {
    if (v === undefined || v === null) return [];
    if (!Array.isArray(v) || !v.every((s) => typeof s === 'string')) throw bad(name + ' is not a list of strings');
    return v;
  }

  function validateShape(m) {
    const stages = [];
    if (m.stages !== undefined && m.stages !== null) {
      if (!Array.isArray(m.stages)) throw bad('stages is not a list');
      m.stages.forEach((s, i) => {
        if (!s || typeof s !== 'object') throw bad('stages[' + i + '] is not an object');
        stages.push({ stage: str(s.stage, 'stages[' + i + '].stage'), ms: num(s.ms, 'stages[' + i + '].ms', true) });
      });
    }
    const centerline = vecs(m.centerline, 3, 'centerline');
    return {
      type: m.type,
      trigger_seq: num(m.trigger_seq, 'trigger_seq', true),
      trigger_utime: num(m.trigger_utime, 'trigger_utime', true),
      valid: m.valid === undefined ? centerline.length > 0 : m.valid === true,
      error: str(m.error, 'error', true),
      centerline,
      markers: vecs(m.markers, 3, 'markers'),
      tip: vec(m.tip, 3, 'tip', true),
      q: vec(m.q, 0, 'q', true),
      length: num(m.length, 'length', true),
      residual_mm: num(m.residual_mm, 'residual_mm', true),
      stages,
      latency_ms: num(m.latency_ms, 'latency_ms', true),
    };
  }

  function validateHello(m) {
    if (!Array.isArray(m.cameras)) throw bad('cameras is not a list');
    const cameras = m.cameras.map((c, i) => {
      if (!c || typeof c !== 'object') throw bad('cameras[' + i + '] is not an object');
      const frustum = c.frustum === undefined || c.frustum === null ? null : vecs(c.frustum, 3, 'cameras[' + i + '].frustum');
      if (frustum && frustum.length !== 5) throw bad('cameras[' + i + '].frustum has ' + frustum.length + ' points, not 5');
      const width = num(c.width, 'cameras[' + i + '].width');
      const height = num(c.height, 'cameras[' + i + '].height');
      if (width <= 0 || height <= 0) throw bad('cameras[' + i + '] has no size');
      return { name: str(c.name, 'cameras[' + i + '].name'), width, height, frustum };
    });
    return {
      type: 'hello',
      version: num(m.version, 'version', true),
      host: str(m.host, 'host', true),
      rig_prefix: str(m.rig_prefix, 'rig_prefix', true),
      estop_enabled: m.estop_enabled === true,
      started_utime: num(m.started_utime, 'started_utime', true),
      cameras,
    };
  }

  function validateTarget(m) {
    return {
      type: 'target',
      kind: str(m.kind, 'kind', true),
      q: vec(m.q, 0, 'q', true),
      tip: vec(m.tip, 3, 'tip', true),
      centerline: m.centerline === null || m.centerline === undefined ? null : vecs(m.centerline, 3, 'centerline'),
      duration_s: num(m.duration_s, 'duration_s', true),
      source: str(m.source, 'source', true),
      utime: num(m.utime, 'utime', true),
    };
  }

  function validateController(m) {
    return {
      type: 'controller',
      utime: num(m.utime, 'utime', true),
      mode: str(m.mode, 'mode', true),
      gate: str(m.gate, 'gate', true),
      gate_reasons: strings(m.gate_reasons, 'gate_reasons'),
      commanded_mm: vec(m.commanded_mm, 0, 'commanded_mm', true) || [],
      actual_mm: vec(m.actual_mm, 0, 'actual_mm', true) || [],
      tensions_n: vec(m.tensions_n, 0, 'tensions_n', true) || [],
      tip_error_mm: num(m.tip_error_mm, 'tip_error_mm', true),
    };
  }

  function validateHealth(m) {
    if (!Array.isArray(m.rows)) throw bad('rows is not a list');
    const rows = m.rows.map((r, i) => {
      if (!r || typeof r !== 'object') throw bad('rows[' + i + '] is not an object');
      str(r.host, 'rows[' + i + '].host');
      str(r.program, 'rows[' + i + '].program');
      str(r.state, 'rows[' + i + '].state');
      for (const key of ['pid', 'uptime_s', 'status_age_s', 'input_rate_hz', 'output_rate_hz', 'received', 'published',
        'dropped', 'rejected', 'errors', 'queue_depth', 'cpu_percent', 'rss_bytes']) {
        num(r[key], 'rows[' + i + '].' + key, true);
      }
      if (r.clock_offsets_ms !== undefined && r.clock_offsets_ms !== null &&
          (typeof r.clock_offsets_ms !== 'object' || Array.isArray(r.clock_offsets_ms))) {
        throw bad('rows[' + i + '].clock_offsets_ms is not an object');
      }
      return r;
    });
    return { type: 'health', now_utime: num(m.now_utime, 'now_utime', true), rows };
  }

  function validateStats(m) {
    const latency = {};
    if (m.latency_ms !== undefined && m.latency_ms !== null) {
      if (typeof m.latency_ms !== 'object' || Array.isArray(m.latency_ms)) throw bad('latency_ms is not an object');
      for (const [k, v] of Object.entries(m.latency_ms)) latency[k] = num(v, 'latency_ms.' + k, true);
    }
    return {
      type: 'stats',
      utime: num(m.utime, 'utime', true),
      frame_set_rate_hz: num(m.frame_set_rate_hz, 'frame_set_rate_hz', true),
      shape_rate_hz: num(m.shape_rate_hz, 'shape_rate_hz', true),
      lost_sets: num(m.lost_sets, 'lost_sets', true),
      invalid_shapes: num(m.invalid_shapes, 'invalid_shapes', true),
      latency_ms: latency,
      p99_latency_ms: num(m.p99_latency_ms, 'p99_latency_ms', true),
    };
  }

  function validateCamera(m) {
    const runs = (v, name) => vecs(v, 3, name);
    let silhouette = null;
    if (m.silhouette !== undefined && m.silhouette !== null) {
      if (typeof m.silhouette !== 'object') throw bad('silhouette is not an object');
      silhouette = { mask: runs(m.silhouette.mask, 'silhouette.mask'), tape: runs(m.silhouette.tape, 'silhouette.tape') };
    }
    const width = num(m.width, 'width');
    const height = num(m.height, 'height');
    if (width <= 0 || height <= 0) throw bad('camera frame has no size');
    return {
      camera: str(m.camera, 'camera'),
      trigger_seq: num(m.trigger_seq, 'trigger_seq', true),
      width,
      height,
      silhouette,
      centerline: m.centerline === null || m.centerline === undefined ? null : vecs(m.centerline, 2, 'centerline'),
      markers: vecs(m.markers, 2, 'markers'),
      tip: vec(m.tip, 2, 'tip', true),
    };
  }

  // ------------------------------------------------------------- handlers
  function noteError(error) {
    api.errors++;
    api.lastError = error && error.message ? error.message : String(error);
    dirty.header = true;
  }

  function counted(type) {
    api.updates++;
    api.updatesByType[type] = (api.updatesByType[type] || 0) + 1;
    receivedAt[type] = performance.now();
    dirty.header = true;
  }

  const textHandlers = {
    hello(m) {
      const hello = validateHello(m);
      api.hello = hello;
      api.latest.hello = hello;
      setupCameras(hello.cameras);
      if (view) view.setCameras(hello.cameras);
      dirty.header = true;
    },
    shape(m) {
      const shape = validateShape(m);
      api.latest.shape = shape;
      if (view) view.setShape(shape);
      if (plots) {
        const t = nowS();
        if (shape.stages.length) {
          lastLatencyFromShape = t;
          for (const s of shape.stages) plots.latency.push(s.stage, t, s.ms);
        }
        if (shape.latency_ms !== null) plots.latency.push('total', t, shape.latency_ms, TOTAL_STYLE);
      }
      dirty.sensing = dirty.info = true;
    },
    truth(m) {
      const truth = validateShape(m);
      api.latest.truth = truth;
      if (view) view.setTruth(truth);
      dirty.info = true;
    },
    voxels(m) {
      const points = m.points;
      if (!Array.isArray(points) || points.length % 3 !== 0 || !points.every(Number.isFinite) ||
          !(Number.isFinite(m.voxel_size) && m.voxel_size > 0)) {
        throw bad('voxels: points must be finite x, y, z triples and voxel_size positive');
      }
      api.latest.voxels = { trigger_seq: m.trigger_seq, count: points.length / 3 };
      if (view) view.setVoxels({ points, voxel_size: m.voxel_size });
    },
    target(m) {
      const target = validateTarget(m);
      api.latest.target = target;
      if (view) view.setTarget(target);
      dirty.controller = true;
    },
    controller(m) {
      const c = validateController(m);
      api.latest.controller = c;
      if (plots) {
        const t = nowS();
        plots.tipError.push('tip error', t, c.tip_error_mm, { color: '#ff40ff' });
        const n = Math.max(c.commanded_mm.length, c.actual_mm.length);
        for (let i = 0; i < n; i++) {
          const color = plots.PALETTE[i % plots.PALETTE.length];
          plots.tendons.push('cmd' + i, t, i < c.commanded_mm.length ? c.commanded_mm[i] : null,
            { label: 'T' + (i + 1) + ' cmd', color });
          plots.tendons.push('act' + i, t, i < c.actual_mm.length ? c.actual_mm[i] : null,
            { label: 'T' + (i + 1) + ' act', color, dash: [4, 3] });
        }
        if (n && (!plots.tendons.extraLegend || plots.tendons.extraLegend.length !== n)) {
          plots.tendons.extraLegend = [];
          for (let i = 0; i < n; i++) {
            plots.tendons.extraLegend.push({ label: 'T' + (i + 1), color: plots.PALETTE[i % plots.PALETTE.length] });
          }
        }
      }
      dirty.controller = true;
    },
    health(m) {
      const h = validateHealth(m);
      api.latest.health = h;
      api.health = h.rows;
      dirty.health = true;
    },
    stats(m) {
      const s = validateStats(m);
      api.latest.stats = s;
      if (plots) {
        const t = nowS();
        plots.rates.push('frame sets/s', t, s.frame_set_rate_hz, { color: '#4fc3f7' });
        plots.rates.push('shapes/s', t, s.shape_rate_hz, { color: '#81c784', dash: [5, 3] });
        plots.lost.push('lost sets', t, s.lost_sets, { color: '#ffb74d' });
        plots.lost.push('invalid shapes', t, s.invalid_shapes, { color: '#e57373' });
        if (t - lastLatencyFromShape > 5) { // no per-shape stages: the server's averages
          for (const [k, v] of Object.entries(s.latency_ms)) {
            plots.latency.push(k, t, v, k === 'total' ? TOTAL_STYLE : undefined);
          }
        }
        if (s.p99_latency_ms !== null) plots.latency.push('p99', t, s.p99_latency_ms, { color: '#ffffff', dash: [2, 3], width: 1 });
      }
      dirty.sensing = true;
    },
    estop_result(m) {
      const result = { ok: m.ok === true, message: str(m.message, 'message', true), at: new Date() };
      if (!result.ok) estopToken = fragment.get('token') || null; // a typed token that failed is asked again
      api.estopResults.push(result);
      showEstopResult(result);
    },
  };
  const TOTAL_STYLE = { color: '#e6edf3', width: 2 };

  function handleText(text) {
    try {
      const m = typeof text === 'string' ? JSON.parse(text) : text;
      if (!m || typeof m !== 'object' || Array.isArray(m)) throw bad('not a JSON object');
      if (typeof m.type !== 'string') throw bad('no "type"');
      const handler = Object.prototype.hasOwnProperty.call(textHandlers, m.type) ? textHandlers[m.type] : null;
      if (!handler) { // a newer server's message: not an error, not applied
        api.ignoredByType[m.type] = (api.ignoredByType[m.type] || 0) + 1;
        return false;
      }
      handler(m);
      counted(m.type);
      return true;
    } catch (e) {
      noteError(e);
      return false;
    }
  }

  function handleBinary(data) {
    try {
      let bytes;
      if (data instanceof ArrayBuffer) bytes = new Uint8Array(data);
      else if (ArrayBuffer.isView(data)) bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
      else throw bad('binary message is not an ArrayBuffer');
      if (bytes.length < 4) throw bad('binary message shorter than its header');
      const n = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength).getUint32(0, true);
      if (n > bytes.length - 4) throw bad('binary message: JSON length ' + n + ' past its end (' + bytes.length + ' bytes)');
      const m = JSON.parse(new TextDecoder('utf-8', { fatal: true }).decode(bytes.subarray(4, 4 + n)));
      if (!m || typeof m !== 'object' || m.type !== 'camera') throw bad('binary message is not a camera frame');
      const frame = validateCamera(m);
      const jpeg = bytes.slice(4 + n); // a copy: the pane keeps only this frame's bytes
      let pane = panes.get(frame.camera);
      if (!pane) pane = addPane({ name: frame.camera, width: frame.width, height: frame.height });
      pane.offer(frame, jpeg);
      counted('camera');
      return true;
    } catch (e) {
      noteError(e);
      return false;
    }
  }

  // --------------------------------------------------------- camera panes
  const layers = { silhouette: true, centerline: true, markers: true, tip: true };

  class CameraPane {
    constructor(camera) {
      this.name = camera.name;
      this.width = camera.width;
      this.height = camera.height;
      this.frame = null;      // the meta of the frame on screen
      this.bitmap = null;
      this.pending = null;    // the latest frame not yet decoded
      this.decoding = false;
      this.decodedTimes = [];
      this.dirty = true;
      this.stats = api.cameras[this.name] = { received: 0, decoded: 0, decodeErrors: 0, trigger_seq: null, fps: 0 };

      const root = (this.root = document.createElement('div'));
      root.className = 'cam';
      const caption = document.createElement('div');
      caption.className = 'cam-caption';
      const name = document.createElement('span');
      name.className = 'cam-name';
      name.textContent = camera.name;
      this.seqEl = document.createElement('span');
      this.sizeEl = document.createElement('span');
      this.fpsEl = document.createElement('span');
      this.fpsEl.className = 'cam-fps';
      caption.append(name, this.seqEl, this.sizeEl, this.fpsEl);
      const body = document.createElement('div');
      body.className = 'cam-body';
      body.style.aspectRatio = camera.width + ' / ' + camera.height;
      const canvas = (this.canvas = document.createElement('canvas'));
      canvas.className = 'camera-canvas';
      canvas.dataset.camera = camera.name;
      body.appendChild(canvas);
      root.append(caption, body);
      this.ctx = canvas.getContext('2d');
      this.updateCaption();
    }

    offer(frame, jpeg) {
      this.stats.received++;
      this.pending = { frame, jpeg };
      if (!this.decoding) this.decodeNext();
    }

    decodeNext() {
      const next = this.pending;
      this.pending = null;
      if (!next) return;
      if (next.jpeg.length === 0) { // overlays without a picture
        this.show(next.frame, null);
        return;
      }
      this.decoding = true;
      createImageBitmap(new Blob([next.jpeg], { type: 'image/jpeg' }))
        .then((bitmap) => this.show(next.frame, bitmap))
        .catch((e) => {
          this.stats.decodeErrors++;
          noteError(new Error(this.name + ': cannot decode the JPEG (' + (e && e.message ? e.message : e) + ')'));
        })
        .finally(() => {
          this.decoding = false;
          if (this.pending) this.decodeNext();
        });
    }

    show(frame, bitmap) {
      if (this.bitmap && this.bitmap.close) this.bitmap.close();
      this.bitmap = bitmap;
      this.frame = frame;
      this.width = frame.width;
      this.height = frame.height;
      const t = performance.now();
      this.decodedTimes.push(t);
      while (this.decodedTimes.length && this.decodedTimes[0] < t - 3000) this.decodedTimes.shift();
      this.stats.decoded++;
      this.stats.trigger_seq = frame.trigger_seq;
      this.lastShown = t;
      this.dirty = true;
    }

    fps() {
      const times = this.decodedTimes;
      const t = performance.now();
      while (times.length && times[0] < t - 3000) times.shift();
      if (times.length < 2) return 0;
      return (times.length - 1) / ((times[times.length - 1] - times[0]) / 1000);
    }

    updateCaption() {
      const f = this.frame;
      setText(this.seqEl, f && f.trigger_seq !== null ? 'seq ' + f.trigger_seq : 'no frame yet');
      setText(this.sizeEl, this.width + '×' + this.height);
      const age = this.lastShown ? (performance.now() - this.lastShown) / 1000 : null;
      const fps = this.fps();
      this.stats.fps = fps;
      const stale = age !== null && age > STALE_S;
      setText(this.fpsEl, stale ? 'no frame for ' + age.toFixed(0) + ' s' : fps.toFixed(1) + ' fps');
      this.fpsEl.className = stale ? 'cam-fps stale' : 'cam-fps';
    }

    draw() {
      const canvas = this.canvas;
      const dpr = window.devicePixelRatio || 1;
      const cw = Math.max(1, Math.round(canvas.clientWidth * dpr));
      const ch = Math.max(1, Math.round(canvas.clientHeight * dpr));
      if (canvas.width !== cw || canvas.height !== ch) {
        canvas.width = cw;
        canvas.height = ch;
      }
      if (this.captionSeq !== (this.frame && this.frame.trigger_seq)) { // a new frame: its seq at once
        this.captionSeq = this.frame && this.frame.trigger_seq;
        this.updateCaption();
      }
      const ctx = this.ctx;
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.fillStyle = '#000';
      ctx.fillRect(0, 0, cw, ch);
      this.dirty = false;
      const f = this.frame;
      if (!f) {
        ctx.fillStyle = '#5a6472';
        ctx.font = Math.round(12 * dpr) + 'px system-ui, sans-serif';
        ctx.textAlign = 'center';
        ctx.textBaseline = 'middle';
        ctx.fillText('no frame yet', cw / 2, ch / 2);
        ctx.textAlign = 'left';
        return;
      }
      // Full-resolution pixels → canvas pixels, letterboxed.
      const s = Math.min(cw / f.width, ch / f.height);
      const ox = (cw - f.width * s) / 2, oy = (ch - f.height * s) / 2;
      ctx.setTransform(s, 0, 0, s, ox, oy);
      if (this.bitmap) {
        ctx.imageSmoothingEnabled = true;
        ctx.drawImage(this.bitmap, 0, 0, f.width, f.height);
      } else {
        ctx.fillStyle = '#111';
        ctx.fillRect(0, 0, f.width, f.height);
      }
      const px = dpr / s; // one CSS pixel in full-resolution pixels
      if (layers.silhouette && f.silhouette) {
        const runs = (list, color) => {
          if (!list.length) return;
          ctx.fillStyle = color;
          ctx.beginPath();
          for (const [row, begin, end] of list) if (end > begin) ctx.rect(begin, row, end - begin, 1);
          ctx.fill();
        };
        runs(f.silhouette.mask, 'rgba(0, 230, 64, 0.35)');
        runs(f.silhouette.tape, 'rgba(255, 40, 40, 0.6)');
      }
      if (layers.centerline && f.centerline && f.centerline.length >= 2) {
        ctx.strokeStyle = '#ffeb3b';
        ctx.lineWidth = 2 * px;
        ctx.lineJoin = 'round';
        ctx.beginPath();
        f.centerline.forEach(([u, v], i) => (i ? ctx.lineTo(u + 0.5, v + 0.5) : ctx.moveTo(u + 0.5, v + 0.5)));
        ctx.stroke();
      }
      if (layers.markers && f.markers.length) {
        ctx.strokeStyle = '#00e5ff';
        ctx.lineWidth = 2 * px;
        for (const [u, v] of f.markers) {
          ctx.beginPath();
          ctx.arc(u + 0.5, v + 0.5, 5 * px, 0, 2 * Math.PI);
          ctx.stroke();
        }
      }
      if (layers.tip && f.tip) {
        const [u, v] = f.tip;
        const r = 7 * px;
        ctx.strokeStyle = '#ff40ff';
        ctx.lineWidth = 2.5 * px;
        ctx.beginPath();
        ctx.moveTo(u + 0.5 - r, v + 0.5 - r); ctx.lineTo(u + 0.5 + r, v + 0.5 + r);
        ctx.moveTo(u + 0.5 + r, v + 0.5 - r); ctx.lineTo(u + 0.5 - r, v + 0.5 + r);
        ctx.stroke();
      }
      ctx.setTransform(1, 0, 0, 1, 0, 0);
    }

    destroy() {
      if (this.bitmap && this.bitmap.close) this.bitmap.close();
      this.root.remove();
    }
  }

  const resizeObserver = typeof ResizeObserver !== 'undefined'
    ? new ResizeObserver(() => { for (const p of panes.values()) p.dirty = true; if (view) view.dirty = true; })
    : null;

  function addPane(camera) {
    const container = $('cameras');
    const placeholder = container.querySelector('.placeholder');
    if (placeholder) placeholder.remove();
    const pane = new CameraPane(camera);
    panes.set(camera.name, pane);
    container.appendChild(pane.root);
    container.style.setProperty('--camera-count', String(Math.max(1, panes.size)));
    if (resizeObserver) resizeObserver.observe(pane.canvas);
    return pane;
  }

  function setupCameras(cameras) {
    const wanted = new Set(cameras.map((c) => c.name));
    for (const [name, pane] of panes) {
      if (!wanted.has(name)) {
        pane.destroy();
        panes.delete(name);
        delete api.cameras[name];
      }
    }
    for (const c of cameras) {
      const pane = panes.get(c.name);
      if (!pane) addPane(c);
    }
    // Keep hello's order.
    const container = $('cameras');
    for (const c of cameras) container.appendChild(panes.get(c.name).root);
    container.style.setProperty('--camera-count', String(Math.max(1, panes.size)));
    if (!cameras.length && !container.querySelector('.placeholder')) {
      const p = document.createElement('div');
      p.className = 'placeholder';
      p.textContent = 'the server reports no cameras';
      container.appendChild(p);
    }
  }

  // ------------------------------------------------------------ formatting
  function fmt(v, digits) {
    return v === null || v === undefined || !Number.isFinite(v) ? '–' : v.toFixed(digits);
  }
  function fmtInt(v) {
    return v === null || v === undefined || !Number.isFinite(v) ? '–' : String(Math.round(v));
  }
  function fmtDuration(s) {
    if (s === null || s === undefined || !Number.isFinite(s)) return '–';
    if (s < 60) return s.toFixed(0) + ' s';
    if (s < 3600) return Math.floor(s / 60) + 'm' + String(Math.floor(s % 60)).padStart(2, '0') + 's';
    if (s < 86400) return Math.floor(s / 3600) + 'h' + String(Math.floor((s % 3600) / 60)).padStart(2, '0') + 'm';
    return Math.floor(s / 86400) + 'd' + String(Math.floor((s % 86400) / 3600)).padStart(2, '0') + 'h';
  }
  function fmtVec(v, digits) {
    return v ? '[' + v.map((x) => fmt(x, digits)).join(', ') + ']' : '–';
  }
  function fmtQ(q) {
    return q ? '[' + q.map((x) => (Math.abs(x) < 0.01 && x !== 0 ? x.toExponential(2) : x.toFixed(3))).join(', ') + ']' : '–';
  }
  function fmtAge(type) {
    if (receivedAt[type] === undefined) return '';
    const age = (performance.now() - receivedAt[type]) / 1000;
    return age < 1 ? '' : age.toFixed(0) + ' s ago';
  }
  function setText(el, text) {
    if (el.textContent !== text) el.textContent = text;
  }
  function setBadge(el, text, kind) {
    setText(el, text);
    const cls = 'badge' + (kind ? ' ' + kind : '');
    if (el.className !== cls) el.className = cls;
  }

  // ------------------------------------------------------------- rendering
  function renderHeader() {
    setText($('update-count'), String(api.updates));
    const hello = api.hello;
    setText($('host'), hello && hello.host ? hello.host : '–');
    const prefix = $('rig-prefix');
    prefix.hidden = !(hello && hello.rig_prefix);
    if (hello && hello.rig_prefix) prefix.textContent = 'rig prefix ' + hello.rig_prefix;
    $('estop').hidden = !(hello && hello.estop_enabled);
    const started = $('server-started');
    started.textContent = hello && hello.started_utime ? 'server started ' + new Date(hello.started_utime / 1000).toLocaleString() : '';
    const warn = $('version-warning');
    warn.hidden = !(hello && hello.version !== null && hello.version !== PROTOCOL_VERSION);
    if (!warn.hidden) warn.textContent = 'server protocol v' + hello.version + ', page knows v' + PROTOCOL_VERSION;
    const errors = $('msg-errors');
    errors.hidden = api.errors === 0;
    if (api.errors) {
      errors.textContent = api.errors + ' bad message' + (api.errors === 1 ? '' : 's');
      errors.title = 'last: ' + api.lastError;
    }
  }

  function renderConnection() {
    const el = $('conn');
    const state = api.connectionState;
    el.dataset.state = state;
    el.className = 'conn conn-' + (state === 'connected' ? 'connected' : state === 'offline' ? 'offline' : 'reconnecting');
    el.textContent = state === 'offline' ? 'offline (#nows)' : state;
  }

  const rateSamples = [];
  function updateRate() {
    const t = performance.now();
    rateSamples.push([t, api.updates]);
    while (rateSamples.length > 2 && rateSamples[0][0] < t - 2000) rateSamples.shift();
    const [t0, u0] = rateSamples[0];
    const rate = t > t0 ? ((api.updates - u0) * 1000) / (t - t0) : 0;
    api.updatesPerSecond = rate;
    setText($('update-rate'), rate.toFixed(1));
  }

  const HEALTH_COLUMNS = [
    ['host', (r) => r.host],
    ['program', (r) => r.program],
    ['state', (r) => r.state],
    ['pid', (r) => fmtInt(r.pid), 'num'],
    ['uptime', (r) => fmtDuration(r.uptime_s), 'num'],
    ['in', (r) => fmt(r.input_rate_hz, 1), 'num'],
    ['out', (r) => fmt(r.output_rate_hz, 1), 'num'],
    ['dropped', (r) => fmtInt(r.dropped), 'num', 'count'],
    ['rejected', (r) => fmtInt(r.rejected), 'num', 'count'],
    ['errors', (r) => fmtInt(r.errors), 'num', 'count'],
    ['queue', (r) => fmtInt(r.queue_depth), 'num'],
    ['cpu', (r) => fmt(r.cpu_percent, 1), 'num'],
    ['rss', (r) => (isNum(r.rss_bytes) ? (r.rss_bytes / 1048576).toFixed(1) : '–'), 'num'],
    ['clock', (r) => clockCell(r).text, 'num'],
    ['auth', (r) => (typeof r.auth === 'string' && r.auth ? r.auth : '–')],
    ['last_error', (r) => (typeof r.last_error === 'string' ? r.last_error : '')],
  ];

  function clockCell(r) {
    const offsets = r.clock_offsets_ms && typeof r.clock_offsets_ms === 'object' ? r.clock_offsets_ms : {};
    let worst = null, worstHost = '';
    for (const [host, v] of Object.entries(offsets)) {
      if (isNum(v) && (worst === null || Math.abs(v) > Math.abs(worst))) { worst = v; worstHost = host; }
    }
    const all = Object.entries(offsets).map(([h, v]) => h + ': ' + (isNum(v) ? v.toFixed(3) : v) + ' ms').join('\n');
    return { text: worst === null ? '–' : (worst >= 0 ? '+' : '') + worst.toFixed(2), host: worstHost, title: all };
  }

  function renderHealth() {
    const body = $('health-body');
    const rows = api.health;
    const frag = document.createDocumentFragment();
    const counts = {};
    for (const r of rows) {
      counts[r.state] = (counts[r.state] || 0) + 1;
      const tr = document.createElement('tr');
      tr.setAttribute('data-testid', 'health-row');
      tr.dataset.program = r.program;
      tr.dataset.host = r.host;
      tr.dataset.state = r.state;
      tr.className = 'state-' + r.state.replace(/[^a-z_-]/gi, '');
      for (const [key, get, cls, kind] of HEALTH_COLUMNS) {
        const td = document.createElement('td');
        td.textContent = get(r);
        if (cls) td.className = cls;
        if (key === 'state') {
          td.className = 'state ' + r.state;
          if (isNum(r.status_age_s)) td.title = 'last status ' + r.status_age_s.toFixed(1) + ' s ago';
        } else if (kind === 'count') {
          const v = key === 'errors' ? r.errors : r[key];
          if (isNum(v) && v > 0) td.className += key === 'errors' ? ' bad' : ' nonzero';
        } else if (key === 'clock') {
          const c = clockCell(r);
          td.title = (r.clock_warning ? r.clock_warning + '\n' : '') + c.title;
          if (r.clock_warning) td.className += ' warn';
        } else if (key === 'last_error') {
          td.className = 'err';
          td.title = td.textContent;
        } else if (key === 'host' && r.clock_warning) {
          td.title = r.clock_warning;
        }
        tr.appendChild(td);
      }
      frag.appendChild(tr);
    }
    body.replaceChildren(frag);
    renderHealthSummary(counts);
  }

  function renderHealthSummary(counts) {
    const rows = api.health;
    if (!api.latest.health) return;
    counts = counts || rows.reduce((c, r) => ((c[r.state] = (c[r.state] || 0) + 1), c), {});
    const parts = [rows.length + ' program' + (rows.length === 1 ? '' : 's')];
    for (const state of ['up', 'stale', 'missing', 'unexpected']) if (counts[state]) parts.push(counts[state] + ' ' + state);
    const age = fmtAge('health');
    setText($('health-summary'), parts.join(' · ') + (age ? ' · updated ' + age : ''));
  }

  const MODE_KIND = { closed_loop: 'ok', open_loop: 'info', model_less: 'info', hold: 'warn', stop: 'bad' };
  const GATE_KIND = { ok: 'ok', held: 'warn', stale: 'warn', estop: 'bad', stopped: '' };

  function renderController() {
    const c = api.latest.controller;
    if (c) {
      setBadge($('ctl-mode'), c.mode || '–', MODE_KIND[c.mode] || '');
      setBadge($('ctl-gate'), 'gate ' + (c.gate || '–'), GATE_KIND[c.gate] === undefined ? 'warn' : GATE_KIND[c.gate]);
      setText($('ctl-reasons'), c.gate_reasons.length ? c.gate_reasons.join(', ') : 'none');
      setText($('ctl-tip-error'), c.tip_error_mm === null ? '–' : c.tip_error_mm.toFixed(2) + ' mm');
      setText($('ctl-commanded'), c.commanded_mm.length ? c.commanded_mm.map((v) => v.toFixed(2)).join('  ') : '–');
      setText($('ctl-actual'), c.actual_mm.length ? c.actual_mm.map((v) => v.toFixed(2)).join('  ') : '–');
      setText($('ctl-tensions'), c.tensions_n.length ? c.tensions_n.map((v) => v.toFixed(2)).join('  ') : '–');
    }
    const t = api.latest.target;
    if (t) {
      const parts = [t.kind || 'target'];
      if (t.kind === 'tip' && t.tip) parts.push('tip ' + fmtVec(t.tip, 1) + ' mm');
      else if (t.q) parts.push('q ' + fmtQ(t.q));
      if (t.kind !== 'tip' && t.tip) parts.push('tip ' + fmtVec(t.tip, 1));
      if (t.duration_s !== null) parts.push(t.duration_s.toFixed(1) + ' s');
      if (t.source) parts.push(t.source);
      setText($('ctl-target'), parts.join(' · '));
      $('ctl-target').title = parts.join(' · ');
    }
  }

  function renderSensing() {
    const s = api.latest.shape;
    if (s) {
      const age = (performance.now() - receivedAt.shape) / 1000;
      if (age > STALE_S) setBadge($('shape-state'), 'no shape for ' + age.toFixed(0) + ' s', 'warn');
      else setBadge($('shape-state'), s.valid ? 'valid' : 'invalid', s.valid ? 'ok' : 'bad');
      const parts = [];
      if (s.trigger_seq !== null) parts.push('seq ' + s.trigger_seq);
      if (!s.valid && s.error) parts.push(s.error);
      if (s.length !== null) parts.push('length ' + s.length.toFixed(1) + ' mm');
      if (s.residual_mm !== null) parts.push('residual ' + s.residual_mm.toFixed(2) + ' mm');
      if (s.tip) parts.push('tip ' + fmtVec(s.tip, 1));
      setText($('shape-summary'), parts.join(' · ') || '–');
      $('shape-summary').title = parts.join(' · ');
    }
    const st = api.latest.stats;
    if (st) {
      $('stats-rates').textContent = 'sets ' + fmt(st.frame_set_rate_hz, 1) + '/s · shapes ' + fmt(st.shape_rate_hz, 1) +
        '/s · lost ' + fmtInt(st.lost_sets) + ' · invalid ' + fmtInt(st.invalid_shapes);
      const lat = Object.entries(st.latency_ms).map(([k, v]) => k + ' ' + fmt(v, 1)).join(' · ');
      setText($('stats-latency'), (lat ? lat + ' ms' : '–') + (st.p99_latency_ms !== null ? ' · p99 ' + st.p99_latency_ms.toFixed(1) + ' ms' : ''));
      $('stats-latency').title = $('stats-latency').textContent;
    }
  }

  function renderInfo() {
    const info = $('view3d-info');
    const s = api.latest.shape;
    info.replaceChildren();
    if (!s) {
      info.textContent = api.hello ? 'waiting for the first shape…' : '';
      return;
    }
    const line = (text, cls) => {
      const div = document.createElement('div');
      div.textContent = text;
      if (cls) div.className = cls;
      info.appendChild(div);
    };
    const parts = [];
    if (s.trigger_seq !== null) parts.push('seq ' + s.trigger_seq);
    if (s.residual_mm !== null) parts.push('residual ' + s.residual_mm.toFixed(2) + ' mm');
    if (s.latency_ms !== null) parts.push('latency ' + s.latency_ms.toFixed(1) + ' ms');
    line(parts.join('   '));
    const tr = api.latest.truth;
    if (tr && tr.tip && s.tip && tr.trigger_seq !== null && tr.trigger_seq === s.trigger_seq) {
      const d = Math.hypot(tr.tip[0] - s.tip[0], tr.tip[1] - s.tip[1], tr.tip[2] - s.tip[2]);
      line('tip vs truth ' + d.toFixed(2) + ' mm');
    }
    if (!s.valid) line('invalid shape' + (s.error ? ': ' + s.error : ''), 'bad');
    const age = (performance.now() - receivedAt.shape) / 1000;
    if (age > STALE_S) line('no shape for ' + age.toFixed(0) + ' s', 'warn');
  }

  function showEstopResult(result) {
    const el = $('estop-result');
    el.hidden = false;
    el.className = 'estop-result ' + (result.ok ? 'ok' : 'fail');
    el.textContent = (result.ok ? 'e-stop accepted' : 'e-stop refused') + (result.message ? ': ' + result.message : '') +
      ' (' + result.at.toLocaleTimeString() + ')';
    el.title = el.textContent;
  }

  // ------------------------------------------------------------- the loop
  let lastPlotDraw = 0;
  let lastSlow = 0;
  let lastText = 0;
  function frame() {
    requestAnimationFrame(frame);
    const t = performance.now();
    try {
      // Text at most 10 times a second (messages come at 30 Hz and more);
      // health as it comes (2 Hz), so a program going missing shows at once.
      const textDue = t - lastText >= 100;
      if (textDue) lastText = t;
      if (dirty.header && textDue) { renderHeader(); dirty.header = false; }
      for (const pane of panes.values()) if (pane.dirty) pane.draw();
      if (dirty.health) { renderHealth(); dirty.health = false; }
      if (dirty.controller && textDue) { renderController(); dirty.controller = false; }
      if (dirty.sensing && textDue) { renderSensing(); dirty.sensing = false; }
      if (dirty.info && textDue) { renderInfo(); dirty.info = false; }
      if (view) view.frame();
      if (plots) {
        // The time axis rolls, so plots redraw a few times a second even without data.
        // Without a GPU (software WebGL: the CPU the pipeline needs) 4 a second at most.
        const least = view && view.software ? 250 : 100;
        const due = t - lastPlotDraw > 250;
        const changed = plots.all.some((p) => p.dirty);
        if (due || (changed && t - lastPlotDraw > least)) {
          const now = nowS();
          for (const p of plots.all) p.draw(now);
          lastPlotDraw = t;
        }
      }
      if (t - lastSlow > 500) { // ages, fps and rates
        lastSlow = t;
        updateRate();
        for (const pane of panes.values()) pane.updateCaption();
        renderHealthSummary();
        if (api.latest.shape) { renderSensing(); renderInfo(); }
      }
    } catch (e) {
      api.renderErrors = (api.renderErrors || 0) + 1;
      api.lastRenderError = e && e.message ? e.message : String(e);
      if (api.renderErrors < 5) console.error('monitor: drawing failed', e);
    }
  }

  // ------------------------------------------------------------ WebSocket
  function setConnection(state) {
    api.connectionState = state;
    api.connected = state === 'connected';
    renderConnection();
  }

  function connect() {
    let ws;
    try {
      const url = new URL('ws', location.href);
      url.protocol = location.protocol === 'https:' ? 'wss:' : 'ws:';
      url.hash = '';
      url.search = '';
      ws = new WebSocket(url.href);
    } catch (e) {
      setConnection('reconnecting');
      setTimeout(connect, RECONNECT_MS);
      return;
    }
    socket = ws;
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => setConnection('connected');
    ws.onmessage = (event) => {
      if (typeof event.data === 'string') handleText(event.data);
      else handleBinary(event.data);
    };
    ws.onerror = () => {}; // onclose follows
    ws.onclose = () => {
      if (socket === ws) socket = null;
      setConnection('reconnecting');
      setTimeout(connect, RECONNECT_MS);
    };
  }

  function pressEstop() {
    let token = estopToken;
    if (!token) {
      token = window.prompt('E-stop token (or open the page as …#token=TOKEN):', '');
      if (token === null) {
        showEstopResult({ ok: false, message: 'cancelled, nothing sent', at: new Date() });
        return;
      }
      estopToken = token;
    }
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      showEstopResult({ ok: false, message: 'not connected to the monitor, nothing sent', at: new Date() });
      return;
    }
    socket.send(JSON.stringify({ type: 'estop', token }));
    const el = $('estop-result');
    el.hidden = false;
    el.className = 'estop-result';
    el.textContent = 'e-stop sent…';
  }

  // ---------------------------------------------------------------- start
  function start() {
    const { TimePlot, PALETTE } = window.ShapesensePlots;
    plots = {
      PALETTE,
      latency: new TimePlot($('plot-latency'), { title: 'Latency per stage', unit: 'ms' }),
      rates: new TimePlot($('plot-rates'), { title: 'Rates', unit: 'Hz' }),
      lost: new TimePlot($('plot-lost'), { title: 'Lost sets, invalid shapes', unit: 'count', minRange: 5 }),
      tipError: new TimePlot($('plot-tip-error'), { title: 'Closed loop: tip error', unit: 'mm' }),
      tendons: new TimePlot($('plot-tendons'), { title: 'Tendons', unit: 'mm', note: 'solid commanded · dashed actual', includeZero: false }),
    };
    plots.all = [plots.latency, plots.rates, plots.lost, plots.tipError, plots.tendons];
    api.plots = plots;
    api.view3dObject = null; // set below, for debugging from the console

    try {
      view = new window.ShapesenseView3D($('view3d'), $('view3d-message'));
    } catch (e) {
      view = null;
      setText($('view3d-message'), '3-D view unavailable: ' + (e && e.message ? e.message : e));
      $('view3d-message').hidden = false;
    }
    api.view3dObject = view;
    if (resizeObserver) resizeObserver.observe($('view3d'));

    for (const name of Object.keys(layers)) {
      const box = $('layer-' + name);
      layers[name] = box.checked;
      box.addEventListener('change', () => {
        layers[name] = box.checked;
        for (const p of panes.values()) p.dirty = true;
      });
    }
    for (const name of ['target', 'truth', 'markers', 'frusta', 'voxels']) {
      const box = $('layer3d-' + name);
      if (view) view.setLayer(name, box.checked);
      box.addEventListener('change', () => view && view.setLayer(name, box.checked));
    }
    $('fit-shape').addEventListener('click', () => view && view.fit(false, false));
    $('fit-all').addEventListener('click', () => view && view.fit(true, false));
    $('estop').addEventListener('click', pressEstop);

    requestAnimationFrame(frame);
    if (fragment.has('nows')) setConnection('offline');
    else { setConnection('connecting'); connect(); }
    api.ready = true;
  }

  // This script is the last element of <body>: the DOM it needs is there.
  start();
})();
