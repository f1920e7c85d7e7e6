// Meshes a heightmap with delatin (greedy Delaunay insertion, npm `delatin`) for
// `planetsculpt bench export`.
//   node delatin.mjs HEIGHTS.f32 WIDTH HEIGHT ERRORS OUT.jsonl [REPEATS]
// HEIGHTS.f32: WIDTH*HEIGHT little-endian float32 heights, row-major (index = y * WIDTH + x).
// ERRORS: comma-separated max errors. Each error is meshed from scratch (new Delatin + run), so
// its time is the whole job; REPEATS timed runs after one untimed warm-up (the JIT's).
// Writes OUT.jsonl, one line per error: {"max_error", "ms": [...], "coords": [x0, y0, ...],
// "triangles": [a, b, c, ...]}.
import fs from 'node:fs';
import Delatin from 'delatin';

const [input, widthArg, heightArg, errorsArg, output, repeatsArg] = process.argv.slice(2);
if (!output) {
  console.error('usage: node delatin.mjs HEIGHTS.f32 WIDTH HEIGHT ERRORS OUT.jsonl [REPEATS]');
  process.exit(2);
}
const width = Number(widthArg), height = Number(heightArg);
const errors = errorsArg.split(',').map(Number);
const repeats = Math.max(1, Number(repeatsArg || 3));
const bytes = fs.readFileSync(input);
if (bytes.length !== width * height * 4) {
  console.error(`${input}: ${bytes.length} bytes, expected ${width * height * 4}`);
  process.exit(2);
}
const data = new Float32Array(width * height);
for (let i = 0; i < data.length; i++) data[i] = bytes.readFloatLE(4 * i);

const out = fs.openSync(output, 'w');
for (const maxError of errors) {
  let tin = new Delatin(data, width, height);
  tin.run(maxError);  // warm-up
  const ms = [];
  for (let r = 0; r < repeats; r++) {
    const t0 = performance.now();
    tin = new Delatin(data, width, height);
    tin.run(maxError);
    ms.push(performance.now() - t0);
  }
  fs.writeSync(out, JSON.stringify({
    max_error: maxError,
    ms,
    coords: Array.from(tin.coords),
    triangles: Array.from(tin.triangles),
  }) + '\n');
}
fs.closeSync(out);
