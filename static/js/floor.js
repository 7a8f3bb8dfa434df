// Real floors (api.md "Floors"): an ESRI ASCII grid (.asc) or GeoJSON contours
// uploaded from the engineer's computer, drawn as shaded relief or contour
// lines, sent as `face.floor`. An uploaded file cannot travel in a link.

import { fmt, h } from './format.js';

/** The largest request the service takes (GET /v1/presets `limits.max_body_bytes`; 16 MiB unless told). */
let maxBodyBytes = 16 * 1024 * 1024;

/** Takes the service's body limit from GET /v1/presets. */
export function setFloorLimits(limits) {
  if (limits?.max_body_bytes > 0) maxBodyBytes = limits.max_body_bytes;
}

/** Bytes in words: "16 MiB", "1.5 MiB", "900 kiB". */
export function bytesWords(n) {
  if (n >= 1024 * 1024) return `${fmt(n / (1024 * 1024), 3)} MiB`;
  if (n >= 1024) return `${fmt(n / 1024, 3)} kiB`;
  return `${n} bytes`;
}

/** Smallest and largest of many numbers (a spread of a big array overflows the call stack). */
function extent(values) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) {
    if (v === null) continue;
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return [lo, hi];
}

/** The floor group of the Migration form (its controls are built here, not by buildForm). */
export function initFloor(form) {
  const group = h('fieldset', { dataset: { group: '/face/floor' } });
  const kind = h('select', { id: 'floor-kind', dataset: { local: 'floor', kind: 'select' } },
    h('option', { value: 'plane' }, 'plane (from dip and length)'),
    h('option', { value: 'upload' }, 'uploaded file (.asc or GeoJSON)'));
  const file = h('input', { type: 'file', id: 'floor-file', dataset: { target: '/face/floor/esri_ascii' }, accept: '.asc,.txt,.geojson,.json', 'aria-describedby': 'floor-info' });
  const elevation = h('input', { type: 'text', id: 'floor-elevation-property', value: 'elevation', dataset: { local: 'floor_elevation_property', kind: 'select', target: '/face/floor/elevation_property' } });
  const resolution = h('input', { type: 'text', id: 'floor-resolution', inputmode: 'decimal', value: '1', dataset: { local: 'floor_resolution', kind: 'number', optional: 'true', target: '/face/floor/resolution_m' } });
  const mapE = h('input', { type: 'text', id: 'floor-map-e', inputmode: 'decimal', placeholder: 'none', dataset: { local: 'map_e', kind: 'number', optional: 'true', target: '/face/floor/map/origin_m/0' } });
  const mapN = h('input', { type: 'text', id: 'floor-map-n', inputmode: 'decimal', placeholder: 'none', dataset: { local: 'map_n', kind: 'number', optional: 'true', target: '/face/floor/map/origin_m/1' } });
  const mapA = h('input', { type: 'text', id: 'floor-map-a', inputmode: 'decimal', placeholder: 'none', dataset: { local: 'map_dir', kind: 'number', optional: 'true', target: '/face/floor/map/dip_direction_deg' } });
  const info = h('p', { class: 'note', id: 'floor-info' }, 'The plane floor follows the dip and length above.');
  const canvas = h('canvas', { id: 'floor-canvas', width: 320, height: 240, role: 'img', 'aria-label': 'the uploaded floor', hidden: true });
  const row = (label, control, unit = '', hint = '') => h('div', { class: `field field-${control.tagName === 'SELECT' ? 'select' : 'number'}` },
    h('label', { for: control.id }, label), h('div', { class: 'control' }, control, h('span', { class: 'unit' }, unit)),
    hint ? h('p', { class: 'hint' }, hint) : null, h('p', { class: 'field-error', hidden: true, role: 'alert' }));
  const fileError = h('p', { class: 'field-error', id: 'floor-file-error', hidden: true, role: 'alert' });
  const uploadBox = h('div', { class: 'floor-upload', hidden: true },
    h('div', { class: 'field field-file' }, h('label', { for: 'floor-file' }, 'File'), file, fileError),
    row('Elevation property (GeoJSON)', elevation, '', 'else the third coordinate'),
    row('Contour resolution (GeoJSON)', resolution, 'm'),
    row('Map origin, easting', mapE, 'm', 'map coordinates: the face\'s origin and dip direction; empty: the file\'s own frame'),
    row('Map origin, northing', mapN, 'm'),
    row('Dip direction (azimuth)', mapA, '°', 'clockwise from north'),
    canvas);
  group.append(h('legend', {}, 'Floor'), h('p', { class: 'group-error', hidden: true }), row('Floor', kind), uploadBox, info);
  form.querySelector('.form-fields fieldset').after(group);
  const zones = initZones(group, row);

  let loaded = null; // {name, floor (without map), draw: {kind, ...}}
  let refused = null; // why the chosen file was refused; stays until another file is chosen

  const showRefusal = (text) => {
    refused = text;
    fileError.textContent = text ?? '';
    fileError.hidden = !text;
    if (text) {
      file.setAttribute('aria-invalid', 'true');
      file.setAttribute('aria-describedby', 'floor-file-error floor-info');
    } else {
      file.removeAttribute('aria-invalid');
      file.setAttribute('aria-describedby', 'floor-info');
    }
  };

  const sync = () => {
    uploadBox.hidden = kind.value !== 'upload';
    form.dataset.floorUploaded = String(kind.value === 'upload' && Boolean(loaded));
    if (kind.value === 'plane') info.textContent = 'The plane floor follows the dip and length above.';
    else if (!loaded && !refused) info.textContent = 'Choose a file. An uploaded floor cannot travel in a link: whoever opens the link must upload the same file.';
    else if (!loaded) info.textContent = 'Choose another file. An uploaded floor cannot travel in a link.';
  };
  kind.addEventListener('change', sync);
  form.addEventListener('reset', () => setTimeout(() => {
    loaded = null;
    file.value = '';
    canvas.hidden = true;
    showRefusal(null);
    sync();
  }));

  file.addEventListener('change', async () => {
    const f = file.files?.[0];
    loaded = null;
    canvas.hidden = true;
    showRefusal(null);
    if (!f) return sync();
    // The file travels inside the JSON request: one over the service's body limit is refused here, unsent.
    if (f.size > maxBodyBytes) {
      showRefusal(`${f.name} is ${bytesWords(f.size)} (${f.size} bytes): the service takes requests up to ${bytesWords(maxBodyBytes)} (${maxBodyBytes} bytes). `
        + 'Coarsen the grid (larger cells) or crop it to the face.');
      return sync();
    }
    // No computing with a half-read file: the button waits for the file.
    const submit = form.querySelector('button[type="submit"]');
    submit.disabled = true;
    try {
      const text = await f.text().finally(() => { submit.disabled = false; });
      loaded = /\.(geo)?json$/i.test(f.name) || text.trim().startsWith('{') ? readGeojson(f.name, text, elevation.value.trim()) : readAsc(f.name, text);
      loaded.sha256 = await sha256Hex(text);
      loaded.bytes = f.size;
      info.textContent = `${f.name}: ${loaded.summary}. An uploaded floor cannot travel in a link: whoever opens the link must upload the same file.`;
      canvas.hidden = false;
      canvas.setAttribute('aria-label', `the uploaded floor ${f.name}, north up: ${loaded.summary}`);
      draw(canvas, loaded.draw, null);
    } catch (err) {
      loaded = null;
      canvas.hidden = true;
      showRefusal(`${f.name} cannot be read: ${err.message}`);
    }
    sync();
    // the case bar names the floor in use
    form.dispatchEvent(new Event('input'));
  });
  sync();

  return {
    /** Sets `request.face.floor` from the form (or throws field errors). */
    apply(request, local) {
      if (local.floor !== 'upload') return;
      if (!loaded && refused) throw { fieldErrors: [{ field: '/face/floor/esri_ascii', message: refused }] };
      if (!loaded) {
        throw { fieldErrors: [{ field: '/face/floor', message: 'choose a floor file (.asc or GeoJSON); an uploaded floor does not travel in links' }] };
      }
      const floor = structuredClone(loaded.floor);
      if (floor.kind === 'contours') {
        floor.elevation_property = local.floor_elevation_property || 'elevation';
        if (local.floor_resolution !== undefined) floor.resolution_m = local.floor_resolution;
      }
      const map = [local.map_e, local.map_n, local.map_dir];
      if (map.some((v) => v !== undefined)) {
        if (map.some((v) => v === undefined)) {
          throw { fieldErrors: [{ field: '/face/floor/map', message: 'give the easting, the northing and the dip direction, or none of them' }] };
        }
        floor.map = { origin_m: [local.map_e, local.map_n], dip_direction_deg: local.map_dir };
      }
      request.face = { ...request.face, floor };
    },
    /** Sets `request.face.zones` from the Zones group (or throws field errors). */
    applyZones(request) {
      const z = zones.read();
      if (z) request.face = { ...request.face, zones: z };
    },
    /** Draws the run's path on the floor (face coordinates turned back to the file's). */
    showPath(data) {
      if (!loaded || canvas.hidden) return;
      const tr = data?.trajectory;
      const map = data?.inputs?.face?.floor?.map;
      const path = tr?.position_m?.map(([x, y]) => (map ? toMap(x, y, map) : [x, y]));
      draw(canvas, loaded.draw, path ?? null);
    },
    uploaded: () => Boolean(loaded),
    /** The uploaded floor in use ({name, sha256, bytes, summary, draw}), or null for the plane. */
    current: () => (kind.value === 'upload' && loaded ? loaded : null),
  };
}

