// The REST API of insdiagd (docs/API.md): the page's only source of data.
// JSON is protobuf's JSON mapping (lowerCamelCase, every field present;
// 64-bit integers as strings, non-finite doubles as "NaN"/"Infinity").

/** An error answer of the API: the google.rpc.Status JSON of docs/API.md. */
export class ApiError extends Error {
  constructor(httpStatus, body) {
    const error = (body && body.error) || {};
    super(error.message || `HTTP ${httpStatus}`);
    this.httpStatus = httpStatus;
    this.status = error.status || '';
    this.details = error.details || [];
  }

  /** BadRequest field violations: [{field, description}]. */
  get fieldViolations() {
    return this.details.flatMap((d) => d.fieldViolations || []);
  }

  /** ErrorInfo metadata, e.g. {source, line, column, field} of a refused file. */
  get errorInfo() {
    return this.details.find((d) => (d['@type'] || '').endsWith('google.rpc.ErrorInfo')) || null;
  }
}

// The bearer token lives in this browser tab's session only (issue: never in
// localStorage, where it would outlive the tab and reach every later visitor).
const TOKEN_KEY = 'insdiag.token';

export const session = {
  get token() {
    return sessionStorage.getItem(TOKEN_KEY) || '';
  },
  set token(value) {
    if (value) sessionStorage.setItem(TOKEN_KEY, value);
    else sessionStorage.removeItem(TOKEN_KEY);
  },
  /**
   * Set by the page: asks the user for a token (the server said 401 with
   * `reason`) and resolves once a new one is in `session.token`.
   */
  askForToken: null,
};

function authorization() {
  return session.token ? { Authorization: `Bearer ${session.token}` } : {};
}

/** Runs `send()` (a fetch-like promise of a Response); on 401 asks for a token and sends once more. */
async function withToken(send) {
  let response = await send();
  if (response.status === 401 && session.askForToken) {
    const error = await errorFrom(response);
    await session.askForToken(error.message);
    response = await send();
  }
  return response;
}

async function errorFrom(response) {
  let body = null;
  try {
    body = await response.json();
  } catch {
    body = { error: { message: `${response.status} ${response.statusText}` } };
  }
  return new ApiError(response.status, body);
}

async function call(method, path, { body, query, contentType } = {}) {
  const url = new URL(path, window.location.origin);
  for (const [key, value] of Object.entries(query || {})) {
    if (value === undefined || value === null || value === '') continue;
    for (const v of Array.isArray(value) ? value : [value]) url.searchParams.append(key, String(v));
  }
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.body = typeof body === 'string' || body instanceof Blob ? body : JSON.stringify(body);
    init.headers['Content-Type'] = contentType || 'application/json';
  }
  const response = await withToken(() => fetch(url, { ...init, headers: { ...init.headers, ...authorization() } }));
  if (!response.ok) throw await errorFrom(response);
  const text = await response.text();
  return text ? JSON.parse(text) : {};
}

/** Calls `onMessage` with each line of a newline-delimited JSON answer. */
async function stream(path, onMessage, signal) {
  const response = await withToken(() =>
    fetch(new URL(path, window.location.origin), { signal, headers: authorization() }),
  );
  if (!response.ok) throw await errorFrom(response);
  const reader = response.body.getReader();
  const decoder = new TextDecoder();
  let pending = '';
  for (;;) {
    const { value, done } = await reader.read();
    if (done) break;
    pending += decoder.decode(value, { stream: true });
    let newline;
    while ((newline = pending.indexOf('\n')) >= 0) {
      const line = pending.slice(0, newline).trim();
      pending = pending.slice(newline + 1);
      if (!line) continue;
      const message = JSON.parse(line);
      // An error after the first message comes as a last line {"error": …}.
      if (message.error) throw new ApiError(message.error.code || 500, message);
      onMessage(message);
    }
  }
}

/** The id of a resource name, "runs/abc" → "abc" (AIP-122: a collection, then the id). */
export function idOf(name) {
  return name.slice(name.indexOf('/') + 1);
}

/** A unit's module, "units/{unit}/modules/{role}" → {unit, role} (the role: "gyro.x"). */
export function moduleOf(name) {
  const [, unit = '', , role = ''] = name.split('/');
  return { unit, role };
}

/** A number of the JSON mapping (doubles may be "NaN"; int64 are strings). */
export function num(value) {
  const n = typeof value === 'number' ? value : Number(value);
  return Number.isFinite(n) ? n : null;
}

/** Every item of a paginated List method (AIP-158), `listPage(token)` a page at a time, at most `limit`. */
export async function listAll(listPage, field, limit) {
  const items = [];
  let token = '';
  do {
    const page = await listPage(token);
    items.push(...page[field]);
    token = page.nextPageToken;
  } while (token && items.length < limit);
  return items;
}

/**
 * Uploads a bench-run file as text/csv; `onProgress(fraction)` as it is sent
 * (XMLHttpRequest, because fetch tells nothing of an upload's progress).
 */
