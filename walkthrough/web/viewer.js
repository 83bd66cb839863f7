// The walkvis web viewer: walks a building exported by `walkvis export FILE --web DIR` in WebGL2,
// drawing each frame in the painter's order of its HFD tree (James & Day 1998 [JamesDay1998HFD],
// docs/REFERENCES.md) with the depth test off. The rules are the C++ walkthrough's, ported line
// for line so that a page and `walkvis render` agree (docs/web/README.md):
//   format      the export's containers, walkvis.bin and one per view cell (docs/web/README.md,
//               "Format"), checksummed (FNV-1a 64)
//   planeSign   exact sign of n·p − d (bsp/exact_sign.h: a filter, then an exact expansion sum)
//   frameOrder  walkthrough/frame.cpp: the level whose height plane holds the eye, its view cell,
//               the tree's root-to-leaf walk (pfd_hfd/pfd.cpp); the BSP's back-to-front order
//               anywhere else (stairs, off the height plane)
//   Walker      walkthrough/movement.cpp: eye height over the floor, steps, walls, sliding
// In a browser it runs the page (index.html); under Node it exports the same functions, which
// tests/web/parity.js checks against the C++ library.
'use strict';

(function (global) {
  // ---- format -------------------------------------------------------------------------------
  const kMagic = 'WALKVISW';
  const kVersion = 3;
  const kHeaderBytes = 40;
  const kTocEntryBytes = 40;
  const kRaw = 0, kDeflate = 1;  // a section's encoding (deflate: a zlib stream, RFC 1950)

  class ExportError extends Error {}

  // FNV-1a 64 over bytes as four 16-bit limbs (JavaScript has no 64-bit integer arithmetic short of
  // BigInt, which is two orders slower): the hash core/hash.h writes, whose offset basis is
  // 1469598103934665603 (0x14650fb0739d0383; the published basis has one more digit), kept as it is
  // because every walkvis file's checksum depends on it.
  function fnv1a64(bytes) {
    let h0 = 0x0383, h1 = 0x739d, h2 = 0x0fb0, h3 = 0x1465;  // low limb first
    for (let i = 0; i < bytes.length; ++i) {
      h0 ^= bytes[i];
      // h *= 0x100000001b3 = 2^40 + 0x1b3 (mod 2^64): limb products with carries.
      const t0 = h0 * 0x1b3;
      const t1 = h1 * 0x1b3 + (t0 >>> 16);
      const t2 = h2 * 0x1b3 + (t1 >>> 16) + (h0 << 8);
      const t3 = h3 * 0x1b3 + (t2 >>> 16) + (h1 << 8);
      h0 = t0 & 0xffff;
      h1 = t1 & 0xffff;
      h2 = t2 & 0xffff;
      h3 = t3 & 0xffff;
    }
    return [(h1 << 16 | h0) >>> 0, (h3 << 16 | h2) >>> 0];  // [low, high] 32-bit words
  }

  function u64(view, at) {
    const lo = view.getUint32(at, true), hi = view.getUint32(at + 4, true);
    return hi * 4294967296 + lo;
  }

  // The `length` bytes of a zlib stream, inflated by the platform (browsers and Node alike) into
  // one buffer as the chunks come (a quarter faster on FZK-Haus than new Response(stream)'s
  // arrayBuffer(), which gathers them first); rejects when the stream is bad or of another length.
  async function inflate(bytes, length) {
    const out = new Uint8Array(length);
    const reader = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate')).getReader();
    let at = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      if (value.length > length - at) throw new Error('longer than ' + length + ' bytes');
      out.set(value, at);
      at += value.length;
    }
    if (at !== length) throw new Error(at + ' bytes, not ' + length);
    return out.buffer;
  }

  // Reads a container (walkvis.bin or a cell file): header, table, every section checked against
  // its checksum as stored, then the deflated ones inflated. Resolves to its sections, each with
  // the buffer and offset of its bytes (the file itself for a raw one), and the checksum of its
  // table as 16 hex digits; rejects with an ExportError naming `name` and what is wrong.
  async function readContainer(buffer, name) {
    const fail = (what) => { throw new ExportError(name + ': ' + what); };
    const bytes = new Uint8Array(buffer);
    if (bytes.length < kHeaderBytes) fail('truncated (' + bytes.length + ' bytes, no header)');
    const view = new DataView(buffer);
    let magic = '';
    for (let i = 0; i < 8; ++i) magic += String.fromCharCode(bytes[i]);
    if (magic !== kMagic) fail('not a walkvis web export (wrong magic)');
    const version = view.getUint32(8, true);
    if (version !== kVersion) fail('format version ' + version + ', this viewer reads ' + kVersion);
    const count = view.getUint32(12, true);
    const total = u64(view, 16);
    if (total !== bytes.length) fail('truncated or extended: ' + bytes.length + ' bytes, the header says ' + total);
    if (kHeaderBytes + count * kTocEntryBytes > bytes.length) fail('truncated (table of sections)');
    const toc = bytes.subarray(kHeaderBytes, kHeaderBytes + count * kTocEntryBytes);
    const tocSum = fnv1a64(toc);
    if (tocSum[0] !== view.getUint32(24, true) || tocSum[1] !== view.getUint32(28, true))
      fail('checksum mismatch in the table of sections');
    const sections = [];
    for (let k = 0; k < count; ++k) {
      const at = kHeaderBytes + k * kTocEntryBytes;
      let tag = '';
      for (let i = 0; i < 4; ++i) tag += String.fromCharCode(bytes[at + i]);
      const encoding = view.getUint32(at + 4, true);
      const offset = u64(view, at + 8), stored = u64(view, at + 16), length = u64(view, at + 24);
      if (offset % 8 !== 0 || offset + stored > bytes.length) fail('section ' + k + ' (' + tag + ') out of range');
      if (encoding !== kRaw && encoding !== kDeflate) fail('section ' + k + ' (' + tag + '): unknown encoding ' + encoding);
      if (encoding === kRaw && stored !== length) fail('section ' + k + ' (' + tag + '): sizes disagree');
      const body = bytes.subarray(offset, offset + stored);
      const sum = fnv1a64(body);
      if (sum[0] !== view.getUint32(at + 32, true) || sum[1] !== view.getUint32(at + 36, true))
        fail('checksum mismatch in section ' + k + ' (' + tag + ')');
      sections.push({ tag, encoding, body, buffer, offset, length });
    }
    await Promise.all(sections.filter((s) => s.encoding === kDeflate).map(async (s) => {
      let raw;
      try {
        raw = await inflate(s.body, s.length);
      } catch (e) {
        fail('section ' + s.tag + ' does not inflate (' + e.message + ')');
      }
      s.buffer = raw, s.offset = 0;
    }));
    const hex = (w) => w.toString(16).padStart(8, '0');
    return { sections, checksum: hex(tocSum[1]) + hex(tocSum[0]) };
  }

  // Reads walkvis.bin (a promise of the scene). Its view cells are listed in scene.cells with no
  // tree until attachCell hands one over. Rejects with an ExportError naming `name`.
  async function parseExport(buffer, name) {
    const fail = (what) => { throw new ExportError(name + ': ' + what); };
    const { sections } = await readContainer(buffer, name);
    const bytes = new Uint8Array(buffer);
    const find = (tag) => {
      const s = sections.filter((x) => x.tag === tag);
      if (s.length === 0) fail('no ' + tag + ' section');
      return s;
    };
    const f64 = (s) => new Float64Array(s.buffer, s.offset, s.length / 8);
    const u32 = (s, from, n) => new Uint32Array(s.buffer, s.offset + from, n);
    const i32 = (s, from, n) => new Int32Array(s.buffer, s.offset + from, n);

    let meta;
    try {
      const m = find('META')[0];
      meta = JSON.parse(new TextDecoder().decode(new Uint8Array(m.buffer, m.offset, m.length)));
    } catch (e) {
      if (e instanceof ExportError) throw e;
      fail('META section is not JSON (' + e.message + ')');
    }
    const scene = {
      meta,
      vertices: f64(find('VERT')[0]),
      frag: (() => { const s = find('FRAG')[0]; return u32(s, 0, s.length / 4); })(),
      frag_planes: f64(find('FPLN')[0]),
      bsp_nodes: (() => { const s = find('BNOD')[0]; return i32(s, 0, s.length / 4); })(),
      bsp_planes: f64(find('BPLN')[0]),
      levels: [],
      cells: [],
      walk: null,
      bytes: bytes.length,
    };
    const n = meta.fragments, v = meta.vertices, m = meta.bsp_nodes;
    if (scene.frag.length !== 4 * n || scene.frag_planes.length !== 4 * n) fail('fragment arrays disagree with META');
    if (scene.vertices.length !== 3 * v) fail('vertex array disagrees with META');
    if (scene.bsp_nodes.length !== 4 * m || scene.bsp_planes.length !== 4 * m) fail('BSP arrays disagree with META');
    for (let f = 0; f < n; ++f) {
      if (scene.frag[4 * f + 1] < 3 || scene.frag[4 * f] + scene.frag[4 * f + 1] > v) fail('fragment ' + f + ' out of range');
    }
    for (let k = 0; k < m; ++k) {
      const front = scene.bsp_nodes[4 * k], back = scene.bsp_nodes[4 * k + 1];
      if ((front >= 0 && (front <= k || front >= m)) || (back >= 0 && (back <= k || back >= m)) ||
          scene.bsp_nodes[4 * k + 2] + scene.bsp_nodes[4 * k + 3] > n)
        fail('BSP node ' + k + ' out of range');
    }
    scene.walk = parseWalk(f64(find('WALK')[0]), fail);
    for (const l of meta.levels) scene.levels.push({ floor_y: l.floor_y, height: l.height, cells: [] });
    if (!Array.isArray(meta.cells)) fail('META lists no view cells');
    meta.cells.forEach((c, k) => {
      const box = c.box;
      if (!(Number.isInteger(c.level) && c.level >= 0 && c.level < scene.levels.length) ||
          !/^[0-9a-f]{16}$/.test(c.checksum) ||
          !(box === null || (Array.isArray(box) && box.length === 4 && box.every(Number.isFinite))))
        fail('view cell ' + k + ' in META is malformed');
      const cell = { index: k, level: c.level, box, file: 'cells/' + k + '.bin', checksum: c.checksum, tree: null };
      scene.cells.push(cell);
      scene.levels[c.level].cells.push(cell);
    });
    return scene;
  }

  // Hands view cell k's file (cells/k.bin: one CELL section) to the scene: checked as a container,
  // then as this export's cell k (the checksum of its table is the one META gives) and as a tree.
  // Resolves to the cell; rejects with an ExportError naming the file.
  async function attachCell(scene, k, buffer) {
    const cell = scene.cells[k];
    const fail = (what) => { throw new ExportError(cell.file + ': ' + what); };
    const { sections, checksum } = await readContainer(buffer, cell.file);
    if (sections.length !== 1 || sections[0].tag !== 'CELL') fail('not a view cell (one CELL section expected)');
    if (checksum !== cell.checksum) fail("not this export's view cell " + k + ' (walkvis.bin names another file)');
    const tree = parseCell(sections[0].buffer, sections[0], scene.meta.fragments, fail);
    if (tree.level !== cell.level) fail('a view cell of level ' + tree.level + ', META says ' + cell.level);
    if (String(tree.box) !== String(cell.box)) fail("its box is not the one META gives");
    cell.tree = tree;
    return cell;
  }

  // WALK: doubles; levels (floor_y, pieces of rings), then connections (patches: plane, ring).
  function parseWalk(w, fail) {
    let at = 0;
    const next = () => { if (at >= w.length) fail('WALK section truncated'); return w[at++]; };
    const count = () => {
      const c = next();
      if (!(c >= 0 && c === Math.floor(c) && c <= w.length)) fail('WALK section: bad count');
      return c;
    };
    const ring = () => {
      const k = count();
      const r = [];
      for (let i = 0; i < k; ++i) r.push([next(), next()]);
      return r;
    };
    const levels = [], connections = [];
    for (let l = count(); l > 0; --l) {
      const floor_y = next();
      const pieces = [];
      for (let p = count(); p > 0; --p) pieces.push(ring());
      levels.push({ floor_y, walkable: pieces });
    }
    for (let c = count(); c > 0; --c) {
      const patches = [];
      for (let p = count(); p > 0; --p) {
        const plane = [next(), next(), next(), next()];
        patches.push({ plane, piece: ring() });
      }
      connections.push({ patches });
    }
    return { levels, connections };
  }

  // CELL: u32 header[16], f64 box[4], f64 planes[4 P], then the u32 arrays (pfd_hfd/pfd.h PfdTree).
  function parseCell(buffer, s, fragments, fail) {
    if (s.length < 96) fail('CELL section truncated');
    const head = new Uint32Array(buffer, s.offset, 16);
    const [level, hasBox, P, nodes, refs, runs, seqs, items, ids, objects, onodes] = head;
    const box = new Float64Array(buffer, s.offset + 64, 4);
    const words = 5 * nodes + refs + 2 * runs + 3 * seqs + items + ids + 3 * objects + 6 * onodes;
    if (96 + 32 * P + 4 * words !== s.length) fail('CELL section of level ' + level + ': sizes disagree');
    const planes = new Float64Array(buffer, s.offset + 96, 4 * P);
    let at = s.offset + 96 + 32 * P;
    const take = (k) => { const a = new Uint32Array(buffer, at, k); at += 4 * k; return a; };
    const cell = {
      level, box: hasBox ? [box[0], box[1], box[2], box[3]] : null, planes,
      nodes: take(5 * nodes), run_refs: take(refs), runs: take(2 * runs), seqs: take(3 * seqs),
      seq_items: take(items), fragment_ids: take(ids), objects: take(3 * objects), object_nodes: take(6 * onodes),
    };
    // What a walk relies on: children after their parents (so it ends), indices in range.
    const bad = (what) => fail('CELL of level ' + level + ': ' + what + ' out of range');
    const ref = (r) => (r & kSeqBit) ? (r & ~kSeqBit) < seqs : (r & kObjectBit) ? (r & ~kObjectBit) < objects : r < runs;
    for (let k = 0; k < nodes; ++k) {
      const c = cell.nodes.subarray(5 * k, 5 * k + 5);
      const front = c[1] | 0, back = c[2] | 0;
      if ((front >= 0) !== (back >= 0)) bad('node children');
      if (front >= 0 && (c[0] >= P || front <= k || back <= k || front >= nodes || back >= nodes)) bad('node');
      if (c[3] + c[4] > refs) bad('node list');
    }
    for (const r of cell.run_refs) if (!ref(r)) bad('list entry');
    for (let k = 0; k < runs; ++k) if (cell.runs[2 * k] + cell.runs[2 * k + 1] > ids) bad('run');
    for (let k = 0; k < seqs; ++k) {
      const first = cell.seqs[3 * k], count = cell.seqs[3 * k + 1];
      if (first + count > items) bad('sequence');
      for (let i = first; i < first + count; ++i) {
        const it = cell.seq_items[i];
        if (!ref(it) || ((it & kSeqBit) && (it & ~kSeqBit) >= k)) bad('sequence item');
      }
    }
    for (const f of cell.fragment_ids) if (f >= fragments) bad('fragment id');
    for (let k = 0; k < objects; ++k)
      if (cell.objects[3 * k] + cell.objects[3 * k + 1] > onodes) bad('object');
    for (let k = 0; k < onodes; ++k) {
      const o = cell.object_nodes.subarray(6 * k, 6 * k + 6);
      if (o[0] >= P || ((o[1] | 0) >= 0 && (o[1] <= k || o[1] >= onodes)) || ((o[2] | 0) >= 0 && (o[2] <= k || o[2] >= onodes)) ||
          ((o[3] | 0) >= k) || (o[4] !== kNoRun && o[4] >= runs) || (o[5] !== kNoRun && o[5] >= runs))
        bad('object node');
    }
    return cell;
  }

  // ---- exact sign (bsp/exact_sign.h) --------------------------------------------------------
  // Veltkamp's split and Dekker's product: JavaScript has no fma, and a·b = p + e exactly when no
  // operand is near overflow (|a|, |b| < 2^996, guarded below like the C++ code's kHuge).
  const kSplitter = 134217729;  // 2^27 + 1
  function twoProductErr(a, b, p) {
    let c = kSplitter * a;
    const ah = c - (c - a), al = a - ah;
    c = kSplitter * b;
    const bh = c - (c - b), bl = b - bh;
    return al * bl - (((p - ah * bh) - al * bh) - ah * bl);
  }
  const expansion = new Float64Array(8), terms = new Float64Array(7);
  function planeSignExact(a, b, c, d, x, y, z) {
    if (!(isFinite(a) && isFinite(b) && isFinite(c) && isFinite(d) && isFinite(x) && isFinite(y) && isFinite(z))) return 0;
    const kTiny = Math.pow(2, -960), kHuge = Math.pow(2, 990);
    const f = [a, b, c], g = [x, y, z];
    for (let i = 0; i < 3; ++i) {
      const p = f[i] * g[i];
      if ((p === 0 && f[i] !== 0 && g[i] !== 0) || (p !== 0 && Math.abs(p) < kTiny) || Math.abs(p) > kHuge ||
          Math.abs(f[i]) > kHuge || Math.abs(g[i]) > kHuge) {
        // Outside any scene's range (the C++ code goes to rationals here): the rounded sign.
        const v = a * x + b * y + c * z - d;
        return v > 0 ? 1 : v < 0 ? -1 : 0;
      }
      terms[2 * i] = p;
      terms[2 * i + 1] = twoProductErr(f[i], g[i], p);
    }
    terms[6] = -d;
    let n = 0;
    for (let t = 0; t < 7; ++t) {
      let q = terms[t];
      let m = 0;
      for (let i = 0; i < n; ++i) {
        const s = q + expansion[i];
        const bv = s - q, av = s - bv;
        const err = (q - av) + (expansion[i] - bv);
        if (err !== 0) expansion[m++] = err;
        q = s;
      }
      expansion[m++] = q;
      n = m;
    }
    for (let i = n - 1; i >= 0; --i) if (expansion[i] !== 0) return expansion[i] > 0 ? 1 : -1;
    return 0;
  }
  const kEpsilon = Math.pow(2, -52);
  function planeSign(a, b, c, d, x, y, z) {
    const v = a * x + b * y + c * z - d;
    const mag = Math.abs(a * x) + Math.abs(b * y) + Math.abs(c * z) + Math.abs(d);
    const bound = 16 * kEpsilon * mag + 1e-300;
    if (v > bound) return 1;
    if (v < -bound) return -1;
    return planeSignExact(a, b, c, d, x, y, z);
  }
  // Side of eye against plane k of a packed array of (nx, ny, nz, d).
  function sideOf(planes, k, eye) {
    return planeSign(planes[4 * k], planes[4 * k + 1], planes[4 * k + 2], planes[4 * k + 3], eye[0], eye[1], eye[2]);
  }

  // ---- the order of a frame (walkthrough/frame.cpp, pfd_hfd/pfd.cpp) ------------------------
  const kSeqBit = 0x80000000, kObjectBit = 0x40000000, kNoRun = 0xffffffff, kMaxSeqDepth = 16;

  // The level whose height plane holds the eye (World::levelAt), or -1.
  function levelAt(scene, eye) {
    for (let i = 0; i < scene.levels.length; ++i) {
      const h = scene.levels[i].height;
      if (Math.abs(eye[1] - h) <= 1e-9 * Math.max(1, Math.abs(h))) return i;
    }
    return -1;
  }

  function findCell(level, eye) {
    for (const t of level.cells) {
      if (!t.box) return t;
      if (eye[0] >= t.box[0] && eye[0] < t.box[2] && eye[2] >= t.box[1] && eye[2] < t.box[3]) return t;
    }
    return null;
  }

  function grow(out, need) {
    const ids = new Uint32Array(Math.max(need, 2 * out.ids.length));
    ids.set(out.ids.subarray(0, out.n));
    out.ids = ids;
  }

  // Appends the fragment ids of run r to out (an Int32Array-backed list: {ids, n}).
  function emitRun(t, r, out) {
    const first = t.runs[2 * r], count = t.runs[2 * r + 1];
    if (out.n + count > out.ids.length) grow(out, out.n + count);
    const ids = t.fragment_ids;
    for (let k = first; k < first + count; ++k) out.ids[out.n++] = ids[k];
  }

  // A detail object's runs in back-to-front order for the eye, by parent links (forEachObjectRun).
  function emitObject(t, object, eye, out) {
    const root = t.objects[3 * object], nodes = t.objects[3 * object + 1];
    const on = t.object_nodes;
    let cur = root, prev = -1;
    while (cur >= 0) {
      const b = 6 * cur;
      const s = sideOf(t.planes, on[b], eye);
      const front = on[b + 1] | 0, back = on[b + 2] | 0, parent = on[b + 3] | 0;
      const far = s >= 0 ? back : front, near = s >= 0 ? front : back;
      const from = prev;
      prev = cur;
      if (from === parent && far >= 0) { cur = far; continue; }
      if (from === parent || from === far) {
        const run = s > 0 ? on[b + 4] : s < 0 ? on[b + 5] : kNoRun;
        if (run !== kNoRun) emitRun(t, run, out);
        if (near >= 0) { cur = near; continue; }
      }
      cur = parent;
    }
    return nodes;
  }

  const seqStack = new Uint32Array(2 * kMaxSeqDepth);
  function emitRef(t, ref, eye, out) {
    if (!(ref & kSeqBit)) {
      if (ref & kObjectBit) out.object_tests += emitObject(t, ref & ~kObjectBit, eye, out);
      else emitRun(t, ref, out);
      return;
    }
    let top = 0;
    const root = (ref & ~kSeqBit) >>> 0;
    seqStack[0] = t.seqs[3 * root];
    seqStack[1] = t.seqs[3 * root] + t.seqs[3 * root + 1];
    while (top >= 0) {
      if (seqStack[2 * top] === seqStack[2 * top + 1]) { --top; continue; }
      const item = t.seq_items[seqStack[2 * top]++];
      if (!(item & kSeqBit)) {
        if (item & kObjectBit) out.object_tests += emitObject(t, item & ~kObjectBit, eye, out);
        else emitRun(t, item, out);
        continue;
      }
      const c = (item & ~kSeqBit) >>> 0;
      if (top + 1 >= kMaxSeqDepth) throw new ExportError('sequences nest deeper than ' + kMaxSeqDepth);
      ++top;
      seqStack[2 * top] = t.seqs[3 * c];
      seqStack[2 * top + 1] = t.seqs[3 * c] + t.seqs[3 * c + 1];
    }
  }

  // The tree's walk from the root, appending every list on the path (pfdQueryRunIds).
  function hfdQuery(t, eye, out) {
    const nodes = t.nodes;
    if (nodes.length === 0) return;
    let i = 0;
    for (;;) {
      const b = 5 * i;
      for (let r = nodes[b + 3]; r < nodes[b + 3] + nodes[b + 4]; ++r) emitRef(t, t.run_refs[r], eye, out);
      const front = nodes[b + 1] | 0;
      if (front < 0) break;
      const s = sideOf(t.planes, nodes[b], eye);
      ++out.tests;
      i = s > 0 ? front : nodes[b + 2] | 0;
    }
  }

  // backToFront(bsp, eye, order, false): far side, the node's fragments, near side.
  function bspOrder(scene, eye, out) {
    const nodes = scene.bsp_nodes, root = scene.meta.bsp_root;
    if (root < 0) return;
    const stack = out.stack;
    let top = 0;
    stack[top++] = root;  // a node index, or ~index for "emit this node, then push its near child"
    while (top > 0) {
      const e = stack[--top];
      if (e >= 0) {
        const s = sideOf(scene.bsp_planes, e, eye);
        const front = nodes[4 * e], back = nodes[4 * e + 1];
        const far = s >= 0 ? back : front;
        stack[top++] = ~e;
        if (far >= 0) stack[top++] = far;
      } else {
        const k = ~e;
        const first = nodes[4 * k + 2], count = nodes[4 * k + 3];
        if (out.n + count > out.ids.length) grow(out, out.n + count);
        for (let f = first; f < first + count; ++f) out.ids[out.n++] = f;
        const s = sideOf(scene.bsp_planes, k, eye);
        const near = s >= 0 ? nodes[4 * k] : nodes[4 * k + 1];
        if (near >= 0) stack[top++] = near;
      }
    }
    out.tests = scene.meta.bsp_nodes;
  }

  // A reusable frame list: no allocation per frame.
  function makeOrder(scene) {
    return { ids: new Uint32Array(Math.max(scene.meta.fragments, 1) * 2), n: 0, tests: 0, object_tests: 0,
             stack: new Int32Array(2 * Math.max(scene.meta.bsp_nodes, 1) + 2), on: [0, 0, 0], level: -1, used: 'bsp',
             waiting: null };
  }

  // The view cell whose box holds the eye on its level's height plane (as FrameBuilder finds it),
  // or null: off every height plane (stairs) or outside every box.
  function cellAt(scene, eye) {
    const l = levelAt(scene, eye);
    return l >= 0 ? findCell(scene.levels[l], eye) : null;
  }

  // FrameBuilder::build for mode hfd, culling none: the fragments of the frame, first drawn first.
  // Where the eye's view cell has no tree yet (its file not yet in: attachCell), the BSP order,
  // which draws the same image with every hidden fragment too; out.waiting is then that cell.
  function frameOrder(scene, eye, out) {
    out.n = 0;
    out.tests = 0;
    out.object_tests = 0;
    out.level = -1;
    out.used = 'bsp';
    out.waiting = null;
    const l = levelAt(scene, eye);
    if (l >= 0) {
      const level = scene.levels[l];
      const on = out.on;  // the eye snapped onto the height plane: the few ulps a decimal path adds
      on[0] = eye[0], on[1] = level.height, on[2] = eye[2];
      const c = findCell(level, on);
      const t = c && c.tree;
      if (t && t.nodes.length > 0) {
        hfdQuery(t, on, out);
        out.tests += out.object_tests;
        out.level = l;
        out.used = 'hfd';
        return out;
      }
      if (c && !t) out.waiting = c;
    }
    bspOrder(scene, eye, out);
    return out;
  }

  // ---- walking (walkthrough/movement.cpp) ---------------------------------------------------
  const kWallMaxNormalY = 0.9;

  // The walker's arithmetic reads vertices in place (sc.vertices, a fragment's run of x, y, z) and
  // writes into the walker's own scratch: a frame's moves allocate nothing. Each expression keeps
  // the C++ operation order (glm's dot, cross and length), so results agree to the last bit where
  // Math.hypot is not involved.

  // pointInPolygon (movement.cpp): q within tol of the inside of every edge of the fragment's ring.
  function pointInPolygon(vs, first, count, pl, f, q, tol) {
    const nx = pl[4 * f], ny = pl[4 * f + 1], nz = pl[4 * f + 2], qx = q[0], qy = q[1], qz = q[2];
    for (let i = 0; i < count; ++i) {
      const a = 3 * (first + i), b = 3 * (first + (i + 1) % count);
      const ex = vs[b] - vs[a], ey = vs[b + 1] - vs[a + 1], ez = vs[b + 2] - vs[a + 2];
      const wx = qx - vs[a], wy = qy - vs[a + 1], wz = qz - vs[a + 2];
      const c = (ey * wz - ez * wy) * nx + (ez * wx - ex * wz) * ny + (ex * wy - ey * wx) * nz;
      if (c < -tol * Math.sqrt(ex * ex + ey * ey + ez * ez)) return false;
    }
    return true;
  }

  // pointPolygonDistance (movement.cpp): the distance from p to the fragment's polygon.
  // q is scratch for the foot of p on the plane.
  function pointPolygonDistance(vs, first, count, pl, f, p, q, tol) {
    const nx = pl[4 * f], ny = pl[4 * f + 1], nz = pl[4 * f + 2], d = pl[4 * f + 3], px = p[0], py = p[1], pz = p[2];
    const s = nx * px + ny * py + nz * pz - d;
    q[0] = px - s * nx, q[1] = py - s * ny, q[2] = pz - s * nz;
    if (pointInPolygon(vs, first, count, pl, f, q, tol)) return Math.abs(s);
    let best = Infinity;
    for (let i = 0; i < count; ++i) {
      const a = 3 * (first + i), b = 3 * (first + (i + 1) % count);
      const ax = vs[a], ay = vs[a + 1], az = vs[a + 2];
      const ex = vs[b] - ax, ey = vs[b + 1] - ay, ez = vs[b + 2] - az;
      const ee = ex * ex + ey * ey + ez * ez;
      const t = ee > 0 ? Math.min(Math.max(((px - ax) * ex + (py - ay) * ey + (pz - az) * ez) / ee, 0), 1) : 0;
      const rx = px - (ax + t * ex), ry = py - (ay + t * ey), rz = pz - (az + t * ez);
      best = Math.min(best, Math.sqrt(rx * rx + ry * ry + rz * rz));
    }
    return best;
  }

  function copyState(from, out) {
    out.eye[0] = from.eye[0], out.eye[1] = from.eye[1], out.eye[2] = from.eye[2];
    out.level = from.level;
    return out;
  }

  // A walk state, {eye: [x, y, z], level}; pass one to move and place to reuse it.
  function makeWalkState() { return { eye: [0, 0, 0], level: -1 }; }

  class Walker {
    constructor(scene) {
      const m = scene.meta;
      this.scene = scene;
      this.eye_height = m.eye_height;
      this.radius = m.walk.radius;
      this.step = m.walk.step;
      this.tol = m.walk.tol;
      this.pieces = [];
      // Scratch for one move: the stack of blocks (a BSP node is pushed at most once, and so is
      // each missing child), the floor found, the eyes tried, the blocker's normal.
      this.stack = new Int32Array(2 * Math.max(m.bsp_nodes, 1) + 2);
      this.floor = { y: 0, level: -1 };
      this.mid = [0, 0, 0];
      this.tried = makeWalkState();
      this.normal = [0, 0, 0];
      this.q = [0, 0, 0];
      const levels = scene.walk.levels, connections = scene.walk.connections;
      let lx = Infinity, lz = Infinity, hx = -Infinity, hz = -Infinity;
      const add = (ring, owner, index, patch) => {
        if (ring.length < 3) return;
        const p = { level: owner, index, lo_x: ring[0][0], lo_z: ring[0][1], hi_x: ring[0][0], hi_z: ring[0][1], patch, ring };
        for (const u of ring) {
          p.lo_x = Math.min(p.lo_x, u[0]); p.hi_x = Math.max(p.hi_x, u[0]);
          p.lo_z = Math.min(p.lo_z, u[1]); p.hi_z = Math.max(p.hi_z, u[1]);
        }
        lx = Math.min(lx, p.lo_x); hx = Math.max(hx, p.hi_x); lz = Math.min(lz, p.lo_z); hz = Math.max(hz, p.hi_z);
        this.pieces.push(p);
      };
      levels.forEach((l, li) => l.walkable.forEach((ring, i) => add(ring, li, i, false)));
      connections.forEach((c, ci) => c.patches.forEach((p, i) => { if (p.plane[1] > 0) add(p.piece, ci, i, true); }));
      this.cells = null;
      if (this.pieces.length === 0) return;
      const w = Math.max(hx - lx, this.tol), h = Math.max(hz - lz, this.tol);
      const cells = Math.min(2 * this.pieces.length, 512 * 512);
      let cell = Math.sqrt(w * h / cells);
      this.nx = Math.min(Math.max(Math.ceil(w / cell), 1), 512);
      this.nz = Math.min(Math.max(Math.ceil(h / cell), 1), 512);
      this.cell = Math.max(w / this.nx, h / this.nz) * (1 + 1e-12);
      this.x0 = lx; this.z0 = lz;
      this.cells = [];
      for (let i = 0; i < this.nx * this.nz; ++i) this.cells.push([]);
      const index = (v, v0, n) => Math.min(Math.max(Math.floor((v - v0) / this.cell), 0), n - 1);
      this.pieces.forEach((p, i) => {
        const x0 = index(p.lo_x - this.tol, this.x0, this.nx), x1 = index(p.hi_x + this.tol, this.x0, this.nx);
        const z0 = index(p.lo_z - this.tol, this.z0, this.nz), z1 = index(p.hi_z + this.tol, this.z0, this.nz);
        for (let z = z0; z <= z1; ++z) for (let x = x0; x <= x1; ++x) this.cells[z * this.nx + x].push(i);
      });
    }

    pieceFloor(p, x, z) {
      if (!p.patch) return this.scene.walk.levels[p.level].floor_y;
      const pl = this.scene.walk.connections[p.level].patches[p.index].plane;
      return (pl[3] - pl[0] * x - pl[2] * z) / pl[1];
    }

    insidePiece(p, x, z) {
      const tol = this.tol;
      if (x < p.lo_x - tol || x > p.hi_x + tol || z < p.lo_z - tol || z > p.hi_z + tol) return false;
      let neg = false, pos = false;
      const r = p.ring;
      for (let k = 0; k < r.length; ++k) {
        const u = r[k], w = r[(k + 1) % r.length];
        const ex = w[0] - u[0], ez = w[1] - u[1];
        const c = ex * (z - u[1]) - ez * (x - u[0]);
        const slack = tol * Math.sqrt(ex * ex + ez * ez);  // as movement.cpp: Math.hypot allocates
        if (c < -slack) neg = true;
        if (c > slack) pos = true;
      }
      return !(neg && pos);
    }

    gridCell(x, z) {
      if (!this.cells || !isFinite(x) || !isFinite(z)) return -1;
      const fx = (x - this.x0) / this.cell, fz = (z - this.z0) / this.cell;
      if (fx < -1 || fz < -1 || fx > this.nx + 1 || fz > this.nz + 1) return -1;
      const cx = Math.min(Math.max(Math.floor(fx), 0), this.nx - 1);
      const cz = Math.min(Math.max(Math.floor(fz), 0), this.nz - 1);
      return cz * this.nx + cx;
    }

    // The highest floor at (x, z) at most max_y, into this.floor ({y, level}, level -1 on a
    // connection patch); false when there is none.
    floorUnder(x, z, max_y) {
      const c = this.gridCell(x, z);
      if (c < 0) return false;
      let found = false;
      const best = this.floor, list = this.cells[c];
      for (let k = 0; k < list.length; ++k) {
        const p = this.pieces[list[k]];
        const fy = this.pieceFloor(p, x, z);
        if (fy > max_y) continue;
        const level = p.patch ? -1 : p.level;
        if (found && (best.y > fy || (best.y === fy && (best.level >= 0 || level < 0)))) continue;
        if (this.insidePiece(p, x, z)) found = true, best.y = fy, best.level = level;
      }
      return found;
    }

    wallBlocks(f, a, b, radius) {
      const sc = this.scene, tol = this.tol, pl = sc.frag_planes;
      const nx = pl[4 * f], ny = pl[4 * f + 1], nz = pl[4 * f + 2], d = pl[4 * f + 3];
      if (!(Math.abs(ny) < kWallMaxNormalY)) return false;
      const vs = sc.vertices, first = sc.frag[4 * f], count = sc.frag[4 * f + 1];
      const sa = nx * a[0] + ny * a[1] + nz * a[2] - d, sb = nx * b[0] + ny * b[1] + nz * b[2] - d;
      if ((sa > tol && sb < -tol) || (sa < -tol && sb > tol)) {
        const t = sa / (sa - sb), q = this.q;
        q[0] = a[0] + t * (b[0] - a[0]), q[1] = a[1] + t * (b[1] - a[1]), q[2] = a[2] + t * (b[2] - a[2]);
        if (pointInPolygon(vs, first, count, pl, f, q, tol)) return true;
      } else if (Math.abs(sb) <= tol && pointInPolygon(vs, first, count, pl, f, b, tol)) {
        return true;
      }
      if (radius > 0 && Math.abs(sb) < radius) {
        const db = pointPolygonDistance(vs, first, count, pl, f, b, this.q, tol);
        if (db < radius && db < pointPolygonDistance(vs, first, count, pl, f, a, this.q, tol) - tol) return true;
      }
      return false;
    }

    // Whether segment a→b (with a ball of `radius` at b) meets a wall; the wall's normal in blocker.
    blocks(a, b, radius, blocker) {
      const sc = this.scene, tol = this.tol;
      const root = sc.meta.bsp_root;
      if (root < 0) return false;
      const stack = this.stack, planes = sc.bsp_planes, nodes = sc.bsp_nodes;
      let top = 0;
      stack[top++] = root;
      while (top > 0) {
        const ni = stack[--top];
        if (ni < 0) continue;
        const q = 4 * ni;
        const sa = planes[q] * a[0] + planes[q + 1] * a[1] + planes[q + 2] * a[2] - planes[q + 3];
        const sb = planes[q] * b[0] + planes[q + 1] * b[1] + planes[q + 2] * b[2] - planes[q + 3];
        const lo = Math.min(sa, sb - radius) - tol, hi = Math.max(sa, sb + radius) + tol;
        if (lo <= 0 && hi >= 0) {
          const first = nodes[q + 2], count = nodes[q + 3];
          for (let f = first; f < first + count; ++f) {
            if (this.wallBlocks(f, a, b, radius)) {
              if (blocker) { blocker[0] = sc.frag_planes[4 * f]; blocker[1] = sc.frag_planes[4 * f + 1]; blocker[2] = sc.frag_planes[4 * f + 2]; }
              return true;
            }
          }
        }
        if (hi > 0) stack[top++] = nodes[q];
        if (lo < 0) stack[top++] = nodes[q + 1];
      }
      return false;
    }

    segmentClear(a, b, radius, blocker) { return !this.blocks(a, b, radius, blocker); }

    // The eye set on the floor under it, into `out` (a new state when none is given).
    place(eye, out = makeWalkState()) {
      const x = eye[0], y = eye[1], z = eye[2];
      if (!this.floorUnder(x, z, y - this.eye_height + this.step + this.tol)) {
        out.eye[0] = x, out.eye[1] = y, out.eye[2] = z, out.level = -1;
        return out;
      }
      out.eye[0] = x, out.eye[1] = this.floor.y + this.eye_height, out.eye[2] = z, out.level = this.floor.level;
      return out;
    }

    // Walker::tryMove into `to` (not `from`); false where the move is refused.
    tryMove(from, dx, dz, to) {
      if (!isFinite(dx) || !isFinite(dz)) return false;
      const mid = this.mid;
      mid[0] = from.eye[0] + dx, mid[1] = from.eye[1], mid[2] = from.eye[2] + dz;
      if (!this.segmentClear(from.eye, mid, this.radius)) return false;
      const floor_now = from.level >= 0 ? this.scene.walk.levels[from.level].floor_y : from.eye[1] - this.eye_height;
      if (!this.floorUnder(mid[0], mid[2], floor_now + this.step + this.tol)) {
        if (from.level >= 0) return false;
        if (this.floorUnder(from.eye[0], from.eye[2], floor_now + this.tol) && this.floor.y >= floor_now - this.tol) return false;
        to.eye[0] = mid[0], to.eye[1] = mid[1], to.eye[2] = mid[2], to.level = -1;
        return true;
      }
      to.eye[0] = mid[0], to.eye[1] = this.floor.y + this.eye_height, to.eye[2] = mid[2], to.level = this.floor.level;
      if (to.eye[1] !== mid[1] && !this.segmentClear(mid, to.eye, 0)) return false;
      return true;
    }

    // Walker::move: the state after walking (dx, dz) from `from`, into `out` (which may be `from`;
    // a new state when none is given).
    move(from, dx, dz, out = makeWalkState()) {
      const tried = this.tried;
      if (dx === 0 && dz === 0) return copyState(from, out);
      if (this.tryMove(from, dx, dz, tried)) return copyState(tried, out);
      const n = this.normal, mid = this.mid;
      n[0] = 0, n[1] = 0, n[2] = 0;
      mid[0] = from.eye[0] + dx, mid[1] = from.eye[1], mid[2] = from.eye[2] + dz;
      if (!this.segmentClear(from.eye, mid, this.radius, n)) {
        const len = Math.hypot(n[0], n[2]);
        if (len > 0) {
          const ux = n[0] / len, uz = n[2] / len;
          const along = dx * ux + dz * uz;
          if (this.tryMove(from, dx - along * ux, dz - along * uz, tried)) return copyState(tried, out);
        }
      }
      if (this.tryMove(from, dx, 0, tried)) return copyState(tried, out);
      if (this.tryMove(from, 0, dz, tried)) return copyState(tried, out);
      return copyState(from, out);
    }
  }

  // ---- camera (walkthrough/camera.cpp, clipFromEyeRelative(FreeCamera)) ----------------------
  // Into `m` (a Float32Array(16)) when given: a frame allocates nothing.
  function clipMatrix(cam, m = new Float32Array(16)) {
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    const cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw);
    const f = 1 / Math.tan(0.5 * cam.fov_y);
    const aspect = cam.width / cam.height;
    const n = cam.near, fa = cam.far;
    const A = (fa + n) / (n - fa), B = 2 * fa * n / (n - fa);
    // Rows: right (x) and up (y) scaled by the focal lengths, forward twice (depth and w).
    const sx = f / aspect, fx = -sy * cp, fy = sp, fz = -cy * cp;
    m[0] = cy * sx, m[4] = 0 * sx, m[8] = -sy * sx, m[12] = 0;
    m[1] = sy * sp * f, m[5] = cp * f, m[9] = cy * sp * f, m[13] = 0;
    m[2] = fx * -A, m[6] = fy * -A, m[10] = fz * -A, m[14] = B;
    m[3] = fx, m[7] = fy, m[11] = fz, m[15] = 0;
    return m;
  }

  const api = { parseExport, attachCell, cellAt, ExportError, fnv1a64, planeSign, planeSignExact, frameOrder, makeOrder, levelAt,
                bspOrder, Walker, makeWalkState, clipMatrix };
  if (typeof module === 'object' && module.exports) module.exports = api;
  else global.walkvis = api;
})(typeof window !== 'undefined' ? window : globalThis);
