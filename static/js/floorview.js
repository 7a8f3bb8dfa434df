// The floor in the results of Migration and Scene: a plan (shaded relief,
// contour lines or the inclined plane, with axes in metres, a scale bar and
// colour bars), the supports where they stand, the release zones, the nominal
// path coloured by speed and where the runs stopped; a profile along the real
// floor under the path; a 3-D view (vendored three.js, loaded on first use)
// that falls back to the 2-D views where WebGL is missing.

import { csvButton, fmt, h } from './format.js';
import { destroy, joinSeries, linePlot } from './plot.js';
import { deviceLabel } from './devices.js';
import { readAsc } from './floor.js';

const ELEV = (t) => `hsl(${120 - 90 * t}, 38%, 46%)`;
/** Speed colour: blue (slow) to red (fast). */
const SPEED = (t) => `hsl(${230 - 230 * Math.max(0, Math.min(1, t))}, 80%, 45%)`;
const SUPPORT_OK = '#2a8f4f';
const SUPPORT_OVER = '#c8423b';
const SUPPORT_IDLE = '#6b7684';
const ZONE = '#d88a1c';
const STOP = '#1c2430';
const BARRIER = '#7a3e12';
const COLLECTOR = '#6b3fa0';
/** A barrier the design search proposes, not yet applied: teal long dashes on a white halo. */
const PROPOSED = '#0097a7';
/** The colour of a drawn line by its kind. */
/** Colours of a floor's material zones, by the material's place in `face.zones.materials`. */
const ZONE_COLOURS = ['#3b6fb6', '#d2691e', '#8a5cc2', '#c8423b', '#8b6b3d', '#d46fb0', '#5b6b7a', '#b8a42a', '#2a9fb8'];

/**
 * The material zones of a request (`face.zones`), in the floor's own frame (the plan's):
 * {polygons, grid (an ESRI code grid as drawn, or null), outside, codes, names, colour(code)},
 * or null without zones.
 */
export function zonesOf(request) {
  const z = request?.face?.zones;
  if (!z) return null;
  const materials = z.materials ?? [];
  const codes = materials.map((m) => m.code);
  let grid = null;
  if (z.esri_ascii) {
    try { grid = readAsc('zones', z.esri_ascii).draw; } catch { grid = null; }
  }
  const polygons = z.polygons ?? [];
  const outside = z.outside_code ?? codes[0];
  // the code at (x, y) of the floor's frame: the last polygon holding it, the grid's cell, or
  // the outside code (even–odd crossing test, as the service's)
  const inside = (pts, x, y) => {
    let odd = false;
    for (let i = 0, j = pts.length - 1; i < pts.length; j = i++) {
      const [ax, ay] = pts[i];
      const [bx, by] = pts[j];
      if ((ay > y) !== (by > y) && x < ((bx - ax) * (y - ay)) / (by - ay) + ax) odd = !odd;
    }
    return odd;
  };
  const codeAt = (x, y) => {
    for (let k = polygons.length - 1; k >= 0; k--) if (inside(polygons[k].points_m, x, y)) return polygons[k].code;
    if (grid) {
      const c = Math.floor((x - grid.x0 + grid.d / 2) / grid.d);
      const r = grid.nrows - 1 - Math.floor((y - grid.y0 + grid.d / 2) / grid.d);
      const v = grid.z[r]?.[c];
      if (v !== undefined && v !== null) return v;
    }
    return outside;
  };
  return {
    polygons,
    grid,
    outside,
    codes,
    codeAt,
    names: new Map(materials.map((m) => [m.code, m.name ?? null])),
    colour: (c) => ZONE_COLOURS[Math.max(0, codes.indexOf(c)) % ZONE_COLOURS.length],
  };
}

const deviceColour = (d) => (d.kind === 'barrier' ? BARRIER : d.kind === 'proposed' ? PROPOSED : COLLECTOR);
/** Map colour: pale yellow (low) through red to purple (high). */
const MAPC = (t) => {
  const u = Math.max(0, Math.min(1, t));
  return `hsl(${(52 - 112 * u + 360) % 360}, 88%, ${62 - 28 * u}%)`;
};

/**
 * The layers of an ensemble's per-cell maps (`maps` of a Migration or Scene answer): the field,
 * its label and unit on the page, and the factor from SI (energies shown in kJ).
 */
export const MAP_LAYERS = [
  { key: 'passages', label: 'passages', short: 'runs', field: 'passages', unit: 'runs', si: 'runs', k: 1 },
  { key: 'speed_mean', label: 'mean speed', short: 'v mean (m/s)', field: 'speed_mean_m_s', unit: 'm/s', si: 'm_s', k: 1 },
  { key: 'speed_p95', label: 'p95 speed', short: 'v p95 (m/s)', field: 'speed_p95_m_s', unit: 'm/s', si: 'm_s', k: 1 },
  { key: 'energy_mean', label: 'mean kinetic energy', short: 'E mean (kJ)', field: 'kinetic_energy_mean_j', unit: 'kJ', si: 'j', k: 1e-3 },
  { key: 'energy_p95', label: 'p95 kinetic energy', short: 'E p95 (kJ)', field: 'kinetic_energy_p95_j', unit: 'kJ', si: 'j', k: 1e-3 },
];

/** Cells along the dip and across of the page's maps (about 60 × 40), fewer when the runs are many. */
const MAP_CELLS = [60, 40];

/**
 * The map grid the page asks for with an ensemble (`output.maps`): 60 × 40 cells over the face
 * (0 to its length along the dip; across, the uploaded floor's extent, else the release, its
 * spread and the supports with 3 m beside them), fewer cells when cells × runs would pass
 * `maxCellRuns` (the server's `max_map_cell_runs`).
 */
export function defaultMapGrid(request, upload, runs, maxCellRuns = 5e7) {
  const map = request?.face?.floor?.map ?? null;
  const draw = request?.face?.floor?.kind && request.face.floor.kind !== 'plane' ? upload?.draw ?? null : null;
  let lo;
  let hi;
  if (draw && !map && draw.kind === 'grid') {
    [lo, hi] = [draw.y0, draw.y0 + (draw.nrows - 1) * draw.d];
  } else if (draw && !map && draw.kind === 'contours') {
    [lo, hi] = extent(draw.lines.flatMap((l) => l.points.map((p) => p[1])));
  } else {
    const length = request?.face?.length_m ?? 120;
    const ys = [request?.release?.across_m ?? 0, request?.monte_carlo?.release_across_m?.min, request?.monte_carlo?.release_across_m?.max,
      ...requestSupports(request, length).map((p) => p.across)].filter((v) => Number.isFinite(v));
    const [a, b] = extent(ys);
    [lo, hi] = [Math.max(-1000, a - 3), Math.min(1000, b + 3)];
  }
  let [na, nc] = MAP_CELLS;
  const n = Math.max(1, runs ?? 1);
  while (na * nc * n > maxCellRuns && (na > 4 || nc > 2)) {
    na = Math.max(4, Math.floor(na * 0.8));
    nc = Math.max(2, Math.floor(nc * 0.8));
  }
  return { cells_along_dip: na, cells_across: nc, across_min_m: lo, across_max_m: hi };
}

/** The values of `layer` ({field, k}) in page units, null where no run passed. */
function mapValues(maps, layer) {
  return maps[layer.field].map((v, i) => (maps.passages[i] > 0 && v !== null && v !== undefined ? v * layer.k : null));
}

/** The across limits of the map's cells some run entered (m), to keep them in the plane's view. */
function passedAcross(maps) {
  if (!maps) return [];
  const out = [];
  maps.passages.forEach((n, k) => {
    if (n > 0) {
      const j = k % maps.cells_across;
      out.push(maps.across_min_m + j * maps.cell_across_m, maps.across_min_m + (j + 1) * maps.cell_across_m);
    }
  });
  return extent(out).filter(Number.isFinite);
}

/** Rows of the CSV of a map layer: each cell's bounds, its passages and the layer's value in SI. */
export function mapCsvRows(maps, layer) {
  const head = ['along_dip_from_m', 'along_dip_to_m', 'across_from_m', 'across_to_m', 'passages'];
  const extra = layer && layer.key !== 'passages' ? layer.field : null;
  const rows = [extra ? [...head, extra] : head];
  for (let i = 0; i < maps.cells_along_dip; i++) {
    for (let j = 0; j < maps.cells_across; j++) {
      const k = i * maps.cells_across + j;
      const row = [maps.along_dip_min_m + i * maps.cell_along_dip_m, maps.along_dip_min_m + (i + 1) * maps.cell_along_dip_m,
        maps.across_min_m + j * maps.cell_across_m, maps.across_min_m + (j + 1) * maps.cell_across_m, maps.passages[k]];
      if (extra) row.push(maps[extra][k] ?? '');
      rows.push(row);
    }
  }
  return rows;
}

