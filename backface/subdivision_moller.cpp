// Heuristic backface culling of animated Loop subdivision surfaces: Tomas Möller & Carlo H.
// Séquin, "Heuristic Backface Culling of Animated Subdivision Surfaces"
// [MollerSequin]. Loop's scheme: C. Loop, "Smooth Subdivision Surfaces Based on Triangles", MSc
// thesis, Utah 1987 [Loop1987] (edge points 3/8·(a + b) + 1/8·(c + d); vertex points
// (1 − nβ)·v + β·Σ neighbours with β = 3/16 for n = 3, else 3/(8n), Warren's weights [Warren1995]).
//
// Per level: status of every triangle not yet culled (front / back / strong / total, subdivision.h),
// totally back-facing ones dropped; the others are split and only the vertices their children use
// are computed. The heuristic has no guarantee (the paper says so): a Loop stencil of a needed vertex
// may reach into a dropped region, and that vertex is then left out with the children using it
// (counted as `incomplete`), rather than computed from missing data.
#include "backface/subdivision.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include <glm/geometric.hpp>

#include "scenes/scene.h"

namespace walkvis {
namespace {

constexpr int kMaxLevels = 6;

LoopTopology::Level makeLevel(std::vector<std::array<uint32_t, 3>> triangles, size_t vertex_count) {
  LoopTopology::Level level;
  level.triangles = std::move(triangles);
  level.vertex_count = vertex_count;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_index;
  level.tri_edges.resize(level.triangles.size());
  for (size_t t = 0; t < level.triangles.size(); ++t) {
    const auto& tri = level.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      const uint32_t c = tri[static_cast<size_t>((k + 2) % 3)];
      const auto key = std::minmax(a, b);
      auto [it, fresh] = edge_index.emplace(key, static_cast<uint32_t>(level.edges.size()));
      if (fresh) {
        level.edges.push_back({key.first, key.second, c, c});
      } else {
        level.edges[it->second][3] = c;
      }
      level.tri_edges[t][static_cast<size_t>(k)] = it->second;
    }
  }
  // Rings and fans (CSR).
  std::vector<std::vector<uint32_t>> ring(vertex_count), fan(vertex_count);
  for (const auto& e : level.edges) {
    ring[e[0]].push_back(e[1]);
    ring[e[1]].push_back(e[0]);
  }
  for (size_t t = 0; t < level.triangles.size(); ++t) {
    for (uint32_t v : level.triangles[t]) fan[v].push_back(static_cast<uint32_t>(t));
  }
  level.ring_begin.push_back(0);
  level.fan_begin.push_back(0);
  for (size_t v = 0; v < vertex_count; ++v) {
    std::sort(ring[v].begin(), ring[v].end());
    level.ring.insert(level.ring.end(), ring[v].begin(), ring[v].end());
    level.ring_begin.push_back(static_cast<uint32_t>(level.ring.size()));
    level.fan.insert(level.fan.end(), fan[v].begin(), fan[v].end());
    level.fan_begin.push_back(static_cast<uint32_t>(level.fan.size()));
  }
  return level;
}

bool frontFacing(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& eye) {
  return glm::dot(glm::cross(b - a, c - a), eye - a) > 0.0;
}

}  // namespace

LoopTopology::LoopTopology(std::span<const std::array<uint32_t, 3>> triangles, size_t vertex_count, int max_levels) {
  if (max_levels < 0 || max_levels > kMaxLevels) {
    throw Error("subdivision: levels must be in [0, " + std::to_string(kMaxLevels) + "]");
  }
  if (triangles.empty()) throw Error("subdivision: control mesh has no triangles");
  // Closed oriented manifold: every directed edge once, and its reverse once.
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a >= vertex_count) {
        throw Error("subdivision: triangle " + std::to_string(t) + " uses vertex " + std::to_string(a) +
                         " of " + std::to_string(vertex_count));
      }
      if (a == b) throw Error("subdivision: triangle " + std::to_string(t) + " repeats a vertex");
      if (++directed[{a, b}] > 1) {
        throw Error("subdivision: edge " + std::to_string(a) + "-" + std::to_string(b) +
                         " is used twice in one direction (not an oriented manifold)");
      }
    }
  }
  for (const auto& [edge, n] : directed) {
    if (!directed.count({edge.second, edge.first})) {
      throw Error("subdivision: edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) +
                       " has no opposite triangle (the control mesh is not closed)");
    }
  }
  levels_.push_back(makeLevel({triangles.begin(), triangles.end()}, vertex_count));
  for (int l = 0; l < max_levels; ++l) {
    const Level& prev = levels_.back();
    const uint32_t base = static_cast<uint32_t>(prev.vertex_count);
    std::vector<std::array<uint32_t, 3>> children;
    children.reserve(4 * prev.triangles.size());
    for (size_t t = 0; t < prev.triangles.size(); ++t) {
      const auto& [a, b, c] = prev.triangles[t];
      const uint32_t ab = base + prev.tri_edges[t][0], bc = base + prev.tri_edges[t][1], ca = base + prev.tri_edges[t][2];
      children.push_back({a, ab, ca});
      children.push_back({b, bc, ab});
      children.push_back({c, ca, bc});
      children.push_back({ab, bc, ca});
    }
    levels_.push_back(makeLevel(std::move(children), prev.vertex_count + prev.edges.size()));
  }
}

