// Study tab: POST /v1/study. Parameter ranges prefilled with the paper's;
// named and shown in the engineer's words and units (SI on the wire); curves of each output against p/p_max, heat maps of the
// pair grids, the Figure 21 chart, sensitivity and ordering tables beside the
// paper's, and a CSV of every table.

import { parseNumber, toSi } from './form.js';
import { csvText, fmt, h, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, linePlot } from './plot.js';

/** The server's default study (GET /v1/presets `defaults.study`): the paper's ranges and points. */
let defaults = { parameters: [], points: '' };

/** Study parameters in words: [name, symbol, display unit, decimal exponent from the unit to SI]. */
const QUANTITIES = {
  velocity_m_s: ['Impact velocity', 'v', 'm/s', 0],
  'rock.side_length_m': ['Rock size', 'L', 'mm', -3],
  'rock.elastic_modulus_pa': ['Rock elastic modulus', 'E', 'GPa', 9],
  'rock.density_kg_m3': ['Rock density', 'ρ', 'kg/m³', 0],
  'rock.poisson_ratio': ['Rock Poisson ratio', 'ν', '', 0],
  'column.outer_diameter_m': ['Column outer diameter', 'D₁', 'mm', -3],
  'column.inner_diameter_m': ['Column inner diameter', 'D₂', 'mm', -3],
  'column.length_m': ['Column length', 'l', 'm', 0],
  'column.elastic_modulus_pa': ['Column elastic modulus', 'Ec', 'GPa', 9],
  'column.density_kg_m3': ['Column density', 'ρc', 'kg/m³', 0],
  'column.poisson_ratio': ['Column Poisson ratio', 'νc', '', 0],
  'column.yield_stress_pa': ['Column yield stress', 'σy', 'MPa', 6],
};

/** Study outputs in words: [name, display unit, factor from SI]. */
const OUTPUTS = {
  max_deformation_m: ['Max approach δmax', 'mm', 1e3],
  max_force_n: ['Max force Pmax', 'kN', 1e-3],
  absorbed_energy_j: ['Column energy', 'J', 1],
  energy_ratio: ['Energy ratio (column / rock)', '', 1],
  max_contact_deformation_m: ['Max contact approach δmax', 'mm', 1e3],
  column_energy_after_contact_j: ['Column energy after contact', 'J', 1],
  kinetic_energy_j: ['Rock kinetic energy', 'J', 1],
  stress_utilisation: ['Stress utilisation σ/σy', '%', 100],
  'max_bending_stress_pa.clamp': ['Bending stress at the clamp', 'MPa', 1e-6],
  'max_bending_stress_pa.midpoint': ['Bending stress at mid-length', 'MPa', 1e-6],
  initial_modal_displacement_m: ['Initial modal displacement', 'mm', 1e3],
  max_midpoint_displacement_m: ['Mid-length displacement', 'mm', 1e3],
  contact_count: ['Contacts', '', 1],
  rebound_velocity_m_s: ['Rebound velocity', 'm/s', 1],
  rock_velocity_end_m_s: ['Rock velocity at the end', 'm/s', 1],
  column_energy_end_j: ['Column energy at the end', 'J', 1],
  damping_energy_j: ['Energy lost to damping', 'J', 1],
};

const quantity = (name) => QUANTITIES[name] ?? [name, name, '', 0];
/** "Rock elastic modulus E (GPa)". */
export const paramWords = (name) => {
  const [words, symbol, unit] = quantity(name);
  return `${words}${QUANTITIES[name] ? ` ${symbol}` : ''}${unit ? ` (${unit})` : ''}`;
};
/** An SI value of a parameter in its display unit. */
const paramShown = (name, si) => Number(`${si}e${-quantity(name)[3]}`);
const outputWords = (o) => {
  const [words, unit] = OUTPUTS[o] ?? [o, '', 1];
  return unit ? `${words} (${unit})` : words;
};
const outputScale = (o) => OUTPUTS[o]?.[2] ?? 1;
/** An ordering of parameter names ("a=b" ties) in symbols: "L > v > ρ = E". */
const orderingWords = (list) => list.map((n) => n.split('=').map((x) => quantity(x)[1]).join(' = ')).join(' > ');
/** Server notes without the specification's section numbers. */
const plainNote = (text) => String(text ?? '').replace(/\s*\((?:see )?physics\.md[^)]*\)/g, '').replace(/physics\.md\s*§\s*[\w.]+/g, 'the physics notes');

