// format.js - numbers with SI units and prefixes, durations, dates, and small DOM helpers.

const PREFIXES = [
  [1e12, 'T'], [1e9, 'G'], [1e6, 'M'], [1e3, 'k'], [1, ''],
  [1e-3, 'm'], [1e-6, 'µ'], [1e-9, 'n'], [1e-12, 'p'], [1e-15, 'f'],
];

// 0.0123 J -> "12.3 mJ"; unit '' gives a bare number with a prefix-free compact form.
export function si(value, unit = '', digits = 3) {
  if (value === null || value === undefined || Number.isNaN(value)) return '–';
  if (!Number.isFinite(value)) return String(value);
  if (value === 0) return unit ? `0 ${unit}` : '0';
  if (!unit) return compact(value, digits);
  const a = Math.abs(value);
  for (const [f, p] of PREFIXES) {
    if (a >= f * 0.9995) return `${+(value / f).toPrecision(digits)} ${p}${unit}`;
  }
  return `${value.toExponential(digits - 1)} ${unit}`;
}

// A number in at most `digits` significant digits, exponent form when very large or small.
export function compact(v, digits = 3) {
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e6)) {
    const [m, e] = v.toExponential(digits - 1).split('e');
    return `${+m}e${+e}`;
  }
  return String(+v.toPrecision(digits));
}

// The SI prefix for values up to maxAbs: [factor, prefix], e.g. 0.004 -> [1e-3, 'm'].
export function prefixFor(maxAbs) {
  if (!(maxAbs > 0) || !Number.isFinite(maxAbs)) return [1, ''];
  for (const [f, p] of PREFIXES) if (maxAbs >= f * 0.9995) return [f, p];
  return PREFIXES[PREFIXES.length - 1];
}

export function count(n) {
  return n === null || n === undefined ? '–' : Math.round(n).toLocaleString('en');
}

// 3725 -> "1 h 02 min"; 42.4 -> "42 s".
export function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return '–';
  s = Math.max(0, Math.round(s));
  if (s < 60) return `${s} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${String(s % 60).padStart(2, '0')} s`;
  const h = Math.floor(s / 3600);
  return `${h} h ${String(Math.floor((s % 3600) / 60)).padStart(2, '0')} min`;
}

export function date(iso) {
  if (!iso) return '–';
  const d = new Date(iso);
  return Number.isNaN(d.getTime()) ? iso : d.toLocaleString();
}

export function percent(fraction) {
  return `${Math.floor(100 * Math.min(1, Math.max(0, fraction || 0)))}%`;
}

// el('a', {href: '#', class: 'x', onclick: f}, 'text', child...) -> element
export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (k === 'class') e.className = v;
    else if (k === 'dataset') Object.assign(e.dataset, v);
    else e.setAttribute(k, v === true ? '' : v);
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined || c === false) continue;
    e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return e;
}

export function statusBadge(status) {
  return el('span', { class: `badge status-${status}` }, status || '?');
}

export function progressBar(fraction, status) {
  const pct = percent(status === 'succeeded' ? 1 : fraction);
  return el('div', { class: 'bar', role: 'progressbar', 'aria-valuenow': parseInt(pct, 10),
    'aria-valuemin': 0, 'aria-valuemax': 100 },
  el('div', { class: `fill status-${status}`, style: `width: ${pct}` }),
  el('span', { class: 'bar-text' }, pct));
}
