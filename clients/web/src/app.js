// The page's router and the runs view: upload (drag & drop or file picker)
// and the list of stored runs. Routes are in the URL's hash, so the server
// serves one page and the back button works:
//   #/                  runs
//   #/runs/{run}        a run and its analyses
//   #/analyses/{a}      an analysis: the model loop (analysis.js)
//   #/units/{unit}/history  a unit's runs, analyses and parameters over time (history.js)
//   #/live              tests being recorded (live.js)
//   #/liveRuns/{id}     one of them, watched as it happens (live.js)
//   #/fleet             fleet statistics (fleet.js)
import { api, ApiError, listAll, num, session, idOf } from './api.js';
import { h, fmt, fmtSeconds, fmtTime, empty, section, table } from './dom.js';
import { navigate, startAnalysis, errorCard } from './nav.js';
import { showAnalysis } from './analysis.js';
import { showFleet } from './fleet.js';
import { showHistory } from './history.js';
import { showLiveRuns, showLiveRun } from './live.js';

const main = document.getElementById('main');
let leaveView = null; // stops the current view's streams and timers

async function route() {
  if (leaveView) leaveView();
  const leaving = [];
  leaveView = () => leaving.forEach((fn) => fn());
  const path = (window.location.hash || '#/').slice(1);
  for (const link of document.querySelectorAll('header nav a')) {
    const nav = link.dataset.nav;
    const section = path.startsWith('/fleet') ? 'fleet' : path.startsWith('/live') ? 'live' : 'runs';
    link.classList.toggle('active', nav === section);
  }
  // The view is in the page from the start: plots take their width from it,
  // and a running analysis shows its progress while the view waits.
  const view = h('div');
  main.replaceChildren(view);
  try {
    let match;
    if ((match = path.match(/^\/analyses\/([^/]+)$/))) await showAnalysis(view, `analyses/${match[1]}`, leaving);
    else if ((match = path.match(/^\/runs\/([^/]+)$/))) await showRun(view, `runs/${match[1]}`);
    else if ((match = path.match(/^\/units\/([^/]+)\/history$/))) await showHistory(view, `units/${match[1]}`);
    else if ((match = path.match(/^\/liveRuns\/([^/]+)$/))) await showLiveRun(view, `liveRuns/${match[1]}`, leaving);
    else if (path.startsWith('/live')) await showLiveRuns(view, leaving);
    else if (path.startsWith('/fleet')) await showFleet(view);
    else await showRuns(view);
  } catch (error) {
    if (view.isConnected) view.append(errorCard(error));
  }
}

// --- runs -------------------------------------------------------------------

async function showRuns(view) {
  const listing = h('div');
  view.append(h('h1', 'Runs'), uploadCard(), section('Stored runs', listing));
  await fillRunList(listing);
}

async function fillRunList(listing) {
  const runs = await listAll(api.listRuns, 'runs', 2000);
  if (!runs.length) {
    listing.replaceChildren(empty('No runs yet: upload a bench-run file above.'));
    return;
  }
  listing.replaceChildren(
    table(
      ['Run', 'Unit', 'Type', 'Samples', 'Duration', 'Uploaded', ''],
      runs.map((run) => {
        const id = idOf(run.name);
        return h('tr.clickable', { dataset: { run: run.name }, onclick: () => navigate(`#/runs/${id}`) },
          h('td', h('a', { href: `#/runs/${id}` }, id.slice(0, 8))),
          h('td', unitLink(run.metadata.unitSerial)),
          h('td', run.metadata.unitType || '—'),
          h('td.num', Number(run.sampleCount).toLocaleString()),
          h('td.num', fmtSeconds(run.durationS)),
          h('td', fmtTime(run.createTime)),
          h('td', h('button.secondary', {
            onclick: async (event) => {
              event.stopPropagation();
              await startAnalysis(run.name, [], []);
            },
          }, 'Analyse')));
      }),
      { id: 'run-list' },
    ),
  );
}

function uploadCard() {
  const input = h('input', { type: 'file', accept: '.csv,text/csv', hidden: true });
  const status = h('div#upload-status');
  const zone = h('div.dropzone#dropzone',
    h('p', 'Drop a bench-run file (CSV) here, or ', h('button.secondary', { onclick: () => input.click() }, 'choose a file…')),
    h('p.hint', 'The run is stored and analysed with the base model at once; then the page shows the loop.'));
  const upload = async (file) => {
    if (!file) return;
    const bar = h('div', { style: 'width:0%' });
    const label = h('p.muted', `Uploading ${file.name} (${(file.size / 1e6).toFixed(1)} MB)…`);
    status.replaceChildren(label, h('div.progress#upload-progress', bar));
    try {
      const run = await api.uploadRun(file, (fraction) => {
        bar.style.width = `${Math.round(100 * fraction)}%`;
        if (fraction >= 1) label.textContent = `Checking and storing ${file.name}…`;
      });
      status.replaceChildren(h('p', `Stored ${run.name} (${Number(run.sampleCount).toLocaleString()} samples); analysing…`));
      await startAnalysis(run.name, [], []);
    } catch (error) {
      status.replaceChildren(await refusal(file, error));
    }
  };
  input.addEventListener('change', () => upload(input.files[0]));
  zone.addEventListener('dragover', (event) => {
    event.preventDefault();
    zone.classList.add('over');
  });
  zone.addEventListener('dragleave', () => zone.classList.remove('over'));
  zone.addEventListener('drop', (event) => {
    event.preventDefault();
    zone.classList.remove('over');
    upload(event.dataTransfer.files[0]);
  });
  return section('Upload a run', zone, input, status);
}

