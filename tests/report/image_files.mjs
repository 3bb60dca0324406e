// Reading the images the CLI writes, for the browser test: PFM (float, "Pf"
// grey or "PF" RGB, rows stored bottom-up) and PNG (8- or 16-bit, grey, grey +
// alpha, RGB or RGBA, not interlaced). Returns { width, height, channels,
// data, max } with row 0 at the top and `max` the full-scale value (1 for PFM).
import fs from 'node:fs';
import zlib from 'node:zlib';

function readPfm(file, bytes) {
  let offset = 0;
  const token = () => {
    while (/\s/.test(String.fromCharCode(bytes[offset]))) ++offset;
    const start = offset;
    while (!/\s/.test(String.fromCharCode(bytes[offset]))) ++offset;
    return bytes.subarray(start, offset).toString('ascii');
  };
  const kind = token();
  if (kind !== 'Pf' && kind !== 'PF') throw new Error(`${file}: not a PFM (starts with '${kind}')`);
  const width = Number(token()), height = Number(token()), scale = Number(token());
  offset += 1;  // the single whitespace after the scale
  const channels = kind === 'PF' ? 3 : 1;
  const little = scale < 0;
  const data = new Float32Array(width * height * channels);
  const view = new DataView(bytes.buffer, bytes.byteOffset + offset);
  for (let row = 0; row < height; ++row) {
    const y = height - 1 - row;  // stored bottom-up
    for (let i = 0; i < width * channels; ++i) {
      data[y * width * channels + i] = view.getFloat32((row * width * channels + i) * 4, little);
    }
  }
  return { width, height, channels, data, max: 1 };
}

function readPng(file, bytes) {
  const signature = [137, 80, 78, 71, 13, 10, 26, 10];
  signature.forEach((b, i) => {
    if (bytes[i] !== b) throw new Error(`${file}: not a PNG`);
  });
  let offset = 8;
  let header = null;
  const idat = [];
  while (offset < bytes.length) {
    const length = bytes.readUInt32BE(offset);
    const type = bytes.subarray(offset + 4, offset + 8).toString('ascii');
    const body = bytes.subarray(offset + 8, offset + 8 + length);
    if (type === 'IHDR') {
      header = { width: body.readUInt32BE(0), height: body.readUInt32BE(4), depth: body[8], colour: body[9],
        interlace: body[12] };
    } else if (type === 'IDAT') {
      idat.push(body);
    } else if (type === 'IEND') {
      break;
    }
    offset += 12 + length;
  }
  if (!header) throw new Error(`${file}: PNG without IHDR`);
  const channels = { 0: 1, 2: 3, 4: 2, 6: 4 }[header.colour];
  if (!channels || header.interlace !== 0 || (header.depth !== 8 && header.depth !== 16)) {
    throw new Error(`${file}: unsupported PNG (colour type ${header.colour}, depth ${header.depth})`);
  }
  const { width, height, depth } = header;
  const bytesPerPixel = (channels * depth) / 8;
  const stride = width * bytesPerPixel;
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const pixels = Buffer.alloc(stride * height);
  const paeth = (a, b, c) => {
    const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
  };
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; ++i) {
      const a = i >= bytesPerPixel ? pixels[y * stride + i - bytesPerPixel] : 0;
      const b = y > 0 ? pixels[(y - 1) * stride + i] : 0;
      const c = y > 0 && i >= bytesPerPixel ? pixels[(y - 1) * stride + i - bytesPerPixel] : 0;
      const predictor = [0, a, b, (a + b) >> 1, paeth(a, b, c)][filter];
      if (predictor === undefined) throw new Error(`${file}: bad PNG filter ${filter} in row ${y}`);
      pixels[y * stride + i] = (line[i] + predictor) & 255;
    }
  }
  const data = new Float32Array(width * height * channels);
  for (let i = 0; i < data.length; ++i) data[i] = depth === 16 ? pixels.readUInt16BE(2 * i) : pixels[i];
  return { width, height, channels, data, max: depth === 16 ? 65535 : 255 };
}

export function readImage(file) {
  const bytes = fs.readFileSync(file);
  if (file.endsWith('.pfm')) return readPfm(file, bytes);
  if (file.endsWith('.png')) return readPng(file, bytes);
  throw new Error(`${file}: expected a .pfm or .png`);
}
