// Scene tab: POST /v1/scene (api.md), the engineer's question in one request:
// release → migration → impact on the first support reached → column →
// checks, for one run or a seeded Monte Carlo ensemble. The rock, the face and
// the contact are the Migration and Impact tabs' case; this form adds the
// supports, the release zones, the ensemble and the design limits.

import { columnChecks, impactChecks, renderChecks } from './checks.js';
import { buildForm, merge } from './form.js';
import { csvButton, csvNumber, fmt, h, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, joinSeries, linePlot, plotMessage } from './plot.js';
import { clearFloorViews, defaultMapGrid, floorModel, offFloor, renderFloorViews } from './floorview.js';
import { deviceLabel, initDeviceEditors, requestDevices } from './devices.js';
import { postJson } from './api.js';

/** The most runs an ensemble "until precise enough" may take, by migration method (the rigid block is far slower). */
const MAX_RUNS = { lumped_mass: 64000, rigid_block: 2000 };

/** Why the release across the face starts from the page's own range. */
const RELEASE_ACROSS = 'an assumed range across the face (the server draws none unless asked)';

const SCENE_GROUPS = [
  {
    legend: 'Supports',
    fields: [
      {
        local: 'supports', label: 'Supports', kind: 'select', choice: { value: 'rows', why: 'the server\'s default is one support at the lower end; the page checks the rows of supports' },
        options: [['rows', 'rows (Table 1 numbering)'], ['lower_end', 'one at the lower end']],
        hint: 'rows: support k stands at the lowest position − (k − 1) × spacing',
      },
      { pointer: '/support_rows/lowest_along_dip_m', label: 'Lowest support along the dip', unit: 'm' },
      { pointer: '/support_rows/spacing_m', label: 'Spacing', unit: 'm' },
      { pointer: '/support_rows/count', label: 'Number of supports', kind: 'integer' },
      {
        local: 'across', label: 'Column position across the face', unit: 'm',
        hint: 'one column of each support stands there (the server\'s default); a rock can pass beside it',
      },
    ],
  },
  {
    legend: 'Impact',
    fields: [
      {
        pointer: '/column_model', label: 'Column model', kind: 'select', settings: true,
        options: [['coupled', 'coupled (recommended)'], ['decoupled', 'decoupled (the paper)']],
        hint: 'coupled conserves energy; decoupled overstates the column energy',
      },
      {
        pointer: '/impact_velocity_m_s', label: 'Impact velocity (skip migration)', unit: 'm/s', placeholder: 'migrate',
        hint: 'given: every support is struck at this speed and no migration runs',
      },
    ],
  },
  {
    legend: 'Release',
    fields: [
      {
        local: 'release_zones', label: 'Release points', kind: 'select', choice: { value: 'table1', why: 'an ensemble from the spalling zones; the server releases at the given point unless asked' },
        options: [['table1', 'Table 1 spalling zones'], ['custom', 'my zones (a table of rows)'], ['point', 'a single point'], ['release', 'Migration tab\'s point']],
        hint: 'Table 1: upper third 23.3 %, middle 58.3 %, lower 18.4 %; zones are drawn from in the ensemble (Monte Carlo only)',
      },
    ],
  },
  {
    legend: 'Monte Carlo ensemble',
    pointer: '/monte_carlo',
    toggle: { name: 'scene_monte_carlo', checked: true },
    note: 'Restitution at every impact; release points from the zones; the rock\'s size and density drawn in the paper\'s study ranges.',
    fields: [
      {
        local: 'runs_mode', label: 'Runs', kind: 'select', choice: { value: 'target', why: 'the server runs a fixed number unless a target is sent; the page stops when the answer is precise enough' },
        options: [['target', 'until precise enough'], ['fixed', 'a fixed number of runs']],
        hint: 'until precise enough: checked at 1 000, 2 000, 4 000, … runs, stopping at the first count where the probability\'s 95 % interval is narrow enough',
      },
      {
        pointer: '/monte_carlo/target/statistic', label: 'Precise enough for', kind: 'select', choice: { value: 'any_exceeded', why: 'the headline probability' },
        options: [['any_exceeded', 'any support overloaded'], ['every_support', 'every support\'s probability']],
        hint: 'any support overloaded: the probability that a rock overloads some support; every support: the widest interval over the supports',
      },
      {
        pointer: '/monte_carlo/target/half_width', label: 'Precision ±', unit: 'points', exp: -2, choice: { value: 0.5, why: 'half a percentage point: a 2 % probability known as 1.5–2.5 %' },
        hint: 'half-width of the Wilson 95 % interval, in percentage points (in (0, 50])',
      },
      {
        local: 'max_runs', target: '/monte_carlo/runs', label: 'Most runs allowed', kind: 'integer', choice: { value: MAX_RUNS.lumped_mass, why: 'enough for ± 0.5 points at any probability' },
        hint: 'default 64 000 with the lumped mass; the rigid block is far slower (it integrates the tumbling block), so 2 000 by default with it',
      },
      { pointer: '/monte_carlo/runs', label: 'Runs', kind: 'integer' },
      { pointer: '/monte_carlo/seed', label: 'Seed', kind: 'integer' },
      { pointer: '/monte_carlo/release_across_m/min', label: 'Release across the face, from', unit: 'm', choice: { value: 0, why: RELEASE_ACROSS } },
      {
        pointer: '/monte_carlo/release_across_m/max', label: 'to', unit: 'm', choice: { value: 1.8, why: RELEASE_ACROSS },
        hint: 'uniform; where along the strike the rock leaves the wall (an assumed range: set your face\'s)',
      },
      { local: 'vary_rock', label: 'Vary size 0.2–0.3 m and density 2000–3000 kg/m³', kind: 'checkbox' },
    ],
  },
  {
    legend: 'Guards on the columns',
    pointer: '/guards',
    toggle: { name: 'scene_guards', checked: false },
    note: 'A guard on every support\'s column takes up to its rating of a striking rock\'s impact energy; the column takes the rest.',
    fields: [
      {
        local: 'guard_rating', label: 'Energy rating of each guard', unit: 'J', choice: { value: 500, why: 'a starting rating to edit' },
        hint: 'a rock within the rating never loads the column; past it the column is struck at √(v² − 2R/m)',
      },
    ],
  },
  {
    legend: 'Barriers across the face',
    pointer: '/barriers',
    toggle: { name: 'scene_barriers', checked: false },
    note: 'A barrier stops a rock that reaches its line below its height with kinetic energy within its rating, lets a faster one through with the rating taken off, '
      + 'and is overtopped by a rock at or above its height. Along the dip in [0, face length] m; across from ≤ to in [−1000, 1000] m, both empty for the whole face; '
      + 'height in (0, 100] m; rating in [0, 10⁹] kJ (sent in J).',
    fields: [],
  },
  {
    legend: 'Collectors across the face',
    pointer: '/collectors',
    toggle: { name: 'scene_collectors', checked: false },
    note: 'A collector records each rock\'s speed, energies and passing height where it crosses its line, changing nothing. Along the dip in [0, face length] m; across as for a barrier.',
    fields: [],
  },
  {
    legend: 'Design the protection',
    pointer: '/design',
    toggle: { name: 'scene_design', checked: false },
    note: 'What protection must take: over the ensemble\'s own seeded runs, the smallest guard rating on each guarded support column and the fewest barriers '
      + 'across the face that bring each column\'s exceedance within the acceptable probability (judged on the upper bound of its Wilson 95 % interval). '
      + 'Needs the Monte Carlo ensemble.',
    fields: [
      {
        pointer: '/design/acceptable_probability', label: 'Acceptable probability', unit: '%', exp: -2,
        choice: { value: 1, why: 'a starting 1 % to edit (the server has no default)' },
        hint: 'in (0, 100) %, sent as a fraction: the largest exceedance probability a support column may have',
      },
      {
        local: 'design_guards', target: '/design/guards', label: 'Guards on', kind: 'select', choice: { value: 'every', why: 'the server\'s default guards every support' },
        options: [['every', 'every support'], ['listed', 'listed supports'], ['none', 'none']],
        hint: 'each guarded column gets the smallest energy rating that makes it acceptable',
      },
      {
        local: 'design_barriers', target: '/design/barriers', label: 'Barriers', kind: 'select', choice: { value: 'off', why: 'the server searches no barriers unless asked' },
        options: [['off', 'off'], ['every_kth', 'candidates in front of every k-th support']],
        hint: 'a greedy search for the fewest barriers, each with its height and rating',
      },
      {
        local: 'design_every_kth', target: '/design/barriers/every_kth_support', label: 'A candidate in front of every k-th support, k', kind: 'integer',
        choice: { value: 10, why: 'a candidate every 10 supports' },
        hint: 'k in [1, 1000], counted from the top of the face; fewer candidates run fewer ensembles',
      },
      {
        local: 'design_offset', target: '/design/barriers/offset_m', label: 'Candidate up-slope of its support by', unit: 'm',
        choice: { value: 1, why: 'the server\'s default 1 m' }, hint: 'in [0, 10] m',
      },
    ],
  },
  {
    legend: 'Release rate (overloads per year)',
    pointer: '/release_rate',
    toggle: { name: 'scene_release_rate', checked: false },
    note: 'Give the rocks released per year, or events counted over a period (the Spalling tab sends its count). Needs the ensemble.',
    fields: [
      { pointer: '/release_rate/rocks_per_year', label: 'Rocks released per year', unit: '1/year', placeholder: 'from the count' },
      { pointer: '/release_rate/observed_events', label: 'Events counted', kind: 'integer', placeholder: 'none' },
      {
        pointer: '/release_rate/observed_period_years', label: 'over', unit: 'years', placeholder: 'none',
        hint: 'e.g. Table 1: 643 spalling events in 9 months (0.75 years); the count\'s own uncertainty widens the intervals',
      },
    ],
  },
  {
    legend: 'Design limits',
    pointer: '/design_limits',
    fields: [
      { pointer: '/design_limits/stress_utilisation', label: 'Stress utilisation σ/σy', unit: '' },
      { pointer: '/design_limits/max_force_n', label: 'Rated force', unit: 'kN', exp: 3, placeholder: 'none' },
      { pointer: '/design_limits/absorbed_energy_j', label: 'Design energy', unit: 'J', placeholder: 'none' },
      {
        pointer: '/design_limits/acceptable_probability', label: 'Acceptable probability', unit: '',
        choice: { value: 0.01, why: 'the server\'s default 0 marks any exceedance; the page shows a 1 % threshold' },
        hint: 'a support whose exceedance probability is above this is marked exceeded',
      },
    ],
  },
];

const DISTRIBUTIONS = [
  ['impact_velocity_m_s', 'Impact speed', 'm/s', 1],
  ['max_deformation_m', 'Max approach δmax', 'mm', 1e3],
  ['max_force_n', 'Max force Pmax', 'kN', 1e-3],
  ['absorbed_energy_j', 'Column energy', 'J', 1],
  ['stress_utilisation', 'Stress utilisation', '%', 100],
];
const LIMIT_WORDS = { stress_utilisation: 'stress utilisation σ/σy', max_force_n: 'rated force (N)', absorbed_energy_j: 'design energy (J)' };
const STAT_COLUMNS = ['mean', 'std', 'min', 'p05', 'p50', 'p95', 'p99', 'max'];
const OUTCOMES = [['support', 'struck a support'], ['barrier', 'stopped by a barrier'], ['lower_end', 'reached the lower end'], ['at_rest', 'came to rest'],
  ['left_floor', 'left the floor'], ['end_time', 'still moving at the end time']];

const RED = '#c8423b';
const GREEN = '#2a8f4f';
const GREY = '#7d8794';
const BLUE = '#1d5fa8';
const BARRIER = '#7a3e12';
const COLLECTOR = '#6b3fa0';
/** A barrier the design search proposes, not yet applied (teal long dashes, as on the floor plan). */
const PROPOSED = '#0097a7';

/** Barriers (solid, labelled with height and rating), proposed barriers (teal, long dashes) and collectors (dashed) on a uPlot of along the dip against across. */
function drawDeviceLines(u, devices) {
  const { ctx } = u;
  const r = devicePixelRatio;
  ctx.save();
  ctx.beginPath();
  ctx.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height);
  ctx.clip();
  const [ylo, yhi] = [u.scales.y.min, u.scales.y.max];
  for (const [k, d] of devices.entries()) {
    const x = u.valToPos(d.s, 'x', true);
    const [a, b] = d.across ?? [ylo, yhi];
    const colour = d.kind === 'barrier' ? BARRIER : d.kind === 'proposed' ? PROPOSED : COLLECTOR;
    ctx.strokeStyle = ctx.fillStyle = colour;
    ctx.lineWidth = (d.kind === 'collector' ? 2 : 3) * r;
    ctx.setLineDash(d.kind === 'barrier' ? [] : d.kind === 'proposed' ? [10 * r, 5 * r] : [6 * r, 4 * r]);
    ctx.beginPath();
    ctx.moveTo(x, u.valToPos(Math.max(a, ylo), 'y', true));
    ctx.lineTo(x, u.valToPos(Math.min(b, yhi), 'y', true));
    ctx.stroke();
    ctx.font = `${11 * r}px system-ui, sans-serif`;
    ctx.textAlign = 'left';
    ctx.textBaseline = 'alphabetic';
    const text = deviceLabel(d);
    const w = ctx.measureText(text).width;
    const tx = x + 4 * r + w <= u.bbox.left + u.bbox.width ? x + 4 * r : x - 4 * r - w;
    const ty = u.bbox.top + (12 + 15 * k) * r;
    ctx.fillStyle = 'rgba(255, 255, 255, 0.85)';
    ctx.fillRect(tx - 2 * r, ty - 11 * r, w + 4 * r, 14 * r);
    ctx.fillStyle = colour;
    ctx.fillText(text, tx, ty);
  }
  ctx.restore();
}

