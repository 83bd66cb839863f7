// Tree files: the BSP and every PFD tree of every level in one versioned, checksummed file,
// written atomically (temporary file next to the target, then rename).
//
// Layout (little-endian, fields one by one, no padding):
//   header  : magic "WVPFD\r\n\x1a" (8), u32 version, u32 0, u64 payload bytes, u64 FNV-1a 64 of the payload
//   payload : f64 eye_height, u8 kind (0 pfd, 1 hfd), u32 region_samples, u32 polygon_samples,
//             u32 refine_rays, u64 seed, u64 BSP bytes + the BSP file (saveBsp's format, checked by loadBspFromMemory),
//             u32 levels; per level: u32 level, f64 floor_y, f64 height, u32 cells; per cell (tree):
//             f64 height, u8 has_cell, 4 f64 cell box, u32 pieces (u32 corners, 2 f64 each),
//             u32 planes (4 f64), u32 nodes (u32 plane, i32 front, i32 back, u32 first_ref, u32 ref_count),
//             u32 run_refs (u32), u32 runs (2 u32), u32 fragment_ids (u32), u32 seqs (3 u32),
//             u32 seq_items (u32), u32 objects (3 u32), u32 object_nodes (u32 plane, i32 front,
//             i32 back, i32 parent, u32 front_run, u32 back_run), stats (21 u64, 5 f64). A run
//             reference with the top bit set (kPfdSeqBit) names a sequence, with the next
//             (kPfdObjectBit) a detail object.
// Build times (the BSP's and each tree's build_seconds) are written as 0: a file's bytes depend
// only on the scene and the options, so that builds on any number of processes, resumed or not,
// write the same file (tools/walkvis/build_runner.cpp). The build's JSON keeps the times.
// Loading checks everything a query relies on: children after their parent, plane, run and
// fragment indices in range, so that a loaded tree is queried without further checks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/byte_io.h"
#include "core/hash.h"
#include "pfd_hfd/pfd.h"

