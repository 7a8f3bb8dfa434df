// Migration tab: POST /v1/migration with the lumped-mass method or the
// rigid block (DEM): one trajectory, or a seeded Monte Carlo ensemble streamed
// with progress.

import { initFloor } from './floor.js';
import { buildForm } from './form.js';
import { csvButton, fillTable, fmt, h, showWarnings } from './format.js';
import { postJson } from './api.js';
import { initPanel } from './panel.js';
import { destroy, joinSeries, linePlot, plotMessage } from './plot.js';
import { clearFloorViews, defaultMapGrid, offFloor, floorModel, renderFloorViews } from './floorview.js';
import { groupDigits, targetProgress } from './scene.js';

/** The vector fields the form reads component by component (`…/0`, `…/1`, …), sent as arrays. */
const VECTOR_FIELDS = ['/rock/dimensions_m', '/release/velocity_m_s', '/release/orientation_wxyz', '/release/angular_velocity_rad_s'];

/** Turns the objects {0: …, 1: …} the form builds at the vector fields into arrays. */
export function vectorsToArrays(request) {
  for (const pointer of VECTOR_FIELDS) {
    const keys = pointer.split('/').slice(1);
    const parent = keys.slice(0, -1).reduce((o, k) => (o ? o[k] : undefined), request);
    const last = keys[keys.length - 1];
    const v = parent?.[last];
    if (v && typeof v === 'object' && !Array.isArray(v)) {
      parent[last] = Object.keys(v).sort((a, b) => a - b).map((k) => v[k]);
    }
  }
}

/** Why the friction spread starts from the page's own values. */
const FRICTION_SPREAD = 'an example spread: the server has none unless one is sent';

