// walkvis export FILE --web DIR: a static page that walks the building of an HFD tree file in the
// browser (walkthrough/web_export.h; docs/web/README.md).
#include <cstdio>
#include <memory>

#include "commands.h"
#include "walkthrough/web_export.h"

namespace walkvis {
namespace {

struct ExportArgs {
  std::string source;
  std::string scene;
  LoadOptions load;
  std::string web;
  WebExportOptions options;
};

int runExport(const ExportArgs& args) {
  if (!isTreeFile(args.source))
    throw Error(args.source + ": not a tree file (make one with `walkvis build SCENE --tree hfd -o FILE`)");
  WorldOptions world_options;
  world_options.load = args.load;
  world_options.scene = args.scene;
  world_options.objects = ObjectSet::kNone;  // the page draws the building, not the animated blob
  auto progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const World world = openWorld(args.source, world_options, progress);
  std::fprintf(stderr, "writing the web export of %s into %s\n", args.source.c_str(), args.web.c_str());
  const WebExportReport r = writeWebExport(world, args.web, args.options);
  std::printf("web export of %s: %u view cells, %u tour keys\n", args.source.c_str(), r.cells, r.tour_keys);
  for (const WebSectionBytes& s : r.sections)
    std::printf("  %-4s %12llu bytes, %12llu stored\n", s.tag.c_str(), static_cast<unsigned long long>(s.bytes),
                static_cast<unsigned long long>(s.stored));
  std::printf("  walkvis.bin %llu bytes, cells/*.bin %llu bytes (%u files), scripts for file:// %llu bytes, page %llu bytes\n",
              static_cast<unsigned long long>(r.binary_bytes), static_cast<unsigned long long>(r.cell_bytes), r.cells,
              static_cast<unsigned long long>(r.script_bytes), static_cast<unsigned long long>(r.page_bytes));
  std::printf("open %s/index.html (or serve the folder)\n", args.web.c_str());
  return 0;
}

}  // namespace

void addExportCommand(CLI::App& app, CommandRunner& runner) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export", "A static web page that walks an HFD tree file's building in WebGL2");
  sub->add_option("source", args->source, "A tree file made by `walkvis build SCENE --tree hfd`")->required();
  sub->add_option("--web", args->web, "Output folder (index.html, viewer.js, page.js, walkvis.bin, walkvis-data.js, cells/K.bin and .js)")
      ->required();
  sub->add_option("--scene", args->scene, "The scene the file was built from (its colours, stairs and start)");
  addLoadOptions(*sub, args->load);
  sub->add_flag("--raw{false}", args->options.deflate, "Store every section raw (default: deflated where smaller)");
  sub->add_option("--frames", args->options.tour_frames, "Keys of the automatic tour stored for ?frame=K")
      ->check(CLI::Range(1u, 100000u));
  sub->callback([args, &runner] { runner = [args] { return runExport(*args); }; });
}

}  // namespace walkvis
