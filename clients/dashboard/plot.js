// plot.js - a small line plot on a canvas: axes with units, 1-2-5 ticks, optional log y, a
// legend for several series, and a readout of the values under the pointer.
//
//   const p = new Plot(canvas, {xLabel: 'time', xUnit: 's', yLabel: 'kinetic energy', yUnit: 'J'});
//
// With a unit, a linear axis is labelled in the SI prefix that suits its range ("time [ms]",
// ticks 0, 5, 10); a log axis keeps the base unit and exponent ticks.
//   p.setData([{name: 'KE', x: Float64Array, y: Float64Array}]);

import { compact, prefixFor } from './format.js';

const COLORS = ['#1f6feb', '#d1242f', '#1a7f37', '#9a6700', '#8250df', '#bf3989', '#0a7ea4'];
const M = { left: 64, right: 14, top: 14, bottom: 42 };

export class Plot {
  // xMax: the x axis reaches at least this far (a running job's duration); legend: 'always'
  // names even a single series.
  constructor(canvas, { xLabel = '', xUnit = '', yLabel = '', yUnit = '', logY = false,
    empty = 'no data yet', xMax = null, legend = 'auto' } = {}) {
    this.xMax = xMax;
    this.legendMode = legend;
    this.canvas = canvas;
    this.xLabel = xLabel;
    this.xUnit = xUnit;
    this.yLabel = yLabel;
    this.yUnit = yUnit;
    this.logY = logY;
    this.empty = empty;
    this.series = [];
    this.hover = null;
    canvas.addEventListener('mousemove', (e) => {
      const r = canvas.getBoundingClientRect();
      this.hover = e.clientX - r.left;
      this.draw();
    });
    canvas.addEventListener('mouseleave', () => {
      this.hover = null;
      this.draw();
    });
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  setData(series) {
    this.series = series.map((s, i) => ({ color: COLORS[i % COLORS.length], ...s }));
    this.draw();
  }

  setLogY(on) {
    this.logY = on;
    this.draw();
  }

  // The data range, with log y ignoring values <= 0.
  range() {
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (const s of this.series) {
      for (let i = 0; i < s.x.length; i++) {
        const x = s.x[i], y = s.y[i];
        if (!Number.isFinite(x) || !Number.isFinite(y) || (this.logY && y <= 0)) continue;
        if (x < x0) x0 = x;
        if (x > x1) x1 = x;
        if (y < y0) y0 = y;
        if (y > y1) y1 = y;
      }
    }
    if (x0 > x1) return null;
    if (this.xMax !== null && this.xMax > x1) x1 = this.xMax;
    if (x0 === x1) x1 = x0 + 1;
    if (this.logY) {
      y0 = Math.log10(y0);
      y1 = Math.log10(y1);
      if (y1 - y0 < 1) { y0 = Math.floor(y0); y1 = Math.max(y1, y0 + 1); }
    } else {
      if (y0 > 0) y0 = 0; // counts, energies and magnitudes read best from zero
      if (y0 === y1) { y0 -= Math.abs(y0) || 1; y1 += Math.abs(y1) || 1; }
      y1 += 0.05 * (y1 - y0); // headroom: a flat line at the maximum stays off the frame
    }
    return { x0, x1, y0, y1 };
  }

  draw() {
    const c = this.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth, h = c.clientHeight;
    if (!w || !h) return;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    g.font = '12px system-ui, sans-serif';
    const pw = w - M.left - M.right, ph = h - M.top - M.bottom;
    const r = this.range();
    const [xf, xp] = r ? prefixFor(Math.max(Math.abs(r.x0), Math.abs(r.x1))) : [1, ''];
    const [yf, yp] = r && !this.logY ? prefixFor(Math.max(Math.abs(r.y0), Math.abs(r.y1))) : [1, ''];
    const label = (name, unit, p) => (unit ? `${name} [${p}${unit}]` : name);
    this.xText = label(this.xLabel, this.xUnit, xp);
    g.fillStyle = '#57606a';
    g.textAlign = 'center';
    g.fillText(this.xText, M.left + pw / 2, h - 6);
    g.save();
    g.translate(14, M.top + ph / 2);
    g.rotate(-Math.PI / 2);
    g.fillText(label(this.yLabel, this.yUnit, yp) + (this.logY ? ' (log)' : ''), 0, 0);
    g.restore();
    g.strokeStyle = '#d0d7de';
    g.strokeRect(M.left + 0.5, M.top + 0.5, pw, ph);
    if (!r) {
      g.fillText(this.empty, M.left + pw / 2, M.top + ph / 2);
      return;
    }
    const X = (x) => M.left + ((x - r.x0) / (r.x1 - r.x0)) * pw;
    const Y = (y) => M.top + ph - ((this.logY ? Math.log10(y) : y) - r.y0) / (r.y1 - r.y0) * ph;
    // grid and ticks
    g.fillStyle = '#57606a';
    g.strokeStyle = '#eaeef2';
    for (const t of ticks(r.x0, r.x1, Math.max(2, Math.floor(pw / 90)))) {
      const px = Math.round(X(t)) + 0.5;
      line(g, px, M.top, px, M.top + ph);
      g.textAlign = 'center';
      g.fillText(compact(this.xUnit ? t / xf : t), px, M.top + ph + 16);
    }
    const yt = this.logY
      ? decades(r.y0, r.y1).map((e) => 10 ** e)
      : ticks(r.y0, r.y1, Math.max(2, Math.floor(ph / 40)));
    for (const t of yt) {
      const py = Math.round(Y(t)) + 0.5;
      line(g, M.left, py, M.left + pw, py);
      g.textAlign = 'right';
      g.fillText(compact(this.yUnit && !this.logY ? t / yf : t), M.left - 6, py + 4);
    }
    // series
    g.save();
    g.beginPath();
    g.rect(M.left, M.top, pw, ph);
    g.clip();
    g.lineWidth = 1.5;
    for (const s of this.series) {
      g.strokeStyle = s.color;
      g.beginPath();
      let pen = false;
      for (let i = 0; i < s.x.length; i++) {
        const y = s.y[i];
        if (!Number.isFinite(y) || (this.logY && y <= 0)) { pen = false; continue; }
        const px = X(s.x[i]), py = Y(y);
        if (pen) g.lineTo(px, py);
        else g.moveTo(px, py);
        pen = true;
      }
      if (s.x.length === 1) g.arc(X(s.x[0]), Y(s.y[0]), 2, 0, 2 * Math.PI);
      g.stroke();
    }
    g.restore();
    this.legend(g, pw);
    this.readout(g, r, X, Y, ph);
  }

  legend(g, pw) {
    if (this.series.length < (this.legendMode === 'always' ? 1 : 2)) return;
    g.textAlign = 'left';
    let x = M.left + 8;
    for (const s of this.series) {
      const tw = g.measureText(s.name).width;
      if (x + tw + 24 > M.left + pw) break;
      g.fillStyle = s.color;
      g.fillRect(x, M.top + 8, 12, 3);
      g.fillStyle = '#24292f';
      g.fillText(s.name, x + 16, M.top + 13);
      x += tw + 30;
    }
  }

  // Values of every series at the x under the pointer.
  readout(g, r, X, Y, ph) {
    if (this.hover === null || this.hover < M.left) return;
    const xv = r.x0 + ((this.hover - M.left) / (X(r.x1) - M.left)) * (r.x1 - r.x0);
    const unit = (u) => (u ? ` ${u}` : '');
    const lines = [`${this.xLabel} ${compact(xv, 4)}${unit(this.xUnit)}`];
    for (const s of this.series) {
      const i = nearest(s.x, xv);
      if (i < 0) continue;
      lines.push(`${s.name}: ${compact(s.y[i], 4)}${unit(this.yUnit)}`);
      g.fillStyle = s.color;
      if (Number.isFinite(s.y[i]) && (!this.logY || s.y[i] > 0)) g.fillRect(X(s.x[i]) - 2, Y(s.y[i]) - 2, 5, 5);
    }
    g.strokeStyle = '#8c959f';
    line(g, this.hover + 0.5, M.top, this.hover + 0.5, M.top + ph);
    g.textAlign = 'left';
    const bw = Math.max(...lines.map((l) => g.measureText(l).width)) + 10;
    const bx = this.hover + bw + 10 > g.canvas.clientWidth ? this.hover - bw - 6 : this.hover + 6;
    g.fillStyle = 'rgba(255,255,255,0.9)';
    g.fillRect(bx, M.top + 20, bw, lines.length * 15 + 6);
    g.fillStyle = '#24292f';
    lines.forEach((l, k) => g.fillText(l, bx + 5, M.top + 35 + 15 * k));
  }
}

function line(g, x0, y0, x1, y1) {
  g.beginPath();
  g.moveTo(x0, y0);
  g.lineTo(x1, y1);
  g.stroke();
}

// About n "nice" (1, 2, 5 x 10^k) ticks in [a, b].
export function ticks(a, b, n) {
  const raw = (b - a) / n;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
  const out = [];
  for (let t = Math.ceil(a / step) * step; t <= b + step * 1e-9; t += step) {
    out.push(Math.abs(t) < step * 1e-9 ? 0 : +t.toPrecision(12));
  }
  return out;
}

function decades(e0, e1) {
  const out = [];
  const stride = Math.max(1, Math.ceil((Math.ceil(e1) - Math.floor(e0)) / 8));
  for (let e = Math.ceil(e0); e <= Math.floor(e1); e += stride) out.push(e);
  return out;
}

// Index of the sample nearest to x in the increasing array xs, -1 when empty.
function nearest(xs, x) {
  if (!xs.length) return -1;
  let lo = 0, hi = xs.length - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (xs[mid] < x) lo = mid;
    else hi = mid;
  }
  return Math.abs(xs[lo] - x) <= Math.abs(xs[hi] - x) ? lo : hi;
}
