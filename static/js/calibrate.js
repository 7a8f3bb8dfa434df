// Calibrate tab: POST /v1/calibrate. The base is the Migration tab's case (face, floor, rock,
// method, release and ensemble); the observations are a CSV pasted or uploaded (a column
// runout_m, horizontal_runout_m, or along_dip_m,across_m; optional release_along_dip_m,
// release_across_m: one release per observed run). The answer shows the best values, the
// objective at the best and at the base, the sensitivity table and the observed against the
// computed ECDFs.

import { postJson } from './api.js';
import { csvButton, fmt, h, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, linePlot, plotMessage } from './plot.js';

/**
 * The parameters the page offers, with the method they belong to and the box a form starts
 * from (`choice`: a starting value for the engineer to change, not a server default).
 */
const PARAMETERS = [
  { name: 'restitution_normal', label: 'Normal restitution eₙ', method: 'lumped_mass', min: 0.1, max: 0.6, on: true },
  { name: 'restitution_tangential', label: 'Tangential restitution eₜ', method: 'lumped_mass', min: 0.5, max: 0.95, on: false },
  { name: 'friction_coefficient', label: 'Friction μ (lumped mass)', method: 'lumped_mass', min: 0.1, max: 1.0, on: true },
  { name: 'critical_damping_ratio', label: 'Damping ratio β (rigid block)', method: 'rigid_block', min: 0.05, max: 0.6, on: true },
  { name: 'rigid_block_friction_coefficient', label: 'Friction μ (rigid block)', method: 'rigid_block', min: 0.1, max: 1.0, on: true },
];

/** Most observed runs the server takes (api: 10 000). */
const MAX_OBSERVATIONS = 10000;

/**
 * Reads the observation CSV: `{observed, releases}` with the releases' along/across (or
 * null), or throws `{fieldErrors}` naming `/observed` with the line at fault.
 */
export function parseObservations(text) {
  const lines = String(text ?? '').split(/\r?\n/).map((l) => l.trim()).filter((l) => l && !l.startsWith('#'));
  const bad = (message) => ({ fieldErrors: [{ field: '/observed', message }] });
  if (lines.length < 2) throw bad('paste or upload a CSV: a header line and at least one observed run');
  const header = lines[0].split(/[,;\t]/).map((c) => c.trim().toLowerCase());
  const col = (name) => header.indexOf(name);
  let kind;
  if (col('runout_m') >= 0) kind = 'runout_m';
  else if (col('horizontal_runout_m') >= 0) kind = 'horizontal_runout_m';
  else if (col('along_dip_m') >= 0 && col('across_m') >= 0) kind = 'stop_points_m';
  else throw bad(`the header needs a column runout_m, horizontal_runout_m, or along_dip_m and across_m (found: ${header.join(', ')})`);
  const rel = [col('release_along_dip_m'), col('release_across_m')];
  const withReleases = rel[0] >= 0 || rel[1] >= 0;
  const rows = lines.slice(1);
  if (rows.length > MAX_OBSERVATIONS) throw bad(`at most ${MAX_OBSERVATIONS} observed runs (${rows.length} lines)`);
  const values = [];
  const releases = [];
  rows.forEach((line, i) => {
    const cells = line.split(/[,;\t]/).map((c) => c.trim());
    const num = (j, what) => {
      const v = Number(cells[j]);
      if (cells[j] === undefined || cells[j] === '' || !Number.isFinite(v)) {
        throw bad(`line ${i + 2}: ${what} "${cells[j] ?? ''}" is not a number`);
      }
      return v;
    };
    if (kind === 'stop_points_m') values.push([num(col('along_dip_m'), 'along_dip_m'), num(col('across_m'), 'across_m')]);
    else values.push(num(col(kind), kind));
    if (withReleases) {
      releases.push({
        along_dip_m: rel[0] >= 0 ? num(rel[0], 'release_along_dip_m') : null,
        across_m: rel[1] >= 0 ? num(rel[1], 'release_across_m') : null,
      });
    }
  });
  return { observed: { [kind]: values }, releases: withReleases ? releases : null, kind };
}

