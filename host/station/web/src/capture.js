// Captures: the plan (LEDs, exposure or automatic, brackets, darks), the
// stacks in the data folder, and a resume for any the station left
// incomplete (paused, or interrupted by a crash or a lost link).
import { useState } from 'preact/hooks';
import { post } from './api.js';
import { html } from './html.js';
import { Placement } from './dome.js';

function numbers(text) {
  return text.split(/[\s,]+/).filter(Boolean).map(Number);
}

export function CapturePanel({ station }) {
  const { status, data, operator, act } = station;
  const [name, setName] = useState('object-1');
  const [target, setTarget] = useState('object');
  const [exposure, setExposure] = useState('auto');
  const [darks, setDarks] = useState(4);
  const [brackets, setBrackets] = useState('');
  const [leds, setLeds] = useState('');
  if (!status || !data) return html`<p>Loading…</p>`;
  const busy = status.job?.state === 'running';
  const start = (event) => {
    event.preventDefault();
    const plan = { name, target, dark_frames: Number(darks) };
    plan.exposure_us = exposure.trim() === 'auto' ? 'auto' : Number(exposure);
    if (brackets.trim()) plan.bracket_stops = numbers(brackets);
    if (leds.trim()) plan.led_ids = numbers(leds);
    act(() => post('/api/capture', plan));
  };
  return html`<section class="panel capture">
    <div>
      <h2>Plan</h2>
      <form id="capture-form" class="plan" onSubmit=${start}>
        <label>Stack name <input id="capture-name" value=${name} onInput=${(e) => setName(e.target.value)} /></label>
        <label>Target <select id="capture-target" value=${target} onChange=${(e) => setTarget(e.target.value)}>
          <option value="object">an object</option>
          <option value="chrome-sphere">a chrome sphere (exposed for its highlight)</option>
        </select></label>
        <label>Exposure (µs, or auto per LED) <input id="capture-exposure" value=${exposure}
          onInput=${(e) => setExposure(e.target.value)} /></label>
        <label>Dark frames per exposure <input id="capture-darks" type="number" min="0" max="64" value=${darks}
          onInput=${(e) => setDarks(e.target.value)} /></label>
        <label>HDR bracket, stops (e.g. 0, -3, -6; empty = none) <input id="capture-brackets" value=${brackets}
          onInput=${(e) => setBrackets(e.target.value)} /></label>
        <label>LEDs (ids; empty = all) <input id="capture-leds" value=${leds} onInput=${(e) => setLeds(e.target.value)} /></label>
        <button id="capture-start" type="submit" disabled=${!operator || busy}>Start the capture</button>
      </form>
      ${status.simulated && html`<${Placement} station=${station} />`}
    </div>
    <div>
      <h2>Stacks</h2>
      <table id="stacks" class="list">
        <thead><tr><th>Name</th><th>Frames</th><th>Size</th><th></th></tr></thead>
        <tbody>${data.stacks.map((s) => html`<tr key=${s.name} data-stack=${s.name}>
          <td>${s.name}</td>
          <td>${s.frames}${s.planned ? ` / ${s.planned}` : ''}${s.complete ? '' : ' (incomplete)'}</td>
          <td>${s.width ? `${s.width} × ${s.height}` : ''}</td>
          <td>${s.resumable && html`<button class="resume" disabled=${!operator || busy}
            onClick=${() => act(() => post('/api/capture/resume', { name: s.name }))}>Resume</button>`}</td>
        </tr>`)}</tbody>
      </table>
    </div>
  </section>`;
}
