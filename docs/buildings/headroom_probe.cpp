// Probes a model's geometry along vertical lines, independently of walkvis's navmesh: what
// docs/buildings/README.md says of FZK-Haus's spiral stair and attic comes from it.
//   g++ -O2 docs/buildings/headroom_probe.cpp -o /tmp/headroom_probe -lassimp
//   /tmp/headroom_probe MODEL column X Z [X Z ...]   every face a vertical line crosses, by node
//   /tmp/headroom_probe MODEL area FLOOR_Y           floor at FLOOR_Y and how much of it has a
//                                                    given headroom (5 cm columns)
// Coordinates as assimp gives them after its own import (FZK-Haus: y up, metres).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

namespace {

struct Triangle {
  aiVector3D a, b, c;
  std::string node;
};

void collect(const aiScene* scene, const aiNode* node, aiMatrix4x4 m, std::vector<Triangle>& out) {
  m = m * node->mTransformation;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.push_back({m * mesh->mVertices[face.mIndices[0]], m * mesh->mVertices[face.mIndices[1]],
                     m * mesh->mVertices[face.mIndices[2]], node->mName.C_Str()});
    }
  }
  for (unsigned i = 0; i < node->mNumChildren; ++i) collect(scene, node->mChildren[i], m, out);
}

// The height at which the vertical line through (x, z) crosses t, if it does (edges included).
bool crossing(const Triangle& t, double x, double z, double& y) {
  const auto edge = [&](const aiVector3D& u, const aiVector3D& w) {
    return (w.x - u.x) * (z - u.z) - (w.z - u.z) * (x - u.x);
  };
  const double e0 = edge(t.a, t.b), e1 = edge(t.b, t.c), e2 = edge(t.c, t.a);
  if (!((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0))) return false;
  const double sum = e0 + e1 + e2;
  if (std::abs(sum) < 1e-12) return false;  // a vertical face: the line runs in its plane
  y = (e1 * t.a.y + e2 * t.b.y + e0 * t.c.y) / sum;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MODEL column X Z [X Z ...] | MODEL area FLOOR_Y\n", argv[0]);
    return 2;
  }
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(argv[1], aiProcess_Triangulate);
  if (!scene || !scene->mRootNode) {
    std::fprintf(stderr, "%s: %s\n", argv[1], importer.GetErrorString());
    return 2;
  }
  std::vector<Triangle> tris;
  collect(scene, scene->mRootNode, aiMatrix4x4(), tris);

  if (std::strcmp(argv[2], "column") == 0) {
    for (int i = 3; i + 1 < argc; i += 2) {
      const double x = std::atof(argv[i]), z = std::atof(argv[i + 1]);
      std::vector<std::pair<double, std::string>> hits;
      double y;
      for (const Triangle& t : tris)
        if (crossing(t, x, z, y)) hits.emplace_back(y, t.node);
      std::sort(hits.begin(), hits.end());
      std::printf("(%.3f, %.3f):", x, z);
      double last = -1e300;
      for (const auto& [hy, name] : hits) {
        if (hy - last > 1e-3) std::printf(" %.3f [%s]", hy, name.c_str());  // one line per surface
        last = hy;
      }
      std::printf("\n");
    }
    return 0;
  }
  if (std::strcmp(argv[2], "area") != 0) {
    std::fprintf(stderr, "%s: unknown probe '%s' (column, area)\n", argv[0], argv[2]);
    return 2;
  }
  const double floor_y = std::atof(argv[3]);
  constexpr double kGrid = 0.05;
  constexpr double kOnFloor = 0.005;  // a surface within 5 mm of FLOOR_Y is that floor
  constexpr double kHeadrooms[] = {2.04, 1.9, 1.82, 1.7};
  aiVector3D lo(1e30f), hi(-1e30f);
  for (const Triangle& t : tris)
    for (const aiVector3D& v : {t.a, t.b, t.c}) {
      lo.x = std::min(lo.x, v.x), lo.z = std::min(lo.z, v.z);
      hi.x = std::max(hi.x, v.x), hi.z = std::max(hi.z, v.z);
    }
  const int nx = static_cast<int>((hi.x - lo.x) / kGrid), nz = static_cast<int>((hi.z - lo.z) / kGrid);
  std::vector<std::vector<double>> columns(static_cast<size_t>(nx) * nz);
  for (const Triangle& t : tris) {
    const double x0 = std::min({t.a.x, t.b.x, t.c.x}), x1 = std::max({t.a.x, t.b.x, t.c.x});
    const double z0 = std::min({t.a.z, t.b.z, t.c.z}), z1 = std::max({t.a.z, t.b.z, t.c.z});
    for (int i = std::max(0, static_cast<int>((x0 - lo.x) / kGrid) - 1); i < nx && lo.x + i * kGrid <= x1; ++i)
      for (int j = std::max(0, static_cast<int>((z0 - lo.z) / kGrid) - 1); j < nz && lo.z + j * kGrid <= z1; ++j) {
        double y;
        if (crossing(t, lo.x + (i + 0.5) * kGrid, lo.z + (j + 0.5) * kGrid, y)) columns[i * nz + j].push_back(y);
      }
  }
  double floor_area = 0.0, area[std::size(kHeadrooms)] = {};
  for (auto& column : columns) {
    std::sort(column.begin(), column.end());
    const auto on = std::find_if(column.begin(), column.end(), [&](double y) { return std::abs(y - floor_y) < kOnFloor; });
    if (on == column.end()) continue;
    const auto above = std::find_if(on, column.end(), [&](double y) { return y > floor_y + kOnFloor; });
    const double clear = above == column.end() ? 1e300 : *above - floor_y;
    floor_area += kGrid * kGrid;
    for (size_t h = 0; h < std::size(kHeadrooms); ++h)
      if (clear >= kHeadrooms[h]) area[h] += kGrid * kGrid;
  }
  std::printf("floor at %.3f: %.2f m2", floor_y, floor_area);
  for (size_t h = 0; h < std::size(kHeadrooms); ++h) std::printf("; headroom >= %.2f m: %.2f m2", kHeadrooms[h], area[h]);
  std::printf("\n");
  return 0;
}
