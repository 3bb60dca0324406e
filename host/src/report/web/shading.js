// The viewer's shading: the same per-pixel models as the host's C++
// (host/include/lightstage/host/report/viewer_data.hpp, and the bi-polynomial
// model of host/include/lightstage/host/reflectance/bipolynomial_model.hpp).
// Camera frame: x right, y up, z toward the camera; viewer v = (0, 0, 1);
// light directions point from the object to the light; image row 0 is the top.
//
//   lambertian:    value = albedo · max(0, n·l)
//   bipolynomial:  value = max(0, ρ(n·h, l·h)) · max(0, n·l),  h = normalise(l + v),
//                  ρ(x, y) = Σ_i Σ_j C_ij x^i y^j, C_ij at index i·(k+1) + j
//                  (+ S · D(n·h) when model.lobe_width m > 0, S the pixel's last
//                  coefficient, D = exp(−tan²θ_h / m²) / cos⁴θ_h: specularLobe)
//   colour (a colour stack's result, surface.chroma): per channel c
//                  max(0, chroma_c · ρ_polynomial + ρ_lobe) · max(0, n·l)
//                  (Lambertian: chroma_c · albedo · max(0, n·l)); the lobe stays white
//
// Display: byte = round(255 · clamp01((exposure · value / scale)^(1/γ))) with
// γ = 1 (linear, the default, what `lightstage relight` writes) or the sRGB curve.

export function normalise(v) {
  const length = Math.hypot(v[0], v[1], v[2]);
  if (!(length > 0)) return [0, 0, 1];
  return [v[0] / length, v[1] / length, v[2] / length];
}

// ρ(x, y) of one pixel's coefficients (order k, (k+1)² terms starting at `offset`).
export function evaluateBiPolynomial(order, coefficients, offset, x, y) {
  const n = order + 1;
  let result = 0;
  for (let i = n - 1; i >= 0; --i) {
    let row = 0;
    for (let j = n - 1; j >= 0; --j) row = row * y + coefficients[offset + i * n + j];
    result = result * x + row;
  }
  return result;
}

// The relighting model's specular lobe (bipolynomial_model.hpp specular_lobe).
export function specularLobe(nh, width) {
  if (!(nh > 0) || !(width > 0)) return 0;
  const c = Math.min(nh, 1), c2 = c * c;
  const exponent = (1 - c2) / (c2 * width * width);
  return exponent > 700 ? 0 : Math.exp(-exponent) / (c2 * c2);  // as the C++: no 0/0 far down the tail
}

// Decodes the payload's normals (uint16, the normal.png encoding, 0 0 0 = none)
// into unit float normals and a validity mask, as io::decode_normal_map does.
export function decodeNormals(encoded, count) {
  const normals = new Float32Array(count * 3);
  const valid = new Uint8Array(count);
  for (let p = 0; p < count; ++p) {
    const ex = encoded[3 * p], ey = encoded[3 * p + 1], ez = encoded[3 * p + 2];
    if (ex === 0 && ey === 0 && ez === 0) continue;
    const x = (ex / 65535) * 2 - 1, y = (ey / 65535) * 2 - 1, z = (ez / 65535) * 2 - 1;
    const length = Math.hypot(x, y, z);
    if (!(length > 0)) continue;
    normals[3 * p] = x / length;
    normals[3 * p + 1] = y / length;
    normals[3 * p + 2] = z / length;
    valid[p] = 1;
  }
  return { normals, valid };
}

// Linear radiance of every pixel under the unit light `light` into `out`
// (Float32Array of width·height; 0 where there is no normal) and, when
// `colour` (Float32Array of width·height·3, r g b) is given, in colour.
export function renderRadiance(surface, light, out, colour = null) {
  const l = normalise(light);
  const { normals, valid, albedo, coefficients, model } = surface;
  const chroma = surface.chroma ?? null;
  const setColour = (p, polynomial, lobe, nl) => {
    if (!colour) return;
    for (let c = 0; c < 3; ++c) {
      const k = chroma ? chroma[3 * p + c] : 1;
      colour[3 * p + c] = Math.max(0, k * polynomial + lobe) * nl;
    }
  };
  const count = valid.length;
  const bipolynomial = model.kind === 'bipolynomial' && coefficients;
  const order = bipolynomial ? model.order : 0;
  const lobe = bipolynomial && model.lobe_width > 0 ? model.lobe_width : 0;
  const polynomialTerms = bipolynomial ? (order + 1) * (order + 1) : 0;
  const terms = polynomialTerms + (lobe > 0 ? 1 : 0);
  const h = normalise([l[0], l[1], l[2] + 1]);
  const lh = l[0] * h[0] + l[1] * h[1] + l[2] * h[2];
  for (let p = 0; p < count; ++p) {
    const nx = normals[3 * p], ny = normals[3 * p + 1], nz = normals[3 * p + 2];
    const nl = nx * l[0] + ny * l[1] + nz * l[2];
    if (!valid[p] || !(nl > 0)) {
      out[p] = 0;
      setColour(p, 0, 0, 0);
      continue;
    }
    let polynomial, specular = 0;
    if (bipolynomial) {
      const nh = nx * h[0] + ny * h[1] + nz * h[2];
      polynomial = evaluateBiPolynomial(order, coefficients, p * terms, nh, lh);
      if (lobe > 0) specular = coefficients[p * terms + polynomialTerms] * specularLobe(nh, lobe);
    } else {
      polynomial = albedo[p];
    }
    out[p] = Math.max(0, polynomial + specular) * nl;  // ρ clamped to ≥ 0
    setColour(p, polynomial, specular, nl);
  }
  return out;
}

function srgbEncode(v) {
  return v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
}

// Radiance to RGBA bytes for a canvas ImageData: grey, or the colour radiance
// (r g b per pixel) when given. Pixels without a normal get alpha 0.
export function toDisplay(radiance, valid, display, rgba, colour = null) {
  const factor = (display.exposure ?? 1) / (display.scale > 0 ? display.scale : 1);
  const srgb = display.gamma === 'srgb';
  const toByte = (value) => {
    let v = value * factor;
    v = v > 1 ? 1 : v > 0 ? v : 0;
    if (srgb) v = srgbEncode(v);
    return Math.round(v * 255);
  };
  for (let p = 0; p < radiance.length; ++p) {
    for (let c = 0; c < 3; ++c) rgba[4 * p + c] = toByte(colour ? colour[3 * p + c] : radiance[p]);
    rgba[4 * p + 3] = valid[p] ? 255 : 0;
  }
  return rgba;
}

// Light direction ↔ position on the hemisphere widget (orthographic view from
// the camera: disc x right, y up, the centre is the light at the camera).
export function lightFromDisc(x, y) {
  const r2 = x * x + y * y;
  if (r2 >= 1) {
    const r = Math.sqrt(r2);
    return [x / r, y / r, 0];
  }
  return [x, y, Math.sqrt(1 - r2)];
}

export function azimuthElevationDeg(l) {
  const v = normalise(l);
  const azimuth = (Math.atan2(v[1], v[0]) * 180) / Math.PI;
  const elevation = (Math.asin(Math.max(-1, Math.min(1, v[2]))) * 180) / Math.PI;
  return { azimuth: (azimuth + 360) % 360, elevation };
}