/**
 * The Zones group (api.md `face.zones`): a zone map pasted or uploaded (polygons as JSON, or an
 * ESRI ASCII grid of integer codes, in the floor's own frame) and a table of materials, each
 * field empty for the face's value. Sent in SI: μ, e_n and e_t are dimensionless.
 */
function initZones(after, row) {
  const group = h('fieldset', { class: 'zones', dataset: { group: '/face/zones' } });
  const use = h('select', { id: 'zones-use', dataset: { local: 'zones_use', kind: 'select' } },
    h('option', { value: 'none' }, 'one material (the face\'s)'),
    h('option', { value: 'map' }, 'several materials by zone'));
  const text = h('textarea', { id: 'zones-map', rows: 5, spellcheck: 'false', 'aria-describedby': 'zones-info',
    placeholder: '[{"code": 2, "points_m": [[28, -50], [200, -50], [200, 50], [28, 50]]}]   or   ncols …' });
  const file = h('input', { type: 'file', id: 'zones-file', accept: '.asc,.txt,.json' });
  const outside = h('input', { type: 'text', id: 'zones-outside', inputmode: 'numeric', placeholder: 'the first material\'s' });
  const body = h('tbody', {});
  const addRow = (m = {}) => {
    const cell = (key, mode, ph) => h('td', {}, h('input', { type: 'text', inputmode: mode, value: m[key] ?? '', placeholder: ph, dataset: { key }, 'aria-label': key }));
    const remove = h('button', { type: 'button', class: 'small', 'aria-label': 'remove this material' }, '×');
    const tr = h('tr', {}, cell('code', 'numeric', ''), cell('name', 'text', ''), cell('friction_coefficient', 'decimal', 'face'),
      cell('restitution_normal', 'decimal', 'face'), cell('restitution_tangential', 'decimal', 'face'), h('td', {}, remove));
    remove.addEventListener('click', () => tr.remove());
    body.append(tr);
  };
  const table = h('table', { class: 'zones-materials', id: 'zones-materials' },
    h('thead', {}, h('tr', {}, ...['code', 'name', 'μ', 'e_n', 'e_t', ''].map((t) => h('th', { scope: 'col' }, t)))), body);
  const add = h('button', { type: 'button', id: 'zones-add', class: 'small' }, 'Add material');
  add.addEventListener('click', () => addRow({ code: body.children.length + 1 }));
  addRow({ code: 1, name: 'scree' });
  addRow({ code: 2, name: 'meadow', friction_coefficient: 0.5, restitution_normal: 0.1 });
  const info = h('p', { class: 'note', id: 'zones-info' }, 'A zone map in the floor\'s own frame (map coordinates when the floor has a map): polygons as JSON, later ones winning, or an ESRI ASCII grid of integer codes. An empty material field takes the face\'s value.');
  const box = h('div', { class: 'zones-box', hidden: true },
    h('div', { class: 'field field-text' }, h('label', { for: 'zones-map' }, 'Zone map'), text),
    h('div', { class: 'field field-file' }, h('label', { for: 'zones-file' }, 'or a file'), file),
    row('Code elsewhere', outside, '', 'outside every polygon, NODATA, off the grid'),
    table, add, info);
  group.append(h('legend', {}, 'Zones'), h('p', { class: 'group-error', hidden: true }), row('Materials', use), box);
  after.after(group);
  const sync = () => { box.hidden = use.value !== 'map'; };
  use.addEventListener('change', sync);
  file.addEventListener('change', async () => {
    const f = file.files?.[0];
    if (f) text.value = await f.text();
  });
  sync();
  const fail = (message, field = '/face/zones') => { throw { fieldErrors: [{ field, message }] }; };
  return {
    /** The `face.zones` object of the group, or null for one material. */
    read() {
      if (use.value !== 'map') return null;
      const src = text.value.trim();
      if (!src) fail('paste or choose a zone map: polygons as JSON or an ESRI ASCII grid of codes');
      const zones = {};
      if (src.startsWith('[') || src.startsWith('{')) {
        let polys;
        try { polys = JSON.parse(src); } catch (err) { fail(`the zone map is not JSON: ${err.message}`); }
        if (!Array.isArray(polys)) polys = polys.polygons;
        if (!Array.isArray(polys)) fail('give the polygons as a list [{"code", "points_m"}, …]');
        zones.polygons = polys;
      } else {
        zones.esri_ascii = text.value;
      }
      if (outside.value.trim()) {
        const c = Number(outside.value);
        if (!Number.isInteger(c)) fail(`${outside.value} is not an integer code`, '/face/zones/outside_code');
        zones.outside_code = c;
      }
      zones.materials = [...body.children].map((tr, i) => {
        const m = {};
        for (const input of tr.querySelectorAll('input')) {
          const v = input.value.trim();
          if (!v) continue;
          const key = input.dataset.key;
          if (key === 'name') { m.name = v; continue; }
          const n = Number(v);
          if (!Number.isFinite(n) || (key === 'code' && !Number.isInteger(n))) fail(`${v} is not ${key === 'code' ? 'an integer code' : 'a number'}`, `/face/zones/materials/${i}/${key}`);
          m[key] = n;
        }
        if (m.code === undefined) fail('each material needs its code', `/face/zones/materials/${i}/code`);
        return m;
      });
      return zones;
    },
  };
}

