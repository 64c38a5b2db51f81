// One analysis: the model loop of docs/WEB.md. While the job runs, its
// progress (WatchAnalysis); once it succeeded, the verdict, the loop's steps
// with the error falling, measured against predicted and the residuals per
// channel (decimated by the server to the plot's width, finer on zoom), the
// fault intervals, the missing effects with an Add button each, the
// identification (ACF, Allan) and the unit's diagnosis.
import { api, num, idOf } from './api.js';
import { h, fmt, fmtP, fmtSeconds, fmtTime, empty, section, table } from './dom.js';
import { plot, replaceData, destroy, line, colors, secondsAxis, valueAxis, uPlot } from './charts.js';
import { navigate, startAnalysis, errorCard } from './nav.js';
import { identificationSection } from './identification.js';
import { diagnosisSection } from './diagnosis.js';

// The attitude channels hold the epochs the table stood still at only.
const CHANNELS = ['lat', 'lon', 'height', 'vel_n', 'vel_e', 'vel_d', 'att_n', 'att_e', 'att_d'];
const terminal = (state) => ['SUCCEEDED', 'FAILED', 'CANCELLED'].includes(state);
const effectsKey = (effects) => [...(effects || [])].sort().join('|');

/** Renders analyses/{a} into `view`; puts what stops its streams and plots into `leaving`. */
export async function showAnalysis(view, name, leaving) {
  const controller = new AbortController();
  const cleanups = [];
  leaving.push(() => {
    controller.abort();
    cleanups.forEach((fn) => fn());
  });
  let analysis = await api.getAnalysis(name);
  if (!terminal(analysis.state)) {
    const progress = progressCard(analysis);
    view.replaceChildren(header(analysis), progress.element);
    try {
      await api.watchAnalysis(name, (message) => {
        analysis = message;
        progress.update(message);
        const badge = view.querySelector('#state');
        if (badge) {
          badge.textContent = message.state;
          badge.className = `badge ${message.state}`;
        }
      }, controller.signal);
    } catch (error) {
      if (!controller.signal.aborted) view.append(errorCard(error));
      return;
    }
    if (controller.signal.aborted) return;
    // The watch's last message carries the report; a watch cut short does not.
    if (!terminal(analysis.state) || !analysis.report) analysis = await api.getAnalysis(name);
    if (!terminal(analysis.state)) {
      view.append(errorCard(new Error('The server stopped reporting progress; reload the page to follow the analysis.')));
      return;
    }
  }
  view.replaceChildren(header(analysis));
  if (analysis.state === 'FAILED') {
    view.append(section('The analysis failed', h('p#analysis-error', analysis.error?.message || 'no reason given')));
    return;
  }
  if (analysis.state === 'CANCELLED') {
    view.append(section('Cancelled', empty('This analysis was cancelled before it finished.')));
    return;
  }
  await showReport(view, analysis, cleanups);
}

function header(analysis) {
  const report = analysis.report;
  const runId = idOf(analysis.run);
  return h('div',
    h('h1', 'Analysis ', h('span.muted', idOf(analysis.name).slice(0, 8)), ' ',
      report && analysis.state === 'SUCCEEDED'
        ? h(`span.badge.${report.verdict}#verdict`, report.verdict)
        : h(`span.badge.${analysis.state}#state`, analysis.state)),
    h('p.muted',
      'Run ', h('a', { href: `#/runs/${runId}` }, runId.slice(0, 8)),
      analysis.unit ? [' · ', h('a#analysis-unit', { href: `#/${analysis.unit}/history`, title: 'the unit\'s history' }, analysis.unit)] : '',
      ' · model: ', h('strong#model-effects', analysis.model.effects.length ? analysis.model.effects.join(', ') : 'base model'),
      analysis.discover ? ' · discover' : '',
      ` · created ${fmtTime(analysis.createTime)}`),
    analysis.state === 'SUCCEEDED'
      ? h('div.row#test-report',
        h('span.muted', 'Test report for the quality department: '),
        h('button.secondary#test-report-pdf', { onclick: () => openTestReport(analysis.name, 'pdf') }, 'PDF'),
        h('button.secondary#test-report-html', { onclick: () => openTestReport(analysis.name, 'html') }, 'HTML'))
      : null);
}

