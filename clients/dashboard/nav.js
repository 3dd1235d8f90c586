// nav.js - the header every page shares: links, the server's health and device, and the token
// field (stored in localStorage, sent as "Authorization: Bearer").

import { api, getToken, setToken } from './api.js';
import { el } from './format.js';

export function mountNav(current) {
  const header = document.querySelector('header.top');
  const link = (href, text, id) =>
    el('a', { href, class: current === id ? 'current' : null }, text);
  const health = el('span', { class: 'health', title: 'server health' }, '…');
  const token = el('input', {
    type: 'password', id: 'token', placeholder: 'token', autocomplete: 'off', size: 18,
    title: 'bearer token for a daemon started with --tokens; kept in this browser',
  });
  token.value = getToken();
  const save = () => {
    if (token.value.trim() !== getToken()) setToken(token.value.trim());
  };
  token.addEventListener('change', save);
  token.addEventListener('keydown', (e) => e.key === 'Enter' && save());
  header.replaceChildren(
    el('a', { href: 'index.html', class: 'brand' }, 'polydem'),
    el('nav', {}, link('index.html', 'Jobs', 'jobs'), link('submit.html', 'Submit', 'submit')),
    el('span', { class: 'spacer' }),
    health,
    el('label', { class: 'token' }, 'Token ', token),
  );
  checkHealth(health);
}

async function checkHealth(span) {
  try {
    await api('/healthz', { timeout: 5000 });
    span.className = 'health ok';
    span.textContent = 'server ok';
  } catch (e) {
    span.className = 'health bad';
    span.textContent = e.status ? `server unhealthy (${e.status})` : 'server unreachable';
    span.title = e.message;
    return;
  }
  try {
    const d = await api('/v1/device', { timeout: 5000 });
    if (d && d.name) span.textContent = `server ok · ${d.name}`;
  } catch {
    /* the device line is optional (a token may be needed) */
  }
}

// A message box at the top of main: showMessage('text', 'error'|'info'); '' hides it.
export function showMessage(text, kind = 'error') {
  let box = document.getElementById('message');
  if (!box) {
    box = el('div', { id: 'message', role: 'alert' });
    document.querySelector('main').prepend(box);
  }
  box.className = text ? `message ${kind}` : 'message hidden';
  box.textContent = text;
}