const MIGRATION_GROUPS = [
  {
    legend: 'Working face',
    pointer: '/face',
    fields: [
      { pointer: '/face/dip_deg', label: 'Dip <i>θ</i>', unit: '°' },
      { pointer: '/face/length_m', label: 'Length along the dip', unit: 'm' },
      { pointer: '/face/friction_coefficient', label: 'Friction coefficient <i>μ</i>', unit: '' },
      { pointer: '/face/restitution_normal', label: 'Normal restitution <i>e</i><sub>n</sub>', unit: '' },
      { pointer: '/face/restitution_tangential', label: 'Tangential restitution <i>e</i><sub>t</sub>', unit: '' },
    ],
  },
  {
    legend: 'Rock',
    pointer: '/rock',
    fields: [
      {
        pointer: '/method', label: 'Method', kind: 'select',
        options: [['lumped_mass', 'lumped mass'], ['rigid_block', 'rigid block (DEM)']],
        hint: '<b>lumped mass</b>: a point with restitution and friction, fast (closed-form flights); <b>rigid block</b>: the cube tumbles and its corners strike (as PFC3D in the paper), slower',
      },
      {
        pointer: '/rock/shape', label: 'Shape', kind: 'select',
        options: [['cube', 'cube'], ['sphere', 'sphere (r = L/2)'], ['cuboid', 'cuboid (dimensions below)'], ['ellipsoid', 'ellipsoid (dimensions below)']],
        hint: 'the shape sets the mass and, for the rigid block, how it tumbles; a cuboid or an ellipsoid takes its measured dimensions',
      },
      {
        pointer: '/rock/side_length_m', label: 'Size <i>L</i>', unit: 'mm', exp: -3,
        hint: 'a cube\'s side or a sphere\'s diameter; a cuboid or an ellipsoid takes its dimensions below instead',
      },
      { pointer: '/rock/density_kg_m3', label: 'Density <i>ρ</i>', unit: 'kg/m³' },
      {
        pointer: '/lumped_mass/motion', label: 'Ground motion', kind: 'select',
        options: [['slide', 'slide'], ['roll', 'roll (sphere, no slip)']],
        hint: 'lumped mass: <b>slide</b> with friction μ, or <b>roll</b> as a sphere without slip (needs μ ≥ (2/7) tan θ)',
      },
    ],
  },
  {
    legend: 'Block dimensions (cuboid, ellipsoid)',
    pointer: '/rock/dimensions_m',
    toggle: { name: 'rock_dimensions', checked: false },
    note: 'The measured dimensions a × b × c along the block\'s own x, y, z axes; an ellipsoid is a 64-point polyhedron with the ellipsoid\'s volume πabc/6.',
    fields: [0, 1, 2].map((k) => ({
      pointer: `/rock/dimensions_m/${k}`, label: ['<i>a</i> (x)', '<i>b</i> (y)', '<i>c</i> (z)'][k], unit: 'mm', exp: -3,
      choice: { value: [460, 300, 200][k], why: 'a plate-like block to edit' },
    })),
  },
  {
    legend: 'Release',
    pointer: '/release',
    fields: [
      { pointer: '/release/drop_height_m', label: 'Drop height', unit: 'm' },
      { pointer: '/release/along_dip_m', label: 'Along the dip', unit: 'm' },
      { pointer: '/release/across_m', label: 'Across the face', unit: 'm' },
      { pointer: '/release/speed_m_s', label: 'Initial speed (down-dip)', unit: 'm/s' },
    ],
  },
  {
    legend: 'Release velocity vector',
    pointer: '/release/velocity_m_s',
    toggle: { name: 'release_velocity', checked: false },
    note: 'Instead of the down-dip speed: [v<sub>x</sub>, v<sub>y</sub>, v<sub>z</sub>] in the face frame (x down the dip, y across, z up). On the floor (drop height 0) only its part along the floor is kept.',
    fields: [0, 1, 2].map((k) => ({
      pointer: `/release/velocity_m_s/${k}`, label: `<i>v</i><sub>${'xyz'[k]}</sub>`, unit: 'm/s',
      choice: { value: [1, 0, 0][k], why: 'a starting velocity to edit' },
    })),
  },
  {
    legend: 'Release orientation and spin (rigid block)',
    pointer: '/release/orientation_wxyz',
    toggle: { name: 'release_orientation', checked: false },
    note: 'The unit quaternion [w, x, y, z] turning the block\'s own axes into the face frame (identity: its a, b, c along x, y, z), and its initial angular velocity in the face frame. The block starts with its lowest point on the floor, lifted by the drop height.',
    fields: [
      ...[0, 1, 2, 3].map((k) => ({
        pointer: `/release/orientation_wxyz/${k}`, label: `<i>q</i><sub>${'wxyz'[k]}</sub>`, unit: '',
        choice: { value: [1, 0, 0, 0][k], why: 'the identity rotation to edit' },
      })),
      ...[0, 1, 2].map((k) => ({
        pointer: `/release/angular_velocity_rad_s/${k}`, label: `<i>ω</i><sub>${'xyz'[k]}</sub>`, unit: 'rad/s',
        choice: { value: 0, why: 'not spinning: no initial angular velocity' },
      })),
    ],
  },
  {
    legend: 'Monte Carlo ensemble',
    pointer: '/monte_carlo',
    toggle: { name: 'monte_carlo', checked: false },
    note: 'Restitution drawn uniformly at every impact (lumped mass). The outcome table shows the nominal run; the ensemble is in the percentiles.',
    fields: [
      { pointer: '/monte_carlo/runs', label: 'Runs', kind: 'integer' },
      { pointer: '/monte_carlo/seed', label: 'Seed', kind: 'integer' },
      { pointer: '/monte_carlo/restitution_normal/min', label: '<i>e</i><sub>n</sub> min', unit: '' },
      { pointer: '/monte_carlo/restitution_normal/max', label: '<i>e</i><sub>n</sub> max', unit: '' },
      { pointer: '/monte_carlo/restitution_tangential/min', label: '<i>e</i><sub>t</sub> min', unit: '' },
      { pointer: '/monte_carlo/restitution_tangential/max', label: '<i>e</i><sub>t</sub> max', unit: '' },
      {
        pointer: '/monte_carlo/release_orientation', label: 'Release orientation', kind: 'select',
        options: [['fixed', 'fixed (the release\'s)'], ['uniform', 'uniformly random per run (rigid block)']],
        hint: 'a block\'s orientation at release is rarely known: draw it per run',
      },
    ],
  },
  {
    legend: 'Until precise enough (ensemble)',
    pointer: '/monte_carlo/target',
    toggle: { name: 'migration_target', checked: false },
    note: 'Stops the ensemble at the first of 1 000, 2 000, 4 000, … runs (and at Runs, then the most allowed) where the percentile of the arrival speed is known '
      + 'to ± the given share of its value (its distribution-free 95 % interval, over the runs that reached the lower end).',
    fields: [
      { pointer: '/monte_carlo/target/percentile', label: 'Percentile of the arrival speed', unit: '%', exp: -2, choice: { value: 95, why: 'the design percentile' } },
      {
        pointer: '/monte_carlo/target/relative_half_width', label: 'known to ±', unit: '%', exp: -2, choice: { value: 2, why: 'a starting precision to edit' },
        hint: 'percentile in [1, 99] %; precision in (0, 100] % of its value',
      },
    ],
  },
  {
    legend: 'Friction spread (ensemble)',
    pointer: '/monte_carlo/friction_coefficient',
    toggle: { name: 'friction_spread', checked: false },
    note: 'Truncated normal, drawn once per run.',
    fields: [
      { pointer: '/monte_carlo/friction_coefficient/mean', label: 'Mean', unit: '', choice: { value: 0.2, why: FRICTION_SPREAD } },
      { pointer: '/monte_carlo/friction_coefficient/std', label: 'Standard deviation', unit: '', choice: { value: 0.02, why: FRICTION_SPREAD } },
      { pointer: '/monte_carlo/friction_coefficient/min', label: 'Min', unit: '', choice: { value: 0, why: FRICTION_SPREAD } },
      { pointer: '/monte_carlo/friction_coefficient/max', label: 'Max', unit: '', choice: { value: 1, why: FRICTION_SPREAD } },
    ],
  },
  {
    legend: 'Output',
    pointer: '/output',
    fields: [
      {
        pointer: '/output/trajectory', label: 'Trajectory', kind: 'checkbox',
        choice: { value: true, why: 'the page draws the trajectory; the server samples it only when asked' },
      },
      { pointer: '/output/sample_interval_s', label: 'Sample interval', unit: 's' },
    ],
  },
];