/** Smallest and largest finite values. */
function extent(values) {
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) {
    if (v === null || v === undefined || !Number.isFinite(v)) continue;
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return [lo, hi];
}

/** Face (x down the dip, y across, metres) to map (E, N) for `map` {origin_m, dip_direction_deg}. */
export function toMap(x, y, map) {
  const a = (map.dip_direction_deg * Math.PI) / 180;
  const [e0, n0] = map.origin_m;
  return [e0 + x * Math.sin(a) - y * Math.cos(a), n0 + x * Math.cos(a) + y * Math.sin(a)];
}

/** Supports where they stand, from the request (`supports` or `support_rows`), each {support, column, s, across}. */
export function requestSupports(request, length) {
  if (!request) return [];
  const rows = request.support_rows;
  if (rows) {
    const out = [];
    for (let k = 1; k <= (rows.count ?? 0); k++) {
      (rows.across_m ?? [null]).forEach((y, j) => out.push({ support: k, column: j, s: rows.lowest_along_dip_m - (k - 1) * rows.spacing_m, across: y }));
    }
    return out;
  }
  return (request.supports ?? []).map((p, i) => ({ support: i + 1, column: 0, s: p.along_dip_m ?? length, across: p.across_m ?? null }));
}

/** Release zones of a request: [{from, to, weight}] along the dip, or a point {s, across}. */
export function requestRelease(request, length) {
  const z = request?.release_zones;
  if (z === 'table1') {
    return { zones: [[0, length / 3, 0.233], [length / 3, 2 * length / 3, 0.583], [2 * length / 3, length, 0.184]].map(([from, to, weight]) => ({ from, to, weight })), table1: true };
  }
  if (Array.isArray(z)) return { zones: z.map((r) => ({ from: r.from_along_dip_m, to: r.to_along_dip_m, weight: r.weight ?? 1 })) };
  const r = request?.release ?? {};
  return { point: { s: r.along_dip_m ?? 0, across: r.across_m ?? 0, drop: r.drop_height_m } };
}

/**
 * The floor in one frame (the file's frame, or map E/N with `map`; the plane's own x
 * horizontal down the dip and y across): where a face point (s along the dip, y across)
 * lies, the floor's height there, its extent and its drawing.
 * `upload`: the page's reading of the uploaded file ({name, sha256, draw}) or null.
 */
export function floorModel(inputs, upload) {
  const face = inputs?.face ?? {};
  const dip = ((face.dip_deg ?? 45) * Math.PI) / 180;
  const length = face.length_m ?? 120;
  const floorIn = face.floor ?? { kind: 'plane' };
  const map = floorIn.map ?? null;
  const draw = floorIn.kind !== 'plane' ? upload?.draw ?? null : null;
  let x0 = 0;
  if (draw?.kind === 'grid') x0 = draw.x0;
  else if (draw?.kind === 'contours') x0 = extent(draw.lines.flatMap((l) => l.points.map((p) => p[0])))[0];
  // Path points come in face coordinates with a map, else in the file's (or the plane's) frame.
  const path = (p) => (map ? toMap(p[0], p[1], map) : [p[0], p[1]]);
  const face2view = (s, y) => (map ? toMap(s * Math.cos(dip), y, map) : [x0 + s * Math.cos(dip), y]);
  let height = null;
  if (!draw) height = (x) => -x * Math.tan(dip);
  else if (draw.kind === 'grid') height = (x, y) => gridHeight(draw, x, y);
  // Where to put marks (release, stops, supports) on contours: between the two nearest lines.
  const markHeight = height ?? ((x, y) => contourHeight(draw.lines, x, y));
  return {
    kind: draw ? draw.kind : 'plane', uploaded: Boolean(draw), name: upload?.name ?? null, sha256: upload?.sha256 ?? null,
    serverSha256: floorIn.sha256 ?? null, map, dip, length, draw, path, face2view, height, markHeight, x0,
  };
}

/** Height at (x, y) between contour lines: the two nearest lines weighted by distance (for marks only). */
export function contourHeight(lines, x, y) {
  const near = lines.map((l) => {
    let best = Infinity;
    for (let i = 0; i < l.points.length; i++) {
      const [ax, ay] = l.points[i];
      const [bx, by] = l.points[Math.min(i + 1, l.points.length - 1)];
      const dx = bx - ax;
      const dy = by - ay;
      const t = dx || dy ? Math.max(0, Math.min(1, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy))) : 0;
      best = Math.min(best, Math.hypot(x - ax - t * dx, y - ay - t * dy));
    }
    return [best, l.z];
  }).sort((a, b) => a[0] - b[0]);
  if (!near.length) return null;
  const [[d1, z1], [d2, z2] = near[0]] = near;
  return d1 + d2 > 0 ? (z1 * d2 + z2 * d1) / (d1 + d2) : z1;
}

/** Bilinear height of a grid at (x, y) in the file's frame; null off the grid or at a hole. */
export function gridHeight(g, x, y) {
  const c = (x - g.x0) / g.d;
  const rFromSouth = (y - g.y0) / g.d;
  if (c < 0 || rFromSouth < 0 || c > g.ncols - 1 || rFromSouth > g.nrows - 1) return null;
  const c0 = Math.min(Math.floor(c), g.ncols - 2 < 0 ? 0 : g.ncols - 2);
  const s0 = Math.min(Math.floor(rFromSouth), g.nrows - 2 < 0 ? 0 : g.nrows - 2);
  const fx = g.ncols > 1 ? c - c0 : 0;
  const fy = g.nrows > 1 ? rFromSouth - s0 : 0;
  const at = (cc, ss) => g.z[g.nrows - 1 - Math.min(ss, g.nrows - 1)]?.[Math.min(cc, g.ncols - 1)] ?? null;
  const v = [at(c0, s0), at(c0 + 1, s0), at(c0, s0 + 1), at(c0 + 1, s0 + 1)];
  if (v.some((q) => q === null)) return null;
  return (v[0] * (1 - fx) + v[1] * fx) * (1 - fy) + (v[2] * (1 - fx) + v[3] * fx) * fy;
}

/** Where the runs stopped, along the dip: [{s, across|null, reason}] from what the response carries. */
export function stopPositions(runsCsv, release, supports) {
  if (!runsCsv) return { stops: [], unplaced: 0 };
  const lines = runsCsv.trim().split('\n');
  const head = lines.shift().split(',');
  const col = (name) => head.indexOf(name);
  const [iRunout, iReason, iSupport, iColumn] = ['runout_m', 'stop_reason', 'support', 'column_index'].map(col);
  const stops = [];
  let unplaced = 0;
  for (const line of lines) {
    const c = line.split(',');
    const reason = c[iReason];
    if (iSupport >= 0 && c[iSupport] !== '') {
      const sup = supports.find((p) => String(p.support) === c[iSupport] && String(p.column) === (c[iColumn] || '0'));
      if (sup) { stops.push({ s: sup.s, across: sup.across, reason: 'support' }); continue; }
    }
    if (release.point) {
      stops.push({ s: release.point.s + Number(c[iRunout]), across: null, reason });
    } else if (reason === 'lower_end') {
      stops.push({ s: null, across: null, reason });
    } else unplaced += 1;
  }
  return { stops, unplaced };
}

/**
 * Draws the plan of `model` into `canvas` (CSS width of its box): the floor, the supports,
 * the release, the path coloured by speed and the stops. Returns what it drew, for the legend.
 */
