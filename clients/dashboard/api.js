// api.js - talking to polydemd: the bearer token (kept in localStorage), JSON requests with
// timeouts and the daemon's error format, job event streams (SSE with a polling fallback), and
// the normalisation of /stats, frames and shapes into typed arrays.

const TOKEN_KEY = 'polydem.token';
export const FINISHED = ['succeeded', 'failed', 'cancelled'];

export function getToken() {
  try {
    return localStorage.getItem(TOKEN_KEY) || '';
  } catch {
    return '';
  }
}

export function setToken(token) {
  if (token) localStorage.setItem(TOKEN_KEY, token);
  else localStorage.removeItem(TOKEN_KEY);
  window.dispatchEvent(new Event('polydem-token'));
}

// An error answer ({"error": {"code", "message", "details": [{"path", "message"}]}}), or no
// answer at all (status 0).
export class ApiError extends Error {
  constructor(status, message, details = [], code = '') {
    super(message);
    this.status = status;
    this.details = details;
    this.code = code;
  }
  toString() {
    return this.status ? `HTTP ${this.status}: ${this.message}` : this.message;
  }
}

// A URL that carries the token as ?token= (EventSource and download links cannot send headers).
export function tokenUrl(path) {
  const t = getToken();
  if (!t) return path;
  return path + (path.includes('?') ? '&' : '?') + 'token=' + encodeURIComponent(t);
}

export function jobPath(id, rest = '') {
  return '/v1/jobs/' + encodeURIComponent(id) + rest;
}

// fetch with the token, a timeout and JSON both ways. Returns the decoded answer (null when
// empty); throws ApiError.
export async function api(path, { method = 'GET', body, headers = {}, timeout = 30000 } = {}) {
  const h = { ...headers };
  const t = getToken();
  if (t) h.Authorization = 'Bearer ' + t;
  if (body !== undefined && typeof body !== 'string') {
    body = JSON.stringify(body);
    h['Content-Type'] = 'application/json';
  } else if (body !== undefined) {
    h['Content-Type'] = 'application/json';
  }
  const ctl = new AbortController();
  const timer = setTimeout(() => ctl.abort(), timeout);
  let r;
  try {
    r = await fetch(path, { method, body, headers: h, signal: ctl.signal });
  } catch (e) {
    const why = e.name === 'AbortError' ? `no answer within ${timeout / 1000} s` : e.message;
    throw new ApiError(0, `${method} ${path}: ${why}`);
  } finally {
    clearTimeout(timer);
  }
  const text = await r.text();
  let data = null;
  if (text.trim()) {
    try {
      data = JSON.parse(text);
    } catch {
      if (r.ok) throw new ApiError(r.status, `${method} ${path}: the answer is not JSON`);
    }
  }
  if (!r.ok) {
    const e = data && data.error;
    if (r.status === 401) {
      const said = e && e.message ? ` (the server says: ${e.message})` : '';
      throw new ApiError(401, (t ? 'the server refused the token in the Token field at the top right'
        : 'the server wants a token: enter it in the Token field at the top right') + said);
    }
    if (e && typeof e === 'object') {
      throw new ApiError(r.status, e.message || r.statusText, e.details || [], e.code || '');
    }
    throw new ApiError(r.status, (text.trim() || r.statusText).slice(0, 300));
  }
  return data;
}

// GET /v1/jobs answers {"jobs": [...], ...} (or a bare array).
export function jobList(answer) {
  if (Array.isArray(answer)) return { jobs: answer, next: null };
  const jobs = (answer && (answer.jobs || answer.items)) || [];
  let next = answer && (answer.next || answer.next_after || null);
  if (!next && answer && answer.more && jobs.length) next = jobs[jobs.length - 1].id;
  return { jobs, next };
}

