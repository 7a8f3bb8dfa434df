// Scene protection lines across the face (api.md `barriers`, `collectors`): rows the engineer
// adds and removes on the Scene form, read into the request in SI, checked against the
// documented ranges before sending; a 422 naming `/barriers/1/height_m` finds its input
// through `data-target`. The rows live in one hidden field (JSON) so that links and recent
// cases carry them, as the release zones do.

import { parseNumber } from './form.js';
import { fmt, h } from './format.js';

/** Largest barrier height, m (api.md). */
const MAX_HEIGHT_M = 100;
/** Largest barrier energy rating, J (api.md). */
const MAX_RATING_J = 1e12;
/** Largest |across| of a line's range, m (api.md). */
const MAX_ACROSS_M = 1000;

/** What a row of each kind holds: key, label, unit shown, power of ten to SI, optional. */
const COLUMNS = {
  barriers: [
    { key: 'along_dip_m', label: 'Along the dip', unit: 'm' },
    { key: 'across_from', label: 'Across, from', unit: 'm', optional: true },
    { key: 'across_to', label: 'to', unit: 'm', optional: true },
    { key: 'height_m', label: 'Height', unit: 'm' },
    { key: 'energy_rating_j', label: 'Energy rating', unit: 'kJ', exp: 3 },
  ],
  collectors: [
    { key: 'along_dip_m', label: 'Along the dip', unit: 'm' },
    { key: 'across_from', label: 'Across, from', unit: 'm', optional: true },
    { key: 'across_to', label: 'to', unit: 'm', optional: true },
  ],
};

/** The first row a ticked group shows (display units): a 1 m, 20 kJ barrier at 40 m; a collector at 30 m. */
const FIRST = { barriers: ['40', '', '', '1', '20'], collectors: ['30', '', ''] };
const NOUN = { barriers: 'barrier', collectors: 'collector' };

/** The request pointer of a row's cell (`across_from` → `/barriers/i/across_m/0`). */
function pointerOf(kind, i, key) {
  if (key === 'across_from') return `/${kind}/${i}/across_m/0`;
  if (key === 'across_to') return `/${kind}/${i}/across_m/1`;
  return `/${kind}/${i}/${key}`;
}

/**
 * Row editors in the fieldsets `[data-group="/barriers"]` and `[data-group="/collectors"]` of
 * `form`. Returns `{apply(request, local, length)}`, which puts the ticked groups' rows into
 * the request in SI or throws `{fieldErrors}` for rows outside the documented ranges.
 */
export function initDeviceEditors(form) {
  const editors = Object.keys(COLUMNS).map((kind) => rowEditor(form, kind));
  return {
    apply(request, local, length) {
      const errors = [];
      for (const e of editors) {
        if (local[e.store] === undefined) continue;
        const lines = e.read(length, errors);
        request[e.kind] = lines;
      }
      if (errors.length) throw { fieldErrors: errors };
    },
  };
}

