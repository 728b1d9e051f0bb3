// smc-dashboard page: a cell view (every mill at a glance, all jobs) and a
// mill view (live F_Y chart with marks, raw forces, the supervisor's Grafcet
// with its active steps and modules, jobs, chatter events, operator
// controls). Data: GET /api/... once, then the Server-Sent Events stream
// /api/stream. See dashboard/README.md for both.

import { ForceChart, LobeChart, PowerChart, RawChart, Sparkline, formatMachineTime } from './charts.js';
import { GrafcetView } from './grafcet.js';

const MODULES = {
  A: 'feedrate routine', B: 'operator input monitor', C: 'feed hold',
  D: 'operator chatter detector', E: 'automatic chatter detector', F: 'chatter suppressor',
  G: 'chatter suppression routine', H: 'parameter estimator', I: 'force signal processor',
  J: 'contact monitor', K: 'adaptive force controller', L: 'model-based force controller',
  M: 'spindle power monitor', N: 'tool-breakage detector', O: 'spindle-speed chatter suppressor',
};
const HISTORY_S = 120;        // kept per mill in the browser
const MAX_POINTS = 4000;      // per mill, trimmed in chunks
const RENDER_INTERVAL_MS = 100;

// ------------------------------------------------------------------ state --

const store = {
  mills: new Map(),
  jobs: new Map(),
  catalog: null,  // the cell's CatalogView (GET /api/catalog, 'catalog' events)
  commands: [],
  session: { operator: null, can_command: false, commands_enabled: false },
  stream: { connected: false, dropped: 0, events: 0 },
  focus: null,  // machine id of the mill view, null for the cell view
};

// Arrival latency of force summaries: browser clock at arrival minus the
// DDS source timestamp of the sample (the edge's wall clock when it wrote it).
const latency = { n: 0, ring: new Float64Array(20000) };
window.smcStats = {
  summaries: () => latency.n,
  latencies: () => Array.from(latency.ring.subarray(0, Math.min(latency.n, latency.ring.length))),
  reset: () => { latency.n = 0; },
};

function newMill(id) {
  return {
    id, online: false, status: null, summary: null, situation: null, config: null, program: null,
    jobId: null, chatterCount: 0,
    hist: { t: [], fy: [], fref: [], feed: [], power: [], pass: [], count: [] },
    situations: [], chatter: [], batches: [],
  };
}

function mill(id) {
  let m = store.mills.get(id);
  if (!m) {
    m = newMill(id);
    store.mills.set(id, m);
    rebuildNav();
  }
  return m;
}

function applyMillState(s) {
  const m = mill(s.machine_id);
  m.online = s.online;
  m.status = s.status;
  m.summary = s.summary;
  m.situation = s.situation;
  m.config = s.config;
  m.program = s.program ? s.program.program : null;
  m.chatterCount = s.chatter_events;
  if (s.job) {
    m.jobId = s.job.job_id;
    store.jobs.set(s.job.job_id, s.job);
    if (s.job.progress) noteBreakage(m, s.job.progress);
  }
  if (s.summary) appendPoint(m, s.summary);
  if (s.situation) appendSituation(m, s.situation);
}

function appendPoint(m, s) {
  const h = m.hist;
  const n = h.t.length;
  if (n > 0 && s.t <= h.t[n - 1]) return;  // already have it (replayed by hello)
  if (n > 0 && s.t - h.t[n - 1] > 1.0) {  // a gap in the data: break the lines there
    h.t.push((s.t + h.t[n - 1]) / 2);
    for (const k of ['fy', 'fref', 'feed', 'power']) h[k].push(null);
    h.pass.push(h.pass[n - 1]);
    h.count.push(h.count[n - 1]);
  }
  h.t.push(s.t);
  h.fy.push(s.f_y_peak_n);
  h.fref.push(s.f_ref_n > 0 ? s.f_ref_n : null);
  h.feed.push(s.feedrate_mm_s);
  h.power.push(s.spindle_power_w);
  h.pass.push(s.pass_index);
  h.count.push(s.pass_count);
  if (h.t.length > MAX_POINTS) {
    const cut = h.t.length - MAX_POINTS * 0.8;
    for (const k of Object.keys(h)) h[k].splice(0, cut);
  }
}

function appendSituation(m, s) {
  const last = m.situations[m.situations.length - 1];
  if (last && s.t <= last.t) return;
  m.situations.push({ t: s.t, modules_mask: s.modules_mask, step_indices: s.step_indices });
  if (m.situations.length > 2000) m.situations.splice(0, 500);
}

// Module N's stop fails the mill's job with the reason ("tool breakage
// ..."): shown until the mill runs another job.
function noteBreakage(m, p) {
  if (p.phase === 'JOB_FAILED' && (p.message ?? '').startsWith('tool breakage')) {
    m.breakage = { t: p.t, message: p.message, job_id: p.job_id };
  } else if (p.phase === 'JOB_RUNNING' && m.breakage && m.breakage.job_id !== p.job_id) {
    m.breakage = null;
  }
}

function setJob(j) {
  const old = store.jobs.get(j.job_id);
  store.jobs.set(j.job_id, { ...old, ...j, progress: j.progress ?? old?.progress ?? null });
}

// -------------------------------------------------------------- the stream --

let source = null;
// Bumped by the events that change the tables (jobs, chatter, commands), so
// a view redraws those only when needed, not on every force sample.
let tablesVersion = 0;
const TABLE_EVENTS = new Set(['hello', 'job', 'progress', 'chatter', 'command', 'config', 'mill', 'catalog', 'status']);

