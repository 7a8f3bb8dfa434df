// The status line above each result: busy, done, or a problem (RFC 9457)
// summarised, with its field errors marked next to the inputs.

import { fmt, h, humanMessage } from './format.js';
import { clearErrors, focusFirstInvalid, locate, localise, markErrors, unitOf } from './form.js';

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
 * Shows a problem in words: a summary line in `el` (no JSON Pointers, no HTTP
 * codes: those go under "Technical details"), each `errors[]` entry next to
 * the field its pointer names (searched in `forms`, in order) in that field's
 * unit, and a suggestion. `endpoint` (e.g. "POST /v1/column") words a 404 as
 * a missing endpoint.
 */
export function showProblem(el, problem, { forms = [], endpoint = '', label = '' } = {}) {
  clearErrors(...forms);
  const unmatched = markErrors(problem.errors, forms);
  // The first marked field takes the focus: typing corrects it at once.
  if (unmatched.length < (problem.errors ?? []).length) queueMicrotask(() => focusFirstInvalid(forms));
  el.hidden = false;
  el.className = 'status error';
  el.replaceChildren();
  el.dataset.problem = problemCode(problem);
  el.dataset.status = String(problem.status ?? '');
  bringIntoView(el);

  const code = problemCode(problem);
  const head = h('p', { class: 'summary' });
  if (label) head.append(h('strong', {}, `${label}: `));
  const suggestion = h('p', { class: 'suggestion' });
  const errors = problem.errors ?? [];

  if (problem.status === 404 && endpoint) {
    head.append(h('strong', {}, 'Not available. '),
      `This server does not offer ${endpoint.replace(/^POST /, '')} yet; the other calculations work without it.`);
  } else if (code === 'capacity_exceeded') {
    const law = forms.map((f) => f.querySelector('[data-pointer="/contact/law"]')).find(Boolean)?.value;
    head.append(h('strong', {}, 'The impact carries more energy than the contact law can store. '),
      humanMessage(problem.detail ?? ''), '.');
    if (problem.max_velocity_m_s !== undefined) {
      el.append(head, h('p', { class: 'extra', dataset: { out: 'max_velocity_m_s' } },
        `Largest impact velocity this contact law can take with these inputs: ${fmt(problem.max_velocity_m_s, 5)} m/s.`));
    } else {
      el.append(head);
    }
    suggestion.append('Lower the marked velocity below that value, or choose a larger, stiffer rock; ',
      law === 'hertz_point' ? '' : 'the hertz_point law has no such limit. ',
      'This is a limit of the contact law (beyond it the law has no solution), not a statement about the column.');
    el.append(suggestion);
    appendList(el, errors, unmatched, forms);
    appendDetails(el, problem);
    return;
  } else if (problem.status === 0) {
    head.append(h('strong', {}, 'No answer from the server. '), 'Check that it is running and reachable, then compute again.');
  } else if (problem.status === 503) {
    head.append(h('strong', {}, 'The server is busy. '), 'All its solver slots are taken; compute again in a few seconds.');
  } else if (problem.status === 504) {
    head.append(h('strong', {}, 'The computation took too long and was stopped. '),
      'Ask for fewer runs, a shorter time or fewer samples.');
  } else if (errors.length) {
    const n = errors.length;
    head.append(h('strong', {}, `${n === 1 ? 'One input needs' : `${n} inputs need`} attention; nothing was computed. `));
    suggestion.append('Correct the marked field', n > 1 ? 's' : '', ' (the valid range is given beside each) and compute again.');
  } else {
    head.append(h('strong', {}, `${problem.title || 'Error'}. `), humanMessage(problem.detail ?? ''));
  }
  el.append(head);
  if (problem.max_velocity_m_s !== undefined) {
    el.append(h('p', { class: 'extra', dataset: { out: 'max_velocity_m_s' } },
      `Largest impact velocity this contact law can take: ${fmt(problem.max_velocity_m_s, 5)} m/s.`));
  }
  appendList(el, errors, unmatched, forms);
  if (suggestion.childNodes.length) el.append(suggestion);
  appendDetails(el, problem);
}

function appendList(el, errors, unmatched, forms) {
  const items = errors.map((e) => {
    const found = e.field ? locate(e.field, forms) : null;
    const where = found?.target.querySelector('label, legend')?.textContent?.trim();
    const message = found?.input ? localise(e.message ?? 'invalid', found.input) : humanMessage(e.message ?? 'invalid');
    const entered = found?.input && found.input.type === 'text' && found.input.value.trim()
      ? ` (entered: ${found.input.value.trim()}${unitOf(found.input) ? ` ${unitOf(found.input)}` : ''})` : '';
    const name = where || (e.field ? fieldWords(e.field) : 'the request');
    return h('li', { class: unmatched.includes(e) ? 'unmatched' : '' }, h('strong', {}, name), `: ${message}${entered}`);
  });
  if (items.length) el.append(h('ul', {}, items));
}

function appendDetails(el, problem) {
  const details = h('details', { class: 'technical' }, h('summary', {}, 'Technical details'),
    h('p', {}, `HTTP ${problem.status ?? '—'}, ${problem.type ?? ''}`),
    ...(problem.errors ?? []).map((e) => h('p', {}, h('code', {}, e.field ?? ''), ` ${e.message ?? ''}`)));
  if (problem.type && problem.type.startsWith('/problems/')) {
    details.append(h('p', {}, h('a', { href: problem.type.slice(1), target: '_blank' }, 'About this problem')));
  }
  el.append(details);
}

/** "/monte_carlo/runs" → "monte carlo › runs" for a field the form does not show. */
function fieldWords(pointer) {
  return pointer.split('/').filter(Boolean).map((k) => k.replace(/_/g, ' ')).join(' › ');
}

function problemCode(problem) {
  return (problem.type ?? '').split('/').pop() || String(problem.status ?? '');
}
