// Forms described as data. Every input carries `data-pointer`, the JSON
// Pointer of its request field (api.md), and `data-exp`, the power of ten
// from the unit shown to SI (mm → -3, GPa → 9). Reading a form builds the
// request; a problem's `errors[].field` pointers lead back to the inputs.

import { fmt, h, humanMessage } from './format.js';

let nextId = 0;

/**
 * Builds fieldsets into `form .form-fields` from groups:
 * `{legend, id?, toggle?: {label, checked}, note?, fields: [field]}` where a
 * field is `{pointer | local, label, unit?, exp?, kind?, options?,
 * placeholder?, hint?, choice?, target?}` (`target`: the request field a
 * local control stands for, where a problem naming it is shown) and kind is number (default), integer, select
 * or checkbox. `local` names a control that shapes the request but is not a
 * field itself. A group with `toggle` is sent only while its box is ticked.
 * A field's starting value is the server's default (GET /v1/presets, see
 * applyServerDefaults) or its settings preset; only a field with `choice`
 * `{value, why}` starts from the page's own value (an example case where the
 * server has none, e.g. 62 supports), and it is marked `data-choice`.
 */
export function buildForm(form, groups) {
  const container = form.querySelector('.form-fields');
  for (const group of groups) {
    const fieldset = h('fieldset', { dataset: group.pointer ? { group: group.pointer } : {} });
    const legend = h('legend', {});
    if (group.toggle) {
      const box = h('input', { type: 'checkbox', name: group.toggle.name, checked: group.toggle.checked });
      legend.append(h('label', { class: 'toggle' }, box, ' ', group.legend));
      const sync = () => { fieldset.disabled = !box.checked; };
      box.addEventListener('change', sync);
      form.addEventListener('reset', () => setTimeout(sync));
      sync();
    } else {
      legend.textContent = group.legend;
    }
    fieldset.append(legend, h('p', { class: 'group-error', hidden: true }));
    if (group.note) fieldset.append(h('p', { class: 'note', html: group.note }));
    for (const field of group.fields) fieldset.append(buildField(field));
    container.append(fieldset);
  }
  form.addEventListener('reset', () => setTimeout(() => clearErrors(form)));
}

function buildField(field) {
  const id = `f${++nextId}`;
  const data = {};
  if (field.pointer) data.pointer = field.pointer;
  if (field.local) data.local = field.local;
  // a local control standing for a request field: a problem naming it is marked here
  if (field.target) data.target = field.target;
  if (field.exp) data.exp = String(field.exp);
  if (field.choice) data.choice = field.choice.why;
  if (field.settings) data.settings = 'true';
  const kind = field.kind ?? 'number';
  const start = field.choice?.value;
  data.kind = kind;

  let control;
  if (kind === 'select') {
    control = h('select', { id, dataset: data },
      field.options.map(([value, label]) =>
        h('option', { value, selected: String(value) === String(start) }, label)));
  } else if (kind === 'checkbox') {
    control = h('input', { id, type: 'checkbox', dataset: data, checked: Boolean(start) });
  } else {
    // Text, not type=number: the page reads and judges every character itself,
    // so letters, "1e400" or an empty box are field errors, never a silent default.
    control = h('input', {
      id,
      type: 'text',
      inputmode: kind === 'integer' ? 'numeric' : 'decimal',
      autocomplete: 'off',
      spellcheck: 'false',
      value: start ?? undefined,
      placeholder: field.placeholder,
      dataset: field.placeholder ? { ...data, optional: 'true' } : data,
    });
  }

  const label = h('label', { for: id, html: field.label });
  const wrapper = h('div', { class: `field field-${kind}` });
  if (kind === 'checkbox') {
    wrapper.append(h('div', { class: 'check' }, control, label));
  } else {
    wrapper.append(label, h('div', { class: 'control' }, control, h('span', { class: 'unit', html: field.unit ?? '' })));
  }
  if (field.hint) wrapper.append(h('p', { class: 'hint', html: field.hint }));
  if (field.placeholder) wrapper.append(h('p', { class: 'used', hidden: true, dataset: { usedFor: field.pointer ?? '' } }));
  wrapper.append(h('p', { class: 'field-error', hidden: true, role: 'alert' }));
  return wrapper;
}

/**
 * Reads the enabled controls of a form into a request object (SI units).
 * Every shown number field is sent; only a field with a visible "auto"
 * placeholder may stay empty (the server then computes it and the page shows
 * the value used). Returns `{request, local, errors}`; `errors` lists inputs
 * that cannot be read (nothing is sent then).
 */
