// A unit's history (GET /v1/units/{unit}/history, docs/API.md): its runs and
// analyses over time, a table of every identified parameter's repeatability
// and trend, and a plot per parameter — each run's value ± its standard error
// against the test date, with the weighted trend line.
import { api, num, idOf } from './api.js';
import { h, fmt, fmtP, fmtTime, empty, section, table } from './dom.js';
import { plot, markers, line, formatTick, colors } from './charts.js';
import { navigate } from './nav.js';

const SECONDS_PER_DAY = 86400;

export async function showHistory(view, unit) {
  const history = await api.unitHistory(unit);
  const serial = unit.replace(/^units\//, '');
  view.append(
    h('h1', `Unit ${serial}`),
    h('p.muted#history-summary', `${history.unitType ? history.unitType.replace(/^unitTypes\//, '') : 'unit type unknown'} · `,
      `${history.runCount} runs, ${history.analysedRunCount} with a succeeded analysis`),
    ...(history.notes.length ? [h('ul.notes', history.notes.map((n) => h('li', n)))] : []),
    section('Runs and analyses', runTable(history.runs)),
  );
  if (!history.parameters.length) {
    view.append(section('Identified parameters', empty('No analysis of this unit has identified a parameter yet.')));
    return;
  }
  const plots = h('div.grid2#history-plots');
  view.append(
    section('Repeatability and trend of each identified parameter', statisticsTable(history),
      h('p.hint', `Run-to-run: the standard deviation across runs with its ${fmt(100 * num(history.confidence))} % `
        + 'χ² interval. Turn-on: a turn-on bias\'s spread between power-ups with the identification\'s error removed. '
        + 'Trend: weighted least squares (weights 1/SE²); * the scatter exceeds the SEs, the slope\'s error is scaled.')),
    section('Each parameter over the unit\'s runs', plots),
  );
  // The plots take their width from the page, so they are drawn once it is laid out.
  requestAnimationFrame(() => {
    for (const p of history.parameters) plots.append(parameterPlot(p));
  });
}

function runTable(runs) {
  if (!runs.length) return empty('No run of this unit.');
  const rows = runs.flatMap((run) => {
    const id = idOf(run.run);
    const analyses = run.analyses.length ? run.analyses : [null];
    return analyses.map((a, i) => h(a ? 'tr.clickable' : 'tr', { onclick: a ? () => navigate(`#/${a.analysis}`) : null },
      h('td', i === 0 ? h('a', { href: `#/runs/${id}` }, id.slice(0, 8)) : ''),
      h('td', i === 0 ? fmtTime(run.testTime) : ''),
      h('td', a ? h('a', { href: `#/${a.analysis}` }, idOf(a.analysis).slice(0, 8)) : 'not analysed'),
      h('td', a ? h(`span.badge.${a.verdict}`, a.verdict.replace('VERDICT_UNSPECIFIED', '—')) : ''),
      h('td.num', a ? String(a.identifiedCount) : ''),
      h('td', a?.counted ? 'counted' : '')));
  });
  return table(['Run', 'Tested', 'Analysis', 'Verdict', 'Identified', 'In the statistics'], rows, { id: 'history-runs' });
}

function statisticsTable(history) {
  const rows = history.parameters.map((p) => {
    const s = p.statistics;
    const t = s.trend;
    const sd = s.count >= 2;
    return h('tr', { dataset: { parameter: p.name, trendP: t.fitted ? String(num(t.pValue)) : '' } },
      h('td', p.name), h('td', p.unit || ''), h('td.num', String(s.count)), h('td.num', fmt(s.mean)),
      h('td.num', sd ? fmt(s.runToRunSd) : '—'),
      h('td.num', sd ? `${fmt(s.runToRunSdLow)} – ${fmt(s.runToRunSdHigh)}` : '—'),
      h('td.num', s.turnOnToTurnOnSd !== undefined ? fmt(s.turnOnToTurnOnSd) : '—'),
      h('td.num', t.fitted ? `${fmt(t.slopePerDay)} ± ${fmt(t.slopeStdErrorPerDay, 2)}` : '—'),
      h(num(t.pValue) < 0.01 && t.fitted ? 'td.num.worse' : 'td.num', t.fitted ? `${fmtP(t.pValue)}${t.excessScatter ? ' *' : ''}` : '—'));
  });
  return h('div.scroll', table(['Parameter', 'Unit', 'n', 'Mean', 'Run-to-run sd', 'Interval', 'Turn-on sd',
    'Trend per day', 'p'], rows, { id: 'history-statistics' }));
}

/** "= 0.03", or "< 1e-16" past what doubles tell apart. */
function pText(value) {
  const text = fmtP(value);
  return text.startsWith('<') ? `< ${text.slice(1)}` : `= ${text}`;
}

/** Vertical bars from `low[i]` to `high[i]` at each x of series 1. */
function errorBarsPlugin(low, high, stroke) {
  return {
    hooks: {
      draw: (u) => {
        const { ctx } = u;
        ctx.save();
        ctx.strokeStyle = stroke;
        ctx.lineWidth = 1;
        u.data[0].forEach((x, i) => {
          if (low[i] === null || high[i] === null) return;
          const px = u.valToPos(x, 'x', true);
          ctx.beginPath();
          ctx.moveTo(px, u.valToPos(low[i], 'y', true));
          ctx.lineTo(px, u.valToPos(high[i], 'y', true));
          ctx.stroke();
        });
        ctx.restore();
      },
    },
  };
}

function parameterPlot(p) {
  const points = p.points;
  const t = p.statistics.trend;
  const x = points.map((q) => new Date(q.testTime).getTime() / 1000);
  const values = points.map((q) => num(q.value));
  const se = points.map((q) => num(q.stdError) || 0);
  const low = values.map((v, i) => v - se[i]);
  const high = values.map((v, i) => v + se[i]);
  const series = [{}, markers('value ± SE', colors.measured, 6)];
  const data = [x, values];
  if (t.fitted) {
    const trend = points.map((q) => num(t.intercept) + num(t.slopePerDay) * num(q.days));
    series.push(line('trend', colors.predicted, { width: 2 }));
    data.push(trend);
  }
  const container = h('div.history-plot', { dataset: { parameter: p.name } });
  const caption = t.fitted
    ? `trend ${fmt(t.slopePerDay)} ± ${fmt(t.slopeStdErrorPerDay, 2)} ${p.unit || ''} per day, p ${pText(t.pValue)}`
    : `${points.length} run${points.length === 1 ? '' : 's'}: no trend before three`;
  const box = h('div', h('h3', p.name), container, h('p.hint', caption));
  requestAnimationFrame(() => plot(container, {
    height: 180,
    scales: {
      x: { time: true, range: (u, min, max) => (min === max ? [min - SECONDS_PER_DAY, max + SECONDS_PER_DAY] : [min, max]) },
      y: { range: () => {
        const lo = Math.min(...low, ...(data[2] || []));
        const hi = Math.max(...high, ...(data[2] || []));
        const pad = 0.08 * (hi - lo || Math.abs(hi) || 1);
        return [lo - pad, hi + pad];
      } },
    },
    axes: [{}, { label: p.unit || '', labelSize: 18, size: 70, values: (u, ticks) => ticks.map(formatTick) }],
    series,
    plugins: [errorBarsPlugin(low, high, colors.measured)],
  }, data));
  return box;
}