export function drawPlan(canvas, model, { supports = [], release = {}, tr = null, stops = [], verdicts = new Map(), maps = null, layer = null, devices = [], hideDevices = false, zones = null } = {}) {
  const cssW = Math.max(280, Math.floor(canvas.parentElement?.clientWidth || 600));
  const pathXY = tr ? tr.position_m.map(model.path) : [];
  // The floor's extent in the view frame.
  let xr; let yr;
  if (model.draw?.kind === 'grid') {
    const g = model.draw;
    xr = [g.x0 - g.d / 2, g.x0 + (g.ncols - 0.5) * g.d];
    yr = [g.y0 - g.d / 2, g.y0 + (g.nrows - 0.5) * g.d];
  } else if (model.draw?.kind === 'contours') {
    const pts = model.draw.lines.flatMap((l) => l.points);
    xr = extent(pts.map((p) => p[0]));
    yr = extent(pts.map((p) => p[1]));
  } else {
    // The inclined plane: along the dip 0…L; across, what the supports, the release and the path use, ±2 m.
    const ys = [0, ...supports.map((p) => p.across), release.point?.across, ...pathXY.map((p) => p[1]), ...passedAcross(maps), ...devices.flatMap((d) => d.across ?? [])]
      .filter((v) => v !== null && v !== undefined);
    const [a, b] = extent(ys);
    xr = [0, model.length * Math.cos(model.dip)];
    yr = [Math.min(a, -1) - 2, Math.max(b, 1) + 2];
  }
  // Narrow screens: the colour bars closer together.
  const narrow = cssW < 560;
  const mapLayer = maps ? MAP_LAYERS.find((l) => l.key === layer) ?? null : null;
  // with maps, room for their colour bar whatever the layer: choosing one moves nothing else
  const M = { l: model.map ? 80 : 58, r: (narrow ? 118 : 160) + (maps ? (narrow ? 62 : 84) : 0), t: 14, b: 58 };
  const plotW = cssW - M.l - M.r;
  const sx = plotW / (xr[1] - xr[0] || 1);
  // Equal scales unless the floor is a thin strip: then across is stretched, and said so.
  let ex = 1;
  let plotH = (yr[1] - yr[0]) * sx;
  if (plotH < 150) { ex = 150 / plotH; plotH = 150; }
  if (plotH > 520) plotH = 520;
  const sy = plotH / (yr[1] - yr[0] || 1);
  const cssH = Math.round(plotH + M.t + M.b);
  const dpr = window.devicePixelRatio || 1;
  canvas.width = Math.round(cssW * dpr);
  canvas.height = Math.round(cssH * dpr);
  canvas.style.width = `${cssW}px`;
  canvas.style.height = `${cssH}px`;
  const ctx = canvas.getContext('2d');
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, cssW, cssH);
  const px = (x) => M.l + (x - xr[0]) * sx;
  const py = (y) => M.t + plotH - (y - yr[0]) * sy;
  ctx.save();
  ctx.beginPath();
  ctx.rect(M.l, M.t, plotW, plotH);
  ctx.clip();
  ctx.fillStyle = '#eef1f5';
  ctx.fillRect(M.l, M.t, plotW, plotH);
  // The floor, coloured by elevation.
  let zr;
  if (model.draw?.kind === 'grid') {
    const g = model.draw;
    zr = extent(g.z.flat());
    // At most about one drawn cell per pixel: a big grid is drawn every k-th node.
    const k = Math.max(1, Math.floor(1 / Math.max(g.d * sx, 1e-9)));
    for (let r = 0; r < g.nrows; r += k) {
      for (let c = 0; c < g.ncols; c += k) {
        const v = g.z[r][c];
        if (v === null) continue;
        const east = (g.z[r][Math.min(c + 1, g.ncols - 1)] ?? v) - (g.z[r][Math.max(c - 1, 0)] ?? v);
        const north = (g.z[Math.max(r - 1, 0)][c] ?? v) - (g.z[Math.min(r + 1, g.nrows - 1)][c] ?? v);
        const gx = east / (2 * g.d);
        const gy = north / (2 * g.d);
        const shade = Math.min(1, Math.max(0, (1 + (gx - gy) * -0.7071) / Math.sqrt(1 + gx * gx + gy * gy)));
        const t = zr[1] > zr[0] ? (v - zr[0]) / (zr[1] - zr[0]) : 0.5;
        ctx.fillStyle = `hsl(${120 - 90 * t}, 38%, ${Math.round(30 + 26 * shade)}%)`;
        const x = g.x0 + c * g.d;
        const y = g.y0 + (g.nrows - 1 - r) * g.d;
        ctx.fillRect(px(x - (k * g.d) / 2), py(y + (k * g.d) / 2), k * g.d * sx + 0.6, k * g.d * sy + 0.6);
      }
    }
  } else if (model.draw?.kind === 'contours') {
    zr = extent(model.draw.lines.map((l) => l.z));
    ctx.lineWidth = 1.5;
    for (const l of model.draw.lines) {
      const t = zr[1] > zr[0] ? (l.z - zr[0]) / (zr[1] - zr[0]) : 0.5;
      ctx.strokeStyle = ELEV(t);
      ctx.beginPath();
      l.points.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
      ctx.stroke();
    }
  } else {
    zr = [model.height(xr[1]), model.height(xr[0])];
    const grad = ctx.createLinearGradient(px(xr[0]), 0, px(xr[1]), 0);
    grad.addColorStop(0, ELEV(1));
    grad.addColorStop(1, ELEV(0));
    ctx.fillStyle = grad;
    ctx.fillRect(px(xr[0]), M.t, (xr[1] - xr[0]) * sx, plotH);
  }
  // The floor's material zones over the relief: a colour per code, the outside code first.
  if (zones) {
    ctx.globalAlpha = 0.38;
    ctx.fillStyle = zones.colour(zones.outside);
    ctx.fillRect(px(xr[0]), M.t, (xr[1] - xr[0]) * sx, plotH);
    const g = zones.grid;
    if (g) {
      for (let r = 0; r < g.nrows; r++) {
        for (let c = 0; c < g.ncols; c++) {
          const v = g.z[r][c];
          if (v === null) continue;
          ctx.fillStyle = zones.colour(v);
          const x = g.x0 + c * g.d;
          const y = g.y0 + (g.nrows - 1 - r) * g.d;
          ctx.fillRect(px(x - g.d / 2), py(y + g.d / 2), g.d * sx + 0.6, g.d * sy + 0.6);
        }
      }
    }
    for (const p of zones.polygons) {
      ctx.fillStyle = zones.colour(p.code);
      ctx.beginPath();
      p.points_m.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
      ctx.closePath();
      ctx.fill();
    }
    ctx.globalAlpha = 1;
    ctx.lineWidth = 1.5;
    for (const p of zones.polygons) {
      ctx.strokeStyle = zones.colour(p.code);
      ctx.beginPath();
      p.points_m.forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
      ctx.closePath();
      ctx.stroke();
    }
  }
  // The ensemble's map: each cell a run entered, coloured by the layer; the others left clear.
  let mapRange = null;
  let mapCells = 0;
  if (mapLayer) {
    const values = mapValues(maps, mapLayer);
    mapRange = extent(values);
    if (mapLayer.key === 'passages') mapRange = [0, mapRange[1]];
    const span = mapRange[1] - mapRange[0];
    ctx.globalAlpha = 0.85;
    for (let i = 0; i < maps.cells_along_dip; i++) {
      const s0 = maps.along_dip_min_m + i * maps.cell_along_dip_m;
      for (let j = 0; j < maps.cells_across; j++) {
        const v = values[i * maps.cells_across + j];
        if (v === null) continue;
        const y0 = maps.across_min_m + j * maps.cell_across_m;
        const corners = [[s0, y0], [s0 + maps.cell_along_dip_m, y0], [s0 + maps.cell_along_dip_m, y0 + maps.cell_across_m], [s0, y0 + maps.cell_across_m]]
          .map(([a, b]) => model.face2view(a, b));
        ctx.fillStyle = MAPC(span > 0 ? (v - mapRange[0]) / span : 1);
        ctx.beginPath();
        corners.forEach(([x, y], q) => (q ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
        ctx.closePath();
        ctx.fill();
        // a hair of the same colour over the seams between cells
        ctx.strokeStyle = ctx.fillStyle;
        ctx.lineWidth = 0.6;
        ctx.stroke();
        mapCells += 1;
      }
    }
    ctx.globalAlpha = 1;
  }
  // Release zones: bands across the floor between their along-dip limits; a point as a ring.
  ctx.lineWidth = 2;
  for (const z of release.zones ?? []) {
    const a = model.face2view(z.from, yr[0] - 1e3);
    const b = model.face2view(z.to, yr[0] - 1e3);
    const c = model.face2view(z.to, yr[1] + 1e3);
    const d = model.face2view(z.from, yr[1] + 1e3);
    ctx.fillStyle = 'rgba(216,138,28,0.22)';
    ctx.strokeStyle = ZONE;
    ctx.beginPath();
    [a, b, c, d].forEach(([x, y], i) => (i ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
    ctx.closePath();
    ctx.fill();
    ctx.setLineDash([5, 4]);
    ctx.stroke();
    ctx.setLineDash([]);
    const [mx] = model.face2view((z.from + z.to) / 2, 0);
    ctx.fillStyle = '#7a4a08';
    ctx.font = '11px system-ui, sans-serif';
    ctx.textAlign = 'center';
    // the longest label that fits the zone's width (narrow screens: the legend names them all)
    const [x0] = model.face2view(z.from, 0);
    const [x1] = model.face2view(z.to, 0);
    const room = Math.abs(px(x1) - px(x0)) - 4;
    const label = [`release ${fmt(z.from, 3)}–${fmt(z.to, 3)} m${release.zones.length > 1 ? `, weight ${fmt(z.weight, 3)}` : ''}`,
      `release ${fmt(z.from, 3)}–${fmt(z.to, 3)} m`, `${fmt(z.from, 3)}–${fmt(z.to, 3)} m`].find((t) => ctx.measureText(t).width <= room);
    if (label) ctx.fillText(label, px(mx), M.t + 12);
  }
  if (release.point) {
    const [x, y] = model.face2view(release.point.s, release.point.across);
    ctx.strokeStyle = ZONE;
    ctx.lineWidth = 2.5;
    ctx.beginPath();
    ctx.arc(px(x), py(y), 6, 0, 2 * Math.PI);
    ctx.stroke();
  }
  // Supports: columns as dots, spanning supports as lines across.
  for (const p of supports) {
    const v = verdicts.get(`${p.support}.${p.column}`);
    ctx.strokeStyle = ctx.fillStyle = v === 'exceeded' ? SUPPORT_OVER : v === 'ok' ? SUPPORT_OK : SUPPORT_IDLE;
    if (p.across === null || p.across === undefined) {
      const [ax, ay] = model.face2view(p.s, yr[0] - 1e3);
      const [bx, by] = model.face2view(p.s, yr[1] + 1e3);
      ctx.lineWidth = 1.5;
      ctx.beginPath();
      ctx.moveTo(px(ax), py(ay));
      ctx.lineTo(px(bx), py(by));
      ctx.stroke();
    } else {
      const [x, y] = model.face2view(p.s, p.across);
      ctx.beginPath();
      ctx.arc(px(x), py(y), 3.2, 0, 2 * Math.PI);
      ctx.fill();
    }
  }
  // Barriers as solid lines across their range (or the whole face), labelled with height and
  // rating; collectors dashed.
  for (const [k, d] of (hideDevices ? [] : devices).entries()) {
    const [a, b] = d.across ?? [yr[0] - 1e3, yr[1] + 1e3];
    const [ax, ay] = model.face2view(d.s, a);
    const [bx, by] = model.face2view(d.s, b);
    if (d.kind === 'proposed') {
      // a white halo under the dashes: the line stands out on the map and the relief alike
      ctx.strokeStyle = 'rgba(255, 255, 255, 0.9)';
      ctx.lineWidth = 7;
      ctx.setLineDash([]);
      ctx.beginPath();
      ctx.moveTo(px(ax), py(ay));
      ctx.lineTo(px(bx), py(by));
      ctx.stroke();
    }
    ctx.strokeStyle = ctx.fillStyle = deviceColour(d);
    ctx.lineWidth = d.kind === 'collector' ? 2 : 3;
    ctx.setLineDash(d.kind === 'barrier' ? [] : d.kind === 'proposed' ? [10, 5] : [6, 4]);
    ctx.beginPath();
    ctx.moveTo(px(ax), py(ay));
    ctx.lineTo(px(bx), py(by));
    ctx.stroke();
    ctx.setLineDash([]);
    // the labels one row each from the plot's bottom (the release zones are named at the top), beside
    // their line (left of it when the right has no room), on a pale box
    const base = M.t + plotH - 5 - 16 * k;
    ctx.font = '11px system-ui, sans-serif';
    ctx.textAlign = 'left';
    // a narrow plot names the line only (the legend gives its height and rating)
    const full = deviceLabel(d);
    const text = ctx.measureText(full).width <= plotW / 2 ? full : `${d.kind} ${d.index}`;
    const w = ctx.measureText(text).width;
    const lx = (px(ax) + px(bx)) / 2;
    const x = Math.max(M.l + 2, lx + 5 + w <= M.l + plotW ? lx + 5 : lx - 5 - w);
    ctx.fillStyle = 'rgba(255, 255, 255, 0.8)';
    ctx.fillRect(x - 2, base - 11, w + 4, 14);
    ctx.fillStyle = deviceColour(d);
    ctx.fillText(text, x, base);
  }
  // The nominal path, coloured by speed.
  const [v0, v1] = tr ? extent(tr.speed_m_s) : [0, 0];
  if (tr) {
    ctx.lineWidth = 3;
    ctx.lineCap = 'round';
    for (let i = 1; i < pathXY.length; i++) {
      const t = v1 > v0 ? (tr.speed_m_s[i] - v0) / (v1 - v0) : 0.5;
      ctx.strokeStyle = SPEED(t);
      ctx.beginPath();
      ctx.moveTo(px(pathXY[i - 1][0]), py(pathXY[i - 1][1]));
      ctx.lineTo(px(pathXY[i][0]), py(pathXY[i][1]));
      ctx.stroke();
    }
  }
  // Where runs stopped: a cross at the stop (across from the support, else from the nominal path).
  const nominalAcross = (s) => {
    if (!tr?.along_dip_m?.length) return release.point?.across ?? 0;
    let best = 0;
    tr.along_dip_m.forEach((a, i) => { if (Math.abs(a - s) < Math.abs(tr.along_dip_m[best] - s)) best = i; });
    return tr.position_m[best][1];
  };
  ctx.strokeStyle = STOP;
  ctx.lineWidth = 1.2;
  const drawnStops = [];
  for (const st of stops) {
    const s = st.s ?? model.length;
    const [x, y] = model.face2view(s, st.across ?? nominalAcross(s));
    drawnStops.push([x, y]);
    ctx.beginPath();
    ctx.moveTo(px(x) - 3, py(y) - 3); ctx.lineTo(px(x) + 3, py(y) + 3);
    ctx.moveTo(px(x) + 3, py(y) - 3); ctx.lineTo(px(x) - 3, py(y) + 3);
    ctx.stroke();
  }
  ctx.restore();

  // Axes in metres.
  ctx.strokeStyle = '#3b4350';
  ctx.lineWidth = 1;
  ctx.strokeRect(M.l, M.t, plotW, plotH);
  ctx.fillStyle = '#1c2430';
  ctx.font = '11px system-ui, sans-serif';
  ctx.textAlign = 'center';
  const xTicks = ticks(xr[0], xr[1], Math.max(3, Math.floor(plotW / 90)));
  canvas.dataset.xticks = xTicks.map(tickText).join(' ');
  for (const v of xTicks) {
    ctx.beginPath(); ctx.moveTo(px(v), M.t + plotH); ctx.lineTo(px(v), M.t + plotH + 4); ctx.stroke();
    ctx.fillText(tickText(v), px(v), M.t + plotH + 15);
  }
  ctx.textAlign = 'right';
  for (const v of ticks(yr[0], yr[1], Math.max(2, Math.floor(plotH / 45)))) {
    ctx.beginPath(); ctx.moveTo(M.l - 4, py(v)); ctx.lineTo(M.l, py(v)); ctx.stroke();
    ctx.fillText(tickText(v), M.l - 6, py(v) + 4);
  }
  const xName = model.map ? 'easting (m)' : model.uploaded ? 'x of the file (m)' : 'x, horizontal down the dip (m)';
  const yName = model.map ? 'northing (m)' : model.uploaded ? 'y of the file (m)' : `y, across (m)${ex > 1.05 ? `, stretched ×${fmt(ex, 2)}` : ''}`;
  ctx.textAlign = 'center';
  ctx.fillText(xName, M.l + plotW / 2, M.t + plotH + 30);
  ctx.save();
  ctx.translate(14, M.t + plotH / 2);
  ctx.rotate(-Math.PI / 2);
  ctx.fillText(yName, 0, 0);
  ctx.restore();
  // Scale bar (along x) under the axis label.
  const barM = niceStep((xr[1] - xr[0]) / 5);
  const bx = M.l;
  const by = M.t + plotH + 46;
  ctx.fillStyle = '#1c2430';
  ctx.fillRect(bx, by - 3, barM * sx / 2, 4);
  ctx.strokeRect(bx + barM * sx / 2, by - 3, barM * sx / 2, 4);
  ctx.textAlign = 'left';
  ctx.fillText(`${fmt(barM, 3)} m`, bx + barM * sx + 6, by + 2);
  if (model.map || model.uploaded) {
    ctx.fillText('N ↑', M.l + plotW - 26, M.t + 14);
  }
  // Colour bars: elevation, and speed along the path.
  colourBar(ctx, cssW - M.r + (narrow ? 12 : 16), M.t, plotH, zr, ELEV, narrow ? 'z (m)' : 'elevation (m)');
  if (tr) colourBar(ctx, cssW - M.r + (narrow ? 66 : 92), M.t, plotH, [v0, v1], SPEED, narrow ? 'v (m/s)' : 'speed (m/s)');
  if (mapLayer && mapRange) {
    colourBar(ctx, cssW - M.r + (narrow ? 120 : 168), M.t, plotH, mapRange, MAPC, narrow ? mapLayer.short : `${mapLayer.label} (${mapLayer.unit})`.replace('kinetic energy', 'energy'));
  }
  canvas.dataset.mapLayer = mapLayer ? mapLayer.key : 'none';
  canvas.dataset.mapCells = String(mapCells);
  // where a face point (s along the dip, y across) is drawn, in CSS pixels of the canvas
  canvas.facePixel = (a, b) => { const [x, y] = model.face2view(a, b); return [px(x), py(y)]; };
  canvas.plotRect = { l: M.l, t: M.t, w: plotW, h: plotH };
  canvas.dataset.exaggeration = String(ex);
  canvas.dataset.stops = String(drawnStops.length);
  return { xr, yr, zr, speed: [v0, v1], stops: drawnStops.length, ex, map: mapLayer ? { layer: mapLayer, range: mapRange, cells: mapCells } : null };
}

function colourBar(ctx, x, y, hgt, [lo, hi], colour, label) {
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) return;
  const w = 12;
  const top = y + 14;
  const hh = Math.max(40, hgt - 18);
  for (let i = 0; i < hh; i++) {
    ctx.fillStyle = colour(1 - i / hh);
    ctx.fillRect(x, top + i, w, 1.5);
  }
  ctx.strokeStyle = '#3b4350';
  ctx.strokeRect(x, top, w, hh);
  ctx.fillStyle = '#1c2430';
  ctx.textAlign = 'left';
  ctx.font = '10px system-ui, sans-serif';
  ctx.fillText(label, x - 8, y + 6);
  const span = hi - lo || 1;
  for (const v of ticks(lo, hi === lo ? lo + 1 : hi, 4)) {
    const ty = top + hh - ((v - lo) / span) * hh;
    if (ty < top - 1 || ty > top + hh + 1) continue;
    ctx.fillText(tickText(v), x + w + 3, ty + 3);
  }
  ctx.font = '11px system-ui, sans-serif';
}

function niceStep(raw) {
  const p = 10 ** Math.floor(Math.log10(raw || 1));
  return [1, 2, 2.5, 5, 10].map((m) => m * p).find((m) => m >= raw) ?? 10 * p;
}

/** Round values between lo and hi, about n of them; each carries the decimals its step needs. */
function ticks(lo, hi, n) {
  if (!(hi > lo)) return [lo];
  const step = niceStep((hi - lo) / n);
  const decimals = Math.max(0, -Math.floor(Math.log10(step) + 1e-9) + (String(step).includes('.5') ? 1 : 0));
  const out = [];
  for (let k = Math.ceil(lo / step); k * step <= hi + step * 1e-9; k++) {
    const v = new Number(k === 0 ? 0 : k * step);
    v.decimals = decimals;
    out.push(v);
  }
  return out;
}

/** A tick's text: every digit of a map coordinate (500010, not 5.00e+5), the decimals of its step. */
function tickText(v) {
  const d = v.decimals ?? (Math.abs(v) >= 100 ? 0 : 3);
  return Number(v).toFixed(d).replace(/^-0(\.0*)?$/, '0');
}

/**
 * The profile along the path, a vertical section: against the horizontal distance down the
 * dip from the face's origin, the floor's elevation directly under the rock (plane: exact;
 * grid: bilinear in the file's heights; contours: the rock's elevation less its height above
 * the floor, an approximation) and the rock's elevation.
 */
export function profileSeries(model, tr) {
  const xy = tr.position_m.map(model.path);
  const floorZ = tr.position_m.map((p, i) => {
    if (model.height) return model.height(xy[i][0], xy[i][1]);
    return p[2] - tr.height_m[i] / Math.cos(model.dip);
  });
  // Face x (down the dip, horizontal): positions come in face coordinates with a map, else in the file's frame.
  const fx = tr.position_m.map((p) => (model.map ? p[0] : p[0] - model.x0));
  const idx = fx.map((_, i) => i).sort((i, j) => fx[i] - fx[j] || i - j);
  const out = { x: [], floor: [], rock: [] };
  for (const i of idx) {
    if (out.x.length && out.x[out.x.length - 1] === fx[i]) {
      out.rock[out.rock.length - 1] = tr.position_m[i][2];
      continue;
    }
    out.x.push(fx[i]);
    out.floor.push(floorZ[i]);
    out.rock.push(tr.position_m[i][2]);
  }
  return out;
}

/** Draws the profile into `el`; `extra`: more paths [{label, tr}] (both methods). */
export function drawProfile(el, model, tr, { stops = [], supports = [], verdicts = new Map(), extra = [], floorLabel = 'floor' } = {}) {
  const main = profileSeries(model, tr);
  const cos = Math.cos(model.dip);
  const tables = [[main.x, main.floor], [main.x, main.rock]];
  const more = extra.filter((e) => e.tr).map((e) => ({ ...e, p: profileSeries(model, e.tr) }));
  for (const m of more) tables.push([m.p.x, m.p.rock]);
  // Stops on the floor line, at their horizontal distance (s·cos θ).
  const floorAt = (x) => {
    let best = 0;
    main.x.forEach((a, i) => { if (Math.abs(a - x) < Math.abs(main.x[best] - x)) best = i; });
    return main.floor[best];
  };
  const stopX = [...new Set(stops.map((st) => (st.s ?? model.length) * cos))].sort((a, b) => a - b);
  if (stopX.length) tables.push([stopX, stopX.map(floorAt)]);
  const joined = joinSeries(tables);
  let k = 1;
  const series = [
    { label: floorLabel, values: joined[k++], color: '#6b5a3a', width: 2.5 },
    { label: 'the rock (nominal run)', values: joined[k++], color: '#1d5fa8' },
    ...more.map((m) => ({ label: m.label, values: joined[k++], color: m.color ?? '#c8423b' })),
  ];
  if (stopX.length) series.push({ label: 'where runs stopped', values: joined[k++], points: 'only', color: STOP, pointSize: 6 });
  linePlot(el, {
    x: { label: 'horizontal distance down the dip (m)', values: joined[0] },
    y: { label: 'elevation (m)' },
    series,
    vlines: supports.map((p) => {
      const v = verdicts.get(`${p.support}.${p.column}`);
      return { x: p.s * cos, color: v === 'exceeded' ? SUPPORT_OVER : v === 'ok' ? '#a9d8b8' : '#c9d0da' };
    }),
    height: 260,
  });
  el.csv = () => [['horizontal_down_dip_m', 'floor_elevation_m', 'rock_elevation_m'], ...main.x.map((x, i) => [x, main.floor[i] ?? '', main.rock[i]])];
  return main;
}

/** True when this browser can draw WebGL. */
export function webglAvailable() {
  try {
    const c = document.createElement('canvas');
    return Boolean(c.getContext('webgl2') || c.getContext('webgl'));
  } catch {
    return false;
  }
}

const views3d = new WeakMap();

/**
 * The 3-D view in `box`: the floor surface, the supports, the release and the path; orbit
 * (drag), zoom (wheel), reset (button). Resolves to true when drawn, false when WebGL is missing.
 */
export async function draw3d(box, model, { supports = [], release = {}, tr = null, stops = [], verdicts = new Map(), devices = [], zones = null } = {}) {
  views3d.get(box)?.dispose();
  views3d.delete(box);
  box.replaceChildren();
  if (!webglAvailable()) {
    box.dataset.webgl = 'missing';
    box.append(h('p', { class: 'placeholder' }, 'This browser has no WebGL, so there is no 3-D view: the plan and the profile above show the same floor, supports and path.'));
    return false;
  }
  let THREE; let OrbitControls;
  try {
    THREE = await import('../vendor/three/three.module.js');
    ({ OrbitControls } = await import('../vendor/three/OrbitControls.js'));
  } catch (err) {
    box.dataset.webgl = 'missing';
    box.append(h('p', { class: 'placeholder' }, `The 3-D view could not be loaded (${err.message}): the plan and the profile show the same.`));
    return false;
  }
  const width = Math.max(280, box.clientWidth || 600);
  const height = Math.round(Math.min(480, Math.max(260, width * 0.55)));
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch {
    box.dataset.webgl = 'missing';
    box.append(h('p', { class: 'placeholder' }, 'WebGL could not start here, so there is no 3-D view: the plan and the profile above show the same.'));
    return false;
  }
  box.dataset.webgl = 'ok';
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  renderer.setClearColor(0xf4f6f9);
  const scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(-1, 1, 2);
  scene.add(sun);

  // Points in the view frame, centred on the floor (large map coordinates lose float precision).
  const pts = [];
  // a floor of several materials: each vertex's colour half its zone's
  const zc = new THREE.Color();
  const tint = (c3, x, y) => {
    if (!zones) return;
    zc.setStyle(zones.colour(zones.codeAt(x, y)));
    c3.lerp(zc, 0.5);
  };
  const surfaceZ = (x, y) => model.markHeight(x, y);
  let centre = [0, 0, 0];
  const V = (x, y, z) => new THREE.Vector3(x - centre[0], y - centre[1], z - centre[2]);
  if (model.draw?.kind === 'grid') {
    const g = model.draw;
    centre = [g.x0 + (g.ncols - 1) * g.d / 2, g.y0 + (g.nrows - 1) * g.d / 2, 0];
    const k = Math.max(1, Math.ceil(Math.max(g.ncols, g.nrows) / 240));
    const cols = Math.floor((g.ncols - 1) / k) + 1;
    const rows = Math.floor((g.nrows - 1) / k) + 1;
    const [zlo, zhi] = extent(g.z.flat());
    centre[2] = (zlo + zhi) / 2;
    const pos = new Float32Array(cols * rows * 3);
    const col = new Float32Array(cols * rows * 3);
    const c3 = new THREE.Color();
    const holes = new Uint8Array(cols * rows);
    for (let r = 0; r < rows; r++) {
      for (let c = 0; c < cols; c++) {
        const z = g.z[r * k][c * k];
        const i = r * cols + c;
        const x = g.x0 + c * k * g.d;
        const y = g.y0 + (g.nrows - 1 - r * k) * g.d;
        pos.set([x - centre[0], y - centre[1], (z ?? zlo) - centre[2]], i * 3);
        holes[i] = z === null ? 1 : 0;
        c3.setStyle(ELEV(zhi > zlo ? ((z ?? zlo) - zlo) / (zhi - zlo) : 0.5));
        tint(c3, x, y);
        col.set([c3.r, c3.g, c3.b], i * 3);
      }
    }
    const index = [];
    for (let r = 0; r + 1 < rows; r++) {
      for (let c = 0; c + 1 < cols; c++) {
        const a = r * cols + c; const b = a + 1; const d = a + cols; const e = d + 1;
        if (!holes[a] && !holes[b] && !holes[d]) index.push(a, d, b);
        if (!holes[b] && !holes[d] && !holes[e]) index.push(b, d, e);
      }
    }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
    geo.setIndex(index);
    geo.computeVertexNormals();
    scene.add(new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide })));
    box.dataset.surface = `grid: ${cols} × ${rows} nodes`;
    pts.push([g.x0, g.y0], [g.x0 + (g.ncols - 1) * g.d, g.y0 + (g.nrows - 1) * g.d]);
  } else if (model.draw?.kind === 'contours') {
    const all = model.draw.lines.flatMap((l) => l.points);
    const [xa, xb] = extent(all.map((p) => p[0]));
    const [ya, yb] = extent(all.map((p) => p[1]));
    const [zlo, zhi] = extent(model.draw.lines.map((l) => l.z));
    centre = [(xa + xb) / 2, (ya + yb) / 2, (zlo + zhi) / 2];
    // The floor surface between the lines: a 60 × 40 mesh at the heights the marks use (the two
    // nearest lines weighted by distance), coloured by elevation; the lines drawn on it.
    const [nx, ny] = [60, 40];
    const pos = new Float32Array(nx * ny * 3);
    const col = new Float32Array(nx * ny * 3);
    const c3 = new THREE.Color();
    for (let r = 0; r < ny; r++) {
      for (let c = 0; c < nx; c++) {
        const x = xa + (xb - xa) * c / (nx - 1);
        const y = ya + (yb - ya) * r / (ny - 1);
        const z = contourHeight(model.draw.lines, x, y) ?? zlo;
        const i = r * nx + c;
        pos.set([x - centre[0], y - centre[1], z - centre[2]], i * 3);
        c3.setStyle(ELEV(zhi > zlo ? (z - zlo) / (zhi - zlo) : 0.5));
        tint(c3, x, y);
        col.set([c3.r, c3.g, c3.b], i * 3);
      }
    }
    const index = [];
    for (let r = 0; r + 1 < ny; r++) {
      for (let c = 0; c + 1 < nx; c++) {
        const a = r * nx + c;
        index.push(a, a + nx, a + 1, a + 1, a + nx, a + nx + 1);
      }
    }
    const surface = new THREE.BufferGeometry();
    surface.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    surface.setAttribute('color', new THREE.BufferAttribute(col, 3));
    surface.setIndex(index);
    surface.computeVertexNormals();
    const mesh = new THREE.Mesh(surface, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
    mesh.name = 'contour-surface';
    scene.add(mesh);
    box.dataset.surface = `contours: ${nx} × ${ny} mesh between ${model.draw.lines.length} lines`;
    for (const l of model.draw.lines) {
      const geo = new THREE.BufferGeometry().setFromPoints(l.points.map(([x, y]) => V(x, y, l.z)));
      scene.add(new THREE.Line(geo, new THREE.LineBasicMaterial({ color: new THREE.Color().setStyle(ELEV(zhi > zlo ? (l.z - zlo) / (zhi - zlo) : 0.5)) })));
    }
    pts.push([xa, ya], [xb, yb]);
  } else {
    const ys = [0, ...supports.map((p) => p.across), release.point?.across].filter((v) => v !== null && v !== undefined);
    const [a, b] = extent(ys);
    // the plane as a strip at least 20 m wide, so that its slope can be seen
    const y0 = Math.min(a - 2, -10);
    const y1 = Math.max(b + 2, 10);
    const x1 = model.length * Math.cos(model.dip);
    centre = [x1 / 2, (y0 + y1) / 2, model.height(x1 / 2)];
    if (zones) {
      // the plane as a fine mesh coloured by zone
      const [nx, ny] = [160, 60];
      const pos = new Float32Array(nx * ny * 3);
      const col = new Float32Array(nx * ny * 3);
      const c3 = new THREE.Color();
      for (let r = 0; r < ny; r++) {
        for (let c = 0; c < nx; c++) {
          const x = (x1 * c) / (nx - 1);
          const y = y0 + ((y1 - y0) * r) / (ny - 1);
          const i = r * nx + c;
          pos.set([x - centre[0], y - centre[1], model.height(x) - centre[2]], i * 3);
          c3.set(0x9fb58a);
          tint(c3, x, y);
          col.set([c3.r, c3.g, c3.b], i * 3);
        }
      }
      const index = [];
      for (let r = 0; r + 1 < ny; r++) {
        for (let c = 0; c + 1 < nx; c++) {
          const a = r * nx + c;
          index.push(a, a + 1, a + nx, a + 1, a + nx + 1, a + nx);
        }
      }
      const geo = new THREE.BufferGeometry();
      geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
      geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
      geo.setIndex(index);
      geo.computeVertexNormals();
      scene.add(new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide })));
      box.dataset.zones = String(zones.codes.length);
    } else {
      const geo = new THREE.BufferGeometry().setFromPoints([V(0, y0, 0), V(x1, y0, model.height(x1)), V(x1, y1, model.height(x1)), V(0, y1, 0)]);
      geo.setIndex([0, 1, 2, 0, 2, 3]);
      geo.computeVertexNormals();
      scene.add(new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ color: 0x9fb58a, side: THREE.DoubleSide })));
    }
    pts.push([0, y0], [x1, y1]);
  }
  const floorZ = (x, y, fallback) => surfaceZ(x, y) ?? fallback;
  // Supports: a column 2 m high (a spanning support as a bar across the floor).
  for (const p of supports) {
    const v = verdicts.get(`${p.support}.${p.column}`);
    const colour = v === 'exceeded' ? SUPPORT_OVER : v === 'ok' ? SUPPORT_OK : SUPPORT_IDLE;
    const [x, y] = model.face2view(p.s, p.across ?? 0);
    const z = floorZ(x, y, centre[2]);
    if (p.across === null || p.across === undefined) {
      const [ax, ay] = model.face2view(p.s, -3);
      const [bx, by] = model.face2view(p.s, 3);
      const geo = new THREE.BufferGeometry().setFromPoints([V(ax, ay, z + 1), V(bx, by, z + 1)]);
      scene.add(new THREE.Line(geo, new THREE.LineBasicMaterial({ color: colour })));
    } else {
      const cyl = new THREE.Mesh(new THREE.CylinderGeometry(0.15, 0.15, 2.2, 10), new THREE.MeshLambertMaterial({ color: colour }));
      cyl.rotation.x = Math.PI / 2;
      cyl.position.copy(V(x, y, z + 1.1));
      scene.add(cyl);
    }
  }
  // Barriers as fences of their height across their range (the whole face: the drawn strip),
  // collectors as dashed lines on the floor.
  const built = devices.filter((d) => d.kind !== 'proposed');
  for (const d of built) {
    const [a, b] = d.across ?? [-10, 10];
    const n = 24;
    const foot = Array.from({ length: n + 1 }, (_, k) => {
      const [x, y] = model.face2view(d.s, a + ((b - a) * k) / n);
      return [x, y, floorZ(x, y, centre[2])];
    });
    const colour = d.kind === 'barrier' ? BARRIER : COLLECTOR;
    if (d.kind === 'barrier') {
      const pos = new Float32Array(foot.length * 6);
      foot.forEach(([x, y, z], k) => pos.set([x, y, z, x, y, z + d.height], k * 6));
      const index = [];
      for (let k = 0; k < n; k++) index.push(2 * k, 2 * k + 2, 2 * k + 1, 2 * k + 1, 2 * k + 2, 2 * k + 3);
      const geo = new THREE.BufferGeometry();
      geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
      geo.setIndex(index);
      geo.computeVertexNormals();
      const fence = new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ color: colour, side: THREE.DoubleSide, transparent: true, opacity: 0.75 }));
      fence.name = `barrier ${d.index}`;
      scene.add(fence);
    } else {
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(foot.map(([x, y, z]) => V(x, y, z + 0.05))),
        new THREE.LineDashedMaterial({ color: colour, dashSize: 0.6, gapSize: 0.4 }));
      line.computeLineDistances();
      line.name = `collector ${d.index}`;
      scene.add(line);
    }
  }
  box.dataset.devices = built.map((d) => `${d.kind} ${d.index}`).join(',');
  // Release zones: their limits as orange lines across; a point as an orange ball.
  for (const zn of release.zones ?? []) {
    for (const s of [zn.from, zn.to]) {
      const line = [-4, -2, 0, 2, 4].map((y) => { const [x, yy] = model.face2view(s, y); return V(x, yy, floorZ(x, yy, centre[2]) + 0.05); });
      scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(line), new THREE.LineBasicMaterial({ color: ZONE })));
    }
  }
  if (release.point) {
    const [x, y] = model.face2view(release.point.s, release.point.across);
    const ball = new THREE.Mesh(new THREE.SphereGeometry(0.35, 12, 8), new THREE.MeshLambertMaterial({ color: ZONE }));
    ball.name = 'release';
    ball.position.copy(V(x, y, floorZ(x, y, centre[2]) + (release.point.drop ?? 0)));
    scene.add(ball);
  }
  // Marks scale with the scene (a 0.3 m rock on a 120 m face would be a dot).
  const floorBox = new THREE.Box3().setFromObject(scene).getBoundingSphere(new THREE.Sphere());
  const mark = Math.max(0.2, floorBox.radius * 0.006);
  if (tr) {
    const [v0, v1] = extent(tr.speed_m_s);
    // The path as a tube coloured by speed (WebGL draws lines one pixel wide).
    const step = Math.max(1, Math.ceil(tr.position_m.length / 400));
    const keep = tr.position_m.map((_, i) => i).filter((i) => i % step === 0 || i === tr.position_m.length - 1);
    const positions = keep.map((i) => { const p = tr.position_m[i]; const [x, y] = model.path(p); return V(x, y, p[2]); });
    if (positions.length > 1) {
      const curve = new THREE.CatmullRomCurve3(positions, false, 'centripetal');
      const segments = positions.length * 2;
      const radial = 6;
      const geo = new THREE.TubeGeometry(curve, segments, mark, radial, false);
      const c3 = new THREE.Color();
      const count = geo.attributes.position.count;
      const col = new Float32Array(count * 3);
      for (let k = 0; k < count; k++) {
        const ring = Math.min(segments, Math.floor(k / (radial + 1)));
        const v = tr.speed_m_s[keep[Math.min(keep.length - 1, Math.round((ring / segments) * (keep.length - 1)))]];
        c3.setStyle(SPEED(v1 > v0 ? (v - v0) / (v1 - v0) : 0.5));
        col.set([c3.r, c3.g, c3.b], k * 3);
      }
      geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
      scene.add(new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ vertexColors: true })));
    }
  }
  if (stops.length) {
    const where = stops.map((st) => {
      const s = st.s ?? model.length;
      const [x, y] = model.face2view(s, st.across ?? (tr ? nearestAcross(tr, s) : 0));
      return V(x, y, floorZ(x, y, centre[2]) + 0.1);
    });
    scene.add(new THREE.Points(new THREE.BufferGeometry().setFromPoints(where), new THREE.PointsMaterial({ color: 0x1c2430, size: 4, sizeAttenuation: false })));
  }
  const ball = scene.getObjectByName('release');
  if (ball) ball.scale.setScalar(Math.max(1, (mark * 3) / 0.35));
  // The camera frames everything drawn: from the south-west, above, at the distance that fits its bounding sphere.
  const sphere = new THREE.Box3().setFromObject(scene).getBoundingSphere(new THREE.Sphere());
  const span = Math.max(sphere.radius, 5);
  const camera = new THREE.PerspectiveCamera(40, width / height, span / 1000, span * 40);
  camera.up.set(0, 0, 1);
  const fit = span / Math.sin((20 * Math.PI) / 180) / Math.min(1, width / height) * 0.9;
  const dir = new THREE.Vector3(0.25, -0.85, 0.47).normalize();
  camera.position.copy(sphere.center).addScaledVector(dir, fit);
  camera.lookAt(sphere.center);
  renderer.domElement.setAttribute('role', 'img');
  renderer.domElement.setAttribute('aria-label', `3-D view of the ${model.uploaded ? `uploaded floor ${model.name}` : 'plane floor'}: drag to turn, wheel to zoom`);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(sphere.center);
  controls.update();
  controls.saveState();
  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  render();
  const reset = h('button', { type: 'button', class: 'chip', dataset: { action: 'reset-3d' } }, 'Reset the view');
  reset.addEventListener('click', () => { controls.reset(); render(); });
  box.append(renderer.domElement, h('p', { class: 'note' }, 'Drag to turn, wheel or pinch to zoom, right-drag to pan. ', reset));
  views3d.set(box, {
    dispose: () => { controls.dispose(); renderer.dispose(); renderer.forceContextLoss?.(); },
    camera, controls, render,
  });
  box.view3d = views3d.get(box);
  return true;
}

