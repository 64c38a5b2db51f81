// Moving between the page's views (app.js routes on the URL's hash).
import { api, ApiError } from './api.js';
import { h } from './dom.js';

export function navigate(hash) {
  if (window.location.hash === hash) window.dispatchEvent(new HashChangeEvent('hashchange'));
  else window.location.hash = hash;
}

/** Queues an analysis of `run` with `effects` over the model `baseline` and opens it. */
export async function startAnalysis(run, effects, baseline, discover = false) {
  const analysis = await api.createAnalysis({ run, model: { effects }, baseline: { effects: baseline }, discover });
  navigate(`#/${analysis.name}`);
  return analysis;
}

export function errorCard(error) {
  return h('div.card.refusal', h('strong', error instanceof ApiError && error.status ? `${error.status}: ` : 'Error: '),
    error.message);
}