function connect() {
  if (source) source.close();
  const params = new URLSearchParams();
  if (store.focus) {
    params.set('mill', store.focus);
    params.set('raw', '1');
  }
  source = new EventSource('/api/stream' + (store.focus ? '?' + params : ''));
  source.onopen = () => { store.stream.connected = true; scheduleRender(); };
  source.onerror = () => { store.stream.connected = false; scheduleRender(); };
  const on = (kind, fn) => source.addEventListener(kind, (e) => {
    store.stream.events++;
    fn(JSON.parse(e.data));
    if (TABLE_EVENTS.has(kind)) tablesVersion++;
    scheduleRender();
  });
  on('hello', (d) => {
    for (const s of d.cell.mills) applyMillState(s);
    for (const j of d.cell.jobs) setJob(j);
    store.commands = d.cell.commands.slice().reverse();
    fetch('/api/catalog').then((r) => r.json()).then((c) => {
      if (c.view) store.catalog = c.view;
      tablesVersion++;
      scheduleRender();
    }).catch(() => {});
    if (store.focus) {
      loadHistory(store.focus, HISTORY_S);
    } else {
      for (const id of store.mills.keys()) loadHistory(id, 40);  // the cards' traces
    }
  });
  on('summary', (s) => {
    const now = performance.timeOrigin + performance.now();
    latency.ring[latency.n % latency.ring.length] = now - s.src_unix_ms;
    latency.n++;
    const m = mill(s.machine_id);
    m.summary = s;
    appendPoint(m, s);
  });
  on('batch', (b) => {
    const m = mill(b.machine_id);
    m.batches.push(b);
    if (m.batches.length > 4) m.batches.shift();
  });
  on('situation', (s) => {
    const m = mill(s.machine_id);
    m.situation = s;
    appendSituation(m, s);
  });
  on('status', (s) => {
    const m = mill(s.machine_id);
    m.status = s;
    m.online = s.online;
  });
  on('chatter', (c) => {
    const m = mill(c.machine_id);
    m.chatter.push(c);
    m.chatterCount++;
  });
  on('progress', (p) => {
    const m = mill(p.machine_id);
    noteBreakage(m, p);
    m.jobId = p.job_id;
    const j = store.jobs.get(p.job_id) ?? { job_id: p.job_id, machine_id: p.machine_id, status: null };
    store.jobs.set(p.job_id, { ...j, progress: p });
  });
  on('job', setJob);
  on('config', (c) => { mill(c.machine_id).config = c; });
  on('program', (p) => { mill(p.machine_id).program = p.program; });
  on('command', (c) => { store.commands.unshift(c); store.commands.length = Math.min(store.commands.length, 50); });
  on('mill', (m) => { mill(m.machine_id); });
  on('catalog', (v) => { store.catalog = v; });
  on('dropped', (d) => { store.stream.dropped += d.dropped; });
}

// A null between two points more than a second apart, so lines do not
// bridge a time without data.
function breakGaps(h) {
  const out = { t: [], fy: [], fref: [], feed: [], power: [], pass: [], count: [] };
  for (let i = 0; i < h.t.length; i++) {
    if (i > 0 && h.t[i] - h.t[i - 1] > 1.0) {
      out.t.push((h.t[i] + h.t[i - 1]) / 2);
      out.fy.push(null); out.fref.push(null); out.feed.push(null); out.power.push(null);
      out.pass.push(h.pass[i - 1]); out.count.push(h.count[i - 1]);
    }
    for (const k of Object.keys(out)) out[k].push(h[k][i]);
  }
  return out;
}

async function loadHistory(id, seconds) {
  const r = await fetch(`/api/mills/${encodeURIComponent(id)}/history?seconds=${seconds}`);
  if (!r.ok) return;
  const h = await r.json();
  const m = mill(id);
  const live = m.hist;
  const firstLive = h.t.length ? h.t[h.t.length - 1] : -Infinity;
  const hist = { t: h.t, fy: h.f_y_peak_n, fref: h.f_ref_n.map((v) => (v > 0 ? v : null)),
    feed: h.feedrate_mm_s, power: h.spindle_power_w, pass: h.pass_index, count: h.pass_count };
  for (let i = 0; i < live.t.length; i++) {
    if (live.t[i] <= firstLive) continue;
    for (const k of Object.keys(hist)) hist[k].push(live[k][i]);
  }
  m.hist = breakGaps(hist);
  m.situations = h.situations.concat(m.situations.filter((s) => s.t > (h.situations.at(-1)?.t ?? -Infinity)));
  m.chatter = h.chatter_events;
  m.batches = h.batches.slice(-4);
  tablesVersion++;
  scheduleRender();
}

// --------------------------------------------------------------- sessions --

const TOKEN_KEY = 'smc-dashboard-token';

function token() { return sessionStorage.getItem(TOKEN_KEY); }

async function checkSession() {
  const headers = token() ? { Authorization: 'Bearer ' + token() } : {};
  const r = await fetch('/api/session', { headers });
  if (r.status === 401) {
    sessionStorage.removeItem(TOKEN_KEY);
    toast('That operator token was refused.', 'error');
    return checkSession();
  }
  store.session = await r.json();
  renderSession();
  scheduleRender();
}

async function sendCommand(action) {
  const id = store.focus;
  const r = await fetch(`/api/mills/${encodeURIComponent(id)}/commands`, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json', Authorization: 'Bearer ' + (token() ?? '') },
    body: JSON.stringify({ action }),
  });
  const body = await r.json().catch(() => ({}));
  if (r.status === 202) {
    toast(`${action.replaceAll('_', ' ')} sent to ${id} (command ${body.command_id}, operator ${body.operator})`, 'ok');
  } else {
    toast(`${action.replaceAll('_', ' ')} refused (${r.status}): ${body.error ?? r.statusText}`, 'error');
  }
}

// ---------------------------------------------------------------- helpers --

function h(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === false || v == null) continue;
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else if (k === 'dataset') Object.assign(e.dataset, v);
    else e.setAttribute(k, v === true ? '' : v);
  }
  for (const c of children.flat()) {
    if (c == null || c === false) continue;
    e.append(c instanceof Node ? c : String(c));
  }
  return e;
}

function toast(text, kind) {
  const t = h('div', { class: `toast ${kind}`, role: 'status' }, text);
  document.getElementById('toasts').append(t);
  setTimeout(() => t.remove(), 6000);
}

const fmt = (v, d = 0, unit = '') => (v == null || !isFinite(v) ? '-' : v.toFixed(d) + unit);
const variantName = (v) => ({ SMC_I: 'SMC I', SMC_II: 'SMC II', SMC_II_PLUS: 'SMC II+', SMC_NONE: 'no control' }[v] ?? '-');
const stateName = (s) => (s ? s.replace(/^EDGE_|^JOB_/, '').replace('_', ' ').toLowerCase() : 'unknown');