// Merges one SSE payload into a job: a whole job, {status, ...}, {progress: {...}} or a bare
// progress record are all accepted.
export function mergeJobEvent(job, data) {
  if (!data || typeof data !== 'object') return job;
  if (data.id && data.status) return { ...job, ...data };
  const out = { ...job };
  for (const k of ['status', 'error', 'started_at', 'finished_at']) if (k in data) out[k] = data[k];
  if (data.progress) out.progress = { ...(job.progress || {}), ...data.progress };
  else if ('fraction' in data || 'step' in data) out.progress = { ...(job.progress || {}), ...data };
  return out;
}

// Follows a job: onJob(job) on every change until it finishes. SSE where the daemon streams,
// else polling every 2 s. Returns {close()}.
export function watchJob(job, onJob) {
  let closed = false;
  let es = null;
  let poll = null;
  let cur = job;
  const emit = (j) => {
    cur = j;
    onJob(j);
    if (FINISHED.includes(j.status)) stop();
  };
  const stop = () => {
    closed = true;
    if (es) es.close();
    if (poll) clearTimeout(poll);
  };
  const startPolling = () => {
    if (closed || poll) return;
    const tick = async () => {
      try {
        emit(await api(jobPath(cur.id)));
      } catch {
        /* keep trying; the page shows the last known state */
      }
      if (!closed) poll = setTimeout(tick, 2000);
    };
    poll = setTimeout(tick, 0);
  };
  try {
    es = new EventSource(tokenUrl(jobPath(job.id, '/events')));
  } catch {
    startPolling();
    return { close: stop };
  }
  const onData = (ev) => {
    window.polydemEvents = (window.polydemEvents || 0) + 1; // diagnostics: events received
    let data;
    try {
      data = JSON.parse(ev.data);
    } catch {
      return;
    }
    emit(mergeJobEvent(cur, data));
  };
  for (const name of ['message', 'progress', 'status', 'job', 'end', 'done']) {
    es.addEventListener(name, onData);
  }
  es.onerror = () => {
    // The stream ended (job finished) or failed: one GET tells which; poll if it still runs.
    if (closed) return;
    es.close();
    es = null;
    startPolling();
  };
  return { close: stop };
}

// Numbers, or rows of numbers, as one flat Float64Array.
export function flat(a) {
  if (!a) return new Float64Array(0);
  if (a.length && Array.isArray(a[0])) {
    const w = a[0].length;
    const out = new Float64Array(a.length * w);
    a.forEach((row, i) => out.set(row, i * w));
    return out;
  }
  return Float64Array.from(a);
}

// /stats as columns: {time, kinetic_energy, contacts, walls: {name: |F| per row}}. The daemon
// answers columns ({"time": [...], "wall_force": {"floor": [[fx, fy, fz], ...]}}); rows are
// accepted too.
export function normalizeStats(s) {
  if (s && s.stats) s = s.stats;
  if (Array.isArray(s)) {
    const cols = { time: [], kinetic_energy: [], contacts: [], wall_force: {} };
    for (const r of s) {
      cols.time.push(r.time);
      cols.kinetic_energy.push(r.kinetic_energy);
      cols.contacts.push(r.contacts);
      for (const [w, f] of Object.entries(r.wall_force || {})) (cols.wall_force[w] ||= []).push(f);
    }
    s = cols;
  }
  s = s || {};
  const walls = {};
  for (const [name, series] of Object.entries(s.wall_force || {})) {
    const v = flat(series);
    const m = new Float64Array(v.length / 3);
    for (let i = 0; i < m.length; i++) m[i] = Math.hypot(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    walls[name] = m;
  }
  // /stats/stage_time: seconds per stage of the step ending at each row (finished jobs only)
  const stages = {};
  for (const [name, series] of Object.entries(s.stage_time || {})) stages[name] = flat(series);
  return {
    time: flat(s.time),
    kinetic_energy: flat(s.kinetic_energy),
    contacts: flat(s.contacts),
    walls,
    stages,
  };
}
