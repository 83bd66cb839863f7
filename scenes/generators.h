// Seeded, deterministic scene generators: `gen:NAME?key=value&key=value`.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "scenes/scene.h"

namespace walkvis {

// Generator parameters from the query string. Every get* names the key it reads; a key given but
// never read, an unparsable value or one outside [lo, hi] is a Error naming the generator.
class GeneratorParams {
 public:
  GeneratorParams(std::string generator, std::map<std::string, std::string> values);
  int64_t getInt(const std::string& key, int64_t fallback, int64_t lo, int64_t hi);
  double getDouble(const std::string& key, double fallback, double lo, double hi);
  uint64_t seed() { return static_cast<uint64_t>(getInt("seed", 1, 0, INT64_MAX)); }
  void checkAllUsed() const;  // throws for keys no getter asked for
  const std::string& generator() const { return generator_; }

 private:
  std::string generator_;
  std::map<std::string, std::string> values_;
  std::set<std::string> used_;
};

// Dispatches on the name: office, campus, ninefacet, sphere, dome, table_room, house, ramp, hard:<case>.
// Unknown names throw.
Scene generateScene(const std::string& name, GeneratorParams& params);

Scene generateOffice(GeneratorParams& params);     // gen_office.cpp
Scene generateCampus(GeneratorParams& params);     // gen_campus.cpp: several offices on one site
Scene generateNineFacet(GeneratorParams& params);  // gen_shapes.cpp
Scene generateSphere(GeneratorParams& params);     // gen_shapes.cpp
Scene generateDome(GeneratorParams& params);       // gen_shapes.cpp
// Buildings with their levels left empty for the navmesh (gen_buildings.cpp).
Scene generateTableRoom(GeneratorParams& params);
Scene generateHouse(GeneratorParams& params);
Scene generateRamp(GeneratorParams& params);
// The cases of docs/DESIGN.md, "Hard cases" (gen_hard.cpp); hardCaseNames() lists them for tests and docs.
Scene generateHardCase(const std::string& name, GeneratorParams& params);
std::vector<std::string> hardCaseNames();

}  // namespace walkvis
