// Exact sign of a·x + b·y + c·z − d for double inputs, read as exact rationals, without CGAL
// headers (it runs in the per-frame traversal).
//
// Method: a forward error bound decides almost every call in double arithmetic. Only a result
// inside the bound goes on to an exact evaluation with floating-point expansions (Shewchuk,
// "Adaptive precision floating-point arithmetic and fast robust geometric predicates", DCG 1997
// [Shewchuk1997]):
// each product becomes an exact sum of two doubles (fma), the seven terms are summed exactly by
// Grow-Expansion, and the sign is the sign of the largest nonzero component. Those steps are exact
// unless a product comes near underflow or a term near overflow; only then does it call rational
// arithmetic (planeSignRational, CGAL's exact rationals in bsp_exact_cgal.cpp).
// Cost: about 10 flops when the filter decides, about 150 in the expansion path, microseconds
// in the rational path (never reached by coordinates between 1e-280 and 1e280).
#pragma once

#include <cfloat>
#include <cmath>

namespace walkvis::exact {

// Exact rationals; in bsp_exact_cgal.cpp. Returns 0 when an input is not finite.
int planeSignRational(double a, double b, double c, double d, double x, double y, double z);

inline void twoSum(double a, double b, double& s, double& err) {
  s = a + b;
  const double bv = s - a;
  const double av = s - bv;
  err = (a - av) + (b - bv);
}

// Exact sign without the filter. Returns 0 when an input is not finite.
inline int planeSignExact(double a, double b, double c, double d, double x, double y, double z) {
  if (!(std::isfinite(a) && std::isfinite(b) && std::isfinite(c) && std::isfinite(d) && std::isfinite(x) &&
        std::isfinite(y) && std::isfinite(z)))
    return 0;
  // Below 2^-960 the error term of a product could fall into the subnormals and lose bits;
  // above 2^1000 a sum of seven terms could overflow. Both are far outside any scene's range.
  constexpr double kTiny = 0x1p-960, kHuge = 0x1p1000;
  const double f[3] = {a, b, c}, g[3] = {x, y, z};
  double terms[7];
  for (int i = 0; i < 3; ++i) {
    const double p = f[i] * g[i];
    if ((p == 0.0 && f[i] != 0.0 && g[i] != 0.0) || (p != 0.0 && std::abs(p) < kTiny) || std::abs(p) > kHuge)
      return planeSignRational(a, b, c, d, x, y, z);
    terms[2 * i] = p;
    terms[2 * i + 1] = std::fma(f[i], g[i], -p);
  }
  if (std::abs(d) > kHuge) return planeSignRational(a, b, c, d, x, y, z);
  terms[6] = -d;
  double e[8];
  int n = 0;
  for (double t : terms) {
    double q = t;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      double s, err;
      twoSum(q, e[i], s, err);
      if (err != 0.0) e[m++] = err;
      q = s;
    }
    e[m++] = q;
    n = m;
  }
  for (int i = n - 1; i >= 0; --i)
    if (e[i] != 0.0) return e[i] > 0.0 ? 1 : -1;
  return 0;
}

// Exact sign of a·x + b·y + c·z − d.
inline int planeSign(double a, double b, double c, double d, double x, double y, double z) {
  const double v = a * x + b * y + c * z - d;
  const double mag = std::abs(a * x) + std::abs(b * y) + std::abs(c * z) + std::abs(d);
  // The evaluation of v has error at most γ4·mag (4 roundings on any term's path, γ4 < 4.5e-16)
  // plus subnormal losses far below 1e-300; 16·DBL_EPSILON·mag also covers mag's own rounding.
  const double bound = 16.0 * DBL_EPSILON * mag + 1e-300;
  if (v > bound) return 1;
  if (v < -bound) return -1;
  return planeSignExact(a, b, c, d, x, y, z);
}

}  // namespace walkvis::exact
