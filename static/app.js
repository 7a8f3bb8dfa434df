// gangue web page: tabs, presets, the shared case (summary, link, recent
// cases, comparison), export buttons and the printable report.

import { getJson } from './js/api.js';
import { initCalibrate } from './js/calibrate.js';
import { initColumn } from './js/column.js';
import { setFloorLimits } from './js/floor.js';
import { applyServerDefaults, applyState, formState, setDefaults } from './js/form.js';
import { csvButton, csvText, download, fmt, h, setCsvHeader, tableRows } from './js/format.js';
import { initImpact } from './js/impact.js';
import { arrivalTargetSentence, initMigration } from './js/migration.js';
import { destroy, joinSeries, linePlot, plotDataUrl, plotPng } from './js/plot.js';
import { initScene, sceneTargetSentence, setSceneRanges } from './js/scene.js';
import { initSpalling, setSpallingDefaults } from './js/spalling.js';
import { initStudy, setStudyDefaults } from './js/study.js';

const TABS = ['scene', 'impact', 'column', 'migration', 'calibrate', 'study', 'spalling'];
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
  scene: ['rock', 'face', 'floor', 'column', 'contact'],
  impact: ['rock', 'column', 'contact', 'velocity'],
  column: ['rock', 'column', 'contact', 'velocity'],
  migration: ['rock', 'face', 'floor'],
  study: ['column'],
  spalling: [],
};

/** The uploaded floor in use ({name, sha256, summary, floor}), or null for the plane. */
function uploadedFloor() {
  return forms.migration?.floor?.current?.() ?? null;
}

/** The floor in words: the plane, or the uploaded file with its kind and sha256. */
function floorWords() {
  const up = uploadedFloor();
  if (!up) return 'Floor: the plane of the face';
  return `Floor: uploaded ${up.floor.kind === 'grid' ? 'ESRI ASCII grid' : 'GeoJSON contours'} ${up.name} (${up.summary}; sha256 ${up.sha256 ?? 'not computed'})`;
}

function caseParts() {
  const i = forms.impact;
  const m = forms.migration;
  return {
    rock: `Rock (all tabs): ${val(m, '/rock/shape')} L ${part(i, '/rock/side_length_m')}, ρ ${part(i, '/rock/density_kg_m3')}, E ${part(i, '/rock/elastic_modulus_pa')}`,
    column: `Column: D₁ ${part(i, '/column/outer_diameter_m')} / D₂ ${part(i, '/column/inner_diameter_m')}, l ${part(i, '/column/length_m')}, σy ${part(i, '/column/yield_stress_pa')}`,
    contact: `Contact: ${val(i, '/contact/law')}, E* ${val(i, '/contact/effective_modulus')}`,
    velocity: `Impact velocity ${part(i, '/velocity_m_s')}`,
    face: `Face: dip ${part(m, '/face/dip_deg')}, ${part(m, '/face/length_m')} long, μ ${val(m, '/face/friction_coefficient')}, ${val(m, '/method')}`,
    floor: floorWords(),
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
      h('span', { class: `case-part ${uses.includes(key) ? 'used' : 'unused'}${key === 'floor' && uploadedFloor() ? ' floor-badge' : ''}`, dataset: { part: key } }, text)));
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
/** The last answer of each tab ({data, request, time}), for the report. */
const lastResults = {};

