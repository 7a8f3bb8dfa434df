// gangue web page: tabs, presets, the shared case (summary, link, recent
// cases, comparison), export buttons and the printable report.

import { getJson } from './js/api.js';
import { initColumn } from './js/column.js';
import { setFloorLimits } from './js/floor.js';
import { applyServerDefaults, applyState, formState, setDefaults } from './js/form.js';
import { csvButton, download, fmt, h, tableRows } from './js/format.js';
import { initImpact } from './js/impact.js';
import { initMigration } from './js/migration.js';
import { plotPng } from './js/plot.js';
import { initScene, setSceneRanges } from './js/scene.js';
import { initSpalling, setSpallingDefaults } from './js/spalling.js';
import { initStudy, setStudyDefaults } from './js/study.js';

const TABS = ['scene', 'impact', 'column', 'migration', 'study', 'spalling'];
const CASE_FORMS = ['scene', 'impact', 'column', 'migration'];
const RECENT_KEY = 'gangue.recent.v1';
const RECENT_MAX = 12;

const forms = Object.fromEntries(CASE_FORMS.map((n) => [n, document.getElementById(`${n}-form`)]));
let settings = 'recommended';
let presets = null;
let modelVersion = '';

// ---- tabs ------------------------------------------------------------------

function currentTab() {
  return document.querySelector('[role="tab"][aria-selected="true"]')?.dataset.tab ?? TABS[0];
}

function showTab(name) {
  const active = TABS.includes(name) ? name : TABS[0];
  for (const tab of document.querySelectorAll('[role="tab"]')) {
    const selected = tab.dataset.tab === active;
    tab.setAttribute('aria-selected', String(selected));
    tab.tabIndex = selected ? 0 : -1;
  }
  for (const panel of document.querySelectorAll('[role="tabpanel"]')) {
    panel.hidden = panel.dataset.panel !== active;
  }
  updateCaseSummary();
}

function parseHash() {
  const raw = location.hash.slice(1);
  const [tab, ...rest] = raw.split('&');
  const params = new URLSearchParams(rest.join('&'));
  return { tab, encoded: params.get('case') };
}

function initTabs() {
  for (const tab of document.querySelectorAll('[role="tab"]')) {
    tab.addEventListener('click', () => {
      history.replaceState(null, '', `#${tab.dataset.tab}`);
      showTab(tab.dataset.tab);
    });
  }
  // Arrow keys move between tabs (WAI-ARIA tabs pattern).
  document.querySelector('[role="tablist"]').addEventListener('keydown', (event) => {
    const step = { ArrowRight: 1, ArrowLeft: -1 }[event.key];
    if (!step) return;
    const current = TABS.indexOf(currentTab());
    const next = TABS[(current + step + TABS.length) % TABS.length];
    history.replaceState(null, '', `#${next}`);
    showTab(next);
    document.getElementById(`tab-${next}`).focus();
  });
  window.addEventListener('hashchange', () => {
    const { tab, encoded } = parseHash();
    showTab(tab);
    if (encoded) openCase(decodeCase(encoded), { run: true });
  });
}

// ---- presets and settings --------------------------------------------------

/**
 * Every form's starting values from GET /v1/presets `defaults`: each route's
 * default request (what `{}` means to the server) and the defaults of the
 * objects sent only when ticked. Nothing numeric is written in the page.
 */
function applyPresetValues() {
  const d = presets.defaults;
  const o = d.objects;
  applyServerDefaults(forms.impact, d.impact);
  applyServerDefaults(forms.column, d.column);
  applyServerDefaults(forms.migration, d.migration, { '/monte_carlo': o.monte_carlo });
  applyServerDefaults(forms.scene, d.scene, { '/monte_carlo': o.scene_monte_carlo, '/support_rows': o.support_rows });
  const across = forms.scene.querySelector('[data-local="across"]');
  across.value = across.defaultValue = String(o.support_rows.across_m[0]);
  for (const [id, value] of [['floor-elevation-property', o.floor.elevation_property], ['floor-resolution', o.floor.resolution_m]]) {
    const el = document.getElementById(id);
    if (el) el.value = el.defaultValue = String(value);
  }
  setSceneRanges(presets.study);
  setFloorLimits(presets.limits);
  setStudyDefaults(d.study);
  setSpallingDefaults(d.spalling);
}

