// submit.js - the submit page: paste, upload or start from a bundled example; the daemon's
// dry run (/v1/scenarios/validate) runs as you type and shows each error next to its JSON path
// (click a path to select it in the editor); submit with tags and a priority.

import { api, ApiError } from './api.js';
import { el, si, count } from './format.js';
import { locate, lineCol, spanFor } from './jsonloc.js';
import { mountNav, showMessage } from './nav.js';

// The scenarios in examples/, served read-only by the daemon at /examples/NAME.json.
const EXAMPLES = [
  ['collision', 'Two-particle collision (rock and sphere)'],
  ['cube_settling', 'A cube and Schönhardt prisms settling on a floor'],
  ['packing', 'Gravity packing of Schönhardt particles in a box'],
  ['hopper', 'Hopper discharge onto a plate'],
  ['tumbler', 'Rocks tumbling in a turning square drum (moving walls)'],
];

const editor = document.getElementById('scenario');
const results = document.getElementById('validation');
const submitBtn = document.getElementById('submit');
const tagsInput = document.getElementById('tags');
const prioInput = document.getElementById('priority');
let timer = null;
let seq = 0;
let idemKey = newKey();

function newKey() {
  return (crypto.randomUUID && crypto.randomUUID()) ||
    Array.from(crypto.getRandomValues(new Uint8Array(16)), (b) => b.toString(16).padStart(2, '0')).join('');
}

// Checks the text: JSON syntax here, everything else by the daemon's dry run.
async function validate() {
  const my = ++seq;
  const text = editor.value;
  if (!text.trim()) {
    results.replaceChildren(el('p', { class: 'muted' }, 'Paste a scenario, upload one or pick an example.'));
    return null;
  }
  const loc = locate(text);
  if (loc.error) {
    const { line, col } = lineCol(text, loc.error.offset);
    showErrors(text, loc.spans, [{ path: '', message: `JSON syntax: ${loc.error.message} at line ${line}, column ${col}`,
      offset: loc.error.offset }]);
    return false;
  }
  results.replaceChildren(el('p', { class: 'muted' }, 'Checking…'));
  try {
    const r = await api('/v1/scenarios/validate', { method: 'POST', body: text });
    if (my !== seq) return null;
    showSummary(r);
    return true;
  } catch (e) {
    if (my !== seq) return null;
    if (e instanceof ApiError && e.details && e.details.length) {
      showErrors(text, loc.spans, e.details);
    } else {
      showErrors(text, loc.spans, [{ path: '', message: e.message }]);
    }
    return false;
  }
}

function showErrors(text, spans, details) {
  results.className = 'validation bad';
  const items = details.map((d) => {
    const path = d.path || '';
    const found = path ? spanFor(spans, path) : null;
    const offset = d.offset ?? (found ? found.span.keyStart : null);
    const where = offset !== null && offset !== undefined ? `line ${lineCol(text, offset).line}` : '';
    const pathEl = el('a', { href: '#', class: 'path', title: 'select in the editor', onclick: (ev) => {
      ev.preventDefault();
      if (found) select(found.span.keyStart, found.span.end);
      else if (offset !== null && offset !== undefined) select(offset, offset + 1);
    } }, path || '(document)');
    return el('li', { class: 'field-error', dataset: { path } },
      pathEl, el('span', { class: 'where' }, where), el('span', { class: 'msg' }, d.message));
  });
  results.replaceChildren(el('p', { class: 'verdict' },
    details.length === 1 ? '1 problem' : `${details.length} problems`), el('ul', {}, items));
  submitBtn.disabled = false; // the daemon has the last word; a submit shows the same errors
}

function select(start, end) {
  editor.focus();
  editor.setSelectionRange(start, end);
  // Scroll the selection into view: the line's share of the text's height.
  const line = lineCol(editor.value, start).line;
  const lines = editor.value.split('\n').length;
  editor.scrollTop = Math.max(0, (line - 3) / lines * editor.scrollHeight);
}