/** The units of a figure's quantity, from its name. */
function unitOf(quantity) {
  return quantity.endsWith('_m_s') ? 'm/s' : 'm';
}

/** Words for a figure's quantity. */
function words(quantity) {
  const named = {
    runout_m: 'runout',
    horizontal_runout_m: 'horizontal runout',
    stop_along_dip_m: 'stop, along the dip',
    stop_across_m: 'stop, across the face',
  };
  if (named[quantity]) return named[quantity];
  const m = /^collectors\/(\d+)\/(speed_m_s|passing_height_m)$/.exec(quantity);
  if (m) return `collector ${Number(m[1]) + 1}: ${m[2] === 'speed_m_s' ? 'speed' : 'passing height'}`;
  return quantity;
}

function paramLabel(name) {
  return PARAMETERS.find((p) => p.name === name)?.label ?? name;
}

/** The parameters table of the form: one row per parameter, a tick, min and max. */
function parametersTable(el) {
  const head = h('tr', {}, h('th', {}, 'Use'), h('th', {}, 'Parameter'), h('th', { class: 'num' }, 'Min'), h('th', { class: 'num' }, 'Max'));
  const rows = PARAMETERS.map((p) => h('tr', { 'data-parameter': p.name },
    h('td', {}, h('input', { type: 'checkbox', name: `calibrate_${p.name}`, checked: p.on, 'aria-label': `calibrate ${p.label}` })),
    h('th', { scope: 'row' }, p.label),
    ...['min', 'max'].map((k) => h('td', {}, h('input', {
      type: 'text', inputmode: 'decimal', size: 4, value: String(p[k]), 'data-bound': k,
      'aria-label': `${p.label}, ${k}`,
    })))));
  el.replaceChildren(h('thead', {}, head), h('tbody', {}, ...rows));
}

/** The ticked parameters of the base's method, in order, as request items. */
function readParameters(el, method) {
  const out = [];
  const errors = [];
  for (const row of el.querySelectorAll('tr[data-parameter]')) {
    const p = PARAMETERS.find((q) => q.name === row.dataset.parameter);
    if (!row.querySelector('input[type="checkbox"]').checked || p.method !== method) continue;
    const i = out.length;
    const item = { name: p.name };
    for (const input of row.querySelectorAll('input[data-bound]')) {
      input.dataset.target = `/parameters/${i}/${input.dataset.bound}`;
      const v = Number(String(input.value).trim().replace(/\u2212/g, '-'));
      if (input.value.trim() === '' || !Number.isFinite(v)) errors.push({ field: input.dataset.target, message: 'must be a number' });
      item[input.dataset.bound] = v;
    }
    out.push(item);
  }
  if (errors.length) throw { fieldErrors: errors };
  if (!out.length || out.length > 3) {
    throw { fieldErrors: [{ field: '/parameters', message: `tick 1 to 3 parameters of the ${method === 'lumped_mass' ? 'lumped mass' : 'rigid block'} (the Migration tab's method); ${out.length} ticked` }] };
  }
  return out;
}

/** The base migration request from the Migration form (its floor applied, no output). */
function baseRequest(mig, migrationForm) {
  const base = mig.request;
  migrationForm.floor?.apply(base, mig.local);
  delete base.output;
  const mc = base.monte_carlo;
  if (mc) {
    delete mc.target;
    if (base.method === 'rigid_block') {
      delete mc.restitution_normal;
      delete mc.restitution_tangential;
    } else {
      for (const key of ['restitution_normal', 'restitution_tangential']) {
        if (mc[key]) mc[key] = { distribution: 'uniform', ...mc[key] };
      }
    }
    if (mc.friction_coefficient) mc.friction_coefficient = { distribution: 'truncated_normal', ...mc.friction_coefficient };
  }
  return base;
}