/** The recommended or the paper's settings on every tab (GET /v1/presets `presets`). */
function applySettings(name) {
  settings = name;
  // A setting the preset does not name is the server's default; the damping
  // value not in use keeps the other preset's (ratio) or the default (c).
  const p = presets.presets[name];
  const d = presets.defaults;
  setDefaults(forms.impact, {
    '/contact/law': p.contact?.law ?? d.impact.contact.law,
    '/contact/effective_modulus': p.contact?.effective_modulus ?? d.impact.contact.effective_modulus,
  });
  const col = forms.column;
  const ratio = p.column?.damping_ratio !== undefined;
  const kind = col.querySelector('[data-local="damping"]');
  for (const o of kind.options) o.defaultSelected = o.value === (ratio ? 'ratio' : 'coefficient');
  kind.value = ratio ? 'ratio' : 'coefficient';
  kind.dispatchEvent(new Event('change'));
  setDefaults(col, {
    '/galerkin/mode_shapes': p.galerkin?.mode_shapes ?? d.column.galerkin.mode_shapes,
    '/column/damping_ratio': p.column?.damping_ratio ?? presets.presets.recommended.column.damping_ratio,
    '/column/damping_coefficient_n_s_m2': p.column?.damping_coefficient_n_s_m2 ?? presets.fields['/column/damping_coefficient_n_s_m2'].default,
  });
  const models = col.querySelector('[data-local="models"]');
  const model = p.model ?? d.column.model;
  for (const o of models.options) o.defaultSelected = o.value === model;
  models.value = model;
  setDefaults(forms.scene, { '/column_model': p.model ?? d.scene.column_model });
  const study = document.getElementById('study-form');
  if (study) {
    study.elements.model.value = p.model ?? d.study.base.model;
    study.elements.law.value = p.contact?.law ?? d.study.base.contact.law;
    study.elements.effective_modulus.value = p.contact?.effective_modulus ?? d.study.base.contact.effective_modulus;
  }
  document.getElementById('preset-recommended').setAttribute('aria-pressed', String(name === 'recommended'));
  document.getElementById('preset-paper').setAttribute('aria-pressed', String(name === 'paper'));
  document.getElementById('preset-note').textContent = name === 'paper'
    ? 'The paper\'s settings: its Eq. 4 law, rock-only modulus, printed mode constants, c = 1 N·s/m², decoupled model. Use them to reproduce the paper, not to design.'
    : 'Recommended: johnson law, two-body modulus, exact modes, ζ₁ = 0.02, coupled model.';
  updateCaseSummary();
}

// ---- the shared rock and the case summary ----------------------------------

const SHARED = ['/rock/side_length_m', '/rock/density_kg_m3'];

function initSharedRock() {
  for (const [a, b] of [[forms.impact, forms.migration], [forms.migration, forms.impact]]) {
    for (const pointer of SHARED) {
      const src = a.querySelector(`[data-pointer="${pointer}"]`);
      const dst = b.querySelector(`[data-pointer="${pointer}"]`);
      if (!src || !dst) continue;
      src.addEventListener('input', () => { dst.value = src.value; });
      src.addEventListener('change', () => { dst.value = src.value; });
      a.addEventListener('reset', () => setTimeout(() => { dst.value = src.value; }));
    }
  }
  for (const form of Object.values(forms)) {
    form.addEventListener('input', updateCaseSummary);
    form.addEventListener('change', updateCaseSummary);
    form.addEventListener('reset', () => setTimeout(updateCaseSummary));
  }
}

