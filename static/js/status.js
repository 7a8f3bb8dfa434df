// The status line above each result: busy, done, or a problem (RFC 9457)
// summarised, with its field errors marked next to the inputs.

import { fmt, h } from './format.js';
import { clearErrors, locate, markErrors } from './form.js';

export function showBusy(el, text) {
  el.hidden = false;
  el.className = 'status busy';
  el.replaceChildren(h('span', { class: 'spinner', 'aria-hidden': 'true' }), text);
  bringIntoView(el);
}

/** Scrolls the status line of a results column into view when it is off screen. */
export function bringIntoView(el) {
  const box = el.getBoundingClientRect();
  if (box.top < 0 || box.bottom > window.innerHeight) el.scrollIntoView({ block: 'nearest' });
}

export function showInfo(el, text) {
  el.hidden = false;
  el.className = 'status info';
  el.replaceChildren(text);
}

export function hideStatus(el) {
  el.hidden = true;
  el.replaceChildren();
}

/**
 * Shows a problem: a summary line in `el` and each `errors[]` entry next to
 * the field its JSON Pointer names (searched in `forms`, in order).
 * `endpoint` (e.g. "POST /v1/column") words a 404 as a missing endpoint.
 */
export function showProblem(el, problem, { forms = [], endpoint = '', label = '' } = {}) {
  clearErrors(...forms);
  const unmatched = markErrors(problem.errors, forms);
  el.hidden = false;
  el.className = 'status error';
  el.replaceChildren();
  el.dataset.problem = problemCode(problem);
  bringIntoView(el);

  const status = problem.status ? `${problem.status} ` : '';
  const head = h('p', { class: 'summary' });
  if (label) head.append(h('strong', {}, `${label}: `));

  if (problem.status === 404 && endpoint) {
    head.append(h('strong', {}, `${status}${problem.title || 'Not Found'}. `),
      `This server does not offer ${endpoint} yet; the other calculations work without it.`);
    el.append(head);
    return;
  }

  head.append(h('strong', {}, `${status}${problem.title || 'Error'}`));
  if (problem.detail) head.append(' — ', problem.detail);
  const count = (problem.errors ?? []).length;
  if (count) head.append(` (${count} field${count > 1 ? 's' : ''} marked in the form)`);
  el.append(head);

  if (problem.max_velocity_m_s !== undefined) {
    el.append(h('p', { class: 'extra', dataset: { out: 'max_velocity_m_s' } },
      `Largest impact velocity this contact law can store: ${fmt(problem.max_velocity_m_s, 5)} m/s.`));
  }
  for (const [key, value] of Object.entries(problem)) {
    if (['type', 'title', 'status', 'detail', 'errors', 'instance', 'max_velocity_m_s'].includes(key)) continue;
    if (typeof value === 'number' || typeof value === 'string') {
      el.append(h('p', { class: 'extra' }, `${key}: ${typeof value === 'number' ? fmt(value, 5) : value}`));
    }
  }

  const items = (problem.errors ?? []).map((e) => {
    const found = e.field ? locate(e.field, forms) : null;
    const where = found?.target.querySelector('label, legend')?.textContent?.trim();
    const value = e.value === undefined ? '' : ` (got ${JSON.stringify(e.value)})`;
    return h('li', { class: unmatched.includes(e) ? 'unmatched' : '' },
      h('code', {}, e.field ?? '(request)'), where ? ` ${where}` : '', `: ${e.message ?? 'invalid'}${value}`);
  });
  if (items.length) el.append(h('ul', {}, items));
  if (problem.type && problem.type.startsWith('/problems/')) {
    el.append(h('p', { class: 'extra' }, h('a', { href: problem.type.slice(1), target: '_blank' }, 'About this problem')));
  }
}

function problemCode(problem) {
  return (problem.type ?? '').split('/').pop() || String(problem.status ?? '');
}
