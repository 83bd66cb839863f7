// Every file of tests/data/bad_input through the real command line: `walkvis info FILE` (or the
// scene argument held in a .spec file), run in that folder with a time limit, must exit with
// status 2 and print exactly one line on stderr, starting "walkvis: ", naming the file and holding
// the substring of FILE.expected — and no sanitizer report.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

namespace fs = std::filesystem;

const fs::path kDir = fs::path(WALKVIS_SOURCE_DIR) / "tests" / "data" / "bad_input";

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

// Bad cases: every file but the .expected files, the generator script and notes.
std::vector<std::string> badFiles() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(kDir)) {
    const std::string name = entry.path().filename().string();
    const std::string ext = entry.path().extension().string();
    if (ext == ".expected" || ext == ".py" || ext == ".md") continue;
    names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

struct RunResult {
  int status = -1;  // exit status, or -1 when killed by a signal
  std::string err;
};

// Runs walkvis in the corpus folder with a shell and `timeout` (sanitizer builds are slow: the
// limit is generous but a hang still fails).
RunResult runWalkvis(const std::string& argument) {
  EXPECT_EQ(argument.find('\''), std::string::npos) << "argument must not contain a single quote";
  char tmpl[] = "/tmp/walkvis_bad_input_XXXXXX";
  const int fd = mkstemp(tmpl);
  EXPECT_GE(fd, 0);
  close(fd);
  const std::string cmd = "cd '" + kDir.string() + "' && timeout -k 5 120 '" + std::string(WALKVIS_BINARY) +
                          "' info '" + argument + "' >/dev/null 2>'" + tmpl + "'";
  const int raw = std::system(cmd.c_str());
  RunResult run;
  if (raw != -1 && WIFEXITED(raw)) run.status = WEXITSTATUS(raw);
  run.err = readText(tmpl);
  std::remove(tmpl);
  return run;
}

TEST(BadInput, CorpusIsComplete) {
  const auto names = badFiles();
  EXPECT_GE(names.size(), 20u);
  for (const auto& name : names) {
    EXPECT_TRUE(fs::exists(kDir / (name + ".expected"))) << name << " has no " << name << ".expected";
  }
  for (const auto& entry : fs::directory_iterator(kDir)) {
    if (entry.path().extension() != ".expected") continue;
    EXPECT_TRUE(fs::exists(entry.path().parent_path() / entry.path().stem())) << entry.path() << " has no bad file";
  }
}

class BadInput : public ::testing::TestWithParam<std::string> {};

TEST_P(BadInput, ExitsTwoWithOneLineNamingTheFile) {
  const std::string name = GetParam();
  const std::string expected = trim(readText(kDir / (name + ".expected")));
  ASSERT_FALSE(expected.empty()) << name << ".expected is empty";
  std::string argument = name;
  std::string names_file = name;  // what the message must name
  if (fs::path(name).extension() == ".spec") {
    argument = trim(readText(kDir / name));
    names_file = argument.substr(0, argument.find('?'));
    // FILE.wad:MAP → the message names the WAD file (the map is checked by .expected).
    const size_t colon = names_file.rfind(':');
    if (names_file.rfind("gen:", 0) != 0 && colon != std::string::npos) names_file = names_file.substr(0, colon);
  }
  const RunResult run = runWalkvis(argument);
  SCOPED_TRACE("walkvis info " + argument + "\nstderr: " + run.err);
  EXPECT_EQ(run.status, 2);
  EXPECT_EQ(run.err.rfind("walkvis: ", 0), 0u);
  ASSERT_FALSE(run.err.empty());
  EXPECT_EQ(run.err.back(), '\n');
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1);
  EXPECT_NE(run.err.find(expected), std::string::npos) << "expected to contain: " << expected;
  EXPECT_NE(run.err.find(names_file), std::string::npos) << "expected to name: " << names_file;
  for (const char* report : {"Sanitizer", "runtime error:", "LeakSanitizer"}) {
    EXPECT_EQ(run.err.find(report), std::string::npos) << report;
  }
}

std::string caseName(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return s;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(badFiles()), caseName);

}  // namespace