const ROWS = [
  { key: 'arrival.speed_m_s', label: 'Speed', symbol: '<i>v</i>', unit: 'm/s', sig: 6 },
  { key: 'arrival.time_s', label: 'Time (with the fall)', symbol: '<i>t</i>', unit: 's', sig: 6 },
  { key: 'arrival.kinetic_energy_j', label: 'Kinetic energy', symbol: 'KE', unit: 'kJ', scale: 1e-3, sig: 5 },
  { key: 'arrival.along_dip_velocity_m_s', label: 'Down-dip velocity', symbol: '<i>v</i><sub>s</sub>', unit: 'm/s', sig: 5, noise: (d) => d.arrival.speed_m_s },
  { key: 'arrival.normal_velocity_m_s', label: 'Normal velocity', symbol: '<i>v</i><sub>n</sub>', unit: 'm/s', sig: 5, noise: (d) => d.arrival.speed_m_s },
  { key: 'arrival.angular_speed_rad_s', label: 'Rotation speed', symbol: '<i>ω</i>', unit: 'rad/s', sig: 5, noise: (d) => d.arrival.speed_m_s / (d.inputs?.rock?.side_length_m ?? 1) },
  { key: 'arrival.stop_reason', label: 'Outcome', symbol: '', words: (_, d) => outcomeWords(d) },
  { key: 'arrival.phase', label: 'Motion at the end', symbol: '', words: (p, d) => (d.arrival.stop_reason === 'left_floor' ? 'left the floor' : PHASE_WORDS[p] ?? p) },
  { key: 'arrival.along_dip_m', label: 'Final position along the dip', symbol: '<i>s</i>', unit: 'm', sig: 5 },
  { key: 'impact_count', label: 'Impacts', symbol: '' },
  { key: 'slide_start_along_dip_m', label: 'Ground phase starts at', symbol: '<i>s</i>', unit: 'm', sig: 6 },
  { key: 'max_bounce_height_m', label: 'Highest bounce', symbol: '<i>h</i><sub>max</sub>', unit: 'm', sig: 5 },
  { key: 'energy.total_start_j', label: 'Energy at the start', symbol: '<i>E</i>₀', unit: 'kJ', scale: 1e-3, sig: 6 },
  { noise: (d) => d.energy.total_start_j, key: 'energy.impacts_j', label: 'Lost in impacts', symbol: '', unit: 'kJ', scale: 1e-3, sig: 6 },
  { noise: (d) => d.energy.total_start_j, key: 'energy.friction_j', label: 'Lost to friction', symbol: '', unit: 'kJ', scale: 1e-3, sig: 6 },
  { noise: (d) => d.energy.total_start_j, key: 'energy.transition_j', label: 'Lost at the flight–ground transition', symbol: '', unit: 'J', sig: 4 },
  { noise: (d) => d.energy.total_start_j, key: 'energy.damping_j', label: 'Lost to contact damping (rigid block)', symbol: '', unit: 'kJ', scale: 1e-3, sig: 6 },
  { noise: (d) => d.energy.total_start_j, key: 'energy.residual_j', label: 'Energy residual', symbol: '', unit: 'J', sig: 3 },
];

const STATS = [
  ['speed_m_s', 'Arrival speed', 'm/s', 1],
  ['along_dip_velocity_m_s', 'Down-dip velocity at arrival', 'm/s', 1],
  ['kinetic_energy_j', 'Arrival kinetic energy', 'kJ', 1e-3],
  ['time_s', 'Arrival time', 's', 1],
  ['impact_count', 'Impacts', '', 1],
  ['runout_m', 'Run-out', 'm', 1],
  ['max_bounce_height_m', 'Highest bounce', 'm', 1],
];
const STAT_COLUMNS = ['mean', 'std', 'min', 'p05', 'p50', 'p95', 'p99', 'max'];

