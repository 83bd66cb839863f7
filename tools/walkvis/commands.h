// The walkvis command line: a thin layer over the libraries. Each subcommand lives in its own
// cmd_*.cpp and is registered by main.cpp through one add*Command call.
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "scenes/scene.h"

namespace walkvis {

// Set by a subcommand's parse callback; main runs it after parsing and returns its exit status.
using CommandRunner = std::function<int()>;

// How a scene is loaded (--eye-height, --loader, --up, --unit-scale, --no-merge, --floors and the
// walker's --agent-* sizes), shared by every command that loads a scene.
void addLoadOptions(CLI::App& sub, LoadOptions& load);

// The scene argument and the load options.
struct SceneArgs {
  std::string scene = "gen:office";
  LoadOptions load;
  const LoadOptions& loadOptions() const { return load; }
};
void addSceneArgs(CLI::App& sub, SceneArgs& args, bool required = true);

// Exit statuses: 0 success, 1 a check or target failed, 2 bad input or usage.
constexpr int kExitBadInput = 2;

void addInfoCommand(CLI::App& app, CommandRunner& runner);
void addBenchCommand(CLI::App& app, CommandRunner& runner);
void addBenchBackface(CLI::App& bench, CommandRunner& runner);  // cmd_bench_backface.cpp: `bench backface`
void addValidateCommand(CLI::App& app, CommandRunner& runner);
void addBuildCommand(CLI::App& app, CommandRunner& runner);
void addPlanCommand(CLI::App& app, CommandRunner& runner);  // cmd_plan.cpp: `walkvis plan`
void addRenderCommand(CLI::App& app, CommandRunner& runner);
void addWalkCommand(CLI::App& app, CommandRunner& runner);  // cmd_walk.cpp, walk_window.cpp
void addBenchFrames(CLI::App& bench, CommandRunner& runner);  // cmd_bench_frames.cpp: `bench frames`
void addStatsCommand(CLI::App& app, CommandRunner& runner);  // cmd_stats.cpp: `stats`
void addBenchHfd(CLI::App& bench, CommandRunner& runner);  // cmd_bench_hfd.cpp: `bench hfd`, `bench rays`
void addReportCommand(CLI::App& app, CommandRunner& runner);  // cmd_report.cpp: `report`
void addExportCommand(CLI::App& app, CommandRunner& runner);  // cmd_export.cpp: `export --web`

}  // namespace walkvis
