// Separation of two convex hulls of small point sets, with a certificate (GJK: Gilbert, Johnson &
// Keerthi, "A fast procedure for computing the distance between complex objects in
// three-dimensional space", 1988 [GilbertJohnsonKeerthi1988]). Used by the HFD visibility proof
// (visibility.cpp) to show that an occluder patch's boundary stays clear of every eye-to-target
// segment.
#pragma once

#include <span>

#include <glm/vec3.hpp>

namespace walkvis {

// True only when a plane is found that has every point of `a` on one side and every point of `b`
// on the other, each at least `margin` from it (so the hulls are more than 2 * margin apart, and
// by the certificate's own arithmetic, not by the iteration's estimate). False when the hulls
// meet, come within that distance, or the iteration does not settle (a false answer is never
// wrong for the caller, which then proves nothing). Both spans non-empty; allocates nothing.
bool hullsSeparated(std::span<const glm::dvec3> a, std::span<const glm::dvec3> b, double margin);

}  // namespace walkvis
