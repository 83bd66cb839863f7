// The build journal (pfd_journal.h). POSIX file calls rather than stdio: a record must reach the
// file in one write() and be synced, and a torn tail must be cut off with ftruncate before the
// next record goes after it.
#include "pfd_hfd/pfd_journal.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/byte_io.h"
#include "core/hash.h"

namespace walkvis {
namespace {

constexpr char kMagic[8] = {'W', 'V', 'J', 'R', 'N', 'L', '\r', '\n'};
constexpr uint32_t kVersion = 3;  // 3: outcomes carry their query timing
constexpr size_t kHeaderBytes = kPfdJournalHeaderBytes;

// A job's identity in the journal: its bytes without the cost estimate, which does not decide its
// tree. (A string rather than a byte vector as the map key: GCC 12 warns falsely on comparing vectors.)
std::string jobKey(PfdCellJob job) {
  job.cost = 0.0;
  const std::vector<uint8_t> bytes = pfdCellJobBytes(job);
  return std::string(bytes.begin(), bytes.end());
}

[[noreturn]] void failIo(const std::string& path, const std::string& what) {
  throw Error(path + ": cannot " + what + " the build journal (" + std::strerror(errno) + ")");
}

void writeAll(int fd, const uint8_t* data, size_t size, const std::string& path) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) failIo(path, "write");
    data += n;
    size -= static_cast<size_t>(n);
  }
}

}  // namespace

uint64_t pfdBuildFingerprint(const TreeFile& head, std::span<const FloorLevel> levels, std::span<const uint32_t> only,
                             const PfdLevelOptions& options) {
  // Each field by name: a field added to one of these structs must be added here too.
  static_assert(sizeof(VisibilityOptions) == 48, "a new VisibilityOptions field belongs in the fingerprint");
  static_assert(sizeof(PfdLevelOptions) == sizeof(PfdOptions) + 32, "a new PfdLevelOptions field belongs in the fingerprint");
  ByteWriter w;
  const std::vector<uint8_t> bsp = bspFileBytes(head.bsp, "build journal", false);
  w.bytes.insert(w.bytes.end(), bsp.begin(), bsp.end());
  w.put(head.eye_height);
  w.put(static_cast<uint8_t>(head.kind));
  const VisibilityOptions& v = head.visibility;
  w.put(v.region_samples);
  w.put(v.polygon_samples);
  w.put(v.refine_rays);
  w.put(v.seed);
  w.put(v.proof_rays);
  w.put<uint8_t>(v.near_samples);
  w.put<uint8_t>(v.fuse_occluders);
  w.put<uint8_t>(v.conservative);
  w.put(v.conservative_proof_rays);
  w.put(v.sampled_max_area);
  const PfdOptions& t = options.tree;
  w.put(static_cast<uint32_t>(t.heuristic));
  w.put(t.candidates);
  w.put<uint8_t>(t.deep_candidates);
  w.put(t.search_lines);
  w.put(t.search_work);
  w.put(t.root_search_lines);
  w.put(t.root_search_work);
  w.put<uint8_t>(t.trim_slivers);
  w.put<uint8_t>(t.dedup);
  w.put(t.share_min);
  w.put(t.max_memory);
  w.put(t.stat_eyes);
  w.put(t.seed);
  w.put<uint8_t>(t.visibility != nullptr);
  w.put<uint8_t>(t.drop_back_faces);
  w.put(t.object_extent);
  w.put<uint8_t>(t.object_boxes);
  w.put(options.cell_memory);
  w.put(options.max_cell_depth);
  w.put(options.max_memory);
  w.put(options.object_extent);
  w.put(static_cast<uint32_t>(levels.size()));
  for (const FloorLevel& l : levels) {
    w.put(l.floor_y);
    w.put(static_cast<uint32_t>(l.walkable.size()));
    for (const auto& ring : l.walkable) {
      w.put(static_cast<uint32_t>(ring.size()));
      for (const glm::dvec2& p : ring) {
        w.put(p.x);
        w.put(p.y);
      }
    }
  }
  w.put(static_cast<uint32_t>(only.size()));
  for (uint32_t l : only) w.put(l);
  return fnv1a(w.bytes.data(), w.bytes.size());
}