function nearestAcross(tr, s) {
  let best = 0;
  tr.along_dip_m.forEach((a, i) => { if (Math.abs(a - s) < Math.abs(tr.along_dip_m[best] - s)) best = i; });
  return tr.position_m[best][1];
}

/** A legend in HTML under the plan: what each mark is (no "--" anywhere). */
export function planLegend(drawn, { model, supports, release, tr, stops, unplaced, verdicts, maps = null, devices = [], zones = null }) {
  const items = [];
  const sw = (colour, shape = 'line') => h('span', { class: `swatch ${shape}`, style: `--c:${colour}` });
  if (zones) {
    for (const c of zones.codes) {
      const name = zones.names.get(c);
      items.push(h('li', { dataset: { out: 'zone' } }, sw(zones.colour(c), 'box'), `zone ${c}${name ? `, ${name}` : ''}${c === zones.outside ? ' (and everywhere no zone is drawn)' : ''}`));
    }
  }
  items.push(h('li', {}, sw('#9fb58a', 'box'), model.uploaded
    ? `floor: uploaded ${model.kind === 'grid' ? 'grid' : 'contours'} ${model.name}${model.sha256 ? ` (sha256 ${model.sha256.slice(0, 12)}…)` : ''}, coloured by elevation ${fmt(drawn.zr[0], 4)} to ${fmt(drawn.zr[1], 4)} m`
    : `floor: the plane of the face (dip ${fmt(model.dip * 180 / Math.PI, 4)}°, ${fmt(model.length, 4)} m along the dip), coloured by elevation`));
  if (supports.length) {
    const over = [...verdicts.values()].filter((v) => v === 'exceeded').length;
    items.push(h('li', {}, sw(SUPPORT_OVER, 'dot'), sw(SUPPORT_OK, 'dot'), `${supports.length} support column${supports.length === 1 ? '' : 's'} where they stand${verdicts.size ? ` (red: exceeded, ${over}; green: within)` : ''}`));
  }
  const barriers = devices.filter((d) => d.kind === 'barrier');
  const collectors = devices.filter((d) => d.kind === 'collector');
  const proposed = devices.filter((d) => d.kind === 'proposed');
  const span = (d) => (d.across ? `${fmt(d.across[0], 4)} to ${fmt(d.across[1], 4)} m across` : 'the whole face');
  if (barriers.length) {
    items.push(h('li', { dataset: { out: 'barriers' } }, sw(BARRIER), `${barriers.length} barrier${barriers.length === 1 ? '' : 's'} as solid lines: `
      + barriers.map((d) => `at ${fmt(d.s, 4)} m along the dip over ${span(d)}, ${fmt(d.height, 3)} m high, rated ${fmt(d.rating / 1e3, 4)} kJ`).join('; ')));
  }
  if (collectors.length) {
    items.push(h('li', { dataset: { out: 'collectors' } }, sw(COLLECTOR, 'dash'), `${collectors.length} collector${collectors.length === 1 ? '' : 's'} as dashed lines: `
      + collectors.map((d) => `at ${fmt(d.s, 4)} m along the dip over ${span(d)}`).join('; ')));
  }
  if (proposed.length) {
    items.push(h('li', { dataset: { out: 'proposed' } }, sw(PROPOSED, 'dash'), `${proposed.length} barrier${proposed.length === 1 ? '' : 's'} the design search proposes, not yet applied, as teal long-dashed lines on a white halo: `
      + proposed.map((d) => `at ${fmt(d.s, 4)} m along the dip in front of support ${d.support}, ${fmt(d.height, 3)} m high, rated ${fmt(d.rating / 1e3, 4)} kJ`).join('; ')));
  }
  if (release.zones?.length) items.push(h('li', {}, sw(ZONE, 'box'), `release zones${release.table1 ? ' (Table 1 thirds)' : ''}: ${release.zones.map((z) => `${fmt(z.from, 4)}–${fmt(z.to, 4)} m`).join(', ')}`));
  if (release.point) items.push(h('li', {}, sw(ZONE, 'ring'), `release point at ${fmt(release.point.s, 4)} m along the dip, ${fmt(release.point.across, 4)} m across`));
  if (tr) items.push(h('li', {}, sw(SPEED(0.8)), `nominal path coloured by speed, ${fmt(drawn.speed[0], 3)} to ${fmt(drawn.speed[1], 3)} m/s`));
  if (stops.length || unplaced) {
    items.push(h('li', {}, sw(STOP, 'cross'), `${stops.length} run${stops.length === 1 ? '' : 's'} stopped where marked (along the dip from the runs' table; across from the support struck, else from the nominal path)`
      + (unplaced ? `; ${unplaced} run${unplaced === 1 ? '' : 's'} not placed (the response does not say where they came to rest)` : '')));
  }
  if (drawn.map) {
    const { layer, range, cells } = drawn.map;
    const m = maps;
    items.push(h('li', { dataset: { out: 'map' } }, sw(MAPC(0.7), 'box'), `map of the ${m.runs} runs: ${layer.label}${layer.key === 'passages' ? ' (runs whose centre, projected on the face, entered the cell)' : ' of each passing run\'s largest value in the cell'}`
      + `, ${Number.isFinite(range[0]) ? `${fmt(range[0], 3)} to ${fmt(range[1], 3)} ${layer.unit}` : 'no cell reached'}; ${cells} of ${m.cells_along_dip} × ${m.cells_across} cells of ${fmt(m.cell_along_dip_m, 3)} m along the dip × ${fmt(m.cell_across_m, 3)} m across were entered, the others are left clear`));
  }
  if (drawn.ex > 1.05) items.push(h('li', {}, `across the face stretched ×${fmt(drawn.ex, 2)} to be seen; the scale bar is along x`));
  return h('ul', { class: 'floor-legend' }, items);
}