/** The impact speed statistic a row sends to the Impact and Column tabs. */
const SEND_STATS = { p50: 'median', p95: 'p95', max: 'largest' };

/** Exceeded first, then the larger exceedance probability (or utilisation), then its upper bound, then the support number. */
function byRisk(a, b) {
  return (b.verdict === 'exceeded') - (a.verdict === 'exceeded') || b.risk - a.risk
    || (b.riskCi?.[1] ?? 0) - (a.riskCi?.[1] ?? 0) || a.support - b.support || (a.column_index ?? 0) - (b.column_index ?? 0);
}

const SORTS = {
  risk: byRisk,
  p: (a, b) => b.risk - a.risk || (b.riskCi?.[1] ?? 0) - (a.riskCi?.[1] ?? 0) || a.support - b.support,
  util: (a, b) => (b.util ?? -1) - (a.util ?? -1) || a.support - b.support,
  support: (a, b) => a.support - b.support || (a.column_index ?? 0) - (b.column_index ?? 0),
};
const SORT_WORDS = { risk: 'exceeded first, then by P(exceed)', p: 'P(exceed), largest first', util: 'stress utilisation, largest first', support: 'support number' };

const FILTERS = {
  all: { words: 'all supports', test: () => true },
  exceeded: { words: 'exceeded only', test: (e) => e.verdict === 'exceeded' },
  risk: { words: 'P(exceed) above 0', test: (e) => e.risk > 0 },
  reached: { words: 'reached by a rock', test: (e) => e.single || e.reached_fraction > 0 },
  util: { words: 'stress utilisation at or above 100 %', test: (e) => (e.util ?? 0) >= 1 },
};

function niceCeil(v) {
  if (!(v > 0)) return 1;
  const p = 10 ** Math.floor(Math.log10(v));
  return [1, 2, 2.5, 5, 10].map((m) => m * p).find((m) => m >= v);
}

/** The paper's study ranges of the rock (GET /v1/presets `study`), drawn when "vary" is ticked. */
let rockRanges = {};

/** Takes the rock's study ranges from GET /v1/presets. */
export function setSceneRanges(study) {
  rockRanges = Object.fromEntries((study?.parameters ?? []).map((p) => [p.name, { min: p.min, max: p.max }]));
}