export function readForm(form) {
  const request = {};
  const local = {};
  const errors = [];
  for (const el of form.querySelectorAll('[data-pointer], [data-local]')) {
    if (el.matches(':disabled')) continue;
    let value;
    const kind = el.dataset.kind;
    if (kind === 'checkbox') value = el.checked;
    else if (kind === 'select') value = el.value;
    else {
      const parsed = parseNumber(el.value, Number(el.dataset.exp ?? 0), unitOf(el));
      if (parsed.empty && el.dataset.optional) continue;
      if (parsed.error) {
        errors.push({ el, message: parsed.error });
        continue;
      }
      value = parsed.value;
      if (kind === 'integer' && !Number.isInteger(value)) {
        errors.push({ el, message: 'must be a whole number' });
        continue;
      }
    }
    if (el.dataset.local) local[el.dataset.local] = value;
    else setPointer(request, el.dataset.pointer, value);
  }
  return { request, local, errors };
}

/** The unit shown beside an input ('' when none). */
export function unitOf(el) {
  return el.closest('.field')?.querySelector('.unit')?.textContent.trim() ?? '';
}

/**
 * Reads decimal text typed in a display unit: `{value}` in SI, or `{error}`
 * saying what is wrong in words (empty, not a number, too large for a
 * double, too small). `empty` is set for an empty box.
 */
export function parseNumber(text, exp = 0, unit = '') {
  const t = String(text ?? '').trim().replace(/\u2212/g, '-');
  const u = unit ? ` ${unit}` : '';
  if (t === '') return { empty: true, error: `required: enter a value${unit ? ` in ${unit}` : ''}` };
  if (/^[+-]?\d+,\d+$/.test(t)) return { error: `not a number: "${t}" (use a point as the decimal mark: ${t.replace(',', '.')}${u})` };
  const m = /^([+-]?(?:\d+\.?\d*|\.\d+))(?:e([+-]?\d+))?$/i.exec(t);
  if (!m) return { error: `not a number: "${t}"` };
  const written = Number(t);
  if (!Number.isFinite(written)) return { error: `out of range: ${t} is too large to compute with` };
  if (written !== 0 && Number(m[1]) !== 0 && Math.abs(written) < 1e-300) return { error: `out of range: ${t} is too small to compute with` };
  const value = toSi(t, exp);
  if (!Number.isFinite(value)) return { error: `out of range: ${t}${u} is too large to compute with` };
  return { value };
}

/**
 * Decimal text in a display unit → SI, by shifting the decimal exponent in
 * the text so that "235" mm becomes exactly the double nearest 0.235.
 */
export function toSi(text, exp) {
  const m = /^\s*([+-]?(?:\d+\.?\d*|\.\d+))(?:e([+-]?\d+))?\s*$/i.exec(text);
  if (!m) return Number(text);
  return Number(`${m[1]}e${Number(m[2] ?? 0) + exp}`);
}

/** Sets `obj` at a JSON Pointer, creating objects on the way. */
export function setPointer(obj, pointer, value) {
  const keys = pointer.split('/').slice(1).map((k) => k.replace(/~1/g, '/').replace(/~0/g, '~'));
  let node = obj;
  keys.slice(0, -1).forEach((key) => {
    if (typeof node[key] !== 'object' || node[key] === null) node[key] = {};
    node = node[key];
  });
  node[keys[keys.length - 1]] = value;
}

/** Deep merge of plain objects (b wins); returns a new object. */
export function merge(a, b) {
  const out = { ...a };
  for (const [key, value] of Object.entries(b)) {
    const both = value && typeof value === 'object' && !Array.isArray(value) &&
      out[key] && typeof out[key] === 'object' && !Array.isArray(out[key]);
    out[key] = both ? merge(out[key], value) : value;
  }
  return out;
}

let errorIds = 0;

/** Adds (or removes) an element id to an input's aria-describedby, keeping the others (hints, notes). */
function describe(input, id, on) {
  const ids = (input.getAttribute('aria-describedby') ?? '').split(/\s+/).filter((x) => x && x !== id);
  if (on) ids.unshift(id);
  if (ids.length) input.setAttribute('aria-describedby', ids.join(' '));
  else input.removeAttribute('aria-describedby');
  if (on) input.dataset.errorId = id;
  else delete input.dataset.errorId;
}

/** Ties an input to the message beside it: aria-invalid, and aria-describedby naming the message. */
function markInvalid(input, p) {
  if (!p.id) p.id = `field-error-${++errorIds}`;
  input.setAttribute('aria-invalid', 'true');
  describe(input, p.id, true);
}