function edgeBadge(m) {
  if (!m.status) return h('span', { class: 'badge muted' }, 'no status');
  if (!m.online) return h('span', { class: 'badge offline' }, 'offline');
  const s = m.status.state;
  const cls = { EDGE_RUNNING: 'run', EDGE_FEED_HOLD: 'hold', EDGE_FAULT: 'fault' }[s] ?? 'idle';
  return h('span', { class: `badge ${cls}`, 'data-edge-state': s }, stateName(s));
}

function stepText(m) {
  const steps = m.situation?.active_steps;
  const g = m.config?.grafcet;
  if (!steps || !g?.ok) return '-';
  return steps.map((n) => `X${n} ${g.steps.find((s) => s.number === n)?.label ?? ''}`).join(', ');
}

function jobRank(j) {
  const s = j.status?.state ?? (j.progress?.phase === 'JOB_DONE' ? 'JOB_DONE' : 'JOB_RUNNING');
  return { JOB_RUNNING: 0, JOB_ASSIGNED: 1, JOB_PLANNED: 2, JOB_QUEUED: 3 }[s] ?? 4;
}

function jobsTable(jobs, showMill) {
  const rows = jobs.slice().sort((a, b) => jobRank(a) - jobRank(b) ||
    (jobRank(a) === 4 ? Number(b.status?.updated_unix_ms ?? 0) - Number(a.status?.updated_unix_ms ?? 0)
                      : a.job_id.localeCompare(b.job_id)));
  const body = rows.slice(0, 40).map((j) => {
    const st = j.status;
    const p = j.progress;
    const state = st?.state ?? p?.phase ?? 'JOB_RUNNING';
    const running = state === 'JOB_RUNNING';
    const frac = state === 'JOB_DONE' ? 1 : (running && p ? p.fraction_done : st?.fraction_done ?? 0);
    const passIndex = running && p ? p.pass_index : st?.pass_index ?? 0;
    const passCount = running && p ? p.pass_count : st?.pass_count ?? 0;
    const planned = st?.passes_planned ?? passCount;
    const chatter = Math.max(st?.chatter_events ?? 0, p?.chatter_events ?? 0);
    return h('tr', { dataset: { job: j.job_id } },
      h('td', {}, h('a', { class: 'strong job-link', href: `#/job/${encodeURIComponent(j.job_id)}`, title: 'the job\'s history' }, j.job_id),
        h('div', { class: 'muted small' }, st?.job?.part_id ?? '')),
      showMill && h('td', {}, j.machine_id || st?.machine_id || '-'),
      h('td', {}, h('span', { class: `badge job-${state.toLowerCase()}` }, stateName(state))),
      h('td', {}, h('span', { class: `badge variant ${st?.variant ?? ''}` }, variantName(st?.variant))),
      h('td', { class: 'num' }, state === 'JOB_DONE' ? `${passCount}` : `${Math.min(passIndex + 1, passCount)} / ${passCount}`,
        planned !== passCount ? h('div', { class: 'muted small' }, `planned ${planned}`) : null),
      h('td', {}, h('div', { class: 'progress', title: `${Math.round(frac * 100)} %` },
        h('div', { class: 'fill', style: `width:${(frac * 100).toFixed(1)}%` })),
        h('div', { class: 'muted small' }, `${Math.round(frac * 100)} %`)),
      h('td', { class: 'num' }, chatter || ''),
      h('td', { class: 'why', title: st?.explanation ?? '' }, h('div', { class: 'clamp' }, st?.explanation ?? '')));
  });
  return h('table', { class: 'jobs' },
    h('thead', {}, h('tr', {}, h('th', {}, 'job'), showMill && h('th', {}, 'mill'), h('th', {}, 'state'),
      h('th', {}, 'SMC'), h('th', {}, 'passes'), h('th', {}, 'progress'), h('th', {}, 'chatter'),
      h('th', {}, 'why this SMC'))),
    h('tbody', {}, body.length ? body : h('tr', {}, h('td', { colspan: 8, class: 'muted' }, 'No jobs yet.'))));
}

// ------------------------------------------------------------------ views --

let view = null;  // { kind, render(), destroy() }
let renderPending = false;

function scheduleRender() {
  if (renderPending) return;
  renderPending = true;
  setTimeout(() => requestAnimationFrame(() => {
    renderPending = false;
    renderHeader();
    view?.render();
  }), RENDER_INTERVAL_MS);
}

function rebuildNav() {
  const nav = document.getElementById('nav');
  nav.replaceChildren(
    h('a', { href: '#/', class: store.focus ? '' : 'current' }, 'Cell'),
    ...[...store.mills.keys()].sort().map((id) =>
      h('a', { href: `#/mill/${encodeURIComponent(id)}`, class: store.focus === id ? 'current' : '' }, id)));
}

function renderHeader() {
  const s = document.getElementById('stream-state');
  s.className = store.stream.connected ? 'live' : 'down';
  s.textContent = store.stream.connected ? 'live' : 'reconnecting';
  s.title = `${store.stream.events} events received; ${store.stream.dropped} dropped by the server for this page`;
  document.getElementById('dropped').textContent = store.stream.dropped ? `${store.stream.dropped} dropped` : '';
}

function renderSession() {
  const box = document.getElementById('session');
  const ses = store.session;
  if (!ses.commands_enabled) {
    box.replaceChildren(h('span', { class: 'muted' }, 'read-only dashboard'));
  } else if (ses.operator) {
    box.replaceChildren(h('span', {}, 'operator ', h('strong', { id: 'operator-name' }, ses.operator)),
      h('button', { class: 'link', onclick: () => { sessionStorage.removeItem(TOKEN_KEY); checkSession(); } }, 'sign out'));
  } else {
    const input = h('input', { type: 'password', id: 'token-input', placeholder: 'operator token', autocomplete: 'off', 'aria-label': 'operator token' });
    const form = h('form', { id: 'signin', onsubmit: (e) => {
      e.preventDefault();
      if (input.value.trim()) sessionStorage.setItem(TOKEN_KEY, input.value.trim());
      checkSession();
    } }, input, h('button', { type: 'submit' }, 'Sign in'));
    box.replaceChildren(h('span', { class: 'muted' }, 'read-only'), form);
  }
}

