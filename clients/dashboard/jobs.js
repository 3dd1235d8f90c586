// jobs.js - the jobs page: every job with status, name, tags, progress, steps/s and ETA, live
// over SSE for the jobs that run (and the next queued ones); filter by status and tag (kept in
// the URL); cancel and delete.

import { api, jobList, jobPath, watchJob, FINISHED } from './api.js';
import { el, statusBadge, progressBar, si, duration, date } from './format.js';
import { mountNav, showMessage } from './nav.js';

const LIST_REFRESH_MS = 4000;
const MAX_STREAMS = 4; // browsers allow about 6 connections per server over HTTP/1.1

const state = {
  jobs: new Map(), // id -> job, in list order
  next: null,
  streams: new Map(), // id -> watcher
  highlight: new URLSearchParams(location.search).get('highlight'),
};

const statusSel = document.getElementById('filter-status');
const tagInput = document.getElementById('filter-tag');
const tbody = document.getElementById('jobs-body');
const more = document.getElementById('more');

function filters() {
  return { status: statusSel.value, tag: tagInput.value.trim() };
}

function listUrl(after) {
  const q = new URLSearchParams();
  const f = filters();
  if (f.status) q.set('status', f.status);
  if (f.tag) q.set('tag', f.tag);
  q.set('limit', '100');
  if (after) q.set('after', after);
  return '/v1/jobs?' + q;
}

async function refresh() {
  try {
    const { jobs, next } = jobList(await api(listUrl()));
    const keep = new Map();
    for (const j of jobs) keep.set(j.id, mergeKnown(j));
    // Jobs loaded with "more" stay below the first page.
    for (const [id, j] of state.jobs) if (!keep.has(id) && state.loadedMore) keep.set(id, j);
    state.jobs = keep;
    if (!state.loadedMore) state.next = next;
    showMessage('');
  } catch (e) {
    showMessage(`cannot list jobs: ${e.message}`);
  }
  render();
  follow();
}

// An ended job never runs again, so a copy fetched before its end (a list or a cancel
// response answered after the stream reported the end) must not bring back its Cancel button:
// that would cancel a finished job (409) where the user wanted Delete.
function notOlder(j) {
  const old = state.jobs.get(j.id);
  return old && FINISHED.includes(old.status) && !FINISHED.includes(j.status) ? old : j;
}

// A streamed job may be newer than the list's copy: keep the furthest progress.
function mergeKnown(j) {
  const old = state.jobs.get(j.id);
  if (notOlder(j) !== j) return old;
  if (old && state.streams.has(j.id) && !FINISHED.includes(j.status)) {
    const a = (old.progress && old.progress.step) || 0;
    const b = (j.progress && j.progress.step) || 0;
    if (a > b) return { ...j, progress: old.progress };
  }
  return j;
}

async function loadMore() {
  if (!state.next) return;
  try {
    const { jobs, next } = jobList(await api(listUrl(state.next)));
    for (const j of jobs) state.jobs.set(j.id, j);
    state.next = next;
    state.loadedMore = true;
  } catch (e) {
    showMessage(`cannot list more jobs: ${e.message}`);
  }
  render();
}

// Streams for running jobs first, then the oldest queued ones, up to MAX_STREAMS.
function follow() {
  const all = [...state.jobs.values()];
  const want = [
    ...all.filter((j) => j.status === 'running'),
    ...all.filter((j) => j.status === 'queued').reverse(),
  ].slice(0, MAX_STREAMS).map((j) => j.id);
  for (const [id, w] of state.streams) {
    if (!want.includes(id)) {
      w.close();
      state.streams.delete(id);
    }
  }
  for (const id of want) {
    if (state.streams.has(id)) continue;
    state.streams.set(id, watchJob(state.jobs.get(id), (j) => {
      if (!state.jobs.has(j.id)) return;
      state.jobs.set(j.id, j);
      renderRow(j);
      if (FINISHED.includes(j.status)) {
        state.streams.delete(j.id);
        setTimeout(refresh, 200); // the next queued job starts
      }
    }));
  }
}

