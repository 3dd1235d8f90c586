// job.js - one job: its state (live over SSE), plots of kinetic energy, contacts, wall forces and stage times
// against time from /stats (refreshed while it runs; the progress events fill in until /stats
// answers), the 3D viewer of any output frame with a time slider and play, and downloads.

import { api, ApiError, getToken, flat, jobPath, watchJob, normalizeStats, FINISHED } from './api.js';
import { el, statusBadge, progressBar, si, count, duration, date } from './format.js';
import { mountNav, showMessage } from './nav.js';
import { Plot } from './plot.js';
import { Viewer, webglAvailable, sceneFromScenario, boxMesh } from './viewer.js';

const id = new URLSearchParams(location.search).get('id');
const $ = (s) => document.getElementById(s);

let job = null;
let scenario = null;
const live = { time: [], kinetic_energy: [], contacts: [] }; // progress samples
let statsOk = false;
let statsTimer = null;
const plots = {};

// ---- job state ---------------------------------------------------------------------------------

function renderJob() {
  const p = job.progress || {};
  document.title = `polydem · ${job.name || job.id}`;
  $('job-name').textContent = job.name || '(unnamed)';
  $('job-status').replaceChildren(statusBadge(job.status));
  $('job-bar').replaceChildren(progressBar(p.fraction, job.status));
  const kv = [
    ['id', job.id],
    ['tags', (job.tags || []).join(', ') || '–'],
    ['created', date(job.created_at)],
    ['started', date(job.started_at)],
    ['finished', date(job.finished_at)],
    ['step', p.steps_total ? `${count(p.step)} / ${count(p.steps_total)}` : count(p.step)],
    ['simulated time', si(p.sim_time, 's')],
    ['speed', p.steps_per_second ? `${si(p.steps_per_second, '', 3)} steps/s` : '–'],
    ['ETA', job.status === 'running' ? duration(p.eta_seconds) : '–'],
    ['particles', count(p.particles)],
    ['contacts', count(p.contacts)],
    ['kinetic energy', si(p.kinetic_energy, 'J')],
  ];
  $('job-facts').replaceChildren(...kv.map(([k, v]) => el('div', {}, el('dt', {}, k), el('dd', {}, v))));
  $('job-error').hidden = !job.error;
  $('job-error').textContent = job.error ? `error: ${job.error}` : '';
  // a job cancelled or failed while running may keep its frames so far (result_available)
  const done = job.status === 'succeeded' || job.result_available === true;
  for (const [a, route] of [['dl-result', '/result'], ['dl-xmf', '/result.xmf']]) {
    $(a).href = done ? jobPath(id, route) : '#';
    $(a).classList.toggle('disabled', !done);
    $(a).title = done ? (job.status === 'succeeded' ? '' : `the frames written before the job was ${job.status}`)
      : 'available when the job has succeeded';
  }
  $('cancel').hidden = FINISHED.includes(job.status);
  $('delete').hidden = !FINISHED.includes(job.status);
}

// With a token, a download goes through fetch (a link cannot send the Authorization header)
// and is saved from a blob; without one the plain link streams it.
async function download(ev) {
  const a = ev.currentTarget;
  if (!getToken() || a.classList.contains('disabled')) return;
  ev.preventDefault();
  const route = a.id === 'dl-xmf' ? '/result.xmf' : '/result';
  try {
    const r = await fetch(jobPath(id, route), { headers: { Authorization: `Bearer ${getToken()}` } });
    if (!r.ok) throw new Error(`HTTP ${r.status}`);
    const url = URL.createObjectURL(await r.blob());
    const save = el('a', { href: url, download: `${id}${route === '/result' ? '.h5' : '.h5.xmf'}` });
    document.body.append(save);
    save.click();
    save.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
  } catch (e) {
    showMessage(`download: ${e.message}`);
  }
}

function onJob(j) {
  const was = job && job.status;
  job = j;
  renderJob();
  const p = j.progress || {};
  if (j.status === 'running' && p.sim_time !== undefined) {
    const n = live.time.length;
    if (!n || p.sim_time > live.time[n - 1]) {
      live.time.push(p.sim_time);
      live.kinetic_energy.push(p.kinetic_energy);
      live.contacts.push(p.contacts);
      if (!statsOk) drawLive();
    }
  }
  if (was !== j.status && FINISHED.includes(j.status)) {
    loadStats();
    if (j.status === 'succeeded' || j.result_available === true) loadViewer();
  }
}

// ---- plots -------------------------------------------------------------------------------------