// A machine's wideband F_y channel, which module E reads: its record's
// (samples per 0.5 ms period), or the cell's default configuration's.
function wideband(w) {
  const n = w?.samples_per_tick ?? 0;
  if (!n) return h('span', { class: 'muted' }, "cell's default");
  return `${fmt(2 * n, 0)} kHz, order-${w.filter_order ?? 2} filter at ${fmt(w.cutoff_hz, 0)} Hz`;
}

// The cell's catalog, read-only (it changes through smc-cell catalog apply):
// machines with their live state, parts with the SMC a job would get and why.
function catalogTables() {
  const c = store.catalog;
  if (!c) return [h('p', { class: 'muted' }, 'No catalog from the cell yet.')];
  const cat = c.catalog ?? {};
  const machines = (cat.machines ?? []).map((m) => {
    const live = store.mills.get(m.id);
    // The cell's warnings on this machine's channel: a y mode of one of its
    // models' structures that the filter hides from E.
    const notes = (c.machine_notes ?? []).filter((n) => n.machine_id === m.id);
    return h('tr', {},
      h('td', { class: 'strong' }, m.id), h('td', {}, m.name),
      h('td', {}, `${fmt(m.max_spindle_power_w, 1)} W`), h('td', {}, `${fmt(m.max_feedrate_mm_s, 1)} mm/s`),
      h('td', {}, `${fmt(m.min_spindle_rpm, 0)}-${fmt(m.max_spindle_rpm, 0)} rpm`), h('td', {}, m.drive),
      h('td', {}, wideband(m.wideband), ...notes.map((n) => h('div', { class: 'channel-warning' },
        h('span', { class: 'badge warn' }, 'warning'), ` with model ${n.model_id}: ${n.text}`))),
      h('td', {}, live ? edgeBadge(live) : h('span', { class: 'muted' }, 'not seen')));
  });
  const models = new Map((cat.models ?? []).map((m) => [m.id, m]));
  const parts = (cat.parts ?? []).map((p) => {
    const choice = (c.parts ?? []).find((x) => x.part_id === p.id);
    const used = (choice?.model_ids ?? []).map((id) => {
      const m = models.get(id);
      return `${id}${m?.validated ? '' : ' (not validated)'}`;
    }).join(', ');
    return h('tr', {},
      h('td', { class: 'strong' }, p.id), h('td', {}, p.material_id), h('td', {}, p.tool_id),
      h('td', {}, `${fmt(p.total_depth_mm, 2)} mm, ${fmt(p.feedrate_mm_s, 1)} mm/s, ${fmt(p.spindle_rpm, 0)} rpm`),
      h('td', {}, h('span', { class: `badge variant ${choice?.variant ?? ''}` }, variantName(choice?.variant)),
        choice?.machine_id ? ` on ${choice.machine_id}` : ''),
      h('td', {}, used || h('span', { class: 'muted' }, 'none')),
      h('td', { class: 'why' }, choice?.explanation ?? ''));
  });
  const table = (head, rows, empty) => h('table', { class: 'catalog' },
    h('thead', {}, h('tr', {}, ...head.map((x) => h('th', {}, x)))),
    h('tbody', {}, rows.length ? rows : h('tr', {}, h('td', { colspan: head.length, class: 'muted' }, empty))));
  return [
    h('h3', {}, 'Machines'),
    table(['machine', 'name', 'power', 'feed', 'speed', 'drive', 'wideband F_y (E)', 'edge'], machines, 'No machines.'),
    h('h3', {}, 'Parts'),
    table(['part', 'material', 'tool', 'programmed cut', 'a job would get', 'models', 'why'], parts, 'No parts.'),
  ];
}

function cellView() {
  const cards = h('div', { class: 'cards' });
  const jobs = h('section', { class: 'panel' }, h('h2', {}, 'Jobs'), h('div', { id: 'jobs' }));
  const catalog = h('section', { class: 'panel' }, h('h2', {}, 'Catalog'), h('div', { id: 'catalog' }));
  const root = h('main', { id: 'cell-view' }, cards, jobs, catalog);
  const sparks = new Map();
  let drawnTables = -1;
  return {
    root,
    render() {
      for (const m of [...store.mills.values()].sort((a, b) => a.id.localeCompare(b.id))) {
        let card = cards.querySelector(`[data-mill="${CSS.escape(m.id)}"]`);
        if (!card) {
          card = h('a', { class: 'card mill-card', href: `#/mill/${encodeURIComponent(m.id)}`, dataset: { mill: m.id } },
            h('div', { class: 'card-head' }, h('span', { class: 'mill-id' }, m.id), h('span', { class: 'edge' }), h('span', { class: 'variant' })),
            h('div', { class: 'figures' }), h('div', { class: 'spark' }), h('div', { class: 'steps' }),
            h('div', { class: 'modules' }), h('div', { class: 'job' }));
          cards.append(card);
          sparks.set(m.id, new Sparkline(card.querySelector('.spark')));
        }
        const s = m.summary;
        card.classList.toggle('offline', !m.online);
        card.querySelector('.edge').replaceChildren(edgeBadge(m));
        card.querySelector('.variant').replaceChildren(h('span', { class: `badge variant ${m.config?.variant ?? ''}` }, variantName(m.config?.variant)));
        card.querySelector('.figures').replaceChildren(
          h('div', {}, h('span', { class: 'label' }, 'F_Y '), h('span', { class: 'big' }, fmt(s?.f_y_peak_n, 0)), ' N'),
          h('div', {}, h('span', { class: 'label' }, 'F_ref '), fmt(s?.f_ref_n || null, 0, ' N')),
          h('div', {}, h('span', { class: 'label' }, 'feed '), fmt(s?.feedrate_mm_s, 1, ' mm/s')),
          ...(s?.chatter ? [h('div', { class: 'chatter-flag' }, 'chatter')] : []),
          ...(m.breakage ? [h('div', { class: 'breakage-flag', title: m.breakage.message }, 'tool broken')] : []));
        const hist = m.hist;
        const from = hist.t.length ? hist.t[hist.t.length - 1] - 30 : 0;
        let i0 = hist.t.findIndex((t) => t >= from);
        if (i0 < 0) i0 = 0;
        sparks.get(m.id).setData([hist.t.slice(i0), hist.fy.slice(i0), hist.fref.slice(i0)]);
        card.querySelector('.steps').textContent = stepText(m);
        card.querySelector('.modules').replaceChildren(...moduleChips(m, true));
        const j = m.jobId ? store.jobs.get(m.jobId) : null;
        const frac = j?.progress?.fraction_done ?? j?.status?.fraction_done ?? 0;
        card.querySelector('.job').replaceChildren(j ? h('div', {},
          h('span', { class: 'strong' }, j.job_id), ' ', h('span', { class: 'muted' }, j.status?.job?.part_id ?? ''),
          ` - pass ${(j.progress?.pass_index ?? 0) + 1}/${j.progress?.pass_count ?? j.status?.pass_count ?? '?'}`,
          m.chatterCount ? h('span', { class: 'chatter-count' }, ` - ${m.chatterCount} chatter`) : null,
          h('div', { class: 'progress' }, h('div', { class: 'fill', style: `width:${(frac * 100).toFixed(1)}%` })))
          : h('span', { class: 'muted' }, 'no job'));
      }
      if (drawnTables !== tablesVersion) {
        drawnTables = tablesVersion;
        document.getElementById('jobs').replaceChildren(jobsTable([...store.jobs.values()], true));
        document.getElementById('catalog').replaceChildren(...catalogTables());
      }
    },
    destroy() { for (const s of sparks.values()) s.destroy(); },
  };
}

