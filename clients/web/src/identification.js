// Identification of the unit's sensor parameters: the identified values, the
// autocorrelation of each drift's smoothed estimate with the fitted
// correlation families (seed eq. 8–9), and the Allan deviation of the static
// segments with its confidence interval and the fitted IEEE 952 terms.
import { num } from './api.js';
import { h, fmt, fmtP, empty, section, table } from './dom.js';
import { plot, destroy, line, markers, colors, valueAxis } from './charts.js';

export function identificationSection(report, cleanups) {
  const plots = [];
  cleanups.push(() => plots.forEach(destroy));
  const after = []; // plots are drawn once their containers are in the page
  const element = section('Identification',
    identifiedTable(report.identified),
    h('h3', 'Autocorrelation of the smoothed drifts'),
    acfPlots(report.correlation, after),
    h('h3', 'Allan deviation'),
    allanPlots(report.allan, after));
  requestAnimationFrame(() => after.forEach((draw) => plots.push(draw())));
  return element;
}

// Whether the run tells the parameter (IdentifiedParameter.observability,
// docs/MULTI_POSITION.md); '—' where it was not judged (methods other than FILTER).
const OBSERVABILITY = {
  OBSERVABLE: 'observable',
  NOT_EXCITED: 'not excited',
  INSEPARABLE: 'inseparable',
  WEAKLY_DETERMINED: 'weakly determined',
};

function observabilityCell(p) {
  const words = OBSERVABILITY[p.observability];
  if (!words) return h('td', '—');
  const told = p.observability === 'OBSERVABLE';
  return h(told ? 'td' : 'td.warn', { title: p.observabilityNote || '' },
    told || !p.observabilityNote ? words : `${words}: ${p.observabilityNote}`);
}

function identifiedTable(identified) {
  if (!identified.length) return empty('No identified parameter in this report yet.');
  return table(['Parameter', 'Value ± SE', 'Method', 'A priori', 'Observability'], identified.map((p) => h('tr',
    h('td', p.name), h('td.num', `${fmt(p.value)} ± ${fmt(p.stdError, 2)} ${p.unit || ''}`), h('td', p.method),
    h('td.num', p.aPriori === undefined ? '—' : fmt(p.aPriori)), observabilityCell(p))), { id: 'identified-table' });
}

function acfPlots(curves, after) {
  if (!curves.length) return empty('No correlation curve in this report yet.');
  return h('div.grid2', curves.map((curve) => {
    const container = h('div');
    const dt = num(curve.dtS) || 1;
    const lags = curve.acf.map((_, j) => j * dt);
    const exponential = curve.fits.find((f) => f.family === 'exponential');
    // The band is ±1.96σ of R̂_j under the exponential fit: drawn around that fit.
    const centre = exponential ? exponential.expected.map(num) : lags.map(() => 0);
    const band = curve.band.map(num);
    const data = [lags, curve.acf.map(num),
      band.map((b, j) => (b === null ? null : (centre[j] || 0) + b)),
      band.map((b, j) => (b === null ? null : (centre[j] || 0) - b))];
    const series = [{}, markers('R̂ (smoothed estimate)', '#1d2430', 3),
      line('band +', 'rgba(120,120,120,0.6)', { width: 0.5 }), line('band −', 'rgba(120,120,120,0.6)', { width: 0.5 })];
    curve.fits.forEach((fit, i) => {
      data.push(fit.expected.map(num));
      const best = fit.family === curve.bestFamily;
      series.push(line(`${fit.family}${best ? ' (best, BIC)' : ''} · p ${fmtP(fit.lrPValue)}`, colors.fits[i % colors.fits.length],
        { width: best ? 2.5 : 1, dash: best ? undefined : [4, 3] }));
    });
    after.push(() => plot(container, {
      height: 200,
      scales: { x: { time: false } },
      axes: [{ label: 'lag [s]', labelSize: 18, size: 34 }, valueAxis('R̂')],
      series,
      bands: [{ series: [2, 3], fill: colors.band }],
    }, data));
    return h('div', h('div.small', h('strong', curve.state), ` · best fit: ${curve.bestFamily || '—'}`,
      curve.resolved ? '' : ' · this run does not resolve this drift'), container);
  }));
}

function allanPlots(curves, after) {
  if (!curves.length) return empty('No Allan deviation in this report yet (it needs static segments).');
  return h('div.grid2', curves.map((curve) => {
    const container = h('div');
    const positive = (v) => {
      const n = num(v);
      return n !== null && n > 0 ? n : null; // a log scale has no place for 0
    };
    const data = [curve.tauS.map(num), curve.deviation.map(positive), curve.deviationHigh.map(positive),
      curve.deviationLow.map(positive), curve.fitted.map(positive)];
    after.push(() => plot(container, {
      height: 220,
      scales: { x: { time: false, distr: 3 }, y: { distr: 3 } },
      axes: [{ label: 'τ [s]', labelSize: 18, size: 34 }, valueAxis(`σ(τ) [${curve.unit}]`, 80)],
      series: [{}, line('Allan deviation', '#1f6fd1', { width: 1.5, points: { show: true, size: 4 } }),
        line('upper', 'rgba(31,111,209,0.35)', { width: 0.5 }), line('lower', 'rgba(31,111,209,0.35)', { width: 0.5 }),
        line('fitted', '#e07b00', { width: 1.5, dash: [5, 3] })],
      bands: [{ series: [2, 3], fill: 'rgba(31,111,209,0.12)' }],
    }, data));
    return h('div', h('div.small', h('strong', curve.channel), ' · ',
      curve.terms.length ? curve.terms.map((t) => `${t.name} ${fmt(t.value)} ± ${fmt(t.stdError, 2)} ${t.unit || ''}`).join(' · ') : 'no fitted term'),
    container);
  }));
}