PfdJournal::PfdJournal(const std::string& path, uint64_t fingerprint, bool fresh, std::string& note)
    : path_(path) {
  note.clear();
  std::error_code ec;
  const bool exists = std::filesystem::exists(path, ec);
  uint64_t keep = 0;  // bytes of the existing file to keep (0: start again)
  if (exists && fresh) {
    note = path + ": --fresh, the build journal's " + "cells are discarded";
  } else if (exists) {
    const std::vector<uint8_t> bytes = readFileBytes(path);
    ByteReader head(bytes, path + ": build journal: ");
    const bool header_ok = bytes.size() >= kHeaderBytes && std::memcmp(bytes.data(), kMagic, 8) == 0;
    uint32_t version = 0;
    uint64_t found = 0;
    if (header_ok) {
      head.take(8);
      version = head.get<uint32_t>();
      head.get<uint32_t>();
      found = head.get<uint64_t>();
    }
    if (!header_ok || version != kVersion) {
      note = path + ": not a build journal of this version; starting the build over";
    } else if (found != fingerprint) {
      note = path + ": the journal is of another scene or other options; starting the build over";
    } else {
      size_t at = kHeaderBytes;
      bool torn = false;
      while (at < bytes.size()) {
        if (bytes.size() - at < 16) {
          torn = true;
          break;
        }
        uint64_t size = 0, sum = 0;
        std::memcpy(&size, bytes.data() + at, 8);
        std::memcpy(&sum, bytes.data() + at + 8, 8);
        if (size > bytes.size() - at - 16 || fnv1a(bytes.data() + at + 16, size) != sum) {
          torn = true;
          break;
        }
        ByteReader r(std::span<const uint8_t>(bytes).subspan(at + 16, size), path + ": build journal: ");
        const uint64_t key_size = r.get<uint64_t>();
        if (key_size > r.remaining()) {
          torn = true;
          break;
        }
        const std::span<const uint8_t> key = r.take(key_size);
        const std::span<const uint8_t> outcome = r.take(r.remaining());
        records_[std::string(key.begin(), key.end())] = std::vector<uint8_t>(outcome.begin(), outcome.end());
        at += 16 + size;
      }
      keep = at;
      note = "resuming from " + path + ": " + std::to_string(records_.size()) + " view cells done" +
             (torn ? " (a record cut short by the kill is dropped)" : "");
    }
  }
  if (keep == 0) {
    records_.clear();
    // A new journal appears whole: its header goes to a temporary file that is renamed.
    ByteWriter h;
    h.bytes.assign(kMagic, kMagic + 8);
    h.put(kVersion);
    h.put<uint32_t>(0);
    h.put(fingerprint);
    writeFileAtomically(path, h.bytes, "build journal");
    keep = kHeaderBytes;
  }
  fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) failIo(path, "open");
  if (::ftruncate(fd_, static_cast<off_t>(keep)) != 0) failIo(path, "truncate");
  if (::lseek(fd_, static_cast<off_t>(keep), SEEK_SET) < 0) failIo(path, "seek in");
}

PfdJournal::~PfdJournal() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<PfdCellOutcome> PfdJournal::find(const PfdCellJob& job, size_t fragments) const {
  const auto it = records_.find(jobKey(job));
  if (it == records_.end()) return std::nullopt;
  return pfdCellOutcomeFromBytes(it->second, fragments, path_ + ": build journal record");
}

void PfdJournal::append(const PfdCellJob& job, const PfdCellOutcome& outcome) {
  const std::string key = jobKey(job);
  const std::vector<uint8_t> bytes = pfdCellOutcomeBytes(outcome);
  ByteWriter payload;
  payload.put(static_cast<uint64_t>(key.size()));
  payload.bytes.insert(payload.bytes.end(), key.begin(), key.end());
  payload.bytes.insert(payload.bytes.end(), bytes.begin(), bytes.end());
  ByteWriter record;
  record.put(static_cast<uint64_t>(payload.bytes.size()));
  record.put(fnv1a(payload.bytes.data(), payload.bytes.size()));
  record.bytes.insert(record.bytes.end(), payload.bytes.begin(), payload.bytes.end());
  writeAll(fd_, record.bytes.data(), record.bytes.size(), path_);
  if (::fdatasync(fd_) != 0) failIo(path_, "sync");
  records_[key] = bytes;
}

void PfdJournal::remove() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

}  // namespace walkvis