/** Puts a saved case into the forms; with `run`, computes its tab. */
function openCase(state, { run = false } = {}) {
  if (!state || !state.forms) return;
  // a case saved before ensembles could stop when precise enough ran a fixed number of runs
  const scene = state.forms.scene;
  if (scene && !('local:runs_mode' in scene)) state.forms.scene = { ...scene, 'local:runs_mode': 'fixed' };
  const migration = state.forms.migration;
  if (migration && !('toggle:migration_target' in migration)) state.forms.migration = { ...migration, 'toggle:migration_target': false };
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
  const options = list.map((e, i) => h('option', { value: String(i) }, caseLabel(e)));
  document.getElementById('case-recent').replaceChildren(h('option', { value: '' }, list.length ? 'choose a case…' : '—'), ...options);
  for (const [id, pick] of [['compare-a', 1], ['compare-b', 0]]) {
    const sel = document.getElementById(id);
    const keep = sel.value;
    sel.replaceChildren(...list.map((e, i) => h('option', { value: String(i) }, caseLabel(e))));
    sel.value = keep && Number(keep) < list.length ? keep : String(Math.min(pick, Math.max(list.length - 1, 0)));
  }
  const a = document.getElementById('compare-a');
  const b = document.getElementById('compare-b');
  if (list.length > 1 && a.value === b.value) { a.value = '1'; b.value = '0'; }
}

