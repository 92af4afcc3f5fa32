// The controller page: polls /api/status, refreshes /api/preview.png, turns drags, wheel and
// pinches into POST /api/camera, the controls into POST /api/settings, /api/time, /api/capture,
// /api/stop.
// Plain JavaScript, no library: served by dfbwall itself, with no network beyond it.
'use strict';

// The page authenticates with the cookie the server set when it was opened at the address
// dfbwall printed (…/?token=…, then redirected here): no URL of the page carries the token.
const $ = (id) => document.getElementById(id);

function showError(text) {
  const box = $('error');
  box.textContent = text;
  box.hidden = !text;
}

// Errors in plain words: what went wrong and what to do.
async function explain(response) {
  let message = '';
  try {
    const body = await response.text();
    try { message = JSON.parse(body).error || body; } catch (e) { message = body; }
  } catch (e) { /* no body */ }
  if (response.status === 401)
    return 'The wall refused the request: it needs the access token. Open this page with the ' +
           'address dfbwall printed at start (it ends in ?token=…).';
  if (response.status === 403) return 'The wall refused the request: ' + message;
  if (response.status === 400) return 'The wall did not accept that: ' + message;
  return 'The wall answered ' + response.status + ': ' + message;
}

async function api(method, path, body) {
  // Changes go as JSON: the server takes a change by cookie only as application/json.
  const headers = {};
  if (body !== undefined) headers['Content-Type'] = 'application/json';
  let response;
  try {
    response = await fetch(path, {
      method, headers, body: body === undefined ? undefined : JSON.stringify(body),
      cache: 'no-store', credentials: 'same-origin'
    });
  } catch (e) {
    throw new Error('Cannot reach the wall (the job may have ended, or the tunnel is down).');
  }
  if (!response.ok) throw new Error(await explain(response));
  const text = await response.text();
  return text ? JSON.parse(text) : {};
}

// --- status -------------------------------------------------------------------------------
let renderer = '';
let stopped = false;
let settingsShown = false;
let contactLost = false;  // the sliders start where the wall is, then follow the user

function setState(text, cls) {
  const s = $('state');
  s.textContent = text;
  s.className = 'state ' + (cls || '');
}

function showStatus(s) {
  $('frame').textContent = s.frame;
  $('fps').textContent = typeof s.fps === 'number' ? s.fps.toFixed(1) : '–';
  $('spp').textContent = s.spp;
  $('renderer').textContent = s.renderer || '–';
  if (s.renderer !== renderer) {
    renderer = s.renderer;
    $('scivis-controls').hidden = renderer !== 'scivis';
  }
  const rows = (s.displays || []).map((d) => {
    const tr = document.createElement('tr');
    const name = document.createElement('td');
    const presented = document.createElement('td');
    const state = document.createElement('td');
    name.textContent = d.name;
    presented.textContent = d.presented;
    state.textContent = d.state || 'presenting';
    if (d.state === 'lost') tr.className = 'lost';
    tr.append(name, presented, state);
    return tr;
  });
  $('displays').tBodies[0].replaceChildren(...rows);
  // A display whose wall process the wall lost is marked on the preview too.
  const lost = new Set(s.lost_displays || []);
  for (const box of $('outlines').children)
    box.classList.toggle('lost', lost.has(box.dataset.name));
  if (!settingsShown && s.settings) {
    settingsShown = true;
    showSettings(s.settings);
  }
  showTime(s.time);
  const errors = s.errors || [];
  if (errors.length) showError('The wall reports: ' + errors.join('; '));
  setState(s.stopping ? 'stopping' : s.idle ? 'converged, idle' : 'running', 'ok');
}

async function pollStatus() {
  try {
    const s = await api('GET', '/api/status');
    if (contactLost) showError('');  // back in contact: the old message no longer holds
    contactLost = false;
    showStatus(s);
  } catch (e) {
    setState(stopped ? 'stopped' : 'no contact', 'bad');
    if (!stopped) showError(e.message);
    contactLost = true;
  }
  setTimeout(pollStatus, 500);
}

// --- preview and display outlines ----------------------------------------------------------
const img = $('preview');
let previewCount = 0;

