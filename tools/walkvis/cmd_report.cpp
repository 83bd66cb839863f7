// walkvis report SCENE|FILE -o DIR: one HTML page (DIR/index.html, PNGs beside it, nothing from
// the network) that a person reads instead of JSON. It runs walkvis' own commands (build, info,
// render, validate, stats, bench frames) as child processes of this binary, each writing JSON
// and images under DIR, then writes the page from what they wrote: the scene (a frame, a plan
// per level), build costs, validation (order errors, z-buffer errors per bit depth, diff images
// of the worst views), rejection statistics (listed / visible / missed per level, per-eye
// histograms), frame times per mode against the floor and the ideal, and for a scene the
// speed-against-error sweeps (HFD sampling, normal-mask cells, Johannsen-Carter T/R), each plotted
// (plot.h). A command that fails
// stops the report with its name and status; index.html is written last, through a temporary
// file, so a page that exists is complete.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "plot.h"
#include "core/byte_io.h"
#include "pfd_hfd/pfd.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

// The backface sweeps' points: normal-mask cells per cube-face side, and Johannsen-Carter T/R.
constexpr std::array<const char*, 6> kMaskCells = {"2", "4", "6", "8", "12", "16"};
constexpr std::array<const char*, 6> kClusterTr = {"0.1", "0.25", "0.5", "1", "2", "4"};

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct ReportArgs {
  std::string source;
  std::string scene;  // for a tree file: the scene it was built from
  std::string out;
  std::string tree = "hfd";  // for a scene: the tree built
  int views = 50;
  uint32_t frames = 60;
};

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string htmlEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '&') o += "&amp;";
    else if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '"') o += "&quot;";
    else o += c;
  }
  return o;
}

std::string fmt(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}
std::string sci(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.2e", v);
  return b;
}
std::string pct(double v) { return fmt(100.0 * v, 1) + "%"; }

// Runs the steps, numbered, with the time each took and an estimate of what is left.
class Steps {
 public:
  Steps(std::string self, fs::path dir, int total)
      : self_(std::move(self)), dir_(std::move(dir)), total_(total), t0_(std::chrono::steady_clock::now()) {}

  // `walkvis ARGS > DIR/json_name` (stdout kept when json_name is set), stderr appended to
  // DIR/report.log. Returns the parsed JSON (null without json_name). Exit statuses in `ok`
  // are accepted (validate exits 1 when it finds errors: that is a finding, not a failure).
  Json run(const std::string& what, const std::vector<std::string>& args, const std::string& json_name,
           std::vector<int> ok = {0}) {
    ++done_;
    const double elapsed = secondsSince(t0_);
    std::string eta;
    if (done_ > 1) eta = ", about " + fmt(elapsed / (done_ - 1) * (total_ - done_ + 1), 0) + " s to go";
    std::fprintf(stderr, "report: step %d/%d: %s (%.0f s so far%s)\n", done_, total_, what.c_str(), elapsed,
                 eta.c_str());
    std::string cmd = shellQuote(self_);
    for (const std::string& a : args) cmd += " " + shellQuote(a);
    cmd += json_name.empty() ? " > /dev/null" : " > " + shellQuote((dir_ / json_name).string());
    cmd += " 2>> " + shellQuote((dir_ / "report.log").string());
    const int status = std::system(cmd.c_str());
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    if (std::find(ok.begin(), ok.end(), code) == ok.end())
      throw Error("report: step '" + what + "' failed: " + lastLine(dir_ / "report.log") + " (walkvis " +
                  args.front() + " exited " + std::to_string(code) + ")");
    if (json_name.empty()) return Json();
    std::ifstream in(dir_ / json_name);
    Json j = Json::parse(in, nullptr, false);
    if (j.is_discarded()) throw Error("report: step '" + what + "' wrote no JSON to " + (dir_ / json_name).string());
    return j;
  }