export function initMigration() {
  const form = document.getElementById('migration-form');
  const status = document.getElementById('migration-status');
  const warnings = document.getElementById('migration-warnings');
  const tbody = document.querySelector('#migration-table tbody');
  const empty = document.getElementById('migration-empty');
  const progress = document.getElementById('migration-progress');
  const progressBar = progress.querySelector('progress');
  const progressText = progress.querySelector('.progress-text');
  const statsCard = document.getElementById('migration-stats-card');
  const histogram = document.getElementById('migration-histogram');
  const percentiles = document.getElementById('migration-percentiles');
  const trajectoryBox = document.getElementById('migration-trajectory');
  const results = form.closest('[data-panel]').querySelector('.results');
  const statsCaption = document.getElementById('migration-stats-caption');
  const percentilesCard = document.getElementById('migration-percentiles-card');
  const plots = {
    side: document.getElementById('migration-side-plot'),
    plan: document.getElementById('migration-plan-plot'),
    energy: document.getElementById('migration-energy-plot'),
    orientation: document.getElementById('migration-orientation-plot'),
  };
  const orientationCard = document.getElementById('migration-orientation-card');
  const compareBox = document.getElementById('migration-compare');
  const comparePlot = document.getElementById('migration-compare-plot');
  const compareBody = document.querySelector('#migration-compare-table tbody');
  // "Compare both methods" runs the panel once with this set: the request is sent
  // with each method and the answer carries both.
  let compareNext = false;
  buildForm(form, MIGRATION_GROUPS);
  const floor = initFloor(form);
  form.floor = floor;
  const sideNote = document.getElementById('migration-side-note');
  let runsCsv = null;
  percentilesCard.append(csvButton('migration_runs.csv', () => {
    if (!runsCsv) return [['no per-run table: run an ensemble']];
    return runsCsv.trim().split('\n').map((line) => line.split(','));
  }, 'CSV: every run'));

  const mcBox = form.querySelector('input[name="monte_carlo"]');
  const frictionBox = form.querySelector('input[name="friction_spread"]');
  const frictionSet = frictionBox.closest('fieldset');
  const targetBox = form.querySelector('input[name="migration_target"]');
  const targetSet = targetBox.closest('fieldset');
  const runsLabel = form.querySelector('[data-pointer="/monte_carlo/runs"]').closest('.field').querySelector('label');
  const syncFriction = () => {
    frictionBox.disabled = !mcBox.checked;
    frictionSet.disabled = !mcBox.checked || !frictionBox.checked;
    targetBox.disabled = !mcBox.checked;
    targetSet.disabled = !mcBox.checked || !targetBox.checked;
    // with a target, Runs is the most the ensemble may take
    runsLabel.textContent = mcBox.checked && targetBox.checked ? 'Most runs allowed' : 'Runs';
  };
  targetBox.addEventListener('change', syncFriction);
  mcBox.addEventListener('change', syncFriction);
  frictionBox.addEventListener('change', syncFriction);
  form.addEventListener('reset', () => setTimeout(syncFriction));
  syncFriction();

  // Rolling without slip needs μ ≥ (2/7) tan θ (physics.md §C): choosing "roll"
  // raises a smaller μ to the least allowed value and says so, instead of a 422.
  const motion = form.querySelector('[data-pointer="/lumped_mass/motion"]');
  const mu = form.querySelector('[data-pointer="/face/friction_coefficient"]');
  const dip = form.querySelector('[data-pointer="/face/dip_deg"]');
  const rollNote = h('p', { class: 'hint roll-note', hidden: true });
  motion.closest('.field').append(rollNote);
  const syncRoll = (raise) => {
    const theta = Number(dip.value) * Math.PI / 180;
    const least = (2 / 7) * Math.tan(theta);
    rollNote.hidden = motion.value !== 'roll' || !Number.isFinite(least);
    if (rollNote.hidden) return;
    const needed = Math.ceil(least * 1000) / 1000;
    const now = Number(mu.value);
    if (raise && !(now >= least)) {
      mu.value = String(needed);
      rollNote.textContent = `Rolling without slip needs μ ≥ (2/7) tan θ = ${fmt(least, 4)} at θ = ${dip.value}°: μ was raised from ${now} to ${needed}.`;
    } else if (!(now >= least)) {
      rollNote.textContent = `Rolling without slip needs μ ≥ (2/7) tan θ = ${fmt(least, 4)} at θ = ${dip.value}°: raise μ to at least ${needed}, or choose "slide".`;
    } else {
      rollNote.textContent = `Rolling without slip: μ = ${now} ≥ (2/7) tan θ = ${fmt(least, 4)}.`;
    }
  };
  motion.addEventListener('change', () => syncRoll(true));
  for (const el of [mu, dip]) el.addEventListener('input', () => syncRoll(false));
  form.addEventListener('reset', () => setTimeout(() => syncRoll(false)));

  const panel = initPanel({
    name: 'migration',
    form,
    endpoint: 'v1/migration',
    status,
    progress,
    unit: 'runs',
    build: ([own]) => {
      const request = own.request;
      vectorsToArrays(request);
      floor.apply(request, own.local);
      floor.applyZones(request);
      const model = floorModel({ face: request.face }, floor.current());
      const r = request.release ?? {};
      const off = offFloor(model, r.along_dip_m ?? 0, r.across_m ?? 0);
      if (off) throw { fieldErrors: [{ field: '/release/along_dip_m', message: `the release ${off}: move it onto the floor` }] };
      const rigid = request.method === 'rigid_block';
      const mc = request.monte_carlo;
      if (mc && rigid) {
        // the rigid block has no restitution: its ensemble varies friction only here
        delete mc.restitution_normal;
        delete mc.restitution_tangential;
      }
      if (mc?.target) {
        const { percentile: p, relative_half_width: r } = mc.target;
        const errors = [];
        if (!(p >= 0.01 && p <= 0.99)) errors.push({ field: '/monte_carlo/target/percentile', message: `must be in [1, 99] %, not ${fmt(p * 100, 6)} %` });
        if (!(r > 0 && r <= 1)) errors.push({ field: '/monte_carlo/target/relative_half_width', message: `must be above 0 and at most 100 %, not ${fmt(r * 100, 6)} %` });
        if (errors.length) throw { fieldErrors: errors };
      }
      if (mc) {
        for (const key of ['restitution_normal', 'restitution_tangential']) {
          if (mc[key]) mc[key] = { distribution: 'uniform', ...mc[key] };
        }
        if (mc.friction_coefficient) mc.friction_coefficient = { distribution: 'truncated_normal', ...mc.friction_coefficient };
        // the ensemble's per-cell maps, drawn on the floor view
        request.output = { ...request.output, runs_csv: true, maps: defaultMapGrid(request, floor.current(), mc.runs) };
      }
      if (compareNext) {
        // the ensemble is kept: the service compares the two methods' ensembles within their
        // intervals (one run each without one)
        compareNext = false;
        request.output = { ...request.output, trajectory: true, runs_csv: false };
        delete request.output.maps;
        Object.defineProperty(request, 'compare', { value: true, enumerable: false });
      }
      return request;
    },
    send: (request, opts) => (request.compare ? sendBoth(request, opts) : postJson('v1/migration', request, opts)),
    stream: (request) => Boolean(request.monte_carlo) && !request.compare,
    busy: (request) => (request.compare
      ? (request.monte_carlo ? `Computing ${request.monte_carlo.runs} runs with each method…` : 'Computing with both methods…')
      : request.monte_carlo?.target ? `Running up to ${groupDigits(request.monte_carlo.runs)} runs, stopping when precise enough…`
        : request.monte_carlo ? `Running ${request.monte_carlo.runs} runs…` : 'Computing…'),
    progressText: (p, request) => targetProgress(p, request),
    render,
    clear: () => {
      empty.hidden = false;
      tbody.replaceChildren();
      tableTitle.textContent = 'Outcome of the run';
      showWarnings(warnings, []);
      renderStatistics(null);
      renderTrajectory(null);
      renderComparison(null);
      clearFloorViews('migration');
    },
  });

  document.getElementById('migration-compare-button').addEventListener('click', () => {
    compareNext = true;
    panel.run();
  });

  /**
   * Sends the request with output.compare_methods (the service runs the other method on the
   * same case and ensemble and says whether the two agree, and why not), and the other method
   * once more without the ensemble for its trajectory; the answer is the form's own method's,
   * with both attached.
   */
  async function sendBoth(request, opts) {
    const ownMethod = request.method ?? 'lumped_mass';
    const otherMethod = ownMethod === 'lumped_mass' ? 'rigid_block' : 'lumped_mass';
    const answers = {};
    const own = await postJson('v1/migration',
      { ...request, method: ownMethod, output: { ...(request.output ?? {}), compare_methods: true } },
      { signal: opts.signal });
    if (!own.ok) return { ...own, label: `with "method": "${ownMethod}"` };
    answers[ownMethod] = own.data;
    const other = { ...request, method: otherMethod };
    delete other.monte_carlo;
    if (otherMethod === 'lumped_mass') delete other.rigid_block;
    else delete other.lumped_mass;
    if (other.output) other.output = { ...other.output, runs_csv: false, maps: undefined };
    const answer = await postJson('v1/migration', other, { signal: opts.signal });
    if (!answer.ok) return { ...answer, label: `with "method": "${otherMethod}"` };
    answers[otherMethod] = answer.data;
    const ordered = { lumped_mass: answers.lumped_mass, rigid_block: answers.rigid_block };
    return { ok: true, status: 200, data: { ...own.data, comparison: ordered } };
  }

  const tableTitle = document.getElementById('migration-table-title');

  function render(data, request) {
    empty.hidden = true;
    tableTitle.textContent = data.statistics
      ? 'Nominal run (the request without random draws), not the ensemble'
      : 'Outcome of the run';
    document.getElementById('migration-table').dataset.nominal = String(Boolean(data.statistics));
    fillTable(tbody, ROWS.map((r) => ({ ...r, label: span(r.label) })), data);
    showWarnings(warnings, data.warnings);
    runsCsv = data.runs_csv ?? null;
    renderStatistics(data.statistics);
    renderTrajectory(data.trajectory, data);
    renderComparison(data.comparison ?? null, data.method_comparison ?? null);
    floor.showPath(data);
    const names = { lumped_mass: 'lumped mass', rigid_block: 'rigid block (DEM)' };
    const extra = Object.entries(data.comparison ?? {})
      .filter(([, d]) => d.trajectory && d.trajectory !== data.trajectory && d.method !== data.method)
      .map(([method, d]) => ({ label: `the rock, ${names[method] ?? method}`, tr: d.trajectory }));
    renderFloorViews('migration', { inputs: data.inputs, request, upload: floor.current(), tr: data.trajectory ?? null, runsCsv, arrival: data.arrival, extra, maps: data.maps ?? null });
  }

  function renderComparison(both, verdict) {
    compareBox.hidden = !both;
    compareBody.replaceChildren();
    renderVerdict(verdict);
    if (!both) {
      destroy(comparePlot);
      return;
    }
    const names = { lumped_mass: 'lumped mass', rigid_block: 'rigid block (DEM)' };
    const tables = [];
    for (const [method, d] of Object.entries(both)) {
      const a = d.arrival;
      compareBody.append(h('tr', { dataset: { method } },
        h('th', { scope: 'row' }, names[method]),
        h('td', { class: 'num', dataset: { out: `comparison.${method}.arrival.speed_m_s` } }, `${fmt(a.speed_m_s, 5)} m/s`),
        h('td', { class: 'num' }, `${fmt(a.time_s, 5)} s`),
        h('td', { class: 'num' }, String(d.impact_count)),
        h('td', {}, outcomeWords(d))));
      const tr = d.trajectory;
      if (tr) tables.push([tr.along_dip_m, tr.speed_m_s]);
    }
    if (tables.length === 2) {
      // one ascending distance axis for both curves (null where a method has no sample)
      const sorted = tables.map(([xs, ys]) => {
        const idx = xs.map((_, i) => i).sort((i, j) => xs[i] - xs[j] || i - j);
        const out = [[], []];
        for (const i of idx) {
          // a repeated distance (at rest) keeps its last sample
          if (out[0].length && out[0][out[0].length - 1] === xs[i]) out[1][out[1].length - 1] = ys[i];
          else { out[0].push(xs[i]); out[1].push(ys[i]); }
        }
        return out;
      });
      const joined = joinSeries(sorted);
      linePlot(comparePlot, {
        x: { label: 'along the dip (m)', values: joined[0] },
        y: { label: 'speed (m/s)' },
        series: [
          { label: `${names.lumped_mass} (m/s)`, values: joined[1] },
          { label: `${names.rigid_block} (m/s)`, values: joined[2] },
        ],
      });
      comparePlot.csv = () => [['along_dip_m', 'lumped_mass_speed_m_s', 'rigid_block_speed_m_s'],
        ...joined[0].map((x, i) => [x, joined[1][i] ?? '', joined[2][i] ?? ''])];
    } else {
      plotMessage(comparePlot, 'Ask for the trajectory to see the two curves.');
    }
  }

  /** The service's word on the two methods (method_comparison): agree or not, and why. */
  function renderVerdict(c) {
    const box = document.getElementById('migration-compare-verdict');
    box.replaceChildren();
    box.hidden = !c;
    if (!c) return;
    const names = { lumped_mass: 'lumped mass', rigid_block: 'rigid block' };
    const floorWords = {
      plane: 'the plane',
      smooth: 'a smooth floor',
      relief_below_rock_size: 'relief smaller than the rock',
      relief_above_rock_size: 'relief of the rock\'s size or larger',
    };
    const speed = (m) => {
      if (m.speed_mean_m_s === null) return `${names[m.method]}: no run reached the lower end`;
      const ci = m.speed_ci95_m_s ? ` [${fmt(m.speed_ci95_m_s[0], 4)}, ${fmt(m.speed_ci95_m_s[1], 4)}]` : '';
      const runs = m.runs > 1 ? `mean of ${m.runs} runs` : 'one run';
      return `${names[m.method]} ${fmt(m.speed_mean_m_s, 4)} m/s${ci} (${runs}, ${fmt(100 * m.reached_fraction, 3)} % reached the lower end)`;
    };
    const diff = c.speed_difference === null ? '' : ` (${c.speed_difference >= 0 ? '+' : ''}${fmt(100 * c.speed_difference, 3)} %)`;
    box.classList.toggle('agree', c.agree);
    box.classList.toggle('differ', !c.agree);
    box.append(
      h('strong', {}, c.agree ? 'The two methods agree on this case.' : 'The two methods do not agree on this case.'),
      ` Arrival speed: ${c.methods.map(speed).join(' against ')}${diff}; they agree within their intervals or ±${fmt(100 * c.speed_tolerance, 2)} %.`,
      ` Floor: ${floorWords[c.floor] ?? c.floor} (relief ${fmt(c.floor_relief_m, 3)} m at the rock's scale, the rock ${fmt(c.rock_size_m, 3)} m).`,
      h('br'),
      c.note.replace(/^The two methods (do not )?agree on this case\. /, ''),
    );
  }

  /** Roll, pitch, yaw (z–y–x Tait–Bryan, degrees) of quaternions [w, x, y, z], unwrapped. */
  function eulerDegrees(qs) {
    const out = [[], [], []];
    const last = [null, null, null];
    for (const [w, x, y, z] of qs) {
      const roll = Math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
      const pitch = Math.asin(Math.max(-1, Math.min(1, 2 * (w * y - z * x))));
      const yaw = Math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
      [roll, pitch, yaw].forEach((r, k) => {
        let deg = r * 180 / Math.PI;
        if (last[k] !== null && k !== 1) deg += 360 * Math.round((last[k] - deg) / 360);
        last[k] = deg;
        out[k].push(deg);
      });
    }
    return out;
  }

  function renderStatistics(stats) {
    statsCard.hidden = !stats;
    percentilesCard.hidden = !stats;
    if (!stats) {
      destroy(histogram);
      percentiles.tHead.replaceChildren();
      percentiles.tBodies[0].replaceChildren();
      runsCsv = null;
      return;
    }
    const hist = stats.speed_m_s?.histogram;
    if (hist && hist.counts?.length) {
      const centres = hist.counts.map((_, i) => (hist.edges[i] + hist.edges[i + 1]) / 2);
      const lo = hist.edges[0];
      const hi = hist.edges[hist.edges.length - 1];
      const pad = hi > lo ? 0 : Math.max(Math.abs(lo) * 1e-3, 1e-3);
      linePlot(histogram, {
        x: { label: 'arrival speed (m/s)', values: centres, range: [lo - pad, hi + pad] },
        y: { label: 'runs', range: [0, Math.max(...hist.counts) * 1.1 || 1] },
        series: [{ label: 'runs', values: hist.counts, bars: true }],
        height: 220,
      });
    } else {
      plotMessage(histogram, 'No run reached the lower end.');
    }

    statsCaption.textContent = `Monte Carlo ensemble: ${stats.runs} runs, seed ${stats.seed}; ` +
      `${fmt(stats.reached_fraction * 100, 4)} % reached the lower end. ` +
      'Speed, energy and time over the runs that reached it; the rest over all runs.';
    // an ensemble "until precise enough": where it stopped and how precise the percentile is
    const outcome = document.getElementById('migration-target-outcome');
    outcome.hidden = !stats.target;
    outcome.className = `answer target-outcome ${stats.target?.met ? 'met' : 'unmet'}`;
    outcome.textContent = stats.target ? `${arrivalTargetSentence(stats.target)}.` : '';
    percentiles.tHead.replaceChildren(h('tr', {},
      h('th', {}, ''),
      STAT_COLUMNS.map((c) => h('th', { class: 'num' }, c)),
      h('th', {}, 'Unit')));
    const body = percentiles.tBodies[0];
    body.replaceChildren();
    for (const [key, label, unit, scale] of STATS) {
      const s = stats[key];
      if (!s) continue;
      // A spread below 1e-12 of the values themselves is rounding noise (a run-out of exactly the face length).
      const noise = Math.max(Math.abs(s.mean ?? 0), Math.abs(s.max ?? 0), Math.abs(s.min ?? 0)) * scale;
      body.append(h('tr', {},
        h('th', { scope: 'row' }, label),
        STAT_COLUMNS.map((c) => h('td', { class: 'num', dataset: { out: `statistics.${key}.${c}`, csv: typeof s[c] === 'number' ? String(s[c] * scale) : '' } },
          fmt(s[c] === null || s[c] === undefined ? s[c] : s[c] * scale, 5, noise))),
        h('td', { class: 'unit' }, unit)));
    }
  }

  function renderTrajectory(tr, data) {
    trajectoryBox.hidden = !tr;
    if (!tr) {
      Object.values(plots).forEach(destroy);
      return;
    }
    const s0 = tr.along_dip_m[0];
    sideNote.textContent = s0 < 0
      ? `The rock is lifted vertically ${fmt(data.inputs?.release?.drop_height_m ?? 0, 4)} m above its release point; ` +
        `measured in the floor's plane, the foot of that point lies ${fmt(-s0, 3)} m up-dip of it, so the path starts at ${fmt(s0, 3)} m. ` +
        'Drag across a plot to zoom in; double-click to zoom out.'
      : 'Drag across a plot to zoom in; double-click to zoom out.';
    const s = tr.along_dip_m;
    const sRange = range(s);
    linePlot(plots.side, {
      x: { label: 'along the dip (m)', values: s, range: sRange },
      y: { label: 'height above the floor (m)' },
      series: [{ label: floor.current() && data.inputs?.face?.floor?.kind !== 'plane' ? `height above the uploaded floor ${floor.current().name}` : 'height above the plane', values: tr.height_m }],
    });

    const xs = tr.position_m.map((p) => p[0]);
    const ys = tr.position_m.map((p) => p[1]);
    linePlot(plots.plan, {
      x: { label: 'x, horizontal in the dip direction (m)', values: xs, range: range(xs) },
      y: { label: 'y: across the face (m)', range: range(ys, 1) },
      series: [{ label: floor.current() && data.inputs?.face?.floor?.kind !== 'plane' ? `path on the uploaded floor ${floor.current().name}` : 'path on the plane', values: ys }],
    });

    const kJ = (a) => a?.map((v) => v * 1e-3);
    const energySeries = [
      { label: 'speed (m/s)', values: tr.speed_m_s, axis: 'y' },
      { label: 'kinetic (kJ)', values: kJ(tr.kinetic_energy_j), axis: 'y2' },
      { label: 'potential (kJ)', values: kJ(tr.potential_energy_j), axis: 'y2' },
      { label: 'dissipated (kJ)', values: kJ(tr.dissipated_energy_j), axis: 'y2' },
    ].filter((x) => x.values);
    linePlot(plots.energy, {
      x: { label: 'along the dip (m)', values: s, range: sRange },
      y: { label: 'speed (m/s)' },
      y2: { label: 'energy (kJ)' },
      series: energySeries,
    });
    const q = tr.orientation_wxyz;
    orientationCard.hidden = !q?.length;
    if (q?.length) {
      const [roll, pitch, yaw] = eulerDegrees(q);
      linePlot(plots.orientation, {
        x: { label: 'time (s)', values: tr.time_s, range: range(tr.time_s) },
        y: { label: 'angle (°)' },
        series: [
          { label: 'roll (°)', values: roll },
          { label: 'pitch (°)', values: pitch },
          { label: 'yaw (°)', values: yaw },
        ],
      });
    } else {
      destroy(plots.orientation);
    }
    const trajectoryCsv = () => trajectoryRows(tr);
    for (const el of Object.values(plots)) el.csv = trajectoryCsv;
  }

  return panel;
}

