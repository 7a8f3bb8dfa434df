// Thin helpers over uPlot (vendored, global `uPlot`). One plot per element;
// drawing again replaces it; plots follow their container's width.

export const COLORS = ['#1d5fa8', '#c8423b', '#2a8f7f', '#d88a1c', '#6b4c9a', '#555e6b'];

const plots = new Map();
const HEIGHT = 280;

const resizer = new ResizeObserver((entries) => {
  for (const entry of entries) {
    const u = plots.get(entry.target);
    const width = Math.floor(entry.contentRect.width);
    if (u && width > 0 && width !== u.width) u.setSize({ width, height: u.height });
  }
});

/**
 * Draws a line plot into `el`.
 * - `x`: {label, values, range?}
 * - `series`: [{label, values, color?, axis?: 'y'|'y2', points?, width?, dash?, bars?, value?}];
 *   points 'only' draws marks without a line, 'none' nothing (a value shown on hover)
 * - `y`, `y2`: {label, range?}; y2 only when a series uses it.
 * - `vlines`: [{x, color, width?, dash?}] vertical marks across the plot (supports on a face).
 * - `y.log`: a logarithmic y axis (base 10; `y.range` then bounds it).
 * - `x.value(i)`: the x shown on hover for the i-th point; `x.ticks(v)`: a tick's label.
 * - `draw(u)`: drawn over the series (error bars, markers).
 * The x values must be ascending (uPlot's own rule) unless `x.range` is given.
 */
export function linePlot(el, { x, y, y2, series, height = HEIGHT, legend = true, vlines = [], draw = null }) {
  destroy(el);
  const axisStyle = { stroke: '#3b4350', grid: { stroke: '#e3e7ed', width: 1 }, ticks: { stroke: '#c9d0da', width: 1 } };
  // Drag-to-zoom: the selection is turned into a zoom range here (uPlot's own
  // zoom would be undone by a fixed x range); double-click returns to the full range.
  const scales = {
    x: { time: false, range: (u, min, max) => u?.zoom ?? x.range ?? padFlat(min, max) },
    y: { ...(y.range ? { range: () => y.range } : {}), ...(y.log ? { distr: 3, log: 10 } : {}) },
  };
  const axes = [
    { ...axisStyle, label: x.label, ...(x.ticks ? { values: (u, ticks) => ticks.map(x.ticks) } : {}) },
    { ...axisStyle, label: y.label, scale: 'y', size: 64, ...(y.ticks ? { values: (u, ticks) => ticks.map(y.ticks) } : {}) },
  ];
  if (y2) {
    scales.y2 = y2.range ? { range: () => y2.range } : {};
    axes.push({ ...axisStyle, label: y2.label, scale: 'y2', side: 1, size: 64, grid: { show: false } });
  }

  const opts = {
    width: Math.max(el.clientWidth, 240),
    height,
    scales,
    axes,
    legend: { show: legend },
    cursor: { drag: { x: true, y: false, setScale: false } },
    hooks: {
      draw: [(u) => {
        if (draw) draw(u);
        if (!vlines.length) return;
        const { ctx } = u;
        ctx.save();
        ctx.lineWidth = Math.max(1, devicePixelRatio);
        for (const mark of vlines) {
          const px = u.valToPos(mark.x, 'x', true);
          if (px < u.bbox.left || px > u.bbox.left + u.bbox.width) continue;
          ctx.strokeStyle = mark.color ?? '#555e6b';
          ctx.lineWidth = (mark.width ?? 1) * Math.max(1, devicePixelRatio);
          ctx.setLineDash((mark.dash ?? []).map((v) => v * devicePixelRatio));
          ctx.beginPath();
          ctx.moveTo(px, u.bbox.top);
          ctx.lineTo(px, u.bbox.top + u.bbox.height);
          ctx.stroke();
        }
        ctx.restore();
      }],
      setSelect: [(u) => {
        if (u.select.width > 4) {
          const min = u.posToVal(u.select.left, 'x');
          const max = u.posToVal(u.select.left + u.select.width, 'x');
          u.zoom = [min, max];
          u.setScale('x', { min, max });
        }
        u.setSelect({ left: 0, top: 0, width: 0, height: 0 }, false);
      }],
    },
    series: [
      // With no point under the cursor a legend shows nothing (uPlot's default is "--", which reads as a value).
      { label: x.label, value: x.value ? (u, v, si, i) => (i === null || i === undefined ? '' : x.value(i)) : legendValue },
      ...series.map((s, i) => {
        const color = s.color ?? COLORS[i % COLORS.length];
        return {
          label: s.label,
          scale: s.axis ?? 'y',
          stroke: color,
          width: s.width ?? 1.75,
          dash: s.dash,
          spanGaps: true,
          value: s.value ? (u, v, si, i) => (i === null || i === undefined ? '' : s.value(v, i)) : legendValue,
          fill: s.bars ? `${color}55` : undefined,
          paths: s.bars ? uPlot.paths.bars({ size: [0.92, Infinity], align: 0 }) : s.points === 'only' || s.points === 'none' ? () => null : undefined,
          points: s.points === 'only' || s.points === true
            ? { show: true, size: s.pointSize ?? 9, stroke: color, fill: s.pointFill ?? color }
            : { show: false },
        };
      }),
    ],
  };
  const data = [x.values, ...series.map((s) => s.values)];
  const u = new uPlot(opts, data, el);
  // uPlot writes "--" in every legend value until the cursor moves: nothing, rather than a dash that reads as a value.
  for (const v of u.root.querySelectorAll('.u-legend .u-value')) if (v.firstChild && v.textContent === '--') v.firstChild.nodeValue = '';
  // The numbers drawn, as the plot's CSV (a caller may give a better one after this).
  el.csv = () => [[x.label, ...series.map((s) => s.label)], ...x.values.map((v, i) => [v, ...series.map((s) => s.values?.[i] ?? '')])];
  // A text alternative: what is plotted against what, over which ranges (the CSV button gives the numbers).
  el.setAttribute('role', 'img');
  el.setAttribute('aria-label', describe(x, y, series));
  u.root.addEventListener('dblclick', () => { u.zoom = null; }, true);
  el.uplot = u;
  el.title = el.title || 'Drag across to zoom in; double-click to zoom out';
  plots.set(el, u);
  resizer.observe(el);
  return u;
}

