// End to end: the page in headless Chromium (Debian's, driven by
// playwright-core) against a real insdiagd on a throwaway database.
//   - a refused file shows the line and column the server names;
//   - a simulated run with a hidden effect: upload, the top missing effect,
//     Add, the re-run's progress, and the step table with the error falling;
//   - zooming a residual plot asks the server for finer data;
//   - a unit's history: a plot per parameter with its trend, reachable from the unit's run.
// Screenshots go to $INSDIAG_ARTIFACTS_DIR (build/test-artifacts/web).
//
// CTest runs this (label e2e) under scripts/with-throwaway-pg.sh with
// INSDIAGD, INSDIAG_CLI, INSDIAG_WEB_DIR and INSDIAG_ARTIFACTS_DIR set
// (clients/web/CMakeLists.txt).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { mkdtempSync, mkdirSync, readFileSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { chromium } from 'playwright-core';

const env = (name) => {
  const value = process.env[name];
  if (!value) throw new Error(`${name} is not set: run this test through ctest (clients/web/CMakeLists.txt)`);
  return value;
};

const databaseUrl = process.env.INSDIAG_TEST_DATABASE_URL;
const skipReason = databaseUrl ? false : 'INSDIAG_TEST_DATABASE_URL is not set (scripts/with-throwaway-pg.sh sets it)';
// The hidden effect: the `full` profile turns the table about every axis, which excites it.
const HIDDEN_EFFECT = 'gyro_scale_factor.y';
const ANALYSIS_TIMEOUT_MS = 8 * 60_000;

let workDir;
let artifacts;
let database;
let server;
let serverLog = '';
let baseUrl;
let browser;
let page;
let runCsv;
let baseAnalysisUrl;
let adminToken;
const foreignRequests = []; // anything the page asked of another origin
const createRequests = []; // the bodies of the analyses the page created
const firstStates = new Map(); // analysis name → its state in the page's first GET of it
const watched = new Set(); // analyses whose :watch stream the page opened

function psql(sql, url = databaseUrl) {
  execFileSync('psql', [url, '-v', 'ON_ERROR_STOP=1', '-qc', sql], { stdio: 'pipe' });
}

/** The throwaway cluster's URL with another database name (a libpq URL: its host may be empty). */
function urlOf(name) {
  return databaseUrl.replace(/^(postgres(?:ql)?:\/\/[^/?]*)\/[^?]*/, `$1/${name}`);
}

async function startServer() {
  const child = spawn(env('INSDIAGD'), [
    '--database-url', urlOf(database), '--data-dir', path.join(workDir, 'data'), '--grpc-port', '0', '--http-port', '0', '--bind', '127.0.0.1',
    '--workers', '1', '--fleet-refresh-seconds', '0', '--web-dir', env('INSDIAG_WEB_DIR'),
  ], { cwd: workDir, stdio: ['ignore', 'pipe', 'pipe'] });
  child.stdout.on('data', (d) => { serverLog += d; });
  child.stderr.on('data', (d) => { serverLog += d; });
  const port = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`insdiagd did not start:\n${serverLog}`)), 60_000);
    const look = () => {
      const match = serverLog.match(/listening grpc=\S+ http=[^ :]+:(\d+)/);
      if (match) {
        clearTimeout(timer);
        resolve(Number(match[1]));
      }
    };
    child.stdout.on('data', look);
    child.on('exit', (code) => reject(new Error(`insdiagd exited (${code}):\n${serverLog}`)));
  });
  return { child, port };
}

async function screenshot(name) {
  await page.screenshot({ path: path.join(artifacts, `${name}.png`), fullPage: true });
}

