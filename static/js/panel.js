// One submit/render cycle shared by every calculation panel: read the forms
// (a field that cannot be read is a field error, nothing is sent), clear the
// old result on any error, show busy / progress / cancel, send, then either
// mark the problem next to its fields or render the answer. Each panel gives
// only what differs: how to build the request, send it, render and clear.

import { postJson } from './api.js';
import { clearErrors, readForm } from './form.js';
import { bringIntoView, hideStatus, showBusy, showInfo, showProblem } from './status.js';

/**
 * `opts`:
 * - `name`: the panel (tab) name; `form`: its form; `forms`: every form whose
 *   fields the request carries, own form first (problems are marked there).
 * - `endpoint`: e.g. "v1/impact" (POSTed by the default `send`).
 * - `status`, `progress` (optional `.progress` box with a cancel button).
 * - `build(reads)`: the request from `readForm` of each of `forms` (in order);
 *   it may throw `{fieldErrors: [{field, message}]}` for inputs it reads itself.
 * - `send(request, {signal, onProgress})`: optional; resolves to an answer
 *   `{ok, data}` or `{ok: false, problem, label?}`.
 * - `stream(request)`: true when progress should be asked for.
 * - `busy(request)`: the busy text. `progressText({done, total, remaining_s}, request)`:
 *   optional, the progress line in the panel's own words (null: the plain line). `render(data, request)`, `clear()`.
 * Returns `{run}`; `run()` does what pressing the panel's button does.
 */
export function initPanel(opts) {
  const { name, form, status, progress } = opts;
  const forms = opts.forms ?? [form];
  const bar = progress?.querySelector('progress');
  const text = progress?.querySelector('.progress-text');
  let running = null;

  progress?.querySelector('button')?.addEventListener('click', () => running?.abort());
  form.addEventListener('submit', (event) => {
    event.preventDefault();
    run();
  });

  async function run() {
    running?.abort();
    clearErrors(...forms);
    const reads = forms.map((f) => readForm(f));
    const bad = reads.flatMap((r) => r.errors);
    if (bad.length) {
      opts.clear();
      showProblem(status, {
        errors: bad.map(({ el, message }) => ({ field: el.dataset.pointer ?? el.dataset.target, message })),
      }, { forms, endpoint: `POST /${opts.endpoint}` });
      status.dataset.local = 'true';
      return null;
    }
    delete status.dataset.local;
    let request;
    try {
      request = opts.build(reads);
    } catch (err) {
      if (!err.fieldErrors) throw err;
      opts.clear();
      showProblem(status, { errors: err.fieldErrors }, { forms });
      return null;
    }

    const controller = new AbortController();
    running = controller;
    const stream = opts.stream?.(request) ?? false;
    showBusy(status, opts.busy?.(request) ?? 'Computing…');
    if (progress && stream) {
      // Indeterminate until the first update: an empty bar would look like "0 % done".
      bar.removeAttribute('value');
      text.textContent = 'starting…';
      progress.hidden = false;
      bringIntoView(progress);
    }
    const onProgress = stream ? ({ done, total, remaining_s: left }) => {
      if (running !== controller) return;
      bar.max = total || 1;
      bar.value = done;
      // a panel may word it itself (an ensemble that stops when precise enough)
      const own = opts.progressText?.({ done, total, remaining_s: left }, request);
      if (own) {
        text.textContent = own;
        return;
      }
      // the server's estimate of the time left at the rate so far
      const eta = typeof left === 'number' ? `, about ${left < 90 ? `${Math.max(1, Math.round(left))} s` : `${Math.round(left / 60)} min`} left` : '';
      text.textContent = `${done} / ${total}${opts.unit ? ` ${opts.unit}` : ''}${eta}`;
    } : undefined;

    let answer;
    try {
      answer = await (opts.send ?? defaultSend)(request, { signal: controller.signal, onProgress });
    } catch (err) {
      if (err.name !== 'AbortError') throw err;
      if (running === controller) {
        opts.clear();
        showInfo(status, 'Cancelled; nothing is shown.');
      }
      return null;
    } finally {
      if (running === controller) {
        if (progress) progress.hidden = true;
        running = null;
      }
    }
    if (running && running !== controller) return null;
    if (!answer.ok) {
      opts.clear();
      showProblem(status, answer.problem, { forms, endpoint: `POST /${opts.endpoint}`, label: answer.label ?? '' });
      return null;
    }
    if (answer.note) showInfo(status, answer.note);
    else hideStatus(status);
    opts.render(answer.data, request);
    document.dispatchEvent(new CustomEvent('gangue:result', { detail: { name, data: answer.data, request } }));
    return answer.data;
  }

  function defaultSend(request, { signal, onProgress }) {
    return postJson(opts.endpoint, request, { signal, onProgress });
  }

  return { run };
}