export { destroy };

/** Where a release point lies off the floor, in words, or null when it is on it. */
export function offFloor(model, s, across) {
  if (!(s >= 0 && s <= model.length)) return `${fmt(s, 4)} m along the dip is off the face (0 to ${fmt(model.length, 4)} m)`;
  if (!model.uploaded) return null;
  const [x, y] = model.face2view(s, across);
  if (model.draw.kind === 'grid') {
    return gridHeight(model.draw, x, y) === null ? `(${fmt(s, 4)} m along the dip, ${fmt(across, 4)} m across) is off the uploaded grid or over a hole` : null;
  }
  const pts = model.draw.lines.flatMap((l) => l.points);
  const [xa, xb] = extent(pts.map((p) => p[0]));
  const [ya, yb] = extent(pts.map((p) => p[1]));
  return x < xa || x > xb || y < ya || y > yb ? `(${fmt(s, 4)} m along the dip, ${fmt(across, 4)} m across) is outside the uploaded contours` : null;
}

/**
 * Fills a floor-views block (`<prefix>-floor`): the plan with its legend, the profile and
 * the 3-D view, for a Migration or Scene answer.
 */
export function renderFloorViews(prefix, { inputs, request, upload, tr, runsCsv, arrival = null, verdicts = new Map(), extra = [], maps = null, devices = [] }) {
  const box = document.getElementById(`${prefix}-floor`);
  const model = floorModel(inputs, upload);
  const length = model.length;
  const supports = requestSupports(request, length);
  const release = requestRelease(request, length);
  const placed = stopPositions(runsCsv, release, supports);
  const { unplaced } = placed;
  // One run (no runs' table): where the nominal run ended.
  const stops = placed.stops.length || unplaced || !arrival ? placed.stops : [{ s: arrival.along_dip_m, across: null, reason: arrival.stop_reason }];
  box.hidden = false;
  const canvas = document.getElementById(`${prefix}-floor-plan`);
  const controls = mapControls(prefix, canvas, maps);
  const zones = zonesOf(request);
  const options = { supports, release, tr, stops, verdicts, maps, layer: controls?.value ?? null, devices, zones };
  // what the plan is drawn with (a redraw after changing it draws the change)
  canvas.options = options;
  let drawn = drawPlan(canvas, model, options);
  const floorWords = model.uploaded ? `uploaded floor ${model.name}` : 'plane floor';
  canvas.setAttribute('aria-label', `Plan of the ${floorWords}: ${supports.length} supports, ${devices.length ? `${devices.length} barriers and collectors, ` : ''}${release.zones ? `${release.zones.length} release zones` : 'one release point'}, `
    + `${tr ? `the nominal path (speed ${fmt(drawn.speed[0], 3)} to ${fmt(drawn.speed[1], 3)} m/s), ` : ''}${stops.length} stops marked.`);
  canvas.dataset.floor = model.uploaded ? 'uploaded' : 'plane';
  const legend = document.getElementById(`${prefix}-floor-legend`);
  canvas.redraw = () => {
    drawn = drawPlan(canvas, model, options);
    legend.replaceChildren(planLegend(drawn, { model, supports, release, tr, stops, unplaced, verdicts, maps, devices, zones }));
    return drawn;
  };
  if (controls) {
    controls.onchange = () => {
      options.layer = controls.value;
      canvas.redraw();
    };
  }
  // A new width (a turned phone, a resized window) draws the plan again at that width.
  if (!canvas.resizeWatch) {
    let width = canvas.parentElement.clientWidth;
    canvas.resizeWatch = new ResizeObserver(() => {
      const now = canvas.parentElement.clientWidth;
      if (now > 0 && now !== width && canvas.redraw) { width = now; canvas.redraw(); }
    });
    canvas.resizeWatch.observe(canvas.parentElement);
  }
  canvas.csv = () => [['run_stop_along_dip_m', 'across_m', 'stop_reason'], ...stops.map((s) => [s.s ?? length, s.across ?? '', s.reason ?? ''])];
  legend.replaceChildren(planLegend(drawn, { model, supports, release, tr, stops, unplaced, verdicts, maps, devices, zones }));
  const profile = document.getElementById(`${prefix}-profile-plot`);
  if (tr) {
    drawProfile(profile, model, tr, {
      stops, supports, verdicts, extra,
      floorLabel: model.uploaded ? `floor under the path: ${model.name} (${model.kind === 'grid' ? 'grid, bilinear' : 'contours, rock elevation less its height'})` : 'floor under the path: plane',
    });
  } else {
    destroy(profile);
    profile.append(h('p', { class: 'placeholder' }, 'No path to draw: the trajectory was not asked for (Output), or the migration was skipped.'));
  }
  const box3d = document.getElementById(`${prefix}-3d`);
  return draw3d(box3d, model, options);
}

