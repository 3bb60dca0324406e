// The operator's station page: the dome, the live view, the calibration
// wizard, captures and results, over the station's API (api.js). The page
// polls the status every second, which also keeps this tab's control alive:
// a closed tab lets it lapse, and LEDs it lit go dark.
import { render } from 'preact';
import { useCallback, useEffect, useState } from 'preact/hooks';
import { get, post } from './api.js';
import { html, formatSeconds } from './html.js';
import { DomePanel } from './dome.js';
import { LivePanel } from './live.js';
import { CalibrationPanel } from './calibration.js';
import { CapturePanel } from './capture.js';
import { ResultsPanel } from './results.js';

const TABS = [
  ['dome', 'Dome', DomePanel],
  ['live', 'Live view', LivePanel],
  ['calibration', 'Calibration', CalibrationPanel],
  ['capture', 'Capture', CapturePanel],
  ['results', 'Results', ResultsPanel],
];

function ControlBar({ access, act }) {
  const [name, setName] = useState(localStorage.getItem('lightstage-operator') ?? '');
  if (!access) return null;
  if (access.you === 'operator') {
    return html`<div class="control">
      <span class="role operator">You control the dome (${access.operator})</span>
      <button id="release" onClick=${() => act(() => post('/api/control/release'))}>Release control</button>
    </div>`;
  }
  const take = (event) => {
    event.preventDefault();
    localStorage.setItem('lightstage-operator', name);
    act(() => post('/api/control', { name }));
  };
  return html`<form class="control" onSubmit=${take}>
    <span class="role viewer">${access.operator ? `Read-only: ${access.operator} controls the dome` : 'Read-only'}</span>
    <input id="operator-name" placeholder="Your name" value=${name} maxlength="64"
      onInput=${(e) => setName(e.target.value)} />
    <button id="take-control" type="submit">Take control</button>
  </form>`;
}

function JobBar({ job, operator, act }) {
  if (!job) return null;
  const share = job.total > 0 ? job.done / job.total : 0;
  const running = job.state === 'running';
  return html`<div class=${`job ${job.state}`} id="job" data-id=${job.id}>
    <span class="job-kind">${job.kind}</span>
    <span class="job-state" id="job-state">${job.state}</span>
    ${job.total > 0 && html`<progress max="1" value=${share}></progress>
      <span>${job.done} / ${job.total} ${job.unit}</span>`}
    ${running && job.eta_seconds !== null && html`<span class="eta">${formatSeconds(job.eta_seconds)} left</span>`}
    ${running && job.message && html`<span class="job-message">${job.message}</span>`}
    ${job.error && html`<span class="job-error">${job.error}</span>`}
    ${running && operator && job.stoppable && html`<span class="job-actions">
      <button id="job-stop" onClick=${() => act(() => post('/api/job/stop'))}>
        ${job.kind === 'capture' ? 'Pause' : 'Stop'}</button>
      ${job.kind === 'capture' &&
        html`<button id="job-abort" class="danger" onClick=${() => act(() => post('/api/job/abort'))}>Abort</button>`}
    </span>`}
  </div>`;
}

function App() {
  const [tab, setTab] = useState(location.hash.slice(1) || 'dome');
  const [status, setStatus] = useState(null);
  const [access, setAccess] = useState(null);
  const [rig, setRig] = useState(null);
  const [data, setData] = useState(null);
  const [methods, setMethods] = useState([]);
  const [error, setError] = useState('');
  const [offline, setOffline] = useState(false);

  const refresh = useCallback(async () => {
    try {
      const [s, a, d] = await Promise.all([get('/api/status'), get('/api/access'), get('/api/data')]);
      setStatus(s);
      setAccess(a);
      setData(d);
      setOffline(false);
    } catch (e) {
      if (e.status === 401) setError(`${e.message}: open the address the station printed`);
      setOffline(true);
    }
  }, []);

  useEffect(() => {
    Promise.all([get('/api/rig'), get('/api/methods')]).then(([r, m]) => {
      setRig(r);
      setMethods(m);
    }).catch((e) => setError(e.message));
    refresh();
    const timer = setInterval(refresh, 1000);
    return () => clearInterval(timer);
  }, [refresh]);

  // Runs an action; its refusal is shown, and the state read again either way.
  const act = useCallback(async (action) => {
    setError('');
    try {
      return await action();
    } catch (e) {
      setError(e.message);
      return undefined;
    } finally {
      refresh();
    }
  }, [refresh]);

  const operator = access?.you === 'operator';
  const station = { status, access, rig, data, methods, operator, act, refresh, setError };
  const dome = status?.dome;
  const select = (id) => {
    setTab(id);
    history.replaceState(null, '', `#${id}`);
  };
  return html`<header>
      <h1>Lightstage station <small>${status?.rig?.name ?? ''}</small></h1>
      <span id="dome-state" class=${`dome-state ${dome?.connected ? 'connected' : 'disconnected'}`}>
        ${offline ? 'station unreachable' : dome?.connected
          ? `dome ${dome.controller?.state?.toLowerCase() ?? ''}` : `dome not connected${dome?.error ? `: ${dome.error}` : ''}`}
      </span>
      <button id="dark" class="danger" title="Every LED off, now (any page may)"
        onClick=${() => act(() => post('/api/dark'))}>All LEDs off</button>
      <${ControlBar} access=${access} act=${act} />
    </header>
    <${JobBar} job=${status?.job} operator=${operator} act=${act} />
    ${error && html`<div class="error" id="error" role="alert">${error}
      <button class="close" onClick=${() => setError('')}>×</button></div>`}
    <nav>${TABS.map(([id, label]) => html`<button id=${`tab-${id}`} class=${tab === id ? 'active' : ''}
      onClick=${() => select(id)}>${label}</button>`)}</nav>
    <main>${TABS.filter(([id]) => id === tab).map(([id, , Panel]) => html`<${Panel} key=${id} station=${station} />`)}</main>`;
}

render(html`<${App} />`, document.getElementById('app'));
