// Impact tab: POST /v1/impact, Hertz contact of a rock on the column.

import { impactChecks, renderChecks } from './checks.js';
import { buildForm, showUsed } from './form.js';
import { fillTable, fmt, showWarnings } from './format.js';
import { initPanel } from './panel.js';
import { destroy, linePlot, plotMessage } from './plot.js';

const CURVE_POINTS = 200;

/** The fields; their starting values are the server's defaults (GET /v1/presets) and the settings. */
export const IMPACT_GROUPS = [
  {
    legend: 'Impact',
    fields: [
      { pointer: '/velocity_m_s', label: 'Velocity <i>v</i>', unit: 'm/s' },
    ],
  },
  {
    legend: 'Rock (cube)',
    pointer: '/rock',
    fields: [
      { pointer: '/rock/side_length_m', label: 'Side <i>L</i>', unit: 'mm', exp: -3 },
      { pointer: '/rock/density_kg_m3', label: 'Density <i>ρ</i>', unit: 'kg/m³' },
      { pointer: '/rock/elastic_modulus_pa', label: 'Elastic modulus <i>E</i>', unit: 'GPa', exp: 9 },
      { pointer: '/rock/poisson_ratio', label: 'Poisson ratio <i>ν</i>', unit: '' },
      {
        pointer: '/rock/corner_radius_m', label: 'Corner radius <i>r</i><sub>c</sub>', unit: 'mm', exp: -3,
        placeholder: 'auto', hint: 'empty: min(20 mm, <i>L</i>/2); used by <code>hertz_point</code> only',
      },
    ],
  },
  {
    legend: 'Column (first stage)',
    pointer: '/column',
    fields: [
      { pointer: '/column/outer_diameter_m', label: 'Outer diameter <i>D</i>₁', unit: 'mm', exp: -3 },
      { pointer: '/column/inner_diameter_m', label: 'Inner diameter <i>D</i>₂', unit: 'mm', exp: -3 },
      { pointer: '/column/length_m', label: 'Length <i>l</i>', unit: 'm' },
      { pointer: '/column/elastic_modulus_pa', label: 'Steel modulus <i>E</i><sub>s</sub>', unit: 'GPa', exp: 9 },
      { pointer: '/column/poisson_ratio', label: 'Poisson ratio <i>ν</i><sub>s</sub>', unit: '' },
      { pointer: '/column/density_kg_m3', label: 'Density <i>ρ</i><sub>s</sub>', unit: 'kg/m³' },
      { pointer: '/column/yield_stress_pa', label: 'Yield stress <i>σ</i><sub>y</sub>', unit: 'MPa', exp: 6, hint: 'the limit of the stress and contact-pressure checks' },
      { pointer: '/column/contact_radius_m', label: 'Contact radius <i>R</i>', unit: 'mm', exp: -3, placeholder: 'auto', hint: 'empty: half the outer diameter' },
    ],
  },
  {
    legend: 'Contact',
    pointer: '/contact',
    fields: [
      {
        pointer: '/contact/law', label: 'Contact law', kind: 'select', settings: true,
        options: [['johnson', 'johnson (recommended)'], ['paper', 'paper (Eq. 4)'], ['hertz_point', 'hertz_point (corner)']],
        hint: '<b>johnson</b>: a face or edge of the cube strikes the column (line contact, corrected law); <b>paper</b>: reproduces the paper\'s numbers; <b>hertz_point</b>: a corner strikes (point contact)',
      },
      {
        pointer: '/contact/effective_modulus', label: 'Effective modulus <i>E</i>*', kind: 'select', settings: true,
        options: [['two_body', 'two_body (recommended)'], ['paper', 'paper (rock only)']],
        hint: 'two_body counts the steel\'s own deformation; the paper neglects it',
      },
      {
        pointer: '/contact/hertz_exact', label: 'Exact elliptical Hertz <i>κ</i>', kind: 'checkbox',
        hint: 'hertz_point only: elliptical contact, else the equivalent radius',
      },
    ],
  },
];

const kN = { unit: 'kN', scale: 1e-3, alt: { unit: 'MN', scale: 1e-6 } };