function render() {
  const rows = [...state.jobs.values()].map(row);
  tbody.replaceChildren(...rows);
  if (!rows.length) {
    tbody.append(el('tr', {}, el('td', { colspan: 9, class: 'empty' },
      filters().status || filters().tag ? 'No job matches the filter.' : 'No jobs yet: submit one.')));
  }
  more.hidden = !state.next;
}

function renderRow(j) {
  const old = tbody.querySelector(`tr[data-id="${CSS.escape(j.id)}"]`);
  if (old) old.replaceWith(row(j));
}

function row(j) {
  const p = j.progress || {};
  const running = j.status === 'running';
  const tags = (j.tags || []).map((t) =>
    el('a', { href: '#', class: 'tag', title: 'show only this tag', onclick: (e) => {
      e.preventDefault();
      tagInput.value = t;
      applyFilters();
    } }, t));
  const actions = [];
  if (!FINISHED.includes(j.status)) {
    actions.push(el('button', { class: 'small', onclick: () => act(j, 'cancel') }, 'Cancel'));
  } else {
    actions.push(el('button', { class: 'small danger', onclick: () => act(j, 'delete') }, 'Delete'));
  }
  return el('tr', { dataset: { id: j.id, status: j.status },
    class: j.id === state.highlight ? 'highlight' : null },
  el('td', {}, el('a', { href: `job.html?id=${encodeURIComponent(j.id)}`, class: 'job-name' },
    j.name || '(unnamed)'), el('div', { class: 'job-id' }, j.id)),
  el('td', {}, statusBadge(j.status), j.error ? el('div', { class: 'job-error', title: j.error }, j.error) : null),
  el('td', {}, tags),
  el('td', { class: 'progress-cell' }, progressBar(p.fraction, j.status)),
  el('td', { class: 'num' }, running && p.steps_per_second ? `${si(p.steps_per_second, '', 3)} steps/s` : '–'),
  el('td', { class: 'num' }, running ? duration(p.eta_seconds) : '–'),
  el('td', { class: 'num' }, p.sim_time !== undefined ? si(p.sim_time, 's') : '–'),
  el('td', {}, date(j.created_at)),
  el('td', { class: 'actions' }, actions));
}

async function act(j, what) {
  if (what === 'delete' && !confirm(`Delete job ${j.name || j.id} and its result files?`)) return;
  try {
    if (what === 'cancel') {
      const r = await api(jobPath(j.id, '/cancel'), { method: 'POST' });
      if (r && r.id) state.jobs.set(j.id, notOlder(r));
    } else {
      await api(jobPath(j.id), { method: 'DELETE' });
      state.jobs.delete(j.id);
    }
  } catch (e) {
    showMessage(`${what} ${j.id}: ${e.message}`);
  }
  render();
  refresh();
}

function applyFilters() {
  const q = new URLSearchParams();
  const f = filters();
  if (f.status) q.set('status', f.status);
  if (f.tag) q.set('tag', f.tag);
  history.replaceState(null, '', q.toString() ? `?${q}` : location.pathname);
  state.jobs = new Map();
  state.loadedMore = false;
  refresh();
}

function init() {
  mountNav('jobs');
  const q = new URLSearchParams(location.search);
  statusSel.value = q.get('status') || '';
  tagInput.value = q.get('tag') || '';
  statusSel.addEventListener('change', applyFilters);
  tagInput.addEventListener('change', applyFilters);
  document.getElementById('filter-clear').addEventListener('click', () => {
    statusSel.value = '';
    tagInput.value = '';
    applyFilters();
  });
  more.addEventListener('click', loadMore);
  window.addEventListener('polydem-token', applyFilters);
  refresh();
  setInterval(() => document.hidden || refresh(), LIST_REFRESH_MS);
}

init();