export function initScene() {
  const form = document.getElementById('scene-form');
  const status = document.getElementById('scene-status');
  const warnings = document.getElementById('scene-warnings');
  const empty = document.getElementById('scene-empty');
  const box = document.getElementById('scene-results');
  const summary = document.getElementById('scene-summary');
  const table = document.getElementById('scene-table');
  const distSelect = document.getElementById('scene-dist-support');
  const distTable = document.getElementById('scene-dist-table');
  const distPlot = document.getElementById('scene-dist-plot');
  const planList = document.getElementById('scene-plan');
  const plots = {
    side: document.getElementById('scene-side-plot'),
    plan: document.getElementById('scene-plan-plot'),
    support: document.getElementById('scene-support-plot'),
  };
  const impactForm = document.getElementById('impact-form');
  const columnForm = document.getElementById('column-form');
  const migrationForm = document.getElementById('migration-form');
  const supportSummary = document.getElementById('scene-support-summary');
  const filter = document.getElementById('scene-filter');
  const sort = document.getElementById('scene-sort');
  const sendStat = document.getElementById('scene-send-stat');
  const sourceNotes = [document.getElementById('impact-source'), document.getElementById('column-source')];
  buildForm(form, SCENE_GROUPS);
  const runsSync = initRunsChoice(form, migrationForm);
  const releaseEditor = initReleaseEditor(form, migrationForm);
  const deviceEditors = initDeviceEditors(form);
  const designEditor = initDesignEditor(form);
  // A velocity typed by hand no longer comes from the Scene.
  impactForm.addEventListener('input', (ev) => {
    if (ev.target.dataset?.pointer === '/velocity_m_s') for (const note of sourceNotes) note.hidden = true;
  });
  impactForm.addEventListener('reset', () => { for (const note of sourceNotes) note.hidden = true; });
  for (const el of [filter, sort, sendStat]) el.addEventListener('change', () => last && renderTable(last, supportEntries(last)));

  const rowFields = ['/support_rows/lowest_along_dip_m', '/support_rows/spacing_m', '/support_rows/count']
    .map((p) => form.querySelector(`[data-pointer="${p}"]`));
  const across = form.querySelector('[data-local="across"]');
  const kind = form.querySelector('[data-local="supports"]');
  const syncSupports = () => {
    for (const el of [...rowFields, across]) el.disabled = kind.value !== 'rows';
  };
  kind.addEventListener('change', syncSupports);
  form.addEventListener('reset', () => setTimeout(syncSupports));
  syncSupports();

  let last = null;
  let runsCsv = null;
  /** Per support entry (support.column), the same runs without protection; null when not compared. */
  let unprotected = null;

  const panel = initPanel({
    name: 'scene',
    form,
    forms: [form, migrationForm, impactForm, columnForm],
    endpoint: 'v1/scene',
    status,
    progress: document.getElementById('scene-progress'),
    unit: 'runs',
    build: ([own, mig, imp, col]) => {
      const m = mig.request;
      const request = merge({
        method: m.method, face: m.face, rock: m.rock, release: m.release, lumped_mass: m.lumped_mass,
      }, { rock: imp.request.rock, column: imp.request.column, contact: imp.request.contact });
      request.galerkin = { ...(col.request.galerkin ?? {}) };
      // The struck column belongs to the supports (api.md): every support gets the Impact and Column tabs' column.
      const column = { ...request.column, ...(col.request.column ?? {}) };
      delete request.column;
      migrationForm.floor?.apply(request, mig.local);
      const own2 = structuredClone(own.request);
      if (own.local.supports === 'rows') {
        const rows = own2.support_rows ?? {};
        rows.across_m = [own.local.across];
        rows.column = column;
        own2.support_rows = rows;
      } else {
        delete own2.support_rows;
        request.supports = [{ along_dip_m: m.face.length_m, across_m: null, column }];
      }
      Object.assign(request, own2);
      if (typeof own.local.guard_rating === 'number') {
        const count = request.support_rows ? request.support_rows.count : 1;
        request.guards = Array.from({ length: count }, (_, k) => ({ support: k + 1, energy_rating_j: own.local.guard_rating }));
      }
      if (request.column_model === 'decoupled') delete request.galerkin.modes;
      else if (request.galerkin.mode_shapes && request.galerkin.mode_shapes !== 'exact') delete request.galerkin.mode_shapes;
      releaseEditor.apply(request, own.local, migrationForm.floor?.current?.() ?? null);
      deviceEditors.apply(request, own.local, m.face.length_m);
      designEditor.apply(request, own.local);
      if (request.monte_carlo) runsSync.apply(request, own.local);
      if (request.monte_carlo) {
        if (own.local.release_zones === 'table1') request.release_zones = 'table1';
        if (request.monte_carlo.release_across_m) request.monte_carlo.release_across_m = { distribution: 'uniform', ...request.monte_carlo.release_across_m };
        if (own.local.vary_rock) {
          request.monte_carlo.side_length_m = { distribution: 'uniform', ...rockRanges['rock.side_length_m'] };
          request.monte_carlo.density_kg_m3 = { distribution: 'uniform', ...rockRanges['rock.density_kg_m3'] };
        }
        // the nominal run's path is drawn on the floor
        request.migration_output = {
          runs_csv: true, trajectory: true, sample_interval_s: m.output?.sample_interval_s,
          // the ensemble's per-cell maps, drawn on the floor view
          maps: defaultMapGrid(request, migrationForm.floor?.current?.() ?? null, request.monte_carlo.runs),
        };
      } else {
        request.migration_output = { trajectory: true, sample_interval_s: m.output?.sample_interval_s };
      }
      return request;
    },
    stream: (request) => Boolean(request.monte_carlo),
    busy: (request) => (request.monte_carlo?.target
      ? `Running up to ${groupDigits(request.monte_carlo.runs)} runs along the face, stopping when precise enough…`
      : request.monte_carlo ? `Running ${request.monte_carlo.runs} runs along the face…` : 'Computing the scene…'),
    progressText: (p, request) => targetProgress(p, request),
    render,
    clear,
  });

  distSelect.addEventListener('change', () => last && renderDistributions(last));
  document.getElementById('scene-table').closest('.card').append(
    csvButton('scene_runs.csv', () => (runsCsv ? runsCsv.trim().split('\n').map((l) => l.split(',')) : [['no per-run table: run an ensemble']]), 'CSV: every run'));

  function clear() {
    last = null;
    runsCsv = null;
    empty.hidden = false;
    box.hidden = true;
    summary.replaceChildren();
    table.replaceChildren();
    supportSummary.textContent = '';
    distTable.replaceChildren();
    renderProtection(null);
    renderDesign(null);
    renderDevices(null);
    renderUnprotected(null);
    planList.replaceChildren();
    showWarnings(warnings, []);
    Object.values(plots).forEach(destroy);
    clearFloorViews('scene');
  }

  function render(data, request) {
    last = data;
    runsCsv = data.runs_csv ?? data.migration?.runs_csv ?? null;
    empty.hidden = true;
    box.hidden = false;
    showWarnings(warnings, data.warnings);
    planList.replaceChildren(...(data.plan ?? []).map((p) =>
      h('li', { class: `plan-${p.status}` }, h('strong', {}, p.stage), ` ${p.status === 'ran' ? 'ran' : 'skipped'}: ${p.reason ?? ''}`)));
    const entries = supportEntries(data);
    renderSummary(data, entries);
    renderTable(data, entries);
    renderProtection(data);
    renderDesign(data, request);
    renderDevices(data, request);
    renderUnprotected(null);
    renderSupportChart(entries, acceptableOf(data));
    renderFace(data, entries, request);
    const verdicts = new Map(entries.map((e) => [`${e.support}.${e.column_index ?? 0}`, e.verdict]));
    renderFloorViews('scene', {
      inputs: data.inputs ?? data.migration?.inputs, request: request ?? data.inputs, upload: migrationForm.floor?.current?.() ?? null,
      tr: data.migration?.trajectory ?? null, runsCsv, arrival: data.migration?.arrival ?? null, verdicts, maps: data.maps ?? null,
      devices: [...requestDevices(request ?? data.inputs), ...proposedDevices(data)],
    });
    distSelect.replaceChildren(...entries.map((e, i) => h('option', { value: String(i) }, label(e))));
    const worst = entries.reduce((b, e, i) => ((e.risk ?? -1) > (entries[b]?.risk ?? -1) ? i : b), 0);
    distSelect.value = String(worst);
    renderDistributions(data);
    if (data.statistics && (request?.guards?.length || request?.barriers?.length)) compareUnprotected(data, request);
  }

  /** The pending request without protection (aborted when a new answer or an error comes). */
  let bareRun = null;

  /**
   * The same request without guards, barriers and collectors (the same seed, so the same
   * draws run for run: common random numbers), sent beside the answer; per support the
   * exceedance without and with protection.
   */
  async function compareUnprotected(data, request) {
    const bare = structuredClone(request);
    delete bare.guards;
    delete bare.barriers;
    delete bare.collectors;
    delete bare.design;
    // the runs the answer used, all of them: an ensemble that stopped when precise enough is
    // compared over the same runs, not over as many as the bare one would need
    if (bare.monte_carlo?.target) {
      delete bare.monte_carlo.target;
      bare.monte_carlo.runs = data.statistics.runs;
    }
    // the per-support statistics are all that is compared
    delete bare.migration_output;
    const controller = new AbortController();
    bareRun = controller;
    const note = document.getElementById('scene-unprotected-note');
    document.getElementById('scene-unprotected-card').hidden = false;
    note.textContent = `Computing the same ${data.statistics.runs} runs without protection…`;
    let answer;
    try {
      answer = await postJson('v1/scene', bare, { signal: controller.signal });
    } catch (err) {
      if (err.name === 'AbortError') return;
      answer = { ok: false, problem: { detail: err.message } };
    }
    if (bareRun !== controller || last !== data) return;
    bareRun = null;
    if (!answer.ok) {
      note.textContent = `The run without protection was refused: ${answer.problem?.detail ?? answer.problem?.title ?? 'no answer'}.`;
      return;
    }
    renderUnprotected(data, answer.data, request);
  }

  /** The with/without table and the risk plot's second series; null clears both. */
  function renderUnprotected(data, bare = null, request = null) {
    const card = document.getElementById('scene-unprotected-card');
    const el = document.getElementById('scene-unprotected');
    if (!bare) {
      bareRun?.abort();
      bareRun = null;
      unprotected = null;
      card.hidden = true;
      el.replaceChildren();
      delete el.csv;
      return;
    }
    const withP = supportEntries(data);
    const without = new Map(supportEntries(bare).map((e) => [`${e.support}.${e.column_index ?? 0}`, e]));
    unprotected = without;
    const st = data.statistics;
    const what = [request?.guards?.length ? `the guards on ${request.guards.length} column${request.guards.length === 1 ? '' : 's'}` : '',
      request?.barriers?.length ? `${request.barriers.length} barrier${request.barriers.length === 1 ? '' : 's'}` : ''].filter(Boolean).join(' and ');
    document.getElementById('scene-unprotected-note').textContent = `The same ${st.runs} seeded runs (seed ${st.seed}) computed twice, with ${what} and without any protection: `
      + 'common random numbers, so each run meets the same rock, release and restitutions and the difference is the protection\'s, not chance. '
      + `P(exceed) is each support's largest over the design limits, with its Wilson 95 % interval. Any support overloaded: ${fmt(bare.statistics.any_exceeded.probability * 100, 3)} % without, `
      + `${fmt(st.any_exceeded.probability * 100, 3)} % with.`;
    const quietWords = (shown, all, quiet) => ` Shown: the ${shown} of ${all} support entries some run overloaded, with or without protection, the largest drop first`
      + `${quiet ? `; the other ${quiet} had no overloading run either way (all are in the CSV)` : ''}.`;
    const pc = (p, ci) => `${fmt(p * 100, 3)} [${fmt(ci[0] * 100, 2)}–${fmt(ci[1] * 100, 2)}]`;
    const rows = withP.map((e) => ({ e, b: without.get(`${e.support}.${e.column_index ?? 0}`) }));
    // shown: the supports some run overloaded with or without protection, the largest change first; the CSV has them all
    const shown = rows.filter(({ e, b }) => e.risk > 0 || (b?.risk ?? 0) > 0)
      .sort((x, y) => ((y.b?.risk ?? 0) - y.e.risk) - ((x.b?.risk ?? 0) - x.e.risk) || (y.b?.risk ?? 0) - (x.b?.risk ?? 0) || x.e.support - y.e.support);
    const quiet = rows.length - shown.length;
    document.getElementById('scene-unprotected-note').append(quietWords(shown.length, rows.length, quiet));
    el.csv = () => [['support', 'column_index', 'along_dip_m', 'p_exceed_without', 'p_exceed_without_ci95_low', 'p_exceed_without_ci95_high',
      'p_exceed_with', 'p_exceed_with_ci95_low', 'p_exceed_with_ci95_high'],
    ...rows.map(({ e, b }) => [e.support, e.column_index ?? 0, csvNumber(e.along_dip_m), csvNumber(b?.risk), csvNumber(b?.riskCi[0]), csvNumber(b?.riskCi[1]),
      csvNumber(e.risk), csvNumber(e.riskCi[0]), csvNumber(e.riskCi[1])])];
    el.replaceChildren(
      h('thead', {}, h('tr', {}, ['Support', 'Along the dip (m)', 'P(exceed) without protection (%) [95 % CI]', 'P(exceed) with protection (%) [95 % CI]', 'Change (points)']
        .map((c) => h('th', { scope: 'col' }, c)))),
      h('tbody', {}, shown.map(({ e, b }) => h('tr', { class: e.verdict === 'exceeded' ? 'verdict-exceeded' : '', dataset: { support: `${e.support}.${e.column_index ?? 0}` } },
        h('th', { scope: 'row' }, `#${e.support}${e.column_index ? `.${e.column_index}` : ''}`),
        h('td', { class: 'num' }, fmt(e.along_dip_m, 5)),
        h('td', { class: 'num', dataset: { without: String(b?.risk ?? '') } }, b ? pc(b.risk, b.riskCi) : '—'),
        h('td', { class: 'num', dataset: { with: String(e.risk) } }, pc(e.risk, e.riskCi)),
        h('td', { class: 'num' }, b ? fmt((e.risk - b.risk) * 100, 3) : '—')))),
    );
    card.hidden = false;
    renderSupportChart(withP, acceptableOf(data));
  }

  /** The design answer whose barriers were applied, kept to show beside the re-run (its check). */
  let appliedDesign = null;

  /**
   * "What protection must take": the design search's answer as a table an engineer can copy
   * into a specification (per support column the guard rating, the runs needing it, the
   * exceedance with its interval and whether it is acceptable; the proposed barriers and each
   * column's exceedance with them), a tab-separated copy, CSVs, and a button that applies the
   * barriers (and guards) and re-runs the scene. After applying, the re-run's answer carries no
   * design: the card then shows the applied design beside the re-run's exceedances.
   */
  function renderDesign(data, request = null) {
    const card = document.getElementById('scene-design-card');
    const note = document.getElementById('scene-design-note');
    const answer = document.getElementById('scene-design-answer');
    const barriersTable = document.getElementById('scene-design-barriers');
    const table = document.getElementById('scene-design-table');
    const actions = document.getElementById('scene-design-actions');
    for (const el of [answer, barriersTable, table, actions]) el.replaceChildren();
    barriersTable.hidden = true;
    let design = data?.design ?? null;
    let check = null;
    let positions = data?.statistics?.supports ?? [];
    if (!design && appliedDesign && data?.statistics) {
      ({ design, positions } = appliedDesign);
      check = new Map(supportEntries(data).map((e) => [`${e.support}.${e.column_index ?? 0}`, e]));
      appliedDesign = null;
    }
    card.hidden = !design;
    if (!design) return;
    const a = design.acceptable_probability;
    const bd = design.barriers ?? null;
    const guarded = design.supports.filter((e) => e.guarded);
    const pc = (x) => `${fmt(x.probability * 100, 3)} [${fmt(x.ci95[0] * 100, 2)}–${fmt(x.ci95[1] * 100, 2)}]`;
    const yes = (ok) => (ok ? 'yes' : 'no');
    const name = (e) => `#${e.support}${e.column_index ? `.${e.column_index}` : ''}`;
    const at = (i) => positions[i]?.along_dip_m;
    note.textContent = `Judged against an acceptable probability of ${fmt(a * 100, 4)} % on the upper bound of each support column's Wilson 95 % interval, `
      + `over the ensemble's own ${groupDigits(design.runs)} seeded runs.`
      + (guarded.length ? ` Guards (${guarded.length} column${guarded.length === 1 ? '' : 's'}): ${design.method}; the rating is the smallest that makes the column acceptable, `
        + 'and a column that stays above it with every run held gets the rating that holds every run that reached it.' : ' No guard searched.')
      + (bd ? ` Barriers: ${bd.method}` : '')
      + (check ? ' The proposed protection was applied (the Barriers rows, and the Guards group with the largest rating) and the scene re-run with the same runs: the last column is that re-run, the check.' : '');
    const words = [];
    if (design.runs_needed !== undefined && design.runs_needed !== null) {
      words.push(h('p', { class: 'answer design-runs-needed', dataset: { out: 'design.runs_needed' } },
        h('strong', {}, 'Not achievable with these runs: '),
        `needs at least ${groupDigits(design.runs_needed)} runs for 0 exceedances to be acceptable (with ${groupDigits(design.runs)} runs even no exceedance has an upper bound above ${fmt(a * 100, 4)} %).`));
    }
    if (guarded.length) {
      const over = guarded.filter((e) => !e.acceptable);
      const need = guarded.filter((e) => e.rating_j > 0);
      const top = need.reduce((m, e) => Math.max(m, e.rating_j), 0);
      words.push(h('p', { class: 'answer', dataset: { out: 'design.guards' } }, need.length
        ? `Guards needed on ${need.length} of ${guarded.length} guarded support columns, the largest rated ${fmt(top / 1e3, 4)} kJ; `
        : `No guarded column needs a guard: all ${guarded.length} are acceptable as they are; `,
      over.length ? `${over.length} of the guarded columns stay above the acceptable probability (${over.slice(0, 8).map(name).join(', ')}${over.length > 8 ? ', …' : ''}).` : 'every guarded column is then acceptable.'));
    }
    if (bd) {
      const over = bd.supports.filter((e) => !e.acceptable);
      words.push(h('p', { class: 'answer', dataset: { out: 'design.barriers' } },
        bd.barriers.length ? `${bd.barriers.length} barrier${bd.barriers.length === 1 ? '' : 's'} proposed from ${bd.candidates.length} candidates (${bd.ensembles} ensembles run); with them `
          : `No barrier proposed from ${bd.candidates.length} candidates (${bd.ensembles} ensembles run); `,
        bd.all_acceptable ? 'every support column is acceptable.' : `${over.length} support column${over.length === 1 ? '' : 's'} stay above the acceptable probability (${over.slice(0, 8).map(name).join(', ')}${over.length > 8 ? ', …' : ''}).`));
      if (bd.barriers.length) {
        barriersTable.hidden = false;
        barriersTable.append(h('caption', {}, 'Proposed barriers across the face (whole width), in the order chosen'),
          h('thead', {}, h('tr', {}, ['Barrier', 'Along the dip (m)', 'In front of support', 'Height (m)', 'Energy rating (kJ)'].map((c) => h('th', { scope: 'col' }, c)))),
          h('tbody', {}, bd.barriers.map((b, i) => h('tr', { dataset: { barrier: String(i + 1) } },
            h('th', { scope: 'row' }, `Barrier ${i + 1}`),
            h('td', { class: 'num', dataset: { out: 'along_dip_m' } }, fmt(b.along_dip_m, 6)),
            h('td', { class: 'num', dataset: { out: 'support' } }, `#${b.support}`),
            h('td', { class: 'num', dataset: { out: 'height_m' } }, fmt(b.height_m, 4)),
            h('td', { class: 'num', dataset: { out: 'energy_rating_kj' } }, fmt(b.energy_rating_j / 1e3, 4))))));
      }
    }
    if (!words.length) words.push(h('p', { class: 'answer' }, design.all_acceptable ? 'Every support column is acceptable.' : 'Some support columns stay above the acceptable probability.'));
    answer.append(...words);

    const rows = design.supports.map((e, i) => ({ e, i, r: bd?.supports[i] ?? null, c: check?.get(`${e.support}.${e.column_index ?? 0}`) ?? null }));
    const withGuard = guarded.length ? 'with the guard' : 'as it is';
    table.append(h('caption', {}, 'Per support column'),
      h('thead', {}, h('tr', {}, ['Support', 'Along the dip (m)', 'Guard rating (kJ)', 'Runs needing a guard', `Exceedance ${withGuard} (%) [95 % CI]`, 'Acceptable',
        ...(bd ? ['Exceedance with the barriers (%) [95 % CI]', 'Acceptable with the barriers'] : []),
        ...(check ? ['Re-run with them applied (%) [95 % CI]'] : [])].map((c) => h('th', { scope: 'col' }, c)))),
      h('tbody', {}, rows.map(({ e, i, r, c }) => h('tr', { class: (r ? !r.acceptable : !e.acceptable) ? 'verdict-exceeded' : '', dataset: { support: `${e.support}.${e.column_index ?? 0}` } },
        h('th', { scope: 'row' }, name(e)),
        h('td', { class: 'num' }, fmt(at(i), 5)),
        h('td', { class: 'num', dataset: { out: 'rating' } }, e.guarded ? fmt(e.rating_j / 1e3, 4) : 'not guarded'),
        h('td', { class: 'num', dataset: { out: 'runs_needing_guard' } }, String(e.runs_needing_guard)),
        h('td', { class: 'num', dataset: { out: 'exceedance' } }, pc(e.exceedance)),
        h('td', { dataset: { out: 'acceptable' } }, yes(e.acceptable)),
        ...(bd ? [h('td', { class: 'num', dataset: { out: 'barrier_exceedance' } }, r ? pc(r.exceedance) : '—'),
          h('td', { dataset: { out: 'barrier_acceptable' } }, r ? yes(r.acceptable) : '—')] : []),
        ...(check ? [h('td', { class: 'num', dataset: { out: 'check' } }, c ? pc({ probability: c.risk, ci95: c.riskCi }) : '—')] : [])))));

    // a copy for a spreadsheet: display units in the headers, plain numbers in the cells
    const n = (x, sig = 6) => (x === null || x === undefined ? '' : String(Number(x.toPrecision(sig))));
    const pcts = (x) => [n(x.probability * 100), n(x.ci95[0] * 100), n(x.ci95[1] * 100)];
    const tsv = () => {
      const out = [];
      if (bd?.barriers.length) {
        out.push(['Barrier', 'Along the dip (m)', 'In front of support', 'Height (m)', 'Energy rating (kJ)']);
        bd.barriers.forEach((b, i) => out.push([i + 1, n(b.along_dip_m, 12), b.support, n(b.height_m), n(b.energy_rating_j / 1e3)]));
        out.push([]);
      }
      out.push(['Support', 'Column', 'Along the dip (m)', 'Guard rating (kJ)', 'Runs needing a guard', `Exceedance ${withGuard} (%)`, '95 % CI low (%)', '95 % CI high (%)', 'Acceptable',
        ...(bd ? ['Exceedance with the barriers (%)', '95 % CI low (%)', '95 % CI high (%)', 'Acceptable with the barriers'] : [])]);
      for (const { e, i, r } of rows) {
        out.push([e.support, e.column_index ?? 0, n(at(i), 12), e.guarded ? n(e.rating_j / 1e3) : '', e.runs_needing_guard, ...pcts(e.exceedance), yes(e.acceptable),
          ...(bd ? [...(r ? pcts(r.exceedance) : ['', '', '']), r ? yes(r.acceptable) : ''] : [])]);
      }
      return `${out.map((r) => r.join('\t')).join('\n')}\n`;
    };
    table.tsv = tsv;
    const copied = h('span', { class: 'note', id: 'scene-design-copied', role: 'status' });
    const copy = h('button', { type: 'button', class: 'export', id: 'scene-design-copy' }, 'Copy as table');
    copy.addEventListener('click', async () => {
      const text = tsv();
      const ok = await copyText(text);
      copied.textContent = ok ? `Copied ${text.trim().split('\n').length} lines, tab-separated: paste them into a spreadsheet.` : 'The browser refused the copy: use the CSV.';
    });
    const csvRows = () => [['support', 'column_index', 'along_dip_m', 'guarded', 'guard_rating_j', 'runs_needing_guard', 'exceedance', 'exceedance_ci95_low', 'exceedance_ci95_high', 'acceptable',
      ...(bd ? ['barrier_exceedance', 'barrier_exceedance_ci95_low', 'barrier_exceedance_ci95_high', 'barrier_acceptable'] : [])],
    ...rows.map(({ e, i, r }) => [e.support, e.column_index ?? 0, csvNumber(at(i)), e.guarded, csvNumber(e.rating_j), e.runs_needing_guard,
      csvNumber(e.exceedance.probability), csvNumber(e.exceedance.ci95[0]), csvNumber(e.exceedance.ci95[1]), e.acceptable,
      ...(bd ? [csvNumber(r?.exceedance.probability), csvNumber(r?.exceedance.ci95[0]), csvNumber(r?.exceedance.ci95[1]), r?.acceptable ?? ''] : [])])];
    actions.append(copy, csvButton('scene_design.csv', csvRows, 'CSV: per support column'));
    if (bd?.barriers.length) {
      actions.append(csvButton('scene_design_barriers.csv', () => [['barrier', 'support', 'along_dip_m', 'height_m', 'energy_rating_j'],
        ...bd.barriers.map((b, i) => [i + 1, b.support, csvNumber(b.along_dip_m), csvNumber(b.height_m), csvNumber(b.energy_rating_j)])], 'CSV: proposed barriers'));
    }
    const guardsToApply = guarded.filter((e) => e.rating_j > 0);
    if (!check && (bd?.barriers.length || guardsToApply.length)) {
      const what = [bd?.barriers.length ? 'barriers' : '', guardsToApply.length ? 'guards' : ''].filter(Boolean).join(' and ');
      const apply = h('button', { type: 'button', class: 'primary', id: 'scene-design-apply' }, `Apply the proposed ${what} and re-run`);
      apply.addEventListener('click', () => applyDesign(design, request, data.statistics?.supports ?? []));
      actions.append(apply);
      if (guardsToApply.length) {
        const top = Math.max(...guardsToApply.map((e) => e.rating_j));
        actions.append(h('p', { class: 'note', id: 'scene-design-guard-note' }, `The Guards group takes one rating for every support: applying puts the largest, ${fmt(top / 1e3, 4)} kJ, `
          + 'on every column (more than most need); the table gives each column\'s own rating for the specification.'));
      }
    }
    actions.append(copied);
  }

  /**
   * Fills the Barriers rows with the proposed barriers (after the ones the search kept), the
   * Guards group with the largest proposed rating, the same runs (a fixed count, the seed
   * unchanged), unticks the design search and re-runs the scene: its answer is the check.
   */
  function applyDesign(design, request, positions) {
    const change = (el) => el.dispatchEvent(new Event('change', { bubbles: true }));
    const tick = (name, on) => {
      const box = form.querySelector(`input[name="${name}"]`);
      if (box.checked !== on) { box.checked = on; change(box); }
    };
    const proposed = design.barriers?.barriers ?? [];
    if (proposed.length) {
      const store = form.querySelector('[data-local="barriers_json"]');
      const kept = request?.barriers?.length ? JSON.parse(store.value || '[]') : [];
      tick('scene_barriers', true);
      store.value = JSON.stringify([...kept, ...proposed.map((b) => [String(b.along_dip_m), '', '', String(b.height_m), String(b.energy_rating_j / 1e3)])]);
      change(store);
    }
    const ratings = design.supports.filter((e) => e.guarded && e.rating_j > 0).map((e) => e.rating_j);
    if (ratings.length) {
      tick('scene_guards', true);
      const rating = form.querySelector('[data-local="guard_rating"]');
      rating.value = String(Math.max(...ratings));
      change(rating);
    }
    // the same runs: an ensemble that stopped when precise enough is re-run at the count it used
    if (request?.monte_carlo?.target) {
      const mode = form.querySelector('[data-local="runs_mode"]');
      mode.value = 'fixed';
      change(mode);
      const runs = form.querySelector('[data-pointer="/monte_carlo/runs"]');
      runs.value = String(design.runs);
      change(runs);
    }
    tick('scene_design', false);
    appliedDesign = { design, positions };
    form.requestSubmit();
  }

  /**
   * What each barrier and collector saw: position, reached share, a barrier's stopped /
   * broken through / overtopped shares (Wilson 95 %), and the design values at the line.
   */
  function renderDevices(data, request = null) {
    const card = document.getElementById('scene-devices-card');
    const el = document.getElementById('scene-devices');
    const note = document.getElementById('scene-devices-note');
    el.replaceChildren();
    delete el.csv;
    const st = data?.statistics;
    const list = [...(st?.barriers ?? []).map((d, i) => ({ d, kind: 'barrier', i: i + 1 })), ...(st?.collectors ?? []).map((d, i) => ({ d, kind: 'collector', i: i + 1 }))];
    const asked = (request?.barriers?.length ?? 0) + (request?.collectors?.length ?? 0);
    card.hidden = !list.length && !asked;
    if (card.hidden) return;
    const m = data.migration;
    const nominal = m?.arrival?.stop_reason === 'barrier'
      ? ` The nominal run was stopped by a barrier at ${fmt(m.arrival.along_dip_m, 4)} m along the dip.` : '';
    const lost = m?.energy?.barriers_j ? ` Barriers took ${fmt(m.energy.barriers_j / 1e3, 4)} kJ from the nominal run.` : '';
    if (!list.length) {
      note.textContent = `A single run: switch on the Monte Carlo ensemble for what each barrier and collector saw.${nominal}${lost}`;
      return;
    }
    const pct = (x) => (x ? `${fmt(x.probability * 100, 3)} [${fmt(x.ci95[0] * 100, 2)}–${fmt(x.ci95[1] * 100, 2)}]` : '—');
    const bound = (v, scale) => (v === null || v === undefined ? 'none' : fmt(v * scale, 3));
    const dv = (x, scale = 1) => (x ? `${fmt(x.design_value * scale, 4)} [${bound(x.design_ci95[0], scale)}–${bound(x.design_ci95[1], scale)}]` : 'not reached');
    const p = list.find(({ d }) => d.values)?.d.values.design_percentile ?? data.inputs?.design_percentile ?? 0.95;
    note.textContent = `Over ${st.runs} runs (seed ${st.seed}): the share of runs that reached each line within its range, what a barrier did with them, `
      + `and the rock's state at the line: the ${fmt(p * 100, 3)} % design value over the runs that reached it, with its distribution-free 95 % interval `
      + `("none": too few runs for that bound). Stopped by a barrier, all lines: ${fmt((st.outcomes?.barrier ?? 0) * 100, 4)} % of the runs.${nominal}${lost}`;
    const across = (d) => (d.across_m ? `${fmt(d.across_m[0], 4)} to ${fmt(d.across_m[1], 4)}` : 'whole face');
    const barriers = list.some(({ kind }) => kind === 'barrier');
    el.append(
      // the line and what it saw first: on a phone they show without scrolling sideways
      h('thead', {}, h('tr', {}, ['Line', 'Reached (%) [95 % CI]',
        ...(barriers ? ['Stopped (%) [95 % CI]', 'Broken through (%) [95 % CI]', 'Overtopped (%) [95 % CI]'] : []),
        `Speed at p${fmt(p * 100, 3)} (m/s) [95 % CI]`, `Kinetic energy at p${fmt(p * 100, 3)} (kJ) [95 % CI]`, `Passing height at p${fmt(p * 100, 3)} (m) [95 % CI]`,
        'Along the dip (m)', 'Across (m)', ...(barriers ? ['Height (m)', 'Rating (kJ)'] : [])]
        .map((c) => h('th', { scope: 'col' }, c)))),
      h('tbody', {}, list.map(({ d, kind, i }) => h('tr', { dataset: { device: `${kind}_${i}` } },
        h('th', { scope: 'row' }, `${kind === 'barrier' ? 'Barrier' : 'Collector'} ${i} at ${fmt(d.along_dip_m, 4)} m`),
        h('td', { class: 'num', dataset: { out: 'reached' } }, pct(d.reached)),
        ...(barriers ? [h('td', { class: 'num', dataset: { out: 'stopped' } }, pct(d.outcomes?.stopped)),
          h('td', { class: 'num', dataset: { out: 'broken_through' } }, pct(d.outcomes?.broken_through)),
          h('td', { class: 'num', dataset: { out: 'overtopped' } }, pct(d.outcomes?.overtopped))] : []),
        h('td', { class: 'num', dataset: { out: 'speed' } }, dv(d.values?.speed_m_s)),
        h('td', { class: 'num', dataset: { out: 'kinetic_energy' } }, dv(d.values?.kinetic_energy_j, 1e-3)),
        h('td', { class: 'num', dataset: { out: 'passing_height' } }, dv(d.values?.passing_height_m)),
        h('td', { class: 'num' }, fmt(d.along_dip_m, 5)),
        h('td', { class: 'num' }, across(d)),
        ...(barriers ? [h('td', { class: 'num' }, d.height_m === undefined ? '—' : fmt(d.height_m, 4)),
          h('td', { class: 'num' }, d.energy_rating_j === undefined ? '—' : fmt(d.energy_rating_j / 1e3, 4))] : [])))),
    );
    // The CSV: SI numbers, each share and design value with its interval as two columns.
    const share = (x) => [csvNumber(x?.probability), csvNumber(x?.ci95?.[0]), csvNumber(x?.ci95?.[1])];
    const value = (x) => [csvNumber(x?.design_value), csvNumber(x?.design_ci95?.[0]), csvNumber(x?.design_ci95?.[1])];
    const QUANTITIES = ['speed_m_s', 'kinetic_energy_j', 'translational_energy_j', 'rotational_energy_j', 'passing_height_m'];
    el.csv = () => [['line', 'index', 'along_dip_m', 'across_from_m', 'across_to_m', 'height_m', 'energy_rating_j', 'reached', 'reached_ci95_low', 'reached_ci95_high',
      ...['stopped', 'broken_through', 'overtopped'].flatMap((k) => [k, `${k}_ci95_low`, `${k}_ci95_high`]), 'design_percentile',
      ...QUANTITIES.flatMap((q) => [`${q}_design`, `${q}_design_ci95_low`, `${q}_design_ci95_high`])],
    ...list.map(({ d, kind, i }) => [kind, i, csvNumber(d.along_dip_m), csvNumber(d.across_m?.[0]), csvNumber(d.across_m?.[1]), csvNumber(d.height_m), csvNumber(d.energy_rating_j),
      ...share(d.reached), ...share(d.outcomes?.stopped), ...share(d.outcomes?.broken_through), ...share(d.outcomes?.overtopped), csvNumber(d.values?.design_percentile),
      ...QUANTITIES.flatMap((q) => value(d.values?.[q]))])];
  }

  /**
   * One row per support entry, from the ensemble statistics or the single run's impacts.
   * `risk` is the largest exceedance probability over the limits (ensemble) or the largest
   * utilisation (single run); `riskCi` its 95 % interval; `util` the stress utilisation
   * (p95 over the runs, or the single run's).
   */
  function supportEntries(data) {
    if (data.statistics?.supports) {
      return data.statistics.supports.map((s) => {
        let worst = null;
        for (const [limit, x] of Object.entries(s.exceedance ?? {})) {
          if (!worst || x.probability > worst.probability || (x.probability === worst.probability && x.ci95[1] > worst.ci95[1])) worst = { limit, ...x };
        }
        return { ...s, risk: worst?.probability ?? 0, riskCi: worst?.ci95 ?? [0, 0], riskLimit: worst?.limit ?? null, util: s.stress_utilisation?.p95 ?? null };
      });
    }
    return (data.impacts ?? []).map((imp) => {
      const worst = Math.max(0, ...(imp.checks ?? []).map((c) => c.utilisation ?? 0));
      const stress = (imp.checks ?? []).find((c) => c.limit === 'stress_utilisation');
      return { ...imp, risk: worst, util: stress?.value ?? null, single: true };
    });
  }

  /** The acceptable exceedance probability the answer was judged against. */
  function acceptableOf(data) {
    const given = data.inputs?.design_limits?.acceptable_probability;
    if (typeof given === 'number') return given;
    const v = Number(form.querySelector('[data-pointer="/design_limits/acceptable_probability"]')?.value);
    return Number.isFinite(v) ? v : 0;
  }

  function label(e) {
    return `#${e.support}${e.column_index ? `.${e.column_index}` : ''} at ${fmt(e.along_dip_m, 4)} m`;
  }

  function verdictBadge(v) {
    return h('span', { class: `badge ${v === 'exceeded' ? 'exceeded' : v === 'ok' ? 'ok' : 'invalid'}` },
      v === 'exceeded' ? 'EXCEEDED' : v === 'ok' ? 'OK' : String(v ?? '—'));
  }

  function renderSummary(data, entries) {
    summary.replaceChildren();
    const st = data.statistics;
    if (st) {
      const any = st.any_exceeded;
      summary.append(h('p', { class: 'answer' },
        any ? h('span', {}, 'Probability that a released rock overloads some support: ',
          h('strong', { dataset: { out: 'statistics.any_exceeded.probability' } }, `${fmt(any.probability * 100, 3)} %`),
          ` (95 % interval ${fmt(any.ci95[0] * 100, 3)}–${fmt(any.ci95[1] * 100, 3)} %), over ${st.runs} runs, seed ${st.seed}. `) : '',
        `${entries.filter((e) => e.verdict === 'exceeded').length} of ${entries.length} support entries exceed the acceptable probability of ${fmt(acceptableOf(data) * 100, 3)} %.`));
      // an ensemble "until precise enough": where it stopped and how precise it is
      if (st.target) {
        summary.append(h('p', { class: `answer target-outcome ${st.target.met ? 'met' : 'unmet'}`, dataset: { out: 'statistics.target' } },
          `${sceneTargetSentence(st.target)}.`));
      }
      summary.append(exceededAnswer(entries));
      if (st.outcomes) {
        summary.append(h('div', { class: 'table-scroll' }, h('table', { class: 'results-table' },
          h('thead', {}, h('tr', {}, h('th', {}, 'Outcome of the runs'), h('th', { class: 'num' }, 'share'))),
          h('tbody', {}, OUTCOMES.filter(([k]) => st.outcomes[k] !== undefined).map(([k, words]) =>
            h('tr', {}, h('th', { scope: 'row' }, words), h('td', { class: 'num', dataset: { out: `statistics.outcomes.${k}` } }, `${fmt(st.outcomes[k] * 100, 4)} %`)))))));
      }
    } else {
      const impacts = data.impacts ?? [];
      if (!impacts.length) {
        const a = data.migration?.arrival;
        const words = { barrier: 'was stopped by a barrier', at_rest: 'came to rest', left_floor: 'left the floor', lower_end: 'reached the lower end', end_time: 'was still moving at the end time' };
        summary.append(h('p', { class: 'answer' }, 'The rock reached no support', a ? ` (it ${words[a.stop_reason] ?? a.stop_reason.replace(/_/g, ' ')} at ${fmt(a.along_dip_m, 4)} m along the dip).` : '.'));
        // where and past which boundary a run left the floor (warning left_floor)
        const left = (data.migration?.warnings ?? []).find((w) => w.code === 'left_floor');
        if (left) summary.append(h('p', {}, left.message));
      }
      if (impacts.length > 1) summary.append(exceededAnswer(entries));
      for (const imp of impacts) appendImpact(imp);
    }
    if (st) for (const imp of data.impacts ?? []) appendImpact(imp);
  }

  /** The supports that exceed, by number and position, worst first. */
  function exceededAnswer(entries) {
    const over = entries.filter((e) => e.verdict === 'exceeded').sort(byRisk);
    if (!over.length) {
      return h('p', { class: 'answer', dataset: { out: 'scene.exceeded' } }, 'No support exceeds: every support is within the limits.');
    }
    const shown = over.slice(0, 12);
    const items = shown.map((e) => h('li', { dataset: { support: String(e.support) } },
      h('strong', {}, `#${e.support}${e.column_index ? `.${e.column_index}` : ''}`), ` at ${fmt(e.along_dip_m, 4)} m along the dip: `,
      e.single ? `utilisation ${fmt(e.risk * 100, 3)} %`
        : `P(exceed) ${fmt(e.risk * 100, 3)} % [95 % interval ${fmt(e.riskCi[0] * 100, 2)}–${fmt(e.riskCi[1] * 100, 2)} %]${e.riskLimit ? `, ${LIMIT_WORDS[e.riskLimit] ?? e.riskLimit}` : ''}`));
    return h('div', { class: 'answer exceeded-list', dataset: { out: 'scene.exceeded' } },
      h('p', {}, h('strong', {}, over.length === 1 ? 'The support that exceeds:' : `The ${over.length} supports that exceed, worst first:`)),
      h('ol', {}, items),
      over.length > shown.length ? h('p', {}, `and ${over.length - shown.length} more (see the table below).`) : '');
  }

  /** One impact in words, its server checks and the page's validity checks of its impact and column. */
  function appendImpact(imp) {
    const nominal = imp.nominal ? 'Nominal run (no random draws): ' : '';
    let words;
    if (imp.outcome === 'capacity_exceeded') {
      words = `support ${label(imp)} struck at ${fmt(imp.impact_velocity_m_s, 4)} m/s, past the contact law's capacity` +
        `${imp.max_velocity_m_s ? ` (it takes at most ${fmt(imp.max_velocity_m_s, 4)} m/s)` : ''}: counted as exceeding every limit. `;
    } else if (imp.outcome === 'no_impact') {
      words = `support ${label(imp)} reached at under 1e-6 m/s: no impact. `;
    } else {
      words = `support ${label(imp)} struck at ${fmt(imp.impact_velocity_m_s, 4)} m/s: `;
    }
    summary.append(h('p', { class: 'answer' }, nominal, words, verdictBadge(imp.verdict), ' ',
      sendButton(imp.impact_velocity_m_s, `${imp.nominal ? 'the nominal run\'s' : 'the single run\'s'} impact speed at support ${label(imp)}`)));
    const checks = [
      ...(imp.checks ?? []).map((c) => ({
        key: `design.${c.limit}`,
        label: `Design limit: ${LIMIT_WORDS[c.limit] ?? c.limit}`,
        value: c.value ?? null,
        allowed: c.allowed,
        ratio: c.utilisation ?? null,
        unit: '',
        verdict: c.exceeded ? 'exceeded' : 'ok',
        note: c.value === undefined ? 'past the contact law\'s capacity' : '',
      })),
      ...(imp.impact ? impactChecks(imp.impact) : []),
      ...(imp.column ? columnChecks(imp.column).filter((c) => c.key !== 'stress_utilisation') : []),
    ];
    const box = h('div', { class: 'table-scroll' });
    renderChecks(box, checks, `impact${imp.support}.`);
    summary.append(box);
  }

  function sendButton(speed, source, text = 'Send to Impact and Column') {
    const ok = typeof speed === 'number' && speed > 0;
    const b = h('button', {
      type: 'button', class: 'chip send', disabled: !ok,
      title: ok ? `Send ${fmt(speed, 4)} m/s (${source}) to the Impact and Column tabs and compute` : 'no impact speed to send',
    }, text);
    b.addEventListener('click', () => sendImpact(speed, source));
    return b;
  }

  /** One click: the speed into the Impact tab's velocity; Impact and Column say where it came from and compute. */
  function sendImpact(speed, source) {
    const v = impactForm.querySelector('[data-pointer="/velocity_m_s"]');
    v.value = String(Number(speed.toPrecision(6)));
    v.dispatchEvent(new Event('change', { bubbles: true }));
    for (const note of sourceNotes) {
      note.textContent = `Velocity ${fmt(Number(v.value), 6)} m/s from the Scene: ${source}.`;
      note.hidden = false;
    }
    document.getElementById('tab-impact').click();
    impactForm.requestSubmit();
    columnForm.requestSubmit();
  }

  function renderTable(data, entries) {
    const ensemble = Boolean(data.statistics);
    const limits = ensemble
      ? [...new Set(entries.flatMap((e) => Object.keys(e.exceedance ?? {})))]
      : [...new Set(entries.flatMap((e) => (e.checks ?? []).map((c) => c.limit)))];
    const perLimit = ensemble && limits.length > 1 ? limits : [];
    const stat = sendStat.value;
    const statWords = SEND_STATS[stat];
    // Support, verdict and P(exceed) first: on a phone they show without scrolling sideways.
    const head = ensemble
      ? ['Support', 'Verdict', 'P(exceed) (%) [95 % CI]', 'Along the dip (m)', 'Column', 'Across (m)', 'Reached (%)', 'Capacity exceeded (%)',
        'Median impact speed (m/s)', 'p95 stress utilisation (%)', ...perLimit.map((l) => `P(${l} exceeded) (%) [95 % CI]`), `Send the ${statWords}`]
      : ['Support', 'Verdict', 'Largest utilisation (%)', 'Along the dip (m)', 'Column', 'Across (m)', 'Impact speed (m/s)',
        ...limits.map((l) => `${l}: value / allowed`), 'Send'];
    const rows = entries.map((e, i) => ({ e, i })).filter(({ e }) => FILTERS[filter.value].test(e));
    rows.sort((a, b) => SORTS[sort.value](a.e, b.e));
    // The CSV: numbers only, each interval as two columns, empty where no run reached the support.
    table.csv = () => {
      const n = (v) => csvNumber(v);
      if (ensemble) {
        return [['support', 'column_index', 'along_dip_m', 'across_m', 'verdict', 'p_exceed', 'p_exceed_ci95_low', 'p_exceed_ci95_high', 'worst_limit',
          'reached_fraction', 'capacity_exceeded_fraction', 'impact_speed_p50_m_s', `impact_speed_${stat}_m_s`, 'stress_utilisation_p95',
          ...limits.flatMap((l) => [`p_${l}`, `p_${l}_ci95_low`, `p_${l}_ci95_high`])],
        ...rows.map(({ e }) => [e.support, e.column_index ?? 0, n(e.along_dip_m), n(e.across_m), e.verdict, n(e.risk), n(e.riskCi[0]), n(e.riskCi[1]), e.riskLimit ?? '',
          n(e.reached_fraction), n(e.capacity_exceeded_fraction ?? 0), n(e.impact_velocity_m_s?.p50), n(e.impact_velocity_m_s?.[stat]), n(e.stress_utilisation?.p95),
          ...limits.flatMap((l) => [n(e.exceedance?.[l]?.probability), n(e.exceedance?.[l]?.ci95?.[0]), n(e.exceedance?.[l]?.ci95?.[1])])])];
      }
      return [['support', 'column_index', 'along_dip_m', 'across_m', 'verdict', 'largest_utilisation', 'impact_speed_m_s', ...limits.flatMap((l) => [`${l}_value`, `${l}_allowed`])],
        ...rows.map(({ e }) => [e.support, e.column_index ?? 0, n(e.along_dip_m), n(e.across_m), e.verdict, n(e.risk), n(e.impact_velocity_m_s),
          ...limits.flatMap((l) => { const c = (e.checks ?? []).find((x) => x.limit === l); return [n(c?.value), n(c?.allowed)]; })])];
    };
    const ci = (x) => (x ? `${fmt(x.probability * 100, 3)} [${fmt(x.ci95[0] * 100, 2)}–${fmt(x.ci95[1] * 100, 2)}]` : '—');
    table.replaceChildren(
      h('caption', { class: 'table-count' }, `${rows.length} of ${entries.length} support entries shown (${FILTERS[filter.value].words}; ${SORT_WORDS[sort.value]})`),
      h('thead', {}, h('tr', {}, head.map((c) => h('th', { scope: 'col' }, c)))),
      h('tbody', {}, rows.map(({ e, i }) => {
        const first = [h('th', { scope: 'row' }, `#${e.support}`), h('td', {}, verdictBadge(e.verdict))];
        const place = [h('td', { class: 'num' }, fmt(e.along_dip_m, 5)), h('td', { class: 'num' }, String(e.column_index ?? 0)),
          h('td', { class: 'num' }, e.across_m === null || e.across_m === undefined ? 'spans' : fmt(e.across_m, 4))];
        if (ensemble) {
          const speed = e.impact_velocity_m_s?.[stat];
          return h('tr', { class: `verdict-${e.verdict}`, dataset: { support: String(i) } }, first,
            h('td', { class: 'num', dataset: { p: String(e.risk) } }, ci({ probability: e.risk, ci95: e.riskCi })),
            place,
            h('td', { class: 'num' }, fmt(e.reached_fraction * 100, 4)),
            h('td', { class: 'num' }, fmt((e.capacity_exceeded_fraction ?? 0) * 100, 4)),
            h('td', { class: 'num' }, e.impact_velocity_m_s ? fmt(e.impact_velocity_m_s.p50, 4) : 'never reached'),
            h('td', { class: 'num' }, e.stress_utilisation ? fmt(e.stress_utilisation.p95 * 100, 4) : '—'),
            perLimit.map((l) => h('td', { class: 'num' }, ci(e.exceedance?.[l]))),
            h('td', {}, e.impact_velocity_m_s
              ? sendButton(speed, `the ${statWords} impact speed at support ${label(e)} over ${data.statistics.runs} runs`, `${stat === 'p50' ? 'median' : stat} ${fmt(speed, 4)} m/s`)
              : ''));
        }
        return h('tr', { class: `verdict-${e.verdict}`, dataset: { support: String(i) } }, first,
          h('td', { class: 'num' }, fmt(e.risk * 100, 4)),
          place,
          h('td', { class: 'num' }, fmt(e.impact_velocity_m_s, 5)),
          limits.map((l) => {
            const c = (e.checks ?? []).find((x) => x.limit === l);
            return h('td', { class: 'num' }, c ? `${fmt(c.value, 4)} / ${fmt(c.allowed, 4)}` : '—');
          }),
          h('td', {}, sendButton(e.impact_velocity_m_s, `the single run's impact speed at support ${label(e)}`, `${fmt(e.impact_velocity_m_s, 4)} m/s`)));
      })),
    );
  }

  /**
   * What each column can take: per support and design limit, the allowed impact speed and
   * energy of the case's rock, the ensemble's design speed (p95) against it, and with a release
   * rate the expected overloads per year and the return period.
   */
  function renderProtection(data) {
    const card = document.getElementById('scene-protection-card');
    const el = document.getElementById('scene-protection');
    const note = document.getElementById('scene-protection-note');
    const allowed = data?.allowed_impacts ?? [];
    card.hidden = !allowed.length;
    el.replaceChildren();
    if (!allowed.length) return;
    const stats = new Map((data.statistics?.supports ?? []).map((s) => [`${s.support}.${s.column_index ?? 0}`, s]));
    const rock = data.inputs?.rock ?? {};
    const face = data.statistics?.any_overloads_per_year;
    const years = (t) => (t === null || t === undefined ? 'never' : t >= 1 ? `${fmt(t, 3)} years` : t * 365.25 >= 1 ? `${fmt(t * 365.25, 3)} days` : `${fmt(t * 8766, 3)} hours`);
    note.textContent = `Allowed: the fastest impact of the case's rock (side ${fmt(rock.side_length_m, 3)} m, ${fmt(rock.density_kg_m3, 4)} kg/m³) each column takes `
      + 'within the limit (the inverse of the chain, to 1e-9).'
      + (data.statistics ? ` Design speed: the ${fmt((data.inputs?.design_percentile ?? 0.95) * 100, 3)} % design value of the impact speeds of the runs that reached the support; design ÷ allowed above 100 % means the design impact exceeds the limit.` : '')
      + (data.inputs?.guards ? ' Behind a guard of rating R the column takes a rock arriving at √(v² + 2R/m); design ÷ allowed is then against that speed.' : '')
      + (face ? ` Overloads of some support: ${fmt(face.per_year, 4)} per year [${fmt(face.ci95_per_year[0], 3)}–${fmt(face.ci95_per_year[1], 3)}], one every ${years(face.return_period_years)}.` : '');
    const ENDS = { limit: 'the limit', capacity: 'the contact capacity', speed_range: 'none up to 1000 m/s', nothing: 'exceeded at any speed' };
    const rows = allowed.flatMap((a) => {
      const s = stats.get(`${a.support}.${a.column_index ?? 0}`);
      const f = s?.overloads_per_year ?? null;
      const g = s?.guard ?? null;
      return a.limits.map((l) => ({ a, l, f, g }));
    });
    const guarded = rows.some((r) => r.g);
    // the most loaded first: overloads per year, then design ÷ allowed, then the support number
    const key = (r) => [-(r.f?.per_year ?? -1), -(r.l.design_utilisation ?? -1), r.a.support, r.a.column_index ?? 0];
    rows.sort((x, y) => { const [a, b] = [key(x), key(y)]; const i = a.findIndex((v, k) => v !== b[k]); return i < 0 ? 0 : a[i] - b[i]; });
    const rate = rows.some((r) => r.f);
    el.csv = () => [['support', 'column_index', 'along_dip_m', 'limit', 'allowed', 'allowed_impact_speed_m_s', 'allowed_kinetic_energy_j', 'ended_by',
      'design_impact_speed_m_s', 'design_over_allowed', 'overloads_per_year', 'overloads_per_year_ci95_low', 'overloads_per_year_ci95_high', 'return_period_years',
      'guard_energy_rating_j', 'behind_guard_impact_speed_m_s', 'guard_held_fraction', 'guard_broken_through_fraction'],
    ...rows.map(({ a, l, f, g }) => [a.support, a.column_index ?? 0, csvNumber(a.along_dip_m), l.limit, csvNumber(l.allowed), csvNumber(l.impact_velocity_m_s),
      csvNumber(l.kinetic_energy_j), l.ended_by, csvNumber(a.design_impact_velocity_m_s), csvNumber(l.design_utilisation), csvNumber(f?.per_year),
      csvNumber(f?.ci95_per_year?.[0]), csvNumber(f?.ci95_per_year?.[1]), csvNumber(f?.return_period_years),
      csvNumber(g?.energy_rating_j), csvNumber(l.behind_guard_impact_velocity_m_s), csvNumber(g?.held?.probability), csvNumber(g?.broken_through?.probability)])];
    el.append(
      h('thead', {}, h('tr', {}, ['Support', 'Design limit', 'Allowed impact speed (m/s)', 'Allowed energy (J)', 'Ended by',
        ...(data.statistics ? ['Design speed (m/s)', 'Design ÷ allowed (%)'] : []),
        ...(rate ? ['Overloads per year [95 % CI]', 'One every'] : []),
        ...(guarded ? ['Guard rating (J)', 'Allowed behind the guard (m/s)', 'Held by the guard (%) [95 % CI]', 'Broke through (%)'] : [])].map((c) => h('th', { scope: 'col' }, c)))),
      h('tbody', {}, rows.map(({ a, l, f, g }) => h('tr', { class: l.design_utilisation > 1 ? 'verdict-exceeded' : '' },
        h('th', { scope: 'row' }, label(a)),
        h('td', {}, LIMIT_WORDS[l.limit] ?? l.limit),
        h('td', { class: 'num' }, fmt(l.impact_velocity_m_s, 4)),
        h('td', { class: 'num' }, fmt(l.kinetic_energy_j, 4)),
        h('td', {}, ENDS[l.ended_by] ?? l.ended_by),
        ...(data.statistics ? [
          h('td', { class: 'num' }, a.design_impact_velocity_m_s === undefined ? 'never reached' : fmt(a.design_impact_velocity_m_s, 4)),
          h('td', { class: 'num' }, l.design_utilisation === undefined ? '—' : fmt(l.design_utilisation * 100, 4)),
        ] : []),
        ...(rate ? [
          h('td', { class: 'num' }, f ? `${fmt(f.per_year, 4)} [${fmt(f.ci95_per_year[0], 3)}–${fmt(f.ci95_per_year[1], 3)}]` : '—'),
          h('td', { class: 'num' }, f ? years(f.return_period_years) : '—'),
        ] : []),
        ...(guarded ? [
          h('td', { class: 'num' }, g ? fmt(g.energy_rating_j, 4) : 'none'),
          h('td', { class: 'num' }, l.behind_guard_impact_velocity_m_s === undefined ? '—' : fmt(l.behind_guard_impact_velocity_m_s, 4)),
          h('td', { class: 'num' }, g ? `${fmt(g.held.probability * 100, 3)} [${fmt(g.held.ci95[0] * 100, 2)}–${fmt(g.held.ci95[1] * 100, 2)}]` : '—'),
          h('td', { class: 'num' }, g ? fmt(g.broken_through.probability * 100, 3) : '—'),
        ] : [])))),
    );
  }

  function renderSupportChart(entries, acceptable) {
    if (!entries.length) {
      plotMessage(plots.support, 'No support entries.');
      supportSummary.textContent = '';
      return;
    }
    const sorted = [...entries].sort((a, b) => a.support - b.support || (a.column_index ?? 0) - (b.column_index ?? 0));
    // x: the support number (columns of one support side by side); positions on hover.
    const cols = Math.max(1, ...sorted.map((e) => (e.column_index ?? 0) + 1));
    const xs = sorted.map((e) => e.support + (e.column_index ?? 0) / (cols + 1));
    const where = (i) => `${label(sorted[i])}`;
    const ticks = (v) => (Number.isInteger(v) ? `#${v}` : '');
    const colour = (e) => (e.verdict === 'exceeded' ? RED : GREEN);
    if (entries[0].single) {
      linePlot(plots.support, {
        x: { label: 'support number', values: xs, range: [xs[0] - 1, xs[xs.length - 1] + 1], value: where, ticks },
        y: { label: 'largest utilisation (%)', range: [0, Math.max(110, ...sorted.map((e) => e.risk * 110))] },
        series: [
          { label: 'within the limits', values: sorted.map((e) => (e.verdict === 'exceeded' ? null : e.risk * 100)), bars: true, color: GREEN },
          { label: 'exceeded', values: sorted.map((e) => (e.verdict === 'exceeded' ? e.risk * 100 : null)), bars: true, color: RED },
        ],
        height: 240,
      });
      const over = sorted.filter((e) => e.verdict === 'exceeded');
      supportSummary.textContent = `${sorted.length} support entries struck in this run; ${over.length} exceed a limit${over.length ? ` (${over.map((e) => `#${e.support}`).join(', ')})` : ''}.`;
      plots.support.setAttribute('aria-label', supportSummary.textContent);
      return;
    }
    const pct = (v) => v * 100;
    // The axis follows the data: every probability, every interval bound and the threshold.
    const values = [...sorted.flatMap((e) => [e.risk, e.riskCi[0], e.riskCi[1], unprotected?.get(`${e.support}.${e.column_index ?? 0}`)?.risk ?? 0]), acceptable]
      .filter((v) => v > 0).map(pct);
    let lo = Infinity;
    let hi = 0;
    for (const v of values) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (!values.length) { lo = 1; hi = 1; }
    const log = hi / lo >= 100;
    const range = log
      ? [10 ** Math.floor(Math.log10(lo)), Math.min(100, 10 ** Math.ceil(Math.log10(hi)))]
      : [0, Math.min(100, niceCeil(hi * 1.1))];
    if (range[1] <= range[0]) range[1] = range[0] * 10;
    const bottom = range[0];
    const pOf = (e) => (e.risk > 0 ? pct(e.risk) : null);
    const draw = (u) => {
      const { ctx } = u;
      const r = devicePixelRatio;
      const step = sorted.length > 1 ? Math.abs(u.valToPos(xs[1], 'x', true) - u.valToPos(xs[0], 'x', true)) : 40 * r;
      const half = Math.max(1.5 * r, Math.min(10 * r, step * 0.35));
      const yPos = (v) => u.valToPos(Math.max(v, bottom), 'y', true);
      ctx.save();
      ctx.setLineDash([]);
      // A clip keeps zoomed-out bars inside the plot.
      ctx.beginPath();
      ctx.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height);
      ctx.clip();
      sorted.forEach((e, i) => {
        const x = u.valToPos(xs[i], 'x', true);
        const c = e.risk > 0 ? colour(e) : GREY;
        if (e.risk > 0) {
          ctx.fillStyle = `${c}66`;
          const top = yPos(pct(e.risk));
          ctx.fillRect(x - half, top, 2 * half, u.bbox.top + u.bbox.height - top);
        }
        // the 95 % interval; P = 0 draws from the axis to its upper bound
        const y0 = yPos(pct(e.riskCi[0]));
        const y1 = yPos(pct(e.riskCi[1]));
        ctx.strokeStyle = c;
        ctx.lineWidth = 1.5 * r;
        ctx.beginPath();
        ctx.moveTo(x, y0);
        ctx.lineTo(x, y1);
        ctx.moveTo(x - half * 0.7, y1);
        ctx.lineTo(x + half * 0.7, y1);
        if (e.riskCi[0] > 0) {
          ctx.moveTo(x - half * 0.7, y0);
          ctx.lineTo(x + half * 0.7, y0);
        }
        ctx.stroke();
      });
      ctx.restore();
    };
    const pShown = (v) => (v === null || v === undefined ? '—' : `${fmt(v, 3)} %`);
    linePlot(plots.support, {
      x: { label: 'support number', values: xs, range: [xs[0] - 0.8, xs[xs.length - 1] + 0.8], value: where, ticks },
      y: { label: `P(exceed) (%)${log ? ', log scale' : ''}`, range, log, ticks: (v) => fmt(v, 3) },
      series: [
        { label: 'P within the acceptable', values: sorted.map((e) => (e.verdict === 'exceeded' ? null : pOf(e))), points: 'only', color: GREEN, pointSize: 6, value: pShown },
        { label: 'P above the acceptable', values: sorted.map((e) => (e.verdict === 'exceeded' ? pOf(e) : null)), points: 'only', color: RED, pointSize: 7, value: pShown },
        { label: 'none exceeded: upper bound', values: sorted.map((e) => (e.risk > 0 ? null : pct(e.riskCi[1]))), points: 'only', color: GREY, pointSize: 6, pointFill: '#fff', value: pShown },
        { label: '95 % upper bound', values: sorted.map((e) => pct(e.riskCi[1])), points: 'none', color: '#3b4350', value: pShown },
        ...(unprotected ? [{
          label: 'P without protection (same runs)', values: sorted.map((e) => { const b = unprotected.get(`${e.support}.${e.column_index ?? 0}`); return b && b.risk > 0 ? pct(b.risk) : null; }),
          points: 'only', color: BLUE, pointSize: 6, value: pShown,
        }] : []),
        ...(acceptable > 0 ? [{ label: 'acceptable probability', values: sorted.map(() => pct(acceptable)), color: '#3b4350', dash: [6, 4], width: 1.5, value: pShown }] : []),
      ],
      draw,
      height: 280,
    });
    plots.support.csv = () => [['support', 'column_index', 'along_dip_m', 'p_exceed', 'ci95_low', 'ci95_high', 'verdict'],
      ...sorted.map((e) => [e.support, e.column_index ?? 0, e.along_dip_m, e.risk, e.riskCi[0], e.riskCi[1], e.verdict])];
    const over = sorted.filter((e) => e.verdict === 'exceeded').sort(byRisk);
    const top = [...sorted].sort(byRisk)[0];
    supportSummary.textContent = `${sorted.length} support entries, #${sorted[0].support} to #${sorted[sorted.length - 1].support}; `
      + `${over.length} above the acceptable probability of ${fmt(acceptable * 100, 3)} %${over.length ? ` (${over.slice(0, 8).map((e) => `#${e.support}`).join(', ')}${over.length > 8 ? ', …' : ''})` : ''}; `
      + `largest P(exceed) ${fmt(top.risk * 100, 3)} % at #${top.support} (95 % interval ${fmt(top.riskCi[0] * 100, 2)}–${fmt(top.riskCi[1] * 100, 2)} %); `
      + `${sorted.filter((e) => e.risk === 0).length} with no exceeding run. ${log ? 'Log scale: the values span decades.' : ''}`;
    plots.support.setAttribute('role', 'img');
    plots.support.setAttribute('aria-label', `Risk along the face: ${supportSummary.textContent}`);
    plots.support.dataset.scale = log ? 'log' : 'linear';
    plots.support.dataset.range = range.join(',');
  }

  /** Side view (a vertical section along the dip) and plan view, supports as vertical marks coloured by verdict. */
  function renderFace(data, entries, request) {
    const length = data.inputs?.face?.length_m ?? 120;
    const dip = (data.inputs?.face?.dip_deg ?? 45) * Math.PI / 180;
    const tr = data.migration?.trajectory;
    const marks = entries.map((e) => ({
      x: e.along_dip_m,
      color: e.verdict === 'exceeded' ? '#c8423b' : (e.single || e.reached_fraction > 0) ? '#2a8f4f' : '#aab2bd',
    }));
    const zones = data.inputs?.release_zones === 'table1'
      ? [[0, length / 3], [length / 3, 2 * length / 3], [2 * length / 3, length]]
      : Array.isArray(data.inputs?.release_zones) ? data.inputs.release_zones.map((z) => [z.from_along_dip_m, z.to_along_dip_m]) : [];
    const elevation = (s) => -s * Math.sin(dip);
    const floor = [[0, length], [elevation(0), elevation(length)]];
    const tables = [floor];
    if (zones.length) {
      const xs = [];
      const ys = [];
      for (const [a, b] of zones) {
        xs.push(a + 1e-9 * length, b - 1e-9 * length, (a + b) / 2 + 1e-7 * length);
        ys.push(elevation(a), elevation(b), null);
      }
      tables.push(dedupe(xs, ys));
    }
    // The rock's height above the floor, measured along the normal, raises it by h / cos θ vertically.
    if (tr) tables.push(dedupe(tr.along_dip_m, tr.along_dip_m.map((s, i) => elevation(s) + tr.height_m[i] / Math.cos(dip))));
    const joined = joinSeries(tables);
    const up = migrationForm.floor?.current?.();
    const series = [{ label: up && data.inputs?.face?.floor?.kind !== 'plane' ? `mean plane of the uploaded floor ${up.name}` : 'floor (plane of the face)', values: joined[1], color: '#555e6b' }];
    let k = 2;
    if (zones.length) series.push({ label: 'release zones (Table 1 thirds)', values: joined[k++], color: '#d88a1c', width: 7 });
    if (tr) series.push({ label: 'nominal run', values: joined[k++], color: '#1d5fa8' });
    // barriers solid brown, proposed barriers long-dashed teal, collectors dashed violet, over the supports' marks
    const devices = [...requestDevices(request ?? data.inputs), ...proposedDevices(data)];
    const deviceMarks = devices.map((d) => ({
      x: d.s, color: d.kind === 'barrier' ? BARRIER : d.kind === 'proposed' ? PROPOSED : COLLECTOR,
      dash: d.kind === 'barrier' ? [] : d.kind === 'proposed' ? [10, 5] : [6, 4], width: 2.5, label: deviceLabel(d),
    }));
    linePlot(plots.side, {
      x: { label: 'along the dip (m); supports as vertical lines', values: joined[0] },
      y: { label: 'elevation (m)' },
      series,
      vlines: [...marks, ...deviceMarks],
      height: 240,
    });
    const sideNote = document.getElementById('scene-side-note');
    sideNote.hidden = !devices.length;
    sideNote.textContent = devices.length ? `Lines across the face: ${devices.map((d) => `${deviceLabel(d)} at ${fmt(d.s, 4)} m`).join('; ')} `
      + `(barriers solid brown, collectors dashed violet${devices.some((d) => d.kind === 'proposed') ? ', barriers the design search proposes, not yet applied, long-dashed teal' : ''}; `
      + 'also on the plan view beside and on the floor below).' : '';
    if (tr) plots.side.csv = () => [['along_dip_m', 'height_m'], ...tr.along_dip_m.map((s, i) => [s, tr.height_m[i]])];

    // Plan: along the dip against across the face; columns as points, spanning supports as lines.
    const cols = entries.filter((e) => e.across_m !== null && e.across_m !== undefined);
    const planTables = [[[0, length], [0, 0]]];
    if (cols.length) planTables.push(dedupe(cols.map((e) => e.along_dip_m), cols.map((e) => e.across_m)));
    if (tr) planTables.push(dedupe(tr.along_dip_m, tr.position_m.map((p) => p[1])));
    const pj = joinSeries(planTables);
    const planSeries = [{ label: 'face centre line', values: pj[1], color: '#555e6b', dash: [4, 4] }];
    let q = 2;
    if (cols.length) planSeries.push({ label: 'support columns', values: pj[q++], points: 'only', color: '#c8423b', pointSize: 6 });
    if (tr) planSeries.push({ label: 'nominal run', values: pj[q++], color: '#1d5fa8' });
    linePlot(plots.plan, {
      x: { label: 'along the dip (m)', values: pj[0] },
      y: { label: 'across the face (m)', range: [-2, 2] },
      series: planSeries,
      vlines: marks.filter((m, i) => entries[i].across_m === null || entries[i].across_m === undefined),
      draw: devices.length ? (u) => drawDeviceLines(u, devices) : null,
      height: 240,
    });
  }

  function renderDistributions(data) {
    const entries = supportEntries(data);
    const e = entries[Number(distSelect.value)];
    distTable.replaceChildren();
    destroy(distPlot);
    if (!e) return;
    const hist = e.impact_velocity_m_s?.histogram;
    if (hist?.counts?.length) {
      const centres = hist.counts.map((_, i) => (hist.edges[i] + hist.edges[i + 1]) / 2);
      const lo = hist.edges[0];
      const hi = hist.edges[hist.edges.length - 1];
      const pad = hi > lo ? 0 : Math.max(Math.abs(lo) * 1e-3, 1e-3);
      linePlot(distPlot, {
        x: { label: `impact speed at ${label(e)} (m/s)`, values: centres, range: [lo - pad, hi + pad] },
        y: { label: 'runs', range: [0, Math.max(...hist.counts) * 1.1 || 1] },
        series: [{ label: 'runs', values: hist.counts, bars: true }],
        height: 200,
      });
      distPlot.csv = () => [['edge_low_m_s', 'edge_high_m_s', 'runs'], ...hist.counts.map((c, i) => [hist.edges[i], hist.edges[i + 1], c])];
    }
    if (e.single) {
      distTable.append(h('tbody', {}, h('tr', {}, h('td', {}, 'A single run has no distributions: switch on the Monte Carlo ensemble.'))));
      return;
    }
    distTable.append(
      h('thead', {}, h('tr', {}, h('th', {}, label(e)), STAT_COLUMNS.map((c) => h('th', { class: 'num' }, c)), h('th', {}, 'unit'))),
      h('tbody', {}, DISTRIBUTIONS.map(([key, words, unit, scale]) => {
        const s = e[key];
        if (!s) return h('tr', {}, h('th', { scope: 'row' }, words), h('td', { colspan: STAT_COLUMNS.length + 1 }, 'never reached within capacity: no distribution'));
        return h('tr', {}, h('th', { scope: 'row' }, words),
          STAT_COLUMNS.map((c) => h('td', { class: 'num' }, fmt(s[c] === null || s[c] === undefined ? s[c] : s[c] * scale, 4,
            Math.max(Math.abs(s.mean ?? 0), Math.abs(s.max ?? 0)) * scale))),
          h('td', { class: 'unit' }, unit));
      })),
    );
  }

  return panel;
}