function setupPlots() {
  const time = { xLabel: 'time', xUnit: 's' };
  plots.ke = new Plot($('plot-ke'), { ...time, yLabel: 'kinetic energy', yUnit: 'J' });
  plots.contacts = new Plot($('plot-contacts'), { ...time, yLabel: 'contacts' });
  plots.walls = new Plot($('plot-walls'), { ...time, yLabel: 'wall force |F|', yUnit: 'N', legend: 'always' });
  plots.stages = new Plot($('plot-stages'), { ...time, yLabel: 'time per step', yUnit: 's', legend: 'always' });
  $('ke-log').addEventListener('change', (e) => plots.ke.setLogY(e.target.checked));
}

function drawLive() {
  const t = Float64Array.from(live.time);
  plots.ke.setData([{ name: 'kinetic energy', x: t, y: Float64Array.from(live.kinetic_energy) }]);
  plots.contacts.setData([{ name: 'contacts', x: t, y: Float64Array.from(live.contacts) }]);
  $('plot-note').textContent = 'from progress reports until /stats is available';
}

async function loadStats() {
  clearTimeout(statsTimer);
  try {
    const s = normalizeStats(await api(jobPath(id, '/stats')));
    statsOk = s.time.length > 0;
    if (statsOk) {
      plots.ke.setData([{ name: 'kinetic energy', x: s.time, y: s.kinetic_energy }]);
      plots.contacts.setData([{ name: 'contacts', x: s.time, y: s.contacts }]);
      const walls = Object.entries(s.walls);
      const hasWalls = scenario && (scenario.walls || []).length > 0;
      plots.walls.empty = hasWalls && !FINISHED.includes(job.status)
        ? 'wall forces are shown when the job has finished' : 'no walls in this scenario';
      plots.walls.setData(walls.map(([name, y]) => ({ name, x: s.time, y })));
      plots.stages.empty = FINISHED.includes(job.status)
        ? 'no stage times in this result' : 'stage times are shown when the job has finished';
      plots.stages.setData(Object.entries(s.stages).map(([name, y]) => ({ name, x: s.time, y })));
      $('plot-note').textContent = `${count(s.time.length)} stats rows`;
    }
  } catch (e) {
    if (!(e instanceof ApiError) || (e.status !== 409 && e.status !== 404)) {
      $('plot-note').textContent = `stats: ${e.message}`;
    }
  }
  if (job && !FINISHED.includes(job.status)) statsTimer = setTimeout(loadStats, 3000);
}

// ---- viewer ------------------------------------------------------------------------------------

const view = { viewer: null, frames: 0, k: 0, cache: new Map(), playing: false, loading: false };

async function loadViewer() {
  const note = $('viewer-note');
  if (!webglAvailable()) {
    note.textContent = 'The 3D viewer needs three.js: the daemon serves it from Debian\'s libjs-three at /vendor/three/.';
    return;
  }
  if (view.viewer) return;
  let info = null;
  let frame0;
  try {
    frame0 = await api(jobPath(id, '/frames/0'));
  } catch (e) {
    note.textContent = e.status === 409 ? 'Frames are shown when the job has finished.' : `frames: ${e.message}`;
    return;
  }
  scenario = scenario || (await api(jobPath(id, '/scenario')).catch(() => ({})));
  const n = (frame0.position.length && Array.isArray(frame0.position[0]))
    ? frame0.position.length : frame0.position.length / 3;
  try {
    info = await api(jobPath(id, '/shapes'));
  } catch {
    info = null;
  }
  if (!info || !info.shapes || !info.particles) {
    info = sceneFromScenario(scenario, n);
    note.textContent = 'The daemon sent no shapes (/shapes): particles are drawn as spheres of their size.';
  } else {
    note.textContent = '';
    if (!info.walls) info.walls = (scenario.walls || []).filter((w) => w.box).map((w) => boxMesh(w.name, w.box.min, w.box.max));
  }
  view.frames = frameCount(info, frame0);
  try {
    view.viewer = new Viewer($('viewer'));
  } catch (e) {
    note.textContent = `3D viewer: ${e.message}`;
    return;
  }
  view.viewer.setScene(info);
  view.cache.set(0, frame0);
  const slider = $('frame');
  slider.max = String(Math.max(0, view.frames - 1));
  slider.disabled = view.frames < 2;
  $('play').disabled = view.frames < 2;
  show(0, frame0);
  // Frame the first and the last positions together (the particles may travel far); a double
  // click frames them again.
  const fitAll = async () => {
    const last = view.frames > 1 ? await getFrame(view.frames - 1).catch(() => null) : null;
    view.viewer.fit([flat(frame0.position), ...(last ? [flat(last.position)] : [])]);
  };
  fitAll();
  $('viewer').addEventListener('dblclick', fitAll);
}