before(async () => {
  if (skipReason) return;
  workDir = mkdtempSync(path.join(tmpdir(), 'insdiag-web-e2e-'));
  artifacts = process.env.INSDIAG_ARTIFACTS_DIR || path.join(workDir, 'artifacts');
  mkdirSync(artifacts, { recursive: true });
  database = `web_e2e_${process.pid}_${Date.now()}`;
  psql(`CREATE DATABASE ${database}`);

  runCsv = path.join(workDir, 'hidden-scale-factor.csv');
  // 10 Hz keeps the upload small; the analysis still has 6,078 epochs per channel.
  execFileSync(env('INSDIAG_CLI'), ['simulate', runCsv, '--profile', 'full', '--effect', `${HIDDEN_EFFECT}=3e-4`,
    '--seed', '7', '--rate', '10', '--serial', 'INS-WEB-1'], { stdio: 'pipe' });

  ({ child: server, port: baseUrl } = await startServer());
  baseUrl = `http://127.0.0.1:${baseUrl}`;
  // insdiagd's first start on this database wrote an admin token into its data directory.
  adminToken = readFileSync(path.join(workDir, 'data', 'admin-token'), 'utf8').trim();
  browser = await chromium.launch({
    executablePath: process.env.INSDIAG_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
      '--no-first-run', '--disable-sync'],
  });
  page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  // Nothing but insdiagd may be asked for anything: the page is self-contained.
  page.on('request', (request) => {
    const url = new URL(request.url());
    if (url.origin !== baseUrl && url.protocol !== 'data:') foreignRequests.push(request.url());
  });
  page.on('pageerror', (error) => { serverLog += `\n[page error] ${error.message}`; });
  page.on('request', (request) => {
    const watch = new URL(request.url()).pathname.match(/^\/v1\/(analyses\/[^/:]+):watch$/);
    if (watch) watched.add(watch[1]);
  });
  page.on('request', (request) => {
    if (request.method() === 'POST' && new URL(request.url()).pathname === '/v1/analyses') {
      createRequests.push(JSON.parse(request.postData() || '{}'));
    }
  });
  page.on('response', async (response) => {
    const get = new URL(response.url()).pathname.match(/^\/v1\/(analyses\/[^/:]+)$/);
    if (!get || response.request().method() !== 'GET' || firstStates.has(get[1])) return;
    firstStates.set(get[1], 'pending');
    try {
      firstStates.set(get[1], (await response.json()).state);
    } catch { /* a page that moved on */ }
  });
});

after(async () => {
  if (skipReason) return;
  await browser?.close().catch(() => {});
  if (server && server.exitCode === null) {
    server.kill('SIGTERM');
    await new Promise((resolve) => server.once('exit', resolve));
  }
  writeFileSync(path.join(artifacts, 'insdiagd.log'), serverLog);
  try {
    psql(`DROP DATABASE IF EXISTS ${database}`);
  } catch { /* the cluster goes away with the test run anyway */ }
  rmSync(workDir, { recursive: true, force: true });
});

test('the page is served by insdiagd with its charting library, nothing from elsewhere', { skip: skipReason }, async () => {
  const response = await page.goto(`${baseUrl}/`);
  assert.equal(response.status(), 200);
  // Nothing of the server's data without a token: the page asks for one.
  await page.locator('dialog#sign-in').waitFor();
  await page.fill('#token-input', adminToken);
  await page.click('#sign-in-button');
  await page.getByText('administrator (first start) (admin)').waitFor();
  await page.getByRole('heading', { name: 'Runs', exact: true }).waitFor();
  await page.getByText('No runs yet').waitFor();
  const library = await page.request.get(`${baseUrl}/vendor/uPlot.esm.js`);
  assert.equal(library.status(), 200);
  assert.match(library.headers()['content-type'], /javascript/);
  assert.deepEqual(foreignRequests, []);
});

test('a refused file shows the line and column the server names', { skip: skipReason }, async () => {
  // Line 40 of a copy of the run gets a gyro_y that is not a number.
  const lines = readFileSync(runCsv, 'utf8').split('\n');
  const header = lines.findIndex((l) => l.startsWith('t,'));
  assert.ok(header >= 0 && header < 30, 'the bench-run file has its column header near the top');
  const bad = 39; // 0-based: line 40
  const fields = lines[bad].split(',');
  const gyroY = lines[header].split(',').indexOf('gyro_y');
  fields[gyroY] = 'abc';
  const column = fields.slice(0, gyroY).join(',').length + 2;
  lines[bad] = fields.join(',');
  const badCsv = path.join(workDir, 'bad-value.csv');
  writeFileSync(badCsv, lines.join('\n'));

  await page.goto(`${baseUrl}/#/`);
  await page.locator('#dropzone input[type=file], input[type=file]').first().setInputFiles(badCsv);
  const refusal = page.locator('#upload-error');
  await refusal.waitFor();
  await assert.doesNotReject(refusal.getByText(`Line 40, column ${column}`).waitFor({ timeout: 5000 }));
  assert.match(await refusal.innerText(), new RegExp(`bad-value\\.csv:40:${column}`));
  assert.match(await refusal.locator('pre').innerText(), /abc/); // the offending line, with a caret under it
  await screenshot('refused-upload');
  // Nothing was stored.
  await page.goto(`${baseUrl}/#/`);
  await page.getByText('No runs yet').waitFor();
});