/** SHA-256 of a text (its UTF-8 bytes, as sent in the request) in hex, computed in the page. */
export async function sha256Hex(text) {
  if (!globalThis.crypto?.subtle) return null;
  const digest = await crypto.subtle.digest('SHA-256', new TextEncoder().encode(text));
  return [...new Uint8Array(digest)].map((b) => b.toString(16).padStart(2, '0')).join('');
}

/** Face (x down the dip, y across) to map (E, N) for `map` {origin_m, dip_direction_deg}. */
function toMap(x, y, map) {
  const a = (map.dip_direction_deg * Math.PI) / 180;
  const [e0, n0] = map.origin_m;
  return [e0 + x * Math.sin(a) - y * Math.cos(a), n0 + x * Math.cos(a) + y * Math.sin(a)];
}

/** Reads an ESRI ASCII grid: the request keeps the text as sent; the drawing its values. */
export function readAsc(name, text) {
  const lines = text.split(/\r?\n/);
  const head = {};
  let i = 0;
  for (; i < lines.length; i++) {
    const m = /^\s*([A-Za-z_]+)\s+(\S+)\s*$/.exec(lines[i]);
    if (!m) break;
    head[m[1].toLowerCase()] = Number(m[2]);
  }
  for (const key of ['ncols', 'nrows', 'cellsize']) {
    if (!(head[key] > 0)) throw new Error(`line ${i + 1}: the header lacks a positive ${key}`);
  }
  // Every value must be a number, as the server reads it: a letter is refused with its line.
  const values = [];
  const number = /^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/;
  for (let k = i; k < lines.length; k++) {
    const line = lines[k].trim();
    if (!line) continue;
    for (const token of line.split(/\s+/)) {
      if (!number.test(token)) throw new Error(`line ${k + 1}: "${token.slice(0, 20)}" is not a number`);
      values.push(Number(token));
    }
  }
  if (values.length !== head.ncols * head.nrows) {
    throw new Error(`${values.length} values for ${head.nrows} rows × ${head.ncols} columns`);
  }
  const nodata = head.nodata_value;
  const d = head.cellsize;
  const x0 = head.xllcenter ?? (head.xllcorner ?? 0) + d / 2;
  const y0 = head.yllcenter ?? (head.yllcorner ?? 0) + d / 2;
  const z = [];
  for (let r = 0; r < head.nrows; r++) {
    // the first data row is the northernmost: row r of the file is y = y0 + (nrows − 1 − r)·d
    z.push(values.slice(r * head.ncols, (r + 1) * head.ncols).map((v) => (v === nodata || !Number.isFinite(v) ? null : v)));
  }
  const holes = z.flat().filter((v) => v === null).length;
  return {
    name,
    floor: { kind: 'grid', esri_ascii: text },
    summary: `${head.ncols} × ${head.nrows} grid, ${fmt(d, 4)} m cells${holes ? `, ${holes} NODATA holes` : ''}`,
    draw: { kind: 'grid', z, x0, y0, d, nrows: head.nrows, ncols: head.ncols },
  };
}

