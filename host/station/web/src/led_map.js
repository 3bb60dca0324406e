// The dome seen from above: each LED at its direction's (x, y), the horizon
// as the outer circle, elevation rings at 30 and 60 degrees. Lit LEDs glow.
import { html } from './html.js';

const SIZE = 360;
const R = SIZE / 2 - 14;

export function LedMap({ leds, lit, selected, onPick, id = 'led-map' }) {
  const c = SIZE / 2;
  const ring = (elevation) => R * Math.cos((elevation * Math.PI) / 180);
  return html`<svg id=${id} class="led-map" viewBox=${`0 0 ${SIZE} ${SIZE}`} width=${SIZE} height=${SIZE}
      role="img" aria-label="LED map">
    <circle cx=${c} cy=${c} r=${R} class="horizon" />
    <circle cx=${c} cy=${c} r=${ring(30)} class="ring" />
    <circle cx=${c} cy=${c} r=${ring(60)} class="ring" />
    ${leds.map((led) => {
      const [x, y] = led.direction;
      const on = lit.has(led.id);
      return html`<circle key=${led.id} data-led=${led.id} cx=${c + x * R} cy=${c - y * R} r="7"
          class=${`led${on ? ' lit' : ''}${selected === led.id ? ' selected' : ''}${onPick ? ' pickable' : ''}`}
          onClick=${onPick ? () => onPick(led.id) : undefined}>
        <title>LED ${led.id}${on ? ' (lit)' : ''}</title>
      </circle>`;
    })}
  </svg>`;
}

// The LEDs lit now: what the controller last said, and during a job what the station follows.
export function litSet(status) {
  const ids = new Set(status?.dome?.controller?.leds_on ?? []);
  for (const led of status?.dome?.lit ?? []) ids.add(led.id);
  return ids;
}
