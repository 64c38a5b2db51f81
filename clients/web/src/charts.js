// Plots on uPlot (clients/web/node_modules/uplot, copied next to the page by
// the build): fast on long series, small, canvas-drawn.
import uPlot from 'uplot';

export const colors = {
  measured: '#1f6fd1',
  predicted: '#e07b00',
  band: 'rgba(120, 120, 120, 0.16)',
  residual: '#1f6fd1',
  before: 'rgba(200, 60, 60, 0.55)',
  fault: 'rgba(220, 40, 40, 0.14)',
  where: 'rgba(250, 190, 0, 0.35)',
  fits: ['#7b3fb5', '#2e9e4f', '#d1495b', '#00798c', '#8a6d00', '#555'],
};

/**
 * Draws x-intervals behind the series: [{start, end, color}] from `intervals()`,
 * read again on every redraw (so highlighting is u.redraw()).
 */
function shadingPlugin(intervals) {
  return {
    hooks: {
      drawClear: (u) => {
        const { ctx, bbox } = u;
        ctx.save();
        for (const { start, end, color } of intervals()) {
          const x0 = Math.max(bbox.left, u.valToPos(start, 'x', true));
          const x1 = Math.min(bbox.left + bbox.width, u.valToPos(end, 'x', true));
          if (!(x1 >= x0)) continue;
          ctx.fillStyle = color;
          ctx.fillRect(x0, bbox.top, Math.max(x1 - x0, 2), bbox.height);
        }
        ctx.restore();
      },
    },
  };
}

/**
 * Calls `onZoom(min, max)` after the user drags across the plot to zoom the
 * x axis; the scale changes uPlot makes by itself (creation, resize) do not.
 */
function zoomPlugin(onZoom) {
  return {
    hooks: {
      init: (u) => {
        u.over.addEventListener('mousedown', () => {
          u._dragging = true;
        });
      },
      setScale: (u, key) => {
        if (key !== 'x' || !u._dragging) return;
        u._dragging = false;
        onZoom(u.scales.x.min, u.scales.x.max);
      },
      setSelect: (u) => {
        // A click without a drag selects nothing and zooms nothing.
        if (u.select.width === 0) u._dragging = false;
      },
    },
  };
}

/**
 * A plot in `container`, as wide as the container, redrawn when it resizes.
 * options: uPlot options without width (height defaults to 220); plus
 * `shade: () => [{start, end, color}]` and `onZoom(min, max)`.
 */
export function plot(container, options, data) {
  const { shade, onZoom, ...rest } = options;
  const plugins = [...(rest.plugins || [])];
  if (shade) plugins.push(shadingPlugin(shade));
  if (onZoom) plugins.push(zoomPlugin(onZoom));
  const width = Math.max(container.clientWidth || 600, 300);
  const u = new uPlot({ height: 220, ...rest, width, plugins }, data, container);
  const observer = new ResizeObserver(() => {
    const w = Math.max(container.clientWidth, 300);
    if (Math.abs(w - u.width) > 2) u.setSize({ width: w, height: u.height });
  });
  observer.observe(container);
  u._observer = observer;
  return u;
}

/** Replaces a plot's data and shows `range` of x (null: all of it). */
export function replaceData(u, data, range) {
  u.setData(data, !range);
  if (range) u.setScale('x', range);
}

export function destroy(u) {
  if (!u) return;
  u._observer?.disconnect();
  u.destroy();
}

/** A series line. */
export function line(label, stroke, extra = {}) {
  return { label, stroke, width: 1.25, spanGaps: true, points: { show: false }, ...extra };
}

/** Bars for categorical x (index 0 … n−1). */
export function bars(label, fill) {
  return { label, fill, stroke: fill, width: 0, paths: uPlot.paths.bars({ size: [0.7, 60] }), points: { show: false } };
}

/** Markers only. */
export function markers(label, stroke, size = 6) {
  return { label, stroke, fill: stroke, width: 0, paths: () => null, points: { show: true, size, fill: stroke } };
}

/** The uPlot time axis in seconds of the run. */
export const secondsAxis = { label: 't [s]', labelSize: 18, size: 34 };

export function valueAxis(label, size = 70) {
  return { label, labelSize: 18, size, values: (u, ticks) => ticks.map((v) => formatTick(v)) };
}

export function formatTick(v) {
  if (v === null || v === undefined) return ''; // log scales leave some ticks out
  if (v === 0) return '0';
  const a = Math.abs(v);
  return a >= 1e4 || a < 1e-2 ? v.toExponential(1) : String(Number(v.toPrecision(4)));
}

export { uPlot };
