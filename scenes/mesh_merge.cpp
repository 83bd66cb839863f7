// Triangle soups into polygons (mesh_merge.h): coplanar patches of an object found by flood fill
// over exactly shared edges, their boundaries cut into convex pieces.
//
// Sources: region growing of coplanar facets as in CGAL 5.6 Polygon_mesh_processing
// region_growing_of_planes_on_faces / remesh_planar_patches (grow from a seed while a face stays
// within a distance and angle of the seed's plane; here with exact shared edges as the adjacency);
// the convex partition is convexPartition() (scene.h: a CGAL constrained triangulation with
// Hertel–Mehlhorn merging); the exact coplanarity test is CGAL's filtered orientation predicate
// (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric predicates",
// DCG 1997), in mesh_merge_cgal.cpp.
//
// Tolerances (their reasons):
// - kMergePlaneUlps (mesh_merge.h): files exported from architectural tools hold float coordinates
//   (IFC → assimp → OBJ/glTF round each coordinate to a 24-bit mantissa), so every coordinate of a
//   truly coplanar wall may be off by up to 2^-24·|coordinate| ≤ 2^-24·M, M the object's largest
//   |coordinate| (half a float ulp), and a distance to a plane by up to √3 times that; the seed's
//   own plane carries an error of the same order at its vertices. 8 ulps covers both with a margin
//   of ~2x, and stays 1000x below the 1e-3 relative folds a model shows on purpose.
// - kMergeMaxAngle: a float-rounded triangle of size s has a normal error of about 2·2^-24·M/s;
//   for a house in metres (M ≈ 20 m) and faces of 5 cm or more that is below 2e-5 rad, so 1e-4 rad
//   leaves a margin of 5 and is 10x below a 1e-3 rad fold, which must stay two faces. Smaller
//   faces whose normals round worse simply stay unmerged.
// - Per piece, the scene model's planarity (addFace: 1e-6 of the piece's size) is checked again
//   against the merged face's plane; a piece that fails becomes planar triangles.
#include "scenes/mesh_merge.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "core/hash.h"