/** Moves the focus to the first marked field that can be seen, in the order of `forms`; true if one took it. */
export function focusFirstInvalid(forms) {
  for (const form of forms) {
    for (const el of form.querySelectorAll('[aria-invalid="true"]')) {
      if (el.disabled || !el.checkVisibility?.()) continue;
      el.focus({ preventScroll: false });
      return true;
    }
  }
  return false;
}

/** Removes every field error mark from the forms. */
export function clearErrors(...forms) {
  for (const form of forms) {
    for (const p of form.querySelectorAll('.field-error, .group-error')) {
      p.hidden = true;
      p.textContent = '';
    }
    for (const el of form.querySelectorAll('.invalid')) el.classList.remove('invalid');
    for (const el of form.querySelectorAll('[aria-invalid]')) el.removeAttribute('aria-invalid');
    for (const el of form.querySelectorAll('[data-error-id]')) describe(el, el.dataset.errorId, false);
    const panel = form.closest('[data-panel]');
    if (panel) document.querySelector(`[data-tab="${panel.dataset.panel}"]`)?.classList.remove('has-error');
  }
}

/**
 * Finds the control (or group) that a JSON Pointer names in the first of
 * `forms` that has it, going up the pointer until something matches:
 * `/face/floor/kind` falls back to a `/face` group if there is no input.
 */
export function locate(pointer, forms) {
  const keys = pointer.split('/');
  for (let n = keys.length; n > 1; n--) {
    const prefix = keys.slice(0, n).join('/');
    for (const form of forms) {
      // of two controls for one field (e.g. the fixed and the most runs), the one in use
      const all = [...form.querySelectorAll(`[data-pointer="${CSS.escape(prefix)}"], [data-target="${CSS.escape(prefix)}"]`)];
      const input = all.find((el) => !el.disabled) ?? all[0];
      if (input) return { form, input, target: input.closest('.field, td, th') ?? input.parentElement };
      const group = form.querySelector(`[data-group="${CSS.escape(prefix)}"]`);
      if (group) return { form, input: null, target: group };
    }
  }
  return null;
}

/**
 * Marks the fields that a problem's `errors` name. Returns the errors that
 * no field on the page matched, for the summary.
 */
export function markErrors(errors, forms) {
  const unmatched = [];
  for (const error of errors ?? []) {
    const rawMessage = error.message ?? 'invalid';
    const found = error.field ? locate(error.field, forms) : null;
    if (!found) {
      unmatched.push(error);
      continue;
    }
    const { input, target } = found;
    let p = target.querySelector(input ? '.field-error' : '.group-error');
    if (!p) {
      p = h('p', { class: 'field-error', role: 'alert' });
      target.append(p);
    }
    const message = input ? localise(rawMessage, input) : humanMessage(rawMessage);
    p.textContent = p.textContent ? `${p.textContent}; ${message}` : message;
    p.hidden = false;
    target.classList.add('invalid');
    if (input) markInvalid(input, p);
    const panel = found.form.closest('[data-panel]');
    if (panel) document.querySelector(`[data-tab="${panel.dataset.panel}"]`)?.classList.add('has-error');
  }
  return unmatched;
}

/** Marks inputs that could not be read (see readForm). */
export function markLocalErrors(errors) {
  for (const { el, message } of errors) {
    const field = el.closest('.field');
    const p = field.querySelector('.field-error');
    p.textContent = message;
    p.hidden = false;
    field.classList.add('invalid');
    markInvalid(el, p);
  }
}

const SI_OF = { mm: 'm', ms: 's', GPa: 'Pa', MPa: 'Pa', kJ: 'J', kN: 'N' };

/**
 * A server message ("must be in [0.01, 5] m") in the unit of the field it is
 * shown beside ("must be in [10, 5000] mm"); numbers in plain notation.
 */
export function localise(message, input) {
  const unit = unitOf(input);
  const exp = Number(input.dataset.exp ?? 0);
  const si = SI_OF[unit];
  let text = String(message);
  if (si && exp) {
    const num = '(-?\\d+(?:\\.\\d+)?(?:e[+-]?\\d+)?)';
    const conv = (v) => fmt(Number(v) / 10 ** exp, 6);
    const range = new RegExp(`([\\[(])\\s*${num}\\s*,\\s*${num}\\s*([\\])])\\s*${si}(?![a-zA-Z/])`, 'g');
    text = text.replace(range, (_, open, a, b, close) => `${open}${conv(a)}, ${conv(b)}${close} ${unit}`);
    const single = new RegExp(`${num}\\s*${si}(?![a-zA-Z/²³])`, 'g');
    text = text.replace(single, (_, a) => `${conv(a)} ${unit}`);
  }
  // a percentage sent as a fraction: the server's bare range "(0, 1)" is "(0, 100) %" beside it
  if (unit === '%' && exp === -2) {
    const num = '(-?\\d+(?:\\.\\d+)?(?:e[+-]?\\d+)?)';
    const range = new RegExp(`([\\[(])\\s*${num}\\s*,\\s*${num}\\s*([\\])])(?!\\s*[a-zA-Z%])`, 'g');
    text = text.replace(range, (_, open, a, b, close) => `${open}${fmt(Number(a) * 100, 6)}, ${fmt(Number(b) * 100, 6)}${close} %`);
  }
  return humanMessage(text);
}