/** Reads GeoJSON contours (LineString / MultiLineString), elevation from the property or the third coordinate. */
export function readGeojson(name, text, property) {
  let json;
  try {
    json = JSON.parse(text);
  } catch (err) {
    throw new Error(`not JSON (${err.message})`);
  }
  if (json?.type !== 'FeatureCollection' || !Array.isArray(json.features)) throw new Error('not a GeoJSON FeatureCollection');
  const lines = [];
  json.features.forEach((f, k) => {
    const g = f?.geometry;
    const parts = g?.type === 'LineString' ? [g.coordinates] : g?.type === 'MultiLineString' ? g.coordinates : null;
    if (!parts) throw new Error(`feature ${k} is not a LineString or MultiLineString`);
    const prop = f.properties?.[property || 'elevation'];
    for (const part of parts) {
      const zs = part.map((p) => (typeof prop === 'number' ? prop : p[2]));
      if (zs.some((v) => typeof v !== 'number')) throw new Error(`feature ${k} has no elevation (property "${property}" or a third coordinate)`);
      lines.push({ points: part.map((p) => [p[0], p[1]]), z: zs[0] });
    }
  });
  return {
    name,
    floor: { kind: 'contours', geojson: json, resolution_m: 1 },
    summary: `${lines.length} contour line${lines.length === 1 ? '' : 's'} in ${json.features.length} features`,
    draw: { kind: 'contours', lines },
  };
}

