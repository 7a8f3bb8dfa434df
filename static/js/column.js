// Column tab: POST /v1/column. Runs the paper's decoupled method and the
// coupled rock–column model on the same case (two requests) and shows them
// side by side, with the midpoint wave (Figure 11) and the energy history.

import { postJson } from './api.js';
import { columnChecks, renderChecks } from './checks.js';
import { buildForm, merge, showUsed } from './form.js';
import { fmt, h, pick, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { COLORS, destroy, joinSeries, linePlot, plotMessage } from './plot.js';

const COLUMN_GROUPS = [
  {
    legend: 'Model',
    fields: [
      {
        local: 'models', label: 'Run', kind: 'select', settings: true,
        options: [['both', 'both, side by side'], ['coupled', 'coupled (recommended)'], ['decoupled', 'decoupled (paper)']],
        hint: '<b>coupled</b>: rock, contact and column integrated together (conserves energy); <b>decoupled</b>: the paper\'s method (the rigid-column approach as initial displacement; overstates the energy)',
      },
    ],
  },
  {
    legend: 'Galerkin modes',
    pointer: '/galerkin',
    fields: [
      {
        pointer: '/galerkin/modes', label: 'Modes (coupled)', kind: 'integer', hint: 'the decoupled method uses mode 1',
        choice: { value: 3, why: 'the server derives it from the model (1 decoupled, 3 coupled); the page runs both' },
      },
      {
        pointer: '/galerkin/mode_shapes', label: 'Mode shapes', kind: 'select', settings: true,
        options: [['exact', 'exact (recommended)'], ['paper', 'paper (printed)'], ['approx', 'approx (λ = 3π/2)']],
        hint: '<code>paper</code> and <code>approx</code>: decoupled only',
      },
      { pointer: '/galerkin/rotary_inertia', label: 'Rotary inertia', kind: 'checkbox', hint: 'include the sections\' rotation (J₀ = ρ<sub>s</sub>I)' },
    ],
  },
  {
    legend: 'Damping',
    fields: [
      {
        local: 'damping', label: 'Given as', kind: 'select', settings: true,
        options: [['ratio', 'ratio ζ₁ (recommended)'], ['coefficient', 'coefficient c (paper)']],
        hint: 'the paper\'s c = 1 N·s/m² barely damps at all (decay in minutes)',
      },
      { pointer: '/column/damping_coefficient_n_s_m2', label: 'Coefficient <i>c</i>', unit: 'N·s/m²', settings: true, hint: 'the paper\'s value is 1' },
      { pointer: '/column/damping_ratio', label: 'Damping ratio <i>ζ</i>₁', unit: '', settings: true },
    ],
  },
  {
    legend: 'Time',
    fields: [
      {
        pointer: '/output/duration_s', label: 'History duration', unit: 'ms', exp: -3,
        choice: { value: 20, why: 'the history is optional on the server (no default window); 20 ms shows the contact and the first vibrations' },
      },
      { pointer: '/output/samples', label: 'Samples', kind: 'integer', placeholder: 'auto' },
      {
        pointer: '/initial_midpoint_displacement_m', label: 'Initial midpoint displacement', unit: 'mm', exp: -3,
        placeholder: 'δmax', hint: 'decoupled only',
      },
      { pointer: '/end_time_s', label: 'End time (coupled)', unit: 'ms', exp: -3, placeholder: '50 × tc' },
    ],
  },
];

const ms = { unit: 'ms', scale: 1e3 };
// [label, symbol, unit/scale, decoupled getter, coupled getter]
const ROWS = [
  ['Natural frequency, mode 1', '<i>f</i>₁', { unit: 'Hz' }, 'natural_frequencies_hz.0', 'natural_frequencies_hz.0'],
  ['Natural frequencies', '<i>f</i><sub>i</sub>', { unit: 'Hz', sig: 4 }, 'natural_frequencies_hz', 'natural_frequencies_hz'],
  ['Damping ratio, mode 1', '<i>ζ</i>₁', {}, 'damping_ratios.0', 'damping_ratios.0'],
  ['Damping coefficient used', '<i>c</i>', { unit: 'N·s/m²' }, 'damping_coefficient_n_s_m2', 'damping_coefficient_n_s_m2'],
  ['Modal mass', '<i>M</i>₁', { unit: 'kg' }, 'modal_mass_kg', 'modal_mass_kg'],
  ['Modal stiffness', '<i>K</i>₁', { unit: 'MN/m', scale: 1e-6 }, 'modal_stiffness_n_m', 'modal_stiffness_n_m'],
  ['Midpoint stiffness', '<i>K</i><sub>mid</sub>', { unit: 'MN/m', scale: 1e-6 }, 'midpoint_stiffness_n_m', 'midpoint_stiffness_n_m'],
  ['Midpoint mass', '<i>M</i><sub>mid</sub>', { unit: 'kg' }, 'midpoint_mass_kg', 'midpoint_mass_kg'],
  ['Rock kinetic energy', 'KE', { unit: 'J' }, 'kinetic_energy_j', 'kinetic_energy_j'],
  ['Maximum force', '<i>P</i><sub>max</sub>', { unit: 'kN', scale: 1e-3 }, 'max_force_n', 'max_force_n'],
  ['Maximum approach', '<i>δ</i><sub>max</sub>', { unit: 'mm', scale: 1e3 }, 'max_deformation_m', 'max_contact_deformation_m'],
  ['Initial modal displacement', '<i>w</i>₁(0)', { unit: 'mm', scale: 1e3 }, 'initial_modal_displacement_m', null],
  ['Largest midpoint displacement', 'max |<i>w</i><sub>mid</sub>|', { unit: 'mm', scale: 1e3 }, null, 'max_midpoint_displacement_m'],
  ['Column energy', '<i>U</i>₀', { unit: 'J' }, 'absorbed_energy_j', 'column_energy_after_contact_j'],
  ['Energy ratio (column / KE)', '<i>U</i>₀/KE', { sig: 5 }, 'energy_ratio', 'energy_ratio'],
  ['Decay to 1 %', '<i>t</i><sub>1%</sub>', { unit: 's' }, 'decay_time_1pct_s', 'decay_time_1pct_s'],
  ['Bending stress at the clamp', '<i>σ</i><sub>clamp</sub>', { unit: 'MPa', scale: 1e-6 }, 'max_bending_stress_pa.clamp', 'max_bending_stress_pa.clamp'],
  ['Bending stress at the midpoint', '<i>σ</i><sub>mid</sub>', { unit: 'MPa', scale: 1e-6 }, 'max_bending_stress_pa.midpoint', 'max_bending_stress_pa.midpoint'],
  ['Stress utilisation', '<i>σ</i>/<i>σ</i><sub>y</sub>', { unit: '%', scale: 100, sig: 4 }, 'stress_utilisation', 'stress_utilisation'],
  ['Contacts', '', { sig: 3 }, null, 'contact_count'],
  ['First contact duration', '<i>t</i><sub>c</sub>', ms, null, 'first_contact_duration_s'],
  ['Rebound velocity', '<i>v</i><sub>r</sub>', { unit: 'm/s' }, null, 'rebound_velocity_m_s'],
  ['End time', '', ms, null, 'end_time_s'],
  ['Integrator steps (rejected)', '', {}, null, (d) => d.integrator && `${d.integrator.steps} (${d.integrator.rejected_steps})`],
];

const MODELS = ['decoupled', 'coupled'];

export function initColumn() {
  const form = document.getElementById('column-form');
  const impactForm = document.getElementById('impact-form');
  const status = document.getElementById('column-status');
  const warnings = document.getElementById('column-warnings');
  const table = document.getElementById('column-table');
  const empty = document.getElementById('column-empty');
  const wavePlot = document.getElementById('column-wave-plot');
  const plotsBox = document.getElementById('column-plots');
  const energyPlots = {
    decoupled: document.getElementById('column-energy-decoupled'),
    coupled: document.getElementById('column-energy-coupled'),
  };
  const checksBox = document.getElementById('column-checks');
  buildForm(form, COLUMN_GROUPS);

  // Only one of c and ζ₁ is sent (giving both is 422).
  const dampingKind = form.querySelector('[data-local="damping"]');
  const syncDamping = () => {
    const ratio = dampingKind.value === 'ratio';
    form.querySelector('[data-pointer="/column/damping_coefficient_n_s_m2"]').disabled = ratio;
    form.querySelector('[data-pointer="/column/damping_ratio"]').disabled = !ratio;
  };
  dampingKind.addEventListener('change', syncDamping);
  form.addEventListener('reset', () => setTimeout(syncDamping));
  syncDamping();

  const panel = initPanel({
    name: 'column',
    form,
    forms: [form, impactForm],
    endpoint: 'v1/column',
    status,
    build: ([own, caseRead]) => {
      const base = merge(caseRead.request, own.request);
      delete base.output;
      if (own.request.output) base.output = own.request.output;
      const models = own.local.models === 'both' ? MODELS : [own.local.models];
      const notes = [];
      const requests = models.map((model) => requestFor(model, base, models.length > 1, notes));
      return { models, requests, notes };
    },
    busy: ({ models }) => `Computing ${models.join(' and ')}…`,
    send: async ({ models, requests, notes }, { signal }) => {
      const answers = await Promise.all(requests.map((r) => postJson('v1/column', r, { signal })));
      const failed = answers.findIndex((a) => !a.ok);
      if (failed >= 0) {
        const { problem } = answers[failed];
        return { ok: false, problem, label: models.length > 1 && problem.status !== 404 ? `${models[failed]} model` : '' };
      }
      const results = {};
      models.forEach((m, i) => { results[m] = answers[i].data; });
      return { ok: true, data: results, note: notes.join(' ') };
    },
    render: (results) => render(results),
    clear: () => render({}),
  });

  function render(results) {
    showUsed(form, null);
    const shown = MODELS.filter((m) => results[m]);
    plotsBox.hidden = !shown.length;
    if (!shown.length) {
      empty.hidden = false;
      checksBox.replaceChildren();
      table.tHead.replaceChildren();
      table.tBodies[0].replaceChildren();
      showWarnings(warnings, []);
      plotMessage(wavePlot, 'No history.');
      for (const el of Object.values(energyPlots)) destroy(el);
      return;
    }
    empty.hidden = true;
    renderTable(results, shown);
    checksBox.replaceChildren(...shown.map((m) => {
      const box = h('div', { class: 'model-checks' }, h('h4', {}, m === 'decoupled' ? 'decoupled (paper)' : 'coupled'));
      const inner = h('div', {});
      renderChecks(inner, columnChecks(results[m]), `${m}.`);
      box.append(inner);
      return box;
    }));
    showUsed(form, results[shown[0]].inputs);
    showWarnings(warnings, mergeWarnings(results, shown));
    renderWave(results, shown);
    for (const model of MODELS) {
      energyPlots[model].closest('.card').hidden = !results[model];
      if (results[model]) renderEnergy(energyPlots[model], results[model], model);
      else destroy(energyPlots[model]);
    }
  }

  function renderTable(results, shown) {
    table.tHead.replaceChildren(h('tr', {},
      h('th', {}, 'Quantity'), h('th', {}, ''),
      shown.map((m) => h('th', { class: 'num' }, m === 'decoupled' ? 'decoupled (paper)' : 'coupled')),
      h('th', {}, 'Unit')));
    const tbody = table.tBodies[0];
    tbody.replaceChildren();
    for (const [label, symbol, unit, ...getters] of ROWS) {
      const values = shown.map((m) => {
        const getter = getters[MODELS.indexOf(m)];
        if (!getter) return undefined;
        return typeof getter === 'function' ? getter(results[m]) : pick(results[m], getter);
      });
      if (values.every((v) => v === undefined)) continue;
      const key = shown.map((m) => getters[MODELS.indexOf(m)]);
      tbody.append(h('tr', {},
        h('th', { scope: 'row' }, label),
        h('td', { class: 'sym', html: symbol }),
        values.map((v, i) => h('td', {
          class: 'num',
          dataset: typeof key[i] === 'string' ? { out: `${shown[i]}.${key[i]}` } : {},
        }, show(v, unit))),
        h('td', { class: 'unit' }, unit.unit ?? '')));
    }
  }

  function show(value, { scale = 1, sig = 6 }) {
    if (value === undefined) return '';
    if (typeof value === 'string') return value;
    if (Array.isArray(value)) return value.map((v) => fmt(v * scale, sig)).join(', ');
    return fmt(value === null ? null : value * scale, sig);
  }

  function renderWave(results, shown) {
    const tables = shown.filter((m) => results[m].history).map((m) => {
      const hist = results[m].history;
      return [hist.time_s.map((t) => t * 1e3), hist.midpoint_displacement_m.map((w) => w * 1e3)];
    });
    const named = shown.filter((m) => results[m].history);
    if (!tables.length) {
      plotMessage(wavePlot, 'No history was returned (set a duration).');
      return;
    }
    const joined = tables.length > 1 ? joinSeries(tables) : tables[0];
    linePlot(wavePlot, {
      x: { label: 'time (ms)', values: joined[0] },
      y: { label: 'midpoint displacement (mm)' },
      series: named.map((m, i) => ({ label: m, values: joined[i + 1], color: COLORS[MODELS.indexOf(m)] })),
    });
    wavePlot.csv = () => historyRows(results, named);
  }

  function renderEnergy(el, data, model) {
    const hist = data.history;
    if (!hist) {
      plotMessage(el, `${model}: no history.`);
      return;
    }
    const series = [
      ['column kinetic', hist.kinetic_energy_j],
      ['column strain', hist.strain_energy_j],
      ['dissipated', hist.dissipated_energy_j],
      ['rock kinetic', hist.rock_kinetic_energy_j],
      ['contact', hist.contact_energy_j],
    ].filter(([, values]) => values);
    linePlot(el, {
      x: { label: 'time (ms)', values: hist.time_s.map((t) => t * 1e3) },
      y: { label: 'energy (J)' },
      series: series.map(([label, values], i) => ({ label, values, color: COLORS[(i + 2) % COLORS.length] })),
      height: 240,
    });
    el.csv = () => historyRows({ [model]: data }, [model]);
  }

  return panel;
}

/** One entry per distinct warning, naming the models that gave it. */
/** Every history column of every model, one row per sample (long format). */
function historyRows(results, shown) {
  const keys = new Set();
  for (const m of shown) for (const k of Object.keys(results[m].history)) keys.add(k);
  const cols = ['time_s', ...[...keys].filter((k) => k !== 'time_s')];
  const rows = [['model', ...cols]];
  for (const m of shown) {
    const hist = results[m].history;
    hist.time_s.forEach((_, i) => rows.push([m, ...cols.map((k) => hist[k]?.[i] ?? '')]));
  }
  return rows;
}

function mergeWarnings(results, shown) {
  const merged = new Map();
  for (const model of shown) {
    for (const w of results[model].warnings ?? []) {
      const key = `${w.code}\n${w.message}`;
      if (!merged.has(key)) merged.set(key, { ...w, models: [] });
      merged.get(key).models.push(model);
    }
  }
  return [...merged.values()].map((w) => ({ code: `${w.models.join(', ')}: ${w.code}`, message: w.message }));
}

/** The request for one model: fields the other model owns are left out. */
function requestFor(model, base, both, notes) {
  const request = structuredClone(base);
  request.model = model;
  if (model === 'decoupled') {
    if (request.galerkin) delete request.galerkin.modes;
    delete request.end_time_s;
  } else {
    delete request.initial_midpoint_displacement_m;
    const shapes = request.galerkin?.mode_shapes;
    if (both && shapes && shapes !== 'exact') {
      delete request.galerkin.mode_shapes;
      notes.push(`The coupled model uses exact mode shapes (${shapes} applies to the decoupled one).`);
    }
  }
  return request;
}
