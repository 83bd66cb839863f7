// The exact regions of the PFD and HFD builds (pfd_build_cgal.cpp): convex pieces of the height
// plane with exact rational corners (CGAL's lazy exact numbers), the test-lines BSP planes make on
// the height plane, and what the builder asks of them: the side of a line a region lies on, clips
// by a line, areas, and the slivers rounded plane coefficients cut off. A corner that lies on a
// line counts as touching it, not crossing it; a double filter with a forward error bound decides
// almost every corner sign, only the rest are evaluated exactly (docs/DESIGN.md, "Numerics").
// Pieces are clipped by lines as Sutherland & Hodgman clip polygons [SutherlandHodgman1974]; the
// exact numbers are CGAL's [CGAL] (docs/REFERENCES.md).
// Internal to pfd_hfd: it includes CGAL, so only *_cgal.cpp files include it.
#pragma once

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "bsp/bsp.h"
#include "pfd_hfd/pfd.h"

namespace walkvis::pfd_exact {

using FT = CGAL::Exact_predicates_exact_constructions_kernel::FT;

struct Corner {
  FT x, z;
  double ax = 0.0, az = 0.0;  // double approximations: |x − ax| <= rx, |z − az| <= rz
  double rx = 0.0, rz = 0.0;
  // Canonical ids of up to two lines the corner lies on exactly (it was made as their
  // intersection): its sign against them is 0 without arithmetic. kNoLine where unknown.
  uint32_t on[2] = {UINT32_MAX, UINT32_MAX};
};

constexpr uint32_t kNoLine = UINT32_MAX;

struct Piece {
  std::vector<Corner> corners;
  std::vector<uint32_t> edge_line;  // canonical line of the edge corners[i] -> corners[i + 1], or kNoLine
  double lox = 0.0, hix = 0.0, loz = 0.0, hiz = 0.0;  // contains every corner exactly
};

using Region = std::vector<Piece>;

// The line a·x + b·z + c = 0 of the height plane; its sign at (x, z) is the sign of the plane
// n·(x, h, z) − d, so that it agrees exactly with planeSide at the eye (x, h, z).
struct Line {
  double a = 0.0, b = 0.0;
  double c = 0.0;     // double approximation of the exact c
  double cmag = 0.0;  // bounds the magnitude of the terms that make c
  FT ec;              // exact c
  bool constant = false;  // a = b = 0: the sign is the sign of c everywhere
  int constant_side = 0;
  uint32_t canon = kNoLine;  // lines with the same plane (either orientation) share it
  Plane plane;               // for the exact sign at a corner that is an exact double point
  double h = 0.0;
};

// The corner at the exact point (x, z), with a double approximation and its radius (exact values
// computed once where the lazy interval is wide or unbounded).
Corner makeCorner(const FT& x, const FT& z);

// Sets p's box to contain every corner exactly (widened by the rounding of its own edges).
void updateBox(Piece& p);

// p's area from the corners' double approximations (a measure for heuristics and progress).
double pieceArea(const Piece& p);

// The line a plane cuts from the height plane y = h.
Line planeLine(const Plane& plane, double h);

// x·a + z·b + c for the box line a·x + b·z + c (cell boundaries: exact doubles).
Line axisLine(double a, double b, double c);

struct Counters {
  uint64_t exact_fallbacks = 0;
  uint64_t touching = 0;
  uint64_t decisions = 0;
};

// The exact sign of l at corner k: the double filter first, then the exact evaluation
// (counted in counters.exact_fallbacks).
int cornerSign(const Line& l, const Corner& k, Counters& counters);

constexpr int kCross = 2;

// Slivers narrower than this × the region's extent are trimmed off regions (trimSlivers).
constexpr double kSliverTolerance = 1e-9;

// The largest coordinate magnitude of the pieces' boxes (at least 1): the scale of sliver_tol.
double regionExtent(std::span<const Piece> pieces);

// A distance `tol` in units of l's value (a·x + b·z + c): how far a sliver may reach past l.
inline double sliverReach(const Line& l, double tol) { return tol * std::hypot(l.a, l.b); }

// Which side of l the pieces lie on by less than `tol` only (a sliver cut off by rounded plane
// coefficients, trimSlivers): +1 front, -1 back; 0 for none, a real crossing, or a sliver on both.
// `crossing`: l is known to cross the pieces exactly, so a side whose corners all evaluate to 0 or
// less in doubles is a sliver too (narrower than the rounding: freedoom2 MAP29 level 12 tested
// such a line for a leaf of area 0 in double, 3 nodes of its 7).
int sliverSide(std::span<const Piece> pieces, const Line& l, double tol, bool crossing = false);

// +1: the region lies in the line's positive side (corners >= 0, some > 0); -1: negative side;
// 0: the line is constant zero (a horizontal plane through the height plane); kCross: corners
// strictly on both sides.
int classifyRegion(const Line& l, const Region& region, Counters& counters);

// Splits a piece by a line: the part with corners >= 0 and the part with corners <= 0; a part
// with no corner strictly on its side is dropped (it has no area).
void clipPiece(const Piece& p, const Line& l, Counters& counters, Region* front, Region* back);

// clipPiece for every piece of r.
void clipRegion(std::span<const Piece> r, const Line& l, Counters& counters, Region* front, Region* back);

// Area of the region on the positive side of the line, in doubles (a heuristic only).
double positiveArea(const Region& r, const Line& l);

inline bool finite2(const glm::dvec2& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// W's convex pieces clipped to the cell, with exact corners; zero-area pieces dropped.
Region makeRegion(std::span<const std::vector<glm::dvec2>> walkable, const std::optional<PfdBox>& cell,
                  Counters& counters);

// Trims off W the slivers that BSP lines cut from it. A wall's line should pass through the
// corners of W it was made from, but the plane's coefficients are rounded doubles, so a diagonal
// wall's line passes a hair beside them and exactly crosses W in a sliver of no visible width.
// Every such line would then be tested (at the cost of every eye of the region it is tested in)
// for a leaf of no area. A piece that a line leaves less than `tol` on one side of is clipped to
// the other side, exactly (so the line then touches it); eyes closer than tol to a wall's plane
// leave W. tol = 1e-9 × the region's extent: far above the rounding (a few ulps of the
// coordinates, ~1e-16 relative) and far below any distance an eye keeps from a wall.
void trimSlivers(Region& region, const BspTree& bsp, double height, const std::vector<uint8_t>& objects,
                 Counters& counters);

}  // namespace walkvis::pfd_exact
