// libFuzzer target: the `gen:NAME?key=value&...` parser and generator parameter checks, through
// loadScene. The input is appended to "gen:" so no file is ever opened. Inputs that could ask for
// a big scene are skipped: every number must be at most 32 and no exponent is allowed, so
// the fuzzer spends its time on parsing and range checks, not on building large scenes.
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <string>

#include "scenes/scene.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

bool tiny(const std::string& s) {
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (std::isdigit(c)) {
      // A maximal run of digits, leading zeros ignored, must read at most 32.
      size_t j = i;
      while (j < s.size() && s[j] == '0') ++j;
      size_t k = j;
      while (k < s.size() && std::isdigit(static_cast<unsigned char>(s[k]))) ++k;
      if (k - j > 2 || (k > j && std::stoi(s.substr(j, k - j)) > 32)) return false;
      i = k;
      continue;
    }
    // No exponents ("1e9") and no hexadecimal ("0x1p9").
    if ((c == 'e' || c == 'E' || c == 'p' || c == 'P') && i + 1 < s.size() &&
        (std::isdigit(static_cast<unsigned char>(s[i + 1])) || s[i + 1] == '+' || s[i + 1] == '-')) {
      return false;
    }
    if ((c == 'x' || c == 'X') && i > 0 && std::isdigit(static_cast<unsigned char>(s[i - 1]))) return false;
    ++i;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 256) return 0;
  const std::string spec = "gen:" + std::string(reinterpret_cast<const char*>(data), size);
  if (!tiny(spec)) return 0;
  try {
    const walkvis::Scene scene = walkvis::loadScene(spec);
    walkvis::checkSceneInvariants(scene);
  } catch (const walkvis::Error&) {
  }
  return 0;
}