/** Opens the analysis's test report in a new tab (docs/TEST_REPORT.md). */
function openTestReport(name, format) {
  // Opened at once, filled when the document arrives: a tab opened later is a pop-up the browser blocks.
  const tab = window.open('', '_blank');
  api.testReport(name, format)
    .then((blob) => { tab.location.href = URL.createObjectURL(blob); })
    .catch((error) => {
      tab?.close();
      window.alert(error.message);
    });
}

function progressCard(analysis) {
  const bar = h('div', { style: 'width:0%' });
  const label = h('p#progress-label.muted');
  const cancel = h('button.danger', { onclick: () => api.cancelAnalysis(analysis.name).catch(() => {}) }, 'Cancel');
  const element = section('Running', h('div.progress#progress', bar), h('div.row', label, h('span.grow'), cancel));
  const update = (a) => {
    const fraction = num(a.progress?.fraction) || 0;
    bar.style.width = `${Math.round(fraction * 100)}%`;
    label.textContent = `${a.state}${a.progress?.stage ? ` — ${a.progress.stage}` : ''} · ${Math.round(fraction * 100)}%` +
      (a.attempts > 1 ? ` · attempt ${a.attempts}` : '');
    if (terminal(a.state)) cancel.disabled = true;
  };
  update(analysis);
  return { element, update };
}

// --- the report ---------------------------------------------------------------

async function showReport(view, analysis, cleanups) {
  const report = analysis.report;
  const steps = await loopSteps(analysis);
  if (!view.isConnected) return; // the user went elsewhere meanwhile
  const before = steps.length > 1 ? steps[steps.length - 2] : null;
  const state = { channel: pickChannel(report), highlight: null };

  const channelsView = channelSection(analysis, before, state, cleanups);
  view.append(...[
    summaryCard(report),
    loopSection(analysis, steps),
    channelsView.element,
    candidatesSection(analysis, state, channelsView),
    discoverySection(report),
    identificationSection(report, cleanups),
    diagnosisSection(analysis),
  ].filter(Boolean));
  channelsView.draw();
}

/** The channel to show first: the worst fit (largest NIS), else lat. */
function pickChannel(report) {
  let best = null;
  for (const c of report.channels) if (!best || num(c.nisMean) > num(best.nisMean)) best = c;
  return best ? best.name : CHANNELS[0];
}

function summaryCard(report) {
  const items = [
    ['mean NIS', `${fmt(report.nisMean)} (band ${fmt(report.nisBandLow)} … ${fmt(report.nisBandHigh)})`],
    ['log-likelihood', fmt(report.logLikelihood, 6)],
    ['AIC', fmt(report.aic, 6)],
    ['BIC', fmt(report.bic, 6)],
    ['duration', fmtSeconds(report.durationS)],
    ['samples', `${Number(report.sampleCount).toLocaleString()} at ${fmt(report.sampleRateHz)} Hz`],
    ['updates', Number(report.updateCount).toLocaleString()],
  ];
  // In plain words first; the engine's notes folded below.
  const plain = report.plainWords || [];
  return section('Verdict',
    plain.length ? h('div.plain-words', plain.map((line) => h('p', line))) : null,
    h('div.row', items.map(([k, v]) => h('div', { style: 'margin-right:18px' }, h('div.small.muted', k), h('div', v)))),
    report.notes.length
      ? h('details.notes', h('summary', `the engine's notes (${report.notes.length})`),
        h('ul.notes', report.notes.map((n) => h('li', n))))
      : null);
}

// --- the loop: every step's fit, before and after ------------------------------