function val(form, pointer) {
  const el = form?.querySelector(`[data-pointer="${pointer}"]`);
  if (!el) return '?';
  if (el.type === 'checkbox') return el.checked ? 'yes' : 'no';
  return el.value.trim() || 'auto';
}

function unitText(form, pointer) {
  return form?.querySelector(`[data-pointer="${pointer}"]`)?.closest('.field')?.querySelector('.unit')?.textContent ?? '';
}

function part(form, pointer, prefix = '') {
  const u = unitText(form, pointer);
  return `${prefix}${val(form, pointer)}${u ? ` ${u}` : ''}`;
}

/** Which parts of the case each tab uses. */
const USES = {
  scene: ['rock', 'face', 'column', 'contact'],
  impact: ['rock', 'column', 'contact', 'velocity'],
  column: ['rock', 'column', 'contact', 'velocity'],
  migration: ['rock', 'face'],
  study: ['column'],
  spalling: [],
};

function caseParts() {
  const i = forms.impact;
  const m = forms.migration;
  return {
    rock: `Rock (all tabs): ${val(m, '/rock/shape')} L ${part(i, '/rock/side_length_m')}, ρ ${part(i, '/rock/density_kg_m3')}, E ${part(i, '/rock/elastic_modulus_pa')}`,
    column: `Column: D₁ ${part(i, '/column/outer_diameter_m')} / D₂ ${part(i, '/column/inner_diameter_m')}, l ${part(i, '/column/length_m')}, σy ${part(i, '/column/yield_stress_pa')}`,
    contact: `Contact: ${val(i, '/contact/law')}, E* ${val(i, '/contact/effective_modulus')}`,
    velocity: `Impact velocity ${part(i, '/velocity_m_s')}`,
    face: `Face: dip ${part(m, '/face/dip_deg')}, ${part(m, '/face/length_m')} long, μ ${val(m, '/face/friction_coefficient')}, ${val(m, '/method')}`,
  };
}

function updateCaseSummary() {
  const box = document.getElementById('case-summary');
  if (!box || !forms.impact) return;
  const tab = currentTab();
  const uses = USES[tab] ?? [];
  const parts = caseParts();
  box.replaceChildren(h('strong', {}, `Case (${tab} tab, ${settings} settings): `),
    ...Object.entries(parts).map(([key, text]) =>
      h('span', { class: `case-part ${uses.includes(key) ? 'used' : 'unused'}`, dataset: { part: key } }, text)));
}

// ---- the case in the link, recent cases, comparison --------------------------

function caseState(tab) {
  const state = { v: 1, tab, settings, forms: {} };
  for (const [name, form] of Object.entries(forms)) if (form) state.forms[name] = formState(form);
  return state;
}

function encodeCase(state) {
  const bytes = new TextEncoder().encode(JSON.stringify(state));
  let bin = '';
  for (const b of bytes) bin += String.fromCharCode(b);
  return btoa(bin).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}

function decodeCase(text) {
  try {
    const bin = atob(text.replace(/-/g, '+').replace(/_/g, '/'));
    return JSON.parse(new TextDecoder().decode(Uint8Array.from(bin, (c) => c.charCodeAt(0))));
  } catch {
    return null;
  }
}

function linkFor(state) {
  return `${location.origin}${location.pathname}#${state.tab}&case=${encodeCase(state)}`;
}

const panels = {};

/** Puts a saved case into the forms; with `run`, computes its tab. */
function openCase(state, { run = false } = {}) {
  if (!state || !state.forms) return;
  if (state.settings && state.settings !== settings) applySettings(state.settings);
  for (const [name, values] of Object.entries(state.forms)) if (forms[name]) applyState(forms[name], values);
  showTab(state.tab);
  if (run) panels[state.tab]?.run();
}

function recent() {
  try {
    return JSON.parse(localStorage.getItem(RECENT_KEY) ?? '[]');
  } catch {
    return [];
  }
}