/**
 * The map controls above a plan (`<prefix>-map-controls`): the layer chooser and the CSV of the
 * chosen layer; hidden without maps. Returns the chooser, or null.
 */
function mapControls(prefix, canvas, maps) {
  const id = `${prefix}-map-controls`;
  let box = document.getElementById(id);
  if (!box) {
    const select = h('select', { id: `${prefix}-map-layer`, 'aria-label': 'Map layer of the ensemble drawn on the floor' },
      h('option', { value: 'none' }, 'none'), ...MAP_LAYERS.map((l) => h('option', { value: l.key }, `${l.label} (${l.unit})`)));
    select.value = 'passages';
    box = h('div', { id, class: 'map-controls' },
      h('label', { for: `${prefix}-map-layer` }, 'Map of the ensemble: '), select,
      csvButton(`${prefix}_map.csv`, () => {
        const m = box.maps;
        if (!m) return [['no map: run an ensemble']];
        return mapCsvRows(m, MAP_LAYERS.find((l) => l.key === select.value) ?? null);
      }, 'CSV: map'));
    canvas.parentElement.before(box);
  }
  box.maps = maps;
  box.hidden = !maps;
  return maps ? box.querySelector('select') : null;
}

/** Hides a floor-views block and lets its 3-D view go. */
export function clearFloorViews(prefix) {
  const box = document.getElementById(`${prefix}-floor`);
  if (!box) return;
  box.hidden = true;
  const box3d = document.getElementById(`${prefix}-3d`);
  views3d.get(box3d)?.dispose();
  views3d.delete(box3d);
  box3d.replaceChildren();
  destroy(document.getElementById(`${prefix}-profile-plot`));
}
