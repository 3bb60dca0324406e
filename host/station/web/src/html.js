// Preact components written as htm tagged templates (no JSX build step).
import { h } from 'preact';
import htm from 'htm';

export const html = htm.bind(h);

export function formatSeconds(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return '';
  if (s < 60) return `${s.toFixed(0)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.round(s - 60 * m)} s`;
}