function remember(entry) {
  const list = recent().filter((e) => e.link !== entry.link);
  list.unshift(entry);
  try {
    localStorage.setItem(RECENT_KEY, JSON.stringify(list.slice(0, RECENT_MAX)));
  } catch {
    // storage full or disabled: the link still works
  }
  fillRecent();
}

function fillRecent() {
  const list = recent();
  const options = list.map((e, i) => h('option', { value: String(i) }, `${new Date(e.time).toLocaleTimeString()} ${e.tab}: ${e.headline}`));
  document.getElementById('case-recent').replaceChildren(h('option', { value: '' }, list.length ? 'choose a case…' : '—'), ...options);
  for (const [id, pick] of [['compare-a', 1], ['compare-b', 0]]) {
    const sel = document.getElementById(id);
    const keep = sel.value;
    sel.replaceChildren(...list.map((e, i) => h('option', { value: String(i) }, `${new Date(e.time).toLocaleTimeString()} ${e.tab}: ${e.headline}`)));
    sel.value = keep && Number(keep) < list.length ? keep : String(Math.min(pick, Math.max(list.length - 1, 0)));
  }
}

/** The rows a result shows, for the comparison: [label, text] from the panel's tables. */
function resultRows(tab) {
  const panel = document.querySelector(`[data-panel="${tab}"]`);
  const rows = [];
  for (const table of panel.querySelectorAll('.results table')) {
    if (table.closest('[hidden]')) continue;
    const all = tableRows(table);
    const head = table.tHead ? all.shift() : null;
    for (const r of all) {
      if (r.length < 2) continue;
      if (head && head.length === r.length && head.length > 3) {
        r.slice(1).forEach((c, j) => { if (head[j + 1]) rows.push([`${r[0]} — ${head[j + 1]}`, c]); });
      } else {
        rows.push([r[0], r.slice(1).filter(Boolean).join(' ')]);
      }
    }
  }
  return rows;
}

function headline(tab, data) {
  switch (tab) {
    case 'impact': return `v ${val(forms.impact, '/velocity_m_s')} m/s, Pmax ${fmt(data.max_force_n * 1e-3, 4)} kN`;
    case 'column': return Object.keys(data).map((m) => `${m} U ${fmt(data[m].absorbed_energy_j ?? data[m].column_energy_after_contact_j, 4)} J`).join(', ');
    case 'migration': return `${data.statistics ? `${data.statistics.runs} runs, ` : ''}v ${fmt(data.arrival?.speed_m_s, 4)} m/s`;
    case 'scene': return data.statistics ? `${data.statistics.runs} runs` : `${(data.impacts ?? []).length} impact(s)`;
    default: return '';
  }
}

function renderCompare() {
  const list = recent();
  const a = list[Number(document.getElementById('compare-a').value)];
  const b = list[Number(document.getElementById('compare-b').value)];
  const table = document.getElementById('compare-table');
  table.replaceChildren();
  if (!a || !b) {
    table.append(h('tbody', {}, h('tr', {}, h('td', {}, 'Compute two cases first: each computed case is kept here.'))));
    return;
  }
  const inputs = [];
  for (const name of new Set([...Object.keys(a.state.forms), ...Object.keys(b.state.forms)])) {
    const fa = a.state.forms[name] ?? {};
    const fb = b.state.forms[name] ?? {};
    for (const key of new Set([...Object.keys(fa), ...Object.keys(fb)])) {
      if (String(fa[key]) !== String(fb[key])) inputs.push([`${name} ${key}`, fa[key], fb[key]]);
    }
  }
  const mapB = new Map(b.rows);
  const mapA = new Map(a.rows);
  const labels = [...new Set([...a.rows.map((r) => r[0]), ...b.rows.map((r) => r[0])])];
  table.append(
    h('thead', {}, h('tr', {}, h('th', {}, ''), h('th', {}, `A: ${a.tab} ${new Date(a.time).toLocaleTimeString()}`),
      h('th', {}, `B: ${b.tab} ${new Date(b.time).toLocaleTimeString()}`))),
    h('tbody', {},
      h('tr', { class: 'group' }, h('th', { colspan: 3 }, inputs.length ? 'Inputs that differ' : 'Same inputs')),
      inputs.map(([k, x, y]) => h('tr', { class: 'diff' }, h('th', { scope: 'row' }, k), h('td', {}, String(x ?? '—')), h('td', {}, String(y ?? '—')))),
      h('tr', { class: 'group' }, h('th', { colspan: 3 }, 'Results')),
      labels.map((l) => h('tr', { class: mapA.get(l) !== mapB.get(l) ? 'diff' : '' },
        h('th', { scope: 'row' }, l), h('td', {}, mapA.get(l) ?? '—'), h('td', {}, mapB.get(l) ?? '—')))),
  );
}