/**
 * The analyses of this run that led to `analysis`, first step first: each
 * step's predecessor is the analysis of its baseline model, else (a server
 * that keeps no baseline) the succeeded analysis whose effects are the
 * largest proper subset of its own.
 */
async function loopSteps(analysis) {
  const { analyses } = await api.listAnalyses(analysis.run, true);
  const done = analyses.filter((a) => a.state === 'SUCCEEDED' && a.report && a.name !== analysis.name);
  const steps = [analysis];
  let current = analysis;
  while (current.model.effects.length && steps.length < 50) {
    const baseline = current.baseline?.effects || [];
    const mine = new Set(current.model.effects);
    let previous = baseline.length
      ? done.find((a) => effectsKey(a.model.effects) === effectsKey(baseline))
      : null;
    if (!previous) {
      const subsets = done.filter((a) => a.model.effects.length < mine.size && a.model.effects.every((e) => mine.has(e)));
      subsets.sort((a, b) => b.model.effects.length - a.model.effects.length || (a.createTime < b.createTime ? 1 : -1));
      previous = subsets[0];
    }
    if (!previous) break;
    steps.unshift(previous);
    current = previous;
  }
  return steps;
}

/** 'better' or 'worse' as `value` moved from `previous`, where less is better (or more, for a likelihood). */
function lower(value, previous, moreIsBetter = false) {
  if (previous === null || value === null || value === previous) return '';
  return (value < previous) !== moreIsBetter ? 'better' : 'worse';
}

function loopSection(analysis, steps) {
  const report = analysis.report;
  const channelNames = report.channels.map((c) => c.name);
  const rows = steps.map((step, i) => {
    const r = step.report;
    const prior = i > 0 ? steps[i - 1] : null;
    const added = prior ? step.model.effects.filter((e) => !prior.model.effects.includes(e)) : step.model.effects;
    const priorChannel = (n) => prior?.report.channels.find((c) => c.name === n);
    const white = r.channels.filter((c) => num(c.whitenessPValue) >= 0.05).length;
    const cell = (value, previous, digits = 4, moreIsBetter = false) =>
      h(`td.num.${lower(value, previous, moreIsBetter) || 'plain'}`, fmt(value, digits));
    return h(`tr.clickable${step.name === analysis.name ? '.selected' : ''}`, {
      dataset: { step: i, nis: num(r.nisMean), aic: num(r.aic), rmsTotal: r.channels.reduce((s, c) => s + (num(c.rms) || 0), 0) },
      onclick: () => step.name !== analysis.name && navigate(`#/${step.name}`),
    },
    h('td', String(i)),
    h('td', i === 0 && !added.length ? 'base model' : added.map((e) => `+ ${e}`).join(', ') || '(same model)'),
    channelNames.map((n) => cell(num(r.channels.find((c) => c.name === n)?.rms), num(priorChannel(n)?.rms), 3)),
    cell(num(r.nisMean), prior ? num(prior.report.nisMean) : null),
    cell(num(r.logLikelihood), prior ? num(prior.report.logLikelihood) : null, 6, true),
    cell(num(r.aic), prior ? num(prior.report.aic) : null, 6),
    cell(num(r.bic), prior ? num(prior.report.bic) : null, 6),
    h('td.num', `${white}/${r.channels.length}`));
  });
  const units = Object.fromEntries(report.channels.map((c) => [c.name, c.unit]));
  return section('The loop: every step',
    h('p.hint', 'Each row is one model of this run; green where a number fell from the step before. Whiteness: channels whose ',
      'normalised residuals pass Ljung–Box at 5 %. Click a row to open that step.'),
    table(['Step', 'Effects added', ...channelNames.map((n) => `RMS ${n} [${units[n]}]`), 'NIS', 'log L', 'AIC', 'BIC', 'White'],
      rows, { id: 'step-table' }),
    comparisonBlock(report.comparison),
    h('div.row', { style: 'margin-top:10px' },
      h('button.secondary#discover', {
        onclick: () => startAnalysis(analysis.run, analysis.model.effects, analysis.model.effects, true, analysis.name),
      }, 'Discover: add effects until none is significant'),
      h('span.hint', 'runs the whole loop on the server and lists its path')));
}