SubdivisionResult subdivide(const LoopTopology& topology, std::span<const glm::dvec3> control_positions, int levels,
                            const glm::dvec3& eye, bool culling) {
  if (levels < 0 || levels > topology.maxLevels()) throw Error("subdivision: levels beyond the topology's");
  if (control_positions.size() != topology.level(0).vertex_count) {
    throw Error("subdivision: " + std::to_string(control_positions.size()) + " positions for " +
                     std::to_string(topology.level(0).vertex_count) + " control vertices");
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  SubdivisionResult out;
  std::vector<glm::dvec3> pos(control_positions.begin(), control_positions.end());
  std::vector<uint8_t> have(pos.size(), 1);
  const LoopTopology::Level& level0 = topology.level(0);
  std::vector<uint8_t> present(level0.triangles.size(), 1), total_front(level0.triangles.size(), 0);
  out.triangles_computed.push_back(level0.triangles.size());
  out.vertices_computed.push_back(pos.size());
  std::vector<FacingClass> cls;
  std::vector<uint8_t> back, strong, vertex_ok, vertex_front;
  for (int l = 0;; ++l) {
    const LoopTopology::Level& lv = topology.level(l);
    const size_t tris = lv.triangles.size();
    // Status of the triangles not culled. Culled (absent) neighbours count as strongly back-facing:
    // they were dropped as totally back-facing or as unreachable by the stencils.
    cls.assign(tris, FacingClass::kFront);
    back.assign(tris, 1);
    strong.assign(tris, 1);
    for (size_t t = 0; t < tris; ++t) {
      if (!present[t]) continue;
      if (total_front[t]) {
        cls[t] = FacingClass::kTotalFront;
        back[t] = 0;
        continue;
      }
      const auto& [a, b, c] = lv.triangles[t];
      back[t] = !frontFacing(pos[a], pos[b], pos[c], eye);
      cls[t] = back[t] ? FacingClass::kBack : FacingClass::kFront;
    }
    // A triangle's neighbours are the triangles around its three vertices: flag each vertex whose
    // whole fan has a property once, then a triangle tests its three vertices.
    auto fanFlags = [&](const std::vector<uint8_t>& flag, uint8_t want, std::vector<uint8_t>& out_ok) {
      out_ok.assign(lv.vertex_count, 1);
      for (size_t v = 0; v < lv.vertex_count; ++v) {
        for (uint32_t f = lv.fan_begin[v]; f < lv.fan_begin[v + 1]; ++f) {
          if (flag[lv.fan[f]] != want) {
            out_ok[v] = 0;
            break;
          }
        }
      }
    };
    auto allOk = [&](size_t t, const std::vector<uint8_t>& ok) {
      const auto& [a, b, c] = lv.triangles[t];
      return ok[a] && ok[b] && ok[c];
    };
    // The final level is only drawn: its strong / total status would decide nothing.
    if (culling && l < levels) {
      fanFlags(back, 1, vertex_ok);
      for (size_t t = 0; t < tris; ++t) {
        if (present[t]) strong[t] = back[t] && allOk(t, vertex_ok);
      }
      // Totally front: front with every neighbour front (absent ones are back, so they break it).
      fanFlags(back, 0, vertex_front);
      fanFlags(strong, 1, vertex_ok);
      for (size_t t = 0; t < tris; ++t) {
        if (!present[t]) continue;
        if (strong[t]) cls[t] = allOk(t, vertex_ok) ? FacingClass::kTotal : FacingClass::kStrong;
        if (!back[t] && allOk(t, vertex_front)) cls[t] = FacingClass::kTotalFront;
      }
    }
    if (l == levels) {
      out.vertices.assign(pos.size(), glm::dvec3(nan));
      for (size_t v = 0; v < pos.size(); ++v) {
        if (have[v]) out.vertices[v] = pos[v];
      }
      for (size_t t = 0; t < tris; ++t) {
        if (!present[t] || cls[t] == FacingClass::kTotal) continue;
        out.triangles.push_back(lv.triangles[t]);
        out.classes.push_back(cls[t]);
      }
      return out;
    }

    // Subdivide every present triangle that is not totally back-facing: vertices first.
    const LoopTopology::Level& next = topology.level(l + 1);
    const uint32_t base = static_cast<uint32_t>(lv.vertex_count);
    std::vector<glm::dvec3> npos(next.vertex_count, glm::dvec3(0.0));
    std::vector<uint8_t> nhave(next.vertex_count, 0), wanted(next.vertex_count, 0);
    for (size_t t = 0; t < tris; ++t) {
      if (!present[t] || cls[t] == FacingClass::kTotal) continue;
      for (uint32_t v : lv.triangles[t]) wanted[v] = 1;
      for (uint32_t e : lv.tri_edges[t]) wanted[base + e] = 1;
    }
    uint64_t computed = 0;
    for (uint32_t v = 0; v < base; ++v) {
      if (!wanted[v] || !have[v]) continue;
      const uint32_t r0 = lv.ring_begin[v], r1 = lv.ring_begin[v + 1];
      bool complete = true;
      glm::dvec3 sum(0.0);
      for (uint32_t r = r0; r < r1; ++r) {
        complete &= have[lv.ring[r]] != 0;
        sum += pos[lv.ring[r]];
      }
      if (!complete) continue;
      const double n = r1 - r0;
      const double beta = n == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * n);
      npos[v] = (1.0 - n * beta) * pos[v] + beta * sum;
      nhave[v] = 1;
      ++computed;
    }
    for (uint32_t e = 0; e < lv.edges.size(); ++e) {
      if (!wanted[base + e]) continue;
      const auto& [a, b, c, d] = lv.edges[e];
      if (!have[a] || !have[b] || !have[c] || !have[d]) continue;
      npos[base + e] = 0.375 * (pos[a] + pos[b]) + 0.125 * (pos[c] + pos[d]);
      nhave[base + e] = 1;
      ++computed;
    }
    std::vector<uint8_t> npresent(next.triangles.size(), 0), ntotal_front(next.triangles.size(), 0);
    uint64_t children = 0;
    for (size_t t = 0; t < tris; ++t) {
      if (!present[t] || cls[t] == FacingClass::kTotal) continue;
      for (size_t k = 4 * t; k < 4 * t + 4; ++k) {
        const auto& [a, b, c] = next.triangles[k];
        if (nhave[a] && nhave[b] && nhave[c]) {
          npresent[k] = 1;
          ntotal_front[k] = culling && cls[t] == FacingClass::kTotalFront;
          ++children;
        } else {
          ++out.incomplete;
        }
      }
    }
    out.triangles_computed.push_back(children);
    out.vertices_computed.push_back(computed);
    pos = std::move(npos);
    have = std::move(nhave);
    present = std::move(npresent);
    total_front = std::move(ntotal_front);
  }
}