function moduleChips(m, compact) {
  const active = m.situation?.modules ?? '';
  const configured = m.config?.modules ?? [];
  return Object.entries(MODULES).map(([k, name]) => h('span', {
    class: `module${active.includes(k) ? ' on' : ''}${configured.length && !configured.includes(k) ? ' unused' : ''}`,
    title: `${k}: ${name}${active.includes(k) ? ' (active)' : ''}`, dataset: { module: k },
  }, compact ? k : h('span', {}, h('b', {}, k), ' ', name)));
}

function marksFor(m) {
  const spans = [];
  let open = null;
  for (const s of m.situations) {
    const kind = s.modules_mask & (1 << 6) ? 'suppression' : s.modules_mask & (1 << 2) ? 'hold' : null;
    if (open && open.kind !== kind) { open.t1 = s.t; spans.push(open); open = null; }
    if (kind && !open) open = { kind, t0: s.t, t1: Infinity };
  }
  const h = m.hist;
  if (open) { open.t1 = h.t.length ? h.t[h.t.length - 1] : open.t0; spans.push(open); }
  const passes = [];
  for (let i = 1; i < h.t.length; i++) {
    if (h.count[i] > 0 && (h.pass[i] !== h.pass[i - 1] || h.count[i] !== h.count[i - 1])) {
      passes.push({ t: h.t[i], label: `pass ${h.pass[i] + 1}/${h.count[i]}` });
    }
  }
  const chatter = m.chatter.map((c) => ({
    t: c.t,
    label: `chatter (${c.source}${c.frequency_hz ? ', ' + c.frequency_hz.toFixed(0) + ' Hz' : ''})${c.new_spindle_rpm > 0 ? ' → ' + c.new_spindle_rpm.toFixed(0) + ' rpm' : ''}`,
  }));
  if (m.breakage) chatter.push({ t: m.breakage.t, label: 'tool broken: feed held' });
  return { spans, passes, chatter };
}

