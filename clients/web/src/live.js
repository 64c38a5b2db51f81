// Tests being recorded (LiveRunService, docs/LIVE.md): the list of live runs,
// and one test watched as it happens — its verdict, each channel's β² and
// moving-window F against the seed's tolerances, the fault intervals as they
// are found, and the window F over time. When the test ends the view links
// to the stored run and its analysis.
import { api, num } from './api.js';
import { h, fmt, fmtSeconds, fmtTime, empty, section, table } from './dom.js';
import { plot, line, secondsAxis, valueAxis } from './charts.js';
import { navigate } from './nav.js';

const LIST_REFRESH_MS = 2000;
// Position, velocity, then attitude (observed while the table stands still).
const CHANNEL_COLORS = ['#1f6fd1', '#e07b00', '#2a9d4b', '#b03a9d', '#7a5c2e', '#c0392b', '#17a2b8', '#6c757d', '#8e44ad'];

/** Lists the live runs, refreshed while the view is open. */
export async function showLiveRuns(view, leaving) {
  const listing = h('div#live-list');
  view.append(h('h1', 'Live tests'),
    h('p.muted', 'Tests fed with ', h('code', 'insdiag stream'), ' while the bench records them, and the ones that ended '
      + 'since the server started.'),
    section('Tests', listing));
  const refresh = async () => {
    const { liveRuns = [] } = await api.listLiveRuns();
    listing.replaceChildren(liveRuns.length ? liveTable(liveRuns) : empty('No test is being recorded.'));
  };
  await refresh();
  const timer = setInterval(() => refresh().catch(() => {}), LIST_REFRESH_MS);
  leaving.push(() => clearInterval(timer));
}

function liveTable(runs) {
  const rows = runs.map((run) => h('tr.clickable', { onclick: () => navigate(`#/${run.name}`), dataset: { name: run.name } },
    h('td', run.unitSerial),
    h('td', h(`span.badge.${run.state === 'STORED' ? 'SUCCEEDED' : run.state === 'FAILED' ? 'FAILED' : 'RUNNING'}`, run.state)),
    h('td', run.verdict ? h(`span.badge.${run.verdict}`, run.verdict.replace('VERDICT_UNSPECIFIED', '—')) : '—'),
    h('td.num', `${fmtSeconds(run.timeS)} of ${fmtSeconds(run.plannedDurationS)}`),
    h('td.num', String((run.faultIntervals || []).length)),
    h('td', fmtTime(run.startTime))));
  return table(['Unit', 'State', 'Verdict', 'Monitored', 'Fault intervals', 'Started'], rows, { id: 'live-runs' });
}

/** Watches liveRuns/{id} until it ends or the view closes. */
export async function showLiveRun(view, name, leaving) {
  const heading = h('h1', 'Live test');
  const summary = h('p#live-summary.muted');
  const channels = h('div#live-channels');
  const faults = h('div#live-faults');
  const chart = h('div.chart#live-chart');
  const ended = h('div#live-ended');
  view.append(heading, summary, ended,
    h('div.grid2', section('Channels now', channels), section('Fault intervals', faults)),
    section('Moving-window F of each channel (the tolerance η² dashed)', chart));

  // One F series per channel the server reports, made on the first update.
  const series = { t: [], F: [] };
  let figure = null;
  const controller = new AbortController();
  leaving.push(() => {
    controller.abort();
    figure?.destroy();
  });
  await api.watchLiveRun(name, (live) => {
    heading.textContent = `Live test of ${live.unitSerial}`;
    summary.replaceChildren(
      h(`span.badge.${live.verdict || 'VERDICT_UNSPECIFIED'}#live-verdict`, (live.verdict || '—').replace('VERDICT_UNSPECIFIED', '—')),
      ' ', h('span#live-state', live.state), ` · ${fmtSeconds(live.timeS)} of ${fmtSeconds(live.plannedDurationS)} monitored`
        + ` · ${live.epochCount || 0} of ${live.plannedEpochCount || 0} update epochs · ${live.sampleCount || 0} samples`
        + ` · mean NIS ${fmt(live.nisMean)} (band ${fmt(live.nisBandLow)} – ${fmt(live.nisBandHigh)})`);
    channels.replaceChildren(channelTable(live));
    faults.replaceChildren((live.faultIntervals || []).length ? faultTable(live.faultIntervals) : empty('None so far.'));
    if (live.epochCount > 0 && live.channels) {
      series.t.push(num(live.timeS));
      live.channels.forEach((c, i) => (series.F[i] ||= series.t.slice(1).map(() => null)).push(Number.isFinite(num(c.windowRatio)) ? num(c.windowRatio) : null));
      figure = drawChart(chart, figure, series, live);
    }
    if (live.state === 'STORED' || live.state === 'FAILED') ended.replaceChildren(endCard(live));
  }, controller.signal);
}

function channelTable(live) {
  const eta2 = num(live.eta2);
  const rows = (live.channels || []).map((c) => {
    const F = num(c.windowRatio);
    return h('tr', h('td', c.name), h('td.num', Number.isFinite(num(c.beta2)) ? fmt(c.beta2) : '—'),
      h(Number.isFinite(F) && F > eta2 ? 'td.num.worse' : 'td.num', Number.isFinite(F) ? fmt(F) : '—'));
  });
  return h('div',
    table(['Channel', 'β² (last update)', 'F (last window)'], rows),
    h('p.hint', `Tolerances: γ² = ${fmt(live.gamma2)} on β², η² = ${fmt(live.eta2)} on F (the seed's); `
      + `fault intervals where β² exceeds ${fmt(live.outlierThreshold)} or F ${fmt(live.gradualThreshold)} `
      + '(family-wise over the planned test), and bias steps by their likelihood ratio.'));
}

function faultTable(intervals) {
  const rows = intervals.map((f) => h('tr', h('td', h(`span.badge.${f.kind === 'OUTLIER' ? 'OPERABLE' : 'FAULTY'}`, f.kind)),
    h('td', f.channel), h('td.num', fmt(f.startS, 5)), h('td.num', fmt(f.endS, 5)), h('td.num', fmt(f.peakStatistic))));
  return table(['Kind', 'Channel', 'From [s]', 'To [s]', 'Peak'], rows, { id: 'live-fault-table' });
}

function drawChart(container, figure, series, live) {
  const eta2 = num(live.eta2);
  const data = [series.t, ...series.F, series.t.map(() => eta2)];
  if (figure) {
    figure.setData(data);
    return figure;
  }
  return plot(container, {
    series: [{}, ...live.channels.map((c, i) => line(c.name, CHANNEL_COLORS[i])), line('η²', '#555', { dash: [6, 4] })],
    axes: [secondsAxis, valueAxis('F')],
    scales: { x: { time: false } },
  }, data);
}

function endCard(live) {
  if (live.state === 'FAILED') {
    return h('div.card.refusal', h('strong', 'Not stored: '), live.error?.message || 'the test ended without its digest');
  }
  return h('div.card',
    h('p', 'The test has ended and is stored as ', h('a#live-run-link', { href: `#/${live.run}` }, live.run), '.'),
    live.analysis ? h('p', 'Its analysis: ', h('a#live-analysis-link', { href: `#/${live.analysis}` }, live.analysis), '.') : null,
    live.error ? h('p.muted', live.error.message) : null);
}
