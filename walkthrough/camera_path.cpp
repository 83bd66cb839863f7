// Camera paths: view directions and the CSV format of recorded walks (camera_path.h).
#include "walkthrough/camera_path.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string_view>
#include <system_error>

#include "core/byte_io.h"

namespace walkvis {

glm::dvec3 viewDirection(double yaw, double pitch) {
  const double c = std::cos(pitch);
  return {-std::sin(yaw) * c, std::sin(pitch), -std::cos(yaw) * c};
}

namespace {

constexpr std::string_view kHeader = "time,x,y,z,yaw,pitch";
// A path line is six numbers; anything far longer is not a camera path (bounds what one bad line
// can make us hold).
constexpr size_t kMaxLineLength = 4096;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

}  // namespace

CameraPath loadCameraPath(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open camera path");
  CameraPath out;
  std::string line;
  uint64_t line_no = 0;
  bool header_seen = false;
  auto fail = [&](const std::string& what) -> Error {
    return Error(path + ":" + std::to_string(line_no) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (line.size() > kMaxLineLength) throw fail("line too long for a camera path");
    const std::string_view text = trim(line);
    if (!header_seen) {
      if (text != kHeader) throw fail("expected the header \"" + std::string(kHeader) + "\"");
      header_seen = true;
      continue;
    }
    if (text.empty()) continue;
    double v[6];
    std::string_view rest = text;
    for (int k = 0; k < 6; ++k) {
      const size_t comma = rest.find(',');
      if ((comma == std::string_view::npos) != (k == 5)) throw fail("expected 6 comma-separated numbers");
      const std::string_view field = trim(rest.substr(0, comma));
      const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), v[k]);
      if (ec != std::errc() || ptr != field.data() + field.size() || field.empty())
        throw fail("not a number: \"" + std::string(field) + "\"");
      if (!std::isfinite(v[k])) throw fail("not a finite number: \"" + std::string(field) + "\"");
      if (comma != std::string_view::npos) rest.remove_prefix(comma + 1);
    }
    CameraKey key{v[0], {v[1], v[2], v[3]}, v[4], v[5]};
    if (!out.keys.empty() && key.time < out.keys.back().time) throw fail("time goes back");
    if (!(std::abs(key.pitch) < std::numbers::pi / 2)) throw fail("|pitch| must be below pi/2");
    out.keys.push_back(key);
  }
  if (in.bad()) throw Error(path + ": read error");
  if (!header_seen) throw Error(path + ": empty file, expected the header \"" + std::string(kHeader) + "\"");
  if (out.keys.empty()) throw Error(path + ": no camera keys");
  return out;
}

void saveCameraPath(const CameraPath& path, const std::string& file) {
  std::string text = std::string(kHeader) + "\n";
  char line[192];  // six %.17g fields of at most 24 characters
  // %.17g round-trips every double, so a saved path loads back bit for bit.
  for (const CameraKey& k : path.keys) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", k.time, k.eye.x, k.eye.y, k.eye.z, k.yaw,
                  k.pitch);
    text += line;
  }
  writeTextFileAtomically(file, text, "camera path");
}

}  // namespace walkvis
