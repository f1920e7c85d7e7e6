// Meshes a heightmap with @mapbox/martini for `planetsculpt bench export`.
//   node mesh.mjs HEIGHTS.f32 SIZE ERRORS OUT.jsonl [REPEATS]
// HEIGHTS.f32: SIZE*SIZE little-endian float32 heights, row-major (index = y * SIZE + x), SIZE =
// 2^k+1. ERRORS: comma-separated max errors (Martini's own threshold, in the heights' units).
// Writes OUT.jsonl, JSON lines: first {"size", "init_ms", "build_ms": [...]}, then one line per
// error {"max_error", "mesh_ms": [...], "vertices": [x0, y0, x1, y1, ...], "triangles": [a, b, c,
// ...]} (one line each: a 1025^2 sweep is more than one JavaScript string can hold). Martini's
// triangle (a, b, c) has its hypotenuse a-b and its right angle at c. Each timing is repeated
// REPEATS times after one untimed warm-up run (the JIT's), so medians compare like with like.
import fs from 'node:fs';
import Martini from '@mapbox/martini';

const [input, sizeArg, errorsArg, output, repeatsArg] = process.argv.slice(2);
if (!output) {
  console.error('usage: node mesh.mjs HEIGHTS.f32 SIZE ERRORS OUT.jsonl [REPEATS]');
  process.exit(2);
}
const size = Number(sizeArg);
const errors = errorsArg.split(',').map(Number);
const repeats = Math.max(1, Number(repeatsArg || 5));
const bytes = fs.readFileSync(input);
if (bytes.length !== size * size * 4) {
  console.error(`${input}: ${bytes.length} bytes, expected ${size * size * 4} for ${size}x${size} float32`);
  process.exit(2);
}
const terrain = new Float32Array(size * size);
for (let i = 0; i < terrain.length; i++) terrain[i] = bytes.readFloatLE(4 * i);

let t0 = performance.now();
const martini = new Martini(size);
const initMs = performance.now() - t0;

let tile = martini.createTile(terrain);  // warm-up
const buildMs = [];
for (let r = 0; r < repeats; r++) {
  t0 = performance.now();
  tile = martini.createTile(terrain);
  buildMs.push(performance.now() - t0);
}

const out = fs.openSync(output, 'w');
fs.writeSync(out, JSON.stringify({size, init_ms: initMs, build_ms: buildMs}) + '\n');
for (const maxError of errors) {
  let mesh = tile.getMesh(maxError);  // warm-up
  const meshMs = [];
  for (let r = 0; r < repeats; r++) {
    t0 = performance.now();
    mesh = tile.getMesh(maxError);
    meshMs.push(performance.now() - t0);
  }
  const line = JSON.stringify({
    max_error: maxError,
    mesh_ms: meshMs,
    vertices: Array.from(mesh.vertices),
    triangles: Array.from(mesh.triangles),
  });
  fs.writeSync(out, line + '\n');
}
fs.closeSync(out);
