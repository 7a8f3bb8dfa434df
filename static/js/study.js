// Study tab: POST /v1/study. Parameter ranges prefilled with the paper's
// (physics.md §D.1); curves of each output against p/p_max, heat maps of the
// pair grids, the Figure 21 chart, sensitivity and ordering tables beside the
// paper's, and a CSV of every table.

import { parseNumber } from './form.js';
import { fmt, h, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, linePlot } from './plot.js';

/** The server's default study (GET /v1/presets `defaults.study`): the paper's ranges and points. */
let defaults = { parameters: [], points: '' };

function paramRows(el, rows) {
  el.replaceChildren(
    h('thead', {}, h('tr', {}, h('th', {}, 'parameter (dotted path)'), h('th', {}, 'min'), h('th', {}, 'max'), h('th', {}, 'use'))),
    h('tbody', {}, ...rows.map(({ name, min, max }, i) => h('tr', {},
      h('td', {}, h('input', { type: 'text', value: name, 'data-param': i, 'data-field': 'name', size: 24, id: `study-parameters-${i}-name`, 'data-target': `/parameters/${i}/name`, 'aria-label': `parameter ${i + 1}` })),
      h('td', {}, h('input', { type: 'text', inputmode: 'decimal', value: min, 'data-param': i, 'data-field': 'min', id: `study-parameters-${i}-min`, 'data-target': `/parameters/${i}/min`, 'aria-label': `${name} min`, size: 10 })),
      h('td', {}, h('input', { type: 'text', inputmode: 'decimal', value: max, 'data-param': i, 'data-field': 'max', id: `study-parameters-${i}-max`, 'data-target': `/parameters/${i}/max`, 'aria-label': `${name} max`, size: 10 })),
      h('td', {}, h('input', { type: 'checkbox', checked: true, 'data-param': i, 'data-field': 'use', 'aria-label': `use ${name}` })),
    ))),
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
      const parsed = parseNumber(input.value);
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

/** CSV text of a table of rows (arrays of cells). */
function csv(rows) {
  return rows.map((r) => r.map((c) => {
    const s = c === null || c === undefined ? '' : String(c);
    return /[",\n]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s;
  }).join(',')).join('\n') + '\n';
}

function csvLink(rows, name) {
  const a = h('a', { class: 'csv', download: name, href: `data:text/csv;charset=utf-8,${encodeURIComponent(csv(rows))}` }, `CSV: ${name}`);
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

function heatMap(grid, output) {
  const z = grid[output];
  const ny = z.length;
  const nx = z[0].length;
  const flat = z.flat();
  const lo = Math.min(...flat);
  const hi = Math.max(...flat);
  const cw = 36;
  const ch = 24;
  const canvas = h('canvas', { width: nx * cw, height: ny * ch, role: 'img', 'aria-label': `${output} over ${grid.x} and ${grid.y}` });
  const ctx = canvas.getContext('2d');
  for (let i = 0; i < ny; i += 1) {
    for (let j = 0; j < nx; j += 1) {
      const t = hi > lo ? (z[i][j] - lo) / (hi - lo) : 0.5;
      ctx.fillStyle = `hsl(${220 - 220 * t}, 70%, ${35 + 25 * t}%)`;
      // Row 0 (y min) at the bottom.
      ctx.fillRect(j * cw, (ny - 1 - i) * ch, cw, ch);
    }
  }
  return h('figure', { class: 'heatmap' }, canvas,
    h('figcaption', {}, `${output}: x = ${grid.x} (${fmt(grid.x_values[0])} → ${fmt(grid.x_values[nx - 1])}), y = ${grid.y} (${fmt(grid.y_values[0])} bottom → ${fmt(grid.y_values[ny - 1])} top); ${fmt(lo)} (blue) to ${fmt(hi)} (red)`));
}

function render(data, els) {
  const outputs = data.inputs.outputs;
  const params = data.inputs.parameters.map((p) => p.name);

  // Curves: one plot per output against p/p_max.
  els.curves.replaceChildren();
  for (const o of outputs) {
    const plot = h('div', { class: 'plot' });
    els.curves.append(h('div', { class: 'card' }, h('h3', {}, o), plot));
    const n = data.inputs.points;
    const series = params.map((p) => ({ label: p, values: data.curves[p][o] }));
    // Each curve on its own x = p/p_max: join on a common axis.
    const xs = [...new Set(params.flatMap((p) => data.curves[p].values.map((v) => v / data.inputs.parameters.find((q) => q.name === p).max)))].sort((a, b) => a - b);
    const aligned = series.map((s, k) => {
      const p = params[k];
      const max = data.inputs.parameters[k].max;
      const map = new Map(data.curves[p].values.map((v, i) => [v / max, s.values[i]]));
      return { ...s, values: xs.map((x) => map.get(x) ?? null), points: true, pointSize: 5 };
    });
    if (n >= 2) linePlot(plot, { x: { label: 'p / p_max', values: xs }, y: { label: o }, series: aligned });
  }

  // Figure 21.
  const ep = data.energy_proportion;
  linePlot(els.fig21, {
    x: { label: 'x = p / p_max', values: ep.x },
    y: { label: `energy ratio (${ep.model})` },
    series: params.map((p) => ({ label: p, values: ep.curves[p], points: true, pointSize: 6 })),
  });
  const epRows = [['x', ...params, 'ordering (highest first)'], ...ep.x.map((x, i) => [fmt(x, 4), ...params.map((p) => ep.curves[p][i]), ep.orderings[i].join(' > ')])];
  els.fig21Table.replaceChildren(tableOf(epRows, 'energy_proportion.csv'));

  // Sensitivity tables.
  els.sensitivity.replaceChildren();
  for (const o of outputs) {
    const s = data.sensitivity[o];
    const rows = [['parameter', 'low', 'high', 'span/base', 'ratio', 'elasticity'],
      ...params.map((p) => {
        const m = s.parameters[p];
        return [p, m.low, m.high, m.span_over_base, m.ratio, m.elasticity];
      })];
    const orderRows = [['measure', 'ordering (largest first)'],
      ...Object.entries(s.ordering).map(([k, v]) => [k, v.join(' > ')])];
    els.sensitivity.append(h('div', { class: 'card' }, h('h3', {}, `${o} (base ${fmt(s.base)})`),
      tableOf(rows, `sensitivity_${o}.csv`), tableOf(orderRows, `ordering_${o}.csv`, { numeric: false })));
  }

  // Paper comparison.
  const cmp = [['item', 'paper', 'ours', 'reproduced', 'note'],
    ...data.paper_comparison.map((c) => [c.item, c.paper, c.ours, c.reproduced ? 'yes' : 'no', c.note])];
  els.paper.replaceChildren(data.paper_comparison.length
    ? tableOf(cmp, 'paper_comparison.csv', { numeric: false })
    : h('p', { class: 'note' }, 'No comparison: the paper states its orderings for its own four parameters and ranges.'));

  // Heat maps.
  els.grids.replaceChildren();
  for (const g of data.grids ?? []) {
    for (const o of outputs) {
      const rows = [[`${g.y} \\ ${g.x}`, ...g.x_values], ...g.y_values.map((y, i) => [y, ...g[o][i]])];
      els.grids.append(h('div', { class: 'card' }, heatMap(g, o), csvLink(rows, `grid_${g.x}_${g.y}_${o}.csv`)));
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
