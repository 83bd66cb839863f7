// walkvis render SCENE|FILE --out DIR: offscreen walkthrough frames (OSMesa) along a camera path or
// the automatic tour: frame_NNNNN.png (shaded) and frames.csv with per-frame times and counts.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "commands.h"
#include "frames_common.h"
#include "walkthrough/osmesa_context.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

struct RenderArgs {
  std::string source;
  std::string scene;
  LoadOptions load;
  std::string path;
  uint32_t frames = 120;
  std::string size = "640x480";
  std::string mode;
  std::string cull = "none";
  std::string out;
  std::string objects = "auto";
  bool ids = false;
};

// The tree kind a mode needs; Error when the source cannot give it.
void checkModeSource(OrderMode mode, const World& world) {
  if (mode == OrderMode::kHfd && (world.trees.levels.empty() || world.trees.kind != TreeKind::kHfd))
    throw Error(world.source + ": --mode hfd needs a tree file made by `walkvis build --tree hfd`");
  if (mode == OrderMode::kPfd && !world.trees.levels.empty() && world.trees.kind != TreeKind::kPfd)
    throw Error(world.source + ": --mode pfd needs a PFD tree file or a scene (this file holds HFD trees)");
}

int runRender(const RenderArgs& args) {
  const ImageSize size = parseImageSize(args.size, "--size");
  const ListCullMethod cull = parseListCullMethod(args.cull);
  WorldOptions options;
  options.load = args.load;
  options.scene = args.scene;
  options.cull = cull;
  options.objects = parseObjectSet(args.objects);
  std::optional<OrderMode> mode;
  if (!args.mode.empty()) mode = parseOrderMode(args.mode);
  options.build_pfd = mode == OrderMode::kPfd;
  auto progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const World world = openWorld(args.source, options, progress);
  // Default: what the source offers best (its trees), else the BSP order.
  if (!mode) mode = world.trees.levels.empty() ? OrderMode::kBsp
                    : world.trees.kind == TreeKind::kHfd ? OrderMode::kHfd
                                                         : OrderMode::kPfd;
  checkModeSource(*mode, world);
  const CameraPath path = framesPath(world, args.path, args.frames);

  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec || !std::filesystem::is_directory(args.out)) throw Error(args.out + ": cannot create the output folder");

  std::string why;
  auto context = OsMesaContext::create(size.width, size.height, 24, &why);
  if (!context) throw std::runtime_error("offscreen GL: " + why);
  auto drawer = SceneDrawer::create(OsMesaContext::loader(), &why);
  if (!drawer) throw std::runtime_error("offscreen GL: " + why);
  drawer->upload(world.trees.bsp, world.scene);

  const std::string csv_path = (std::filesystem::path(args.out) / "frames.csv").string();
  const std::string csv_tmp = csv_path + ".tmp";
  std::ofstream csv(csv_tmp);
  if (!csv) throw Error(csv_path + ": cannot open for writing");
  csv << "frame,time,x,y,z,yaw,pitch,frame_ms,order_ms,draw_ms,drawn,listed,tests,culled,used,level,object_ms,"
         "object_triangles,object_triangles_computed,outside,occluded\n";
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  std::vector<uint8_t> rgb;
  const DrawStyle style = args.ids ? DrawStyle::kIds : DrawStyle::kShaded;
  std::fprintf(stderr, "rendering %zu frames of %s, %dx%d, mode %s, cull %s, into %s\n", path.keys.size(),
               args.source.c_str(), size.width, size.height, std::string(orderModeName(*mode)).c_str(),
               std::string(listCullMethodName(cull)).c_str(), args.out.c_str());
  for (size_t k = 0; k < path.keys.size(); ++k) {
    const CameraKey& key = path.keys[k];
    const FreeCamera camera = cameraAt(key, size);
    // The objects' animation runs on the path's clock.
    const FrameStats s = timedFrame(world, builder, *drawer, camera, *mode, style, draw, key.time);
    drawer->readRgb(size.width, size.height, rgb);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.png", k);
    writePngRgb((std::filesystem::path(args.out) / name).string(), size.width, size.height, rgb);
    char line[512];
    std::snprintf(line, sizeof line, "%zu,%.6f,%.17g,%.17g,%.17g,%.17g,%.17g,%.4f,%.4f,%.4f,%u,%u,%u,%u,%s,%d,%.4f,%u,%llu,%u,%u\n",
                  k, key.time, key.eye.x, key.eye.y, key.eye.z, key.yaw, key.pitch,
                  s.order_ms + s.object_ms + s.draw_ms, s.order_ms, s.draw_ms, s.drawn, s.listed, s.tests, s.culled,
                  std::string(orderModeName(s.used)).c_str(), s.level, s.object_ms, s.object_triangles,
                  static_cast<unsigned long long>(s.object_triangles_computed), s.outside, s.occluded);
    csv << line;
    if ((k + 1) % 20 == 0 || k + 1 == path.keys.size())
      std::fprintf(stderr, "  frame %zu/%zu\n", k + 1, path.keys.size());
  }
  csv.close();
  if (!csv) throw Error(csv_path + ": cannot write");
  std::filesystem::rename(csv_tmp, csv_path, ec);
  if (ec) throw Error(csv_path + ": cannot write (" + ec.message() + ")");
  std::printf("%zu frames written to %s (frames.csv, frame_*.png)\n", path.keys.size(), args.out.c_str());
  return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand("render", "Offscreen walkthrough frames (PNG) and per-frame figures (CSV)");
  sub->add_option("source", args->source, "A scene (model.obj, freedoom2.wad:MAP01, gen:office) or a tree file")
      ->required();
  sub->add_option("--scene", args->scene, "For a tree file: the scene it was built from (its colours)");
  addLoadOptions(*sub, args->load);
  sub->add_option("--path", args->path, "Camera path CSV (time,x,y,z,yaw,pitch); default: the automatic tour");
  sub->add_option("--frames", args->frames, "Frames of the automatic tour (with --path: at most this many keys)")
      ->check(CLI::Range(1u, 1000000u));
  sub->add_option("--size", args->size, "Image size WxH");
  sub->add_option("--mode", args->mode, "zbuffer | bsp | pfd | hfd (default: the tree file's kind, else bsp)");
  sub->add_option("--cull", args->cull, "Backface method: none | polygon | mask | cluster | hierarchy | region");
  sub->add_option("--out", args->out, "Output folder")->required();
  sub->add_option("--objects", args->objects,
                  "Mesh objects: auto (the animated blob in gen:office) | none | blob (in the start room)");
  sub->add_flag("--ids", args->ids, "Write ids images (fragment index + 1 as RGB) instead of shaded ones");
  sub->callback([args, &runner] { runner = [args] { return runRender(*args); }; });
}

}  // namespace walkvis
