// Exact regions of the height plane (pfd_region_cgal.h).
#include "pfd_hfd/pfd_region_cgal.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "bsp/exact_sign.h"

namespace walkvis::pfd_exact {

Corner makeCorner(const FT& x, const FT& z) {
  Corner k{x, z};
  // A lazy exact number's interval can be unbounded where its construction divided by an interval
  // holding 0 (the intersection of two nearly parallel lines): its midpoint is then NaN, and boxes
  // built from it silently leave the corner out (freedoom2 MAP01 level 46: a piece decided to lie
  // on one side of a line it crosses, so a fragment was missing from the order). Computing the
  // exact value once makes the interval tight.
  // A finite but wide interval is as bad in another way: the signs stay right (they use the
  // radius), but the midpoint is what the tree stores as its region ring and what eyes are sampled
  // from, and FZK-Haus had corners 0.3 m from where they are (a ring with a spike, eyes outside W).
  // Wider than 1e-12 of the magnitude (a few thousand ulps: chains of clips stay far below it).
  auto loose = [](const std::pair<double, double>& i) {
    return !std::isfinite(i.first) || !std::isfinite(i.second) ||
           i.second - i.first > 1e-12 * std::max({1.0, std::abs(i.first), std::abs(i.second)});
  };
  auto ix = CGAL::to_interval(x);
  auto iz = CGAL::to_interval(z);
  if (loose(ix)) {
    x.exact();
    ix = CGAL::to_interval(x);
  }
  if (loose(iz)) {
    z.exact();
    iz = CGAL::to_interval(z);
  }
  k.ax = 0.5 * (ix.first + ix.second);
  k.az = 0.5 * (iz.first + iz.second);
  // The radius of the interval around the midpoint, rounded up by a relative 1e-15 (the
  // subtraction rounds at most half an ulp) plus the smallest subnormal.
  k.rx = std::max(ix.second - k.ax, k.ax - ix.first) * (1.0 + 1e-15) + 5e-324;
  k.rz = std::max(iz.second - k.az, k.az - iz.first) * (1.0 + 1e-15) + 5e-324;
  if (ix.first == ix.second) k.rx = 0.0;
  if (iz.first == iz.second) k.rz = 0.0;
  return k;
}

void updateBox(Piece& p) {
  p.lox = p.loz = HUGE_VAL;
  p.hix = p.hiz = -HUGE_VAL;
  for (const Corner& k : p.corners) {
    p.lox = std::min(p.lox, k.ax - k.rx);
    p.hix = std::max(p.hix, k.ax + k.rx);
    p.loz = std::min(p.loz, k.az - k.rz);
    p.hiz = std::max(p.hiz, k.az + k.rz);
  }
  // The box edges themselves were rounded: widen by a relative ulp.
  auto widen = [](double& lo, double& hi) {
    lo -= std::abs(lo) * 4.0 * DBL_EPSILON + 5e-324;
    hi += std::abs(hi) * 4.0 * DBL_EPSILON + 5e-324;
  };
  widen(p.lox, p.hix);
  widen(p.loz, p.hiz);
}

double pieceArea(const Piece& p) {
  double s = 0.0;
  const size_t n = p.corners.size();
  for (size_t i = 0; i < n; ++i) {
    const Corner& u = p.corners[i];
    const Corner& v = p.corners[(i + 1) % n];
    s += u.ax * v.az - v.ax * u.az;
  }
  return 0.5 * std::abs(s);
}

Line planeLine(const Plane& plane, double h) {
  Line l;
  l.a = plane.n.x;
  l.b = plane.n.z;
  l.c = plane.n.y * h - plane.d;
  l.cmag = std::abs(plane.n.y * h) + std::abs(plane.d);
  l.ec = FT(plane.n.y) * FT(h) - FT(plane.d);
  l.plane = plane;
  l.h = h;
  if (l.a == 0.0 && l.b == 0.0) {
    l.constant = true;
    // Exactly planeSide's answer at any eye of the height plane.
    l.constant_side = exact::planeSign(0.0, plane.n.y, 0.0, plane.d, 0.0, h, 0.0);
  }
  return l;
}

Line axisLine(double a, double b, double c) {
  Line l;
  l.a = a;
  l.b = b;
  l.c = c;
  l.cmag = std::abs(c);
  l.ec = FT(c);
  l.plane.n = glm::dvec3(a, 0.0, b);  // exact: the sign of a·x + b·z + c with y's term 0
  l.plane.d = -c;
  return l;
}

int cornerSign(const Line& l, const Corner& k, Counters& counters) {
  const double v = l.a * k.ax + l.b * k.az + l.c;
  const double mag = std::abs(l.a * k.ax) + std::abs(l.b * k.az) + l.cmag;
  // Rounding of the evaluation (5 operations: γ5·mag < 6e-16·mag, with c's own rounding), plus
  // how far the corner's approximation may be from the corner.
  const double bound = 16.0 * DBL_EPSILON * mag + (std::abs(l.a) * k.rx + std::abs(l.b) * k.rz) * (1.0 + 1e-14) + 1e-300;
  if (v > bound) return 1;
  if (v < -bound) return -1;
  if (l.canon != kNoLine && (k.on[0] == l.canon || k.on[1] == l.canon)) return 0;
  ++counters.exact_fallbacks;
  // An input corner is an exact double point: the expansion arithmetic of exact_sign.h is exact
  // there and much cheaper than the rational path.
  if (k.rx == 0.0 && k.rz == 0.0)  // a point interval: the corner is exactly (ax, az)
    return exact::planeSign(l.plane.n.x, l.plane.n.y, l.plane.n.z, l.plane.d, k.ax, l.h, k.az);
  return CGAL::sign(FT(l.a) * k.x + FT(l.b) * k.z + l.ec);
}

double regionExtent(std::span<const Piece> pieces) {
  double extent = 1.0;
  for (const Piece& p : pieces)
    extent = std::max({extent, std::abs(p.lox), std::abs(p.hix), std::abs(p.loz), std::abs(p.hiz)});
  return extent;
}

int sliverSide(std::span<const Piece> pieces, const Line& l, double tol, bool crossing) {
  if (l.constant) return 0;
  double hi = 0.0, lo = 0.0;
  for (const Piece& p : pieces) {
    for (const Corner& k : p.corners) {
      const double v = l.a * k.ax + l.b * k.az + l.c;
      hi = std::max(hi, v);
      lo = std::min(lo, v);
    }
  }
  const double reach = sliverReach(l, tol);
  const bool front = (hi > 0.0 || crossing) && hi < reach, back = (lo < 0.0 || crossing) && -lo < reach;
  return front == back ? 0 : front ? 1 : -1;
}

int classifyRegion(const Line& l, const Region& region, Counters& counters) {
  if (l.constant) return l.constant_side;
  bool pos = false, neg = false, touch = false;
  for (const Piece& p : region) {
    const double xmin = l.a > 0 ? p.lox : p.hix, xmax = l.a > 0 ? p.hix : p.lox;
    const double zmin = l.b > 0 ? p.loz : p.hiz, zmax = l.b > 0 ? p.hiz : p.loz;
    const double lo = l.a * xmin + l.b * zmin + l.c;
    const double hi = l.a * xmax + l.b * zmax + l.c;
    const double mag = std::abs(l.a) * std::max(std::abs(p.lox), std::abs(p.hix)) +
                       std::abs(l.b) * std::max(std::abs(p.loz), std::abs(p.hiz)) + l.cmag;
    const double bound = 16.0 * DBL_EPSILON * mag + 1e-300;  // rounding of the two evaluations
    if (lo > bound) {
      pos = true;
    } else if (hi < -bound) {
      neg = true;
    } else {
      for (const Corner& k : p.corners) {
        const int s = cornerSign(l, k, counters);
        pos |= s > 0;
        neg |= s < 0;
        touch |= s == 0;
      }
    }
    if (pos && neg) {
      ++counters.decisions;
      return kCross;
    }
  }
  ++counters.decisions;
  if (touch) ++counters.touching;
  return pos ? 1 : (neg ? -1 : 0);
}

void clipPiece(const Piece& p, const Line& l, Counters& counters, Region* front, Region* back) {
  const size_t n = p.corners.size();
  std::vector<int> s(n);
  bool pos = false, neg = false;
  for (size_t i = 0; i < n; ++i) {
    s[i] = cornerSign(l, p.corners[i], counters);
    pos |= s[i] > 0;
    neg |= s[i] < 0;
  }
  if (!neg) {
    if (pos && front) front->push_back(p);
    return;
  }
  if (!pos) {
    if (back) back->push_back(p);
    return;
  }
  // Sutherland–Hodgman for both sides. Per output corner: whether it lies on l, and the input
  // edge that arrives at it, to carry the edges' line tags over.
  Piece f, b;
  std::vector<uint8_t> f_on, b_on;
  std::vector<uint32_t> f_arrive, b_arrive;
  for (size_t i = 0; i < n; ++i) {
    const size_t j = (i + 1) % n;
    const Corner& u = p.corners[i];
    const Corner& v = p.corners[j];
    const uint32_t arrive_u = static_cast<uint32_t>((i + n - 1) % n);
    if (s[i] >= 0) {
      f.corners.push_back(u);
      f_on.push_back(s[i] == 0);
      f_arrive.push_back(arrive_u);
    }
    if (s[i] <= 0) {
      b.corners.push_back(u);
      b_on.push_back(s[i] == 0);
      b_arrive.push_back(arrive_u);
    }
    if (s[i] * s[j] < 0) {
      const FT fu = FT(l.a) * u.x + FT(l.b) * u.z + l.ec;
      const FT fv = FT(l.a) * v.x + FT(l.b) * v.z + l.ec;
      const FT t = fu / (fu - fv);
      Corner k = makeCorner(u.x + t * (v.x - u.x), u.z + t * (v.z - u.z));
      k.on[0] = l.canon;
      k.on[1] = p.edge_line[i];
      f.corners.push_back(k);
      b.corners.push_back(k);
      f_on.push_back(1);
      b_on.push_back(1);
      f_arrive.push_back(static_cast<uint32_t>(i));
      b_arrive.push_back(static_cast<uint32_t>(i));
    }
  }
  auto edges = [&](Piece& q, const std::vector<uint8_t>& on, const std::vector<uint32_t>& arrive) {
    const size_t m = q.corners.size();
    q.edge_line.resize(m);
    for (size_t k = 0; k < m; ++k) {
      const size_t next = (k + 1) % m;
      q.edge_line[k] = on[k] && on[next] ? l.canon : p.edge_line[arrive[next]];
    }
  };
  edges(f, f_on, f_arrive);
  edges(b, b_on, b_arrive);
  updateBox(f);
  updateBox(b);
  if (front) front->push_back(std::move(f));
  if (back) back->push_back(std::move(b));
}

void clipRegion(std::span<const Piece> r, const Line& l, Counters& counters, Region* front, Region* back) {
  for (const Piece& p : r) clipPiece(p, l, counters, front, back);
}

double positiveArea(const Region& r, const Line& l) {
  double total = 0.0;
  std::vector<double> xs, zs;
  for (const Piece& p : r) {
    xs.clear();
    zs.clear();
    const size_t n = p.corners.size();
    for (size_t i = 0; i < n; ++i) {
      const Corner& u = p.corners[i];
      const Corner& v = p.corners[(i + 1) % n];
      const double fu = l.a * u.ax + l.b * u.az + l.c;
      const double fv = l.a * v.ax + l.b * v.az + l.c;
      if (fu >= 0) {
        xs.push_back(u.ax);
        zs.push_back(u.az);
      }
      if ((fu > 0 && fv < 0) || (fu < 0 && fv > 0)) {
        const double t = fu / (fu - fv);
        xs.push_back(u.ax + t * (v.ax - u.ax));
        zs.push_back(u.az + t * (v.az - u.az));
      }
    }
    double s = 0.0;
    for (size_t i = 0; i < xs.size(); ++i) {
      const size_t j = (i + 1) % xs.size();
      s += xs[i] * zs[j] - xs[j] * zs[i];
    }
    total += 0.5 * std::abs(s);
  }
  return total;
}

Region makeRegion(std::span<const std::vector<glm::dvec2>> walkable, const std::optional<PfdBox>& cell,
                  Counters& counters) {
  if (cell && !(finite2(cell->lo) && finite2(cell->hi) && cell->lo.x < cell->hi.x && cell->lo.y < cell->hi.y))
    throw Error("pfd: view cell is not a finite box with lo < hi");
  Region region;
  for (const auto& ring : walkable) {
    Piece p;
    for (const glm::dvec2& v : ring) {
      if (!finite2(v)) throw Error("pfd: walkable region has a non-finite corner");
      // Consecutive duplicates would make zero-length edges: skip them.
      if (!p.corners.empty() && p.corners.back().ax == v.x && p.corners.back().az == v.y) continue;
      p.corners.push_back(makeCorner(FT(v.x), FT(v.y)));
    }
    while (p.corners.size() > 1 && p.corners.front().ax == p.corners.back().ax &&
           p.corners.front().az == p.corners.back().az)
      p.corners.pop_back();
    if (p.corners.size() < 3) continue;
    // Exactly zero area (all corners on one line): no eye can stand there.
    bool flat = true;
    for (size_t i = 2; i < p.corners.size() && flat; ++i) {
      const FT cross = (p.corners[1].x - p.corners[0].x) * (p.corners[i].z - p.corners[0].z) -
                       (p.corners[1].z - p.corners[0].z) * (p.corners[i].x - p.corners[0].x);
      flat = CGAL::is_zero(cross);
    }
    if (flat) continue;
    p.edge_line.assign(p.corners.size(), kNoLine);
    updateBox(p);
    region.push_back(std::move(p));
  }
  if (cell) {
    // Half-open boxes: x >= lo.x, x <= hi.x, ... (the boundary has no area, either is right).
    const Line edges[4] = {axisLine(1, 0, -cell->lo.x), axisLine(-1, 0, cell->hi.x), axisLine(0, 1, -cell->lo.y),
                           axisLine(0, -1, cell->hi.y)};
    for (const Line& l : edges) {
      Region clipped;
      clipRegion(region, l, counters, &clipped, nullptr);
      region = std::move(clipped);
    }
  }
  return region;
}

void trimSlivers(Region& region, const BspTree& bsp, double height, const std::vector<uint8_t>& objects,
                 Counters& counters) {
  const double tol = kSliverTolerance * regionExtent(region);
  Region front, back;
  for (size_t i = 0; i < bsp.nodes.size(); ++i) {
    if (objects[i] != 0) continue;  // never a test-line
    const Line l = planeLine(bsp.nodes[i].plane, height);
    if (l.constant) continue;
    const double reach = sliverReach(l, tol);
    for (Piece& p : region) {
      // Box filter: most lines pass far from most pieces.
      const double xmin = l.a > 0 ? p.lox : p.hix, xmax = l.a > 0 ? p.hix : p.lox;
      const double zmin = l.b > 0 ? p.loz : p.hiz, zmax = l.b > 0 ? p.hiz : p.loz;
      if (l.a * xmin + l.b * zmin + l.c > reach || l.a * xmax + l.b * zmax + l.c < -reach) continue;
      const int sliver = sliverSide(std::span<const Piece>(&p, 1), l, tol);
      if (sliver == 0) continue;
      front.clear();
      back.clear();
      clipRegion(std::span<const Piece>(&p, 1), l, counters, &front, &back);
      Region& keep = sliver > 0 ? back : front;
      if (keep.size() != 1) continue;  // exactly no crossing after all (or nothing left): leave it
      p = std::move(keep[0]);
    }
  }
}

}  // namespace walkvis::pfd_exact
