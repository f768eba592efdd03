// Small rolling time plots on a 2-D canvas (no library): the last `windowS`
// seconds of a few series against the page's clock. A value of null breaks
// the line, as does a pause longer than `gapS`. Drawn only when asked
// (monitor.js's animation frame), never from a message handler.
'use strict';

(function () {
  const PALETTE = ['#4fc3f7', '#ffb74d', '#81c784', '#e57373', '#ba68c8', '#fff176', '#4dd0e1', '#f06292', '#a1887f', '#90a4ae'];

  function niceStep(range, count) {
    const raw = range / Math.max(1, count);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const norm = raw / mag;
    const step = norm <= 1 ? 1 : norm <= 2 ? 2 : norm <= 2.5 ? 2.5 : norm <= 5 ? 5 : 10;
    return step * mag;
  }

  function formatTick(v, step) {
    if (Math.abs(v) < step * 1e-6) return '0';
    const digits = step >= 1 ? 0 : Math.min(4, Math.ceil(-Math.log10(step)));
    const a = Math.abs(v);
    if (a >= 10000) return (v / 1000).toFixed(0) + 'k';
    return v.toFixed(digits);
  }

  function formatValue(v) {
    if (v === null || v === undefined || !Number.isFinite(v)) return '–';
    const a = Math.abs(v);
    if (a >= 1000) return v.toFixed(0);
    if (a >= 100) return v.toFixed(1);
    if (a >= 1) return v.toFixed(2);
    return v.toPrecision(2);
  }

  class Series {
    constructor(key, options) {
      this.key = key;
      this.label = options.label || key;
      this.color = options.color;
      this.dash = options.dash || null;
      this.width = options.width || 1.5;
      this.legend = options.legend !== false;
      this.t = [];
      this.v = [];
      this.start = 0; // index of the first live point; compacted now and then
    }
    push(t, v) {
      this.t.push(t);
      this.v.push(Number.isFinite(v) ? v : null);
    }
    trim(oldest) {
      while (this.start < this.t.length && this.t[this.start] < oldest) this.start++;
      if (this.start > 512 && this.start * 2 > this.t.length) {
        this.t = this.t.slice(this.start);
        this.v = this.v.slice(this.start);
        this.start = 0;
      }
    }
    last() {
      for (let i = this.t.length - 1; i >= this.start; i--) if (this.v[i] !== null) return this.v[i];
      return null;
    }
  }

  class TimePlot {
    // options: title, unit, windowS (30), gapS (3), includeZero (true), note (text after the legend)
    constructor(canvas, options) {
      this.canvas = canvas;
      this.ctx = canvas.getContext('2d');
      this.title = options.title || '';
      this.unit = options.unit || '';
      this.windowS = options.windowS || 30;
      this.gapS = options.gapS || 3;
      this.includeZero = options.includeZero !== false;
      this.minRange = options.minRange || 1;
      this.note = options.note || '';
      this.series = new Map();
      this.everHadData = false;
      this.dirty = true;
      this.extraLegend = null; // [{label, color}] drawn instead of the series' own entries when set
    }

    ensure(key, options) {
      let s = this.series.get(key);
      if (!s) {
        const opts = Object.assign({}, options || {});
        if (!opts.color) opts.color = PALETTE[this.series.size % PALETTE.length];
        s = new Series(key, opts);
        this.series.set(key, s);
      }
      return s;
    }

    push(key, t, v, options) {
      const s = this.ensure(key, options);
      s.push(t, v);
      if (Number.isFinite(v)) this.everHadData = true;
      this.dirty = true;
    }

    resize() {
      const dpr = window.devicePixelRatio || 1;
      const w = Math.max(1, Math.round(this.canvas.clientWidth * dpr));
      const h = Math.max(1, Math.round(this.canvas.clientHeight * dpr));
      if (this.canvas.width !== w || this.canvas.height !== h) {
        this.canvas.width = w;
        this.canvas.height = h;
        this.dirty = true;
      }
      return dpr;
    }

    draw(nowS) {
      const dpr = this.resize();
      const ctx = this.ctx;
      const W = this.canvas.width / dpr;
      const H = this.canvas.height / dpr;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      ctx.clearRect(0, 0, W, H);
      ctx.fillStyle = '#10151b';
      ctx.fillRect(0, 0, W, H);
      ctx.font = '11px system-ui, sans-serif';
      ctx.textBaseline = 'top';

      // Title and legend, wrapping onto a second line when needed.
      ctx.fillStyle = '#e6edf3';
      const title = this.title + (this.unit ? ' (' + this.unit + ')' : '');
      ctx.fillText(title, 6, 3);
      let x = 6 + ctx.measureText(title).width + 12;
      let y = 3;
      const legend = this.extraLegend ? this.extraLegend.slice() :
        Array.from(this.series.values()).filter((s) => s.legend).map((s) => ({
          label: s.label + ' ' + formatValue(s.last()), color: s.color, dash: s.dash,
        }));
      if (this.note) legend.push({ label: this.note, color: null });
      for (const item of legend) {
        const w = ctx.measureText(item.label).width + (item.color ? 16 : 0);
        if (x + w > W - 4 && x > 60) { x = 40; y += 13; }
        if (item.color) {
          ctx.strokeStyle = item.color;
          ctx.lineWidth = 2;
          ctx.setLineDash(item.dash || []);
          ctx.beginPath();
          ctx.moveTo(x, y + 6);
          ctx.lineTo(x + 11, y + 6);
          ctx.stroke();
          ctx.setLineDash([]);
          x += 14;
        }
        ctx.fillStyle = item.color ? '#c9d1d9' : '#8590a0';
        ctx.fillText(item.label, x, y);
        x += ctx.measureText(item.label).width + 10;
      }

      const left = 40, right = W - 8, top = y + 17, bottom = H - 14;
      const oldest = nowS - this.windowS;
      for (const s of this.series.values()) s.trim(oldest - 1);

      let lo = Infinity, hi = -Infinity, any = false;
      for (const s of this.series.values()) {
        for (let i = s.start; i < s.t.length; i++) {
          const v = s.v[i];
          if (v === null || s.t[i] < oldest) continue;
          any = true;
          if (v < lo) lo = v;
          if (v > hi) hi = v;
        }
      }
      ctx.strokeStyle = '#2a323d';
      ctx.lineWidth = 1;
      ctx.strokeRect(left + 0.5, top + 0.5, right - left, Math.max(1, bottom - top));
      if (!any || bottom - top < 8) {
        ctx.fillStyle = '#8590a0';
        ctx.textAlign = 'center';
        ctx.textBaseline = 'middle';
        ctx.fillText(this.everHadData ? 'no data for ' + this.windowS + ' s' : 'no data yet',
                     (left + right) / 2, (top + bottom) / 2);
        ctx.textAlign = 'left';
        this.dirty = false;
        return;
      }
      if (this.includeZero) { lo = Math.min(lo, 0); hi = Math.max(hi, 0); }
      if (hi - lo < this.minRange) {
        const mid = (hi + lo) / 2;
        lo = this.includeZero && lo >= 0 ? Math.max(0, mid - this.minRange / 2) : mid - this.minRange / 2;
        hi = lo + this.minRange;
      }
      const pad = (hi - lo) * 0.06;
      if (!(this.includeZero && lo === 0)) lo -= pad;
      hi += pad;
      const step = niceStep(hi - lo, Math.max(2, Math.floor((bottom - top) / 22)));
      const yOf = (v) => bottom - ((v - lo) / (hi - lo)) * (bottom - top);
      const xOf = (t) => left + ((t - oldest) / this.windowS) * (right - left);

      // Grid and ticks.
      ctx.font = '10px system-ui, sans-serif';
      ctx.textBaseline = 'middle';
      ctx.textAlign = 'right';
      for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9; v += step) {
        const yy = Math.round(yOf(v)) + 0.5;
        ctx.strokeStyle = '#1f262f';
        ctx.beginPath(); ctx.moveTo(left, yy); ctx.lineTo(right, yy); ctx.stroke();
        ctx.fillStyle = '#8590a0';
        ctx.fillText(formatTick(v, step), left - 4, yy);
      }
      ctx.textAlign = 'center';
      ctx.textBaseline = 'top';
      for (let s = 0; s <= this.windowS; s += 10) {
        const xx = Math.round(xOf(oldest + s)) + 0.5;
        ctx.strokeStyle = '#1f262f';
        ctx.beginPath(); ctx.moveTo(xx, top); ctx.lineTo(xx, bottom); ctx.stroke();
        ctx.fillStyle = '#8590a0';
        const label = s === this.windowS ? 'now' : '-' + (this.windowS - s) + ' s';
        ctx.fillText(label, Math.min(Math.max(xx, left + 12), right - 12), bottom + 2);
      }
      ctx.textAlign = 'left';

      // Lines.
      ctx.save();
      ctx.beginPath();
      ctx.rect(left, top, right - left, bottom - top);
      ctx.clip();
      for (const s of this.series.values()) {
        ctx.strokeStyle = s.color;
        ctx.lineWidth = s.width;
        ctx.setLineDash(s.dash || []);
        ctx.beginPath();
        let pen = false, lastT = -Infinity, lone = null;
        for (let i = s.start; i < s.t.length; i++) {
          const t = s.t[i], v = s.v[i];
          if (v === null) { pen = false; continue; }
          const px = xOf(t), py = yOf(v);
          if (pen && t - lastT <= this.gapS) {
            ctx.lineTo(px, py);
            lone = null;
          } else {
            ctx.moveTo(px, py);
            lone = [px, py];
          }
          pen = true;
          lastT = t;
        }
        ctx.stroke();
        if (lone) { // a single fresh point: show it as a dot
          ctx.fillStyle = s.color;
          ctx.fillRect(lone[0] - 1.5, lone[1] - 1.5, 3, 3);
        }
      }
      ctx.setLineDash([]);
      ctx.restore();
      this.dirty = false;
    }
  }

  window.ShapesensePlots = { TimePlot, PALETTE, formatValue };
})();
