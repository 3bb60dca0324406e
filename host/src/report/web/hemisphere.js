// The hemisphere widget: a disc seen from the camera (x right, y up; the
// centre is a light at the camera, the rim a light at the horizon). Drag on it
// with a mouse, pen or finger (pointer events), or focus it and use the arrow
// keys (Shift for small steps, Home for the camera direction).
import { azimuthElevationDeg, lightFromDisc, normalise } from './shading.js';

export class HemisphereWidget {
  // canvas: the <canvas> to draw on; captureLights: [[x,y,z], ...] drawn as
  // dots; onChange(light) is called whenever the light moves.
  constructor(canvas, captureLights, onChange) {
    this.canvas = canvas;
    this.captureLights = captureLights || [];
    this.onChange = onChange;
    this.light = [0, 0, 1];
    this.dragging = false;
    canvas.tabIndex = 0;
    canvas.style.touchAction = 'none';
    canvas.setAttribute('role', 'slider');
    canvas.setAttribute('aria-label', 'light direction: drag, or use the arrow keys');
    canvas.addEventListener('pointerdown', (event) => this.pointerDown(event));
    canvas.addEventListener('pointermove', (event) => this.pointerMove(event));
    canvas.addEventListener('pointerup', (event) => this.pointerUp(event));
    canvas.addEventListener('pointercancel', (event) => this.pointerUp(event));
    canvas.addEventListener('keydown', (event) => this.keyDown(event));
    this.draw();
  }

  geometry() {
    const width = this.canvas.width, height = this.canvas.height;
    return { cx: width / 2, cy: height / 2, r: Math.min(width, height) / 2 - 8 };
  }

  // Canvas pixel (CSS pixels relative to the element) to a disc position.
  discFromEvent(event) {
    const rect = this.canvas.getBoundingClientRect();
    const sx = this.canvas.width / rect.width, sy = this.canvas.height / rect.height;
    const { cx, cy, r } = this.geometry();
    const px = (event.clientX - rect.left) * sx, py = (event.clientY - rect.top) * sy;
    return [(px - cx) / r, -(py - cy) / r];
  }

  pointerDown(event) {
    this.dragging = true;
    this.canvas.setPointerCapture(event.pointerId);
    this.canvas.focus();
    event.preventDefault();
    this.set(lightFromDisc(...this.discFromEvent(event)));
  }

  pointerMove(event) {
    if (!this.dragging) return;
    event.preventDefault();
    this.set(lightFromDisc(...this.discFromEvent(event)));
  }

  pointerUp(event) {
    if (!this.dragging) return;
    this.dragging = false;
    if (this.canvas.hasPointerCapture(event.pointerId)) this.canvas.releasePointerCapture(event.pointerId);
  }

  keyDown(event) {
    const step = event.shiftKey ? 0.01 : 0.05;
    let [x, y] = this.light;
    switch (event.key) {
      case 'ArrowLeft': x -= step; break;
      case 'ArrowRight': x += step; break;
      case 'ArrowUp': y += step; break;
      case 'ArrowDown': y -= step; break;
      case 'Home': x = 0; y = 0; break;
      default: return;
    }
    event.preventDefault();
    this.set(lightFromDisc(x, y));
  }

  set(light, notify = true) {
    this.light = normalise(light);
    if (this.light[2] < 0) this.light = lightFromDisc(this.light[0], this.light[1]);
    const { azimuth, elevation } = azimuthElevationDeg(this.light);
    this.canvas.setAttribute('aria-valuetext',
      `azimuth ${azimuth.toFixed(0)} degrees, elevation ${elevation.toFixed(0)} degrees`);
    this.draw();
    if (notify && this.onChange) this.onChange(this.light);
  }

  draw() {
    const context = this.canvas.getContext('2d');
    const { cx, cy, r } = this.geometry();
    context.clearRect(0, 0, this.canvas.width, this.canvas.height);
    context.fillStyle = '#20242b';
    context.beginPath();
    context.arc(cx, cy, r, 0, 2 * Math.PI);
    context.fill();
    context.strokeStyle = '#59606b';
    context.lineWidth = 1;
    for (const elevation of [30, 60]) {  // rings of equal elevation
      context.beginPath();
      context.arc(cx, cy, r * Math.cos((elevation * Math.PI) / 180), 0, 2 * Math.PI);
      context.stroke();
    }
    context.beginPath();
    context.moveTo(cx - r, cy);
    context.lineTo(cx + r, cy);
    context.moveTo(cx, cy - r);
    context.lineTo(cx, cy + r);
    context.stroke();
    context.fillStyle = '#8fa3bf';
    for (const l of this.captureLights) {
      context.beginPath();
      context.arc(cx + l[0] * r, cy - l[1] * r, 2, 0, 2 * Math.PI);
      context.fill();
    }
    const [x, y] = this.light;
    context.fillStyle = '#ffd23f';
    context.strokeStyle = '#000000';
    context.lineWidth = 2;
    context.beginPath();
    context.arc(cx + x * r, cy - y * r, 7, 0, 2 * Math.PI);
    context.fill();
    context.stroke();
  }
}