function nextPreview() {
  if (stopped) return;
  img.src = '/api/preview.png?n=' + (++previewCount);
}
let previewSize = '';
img.addEventListener('load', () => {
  // A service wall moved or resized the job's window: the outlines are the new window's.
  const size = img.naturalWidth + 'x' + img.naturalHeight;
  if (previewSize && size !== previewSize) drawOutlines();
  previewSize = size;
  setTimeout(nextPreview, 200);
});
img.addEventListener('error', () => setTimeout(nextPreview, 1000));

async function drawOutlines() {
  let layout;
  try {
    layout = await api('GET', '/api/layout');
  } catch (e) {
    setTimeout(drawOutlines, 2000);
    return;
  }
  const [w, h] = layout.canvas;
  const boxes = layout.displays.map((d) => {
    const [x0, y0, x1, y1] = d.rect;
    const box = document.createElement('div');
    box.className = 'display';
    box.dataset.name = d.name;
    box.style.left = (100 * x0 / w) + '%';
    box.style.top = (100 * y0 / h) + '%';
    box.style.width = (100 * (x1 - x0) / w) + '%';
    box.style.height = (100 * (y1 - y0) / h) + '%';
    const label = document.createElement('span');
    label.textContent = d.name;
    box.append(label);
    return box;
  });
  $('outlines').replaceChildren(...boxes);
}

// --- camera: one request in flight, movements in between add up -----------------------------
const pending = { orbit: 0, pan: [0, 0], dolly: 1 };
let sending = false;

function queueCamera(change) {
  if (change.orbit) pending.orbit += change.orbit;
  if (change.pan) { pending.pan[0] += change.pan[0]; pending.pan[1] += change.pan[1]; }
  if (change.dolly) pending.dolly *= change.dolly;
  flushCamera();
}

async function flushCamera() {
  if (sending) return;
  const requests = [];
  // Within the API's ranges (orbit ±360°, pan ±10 view heights, dolly 0.01..100).
  const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
  if (pending.orbit) requests.push({ orbit: clamp(pending.orbit, -360, 360) });
  if (pending.pan[0] || pending.pan[1])
    requests.push({ pan: pending.pan.map((v) => clamp(v, -10, 10)) });
  if (pending.dolly !== 1) requests.push({ dolly: clamp(pending.dolly, 0.01, 100) });
  if (!requests.length) return;
  pending.orbit = 0; pending.pan = [0, 0]; pending.dolly = 1;
  sending = true;
  try {
    for (const r of requests) await api('POST', '/api/camera', r);
    showError('');
  } catch (e) {
    showError(e.message);
  }
  sending = false;
  flushCamera();
}

// Pointer events cover mouse, pen and touch. One pointer drags (orbit, or pan with Shift);
// two pointers pan by their midpoint and dolly by their spread.
const stage = $('stage');
const pointers = new Map();
let lastMid = null, lastSpread = null;

function midAndSpread() {
  const p = [...pointers.values()];
  const mid = [(p[0].x + p[1].x) / 2, (p[0].y + p[1].y) / 2];
  return [mid, Math.hypot(p[0].x - p[1].x, p[0].y - p[1].y)];
}

stage.addEventListener('pointerdown', (e) => {
  stage.setPointerCapture(e.pointerId);
  pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
  stage.classList.add('dragging');
  if (pointers.size === 2) [lastMid, lastSpread] = midAndSpread();
  e.preventDefault();
});

stage.addEventListener('pointermove', (e) => {
  const p = pointers.get(e.pointerId);
  if (!p) return;
  const dx = e.clientX - p.x, dy = e.clientY - p.y;
  p.x = e.clientX; p.y = e.clientY;
  const width = stage.clientWidth || 1, height = stage.clientHeight || 1;
  if (pointers.size === 1) {
    // Pan is in view heights, camera right and up: the scene follows the finger.
    if (e.shiftKey) queueCamera({ pan: [-dx / height, dy / height] });
    else queueCamera({ orbit: -dx * 180 / width });
  } else if (pointers.size === 2) {
    const [mid, spread] = midAndSpread();
    queueCamera({ pan: [-(mid[0] - lastMid[0]) / height, (mid[1] - lastMid[1]) / height] });
    // Fingers apart: closer (dolly divides the distance to the look-at point).
    if (lastSpread > 0 && spread > 0) queueCamera({ dolly: spread / lastSpread });
    lastMid = mid; lastSpread = spread;
  }
});

