// node tests/web/parity.js EXPORT_DIR EXPECTED_JSON: the viewer's ported rules against the C++
// library's answers, written by tests/test_web_export.cpp for the same export:
//   orders  frame orders (FrameBuilder::build, mode hfd, no culling) at eyes on and off the levels'
//           height planes: the same fragment ids in the same order, and the same source (hfd/bsp)
//   moves   Walker::move from recorded states: the same level, the eye within 1e-9 of the scene's
//           scale (std::hypot and Math.hypot may round differently in the last bit)
//   places  Walker::place: the same
//   alloc   200,000 moves and frame orders into one state and list: at most one young-generation
//           collection per 5,000 (the page's frame loop allocates nothing)
// Prints one summary line per part; exit status 0 when everything agrees, 1 otherwise.
'use strict';
const fs = require('fs');
const { W, readExport } = require('./read_export.js');

async function main() {
  const [dir, expectedFile] = process.argv.slice(2);
  const scene = await readExport(dir);
  const expected = JSON.parse(fs.readFileSync(expectedFile, 'utf8'));
  const walker = new W.Walker(scene);
  const order = W.makeOrder(scene);
  const tol = Math.max(expected.scale, 1) * 1e-9;
  let failures = 0;
  const fail = (what) => {
    if (failures++ < 10) console.log('MISMATCH ' + what);
  };

  let hfd = 0, ids = 0;
  expected.orders.forEach((o, i) => {
    W.frameOrder(scene, o.eye, order);
    const got = Array.from(order.ids.subarray(0, order.n));
    if (order.used !== o.used) fail('order ' + i + ': used ' + order.used + ', C++ ' + o.used);
    if (got.length !== o.ids.length || got.some((v, k) => v !== o.ids[k]))
      fail('order ' + i + ' at ' + o.eye + ': ' + got.length + ' ids, C++ ' + o.ids.length);
    hfd += o.used === 'hfd';
    ids += o.ids.length;
  });

  const near = (a, b) => a.every((v, k) => Math.abs(v - b[k]) <= tol);
  let blocked = 0, level_changes = 0;
  expected.moves.forEach((m, i) => {
    const to = walker.move({ eye: m.from.eye.slice(), level: m.from.level }, m.d[0], m.d[1]);
    if (to.level !== m.to.level || !near(to.eye, m.to.eye))
      fail('move ' + i + ': (' + to.eye + ') level ' + to.level + ', C++ (' + m.to.eye + ') level ' + m.to.level);
    blocked += m.to.eye[0] === m.from.eye[0] && m.to.eye[2] === m.from.eye[2];
    level_changes += m.to.level !== m.from.level;
  });
  expected.places.forEach((p, i) => {
    const got = walker.place(p.eye);
    if (got.level !== p.to.level || !near(got.eye, p.to.eye)) fail('place ' + i + ': level ' + got.level + ', C++ ' + p.to.level);
  });

  // A frame allocates nothing: the page walks and orders into states and lists it keeps. V8 still
  // boxes a few doubles that cross calls, so the check counts young-generation collections, which
  // garbage brings: the walker before it reused its scratch had 1 per 100 to 300 moves of this loop.
  const kGcMoves = 200000;
  const { PerformanceObserver, constants } = require('perf_hooks');
  let minor_gcs = 0;
  const gcObserver = new PerformanceObserver((list) => {
    for (const e of list.getEntries()) if (e.detail && e.detail.kind === constants.NODE_PERFORMANCE_GC_MINOR) ++minor_gcs;
  });
  const walkLoop = (n) => {
    const state = walker.place(expected.places.length ? expected.places[0].eye : scene.meta.start.eye);
    for (let i = 0; i < n; ++i) {
      const m = expected.moves[i % expected.moves.length];
      walker.move(state, m.d[0], m.d[1], state);
      W.frameOrder(scene, state.eye, order);
    }
  };

  function finish() {
    console.log('parity: ' + expected.orders.length + ' orders (' + hfd + ' from HFD trees, ' + ids + ' ids), ' +
                expected.moves.length + ' moves (' + blocked + ' blocked, ' + level_changes + ' level changes), ' +
                expected.places.length + ' places: ' + failures + ' mismatches');
    console.log('allocation: ' + kGcMoves + ' moves and frame orders into one state and list: ' + minor_gcs +
                ' young-generation collections');
    if (minor_gcs > kGcMoves / 5000) fail('the walk allocates: ' + minor_gcs + ' collections (at most ' + kGcMoves / 5000 + ')');
    process.exit(failures === 0 ? 0 : 1);
  }

  walkLoop(kGcMoves / 10);  // compiled before counting
  gcObserver.observe({ entryTypes: ['gc'] });
  walkLoop(kGcMoves);
  setTimeout(finish, 50);  // gc entries arrive asynchronously
}

main().catch((e) => {
  console.log('parity: ' + e.message);
  process.exit(1);
});