/** Sorted by x with repeated x values dropped (uPlot.join needs strictly ascending x). */
function dedupe(xs, ys) {
  const pairs = xs.map((x, i) => [x, ys[i]]).sort((a, b) => a[0] - b[0]);
  const out = [[], []];
  for (const [x, y] of pairs) {
    if (out[0].length && x === out[0][out[0].length - 1]) continue;
    out[0].push(x);
    out[1].push(y);
  }
  return out;
}

/**
 * The ensemble's runs: "until precise enough" (a target on a probability's Wilson interval,
 * `monte_carlo.runs` the most runs allowed) or a fixed number. The most runs follows the
 * migration method (64 000 with the lumped mass, 2 000 with the far slower rigid block)
 * until it is typed or opened from a case.
 */
function initRunsChoice(form, migrationForm) {
  const mode = form.querySelector('[data-local="runs_mode"]');
  const fixed = form.querySelector('[data-pointer="/monte_carlo/runs"]');
  const most = form.querySelector('[data-local="max_runs"]');
  const targetOnly = [form.querySelector('[data-pointer="/monte_carlo/target/statistic"]'), form.querySelector('[data-pointer="/monte_carlo/target/half_width"]'), most];
  const method = migrationForm.querySelector('[data-pointer="/method"]');
  const byMethod = () => MAX_RUNS[method?.value] ?? MAX_RUNS.lumped_mass;
  // true while the page chose the most runs (not typed, not opened from a case)
  let auto = true;
  const sync = () => {
    const target = mode.value !== 'fixed';
    for (const el of targetOnly) {
      el.disabled = !target;
      el.closest('.field').hidden = !target;
    }
    fixed.disabled = target;
    fixed.closest('.field').hidden = target;
  };
  const follow = () => {
    if (!auto) return;
    most.value = String(byMethod());
  };
  mode.addEventListener('change', sync);
  most.addEventListener('input', () => { auto = false; });
  // a case opened from a link or the recent list sets it with a change event
  most.addEventListener('change', () => { auto = false; });
  method?.addEventListener('change', follow);
  form.addEventListener('reset', () => setTimeout(() => { auto = true; follow(); sync(); }));
  sync();
  return {
    /** Sends the target and the most runs, or nothing more for a fixed number; a precision out of range is a field error. */
    apply(request, local) {
      const mc = request.monte_carlo;
      if (local.runs_mode === 'fixed') {
        delete mc.target;
        return;
      }
      mc.runs = local.max_runs;
      const hw = mc.target?.half_width;
      if (!(hw > 0 && hw <= 0.5)) {
        throw { fieldErrors: [{ field: '/monte_carlo/target/half_width', message: `must be above 0 and at most 50 points, not ${fmt(hw * 100, 6)}` }] };
      }
    },
  };
}