namespace walkvis {
namespace {

constexpr double kFloatRounding = 0x1p-24;  // float's unit roundoff (half an ulp, relative)
constexpr double kEps = std::numeric_limits<double>::epsilon();

// + 0.0 in the hashes: -0.0 and 0.0 are one position.
struct PositionHash {
  size_t operator()(const glm::dvec3& p) const {
    const uint64_t h = fnv1aDoubles({p.x + 0.0, p.y + 0.0, p.z + 0.0});
    return static_cast<size_t>(h ^ (h >> 29));
  }
};
struct Position2Hash {
  size_t operator()(const glm::dvec2& p) const {
    const uint64_t h = fnv1aDoubles({p.x + 0.0, p.y + 0.0});
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t{a} << 32) | b; }

// As scene.cpp: u × v = n, so counter-clockwise about n stays counter-clockwise in (u, v).
void planeAxes(const glm::dvec3& n, glm::dvec3& u, glm::dvec3& v) {
  const glm::dvec3 a = std::abs(n.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  u = glm::normalize(glm::cross(a, n));
  v = glm::cross(n, u);
}


struct Face {
  std::vector<uint32_t> loop;  // distinct vertex ids, consecutive repeats removed
  glm::dvec3 normal{0.0};      // unit Newell normal
  glm::dvec3 centroid{0.0};
  double area = 0.0;
  uint32_t color = 0;
  bool eligible = false;       // may merge: >= 3 vertices, area, planar on its own
};

class Merger {
 public:
  Merger(Scene& scene, const MeshObjectInput& object, const std::string& context)
      : scene_(scene), object_(object), context_(context) {}

  std::vector<uint32_t> run() {
    indexVertices();
    buildFaces();
    splitTJunctions();
    buildEdges();
    growGroups();
    return emit();
  }

 private:
  void indexVertices() {
    std::unordered_map<glm::dvec3, uint32_t, PositionHash> ids;
    ids.reserve(object_.indices.size());
    vertex_of_index_.resize(object_.indices.size());
    double m = 0.0;
    for (size_t i = 0; i < object_.indices.size(); ++i) {
      glm::dvec3 p = object_.positions[object_.indices[i]];
      p += glm::dvec3(0.0);  // -0.0 → 0.0, so equal positions are equal keys
      auto [it, added] = ids.emplace(p, static_cast<uint32_t>(points_.size()));
      if (added) {
        points_.push_back(p);
        m = std::max({m, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      }
      vertex_of_index_[i] = it->second;
    }
    tolerance_ = kMergePlaneUlps * kFloatRounding * m;
  }

  void buildFaces() {
    faces_.resize(object_.face_sizes.size());
    size_t at = 0;
    for (size_t f = 0; f < faces_.size(); ++f) {
      Face& face = faces_[f];
      face.color = object_.face_colors[f];
      face_start_.push_back(at);
      for (uint32_t k = 0; k < object_.face_sizes[f]; ++k) {
        const uint32_t v = vertex_of_index_[at + k];
        if (face.loop.empty() || face.loop.back() != v) face.loop.push_back(v);
      }
      at += object_.face_sizes[f];
      while (face.loop.size() > 1 && face.loop.back() == face.loop.front()) face.loop.pop_back();
      if (face.loop.size() < 3) continue;
      // A vertex used twice (a pinched loop) makes edges ambiguous: such a face stays on its own.
      std::vector<uint32_t> sorted = face.loop;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
      const glm::dvec3 o = points_[face.loop[0]];
      glm::dvec3 n(0.0), c(0.0), lo = o, hi = o;
      for (size_t k = 0; k < face.loop.size(); ++k) {
        const glm::dvec3& p = points_[face.loop[k]];
        n += glm::cross(p - o, points_[face.loop[(k + 1) % face.loop.size()]] - o);
        c += p;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
      const double len = glm::length(n);
      const glm::dvec3 e = hi - lo;
      const double extent = std::max({e.x, e.y, e.z});
      // addFace's zero-area floor: such a face is dropped there, so it never joins a group.
      const double area_floor = 16.0 * static_cast<double>(face.loop.size()) * kEps * extent * extent;
      if (!(0.5 * len > area_floor)) continue;
      face.normal = n / len;
      face.centroid = c / static_cast<double>(face.loop.size());
      face.area = 0.5 * len;
      bool planar = true;
      for (uint32_t v : face.loop) {
        planar = planar && std::abs(glm::dot(face.normal, points_[v] - face.centroid)) <= tolerance_;
      }
      face.eligible = planar;
    }
  }

  // Faces that may share a merged face: same colour and normals within kMergeMaxAngle.
  bool compatible(const Face& a, const Face& b) const {
    return a.eligible && b.eligible && a.color == b.color && glm::dot(a.normal, b.normal) >= cos_max_angle_;
  }

  // A vertex x of a face on an edge p → q of a compatible face, with no exact partner edge q → p:
  // walk from p along the edges that end there and run back along p → q (x → p with x on the
  // segment), inserting each x into p → q. Only within compatible faces (the same plane up to the
  // tolerance); edges between faces of different planes stay as they are.
  void splitTJunctions() {
    std::unordered_set<uint64_t> edges;
    for (const Face& f : faces_) {
      if (!f.eligible) continue;
      for (size_t k = 0; k < f.loop.size(); ++k) edges.insert(edgeKey(f.loop[k], f.loop[(k + 1) % f.loop.size()]));
    }
    std::unordered_map<uint32_t, std::vector<std::pair<uint32_t, uint32_t>>> incoming;  // end -> (start, face)
    for (uint32_t fi = 0; fi < faces_.size(); ++fi) {
      const Face& f = faces_[fi];
      if (!f.eligible) continue;
      for (size_t k = 0; k < f.loop.size(); ++k) {
        const uint32_t a = f.loop[k], b = f.loop[(k + 1) % f.loop.size()];
        if (!edges.count(edgeKey(b, a))) incoming[b].emplace_back(a, fi);
      }
    }
    if (incoming.empty()) return;
    std::vector<uint32_t> loop;
    for (uint32_t fi = 0; fi < faces_.size(); ++fi) {
      Face& f = faces_[fi];
      if (!f.eligible) continue;
      loop.clear();
      bool changed = false;
      for (size_t k = 0; k < f.loop.size(); ++k) {
        const uint32_t p = f.loop[k], q = f.loop[(k + 1) % f.loop.size()];
        loop.push_back(p);
        if (edges.count(edgeKey(q, p))) continue;
        const glm::dvec3 P = points_[p], Q = points_[q];
        const glm::dvec3 pq = Q - P;
        const double len2 = glm::dot(pq, pq);
        uint32_t cur = p;
        double t_cur = 0.0;
        for (;;) {
          const auto it = incoming.find(cur);
          if (it == incoming.end()) break;
          uint32_t best = UINT32_MAX;
          double best_t = 2.0;
          for (const auto& [x, gi] : it->second) {
            if (gi == fi || x == q || x == p || !compatible(f, faces_[gi])) continue;
            const glm::dvec3 px = points_[x] - P;
            const double t = glm::dot(px, pq) / len2;
            if (!(t > t_cur && t < 1.0 && t < best_t)) continue;
            // Distance from the line through p and q.
            if (glm::length(glm::cross(pq, px)) > tolerance_ * std::sqrt(len2)) continue;
            best = x;
            best_t = t;
          }
          if (best == UINT32_MAX) break;
          loop.push_back(best);
          changed = true;
          scene_.report.tjunctions_removed++;
          cur = best;
          t_cur = best_t;
        }
      }
      if (changed) f.loop = loop;
    }
  }

  void buildEdges() {
    for (uint32_t fi = 0; fi < faces_.size(); ++fi) {
      const Face& f = faces_[fi];
      if (!f.eligible) continue;
      for (size_t k = 0; k < f.loop.size(); ++k) {
        edge_faces_.emplace_back(edgeKey(f.loop[k], f.loop[(k + 1) % f.loop.size()]), fi);
      }
    }
    std::sort(edge_faces_.begin(), edge_faces_.end());
  }

  // A face joins the seed's group when each of its vertices is exactly coplanar with the seed
  // triangle or within the tolerance of the seed's plane.
  bool inSeedPlane(const Face& g, const Face& seed, const uint32_t tri[3]) const {
    for (uint32_t v : g.loop) {
      const glm::dvec3& p = points_[v];
      if (std::abs(glm::dot(seed.normal, p - seed.centroid)) <= tolerance_) continue;
      if (orient3dExact(points_[tri[0]], points_[tri[1]], points_[tri[2]], p) == 0) continue;
      return false;
    }
    return true;
  }

  void growGroups() {
    group_of_.assign(faces_.size(), UINT32_MAX);
    std::vector<uint32_t> order;
    for (uint32_t fi = 0; fi < faces_.size(); ++fi) {
      if (faces_[fi].eligible) order.push_back(fi);
    }
    // Largest faces first: their planes are the best-determined seeds.
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return faces_[a].area > faces_[b].area; });
    std::vector<uint32_t> queue;
    for (uint32_t s : order) {
      if (group_of_[s] != UINT32_MAX) continue;
      const Face& seed = faces_[s];
      // The seed's largest fan triangle carries the exact test.
      uint32_t tri[3] = {seed.loop[0], seed.loop[1], seed.loop[2]};
      double best = -1.0;
      for (size_t k = 1; k + 1 < seed.loop.size(); ++k) {
        const double a = glm::length(glm::cross(points_[seed.loop[k]] - points_[seed.loop[0]],
                                                points_[seed.loop[k + 1]] - points_[seed.loop[0]]));
        if (a > best) {
          best = a;
          tri[1] = seed.loop[k];
          tri[2] = seed.loop[k + 1];
        }
      }
      const auto g = static_cast<uint32_t>(groups_.size());
      groups_.emplace_back();
      group_of_[s] = g;
      queue.assign(1, s);
      for (size_t at = 0; at < queue.size(); ++at) {
        const uint32_t fi = queue[at];
        groups_[g].push_back(fi);
        const Face& f = faces_[fi];
        for (size_t k = 0; k < f.loop.size(); ++k) {
          const uint64_t reverse = edgeKey(f.loop[(k + 1) % f.loop.size()], f.loop[k]);
          auto it = std::lower_bound(edge_faces_.begin(), edge_faces_.end(), std::make_pair(reverse, 0u));
          for (; it != edge_faces_.end() && it->first == reverse; ++it) {
            const uint32_t ni = it->second;
            if (group_of_[ni] != UINT32_MAX || !compatible(seed, faces_[ni])) continue;
            if (!inSeedPlane(faces_[ni], seed, tri)) continue;
            group_of_[ni] = g;
            queue.push_back(ni);
          }
        }
      }
      std::sort(groups_[g].begin(), groups_[g].end());
    }
  }

  struct Pieces {
    std::vector<std::vector<uint32_t>> polygons;  // vertex ids, counter-clockwise about plane.n
    std::vector<std::vector<bool>> straight;      // per vertex: a straight-on corner put back
    Plane plane;
  };

  // The group's region cut into convex pieces over its own vertices, or nullopt when the faces
  // do not make a clean region (overlaps, crossings, two vertices at one projected point): those
  // faces are then added one by one.
  std::optional<Pieces> groupPieces(const std::vector<uint32_t>& members) const {
    Pieces out;
    const glm::dvec3 o = points_[faces_[members[0]].loop[0]];
    glm::dvec3 n(0.0), c(0.0);
    std::vector<uint32_t> verts;
    bool flat = true;
    for (uint32_t fi : members) {
      const auto& loop = faces_[fi].loop;
      for (size_t k = 0; k < loop.size(); ++k) {
        n += glm::cross(points_[loop[k]] - o, points_[loop[(k + 1) % loop.size()]] - o);
        verts.push_back(loop[k]);
        flat = flat && points_[loop[k]].y == o.y;
      }
    }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    for (uint32_t v : verts) c += points_[v];
    c /= static_cast<double>(verts.size());
    const double len = glm::length(n);
    if (!(len > 0.0)) return std::nullopt;
    // As newellPlane: a face whose vertices share one y is exactly horizontal.
    if (flat) {
      out.plane.n = glm::dvec3(0.0, n.y > 0.0 ? 1.0 : -1.0, 0.0);
      out.plane.d = out.plane.n.y * o.y;
    } else {
      out.plane.n = n / len;
      out.plane.d = glm::dot(out.plane.n, c);
    }
    glm::dvec3 u_axis, v_axis;
    planeAxes(out.plane.n, u_axis, v_axis);
    std::unordered_map<uint32_t, glm::dvec2> flat2;
    std::unordered_map<glm::dvec2, uint32_t, Position2Hash> lift;
    for (uint32_t v : verts) {
      const glm::dvec3 r = points_[v] - c;
      const glm::dvec2 q(glm::dot(r, u_axis), glm::dot(r, v_axis));
      flat2.emplace(v, q);
      if (!lift.emplace(q, v).second) return std::nullopt;
    }
    // Boundary: each undirected edge's net count over the faces' loops.
    std::unordered_map<uint64_t, int> net;
    double faces_area = 0.0;
    std::vector<glm::dvec2> ring;
    for (uint32_t fi : members) {
      const auto& loop = faces_[fi].loop;
      ring.clear();
      for (size_t k = 0; k < loop.size(); ++k) {
        const uint32_t a = loop[k], b = loop[(k + 1) % loop.size()];
        net[a < b ? edgeKey(a, b) : edgeKey(b, a)] += a < b ? 1 : -1;
        ring.push_back(flat2.at(a));
      }
      const double a = signedArea(ring);
      if (!(a > 0.0)) return std::nullopt;
      faces_area += a;
    }
    std::unordered_map<uint32_t, std::vector<uint32_t>> next;  // boundary successors
    size_t boundary_edges = 0;
    for (const auto& [key, count] : net) {
      const auto a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key & 0xffffffffu);
      for (int i = 0; i < std::abs(count); ++i) {
        if (count > 0) {
          next[a].push_back(b);
        } else {
          next[b].push_back(a);
        }
        ++boundary_edges;
      }
    }
    // Closed loops: every vertex has as many boundary edges in as out, so a walk along unused
    // edges returns to its start. Any such decomposition gives the same odd-winding region.
    std::vector<std::vector<glm::dvec2>> rings;
    {
      auto unused = next;
      std::vector<uint32_t> starts;
      for (const auto& [v, list] : unused) starts.push_back(v);
      std::sort(starts.begin(), starts.end());
      size_t used = 0;
      for (uint32_t s : starts) {
        while (!unused[s].empty()) {
          std::vector<glm::dvec2> r;
          uint32_t v = s;
          do {
            auto& list = unused[v];
            if (list.empty()) return std::nullopt;  // unbalanced: cannot happen for closed loops
            r.push_back(flat2.at(v));
            const uint32_t w = list.back();
            list.pop_back();
            ++used;
            v = w;
          } while (v != s);
          rings.push_back(std::move(r));
        }
      }
      if (used != boundary_edges) return std::nullopt;
    }
    const auto pieces = convexPartition(rings);
    double pieces_area = 0.0;
    std::unordered_set<uint32_t> in_pieces;
    for (const auto& piece : pieces) {
      std::vector<uint32_t> ids;
      for (const auto& q : piece) {
        const auto it = lift.find(q);
        if (it == lift.end()) return std::nullopt;  // a point the faces' edges made by crossing
        ids.push_back(it->second);
        in_pieces.insert(it->second);
      }
      pieces_area += signedArea(piece);
      out.polygons.push_back(std::move(ids));
    }
    // The pieces cover the odd-winding region; faces that overlap would make it smaller than
    // their sum. The sums differ only by the rounding of two orders of summation.
    if (!(std::abs(pieces_area - faces_area) <= 1e-9 * faces_area)) return std::nullopt;
    // Put back the boundary vertices the partition left out as straight-on corners, each on the
    // piece edge that runs along it, so a neighbour outside the group keeps its exact edges.
    for (auto& poly : out.polygons) {
      std::vector<uint32_t> full;
      std::vector<bool> straight;
      for (size_t k = 0; k < poly.size(); ++k) {
        const uint32_t p = poly[k], q = poly[(k + 1) % poly.size()];
        full.push_back(p);
        straight.push_back(false);
        const glm::dvec2 P = flat2.at(p), pq = flat2.at(q) - P;
        const double len2 = glm::dot(pq, pq);
        uint32_t cur = p;
        double t_cur = 0.0;
        for (;;) {
          const auto it = next.find(cur);
          if (it == next.end()) break;
          bool found = false;
          for (uint32_t s : it->second) {
            if (s == q || in_pieces.count(s)) continue;
            const glm::dvec2 ps = flat2.at(s) - P;
            const double t = glm::dot(ps, pq) / len2;
            if (!(t > t_cur && t < 1.0)) continue;
            // The partition found s exactly collinear: only rounding of the projection is left.
            if (std::abs(pq.x * ps.y - pq.y * ps.x) > 1e-9 * len2) continue;
            full.push_back(s);
            straight.push_back(true);
            cur = s;
            t_cur = t;
            found = true;
            break;
          }
          if (!found) break;
        }
      }
      poly = std::move(full);
      out.straight.push_back(std::move(straight));
    }
    std::unordered_set<uint32_t> placed;
    for (const auto& poly : out.polygons) placed.insert(poly.begin(), poly.end());
    for (const auto& [v, list] : next) {
      if (!placed.count(v)) return std::nullopt;  // would open a gap to a neighbour
    }
    return out;
  }

  uint32_t newFaceId(uint32_t color) {
    const auto id = static_cast<uint32_t>(scene_.face_colors.size());
    scene_.face_colors.push_back(color == kFaceColorById ? faceColor(id) : color);
    return id;
  }


  uint32_t emitGroup(const std::vector<uint32_t>& members, const Pieces& pieces) {
    const uint32_t id = newFaceId(faces_[members[0]].color);
    LoadReport& r = scene_.report;
    r.input_faces += members.size();
    r.merged_input_faces += members.size();
    r.merged_faces++;
    uint64_t made = 0;
    std::vector<glm::dvec3> p3;
    for (size_t pi = 0; pi < pieces.polygons.size(); ++pi) {
      const auto& poly = pieces.polygons[pi];
      const auto& straight = pieces.straight[pi];
      p3.clear();
      glm::dvec3 lo = points_[poly[0]], hi = lo;
      for (uint32_t v : poly) {
        p3.push_back(points_[v]);
        lo = glm::min(lo, points_[v]);
        hi = glm::max(hi, points_[v]);
      }
      const glm::dvec3 e = hi - lo;
      const double extent = std::max({e.x, e.y, e.z});
      double off = 0.0;
      for (const auto& p : p3) off = std::max(off, std::abs(glm::dot(pieces.plane.n, p) - pieces.plane.d));
      // addFace's planarity tolerance (scene.cpp), so a merged piece is as planar as a kept face.
      if (off <= 1e-6 * extent) {
        appendPolygon(scene_, p3, id, pieces.plane);
        ++made;
        continue;
      }
      // A fan of triangles, each planar by construction, from a corner whose two edges carry no
      // straight-on corners (a fan over those would make slivers whose normals rounding decides);
      // from the centroid when every corner has one.
      const size_t n = p3.size();
      size_t apex = n;
      for (size_t k = 0; k < n && apex == n; ++k) {
        if (!straight[k] && !straight[(k + 1) % n] && !straight[(k + n - 1) % n]) apex = k;
      }
      std::vector<std::vector<glm::dvec3>> tris;
      if (apex < n) {
        for (size_t i = 1; i + 1 < n; ++i) tris.push_back({p3[apex], p3[(apex + i) % n], p3[(apex + i + 1) % n]});
      } else {
        glm::dvec3 centre(0.0);
        for (const auto& p : p3) centre += p;
        centre /= static_cast<double>(n);
        for (size_t i = 0; i < n; ++i) tris.push_back({centre, p3[i], p3[(i + 1) % n]});
      }
      for (const auto& tri : tris) {
        const Plane tp = newellPlane(tri);
        if (glm::length(tp.n) == 0.0) continue;
        appendPolygon(scene_, tri, id, tp);
        ++made;
      }
    }
    if (made == 1) {
      r.kept_faces++;
    } else {
      // Never 0: the pieces cover the faces' (positive) area.
      r.split_faces++;
      r.split_pieces += made;
    }
    return id;
  }

  uint32_t emitSingle(uint32_t fi) {
    std::vector<glm::dvec3> v;
    const Face& f = faces_[fi];
    if (f.eligible) {
      // With any T-junction vertices it received: they keep its edges matched to its neighbours.
      for (uint32_t p : f.loop) v.push_back(points_[p]);
    } else {
      for (uint32_t k = 0; k < object_.face_sizes[fi]; ++k) {
        v.push_back(object_.positions[object_.indices[face_start_[fi] + k]]);
      }
    }
    const uint32_t color = f.color == kFaceColorById ? faceColor(static_cast<uint32_t>(scene_.face_colors.size()))
                                                     : f.color;
    return addFace(scene_, v, color, context_);
  }

  std::vector<uint32_t> emit() {
    std::vector<uint32_t> ids(faces_.size(), UINT32_MAX);
    std::vector<bool> failed(groups_.size(), false);
    for (uint32_t fi = 0; fi < faces_.size(); ++fi) {
      if (ids[fi] != UINT32_MAX) continue;
      const uint32_t g = group_of_[fi];
      if (g != UINT32_MAX && groups_[g].size() > 1 && !failed[g]) {
        const auto pieces = groupPieces(groups_[g]);
        if (pieces) {
          const uint32_t id = emitGroup(groups_[g], *pieces);
          for (uint32_t m : groups_[g]) ids[m] = id;
          continue;
        }
        failed[g] = true;
      }
      ids[fi] = emitSingle(fi);
    }
    return ids;
  }

  Scene& scene_;
  const MeshObjectInput& object_;
  const std::string& context_;
  const double cos_max_angle_ = std::cos(kMergeMaxAngle);
  double tolerance_ = 0.0;
  std::vector<glm::dvec3> points_;            // distinct positions
  std::vector<uint32_t> vertex_of_index_;     // per entry of object.indices
  std::vector<size_t> face_start_;            // per face: first entry in object.indices
  std::vector<Face> faces_;
  std::vector<std::pair<uint64_t, uint32_t>> edge_faces_;  // (directed edge, face), sorted
  std::vector<uint32_t> group_of_;
  std::vector<std::vector<uint32_t>> groups_;
};

void checkInput(const MeshObjectInput& object, const std::string& context) {
  if (object.face_colors.size() != object.face_sizes.size()) {
    throw Error(context + ": " + std::to_string(object.face_sizes.size()) + " faces but " +
                     std::to_string(object.face_colors.size()) + " face colours");
  }
  uint64_t total = 0;
  for (uint32_t s : object.face_sizes) total += s;
  if (total != object.indices.size()) {
    throw Error(context + ": faces need " + std::to_string(total) + " indices, got " +
                     std::to_string(object.indices.size()));
  }
  for (uint32_t i : object.indices) {
    if (i >= object.positions.size()) {
      throw Error(context + ": vertex index " + std::to_string(i) + " out of range (" +
                       std::to_string(object.positions.size()) + " vertices)");
    }
    const glm::dvec3& p = object.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw Error(context + ": vertex " + std::to_string(i) + " has a non-finite coordinate (" +
                       std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
    }
  }
}

}  // namespace

namespace {

// Faces [first_face, end) are one object: the next object number (objects are added in order, so
// the last entry is the highest so far). Faces added before any object get none of their own and
// count as one object of their own each.
void tagObject(Scene& scene, size_t first_face) {
  std::vector<uint32_t>& tags = scene.face_object;
  uint32_t next = tags.empty() ? 0 : tags.back() + 1;
  while (tags.size() < first_face) tags.push_back(next++);
  tags.resize(scene.face_colors.size(), next);
}

}  // namespace

std::vector<uint32_t> addMeshObject(Scene& scene, const MeshObjectInput& object, bool merge,
                                    const std::string& context) {
  checkInput(object, context);
  const size_t first_face = scene.face_colors.size();
  std::vector<uint32_t> ids;
  if (!merge) {
    ids.reserve(object.face_sizes.size());
    std::vector<glm::dvec3> v;
    size_t at = 0;
    for (size_t f = 0; f < object.face_sizes.size(); ++f) {
      v.clear();
      for (uint32_t k = 0; k < object.face_sizes[f]; ++k) v.push_back(object.positions[object.indices[at + k]]);
      at += object.face_sizes[f];
      uint32_t color = object.face_colors[f];
      if (color == kFaceColorById) color = faceColor(static_cast<uint32_t>(scene.face_colors.size()));
      ids.push_back(addFace(scene, v, color, context));
    }
  } else {
    ids = Merger(scene, object, context).run();
    scene.report.input_to_face.insert(scene.report.input_to_face.end(), ids.begin(), ids.end());
  }
  tagObject(scene, first_face);
  return ids;
}

}  // namespace walkvis
