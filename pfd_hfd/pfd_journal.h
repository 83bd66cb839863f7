// A build's journal: every finished view cell of buildPfdLevels, appended to a file beside the
// output as it finishes, so that a build killed at any moment (SIGKILL included) goes on from the
// cells it had (docs/DESIGN.md, "Builds across processes and restarts").
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pfd_hfd/pfd.h"

namespace walkvis {

// What a build's trees depend on, hashed (FNV-1a 64): the BSP (the scene's polygons and their
// partition), the eye height, the tree kind and visibility sampling, every tree option, the
// levels' walkable regions and the levels chosen. Not the thread or process count, which change
// nothing. Two builds with equal fingerprints build equal trees for equal jobs.
uint64_t pfdBuildFingerprint(const TreeFile& head, std::span<const FloorLevel> levels, std::span<const uint32_t> only,
                             const PfdLevelOptions& options);

// The journal file: header (magic "WVJRNL\r\n", u32 version, u32 0, u64 fingerprint), then one
// record per finished job: u64 payload bytes, u64 FNV-1a 64 of the payload, payload (the job's
// key, u64 outcome bytes, pfdCellOutcomeBytes). A record is written with one write() and synced
// before the build goes on; a record cut short by a kill, or one whose checksum fails, ends the
// journal there (it is truncated on open).
constexpr size_t kPfdJournalHeaderBytes = 24;
class PfdJournal {
 public:
  // Opens `path` for a build with `fingerprint`: keeps its records when its header matches and
  // `fresh` is false, else starts it again. `note` says which in one line (empty when a new
  // journal was started where none was). Error naming the path when it cannot be read or written.
  PfdJournal(const std::string& path, uint64_t fingerprint, bool fresh, std::string& note);
  ~PfdJournal();
  PfdJournal(const PfdJournal&) = delete;
  PfdJournal& operator=(const PfdJournal&) = delete;

  // The outcome recorded for `job` (same level, box, depth and budget), if any; `fragments` is the
  // BSP's fragment count (records are checked as a tree file's trees are).
  std::optional<PfdCellOutcome> find(const PfdCellJob& job, size_t fragments) const;
  // Appends and syncs one record (Error naming the path when it cannot).
  void append(const PfdCellJob& job, const PfdCellOutcome& outcome);
  size_t records() const { return records_.size(); }
  const std::string& path() const { return path_; }
  // Closes and deletes the file: the build it served is written.
  void remove();

 private:
  std::string path_;
  int fd_ = -1;
  std::map<std::string, std::vector<uint8_t>> records_;  // job key -> outcome bytes
};

}  // namespace walkvis