const ROWS = [
  { key: 'mass_kg', label: 'Rock mass', symbol: '<i>m</i>', unit: 'kg', sig: 5 },
  { key: 'kinetic_energy_j', label: 'Kinetic energy', symbol: 'KE', unit: 'J', sig: 6 },
  { key: 'effective_modulus_pa', label: 'Effective modulus', symbol: '<i>E</i>*', unit: 'GPa', scale: 1e-9, sig: 6 },
  { key: 'contact_radius_m', label: 'Contact radius', symbol: '<i>R</i>', unit: 'mm', scale: 1e3, sig: 5 },
  { key: 'energy_parameter', label: 'Energy parameter', symbol: '<i>G</i>', unit: '', sig: 6 },
  { key: 'lambert_w', label: 'Lambert W₋₁(−G/e)', symbol: '<i>W</i>', unit: '', sig: 7 },
  { key: 'max_deformation_m', label: 'Maximum approach', symbol: '<i>δ</i><sub>max</sub>', unit: 'mm', scale: 1e3, sig: 6 },
  { key: 'max_force_n', label: 'Maximum force', symbol: '<i>P</i><sub>max</sub>', sig: 6, ...kN },
  { key: 'contact_half_width_m', label: 'Contact half width', symbol: '<i>a</i>', unit: 'mm', scale: 1e3, sig: 5 },
  { key: 'hertz_stiffness_n_m1_5', label: 'Hertz stiffness', symbol: '<i>κ</i>', unit: 'GN/m<sup>1.5</sup>', scale: 1e-9, sig: 6 },
  { key: 'equivalent_radius_m', label: 'Equivalent radius', symbol: '<i>R</i><sub>e</sub>', unit: 'mm', scale: 1e3, sig: 5 },
  { key: 'max_deformation_equivalent_radius_m', label: 'Approach with R<sub>e</sub>', symbol: '<i>δ</i><sub>max,e</sub>', unit: 'mm', scale: 1e3, sig: 6 },
  { key: 'contact_ellipse_axis_ratio', label: 'Ellipse axis ratio', symbol: '<i>b</i>/<i>a</i>', unit: '', sig: 5 },
  { key: 'contact_semi_axes_m', label: 'Contact semi-axes', symbol: '<i>a</i>, <i>b</i>', unit: 'mm', scale: 1e3, sig: 5 },
  { key: 'max_contact_pressure_pa', label: 'Max contact pressure', symbol: '<i>p</i>₀', unit: 'MPa', scale: 1e-6, sig: 5 },
  { key: 'contact_duration_s', label: 'Contact duration (rigid column)', symbol: '<i>t</i><sub>c</sub>', unit: 'ms', scale: 1e3, sig: 6 },
  { key: 'energy_capacity_j', label: 'Contact-law capacity (limit of the law, not of the column)', symbol: '<i>E</i><sub>cap</sub>', unit: 'J', sig: 6 },
  { key: 'deformation_capacity_m', label: 'Approach at the law\'s capacity', symbol: '<i>δ</i><sub>cap</sub>', unit: 'mm', scale: 1e3, sig: 6 },
  { key: 'force_capacity_n', label: 'Force at the law\'s capacity', symbol: '<i>P</i><sub>cap</sub>', sig: 6, ...kN },
];
for (const row of ROWS) row.label = htmlLabel(row.label);

function htmlLabel(text) {
  const span = document.createElement('span');
  span.innerHTML = text;
  return span;
}

export function initImpact() {
  const form = document.getElementById('impact-form');
  const status = document.getElementById('impact-status');
  const warnings = document.getElementById('impact-warnings');
  const tbody = document.querySelector('#impact-table tbody');
  const empty = document.getElementById('impact-empty');
  const plotEl = document.getElementById('impact-plot');
  const capacity = document.getElementById('impact-capacity');
  const checks = document.getElementById('impact-checks');
  buildForm(form, IMPACT_GROUPS);

  const panel = initPanel({
    name: 'impact',
    form,
    endpoint: 'v1/impact',
    status,
    build: ([own]) => ({ ...own.request, output: { curve_points: CURVE_POINTS } }),
    render,
    clear,
  });

  function clear() {
    empty.hidden = false;
    tbody.replaceChildren();
    checks.replaceChildren();
    capacity.replaceChildren();
    showWarnings(warnings, []);
    destroy(plotEl);
    showUsed(form, null);
  }

  function render(data) {
    empty.hidden = true;
    fillTable(tbody, ROWS, data);
    renderChecks(checks, impactChecks(data));
    showWarnings(warnings, data.warnings);
    showUsed(form, data.inputs);
    renderCapacity(data);
    renderCurve(data);
  }

  function renderCapacity(data) {
    capacity.replaceChildren();
    if (data.energy_capacity_j !== undefined) {
      capacity.innerHTML =
        `<b>Limit of the contact law, not of the column.</b> The <code>${data.law}</code> law has no solution ` +
        `beyond <i>E</i><sub>cap</sub> = ${fmt(data.energy_capacity_j, 4)} J (reached at an approach of ` +
        `${fmt(data.deformation_capacity_m * 1e3, 4)} mm, far outside the law's validity). Being below it says ` +
        'nothing about whether the column survives: see the checks above.';
    } else {
      capacity.innerHTML =
        `The <code>${data.law ?? 'hertz_point'}</code> law has no capacity: its force grows without bound with ` +
        'the approach. That is a property of the law, not of the column: see the checks above.';
    }
  }

  function renderCurve(data) {
    const curve = data.curve;
    if (!curve || !curve.deformation_m?.length) {
      plotMessage(plotEl, 'The response has no curve.');
      return;
    }
    const xs = curve.deformation_m.map((d) => d * 1e3);
    const ys = curve.force_n.map((p) => p * 1e-3);
    // Mark the maximum at the curve point nearest δmax (the last one).
    let iMax = xs.length - 1;
    const target = data.max_deformation_m * 1e3;
    xs.forEach((x, i) => { if (Math.abs(x - target) < Math.abs(xs[iMax] - target)) iMax = i; });
    const marker = ys.map((y, i) => (i === iMax ? y : null));
    linePlot(plotEl, {
      x: { label: 'approach δ (mm)', values: xs },
      y: { label: 'force P (kN)' },
      series: [
        { label: 'P(δ)', values: ys },
        {
          label: `maximum: δmax ${fmt(data.max_deformation_m * 1e3, 5)} mm, Pmax ${fmt(data.max_force_n * 1e-3, 5)} kN`,
          values: marker,
          points: 'only',
          color: '#c8423b',
        },
      ],
    });
    plotEl.csv = () => [['approach_m', 'force_n'], ...curve.deformation_m.map((d, i) => [d, curve.force_n[i]])];
  }

  return panel;
}