function paramRows(el, rows) {
  el.replaceChildren(
    h('thead', {}, h('tr', {}, h('th', {}, 'Parameter'), h('th', {}, 'from'), h('th', {}, 'to'), h('th', {}, 'unit'), h('th', {}, 'vary'))),
    h('tbody', {}, ...rows.map(({ name, min, max }, i) => {
      const [words, , unit, exp] = quantity(name);
      const number = (field, value) => h('input', {
        type: 'text', inputmode: 'decimal', value: paramShown(name, value), 'data-param': i, 'data-field': field, 'data-exp': exp,
        id: `study-parameters-${i}-${field}`, 'data-target': `/parameters/${i}/${field}`, 'aria-label': `${words} ${field === 'min' ? 'from' : 'to'}${unit ? ` (${unit})` : ''}`, size: 10,
      });
      return h('tr', {},
        h('th', { scope: 'row' }, h('input', { type: 'hidden', value: name, 'data-param': i, 'data-field': 'name', id: `study-parameters-${i}-name`, 'data-target': `/parameters/${i}/name` }),
          paramWords(name).replace(/ \([^)]*\)$/, '')),
        h('td', {}, number('min', min)),
        h('td', {}, number('max', max)),
        h('td', { class: 'unit' }, unit),
        h('td', {}, h('input', { type: 'checkbox', checked: true, 'data-param': i, 'data-field': 'use', 'aria-label': `vary ${words}` })),
      );
    })),
  );
}

function readRequest(form, table) {
  const rows = [];
  const fieldErrors = [];
  for (const input of table.querySelectorAll('input[data-param]')) {
    const i = Number(input.dataset.param);
    rows[i] ??= {};
    const f = input.dataset.field;
    if (f === 'use') rows[i][f] = input.checked;
    else if (f === 'name') rows[i][f] = input.value.trim();
    else {
      const parsed = parseNumber(input.value, Number(input.dataset.exp ?? 0));
      if (parsed.error) fieldErrors.push({ field: input.dataset.target, message: parsed.error });
      rows[i][f] = parsed.value;
    }
  }
  const points = parseNumber(form.elements.points.value);
  if (points.error || !Number.isInteger(points.value)) {
    fieldErrors.push({ field: '/points', message: points.error ?? 'must be a whole number' });
  }
  if (fieldErrors.length) throw { fieldErrors };
  // Only the ticked parameters are sent; the request names them by position in that list.
  const used = rows.map((r, i) => [r, i]).filter(([r]) => r.use);
  for (const input of table.querySelectorAll('input[data-param]')) {
    const k = used.findIndex(([, i]) => i === Number(input.dataset.param));
    input.dataset.target = k < 0 ? '' : `/parameters/${k}/${input.dataset.field}`;
  }
  const parameters = used.map(([{ name, min, max }]) => ({ name, min, max }));
  const get = (name) => form.elements[name].value;
  const base = { model: get('model'), contact: { law: get('law'), effective_modulus: get('effective_modulus') } };
  return { base, parameters, points: points.value, grid: get('grid') };
}

/** A link that saves `rows` as CSV, headed (version, date, case) when it is clicked. */
function csvLink(rows, name, words = 'this table') {
  const a = h('a', { class: 'csv', download: name, title: `Download ${name}`, href: '#' }, `CSV: ${words}`);
  a.addEventListener('click', () => { a.href = `data:text/csv;charset=utf-8,${encodeURIComponent(csvText(rows))}`; });
  return a;
}

