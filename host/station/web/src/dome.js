// The dome: the LED map live, the controller's state and faults, a test
// sequence, and single LEDs lit by hand (within the firmware's limits: it
// switches an LED off itself after its on-time limit, and says so).
import { useRef, useState } from 'preact/hooks';
import { post } from './api.js';
import { html } from './html.js';
import { LedMap, litSet } from './led_map.js';

export function DomePanel({ station }) {
  const { status, rig, operator, act } = station;
  if (!status || !rig) return html`<p>Loading…</p>`;
  const controller = status.dome.controller;
  const lit = litSet(status);
  const busy = status.job?.state === 'running';
  const [slow, setSlow] = useState(false);
  // What this page last asked for: two clicks quicker than the status poll
  // build on each other, not on the older status.
  const asked = useRef(null);
  const toggle = (id) => {
    const recent = asked.current && Date.now() - asked.current.at < 2000;
    const next = new Set(recent ? asked.current.leds : status.dome.controller?.leds_on ?? []);
    if (next.has(id)) next.delete(id);
    else next.add(id);
    asked.current = { leds: next, at: Date.now() };
    act(() => post('/api/leds', { leds: [...next].map((led) => ({ id: led })) }));
  };
  return html`<section class="panel dome">
    <div>
      <${LedMap} leds=${rig.leds} lit=${lit} onPick=${operator && !busy ? toggle : null} />
      <p class="hint">${operator
        ? busy ? 'The dome is busy with the running job.' : 'Click an LED to light it or put it out.'
        : 'Take control to light LEDs.'}</p>
    </div>
    <div>
      <h2>Controller</h2>
      ${controller ? html`<dl class="facts">
          <dt>State</dt><dd id="controller-state">${controller.state}</dd>
          <dt>Rig</dt><dd>${controller.rig} (${rig.leds.length} LEDs)</dd>
          <dt>Firmware</dt><dd>${controller.firmware}</dd>
          <dt>Watchdog</dt><dd>${controller.watchdog_ms} ms</dd>
          <dt>LEDs on</dt><dd id="leds-on">${controller.leds_on.length ? controller.leds_on.join(', ') : 'none'}</dd>
          <dt>Last fault</dt><dd id="last-fault" class=${controller.last_fault ? 'fault' : ''}>
            ${controller.last_fault || 'none'}</dd>
        </dl>`
        : html`<p class="fault">Not connected: ${status.dome.error}</p>`}
      <p>
        <button id="test-sequence" disabled=${!operator || busy}
          onClick=${() => act(() => post('/api/test-sequence', { on_us: slow ? 250000 : 10000 }))}>
          Run the test sequence</button>
        <label><input type="checkbox" id="test-slow" checked=${slow}
          onChange=${(e) => setSlow(e.target.checked)} /> slowly, to watch each LED</label>
      </p>
      ${status.job?.kind === 'test-sequence' && status.job.result && html`<p id="test-result">
        ${status.job.result.steps} steps; lateness median ${status.job.result.lateness_us.median.toFixed(1)} µs,
        99th percentile ${status.job.result.lateness_us.p99.toFixed(1)} µs, max ${status.job.result.lateness_us.max.toFixed(1)} µs</p>`}
      ${status.simulated && html`<${Placement} station=${station} />`}
    </div>
  </section>`;
}

// On the simulated dome the page chooses what lies under it.
export function Placement({ station }) {
  const { status, operator, act } = station;
  const busy = status.job?.state === 'running';
  return html`<div class="placement">
    <h3>Under the simulated dome</h3>
    ${status.simulated.choices.map((choice) => html`<label key=${choice}>
      <input type="radio" name="placed" value=${choice} checked=${status.simulated.placed === choice}
        disabled=${!operator || busy} data-place=${choice}
        onChange=${() => act(() => post('/api/place', { object: choice }))} />
      ${choice === 'object' ? `the object (${status.simulated.scene})` : `the chrome sphere, position ${choice.split('-')[1]}`}
    </label>`)}
  </div>`;
}
