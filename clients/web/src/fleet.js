// Fleet statistics from the knowledge base (docs/FLEET.md): failure rates
// with MTBF bounds, the Pareto of failure modes, the Weibull life of a module
// role on Weibull paper with its B10, trends of an identified parameter
// across the fleet, and the units ranked by fault probability.
import { api, listAll, moduleOf, num } from './api.js';
import { h, fmt, fmtTime, empty, section, table } from './dom.js';
import { plot, line, bars, markers, formatTick, uPlot } from './charts.js';

export async function showFleet(view) {
  const [statistics, pareto, ranking, unitTypes] = await Promise.all([
    api.fleetStatistics(), api.pareto(), api.unitRanking(), api.listUnitTypes(),
  ]);
  const after = [];
  view.append(
    h('h1', 'Fleet'),
    statisticsSection(statistics),
    paretoSection(pareto, after),
    weibullSection(statistics),
    trendSection(unitTypes.unitTypes),
    rankingSection(ranking));
  requestAnimationFrame(() => after.forEach((draw) => draw()));
}

function statisticsSection(s) {
  const counts = h('div.row', [['units', s.unitCount], ['runs', s.runCount], ['analyses', s.analysisCount],
    ['confirmed failures', s.failureCount], ['no fault found', s.noFaultFoundCount]]
    .map(([k, v]) => h('div', { style: 'margin-right:22px' }, h('div.small.muted', k), h('div', { style: 'font-size:18px' }, String(v)))));
  const rates = s.failureRates.length
    ? table(['Module role', 'Failures', 'Operating hours', 'per 10⁶ h', `MTBF [h] (${fmt(100 * num(s.confidence))} % bounds)`, 'NFF', 'Modules'],
      s.failureRates.map((r) => h('tr', h('td', r.moduleRole), h('td.num', r.failures), h('td.num', fmt(r.operatingHours, 4)),
        h('td.num', fmt(r.failuresPerMillionHours)),
        h('td.num', num(r.mtbfHours) ? `${fmt(r.mtbfHours)} (${fmt(r.mtbfLowerHours)} … ${num(r.mtbfUpperHours) ? fmt(r.mtbfUpperHours) : '∞'})` : '—'),
        h('td.num', r.noFaultFound), h('td.num', r.modules))))
    : empty('No module in the knowledge base yet: failure rates appear once units are analysed and failures recorded.');
  return section('Statistics', counts, h('h3', 'Failure rates per module role'), rates,
    s.countsTime ? h('p.hint', `counts refreshed ${fmtTime(s.countsTime)}`) : null);
}

function paretoSection(pareto, after) {
  // Modes that never failed have no bar.
  const entries = pareto.entries.filter((e) => num(e.failures) > 0);
  if (!entries.length) {
    return section('Pareto of failure modes', empty('No confirmed failure yet: confirm a diagnosis to start the Pareto.'));
  }
  const container = h('div#pareto-plot');
  const x = entries.map((_, i) => i);
  after.push(() => plot(container, {
    height: 260,
    legend: { show: false },
    scales: { x: { time: false, range: [-0.5, entries.length - 0.5] }, share: { range: [0, 100] } },
    axes: [
      { values: (u, ticks) => ticks.map((i) => (Number.isInteger(i) && entries[i] ? short(entries[i].displayName || entries[i].failureMode) : '')), size: 50, rotate: 0 },
      { label: 'failures', labelSize: 18 },
      { scale: 'share', side: 1, label: 'cumulative %', labelSize: 18, grid: { show: false } },
    ],
    series: [{}, bars('failures', 'rgba(31,111,209,0.7)'),
      line('cumulative %', '#c0262d', { scale: 'share', width: 2, points: { show: true, size: 5 } })],
  }, [x, entries.map((e) => num(e.failures)), entries.map((e) => 100 * num(e.cumulativeShare))]));
  return section(`Pareto of failure modes (${pareto.totalFailures} confirmed failures)`, container,
    table(['Failure mode', 'Module', 'Failures', 'Share', 'Cumulative'], entries.map((e) => h('tr',
      h('td', e.displayName || e.failureMode), h('td', e.moduleRole), h('td.num', e.failures),
      h('td.num', `${fmt(100 * num(e.share))} %`), h('td.num', `${fmt(100 * num(e.cumulativeShare))} %`)))));
}

const short = (text) => (text.length > 18 ? `${text.slice(0, 17)}…` : text);

// --- Weibull ------------------------------------------------------------------

/** Weibull paper: y = ln(−ln(1 − F)) against log t, where a Weibull law is a straight line. */
const weibullY = (F) => Math.log(-Math.log(1 - F));
const paperTicks = [0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.632, 0.8, 0.9, 0.95, 0.99];