/** The rows a result shows, for the comparison: [label, text] from the panel's tables. */
function resultRows(tab) {
  const panel = document.querySelector(`[data-panel="${tab}"]`);
  const rows = [];
  for (const table of panel.querySelectorAll('.results table:not(.u-legend)')) {
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
    case 'migration': return `${data.statistics ? `${data.statistics.runs} runs${data.statistics.target ? ` (${data.statistics.target.met ? 'precise enough' : 'target not met'})` : ''}, ` : ''}v ${fmt(data.arrival?.speed_m_s, 4)} m/s`;
    case 'scene': return data.statistics
      ? `${data.statistics.runs} runs${data.statistics.target ? ` (${data.statistics.target.met ? 'precise enough' : 'target not met'})` : ''}`
      : `${(data.impacts ?? []).length} impact(s)`;
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
  const figA = new Map(a.figures ?? []);
  const figB = new Map(b.figures ?? []);
  const figLabels = [...new Set([...figA.keys(), ...figB.keys()])];
  table.append(
    h('thead', {}, h('tr', {}, h('th', {}, ''), h('th', {}, `A: ${caseLabel(a)}`), h('th', {}, `B: ${caseLabel(b)}`))),
    h('tbody', {},
      h('tr', { class: 'group' }, h('th', { colspan: 3 }, 'Headline figures')),
      figLabels.map((l) => h('tr', { class: `headline${figA.get(l) !== figB.get(l) ? ' diff' : ''}` },
        h('th', { scope: 'row' }, l), h('td', {}, figA.get(l) ?? '—'), h('td', {}, figB.get(l) ?? '—'))),
      h('tr', { class: 'group' }, h('th', { colspan: 3 }, inputs.length ? 'Inputs that differ' : 'Same inputs')),
      inputs.map(([k, x, y]) => h('tr', { class: 'diff' }, h('th', { scope: 'row' }, k), h('td', {}, String(x ?? '—')), h('td', {}, String(y ?? '—')))),
      h('tr', { class: 'group' }, h('th', { colspan: 3 }, 'Results')),
      labels.map((l) => h('tr', { class: mapA.get(l) !== mapB.get(l) ? 'diff' : '' },
        h('th', { scope: 'row' }, l), h('td', {}, mapA.get(l) ?? '—'), h('td', {}, mapB.get(l) ?? '—')))),
  );
  overlaySupports(a, b);
}

/** The per-support risk of the two cases on one plot (scene cases), or a note why there is none. */
function overlaySupports(a, b) {
  const el = document.getElementById('compare-plot');
  destroy(el);
  if (!a.supports?.length || !b.supports?.length) {
    el.append(h('p', { class: 'note' }, 'The per-support plot is overlaid when both cases are Scene cases.'));
    return;
  }
  const ensemble = a.supports[0].length > 4 && b.supports[0].length > 4;
  const xy = (list) => {
    const cols = Math.max(1, ...list.map((r) => r[1] + 1));
    const pairs = list.map((r) => [r[0] + r[1] / (cols + 1), r[3] * 100]).sort((p, q) => p[0] - q[0]);
    return [pairs.map((p) => p[0]), pairs.map((p) => p[1])];
  };
  const joined = joinSeries([xy(a.supports), xy(b.supports)]);
  linePlot(el, {
    x: { label: 'support number', values: joined[0], ticks: (v) => (Number.isInteger(v) ? `#${v}` : '') },
    y: { label: ensemble ? 'P(exceed) (%)' : 'largest utilisation (%)' },
    series: [
      { label: `A: ${caseLabel(a)}`, values: joined[1], points: true, color: '#1d5fa8' },
      { label: `B: ${caseLabel(b)}`, values: joined[2], points: true, color: '#c8423b', dash: [5, 4] },
    ],
    height: 240,
  });
}

/** A recent case in one line: its name (if given), time, tab and headline. */
function caseLabel(e) {
  return `${e.name ? `${e.name} — ` : ''}${new Date(e.time).toLocaleTimeString()} ${e.tab}: ${e.headline}`;
}

/** The headline figures of a result, [label, text], for the comparison and the report. */
function figures(tab, data) {
  const pct = (p) => `${fmt(p * 100, 3)} %`;
  const ci = (x) => `${pct(x.probability)} [95 % interval ${fmt(x.ci95[0] * 100, 3)}–${fmt(x.ci95[1] * 100, 3)} %]`;
  switch (tab) {
    case 'scene': {
      const st = data.statistics;
      if (st) {
        const over = (st.supports ?? []).filter((e) => e.verdict === 'exceeded');
        return [
          ['Runs', `${st.runs} (seed ${st.seed})${st.target ? `. ${sceneTargetSentence(st.target)}` : ''}`],
          ['P(a rock overloads some support)', st.any_exceeded ? ci(st.any_exceeded) : '—'],
          ['Supports exceeding', `${over.length} of ${(st.supports ?? []).length}`],
          ['Reached the lower end', pct(st.outcomes?.lower_end ?? 0)],
          ['Struck a support', pct(st.outcomes?.support ?? 0)],
        ];
      }
      const imps = data.impacts ?? [];
      return [['Supports struck', String(imps.length)], ['Exceeded', String(imps.filter((i) => i.verdict === 'exceeded').length)],
        ...imps.slice(0, 3).map((i) => [`Support #${i.support} impact speed`, `${fmt(i.impact_velocity_m_s, 4)} m/s`])];
    }
    case 'migration':
      return [['Arrival speed', `${fmt(data.arrival?.speed_m_s, 5)} m/s`], ['Outcome', data.arrival?.stop_reason ?? '—'],
        ['Final position along the dip', `${fmt(data.arrival?.along_dip_m, 5)} m`],
        ...(data.statistics ? [['Runs', `${data.statistics.runs}${data.statistics.target ? `. ${arrivalTargetSentence(data.statistics.target)}` : ''}`], ['Mean arrival speed', `${fmt(data.statistics.speed_m_s?.mean, 5)} m/s`], ['p95 arrival speed', `${fmt(data.statistics.speed_m_s?.p95, 5)} m/s`]] : [])];
    case 'impact':
      return [['Impact velocity', `${val(forms.impact, '/velocity_m_s')} m/s`], ['Max force Pmax', `${fmt(data.max_force_n * 1e-3, 5)} kN`], ['Max approach δmax', `${fmt(data.max_deformation_m * 1e3, 5)} mm`]];
    case 'column':
      return Object.entries(data).filter(([, d]) => d && typeof d === 'object' && (d.absorbed_energy_j !== undefined || d.column_energy_after_contact_j !== undefined))
        .map(([m, d]) => [`${m}: column energy`, `${fmt(d.absorbed_energy_j ?? d.column_energy_after_contact_j, 5)} J`]);
    default: return [];
  }
}

/** Per-support [support, column, along_dip_m, risk, lo, hi] of a scene answer (for the overlay). */
function supportRisks(data) {
  if (data.statistics?.supports) {
    return data.statistics.supports.map((e) => {
      let worst = { probability: 0, ci95: [0, 0] };
      for (const x of Object.values(e.exceedance ?? {})) if (x.probability > worst.probability || (x.probability === worst.probability && x.ci95[1] > worst.ci95[1])) worst = x;
      return [e.support, e.column_index ?? 0, e.along_dip_m, worst.probability, worst.ci95[0], worst.ci95[1]];
    });
  }
  if (Array.isArray(data.impacts) && data.impacts.length) {
    return data.impacts.map((i) => [i.support, i.column_index ?? 0, i.along_dip_m, Math.max(0, ...(i.checks ?? []).map((c) => c.utilisation ?? 0))]);
  }
  return null;
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
    lastResults[name] = { data, request: detail.request, time: new Date() };
    document.getElementById('case-name').value = '';
    remember({ time: Date.now(), tab: name, headline: headline(name, data), link, state, rows: resultRows(name), figures: figures(name, data), supports: supportRisks(data) });
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
  // Two different cases: choosing the other's case moves the other to the next one.
  for (const [id, other] of [['compare-a', 'compare-b'], ['compare-b', 'compare-a']]) {
    document.getElementById(id).addEventListener('change', () => {
      const me = document.getElementById(id);
      const them = document.getElementById(other);
      const n = recent().length;
      if (me.value === them.value && n > 1) them.value = String((Number(me.value) + 1) % n);
      renderCompare();
    });
  }
  const nameBox = document.getElementById('case-name');
  nameBox.addEventListener('change', () => {
    const list = recent();
    if (!list.length) return;
    list[0].name = nameBox.value.trim();
    try {
      localStorage.setItem(RECENT_KEY, JSON.stringify(list));
    } catch {
      // storage full or disabled
    }
    fillRecent();
    if (!document.getElementById('compare').hidden) renderCompare();
  });
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
    // a card with its own CSV buttons (data-exports="own") gets none here
    if (tables.length && card.dataset.exports !== 'own') {
      bar.append(csvButton(`${panel}_${slug(title)}.csv`, () => tables.flatMap((t) => (t.csv ? t.csv() : tableRows(t))), 'CSV'));
    }
    for (const canvas of card.querySelectorAll('canvas.floor-plan')) {
      const png = h('button', { type: 'button', class: 'export', dataset: { png: canvas.id } }, 'PNG');
      png.addEventListener('click', () => canvas.toBlob((blob) => blob && download(`${canvas.id}.png`, blob, 'image/png'), 'image/png'));
      const data = h('button', { type: 'button', class: 'export', dataset: { csv: `${canvas.id}.csv` } }, 'CSV: where runs stopped');
      data.addEventListener('click', () => { if (canvas.csv) download(`${canvas.id}.csv`, csvText(canvas.csv())); });
      bar.append(png, data);
    }
    for (const plot of card.querySelectorAll('.plot')) {
      const png = h('button', { type: 'button', class: 'export', dataset: { png: plot.id } }, 'PNG');
      png.addEventListener('click', async () => {
        const blob = await plotPng(plot, title);
        if (blob) download(`${plot.id}.png`, blob, 'image/png');
      });
      const data = h('button', { type: 'button', class: 'export', dataset: { csv: `${plot.id}.csv` } }, 'CSV: data');
      data.addEventListener('click', () => {
        // a plot not drawn still gives a file that says why
        download(`${plot.id}.csv`, csvText(plot.csv ? plot.csv() : [[`no data: ${plot.textContent.trim() || 'nothing drawn yet'}`]]));
      });
      bar.append(png, data);
    }
    if (bar.childNodes.length) card.append(bar);
  }
}


