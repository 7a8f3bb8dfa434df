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
 * - `series`: [{label, values, color?, axis?: 'y'|'y2', points?, width?, dash?, bars?}]
 * - `y`, `y2`: {label, range?}; y2 only when a series uses it.
 * The x values must be ascending (uPlot's own rule) unless `x.range` is given.
 */
export function linePlot(el, { x, y, y2, series, height = HEIGHT, legend = true }) {
  destroy(el);
  const axisStyle = { stroke: '#3b4350', grid: { stroke: '#e3e7ed', width: 1 }, ticks: { stroke: '#c9d0da', width: 1 } };
  const scales = {
    x: { time: false, ...(x.range ? { range: () => x.range } : {}) },
    y: y.range ? { range: () => y.range } : {},
  };
  const axes = [
    { ...axisStyle, label: x.label },
    { ...axisStyle, label: y.label, scale: 'y', size: 64 },
  ];
  if (y2) {
    scales.y2 = y2.range ? { range: () => y2.range } : {};
    axes.push({ ...axisStyle, label: y2.label, scale: 'y2', side: 1, size: 64, grid: { show: false } });
  }

  const opts = {
    width: Math.max(el.clientWidth, 320),
    height,
    scales,
    axes,
    legend: { show: legend },
    cursor: { drag: { x: true, y: false } },
    series: [
      { label: x.label },
      ...series.map((s, i) => {
        const color = s.color ?? COLORS[i % COLORS.length];
        return {
          label: s.label,
          scale: s.axis ?? 'y',
          stroke: color,
          width: s.width ?? 1.75,
          dash: s.dash,
          spanGaps: true,
          fill: s.bars ? `${color}55` : undefined,
          paths: s.bars ? uPlot.paths.bars({ size: [0.92, Infinity], align: 0 }) : s.points === 'only' ? () => null : undefined,
          points: s.points === 'only' || s.points === true
            ? { show: true, size: s.pointSize ?? 9, stroke: color, fill: s.pointFill ?? color }
            : { show: false },
        };
      }),
    ],
  };
  const data = [x.values, ...series.map((s) => s.values)];
  const u = new uPlot(opts, data, el);
  plots.set(el, u);
  resizer.observe(el);
  return u;
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
  el.replaceChildren();
}

/** Puts a short message where a plot would be. */
export function plotMessage(el, text) {
  destroy(el);
  const p = document.createElement('p');
  p.className = 'placeholder';
  p.textContent = text;
  el.append(p);
}
