// Spalling tab: POST /v1/spalling. Table 1 (paper) is editable; the answer
// shows the zone shares, P1 = P(A|B), P2 = P(A|C) with Wilson 95 % intervals,
// and a bar chart by zone. Percentages whose denominator is 0 arrive as null.

import { parseNumber } from './form.js';
import { fmt, h, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, linePlot, plotMessage } from './plot.js';

/** The paper's Table 1 as the server's default zones (GET /v1/presets `defaults.spalling`). */
let table1 = [];

/** Fills the counts table from the server's default zones. */
export function setSpallingDefaults(spalling) {
  table1 = spalling.zones;
  const input = document.getElementById('spalling-input');
  if (input) countsTable(input, table1);
}
const COUNTS = [
  ['spalling', 'A (spalling)'],
  ['high_resistance', 'B (high resistance)'],
  ['low_resistance', 'C (low resistance)'],
  ['spalling_and_high', 'A∩B'],
  ['spalling_and_low', 'A∩C'],
];
const DERIVED = [
  ['spalling_share_pct', 'share of A, %'],
  ['high_share_pct', 'share of B, %'],
  ['low_share_pct', 'share of C, %'],
  ['spalling_given_high_pct', 'P₁ = P(A|B), %'],
  ['spalling_given_high_ci95_pct', 'P₁ 95 % interval (Wilson), %'],
  ['spalling_given_low_pct', 'P₂ = P(A|C), %'],
  ['spalling_given_low_ci95_pct', 'P₂ 95 % interval (Wilson), %'],
  ['high_given_spalling_pct', 'P(B|A), %'],
  ['low_given_spalling_pct', 'P(C|A), %'],
];

function countsTable(el, zones) {
  const head = h('tr', {}, h('th', {}, 'event'), ...zones.map((z, i) => h('th', {},
    h('input', { type: 'text', value: z.name, 'data-zone': i, 'data-field': 'name', 'aria-label': `zone ${i} name`, size: 8 }))));
  const rows = COUNTS.map(([key, label]) => h('tr', {}, h('th', { scope: 'row' }, label),
    ...zones.map((z, i) => h('td', {}, h('input', {
      type: 'text', inputmode: 'decimal', size: 7, value: z[key], 'data-zone': i, 'data-field': key,
      'aria-label': `${label}, zone ${z.name}`, id: `spalling-zones-${i}-${key}`, 'data-target': `/zones/${i}/${key}`,
    })))));
  el.replaceChildren(h('thead', {}, head), h('tbody', {}, ...rows));
}

function readZones(el) {
  const zones = [];
  const fieldErrors = [];
  for (const input of el.querySelectorAll('input[data-zone]')) {
    const i = Number(input.dataset.zone);
    zones[i] ??= {};
    if (input.dataset.field === 'name') {
      zones[i].name = input.value;
      continue;
    }
    const parsed = parseNumber(input.value);
    if (parsed.error) fieldErrors.push({ field: `/zones/${i}/${input.dataset.field}`, message: parsed.error });
    zones[i][input.dataset.field] = parsed.value;
  }
  if (fieldErrors.length) throw { fieldErrors };
  return zones;
}

function cell(v) {
  if (Array.isArray(v)) return `${fmt(v[0], 4)} – ${fmt(v[1], 4)}`;
  return fmt(v, 4);
}

function resultTable(el, data) {
  const all = [...data.zones, data.total];
  const head = h('tr', {}, h('th', {}, ''), ...all.map((z) => h('th', {}, z.name)));
  const rows = DERIVED.map(([key, label]) => h('tr', {}, h('th', { scope: 'row' }, label),
    ...all.map((z, i) => h('td', { 'data-out': `${i < data.zones.length ? `zones/${i}` : 'total'}/${key}` }, cell(z[key])))));
  el.replaceChildren(h('thead', {}, head), h('tbody', {}, ...rows));
}

function barChart(el, data) {
  const zones = data.zones;
  if (!zones.length) return plotMessage(el, 'No zones.');
  const xs = zones.map((_, i) => i + 1);
  linePlot(el, {
    x: { label: `zone (${zones.map((z, i) => `${i + 1} ${z.name}`).join(', ')})`, values: xs, range: [0.5, zones.length + 0.5] },
    y: { label: '%', range: [0, 100] },
    series: [
      { label: 'P₁ = P(A|B)', values: zones.map((z) => z.spalling_given_high_pct), bars: true },
      { label: 'P₂ = P(A|C)', values: zones.map((z) => z.spalling_given_low_pct), bars: true },
      { label: 'share of A', values: zones.map((z) => z.spalling_share_pct), points: 'only' },
    ],
  });
}

/**
 * The spalling count as the Scene's release rate: observed_events (the total count, whole) over
 * the period typed beside the button; the Scene's release-rate group is ticked and shown.
 */
function sendCount(data) {
  const note = document.getElementById('spalling-send-note');
  const events = data.total.spalling;
  const period = parseNumber(document.getElementById('spalling-period').value, 0, 'years');
  if (!Number.isInteger(events)) {
    note.textContent = `The total count ${fmt(events, 6)} is not whole: the release rate needs whole events.`;
    return;
  }
  if (period.error || period.empty || !(period.value > 0 && period.value <= 1000)) {
    note.textContent = 'The period must be a number of years in (0, 1000].';
    return;
  }
  const scene = document.getElementById('scene-form');
  const box = scene.querySelector('input[name="scene_release_rate"]');
  box.checked = true;
  box.dispatchEvent(new Event('change', { bubbles: true }));
  const set = (pointer, v) => {
    const el = scene.querySelector(`[data-pointer="${pointer}"]`);
    el.value = v;
    el.dispatchEvent(new Event('change', { bubbles: true }));
  };
  set('/release_rate/rocks_per_year', '');
  set('/release_rate/observed_events', String(events));
  set('/release_rate/observed_period_years', String(period.value));
  note.textContent = `Sent: ${events} events over ${fmt(period.value, 6)} years to the Scene.`;
  document.getElementById('tab-scene').click();
  box.closest('fieldset').scrollIntoView({ block: 'center' });
}

let last = null;

export function initSpalling() {
  document.getElementById('spalling-to-scene')?.addEventListener('click', () => last && sendCount(last));
  const form = document.getElementById('spalling-form');
  const input = document.getElementById('spalling-input');
  const status = document.getElementById('spalling-status');
  const warnings = document.getElementById('spalling-warnings');
  const output = document.getElementById('spalling-table');
  const plot = document.getElementById('spalling-plot');
  if (!form) return null;
  form.addEventListener('reset', (event) => {
    event.preventDefault();
    countsTable(input, table1);
  });
  return initPanel({
    name: 'spalling',
    form,
    endpoint: 'v1/spalling',
    status,
    build: () => ({ zones: readZones(input) }),
    busy: () => 'Computing the zone statistics…',
    render: (data) => {
      showWarnings(warnings, data.warnings);
      resultTable(output, data);
      document.getElementById('spalling-empty').hidden = true;
      barChart(plot, data);
      last = data;
      document.getElementById('spalling-send').hidden = false;
    },
    clear: () => {
      showWarnings(warnings, []);
      last = null;
      document.getElementById('spalling-send').hidden = true;
      output.replaceChildren();
      document.getElementById('spalling-empty').hidden = false;
      destroy(plot);
    },
  });
}
