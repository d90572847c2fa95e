// Encodes buffers with meshoptimizer's own encoder (npm `meshoptimizer`, the reference
// implementation of EXT_ and KHR_meshopt_compression) and decodes them with its decoder, so that
// lanterna's decoder (src/scene/meshopt.rs) is checked against streams it did not write.
//
//   cd /tmp && npm install meshoptimizer@1.3.0 gltfpack@1.3.0 && cd - && \
//     NODE_PATH=/tmp/node_modules node tests/data/meshopt/make_fixtures.mjs > tests/data/meshopt/fixtures.json
//
// The .glb files beside it are gltfpack 1.3.0's compressions of scenes in this
// repository (tests/scene_load.rs compares them with their originals):
//   gltfpack -i scenes/cornell-lights.gltf -o cornell-lights-noq.glb -c -noq
//   gltfpack -i tests/data/mitsuba/instanced.gltf -o instanced-cc-mi.glb -cc -mi
//   gltfpack -i tests/data/mitsuba/instanced.gltf -o instanced-cc-mi-khr.glb -cc -mi -ce khr
//   gltfpack -i tests/data/mitsuba/colors.gltf -o colors-cc-khr.glb -cc -ce khr
import { createRequire } from "module";
const require = createRequire(process.env.NODE_PATH + "/");
const { MeshoptEncoder, MeshoptDecoder } = require("meshoptimizer");

await MeshoptEncoder.ready;
await MeshoptDecoder.ready;

let seed = 12345;
const rand = () => {
  seed = (Math.imul(seed, 1103515245) + 12345) >>> 0;
  return seed >>> 8;
};
const b64 = (u8) => Buffer.from(u8).toString("base64");
const cases = [];

function add(name, count, stride, mode, filter, encoded) {
  const decoded = new Uint8Array(count * stride);
  MeshoptDecoder.decodeGltfBuffer(decoded, count, stride, encoded, mode, filter);
  cases.push({ name, count, stride, mode, filter: filter || "NONE", encoded: b64(encoded), decoded: b64(decoded) });
}

// Attributes: per byte lane, constant, small steps, medium noise and random bytes, so
// that every group mode (zero, 2-bit, 4-bit, raw) and the sentinels occur; several
// blocks where count exceeds a block's elements.
for (const stride of [4, 8, 12, 16, 64]) {
  for (const count of [1, 17, 300]) {
    for (const level of [0, 2]) {
      const src = new Uint8Array(count * stride);
      const acc = new Uint8Array(stride);
      for (let i = 0; i < count; i++) {
        for (let k = 0; k < stride; k++) {
          const lane = k % 4;
          if (lane === 0) acc[k] = 7;
          else if (lane === 1) acc[k] = (acc[k] + (rand() % 3)) & 255;
          else if (lane === 2) acc[k] = (acc[k] + (rand() % 21) - 10) & 255;
          else acc[k] = rand() & 255;
          src[i * stride + k] = acc[k];
        }
      }
      const enc = MeshoptEncoder.encodeVertexBufferLevel(src, count, stride, level, 0);
      add(`attributes stride ${stride} count ${count} level ${level}`, count, stride, "ATTRIBUTES", undefined, enc);
    }
  }
}

// Version 1 (KHR_meshopt_compression): the same byte lanes, and lanes of 16-bit counters
// and of floats on a smooth curve, where the encoder's higher levels pick the 2-byte and
// rotated-XOR channel modes and the 1-bit and literal control modes.
for (const stride of [4, 12, 16]) {
  for (const count of [17, 300]) {
    for (const level of [0, 3]) {
      const src = new Uint8Array(count * stride);
      const view = new DataView(src.buffer);
      for (let i = 0; i < count; i++) {
        for (let c = 0; c < stride / 4; c++) {
          const at = i * stride + 4 * c;
          const kind = (c + (stride === 4 ? count : 0)) % 4;
          if (kind === 0) view.setFloat32(at, 1.0 + (rand() % 1000) * 1e-6, true);
          else if (kind === 1) {
            view.setUint16(at, (40 * i + c) & 0xffff, true);
            view.setUint16(at + 2, (7 * i * i + (rand() % 5)) & 0xffff, true);
          } else if (kind === 2) {
            const v = (rand() & 1 ? 1 : -1) * Math.pow(2, rand() % 8) * (1 + (rand() % 256) / 256);
            view.setFloat32(at, v, true);
          } else for (let k = 0; k < 4; k++) src[at + k] = k < 2 ? rand() & 255 : (i >> k) & 255;
        }
      }
      const enc = MeshoptEncoder.encodeVertexBufferLevel(src, count, stride, level, 1);
      add(`attributes v1 stride ${stride} count ${count} level ${level}`, count, stride, "ATTRIBUTES", undefined, enc);
    }
  }
}

