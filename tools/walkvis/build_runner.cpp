// Building view cells on many processes (MPI, OpenMPI) and resuming a killed build. The work is
// the jobs of buildPfdLevels' rounds (pfd.h, PfdCellJob): each job's tree depends on the job and
// the build's context only, which every rank computes itself from the same command, so a job may
// run on any rank and the tree file comes out byte for byte the same on 1 or K ranks, resumed or
// not (docs/DESIGN.md, "Builds across processes and restarts").
//
// Rank 0 schedules: each round's jobs, the costliest first, go to whichever slot is free, its own
// or another rank's (dynamic assignment; an HFD cell's cost is poorly estimated before it is
// built). Messages (MPI_BYTE): a rank's READY (u32 slots), rank 0's JOB (u32 index, u32 timing
// eyes, job bytes) and STOP, a rank's RESULT (u32 index + outcome bytes) or FAILED (the error's
// text). Only the thread that called MPI_Init calls MPI (MPI_THREAD_FUNNELED); jobs run on slot
// threads of their own. The slot that builds a cell also times queries of its tree
// (buildTimedPfdCell), so that this part of the report spreads over the ranks as the trees do. A
// waiting rank polls (MPI_Iprobe, then a 1 ms sleep) rather than blocking in MPI_Recv: OpenMPI's
// blocking calls spin, and would take a core from the slots on a machine whose cores are all
// ranks.
#include "build_runner.h"

#include <mpi.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <numeric>
#include <optional>
#include <thread>

#include "core/byte_io.h"

namespace walkvis {
namespace {

constexpr int kTagReady = 1, kTagJob = 2, kTagStop = 3, kTagResult = 4, kTagFailed = 5;
// How long a waiting main thread sleeps between polls of MPI and of its slots.
constexpr auto kPollInterval = std::chrono::milliseconds(1);
// Progress lines come at most this often (and at the end of each round).
constexpr double kProgressSeconds = 2.0;

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// "1h02m", "3m05s", "12s".
std::string formatDuration(double seconds) {
  if (!(seconds >= 0.0) || seconds > 1e8) return "?";
  const long s = std::lround(seconds);
  char t[32];
  if (s >= 3600) std::snprintf(t, sizeof t, "%ldh%02ldm", s / 3600, (s / 60) % 60);
  else if (s >= 60) std::snprintf(t, sizeof t, "%ldm%02lds", s / 60, s % 60);
  else std::snprintf(t, sizeof t, "%lds", s);
  return t;
}

void sendBytes(int dest, int tag, const std::vector<uint8_t>& bytes) {
  if (bytes.size() > static_cast<size_t>(INT_MAX)) throw Error("mpi: a message of " + std::to_string(bytes.size()) + " bytes is over MPI's limit");
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}

// A waiting message from `source` (MPI_ANY_SOURCE: any), received; false when none waits.
bool receiveBytes(int source, int& from, int& tag, std::vector<uint8_t>& bytes) {
  int flag = 0;
  MPI_Status status;
  MPI_Iprobe(source, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
  if (!flag) return false;
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  bytes.resize(static_cast<size_t>(count));
  MPI_Recv(bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  from = status.MPI_SOURCE;
  tag = status.MPI_TAG;
  return true;
}

// An index followed by bytes, as RESULT carries them (JOB: with its timing eyes between).
std::vector<uint8_t> indexed(uint32_t index, const std::vector<uint8_t>& bytes, std::optional<uint32_t> eyes = {}) {
  ByteWriter w;
  w.put(index);
  if (eyes) w.put(*eyes);
  w.bytes.insert(w.bytes.end(), bytes.begin(), bytes.end());
  return std::move(w.bytes);
}

struct Cancelled {};  // thrown from a job's progress callback to abandon it

// `count` threads that build the jobs handed to them, one at a time each.
class LocalSlots {
 public:
  struct Done {
    uint32_t index = 0;
    PfdCellOutcome outcome;
    std::string error;  // what went wrong; empty: the outcome holds
  };
  struct Job {
    uint32_t index = 0;
    PfdCellJob job;
    uint32_t timing_eyes = 0;  // timePfdQueries of the tree at this many eyes (0: none)
  };

  LocalSlots(const PfdCellContext& context, uint32_t count) : context_(context), count_(count) {
    for (uint32_t k = 0; k < count; ++k) threads_.emplace_back([this] { work(); });
  }
  ~LocalSlots() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  uint32_t free() const { return count_ - busy_; }
  void submit(const Job& job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      inbox_.push_back(job);
      ++busy_;
    }
    wake_.notify_one();
  }
  // Moves the finished jobs into `out`, waiting up to `wait` for one when none has finished (the
  // whole `wait` when none runs: the poll's sleep).
  void collect(std::vector<Done>& out, std::chrono::milliseconds wait) {
    out.clear();
    std::unique_lock<std::mutex> lock(mutex_);
    if (outbox_.empty()) finished_.wait_for(lock, wait, [&] { return !outbox_.empty(); });
    busy_ -= static_cast<uint32_t>(outbox_.size());
    out.swap(outbox_);
  }
  // Abandons the jobs running (their builds stop at their next leaf) and those not begun.
  void cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancel_ = true;
    inbox_.clear();
  }

 private:
  void work() {
    while (true) {
      Job item;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return closed_ || !inbox_.empty(); });
        if (inbox_.empty()) return;
        item = inbox_.front();
        inbox_.pop_front();
      }
      Done done;
      done.index = item.index;
      try {
        done.outcome = buildTimedPfdCell(context_, item.job, item.timing_eyes, [this](double) {
          if (cancel_) throw Cancelled{};
        });
      } catch (const Cancelled&) {
        done.error = "cancelled";
      } catch (const std::exception& e) {
        done.error = e.what();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        outbox_.push_back(std::move(done));
      }
      finished_.notify_one();
    }
  }

  const PfdCellContext& context_;
  const uint32_t count_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::deque<Job> inbox_;
  std::vector<Done> outbox_;
  uint32_t busy_ = 0;  // submitted and not yet collected
  bool closed_ = false;
  std::atomic<bool> cancel_{false};
  std::vector<std::thread> threads_;
};

}  // namespace