// The dry run's estimates: whatever the daemon reports, with units where the name tells them.
function showSummary(r) {
  results.className = 'validation ok';
  const rows = [];
  const add = (label, value) => rows.push(el('tr', {}, el('th', {}, label), el('td', {}, value)));
  const flat = (o, prefix = '') => {
    for (const [k, v] of Object.entries(o || {})) {
      if (v && typeof v === 'object' && !Array.isArray(v)) flat(v, `${prefix}${k}.`);
      else if (k !== 'valid' && k !== 'ok') add(prefix + k.replace(/_/g, ' '), describe(k, v));
    }
  };
  flat(r && r.summary ? { name: r.name, ...r.summary } : r);
  results.replaceChildren(el('p', { class: 'verdict' }, 'Valid scenario'), el('table', { class: 'kv' }, rows));
}

function describe(key, v) {
  if (typeof v !== 'number') return Array.isArray(v) ? v.join(', ') : String(v);
  if (/bytes|memory/.test(key)) return si(v, 'B');
  if (/(^|_)dt|time|duration|interval|seconds/.test(key)) return si(v, 's');
  if (/particles|count|steps|frames|triangles|pairs/.test(key)) return count(v);
  return si(v);
}

function scheduleValidate() {
  clearTimeout(timer);
  idemKey = newKey();
  timer = setTimeout(validate, 600);
}

async function submit() {
  showMessage('');
  const text = editor.value;
  let scenario;
  try {
    scenario = JSON.parse(text);
  } catch {
    await validate();
    return;
  }
  const tags = tagsInput.value.split(',').map((t) => t.trim()).filter(Boolean);
  const priority = parseInt(prioInput.value || '0', 10);
  if (!Number.isFinite(priority)) {
    showMessage('priority: expected a whole number');
    return;
  }
  submitBtn.disabled = true;
  try {
    const job = await api('/v1/jobs', { method: 'POST', body: { scenario, tags, priority },
      headers: { 'Idempotency-Key': idemKey } });
    idemKey = newKey();
    location.href = `index.html?highlight=${encodeURIComponent(job.id)}`;
  } catch (e) {
    if (e.details && e.details.length) {
      showErrors(text, locate(text).spans, e.details.map((d) => ({ ...d, path: editorPath(d.path, scenario) })));
      showMessage(`not submitted: ${e.message}`);
    } else {
      showMessage(`not submitted: ${e.message}`);
    }
  } finally {
    submitBtn.disabled = false;
  }
}

// POST /v1/jobs gets the editor's scenario wrapped as {scenario, tags, priority}, so its error
// paths point into the wrapper (/scenario/time/dt); the editor holds the bare scenario
// (/time/dt) unless it has a "scenario" member of its own.
function editorPath(path, scenario) {
  if (!path || (scenario && typeof scenario === 'object' && 'scenario' in scenario)) return path;
  if (path === '/scenario') return '';
  return path.startsWith('/scenario/') ? path.slice('/scenario'.length) : path;
}

async function loadExample(name) {
  if (!name) return;
  try {
    const r = await fetch(`/examples/${encodeURIComponent(name)}.json`);
    if (!r.ok) throw new Error(`HTTP ${r.status}`);
    editor.value = await r.text();
    showMessage('');
    scheduleValidate();
  } catch (e) {
    showMessage(`example ${name}: cannot load /examples/${name}.json (${e.message}); this daemon does not serve the examples`);
  }
}

function init() {
  mountNav('submit');
  const sel = document.getElementById('example');
  for (const [name, label] of EXAMPLES) sel.append(el('option', { value: name }, `${name} — ${label}`));
  sel.addEventListener('change', () => loadExample(sel.value));
  document.getElementById('file').addEventListener('change', async (ev) => {
    const f = ev.target.files[0];
    if (!f) return;
    editor.value = await f.text();
    sel.value = '';
    scheduleValidate();
  });
  editor.addEventListener('input', scheduleValidate);
  document.getElementById('check').addEventListener('click', validate);
  submitBtn.addEventListener('click', submit);
  window.addEventListener('polydem-token', validate);
  const q = new URLSearchParams(location.search).get('example');
  if (q) {
    sel.value = q;
    loadExample(q);
  } else {
    validate();
  }
}

init();