function millView(id) {
  const m = mill(id);
  const controls = h('div', { class: 'controls' },
    h('button', { id: 'btn-feed-hold', class: 'hold', onclick: () => sendCommand('feed_hold_on') }, 'Feed hold'),
    h('button', { id: 'btn-release', class: 'release', onclick: () => sendCommand('feed_hold_off') }, 'Release'),
    h('button', { id: 'btn-chatter', class: 'chatter', onclick: () => sendCommand('chatter_signal') }, 'Signal chatter'));
  const head = h('section', { class: 'mill-head panel' },
    h('div', { class: 'title' }, h('h1', {}, id), h('span', { id: 'edge-badge' }), h('span', { id: 'variant-badge' })),
    h('div', { id: 'mill-facts', class: 'facts' }), controls);
  const force = h('section', { class: 'panel force' }, h('h2', {}, 'F_Y per revolution, reference, feed'), h('div', { id: 'force-chart' }));
  const power = h('section', { class: 'panel power' }, h('h2', {}, 'Spindle power per revolution, against its limit'), h('div', { id: 'power-chart' }));
  const raw = h('section', { class: 'panel raw' }, h('h2', {}, 'Raw F_y and F_z, last revolutions'), h('div', { id: 'raw-chart' }));
  const grafcet = h('section', { class: 'panel grafcet-panel' },
    h('h2', {}, 'Operation supervisor ', h('span', { id: 'grafcet-name', class: 'muted' })),
    h('div', { id: 'grafcet' }), h('h3', {}, 'Modules'), h('div', { id: 'modules', class: 'module-list' }),
    h('h3', {}, 'Receptivities'), h('div', { id: 'inputs', class: 'inputs' }));
  const jobs = h('section', { class: 'panel jobs-panel' }, h('h2', {}, 'Job queue'), h('div', { id: 'mill-jobs' }));
  const chatter = h('section', { class: 'panel' }, h('h2', {}, 'Chatter events'), h('div', { id: 'chatter-list' }));
  const log = h('section', { class: 'panel' }, h('h2', {}, 'Operator commands'), h('div', { id: 'command-log' }));
  const program = h('section', { class: 'panel' }, h('h2', {}, 'Part program (G-code)'), h('div', { id: 'program-view' }));
  const root = h('main', { id: 'mill-view', dataset: { mill: id } },
    head, h('div', { class: 'mill-grid' }, h('div', { class: 'left' }, force, power, raw, jobs,
      h('div', { class: 'two' }, chatter, log), program), grafcet));
  let forceChart = null;
  let powerChart = null;
  let rawChart = null;
  const gv = new GrafcetView(grafcet.querySelector('#grafcet'));
  const onResize = () => { forceChart?.resize(); powerChart?.resize(); rawChart?.resize(); };
  let drawnTables = -1;
  window.addEventListener('resize', onResize);
  return {
    root,
    mounted() {
      forceChart = new ForceChart(force.querySelector('#force-chart'), () => marksFor(m));
      powerChart = new PowerChart(power.querySelector('#power-chart'), () => marksFor(m));
      rawChart = new RawChart(raw.querySelector('#raw-chart'));
    },
    render() {
      const mm = mill(id);
      root.querySelector('#edge-badge').replaceChildren(edgeBadge(mm));
      root.querySelector('#variant-badge').replaceChildren(h('span', { class: `badge variant ${mm.config?.variant ?? ''}` }, variantName(mm.config?.variant)));
      const s = mm.summary;
      root.querySelector('#mill-facts').replaceChildren(
        fact('F_Y', fmt(s?.f_y_peak_n, 0, ' N')), fact('F_ref', fmt(s?.f_ref_n || null, 0, ' N')),
        fact('spindle power', s ? `${fmt(s.spindle_power_w, 0, ' W')} of ${fmt(mm.config?.max_spindle_power_w || null, 0, ' W')}` : '-'),
        fact('feed', fmt(s?.feedrate_mm_s, 1, ' mm/s')), fact('depth', fmt(s?.depth_mm, 2, ' mm')),
        fact('pass', s ? `${Math.min(s.pass_index + 1, s.pass_count)} / ${s.pass_count}` : '-'),
        fact('contact', s ? (s.in_contact ? 'yes' : 'no') : '-'),
        fact('machine time', s ? formatMachineTime(s.t, 2) : '-'),
        fact('config in force', mm.config?.config_id ?? '-'),
        ...(mm.breakage
          ? [h('div', { class: 'fact breakage', id: 'breakage' }, h('span', { class: 'breakage-flag' }, 'tool broken'), ' ', mm.breakage.message)]
          : []),
        ...(mm.status?.refused_config_id
          ? [h('div', { class: 'fact refused', title: mm.status.refusal },
              h('span', { class: 'muted' }, 'last refused '),
              h('span', { class: 'strong' }, mm.status.refused_config_id), ': ', mm.status.refusal)]
          : []));
      for (const b of root.querySelectorAll('.controls button')) {
        b.disabled = !store.session.can_command || !mm.online;
        b.title = store.session.can_command ? '' : 'sign in with an operator token to send commands';
      }
      const hist = mm.hist;
      forceChart?.setData([hist.t, hist.fy, hist.fref, hist.feed]);
      const limit = mm.config?.max_spindle_power_w || null;
      powerChart?.setData([hist.t, hist.power, hist.t.map(() => limit)]);
      rawChart?.setBatches(mm.batches);
      gv.setModel(mm.config?.grafcet ?? null);
      gv.update(mm.situation?.active_steps ?? [], mm.situation?.modules ?? '');
      root.querySelector('#grafcet-name').textContent = mm.config?.grafcet?.title ?? '';
      root.querySelector('#grafcet').dataset.activeSteps = (mm.situation?.active_steps ?? []).join(',');
      root.querySelector('#modules').replaceChildren(...moduleChips(mm, false));
      const inputs = mm.situation?.inputs ?? {};
      const described = mm.config?.grafcet?.inputs ?? [];
      root.querySelector('#inputs').replaceChildren(...Object.entries(inputs).map(([k, v]) => h('span', {
        class: `input${v ? ' on' : ''}`, title: described.find((d) => d.name === k)?.description ?? '' },
      h('b', {}, k), ' ', described.find((d) => d.name === k)?.description ?? '')));
      if (drawnTables === tablesVersion) return;
      drawnTables = tablesVersion;
      root.querySelector('#mill-jobs').replaceChildren(jobsTable([...store.jobs.values()].filter(
        (j) => (j.machine_id || j.status?.machine_id) === id), false));
      root.querySelector('#chatter-list').replaceChildren(mm.chatter.length ? h('table', { class: 'events' },
        h('thead', {}, h('tr', {}, ...['machine time', 'source', 'frequency', 'ratio', 'pass', 'remedy', 'job'].map((t) => h('th', {}, t)))),
        h('tbody', {}, ...mm.chatter.slice(-8).reverse().map((c) => h('tr', {},
          h('td', {}, formatMachineTime(c.t, 2)), h('td', {}, c.source), h('td', { class: 'num' }, c.frequency_hz ? fmt(c.frequency_hz, 0, ' Hz') : '-'),
          h('td', { class: 'num' }, fmt(c.energy_ratio, 1)), h('td', { class: 'num' }, c.pass_index + 1),
          h('td', { class: 'remedy' }, c.new_spindle_rpm > 0 ? `spindle speed → ${fmt(c.new_spindle_rpm, 0, ' rpm')}` : `${c.new_pass_count} passes`),
          h('td', {}, c.job_id)))))
        : h('p', { class: 'muted' }, 'No chatter events.'));
      // The program as a CNC control is given it: the plan's (from the
      // configuration in force) until the chatter suppressor rewrites it,
      // then the edge's rewrite (the remaining depth).
      const box = root.querySelector('#program-view');
      if (mm.program?.gcode) {
        box.dataset.config = '';
        box.replaceChildren(
          h('p', { class: 'muted' }, `rewritten by the chatter suppressor (revision ${mm.program.revision}): ${mm.program.passes?.length ?? '?'} passes in all`),
          h('pre', { class: 'gcode' }, mm.program.gcode));
      } else if (!mm.config) {
        box.replaceChildren(h('p', { class: 'muted' }, 'No configuration in force.'));
      } else if (box.dataset.config !== mm.config.config_id) {
        box.dataset.config = mm.config.config_id;
        fetch(`/api/mills/${encodeURIComponent(id)}/config`).then((r) => r.json()).then((c) => {
          if (mm.program?.gcode) return;
          box.replaceChildren(c?.program?.gcode
            ? h('pre', { class: 'gcode' }, c.program.gcode)
            : h('p', { class: 'muted' }, 'No G-code in this configuration.'));
        }).catch(() => {});
      }
      const cmds = store.commands.filter((c) => c.machine_id === id).slice(0, 8);
      root.querySelector('#command-log').replaceChildren(cmds.length ? h('table', { class: 'events' },
        h('tbody', {}, ...cmds.map((c) => h('tr', {},
          h('td', {}, new Date(c.issued_unix_ms).toLocaleTimeString()), h('td', {}, c.action.replaceAll('_', ' ')),
          h('td', {}, h('strong', {}, c.operator)), h('td', {}, c.sent ? 'sent' : 'failed: ' + c.error)))))
        : h('p', { class: 'muted' }, 'No commands sent from this dashboard.'));
    },
    destroy() {
      window.removeEventListener('resize', onResize);
      forceChart?.destroy();
      powerChart?.destroy();
      rawChart?.destroy();
    },
  };
}

