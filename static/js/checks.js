// Checked quantities: each shown with its limit, the ratio and a coloured
// verdict. "exceeded": past a limit of the support (yield); "invalid": the
// result lies outside the model's validity and must not be relied on.

import { fmt, h } from './format.js';

/** Verdict words, shown in the table and printed. */
export const VERDICT_WORDS = {
  ok: 'OK',
  exceeded: 'EXCEEDED',
  invalid: 'OUTSIDE VALIDITY',
};

/**
 * Checks of an impact answer: contact pressure against the column's yield
 * stress (elastic contact) and the approach against a tenth of the contact
 * radius (Hertz's small-approach assumption).
 */
export function impactChecks(data) {
  const checks = [];
  const yieldPa = data.inputs?.column?.yield_stress_pa;
  if (typeof data.max_contact_pressure_pa === 'number' && typeof yieldPa === 'number') {
    const over = data.max_contact_pressure_pa > yieldPa;
    checks.push({
      key: 'contact_pressure',
      label: 'Max contact pressure p₀ vs the column\'s yield stress σy',
      value: data.max_contact_pressure_pa * 1e-6,
      allowed: yieldPa * 1e-6,
      unit: 'MPa',
      verdict: over ? 'exceeded' : 'ok',
      note: over
        ? 'the steel yields under the contact: elastic (Hertz) contact does not hold, so δmax and Pmax are outside the model\'s validity'
        : 'elastic contact',
    });
  }
  const radius = data.contact_radius_m;
  if (typeof data.max_deformation_m === 'number' && typeof radius === 'number') {
    const allowed = radius / 10;
    const over = data.max_deformation_m > allowed;
    checks.push({
      key: 'approach',
      label: 'Max approach δmax vs a tenth of the contact radius R/10',
      value: data.max_deformation_m * 1e3,
      allowed: allowed * 1e3,
      unit: 'mm',
      verdict: over ? 'invalid' : 'ok',
      note: over
        ? 'the approach is comparable to the radius: Hertz theory assumes it is small, so this result is outside its validity'
        : 'small approach (Hertz assumption holds)',
    });
  }
  return checks;
}

/** Checks of a column answer (one model): bending-stress utilisation, energy balance. */
export function columnChecks(data) {
  const checks = [];
  const yieldPa = data.inputs?.column?.yield_stress_pa;
  if (typeof data.stress_utilisation === 'number') {
    const stress = Math.max(data.max_bending_stress_pa?.clamp ?? 0, data.max_bending_stress_pa?.midpoint ?? 0);
    const over = data.stress_utilisation > 1;
    checks.push({
      key: 'stress_utilisation',
      label: 'Largest bending stress vs the yield stress σy',
      value: stress * 1e-6,
      allowed: typeof yieldPa === 'number' ? yieldPa * 1e-6 : null,
      ratio: data.stress_utilisation,
      unit: 'MPa',
      verdict: over ? 'exceeded' : 'ok',
      note: over
        ? `the column yields (${fmt(data.stress_utilisation * 100, 4)} % of σy): the support is overloaded, and past yield the elastic beam model no longer describes it`
        : 'elastic',
    });
  }
  if (data.model === 'decoupled' && typeof data.energy_ratio === 'number') {
    const over = data.energy_ratio > 1;
    checks.push({
      key: 'energy_ratio',
      label: 'Column energy vs the rock\'s kinetic energy',
      value: data.absorbed_energy_j,
      allowed: data.kinetic_energy_j,
      unit: 'J',
      verdict: over ? 'invalid' : 'ok',
      note: over
        ? 'the decoupled method puts more energy into the column than the rock brought (energy not conserved): use the coupled model'
        : 'energy conserved',
    });
  }
  return checks;
}

/** Fills `el` with a checks table (or empties it when there are none). */
export function renderChecks(el, checks, prefix = '') {
  el.replaceChildren();
  if (!checks.length) return;
  el.append(h('table', { class: 'results-table checks' },
    h('thead', {}, h('tr', {}, h('th', {}, 'Check'), h('th', { class: 'num' }, 'Value'),
      h('th', { class: 'num' }, 'Limit'), h('th', { class: 'num' }, 'Ratio'), h('th', {}, 'Verdict'))),
    h('tbody', {}, checks.map((c) => {
      const ratio = 'ratio' in c ? c.ratio : (c.allowed && typeof c.value === 'number' ? c.value / c.allowed : null);
      return h('tr', { class: `verdict-${c.verdict}`, dataset: { check: prefix + c.key, verdict: c.verdict } },
        h('th', { scope: 'row' }, c.label),
        h('td', { class: 'num' }, c.value === null ? '—' : `${fmt(c.value, 5)} ${c.unit}`.trim()),
        h('td', { class: 'num' }, c.allowed === null || c.allowed === undefined ? '—' : `${fmt(c.allowed, 5)} ${c.unit}`.trim()),
        h('td', { class: 'num' }, ratio === null ? '—' : `${fmt(ratio * 100, 4)} %`),
        h('td', {}, h('span', { class: `badge ${c.verdict}` }, VERDICT_WORDS[c.verdict]), h('span', { class: 'why' }, c.note)));
    }))));
}