// Triangles: a grid in strip order (edges and FIFO hits) and random triangles with
// 32-bit indices (explicit indices, restarts).
function grid(n) {
  const out = [];
  for (let y = 0; y < n; y++)
    for (let x = 0; x < n; x++) {
      const v = y * (n + 1) + x;
      out.push(v, v + 1, v + n + 1, v + 1, v + n + 2, v + n + 1);
    }
  return out;
}
// Vertices renumbered in order of first use, as gltfpack writes them (optimised vertex
// fetch): the codes that reuse the FIFOs' edges and vertices dominate.
function firstUse(indices) {
  const map = new Map();
  return indices.map((v) => {
    if (!map.has(v)) map.set(v, map.size);
    return map.get(v);
  });
}
// A grid's triangles in rows of two, each row's quads alternating diagonals, in a
// cache-friendly order (column strips of 4 quads).
function strips(n) {
  const out = [];
  for (let x0 = 0; x0 < n; x0 += 4)
    for (let y = 0; y < n; y++)
      for (let x = x0; x < Math.min(x0 + 4, n); x++) {
        const v = y * (n + 1) + x;
        if ((x + y) % 2) out.push(v, v + 1, v + n + 2, v, v + n + 2, v + n + 1);
        else out.push(v, v + 1, v + n + 1, v + 1, v + n + 2, v + n + 1);
      }
  return out;
}
for (const [name, tris, stride] of [
  ["grid 12 first use", firstUse(grid(12)), 2],
  ["strips 24 first use", firstUse(strips(24)), 4],
  ["strips 9 first use", firstUse(strips(9)), 2],
  ["grid 8", grid(8), 2],
  ["grid 20", grid(20), 4],
  ["random", Array.from({ length: 300 }, () => rand() % 70000), 4],
  ["random small", Array.from({ length: 96 }, () => rand() % 40), 2],
]) {
  const src = stride === 2 ? new Uint16Array(tris) : new Uint32Array(tris);
  const enc = MeshoptEncoder.encodeIndexBuffer(new Uint8Array(src.buffer), tris.length, stride);
  add(`triangles ${name}`, tris.length, stride, "TRIANGLES", undefined, enc);
}

// Index sequences: two interleaved runs (both baselines) and random jumps.
for (const [name, seq, stride] of [
  ["two runs", Array.from({ length: 200 }, (_, i) => (i % 2 ? 1000 + i : i * 3)), 2],
  ["random", Array.from({ length: 150 }, () => rand() % 100000), 4],
]) {
  const src = stride === 2 ? new Uint16Array(seq) : new Uint32Array(seq);
  const enc = MeshoptEncoder.encodeIndexSequence(new Uint8Array(src.buffer), seq.length, stride);
  add(`indices ${name}`, seq.length, stride, "INDICES", undefined, enc);
}

// Filters, each encoded by the library's filter encoder then the attribute codec.
const count = 64;
const unit = new Float32Array(count * 4);
for (let i = 0; i < count; i++) {
  let v = [rand() / 8388608 - 1, rand() / 8388608 - 1, rand() / 8388608 - 1];
  const l = Math.hypot(...v);
  unit.set([v[0] / l, v[1] / l, v[2] / l, i % 2 ? 1 : -1], 4 * i);
}
for (const [stride, bits] of [[4, 8], [4, 6], [8, 16], [8, 11]]) {
  const f = MeshoptEncoder.encodeFilterOct(unit, count, stride, bits);
  const enc = MeshoptEncoder.encodeGltfBuffer(f, count, stride, "ATTRIBUTES", 0);
  add(`octahedral stride ${stride} bits ${bits}`, count, stride, "ATTRIBUTES", "OCTAHEDRAL", enc);
}
const quats = new Float32Array(count * 4);
for (let i = 0; i < count; i++) {
  let q = [0, 1, 2, 3].map(() => rand() / 8388608 - 1);
  const l = Math.hypot(...q);
  quats.set(q.map((c) => c / l), 4 * i);
}
for (const bits of [16, 12]) {
  const f = MeshoptEncoder.encodeFilterQuat(quats, count, 8, bits);
  const enc = MeshoptEncoder.encodeGltfBuffer(f, count, 8, "ATTRIBUTES", 0);
  add(`quaternion bits ${bits}`, count, 8, "ATTRIBUTES", "QUATERNION", enc);
}
const floats = new Float32Array(count * 3);
for (let i = 0; i < floats.length; i++) floats[i] = (rand() / 8388608 - 1) * Math.pow(2, (rand() % 40) - 20);
for (const bits of [23, 15]) {
  const f = MeshoptEncoder.encodeFilterExp(floats, count, 12, bits);
  const enc = MeshoptEncoder.encodeGltfBuffer(f, count, 12, "ATTRIBUTES", 0);
  add(`exponential bits ${bits}`, count, 12, "ATTRIBUTES", "EXPONENTIAL", enc);
}

const colors = new Float32Array(count * 4);
for (let i = 0; i < colors.length; i++) colors[i] = (rand() % 1000) / 999;
for (const [stride, bits] of [[4, 8], [4, 6], [8, 16], [8, 12]]) {
  const f = MeshoptEncoder.encodeFilterColor(colors, count, stride, bits);
  const enc = MeshoptEncoder.encodeGltfBuffer(f, count, stride, "ATTRIBUTES", 1);
  add(`color stride ${stride} bits ${bits}`, count, stride, "ATTRIBUTES", "COLOR", enc);
}

process.stdout.write(JSON.stringify({ generator: "meshoptimizer@1.3.0 (npm)", cases }, null, 1) + "\n");
