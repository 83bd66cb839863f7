// BSP tree: build wrapper (validation, statistics) and traversal.
// Source: H. Fuchs, Z. M. Kedem, B. F. Naylor, "On visible surface generation by a priori tree
// structures", SIGGRAPH 1980 [FuchsKedemNaylor1980]: back-to-front for an eye v is the far subtree,
// the node's polygons, the near subtree; front-to-back is the reverse.
#include "bsp/bsp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>

#include <glm/common.hpp>

#include "bsp/bsp_internal.h"
#include "bsp/exact_sign.h"
#include "core/check.h"
#include "core/hash.h"

namespace walkvis {

namespace {

void validate(const Scene& scene) {
  if (scene.polygons.size() >= UINT32_MAX / 2)
    throw Error("bsp: " + scene.name + ": too many polygons (" + std::to_string(scene.polygons.size()) + ")");
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const Polygon& p = scene.polygons[i];
    const std::string where = "bsp: " + scene.name + ": polygon " + std::to_string(i);
    if (p.vertex_count < 3) throw Error(where + " has fewer than 3 vertices");
    if (static_cast<uint64_t>(p.first_vertex) + p.vertex_count > scene.vertices.size())
      throw Error(where + " has vertices out of range");
    const Plane& pl = p.plane;
    if (!(std::isfinite(pl.n.x) && std::isfinite(pl.n.y) && std::isfinite(pl.n.z) && std::isfinite(pl.d)))
      throw Error(where + " has a non-finite plane");
    if (pl.n.x == 0.0 && pl.n.y == 0.0 && pl.n.z == 0.0) throw Error(where + " has a zero normal");
    for (const glm::dvec3& v : scene.polygonVertices(p))
      if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)))
        throw Error(where + " has a non-finite vertex");
  }
}

void computeStats(BspTree& tree, size_t input_polygons) {
  BspStats& s = tree.stats;
  s.nodes = tree.nodes.size();
  s.fragments = tree.fragments.size();
  s.input_polygons = input_polygons;
  s.ratio = input_polygons ? static_cast<double>(s.fragments) / static_cast<double>(input_polygons) : 0.0;
  s.depth_max = 0;
  double depth_sum = 0.0;
  for (const BspNode& node : tree.nodes) {
    s.depth_max = std::max(s.depth_max, node.depth);
    depth_sum += static_cast<double>(node.depth) * node.fragment_count;
  }
  s.depth_mean = s.fragments ? depth_sum / static_cast<double>(s.fragments) : 0.0;
  s.bytes = tree.vertices.size() * sizeof(glm::dvec3) + tree.fragments.size() * sizeof(Polygon) +
            tree.fragment_polygon.size() * sizeof(uint32_t) + tree.fragment_orientation.size() * sizeof(int8_t) +
            tree.nodes.size() * sizeof(BspNode);
}

inline int nodeSide(const BspNode& node, const glm::dvec3& eye) { return planeSide(node.plane, eye); }

// Emits the node's fragments, dropping back faces when asked. `side` is the eye's side of the
// node plane.
inline void emitNode(const BspTree& tree, const BspNode& node, int side, const glm::dvec3& eye,
                     std::vector<uint32_t>& order, bool skip_back_faces) {
  const uint32_t end = node.first_fragment + node.fragment_count;
  for (uint32_t f = node.first_fragment; f < end; ++f) {
    if (skip_back_faces) {
      const int8_t o = tree.fragment_orientation[f];
      const int s = o != 0 ? side * o : sideOfPlane(tree, f, eye);
      if (s <= 0) continue;
    }
    order.push_back(f);
  }
}

// Stackless in-order walk with parent links, so the per-frame traversal never allocates and never
// recurses (a degenerate tree may be as deep as it has nodes). The side of a node is recomputed
// when the walk comes back to it: the same exact answer, no scratch storage.
void traverse(const BspTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order, bool skip_back_faces,
              bool back_to_front) {
  order.clear();
  int32_t cur = tree.root;
  int32_t prev = -1;
  while (cur != -1) {
    const BspNode& node = tree.nodes[static_cast<size_t>(cur)];
    const int side = nodeSide(node, eye);
    // Eye in front: the back subtree is far. On the plane either order is right (the halves
    // cannot overlap as seen from a point of the plane); take the same as in front.
    const int32_t far_child = side >= 0 ? node.back : node.front;
    const int32_t near_child = side >= 0 ? node.front : node.back;
    const int32_t first = back_to_front ? far_child : near_child;
    const int32_t second = back_to_front ? near_child : far_child;
    int32_t next;
    if (prev == node.parent) {
      if (first != -1) {
        next = first;
      } else {
        emitNode(tree, node, side, eye, order, skip_back_faces);
        next = second != -1 ? second : node.parent;
      }
    } else if (prev == first) {
      emitNode(tree, node, side, eye, order, skip_back_faces);
      next = second != -1 ? second : node.parent;
    } else {
      next = node.parent;
    }
    prev = cur;
    cur = next;
  }
}

}  // namespace