/** Model B against the model A it extends, as the engine compared them on one run. */
function comparisonBlock(comparison) {
  if (!comparison || !comparison.addedEffects?.length) return null;
  const arrow = (before, after, digits = 4, moreIsBetter = false) => {
    const b = num(before);
    const a = num(after);
    return h(`td.num.${lower(a, b, moreIsBetter) || 'plain'}`, `${fmt(b, digits)} → ${fmt(a, digits)}`);
  };
  const arrowP = (before, after) =>
    h(`td.num.${lower(num(after), num(before), true) || 'plain'}`, `${fmtP(before)} → ${fmtP(after)}`);
  return h('div#comparison',
    h('h3', `Before and after: + ${comparison.addedEffects.join(', ')}`),
    table(['Channel', 'RMS', 'NIS', 'whiteness p', 'fit %'], comparison.channels.map((c) => h('tr',
      h('td', c.name), arrow(c.rmsBefore, c.rmsAfter, 3), arrow(c.nisMeanBefore, c.nisMeanAfter),
      arrowP(c.whitenessPValueBefore, c.whitenessPValueAfter), arrow(c.fitPercentBefore, c.fitPercentAfter, 3, true)))),
    table(['', 'NIS', 'log L', 'AIC', 'BIC', 'LR realised', 'LR predicted'], [h('tr', h('td', 'model'),
      arrow(comparison.nisMeanBefore, comparison.nisMeanAfter), arrow(comparison.logLikelihoodBefore, comparison.logLikelihoodAfter, 6, true),
      arrow(comparison.aicBefore, comparison.aicAfter, 6), arrow(comparison.bicBefore, comparison.bicAfter, 6),
      h('td.num', fmt(comparison.realizedLr)), h('td.num', fmt(comparison.predictedLr)))]));
}

// --- per channel: measured vs predicted, residuals ---------------------------