/** Shaded relief (grid) or coloured contour lines, north up, with an optional path. */
function draw(canvas, floor, path) {
  let xmin; let xmax; let ymin; let ymax;
  if (floor.kind === 'grid') {
    xmin = floor.x0 - floor.d / 2;
    xmax = floor.x0 + (floor.ncols - 0.5) * floor.d;
    ymin = floor.y0 - floor.d / 2;
    ymax = floor.y0 + (floor.nrows - 0.5) * floor.d;
  } else {
    const pts = floor.lines.flatMap((l) => l.points);
    [xmin, xmax] = extent(pts.map((p) => p[0]));
    [ymin, ymax] = extent(pts.map((p) => p[1]));
  }
  // The canvas takes the floor's aspect (within limits), north up, the floor centred.
  const W = canvas.width;
  const H = Math.round(Math.min(360, Math.max(120, (W - 20) * ((ymax - ymin) / (xmax - xmin || 1)) + 20)));
  canvas.height = H;
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, W, H);
  const scale = Math.min((W - 20) / (xmax - xmin || 1), (H - 20) / (ymax - ymin || 1));
  const ox = (W - (xmax - xmin) * scale) / 2;
  const oy = (H - (ymax - ymin) * scale) / 2;
  const px = (x) => ox + (x - xmin) * scale;
  const py = (y) => H - oy - (y - ymin) * scale;
  if (floor.kind === 'grid') {
    const { z, d, nrows, ncols } = floor;
    const [lo, hi] = extent(z.flat());
    const cell = Math.max(1, d * scale);
    for (let r = 0; r < nrows; r++) {
      for (let c = 0; c < ncols; c++) {
        const v = z[r][c];
        if (v === null) continue;
        // Hillshade from the north-west, 45° above the horizon.
        const east = (z[r][Math.min(c + 1, ncols - 1)] ?? v) - (z[r][Math.max(c - 1, 0)] ?? v);
        const north = (z[Math.max(r - 1, 0)][c] ?? v) - (z[Math.min(r + 1, nrows - 1)][c] ?? v);
        const gx = east / (2 * d);
        const gy = north / (2 * d);
        const shade = Math.max(0, (1 + (gx - gy) * -0.7071) / Math.sqrt(1 + gx * gx + gy * gy));
        const t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
        ctx.fillStyle = `hsl(${120 - 90 * t}, 35%, ${Math.round(25 + 45 * shade)}%)`;
        const x = floor.x0 + c * d;
        const y = floor.y0 + (nrows - 1 - r) * d;
        ctx.fillRect(px(x) - cell / 2, py(y) - cell / 2, cell + 0.5, cell + 0.5);
      }
    }
  } else {
    const [lo, hi] = extent(floor.lines.map((l) => l.z));
    ctx.lineWidth = 1.5;
    for (const l of floor.lines) {
      const t = hi > lo ? (l.z - lo) / (hi - lo) : 0.5;
      ctx.strokeStyle = `hsl(${120 - 90 * t}, 55%, 35%)`;
      ctx.beginPath();
      l.points.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
      ctx.stroke();
    }
  }
  if (path?.length) {
    ctx.strokeStyle = '#1d5fa8';
    ctx.lineWidth = 2;
    ctx.beginPath();
    path.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
    ctx.stroke();
  }
  ctx.fillStyle = '#1c2430';
  ctx.font = '11px system-ui, sans-serif';
  ctx.fillText('N ↑', W - 28, 14);
}