 private:
  // The last line a child wrote to the log: its one-line error, naming the file and what is wrong.
  static std::string lastLine(const fs::path& log) {
    std::ifstream in(log);
    std::string line, last;
    while (std::getline(in, line))
      if (!line.empty()) last = line;
    return last.empty() ? "no message" : last;
  }
  static double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }
  std::string self_;
  fs::path dir_;
  int total_, done_ = 0;
  std::chrono::steady_clock::time_point t0_;
};

class Page {
 public:
  void h2(const std::string& t) { html_ << "<h2>" << htmlEscape(t) << "</h2>\n"; }
  void p(const std::string& t) { html_ << "<p>" << t << "</p>\n"; }
  void img(const std::string& src, const std::string& alt) {
    html_ << "<figure><img src=\"" << htmlEscape(src) << "\" alt=\"" << htmlEscape(alt) << "\"><figcaption>"
          << htmlEscape(alt) << "</figcaption></figure>\n";
  }
  // A small image that links to itself at full size (plans of many levels).
  void thumb(const std::string& src, const std::string& alt) {
    html_ << "<figure class=\"thumb\"><a href=\"" << htmlEscape(src) << "\"><img src=\"" << htmlEscape(src)
          << "\" alt=\"" << htmlEscape(alt) << "\"></a><figcaption>" << htmlEscape(alt) << "</figcaption></figure>\n";
  }
  void table(const std::vector<std::string>& head, const std::vector<std::vector<std::string>>& rows) {
    html_ << "<table><tr>";
    for (const auto& h : head) html_ << "<th>" << htmlEscape(h) << "</th>";
    html_ << "</tr>\n";
    for (const auto& r : rows) {
      html_ << "<tr>";
      for (const auto& c : r) html_ << "<td>" << htmlEscape(c) << "</td>";
      html_ << "</tr>\n";
    }
    html_ << "</table>\n";
  }
  void raw(const std::string& t) { html_ << t; }
  std::string str(const std::string& title) const {
    return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + htmlEscape(title) +
           "</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
           "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;"
           "text-align:right}th{background:#eee}figure{display:inline-block;margin:.5em}"
           "img{border:1px solid #ccc;max-width:100%}.thumb img{width:240px}figcaption{font-size:90%;color:#555}</style>\n"
           "</head><body>\n" +
           html_.str() +
           // For a reader of the page's DOM (the page test): how many of its images loaded.
           "<script>window.addEventListener('load',()=>{const i=[...document.images];"
           "document.body.dataset.imagesLoaded=i.filter(x=>x.complete&&x.naturalWidth>0).length+'/'+i.length;});"
           "</script>\n</body></html>\n";
  }

 private:
  std::ostringstream html_;
};

