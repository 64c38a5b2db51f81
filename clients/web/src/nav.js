// Moving between the page's views (app.js routes on the URL's hash).
import { api, ApiError } from './api.js';
import { h } from './dom.js';

export function navigate(hash) {
  if (window.location.hash === hash) window.dispatchEvent(new HashChangeEvent('hashchange'));
  else window.location.hash = hash;
}

/**
 * Queues an analysis of `run` with `effects` over the model `baseline` and opens it.
 * With `baseAnalysis` (an analysis of the same run that succeeded), model A is the
 * model it identified, and the server does not identify it again.
 */
export async function startAnalysis(run, effects, baseline, discover = false, baseAnalysis = '') {
  const request = { run, model: { effects }, baseline: { effects: baseline }, discover };
  if (baseAnalysis) request.baseAnalysis = baseAnalysis;
  const analysis = await api.createAnalysis(request);
  navigate(`#/${analysis.name}`);
  return analysis;
}

export function errorCard(error) {
  return h('div.card.refusal', h('strong', error instanceof ApiError && error.status ? `${error.status}: ` : 'Error: '),
    error.message);
}
