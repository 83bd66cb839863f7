// The automatic tour (camera_path.h): a random walk of straight legs between walkable points, each
// leg checked by the walking physics (movement.h) before it is taken, so the tour steps up stairs,
// switches levels and never passes through a wall, exactly as a person in the window would.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include <glm/geometric.hpp>

#include "walkthrough/camera_path.h"
#include "walkthrough/movement.h"

namespace walkvis {

namespace {

constexpr double kSpeedEyeHeights = 2.0;         // walking speed: 2 eye heights per second (3.4 m/s, 82 Doom units/s)
constexpr double kTurnRate = std::numbers::pi;   // radians per second
constexpr double kWalkWhileTurning = 0.5;        // walk only once the view is within this (radians) of the leg
constexpr int kCandidates = 64;                  // random targets tried per leg
constexpr double kArrived = 1e-6;                // within this many steps of the target counts as there (rounding)
constexpr double kMinLegEyeHeights = 4.0;        // a leg shorter than this is taken only when nothing longer is

double wrapAngle(double a) {
  a = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
  if (a < 0.0) a += 2.0 * std::numbers::pi;
  return a - std::numbers::pi;
}

// The yaw looking along (dx, dz) (camera_path.h: yaw 0 looks along −z, positive towards −x).
double yawOf(double dx, double dz) { return std::atan2(-dx, -dz); }

glm::dvec2 stepTowards(const glm::dvec3& eye, const glm::dvec2& target, double step) {
  const glm::dvec2 d{target.x - eye.x, target.y - eye.z};
  const double len = std::hypot(d.x, d.y);
  return len <= step ? d : d * (step / len);
}

// Walks the leg as the tour will; true when the walker reaches the target.
bool legWalkable(const Walker& walker, WalkState s, const glm::dvec2& target, double step) {
  const double len = std::hypot(target.x - s.eye.x, target.y - s.eye.z);
  const int steps = static_cast<int>(std::ceil(len / step)) + 1;
  for (int k = 0; k < steps; ++k) {
    const glm::dvec2 d = stepTowards(s.eye, target, step);
    if (std::hypot(d.x, d.y) <= kArrived * step) return true;
    const auto next = walker.tryMove(s, d);
    if (!next) return false;
    s = *next;
  }
  return std::hypot(target.x - s.eye.x, target.y - s.eye.z) <= kArrived * step;
}

}  // namespace

CameraPath automaticTour(const Scene& scene, const BspTree& bsp, uint32_t frames, double fps, uint64_t seed) {
  CameraPath path;
  if (frames == 0 || scene.levels.empty() || !(fps > 0.0)) return path;
  const Walker walker(scene, bsp);
  uint64_t rng = seed;  // core/rng.h state
  WalkState state = walker.place(scene.start_eye);
  if (state.level < 0) {
    // The start eye is not over a floor: begin at a random walkable point instead.
    const auto p = walker.randomWalkablePoint(rng);
    if (!p) return path;
    state = {{p->first.x, scene.levels[p->second].floor_y + scene.eye_height, p->first.y}, static_cast<int>(p->second)};
  }
  const double step = kSpeedEyeHeights * scene.eye_height / fps;
  const double turn = kTurnRate / fps;
  double yaw = scene.start_yaw;
  std::optional<glm::dvec2> target;
  path.keys.reserve(frames);
  for (uint32_t frame = 0; frame < frames; ++frame) {
    path.keys.push_back({frame / fps, state.eye, yaw, 0.0});
    if (!target) {
      std::optional<glm::dvec2> best;
      double best_len = 0.0;
      for (int c = 0; c < kCandidates; ++c) {
        const auto p = walker.randomWalkablePoint(rng);
        if (!p) break;
        const double len = std::hypot(p->first.x - state.eye.x, p->first.y - state.eye.z);
        if (len <= best_len || len < step) continue;
        // The straight line at eye height first (cheap), then the walk itself (stairs, floors).
        const glm::dvec3 end{p->first.x, state.eye.y, p->first.y};
        if (!walker.segmentClear(state.eye, end, walker.radius())) continue;
        if (!legWalkable(walker, state, p->first, step)) continue;
        best = p->first, best_len = len;
        if (len >= kMinLegEyeHeights * scene.eye_height) break;
      }
      target = best;
      if (!target) {
        yaw = wrapAngle(yaw + turn);  // nowhere to go from here: look around
        continue;
      }
    }
    const glm::dvec2 d = stepTowards(state.eye, *target, step);
    if (std::hypot(d.x, d.y) <= kArrived * step) {
      target.reset();
      continue;
    }
    const double diff = wrapAngle(yawOf(d.x, d.y) - yaw);
    yaw = wrapAngle(yaw + std::clamp(diff, -turn, turn));
    if (std::abs(diff) > kWalkWhileTurning) continue;
    const auto next = walker.tryMove(state, d);
    if (!next) {
      target.reset();
      continue;
    }
    state = *next;
    if (std::hypot(target->x - state.eye.x, target->y - state.eye.z) <= kArrived * step) target.reset();
  }
  return path;
}

}  // namespace walkvis