test('upload a run with a hidden effect, add it, and see the error fall', { skip: skipReason, timeout: 3 * ANALYSIS_TIMEOUT_MS }, async () => {
  await page.goto(`${baseUrl}/#/`);
  await page.locator('input[type=file]').first().setInputFiles(runCsv);
  // The upload starts the base model's analysis and opens it: progress, then the verdict.
  await page.waitForURL(/#\/analyses\//, { timeout: 120_000 });
  await page.locator('#progress, #verdict').first().waitFor();
  if (await page.locator('#progress').count()) await screenshot('base-model-running');
  await page.locator('#verdict').waitFor({ timeout: ANALYSIS_TIMEOUT_MS });
  baseAnalysisUrl = page.url();
  await page.locator('#plot-residual canvas').first().waitFor();
  await page.locator('#step-table tbody tr').first().waitFor();
  assert.equal(await page.locator('#step-table tbody tr').count(), 1);
  await screenshot('base-model');

  // The plots show the series decimated to the plot's width; zooming asks for finer data.
  const info = page.locator('#plot-residual + p.hint');
  await info.getByText(/epochs/).waitFor();
  const wholeRun = await info.innerText();
  assert.match(wholeRun, /min\/max envelope in \d+ columns/);
  const over = page.locator('#plot-residual .u-over');
  // A user scrolls to the plot before dragging on it: mouse events land on
  // the viewport only.
  await over.scrollIntoViewIfNeeded();
  const box = await over.boundingBox();
  await page.mouse.move(box.x + box.width * 0.40, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.45, box.y + box.height / 2, { steps: 5 });
  await page.mouse.up();
  await page.waitForFunction((before) => {
    const text = document.querySelector('#plot-residual + p.hint')?.innerText || '';
    return text !== before && /epochs/.test(text);
  }, wholeRun, { timeout: 20_000 });
  const zoomed = await info.innerText();
  const epochs = (text) => Number(text.match(/^([\d,]+) epochs/)[1].replace(/,/g, ''));
  assert.ok(epochs(zoomed) < epochs(wholeRun), `zoomed: ${zoomed} / whole: ${wholeRun}`);
  await screenshot('zoomed');

  // Add the hidden effect, see the re-run's progress, then the step table.
  await page.locator('#add-effect-name').fill(HIDDEN_EFFECT);
  await page.locator('#add-effect').click();
  await expectLoopStep(baseAnalysisUrl, 'after-adding-the-effect');
});

test('the hidden effect is the top missing effect, and its Add button re-runs with it', {
  skip: skipReason,
  timeout: 2 * ANALYSIS_TIMEOUT_MS,
}, async () => {
  assert.ok(baseAnalysisUrl, 'the previous test opened the base model\'s analysis');
  await page.goto(baseAnalysisUrl);
  await page.locator('#verdict').waitFor();
  // The missing effects, most significant first: the hidden one on top.
  const top = page.locator('#candidate-table tbody tr').first();
  await top.waitFor({ timeout: 10_000 });
  assert.equal(await top.getAttribute('data-effect'), HIDDEN_EFFECT);
  await top.hover(); // its segments are shaded on the plots
  await page.getByText(`where ${HIDDEN_EFFECT} shows`).waitFor();
  await screenshot('top-candidate');
  await top.getByRole('button', { name: 'Add' }).click();
  await expectLoopStep(baseAnalysisUrl, 'after-adding-the-top-candidate');
});

test('a unit that warms up: the warm-up is listed with its time constant, and its Add puts it in at that τ', {
  skip: skipReason,
  timeout: 2 * ANALYSIS_TIMEOUT_MS,
}, async () => {
  // A navigation-grade unit on a still table whose vertical accelerometer
  // settles by 3 mg (ten drift σ) with τ 300 s after power-up.
  const warmUpCsv = path.join(workDir, 'warm-up.csv');
  execFileSync(env('INSDIAG_CLI'), ['simulate', warmUpCsv, '--profile', 'static', '--effect',
    'acc_warm_up.z=3e-3,300', '--seed', '7', '--rate', '10', '--serial', 'INS-WEB-2'], { stdio: 'pipe' });
  await page.goto(`${baseUrl}/#/`);
  await page.locator('input[type=file]').first().setInputFiles(warmUpCsv);
  await page.waitForURL(/#\/analyses\//, { timeout: 120_000 });
  await page.locator('#verdict').waitFor({ timeout: ANALYSIS_TIMEOUT_MS });
  const fromUrl = page.url();
  const row = page.locator('#candidate-table tbody tr[data-effect="acc_warm_up.z"]');
  await row.waitFor({ timeout: 10_000 });
  const listed = await row.innerText();
  const tau = Number(listed.match(/settling from the start, τ ([\d.,]+) s/)[1].replace(/,/g, ''));
  assert.ok(tau > 100 && tau < 900, `the listed time constant ${tau} s is the settling's (300 s)`);
  await row.getByRole('button', { name: 'Add' }).click();
  await page.waitForURL((url) => url.toString() !== fromUrl && /#\/analyses\//.test(url.toString()));
  const added = (createRequests.at(-1)?.model?.effects || []).find((e) => e.startsWith('acc_warm_up.z@'));
  assert.ok(added, `the Add asked for the warm-up at its time constant: ${JSON.stringify(createRequests.at(-1))}`);
  await page.locator('#verdict').waitFor({ timeout: ANALYSIS_TIMEOUT_MS });
  assert.match(await page.locator('#model-effects').innerText(), /acc_warm_up\.z@/);
  const rows = page.locator('#step-table tbody tr');
  await rows.nth(1).waitFor();
  const nis = async (i) => Number(await rows.nth(i).getAttribute('data-nis'));
  assert.ok(await nis(1) < await nis(0), 'mean NIS falls when the warm-up is added');
  await screenshot('after-adding-the-warm-up');
  assert.deepEqual(foreignRequests, []);
});

/**
 * After an Add on the analysis at `fromUrl`: the next analysis opens, shows
 * its progress and then the step table, whose second step has the hidden
 * effect with mean NIS and AIC lower than the base model's, and the residual
 * plot overlays the step before.
 */
async function expectLoopStep(fromUrl, shot) {
  await page.waitForURL((url) => url.toString() !== fromUrl && /#\/analyses\//.test(url.toString()));
  // The Add starts from the analysis it was made on: its model is not identified again.
  assert.equal(createRequests.at(-1)?.baseAnalysis, `analyses/${fromUrl.split('#/analyses/')[1]}`);
  await page.locator('#progress, #verdict').first().waitFor();
  if (await page.locator('#progress').count()) await screenshot(`${shot}-running`);
  await page.locator('#verdict').waitFor({ timeout: ANALYSIS_TIMEOUT_MS });
  // An analysis the page found queued or running was followed through its watch stream.
  const name = `analyses/${page.url().split('#/analyses/')[1]}`;
  if (['QUEUED', 'RUNNING'].includes(firstStates.get(name))) {
    assert.ok(watched.has(name), `the page showed ${name}'s progress from ${name}:watch`);
  }
  assert.match(await page.locator('#model-effects').innerText(), new RegExp(HIDDEN_EFFECT.replace('.', '\\.')));
  const rows = page.locator('#step-table tbody tr');
  await rows.nth(1).waitFor();
  assert.equal(await rows.count(), 2);
  const step = async (i, key) => Number(await rows.nth(i).getAttribute(`data-${key}`));
  assert.ok(await step(1, 'nis') < await step(0, 'nis'), 'mean NIS falls when the hidden effect is added');
  assert.ok(await step(1, 'aic') < await step(0, 'aic'), 'AIC falls when the hidden effect is added');
  assert.match(await rows.nth(1).innerText(), new RegExp(`\\+ ${HIDDEN_EFFECT.replace('.', '\\.')}`));
  // The before and after residuals, overlaid.
  await page.getByText('residual, the step before').waitFor();
  await page.locator('#plot-residual canvas').first().waitFor();
  await screenshot(shot);
  assert.deepEqual(foreignRequests, []);
}

/**
 * A unit's history written into the test's database as the fleet generator
 * writes one (runs without samples, succeeded analyses with their identified
 * parameters): gyro x's drift σ grows by a quarter of nominal a week over five
 * weekly runs, its turn-on bias scatters without a trend.
 */
const HISTORY_SERIAL = 'INS-HIST-1';
const DRIFTING = 'gyro_bias_gm.x.sigma';
const STABLE = 'gyro_turn_on_bias.x';

function seedHistory() {
  const sigmaNominal = 4.84813681109536e-08;
  const bias = [1.0e-6, 1.1e-6, 0.95e-6, 1.05e-6, 0.98e-6];
  const runs = bias.map((b, i) => {
    const sigma = sigmaNominal * (1 + 0.25 * i);
    return `WITH r AS (INSERT INTO runs (unit_id, format, unit_serial, unit_type, site_latitude_deg, site_longitude_deg,
        site_height_m, has_temperature, sample_count, nominal_interval_s, duration_s, first_t, sha256, test_time)
      SELECT unit_id, 'insdiag-bench-run/1', '${HISTORY_SERIAL}', 'INS-2000', 55.7, 37.6, 150, false, 0, 0.1, 3600, 0, 'seed',
        timestamptz '2026-01-05 08:00+00' + interval '${7 * i} days' FROM units WHERE serial = '${HISTORY_SERIAL}'
      RETURNING run_id, unit_id),
    a AS (INSERT INTO analyses (run_id, unit_id, state, verdict, end_time)
      SELECT run_id, unit_id, 'SUCCEEDED', 'GOOD', now() FROM r RETURNING analysis_id)
    INSERT INTO identified_parameters (analysis_id, parameter_id, value, std_error, method)
      SELECT a.analysis_id, n.parameter_id, v.value, v.se, 'ACF' FROM a,
        (VALUES ('${DRIFTING}', ${sigma}::float8, ${0.05 * sigma}::float8), ('${STABLE}', ${b}::float8, 1e-7::float8))
          AS v(name, value, se) JOIN parameter_names n USING (name);`;
  });
  psql(`INSERT INTO units (serial, unit_type) VALUES ('${HISTORY_SERIAL}', 'INS-2000');
    INSERT INTO parameter_names (name) VALUES ('${DRIFTING}'), ('${STABLE}') ON CONFLICT DO NOTHING;
    ${runs.join('\n')}`, urlOf(database));
}

test('a unit\'s history: from its run to a plot per parameter with the trend, the drifting one significant', {
  skip: skipReason,
}, async () => {
  seedHistory();
  // Signed in, whether or not the first test ran (node --test-name-pattern).
  await page.goto(`${baseUrl}/`);
  await page.evaluate((token) => sessionStorage.setItem('insdiag.token', token), adminToken);
  await page.goto(`${baseUrl}/#/`);
  await page.reload();
  // The runs list links each unit to its history; so does a run's page.
  const row = page.locator('#run-list tr', { hasText: HISTORY_SERIAL }).first();
  await row.waitFor();
  await row.locator('td').first().click();
  await page.waitForURL(/#\/runs\//);
  await page.locator('#unit-history').click();
  await page.waitForURL(new RegExp(`#/units/${HISTORY_SERIAL}/history$`));
  await page.locator('#history-summary').getByText('5 runs, 5 with a succeeded analysis').waitFor();
  assert.equal(await page.locator('#history-runs tbody tr').count(), 5);

  const drifting = page.locator(`#history-statistics tr[data-parameter="${DRIFTING}"]`);
  const stable = page.locator(`#history-statistics tr[data-parameter="${STABLE}"]`);
  await drifting.waitFor();
  assert.ok(Number(await drifting.getAttribute('data-trend-p')) < 1e-6, 'σ growing a quarter of nominal a week is a trend');
  assert.ok(Number(await stable.getAttribute('data-trend-p')) > 0.01, 'the scattering bias is not');
  assert.match(await stable.innerText(), /\d/); // its repeatability is shown

  // A plot per parameter: the values with their SE bars and the trend line.
  for (const name of [DRIFTING, STABLE]) {
    await page.locator(`.history-plot[data-parameter="${name}"] canvas`).first().waitFor();
  }
  assert.equal(await page.locator('#history-plots .history-plot').count(), 2);
  await page.getByText(/trend .* per day, p [=<] /).first().waitFor();
  await screenshot('unit-history');

  // Each analysis opens from the history, and links back to it.
  await page.locator('#history-runs tbody tr.clickable').first().click();
  await page.waitForURL(/#\/analyses\//);
  await page.locator('#analysis-unit').click();
  await page.waitForURL(new RegExp(`#/units/${HISTORY_SERIAL}/history$`));
  await page.locator('#history-plots .history-plot').first().waitFor();
  assert.deepEqual(foreignRequests, []);
});

test('a test streamed live shows on the Live page with its step as it happens, then links to its analysis', {
  skip: skipReason, timeout: 5 * 60_000,
}, async () => {
  // The independent simulator's unit (not the engine's code): an accelerometer
  // step of five drift σ at 400.3 s of a 700-s test at 10 Hz.
  const liveCsv = path.join(workDir, 'live.csv');
  execFileSync('/usr/bin/python3', [path.join(env('INSDIAG_SOURCE_DIR'), 'tests', 'benchsim', 'benchsim.py'),
    '--out', liveCsv, '--preset', 'nav', '--profile', 'positions', '--rate-hz', '10', '--duration', '700',
    '--seed', '11', '--fault', 'acc_bias_step.y=1.471e-3@400.3', '--serial', 'INS-LIVE-1'], { stdio: 'pipe' });
  const grpc = serverLog.match(/listening grpc=(\S+)/)[1];
  const port = 20000 + (process.pid % 20000);
  const streamer = spawn(env('INSDIAG_CLI'), ['stream', '--listen', String(port), '--planned-duration', '700',
    '--server', grpc], { cwd: workDir, env: { ...process.env, INSDIAG_TOKEN: adminToken }, stdio: ['ignore', 'pipe', 'pipe'] });
  let streamerLog = '';
  streamer.stdout.on('data', (d) => { streamerLog += d; });
  streamer.stderr.on('data', (d) => { streamerLog += d; });
  const exited = new Promise((resolve) => streamer.once('exit', resolve));

  // The bench: the file in 40 parts, a quarter of a second apart.
  const net = await import('node:net');
  let socket = null;
  for (let attempt = 0; attempt < 100 && !socket; attempt += 1) {
    socket = await new Promise((resolve) => {
      const s = net.connect(port, '127.0.0.1', () => resolve(s));
      s.once('error', () => resolve(null));
    });
    if (!socket) await new Promise((r) => setTimeout(r, 100));
  }
  assert.ok(socket, `insdiag stream does not listen:\n${streamerLog}`);
  const text = readFileSync(liveCsv);
  const feeding = (async () => {
    for (let part = 0; part < 40; part += 1) {
      socket.write(text.subarray(Math.floor(text.length * part / 40), Math.floor(text.length * (part + 1) / 40)));
      await new Promise((r) => setTimeout(r, 250));
    }
    socket.end();
  })();

  await page.goto(`${baseUrl}/#/live`);
  const row = page.locator('#live-runs tbody tr', { hasText: 'INS-LIVE-1' });
  await row.waitFor({ timeout: 30_000 });
  await row.click();
  await page.waitForURL(/#\/liveRuns\//);
  await page.locator('#live-chart canvas').first().waitFor({ timeout: 30_000 });
  await page.locator('#live-fault-table tbody tr').first().waitFor({ timeout: 60_000 });
  await screenshot('live-test');
  await feeding;
  assert.equal(await exited, 0, streamerLog);
  await page.locator('#live-analysis-link').waitFor({ timeout: 30_000 });
  assert.equal(await page.locator('#live-state').innerText(), 'STORED');
  assert.equal(await page.locator('#live-verdict').innerText(), 'FAULTY');
  // The step's interval is among those shown, starting within a minute of the onset.
  const starts = await page.locator('#live-fault-table tbody tr td:nth-child(3)').allInnerTexts();
  assert.ok(starts.some((s) => Number(s) >= 400.3 - 60 && Number(s) <= 400.3 + 60), `interval starts: ${starts}`);
  await page.locator('#live-analysis-link').click();
  await page.waitForURL(/#\/analyses\//);
  assert.deepEqual(foreignRequests, []);
});

test('an analysis opens its test report, HTML and PDF, from the page with the session token', {
  skip: skipReason, timeout: 2 * 60_000,
}, async () => {
  assert.ok(baseAnalysisUrl, 'the upload test ran first');
  await page.goto(baseAnalysisUrl);
  await page.locator('#test-report-html').waitFor();
  const [html] = await Promise.all([page.waitForEvent('popup'), page.click('#test-report-html')]);
  await html.waitForURL(/^blob:/, { timeout: 60_000 });
  await html.getByText('INS-WEB-1').first().waitFor({ timeout: 30_000 });
  await html.close();
  const pdfResponse = page.waitForResponse((r) => /:testReport\?format=pdf$/.test(r.url()));
  const [pdf] = await Promise.all([page.waitForEvent('popup'), page.click('#test-report-pdf')]);
  const answered = await pdfResponse;
  assert.equal(answered.status(), 200);
  assert.equal(answered.headers()['content-type'], 'application/pdf');
  await pdf.close();
});