const PHASE_WORDS = { flight: 'in flight', slide: 'sliding', roll: 'rolling', stopped: 'at rest' };

/** What happened to the rock, in words ("came to rest at 16.6 m along the dip"). */
export function outcomeWords(data) {
  const a = data.arrival;
  const at = `${fmt(a.along_dip_m, 4)} m along the dip`;
  switch (a.stop_reason) {
    case 'lower_end': return `reached the lower end of the face (${at}) at ${fmt(a.speed_m_s, 4)} m/s`;
    case 'at_rest': return `came to rest at ${at}`;
    case 'end_time': return `still moving at the end time, at ${at}`;
    case 'left_floor': {
      // the service says where and past which boundary (warning left_floor)
      const why = (data.warnings ?? []).find((w) => w.code === 'left_floor');
      return why ? why.message : `left the floor at ${at}`;
    }
    case 'support': return `struck a support at ${at}`;
    default: return `${a.stop_reason} at ${at}`;
  }
}

/** The trajectory as CSV rows (vectors split into components). */
function trajectoryRows(tr) {
  const keys = Object.keys(tr).filter((k) => Array.isArray(tr[k]));
  const head = [];
  for (const k of keys) {
    const first = tr[k][0];
    if (Array.isArray(first)) {
      const names = first.length === 4 ? ['w', 'x', 'y', 'z'] : ['x', 'y', 'z'];
      first.forEach((_, i) => head.push(`${k}_${names[i] ?? i}`));
    } else head.push(k);
  }
  const rows = [head];
  const n = tr.time_s.length;
  for (let i = 0; i < n; i++) rows.push(keys.flatMap((k) => (Array.isArray(tr[k][i]) ? tr[k][i] : [tr[k][i]])));
  return rows;
}