/** 64000 → "64 000" (no-break spaces between groups of three digits). */
export function groupDigits(n) {
  return String(Math.round(n)).replace(/\B(?=(\d{3})+(?!\d))/g, '\u00a0');
}

/** Percentage points with the fewest digits (2 at least) that keep "within the target" true to the unrounded value. */
function points(hw, asked) {
  let sig = 2;
  const within = hw <= asked;
  while (sig < 8 && (Number((hw * 100).toPrecision(sig)) <= asked * 100) !== within) sig += 1;
  return fmt(hw * 100, sig);
}

const TARGET_WORDS = { any_exceeded: 'any-support probability', every_support: 'every support\'s probability' };

/**
 * What an ensemble "until precise enough" did, from the answer's `statistics.target`:
 * "Stopped at 4 000 runs: any-support probability known to ± 0.42 points (asked ± 0.5)", or
 * "Ran all 64 000 runs: ± 0.61 points, the target was not met — raise the most runs or loosen the target".
 */
export function sceneTargetSentence(t) {
  if (!t) return '';
  const asked = t.target.half_width;
  const reached = points(t.half_width, asked);
  const words = TARGET_WORDS[t.target.statistic] ?? t.target.statistic;
  if (t.met) {
    const at = t.runs_used < t.max_runs ? `Stopped at ${groupDigits(t.runs_used)} runs` : `Met at all ${groupDigits(t.runs_used)} runs`;
    return `${at}: ${words} known to ± ${reached} points (asked ± ${fmt(asked * 100, 6)})`;
  }
  return `Ran all ${groupDigits(t.runs_used)} runs: ± ${reached} points, the target was not met — raise the most runs or loosen the target`;
}