/** The CSV header's line on the runs of the tab's last ensemble ("runs 4000 of at most 64000 (seed 42): Stopped at …"). */
function runsLines(tab) {
  const st = lastResults[tab]?.data?.statistics;
  if (!st || typeof st.runs !== 'number') return [];
  const t = st.target;
  const words = t ? (tab === 'scene' ? sceneTargetSentence(t) : arrivalTargetSentence(t)) : '';
  return [`runs ${st.runs}${t ? ` of at most ${t.max_runs}` : ''} (seed ${st.seed})${words ? `: ${words.replace(/\u00a0/g, ' ')}` : ''}`];
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

const REPORT_KEY = 'gangue.report.v1';

/** Every field of an `inputs` object as [JSON Pointer, value]; a floor file's text stands as its name and hash. */
function flatten(obj, prefix = '', out = []) {
  for (const [k, v] of Object.entries(obj ?? {})) {
    const p = `${prefix}/${k}`;
    if (k === 'esri_ascii' || k === 'geojson') out.push([p, `(the file's text: ${uploadedFloor()?.name ?? 'uploaded'})`]);
    else if (v && typeof v === 'object' && !Array.isArray(v)) flatten(v, p, out);
    else if (Array.isArray(v) && v.some((x) => x && typeof x === 'object')) v.forEach((x, i) => flatten(x, `${p}/${i}`, out));
    else out.push([p, Array.isArray(v) ? v.join(', ') : v === null ? 'null (derived by the service)' : String(v)]);
  }
  return out;
}

/** What each part of the inputs is, for the report's headings. */
const INPUT_GROUPS = [
  ['/face', 'Face and floor (migration)'], ['/rock', 'Rock'], ['/release', 'Release'], ['/method', 'Migration method'], ['/lumped_mass', 'Lumped mass'],
  ['/rigid_block', 'Rigid-block settings'], ['/monte_carlo', 'Ensemble: runs, seed and ranges'], ['/release_zones', 'Release zones'],
  ['/support_rows', 'Supports'], ['/supports', 'Supports'], ['/column', 'Column'], ['/contact', 'Contact'], ['/galerkin', 'Galerkin'],
  ['/design_limits', 'Design limits'], ['/column_model', 'Column model'], ['/impact_velocity_m_s', 'Impact velocity'],
  ['/guards', 'Guards on the columns'], ['/barriers', 'Barriers across the face (m, J)'], ['/collectors', 'Collectors across the face (m)'],
];

/**
 * The report for the safety file (what "Print report" prints): the heading fields, the case,
 * the model version, the floor with its sha256, every input of the chain, the verdicts with
 * probabilities and intervals, the plots as images and the warnings.
 */
function buildReport() {
  const tab = currentTab();
  const last = lastResults[tab];
  const report = document.getElementById('report');
  const field = (id) => document.getElementById(id).value.trim();
  const link = linkFor(caseState(tab));
  const kv = (rows) => h('table', {}, h('tbody', {}, rows.map(([k, v]) => h('tr', {}, h('th', { scope: 'row' }, k), h('td', {}, v)))));
  const up = uploadedFloor();
  const serverFloor = last?.data?.inputs?.face?.floor ?? last?.data?.migration?.inputs?.face?.floor;
  const parts = [
    h('h1', {}, 'Flying gangue: calculation report'),
    kv([
      ['Project', field('report-project') || '(not given)'], ['Face', field('report-face') || '(not given)'], ['Author', field('report-author') || '(not given)'],
      ['Case', recent()[0]?.name || '(unnamed)'], ['Date', new Date().toISOString()], ['Calculation', `${tab} (${settings} settings)`],
      ['Model version', `gangue ${modelVersion || 'unknown'}`], ['Link to this case', h('span', { class: 'report-link' }, link)],
    ]),
    h('h2', {}, 'Floor'),
    kv(up
      ? [['Floor', `uploaded ${up.floor.kind === 'grid' ? 'ESRI ASCII grid' : 'GeoJSON contours'}`], ['File', `${up.name} (${up.bytes ?? '?'} bytes; ${up.summary})`],
        ['sha256 (computed in the page)', up.sha256 ?? 'not computed'], ['sha256 (echoed by the service)', serverFloor?.sha256 ?? '—'],
        ['Map', serverFloor?.map ? `origin ${serverFloor.map.origin_m.join(', ')} m, dip direction ${serverFloor.map.dip_direction_deg}°` : 'the file\'s own frame']]
      : [['Floor', 'the plane of the face (from the dip and the length)']]),
  ];
  if (!last) {
    parts.push(h('p', {}, `Nothing computed on the ${tab} tab yet: compute it, then print the report.`));
  } else {
    const data = last.data;
    const inputs = data.inputs ?? Object.values(data).find((d) => d?.inputs)?.inputs ?? {};
    parts.push(h('h2', {}, 'Inputs of the chain (every default filled in by the service)'));
    const all = flatten(inputs);
    const used = new Set();
    for (const [prefix, words] of INPUT_GROUPS) {
      const rows = all.filter(([p]) => (p === prefix || p.startsWith(`${prefix}/`)) && !used.has(p));
      if (!rows.length) continue;
      rows.forEach(([p]) => used.add(p));
      parts.push(h('h3', {}, words), kv(rows));
    }
    const rest = all.filter(([p]) => !used.has(p));
    if (rest.length) parts.push(h('h3', {}, 'Other settings'), kv(rest));
    parts.push(h('h2', {}, 'Headline figures'), kv(figures(tab, data)));
    const verdicts = verdictRows(data);
    if (verdicts) {
      parts.push(h('h2', {}, 'Verdicts, worst first'), h('table', {},
        h('thead', {}, h('tr', {}, verdicts.head.map((c) => h('th', { scope: 'col' }, c)))),
        h('tbody', {}, verdicts.rows.map((r) => h('tr', { class: r[1] === 'EXCEEDED' ? 'verdict-exceeded' : '' }, r.map((c, i) => h('td', { class: i > 1 ? 'num' : '' }, c)))))));
    }
    const panel = document.querySelector(`[data-panel="${tab}"]`);
    const checks = [...panel.querySelectorAll('.checks-card table')].filter((t) => !t.closest('[hidden]'));
    if (checks.length) parts.push(h('h2', {}, 'Checks'), ...checks.map((t) => t.cloneNode(true)));
    // result cards marked for the report (the Scene's design, barriers and collectors, with and without protection)
    for (const card of panel.querySelectorAll('.results .card[data-report]')) {
      if (card.closest('[hidden]')) continue;
      // its note, its answer in words and every table it shows (the design card has two)
      const tables = [...card.querySelectorAll('table')].filter((t) => !t.hidden);
      const note = card.querySelector('.note')?.textContent.trim();
      const answers = [...card.querySelectorAll('p.answer')].map((p) => h('p', {}, p.textContent.trim()));
      parts.push(h('h2', {}, card.querySelector('h3')?.textContent.trim() ?? ''), ...(note ? [h('p', {}, note)] : []), ...answers, ...tables.map((t) => t.cloneNode(true)));
    }
    const figs = [];
    for (const el of panel.querySelectorAll('.results .plot, .results canvas.floor-plan, .results .view3d canvas')) {
      if (el.closest('[hidden]')) continue;
      const card = el.closest('.card');
      const title = card?.querySelector('h3')?.textContent.trim() ?? '';
      const url = el.tagName === 'CANVAS' ? el.toDataURL('image/png') : plotDataUrl(el, title);
      // the plan's legend is HTML beside it: its lines go under the image
      const legend = el.classList.contains('floor-plan') ? [...card.querySelectorAll('.floor-legend li')].map((li) => li.textContent.trim()) : [];
      if (url) {
        figs.push(h('figure', {}, h('img', { src: url, alt: el.getAttribute('aria-label') ?? title }), h('figcaption', {}, title,
          legend.length ? h('ul', {}, legend.map((t) => h('li', {}, t))) : null)));
      }
    }
    if (figs.length) parts.push(h('h2', {}, 'Plots'), ...figs);
    const warnings = [...(data.warnings ?? []), ...(data.migration?.warnings ?? [])];
    parts.push(h('h2', {}, 'Warnings'), warnings.length
      ? h('ul', {}, warnings.map((w) => h('li', {}, `${w.message} (${w.code})`)))
      : h('p', {}, 'No warnings.'));
  }
  report.replaceChildren(...parts);
  report.dataset.tab = tab;
  return report;
}

/** The verdicts of a scene (per support, worst first) or of the checks of impact and column. */
function verdictRows(data) {
  const sup = data.statistics?.supports;
  if (sup) {
    const rows = sup.map((e) => {
      let worst = { probability: 0, ci95: [0, 0] };
      let limit = '';
      for (const [l, x] of Object.entries(e.exceedance ?? {})) if (x.probability > worst.probability || (x.probability === worst.probability && x.ci95[1] > worst.ci95[1])) { worst = x; limit = l; }
      return { e, worst, limit };
    }).sort((a, b) => (b.e.verdict === 'exceeded') - (a.e.verdict === 'exceeded') || b.worst.probability - a.worst.probability || b.worst.ci95[1] - a.worst.ci95[1] || a.e.support - b.e.support);
    return {
      head: ['Support', 'Verdict', 'Along the dip (m)', 'P(exceed) (%)', '95 % interval (%)', 'Limit', 'Reached (%)'],
      rows: rows.map(({ e, worst, limit }) => [`#${e.support}${e.column_index ? `.${e.column_index}` : ''}`, e.verdict === 'exceeded' ? 'EXCEEDED' : 'OK',
        fmt(e.along_dip_m, 5), fmt(worst.probability * 100, 3), `${fmt(worst.ci95[0] * 100, 3)}–${fmt(worst.ci95[1] * 100, 3)}`, limit, fmt(e.reached_fraction * 100, 4)]),
    };
  }
  if (Array.isArray(data.impacts) && data.impacts.length) {
    return {
      head: ['Support', 'Verdict', 'Along the dip (m)', 'Impact speed (m/s)', 'Largest utilisation (%)'],
      rows: data.impacts.map((i) => [`#${i.support}`, i.verdict === 'exceeded' ? 'EXCEEDED' : 'OK', fmt(i.along_dip_m, 5), fmt(i.impact_velocity_m_s, 4),
        fmt(Math.max(0, ...(i.checks ?? []).map((c) => c.utilisation ?? 0)) * 100, 4)]),
    };
  }
  return null;
}

function initPrint() {
  // The report's heading fields are kept in the browser.
  let saved = {};
  try {
    saved = JSON.parse(localStorage.getItem(REPORT_KEY) ?? '{}');
  } catch {
    saved = {};
  }
  for (const id of ['report-project', 'report-face', 'report-author']) {
    const el = document.getElementById(id);
    el.value = saved[id] ?? '';
    el.addEventListener('change', () => {
      saved[id] = el.value;
      try {
        localStorage.setItem(REPORT_KEY, JSON.stringify(saved));
      } catch {
        // no storage
      }
    });
  }
  document.getElementById('case-print').addEventListener('click', () => {
    updatePrintHeader();
    buildReport();
    document.body.classList.add('printing-report');
    window.print();
  });
  window.addEventListener('beforeprint', updatePrintHeader);
  window.addEventListener('afterprint', () => document.body.classList.remove('printing-report'));
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
  // Every saved CSV starts with what it is: the model version, the date, the case's link (and the floor file).
  setCsvHeader(() => {
    const up = uploadedFloor();
    return [`gangue ${modelVersion || 'unknown'}`, `date ${new Date().toISOString()}`, `case ${linkFor(caseState(currentTab()))}`,
      ...(up ? [`floor ${up.name} sha256 ${up.sha256 ?? 'not computed'}`] : []), ...runsLines(currentTab())];
  });
  panels.impact = initImpact();
  panels.column = initColumn();
  panels.migration = initMigration();
  panels.scene = initScene();
  initCalibrate();
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