PfdCellOutcome buildTimedPfdCell(const PfdCellContext& context, const PfdCellJob& job, uint32_t timing_eyes,
                                 const std::function<void(double)>& progress) {
  PfdCellOutcome outcome = buildPfdCell(context, job, progress);
  if (outcome.tree) outcome.tree->stats.query_timing = timePfdQueries(*context.bsp, *outcome.tree, timing_eyes);
  return outcome;
}

uint32_t queryTimingEyes(uint32_t stat_eyes, size_t cells) {
  const size_t most = std::min<size_t>(stat_eyes, 2000);
  return static_cast<uint32_t>(std::clamp<size_t>(100000 / std::max<size_t>(cells, 1), std::min<size_t>(64, most), most));
}

MpiWorld::MpiWorld() {
  // mpirun (OpenMPI's ORTE or PMIx) sets these; without them the process runs alone, no MPI_Init.
  if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMIX_RANK") && !std::getenv("PMI_RANK")) return;
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw Error("mpi: the MPI library gives no thread support (MPI_THREAD_FUNNELED needed)");
  }
  active_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  MPI_Comm_size(local, &local_size_);
  MPI_Comm_free(&local);
}

void MpiWorld::abort(int status) const {
  MPI_Abort(MPI_COMM_WORLD, status);
  std::_Exit(status);  // MPI_Abort does not return; the compiler does not know it
}

MpiWorld::~MpiWorld() {
  if (active_) MPI_Finalize();
}

struct CellScheduler::State {
  const PfdCellContext& context;
  const MpiWorld& world;
  PfdJournal* journal;
  std::function<void(const std::string&)> progress;
  LocalSlots local;
  std::vector<uint32_t> remote_free;  // per rank: slots that asked for a job
  std::vector<uint64_t> rank_cells, rank_rays;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  uint32_t round = 0;
  uint64_t journal_cells = 0;

  State(const PfdCellContext& c, const MpiWorld& w, uint32_t threads, PfdJournal* j,
        std::function<void(const std::string&)> p)
      : context(c), world(w), journal(j), progress(std::move(p)), local(c, threads),
        remote_free(static_cast<size_t>(w.size()), 0), rank_cells(static_cast<size_t>(w.size()), 0),
        rank_rays(static_cast<size_t>(w.size()), 0) {}

  std::string ranks() const {
    std::string s;
    for (size_t r = 0; r < rank_cells.size(); ++r) {
      char t[96];
      std::snprintf(t, sizeof t, "%srank %zu: %llu cells, %.3g rays/s", r == 0 ? "" : "; ", r,
                    static_cast<unsigned long long>(rank_cells[r]),
                    static_cast<double>(rank_rays[r]) / std::max(secondsSince(start), 1e-9));
      s += t;
    }
    return s;
  }