/** A legend's value: the number under the cursor, or nothing. */
function legendValue(u, v) {
  return v === null || v === undefined || !Number.isFinite(v) ? '' : short(v);
}

/** "Plot of A (from 1 to 5) and B (from 0 to 3) against x (m), from 0 to 120." */
function describe(x, y, series) {
  const span = (values) => {
    let lo = Infinity;
    let hi = -Infinity;
    for (const v of values ?? []) {
      if (v === null || v === undefined || !Number.isFinite(v)) continue;
      if (v < lo) lo = v;
      if (v > hi) hi = v;
    }
    return lo <= hi ? `from ${short(lo)} to ${short(hi)}` : 'no values';
  };
  const parts = series.filter((s) => s.label).map((s) => `${s.label} (${span(s.values)})`);
  return `Plot of ${y.label ? `${y.label}: ` : ''}${parts.join('; ')}, against ${x.label}, ${span(x.values)}.`;
}

function short(v) {
  return Math.abs(v) >= 1e-3 && Math.abs(v) < 1e6 ? String(Number(v.toPrecision(4))) : v.toExponential(3);
}

/** Aligns several [xs, ys] tables on one ascending x (null where absent). */
export function joinSeries(tables) {
  return uPlot.join(tables);
}

export function destroy(el) {
  const old = plots.get(el);
  if (old) {
    resizer.unobserve(el);
    old.destroy();
    plots.delete(el);
  }
  el.uplot = null;
  el.csv = null;
  el.removeAttribute('aria-label');
  el.removeAttribute('role');
  el.replaceChildren();
}

function padFlat(min, max) {
  if (min === null || max === null) return [0, 1];
  if (max > min) return [min, max];
  const pad = Math.max(Math.abs(min) * 1e-3, 1e-3);
  return [min - pad, max + pad];
}

/**
 * The plot in `el` as a PNG (a Blob): its title, the canvas uPlot drew (axes
 * and labels included) and the series names with their colours.
 */
export function plotPng(el, title) {
  const out = plotCanvas(el, title);
  return out ? new Promise((resolve) => out.toBlob(resolve, 'image/png')) : Promise.resolve(null);
}

/** The plot in `el` as a PNG data URL (for the printed report), or null. */
export function plotDataUrl(el, title) {
  return plotCanvas(el, title)?.toDataURL('image/png') ?? null;
}

function plotCanvas(el, title) {
  const u = plots.get(el);
  if (!u) return null;
  const src = u.ctx.canvas;
  const ratio = src.width / u.width;
  const names = u.series.slice(1).filter((s) => s.show !== false && s.label).map((s) => [s.label, typeof s.stroke === 'function' ? s.stroke(u, 1) : s.stroke]);
  const lineH = 20 * ratio;
  const out = document.createElement('canvas');
  out.width = src.width;
  out.height = src.height + lineH * (1.5 + names.length);
  const ctx = out.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, out.width, out.height);
  ctx.fillStyle = '#1c2430';
  ctx.font = `600 ${14 * ratio}px system-ui, sans-serif`;
  ctx.fillText(title, 8 * ratio, 15 * ratio);
  ctx.drawImage(src, 0, lineH * 1.2);
  ctx.font = `${12 * ratio}px system-ui, sans-serif`;
  names.forEach(([label, color], i) => {
    const y = src.height + lineH * (1.6 + i);
    ctx.fillStyle = color || '#1c2430';
    ctx.fillRect(8 * ratio, y - 9 * ratio, 16 * ratio, 4 * ratio);
    ctx.fillStyle = '#1c2430';
    ctx.fillText(label, 30 * ratio, y);
  });
  return out;
}

/** Puts a short message where a plot would be. */
export function plotMessage(el, text) {
  destroy(el);
  const p = document.createElement('p');
  p.className = 'placeholder';
  p.textContent = text;
  el.append(p);
}