namespace walkvis {
namespace {

constexpr char kMagic[8] = {'W', 'V', 'P', 'F', 'D', '\r', '\n', '\x1a'};
// 2: tree kind and visibility sampling after eye_height; HFD counters in the stats.
// 3: sequences (orders stored as references to sub-orders) after the fragment ids.
// 4: detail objects after the sequences; their counts in the stats.
constexpr uint32_t kVersion = 4;
constexpr size_t kHeaderBytes = 32;

using Writer = ByteWriter;
using Reader = ByteReader;

void writeTree(Writer& w, const PfdTree& t) {
  w.put(t.height);
  w.put<uint8_t>(t.cell ? 1 : 0);
  const PfdBox box = t.cell.value_or(PfdBox{});
  w.put(box.lo.x);
  w.put(box.lo.y);
  w.put(box.hi.x);
  w.put(box.hi.y);
  w.put(static_cast<uint32_t>(t.region.size()));
  for (const auto& ring : t.region) {
    w.put(static_cast<uint32_t>(ring.size()));
    for (const glm::dvec2& p : ring) {
      w.put(p.x);
      w.put(p.y);
    }
  }
  w.put(static_cast<uint32_t>(t.planes.size()));
  for (const Plane& p : t.planes) w.putPlane(p);
  w.put(static_cast<uint32_t>(t.nodes.size()));
  for (const PfdNode& n : t.nodes) {
    w.put(n.plane);
    w.put(n.front);
    w.put(n.back);
    w.put(n.first_ref);
    w.put(n.ref_count);
  }
  w.put(static_cast<uint32_t>(t.run_refs.size()));
  for (uint32_t r : t.run_refs) w.put(r);
  w.put(static_cast<uint32_t>(t.runs.size()));
  for (const PfdRun& r : t.runs) {
    w.put(r.first);
    w.put(r.count);
  }
  w.put(static_cast<uint32_t>(t.fragment_ids.size()));
  for (uint32_t f : t.fragment_ids) w.put(f);
  w.put(static_cast<uint32_t>(t.seqs.size()));
  for (const PfdSeq& q : t.seqs) {
    w.put(q.first);
    w.put(q.count);
    w.put(q.length);
  }
  w.put(static_cast<uint32_t>(t.seq_items.size()));
  for (uint32_t x : t.seq_items) w.put(x);
  w.put(static_cast<uint32_t>(t.objects.size()));
  for (const PfdObject& o : t.objects) {
    w.put(o.root);
    w.put(o.nodes);
    w.put(o.fragments);
  }
  w.put(static_cast<uint32_t>(t.object_nodes.size()));
  for (const PfdObjectNode& n : t.object_nodes) {
    w.put(n.plane);
    w.put(n.front);
    w.put(n.back);
    w.put(n.parent);
    w.put(n.front_run);
    w.put(n.back_run);
  }
  const PfdStats& s = t.stats;
  for (uint64_t v : {s.fragments, s.nodes, s.leaves, s.depth_max, s.list_entries, s.list_fragments, s.pool_entries,
                     s.runs, s.seqs, s.seq_items, s.test_planes, s.exact_fallbacks, s.touching, s.decisions, s.tests_max, s.visibility_tests,
                     s.visibility_rays, s.hidden_rejected, s.objects, s.object_nodes, s.object_fragments})
    w.put(v);
  for (double v : {s.tests_mean, s.tests_entropy_bound, s.region_area, 0.0, s.tests_huffman_bound}) w.put(v);
}

PfdTree readTree(Reader& r, size_t fragments) {
  PfdTree t;
  t.height = r.getFinite();
  const uint8_t has_cell = r.get<uint8_t>();
  if (has_cell > 1) r.fail("bad view cell flag");
  PfdBox box;
  box.lo.x = r.getFinite();
  box.lo.y = r.getFinite();
  box.hi.x = r.getFinite();
  box.hi.y = r.getFinite();
  if (has_cell) t.cell = box;
  const uint32_t pieces = r.count(4);
  t.region.resize(pieces);
  for (auto& ring : t.region) {
    const uint32_t n = r.count(16);
    ring.resize(n);
    for (glm::dvec2& p : ring) {
      p.x = r.getFinite();
      p.y = r.getFinite();
    }
  }
  const uint32_t planes = r.count(32);
  t.planes.resize(planes);
  for (Plane& p : t.planes) {
    p.n.x = r.getFinite();
    p.n.y = r.getFinite();
    p.n.z = r.getFinite();
    p.d = r.getFinite();
  }
  const uint32_t nodes = r.count(20);
  if (nodes == 0) r.fail("PFD tree without nodes");
  t.nodes.resize(nodes);
  for (PfdNode& n : t.nodes) {
    n.plane = r.get<uint32_t>();
    n.front = r.get<int32_t>();
    n.back = r.get<int32_t>();
    n.first_ref = r.get<uint32_t>();
    n.ref_count = r.get<uint32_t>();
  }
  const uint32_t refs = r.count(4);
  t.run_refs.resize(refs);
  for (uint32_t& x : t.run_refs) x = r.get<uint32_t>();
  const uint32_t runs = r.count(8);
  t.runs.resize(runs);
  for (PfdRun& x : t.runs) {
    x.first = r.get<uint32_t>();
    x.count = r.get<uint32_t>();
  }
  const uint32_t ids = r.count(4);
  t.fragment_ids.resize(ids);
  for (uint32_t& x : t.fragment_ids) x = r.get<uint32_t>();
  const uint32_t seqs = r.count(12);
  t.seqs.resize(seqs);
  for (PfdSeq& q : t.seqs) {
    q.first = r.get<uint32_t>();
    q.count = r.get<uint32_t>();
    q.length = r.get<uint32_t>();
  }
  const uint32_t items = r.count(4);
  t.seq_items.resize(items);
  for (uint32_t& x : t.seq_items) x = r.get<uint32_t>();
  const uint32_t objects = r.count(12);
  t.objects.resize(objects);
  for (PfdObject& o : t.objects) {
    o.root = r.get<uint32_t>();
    o.nodes = r.get<uint32_t>();
    o.fragments = r.get<uint32_t>();
  }
  const uint32_t object_nodes = r.count(24);
  t.object_nodes.resize(object_nodes);
  for (PfdObjectNode& n : t.object_nodes) {
    n.plane = r.get<uint32_t>();
    n.front = r.get<int32_t>();
    n.back = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.front_run = r.get<uint32_t>();
    n.back_run = r.get<uint32_t>();
  }
  PfdStats& s = t.stats;
  for (uint64_t* v : {&s.fragments, &s.nodes, &s.leaves, &s.depth_max, &s.list_entries, &s.list_fragments,
                      &s.pool_entries, &s.runs, &s.seqs, &s.seq_items, &s.test_planes, &s.exact_fallbacks, &s.touching, &s.decisions,
                      &s.tests_max, &s.visibility_tests, &s.visibility_rays, &s.hidden_rejected, &s.objects,
                      &s.object_nodes, &s.object_fragments})
    *v = r.get<uint64_t>();
  // The last slot was written as 0 before tests_huffman_bound had it (same format version): 0 then
  // reads as "not computed".
  for (double* v : {&s.tests_mean, &s.tests_entropy_bound, &s.region_area, &s.build_seconds, &s.tests_huffman_bound})
    *v = r.getFinite();

  // What a query relies on.
  for (uint32_t i = 0; i < nodes; ++i) {
    const PfdNode& n = t.nodes[i];
    const bool leaf = n.front < 0;
    if (leaf != (n.back < 0) || (leaf && (n.front != -1 || n.back != -1)))
      r.fail("PFD node " + std::to_string(i) + " has one child");
    if (!leaf) {
      if (static_cast<uint32_t>(n.front) <= i || static_cast<uint32_t>(n.front) >= nodes ||
          static_cast<uint32_t>(n.back) <= i || static_cast<uint32_t>(n.back) >= nodes)
        r.fail("PFD node " + std::to_string(i) + " has a child out of range");
      if (n.plane >= planes) r.fail("PFD node " + std::to_string(i) + " has a plane out of range");
    }
    if (static_cast<uint64_t>(n.first_ref) + n.ref_count > refs)
      r.fail("PFD node " + std::to_string(i) + " has a list out of range");
  }
  // An object is a tree of its own nodes: children after their parent and linked back to it, so
  // that the query's walk by parent links ends; its runs exist and hold its stated fragments.
  auto runCount = [&](uint32_t run) -> uint64_t { return run == kPfdNoRun ? 0 : t.runs[run].count; };
  for (uint32_t i = 0; i < objects; ++i) {
    const PfdObject& o = t.objects[i];
    const std::string what = "PFD object " + std::to_string(i);
    if (o.nodes == 0 || static_cast<uint64_t>(o.root) + o.nodes > object_nodes) r.fail(what + " out of range");
    uint64_t fragments_in = 0;
    for (uint32_t k = o.root; k < o.root + o.nodes; ++k) {
      const PfdObjectNode& n = t.object_nodes[k];
      if (n.plane >= planes) r.fail(what + " has a plane out of range");
      if ((n.front_run != kPfdNoRun && n.front_run >= runs) || (n.back_run != kPfdNoRun && n.back_run >= runs))
        r.fail(what + " has a run out of range");
      for (const int32_t c : {n.front, n.back}) {
        if (c == -1) continue;
        if (c < 0 || static_cast<uint32_t>(c) <= k || static_cast<uint32_t>(c) >= o.root + o.nodes ||
            t.object_nodes[c].parent != static_cast<int32_t>(k))
          r.fail(what + " has a child out of range");
      }
      if (n.front != -1 && n.front == n.back) r.fail(what + " has a child twice");
      if (k == o.root ? n.parent != -1
                      : (n.parent < static_cast<int32_t>(o.root) || static_cast<uint32_t>(n.parent) >= k ||
                         (t.object_nodes[n.parent].front != static_cast<int32_t>(k) &&
                          t.object_nodes[n.parent].back != static_cast<int32_t>(k))))
        r.fail(what + " has a parent out of range");
      fragments_in += runCount(n.front_run) + runCount(n.back_run);
    }
    if (fragments_in != o.fragments) r.fail(what + " has a wrong fragment count");
  }
  // A reference names a run, an object or a sequence; a sequence only refers to sequences before
  // it (so none contains itself), nests at most kPfdMaxSeqDepth deep and expands to its stated
  // length.
  auto refOk = [&](uint32_t x, uint32_t seq_limit) {
    if (x & kPfdSeqBit) return (x & ~kPfdSeqBit) < seq_limit;
    if (x & kPfdObjectBit) return (x & ~kPfdObjectBit) < objects;
    return x < runs;
  };
  for (uint32_t x : t.run_refs)
    if (!refOk(x, seqs)) r.fail("PFD run reference out of range");
  std::vector<uint8_t> depth(seqs, 0);
  for (uint32_t i = 0; i < seqs; ++i) {
    const PfdSeq& q = t.seqs[i];
    if (static_cast<uint64_t>(q.first) + q.count > items) r.fail("PFD sequence " + std::to_string(i) + " out of range");
    uint64_t length = 0;
    uint32_t d = 0;
    for (uint32_t k = q.first; k < q.first + q.count; ++k) {
      const uint32_t x = t.seq_items[k];
      if (!refOk(x, i)) r.fail("PFD sequence " + std::to_string(i) + " refers to an item out of range");
      if (x & kPfdSeqBit) {
        length += t.seqs[x & ~kPfdSeqBit].length;
        d = std::max<uint32_t>(d, depth[x & ~kPfdSeqBit]);
      } else if (x & kPfdObjectBit) {
        length += t.objects[x & ~kPfdObjectBit].fragments;
      } else {
        length += x < runs ? t.runs[x].count : 0;
      }
    }
    if (d + 1 > kPfdMaxSeqDepth) r.fail("PFD sequence " + std::to_string(i) + " nests too deep");
    if (length != q.length) r.fail("PFD sequence " + std::to_string(i) + " has a wrong length");
    depth[i] = static_cast<uint8_t>(d + 1);
  }
  for (const PfdRun& x : t.runs)
    if (static_cast<uint64_t>(x.first) + x.count > ids) r.fail("PFD run out of range");
  for (uint32_t x : t.fragment_ids)
    if (x >= fragments) r.fail("PFD fragment id out of range");
  // Bytes only: measurePfd with no eyes would also clear the tests_mean and tests_max just read.
  const double tests_mean = s.tests_mean;
  const uint64_t tests_max = s.tests_max;
  measurePfd(t, 0, 0);
  s.tests_mean = tests_mean;
  s.tests_max = tests_max;
  return t;
}

void writeJob(Writer& w, const PfdCellJob& job) {
  w.put(job.level);
  w.put(job.depth);
  w.put<uint8_t>(job.box ? 1 : 0);
  const PfdBox box = job.box.value_or(PfdBox{});
  for (double v : {box.lo.x, box.lo.y, box.hi.x, box.hi.y}) w.put(v);
  w.put(job.budget);
  w.put<uint8_t>(job.total_limited ? 1 : 0);
  w.put(job.cost);
}

}  // namespace

std::vector<uint8_t> pfdTreeBytes(const PfdTree& tree) {
  Writer w;
  writeTree(w, tree);
  return std::move(w.bytes);
}

PfdTree pfdTreeFromBytes(std::span<const uint8_t> bytes, size_t fragments, const std::string& context) {
  Reader r(bytes, context + ": ");
  PfdTree t = readTree(r, fragments);
  if (r.remaining() != 0) r.fail("trailing bytes");
  return t;
}

std::vector<uint8_t> pfdCellJobBytes(const PfdCellJob& job) {
  Writer w;
  writeJob(w, job);
  return std::move(w.bytes);
}

PfdCellJob pfdCellJobFromBytes(std::span<const uint8_t> bytes, const std::string& context) {
  Reader r(bytes, context + ": ");
  PfdCellJob job;
  job.level = r.get<uint32_t>();
  job.depth = r.get<uint32_t>();
  const uint8_t has_box = r.get<uint8_t>();
  PfdBox box;
  box.lo.x = r.getFinite();
  box.lo.y = r.getFinite();
  box.hi.x = r.getFinite();
  box.hi.y = r.getFinite();
  if (has_box > 1) r.fail("bad view cell flag");
  if (has_box) job.box = box;
  job.budget = r.get<uint64_t>();
  const uint8_t limited = r.get<uint8_t>();
  if (limited > 1) r.fail("bad budget flag");
  job.total_limited = limited != 0;
  job.cost = r.getFinite();
  if (r.remaining() != 0) r.fail("trailing bytes");
  return job;
}

// Outcome: u8 built; built: the tree, f64 its build_seconds (which the tree's layout writes as 0)
// and its query timing (u32 eyes, 7 f64); else u64 stopped_bytes, f64 stopped_fraction.
std::vector<uint8_t> pfdCellOutcomeBytes(const PfdCellOutcome& outcome) {
  Writer w;
  w.put<uint8_t>(outcome.tree ? 1 : 0);
  if (outcome.tree) {
    writeTree(w, *outcome.tree);
    w.put(outcome.tree->stats.build_seconds);
    const PfdQueryTiming& q = outcome.tree->stats.query_timing;
    w.put(q.eyes);
    for (double v : {q.pfd_ns, q.runs_ns, q.refs_ns, q.bsp_ns, q.runs_mean, q.refs_mean, q.object_tests_mean}) w.put(v);
  } else {
    w.put(outcome.stopped_bytes);
    w.put(outcome.stopped_fraction);
  }
  return std::move(w.bytes);
}

PfdCellOutcome pfdCellOutcomeFromBytes(std::span<const uint8_t> bytes, size_t fragments, const std::string& context) {
  Reader r(bytes, context + ": ");
  PfdCellOutcome out;
  const uint8_t built = r.get<uint8_t>();
  if (built > 1) r.fail("bad outcome flag");
  if (built) {
    out.tree = readTree(r, fragments);
    out.tree->stats.build_seconds = r.getFinite();
    PfdQueryTiming& q = out.tree->stats.query_timing;
    q.eyes = r.get<uint32_t>();
    for (double* v : {&q.pfd_ns, &q.runs_ns, &q.refs_ns, &q.bsp_ns, &q.runs_mean, &q.refs_mean, &q.object_tests_mean})
      *v = r.getFinite();
  } else {
    out.stopped_bytes = r.get<uint64_t>();
    out.stopped_fraction = r.getFinite();
  }
  if (r.remaining() != 0) r.fail("trailing bytes");
  return out;
}

void saveTreeFile(const TreeFile& file, const std::string& path) {
  const std::vector<uint8_t> bsp_bytes = bspFileBytes(file.bsp, path, false);
  Writer w;
  w.put(file.eye_height);
  w.put(static_cast<uint8_t>(file.kind));
  w.put(file.visibility.region_samples);
  w.put(file.visibility.polygon_samples);
  w.put(file.visibility.refine_rays);
  w.put(file.visibility.seed);
  w.put(static_cast<uint64_t>(bsp_bytes.size()));
  w.bytes.insert(w.bytes.end(), bsp_bytes.begin(), bsp_bytes.end());
  w.put(static_cast<uint32_t>(file.levels.size()));
  for (const PfdLevel& l : file.levels) {
    w.put(l.level);
    w.put(l.floor_y);
    w.put(l.height);
    w.put(static_cast<uint32_t>(l.cells.size()));
    for (const PfdTree& t : l.cells) writeTree(w, t);
  }
  Writer h;
  h.bytes.assign(kMagic, kMagic + 8);
  h.put(kVersion);
  h.put<uint32_t>(0);
  h.put(static_cast<uint64_t>(w.bytes.size()));
  h.put(fnv1a(w.bytes.data(), w.bytes.size()));
  const std::span<const uint8_t> parts[2] = {h.bytes, w.bytes};
  writeFileAtomically(path, parts, "tree file");
}

TreeFile loadTreeFileFromMemory(std::span<const uint8_t> bytes, const std::string& context) {
  if (bytes.size() < kHeaderBytes) throw Error(context + ": truncated tree file (no header)");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) throw Error(context + ": not a walkvis tree file (bad magic)");
  Reader hr(bytes.subspan(8), context + ": tree file: ");
  const uint32_t version = hr.get<uint32_t>();
  if (version != kVersion)
    throw Error(context + ": tree file version " + std::to_string(version) + ", expected " +
                     std::to_string(kVersion));
  if (hr.get<uint32_t>() != 0) throw Error(context + ": bad tree file header");
  const uint64_t size = hr.get<uint64_t>();
  const uint64_t checksum = hr.get<uint64_t>();
  if (size != bytes.size() - kHeaderBytes)
    throw Error(context + ": truncated tree file (" + std::to_string(bytes.size() - kHeaderBytes) +
                     " payload bytes, header says " + std::to_string(size) + ")");
  const std::span<const uint8_t> payload = bytes.subspan(kHeaderBytes);
  if (fnv1a(payload.data(), payload.size()) != checksum) throw Error(context + ": tree file checksum mismatch");