function tableOf(rows, name, { numeric = true } = {}) {
  const [head, ...body] = rows;
  return h('div', { class: 'table-block' },
    h('div', { class: 'table-scroll' }, h('table', { class: 'results-table' },
      h('thead', {}, h('tr', {}, ...head.map((c) => h('th', {}, c)))),
      h('tbody', {}, ...body.map((r) => h('tr', {}, ...r.map((c, j) => (j === 0 ? h('th', { scope: 'row' }, c) : h('td', {}, numeric && typeof c === 'number' ? fmt(c, 5) : c ?? '—')))))))),
    csvLink(rows, name));
}

/** A colour from blue (low) to red (high), t in [0, 1]. */
const heat = (t) => `hsl(${220 - 220 * t}, 70%, ${35 + 25 * t}%)`;

/** A heat map with ticks on both axes (parameters in their units) and a colour bar (the output in its unit). */
function heatMap(grid, output) {
  const scale = outputScale(output);
  const z = grid[output].map((row) => row.map((v) => v * scale));
  const ny = z.length;
  const nx = z[0].length;
  let lo = Infinity;
  let hi = -Infinity;
  for (const row of z) for (const v of row) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  const cw = Math.max(14, Math.min(40, Math.floor(300 / nx)));
  const ch = Math.max(12, Math.min(28, Math.floor(220 / ny)));
  const left = 64;
  const bottom = 44;
  const top = 10;
  const bar = 70;
  const W = left + nx * cw + bar;
  const H = top + ny * ch + bottom;
  const xs = grid.x_values.map((v) => paramShown(grid.x, v));
  const ys = grid.y_values.map((v) => paramShown(grid.y, v));
  const summary = `${outputWords(output)} over ${paramWords(grid.x)} (${fmt(xs[0], 4)} to ${fmt(xs[nx - 1], 4)}) and ${paramWords(grid.y)} (${fmt(ys[0], 4)} to ${fmt(ys[ny - 1], 4)}): from ${fmt(lo, 4)} (blue) to ${fmt(hi, 4)} (red)`;
  const canvas = h('canvas', { width: W, height: H, role: 'img', 'aria-label': summary });
  const ctx = canvas.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, W, H);
  for (let i = 0; i < ny; i += 1) {
    for (let j = 0; j < nx; j += 1) {
      ctx.fillStyle = heat(hi > lo ? (z[i][j] - lo) / (hi - lo) : 0.5);
      // Row 0 (y min) at the bottom.
      ctx.fillRect(left + j * cw, top + (ny - 1 - i) * ch, cw, ch);
    }
  }
  ctx.fillStyle = '#1c2430';
  ctx.strokeStyle = '#3b4350';
  ctx.font = '10px system-ui, sans-serif';
  // Ticks: every cell when they fit, else about five.
  const every = (n, room) => Math.max(1, Math.ceil(n / Math.max(1, Math.floor(room))));
  ctx.textAlign = 'center';
  for (let j = 0; j < nx; j += every(nx, (nx * cw) / 44)) {
    const x = left + (j + 0.5) * cw;
    ctx.beginPath(); ctx.moveTo(x, top + ny * ch); ctx.lineTo(x, top + ny * ch + 4); ctx.stroke();
    ctx.fillText(fmt(xs[j], 3), x, top + ny * ch + 14);
  }
  ctx.textAlign = 'right';
  for (let i = 0; i < ny; i += every(ny, (ny * ch) / 16)) {
    const y = top + (ny - 1 - i + 0.5) * ch;
    ctx.beginPath(); ctx.moveTo(left - 4, y); ctx.lineTo(left, y); ctx.stroke();
    ctx.fillText(fmt(ys[i], 3), left - 6, y + 3);
  }
  ctx.textAlign = 'center';
  ctx.font = '600 10px system-ui, sans-serif';
  ctx.fillText(paramWords(grid.x), left + (nx * cw) / 2, top + ny * ch + 32);
  ctx.save();
  ctx.translate(12, top + (ny * ch) / 2);
  ctx.rotate(-Math.PI / 2);
  ctx.fillText(paramWords(grid.y), 0, 0);
  ctx.restore();
  // The colour bar: the output's range, low at the bottom.
  const bx = left + nx * cw + 12;
  const bh = ny * ch;
  for (let k = 0; k < bh; k += 1) {
    ctx.fillStyle = heat(1 - k / Math.max(1, bh - 1));
    ctx.fillRect(bx, top + k, 12, 1);
  }
  ctx.strokeRect(bx, top, 12, bh);
  ctx.fillStyle = '#1c2430';
  ctx.font = '10px system-ui, sans-serif';
  ctx.textAlign = 'left';
  for (const [t, v] of [[0, hi], [0.5, (lo + hi) / 2], [1, lo]]) ctx.fillText(fmt(v, 3), bx + 16, top + t * bh + 4);
  canvas.dataset.bar = `${bx},${top},${bh}`;
  return h('figure', { class: 'heatmap' }, h('figcaption', { class: 'heatmap-title' }, outputWords(output)), canvas,
    h('figcaption', { class: 'note' }, summary));
}

