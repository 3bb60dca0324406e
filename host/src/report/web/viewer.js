// The relighting viewer of a Lightstage report. The page (written by
// host/src/report/report.cpp) carries:
//   <script type="application/json" id="lightstage-viewer-meta">  width, height,
//       planes (name, type, components, offset, bytes), model, display, lights
//   <script type="application/octet-stream" id="lightstage-viewer-data">  base64
//       of the planes (zlib-deflated when meta.encoding is "deflate")
// and the elements #viewer-canvas, #viewer-hemisphere, #viewer-exposure,
// #viewer-srgb, #viewer-readout, #viewer-status (and #viewer-grey for a colour result).
//
// Test hook: window.lightstageViewer = { ready, setLight(x, y, z), getLight(),
// getImageData(), getRadiance(), getColourRadiance() (null for grey), meta, renders }.
import { azimuthElevationDeg, decodeNormals, normalise, renderRadiance, toDisplay } from './shading.js';
import { HemisphereWidget } from './hemisphere.js';

function base64Bytes(text) {
  const binary = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

async function payloadBuffer(meta, text) {
  const bytes = base64Bytes(text);
  if (meta.encoding === 'raw') return bytes.buffer;
  if (meta.encoding !== 'deflate') throw new Error(`viewer data: unknown encoding '${meta.encoding}'`);
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Response(stream).arrayBuffer();
}

function plane(meta, buffer, name) {
  const entry = meta.planes.find((p) => p.name === name);
  if (!entry) return null;
  const count = meta.width * meta.height * entry.components;
  if (entry.offset + entry.bytes > buffer.byteLength) {
    throw new Error(`viewer data: plane '${name}' runs past the end of the data`);
  }
  if (entry.type === 'float32') return new Float32Array(buffer, entry.offset, count);
  if (entry.type === 'uint16') return new Uint16Array(buffer, entry.offset, count);
  throw new Error(`viewer data: plane '${name}' has unknown type '${entry.type}'`);
}

async function loadSurface(meta, dataText) {
  const buffer = await payloadBuffer(meta, dataText);
  const count = meta.width * meta.height;
  const encoded = plane(meta, buffer, 'normals');
  const albedo = plane(meta, buffer, 'albedo');
  if (!encoded || !albedo) throw new Error('viewer data: the normals or albedo plane is missing');
  const { normals, valid } = decodeNormals(encoded, count);
  const coefficients = meta.model.kind === 'bipolynomial' ? plane(meta, buffer, 'coefficients') : null;
  if (meta.model.kind === 'bipolynomial' && !coefficients) {
    throw new Error('viewer data: a bi-polynomial model without its coefficients plane');
  }
  if (coefficients) {
    const terms = (meta.model.order + 1) ** 2 + (meta.model.lobe_width > 0 ? 1 : 0);
    const given = meta.planes.find((p) => p.name === 'coefficients').components;
    if (given !== terms) throw new Error(`viewer data: ${given} coefficients per pixel, the model has ${terms}`);
  }
  const chroma = meta.colour ? plane(meta, buffer, 'chroma') : null;
  if (meta.colour && !chroma) throw new Error('viewer data: a colour result without its chroma plane');
  return { normals, valid, albedo, coefficients, chroma, model: meta.model };
}

function byId(id) {
  const element = document.getElementById(id);
  if (!element) throw new Error(`viewer: the page has no #${id}`);
  return element;
}

async function start() {
  const meta = JSON.parse(byId('lightstage-viewer-meta').textContent);
  const surface = await loadSurface(meta, byId('lightstage-viewer-data').textContent);
  const canvas = byId('viewer-canvas');
  canvas.width = meta.width;
  canvas.height = meta.height;
  const context = canvas.getContext('2d', { willReadFrequently: true });
  const image = context.createImageData(meta.width, meta.height);
  const radiance = new Float32Array(meta.width * meta.height);
  const colour = surface.chroma ? new Float32Array(meta.width * meta.height * 3) : null;
  const display = { scale: meta.display.scale, exposure: 1, gamma: meta.display.gamma || 'linear' };
  const exposure = byId('viewer-exposure');
  const srgb = byId('viewer-srgb');
  const readout = byId('viewer-readout');
  const hook = window.lightstageViewer;
  let light = normalise(meta.light || [0, 0, 1]);

  const render = () => {
    renderRadiance(surface, light, radiance, colour);
    toDisplay(radiance, surface.valid, display, image.data, display.grey ? null : colour);
    context.putImageData(image, 0, 0);
    const { azimuth, elevation } = azimuthElevationDeg(light);
    readout.textContent = `l = (${light.map((v) => v.toFixed(3)).join(', ')}), ` +
      `azimuth ${azimuth.toFixed(1)}°, elevation ${elevation.toFixed(1)}°`;
    hook.renders += 1;
  };
  const widget = new HemisphereWidget(byId('viewer-hemisphere'), meta.lights, (l) => {
    light = l;
    render();
  });
  exposure.addEventListener('input', () => {
    display.exposure = Math.pow(2, Number(exposure.value));
    render();
  });
  const grey = document.getElementById('viewer-grey');
  if (grey) {
    grey.checked = false;  // a reload may restore the box; the canvas starts in colour
    grey.addEventListener('change', () => {
      display.grey = grey.checked;
      render();
    });
  }
  srgb.checked = display.gamma === 'srgb';
  srgb.addEventListener('change', () => {
    display.gamma = srgb.checked ? 'srgb' : 'linear';
    render();
  });

  hook.meta = meta;
  hook.setLight = (x, y, z) => widget.set([x, y, z]);
  hook.getLight = () => light.slice();
  hook.getImageData = () => context.getImageData(0, 0, meta.width, meta.height);
  hook.getRadiance = () => radiance.slice();
  hook.getColourRadiance = () => (colour ? colour.slice() : null);
  widget.set(light);
}

window.lightstageViewer = { renders: 0 };
window.lightstageViewer.ready = start().catch((error) => {
  const status = document.getElementById('viewer-status');
  if (status) status.textContent = `The viewer could not start: ${error.message}`;
  console.error(`lightstage viewer: ${error.message}`);
  throw error;
});