/**
 * The progress line of an ensemble with a target. The server counts toward the most runs
 * (its total is 1 + monte_carlo.runs, the nominal run first) whatever check the ensemble is
 * at, and its time left is the time to run them all, which overstates it when the ensemble
 * stops early; with per-cell maps the runs used are counted again while the maps are
 * recorded. So the line says how many runs are done, where the checks come, and no time left.
 */
export function targetProgress({ done }, request) {
  const most = request?.monte_carlo?.target ? request.monte_carlo.runs : null;
  if (!most) return null;
  const checks = [1000, 2000, 4000].filter((n) => n < most).map(groupDigits);
  return `${groupDigits(Math.max(0, done - 1))} runs computed; checked at ${[...checks, ...(most > 4000 ? ['…'] : []), groupDigits(most)].join(', ')} runs `
    + 'until precise enough, so the time left is not known';
}

/**
 * The release on the Scene form: the Table 1 zones, the engineer's own zones (a small table
 * of rows: from, to along the dip, weight), a single point, or the Migration tab's point.
 * Custom rows live in one hidden field (JSON) so that links and recent cases carry them.
 */
function initReleaseEditor(form, migrationForm) {
  const choice = form.querySelector('[data-local="release_zones"]');
  const group = choice.closest('fieldset');
  const store = h('input', { type: 'hidden', dataset: { local: 'zones_json', kind: 'select' }, value: '' });
  const body = h('tbody', {});
  const table = h('table', { class: 'results-table zones-table', id: 'scene-zones' },
    h('caption', {}, 'Release zones along the dip: a rock is released in zone i with probability weightᵢ / Σ weight, uniformly inside it.'),
    h('thead', {}, h('tr', {}, h('th', { scope: 'col' }, 'from (m)'), h('th', { scope: 'col' }, 'to (m)'), h('th', { scope: 'col' }, 'weight'), h('th', {}, ''))),
    body);
  const add = h('button', { type: 'button', class: 'chip', id: 'scene-zone-add' }, 'Add a zone');
  const zonesBox = h('div', { class: 'zones-box', hidden: true }, h('div', { class: 'table-scroll' }, table), add);
  const pointS = h('input', { type: 'text', inputmode: 'decimal', id: 'scene-point-s', value: '0', dataset: { local: 'point_s', kind: 'number', target: '/release/along_dip_m' } });
  const pointY = h('input', { type: 'text', inputmode: 'decimal', id: 'scene-point-y', value: '0', dataset: { local: 'point_y', kind: 'number', target: '/release/across_m' } });
  const row = (label, control, unit) => h('div', { class: 'field field-number' }, h('label', { for: control.id }, label),
    h('div', { class: 'control' }, control, h('span', { class: 'unit' }, unit)), h('p', { class: 'field-error', hidden: true, role: 'alert' }));
  const pointBox = h('div', { class: 'point-box', hidden: true }, row('Release along the dip', pointS, 'm'), row('Release across the face', pointY, 'm'));
  group.append(store, zonesBox, pointBox);

  const length = () => Number(migrationForm.querySelector('[data-pointer="/face/length_m"]')?.value) || 120;
  const rowsNow = () => [...body.rows].map((tr) => [...tr.querySelectorAll('input')].map((i) => i.value));
  const save = () => { store.value = JSON.stringify(rowsNow()); };
  const addRow = (values = ['', '', '1']) => {
    const i = body.rows.length;
    const cells = ['from_along_dip_m', 'to_along_dip_m', 'weight'].map((key, k) => {
      const input = h('input', { type: 'text', inputmode: 'decimal', value: values[k] ?? '', 'aria-label': `zone ${i + 1} ${['from', 'to', 'weight'][k]}`, dataset: { target: `/release_zones/${i}/${key}` } });
      input.addEventListener('input', save);
      return h('td', {}, input);
    });
    const remove = h('button', { type: 'button', class: 'link', 'aria-label': `remove zone ${i + 1}` }, 'remove');
    remove.addEventListener('click', () => { tr.remove(); renumber(); save(); });
    const tr = h('tr', {}, cells, h('td', {}, remove));
    body.append(tr);
  };
  const renumber = () => [...body.rows].forEach((tr, i) => tr.querySelectorAll('input').forEach((input, k) => {
    const key = ['from_along_dip_m', 'to_along_dip_m', 'weight'][k];
    input.dataset.target = `/release_zones/${i}/${key}`;
    input.setAttribute('aria-label', `zone ${i + 1} ${['from', 'to', 'weight'][k]}`);
  }));
  const fill = (rows) => { body.replaceChildren(); rows.forEach((r) => addRow(r)); };
  const thirds = () => {
    const L = length();
    return [[0, L / 3, 0.233], [L / 3, (2 * L) / 3, 0.583], [(2 * L) / 3, L, 0.184]].map((r) => r.map((v) => String(Number(v.toPrecision(6)))));
  };
  add.addEventListener('click', () => { addRow(); save(); body.rows[body.rows.length - 1].querySelector('input').focus(); });
  const sync = () => {
    zonesBox.hidden = choice.value !== 'custom';
    pointBox.hidden = choice.value !== 'point';
    pointS.disabled = pointY.disabled = choice.value !== 'point';
    if (choice.value === 'custom' && !body.rows.length) { fill(thirds()); save(); }
  };
  choice.addEventListener('change', sync);
  // a link or a recent case sets the hidden field: the table follows it
  store.addEventListener('change', () => {
    try {
      const rows = JSON.parse(store.value || '[]');
      if (Array.isArray(rows)) fill(rows);
    } catch {
      // an old link without zones
    }
    sync();
  });
  form.addEventListener('reset', () => setTimeout(() => { body.replaceChildren(); store.value = ''; sync(); }));
  sync();

  return {
    /** Puts the chosen release into the request; a zone or point off the floor is a field error (nothing is sent). */
    apply(request, local, upload) {
      const model = floorModel({ face: request.face }, upload);
      const errors = [];
      if (local.release_zones === 'point') {
        request.release = { ...request.release, along_dip_m: local.point_s, across_m: local.point_y };
        const off = offFloor(model, local.point_s, local.point_y);
        if (off) errors.push({ field: '/release/along_dip_m', message: `the release point ${off}` });
      }
      if (local.release_zones === 'custom') {
        const across = request.release?.across_m ?? 0;
        const zones = [];
        const rows = rowsNow();
        if (!rows.length) errors.push({ field: '/release_zones/0/from_along_dip_m', message: 'add at least one zone' });
        rows.forEach((r, i) => {
          const [from, to, weight] = r.map((v) => (v.trim() === '' ? NaN : Number(v)));
          const at = (k) => `/release_zones/${i}/${k}`;
          if (!Number.isFinite(from)) errors.push({ field: at('from_along_dip_m'), message: `"${r[0]}" is not a number of metres` });
          if (!Number.isFinite(to)) errors.push({ field: at('to_along_dip_m'), message: `"${r[1]}" is not a number of metres` });
          if (!(weight > 0)) errors.push({ field: at('weight'), message: `the weight must be a number above 0, not "${r[2]}"` });
          if (Number.isFinite(from) && Number.isFinite(to)) {
            if (!(to > from)) errors.push({ field: at('to_along_dip_m'), message: `must be beyond "from" (${from} m)` });
            for (const [k, s] of [['from_along_dip_m', from], ['to_along_dip_m', to]]) {
              const off = offFloor(model, s, across);
              if (off) errors.push({ field: at(k), message: `off the floor: ${off}` });
            }
          }
          zones.push({ from_along_dip_m: from, to_along_dip_m: to, weight });
        });
        request.release_zones = zones;
      }
      if (errors.length) throw { fieldErrors: errors };
    },
  };
}