function render(data, els) {
  const outputs = data.inputs.outputs;
  const params = data.inputs.parameters.map((p) => p.name);

  // Curves: one plot per output against p/p_max.
  els.curves.replaceChildren();
  for (const o of outputs) {
    const plot = h('div', { class: 'plot' });
    els.curves.append(h('div', { class: 'card' }, h('h3', {}, outputWords(o)), plot));
    const n = data.inputs.points;
    const series = params.map((p) => ({ label: paramWords(p).replace(/ \([^)]*\)$/, ''), values: data.curves[p][o].map((v) => v * outputScale(o)) }));
    // Each curve on its own x = p/p_max: join on a common axis.
    const xs = [...new Set(params.flatMap((p) => data.curves[p].values.map((v) => v / data.inputs.parameters.find((q) => q.name === p).max)))].sort((a, b) => a - b);
    const aligned = series.map((s, k) => {
      const p = params[k];
      const max = data.inputs.parameters[k].max;
      const map = new Map(data.curves[p].values.map((v, i) => [v / max, s.values[i]]));
      return { ...s, values: xs.map((x) => map.get(x) ?? null), points: true, pointSize: 5 };
    });
    if (n >= 2) linePlot(plot, { x: { label: 'parameter ÷ its largest value', values: xs }, y: { label: outputWords(o) }, series: aligned });
  }

  // Figure 21.
  const ep = data.energy_proportion;
  linePlot(els.fig21, {
    x: { label: 'x = parameter ÷ its largest value', values: ep.x },
    y: { label: `energy ratio (${ep.model})` },
    series: params.map((p) => ({ label: paramWords(p).replace(/ \([^)]*\)$/, ''), values: ep.curves[p], points: true, pointSize: 6 })),
  });
  const epRows = [['x = p ÷ largest', ...params.map((p) => quantity(p)[1]), 'ordering (highest first)'], ...ep.x.map((x, i) => [fmt(x, 4), ...params.map((p) => ep.curves[p][i]), orderingWords(ep.orderings[i])])];
  els.fig21Table.replaceChildren(tableOf(epRows, 'energy_proportion.csv'));

  // Sensitivity tables.
  els.sensitivity.replaceChildren();
  for (const o of outputs) {
    const s = data.sensitivity[o];
    const [, unit] = OUTPUTS[o] ?? [o, ''];
    const k = outputScale(o);
    const rows = [['parameter', `output at the low end${unit ? ` (${unit})` : ''}`, `at the high end${unit ? ` (${unit})` : ''}`, 'span / base', 'high / low', 'elasticity'],
      ...params.map((p) => {
        const m = s.parameters[p];
        return [paramWords(p).replace(/ \([^)]*\)$/, ''), m.low * k, m.high * k, m.span_over_base, m.ratio, m.elasticity];
      })];
    const MEASURES = { span_over_base: 'span / base', ratio: 'high / low', elasticity: 'elasticity' };
    const orderRows = [['measure', 'ordering (largest first)'],
      ...Object.entries(s.ordering).map(([m, v]) => [MEASURES[m] ?? m, orderingWords(v)])];
    els.sensitivity.append(h('div', { class: 'card' }, h('h3', {}, `${outputWords(o)}: base ${fmt(s.base * k)}`),
      tableOf(rows, `sensitivity_${o}.csv`), tableOf(orderRows, `ordering_${o}.csv`, { numeric: false })));
  }

  // Paper comparison.
  const cmp = [['item', 'paper', 'ours', 'reproduced', 'note'],
    ...data.paper_comparison.map((c) => [c.item, c.paper, c.ours, c.reproduced ? 'yes' : 'no', plainNote(c.note)])];
  els.paper.replaceChildren(data.paper_comparison.length
    ? tableOf(cmp, 'paper_comparison.csv', { numeric: false })
    : h('p', { class: 'note' }, 'No comparison: the paper states its orderings for its own four parameters and ranges.'));

  // Heat maps.
  els.grids.replaceChildren();
  for (const g of data.grids ?? []) {
    for (const o of outputs) {
      const rows = [[`${paramWords(g.y)} \\ ${paramWords(g.x)}: ${outputWords(o)}`, ...g.x_values.map((v) => paramShown(g.x, v))],
        ...g.y_values.map((y, i) => [paramShown(g.y, y), ...g[o][i].map((v) => v * outputScale(o))])];
      els.grids.append(h('div', { class: 'card' }, heatMap(g, o), csvLink(rows, `grid_${g.x}_${g.y}_${o}.csv`, 'this grid')));
    }
  }
}