// A job's history page (#/job/ID), from the cell's database through the
// dashboard (GET /api/jobs/ID/history): kept after the job ends and after a
// dashboard restart. F_Y, feed and spindle power of every recorded
// revolution, the events, the plan and why, the programs as run, CSV export.
function jobView(id) {
  const started = performance.now();
  const enc = encodeURIComponent(id);
  const head = h('section', { class: 'panel job-head' },
    h('div', { class: 'title' }, h('h1', {}, id), h('span', { id: 'job-state' }), h('span', { id: 'job-variant' })),
    h('div', { id: 'job-facts', class: 'facts' }),
    h('div', { class: 'controls' },
      h('a', { id: 'job-csv', class: 'button', href: `/api/jobs/${enc}/history.csv`, download: `${id}-history.csv` }, 'Export CSV'),
      h('a', { class: 'button', href: '#/' }, 'Back to the cell')));
  const force = h('section', { class: 'panel force' }, h('h2', {}, 'F_Y per revolution, reference, feed'), h('div', { id: 'job-force' }));
  const power = h('section', { class: 'panel power' }, h('h2', {}, 'Spindle power per revolution, against the machine\'s limit'), h('div', { id: 'job-power' }));
  const events = h('section', { class: 'panel' }, h('h2', {}, 'Events'), h('div', { id: 'job-events' }));
  const plan = h('section', { class: 'panel' }, h('h2', {}, 'Plan and why'), h('div', { id: 'job-plan' }));
  const programs = h('section', { class: 'panel' }, h('h2', {}, 'Part program as run'), h('div', { id: 'job-programs' }));
  const lobes = h('section', { class: 'panel', id: 'job-lobes-panel', hidden: true },
    h('h2', {}, 'The plan on its lobe diagram'), h('p', { id: 'job-lobes-text' }), h('div', { id: 'job-lobes' }));
  const root = h('main', { id: 'job-view', dataset: { job: id } }, head, force, power,
    h('div', { class: 'two' }, events, plan), lobes, programs);
  let forceChart = null;
  let powerChart = null;
  let lobeChart = null;
  let marks = { spans: [], passes: [], chatter: [] };
  const onResize = () => { forceChart?.resize(); powerChart?.resize(); };
  window.addEventListener('resize', onResize);

  function draw(d) {
    const r = d.revolutions;
    root.querySelector('#job-state').replaceChildren(h('span', { class: `badge job-${d.state.toLowerCase()}` }, d.state));
    root.querySelector('#job-variant').replaceChildren(h('span', { class: 'badge variant' }, d.variant));
    const res = d.result;
    root.querySelector('#job-facts').replaceChildren(
      fact('part', d.part_id), fact('tool', d.tool_id), fact('machine', d.machine_id || '-'),
      fact('attempt', String(d.attempt)),
      fact('cycle time', res?.cycle_time_s ? `${res.cycle_time_s.toFixed(1)} s` : '-'),
      fact('chatter events', String(res?.chatter_events ??
        d.events.filter((e) => e.note && e.reason.startsWith('chatter event')).length)),
      fact('chatter revolutions', String(r.chatter.filter(Boolean).length)),
      fact('revolutions recorded', String(r.count)),
      fact('peak F_Y', r.count ? `${Math.max(...r.f_y_peak_n).toFixed(0)} N` : '-'));
    // Marks: pass boundaries and the first revolution of each chatter run.
    const passes = [];
    const chatter = [];
    for (let i = 0; i < r.count; i++) {
      if (i === 0 || r.pass_index[i] !== r.pass_index[i - 1] || r.pass_count[i] !== r.pass_count[i - 1]) {
        passes.push({ t: r.t[i], label: `pass ${r.pass_index[i] + 1}/${r.pass_count[i]}` });
      }
      if (r.chatter[i] && (i === 0 || !r.chatter[i - 1])) chatter.push({ t: r.t[i], label: 'chatter' });
    }
    // The breakage, at the machine time the edge's reason gives.
    const broken = d.events.map((e) => e.reason.match(/tool breakage at ([\d.]+) s/)).find(Boolean);
    if (broken) chatter.push({ t: Number(broken[1]), label: 'tool broken' });
    marks = { spans: [], passes, chatter };
    forceChart.setData([r.t, r.f_y_peak_n, r.f_ref_n.map((v) => (v > 0 ? v : null)), r.feedrate_mm_s]);
    const limit = d.max_spindle_power_w || null;
    powerChart.setData([r.t, r.spindle_power_w, r.t.map(() => limit)]);
    root.querySelector('#job-events').replaceChildren(d.events.length ? h('table', { class: 'events' },
      h('thead', {}, h('tr', {}, ...['time', 'state', 'what'].map((t) => h('th', {}, t)))),
      h('tbody', {}, ...d.events.map((e) => h('tr', {},
        h('td', {}, new Date(Number(e.time_ms)).toLocaleTimeString()),
        h('td', {}, e.note ? 'note' : `${e.from === 'JOB_STATE_UNSPECIFIED' ? '' : e.from + ' → '}${e.to}`),
        h('td', { class: 'reason' }, e.reason)))))
      : h('p', { class: 'muted' }, 'No events.'));
    const p = d.plan;
    root.querySelector('#job-plan').replaceChildren(
      h('p', { class: 'explanation' }, d.explanation || 'not planned'),
      ...(p ? [h('table', { class: 'events' },
        h('thead', {}, h('tr', {}, ...['pass', 'depth', 'feed', 'speed', 'F_ref'].map((t) => h('th', {}, t)))),
        h('tbody', {}, ...p.passes.map((x, i) => h('tr', {},
          h('td', { class: 'num' }, i + 1), h('td', { class: 'num' }, fmt(x.depth_mm, 2, ' mm')),
          h('td', { class: 'num' }, fmt(x.feedrate_mm_s, 1, ' mm/s')), h('td', { class: 'num' }, fmt(x.spindle_rpm, 0, ' rpm')),
          h('td', { class: 'num' }, x.force_reference_n ? fmt(x.force_reference_n, 0, ' N') : 'P_max / V'))))),
        h('p', { class: 'muted small' }, `supervisor ${p.grafcet_name}, modules ${p.modules.join('')}`)] : []));
    const progs = [];
    if (p?.gcode) progs.push(h('div', {}, h('h3', {}, 'as planned'), h('pre', { class: 'gcode' }, p.gcode)));
    for (const x of d.programs) {
      progs.push(h('div', {}, h('h3', {}, `attempt ${x.attempt}, revision ${x.revision}: ${x.passes} passes`),
        h('pre', { class: 'gcode' }, x.gcode || '(no G-code)')));
    }
    root.querySelector('#job-programs').replaceChildren(...(progs.length ? progs : [h('p', { class: 'muted' }, 'No program recorded.')]));
    root.dataset.ready = 'true';
    window.smcApp.jobLoadMs = performance.now() - started;
    if (d.variant === 'SMC I' && p) drawLobes(d);
  }

  // SMC I: the plan on its lobe diagram (computed by the dashboard from the
  // plan's structural model), with the margin.
  function drawLobes(d) {
    fetch(`/api/jobs/${enc}/lobes`).then((r) => r.json()).then((l) => {
      if (!l.lobes) return;
      lobes.hidden = false;
      const rpm = l.planned_rpm;
      const depth = Math.max(...l.planned_depths_mm);
      const xs = l.lobes.rpm.slice();
      const ys = l.lobes.critical_depth_mm.slice();
      let i = xs.findIndex((x) => x >= rpm);
      if (i < 0) i = xs.length;
      const lo = Math.max(0, i - 1);
      const hi = Math.min(xs.length - 1, i);
      const w = xs[hi] === xs[lo] ? 0 : (rpm - xs[lo]) / (xs[hi] - xs[lo]);
      const sdm = ys[lo] + w * (ys[hi] - ys[lo]);
      if (xs[i] !== rpm) { xs.splice(i, 0, rpm); ys.splice(i, 0, sdm); }
      const tdsMatch = d.explanation.match(/Critical depth at [\d.]+ rpm on \S+: ([\d.]+) mm/);
      const tds = tdsMatch ? Number(tdsMatch[1]) : null;
      const planned = xs.map((x, k) => (k === i ? depth : null));
      const checked = xs.map((x, k) => (k === i ? tds : null));
      lobeChart = new LobeChart(lobes.querySelector('#job-lobes'));
      lobeChart.setData([xs, ys, planned, checked]);
      const ref = tds ?? sdm;
      lobes.querySelector('#job-lobes-text').textContent =
        `planned ${depth.toFixed(2)} mm per pass at ${rpm.toFixed(0)} rpm; critical depth there ` +
        `${sdm.toFixed(2)} mm by the lobes` + (tds ? `, ${tds.toFixed(2)} mm by the plan's time-domain check` : '') +
        `; margin ${(depth / ref).toFixed(2)} of critical (${((1 - depth / ref) * 100).toFixed(0)} % below it).`;
    }).catch(() => {});
  }

  return {
    root,
    mounted() {
      forceChart = new ForceChart(force.querySelector('#job-force'), () => marks, Infinity);
      powerChart = new PowerChart(power.querySelector('#job-power'), () => marks, Infinity);
      fetch(`/api/jobs/${enc}/history`).then(async (res) => {
        const body = await res.json();
        if (!res.ok) {
          root.querySelector('#job-facts').replaceChildren(h('p', { class: 'error' }, body.error ?? `HTTP ${res.status}`));
          root.dataset.ready = 'error';
          return;
        }
        draw(body);
      }).catch((e) => {
        root.querySelector('#job-facts').replaceChildren(h('p', { class: 'error' }, String(e)));
        root.dataset.ready = 'error';
      });
    },
    render() {},
    destroy() {
      window.removeEventListener('resize', onResize);
      forceChart?.destroy();
      powerChart?.destroy();
      lobeChart?.destroy();
    },
  };
}

