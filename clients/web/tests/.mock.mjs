import { chromium } from 'playwright-core';
const [base, name, out] = process.argv.slice(2);
const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', headless: true, args: ['--no-sandbox', '--disable-gpu'] });
const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
page.on('request', (r) => { if (r.url().includes('display')) console.log('REQ', r.url()); });
page.on('requestfinished', (r) => { if (r.url().includes('display')) console.log('DONE', r.url()); });
page.on('console', (m) => console.log('console', m.text()));
page.on('pageerror', (e) => console.log('pageerror:', e.message, e.stack));
const real = await (await fetch(`${base}/v1/${name}`)).json();
const r = real.report;
const lags = Array.from({ length: 60 }, (_, j) => j);
r.effectCandidates = [
  { name: 'gyro_scale_factor.y', family: 'gyro_scale_factor', statistic: 812.3, pValue: 1e-30, pValueHolm: 1e-29, estimate: 2.9e-4, stdError: 1.1e-5, unit: '', identifiable: true, predictedDeltaAic: -790, correlatedWith: [], source: 'SCORE',
    where: [{ channel: 'vel_e', startS: 900, endS: 1900, motion: 'turning', share: 0.46 }, { channel: 'vel_n', startS: 3100, endS: 3600, motion: 'turning', share: 0.21 }] },
  { name: 'gyro_misalignment.xy', family: 'gyro_misalignment', statistic: 33.1, pValue: 1e-7, pValueHolm: 2e-6, estimate: 1.2e-5, stdError: 4e-6, unit: '', identifiable: true, predictedDeltaAic: -29, correlatedWith: ['gyro_misalignment.xz'], source: 'SCORE', where: [] },
  { name: 'acc_temp_coeff.z', family: 'acc_temp_coeff', statistic: 0.4, pValue: 0.5, pValueHolm: 1, estimate: 0, stdError: 1e-6, unit: 'm/s^2/degC', identifiable: false, predictedDeltaAic: 2, correlatedWith: [], source: 'SCORE', where: [] },
];
r.identified = [{ name: 'gyro_bias_gm.x.sigma', value: 4.9e-8, stdError: 3e-9, method: 'ACF', unit: 'rad/s', aPriori: 4.8e-8 }];
const expo = lags.map((j) => Math.exp(-j / 15));
r.correlation = [{ state: 'gyro_bias_gm.x', dtS: 10, acf: expo.map((v, j) => v + 0.05 * Math.sin(j)), band: lags.map((j) => 0.1 + 0.003 * j), errorAcf: [], bestFamily: 'exponential', resolved: true,
  fits: [{ family: 'exponential', expected: expo, aic: 1, bic: 2, lrPValue: 1, parameters: [] }, { family: 'exponential-cosine', expected: expo.map((v, j) => v * Math.cos(j / 20)), aic: 3, bic: 5, lrPValue: 0.3, parameters: [] }] }];
const taus = Array.from({ length: 20 }, (_, i) => 0.1 * 1.6 ** i);
r.allan = [{ channel: 'gyro_x', unit: 'rad/s', tauS: taus, deviation: taus.map((t) => 5e-7 / Math.sqrt(t) + 1e-9 * Math.sqrt(t)), deviationLow: taus.map((t) => 0.8 * (5e-7 / Math.sqrt(t) + 1e-9 * Math.sqrt(t))), deviationHigh: taus.map((t) => 1.25 * (5e-7 / Math.sqrt(t) + 1e-9 * Math.sqrt(t))), fitted: taus.map((t) => 5e-7 / Math.sqrt(t)), terms: [{ name: 'gyro_arw.x', value: 5e-7, stdError: 1e-8, unit: 'rad/sqrt(s)' }] }];
r.comparison = { baselineEffects: [], addedEffects: ['gyro_scale_factor.y'], channels: r.channels.map((c) => ({ name: c.name, rmsBefore: c.rms * 1.3, rmsAfter: c.rms, nisMeanBefore: c.nisMean * 1.5, nisMeanAfter: c.nisMean, whitenessPValueBefore: 0, whitenessPValueAfter: 0.2, fitPercentBefore: 50, fitPercentAfter: 70 })), nisMeanBefore: 189, nisMeanAfter: 144, logLikelihoodBefore: -3.1e6, logLikelihoodAfter: -2.3e6, aicBefore: 6.2e6, aicAfter: 4.6e6, bicBefore: 6.2e6, bicAfter: 4.6e6, realizedLr: 1.6e6, predictedLr: 1.5e6 };
r.discovery = [{ step: 1, effect: 'gyro_scale_factor.y', estimate: 3e-4, stdError: 1e-5, unit: '', statistic: 812, pValue: 1e-29, nisMean: 144, logLikelihood: -2.3e6, aic: 4.6e6, bic: 4.6e6, channels: [] }];
await page.route(`**/v1/${name}`, (route) => route.fulfill({ json: real }));
await page.goto(`${base}/#/${name}`);
await page.locator('#candidate-table').waitFor();
await page.waitForTimeout(3000);
if (!process.env.NOCLICK) await page.locator('#candidate-table tbody tr').first().click();
const t0 = Date.now(); await page.evaluate(() => 1); console.log('evaluate took', Date.now() - t0);
console.log('plots', await page.locator('#plot-residual canvas').count(), await page.locator('#plot-measured').count(), await page.locator('#channel-tabs').count());
await page.waitForTimeout(3000);
await page.screenshot({ path: out, fullPage: true });
await page.locator('#plot-measured').locator('xpath=..').screenshot({ path: out.replace('.png', '-channels.png') });
await browser.close();
