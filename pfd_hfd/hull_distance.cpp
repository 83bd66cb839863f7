// GJK distance iteration [GilbertJohnsonKeerthi1988] on the Minkowski difference a - b, with the
// sub-simplex search done by brute force over the (at most 15) faces of a tetrahedron instead of
// Johnson's case analysis: the sets are tiny, and the answer rests on a separating-plane
// certificate checked against every point, not on the iteration being exact.
#include "pfd_hfd/hull_distance.h"

#include <cassert>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace walkvis {
namespace {

struct Box3 {
  glm::dvec3 lo, hi;
};

Box3 boundsOf(std::span<const glm::dvec3> points) {
  Box3 box{points[0], points[0]};
  for (const auto& p : points) box.lo = glm::min(box.lo, p), box.hi = glm::max(box.hi, p);
  return box;
}

// True when an axis-aligned plane has all of box a on one side and all of b on the other, each at
// least `margin` from it: a certificate for whatever the boxes bound.
bool boxesSeparated(const Box3& a, const Box3& b, double margin) {
  for (int k = 0; k < 3; ++k)
    if (b.lo[k] - a.hi[k] > 2.0 * margin || a.lo[k] - b.hi[k] > 2.0 * margin) return true;
  return false;
}

// Solves the m x m system (m <= 3) in place by Gaussian elimination with partial pivoting; false
// when a pivot is negligible against the matrix's scale (a degenerate face, skipped by the caller).
bool solveSmall(double g[3][3], double r[3], int m) {
  double scale = 0.0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) scale = std::max(scale, std::abs(g[i][j]));
  if (!(scale > 0.0)) return false;
  for (int c = 0; c < m; ++c) {
    int p = c;
    for (int i = c + 1; i < m; ++i)
      if (std::abs(g[i][c]) > std::abs(g[p][c])) p = i;
    // 1e-12 of the scale: below that the face is flat to rounding and a lower face gives the point.
    if (!(std::abs(g[p][c]) > 1e-12 * scale)) return false;
    if (p != c) {
      for (int j = 0; j < m; ++j) std::swap(g[p][j], g[c][j]);
      std::swap(r[p], r[c]);
    }
    for (int i = c + 1; i < m; ++i) {
      const double f = g[i][c] / g[c][c];
      for (int j = c; j < m; ++j) g[i][j] -= f * g[c][j];
      r[i] -= f * r[c];
    }
  }
  for (int c = m - 1; c >= 0; --c) {
    for (int j = c + 1; j < m; ++j) r[c] -= g[c][j] * r[j];
    r[c] /= g[c][c];
  }
  return true;
}

// The point of the simplex s[0, n) nearest the origin; s is reduced to the vertices of the face
// that holds it.
glm::dvec3 nearestOnSimplex(glm::dvec3* s, int& n) {
  double best = std::numeric_limits<double>::infinity();
  int best_mask = 1;
  glm::dvec3 best_p = s[0];
  for (int mask = 1; mask < (1 << n); ++mask) {
    int idx[4], m = 0;
    for (int k = 0; k < n; ++k)
      if (mask >> k & 1) idx[m++] = k;
    glm::dvec3 p = s[idx[0]];
    if (m > 1) {
      // p = s0 + sum_j x_j (s_j - s0), with (s_i - s0) . p = 0 for every i.
      glm::dvec3 e[3];
      for (int j = 1; j < m; ++j) e[j - 1] = s[idx[j]] - s[idx[0]];
      double g[3][3], r[3];
      for (int i = 0; i < m - 1; ++i) {
        for (int j = 0; j < m - 1; ++j) g[i][j] = glm::dot(e[i], e[j]);
        r[i] = -glm::dot(e[i], s[idx[0]]);
      }
      if (!solveSmall(g, r, m - 1)) continue;
      double sum = 0.0;
      bool inside = true;
      for (int j = 0; j < m - 1; ++j) {
        inside = inside && r[j] >= 0.0;
        sum += r[j];
      }
      if (!inside || sum > 1.0) continue;
      for (int j = 0; j < m - 1; ++j) p += r[j] * e[j];
    }
    const double d = glm::dot(p, p);
    if (d < best) best = d, best_mask = mask, best_p = p;
  }
  int m = 0;
  for (int k = 0; k < n; ++k)
    if (best_mask >> k & 1) s[m++] = s[k];
  n = m;
  return best_p;
}

}  // namespace

bool hullsSeparated(std::span<const glm::dvec3> a, std::span<const glm::dvec3> b, double margin) {
  assert(!a.empty() && !b.empty());
  // An axis-aligned plane first: it settles most of the proof's queries (a patch edge against the
  // thin hull of one sub-cone) at a fraction of one GJK step.
  if (boxesSeparated(boundsOf(a), boundsOf(b), margin)) return true;
  glm::dvec3 simplex[4];
  int n = 0;
  glm::dvec3 v = a[0] - b[0];
  // Each step either certifies, meets the hulls, or brings v strictly nearer the origin; 64 is far
  // beyond what point sets of tens of points need (a handful), and the cap keeps a degenerate
  // configuration from looping.
  for (int iter = 0; iter < 64; ++iter) {
    const double vv = glm::dot(v, v);
    if (!(vv > 4.0 * margin * margin)) return false;
    // Support of a - b in the direction -v: the points of a lowest along v, of b highest.
    double lo_a = std::numeric_limits<double>::infinity(), hi_b = -lo_a;
    glm::dvec3 sa{0.0}, sb{0.0};
    for (const auto& p : a) {
      const double d = glm::dot(v, p);
      if (d < lo_a) lo_a = d, sa = p;
    }
    for (const auto& p : b) {
      const double d = glm::dot(v, p);
      if (d > hi_b) hi_b = d, sb = p;
    }
    // The certificate: the plane v . x = (lo_a + hi_b) / 2 has all of a above and all of b below,
    // each more than `margin` away.
    const double len = std::sqrt(vv);
    if (lo_a - hi_b > 2.0 * margin * len) return true;
    const glm::dvec3 w = sa - sb;
    // No progress (v is already the nearest point to rounding): the hulls are within the margin.
    if (vv - glm::dot(v, w) <= 1e-12 * vv) return false;
    for (int k = 0; k < n; ++k)
      if (simplex[k] == w) return false;
    simplex[n++] = w;
    v = nearestOnSimplex(simplex, n);
    if (n == 4) return false;  // the origin is inside the tetrahedron: the hulls meet
  }
  return false;
}

}  // namespace walkvis