DetailGroups detailGroups(const Scene& scene, double detail_extent) {
  DetailGroups out;
  const size_t n = scene.polygons.size();
  if (!(detail_extent > 0.0) || n == 0) return out;
  const auto objectOf = [&](uint32_t polygon) -> uint32_t {
    if (scene.face_object.empty()) return 0;
    const uint32_t face = scene.polygons[polygon].face_id;
    return face < scene.face_object.size() ? scene.face_object[face] : UINT32_MAX;
  };
  // Connected pieces: polygons of one object that share an exactly equal vertex (sorting, so -0
  // and 0 are one position) are joined by union-find with path halving.
  std::vector<uint32_t> parent(n);
  for (uint32_t i = 0; i < n; ++i) parent[i] = i;
  const auto find = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  struct Corner {
    uint32_t object;
    glm::dvec3 p;
    uint32_t polygon;
  };
  std::vector<Corner> corners;
  corners.reserve(scene.vertices.size());
  for (uint32_t i = 0; i < n; ++i)
    for (const glm::dvec3& v : scene.polygonVertices(i)) corners.push_back({objectOf(i), v, i});
  const auto before = [](const Corner& a, const Corner& b) {
    if (a.object != b.object) return a.object < b.object;
    if (a.p.x != b.p.x) return a.p.x < b.p.x;
    if (a.p.y != b.p.y) return a.p.y < b.p.y;
    return a.p.z < b.p.z;
  };
  std::sort(corners.begin(), corners.end(), before);
  for (size_t k = 1; k < corners.size(); ++k) {
    if (before(corners[k - 1], corners[k])) continue;  // equal: the same position in one object
    const uint32_t a = find(corners[k - 1].polygon), b = find(corners[k].polygon);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<Bounds> box(n);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t r = find(i);  // the smallest polygon index of its piece: met first
    if (r == i) box[r].lo = box[r].hi = scene.polygonVertices(i)[0];
    for (const glm::dvec3& v : scene.polygonVertices(i)) {
      box[r].lo = glm::min(box[r].lo, v);
      box[r].hi = glm::max(box[r].hi, v);
    }
  }
  const double limit = detail_extent * scene.eye_height;
  std::vector<uint32_t> id(n, kStructureGroup);
  std::vector<uint32_t> objects;
  out.group.assign(n, kStructureGroup);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t r = find(i);
    if (r == i) {
      const glm::dvec3 e = box[r].hi - box[r].lo;
      if (std::max({e.x, e.y, e.z}) < limit) {
        id[r] = static_cast<uint32_t>(out.groups++);
        objects.push_back(objectOf(i));
      }
    }
    out.group[i] = id[r];
    out.polygons += id[r] != kStructureGroup;
  }
  if (out.groups == 0) return DetailGroups{};
  std::sort(objects.begin(), objects.end());
  out.objects = static_cast<uint64_t>(std::unique(objects.begin(), objects.end()) - objects.begin());
  return out;
}