function fact(label, value) {
  return h('div', { class: 'fact' }, h('span', { class: 'label' }, label), h('span', { class: 'value' }, value));
}

// ---------------------------------------------------------------- routing --

function route() {
  const hash = location.hash;
  const tokenMatch = hash.match(/^#token=(.+)$/);
  if (tokenMatch) {  // a link carrying the operator token: keep it for this tab only
    sessionStorage.setItem(TOKEN_KEY, decodeURIComponent(tokenMatch[1]));
    history.replaceState(null, '', location.pathname + '#/');
    checkSession();
  }
  const m = location.hash.match(/^#\/mill\/(.+)$/);
  const jm = location.hash.match(/^#\/job\/(.+)$/);
  const focus = m ? decodeURIComponent(m[1]) : null;
  const jobFocus = jm ? decodeURIComponent(jm[1]) : null;
  if (view && focus === store.focus && jobFocus === store.jobFocus) return;
  view?.destroy();
  store.focus = focus;
  store.jobFocus = jobFocus;
  view = jobFocus ? jobView(jobFocus) : focus ? millView(focus) : cellView();
  document.getElementById('view').replaceChildren(view.root);
  view.mounted?.();
  rebuildNav();
  connect();
  scheduleRender();
}

window.smcApp = {
  store,
  points: (id) => store.mills.get(id)?.hist.t.length ?? 0,
  lastTime: (id) => store.mills.get(id)?.hist.t.at(-1) ?? null,
  activeSteps: (id) => store.mills.get(id)?.situation?.active_steps ?? [],
};

window.addEventListener('hashchange', route);
route();
checkSession();