function channelSection(analysis, before, state, cleanups) {
  const report = analysis.report;
  const tabs = h('div.tabs#channel-tabs');
  const legend1 = h('div.plot-legend');
  const legend2 = h('div.plot-legend');
  const plot1 = h('div.plot#plot-measured');
  const plot2 = h('div.plot#plot-residual');
  const info = h('p.hint');
  const faults = faultList(report, state, (f) => {
    const pad = Math.max((num(f.endS) - num(f.startS)) * 2, 5);
    load([num(f.startS) - pad, num(f.endS) + pad]);
  });
  const tableBody = report.channels.map((c) => h('tr.clickable', { dataset: { channel: c.name }, onclick: () => select(c.name) },
    h('td', c.name), h('td.num', `${fmt(c.rms)} ${c.unit}`), h('td.num', fmt(c.fitPercent)), h('td.num', fmt(c.nisMean)),
    h('td.num', fmtP(c.whitenessPValue)), h('td.num', `${fmt(100 * num(c.fractionOverGamma2))} %`),
    h('td.num', report.faultIntervals.filter((f) => f.channel === c.name).length)));
  const element = section('Measured against predicted, and residuals',
    tabs, legend1, plot1, legend2, plot2, info,
    h('h3', 'Per channel'),
    table(['Channel', 'RMS', 'Fit %', 'NIS', 'Whiteness p', 'β² > γ²', 'Fault intervals'], tableBody, { id: 'channel-table' }),
    faults.element);

  let u1 = null;
  let u2 = null;
  let range = null; // null: the whole run
  let plotted = null; // the channel u1 and u2 show
  let request = 0;
  cleanups.push(() => {
    destroy(u1);
    destroy(u2);
  });

  const shade = () => {
    const out = report.faultIntervals.filter((f) => f.channel === state.channel)
      .map((f) => ({ start: num(f.startS), end: num(f.endS), color: colors.fault }));
    for (const w of state.highlight?.where || []) {
      if (w.channel === state.channel) out.push({ start: num(w.startS), end: num(w.endS), color: colors.where });
    }
    return out;
  };

  function select(channel) {
    state.channel = channel;
    for (const b of tabs.children) b.classList.toggle('active', b.dataset.channel === channel);
    for (const row of tableBody) row.classList.toggle('selected', row.dataset.channel === channel);
    faults.fill();
    load(range);
  }

  async function fetchSeries(name, columns, zoom) {
    const series = await api.displaySeries(name, {
      channels: [state.channel], columns, startS: zoom?.[0], endS: zoom?.[1],
    });
    return { series, envelope: series.channels[0] || null };
  }

  async function load(zoom) {
    const mine = ++request;
    range = zoom;
    const columns = Math.min(Math.max(Math.round(plot1.clientWidth || 800), 200), 4000);
    let current;
    let previous = null;
    try {
      [current, previous] = await Promise.all([
        fetchSeries(analysis.name, columns, zoom),
        before ? fetchSeries(before.name, columns, zoom) : Promise.resolve(null),
      ]);
    } catch (error) {
      if (mine === request) info.replaceChildren(`The series could not be read: ${error.message}`);
      return;
    }
    if (mine !== request) return; // a newer request superseded this one
    const e = current.envelope;
    const unit = report.channels.find((c) => c.name === state.channel)?.unit || '';
    if (!e || !e.t.length) {
      destroy(u1);
      destroy(u2);
      u1 = u2 = null;
      plot1.replaceChildren(empty('This analysis stored no series for this channel.'));
      plot2.replaceChildren();
      return;
    }
    const n = (xs) => xs.map(num);
    const t = n(e.t);
    const data1 = [t, n(e.bandHigh), n(e.bandLow), n(e.predictedMax), n(e.predictedMin), n(e.measuredMax), n(e.measuredMin)];
    // The step before (when there is one) first, so this model's residual is drawn over it.
    const p = previous?.envelope;
    const sigma = [t, n(e.sigma3Max), n(e.sigma3Max).map((v) => (v === null ? null : -v))];
    const data2 = p && p.t.length
      ? uPlot.join([sigma, [n(p.t), n(p.residualMax), n(p.residualMin)], [t, n(e.residualMax), n(e.residualMin)]])
      : [...sigma, n(e.residualMax), n(e.residualMin)];
    const full = [num(current.series.seriesStartS), num(current.series.seriesEndS)];
    const shown = zoom || full;
    info.replaceChildren(
      `${e.decimated ? `${Number(e.epochs).toLocaleString()} epochs as a min/max envelope in ${e.t.length} columns`
        : `${Number(e.epochs).toLocaleString()} epochs, each drawn`} · ${fmt(shown[0])} … ${fmt(shown[1])} s of ${fmt(full[0])} … ${fmt(full[1])} s. `,
      'Drag across a plot to zoom (the server sends finer data); double-click for the whole run.');
    legend1.replaceChildren(
      h('span.area', { style: `--c:${colors.band}` }, 'predicted ± 3σ'),
      h('span', { style: `--c:${colors.predicted}` }, 'predicted'),
      h('span', { style: `--c:${colors.measured}` }, `measured [${unit}]`));
    legend2.replaceChildren(...[
      h('span.area', { style: `--c:${colors.band}` }, '± 3σ'),
      h('span', { style: `--c:${colors.residual}` }, p ? `residual, this model` : 'residual'),
      p ? h('span', { style: `--c:${colors.before}` }, `residual, the step before (${before.model.effects.join(', ') || 'base model'})`) : null,
      h('span.area', { style: `--c:${colors.fault}` }, 'fault intervals'),
      state.highlight ? h('span.area', { style: `--c:${colors.where}` }, `where ${state.highlight.name} shows`) : null,
    ].filter(Boolean));

    if (u1 && u2 && plotted === state.channel && u2.series.length === data2.length) {
      replaceData(u1, data1, { min: shown[0], max: shown[1] });
      replaceData(u2, data2, { min: shown[0], max: shown[1] });
      return;
    }
    destroy(u1);
    destroy(u2);
    plot1.replaceChildren();
    plot2.replaceChildren();
    plotted = state.channel;
    const common = {
      height: 230,
      shade,
      onZoom: (min, max) => load([min, max]),
      cursor: {
        sync: { key: `channels-${analysis.name}` },
        bind: { dblclick: () => () => { load(null); return null; } },
      },
      legend: { show: false },
      scales: { x: { time: false } },
    };
    u1 = plot(plot1, {
      ...common,
      axes: [secondsAxis, valueAxis(`${state.channel} [${unit}]`)],
      series: [{}, line('+3σ', 'rgba(120,120,120,0.5)', { width: 0.5 }), line('−3σ', 'rgba(120,120,120,0.5)', { width: 0.5 }),
        line('predicted max', colors.predicted), line('predicted min', colors.predicted),
        line('measured max', colors.measured), line('measured min', colors.measured)],
      bands: [{ series: [1, 2], fill: colors.band }, { series: [3, 4], fill: colors.predicted }, { series: [5, 6], fill: colors.measured }],
    }, data1);
    const residualSeries = [{}, line('+3σ', 'rgba(120,120,120,0.6)', { width: 0.5 }), line('−3σ', 'rgba(120,120,120,0.6)', { width: 0.5 })];
    const residualBands = [{ series: [1, 2], fill: colors.band }];
    if (data2.length > 5) {
      residualSeries.push(line('before max', colors.before), line('before min', colors.before));
      residualBands.push({ series: [3, 4], fill: colors.before });
    }
    const own = residualSeries.length;
    residualSeries.push(line('residual max', colors.residual), line('residual min', colors.residual));
    residualBands.push({ series: [own, own + 1], fill: colors.residual });
    u2 = plot(plot2, {
      ...common,
      axes: [secondsAxis, valueAxis(`residual [${unit}]`)],
      series: residualSeries,
      bands: residualBands,
    }, data2);
    if (zoom) {
      replaceData(u1, data1, { min: zoom[0], max: zoom[1] });
      replaceData(u2, data2, { min: zoom[0], max: zoom[1] });
    }
  }

  for (const c of report.channels) {
    tabs.append(h('button', { dataset: { channel: c.name }, onclick: () => select(c.name) }, c.name));
  }
  return {
    element,
    draw: () => select(state.channel),
    redraw: () => {
      u1?.redraw();
      u2?.redraw();
      load(range);
    },
    select,
  };
}