function release(e) {
  pointers.delete(e.pointerId);
  if (pointers.size < 2) lastMid = lastSpread = null;
  if (!pointers.size) stage.classList.remove('dragging');
}
stage.addEventListener('pointerup', release);
stage.addEventListener('pointercancel', release);

stage.addEventListener('wheel', (e) => {
  e.preventDefault();
  const lines = e.deltaMode === 1 ? 20 : e.deltaMode === 2 ? 400 : 1;
  queueCamera({ dolly: Math.exp(-e.deltaY * lines * 0.0015) });  // wheel up: closer
}, { passive: false });

// --- settings, capture, stop ---------------------------------------------------------------
function debounce(fn, ms) {
  let timer = null;
  return (...args) => { clearTimeout(timer); timer = setTimeout(() => fn(...args), ms); };
}

async function postSettings(settings) {
  try {
    await api('POST', '/api/settings', settings);
    showError('');
  } catch (e) {
    showError(e.message);
  }
}
const sendSettings = debounce(postSettings, 150);

$('exposure').addEventListener('input', () => {
  const exposure = Math.pow(2, Number($('exposure').value));
  $('exposure-value').textContent = exposure.toFixed(2);
  sendSettings({ exposure });
});
$('spp-per-frame').addEventListener('input', () => {
  const spp = Number($('spp-per-frame').value);
  $('spp-value').textContent = spp;
  sendSettings({ spp });
});
$('opacity-scale').addEventListener('input', () => {
  const scale = Number($('opacity-scale').value);
  $('opacity-value').textContent = scale.toFixed(2);
  sendSettings({ opacity_scale: scale });
});
$('transfer-function').addEventListener('change', () =>
  postSettings({ transfer_function: $('transfer-function').value }));

$('capture').addEventListener('click', async () => {
  try {
    await api('POST', '/api/capture', {});
    showError('');
    setState('capture asked for', 'ok');
  } catch (e) {
    showError(e.message);
  }
});

$('stop').addEventListener('click', async () => {
  if (!confirm('Stop the wall? The job writes its statistics and captures, then ends.')) return;
  try {
    await api('POST', '/api/stop', {});
    stopped = true;
    setState('stopping', 'bad');
  } catch (e) {
    showError(e.message);
  }
});

// --- a time series: play, pause, step, seek -------------------------------------------------
let playing = false;
let seeking = false;  // the slider is held: the status does not move it meanwhile
function showTime(t) {
  $('time-controls').hidden = !t;
  if (!t) return;
  playing = t.playing;
  $('play').textContent = playing ? 'Pause' : 'Play';
  $('step-value').textContent = (t.step + 1) + ' / ' + t.steps;
  $('seek').max = t.steps - 1;
  if (!seeking) $('seek').value = t.step;
}
async function postTime(body) {
  try {
    await api('POST', '/api/time', body);
    showError('');
  } catch (e) {
    showError(e.message);
  }
}
$('play').addEventListener('click', () => postTime({ play: !playing }));
$('step-back').addEventListener('click', () => postTime({ step: -1 }));
$('step-on').addEventListener('click', () => postTime({ step: 1 }));
const sendSeek = debounce((step) => postTime({ seek: step }), 150);
$('seek').addEventListener('input', () => {
  seeking = true;
  sendSeek(Number($('seek').value));
});
$('seek').addEventListener('change', () => { seeking = false; });

// The sliders start where the wall is (the settings in the first status).
function showSettings(s) {
  if (typeof s.exposure === 'number') {
    $('exposure').value = Math.log2(s.exposure);
    $('exposure-value').textContent = s.exposure.toFixed(2);
  }
  if (typeof s.spp === 'number') {
    $('spp-per-frame').value = s.spp;
    $('spp-value').textContent = s.spp;
  }
  if (s.transfer_function) $('transfer-function').value = s.transfer_function;
  if (typeof s.opacity_scale === 'number') {
    $('opacity-scale').value = s.opacity_scale;
    $('opacity-value').textContent = s.opacity_scale.toFixed(2);
  }
}

drawOutlines();
pollStatus();
nextPreview();