async function uploadRun(file, onProgress = () => {}) {
  // A token first (a cheap read), so that a 401 never costs a whole upload.
  await call('GET', '/v1/caller');
  const url = new URL('/v1/runs:upload', window.location.origin);
  url.searchParams.set('filename', file.name);
  return new Promise((resolve, reject) => {
    const request = new XMLHttpRequest();
    request.open('POST', url);
    request.setRequestHeader('Content-Type', 'text/csv');
    for (const [name, value] of Object.entries(authorization())) request.setRequestHeader(name, value);
    request.upload.addEventListener('progress', (event) => {
      if (event.lengthComputable) onProgress(event.loaded / event.total);
    });
    request.addEventListener('load', () => {
      let body = null;
      try {
        body = JSON.parse(request.responseText);
      } catch {
        body = { error: { message: `${request.status} ${request.statusText}` } };
      }
      if (request.status >= 200 && request.status < 300) resolve(body);
      else reject(new ApiError(request.status, body));
    });
    request.addEventListener('error', () => reject(new Error('the upload did not reach insdiagd')));
    request.send(file);
  });
}

/** Saves the run as a bench-run CSV file (a plain link would carry no token). */
async function downloadRun(name) {
  const url = new URL(`/v1/${name}:download`, window.location.origin);
  const response = await withToken(() => fetch(url, { headers: authorization() }));
  if (!response.ok) throw await errorFrom(response);
  const link = document.createElement('a');
  link.href = URL.createObjectURL(await response.blob());
  link.download = `${idOf(name)}.csv`;
  link.click();
  setTimeout(() => URL.revokeObjectURL(link.href), 60_000);
}

/** An analysis's test report, HTML or PDF, as a blob (a plain link would carry no token). */
async function testReport(name, format) {
  const url = new URL(`/v1/${name}:testReport`, window.location.origin);
  url.searchParams.set('format', format);
  const response = await withToken(() => fetch(url, { headers: authorization() }));
  if (!response.ok) throw await errorFrom(response);
  return response.blob();
}

/** A unit's history with every run (the server pages the runs; the statistics come whole on each page). */
async function unitHistory(unit) {
  let history = null;
  let pageToken = '';
  do {
    const page = await call('GET', `/v1/${unit}/history`, { query: { pageSize: 1000, pageToken } });
    if (history) history.runs.push(...page.runs);
    else history = page;
    pageToken = page.nextPageToken;
  } while (pageToken);
  return history;
}

export const api = {
  getCaller: () => call('GET', '/v1/caller'),
  downloadRun,
  listRuns: (pageToken) => call('GET', '/v1/runs', { query: { pageSize: 200, pageToken } }),
  getRun: (name) => call('GET', `/v1/${name}`),
  deleteRun: (name) => call('DELETE', `/v1/${name}`),
  uploadRun,

  createAnalysis: (analysis) => call('POST', '/v1/analyses', { body: analysis }),
  getAnalysis: (name) => call('GET', `/v1/${name}`),
  listAnalyses: (run, includeReports = false) =>
    call('GET', '/v1/analyses', { query: { run, includeReports, pageSize: 1000 } }),
  cancelAnalysis: (name) => call('POST', `/v1/${name}:cancel`, { body: {} }),
  watchAnalysis: (name, onMessage, signal) => stream(`/v1/${name}:watch`, onMessage, signal),
  displaySeries: (name, { channels, startS, endS, columns }) =>
    call('GET', `/v1/${name}/displaySeries`, { query: { channels, startS, endS, columns } }),

  createDiagnosis: (analysis) => call('POST', '/v1/diagnoses', { body: { analysis } }),
  listDiagnoses: (analysis) => call('GET', '/v1/diagnoses', { query: { analysis, pageSize: 50 } }),
  resolveDiagnosis: (name, resolution) => call('POST', `/v1/${name}:resolve`, { body: resolution }),

  unitHistory,
  testReport,

  listLiveRuns: () => call('GET', '/v1/liveRuns'),
  watchLiveRun: (name, onMessage, signal) => stream(`/v1/${name}:watch`, onMessage, signal),

  listUnitTypes: () => call('GET', '/v1/unitTypes'),
  listFailureRecords: (pageToken) => call('GET', '/v1/failureRecords', { query: { pageSize: 1000, pageToken } }),
  fleetStatistics: () => call('GET', '/v1/fleetStatistics'),
  pareto: () => call('GET', '/v1/fleet/pareto'),
  weibull: (moduleRole) => call('GET', '/v1/fleet/weibull', { query: { moduleRole } }),
  parameterTrend: (unitType, parameter) => call('GET', `/v1/${unitType}/parameterTrend`, { query: { parameter } }),
  parameterPoints: (unitType, parameter) =>
    call('GET', `/v1/${unitType}/parameterTrends`, { query: { parameter, pageSize: 1000 } }),
  unitRanking: () => call('GET', '/v1/fleet/unitRanking', { query: { pageSize: 50 } }),
};