SubdivisionResult subdivide(const ControlMesh& mesh, int levels, const glm::dvec3& eye, bool culling) {
  for (const glm::dvec3& p : mesh.positions) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw Error("subdivision: control mesh has a non-finite vertex");
    }
  }
  const LoopTopology topology(mesh.triangles, mesh.positions.size(), levels);
  return subdivide(topology, mesh.positions, levels, eye, culling);
}

ControlMesh animatedBlob(double t, int refine) {
  if (refine < 0 || refine > 5) throw Error("animatedBlob: refine must be in [0, 5]");
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v = {{-1, g, 0}, {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                               {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p = glm::normalize(p);
  for (int r = 0; r < refine; ++r) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto [it, fresh] = mid.emplace(std::minmax(a, b), static_cast<uint32_t>(v.size()));
      if (fresh) v.push_back(glm::normalize(v[a] + v[b]));
      return it->second;
    };
    std::vector<std::array<uint32_t, 3>> nf;
    for (const auto& [a, b, c] : f) {
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      nf.push_back({a, ab, ca});
      nf.push_back({b, bc, ab});
      nf.push_back({c, ca, bc});
      nf.push_back({ab, bc, ca});
    }
    f = std::move(nf);
  }
  ControlMesh mesh;
  mesh.triangles = std::move(f);
  for (const glm::dvec3& p : v) {
    // A radial bulge that travels with t: smooth, never folds (radius in [0.55, 1.45]).
    const double r = 1.0 + 0.3 * std::sin(3.0 * p.x + 2.0 * t) * std::cos(2.0 * p.y - 1.5 * t) +
                     0.15 * std::sin(4.0 * p.z + t);
    mesh.positions.push_back(r * p);
  }
  return mesh;
}

}  // namespace walkvis