/** [min, max] of an array, widened by `pad` when flat. */
function range(values, pad = 0) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) {
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  if (!(hi > lo)) return [lo - (pad || 1), hi + (pad || 1)];
  return [lo, hi];
}

function span(html) {
  const el = document.createElement('span');
  el.innerHTML = html;
  return el;
}

/**
 * What a migration ensemble "until precise enough" did, from the answer's `statistics.target`:
 * "Stopped at 4 000 runs: the p95 arrival speed known to ± 1.6 % (asked ± 2)", or "Ran all …
 * runs: ± 2.4 %, the target was not met — raise the most runs or loosen the target".
 */
export function arrivalTargetSentence(t) {
  if (!t) return '';
  const asked = t.target.relative_half_width;
  const p = `p${fmt(t.target.percentile * 100, 4)}`;
  const r = t.relative_half_width;
  let sig = 2;
  while (typeof r === 'number' && sig < 8 && (Number((r * 100).toPrecision(sig)) <= asked * 100) !== (r <= asked)) sig += 1;
  const reached = typeof r === 'number' ? `± ${fmt(r * 100, sig)} %` : `too few runs reached the lower end for the ${p}'s interval`;
  if (t.met) {
    const at = t.runs_used < t.max_runs ? `Stopped at ${groupDigits(t.runs_used)} runs` : `Met at all ${groupDigits(t.runs_used)} runs`;
    return `${at}: the ${p} arrival speed known to ${reached} (asked ± ${fmt(asked * 100, 6)})`;
  }
  return `Ran all ${groupDigits(t.runs_used)} runs: ${reached}, the target was not met — raise the most runs or loosen the target`;
}