function rowEditor(form, kind) {
  const group = form.querySelector(`[data-group="/${kind}"]`);
  const storeName = `${kind}_json`;
  const store = h('input', { type: 'hidden', dataset: { local: storeName, kind: 'select' }, value: '' });
  const list = h('div', { class: 'device-rows', id: `scene-${kind}` });
  const add = h('button', { type: 'button', class: 'chip', id: `scene-${kind}-add` }, `Add a ${NOUN[kind]}`);
  group.append(store, list, add);
  const cols = COLUMNS[kind];

  const rowsNow = () => [...list.children].map((row) => [...row.querySelectorAll('input')].map((i) => i.value));
  const save = () => { store.value = JSON.stringify(rowsNow()); };
  const renumber = () => [...list.children].forEach((row, i) => {
    row.querySelector('.device-title').textContent = `${NOUN[kind][0].toUpperCase()}${NOUN[kind].slice(1)} ${i + 1}`;
    row.querySelector('.device-remove').setAttribute('aria-label', `remove ${NOUN[kind]} ${i + 1}`);
    row.querySelectorAll('.device-name').forEach((span) => { span.textContent = `${NOUN[kind][0].toUpperCase()}${NOUN[kind].slice(1)} ${i + 1}: `; });
    row.querySelectorAll('input').forEach((input, k) => { input.dataset.target = pointerOf(kind, i, cols[k].key); });
  });
  const addRow = (values = FIRST[kind]) => {
    const fields = cols.map((c, k) => {
      const id = `scene-${kind}-${list.children.length}-${c.key}-${Math.random().toString(36).slice(2, 7)}`;
      const input = h('input', {
        id, type: 'text', inputmode: 'decimal', autocomplete: 'off', spellcheck: 'false', value: values[k] ?? '',
        placeholder: c.optional ? 'whole face' : undefined, dataset: { exp: c.exp ? String(c.exp) : undefined, col: c.key },
      });
      if (!c.exp) delete input.dataset.exp;
      input.addEventListener('input', save);
      // the row's name is in the label too (hidden on screen, where the row's title shows it), so a
      // problem's summary says which row it means
      return h('div', { class: 'field field-number' }, h('label', { for: id }, h('span', { class: 'visually-hidden device-name' }), c.label),
        h('div', { class: 'control' }, input, h('span', { class: 'unit' }, c.unit)),
        h('p', { class: 'field-error', hidden: true, role: 'alert' }));
    });
    const remove = h('button', { type: 'button', class: 'link device-remove' }, 'remove');
    const row = h('div', { class: `device-row device-${kind}` }, h('div', { class: 'device-head' }, h('strong', { class: 'device-title' }), remove), fields);
    remove.addEventListener('click', () => { row.remove(); renumber(); save(); });
    list.append(row);
    renumber();
  };
  const fill = (rows) => { list.replaceChildren(); rows.forEach((r) => addRow(r)); };
  add.addEventListener('click', () => { addRow(); save(); list.lastElementChild.querySelector('input').focus(); });
  // a link or a recent case sets the hidden field: the rows follow it
  store.addEventListener('change', () => {
    try {
      const rows = JSON.parse(store.value || '[]');
      if (Array.isArray(rows)) fill(rows.length || store.value ? rows : [FIRST[kind]]);
    } catch {
      // an old link without rows
    }
  });
  const start = () => { fill([FIRST[kind]]); save(); };
  form.addEventListener('reset', () => setTimeout(start));
  start();

  return {
    kind,
    store: storeName,
    /** The rows as lines in SI; pushes `{field, message}` for each cell outside its range. */
    read(length, errors) {
      return rowsNow().map((texts, i) => {
        const v = {};
        cols.forEach((c, k) => {
          const field = pointerOf(kind, i, c.key);
          const p = parseNumber(texts[k], c.exp ?? 0, c.unit);
          if (p.empty && c.optional) { v[c.key] = null; return; }
          if (p.error) { errors.push({ field, message: p.error }); v[c.key] = NaN; return; }
          v[c.key] = p.value;
        });
        const bad = (key, message) => errors.push({ field: pointerOf(kind, i, key), message });
        if (Number.isFinite(v.along_dip_m) && !(v.along_dip_m >= 0 && v.along_dip_m <= length)) {
          bad('along_dip_m', `must be in [0, ${fmt(length, 6)}] m (on the face)`);
        }
        let across = null;
        const [a, b] = [v.across_from, v.across_to];
        if ((a === null) !== (b === null)) {
          bad(a === null ? 'across_from' : 'across_to', 'give both ends of the across range, or neither (the whole face)');
        } else if (a !== null) {
          for (const [key, x] of [['across_from', a], ['across_to', b]]) {
            if (Number.isFinite(x) && Math.abs(x) > MAX_ACROSS_M) bad(key, `must be in [-${MAX_ACROSS_M}, ${MAX_ACROSS_M}] m`);
          }
          if (Number.isFinite(a) && Number.isFinite(b) && b < a) bad('across_to', `must be at least "from" (${fmt(a, 6)} m)`);
          across = [a, b];
        }
        const line = { along_dip_m: v.along_dip_m, across_m: across };
        if (kind === 'barriers') {
          if (Number.isFinite(v.height_m) && !(v.height_m > 0 && v.height_m <= MAX_HEIGHT_M)) bad('height_m', `must be in (0, ${MAX_HEIGHT_M}] m`);
          if (Number.isFinite(v.energy_rating_j) && !(v.energy_rating_j >= 0 && v.energy_rating_j <= MAX_RATING_J)) bad('energy_rating_j', 'must be in [0, 1e12] J');
          line.height_m = v.height_m;
          line.energy_rating_j = v.energy_rating_j;
        }
        return line;
      });
    },
  };
}

/**
 * The lines of a request as drawn marks: `[{kind, index, s, across: [a, b] | null, height?,
 * rating?}]`, barriers first (index from 1 in each kind).
 */
export function requestDevices(request) {
  const out = [];
  for (const kind of ['barriers', 'collectors']) {
    (request?.[kind] ?? []).forEach((d, i) => out.push({
      kind: NOUN[kind], index: i + 1, s: d.along_dip_m, across: d.across_m ?? null, height: d.height_m, rating: d.energy_rating_j,
    }));
  }
  return out;
}

/** A device's label on the drawings: "barrier 1: 1 m, 20 kJ", "collector 1", "proposed barrier 1: 0.6 m, 12 kJ". */
export function deviceLabel(d) {
  if (d.kind === 'proposed') return `proposed barrier ${d.index}: ${fmt(d.height, 3)} m, ${fmt(d.rating / 1e3, 3)} kJ`;
  return d.kind === 'barrier' ? `barrier ${d.index}: ${fmt(d.height, 3)} m, ${fmt(d.rating / 1e3, 3)} kJ` : `collector ${d.index}`;
}