int runReport(const ReportArgs& args) {
  if (args.views < 1 || args.views > 100000) throw Error("report: --views must be in [1, 100000]");
  if (args.frames < 1 || args.frames > 100000) throw Error("report: --frames must be in [1, 100000]");
  if (args.tree != "hfd" && args.tree != "pfd") throw Error("report: --tree must be hfd or pfd");
  const fs::path dir(args.out);
  std::error_code ec;
  for (const char* sub : {"plan", "diff-bsp", "diff-tree"}) fs::create_directories(dir / sub, ec);
  if (ec || !fs::is_directory(dir)) throw Error(args.out + ": cannot create the report folder");
  fs::remove(dir / "report.log", ec);
  char self[4096];
  const ssize_t len = readlink("/proc/self/exe", self, sizeof self - 1);
  if (len <= 0) throw Error("report: cannot find the walkvis executable (/proc/self/exe)");
  self[len] = 0;

  const bool is_tree = isTreeFile(args.source);
  const std::string scene = is_tree ? args.scene : args.source;
  const std::string tree = is_tree ? args.source : (dir / "tree.wvt").string();
  // Info and the sweeps' steps (HFD sampling; kMaskCells and kClusterTr for backface), the build, the rest.
  Steps steps(self, dir, (scene.empty() ? 0 : 2 + kMaskCells.size() + kClusterTr.size()) + (is_tree ? 0 : 1) + 5);

  Json info, build;
  if (!scene.empty())
    info = steps.run("the scene and its plans", {"info", scene, "--json", "--plan", (dir / "plan").string()},
                     "info.json");
  if (!is_tree)
    build = steps.run("the " + args.tree + " tree", {"build", scene, "--tree", args.tree, "-o", tree, "--json"},
                      "build.json");
  std::vector<std::string> with_scene = {tree};
  if (!scene.empty()) with_scene.insert(with_scene.end(), {"--scene", scene});
  auto withScene = [&](std::vector<std::string> a) {
    a.insert(a.begin() + 1, with_scene.begin(), with_scene.end());
    return a;
  };
  steps.run("a frame", withScene({"render", "--frames", "1", "--size", "640x480", "--out", (dir / "frame").string()}),
            "");
  const std::string views = std::to_string(args.views);
  const Json vbsp = steps.run("validation of the BSP order",
                              {"validate", tree, "--order", "bsp", "--views", views, "--size", "64", "--zbits",
                               "16,24,32", "--json", "--diff-dir", (dir / "diff-bsp").string()},
                              "validate-bsp.json", {0, 1});
  const TreeFile file = loadTreeFile(tree);
  const std::string kind = file.kind == TreeKind::kHfd ? "hfd" : "pfd";
  const Json vtree = steps.run("validation of the " + kind + " order",
                               {"validate", tree, "--order", kind, "--views", views, "--size", "64", "--zbits", "none",
                                "--json", "--diff-dir", (dir / "diff-tree").string()},
                               "validate-tree.json", {0, 1});
  const Json stats = file.kind == TreeKind::kHfd
                         ? steps.run("rejection statistics", {"stats", tree, "--views", views, "--res", "64", "--json"},
                                     "stats.json")
                         : Json();
  std::vector<std::string> bench = {"bench", "frames", tree};
  if (!scene.empty()) bench.insert(bench.end(), {"--scene", scene});
  bench.insert(bench.end(), {"--frames", std::to_string(args.frames), "--rounds", "2", "--json"});
  const Json frames = steps.run("frame times", bench, "frames.json");

  // Speed against error, on the scene (these commands load it themselves).
  std::vector<std::vector<std::string>> mask_rows, tr_rows;
  if (!scene.empty()) {
    steps.run("the HFD sampling sweep",
              {"bench", "hfd", scene, "--region-samples", "4,16", "--polygon-samples", "8", "--refine-rays", "0,256",
               "--views", std::to_string(std::max(4, args.views / 5)), "--res", "32", "--max-seconds", "300", "--csv",
               (dir / "hfd-sweep.csv").string(), "--png", (dir / "hfd-sweep.png").string()},
              "");
    auto backface = [&](const std::string& what, const std::vector<std::string>& extra, const std::string& name) {
      std::vector<std::string> a = {"bench", "backface", "--mesh", scene, "--eyes", "200", "--runs", "1",
                                    "--no-bunny", "--lists", "", "--json"};
      a.insert(a.end(), extra.begin(), extra.end());
      const Json j = steps.run(what, a, name);
      return j.is_array() && !j.empty() && !j[0]["methods"].empty() ? j[0]["methods"][0] : Json::object();
    };
    auto row = [](const std::string& knob, const Json& m) {
      return std::vector<std::string>{knob, pct(m.value("culled_ratio", 0.0)), pct(m.value("effectiveness", 0.0)),
                                      fmt(m.value("ns_per_polygon", 0.0), 3), fmt(m.value("bytes_per_polygon", 0.0), 2),
                                      std::to_string(m.value("false_culls", 0))};
    };
    // One step per point of the two backface sweeps; each is a row and a point of its plot (time per
    // polygon across, effectiveness up, labelled with the knob's value).
    auto sweep = [&](const char* what, const char* name, const char* option, std::span<const char* const> values,
                     std::vector<std::vector<std::string>>& rows, const char* png) {
      std::vector<PlotPoint> points;
      for (const char* v : values) {
        const Json m = backface(std::string(what) + " " + v, {"--only", name, option, v},
                                std::string(name) + "-" + v + ".json");
        rows.push_back(row(v, m));
        points.push_back({m.value("ns_per_polygon", 0.0), m.value("effectiveness", 0.0), Rgb{30, 30, 200}, v});
      }
      writeScatterPlot((dir / png).string(), points, "ns", PlotAxis{0.0, 1.0, false, ""});
    };
    sweep("normal-mask resolution", "mask", "--mask-n", kMaskCells, mask_rows, "mask-sweep.png");
    sweep("Johannsen-Carter T/R", "cluster", "--tr", kClusterTr, tr_rows, "cluster-sweep.png");
  }

  Page page;
  const std::string title = "walkvis report: " + (scene.empty() ? tree : scene);
  page.raw("<h1>" + htmlEscape(title) + "</h1>\n");
  page.p("Made by <code>walkvis report</code>. Every figure below comes from this run; the JSON each step wrote "
         "lies beside this page.");

  page.h2("The scene");
  if (fs::exists(dir / "frame" / "frame_00000.png")) page.img("frame/frame_00000.png", "The start eye's view");
  std::vector<fs::path> plans;
  for (const auto& e : fs::directory_iterator(dir / "plan", ec))
    if (e.path().extension() == ".png") plans.push_back(e.path());
  // level-K.png in level order (not as strings: level-10 after level-9).
  auto levelOf = [](const fs::path& pl) {
    const std::string stem = pl.stem().string();
    const size_t dash = stem.rfind('-');
    return dash == std::string::npos ? 0L : std::strtol(stem.c_str() + dash + 1, nullptr, 10);
  };
  std::sort(plans.begin(), plans.end(), [&](const fs::path& a, const fs::path& b) { return levelOf(a) < levelOf(b); });
  if (!plans.empty())
    page.p("Plans, one per level (green: the level's walkable region; click for the full size):");
  for (const fs::path& pl : plans) page.thumb("plan/" + pl.filename().string(), pl.stem().string());
  std::vector<std::vector<std::string>> rows;
  if (info.is_object()) {
    rows.push_back({"polygons", std::to_string(info.value("polygons", 0))});
    rows.push_back({"levels", std::to_string(info.value("levels", Json::array()).size())});
    rows.push_back({"eye height", fmt(info.value("eye_height", 0.0), 2)});
  }
  rows.push_back({"BSP fragments", std::to_string(file.bsp.fragments.size())});
  rows.push_back({"tree kind", kind});
  page.table({"", ""}, rows);

  page.h2("Build costs");
  rows.clear();
  if (build.is_object()) {
    for (const auto& t : build["trees"])
      rows.push_back({std::to_string(t.value("level", 0)), std::to_string(t.value("cell", 0)),
                      std::to_string(t.value("nodes", 0)), std::to_string(t.value("bytes", 0)),
                      fmt(t.value("build_seconds", 0.0), 2), fmt(t.value("tests_mean", 0.0), 1),
                      std::to_string(t.value("visibility_tests", 0)), std::to_string(t.value("visibility_rays", 0))});
    page.table({"level", "cell", "nodes", "bytes", "build s", "tests per query", "visibility tests", "rays"}, rows);
  } else {  // a tree file given: what it stores (not build times, which tree files leave out)
    for (const PfdLevel& l : file.levels)
      for (size_t c = 0; c < l.cells.size(); ++c)
        rows.push_back({std::to_string(l.level), std::to_string(c), std::to_string(l.cells[c].nodes.size()),
                        std::to_string(l.cells[c].stats.bytes), fmt(l.cells[c].stats.tests_mean, 1)});
    page.table({"level", "cell", "nodes", "bytes", "tests per query"}, rows);
  }
  if (build.is_object())
    page.p("BSP " + fmt(build.value("bsp_build_seconds", 0.0), 2) + " s, trees " +
           fmt(build.value("trees_seconds", 0.0), 2) + " s, " + std::to_string(build.value("total_bytes", 0)) +
           " bytes written.");

  page.h2("Validation");
  const double images = std::max(1.0, static_cast<double>(vbsp.value("views", 0)));  // one image per view
  rows.clear();
  for (const auto* v : {&vbsp, &vtree}) {
    rows.push_back({v->value("order", "?"), std::to_string(v->value("views", 0)),
                    std::to_string(v->value("exact_pixels", 0)), std::to_string(v->value("order_error_pixels", 0)),
                    std::to_string(v->value("missed_pixels", 0)), std::to_string(v->value("tie_pixels", 0)),
                    std::to_string(v->value("edge_pixels", 0))});
  }
  page.table({"order", "views", "exact pixels", "order errors", "missed", "ties", "edge"}, rows);
  rows.clear();
  if (vbsp.contains("zbuffer"))
    for (const auto& [bits, z] : vbsp["zbuffer"].items())
      rows.push_back({bits, z.value("depth_format", ""), std::to_string(z.value("order_error_pixels", 0)),
                      std::to_string(z.value("missed_pixels", 0)), std::to_string(z.value("tie_pixels", 0)),
                      std::to_string(z.value("edge_pixels", 0)),
                      fmt(1e3 * z.value("render_seconds", 0.0) / images, 3)});
  page.p("The z-buffer against the same exact images, per depth precision:");
  page.table({"bits", "format", "errors", "missed", "ties", "edge", "ms per image"}, rows);
  if (vbsp.contains("zbuffer") && !vbsp["zbuffer"].empty()) {
    // Speed against error for the depth precision: time per image across, the share of pixels in
    // error up (log, down to one pixel in error; none in error is drawn at the floor), each point
    // labelled with its bits.
    const double exact = std::max(1.0, static_cast<double>(vbsp.value("exact_pixels", 0)));
    std::vector<PlotPoint> points;
    double highest = 0.0;
    for (const auto& [bits, z] : vbsp["zbuffer"].items()) {
      const double ratio = z.value("order_error_pixels", 0) / exact;
      points.push_back({1e3 * z.value("render_seconds", 0.0) / images, ratio, Rgb{200, 30, 30}, bits});
      highest = std::max(highest, ratio);
    }
    // One pixel in error is the least share there is, 1 / exact; the axis spans a decade at least.
    const double lo = std::floor(std::log10(1.0 / exact));
    const double hi = std::max(lo + 1.0, highest > 0.0 ? std::ceil(std::log10(highest)) : 0.0);
    writeScatterPlot((dir / "zbuffer-bits.png").string(), points, "ms", PlotAxis{lo, hi, true, ""});
    page.img("zbuffer-bits.png",
             "Depth precision: milliseconds per image (drawing and reading back) across, the share of the exact "
             "pixels the z-buffer gets wrong up, per depth-buffer bits");
  }
  int shown = 0;
  for (const char* sub : {"diff-bsp", "diff-tree"}) {
    std::vector<fs::path> diffs;
    for (const auto& e : fs::directory_iterator(dir / sub, ec))
      if (e.path().extension() == ".png") diffs.push_back(e.path());
    std::sort(diffs.begin(), diffs.end());
    for (size_t k = 0; k < diffs.size() && k < 4; ++k, ++shown)
      page.img(std::string(sub) + "/" + diffs[k].filename().string(), diffs[k].stem().string());
  }
  page.p(shown ? "Views with errors (red: order error, orange: missed, cyan: tie, yellow: edge, magenta: uncovered)."
               : "No view had an order error, a missed pixel or a z-buffer error.");

  if (stats.is_object()) {
    page.h2("Rejection");
    rows.clear();
    for (const auto& l : stats["levels"]) {
      rows.push_back({std::to_string(l.value("level", 0)), std::to_string(l.value("eyes", 0)),
                      std::to_string(l.value("fragments", 0)), fmt(l.value("listed_mean", 0.0), 1),
                      fmt(l.value("visible_mean", 0.0), 1), fmt(l.value("missed_mean", 0.0), 3),
                      pct(l.value("eyes_with_miss", 0.0)), sci(l.value("pixel_error_ratio", 0.0)),
                      sci(l.value("pixel_error_ratio_max", 0.0)), pct(l.value("rejection_ratio", 0.0))});
    }
    page.table({"level", "eyes", "fragments", "listed", "visible", "missed", "eyes with a miss", "pixel error",
                "worst eye", "rejection"},
               rows);
    const Json& o = stats["overall"];
    // The buckets in their order (a JSON object's keys come back sorted as strings).
    const std::vector<std::string> missed_buckets = {"0", "1", "2", "3", "4-7", "8-15", "16+"};
    const std::vector<std::string> error_buckets = {"0", "<=1e-6", "<=1e-5", "<=1e-4", "<=1e-3", "<=1e-2", ">1e-2"};
    for (const auto& [key, buckets, colour, what] :
         {std::tuple{"missed_histogram", &missed_buckets, 0xd06030u, "Eyes by polygons missed"},
          std::tuple{"pixel_error_histogram", &error_buckets, 0x3070c0u, "Eyes by pixel error"}}) {
      std::vector<double> values;
      std::string labels;
      for (const std::string& bucket : *buckets) {
        const int64_t count = o.contains(key) ? o[key].value(bucket, int64_t{0}) : 0;
        values.push_back(static_cast<double>(count));
        labels += (labels.empty() ? "" : ", ") + bucket + ": " + std::to_string(count);
      }
      const std::string name = std::string(key) + ".png";
      writeBarChart((dir / name).string(), values, colour);
      page.img(name, std::string(what) + " (" + labels + ")");
    }
  }

  page.h2("Frame times");
  {
    const Json& fj = frames;
    rows.clear();
    for (const auto& m : fj["modes"])
      rows.push_back({m.value("mode", ""), fmt(m.value("frame_ms_median", 0.0)),
                      pct(m.value("frame_ms_round_spread", 0.0)), fmt(m.value("drawn_median", 0.0), 0),
                      fmt(m.value("outside_median", 0.0), 0), fmt(m.value("occluded_median", 0.0), 0),
                      fmt(m.value("speedup_vs_zbuffer", 0.0), 2),
                      pct(m.value("ideal_fraction", 0.0)), pct(m.value("ideal_fraction_paired", 0.0))});
    page.p(std::to_string(fj.value("frames", 0)) + " frames of the automatic tour at " + fj.value("size", "") +
           " (OSMesa), " + std::to_string(fj.value("rounds", 0)) + " rounds. The floor draws nothing; the ideal " +
           "draws exactly what the z-buffer shows (" + fmt(fj.value("ideal_speedup", 0.0), 2) +
           "&times; the z-buffer's speed). Every mode leaves out the fragments wholly outside the view "
           "(outside), and the painter's modes what the frame's largest fragments hide from the eye "
           "(occluded). Of the ideal: the ideal's median time over the mode's; paired: the median over "
           "frames of the same ratio frame by frame, the steadier figure.");
    page.table({"mode", "frame ms", "round spread", "drawn", "outside", "occluded", "speed-up", "of the ideal", "paired"},
               rows);
  }
  page.h2("Speed against error");
  if (scene.empty()) {
    page.p("No scene was given (<code>--scene</code>), so the sweeps were not run.");
  } else {
    page.p("HFD sampling (region samples 4 and 16, polygon samples 8, refinement rays 0 and 256): tree build "
           "seconds across, pixel error up (log scale), one labelled point per row of the table.");
    if (fs::exists(dir / "hfd-sweep.png")) page.img("hfd-sweep.png", "HFD sampling: build seconds against pixel error");
    rows.clear();
    std::ifstream csv(dir / "hfd-sweep.csv");
    std::string line;
    std::vector<std::string> head;
    auto split = [](const std::string& l) {
      std::vector<std::string> f;
      std::stringstream ss(l);
      std::string x;
      while (std::getline(ss, x, ',')) f.push_back(x);
      return f;
    };
    if (std::getline(csv, line)) head = split(line);
    auto col = [&](const std::vector<std::string>& f, const std::string& name) {
      const auto it = std::find(head.begin(), head.end(), name);
      const size_t i = static_cast<size_t>(it - head.begin());
      return it != head.end() && i < f.size() ? f[i] : std::string();
    };
    while (std::getline(csv, line)) {
      const auto f = split(line);
      rows.push_back({col(f, "point"), col(f, "region_samples"), col(f, "polygon_samples"), col(f, "refine_rays"),
                      col(f, "build_seconds"), col(f, "rays"), col(f, "pixel_error_ratio"),
                      col(f, "eyes_with_miss"), col(f, "rejection_ratio")});
    }
    page.table({"point", "region samples", "polygon samples", "refine rays", "build s", "rays", "pixel error",
                "eyes with a miss", "rejection"},
               rows);
    page.p("Backface culling of the scene's polygons over 200 random eyes (<code>walkvis bench backface</code>): "
           "the share culled and the share of back faces found (effectiveness) against the time per polygon. "
           "A conservative method never culls a front face (false culls 0).");
    page.p("Normal mask, cells per cube-face side:");
    if (fs::exists(dir / "mask-sweep.png"))
      page.img("mask-sweep.png", "Normal mask: effectiveness (up, 0 to 1) against ns per polygon, by cells per side");
    page.table({"cells", "culled", "effectiveness", "ns per polygon", "bytes per polygon", "false culls"}, mask_rows);
    page.p("Johannsen&ndash;Carter clusters, T/R (cluster test time over vertex time):");
    if (fs::exists(dir / "cluster-sweep.png"))
      page.img("cluster-sweep.png", "Johannsen-Carter clusters: effectiveness (up, 0 to 1) against ns per polygon, by T/R");
    page.table({"T/R", "culled", "effectiveness", "ns per polygon", "bytes per polygon", "false culls"}, tr_rows);
    page.p("Z-buffer precision against order errors: the table under Validation.");
  }

  const std::string html = page.str(title);
  writeTextFileAtomically((dir / "index.html").string(), html, "report page");
  std::printf("wrote %s\n", (dir / "index.html").string().c_str());
  return 0;
}

}  // namespace

void addReportCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* sub = app.add_subcommand(
      "report", "One HTML page (DIR/index.html, PNGs beside it, no network) with the scene, build costs, validation, "
                "rejection statistics and frame times");
  sub->add_option("source", args->source, "A scene (its tree is built) or a tree file made by `walkvis build`")
      ->required();
  sub->add_option("-o,--out", args->out, "Folder for the page")->required();
  sub->add_option("--scene", args->scene, "For a tree file: the scene it was built from (plans, colours)");
  sub->add_option("--tree", args->tree, "For a scene: the tree to build, hfd (default) or pfd");
  sub->add_option("--views", args->views, "Eyes for validation and statistics (default 50)");
  sub->add_option("--frames", args->frames, "Frames of the tour for the frame times (default 60)");
  sub->callback([args, &runner] { runner = [args] { return runReport(*args); }; });
}

}  // namespace walkvis
