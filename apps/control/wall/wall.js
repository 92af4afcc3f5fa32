// The wall's page (serve --control): the wall to scale, each job's window on it with a live
// thumbnail of what it shows; a click raises a window, × closes it (its job ends), dragging its
// title bar moves it, its corner resizes it. Polls /api/windows and, once a second, each
// window's thumbnail; plain JavaScript, no library, nothing fetched from elsewhere.
'use strict';

// The page authenticates with the cookie set when it was opened at the printed address
// (…/?token=…, then redirected here): no URL of the page carries the token.
const $ = (id) => document.getElementById(id);

function showError(text) {
  $('error').textContent = text;
  $('error').hidden = !text;
}

function setState(text, cls) {
  $('state').textContent = text;
  $('state').className = 'state ' + (cls || '');
}

async function explain(response) {
  let message = '';
  try {
    const body = await response.text();
    try { message = JSON.parse(body).error || body; } catch (e) { message = body; }
  } catch (e) { /* no body */ }
  if (response.status === 401)
    return 'The wall refused the request: it needs the access token. Open this page with the ' +
           'address dfbwall serve printed at start (it ends in ?token=…).';
  if (response.status === 404) return 'That window is gone: ' + message;
  return 'The wall answered ' + response.status + ': ' + message;
}

async function api(method, path, body) {
  // Changes go as JSON from this page: the server takes a change by cookie only so.
  const headers = {};
  if (method !== 'GET') headers['Content-Type'] = 'application/json';
  let response;
  try {
    response = await fetch(path, {
      method, headers, body: body === undefined ? undefined : JSON.stringify(body),
      cache: 'no-store', credentials: 'same-origin'
    });
  } catch (e) {
    throw new Error('Cannot reach the wall (serve stopped, or the tunnel is down).');
  }
  if (!response.ok) {
    const error = new Error(await explain(response));
    error.status = response.status;
    throw error;
  }
  const text = await response.text();
  return text ? JSON.parse(text) : {};
}

// --- the wall ------------------------------------------------------------------------------
let wall = null;  // GET /api/wall
const boxes = new Map();  // window id -> its element
let dragging = null;
// Moves the wall took but does not list yet (a window changes place at its job's switch
// frame): id -> {rect, until}; the window is drawn there meanwhile, not back at the old place.
const moving = new Map();
const kMinSide = 16;  // the wall refuses smaller windows

function place(element, r) {
  const { w, h } = wall.canvas;
  element.style.left = (100 * r.x / w) + '%';
  element.style.top = (100 * r.y / h) + '%';
  element.style.width = (100 * r.w / w) + '%';
  element.style.height = (100 * r.h / h) + '%';
}

function drawWall() {
  const { w, h } = wall.canvas;
  $('wall').style.aspectRatio = w + ' / ' + h;
  $('displays').replaceChildren(...wall.displays.map((d) => {
    const box = document.createElement('div');
    box.className = 'display';
    place(box, d.rect);
    const name = document.createElement('span');
    name.textContent = d.name;
    box.append(name);
    return box;
  }));
  const facts = [['Canvas', w + ' × ' + h], ['Displays', wall.displays.length],
                 ['Background', wall.background], ['Jobs at once', wall.max_jobs]];
  $('facts').replaceChildren(...facts.flatMap(([k, v]) => {
    const dt = document.createElement('dt');
    const dd = document.createElement('dd');
    dt.textContent = k;
    dd.textContent = v;
    return [dt, dd];
  }));
}

function windowBox(id) {
  const box = document.createElement('div');
  box.className = 'window';
  box.dataset.id = id;
  const bar = document.createElement('div');
  bar.className = 'bar';
  const title = document.createElement('span');
  title.className = 'title';
  const link = document.createElement('a');
  link.className = 'page';
  link.textContent = 'page';
  link.target = '_blank';
  link.rel = 'noopener noreferrer';
  link.hidden = true;
  const close = document.createElement('button');
  close.className = 'close';
  close.title = 'Close this window (its job ends)';
  close.textContent = '×';
  bar.append(title, link, close);
  const info = document.createElement('div');
  info.className = 'info';
  // What the window shows, refreshed once a second (refreshThumbnail); hidden until one came.
  const thumb = document.createElement('img');
  thumb.className = 'thumb';
  thumb.alt = '';
  thumb.hidden = true;
  thumb.addEventListener('load', () => { thumb.hidden = false; });
  thumb.addEventListener('error', () => { thumb.hidden = true; });  // none yet (503), or gone
  const corner = document.createElement('div');
  corner.className = 'resize';
  corner.title = 'Drag to resize this window (its job renders at the new size)';
  box.append(thumb, bar, info, corner);
  close.addEventListener('click', (e) => { e.stopPropagation(); closeWindow(id); });
  link.addEventListener('click', (e) => e.stopPropagation());
  bar.addEventListener('pointerdown', (e) => startDrag(e, id, box, 'move'));
  corner.addEventListener('pointerdown', (e) => startDrag(e, id, box, 'resize'));
  box.addEventListener('click', () => raiseWindow(id));
  return box;
}

// A fresh address each time: replies are never cached (Cache-Control: no-store).
const kThumbnailEveryMs = 1000;
let thumbnailLoads = 0;
function refreshThumbnail(box, id) {
  const now = Date.now();
  if (now - Number(box.dataset.thumbAt || 0) < kThumbnailEveryMs) return;
  box.dataset.thumbAt = String(now);
  box.querySelector('.thumb').src =
      '/api/windows/' + encodeURIComponent(id) + '/thumbnail?n=' + (++thumbnailLoads);
}

