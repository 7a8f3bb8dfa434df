// Number formatting and result tables. Values arrive in SI; each row names
// the engineering unit it is shown in and the factor from SI to that unit.

const SUPERSCRIPT = { '-': '⁻', '+': '', 0: '⁰', 1: '¹', 2: '²', 3: '³', 4: '⁴', 5: '⁵', 6: '⁶', 7: '⁷', 8: '⁸', 9: '⁹' };

/**
 * A number with `sig` significant digits; × 10ⁿ outside [1e-3, 1e6).
 * With `scale` (the size of the quantities it stands among), |x| below
 * 1e-12·scale is rounding noise and shown as 0.
 */
export function fmt(x, sig = 5, scale = 0) {
  if (x === null || x === undefined) return '—';
  if (typeof x !== 'number') return String(x);
  if (!Number.isFinite(x)) return String(x);
  if (x === 0 || Math.abs(x) < 1e-12 * Math.abs(scale)) return '0';
  const a = Math.abs(x);
  if (a >= 1e-3 && a < 1e6) return trimZeros(x.toPrecision(sig));
  const [mantissa, exponent] = x.toExponential(sig - 1).split('e');
  const power = [...exponent].map((c) => SUPERSCRIPT[c] ?? c).join('');
  return `${trimZeros(mantissa)} × 10${power}`;
}

function trimZeros(s) {
  if (s.includes('e') || !s.includes('.')) return s;
  return s.replace(/0+$/, '').replace(/\.$/, '');
}

/** Scales an SI value (number, array or null) for display. */
export function scaled(value, scale = 1) {
  if (value === null || value === undefined) return value;
  if (Array.isArray(value)) return value.map((v) => scaled(v, scale));
  return typeof value === 'number' ? value * scale : value;
}

/** Text for a value that may be an array ([a, b] → "a, b"). */
export function fmtValue(value, sig, scale = 0) {
  if (Array.isArray(value)) return value.map((v) => fmt(v, sig, scale)).join(', ');
  return fmt(value, sig, scale);
}

/** Creates an element with attributes and children (strings or nodes). */
export function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === 'class') el.className = value;
    else if (key === 'html') el.innerHTML = value;
    else if (key === 'dataset') Object.assign(el.dataset, value);
    else el.setAttribute(key, value === true ? '' : value);
  }
  for (const child of children.flat()) {
    if (child === null || child === undefined || child === false) continue;
    el.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return el;
}

/**
 * Fills a table body with rows `{key, label, symbol, unit, scale, sig, alt}`
 * for the keys present in `data`. `key` may be a dotted path; `alt` is an
 * optional second unit `{unit, scale}`. The value cell carries
 * `data-out="<prefix><key>"` so that tests and scripts can find it.
 */
export function fillTable(tbody, rows, data, prefix = '') {
  tbody.replaceChildren();
  for (const row of rows) {
    const raw = row.get ? row.get(data) : pick(data, row.key);
    if (raw === undefined) continue;
    const value = scaled(raw, row.scale ?? 1);
    const noise = row.noise ? row.noise(data) * (row.scale ?? 1) : 0;
    const text = row.words ? row.words(raw, data) : fmtValue(value, row.sig, noise);
    const cell = h('td', { class: row.words ? 'text' : 'num', dataset: { out: prefix + row.key } }, text);
    if (!row.words && typeof value === 'number') cell.dataset.csv = csvNumber(value);
    const unit = h('td', { class: 'unit', html: row.unit ?? '' });
    if (row.alt && typeof raw === 'number') {
      unit.append(h('span', { class: 'alt' }, `= ${fmt(raw * row.alt.scale, row.sig)} ${row.alt.unit}`));
    }
    tbody.append(
      h('tr', {},
        h('th', { scope: 'row' }, row.label),
        h('td', { class: 'sym', html: row.symbol ?? '' }),
        cell,
        unit),
    );
  }
}

/** `pick(obj, "a.b")` → obj.a.b, or undefined. */
export function pick(obj, path) {
  return path.split('.').reduce((o, k) => (o === null || o === undefined ? undefined : o[k]), obj);
}