/**
 * The "Design the protection" group: the guarded supports (every one, a typed list, none) and
 * the barrier candidates (off, or every k-th support with its offset). `apply` turns them into
 * the request's `design` (fractions and SI) or throws `{fieldErrors}` naming `/design/...`, so
 * that nothing is sent with a value outside its range.
 */
function initDesignEditor(form) {
  const guards = form.querySelector('[data-local="design_guards"]');
  const barriers = form.querySelector('[data-local="design_barriers"]');
  const kth = form.querySelector('[data-local="design_every_kth"]');
  const offset = form.querySelector('[data-local="design_offset"]');
  const list = h('input', {
    type: 'text', id: 'scene-design-list', autocomplete: 'off', spellcheck: 'false', placeholder: 'e.g. 1, 5, 12',
    dataset: { local: 'design_guard_list', kind: 'select', target: '/design/guards/supports' },
  });
  const listField = h('div', { class: 'field field-number' }, h('label', { for: list.id }, 'Guarded supports'),
    h('div', { class: 'control' }, list, h('span', { class: 'unit' }, 'numbers')),
    h('p', { class: 'hint' }, 'support numbers from 1, separated by commas or spaces'),
    h('p', { class: 'field-error', hidden: true, role: 'alert' }));
  guards.closest('.field').after(listField);
  const sync = () => {
    const listed = guards.value === 'listed';
    list.disabled = !listed;
    listField.hidden = !listed;
    for (const el of [kth, offset]) {
      el.disabled = barriers.value !== 'every_kth';
      el.closest('.field').hidden = el.disabled;
    }
  };
  guards.addEventListener('change', sync);
  barriers.addEventListener('change', sync);
  form.addEventListener('reset', () => setTimeout(sync));
  sync();
  return {
    /** Puts `design` into the request (when its group is ticked), or throws `{fieldErrors}`. */
    apply(request, local) {
      const d = request.design;
      if (!d) return;
      const errors = [];
      const count = request.support_rows ? request.support_rows.count : (request.supports?.length ?? 1);
      const a = d.acceptable_probability;
      if (!(a > 0 && a < 1)) errors.push({ field: '/design/acceptable_probability', message: `must be above 0 and below 100 %, not ${fmt(a * 100, 6)} %` });
      if (!request.monte_carlo || typeof request.impact_velocity_m_s === 'number') {
        errors.push({ field: '/design', message: 'the design search runs over the ensemble\'s runs: tick the Monte Carlo ensemble and leave the impact velocity empty' });
      }
      const withBarriers = local.design_barriers === 'every_kth';
      if (withBarriers) {
        const k = local.design_every_kth;
        const off = local.design_offset;
        if (!(Number.isInteger(k) && k >= 1 && k <= 1000)) errors.push({ field: '/design/barriers/every_kth_support', message: `must be a whole number in [1, 1000], not ${fmt(k, 6)}` });
        if (!(off >= 0 && off <= 10)) errors.push({ field: '/design/barriers/offset_m', message: `must be in [0, 10] m, not ${fmt(off, 6)} m` });
        d.barriers = { every_kth_support: k, offset_m: off };
      }
      if (local.design_guards === 'listed') {
        const text = String(local.design_guard_list ?? '').trim();
        const words = text.split(/[\s,;]+/).filter(Boolean);
        const numbers = words.map(Number);
        const bad = words.find((w, i) => !(Number.isInteger(numbers[i]) && numbers[i] >= 1 && numbers[i] <= count));
        if (!words.length) errors.push({ field: '/design/guards/supports', message: 'list at least one support number' });
        else if (bad !== undefined) errors.push({ field: '/design/guards/supports', message: `"${bad}" is not a support: the supports are numbered 1 to ${count}` });
        d.guards = { supports: [...new Set(numbers)] };
      } else if (local.design_guards === 'every') {
        // with a barrier search the server guards nothing unless the supports are listed
        if (withBarriers) d.guards = { supports: Array.from({ length: count }, (_, i) => i + 1) };
      } else if (!withBarriers) {
        errors.push({ field: '/design/guards', message: 'nothing to design: guard some supports or search for barriers' });
      }
      if (errors.length) throw { fieldErrors: errors };
    },
  };
}

/** The barriers a design answer proposes, as marks drawn in their own style before they are applied. */
function proposedDevices(data) {
  return (data?.design?.barriers?.barriers ?? []).map((b, i) => ({
    kind: 'proposed', index: i + 1, s: b.along_dip_m, across: null, height: b.height_m, rating: b.energy_rating_j, support: b.support,
  }));
}

/** Puts text on the clipboard (a hidden text area where the Clipboard API is refused); true when copied. */
async function copyText(text) {
  try {
    await navigator.clipboard.writeText(text);
    return true;
  } catch {
    const area = h('textarea', { readonly: true, style: 'position: fixed; opacity: 0' });
    area.value = text;
    document.body.append(area);
    area.select();
    const ok = document.execCommand('copy');
    area.remove();
    return ok;
  }
}