/** The text of every control of a form, keyed by pointer / local / toggle name (for links). */
export function formState(form) {
  const state = {};
  for (const el of form.querySelectorAll('[data-pointer], [data-local], legend input[type="checkbox"]')) {
    const key = el.dataset.pointer ?? (el.dataset.local ? `local:${el.dataset.local}` : `toggle:${el.name}`);
    state[key] = el.type === 'checkbox' ? el.checked : el.value;
  }
  return state;
}

/** Puts a formState back into a form (unknown keys are ignored). */
export function applyState(form, state) {
  for (const el of form.querySelectorAll('[data-pointer], [data-local], legend input[type="checkbox"]')) {
    const key = el.dataset.pointer ?? (el.dataset.local ? `local:${el.dataset.local}` : `toggle:${el.name}`);
    if (!(key in state)) continue;
    if (el.type === 'checkbox') el.checked = Boolean(state[key]);
    else el.value = state[key];
    el.dispatchEvent(new Event('change', { bubbles: true }));
  }
}

/**
 * Sets a form's values (and the values its Defaults button restores) from SI
 * values keyed by JSON Pointer.
 */
export function setDefaults(form, values) {
  for (const [pointer, value] of Object.entries(values)) {
    const el = form.querySelector(`[data-pointer="${CSS.escape(pointer)}"]`);
    if (!el || value === undefined || value === null) continue;
    if (el.type === 'checkbox') {
      el.checked = Boolean(value);
      el.defaultChecked = Boolean(value);
    } else if (el.tagName === 'SELECT') {
      for (const o of el.options) o.defaultSelected = o.value === String(value);
      el.value = String(value);
    } else {
      const text = typeof value === 'number' ? fromSi(value, Number(el.dataset.exp ?? 0)) : String(value);
      el.value = text;
      el.defaultValue = text;
    }
    el.dispatchEvent(new Event('change', { bubbles: true }));
  }
}

/**
 * Fills a form from the server's defaults (GET /v1/presets `defaults`): every
 * control whose pointer has a value in the request object `defaults` shows it
 * and restores it on Defaults. `objects` maps a pointer prefix to the defaults
 * of an object the request carries only when ticked (`/monte_carlo`). Fields
 * with the page's own starting value (`data-choice`) and those the settings
 * set (`data-settings`) are left alone; a default that is null or absent
 * (derived by the server) leaves the field empty on its "auto" placeholder.
 */
export function applyServerDefaults(form, defaults, objects = {}) {
  const values = {};
  for (const el of form.querySelectorAll('[data-pointer]')) {
    if (el.dataset.choice || el.dataset.settings) continue;
    const pointer = el.dataset.pointer;
    const prefix = Object.keys(objects).find((p) => pointer.startsWith(`${p}/`));
    const value = prefix ? pickPointer(objects[prefix], pointer.slice(prefix.length)) : pickPointer(defaults, pointer);
    if (value !== undefined && value !== null) values[pointer] = value;
  }
  setDefaults(form, values);
}

/** SI → display text, exactly (shifts the decimal exponent of the shortest form). */
export function fromSi(value, exp) {
  if (!exp) return String(value);
  const [m, e] = value.toExponential().split('e');
  const shifted = Number(`${m}e${Number(e) - exp}`);
  return String(shifted);
}

/** Shows, under each "auto" field, the value the server used (from the answer's `inputs`). */
export function showUsed(form, inputs) {
  for (const p of form.querySelectorAll('.used')) {
    const el = p.closest('.field').querySelector('[data-pointer]');
    const blank = el && el.value.trim() === '' && !el.disabled;
    const value = blank && inputs ? pickPointer(inputs, el.dataset.pointer) : undefined;
    p.hidden = typeof value !== 'number';
    if (!p.hidden) p.textContent = `used: ${fmt(value / 10 ** Number(el.dataset.exp ?? 0), 6)} ${unitOf(el)}`.trim();
  }
}

/** The value at a JSON Pointer, or undefined. */
export function pickPointer(obj, pointer) {
  return pointer.split('/').slice(1).reduce((o, k) => (o === null || o === undefined ? undefined : o[k]), obj);
}