function initCases() {
  document.addEventListener('gangue:result', ({ detail }) => {
    const { name, data } = detail;
    if (!CASE_FORMS.includes(name)) return;
    const state = caseState(name);
    const link = linkFor(state);
    history.replaceState(null, '', link.slice(link.indexOf('#')));
    const version = data.model_version ?? Object.values(data).find((d) => d?.model_version)?.model_version;
    if (version) modelVersion = version;
    updatePrintHeader();
    remember({ time: Date.now(), tab: name, headline: headline(name, data), link, state, rows: resultRows(name) });
    const floorNote = document.getElementById('case-link-note');
    const uploaded = document.querySelector('[data-floor-uploaded="true"]');
    floorNote.hidden = !uploaded;
    floorNote.textContent = uploaded ? 'The uploaded floor cannot travel in a link: whoever opens it gets the plane floor unless they upload the same file.' : '';
  });
  document.getElementById('case-copy').addEventListener('click', async () => {
    const link = linkFor(caseState(currentTab()));
    history.replaceState(null, '', link.slice(link.indexOf('#')));
    const note = document.getElementById('case-link-note');
    try {
      await navigator.clipboard.writeText(link);
      note.textContent = 'Link copied: opening it fills every form and computes this tab.' +
        (document.querySelector('[data-floor-uploaded="true"]') ? ' The uploaded floor is not in it: whoever opens it must upload the same file.' : '');
    } catch {
      note.textContent = `Link (copy it from the address bar): ${link}`;
    }
    note.hidden = false;
  });
  document.getElementById('case-recent').addEventListener('change', (event) => {
    const entry = recent()[Number(event.target.value)];
    if (entry) openCase(entry.state, { run: true });
    event.target.value = '';
  });
  document.getElementById('case-compare').addEventListener('click', () => {
    const box = document.getElementById('compare');
    box.hidden = !box.hidden;
    if (!box.hidden) {
      fillRecent();
      renderCompare();
    }
  });
  document.getElementById('compare-close').addEventListener('click', () => { document.getElementById('compare').hidden = true; });
  for (const id of ['compare-a', 'compare-b']) document.getElementById(id).addEventListener('change', renderCompare);
  fillRecent();
}

// ---- export and print --------------------------------------------------------

function slug(text) {
  return text.toLowerCase().replace(/[^a-z0-9]+/g, '_').replace(/^_|_$/g, '').slice(0, 60) || 'table';
}

