// `walkvis build` on several MPI ranks and after kills: the tree file must come out byte for byte
// the same as one uninterrupted process's (tools/walkvis/build_runner.cpp), and the journal must
// survive a record cut short (pfd_hfd/pfd_journal.h).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bsp/bsp.h"
#include "command_test_util.h"
#include "core/byte_io.h"
#include "core/rng.h"
#include "pfd_hfd/pfd.h"
#include "pfd_hfd/pfd_journal.h"
#include "scenes/scene.h"

extern char** environ;

namespace walkvis {
namespace {

namespace fs = std::filesystem;

// An HFD build of the generated office cut into about seventy view cells over four rounds: enough
// jobs to spread and to be killed between, a few seconds on one thread.
const std::vector<std::string> kBuildArgs = {"build", "gen:office", "--tree", "hfd", "--cell-memory", "48k",
                                             "--threads", "1", "--stat-eyes", "200"};

fs::path testDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("walkvis_distributed_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string quoted(const std::vector<std::string>& args) {
  std::string s;
  for (const std::string& a : args) s += " '" + a + "'";
  return s;
}

// Runs the build under `launcher` (empty: alone) writing `output`; its exit status, stderr in `log`.
int runBuild(const std::string& launcher, const fs::path& output, const fs::path& log,
             const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = kBuildArgs;
  args.insert(args.end(), {"-o", output.string()});
  args.insert(args.end(), extra.begin(), extra.end());
  return runCommand("timeout -k 5 300 " + launcher + " '" + std::string(WALKVIS_BINARY) + "'" + quoted(args) +
                    " > /dev/null 2> '" + log.string() + "'");
}

// mpirun as the test suite may run it: as root in a container, more ranks than cores.
// Under the sanitizers the ranks run without LeakSanitizer: Open MPI 4.1 leaks in MPI_Init and
// unloads its components (mca_*.so) in MPI_Finalize, so their leaks have no module a suppression
// could name, and it has no parameter to keep them loaded. The same code alone, where MPI is
// never initialized, runs with leak checking in this file and the rest of the suite.
std::string mpirun(int ranks) {
  const std::string no_leak_check = std::getenv("WALKVIS_SANITIZER_BUILD") ? "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" " : "";
  return "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none " +
         no_leak_check + "mpirun --oversubscribe -n " + std::to_string(ranks);
}

std::vector<uint8_t> bytesOf(const fs::path& path) { return fs::exists(path) ? readFileBytes(path.string()) : std::vector<uint8_t>{}; }

TEST(DistributedBuild, OneTwoAndThreeRanksWriteTheSameBytes) {
  const fs::path dir = testDir("ranks");
  ASSERT_EQ(runBuild("", dir / "alone.wvt", dir / "alone.log"), 0) << readText(dir / "alone.log");
  const std::vector<uint8_t> alone = bytesOf(dir / "alone.wvt");
  ASSERT_FALSE(alone.empty());
  EXPECT_FALSE(fs::exists(dir / "alone.wvt.journal")) << "a finished build leaves no journal";
  for (int ranks : {1, 2, 3}) {
    const fs::path out = dir / ("ranks" + std::to_string(ranks) + ".wvt");
    const fs::path log = dir / ("ranks" + std::to_string(ranks) + ".log");
    ASSERT_EQ(runBuild(mpirun(ranks), out, log), 0) << readText(log);
    EXPECT_TRUE(bytesOf(out) == alone) << ranks << " ranks wrote other bytes than one process\n" << readText(log);
    // The progress names every rank, and every rank built some of the cells.
    const std::string text = readText(log);
    for (int r = 0; r < ranks; ++r) {
      const std::string name = "rank " + std::to_string(r) + ": ";
      const size_t at = text.rfind(name);
      ASSERT_NE(at, std::string::npos) << text;
      EXPECT_NE(text.compare(at + name.size(), 2, "0 "), 0) << "rank " << r << " built no cell\n" << text;
    }
  }
  fs::remove_all(dir);
}

// Starts the build, SIGKILLs it after `delay` or as soon as `kill_now` says so, unless it ended
// before; true when it ended by itself.
bool runUntilKilled(const fs::path& output, std::chrono::microseconds delay, int& status,
                    const std::function<bool()>& kill_now = {}) {
  std::vector<std::string> args = kBuildArgs;
  args.insert(args.end(), {"-o", output.string()});
  args.insert(args.begin(), WALKVIS_BINARY);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&files, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (spawned != 0) {
    status = -1;
    return true;
  }
  const auto end = std::chrono::steady_clock::now() + delay;
  int wstatus = 0;
  while (std::chrono::steady_clock::now() < end && !(kill_now && kill_now())) {
    if (::waitpid(pid, &wstatus, WNOHANG) == pid) {
      status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1;
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &wstatus, 0);
  status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1;
  return WIFEXITED(wstatus);  // it may have ended just before the signal
}

TEST(DistributedBuild, KilledAtRandomMomentsAndRerunWritesTheSameBytes) {
  const fs::path dir = testDir("kill");
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(runBuild("", dir / "whole.wvt", dir / "whole.log"), 0) << readText(dir / "whole.log");
  // The kills fall anywhere in an uninterrupted build's time, however fast this build is
  // (Release, the sanitizers, a loaded machine).
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<uint8_t> whole = bytesOf(dir / "whole.wvt");
  ASSERT_FALSE(whole.empty());
  // Fewer under the sanitizers, where each build takes several times as long: there the test is
  // for memory errors on the resumed paths, the Release suite's for the count.
  const int kills_wanted = std::getenv("WALKVIS_SANITIZER_BUILD") ? 5 : 24;
  int kills = 0;
  uint64_t seed = 1;
  for (; kills < kills_wanted || seed <= 3; ++seed) {
    ASSERT_LT(seed, 40u) << "the builds keep ending before their kill";
    Rng rng{seed};
    const fs::path out = dir / ("seed" + std::to_string(seed) + ".wvt");
    int status = 0;
    for (int attempt = 0;; ++attempt) {
      ASSERT_LT(attempt, 60) << "seed " << seed << ": no progress between kills";
      // Anywhere from the scene's loading to the last cells and the final write.
      const auto delay = std::chrono::microseconds(static_cast<int64_t>(rng.uniform(0.01, 1.0) * build_seconds * 1e6));
      if (runUntilKilled(out, delay, status)) break;
      ++kills;
      // Whatever moment the kill came at, the output path holds nothing or the whole file.
      const std::vector<uint8_t> now = bytesOf(out);
      EXPECT_TRUE(now.empty() || now == whole) << "seed " << seed << ": a half-written tree file after a kill";
    }
    ASSERT_EQ(status, 0) << "seed " << seed;
    EXPECT_TRUE(bytesOf(out) == whole) << "seed " << seed << ": the resumed build wrote other bytes";
    EXPECT_FALSE(fs::exists(out.string() + ".journal"));
  }
  EXPECT_GE(kills, std::min(kills_wanted, 20));
  std::printf("%d kills over %llu seeds, each rerun wrote the same bytes\n", kills, static_cast<unsigned long long>(seed - 1));
  fs::remove_all(dir);
}

// Kills the build as soon as its journal holds a cell's record (more than its header),
// however long the scene and the first cells take on a loaded machine; true when it ended first.
bool runUntilJournaled(const fs::path& output, int& status) {
  const fs::path journal = output.string() + ".journal";
  const auto journaled = [&journal] {
    std::error_code error;
    const uintmax_t size = fs::file_size(journal, error);
    return !error && size > kPfdJournalHeaderBytes;
  };
  return runUntilKilled(output, std::chrono::seconds(240), status, journaled);
}

TEST(DistributedBuild, AJournalOfOtherOptionsOrFreshStartsOver) {
  const fs::path dir = testDir("options");
  const fs::path out = dir / "a.wvt";
  int status = 0;
  // A journal with some cells of the build with the default visibility seed; the rerun takes another.
  ASSERT_FALSE(runUntilJournaled(out, status)) << "the build ended before its kill";
  ASSERT_TRUE(fs::exists(out.string() + ".journal"));
  ASSERT_EQ(runBuild("", out, dir / "other.log", {"--visibility-seed", "2"}), 0);
  EXPECT_NE(readText(dir / "other.log").find("of another scene or other options; starting the build over"),
            std::string::npos)
      << readText(dir / "other.log");
  ASSERT_EQ(runBuild("", dir / "b.wvt", dir / "b.log", {"--visibility-seed", "2"}), 0);
  EXPECT_TRUE(bytesOf(out) == bytesOf(dir / "b.wvt"));
  // --fresh discards a matching journal.
  fs::remove(out);
  ASSERT_FALSE(runUntilJournaled(out, status));
  ASSERT_TRUE(fs::exists(out.string() + ".journal"));
  ASSERT_EQ(runBuild("", out, dir / "fresh.log", {"--fresh"}), 0);
  const std::string fresh = readText(dir / "fresh.log");
  EXPECT_NE(fresh.find("--fresh"), std::string::npos) << fresh;
  EXPECT_EQ(fresh.find("resuming"), std::string::npos) << fresh;
  fs::remove_all(dir);
}

nlohmann::json jsonOf(const std::string& command, const fs::path& out, const fs::path& log) {
  EXPECT_EQ(runCommand(command + " --json > '" + out.string() + "' 2> '" + log.string() + "'"), 0) << readText(log);
  return nlohmann::json::parse(readText(out), nullptr, false);
}

// `walkvis plan` on the build above: its cells, its sample, and an estimate that is a schedule of
// the measured cells (between the CPU over the slots and the one-slot time) and in reach of the
// built trees' bytes.
TEST(DistributedBuild, PlanSamplesTheCellsAndEstimatesTheBuild) {
  const fs::path dir = testDir("plan");
  std::vector<std::string> args = kBuildArgs;
  args.insert(args.end(), {"-o", (dir / "a.wvt").string()});
  const nlohmann::json built = jsonOf("'" + std::string(WALKVIS_BINARY) + "'" + quoted(args), dir / "build.json", dir / "build.log");
  ASSERT_FALSE(built.is_discarded());
  args = kBuildArgs;
  args[0] = "plan";
  args.insert(args.end(), {"--sample", "6", "--ranks", "3"});
  const nlohmann::json plan = jsonOf("'" + std::string(WALKVIS_BINARY) + "'" + quoted(args), dir / "plan.json", dir / "plan.log");
  ASSERT_FALSE(plan.is_discarded()) << readText(dir / "plan.log");
  EXPECT_EQ(plan["scene"], "gen:office");
  EXPECT_EQ(plan["fragments"], built["fragments"]) << "the plan's BSP is the build's";
  EXPECT_GE(plan["cells"].get<size_t>(), 6u);
  ASSERT_EQ(plan["sampled"], 6);
  ASSERT_EQ(plan["samples"].size(), 6u);
  std::vector<size_t> cells;
  for (const auto& sample : plan["samples"]) {
    EXPECT_GT(sample["seconds"].get<double>(), 0.0);
    EXPECT_GT(sample["bytes"].get<double>(), 0.0);
    cells.push_back(sample["cell"].get<size_t>());
  }
  EXPECT_TRUE(std::is_sorted(cells.begin(), cells.end())) << "one sample per stratum, costliest stratum first";
  EXPECT_EQ(std::adjacent_find(cells.begin(), cells.end()), cells.end()) << "six different cells";
  const double cpu = plan["trees_cpu_seconds"], trees_wall = plan["trees_wall_seconds"];
  const double setup = plan["setup_seconds"], one_slot = plan["wall_seconds_one_slot"];
  EXPECT_GE(trees_wall, cpu / 3 * (1 - 1e-9)) << "three slots do no more than three slots' work";
  EXPECT_LE(trees_wall, cpu * (1 + 1e-9));
  EXPECT_NEAR(one_slot, setup + cpu, 1e-9 * one_slot);
  EXPECT_NEAR(plan["cpu_seconds"].get<double>(), cpu + 3 * setup, 1e-9 * (cpu + 3 * setup)) << "every rank does the setup";
  EXPECT_GT(plan["rank0_memory_bytes"].get<double>(), plan["rank_memory_bytes"].get<double>());
  // The build cuts a cell when its tree goes over --cell-memory; the plan cuts by the lines'
  // estimate into smaller cells that repeat what neighbours share, so it says more bytes (2.5x here
  // when written), never less than half.
  const double built_bytes = built["total_bytes"], planned_bytes = plan["tree_bytes"];
  EXPECT_GT(planned_bytes, 0.5 * built_bytes);
  EXPECT_LT(planned_bytes, 4.0 * built_bytes);
  // Whole levels estimated from windows: the office's one level against its whole build (bytes
  // +35% when written; the figures are in docs/scaleout/README.md).
  const std::string whole = "'" + std::string(WALKVIS_BINARY) + "' build gen:office --tree hfd --stat-eyes 200 --threads 1 -o '" +
                            (dir / "w.wvt").string() + "' --json";
  const nlohmann::json built_whole = jsonOf(whole, dir / "whole.json", dir / "whole.log");
  ASSERT_FALSE(built_whole.is_discarded()) << readText(dir / "whole.log");
  ASSERT_EQ(built_whole["view_cells"], 1);
  const nlohmann::json windows =
      jsonOf("'" + std::string(WALKVIS_BINARY) + "' plan gen:office --tree hfd --stat-eyes 200 --hfd-cells windows --json",
             dir / "windows.json", dir / "windows.log");
  ASSERT_FALSE(windows.is_discarded()) << readText(dir / "windows.log");
  EXPECT_EQ(windows["sampled_by"], "windows");
  EXPECT_EQ(windows["cells"], 1);
  const double whole_bytes = built_whole["total_bytes"], window_bytes = windows["tree_bytes"];
  EXPECT_GT(window_bytes, 0.5 * whole_bytes);
  EXPECT_LT(window_bytes, 2.0 * whole_bytes);
  EXPECT_LT(windows["sample_seconds"].get<double>(), windows["trees_cpu_seconds"].get<double>())
      << "four windows of a sixteenth each cost less than the level they estimate";
  // Bad input: one line, exit status 2.
  for (const std::string& bad : {std::string("plan gen:office --ranks 0"), std::string("plan gen:office --hfd-cells windows --windows 0"),
                                 std::string("plan '") + (dir / "none.obj").string() + "'"}) {
    EXPECT_EQ(runCommand("'" + std::string(WALKVIS_BINARY) + "' " + bad + " > /dev/null 2> '" + (dir / "bad.log").string() + "'"), 2) << bad;
    const std::string text = readText(dir / "bad.log");
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  }
  fs::remove_all(dir);
}

// The journal's own rules, without processes: records round-trip, a torn last record is dropped
// and cut off, a changed fingerprint starts over.
TEST(PfdJournal, KeepsWholeRecordsAndDropsATornOne) {
  const fs::path dir = testDir("journal");
  const Scene scene = loadScene("gen:office");
  const BspTree bsp = buildBsp(scene);
  PfdLevelOptions options;
  options.cell_memory = 0;
  options.tree.stat_eyes = 100;
  const PfdCellContext context{&bsp, scene.levels, scene.eye_height, options};
  std::vector<PfdCellJob> jobs;
  for (int k = 0; k < 3; ++k) {
    PfdCellJob job;
    const auto& ring = scene.levels[0].walkable[0];
    const glm::dvec2 lo = ring[0] - glm::dvec2(50.0), hi = ring[0] + glm::dvec2(2.0 + k);
    job.box = PfdBox{lo, hi};
    job.depth = 1;
    jobs.push_back(job);
  }
  std::vector<PfdCellOutcome> outcomes;
  for (const PfdCellJob& job : jobs) {
    outcomes.push_back(buildPfdCell(context, job));
    outcomes.back().tree->stats.query_timing = timePfdQueries(bsp, *outcomes.back().tree, 20 + 10 * outcomes.size());
  }
  PfdCellOutcome over;
  over.stopped_bytes = 1234;
  over.stopped_fraction = 0.25;
  const std::string path = (dir / "j").string();
  std::string note;
  {
    PfdJournal journal(path, 42, false, note);
    EXPECT_EQ(note, "");
    for (size_t k = 0; k < jobs.size(); ++k) journal.append(jobs[k], k == 1 ? over : outcomes[k]);
  }
  const size_t fragments = bsp.fragments.size();
  {
    PfdJournal journal(path, 42, false, note);
    EXPECT_NE(note.find("3 view cells done"), std::string::npos) << note;
    for (size_t k = 0; k < jobs.size(); ++k) {
      const std::optional<PfdCellOutcome> got = journal.find(jobs[k], fragments);
      ASSERT_TRUE(got.has_value());
      if (k == 1) {
        EXPECT_FALSE(got->tree);
        EXPECT_EQ(got->stopped_bytes, 1234u);
      } else {
        ASSERT_TRUE(got->tree && outcomes[k].tree);
        EXPECT_TRUE(pfdTreeBytes(*got->tree) == pfdTreeBytes(*outcomes[k].tree));
        EXPECT_EQ(got->tree->stats.tests_mean, outcomes[k].tree->stats.tests_mean);
        // The query timing travels with the outcome, not in the tree's bytes.
        const PfdQueryTiming &a = got->tree->stats.query_timing, &b = outcomes[k].tree->stats.query_timing;
        EXPECT_EQ(a.eyes, 20 + 10 * (k + 1));
        EXPECT_EQ(a.eyes, b.eyes);
        EXPECT_GT(a.bsp_ns, 0.0);
        EXPECT_EQ(a.pfd_ns, b.pfd_ns);
        EXPECT_EQ(a.bsp_ns, b.bsp_ns);
        EXPECT_EQ(a.refs_mean, b.refs_mean);
      }
    }
    PfdCellJob other = jobs[0];
    other.depth = 2;
    EXPECT_FALSE(journal.find(other, fragments).has_value());
  }
  // A kill in the middle of the last record's write.
  const uintmax_t size = fs::file_size(path);
  fs::resize_file(path, size - 10);
  {
    PfdJournal journal(path, 42, false, note);
    EXPECT_NE(note.find("2 view cells done (a record cut short"), std::string::npos) << note;
    EXPECT_FALSE(journal.find(jobs[2], fragments).has_value());
    journal.append(jobs[2], outcomes[2]);
  }
  EXPECT_EQ(fs::file_size(path), size) << "the torn record was cut off before the next one";
  {
    PfdJournal journal(path, 43, false, note);
    EXPECT_NE(note.find("of another scene or other options"), std::string::npos) << note;
    EXPECT_EQ(journal.records(), 0u);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace walkvis