/** Fills the study form from the server's default study request. */
export function setStudyDefaults(study) {
  defaults = study;
  const form = document.getElementById('study-form');
  if (!form) return;
  paramRows(document.getElementById('study-parameters'), study.parameters);
  form.elements.points.value = String(study.points);
  form.elements.points.defaultValue = String(study.points);
  for (const o of form.elements.grid.options) o.defaultSelected = o.value === study.grid;
  form.elements.grid.value = study.grid;
}

export function initStudy() {
  const form = document.getElementById('study-form');
  if (!form) return null;
  const table = document.getElementById('study-parameters');
  const status = document.getElementById('study-status');
  const warnings = document.getElementById('study-warnings');
  const els = {
    curves: document.getElementById('study-curves'),
    fig21: document.getElementById('study-fig21'),
    fig21Table: document.getElementById('study-fig21-table'),
    sensitivity: document.getElementById('study-sensitivity'),
    paper: document.getElementById('study-paper'),
    grids: document.getElementById('study-grids'),
  };
  form.elements.points.dataset.target = '/points';
  form.elements.points.type = 'text';
  form.elements.points.inputMode = 'numeric';
  form.addEventListener('reset', () => setTimeout(() => paramRows(table, defaults.parameters)));
  const panel = initPanel({
    name: 'study',
    form,
    endpoint: 'v1/study',
    status,
    progress: document.getElementById('study-progress'),
    unit: 'points',
    build: () => readRequest(form, table),
    stream: () => true,
    busy: () => 'Running the study…',
    render: (data) => {
      showWarnings(warnings, data.warnings);
      document.getElementById('study-empty').hidden = true;
      document.getElementById('study-results').hidden = false;
      destroy(els.fig21);
      render(data, els);
    },
    clear: () => {
      showWarnings(warnings, []);
      document.getElementById('study-empty').hidden = false;
      document.getElementById('study-results').hidden = true;
      destroy(els.fig21);
      for (const el of [els.curves, els.fig21Table, els.sensitivity, els.paper, els.grids]) el.replaceChildren();
    },
  });
  return panel;
}