function showWindows(list) {
  const seen = new Set();
  const top = list.reduce((m, w) => Math.max(m, w.z), -1);
  for (const w of list) {
    seen.add(w.id);
    let box = boxes.get(w.id);
    if (!box) {
      box = windowBox(w.id);
      boxes.set(w.id, box);
      $('windows').append(box);
    }
    box.style.zIndex = String(1 + w.z);
    box.classList.toggle('top', w.z === top);
    box.classList.toggle('ending', w.state === 'ending');
    box.dataset.z = String(w.z);
    box.dataset.state = w.state;
    if (w.state !== 'starting') refreshThumbnail(box, w.id);
    box.querySelector('.title').textContent = w.id + ' · ' + (w.job || 'job') + ' · ' + w.host;
    box.querySelector('.info').textContent =
      w.state + ' · ' + w.fps.toFixed(1) + ' frames/s · frame ' + w.frames;
    const link = box.querySelector('.page');
    // Only the server's checked http(s) address, never another scheme.
    link.hidden = !(typeof w.page === 'string' && /^https?:\/\//.test(w.page));
    if (!link.hidden) link.href = w.page;
    const asked = moving.get(w.id);
    const same = (a, b) => a.x === b.x && a.y === b.y && a.w === b.w && a.h === b.h;
    if (asked && (same(asked.rect, w.rect) || Date.now() > asked.until)) moving.delete(w.id);
    const rect = moving.has(w.id) ? moving.get(w.id).rect : w.rect;
    box.classList.toggle('moving', moving.has(w.id));
    if (!dragging || dragging.id !== w.id) {
      place(box, rect);
      box.dataset.rect = [rect.x, rect.y, rect.w, rect.h].join(',');
    }
  }
  for (const [id, box] of boxes) {
    if (!seen.has(id)) {
      box.remove();
      boxes.delete(id);
    }
  }
  $('list').replaceChildren(...list.map((w) => {
    const tr = document.createElement('tr');
    for (const v of [w.id, w.job || '–', w.host, w.state, w.fps.toFixed(1), w.z]) {
      const td = document.createElement('td');
      td.textContent = v;
      tr.append(td);
    }
    return tr;
  }));
  $('none').hidden = list.length > 0;
}

// --- changes -------------------------------------------------------------------------------
async function raiseWindow(id) {
  try {
    await api('POST', '/api/windows/' + encodeURIComponent(id), { raise: true });
    showError('');
    await poll();
  } catch (e) {
    showError(e.message);
  }
}

async function closeWindow(id) {
  try {
    await api('DELETE', '/api/windows/' + encodeURIComponent(id));
    showError('');
    await poll();
  } catch (e) {
    showError(e.message);
  }
}

function startDrag(e, id, box, mode) {
  if (e.button !== 0 || e.target.closest('button, a')) return;
  e.stopPropagation();  // the corner is inside the box: one drag, not two
  const r = box.dataset.rect.split(',').map(Number);
  dragging = { id, box, mode, x0: e.clientX, y0: e.clientY, rect: r, moved: false };
  box.setPointerCapture(e.pointerId);
  box.classList.add('dragging');
  e.preventDefault();
}

function dragTo(e) {
  if (!dragging) return;
  const scale = wall.canvas.w / $('wall').clientWidth;  // canvas pixels per page pixel
  const dx = Math.round((e.clientX - dragging.x0) * scale);
  const dy = Math.round((e.clientY - dragging.y0) * scale);
  if (Math.abs(e.clientX - dragging.x0) + Math.abs(e.clientY - dragging.y0) > 3) dragging.moved = true;
  const [x, y, w, h] = dragging.rect;
  if (dragging.mode === 'resize') {
    dragging.to = {
      x, y, w: Math.max(kMinSide, Math.min(wall.canvas.w - x, w + dx)),
      h: Math.max(kMinSide, Math.min(wall.canvas.h - y, h + dy))
    };
  } else {
    dragging.to = {
      x: Math.max(0, Math.min(wall.canvas.w - w, x + dx)),
      y: Math.max(0, Math.min(wall.canvas.h - h, y + dy)), w, h
    };
  }
  place(dragging.box, dragging.to);
}

async function endDrag() {
  if (!dragging) return;
  const d = dragging;
  d.box.classList.remove('dragging');
  if (!d.moved || !d.to) {
    dragging = null;
    return;  // a click: the box's click handler raises it
  }
  // The click that ends a drag is not a raise.
  d.box.addEventListener('click', (e) => e.stopImmediatePropagation(), { capture: true, once: true });
  try {
    const answer = await api('POST', '/api/windows/' + encodeURIComponent(d.id), d.to);
    // Drawn where the wall put it until the wall lists it there (or 10 s pass: it did not).
    moving.set(d.id, { rect: answer.rect, until: Date.now() + 10000 });
    showError('');
  } catch (e) {
    // Refused (409: its job cannot move now or at all; 400: not a window the wall can show):
    // said in words, and the window goes back where the wall has it.
    showError(e.status === 409 || e.status === 400
                  ? 'The wall did not move window ' + d.id + ': ' + e.message.replace(/^The wall answered \d+: (window \S+: )?/, '')
                  : e.message);
  }
  dragging = null;
  await poll();
}

// --- polling -------------------------------------------------------------------------------
async function poll() {
  try {
    if (!wall) {
      wall = await api('GET', '/api/wall');
      drawWall();
    }
    const list = await api('GET', '/api/windows');
    showWindows(list);
    setState(list.length + (list.length === 1 ? ' job' : ' jobs') + ' on the wall', 'ok');
  } catch (e) {
    setState('no contact', 'bad');
    showError(e.message);
  }
}

document.addEventListener('pointermove', dragTo);
document.addEventListener('pointerup', endDrag);
document.addEventListener('pointercancel', endDrag);
poll();
setInterval(() => { if (!dragging) poll(); }, 500);
