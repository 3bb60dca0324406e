// The calibration wizard: the chrome sphere captured at each position, its
// outline found (or drawn by the operator where detection fails: a chrome
// sphere in a dark dome is nearly invisible), then the lights calibrated and
// shown on the hemisphere with a warning for every light that went wrong.
import { useEffect, useRef, useState } from 'preact/hooks';
import { apiImageUrl, fileUrl, get, post } from './api.js';
import { html } from './html.js';

// The stack's picture with the sphere's outline over it: drag inside to move
// it, drag the handle on its rim to size it.
function SphereEditor({ stack, operator, act }) {
  const [found, setFound] = useState(null);
  const [circle, setCircle] = useState(null);
  const [image, setImage] = useState('');
  const [changed, setChanged] = useState(false);
  const drag = useRef(null);
  const svg = useRef(null);

  const load = async () => {
    const result = await act(() => get(`/api/stacks/${encodeURIComponent(stack)}/sphere`));
    if (!result) return;
    setFound(result);
    setImage(apiImageUrl(`/api/stacks/${encodeURIComponent(stack)}/sphere.png`));
    setCircle(result.circle ?? { x_px: result.width / 2, y_px: result.height / 2, radius_px: Math.min(result.width, result.height) / 4 });
    setChanged(false);
  };
  useEffect(() => { load(); }, [stack]);
  if (!found || !circle) return html`<p>Looking for the sphere…</p>`;

  const point = (event) => {
    const box = svg.current.getBoundingClientRect();
    return [((event.clientX - box.left) / box.width) * found.width, ((event.clientY - box.top) / box.height) * found.height];
  };
  const down = (what) => (event) => {
    if (!operator) return;
    event.preventDefault();
    event.target.setPointerCapture?.(event.pointerId);
    const [x, y] = point(event);
    drag.current = { what, x, y, start: { ...circle } };
  };
  const move = (event) => {
    const d = drag.current;
    if (!d) return;
    const [x, y] = point(event);
    if (d.what === 'centre') {
      setCircle({ ...d.start, x_px: d.start.x_px + x - d.x, y_px: d.start.y_px + y - d.y });
    } else {
      setCircle({ ...d.start, radius_px: Math.max(2, Math.hypot(x - d.start.x_px, y - d.start.y_px)) });
    }
    setChanged(true);
  };
  const up = () => { drag.current = null; };
  const save = async () => {
    const result = await act(() => post(`/api/stacks/${encodeURIComponent(stack)}/sphere`, {
      x_px: circle.x_px, y_px: circle.y_px, radius_px: circle.radius_px,
    }));
    if (result) load();
  };
  const forget = async () => {
    const result = await act(() => post(`/api/stacks/${encodeURIComponent(stack)}/sphere/forget`));
    if (result) load();
  };
  const handle = [circle.x_px + circle.radius_px, circle.y_px];
  return html`<div class="sphere-editor" data-stack=${stack}>
    <div class="sphere-view">
      <img src=${image} alt=${`the brightest of ${stack}'s frames`} />
      <svg ref=${svg} class="outline" viewBox=${`0 0 ${found.width} ${found.height}`} preserveAspectRatio="none"
        onPointerMove=${move} onPointerUp=${up} onPointerLeave=${up}>
        <circle class="sphere-outline" cx=${circle.x_px} cy=${circle.y_px} r=${circle.radius_px}
          onPointerDown=${down('centre')} />
        <circle class="sphere-handle" cx=${handle[0]} cy=${handle[1]} r=${Math.max(2, found.width / 60)}
          onPointerDown=${down('radius')} />
      </svg>
    </div>
    <p class=${found.circle ? 'ok' : 'fault'}>
      ${found.circle
        ? `Sphere ${found.circle.source === 'mask' ? (found.drawn ? 'as drawn' : "from the stack's mask") : 'found'}: centre (${found.circle.x_px.toFixed(1)}, ${found.circle.y_px.toFixed(1)}), radius ${found.circle.radius_px.toFixed(1)} px`
        : `Not found (${found.error}). Drag the circle onto the sphere and size it by its handle.`}
    </p>
    ${operator && html`<p class="row">
      <button class="sphere-save" disabled=${!changed && found.circle} onClick=${save}>Use this outline</button>
      ${found.drawn && html`<button class="sphere-forget" onClick=${forget}>Forget it, detect again</button>`}
    </p>`}
    ${changed && html`<p class="hint">Draw it to a fraction of a pixel: each LED's position is triangulated from it.</p>`}
  </div>`;
}

function CalibrationResult({ name }) {
  const [calibration, setCalibration] = useState(null);
  useEffect(() => {
    fetch(fileUrl(`calibrations/${name}/calibration.json`)).then((r) => r.json()).then(setCalibration)
      .catch(() => setCalibration(null));
  }, [name]);
  const lights = calibration?.lights ?? [];
  const measured = lights.filter((l) => l.measured).length;
  return html`<div class="calibration-result" id="calibration-result">
    <img src=${fileUrl(`calibrations/${name}/lights_hemisphere.png`)} alt="the calibrated lights on the hemisphere" />
    ${calibration && html`<p>${measured} of ${lights.length} lights measured.</p>`}
    ${calibration?.problems?.length > 0 && html`<details open=${calibration.problems.length < 6}>
      <summary>${calibration.problems.length} warning(s)</summary>
      <ul class="warnings">${calibration.problems.map((p, i) => html`<li key=${i}>${p}</li>`)}</ul>
    </details>`}
  </div>`;
}

export function CalibrationPanel({ station }) {
  const { status, data, operator, act } = station;
  const choices = status?.simulated?.choices.filter((c) => c.startsWith('chrome-')) ?? [];
  const [positions, setPositions] = useState(Math.max(choices.length, 2));
  const [prefix, setPrefix] = useState('chrome');
  const [name, setName] = useState('calibration');
  if (!status || !data) return html`<p>Loading…</p>`;
  const busy = status.job?.state === 'running';
  const stacks = new Map(data.stacks.map((s) => [s.name, s]));
  const names = Array.from({ length: positions }, (_, k) => `${prefix}-${k + 1}`);
  const ready = names.every((n) => stacks.get(n)?.complete);
  const done = data.calibrations.find((c) => c.name === name && c.ready);
  return html`<section class="panel calibration">
    <p class="hint">Place the chrome sphere where the object will be, capture it, move it, capture again:
      two positions or more give each LED's position, one gives directions only.</p>
    <div class="row">
      <label>Positions <input id="calibration-positions" type="number" min="1" max="8" value=${positions}
        onInput=${(e) => setPositions(Math.max(1, Math.min(8, Number(e.target.value) || 1)))} /></label>
      <label>Stack names <input value=${prefix} onInput=${(e) => setPrefix(e.target.value)} />-N</label>
    </div>
    <ol class="steps">${names.map((stack, k) => {
      const captured = stacks.get(stack);
      const place = `chrome-${k + 1}`;
      return html`<li key=${stack} class="step">
        <h3>Position ${k + 1}: ${stack}</h3>
        ${status.simulated && choices.includes(place) && html`<button class="place" data-place=${place}
          disabled=${!operator || busy || status.simulated.placed === place}
          onClick=${() => act(() => post('/api/place', { object: place }))}>
          ${status.simulated.placed === place ? 'The sphere is at this position' : 'Place the sphere here'}</button>`}
        ${captured
          ? html`<span class="ok">${captured.frames} frames${captured.complete ? '' : ' (incomplete)'}</span>`
          : html`<button class="capture-sphere" data-stack=${stack} disabled=${!operator || busy}
              onClick=${() => act(() => post('/api/capture', { name: stack, target: 'chrome-sphere' }))}>
              Capture the sphere</button>`}
        ${captured?.complete && html`<${SphereEditor} stack=${stack} operator=${operator} act=${act} />`}
      </li>`;
    })}</ol>
    <div class="row">
      <label>Calibration name <input id="calibration-name" value=${name} onInput=${(e) => setName(e.target.value)} /></label>
      <button id="calibrate" disabled=${!operator || busy || !ready || done}
        onClick=${() => act(() => post('/api/calibrate', { name, stacks: names }))}>Calibrate the lights</button>
    </div>
    ${done && html`<${CalibrationResult} name=${name} />`}
  </section>`;
}