/** The fault intervals of the selected channel (all channels' count in the heading); a click zooms onto one. */
function faultList(report, state, onPick) {
  const body = h('div.scroll');
  const heading = h('h3');
  const fill = () => {
    const mine = report.faultIntervals.filter((f) => f.channel === state.channel);
    heading.textContent = `Fault intervals on ${state.channel}: ${mine.length} (all channels: ${report.faultIntervals.length})`;
    body.replaceChildren(mine.length
      ? table(['From', 'To', 'Kind', 'Peak statistic'], mine.map((f) =>
        h('tr.clickable', { onclick: () => onPick(f) },
          h('td.num', `${fmt(f.startS, 5)} s`), h('td.num', `${fmt(f.endS, 5)} s`), h('td', f.kind),
          h('td.num', fmt(f.peakStatistic)))), { id: 'fault-table' })
      : empty(`No fault interval on ${state.channel}: the model holds there within tolerance.`));
  };
  return { element: h('div', heading, h('p.hint', 'Click an interval to zoom onto it.'), body), fill };
}

// --- missing effects ------------------------------------------------------------

// Effect names of shared/spec/effects.md, offered while typing; the server is
// the judge of what it accepts.
const FAMILIES = {
  gyro_turn_on_bias: 'xyz', gyro_scale_factor: 'xyz', gyro_misalignment: 'pairs', gyro_g_sensitivity: 'all pairs',
  gyro_temp_coeff: 'xyz', gyro_yaw_harmonic: 'xyz', gyro_bias_rw: 'xyz', gyro_bias_second_order: 'xyz',
  acc_turn_on_bias: 'xyz', acc_scale_factor: 'xyz', acc_misalignment: 'pairs', acc_temp_coeff: 'xyz',
  acc_bias_rw: 'xyz', acc_bias_second_order: 'xyz',
};
const AXES = {
  xyz: ['x', 'y', 'z'],
  pairs: ['xy', 'xz', 'yx', 'yz', 'zx', 'zy'],
  'all pairs': ['xx', 'xy', 'xz', 'yx', 'yy', 'yz', 'zx', 'zy', 'zz'],
};
const CATALOGUE = Object.entries(FAMILIES).flatMap(([family, axes]) => [family, ...AXES[axes].map((a) => `${family}.${a}`)]);

