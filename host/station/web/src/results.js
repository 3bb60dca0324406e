// Results: a stack solved with a chosen method (and calibration), then its
// surface and report; the report opens in its own tab, the normals, depth,
// mesh and RTI exports download.
import { useState } from 'preact/hooks';
import { fileUrl, post } from './api.js';
import { html } from './html.js';

export function ResultsPanel({ station }) {
  const { status, data, methods, operator, act } = station;
  const [stack, setStack] = useState('');
  const [method, setMethod] = useState('l2');
  const [calibration, setCalibration] = useState('');
  const [name, setName] = useState('');
  if (!status || !data) return html`<p>Loading…</p>`;
  const busy = status.job?.state === 'running';
  const stacks = data.stacks.filter((s) => s.complete);
  const chosen = stack || stacks[0]?.name || '';
  const solve = (event) => {
    event.preventDefault();
    const request = { stack: chosen, method };
    if (calibration) request.calibration = calibration;
    if (name.trim()) request.name = name.trim();
    act(() => post('/api/solve', request));
  };
  return html`<section class="panel results">
    <div>
      <h2>Solve</h2>
      <form id="solve-form" class="plan" onSubmit=${solve}>
        <label>Stack <select id="solve-stack" value=${chosen} onChange=${(e) => setStack(e.target.value)}>
          ${stacks.map((s) => html`<option key=${s.name} value=${s.name}>${s.name}</option>`)}
        </select></label>
        <label>Method <select id="solve-method" value=${method} onChange=${(e) => setMethod(e.target.value)}>
          ${methods.map((m) => html`<option key=${m} value=${m}>${m}</option>`)}
        </select></label>
        <label>Lights <select id="solve-calibration" value=${calibration} onChange=${(e) => setCalibration(e.target.value)}>
          <option value="">the stack's own</option>
          ${data.calibrations.filter((c) => c.ready).map((c) => html`<option key=${c.name} value=${c.name}>calibrated: ${c.name}</option>`)}
        </select></label>
        <label>Result name <input id="solve-name" placeholder=${`${chosen}-${method}`} value=${name}
          onInput=${(e) => setName(e.target.value)} /></label>
        <button id="solve-start" type="submit" disabled=${!operator || busy || !chosen}>Solve</button>
      </form>
    </div>
    <div>
      <h2>Results</h2>
      <table id="results" class="list">
        <thead><tr><th>Name</th><th>Method</th><th>Files</th><th>RTI</th></tr></thead>
        <tbody>${data.results.map((r) => html`<tr key=${r.name} data-result=${r.name}>
          <td>${r.name}</td>
          <td>${r.method}</td>
          <td class="files">${r.files.map((f) => f.endsWith('report.html')
            ? html`<a key=${f} class="report-link" href=${fileUrl(f)} target="_blank" rel="noopener">report</a>`
            : html`<a key=${f} href=${fileUrl(f)} download>${f.split('/').pop()}</a>`)}</td>
          <td>${['ptm', 'hsh'].map((format) => {
            const file = r.exports?.[format];
            return file
              ? html`<a key=${format} href=${fileUrl(file)} download>${file.split('/').pop()}</a>`
              : html`<button key=${format} class="export" data-format=${format} disabled=${!operator || busy}
                  onClick=${() => act(() => post('/api/export', { result: r.name, format }))}>${format.toUpperCase()}</button>`;
          })}</td>
        </tr>`)}</tbody>
      </table>
    </div>
  </section>`;
}