namespace detail {

std::string bspStructureProblem(const BspTree& tree) {
  const size_t nf = tree.fragments.size(), nn = tree.nodes.size();
  if (tree.fragment_polygon.size() != nf || tree.fragment_orientation.size() != nf)
    return "fragment arrays of different lengths";
  for (size_t i = 0; i < nf; ++i) {
    const Polygon& f = tree.fragments[i];
    if (f.vertex_count < 3 || static_cast<uint64_t>(f.first_vertex) + f.vertex_count > tree.vertices.size())
      return "fragment " + std::to_string(i) + " has vertices out of range";
    if (tree.fragment_orientation[i] < -1 || tree.fragment_orientation[i] > 1)
      return "fragment " + std::to_string(i) + " has a bad orientation";
  }
  if (nn == 0 ? tree.root != -1 : tree.root != 0) return "bad root";
  // The message is made only for the node that breaks a rule: a loaded tree may have millions.
  const auto bad = [](size_t i, const char* what) { return "node " + std::to_string(i) + ": " + what; };
  std::vector<uint8_t> covered(nf, 0);
  uint64_t listed = 0;
  for (size_t i = 0; i < nn; ++i) {
    const BspNode& n = tree.nodes[i];
    const auto idx = static_cast<int32_t>(i);
    if (i == 0 ? n.parent != -1 : (n.parent < 0 || n.parent >= idx)) return bad(i, "bad parent");
    if (i > 0) {
      const BspNode& p = tree.nodes[static_cast<size_t>(n.parent)];
      if (p.front != idx && p.back != idx) return bad(i, "parent does not link to it");
      if (n.depth != p.depth + 1) return bad(i, "bad depth");
    } else if (n.depth != 1) {
      return bad(i, "bad depth");
    }
    for (int32_t c : {n.front, n.back})
      if (c != -1 && (c <= idx || static_cast<uint64_t>(c) >= nn || tree.nodes[static_cast<size_t>(c)].parent != idx))
        return bad(i, "bad child");
    if (n.front != -1 && n.front == n.back) return bad(i, "bad child");
    // Only a separator (a plane between detail groups, bsp.h) holds no fragment.
    if ((n.fragment_count == 0) != (n.polygon == kSeparatorPolygon) ||
        static_cast<uint64_t>(n.first_fragment) + n.fragment_count > nf)
      return bad(i, "fragments out of range");
    for (uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f) {
      if (covered[f]) return bad(i, "fragment listed twice");
      covered[f] = 1;
      const Plane& q = tree.fragments[f].plane;
      const int8_t o = q.n == n.plane.n && q.d == n.plane.d ? 1 : q.n == -n.plane.n && q.d == -n.plane.d ? -1 : 0;
      if (tree.fragment_orientation[f] != o) return "fragment " + std::to_string(f) + " has a bad orientation";
    }
    listed += n.fragment_count;
  }
  if (listed != nf) return "fragments not covered by nodes";
  if (tree.stats.nodes != nn || tree.stats.fragments != nf) return "statistics do not match the arrays";
  return {};
}

}  // namespace detail

BspTree buildBsp(const Scene& scene, const BspOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(scene);
  BspTree tree;
  const DetailGroups detail = detailGroups(scene, options.detail_extent);
  tree.stats.exact_fallbacks = detail::buildBspExact(scene, options, detail, tree);
  tree.scene_hash = sceneHash(scene);
  computeStats(tree, scene.polygons.size());
  WALKVIS_DCHECK(detail::bspStructureProblem(tree).empty());
  tree.stats.detail_objects = detail.objects;
  tree.stats.detail_groups = detail.groups;
  tree.stats.detail_polygons = detail.polygons;
  for (uint32_t p : tree.fragment_polygon)
    tree.stats.structure_fragments += detail.group.empty() || detail.group[p] == kStructureGroup;
  tree.stats.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tree;
}

int planeSide(const Plane& plane, const glm::dvec3& p) {
  return exact::planeSign(plane.n.x, plane.n.y, plane.n.z, plane.d, p.x, p.y, p.z);
}

int sideOfPlane(const BspTree& tree, uint32_t fragment, const glm::dvec3& point) {
  return planeSide(tree.fragments[fragment].plane, point);
}

void backToFront(const BspTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order, bool skip_back_faces) {
  traverse(tree, eye, order, skip_back_faces, true);
}

void frontToBack(const BspTree& tree, const glm::dvec3& eye, std::vector<uint32_t>& order, bool skip_back_faces) {
  traverse(tree, eye, order, skip_back_faces, false);
}

uint64_t sceneHash(const Scene& scene) {
  // FNV-1a over the bytes of every polygon's vertices, plane and face id.
  uint64_t h = kFnvOffset;
  auto mix = [&h](const void* data, size_t size) { h = fnv1a(data, size, h); };
  auto mixDouble = [&mix](double v) { mix(&v, sizeof v); };
  const uint64_t count = scene.polygons.size();
  mix(&count, sizeof count);
  for (const Polygon& p : scene.polygons) {
    mix(&p.face_id, sizeof p.face_id);
    mix(&p.vertex_count, sizeof p.vertex_count);
    mixDouble(p.plane.n.x);
    mixDouble(p.plane.n.y);
    mixDouble(p.plane.n.z);
    mixDouble(p.plane.d);
    for (const glm::dvec3& v : scene.polygonVertices(p)) {
      mixDouble(v.x);
      mixDouble(v.y);
      mixDouble(v.z);
    }
  }
  return h;
}

void checkBspMatchesScene(const BspTree& tree, const Scene& scene, const std::string& context) {
  if (tree.scene_hash != sceneHash(scene))
    throw Error(context + ": BSP tree was built from another scene than " + scene.name);
  if (tree.stats.input_polygons != scene.polygons.size())
    throw Error(context + ": BSP tree was built from " + std::to_string(tree.stats.input_polygons) +
                     " polygons, " + scene.name + " has " + std::to_string(scene.polygons.size()));
}

}  // namespace walkvis
