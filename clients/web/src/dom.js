// Small helpers for building the page's elements and formatting numbers.
import { num } from './api.js';

/**
 * h('div.card#id', {onclick, title, dataset: {…}}, child, …): an element.
 * Children may be strings, numbers, nodes, arrays, null or false.
 */
export function h(tag, attributes, ...children) {
  const [, name, rest] = tag.match(/^([a-z0-9]+)(.*)$/i);
  const element = document.createElement(name);
  for (const part of rest.match(/[.#][^.#]+/g) || []) {
    if (part[0] === '.') element.classList.add(part.slice(1));
    else element.id = part.slice(1);
  }
  if (attributes && (typeof attributes !== 'object' || attributes instanceof Node || Array.isArray(attributes))) {
    children.unshift(attributes);
    attributes = null;
  }
  for (const [key, value] of Object.entries(attributes || {})) {
    if (value === undefined || value === null || value === false) continue;
    if (key.startsWith('on')) element.addEventListener(key.slice(2), value);
    else if (key === 'dataset') Object.assign(element.dataset, value);
    else if (key === 'class') element.className = value;
    else if (key in element && typeof value !== 'string') element[key] = value;
    else element.setAttribute(key, value === true ? '' : value);
  }
  append(element, children);
  return element;
}

function append(element, children) {
  for (const child of children) {
    if (child === null || child === undefined || child === false) continue;
    if (Array.isArray(child)) append(element, child);
    else element.append(child instanceof Node ? child : String(child));
  }
}

/** A number with `digits` significant digits; exponent form when very large or small. */
export function fmt(value, digits = 3) {
  const n = num(value);
  if (n === null) return '—';
  if (n === 0) return '0';
  const magnitude = Math.abs(n);
  if (magnitude >= 1e5 || magnitude < 1e-3) return n.toExponential(digits - 1);
  return Number(n.toPrecision(digits)).toString();
}

/** A p-value: "<1e-16" style below what doubles tell apart. */
export function fmtP(value) {
  const n = num(value);
  if (n === null) return '—';
  if (n < 1e-16) return '<1e-16';
  return n < 1e-3 ? n.toExponential(1) : n.toFixed(3);
}

export function fmtSeconds(value) {
  const s = num(value);
  if (s === null) return '—';
  if (s < 120) return `${fmt(s, 3)} s`;
  if (s < 7200) return `${fmt(s / 60, 3)} min`;
  return `${fmt(s / 3600, 3)} h`;
}

export function fmtTime(timestamp) {
  if (!timestamp) return '—';
  const date = new Date(timestamp);
  return Number.isNaN(date.getTime()) ? String(timestamp) : date.toLocaleString();
}

/** An empty state: what is missing and, when known, why. */
export function empty(text) {
  return h('p.empty', text);
}

/** A section with a heading. */
export function section(title, ...children) {
  return h('section.card', h('h2', title), ...children);
}

/** A table (`attributes` go on the <table>) in a box that scrolls sideways when too wide. */
export function table(headers, rows, attributes = {}) {
  // A heading sits on the side its column's numbers do.
  const first = rows[0]?.children || [];
  const numeric = (i) => Boolean(first[i]?.classList.contains('num'));
  return h('div.table-wrap', h(
    'table',
    attributes,
    h('thead', h('tr', headers.map((header, i) => h(numeric(i) ? 'th.num' : 'th', header)))),
    h('tbody', rows),
  ));
}