function resultTable(el, data) {
  const rows = Object.keys(data.best).map((name) => h('tr', {},
    h('th', { scope: 'row' }, paramLabel(name)),
    h('td', { class: 'num', 'data-out': `best/${name}` }, fmt(data.best[name], 4)),
    h('td', { class: 'num', 'data-out': `base_values/${name}` }, fmt(data.base_values[name], 4))));
  const objective = data.objective.kind === 'ks' ? 'Kolmogorov–Smirnov distance' : 'quantile loss (over the observed spread)';
  rows.push(h('tr', {}, h('th', { scope: 'row' }, objective),
    h('td', { class: 'num', 'data-out': 'objective/best' }, fmt(data.objective.best, 4)),
    h('td', { class: 'num', 'data-out': 'objective/base' }, fmt(data.objective.base, 4))));
  rows.push(h('tr', {}, h('th', { scope: 'row' }, 'Evaluations × runs'),
    h('td', { class: 'num', colspan: 2 }, `${data.evaluations.length} × ${data.runs_per_evaluation}`)));
  el.replaceChildren(h('thead', {}, h('tr', {}, h('th', {}, ''), h('th', { class: 'num' }, 'Best'), h('th', { class: 'num' }, 'Base case'))), h('tbody', {}, ...rows));
}

function sensitivityTable(el, data) {
  const cell = (n) => (n ? `${fmt(n.objective, 4)} at ${fmt(n.value, 4)}` : 'outside the box');
  const rows = Object.entries(data.sensitivity).map(([name, s]) => h('tr', {},
    h('th', { scope: 'row' }, paramLabel(name)),
    h('td', { class: 'num' }, fmt(s.step, 3)),
    h('td', {}, cell(s.low)),
    h('td', { class: 'num' }, fmt(data.objective.best, 4)),
    h('td', {}, cell(s.high)),
    h('td', { class: 'num', 'data-out': `sensitivity/${name}/slope` }, fmt(s.slope, 3))));
  el.replaceChildren(h('thead', {}, h('tr', {}, h('th', {}, 'Parameter'), h('th', { class: 'num' }, 'Final step'),
    h('th', {}, 'Objective at best − step'), h('th', { class: 'num' }, 'At the best'), h('th', {}, 'At best + step'),
    h('th', { class: 'num' }, 'Slope per unit'))), h('tbody', {}, ...rows));
}

/** Observed, best and base ECDFs of one figure series on one x axis (steps as points). */
function ecdfPlot(el, f) {
  const unit = unitOf(f.quantity);
  const tables = [f.observed_ecdf, f.best_ecdf, f.base_ecdf];
  const xs = [...new Set(tables.flatMap((t) => t.map((p) => p[0])))].sort((a, b) => a - b);
  if (!xs.length) return plotMessage(el, 'Nothing to plot.');
  // each ECDF as a step function on the common x: F at the largest point ≤ x
  const at = (table) => {
    let j = -1;
    return xs.map((x) => {
      while (j + 1 < table.length && table[j + 1][0] <= x) j++;
      return j < 0 ? 0 : table[j][1];
    });
  };
  linePlot(el, {
    x: { label: `${words(f.quantity)} (${unit})`, values: xs },
    y: { label: 'fraction of runs at or below', range: [0, 1] },
    series: [
      { label: 'observed', values: at(f.observed_ecdf), width: 2.5 },
      { label: 'computed at the best', values: at(f.best_ecdf) },
      { label: 'computed at the base case', values: at(f.base_ecdf), dash: [6, 4] },
    ],
  });
  el.csv = () => [['probability', `observed ${f.quantity}`, `best ${f.quantity}`, `base ${f.quantity}`],
    ...f.probabilities.map((p, i) => [p, f.observed_quantiles[i], f.best_quantiles[i], f.base_quantiles[i]])];
}