/** Adding an effect by name: for one the ranking does not list, or a whole family. */
function addByName(analysis) {
  const input = h('input#add-effect-name', { list: 'effect-catalogue', placeholder: 'e.g. gyro_scale_factor.z', size: 32 });
  const message = h('span.worse.small');
  const add = async () => {
    const name = input.value.trim();
    if (!name) return;
    if (analysis.model.effects.includes(name)) {
      message.textContent = `${name} is in the model already`;
      return;
    }
    try {
      await startAnalysis(analysis.run, [...analysis.model.effects, name], analysis.model.effects, false, analysis.name);
    } catch (error) {
      message.textContent = error.message;
    }
  };
  input.addEventListener('keydown', (event) => event.key === 'Enter' && add());
  return h('div.row', { style: 'margin-top:10px' }, 'Add an effect by name: ', input,
    h('datalist#effect-catalogue', CATALOGUE.map((name) => h('option', { value: name }))),
    h('button.secondary#add-effect', { onclick: add }, 'Add and re-run'), message);
}

function candidatesSection(analysis, state, channelsView) {
  const report = analysis.report;
  const candidates = report.effectCandidates;
  if (!candidates.length) {
    return section('Missing effects', empty(
      'No candidate effect in this report: either every catalogue effect is in the model, or this server\'s engine does not rank candidates yet.'),
    addByName(analysis));
  }
  const rows = candidates.map((c, i) => {
    const where = [...(c.where || [])].sort((a, b) => num(b.share) - num(a.share));
    const row = h(
        'tr.candidate', {
          dataset: {effect: c.name, rank: i + 1},
          onmouseenter: () => highlight(c, false),
          onmouseleave: () => state.pinned || highlight(null, false),
          onclick: () => highlight(c, true),
        },
        h('td.num', String(i + 1)),
        h('td', h('strong', c.name),
          c.source === 'STRUCTURE'      ? h('div.small.muted', 'correlation structure') :
              c.source === 'LIKELIHOOD' ? h('div.small.muted', 'likelihood-ratio test') :
              c.source === 'GLR'        ? h('div.small.muted',
                                            `from ${fmt(c.onsetS, 5)} ± ${
                                         fmt(c.onsetStdS, 2)} s (likelihood ratio over onsets)`) :
                     c.source === 'RAW' ? h('div.small.muted',
                                            `from ${fmt(c.onsetS, 5)} ± ${
                                         fmt(c.onsetStdS, 2)} s (a ramp in the still samples)`) :
                     c.timeConstantS !== undefined ? h('div.small.muted',
                                            `settling from the start, τ ${fmt(c.timeConstantS, 3)} s`) :
                                          null,
          // Why a candidate is not ranked or has no p-value of its own: not excitable by this run,
          // far outside the linear range, refuted by the still samples, or left to a later model.
          c.note && (!c.identifiable || c.notTested) ? h('div.small.muted', c.note) : null),
        h('td.num', `${fmt(c.estimate)} ± ${fmt(c.stdError, 2)}${c.unit ? ` ${c.unit}` : ''       }`),
        h('td.num', fmt(c.statistic)), h('td.num', fmtP(c.pValueHolm || c.pValue)),
        h('td.num', fmt(c.predictedDeltaAic)),
        h('td', c.identifiable ? 'yes' : h('span.worse', 'no')),
        h('td.where-list',
          where.length ? where.slice(0, 3).map(
                                    (w) =>
                                        h('div',
                                          `${w.channel} ${fmt(w.startS, 4)}–${fmt(w.endS, 4)} s ${
                                       w.motion} · ${fmt(100 * num(w.share), 2)} %`)) :
                                '—',
          c.correlatedWith?.length ?
                     h('div', `not told apart from ${c.correlatedWith.join(', ')}`) :
                     null),
               h('td',
                 h(
                     'button.add', {
                       disabled: analysis.model.effects.includes(c.name),
                       title: `Re-run with ${c.name} added to the model`,
                onclick:
                    async (event) => {
                             event.stopPropagation();
                      event.target.disabled = true;
                      // A fault goes in at the onset the scan estimated, a warm-up at its time constant.
                      const added = c.onsetS !== undefined        ? `${c.name}@${num(c.onsetS)}` :
                                    c.timeConstantS !== undefined ? `${c.name}@${num(c.timeConstantS)}` :
                                                                    c.name;
                      await startAnalysis(
                                 analysis.run, [...analysis.model.effects, added], analysis.model.effects,
                                 false, analysis.name);
                    },
              },
              'Add')));
    return row;
  });

  function highlight(candidate, pin) {
    state.highlight = candidate;
    state.pinned = pin && candidate ? candidate.name : null;
    for (const r of rows) r.classList.toggle('selected', candidate && r.dataset.effect === candidate.name);
    const top = candidate?.where?.length ? [...candidate.where].sort((a, b) => num(b.share) - num(a.share))[0] : null;
    if (pin && top && top.channel !== state.channel) channelsView.select(top.channel);
    else channelsView.redraw();
  }

  return section(
      'Missing effects, most significant first',
      h('p.hint',
        'Every catalogue effect the model lacks, scored from this pass. Hover or click a row to see where in the test it shows ',
        '(highlighted on the plots above); Add re-runs with it and compares.'),
      table(
          [
            '#', 'Effect', 'Estimate ± SE', 'Statistic', 'p (Holm)', 'ΔAIC if added', 'Ranked',
            'Where it shows', ''
          ],
          rows, {id: 'candidate-table'}),
      addByName(analysis));
}

function discoverySection(report) {
  if (!report.discovery?.length) return null;
  return section('Discovery: the effects added one by one',
    table(['Step', 'Effect added', 'Estimate ± SE', 'Statistic', 'p (Holm)', 'NIS', 'log L', 'AIC', 'BIC'],
      report.discovery.map((s, i) => {
        const prior = i > 0 ? report.discovery[i - 1] : null;
        return h('tr', h('td', String(s.step)), h('td', s.effect),
          h('td.num', `${fmt(s.estimate)} ± ${fmt(s.stdError, 2)} ${s.unit || ''}`), h('td.num', fmt(s.statistic)),
          h('td.num', fmtP(s.pValue)),
          h(`td.num.${lower(num(s.nisMean), prior ? num(prior.nisMean) : null) || 'plain'}`, fmt(s.nisMean)),
          h(`td.num.${lower(num(s.logLikelihood), prior ? num(prior.logLikelihood) : null, true) || 'plain'}`, fmt(s.logLikelihood, 6)),
          h(`td.num.${lower(num(s.aic), prior ? num(prior.aic) : null) || 'plain'}`, fmt(s.aic, 6)),
          h('td.num', fmt(s.bic, 6)));
      }), { id: 'discovery-table' }));
}