function weibullSection(statistics) {
  const roles = statistics.failureRates.map((r) => r.moduleRole);
  const body = h('div');
  if (!roles.length) return section('Weibull life', empty('No module role with records yet.'));
  const picker = h('select', { onchange: () => drawWeibull(body, picker.value) },
    roles.map((r) => h('option', { value: r }, r)));
  const withFailures = statistics.failureRates.find((r) => num(r.failures) > 0);
  if (withFailures) picker.value = withFailures.moduleRole;
  requestAnimationFrame(() => drawWeibull(body, picker.value));
  return section('Weibull life per module role', h('div.row', 'Module role ', picker), body);
}

async function drawWeibull(body, role) {
  body.replaceChildren(h('p.muted', 'Loading…'));
  let fit;
  try {
    fit = await api.weibull(role);
  } catch (error) {
    body.replaceChildren(empty(`No Weibull fit for ${role}: ${error.message}`));
    return;
  }
  if (!num(fit.failures) || !num(fit.shape)) {
    body.replaceChildren(empty(`No confirmed failure of ${role} yet: a Weibull life needs at least one.`));
    return;
  }
  const points = await failurePoints(role, num(fit.suspensions) || 0);
  const beta = num(fit.shape);
  const eta = num(fit.scaleHours);
  const b10 = num(fit.b10Hours);
  const times = points.map((p) => p.t);
  const lo = Math.min(b10 || eta, ...times, eta) / 3;
  const hi = Math.max(eta, ...times) * 3;
  const xs = Array.from({ length: 40 }, (_, i) => lo * (hi / lo) ** (i / 39));
  const fitted = [xs, xs.map((t) => beta * (Math.log(t) - Math.log(eta)))];
  const ranked = [times, points.map((p) => weibullY(p.F))];
  const b10Point = b10 ? [[b10], [weibullY(0.1)]] : [[], []];
  const data = uPlot.join([fitted, ranked, b10Point]);
  const container = h('div#weibull-plot');
  body.replaceChildren(
    h('p', `β = ${fmt(beta)} (${fmt(fit.shapeLower)} … ${fmt(fit.shapeUpper)}), η = ${fmt(eta)} h (${fmt(fit.scaleLowerHours)} … ${fmt(fit.scaleUpperHours)}), `,
      h('strong', `B10 = ${fmt(b10)} h`), ` (${fmt(fit.b10LowerHours)} … ${fmt(fit.b10UpperHours)}) · ${fit.failures} failures, ${fit.suspensions} suspensions`),
    container,
    h('p.hint', 'Line: the server\'s maximum-likelihood fit with right censoring. Points: each module\'s first confirmed failure at Bernard\'s median rank, the suspensions taken after the last failure (a display approximation). Green: B10.'));
  requestAnimationFrame(() => plot(container, {
    height: 280,
    legend: { show: false },
    scales: { x: { time: false, distr: 3 }, y: { range: [weibullY(0.005), weibullY(0.995)] } },
    axes: [{ label: 'operating hours', labelSize: 18, size: 34 },
      { label: 'unreliability F', labelSize: 18, size: 60, splits: () => paperTicks.map(weibullY),
        values: () => paperTicks.map((F) => `${fmt(100 * F, 3)} %`) }],
    series: [{}, line('Weibull fit', '#1f6fd1', { width: 2 }), markers('failures', '#c0262d', 7), markers('B10', '#1b7f3b', 10)],
  }, data));
}

/**
 * The failures behind a role's fit, as the server counts them (each module's
 * first confirmed failure), at Bernard's median ranks among failures plus
 * suspensions. The suspensions' hours are not listed by the API: they are
 * taken to lie after the last failure, which is what the plot approximates.
 */
async function failurePoints(role, suspensions) {
  const records = await listAll(api.listFailureRecords, 'failureRecords', 20000);
  const firstFailure = new Map();
  for (const r of records) {
    const hours = num(r.operatingHours);
    if (!r.confirmed || moduleOf(r.module).role !== role || !(hours > 0)) continue;
    firstFailure.set(r.module, Math.min(hours, firstFailure.get(r.module) ?? Infinity));
  }
  const times = [...firstFailure.values()].sort((a, b) => a - b);
  const n = times.length + suspensions;
  return times.map((t, i) => ({ t, F: (i + 1 - 0.3) / (n + 0.4) }));
}

// --- parameter trends -----------------------------------------------------------