function frameCount(info, frame0) {
  const c = (info.frames && (info.frames.count ?? info.frames.length)) ?? info.frame_count ??
    frame0.frames ?? frame0.count;
  if (Number.isInteger(c) && c > 0) return c;
  const t = (scenario && scenario.time) || {};
  const dt = t.output_interval || Math.max((t.duration || 0) / 100, t.dt || 0);
  return dt > 0 ? Math.floor(t.duration / dt + 1e-6) + 1 : 1;
}

function show(k, frame) {
  view.k = k;
  view.viewer.setFrame(frame);
  $('frame').value = String(k);
  $('frame-label').textContent = `frame ${k} / ${view.frames - 1} · t = ${si(frame.time, 's', 4)}`;
}

async function getFrame(k) {
  if (view.cache.has(k)) return view.cache.get(k);
  const f = await api(jobPath(id, `/frames/${k}`));
  view.cache.set(k, f);
  if (view.cache.size > 64) view.cache.delete(view.cache.keys().next().value);
  return f;
}

async function goTo(k) {
  if (view.loading) {
    view.pending = k;
    return;
  }
  view.loading = true;
  try {
    show(k, await getFrame(k));
  } catch (e) {
    if (e.status === 404 && k > 0) {
      view.frames = k; // fewer frames than the scenario suggests
      $('frame').max = String(k - 1);
    } else {
      $('viewer-note').textContent = `frame ${k}: ${e.message}`;
    }
    stop();
  } finally {
    view.loading = false;
  }
  if (view.pending !== undefined) {
    const p = view.pending;
    view.pending = undefined;
    goTo(p);
  }
}

async function play() {
  if (view.playing) return stop();
  view.playing = true;
  $('play').textContent = 'Pause';
  if (view.k >= view.frames - 1) view.k = -1;
  while (view.playing && view.k < view.frames - 1) {
    const t0 = performance.now();
    await goTo(view.k + 1);
    getFrame(view.k + 1).catch(() => {}); // prefetch
    await new Promise((r) => setTimeout(r, Math.max(0, 100 - (performance.now() - t0))));
  }
  stop();
}

function stop() {
  view.playing = false;
  $('play').textContent = 'Play';
}

// ---- actions and start -------------------------------------------------------------------------

async function act(what) {
  if (what === 'delete' && !confirm(`Delete job ${job.name || id} and its result files?`)) return;
  try {
    if (what === 'cancel') onJob(await api(jobPath(id, '/cancel'), { method: 'POST' }) || job);
    else {
      await api(jobPath(id), { method: 'DELETE' });
      location.href = 'index.html';
    }
  } catch (e) {
    showMessage(`${what}: ${e.message}`);
  }
}

async function init() {
  mountNav('');
  if (!id) {
    showMessage('no job id: open a job from the jobs page');
    return;
  }
  setupPlots();
  $('play').addEventListener('click', play);
  $('frame').addEventListener('input', (e) => {
    stop();
    goTo(parseInt(e.target.value, 10));
  });
  $('cancel').addEventListener('click', () => act('cancel'));
  $('dl-result').addEventListener('click', download);
  $('dl-xmf').addEventListener('click', download);
  $('delete').addEventListener('click', () => act('delete'));
  $('show-scenario').addEventListener('toggle', async (e) => {
    if (!e.target.open || $('scenario-text').textContent) return;
    try {
      scenario = scenario || (await api(jobPath(id, '/scenario')));
      $('scenario-text').textContent = JSON.stringify(scenario, null, 2);
    } catch (err) {
      $('scenario-text').textContent = err.message;
    }
  });
  window.addEventListener('polydem-token', () => location.reload());
  try {
    job = await api(jobPath(id));
  } catch (e) {
    showMessage(e.status === 404 ? `no job ${id} (or it belongs to another token)` : `job ${id}: ${e.message}`);
    return;
  }
  renderJob();
  if (!FINISHED.includes(job.status)) {
    // While it runs, the time axes span the whole simulated duration.
    scenario = await api(jobPath(id, '/scenario')).catch(() => null);
    const d = scenario && scenario.time && scenario.time.duration;
    if (d > 0) for (const p of Object.values(plots)) p.xMax = d;
  }
  loadStats();
  if (job.status === 'succeeded' || job.result_available === true) loadViewer();
  else if (!FINISHED.includes(job.status)) {
    $('viewer-note').textContent = 'Frames are shown when the job has finished.';
    watchJob(job, onJob);
  } else {
    $('viewer-note').textContent = `No frames: the job ${job.status}.`;
  }
}

init();
