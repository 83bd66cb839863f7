// Reading PNGs back in tests (the frames, screenshots and pages walkvis writes).
#pragma once

#include <png.h>

#include <cstdint>
#include <string>
#include <vector>

namespace walkvis {

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
};

// An 8-bit RGB image of any PNG libpng reads; empty image when it cannot be read.
inline Image readPng(const std::string& path) {
  Image img;
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) return img;
  png.format = PNG_FORMAT_RGB;
  img.width = static_cast<int>(png.width), img.height = static_cast<int>(png.height);
  img.rgb.resize(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, img.rgb.data(), 0, nullptr)) return {};
  return img;
}

}  // namespace walkvis
