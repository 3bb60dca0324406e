// The live view: the camera's frame at one LED, to place, expose and focus
// by. The histogram (log counts) shows clipping in red; the sharpness number
// rises as focus improves (its best so far is kept to focus against).
import { useEffect, useRef, useState } from 'preact/hooks';
import { apiImageUrl, post } from './api.js';
import { html } from './html.js';
import { LedMap } from './led_map.js';

function Histogram({ counts }) {
  const canvas = useRef(null);
  useEffect(() => {
    const c = canvas.current;
    if (!c || !counts) return;
    const g = c.getContext('2d');
    g.clearRect(0, 0, c.width, c.height);
    const top = Math.log1p(Math.max(...counts));
    const w = c.width / counts.length;
    counts.forEach((n, i) => {
      const bar = top > 0 ? (Math.log1p(n) / top) * c.height : 0;
      g.fillStyle = i === counts.length - 1 && n > 0 ? '#d33' : '#4a7';
      g.fillRect(i * w, c.height - bar, Math.max(1, w - 1), bar);
    });
  }, [counts]);
  return html`<canvas id="histogram" ref=${canvas} width="320" height="100"></canvas>`;
}

export function LivePanel({ station }) {
  const { rig, status, operator, act } = station;
  const [led, setLed] = useState(rig?.leds?.[0]?.id ?? 0);
  const [exposure, setExposure] = useState(10000);
  const [gain, setGain] = useState('');
  const [figures, setFigures] = useState(null);
  const [image, setImage] = useState('');
  const [live, setLive] = useState(false);
  const [best, setBest] = useState(0);
  const taking = useRef(false);

  const take = async () => {
    if (taking.current) return;
    taking.current = true;
    const body = { led: Number(led), exposure_us: Number(exposure) };
    if (gain !== '') body.gain = Number(gain);
    const result = await act(() => post('/api/preview', body));
    taking.current = false;
    if (!result) {
      setLive(false);
      return;
    }
    setFigures(result);
    setBest((b) => Math.max(b, result.sharpness));
    setImage(apiImageUrl('/api/preview.png'));
  };
  useEffect(() => {
    if (!live) return undefined;
    const timer = setInterval(take, 1000);
    return () => clearInterval(timer);
  }, [live, led, exposure, gain]);

  if (!rig) return html`<p>Loading…</p>`;
  const busy = status?.job?.state === 'running';
  return html`<section class="panel live">
    <div>
      <${LedMap} id="live-led-map" leds=${rig.leds} lit=${new Set()} selected=${Number(led)}
        onPick=${(id) => setLed(id)} />
      <form class="row" onSubmit=${(e) => { e.preventDefault(); take(); }}>
        <label>LED <input id="live-led" type="number" value=${led} onInput=${(e) => setLed(e.target.value)} /></label>
        <label>Exposure (µs) <input id="live-exposure" type="number" min="1" value=${exposure}
          onInput=${(e) => setExposure(e.target.value)} /></label>
        <label>Gain <input id="live-gain" type="number" min="0" step="0.1" placeholder="camera's" value=${gain}
          onInput=${(e) => setGain(e.target.value)} /></label>
        <button id="live-take" type="submit" disabled=${!operator || busy}>Take a frame</button>
        <label><input id="live-repeat" type="checkbox" checked=${live} disabled=${!operator || busy}
          onChange=${(e) => setLive(e.target.checked)} /> live</label>
      </form>
    </div>
    <div>
      ${image ? html`<img id="live-image" class="frame" src=${image} alt="the camera's frame" />`
        : html`<p class="hint">${operator ? 'Take a frame to see what the camera sees.' : 'Take control to use the camera.'}</p>`}
      ${figures && html`<div class="figures">
        <${Histogram} counts=${figures.histogram} />
        <dl class="facts">
          <dt>Clipped</dt><dd id="live-clipped" class=${figures.clipped > 0.001 ? 'fault' : ''}>
            ${(100 * figures.clipped).toFixed(2)} %</dd>
          <dt>Mean</dt><dd>${(100 * figures.mean).toFixed(1)} % of full scale</dd>
          <dt>Sharpness</dt><dd id="live-sharpness">${figures.sharpness.toFixed(1)}
            (best ${best.toFixed(1)}) <button type="button" onClick=${() => setBest(0)}>reset</button></dd>
          <dt>Size</dt><dd>${figures.width} × ${figures.height}</dd>
        </dl>
      </div>`}
    </div>
  </section>`;
}
