// generateScene: the name of a `gen:NAME?...` scene argument to its generator (generators.h).
#include <string>

#include "scenes/generators.h"

namespace walkvis {

Scene generateScene(const std::string& name, GeneratorParams& params) {
  if (name == "office") return generateOffice(params);
  if (name == "campus") return generateCampus(params);
  if (name == "ninefacet") return generateNineFacet(params);
  if (name == "sphere") return generateSphere(params);
  if (name == "dome") return generateDome(params);
  if (name == "table_room") return generateTableRoom(params);
  if (name == "house") return generateHouse(params);
  if (name == "ramp") return generateRamp(params);
  if (name.rfind("hard:", 0) == 0) return generateHardCase(name, params);
  std::string known = "office, campus, ninefacet, sphere, dome, table_room, house, ramp";
  for (const auto& n : hardCaseNames()) known += ", " + n;
  throw Error("gen:" + name + ": unknown generator (known: " + known + ")");
}

}  // namespace walkvis