/** Warning codes that say a result lies outside the model's validity. */
const VALIDITY = /validity|yield|plastic|exceed|above|outside|beyond|energy_ratio_above_one|too_large|comparable/i;

/** Shows `warnings` ([{code, message}]) in a box, or hides it; validity warnings in red. */
export function showWarnings(el, warnings, heading = 'Warnings') {
  const list = (warnings ?? []).filter(Boolean);
  el.hidden = list.length === 0;
  el.replaceChildren();
  if (!list.length) return;
  // Many warnings of one code (a support no run reached, one per support) become one line
  // with the rest folded under it.
  const groups = new Map();
  for (const w of list) {
    if (!groups.has(w.code)) groups.set(w.code, []);
    groups.get(w.code).push(w);
  }
  const items = [];
  for (const [code, ws] of groups) {
    const cls = VALIDITY.test(code) ? 'validity' : '';
    if (ws.length <= 3) {
      for (const w of ws) items.push(h('li', { class: cls, dataset: { code } }, humanMessage(w.message), ' ', h('code', {}, code)));
    } else {
      items.push(h('li', { class: cls, dataset: { code, count: String(ws.length) } },
        humanMessage(ws[0].message), ` — and ${ws.length - 1} more like it `, h('code', {}, code),
        h('details', {}, h('summary', {}, `all ${ws.length}`), h('ul', {}, ws.slice(1).map((w) => h('li', {}, humanMessage(w.message)))))));
    }
  }
  el.append(h('strong', {}, heading), h('ul', {}, items));
}

/** Server text with exponent notation ("2.335413e0") shown as people write numbers. */
export function humanMessage(text) {
  const unknown = /^unknown field `([^`]+)`/.exec(String(text ?? ''));
  if (unknown) return `this server does not accept "${unknown[1]}" yet (the page is newer than the server)`;
  return String(text ?? '').replace(/(-?\d+(?:\.\d+)?)e([+-]?\d+)/g, (_, m, e) => fmt(Number(`${m}e${e}`), 5));
}

/** The lines that head every CSV the page saves ("# gangue <version>", "# date <ISO>", "# case <link>", …). */
let csvHeader = () => [];

/** Sets what heads every saved CSV: a function giving its comment lines (without "# "). */
export function setCsvHeader(fn) {
  csvHeader = fn;
}

/** The header block of a saved CSV, one "# …" line each. */
export function csvHeaderText() {
  return csvHeader().map((line) => `# ${String(line).replace(/\s*\n\s*/g, ' ')}\n`).join('');
}

/** CSV text of rows of cells (RFC 4180 quoting), after the header block. */
export function csvText(rows) {
  return csvHeaderText() + rows.map((r) => r.map((c) => {
    const s = c === null || c === undefined ? '' : String(c);
    return /[",\n]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s;
  }).join(',')).join('\n') + '\n';
}

/** Starts a download of `text` (or a Blob) as `name`. */
export function download(name, content, type = 'text/csv') {
  const blob = content instanceof Blob ? content : new Blob([content], { type: `${type};charset=utf-8` });
  const a = h('a', { href: URL.createObjectURL(blob), download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
}

/**
 * Rows of a rendered HTML table (header included); a cell's `data-csv` (a plain number, or
 * empty) stands for its text, so that numeric columns stay numbers.
 */
export function tableRows(table) {
  return [...table.querySelectorAll('tr')].map((tr) =>
    [...tr.children].map((c) => (c.dataset.csv !== undefined ? c.dataset.csv : c.textContent.replace(/\s+/g, ' ').trim())));
}

/** A number as a CSV cell: shortest round-trip text, or empty for null / not a number. */
export function csvNumber(v) {
  return typeof v === 'number' && Number.isFinite(v) ? String(v) : '';
}

/** A small button that downloads the CSV that `rows()` gives. */
export function csvButton(name, rows, label = 'CSV') {
  const b = h('button', { type: 'button', class: 'export', dataset: { csv: name }, title: `Download ${name}` }, label);
  b.addEventListener('click', () => download(name, csvText(rows())));
  return b;
}
