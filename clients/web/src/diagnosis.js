// The unit's diagnosis from this analysis: its modules ranked by fault
// probability against the knowledge base, the evidence for each, and the
// bench's answer (confirm writes a failure record, reject a no-fault-found).
import { api, num } from './api.js';
import { h, fmt, empty, section, table } from './dom.js';

export function diagnosisSection(analysis) {
  const body = h('div', h('p.muted', 'Loading…'));
  const element = section('Diagnosis of the unit', body);
  load(analysis, body);
  return element;
}

async function load(analysis, body) {
  try {
    const { diagnoses } = await api.listDiagnoses(analysis.name);
    if (diagnoses.length) return render(body, diagnoses[0], analysis);
    body.replaceChildren(
      empty('Not diagnosed yet.'),
      h('button#diagnose', {
        onclick: async (event) => {
          event.target.disabled = true;
          try {
            render(body, await api.createDiagnosis(analysis.name), analysis);
          } catch (error) {
            body.append(h('p.worse', error.message));
            event.target.disabled = false;
          }
        },
      }, 'Diagnose the unit'));
  } catch (error) {
    body.replaceChildren(h('p.worse', `The diagnoses could not be read: ${error.message}`));
  }
}

function render(body, diagnosis, analysis) {
  const resolved = Boolean(diagnosis.failureRecord);
  const resolve = async (candidate, confirmed) => {
    try {
      const updated = await api.resolveDiagnosis(diagnosis.name, {
        module: candidate.module, failureMode: candidate.failureMode, confirmed,
      });
      render(body, updated, analysis);
    } catch (error) {
      body.append(h('p.worse', error.message));
    }
  };
  const faulty = (c) => !['healthy', 'unknown'].includes(c.module);
  body.replaceChildren(
    resolved
      ? h('p#diagnosis-resolved', diagnosis.confirmed ? `Confirmed: ${diagnosis.resolvedModule}` : 'Rejected: no fault found',
        ` (${diagnosis.failureRecord})`)
      : h('p.hint', 'Confirm the module the bench found faulty, or reject: either answer goes into the failure records and the fleet statistics.'),
    diagnosis.candidates.length
      ? table(['Module', 'Failure mode', 'Probability', 'Evidence', ''], diagnosis.candidates.map((c) => h('tr',
        h('td', h('strong', c.module)),
        h('td', c.failureMode ? c.failureMode.replace(/^failureModes\//, '') : '—'),
        h('td.num', { style: 'min-width:120px' }, `${fmt(100 * num(c.probability), 3)} %`,
          h('div.bar', { style: `width:${Math.max(2, Math.round(100 * num(c.probability)))}%` })),
        h('td', c.evidence.length ? h('ul.evidence', c.evidence.map((e) => h('li', e))) : h('span.muted', '—')),
        h('td', resolved || !faulty(c) ? null : h('div.row',
          h('button.secondary', { onclick: () => resolve(c, true) }, 'Confirm'),
          h('button.danger', { onclick: () => resolve(c, false) }, 'Reject'))))), { id: 'diagnosis-table' })
      : empty('The diagnosis names no candidate.'),
    diagnosis.notes?.length ? h('ul.notes', diagnosis.notes.map((n) => h('li', n))) : null);
}