/**
 * A refused upload: the server's message, and for a refused file the line
 * and column it names, with that line of the file and a caret under the column.
 */
async function refusal(file, error) {
  const box = h('div.refusal#upload-error', h('div', h('strong', 'The run was refused. '), error.message));
  const info = error instanceof ApiError ? error.errorInfo : null;
  const line = num(info?.metadata?.line);
  const column = num(info?.metadata?.column);
  if (line !== null) {
    box.append(h('div.where', `Line ${line}${column !== null ? `, column ${column}` : ''}`,
      info.metadata.field ? ` (${info.metadata.field})` : ''));
    const text = await lineOf(file, line);
    if (text !== null) {
      box.append(h('pre', `${line} | ${text}\n`,
        column !== null ? h('span.caret', `${' '.repeat(String(line).length + 3 + Math.max(column - 1, 0))}^`) : null));
    }
  }
  for (const violation of error instanceof ApiError ? error.fieldViolations : []) {
    if (!error.message.includes(violation.description)) box.append(h('div.small', `${violation.field}: ${violation.description}`));
  }
  return box;
}

/** Line `n` (1-based) of a text file, or null. Reads only as far as needed. */
async function lineOf(file, n) {
  const reader = file.stream().pipeThrough(new TextDecoderStream()).getReader();
  let seen = 1;
  let current = '';
  try {
    for (;;) {
      const { value, done } = await reader.read();
      if (done) return seen === n ? current : null;
      for (const ch of value) {
        if (ch === '\n') {
          if (seen === n) return current.replace(/\r$/, '');
          seen += 1;
          current = '';
        } else if (seen === n) {
          current += ch;
        }
      }
    }
  } finally {
    reader.cancel().catch(() => {});
  }
}

// --- one run ----------------------------------------------------------------

async function showRun(view, name) {
  const [run, analyses] = await Promise.all([api.getRun(name), api.listAnalyses(name)]);
  const meta = run.metadata;
  view.append(
    h('h1', `Run ${idOf(name)}`),
    section('Run',
      table(['Unit', 'Type', 'Samples', 'Rate', 'Duration', 'Temperature', 'Uploaded'], [h('tr',
        h('td', unitLink(meta.unitSerial)), h('td', meta.unitType || '—'), h('td.num', Number(run.sampleCount).toLocaleString()),
        h('td.num', `${fmt(1 / num(run.nominalIntervalS))} Hz`), h('td.num', fmtSeconds(run.durationS)),
        h('td', meta.hasTemperature ? 'yes' : 'no'), h('td', fmtTime(run.createTime)))]),
      h('div.row', { style: 'margin-top:10px' },
        h('button', { onclick: () => startAnalysis(name, [], []) }, 'Analyse with the base model'),
        h('button.secondary', { onclick: () => startAnalysis(name, [], [], true) }, 'Discover missing effects'),
        h('button.secondary#unit-history', { onclick: () => navigate(historyHash(meta.unitSerial)) }, 'Unit history'),
        h('button.secondary', { onclick: () => api.downloadRun(name).catch((error) => window.alert(error.message)) },
          'Download CSV'),
        h('span.grow'),
        h('button.danger', {
          onclick: async () => {
            if (!window.confirm(`Delete ${name} and its analyses?`)) return;
            try {
              await api.deleteRun(name);
              navigate('#/');
            } catch (error) {
              // Not an administrator, or a diagnosis rests on the run: the server says which.
              window.alert(error.message);
            }
          },
        }, 'Delete'))),
    section('Analyses', analyses.analyses.length
      ? analysisTable(analyses.analyses)
      : empty('No analysis of this run yet.')),
  );
}

function historyHash(serial) {
  return `#/units/${encodeURIComponent(serial)}/history`;
}

/** The unit's serial, linking to its history (a click on it does not open the row's run). */
function unitLink(serial) {
  return h('a.unit-link', { href: historyHash(serial), onclick: (event) => event.stopPropagation() }, serial);
}

function analysisTable(analyses) {
  return table(['Analysis', 'Model', 'State', 'Created'], analyses.map((a) => {
    const id = idOf(a.name);
    return h('tr.clickable', { onclick: () => navigate(`#/${a.name}`) },
      h('td', h('a', { href: `#/${a.name}` }, id.slice(0, 8))),
      h('td', a.model.effects.length ? a.model.effects.join(', ') : 'base model', a.discover ? ' (discover)' : ''),
      h('td', h(`span.badge.${a.state}`, a.state)),
      h('td', fmtTime(a.createTime)));
  }));
}

// --- who is signed in --------------------------------------------------------

const signIn = document.getElementById('sign-in');
let pendingSignIn = null;

/** Shows the sign-in dialog; resolves when the user has given a token. */
session.askForToken = (reason) => {
  if (!pendingSignIn) {
    pendingSignIn = new Promise((resolve) => {
      document.getElementById('sign-in-reason').textContent = session.token ? reason : '';
      const input = document.getElementById('token-input');
      input.value = '';
      signIn.addEventListener('close', () => {
        session.token = input.value.trim();
        pendingSignIn = null;
        resolve();
        showCaller();
      }, { once: true });
      signIn.showModal();
    });
  }
  return pendingSignIn;
};

async function showCaller() {
  const place = document.getElementById('caller');
  if (!session.token) return place.replaceChildren();
  try {
    const caller = await api.getCaller();
    place.replaceChildren(`${caller.displayName} (${caller.role.toLowerCase()}) `,
      h('a', { href: '#/', onclick: () => { session.token = ''; place.replaceChildren(); } }, 'sign out'));
  } catch {
    place.replaceChildren();
  }
}

window.addEventListener('hashchange', route);
route();
showCaller();