  Reader r(payload, context + ": tree file: ");
  TreeFile file;
  file.eye_height = r.getFinite();
  const uint8_t kind = r.get<uint8_t>();
  if (kind > 1) r.fail("unknown tree kind " + std::to_string(kind));
  file.kind = static_cast<TreeKind>(kind);
  file.visibility.region_samples = r.get<uint32_t>();
  file.visibility.polygon_samples = r.get<uint32_t>();
  file.visibility.refine_rays = r.get<uint32_t>();
  file.visibility.seed = r.get<uint64_t>();
  const uint64_t bsp_size = r.get<uint64_t>();
  if (bsp_size > r.remaining()) r.fail("truncated (BSP part)");
  file.bsp = loadBspFromMemory(r.take(bsp_size), context + " (BSP part)");
  const uint32_t levels = r.count(24);
  file.levels.resize(levels);
  for (PfdLevel& l : file.levels) {
    l.level = r.get<uint32_t>();
    l.floor_y = r.getFinite();
    l.height = r.getFinite();
    const uint32_t cells = r.count(64);
    l.cells.reserve(cells);
    for (uint32_t c = 0; c < cells; ++c) l.cells.push_back(readTree(r, file.bsp.fragments.size()));
  }
  if (r.remaining() != 0) r.fail("trailing bytes");
  return file;
}

bool isTreeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[sizeof kMagic] = {};
  return in.read(head, sizeof head) && std::memcmp(head, kMagic, sizeof kMagic) == 0;
}

TreeFile loadTreeFile(const std::string& path) {
  const std::vector<uint8_t> bytes = readFileBytes(path);
  return loadTreeFileFromMemory(bytes, path);
}

}  // namespace walkvis
