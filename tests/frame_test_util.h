// Shared by the frame and mesh-object tests: an OSMesa context with a drawer on it, and the default
// office as a world with PFD trees built in memory (objects: auto, so the blob is in it).
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include "walkthrough/frame.h"
#include "walkthrough/osmesa_context.h"
#include "walkthrough/scene_drawer.h"

namespace walkvis {

constexpr int kW = 160, kH = 120;

struct Offscreen {
  OsMesaContext context;
  SceneDrawer drawer;
};

inline Offscreen makeOffscreen() {
  std::string why;
  auto context = OsMesaContext::create(kW, kH, 24, &why);
  if (!context) throw std::runtime_error("no OSMesa context: " + why);
  auto drawer = SceneDrawer::create(OsMesaContext::loader(), &why);
  if (!drawer) throw std::runtime_error("no drawer: " + why);
  return {std::move(*context), std::move(*drawer)};
}

inline const World& office() {
  static const World world = [] {
    WorldOptions options;
    options.build_pfd = true;
    options.cull = ListCullMethod::kRegion;
    return openWorld("gen:office", options);
  }();
  return world;
}

}  // namespace walkvis