function trendSection(unitTypes) {
  const body = h('div');
  const parameters = unitTypes.flatMap((t) => t.nominal.map((p) => ({ type: t, parameter: p })));
  if (!parameters.length) return section('Parameter trends', empty('No unit type with nominal parameters in the knowledge base.'));
  const picker = h('select', { onchange: () => drawTrend(body, parameters[picker.value]) },
    parameters.map((p, i) => h('option', { value: i }, `${p.type.displayName} · ${p.parameter.name}`)));
  requestAnimationFrame(() => drawTrend(body, parameters[0]));
  return section('Parameter trends across the fleet', h('div.row', 'Parameter ', picker), body);
}

async function drawTrend(body, { type, parameter }) {
  body.replaceChildren(h('p.muted', 'Loading…'));
  let trend;
  let points;
  try {
    [trend, points] = await Promise.all([api.parameterTrend(type.name, parameter.name), api.parameterPoints(type.name, parameter.name)]);
  } catch (error) {
    body.replaceChildren(empty(`No trend for ${parameter.name}: ${error.message}`));
    return;
  }
  if (!trend.buckets.length && !points.points.length) {
    body.replaceChildren(empty(`No analysis has identified ${parameter.name} on a ${type.displayName} yet.`));
    return;
  }
  const seconds = (ts) => new Date(ts).getTime() / 1000;
  const buckets = [...trend.buckets].sort((a, b) => seconds(a.month) - seconds(b.month));
  const raw = [...points.points].sort((a, b) => seconds(a.time) - seconds(b.time));
  const nominal = num(trend.nominal);
  const tolerance = num(trend.tolerance);
  const frames = [
    [buckets.map((b) => seconds(b.month)), buckets.map((b) => num(b.median)), buckets.map((b) => num(b.p75)), buckets.map((b) => num(b.p25))],
    [raw.map((p) => seconds(p.time)), raw.map((p) => num(p.value))],
  ];
  const data = uPlot.join(frames.filter((f) => f[0].length));
  const series = [{}];
  const bands = [];
  if (buckets.length) {
    series.push(line('monthly median', '#1f6fd1', { width: 2, points: { show: true, size: 5 } }),
      line('p75', 'rgba(31,111,209,0.4)', { width: 0.5 }), line('p25', 'rgba(31,111,209,0.4)', { width: 0.5 }));
    bands.push({ series: [2, 3], fill: 'rgba(31,111,209,0.12)' });
  }
  if (raw.length) series.push(markers('analyses', 'rgba(29,36,48,0.6)', 4));
  const container = h('div#trend-plot');
  body.replaceChildren(
    h('p', `nominal ${fmt(nominal)} ± ${fmt(tolerance)} ${trend.unit || parameter.unit || ''} · slope ${fmt(trend.slopePerYear)} per year (${fmt(100 * num(trend.relativeSlopePerYear))} % of nominal)`),
    container);
  const limits = nominal === null ? [] : [nominal - (tolerance || 0), nominal + (tolerance || 0)];
  requestAnimationFrame(() => plot(container, {
    height: 240,
    // The tolerance limits stay in view however the values lie.
    scales: { y: { range: (u, min, max) => {
      const lo = Math.min(min, ...limits);
      const hi = Math.max(max, ...limits);
      const pad = 0.05 * (hi - lo || Math.abs(hi) || 1);
      return [lo - pad, hi + pad];
    } } },
    axes: [{}, { label: `${parameter.name} [${trend.unit || parameter.unit || ''}]`, labelSize: 18, size: 70, values: (u, t) => t.map(formatTick) }],
    series,
    bands,
    // The tolerance limits as dashed lines across the plot.
    plugins: [{ hooks: { draw: (u) => {
      const { ctx, bbox } = u;
      ctx.save();
      ctx.setLineDash([6, 4]);
      ctx.strokeStyle = '#c0262d';
      for (const v of limits) {
        const y = u.valToPos(v, 'y', true);
        if (y < bbox.top || y > bbox.top + bbox.height) continue;
        ctx.beginPath();
        ctx.moveTo(bbox.left, y);
        ctx.lineTo(bbox.left + bbox.width, y);
        ctx.stroke();
      }
      ctx.restore();
    } } }],
  }, data));
}

function rankingSection(ranking) {
  if (!ranking.units.length) return section('Units by fault probability', empty('No diagnosed unit yet.'));
  return section('Units by fault probability',
    table(['Unit', 'Type', 'Batch', 'Fault probability', 'Top module', 'Failure mode', 'Operating hours'], ranking.units.map((u) => h('tr',
      h('td', u.unit.replace(/^units\//, '')), h('td', u.unitType.replace(/^unitTypes\//, '') || '—'), h('td', u.batch || '—'),
      h('td.num', `${fmt(100 * num(u.faultProbability))} %`), h('td', u.topModule || '—'),
      h('td', (u.topFailureMode || '—').replace(/^failureModes\//, '')), h('td.num', fmt(u.operatingHours, 4))))));
}