  void run(std::span<const PfdCellJob> jobs, std::span<PfdCellOutcome> outcomes) {
    ++round;
    const size_t fragments = context.bsp->fragments.size();
    std::vector<uint32_t> order(jobs.size());
    std::iota(order.begin(), order.end(), uint32_t{0});
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return jobs[a].cost > jobs[b].cost; });
    std::deque<uint32_t> pending;
    double total_cost = 0.0, done_cost = 0.0;
    size_t from_journal = 0;
    for (uint32_t i : order) {
      if (journal) {
        if (std::optional<PfdCellOutcome> o = journal->find(jobs[i], fragments)) {
          outcomes[i] = std::move(*o);
          ++from_journal;
          continue;
        }
      }
      pending.push_back(i);
      total_cost += jobs[i].cost + 1.0;  // + 1: a cell of no lines still costs its setup
    }
    journal_cells += from_journal;
    const size_t needed = pending.size();
    if (needed == 0 && progress)
      progress("round " + std::to_string(round) + ": all " + std::to_string(jobs.size()) + " cells from the journal");
    const uint32_t eyes = queryTimingEyes(context.options.tree.stat_eyes, jobs.size());
    size_t received = 0;
    const auto round_start = std::chrono::steady_clock::now();
    double last_line = -kProgressSeconds;
    auto record = [&](uint32_t index, PfdCellOutcome outcome, int rank) {
      if (journal) journal->append(jobs[index], outcome);
      if (outcome.tree) rank_rays[static_cast<size_t>(rank)] += outcome.tree->stats.visibility_rays;
      ++rank_cells[static_cast<size_t>(rank)];
      outcomes[index] = std::move(outcome);
      done_cost += jobs[index].cost + 1.0;
      ++received;
      const double t = secondsSince(round_start);
      if (!progress || (t - last_line < kProgressSeconds && received != needed)) return;
      last_line = t;
      const double eta = received == needed ? 0.0 : t * (total_cost - done_cost) / std::max(done_cost, 1e-9);
      char line[200];
      std::snprintf(line, sizeof line, "round %u: %zu of %zu cells built", round, received + from_journal,
                    jobs.size());
      std::string text = line;
      if (from_journal > 0) text += " (" + std::to_string(from_journal) + " from the journal)";
      text += ", " + std::string(received == needed ? "done in " + formatDuration(t)
                                                    : "ETA " + formatDuration(eta) + " by estimated cost");
      progress(text + "; " + ranks());
    };

    std::vector<LocalSlots::Done> done;
    std::vector<uint8_t> bytes;
    while (received < needed) {
      while (local.free() > 0 && !pending.empty()) {
        local.submit({pending.front(), jobs[pending.front()], eyes});
        pending.pop_front();
      }
      for (int r = 1; r < world.size(); ++r)
        for (; remote_free[r] > 0 && !pending.empty(); --remote_free[r]) {
          sendBytes(r, kTagJob, indexed(pending.front(), pfdCellJobBytes(jobs[pending.front()]), eyes));
          pending.pop_front();
        }
      bool got = false;
      int from = 0, tag = 0;
      while (world.active() && receiveBytes(MPI_ANY_SOURCE, from, tag, bytes)) {
        got = true;
        const std::string who = "mpi: rank " + std::to_string(from);
        ByteReader r(bytes, who + ": ");
        if (tag == kTagReady) {
          remote_free[from] += r.get<uint32_t>();
        } else if (tag == kTagResult) {
          const uint32_t index = r.get<uint32_t>();
          if (index >= jobs.size()) r.fail("result for a job out of range");
          record(index, pfdCellOutcomeFromBytes(r.take(r.remaining()), fragments, who + " result"), from);
          ++remote_free[from];
        } else if (tag == kTagFailed) {
          throw Error(who + ": " + std::string(bytes.begin(), bytes.end()));
        }
      }
      // Alone, nothing but a slot can end the wait: it wakes this thread itself.
      local.collect(done, got ? std::chrono::milliseconds(0) : world.size() > 1 ? kPollInterval : std::chrono::milliseconds(1000));
      for (LocalSlots::Done& d : done) {
        if (!d.error.empty()) throw Error(d.error);
        record(d.index, std::move(d.outcome), 0);
      }
    }
  }
};

CellScheduler::CellScheduler(const PfdCellContext& context, const MpiWorld& world, uint32_t threads,
                             PfdJournal* journal, std::function<void(const std::string&)> progress)
    : state_(std::make_unique<State>(context, world, threads, journal, std::move(progress))) {}

CellScheduler::~CellScheduler() {
  state_->local.cancel();
  for (int r = 1; r < state_->world.size(); ++r) sendBytes(r, kTagStop, {});
}

PfdCellRunner CellScheduler::runner() {
  return [this](std::span<const PfdCellJob> jobs, std::span<PfdCellOutcome> outcomes) { state_->run(jobs, outcomes); };
}

std::string CellScheduler::summary() const { return state_->ranks(); }

void serveCells(const PfdCellContext& context, const MpiWorld& world, uint32_t threads) {
  (void)world;
  LocalSlots local(context, threads);
  ByteWriter ready;
  ready.put(threads);
  sendBytes(0, kTagReady, ready.bytes);
  std::vector<LocalSlots::Done> done;
  std::vector<uint8_t> bytes;
  const std::string who = "mpi: message from rank 0: ";
  while (true) {
    bool got = false, stop = false;
    int from = 0, tag = 0;
    while (receiveBytes(0, from, tag, bytes)) {
      got = true;
      if (tag == kTagStop) {
        stop = true;
        break;
      }
      if (tag != kTagJob) continue;
      ByteReader r(bytes, who);
      const uint32_t index = r.get<uint32_t>();
      const uint32_t eyes = r.get<uint32_t>();
      local.submit({index, pfdCellJobFromBytes(r.take(r.remaining()), who + "job"), eyes});
    }
    if (stop) {
      local.cancel();
      return;
    }
    local.collect(done, got ? std::chrono::milliseconds(0) : kPollInterval);
    for (const LocalSlots::Done& d : done) {
      if (!d.error.empty()) {
        sendBytes(0, kTagFailed, std::vector<uint8_t>(d.error.begin(), d.error.end()));
        continue;
      }
      sendBytes(0, kTagResult, indexed(d.index, pfdCellOutcomeBytes(d.outcome)));
    }
  }
}

}  // namespace walkvis