/** Every card gets CSV buttons for its tables and data, PNG buttons for its plots. */
function initExports() {
  for (const card of document.querySelectorAll('.results .card')) {
    const title = card.querySelector('h3')?.textContent.trim() ?? 'result';
    const panel = card.closest('[data-panel]')?.dataset.panel ?? 'gangue';
    const bar = h('div', { class: 'export-bar' });
    const tables = [...card.querySelectorAll('table')];
    if (tables.length) {
      bar.append(csvButton(`${panel}_${slug(title)}.csv`, () => tables.flatMap((t) => tableRows(t)), 'CSV'));
    }
    for (const plot of card.querySelectorAll('.plot')) {
      const png = h('button', { type: 'button', class: 'export', dataset: { png: plot.id } }, 'PNG');
      png.addEventListener('click', async () => {
        const blob = await plotPng(plot, title);
        if (blob) download(`${plot.id}.png`, blob, 'image/png');
      });
      const data = h('button', { type: 'button', class: 'export', dataset: { csv: `${plot.id}.csv` } }, 'CSV: data');
      data.addEventListener('click', () => {
        if (plot.csv) download(`${plot.id}.csv`, csvText(plot.csv()));
      });
      bar.append(png, data);
    }
    if (bar.childNodes.length) card.append(bar);
  }
}

function csvText(rows) {
  return rows.map((r) => r.map((c) => {
    const s = c === null || c === undefined ? '' : String(c);
    return /[",\n]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s;
  }).join(',')).join('\n') + '\n';
}

function updatePrintHeader() {
  const el = document.getElementById('print-header');
  el.replaceChildren(
    h('h1', {}, 'gangue calculation report'),
    h('p', {}, `Printed ${new Date().toISOString().slice(0, 16).replace('T', ' ')} UTC · model_version ${modelVersion || 'unknown'} · ${settings} settings`),
    h('p', {}, Object.values(caseParts()).join(' · ')),
    h('p', {}, 'The inputs are the form below; verdicts, warnings and results follow it.'),
  );
}

function initPrint() {
  document.getElementById('case-print').addEventListener('click', () => {
    updatePrintHeader();
    window.print();
  });
  window.addEventListener('beforeprint', updatePrintHeader);
}

// ---- start -------------------------------------------------------------------

async function showVersion() {
  const health = await getJson('healthz');
  if (health?.version) {
    modelVersion ||= health.version;
    document.getElementById('server-version').textContent = `server ${health.version}`;
  }
}

/**
 * The guidance is open on the first visit (not on a phone) and folded after it,
 * unless the engineer left it open; one click opens it.
 */
function initGuide() {
  const guide = document.getElementById('guide');
  const KEY = 'gangue.guide';
  let seen = null;
  try {
    seen = localStorage.getItem(KEY);
    if (seen === null) localStorage.setItem(KEY, 'seen');
  } catch {
    // no storage: every visit is the first
  }
  guide.open = seen === 'open' || (seen === null && !window.matchMedia('(max-width: 600px)').matches);
  // A click on the summary is the engineer's choice (a toggle event also follows the page's own setting).
  guide.querySelector('summary').addEventListener('click', () => {
    try {
      localStorage.setItem(KEY, guide.open ? 'closed' : 'open');
    } catch {
      // no storage
    }
  });
}

async function main() {
  initGuide();
  panels.impact = initImpact();
  panels.column = initColumn();
  panels.migration = initMigration();
  panels.scene = initScene();
  initStudy();
  initSpalling();
  initTabs();
  initSharedRock();
  initCases();
  initExports();
  initPrint();

  // The forms start empty: nothing is computed until the server's defaults are in.
  const buttons = [...document.querySelectorAll('form button[type="submit"], #migration-compare-button, .settings button')];
  for (const b of buttons) b.disabled = true;
  presets = await getJson('v1/presets');
  if (!presets?.defaults) {
    document.getElementById('preset-note').textContent = 'The server\'s defaults (GET /v1/presets) could not be loaded: reload the page to compute.';
    return;
  }
  applyPresetValues();
  applySettings('recommended');
  for (const b of buttons) b.disabled = false;
  document.getElementById('preset-recommended').addEventListener('click', () => applySettings('recommended'));
  document.getElementById('preset-paper').addEventListener('click', () => applySettings('paper'));
  await showVersion();

  const { tab, encoded } = parseHash();
  showTab(tab);
  document.body.dataset.ready = 'true';
  if (encoded) openCase(decodeCase(encoded), { run: true });
}

main();