let lastData = null;

export function initCalibrate() {
  const form = document.getElementById('calibrate-form');
  if (!form) return null;
  const migrationForm = document.getElementById('migration-form');
  const status = document.getElementById('calibrate-status');
  const warnings = document.getElementById('calibrate-warnings');
  const progress = document.getElementById('calibrate-progress');
  const params = document.getElementById('calibrate-parameters');
  const csv = document.getElementById('calibrate-csv');
  const file = document.getElementById('calibrate-file');
  const fileNote = document.getElementById('calibrate-file-note');
  const results = document.getElementById('calibrate-results');
  const empty = document.getElementById('calibrate-empty');
  const figures = document.getElementById('calibrate-figures');
  parametersTable(params);
  form.addEventListener('reset', () => setTimeout(() => parametersTable(params)));
  file.addEventListener('change', async () => {
    const f = file.files?.[0];
    if (!f) return;
    csv.value = await f.text();
    fileNote.textContent = `Read ${f.name} (${f.size} bytes).`;
  });
  document.getElementById('calibrate-sensitivity-card').append(csvButton('calibration_evaluations.csv', () => {
    if (!lastData) return [['no calibration yet']];
    const names = Object.keys(lastData.best);
    return [['stage', 'round', ...names, 'objective'],
      ...lastData.evaluations.map((e) => [e.stage, e.round ?? '', ...names.map((n) => e.values[n]), e.objective])];
  }, 'CSV: every evaluation'));

  return initPanel({
    name: 'calibrate',
    form,
    forms: [form, migrationForm],
    endpoint: 'v1/calibrate',
    status,
    progress,
    unit: 'runs',
    build: ([own, mig]) => {
      const base = baseRequest(mig, migrationForm);
      const { observed, releases } = parseObservations(csv.value);
      const request = {
        base,
        observed,
        parameters: readParameters(params, base.method ?? 'lumped_mass'),
        objective: own.request.objective,
        search: own.request.search,
      };
      if (releases) {
        const r0 = base.release ?? {};
        request.releases = releases.map((r) => ({
          release: { ...r0, ...(r.along_dip_m === null ? {} : { along_dip_m: r.along_dip_m }), ...(r.across_m === null ? {} : { across_m: r.across_m }) },
        }));
      }
      return request;
    },
    send: (request, opts) => postJson('v1/calibrate', request, opts),
    stream: () => true,
    busy: (request) => `Calibrating ${request.parameters.map((p) => paramLabel(p.name)).join(', ')}…`,
    render: (data) => {
      lastData = data;
      showWarnings(warnings, data.warnings);
      empty.hidden = true;
      results.hidden = false;
      resultTable(document.getElementById('calibrate-table'), data);
      sensitivityTable(document.getElementById('calibrate-sensitivity'), data);
      for (const el of figures.querySelectorAll('.plot')) destroy(el);
      figures.replaceChildren(...data.figure.map((f, i) => {
        const plot = h('div', { class: 'plot', id: `calibrate-ecdf-${i}` });
        const card = h('div', { class: 'card wide' },
          h('h3', {}, `Observed and computed: ${words(f.quantity)} (${unitOf(f.quantity)})`),
          plot,
          h('p', { class: 'note' }, `This quantity's term of the objective: ${fmt(f.best_term, 3)} at the best, ${fmt(f.base_term, 3)} at the base case. The CSV gives the quantiles p01…p99.`));
        return card;
      }));
      data.figure.forEach((f, i) => ecdfPlot(document.getElementById(`calibrate-ecdf-${i}`), f));
    },
    clear: () => {
      lastData = null;
      showWarnings(warnings, []);
      results.hidden = true;
      empty.hidden = false;
      for (const el of figures.querySelectorAll('.plot')) destroy(el);
      figures.replaceChildren();
    },
  });
}
