// Small PNG charts for the benchmarks and the report, drawn pixel by pixel with no font or plotting
// library: 5 × 7 glyphs for the numbers on the axes (digits, '.', '-', 'e', 'm', 'n', 's'; other characters
// are blank), points labelled with short numbers, and a bar chart whose page labels it.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace walkvis {

using Rgb = std::array<uint8_t, 3>;

struct Canvas {
  int w, h;
  std::vector<uint8_t> rgb;  // row 0 at the top, white to begin with
  Canvas(int width, int height);
  void set(int x, int y, Rgb c);  // outside the canvas: nothing
  void text(int x, int y, const std::string& s, Rgb c = {0, 0, 0});  // top-left corner at (x, y)
  void write(const std::string& path) const;  // PNG; Error naming the path when it cannot be written
};

// One axis of a panel: linear from lo to hi with five labelled ticks ("%.3g"), or log10, a tick
// and label "1eK" per decade, from 10^lo to 10^hi (values <= 0 are drawn at the floor).
struct PlotAxis {
  double lo = 0.0, hi = 1.0;
  bool log10 = false;
  std::string unit;  // printed at the end of the x axis (glyphs only)
};

struct PlotPoint {
  double x = 0.0, y = 0.0;
  Rgb colour{30, 30, 200};
  std::string label;  // beside the point
};

// A scatter panel with its axes, between x0..x1 and y_top..y_bottom on the canvas.
void drawPanel(Canvas& cv, std::span<const PlotPoint> points, int x0, int x1, int y_top, int y_bottom,
               const PlotAxis& x, const PlotAxis& y);

// One panel on a 640 × 440 canvas written to `path` (PNG): x from 0 to a tenth past the largest
// point's, in `x_unit`; y as given.
void writeScatterPlot(const std::string& path, std::span<const PlotPoint> points, const std::string& x_unit,
                      const PlotAxis& y);

// A bar chart without text: one bar per value, heights against the largest, 280 × 120 pixels.
void writeBarChart(const std::string& path, std::span<const double> values, uint32_t rgb);

}  // namespace walkvis
