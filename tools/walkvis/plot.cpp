#include "plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "walkthrough/validate.h"

namespace walkvis {
namespace {

// 5 x 7 bitmap glyphs, row by row: digits, '.', '-', 'e', 'm', 'n', 's'; anything else is blank.
const char* glyph(char c) {
  static const char* digits[10] = {
      "01110100011001110101110011000101110", "00100011000010000100001000010001110",
      "01110100010000100010001000100011111", "11111000100010000010000011000101110",
      "00010001100101010010111110001000010", "11111100001111000001000011000101110",
      "00110010001000011110100011000101110", "11111000010001000100010000100001000",
      "01110100011000101110100011000101110", "01110100011000101111000010001001100"};
  if (c >= '0' && c <= '9') return digits[c - '0'];
  switch (c) {
    case '.': return "00000000000000000000000000110001100";
    case '-': return "00000000000000011111000000000000000";
    case 'e': return "00000000000111010001111111000001110";
    case 'm': return "00000000001101010101101011000110001";
    case 'n': return "00000000001011011001100011000110001";
    case 's': return "00000000000111110000011100000111110";
    default: return "00000000000000000000000000000000000";
  }
}

// Where value v falls along an axis drawn from pixel `from` (the axis's lo) to pixel `to` (its hi).
int axisPixel(const PlotAxis& a, double v, int from, int to) {
  double t;
  if (a.log10) {
    const double l = std::clamp(v > 0.0 ? std::log10(v) : a.lo, a.lo, a.hi);
    t = (l - a.lo) / (a.hi - a.lo);
  } else {
    t = (std::clamp(v, a.lo, a.hi) - a.lo) / (a.hi - a.lo);
  }
  return static_cast<int>(from + t * (to - from));
}

// The ticks of an axis: (fraction along it, label).
std::vector<std::pair<double, std::string>> ticks(const PlotAxis& a) {
  std::vector<std::pair<double, std::string>> out;
  if (a.log10) {
    const int decades = static_cast<int>(std::lround(a.hi - a.lo));
    for (int k = 0; k <= decades; ++k)
      out.push_back({static_cast<double>(k) / (a.hi - a.lo), "1e" + std::to_string(static_cast<int>(a.lo) + k)});
  } else {
    for (int k = 0; k <= 4; ++k) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.3g", a.lo + (a.hi - a.lo) * k / 4.0);
      out.push_back({k / 4.0, buf});
    }
  }
  return out;
}

}  // namespace

Canvas::Canvas(int width, int height) : w(width), h(height), rgb(static_cast<size_t>(width) * height * 3, 255) {}

void Canvas::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= w || y >= h) return;
  std::copy(c.begin(), c.end(), rgb.begin() + (static_cast<size_t>(y) * w + x) * 3);
}

void Canvas::text(int x, int y, const std::string& s, Rgb c) {
  for (char ch : s) {
    const char* g = glyph(ch);
    for (int r = 0; r < 7; ++r)
      for (int k = 0; k < 5; ++k)
        if (g[r * 5 + k] == '1') set(x + k, y + r, c);
    x += 6;
  }
}

void Canvas::write(const std::string& path) const { writePngRgb(path, w, h, rgb); }

void drawPanel(Canvas& cv, std::span<const PlotPoint> points, int x0, int x1, int y_top, int y_bottom,
               const PlotAxis& x, const PlotAxis& y) {
  for (int px = x0; px <= x1; ++px) cv.set(px, y_bottom, {0, 0, 0});
  for (int py = y_top; py <= y_bottom; ++py) cv.set(x0, py, {0, 0, 0});
  for (const auto& [t, label] : ticks(y)) {
    const int py = static_cast<int>(y_bottom - t * (y_bottom - y_top));
    for (int px = x0 - 4; px < x0; ++px) cv.set(px, py, {0, 0, 0});
    for (int px = x0 + 1; px <= x1; px += 4) cv.set(px, py, {200, 200, 200});
    cv.text(x0 - 40, py - 3, label);
  }
  for (const auto& [t, label] : ticks(x)) {
    const int px = static_cast<int>(x0 + t * (x1 - x0));
    for (int py = y_bottom; py < y_bottom + 4; ++py) cv.set(px, py, {0, 0, 0});
    cv.text(px - 10, y_bottom + 8, label);
  }
  if (!x.unit.empty()) cv.text(x1 - 30, y_bottom + 24, x.unit);
  for (const PlotPoint& p : points) {
    const int px = axisPixel(x, p.x, x0, x1);
    const int py = axisPixel(y, p.y, y_bottom, y_top);
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) cv.set(px + dx, py + dy, p.colour);
    cv.text(px + 4, py - 10, p.label, p.colour);
  }
}

void writeScatterPlot(const std::string& path, std::span<const PlotPoint> points, const std::string& x_unit,
                      const PlotAxis& y) {
  double xmax = 0.0;
  for (const PlotPoint& q : points) xmax = std::max(xmax, q.x);
  Canvas cv(640, 440);
  drawPanel(cv, points, 60, 620, 20, 400, PlotAxis{0.0, xmax > 0.0 ? xmax * 1.1 : 1.0, false, x_unit}, y);
  cv.write(path);
}

void writeBarChart(const std::string& path, std::span<const double> values, uint32_t rgb) {
  constexpr int kW = 280, kH = 120, kPad = 8;
  Canvas cv(kW, kH);
  const Rgb bar{static_cast<uint8_t>(rgb >> 16), static_cast<uint8_t>(rgb >> 8), static_cast<uint8_t>(rgb)};
  const double top = values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
  const int n = std::max<int>(1, static_cast<int>(values.size()));
  const int slot = (kW - 2 * kPad) / n;
  for (int i = 0; i < static_cast<int>(values.size()); ++i) {
    const int bh = top > 0.0 ? static_cast<int>(std::lround((kH - 2 * kPad) * values[i] / top)) : 0;
    for (int px = kPad + i * slot + 2; px < kPad + (i + 1) * slot - 2; ++px)
      for (int py = kH - kPad - bh; py < kH - kPad; ++py) cv.set(px, py, bar);
  }
  for (int px = kPad; px < kW - kPad; ++px) cv.set(px, kH - kPad, {0x40, 0x40, 0x40});
  cv.write(path);
}

}  // namespace walkvis
